//! The jobs whose reply is a listing: a listing written a line per slice ([`Writing`]), and
//! `status` with a payload, whose holding torques take a slice of their own before it is
//! listed ([`StatusTorques`]). (`limits`' search, which ends in a listing too, is
//! `controller/limits.rs`; what `status` reports is `controller/status.rs`.)

use core::fmt::Write;

use kinematics_core::ik;
use kinematics_core::Math;

use super::pose_check::{PoseCheck, Torques};
use crate::report::{Listing, StatusReport};
use crate::settings::Settings;

/// A listing being written, line `next` next.
#[derive(Debug, Clone)]
pub(super) struct Writing {
    listing: Listing,
    next: usize,
}

impl Writing {
    /// `listing`, from its first line.
    pub fn new(listing: Listing) -> Writing {
        Writing { listing, next: 0 }
    }

    /// Writes the next line (`settings` and `solver` are the active ones): `true` if it did,
    /// `false` if the listing is complete.
    pub fn step(&mut self, settings: &Settings, solver: &ik::Solver, out: &mut impl Write) -> bool {
        let wrote = self.listing.write_line(self.next, settings, solver, out);
        if wrote {
            self.next += 1;
        }
        wrote
    }
}

/// `status` with a payload: the report, whose holding torques are computed (a slice), then
/// listed.
#[derive(Debug, Clone, Copy)]
pub(super) struct StatusTorques(pub StatusReport);

impl StatusTorques {
    /// The slice: the holding torques at the report's pose, with its arm angles; the listing
    /// to write.
    pub fn step<M: Math>(&self, check: PoseCheck<'_>) -> Listing {
        let mut report = self.0;
        report.torque_kgcm = Some(self.torques::<M>(check));
        Listing::Status(report)
    }

    /// The holding torques `status` shows: at its pose, with its arm angles (with pulses set
    /// by `servo` that correspond to no pose, there are none).
    fn torques<M: Math>(&self, check: PoseCheck<'_>) -> Torques {
        let report = &self.0;
        if let Some(Err(e)) = report.pulse_pose {
            return Err(e);
        }
        check.settings.payload.holding_torques_kgcm::<M>(
            check.solver,
            &report.pose,
            &report.arm_rad,
        )
    }
}
