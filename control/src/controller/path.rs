//! A path check: the job of a reachable target whose straight path from the current pose is
//! checked by the IK at up to [`crate::motion::MAX_PATH_CHECKS`] checkpoints, a few per slice
//! ([`PoseCheck::per_slice`]). With a payload to check against ratings or to report (`check`),
//! the target's holding torques come first, in a slice of their own. What a checked path leads
//! to (a move, a jump, `check`'s listing, the way home) is the controller's
//! (`controller/moves.rs`).

use kinematics_core::ik::Solution;
use kinematics_core::Math;

use super::pose_check::{PoseCheck, Torques};
use crate::error::Error;
use crate::motion::{Checkpoints, Segment};
use crate::payload::TorqueError;
use crate::settings::Settings;

/// What a checked path is for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Purpose {
    /// `pose`, `move`, `nudge`, `home`: start the move (a jump if `jump`).
    Move { jump: bool },
    /// `check`: report, move nothing.
    Check,
    /// Link loss: return home.
    ReturnHome,
    /// The e-stop opened with `estop_action home`: go home.
    EstopHome,
}

impl Purpose {
    /// The controller's own (no command waits for its reply).
    pub fn is_own(self) -> bool {
        matches!(self, Purpose::ReturnHome | Purpose::EstopHome)
    }

    /// Whether a path check for this starts with the target's holding torques: with ratings to
    /// check, or for `check` to report.
    pub fn needs_target_torque(self, settings: &Settings) -> bool {
        let payload = &settings.payload;
        payload.checked() || (self == Purpose::Check && payload.carried())
    }
}

/// A reachable target whose straight path is being checked.
#[derive(Debug, Clone, Copy)]
pub(super) struct PathCheck {
    pub purpose: Purpose,
    /// The target's solution (solved when the command came).
    pub solution: Solution,
    pub segment: Segment,
    checkpoints: Checkpoints,
    /// The target's holding torques: `None` until computed (the first slice, when there is a
    /// payload to check or report), then what `check` reports.
    torque: Option<Option<Torques>>,
}

impl PathCheck {
    /// The check of `segment`, whose target has `solution`, for `purpose` with `settings`.
    pub fn new(
        purpose: Purpose,
        solution: Solution,
        segment: Segment,
        settings: &Settings,
    ) -> PathCheck {
        PathCheck {
            purpose,
            solution,
            segment,
            checkpoints: segment.checkpoints(),
            // The target's torques take a slice of their own, if they are needed at all.
            torque: if purpose.needs_target_torque(settings) {
                None
            } else {
                Some(None)
            },
        }
    }

    /// The target's holding torques for `check` to report (`None` when there are none to
    /// report, or they were not reached).
    pub fn torque(&self) -> Option<Torques> {
        self.torque.flatten()
    }

    /// One slice: the target's holding torques, or [`PoseCheck::per_slice`] more poses of the
    /// path. `None` while poses remain, `Some(Ok)` if the whole path is clear, `Some(Err)` at
    /// the first pose that is not (or if the target's torques exceed the ratings).
    pub fn step<M: Math>(&mut self, check: PoseCheck<'_>) -> Option<Result<(), Error>> {
        if self.torque.is_none() {
            // The target's holding torques first, in a slice of their own.
            return match self.target_torque::<M>(check) {
                Ok(torque) => {
                    self.torque = Some(torque);
                    None
                }
                Err(e) => Some(Err(e)),
            };
        }
        self.check_slice::<M>(check)
    }

    /// The first slice of a path check: the target's holding torques, if there is a payload
    /// to check against ratings (refused if one is exceeded) or to report (`check`);
    /// `Ok(None)` otherwise.
    fn target_torque<M: Math>(&self, check: PoseCheck<'_>) -> Result<Option<Torques>, Error> {
        let payload = &check.settings.payload;
        let report = self.purpose == Purpose::Check && payload.carried();
        if !self.purpose.needs_target_torque(check.settings) {
            return Ok(None);
        }
        let torques = payload.holding_torques_kgcm::<M>(
            check.solver,
            self.segment.target(),
            &self.solution.arm_rad,
        );
        if payload.checked() {
            match torques {
                Ok(t) => payload.within_ratings(&t)?,
                Err(e) => return Err(TorqueError::Unknown(e).into()),
            }
        }
        Ok(report.then_some(torques))
    }

    /// Checks [`PoseCheck::per_slice`] more poses of the path: `None` if poses remain,
    /// `Some(Ok)` if the whole path is clear, `Some(Err)` at the first that is not.
    fn check_slice<M: Math>(&mut self, check: PoseCheck<'_>) -> Option<Result<(), Error>> {
        let torque = check.settings.payload.checked();
        let mut solved = 0;
        while solved < check.per_slice() {
            let Some((pose, fraction)) = self.checkpoints.next() else {
                return Some(Ok(()));
            };
            if pose == *self.segment.target() {
                continue; // checked when the command came and in the first slice
            }
            solved += 1;
            if let Err(cause) = check.pose::<M>(&pose, torque) {
                return Some(Err(Error::PathBlocked {
                    percent: fraction * 100.0,
                    cause,
                }));
            }
        }
        None
    }
}
