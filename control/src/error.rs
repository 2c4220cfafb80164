//! [`Error`]: why a line is refused, with what is at fault (the field, leg, servo or limit) as
//! payload. Each layer has its own error type and this one gathers them: the line itself
//! ([`Spoiled`]), its words ([`ParseError`]), a setting ([`SettingError`]), the kinematics
//! ([`IkError`]), the motion and the flash ([`SaveError`]). How each is worded, and its
//! `error:<code>`, is [`crate::report`]'s.

use kinematics_core::ik::IkError;

use crate::command::ParseError;
use crate::protocol::Spoiled;
use crate::safety::Estop;
use crate::settings::SettingError;
use crate::store::SaveError;

/// Why a line is refused. Nothing changed; the platform holds its pose.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// The line was too long, held a byte that is not printable ASCII, or lost bytes in the
    /// receive queue.
    Spoiled(Spoiled),
    /// The line is not a command.
    Parse(ParseError),
    /// A setting value, or the settings it would make, is refused.
    Setting(SettingError),
    /// The target pose cannot be driven.
    Pose(IkError),
    /// The straight path to the target leaves the workspace or a servo limit.
    PathBlocked {
        /// How far along the path the first failing pose is, percent.
        percent: f32,
        /// Why that pose fails.
        cause: IkError,
    },
    /// With the new settings the pose being held could not be driven.
    PoseConflict {
        /// Why the held pose fails.
        cause: IkError,
    },
    /// Not possible while the platform moves.
    Busy,
    /// The emergency stop is on: no motion until its input is closed and `reset` is sent.
    Estop(Estop),
    /// The settings could not be written to flash (the save before is kept).
    SaveFailed(SaveError),
    /// A line came before the reply to the one before (only where the board feeds bytes while
    /// the controller is busy, which the firmware never does).
    Pending,
}

impl From<Spoiled> for Error {
    fn from(e: Spoiled) -> Error {
        Error::Spoiled(e)
    }
}

/// A parse error of the line itself or of a setting value becomes that kind of error, so the
/// same refusal always has the same form.
impl From<ParseError> for Error {
    fn from(e: ParseError) -> Error {
        match e {
            ParseError::Spoiled(s) => Error::Spoiled(s),
            ParseError::Setting(s) => Error::Setting(s),
            other => Error::Parse(other),
        }
    }
}

impl From<SettingError> for Error {
    fn from(e: SettingError) -> Error {
        Error::Setting(e)
    }
}

impl From<IkError> for Error {
    fn from(e: IkError) -> Error {
        Error::Pose(e)
    }
}
