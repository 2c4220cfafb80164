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
//! One job at a time: while [`Controller::is_busy`], the board feeds no bytes (they wait in the
//! link's receive queue, or the USB host waits). A move checked while the platform moves (or a
//! stream is tracked), with an acceleration limit set, is a blend ([`crate::motion::blend`],
//! within the servos' rated speeds if they have any): the motion goes on while it is checked,
//! and it takes over at a hand-over frame planned ahead (`moves.rs`). Without an acceleration
//! limit (or while a stream is passed through), the platform holds where it was when the command
//! arrived until the check ends (a few milliseconds; at most about 150 ms on the RP2040 for the
//! longest check), then starts from there. A refused move lets the move in progress go on.
//! `check` does not hold anything.
//!
//! This file holds the state, the public API and the dispatch: a line to its command
//! ([`Controller::on_byte`]), a slice to the job in progress ([`Controller::work`]), a frame to
//! the motion ([`Controller::on_frame`]). Each job is a state machine of its own type with a
//! `step` (a slice), in a file of its own that knows nothing of the controller:
//! - `path.rs`: a target's straight path checked, a few poses per slice;
//! - `stream_goal.rs`: what a stream follows, and the clamp of a target out of reach;
//! - `locate.rs`: the pose of pulses set directly (`servo`), by forward kinematics;
//! - `rebuild.rs`: new build numbers' geometry and IK;
//! - `save.rs`: the flash write the board performs;
//! - `listing.rs` (a listing a line per slice, `status`' torques), `limits.rs` (`limits`);
//! - `pose_check.rs`: whether a pose can be taken (IK, torque ratings), shared by the above.
//!
//! What their outcomes do to the platform, and the controller's other jobs, are `impl
//! Controller` blocks of their own: `moves.rs` (moves, `check`, jumps), `streaming.rs`,
//! `servo.rs`, `servo_speed.rs` (moves and stream steps within the servos' rated speeds),
//! `settings_change.rs`, `link_loss.rs`, `estop.rs`, `status.rs` and `notices.rs`.

use core::fmt::Write;
use core::marker::PhantomData;

use kinematics_core::ik::{self, Solution};
use kinematics_core::{Geometry, KinematicsError, Libm, Math, Pose, LEGS};

use crate::command::{self, Command, ParseError};
use crate::error::Error;
use crate::motion::Motion;
use crate::protocol::{Feed, Lost};
use crate::report::{self, Fault, Listing, Notice, Saved, StreamCounts, EOL};
use crate::safety::Estop;
use crate::session::Session;
use crate::settings::{LinkSettings, SettingId, SettingValue, Settings, DEFAULT_BAUD};
use crate::store::{self, Found, Loaded, SaveError, Store};

use self::limits::LimitsSearch;
use self::listing::{StatusTorques, Writing};
use self::locate::{Locate, Located};
use self::loss_burst::LossBurst;
use self::path::{PathCheck, Purpose};
use self::pose_check::PoseCheck;
use self::rebuild::Rebuild;
use self::save::Save;
use self::stream_goal::{Clamp, Streaming};

pub use self::locate::FK_STEP_RAD;
pub use self::pose_check::CHECKS_PER_SLICE;
pub use self::stream_goal::CLAMP_STEPS;

// The jobs: state machines that know nothing of the controller.
mod limits;
mod listing;
mod locate;
mod loss_burst;
mod path;
mod pose_check;
mod rebuild;
mod save;
mod stream_goal;

// What the controller does with them, and its other work: `impl Controller` blocks.
mod estop;
mod link_loss;
mod moves;
mod notices;
mod servo;
mod servo_speed;
mod settings_change;
mod status;
mod streaming;

#[cfg(test)]
mod test_support;

/// Linear speed for returning home after link loss (`link_loss.rs`) when `speed_mm_s` is off,
/// mm/s.
pub const LINK_LOSS_SPEED_MM_S: f32 = 10.0;
/// Angular speed for returning home after link loss when `speed_deg_s` is off, deg/s.
pub const LINK_LOSS_SPEED_DEG_S: f32 = 15.0;

/// Path checks per frame assumed before any was measured (see `moves.rs`, blends).
const INITIAL_CHECK_RATE: u32 = 16;

/// Notices kept for links that have not shown them yet (the latest ones).
const NOTICE_QUEUE: usize = 4;

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

/// A command's work left for later slices ([`Controller::work`]), or the controller's own;
/// each advanced where it is held, a slice at a time, by its own `step`.
// No heap to box the large variants into: there is one job at a time, held in place (moving
// one whose candidate settings and IK are over 1.6 KB costs the RP2040 thousands of cycles, a
// good part of a slice's IK).
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
enum Job {
    /// A reachable target whose straight path is being checked.
    Path(PathCheck),
    /// A listing being written, a line per slice.
    Listing(Writing),
    /// `status` with a payload: the holding torques are computed (a slice), then listed.
    Status(StatusTorques),
    /// `limits`: the reach along each axis-direction, a few poses per slice.
    Limits(LimitsSearch),
    /// Pulses whose pose is being found (forward kinematics, a Newton iteration per slice),
    /// and the settings they go with; committed when found (or found to be no pose).
    Locate(Locate),
    /// New settings with new build numbers: their geometry and IK are built a step per slice.
    Rebuild(Rebuild),
    /// `save`: the flash write the board performs, and its outcome.
    Save(Save),
    /// An unreachable stream target being clamped, a few IK solutions per slice (the
    /// controller's own work: no reply); with torque ratings, a reachable one whose holding
    /// torques are checked first.
    Clamp(Clamp),
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
    /// UART0's baud rate (a link setting: `defaults` keeps it, `save` saves it).
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
    /// The motion holds still until the job's check ends (a move checked while moving, no
    /// blend).
    holding: bool,
    /// Path checks a frame has been seen to fit (a blend's hand-over is put that far ahead),
    /// and how many the last blend needed.
    check_rate: u32,
    blend_checks: u32,
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
    /// A burst of UART receive errors going on: its first loss was announced, the others are
    /// counted for one notice when it ends.
    uart_burst: Option<LossBurst>,
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
            check_rate: INITIAL_CHECK_RATE,
            blend_checks: 0,
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
            uart_burst: None,
            _math: PhantomData,
        })
    }

    /// The controller at power-up, from what the flash holds ([`Store::load`]): the newest
    /// good saved settings and UART0's baud rate, or the defaults; a warning notice says why
    /// when it is not simply the last save (nothing saved, a copy that cannot be used). Saved settings these maths
    /// cannot drive are replaced by the defaults too (see [`Controller::with_math`]).
    pub fn power_up(loaded: Loaded) -> Self {
        let Loaded { store, found } = loaded;
        let mut c = Self::with_math(store.saved().copied().unwrap_or_default());
        // UART0 opens at the saved rate (the USB port answers whatever it is).
        c.baud = store.saved_baud().unwrap_or(DEFAULT_BAUD);
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
        matches!(&self.job, Some(Job::Save(save)) if save.awaits_flash())
    }

    /// The flash write a `save` asks for, once: the board performs it
    /// ([`store::Write::perform`]: erase the sector, program the page, read it back) and hands
    /// the outcome to [`Controller::flash_written`]; the reply follows in [`Controller::work`].
    pub fn take_flash_write(&mut self) -> Option<store::Write> {
        match &mut self.job {
            Some(Job::Save(save)) => save.take_write(),
            _ => None,
        }
    }

    /// The outcome of the flash write taken with [`Controller::take_flash_write`] (ignored if
    /// none was taken).
    pub fn flash_written(&mut self, result: Result<(), SaveError>) {
        if let Some(Job::Save(save)) = &mut self.job {
            save.written(result);
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
                // Parsed where it lies (nothing copied), then the link's buffer is free for the
                // next line while the command runs.
                let parsed = parse_line(session.typed());
                session.clear_line();
                if self.begin_line(session, parsed, out) == Begun::Answered {
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
        self.apply_newest_frame();
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
        if self.begin_line(session, parse_line(line), out) == Begun::Pending {
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
        let commanded = match &self.job {
            Some(Job::Path(path)) => !path.purpose.is_own(),
            Some(Job::Clamp(_)) => false,
            _ => true,
        };
        if commanded && !session.awaits_reply() {
            return;
        }
        let Some(done) = self.step_job(out) else {
            return;
        };
        self.holding = false;
        match done {
            Done::List(listing) => self.job = Some(Job::Listing(Writing::new(listing))),
            Done::Quiet => {}
            Done::Ok => self.reply(session, Ok(()), out),
            Done::Refused(e) => self.reply(session, Err(e), out),
        }
    }

    /// A slice of the job in progress, advanced where it is held by its own `step` (see
    /// [`Job`]; when it ends, only what its outcome needs is copied or moved out): `None` while
    /// it goes on, else how it ended (and it is gone, or a job that follows from it has taken
    /// its place).
    fn step_job(&mut self, out: &mut impl Write) -> Option<Done> {
        let check = PoseCheck {
            settings: &self.settings,
            solver: &self.solver,
        };
        match self.job.as_mut()? {
            Job::Path(path) if path.replan => {
                // Planned (again) from the motion as it is now, in a slice of its own.
                self.replan();
                None
            }
            Job::Path(path) => {
                let result = path.step::<M>(check)?;
                // What follows needs only part of it, copied out (not the whole job, which
                // `take` would move, nor the whole check).
                let checked = path.checked();
                // (`check` takes nothing over: what it checked is what it reports.)
                let missed = result.is_ok()
                    && checked.purpose != Purpose::Check
                    && !self.estop.stops_motion()
                    && self.missed_hand_over(&checked);
                self.learn_check_rate(&checked, missed);
                if missed {
                    // Too late to take over as planned: planned (next slice) and checked again.
                    if let Some(Job::Path(path)) = &mut self.job {
                        *path = path.to_replan();
                    }
                    return None;
                }
                self.job = None;
                Some(self.finish_path(&checked, result))
            }
            Job::Clamp(clamp) => {
                let (pose, solution) = clamp.step::<M>(check, &mut self.stream_counts)?;
                self.job = None;
                self.reach_stream_goal(pose, solution);
                Some(Done::Quiet)
            }
            Job::Listing(writing) => {
                if writing.step(check.settings, check.solver, out) {
                    return None;
                }
                self.job = None;
                Some(Done::Ok)
            }
            Job::Status(status) => {
                let listing = status.step::<M>(check);
                self.job = None;
                Some(Done::List(listing))
            }
            Job::Limits(limits) => {
                let listing = limits.step::<M>(check)?;
                self.job = None;
                Some(Done::List(listing))
            }
            Job::Locate(_) => self.locate_slice(),
            Job::Rebuild(_) => self.rebuild_slice(),
            Job::Save(save) => {
                let outcome = save.step()?;
                self.job = None;
                Some(match outcome {
                    Ok(write) => {
                        self.store.commit(&write);
                        Done::Ok
                    }
                    Err(e) => Done::Refused(Error::SaveFailed(e)),
                })
            }
        }
    }

    /// Bytes were lost on their way in (a receive queue was full, or the UART saw an overrun,
    /// framing, parity or break error) and the board has just noticed: a warning goes to every
    /// link at once (to this one now). `at_least` bytes so far; `in_uart`: the UART's
    /// hardware lost them (it cannot tell how many). The line they cut is refused when the
    /// board reaches the gap ([`Controller::on_rx_overflow`]). UART losses come in bursts (a
    /// sender at the wrong baud rate garbles every few bytes): only the first of a burst is
    /// announced at once, the rest counted for one notice when the burst ends
    /// ([`BURST_QUIET_US`](loss_burst::BURST_QUIET_US) without a loss).
    pub fn on_input_lost(
        &mut self,
        session: &mut Session,
        at_least: u32,
        in_uart: bool,
        out: &mut impl Write,
    ) {
        if in_uart && self.count_in_burst(at_least) {
            return;
        }
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
        self.time_burst(frame_us);

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

    /// Starts a line (parsed by [`parse_line`]; `None`: blank, no reply): its reply at once,
    /// or a job whose reply comes later.
    fn begin_line(
        &mut self,
        session: &mut Session,
        parsed: Option<Result<Command, ParseError>>,
        out: &mut impl Write,
    ) -> Begun {
        let Some(parsed) = parsed else {
            return Begun::Answered;
        };
        self.heard_from_host();
        self.flush_notices(session, out);
        if self.job.is_some() {
            report::write_error(out, &Error::Pending);
            return Begun::Answered;
        }
        let result = parsed
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
                    self.job = Some(Job::Status(StatusTorques(report)));
                    Ok(Begun::Pending)
                } else {
                    Ok(self.list(Listing::Status(report)))
                }
            }
            // What the PWM outputs now: the same guard as on_frame's.
            Command::Pulses => Ok(self.list(Listing::Pulses(self.safe_pulses()))),
            Command::Limits => {
                if let Some(Err(e)) = self.direct {
                    return Err(Error::NoPose(e));
                }
                self.job = Some(Job::Limits(LimitsSearch::new(*self.motion.pose())));
                Ok(Begun::Pending)
            }
            Command::Servo { servo, pulse_us } => self.drive_servo(servo, pulse_us),
            Command::Geometry => Ok(self.list(Listing::Geometry)),
            Command::Config => {
                let saved = match self.store.newest() {
                    None => Saved::Nothing,
                    Some((_, r)) if r.settings == self.settings && r.baud == self.baud => {
                        Saved::Same
                    }
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
                        | SettingId::Pivot(_)
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
                // The platform's settings and UART0's rate; echo stays the links' own (see
                // crate::record).
                let write = self.store.prepare(&self.settings, self.baud);
                self.job = Some(Job::Save(Save::new(write)));
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
        self.job = Some(Job::Listing(Writing::new(listing)));
        Begun::Pending
    }

    /// The last good pulses, guarded once more: finite and within the current limits.
    fn safe_pulses(&self) -> [f32; LEGS] {
        let servos = &self.settings.servos.0;
        core::array::from_fn(|i| {
            let s = &servos[i];
            let w = self.solution.pulse_us[i];
            // `clamp` by `total_cmp` (integer instructions; float comparisons are library
            // calls on the RP2040): the same for a finite pulse and limits (min < max).
            if w.to_bits() & 0x7f80_0000 == 0x7f80_0000 {
                s.home_us
            } else if w.total_cmp(&s.min_us).is_lt() {
                s.min_us
            } else if w.total_cmp(&s.max_us).is_gt() {
                s.max_us
            } else {
                w
            }
        })
    }
}

/// A received line as a command: `None` for a blank one (spaces and tabs only, no reply), else
/// [`command::parse`]'s answer.
fn parse_line(line: &str) -> Option<Result<Command, ParseError>> {
    if line.bytes().all(|b| b == b' ' || b == b'\t') {
        None
    } else {
        Some(command::parse(line))
    }
}

#[cfg(test)]
mod tests {
    use super::test_support::*;
    use super::*;
    use crate::motion::Segment;
    use crate::report::Code;

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
