//! [`Math`] for the RP2040: the boot ROM's float routines, called directly.
//!
//! The M0+ has no FPU. `libm`'s `sinf`/`cosf` compute in f64 and cost thousands of cycles per
//! call; the ROM routines are accurate to about 1e-7 and several times faster. rp2040-hal's
//! `__aeabi_f*` routines the compiler calls for `+ - * /` ([`crate::intrinsics`]) check their
//! operands before each ROM call (about 20 cycles on top of a 55-70 cycle `fadd` or `fmul`)
//! to give IEEE's results where the ROM does not (denormals, infinities, NaN). The kinematics
//! call the ROM through [`Math`] instead, as the Pico SDK does: the soft-float table's address
//! is looked up once and kept in RAM, and so are the addresses of `fadd` and `fmul` (the most
//! called; the same slots as the intrinsics', [`intrinsics::ROM_FADD`]), so each call is two
//! loads and a `blx`.
//!
//! The IK's hot loop calls none of them: it runs in fixed point, with the core's integer sine,
//! square root and arc tangent (`kinematics_core::fixed`, [`Math`]'s default fixed-point
//! functions, which this implementation keeps: faster than these routines and more accurate
//! than `f32`; `./dev bench` measures both). These routines serve the rest: the IK's float
//! path (builds beyond the fixed-point bounds), Jacobians, forward kinematics, statics, the
//! stream tracker's limits per frame (its step is integer). Subtraction is `fadd` with the
//! second operand's sign flipped (IEEE defines `a - b` as `a + (-b)`; both are correctly
//! rounded): the ROM's `fsub` costs about 9 cycles more per call.
//!
//! ABI facts relied on (RP2040 datasheet, section 2.8.3 "Floating point"; checked on the
//! emulated chip by `emulator/test/rom-math.test.js`):
//! - every soft-float table entry is an AAPCS function (arguments in r0, r1; result in r0;
//!   r0-r3, r12 and lr clobbered; r4-r11 and sp preserved), Thumb address with bit 0 set;
//! - `fsin` (offset 0x40) also leaves `cos(x)` in r1, so one call gives both (the SDK's
//!   `sincosf` relies on the same);
//! - `fsin`/`fcos` want `|x| < 128` rad (the kinematics keeps angles within `2 pi`);
//! - `fatan2` (offset 0x58) exists from ROM version 2 (every RP2040 sold, B1 and later; B0 was
//!   never on a Pico); on an older ROM `libm`'s `atan2f` is used instead;
//! - `fsqrt` returns -inf for negative input; the trait wants NaN, so negatives are caught here;
//! - `fadd`, `fmul` are correctly rounded for normal and zero operands, overflow included, but
//!   read denormal operands as zero and flush denormal results to zero (far below anything
//!   the kinematics computes), and give an infinity for a NaN operand, `inf - inf` or
//!   `0 * inf` (measured: `emulator/test/intrinsics.test.js`), which the trait allows: the IK
//!   checks the pose and bounds its magnitudes before they could overflow.

use core::arch::asm;
use core::sync::atomic::{AtomicUsize, Ordering};

use kinematics_core::Math;
use rp2040_hal::rom_data;

use crate::intrinsics::{self, rom_float_entry as entry, FADD, FMUL, ROM_FADD, ROM_FMUL};

/// Byte offsets in the soft-float table (datasheet table 180; `fadd`'s and `fmul`'s are
/// [`intrinsics`]').
const FSQRT: usize = 0x18;
const FSIN: usize = 0x40;
const FATAN2: usize = 0x58;

/// The soft-float routines the IK calls, by name, with their table offsets (for the benchmark,
/// which attributes cycles to them).
pub const IK_ROUTINES: [(&str, usize); 5] = [
    ("fadd", FADD),
    ("fmul", FMUL),
    ("fsqrt", FSQRT),
    ("fsin", FSIN),
    ("fatan2", FATAN2),
];

/// `fatan2`, or `libm`'s on a ROM without it (0 until first looked up).
static ATAN2: AtomicUsize = AtomicUsize::new(0);

type BinaryFn = extern "C" fn(f32, f32) -> f32;
type UnaryFn = extern "C" fn(f32) -> f32;

/// The boot ROM's float library, called directly.
#[derive(Debug, Clone, Copy, Default)]
pub struct RomMath;

extern "C" fn libm_atan2(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

fn atan2_fn() -> BinaryFn {
    let f = match ATAN2.load(Ordering::Relaxed) {
        0 => {
            let f = if rom_data::rom_version_number() >= 2 {
                entry(FATAN2)
            } else {
                libm_atan2 as BinaryFn as usize
            };
            ATAN2.store(f, Ordering::Relaxed);
            f
        }
        f => f,
    };
    // SAFETY: either the ROM's `fatan2` or `libm_atan2`, both `extern "C" fn(f32, f32) -> f32`.
    unsafe { core::mem::transmute::<usize, BinaryFn>(f) }
}

impl Math for RomMath {
    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        // |x| < 128, NaN excluded, in integer instructions (non-negative floats order like
        // their bit patterns; NaN's are above infinity's).
        if x.abs().to_bits() >= 128.0f32.to_bits() {
            return (f32::NAN, f32::NAN);
        }
        let f = entry(FSIN);
        let (sin, cos): (u32, u32);
        // SAFETY: `f` is the ROM's `fsin`, an AAPCS function taking x in r0 and returning
        // sin(x) in r0 and cos(x) in r1 (module docs); `clobber_abi("C")` tells the compiler
        // everything else such a call may change (r2, r3, r12, lr, flags).
        unsafe {
            asm!(
                "blx {f}",
                f = in(reg) f,
                inlateout("r0") x.to_bits() => sin,
                lateout("r1") cos,
                clobber_abi("C"),
            );
        }
        (f32::from_bits(sin), f32::from_bits(cos))
    }

    #[inline]
    fn sqrt(x: f32) -> f32 {
        // The ROM returns -inf for negative input; the trait promises NaN. `x >= 0.0` in
        // integer instructions (a float comparison is a library call): +0 up to +inf, or -0.
        if x.to_bits() <= f32::INFINITY.to_bits() || x.to_bits() == (-0.0f32).to_bits() {
            // SAFETY: `fsqrt` is `extern "C" fn(f32) -> f32`.
            let f: UnaryFn = unsafe { core::mem::transmute::<usize, UnaryFn>(entry(FSQRT)) };
            f(x)
        } else {
            f32::NAN
        }
    }

    #[inline]
    fn atan2(y: f32, x: f32) -> f32 {
        atan2_fn()(y, x)
    }

    #[inline]
    fn add(a: f32, b: f32) -> f32 {
        intrinsics::call(&ROM_FADD, a, b)
    }

    #[inline]
    fn sub(a: f32, b: f32) -> f32 {
        // `a + (-b)`: see the module docs.
        intrinsics::call(&ROM_FADD, a, -b)
    }

    #[inline]
    fn mul(a: f32, b: f32) -> f32 {
        intrinsics::call(&ROM_FMUL, a, b)
    }
}
