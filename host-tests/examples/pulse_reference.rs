//! The host core's answer for poses, for the emulator's end-to-end tests.
//!
//! The tests drive the real firmware (RP2040 boot ROM floats) in the emulator and compare the
//! pulse widths measured on its pins with what the host build of `kinematics-core` (libm)
//! computes for the same pose and settings. This program is that host computation; it uses
//! only `kinematics-core` (not the `control` crate, whose behaviour is under test).
//!
//! It reads commands from stdin, one per line, and answers each with one line of JSON:
//!
//! ```text
//! layout <base_radius_mm> <base_half_angle_deg> <platform_radius_mm>
//!        <platform_half_angle_deg> <arm_mm> <rod_mm>
//!     -> {"ok":true} or {"ok":false,"error":"..."}             (the geometry used from now on)
//! servo <1-6> <trim_us> <rate_us_rad> <normal|reversed> <min_us> <max_us>
//!     -> {"ok":true}                                            (that servo from now on)
//! solve <x_mm> <y_mm> <z_mm> <roll_deg> <pitch_deg> <yaw_deg>
//!     -> {"ok":true,"arm_deg":[6],"pulse_us":[6]}
//!      | {"ok":false,"code":"unreachable","leg":n}
//!      | {"ok":false,"code":"servo-limit","servo":n,"pulse_us":w,"min_us":lo,"max_us":hi}
//!      | {"ok":false,"code":"angle-too-large","axis":"roll"}
//!      | {"ok":false,"code":"pose-not-finite","axis":"x"}
//! geometry
//!     -> {"ok":true,"arm_mm":a,"rod_mm":s,"h0_mm":h,
//!         "legs":[{"b_mm":[3],"p_mm":[3],"beta_deg":b,"alpha0_deg":a0}]}
//! ```
//!
//! It starts with the core's default layout and servos; the tests send theirs explicitly.
//! Numbers are read as `f32` (as the firmware reads what is typed) and printed in full.
//!
//! `cargo run -q -p host-tests --example pulse_reference` (the tests build it once and run
//! the binary).

use std::fmt::Write as _;
use std::io::{self, BufRead, Write};

use kinematics_core::geometry::PairedLayout;
use kinematics_core::ik::{self, IkError};
use kinematics_core::{Direction, Libm, Pose, ServoConfig, ServoSet, LEGS};

struct Reference {
    layout: PairedLayout,
    /// The IK of the layout's geometry (and the geometry).
    solver: ik::Solver,
    servos: ServoSet,
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
        }
    }

    fn run(&mut self, line: &str) -> String {
        let words: Vec<&str> = line.split_whitespace().collect();
        let result = match words.split_first() {
            Some((&"layout", rest)) => self.set_layout(rest),
            Some((&"servo", rest)) => self.set_servo(rest),
            Some((&"solve", rest)) => numbers::<6>(rest).map(|v| self.solve(v)),
            Some((&"geometry", [])) => Ok(self.geometry()),
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
            .map_err(|e| format!("geometry: {e}"))?;
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

    fn solve(&self, [x, y, z, roll, pitch, yaw]: [f32; 6]) -> String {
        let pose = Pose::from_degrees(x, y, z, roll, pitch, yaw);
        match self.solver.solve::<Libm>(&self.servos, &pose) {
            Ok(solution) => format!(
                "{{\"ok\":true,\"arm_deg\":{},\"pulse_us\":{}}}",
                nums(&solution.arm_rad.map(f32::to_degrees)),
                nums(&solution.pulse_us)
            ),
            Err(IkError::Unreachable { leg }) => {
                format!("{{\"ok\":false,\"code\":\"unreachable\",\"leg\":{leg}}}")
            }
            Err(IkError::ServoLimit {
                servo,
                pulse_us,
                min_us,
                max_us,
            }) => format!(
                "{{\"ok\":false,\"code\":\"servo-limit\",\"servo\":{servo},\"pulse_us\":{},\"min_us\":{},\"max_us\":{}}}",
                num(pulse_us),
                num(min_us),
                num(max_us)
            ),
            Err(IkError::AngleTooLarge { axis, .. }) => format!(
                "{{\"ok\":false,\"code\":\"angle-too-large\",\"axis\":\"{}\"}}",
                axis.name()
            ),
            Err(IkError::NonFinite { axis }) => format!(
                "{{\"ok\":false,\"code\":\"pose-not-finite\",\"axis\":\"{}\"}}",
                axis.name()
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
