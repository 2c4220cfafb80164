//! Driving servos one by one (`servo n us`): the pulse goes to that servo (within its limits;
//! refused while a move is in progress or the e-stop is on; a stream ends), and the job finds
//! the pose the six pulses correspond to by forward kinematics
//! ([`Newton`](kinematics_core::forward::Newton), one iteration per slice) along a
//! continuation from the pose the platform was at ([`FK_STEP_RAD`](super::FK_STEP_RAD)), then
//! checks it with the IK (and, with torque ratings, its holding torques); the pulse is given
//! when that is done. FK runs there, once per change of the pulses, not in `status`: `status`
//! shows the pose found (or that there is none), and moves, `check` and `limits` start from
//! it, so that a move after `servo` does not jump (with no pose they are refused). A settings
//! change while the pulses are set this way keeps them and finds their pose again. An accepted
//! move or stream frame ends it.
//!
//! The forward kinematics job is `controller/locate.rs`'s; here is what starts it and what its
//! outcome does.

use kinematics_core::ik::{self, Solution};
use kinematics_core::{Math, LEGS};

use super::locate::{direct_solution, Locate, Located, Relocate};
use super::{Begun, Controller, Done, Job};
use crate::error::Error;
use crate::motion::Motion;
use crate::settings::Settings;

impl<M: Math> Controller<M> {
    /// `servo n us`: refused while a move is in progress and with the e-stop on; the pulse
    /// within the servo's limits. Its pose is found (a job); the pulse is given once found.
    pub(super) fn drive_servo(&mut self, servo: u8, pulse_us: f32) -> Result<Begun, Error> {
        if self.motion.is_moving() {
            return Err(Error::Busy);
        }
        let index = usize::from(servo.clamp(1, LEGS as u8) - 1);
        let config = &self.settings.servos.0[index];
        if !config.allows(pulse_us) {
            return Err(Error::PulseOutsideLimits {
                servo,
                pulse_us,
                min_us: config.min_us,
                max_us: config.max_us,
            });
        }
        let mut pulses = self.safe_pulses();
        pulses[index] = pulse_us;
        let solution =
            direct_solution(&self.settings, &self.solver, pulses).map_err(Error::from)?;
        // A stream holds while the pose is found; the command ends it.
        self.holding = self.is_streaming();
        self.start_locate(
            Relocate::Servo,
            self.settings,
            self.solver.clone(),
            solution,
        );
        Ok(Begun::Pending)
    }

    /// Starts finding the pose of `solution`'s arm angles (forward kinematics), along the
    /// continuation from the pose the platform was last known at.
    pub(super) fn start_locate(
        &mut self,
        why: Relocate,
        candidate: Settings,
        solver: ik::Solver,
        solution: Solution,
    ) {
        let start = *self.motion.pose();
        self.job = Some(Job::Locate(Locate::new::<M>(
            why, candidate, solver, solution, start,
        )));
    }

    /// A slice of a [`Locate`]: `None` while steps remain, then the outcome: the pulses given
    /// (with the pose found, or knowing there is none), or refused (the e-stop opened
    /// meanwhile, or a servo would be overloaded).
    pub(super) fn locate_slice(&mut self) -> Option<Done> {
        let estop = self.estop.stops_motion();
        let Some(Job::Locate(locate)) = &mut self.job else {
            return None;
        };
        if locate.why == Relocate::Servo && estop {
            // The e-stop opened while the pose was being found: the servo is not driven.
            self.job = None;
            self.estop_home_after_job();
            return Some(Done::Refused(Error::Estop(self.estop)));
        }
        let located = match locate.step::<M>()? {
            Ok(located) => located,
            Err(e) => {
                self.job = None;
                return Some(Done::Refused(e));
            }
        };
        let Some(Job::Locate(Locate {
            why,
            candidate,
            solver,
            solution,
            ..
        })) = self.job.take()
        else {
            return None;
        };
        self.commit_direct(why, candidate, solver, solution, located);
        Some(Done::Ok)
    }

    /// Gives pulses set directly, with their settings, and where they put the platform.
    pub(super) fn commit_direct(
        &mut self,
        why: Relocate,
        candidate: Settings,
        solver: ik::Solver,
        solution: Solution,
        located: Located,
    ) {
        if why == Relocate::Servo {
            // Like an accepted move: the stream ends, the servos are powered, a fault is
            // cleared.
            self.end_stream();
            self.returning_home = false;
            self.servo_power = true;
            self.fault = None;
        }
        if candidate != self.settings {
            self.generation = self.generation.wrapping_add(1);
        }
        self.settings = candidate;
        self.solver = solver;
        self.new_pulses |= solution.pulse_us != self.solution.pulse_us;
        self.solution = solution;
        if let Ok(pose) = located {
            self.motion = Motion::new(pose);
        }
        self.direct = Some(located);
    }
}
