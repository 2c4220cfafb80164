//! What the firmware's binaries share: the board's [`kinematics_core::Math`] ([`rom_math`]).
//!
//! `src/main.rs` is the firmware; `src/bin/bench.rs` is the IK benchmark, which must run the
//! very same maths (`./dev bench`).

#![no_std]

pub mod rom_math;
