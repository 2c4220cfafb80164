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
    /// from `M`'s fixed-point sines and cosines ([`Math::sin_cos_fixed`]), every entry below
    /// `fixed::MAX_ROTATION_ENTRY` (1 + 2^-4) in magnitude, or `None`: a sine or cosine at or
    /// beyond [`MAX_SINE`] (1 + 2^-6: no sine of any usable library is), or, with sines whose
    /// `sin^2 + cos^2` is far from 1, an entry beyond that bound. Each product is rounded to
    /// nearest (`fixed::mul_rot`, 32-bit products), so an entry is within about one step of its
    /// sines' exact one; `c_psi s_theta` and `s_psi s_theta`, each shared by two entries, are
    /// rounded first. An entry that is one product (or a sine) is within the bound by the
    /// sines' (`(1 + 2^-6)^2 < 1 + 2^-4`, the rounding included): only the entries that are
    /// sums of two products are checked. (The sums wrap rather than panic: each product is
    /// below 1.05 in magnitude, so a wrapped sum is far beyond the bound too.)
    /// With `third_column` false that column is left zero, as in [`Pose::rotation_columns`].
    /// The angles must be finite.
    #[inline(always)]
    pub(crate) fn rotation_fixed<M: Math>(&self, third_column: bool) -> Option<[[i32; 3]; 3]> {
        let (s_phi, c_phi) = M::sin_cos_fixed(self.roll_rad);
        let (s_theta, c_theta) = M::sin_cos_fixed(self.pitch_rad);
        let (s_psi, c_psi) = M::sin_cos_fixed(self.yaw_rad);
        let sines = [s_phi, c_phi, s_theta, c_theta, s_psi, c_psi];
        if !sines.iter().all(|&v| below_bound(v, MAX_SINE)) {
            return None;
        }
        let cs = mul_rot(c_psi, s_theta);
        let ss = mul_rot(s_psi, s_theta);
        let r01 = mul_rot(cs, s_phi).wrapping_sub(mul_rot(s_psi, c_phi));
        let r11 = mul_rot(c_psi, c_phi).wrapping_add(mul_rot(ss, s_phi));
        let (r02, r12, r22) = if third_column {
            (
                mul_rot(s_psi, s_phi).wrapping_add(mul_rot(cs, c_phi)),
                mul_rot(ss, c_phi).wrapping_sub(mul_rot(c_psi, s_phi)),
                mul_rot(c_theta, c_phi),
            )
        } else {
            (0, 0, 0)
        };
        let bound = MAX_ROTATION_ENTRY as u32;
        if ![r01, r11, r02, r12].iter().all(|&v| below_bound(v, bound)) {
            return None;
        }
        Some([
            [mul_rot(c_psi, c_theta), r01, r02],
            [mul_rot(s_psi, c_theta), r11, r12],
            [-s_theta, mul_rot(c_theta, s_phi), r22],
        ])
    }
}

/// Bound (exclusive) on the magnitude of the fixed-point sines and cosines
/// [`Pose::rotation_fixed`] takes, in steps of 2^-30: 1 + 2^-6. A product of two, rounded to
/// nearest, is then within `(1 + 2^-6)^2 + 2^-31 < 1 + 2^-4` (`fixed::MAX_ROTATION_ENTRY`).
pub(crate) const MAX_SINE: u32 = (1 << 30) + (1 << 24);

/// `|v| < bound` (`0 < bound <= 2^31`) in one addition and one unsigned comparison:
/// `-bound < v < bound` exactly when `v + bound - 1` is in `[0, 2 bound - 2]`.
#[inline(always)]
fn below_bound(v: i32, bound: u32) -> bool {
    (v as u32).wrapping_add(bound - 1) <= 2 * (bound - 1)
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
    fn rotation_entries_stay_within_the_bound() {
        // Products of sines at the bound stay below `fixed::MAX_ROTATION_ENTRY` (the reason
        // only the sums are checked), and `below_bound` is `|v| < bound` exactly.
        let largest = (MAX_SINE - 1) as i32;
        for a in [largest, -largest] {
            for b in [largest, -largest] {
                let p = mul_rot(a, b);
                assert!(
                    p.unsigned_abs() < MAX_ROTATION_ENTRY as u32,
                    "{a} * {b}: {p}"
                );
                // A product of a product and a sine, as in the sums' terms: below 1.05.
                let q = mul_rot(p, b);
                assert!(
                    f64::from(q.unsigned_abs()) < 1.05 * f64::from(1u32 << 30),
                    "{q}"
                );
            }
        }
        for bound in [MAX_SINE, MAX_ROTATION_ENTRY as u32, 1, 1 << 31] {
            for v in [
                0,
                1,
                -1,
                i32::MAX,
                i32::MIN,
                (bound - 1) as i32,
                bound as i32,
            ] {
                for v in [v, v.wrapping_neg(), v.wrapping_add(1), v.wrapping_sub(1)] {
                    assert_eq!(
                        below_bound(v, bound),
                        v.unsigned_abs() < bound,
                        "{v} {bound}"
                    );
                }
            }
        }
    }

    /// A `Math` whose fixed-point sines are `libm`'s times a factor: sines that are no sines.
    struct Scaled<const PERCENT: i32>;

    impl<const PERCENT: i32> Math for Scaled<PERCENT> {
        crate::math::forward_math!(Libm => sin_cos, sqrt, atan2);
        fn sin_cos_fixed(x_rad: f32) -> (i32, i32) {
            let (s, c) = crate::fixed::sin_cos::sin_cos(x_rad);
            let scale = |v: i32| (i64::from(v) * i64::from(PERCENT) / 100) as i32;
            (scale(s), scale(c))
        }
    }

    /// A `Math` whose fixed-point sine and cosine are both 1 at every angle: no sines at all,
    /// within their bound.
    struct Ones;

    impl Math for Ones {
        crate::math::forward_math!(Libm => sin_cos, sqrt, atan2);
        fn sin_cos_fixed(_: f32) -> (i32, i32) {
            (1 << 30, 1 << 30)
        }
    }

    #[test]
    fn rotation_from_sines_that_are_no_sines_is_refused_or_bounded() {
        // Sines 1 % too large (within 1 + 2^-6): every entry within the bound of `fixed`;
        // 2 % too large: refused where one passes 1 + 2^-6, else within the bound; sines and
        // cosines all 1: an entry of 2 (`r11`), refused.
        let bounded = |r: [[i32; 3]; 3]| {
            r.iter()
                .flatten()
                .all(|v| v.unsigned_abs() < MAX_ROTATION_ENTRY as u32)
        };
        let mut refused = 0;
        for i in 0..400 {
            let a = (i as f32 / 400.0 - 0.5) * 2.0 * core::f32::consts::PI;
            for third_column in [false, true] {
                let pose = Pose::from_array([0.0, 0.0, 0.0, a, 0.6 * a, -0.8 * a]);
                let r = pose.rotation_fixed::<Scaled<101>>(third_column);
                assert!(bounded(r.expect("within the bounds")));
                match pose.rotation_fixed::<Scaled<102>>(third_column) {
                    Some(r) => assert!(bounded(r)),
                    None => refused += 1,
                }
                assert_eq!(pose.rotation_fixed::<Ones>(third_column), None);
            }
        }
        assert!((100..800).contains(&refused), "{refused}");
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
