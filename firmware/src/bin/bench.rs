//! IK benchmark firmware (`./dev bench`; `emulator/src/bench.js` drives it).
//!
//! Runs the firmware's own IK, `kinematics_core::ik::Solver::solve` with the firmware's
//! [`RomMath`] (the code path `control::Controller` runs for every pose), on poses sent over
//! UART0, and for comparison the same IK with `libm` (a straightforward port). GP16 is a
//! marker: it is high exactly while one IK runs, so the emulator reads the CPU cycle counter at
//! its edges. Each pose gets three brackets: an empty one (the marker's own cost, subtracted),
//! the ROM IK and the `libm` IK.
//!
//! Protocol (921,600 baud 8N1, lines end in LF; numbers are f32 bit patterns in hex, so
//! nothing is lost in decimal conversion):
//! - `p X Y Z ROLL PITCH YAW` (mm, rad) -> `r W1..W6 l W1..W6`: the six pulse widths (us)
//!   from the ROM path and from `libm`; an IK error gives `x` in place of the six widths.
//! - `t` -> `t fadd=ADDR ...`: the ROM addresses of the soft-float routines the IK uses.
//! - `m` -> `m sin=E cos=E sqrt=E atan2=E`: the largest difference between [`RomMath`] and
//!   `libm` on the chip over a grid of arguments (absolute; sqrt relative).

#![no_std]
#![no_main]

use core::fmt::Write as _;
use core::hint::black_box;

use defmt_rtt as _;
use embedded_hal::digital::OutputPin;
use firmware::rom_math::RomMath;
use heapless::String;
use kinematics_core::{ik, Geometry, Libm, Math, Pose, ServoSet, LEGS};
use panic_probe as _;
use rp2040_hal::{
    self as hal,
    clocks::Clock,
    fugit::RateExtU32,
    pac,
    uart::{DataBits, StopBits, UartConfig, UartPeripheral},
    Sio, Watchdog,
};

#[unsafe(link_section = ".boot2")]
#[used]
pub static BOOT2: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

const BAUD: u32 = 921_600;
const MAX_LINE: usize = 128;

#[hal::entry]
fn main() -> ! {
    let mut p = pac::Peripherals::take().expect("peripherals are taken once, here");
    let mut watchdog = Watchdog::new(p.WATCHDOG);
    let clocks = firmware::init_clocks(
        p.XOSC,
        p.CLOCKS,
        p.PLL_SYS,
        p.PLL_USB,
        &mut p.RESETS,
        &mut watchdog,
    );
    let sio = Sio::new(p.SIO);
    let pins = hal::gpio::Pins::new(p.IO_BANK0, p.PADS_BANK0, sio.gpio_bank0, &mut p.RESETS);
    let uart_pins = (pins.gpio0.into_function(), pins.gpio1.into_function());
    let uart = UartPeripheral::new(p.UART0, uart_pins, &mut p.RESETS)
        .enable(
            UartConfig::new(BAUD.Hz(), DataBits::Eight, None, StopBits::One),
            clocks.peripheral_clock.freq(),
        )
        .expect("921600 baud is in range");
    let mut marker = pins.gpio16.into_push_pull_output();
    let _ = marker.set_low();

    let solver = ik::Solver::new(Geometry::default()).expect("a valid geometry");
    let servos = ServoSet::default();
    let mut line = [0u8; MAX_LINE];
    let mut len = 0;
    let mut out: String<256> = String::new();
    let _ = writeln!(
        out,
        "bench ready rom=v{}",
        hal::rom_data::rom_version_number()
    );
    uart.write_full_blocking(out.as_bytes());
    loop {
        let mut byte = [0u8];
        if uart.read_full_blocking(&mut byte).is_err() {
            continue;
        }
        if byte[0] != b'\n' {
            if len < MAX_LINE {
                line[len] = byte[0];
                len += 1;
            }
            continue;
        }
        out.clear();
        let text = core::str::from_utf8(&line[..len]).unwrap_or("");
        len = 0;
        match text
            .split_once(' ')
            .map_or((text, ""), |(c, rest)| (c, rest))
        {
            ("p", args) => match parse_pose(args) {
                Some(pose) => {
                    // Empty bracket: what the marker itself costs.
                    let _ = marker.set_high();
                    black_box(&pose);
                    let _ = marker.set_low();
                    let _ = marker.set_high();
                    let rom = solver.solve::<RomMath>(&servos, black_box(&pose));
                    black_box(&rom);
                    let _ = marker.set_low();
                    let _ = marker.set_high();
                    let libm = solver.solve::<Libm>(&servos, black_box(&pose));
                    black_box(&libm);
                    let _ = marker.set_low();
                    let _ = out.push('r');
                    write_pulses(&mut out, rom.map(|s| s.pulse_us).ok());
                    let _ = out.push_str(" l");
                    write_pulses(&mut out, libm.map(|s| s.pulse_us).ok());
                }
                None => {
                    let _ = out.push_str("error: bad pose");
                }
            },
            ("t", _) => {
                // Where the soft-float routines are, so the harness can name ROM addresses.
                let table = hal::rom_data::soft_float_table();
                let _ = out.push('t');
                for (name, offset) in firmware::rom_math::IK_ROUTINES {
                    // SAFETY: offsets inside the table of every ROM version with fatan2 (v2+).
                    let address = unsafe { table.add(offset / 4).read() } & !1;
                    let _ = write!(out, " {name}={address:x}");
                }
            }
            ("m", _) => {
                let e = math_differences();
                let _ = write!(
                    out,
                    "m sin={:e} cos={:e} sqrt={:e} atan2={:e}",
                    e[0], e[1], e[2], e[3]
                );
            }
            _ => {
                let _ = out.push_str("error: unknown");
            }
        }
        let _ = out.push('\n');
        uart.write_full_blocking(out.as_bytes());
    }
}

/// Six f32 bit patterns in hex.
fn parse_pose(args: &str) -> Option<Pose> {
    let mut v = [0.0f32; 6];
    let mut words = args.split_ascii_whitespace();
    for x in v.iter_mut() {
        *x = f32::from_bits(u32::from_str_radix(words.next()?, 16).ok()?);
    }
    words.next().is_none().then(|| Pose::from_array(v))
}

fn write_pulses(out: &mut String<256>, pulses: Option<[f32; LEGS]>) {
    match pulses {
        Some(w) => {
            for x in w {
                let _ = write!(out, " {:08x}", x.to_bits());
            }
        }
        None => {
            let _ = out.push_str(" x");
        }
    }
}

/// Largest |RomMath - libm| over a grid: sin, cos on [-2 pi, 2 pi]; sqrt (relative) on
/// [0, 1e5]; atan2 all round the circle at several radii.
fn math_differences() -> [f32; 4] {
    let mut e = [0.0f32; 4];
    const N: i32 = 200;
    for k in -N..=N {
        let x = k as f32 * (2.0 * core::f32::consts::PI / N as f32);
        let (s, c) = RomMath::sin_cos(x);
        let (ls, lc) = Libm::sin_cos(x);
        e[0] = e[0].max((s - ls).abs());
        e[1] = e[1].max((c - lc).abs());
        let y = (k + N) as f32 * 25.0;
        let (r, lr) = (RomMath::sqrt(y), Libm::sqrt(y));
        if lr > 0.0 {
            e[2] = e[2].max((r - lr).abs() / lr);
        }
        for radius in [1e-3f32, 1.0, 3e3] {
            let (sy, sx) = Libm::sin_cos(x * 0.5);
            let (yy, xx) = (radius * sy, radius * sx);
            e[3] = e[3].max((RomMath::atan2(yy, xx) - Libm::atan2(yy, xx)).abs());
        }
    }
    e
}
