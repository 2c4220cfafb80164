//! Where the servos and rod joints are, and the constants derived from them once.
//!
//! All lengths are in millimetres and angles in radians. The base frame has its origin at the
//! centre of the servo shafts' plane with z up; the platform frame has its origin at the
//! centre of the platform joints' plane. Each leg `i` has:
//! - `b_i`: the centre of servo `i`'s shaft (base frame), the point the arm turns about;
//! - `p_i`: the rod's joint on the platform (platform frame);
//! - `beta_i`: the angle of the arm's plane of rotation from the base x axis, chosen so that
//!   the arm tip at arm angle `alpha` is `b_i + a (cos(alpha) cos(beta_i),
//!   cos(alpha) sin(beta_i), sin(alpha))` ("The Mathematics of the Stewart Platform", eq. 4-6).
//!   The two servos of a pair are mirror images: in [`PairedLayout`] each arm is tangent to the
//!   base circle and points away from the pair's centre, so their `beta` differ by 180 degrees
//!   plus the angle between the two shafts. Their opposite sense of rotation is a property of
//!   the servo, see [`crate::servo::Direction`].
//!
//! All legs share the arm (horn) length `a` and the rod length `s`.
//!
//! From these, [`Geometry::new`] derives the home height `h0` (eq. 10). A geometry is a
//! description of the build and nothing else: what the IK derives from it (the home arm angles
//! `alpha0` of eq. 12, which are the IK's own answer at the home pose, and the constants it needs
//! on every pose) lives in [`crate::ik::Solver`].
//!
//! The layouts compute their joints with `M`'s sine and cosine (`build_with`), so a board
//! builds a geometry with its fast routines; `build` uses `libm`.

use core::fmt;

use crate::math::{Libm, Math};
use crate::types::{Vec3, LEGS};

/// Largest disagreement between the legs' home heights (eq. 10) that a geometry may have, mm.
/// Below it, `h0` is their mean (and the IK computes each leg's `alpha0` exactly for that
/// height); above it, the build numbers are almost certainly mistyped.
pub const HOME_HEIGHT_TOLERANCE_MM: f32 = 0.1;

/// One leg's build coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leg {
    /// Servo shaft centre `b_i`, base frame, mm.
    pub base_mm: Vec3,
    /// Rod joint on the platform `p_i`, platform frame, mm.
    pub platform_mm: Vec3,
    /// Arm-plane angle `beta_i` from the base x axis, rad.
    pub beta_rad: f32,
}

/// A validated platform geometry: the build (legs, arm and rod lengths) and what follows from
/// it alone, the home height `h0`.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    legs: [Leg; LEGS],
    arm_mm: f32,
    rod_mm: f32,
    /// `h0` (eq. 10), mm.
    home_height_mm: f32,
}

/// Which length of a geometry a [`GeometryError`] is about.
///
/// `Display` gives its name for developers; the wording users see is `control::report`'s.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Length {
    /// The servo arm (horn) length `a`.
    Arm,
    /// The rod length `s`.
    Rod,
    /// The base joint circle radius.
    BaseRadius,
    /// The platform joint circle radius.
    PlatformRadius,
}

impl fmt::Display for Length {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Length::Arm => "arm length a",
            Length::Rod => "rod length s",
            Length::BaseRadius => "base radius",
            Length::PlatformRadius => "platform radius",
        })
    }
}

/// Why a set of build numbers is not a usable geometry.
///
/// `Display` gives one short line for developers (the case and its values, in the units of the
/// fields); the wording users see is `control::report`'s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GeometryError {
    /// A coordinate or angle of leg `leg` (1..=6) is NaN or infinite.
    NonFiniteLeg {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// A length is NaN, infinite, zero or negative.
    BadLength {
        /// Which length.
        which: Length,
        /// The value given, mm.
        value_mm: f32,
    },
    /// Eq. 10 has no real solution for this leg: the rod and arm are too short to reach the
    /// platform joint with arm and rod at right angles, or the platform would sit at or below
    /// the servo shaft.
    NoHomeHeight {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// The legs' home heights (eq. 10) differ by more than [`HOME_HEIGHT_TOLERANCE_MM`].
    LegsDisagree {
        /// The first leg that disagrees with leg 1, 1..=6.
        leg: u8,
        /// Its home height, mm.
        home_height_mm: f32,
        /// Leg 1's home height, mm.
        leg1_home_height_mm: f32,
    },
    /// At the home pose this leg's arm cannot reach its rod (eq. 9 has no solution).
    HomeUnreachable {
        /// Leg number, 1..=6.
        leg: u8,
    },
}

impl fmt::Display for GeometryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            GeometryError::NonFiniteLeg { leg } => {
                write!(f, "leg {leg}: non-finite coordinate or angle")
            }
            GeometryError::BadLength { which, value_mm } => {
                write!(f, "{which} not a positive finite length: {value_mm} mm")
            }
            GeometryError::NoHomeHeight { leg } => {
                write!(f, "leg {leg}: no home height (no real root of eq. 10)")
            }
            GeometryError::LegsDisagree {
                leg,
                home_height_mm,
                leg1_home_height_mm,
            } => write!(
                f,
                "leg {leg}: home height {home_height_mm} mm, leg 1: {leg1_home_height_mm} mm"
            ),
            GeometryError::HomeUnreachable { leg } => {
                write!(f, "leg {leg}: home pose unreachable (no root of eq. 9)")
            }
        }
    }
}

impl core::error::Error for GeometryError {}

fn check_length(which: Length, value_mm: f32) -> Result<f32, GeometryError> {
    if value_mm.is_finite() && value_mm > 0.0 {
        Ok(value_mm)
    } else {
        Err(GeometryError::BadLength { which, value_mm })
    }
}

fn leg_number(index: usize) -> u8 {
    // LEGS is 6, so this never truncates.
    (index + 1) as u8
}

impl Geometry {
    /// Validates explicit build coordinates and derives `h0`.
    pub fn new(legs: [Leg; LEGS], arm_mm: f32, rod_mm: f32) -> Result<Geometry, GeometryError> {
        let arm_mm = check_length(Length::Arm, arm_mm)?;
        let rod_mm = check_length(Length::Rod, rod_mm)?;
        for (i, leg) in legs.iter().enumerate() {
            let finite = leg.base_mm.iter().all(|v| v.is_finite())
                && leg.platform_mm.iter().all(|v| v.is_finite())
                && leg.beta_rad.is_finite();
            if !finite {
                return Err(GeometryError::NonFiniteLeg { leg: leg_number(i) });
            }
        }

        // Eq. 10, generalised to a shaft at height z_b: at home (T = (0, 0, h0), R = I) the arm
        // and rod are at right angles, so |l|^2 = s^2 + a^2 with
        // l = (x_p - x_b, y_p - y_b, h0 + z_p - z_b); take the root with the platform above.
        let mut heights = [0.0f32; LEGS];
        for (i, leg) in legs.iter().enumerate() {
            let d = leg.platform_mm - leg.base_mm;
            let vertical_sq = rod_mm * rod_mm + arm_mm * arm_mm - d.x * d.x - d.y * d.y;
            if vertical_sq.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
                return Err(GeometryError::NoHomeHeight { leg: leg_number(i) });
            }
            heights[i] = libm::sqrtf(vertical_sq) - d.z;
        }
        for (i, &h) in heights.iter().enumerate().skip(1) {
            if libm::fabsf(h - heights[0]) > HOME_HEIGHT_TOLERANCE_MM {
                return Err(GeometryError::LegsDisagree {
                    leg: leg_number(i),
                    home_height_mm: h,
                    leg1_home_height_mm: heights[0],
                });
            }
        }
        let home_height_mm = heights.iter().sum::<f32>() / LEGS as f32;
        Ok(Geometry {
            legs,
            arm_mm,
            rod_mm,
            home_height_mm,
        })
    }

    /// The six legs' build coordinates.
    pub fn legs(&self) -> &[Leg; LEGS] {
        &self.legs
    }

    /// Leg `index` (0..=5).
    pub fn leg(&self, index: usize) -> &Leg {
        &self.legs[index]
    }

    /// Servo arm (horn) length `a`, mm.
    pub fn arm_mm(&self) -> f32 {
        self.arm_mm
    }

    /// Rod length `s`, mm.
    pub fn rod_mm(&self) -> f32 {
        self.rod_mm
    }

    /// Home height `h0` (eq. 10): the height of the platform frame above the base frame at the
    /// home pose, mm.
    pub fn home_height_mm(&self) -> f32 {
        self.home_height_mm
    }
}

impl Default for Geometry {
    /// The default build, [`PairedLayout::default`].
    fn default() -> Geometry {
        PairedLayout::default()
            .build()
            .expect("the default paired layout is a valid geometry (tested)")
    }
}

/// Joints on two circles at given angles (the "general configuration" of the Stewart platform
/// Simscape model documentation), each leg with its own arm-plane angle. Angles in degrees, as
/// users measure them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CircularLayout {
    /// Radius of the circle through the servo shaft centres, mm.
    pub base_radius_mm: f32,
    /// Radius of the circle through the platform joints, mm.
    pub platform_radius_mm: f32,
    /// Angle of each servo shaft centre about z from the base x axis, degrees.
    pub base_angles_deg: [f32; LEGS],
    /// Angle of each platform joint about z from the platform x axis, degrees.
    pub platform_angles_deg: [f32; LEGS],
    /// Arm-plane angle `beta_i` of each servo, degrees.
    pub beta_deg: [f32; LEGS],
    /// Servo arm (horn) length `a`, mm.
    pub arm_mm: f32,
    /// Rod length `s`, mm.
    pub rod_mm: f32,
}

impl CircularLayout {
    /// The explicit legs of this layout (all joints in their frame's z = 0 plane).
    pub fn legs(&self) -> [Leg; LEGS] {
        self.legs_with::<Libm>()
    }

    /// [`CircularLayout::legs`] with `M`'s sine and cosine. `M` may take only small angles
    /// (the boot ROM's up to 128 rad, about 7,300 degrees): beyond, a coordinate is NaN and
    /// [`Geometry::new`] refuses it.
    pub fn legs_with<M: Math>(&self) -> [Leg; LEGS] {
        core::array::from_fn(|i| {
            let (sb, cb) = M::sin_cos(self.base_angles_deg[i].to_radians());
            let (sp, cp) = M::sin_cos(self.platform_angles_deg[i].to_radians());
            Leg {
                base_mm: Vec3::new(self.base_radius_mm * cb, self.base_radius_mm * sb, 0.0),
                platform_mm: Vec3::new(
                    self.platform_radius_mm * cp,
                    self.platform_radius_mm * sp,
                    0.0,
                ),
                beta_rad: self.beta_deg[i].to_radians(),
            }
        })
    }

    /// Validates the layout and derives the geometry.
    pub fn build(&self) -> Result<Geometry, GeometryError> {
        self.build_with::<Libm>()
    }

    /// [`CircularLayout::build`] with `M`'s sine and cosine.
    pub fn build_with<M: Math>(&self) -> Result<Geometry, GeometryError> {
        check_length(Length::BaseRadius, self.base_radius_mm)?;
        check_length(Length::PlatformRadius, self.platform_radius_mm)?;
        Geometry::new(self.legs_with::<M>(), self.arm_mm, self.rod_mm)
    }
}

/// The usual hobby layout: three pairs of mirrored servos 120 degrees apart, arms tangential
/// and pointing away from their pair's centre, each rod running to the platform joint pair
/// turned 60 degrees towards it. Three-fold symmetric about z.
///
/// Servo pair `k` (0, 1, 2) is centred at `120k` degrees: servo `2k+1` sits at
/// `120k - base_half_angle`, servo `2k+2` at `120k + base_half_angle`. Their platform joints
/// are at `120k - 60 + platform_half_angle` and `120k + 60 - platform_half_angle`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairedLayout {
    /// Radius of the circle through the servo shaft centres, mm.
    pub base_radius_mm: f32,
    /// Half the angle between the two servos of a pair, degrees.
    pub base_half_angle_deg: f32,
    /// Radius of the circle through the platform joints, mm.
    pub platform_radius_mm: f32,
    /// Half the angle between the two platform joints of a pair, degrees.
    pub platform_half_angle_deg: f32,
    /// Servo arm (horn) length `a`, mm.
    pub arm_mm: f32,
    /// Rod length `s`, mm.
    pub rod_mm: f32,
}

impl Default for PairedLayout {
    /// A typical desk-sized build with standard servos, 20 mm horns and 120 mm rods. The
    /// numbers put the arms nearly horizontal at home (alpha0 = -0.25 degrees, h0 = 118.46 mm),
    /// which centres the servos' travel: with tangential arms, alpha0 = 0 exactly when
    /// `platform_radius * sin(60 - base_half_angle - platform_half_angle) = arm`.
    fn default() -> PairedLayout {
        PairedLayout {
            base_radius_mm: 75.0,
            base_half_angle_deg: 20.0,
            platform_radius_mm: 60.0,
            platform_half_angle_deg: 20.0,
            arm_mm: 20.0,
            rod_mm: 120.0,
        }
    }
}

impl PairedLayout {
    /// The equivalent general circular layout.
    pub fn circular(&self) -> CircularLayout {
        let db = self.base_half_angle_deg;
        let dp = self.platform_half_angle_deg;
        let mut base = [0.0; LEGS];
        let mut platform = [0.0; LEGS];
        let mut beta = [0.0; LEGS];
        for k in 0..3 {
            let centre = 120.0 * k as f32;
            // Odd servo (2k+1, index 2k): arm points clockwise, away from the pair centre.
            base[2 * k] = centre - db;
            platform[2 * k] = centre - 60.0 + dp;
            beta[2 * k] = centre - db - 90.0;
            // Even servo (2k+2, index 2k+1): the mirror image.
            base[2 * k + 1] = centre + db;
            platform[2 * k + 1] = centre + 60.0 - dp;
            beta[2 * k + 1] = centre + db + 90.0;
        }
        CircularLayout {
            base_radius_mm: self.base_radius_mm,
            platform_radius_mm: self.platform_radius_mm,
            base_angles_deg: base,
            platform_angles_deg: platform,
            beta_deg: beta,
            arm_mm: self.arm_mm,
            rod_mm: self.rod_mm,
        }
    }

    /// Validates the layout and derives the geometry.
    pub fn build(&self) -> Result<Geometry, GeometryError> {
        self.circular().build()
    }

    /// [`PairedLayout::build`] with `M`'s sine and cosine (a board's fast routines).
    pub fn build_with<M: Math>(&self) -> Result<Geometry, GeometryError> {
        self.circular().build_with::<M>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_geometry_has_the_documented_home_height() {
        let g = Geometry::default();
        assert!(
            (g.home_height_mm() - 118.458).abs() < 0.01,
            "{}",
            g.home_height_mm()
        );
    }

    fn layout_with(change: impl FnOnce(&mut PairedLayout)) -> Result<Geometry, GeometryError> {
        let mut p = PairedLayout::default();
        change(&mut p);
        p.build()
    }

    #[test]
    fn bad_lengths_are_named() {
        assert_eq!(
            layout_with(|p| p.arm_mm = 0.0),
            Err(GeometryError::BadLength {
                which: Length::Arm,
                value_mm: 0.0
            })
        );
        assert!(matches!(
            layout_with(|p| p.rod_mm = f32::NAN),
            Err(GeometryError::BadLength {
                which: Length::Rod,
                ..
            })
        ));
        assert!(matches!(
            layout_with(|p| p.platform_radius_mm = -1.0),
            Err(GeometryError::BadLength {
                which: Length::PlatformRadius,
                ..
            })
        ));
    }

    #[test]
    fn too_short_rod_has_no_home_height() {
        assert!(matches!(
            layout_with(|p| p.rod_mm = 10.0),
            Err(GeometryError::NoHomeHeight { leg: 1 })
        ));
    }

    #[test]
    fn a_moved_joint_makes_legs_disagree() {
        let mut legs = PairedLayout::default().circular().legs();
        legs[3].platform_mm.y += 10.0;
        let err = Geometry::new(legs, 20.0, 120.0).unwrap_err();
        assert!(
            matches!(err, GeometryError::LegsDisagree { leg: 4, .. }),
            "{err}"
        );
    }

    #[test]
    fn non_finite_leg_is_named() {
        let mut legs = PairedLayout::default().circular().legs();
        legs[5].beta_rad = f32::INFINITY;
        assert_eq!(
            Geometry::new(legs, 20.0, 120.0),
            Err(GeometryError::NonFiniteLeg { leg: 6 })
        );
    }
}
