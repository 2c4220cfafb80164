//! Moves: `pose`, `move`, `nudge`, `home` (and `check`, and the controller's own ways home)
//! check their target at once (its error is the most useful one), then the straight path to it
//! as a job ([`PathCheck`]); what a checked path leads to is here: the move started, a jump
//! made, `check`'s listing, the way home, or the refusal.
//!
//! Latency: with both speed limits off a move is a jump, and a jump is made as soon as its
//! path is checked: the command's reply is followed by new pulses from
//! [`Controller::take_new_pulses`], which the board writes right away instead of at the next
//! frame (hobby-servo PWM latches new compare values at the next period, so nothing is cut
//! short). Streaming hosts use this mode. With a speed limit set the first step comes with the
//! next frame (up to one frame later), because writing it early could put two steps into one
//! frame and exceed the limit.
//!
//! A new target while moving, with an acceleration limit set: a blend
//! ([`crate::motion::blend`]), checked while the motion in progress goes on. It takes over at
//! the hand-over, a frame chosen in the job's first slice (the line's own pass has parsed it and
//! solved the target: [`Controller::replan`]), as far ahead as the check is expected
//! to take (its number of poses over the poses a frame has been seen to fit, `check_rate`,
//! with a quarter to spare), and it is planned from the pose and velocity the motion will have
//! then ([`crate::motion::Motion::state_after`]), so the path checked is the path taken. A
//! check that ends after its hand-over (or after the motion changed: a fault) is planned and
//! checked again from the motion as it is then, with half the rate; the motion goes on
//! meanwhile. A blend waiting for its hand-over is replaced by the next target's, which
//! therefore takes over no later than it would. Without an acceleration limit (or while a
//! stream is passed through), the platform holds during the check and starts from rest (the
//! speed may jump).
//!
//! With servo speed ratings a blend is planned first no faster than the arm angles at its ends
//! allow, then its check measures every frame's arm turns against the ratings and, if one is
//! too fast, it is planned again from the motion as it is then, slower
//! (`path.rs`, `FrameTurns`; at most four passes, the last braking to rest at its corner).
//!
//! A move while a stream is tracked (its limits on, the tracker moving): the stream ends as
//! the move's check begins (its first slice) and its motion goes on as a planned one, a blend from the tracker's pose
//! and velocity to the stream's goal ([`Controller::stream_as_motion`]), which the move takes
//! over from like any motion in progress. `check` plans the same as a `pose` at that moment
//! would (from the stream as a motion, without ending it), and takes nothing over.

use kinematics_core::{Math, Pose};

use super::path::{Checked, FrameTurns, HandOver, PathCheck, Purpose};
use super::{Begun, Controller, Done, Job};
use crate::error::Error;
use crate::motion::{Motion, Plan, Segment, SpeedLimits};
use crate::report::{Listing, Notice};
use crate::servo_speed::ServoSpeeds;

/// The most frames a blend's hand-over is put ahead (10 s at 50 Hz, 1.5 s at 333 Hz; a check
/// takes about 0.2 s at most, 0.7 s with torque ratings).
const MAX_LEAD_FRAMES: u32 = 500;

impl<M: Math> Controller<M> {
    /// The speed and acceleration limits of commanded moves.
    pub(super) fn speed_limits(&self) -> SpeedLimits {
        let s = &self.settings;
        SpeedLimits {
            mm_per_s2: s.accel_mm_s2,
            deg_per_s2: s.accel_deg_s2,
            ..SpeedLimits::speeds(s.speed_mm_s, s.speed_deg_s)
        }
    }

    pub(super) fn move_to(&mut self, target: Pose) -> Result<Begun, Error> {
        let limits = self.speed_limits();
        let jump = self.jumps(&limits);
        self.start_path(target, limits, Purpose::Move { jump })
    }

    /// Whether a move at `limits` is a jump: no speed limit and no servo speed rating (with
    /// ratings a move takes as long as the servos need).
    fn jumps(&self, limits: &SpeedLimits) -> bool {
        !(limits.mm_per_s > 0.0 || limits.deg_per_s > 0.0 || self.settings.servo_speed.rated())
    }

    /// Checks the target now (its error is the most useful one), then starts the check of the
    /// path to it as a job: the straight line from the current pose, or, for a move (or
    /// `check`) while the platform moves with an acceleration limit set, a blend from the
    /// motion in progress ([`Controller::blend_plan`]); a stream being tracked is that motion
    /// once it is planned ([`Controller::stream_as_motion`]).
    pub(super) fn start_path(
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
        let accel = limits.mm_per_s2 > 0.0 || limits.deg_per_s2 > 0.0;
        let blends = accel
            && match purpose {
                Purpose::Move { jump } => !jump,
                Purpose::Check => !self.jumps(&limits),
                _ => false,
            };
        // Blended into: the motion in progress, or a stream being tracked (which goes on as a
        // planned motion: [`Controller::stream_as_motion`]).
        let takes_over = blends && (self.motion.is_moving() || self.tracks_stream());
        let rated = self.settings.servo_speed.rated();
        let (plan, hand_over, servo_time, frame_turns) = if takes_over {
            let hz = f32::from(self.settings.frame_hz);
            let turns = rated.then(|| {
                // First planned at most as fast as the arm angles at its two ends allow (the
                // servos' now, the target's), then measured frame by frame (`path.rs`).
                let least = self
                    .settings
                    .servo_speed
                    .least_time_s(&self.solution.arm_rad, &solution.arm_rad);
                let here = self.motion.pose();
                let capped = ServoSpeeds::capped_limits(limits, here, &target, least);
                FrameTurns::new(capped, 1.0, hz)
            });
            // The blend is planned in the job's first slice (`Controller::replan`), from the
            // motion as it is then: this pass has parsed the line and solved the target.
            let placeholder = Segment::plan(*self.motion.pose(), target, limits, hz);
            (Plan::Straight(placeholder), None, None, turns)
        } else {
            // Within the servos' rated speeds, if they have any (`controller/servo_speed.rs`).
            let (segment, servo_time) = self.plan_within_servo_speed(target, &solution, limits);
            (Plan::Straight(segment), None, servo_time, None)
        };
        // A move checked while moving (or streaming) without a blend: the platform holds here
        // until the check ends.
        self.holding = purpose != Purpose::Check
            && !takes_over
            && (self.motion.is_moving() || self.is_streaming());
        // Built where it is kept (a check is hundreds of bytes: no copy of it on the way).
        self.job = Some(Job::Path(PathCheck::new(
            purpose,
            solution,
            plan,
            hand_over,
            &self.settings,
            servo_time,
            frame_turns,
        )));
        if takes_over {
            if let Some(Job::Path(path)) = &mut self.job {
                *path = path.to_replan();
            }
        }
        Ok(Begun::Pending)
    }

    /// The slice that plans (again) the move of a path check that takes over from the motion
    /// in progress: its first slice, after a missed hand-over, or after its arms were found too
    /// fast for their ratings; with the limits the ratings need, from the motion as it is now
    /// (a stream being tracked becomes that motion here, for a move; `check` only plans from
    /// it).
    pub(super) fn replan(&mut self) {
        let Some(Job::Path(path)) = &self.job else {
            return;
        };
        let (target, purpose) = (*path.plan.target(), path.purpose);
        let (limits, corner) = path
            .frame_turns
            .map_or((self.speed_limits(), 1.0), |t| (t.limits, t.corner_scale));
        let motion = match self.stream_as_motion() {
            Some(motion) if purpose != Purpose::Check => {
                // A move ends the stream; its motion goes on, planned.
                self.stream = None;
                self.motion = motion;
                motion
            }
            Some(motion) => motion,
            None => self.motion,
        };
        let (plan, hand_over) = self.blend_plan(&motion, target, limits, corner);
        if let Some(Job::Path(path)) = &mut self.job {
            *path = path.replanned(plan, hand_over);
        }
    }

    /// A stream is being tracked (not passed through) and its tracker moves.
    fn tracks_stream(&self) -> bool {
        self.stream
            .as_ref()
            .is_some_and(|s| !s.tracker.at_rest() && !self.passes_through())
    }

    /// The stream's tracker, moving, as a planned motion: from its pose and velocity, a blend
    /// to the stream's goal within the move's limits (with servo speed ratings, braking to rest
    /// first and on from rest no faster than the arm angles at the goal allow), so that a move
    /// can take over from it. `None` when no stream is being tracked (pass-through, or none),
    /// or its tracker is at rest.
    fn stream_as_motion(&self) -> Option<Motion> {
        if !self.tracks_stream() {
            return None;
        }
        let stream = self.stream.as_ref()?;
        let hz = f32::from(self.settings.frame_hz.max(1));
        let rate = stream.tracker.rate_per_frame(1.0 / hz);
        let pose = stream.tracker.pose();
        let mut limits = self.speed_limits();
        let mut corner = 1.0;
        if self.settings.servo_speed.rated() {
            let goal = self
                .solver
                .solve::<M>(&self.settings.servos, &stream.goal)
                .ok()?;
            let least = self
                .settings
                .servo_speed
                .least_time_s(&self.solution.arm_rad, &goal.arm_rad);
            limits = ServoSpeeds::capped_limits(limits, &pose, &stream.goal, least);
            corner = 0.0;
        }
        let plan = Plan::after_within::<M>(pose, rate, stream.goal, limits, corner, hz);
        let mut motion = Motion::new(pose);
        motion.start_after(plan, 0);
        Some(motion)
    }

    /// The straight move from the current pose.
    fn straight_plan(&self, target: Pose, limits: SpeedLimits) -> Plan {
        let hz = f32::from(self.settings.frame_hz);
        Plan::Straight(Segment::plan(*self.motion.pose(), target, limits, hz))
    }

    /// The move to `target` taking over from `motion` (the motion in progress) a few frames
    /// from now, when its check will have ended (the hand-over): planned from the pose and
    /// velocity the motion will have then (a blend taking `corner` of its largest corner
    /// velocity), so the motion goes on while the check runs and the path checked is the path
    /// taken. The lead is the check's size over the checks a frame has been
    /// seen to fit (`check_rate`), with a quarter to spare: planned first with the lead the
    /// last blend's size needed, and again if this one needs more, or much less. A check that ends too
    /// late is planned and checked again ([`Controller::missed_hand_over`]). Standing still:
    /// the straight move.
    pub(super) fn blend_plan(
        &self,
        motion: &Motion,
        target: Pose,
        limits: SpeedLimits,
        corner: f32,
    ) -> (Plan, Option<HandOver>) {
        if !motion.is_moving() {
            return (self.straight_plan(target, limits), None);
        }
        let hz = f32::from(self.settings.frame_hz);
        let plan_after = |lead: u32| {
            let (pose, rate) = motion.state_after(lead);
            let plan = Plan::after_within::<M>(pose, rate, target, limits, corner, hz);
            let hand_over = HandOver {
                begun: self.frame_ticks,
                at: self.frame_ticks.wrapping_add(lead),
                pose,
                rate,
            };
            (plan, Some(hand_over))
        };
        // A move queued and not started yet is replaced, so the new one takes over no later
        // than it would (if the check takes longer, it is planned again once that one runs).
        let latest = motion.queued_after().unwrap_or(MAX_LEAD_FRAMES);
        let lead_for = |checks: u32| {
            let lead = (checks.saturating_mul(5) / 4).div_ceil(self.check_rate.max(1));
            lead.clamp(1, MAX_LEAD_FRAMES).min(latest)
        };
        let guess = lead_for(self.blend_checks);
        let first = plan_after(guess);
        let needed = lead_for(first.0.check_count());
        if needed <= guess && guess <= needed + needed.div_ceil(4) {
            first
        } else {
            // Later, or sooner (the platform should not wait much longer than the check needs:
            // the motion in progress may end before the hand-over).
            plan_after(needed)
        }
    }

    /// Whether a blend whose check has just ended can no longer take over as planned (its
    /// hand-over frame has passed, or the motion changed meanwhile): then it is planned and
    /// checked again from the motion as it is now.
    pub(super) fn missed_hand_over(&self, path: &Checked) -> bool {
        match path.hand_over {
            Some(h) => {
                let wait = h.at.wrapping_sub(self.frame_ticks) as i32;
                self.motion.state_after(wait.max(0) as u32) != (h.pose, h.rate)
            }
            None => false,
        }
    }

    /// Learns how many path checks fit in a frame, from the check that has just ended; after a
    /// missed hand-over, half as many.
    pub(super) fn learn_check_rate(&mut self, path: &Checked, missed: bool) {
        let Some(h) = path.hand_over else {
            return;
        };
        self.blend_checks = path.plan.check_count();
        let frames = self.frame_ticks.wrapping_sub(h.begun);
        self.check_rate = match path.solved.checked_div(frames) {
            Some(rate) => rate.max(1),
            // Done within the frame it began in: at least that many fit.
            None => self.check_rate.max(path.solved),
        };
        if missed {
            self.check_rate = (self.check_rate / 2).max(1);
        }
    }

    /// What a checked path leads to.
    pub(super) fn finish_path(&mut self, path: &Checked, result: Result<(), Error>) -> Done {
        // (Borrowed: each outcome copies only what it keeps.)
        let Checked {
            purpose,
            ref solution,
            ref plan,
            hand_over,
            torque: torque_kgcm,
            ..
        } = *path;
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
                self.start_plan(*plan, hand_over);
                self.servo_power = true;
                Done::Ok
            }
            (Purpose::Move { jump: true }, Ok(())) => {
                // No speed limit: a jump, made now (see the module docs on latency).
                self.end_stream();
                self.direct = None;
                self.motion = Motion::new(*plan.target());
                self.solution = *solution;
                self.new_pulses = true;
                self.returning_home = false;
                self.fault = None;
                self.servo_power = true;
                Done::Ok
            }
            (Purpose::EstopHome, Ok(())) => {
                self.end_stream();
                self.direct = None;
                self.start_plan(*plan, None);
                Done::Quiet
            }
            (Purpose::EstopHome, Err(e)) => {
                self.home_blocked(e);
                self.servo_power = false;
                Done::Quiet
            }
            (Purpose::Check, Ok(())) => {
                let duration_s = if plan.start() == *plan.target() {
                    0.0
                } else {
                    plan.frames() as f32 / f32::from(self.settings.frame_hz)
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
                self.start_plan(*plan, None);
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

    /// Starts a checked move.
    pub(super) fn start(&mut self, segment: Segment) {
        self.motion.start(segment);
        self.returning_home = false;
        self.fault = None;
    }

    /// Starts a checked plan: a straight move now, or a blend at its hand-over (which
    /// [`Controller::missed_hand_over`] has found still ahead, or now).
    fn start_plan(&mut self, plan: Plan, hand_over: Option<HandOver>) {
        match (plan, hand_over) {
            (Plan::Straight(segment), None) => self.start(segment),
            (plan, hand_over) => {
                let wait = hand_over.map_or(0, |h| h.at.wrapping_sub(self.frame_ticks) as i32);
                self.motion.start_after(plan, wait.max(0) as u32);
                self.returning_home = false;
                self.fault = None;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::controller::test_support::*;
    use crate::controller::CHECKS_PER_SLICE;
    use kinematics_core::Pose;

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

    /// Feeds `line` to `c` as the board does, then runs frames with `slices` slices of work
    /// between them until the reply; the poses of those frames, and the reply.
    fn line_while_moving(
        c: &mut crate::Controller,
        link: &mut crate::Session,
        line: &str,
        slices: u32,
        poses: &mut std::vec::Vec<Pose>,
    ) -> std::string::String {
        let mut out = std::string::String::new();
        for &b in line.as_bytes().iter().chain(b"\n") {
            c.on_byte(link, b, &mut out);
        }
        while link.awaits_reply() {
            c.on_frame();
            poses.push(*c.pose());
            for _ in 0..slices {
                c.work(link, &mut out);
            }
        }
        out
    }

    /// Per-frame speed and change of velocity of z (mm per frame, per frame^2).
    fn steps(poses: &[Pose]) -> std::vec::Vec<f32> {
        poses.windows(2).map(|w| w[1].z_mm - w[0].z_mm).collect()
    }

    #[test]
    fn with_an_acceleration_limit_a_new_target_blends_in_while_the_check_runs() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        c.execute_line(&mut link, "set speed_mm_s 40", &mut out);
        c.execute_line(&mut link, "set accel_mm_s2 200", &mut out);
        c.execute_line(&mut link, "pose 0 0 6 0 0 0", &mut out);
        let mut poses = std::vec![*c.pose()];
        for _ in 0..8 {
            c.on_frame();
            poses.push(*c.pose());
        }
        // Every 5 frames a new target (ahead, ahead, back down, up again), each checked over
        // one frame or more (six slices, 18 IK solutions, per frame: the board fits more),
        // the platform moving on meanwhile.
        for line in [
            "nudge z=4",
            "nudge z=4",
            "pose 0 0 -2 0 0 0",
            "pose 0 0 9 0 0 0",
        ] {
            let before = poses.len();
            let reply = line_while_moving(&mut c, &mut link, line, 6, &mut poses);
            assert_eq!(reply, "ok\r\n", "{line}");
            let during = &poses[before - 1..];
            assert!(
                during.windows(2).all(|w| w[0] != w[1]),
                "{line}: held during its check"
            );
            while poses.len() - before < 5 {
                c.on_frame();
                poses.push(*c.pose());
            }
        }
        while c.is_moving() {
            c.on_frame();
            poses.push(*c.pose());
        }
        assert_eq!(*c.pose(), Pose::from_degrees(0.0, 0.0, 9.0, 0.0, 0.0, 0.0));
        // 200 mm/s2 is 0.08 mm of change per frame at 50 Hz, 40 mm/s is 0.8 mm a frame (f32
        // rounding of poses of a few mm: 1e-5 mm).
        let v = steps(&poses);
        for (k, w) in v.windows(2).enumerate() {
            assert!((w[1] - w[0]).abs() <= 0.08 + 1e-4, "frame {}: {v:?}", k + 1);
        }
        assert!(v.iter().all(|s| s.abs() <= 0.8 + 1e-4), "{v:?}");
        // Never held still before it arrived: no two frames in a row without a step (a turn
        // back passes through rest, which may round to one step of 0).
        let end = v.iter().rposition(|s| *s != 0.0).unwrap();
        assert!(
            v[..end].windows(2).all(|w| w[0] != 0.0 || w[1] != 0.0),
            "{v:?}"
        );
        // The turn back came from the velocity it had, not from a stop at the command.
        assert!(
            v.iter().any(|s| *s > 0.5) && v.iter().any(|s| *s < -0.5),
            "{v:?}"
        );
        assert!(c.fault().is_none());
    }

    #[test]
    fn a_check_slower_than_its_lead_is_planned_again_and_still_within_the_limits() {
        // One slice (3 IK solutions) a frame: far fewer than first assumed, so the first
        // hand-overs are missed and planned again from the motion as it is by then.
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        c.execute_line(&mut link, "set speed_mm_s 30", &mut out);
        c.execute_line(&mut link, "set accel_mm_s2 100", &mut out);
        c.execute_line(&mut link, "pose 0 0 20 0 0 0", &mut out);
        let mut poses = std::vec![*c.pose()];
        for _ in 0..20 {
            c.on_frame();
            poses.push(*c.pose());
        }
        for line in ["pose 0 0 3 0 0 0", "nudge z=6"] {
            let reply = line_while_moving(&mut c, &mut link, line, 1, &mut poses);
            assert_eq!(reply, "ok\r\n", "{line}");
        }
        while c.is_moving() {
            c.on_frame();
            poses.push(*c.pose());
        }
        assert_eq!(*c.pose(), Pose::from_degrees(0.0, 0.0, 9.0, 0.0, 0.0, 0.0));
        let v = steps(&poses);
        for w in v.windows(2) {
            assert!((w[1] - w[0]).abs() <= 0.04 + 1e-4, "{v:?}");
        }
    }

    #[test]
    fn a_refused_target_while_blending_changes_nothing() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        c.execute_line(&mut link, "set speed_mm_s 20", &mut out);
        c.execute_line(&mut link, "set accel_mm_s2 100", &mut out);
        c.execute_line(&mut link, "pose 0 0 10 0 0 0", &mut out);
        for _ in 0..10 {
            c.on_frame();
        }
        let mut untouched = c.clone();
        let mut poses = std::vec::Vec::new();
        // Reachable, but not along any way there from here (far out sideways and tilted).
        let reply = line_while_moving(&mut c, &mut link, "pose 60 0 -20 0 25 0", 1, &mut poses);
        assert!(reply.starts_with("error:"), "{reply}");
        let mut expected = std::vec::Vec::new();
        for _ in 0..poses.len() {
            untouched.on_frame();
            expected.push(*untouched.pose());
        }
        assert_eq!(
            poses, expected,
            "the motion went on as if the line had not come"
        );
        while c.is_moving() || untouched.is_moving() {
            assert_eq!(c.on_frame(), untouched.on_frame());
        }
        assert_eq!(*c.pose(), *untouched.pose());
    }

    /// Per frame, the largest share of its rating any arm turned by (from the pulses, eq. 13,
    /// 14: an arm turns by |dW| / r).
    fn rating_shares(c: &crate::Controller, pulses: &[[f32; 6]]) -> std::vec::Vec<f32> {
        let s = c.settings();
        let dt = 1.0 / f32::from(s.frame_hz);
        pulses
            .windows(2)
            .map(|w| {
                (0..6)
                    .map(|i| {
                        let turn = (w[1][i] - w[0][i]).abs() / s.servos.0[i].rate_us_per_rad;
                        let rated = core::f32::consts::FRAC_PI_3 / s.servo_speed.s_per_60deg[i];
                        turn / (rated * dt)
                    })
                    .fold(0.0, f32::max)
            })
            .collect()
    }

    /// Per frame, the change of velocity of the linear (mm) and angular (deg) groups, Euclidean.
    fn velocity_changes(poses: &[Pose]) -> std::vec::Vec<[f32; 2]> {
        let v = frame_velocities(poses);
        v.windows(2)
            .map(|w| {
                let n = |r: core::ops::Range<usize>| {
                    libm::sqrtf(r.map(|i| (w[1][i] - w[0][i]).powi(2)).sum())
                };
                [n(0..3), n(3..6)]
            })
            .collect()
    }

    #[test]
    fn with_servo_speed_ratings_a_new_target_blends_in_within_the_ratings_and_the_limits() {
        // (Until now, with ratings a new target while moving held the platform during its
        // check and started from rest; now it blends in as without ratings, slowed where an
        // arm would turn faster than its rating.) Targets every 5 frames, across and turning,
        // each checked over a frame or more (six slices a frame).
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        for line in [
            "set servos.speed_s_60deg 0.4",
            "set servo4.speed_s_60deg 0.6",
            "set speed_mm_s 60",
            "set speed_deg_s 60",
            "set accel_mm_s2 300",
            "set accel_deg_s2 300",
            "pose 0 0 10 0 0 0",
        ] {
            c.execute_line(&mut link, line, &mut out);
        }
        assert!(!out.contains("error"), "{out}");
        let (mut poses, mut pulses) = (std::vec![*c.pose()], std::vec![c.pulses_us()]);
        for _ in 0..8 {
            pulses.push(c.on_frame());
            poses.push(*c.pose());
        }
        let lines = [
            "pose 15 0 0 0 0 10",
            "nudge z=-4",
            "pose -12 5 -3 0 5 -8",
            "pose -12 -5 -3 0 -5 8",
            "move x=10",
            "home",
        ];
        for line in lines {
            let before = poses.len();
            let mut reply = std::string::String::new();
            for &b in line.as_bytes().iter().chain(b"\n") {
                c.on_byte(&mut link, b, &mut reply);
            }
            while link.awaits_reply() {
                pulses.push(c.on_frame());
                poses.push(*c.pose());
                for _ in 0..6 {
                    c.work(&mut link, &mut reply);
                }
            }
            assert_eq!(reply, "ok\r\n", "{line}");
            assert!(
                poses[before - 1..].windows(2).all(|w| w[0] != w[1]),
                "{line}: held during its check"
            );
            while poses.len() - before < 5 {
                pulses.push(c.on_frame());
                poses.push(*c.pose());
            }
        }
        while c.is_moving() {
            pulses.push(c.on_frame());
            poses.push(*c.pose());
        }
        assert_eq!(*c.pose(), Pose::HOME);
        assert!(c.fault().is_none());
        // No arm faster than its rating in any frame; and the ratings set the pace somewhere.
        let shares = rating_shares(&c, &pulses);
        let most = shares.iter().copied().fold(0.0, f32::max);
        assert!(most <= 1.0001, "{shares:?}");
        assert!(most > 0.8, "the ratings never bound: {most}");
        // Within the acceleration limits at every frame (300 mm/s2 and deg/s2 at 50 Hz: 0.12
        // per frame per frame; f32 rounding of poses of tens of mm: 1e-4).
        for (k, d) in velocity_changes(&poses).iter().enumerate() {
            assert!(
                d[0] <= 0.12 + 2e-4 && d[1] <= 0.12 + 2e-4,
                "frame {}: {d:?}",
                k + 1
            );
        }
        // Never held still mid-way: no two frames in a row without a step before it arrived.
        let end = poses.iter().rposition(|p| *p != Pose::HOME).unwrap();
        assert!(
            poses[..=end]
                .windows(3)
                .all(|w| w[0] != w[1] || w[1] != w[2]),
            "held still"
        );
    }

    #[test]
    fn without_acceleration_limits_a_new_target_holds_then_jumps_or_starts_from_rest() {
        // Speed limits off, acceleration set: a move is a jump, made when its check ends.
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        c.execute_line(&mut link, "set speed_mm_s 0", &mut out);
        c.execute_line(&mut link, "set speed_deg_s 0", &mut out);
        c.execute_line(&mut link, "set accel_mm_s2 100", &mut out);
        c.execute_line(&mut link, "pose 0 0 10 0 0 0", &mut out);
        c.on_frame();
        assert_eq!(*c.pose(), Pose::from_degrees(0.0, 0.0, 10.0, 0.0, 0.0, 0.0));
        assert!(!c.is_moving());
        // The hold of `a_move_checked_while_moving_holds_the_platform_then_starts_from_there`
        // is the rule with speed limits and no acceleration limit.
    }

    #[test]
    fn check_while_moving_reports_the_blend_a_pose_would_take() {
        // Going up at 40 mm/s, `check` of a target below: a `pose` would brake (0.2 s) and
        // come back, which takes longer than the straight line from rest `check` used to give.
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        for line in [
            "set speed_mm_s 40",
            "set accel_mm_s2 200",
            "pose 0 0 12 0 0 0",
        ] {
            c.execute_line(&mut link, line, &mut out);
        }
        for _ in 0..10 {
            c.on_frame();
        }
        let target = Pose::from_degrees(0.0, 0.0, -4.0, 0.0, 0.0, 0.0);
        let from_rest =
            crate::motion::Segment::plan(*c.pose(), target, c.speed_limits(), 50.0).frames();
        let mut twin = c.clone();
        let mut twin_link = link.clone();
        let mut poses = std::vec::Vec::new();
        let reply = line_while_moving(&mut c, &mut link, "check 0 0 -4 0 0 0", 6, &mut poses);
        let duration: f32 = reply
            .lines()
            .find_map(|l| l.strip_prefix("# duration_s: "))
            .unwrap()
            .parse()
            .unwrap();
        let frames = (duration * 50.0).round() as u32;
        // The same line as a `pose`, from the same moment: frames from the line to arrival.
        let mut seen = std::vec::Vec::new();
        let reply = line_while_moving(&mut twin, &mut twin_link, "pose 0 0 -4 0 0 0", 6, &mut seen);
        assert_eq!(reply, "ok\r\n");
        let mut taken = seen.len() as u32;
        while twin.is_moving() {
            twin.on_frame();
            taken += 1;
        }
        // From its hand-over (a few frames after the line: the check's expected length, with
        // a quarter to spare) to arrival.
        assert!(frames <= taken && taken <= frames + 8, "{frames} {taken}");
        assert!(frames > from_rest + 4, "{frames} vs {from_rest} from rest");
        // And nothing moved differently for it.
        assert_eq!(
            *c.target(),
            Pose::from_degrees(0.0, 0.0, 12.0, 0.0, 0.0, 0.0)
        );
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
}
