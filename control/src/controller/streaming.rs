//! Streaming ([`crate::stream`]): a stream frame's pose becomes the stream's target; the newest
//! frame wins (the board feeds every waiting byte, then calls [`Controller::apply_stream`],
//! which applies only the newest frame). An unreachable target is clamped: the last reachable
//! pose on the straight line from the current pose to it, found by bisection
//! ([`CLAMP_STEPS`](super::CLAMP_STEPS) IK solutions, as a job a slice per pass: so a clamped
//! frame takes effect a few passes, well under a millisecond, later), and counted. With every
//! speed and acceleration limit off (and no servo speed rating) the pose is applied at once
//! (pass-through, like a jump: [`Controller::take_new_pulses`]);
//! otherwise each axis follows it at the servo frame rate within the limits
//! ([`crate::tracker`]), each step shortened to the servos' rated speeds if they have any
//! (`controller/servo_speed.rs`); a step that would leave the workspace (the axes' own paths to a
//! reachable goal can) stops the tracker where it is, counted as a clamp too. An accepted
//! move (`pose`, `move`, `nudge`, `home`) or `stop` ends the stream; with acceleration limits
//! a move ends it as its check begins, the tracker's motion going on as a planned one that
//! the move takes over from (`controller/moves.rs`), while in pass-through the stream holds
//! during the move's check (a refused one lets it go on). The next frame starts the stream
//! again from wherever the platform is, at the velocity it has there.
//!
//! The stream's state and the clamp's bisection are `controller/stream_goal.rs`'s; here is what
//! frames do to the platform.

use kinematics_core::ik::Solution;
use kinematics_core::{Math, Pose};

use super::stream_goal::{Clamp, Streaming, TrackTiming};
use super::{Controller, Job};
use crate::motion::Motion;
use crate::settings::Settings;
use crate::stream::Frame;
use crate::tracker::{TrackLimits, Tracker};

impl<M: Math> Controller<M> {
    /// The body of [`Controller::apply_stream`] (see there).
    pub(super) fn apply_newest_frame(&mut self) {
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

    /// The stream tracker's limits (the same settings as commanded moves, per axis).
    pub(super) fn track_limits(&self) -> TrackLimits {
        let s = &self.settings;
        TrackLimits {
            mm_per_s: s.speed_mm_s,
            mm_per_s2: s.accel_mm_s2,
            rad_per_s: s.speed_deg_s.to_radians(),
            rad_per_s2: s.accel_deg_s2.to_radians(),
        }
    }

    /// True if stream targets are applied as they come (pass-through): every speed and
    /// acceleration limit off, and no servo speed rating (a rated stream is tracked, one
    /// step per frame, so that each step can be kept to the ratings).
    pub(super) fn passes_through(&self) -> bool {
        Self::passes_through_with(self.track_limits(), &self.settings)
    }

    /// [`Controller::passes_through`] with the tracker's limits already worked out (the one
    /// rule, for the per-frame timing cached in [`TrackTiming`] too).
    fn passes_through_with(limits: TrackLimits, settings: &Settings) -> bool {
        limits == TrackLimits::OFF && !settings.servo_speed.rated()
    }

    /// A whole stream frame arrived: its pose becomes the stream's target (applied by
    /// [`Controller::apply_stream`]).
    pub(super) fn on_stream_frame(&mut self, frame: Frame) {
        let counts = &mut self.stream_counts;
        let Ok(fractions) = self.settings.stream.fractions(frame) else {
            counts.damaged = counts.damaged.wrapping_add(1);
            return;
        };
        // The step guard (off by default): a frame too far from the last one taken (a lost
        // digit) is dropped as damaged, unless the one before it agrees (a real jump).
        if let Some(stream) = self.stream.as_mut() {
            let allowed =
                self.settings
                    .stream
                    .step_allowed(&stream.taken, &stream.seen, &fractions);
            stream.seen = fractions;
            if !allowed {
                counts.damaged = counts.damaged.wrapping_add(1);
                return;
            }
        }
        let target = self.settings.stream.pose_of(&fractions);
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
                stream.taken = fractions;
                stream.last_frame_tick = self.frame_ticks;
            }
            None => {
                // The stream starts (again) from where the platform is, at the velocity it has
                // (a move in progress ends, and its velocity goes on in the tracker), and
                // driving the servos one by one ends.
                let (_, rate) = self.motion.state_after(0);
                let frame_s = 1.0 / f32::from(self.settings.frame_hz.max(1));
                self.motion = Motion::new(here);
                self.returning_home = false;
                self.direct = None;
                self.stream = Some(Streaming {
                    target,
                    fresh: true,
                    goal: here,
                    tracker: Tracker::moving(&here, &rate, frame_s),
                    taken: fractions,
                    seen: fractions,
                    last_frame_tick: self.frame_ticks,
                    timing: None,
                });
            }
        }
    }

    /// The stream's tracker limits and frame time (see [`TrackTiming`]), worked out again only
    /// if the settings changed since; `None` without a stream.
    fn track_timing(&mut self) -> Option<TrackTiming> {
        let generation = self.generation;
        let cached = self.stream.as_ref()?.timing;
        if let Some(timing) = cached.filter(|t| t.generation == generation) {
            return Some(timing);
        }
        let limits = self.track_limits();
        let timing = TrackTiming {
            generation,
            limits,
            pass_through: Self::passes_through_with(limits, &self.settings),
            frame_s: 1.0 / f32::from(self.settings.frame_hz.max(1)),
        };
        self.stream.as_mut()?.timing = Some(timing);
        Some(timing)
    }

    /// One servo frame of a stream: the tracker steps towards its goal; a step that cannot be
    /// driven is clamped and the tracker stops there. (The stream is worked on in place: a
    /// copy of its state, in and out, costs a frame hundreds of cycles.)
    pub(super) fn track_frame(&mut self) {
        let Some(timing) = self.track_timing() else {
            return;
        };
        if timing.pass_through {
            return; // pass-through: applied as frames come
        }
        let Some(stream) = self.stream.as_mut() else {
            return;
        };
        // With servo speed ratings the step may be shortened: the tracker before it, kept.
        let before = if self.settings.servo_speed.rated() {
            Some(stream.tracker)
        } else {
            None
        };
        // Stepped in place: if its pose cannot be driven, the tracker is reset below anyway.
        stream.tracker = stream
            .tracker
            .step::<M>(&stream.goal, &timing.limits, timing.frame_s);
        let next = stream.tracker.pose();
        if same_bits(&next, self.motion.pose()) {
            // Settled (or a step too small to change the pose): this pose's pulses are
            // solved already.
            return;
        }
        match self.solver.solve::<M>(&self.settings.servos, &next) {
            Ok(mut solution) => {
                let mut next = next;
                if let Some(before) = before {
                    // Shortened to the servos' rated speeds (`controller/servo_speed.rs`).
                    let mut stepped = stream.tracker;
                    self.step_within_servo_speed(&before, &mut stepped, &mut solution);
                    next = stepped.pose();
                    if let Some(stream) = self.stream.as_mut() {
                        stream.tracker = stepped;
                    }
                }
                self.motion = Motion::new(next);
                self.solution = solution;
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
    }

    /// Starts clamping a stream target as the controller's own job: `to` cannot be reached
    /// (`unchecked: None`), or can, with this solution, but its holding torques are to be
    /// checked against the ratings first. ([`Controller::apply_stream`] waits for a command's
    /// work to end first; a job still running here means this frame came through a transport
    /// that feeds while busy: then the goal stays where it was.)
    pub(super) fn start_clamp(&mut self, from: Pose, to: Pose, unchecked: Option<Solution>) {
        if self.job.is_none() {
            self.job = Some(Job::Clamp(Clamp::new(from, to, unchecked)));
        }
    }

    /// A stream target, or what it was clamped to, is the goal: in pass-through the pose now
    /// (`solution`: its IK; `None` to stay where the platform is), else the tracker's goal.
    /// Nothing if the stream has ended meanwhile (a clamp's job outlived it).
    pub(super) fn reach_stream_goal(&mut self, pose: Pose, solution: Option<Solution>) {
        let Some(timing) = self.track_timing() else {
            return;
        };
        let Some(mut stream) = self.stream else {
            return;
        };
        if timing.pass_through {
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
    pub(super) fn end_stream(&mut self) {
        if self.stream.take().is_some() {
            self.motion = Motion::new(*self.motion.pose());
        }
    }
}

/// `a` and `b` are the same pose, bit for bit (integer comparisons, where `==` on `f32` is a
/// library call on the RP2040; a zero of the other sign only costs an IK).
fn same_bits(a: &Pose, b: &Pose) -> bool {
    let (a, b) = (a.to_array(), b.to_array());
    (0..6).fold(0, |d, i| d | (a[i].to_bits() ^ b[i].to_bits())) == 0
}

#[cfg(test)]
mod tests {
    use crate::controller::test_support::*;
    use crate::controller::Controller;
    use crate::session::Session;

    /// Feeds a SimTools text frame (8 bits, axes x y z roll pitch yaw) with heave count `z`
    /// and applies it as the board does.
    fn send(c: &mut Controller, link: &mut Session, frame: &str) {
        let mut out = std::string::String::new();
        for &b in frame.as_bytes() {
            c.on_byte(link, b, &mut out);
        }
        c.apply_stream();
        assert_eq!(out, "", "frames get no reply");
    }

    /// Heave, mm, of count `z` at the default full scale (15 mm), by the documented formula.
    fn heave(z: f32) -> f32 {
        (z - 128.0) / 128.0 * 15.0
    }

    fn pass_through(guard: &str) -> (Controller, Session) {
        let (mut c, mut link) = (quiet(), program());
        for line in ["set speed_mm_s off", "set speed_deg_s off"] {
            assert_eq!(run(&mut c, &mut link, line), "ok\r\n");
        }
        let line = std::format!("set stream.max_step_pct {guard}");
        assert_eq!(run(&mut c, &mut link, &line), "ok\r\n");
        (c, link)
    }

    #[test]
    fn a_move_while_a_stream_is_tracked_takes_over_from_its_motion_within_the_limits() {
        // With acceleration limits and servo speed ratings: the tracker chases a frame, then
        // a `pose` line comes; the motion goes on while it is checked (as a planned motion to
        // the stream's goal) and the move takes over from its pose and velocity.
        let (mut c, mut link) = (quiet(), program());
        for line in [
            "set servos.speed_s_60deg 0.4",
            "set speed_mm_s 60",
            "set speed_deg_s 60",
            "set accel_mm_s2 300",
            "set accel_deg_s2 300",
        ] {
            assert_eq!(run(&mut c, &mut link, line), "ok\r\n");
        }
        send(&mut c, &mut link, "128,150,230,128,128,160X");
        let (mut poses, mut pulses) = (std::vec![*c.pose()], std::vec![c.pulses_us()]);
        for _ in 0..12 {
            pulses.push(c.on_frame());
            poses.push(*c.pose());
        }
        assert!(c.is_streaming() && c.is_moving());
        let mut reply = std::string::String::new();
        for &b in b"pose 5 0 -4 0 0 -5\n" {
            c.on_byte(&mut link, b, &mut reply);
        }
        let line_at = poses.len();
        while link.awaits_reply() {
            pulses.push(c.on_frame());
            poses.push(*c.pose());
            for _ in 0..6 {
                c.work(&mut link, &mut reply);
            }
        }
        assert_eq!(reply, "ok\r\n");
        assert!(poses.len() > line_at + 1, "the check took frames");
        while c.is_moving() {
            pulses.push(c.on_frame());
            poses.push(*c.pose());
        }
        let target = crate::controller::test_support::pose([5.0, 0.0, -4.0, 0.0, 0.0, -5.0]);
        assert_eq!(*c.pose(), target);
        assert!(!c.is_streaming() && c.fault().is_none());
        // Never held still from the first step to arrival.
        let end = poses.iter().position(|p| *p == target).unwrap();
        assert!(
            poses[1..=end].windows(2).all(|w| w[0] != w[1]),
            "held still"
        );
        // From the frame before the line on, every axis' change of velocity within its limit
        // (0.12 mm or deg per frame per frame at 50 Hz: the tracker's steps shortened to the
        // ratings before it may drop more), and no arm over its rating all along.
        let v = frame_velocities(&poses);
        for (k, w) in v.windows(2).enumerate().skip(line_at - 2) {
            for i in 0..6 {
                assert!(
                    (w[1][i] - w[0][i]).abs() <= 0.12 + 2e-4,
                    "frame {} axis {i}: {:?} then {:?}",
                    k + 1,
                    w[0],
                    w[1]
                );
            }
        }
        let s = c.settings();
        for (k, w) in pulses.windows(2).enumerate() {
            for (i, servo) in s.servos.0.iter().enumerate() {
                let turn = (w[1][i] - w[0][i]).abs() / servo.rate_us_per_rad;
                let rated = core::f32::consts::FRAC_PI_3 / 0.4 / 50.0;
                assert!(turn <= rated * 1.0001, "frame {} servo {}", k + 1, i + 1);
            }
        }
    }

    #[test]
    fn the_step_guard_drops_a_lost_digit_and_takes_the_next_good_frame() {
        let (mut c, mut link) = pass_through("10");
        send(&mut c, &mut link, "128,128,140,128,128,128X");
        assert!((c.pose().z_mm - heave(140.0)).abs() < 1e-4);
        // "140" lost its "0": 14 is 126 counts (98 % of full scale) away.
        send(&mut c, &mut link, "128,128,14,128,128,128X");
        assert!((c.pose().z_mm - heave(140.0)).abs() < 1e-4, "not applied");
        let counts = c.stream_counts();
        assert_eq!((counts.frames, counts.damaged), (1, 1));
        // The next good frame is near the last one taken: applied.
        send(&mut c, &mut link, "128,128,142,128,128,128X");
        assert!((c.pose().z_mm - heave(142.0)).abs() < 1e-4);
        // A step at the limit (12.8 counts is 10 %: 12 counts) is taken, one above it is not.
        send(&mut c, &mut link, "128,128,154,128,128,128X");
        assert!((c.pose().z_mm - heave(154.0)).abs() < 1e-4);
        send(&mut c, &mut link, "128,128,168,128,128,128X");
        assert!((c.pose().z_mm - heave(154.0)).abs() < 1e-4);
        // A real jump: its second frame agrees with its first, and is taken.
        send(&mut c, &mut link, "128,128,168,128,128,128X");
        assert!((c.pose().z_mm - heave(168.0)).abs() < 1e-4);
        let counts = c.stream_counts();
        assert_eq!((counts.frames, counts.applied, counts.damaged), (4, 4, 2));
    }

    #[test]
    fn without_the_guard_a_lost_digit_is_applied_and_off_is_the_default() {
        assert_eq!(quiet().settings().stream.max_step_pct, 0.0);
        let (mut c, mut link) = pass_through("off");
        send(&mut c, &mut link, "128,128,140,128,128,128X");
        send(&mut c, &mut link, "128,128,14,128,128,128X");
        assert!((c.pose().z_mm - heave(14.0)).abs() < 1e-4);
        assert_eq!(c.stream_counts().damaged, 0);
    }

    #[test]
    fn the_guard_checks_every_axis_against_its_own_full_scale() {
        let (mut c, mut link) = pass_through("5");
        send(&mut c, &mut link, "128,128,128,128,128,128X");
        // Yaw (full scale 20 deg) by 7 counts (5.5 %): dropped; roll by 6 (4.7 %): taken.
        send(&mut c, &mut link, "128,128,128,128,128,135X");
        send(&mut c, &mut link, "128,128,128,134,128,128X");
        let counts = c.stream_counts();
        assert_eq!((counts.applied, counts.damaged), (2, 1));
        assert!((c.pose().roll_rad.to_degrees() - 6.0 / 128.0 * 15.0).abs() < 1e-3);
        assert_eq!(c.pose().yaw_rad, 0.0);
    }
}
