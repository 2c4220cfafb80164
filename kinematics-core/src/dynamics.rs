//! Link kinematics and actuation along a trajectory: the speed and acceleration of each leg's
//! platform joint, of the link itself and of the servo arms, from the platform's twist and
//! acceleration; and the joint forces that carry a payload along it, inertia included.
//!
//! After the ROBOOP `LinkStewart` class reference, with the twist at the rotation centre `C`
//! (see [`crate::jacobian`]) and the lever `r_i = q_i - C`:
//! - `Find_da`: joint velocity `q_i' = v + omega x r_i`;
//! - `Find_dda`: joint acceleration `q_i'' = a + alpha x r_i + omega x (omega x r_i)`;
//! - `Find_Lenght`, `Find_UnitV`: strut length `l_i` and unit vector `n_i`;
//! - `Find_AngularKin`: the link's angular velocity and acceleration. ROBOOP splits them along
//!   the two axes of a universal joint at the base; here the link turns in spherical joints
//!   and does not spin about its own axis, so `omega_l = n x q' / l` and, from
//!   `q'' = l'' n + 2 l' omega_l x n + l (alpha_l x n + omega_l x (omega_l x n))`,
//!   `alpha_l = n x (q'' - 2 l' omega_l x n) / l`; along the link `l' = n . q'` and
//!   `l'' = n . q'' + l |omega_l|^2`. (A slender link's spin carries no axial force.)
//! - Servo arms (differentiating the rod closure behind eq. 7-9 of "The Mathematics of the
//!   Stewart Platform" twice): `alpha' = d . q' / (d . t)` and
//!   `alpha'' = (d . q'' + alpha'^2 d . (A - b) + |q' - t alpha'|^2) / (d . t)`, with the
//!   rod `d = q - A`, `t = dA/d alpha` and `d^2 A / d alpha^2 = -(A - b)`.
//! - `ActuationForce`: the force that powers each actuator. Here the payload is a rigid body
//!   on the platform (mass, centre of mass, inertia: [`Payload`]) and the legs are massless:
//!   the wrench the legs must apply is Newton-Euler's, `F = m (a_G - g)`,
//!   `M = rho x F + I alpha + omega x (I omega)` about `C` (`rho` from `C` to the centre of
//!   mass `G`, `I` the inertia about `G` in base axes), and the joint forces are
//!   `J^-T (F, M)` as in [`crate::statics`]. ROBOOP's terms for the links' own masses are left
//!   out: a hobby platform's rods weigh grams.
//!
//! Units: mm, s, rad, kg; forces N, moments and servo torques N mm.

use crate::configuration::Placement;
use crate::error::{Input, KinematicsError};
use crate::ik::Solver;
use crate::jacobian::{Actuators, DEAD_CENTRE_TOLERANCE};
use crate::legs::{ArmState, Struts};
use crate::math::{lt, mul_mat_vec, Math};
use crate::pose::Pose;
use crate::rates::Twist;
use crate::statics::{joint_forces_for, Payload, Wrench, GRAVITY_MM_S2};
use crate::types::{Vec3, LEGS};

/// The platform's acceleration: of the rotation centre, and angular, base axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Acceleration {
    /// Acceleration of the rotation centre, mm/s^2.
    pub linear_mm_s2: Vec3,
    /// Angular acceleration, rad/s^2.
    pub angular_rad_s2: Vec3,
}

impl Acceleration {
    /// No acceleration.
    pub const ZERO: Acceleration = Acceleration {
        linear_mm_s2: Vec3::new(0.0, 0.0, 0.0),
        angular_rad_s2: Vec3::new(0.0, 0.0, 0.0),
    };

    fn check(&self) -> Result<(), KinematicsError> {
        let finite = self.linear_mm_s2.iter().all(|v| v.is_finite())
            && self.angular_rad_s2.iter().all(|v| v.is_finite());
        if finite {
            Ok(())
        } else {
            Err(KinematicsError::NonFinite {
                input: Input::Acceleration,
            })
        }
    }
}

fn check_twist(twist: &Twist) -> Result<(), KinematicsError> {
    if twist.is_finite() {
        Ok(())
    } else {
        Err(KinematicsError::NonFinite {
            input: Input::Twist,
        })
    }
}

/// How one platform joint moves (ROBOOP `Find_da`, `Find_dda`), base frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointMotion {
    /// Velocity, mm/s.
    pub velocity_mm_s: Vec3,
    /// Acceleration, mm/s^2.
    pub acceleration_mm_s2: Vec3,
}

/// The platform joints' velocities and accelerations.
pub fn joint_motions(
    placement: &Placement,
    twist: &Twist,
    acceleration: &Acceleration,
) -> [JointMotion; LEGS] {
    let (v, w) = (twist.linear_mm_s, twist.angular_rad_s);
    let (a, alpha) = (acceleration.linear_mm_s2, acceleration.angular_rad_s2);
    core::array::from_fn(|i| {
        let r = placement.levers_mm[i];
        let w_r = w.cross(&r);
        JointMotion {
            velocity_mm_s: v + w_r,
            acceleration_mm_s2: a + alpha.cross(&r) + w.cross(&w_r),
        }
    })
}

/// How one strut moves (ROBOOP `LinkStewart`; see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinkMotion {
    /// The platform joint's motion.
    pub joint: JointMotion,
    /// Length `l`, mm.
    pub length_mm: f32,
    /// Unit vector `n` from the base joint to the platform joint.
    pub unit: Vec3,
    /// Extension rate `l'`, mm/s.
    pub length_rate_mm_s: f32,
    /// Extension acceleration `l''`, mm/s^2.
    pub length_acceleration_mm_s2: f32,
    /// The link's angular velocity (square to it), rad/s.
    pub angular_velocity_rad_s: Vec3,
    /// The link's angular acceleration (square to it), rad/s^2.
    pub angular_acceleration_rad_s2: Vec3,
}

/// The struts' motion at `pose` for a twist and an acceleration.
pub fn strut_motions<M: Math>(
    struts: &Struts,
    pose: &Pose,
    twist: &Twist,
    acceleration: &Acceleration,
) -> Result<[LinkMotion; LEGS], KinematicsError> {
    check_twist(twist)?;
    acceleration.check()?;
    let state = struts.state::<M>(pose)?;
    let joints = joint_motions(&state.placement, twist, acceleration);
    Ok(core::array::from_fn(|i| {
        let (l, n, joint) = (state.lengths_mm[i], state.units[i], joints[i]);
        let length_rate = n.dot(&joint.velocity_mm_s);
        let omega = n.cross(&joint.velocity_mm_s) / l;
        let n_rate = omega.cross(&n);
        let alpha = n.cross(&(joint.acceleration_mm_s2 - n_rate * (2.0 * length_rate))) / l;
        LinkMotion {
            joint,
            length_mm: l,
            unit: n,
            length_rate_mm_s: length_rate,
            length_acceleration_mm_s2: n.dot(&joint.acceleration_mm_s2) + l * omega.norm_squared(),
            angular_velocity_rad_s: omega,
            angular_acceleration_rad_s2: alpha,
        }
    }))
}

/// How one servo arm moves.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ArmMotion {
    /// The platform joint's motion.
    pub joint: JointMotion,
    /// Arm angle `alpha`, rad.
    pub arm_rad: f32,
    /// Arm rate `alpha'`, rad/s.
    pub rate_rad_s: f32,
    /// Arm acceleration `alpha''`, rad/s^2.
    pub acceleration_rad_s2: f32,
}

/// The servo arms' motion at `pose` for a twist and an acceleration (see the module docs).
/// Refused where an arm is at dead centre.
pub fn arm_motions<M: Math>(
    solver: &Solver,
    pose: &Pose,
    twist: &Twist,
    acceleration: &Acceleration,
) -> Result<[ArmMotion; LEGS], KinematicsError> {
    check_twist(twist)?;
    acceleration.check()?;
    let state = ArmState::new::<M>(solver, pose)?;
    let g = solver.geometry();
    let threshold = DEAD_CENTRE_TOLERANCE * g.rod_mm() * g.arm_mm();
    let joints = joint_motions(&state.placement, twist, acceleration);
    let anchors = solver.anchors();
    let mut out = [ArmMotion::default(); LEGS];
    for (i, motion) in out.iter_mut().enumerate() {
        let (d, t, joint) = (state.rods_mm[i], state.tip_rates_mm[i], joints[i]);
        let along = d.dot(&t);
        if !lt(threshold, along.abs()) {
            return Err(KinematicsError::DeadCentre { leg: i as u8 + 1 });
        }
        let rate = d.dot(&joint.velocity_mm_s) / along;
        let arm = state.tips_mm[i] - anchors.base_mm[i];
        let rod_rate = joint.velocity_mm_s - t * rate;
        let acceleration = (d.dot(&joint.acceleration_mm_s2)
            + rate * rate * d.dot(&arm)
            + rod_rate.norm_squared())
            / along;
        *motion = ArmMotion {
            joint,
            arm_rad: state.arm_rad[i],
            rate_rad_s: rate,
            acceleration_rad_s2: acceleration,
        };
    }
    Ok(out)
}

/// The wrench the legs must apply to the platform to carry `payload` with this twist and
/// acceleration against gravity (Newton-Euler about the rotation centre; see the module docs).
/// `centre_mm` is the rotation centre in the platform frame.
pub fn required_wrench<M: Math>(
    placement: &Placement,
    centre_mm: Vec3,
    payload: &Payload,
    twist: &Twist,
    acceleration: &Acceleration,
) -> Wrench {
    let (w, alpha) = (twist.angular_rad_s, acceleration.angular_rad_s2);
    let rho = mul_mat_vec::<M>(&placement.rotation, payload.centre_of_mass_mm - centre_mm);
    let a_g = acceleration.linear_mm_s2 + alpha.cross(&rho) + w.cross(&w.cross(&rho));
    let gravity = Vec3::new(0.0, 0.0, -GRAVITY_MM_S2);
    // kg mm/s^2 is 1e-3 N; kg mm^2/s^2 is 1e-3 N mm.
    let force_n = (a_g - gravity) * (payload.mass_kg * 1e-3);
    let inertia = placement.rotation * payload.inertia_kg_mm2 * placement.rotation.transpose();
    let spin = inertia * alpha + w.cross(&(inertia * w));
    Wrench {
        force_n,
        moment_n_mm: rho.cross(&force_n) + spin * 1e-3,
    }
}

/// The joint forces (N per strut, N mm per servo arm, signs as in [`crate::statics`]) that
/// carry `payload` through `pose` with this twist and acceleration, gravity and inertia
/// included: the actuation the trajectory asks of each actuator at that instant.
pub fn actuation<M: Math, A: Actuators>(
    actuators: &A,
    pose: &Pose,
    payload: &Payload,
    twist: &Twist,
    acceleration: &Acceleration,
) -> Result<[f32; LEGS], KinematicsError> {
    check_twist(twist)?;
    acceleration.check()?;
    payload.check()?;
    let centre_mm = actuators.anchors().rotation_centre_mm;
    let linear = actuators.linearise::<M>(pose)?;
    let wrench = required_wrench::<M>(&linear.placement, centre_mm, payload, twist, acceleration);
    joint_forces_for::<M>(&linear.jacobian, &wrench)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Geometry;
    use crate::math::Libm;
    use crate::statics::holding_loads;

    #[test]
    fn at_rest_the_actuation_is_the_holding_load() {
        let solver = Solver::new(Geometry::default()).unwrap();
        let pose = Pose::from_degrees(4.0, -3.0, 2.0, 3.0, -2.0, 6.0);
        let payload = Payload::point(0.8, Vec3::new(10.0, -5.0, 20.0));
        let held = holding_loads::<Libm, _>(&solver, &pose, &payload).unwrap();
        let carried =
            actuation::<Libm, _>(&solver, &pose, &payload, &Twist::ZERO, &Acceleration::ZERO)
                .unwrap();
        for i in 0..LEGS {
            assert!((held[i] - carried[i]).abs() <= 1e-3 * held[i].abs().max(1.0));
        }
    }
}
