//! New build numbers (`set` of a layout setting): the new geometry and its IK are built a step
//! per slice, a job; then the pose being held must be drivable (and, with torque ratings,
//! held) with them, which the controller checks before it commits
//! (`controller/settings_change.rs`).

use kinematics_core::ik::{self, Solution};
use kinematics_core::{Geometry, Math};

use crate::error::Error;
use crate::settings::{SettingError, Settings};

/// How far a [`Rebuild`] has got.
#[allow(clippy::large_enum_variant)] // held in place, in the controller's one job
#[derive(Debug, Clone)]
pub(super) enum Stage {
    /// The geometry is to be built.
    Geometry,
    /// The geometry is built; its IK is next.
    Solver(Geometry),
    /// The IK is built; the pose being held must be drivable with it.
    HeldPose(ik::Solver),
    /// The held pose can be driven; with torque ratings, it must be held too.
    HeldTorque(ik::Solver, Solution),
}

/// New settings whose geometry and IK are being built, or whose held pose's holding torques
/// are to be checked.
#[derive(Debug, Clone)]
pub(super) struct Rebuild {
    pub candidate: Settings,
    pub stage: Stage,
}

impl Rebuild {
    /// Builds `candidate`'s geometry and IK, from the start.
    pub fn new(candidate: Settings) -> Rebuild {
        Rebuild {
            candidate,
            stage: Stage::Geometry,
        }
    }

    /// One step of building: `None` while building goes on (a step done), `Some(Err)` if the
    /// build cannot be, `Some(Ok)` when the IK is built and what is left is the held pose's
    /// check ([`Stage::HeldPose`], [`Stage::HeldTorque`]: nothing is done here then).
    pub fn step<M: Math>(&mut self) -> Option<Result<(), Error>> {
        let next = match &self.stage {
            Stage::Geometry => match self.candidate.layout.build_with::<M>() {
                Ok(geometry) => Stage::Solver(geometry),
                Err(e) => return Some(Err(SettingError::BadGeometry(e).into())),
            },
            Stage::Solver(geometry) => match ik::Solver::new_with::<M>(geometry.clone()) {
                Ok(solver) => Stage::HeldPose(self.candidate.about_pivot(solver)),
                Err(e) => return Some(Err(SettingError::BadGeometry(e).into())),
            },
            Stage::HeldPose(_) | Stage::HeldTorque(..) => return Some(Ok(())),
        };
        self.stage = next;
        None
    }
}
