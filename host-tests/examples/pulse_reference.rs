//! The host core's answer for poses, for the emulator's end-to-end tests.
//!
//! The tests drive the real firmware (RP2040 boot ROM floats) in the emulator and compare the
//! pulse widths measured on its pins with what the host build of `kinematics-core` (libm)
//! computes for the same pose and settings. This program is that host computation; it uses
//! only `kinematics-core` (not the `control` crate, whose behaviour is under test), and for
//! `f64` the independent f64 reference of `host-tests`.
//!
//! It reads commands from stdin, one per line, and answers each with one line of JSON:
//!
//! ```text
//! layout <base_radius_mm> <base_half_angle_deg> <platform_radius_mm>
//!        <platform_half_angle_deg> <arm_mm> <rod_mm>
//!     -> {"ok":true} or {"ok":false,"error":"..."}             (the geometry used from now on)
//! servo <1-6> <trim_us> <rate_us_rad> <normal|reversed> <min_us> <max_us>
//!     -> {"ok":true}                                            (that servo from now on)
//! pivot <x_mm> <y_mm> <z_mm>
//!     -> {"ok":true} or {"ok":false,"error":"..."}   (the rotation centre, platform frame,
//!         from now on, whatever the layout)
//! f64 <x_mm> <y_mm> <z_mm> <roll_deg> <pitch_deg> <yaw_deg>
//!     -> {"ok":true,"arm_deg":[6],"pulse_us":[6]} | {"ok":false,"code":"unreachable"}
//!         (not the core: `host_tests::platform`'s f64 chain of frames about the pivot and a
//!         numeric root of each rod closure, eq. 13, 14 in f64; no servo limits)
//! solve <x_mm> <y_mm> <z_mm> <roll_deg> <pitch_deg> <yaw_deg>
//!     -> {"ok":true,"arm_deg":[6],"pulse_us":[6]}
//!      | {"ok":false,"code":"unreachable","leg":n}
//!      | {"ok":false,"code":"servo-limit","servo":n,"pulse_us":w,"min_us":lo,"max_us":hi}
//!      | {"ok":false,"code":"angle-too-large","axis":"roll"}
//!      | {"ok":false,"code":"pose-not-finite","axis":"x"}
//! geometry
//!     -> {"ok":true,"arm_mm":a,"rod_mm":s,"h0_mm":h,
//!         "legs":[{"b_mm":[3],"p_mm":[3],"beta_deg":b,"alpha0_deg":a0}]}
//! payload <mass_g> <com_x_mm> <com_y_mm> <com_z_mm>
//!     -> {"ok":true}                           (the payload from now on; 0 g: none)
//! ratings <t1> .. <t6>
//!     -> {"ok":true}                           (torque ratings, kgf cm, 0 = not rated)
//! torque <x_mm> <y_mm> <z_mm> <roll_deg> <pitch_deg> <yaw_deg>
//!     -> {"ok":true,"torque_kgcm":[6]}         (holding torques at the pose, signed)
//!      | a solve error | {"ok":false,"code":"kinematics","error":"..."}
//! fk <w1_us> .. <w6_us> <x_mm> <y_mm> <z_mm> <roll_deg> <pitch_deg> <yaw_deg>
//!     -> {"ok":true,"pose":[x,y,z,roll,pitch,yaw]}  (the pose of six pulses, reached from the
//!         pose given: the arm angles go from the IK's there to the pulses' in 0.25 degree
//!         steps, each solved by Newton's method from the last, the end checked with the IK)
//!      | {"ok":false,"code":"no-pose","error":"..."}
//! limits <x_mm> <y_mm> <z_mm> <roll_deg> <pitch_deg> <yaw_deg>
//!     -> {"ok":true,"reaches":[12 x {"axis":"x","sense":"-","distance":d,"extreme":e,
//!         "limit":{"kind":"blocked"|"range"|"start", ...why}}]}  (mm or degrees; x- first;
//!         within the servo limits and, with a payload and ratings, the ratings)
//!     why: "code":"unreachable","leg":n | "code":"servo-limit","servo":n,"bound":"min_us"|
//!          "max_us","limit_us":w | "code":"torque-limit","servo":n,"rated_kgcm":r |
//!          "code":"angle-too-large","axis":a | "code":"kinematics","error":"..."
//! ```
//!
//! It starts with the core's default layout and servos; the tests send theirs explicitly.
//! Numbers are read as `f32` (as the firmware reads what is typed) and printed in full.
//!
//! `cargo run -q -p host-tests --example pulse_reference` (the tests build it once and run
//! the binary).

use std::fmt::Write as _;
use std::io::{self, BufRead, Write};

use host_tests::platform::RefArms;
use host_tests::reference::RefPose;
use kinematics_core::forward;
use kinematics_core::geometry::PairedLayout;
use kinematics_core::ik::{self, IkError};
use kinematics_core::statics::{servo_holding_torques, Payload, N_MM_PER_KGF_CM};
use kinematics_core::workspace::{self, Limit, Sense};
use kinematics_core::{Direction, KinematicsError, Libm, Pose, ServoConfig, ServoSet, Vec3, LEGS};

struct Reference {
    layout: PairedLayout,
    /// The IK of the layout's geometry (and the geometry).
    solver: ik::Solver,
    servos: ServoSet,
    /// Mass (kg; 0: none) and centre of mass (platform frame, mm).
    payload: Payload,
    /// Torque ratings, kgf cm (0: not rated).
    ratings_kgcm: [f32; LEGS],
    /// The rotation centre (platform frame), mm.
    pivot_mm: Vec3,
}

/// Why a pose fails the `limits` test.
#[derive(Debug, Clone, Copy)]
enum Fails {
    Ik(IkError),
    Torque { servo: u8, rated_kgcm: f32 },
    Kinematics(KinematicsError),
}

/// A JSON number (`null` for a value that is not finite, which JSON cannot express).
fn num(v: f32) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        "null".to_owned()
    }
}

fn nums(values: &[f32]) -> String {
    let parts: Vec<String> = values.iter().map(|&v| num(v)).collect();
    format!("[{}]", parts.join(","))
}

fn error(message: &str) -> String {
    let mut text = String::new();
    for c in message.chars() {
        match c {
            '"' | '\\' => {
                text.push('\\');
                text.push(c);
            }
            c if c.is_control() => text.push(' '),
            c => text.push(c),
        }
    }
    format!("{{\"ok\":false,\"error\":\"{text}\"}}")
}

/// A JSON string's contents.
fn quoted(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        match c {
            '"' | '\\' => {
                out.push('\\');
                out.push(c);
            }
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// An IK error as `solve` answers it.
fn ik_error(e: &IkError) -> String {
    match *e {
        IkError::Unreachable { leg } => {
            format!("{{\"ok\":false,\"code\":\"unreachable\",\"leg\":{leg}}}")
        }
        IkError::ServoLimit {
            servo,
            pulse_us,
            min_us,
            max_us,
        } => format!(
            "{{\"ok\":false,\"code\":\"servo-limit\",\"servo\":{servo},\"pulse_us\":{},\"min_us\":{},\"max_us\":{}}}",
            num(pulse_us),
            num(min_us),
            num(max_us)
        ),
        IkError::AngleTooLarge { axis, .. } => format!(
            "{{\"ok\":false,\"code\":\"angle-too-large\",\"axis\":\"{}\"}}",
            axis.name()
        ),
        IkError::NonFinite { axis } => format!(
            "{{\"ok\":false,\"code\":\"pose-not-finite\",\"axis\":\"{}\"}}",
            axis.name()
        ),
    }
}

/// A torque or limits failure as an answer.
fn fails(e: &Fails) -> String {
    format!("{{\"ok\":false,{}}}", why(e))
}

/// The fields that say why a pose fails.
fn why(e: &Fails) -> String {
    match *e {
        Fails::Ik(IkError::Unreachable { leg }) => {
            format!("\"code\":\"unreachable\",\"leg\":{leg}")
        }
        Fails::Ik(IkError::ServoLimit {
            servo,
            pulse_us,
            min_us,
            max_us,
        }) => {
            let (bound, limit) = if pulse_us > max_us {
                ("max_us", max_us)
            } else {
                ("min_us", min_us)
            };
            format!(
                "\"code\":\"servo-limit\",\"servo\":{servo},\"pulse_us\":{},\"bound\":\"{bound}\",\"limit_us\":{}",
                num(pulse_us),
                num(limit)
            )
        }
        Fails::Ik(IkError::AngleTooLarge { axis, .. }) => {
            format!("\"code\":\"angle-too-large\",\"axis\":\"{}\"", axis.name())
        }
        Fails::Ik(IkError::NonFinite { axis }) => {
            format!("\"code\":\"pose-not-finite\",\"axis\":\"{}\"", axis.name())
        }
        Fails::Torque { servo, rated_kgcm } => format!(
            "\"code\":\"torque-limit\",\"servo\":{servo},\"rated_kgcm\":{}",
            num(rated_kgcm)
        ),
        Fails::Kinematics(e) => format!(
            "\"code\":\"kinematics\",\"error\":\"{}\"",
            quoted(&e.to_string())
        ),
    }
}

fn numbers<const N: usize>(words: &[&str]) -> Result<[f32; N], String> {
    if words.len() != N {
        return Err(format!("expected {N} numbers, got {}", words.len()));
    }
    let mut out = [0.0; N];
    for (slot, word) in out.iter_mut().zip(words) {
        *slot = word
            .parse::<f32>()
            .map_err(|e| format!("'{word}' is not a number: {e}"))?;
    }
    Ok(out)
}

impl Reference {
    fn new() -> Reference {
        let layout = PairedLayout::default();
        let geometry = layout.build().expect("the default layout builds");
        Reference {
            layout,
            solver: ik::Solver::new(geometry).expect("the default layout builds"),
            servos: ServoSet::default(),
            payload: Payload::point(0.0, Vec3::zeros()),
            ratings_kgcm: [0.0; LEGS],
            pivot_mm: Vec3::zeros(),
        }
    }

    fn run(&mut self, line: &str) -> String {
        let words: Vec<&str> = line.split_whitespace().collect();
        let result = match words.split_first() {
            Some((&"layout", rest)) => self.set_layout(rest),
            Some((&"servo", rest)) => self.set_servo(rest),
            Some((&"solve", rest)) => numbers::<6>(rest).map(|v| self.solve(v)),
            Some((&"geometry", [])) => Ok(self.geometry()),
            Some((&"payload", rest)) => numbers::<4>(rest).map(|[g, x, y, z]| {
                self.payload = Payload::point(g / 1000.0, Vec3::new(x, y, z));
                "{\"ok\":true}".to_owned()
            }),
            Some((&"ratings", rest)) => numbers::<6>(rest).map(|r| {
                self.ratings_kgcm = r;
                "{\"ok\":true}".to_owned()
            }),
            Some((&"torque", rest)) => numbers::<6>(rest).map(|v| self.torque(v)),
            Some((&"fk", rest)) => numbers::<12>(rest).map(|v| self.fk(v)),
            Some((&"limits", rest)) => numbers::<6>(rest).map(|v| self.limits(v)),
            Some((&"pivot", rest)) => numbers::<3>(rest).and_then(|[x, y, z]| {
                let pivot = Vec3::new(x, y, z);
                self.solver
                    .set_rotation_centre_mm(pivot)
                    .map_err(|e| format!("pivot: {e}"))?;
                self.pivot_mm = pivot;
                Ok("{\"ok\":true}".to_owned())
            }),
            Some((&"f64", rest)) => numbers::<6>(rest).map(|v| self.f64_pulses(v)),
            _ => Err(format!("unknown request '{line}'")),
        };
        result.unwrap_or_else(|e| error(&e))
    }

    fn set_layout(&mut self, words: &[&str]) -> Result<String, String> {
        let [br, bh, pr, ph, arm, rod] = numbers::<6>(words)?;
        let layout = PairedLayout {
            base_radius_mm: br,
            base_half_angle_deg: bh,
            platform_radius_mm: pr,
            platform_half_angle_deg: ph,
            arm_mm: arm,
            rod_mm: rod,
        };
        let solver = layout
            .build()
            .and_then(ik::Solver::new)
            .map_err(|e| format!("geometry: {e}"))?
            .with_rotation_centre_mm(self.pivot_mm)
            .map_err(|e| format!("pivot: {e}"))?;
        self.layout = layout;
        self.solver = solver;
        Ok("{\"ok\":true}".to_owned())
    }

    fn set_servo(&mut self, words: &[&str]) -> Result<String, String> {
        let [n, trim, rate, dir, min, max] = words else {
            return Err("usage: servo <n> <trim> <rate> <dir> <min> <max>".to_owned());
        };
        let index = match n.parse::<usize>() {
            Ok(n @ 1..=LEGS) => n - 1,
            _ => return Err(format!("no servo '{n}'")),
        };
        let direction = match *dir {
            "normal" => Direction::Normal,
            "reversed" => Direction::Reversed,
            _ => return Err(format!("direction '{dir}'")),
        };
        let [home_us, rate_us_per_rad, min_us, max_us] = numbers::<4>(&[trim, rate, min, max])?;
        self.servos.0[index] = ServoConfig {
            home_us,
            rate_us_per_rad,
            direction,
            min_us,
            max_us,
        };
        Ok("{\"ok\":true}".to_owned())
    }

    /// The f64 reference's arm angles and pulses (the core's geometry and pivot as inputs
    /// only): the chain of frames about the pivot, each rod closure's root, eq. 13, 14.
    fn f64_pulses(&self, v: [f32; 6]) -> String {
        let arms = RefArms::from_solver(&self.solver);
        let [x, y, z, roll, pitch, yaw] = v.map(f64::from);
        let pose = RefPose::from_degrees(x, y, z, roll, pitch, yaw);
        let Some(alpha) = arms.arm_angles(&pose) else {
            return "{\"ok\":false,\"code\":\"unreachable\"}".to_owned();
        };
        let pulse: Vec<String> = (0..LEGS)
            .map(|i| {
                let servo = &self.servos.0[i];
                let sign = match servo.direction {
                    Direction::Normal => 1.0,
                    Direction::Reversed => -1.0,
                };
                let w = f64::from(servo.home_us)
                    + sign * f64::from(servo.rate_us_per_rad) * (alpha[i] - arms.alpha0[i]);
                format!("{w}")
            })
            .collect();
        let arm: Vec<String> = alpha
            .iter()
            .map(|a| format!("{}", a.to_degrees()))
            .collect();
        format!(
            "{{\"ok\":true,\"arm_deg\":[{}],\"pulse_us\":[{}]}}",
            arm.join(","),
            pulse.join(",")
        )
    }

    fn solve(&self, [x, y, z, roll, pitch, yaw]: [f32; 6]) -> String {
        let pose = Pose::from_degrees(x, y, z, roll, pitch, yaw);
        match self.solver.solve::<Libm>(&self.servos, &pose) {
            Ok(solution) => format!(
                "{{\"ok\":true,\"arm_deg\":{},\"pulse_us\":{}}}",
                nums(&solution.arm_rad.map(f32::to_degrees)),
                nums(&solution.pulse_us)
            ),
            Err(e) => ik_error(&e),
        }
    }

    /// The holding torques (kgf cm) at a pose the IK solves.
    fn torques_at(&self, pose: &Pose) -> Result<[f32; LEGS], Fails> {
        let solution = self
            .solver
            .solve::<Libm>(&self.servos, pose)
            .map_err(Fails::Ik)?;
        let n_mm =
            servo_holding_torques::<Libm>(&self.solver, pose, &solution.arm_rad, &self.payload)
                .map_err(Fails::Kinematics)?;
        Ok(n_mm.map(|t| t / N_MM_PER_KGF_CM))
    }

    fn torque(&self, [x, y, z, roll, pitch, yaw]: [f32; 6]) -> String {
        match self.torques_at(&Pose::from_degrees(x, y, z, roll, pitch, yaw)) {
            Ok(t) => format!("{{\"ok\":true,\"torque_kgcm\":{}}}", nums(&t)),
            Err(e) => fails(&e),
        }
    }

    /// The limits test: the IK within the servo limits and, with a payload and ratings, every
    /// holding torque within its rating.
    fn passes(&self, pose: &Pose) -> Result<(), Fails> {
        let rated = self.payload.mass_kg > 0.0 && self.ratings_kgcm.iter().any(|&r| r > 0.0);
        if !rated {
            return self
                .solver
                .solve::<Libm>(&self.servos, pose)
                .map(|_| ())
                .map_err(Fails::Ik);
        }
        let torques = self.torques_at(pose)?;
        for (i, (t, r)) in torques.iter().zip(self.ratings_kgcm).enumerate() {
            if r > 0.0 && t.abs() > r {
                return Err(Fails::Torque {
                    servo: i as u8 + 1,
                    rated_kgcm: r,
                });
            }
        }
        Ok(())
    }

    fn limits(&self, [x, y, z, roll, pitch, yaw]: [f32; 6]) -> String {
        let start = Pose::from_degrees(x, y, z, roll, pitch, yaw);
        let mut search = workspace::Limits::new(start, workspace::Options::default());
        let reaches = loop {
            if let Some(r) = search.step(|p| self.passes(p)) {
                break r;
            }
        };
        let parts: Vec<String> = reaches
            .iter()
            .map(|r| {
                let scale = if r.axis.is_angle() {
                    1.0f32.to_degrees()
                } else {
                    1.0
                };
                let limit = match r.limit {
                    Limit::Blocked(e) => format!("{{\"kind\":\"blocked\",{}}}", why(&e)),
                    Limit::Range => "{\"kind\":\"range\"}".to_owned(),
                    Limit::Start(e) => format!("{{\"kind\":\"start\",{}}}", why(&e)),
                };
                format!(
                    "{{\"axis\":\"{}\",\"sense\":\"{}\",\"distance\":{},\"extreme\":{},\"limit\":{limit}}}",
                    r.axis.name(),
                    match r.sense {
                        Sense::Minus => "-",
                        Sense::Plus => "+",
                    },
                    num(r.distance * scale),
                    num(r.extreme(&start) * scale)
                )
            })
            .collect();
        format!("{{\"ok\":true,\"reaches\":[{}]}}", parts.join(","))
    }

    /// The pose the arms reach when they turn from where the IK puts them at `start` to
    /// `to_rad` in small steps (one solve from `start` if the IK cannot put them there).
    fn continuation(&self, start: &Pose, to_rad: &[f32; LEGS]) -> Result<Pose, KinematicsError> {
        const STEP_RAD: f32 = 0.25 * core::f32::consts::PI / 180.0;
        let options = forward::Options::default();
        let Ok(from_rad) = self.solver.arm_angles::<Libm>(start) else {
            return forward::arms::<Libm>(&self.solver, to_rad, start, options).map(|c| c.pose);
        };
        let change = (0..LEGS).fold(0.0f32, |m, i| m.max((to_rad[i] - from_rad[i]).abs()));
        let steps = (change / STEP_RAD).ceil().max(1.0) as u32;
        let mut pose = *start;
        for k in 1..=steps {
            let t = k as f32 / steps as f32;
            let arm: [f32; LEGS] =
                core::array::from_fn(|i| from_rad[i] + (to_rad[i] - from_rad[i]) * t);
            let closure = forward::Closure::arms::<Libm>(&self.solver, &arm)?;
            pose = forward::solve::<Libm>(&closure, &pose, options)?.pose;
        }
        forward::check_arms::<Libm>(&self.solver, &pose, to_rad)?;
        Ok(pose)
    }

    fn fk(&self, v: [f32; 12]) -> String {
        let pulses: [f32; LEGS] = core::array::from_fn(|i| v[i]);
        let start = Pose::from_degrees(v[6], v[7], v[8], v[9], v[10], v[11]);
        let found = forward::arm_angles_for_pulses(&self.solver, &self.servos, &pulses)
            .and_then(|arm| self.continuation(&start, &arm));
        match found {
            Ok(p) => {
                format!(
                    "{{\"ok\":true,\"pose\":{}}}",
                    nums(&[
                        p.x_mm,
                        p.y_mm,
                        p.z_mm,
                        p.roll_rad.to_degrees(),
                        p.pitch_rad.to_degrees(),
                        p.yaw_rad.to_degrees()
                    ])
                )
            }
            Err(e) => format!(
                "{{\"ok\":false,\"code\":\"no-pose\",\"error\":\"{}\"}}",
                quoted(&e.to_string())
            ),
        }
    }

    fn geometry(&self) -> String {
        let g = self.solver.geometry();
        let mut legs = String::new();
        for (i, leg) in g.legs().iter().enumerate() {
            if i > 0 {
                legs.push(',');
            }
            let b = leg.base_mm;
            let p = leg.platform_mm;
            let _ = write!(
                legs,
                "{{\"b_mm\":{},\"p_mm\":{},\"beta_deg\":{},\"alpha0_deg\":{}}}",
                nums(&[b.x, b.y, b.z]),
                nums(&[p.x, p.y, p.z]),
                num(leg.beta_rad.to_degrees()),
                num(self.solver.alpha0_rad(i).to_degrees())
            );
        }
        format!(
            "{{\"ok\":true,\"arm_mm\":{},\"rod_mm\":{},\"h0_mm\":{},\"legs\":[{legs}]}}",
            num(g.arm_mm()),
            num(g.rod_mm()),
            num(g.home_height_mm())
        )
    }
}

fn main() -> io::Result<()> {
    let mut reference = Reference::new();
    let stdin = io::stdin();
    let mut stdout = io::BufWriter::new(io::stdout().lock());
    for line in stdin.lock().lines() {
        let line = line?;
        if line.trim().is_empty() {
            continue;
        }
        writeln!(stdout, "{}", reference.run(line.trim()))?;
    }
    stdout.flush()
}
