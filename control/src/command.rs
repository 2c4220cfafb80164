//! Command parsing: one line of text -> one [`Command`], or the [`Error`] that explains why not.
//!
//! Lines are case-insensitive; words are separated by spaces, tabs or commas. Numbers are strict
//! decimals ([`crate::number`]); lengths are mm, angles degrees. Parsing only looks at the text:
//! whether a pose is reachable is decided later by the controller.

use kinematics_core::pose::Axis;
use kinematics_core::Pose;

use crate::number::{parse_f32, NumberError};
use crate::protocol::MAX_LINE;
use crate::report::{
    word, Error, Field, USAGE_CHECK, USAGE_MOVE, USAGE_NUDGE, USAGE_POSE, USAGE_SET,
};
use crate::settings::{SettingId, SettingValue};

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
    /// `home`.
    Home,
    /// `stop`.
    Stop,
    /// `status` or `?`.
    Status,
    /// `geometry`.
    Geometry,
    /// `config`.
    Config,
    /// `help`.
    Help,
    /// `defaults`.
    Defaults,
    /// `set name value`.
    Set(SettingId, SettingValue),
}

/// The words of a line.
struct Words<'a> {
    inner: core::str::Split<'a, fn(char) -> bool>,
}

impl<'a> Words<'a> {
    fn new(line: &'a str) -> Self {
        fn separator(c: char) -> bool {
            c == ' ' || c == '\t' || c == ','
        }
        Words {
            inner: line.split(separator as fn(char) -> bool),
        }
    }
}

impl<'a> Iterator for Words<'a> {
    type Item = &'a str;
    fn next(&mut self) -> Option<&'a str> {
        self.inner.by_ref().find(|w| !w.is_empty())
    }
}

/// Parses one number for `field`.
fn number(field: Field, text: &str) -> Result<f32, Error> {
    parse_f32(text).map_err(|e| {
        let word = word(text);
        match e {
            NumberError::NotFinite => Error::NotFinite { field, word },
            NumberError::TooLarge => Error::NumberTooLarge { field, word },
            NumberError::Syntax | NumberError::NotWhole => Error::BadNumber { field, word },
        }
    })
}

fn no_more(words: &mut Words<'_>, usage: &'static str) -> Result<(), Error> {
    match words.next() {
        Some(extra) => Err(Error::ExtraField {
            word: word(extra),
            usage,
        }),
        None => Ok(()),
    }
}

/// `x y z roll pitch yaw`, exactly six numbers.
fn full_pose(words: &mut Words<'_>, usage: &'static str) -> Result<Pose, Error> {
    let mut v = [0.0f32; 6];
    for (slot, axis) in v.iter_mut().zip(Axis::ALL) {
        let text = words.next().ok_or(Error::MissingField {
            what: axis.name(),
            usage,
        })?;
        *slot = number(Field::Axis(axis), text)?;
    }
    no_more(words, usage)?;
    Ok(Pose::from_degrees(v[0], v[1], v[2], v[3], v[4], v[5]))
}

/// `axis=value ...`, at least one, each axis at most once.
fn axis_values(words: &mut Words<'_>, usage: &'static str) -> Result<AxisValues, Error> {
    let mut values = AxisValues::default();
    let mut any = false;
    for w in words {
        let (name, value) = w
            .split_once('=')
            .ok_or(Error::BadAssignment { word: word(w) })?;
        let axis = Axis::ALL
            .into_iter()
            .find(|a| a.name() == name)
            .ok_or(Error::UnknownAxis { word: word(name) })?;
        let slot = &mut values.0[axis as usize];
        if slot.is_some() {
            return Err(Error::DuplicateAxis { axis });
        }
        if value.is_empty() {
            return Err(Error::MissingField {
                what: axis.name(),
                usage,
            });
        }
        *slot = Some(number(Field::Axis(axis), value)?);
        any = true;
    }
    if any {
        Ok(values)
    } else {
        Err(Error::MissingField {
            what: "axis=value",
            usage,
        })
    }
}

/// Parses one line (any case; at most [`MAX_LINE`] characters of printable ASCII). The line
/// must not be blank.
pub fn parse(line: &str) -> Result<Command, Error> {
    if line.len() > MAX_LINE {
        return Err(Error::LineTooLong);
    }
    if let Some(&byte) = line
        .as_bytes()
        .iter()
        .find(|b| !(0x20..=0x7E).contains(*b) && **b != b'\t')
    {
        return Err(Error::BadCharacter { byte });
    }
    let mut lower = [0u8; MAX_LINE];
    let lower = &mut lower[..line.len()];
    lower.copy_from_slice(line.as_bytes());
    lower.make_ascii_lowercase();
    // Printable ASCII throughout, checked above.
    let line = core::str::from_utf8(lower).map_err(|_| Error::BadCharacter { byte: 0 })?;

    let mut words = Words::new(line);
    let name = words.next().unwrap_or("");
    let simple = |cmd: Command, usage: &'static str, words: &mut Words<'_>| {
        no_more(words, usage).map(|()| cmd)
    };
    match name {
        "pose" => full_pose(&mut words, USAGE_POSE).map(Command::Pose),
        "check" => full_pose(&mut words, USAGE_CHECK).map(Command::Check),
        "move" => axis_values(&mut words, USAGE_MOVE).map(Command::Move),
        "nudge" => axis_values(&mut words, USAGE_NUDGE).map(Command::Nudge),
        "home" => simple(Command::Home, "home", &mut words),
        "stop" => simple(Command::Stop, "stop", &mut words),
        "status" | "?" => simple(Command::Status, "status", &mut words),
        "geometry" => simple(Command::Geometry, "geometry", &mut words),
        "config" => simple(Command::Config, "config", &mut words),
        "help" => simple(Command::Help, "help", &mut words),
        "defaults" => simple(Command::Defaults, "defaults", &mut words),
        "set" => {
            let name = words.next().ok_or(Error::MissingField {
                what: "name",
                usage: USAGE_SET,
            })?;
            let id = SettingId::parse(name).ok_or(Error::UnknownSetting { word: word(name) })?;
            let value = words.next().ok_or(Error::MissingField {
                what: "value",
                usage: USAGE_SET,
            })?;
            let value = id.parse_value(value)?;
            no_more(&mut words, USAGE_SET)?;
            Ok(Command::Set(id, value))
        }
        other => Err(Error::UnknownCommand { word: word(other) }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::Code;
    use crate::settings::{ServoParam, ServoSel};

    fn code(line: &str) -> Code {
        parse(line).unwrap_err().code()
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
            Err(Error::MissingField {
                what: "pitch",
                usage: USAGE_POSE
            })
        );
        assert_eq!(
            parse("pose 1 2 3 4 5 6 7"),
            Err(Error::ExtraField {
                word: word("7"),
                usage: USAGE_POSE
            })
        );
        assert_eq!(
            parse("pose 1 2 x 0 0 0"),
            Err(Error::BadNumber {
                field: Field::Axis(Axis::Z),
                word: word("x")
            })
        );
        assert_eq!(
            parse("pose 0 0 0 nan 0 0"),
            Err(Error::NotFinite {
                field: Field::Axis(Axis::Roll),
                word: word("nan")
            })
        );
        assert_eq!(
            parse("pose 0 0 0 0 0 -inf"),
            Err(Error::NotFinite {
                field: Field::Axis(Axis::Yaw),
                word: word("-inf")
            })
        );
        assert_eq!(
            parse("pose 1e39 0 0 0 0 0"),
            Err(Error::NumberTooLarge {
                field: Field::Axis(Axis::X),
                word: word("1e39")
            })
        );
        assert_eq!(code("pose 0x10 0 0 0 0 0"), Code::BadNumber);
        assert_eq!(code("check 0 0 0 0 0"), Code::MissingField);
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
        assert_eq!(code("move"), Code::MissingField);
        assert_eq!(code("move z"), Code::BadAssignment);
        assert_eq!(code("move z 10"), Code::BadAssignment);
        assert_eq!(code("move w=1"), Code::UnknownAxis);
        assert_eq!(code("move z=1 z=2"), Code::DuplicateAxis);
        assert_eq!(code("move z="), Code::MissingField);
        assert_eq!(code("nudge roll=abc"), Code::BadNumber);
        assert_eq!(code("nudge roll=inf"), Code::NotFinite);
        assert_eq!(code("nudge x=-1e40"), Code::NumberTooLarge);
    }

    #[test]
    fn simple_commands_take_nothing_more() {
        for (text, cmd) in [
            ("home", Command::Home),
            ("Stop", Command::Stop),
            ("status", Command::Status),
            ("?", Command::Status),
            ("geometry", Command::Geometry),
            ("config", Command::Config),
            ("HELP", Command::Help),
            ("defaults", Command::Defaults),
        ] {
            assert_eq!(parse(text), Ok(cmd), "{text}");
            let extra = std::format!("{text} now");
            assert_eq!(code(&extra), Code::ExtraField, "{extra}");
        }
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
        assert_eq!(code("set"), Code::MissingField);
        assert_eq!(code("set frame_hz"), Code::MissingField);
        assert_eq!(code("set colour red"), Code::UnknownSetting);
        assert_eq!(code("set frame_hz 100 now"), Code::ExtraField);
        assert_eq!(code("set frame_hz 1000"), Code::OutOfRange);
    }

    #[test]
    fn unknown_commands_and_bad_lines() {
        assert_eq!(
            parse("fly 1 2"),
            Err(Error::UnknownCommand { word: word("fly") })
        );
        assert_eq!(code(&"x".repeat(MAX_LINE + 1)), Code::LineTooLong);
        assert_eq!(code("home\u{7}"), Code::BadCharacter);
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
