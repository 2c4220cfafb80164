//! Command parsing: one line of text -> one [`Command`], or the [`ParseError`] that explains
//! why not.
//!
//! Lines are case-insensitive; words are separated by spaces, tabs or commas. Numbers are strict
//! decimals ([`crate::number`]); lengths are mm, angles degrees. Parsing only looks at the text:
//! whether a pose is reachable is decided later by the controller. The usage text and the
//! message of every refusal are [`crate::report`]'s.

use kinematics_core::pose::Axis;
use kinematics_core::Pose;

use crate::number::{parse_f32, NumberError};
use crate::protocol::{Spoiled, MAX_LINE};
use crate::settings::{SettingError, SettingId, SettingValue};
use crate::word::{word, Word};

/// Values for some of the six axes, in user units (mm, degrees), in [`Axis::ALL`] order.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxisValues(pub [Option<f32>; 6]);

impl AxisValues {
    /// `base` with the named axes replaced by (or, if `relative`, moved by) the values.
    pub fn apply(&self, base: &Pose, relative: bool) -> Pose {
        let mut pose = *base;
        for (axis, value) in Axis::ALL.into_iter().zip(self.0) {
            if let Some(v) = value {
                let v = if axis.is_angle() { v.to_radians() } else { v };
                let new = if relative { pose.get(axis) + v } else { v };
                pose.set(axis, new);
            }
        }
        pose
    }
}

/// The command words, in the order `help` lists them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verb {
    /// `pose`.
    Pose,
    /// `move`.
    Move,
    /// `nudge`.
    Nudge,
    /// `check`.
    Check,
    /// `limits`.
    Limits,
    /// `home`.
    Home,
    /// `stop`.
    Stop,
    /// `servo`.
    Servo,
    /// `reset`.
    Reset,
    /// `status` (or `?`).
    Status,
    /// `pulses`.
    Pulses,
    /// `geometry`.
    Geometry,
    /// `config`.
    Config,
    /// `set`.
    Set,
    /// `defaults`.
    Defaults,
    /// `save`.
    Save,
    /// `help`.
    Help,
}

impl Verb {
    /// Every command word.
    pub const ALL: [Verb; 17] = [
        Verb::Pose,
        Verb::Move,
        Verb::Nudge,
        Verb::Check,
        Verb::Limits,
        Verb::Home,
        Verb::Stop,
        Verb::Servo,
        Verb::Reset,
        Verb::Status,
        Verb::Pulses,
        Verb::Geometry,
        Verb::Config,
        Verb::Set,
        Verb::Defaults,
        Verb::Save,
        Verb::Help,
    ];

    /// The word that names the command (as typed, lowercase).
    pub const fn name(self) -> &'static str {
        match self {
            Verb::Pose => "pose",
            Verb::Move => "move",
            Verb::Nudge => "nudge",
            Verb::Check => "check",
            Verb::Limits => "limits",
            Verb::Home => "home",
            Verb::Stop => "stop",
            Verb::Servo => "servo",
            Verb::Reset => "reset",
            Verb::Status => "status",
            Verb::Pulses => "pulses",
            Verb::Geometry => "geometry",
            Verb::Config => "config",
            Verb::Set => "set",
            Verb::Defaults => "defaults",
            Verb::Save => "save",
            Verb::Help => "help",
        }
    }

    /// The command a word names, in any case; `?` is `status`.
    pub fn parse(word: &str) -> Option<Verb> {
        if word == "?" {
            return Some(Verb::Status);
        }
        Verb::ALL
            .into_iter()
            .find(|v| v.name().as_bytes().eq_ignore_ascii_case(word.as_bytes()))
    }
}

/// A number a command takes, for the errors that name it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// A pose coordinate (or the value after `axis=`).
    Axis(Axis),
    /// `servo`'s pulse width, us.
    PulseUs,
}

/// What a [`ParseError::MissingField`] is missing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Missing {
    /// A pose coordinate (or the value after `axis=`).
    Axis(Axis),
    /// `servo`'s servo number.
    ServoNumber,
    /// `servo`'s pulse width.
    PulseUs,
    /// `move`/`nudge` without any `axis=value`.
    AxisValue,
    /// `set` without a setting name.
    SettingName,
    /// `set <name>` without a value.
    SettingValue,
}

/// Why a line is not a command.
#[derive(Debug, Clone, PartialEq)]
pub enum ParseError {
    /// The line is too long, or holds a byte that is not printable ASCII.
    Spoiled(Spoiled),
    /// The first word is not a command.
    UnknownCommand {
        /// What was typed.
        word: Word,
    },
    /// The line holds nothing but separators (commas among the spaces).
    NoCommand,
    /// A value the command needs is missing.
    MissingField {
        /// What is missing.
        what: Missing,
        /// The command.
        verb: Verb,
    },
    /// There is more on the line than the command takes.
    ExtraField {
        /// The first word too many.
        word: Word,
        /// The command.
        verb: Verb,
    },
    /// A value is not a decimal number.
    BadNumber {
        /// Which value.
        field: Field,
        /// What was typed.
        word: Word,
    },
    /// A value is NaN or infinity.
    NotFinite {
        /// Which value.
        field: Field,
        /// What was typed.
        word: Word,
    },
    /// A value does not fit (e.g. `1e39`).
    NumberTooLarge {
        /// Which value.
        field: Field,
        /// What was typed.
        word: Word,
    },
    /// `servo` named something that is not a servo number (1..=6).
    BadServo {
        /// What was typed.
        word: Word,
    },
    /// `move`/`nudge` named something that is not an axis.
    UnknownAxis {
        /// What was typed.
        word: Word,
    },
    /// `move`/`nudge` named an axis twice.
    DuplicateAxis {
        /// The axis named twice.
        axis: Axis,
    },
    /// `move`/`nudge` got a word that is not `axis=value`.
    BadAssignment {
        /// What was typed.
        word: Word,
    },
    /// `set` named something that is not a setting.
    UnknownSetting {
        /// What was typed.
        word: Word,
    },
    /// `set` got a value the setting does not take.
    Setting(SettingError),
}

impl From<SettingError> for ParseError {
    fn from(e: SettingError) -> ParseError {
        ParseError::Setting(e)
    }
}

/// A parsed line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// `pose x y z roll pitch yaw`: move to an absolute pose.
    Pose(Pose),
    /// `move axis=value ...`: move the named axes to absolute values.
    Move(AxisValues),
    /// `nudge axis=delta ...`: move the named axes by relative amounts.
    Nudge(AxisValues),
    /// `check x y z roll pitch yaw`: would `pose` accept this? Nothing moves.
    Check(Pose),
    /// `limits`: how far each axis reaches from the current pose, both ways.
    Limits,
    /// `servo n us`: drive servo `n` directly to a pulse width; the others hold.
    Servo {
        /// Servo number, 1..=6.
        servo: u8,
        /// Pulse width, us (finite).
        pulse_us: f32,
    },
    /// `home`.
    Home,
    /// `stop`.
    Stop,
    /// `reset`: clear the emergency stop (once its input is closed) and any fault.
    Reset,
    /// `status` or `?`.
    Status,
    /// `pulses`: the six pulse widths on the pins now, one short line (for a host that
    /// follows the platform).
    Pulses,
    /// `geometry`.
    Geometry,
    /// `config`.
    Config,
    /// `help`.
    Help,
    /// `defaults`.
    Defaults,
    /// `save`: write the platform's settings to flash.
    Save,
    /// `set name value`.
    Set(SettingId, SettingValue),
}

/// The words of a line: what lies between separators (spaces, tabs, commas), empty ones
/// skipped. Separators are ASCII, so every cut is a character boundary; found byte by byte
/// (no character decoding: this runs over every byte of every command line).
struct Words<'a> {
    rest: &'a str,
}

impl<'a> Words<'a> {
    fn new(line: &'a str) -> Self {
        Words { rest: line }
    }
}

/// A byte that separates words.
fn separator(b: u8) -> bool {
    b == b' ' || b == b'\t' || b == b','
}

impl<'a> Iterator for Words<'a> {
    type Item = &'a str;
    fn next(&mut self) -> Option<&'a str> {
        let bytes = self.rest.as_bytes();
        let mut start = 0;
        while bytes.get(start).is_some_and(|&b| separator(b)) {
            start += 1;
        }
        if start == bytes.len() {
            self.rest = "";
            return None;
        }
        let mut end = start + 1;
        while bytes.get(end).is_some_and(|&b| !separator(b)) {
            end += 1;
        }
        let (word, rest) = (self.rest.get(start..end)?, self.rest.get(end..)?);
        self.rest = rest;
        Some(word)
    }
}

/// Parses one number for `field`.
fn number(field: Field, text: &str) -> Result<f32, ParseError> {
    parse_f32(text).map_err(|e| {
        let word = lower(text);
        match e {
            NumberError::NotFinite => ParseError::NotFinite { field, word },
            NumberError::TooLarge => ParseError::NumberTooLarge { field, word },
            NumberError::Syntax | NumberError::NotWhole => ParseError::BadNumber { field, word },
        }
    })
}

/// `n us`: a servo number 1..=6 and a pulse width.
fn servo_pulse(words: &mut Words<'_>, verb: Verb) -> Result<Command, ParseError> {
    let missing = |what| ParseError::MissingField { what, verb };
    let n = words.next().ok_or(missing(Missing::ServoNumber))?;
    let servo = match n.as_bytes() {
        [d @ b'1'..=b'6'] => d - b'0',
        _ => return Err(ParseError::BadServo { word: lower(n) }),
    };
    let pulse_us = number(
        Field::PulseUs,
        words.next().ok_or(missing(Missing::PulseUs))?,
    )?;
    no_more(words, verb)?;
    Ok(Command::Servo { servo, pulse_us })
}

fn no_more(words: &mut Words<'_>, verb: Verb) -> Result<(), ParseError> {
    match words.next() {
        Some(extra) => Err(ParseError::ExtraField {
            word: lower(extra),
            verb,
        }),
        None => Ok(()),
    }
}

/// `x y z roll pitch yaw`, exactly six numbers.
fn full_pose(words: &mut Words<'_>, verb: Verb) -> Result<Pose, ParseError> {
    let mut v = [0.0f32; 6];
    for (slot, axis) in v.iter_mut().zip(Axis::ALL) {
        let text = words.next().ok_or(ParseError::MissingField {
            what: Missing::Axis(axis),
            verb,
        })?;
        *slot = number(Field::Axis(axis), text)?;
    }
    no_more(words, verb)?;
    Ok(Pose::from_degrees(v[0], v[1], v[2], v[3], v[4], v[5]))
}

/// `axis=value ...`, at least one, each axis at most once.
fn axis_values(words: &mut Words<'_>, verb: Verb) -> Result<AxisValues, ParseError> {
    let mut values = AxisValues::default();
    let mut any = false;
    for w in words {
        let (name, value) = w
            .split_once('=')
            .ok_or_else(|| ParseError::BadAssignment { word: lower(w) })?;
        let axis = Axis::ALL
            .into_iter()
            .find(|a| a.name().eq_ignore_ascii_case(name))
            .ok_or_else(|| ParseError::UnknownAxis { word: lower(name) })?;
        let slot = &mut values.0[axis as usize];
        if slot.is_some() {
            return Err(ParseError::DuplicateAxis { axis });
        }
        if value.is_empty() {
            return Err(ParseError::MissingField {
                what: Missing::Axis(axis),
                verb,
            });
        }
        *slot = Some(number(Field::Axis(axis), value)?);
        any = true;
    }
    if any {
        Ok(values)
    } else {
        Err(ParseError::MissingField {
            what: Missing::AxisValue,
            verb,
        })
    }
}

/// A word the user typed, lowercased, for an error that quotes it (lines are
/// case-insensitive, and their words are quoted as if typed in lowercase).
fn lower(text: &str) -> Word {
    let mut w = word(text);
    w.make_ascii_lowercase();
    w
}

/// Parses one line (any case; at most [`MAX_LINE`] characters of printable ASCII). The line
/// must not be blank.
///
/// The words are read where they lie, in any case (command words, axis names and numbers
/// are matched so); a word an error quotes is lowercased then. `set`'s name and value are
/// read from a lowercased copy of the line ([`crate::settings`] takes lowercase words).
pub fn parse(line: &str) -> Result<Command, ParseError> {
    if line.len() > MAX_LINE {
        return Err(ParseError::Spoiled(Spoiled::TooLong));
    }
    // The first byte that is not printable ASCII or a tab refuses the line.
    if let Some(&byte) = line
        .as_bytes()
        .iter()
        .find(|&&b| !(0x20..=0x7E).contains(&b) && b != b'\t')
    {
        return Err(ParseError::Spoiled(Spoiled::BadByte(byte)));
    }

    let mut words = Words::new(line);
    let name = words.next().ok_or(ParseError::NoCommand)?;
    let verb = Verb::parse(name).ok_or_else(|| ParseError::UnknownCommand { word: lower(name) })?;
    let simple = |cmd: Command, words: &mut Words<'_>| no_more(words, verb).map(|()| cmd);
    match verb {
        Verb::Pose => full_pose(&mut words, verb).map(Command::Pose),
        Verb::Check => full_pose(&mut words, verb).map(Command::Check),
        Verb::Limits => simple(Command::Limits, &mut words),
        Verb::Servo => servo_pulse(&mut words, verb),
        Verb::Move => axis_values(&mut words, verb).map(Command::Move),
        Verb::Nudge => axis_values(&mut words, verb).map(Command::Nudge),
        Verb::Home => simple(Command::Home, &mut words),
        Verb::Stop => simple(Command::Stop, &mut words),
        Verb::Reset => simple(Command::Reset, &mut words),
        Verb::Status => simple(Command::Status, &mut words),
        Verb::Pulses => simple(Command::Pulses, &mut words),
        Verb::Geometry => simple(Command::Geometry, &mut words),
        Verb::Config => simple(Command::Config, &mut words),
        Verb::Help => simple(Command::Help, &mut words),
        Verb::Defaults => simple(Command::Defaults, &mut words),
        Verb::Save => simple(Command::Save, &mut words),
        Verb::Set => {
            // Lowered (printable ASCII throughout, checked above).
            let mut lowered = [0u8; MAX_LINE];
            let lowered = &mut lowered[..line.len()];
            for (slot, &byte) in lowered.iter_mut().zip(line.as_bytes()) {
                *slot = byte.to_ascii_lowercase();
            }
            let line = core::str::from_utf8(lowered)
                .map_err(|_| ParseError::Spoiled(Spoiled::BadByte(0)))?;
            let mut words = Words::new(line);
            words.next(); // `set`
            let name = words.next().ok_or(ParseError::MissingField {
                what: Missing::SettingName,
                verb,
            })?;
            let id =
                SettingId::parse(name).ok_or(ParseError::UnknownSetting { word: word(name) })?;
            let value = words.next().ok_or(ParseError::MissingField {
                what: Missing::SettingValue,
                verb,
            })?;
            let value = id.parse_value(value)?;
            no_more(&mut words, verb)?;
            Ok(Command::Set(id, value))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::{ServoParam, ServoSel};

    fn err(line: &str) -> ParseError {
        parse(line).unwrap_err()
    }

    #[test]
    fn pose_takes_six_numbers_in_mm_and_degrees() {
        assert_eq!(
            parse("pose 1 2 3 10 -20 30"),
            Ok(Command::Pose(Pose::from_degrees(
                1.0, 2.0, 3.0, 10.0, -20.0, 30.0
            )))
        );
        assert_eq!(
            parse("  POSE\t1,2,3, 0 ,0,0  "),
            Ok(Command::Pose(Pose::from_degrees(
                1.0, 2.0, 3.0, 0.0, 0.0, 0.0
            )))
        );
        assert!(matches!(parse("check 0 0 5 0 0 0"), Ok(Command::Check(_))));
    }

    #[test]
    fn pose_field_errors_name_the_field() {
        assert_eq!(
            parse("pose 1 2 3 4"),
            Err(ParseError::MissingField {
                what: Missing::Axis(Axis::Pitch),
                verb: Verb::Pose
            })
        );
        assert_eq!(
            parse("pose 1 2 3 4 5 6 7"),
            Err(ParseError::ExtraField {
                word: word("7"),
                verb: Verb::Pose
            })
        );
        assert_eq!(
            parse("pose 1 2 x 0 0 0"),
            Err(ParseError::BadNumber {
                field: Field::Axis(Axis::Z),
                word: word("x")
            })
        );
        assert_eq!(
            parse("pose 0 0 0 nan 0 0"),
            Err(ParseError::NotFinite {
                field: Field::Axis(Axis::Roll),
                word: word("nan")
            })
        );
        assert_eq!(
            parse("pose 0 0 0 0 0 -inf"),
            Err(ParseError::NotFinite {
                field: Field::Axis(Axis::Yaw),
                word: word("-inf")
            })
        );
        assert_eq!(
            parse("pose 1e39 0 0 0 0 0"),
            Err(ParseError::NumberTooLarge {
                field: Field::Axis(Axis::X),
                word: word("1e39")
            })
        );
        assert!(matches!(
            err("pose 0x10 0 0 0 0 0"),
            ParseError::BadNumber {
                field: Field::Axis(Axis::X),
                ..
            }
        ));
        assert!(matches!(
            err("check 0 0 0 0 0"),
            ParseError::MissingField {
                what: Missing::Axis(Axis::Yaw),
                verb: Verb::Check
            }
        ));
    }

    #[test]
    fn move_and_nudge_take_named_axes() {
        let Ok(Command::Move(v)) = parse("move z=10 roll=5") else {
            panic!()
        };
        assert_eq!(v.0, [None, None, Some(10.0), Some(5.0), None, None]);
        let base = Pose::from_degrees(1.0, 2.0, 3.0, 4.0, 5.0, 6.0);
        let moved = v.apply(&base, false);
        assert_eq!(moved.to_array()[..3], [1.0, 2.0, 10.0]);
        assert!((moved.roll_rad.to_degrees() - 5.0).abs() < 1e-5);
        assert_eq!(moved.yaw_rad, base.yaw_rad);
        let Ok(Command::Nudge(v)) = parse("NUDGE x=-1.5 yaw=2") else {
            panic!()
        };
        let nudged = v.apply(&base, true);
        assert_eq!(nudged.x_mm, -0.5);
        assert!((nudged.yaw_rad.to_degrees() - 8.0).abs() < 1e-4);
        assert_eq!(nudged.z_mm, 3.0);
    }

    #[test]
    fn move_errors() {
        assert!(matches!(
            err("move"),
            ParseError::MissingField {
                what: Missing::AxisValue,
                verb: Verb::Move
            }
        ));
        assert!(matches!(err("move z"), ParseError::BadAssignment { .. }));
        assert!(matches!(err("move z 10"), ParseError::BadAssignment { .. }));
        assert!(matches!(err("move w=1"), ParseError::UnknownAxis { .. }));
        assert_eq!(
            err("move z=1 z=2"),
            ParseError::DuplicateAxis { axis: Axis::Z }
        );
        assert!(matches!(
            err("move z="),
            ParseError::MissingField {
                what: Missing::Axis(Axis::Z),
                ..
            }
        ));
        assert!(matches!(
            err("nudge roll=abc"),
            ParseError::BadNumber { .. }
        ));
        assert!(matches!(
            err("nudge roll=inf"),
            ParseError::NotFinite { .. }
        ));
        assert!(matches!(
            err("nudge x=-1e40"),
            ParseError::NumberTooLarge { .. }
        ));
    }

    #[test]
    fn simple_commands_take_nothing_more() {
        for (text, cmd) in [
            ("home", Command::Home),
            ("Stop", Command::Stop),
            ("reset", Command::Reset),
            ("status", Command::Status),
            ("?", Command::Status),
            ("pulses", Command::Pulses),
            ("geometry", Command::Geometry),
            ("config", Command::Config),
            ("HELP", Command::Help),
            ("defaults", Command::Defaults),
            ("limits", Command::Limits),
        ] {
            assert_eq!(parse(text), Ok(cmd), "{text}");
            let extra = std::format!("{text} now");
            assert!(
                matches!(err(&extra), ParseError::ExtraField { .. }),
                "{extra}"
            );
        }
    }

    #[test]
    fn servo_takes_a_servo_number_and_a_pulse() {
        assert_eq!(
            parse("servo 3 1520.5"),
            Ok(Command::Servo {
                servo: 3,
                pulse_us: 1520.5
            })
        );
        assert_eq!(
            parse("SERVO,6,900"),
            Ok(Command::Servo {
                servo: 6,
                pulse_us: 900.0
            })
        );
        for bad in [
            "servo 0 1500",
            "servo 7 1500",
            "servo x 1500",
            "servo 12 1500",
        ] {
            assert!(matches!(err(bad), ParseError::BadServo { .. }), "{bad}");
        }
        assert_eq!(
            err("servo"),
            ParseError::MissingField {
                what: Missing::ServoNumber,
                verb: Verb::Servo
            }
        );
        assert_eq!(
            err("servo 2"),
            ParseError::MissingField {
                what: Missing::PulseUs,
                verb: Verb::Servo
            }
        );
        assert_eq!(
            err("servo 2 fast"),
            ParseError::BadNumber {
                field: Field::PulseUs,
                word: word("fast")
            }
        );
        assert!(matches!(
            err("servo 2 nan"),
            ParseError::NotFinite {
                field: Field::PulseUs,
                ..
            }
        ));
        assert!(matches!(
            err("servo 2 1500 3"),
            ParseError::ExtraField { .. }
        ));
    }

    #[test]
    fn set_parses_name_and_value() {
        assert_eq!(
            parse("set servo3.trim_us 1520"),
            Ok(Command::Set(
                SettingId::Servo(ServoSel::One(3), ServoParam::TrimUs),
                SettingValue::Number(1520.0)
            ))
        );
        assert_eq!(
            parse("SET Echo OFF"),
            Ok(Command::Set(SettingId::Echo, SettingValue::Flag(false)))
        );
        assert!(matches!(
            err("set"),
            ParseError::MissingField {
                what: Missing::SettingName,
                ..
            }
        ));
        assert!(matches!(
            err("set frame_hz"),
            ParseError::MissingField {
                what: Missing::SettingValue,
                ..
            }
        ));
        assert!(matches!(
            err("set colour red"),
            ParseError::UnknownSetting { .. }
        ));
        assert!(matches!(
            err("set frame_hz 100 now"),
            ParseError::ExtraField { .. }
        ));
        assert!(matches!(
            err("set frame_hz 1000"),
            ParseError::Setting(SettingError::OutOfRange { .. })
        ));
    }

    #[test]
    fn unknown_commands_and_bad_lines() {
        assert_eq!(
            parse("fly 1 2"),
            Err(ParseError::UnknownCommand { word: word("fly") })
        );
        // Separators only: not blank (commas are not spaces), but no command either.
        assert_eq!(parse(" , ,"), Err(ParseError::NoCommand));
        assert_eq!(parse(","), Err(ParseError::NoCommand));
        assert_eq!(
            err(&"x".repeat(MAX_LINE + 1)),
            ParseError::Spoiled(Spoiled::TooLong)
        );
        assert_eq!(err("home\u{7}"), ParseError::Spoiled(Spoiled::BadByte(7)));
    }

    proptest::proptest! {
        #[test]
        fn parse_never_panics(line in "[ -~]{0,128}") {
            let _ = parse(&line);
        }

        #[test]
        fn parsed_poses_are_finite(v in proptest::array::uniform6(-1e38f32..1e38)) {
            let line = std::format!("pose {} {} {} {} {} {}", v[0], v[1], v[2], v[3], v[4], v[5]);
            if let Ok(Command::Pose(p)) = parse(&line) {
                proptest::prop_assert!(p.first_non_finite().is_none());
            }
        }
    }
}
