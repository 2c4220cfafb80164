//! The run-time routines the compiler calls for what the Cortex-M0+ has no instruction for:
//! `f32` arithmetic, comparisons and conversions, copying and filling memory, 64-bit
//! multiplication and 32-bit integer division (ARM EABI names, `__aeabi_*`). rp2040-hal's
//! versions are switched off (its `disable-intrinsics` feature); what is not here (f64, 64-bit
//! division, `memmove`, `memcmp` ...) comes from the compiler's own library,
//! `compiler_builtins`.
//!
//! Results are IEEE 754's (round to nearest, ties to even; denormals, signed zeros, infinities
//! and NaN as the standard says), bit for bit, except that a NaN's payload is not kept (a NaN
//! result is some quiet NaN). `emulator/test/intrinsics.test.js` checks every routine here on
//! the emulated chip, with the real boot ROM, against the host's IEEE arithmetic.
//!
//! - `fadd`, `fsub`, `fmul`, `fdiv`: the boot ROM's routines (RP2040 datasheet 2.8.3.2), which
//!   are correctly rounded for normal operands and results but flush denormals to zero and do
//!   not follow IEEE for infinities and NaN. So a few integer instructions look at the
//!   operands' exponent fields first: when both operands are normal and their exponents say
//!   the result can be neither denormal nor overflow, a tail call to the ROM routine (its
//!   address looked up at the first call and kept in RAM: two loads and a `bx`); otherwise
//!   (a zero, a denormal, an infinity, a NaN, a result near the ends of the range) the
//!   `compiler_builtins` routine, exact but slower. On the emulated chip a call takes about 20
//!   cycles more than the ROM routine alone (fadd 88, fmul 79, fdiv 96), where rp2040-hal's
//!   wrappers took about 40 (109, 99, 154).
//! - `fdiv`: the ROM's uses the SIO hardware divider, so it follows the divider's rule
//!   (datasheet 2.3.1.5): if the divider's state is dirty (a division was interrupted), it is
//!   saved and restored around the call.
//! - Comparisons and the conversions between `f32` and `i32`/`u32`: integer instructions here,
//!   no ROM call (a comparison is a dozen instructions). `f32` to `i32` truncates, as Rust's
//!   `as` needs (rp2040-hal 0.12's `__aeabi_f2iz` was the ROM's `float2int`, which rounds
//!   towards minus infinity: it gave -1 for -0.25, and `i32::MAX` for NaN).
//! - `__aeabi_memcpy`, `__aeabi_memset`, `__aeabi_memclr` (and their word-aligned forms): the
//!   ROM's routines, through their addresses kept in RAM (`compiler_builtins`' are several
//!   times slower for the controller's word-aligned copies).
//! - 64-bit multiplication (`__aeabi_lmul`): a few single-cycle 32-bit multiplications, half
//!   the cycles of `compiler_builtins`'.
//! - Integer division (`__aeabi_uidiv`, `__aeabi_idiv` and their `mod` forms): the SIO
//!   hardware divider, 8 cycles, with the same save and restore when dirty. Division by zero
//!   never reaches it (Rust checks first).

use core::arch::global_asm;
use core::sync::atomic::{AtomicPtr, AtomicUsize, Ordering};

use rp2040_hal::rom_data;

/// Byte offsets in the boot ROM's soft-float table (datasheet table 180).
pub(crate) const FADD: usize = 0x00;
pub(crate) const FMUL: usize = 0x08;
const FDIV: usize = 0x0c;

type BinaryFn = extern "C" fn(f32, f32) -> f32;

/// The ROM's `fadd`, `fmul` and `fdiv`: until the first call, stand-ins ([`first_fadd`] ...)
/// that look the three up, store them here and then call the ROM. Each always holds an
/// `extern "C" fn(f32, f32) -> f32` (a Thumb address, bit 0 set). The assembly below and
/// `rom_math` load them.
pub(crate) static ROM_FADD: AtomicPtr<()> = AtomicPtr::new(first_fadd as BinaryFn as *mut ());
/// See [`ROM_FADD`].
pub(crate) static ROM_FMUL: AtomicPtr<()> = AtomicPtr::new(first_fmul as BinaryFn as *mut ());
/// See [`ROM_FADD`].
static ROM_FDIV: AtomicPtr<()> = AtomicPtr::new(first_fdiv as BinaryFn as *mut ());

/// The soft-float table's address (0 until first looked up).
static TABLE: AtomicUsize = AtomicUsize::new(0);

/// The entry at byte offset `offset` of the ROM's soft-float table: a Thumb function address.
/// The table is looked up in the ROM the first time (always the same address, so a race could
/// only repeat it).
#[inline]
pub(crate) fn rom_float_entry(offset: usize) -> usize {
    let table = match TABLE.load(Ordering::Relaxed) {
        0 => {
            let table = rom_data::soft_float_table();
            TABLE.store(table as usize, Ordering::Relaxed);
            table
        }
        table => table as *const usize,
    };
    // SAFETY: `offset` is one of the offsets above or in `rom_math`, all inside the table of
    // every ROM version; the table lives in ROM, which is always readable.
    unsafe { table.add(offset / 4).read() }
}

/// Stores the ROM's routines in the slots (the same addresses whoever does it, so a race,
/// e.g. with an interrupt, could only repeat it). Integer instructions only: the routines
/// are not there yet.
fn resolve() {
    ROM_FADD.store(rom_float_entry(FADD) as *mut (), Ordering::Relaxed);
    ROM_FMUL.store(rom_float_entry(FMUL) as *mut (), Ordering::Relaxed);
    ROM_FDIV.store(rom_float_entry(FDIV) as *mut (), Ordering::Relaxed);
}

pub(crate) fn call(slot: &AtomicPtr<()>, a: f32, b: f32) -> f32 {
    // SAFETY: the slots only ever hold `extern "C" fn(f32, f32) -> f32`s (see `ROM_FADD`).
    let f = unsafe { core::mem::transmute::<*mut (), BinaryFn>(slot.load(Ordering::Relaxed)) };
    f(a, b)
}

extern "C" fn first_fadd(a: f32, b: f32) -> f32 {
    resolve();
    call(&ROM_FADD, a, b)
}

extern "C" fn first_fmul(a: f32, b: f32) -> f32 {
    resolve();
    call(&ROM_FMUL, a, b)
}

// Reached from `__aeabi_fdiv` after its divider check, so the ROM's `fdiv` may use it.
extern "C" fn first_fdiv(a: f32, b: f32) -> f32 {
    resolve();
    call(&ROM_FDIV, a, b)
}

// fadd and fsub. The ROM's result is IEEE's when each operand is a zero or has an exponent
// field in 24..=253 (measured on the ROM, for a zero; by reasoning for the rest; a second
// chance below for small operands): a sum of two
// such nonzero operands is a multiple of the smaller one's unit in the last place,
// 2^(e - 150) for exponent field e, so it is zero (+0, as IEEE wants) or at least 2^-126, never
// denormal; and each is below 2^127, so the sum cannot round past the largest float. A zero
// plus a zero or a normal number is exact in the ROM too. `a - b` is `a + (-b)`, exactly (IEEE
// 754, 5.4.1; the ROM's `fsub` is slower than its `fadd`), so fsub flips b's sign and runs on
// into fadd.
global_asm!(
    ".section .text.__aeabi_fadd,\"ax\",%progbits",
    ".global __aeabi_fsub",
    ".type __aeabi_fsub,%function",
    ".global __aeabi_fadd",
    ".type __aeabi_fadd,%function",
    ".thumb_func",
    "__aeabi_fsub:",
    "    movs r2, #1",
    "    lsls r2, r2, #31",
    "    eors r1, r2",
    ".thumb_func",
    "__aeabi_fadd:",
    "    lsls r2, r0, #1",
    "    beq 5f",
    "    lsrs r2, r2, #24",
    "    subs r2, #24",
    "    cmp r2, #(253 - 24)",
    "    bhi 7f",
    "    lsls r3, r1, #1",
    "    beq 6f",
    "    lsrs r3, r3, #24",
    "    subs r3, #24",
    "    cmp r3, #(253 - 24)",
    "    bhi 7f",
    "6:  ldr r2, ={fadd}",
    "    ldr r2, [r2]",
    "    bx r2",
    // a is a zero: b a zero or normal.
    "5:  lsls r3, r1, #1",
    "    beq 6b",
    "    lsrs r3, r3, #24",
    "    subs r3, #1",
    "    cmp r3, #253",
    "    bls 6b",
    "    b 1f",
    // Second chance (an exponent field outside 24..=253): both in 1..=253 with a sum of at
    // least 48 is also safe. If the smaller is 23 or less, the larger e is then at least 25,
    // two more, so the sum's magnitude is above 2^(e - 127) - 2^(e - 128) >= 2^-103.
    "7:  lsls r2, r0, #1",
    "    lsrs r2, r2, #24",
    "    subs r2, #1",
    "    cmp r2, #252",
    "    bhi 1f",
    "    lsls r3, r1, #1",
    "    lsrs r3, r3, #24",
    "    subs r3, #1",
    "    cmp r3, #252",
    "    bhi 1f",
    // (ea - 1) + (eb - 1) >= 46
    "    adds r2, r2, r3",
    "    cmp r2, #46",
    "    bhs 6b",
    "1:  ldr r2, =__addsf3",
    "    bx r2",
    ".ltorg",
    ".size __aeabi_fsub, __aeabi_fadd - __aeabi_fsub",
    ".size __aeabi_fadd, . - __aeabi_fadd",
    fadd = sym ROM_FADD,
);

// fmul. Both exponent fields normal (1..=254) and their sum in 128..=379: the product of the
// significands is in [1, 4), so the result is at least 2^(128 - 254) = 2^-126 (normal) and
// below 2^(379 - 252) = 2^127 (no overflow). A zero times a zero or a normal number is exact
// in the ROM too (its sign the operands' exclusive or).
global_asm!(
    ".section .text.__aeabi_fmul,\"ax\",%progbits",
    ".global __aeabi_fmul",
    ".type __aeabi_fmul,%function",
    ".thumb_func",
    "__aeabi_fmul:",
    "    lsls r2, r0, #1",
    "    beq 5f",
    "    lsrs r2, r2, #24",
    "    subs r2, #1",
    "    cmp r2, #253",
    "    bhi 1f",
    "    lsls r3, r1, #1",
    "    beq 6f",
    "    lsrs r3, r3, #24",
    "    subs r3, #1",
    "    cmp r3, #253",
    "    bhi 1f",
    // (ea - 1) + (eb - 1) - 126 = ea + eb - 128, in 0..=251.
    "    adds r2, r2, r3",
    "    subs r2, #126",
    "    cmp r2, #251",
    "    bhi 1f",
    "6:  ldr r2, ={fmul}",
    "    ldr r2, [r2]",
    "    bx r2",
    // a is a zero: b a zero or normal.
    "5:  lsls r3, r1, #1",
    "    beq 6b",
    "    lsrs r3, r3, #24",
    "    subs r3, #1",
    "    cmp r3, #253",
    "    bls 6b",
    "1:  ldr r2, =__mulsf3",
    "    bx r2",
    ".ltorg",
    ".size __aeabi_fmul, . - __aeabi_fmul",
    fmul = sym ROM_FMUL,
);

// fdiv. Both exponent fields normal and ea - eb in -125..=126: the quotient of the
// significands is in (1/2, 2), so the result is above 2^(ea - eb - 1) >= 2^-126 and below
// 2^(ea - eb + 1) <= 2^127. A zero divided by a normal number, and a normal number divided by
// a zero (an infinity), are exact in the ROM too. Then the divider's rule: dirty means an
// interrupted division's state is in it, so it is saved (its quotient read last: that clears
// the dirty flag), the ROM called, and the state written back (the quotient last: that sets
// the flags again).
global_asm!(
    ".section .text.__aeabi_fdiv,\"ax\",%progbits",
    ".global __aeabi_fdiv",
    ".type __aeabi_fdiv,%function",
    ".thumb_func",
    "__aeabi_fdiv:",
    "    lsls r2, r0, #1",
    "    beq 5f",
    "    lsrs r2, r2, #24",
    "    subs r2, #1",
    "    cmp r2, #253",
    "    bhi 1f",
    "    lsls r3, r1, #1",
    "    beq 6f",
    "    lsrs r3, r3, #24",
    "    subs r3, #1",
    "    cmp r3, #253",
    "    bhi 1f",
    // (ea - 1) - (eb - 1) + 125 = ea - eb + 125, in 0..=251.
    "    subs r2, r2, r3",
    "    adds r2, #125",
    "    cmp r2, #251",
    "    bhi 1f",
    "6:  ldr r2, =0xd0000000",
    "    ldr r3, [r2, #0x78]",
    "    lsrs r3, r3, #2",
    "    bcs 2f",
    "    ldr r2, ={fdiv}",
    "    ldr r2, [r2]",
    "    bx r2",
    // a is a zero: b normal.
    "5:  lsls r3, r1, #1",
    "    lsrs r3, r3, #24",
    "    subs r3, #1",
    "    cmp r3, #253",
    "    bls 6b",
    "1:  ldr r2, =__divsf3",
    "    bx r2",
    // r3 too: six words keep the stack eight-byte aligned for the call (AAPCS).
    "2:  push {{r3-r7, lr}}",
    "    ldr r4, [r2, #0x60]",
    "    ldr r5, [r2, #0x64]",
    "    ldr r6, [r2, #0x74]",
    "    ldr r7, [r2, #0x70]",
    "    ldr r2, ={fdiv}",
    "    ldr r2, [r2]",
    "    blx r2",
    "    ldr r2, =0xd0000000",
    "    str r4, [r2, #0x60]",
    "    str r5, [r2, #0x64]",
    "    str r6, [r2, #0x74]",
    "    str r7, [r2, #0x70]",
    "    pop {{r3-r7, pc}}",
    ".ltorg",
    ".size __aeabi_fdiv, . - __aeabi_fdiv",
    fdiv = sym ROM_FDIV,
);

// Integer division on the SIO divider (SIO_BASE 0xd0000000: DIV_UDIVIDEND 0x60, DIV_UDIVISOR
// 0x64, DIV_SDIVIDEND 0x68, DIV_SDIVISOR 0x6c, DIV_QUOTIENT 0x70, DIV_REMAINDER 0x74, DIV_CSR
// 0x78 with DIRTY in bit 1). Quotient in r0, remainder in r1 (the `mod` forms' ABI; the plain
// forms return r0 and may clobber r1). The result is ready 8 cycles after the divisor's write:
// four two-cycle branches. When dirty, the interrupted division's state is kept in r4-r7
// around a call of the fast path (which leaves r3-r7 alone) and written back, quotient last.
//
/// One division pair on the SIO divider: `$divmod` (quotient and remainder) and `$div` (the
/// quotient), writing the dividend and divisor at `$dividend` and `$divisor` (the unsigned
/// or the signed pair; the rest is the same for both).
macro_rules! sio_division {
    ($divmod:literal, $div:literal, $dividend:literal, $divisor:literal) => {
        global_asm!(
            concat!(".section .text.", $divmod, ",\"ax\",%progbits"),
            concat!(".global ", $divmod),
            concat!(".global ", $div),
            concat!(".type ", $divmod, ",%function"),
            concat!(".type ", $div, ",%function"),
            ".thumb_func",
            concat!($divmod, ":"),
            ".thumb_func",
            concat!($div, ":"),
            "    ldr r2, =0xd0000000",
            "    ldr r3, [r2, #0x78]",
            "    lsrs r3, r3, #2",
            "    bcs 2f",
            concat!("1:  str r0, [r2, #", $dividend, "]"),
            concat!("    str r1, [r2, #", $divisor, "]"),
            "    b 3f",
            "3:  b 3f",
            "3:  b 3f",
            "3:  b 3f",
            "3:  ldr r1, [r2, #0x74]",
            "    ldr r0, [r2, #0x70]",
            "    bx lr",
            "2:  push {{r4-r7, lr}}",
            "    ldr r4, [r2, #0x60]",
            "    ldr r5, [r2, #0x64]",
            "    ldr r6, [r2, #0x74]",
            "    ldr r7, [r2, #0x70]",
            "    bl 1b",
            "    str r4, [r2, #0x60]",
            "    str r5, [r2, #0x64]",
            "    str r6, [r2, #0x74]",
            "    str r7, [r2, #0x70]",
            "    pop {{r4-r7, pc}}",
            ".ltorg",
            concat!(".size ", $divmod, ", . - ", $divmod),
        );
    };
}

sio_division!("__aeabi_uidivmod", "__aeabi_uidiv", "0x60", "0x64");
sio_division!("__aeabi_idivmod", "__aeabi_idiv", "0x68", "0x6c");

// The low 64 bits of a 64-bit product (`__aeabi_lmul`: a in r1:r0, b in r3:r2, high words
// first). The RP2040's multiplier takes one cycle for 32 x 32 -> 32 bits, so: the high word
// gets a_hi * b_lo + a_lo * b_hi; a_lo * b_lo in full from four 16-bit products, the middle
// two summed with their carry (bit 32) kept.
global_asm!(
    ".section .text.__aeabi_lmul,\"ax\",%progbits",
    ".global __aeabi_lmul",
    ".type __aeabi_lmul,%function",
    ".thumb_func",
    "__aeabi_lmul:",
    "    push {{r4, r5}}",
    "    muls r1, r2",
    "    muls r3, r0",
    "    adds r1, r1, r3",
    "    lsrs r3, r0, #16",
    "    uxth r0, r0",
    "    lsrs r4, r2, #16",
    "    uxth r2, r2",
    "    movs r5, r0",
    "    muls r5, r4",
    "    muls r4, r3",
    "    muls r3, r2",
    "    muls r0, r2",
    // r5: the middle sum's low 32 bits, its carry to bit 48 of a_lo * b_lo.
    "    adds r5, r5, r3",
    "    movs r2, #0",
    "    adcs r2, r2",
    "    lsls r2, r2, #16",
    "    adds r4, r4, r2",
    "    lsls r2, r5, #16",
    "    lsrs r3, r5, #16",
    "    adds r0, r0, r2",
    "    adcs r4, r3",
    "    adds r1, r1, r4",
    "    pop {{r4, r5}}",
    "    bx lr",
    ".size __aeabi_lmul, . - __aeabi_lmul",
);

const SIGN: u32 = 1 << 31;
const INF: u32 = 0x7f80_0000;

#[inline(always)]
fn is_nan(x: u32) -> bool {
    x & !SIGN > INF
}

// Comparisons (1 if the relation holds, 0 if not or unordered). Two floats that are not NaN
// are equal when their bits are, or when both are zeros. Ordered ones: NaN (`|x| << 1` above
// 0xff000000) gives 0; two zeros are equal; otherwise, as signed integers, floats order like
// their bits when at least one is positive, and the other way round when both are negative.
// `a < b` is `b > a`, `a <= b` is `b >= a`.
global_asm!(
    ".macro unordered_to label",
    "    movs r3, #0xff",
    "    lsls r3, r3, #24",
    "    lsls r2, r0, #1",
    "    cmp r2, r3",
    "    bhi \\label",
    "    lsls r2, r1, #1",
    "    cmp r2, r3",
    "    bhi \\label",
    ".endm",
    "",
    ".section .text.__aeabi_fcmpeq,\"ax\",%progbits",
    ".global __aeabi_fcmpeq",
    ".type __aeabi_fcmpeq,%function",
    ".thumb_func",
    "__aeabi_fcmpeq:",
    "    cmp r0, r1",
    "    beq 1f",
    "    lsls r2, r0, #1",
    "    lsls r3, r1, #1",
    "    orrs r2, r3",
    "    beq 2f",
    "0:  movs r0, #0",
    "    bx lr",
    // The same bits: equal unless NaN.
    "1:  lsls r2, r0, #1",
    "    movs r3, #0xff",
    "    lsls r3, r3, #24",
    "    cmp r2, r3",
    "    bhi 0b",
    "2:  movs r0, #1",
    "    bx lr",
    ".size __aeabi_fcmpeq, . - __aeabi_fcmpeq",
    "",
    ".section .text.__aeabi_fcmpgt,\"ax\",%progbits",
    ".global __aeabi_fcmplt",
    ".type __aeabi_fcmplt,%function",
    ".global __aeabi_fcmpgt",
    ".type __aeabi_fcmpgt,%function",
    ".thumb_func",
    "__aeabi_fcmplt:",
    "    mov r2, r0",
    "    mov r0, r1",
    "    mov r1, r2",
    ".thumb_func",
    "__aeabi_fcmpgt:",
    "    unordered_to 0f",
    "    lsls r3, r0, #1",
    "    orrs r2, r3",
    "    beq 0f",
    "    movs r2, r0",
    "    ands r2, r1",
    "    bmi 2f",
    "    cmp r0, r1",
    "    bgt 1f",
    "0:  movs r0, #0",
    "    bx lr",
    "1:  movs r0, #1",
    "    bx lr",
    "2:  cmp r1, r0",
    "    bgt 1b",
    "    b 0b",
    ".size __aeabi_fcmplt, __aeabi_fcmpgt - __aeabi_fcmplt",
    ".size __aeabi_fcmpgt, . - __aeabi_fcmpgt",
    "",
    ".section .text.__aeabi_fcmpge,\"ax\",%progbits",
    ".global __aeabi_fcmple",
    ".type __aeabi_fcmple,%function",
    ".global __aeabi_fcmpge",
    ".type __aeabi_fcmpge,%function",
    ".thumb_func",
    "__aeabi_fcmple:",
    "    mov r2, r0",
    "    mov r0, r1",
    "    mov r1, r2",
    ".thumb_func",
    "__aeabi_fcmpge:",
    "    unordered_to 0f",
    "    lsls r3, r0, #1",
    "    orrs r2, r3",
    "    beq 1f",
    "    movs r2, r0",
    "    ands r2, r1",
    "    bmi 2f",
    "    cmp r0, r1",
    "    bge 1f",
    "0:  movs r0, #0",
    "    bx lr",
    "1:  movs r0, #1",
    "    bx lr",
    "2:  cmp r1, r0",
    "    bge 1b",
    "    b 0b",
    ".size __aeabi_fcmple, __aeabi_fcmpge - __aeabi_fcmple",
    ".size __aeabi_fcmpge, . - __aeabi_fcmpge",
    "",
    ".section .text.__aeabi_fcmpun,\"ax\",%progbits",
    ".global __aeabi_fcmpun",
    ".type __aeabi_fcmpun,%function",
    ".thumb_func",
    "__aeabi_fcmpun:",
    "    unordered_to 1f",
    "    movs r0, #0",
    "    bx lr",
    "1:  movs r0, #1",
    "    bx lr",
    ".size __aeabi_fcmpun, . - __aeabi_fcmpun",
    ".purgem unordered_to",
);

/// `f32` to `i32`, toward zero, as Rust's `as`: saturating, NaN to 0.
#[no_mangle]
extern "aapcs" fn __aeabi_f2iz(a: f32) -> i32 {
    let bits = a.to_bits();
    let exponent = (bits >> 23) & 0xff;
    if exponent < 127 {
        // |a| < 1, zeros and denormals.
        return 0;
    }
    if exponent >= 127 + 31 {
        // |a| >= 2^31: only -2^31 fits; infinities; NaN.
        return if is_nan(bits) {
            0
        } else if bits & SIGN == 0 {
            i32::MAX
        } else {
            i32::MIN
        };
    }
    let magnitude = truncate(bits, exponent);
    if bits & SIGN == 0 {
        magnitude as i32
    } else {
        (magnitude as i32).wrapping_neg()
    }
}

/// `f32` to `u32`, toward zero, as Rust's `as`: saturating (negatives to 0), NaN to 0.
#[no_mangle]
extern "aapcs" fn __aeabi_f2uiz(a: f32) -> u32 {
    let bits = a.to_bits();
    let exponent = (bits >> 23) & 0xff;
    if exponent < 127 || bits & SIGN != 0 {
        // |a| < 1, zeros, denormals; negatives, -inf and NaNs with the sign bit set.
        return 0;
    }
    if exponent >= 127 + 32 {
        return if is_nan(bits) { 0 } else { u32::MAX };
    }
    truncate(bits, exponent)
}

/// The integer part of a float with exponent field `exponent` in 127..=158.
#[inline(always)]
fn truncate(bits: u32, exponent: u32) -> u32 {
    let significand = (bits & 0x7f_ffff) | 0x80_0000;
    if exponent >= 127 + 23 {
        significand << (exponent - (127 + 23))
    } else {
        significand >> ((127 + 23) - exponent)
    }
}

// `u32` and `i32` to `f32`, rounded to nearest, ties to even. The leading zeros are counted by
// halves (the M0+ has no instruction for it) while r2 counts the exponent field down from
// that of 2^31; the 24 bits below the leading one (the leading one adds one to the exponent
// field, so it goes in one below) and the 8 below them round.
global_asm!(
    ".section .text.__aeabi_ui2f,\"ax\",%progbits",
    ".global __aeabi_i2f",
    ".type __aeabi_i2f,%function",
    ".global __aeabi_ui2f",
    ".type __aeabi_ui2f,%function",
    ".thumb_func",
    "__aeabi_i2f:",
    "    asrs r3, r0, #31",
    "    eors r0, r3",
    "    subs r0, r0, r3",
    "    b 0f",
    ".thumb_func",
    "__aeabi_ui2f:",
    "    movs r3, #0",
    "0:  cmp r0, #0",
    "    beq 9f",
    "    movs r2, #(127 + 31)",
    "    lsrs r1, r0, #16",
    "    bne 1f",
    "    lsls r0, r0, #16",
    "    subs r2, #16",
    "1:  lsrs r1, r0, #24",
    "    bne 1f",
    "    lsls r0, r0, #8",
    "    subs r2, #8",
    "1:  lsrs r1, r0, #28",
    "    bne 1f",
    "    lsls r0, r0, #4",
    "    subs r2, #4",
    "1:  lsrs r1, r0, #30",
    "    bne 1f",
    "    lsls r0, r0, #2",
    "    subs r2, #2",
    "1:  cmp r0, #0",
    "    blt 1f",
    "    lsls r0, r0, #1",
    "    subs r2, #1",
    "1:  lsls r1, r0, #24",
    "    lsrs r0, r0, #8",
    "    subs r2, #1",
    "    lsls r2, r2, #23",
    "    adds r0, r0, r2",
    // The rounding bits: the half in C, the rest zero or not in Z.
    "    lsls r1, r1, #1",
    "    bcc 2f",
    "    bne 1f",
    "    lsrs r1, r0, #1",
    "    bcc 2f",
    "1:  adds r0, #1",
    "2:  lsls r3, r3, #31",
    "    orrs r0, r3",
    "9:  bx lr",
    ".size __aeabi_i2f, __aeabi_ui2f - __aeabi_i2f",
    ".size __aeabi_ui2f, . - __aeabi_ui2f",
);

/// The ROM's `memcpy`, `memcpy44` (word-aligned), `memset` and `memset4` (word-aligned), as
/// the compiler's `__aeabi_mem*` routines below reach them: until the first call, stand-ins
/// that look them up (rp2040-hal's cached look-ups) and call them.
static ROM_MEMCPY: AtomicPtr<()> = AtomicPtr::new(first_memcpy as MemFn as *mut ());
/// See [`ROM_MEMCPY`].
static ROM_MEMCPY44: AtomicPtr<()> = AtomicPtr::new(first_memcpy44 as MemFn as *mut ());
/// See [`ROM_MEMCPY`].
static ROM_MEMSET: AtomicPtr<()> = AtomicPtr::new(first_memset as MemFn as *mut ());
/// See [`ROM_MEMCPY`].
static ROM_MEMSET4: AtomicPtr<()> = AtomicPtr::new(first_memset4 as MemFn as *mut ());

/// The ROM's memory routines' ABI: `(dest, src or fill byte, bytes) -> dest`.
type MemFn = unsafe extern "C" fn(usize, usize, usize) -> usize;

fn resolve_memory() {
    ROM_MEMCPY.store(rom_data::memcpy::ptr() as *mut (), Ordering::Relaxed);
    ROM_MEMCPY44.store(rom_data::memcpy44::ptr() as *mut (), Ordering::Relaxed);
    ROM_MEMSET.store(rom_data::memset::ptr() as *mut (), Ordering::Relaxed);
    ROM_MEMSET4.store(rom_data::memset4::ptr() as *mut (), Ordering::Relaxed);
}

/// Calls the routine in `slot` (one of the four above).
///
/// # Safety
/// As the ROM routine's: the memory named must be valid (the compiler's calls guarantee it).
unsafe fn call_memory(slot: &AtomicPtr<()>, a: usize, b: usize, n: usize) -> usize {
    // SAFETY: the slots only ever hold `MemFn`s: their stand-in or the ROM routine.
    let f = unsafe { core::mem::transmute::<*mut (), MemFn>(slot.load(Ordering::Relaxed)) };
    // SAFETY: the caller's.
    unsafe { f(a, b, n) }
}

unsafe extern "C" fn first_memcpy(a: usize, b: usize, n: usize) -> usize {
    resolve_memory();
    // SAFETY: the compiler's call that came here guarantees the memory.
    unsafe { call_memory(&ROM_MEMCPY, a, b, n) }
}

unsafe extern "C" fn first_memcpy44(a: usize, b: usize, n: usize) -> usize {
    resolve_memory();
    // SAFETY: as `first_memcpy`.
    unsafe { call_memory(&ROM_MEMCPY44, a, b, n) }
}

unsafe extern "C" fn first_memset(a: usize, b: usize, n: usize) -> usize {
    resolve_memory();
    // SAFETY: as `first_memcpy`.
    unsafe { call_memory(&ROM_MEMSET, a, b, n) }
}

unsafe extern "C" fn first_memset4(a: usize, b: usize, n: usize) -> usize {
    resolve_memory();
    // SAFETY: as `first_memcpy`.
    unsafe { call_memory(&ROM_MEMSET4, a, b, n) }
}

// The compiler's memory routines on the ROM's (as rp2040-hal's were): `memcpy(dest, src, n)`
// as it is; `memset(dest, n, c)` and `memclr(dest, n)` with the ROM's argument order
// `(dest, c, n)`. The `4` and `8` forms have word-aligned pointers.
global_asm!(
    ".section .text.__aeabi_memcpy,\"ax\",%progbits",
    ".global __aeabi_memcpy",
    ".type __aeabi_memcpy,%function",
    ".thumb_func",
    "__aeabi_memcpy:",
    "    ldr r3, ={memcpy}",
    "    ldr r3, [r3]",
    "    bx r3",
    ".ltorg",
    ".size __aeabi_memcpy, . - __aeabi_memcpy",
    "",
    ".section .text.__aeabi_memcpy4,\"ax\",%progbits",
    ".global __aeabi_memcpy4",
    ".type __aeabi_memcpy4,%function",
    ".global __aeabi_memcpy8",
    ".type __aeabi_memcpy8,%function",
    ".thumb_func",
    "__aeabi_memcpy4:",
    ".thumb_func",
    "__aeabi_memcpy8:",
    "    ldr r3, ={memcpy44}",
    "    ldr r3, [r3]",
    "    bx r3",
    ".ltorg",
    ".size __aeabi_memcpy4, . - __aeabi_memcpy4",
    "",
    ".section .text.__aeabi_memset,\"ax\",%progbits",
    ".global __aeabi_memset",
    ".type __aeabi_memset,%function",
    ".global __aeabi_memclr",
    ".type __aeabi_memclr,%function",
    ".thumb_func",
    "__aeabi_memset:",
    "    mov r3, r1",
    "    mov r1, r2",
    "    mov r2, r3",
    "    b 1f",
    ".thumb_func",
    "__aeabi_memclr:",
    "    mov r2, r1",
    "    movs r1, #0",
    "1:  ldr r3, ={memset}",
    "    ldr r3, [r3]",
    "    bx r3",
    ".ltorg",
    ".size __aeabi_memset, __aeabi_memclr - __aeabi_memset",
    ".size __aeabi_memclr, . - __aeabi_memclr",
    "",
    ".section .text.__aeabi_memset4,\"ax\",%progbits",
    ".global __aeabi_memset4",
    ".type __aeabi_memset4,%function",
    ".global __aeabi_memset8",
    ".type __aeabi_memset8,%function",
    ".global __aeabi_memclr4",
    ".type __aeabi_memclr4,%function",
    ".global __aeabi_memclr8",
    ".type __aeabi_memclr8,%function",
    ".thumb_func",
    "__aeabi_memset4:",
    ".thumb_func",
    "__aeabi_memset8:",
    "    mov r3, r1",
    "    mov r1, r2",
    "    mov r2, r3",
    "    b 1f",
    ".thumb_func",
    "__aeabi_memclr4:",
    ".thumb_func",
    "__aeabi_memclr8:",
    "    mov r2, r1",
    "    movs r1, #0",
    "1:  ldr r3, ={memset4}",
    "    ldr r3, [r3]",
    "    bx r3",
    ".ltorg",
    ".size __aeabi_memset4, __aeabi_memclr4 - __aeabi_memset4",
    ".size __aeabi_memclr4, . - __aeabi_memclr4",
    memcpy = sym ROM_MEMCPY,
    memcpy44 = sym ROM_MEMCPY44,
    memset = sym ROM_MEMSET,
    memset4 = sym ROM_MEMSET4,
);
