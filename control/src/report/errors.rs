//! The error vocabulary: the `error:<code>` of every refusal and its message, worded once for
//! every error type of the firmware (the line's, the parser's, the settings', the kinematics'
//! and the motion's). The message names the field, leg, servo or limit at fault, in the names a
//! user types (`servo4.trim_us`, `rod_mm`, `leg 3`).

use core::fmt::{self, Display, Formatter};

use kinematics_core::geometry::{GeometryError, Length};
use kinematics_core::ik::IkError;
use kinematics_core::servo::{
    ServoError, ServoField, MAX_PULSE_US, MAX_RATE_US_PER_RAD, MIN_PULSE_US, MIN_RATE_US_PER_RAD,
};
use kinematics_core::KinematicsError;

use super::format::{AsGiven, Fixed};
use super::near::{nearest_setting, nearest_verb};
use crate::command::{Field, Missing, ParseError, Verb};
use crate::error::{Error, PoseError};
use crate::payload::TorqueError;
use crate::protocol::{Lost, Spoiled, MAX_LINE};
use crate::safety::{Estop, FREE_GPIOS};
use crate::settings::{Expected, SettingError, DIR_WORDS, FLAG_WORDS};
use crate::store::SaveError;

/// The error codes, one per kind of refusal. `error:<code>` is what programs match on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Code {
    /// The line was longer than [`MAX_LINE`] characters.
    LineTooLong,
    /// The receive queue overflowed while the line arrived.
    RxOverflow,
    /// The line contained a byte that is not printable ASCII.
    BadCharacter,
    /// The first word is not a command.
    UnknownCommand,
    /// A value the command needs is missing.
    MissingField,
    /// There is more on the line than the command takes.
    ExtraField,
    /// A value is not a decimal number.
    BadNumber,
    /// A value is NaN or infinity.
    NotFinite,
    /// A value does not fit (e.g. `1e39`).
    NumberTooLarge,
    /// `move`/`nudge` named something that is not an axis.
    UnknownAxis,
    /// `move`/`nudge` named an axis twice.
    DuplicateAxis,
    /// `move`/`nudge` got a word that is not `axis=value`.
    BadAssignment,
    /// `set` named something that is not a setting.
    UnknownSetting,
    /// A setting value has the wrong form (e.g. `echo maybe`).
    BadValue,
    /// A setting value is outside its range.
    OutOfRange,
    /// The resulting servo settings are inconsistent.
    BadServoConfig,
    /// The resulting geometry is not a buildable platform.
    BadGeometry,
    /// A leg cannot reach the target pose.
    Unreachable,
    /// The target pose needs a pulse outside a servo's limits.
    ServoLimit,
    /// A rotation beyond +-180 degrees.
    AngleTooLarge,
    /// A computed pose coordinate is not finite.
    PoseNotFinite,
    /// The straight path to the target leaves the workspace or a servo limit.
    PathBlocked,
    /// With the new settings the current pose could not be held.
    PoseConflict,
    /// Not possible while moving.
    Busy,
    /// Two settings that may not be equal are (an axis given to two stream counts, one GPIO
    /// for two pins).
    SettingConflict,
    /// The emergency stop is on.
    Estop,
    /// The settings could not be written to flash.
    SaveFailed,
    /// The target pose would need more torque of a servo than its rating, with the payload.
    TorqueLimit,
    /// The pulses set with `servo` correspond to no pose, so there is no pose to move from.
    NoPose,
}

impl Code {
    /// Every code, for documentation checks.
    pub const ALL: [Code; 29] = [
        Code::LineTooLong,
        Code::RxOverflow,
        Code::BadCharacter,
        Code::UnknownCommand,
        Code::MissingField,
        Code::ExtraField,
        Code::BadNumber,
        Code::NotFinite,
        Code::NumberTooLarge,
        Code::UnknownAxis,
        Code::DuplicateAxis,
        Code::BadAssignment,
        Code::UnknownSetting,
        Code::BadValue,
        Code::OutOfRange,
        Code::BadServoConfig,
        Code::BadGeometry,
        Code::Unreachable,
        Code::ServoLimit,
        Code::AngleTooLarge,
        Code::PoseNotFinite,
        Code::PathBlocked,
        Code::PoseConflict,
        Code::Busy,
        Code::SettingConflict,
        Code::Estop,
        Code::SaveFailed,
        Code::TorqueLimit,
        Code::NoPose,
    ];

    /// The code as written after `error:`.
    pub const fn as_str(self) -> &'static str {
        match self {
            Code::LineTooLong => "line-too-long",
            Code::RxOverflow => "rx-overflow",
            Code::BadCharacter => "bad-character",
            Code::UnknownCommand => "unknown-command",
            Code::MissingField => "missing-field",
            Code::ExtraField => "extra-field",
            Code::BadNumber => "bad-number",
            Code::NotFinite => "not-finite",
            Code::NumberTooLarge => "number-too-large",
            Code::UnknownAxis => "unknown-axis",
            Code::DuplicateAxis => "duplicate-axis",
            Code::BadAssignment => "bad-assignment",
            Code::UnknownSetting => "unknown-setting",
            Code::BadValue => "bad-value",
            Code::OutOfRange => "out-of-range",
            Code::BadServoConfig => "bad-servo-config",
            Code::BadGeometry => "bad-geometry",
            Code::Unreachable => "unreachable",
            Code::ServoLimit => "servo-limit",
            Code::AngleTooLarge => "angle-too-large",
            Code::PoseNotFinite => "pose-not-finite",
            Code::PathBlocked => "path-blocked",
            Code::PoseConflict => "pose-conflict",
            Code::Busy => "busy",
            Code::SettingConflict => "setting-conflict",
            Code::Estop => "e-stop",
            Code::SaveFailed => "save-failed",
            Code::TorqueLimit => "torque-limit",
            Code::NoPose => "no-pose",
        }
    }

    /// What the code means, in Markdown: the meaning column of `docs/error-codes.md`.
    pub const fn meaning(self) -> &'static str {
        match self {
            Code::LineTooLong => "more than 128 characters; the line was discarded to its end",
            Code::RxOverflow => "input arrived on UART0 faster than it could be handled and bytes were lost (a `# warning:` line says so at once; the error answers the line they fell into and says how many, \"at least\" where the UART lost them); never on USB",
            Code::BadCharacter => "a non-ASCII byte (0x80-0xFF) in the line; other control bytes are ignored",
            Code::UnknownCommand => "the first word is not a command",
            Code::MissingField => "a value is missing (names it)",
            Code::ExtraField => "more words than the command takes",
            Code::BadNumber => "not a decimal number (also `0x10`, `1_000`)",
            Code::NotFinite => "`nan` / `inf`",
            Code::NumberTooLarge => "does not fit a 32-bit float",
            Code::UnknownAxis => "not one of x y z roll pitch yaw",
            Code::DuplicateAxis => "an axis named twice",
            Code::BadAssignment => "not `axis=value`",
            Code::UnknownSetting => "not a setting name",
            Code::BadValue => "wrong form for the setting, or not a servo number",
            Code::OutOfRange => "outside the setting's range (names the range)",
            Code::BadServoConfig => "the resulting servo set is inconsistent",
            Code::BadGeometry => "the resulting geometry cannot be built",
            Code::Unreachable => "a leg cannot reach the target (names the leg)",
            Code::ServoLimit => "the target needs a pulse outside a servo's limits (names servo, pulse, limits); or `servo` asks for one",
            Code::AngleTooLarge => "a rotation beyond +-180 degrees",
            Code::PoseNotFinite => "a computed target coordinate is not finite (cannot happen from typed numbers; kept for completeness)",
            Code::PathBlocked => "the straight path leaves the workspace, a servo limit or a torque rating (says where and why)",
            Code::PoseConflict => "with the new setting the held pose could not be driven (or held: torque ratings)",
            Code::Busy => "frame rate, geometry, servo, payload or pivot settings, `defaults`, `save` or `servo` while moving",
            Code::SettingConflict => "two settings that must differ would be equal (an axis on two stream counts, one GPIO for both pins)",
            Code::Estop => "a move while the emergency stop is open or latched (says which: close the input, then `reset`)",
            Code::SaveFailed => "the flash did not keep what `save` wrote (it read back differently) or refused the write; the settings saved before are kept",
            Code::TorqueLimit => "with a payload and torque ratings, a servo could not hold the target (names the servo, the torque it would need and its rating)",
            Code::NoPose => "the pulses set with `servo` correspond to no pose of the platform, so a move (or `check`, `limits`) has no pose to start from: drive the servos back with `servo`",
        }
    }

    /// A line that gets this code (with what must hold first, where something must), in
    /// Markdown: the example column of `docs/error-codes.md`; the end-to-end tests
    /// (`emulator/test/errors.test.js`) make the real firmware produce each code.
    pub const fn example(self) -> &'static str {
        match self {
            Code::LineTooLong => "a 129-character line",
            Code::RxOverflow => "a long burst of lines without waiting for replies",
            Code::BadCharacter => "`pose 0 0 1 0 0 0°`",
            Code::UnknownCommand => "`fly`",
            Code::MissingField => "`pose 1 2 3`",
            Code::ExtraField => "`home now`",
            Code::BadNumber => "`pose 1 2 three 4 5 6`",
            Code::NotFinite => "`pose 1 2 3 nan 5 6`",
            Code::NumberTooLarge => "`pose 1e39 0 0 0 0 0`",
            Code::UnknownAxis => "`move q=1`",
            Code::DuplicateAxis => "`move z=1 z=2`",
            Code::BadAssignment => "`move z 10`",
            Code::UnknownSetting => "`set colour red`",
            Code::BadValue => "`set echo sometimes`, `set baud 100000`, `servo 7 1500`",
            Code::OutOfRange => "`set frame_hz 20`",
            Code::BadServoConfig => "`set servo1.trim_us 1950`",
            Code::BadGeometry => "`set rod_mm 15`",
            Code::Unreachable => "`pose 0 0 80 0 0 0`",
            Code::ServoLimit => "`pose 0 0 -15 0 0 0`, `servo 2 2000`",
            Code::AngleTooLarge => "`pose 0 0 0 181 0 0`",
            Code::PoseNotFinite => "-",
            Code::PathBlocked => "from `pose -28 19 -2.5 11 2 -20`: `pose 30 -12 -13.5 5 -13 28`",
            Code::PoseConflict => "at `pose 0 0 -8 0 0 0`: `set servo1.max_us 1600`",
            Code::Busy => "`set frame_hz 100` during a move",
            Code::SettingConflict => "`set stream.axis2 x` with `stream.axis1` at `x`",
            Code::Estop => "`home` with the e-stop input open",
            Code::SaveFailed => "`save` on a worn-out flash",
            Code::TorqueLimit => {
                "`pose 10 0 0 0 0 0` with `payload_g 2000` and `servos.torque_kgcm 1`"
            }
            Code::NoPose => "`home` after `servo 1 1900`, `servo 2 1900`",
        }
    }
}

/// Writes `docs/error-codes.md`: every code of [`Code::ALL`] with its meaning and an example.
/// `cargo run -p control --example documents` writes the file with it, and
/// `control/tests/documents.rs` fails when the file differs, so the list is never kept in step
/// by hand (`emulator/test/errors.test.js` reads its codes from the file).
pub fn write_error_codes_doc(out: &mut impl fmt::Write) -> fmt::Result {
    out.write_str(
        "# Error codes\n\
         \n\
         <!-- Written by `cargo run -p control --example documents` from `Code::ALL`\n\
         (control/src/report/errors.rs); do not edit: control/tests/documents.rs fails when\n\
         this file is out of date. -->\n\
         \n\
         Every refusal is `error:<code> <message>`: the message names the field, leg, servo or\n\
         limit at fault. Nothing changes and the platform holds its pose. Programs match on the\n\
         code; the message is for people. (The replies and the rest of the protocol:\n\
         [commands.md](commands.md).)\n\
         \n\
         | code | meaning | example |\n\
         | --- | --- | --- |\n",
    )?;
    for code in Code::ALL {
        writeln!(
            out,
            "| `error:{}` | {} | {} |",
            code.as_str(),
            code.meaning(),
            code.example()
        )?;
    }
    Ok(())
}

impl Display for Code {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl Error {
    /// The code of this refusal.
    pub fn code(&self) -> Code {
        match self {
            Error::Spoiled(s) => spoiled_code(*s),
            Error::Parse(e) => e.code(),
            Error::Setting(e) => e.code(),
            Error::Pose(e) => ik_code(e),
            Error::Torque(_) => Code::TorqueLimit,
            Error::PulseOutsideLimits { .. } => Code::ServoLimit,
            Error::NoPose(_) => Code::NoPose,
            Error::PathBlocked { .. } => Code::PathBlocked,
            Error::PoseConflict { .. } => Code::PoseConflict,
            Error::Busy | Error::Pending => Code::Busy,
            Error::Estop(_) => Code::Estop,
            Error::SaveFailed(_) => Code::SaveFailed,
        }
    }
}

fn spoiled_code(s: Spoiled) -> Code {
    match s {
        Spoiled::TooLong => Code::LineTooLong,
        Spoiled::BadByte(_) => Code::BadCharacter,
        Spoiled::RxOverflow(_) => Code::RxOverflow,
    }
}

fn ik_code(e: &IkError) -> Code {
    match e {
        IkError::NonFinite { .. } => Code::PoseNotFinite,
        IkError::AngleTooLarge { .. } => Code::AngleTooLarge,
        IkError::Unreachable { .. } => Code::Unreachable,
        IkError::ServoLimit { .. } => Code::ServoLimit,
    }
}

impl ParseError {
    /// The code of this refusal.
    pub fn code(&self) -> Code {
        match self {
            ParseError::Spoiled(s) => spoiled_code(*s),
            ParseError::UnknownCommand { .. } | ParseError::NoCommand => Code::UnknownCommand,
            ParseError::MissingField { .. } => Code::MissingField,
            ParseError::ExtraField { .. } => Code::ExtraField,
            ParseError::BadNumber { .. } => Code::BadNumber,
            ParseError::NotFinite { .. } => Code::NotFinite,
            ParseError::NumberTooLarge { .. } => Code::NumberTooLarge,
            ParseError::UnknownAxis { .. } => Code::UnknownAxis,
            ParseError::DuplicateAxis { .. } => Code::DuplicateAxis,
            ParseError::BadAssignment { .. } => Code::BadAssignment,
            ParseError::UnknownSetting { .. } => Code::UnknownSetting,
            ParseError::BadServo { .. } => Code::BadValue,
            ParseError::Setting(e) => e.code(),
        }
    }
}

impl SettingError {
    /// The code of this refusal.
    pub fn code(&self) -> Code {
        match self {
            SettingError::BadNumber { .. } => Code::BadNumber,
            SettingError::NotFinite { .. } => Code::NotFinite,
            SettingError::NumberTooLarge { .. } => Code::NumberTooLarge,
            SettingError::BadValue { .. } | SettingError::NotOneOf { .. } => Code::BadValue,
            SettingError::OutOfRange { .. } => Code::OutOfRange,
            SettingError::BadServoConfig(_) => Code::BadServoConfig,
            SettingError::BadGeometry(_) => Code::BadGeometry,
            SettingError::StreamAxisTwice { .. } | SettingError::PinTwice { .. } => {
                Code::SettingConflict
            }
        }
    }
}

/// How a command is used, as `missing-field` and `extra-field` messages show it.
pub const fn usage(verb: Verb) -> &'static str {
    match verb {
        Verb::Pose => "pose <x> <y> <z> <roll> <pitch> <yaw>",
        Verb::Check => "check <x> <y> <z> <roll> <pitch> <yaw>",
        Verb::Move => "move <axis>=<value> ... (axes x y z roll pitch yaw)",
        Verb::Nudge => "nudge <axis>=<delta> ... (axes x y z roll pitch yaw)",
        Verb::Set => "set <name> <value> (names as listed by config)",
        Verb::Servo => "servo <1-6> <us>",
        // The others take nothing: their usage is their name.
        other => other.name(),
    }
}

/// The words a setting takes, as a refusal lists them: the two `config` shows, then the
/// forms a script may write, e.g. `on or off (1 / 0)`.
struct Words<'a>(&'a [&'a str]);

impl Display for Words<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let (shown, also) = self.0.split_at(self.0.len().min(2));
        for (i, w) in shown.iter().enumerate() {
            if i > 0 {
                f.write_str(" or ")?;
            }
            f.write_str(w)?;
        }
        for (i, w) in also.iter().enumerate() {
            f.write_str(if i == 0 { " (" } else { " / " })?;
            f.write_str(w)?;
        }
        if also.is_empty() {
            Ok(())
        } else {
            f.write_str(")")
        }
    }
}

/// The message of a refused line: `Display` writes it without the code (see
/// [`super::refusal`] for the whole reply line).
impl Display for Error {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Error::Spoiled(s) => SpoiledMessage(*s).fmt(f),
            Error::Parse(e) => e.fmt(f),
            Error::Setting(e) => e.fmt(f),
            Error::Pose(e) => IkMessage(e).fmt(f),
            Error::Torque(e) => TorqueMessage(e).fmt(f),
            Error::PathBlocked { percent, cause } => write!(
                f,
                "the straight path from the current pose is blocked {}% of the way: {}; nothing moved",
                Fixed(*percent, 1),
                PoseMessage(cause)
            ),
            Error::PoseConflict { cause } => write!(
                f,
                "with that setting the current pose could not be held: {}; send home first",
                PoseMessage(cause)
            ),
            Error::PulseOutsideLimits {
                servo,
                pulse_us,
                min_us,
                max_us,
            } => write!(
                f,
                "servo {servo}: {} us is outside its limits {}..{} us (servo{servo}.min_us, max_us)",
                AsGiven(*pulse_us, 2),
                Fixed(*min_us, 2),
                Fixed(*max_us, 2)
            ),
            Error::NoPose(e) => write!(
                f,
                "the pulses set with servo correspond to no pose of the platform ({}); \
                 drive the servos back with servo first (servoN.trim_us is home)",
                KinematicsMessage(e)
            ),
            Error::Busy => f.write_str("the platform is moving; wait for it or send stop first"),
            Error::Pending => f.write_str(
                "the previous command is still being carried out; wait for its reply",
            ),
            Error::Estop(Estop::Open) => f.write_str(
                "emergency stop: the e-stop input is open; close it, then send reset",
            ),
            Error::Estop(_) => f.write_str(
                "emergency stop: the e-stop input is closed again; send reset to move again",
            ),
            Error::SaveFailed(SaveError::Flash) => f.write_str(
                "the flash refused the write; the settings saved before are kept",
            ),
            Error::SaveFailed(SaveError::Verify {
                offset,
                wrote,
                read,
            }) => write!(
                f,
                "the flash did not keep what was written (byte {offset} of the settings storage \
                 read 0x{read:02X}, not 0x{wrote:02X}); the settings saved before are kept"
            ),
        }
    }
}

struct SpoiledMessage(Spoiled);

impl Display for SpoiledMessage {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self.0 {
            Spoiled::TooLong => write!(
                f,
                "line longer than {MAX_LINE} characters; it was discarded"
            ),
            Spoiled::RxOverflow(Lost { bytes, in_uart: false }) => write!(
                f,
                "receive queue overflowed, {} lost; the line was discarded (wait for each reply before sending more)",
                Bytes(bytes)
            ),
            Spoiled::RxOverflow(Lost { bytes, in_uart: true }) => write!(
                f,
                "input lost (at least {}, some in the UART); the line was discarded (wait for each reply before sending more)",
                Bytes(bytes)
            ),
            Spoiled::BadByte(byte) => write!(
                f,
                "byte 0x{byte:02X} is not printable ASCII; the line was discarded"
            ),
        }
    }
}

/// The parser's message (without the code).
impl Display for ParseError {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            ParseError::Spoiled(s) => SpoiledMessage(*s).fmt(f),
            ParseError::UnknownCommand { word } => {
                write!(f, "'{word}' is not a command; ")?;
                if let Some(verb) = nearest_verb(word) {
                    write!(f, "did you mean {}? ", verb.name())?;
                }
                f.write_str("type help")
            }
            ParseError::NoCommand => f.write_str("only separators, no command; type help"),
            ParseError::MissingField { what, verb } => {
                let what = match what {
                    Missing::Axis(axis) => axis.name(),
                    Missing::ServoNumber => "servo number",
                    Missing::PulseUs => "pulse_us",
                    Missing::AxisValue => "axis=value",
                    Missing::SettingName => "name",
                    Missing::SettingValue => "value",
                };
                write!(f, "missing {what}; usage: {}", usage(*verb))
            }
            ParseError::ExtraField { word, verb } => {
                write!(f, "unexpected '{word}'; usage: {}", usage(*verb))
            }
            ParseError::BadNumber { field, word } => {
                write!(
                    f,
                    "{}: '{word}' is not a decimal number",
                    field_name(*field)
                )
            }
            ParseError::NotFinite { field, word } => {
                write!(f, "{}: '{word}' is not a finite number", field_name(*field))
            }
            ParseError::NumberTooLarge { field, word } => {
                write!(f, "{}: '{word}' is too large", field_name(*field))
            }
            ParseError::BadServo { word } => {
                write!(f, "'{word}' is not a servo number; servos are 1 to 6")
            }
            ParseError::UnknownAxis { word } => {
                write!(f, "'{word}' is not an axis; axes are x y z roll pitch yaw")
            }
            ParseError::DuplicateAxis { axis } => write!(f, "{} is given twice", axis.name()),
            ParseError::BadAssignment { word } => {
                write!(f, "'{word}' should be axis=value, for example z=10")
            }
            ParseError::UnknownSetting { word } => {
                write!(f, "'{word}' is not a setting; ")?;
                if let Some(id) = nearest_setting(word) {
                    write!(f, "did you mean {id}? ")?;
                }
                f.write_str("type config for the list")
            }
            ParseError::Setting(e) => e.fmt(f),
        }
    }
}

/// The settings' message (without the code).
impl Display for SettingError {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            SettingError::BadNumber { setting, word } => {
                write!(f, "{setting}: '{word}' is not a decimal number")
            }
            SettingError::NotFinite { setting, word } => {
                write!(f, "{setting}: '{word}' is not a finite number")
            }
            SettingError::NumberTooLarge { setting, word } => {
                write!(f, "{setting}: '{word}' is too large")
            }
            SettingError::BadValue {
                setting,
                word,
                expected,
            } => {
                write!(f, "{setting}: '{word}' is not ")?;
                match expected {
                    Expected::WholeNumber => f.write_str("a whole number"),
                    Expected::OnOrOff => Words(&FLAG_WORDS.map(|(w, _)| w)).fmt(f),
                    Expected::NormalOrReversed => Words(&DIR_WORDS.map(|(w, _)| w)).fmt(f),
                    Expected::OneOf(words) => {
                        f.write_str("one of")?;
                        words.iter().try_for_each(|w| write!(f, " {w}"))
                    }
                    Expected::FreePin => {
                        f.write_str("off or a free GPIO:")?;
                        FREE_GPIOS.iter().try_for_each(|p| write!(f, " {p}"))
                    }
                    Expected::Hundredths => f.write_str(
                        "a number of hundredths (at most two decimals: the flash keeps hundredths, so the value saved comes back as given)",
                    ),
                }
            }
            SettingError::NotOneOf {
                setting,
                word,
                allowed,
            } => {
                write!(f, "{setting}: '{word}' is not one of")?;
                for v in allowed.iter() {
                    write!(f, " {v}")?;
                }
                Ok(())
            }
            SettingError::OutOfRange {
                setting,
                value,
                min,
                max,
                unit,
                off_allowed,
            } => {
                write!(f, "{setting} {value} is outside {min}..{max}")?;
                if !unit.is_empty() {
                    write!(f, " {unit}")?;
                }
                if *off_allowed {
                    f.write_str(" (or 0/off)")?;
                }
                Ok(())
            }
            SettingError::BadServoConfig(e) => write!(f, "{}; nothing changed", ServoMessage(e)),
            SettingError::BadGeometry(e) => write!(f, "{}; nothing changed", GeometryMessage(e)),
            SettingError::StreamAxisTwice {
                axis,
                first,
                second,
            } => write!(
                f,
                "stream.axis{first} and stream.axis{second} would both be {}; each axis comes from one count at most (set the other to none first); nothing changed",
                axis.name()
            ),
            SettingError::PinTwice { pin } => write!(
                f,
                "estop_pin and power_pin cannot both be GPIO {pin}; nothing changed"
            ),
        }
    }
}

/// The name of a number a command takes, as errors show it.
fn field_name(field: Field) -> &'static str {
    match field {
        Field::Axis(axis) => axis.name(),
        Field::PulseUs => "pulse_us",
    }
}

/// The message for a pose's refusal, whatever refused it (paths, conflicts, faults, `limits`).
pub(super) struct PoseMessage<'a>(pub &'a PoseError);

impl Display for PoseMessage<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self.0 {
            PoseError::Ik(e) => IkMessage(e).fmt(f),
            PoseError::Torque(e) => TorqueMessage(e).fmt(f),
        }
    }
}

/// The message for a pose that would overload a servo.
pub(super) struct TorqueMessage<'a>(pub &'a TorqueError);

impl Display for TorqueMessage<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match *self.0 {
            TorqueError::Over {
                servo,
                needed_kgcm,
                rated_kgcm,
            } => write!(
                f,
                "servo {servo} would need {} kgf cm to hold the payload, over its rating {} kgf cm",
                Fixed(needed_kgcm.abs(), 3),
                Fixed(rated_kgcm, 2)
            ),
            TorqueError::Unknown(ref e) => write!(
                f,
                "the servos' holding torques are unbounded there ({})",
                KinematicsMessage(e)
            ),
        }
    }
}

/// The message for what the kinematics beyond the IK (the forward kinematics, the statics)
/// cannot compute.
pub(super) struct KinematicsMessage<'a>(pub &'a KinematicsError);

impl Display for KinematicsMessage<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match *self.0 {
            KinematicsError::Ik(ref e) => IkMessage(e).fmt(f),
            KinematicsError::Stroke { leg, .. } => {
                write!(f, "leg {leg} would leave its stroke")
            }
            KinematicsError::ZeroLength { leg } => {
                write!(f, "leg {leg}'s rod would have no length")
            }
            KinematicsError::DeadCentre { leg } => {
                write!(f, "leg {leg}'s arm is at dead centre, square to its rod")
            }
            KinematicsError::ElbowFlipped { leg } => {
                write!(f, "leg {leg}'s arm would have to fold through its rod")
            }
            KinematicsError::Singular { .. } => f.write_str("the platform is at a singular pose"),
            KinematicsError::GimbalLock { .. } => {
                f.write_str("pitch at +-90 deg, where roll and yaw are not defined")
            }
            KinematicsError::NotConverged { iterations, .. } => write!(
                f,
                "the rods cannot all reach their joints: no pose found in {iterations} iterations"
            ),
            KinematicsError::NonFinite { .. } => f.write_str("a value is not a finite number"),
        }
    }
}

/// The message for an IK refusal (shared by direct, path and conflict errors and faults).
pub(super) struct IkMessage<'a>(pub &'a IkError);

impl Display for IkMessage<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match *self.0 {
            IkError::NonFinite { axis } => write!(f, "{} is not a finite number", axis.name()),
            IkError::AngleTooLarge { axis, value_rad } => write!(
                f,
                "{} {} deg is beyond +-180 deg",
                axis.name(),
                Fixed(value_rad.to_degrees(), 3)
            ),
            IkError::Unreachable { leg } => write!(
                f,
                "leg {leg} cannot reach (arm and rod cannot meet the platform joint)"
            ),
            IkError::ServoLimit {
                servo,
                pulse_us,
                min_us,
                max_us,
            } => write!(
                f,
                "servo {servo} would need {} us, outside its limits {}..{} us",
                Fixed(pulse_us, 2),
                Fixed(min_us, 2),
                Fixed(max_us, 2)
            ),
        }
    }
}

/// The message for a refused servo set, in the names `set` uses.
struct ServoMessage<'a>(&'a ServoError);

impl Display for ServoMessage<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match *self.0 {
            ServoError::PulseOutOfRange {
                servo,
                field,
                value_us,
            } => {
                let name = match field {
                    ServoField::Home => "trim_us",
                    ServoField::Min => "min_us",
                    ServoField::Max => "max_us",
                };
                write!(
                    f,
                    "servo{servo}.{name} {} us is outside {}..{} us",
                    Fixed(value_us, 2),
                    Fixed(MIN_PULSE_US, 2),
                    Fixed(MAX_PULSE_US, 2)
                )
            }
            ServoError::RateOutOfRange { servo, value } => write!(
                f,
                "servo{servo}.rate_us_rad {} is outside {}..{} us/rad",
                Fixed(value, 3),
                Fixed(MIN_RATE_US_PER_RAD, 3),
                Fixed(MAX_RATE_US_PER_RAD, 3)
            ),
            ServoError::HomeOutsideLimits {
                servo,
                home_us,
                min_us,
                max_us,
            } => write!(
                f,
                "servo{servo}.trim_us {} us must lie within servo{servo}.min_us..max_us = {}..{} us",
                Fixed(home_us, 2),
                Fixed(min_us, 2),
                Fixed(max_us, 2)
            ),
        }
    }
}

/// The message for a refused geometry, in the names `set` uses.
struct GeometryMessage<'a>(&'a GeometryError);

impl Display for GeometryMessage<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match *self.0 {
            GeometryError::NonFiniteLeg { leg } => {
                write!(f, "leg {leg} has a coordinate that is not a finite number")
            }
            GeometryError::BadLength { which, value_mm } => {
                let name = match which {
                    Length::Arm => "arm_mm",
                    Length::Rod => "rod_mm",
                    Length::BaseRadius => "base_radius_mm",
                    Length::PlatformRadius => "platform_radius_mm",
                };
                write!(f, "{name} must be a positive length, not {value_mm}")
            }
            GeometryError::NoHomeHeight { leg } => write!(
                f,
                "leg {leg}: arm and rod cannot stand at right angles under the platform (rod_mm too short for the joint spacing)"
            ),
            GeometryError::LegsDisagree {
                leg,
                home_height_mm,
                leg1_home_height_mm,
            } => write!(
                f,
                "legs disagree on the home height: leg {leg} gives {} mm, leg 1 gives {} mm",
                Fixed(home_height_mm, 3),
                Fixed(leg1_home_height_mm, 3)
            ),
            GeometryError::HomeUnreachable { leg } => {
                write!(f, "leg {leg}: the arm cannot reach its rod at the home pose")
            }
        }
    }
}

/// A count of bytes: `1 byte`, `2 bytes`.
pub(super) struct Bytes(pub u32);

impl Display for Bytes {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self.0 {
            1 => f.write_str("1 byte"),
            n => write!(f, "{n} bytes"),
        }
    }
}
