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
//!
//! The rest of the kinematics, all with [`RomMath`], each bracketed like the IK (an empty
//! bracket, then the one measured):
//! - `f W1..W6 X Y Z ROLL PITCH YAW` -> `f X Y Z ROLL PITCH YAW n=N`: forward kinematics from
//!   six pulse widths (us) starting at the pose given (the previous frame's):
//!   `forward::Closure::pulses` and `forward::solve` to convergence, `N` iterations; `f x`
//!   if it fails;
//! - `j X Y Z ROLL PITCH YAW` -> `j J11 J12 .. J66`: the servo Jacobian at the pose
//!   (`jacobian::Jacobian::at`: the IK, the arm tips, the rows), row by row;
//! - `q X Y Z ROLL PITCH YAW` -> `q T1..T6 U1..U6`: the holding torques (N mm) for
//!   [`PAYLOAD`] from the pose (`statics::holding_loads`: the IK, the Jacobian, a 6x6 solve),
//!   then again from the IK's arm angles (`statics::servo_holding_torques`, what a firmware
//!   that has just solved the pose does; a second measured bracket);
//! - `w X Y Z ROLL PITCH YAW` -> `w D1..D12 n=N`: the reach along the twelve
//!   axis-directions from the pose within the default servo limits (`workspace::Limits`, what
//!   a `limits` command does), `N` IKs.

#![no_std]
#![no_main]

use core::fmt::Write as _;
use core::hint::black_box;

use defmt_rtt as _;
use embedded_hal::digital::OutputPin;
use firmware::rom_math::RomMath;
use heapless::String;
use kinematics_core::forward::{self, Closure};
use kinematics_core::jacobian::Jacobian;
use kinematics_core::statics::{holding_loads, servo_holding_torques, Payload};
use kinematics_core::workspace::{self, Limits};
use kinematics_core::{ik, Geometry, Libm, Math, Pose, ServoSet, Vec3, LEGS};
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
/// The payload of the torque benchmark: 1 kg, 30 mm above the platform's centre.
const PAYLOAD: Payload = Payload {
    mass_kg: 1.0,
    centre_of_mass_mm: Vec3::new(0.0, 0.0, 30.0),
    inertia_kg_mm2: kinematics_core::Mat3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
};

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
    let mut out: String<512> = String::new();
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
            ("f", args) => match parse_floats::<12>(args) {
                Some(v) => {
                    let pulses: [f32; LEGS] = core::array::from_fn(|i| v[i]);
                    let start = Pose::from_array(core::array::from_fn(|i| v[LEGS + i]));
                    let _ = marker.set_high();
                    black_box(&pulses);
                    let _ = marker.set_low();
                    let _ = marker.set_high();
                    let found = Closure::pulses::<RomMath>(&solver, &servos, black_box(&pulses))
                        .and_then(|c| forward::solve::<RomMath>(&c, &start, Default::default()));
                    black_box(&found);
                    let _ = marker.set_low();
                    let _ = out.push('f');
                    match found {
                        Ok(c) => {
                            write_floats(&mut out, &c.pose.to_array());
                            let _ = write!(out, " n={}", c.iterations);
                        }
                        Err(_) => {
                            let _ = out.push_str(" x");
                        }
                    }
                }
                None => {
                    let _ = out.push_str("error: bad arguments");
                }
            },
            ("j", args) => match parse_pose(args) {
                Some(pose) => {
                    bracket_empty(&mut marker, &pose);
                    let _ = marker.set_high();
                    let j = Jacobian::at::<RomMath, _>(&solver, black_box(&pose));
                    black_box(&j);
                    let _ = marker.set_low();
                    let _ = out.push('j');
                    match j {
                        Ok(j) => {
                            for row in 0..LEGS {
                                let values: [f32; 6] = core::array::from_fn(|k| j.matrix[(row, k)]);
                                write_floats(&mut out, &values);
                            }
                        }
                        Err(_) => {
                            let _ = out.push_str(" x");
                        }
                    }
                }
                None => {
                    let _ = out.push_str("error: bad pose");
                }
            },
            ("q", args) => match parse_pose(args) {
                Some(pose) => {
                    let arm_rad = solver.arm_angles::<RomMath>(&pose).unwrap_or([0.0; LEGS]);
                    bracket_empty(&mut marker, &pose);
                    let _ = marker.set_high();
                    let torques = holding_loads::<RomMath, _>(&solver, black_box(&pose), &PAYLOAD);
                    black_box(&torques);
                    let _ = marker.set_low();
                    let _ = marker.set_high();
                    let again = servo_holding_torques::<RomMath>(
                        &solver,
                        black_box(&pose),
                        black_box(&arm_rad),
                        &PAYLOAD,
                    );
                    black_box(&again);
                    let _ = marker.set_low();
                    let _ = out.push('q');
                    match (torques, again) {
                        (Ok(t), Ok(u)) => {
                            write_floats(&mut out, &t);
                            write_floats(&mut out, &u);
                        }
                        _ => {
                            let _ = out.push_str(" x");
                        }
                    }
                }
                None => {
                    let _ = out.push_str("error: bad pose");
                }
            },
            ("w", args) => match parse_pose(args) {
                Some(pose) => {
                    bracket_empty(&mut marker, &pose);
                    let mut tests = 0u32;
                    let _ = marker.set_high();
                    let mut limits = Limits::new(black_box(pose), workspace::Options::default());
                    let reach = loop {
                        let done = limits.step(|p| {
                            tests += 1;
                            solver.solve::<RomMath>(&servos, p).map(|_| ())
                        });
                        if let Some(all) = done {
                            break all;
                        }
                    };
                    black_box(&reach);
                    let _ = marker.set_low();
                    let _ = out.push('w');
                    let distances: [f32; 12] = core::array::from_fn(|k| reach[k].distance);
                    write_floats(&mut out, &distances);
                    let _ = write!(out, " n={tests}");
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
    parse_floats::<6>(args).map(Pose::from_array)
}

/// `N` f32 bit patterns in hex, and nothing more.
fn parse_floats<const N: usize>(args: &str) -> Option<[f32; N]> {
    let mut v = [0.0f32; N];
    let mut words = args.split_ascii_whitespace();
    for x in v.iter_mut() {
        *x = f32::from_bits(u32::from_str_radix(words.next()?, 16).ok()?);
    }
    words.next().is_none().then_some(v)
}

/// The empty bracket before a measured one: what the marker itself costs.
fn bracket_empty(marker: &mut impl OutputPin, pose: &Pose) {
    let _ = marker.set_high();
    black_box(pose);
    let _ = marker.set_low();
}

fn write_floats(out: &mut String<512>, values: &[f32]) {
    for x in values {
        let _ = write!(out, " {:08x}", x.to_bits());
    }
}

fn write_pulses(out: &mut String<512>, pulses: Option<[f32; LEGS]>) {
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
