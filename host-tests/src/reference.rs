//! An f64 reference for "The Mathematics of the Stewart Platform", written from the document
//! and NOT from `kinematics-core`'s code.
//!
//! What it shares with the core is only the inputs: build coordinates `b_i`, `p_i`, `beta_i`,
//! `a`, `s` (read from the core's public getters or from the same `Leg` values the core is
//! given), the pose (the core's `f32` values widened exactly to `f64`) and the servo settings.
//! Everything derived from them is computed here, in `f64`, by different means:
//!
//! - the rotation is the product of the three elementary matrices `Rz(psi) Ry(theta) Rx(phi)`
//!   (the document's, before it expands them into eq. 1);
//! - platform joints `q_i = T + R p_i` with `T = (x, y, h0 + z)` (eq. 2);
//! - the arm angle is found NUMERICALLY: the arm tip
//!   `A(alpha) = b + a (cos alpha cos beta, cos alpha sin beta, sin alpha)` (eq. 4-6) must be at
//!   rod length `s` from `q`, so we look for a zero of the closure function
//!   `g(alpha) = |q - A(alpha)|^2 - s^2` by sampling, golden-section search and bisection. No
//!   `asin`, `atan` or half-angle formula is involved; see [`solve_leg`] for how the branch is
//!   chosen;
//! - as a second, literal reference, eq. 9 itself: `alpha = asin(L / sqrt(M^2 + N^2)) -
//!   atan2(N, M)` ([`eq9_alpha`]), and eq. 10 / eq. 12 for `h0` and `alpha0`;
//! - pulse widths by eq. 13 / 14.

use kinematics_core::servo::{Direction, ServoConfig};
use kinematics_core::{Geometry, Leg, Pose, ServoSet, LEGS};

/// A 3-vector, mm.
pub type V3 = [f64; 3];
/// A 3x3 matrix, row-major: `m[row][column]`.
pub type M3 = [[f64; 3]; 3];

/// `u + v`.
pub fn add(u: V3, v: V3) -> V3 {
    [u[0] + v[0], u[1] + v[1], u[2] + v[2]]
}

/// `u - v`.
pub fn sub(u: V3, v: V3) -> V3 {
    [u[0] - v[0], u[1] - v[1], u[2] - v[2]]
}

/// `k u`.
pub fn scale(k: f64, u: V3) -> V3 {
    [k * u[0], k * u[1], k * u[2]]
}

/// `u . v`.
pub fn dot(u: V3, v: V3) -> f64 {
    u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
}

/// `|u|`.
pub fn norm(u: V3) -> f64 {
    dot(u, u).sqrt()
}

/// `m v`.
pub fn mat_vec(m: &M3, v: V3) -> V3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// `m n`.
pub fn mat_mul(m: &M3, n: &M3) -> M3 {
    let mut out = [[0.0; 3]; 3];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, cell) in row.iter_mut().enumerate() {
            *cell = (0..3).map(|k| m[r][k] * n[k][c]).sum();
        }
    }
    out
}

/// Transpose (the inverse of a rotation).
pub fn transpose(m: &M3) -> M3 {
    let mut out = [[0.0; 3]; 3];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, cell) in row.iter_mut().enumerate() {
            *cell = m[c][r];
        }
    }
    out
}

/// Elementary rotation about x by `phi` (roll), the document's `R_x`.
pub fn rot_x(phi: f64) -> M3 {
    let (s, c) = phi.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

/// Elementary rotation about y by `theta` (pitch), the document's `R_y`.
pub fn rot_y(theta: f64) -> M3 {
    let (s, c) = theta.sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

/// Elementary rotation about z by `psi` (yaw), the document's `R_z`.
pub fn rot_z(psi: f64) -> M3 {
    let (s, c) = psi.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// A pose in f64: mm and radians, `z` measured from the home height like the core's [`Pose`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RefPose {
    /// Translation along base x, mm.
    pub x: f64,
    /// Translation along base y, mm.
    pub y: f64,
    /// Translation along base z from the home height, mm.
    pub z: f64,
    /// Roll phi about x, rad.
    pub roll: f64,
    /// Pitch theta about y, rad.
    pub pitch: f64,
    /// Yaw psi about z, rad.
    pub yaw: f64,
}

impl RefPose {
    /// The exact f64 value of a core pose (no rounding: every f32 is an f64).
    pub fn from_core(p: &Pose) -> RefPose {
        RefPose {
            x: f64::from(p.x_mm),
            y: f64::from(p.y_mm),
            z: f64::from(p.z_mm),
            roll: f64::from(p.roll_rad),
            pitch: f64::from(p.pitch_rad),
            yaw: f64::from(p.yaw_rad),
        }
    }

    /// A pose from mm and degrees, converted in f64.
    pub fn from_degrees(x: f64, y: f64, z: f64, roll: f64, pitch: f64, yaw: f64) -> RefPose {
        RefPose {
            x,
            y,
            z,
            roll: roll.to_radians(),
            pitch: pitch.to_radians(),
            yaw: yaw.to_radians(),
        }
    }

    /// The nearest core pose (each coordinate rounded to f32).
    pub fn to_core(&self) -> Pose {
        Pose {
            x_mm: self.x as f32,
            y_mm: self.y as f32,
            z_mm: self.z as f32,
            roll_rad: self.roll as f32,
            pitch_rad: self.pitch as f32,
            yaw_rad: self.yaw as f32,
        }
    }

    /// `R = Rz(yaw) Ry(pitch) Rx(roll)`, multiplied out numerically (not eq. 1's expansion).
    pub fn rotation(&self) -> M3 {
        mat_mul(
            &mat_mul(&rot_z(self.yaw), &rot_y(self.pitch)),
            &rot_x(self.roll),
        )
    }

    /// The ZYX angles of a rotation matrix (pitch within +-90 degrees): the inverse of
    /// [`RefPose::rotation`]. Translation is left at zero.
    pub fn angles_of(r: &M3) -> (f64, f64, f64) {
        // R[2][0] = -sin(pitch); R[2][1] / R[2][2] = tan(roll); R[1][0] / R[0][0] = tan(yaw)
        // (each pair scaled by cos(pitch) > 0).
        let pitch = (-r[2][0]).clamp(-1.0, 1.0).asin();
        let roll = r[2][1].atan2(r[2][2]);
        let yaw = r[1][0].atan2(r[0][0]);
        (roll, pitch, yaw)
    }
}

/// One leg's build coordinates in f64.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefLeg {
    /// Servo shaft centre `b`, base frame, mm.
    pub b: V3,
    /// Rod joint `p`, platform frame, mm.
    pub p: V3,
    /// Arm-plane angle `beta`, rad.
    pub beta: f64,
}

impl RefLeg {
    /// The exact f64 value of a core leg.
    pub fn from_core(leg: &Leg) -> RefLeg {
        let v = |u: &kinematics_core::Vec3| [f64::from(u.x), f64::from(u.y), f64::from(u.z)];
        RefLeg {
            b: v(&leg.base_mm),
            p: v(&leg.platform_mm),
            beta: f64::from(leg.beta_rad),
        }
    }

    /// The arm tip `A(alpha) = b + a (cos alpha cos beta, cos alpha sin beta, sin alpha)`
    /// ("The Mathematics of the Stewart Platform", eq. 4-6), mm.
    pub fn arm_tip(&self, arm: f64, alpha: f64) -> V3 {
        let (sa, ca) = alpha.sin_cos();
        let (sb, cb) = self.beta.sin_cos();
        add(self.b, [arm * ca * cb, arm * ca * sb, arm * sa])
    }

    /// Velocity of the arm tip per radian of arm, `dA/dalpha`, mm/rad.
    pub fn arm_tip_velocity(&self, arm: f64, alpha: f64) -> V3 {
        let (sa, ca) = alpha.sin_cos();
        let (sb, cb) = self.beta.sin_cos();
        [-arm * sa * cb, -arm * sa * sb, arm * ca]
    }

    /// Eq. 10 for this leg, generalised to a shaft at height `z_b`: the home height `h0` at which
    /// `|l|^2 = s^2 + a^2` with `l = (x_p - x_b, y_p - y_b, h0 + z_p - z_b)` and the platform
    /// joint above the shaft. `None` if the radicand is not positive.
    pub fn eq10_home_height(&self, arm: f64, rod: f64) -> Option<f64> {
        let dx = self.p[0] - self.b[0];
        let dy = self.p[1] - self.b[1];
        let radicand = rod * rod + arm * arm - dx * dx - dy * dy;
        (radicand > 0.0).then(|| radicand.sqrt() - (self.p[2] - self.b[2]))
    }
}

/// The closure function `g(alpha) = |q - A(alpha)|^2 - s^2`, mm^2: zero when the rod fits.
pub fn closure(leg: &RefLeg, arm: f64, rod: f64, q: V3, alpha: f64) -> f64 {
    let d = sub(q, leg.arm_tip(arm, alpha));
    dot(d, d) - rod * rod
}

/// A leg's arm angle found by [`solve_leg`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmRoot {
    /// The arm angle on the physical branch, rad, within `(centre - pi, centre + pi]`.
    pub alpha: f64,
    /// The other solution (the "elbow through" branch), rad, same range.
    pub other: f64,
    /// How far inside the workspace the leg is, mm: the smaller of `s - d_min` and
    /// `d_max - s`, where `d_min`, `d_max` are the least and greatest distances from `q` to the
    /// arm tip's circle. Zero at the workspace boundary (arm and rod in line).
    pub margin_mm: f64,
    /// `dg/dalpha` at the root, mm^2/rad (negative on the physical branch). Its size says how
    /// well conditioned the angle is: `|d alpha| = |d g| / |slope|`.
    pub slope: f64,
}

/// Why [`solve_leg`] found no arm angle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unreachable {
    /// How far outside the workspace the leg is, mm (negative: `s - d_min` or `d_max - s`).
    pub margin_mm: f64,
}

fn wrap_near(alpha: f64, centre: f64) -> f64 {
    use core::f64::consts::{PI, TAU};
    let mut a = alpha;
    while a - centre > PI {
        a -= TAU;
    }
    while a - centre <= -PI {
        a += TAU;
    }
    a
}

/// Golden-section search for an extremum of `f` in `[lo, hi]` (which must hold exactly one).
/// `sign` = +1 finds a maximum, -1 a minimum.
fn golden_extremum(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64, sign: f64) -> f64 {
    let inv_phi = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = hi - inv_phi * (hi - lo);
    let mut d = lo + inv_phi * (hi - lo);
    let (mut fc, mut fd) = (sign * f(c), sign * f(d));
    for _ in 0..200 {
        if hi - lo <= 1e-13 {
            break;
        }
        if fc > fd {
            hi = d;
            d = c;
            fd = fc;
            c = hi - inv_phi * (hi - lo);
            fc = sign * f(c);
        } else {
            lo = c;
            c = d;
            fc = fd;
            d = lo + inv_phi * (hi - lo);
            fd = sign * f(d);
        }
    }
    (lo + hi) / 2.0
}

/// Bisection for the zero of `f` in `[lo, hi]`, given `f(lo) >= 0 >= f(hi)`.
fn bisect_descending(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if f(mid) >= 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Bisection for the zero of `f` in `[lo, hi]`, given `f(lo) <= 0 <= f(hi)`.
fn bisect_ascending(f: impl Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
    bisect_descending(|x| -f(x), lo, hi)
}

/// Number of samples per turn used to bracket the extremes of `g`.
pub const SAMPLES: usize = 72;

/// Solves one leg numerically: the arm angle `alpha` with `|q - A(alpha)| = s`.
///
/// As the arm turns, its tip runs round a circle, and the squared distance from the tip to
/// `q` has exactly one greatest and one least value per turn (unless `q` is on the shaft's
/// axis, where it is constant and we call the leg unreachable). We locate both by sampling
/// [`SAMPLES`] angles and refining the best samples by golden-section search. The leg can
/// reach iff `d_min <= s <= d_max`; then `g` has one zero on each of the two arcs between the
/// extremes.
///
/// Branch choice (physical, not taken from eq. 9): the build works with the arm RISING
/// towards its rod's joint, i.e. turning the arm the positive way moves its tip towards `q`
/// (the rod is pushed, the elbow has not gone "through" the line from shaft to joint).
/// That is the zero on the arc where `g` DECREASES, from the farthest tip position forwards to
/// the nearest; we find it by bisection on that monotonic arc. At the home pose (arm and rod at
/// right angles, the rod leaning up and over the arm) this is the home arm angle, and for the
/// whole servo travel it is also the zero nearer to `alpha0` (tested); the other zero, the arm
/// folded back past the joint, is returned as [`ArmRoot::other`].
///
/// Angles are returned within `(centre - pi, centre + pi]`; pass `alpha0` (or 0 when
/// computing `alpha0` itself).
pub fn solve_leg(
    leg: &RefLeg,
    arm: f64,
    rod: f64,
    q: V3,
    centre: f64,
) -> Result<ArmRoot, Unreachable> {
    use core::f64::consts::{PI, TAU};
    let g = |alpha: f64| closure(leg, arm, rod, q, alpha);
    let step = TAU / SAMPLES as f64;
    let start = centre - PI;
    let mut i_max = 0;
    let mut i_min = 0;
    let mut g_max = f64::NEG_INFINITY;
    let mut g_min = f64::INFINITY;
    for i in 0..SAMPLES {
        let v = g(start + step * i as f64);
        if v > g_max {
            g_max = v;
            i_max = i;
        }
        if v < g_min {
            g_min = v;
            i_min = i;
        }
    }
    if !(g_max.is_finite() && g_min.is_finite()) {
        return Err(Unreachable {
            margin_mm: f64::NEG_INFINITY,
        });
    }
    // The true extremes lie within one sample step of the best samples.
    let around = |i: usize| {
        let a = start + step * i as f64;
        (a - step, a + step)
    };
    let (lo, hi) = around(i_max);
    let alpha_far = golden_extremum(g, lo, hi, 1.0);
    let (lo, hi) = around(i_min);
    let mut alpha_near = golden_extremum(g, lo, hi, -1.0);
    let (g_far, g_near) = (g(alpha_far), g(alpha_near));
    let d_max = (g_far + rod * rod).max(0.0).sqrt();
    let d_min = (g_near + rod * rod).max(0.0).sqrt();
    let margin_mm = (rod - d_min).min(d_max - rod);
    // q on the shaft axis: every tip position is equally far away.
    if g_far - g_near <= 1e-12 * (rod * rod) {
        return Err(Unreachable {
            margin_mm: margin_mm.min(0.0),
        });
    }
    if margin_mm < 0.0 {
        return Err(Unreachable { margin_mm });
    }
    // The descending arc runs forwards from the farthest to the nearest tip position.
    while alpha_near <= alpha_far {
        alpha_near += TAU;
    }
    let alpha = bisect_descending(g, alpha_far, alpha_near);
    // The ascending arc runs forwards from the nearest to the farthest (one turn on).
    let other = bisect_ascending(g, alpha_near, alpha_far + TAU);
    let tip = leg.arm_tip(arm, alpha);
    let slope = -2.0 * dot(sub(q, tip), leg.arm_tip_velocity(arm, alpha));
    Ok(ArmRoot {
        alpha: wrap_near(alpha, centre),
        other: wrap_near(other, centre),
        margin_mm,
        slope,
    })
}

/// Eq. 9 of "The Mathematics of the Stewart Platform", literally: `alpha = asin(L / sqrt(M^2 +
/// N^2)) - atan2(N, M)` with `L = |l|^2 - (s^2 - a^2)`, `M = 2a (z_p - z_b)`, `N = 2a
/// [cos(beta) (x_p - x_b) + sin(beta) (y_p - y_b)]` (here `(x_p, y_p, z_p)` is the joint `q`
/// in the base frame). The document writes `tan^-1(N / M)`; `atan2(N, M)` is the same for `M > 0` (joint above the
/// shaft) and keeps the formula's branch for `M <= 0`. `None` where `|L| > sqrt(M^2 + N^2)`.
pub fn eq9_alpha(leg: &RefLeg, arm: f64, rod: f64, q: V3) -> Option<f64> {
    let l = sub(q, leg.b);
    let big_l = dot(l, l) - (rod * rod - arm * arm);
    let big_m = 2.0 * arm * l[2];
    let big_n = 2.0 * arm * (leg.beta.cos() * l[0] + leg.beta.sin() * l[1]);
    let ratio = big_l / (big_m * big_m + big_n * big_n).sqrt();
    (ratio.abs() <= 1.0).then(|| ratio.asin() - big_n.atan2(big_m))
}

/// Eq. 12 of "The Mathematics of the Stewart Platform", literally, generalised from leg 2
/// (`beta = 0`) to any leg by projecting the horizontal offset onto the arm plane: `alpha0 = asin(L0 / sqrt(M0^2 + N0^2)) -
/// atan(M0 / N0)` with eq. 12's OWN naming, `M0 = 2a [cos(beta) (x_p - x_b) + sin(beta)
/// (y_p - y_b)]` (horizontal), `N0 = 2a (h0 + z_p - z_b)` (vertical) and `L0 = 2a^2`.
pub fn eq12_alpha0(leg: &RefLeg, arm: f64, h0: f64) -> Option<f64> {
    let l0_big = 2.0 * arm * arm;
    let m0 = 2.0
        * arm
        * (leg.beta.cos() * (leg.p[0] - leg.b[0]) + leg.beta.sin() * (leg.p[1] - leg.b[1]));
    let n0 = 2.0 * arm * (h0 + leg.p[2] - leg.b[2]);
    let ratio = l0_big / (m0 * m0 + n0 * n0).sqrt();
    (ratio.abs() <= 1.0 && n0 > 0.0).then(|| ratio.asin() - (m0 / n0).atan())
}

/// Why the reference refuses a geometry (mirrors the core's `GeometryError` cases that are
/// about geometry rather than input checking).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RefGeometryError {
    /// Eq. 10 has no real solution for leg `leg` (1..=6).
    NoHomeHeight {
        /// Leg number.
        leg: usize,
    },
    /// Leg `leg`'s eq. 10 height differs from leg 1's by more than the tolerance.
    LegsDisagree {
        /// Leg number.
        leg: usize,
        /// The difference, mm.
        diff_mm: f64,
    },
    /// At home, leg `leg` cannot reach its rod.
    HomeUnreachable {
        /// Leg number.
        leg: usize,
    },
}

/// A geometry with its derived constants, all in f64.
#[derive(Debug, Clone, PartialEq)]
pub struct RefGeometry {
    /// The legs.
    pub legs: [RefLeg; LEGS],
    /// Arm length `a`, mm.
    pub arm: f64,
    /// Rod length `s`, mm.
    pub rod: f64,
    /// Each leg's own eq. 10 home height, mm.
    pub leg_home_heights: [f64; LEGS],
    /// The home height used for poses: the mean of the legs' eq. 10 heights, mm.
    pub h0: f64,
    /// Home arm angles: the numeric root at the home pose (height `h0`), rad.
    pub alpha0: [f64; LEGS],
    /// Home arm angles by eq. 12 with each leg's own eq. 10 height, rad.
    pub alpha0_eq12: [f64; LEGS],
}

impl RefGeometry {
    /// Derives `h0` and `alpha0` from build coordinates. `tolerance_mm` is the largest spread
    /// of the legs' home heights accepted (the core's documented `HOME_HEIGHT_TOLERANCE_MM`).
    pub fn new(
        legs: [RefLeg; LEGS],
        arm: f64,
        rod: f64,
        tolerance_mm: f64,
    ) -> Result<RefGeometry, RefGeometryError> {
        let mut heights = [0.0; LEGS];
        for (i, leg) in legs.iter().enumerate() {
            heights[i] = leg
                .eq10_home_height(arm, rod)
                .ok_or(RefGeometryError::NoHomeHeight { leg: i + 1 })?;
        }
        for (i, h) in heights.iter().enumerate().skip(1) {
            let diff_mm = (h - heights[0]).abs();
            if diff_mm > tolerance_mm {
                return Err(RefGeometryError::LegsDisagree {
                    leg: i + 1,
                    diff_mm,
                });
            }
        }
        let h0 = heights.iter().sum::<f64>() / LEGS as f64;
        let mut alpha0 = [0.0; LEGS];
        let mut alpha0_eq12 = [f64::NAN; LEGS];
        for (i, leg) in legs.iter().enumerate() {
            let q = add(leg.p, [0.0, 0.0, h0]);
            alpha0[i] = solve_leg(leg, arm, rod, q, 0.0)
                .map_err(|_| RefGeometryError::HomeUnreachable { leg: i + 1 })?
                .alpha;
            alpha0_eq12[i] = eq12_alpha0(leg, arm, heights[i]).unwrap_or(f64::NAN);
        }
        Ok(RefGeometry {
            legs,
            arm,
            rod,
            leg_home_heights: heights,
            h0,
            alpha0,
            alpha0_eq12,
        })
    }

    /// The reference for a core geometry: its inputs through the public getters, everything
    /// else derived here.
    pub fn from_core(g: &Geometry) -> RefGeometry {
        let legs = core::array::from_fn(|i| RefLeg::from_core(g.leg(i)));
        RefGeometry::new(
            legs,
            f64::from(g.arm_mm()),
            f64::from(g.rod_mm()),
            f64::from(kinematics_core::geometry::HOME_HEIGHT_TOLERANCE_MM),
        )
        .expect("a geometry the core accepted is valid for the reference too")
    }

    /// Platform joints `q_i = T + R p_i` in the base frame (eq. 2), `T = (x, y, h0 + z)`, mm.
    pub fn platform_joints(&self, pose: &RefPose) -> [V3; LEGS] {
        let r = pose.rotation();
        let t = [pose.x, pose.y, self.h0 + pose.z];
        core::array::from_fn(|i| add(t, mat_vec(&r, self.legs[i].p)))
    }

    /// Numeric arm angles for a pose, each near its `alpha0`.
    pub fn arm_angles(&self, pose: &RefPose) -> [Result<ArmRoot, Unreachable>; LEGS] {
        let q = self.platform_joints(pose);
        core::array::from_fn(|i| solve_leg(&self.legs[i], self.arm, self.rod, q[i], self.alpha0[i]))
    }

    /// Literal eq. 9 arm angles for a pose (`None` where eq. 9 has no solution).
    pub fn eq9_arm_angles(&self, pose: &RefPose) -> [Option<f64>; LEGS] {
        let q = self.platform_joints(pose);
        core::array::from_fn(|i| eq9_alpha(&self.legs[i], self.arm, self.rod, q[i]))
    }

    /// `| |q_i - A_i(alpha_i)| - s |` for given arm angles: how badly the rods would fail to
    /// fit, mm.
    pub fn rod_closure_errors(&self, pose: &RefPose, alpha: &[f64; LEGS]) -> [f64; LEGS] {
        let q = self.platform_joints(pose);
        core::array::from_fn(|i| {
            (norm(sub(q[i], self.legs[i].arm_tip(self.arm, alpha[i]))) - self.rod).abs()
        })
    }
}

/// Eq. 13 / 14 with the servo's settings: `W = W0 + d (alpha - alpha0) r`, `d = +1` for a
/// normal servo (eq. 13, even by default) and `-1` for a reversed one (eq. 14, odd), us.
pub fn pulse_us(servo: &ServoConfig, alpha: f64, alpha0: f64) -> f64 {
    let d = match servo.direction {
        Direction::Normal => 1.0,
        Direction::Reversed => -1.0,
    };
    f64::from(servo.home_us) + d * (alpha - alpha0) * f64::from(servo.rate_us_per_rad)
}

/// Eq. 13 / 14 exactly as the document writes them, by servo number (1..=6): even servos add,
/// odd servos subtract, us.
pub fn eq13_14_pulse_us(servo_number: usize, w0: f64, rate: f64, alpha: f64, alpha0: f64) -> f64 {
    if servo_number % 2 == 0 {
        w0 + (alpha - alpha0) * rate
    } else {
        w0 - (alpha - alpha0) * rate
    }
}

/// What the reference expects of `solve` for one pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Expectation {
    /// Each leg's numeric solution.
    pub legs: [Result<ArmRoot, Unreachable>; LEGS],
    /// Each servo's pulse (NaN for a leg that cannot reach), us.
    pub pulse_us: [f64; LEGS],
    /// How far each pulse is inside its servo's limits, us (negative: outside).
    pub limit_margin_us: [f64; LEGS],
}

impl Expectation {
    /// Computes everything the reference knows about `pose`.
    pub fn new(geometry: &RefGeometry, servos: &ServoSet, pose: &RefPose) -> Expectation {
        let legs = geometry.arm_angles(pose);
        let mut pulse = [f64::NAN; LEGS];
        let mut margin = [f64::NAN; LEGS];
        for i in 0..LEGS {
            if let Ok(root) = legs[i] {
                let s = &servos.0[i];
                pulse[i] = pulse_us(s, root.alpha, geometry.alpha0[i]);
                margin[i] = (pulse[i] - f64::from(s.min_us)).min(f64::from(s.max_us) - pulse[i]);
            }
        }
        Expectation {
            legs,
            pulse_us: pulse,
            limit_margin_us: margin,
        }
    }

    /// Leg `i`'s workspace margin, mm (negative outside).
    pub fn leg_margin_mm(&self, i: usize) -> f64 {
        match self.legs[i] {
            Ok(r) => r.margin_mm,
            Err(u) => u.margin_mm,
        }
    }

    /// Arm angles if every leg can reach.
    pub fn alphas(&self) -> Option<[f64; LEGS]> {
        let mut out = [0.0; LEGS];
        for (o, leg) in out.iter_mut().zip(self.legs.iter()) {
            *o = leg.ok()?.alpha;
        }
        Some(out)
    }
}
