//! Inverse kinematics: pose -> six arm angles (rad) -> six pulse widths (us).
//!
//! For each leg ("The Mathematics of the Stewart Platform"):
//! - eq. 1: `R = Rz(yaw) Ry(pitch) Rx(roll)`;
//! - eq. 2, 3: platform joint `q_i = T + R p_i` with `T = (x, y, h0 + z)`, leg `l_i = q_i - b_i`;
//!   with a rotation centre `c` set (see [`crate::configuration`]) the platform turns about it
//!   and `T = (x, y, h0 + z) + c - R c`: one rotation of `c` per pose, none with `c = 0`;
//! - eq. 9: the arm tip `A(alpha) = b + a (cos(alpha) cos(beta), cos(alpha) sin(beta), sin(alpha))`
//!   is at rod length `s` from `q` exactly when `L = M sin(alpha) + N cos(alpha)` with
//!   `L = |l|^2 - (s^2 - a^2)`, `M = 2a l_z`, `N = 2a (cos(beta) l_x + sin(beta) l_y)`.
//!
//! Eq. 9 solves this as `alpha = asin(L / sqrt(M^2 + N^2)) - atan(N / M)`. We use the same
//! root in half-angle form, which needs no `asin`: with `t = tan(alpha / 2)` the equation
//! becomes `(L + N) t^2 - 2 M t + (L - N) = 0`, whose root on eq. 9's branch
//! (`cos(alpha + delta) >= 0`, `delta = atan2(N, M)`) is, with `D = M^2 + N^2 - L^2`,
//! `t = (L - N) / (M + sqrt(D)) = (M - sqrt(D)) / (L + N)`. Each form is 0/0 somewhere: the
//! first where `M = -sqrt(D)` (only possible for `M < 0`, joint below the shaft), the second
//! where `M = sqrt(D)` (only for `M > 0`). So `alpha = 2 atan2(L - N, M + sqrt(D))` for
//! `M >= 0` and `alpha = 2 atan2(M - sqrt(D), L + N)` for `M < 0`; both stay well
//! conditioned away from the workspace boundary.
//! The leg is unreachable exactly when `M^2 + N^2 - L^2 < 0`, i.e. `|L| / sqrt(M^2 + N^2) > 1`.
//!
//! Eq. 13, 14 then map `alpha` to a pulse width (see [`crate::servo`]). A pose is accepted or
//! rejected as a whole: there is never a partial or NaN result.
//!
//! A [`Solver`] is the IK of one [`Geometry`]: it owns the geometry, derives the home arm angles
//! `alpha0` (eq. 12, which is eq. 9 at the home pose: the IK's own answer there, so the home
//! pose gives exactly the home pulses) and holds what it needs on every pose: per-leg
//! constants (mm, rad), in `f32` and, where the build allows, in fixed point (module `fixed`).
//! Build it once per geometry.
//!
//! Two paths compute the same equations. Every usual build (a planar platform within the
//! bounds of module `fixed`) and pose takes the fixed-point path: integer instructions only,
//! from the rotation to the pulses, with `M`'s fixed-point sine and cosine, square root and arc
//! tangent (by default the core's own: then the host and the chip compute the same bits); a leg
//! whose vector and build are within smaller bounds (every leg of every usual pose) computes
//! eq. 9's terms in 32-bit words, any other in 64-bit words. Other builds and poses take the
//! float path, `f32` arithmetic through `M`. Each has its own home angles, so each gives
//! exactly the home pulses at home.

use core::f32::consts::PI;
use core::fmt;

use crate::configuration::{check_centre, Anchors, ConfigurationError};
use crate::fixed::{
    from_fixed, from_fixed32, leading_zeros, leg_square_narrow, mul_mm, mul_mm_narrow,
    rotate_mm_split, split13, split15, square, square_mm, to_fixed, to_fixed_sq, wide_mul,
    ARM_FRAC, MAX_FIXED_MM, MAX_FIXED_ROD_TERM_MM2, MAX_FIXED_TWO_ARM_MM, MAX_NARROW_ROD_TERM_MM2,
    MAX_NARROW_TWO_ARM_MM, MM_FRAC, NARROW_LEG_Q, NARROW_SQ_FRAC, ROT_FRAC,
};
use crate::geometry::{Geometry, GeometryError};
use crate::math::{is_zero, Libm, Math, Real};
use crate::pose::{Axis, Pose};
use crate::servo::{ServoConfig, ServoSet};
use crate::types::{Vec3, LEGS};

/// Largest rotation accepted about any axis, rad (180 degrees). Larger angles describe the same
/// orientation as a smaller one and would only hide typing mistakes.
pub const MAX_ANGLE_RAD: f32 = PI;

/// The arm angles and pulse widths for one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solution {
    /// Arm angle `alpha_i` of each servo above horizontal, rad.
    pub arm_rad: [f32; LEGS],
    /// Pulse width `W_i` of each servo, us; finite and within that servo's limits.
    pub pulse_us: [f32; LEGS],
}

/// Why a pose cannot be driven.
///
/// `Display` gives one short line for developers (the case and its values, in the units of the
/// fields); the wording users see is `control::report`'s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum IkError {
    /// A pose coordinate is NaN or infinite.
    NonFinite {
        /// The offending coordinate.
        axis: Axis,
    },
    /// A rotation is larger than [`MAX_ANGLE_RAD`].
    AngleTooLarge {
        /// The offending rotation.
        axis: Axis,
        /// The value given, rad.
        value_rad: f32,
    },
    /// The arm of this leg cannot reach its rod's platform joint (eq. 9 has no solution).
    Unreachable {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// The pose needs a pulse outside this servo's limits.
    ServoLimit {
        /// Servo number, 1..=6.
        servo: u8,
        /// The pulse the pose would need, us.
        pulse_us: f32,
        /// The servo's lower limit, us.
        min_us: f32,
        /// The servo's upper limit, us.
        max_us: f32,
    },
}

impl fmt::Display for IkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            IkError::NonFinite { axis } => write!(f, "non-finite pose coordinate {}", axis.name()),
            IkError::AngleTooLarge { axis, value_rad } => {
                write!(f, "{} = {value_rad} rad, beyond +-pi", axis.name())
            }
            IkError::Unreachable { leg } => write!(f, "leg {leg}: unreachable (no root of eq. 9)"),
            IkError::ServoLimit {
                servo,
                pulse_us,
                min_us,
                max_us,
            } => write!(
                f,
                "servo {servo}: pulse {pulse_us} us outside its limits {min_us}..={max_us} us"
            ),
        }
    }
}

impl core::error::Error for IkError {}

/// Checks that a pose is made of usable numbers.
pub fn check_pose(pose: &Pose) -> Result<(), IkError> {
    // The usual case first, in six integer comparisons (the IK's hot path): a finite position
    // (magnitude bits below the infinities') and angles of at most pi (non-negative floats
    // order like their bits; a NaN's are above every finite bound). Anything else takes the
    // checks below, which name the axis.
    let magnitude = |v: f32| v.to_bits() & 0x7fff_ffff;
    let (finite, pi) = (f32::INFINITY.to_bits(), MAX_ANGLE_RAD.to_bits());
    if magnitude(pose.x_mm) < finite
        && magnitude(pose.y_mm) < finite
        && magnitude(pose.z_mm) < finite
        && magnitude(pose.roll_rad) <= pi
        && magnitude(pose.pitch_rad) <= pi
        && magnitude(pose.yaw_rad) <= pi
    {
        return Ok(());
    }
    if let Some(axis) = pose.first_non_finite() {
        return Err(IkError::NonFinite { axis });
    }
    for axis in [Axis::Roll, Axis::Pitch, Axis::Yaw] {
        let value_rad = pose.get(axis);
        // Integer comparison (a float one is a library call on the chip).
        if crate::math::lt(MAX_ANGLE_RAD, value_rad.abs()) {
            return Err(IkError::AngleTooLarge { axis, value_rad });
        }
    }
    Ok(())
}

/// Bound on `|l|^2`, `|M|` and `|N|` (mm^2): no build reaches that far, and below it no later
/// product or sum of the hot loop can overflow, whatever the [`Math`] does on overflow.
const MAX_TERM_MM2: f32 = 1e18;

/// `0 <= x < bound` (`bound` positive) in integer instructions: non-negative floats order like
/// their bit patterns, while negative values, -0 and NaN (sign bit set, or all exponent bits)
/// compare above every finite bound. Float comparisons are library calls on an FPU-less chip.
#[inline]
fn below(x: f32, bound: f32) -> bool {
    x.to_bits() < bound.to_bits()
}

/// `x + x` (exact): for a normal `x` below 2^127 by adding one to the binary exponent in
/// integer instructions (an `M::add` costs a library call on the chip); through `M` otherwise.
#[inline]
fn twice<M: Math>(x: f32) -> f32 {
    let exponent = x.to_bits() & 0x7f80_0000;
    if exponent != 0 && exponent < 0x7f00_0000 {
        f32::from_bits(x.to_bits() + 0x0080_0000)
    } else {
        (Real::<M>::new(x) + Real::new(x)).0
    }
}

/// Wraps an angle into `(-pi, pi]`, rad, with `M`'s arithmetic (the IK's hot path). The angle
/// must be finite (see [`Math::add`]).
fn wrap_angle_rad<M: Math>(a: f32) -> f32 {
    // Integer comparisons (`math::lt`, `math::le`): float ones are library calls on the chip.
    // The correction goes through `M` too: a plain `a - 2 pi` would be computed on every call
    // (the compiler evaluates cheap-looking float operations ahead of the branch, but on the
    // chip it is a library call of about 100 cycles).
    let two_pi = Real::<M>::new(2.0 * PI);
    if crate::math::lt(PI, a) {
        (Real::new(a) - two_pi).0
    } else if crate::math::le(a, -PI) {
        (Real::new(a) + two_pi).0
    } else {
        a
    }
}

/// One leg's constants for the float path (mm, rad).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct FloatLeg {
    /// `p_i`, mm.
    platform_mm: [f32; 3],
    /// `(0, 0, h0) - b_i`: the leg vector is `l_i = R p_i + (x, y, z) + offset`, mm.
    offset_mm: [f32; 3],
    /// `(cos(beta_i), sin(beta_i))` with the `M` of [`Solver::new_with`]: the direction of arm
    /// `i`'s plane (also for the arm tip of eq. 4-6 outside the IK).
    plane: [f32; 2],
    /// `2a cos(beta)`, `2a sin(beta)`: `N = n_x l_x + n_y l_y` (eq. 9), mm.
    n_mm: [f32; 2],
    /// Home arm angle alpha0 (eq. 12) as this path finds it, rad: home stays exact on it.
    alpha0_rad: f32,
}

/// The float path's constants: `f32` arithmetic through `M`, for every build (the only path of
/// a build beyond the fixed-point bounds; on the others, for poses beyond them).
#[derive(Debug, Clone, Copy, PartialEq)]
struct FloatTable {
    /// `s^2 - a^2`, mm^2 (the constant in `L` of eq. 9).
    rod_sq_minus_arm_sq: f32,
    /// `2a`, mm (the factor in `M` and `N` of eq. 9).
    two_arm_mm: f32,
    /// Every platform joint has `z = 0` (true of every circular layout): `R p` skips a column.
    planar_platform: bool,
    /// Every base joint has the same `z` (true of every circular layout): the `z` of
    /// `(x, y, z) + offset` is the same for all legs, so the IK adds it once.
    flat_base: bool,
    legs: [FloatLeg; LEGS],
}

/// One leg's constants for the fixed-point path (module `fixed`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct FixedLeg {
    /// `p_i` (x, y; `z = 0`) in steps of 2^-20 mm (`fixed::MM_FRAC`), each split at bit 15
    /// (`fixed::split15`) for `fixed::rotate_mm_split`.
    platform_split: [[i32; 2]; 2],
    /// `(0, 0, h0) - b_i`, 2^-20 mm.
    offset_q: [i32; 3],
    /// `2a cos(beta)`, `2a sin(beta)`, 2^-20 mm.
    n_q: [i32; 2],
    /// `n_q`, each split at bit 13 (`fixed::split13`) for the 32-bit path's products.
    n_split: [[i32; 2]; 2],
    /// Home arm angle alpha0 (eq. 12) as this path finds it, in steps of 2^-28 rad
    /// (`fixed::ARM_FRAC`): home stays exact on it.
    alpha0_q: i32,
    /// `alpha0_q` wrapped into `(-pi, pi]`, for the offsets from home.
    alpha0_wrapped_q: i32,
}

/// Where the rotation centre `c` is, for the fixed-point path.
#[derive(Debug, Clone, Copy, PartialEq)]
enum FixedCentre {
    /// `c = 0`: nothing to add to the pose's translation.
    Origin,
    /// `c` in steps of 2^-20 mm (every coordinate within `fixed::MAX_FIXED_MM`): the IK adds
    /// `c - R c` to the pose's translation (one rotation of `c` per pose).
    At([i32; 3]),
    /// A coordinate beyond `fixed::MAX_FIXED_MM`: every pose takes the float path.
    Beyond,
}

/// The fixed-point path's constants (module `fixed`): a planar build whose every `p_i` and
/// offset coordinate is within `fixed::MAX_FIXED_MM`, `2a` and `s^2 - a^2` within their bounds,
/// has one, and then every pose within the bounds takes this path.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FixedTable {
    /// `s^2 - a^2`, 2^-36 mm^2 (`fixed::SQ_FRAC`), from the lengths in `f64`.
    rod_term_q: i64,
    /// `2a`, 2^-20 mm (`fixed::MM_FRAC`).
    two_arm_q: i32,
    /// `two_arm_q` split at bit 13 (`fixed::split13`) for the 32-bit path's products.
    two_arm_split: [i32; 2],
    /// `s^2 - a^2` in steps of 2^-15 mm^2 (`fixed::NARROW_SQ_FRAC`), where the build allows the
    /// 32-bit path (`0 <= s^2 - a^2 < fixed::MAX_NARROW_ROD_TERM_MM2`,
    /// `2a < fixed::MAX_NARROW_TWO_ARM_MM`: every usual build); `None`: every leg takes the
    /// 64-bit path.
    narrow_rod_term_q: Option<i32>,
    centre: FixedCentre,
    legs: [FixedLeg; LEGS],
}

/// The IK of one geometry: the geometry, the rotation centre
/// ([`Solver::set_rotation_centre_mm`], the platform frame's origin by default), the per-leg
/// constants and home arm angles of the float path and, where the build allows, of the
/// fixed-point path, computed once by [`Solver::new`], and the solving itself
/// ([`Solver::solve`], [`Solver::arm_angles`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Solver {
    geometry: Geometry,
    /// The rotation centre `c`, platform frame, mm (module `configuration`): the platform turns
    /// about it and a pose's `(x, y, z)` is how far it moved from home.
    centre_mm: [f32; 3],
    float: FloatTable,
    fixed: Option<FixedTable>,
}

/// The pose's part of eq. 2, 3 in fixed point: the first two columns of `R` (`fixed::ROT_FRAC`
/// fraction bits, each entry split at bit 15 for `fixed::rotate_mm_split`) and the translation
/// `(x, y, z)` (with the centre's `c - R c`; `fixed::MM_FRAC`).
struct FixedPose {
    rows: [[[i32; 2]; 2]; 3],
    position: [i32; 3],
}

/// `pi` and `2 pi` in steps of 2^-28 rad (`fixed::ARM_FRAC`), rounded.
const PI_ARM: i32 = 843_314_857;
const TWO_PI_ARM: i32 = 1_686_629_713;

/// An angle in steps of 2^-28 rad within `(-2 pi, 2 pi]` wrapped into `(-pi, pi]` (one turn
/// added or taken away at most).
#[inline(always)]
fn wrap_fixed(a: i32) -> i32 {
    if a > PI_ARM {
        a - TWO_PI_ARM
    } else if a <= -PI_ARM {
        a + TWO_PI_ARM
    } else {
        a
    }
}

/// The arm angle `alpha0 + offset` (steps of 2^-28 rad) in rad, rounded once to `f32` (in 32
/// bits unless the sum leaves them: only for a home angle beyond `pi`).
#[inline(always)]
fn arm_rad_fixed(alpha0: i32, offset: i32) -> f32 {
    match alpha0.checked_add(offset) {
        Some(alpha) => from_fixed32(alpha, ARM_FRAC),
        None => from_fixed(i64::from(alpha0) + i64::from(offset), ARM_FRAC),
    }
}

/// `alpha - alpha0` wrapped into `(-pi, pi]` for an arm angle `alpha` (steps of 2^-28 rad,
/// within `(-2 pi, 2 pi]`) and a home angle already wrapped: after wrapping `alpha`, their
/// difference is within `(-2 pi, 2 pi)`, so one more wrap does, all in 32 bits.
#[inline(always)]
fn offset_fixed(alpha: i32, alpha0_wrapped: i32) -> i32 {
    wrap_fixed(wrap_fixed(alpha) - alpha0_wrapped)
}

/// `M`, `L - N` and `L + N` of eq. 9 (steps of 2^-36 mm^2) scaled by one power of two, rounded
/// to nearest, so that the largest magnitude is in `[2^28, 2^29]` (all zero stay zero): their
/// ratios, all the root of eq. 9 needs, to about 2^-29 of the largest. Then
/// `M^2 - (L - N)(L + N)` is exact in an `i64` and `M + sqrt(D)` fits an `i32`. In 32-bit
/// words: a variable 64-bit shift is a library call on the M0+.
#[inline(always)]
fn scale_terms(terms: [i64; 3]) -> [i32; 3] {
    // The width of the largest magnitude from the high words (`h ^ (h >> 31)` is `|h|`, or
    // `|h| - 1` for a negative one: the width of `|t|` but for a power of two, whose scaled
    // magnitude is then 2^29 exactly: still within the bound).
    let magnitude_bits = |t: i64| {
        let high = (t >> 32) as i32;
        (high ^ (high >> 31)) as u32
    };
    let high_bits = magnitude_bits(terms[0]) | magnitude_bits(terms[1]) | magnitude_bits(terms[2]);
    let width = if high_bits != 0 {
        64 - leading_zeros(high_bits)
    } else {
        // Every |t| <= 2^32 (rare: only far from any usual pose).
        let magnitudes = terms.map(|t| t.unsigned_abs());
        if magnitudes.iter().any(|&m| m >> 32 != 0) {
            33
        } else {
            let low_bits = magnitudes.iter().fold(0u32, |bits, &m| bits | m as u32);
            if low_bits == 0 {
                return [0; 3];
            }
            32 - leading_zeros(low_bits)
        }
    };
    if width <= 29 {
        // Below 2^29 already: exact.
        let up = 29 - width;
        return [
            (terms[0] as i32) << up,
            (terms[1] as i32) << up,
            (terms[2] as i32) << up,
        ];
    }
    // t >> shift rounded (half up): the floor, plus the bit below it.
    let shift = width - 29;
    let scale = |t: i64| {
        let (high, low) = ((t >> 32) as i32, t as u32);
        if shift >= 32 {
            let s = shift - 32;
            let below = if s == 0 {
                (low >> 31) as i32
            } else {
                (high >> (s - 1)) & 1
            };
            (high >> s) + below
        } else {
            let floor = ((low >> shift) | ((high as u32) << (32 - shift))) as i32;
            floor + ((low >> (shift - 1)) & 1) as i32
        }
    };
    [scale(terms[0]), scale(terms[1]), scale(terms[2])]
}

/// `l` (eq. 2, 3) of one leg in steps of 2^-20 mm: `R p` within 2 steps of its exact value,
/// unbiased (`fixed::rotate_mm_split`), then the translation, exactly.
#[inline(always)]
fn leg_vector(c: &FixedLeg, fixed: &FixedPose) -> [i32; 3] {
    let (rows, position, p) = (&fixed.rows, &fixed.position, c.platform_split);
    [
        rotate_mm_split(rows[0], p) + position[0] + c.offset_q[0],
        rotate_mm_split(rows[1], p) + position[1] + c.offset_q[1],
        rotate_mm_split(rows[2], p) + position[2] + c.offset_q[2],
    ]
}

/// The root of eq. 9 from its scaled terms `[M, L - N, L + N]` (each within 2^29): the
/// half-angle in steps of 2^-29 rad, which is the arm angle in steps of 2^-28 rad; `None` if
/// the leg cannot reach.
#[inline(always)]
fn half_angle<M: Math>([m, l_minus_n, l_plus_n]: [i32; 3]) -> Option<i32> {
    // D < 0: |L| > sqrt(M^2 + N^2), no arm angle reaches (eq. 9 has no root).
    let discriminant = square(m) - wide_mul(l_minus_n, l_plus_n);
    if discriminant < 0 {
        return None;
    }
    // |M|, |L +- N| <= 2^29: D < 2^59, sqrt(D) < 2^29.5, and the sums below fit.
    let root = M::sqrt_fixed(discriminant as u64) as i32;
    // The form that cannot be 0/0 (module docs); alpha = 2 atan2(..) is the half-angle in
    // steps of 2^-29 rad read in steps of 2^-28.
    Some(if m >= 0 {
        M::atan2_fixed(l_minus_n, m + root)
    } else {
        M::atan2_fixed(m - root, l_plus_n)
    })
}

/// The 32-bit path's terms (steps of 2^-15 mm^2, each within an `i32`) brought within 2^29 in
/// magnitude, as [`half_angle`] needs: unchanged where they are (every usual leg), else halved
/// or quartered, rounded to nearest. Never scaled up (unlike [`scale_terms`], whose terms are
/// exact): each term is already within half a step of its exact value and `l`'s rounding moves
/// `L` by tens of steps (`FixedTable::narrow_terms`), so the extra bits would be zeros, and the
/// square root's error (within 1) is no larger than what the terms' own rounding puts into
/// `sqrt(D)`. Two comparisons, no count of leading zeros.
#[inline(always)]
fn scale_terms32(terms: [i32; 3]) -> [i32; 3] {
    // `t ^ (t >> 31)` is `|t|`, or `|t| - 1` for a negative one (see `scale_terms`): below
    // 2^29 exactly when every `|t| <= 2^29`; below 2^31 always.
    let magnitude_bits = |t: i32| (t ^ (t >> 31)) as u32;
    let bits = magnitude_bits(terms[0]) | magnitude_bits(terms[1]) | magnitude_bits(terms[2]);
    if bits < 1 << 29 {
        return terms;
    }
    // |t| <= 2^30: halved; |t| <= 2^31: quartered; either within 2^29 after the rounding.
    let shift = if bits < 1 << 30 { 1 } else { 2 };
    terms.map(|t| ((t >> (shift - 1)) + 1) >> 1)
}

impl Solver {
    /// The IK of `geometry` with `libm`'s sine and cosine: see [`Solver::new_with`].
    pub fn new(geometry: Geometry) -> Result<Solver, GeometryError> {
        Solver::new_with::<Libm>(geometry)
    }

    /// The IK of `geometry`: its per-leg constants (with `M`'s sine and cosine of `beta_i`),
    /// the fixed-point path's where the build allows, and the home arm angles `alpha0`
    /// (eq. 12) computed by this very solver with `M`, on each path, so the home pose gives
    /// exactly the home pulses. Refused ([`GeometryError::HomeUnreachable`]) if an arm cannot
    /// reach its rod at the home pose.
    pub fn new_with<M: Math>(geometry: Geometry) -> Result<Solver, GeometryError> {
        let legs = *geometry.legs();
        let (arm_mm, rod_mm) = (geometry.arm_mm(), geometry.rod_mm());
        let home_height_mm = geometry.home_height_mm();
        let two_arm_mm = 2.0 * arm_mm;
        let float_legs = legs.map(|leg| {
            let (sin_beta, cos_beta) = M::sin_cos(leg.beta_rad);
            FloatLeg {
                platform_mm: leg.platform_mm.into(),
                offset_mm: [
                    -leg.base_mm.x,
                    -leg.base_mm.y,
                    home_height_mm - leg.base_mm.z,
                ],
                plane: [cos_beta, sin_beta],
                n_mm: [two_arm_mm * cos_beta, two_arm_mm * sin_beta],
                alpha0_rad: 0.0,
            }
        });
        let float = FloatTable {
            rod_sq_minus_arm_sq: rod_mm * rod_mm - arm_mm * arm_mm,
            two_arm_mm,
            planar_platform: legs.iter().all(|leg| leg.platform_mm.z == 0.0),
            flat_base: legs.iter().all(|leg| leg.base_mm.z == legs[0].base_mm.z),
            legs: float_legs,
        };
        let rod_term_mm2 =
            f64::from(rod_mm) * f64::from(rod_mm) - f64::from(arm_mm) * f64::from(arm_mm);
        let fixed_point = float.planar_platform
            && two_arm_mm < MAX_FIXED_TWO_ARM_MM
            && libm::fabs(rod_term_mm2) < f64::from(MAX_FIXED_ROD_TERM_MM2)
            && float.legs.iter().all(|c| {
                c.platform_mm
                    .iter()
                    .chain(c.offset_mm.iter())
                    .all(|v| v.abs() < MAX_FIXED_MM)
            });
        let fixed = fixed_point.then(|| {
            let two_arm_q = to_fixed(two_arm_mm, MM_FRAC);
            let narrow = (0.0..MAX_NARROW_ROD_TERM_MM2).contains(&rod_term_mm2)
                && two_arm_mm < MAX_NARROW_TWO_ARM_MM;
            FixedTable {
                rod_term_q: to_fixed_sq(rod_term_mm2),
                two_arm_q,
                two_arm_split: split13(two_arm_q),
                narrow_rod_term_q: narrow
                    .then(|| libm::round(rod_term_mm2 * f64::from(1u32 << NARROW_SQ_FRAC)) as i32),
                centre: FixedCentre::Origin,
                legs: core::array::from_fn(|i| {
                    let (leg, c) = (&legs[i], &float.legs[i]);
                    // 2a (cos(beta), sin(beta)) from `M`'s fixed-point sine and cosine, exactly
                    // rounded to 2^-20 mm (|n| <= 2a: within range): the same bits on every
                    // machine, like the rest of the fixed-point path.
                    let (sin_q, cos_q) = M::sin_cos_fixed(leg.beta_rad);
                    let round = |v: i64| ((v + (1 << (ROT_FRAC - 1))) >> ROT_FRAC) as i32;
                    let n_q = [
                        round(wide_mul(two_arm_q, cos_q)),
                        round(wide_mul(two_arm_q, sin_q)),
                    ];
                    FixedLeg {
                        platform_split: [0, 1]
                            .map(|k| split15(to_fixed(c.platform_mm[k], MM_FRAC))),
                        offset_q: [0, 1, 2].map(|k| to_fixed(c.offset_mm[k], MM_FRAC)),
                        n_q,
                        n_split: n_q.map(split13),
                        alpha0_q: 0,
                        alpha0_wrapped_q: 0,
                    }
                }),
            }
        });
        let mut solver = Solver {
            geometry,
            centre_mm: [0.0; 3],
            float,
            fixed,
        };
        // Eq. 12 is eq. 9 at the home pose (with eq. 9's naming: M0 = 2a(h0 + z_p - z_b),
        // N0 = 2a[cos(beta)(x_p - x_b) + sin(beta)(y_p - y_b)], L0 = 2a^2 when the legs agree
        // exactly). Evaluating eq. 9 itself at home gives the exact alpha0 of every leg: with
        // each path (float, fixed point), so that each gives exactly the home pulses at home.
        let unreachable = |leg| GeometryError::HomeUnreachable { leg };
        let float_home = solver
            .float
            .arm_angles::<M>(&solver.centre_mm, &Pose::HOME)
            .map_err(unreachable)?;
        for (c, alpha0) in solver.float.legs.iter_mut().zip(float_home) {
            c.alpha0_rad = alpha0;
        }
        if let Some(table) = solver.fixed {
            // (No pose at home only for a `Math` whose sines break the bounds of `fixed` there:
            // then no fixed-point path.)
            solver.fixed = match table.pose::<M>(&Pose::HOME) {
                Some(home) => {
                    let alpha0 = table.arm_angles::<M>(&home).map_err(unreachable)?;
                    let mut table = table;
                    for (c, alpha0) in table.legs.iter_mut().zip(alpha0) {
                        c.alpha0_q = alpha0;
                        c.alpha0_wrapped_q = wrap_fixed(alpha0);
                    }
                    Some(table)
                }
                None => None,
            };
        }
        Ok(solver)
    }

    /// The geometry this solver solves.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// Home arm angle `alpha0` (eq. 12) of leg `index` (0..=5), rad, above horizontal: the
    /// fixed-point path's where the build has one, else the float path's.
    pub fn alpha0_rad(&self, index: usize) -> f32 {
        match &self.fixed {
            Some(table) => from_fixed(i64::from(table.legs[index].alpha0_q), ARM_FRAC),
            None => self.float.legs[index].alpha0_rad,
        }
    }

    /// `(cos(beta_i), sin(beta_i))` of leg `index` (0..=5): the direction of its arm's plane.
    pub fn arm_plane(&self, index: usize) -> [f32; 2] {
        self.float.legs[index].plane
    }

    /// The rotation centre `c`, platform frame, mm (see [`crate::configuration`]).
    pub fn rotation_centre_mm(&self) -> Vec3 {
        Vec3::from(self.centre_mm)
    }

    /// Sets the rotation centre `c` (platform frame, mm): from now on the platform turns about
    /// it, and a pose's `(x, y, z)` is how far `c` moved from its home position. The geometry,
    /// the home pose and `alpha0` do not change (at home `R = I`). Refused if not finite or
    /// farther than [`crate::configuration::MAX_CENTRE_MM`] from the platform frame's origin.
    pub fn set_rotation_centre_mm(&mut self, centre_mm: Vec3) -> Result<(), ConfigurationError> {
        let c = check_centre(centre_mm)?;
        self.centre_mm = c.into();
        if let Some(table) = &mut self.fixed {
            table.centre = if c == Vec3::zeros() {
                FixedCentre::Origin
            } else if self.centre_mm.iter().all(|v| below(v.abs(), MAX_FIXED_MM)) {
                FixedCentre::At(self.centre_mm.map(|v| to_fixed(v, MM_FRAC)))
            } else {
                FixedCentre::Beyond
            };
        }
        Ok(())
    }

    /// [`Solver::set_rotation_centre_mm`], by value.
    pub fn with_rotation_centre_mm(
        mut self,
        centre_mm: Vec3,
    ) -> Result<Solver, ConfigurationError> {
        self.set_rotation_centre_mm(centre_mm)?;
        Ok(self)
    }

    /// The anchors this solver works with: servo shafts, platform joints, `h0`, the rotation
    /// centre (for the kinematics outside the IK: Jacobian, statics, forward kinematics).
    pub fn anchors(&self) -> Anchors {
        let legs = self.geometry.legs();
        Anchors {
            base_mm: core::array::from_fn(|i| legs[i].base_mm),
            platform_mm: core::array::from_fn(|i| legs[i].platform_mm),
            home_height_mm: self.geometry.home_height_mm(),
            rotation_centre_mm: self.rotation_centre_mm(),
        }
    }

    /// Arm angles `alpha_i` for a pose (eq. 9), rad, each within `(-pi, pi]` of its `alpha0`.
    pub fn arm_angles<M: Math>(&self, pose: &Pose) -> Result<[f32; LEGS], IkError> {
        check_pose(pose)?;
        let unreachable = |leg| IkError::Unreachable { leg };
        if let Some((table, fixed)) = self.fixed_pose::<M>(pose) {
            let alpha = table.arm_angles::<M>(&fixed).map_err(unreachable)?;
            return Ok(core::array::from_fn(|i| {
                let c = &table.legs[i];
                arm_rad_fixed(c.alpha0_q, offset_fixed(alpha[i], c.alpha0_wrapped_q))
            }));
        }
        let mut alpha = self
            .float
            .arm_angles::<M>(&self.centre_mm, pose)
            .map_err(unreachable)?;
        for (a, c) in alpha.iter_mut().zip(&self.float.legs) {
            let alpha0 = Real::<M>::new(c.alpha0_rad);
            let offset = wrap_angle_rad::<M>((Real::new(*a) - alpha0).0);
            *a = (alpha0 + Real::new(offset)).0;
        }
        Ok(alpha)
    }

    /// Arm angles and pulse widths for a pose (eq. 9, 13, 14): all six or an error naming the
    /// first leg or servo that cannot follow. The pulses come from each arm's offset from home,
    /// `alpha_i - alpha0_i` wrapped into `(-pi, pi]` (eq. 13, 14 use it), not from the angles,
    /// which saves a subtraction per servo. On the fixed-point path they are computed in fixed
    /// point too (`ServoConfig::pulse_us_for_fixed_offset`), each pulse and angle rounded once to
    /// `f32`: no float operation at all (each is a library call on the RP2040).
    pub fn solve<M: Math>(&self, servos: &ServoSet, pose: &Pose) -> Result<Solution, IkError> {
        check_pose(pose)?;
        let unreachable = |leg| IkError::Unreachable { leg };
        let limit = |i: usize, servo: &ServoConfig, pulse_us: f32| IkError::ServoLimit {
            servo: i as u8 + 1,
            pulse_us,
            min_us: servo.min_us,
            max_us: servo.max_us,
        };
        if let Some((table, fixed)) = self.fixed_pose::<M>(pose) {
            let mut alpha = [0i32; LEGS];
            table
                .arm_angles_into::<M>(&fixed, &mut alpha)
                .map_err(unreachable)?;
            // Each arm's offset from home, in place; then every pulse and the limits (the first
            // servo beyond them is named); then the angles, written straight into the solution
            // (no zero-filled arrays to copy).
            for (a, c) in alpha.iter_mut().zip(&table.legs) {
                *a = offset_fixed(*a, c.alpha0_wrapped_q);
            }
            let pulse_us: [f32; LEGS] =
                core::array::from_fn(|i| servos.0[i].pulse_us_for_fixed_offset::<M>(alpha[i]));
            for (i, servo) in servos.0.iter().enumerate() {
                if !servo.allows(pulse_us[i]) {
                    return Err(limit(i, servo, pulse_us[i]));
                }
            }
            return Ok(Solution {
                arm_rad: core::array::from_fn(|i| arm_rad_fixed(table.legs[i].alpha0_q, alpha[i])),
                pulse_us,
            });
        }
        let alpha = self
            .float
            .arm_angles::<M>(&self.centre_mm, pose)
            .map_err(unreachable)?;
        let mut arm_rad = [0.0f32; LEGS];
        let mut pulse_us = [0.0f32; LEGS];
        for (i, servo) in servos.0.iter().enumerate() {
            let alpha0 = Real::<M>::new(self.float.legs[i].alpha0_rad);
            let offset = wrap_angle_rad::<M>((Real::new(alpha[i]) - alpha0).0);
            let pulse = servo.pulse_us_for_offset::<M>(offset);
            if !servo.allows(pulse) {
                return Err(limit(i, servo, pulse));
            }
            pulse_us[i] = pulse;
            arm_rad[i] = (alpha0 + Real::new(offset)).0;
        }
        Ok(Solution { arm_rad, pulse_us })
    }

    /// The fixed-point path's table and the pose's part of eq. 2, 3 on it, where this build
    /// and pose take that path (every usual build and pose).
    #[inline(always)]
    fn fixed_pose<M: Math>(&self, pose: &Pose) -> Option<(&FixedTable, FixedPose)> {
        let table = self.fixed.as_ref()?;
        Some((table, table.pose::<M>(pose)?))
    }
}

impl FixedTable {
    /// The pose's part of eq. 2, 3 in fixed point, or `None` where the float path must run: a
    /// position beyond `fixed::MAX_FIXED_MM`, a rotation centre beyond it, or a translation
    /// with `c - R c` beyond it. `R` (eq. 1) comes from `M`'s fixed-point sines and cosines
    /// ([`Pose::rotation_fixed`]); the pose must be finite.
    #[inline(always)]
    fn pose<M: Math>(&self, pose: &Pose) -> Option<FixedPose> {
        let position = [pose.x_mm, pose.y_mm, pose.z_mm];
        if !position.iter().all(|v| below(v.abs(), MAX_FIXED_MM)) {
            return None;
        }
        let centre = match self.centre {
            FixedCentre::Origin => None,
            FixedCentre::At(c) => Some(c),
            FixedCentre::Beyond => return None,
        };
        // The platform is planar: `R`'s third column only turns the centre's `z`.
        // (Every entry within `fixed::MAX_ROTATION_ENTRY`, whatever the sines of the `Math`
        // in use: the bounds of `fixed` hold.)
        let r = pose.rotation_fixed::<M>(centre.is_some_and(|c| c[2] != 0))?;
        // (Written out: `map` here is a call of its own on the chip.)
        let mut position = [
            to_fixed(position[0], MM_FRAC),
            to_fixed(position[1], MM_FRAC),
            to_fixed(position[2], MM_FRAC),
        ];
        if let Some(c) = centre {
            // About the rotation centre c: q = T + c + R (p - c) = (T + c - R c) + R p, with
            // R c exact and rounded once to 2^-20 mm (|c_k| < 384 mm: no overflow).
            for (k, t) in position.iter_mut().enumerate() {
                let rc =
                    wide_mul(r[k][0], c[0]) + wide_mul(r[k][1], c[1]) + wide_mul(r[k][2], c[2]);
                *t += c[k] - (((rc >> (ROT_FRAC - 1)) + 1) >> 1) as i32;
            }
            let bound = to_fixed(MAX_FIXED_MM, MM_FRAC).unsigned_abs();
            if !position.iter().all(|t| t.unsigned_abs() < bound) {
                return None;
            }
        }
        Some(FixedPose {
            rows: r.map(|row| [split15(row[0]), split15(row[1])]),
            position,
        })
    }

    /// The firmware's hot loop: eq. 2, 3 and 9 for all legs in fixed point (module
    /// [`crate::fixed`]), arm angles in steps of 2^-28 rad; `Err(leg number)` if a leg cannot
    /// reach.
    ///
    /// Per leg: `l = R p + (x, y, z) + ((0, 0, h0) - b)` (eq. 2, 3) in steps of 2^-20 mm (`R p`
    /// within 2 steps, unbiased); `|l|^2`, `L`, `N`, `M` of eq. 9 in 32-bit words, in steps of
    /// 2^-15 mm^2 (products rounded once: [`FixedTable::narrow_terms`], every usual leg), or
    /// beyond that path's bounds in 64-bit words, in steps of 2^-36 mm^2 (exact products cut
    /// once: [`FixedTable::wide_terms`]); then `M`, `L - N`, `L + N` scaled by one power of two
    /// (the root depends only on their ratios): the 64-bit path's to about 29 bits, the 32-bit
    /// path's only where they pass 2^29 ([`scale_terms32`]), then the discriminant
    /// `D = M^2 - (L - N)(L + N) = M^2 + N^2 - L^2` exactly, and the half-angle root (module
    /// docs) from `M`'s fixed-point square root and arc tangent ([`Math::sqrt_fixed`],
    /// [`Math::atan2_fixed`]: by default the core's integer routines, so the host runs exactly
    /// what the chip runs). No float arithmetic at all: on the RP2040 each float operation is a
    /// library call.
    #[inline(always)]
    fn arm_angles<M: Math>(&self, fixed: &FixedPose) -> Result<[i32; LEGS], u8> {
        let mut alpha = [0i32; LEGS];
        self.arm_angles_into::<M>(fixed, &mut alpha)?;
        Ok(alpha)
    }

    /// [`FixedTable::arm_angles`] written into `alpha` (the hot path's form: returning the
    /// array inside a `Result` costs a copy of it on the chip).
    #[inline(always)]
    fn arm_angles_into<M: Math>(
        &self,
        fixed: &FixedPose,
        alpha: &mut [i32; LEGS],
    ) -> Result<(), u8> {
        for (i, c) in self.legs.iter().enumerate() {
            let l = leg_vector(c, fixed);
            let terms = match self.narrow_terms(c, l) {
                Some(terms) => terms,
                None => self.wide_terms(c, l[0], l[1], l[2]),
            };
            alpha[i] = half_angle::<M>(terms).ok_or(i as u8 + 1)?;
        }
        Ok(())
    }

    /// The usual way to `M`, `L - N` and `L + N` of eq. 9 for one leg `l` (steps of 2^-20 mm),
    /// in 32-bit words ([`scale_terms32`]), where the build allows it and every `|l_k|` is below
    /// 256 mm (`fixed::NARROW_LEG_Q`), `|l|^2` below 2^16 mm^2 and `L +- N` within an `i32`;
    /// `None` otherwise (the leg then takes [`FixedTable::wide_terms`]: far outside any usual
    /// pose, or a build with a long arm or rod).
    ///
    /// Why each step stays in range: `|l|^2` (`fixed::leg_square_narrow`: the sum of three
    /// squares rounded once) is required below 2^31 steps of 2^-15 mm^2; `s^2 - a^2` is in `[0, 2^31)` steps, so `L` fits; `|n_k| <= 2a < 128 mm` and
    /// `|l_k| < 256 mm` keep each product of `N` and `M` below 2^30 steps (within 2^30 - 11
    /// rounded), so `N` fits; `L - N` and `L + N` are checked. The terms are then exact
    /// sums of products rounded to 2^-15 mm^2 (`|l|^2` within 0.51 of a step, each product of
    /// `N` and `M` too), against the 2^-36 mm^2 of
    /// the 64-bit path: the rounding of `l` to 2^-21 mm already moves `L` by more.
    #[inline(always)]
    fn narrow_terms(&self, c: &FixedLeg, l: [i32; 3]) -> Option<[i32; 3]> {
        let rod_term = self.narrow_rod_term_q?;
        let [l_x, l_y, l_z] = l;
        if l_x.unsigned_abs() | l_y.unsigned_abs() | l_z.unsigned_abs() >= NARROW_LEG_Q {
            return None;
        }
        let leg_sq = leg_square_narrow(l)?;
        let big_l = leg_sq as i32 - rod_term;
        let big_n = mul_mm_narrow(c.n_split[0], l_x) + mul_mm_narrow(c.n_split[1], l_y);
        let big_m = mul_mm_narrow(self.two_arm_split, l_z);
        Some(scale_terms32([
            big_m,
            big_l.checked_sub(big_n)?,
            big_l.checked_add(big_n)?,
        ]))
    }

    /// `M`, `L - N` and `L + N` of eq. 9 for one leg `l` (steps of 2^-20 mm) in 64-bit words,
    /// for every leg within the bounds of module `fixed` (the legs
    /// [`FixedTable::narrow_terms`] leaves out): `|l|^2`, `L`, `N`, `M` in steps of 2^-36 mm^2
    /// (exact products cut once), then scaled ([`scale_terms`]).
    #[inline(never)]
    fn wide_terms(&self, c: &FixedLeg, l_x: i32, l_y: i32, l_z: i32) -> [i32; 3] {
        // L = |l|^2 - (s^2 - a^2), N = 2a (cos(beta) l_x + sin(beta) l_y), M = 2a l_z
        // (eq. 9): products of two 2^-20 mm numbers, cut to 2^-36 mm^2.
        let leg_sq = square_mm(l_x) + square_mm(l_y) + square_mm(l_z);
        let big_l = leg_sq - self.rod_term_q;
        let big_n = mul_mm(c.n_q[0], l_x) + mul_mm(c.n_q[1], l_y);
        let big_m = mul_mm(self.two_arm_q, l_z);
        scale_terms([big_m, big_l - big_n, big_l + big_n])
    }
}

impl FloatTable {
    /// The float path of eq. 2, 3 and 9, for builds and poses beyond the fixed-point bounds:
    /// per leg, `l = R p + (x, y, z) + ((0, 0, h0) - b)`, then `L`, `M`, `N` and the half-angle
    /// root, float arithmetic through `M` ([`Real`]). With `L - N` and `L + N` at hand, the
    /// discriminant is `D = M^2 - (L - N)(L + N)`. `Err(leg number)` if a leg cannot reach.
    fn arm_angles<M: Math>(&self, centre_mm: &[f32; 3], pose: &Pose) -> Result<[f32; LEGS], u8> {
        // `R`'s third column turns the platform joints' and the centre's `z`.
        let r = pose.rotation_columns::<M>(!self.planar_platform || !is_zero(centre_mm[2]));
        let real = Real::<M>::new;
        let row = |i: usize| [real(r[(i, 0)]), real(r[(i, 1)]), real(r[(i, 2)])];
        let rows = [row(0), row(1), row(2)];
        let mut translation = [pose.x_mm, pose.y_mm, pose.z_mm];
        if !centre_mm.iter().all(|v| is_zero(*v)) {
            // About the rotation centre c: q = T + c + R (p - c) = (T + c - R c) + R p.
            let c = centre_mm.map(real);
            for (k, t) in translation.iter_mut().enumerate() {
                let rc = rows[k][0] * c[0] + rows[k][1] * c[1] + rows[k][2] * c[2];
                *t = (real(*t) + (c[k] - rc)).0;
            }
        }
        let position = translation.map(real);
        let rod_sq_minus_arm_sq = real(self.rod_sq_minus_arm_sq);
        let two_arm = real(self.two_arm_mm);
        // With a flat base every leg has the same z offset: `z + offset_z` once for all legs
        // (the same sum each leg would compute).
        let shared_z = position[2] + real(self.legs[0].offset_mm[2]);
        let mut alpha = [0.0f32; LEGS];
        for (i, c) in self.legs.iter().enumerate() {
            // `M`, `L - N` and `L + N` of eq. 9, mm^2.
            let p = c.platform_mm.map(real);
            let l: [Real<M>; 3] = core::array::from_fn(|k| {
                let rp = if self.planar_platform {
                    rows[k][0] * p[0] + rows[k][1] * p[1]
                } else {
                    rows[k][0] * p[0] + rows[k][1] * p[1] + rows[k][2] * p[2]
                };
                let translation = if k == 2 && self.flat_base {
                    shared_z
                } else {
                    position[k] + real(c.offset_mm[k])
                };
                rp + translation
            });
            let leg_sq = l[0] * l[0] + l[1] * l[1] + l[2] * l[2];
            let big_m = two_arm * l[2];
            let big_n = real(c.n_mm[0]) * l[0] + real(c.n_mm[1]) * l[1];
            let bounded = below(leg_sq.0, MAX_TERM_MM2)
                && below(big_m.0.abs(), MAX_TERM_MM2)
                && below(big_n.0.abs(), MAX_TERM_MM2);
            if !bounded {
                return Err(i as u8 + 1);
            }
            let big_l = leg_sq - rod_sq_minus_arm_sq;
            let (l_minus_n, l_plus_n) = (big_l - big_n, big_l + big_n);
            let discriminant = big_m * big_m - l_minus_n * l_plus_n;
            if !below(discriminant.0, f32::INFINITY) {
                return Err(i as u8 + 1);
            }
            // The two equal forms of the root; use the one that cannot be 0/0 (see module docs).
            let root = real(M::sqrt(discriminant.0));
            // (-0 may take either form: only M = 0 with D = 0 is 0/0, and only in one of them.)
            let half = if big_m.0.is_sign_positive() {
                M::atan2(l_minus_n.0, (big_m + root).0)
            } else {
                M::atan2((big_m - root).0, l_plus_n.0)
            };
            let a = twice::<M>(half);
            if !below(a.abs(), f32::INFINITY) {
                return Err(i as u8 + 1);
            }
            alpha[i] = a;
        }
        Ok(alpha)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Leg;
    use crate::test_support::uniform;

    /// Eq. 9's arm angles of all six legs, from either path.
    #[derive(Debug, Clone, Copy, PartialEq)]
    enum Angles {
        /// The fixed-point path's: rad, in steps of 2^-28 (`fixed::ARM_FRAC`).
        Fixed([i32; LEGS]),
        /// The float path's, rad.
        Float([f32; LEGS]),
    }

    impl Angles {
        /// The angles in rad.
        fn rad(&self) -> [f32; LEGS] {
            match *self {
                Angles::Fixed(a) => a.map(|a| from_fixed(i64::from(a), ARM_FRAC)),
                Angles::Float(a) => a,
            }
        }
    }

    /// Eq. 9 for all legs without the pose checks; `Err(leg number)` if a leg cannot reach.
    /// The fixed-point path where the solver takes it (every usual build and pose), else the
    /// float path (the steps [`Solver::solve`] takes).
    fn arm_angles_raw<M: Math>(solver: &Solver, pose: &Pose) -> Result<Angles, u8> {
        match solver.fixed_pose::<M>(pose) {
            Some((table, fixed)) => table.arm_angles::<M>(&fixed).map(Angles::Fixed),
            None => solver
                .float
                .arm_angles::<M>(&solver.centre_mm, pose)
                .map(Angles::Float),
        }
    }

    /// Eq. 9 (half-angle form, as in [`Solver::solve`]) for one leg in `f64`, rad.
    fn arm_angle_f64(g: &Geometry, pose: &Pose, leg: usize) -> f64 {
        let (sr, cr) = libm::sincos(f64::from(pose.roll_rad));
        let (sp, cp) = libm::sincos(f64::from(pose.pitch_rad));
        let (sy, cy) = libm::sincos(f64::from(pose.yaw_rad));
        let r = [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ];
        let t = [
            f64::from(pose.x_mm),
            f64::from(pose.y_mm),
            f64::from(g.home_height_mm()) + f64::from(pose.z_mm),
        ];
        let Leg {
            base_mm: b,
            platform_mm: p,
            beta_rad,
        } = *g.leg(leg);
        let (p, b) = (
            [p.x, p.y, p.z].map(f64::from),
            [b.x, b.y, b.z].map(f64::from),
        );
        let l: [f64; 3] =
            core::array::from_fn(|k| t[k] + (0..3).map(|j| r[k][j] * p[j]).sum::<f64>() - b[k]);
        let (a, s) = (f64::from(g.arm_mm()), f64::from(g.rod_mm()));
        let (sin_beta, cos_beta) = libm::sincos(f64::from(beta_rad));
        let big_l = l.iter().map(|v| v * v).sum::<f64>() - (s * s - a * a);
        let big_m = 2.0 * a * l[2];
        let big_n = 2.0 * a * (cos_beta * l[0] + sin_beta * l[1]);
        let root = libm::sqrt(big_m * big_m + big_n * big_n - big_l * big_l);
        if big_m >= 0.0 {
            2.0 * libm::atan2(big_l - big_n, big_m + root)
        } else {
            2.0 * libm::atan2(big_m - root, big_l + big_n)
        }
    }

    #[test]
    fn fixed_point_path_is_more_accurate_than_float() {
        let g = Geometry::default();
        let solver = Solver::new(g.clone()).expect("a valid geometry");
        assert!(solver.fixed.is_some());
        let mut float = solver.clone();
        float.fixed = None;
        let (mut worst_fixed, mut worst_float) = (0.0f64, 0.0f64);
        for i in 0..2000 {
            let t = i as f32 * 0.01;
            let pose = Pose::from_degrees(
                20.0 * libm::sinf(t),
                20.0 * libm::cosf(1.3 * t),
                10.0 * libm::sinf(0.7 * t),
                8.0 * libm::sinf(1.1 * t),
                8.0 * libm::cosf(0.9 * t),
                15.0 * libm::sinf(0.5 * t),
            );
            match (
                arm_angles_raw::<Libm>(&solver, &pose),
                arm_angles_raw::<Libm>(&float, &pose),
            ) {
                (Ok(a), Ok(b)) => {
                    assert!(matches!((a, b), (Angles::Fixed(_), Angles::Float(_))));
                    let (a, b) = (a.rad(), b.rad());
                    for leg in 0..LEGS {
                        let exact = arm_angle_f64(&g, &pose, leg);
                        worst_fixed = worst_fixed.max((f64::from(a[leg]) - exact).abs());
                        worst_float = worst_float.max((f64::from(b[leg]) - exact).abs());
                    }
                }
                (a, b) => assert_eq!(a.is_ok(), b.is_ok(), "{pose:?}"),
            }
        }
        eprintln!("fixed {worst_fixed:e} rad, float {worst_float:e} rad");
        // Measured: 1.8e-6 rad fixed point, 1.0e-5 rad float (the rest is the f32 rotation,
        // discriminant and atan2). 1e-5 rad is ~0.005 us of pulse.
        assert!(worst_fixed < 3e-6, "fixed point: {worst_fixed:e} rad");
        assert!(worst_float < 3e-5, "float: {worst_float:e} rad");
        assert!(
            worst_fixed < worst_float,
            "{worst_fixed:e} vs {worst_float:e}"
        );
    }

    #[test]
    fn fixed_point_path_holds_up_to_its_bounds() {
        use crate::geometry::PairedLayout;
        // Builds near the bounds of the fixed-point path (offsets up to ~380 mm, 2a up to
        // 760 mm), which must take it, and poses out to its limits: integer overflow would
        // panic in this (debug) build; reachable poses must agree with eq. 9 in f64.
        let builds = [
            PairedLayout {
                base_radius_mm: 240.0,
                platform_radius_mm: 192.0,
                arm_mm: 64.0,
                rod_mm: 384.0,
                ..PairedLayout::default()
            },
            PairedLayout {
                base_radius_mm: 370.0,
                platform_radius_mm: 330.0,
                arm_mm: 380.0,
                rod_mm: 120.0,
                ..PairedLayout::default()
            },
        ];
        let mut next = uniform(0x9e37_79b9_u32);
        for build in builds {
            let g = build.build().unwrap();
            let solver = Solver::new(g.clone()).expect("a valid geometry");
            assert!(solver.fixed.is_some(), "{build:?}");
            let (mut ok, mut worst) = (0, 0.0f64);
            for i in 0..4000 {
                // Half the poses small, half out to the fixed-point limits.
                let (mm, deg) = if i % 2 == 0 {
                    (20.0, 10.0)
                } else {
                    (383.0, 180.0)
                };
                let pose = Pose::from_degrees(
                    next(mm),
                    next(mm),
                    next(mm),
                    next(deg),
                    next(deg),
                    next(deg),
                );
                if let Ok(alpha) = arm_angles_raw::<Libm>(&solver, &pose) {
                    ok += 1;
                    for (leg, a) in alpha.rad().iter().enumerate() {
                        let d = (f64::from(*a) - arm_angle_f64(&g, &pose, leg)).abs();
                        worst = worst.max(d.min((d - 2.0 * core::f64::consts::PI).abs()));
                    }
                }
            }
            assert!(ok > 500, "{build:?}: {ok} reachable poses");
            assert!(worst < 2e-5, "{build:?}: {worst:e} rad");
        }
        // One step past a bound the float path takes over.
        let past = PairedLayout {
            arm_mm: 385.0,
            ..builds[1]
        };
        assert!(Solver::new(past.build().unwrap())
            .expect("a valid geometry")
            .fixed
            .is_none());
    }

    #[test]
    fn narrow_and_wide_terms_give_the_same_angles() {
        use crate::geometry::PairedLayout;
        // The default build, whose every leg of every usual pose takes the 32-bit path, and a
        // long one (rod 250 mm, arm 60 mm) whose far-reaching legs pass 256 mm and take the
        // 64-bit path: for every leg the 32-bit terms give (where they apply) the 64-bit
        // terms' angle within a few steps of 2^-28 rad, and each path is taken.
        let long = PairedLayout {
            base_radius_mm: 150.0,
            platform_radius_mm: 120.0,
            arm_mm: 60.0,
            rod_mm: 250.0,
            ..PairedLayout::default()
        };
        let mut next = uniform(0x5eed_1234_u32);
        for (g, mm, deg) in [
            (Geometry::default(), 20.0, 15.0),
            (long.build().unwrap(), 80.0, 25.0),
        ] {
            let solver = Solver::new(g).expect("a valid geometry");
            let table = solver.fixed.expect("the fixed-point path");
            assert!(table.narrow_rod_term_q.is_some());
            let (mut narrow, mut wide) = (0, 0);
            // The largest error against eq. 9 in f64 of either path, rad, where they differ,
            // and the largest difference, in steps of 2^-28 rad.
            let (mut worst_narrow, mut worst_wide, mut apart) = (0.0f64, 0.0f64, 0);
            for _ in 0..3000 {
                let pose = Pose::from_degrees(
                    next(mm),
                    next(mm),
                    next(mm),
                    next(deg),
                    next(deg),
                    next(deg),
                );
                let fixed = table.pose::<Libm>(&pose).expect("within the bounds");
                for (leg, c) in table.legs.iter().enumerate() {
                    let l = leg_vector(c, &fixed);
                    let exact = half_angle::<Libm>(table.wide_terms(c, l[0], l[1], l[2]));
                    match table.narrow_terms(c, l) {
                        Some(terms) => {
                            let a = half_angle::<Libm>(terms);
                            assert_eq!(a.is_some(), exact.is_some(), "{pose:?}");
                            if let (Some(a), Some(b)) = (a, exact) {
                                narrow += 1;
                                if a != b {
                                    let f64_rad = arm_angle_f64(solver.geometry(), &pose, leg);
                                    let error = |q: i32| {
                                        let d = (f64::from(q) / f64::from(1u32 << ARM_FRAC)
                                            - f64_rad)
                                            .abs();
                                        d.min((d - 2.0 * core::f64::consts::PI).abs())
                                    };
                                    worst_narrow = worst_narrow.max(error(a));
                                    worst_wide = worst_wide.max(error(b));
                                    apart = apart.max((a - b).abs());
                                }
                            }
                        }
                        None => wide += usize::from(exact.is_some()),
                    }
                }
            }
            eprintln!(
                "{narrow} legs narrow, {wide} wide; where they differ (at most {apart} steps of \
                 2^-28 rad) narrow {worst_narrow:e} rad, wide {worst_wide:e} rad from f64"
            );
            assert!(narrow > 1000, "{narrow}");
            // Where they differ (near the edge of the workspace, where the angle is most
            // sensitive to `L`), the 32-bit path is about as far from eq. 9 in f64 as the
            // 64-bit one (measured: 1.7e-6 and 1.5e-6 rad on the default build; the rounding
            // of `R p` to 2^-21 mm, common to both, dominates), and within the fixed-point
            // bound of `fixed_point_path_is_more_accurate_than_float`.
            assert!(worst_narrow < 3e-6, "{worst_narrow:e} rad");
            assert!(
                worst_narrow <= 1.5 * worst_wide + 1e-7,
                "{worst_narrow:e} vs {worst_wide:e} rad"
            );
            if mm > 50.0 {
                assert!(wide > 100, "{wide} legs beyond the 32-bit bounds");
            } else {
                assert_eq!(wide, 0, "a usual pose left the 32-bit path");
            }
        }
    }

    #[test]
    fn check_pose_agrees_with_float_comparisons() {
        // The integer fast path and the checks after it against the plain rule in float
        // comparisons: the first non-finite coordinate in pose order, else the first angle
        // beyond pi, over values at and around every bound, in every position.
        let expected = |pose: &Pose| -> Result<(), IkError> {
            let v = pose.to_array();
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(IkError::NonFinite { axis: Axis::ALL[k] });
            }
            match (3..6).find(|&k| v[k].abs() > PI) {
                Some(k) => Err(IkError::AngleTooLarge {
                    axis: Axis::ALL[k],
                    value_rad: v[k],
                }),
                None => Ok(()),
            }
        };
        let above_pi = f32::from_bits(PI.to_bits() + 1);
        let values = [
            0.0,
            -0.0,
            1e-45,
            1.0,
            -2.5,
            PI,
            -PI,
            above_pi,
            -above_pi,
            4.0,
            f32::MAX,
            -f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        let mut seed = 0x0c0f_fee5_u32;
        for _ in 0..20_000 {
            let mut v = [0.0f32; 6];
            for x in v.iter_mut() {
                let r = crate::test_support::xorshift(&mut seed);
                // Mostly ordinary values, one in four a bound or its neighbour.
                *x = if r % 4 == 0 {
                    values[(r >> 8) as usize % values.len()]
                } else {
                    (r >> 8) as f32 / (1u32 << 24) as f32 * 7.0 - 3.5
                };
            }
            let pose = Pose::from_array(v);
            assert_eq!(check_pose(&pose), expected(&pose), "{v:?}");
        }
        for &x in &values {
            for k in 0..6 {
                let mut v = [0.1f32; 6];
                v[k] = x;
                let pose = Pose::from_array(v);
                assert_eq!(check_pose(&pose), expected(&pose), "{v:?}");
            }
        }
    }

    #[test]
    fn narrow_terms_are_brought_within_2_29() {
        // Against the plain rule in 64 bits: unchanged when every term is in [-2^29, 2^29),
        // else divided by 2 (every term in [-2^30, 2^30)) or 4, rounded to nearest (halves
        // up); within 2^29 in magnitude either way, as `half_angle` needs.
        let expected = |terms: [i32; 3]| {
            let within = |k: u32| {
                terms
                    .iter()
                    .all(|&t| (-(1i64 << k)..1 << k).contains(&t.into()))
            };
            let shift = if within(29) {
                0
            } else if within(30) {
                1
            } else {
                2
            };
            terms.map(|t| {
                let t = i64::from(t);
                (if shift == 0 {
                    t
                } else {
                    (t + (1 << (shift - 1))) >> shift
                }) as i32
            })
        };
        let mut seed = 0x5ca1_ab1e_u32;
        let extremes = [
            0,
            1,
            -1,
            1 << 29,
            -(1 << 29),
            (1 << 29) - 1,
            1 << 30,
            -(1 << 30),
        ];
        let extremes = [extremes.as_slice(), &[i32::MAX, i32::MIN, i32::MIN + 1]].concat();
        for i in 0..300_000 {
            let mut next = || {
                let r = crate::test_support::xorshift(&mut seed);
                if i % 8 == 0 {
                    extremes[r as usize % extremes.len()]
                } else {
                    (r as i32) >> (r % 31)
                }
            };
            let terms = [next(), next(), next()];
            let scaled = scale_terms32(terms);
            assert_eq!(scaled, expected(terms), "{terms:?}");
            assert!(
                scaled.iter().all(|t| t.unsigned_abs() <= 1 << 29),
                "{terms:?}"
            );
        }
    }

    #[test]
    fn wrap_angle_stays_in_range() {
        assert!((wrap_angle_rad::<Libm>(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-6);
        assert!((wrap_angle_rad::<Libm>(-3.0 * PI / 2.0) - PI / 2.0).abs() < 1e-6);
        assert_eq!(wrap_angle_rad::<Libm>(0.5), 0.5);
    }

    #[test]
    fn twice_is_x_plus_x() {
        for x in [
            0.0f32,
            -0.0,
            1e-45,
            -1e-40,
            f32::MIN_POSITIVE,
            -1.0,
            0.8,
            -3.0,
            1.7e38,
            -1.7e38,
            3e38,
        ] {
            assert_eq!(twice::<Libm>(x).to_bits(), (x + x).to_bits(), "{x}");
        }
    }

    #[test]
    fn default_home_arm_angles_are_symmetric_and_near_horizontal() {
        let g = Solver::new(Geometry::default()).expect("a valid geometry");
        let a0 = g.alpha0_rad(0);
        for i in 0..LEGS {
            assert!((g.alpha0_rad(i) - a0).abs() < 1e-5, "leg {i}");
        }
        // The default is chosen with the arms close to horizontal at home.
        assert!(
            a0.abs() < 0.5f32.to_radians(),
            "alpha0 = {} deg",
            a0.to_degrees()
        );
    }

    #[test]
    fn at_home_every_arm_and_rod_are_at_right_angles() {
        let solver = Solver::new(Geometry::default()).expect("a valid geometry");
        let g = solver.geometry();
        for (i, leg) in g.legs().iter().enumerate() {
            let alpha0 = solver.alpha0_rad(i);
            let (sin_beta, cos_beta) = libm::sincosf(leg.beta_rad);
            let tip = leg.base_mm
                + g.arm_mm()
                    * Vec3::new(
                        alpha0.cos() * cos_beta,
                        alpha0.cos() * sin_beta,
                        alpha0.sin(),
                    );
            let joint = leg.platform_mm + Vec3::new(0.0, 0.0, g.home_height_mm());
            let arm = tip - leg.base_mm;
            let rod = joint - tip;
            assert!(
                (rod.norm() - g.rod_mm()).abs() < 1e-3,
                "rod closure leg {i}"
            );
            assert!(
                arm.dot(&rod).abs() / (arm.norm() * rod.norm()) < 1e-4,
                "leg {i}"
            );
        }
    }

    #[test]
    fn home_gives_home_pulses_exactly() {
        let g = Geometry::default();
        let s = ServoSet::default();
        let sol = Solver::new(g.clone())
            .expect("a valid geometry")
            .solve::<Libm>(&s, &Pose::HOME)
            .unwrap();
        for i in 0..LEGS {
            assert_eq!(sol.pulse_us[i], s.0[i].home_us, "servo {}", i + 1);
        }
    }

    #[test]
    fn far_pose_is_unreachable_and_names_a_leg() {
        let g = Geometry::default();
        let err = Solver::new(g.clone())
            .expect("a valid geometry")
            .arm_angles::<Libm>(&Pose::from_degrees(0.0, 0.0, 80.0, 0.0, 0.0, 0.0));
        assert!(
            matches!(err, Err(IkError::Unreachable { leg: 1 })),
            "{err:?}"
        );
    }

    #[test]
    fn limit_error_names_servo_and_pulse() {
        let g = Geometry::default();
        let mut s = ServoSet::default();
        s.0[1].max_us = 1510.0;
        // Pure heave up: even servos' pulses grow.
        let err = Solver::new(g.clone())
            .expect("a valid geometry")
            .solve::<Libm>(&s, &Pose::from_degrees(0.0, 0.0, 5.0, 0.0, 0.0, 0.0));
        match err {
            Err(IkError::ServoLimit {
                servo: 2,
                pulse_us,
                max_us,
                ..
            }) => assert!(pulse_us > max_us),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn non_finite_and_huge_inputs_are_errors() {
        let solver = Solver::new(Geometry::default()).expect("a valid geometry");
        let s = ServoSet::default();
        let nan = Pose::from_degrees(0.0, f32::NAN, 0.0, 0.0, 0.0, 0.0);
        assert_eq!(
            solver.solve::<Libm>(&s, &nan),
            Err(IkError::NonFinite { axis: Axis::Y })
        );
        let big = Pose::from_degrees(0.0, 0.0, 0.0, 0.0, 200.0, 0.0);
        assert!(matches!(
            solver.solve::<Libm>(&s, &big),
            Err(IkError::AngleTooLarge {
                axis: Axis::Pitch,
                ..
            })
        ));
        let huge = Pose::from_degrees(3e38, 0.0, 0.0, 0.0, 0.0, 0.0);
        assert!(matches!(
            solver.solve::<Libm>(&s, &huge),
            Err(IkError::Unreachable { .. })
        ));
    }
}
