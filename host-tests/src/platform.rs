//! An f64 reference for the kinematics beyond the servo IK (rotation centre, struts, Jacobian,
//! forward kinematics, statics), written from the documents and NOT from `kinematics-core`.
//!
//! It shares only inputs with the core: anchor coordinates, `h0`, the rotation centre, the
//! servo build (widened exactly from the core's `f32`). Everything else is computed here, in
//! `f64`, by other means:
//! - the pose with a rotation centre is a chain of homogeneous transforms, as the Stewart
//!   platform Simscape model documentation chains its frames {F} -> {A} -> {B} -> {M}
//!   (`displayArchitecture`): base -> {A} (a translation to where the centre is at home),
//!   {A} -> {B} (the pose: translation, then `Rz Ry Rx`), {B} -> platform (a translation by
//!   minus the centre); not the core's `C + R (p - c)`;
//! - strut lengths are distances between the transformed points; servo arm angles come from
//!   the numeric solver of [`crate::reference`];
//! - derivatives (Jacobians, rates, stiffness) are central finite differences of those;
//! - forward kinematics is Newton's method on finite-difference Jacobians with an `f64`
//!   Gaussian elimination of its own;
//! - small motions ("twists") are applied as a translation of the centre and a rotation
//!   `exp([dw]) R` about it, built from an axis and an angle.

// Index loops read like the textbook algorithms they are.
#![allow(clippy::needless_range_loop)]

use crate::reference::{mat_mul, mat_vec, solve_leg, RefLeg, RefPose, M3, V3};
use kinematics_core::configuration::Anchors;
use kinematics_core::ik::Solver;
use kinematics_core::LEGS;

/// A 4x4 homogeneous transform, row-major.
pub type H4 = [[f64; 4]; 4];

/// The transform with rotation `r` and translation `t`.
pub fn homogeneous(r: &M3, t: V3) -> H4 {
    let mut h = [[0.0; 4]; 4];
    for i in 0..3 {
        for j in 0..3 {
            h[i][j] = r[i][j];
        }
        h[i][3] = t[i];
    }
    h[3][3] = 1.0;
    h
}

/// `a b`.
pub fn compose(a: &H4, b: &H4) -> H4 {
    let mut out = [[0.0; 4]; 4];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, cell) in row.iter_mut().enumerate() {
            *cell = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    out
}

/// `h (p, 1)`, the point part.
pub fn apply(h: &H4, p: V3) -> V3 {
    core::array::from_fn(|i| h[i][0] * p[0] + h[i][1] * p[1] + h[i][2] * p[2] + h[i][3])
}

const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// The rotation by `|v|` about the axis `v`: the matrix exponential of `[v]x`, summed as a
/// power series (no Rodrigues formula).
pub fn exp_rotation(v: V3) -> M3 {
    let k: M3 = [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]];
    let mut sum = IDENTITY;
    let mut term = IDENTITY;
    for n in 1..40 {
        term = mat_mul(&term, &k);
        for row in term.iter_mut() {
            for cell in row.iter_mut() {
                *cell /= n as f64;
            }
        }
        for i in 0..3 {
            for j in 0..3 {
                sum[i][j] += term[i][j];
            }
        }
    }
    sum
}

/// A pose moved by a small motion `dx = (dv, dw)` of the rotation centre: translation `+ dv`,
/// rotation `exp([dw]) R` (about the centre, base axes). Pitch stays within +-90 degrees.
pub fn moved(pose: &RefPose, dx: &[f64; 6]) -> RefPose {
    let r = mat_mul(&exp_rotation([dx[3], dx[4], dx[5]]), &pose.rotation());
    let (roll, pitch, yaw) = RefPose::angles_of(&r);
    RefPose {
        x: pose.x + dx[0],
        y: pose.y + dx[1],
        z: pose.z + dx[2],
        roll,
        pitch,
        yaw,
    }
}

/// The anchors of a platform, in f64.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefAnchors {
    /// Lower anchors (base frame), mm.
    pub base: [V3; LEGS],
    /// Upper anchors (platform frame), mm.
    pub platform: [V3; LEGS],
    /// Home height, mm.
    pub h0: f64,
    /// Rotation centre (platform frame), mm.
    pub centre: V3,
}

fn widen(v: &kinematics_core::Vec3) -> V3 {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}

impl RefAnchors {
    /// The exact f64 values of a core's anchors.
    pub fn from_core(a: &Anchors) -> RefAnchors {
        RefAnchors {
            base: core::array::from_fn(|i| widen(&a.base_mm[i])),
            platform: core::array::from_fn(|i| widen(&a.platform_mm[i])),
            h0: f64::from(a.home_height_mm),
            centre: widen(&a.rotation_centre_mm),
        }
    }

    /// base <- platform: base <- {A} (to the centre's home position), {A} <- {B} (the pose),
    /// {B} <- platform (the centre is at `c` in the platform frame).
    pub fn transform(&self, pose: &RefPose) -> H4 {
        let c = self.centre;
        let base_a = homogeneous(&IDENTITY, [c[0], c[1], self.h0 + c[2]]);
        let a_b = homogeneous(&pose.rotation(), [pose.x, pose.y, pose.z]);
        let b_platform = homogeneous(&IDENTITY, [-c[0], -c[1], -c[2]]);
        compose(&compose(&base_a, &a_b), &b_platform)
    }

    /// The upper anchors in the base frame, mm.
    pub fn joints(&self, pose: &RefPose) -> [V3; LEGS] {
        let h = self.transform(pose);
        core::array::from_fn(|i| apply(&h, self.platform[i]))
    }

    /// Where the rotation centre is, base frame, mm.
    pub fn centre_position(&self, pose: &RefPose) -> V3 {
        apply(&self.transform(pose), self.centre)
    }

    /// Strut lengths, mm.
    pub fn strut_lengths(&self, pose: &RefPose) -> [f64; LEGS] {
        let q = self.joints(pose);
        core::array::from_fn(|i| {
            let d: V3 = core::array::from_fn(|k| q[i][k] - self.base[i][k]);
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        })
    }
}

/// A servo platform in f64: anchors, arms, rods, home arm angles.
#[derive(Debug, Clone, PartialEq)]
pub struct RefArms {
    /// The anchors (servo shafts, platform joints, h0, centre).
    pub anchors: RefAnchors,
    /// The legs (shaft, joint, arm plane).
    pub legs: [RefLeg; LEGS],
    /// Arm length, mm.
    pub arm: f64,
    /// Rod length, mm.
    pub rod: f64,
    /// Home arm angles (numeric, at the home pose), rad.
    pub alpha0: [f64; LEGS],
}

impl RefArms {
    /// The reference of a core solver (its geometry, `h0` and rotation centre as inputs).
    pub fn from_solver(solver: &Solver) -> RefArms {
        let g = solver.geometry();
        let anchors = RefAnchors::from_core(&solver.anchors());
        let legs = core::array::from_fn(|i| RefLeg::from_core(g.leg(i)));
        let (arm, rod) = (f64::from(g.arm_mm()), f64::from(g.rod_mm()));
        let home = anchors.joints(&RefPose::default());
        let alpha0 = core::array::from_fn(|i| {
            solve_leg(&legs[i], arm, rod, home[i], 0.0)
                .expect("home is reachable")
                .alpha
        });
        RefArms {
            anchors,
            legs,
            arm,
            rod,
            alpha0,
        }
    }

    /// Arm angles (numeric root of the rod closure, near `alpha0`), rad; `None` if a leg
    /// cannot reach.
    pub fn arm_angles(&self, pose: &RefPose) -> Option<[f64; LEGS]> {
        let q = self.anchors.joints(pose);
        let mut out = [0.0; LEGS];
        for i in 0..LEGS {
            out[i] = solve_leg(&self.legs[i], self.arm, self.rod, q[i], self.alpha0[i])
                .ok()?
                .alpha;
        }
        Some(out)
    }

    /// Each leg's workspace margin at `pose`, mm (negative: out of reach); see
    /// [`crate::reference::ArmRoot::margin_mm`].
    pub fn margins_mm(&self, pose: &RefPose) -> [f64; LEGS] {
        let q = self.anchors.joints(pose);
        core::array::from_fn(|i| {
            match solve_leg(&self.legs[i], self.arm, self.rod, q[i], self.alpha0[i]) {
                Ok(root) => root.margin_mm,
                Err(u) => u.margin_mm,
            }
        })
    }
}

/// A 6x6 matrix, row-major.
pub type M6 = [[f64; 6]; 6];

/// The central finite-difference Jacobian of `f` at `pose` in twist coordinates (translation
/// of the centre in mm, rotation vector in rad): column `k` is
/// `(f(moved(+h e_k)) - f(moved(-h e_k))) / 2h`, `h` = `h_mm` or `h_rad`.
pub fn fd_jacobian(
    f: impl Fn(&RefPose) -> Option<[f64; LEGS]>,
    pose: &RefPose,
    h_mm: f64,
    h_rad: f64,
) -> Option<M6> {
    let mut j = [[0.0; 6]; 6];
    for k in 0..6 {
        let h = if k < 3 { h_mm } else { h_rad };
        let mut dx = [0.0; 6];
        dx[k] = h;
        let plus = f(&moved(pose, &dx))?;
        dx[k] = -h;
        let minus = f(&moved(pose, &dx))?;
        for i in 0..LEGS {
            j[i][k] = (plus[i] - minus[i]) / (2.0 * h);
        }
    }
    Some(j)
}

/// `x` with `a x = b`, by Gaussian elimination with partial pivoting; `None` if singular.
pub fn solve6(a: &M6, b: &[f64; 6]) -> Option<[f64; 6]> {
    let mut m = *a;
    let mut v = *b;
    for k in 0..6 {
        let p = (k..6).max_by(|&i, &j| m[i][k].abs().total_cmp(&m[j][k].abs()))?;
        if m[p][k].abs() < 1e-300 {
            return None;
        }
        m.swap(k, p);
        v.swap(k, p);
        for i in k + 1..6 {
            let f = m[i][k] / m[k][k];
            for j in k..6 {
                m[i][j] -= f * m[k][j];
            }
            v[i] -= f * v[k];
        }
    }
    let mut x = [0.0; 6];
    for i in (0..6).rev() {
        let s: f64 = (i + 1..6).map(|j| m[i][j] * x[j]).sum();
        x[i] = (v[i] - s) / m[i][i];
    }
    Some(x)
}

/// `a^T`.
pub fn transpose6(a: &M6) -> M6 {
    core::array::from_fn(|i| core::array::from_fn(|j| a[j][i]))
}

/// `a x`.
pub fn mul6(a: &M6, x: &[f64; 6]) -> [f64; 6] {
    core::array::from_fn(|i| (0..6).map(|k| a[i][k] * x[k]).sum())
}

/// Forward kinematics in f64: Newton's method on `f(pose) = target` with finite-difference
/// Jacobians, from `start`, to `|step| < 1e-10` (the numeric IK is good to about 1e-13);
/// a step that leaves the domain of `f` or does not reduce the largest residual is halved
/// (up to 30 times). `None` if it fails within 50 iterations.
pub fn newton_fk(
    f: impl Fn(&RefPose) -> Option<[f64; LEGS]>,
    target: &[f64; LEGS],
    start: &RefPose,
) -> Option<RefPose> {
    let largest = |values: &[f64; LEGS]| {
        (0..LEGS)
            .map(|i| (target[i] - values[i]).abs())
            .fold(0.0, f64::max)
    };
    let mut pose = *start;
    let mut values = f(&pose)?;
    for _ in 0..50 {
        let residual: [f64; 6] = core::array::from_fn(|i| target[i] - values[i]);
        let j = fd_jacobian(&f, &pose, 1e-4, 1e-6)?;
        let mut dx = solve6(&j, &residual)?;
        let mut accepted = None;
        for _ in 0..30 {
            let next = moved(&pose, &dx);
            match f(&next) {
                Some(v) if largest(&v) <= largest(&values) || largest(&v) < 1e-12 => {
                    accepted = Some((next, v));
                    break;
                }
                _ => dx = dx.map(|d| 0.5 * d),
            }
        }
        let (next, v) = accepted?;
        pose = next;
        values = v;
        if dx.iter().all(|d| d.abs() < 1e-10) {
            return Some(pose);
        }
    }
    None
}

/// The largest rotation angle between two poses' orientations, rad.
pub fn rotation_between(a: &RefPose, b: &RefPose) -> f64 {
    let r = mat_mul(&crate::reference::transpose(&a.rotation()), &b.rotation());
    let trace = r[0][0] + r[1][1] + r[2][2];
    ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos()
}

/// How far two poses' rotation centres are apart, mm.
pub fn translation_between(a: &RefPose, b: &RefPose) -> f64 {
    ((a.x - b.x).powi(2) + (a.y - b.y).powi(2) + (a.z - b.z).powi(2)).sqrt()
}

/// `r v` for a rotation given as a pose.
pub fn rotate(pose: &RefPose, v: V3) -> V3 {
    mat_vec(&pose.rotation(), v)
}
