//! What the firmware's binaries share: the board's bring-up ([`board`]: boot2, clocks, GPIOs),
//! the board's [`kinematics_core::Math`] ([`rom_math`]) and the compiler's run-time routines
//! for `f32`, memory and integer division (`intrinsics`).
//!
//! `src/main.rs` is the firmware; `src/bin/bench.rs` is the IK benchmark, which must run the
//! very same maths on the very same clocks (`./dev bench`).

#![no_std]

pub mod board;
mod intrinsics;
mod ram_code;
pub mod rom_math;

pub use board::Board;

/// The controller as the board runs it: on the boot ROM's float routines where it computes in
/// `f32` (its IK runs in fixed point, `kinematics_core::fixed`).
pub type Controller = control::Controller<rom_math::RomMath>;
