//! Rates: joint rates (strut length rates in mm/s, servo arm rates in rad/s) from a platform
//! twist and back, Euler pose rates and twists, and the speed limits of servos.
//!
//! `joint rates = J twist` with the Jacobian `J` of [`crate::jacobian`] (the Stewart platform
//! Simscape model documentation's `computeJacobian` for struts, the differentiated rod closure
//! of "The Mathematics of the Stewart Platform" for servo arms), and `twist = J^-1 joint
//! rates`. The twist is taken at the rotation centre, in base axes (see [`crate::jacobian`]).
//!
//! A hobby servo's speed is given as the time it takes to turn 60 degrees without load (e.g.
//! 0.10 s / 60 degrees): [`ServoSpeed`]. [`speed_scale`] says how much a motion must be slowed
//! down so that no joint moves faster than it can.

use crate::error::{Input, KinematicsError};
use crate::jacobian::{euler_rate_matrix, euler_rates, Actuators};
use crate::linalg::Vec6;
use crate::math::Math;
use crate::pose::Pose;
use crate::types::{Vec3, LEGS};

/// A platform twist: the velocity of the rotation centre and the angular velocity, base axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Twist {
    /// Velocity of the rotation centre, mm/s.
    pub linear_mm_s: Vec3,
    /// Angular velocity, rad/s.
    pub angular_rad_s: Vec3,
}

impl Twist {
    /// At rest.
    pub const ZERO: Twist = Twist {
        linear_mm_s: Vec3::new(0.0, 0.0, 0.0),
        angular_rad_s: Vec3::new(0.0, 0.0, 0.0),
    };

    /// `(v_x, v_y, v_z, omega_x, omega_y, omega_z)`: the Jacobian's column order.
    pub fn to_vec6(&self) -> Vec6 {
        let (v, w) = (self.linear_mm_s, self.angular_rad_s);
        Vec6::new(v.x, v.y, v.z, w.x, w.y, w.z)
    }

    /// The twist of a 6-vector in the Jacobian's column order.
    pub fn from_vec6(v: &Vec6) -> Twist {
        Twist {
            linear_mm_s: Vec3::new(v[0], v[1], v[2]),
            angular_rad_s: Vec3::new(v[3], v[4], v[5]),
        }
    }

    /// The twist of a platform at `pose` whose pose coordinates change at `pose_rate`
    /// (`x', y', z'` in mm/s, `roll', pitch', yaw'` in rad/s): `v = (x', y', z')`,
    /// `omega = E (roll', pitch', yaw')` ([`euler_rate_matrix`]).
    pub fn from_pose_rate<M: Math>(pose: &Pose, pose_rate: &[f32; 6]) -> Twist {
        let e = euler_rate_matrix::<M>(pose);
        Twist {
            linear_mm_s: Vec3::new(pose_rate[0], pose_rate[1], pose_rate[2]),
            angular_rad_s: e * Vec3::new(pose_rate[3], pose_rate[4], pose_rate[5]),
        }
    }

    /// The pose rate of this twist at `pose` (the inverse of [`Twist::from_pose_rate`]);
    /// refused at gimbal lock.
    pub fn to_pose_rate<M: Math>(&self, pose: &Pose) -> Result<[f32; 6], KinematicsError> {
        let e = euler_rates::<M>(pose, self.angular_rad_s)?;
        let v = self.linear_mm_s;
        Ok([v.x, v.y, v.z, e.x, e.y, e.z])
    }

    /// True if every component is finite.
    pub fn is_finite(&self) -> bool {
        self.to_vec6().iter().all(|v| v.is_finite())
    }
}

/// Joint rates for a twist at `pose`: `J twist` (mm/s per strut, rad/s per servo arm).
pub fn joint_rates<M: Math, A: Actuators>(
    actuators: &A,
    pose: &Pose,
    twist: &Twist,
) -> Result<[f32; LEGS], KinematicsError> {
    if !twist.is_finite() {
        return Err(KinematicsError::NonFinite {
            input: Input::Twist,
        });
    }
    let j = actuators.linearise::<M>(pose)?.jacobian;
    Ok(j.joint_rates::<M>(&twist.to_vec6()).into())
}

/// The twist that moves the joints at `rates` from `pose`: `J^-1 rates`. Refused near a
/// singular pose.
pub fn twist_from_joint_rates<M: Math, A: Actuators>(
    actuators: &A,
    pose: &Pose,
    rates: &[f32; LEGS],
) -> Result<Twist, KinematicsError> {
    if !rates.iter().all(|v| v.is_finite()) {
        return Err(KinematicsError::NonFinite {
            input: Input::JointRates,
        });
    }
    let lu = actuators.linearise::<M>(pose)?.jacobian.factor::<M>()?;
    Ok(Twist::from_vec6(&lu.solve::<M>(&Vec6::from(*rates))))
}

/// A servo's no-load speed, as data sheets give it: seconds per 60 degrees of turn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoSpeed {
    /// Time to turn 60 degrees, s (e.g. 0.10 for a fast standard servo).
    pub seconds_per_60_deg: f32,
}

impl ServoSpeed {
    /// The largest arm rate, rad/s: `(pi / 3) / seconds_per_60_deg`.
    pub fn max_rad_s(&self) -> f32 {
        core::f32::consts::FRAC_PI_3 / self.seconds_per_60_deg
    }
}

/// The largest factor `k` in `(0, 1]` such that every `|k rates_i| <= max_rate` (in the unit
/// of the rates): 1 if the rates are within the limit already, otherwise how much a motion must
/// be slowed. `max_rate` must be positive; a non-finite rate gives 0 (stand still).
pub fn speed_scale(rates: &[f32; LEGS], max_rate: f32) -> f32 {
    let fastest = rates.iter().fold(0.0f32, |m, r| {
        if r.is_finite() {
            m.max(r.abs())
        } else {
            f32::INFINITY
        }
    });
    if fastest <= max_rate {
        1.0
    } else if fastest.is_finite() {
        max_rate / fastest
    } else {
        0.0
    }
}

/// How much a motion through `pose` at `pose_rate` (pose coordinates per second, mm/s and
/// rad/s) must be slowed so that no joint moves faster than `max_rate` (mm/s for struts,
/// rad/s for servo arms, e.g. [`ServoSpeed::max_rad_s`]): see [`speed_scale`].
pub fn pose_rate_scale<M: Math, A: Actuators>(
    actuators: &A,
    pose: &Pose,
    pose_rate: &[f32; 6],
    max_rate: f32,
) -> Result<f32, KinematicsError> {
    let twist = Twist::from_pose_rate::<M>(pose, pose_rate);
    Ok(speed_scale(
        &joint_rates::<M, A>(actuators, pose, &twist)?,
        max_rate,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn servo_speed_and_scale() {
        let speed = ServoSpeed {
            seconds_per_60_deg: 0.10,
        };
        assert!((speed.max_rad_s() - 10.471_976).abs() < 1e-4);
        assert_eq!(speed_scale(&[1.0, -2.0, 0.0, 0.0, 0.0, 0.0], 4.0), 1.0);
        assert_eq!(speed_scale(&[1.0, -8.0, 0.0, 0.0, 0.0, 0.0], 4.0), 0.5);
        assert_eq!(speed_scale(&[f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0], 4.0), 0.0);
    }
}
