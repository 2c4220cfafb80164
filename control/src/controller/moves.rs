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

use kinematics_core::{Math, Pose};

use super::path::{PathCheck, Purpose};
use super::{Begun, Controller, Done, Job};
use crate::error::Error;
use crate::motion::{Motion, Segment, SpeedLimits};
use crate::report::{Listing, Notice};

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
        // (With servo speed ratings a move takes as long as the servos need: never a jump.)
        let jump =
            !(limits.mm_per_s > 0.0 || limits.deg_per_s > 0.0 || self.settings.servo_speed.rated());
        self.start_path(target, limits, Purpose::Move { jump })
    }

    /// Checks the target now (its error is the most useful one), then starts the check of the
    /// straight path to it from the current pose as a job.
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
        // Within the servos' rated speeds, if they have any (`controller/servo_speed.rs`).
        let (segment, servo_time) = self.plan_within_servo_speed(target, &solution, limits);
        // A move checked while moving (or streaming): the platform holds here until the check
        // ends.
        self.holding =
            purpose != Purpose::Check && (self.motion.is_moving() || self.is_streaming());
        self.job = Some(Job::Path(PathCheck::new(
            purpose,
            solution,
            segment,
            &self.settings,
            servo_time,
        )));
        Ok(Begun::Pending)
    }

    /// What a checked path leads to.
    pub(super) fn finish_path(&mut self, path: PathCheck, result: Result<(), Error>) -> Done {
        let torque_kgcm = path.torque();
        let PathCheck {
            purpose,
            solution,
            segment,
            ..
        } = path;
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

    /// Starts a checked move.
    pub(super) fn start(&mut self, segment: Segment) {
        self.motion.start(segment);
        self.returning_home = false;
        self.fault = None;
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
