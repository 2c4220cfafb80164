//! The platform pose: a translation in mm and ZYX Euler angles in radians.
//!
//! `z_mm` is measured from the home height `h0`, so [`Pose::HOME`] is all zeros. The rotation is
//! `R = Rz(yaw) * Ry(pitch) * Rx(roll)` (eq. 1 of "The Mathematics of the Stewart Platform"): yaw
//! about z, then pitch about the new y, then roll about the new x.

use crate::fixed::{mul_rot, MAX_ROTATION_ENTRY};
use crate::math::{Math, Real};
use crate::types::Mat3;

/// A platform pose relative to home.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose {
    /// Translation along the base x axis, mm.
    pub x_mm: f32,
    /// Translation along the base y axis, mm.
    pub y_mm: f32,
    /// Translation along the base z axis, mm, measured from the home height `h0`.
    pub z_mm: f32,
    /// Rotation about x (phi), radians.
    pub roll_rad: f32,
    /// Rotation about y (theta), radians.
    pub pitch_rad: f32,
    /// Rotation about z (psi), radians.
    pub yaw_rad: f32,
}

/// One of the six pose coordinates, for error messages and per-axis commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// Translation along x.
    X,
    /// Translation along y.
    Y,
    /// Translation along z.
    Z,
    /// Rotation about x.
    Roll,
    /// Rotation about y.
    Pitch,
    /// Rotation about z.
    Yaw,
}

impl Axis {
    /// All axes in pose order.
    pub const ALL: [Axis; 6] = [
        Axis::X,
        Axis::Y,
        Axis::Z,
        Axis::Roll,
        Axis::Pitch,
        Axis::Yaw,
    ];

    /// The axis name users type (`x`, `y`, `z`, `roll`, `pitch`, `yaw`).
    pub const fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Z => "z",
            Axis::Roll => "roll",
            Axis::Pitch => "pitch",
            Axis::Yaw => "yaw",
        }
    }

    /// True for the three rotations.
    pub const fn is_angle(self) -> bool {
        matches!(self, Axis::Roll | Axis::Pitch | Axis::Yaw)
    }
}

impl Pose {
    /// The home pose: platform level and centred, at height `h0`.
    pub const HOME: Pose = Pose {
        x_mm: 0.0,
        y_mm: 0.0,
        z_mm: 0.0,
        roll_rad: 0.0,
        pitch_rad: 0.0,
        yaw_rad: 0.0,
    };

    /// A pose from millimetres and degrees (the units users type).
    pub fn from_degrees(
        x_mm: f32,
        y_mm: f32,
        z_mm: f32,
        roll_deg: f32,
        pitch_deg: f32,
        yaw_deg: f32,
    ) -> Pose {
        Pose {
            x_mm,
            y_mm,
            z_mm,
            roll_rad: roll_deg.to_radians(),
            pitch_rad: pitch_deg.to_radians(),
            yaw_rad: yaw_deg.to_radians(),
        }
    }

    /// The six coordinates in pose order (mm, mm, mm, rad, rad, rad).
    pub const fn to_array(&self) -> [f32; 6] {
        [
            self.x_mm,
            self.y_mm,
            self.z_mm,
            self.roll_rad,
            self.pitch_rad,
            self.yaw_rad,
        ]
    }

    /// A pose from six coordinates in pose order (mm, mm, mm, rad, rad, rad).
    pub const fn from_array(v: [f32; 6]) -> Pose {
        Pose {
            x_mm: v[0],
            y_mm: v[1],
            z_mm: v[2],
            roll_rad: v[3],
            pitch_rad: v[4],
            yaw_rad: v[5],
        }
    }

    /// One coordinate (mm or rad).
    pub const fn get(&self, axis: Axis) -> f32 {
        self.to_array()[axis as usize]
    }

    /// Sets one coordinate (mm or rad).
    pub fn set(&mut self, axis: Axis, value: f32) {
        let mut v = self.to_array();
        v[axis as usize] = value;
        *self = Pose::from_array(v);
    }

    /// The first coordinate that is NaN or infinite, if any.
    pub fn first_non_finite(&self) -> Option<Axis> {
        Axis::ALL.into_iter().find(|&a| !self.get(a).is_finite())
    }

    /// The rotation matrix `R = Rz(yaw) Ry(pitch) Rx(roll)`, written out as in eq. 1 of "The
    /// Mathematics of the Stewart Platform".
    /// Angles must be finite; keep them within +-2*pi (the boot ROM's sin/cos need |x| < 128).
    pub fn rotation<M: Math>(&self) -> Mat3 {
        self.rotation_columns::<M>(true)
    }

    /// [`Pose::rotation`], but with `third_column` false the third column is left zero (and its
    /// five multiplications and two additions are not done): the IK of a platform whose joints
    /// all have `z = 0` never uses it. Always inlined: in the IK's hot path that saves about 50
    /// cycles per pose on the RP2040 (measured with `./dev bench`).
    #[inline(always)]
    pub(crate) fn rotation_columns<M: Math>(&self, third_column: bool) -> Mat3 {
        let sin_cos = |x: f32| {
            let (s, c) = M::sin_cos(x);
            (Real::<M>::new(s), Real::<M>::new(c))
        };
        let (s_phi, c_phi) = sin_cos(self.roll_rad);
        let (s_theta, c_theta) = sin_cos(self.pitch_rad);
        let (s_psi, c_psi) = sin_cos(self.yaw_rad);
        // Shared products, so each entry costs at most two multiplications.
        let (cs, ss) = (c_psi * s_theta, s_psi * s_theta);
        let (r02, r12, r22) = if third_column {
            (
                (s_psi * s_phi + cs * c_phi).0,
                (ss * c_phi - c_psi * s_phi).0,
                (c_theta * c_phi).0,
            )
        } else {
            (0.0, 0.0, 0.0)
        };
        Mat3::new(
            (c_psi * c_theta).0,
            (cs * s_phi - s_psi * c_phi).0,
            r02,
            (s_psi * c_theta).0,
            (c_psi * c_phi + ss * s_phi).0,
            r12,
            -s_theta.0,
            (c_theta * s_phi).0,
            r22,
        )
    }

    /// [`Pose::rotation`] in fixed point, entries in steps of 2^-30 (eq. 1, the same symbols),
    /// from `M`'s fixed-point sines and cosines ([`Math::sin_cos_fixed`]), or `None` if one of
    /// them is beyond `fixed::MAX_ROTATION_ENTRY` (no sine of any usable library is). Each
    /// product is rounded to nearest (`fixed::mul_rot`, 32-bit products), so an entry is within
    /// about one step of its sines' exact one; `c_psi s_theta` and `s_psi s_theta`, each shared
    /// by two entries, are rounded first. (The sums wrap rather than panic: only sines whose
    /// `sin^2 + cos^2` is far from 1 could pass 2^31, and the IK bounds every entry after.)
    /// With `third_column` false that column is left zero, as in [`Pose::rotation_columns`].
    /// The angles must be finite.
    #[inline(always)]
    pub(crate) fn rotation_fixed<M: Math>(&self, third_column: bool) -> Option<[[i32; 3]; 3]> {
        let (s_phi, c_phi) = M::sin_cos_fixed(self.roll_rad);
        let (s_theta, c_theta) = M::sin_cos_fixed(self.pitch_rad);
        let (s_psi, c_psi) = M::sin_cos_fixed(self.yaw_rad);
        let bound = MAX_ROTATION_ENTRY as u32;
        let sines = [s_phi, c_phi, s_theta, c_theta, s_psi, c_psi];
        if sines.iter().any(|v| v.unsigned_abs() >= bound) {
            return None;
        }
        let cs = mul_rot(c_psi, s_theta);
        let ss = mul_rot(s_psi, s_theta);
        let (r02, r12, r22) = if third_column {
            (
                mul_rot(s_psi, s_phi).wrapping_add(mul_rot(cs, c_phi)),
                mul_rot(ss, c_phi).wrapping_sub(mul_rot(c_psi, s_phi)),
                mul_rot(c_theta, c_phi),
            )
        } else {
            (0, 0, 0)
        };
        Some([
            [
                mul_rot(c_psi, c_theta),
                mul_rot(cs, s_phi).wrapping_sub(mul_rot(s_psi, c_phi)),
                r02,
            ],
            [
                mul_rot(s_psi, c_theta),
                mul_rot(c_psi, c_phi).wrapping_add(mul_rot(ss, s_phi)),
                r12,
            ],
            [-s_theta, mul_rot(c_theta, s_phi), r22],
        ])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;
    use crate::types::Vec3;

    fn rx(a: f32) -> Mat3 {
        Mat3::new(1.0, 0.0, 0.0, 0.0, a.cos(), -a.sin(), 0.0, a.sin(), a.cos())
    }
    fn ry(a: f32) -> Mat3 {
        Mat3::new(a.cos(), 0.0, a.sin(), 0.0, 1.0, 0.0, -a.sin(), 0.0, a.cos())
    }
    fn rz(a: f32) -> Mat3 {
        Mat3::new(a.cos(), -a.sin(), 0.0, a.sin(), a.cos(), 0.0, 0.0, 0.0, 1.0)
    }

    #[test]
    fn rotation_is_the_product_of_the_three_elementary_rotations() {
        let pose = Pose::from_degrees(0.0, 0.0, 0.0, 10.0, -20.0, 35.0);
        let expected = rz(pose.yaw_rad) * ry(pose.pitch_rad) * rx(pose.roll_rad);
        let r = pose.rotation::<Libm>();
        assert!((r - expected).abs().max() < 1e-6, "{r} vs {expected}");
    }

    #[test]
    fn fixed_point_rotation_matches_the_float_one() {
        for (roll, pitch, yaw) in [(10.0, -20.0, 35.0), (-179.0, 90.0, 180.0), (0.0, 0.0, 0.0)] {
            let pose = Pose::from_degrees(0.0, 0.0, 0.0, roll, pitch, yaw);
            let expected = pose.rotation::<Libm>();
            let r = pose
                .rotation_fixed::<Libm>(true)
                .expect("within the bounds");
            for (k, row) in r.iter().enumerate() {
                for (j, &entry) in row.iter().enumerate() {
                    let entry = f64::from(entry) / f64::from(1u32 << 30);
                    assert!(
                        (entry - f64::from(expected[(k, j)])).abs() < 1e-6,
                        "({k}, {j})"
                    );
                }
            }
            assert_eq!(pose.rotation_fixed::<Libm>(false).map(|r| r[1][2]), Some(0));
        }
    }

    #[test]
    fn yaw_turns_x_towards_y() {
        let r = Pose::from_degrees(0.0, 0.0, 0.0, 0.0, 0.0, 90.0).rotation::<Libm>();
        let v = r * Vec3::new(1.0, 0.0, 0.0);
        assert!((v - Vec3::new(0.0, 1.0, 0.0)).norm() < 1e-6);
    }

    #[test]
    fn get_set_roundtrip_every_axis() {
        let mut p = Pose::HOME;
        for (i, a) in Axis::ALL.into_iter().enumerate() {
            p.set(a, i as f32 + 1.0);
        }
        assert_eq!(p.to_array(), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        p.set(Axis::Pitch, f32::NAN);
        assert_eq!(p.first_non_finite(), Some(Axis::Pitch));
    }
}
