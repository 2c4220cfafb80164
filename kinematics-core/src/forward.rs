//! Forward kinematics: the pose from the six joint values, strut lengths (mm) or servo arm
//! angles (rad).
//!
//! - [`approximate`]: the Stewart platform Simscape model documentation's
//!   `forwardKinematicsApprox`, `dX = J^-1 dL` about a known pose, the rotation part applied
//!   as a rotation about the screw axis `dX[3..6]` (Rodrigues' formula, as the documentation
//!   does). Exact to first order; good for small changes. Any [`Actuators`].
//! - [`Newton`]: exact, by Newton's method from a starting pose (the pose at the previous frame,
//!   or [`approximate`]'s answer). The forward kinematics has several solutions ("The
//!   Mathematics of the Stewart Platform": up to 40 for struts; the planar 3-RPR forward
//!   kinematics project finds one root per assembly mode), so where it ends depends on where
//!   it starts: each step is bounded ([`Options::max_step_mm`], [`Options::max_step_rad`]) and
//!   a step that makes the residual clearly worse is halved, so that it stays with the
//!   solution nearest the start instead of jumping to another assembly mode; iterations are
//!   bounded too ([`Options::max_iterations`]) and running out is an error
//!   ([`KinematicsError::NotConverged`]), as is a singular pose on the way.
//!
//! Both kinds of platform are solved as six closures ([`Closure`]): platform joint `q_i(X)`
//! must be at the distance `L_i` from a point `A_i` fixed in the base frame. For struts `A_i`
//! is the base joint and `L_i` the strut's length (eq. 3 of "The Mathematics of the Stewart
//! Platform" with `|l_i| = L_i`); for servos `A_i` is the arm tip at the arm angle given
//! (eq. 4-6) and `L_i` the rod length `s` (the rod closure behind eq. 7-9). Solving the
//! closures rather than eq. 9's arm angles keeps Newton's method well behaved near the edge of
//! the workspace (where an arm angle moves like the square root of the distance to it) and
//! costs no IK per iteration.
//!
//! Newton's step solves `J dX = (L^2 - |q(X) - A|^2) / 2` with the Jacobian of
//! `|q(X) - A|^2 / 2`, rows `[d_i^T, (r_i x d_i)^T]` (`d_i = q_i - A_i`, as the struts' rows
//! of [`crate::jacobian`] times `|d_i|`; no square root); `dX` moves the rotation centre by
//! `dX[0..3]` and turns the platform by `dX[3..6]`; it becomes pose coordinates with
//! [`euler_rates_from_rotation`]. To save work it
//! keeps `J`'s factors while the steps are short and shrink fast (the chord method: the same
//! root, as the residual is always exact) and linearises afresh when they do not. It stops
//! after a step that moves less than [`Options::step_tolerance_mm`] and
//! [`Options::step_tolerance_rad`], or that was computed from residuals as small as the
//! `f32` rounding of the lengths (four units in the last place).
//!
//! [`Newton`] is a state that does one iteration per [`Newton::step`] (the platform's joints,
//! at most one Jacobian and one 6x6 factorisation; less than one IK), so a main loop can spread
//! a solve over several passes; [`solve`] runs it to the end.

use core::f32::consts::PI;

use crate::configuration::Anchors;
use crate::error::{Input, KinematicsError};
use crate::ik::Solver;
use crate::jacobian::{euler_rates_from_rotation, Actuators};
use crate::legs::{arm_tips, Struts, MIN_LENGTH_MM};
use crate::linalg::{Lu6, Mat6, Vec6};
use crate::math::{abs_bits, cross, dot, lt, sub, Math, Real};
use crate::pose::Pose;
use crate::servo::ServoSet;
use crate::types::{Mat3, Vec3, LEGS};

/// How [`Newton`] iterates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Most iterations before giving up.
    pub max_iterations: u8,
    /// Converged when a step moves the rotation centre less than this, mm...
    pub step_tolerance_mm: f32,
    /// ...and turns each Euler angle less than this, rad.
    pub step_tolerance_rad: f32,
    /// A step moving the centre farther is shortened to this, mm.
    pub max_step_mm: f32,
    /// A step turning the platform more is shortened to this, rad.
    pub max_step_rad: f32,
}

impl Default for Options {
    /// 8 iterations; converged after a step below 1e-3 mm and 5e-5 rad (what is left after a
    /// step is at most a tenth of it: a fresh Newton step converges quadratically, and the
    /// chord method keeps its factors only while steps shrink tenfold; the `f32` noise of the
    /// closures moves a hand-sized platform by about 1e-4 mm); steps of at most 10 mm and
    /// 0.2 rad.
    fn default() -> Options {
        Options {
            max_iterations: 8,
            step_tolerance_mm: 1e-3,
            step_tolerance_rad: 5e-5,
            max_step_mm: 10.0,
            max_step_rad: 0.2,
        }
    }
}

/// The six closures a forward kinematics solves: platform joint `i` at the distance
/// `lengths_mm[i]` from the base-frame point `lower_mm[i]` (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closure {
    /// The platform's anchors (upper anchors, home height, rotation centre).
    anchors: Anchors,
    /// `A_i`: base joints, or arm tips, base frame, mm.
    lower_mm: [Vec3; LEGS],
    /// `L_i`: strut lengths, or the rod length, mm.
    lengths_mm: [f32; LEGS],
    /// `L_i^2 / 2`, mm^2.
    half_squares_mm2: [f32; LEGS],
    /// Residuals (mm^2) this small are the `f32` rounding of the lengths (see
    /// [`Closure::evaluate`]).
    noise_mm2: f32,
    /// Residuals (mm^2) below this are too close to that noise to judge a step by.
    floor_mm2: f32,
}

/// One evaluation of the closures at a pose.
struct Evaluation {
    /// `L_i^2 / 2 - |q_i - A_i|^2 / 2`, mm^2.
    residual: Vec6,
    /// The leg with the largest residual magnitude, and that magnitude, mm^2.
    largest_leg: usize,
    largest_mm2: f32,
    /// The platform's rotation at that pose.
    rotation: Mat3,
    /// The residuals' Jacobian, if asked for: rows `[d_i^T, (r_i x d_i)^T]`.
    jacobian: Option<Mat6>,
}

impl Closure {
    fn new(anchors: Anchors, lower_mm: [Vec3; LEGS], lengths_mm: [f32; LEGS]) -> Closure {
        let longest = lengths_mm.iter().fold(0.0f32, |m, l| m.max(*l));
        Closure {
            anchors,
            lower_mm,
            lengths_mm,
            half_squares_mm2: lengths_mm.map(|l| 0.5 * l * l),
            // Four units in the last place of the longest length, times the length.
            noise_mm2: 4.0 * f32::EPSILON * longest * longest,
            floor_mm2: NOISE_RESIDUAL_MM * longest,
        }
    }

    /// Struts of the given lengths (mm).
    pub fn struts(struts: &Struts, lengths_mm: &[f32; LEGS]) -> Result<Closure, KinematicsError> {
        for (i, l) in lengths_mm.iter().enumerate() {
            if !(l.is_finite() && lt(MIN_LENGTH_MM, *l)) {
                return Err(KinematicsError::NonFinite {
                    input: Input::Joint { leg: i as u8 + 1 },
                });
            }
        }
        let anchors = struts.anchors();
        Ok(Closure::new(anchors, anchors.base_mm, *lengths_mm))
    }

    /// Servo arms at the given angles (rad): the rods' lower ends are the arm tips (eq. 4-6).
    pub fn arms<M: Math>(
        solver: &Solver,
        arm_rad: &[f32; LEGS],
    ) -> Result<Closure, KinematicsError> {
        if let Some(i) = arm_rad.iter().position(|a| !a.is_finite()) {
            return Err(KinematicsError::NonFinite {
                input: Input::Joint { leg: i as u8 + 1 },
            });
        }
        Ok(Closure::new(
            Actuators::anchors(solver),
            arm_tips::<M>(solver, arm_rad).0,
            [solver.geometry().rod_mm(); LEGS],
        ))
    }

    /// Servo arms at the angles six pulse widths command (the inverse of eq. 13, 14).
    pub fn pulses<M: Math>(
        solver: &Solver,
        servos: &ServoSet,
        pulse_us: &[f32; LEGS],
    ) -> Result<Closure, KinematicsError> {
        Closure::arms::<M>(solver, &arm_angles_for_pulses(solver, servos, pulse_us)?)
    }

    /// The closures at `pose` as residuals `f_i = (L_i^2 - |d_i|^2) / 2` with `d_i = q_i - A_i`
    /// (mm^2; no square root), whose Jacobian is `-[d_i^T, (r_i x d_i)^T]` (the derivative of
    /// `|d_i|^2 / 2` along a twist is `d_i . (v + omega x r_i)`), so that Newton's step solves
    /// `[d_i, r_i x d_i] dX = f`. A residual `f_i` is `L_i` times the length error. Rounding
    /// makes `|d_i|^2` uncertain by a few units in its last place: [`Closure::noise_mm2`].
    fn evaluate<M: Math>(
        &self,
        pose: &Pose,
        jacobian: bool,
    ) -> Result<Evaluation, KinematicsError> {
        let r = Real::<M>::new;
        let placement = self.anchors.place::<M>(pose);
        let mut residual = Vec6::zeros();
        let (mut largest_leg, mut largest_bits) = (0, 0u32);
        let mut matrix = Mat6::zeros();
        for i in 0..LEGS {
            let d = sub::<M>(placement.joints_mm[i], self.lower_mm[i]);
            let half_square = r(0.5) * r(dot::<M>(d, d));
            let f = r(self.half_squares_mm2[i]) - half_square;
            // Not finite (NaN bits are above every finite magnitude), or the joint on its
            // lower point: no direction to move it along.
            if !lt(0.5 * MIN_LENGTH_MM * MIN_LENGTH_MM, half_square.0)
                || abs_bits(f.0) >= 0x7f80_0000
            {
                return Err(KinematicsError::ZeroLength { leg: i as u8 + 1 });
            }
            residual[i] = f.0;
            if abs_bits(f.0) > largest_bits {
                (largest_leg, largest_bits) = (i, abs_bits(f.0));
            }
            if jacobian {
                let moment = cross::<M>(placement.levers_mm[i], d);
                for c in 0..3 {
                    matrix[(i, c)] = d[c];
                    matrix[(i, c + 3)] = moment[c];
                }
            }
        }
        Ok(Evaluation {
            residual,
            largest_leg,
            largest_mm2: f32::from_bits(largest_bits),
            rotation: placement.rotation,
            jacobian: jacobian.then_some(matrix),
        })
    }
}

/// A converged forward kinematics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Converged {
    /// The pose.
    pub pose: Pose,
    /// Iterations made.
    pub iterations: u8,
    /// The largest closure residual `|L_i - |q_i - A_i||` at the last evaluation, before the
    /// last (smaller than tolerance) step, mm.
    pub residual_mm: f32,
}

/// One forward kinematics solve by Newton's method, an iteration per [`Newton::step`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Newton {
    closure: Closure,
    pose: Pose,
    options: Options,
    iterations: u8,
    /// `J`'s factors at an earlier iterate, while they serve.
    factors: Option<Lu6>,
    /// The size of the last step, relative to the tolerances.
    last_step: f32,
    /// The last step, to halve it if it went too far.
    last_delta: [f32; 6],
    /// The pose before the last step.
    previous: Pose,
    /// The largest residual before the last step, mm^2.
    last_residual_mm2: f32,
    /// A step has been taken.
    stepped: bool,
    /// How often a step was halved.
    retreats: u8,
    done: bool,
}

/// Steps shorter than this (mm and rad) keep the Jacobian's factors for the next iteration.
const CHORD_MM: f32 = 1.0;
const CHORD_RAD: f32 = 0.01;
/// Most halvings of steps that went too far, per solve.
const MAX_RETREATS: u8 = 8;
/// Residuals below this (mm of length) are too close to the `f32` noise of the closures (joint
/// coordinates of a few hundred mm round to about 3e-5 mm) to judge a step by.
const NOISE_RESIDUAL_MM: f32 = 1e-4;

impl Newton {
    /// A solve for `closure` starting from `start`.
    pub fn new(closure: Closure, start: Pose, options: Options) -> Newton {
        Newton {
            closure,
            pose: start,
            options,
            iterations: 0,
            factors: None,
            last_step: f32::INFINITY,
            last_delta: [0.0; 6],
            previous: start,
            last_residual_mm2: f32::INFINITY,
            stepped: false,
            retreats: 0,
            done: false,
        }
    }

    /// The current iterate.
    pub fn pose(&self) -> &Pose {
        &self.pose
    }

    /// Iterations made so far.
    pub fn iterations(&self) -> u8 {
        self.iterations
    }

    /// One iteration. `None` while not done; then the outcome, once (later calls return
    /// `None` again).
    pub fn step<M: Math>(&mut self) -> Option<Result<Converged, KinematicsError>> {
        if self.done {
            return None;
        }
        let outcome = self.iterate::<M>();
        if outcome.is_some() {
            self.done = true;
        }
        outcome
    }

    fn iterate<M: Math>(&mut self) -> Option<Result<Converged, KinematicsError>> {
        if let Some(out) = self.out_of_iterations(f32::INFINITY) {
            return Some(out);
        }
        if let Err(e) = crate::ik::check_pose(&self.pose) {
            return Some(Err(e.into()));
        }
        self.iterations += 1;
        let chord = self.factors.is_some();
        let evaluated = self
            .closure
            .evaluate::<M>(&self.pose, !chord)
            .and_then(|e| {
                let lu = match (&e.jacobian, self.factors) {
                    (Some(j), _) => Lu6::factor::<M>(j)?,
                    (None, Some(lu)) => lu,
                    (None, None) => unreachable!("factors kept or a Jacobian computed"),
                };
                Ok((e, lu))
            });
        let (e, lu) = match evaluated {
            // The last step made things clearly worse, or landed where nothing can be computed
            // (a joint on its lower point, a singular pose): it went too far; take half of it.
            Ok((e, _)) if self.stepped && self.worse(e.largest_mm2) => {
                return self.retreat::<M>(self.residual_mm(&e))
            }
            Err(_) if self.stepped => return self.retreat::<M>(f32::INFINITY),
            Ok(v) => v,
            Err(e) => return Some(Err(e)),
        };
        let residual_mm = self.residual_mm(&e);
        let dx = lu.solve::<M>(&e.residual);
        let translation = Vec3::new(dx[0], dx[1], dx[2]);
        let omega = Vec3::new(dx[3], dx[4], dx[5]);
        let angles = match euler_rates_from_rotation::<M>(&e.rotation, omega) {
            Ok(a) => a,
            Err(e) => return Some(Err(e)),
        };
        // Bound the step (stay with the nearest solution).
        let (o, t_max, a_max) = (&self.options, amax(&translation), amax(&angles));
        if !(t_max.is_finite() && a_max.is_finite()) {
            return Some(Err(KinematicsError::Singular { pivot_ratio: 0.0 }));
        }
        let mut bound = 1.0f32;
        if lt(o.max_step_mm, t_max) {
            bound = o.max_step_mm / t_max;
        }
        if lt(o.max_step_rad, a_max * bound) {
            bound = o.max_step_rad / a_max;
        }
        let delta = [
            translation.x * bound,
            translation.y * bound,
            translation.z * bound,
            angles.x * bound,
            angles.y * bound,
            angles.z * bound,
        ];
        let (t_step, a_step) = (t_max * bound, a_max * bound);
        let step = (t_step / o.step_tolerance_mm).max(a_step / o.step_tolerance_rad);
        self.previous = self.pose;
        self.pose = add_delta::<M>(&self.pose, &delta);
        self.last_delta = delta;
        self.last_residual_mm2 = e.largest_mm2;
        self.stepped = true;
        // Keep the factors for the next iterate (the chord method) after a short step: over
        // CHORD_MM and CHORD_RAD the Jacobian of a hand-sized platform changes by about 1%
        // away from singularities, so a chord step gains about two digits. Keep them again
        // only if it did (the step shrank at least tenfold); otherwise linearise afresh.
        let short = lt(t_step, CHORD_MM) && lt(a_step, CHORD_RAD);
        let contracting = !chord || lt(step, 0.1 * self.last_step);
        self.factors = (short && contracting).then_some(lu);
        self.last_step = step;
        if !lt(1.0, step) || !lt(self.closure.noise_mm2, e.largest_mm2) {
            return Some(Ok(Converged {
                pose: self.pose,
                iterations: self.iterations,
                residual_mm,
            }));
        }
        self.out_of_iterations(residual_mm)
    }

    /// The last step made the residual clearly worse (above the noise).
    fn worse(&self, largest_mm2: f32) -> bool {
        lt(2.0 * self.last_residual_mm2, largest_mm2) && lt(self.closure.floor_mm2, largest_mm2)
    }

    /// The largest residual of an evaluation as a length error, mm.
    fn residual_mm(&self, e: &Evaluation) -> f32 {
        e.largest_mm2 / self.closure.lengths_mm[e.largest_leg]
    }

    /// Goes back and takes half of the last step, with fresh factors.
    fn retreat<M: Math>(&mut self, residual: f32) -> Option<Result<Converged, KinematicsError>> {
        if self.retreats >= MAX_RETREATS {
            return Some(Err(KinematicsError::NotConverged {
                iterations: self.iterations,
                residual,
            }));
        }
        self.retreats += 1;
        self.factors = None;
        self.last_delta = self.last_delta.map(|d| 0.5 * d);
        self.pose = add_delta::<M>(&self.previous, &self.last_delta);
        self.out_of_iterations(residual)
    }

    /// `NotConverged` if no iteration is left, with the residual last seen.
    fn out_of_iterations(&self, residual: f32) -> Option<Result<Converged, KinematicsError>> {
        (self.iterations >= self.options.max_iterations).then_some(Err(
            KinematicsError::NotConverged {
                iterations: self.iterations,
                residual,
            },
        ))
    }
}

/// The largest magnitude of a vector's components (in integer instructions; NaN is larger
/// than any number).
fn amax(v: &Vec3) -> f32 {
    f32::from_bits(abs_bits(v.x).max(abs_bits(v.y)).max(abs_bits(v.z)))
}

/// `pose + delta` with `M`'s arithmetic, angles wrapped into `(-pi, pi]`.
fn add_delta<M: Math>(pose: &Pose, delta: &[f32; 6]) -> Pose {
    let r = Real::<M>::new;
    let mut v = pose.to_array();
    for k in 0..6 {
        v[k] = (r(v[k]) + r(delta[k])).0;
        if k >= 3 {
            if lt(PI, v[k]) {
                v[k] = (r(v[k]) - r(2.0 * PI)).0;
            } else if crate::math::le(v[k], -PI) {
                v[k] = (r(v[k]) + r(2.0 * PI)).0;
            }
        }
    }
    Pose::from_array(v)
}

/// Runs a [`Newton`] solve to the end: the pose nearest `start` that closes `closure`.
pub fn solve<M: Math>(
    closure: &Closure,
    start: &Pose,
    options: Options,
) -> Result<Converged, KinematicsError> {
    let mut newton = Newton::new(*closure, *start, options);
    loop {
        if let Some(outcome) = newton.step::<M>() {
            return outcome;
        }
    }
}

/// The pose nearest `start` at which the struts have the given lengths (mm).
pub fn struts<M: Math>(
    struts: &Struts,
    lengths_mm: &[f32; LEGS],
    start: &Pose,
    options: Options,
) -> Result<Converged, KinematicsError> {
    solve::<M>(&Closure::struts(struts, lengths_mm)?, start, options)
}

/// The pose nearest `start` at which the servo arms have the given angles (rad), checked with
/// the IK ([`check_arms`]).
pub fn arms<M: Math>(
    solver: &Solver,
    arm_rad: &[f32; LEGS],
    start: &Pose,
    options: Options,
) -> Result<Converged, KinematicsError> {
    let found = solve::<M>(&Closure::arms::<M>(solver, arm_rad)?, start, options)?;
    check_arms::<M>(solver, &found.pose, arm_rad)?;
    Ok(found)
}

/// Largest difference between the IK's arm angle and the one asked for at a converged pose
/// for [`check_arms`], rad (0.06 degree; a converged pose is within 1e-5 rad).
pub const ARM_CHECK_RAD: f32 = 1e-3;

/// Checks a pose found for servo arm angles with the IK (one IK): the rods close there with
/// the arms at `arm_rad`, but the IK might put an arm on eq. 9's other root (the elbow folded
/// through the rod, [`KinematicsError::ElbowFlipped`]) or find a leg out of reach. Call it on
/// what [`Newton`] converges to for [`Closure::arms`].
pub fn check_arms<M: Math>(
    solver: &Solver,
    pose: &Pose,
    arm_rad: &[f32; LEGS],
) -> Result<(), KinematicsError> {
    let alpha = solver.arm_angles::<M>(pose)?;
    for i in 0..LEGS {
        if !lt((alpha[i] - arm_rad[i]).abs(), ARM_CHECK_RAD) {
            return Err(KinematicsError::ElbowFlipped { leg: i as u8 + 1 });
        }
    }
    Ok(())
}

/// The Simscape documentation's approximate forward kinematics about `around`: with the joint
/// values and `J` there, `dX = J^-1 (target - joints)`; the pose moves the rotation centre by
/// `dX[0..3]` and turns the platform by the angle `|dX[3..6]|` about the axis `dX[3..6]`.
pub fn approximate<M: Math, A: Actuators>(
    actuators: &A,
    around: &Pose,
    target: &[f32; LEGS],
) -> Result<Pose, KinematicsError> {
    if let Some(leg) = target.iter().position(|v| !v.is_finite()) {
        return Err(KinematicsError::NonFinite {
            input: Input::Joint { leg: leg as u8 + 1 },
        });
    }
    let linear = actuators.linearise::<M>(around)?;
    let lu = linear.jacobian.factor::<M>()?;
    let change = Vec6::from_fn(|i, _| target[i] - linear.joint_values[i]);
    let dx = lu.solve::<M>(&change);
    let turn = axis_angle_rotation::<M>(Vec3::new(dx[3], dx[4], dx[5]));
    let (roll_rad, pitch_rad, yaw_rad) = euler_angles::<M>(&(turn * linear.placement.rotation));
    Ok(Pose {
        x_mm: around.x_mm + dx[0],
        y_mm: around.y_mm + dx[1],
        z_mm: around.z_mm + dx[2],
        roll_rad,
        pitch_rad,
        yaw_rad,
    })
}

/// The rotation by the angle `|v|` about the axis `v` (Rodrigues' formula, as the Simscape
/// documentation writes it out); the identity for `v = 0`.
pub fn axis_angle_rotation<M: Math>(v: Vec3) -> Mat3 {
    let theta = M::sqrt(v.dot(&v));
    if !lt(0.0, theta) {
        return Mat3::identity();
    }
    let s = v / theta;
    let (sin, cos) = M::sin_cos(theta);
    let k = 1.0 - cos;
    Mat3::new(
        s.x * s.x * k + cos,
        s.x * s.y * k - s.z * sin,
        s.x * s.z * k + s.y * sin,
        s.y * s.x * k + s.z * sin,
        s.y * s.y * k + cos,
        s.y * s.z * k - s.x * sin,
        s.z * s.x * k - s.y * sin,
        s.z * s.y * k + s.x * sin,
        s.z * s.z * k + cos,
    )
}

/// The angles `(roll, pitch, yaw)` of a rotation `R = Rz(yaw) Ry(pitch) Rx(roll)` (eq. 1),
/// rad, pitch within +-90 degrees: `R_20 = -sin(pitch)`, `R_21 / R_22 = tan(roll)`,
/// `R_10 / R_00 = tan(yaw)`.
pub fn euler_angles<M: Math>(r: &Mat3) -> (f32, f32, f32) {
    let cos_pitch = M::sqrt(r[(0, 0)] * r[(0, 0)] + r[(1, 0)] * r[(1, 0)]);
    (
        M::atan2(r[(2, 1)], r[(2, 2)]),
        M::atan2(-r[(2, 0)], cos_pitch),
        M::atan2(r[(1, 0)], r[(0, 0)]),
    )
}

/// The arm angles six pulse widths command (the inverse of eq. 13, 14), rad: the target of a
/// servo platform's forward kinematics. Refused for a non-finite pulse.
pub fn arm_angles_for_pulses(
    solver: &Solver,
    servos: &ServoSet,
    pulse_us: &[f32; LEGS],
) -> Result<[f32; LEGS], KinematicsError> {
    let mut out = [0.0; LEGS];
    for (i, o) in out.iter_mut().enumerate() {
        *o = servos.0[i].alpha_rad(pulse_us[i], solver.alpha0_rad(i));
        if !o.is_finite() {
            return Err(KinematicsError::NonFinite {
                input: Input::Joint { leg: i as u8 + 1 },
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Geometry;
    use crate::math::Libm;

    #[test]
    fn euler_angles_invert_eq_1() {
        let pose = Pose::from_degrees(0.0, 0.0, 0.0, 12.0, -33.0, 150.0);
        let (r, p, y) = euler_angles::<Libm>(&pose.rotation::<Libm>());
        assert!((r - pose.roll_rad).abs() < 1e-6);
        assert!((p - pose.pitch_rad).abs() < 1e-6);
        assert!((y - pose.yaw_rad).abs() < 1e-6);
    }

    #[test]
    fn servo_round_trip_from_home() {
        let solver = Solver::new(Geometry::default()).unwrap();
        let pose = Pose::from_degrees(5.0, -4.0, 3.0, 4.0, -3.0, 8.0);
        let target = solver.arm_angles::<Libm>(&pose).unwrap();
        let found = arms::<Libm>(&solver, &target, &Pose::HOME, Options::default()).unwrap();
        let (a, b) = (found.pose.to_array(), pose.to_array());
        for k in 0..6 {
            assert!((a[k] - b[k]).abs() < 1e-3, "{found:?}");
        }
    }

    #[test]
    fn strut_round_trip_and_approximation() {
        let s = Struts::from_general(&crate::configuration::GeneralConfiguration::SIMSCAPE, 90.0)
            .unwrap();
        let pose = Pose::from_degrees(3.0, 2.0, -1.0, 1.0, 2.0, -3.0);
        let target = s.joint_values::<Libm>(&pose).unwrap();
        let near = approximate::<Libm, _>(&s, &Pose::HOME, &target).unwrap();
        let found = struts::<Libm>(&s, &target, &near, Options::default()).unwrap();
        let (a, b) = (found.pose.to_array(), pose.to_array());
        for k in 0..6 {
            assert!((a[k] - b[k]).abs() < 1e-4, "{found:?}");
        }
        let (a, b) = (near.to_array(), pose.to_array());
        for k in 0..6 {
            assert!((a[k] - b[k]).abs() < 0.2, "{near:?}");
        }
    }
}
