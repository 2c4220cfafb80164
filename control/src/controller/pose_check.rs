//! Whether a pose can be taken, the test every job that checks poses shares (a path's
//! checkpoints, a clamp's halvings, `limits`' search): the IK within the servo limits and, with
//! torque ratings, every servo's holding torque within its rating; and how many poses one slice
//! of work checks.
//!
//! Payload and torque ratings ([`crate::payload`]): with a payload, `check` and `status` show
//! the holding torques (a slice of their own: about five IK solutions' worth); with ratings as
//! well, every pose checked (a target, each checkpoint of a path, each pose `limits` tries, a
//! stream target and its clamp, the pose held when the settings change) must be within them,
//! and a slice then checks one pose with its torques instead of [`CHECKS_PER_SLICE`] by the IK.

use kinematics_core::ik::{self, Solution};
use kinematics_core::{KinematicsError, Math, Pose, LEGS};

use crate::error::PoseError;
use crate::settings::Settings;

/// Most IK solutions of a path check in one slice of work
/// ([`Controller::work`](super::Controller::work)): on the RP2040 one takes about 0.09 ms, so a
/// slice stays well under half a millisecond. With a payload and torque ratings, each pose
/// checked also needs its holding torques (about 0.38 ms, five IK solutions' worth): then a
/// slice checks one pose.
pub const CHECKS_PER_SLICE: u32 = 3;

/// Holding torques (kgf cm), or why there are none.
pub(super) type Torques = Result<[f32; LEGS], KinematicsError>;

/// The active settings and their IK, as a slice of work reads them (borrowed beside the job
/// being advanced, which stays where it is held).
#[derive(Clone, Copy)]
pub(super) struct PoseCheck<'a> {
    pub settings: &'a Settings,
    pub solver: &'a ik::Solver,
}

impl PoseCheck<'_> {
    /// How many poses a slice of work checks: [`CHECKS_PER_SLICE`] by the IK alone, or one
    /// with its holding torques when there are ratings to check.
    pub fn per_slice(&self) -> u32 {
        if self.settings.payload.checked() {
            1
        } else {
            CHECKS_PER_SLICE
        }
    }

    /// Whether a pose can be taken: the IK within the servo limits and, if `torque`, every
    /// servo's holding torque within its rating. Its solution if so.
    pub fn pose<M: Math>(&self, pose: &Pose, torque: bool) -> Result<Solution, PoseError> {
        let solution = self.solver.solve::<M>(&self.settings.servos, pose)?;
        if torque {
            self.settings
                .payload
                .check::<M>(self.solver, pose, &solution.arm_rad)?;
        }
        Ok(solution)
    }
}
