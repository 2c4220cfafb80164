//! The servos' rated speeds ([`crate::servo_speed`]) applied: a move planned within them (and
//! its path time measured by its path check, `path.rs`), and a stream step shortened to them.
//! Off (no servo rated), each is one test of the settings.

use kinematics_core::ik::Solution;
use kinematics_core::{Math, Pose, LEGS};

use super::path::ServoTime;
use super::Controller;
use crate::motion::{Segment, SpeedLimits};
use crate::servo_speed::{PathTime, ServoSpeeds, PLAN_MARGIN};
use crate::tracker::Tracker;

impl<M: Math> Controller<M> {
    /// The straight move from the current pose to `target` (whose IK is `solution`) within
    /// `limits` and, with servo speed ratings, at most as fast as the arm angles at its two
    /// ends allow; then the path time its check is to measure along the path (`None` without
    /// ratings).
    pub(super) fn plan_within_servo_speed(
        &self,
        target: Pose,
        solution: &Solution,
        limits: SpeedLimits,
    ) -> (Segment, Option<ServoTime>) {
        let start = *self.motion.pose();
        let frame_hz = f32::from(self.settings.frame_hz);
        let speeds = &self.settings.servo_speed;
        if !speeds.rated() {
            return (Segment::plan(start, target, limits, frame_hz), None);
        }
        // The arms the servos are given now (those of `start`, or of pulses set by `servo`).
        let from = &self.solution.arm_rad;
        let planned_s = speeds.least_time_s(from, &solution.arm_rad);
        let capped = ServoSpeeds::capped_limits(limits, &start, &target, planned_s);
        let time = ServoTime {
            measured: PathTime::new(&start, &target, from),
            planned_s,
            limits,
            frame_hz,
        };
        (Segment::plan(start, target, capped, frame_hz), Some(time))
    }

    /// A stream step from the current pose to `next` (the tracker's step, whose IK is
    /// `solution`), shortened with servo speed ratings so that no arm turns by more than its
    /// rating in the frame: `next` and `solution` become the tracker and solution to take
    /// (left as they are if the servos can follow the step). The step is shortened, all axes
    /// alike, to the fraction of it the slowest arm can follow (at [`PLAN_MARGIN`]) and solved
    /// there; if an arm still turns too far (its angle is not linear along the step), its arm
    /// angles and pulses are taken the fraction of the way that keeps them within the ratings
    /// (pulses are linear in arm angles, eq. 13, 14; the pose is taken as far, within a
    /// second-order error of so short a step). Without ratings nothing is done; with ratings
    /// that the step keeps, six differences; a step shortened costs one IK solution more.
    pub(super) fn step_within_servo_speed(
        &self,
        tracker: &Tracker,
        next: &mut Tracker,
        solution: &mut Solution,
    ) {
        let speeds = &self.settings.servo_speed;
        if !speeds.rated() {
            return;
        }
        let dt_s = 1.0 / f32::from(self.settings.frame_hz.max(1));
        let from = &self.solution;
        let k = speeds.step_scale(&from.arm_rad, &solution.arm_rad, dt_s);
        if k >= 1.0 {
            return;
        }
        let part = tracker.part_way(next, k * PLAN_MARGIN);
        // (Both ends can be driven; should the way between them not be, the arms are taken
        // part of the way, as below.)
        if let Ok(there) = self.solver.solve::<M>(&self.settings.servos, &part.pose()) {
            *next = part;
            *solution = there;
        }
        let k = speeds.step_scale(&from.arm_rad, &solution.arm_rad, dt_s);
        if k >= 1.0 {
            return;
        }
        let part = |a: &[f32; LEGS], b: &[f32; LEGS]| -> [f32; LEGS] {
            core::array::from_fn(|i| a[i] + (b[i] - a[i]) * k)
        };
        *solution = Solution {
            arm_rad: part(&from.arm_rad, &solution.arm_rad),
            pulse_us: part(&from.pulse_us, &solution.pulse_us),
        };
        *next = tracker.part_way(next, k);
    }
}
