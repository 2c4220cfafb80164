//! Everything the user sees: final replies, error codes, data lines, notices, help.
//!
//! # Output conventions
//!
//! - Every output line ends with CR LF.
//! - Every completed, non-empty input line gets exactly one **final reply**, always the last
//!   line written for it:
//!   - `ok` - done (any data came before it, on `# ` lines);
//!   - `error:<code> <message>` - refused; nothing happened. `<code>` is one of the
//!     [`Code`]s below (lowercase words joined by `-`); the message names the field, leg,
//!     servo or limit involved.
//! - Every other line starts with `# `: data (`# key: value`), help text, the banner and
//!   notices about things that happened on their own (`# fault: ...`, `# link lost: ...`).
//!   A program can therefore read lines until one starts with `ok` or `error:`, and ignore
//!   or parse the `# ` lines before it.
//! - A blank line gets no reply (with echo on, just a fresh prompt).
//! - With echo on (the default, for terminals) typed characters are echoed, the line end is
//!   echoed as CR LF and a prompt `> ` follows every reply. `set echo off` turns off echo and
//!   prompt, for programs.
//!
//! Numbers: poses in mm and degrees with 3 decimals, arm angles in degrees with 3 decimals,
//! pulse widths in microseconds with 2 decimals.

use core::fmt::{self, Display, Formatter, Write};

use kinematics_core::geometry::{GeometryError, Length};
use kinematics_core::ik::IkError;
use kinematics_core::pose::Axis;
use kinematics_core::servo::{
    ServoError, ServoField, MAX_PULSE_US, MAX_RATE_US_PER_RAD, MIN_PULSE_US, MIN_RATE_US_PER_RAD,
};
use kinematics_core::{Geometry, Pose, LEGS};

use crate::protocol::MAX_LINE;
use crate::settings::{Kind, ServoParam, ServoSel, SettingId, SettingValue, Settings};
use kinematics_core::Direction;

/// Line end for everything written.
pub const EOL: &str = "\r\n";
/// Prompt written after each reply when echo is on.
pub const PROMPT: &str = "> ";

/// A short copy of a word the user typed, for error messages (longer words are cut, `...`).
pub type Word = heapless::String<24>;

/// Copies `text` into a [`Word`], cutting it with `...` if it does not fit.
pub fn word(text: &str) -> Word {
    let mut w = Word::new();
    if text.len() <= w.capacity() {
        // Fits: cannot fail.
        let _ = w.push_str(text);
    } else {
        let keep = w.capacity() - 3;
        // Input lines are ASCII, so byte slicing is on character boundaries; be safe anyway.
        let cut = (0..=keep)
            .rev()
            .find(|&i| text.is_char_boundary(i))
            .unwrap_or(0);
        let _ = w.push_str(&text[..cut]);
        let _ = w.push_str("...");
    }
    w
}

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
}

impl Code {
    /// Every code, for documentation checks.
    pub const ALL: [Code; 24] = [
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
        }
    }
}

impl Display for Code {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// What a number or value belongs to, for error messages.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Field {
    /// A pose coordinate.
    Axis(Axis),
    /// A setting.
    Setting(SettingId),
}

impl Display for Field {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Field::Axis(a) => f.write_str(a.name()),
            Field::Setting(s) => s.fmt(f),
        }
    }
}

/// Why a line is refused. Displays as the message after the code.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// See [`Code::LineTooLong`].
    LineTooLong,
    /// See [`Code::RxOverflow`].
    RxOverflow {
        /// Bytes lost.
        dropped: u32,
    },
    /// See [`Code::BadCharacter`].
    BadCharacter {
        /// The first offending byte.
        byte: u8,
    },
    /// See [`Code::UnknownCommand`].
    UnknownCommand {
        /// What was typed.
        word: Word,
    },
    /// See [`Code::MissingField`].
    MissingField {
        /// What is missing (a field name or `axis=value`).
        what: &'static str,
        /// How the command is used.
        usage: &'static str,
    },
    /// See [`Code::ExtraField`].
    ExtraField {
        /// The first word too many.
        word: Word,
        /// How the command is used.
        usage: &'static str,
    },
    /// See [`Code::BadNumber`].
    BadNumber {
        /// What the number was for.
        field: Field,
        /// What was typed.
        word: Word,
    },
    /// See [`Code::NotFinite`].
    NotFinite {
        /// What the number was for.
        field: Field,
        /// What was typed.
        word: Word,
    },
    /// See [`Code::NumberTooLarge`].
    NumberTooLarge {
        /// What the number was for.
        field: Field,
        /// What was typed.
        word: Word,
    },
    /// See [`Code::UnknownAxis`].
    UnknownAxis {
        /// What was typed.
        word: Word,
    },
    /// See [`Code::DuplicateAxis`].
    DuplicateAxis {
        /// The axis named twice.
        axis: Axis,
    },
    /// See [`Code::BadAssignment`].
    BadAssignment {
        /// What was typed.
        word: Word,
    },
    /// See [`Code::UnknownSetting`].
    UnknownSetting {
        /// What was typed.
        word: Word,
    },
    /// See [`Code::BadValue`].
    BadValue {
        /// The setting.
        setting: SettingId,
        /// What was typed.
        word: Word,
        /// What is accepted.
        expected: &'static str,
    },
    /// See [`Code::OutOfRange`].
    OutOfRange {
        /// The setting.
        setting: SettingId,
        /// The value given.
        value: f32,
        /// Smallest value accepted.
        min: f32,
        /// Largest value accepted.
        max: f32,
        /// Unit of the three numbers (may be empty).
        unit: &'static str,
        /// Whether 0 / `off` is also accepted.
        off_allowed: bool,
    },
    /// See [`Code::BadServoConfig`].
    BadServoConfig(ServoError),
    /// See [`Code::BadGeometry`].
    BadGeometry(GeometryError),
    /// A pose is refused by the IK ([`Code::Unreachable`], [`Code::ServoLimit`],
    /// [`Code::AngleTooLarge`], [`Code::PoseNotFinite`]).
    Pose(IkError),
    /// See [`Code::PathBlocked`].
    PathBlocked {
        /// How far along the path, 0..=100 %.
        percent: f32,
        /// Why the pose there is refused.
        cause: IkError,
    },
    /// See [`Code::PoseConflict`].
    PoseConflict {
        /// Why the current pose could not be held.
        cause: IkError,
    },
    /// See [`Code::Busy`].
    Busy,
}

impl Error {
    /// The code written after `error:`.
    pub fn code(&self) -> Code {
        match self {
            Error::LineTooLong => Code::LineTooLong,
            Error::RxOverflow { .. } => Code::RxOverflow,
            Error::BadCharacter { .. } => Code::BadCharacter,
            Error::UnknownCommand { .. } => Code::UnknownCommand,
            Error::MissingField { .. } => Code::MissingField,
            Error::ExtraField { .. } => Code::ExtraField,
            Error::BadNumber { .. } => Code::BadNumber,
            Error::NotFinite { .. } => Code::NotFinite,
            Error::NumberTooLarge { .. } => Code::NumberTooLarge,
            Error::UnknownAxis { .. } => Code::UnknownAxis,
            Error::DuplicateAxis { .. } => Code::DuplicateAxis,
            Error::BadAssignment { .. } => Code::BadAssignment,
            Error::UnknownSetting { .. } => Code::UnknownSetting,
            Error::BadValue { .. } => Code::BadValue,
            Error::OutOfRange { .. } => Code::OutOfRange,
            Error::BadServoConfig(_) => Code::BadServoConfig,
            Error::BadGeometry(_) => Code::BadGeometry,
            Error::Pose(e) => match e {
                IkError::NonFinite { .. } => Code::PoseNotFinite,
                IkError::AngleTooLarge { .. } => Code::AngleTooLarge,
                IkError::Unreachable { .. } => Code::Unreachable,
                IkError::ServoLimit { .. } => Code::ServoLimit,
            },
            Error::PathBlocked { .. } => Code::PathBlocked,
            Error::PoseConflict { .. } => Code::PoseConflict,
            Error::Busy => Code::Busy,
        }
    }
}

impl From<IkError> for Error {
    fn from(e: IkError) -> Error {
        Error::Pose(e)
    }
}

/// The message for an IK refusal (shared by direct, path and conflict errors).
struct IkMessage<'a>(&'a IkError);

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

impl Display for Error {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Error::LineTooLong => write!(
                f,
                "line longer than {MAX_LINE} characters; it was discarded"
            ),
            Error::RxOverflow { dropped } => write!(
                f,
                "receive queue overflowed, {dropped} bytes lost; the line was discarded (wait for each reply before sending more)"
            ),
            Error::BadCharacter { byte } => write!(
                f,
                "byte 0x{byte:02X} is not printable ASCII; the line was discarded"
            ),
            Error::UnknownCommand { word } => {
                write!(f, "'{word}' is not a command; type help")
            }
            Error::MissingField { what, usage } => {
                write!(f, "missing {what}; usage: {usage}")
            }
            Error::ExtraField { word, usage } => {
                write!(f, "unexpected '{word}'; usage: {usage}")
            }
            Error::BadNumber { field, word } => {
                write!(f, "{field}: '{word}' is not a decimal number")
            }
            Error::NotFinite { field, word } => {
                write!(f, "{field}: '{word}' is not a finite number")
            }
            Error::NumberTooLarge { field, word } => {
                write!(f, "{field}: '{word}' is too large")
            }
            Error::UnknownAxis { word } => write!(
                f,
                "'{word}' is not an axis; axes are x y z roll pitch yaw"
            ),
            Error::DuplicateAxis { axis } => write!(f, "{} is given twice", axis.name()),
            Error::BadAssignment { word } => write!(
                f,
                "'{word}' should be axis=value, for example z=10"
            ),
            Error::UnknownSetting { word } => {
                write!(f, "'{word}' is not a setting; type config for the list")
            }
            Error::BadValue {
                setting,
                word,
                expected,
            } => write!(f, "{setting}: '{word}' is not {expected}"),
            Error::OutOfRange {
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
            Error::BadServoConfig(e) => write!(f, "{}; nothing changed", ServoMessage(e)),
            Error::BadGeometry(e) => write!(f, "{}; nothing changed", GeometryMessage(e)),
            Error::Pose(e) => IkMessage(e).fmt(f),
            Error::PathBlocked { percent, cause } => write!(
                f,
                "the straight path from the current pose is blocked {}% of the way: {}; nothing moved",
                Fixed(*percent, 1),
                IkMessage(cause)
            ),
            Error::PoseConflict { cause } => write!(
                f,
                "with that setting the current pose could not be held: {}; send home first",
                IkMessage(cause)
            ),
            Error::Busy => f.write_str("the platform is moving; wait for it or send stop first"),
        }
    }
}

/// A number with a fixed count of decimals, never shown as `-0.000`.
#[derive(Debug, Clone, Copy)]
pub struct Fixed(pub f32, pub usize);

impl Display for Fixed {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let Fixed(value, decimals) = *self;
        // Values that round to zero print as an unsigned zero.
        const HALF_STEP: [f32; 7] = [0.5, 0.05, 5e-3, 5e-4, 5e-5, 5e-6, 5e-7];
        let half_step = HALF_STEP.get(decimals).copied().unwrap_or(0.0);
        let value = if value.abs() < half_step { 0.0 } else { value };
        write!(f, "{value:.decimals$}")
    }
}

/// Writes `ok` (the success reply).
pub fn write_ok(out: &mut impl Write) {
    let _ = write!(out, "ok{EOL}");
}

/// Writes `error:<code> <message>` (the failure reply).
pub fn write_error(out: &mut impl Write, error: &Error) {
    let _ = write!(out, "error:{} {}{EOL}", error.code(), error);
}

/// Writes one data line: `# ` + the text + line end.
fn line(out: &mut impl Write, args: fmt::Arguments<'_>) {
    let _ = write!(out, "# {args}{EOL}");
}

/// Six values in servo order with a fixed number of decimals.
struct Six<'a>(&'a [f32; LEGS], usize);

impl Display for Six<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        for (i, v) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_char(' ')?;
            }
            Fixed(*v, self.1).fmt(f)?;
        }
        Ok(())
    }
}

/// A pose in user units: `x=.. y=.. z=.. roll=.. pitch=.. yaw=..` (mm, degrees, 3 decimals).
pub struct PoseText<'a>(pub &'a Pose);

impl Display for PoseText<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        for (i, axis) in Axis::ALL.into_iter().enumerate() {
            let v = self.0.get(axis);
            let v = if axis.is_angle() { v.to_degrees() } else { v };
            if i > 0 {
                f.write_char(' ')?;
            }
            write!(f, "{}={}", axis.name(), Fixed(v, 3))?;
        }
        Ok(())
    }
}

/// Arm angles in degrees.
fn degrees(arm_rad: &[f32; LEGS]) -> [f32; LEGS] {
    arm_rad.map(f32::to_degrees)
}

/// Firmware name and version for the banner.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The greeting written at start-up.
pub fn write_banner(out: &mut impl Write) {
    line(
        out,
        format_args!("hexapod control {VERSION}: poses in mm and degrees; type help"),
    );
}

/// How `pose` is used.
pub const USAGE_POSE: &str = "pose <x> <y> <z> <roll> <pitch> <yaw>";
/// How `check` is used.
pub const USAGE_CHECK: &str = "check <x> <y> <z> <roll> <pitch> <yaw>";
/// How `move` is used.
pub const USAGE_MOVE: &str = "move <axis>=<value> ... (axes x y z roll pitch yaw)";
/// How `nudge` is used.
pub const USAGE_NUDGE: &str = "nudge <axis>=<delta> ... (axes x y z roll pitch yaw)";
/// How `set` is used.
pub const USAGE_SET: &str = "set <name> <value> (names as listed by config)";

/// The command list for `help`.
pub const HELP: &[&str] = &[
    "commands (case does not matter; mm and degrees; each line ends with ok or error:<code>):",
    "  pose <x> <y> <z> <roll> <pitch> <yaw>  move to this pose (absolute)",
    "  move <axis>=<value> ...                move the named axes to these values (absolute)",
    "  nudge <axis>=<delta> ...               move the named axes by these amounts (relative)",
    "  check <x> <y> <z> <roll> <pitch> <yaw> would pose accept this? pulses and duration; nothing moves",
    "  home                                   move back to the home pose",
    "  stop                                   freeze where it is now",
    "  status (or ?)                          pose, target, motion, arm angles, pulse widths",
    "  geometry                               the active geometry",
    "  config                                 list the settings",
    "  set <name> <value>                     change a setting (names as in config)",
    "  defaults                               restore the default settings (except baud and echo)",
    "  help                                   this list",
    "axes: x y z (mm, z from the home height) roll pitch yaw (degrees, applied yaw-pitch-roll)",
    "moves run in a straight line at speed_mm_s / speed_deg_s (0 or off: jump)",
    "servo settings: servo<1-6>.<trim_us|rate_us_rad|dir|min_us|max_us>, servos.<...> sets all six",
    "editing: backspace erases, ctrl-u erases the line, ctrl-c abandons it; set echo off for programs",
];

/// Writes the help text.
pub fn write_help(out: &mut impl Write) {
    for text in HELP {
        line(out, format_args!("{text}"));
    }
}

/// What the motion is doing, for `status`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MotionReport {
    /// Standing still.
    Idle,
    /// Moving to the target.
    Moving {
        /// Seconds done.
        elapsed_s: f32,
        /// Seconds in total.
        duration_s: f32,
    },
    /// Returning home because no command arrived within the link timeout.
    ReturningHome {
        /// Seconds done.
        elapsed_s: f32,
        /// Seconds in total.
        duration_s: f32,
    },
}

/// Something that went wrong on its own (not in reply to a line).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fault {
    /// The IK failed on a frame: the platform holds the last good pose.
    IkFailed {
        /// Why.
        cause: IkError,
        /// Where it stopped.
        held: Pose,
    },
    /// The link timed out but the way home is blocked: the platform holds its pose.
    HomeBlocked {
        /// Why.
        cause: IkError,
    },
}

/// A line written on its own initiative (see [`crate::Controller::write_notices`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Notice {
    /// A fault happened.
    Fault(Fault),
    /// No command within the link timeout: returning home.
    LinkLost {
        /// The timeout, s.
        timeout_s: f32,
    },
    /// The receive queue overflowed (the line being received will be refused).
    RxOverflow {
        /// Bytes lost.
        dropped: u32,
    },
    /// The settings given at start-up were invalid; the defaults are used.
    SettingsRejected(Error),
}

impl Display for Fault {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Fault::IkFailed { cause, held } => write!(
                f,
                "motion stopped: {}; holding {}",
                IkMessage(cause),
                PoseText(held)
            ),
            Fault::HomeBlocked { cause } => write!(
                f,
                "link lost but the way home is blocked: {}; holding",
                IkMessage(cause)
            ),
        }
    }
}

/// Writes a notice line.
pub fn write_notice(out: &mut impl Write, notice: &Notice) {
    match notice {
        Notice::Fault(fault) => line(out, format_args!("fault: {fault}")),
        Notice::LinkLost { timeout_s } => line(
            out,
            format_args!("link lost: no command for {timeout_s} s; returning home"),
        ),
        Notice::RxOverflow { dropped } => line(
            out,
            format_args!("warning: receive queue overflowed, {dropped} bytes lost"),
        ),
        Notice::SettingsRejected(e) => line(
            out,
            format_args!(
                "warning: stored settings refused (error:{} {e}); using defaults",
                e.code()
            ),
        ),
    }
}

/// Everything `status` shows.
#[derive(Debug, Clone, Copy)]
pub struct StatusReport<'a> {
    /// What the motion is doing.
    pub motion: MotionReport,
    /// The pose commanded on the last frame.
    pub pose: &'a Pose,
    /// Where it is going.
    pub target: &'a Pose,
    /// Arm angles of the last frame, rad.
    pub arm_rad: &'a [f32; LEGS],
    /// Pulse widths of the last frame, us.
    pub pulse_us: &'a [f32; LEGS],
    /// The last fault, until the next accepted move.
    pub fault: Option<&'a Fault>,
}

/// Writes the `status` data lines.
pub fn write_status(out: &mut impl Write, s: &StatusReport<'_>) {
    match s.motion {
        MotionReport::Idle => line(out, format_args!("state: idle")),
        MotionReport::Moving {
            elapsed_s,
            duration_s,
        } => line(
            out,
            format_args!(
                "state: moving {} of {} s",
                Fixed(elapsed_s, 3),
                Fixed(duration_s, 3)
            ),
        ),
        MotionReport::ReturningHome {
            elapsed_s,
            duration_s,
        } => line(
            out,
            format_args!(
                "state: returning home (link lost) {} of {} s",
                Fixed(elapsed_s, 3),
                Fixed(duration_s, 3)
            ),
        ),
    }
    line(out, format_args!("pose: {}", PoseText(s.pose)));
    line(out, format_args!("target: {}", PoseText(s.target)));
    line(
        out,
        format_args!("arm_deg: {}", Six(&degrees(s.arm_rad), 3)),
    );
    line(out, format_args!("pulse_us: {}", Six(s.pulse_us, 2)));
    if let Some(fault) = s.fault {
        line(out, format_args!("fault: {fault}"));
    }
}

/// Writes the `check` data lines for an acceptable pose.
pub fn write_check(
    out: &mut impl Write,
    arm_rad: &[f32; LEGS],
    pulse_us: &[f32; LEGS],
    duration_s: f32,
) {
    line(out, format_args!("arm_deg: {}", Six(&degrees(arm_rad), 3)));
    line(out, format_args!("pulse_us: {}", Six(pulse_us, 2)));
    line(out, format_args!("duration_s: {}", Fixed(duration_s, 3)));
}

/// A vector as `(x, y, z)` with 3 decimals.
struct Vector<'a>(&'a kinematics_core::Vec3);

impl Display for Vector<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "({}, {}, {})",
            Fixed(self.0.x, 3),
            Fixed(self.0.y, 3),
            Fixed(self.0.z, 3)
        )
    }
}

/// Writes the `geometry` data lines.
pub fn write_geometry(out: &mut impl Write, settings: &Settings, geometry: &Geometry) {
    let l = &settings.layout;
    line(
        out,
        format_args!(
            "layout: paired base_radius_mm={} base_half_angle_deg={} platform_radius_mm={} platform_half_angle_deg={}",
            Fixed(l.base_radius_mm, 3),
            Fixed(l.base_half_angle_deg, 3),
            Fixed(l.platform_radius_mm, 3),
            Fixed(l.platform_half_angle_deg, 3)
        ),
    );
    line(
        out,
        format_args!("arm_mm (a): {}", Fixed(geometry.arm_mm(), 3)),
    );
    line(
        out,
        format_args!("rod_mm (s): {}", Fixed(geometry.rod_mm(), 3)),
    );
    line(
        out,
        format_args!(
            "home_height_mm (h0): {}",
            Fixed(geometry.home_height_mm(), 3)
        ),
    );
    for (i, leg) in geometry.legs().iter().enumerate() {
        line(
            out,
            format_args!(
                "leg {}: b_mm={} p_mm={} beta_deg={} alpha0_deg={}",
                i + 1,
                Vector(&leg.base_mm),
                Vector(&leg.platform_mm),
                Fixed(leg.beta_rad.to_degrees(), 3),
                Fixed(geometry.alpha0_rad(i).to_degrees(), 3)
            ),
        );
    }
}

/// Writes the `config` data lines: `# name: value`, servos one line each.
pub fn write_config(out: &mut impl Write, settings: &Settings) {
    for id in SettingId::GLOBAL {
        line(
            out,
            format_args!("{id}: {}", ValueText(id, settings.get(id))),
        );
    }
    for servo in 1..=LEGS as u8 {
        line(out, format_args!("{}", ServoLine(settings, servo)));
    }
}

/// `servoN: trim_us=.. rate_us_rad=.. dir=.. min_us=.. max_us=..`
struct ServoLine<'a>(&'a Settings, u8);

impl Display for ServoLine<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let ServoLine(settings, servo) = *self;
        write!(f, "servo{servo}:")?;
        for param in ServoParam::ALL {
            let id = SettingId::Servo(ServoSel::One(servo), param);
            write!(f, " {}={}", param.name(), ValueText(id, settings.get(id)))?;
        }
        Ok(())
    }
}

/// A setting's value as `config` shows it and `set` accepts it.
pub struct ValueText(pub SettingId, pub SettingValue);

impl Display for ValueText {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match (self.0.kind(), self.1) {
            (_, SettingValue::Flag(on)) => f.write_str(if on { "on" } else { "off" }),
            (_, SettingValue::Dir(Direction::Normal)) => f.write_str("normal"),
            (_, SettingValue::Dir(Direction::Reversed)) => f.write_str("reversed"),
            (_, SettingValue::Whole(v)) => write!(f, "{v}"),
            (
                Kind::Number {
                    off_allowed: true, ..
                },
                SettingValue::Number(0.0),
            ) => f.write_str("off"),
            (Kind::Number { decimals, .. }, SettingValue::Number(v)) => {
                Fixed(v, usize::from(decimals)).fmt(f)
            }
            (_, SettingValue::Number(v)) => write!(f, "{v}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::LayoutParam;

    /// One error of every kind.
    pub(crate) fn one_of_each() -> std::vec::Vec<Error> {
        let setting = SettingId::FrameHz;
        std::vec![
            Error::LineTooLong,
            Error::RxOverflow { dropped: 3 },
            Error::BadCharacter { byte: 0xC2 },
            Error::UnknownCommand { word: word("fly") },
            Error::MissingField {
                what: "yaw",
                usage: "pose <x> <y> <z> <roll> <pitch> <yaw>",
            },
            Error::ExtraField {
                word: word("7"),
                usage: "home",
            },
            Error::BadNumber {
                field: Field::Axis(Axis::X),
                word: word("abc"),
            },
            Error::NotFinite {
                field: Field::Axis(Axis::Roll),
                word: word("nan"),
            },
            Error::NumberTooLarge {
                field: Field::Axis(Axis::Z),
                word: word("1e39"),
            },
            Error::UnknownAxis { word: word("w") },
            Error::DuplicateAxis { axis: Axis::Z },
            Error::BadAssignment { word: word("z") },
            Error::UnknownSetting {
                word: word("colour")
            },
            Error::BadValue {
                setting: SettingId::Echo,
                word: word("maybe"),
                expected: "on or off",
            },
            Error::OutOfRange {
                setting,
                value: 20.0,
                min: 50.0,
                max: 333.0,
                unit: "Hz",
                off_allowed: false,
            },
            Error::BadServoConfig(ServoError::PulseOutOfRange {
                servo: 2,
                field: ServoField::Max,
                value_us: 3000.0,
            }),
            Error::BadGeometry(GeometryError::NoHomeHeight { leg: 1 }),
            Error::Pose(IkError::Unreachable { leg: 3 }),
            Error::Pose(IkError::ServoLimit {
                servo: 2,
                pulse_us: 1950.0,
                min_us: 1100.0,
                max_us: 1900.0,
            }),
            Error::Pose(IkError::AngleTooLarge {
                axis: Axis::Pitch,
                value_rad: 4.0,
            }),
            Error::Pose(IkError::NonFinite { axis: Axis::Y }),
            Error::PathBlocked {
                percent: 42.0,
                cause: IkError::Unreachable { leg: 5 },
            },
            Error::PoseConflict {
                cause: IkError::ServoLimit {
                    servo: 1,
                    pulse_us: 1000.0,
                    min_us: 1100.0,
                    max_us: 1900.0,
                },
            },
            Error::Busy,
        ]
    }

    #[test]
    fn every_error_code_is_distinct_and_every_code_is_used() {
        let codes: std::vec::Vec<&str> = Code::ALL.iter().map(|c| c.as_str()).collect();
        let mut sorted = codes.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), codes.len(), "duplicate code in {codes:?}");
        let used: std::vec::Vec<Code> = one_of_each().iter().map(Error::code).collect();
        for code in Code::ALL {
            assert!(used.contains(&code), "no example error for {code}");
        }
        for code in codes {
            assert!(
                code.bytes().all(|b| b.is_ascii_lowercase() || b == b'-'),
                "{code}"
            );
        }
    }

    #[test]
    fn error_replies_are_one_line_with_code_and_message() {
        for e in one_of_each() {
            let mut s = std::string::String::new();
            write_error(&mut s, &e);
            let expected_start = std::format!("error:{} ", e.code());
            assert!(s.starts_with(&expected_start), "{s}");
            assert!(s.ends_with("\r\n") && s.matches('\n').count() == 1, "{s:?}");
            assert!(
                s.len() > expected_start.len() + 10,
                "message too short: {s}"
            );
            assert!(s.is_ascii(), "{s}");
        }
    }

    #[test]
    fn messages_name_what_is_wrong() {
        let text = |e: Error| std::format!("{e}");
        assert!(text(Error::Pose(IkError::Unreachable { leg: 3 })).contains("leg 3"));
        let limit = text(Error::Pose(IkError::ServoLimit {
            servo: 2,
            pulse_us: 1950.123,
            min_us: 1100.0,
            max_us: 1900.0,
        }));
        assert!(
            limit.contains("servo 2") && limit.contains("1950.12") && limit.contains("1900.00")
        );
        let field = text(Error::NotFinite {
            field: Field::Setting(SettingId::Servo(ServoSel::One(4), ServoParam::TrimUs)),
            word: word("inf"),
        });
        assert!(
            field.contains("servo4.trim_us") && field.contains("'inf'"),
            "{field}"
        );
        let layout = text(Error::BadNumber {
            field: Field::Setting(SettingId::Layout(LayoutParam::RodMm)),
            word: word("x"),
        });
        assert!(layout.starts_with("rod_mm:"), "{layout}");
    }

    #[test]
    fn long_words_are_cut() {
        let w = word("abcdefghijklmnopqrstuvwxyz0123456789");
        assert_eq!(w.as_str(), "abcdefghijklmnopqrstu...");
        assert_eq!(word("short").as_str(), "short");
    }

    #[test]
    fn fixed_never_prints_negative_zero() {
        assert_eq!(std::format!("{}", Fixed(-0.0001, 3)), "0.000");
        assert_eq!(std::format!("{}", Fixed(-0.0, 2)), "0.00");
        assert_eq!(std::format!("{}", Fixed(-0.0006, 3)), "-0.001");
        assert_eq!(std::format!("{}", Fixed(1500.0, 2)), "1500.00");
    }

    #[test]
    fn pose_text_is_in_user_units() {
        let p = Pose::from_degrees(1.0, -2.5, 3.0, 10.0, 0.0, -45.0);
        assert_eq!(
            std::format!("{}", PoseText(&p)),
            "x=1.000 y=-2.500 z=3.000 roll=10.000 pitch=0.000 yaw=-45.000"
        );
    }
}
