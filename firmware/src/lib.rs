//! What the firmware's binaries share: the clock set-up and the board's
//! [`kinematics_core::Math`] ([`rom_math`]).
//!
//! `src/main.rs` is the firmware; `src/bin/bench.rs` is the IK benchmark, which must run the
//! very same maths (`./dev bench`).

#![no_std]

pub mod rom_math;

use rp2040_hal::{clocks::ClocksManager, pac, Watchdog};

/// The Pico's crystal, Hz.
pub const XTAL_HZ: u32 = 12_000_000;

/// 12 MHz crystal -> PLLs -> 125 MHz `clk_sys` and `clk_peri`, which the PWM divider and the
/// UART baud rates assume. Panics if the crystal or a PLL does not start (nothing can run).
pub fn init_clocks(
    xosc: pac::XOSC,
    clocks: pac::CLOCKS,
    pll_sys: pac::PLL_SYS,
    pll_usb: pac::PLL_USB,
    resets: &mut pac::RESETS,
    watchdog: &mut Watchdog,
) -> ClocksManager {
    let Ok(clocks) = rp2040_hal::clocks::init_clocks_and_plls(
        XTAL_HZ, xosc, clocks, pll_sys, pll_usb, resets, watchdog,
    ) else {
        panic!("clock setup failed");
    };
    clocks
}
