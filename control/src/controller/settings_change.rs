//! A settings change (`set`, `defaults`): committed only if the complete new settings are
//! valid and the pose being held can still be driven (and, with torque ratings, held) with
//! them. New build numbers mean a new geometry and IK, built as a job ([`Rebuild`], a step per
//! slice); the held pose's torques are a step of that job too, and with pulses set by `servo`
//! their pose is found again ([`Locate`](super::locate::Locate)).

use kinematics_core::ik::{self, Solution};
use kinematics_core::Math;

use super::locate::{direct_solution, Relocate};
use super::rebuild::{Rebuild, Stage};
use super::{Begun, Controller, Done, Job};
use crate::error::Error;
use crate::settings::Settings;

impl<M: Math> Controller<M> {
    /// Commits `candidate` if it is valid and the pose being held can still be driven (and,
    /// with torque ratings, held) with it. New build numbers mean a new geometry and IK: that
    /// is built as a job, a step per slice; so are a torque check and, with pulses set by
    /// `servo`, finding their pose again.
    pub(super) fn change_settings(&mut self, candidate: Settings) -> Result<Begun, Error> {
        candidate.check_values()?;
        // A stream holds while the job runs (the held pose is what is checked).
        if candidate.layout != self.settings.layout {
            self.holding = self.is_streaming();
            self.job = Some(Job::Rebuild(Rebuild::new(candidate)));
            return Ok(Begun::Pending);
        }
        // A new pivot: the same geometry, turning about another point.
        let solver = candidate.about_pivot(self.solver.clone());
        self.hold_with(candidate, solver)
    }

    /// The last step of a settings change: the pose being held with the new settings and
    /// their IK. Committed now, or a job that checks more (the held pose's torques, or the
    /// pose of pulses set by `servo`).
    pub(super) fn hold_with(
        &mut self,
        candidate: Settings,
        solver: ik::Solver,
    ) -> Result<Begun, Error> {
        // A new pivot keeps the pose's numbers, so it moves the platform (away from home) or,
        // with pulses set by `servo`, changes the pose they are.
        let pivot_changed = candidate.pivot_mm != self.settings.pivot_mm;
        let torque_changed = candidate.payload != self.settings.payload
            || candidate.layout != self.settings.layout
            || pivot_changed;
        if self.direct.is_some() {
            let pulses_changed = candidate.servos != self.settings.servos
                || candidate.layout != self.settings.layout
                || pivot_changed;
            if !(pulses_changed || (torque_changed && candidate.payload.checked())) {
                self.commit_settings(candidate, solver, self.solution);
                return Ok(Begun::Answered);
            }
            // The pulses stay as they are: where they put the platform is found again.
            let solution = direct_solution(&candidate, &solver, self.solution.pulse_us)
                .map_err(|cause| Error::PoseConflict { cause })?;
            self.start_locate(Relocate::Settings, candidate, solver, solution);
            return Ok(Begun::Pending);
        }
        let solution = solver
            .solve::<M>(&candidate.servos, self.motion.pose())
            .map_err(|cause| Error::PoseConflict {
                cause: cause.into(),
            })?;
        if torque_changed && candidate.payload.checked() {
            self.holding = self.is_streaming();
            self.job = Some(Job::Rebuild(Rebuild {
                candidate,
                stage: Stage::HeldTorque(solver, solution),
            }));
            return Ok(Begun::Pending);
        }
        self.commit_settings(candidate, solver, solution);
        Ok(Begun::Answered)
    }

    /// A slice of a [`Rebuild`]: a step of building new settings' geometry and IK, then the
    /// held pose with them (or its torques). `None` while steps remain (or a job of its own
    /// follows), then the outcome (committed, or why not).
    pub(super) fn rebuild_slice(&mut self) -> Option<Done> {
        let Some(Job::Rebuild(rebuild)) = &mut self.job else {
            return None;
        };
        if let Err(e) = rebuild.step::<M>()? {
            self.job = None;
            return Some(Done::Refused(e));
        }
        let Some(Job::Rebuild(Rebuild { candidate, stage })) = self.job.take() else {
            return None;
        };
        let result = match stage {
            Stage::HeldPose(solver) => match self.hold_with(candidate, solver) {
                Ok(Begun::Answered) => Ok(()),
                Ok(Begun::Pending) => return None, // a job of its own follows
                Err(e) => Err(e),
            },
            Stage::HeldTorque(solver, solution) => {
                let pose = *self.motion.pose();
                candidate
                    .payload
                    .check::<M>(&solver, &pose, &solution.arm_rad)
                    .map_err(|cause| Error::PoseConflict {
                        cause: cause.into(),
                    })
                    .map(|()| self.commit_settings(candidate, solver, solution))
            }
            // (Built by `step` above.)
            Stage::Geometry | Stage::Solver(_) => return None,
        };
        Some(match result {
            Ok(()) => Done::Ok,
            Err(e) => Done::Refused(e),
        })
    }

    /// Commits checked settings, their IK and the pulses to give with them (which change
    /// right away).
    pub(super) fn commit_settings(
        &mut self,
        candidate: Settings,
        solver: ik::Solver,
        solution: Solution,
    ) {
        self.settings = candidate;
        self.solver = solver;
        self.new_pulses |= solution.pulse_us != self.solution.pulse_us;
        self.solution = solution;
        self.generation = self.generation.wrapping_add(1);
    }
}

#[cfg(test)]
mod tests {
    use crate::controller::test_support::*;

    #[test]
    fn new_build_numbers_are_built_a_step_per_slice() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        let h0 = c.geometry().home_height_mm();
        for &b in b"set rod_mm 125\n" {
            c.on_byte(&mut link, b, &mut out);
        }
        assert!(link.awaits_reply() && out.is_empty());
        let mut slices = 0;
        while link.awaits_reply() {
            assert_eq!(
                c.settings().layout.rod_mm,
                120.0,
                "committed only at the end"
            );
            c.work(&mut link, &mut out);
            slices += 1;
        }
        assert_eq!((slices, out.as_str()), (3, "ok\r\n"));
        assert_eq!(c.settings().layout.rod_mm, 125.0);
        assert!(c.geometry().home_height_mm() > h0 + 4.0);
        // A build that cannot be is refused at the step that finds it; nothing changes.
        out.clear();
        let before = *c.settings();
        c.execute_line(&mut link, "set rod_mm 15", &mut out);
        assert!(out.starts_with("error:bad-geometry "), "{out}");
        assert_eq!(*c.settings(), before);
        // A value out of range is refused at once, before any step.
        out.clear();
        for &b in b"set rod_mm 3000\n" {
            c.on_byte(&mut link, b, &mut out);
        }
        assert!(!link.awaits_reply() && out.starts_with("error:out-of-range "));
    }
}
