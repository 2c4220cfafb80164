//! The guided calibration's pieces (`hexapod calibrate`; docs/geometry-and-calibration.md,
//! "Calibration"), each testable without a board: the keys typed to step one servo's pulse
//! (us), every step kept within the servo's `min_us`..`max_us`; the trim taken from the pulse
//! that holds the arm level (eq. 13 / 14 solved for `W0`, with the firmware's own pulse mapping,
//! `kinematics_core::servo::ServoConfig`); the poses the platform is checked at; and a build
//! file's text with its trims replaced, the user's other keys and comments kept.
//!
//! Units: pulses in microseconds, angles in radians (degrees only in pose lines).

use kinematics_core::servo::ServoConfig;
use kinematics_core::LEGS;

/// `+` / `-`: a small step, us (about a tenth of a degree of arm at the default rate).
pub const SMALL_STEP_US: f32 = 1.0;
/// `]` / `[`: a big step, us (about 1.1 degrees at the default rate).
pub const BIG_STEP_US: f32 = 10.0;

/// What a typed line asks for, one servo at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Typed {
    /// Step the pulse by this much, us (the keys `+ - [ ]`, several in a line add up).
    Step(f32),
    /// Go to this pulse, us (a number typed).
    Pulse(f32),
    /// Enter alone: the arm is level; take the trim.
    Accept,
    /// `q`: quit, putting everything back.
    Quit,
    /// Anything else: nothing is sent.
    Unknown,
}

/// Reads a typed line: keys `+ - [ ]` (spaces ignored), a pulse in us, nothing (Enter), or `q`.
pub fn read_line(line: &str) -> Typed {
    let line = line.trim();
    if line.is_empty() {
        return Typed::Accept;
    }
    if line.eq_ignore_ascii_case("q") || line.eq_ignore_ascii_case("quit") {
        return Typed::Quit;
    }
    if let Ok(pulse) = line.parse::<f32>() {
        return if pulse.is_finite() {
            Typed::Pulse(pulse)
        } else {
            Typed::Unknown
        };
    }
    let mut step = 0.0;
    for key in line.chars().filter(|c| !c.is_whitespace()) {
        step += match key {
            '+' | '=' => SMALL_STEP_US,
            '-' | '_' => -SMALL_STEP_US,
            ']' => BIG_STEP_US,
            '[' => -BIG_STEP_US,
            _ => return Typed::Unknown,
        };
    }
    Typed::Step(step)
}

/// A pulse to send: within the servo's limits, to 0.01 us (what `servo` and `config` show).
pub fn within_limits(servo: &ServoConfig, pulse_us: f32) -> f32 {
    hundredths(pulse_us.clamp(servo.min_us, servo.max_us))
}

/// Rounded to 0.01 us.
fn hundredths(us: f32) -> f32 {
    (us * 100.0).round() / 100.0
}

/// The pulse that puts the arm level (arm angle 0) with the servo's present trim, within its
/// limits: where a trimmed servo's arm would be level, so where the search starts.
pub fn level_pulse(servo: &ServoConfig, alpha0_rad: f32) -> f32 {
    within_limits(servo, servo.pulse_us(0.0, alpha0_rad))
}

/// The trim (`servoN.trim_us`, the home pulse `W0` of eq. 13 / 14) of a servo whose arm is level
/// at `level_us`: home is the arm at `alpha0`, not level, so the trim is `level_us` moved by the
/// pulse that turns the arm from level to `alpha0` (`d r alpha0`, with the servo's own rate and
/// direction). To 0.01 us.
pub fn trim_from_level(servo: &ServoConfig, alpha0_rad: f32, level_us: f32) -> f32 {
    // eq. 13 / 14 at alpha = 0: W = W0 + d r (0 - alpha0), so W0 = W - (W(0) - W0).
    hundredths(level_us - (servo.pulse_us(0.0, alpha0_rad) - servo.home_us))
}

/// A pose the platform is checked at, and what to measure there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Check {
    /// The pose, as `pose` takes it (x y z mm, roll pitch yaw degrees).
    pub pose: [f32; 6],
    /// What to look at and what is good enough.
    pub measure: &'static str,
}

impl Check {
    /// The `pose` line.
    pub fn line(&self) -> String {
        let [x, y, z, roll, pitch, yaw] = self.pose;
        format!("pose {x} {y} {z} {roll} {pitch} {yaw}")
    }
}

/// The poses the platform is checked at after trimming, with what to measure (a spirit level,
/// a ruler, an inclinometer or a phone's level app). Small moves, within every default
/// platform's reach (the golden poses of docs/geometry-and-calibration.md go further).
pub const CHECKS: [Check; 5] = [
    Check {
        pose: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        measure: "home: a spirit level on the platform, along x and then along y: the bubble \
                  within its marks (level within about 0.5 degree); measure the platform's \
                  height above the base plate with a ruler and note it",
    },
    Check {
        pose: [0.0, 0.0, 10.0, 0.0, 0.0, 0.0],
        measure: "10 mm up: the ruler shows the platform 10 mm higher than at home (within 1 mm), \
                  still level",
    },
    Check {
        pose: [0.0, 0.0, 0.0, 5.0, 0.0, 0.0],
        measure: "roll 5 degrees: tilted about the x axis by 5 degrees (an inclinometer across \
                  x, within 1 degree), not about y",
    },
    Check {
        pose: [0.0, 0.0, 0.0, 0.0, 5.0, 0.0],
        measure: "pitch 5 degrees: tilted about the y axis by 5 degrees (within 1 degree), not \
                  about x",
    },
    Check {
        pose: [0.0, 0.0, 0.0, 0.0, 0.0, 10.0],
        measure: "yaw 10 degrees: turned 10 degrees about the vertical (a mark on the platform \
                  against one on the base), level and at the home height",
    },
];

/// A build file's text with the trims set to `trims_us` (servo 1 first), everything else kept:
/// a `trim_us` under `[servoN]` or a `servoN.trim_us` key gets its new value (its comment
/// kept); `servos.trim_us` (all six at once) is commented out, since each servo now has its
/// own; a servo with no trim key gets one, under its `[servoN]` table or in a new one at the
/// end. The caller reads the result back to make sure (`crate::build_file::parse`).
pub fn with_trims(text: &str, trims_us: &[f32; LEGS]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut written = [false; LEGS];
    let mut tables: [Option<usize>; LEGS] = [None; LEGS];
    let mut table = String::new();
    for (index, line) in lines.iter_mut().enumerate() {
        let code = line.split('#').next().unwrap_or("").trim();
        if let Some(name) = code.strip_prefix('[').and_then(|c| c.strip_suffix(']')) {
            table = name.trim().to_ascii_lowercase();
            if let Some(servo) = servo_number(&table) {
                tables[servo - 1] = Some(index);
            }
            continue;
        }
        let Some((key, _)) = code.split_once('=') else {
            continue;
        };
        let key = key.trim().to_ascii_lowercase();
        let name = if table.is_empty() {
            key
        } else {
            format!("{table}.{key}")
        };
        let Some(servo) = name.strip_suffix(".trim_us") else {
            continue;
        };
        if servo == "servos" {
            *line = format!("# {line}  (each [servoN] has its own trim_us: hexapod calibrate)");
        } else if let Some(n) = servo_number(servo) {
            *line = with_value(line, trims_us[n - 1]);
            written[n - 1] = true;
        }
    }
    // Missing trims: under their table (from the last, so earlier indexes stay right), or new
    // tables at the end.
    let mut inserts: Vec<(usize, usize)> = (0..LEGS)
        .filter(|&i| !written[i])
        .filter_map(|i| tables[i].map(|at| (at, i)))
        .collect();
    inserts.sort_unstable_by(|a, b| b.cmp(a));
    for &(at, i) in &inserts {
        lines.insert(at + 1, format!("trim_us = {}", number(trims_us[i])));
        written[i] = true;
    }
    let mut out = lines.join("\n");
    if !out.is_empty() {
        out.push('\n');
    }
    for (i, trim) in trims_us.iter().enumerate() {
        if !written[i] {
            out.push_str(&format!(
                "\n[servo{}]\ntrim_us = {}\n",
                i + 1,
                number(*trim)
            ));
        }
    }
    out
}

/// `servoN` -> N (1..=6).
fn servo_number(name: &str) -> Option<usize> {
    let n: usize = name.strip_prefix("servo")?.parse().ok()?;
    (1..=LEGS).contains(&n).then_some(n)
}

/// `key = old  # comment` with a new value, the key and the comment as they were.
fn with_value(line: &str, value: f32) -> String {
    let Some((key, rest)) = line.split_once('=') else {
        return line.to_string();
    };
    let new = number(value);
    match rest.find('#') {
        // The comment kept in its column where the new value is no longer than the old.
        Some(at) => {
            let (value_part, comment) = rest.split_at(at);
            let old = value_part.trim();
            let gap = value_part.len() - value_part.trim_end().len();
            let pad = (gap + old.len()).saturating_sub(new.len()).max(1);
            format!("{key}= {new}{}{comment}", " ".repeat(pad))
        }
        None => format!("{key}= {new}"),
    }
}

/// A pulse as TOML: to 0.01 us, with a decimal point.
fn number(us: f32) -> String {
    let text = format!("{}", hundredths(us));
    if text.contains('.') {
        text
    } else {
        format!("{text}.0")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use kinematics_core::servo::Direction;

    fn servo(direction: Direction) -> ServoConfig {
        ServoConfig {
            home_us: 1500.0,
            rate_us_per_rad: 1600.0 / std::f32::consts::PI,
            direction,
            min_us: 1100.0,
            max_us: 1900.0,
        }
    }

    #[test]
    fn keys_step_the_pulse_and_words_accept_or_quit() {
        assert_eq!(read_line("+"), Typed::Step(1.0));
        assert_eq!(read_line("- -"), Typed::Step(-2.0));
        assert_eq!(read_line("]]+"), Typed::Step(21.0));
        assert_eq!(read_line("["), Typed::Step(-10.0));
        assert_eq!(read_line(""), Typed::Accept);
        assert_eq!(read_line("  \r"), Typed::Accept);
        assert_eq!(read_line("q"), Typed::Quit);
        assert_eq!(read_line("1512.5"), Typed::Pulse(1512.5));
        assert_eq!(read_line("x"), Typed::Unknown);
        assert_eq!(read_line("++x"), Typed::Unknown);
        assert_eq!(read_line("nan"), Typed::Unknown);
    }

    #[test]
    fn every_pulse_sent_stays_within_the_servo_s_limits() {
        let s = servo(Direction::Normal);
        assert_eq!(within_limits(&s, 1000.0), 1100.0);
        assert_eq!(within_limits(&s, 2500.0), 1900.0);
        assert_eq!(within_limits(&s, 1512.344), 1512.34);
    }

    #[test]
    fn the_trim_is_the_level_pulse_moved_to_alpha0() {
        // Worked by hand from eq. 13 / 14: alpha0 = -0.252 degrees (the default platform's),
        // r = 1600/pi us/rad, so d r alpha0 = -2.2399 us for a normal servo, +2.2399 us for a
        // reversed one; an arm level at 1503.00 us has W0 = 1503.00 + d r alpha0.
        let alpha0 = (-0.252f32).to_radians();
        assert_eq!(
            trim_from_level(&servo(Direction::Normal), alpha0, 1503.0),
            1500.76
        );
        assert_eq!(
            trim_from_level(&servo(Direction::Reversed), alpha0, 1503.0),
            1505.24
        );
        // With its trim, the arm is level where the search starts (1497.76 / 1502.24 us).
        assert_eq!(level_pulse(&servo(Direction::Normal), alpha0), 1502.24);
        assert_eq!(level_pulse(&servo(Direction::Reversed), alpha0), 1497.76);
        // A level arm at home (alpha0 = 0): the trim is the level pulse.
        assert_eq!(
            trim_from_level(&servo(Direction::Normal), 0.0, 1512.0),
            1512.0
        );
    }

    #[test]
    fn check_poses_are_pose_lines() {
        assert_eq!(CHECKS[0].line(), "pose 0 0 0 0 0 0");
        assert_eq!(CHECKS[1].line(), "pose 0 0 10 0 0 0");
    }

    #[test]
    fn trims_replace_theirs_and_keep_everything_else() {
        let text = "# my platform\nrod_mm = 125.0   # measured\nservos.trim_us = 1490\n\
                    servo2.trim_us = 1495 # old\n[servo1]\ndir = \"normal\"\ntrim_us = 1500.0  \
                    # home\n[servo4]\nmin_us = 1200\n[sizing]\nservo_stiffness_nmm_rad = 4000.0\n";
        let trims = [1501.5, 1502.0, 1503.25, 1504.0, 1505.0, 1506.0];
        let out = with_trims(text, &trims);
        assert_eq!(
            out,
            "# my platform\nrod_mm = 125.0   # measured\n# servos.trim_us = 1490  (each \
             [servoN] has its own trim_us: hexapod calibrate)\nservo2.trim_us = 1502.0 # old\n\
             [servo1]\ndir = \"normal\"\ntrim_us = 1501.5  # home\n[servo4]\ntrim_us = 1504.0\n\
             min_us = 1200\n[sizing]\nservo_stiffness_nmm_rad = 4000.0\n\n[servo3]\n\
             trim_us = 1503.25\n\n[servo5]\ntrim_us = 1505.0\n\n[servo6]\ntrim_us = 1506.0\n"
        );
        // And it reads back as those trims, rod_mm kept.
        let file = crate::build_file::parse("b.toml", &out).unwrap();
        for (i, trim) in trims.iter().enumerate() {
            assert_eq!(file.settings.servos.0[i].home_us, *trim);
        }
        assert_eq!(file.settings.servos.0[3].min_us, 1200.0);
        assert_eq!(file.sizing.entries()[0].1, 4000.0);
    }

    #[test]
    fn an_empty_file_gets_six_tables() {
        let out = with_trims("", &[1500.0; LEGS]);
        let file = crate::build_file::parse("b.toml", &out).unwrap();
        assert_eq!(file.steps.len(), LEGS);
    }
}
