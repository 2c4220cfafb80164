//! The chip brought up the one way both binaries need it: the second-stage bootloader, the
//! clocks (12 MHz crystal -> 125 MHz `clk_sys` and `clk_peri`), the watchdog (not started),
//! the GPIO bank; and the peripherals each binary drives its own way, handed over untouched.
//!
//! `src/main.rs` builds its drivers (UART0, the USB port, the servo PWM, the safety pins) on
//! [`Board`]; `src/bin/bench.rs` its blocking UART0 and marker pin, so that the benchmark runs
//! on the very clocks the firmware does.

use rp2040_hal::{self as hal, clocks::ClocksManager, pac, Sio, Watchdog};

/// Second-stage bootloader for the Pico's W25Q080 flash: the first 256 bytes of flash
/// (`memory.x` places the `.boot2` section there).
#[unsafe(link_section = ".boot2")]
#[used]
pub static BOOT2: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

/// The Pico's crystal, Hz.
pub const XTAL_HZ: u32 = 12_000_000;

/// The chip after [`Board::take`]: clocks running, GPIOs in their reset state, the rest of the
/// peripherals not yet configured.
pub struct Board {
    /// Not started: each binary decides whether and when.
    pub watchdog: Watchdog,
    pub clocks: ClocksManager,
    /// GP0..GP29 in their reset state.
    pub pins: hal::gpio::Pins,
    pub resets: pac::RESETS,
    pub uart0: pac::UART0,
    pub pwm: pac::PWM,
    pub timer: pac::TIMER,
    pub usbctrl_regs: pac::USBCTRL_REGS,
    pub usbctrl_dpram: pac::USBCTRL_DPRAM,
    /// The XIP controller (its cache's hit and access counters, for the benchmark).
    pub xip_ctrl: pac::XIP_CTRL,
}

impl Board {
    /// Takes the chip's peripherals and starts the clocks and the GPIO bank. Call once, first
    /// thing; panics if called again, or if the crystal or a PLL does not start (nothing could
    /// run).
    pub fn take() -> Board {
        let mut p = pac::Peripherals::take().expect("peripherals are taken once, here");
        let mut watchdog = Watchdog::new(p.WATCHDOG);
        let Ok(clocks) = hal::clocks::init_clocks_and_plls(
            XTAL_HZ,
            p.XOSC,
            p.CLOCKS,
            p.PLL_SYS,
            p.PLL_USB,
            &mut p.RESETS,
            &mut watchdog,
        ) else {
            panic!("clock setup failed");
        };
        let sio = Sio::new(p.SIO);
        let pins = hal::gpio::Pins::new(p.IO_BANK0, p.PADS_BANK0, sio.gpio_bank0, &mut p.RESETS);
        Board {
            watchdog,
            clocks,
            pins,
            resets: p.RESETS,
            uart0: p.UART0,
            pwm: p.PWM,
            timer: p.TIMER,
            usbctrl_regs: p.USBCTRL_REGS,
            usbctrl_dpram: p.USBCTRL_DPRAM,
            xip_ctrl: p.XIP_CTRL,
        }
    }
}
