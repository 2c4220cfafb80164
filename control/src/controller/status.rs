//! What `status` reports: the motion (moving, going home, streaming, pulses set directly,
//! idle), the pose, target, arm angles and pulses, the fault, the stream's counts, the e-stop
//! and the servo power. (With a payload its holding torques follow in a slice of their own:
//! [`StatusTorques`](super::listing::StatusTorques).)

use kinematics_core::Math;

use super::Controller;
use crate::report::{MotionReport, StatusReport};

impl<M: Math> Controller<M> {
    /// The report `status` lists, the holding torques still to be computed.
    pub(super) fn status(&self) -> StatusReport {
        let hz = f32::from(self.settings.frame_hz);
        let motion = match self.motion.progress() {
            None if self.stream.is_some() => MotionReport::Streaming {
                tracking: !self.passes_through(),
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
}
