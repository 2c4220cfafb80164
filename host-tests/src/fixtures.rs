//! Geometries, a seeded random number generator and pose samplers shared by the tests.

use kinematics_core::configuration::{CubicConfiguration, GeneralConfiguration};
use kinematics_core::geometry::{CircularLayout, PairedLayout};
use kinematics_core::legs::Struts;
use kinematics_core::{ik, Geometry, Pose, Vec3};

/// The angles of the general circular configuration of the Stewart platform Simscape model
/// documentation, degrees: servo shafts...
pub const SIMSCAPE_BASE_DEG: [f32; 6] = [-10.0, 10.0, 110.0, 130.0, 230.0, 250.0];
/// ...and platform joints.
pub const SIMSCAPE_PLATFORM_DEG: [f32; 6] = [-50.0, 50.0, 70.0, 170.0, 190.0, -70.0];

/// The Simscape documentation's angles with tangential arms. `outwards` points each arm away
/// from its pair's centre (towards its own platform joint, like [`PairedLayout`]); otherwise
/// towards it.
pub fn simscape_layout(outwards: bool) -> CircularLayout {
    let turn = if outwards { 90.0 } else { -90.0 };
    let beta_deg = core::array::from_fn(|i| {
        // Odd servos (index 0, 2, 4) are the clockwise member of their pair.
        let sense = if i % 2 == 0 { -1.0 } else { 1.0 };
        SIMSCAPE_BASE_DEG[i] + sense * turn
    });
    CircularLayout {
        base_radius_mm: 75.0,
        platform_radius_mm: 60.0,
        base_angles_deg: SIMSCAPE_BASE_DEG,
        platform_angles_deg: SIMSCAPE_PLATFORM_DEG,
        beta_deg,
        arm_mm: 20.0,
        rod_mm: 120.0,
    }
}

/// A named test geometry with the pose box it is exercised over.
#[derive(Debug, Clone)]
pub struct Case {
    /// What it is.
    pub name: &'static str,
    /// The geometry.
    pub geometry: Geometry,
    /// Half-widths of the pose box: mm for x, y, z and degrees for roll, pitch, yaw.
    pub range: [f64; 6],
    /// Largest arm-angle error (core vs f64 reference) accepted within the servo travel,
    /// degrees. See `tests/agreement.rs` for the measured values.
    pub angle_tol_deg: f64,
}

/// Arm-angle tolerance for geometries with every joint in its frame's z = 0 plane, degrees.
/// f32 holds joint coordinates of 100-200 mm to half an ulp (4-8 nm); a 15-30 mm arm turns
/// one such ulp into 2-4e-5 degrees, and the IK rounds a handful of such quantities. Measured
/// maxima are 5-9e-5 degrees.
pub const TIGHT_DEG: f64 = 1.0e-4;

/// The geometries the agreement tests run on: the default, other paired layouts, the Simscape
/// documentation's circular layout both ways round, and an explicit build with joints off the
/// z = 0 planes.
pub fn cases() -> Vec<Case> {
    let realistic = [15.0, 15.0, 12.0, 8.0, 8.0, 15.0];
    let paired = |base_radius_mm,
                  base_half_angle_deg,
                  platform_radius_mm,
                  platform_half_angle_deg,
                  arm_mm,
                  rod_mm| {
        PairedLayout {
            base_radius_mm,
            base_half_angle_deg,
            platform_radius_mm,
            platform_half_angle_deg,
            arm_mm,
            rod_mm,
        }
        .build()
        .expect("test layout is valid")
    };
    let mut lifted = PairedLayout::default().circular().legs();
    for leg in lifted.iter_mut() {
        leg.base_mm.z += 8.0;
        leg.platform_mm.z -= 5.0;
    }
    vec![
        Case {
            name: "default PairedLayout",
            geometry: Geometry::default(),
            range: realistic,
            angle_tol_deg: TIGHT_DEG,
        },
        Case {
            name: "PairedLayout 90/12 70/8 a25 s150",
            geometry: paired(90.0, 12.0, 70.0, 8.0, 25.0, 150.0),
            range: realistic,
            angle_tol_deg: TIGHT_DEG,
        },
        Case {
            name: "PairedLayout 120/15 100/25 a30 s200",
            geometry: paired(120.0, 15.0, 100.0, 25.0, 30.0, 200.0),
            range: [25.0, 25.0, 20.0, 8.0, 8.0, 15.0],
            angle_tol_deg: TIGHT_DEG,
        },
        Case {
            name: "PairedLayout 50/30 45/25 a15 s80 (small)",
            geometry: paired(50.0, 30.0, 45.0, 25.0, 15.0, 80.0),
            range: [10.0, 10.0, 8.0, 8.0, 8.0, 15.0],
            angle_tol_deg: TIGHT_DEG,
        },
        Case {
            name: "Simscape circular, arms outwards",
            geometry: simscape_layout(true).build().expect("valid"),
            range: realistic,
            angle_tol_deg: TIGHT_DEG,
        },
        Case {
            name: "Simscape circular, arms inwards",
            geometry: simscape_layout(false).build().expect("valid"),
            range: realistic,
            angle_tol_deg: TIGHT_DEG,
        },
        Case {
            name: "default legs, shafts at z=+8, joints at z=-5",
            geometry: Geometry::new(lifted, 20.0, 120.0).expect("valid"),
            range: realistic,
            // Here the core's h0 (a plain f32 mean of six heights near 131 mm) is 1.9e-5 mm
            // (1.3 ulp) off the exact value, which alone shifts every angle by up to 8e-5
            // degrees; with the core's own h0 the reference agrees to 8.2e-5 degrees.
            angle_tol_deg: 2.0e-4,
        },
    ]
}

/// The IK of a test geometry rotating about `centre_mm` (platform frame); both must be valid.
pub fn solver_about(geometry: Geometry, centre_mm: Vec3) -> ik::Solver {
    ik::Solver::new(geometry)
        .expect("a test geometry builds")
        .with_rotation_centre_mm(centre_mm)
        .expect("a valid rotation centre")
}

/// A small deterministic generator (xorshift64*), so every failure reproduces.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed (any value; zero is replaced).
    pub fn new(seed: u64) -> Rng {
        Rng(seed.max(1))
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[-half, half)`.
    pub fn symmetric(&mut self, half: f64) -> f64 {
        half * (2.0 * self.unit() - 1.0)
    }

    /// A vector uniformly in the box `[-half, half)` per coordinate, as the core's f32 vector
    /// (x drawn first).
    pub fn vec3(&mut self, half: [f64; 3]) -> Vec3 {
        let [x, y, z] = half.map(|h| self.symmetric(h) as f32);
        Vec3::new(x, y, z)
    }

    /// A pose uniformly in the box `range` (mm, degrees), as the core's f32 pose.
    pub fn pose(&mut self, range: &[f64; 6]) -> Pose {
        let v: [f64; 6] = core::array::from_fn(|i| self.symmetric(range[i]));
        Pose::from_degrees(
            v[0] as f32,
            v[1] as f32,
            v[2] as f32,
            v[3] as f32,
            v[4] as f32,
            v[5] as f32,
        )
    }
}

/// Rotation centres the tests try (platform frame, mm): the platform frame's origin, the
/// Simscape documentation's default {B} 50 mm above it, a point below and off-axis (a motion
/// platform's pivot under a seat), and one far below.
pub const CENTRES_MM: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [0.0, 0.0, 50.0],
    [12.0, -7.5, -35.0],
    [0.0, 0.0, -118.0],
];

/// A named strut platform with the pose box it is exercised over.
#[derive(Debug, Clone)]
pub struct StrutCase {
    /// What it is.
    pub name: &'static str,
    /// The struts.
    pub struts: Struts,
    /// Half-widths of the pose box: mm for x, y, z and degrees for roll, pitch, yaw.
    pub range: [f64; 6],
}

/// The strut platforms the tests run on: the Simscape documentation's general configuration
/// (its 90 mm height), the same with its default frame {B} 50 mm above the platform, its cubic
/// configuration turning about the cube's centre, and the default servo build's anchors as
/// struts.
pub fn strut_cases() -> Vec<StrutCase> {
    let general = Struts::from_general(&GeneralConfiguration::SIMSCAPE, 90.0).expect("valid");
    let mut general_b = general;
    general_b
        .set_rotation_centre_mm(Vec3::new(0.0, 0.0, 50.0))
        .expect("valid");
    let cube = CubicConfiguration::SIMSCAPE;
    let mut cubic = Struts::from_cubic(&cube).expect("valid");
    cubic
        .set_rotation_centre_mm(cube.cube_centre_mm())
        .expect("valid");
    let g = Geometry::default();
    let legs = g.legs();
    let paired = Struts::new(
        core::array::from_fn(|i| legs[i].base_mm),
        core::array::from_fn(|i| legs[i].platform_mm),
        g.home_height_mm(),
    )
    .expect("valid");
    let range = [10.0, 10.0, 8.0, 6.0, 6.0, 10.0];
    vec![
        StrutCase {
            name: "Simscape general, H 90",
            struts: general,
            range,
        },
        StrutCase {
            name: "Simscape general, centre at {B} (+50)",
            struts: general_b,
            range,
        },
        StrutCase {
            name: "Simscape cubic, centre at the cube's",
            struts: cubic,
            range,
        },
        StrutCase {
            name: "default servo build's anchors as struts",
            struts: paired,
            range: [15.0, 15.0, 12.0, 8.0, 8.0, 15.0],
        },
    ]
}
