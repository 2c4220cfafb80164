//! The legs at a pose, for both kinds of platform (what the kinematics beyond the IK need of
//! either, [`crate::jacobian::Actuators`], is implemented with them in [`crate::jacobian`]).
//!
//! - Linear struts ([`Struts`]): leg `i` runs from its base joint `b_i` to its platform joint
//!   `q_i`; its vector is `l_i = q_i - b_i` (eq. 3 of "The Mathematics of the Stewart
//!   Platform"), its length `|l_i|` and its unit vector `s_i = l_i / |l_i|` (the Stewart
//!   platform Simscape model documentation's `inverseKinematics` and `computeJointsPose`;
//!   `Find_Lenght` and `Find_UnitV` of the ROBOOP `LinkStewart` class). A strut has a stroke:
//!   the lengths it can take.
//! - Servo arms ([`ArmState`], from an [`ik::Solver`]): the arm of servo `i` turns about the
//!   shaft `b_i`; its tip is `A_i = b_i + a (cos(alpha) cos(beta), cos(alpha) sin(beta),
//!   sin(alpha))` (eq. 4-6), the rod runs from the tip to the joint: `d_i = q_i - A_i`, of
//!   length `s` (the rod closure behind eq. 7-9).
//!
//! Lengths in mm, angles in radians. The platform joints come from [`Anchors::place`], so every
//! leg honours the rotation centre.

use crate::configuration::{
    check_centre, Anchors, ConfigurationError, CubicConfiguration, Dimension, GeneralConfiguration,
    Placement,
};
use crate::error::KinematicsError;
use crate::ik::{check_pose, Solver};
use crate::math::{dot, lt, sub, Math, Real};
use crate::pose::Pose;
use crate::types::{Vec3, LEGS};

/// Struts shorter than this are refused as [`KinematicsError::ZeroLength`], mm: their
/// direction is lost in `f32` rounding.
pub const MIN_LENGTH_MM: f32 = 1e-3;

/// The lengths a strut can take, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stroke {
    /// Shortest length, mm.
    pub min_mm: f32,
    /// Longest length, mm.
    pub max_mm: f32,
}

impl Stroke {
    /// Any length.
    pub const UNLIMITED: Stroke = Stroke {
        min_mm: 0.0,
        max_mm: f32::MAX,
    };

    /// True if `length_mm` is within the stroke.
    pub fn allows(&self, length_mm: f32) -> bool {
        self.min_mm <= length_mm && length_mm <= self.max_mm
    }
}

/// A platform of six linear struts: anchors, rotation centre and strokes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Struts {
    anchors: Anchors,
    strokes: [Stroke; LEGS],
    home_lengths_mm: [f32; LEGS],
}

/// The struts at one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrutState {
    /// Where the platform is.
    pub placement: Placement,
    /// `|l_i|`, mm.
    pub lengths_mm: [f32; LEGS],
    /// `s_i = l_i / |l_i|`, from the base joint towards the platform joint.
    pub units: [Vec3; LEGS],
}

impl Struts {
    /// Struts from base joints `b_i` (base frame), platform joints `p_i` (platform frame) and
    /// the home height `h0` (mm); any length, rotation centre at the platform frame's origin.
    pub fn new(
        base_mm: [Vec3; LEGS],
        platform_mm: [Vec3; LEGS],
        home_height_mm: f32,
    ) -> Result<Struts, ConfigurationError> {
        if !home_height_mm.is_finite() {
            return Err(ConfigurationError::NonFinite {
                which: Dimension::HomeHeight,
            });
        }
        for (i, (b, p)) in base_mm.iter().zip(platform_mm.iter()).enumerate() {
            if !(b.iter().all(|v| v.is_finite()) && p.iter().all(|v| v.is_finite())) {
                return Err(ConfigurationError::NonFinite {
                    which: Dimension::Anchor { leg: i as u8 + 1 },
                });
            }
        }
        let anchors = Anchors {
            base_mm,
            platform_mm,
            home_height_mm,
            rotation_centre_mm: Vec3::zeros(),
        };
        let home = Pose::HOME;
        let placement = anchors.place::<crate::math::Libm>(&home);
        let mut home_lengths_mm = [0.0; LEGS];
        for (i, length) in home_lengths_mm.iter_mut().enumerate() {
            *length = (placement.joints_mm[i] - base_mm[i]).norm();
            if !lt(MIN_LENGTH_MM, *length) {
                return Err(ConfigurationError::CoincidentJoints { leg: i as u8 + 1 });
            }
        }
        Ok(Struts {
            anchors,
            strokes: [Stroke::UNLIMITED; LEGS],
            home_lengths_mm,
        })
    }

    /// Struts on a general configuration, its platform frame `home_height_mm` above the base.
    pub fn from_general(
        config: &GeneralConfiguration,
        home_height_mm: f32,
    ) -> Result<Struts, ConfigurationError> {
        let (base, platform) = config.anchors()?;
        Struts::new(base, platform, home_height_mm)
    }

    /// Struts on a cubic configuration (rotation centre at the platform frame's origin; set it
    /// to [`CubicConfiguration::cube_centre_mm`] for the decoupled stiffness).
    pub fn from_cubic(config: &CubicConfiguration) -> Result<Struts, ConfigurationError> {
        let (base, platform) = config.anchors()?;
        Struts::new(base, platform, config.home_height_mm)
    }

    /// The anchors, home height and rotation centre.
    pub fn anchors(&self) -> Anchors {
        self.anchors
    }

    /// Sets the rotation centre (platform frame, mm; see [`crate::configuration`]).
    pub fn set_rotation_centre_mm(&mut self, centre_mm: Vec3) -> Result<(), ConfigurationError> {
        self.anchors.rotation_centre_mm = check_centre(centre_mm)?;
        Ok(())
    }

    /// Sets the stroke of leg `index` (0..=5).
    pub fn set_stroke(&mut self, index: usize, stroke: Stroke) {
        self.strokes[index] = stroke;
    }

    /// The same stroke for every leg.
    pub fn with_strokes(mut self, stroke: Stroke) -> Struts {
        self.strokes = [stroke; LEGS];
        self
    }

    /// The stroke of leg `index` (0..=5).
    pub fn stroke(&self, index: usize) -> Stroke {
        self.strokes[index]
    }

    /// The strut lengths at the home pose, mm.
    pub fn home_lengths_mm(&self) -> [f32; LEGS] {
        self.home_lengths_mm
    }

    /// The struts at `pose`, whatever their strokes.
    pub fn state<M: Math>(&self, pose: &Pose) -> Result<StrutState, KinematicsError> {
        check_pose(pose)?;
        let placement = self.anchors.place::<M>(pose);
        let mut lengths_mm = [0.0; LEGS];
        let mut units = [Vec3::zeros(); LEGS];
        for i in 0..LEGS {
            let l = placement.joints_mm[i] - self.anchors.base_mm[i];
            let length = M::sqrt(dot::<M>(l, l));
            if !(length > MIN_LENGTH_MM && length.is_finite()) {
                return Err(KinematicsError::ZeroLength { leg: i as u8 + 1 });
            }
            lengths_mm[i] = length;
            units[i] = l * (1.0 / length);
        }
        Ok(StrutState {
            placement,
            lengths_mm,
            units,
        })
    }

    /// The inverse kinematics of the struts: their state at `pose`, refused
    /// ([`KinematicsError::Stroke`], naming the first leg) if a length is outside its stroke.
    pub fn solve<M: Math>(&self, pose: &Pose) -> Result<StrutState, KinematicsError> {
        let state = self.state::<M>(pose)?;
        for (i, (&length_mm, stroke)) in state.lengths_mm.iter().zip(&self.strokes).enumerate() {
            if !stroke.allows(length_mm) {
                return Err(KinematicsError::Stroke {
                    leg: i as u8 + 1,
                    length_mm,
                    min_mm: stroke.min_mm,
                    max_mm: stroke.max_mm,
                });
            }
        }
        Ok(state)
    }
}

/// The servo arms and rods at one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmState {
    /// Where the platform is.
    pub placement: Placement,
    /// Arm angles `alpha_i` (eq. 9), rad.
    pub arm_rad: [f32; LEGS],
    /// Arm tips `A_i` (eq. 4-6), base frame, mm.
    pub tips_mm: [Vec3; LEGS],
    /// Rods `d_i = q_i - A_i`, from the arm tip to the platform joint, mm (length `s`).
    pub rods_mm: [Vec3; LEGS],
    /// `t_i = dA_i / d alpha_i`: how fast the tip moves per radian of arm, mm/rad (length `a`,
    /// square to the arm in its plane).
    pub tip_rates_mm: [Vec3; LEGS],
}

impl ArmState {
    /// Each arm's transmission, `d_i . t_i / (|d_i| |t_i|)`: the cosine of the angle between
    /// the rod and the path of the arm tip. 1 when the rod runs along the tip's path (in the
    /// arm's plane, square to the arm; at the home pose of eq. 10 arm and rod are square, and
    /// the transmission is the cosine of the rod's slant out of the arm's plane); 0 at dead
    /// centre, where the arm cannot move the rod (the leg's workspace boundary). It says how
    /// close a servo platform is to that singularity, which scales its Jacobian's rows and so
    /// does not show in [`crate::jacobian::Jacobian::condition_number`].
    pub fn transmission(&self) -> [f32; LEGS] {
        core::array::from_fn(|i| {
            let (d, t) = (self.rods_mm[i], self.tip_rates_mm[i]);
            d.dot(&t) / (d.norm() * t.norm())
        })
    }

    /// The servo arms at `pose`: the IK's arm angles (no servo limits), then the tips and rods.
    pub fn new<M: Math>(solver: &Solver, pose: &Pose) -> Result<ArmState, KinematicsError> {
        let arm_rad = solver.arm_angles::<M>(pose)?;
        Ok(ArmState::at_angles::<M>(solver, pose, arm_rad))
    }

    /// The arms at `pose` with given arm angles (which should be the IK's at that pose).
    pub fn at_angles<M: Math>(solver: &Solver, pose: &Pose, arm_rad: [f32; LEGS]) -> ArmState {
        let placement = solver.anchors().place::<M>(pose);
        let (tips_mm, tip_rates_mm) = arm_tips::<M>(solver, &arm_rad);
        let rods_mm = core::array::from_fn(|i| sub::<M>(placement.joints_mm[i], tips_mm[i]));
        ArmState {
            placement,
            arm_rad,
            tips_mm,
            rods_mm,
            tip_rates_mm,
        }
    }
}

/// The arm tips `A_i` (eq. 4-6) at the arm angles `alpha_i`, base frame, mm, and their rates
/// `t_i = dA_i / d alpha_i`, mm/rad.
pub fn arm_tips<M: Math>(solver: &Solver, arm_rad: &[f32; LEGS]) -> ([Vec3; LEGS], [Vec3; LEGS]) {
    let r = Real::<M>::new;
    let a = r(solver.geometry().arm_mm());
    let mut tips_mm = [Vec3::zeros(); LEGS];
    let mut rates_mm = [Vec3::zeros(); LEGS];
    for i in 0..LEGS {
        let (sin_a, cos_a) = M::sin_cos(arm_rad[i]);
        let [cos_b, sin_b] = solver.arm_plane(i).map(r);
        let (a_sin, a_cos) = (a * r(sin_a), a * r(cos_a));
        let b = solver.geometry().leg(i).base_mm;
        tips_mm[i] = Vec3::new(
            (r(b.x) + a_cos * cos_b).0,
            (r(b.y) + a_cos * sin_b).0,
            (r(b.z) + a_sin).0,
        );
        rates_mm[i] = Vec3::new(-(a_sin * cos_b).0, -(a_sin * sin_b).0, a_cos.0);
    }
    (tips_mm, rates_mm)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Geometry;
    use crate::math::Libm;

    #[test]
    fn strut_lengths_at_home_and_stroke_errors() {
        let s = Struts::from_general(&GeneralConfiguration::SIMSCAPE, 90.0).unwrap();
        let state = s.state::<Libm>(&Pose::HOME).unwrap();
        assert_eq!(state.lengths_mm, s.home_lengths_mm());
        for u in state.units {
            assert!((u.norm() - 1.0).abs() < 1e-6);
        }
        let short = s.with_strokes(Stroke {
            min_mm: 0.0,
            max_mm: s.home_lengths_mm()[0] + 1.0,
        });
        let up = Pose::from_degrees(0.0, 0.0, 5.0, 0.0, 0.0, 0.0);
        assert!(matches!(
            short.solve::<Libm>(&up),
            Err(KinematicsError::Stroke { leg: 1, .. })
        ));
    }

    #[test]
    fn arm_state_closes_every_rod() {
        let solver = Solver::new(Geometry::default()).unwrap();
        let pose = Pose::from_degrees(3.0, -2.0, 4.0, 2.0, -3.0, 5.0);
        let arms = ArmState::new::<Libm>(&solver, &pose).unwrap();
        for i in 0..LEGS {
            assert!((arms.rods_mm[i].norm() - 120.0).abs() < 1e-3, "leg {i}");
            assert!((arms.tip_rates_mm[i].norm() - 20.0).abs() < 1e-4, "leg {i}");
        }
    }
}
