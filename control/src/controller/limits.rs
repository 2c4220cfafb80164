//! `limits`: the reach along each axis-direction from the current pose
//! ([`workspace::Limits`]), a job of a few poses per slice, each checked as every target is
//! ([`PoseCheck`]); its reply is the listing of the twelve reaches.

use kinematics_core::{workspace, Math, Pose};

use super::pose_check::PoseCheck;
use crate::error::PoseError;
use crate::report::Listing;

/// `limits`' search in progress.
#[derive(Debug, Clone)]
pub(super) struct LimitsSearch {
    start: Pose,
    search: workspace::Limits<PoseError>,
}

impl LimitsSearch {
    /// The search from `start`.
    pub fn new(start: Pose) -> LimitsSearch {
        LimitsSearch {
            start,
            search: workspace::Limits::new(start, workspace::Options::default()),
        }
    }

    /// A slice of the search: `None` while poses remain, then the listing of the twelve
    /// reaches.
    pub fn step<M: Math>(&mut self, check: PoseCheck<'_>) -> Option<Listing> {
        let torque = check.settings.payload.checked();
        for _ in 0..check.per_slice() {
            let found = self
                .search
                .step(|pose| check.pose::<M>(pose, torque).map(|_| ()));
            if let Some(reaches) = found {
                return Some(Listing::Limits {
                    start: self.start,
                    reaches,
                });
            }
        }
        None
    }
}
