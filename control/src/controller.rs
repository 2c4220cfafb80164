//! The controller: the platform's state and the commands that change it. Bytes in (with the
//! [`Session`] of the link they came from), replies out to that link, six pulse widths per frame.
//!
//! It owns the settings, UART0's baud rate, the motion and the last IK solution, and runs
//! commands. Data flows one way: the link's [`Session`] (bytes -> lines, echo) -> [`command`]
//! (line -> command) -> here (command -> target pose, checked by the IK) ->
//! [`motion`](crate::motion) (target -> one pose per frame) -> IK -> pulse widths. Everything
//! written goes through [`report`].
//!
//! Rules it keeps:
//! - exactly one final reply per completed non-blank line;
//! - a target is accepted only if it and the straight path to it can be driven; otherwise
//!   nothing changes and the platform holds its pose;
//! - a settings change is committed only if the complete new settings are valid and the pose
//!   being held can still be driven with them; changes to the frame rate, geometry or servos
//!   are refused while moving (`error:busy`);
//! - [`Controller::on_frame`] always returns finite pulses within the servo limits: if the IK
//!   fails on a frame, the last good pulses are held and the motion stops (a fault notice);
//! - no call does much work at once: a command whose work is long (a path check solves the IK
//!   at up to [`crate::motion::MAX_PATH_CHECKS`] poses; a listing writes many lines) becomes a
//!   job that [`Controller::work`] advances a slice at a time (at most [`CHECKS_PER_SLICE`]
//!   IK solutions, or one line), and the command's reply comes when its job is done. So the
//!   board's main loop never stalls: frames, the watchdog and the other links are served
//!   between slices.
//!
//! `save` is a job too, whose flash I/O is the board's: the controller prepares the record
//! (the A/B choice of sector and the sequence number are [`crate::store`]'s), the board takes
//! it with [`Controller::take_flash_write`], erases, programs and reads back, and hands the
//! outcome to [`Controller::flash_written`]; the reply follows in [`Controller::work`]. The
//! controller knows which settings are saved (for `config`) and never touches the flash.
//!
//! One job at a time: while [`Controller::is_busy`], the board feeds no bytes (they wait in the
//! link's receive queue, or the USB host waits). A move checked while the platform moves holds
//! the platform where it was when the command arrived until the check ends (a few
//! milliseconds; at most about 150 ms on the RP2040 for the longest check), then starts from
//! there; a refused move lets the move in progress go on. `check` does not hold anything.
//!
//! Latency: with both speed limits off a move is a jump, and a jump is made as soon as its
//! path is checked: the command's reply is followed by new pulses from
//! [`Controller::take_new_pulses`], which the board writes right away instead of at the next
//! frame (hobby-servo PWM latches new compare values at the next period, so nothing is cut
//! short). Streaming hosts use this mode. With a speed limit set the first step comes with the
//! next frame (up to one frame later), because writing it early could put two steps into one
//! frame and exceed the limit.
//!
//! Link loss: with `link_timeout_s` set, when that long passes without a completed non-blank
//! line (any line, valid or not, counts as a sign of life, and so does a command being
//! carried out), the platform returns home at the configured speeds (a group whose speed is
//! off uses [`LINK_LOSS_SPEED_MM_S`] / [`LINK_LOSS_SPEED_DEG_S`] so it never jumps). It fires
//! once per silence, never before the timeout: silence is counted in whole frames from the
//! first frame that starts after the line's end (so up to one frame late). A stream frame is
//! a sign of life too, so a stream that stops eases the platform home the same way.
//!
//! Streaming ([`crate::stream`]): a stream frame's pose becomes the stream's target; the newest
//! frame wins (the board feeds every waiting byte, then calls [`Controller::apply_stream`],
//! which applies only the newest frame). An unreachable target is clamped: the last reachable
//! pose on the straight line from the current pose to it, found by bisection
//! ([`CLAMP_STEPS`] IK solutions, as a job a slice per pass: so a clamped frame takes effect
//! a few passes, well under a millisecond, later), and counted. With every speed and acceleration limit off
//! the pose is applied at once (pass-through, like a jump: [`Controller::take_new_pulses`]);
//! otherwise each axis follows it at the servo frame rate within the limits
//! ([`crate::tracker`]); a step that would leave the workspace (the axes' own paths to a
//! reachable goal can) stops the tracker where it is, counted as a clamp too. An accepted
//! move (`pose`, `move`, `nudge`, `home`) or `stop` ends the stream (while a move's path is
//! checked the stream holds, as a move in progress does; a refused one lets it go on); the
//! next frame starts it again from wherever the platform is.
//!
//! Driving servos one by one (`servo n us`): the pulse goes to that servo (within its limits;
//! refused while a move is in progress or the e-stop is on; a stream ends), and the job finds
//! the pose the six pulses correspond to by forward kinematics ([`forward::Newton`], one
//! iteration per slice) along a continuation from the pose the platform was at
//! ([`FK_STEP_RAD`]), then checks it with the IK (and, with torque ratings, its holding
//! torques); the pulse is given when that is done. FK runs there, once per change of the
//! pulses, not in `status`: `status` shows the pose found (or that there is none), and moves,
//! `check` and `limits` start from it, so that a move after `servo` does not jump (with no pose
//! they are refused). A settings change while the pulses are set this way keeps them and finds
//! their pose again. An accepted move or stream frame ends it.
//!
//! Payload and torque ratings ([`crate::payload`]): with a payload, `check` and `status` show
//! the holding torques (a slice of their own: about three IK solutions' worth); with ratings as
//! well, every pose checked (a target, each checkpoint of a path, each pose `limits` tries, a
//! stream target and its clamp, the pose held when the settings change) must be within them,
//! and a slice then checks one pose with its torques instead of [`CHECKS_PER_SLICE`] by the IK.
//!
//! Emergency stop ([`crate::safety`]): the board reports the input with
//! [`Controller::set_estop_input`]; while it is open or latched, moves and stream frames are
//! refused. [`Controller::servo_power`] says whether the servo-power output should be on.

use core::fmt::Write;
use core::marker::PhantomData;

use kinematics_core::forward::{self, Newton};
use kinematics_core::ik::{self, IkError, Solution};
use kinematics_core::workspace;
use kinematics_core::{Geometry, KinematicsError, Libm, Math, Pose, LEGS};

use crate::command::{self, Command};
use crate::error::{Error, PoseError};
use crate::motion::{Checkpoints, Motion, Segment, SpeedLimits};
use crate::payload::TorqueError;
use crate::protocol::{Feed, Frame, Lost};
use crate::report::{
    self, Fault, Listing, MotionReport, Notice, Saved, StatusReport, StreamCounts, EOL,
};
use crate::safety::{Estop, EstopAction};
use crate::session::Session;
use crate::settings::{
    LinkSettings, SettingError, SettingId, SettingValue, Settings, DEFAULT_BAUD,
};
use crate::store::{self, Found, Loaded, SaveError, Store};
use crate::tracker::{TrackLimits, Tracker};

/// Linear speed for returning home after link loss when `speed_mm_s` is off, mm/s.
pub const LINK_LOSS_SPEED_MM_S: f32 = 10.0;
/// Angular speed for returning home after link loss when `speed_deg_s` is off, deg/s.
pub const LINK_LOSS_SPEED_DEG_S: f32 = 15.0;
/// Most IK solutions of a path check in one slice of work ([`Controller::work`]): on the
/// RP2040 one takes about 0.09 ms, so a slice stays well under half a millisecond. With a
/// payload and torque ratings, each pose checked also needs its holding torques (about
/// 0.47 ms, five IK solutions' worth): then a slice checks one pose.
pub const CHECKS_PER_SLICE: u32 = 3;

/// Halvings of a clamp's bisection: the clamped pose is within 1/64 of the way from the
/// current pose to the target (a clamp costs 1 + 6 IK solutions, the 6 as the controller's
/// own job, [`CHECKS_PER_SLICE`] per pass).
pub const CLAMP_STEPS: u32 = 6;

/// Notices kept for links that have not shown them yet (the latest ones).
const NOTICE_QUEUE: usize = 4;

/// What a checked path is for.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Purpose {
    /// `pose`, `move`, `nudge`, `home`: start the move (a jump if `jump`).
    Move { jump: bool },
    /// `check`: report, move nothing.
    Check,
    /// Link loss: return home.
    ReturnHome,
    /// The e-stop opened with `estop_action home`: go home.
    EstopHome,
}

/// What [`Controller::on_byte`] did with a byte, for the board's input loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fed {
    /// Part of a line or a frame.
    Byte,
    /// It ended a line (a command ran or started, or a refusal was written): the board ends
    /// the pass's input here, so at most one command runs per pass.
    LineEnded,
    /// It ended a stream frame (stored; [`Controller::apply_stream`] applies the newest).
    Frame,
}

/// The stream being followed.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Streaming {
    /// The newest frame's pose, as sent.
    target: Pose,
    /// A frame arrived since the last [`Controller::apply_stream`].
    fresh: bool,
    /// What the tracker follows: the target, clamped to the workspace.
    goal: Pose,
    /// Where the tracker is and how fast it goes.
    tracker: Tracker,
}

/// The pulses set with `servo`: the pose they correspond to (the forward kinematics), or why
/// there is none.
type Located = Result<Pose, KinematicsError>;

/// Largest change of any arm angle between two forward kinematics solves of a continuation,
/// rad (5 degrees).
///
/// The forward kinematics has several solutions and Newton's method finds the one nearest
/// where it starts; a servo driven far at once (tens of degrees) can make it land on another
/// assembly mode than the one the platform moves through (with the default build, servo 1
/// from 1900 us back to 1500 us, one step, lands 40 mm away from home). So the arm angles go
/// from those of the pose the platform was at to the new ones in steps of at most this much,
/// each solved from the last: the platform's own continuous path. Against a continuation in
/// 0.1 degree steps, 5 degree steps agreed on every one of 1,200 random single-servo changes;
/// they cost about 20 Newton iterations for a change of tens of degrees.
pub const FK_STEP_RAD: f32 = 5.0 * core::f32::consts::PI / 180.0;

/// Forward kinematics along a continuation: the arm angles go from `from_rad` to `to_rad` in
/// `steps` equal steps, each solved by Newton's method from the pose of the step before.
#[derive(Debug, Clone)]
struct Continuation {
    from_rad: [f32; LEGS],
    to_rad: [f32; LEGS],
    /// The step being solved, 1..=steps.
    step: u8,
    steps: u8,
    newton: Newton,
}

impl Continuation {
    /// The arm angles of step `step` of `steps` from `from_rad` to `to_rad`.
    fn arms_at(from_rad: &[f32; LEGS], to_rad: &[f32; LEGS], step: u8, steps: u8) -> [f32; LEGS] {
        let t = f32::from(step) / f32::from(steps);
        core::array::from_fn(|i| from_rad[i] + (to_rad[i] - from_rad[i]) * t)
    }

    /// The arm angles of step `step`.
    fn arms(&self, step: u8) -> [f32; LEGS] {
        Continuation::arms_at(&self.from_rad, &self.to_rad, step, self.steps)
    }
}

/// Why the pose of a set of pulses is being found ([`Job::Locate`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Relocate {
    /// `servo` drives a servo directly.
    Servo,
    /// The settings change while the pulses are set directly: the pulses stay.
    Settings,
}

/// How far a [`Job::Locate`] has got.
#[allow(clippy::large_enum_variant)] // see Job
#[derive(Debug, Clone)]
enum LocateStage {
    /// Newton's method, an iteration per slice ([`forward::Newton::step`]), along a
    /// continuation.
    Newton(Continuation),
    /// Found: the IK must agree (the arms on eq. 9's root the IK takes).
    Arms(Pose),
    /// The holding torques at the pose found, against the ratings.
    Torque(Pose),
    /// There is none: why.
    NoPose(KinematicsError),
}

/// A command's work left for later slices ([`Controller::work`]).
// No heap to box the large variants into: there is one job at a time, held in place.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
enum Job {
    /// A reachable target whose straight path is being checked.
    Path {
        purpose: Purpose,
        /// The target's solution (solved when the command came).
        solution: Solution,
        segment: Segment,
        checkpoints: Checkpoints,
        /// The target's holding torques: `None` until computed (the first slice, when there
        /// is a payload to check or report), then what `check` reports.
        torque: Option<Option<Torques>>,
    },
    /// A listing being written, line `next` next.
    Listing { listing: Listing, next: usize },
    /// `status` with a payload: the holding torques are computed (a slice), then listed.
    Status(StatusReport),
    /// `limits`: the reach along each axis-direction, a few poses per slice.
    Limits {
        start: Pose,
        search: workspace::Limits<PoseError>,
    },
    /// Pulses whose pose is being found (forward kinematics, a Newton iteration per slice),
    /// and the settings they go with; committed when found (or found to be no pose).
    Locate {
        why: Relocate,
        candidate: Settings,
        solver: ik::Solver,
        /// The pulses and the arm angles they command.
        solution: Solution,
        stage: LocateStage,
    },
    /// New settings with new build numbers: their geometry and IK are built a step per slice.
    Rebuild { candidate: Settings, stage: Rebuild },
    /// `save`: the flash write the board performs, and its outcome.
    Save(SaveStep),
    /// An unreachable stream target being clamped, a few IK solutions per slice (the
    /// controller's own work: no reply); with torque ratings, a reachable one whose holding
    /// torques are checked first.
    Clamp(Bisection),
}

/// A clamp in progress: bisection on the straight line from `from` (which can be driven) to
/// `to` (which cannot), [`CLAMP_STEPS`] halvings in all.
#[derive(Debug, Clone, Copy)]
struct Bisection {
    from: Pose,
    to: Pose,
    /// `to - from` per axis ([`Pose::to_array`] order).
    span: [f32; 6],
    /// `to` is within reach with this solution, but its holding torques are still to be
    /// checked against the ratings (the first slice); if they are within them, `to` is the
    /// goal, else the bisection goes on.
    unchecked: Option<Solution>,
    /// Fractions of the way known to be drivable and not.
    reachable: f32,
    unreachable: f32,
    /// The furthest drivable pose found and its solution (`None`: only `from`).
    best: Option<(Pose, Solution)>,
    /// Halvings done.
    steps: u32,
}

impl Bisection {
    /// A bisection on the straight line from `from` to `to`.
    fn new(from: Pose, to: Pose, unchecked: Option<Solution>) -> Bisection {
        let (a, b) = (from.to_array(), to.to_array());
        Bisection {
            from,
            span: core::array::from_fn(|i| b[i] - a[i]),
            to,
            unchecked,
            reachable: 0.0,
            unreachable: 1.0,
            best: None,
            steps: 0,
        }
    }

    /// The pose a fraction `t` of the way (what [`crate::motion::lerp`] gives, the differences computed
    /// once per clamp rather than once per halving).
    fn at(&self, t: f32) -> Pose {
        let a = self.from.to_array();
        Pose::from_array(core::array::from_fn(|i| a[i] + self.span[i] * t))
    }
}

/// How far a [`Job::Save`] has got.
#[derive(Debug, Clone)]
enum SaveStep {
    /// The write waits for the board to take it ([`Controller::take_flash_write`]).
    Waiting(store::Write),
    /// The board has taken it and is writing.
    Writing(store::Write),
    /// The board has written and read it back ([`Controller::flash_written`]).
    Written(store::Write, Result<(), SaveError>),
}

/// How far a [`Job::Rebuild`] has got.
#[allow(clippy::large_enum_variant)] // see Job
#[derive(Debug, Clone)]
enum Rebuild {
    /// The geometry is to be built.
    Geometry,
    /// The geometry is built; its IK is next.
    Solver(Geometry),
    /// The IK is built; the pose being held must be drivable with it.
    HeldPose(ik::Solver),
    /// The held pose can be driven; with torque ratings, it must be held too.
    HeldTorque(ik::Solver, Solution),
}

/// Holding torques (kgf cm), or why there are none.
type Torques = Result<[f32; LEGS], KinematicsError>;

/// What [`Controller::advance_in_place`] did.
#[allow(clippy::large_enum_variant)] // see Job
enum InPlace {
    /// A slice of the job is done; more remain.
    Pending,
    /// The job has ended.
    Done(Done),
    /// Not a job it advances.
    Other,
}

/// A job's outcome, for the reply.
#[allow(clippy::large_enum_variant)] // see Job
enum Done {
    /// Reply `ok` (after any data already written).
    Ok,
    /// Data lines to write first, a line per slice, then `ok`.
    List(Listing),
    /// Reply with this error.
    Refused(Error),
    /// The job was the controller's own (link loss): no reply.
    Quiet,
}

/// What starting a line did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Begun {
    /// Its final reply is written (or it was blank).
    Answered,
    /// A job runs; the reply comes when [`Controller::work`] completes it.
    Pending,
}

/// The hardware-independent firmware: feed it bytes and frames.
///
/// `M` supplies sin/cos, sqrt and atan2 (the host and default use `libm`; the board may
/// supply faster routines).
#[derive(Debug, Clone)]
pub struct Controller<M: Math = Libm> {
    settings: Settings,
    /// UART0's baud rate (a link setting: `defaults` keeps it).
    baud: u32,
    generation: u32,
    /// The IK of the settings' geometry (and the geometry).
    solver: ik::Solver,
    motion: Motion,
    /// The last good IK result (what the servos are being given).
    solution: Solution,
    /// The move in progress was started by link loss.
    returning_home: bool,
    /// The work in progress, if any.
    job: Option<Job>,
    /// The motion holds still until the job's check ends (a move checked while moving).
    holding: bool,
    /// Time without a line, us, counted in whole frames from the first frame that started
    /// after the last line; `None` until that frame.
    silence_us: Option<u32>,
    /// Link loss already handled for this silence.
    link_loss_handled: bool,
    /// The last fault, until the next accepted move.
    fault: Option<Fault>,
    /// The commanded pulses changed outside a frame (see [`Controller::take_new_pulses`]).
    new_pulses: bool,
    /// The stream being followed, if the last motion input was a stream frame.
    stream: Option<Streaming>,
    /// The pulses were set one servo at a time (`servo`) and where that put the platform:
    /// the motion's pose is that pose (when there is one), moves start from there.
    direct: Option<Located>,
    /// Stream frames counted since start-up.
    stream_counts: StreamCounts,
    /// The emergency stop.
    estop: Estop,
    /// The servo-power output should be on.
    servo_power: bool,
    /// Servo frames so far (wrapping): the links' clock for frames cut short.
    frame_ticks: u32,
    /// Which flash sector holds the newest good save, and its settings.
    store: Store,
    /// The board's id (its flash chip's unique ID), for the banner; none off the board.
    board_id: Option<u64>,
    /// The latest notices, each with its sequence number.
    notices: heapless::Deque<(u32, Notice), NOTICE_QUEUE>,
    /// Sequence number of the next notice.
    next_notice: u32,
    _math: PhantomData<M>,
}

impl Controller<Libm> {
    /// A controller with these settings, using `libm`. Invalid settings are replaced by the
    /// defaults (the banner says so); use [`Controller::try_with_math`] to handle that yourself.
    pub fn new(settings: Settings) -> Self {
        Self::with_math(settings)
    }
}

impl<M: Math> Controller<M> {
    /// A controller with these settings and math routines (invalid settings: see
    /// [`Controller::new`]).
    pub fn with_math(settings: Settings) -> Self {
        match Self::try_with_math(settings) {
            Ok(c) => c,
            Err(e) => {
                let mut c = Self::try_with_math(Settings::default())
                    .expect("the default settings are valid (tested)");
                c.notify(Notice::SettingsRejected(e));
                c
            }
        }
    }

    /// A controller with these settings, or why they cannot be used.
    pub fn try_with_math(settings: Settings) -> Result<Self, Error> {
        let solver = settings.validate_with::<M>()?;
        let solution = solver.solve::<M>(&settings.servos, &Pose::HOME)?;
        Ok(Controller {
            settings,
            baud: DEFAULT_BAUD,
            generation: 0,
            solver,
            motion: Motion::new(Pose::HOME),
            solution,
            returning_home: false,
            job: None,
            holding: false,
            silence_us: None,
            link_loss_handled: false,
            fault: None,
            new_pulses: false,
            stream: None,
            direct: None,
            stream_counts: StreamCounts::default(),
            estop: Estop::Clear,
            servo_power: false,
            frame_ticks: 0,
            store: Store::empty(),
            board_id: None,
            notices: heapless::Deque::new(),
            next_notice: 0,
            _math: PhantomData,
        })
    }

    /// The controller at power-up, from what the flash holds ([`Store::load`]): the newest
    /// good saved settings, or the defaults; a warning notice says why when it is not simply
    /// the last save (nothing saved, a copy that cannot be used). Saved settings these maths
    /// cannot drive are replaced by the defaults too (see [`Controller::with_math`]).
    pub fn power_up(loaded: Loaded) -> Self {
        let Loaded { store, found } = loaded;
        let mut c = Self::with_math(store.saved().copied().unwrap_or_default());
        c.store = store;
        match found {
            Found::Saved { .. } => {}
            Found::Nothing => c.notify(Notice::NoSavedSettings(None)),
            Found::Unusable(why) => c.notify(Notice::NoSavedSettings(Some(why))),
            Found::SavedOtherUnusable { sequence, other } => {
                c.notify(Notice::SavedCopyUnusable {
                    sequence,
                    why: other,
                });
            }
        }
        c
    }

    // ----- what the board reads -----

    /// The platform's active settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Increases every time the settings or the baud rate change; the board compares it with
    /// the value it last applied and then reconfigures (UART baud after the reply has been
    /// sent, PWM frame rate).
    pub fn settings_generation(&self) -> u32 {
        self.generation
    }

    /// Servo frame rate, Hz.
    pub fn frame_hz(&self) -> u16 {
        self.settings.frame_hz
    }

    /// UART0's baud rate (`set baud`; a link setting, kept by `defaults`).
    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// The active geometry.
    pub fn geometry(&self) -> &Geometry {
        self.solver.geometry()
    }

    /// The pose commanded on the last frame.
    pub fn pose(&self) -> &Pose {
        self.motion.pose()
    }

    /// Where the platform is going.
    pub fn target(&self) -> &Pose {
        self.motion.target()
    }

    /// True while a move is in progress, or a stream's tracker has not settled on its goal.
    pub fn is_moving(&self) -> bool {
        self.motion.is_moving()
            || self
                .stream
                .as_ref()
                .is_some_and(|s| s.fresh || !s.tracker.at_rest() || s.tracker.pose() != s.goal)
    }

    /// True while stream frames drive the platform.
    pub fn is_streaming(&self) -> bool {
        self.stream.is_some()
    }

    /// With pulses set by `servo`: the pose they correspond to, or why there is none; `None`
    /// when the pulses are the IK's for [`Controller::pose`].
    pub fn direct(&self) -> Option<&Result<Pose, KinematicsError>> {
        self.direct.as_ref()
    }

    /// Stream frames counted since start-up.
    pub fn stream_counts(&self) -> StreamCounts {
        self.stream_counts
    }

    /// The emergency stop's state.
    pub fn estop(&self) -> Estop {
        self.estop
    }

    /// Whether the servo-power output (`power_pin`) should be on: off at start-up until the
    /// first accepted move or stream frame, off on an emergency stop (after reaching home with
    /// `estop_action home`).
    pub fn servo_power(&self) -> bool {
        self.servo_power
    }

    /// True while a command's (or the controller's own) work is in progress: feed no bytes
    /// until it is done, but keep calling [`Controller::work`] and [`Controller::on_frame`].
    pub fn is_busy(&self) -> bool {
        self.job.is_some()
    }

    /// The pulses being commanded, us.
    pub fn pulses_us(&self) -> [f32; LEGS] {
        self.solution.pulse_us
    }

    /// The arm angles being commanded, rad.
    pub fn arm_rad(&self) -> [f32; LEGS] {
        self.solution.arm_rad
    }

    /// The last fault, until the next accepted move.
    pub fn fault(&self) -> Option<&Fault> {
        self.fault.as_ref()
    }

    /// What the controller knows of the flash: the newest good save and where it is.
    pub fn store(&self) -> &Store {
        &self.store
    }

    /// True while a `save` waits for the board's flash write (taken or not).
    pub fn awaits_flash(&self) -> bool {
        matches!(
            self.job,
            Some(Job::Save(SaveStep::Waiting(_) | SaveStep::Writing(_)))
        )
    }

    /// The flash write a `save` asks for, once: the board performs it
    /// ([`store::Write::perform`]: erase the sector, program the page, read it back) and hands
    /// the outcome to [`Controller::flash_written`]; the reply follows in [`Controller::work`].
    pub fn take_flash_write(&mut self) -> Option<store::Write> {
        match self.job {
            Some(Job::Save(SaveStep::Waiting(write))) => {
                self.job = Some(Job::Save(SaveStep::Writing(write)));
                Some(write)
            }
            _ => None,
        }
    }

    /// The outcome of the flash write taken with [`Controller::take_flash_write`] (ignored if
    /// none was taken).
    pub fn flash_written(&mut self, result: Result<(), SaveError>) {
        if let Some(Job::Save(SaveStep::Writing(write))) = self.job {
            self.job = Some(Job::Save(SaveStep::Written(write, result)));
        }
    }

    /// The pulses to write now if a command changed them outside a frame (a jump, or a
    /// settings change that moves the held pose's pulses), once; `None` otherwise. Finite and
    /// within the servo limits, like [`Controller::on_frame`]'s.
    pub fn take_new_pulses(&mut self) -> Option<[f32; LEGS]> {
        core::mem::take(&mut self.new_pulses).then(|| self.safe_pulses())
    }

    // ----- what the board calls -----

    /// The board's id (its flash chip's unique ID), handed over by the board at power-up: the
    /// banner shows it, so that two boards on one computer are told apart.
    pub fn set_board_id(&mut self, id: u64) {
        self.board_id = Some(id);
    }

    /// Writes the banner (and the notices this link has not shown, e.g. refused settings), then
    /// the prompt, to one link: at power-up, and when a link opens (a USB host opening its
    /// port, after [`Session::reopen`]).
    pub fn banner(&self, session: &mut Session, out: &mut impl Write) {
        report::write_banner(out, self.board_id);
        self.flush_notices(session, out);
        session.prompt(out);
    }

    /// Feeds one byte received on `session`'s link: echo and line editing; at the end of a
    /// line, runs it and writes exactly one final reply to that link (blank lines get none),
    /// at once or, if the command has long work, when [`Controller::work`] completes it. Feed
    /// no byte while [`Controller::is_busy`]: a line ended then is refused (`error:busy`).
    /// A stream frame is stored for [`Controller::apply_stream`].
    pub fn on_byte(&mut self, session: &mut Session, byte: u8, out: &mut impl Write) -> Fed {
        let feed = session.feed(byte, self.frame_ticks, out);
        if session.take_abandoned_frame() {
            self.stream_counts.damaged = self.stream_counts.damaged.wrapping_add(1);
        }
        match feed {
            Feed::Line => {
                // Copied out so the link can take the next line while the command runs.
                let line = session.take_line();
                if self.begin_line(session, &line, out) == Begun::Answered {
                    session.prompt(out);
                }
                Fed::LineEnded
            }
            Feed::Spoiled(why) => {
                self.heard_from_host();
                self.flush_notices(session, out);
                report::write_error(out, &Error::from(why));
                session.prompt(out);
                Fed::LineEnded
            }
            Feed::Empty | Feed::Cancelled => {
                session.prompt(out);
                Fed::LineEnded
            }
            Feed::Frame(frame) => {
                self.on_stream_frame(frame);
                Fed::Frame
            }
            Feed::DamagedFrame => {
                self.stream_counts.damaged = self.stream_counts.damaged.wrapping_add(1);
                Fed::Frame
            }
            _ => Fed::Byte,
        }
    }

    /// Applies the newest stream frame if one arrived since the last call: its pose becomes the
    /// pose now (pass-through: the new pulses are ready from [`Controller::take_new_pulses`])
    /// or the tracker's goal, if it can be taken; else it is clamped. One IK solution here; a
    /// clamp (the target out of reach, or with torque ratings, a target whose holding torques
    /// are to be checked) is the controller's own job ([`Controller::work`], a slice per pass).
    /// The board calls it after feeding the bytes waiting. If those bytes ended with a command
    /// whose work is running (the host's `status` after its last frame), a frame that needs a
    /// job of its own waits, still fresh, for the first call after that work is done.
    pub fn apply_stream(&mut self) {
        let Some(mut stream) = self.stream.filter(|s| s.fresh) else {
            return;
        };
        let solved = self
            .solver
            .solve::<M>(&self.settings.servos, &stream.target);
        let needs_job = solved.is_err() || self.settings.payload.checked();
        if needs_job && self.job.is_some() {
            return;
        }
        stream.fresh = false;
        self.stream = Some(stream);
        self.stream_counts.applied = self.stream_counts.applied.wrapping_add(1);
        self.servo_power = true;
        self.fault = None;
        let from = *self.motion.pose();
        match solved {
            Ok(solution) if !self.settings.payload.checked() => {
                self.reach_stream_goal(stream.target, Some(solution))
            }
            // Within reach, but with torque ratings its holding torques are checked first, as
            // the controller's own job (a slice of their own), then it is the goal or clamped.
            Ok(solution) => self.start_clamp(from, stream.target, Some(solution)),
            Err(_) => {
                // Unreachable: clamped by a bisection that runs as the controller's own job,
                // a slice per pass (so no pass grows by its IK solutions); the platform goes
                // on towards the previous goal meanwhile.
                self.stream_counts.clamped = self.stream_counts.clamped.wrapping_add(1);
                self.start_clamp(from, stream.target, None);
            }
        }
    }

    /// The emergency-stop input, as the board reads it (`open`: the pin is high; call it every
    /// pass when `estop_pin` is set). Opening it stops the platform (see [`crate::safety`]).
    pub fn set_estop_input(&mut self, open: bool) {
        let before = self.estop;
        self.estop = before.with_input(open);
        match (before, self.estop) {
            (Estop::Clear, Estop::Open) => self.on_estop(),
            (Estop::Open, Estop::Latched) => self.notify(Notice::EstopClosed),
            _ => {}
        }
    }

    /// Runs one line as if it had been typed on `session`'s link (any case, blank lines
    /// ignored) and writes its replies there, its work done to the end at once: for
    /// transports other than the byte stream, and for tests. The one exception is `save`,
    /// whose flash write is the board's: this returns with it waiting
    /// ([`Controller::awaits_flash`]); perform it, then call [`Controller::work`] for the reply.
    pub fn execute_line(&mut self, session: &mut Session, line: &str, out: &mut impl Write) {
        if self.begin_line(session, line, out) == Begun::Pending {
            while session.awaits_reply() && !self.awaits_flash() {
                self.work(session, out);
            }
        }
    }

    /// Does one slice of the work in progress: at most [`CHECKS_PER_SLICE`] IK solutions of a
    /// path check, or one line of a listing. When the work of a command completes, its final
    /// reply (and the prompt) goes to `session`, which must be the link that sent it
    /// ([`Session::awaits_reply`]); called with another link, a command's work waits. The
    /// controller's own work (the return home after link loss) goes on whichever link is
    /// passed. Call it once per main-loop pass while [`Controller::is_busy`].
    pub fn work(&mut self, session: &mut Session, out: &mut impl Write) {
        let commanded = !matches!(
            self.job,
            Some(
                Job::Path {
                    purpose: Purpose::ReturnHome | Purpose::EstopHome,
                    ..
                } | Job::Clamp(_)
            )
        );
        if commanded && !session.awaits_reply() {
            return;
        }
        let done = match self.advance_in_place() {
            InPlace::Pending => return,
            InPlace::Done(done) => done,
            InPlace::Other => match self.take_and_advance(out) {
                Some(done) => done,
                None => return,
            },
        };
        self.holding = false;
        match done {
            Done::List(listing) => self.job = Some(Job::Listing { listing, next: 0 }),
            Done::Quiet => {}
            Done::Ok => self.reply(session, Ok(()), out),
            Done::Refused(e) => self.reply(session, Err(e), out),
        }
    }

    /// A slice of the jobs that take many (a path check's poses, a clamp's halvings), done
    /// where the job is held: the job is moved out only when it ends. Moving a whole [`Job`]
    /// (its largest variants hold a candidate IK and settings, over 1.6 KB) out and back
    /// costs the RP2040 thousands of cycles, a good part of a slice's IK.
    fn advance_in_place(&mut self) -> InPlace {
        match &self.job {
            Some(Job::Path {
                segment,
                checkpoints,
                torque: Some(_),
                ..
            }) => {
                let (segment, mut next) = (*segment, *checkpoints);
                let result = self.check_slice(&segment, &mut next);
                let Some(result) = result else {
                    if let Some(Job::Path { checkpoints, .. }) = &mut self.job {
                        *checkpoints = next;
                    }
                    return InPlace::Pending;
                };
                match self.job.take() {
                    Some(Job::Path {
                        purpose,
                        solution,
                        torque: Some(torque),
                        ..
                    }) => {
                        InPlace::Done(self.finish_path(purpose, solution, segment, torque, result))
                    }
                    other => {
                        self.job = other;
                        InPlace::Pending
                    }
                }
            }
            Some(Job::Clamp(bisection)) => {
                let mut bisection = *bisection;
                match self.clamp_slice(&mut bisection) {
                    None => {
                        if let Some(Job::Clamp(held)) = &mut self.job {
                            *held = bisection;
                        }
                        InPlace::Pending
                    }
                    Some((pose, solution)) => {
                        self.job = None;
                        self.reach_stream_goal(pose, solution);
                        InPlace::Done(Done::Quiet)
                    }
                }
            }
            _ => InPlace::Other,
        }
    }

    /// A slice of any other job, moved out of its place and back if it goes on: `None` while
    /// it does, else how it ended.
    fn take_and_advance(&mut self, out: &mut impl Write) -> Option<Done> {
        let job = self.job.take()?;
        let done = match job {
            Job::Path {
                purpose,
                solution,
                segment,
                checkpoints,
                torque: None,
            } => {
                // The target's holding torques first, in a slice of their own.
                match self.target_torque(purpose, &segment, &solution) {
                    Ok(torque) => {
                        self.job = Some(Job::Path {
                            purpose,
                            solution,
                            segment,
                            checkpoints,
                            torque: Some(torque),
                        });
                        return None;
                    }
                    Err(e) => self.finish_path(purpose, solution, segment, None, Err(e)),
                }
            }
            Job::Listing { listing, next } => {
                if listing.write_line(next, &self.settings, &self.solver, out) {
                    self.job = Some(Job::Listing {
                        listing,
                        next: next + 1,
                    });
                    return None;
                }
                Done::Ok
            }
            Job::Status(mut report) => {
                report.torque_kgcm = Some(self.status_torques(&report));
                Done::List(Listing::Status(report))
            }
            Job::Limits { start, mut search } => match self.limits_slice(&mut search) {
                None => {
                    self.job = Some(Job::Limits { start, search });
                    return None;
                }
                Some(reaches) => Done::List(Listing::Limits { start, reaches }),
            },
            Job::Locate {
                why,
                candidate,
                solver,
                solution,
                stage,
            } => match self.locate_step(why, candidate, solver, solution, stage) {
                None => return None,
                Some(Ok(())) => Done::Ok,
                Some(Err(e)) => Done::Refused(e),
            },
            Job::Rebuild { candidate, stage } => match self.rebuild_step(candidate, stage) {
                None => return None,
                Some(Ok(())) => Done::Ok,
                Some(Err(e)) => Done::Refused(e),
            },
            Job::Save(SaveStep::Written(write, Ok(()))) => {
                self.store.commit(&write);
                Done::Ok
            }
            Job::Save(SaveStep::Written(_, Err(e))) => Done::Refused(Error::SaveFailed(e)),
            Job::Save(step) => {
                // The board has not written yet.
                self.job = Some(Job::Save(step));
                return None;
            }
            // Advanced in place (see advance_in_place).
            in_place @ (Job::Path {
                torque: Some(_), ..
            }
            | Job::Clamp(_)) => {
                self.job = Some(in_place);
                return None;
            }
        };
        Some(done)
    }

    /// Bytes were lost on their way in (a receive queue was full, or the UART saw an overrun,
    /// framing, parity or break error) and the board has just noticed: a warning goes to every
    /// link at once (to this one now). `at_least` bytes so far; `in_uart`: the UART's
    /// hardware lost them (it cannot tell how many). The line they cut is refused when the
    /// board reaches the gap ([`Controller::on_rx_overflow`]).
    pub fn on_input_lost(
        &mut self,
        session: &mut Session,
        at_least: u32,
        in_uart: bool,
        out: &mut impl Write,
    ) {
        self.notify(Notice::InputLost { at_least, in_uart });
        self.write_notices(session, out);
    }

    /// The board reached the gap where `session`'s link lost bytes: the line being received
    /// there is refused when it ends (`error:rx-overflow`, naming what was lost).
    pub fn on_rx_overflow(&mut self, session: &mut Session, lost: Lost) {
        session.rx_overflow(lost);
    }

    /// Writes the notices (faults, link loss, warnings) this link has not shown yet, restoring
    /// the prompt and the line being typed when echo is on. Call it for every link after
    /// anything that may notify (a frame, lost input); notices pending for a link are also
    /// written before its next reply.
    pub fn write_notices(&self, session: &mut Session, out: &mut impl Write) {
        if !self.has_notices_for(session) {
            return;
        }
        if session.echo() && !session.awaits_reply() {
            let _ = out.write_str(EOL);
        }
        self.flush_notices(session, out);
        if session.echo() && !session.awaits_reply() {
            session.prompt(out);
            let _ = out.write_str(session.typed());
        }
    }

    /// Advances by one frame (`1 / frame_hz` s): link-loss timer, motion, IK. Returns the six
    /// pulse widths (us, servo 1 first), always finite and within each servo's limits.
    pub fn on_frame(&mut self) -> [f32; LEGS] {
        self.frame_ticks = self.frame_ticks.wrapping_add(1);
        let frame_us = 1_000_000 / u32::from(self.settings.frame_hz.max(1));
        // The frame in which the last line ended counts nothing (part of it was not silent).
        self.silence_us = Some(self.silence_us.map_or(0, |s| s.saturating_add(frame_us)));
        self.check_link();

        if self.stream.is_some() && !self.holding {
            self.track_frame();
            return self.safe_pulses();
        }
        if !self.motion.is_moving() || self.holding {
            // Standing still (or holding while a new path is checked): the held pose's pulses
            // are solved already (when it was reached or the settings changed), and the IK is
            // deterministic. This keeps idle frames cheap, so a frame never delays a command
            // much.
            return self.safe_pulses();
        }
        let next = self.motion.next_pose();
        match self.solver.solve::<M>(&self.settings.servos, &next) {
            Ok(solution) => {
                self.motion.commit();
                self.solution = solution;
                if !self.motion.is_moving() {
                    self.returning_home = false;
                    if self.estop.stops_motion() {
                        // Home after an e-stop (`estop_action home`): now the power goes off.
                        self.servo_power = false;
                    }
                }
            }
            Err(cause) => {
                // Should not happen (targets and paths are checked), but if it does: hold the
                // last good pulses and stop where the last good frame was.
                let first = self.fault.is_none() || self.motion.is_moving();
                self.motion.stop();
                self.returning_home = false;
                if first {
                    let fault = Fault::IkFailed {
                        cause,
                        held: *self.motion.pose(),
                    };
                    self.fault = Some(fault);
                    self.notify(Notice::Fault(fault));
                }
            }
        }
        self.safe_pulses()
    }

    // ----- commands -----

    /// Starts a line: its reply at once, or a job whose reply comes later.
    fn begin_line(&mut self, session: &mut Session, line: &str, out: &mut impl Write) -> Begun {
        if line.bytes().all(|b| b == b' ' || b == b'\t') {
            return Begun::Answered;
        }
        self.heard_from_host();
        self.flush_notices(session, out);
        if self.job.is_some() {
            report::write_error(out, &Error::Pending);
            return Begun::Answered;
        }
        let result = command::parse(line)
            .map_err(Error::from)
            .and_then(|cmd| self.run(session, cmd));
        match result {
            Ok(Begun::Answered) => {
                report::write_ok(out);
                Begun::Answered
            }
            Ok(Begun::Pending) => {
                session.set_awaiting_reply(true);
                Begun::Pending
            }
            Err(e) => {
                report::write_error(out, &e);
                Begun::Answered
            }
        }
    }

    /// Writes a job's final reply to `session` and the prompt.
    fn reply(&mut self, session: &mut Session, result: Result<(), Error>, out: &mut impl Write) {
        session.set_awaiting_reply(false);
        // The host is alive: the link-loss silence starts from the reply.
        self.heard_from_host();
        self.flush_notices(session, out);
        match result {
            Ok(()) => report::write_ok(out),
            Err(e) => report::write_error(out, &e),
        }
        session.prompt(out);
    }

    fn run(&mut self, session: &mut Session, cmd: Command) -> Result<Begun, Error> {
        let moves = matches!(
            cmd,
            Command::Pose(_) | Command::Move(_) | Command::Nudge(_) | Command::Home
        );
        let moves = moves || matches!(cmd, Command::Servo { .. });
        if moves && self.estop.stops_motion() {
            return Err(Error::Estop(self.estop));
        }
        match cmd {
            Command::Pose(target) => self.move_to(target),
            Command::Move(values) => self.move_to(values.apply(self.motion.target(), false)),
            Command::Nudge(values) => self.move_to(values.apply(self.motion.target(), true)),
            Command::Home => self.move_to(Pose::HOME),
            Command::Check(target) => self.start_path(target, self.speed_limits(), Purpose::Check),
            Command::Stop => {
                self.end_stream();
                self.motion.stop();
                self.returning_home = false;
                Ok(Begun::Answered)
            }
            Command::Reset => match self.estop {
                Estop::Open => Err(Error::Estop(Estop::Open)),
                Estop::Latched | Estop::Clear => {
                    self.estop = Estop::Clear;
                    self.fault = None;
                    Ok(Begun::Answered)
                }
            },
            Command::Status => {
                let report = self.status();
                if self.settings.payload.carried() {
                    // The holding torques at the pose: a slice of their own.
                    self.job = Some(Job::Status(report));
                    Ok(Begun::Pending)
                } else {
                    Ok(self.list(Listing::Status(report)))
                }
            }
            Command::Limits => {
                if let Some(Err(e)) = self.direct {
                    return Err(Error::NoPose(e));
                }
                let start = *self.motion.pose();
                self.job = Some(Job::Limits {
                    start,
                    search: workspace::Limits::new(start, workspace::Options::default()),
                });
                Ok(Begun::Pending)
            }
            Command::Servo { servo, pulse_us } => self.drive_servo(servo, pulse_us),
            Command::Geometry => Ok(self.list(Listing::Geometry)),
            Command::Config => {
                let saved = match self.store.saved() {
                    None => Saved::Nothing,
                    Some(s) if *s == self.settings => Saved::Same,
                    Some(_) => Saved::Differs,
                };
                let link = LinkSettings {
                    baud: self.baud,
                    echo: session.echo(),
                };
                Ok(self.list(Listing::Config(link, saved)))
            }
            Command::Help => Ok(self.list(Listing::Help)),
            Command::Set(SettingId::Echo, SettingValue::Flag(on)) => {
                session.set_echo(on);
                Ok(Begun::Answered)
            }
            Command::Set(SettingId::Baud, SettingValue::Whole(baud)) => {
                if baud != self.baud {
                    // The prompt after the `ok` must go out at the new rate, which the board
                    // switches to once the `ok` has left (see Session::prompt_deferred).
                    session.defer_prompt();
                }
                self.baud = baud;
                self.generation = self.generation.wrapping_add(1);
                Ok(Begun::Answered)
            }
            Command::Set(id, value) => {
                // (A payload or a rating changes what the path in progress was checked for.)
                let moves_matter = matches!(
                    id,
                    SettingId::FrameHz
                        | SettingId::Layout(_)
                        | SettingId::Servo(..)
                        | SettingId::PayloadG
                        | SettingId::PayloadCom(_)
                );
                if moves_matter && self.motion.is_moving() {
                    return Err(Error::Busy);
                }
                self.change_settings(self.settings.with(id, value))
            }
            Command::Save => {
                if self.motion.is_moving() {
                    return Err(Error::Busy);
                }
                // The platform's settings only: the links keep theirs (see crate::record).
                let write = self.store.prepare(&self.settings);
                self.job = Some(Job::Save(SaveStep::Waiting(write)));
                Ok(Begun::Pending)
            }
            Command::Defaults => {
                if self.motion.is_moving() {
                    return Err(Error::Busy);
                }
                // Only the platform's settings: the links stay as they are (a host talking at
                // 921600 baud without echo keeps talking).
                self.change_settings(Settings::default())
            }
        }
    }

    /// Starts writing a listing, a line per slice.
    fn list(&mut self, listing: Listing) -> Begun {
        self.job = Some(Job::Listing { listing, next: 0 });
        Begun::Pending
    }

    fn speed_limits(&self) -> SpeedLimits {
        let s = &self.settings;
        SpeedLimits {
            mm_per_s2: s.accel_mm_s2,
            deg_per_s2: s.accel_deg_s2,
            ..SpeedLimits::speeds(s.speed_mm_s, s.speed_deg_s)
        }
    }

    /// The stream tracker's limits (the same settings as commanded moves, per axis).
    fn track_limits(&self) -> TrackLimits {
        let s = &self.settings;
        TrackLimits {
            mm_per_s: s.speed_mm_s,
            mm_per_s2: s.accel_mm_s2,
            rad_per_s: s.speed_deg_s.to_radians(),
            rad_per_s2: s.accel_deg_s2.to_radians(),
        }
    }

    /// Speeds for going home on its own (link loss, e-stop): the configured ones, or where a
    /// group's is off, a slow default (it never jumps).
    fn own_move_limits(&self) -> SpeedLimits {
        let or = |v: f32, fallback: f32| if v > 0.0 { v } else { fallback };
        SpeedLimits {
            mm_per_s: or(self.settings.speed_mm_s, LINK_LOSS_SPEED_MM_S),
            deg_per_s: or(self.settings.speed_deg_s, LINK_LOSS_SPEED_DEG_S),
            ..self.speed_limits()
        }
    }

    fn move_to(&mut self, target: Pose) -> Result<Begun, Error> {
        let limits = self.speed_limits();
        let jump = !(limits.mm_per_s > 0.0 || limits.deg_per_s > 0.0);
        self.start_path(target, limits, Purpose::Move { jump })
    }

    // ----- streaming -----

    /// A whole stream frame arrived: its pose becomes the stream's target (applied by
    /// [`Controller::apply_stream`]).
    fn on_stream_frame(&mut self, frame: Frame) {
        let counts = &mut self.stream_counts;
        let Ok(target) = self.settings.stream.to_pose(frame) else {
            counts.damaged = counts.damaged.wrapping_add(1);
            return;
        };
        counts.frames = counts.frames.wrapping_add(1);
        // No pose to start from (pulses set with servo that correspond to none) is refused
        // like the e-stop. (The board feeds no bytes while a job runs; refused all the same if
        // it did.)
        let no_pose = matches!(self.direct, Some(Err(_)));
        if self.estop.stops_motion() || self.job.is_some() || no_pose {
            counts.refused = counts.refused.wrapping_add(1);
            return;
        }
        self.heard_from_host();
        let here = *self.motion.pose();
        match self.stream.as_mut() {
            Some(stream) => {
                stream.target = target;
                stream.fresh = true;
            }
            None => {
                // The stream starts (again) from where the platform is; a move in progress ends,
                // and so does driving the servos one by one.
                self.motion = Motion::new(here);
                self.returning_home = false;
                self.direct = None;
                self.stream = Some(Streaming {
                    target,
                    fresh: true,
                    goal: here,
                    tracker: Tracker::new(&here),
                });
            }
        }
    }

    /// One servo frame of a stream: the tracker steps towards its goal; a step that cannot be
    /// driven is clamped and the tracker stops there.
    fn track_frame(&mut self) {
        let Some(mut stream) = self.stream else {
            return;
        };
        let limits = self.track_limits();
        if limits == TrackLimits::OFF {
            return; // pass-through: applied as frames come
        }
        let dt_s = 1.0 / f32::from(self.settings.frame_hz.max(1));
        let next = stream.tracker.step::<M>(&stream.goal, &limits, dt_s);
        if next.pose() == *self.motion.pose() && next == stream.tracker {
            return; // settled: the pulses are solved already
        }
        match self.solver.solve::<M>(&self.settings.servos, &next.pose()) {
            Ok(solution) => {
                self.motion = Motion::new(next.pose());
                self.solution = solution;
                stream.tracker = next;
            }
            Err(_) => {
                // The goal can be driven (it was clamped), but the axes' own paths to it
                // leave the workspace here: stop where the last step was, a step (at most one
                // frame's travel) short of the edge, rather than spend a bisection in this
                // pass (which also holds a clamp of the goal: the pass must stay short).
                let here = *self.motion.pose();
                stream.tracker.hold_at(&here);
                stream.goal = here;
                self.stream_counts.clamped = self.stream_counts.clamped.wrapping_add(1);
            }
        }
        self.stream = Some(stream);
    }

    /// Starts clamping a stream target as the controller's own job: `to` cannot be reached
    /// (`unchecked: None`), or can, with this solution, but its holding torques are to be
    /// checked against the ratings first. ([`Controller::apply_stream`] waits for a command's
    /// work to end first; a job still running here means this frame came through a transport
    /// that feeds while busy: then the goal stays where it was.)
    fn start_clamp(&mut self, from: Pose, to: Pose, unchecked: Option<Solution>) {
        if self.job.is_none() {
            self.job = Some(Job::Clamp(Bisection::new(from, to, unchecked)));
        }
    }

    /// A slice of a clamp: the target's holding torques if they are to be checked (then the
    /// target is the goal if they are within the ratings), else
    /// [`Controller::poses_per_slice`] more halvings of the bisection (each pose within reach
    /// and, with ratings, within them). `Some` when it is done: the goal and its solution
    /// (`None`: where the bisection started, whose solution is the current one).
    fn clamp_slice(&mut self, b: &mut Bisection) -> Option<(Pose, Option<Solution>)> {
        let torque = self.settings.payload.checked();
        if let Some(solution) = b.unchecked.take() {
            let held = self
                .settings
                .payload
                .check::<M>(&self.solver, &b.to, &solution.arm_rad);
            if held.is_ok() {
                return Some((b.to, Some(solution)));
            }
            self.stream_counts.clamped = self.stream_counts.clamped.wrapping_add(1);
            return None;
        }
        for _ in 0..self.poses_per_slice() {
            if b.steps >= CLAMP_STEPS {
                break;
            }
            b.steps += 1;
            let t = 0.5 * (b.reachable + b.unreachable);
            let pose = b.at(t);
            match self.pose_check(&pose, torque) {
                Ok(solution) => {
                    b.reachable = t;
                    b.best = Some((pose, solution));
                }
                Err(_) => b.unreachable = t,
            }
        }
        (b.steps >= CLAMP_STEPS).then(|| {
            b.best
                .map_or((b.from, None), |(pose, solution)| (pose, Some(solution)))
        })
    }

    /// A stream target, or what it was clamped to, is the goal: in pass-through the pose now
    /// (`solution`: its IK; `None` to stay where the platform is), else the tracker's goal.
    /// Nothing if the stream has ended meanwhile (a clamp's job outlived it).
    fn reach_stream_goal(&mut self, pose: Pose, solution: Option<Solution>) {
        let Some(mut stream) = self.stream else {
            return;
        };
        if self.track_limits() == TrackLimits::OFF {
            if let Some(solution) = solution {
                self.motion = Motion::new(pose);
                self.solution = solution;
                self.new_pulses = true;
            }
            stream.tracker.hold_at(self.motion.pose());
            stream.goal = *self.motion.pose();
        } else {
            stream.goal = pose;
        }
        self.stream = Some(stream);
    }

    /// Ends the stream (the platform holds where it is).
    fn end_stream(&mut self) {
        if self.stream.take().is_some() {
            self.motion = Motion::new(*self.motion.pose());
        }
    }

    // ----- emergency stop -----

    /// The e-stop input opened: stop (or go home), end the stream, power off.
    fn on_estop(&mut self) {
        self.end_stream();
        self.motion.stop();
        self.returning_home = false;
        let safety = self.settings.safety;
        self.notify(Notice::EstopOpened {
            action: safety.estop_action,
            power_pin: safety.power_pin.is_some(),
        });
        match safety.estop_action {
            EstopAction::Freeze => self.servo_power = false,
            EstopAction::Home => {
                if *self.motion.pose() == Pose::HOME {
                    self.servo_power = false;
                } else if self.job.is_none() {
                    let limits = self.own_move_limits();
                    if let Err(e) = self.start_path(Pose::HOME, limits, Purpose::EstopHome) {
                        self.home_blocked(e);
                        self.servo_power = false;
                    }
                }
                // (With a command's job running, the way home starts when it ends: see
                // finish_path.)
            }
        }
    }

    /// Checks the target now (its error is the most useful one), then starts the check of the
    /// straight path to it from the current pose as a job.
    fn start_path(
        &mut self,
        target: Pose,
        limits: SpeedLimits,
        purpose: Purpose,
    ) -> Result<Begun, Error> {
        if let Some(Err(e)) = self.direct {
            // Pulses set with servo that correspond to no pose: no pose to start from.
            return Err(Error::NoPose(e));
        }
        let solution = self.solver.solve::<M>(&self.settings.servos, &target)?;
        let segment = Segment::plan(
            *self.motion.pose(),
            target,
            limits,
            f32::from(self.settings.frame_hz),
        );
        // A move checked while moving (or streaming): the platform holds here until the check
        // ends.
        self.holding =
            purpose != Purpose::Check && (self.motion.is_moving() || self.is_streaming());
        self.job = Some(Job::Path {
            purpose,
            solution,
            segment,
            checkpoints: segment.checkpoints(),
            // The target's torques take a slice of their own, if they are needed at all.
            torque: if self.target_torque_needed(purpose) {
                None
            } else {
                Some(None)
            },
        });
        Ok(Begun::Pending)
    }

    /// Whether a path check starts with the target's holding torques: with ratings to check,
    /// or for `check` to report.
    fn target_torque_needed(&self, purpose: Purpose) -> bool {
        let payload = &self.settings.payload;
        payload.checked() || (purpose == Purpose::Check && payload.carried())
    }

    /// The first slice of a path check: the target's holding torques, if there is a payload
    /// to check against ratings (refused if one is exceeded) or to report (`check`);
    /// `Ok(None)` otherwise.
    fn target_torque(
        &self,
        purpose: Purpose,
        segment: &Segment,
        solution: &Solution,
    ) -> Result<Option<Torques>, Error> {
        let payload = &self.settings.payload;
        let report = purpose == Purpose::Check && payload.carried();
        if !self.target_torque_needed(purpose) {
            return Ok(None);
        }
        let torques =
            payload.holding_torques_kgcm::<M>(&self.solver, segment.target(), &solution.arm_rad);
        if payload.checked() {
            match torques {
                Ok(t) => payload.within_ratings(&t)?,
                Err(e) => return Err(TorqueError::Unknown(e).into()),
            }
        }
        Ok(report.then_some(torques))
    }

    /// How many poses a slice of work checks: [`CHECKS_PER_SLICE`] by the IK alone, or one
    /// with its holding torques when there are ratings to check.
    fn poses_per_slice(&self) -> u32 {
        if self.settings.payload.checked() {
            1
        } else {
            CHECKS_PER_SLICE
        }
    }

    /// Whether a pose can be taken: the IK within the servo limits and, if `torque`, every
    /// servo's holding torque within its rating. Its solution if so.
    fn pose_check(&self, pose: &Pose, torque: bool) -> Result<Solution, PoseError> {
        let solution = self.solver.solve::<M>(&self.settings.servos, pose)?;
        if torque {
            self.settings
                .payload
                .check::<M>(&self.solver, pose, &solution.arm_rad)?;
        }
        Ok(solution)
    }

    /// Checks [`Controller::poses_per_slice`] more poses of the path: `None` if poses remain,
    /// `Some(Ok)` if the whole path is clear, `Some(Err)` at the first that is not.
    fn check_slice(
        &self,
        segment: &Segment,
        checkpoints: &mut Checkpoints,
    ) -> Option<Result<(), Error>> {
        let torque = self.settings.payload.checked();
        let mut solved = 0;
        while solved < self.poses_per_slice() {
            let Some((pose, fraction)) = checkpoints.next() else {
                return Some(Ok(()));
            };
            if pose == *segment.target() {
                continue; // checked when the command came and in the first slice
            }
            solved += 1;
            if let Err(cause) = self.pose_check(&pose, torque) {
                return Some(Err(Error::PathBlocked {
                    percent: fraction * 100.0,
                    cause,
                }));
            }
        }
        None
    }

    /// A slice of `limits`' search: `None` while poses remain, then the twelve reaches.
    fn limits_slice(
        &self,
        search: &mut workspace::Limits<PoseError>,
    ) -> Option<[workspace::Reach<PoseError>; 12]> {
        let torque = self.settings.payload.checked();
        for _ in 0..self.poses_per_slice() {
            let found = search.step(|pose| self.pose_check(pose, torque).map(|_| ()));
            if found.is_some() {
                return found;
            }
        }
        None
    }

    /// What a checked path leads to.
    fn finish_path(
        &mut self,
        purpose: Purpose,
        solution: Solution,
        segment: Segment,
        torque_kgcm: Option<Torques>,
        result: Result<(), Error>,
    ) -> Done {
        if self.estop.stops_motion()
            && matches!(purpose, Purpose::Move { .. } | Purpose::ReturnHome)
        {
            // The e-stop opened while the path was checked: nothing moves (but home, if that
            // is the e-stop's action).
            self.estop_home_after_job();
            return match purpose {
                Purpose::ReturnHome => Done::Quiet,
                _ => Done::Refused(Error::Estop(self.estop)),
            };
        }
        match (purpose, result) {
            (Purpose::Move { jump: false }, Ok(())) => {
                // An accepted move ends the stream (and driving the servos one by one).
                self.end_stream();
                self.direct = None;
                self.start(segment);
                self.servo_power = true;
                Done::Ok
            }
            (Purpose::Move { jump: true }, Ok(())) => {
                // No speed limit: a jump, made now (see the module docs on latency).
                self.end_stream();
                self.direct = None;
                self.motion = Motion::new(*segment.target());
                self.solution = solution;
                self.new_pulses = true;
                self.returning_home = false;
                self.fault = None;
                self.servo_power = true;
                Done::Ok
            }
            (Purpose::EstopHome, Ok(())) => {
                self.end_stream();
                self.direct = None;
                self.start(segment);
                Done::Quiet
            }
            (Purpose::EstopHome, Err(e)) => {
                self.home_blocked(e);
                self.servo_power = false;
                Done::Quiet
            }
            (Purpose::Check, Ok(())) => {
                let duration_s = if segment.start() == segment.target() {
                    0.0
                } else {
                    segment.frames() as f32 / f32::from(self.settings.frame_hz)
                };
                Done::List(Listing::Check {
                    arm_rad: solution.arm_rad,
                    pulse_us: solution.pulse_us,
                    torque_kgcm,
                    duration_s,
                })
            }
            (Purpose::ReturnHome, Ok(())) => {
                self.end_stream();
                self.direct = None;
                self.start(segment);
                self.returning_home = true;
                self.notify(Notice::LinkLost {
                    timeout_s: self.settings.link_timeout_s,
                });
                Done::Quiet
            }
            (Purpose::ReturnHome, Err(e)) => {
                self.home_blocked(e);
                Done::Quiet
            }
            (_, Err(e)) => Done::Refused(e),
        }
    }

    /// The e-stop opened while a command's job ran (its motion refused): with `estop_action
    /// home`, the way home starts now (its check is the next job).
    fn estop_home_after_job(&mut self) {
        if self.settings.safety.estop_action == EstopAction::Home && !self.motion.is_moving() {
            let limits = self.own_move_limits();
            if let Err(e) = self.start_path(Pose::HOME, limits, Purpose::EstopHome) {
                self.home_blocked(e);
                self.servo_power = false;
            }
        }
    }

    /// Starts a checked move.
    fn start(&mut self, segment: Segment) {
        self.motion.start(segment);
        self.returning_home = false;
        self.fault = None;
    }

    /// Commits `candidate` if it is valid and the pose being held can still be driven (and,
    /// with torque ratings, held) with it. New build numbers mean a new geometry and IK: that
    /// is built as a job, a step per slice; so are a torque check and, with pulses set by
    /// `servo`, finding their pose again.
    fn change_settings(&mut self, candidate: Settings) -> Result<Begun, Error> {
        candidate.check_values()?;
        // A stream holds while the job runs (the held pose is what is checked).
        if candidate.layout != self.settings.layout {
            self.holding = self.is_streaming();
            self.job = Some(Job::Rebuild {
                candidate,
                stage: Rebuild::Geometry,
            });
            return Ok(Begun::Pending);
        }
        self.hold_with(candidate, self.solver.clone())
    }

    /// The last step of a settings change: the pose being held with the new settings and
    /// their IK. Committed now, or a job that checks more (the held pose's torques, or the
    /// pose of pulses set by `servo`).
    fn hold_with(&mut self, candidate: Settings, solver: ik::Solver) -> Result<Begun, Error> {
        let torque_changed =
            candidate.payload != self.settings.payload || candidate.layout != self.settings.layout;
        if self.direct.is_some() {
            let pulses_changed = candidate.servos != self.settings.servos
                || candidate.layout != self.settings.layout;
            if !(pulses_changed || (torque_changed && candidate.payload.checked())) {
                self.commit_settings(candidate, solver, self.solution);
                return Ok(Begun::Answered);
            }
            // The pulses stay as they are: where they put the platform is found again.
            let solution = self
                .direct_solution(&candidate, &solver, self.solution.pulse_us)
                .map_err(|cause| Error::PoseConflict { cause })?;
            self.start_locate(Relocate::Settings, candidate, solver, solution);
            return Ok(Begun::Pending);
        }
        let solution = solver
            .solve::<M>(&candidate.servos, self.motion.pose())
            .map_err(|cause| Error::PoseConflict {
                cause: cause.into(),
            })?;
        if torque_changed && candidate.payload.checked() {
            self.holding = self.is_streaming();
            self.job = Some(Job::Rebuild {
                candidate,
                stage: Rebuild::HeldTorque(solver, solution),
            });
            return Ok(Begun::Pending);
        }
        self.commit_settings(candidate, solver, solution);
        Ok(Begun::Answered)
    }

    /// One step of building new settings' geometry and IK, or checking the held pose's
    /// torques: `None` while steps remain, then the outcome (committed, or why not).
    fn rebuild_step(&mut self, candidate: Settings, stage: Rebuild) -> Option<Result<(), Error>> {
        let next = match stage {
            Rebuild::Geometry => match candidate.layout.build_with::<M>() {
                Ok(geometry) => Rebuild::Solver(geometry),
                Err(e) => return Some(Err(SettingError::BadGeometry(e).into())),
            },
            Rebuild::Solver(geometry) => match ik::Solver::new_with::<M>(geometry) {
                Ok(solver) => Rebuild::HeldPose(solver),
                Err(e) => return Some(Err(SettingError::BadGeometry(e).into())),
            },
            Rebuild::HeldPose(solver) => {
                return match self.hold_with(candidate, solver) {
                    Ok(Begun::Answered) => Some(Ok(())),
                    Ok(Begun::Pending) => None, // a job of its own follows
                    Err(e) => Some(Err(e)),
                };
            }
            Rebuild::HeldTorque(solver, solution) => {
                let pose = *self.motion.pose();
                return Some(
                    candidate
                        .payload
                        .check::<M>(&solver, &pose, &solution.arm_rad)
                        .map_err(|cause| Error::PoseConflict {
                            cause: cause.into(),
                        })
                        .map(|()| self.commit_settings(candidate, solver, solution)),
                );
            }
        };
        self.job = Some(Job::Rebuild {
            candidate,
            stage: next,
        });
        None
    }

    /// Commits checked settings, their IK and the pulses to give with them (which change
    /// right away).
    fn commit_settings(&mut self, candidate: Settings, solver: ik::Solver, solution: Solution) {
        self.settings = candidate;
        self.solver = solver;
        self.new_pulses |= solution.pulse_us != self.solution.pulse_us;
        self.solution = solution;
        self.generation = self.generation.wrapping_add(1);
    }

    // ----- servos driven one by one -----

    /// `servo n us`: refused while a move is in progress and with the e-stop on; the pulse
    /// within the servo's limits. Its pose is found (a job); the pulse is given once found.
    fn drive_servo(&mut self, servo: u8, pulse_us: f32) -> Result<Begun, Error> {
        if self.motion.is_moving() {
            return Err(Error::Busy);
        }
        let index = usize::from(servo.clamp(1, LEGS as u8) - 1);
        let config = &self.settings.servos.0[index];
        if !config.allows(pulse_us) {
            return Err(Error::PulseOutsideLimits {
                servo,
                pulse_us,
                min_us: config.min_us,
                max_us: config.max_us,
            });
        }
        let mut pulses = self.safe_pulses();
        pulses[index] = pulse_us;
        let solution = self
            .direct_solution(&self.settings, &self.solver, pulses)
            .map_err(Error::from)?;
        // A stream holds while the pose is found; the command ends it.
        self.holding = self.is_streaming();
        self.start_locate(
            Relocate::Servo,
            self.settings,
            self.solver.clone(),
            solution,
        );
        Ok(Begun::Pending)
    }

    /// The solution of pulses set directly: the pulses, within `settings`' limits, and the arm
    /// angles they command (the inverse of eq. 13, 14).
    fn direct_solution(
        &self,
        settings: &Settings,
        solver: &ik::Solver,
        pulse_us: [f32; LEGS],
    ) -> Result<Solution, PoseError> {
        for (i, (servo, &pulse)) in settings.servos.0.iter().zip(&pulse_us).enumerate() {
            if !servo.allows(pulse) {
                return Err(IkError::ServoLimit {
                    servo: i as u8 + 1,
                    pulse_us: pulse,
                    min_us: servo.min_us,
                    max_us: servo.max_us,
                }
                .into());
            }
        }
        // Finite pulses within valid servo settings: finite angles.
        let arm_rad =
            forward::arm_angles_for_pulses(solver, &settings.servos, &pulse_us).map_err(|_| {
                IkError::NonFinite {
                    axis: kinematics_core::pose::Axis::X,
                }
            })?;
        Ok(Solution { arm_rad, pulse_us })
    }

    /// Starts finding the pose of `solution`'s arm angles (forward kinematics), along the
    /// continuation from the pose the platform was last known at (and the arm angles the IK
    /// gives there) to them ([`FK_STEP_RAD`]).
    fn start_locate(
        &mut self,
        why: Relocate,
        candidate: Settings,
        solver: ik::Solver,
        solution: Solution,
    ) {
        let start = *self.motion.pose();
        let to_rad = solution.arm_rad;
        // Where that pose puts the arms with these settings (if it can: else one solve from
        // there).
        let from_rad = solver.arm_angles::<M>(&start).unwrap_or(to_rad);
        let change = (0..LEGS).fold(0.0f32, |m, i| m.max((to_rad[i] - from_rad[i]).abs()));
        // At most 36 steps: arm angles stay within half a turn of each other.
        let steps = (change / FK_STEP_RAD).clamp(1.0, 36.0) as u8;
        let steps = if f32::from(steps) * FK_STEP_RAD < change {
            steps.saturating_add(1)
        } else {
            steps
        };
        let first = Continuation::arms_at(&from_rad, &to_rad, 1, steps);
        let stage = match forward::Closure::arms::<M>(&solver, &first) {
            Ok(closure) => LocateStage::Newton(Continuation {
                from_rad,
                to_rad,
                step: 1,
                steps,
                newton: Newton::new(closure, start, forward::Options::default()),
            }),
            // (Only for angles that are not finite, which pulses within limits never give.)
            Err(e) => LocateStage::NoPose(e),
        };
        self.job = Some(Job::Locate {
            why,
            candidate,
            solver,
            solution,
            stage,
        });
    }

    /// One step of finding the pose of pulses set directly: a Newton iteration, the IK's
    /// agreement, the holding torques. `None` while steps remain, then the outcome: committed
    /// (with the pose, or knowing there is none), or refused (a servo would be overloaded).
    fn locate_step(
        &mut self,
        why: Relocate,
        candidate: Settings,
        solver: ik::Solver,
        solution: Solution,
        stage: LocateStage,
    ) -> Option<Result<(), Error>> {
        if why == Relocate::Servo && self.estop.stops_motion() {
            // The e-stop opened while the pose was being found: the servo is not driven.
            self.estop_home_after_job();
            return Some(Err(Error::Estop(self.estop)));
        }
        let next = match stage {
            LocateStage::Newton(mut c) => match c.newton.step::<M>() {
                None => LocateStage::Newton(c),
                Some(Ok(found)) if c.step >= c.steps => LocateStage::Arms(found.pose),
                Some(Ok(found)) => {
                    // The next step of the continuation, from this one's pose.
                    c.step += 1;
                    match forward::Closure::arms::<M>(&solver, &c.arms(c.step)) {
                        Ok(closure) => {
                            c.newton =
                                Newton::new(closure, found.pose, forward::Options::default());
                            LocateStage::Newton(c)
                        }
                        Err(e) => LocateStage::NoPose(e),
                    }
                }
                Some(Err(e)) => LocateStage::NoPose(e),
            },
            LocateStage::Arms(pose) => {
                match forward::check_arms::<M>(&solver, &pose, &solution.arm_rad) {
                    Err(e) => LocateStage::NoPose(e),
                    Ok(()) if candidate.payload.checked() => LocateStage::Torque(pose),
                    Ok(()) => {
                        self.commit_direct(why, candidate, solver, solution, Ok(pose));
                        return Some(Ok(()));
                    }
                }
            }
            LocateStage::Torque(pose) => {
                let held = candidate
                    .payload
                    .check::<M>(&solver, &pose, &solution.arm_rad);
                return Some(match (held, why) {
                    (Ok(()), _) => {
                        self.commit_direct(why, candidate, solver, solution, Ok(pose));
                        Ok(())
                    }
                    (Err(e), Relocate::Servo) => Err(Error::Torque(e)),
                    (Err(e), Relocate::Settings) => Err(Error::PoseConflict { cause: e.into() }),
                });
            }
            LocateStage::NoPose(e) => {
                // Pulses that correspond to no pose are given all the same (rods unhooked,
                // calibration): moves are refused until they do again.
                self.commit_direct(why, candidate, solver, solution, Err(e));
                return Some(Ok(()));
            }
        };
        self.job = Some(Job::Locate {
            why,
            candidate,
            solver,
            solution,
            stage: next,
        });
        None
    }

    /// Gives pulses set directly, with their settings, and where they put the platform.
    fn commit_direct(
        &mut self,
        why: Relocate,
        candidate: Settings,
        solver: ik::Solver,
        solution: Solution,
        located: Located,
    ) {
        if why == Relocate::Servo {
            // Like an accepted move: the stream ends, the servos are powered, a fault is
            // cleared.
            self.end_stream();
            self.returning_home = false;
            self.servo_power = true;
            self.fault = None;
        }
        if candidate != self.settings {
            self.generation = self.generation.wrapping_add(1);
        }
        self.settings = candidate;
        self.solver = solver;
        self.new_pulses |= solution.pulse_us != self.solution.pulse_us;
        self.solution = solution;
        if let Ok(pose) = located {
            self.motion = Motion::new(pose);
        }
        self.direct = Some(located);
    }

    fn status(&self) -> StatusReport {
        let hz = f32::from(self.settings.frame_hz);
        let motion = match self.motion.progress() {
            None if self.stream.is_some() => MotionReport::Streaming {
                tracking: self.track_limits() != TrackLimits::OFF,
            },
            None if self.direct.is_some() => MotionReport::Direct,
            None => MotionReport::Idle,
            Some((done, total)) => {
                let (elapsed_s, duration_s) = (done as f32 / hz, total as f32 / hz);
                if self.estop.stops_motion() {
                    MotionReport::EstopHome {
                        elapsed_s,
                        duration_s,
                    }
                } else if self.returning_home {
                    MotionReport::ReturningHome {
                        elapsed_s,
                        duration_s,
                    }
                } else {
                    MotionReport::Moving {
                        elapsed_s,
                        duration_s,
                    }
                }
            }
        };
        StatusReport {
            motion,
            pose: *self.motion.pose(),
            target: *self.motion.target(),
            arm_rad: self.solution.arm_rad,
            pulse_us: self.solution.pulse_us,
            fault: self.fault,
            stream: self.stream_counts,
            estop: self.estop,
            servo_power: self.servo_power,
            pulse_pose: self.direct,
            // Computed in a slice of their own (Job::Status).
            torque_kgcm: None,
        }
    }

    /// The holding torques `status` shows: at its pose, with its arm angles (with pulses set
    /// by `servo` that correspond to no pose, there are none).
    fn status_torques(&self, report: &StatusReport) -> Torques {
        if let Some(Err(e)) = report.pulse_pose {
            return Err(e);
        }
        self.settings
            .payload
            .holding_torques_kgcm::<M>(&self.solver, &report.pose, &report.arm_rad)
    }

    // ----- link loss -----

    fn heard_from_host(&mut self) {
        self.silence_us = None;
        self.link_loss_handled = false;
    }

    fn check_link(&mut self) {
        let timeout_s = self.settings.link_timeout_s;
        if timeout_s <= 0.0 || self.link_loss_handled {
            return;
        }
        // A command being carried out is a sign of life; and one job at a time.
        if self.job.is_some() {
            self.heard_from_host();
            return;
        }
        let silence_us = self.silence_us.unwrap_or(0);
        if (silence_us as f32) < timeout_s * 1e6 {
            return;
        }
        self.link_loss_handled = true;
        if *self.motion.pose() == Pose::HOME && !self.motion.is_moving() {
            return;
        }
        self.end_stream();
        let limits = self.own_move_limits();
        if let Err(e) = self.start_path(Pose::HOME, limits, Purpose::ReturnHome) {
            self.home_blocked(e);
        }
    }

    /// Link loss (or the e-stop's `home`), but home cannot be reached: stop and hold, and say
    /// so.
    fn home_blocked(&mut self, e: Error) {
        self.motion.stop();
        let fault = match e {
            Error::Pose(cause) => Fault::HomeBlocked {
                cause: cause.into(),
            },
            Error::Torque(cause) => Fault::HomeBlocked {
                cause: cause.into(),
            },
            Error::PathBlocked { cause, .. } => Fault::HomeBlocked { cause },
            Error::NoPose(cause) => Fault::NoPose { cause },
            // Only the four above come from a path.
            _ => Fault::HomeBlocked {
                cause: IkError::Unreachable { leg: 0 }.into(),
            },
        };
        self.fault = Some(fault);
        self.notify(Notice::Fault(fault));
    }

    // ----- output helpers -----

    /// Keeps a notice for every link to show (only the latest [`NOTICE_QUEUE`]).
    fn notify(&mut self, notice: Notice) {
        if self.notices.is_full() {
            self.notices.pop_front();
        }
        let _ = self.notices.push_back((self.next_notice, notice));
        self.next_notice = self.next_notice.wrapping_add(1);
    }

    fn has_notices_for(&self, session: &Session) -> bool {
        self.notices
            .back()
            .is_some_and(|(seq, _)| session.has_not_seen(*seq))
    }

    /// Writes the notices `session` has not shown yet.
    fn flush_notices(&self, session: &mut Session, out: &mut impl Write) {
        for (seq, notice) in &self.notices {
            if session.has_not_seen(*seq) {
                report::write_notice(out, notice);
            }
        }
        session.saw_notices_until(self.next_notice);
    }

    /// The last good pulses, guarded once more: finite and within the current limits.
    fn safe_pulses(&self) -> [f32; LEGS] {
        let servos = &self.settings.servos.0;
        core::array::from_fn(|i| {
            let s = &servos[i];
            let w = self.solution.pulse_us[i];
            if w.is_finite() {
                w.clamp(s.min_us, s.max_us)
            } else {
                s.home_us
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::Code;

    fn quiet() -> Controller {
        Controller::new(Settings::default())
    }

    /// A link with echo off, as a program talks.
    fn program() -> Session {
        let mut session = Session::new();
        session.set_echo(false);
        session
    }

    fn run(c: &mut Controller, link: &mut Session, line: &str) -> std::string::String {
        let mut out = std::string::String::new();
        c.execute_line(link, line, &mut out);
        out
    }

    fn notices(c: &Controller, link: &mut Session) -> std::string::String {
        let mut out = std::string::String::new();
        c.write_notices(link, &mut out);
        out
    }

    fn within_limits(c: &Controller, pulses: &[f32; LEGS]) -> bool {
        pulses
            .iter()
            .zip(c.settings().servos.0.iter())
            .all(|(w, s)| w.is_finite() && *w >= s.min_us && *w <= s.max_us)
    }

    /// Reachable, but the straight line between them is not (found by search).
    const FROM: [f32; 6] = [-28.0, 19.0, -2.5, 11.0, 2.0, -20.0];
    const TO: [f32; 6] = [30.0, -12.0, -13.5, 5.0, -13.0, 28.0];

    fn pose_command(v: [f32; 6]) -> std::string::String {
        std::format!("pose {} {} {} {} {} {}", v[0], v[1], v[2], v[3], v[4], v[5])
    }

    fn pose(v: [f32; 6]) -> Pose {
        Pose::from_degrees(v[0], v[1], v[2], v[3], v[4], v[5])
    }

    #[test]
    fn ik_failure_on_a_frame_holds_the_last_good_pulses_and_stops() {
        let (mut c, mut link) = (quiet(), program());
        assert_eq!(run(&mut c, &mut link, &pose_command(FROM)), "ok\r\n");
        while c.is_moving() {
            c.on_frame();
        }
        // Start the blocked move without its path check, as if the check had missed it.
        let segment = Segment::plan(*c.pose(), pose(TO), c.speed_limits(), 50.0);
        assert!(segment
            .check_path(|p| c.solver.solve::<Libm>(&c.settings.servos, p).map(|_| ()))
            .is_err());
        c.start(segment);
        let mut last_good = c.pulses_us();
        let mut frames = 0;
        while c.is_moving() {
            let before = *c.pose();
            let pulses = c.on_frame();
            assert!(within_limits(&c, &pulses), "{pulses:?}");
            if c.is_moving() {
                last_good = pulses;
            } else {
                // The failing frame: nothing new commanded, stopped where the last good was.
                assert_eq!(pulses, last_good);
                assert_eq!(*c.pose(), before);
                assert_eq!(*c.target(), before);
            }
            frames += 1;
        }
        assert!(
            frames < segment.frames(),
            "the move should have failed part way"
        );
        assert!(matches!(c.fault(), Some(Fault::IkFailed { .. })));
        // Holding from now on.
        for _ in 0..10 {
            assert_eq!(c.on_frame(), last_good);
        }
        let out = notices(&c, &mut link);
        assert!(out.starts_with("# fault: motion stopped: "), "{out:?}");
        let status = run(&mut c, &mut link, "status");
        assert!(status.contains("# fault: motion stopped"), "{status}");
        // The next accepted move clears the fault.
        assert_eq!(run(&mut c, &mut link, "home"), "ok\r\n");
        assert!(c.fault().is_none());
    }

    #[test]
    fn link_loss_with_the_way_home_blocked_holds_and_reports() {
        let (mut c, mut link) = (quiet(), program());
        assert_eq!(run(&mut c, &mut link, "set link_timeout_s 0.1"), "ok\r\n");
        // Put the platform at a reachable pose from which the line home is not.
        let stuck = pose([40.0, 20.0, -18.5, -5.0, -16.0, -26.0]);
        c.motion = Motion::new(stuck);
        c.solution = c.solver.solve::<Libm>(&c.settings.servos, &stuck).unwrap();
        let mut out = std::string::String::new();
        for _ in 0..50 {
            let pulses = c.on_frame();
            assert!(within_limits(&c, &pulses));
            // The board's main loop: a slice of the return home's check per pass.
            c.work(&mut link, &mut out);
        }
        assert_eq!(out, "", "the controller's own work replies to nobody");
        assert!(!c.is_moving() && !c.is_busy());
        assert_eq!(*c.pose(), stuck);
        assert!(matches!(c.fault(), Some(Fault::HomeBlocked { .. })));
        let out = notices(&c, &mut link);
        assert!(
            out.starts_with("# fault: link lost but the way home is blocked"),
            "{out:?}"
        );
    }

    #[test]
    fn pulses_are_finite_and_within_limits_even_if_the_solution_were_not() {
        let mut c = quiet();
        c.solution.pulse_us = [f32::NAN, 5000.0, -3.0, 1500.0, f32::INFINITY, 1200.0];
        let w = c.safe_pulses();
        assert!(within_limits(&c, &w), "{w:?}");
        assert_eq!(w[0], c.settings.servos.0[0].home_us);
        assert_eq!(w[1], c.settings.servos.0[1].max_us);
    }

    #[test]
    fn blank_lines_through_execute_line_get_no_reply() {
        let (mut c, mut link) = (quiet(), program());
        assert_eq!(run(&mut c, &mut link, "   "), "");
        assert!(run(&mut c, &mut link, "nonsense")
            .starts_with(&std::format!("error:{} ", Code::UnknownCommand)));
    }

    #[test]
    fn notice_queue_keeps_the_latest() {
        let (mut c, mut link) = (quiet(), program());
        for at_least in 1..=10 {
            c.notify(Notice::InputLost {
                at_least,
                in_uart: false,
            });
        }
        let mut out = std::string::String::new();
        c.write_notices(&mut link, &mut out);
        assert_eq!(out.lines().count(), NOTICE_QUEUE);
        assert!(
            out.contains("at least 10 bytes") && !out.contains("at least 1 byte "),
            "{out}"
        );
        // Shown once per link: the same link gets nothing more, another link gets them too.
        out.clear();
        c.write_notices(&mut link, &mut out);
        assert_eq!(out, "");
        assert_eq!(notices(&c, &mut program()).lines().count(), NOTICE_QUEUE);
    }

    /// Runs the work of `link`'s command to its end, as the board's main loop does.
    fn finish(c: &mut Controller, link: &mut Session, out: &mut std::string::String) {
        while link.awaits_reply() {
            c.work(link, out);
        }
    }

    #[test]
    fn replies_go_to_the_asking_link_and_notices_to_every_link() {
        let mut c = quiet();
        let (mut terminal, mut program) = (Session::new(), program());
        let (mut to_terminal, mut to_program) =
            (std::string::String::new(), std::string::String::new());
        c.banner(&mut terminal, &mut to_terminal);
        c.banner(&mut program, &mut to_program);
        to_terminal.clear();
        to_program.clear();
        // Each link assembles its own line, even interleaved byte by byte.
        for (a, b) in b"home".iter().zip(b"help") {
            c.on_byte(&mut terminal, *a, &mut to_terminal);
            c.on_byte(&mut program, *b, &mut to_program);
        }
        c.on_byte(&mut terminal, b'\r', &mut to_terminal);
        assert!(terminal.awaits_reply() && !program.awaits_reply());
        // The work goes on only with the link that asked.
        c.work(&mut program, &mut to_program);
        assert!(terminal.awaits_reply());
        finish(&mut c, &mut terminal, &mut to_terminal);
        c.on_byte(&mut program, b'\n', &mut to_program);
        finish(&mut c, &mut program, &mut to_program);
        assert_eq!(to_terminal, "home\r\nok\r\n> ");
        assert!(
            to_program.starts_with("# commands") && to_program.ends_with("\r\nok\r\n"),
            "{to_program:?}"
        );
        // Echo is the link's own.
        to_program.clear();
        c.execute_line(&mut program, "set echo on", &mut to_program);
        assert!(program.echo() && terminal.echo());
        c.execute_line(&mut terminal, "set echo off", &mut to_terminal);
        assert!(program.echo() && !terminal.echo());
        // A notice caused by one link reaches both, once each; the typed line is restored.
        to_terminal.clear();
        to_program.clear();
        c.on_byte(&mut program, b's', &mut to_program);
        c.on_input_lost(&mut terminal, 9, false, &mut to_terminal);
        c.write_notices(&mut program, &mut to_program);
        c.write_notices(&mut terminal, &mut to_terminal);
        assert_eq!(
            to_terminal,
            "# warning: receive queue overflowed, input lost (at least 9 bytes so far)\r\n"
        );
        assert_eq!(
            to_program,
            "s\r\n# warning: receive queue overflowed, input lost (at least 9 bytes so far)\r\n> s"
        );
    }

    #[test]
    fn a_reopened_link_starts_afresh_and_shows_only_what_came_while_it_was_closed() {
        let mut c = quiet();
        let mut usb = program();
        let mut out = std::string::String::new();
        c.on_input_lost(&mut usb, 3, false, &mut out);
        for &b in b"pose 1" {
            c.on_byte(&mut usb, b, &mut out);
        }
        // Closed (the host dropped DTR); a notice comes meanwhile, then the host opens again.
        c.notify(Notice::InputLost {
            at_least: 7,
            in_uart: true,
        });
        usb.reopen();
        assert!(usb.echo(), "a new terminal: echo on");
        assert_eq!(usb.typed(), "", "the partial line is abandoned");
        out.clear();
        c.banner(&mut usb, &mut out);
        assert_eq!(
            out,
            std::format!(
                "# hexapod control {}: poses in mm and degrees; type help\r\n\
                 # warning: UART receive error, input lost (at least 7 bytes)\r\n> ",
                report::VERSION
            )
        );
        // The new terminal's first line is a line of its own.
        out.clear();
        for &b in b"home\r" {
            c.on_byte(&mut usb, b, &mut out);
        }
        finish(&mut c, &mut usb, &mut out);
        assert_eq!(out, "home\r\nok\r\n> ");
    }

    #[test]
    fn a_long_path_check_runs_in_slices_and_the_reply_comes_at_its_end() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        c.execute_line(&mut link, "set speed_mm_s 1", &mut out);
        // 20 mm at 1 mm/s: 1000 frames, every one checked.
        for &b in b"pose 20 0 0 0 0 0\n" {
            c.on_byte(&mut link, b, &mut out);
        }
        assert_eq!(out, "ok\r\n", "nothing but the set's reply yet");
        assert!(c.is_busy() && link.awaits_reply() && !c.is_moving());
        let mut slices = 0;
        while link.awaits_reply() {
            // Frames go on between slices; the platform does not move before the reply.
            c.on_frame();
            assert_eq!(*c.pose(), Pose::HOME);
            c.work(&mut link, &mut out);
            slices += 1;
        }
        assert_eq!(out, "ok\r\nok\r\n");
        assert!(c.is_moving() && !c.is_busy());
        // 1000 checks of which the target was solved when the command came, CHECKS_PER_SLICE
        // a slice (and a last slice may find nothing left).
        let full = 999u32.div_ceil(CHECKS_PER_SLICE);
        assert!(slices == full || slices == full + 1, "{slices} slices");
    }

    #[test]
    fn a_move_checked_while_moving_holds_the_platform_then_starts_from_there() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        c.execute_line(&mut link, "set speed_mm_s 1", &mut out);
        c.execute_line(&mut link, "pose 10 0 0 0 0 0", &mut out);
        for _ in 0..100 {
            c.on_frame();
        }
        let here = *c.pose();
        assert!(here.x_mm > 1.9 && here.x_mm < 2.1, "{here:?}");
        for &b in b"move x=-10\n" {
            c.on_byte(&mut link, b, &mut out);
        }
        assert!(link.awaits_reply());
        let pulses = c.on_frame();
        while link.awaits_reply() {
            assert_eq!(c.on_frame(), pulses, "the platform holds during the check");
            assert_eq!(*c.pose(), here);
            c.work(&mut link, &mut out);
        }
        assert!(out.ends_with("ok\r\n"));
        assert_eq!(
            *c.target(),
            Pose::from_degrees(-10.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        );
        c.on_frame();
        assert!(
            c.pose().x_mm < here.x_mm,
            "moving towards the new target from where it held"
        );
        // A refused move lets the move in progress go on, from where it held.
        out.clear();
        let before = *c.target();
        for &b in b"move z=80\n" {
            c.on_byte(&mut link, b, &mut out);
        }
        assert!(out.starts_with("error:unreachable"), "{out}");
        assert_eq!(*c.target(), before);
        let held = *c.pose();
        c.on_frame();
        assert!(c.pose().x_mm < held.x_mm);
    }

    #[test]
    fn check_runs_in_slices_without_holding_a_move() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        c.execute_line(&mut link, "set speed_mm_s 1", &mut out);
        c.execute_line(&mut link, "pose 10 0 0 0 0 0", &mut out);
        out.clear();
        for &b in b"check -10 0 0 0 0 0\n" {
            c.on_byte(&mut link, b, &mut out);
        }
        let mut last = *c.pose();
        while link.awaits_reply() {
            c.on_frame();
            assert!(c.pose().x_mm > last.x_mm, "the move goes on during a check");
            last = *c.pose();
            c.work(&mut link, &mut out);
        }
        assert!(
            out.starts_with("# arm_deg: ") && out.ends_with("ok\r\n"),
            "{out}"
        );
        assert_eq!(
            *c.target(),
            Pose::from_degrees(10.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        );
    }

    #[test]
    fn a_line_sent_before_the_reply_is_refused_not_lost() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        for &b in b"status\nhome\n" {
            c.on_byte(&mut link, b, &mut out);
        }
        assert_eq!(
            out,
            "error:busy the previous command is still being carried out; wait for its reply\r\n"
        );
        finish(&mut c, &mut link, &mut out);
        assert!(
            out.contains("# pulse_us: 1500.00 1500.00 1500.00 1500.00 1500.00 1500.00\r\n"),
            "{out}"
        );
        assert!(out.ends_with("# servo_power: off\r\nok\r\n"), "{out}");
    }

    #[test]
    fn a_listing_is_written_a_line_per_slice() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        for &b in b"config\n" {
            c.on_byte(&mut link, b, &mut out);
        }
        let mut lines = std::vec::Vec::new();
        while link.awaits_reply() {
            let before = out.len();
            c.work(&mut link, &mut out);
            lines.push(out[before..].matches("\r\n").count());
        }
        // The global settings, 6 servos, whether they are saved, then the reply.
        assert_eq!(lines.len(), SettingId::GLOBAL.len() + 6 + 1 + 1);
        assert!(lines.iter().all(|&n| n == 1), "{lines:?}");
        assert!(out.ends_with("ok\r\n"));
    }

    #[test]
    fn new_build_numbers_are_built_a_step_per_slice() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        let h0 = c.geometry().home_height_mm();
        for &b in b"set rod_mm 125\n" {
            c.on_byte(&mut link, b, &mut out);
        }
        assert!(link.awaits_reply() && out.is_empty());
        let mut slices = 0;
        while link.awaits_reply() {
            assert_eq!(
                c.settings().layout.rod_mm,
                120.0,
                "committed only at the end"
            );
            c.work(&mut link, &mut out);
            slices += 1;
        }
        assert_eq!((slices, out.as_str()), (3, "ok\r\n"));
        assert_eq!(c.settings().layout.rod_mm, 125.0);
        assert!(c.geometry().home_height_mm() > h0 + 4.0);
        // A build that cannot be is refused at the step that finds it; nothing changes.
        out.clear();
        let before = *c.settings();
        c.execute_line(&mut link, "set rod_mm 15", &mut out);
        assert!(out.starts_with("error:bad-geometry "), "{out}");
        assert_eq!(*c.settings(), before);
        // A value out of range is refused at once, before any step.
        out.clear();
        for &b in b"set rod_mm 3000\n" {
            c.on_byte(&mut link, b, &mut out);
        }
        assert!(!link.awaits_reply() && out.starts_with("error:out-of-range "));
    }

    #[test]
    fn link_loss_never_comes_before_the_timeout() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        // 50 Hz: 20 ms frames; 0.1 s is 5 frames, counted from the first frame after the line.
        c.execute_line(&mut link, "set link_timeout_s 0.1", &mut out);
        c.execute_line(&mut link, "pose 0 0 1 0 0 0", &mut out);
        while c.is_moving() {
            c.on_frame();
        }
        c.execute_line(&mut link, "status", &mut out);
        // The line ended somewhere inside the current frame: that frame counts nothing.
        for frame in 1..=5 {
            c.on_frame();
            assert!(
                !c.is_busy() && !c.is_moving(),
                "link loss after {frame} frames"
            );
        }
        c.on_frame();
        assert!(
            c.is_busy(),
            "the return home is being checked after 6 frames"
        );
        while c.is_busy() {
            c.work(&mut link, &mut out);
        }
        assert!(c.is_moving());
        assert!(notices(&c, &mut link).starts_with("# link lost: no command for 0.1 s"));
    }

    #[test]
    fn the_prompt_after_a_baud_change_waits_for_the_switch() {
        let mut c = quiet();
        let mut terminal = Session::new();
        let mut out = std::string::String::new();
        for &b in b"set baud 230400\r" {
            c.on_byte(&mut terminal, b, &mut out);
        }
        assert_eq!(out, "set baud 230400\r\nok\r\n", "nothing after the ok");
        terminal.write_deferred_prompt(&mut out);
        assert!(out.ends_with("ok\r\n> "));
        terminal.write_deferred_prompt(&mut out);
        assert!(out.ends_with("ok\r\n> "), "once");
        // Unchanged rate: no switch, so the prompt comes at once.
        out.clear();
        for &b in b"set baud 230400\r" {
            c.on_byte(&mut terminal, b, &mut out);
        }
        assert!(out.ends_with("ok\r\n> "));
    }
}
