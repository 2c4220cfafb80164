//! Finding the pose of pulses set directly (`servo`, or a settings change while they are): the
//! forward kinematics ([`forward::Newton`], one iteration per slice) along a continuation from
//! the pose the platform was at ([`FK_STEP_RAD`]), then the IK's agreement and, with torque
//! ratings, the holding torques. A job; what its outcome does is the controller's
//! (`controller/servo.rs`).

use kinematics_core::forward::{self, Newton};
use kinematics_core::ik::{self, IkError, Solution};
use kinematics_core::{KinematicsError, Math, Pose, LEGS};

use crate::error::{Error, PoseError};
use crate::settings::Settings;

/// Largest change of any arm angle between two forward kinematics solves of a continuation,
/// rad (5 degrees).
///
/// The forward kinematics has several solutions and Newton's method finds the one nearest
/// where it starts; a servo driven far at once (tens of degrees) can make it land on another
/// assembly mode than the one the platform moves through (with the default build, servo 1
/// from 1900 us back to 1500 us, one step, lands 40 mm away from home). So the arm angles go
/// from those of the pose the platform was at to the new ones in steps of at most this much,
/// each solved from the last: the platform's own continuous path. Against a continuation in
/// 0.1 degree steps, 5 degree steps agreed on every one of 1,200 random single-servo changes;
/// they cost about 20 Newton iterations for a change of tens of degrees.
pub const FK_STEP_RAD: f32 = 5.0 * core::f32::consts::PI / 180.0;

/// The pulses set with `servo`: the pose they correspond to (the forward kinematics), or why
/// there is none.
pub(super) type Located = Result<Pose, KinematicsError>;

/// Why the pose of a set of pulses is being found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Relocate {
    /// `servo` drives a servo directly.
    Servo,
    /// The settings change while the pulses are set directly: the pulses stay.
    Settings,
}

/// Forward kinematics along a continuation: the arm angles go from `from_rad` to `to_rad` in
/// `steps` equal steps, each solved by Newton's method from the pose of the step before.
#[derive(Debug, Clone)]
struct Continuation {
    from_rad: [f32; LEGS],
    to_rad: [f32; LEGS],
    /// The step being solved, 1..=steps.
    step: u8,
    steps: u8,
    newton: Newton,
}

impl Continuation {
    /// The arm angles of step `step` of `steps` from `from_rad` to `to_rad`.
    fn arms_at(from_rad: &[f32; LEGS], to_rad: &[f32; LEGS], step: u8, steps: u8) -> [f32; LEGS] {
        let t = f32::from(step) / f32::from(steps);
        core::array::from_fn(|i| from_rad[i] + (to_rad[i] - from_rad[i]) * t)
    }

    /// The arm angles of step `step`.
    fn arms(&self, step: u8) -> [f32; LEGS] {
        Continuation::arms_at(&self.from_rad, &self.to_rad, step, self.steps)
    }
}

/// How far a [`Locate`] has got.
#[allow(clippy::large_enum_variant)] // held in place, in the controller's one job
#[derive(Debug, Clone)]
enum Stage {
    /// Newton's method, an iteration per slice ([`forward::Newton::step`]), along a
    /// continuation.
    Newton(Continuation),
    /// Found: the IK must agree (the arms on eq. 9's root the IK takes).
    Arms(Pose),
    /// The holding torques at the pose found, against the ratings.
    Torque(Pose),
    /// There is none: why.
    NoPose(KinematicsError),
}

/// Pulses whose pose is being found (forward kinematics, a Newton iteration per slice), and
/// the settings they go with; committed when found (or found to be no pose).
#[derive(Debug, Clone)]
pub(super) struct Locate {
    pub why: Relocate,
    pub candidate: Settings,
    pub solver: ik::Solver,
    /// The pulses and the arm angles they command.
    pub solution: Solution,
    stage: Stage,
}

impl Locate {
    /// Starts finding the pose of `solution`'s arm angles (forward kinematics), along the
    /// continuation from `start`, the pose the platform was last known at (and the arm
    /// angles the IK gives there), to them ([`FK_STEP_RAD`]).
    pub fn new<M: Math>(
        why: Relocate,
        candidate: Settings,
        solver: ik::Solver,
        solution: Solution,
        start: Pose,
    ) -> Locate {
        let to_rad = solution.arm_rad;
        // Where that pose puts the arms with these settings (if it can: else one solve from
        // there).
        let from_rad = solver.arm_angles::<M>(&start).unwrap_or(to_rad);
        let change = (0..LEGS).fold(0.0f32, |m, i| m.max((to_rad[i] - from_rad[i]).abs()));
        // At most 36 steps: arm angles stay within half a turn of each other.
        let steps = (change / FK_STEP_RAD).clamp(1.0, 36.0) as u8;
        let steps = if f32::from(steps) * FK_STEP_RAD < change {
            steps.saturating_add(1)
        } else {
            steps
        };
        let first = Continuation::arms_at(&from_rad, &to_rad, 1, steps);
        let stage = match forward::Closure::arms::<M>(&solver, &first) {
            Ok(closure) => Stage::Newton(Continuation {
                from_rad,
                to_rad,
                step: 1,
                steps,
                newton: Newton::new(closure, start, forward::Options::default()),
            }),
            // (Only for angles that are not finite, which pulses within limits never give.)
            Err(e) => Stage::NoPose(e),
        };
        Locate {
            why,
            candidate,
            solver,
            solution,
            stage,
        }
    }

    /// One step of finding the pose: a Newton iteration, the IK's agreement, the holding
    /// torques. `None` while steps remain, then the outcome: the pulses are to be given, with
    /// the pose found or knowing there is none (`Ok`), or refused (a servo would be
    /// overloaded).
    pub fn step<M: Math>(&mut self) -> Option<Result<Located, Error>> {
        let next = match &mut self.stage {
            Stage::Newton(c) => match c.newton.step::<M>() {
                None => return None,
                Some(Ok(found)) if c.step >= c.steps => Stage::Arms(found.pose),
                Some(Ok(found)) => {
                    // The next step of the continuation, from this one's pose.
                    c.step += 1;
                    match forward::Closure::arms::<M>(&self.solver, &c.arms(c.step)) {
                        Ok(closure) => {
                            c.newton =
                                Newton::new(closure, found.pose, forward::Options::default());
                            return None;
                        }
                        Err(e) => Stage::NoPose(e),
                    }
                }
                Some(Err(e)) => Stage::NoPose(e),
            },
            Stage::Arms(pose) => {
                let pose = *pose;
                match forward::check_arms::<M>(&self.solver, &pose, &self.solution.arm_rad) {
                    Err(e) => Stage::NoPose(e),
                    Ok(()) if self.candidate.payload.checked() => Stage::Torque(pose),
                    Ok(()) => return Some(Ok(Ok(pose))),
                }
            }
            Stage::Torque(pose) => {
                let pose = *pose;
                let held =
                    self.candidate
                        .payload
                        .check::<M>(&self.solver, &pose, &self.solution.arm_rad);
                return Some(match (held, self.why) {
                    (Ok(()), _) => Ok(Ok(pose)),
                    (Err(e), Relocate::Servo) => Err(Error::Torque(e)),
                    (Err(e), Relocate::Settings) => Err(Error::PoseConflict { cause: e.into() }),
                });
            }
            // Pulses that correspond to no pose are given all the same (rods unhooked,
            // calibration): moves are refused until they do again.
            Stage::NoPose(e) => return Some(Ok(Err(*e))),
        };
        self.stage = next;
        None
    }
}

/// The solution of pulses set directly: the pulses, within `settings`' limits, and the arm
/// angles they command (the inverse of eq. 13, 14).
pub(super) fn direct_solution(
    settings: &Settings,
    solver: &ik::Solver,
    pulse_us: [f32; LEGS],
) -> Result<Solution, PoseError> {
    for (i, (servo, &pulse)) in settings.servos.0.iter().zip(&pulse_us).enumerate() {
        if !servo.allows(pulse) {
            return Err(IkError::ServoLimit {
                servo: i as u8 + 1,
                pulse_us: pulse,
                min_us: servo.min_us,
                max_us: servo.max_us,
            }
            .into());
        }
    }
    // Finite pulses within valid servo settings: finite angles.
    let arm_rad =
        forward::arm_angles_for_pulses(solver, &settings.servos, &pulse_us).map_err(|_| {
            IkError::NonFinite {
                axis: kinematics_core::pose::Axis::X,
            }
        })?;
    Ok(Solution { arm_rad, pulse_us })
}
