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
//!   fails on a frame, the last good pulses are held and the motion stops (a fault notice).
//!
//! Latency: with both speed limits off a move is a jump, and a jump is made at once: the
//! command's reply is followed by new pulses from [`Controller::take_new_pulses`], which the
//! board writes right away instead of at the next frame (hobby-servo PWM latches new compare
//! values at the next period, so nothing is cut short). Streaming hosts use this mode. With a
//! speed limit set the first step comes with the next frame (up to one frame later), because
//! writing it early could put two steps into one frame and exceed the limit.
//!
//! Link loss: with `link_timeout_s` set, when that long passes without a completed non-blank
//! line (any line, valid or not, counts as a sign of life), the platform returns home at the
//! configured speeds (a group whose speed is off uses [`LINK_LOSS_SPEED_MM_S`] /
//! [`LINK_LOSS_SPEED_DEG_S`] so it never jumps). It fires once per silence.

use core::fmt::Write;
use core::marker::PhantomData;

use kinematics_core::ik::{self, IkError, Solution};
use kinematics_core::{Geometry, Libm, Math, Pose, LEGS};

use crate::command::{self, Command};
use crate::error::Error;
use crate::motion::{Motion, Segment, SpeedLimits};
use crate::protocol::Feed;
use crate::report::{self, Fault, MotionReport, Notice, StatusReport, EOL};
use crate::session::Session;
use crate::settings::{LinkSettings, SettingId, SettingValue, Settings, DEFAULT_BAUD};

/// Linear speed for returning home after link loss when `speed_mm_s` is off, mm/s.
pub const LINK_LOSS_SPEED_MM_S: f32 = 10.0;
/// Angular speed for returning home after link loss when `speed_deg_s` is off, deg/s.
pub const LINK_LOSS_SPEED_DEG_S: f32 = 15.0;

/// Notices kept for links that have not shown them yet (the latest ones).
const NOTICE_QUEUE: usize = 4;

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
    /// Time since the last completed line, us.
    silence_us: u32,
    /// Link loss already handled for this silence.
    link_loss_handled: bool,
    /// The last fault, until the next accepted move.
    fault: Option<Fault>,
    /// The commanded pulses changed outside a frame (see [`Controller::take_new_pulses`]).
    new_pulses: bool,
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
            silence_us: 0,
            link_loss_handled: false,
            fault: None,
            new_pulses: false,
            notices: heapless::Deque::new(),
            next_notice: 0,
            _math: PhantomData,
        })
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

    /// True while a move is in progress.
    pub fn is_moving(&self) -> bool {
        self.motion.is_moving()
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

    /// The pulses to write now if a command changed them outside a frame (a jump, or a
    /// settings change that moves the held pose's pulses), once; `None` otherwise. Finite and
    /// within the servo limits, like [`Controller::on_frame`]'s.
    pub fn take_new_pulses(&mut self) -> Option<[f32; LEGS]> {
        core::mem::take(&mut self.new_pulses).then(|| self.safe_pulses())
    }

    // ----- what the board calls -----

    /// Writes the start-up banner (and any notice, e.g. refused settings), then the prompt, to
    /// one link.
    pub fn banner(&self, session: &mut Session, out: &mut impl Write) {
        report::write_banner(out);
        self.flush_notices(session, out);
        session.prompt(out);
    }

    /// Feeds one byte received on `session`'s link: echo and line editing; at the end of a
    /// line, runs it and writes exactly one final reply to that link (blank lines get none).
    pub fn on_byte(&mut self, session: &mut Session, byte: u8, out: &mut impl Write) {
        match session.feed(byte, out) {
            Feed::Line => {
                // Copied out so the link can take the next line while the command runs.
                let line = session.take_line();
                self.execute_line(session, &line, out);
                session.prompt(out);
            }
            Feed::Spoiled(why) => {
                self.heard_from_host();
                self.flush_notices(session, out);
                report::write_error(out, &Error::from(why));
                session.prompt(out);
            }
            Feed::Empty | Feed::Cancelled => session.prompt(out),
            _ => {}
        }
    }

    /// `session`'s link lost `dropped` received bytes: the line being received there is refused
    /// when it ends (`error:rx-overflow`), and a warning goes to every link (to this one now).
    pub fn on_rx_overflow(&mut self, session: &mut Session, dropped: u32, out: &mut impl Write) {
        session.rx_overflow(dropped);
        self.notify(Notice::RxOverflow { dropped });
        self.write_notices(session, out);
    }

    /// Writes the notices (faults, link loss, warnings) this link has not shown yet, restoring
    /// the prompt and the line being typed when echo is on. Call it for every link after
    /// anything that may notify (a frame, a receive overflow); notices pending for a link are
    /// also written before its next reply.
    pub fn write_notices(&self, session: &mut Session, out: &mut impl Write) {
        if !self.has_notices_for(session) {
            return;
        }
        if session.echo() {
            let _ = out.write_str(EOL);
        }
        self.flush_notices(session, out);
        if session.echo() {
            session.prompt(out);
            let _ = out.write_str(session.typed());
        }
    }

    /// Advances by one frame (`1 / frame_hz` s): link-loss timer, motion, IK. Returns the six
    /// pulse widths (us, servo 1 first), always finite and within each servo's limits.
    pub fn on_frame(&mut self) -> [f32; LEGS] {
        let frame_us = 1_000_000 / u32::from(self.settings.frame_hz.max(1));
        self.silence_us = self.silence_us.saturating_add(frame_us);
        self.check_link();

        if !self.motion.is_moving() {
            // Standing still: the held pose's pulses are solved already (when it was reached or
            // the settings changed), and the IK is deterministic. This keeps idle frames cheap,
            // so a frame never delays a command much.
            return self.safe_pulses();
        }
        let next = self.motion.next_pose();
        match self.solver.solve::<M>(&self.settings.servos, &next) {
            Ok(solution) => {
                self.motion.commit();
                self.solution = solution;
                if !self.motion.is_moving() {
                    self.returning_home = false;
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

    /// Runs one line as if it had been typed on `session`'s link (any case, blank lines
    /// ignored) and writes its replies there; for transports other than the byte stream.
    pub fn execute_line(&mut self, session: &mut Session, line: &str, out: &mut impl Write) {
        if line.bytes().all(|b| b == b' ' || b == b'\t') {
            return;
        }
        self.heard_from_host();
        self.flush_notices(session, out);
        let result = command::parse(line)
            .map_err(Error::from)
            .and_then(|cmd| self.run(session, cmd, out));
        match result {
            Ok(()) => report::write_ok(out),
            Err(e) => report::write_error(out, &e),
        }
    }

    // ----- commands -----

    fn run(
        &mut self,
        session: &mut Session,
        cmd: Command,
        out: &mut impl Write,
    ) -> Result<(), Error> {
        match cmd {
            Command::Pose(target) => self.move_to(target),
            Command::Move(values) => self.move_to(values.apply(self.motion.target(), false)),
            Command::Nudge(values) => self.move_to(values.apply(self.motion.target(), true)),
            Command::Home => self.move_to(Pose::HOME),
            Command::Check(target) => {
                let (solution, segment) = self.plan(target, self.speed_limits())?;
                let duration_s = segment.frames() as f32 / f32::from(self.settings.frame_hz);
                let duration_s = if segment.start() == segment.target() {
                    0.0
                } else {
                    duration_s
                };
                report::write_check(out, &solution.arm_rad, &solution.pulse_us, duration_s);
                Ok(())
            }
            Command::Stop => {
                self.motion.stop();
                self.returning_home = false;
                Ok(())
            }
            Command::Status => {
                report::write_status(out, &self.status());
                Ok(())
            }
            Command::Geometry => {
                report::write_geometry(out, &self.settings, &self.solver);
                Ok(())
            }
            Command::Config => {
                let link = LinkSettings {
                    baud: self.baud,
                    echo: session.echo(),
                };
                report::write_config(out, &self.settings, &link);
                Ok(())
            }
            Command::Help => {
                report::write_help(out);
                Ok(())
            }
            Command::Set(SettingId::Echo, SettingValue::Flag(on)) => {
                session.set_echo(on);
                Ok(())
            }
            Command::Set(SettingId::Baud, SettingValue::Whole(baud)) => {
                self.baud = baud;
                self.generation = self.generation.wrapping_add(1);
                Ok(())
            }
            Command::Set(id, value) => {
                let moves_matter = matches!(
                    id,
                    SettingId::FrameHz | SettingId::Layout(_) | SettingId::Servo(..)
                );
                if moves_matter && self.motion.is_moving() {
                    return Err(Error::Busy);
                }
                self.change_settings(self.settings.with(id, value))
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

    fn speed_limits(&self) -> SpeedLimits {
        SpeedLimits {
            mm_per_s: self.settings.speed_mm_s,
            deg_per_s: self.settings.speed_deg_s,
        }
    }

    /// Checks a target and the straight path to it from the current pose.
    fn plan(&self, target: Pose, limits: SpeedLimits) -> Result<(Solution, Segment), Error> {
        // The target itself first: its error is the most useful one.
        let solution = self.solver.solve::<M>(&self.settings.servos, &target)?;
        let segment = Segment::plan(
            *self.motion.pose(),
            target,
            limits,
            f32::from(self.settings.frame_hz),
        );
        segment
            .check_path(|p| {
                if *p == target {
                    return Ok(()); // solved above
                }
                self.solver.solve::<M>(&self.settings.servos, p).map(|_| ())
            })
            .map_err(|e| Error::PathBlocked {
                percent: e.fraction * 100.0,
                cause: e.error,
            })?;
        Ok((solution, segment))
    }

    fn move_to(&mut self, target: Pose) -> Result<(), Error> {
        let limits = self.speed_limits();
        let (solution, segment) = self.plan(target, limits)?;
        if limits.mm_per_s > 0.0 || limits.deg_per_s > 0.0 {
            self.start(segment);
        } else {
            // No speed limit: a jump, made now (see the module docs on latency).
            self.motion = Motion::new(target);
            self.solution = solution;
            self.new_pulses = true;
            self.returning_home = false;
            self.fault = None;
        }
        Ok(())
    }

    /// Starts a checked move.
    fn start(&mut self, segment: Segment) {
        self.motion.start(segment);
        self.returning_home = false;
        self.fault = None;
    }

    fn change_settings(&mut self, candidate: Settings) -> Result<(), Error> {
        // A new geometry and IK only if the build numbers changed (that is the slow part).
        let solver = if candidate.layout == self.settings.layout {
            candidate.check_values()?;
            self.solver.clone()
        } else {
            candidate.validate_with::<M>()?
        };
        // The pose being held must stay drivable (and the pulses change right away).
        let solution = solver
            .solve::<M>(&candidate.servos, self.motion.pose())
            .map_err(|cause| Error::PoseConflict { cause })?;
        self.settings = candidate;
        self.solver = solver;
        self.new_pulses |= solution.pulse_us != self.solution.pulse_us;
        self.solution = solution;
        self.generation = self.generation.wrapping_add(1);
        Ok(())
    }

    fn status(&self) -> StatusReport<'_> {
        let hz = f32::from(self.settings.frame_hz);
        let motion = match self.motion.progress() {
            None => MotionReport::Idle,
            Some((done, total)) => {
                let (elapsed_s, duration_s) = (done as f32 / hz, total as f32 / hz);
                if self.returning_home {
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
            pose: self.motion.pose(),
            target: self.motion.target(),
            arm_rad: &self.solution.arm_rad,
            pulse_us: &self.solution.pulse_us,
            fault: self.fault.as_ref(),
        }
    }

    // ----- link loss -----

    fn heard_from_host(&mut self) {
        self.silence_us = 0;
        self.link_loss_handled = false;
    }

    fn check_link(&mut self) {
        let timeout_s = self.settings.link_timeout_s;
        if timeout_s <= 0.0 || self.link_loss_handled {
            return;
        }
        if (self.silence_us as f32) < timeout_s * 1e6 {
            return;
        }
        self.link_loss_handled = true;
        if *self.motion.pose() == Pose::HOME && !self.motion.is_moving() {
            return;
        }
        let or = |v: f32, fallback: f32| if v > 0.0 { v } else { fallback };
        let limits = SpeedLimits {
            mm_per_s: or(self.settings.speed_mm_s, LINK_LOSS_SPEED_MM_S),
            deg_per_s: or(self.settings.speed_deg_s, LINK_LOSS_SPEED_DEG_S),
        };
        match self.plan(Pose::HOME, limits) {
            Ok((_, segment)) => {
                self.start(segment);
                self.returning_home = true;
                self.notify(Notice::LinkLost { timeout_s });
            }
            Err(e) => {
                self.motion.stop();
                let cause = match e {
                    Error::Pose(cause) | Error::PathBlocked { cause, .. } => cause,
                    // `plan` only fails with the two above.
                    _ => IkError::Unreachable { leg: 0 },
                };
                let fault = Fault::HomeBlocked { cause };
                self.fault = Some(fault);
                self.notify(Notice::Fault(fault));
            }
        }
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
        for _ in 0..20 {
            let pulses = c.on_frame();
            assert!(within_limits(&c, &pulses));
        }
        assert!(!c.is_moving());
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
        for dropped in 1..=10 {
            c.notify(Notice::RxOverflow { dropped });
        }
        let mut out = std::string::String::new();
        c.write_notices(&mut link, &mut out);
        assert_eq!(out.lines().count(), NOTICE_QUEUE);
        assert!(
            out.contains("10 bytes") && !out.contains(" 1 bytes"),
            "{out}"
        );
        // Shown once per link: the same link gets nothing more, another link gets them too.
        out.clear();
        c.write_notices(&mut link, &mut out);
        assert_eq!(out, "");
        assert_eq!(notices(&c, &mut program()).lines().count(), NOTICE_QUEUE);
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
        for (a, b) in b"home\r".iter().zip(b"help\n") {
            c.on_byte(&mut terminal, *a, &mut to_terminal);
            c.on_byte(&mut program, *b, &mut to_program);
        }
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
        c.on_rx_overflow(&mut terminal, 9, &mut to_terminal);
        c.write_notices(&mut program, &mut to_program);
        c.write_notices(&mut terminal, &mut to_terminal);
        assert_eq!(
            to_terminal,
            "# warning: receive queue overflowed, 9 bytes lost\r\n"
        );
        assert_eq!(
            to_program,
            "s\r\n# warning: receive queue overflowed, 9 bytes lost\r\n> s"
        );
    }
}
