//! The Jacobian `J`: how fast each joint moves per unit of platform twist, `joint rates =
//! J twist`; and the Euler-angle rates of eq. 1 of "The Mathematics of the Stewart Platform".
//!
//! The twist `(v, omega)` is taken at the rotation centre `C` (the point the platform turns
//! about, see [`crate::configuration`]), in base-frame axes: `v` is the velocity of `C`
//! (mm/s), which is the rate of the pose's `(x, y, z)`; `omega` the platform's angular
//! velocity (rad/s). Platform joint `i` then moves at `q_i' = v + omega x r_i`, with the lever
//! `r_i = q_i - C = R (p_i - c)`. Column order: `v_x, v_y, v_z, omega_x, omega_y, omega_z`.
//!
//! - Struts (the Stewart platform Simscape model documentation, `computeJacobian`): the
//!   length rate is `l_i' = s_i . q_i'`, so row `i` is `[s_i^T, (r_i x s_i)^T]` (mm/mm,
//!   mm/rad). The documentation measures its `b_i` from its frame {A}; at home {A} is where
//!   {B} (our `C`) is, so the two agree there; away from home, levers from the fixed {A} would
//!   refer the twist to {A}'s origin instead of the moving `C`.
//! - Servo arms: differentiating the rod closure behind eq. 7-9 of "The Mathematics of the
//!   Stewart Platform", `|q_i - A_i(alpha_i)|^2 = s^2`, gives `d_i . (q_i' - t_i alpha_i') = 0`
//!   with the rod `d_i = q_i - A_i` and `t_i = dA_i/d alpha` (see [`crate::legs::ArmState`]):
//!   `alpha_i' = d_i . q_i' / (d_i . t_i)`, row `i` is `[d_i^T, (r_i x d_i)^T] / (d_i . t_i)`
//!   (rad/mm, rad/rad). It is unbounded where `d_i . t_i = 0`, the arm at dead centre (the
//!   leg's workspace boundary, where eq. 9's discriminant vanishes): refused
//!   ([`KinematicsError::DeadCentre`]).
//!
//! [`Actuators`] is what the kinematics beyond the IK (forward kinematics, rates, statics,
//! dynamics) need of either kind of leg: joint values and this Jacobian at a pose.
//!
//! Near-singular poses, where nothing divides by zero:
//! - where the platform gains a freedom the legs cannot resist (a parallel singularity, e.g.
//!   struts lying flat), [`Jacobian::condition_number`] grows without bound and
//!   [`Jacobian::factor`] refuses them ([`KinematicsError::Singular`]);
//! - where a servo arm comes to dead centre (the leg's workspace boundary), its row grows
//!   without bound (refused at [`DEAD_CENTRE_TOLERANCE`]); that scales the row and need not
//!   show in the condition number: [`crate::legs::ArmState::transmission`] measures it.

use crate::configuration::{Anchors, Placement};
use crate::error::KinematicsError;
use crate::geometry::Geometry;
use crate::ik::Solver;
use crate::legs::{ArmState, StrutState, Struts};
use crate::linalg::{condition_number, Lu6, Mat6, Vec6};
use crate::math::{cross, dot, lt, Math, Real};
use crate::pose::Pose;
use crate::types::{Mat3, Vec3, LEGS};

/// `|d . t|` below this fraction of `|d| |t| = s a` is dead centre: the arm's rate would be
/// more than 1e5 times its rate at right angles, and `d . t` is within a few hundred `f32`
/// roundings of zero.
pub const DEAD_CENTRE_TOLERANCE: f32 = 1e-5;

/// `J` at one pose: row `i` is leg `i`'s joint rate per unit twist (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jacobian {
    /// The matrix, rows legs 1..=6, columns `v_x, v_y, v_z` (per mm) then `omega_x, omega_y,
    /// omega_z` (per rad).
    pub matrix: Mat6,
    /// The longest lever `|r_i|` at this pose (at least 1 mm), mm: the length that makes the
    /// angular columns comparable to the linear ones ([`Jacobian::condition_number`]).
    pub lever_scale_mm: f32,
}

impl Jacobian {
    /// The struts' Jacobian, rows `[s_i^T, (r_i x s_i)^T]` (Simscape `computeJacobian`).
    pub fn of_struts<M: Math>(state: &StrutState) -> Jacobian {
        let mut matrix = Mat6::zeros();
        for i in 0..LEGS {
            let s = state.units[i];
            let moment = cross::<M>(state.placement.levers_mm[i], s);
            set_row(&mut matrix, i, s, moment);
        }
        Jacobian {
            matrix,
            lever_scale_mm: lever_scale::<M>(&state.placement.levers_mm),
        }
    }

    /// The servo arms' Jacobian, rows `[d_i^T, (r_i x d_i)^T] / (d_i . t_i)`; refused at dead
    /// centre.
    pub fn of_arms<M: Math>(
        state: &ArmState,
        geometry: &Geometry,
    ) -> Result<Jacobian, KinematicsError> {
        let r = Real::<M>::new;
        let threshold = DEAD_CENTRE_TOLERANCE * geometry.rod_mm() * geometry.arm_mm();
        let mut matrix = Mat6::zeros();
        for i in 0..LEGS {
            let d = state.rods_mm[i];
            let along = dot::<M>(d, state.tip_rates_mm[i]);
            if !lt(threshold, along.abs()) {
                return Err(KinematicsError::DeadCentre { leg: i as u8 + 1 });
            }
            let k = r(1.0 / along);
            let moment = cross::<M>(state.placement.levers_mm[i], d);
            let scaled = |v: Vec3| Vec3::new((r(v.x) * k).0, (r(v.y) * k).0, (r(v.z) * k).0);
            set_row(&mut matrix, i, scaled(d), scaled(moment));
        }
        Ok(Jacobian {
            matrix,
            lever_scale_mm: lever_scale::<M>(&state.placement.levers_mm),
        })
    }

    /// The Jacobian of `actuators` at `pose`.
    pub fn at<M: Math, A: Actuators>(
        actuators: &A,
        pose: &Pose,
    ) -> Result<Jacobian, KinematicsError> {
        Ok(actuators.linearise::<M>(pose)?.jacobian)
    }

    /// Joint rates for a twist: `J twist` (mm/s or rad/s per leg).
    pub fn joint_rates<M: Math>(&self, twist: &Vec6) -> Vec6 {
        let r = Real::<M>::new;
        Vec6::from_fn(|i, _| {
            (0..6)
                .map(|k| r(self.matrix[(i, k)]) * r(twist[k]))
                .fold(r(0.0), |a, b| a + b)
                .0
        })
    }

    /// `J`'s LU factors, to solve for a twist from joint rates (`J x = rates`) or for joint
    /// forces from a wrench (`J^T f = w`). Refused near a singular pose.
    pub fn factor<M: Math>(&self) -> Result<Lu6, KinematicsError> {
        Lu6::factor::<M>(&self.matrix)
    }

    /// The condition number (1-norm) of `J` with its angular columns divided by
    /// [`Jacobian::lever_scale_mm`], so that it does not depend on units: 1 is ideal, it grows
    /// without bound towards a singular pose and is infinite where `J` cannot be factored.
    pub fn condition_number<M: Math>(&self) -> f32 {
        let mut scaled = self.matrix;
        for k in 3..6 {
            let column = scaled.column(k) * (1.0 / self.lever_scale_mm);
            scaled.set_column(k, &column);
        }
        condition_number::<M>(&scaled)
    }

    /// `J E`, the Jacobian per unit of pose rate `(x', y', z', roll', pitch', yaw')`: the
    /// angular columns multiplied by [`euler_rate_matrix`].
    pub fn per_pose_rate<M: Math>(&self, pose: &Pose) -> Mat6 {
        let e = euler_rate_matrix::<M>(pose);
        let mut out = self.matrix;
        let angular = self.matrix.fixed_columns::<3>(3) * e;
        out.fixed_columns_mut::<3>(3).copy_from(&angular);
        out
    }
}

/// What the kinematics beyond the IK need of a platform's six actuators: their joint values at
/// a pose (strut lengths in mm, or servo arm angles in rad) and the Jacobian there.
///
/// Implemented here for [`Struts`] (linear actuators) and [`Solver`] (RC servos). The forward
/// kinematics, rates, statics and dynamics work with either.
pub trait Actuators {
    /// The anchors, home height and rotation centre.
    fn anchors(&self) -> Anchors;

    /// The joint values at `pose` (strut lengths, mm, or arm angles, rad), whatever the
    /// actuators' limits (stroke, servo pulses).
    fn joint_values<M: Math>(&self, pose: &Pose) -> Result<[f32; LEGS], KinematicsError>;

    /// The joint values and the Jacobian at `pose` (computed together, sharing the work).
    fn linearise<M: Math>(&self, pose: &Pose) -> Result<Linearisation, KinematicsError>;
}

/// The joint values at a pose and the Jacobian there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Linearisation {
    /// Strut lengths (mm) or arm angles (rad).
    pub joint_values: [f32; LEGS],
    /// `d joint / d twist` (see [`Jacobian`]).
    pub jacobian: Jacobian,
    /// Where the platform is.
    pub placement: Placement,
}

impl Actuators for Struts {
    fn anchors(&self) -> Anchors {
        Struts::anchors(self)
    }

    fn joint_values<M: Math>(&self, pose: &Pose) -> Result<[f32; LEGS], KinematicsError> {
        Ok(self.state::<M>(pose)?.lengths_mm)
    }

    fn linearise<M: Math>(&self, pose: &Pose) -> Result<Linearisation, KinematicsError> {
        let state = self.state::<M>(pose)?;
        Ok(Linearisation {
            joint_values: state.lengths_mm,
            jacobian: Jacobian::of_struts::<M>(&state),
            placement: state.placement,
        })
    }
}

impl Actuators for Solver {
    fn anchors(&self) -> Anchors {
        Solver::anchors(self)
    }

    fn joint_values<M: Math>(&self, pose: &Pose) -> Result<[f32; LEGS], KinematicsError> {
        Ok(self.arm_angles::<M>(pose)?)
    }

    fn linearise<M: Math>(&self, pose: &Pose) -> Result<Linearisation, KinematicsError> {
        let state = ArmState::new::<M>(self, pose)?;
        Ok(Linearisation {
            joint_values: state.arm_rad,
            jacobian: Jacobian::of_arms::<M>(&state, self.geometry())?,
            placement: state.placement,
        })
    }
}

fn set_row(matrix: &mut Mat6, i: usize, linear: Vec3, angular: Vec3) {
    for k in 0..3 {
        matrix[(i, k)] = linear[k];
        matrix[(i, k + 3)] = angular[k];
    }
}

/// The longest lever, at least 1 mm (one square root, the largest found in integer
/// instructions).
fn lever_scale<M: Math>(levers: &[Vec3; LEGS]) -> f32 {
    let longest_sq = levers
        .iter()
        .map(|r| dot::<M>(*r, *r).to_bits())
        .max()
        .unwrap_or(0);
    M::sqrt(f32::from_bits(longest_sq)).max(1.0)
}

/// `E` with `omega = E (roll', pitch', yaw')` for `R = Rz(yaw) Ry(pitch) Rx(roll)` (eq. 1):
/// yaw turns about base z, pitch about `Rz e_y`, roll about `Rz Ry e_x`, so the columns are
/// `(cos(yaw) cos(pitch), sin(yaw) cos(pitch), -sin(pitch))`, `(-sin(yaw), cos(yaw), 0)`,
/// `(0, 0, 1)`.
pub fn euler_rate_matrix<M: Math>(pose: &Pose) -> Mat3 {
    let (s_p, c_p) = M::sin_cos(pose.pitch_rad);
    let (s_y, c_y) = M::sin_cos(pose.yaw_rad);
    Mat3::new(c_y * c_p, -s_y, 0.0, s_y * c_p, c_y, 0.0, -s_p, 0.0, 1.0)
}

/// Smallest `|cos(pitch)|` for which Euler rates are computed (about 0.06 degrees from +-90).
const MIN_COS_PITCH: f32 = 1e-3;

/// The Euler-angle rates `(roll', pitch', yaw')` for an angular velocity `omega` (base axes,
/// rad/s), `E^-1 omega`: `roll' = (cos(yaw) w_x + sin(yaw) w_y) / cos(pitch)`,
/// `pitch' = -sin(yaw) w_x + cos(yaw) w_y`, `yaw' = w_z + sin(pitch) roll'`. Refused at
/// gimbal lock (pitch within 0.06 degrees of +-90).
pub fn euler_rates<M: Math>(pose: &Pose, omega: Vec3) -> Result<Vec3, KinematicsError> {
    let r = Real::<M>::new;
    let (s_p, c_p) = M::sin_cos(pose.pitch_rad);
    let (s_y, c_y) = M::sin_cos(pose.yaw_rad);
    if !lt(MIN_COS_PITCH, c_p.abs()) {
        return Err(KinematicsError::GimbalLock {
            pitch_rad: pose.pitch_rad,
        });
    }
    let (w_x, w_y, w_z) = (r(omega.x), r(omega.y), r(omega.z));
    let roll = (r(c_y) * w_x + r(s_y) * w_y).0 / c_p;
    let pitch = r(c_y) * w_y - r(s_y) * w_x;
    let yaw = w_z + r(s_p) * r(roll);
    Ok(Vec3::new(roll, pitch.0, yaw.0))
}

/// [`euler_rates`] from the rotation matrix of eq. 1 instead of the angles (a square root
/// instead of two sines and cosines): with `cos(pitch)^2 = R_00^2 + R_10^2`,
/// `roll' = (R_00 w_x + R_10 w_y) / cos(pitch)^2`, `pitch' = (R_00 w_y - R_10 w_x) /
/// cos(pitch)`, `yaw' = w_z - R_20 roll'` (`R_00 = cos(yaw) cos(pitch)`,
/// `R_10 = sin(yaw) cos(pitch)`, `R_20 = -sin(pitch)`).
pub fn euler_rates_from_rotation<M: Math>(
    rotation: &Mat3,
    omega: Vec3,
) -> Result<Vec3, KinematicsError> {
    let r = Real::<M>::new;
    let (r00, r10, r20) = (
        r(rotation[(0, 0)]),
        r(rotation[(1, 0)]),
        r(rotation[(2, 0)]),
    );
    let cos_sq = (r00 * r00 + r10 * r10).0;
    if !lt(MIN_COS_PITCH * MIN_COS_PITCH, cos_sq) {
        return Err(KinematicsError::GimbalLock {
            pitch_rad: M::atan2(-r20.0, M::sqrt(cos_sq)),
        });
    }
    let (w_x, w_y, w_z) = (r(omega.x), r(omega.y), r(omega.z));
    let roll = (r00 * w_x + r10 * w_y).0 / cos_sq;
    let pitch = (r00 * w_y - r10 * w_x).0 / M::sqrt(cos_sq);
    let yaw = w_z - r20 * r(roll);
    Ok(Vec3::new(roll, pitch, yaw.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Geometry;
    use crate::math::Libm;

    #[test]
    fn euler_rates_invert_the_rate_matrix() {
        let pose = Pose::from_degrees(0.0, 0.0, 0.0, 20.0, -35.0, 70.0);
        let e = euler_rate_matrix::<Libm>(&pose);
        let rates = Vec3::new(0.3, -0.2, 0.7);
        let back = euler_rates::<Libm>(&pose, e * rates).unwrap();
        assert!((back - rates).amax() < 1e-6);
        let rotation = pose.rotation::<Libm>();
        let back = euler_rates_from_rotation::<Libm>(&rotation, e * rates).unwrap();
        assert!((back - rates).amax() < 1e-6);
        let locked = Pose::from_degrees(0.0, 0.0, 0.0, 0.0, 90.0, 0.0);
        assert!(matches!(
            euler_rates::<Libm>(&locked, rates),
            Err(KinematicsError::GimbalLock { .. })
        ));
    }

    #[test]
    fn default_build_is_well_conditioned_at_home() {
        let solver = Solver::new(Geometry::default()).unwrap();
        let j = Jacobian::at::<Libm, _>(&solver, &Pose::HOME).unwrap();
        let k = j.condition_number::<Libm>();
        assert!(k > 1.0 && k < 100.0, "{k}");
    }
}
