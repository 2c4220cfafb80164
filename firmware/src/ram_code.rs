//! The hot code's copy to RAM: `memory.x` gathers the functions a received byte, a `pose`
//! line, a stream frame and a servo frame run through into `.ram_code`, which runs from SRAM
//! (no XIP cache miss, one cycle a fetch) and is loaded in flash at `RAM_CODE_LOAD`. This
//! copies it, a word at a time, before anything runs (cortex-m-rt's `__pre_init`, called by
//! the reset handler before it initialises `.data` and `.bss`), so it is written in assembly:
//! no Rust code may run before RAM is set up, and none of the copied functions (`memcpy`
//! among them) may run before the copy.

core::arch::global_asm!(
    ".section .text.__pre_init, \"ax\"",
    ".global __pre_init",
    ".type __pre_init, %function",
    ".thumb_func",
    "__pre_init:",
    "    ldr r0, =__sram_code",
    "    ldr r1, =__eram_code",
    "    ldr r2, =__siram_code",
    "0:  cmp r0, r1",
    "    beq 1f",
    "    ldm r2!, {{r3}}",
    "    stm r0!, {{r3}}",
    "    b 0b",
    "1:  bx lr",
    ".ltorg",
    ".size __pre_init, . - __pre_init",
);
