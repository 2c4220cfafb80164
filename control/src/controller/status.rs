//! What `status` reports: the motion (moving, going home, streaming, a stream gone quiet,
//! pulses set directly, idle), the pose, target, arm angles and pulses, the fault, the stream's counts, the e-stop
//! and the servo power. (With a payload its holding torques follow in a slice of their own:
//! [`StatusTorques`](super::listing::StatusTorques).)

use kinematics_core::Math;

use super::Controller;
use crate::report::{MotionReport, StatusReport};

/// A stream whose last frame came this long ago, s, and that has come to rest, is reported as
/// idle (a sim paused or closed sends nothing, and nothing ends the stream but the next
/// command; the next frame takes it up again).
pub const STREAM_IDLE_S: f32 = 2.0;

impl<M: Math> Controller<M> {
    /// The report `status` lists, the holding torques still to be computed.
    pub(super) fn status(&self) -> StatusReport {
        let hz = f32::from(self.settings.frame_hz);
        let motion = match self.motion.progress() {
            None if self.stream.is_some() => self.stream_state(hz),
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

    /// A stream's state: following frames, or idle since its last frame long ago.
    fn stream_state(&self, hz: f32) -> MotionReport {
        let tracking = !self.passes_through();
        let Some(stream) = self.stream else {
            return MotionReport::Streaming { tracking };
        };
        let quiet_s = self.frame_ticks.wrapping_sub(stream.last_frame_tick) as f32 / hz;
        let at_rest = !tracking || (stream.tracker.at_rest() && stream.goal == *self.motion.pose());
        if quiet_s >= STREAM_IDLE_S && at_rest && !stream.fresh && self.job.is_none() {
            MotionReport::StreamIdle { quiet_s }
        } else {
            MotionReport::Streaming { tracking }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::controller::test_support::*;
    use crate::controller::Controller;
    use crate::session::Session;

    fn state(c: &mut Controller, link: &mut Session) -> std::string::String {
        let mut out = run(c, link, "status");
        finish(c, link, &mut out);
        let line = out
            .lines()
            .find_map(|l| l.strip_prefix("# state: "))
            .expect("a state line");
        line.into()
    }

    fn frame(c: &mut Controller, link: &mut Session, text: &str) {
        let mut out = std::string::String::new();
        for &b in text.as_bytes() {
            c.on_byte(link, b, &mut out);
        }
        c.apply_stream();
    }

    #[test]
    fn a_stream_without_frames_for_two_seconds_is_reported_idle_until_the_next_frame() {
        let (mut c, mut link) = (quiet(), program());
        run(&mut c, &mut link, "set speed_mm_s off");
        run(&mut c, &mut link, "set speed_deg_s off");
        frame(&mut c, &mut link, "128,128,140,128,128,128X");
        for _ in 0..99 {
            c.on_frame();
        }
        // 1.98 s at 50 Hz: still streaming.
        assert_eq!(state(&mut c, &mut link), "streaming (pass-through)");
        // 6,099 frames in all: 121.98 s.
        for _ in 0..6000 {
            c.on_frame();
        }
        assert_eq!(
            state(&mut c, &mut link),
            "idle (stream: no frame for 122.0 s; holding its last pose, the next frame resumes it)"
        );
        frame(&mut c, &mut link, "128,128,141,128,128,128X");
        assert_eq!(state(&mut c, &mut link), "streaming (pass-through)");
    }

    #[test]
    fn a_tracked_stream_still_on_its_way_is_streaming_however_old_its_last_frame() {
        let (mut c, mut link) = (quiet(), program());
        run(&mut c, &mut link, "set speed_mm_s 1");
        // Heave 7 mm at 1 mm/s: 7 s on the way.
        frame(&mut c, &mut link, "128,128,188,128,128,128X");
        for _ in 0..150 {
            c.on_frame();
        }
        assert!(c.is_streaming() && c.pose().z_mm > 2.0 && c.pose().z_mm < 5.0);
        assert_eq!(state(&mut c, &mut link), "streaming (tracking)");
        for _ in 0..400 {
            c.on_frame();
        }
        assert!(state(&mut c, &mut link).starts_with("idle (stream: no frame for 11.0 s;"));
    }
}
