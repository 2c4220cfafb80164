//! Where the legs attach, the frames a pose is measured in, and the configuration generators.
//!
//! Lengths in mm, angles in radians (the generators take degrees, as users measure them).
//!
//! Frames, after the Stewart platform Simscape model documentation:
//! - the base frame (the documentation's {F}): z up; the legs' lower anchors `b_i` are fixed in
//!   it (for a servo platform the servo shaft centres, "The Mathematics of the Stewart
//!   Platform"; for linear struts the base joints, the documentation's `a_i`);
//! - the platform frame ({M}): moves with the platform; the upper anchors `p_i` (the
//!   documentation's `b_i`) are fixed in it. At home it is parallel to the base frame,
//!   `h0` above it ([`Anchors::home_height_mm`]);
//! - the rotation centre `c`, a point fixed to the platform, given in the platform frame: the
//!   documentation's frame {B} sits there, and {A} is the base-fixed frame that coincides with
//!   {B} at home. A pose is {B} relative to {A}: `(x, y, z)` is how far `c` has moved from its
//!   home position (base axes) and `R` (eq. 1 of "The Mathematics of the Stewart Platform") the
//!   platform's orientation, so the platform turns about `c`. A motion platform's pivot
//!   (e.g. the driver's head) is such a point.
//!
//! So the upper anchor of leg `i` is, in the base frame ([`Anchors::place`]),
//! `q_i = C + R (p_i - c)` with `C = (x, y, h0 + z) + c` the centre's position: eq. 2 of "The
//! Mathematics of the Stewart Platform" (`q_i = T + R p_i`) with `T = C - R c`. With `c = 0`
//! (the default) it is eq. 2 itself.
//!
//! Generators: [`GeneralConfiguration`] (joints on circles at given radii, heights and angles,
//! `generateGeneralConfiguration`) and [`CubicConfiguration`] (the struts along the edges of a
//! cube standing on a corner, `generateCubicConfiguration`).

use core::fmt;

use crate::math::{add, is_zero, mul_mat_vec, sub, Libm, Math, Real};
use crate::pose::Pose;
use crate::types::{Mat3, Vec3, LEGS};

/// Farthest a rotation centre may be from the platform frame's origin, mm (10 m): beyond,
/// it is a typing mistake, and the kinematics keep their magnitudes bounded.
pub const MAX_CENTRE_MM: f32 = 10_000.0;

/// Why a configuration or a rotation centre is refused.
///
/// `Display` gives one short line for developers; the wording users see is `control::report`'s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ConfigurationError {
    /// A number of the configuration is NaN or infinite.
    NonFinite {
        /// Which number.
        which: Dimension,
    },
    /// A length that must be positive is not.
    NotPositive {
        /// Which length.
        which: Dimension,
        /// The value given, mm.
        value_mm: f32,
    },
    /// The base joints are not below the platform joints at home (the legs would point down
    /// or lie flat).
    JointsNotBelow {
        /// Height of the base joints above the base frame, mm.
        base_mm: f32,
        /// Height of the platform joints above the base frame at home, mm.
        platform_mm: f32,
    },
    /// A leg's two joints coincide at home (a strut of zero length).
    CoincidentJoints {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// The rotation centre is NaN, infinite or farther than [`MAX_CENTRE_MM`] from the platform
    /// frame's origin.
    BadCentre {
        /// Its distance from the platform frame's origin, mm (NaN or infinite if not finite).
        distance_mm: f32,
    },
}

/// Which number of a configuration a [`ConfigurationError`] is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// Radius of the base joints' circle.
    BaseRadius,
    /// Radius of the platform joints' circle.
    PlatformRadius,
    /// Height of the base joints.
    BaseHeight,
    /// Height of the platform joints.
    PlatformHeight,
    /// An angle of joint `leg` (1..=6).
    Angle {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// A joint position (anchor) of leg `leg` (1..=6).
    Anchor {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// The home height `h0` (the platform frame above the base frame at home).
    HomeHeight,
    /// The height of the cube of a cubic configuration.
    CubeHeight,
    /// The height of the cube's centre.
    CubeCentreHeight,
}

impl fmt::Display for Dimension {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Dimension::BaseRadius => f.write_str("base radius"),
            Dimension::PlatformRadius => f.write_str("platform radius"),
            Dimension::BaseHeight => f.write_str("base joint height"),
            Dimension::PlatformHeight => f.write_str("platform joint height"),
            Dimension::Angle { leg } => write!(f, "joint angle of leg {leg}"),
            Dimension::Anchor { leg } => write!(f, "joint position of leg {leg}"),
            Dimension::HomeHeight => f.write_str("home height"),
            Dimension::CubeHeight => f.write_str("cube height"),
            Dimension::CubeCentreHeight => f.write_str("cube centre height"),
        }
    }
}

impl fmt::Display for ConfigurationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ConfigurationError::NonFinite { which } => write!(f, "{which}: not finite"),
            ConfigurationError::NotPositive { which, value_mm } => {
                write!(f, "{which}: {value_mm} mm, not positive")
            }
            ConfigurationError::JointsNotBelow {
                base_mm,
                platform_mm,
            } => write!(
                f,
                "base joints at {base_mm} mm not below platform joints at {platform_mm} mm"
            ),
            ConfigurationError::CoincidentJoints { leg } => {
                write!(f, "leg {leg}: joints coincide at home")
            }
            ConfigurationError::BadCentre { distance_mm } => write!(
                f,
                "rotation centre {distance_mm} mm from the platform origin, limit {MAX_CENTRE_MM}"
            ),
        }
    }
}

impl core::error::Error for ConfigurationError {}

/// Checks a rotation centre (platform frame, mm): finite and within [`MAX_CENTRE_MM`].
pub fn check_centre(centre_mm: Vec3) -> Result<Vec3, ConfigurationError> {
    let distance_mm = libm::sqrtf(centre_mm.dot(&centre_mm));
    if distance_mm.is_finite() && distance_mm <= MAX_CENTRE_MM {
        Ok(centre_mm)
    } else {
        Err(ConfigurationError::BadCentre { distance_mm })
    }
}

/// The six legs' anchors, the home height and the rotation centre: everything the kinematics
/// of either kind of leg (servo arm and rod, or linear strut) need about where the legs attach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anchors {
    /// Lower anchors `b_i`, base frame, mm: servo shaft centres or base joints.
    pub base_mm: [Vec3; LEGS],
    /// Upper anchors `p_i`, platform frame, mm: the joints on the platform.
    pub platform_mm: [Vec3; LEGS],
    /// `h0`: how far the platform frame is above the base frame at the home pose, mm.
    pub home_height_mm: f32,
    /// The rotation centre `c`, platform frame, mm (see the module docs).
    pub rotation_centre_mm: Vec3,
}

/// Where the platform is at one pose: its rotation, the rotation centre and the upper anchors
/// in the base frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// `R = Rz(yaw) Ry(pitch) Rx(roll)` (eq. 1 of "The Mathematics of the Stewart Platform").
    pub rotation: Mat3,
    /// Where the rotation centre is, base frame, mm: `C = (x, y, h0 + z) + c`.
    pub centre_mm: Vec3,
    /// Lever arms `r_i = R (p_i - c)`: from the rotation centre to each upper anchor, base axes,
    /// mm. A twist taken at the rotation centre moves anchor `i` at `v + omega x r_i`.
    pub levers_mm: [Vec3; LEGS],
    /// Upper anchors `q_i = C + r_i`, base frame, mm (eq. 2).
    pub joints_mm: [Vec3; LEGS],
}

impl Anchors {
    /// Where the platform's anchors are at `pose` (eq. 1, 2), with `M`'s sine, cosine and
    /// arithmetic. The pose must be finite (see [`crate::ik::check_pose`]).
    pub fn place<M: Math>(&self, pose: &Pose) -> Placement {
        let rotation = pose.rotation::<M>();
        let c = self.rotation_centre_mm;
        let r = Real::<M>::new;
        let centre_mm = Vec3::new(
            (r(pose.x_mm) + r(c.x)).0,
            (r(pose.y_mm) + r(c.y)).0,
            (r(self.home_height_mm) + r(pose.z_mm) + r(c.z)).0,
        );
        let at_origin = c.iter().all(|v| is_zero(*v));
        let levers_mm: [Vec3; LEGS] = core::array::from_fn(|i| {
            let p = self.platform_mm[i];
            mul_mat_vec::<M>(&rotation, if at_origin { p } else { sub::<M>(p, c) })
        });
        let joints_mm = core::array::from_fn(|i| add::<M>(centre_mm, levers_mm[i]));
        Placement {
            rotation,
            centre_mm,
            levers_mm,
            joints_mm,
        }
    }
}

/// Joints on two circles about z at given radii, heights and angles: the "general
/// configuration" of the Stewart platform Simscape model documentation
/// (`generateGeneralConfiguration`). Degrees for angles, as users measure them.
///
/// The base joints are at height `base_height_mm` above the base frame, the platform joints at
/// `platform_height_mm` in the platform frame (the documentation puts them `MH` below its
/// {M}: `platform_height_mm = -MH`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeneralConfiguration {
    /// Radius of the base joints' circle, mm (the documentation's `FR`).
    pub base_radius_mm: f32,
    /// Height of the base joints above the base frame, mm (`FH`).
    pub base_height_mm: f32,
    /// Angle of each base joint about z from the base x axis, degrees (`FTh`).
    pub base_angles_deg: [f32; LEGS],
    /// Radius of the platform joints' circle, mm (`MR`).
    pub platform_radius_mm: f32,
    /// Height of the platform joints in the platform frame, mm (`-MH`).
    pub platform_height_mm: f32,
    /// Angle of each platform joint about z from the platform x axis, degrees (`MTh`).
    pub platform_angles_deg: [f32; LEGS],
}

impl GeneralConfiguration {
    /// The documentation's defaults, in mm: base joints at 115 mm radius, 15 mm up, at -10,
    /// 10, 110, 130, 230, 250 degrees; platform joints at 90 mm radius, 15 mm below the platform
    /// frame, at -50, 50, 70, 170, 190, -70 degrees (its platform is 90 mm above the base).
    pub const SIMSCAPE: GeneralConfiguration = GeneralConfiguration {
        base_radius_mm: 115.0,
        base_height_mm: 15.0,
        base_angles_deg: [-10.0, 10.0, 110.0, 130.0, 230.0, 250.0],
        platform_radius_mm: 90.0,
        platform_height_mm: -15.0,
        platform_angles_deg: [-50.0, 50.0, 70.0, 170.0, 190.0, -70.0],
    };

    /// The lower and upper anchors `(b_i, p_i)`, mm, with `libm`'s sine and cosine.
    pub fn anchors(&self) -> Result<([Vec3; LEGS], [Vec3; LEGS]), ConfigurationError> {
        self.anchors_with::<Libm>()
    }

    /// [`GeneralConfiguration::anchors`] with `M`'s sine and cosine (angles up to 7,000
    /// degrees for the boot ROM's).
    pub fn anchors_with<M: Math>(
        &self,
    ) -> Result<([Vec3; LEGS], [Vec3; LEGS]), ConfigurationError> {
        for (which, value) in [
            (Dimension::BaseRadius, self.base_radius_mm),
            (Dimension::PlatformRadius, self.platform_radius_mm),
        ] {
            positive(which, value)?;
        }
        finite(Dimension::BaseHeight, self.base_height_mm)?;
        finite(Dimension::PlatformHeight, self.platform_height_mm)?;
        for i in 0..LEGS {
            let leg = i as u8 + 1;
            finite(Dimension::Angle { leg }, self.base_angles_deg[i])?;
            finite(Dimension::Angle { leg }, self.platform_angles_deg[i])?;
        }
        let on_circle = |radius: f32, height: f32, angle_deg: f32| {
            let (s, c) = M::sin_cos(angle_deg.to_radians());
            Vec3::new(radius * c, radius * s, height)
        };
        Ok((
            core::array::from_fn(|i| {
                on_circle(
                    self.base_radius_mm,
                    self.base_height_mm,
                    self.base_angles_deg[i],
                )
            }),
            core::array::from_fn(|i| {
                on_circle(
                    self.platform_radius_mm,
                    self.platform_height_mm,
                    self.platform_angles_deg[i],
                )
            }),
        ))
    }
}

/// The struts along three mutually orthogonal edges of a cube standing on a corner, its
/// diagonal vertical: the "cubic configuration" of the Stewart platform Simscape model
/// documentation (`generateCubicConfiguration`). At home every strut is orthogonal to four
/// others and parallel to the fifth, so with the rotation centre at the cube's centre
/// ([`CubicConfiguration::cube_centre_mm`]) the stiffness is the same in every direction of
/// translation and translations and rotations are decoupled.
///
/// The cube's six corners off its vertical diagonal lie in two horizontal planes `Hc` apart
/// (the cube's edge is `Hc sqrt(3)`), three at `120k` degrees about z on the lower plane and
/// three at `60 + 120k` on the upper, all on a circle of radius `Hc sqrt(2)`. Leg 1 runs from
/// the lower corner at 240 degrees to the upper one at 300, leg 2 from 0 to 300, leg 3 from 0
/// to 60, leg 4 from 120 to 60, leg 5 from 120 to 180, leg 6 from 240 to 180 (each along a
/// cube edge; the documentation's numbering). Each joint is then slid along its strut's line
/// to the height wanted: base joints `base_height_mm` above the base frame, platform joints
/// `platform_depth_mm` below the platform frame, which is `home_height_mm` above the base.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CubicConfiguration {
    /// `Hc`: the height between the cube's lower and upper corner planes, mm.
    pub cube_height_mm: f32,
    /// `FOc`: the height of the cube's centre above the base frame, mm.
    pub cube_centre_height_mm: f32,
    /// `FHa`: the height of the base joints above the base frame, mm.
    pub base_height_mm: f32,
    /// `MHb`: how far the platform joints are below the platform frame, mm.
    pub platform_depth_mm: f32,
    /// `H`: the height of the platform frame above the base frame at home, mm (`h0`).
    pub home_height_mm: f32,
}

impl CubicConfiguration {
    /// The documentation's defaults, in mm: `Hc` 60, `FOc` 50, `FHa` 15, `MHb` 15, `H` 90.
    pub const SIMSCAPE: CubicConfiguration = CubicConfiguration {
        cube_height_mm: 60.0,
        cube_centre_height_mm: 50.0,
        base_height_mm: 15.0,
        platform_depth_mm: 15.0,
        home_height_mm: 90.0,
    };

    /// The cube's centre in the platform frame, mm: the rotation centre that decouples
    /// translations from rotations.
    pub fn cube_centre_mm(&self) -> Vec3 {
        Vec3::new(0.0, 0.0, self.cube_centre_height_mm - self.home_height_mm)
    }

    /// The lower and upper anchors `(b_i, p_i)`, mm.
    pub fn anchors(&self) -> Result<([Vec3; LEGS], [Vec3; LEGS]), ConfigurationError> {
        positive(Dimension::CubeHeight, self.cube_height_mm)?;
        positive(Dimension::HomeHeight, self.home_height_mm)?;
        finite(Dimension::CubeCentreHeight, self.cube_centre_height_mm)?;
        finite(Dimension::BaseHeight, self.base_height_mm)?;
        finite(Dimension::PlatformHeight, self.platform_depth_mm)?;
        let top_mm = self.home_height_mm - self.platform_depth_mm;
        if self.base_height_mm >= top_mm {
            return Err(ConfigurationError::JointsNotBelow {
                base_mm: self.base_height_mm,
                platform_mm: top_mm,
            });
        }
        let hc = self.cube_height_mm;
        let radius = hc * core::f32::consts::SQRT_2;
        // A corner at `deg` degrees about z, `dz` above the cube's centre (base frame).
        let corner = |deg: f32, dz: f32| {
            let (s, c) = libm::sincosf(deg.to_radians());
            Vec3::new(radius * c, radius * s, self.cube_centre_height_mm + dz)
        };
        // (lower corner, upper corner) of each leg, degrees.
        const EDGES_DEG: [(f32, f32); LEGS] = [
            (240.0, 300.0),
            (0.0, 300.0),
            (0.0, 60.0),
            (120.0, 60.0),
            (120.0, 180.0),
            (240.0, 180.0),
        ];
        let mut base = [Vec3::zeros(); LEGS];
        let mut platform = [Vec3::zeros(); LEGS];
        for (i, (lower_deg, upper_deg)) in EDGES_DEG.into_iter().enumerate() {
            let from = corner(lower_deg, -0.5 * hc);
            let to = corner(upper_deg, 0.5 * hc);
            // The edge rises Hc over its length Hc sqrt(3): its direction's z is 1/sqrt(3).
            let along = (to - from) / (hc * libm::sqrtf(3.0));
            let at_height = |z: f32| from + along * ((z - from.z) / along.z);
            base[i] = at_height(self.base_height_mm);
            platform[i] = at_height(top_mm) - Vec3::new(0.0, 0.0, self.home_height_mm);
        }
        Ok((base, platform))
    }
}

fn finite(which: Dimension, value: f32) -> Result<f32, ConfigurationError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ConfigurationError::NonFinite { which })
    }
}

fn positive(which: Dimension, value_mm: f32) -> Result<f32, ConfigurationError> {
    finite(which, value_mm)?;
    if value_mm > 0.0 {
        Ok(value_mm)
    } else {
        Err(ConfigurationError::NotPositive { which, value_mm })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn general_configuration_puts_joints_on_their_circles() {
        let (b, p) = GeneralConfiguration::SIMSCAPE.anchors().unwrap();
        for i in 0..LEGS {
            assert!((b[i].xy().norm() - 115.0).abs() < 1e-4 && b[i].z == 15.0);
            assert!((p[i].xy().norm() - 90.0).abs() < 1e-4 && p[i].z == -15.0);
        }
        let mut bad = GeneralConfiguration::SIMSCAPE;
        bad.platform_angles_deg[3] = f32::NAN;
        assert_eq!(
            bad.anchors(),
            Err(ConfigurationError::NonFinite {
                which: Dimension::Angle { leg: 4 }
            })
        );
    }

    #[test]
    fn cubic_joints_are_at_the_heights_asked_for() {
        let cube = CubicConfiguration::SIMSCAPE;
        let (b, p) = cube.anchors().unwrap();
        for i in 0..LEGS {
            assert!((b[i].z - 15.0).abs() < 1e-4, "{}", b[i].z);
            assert!((p[i].z + 15.0).abs() < 1e-4, "{}", p[i].z);
        }
        let flat = CubicConfiguration {
            base_height_mm: 80.0,
            ..cube
        };
        assert!(matches!(
            flat.anchors(),
            Err(ConfigurationError::JointsNotBelow { .. })
        ));
    }

    #[test]
    fn centre_is_checked() {
        assert!(check_centre(Vec3::new(0.0, 0.0, -40.0)).is_ok());
        assert!(check_centre(Vec3::new(f32::NAN, 0.0, 0.0)).is_err());
        assert!(check_centre(Vec3::new(0.0, 2e4, 0.0)).is_err());
    }
}
