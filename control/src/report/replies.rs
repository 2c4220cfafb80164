//! The reply writers: final replies, the data lines of `status`, `check`, `geometry`,
//! `config` and `help`, the banner, notices, and the echo of typed characters.

use core::fmt::{self, Display, Formatter, Write};

use kinematics_core::ik::{IkError, Solver};
use kinematics_core::workspace::{Limit, Reach, Sense};
use kinematics_core::{KinematicsError, Pose, LEGS};

use super::errors::{Bytes, IkMessage, KinematicsMessage, PoseMessage};
use super::format::{degrees, Fixed, PoseText, Six, ValueText, Vector};
use crate::error::{Error, PoseError};
use crate::payload::TorqueError;
use crate::protocol::Feed;
use crate::record::{DecodeError, FORMAT_VERSION, FORMAT_VERSION_NO_BAUD};
use crate::safety::{Estop, EstopAction};
use crate::settings::{LinkSettings, ServoParam, ServoSel, SettingId, Settings};

/// Line end for everything written.
pub const EOL: &str = "\r\n";
/// Prompt written after each reply when echo is on.
pub const PROMPT: &str = "> ";
/// What the echo writes to erase one character on a terminal.
const ERASE: &str = "\x08 \x08";

/// Firmware name and version for the banner.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The manufacturer the board names to a USB host (`lsusb`, Device Manager, the
/// `/dev/serial/by-id/` name).
pub const USB_MANUFACTURER: &str = "hexapod-fw";
/// The product the board names to a USB host, beside [`USB_MANUFACTURER`].
pub const USB_PRODUCT: &str = "hexapod control";
/// The board's USB vendor ID: the pid.codes test vendor, for open-source devices in
/// development, until the project has a product ID of its own (pid.codes gives them to open
/// hardware for free). A CDC ACM device needs no driver on Linux, macOS or Windows 10 and
/// later, whatever its IDs. The host tool finds boards by it and [`USB_PID`] (`hexapod boards`).
pub const USB_VID: u16 = 0x1209;
/// The board's USB product ID, beside [`USB_VID`]: pid.codes' test product.
pub const USB_PID: u16 = 0x0001;

/// Writes `ok` (the success reply).
pub fn write_ok(out: &mut impl Write) {
    let _ = write!(out, "ok{EOL}");
}

/// The whole reply line of a refusal, `error:<code> <message>` without the line end: the one
/// way a refusal is worded, by the firmware and by host programs alike.
pub fn refusal(error: &Error) -> impl Display + '_ {
    struct Refusal<'a>(&'a Error);
    impl Display for Refusal<'_> {
        fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
            write!(f, "error:{} {}", self.0.code(), self.0)
        }
    }
    Refusal(error)
}

/// Why the kinematics give no answer at a pose, as host programs word it where the board has no
/// command of its own (the servo torques of carrying a payload along a trajectory): the IK's
/// refusal exactly as the board writes it ([`refusal`], with its code); a servo arm at dead
/// centre, a singular pose and gimbal lock said for a platform carrying a load; anything the
/// servo platform's kinematics never give there in the kinematics' own line.
pub fn kinematics_refusal(error: &KinematicsError) -> impl Display + '_ {
    struct Words<'a>(&'a KinematicsError);
    impl Display for Words<'_> {
        fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
            match *self.0 {
                KinematicsError::Ik(e) => refusal(&Error::from(e)).fmt(f),
                KinematicsError::DeadCentre { leg } => {
                    write!(
                        f,
                        "leg {leg}'s arm is at dead centre (it cannot move its rod)"
                    )
                }
                KinematicsError::Singular { .. } => {
                    f.write_str("the platform is at a singular pose (it cannot hold a load there)")
                }
                KinematicsError::GimbalLock { .. } => {
                    f.write_str("pitch at +-90 degrees: roll and yaw rates are undefined")
                }
                ref other => other.fmt(f),
            }
        }
    }
    Words(error)
}

/// Writes `error:<code> <message>` (the failure reply).
pub fn write_error(out: &mut impl Write, error: &Error) {
    let _ = write!(out, "{}{EOL}", refusal(error));
}

/// Writes one data line: `# ` + the text + line end.
fn line(out: &mut impl Write, args: fmt::Arguments<'_>) {
    let _ = write!(out, "# {args}{EOL}");
}

/// Writes the prompt.
pub fn write_prompt(out: &mut impl Write) {
    let _ = out.write_str(PROMPT);
}

/// Echoes what one received byte did to the line being typed (for a link with echo on).
pub fn write_echo(out: &mut impl Write, feed: Feed) {
    let _ = match feed {
        Feed::Added(b) => out.write_char(char::from(b)),
        Feed::Erased => out.write_str(ERASE),
        Feed::ErasedLine(n) => (0..n).try_for_each(|_| out.write_str(ERASE)),
        Feed::Cancelled => out.write_str("^C").and_then(|()| out.write_str(EOL)),
        // Bell: the rest of the line is ignored.
        Feed::Overflowed => out.write_char('\x07'),
        Feed::Empty | Feed::Line | Feed::Spoiled(_) => out.write_str(EOL),
        Feed::Nothing | Feed::Frame(_) | Feed::DamagedFrame => Ok(()),
    };
}

/// Echoes characters added to the line one after the other (printable ASCII: what
/// [`write_echo`] writes for each one's [`Feed::Added`]).
pub fn write_echo_chars(out: &mut impl Write, chars: &[u8]) {
    if let Ok(text) = core::str::from_utf8(chars) {
        let _ = out.write_str(text);
    }
}

/// Echoes a whole line whose characters were held back as they came (it began with a digit,
/// so it might have been a text frame), with its line end.
pub fn write_held_echo(out: &mut impl Write, line: &str) {
    let _ = out.write_str(line).and_then(|()| out.write_str(EOL));
}

/// The greeting written at start-up; with the board's id ([`board_id_digits`]) when the
/// board has one (the real board: its flash chip's unique ID, also its USB serial number).
pub fn write_banner(out: &mut impl Write, board_id: Option<u64>) {
    match board_id {
        Some(id) => line(
            out,
            format_args!(
                "hexapod control {VERSION} on board {}: poses in mm and degrees; type help",
                BoardId(id)
            ),
        ),
        None => line(
            out,
            format_args!("hexapod control {VERSION}: poses in mm and degrees; type help"),
        ),
    }
}

/// A board's id as it is shown: its 16 hexadecimal digits, upper case, most significant
/// first (the flash chip's unique ID bytes in the order the chip sends them). The same text
/// is the USB serial number (so `/dev/serial/by-id/usb-hexapod-fw_hexapod_control_<id>-if00`
/// names the board) and is in the banner.
pub fn board_id_digits(id: u64) -> [u8; 16] {
    const DIGITS: &[u8; 16] = b"0123456789ABCDEF";
    let mut text = [0; 16];
    for (i, digit) in text.iter_mut().enumerate() {
        *digit = DIGITS[((id >> (60 - 4 * i)) & 0xF) as usize];
    }
    text
}

/// [`board_id_digits`] for `format_args!`.
struct BoardId(u64);

impl Display for BoardId {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        for &digit in &board_id_digits(self.0) {
            f.write_char(char::from(digit))?;
        }
        Ok(())
    }
}

/// The command list for `help`.
pub const HELP: &[&str] = &[
    "commands (case does not matter; mm and degrees; each line ends with ok or error:<code>):",
    "  pose <x> <y> <z> <roll> <pitch> <yaw>  move to this pose (absolute)",
    "  move <axis>=<value> ...                move the named axes to these values (absolute)",
    "  nudge <axis>=<delta> ...               move the named axes by these amounts (relative)",
    "  check <x> <y> <z> <roll> <pitch> <yaw> would pose accept this? pulses and duration; nothing moves",
    "  limits                                 how far each axis reaches from here, both ways, and why",
    "  home                                   move back to the home pose",
    "  stop                                   freeze where it is now (also ends a stream)",
    "  servo <1-6> <us>                       drive one servo to a pulse (the others hold), e.g. to calibrate",
    "  reset                                  clear the emergency stop once its input is closed",
    "  status (or ?)                          pose, target, motion, arm angles, pulse widths",
    "  pulses                                 the six pulse widths on the pins now (one line)",
    "  geometry                               the active geometry",
    "  config                                 list the settings",
    "  set <name> <value>                     change a setting (names as in config)",
    "  defaults                               restore the default settings (except baud and echo)",
    "  save                                   keep the settings in flash for the next power-up",
    "  help                                   this list",
    "axes: x y z (mm, z from the home height) roll pitch yaw (degrees, applied yaw-pitch-roll)",
    "moves run in a straight line at speed_mm_s / speed_deg_s (0 or off: jump), accel_* ramps",
    "stream frames (binary A5 5A ... 0D 0A, or text 127,127,127,127,127,127X) set the target;",
    "  each axis follows at speed_* / accel_*; unreachable targets are clamped (see stream.*)",
    "servo settings: servo<1-6>.<trim_us|rate_us_rad|dir|min_us|max_us|torque_kgcm>, servos.<...> sets all six",
    "payload_g and payload_com_*_mm: check and status show the holding torques (kgf cm)",
    "editing: backspace erases, ctrl-u erases the line, ctrl-c or ctrl-x abandons it; set echo off for programs",
];

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
    /// Going home because the emergency stop opened (`estop_action home`).
    EstopHome {
        /// Seconds done.
        elapsed_s: f32,
        /// Seconds in total.
        duration_s: f32,
    },
    /// Following stream frames.
    Streaming {
        /// Each axis follows within the speed and acceleration limits (not pass-through).
        tracking: bool,
    },
    /// A stream no frame has come for in a while (it has come to rest): holding its last
    /// pose; the next frame takes it up again.
    StreamIdle {
        /// Seconds since its last frame.
        quiet_s: f32,
    },
    /// Holding pulses set one servo at a time (`servo`).
    Direct,
}

/// Stream frames counted since start-up, for `status`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StreamCounts {
    /// Whole frames received (with counts that fit).
    pub frames: u32,
    /// Frames whose pose became the target (the others were superseded by a newer one before
    /// they were applied: the newest frame wins).
    pub applied: u32,
    /// Frames dropped as damaged (wrong length or trailer, garbage, counts that do not fit, a
    /// step larger than the step guard allows).
    pub damaged: u32,
    /// Targets or steps moved back inside the workspace.
    pub clamped: u32,
    /// Frames refused because of the emergency stop.
    pub refused: u32,
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
    /// The link timed out (or the e-stop opened, to go home) but the way home is blocked: the
    /// platform holds its pose.
    HomeBlocked {
        /// Why.
        cause: PoseError,
    },
    /// The way home could not even be planned: the pulses set with `servo` correspond to no
    /// pose. The platform holds them.
    NoPose {
        /// Why there is no pose (the forward kinematics' error).
        cause: KinematicsError,
    },
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
                PoseMessage(cause)
            ),
            Fault::NoPose { cause } => write!(
                f,
                "cannot go home: the pulses set with servo correspond to no pose ({}); holding",
                KinematicsMessage(cause)
            ),
        }
    }
}

/// A line written on the firmware's own initiative, to every link
/// (see [`crate::Controller::write_notices`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Notice {
    /// A fault happened.
    Fault(Fault),
    /// No command within the link timeout: returning home.
    LinkLost {
        /// The timeout, s.
        timeout_s: f32,
    },
    /// Input was lost on its way in (the line it cuts will be refused when the board reaches
    /// the gap).
    InputLost {
        /// Bytes lost so far (more may follow until the board catches up).
        at_least: u32,
        /// The UART's hardware lost them (an overrun or a line error), not a receive queue.
        in_uart: bool,
    },
    /// More UART receive errors in the burst whose first loss was announced
    /// ([`Notice::InputLost`]): counted, not announced one by one.
    InputLostBurst {
        /// Losses after the first.
        losses: u32,
        /// Bytes they lost, at least.
        at_least: u32,
        /// Over how long, s (from the burst's start, or its last report, to its last loss).
        over_s: f32,
    },
    /// The settings given at start-up were invalid; the defaults are used.
    SettingsRejected(Error),
    /// The emergency-stop input opened.
    EstopOpened {
        /// What the platform does.
        action: EstopAction,
        /// A servo-power output is configured (it goes off).
        power_pin: bool,
    },
    /// The emergency-stop input closed again.
    EstopClosed,
    /// Power-up found no usable settings in flash (`None`: nothing was ever saved); the
    /// defaults are used.
    NoSavedSettings(Option<DecodeError>),
    /// Power-up loaded a saved copy of the settings, but the other copy cannot be used (it
    /// may have been the newer one: a save cut short, or damage).
    SavedCopyUnusable {
        /// The sequence number of the copy loaded.
        sequence: u32,
        /// Why the other cannot be used.
        why: DecodeError,
    },
}

/// Writes a notice line.
pub fn write_notice(out: &mut impl Write, notice: &Notice) {
    match notice {
        Notice::Fault(fault) => line(out, format_args!("fault: {fault}")),
        Notice::LinkLost { timeout_s } => line(
            out,
            format_args!("link lost: no command for {timeout_s} s; returning home"),
        ),
        Notice::InputLost {
            at_least,
            in_uart: false,
        } => line(
            out,
            format_args!(
                "warning: receive queue overflowed, input lost (at least {} so far)",
                Bytes(*at_least)
            ),
        ),
        Notice::InputLost {
            at_least,
            in_uart: true,
        } => line(
            out,
            format_args!(
                "warning: UART receive error, input lost (at least {})",
                Bytes(*at_least)
            ),
        ),
        Notice::InputLostBurst {
            losses,
            at_least,
            over_s,
        } => line(
            out,
            format_args!(
                "warning: UART receive errors went on: {losses} more, input lost (at least {}) in {} s",
                Bytes(*at_least),
                Fixed(*over_s, 2)
            ),
        ),
        Notice::SettingsRejected(e) => line(
            out,
            format_args!(
                "warning: stored settings refused (error:{} {e}); using defaults",
                e.code()
            ),
        ),
        Notice::EstopOpened { action, power_pin } => line(
            out,
            format_args!(
                "emergency stop: input open; {}{}; motion refused until the input is closed and reset is sent",
                match action {
                    EstopAction::Freeze => "platform frozen",
                    EstopAction::Home => "going home",
                },
                match (power_pin, action) {
                    (false, _) => "",
                    (true, EstopAction::Freeze) => ", servo power off",
                    (true, EstopAction::Home) => ", servo power off when home",
                }
            ),
        ),
        Notice::EstopClosed => line(
            out,
            format_args!("emergency stop: input closed; send reset to move again"),
        ),
        Notice::NoSavedSettings(None) => line(
            out,
            format_args!("warning: no settings saved in flash; using the defaults"),
        ),
        Notice::NoSavedSettings(Some(why)) => line(
            out,
            format_args!(
                "warning: the settings saved in flash cannot be used ({}); using the defaults",
                Unusable(why)
            ),
        ),
        Notice::SavedCopyUnusable { sequence, why } => line(
            out,
            format_args!(
                "warning: one of the two saved copies of the settings cannot be used ({}); \
                 loaded the other, save {sequence}: check config",
                Unusable(why)
            ),
        ),
    }
}

/// Why a record in flash cannot be used, in a user's words.
struct Unusable<'a>(&'a DecodeError);

impl Display for Unusable<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self.0 {
            DecodeError::UnsupportedVersion(v) => write!(
                f,
                "written in format version {v}; this firmware reads versions \
                 {FORMAT_VERSION_NO_BAUD} to {FORMAT_VERSION}"
            ),
            DecodeError::BadChecksum => f.write_str("damaged: checksum mismatch"),
            DecodeError::BadMagic | DecodeError::TooShort => {
                f.write_str("damaged: not a settings record")
            }
            DecodeError::BadLength(n) => write!(f, "damaged: payload length {n}"),
            DecodeError::BadField { offset } => write!(f, "damaged: byte {offset}"),
            DecodeError::Invalid(e) => {
                write!(f, "invalid: error:{} {e}", Error::from(e.clone()).code())
            }
        }
    }
}

/// How the running settings stand against those saved in flash (the last line of `config`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Saved {
    /// They are the ones saved.
    Same,
    /// They have changed since the last save.
    Differs,
    /// Nothing usable is saved.
    Nothing,
}

/// Everything `status` shows, as it was when the command ran.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StatusReport {
    /// What the motion is doing.
    pub motion: MotionReport,
    /// The pose commanded on the last frame.
    pub pose: Pose,
    /// Where it is going.
    pub target: Pose,
    /// Arm angles of the last frame, rad.
    pub arm_rad: [f32; LEGS],
    /// Pulse widths of the last frame, us.
    pub pulse_us: [f32; LEGS],
    /// The last fault, until the next accepted move.
    pub fault: Option<Fault>,
    /// Stream frames so far.
    pub stream: StreamCounts,
    /// The emergency stop.
    pub estop: Estop,
    /// The servo-power output is on.
    pub servo_power: bool,
    /// With pulses set by `servo`: the pose they correspond to (the forward kinematics), or
    /// why there is none. `None` otherwise (the pulses are the IK's for `pose`).
    pub pulse_pose: Option<Result<Pose, KinematicsError>>,
    /// With a payload: each servo's holding torque at the pose (kgf cm), or why it cannot be
    /// computed. `None` without a payload.
    pub torque_kgcm: Option<Result<[f32; LEGS], KinematicsError>>,
}

/// A reply of several data lines. It may be written a line at a time (the controller writes
/// one per slice of work, so a long listing never keeps the main loop long):
/// [`Listing::write_line`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Listing {
    /// `status`, from its snapshot.
    Status(StatusReport),
    /// `pulses`: the pulse widths the pins carry, us.
    Pulses([f32; LEGS]),
    /// `geometry`: the layout, the geometry and the IK's home arm angles.
    Geometry,
    /// `config`: the platform's settings, the asking link's, and how they stand against those
    /// saved in flash.
    Config(LinkSettings, Saved),
    /// `help`.
    Help,
    /// `check` of an acceptable pose: its arm angles (rad), pulses (us) and the move's
    /// duration (s).
    Check {
        /// Arm angles, rad.
        arm_rad: [f32; LEGS],
        /// Pulse widths, us.
        pulse_us: [f32; LEGS],
        /// With a payload, the holding torques there, kgf cm.
        torque_kgcm: Option<Result<[f32; LEGS], KinematicsError>>,
        /// How long the move would take, s.
        duration_s: f32,
    },
    /// `limits`: the reach along each axis-direction from `start`.
    Limits {
        /// Where the search started.
        start: Pose,
        /// The twelve reaches, x- first (see [`kinematics_core::workspace::axis_directions`]).
        reaches: [Reach<PoseError>; 12],
    },
}

impl Listing {
    /// Writes data line `index` (from 0); `false` if there is no such line (the listing is
    /// complete). `settings` and `solver` are the active ones.
    pub fn write_line(
        &self,
        index: usize,
        settings: &Settings,
        solver: &Solver,
        out: &mut impl Write,
    ) -> bool {
        match self {
            Listing::Status(report) => status_line(out, report, index),
            Listing::Pulses(pulse_us) => {
                if index > 0 {
                    return false;
                }
                line(out, format_args!("pulse_us: {}", Six(pulse_us, 2)));
                true
            }
            Listing::Geometry => geometry_line(out, settings, solver, index),
            Listing::Config(link, saved) => config_line(out, settings, link, *saved, index),
            Listing::Help => HELP.get(index).is_some_and(|text| {
                line(out, format_args!("{text}"));
                true
            }),
            Listing::Check {
                arm_rad,
                pulse_us,
                torque_kgcm,
                duration_s,
            } => {
                // The torque line is there only with a payload.
                let index = if torque_kgcm.is_none() && index >= 2 {
                    index + 1
                } else {
                    index
                };
                match (index, torque_kgcm) {
                    (0, _) => line(out, format_args!("arm_deg: {}", Six(&degrees(arm_rad), 3))),
                    (1, _) => line(out, format_args!("pulse_us: {}", Six(pulse_us, 2))),
                    (2, Some(torques)) => torque_line(out, torques),
                    (3, _) => line(out, format_args!("duration_s: {}", Fixed(*duration_s, 3))),
                    _ => return false,
                }
                true
            }
            Listing::Limits { start, reaches } => match reaches.get(index) {
                Some(reach) => {
                    line(out, format_args!("{}", ReachText(start, reach)));
                    true
                }
                None => false,
            },
        }
    }

    /// Writes every line at once.
    pub fn write(&self, settings: &Settings, solver: &Solver, out: &mut impl Write) {
        let mut index = 0;
        while self.write_line(index, settings, solver, out) {
            index += 1;
        }
    }
}

/// `torque_kgcm: ...` (six signed holding torques, kgf cm, 3 decimals) or why there are none.
fn torque_line(out: &mut impl Write, torques: &Result<[f32; LEGS], KinematicsError>) {
    match torques {
        Ok(t) => line(out, format_args!("torque_kgcm: {}", Six(t, 3))),
        Err(e) => line(
            out,
            format_args!("torque_kgcm: none ({})", KinematicsMessage(e)),
        ),
    }
}

/// One line of `limits`: `x-: 23.456 mm to x=-23.456 (servo 2 at max_us 1900.00 us)`.
struct ReachText<'a>(&'a Pose, &'a Reach<PoseError>);

impl Display for ReachText<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let ReachText(start, reach) = *self;
        let (scale, unit) = if reach.axis.is_angle() {
            (1.0f32.to_degrees(), "deg")
        } else {
            (1.0, "mm")
        };
        let sign = match reach.sense {
            Sense::Minus => '-',
            Sense::Plus => '+',
        };
        write!(
            f,
            "{}{sign}: {} {unit} to {}={} (",
            reach.axis.name(),
            Fixed(reach.distance * scale, 3),
            reach.axis.name(),
            Fixed(reach.extreme(start) * scale, 3),
        )?;
        match &reach.limit {
            Limit::Blocked(cause) => StopText(cause).fmt(f)?,
            Limit::Range => write!(
                f,
                "nothing stops it within {} {unit}",
                Fixed(reach.distance * scale, 0)
            )?,
            Limit::Start(cause) => write!(f, "the pose itself: {}", PoseMessage(cause))?,
        }
        f.write_str(")")
    }
}

/// What stops an excursion, in a few words.
struct StopText<'a>(&'a PoseError);

impl Display for StopText<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match *self.0 {
            PoseError::Ik(IkError::Unreachable { leg }) => {
                write!(f, "leg {leg} out of reach")
            }
            PoseError::Ik(IkError::ServoLimit {
                servo,
                pulse_us,
                min_us,
                max_us,
            }) => {
                let (name, limit) = if pulse_us > max_us {
                    ("max_us", max_us)
                } else {
                    ("min_us", min_us)
                };
                write!(f, "servo {servo} at {name} {} us", Fixed(limit, 2))
            }
            PoseError::Ik(IkError::AngleTooLarge { axis, .. }) => {
                write!(f, "{} at +-180 deg", axis.name())
            }
            PoseError::Ik(e @ IkError::NonFinite { .. }) => IkMessage(&e).fmt(f),
            PoseError::Torque(TorqueError::Over {
                servo, rated_kgcm, ..
            }) => write!(
                f,
                "servo {servo} at its torque rating {} kgf cm",
                Fixed(rated_kgcm, 2)
            ),
            PoseError::Torque(TorqueError::Unknown(ref e)) => {
                write!(f, "unbounded holding torques: {}", KinematicsMessage(e))
            }
        }
    }
}

/// The lines of `status`, in order; some only sometimes.
#[derive(Clone, Copy)]
enum StatusLine {
    State,
    Pose,
    Target,
    ArmDeg,
    PulseUs,
    PulsePose,
    Torque,
    Stream,
    Estop,
    ServoPower,
    Fault,
}

fn status_line(out: &mut impl Write, s: &StatusReport, index: usize) -> bool {
    use StatusLine as L;
    let lines = [
        L::State,
        L::Pose,
        L::Target,
        L::ArmDeg,
        L::PulseUs,
        L::PulsePose,
        L::Torque,
        L::Stream,
        L::Estop,
        L::ServoPower,
        L::Fault,
    ];
    let shown = |l: &&StatusLine| match l {
        L::PulsePose => s.pulse_pose.is_some(),
        L::Torque => s.torque_kgcm.is_some(),
        L::Fault => s.fault.is_some(),
        _ => true,
    };
    let Some(&which) = lines.iter().filter(shown).nth(index) else {
        return false;
    };
    match which {
        L::State => match s.motion {
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
            MotionReport::EstopHome {
                elapsed_s,
                duration_s,
            } => line(
                out,
                format_args!(
                    "state: going home (e-stop) {} of {} s",
                    Fixed(elapsed_s, 3),
                    Fixed(duration_s, 3)
                ),
            ),
            MotionReport::Streaming { tracking: true } => {
                line(out, format_args!("state: streaming (tracking)"))
            }
            MotionReport::Streaming { tracking: false } => {
                line(out, format_args!("state: streaming (pass-through)"))
            }
            MotionReport::StreamIdle { quiet_s } => line(
                out,
                format_args!(
                    "state: idle (stream: no frame for {} s; holding its last pose, the next frame resumes it)",
                    Fixed(quiet_s, 1)
                ),
            ),
            MotionReport::Direct => {
                line(out, format_args!("state: direct (pulses set with servo)"))
            }
        },
        L::Pose => line(out, format_args!("pose: {}", PoseText(&s.pose))),
        L::Target => line(out, format_args!("target: {}", PoseText(&s.target))),
        L::ArmDeg => line(
            out,
            format_args!("arm_deg: {}", Six(&degrees(&s.arm_rad), 3)),
        ),
        L::PulseUs => line(out, format_args!("pulse_us: {}", Six(&s.pulse_us, 2))),
        L::PulsePose => match &s.pulse_pose {
            Some(Ok(pose)) => line(out, format_args!("pulse_pose: {}", PoseText(pose))),
            Some(Err(e)) => line(
                out,
                format_args!("pulse_pose: none ({})", KinematicsMessage(e)),
            ),
            None => {}
        },
        L::Torque => {
            if let Some(torques) = &s.torque_kgcm {
                torque_line(out, torques);
            }
        }
        L::Stream => {
            let c = &s.stream;
            line(
                out,
                format_args!(
                    "stream: frames={} applied={} damaged={} clamped={} refused={}",
                    c.frames, c.applied, c.damaged, c.clamped, c.refused
                ),
            )
        }
        L::Estop => line(
            out,
            format_args!(
                "e-stop: {}",
                match s.estop {
                    Estop::Clear => "clear",
                    Estop::Open => "open",
                    Estop::Latched => "latched (input closed; send reset)",
                }
            ),
        ),
        L::ServoPower => line(
            out,
            format_args!("servo_power: {}", if s.servo_power { "on" } else { "off" }),
        ),
        L::Fault => {
            if let Some(fault) = &s.fault {
                line(out, format_args!("fault: {fault}"));
            }
        }
    }
    true
}

/// `geometry`: the layout, a, s, h0, then a line per leg.
fn geometry_line(out: &mut impl Write, settings: &Settings, solver: &Solver, index: usize) -> bool {
    let geometry = solver.geometry();
    let l = &settings.layout;
    match index {
        0 => line(
            out,
            format_args!(
                "layout: paired base_radius_mm={} base_half_angle_deg={} platform_radius_mm={} platform_half_angle_deg={}",
                Fixed(l.base_radius_mm, 3),
                Fixed(l.base_half_angle_deg, 3),
                Fixed(l.platform_radius_mm, 3),
                Fixed(l.platform_half_angle_deg, 3)
            ),
        ),
        1 => line(
            out,
            format_args!("arm_mm (a): {}", Fixed(geometry.arm_mm(), 3)),
        ),
        2 => line(
            out,
            format_args!("rod_mm (s): {}", Fixed(geometry.rod_mm(), 3)),
        ),
        3 => line(
            out,
            format_args!(
                "home_height_mm (h0): {}",
                Fixed(geometry.home_height_mm(), 3)
            ),
        ),
        _ => {
            let i = index - 4;
            let Some(leg) = geometry.legs().get(i) else {
                return false;
            };
            line(
                out,
                format_args!(
                    "leg {}: b_mm={} p_mm={} beta_deg={} alpha0_deg={}",
                    i + 1,
                    Vector(&leg.base_mm),
                    Vector(&leg.platform_mm),
                    Fixed(leg.beta_rad.to_degrees(), 3),
                    Fixed(solver.alpha0_rad(i).to_degrees(), 3)
                ),
            );
        }
    }
    true
}

/// `config`: `# name: value` (the platform's settings and the link settings, in
/// [`SettingId::GLOBAL`] order), then the servos one line each, then `# saved: ...`.
fn config_line(
    out: &mut impl Write,
    settings: &Settings,
    link: &LinkSettings,
    saved: Saved,
    index: usize,
) -> bool {
    if let Some(&id) = SettingId::GLOBAL.get(index) {
        if let Some(value) = settings.get(id).or_else(|| link.get(id)) {
            line(out, format_args!("{id}: {}", ValueText(id, value)));
        }
        return true;
    }
    let servo = index - SettingId::GLOBAL.len() + 1;
    if servo == LEGS + 1 {
        let text = match saved {
            Saved::Same => "yes (these settings are the ones saved in flash)",
            Saved::Differs => "no (changed since the last save; save keeps them)",
            Saved::Nothing => "none (nothing saved in flash: the defaults at power-up)",
        };
        line(out, format_args!("saved: {text}"));
        return true;
    }
    if servo > LEGS {
        return false;
    }
    // LEGS is 6: never truncates.
    line(out, format_args!("{}", ServoLine(settings, servo as u8)));
    true
}

/// `servoN: trim_us=.. rate_us_rad=.. dir=.. min_us=.. max_us=..`
struct ServoLine<'a>(&'a Settings, u8);

impl Display for ServoLine<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let ServoLine(settings, servo) = *self;
        write!(f, "servo{servo}:")?;
        for param in ServoParam::ALL {
            let id = SettingId::Servo(ServoSel::One(servo), param);
            if let Some(value) = settings.get(id) {
                write!(f, " {}={}", param.name(), ValueText(id, value))?;
            }
        }
        Ok(())
    }
}
