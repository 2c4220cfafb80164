//! Link loss: with `link_timeout_s` set, when that long passes without a completed non-blank
//! line (any line, valid or not, counts as a sign of life, and so does a command being
//! carried out), the platform returns home at the configured speeds (a group whose speed is
//! off uses [`LINK_LOSS_SPEED_MM_S`] / [`LINK_LOSS_SPEED_DEG_S`] so it never jumps). It fires
//! once per silence, never before the timeout: silence is counted in whole frames from the
//! first frame that starts after the line's end (so up to one frame late). A stream frame is
//! a sign of life too, so a stream that stops eases the platform home the same way.

use kinematics_core::ik::IkError;
use kinematics_core::{Math, Pose};

use super::path::Purpose;
use super::{Controller, LINK_LOSS_SPEED_DEG_S, LINK_LOSS_SPEED_MM_S};
use crate::error::Error;
use crate::motion::SpeedLimits;
use crate::report::{Fault, Notice};

impl<M: Math> Controller<M> {
    /// Speeds for going home on its own (link loss, e-stop): the configured ones, or where a
    /// group's is off, a slow default (it never jumps).
    pub(super) fn own_move_limits(&self) -> SpeedLimits {
        let or = |v: f32, fallback: f32| if v > 0.0 { v } else { fallback };
        SpeedLimits {
            mm_per_s: or(self.settings.speed_mm_s, LINK_LOSS_SPEED_MM_S),
            deg_per_s: or(self.settings.speed_deg_s, LINK_LOSS_SPEED_DEG_S),
            ..self.speed_limits()
        }
    }

    /// A line (or a reply, a stream frame) came: the silence starts again.
    pub(super) fn heard_from_host(&mut self) {
        self.silence_us = None;
        self.link_loss_handled = false;
    }

    /// Once per frame: with `link_timeout_s` set and that long silent, the way home starts
    /// (once per silence).
    pub(super) fn check_link(&mut self) {
        let timeout_s = self.settings.link_timeout_s;
        // `timeout_s <= 0.0` by its bits, as every servo frame asks (a float comparison is a
        // library call on the RP2040): zero, negative or a negative NaN. (A positive NaN is
        // not `<= 0.0` either.)
        if timeout_s.to_bits() as i32 <= 0 || self.link_loss_handled {
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
    pub(super) fn home_blocked(&mut self, e: Error) {
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
}

#[cfg(test)]
mod tests {
    use crate::controller::test_support::*;
    use crate::motion::Motion;
    use crate::report::Fault;
    use kinematics_core::Libm;

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
}
