//! IK benchmark firmware (`./dev bench`; `emulator/src/bench.js` drives it).
//!
//! Runs the firmware's own IK, `kinematics_core::ik::Solver::solve` with the firmware's
//! [`RomMath`] (the code path `control::Controller` runs for every pose: its fixed-point path,
//! with the core's integer sine, square root and arc tangent), on poses sent over UART0, and
//! for comparison the same IK with other libraries' routines in their place
//! ([`FloatRoutines`]): the boot ROM's float routines (what the firmware used before), `libm`'s
//! and, built with the `micromath` feature (`./dev bench` does), `micromath`'s: all three, and
//! each alone. Every variant has its own solver (its home angles from its own routines, as a
//! firmware built on them would). GP16 is a marker: it is high exactly while one computation
//! runs, so the emulator reads the CPU cycle counter at its edges. Each pose gets an empty
//! bracket first (the marker's own cost, subtracted), then one per variant.
//!
//! Protocol (921,600 baud 8N1, lines end in LF; numbers are f32 bit patterns in hex, so
//! nothing is lost in decimal conversion). At start: `bench ready rom=vN variants=A,B,...`.
//! - `p X Y Z ROLL PITCH YAW` (mm, rad) -> `r W1..W6 W1..W6 ...`: the six pulse widths (us)
//!   of each variant in the order of `variants`; an IK error gives `x` in place of six widths.
//! - `i X Y Z ROLL PITCH YAW` -> `i W1..W6`: the firmware's IK alone, twice on the same pose
//!   (an empty bracket, then two measured ones): the second finds in the XIP cache what the
//!   first brought in (warm), the first what the line's handling left there.
//! - `t` -> `t fadd=ADDR ...`: the ROM addresses of the soft-float routines the IK uses.
//! - `x` -> `x hit=H acc=A`: the XIP cache's counters (XIP_CTRL CTR_HIT, CTR_ACC: hits and
//!   accesses to flash since the last `x`), then clears them; so `x`, a command, `x` gives the
//!   command's flash accesses (with the line's own handling), to compare a real Pico with the
//!   emulator's cache model (emulator/src/gaps/xip-cache.js).
//! - `m` -> `m rom=S,C,Q,A fixed=S,C,Q,A [micromath=S,C,Q,A]`: the largest errors on the chip
//!   against `libm`'s `f64` over a grid of arguments (sin, cos absolute; sqrt relative, but
//!   the fixed-point one's absolute, in units; atan2 rad): of the boot ROM's `f32` routines, of
//!   the IK's fixed-point ones, of `micromath`'s.
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
//!
//! The stream pipeline, through a real `control::Controller<RomMath>` (the firmware's) fed
//! binary stream frames (`control::stream`) whose counts encode the poses given:
//! - `c X Y Z ROLL PITCH YAW DZ` -> `c n=N`: in pass-through (speed limits off), a frame at the
//!   pose, applied (not measured), then one `DZ` mm higher, out of reach: the measured bracket
//!   is `Controller::apply_stream` and the clamp job it starts, run to its end with
//!   `Controller::work` (1 + `CLAMP_STEPS` IK solutions, bisection on the straight line, up to
//!   `CHECKS_PER_SLICE` per slice); `N` clamps counted (1 if it clamped);
//! - `k X Y Z ROLL PITCH YAW F` -> `k FLAGS`: with the tracker's default limits (speeds, and
//!   accelerations of 1000 mm/s^2 and 1000 deg/s^2), a frame at the pose becomes the tracker's
//!   goal, then `F` measured brackets of `Controller::on_frame` (the tracker's step and one IK),
//!   a flag per frame: `m` moved, `c` clamped (the step left the workspace: the tracker holds a
//!   step short of the edge, no bisection in the frame), `s` still.

#![no_std]
#![no_main]

use core::fmt::Write as _;
use core::hint::black_box;

use control::stream::{BINARY_HEADER, BINARY_TRAILER};
use control::{Controller, Session, Settings};
use defmt_rtt as _;
use embedded_hal::digital::OutputPin;
use firmware::rom_math::RomMath;
use firmware::Board;
use heapless::String;
use kinematics_core::forward::{self, Closure};
use kinematics_core::jacobian::Jacobian;
use kinematics_core::statics::{holding_loads, servo_holding_torques, Payload};
use kinematics_core::workspace::{self, Limits};
use kinematics_core::{ik, FloatRoutines, Geometry, Libm, Math, Pose, ServoSet, Vec3, LEGS};
use panic_probe as _;
use rp2040_hal::{
    self as hal,
    clocks::Clock,
    fugit::RateExtU32,
    uart::{DataBits, StopBits, UartConfig, UartPeripheral},
};

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
    let mut board = Board::take();
    let uart_pins = (
        board.pins.gpio0.into_function(),
        board.pins.gpio1.into_function(),
    );
    let uart = UartPeripheral::new(board.uart0, uart_pins, &mut board.resets)
        .enable(
            UartConfig::new(BAUD.Hz(), DataBits::Eight, None, StopBits::One),
            board.clocks.peripheral_clock.freq(),
        )
        .expect("921600 baud is in range");
    let xip = board.xip_ctrl;
    let mut marker = board.pins.gpio16.into_push_pull_output();
    let _ = marker.set_low();

    let solver = ik::Solver::new_with::<RomMath>(Geometry::default()).expect("a valid geometry");
    let variants = Variants::new();
    let servos = ServoSet::default();
    let mut streams = Streams::new();
    let mut line = [0u8; MAX_LINE];
    let mut len = 0;
    let mut out: String<512> = String::new();
    let _ = write!(
        out,
        "bench ready rom=v{} variants=",
        hal::rom_data::rom_version_number()
    );
    for (i, name) in Variants::NAMES.iter().enumerate() {
        let _ = write!(out, "{}{name}", if i == 0 { "" } else { "," });
    }
    let _ = out.push('\n');
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
                    bracket_empty(&mut marker, &pose);
                    let _ = out.push('r');
                    let firmware = timed::<RomMath>(&mut marker, &solver, &servos, &pose);
                    write_pulses(&mut out, firmware);
                    variants.run(&mut marker, &servos, &pose, &mut out);
                }
                None => {
                    let _ = out.push_str("error: bad pose");
                }
            },
            ("c", args) => match parse_floats::<7>(args) {
                Some(v) => {
                    let pose = Pose::from_array(core::array::from_fn(|i| v[i]));
                    let clamps = streams.clamp(&mut marker, &pose, v[6]);
                    let _ = write!(out, "c n={clamps}");
                }
                None => {
                    let _ = out.push_str("error: bad arguments");
                }
            },
            ("k", args) => match parse_floats::<7>(args) {
                Some(v) => {
                    let pose = Pose::from_array(core::array::from_fn(|i| v[i]));
                    let _ = out.push_str("k ");
                    streams.track(&mut marker, &pose, v[6] as u32, &mut out);
                }
                None => {
                    let _ = out.push_str("error: bad arguments");
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
            ("i", args) => match parse_pose(args) {
                Some(pose) => {
                    bracket_empty(&mut marker, &pose);
                    let _ = timed::<RomMath>(&mut marker, &solver, &servos, &pose);
                    let _ = out.push('i');
                    let again = timed::<RomMath>(&mut marker, &solver, &servos, &pose);
                    write_pulses(&mut out, again);
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
            ("x", _) => {
                let (hits, accesses) = (xip.ctr_hit().read().bits(), xip.ctr_acc().read().bits());
                // Any value written clears a counter (RP2040 datasheet, XIP_CTRL registers).
                xip.ctr_hit().reset();
                xip.ctr_acc().reset();
                let _ = write!(out, "x hit={hits} acc={accesses}");
            }
            ("m", _) => {
                let _ = out.push('m');
                write_errors(&mut out, "rom", float_errors::<RomMath>());
                write_errors(&mut out, "fixed", fixed_errors::<RomMath>());
                #[cfg(feature = "micromath")]
                write_errors(&mut out, "micromath", float_errors::<micro::Micromath>());
            }
            _ => {
                let _ = out.push_str("error: unknown");
            }
        }
        let _ = out.push('\n');
        uart.write_full_blocking(out.as_bytes());
    }
}

/// One IK in a marker bracket, with `M`: the six pulse widths, or `None` if refused.
fn timed<M: Math>(
    marker: &mut impl OutputPin,
    solver: &ik::Solver,
    servos: &ServoSet,
    pose: &Pose,
) -> Option<[f32; LEGS]> {
    let _ = marker.set_high();
    let solution = solver.solve::<M>(servos, black_box(pose));
    black_box(&solution);
    let _ = marker.set_low();
    solution.ok().map(|s| s.pulse_us)
}

/// The IK with other libraries' routines in the fixed-point path, each with its own solver.
struct Variants {
    rom: ik::Solver,
    libm: ik::Solver,
    #[cfg(feature = "micromath")]
    micromath: [ik::Solver; 4],
}

impl Variants {
    /// The variants' names, in the order of the reply to `p` (after the firmware's).
    #[cfg(not(feature = "micromath"))]
    const NAMES: &[&str] = &["firmware", "rom", "libm"];
    #[cfg(feature = "micromath")]
    const NAMES: &[&str] = &[
        "firmware",
        "rom",
        "libm",
        "micromath",
        "micromath-sin-cos",
        "micromath-sqrt",
        "micromath-atan2",
    ];

    fn new() -> Variants {
        fn solver<M: Math>() -> ik::Solver {
            ik::Solver::new_with::<M>(Geometry::default()).expect("a valid geometry")
        }
        Variants {
            rom: solver::<FloatRoutines<RomMath>>(),
            libm: solver::<FloatRoutines<Libm>>(),
            #[cfg(feature = "micromath")]
            micromath: [
                solver::<FloatRoutines<micro::Micromath>>(),
                solver::<micro::SinCosOnly>(),
                solver::<micro::SqrtOnly>(),
                solver::<micro::Atan2Only>(),
            ],
        }
    }

    /// One bracket per variant; their pulses appended to `out`.
    fn run(&self, marker: &mut impl OutputPin, servos: &ServoSet, pose: &Pose, out: &mut Out) {
        let rom = timed::<FloatRoutines<RomMath>>(marker, &self.rom, servos, pose);
        write_pulses(out, rom);
        let libm = timed::<FloatRoutines<Libm>>(marker, &self.libm, servos, pose);
        write_pulses(out, libm);
        #[cfg(feature = "micromath")]
        {
            let [all, sin_cos, sqrt, atan2] = &self.micromath;
            let m = timed::<FloatRoutines<micro::Micromath>>(marker, all, servos, pose);
            write_pulses(out, m);
            write_pulses(
                out,
                timed::<micro::SinCosOnly>(marker, sin_cos, servos, pose),
            );
            write_pulses(out, timed::<micro::SqrtOnly>(marker, sqrt, servos, pose));
            write_pulses(out, timed::<micro::Atan2Only>(marker, atan2, servos, pose));
        }
    }
}

/// `micromath`'s routines, as the IK's [`Math`] (the `micromath` feature).
#[cfg(feature = "micromath")]
mod micro {
    use firmware::rom_math::RomMath;
    use kinematics_core::{FloatRoutines, Math};
    use micromath::F32Ext;

    /// A [`Math`] named `$name` with the boot ROM's arithmetic and the routines given.
    macro_rules! rom_arithmetic {
        ($name:ident, $doc:literal, $($routines:tt)*) => {
            #[doc = $doc]
            pub struct $name;

            impl Math for $name {
                fn add(a: f32, b: f32) -> f32 {
                    RomMath::add(a, b)
                }
                fn sub(a: f32, b: f32) -> f32 {
                    RomMath::sub(a, b)
                }
                fn mul(a: f32, b: f32) -> f32 {
                    RomMath::mul(a, b)
                }
                $($routines)*
            }
        };
    }

    rom_arithmetic! {
        Micromath,
        "`micromath`'s sine, cosine, square root and arc tangent; the arithmetic the boot ROM's.",
        fn sin_cos(x: f32) -> (f32, f32) {
            F32Ext::sin_cos(x)
        }
        fn sqrt(x: f32) -> f32 {
            F32Ext::sqrt(x)
        }
        fn atan2(y: f32, x: f32) -> f32 {
            F32Ext::atan2(y, x)
        }
    }

    /// The firmware's maths with one of `micromath`'s routines in the IK's fixed-point path.
    macro_rules! one_routine {
        ($name:ident, $doc:literal, $($routine:tt)*) => {
            rom_arithmetic!(
                $name,
                $doc,
                fn sin_cos(x: f32) -> (f32, f32) {
                    RomMath::sin_cos(x)
                }
                fn sqrt(x: f32) -> f32 {
                    RomMath::sqrt(x)
                }
                fn atan2(y: f32, x: f32) -> f32 {
                    RomMath::atan2(y, x)
                }
                $($routine)*
            );
        };
    }

    one_routine!(
        SinCosOnly,
        "`micromath`'s sine and cosine only.",
        fn sin_cos_fixed(x_rad: f32) -> (i32, i32) {
            FloatRoutines::<Micromath>::sin_cos_fixed(x_rad)
        }
    );
    one_routine!(
        SqrtOnly,
        "`micromath`'s square root only.",
        fn sqrt_fixed(d: u64) -> u32 {
            FloatRoutines::<Micromath>::sqrt_fixed(d)
        }
    );
    one_routine!(
        Atan2Only,
        "`micromath`'s arc tangent only.",
        fn atan2_fixed(y: i32, x: i32) -> i32 {
            FloatRoutines::<Micromath>::atan2_fixed(y, x)
        }
    );
}

/// The stream pipeline of the firmware's own controller (see the module docs), two of them:
/// one in pass-through, one tracking.
struct Streams {
    pass_through: Controller<RomMath>,
    tracking: Controller<RomMath>,
    session: Session,
}

/// Full scales of the bench's stream frames (`stream.*` settings: mm, degrees): the bench
/// poses and clamp targets well inside them.
const STREAM_SCALES: [(&str, f32); 6] = [
    ("stream.x_mm", 100.0),
    ("stream.y_mm", 100.0),
    ("stream.z_mm", 100.0),
    ("stream.roll_deg", 45.0),
    ("stream.pitch_deg", 45.0),
    ("stream.yaw_deg", 45.0),
];

impl Streams {
    fn new() -> Streams {
        let mut streams = Streams {
            pass_through: Controller::with_math(Settings::default()),
            tracking: Controller::with_math(Settings::default()),
            session: Session::default(),
        };
        let mut sink = Sink;
        let mut set = |ctl: &mut Controller<RomMath>, line: &str| {
            ctl.execute_line(&mut streams.session, line, &mut sink);
        };
        let mut text: String<64> = String::new();
        for ctl in [&mut streams.pass_through, &mut streams.tracking] {
            for (name, scale) in STREAM_SCALES {
                text.clear();
                let _ = write!(text, "set {name} {scale}");
                set(ctl, &text);
            }
        }
        set(&mut streams.pass_through, "set speed_mm_s off");
        set(&mut streams.pass_through, "set speed_deg_s off");
        set(&mut streams.tracking, "set accel_mm_s2 1000");
        set(&mut streams.tracking, "set accel_deg_s2 1000");
        streams
    }

    /// A binary stream frame for `pose` (mm, rad) at [`STREAM_SCALES`], fed to `ctl`.
    fn feed(ctl: &mut Controller<RomMath>, session: &mut Session, pose: &Pose) {
        let mut frame = [0u8; 16];
        frame[..2].copy_from_slice(&BINARY_HEADER);
        for (k, value) in pose.to_array().into_iter().enumerate() {
            let (_, scale) = STREAM_SCALES[k];
            let full = if k < 3 { scale } else { scale.to_radians() };
            let count = (32768.0 + value / full * 32768.0 + 0.5).clamp(0.0, 65535.0) as u16;
            frame[2 + 2 * k..4 + 2 * k].copy_from_slice(&count.to_be_bytes());
        }
        frame[14..].copy_from_slice(&BINARY_TRAILER);
        for byte in frame {
            let _ = ctl.on_byte(session, byte, &mut Sink);
        }
    }

    /// Pass-through to `pose`, then a clamp of a target `dz_mm` above it (measured).
    fn clamp(&mut self, marker: &mut impl OutputPin, pose: &Pose, dz_mm: f32) -> u32 {
        let ctl = &mut self.pass_through;
        Streams::feed(ctl, &mut self.session, pose);
        ctl.apply_stream();
        let before = ctl.stream_counts().clamped;
        let mut target = *pose;
        target.z_mm += dz_mm;
        Streams::feed(ctl, &mut self.session, &target);
        bracket_empty(marker, pose);
        let _ = marker.set_high();
        ctl.apply_stream();
        while ctl.is_busy() {
            ctl.work(&mut self.session, &mut Sink);
        }
        let _ = marker.set_low();
        black_box(ctl.pose());
        ctl.stream_counts().clamped.wrapping_sub(before)
    }

    /// `pose` as the tracker's goal, then `frames` servo frames (each measured), a flag each
    /// in `out` (see the module docs).
    fn track(&mut self, marker: &mut impl OutputPin, pose: &Pose, frames: u32, out: &mut Out) {
        let ctl = &mut self.tracking;
        Streams::feed(ctl, &mut self.session, pose);
        ctl.apply_stream();
        bracket_empty(marker, pose);
        for _ in 0..frames {
            let (before, clamps) = (*ctl.pose(), ctl.stream_counts().clamped);
            let _ = marker.set_high();
            let pulses = ctl.on_frame();
            let _ = marker.set_low();
            black_box(pulses);
            let flag = if ctl.stream_counts().clamped != clamps {
                'c'
            } else if *ctl.pose() != before {
                'm'
            } else {
                's'
            };
            let _ = out.push(flag);
        }
    }
}

/// Discards the controllers' replies.
struct Sink;

impl core::fmt::Write for Sink {
    fn write_str(&mut self, _: &str) -> core::fmt::Result {
        Ok(())
    }
}

type Out = String<512>;

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

fn write_pulses(out: &mut Out, pulses: Option<[f32; LEGS]>) {
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

/// The largest errors of `M`'s `f32` routines against `libm`'s `f64` over a grid: sin, cos on
/// [-pi, pi] (the pose's angles); sqrt (relative) on [0, 1e5]; atan2 (rad) all round the
/// circle at several radii.
fn float_errors<M: Math>() -> [f64; 4] {
    let mut e = [0.0f64; 4];
    for k in -GRID..=GRID {
        let x = k as f32 * (core::f32::consts::PI / GRID as f32);
        let (s, c) = M::sin_cos(x);
        let (ls, lc) = libm::sincos(f64::from(x));
        e[0] = e[0].max((f64::from(s) - ls).abs());
        e[1] = e[1].max((f64::from(c) - lc).abs());
        let y = (k + GRID) as f32 * 25.0;
        let ly = libm::sqrt(f64::from(y));
        if ly > 0.0 {
            e[2] = e[2].max((f64::from(M::sqrt(y)) - ly).abs() / ly);
        }
        for radius in [1e-3f32, 1.0, 3e3] {
            let (yy, xx) = (radius * libm::sinf(x), radius * libm::cosf(x));
            let exact = libm::atan2(f64::from(yy), f64::from(xx));
            e[3] = e[3].max(angle_difference(f64::from(M::atan2(yy, xx)), exact));
        }
    }
    e
}

/// The same for `M`'s fixed-point routines (the ones the IK's hot loop calls): sin, cos of the
/// same angles; sqrt (absolute, in units) of integers up to 2^59 spread pseudo-randomly (the
/// IK's discriminants); atan2 (rad) of vectors of radius 2^29.
fn fixed_errors<M: Math>() -> [f64; 4] {
    let mut e = [0.0f64; 4];
    for k in -GRID..=GRID {
        let x = k as f32 * (core::f32::consts::PI / GRID as f32);
        let (s, c) = M::sin_cos_fixed(x);
        let (ls, lc) = libm::sincos(f64::from(x));
        let unit = f64::from(1u32 << 30);
        e[0] = e[0].max((f64::from(s) / unit - ls).abs());
        e[1] = e[1].max((f64::from(c) / unit - lc).abs());
        let d = ((k + GRID) as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 5;
        e[2] = e[2].max((f64::from(M::sqrt_fixed(d)) - libm::sqrt(d as f64)).abs());
        let radius = f64::from(1u32 << 29);
        let (yy, xx) = (
            radius * libm::sin(f64::from(x)),
            radius * libm::cos(f64::from(x)),
        );
        let exact = libm::atan2(f64::from(yy as i32), f64::from(xx as i32));
        let angle = f64::from(M::atan2_fixed(yy as i32, xx as i32)) / radius;
        e[3] = e[3].max(angle_difference(angle, exact));
    }
    e
}

/// `|a - b|` as angles (rad): `pi` and `-pi` are the same direction.
fn angle_difference(a: f64, b: f64) -> f64 {
    let d = (a - b).abs() % (2.0 * core::f64::consts::PI);
    d.min(2.0 * core::f64::consts::PI - d)
}

/// Half the number of grid points of [`float_errors`] and [`fixed_errors`].
const GRID: i32 = 200;

/// `name=a,b,c,d` (sin, cos, sqrt, atan2 errors).
fn write_errors(out: &mut Out, name: &str, e: [f64; 4]) {
    let _ = write!(out, " {name}={:e},{:e},{:e},{:e}", e[0], e[1], e[2], e[3]);
}
