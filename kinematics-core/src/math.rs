//! The transcendental functions the kinematics need, behind a trait.
//!
//! The core is generic over [`Math`] so that the same algorithm runs with `libm` on the host (and
//! in host tests) and with the RP2040 boot ROM's faster float routines in the firmware. All
//! angles are in radians.
//!
//! The IK's hot loop also does its arithmetic through the trait ([`Math::add`], [`Math::sub`],
//! [`Math::mul`], via [`Real`]): by default that is plain `f32` arithmetic, but a board whose
//! compiler-inserted float routines are slow (the RP2040's add finiteness checks around each
//! boot ROM call) may call its float routines directly. The operations and their order are the
//! same either way, so the host runs the very algorithm the board runs.
//!
//! The IK's fixed-point path (module [`crate::fixed`]: every usual build) asks for its sine
//! and cosine, square root and arc tangent in fixed point ([`Math::sin_cos_fixed`],
//! [`Math::sqrt_fixed`], [`Math::atan2_fixed`]). By default these are the core's integer
//! routines, the same bits on every machine, so the host and the chip solve a pose alike;
//! [`FloatRoutines`] puts a [`Math`]'s own `f32` routines there instead (converted there and
//! back), which is how the benchmark measures other libraries in the same IK.

use core::marker::PhantomData;
use core::ops::{Add, Mul, Neg, Sub};

use crate::fixed::{self, to_fixed, ANGLE_FRAC, ROT_FRAC};
use crate::types::{Mat3, Vec3};

/// Scalar functions used by the kinematics. Implementations must return NaN (never panic) for
/// inputs outside their domain; callers check results for finiteness.
pub trait Math {
    /// `(sin x, cos x)`. Callers keep `|x| <= 2*pi` (the ROM routines need `|x| < 128`).
    fn sin_cos(x: f32) -> (f32, f32);
    /// Square root; NaN for negative input.
    fn sqrt(x: f32) -> f32;
    /// Four-quadrant arc tangent of `y / x`, in `(-pi, pi]`.
    fn atan2(y: f32, x: f32) -> f32;

    /// `a + b`, correctly rounded when the operands and the result are finite. Otherwise the
    /// result is unspecified (the boot ROM does not follow IEEE there): callers keep their
    /// operands finite and bounded (the IK checks the pose and bounds `|l|^2` first).
    #[inline]
    fn add(a: f32, b: f32) -> f32 {
        a + b
    }

    /// `a - b`, as [`Math::add`].
    #[inline]
    fn sub(a: f32, b: f32) -> f32 {
        a - b
    }

    /// `a * b`, as [`Math::add`].
    #[inline]
    fn mul(a: f32, b: f32) -> f32 {
        a * b
    }

    /// `(sin x, cos x)` in steps of 2^-30 (the IK's rotation entries) for `|x| < 4` rad: the
    /// pose's angles in the IK's fixed-point path. By default [`fixed::sin_cos::sin_cos`]: integer
    /// instructions, within 2^-29.
    #[inline]
    fn sin_cos_fixed(x_rad: f32) -> (i32, i32) {
        fixed::sin_cos::sin_cos(x_rad)
    }

    /// `sqrt(d)` within 1: the root of eq. 9's discriminant in the IK's fixed-point path (`d`
    /// below 2^60 there). By default [`fixed::sqrt::sqrt`]: integer instructions.
    #[inline]
    fn sqrt_fixed(d: u64) -> u32 {
        fixed::sqrt::sqrt(d)
    }

    /// `atan2(y, x)` in steps of 2^-29 rad within `(-pi, pi]` (0 for `(0, 0)`): the half-angle
    /// of eq. 9 in the IK's fixed-point path (`|y|, |x| < 2^31` there). By default
    /// [`fixed::atan2::atan2`]: integer instructions, within 2^-29 rad.
    #[inline]
    fn atan2_fixed(y: i32, x: i32) -> i32 {
        fixed::atan2::atan2(y, x)
    }
}

/// [`Math`] methods that hand their arguments to another `Math`, `$to`, for an impl that
/// changes only some of them: `forward_math!(M => sqrt, atan2, add)` inside `impl Math for ..`.
macro_rules! forward_math {
    ($to:ty => $($method:ident),+ $(,)?) => {
        $( $crate::math::forward_math!(@ $to, $method); )+
    };
    (@ $to:ty, sin_cos) => {
        #[inline]
        fn sin_cos(x: f32) -> (f32, f32) {
            <$to as $crate::Math>::sin_cos(x)
        }
    };
    (@ $to:ty, sqrt) => {
        #[inline]
        fn sqrt(x: f32) -> f32 {
            <$to as $crate::Math>::sqrt(x)
        }
    };
    (@ $to:ty, atan2) => {
        #[inline]
        fn atan2(y: f32, x: f32) -> f32 {
            <$to as $crate::Math>::atan2(y, x)
        }
    };
    (@ $to:ty, add) => {
        #[inline]
        fn add(a: f32, b: f32) -> f32 {
            <$to as $crate::Math>::add(a, b)
        }
    };
    (@ $to:ty, sub) => {
        #[inline]
        fn sub(a: f32, b: f32) -> f32 {
            <$to as $crate::Math>::sub(a, b)
        }
    };
    (@ $to:ty, mul) => {
        #[inline]
        fn mul(a: f32, b: f32) -> f32 {
            <$to as $crate::Math>::mul(a, b)
        }
    };
    (@ $to:ty, sin_cos_fixed) => {
        #[inline]
        fn sin_cos_fixed(x_rad: f32) -> (i32, i32) {
            <$to as $crate::Math>::sin_cos_fixed(x_rad)
        }
    };
    (@ $to:ty, sqrt_fixed) => {
        #[inline]
        fn sqrt_fixed(d: u64) -> u32 {
            <$to as $crate::Math>::sqrt_fixed(d)
        }
    };
    (@ $to:ty, atan2_fixed) => {
        #[inline]
        fn atan2_fixed(y: i32, x: i32) -> i32 {
            <$to as $crate::Math>::atan2_fixed(y, x)
        }
    };
}
pub(crate) use forward_math;

/// `M` with its own `f32` sine and cosine, square root and arc tangent in the IK's fixed-point
/// path too, in place of the integer routines (the arguments converted to `f32` and the results
/// back to fixed point): the same IK with `M`'s routines, to measure them (the benchmark's
/// boot ROM, `libm` and `micromath` rows). Everything else is `M`'s.
#[derive(Debug, Clone, Copy, Default)]
pub struct FloatRoutines<M>(PhantomData<M>);

impl<M: Math> Math for FloatRoutines<M> {
    forward_math!(M => sin_cos, sqrt, atan2, add, sub, mul);

    fn sin_cos_fixed(x_rad: f32) -> (i32, i32) {
        // |sin|, |cos| of any library stay far below 2, the bound of `to_fixed` here.
        let (s, c) = M::sin_cos(x_rad);
        (to_fixed(s, ROT_FRAC), to_fixed(c, ROT_FRAC))
    }

    fn sqrt_fixed(d: u64) -> u32 {
        // `as` saturates (and takes NaN to 0).
        M::sqrt(d as f32) as u32
    }

    fn atan2_fixed(y: i32, x: i32) -> i32 {
        let angle = M::atan2(y as f32, x as f32);
        // Within (-4, 4) rad, the bound of `to_fixed` here (NaN: 0).
        if abs_bits(angle) < 4.0f32.to_bits() {
            to_fixed(angle, ANGLE_FRAC)
        } else {
            0
        }
    }
}

/// An `f32` whose `+`, `-` and `*` go through [`Math`], so formulas read as written.
#[derive(Debug)]
pub struct Real<M>(pub f32, PhantomData<M>);

impl<M> Real<M> {
    /// Wraps a value.
    #[inline]
    pub const fn new(x: f32) -> Self {
        Real(x, PhantomData)
    }
}

impl<M> Clone for Real<M> {
    #[inline]
    fn clone(&self) -> Self {
        *self
    }
}

impl<M> Copy for Real<M> {}

impl<M: Math> Add for Real<M> {
    type Output = Self;
    #[inline]
    fn add(self, rhs: Self) -> Self {
        Real::new(M::add(self.0, rhs.0))
    }
}

impl<M: Math> Sub for Real<M> {
    type Output = Self;
    #[inline]
    fn sub(self, rhs: Self) -> Self {
        Real::new(M::sub(self.0, rhs.0))
    }
}

impl<M: Math> Mul for Real<M> {
    type Output = Self;
    #[inline]
    fn mul(self, rhs: Self) -> Self {
        Real::new(M::mul(self.0, rhs.0))
    }
}

impl<M> Neg for Real<M> {
    type Output = Self;
    /// Exact (flips the sign bit), so no [`Math`] routine is needed.
    #[inline]
    fn neg(self) -> Self {
        Real::new(-self.0)
    }
}

/// IEEE `a <= b` in integer instructions. On a chip without an FPU every float comparison is a
/// library call (about 45 cycles on the RP2040, more than the comparison it replaces here).
///
/// Non-NaN floats order like their bit patterns read as sign-magnitude integers; flipping the
/// magnitude bits of the negative ones turns that into two's-complement order. `-0` and `+0`
/// (the only equal values with different bits) are caught separately; NaN compares false.
#[inline]
pub fn le(a: f32, b: f32) -> bool {
    let (a, b) = (a.to_bits(), b.to_bits());
    let not_nan = |x: u32| x & 0x7fff_ffff <= 0x7f80_0000;
    let key = |x: u32| (x ^ ((x as i32 >> 31) as u32 >> 1)) as i32;
    not_nan(a) && not_nan(b) && (key(a) <= key(b) || (a | b) << 1 == 0)
}

/// IEEE `a < b` in integer instructions (see [`le`]).
#[inline]
pub fn lt(a: f32, b: f32) -> bool {
    let (a_bits, b_bits) = (a.to_bits(), b.to_bits());
    let not_nan = |x: u32| x & 0x7fff_ffff <= 0x7f80_0000;
    not_nan(a_bits) && not_nan(b_bits) && !le(b, a)
}

/// IEEE `lo <= x && x <= hi` in integer instructions, as [`le`] twice but with `x`'s order key
/// and NaN check computed once (the IK asks it of every pulse).
#[inline]
pub fn within(x: f32, lo: f32, hi: f32) -> bool {
    let (x, lo, hi) = (x.to_bits(), lo.to_bits(), hi.to_bits());
    // The usual case first (the IK's pulses): `x` positive and finite, its bits in
    // `(0, +inf)`. Then `lo <= x` exactly when `lo`'s bits are at most `x`'s (a non-negative
    // `lo`; a NaN's are above) or `lo` is negative and not NaN (bits in `[2^31, -inf]`), and
    // `x <= hi` exactly when `hi`'s bits are in `[x, +inf]` (a negative `hi`'s pass 2^31, a
    // NaN's pass +inf's): three comparisons in all.
    const INFINITY: u32 = 0x7f80_0000;
    if x.wrapping_sub(1) < INFINITY - 1 {
        return (lo <= x || lo.wrapping_sub(0x8000_0000) <= INFINITY)
            && hi.wrapping_sub(x) <= INFINITY - x;
    }
    let not_nan = |v: u32| v & 0x7fff_ffff <= 0x7f80_0000;
    let key = |v: u32| (v ^ ((v as i32 >> 31) as u32 >> 1)) as i32;
    let key_x = key(x);
    not_nan(x)
        && not_nan(lo)
        && not_nan(hi)
        && (key(lo) <= key_x || (lo | x) << 1 == 0)
        && (key_x <= key(hi) || (x | hi) << 1 == 0)
}

/// `u . v` with `M`'s arithmetic.
pub(crate) fn dot<M: Math>(u: Vec3, v: Vec3) -> f32 {
    let r = Real::<M>::new;
    (r(u.x) * r(v.x) + r(u.y) * r(v.y) + r(u.z) * r(v.z)).0
}

/// `u x v` with `M`'s arithmetic.
pub(crate) fn cross<M: Math>(u: Vec3, v: Vec3) -> Vec3 {
    let r = Real::<M>::new;
    Vec3::new(
        (r(u.y) * r(v.z) - r(u.z) * r(v.y)).0,
        (r(u.z) * r(v.x) - r(u.x) * r(v.z)).0,
        (r(u.x) * r(v.y) - r(u.y) * r(v.x)).0,
    )
}

/// `u + v` with `M`'s arithmetic.
pub(crate) fn add<M: Math>(u: Vec3, v: Vec3) -> Vec3 {
    let r = Real::<M>::new;
    Vec3::new(
        (r(u.x) + r(v.x)).0,
        (r(u.y) + r(v.y)).0,
        (r(u.z) + r(v.z)).0,
    )
}

/// `u - v` with `M`'s arithmetic.
pub(crate) fn sub<M: Math>(u: Vec3, v: Vec3) -> Vec3 {
    let r = Real::<M>::new;
    Vec3::new(
        (r(u.x) - r(v.x)).0,
        (r(u.y) - r(v.y)).0,
        (r(u.z) - r(v.z)).0,
    )
}

/// `m v` with `M`'s arithmetic. A vector with `z = 0` (every joint of a planar layout) skips
/// the third column: adding `m_k2 * 0` changes nothing.
pub(crate) fn mul_mat_vec<M: Math>(m: &Mat3, v: Vec3) -> Vec3 {
    let r = Real::<M>::new;
    let planar = is_zero(v.z);
    let row = |k: usize| {
        let xy = r(m[(k, 0)]) * r(v.x) + r(m[(k, 1)]) * r(v.y);
        if planar {
            xy.0
        } else {
            (xy + r(m[(k, 2)]) * r(v.z)).0
        }
    };
    Vec3::new(row(0), row(1), row(2))
}

/// `x == 0` (either sign) in integer instructions.
#[inline]
pub(crate) fn is_zero(x: f32) -> bool {
    x.to_bits() << 1 == 0
}

/// `|x|` as bits: non-negative floats (and NaN above them all) order like their bit patterns,
/// so the largest magnitude can be found in integer instructions.
#[inline]
pub(crate) fn abs_bits(x: f32) -> u32 {
    x.to_bits() & 0x7fff_ffff
}

/// [`Math`] backed by the portable `libm` crate (correctly rounded or nearly so).
#[derive(Debug, Clone, Copy, Default)]
pub struct Libm;

impl Math for Libm {
    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        libm::sincosf(x)
    }

    #[inline]
    fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }

    #[inline]
    fn atan2(y: f32, x: f32) -> f32 {
        libm::atan2f(y, x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_comparisons_match_ieee() {
        let values = [
            f32::NEG_INFINITY,
            -3e38,
            -1.5,
            -f32::MIN_POSITIVE,
            -1e-45,
            -0.0,
            0.0,
            1e-45,
            f32::MIN_POSITIVE,
            1.0,
            1.5,
            core::f32::consts::PI,
            3e38,
            f32::INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        for a in values {
            for b in values {
                assert_eq!(le(a, b), a <= b, "{a} <= {b}");
                assert_eq!(lt(a, b), a < b, "{a} < {b}");
                for x in values {
                    assert_eq!(within(x, a, b), a <= x && x <= b, "{a} <= {x} <= {b}");
                }
            }
        }
        // Random bit patterns (every sign, NaN payloads, subnormals), with one of the values
        // above, or a neighbour of one of the others, in one place in four.
        let mut seed = 0x00c0_ffee_u32;
        let mut next = || crate::test_support::xorshift(&mut seed);
        for _ in 0..300_000 {
            let mut pick = |near: u32| {
                let r = next();
                match r % 8 {
                    0 => values[(r >> 8) as usize % values.len()].to_bits(),
                    1 => near.wrapping_add((r >> 8) % 3).wrapping_sub(1),
                    _ => r,
                }
            };
            let x = pick(0x44bb_8000);
            let (a, b) = (pick(x), pick(x));
            let (x, a, b) = (f32::from_bits(x), f32::from_bits(a), f32::from_bits(b));
            assert_eq!(within(x, a, b), a <= x && x <= b, "{a:e} <= {x:e} <= {b:e}");
        }
    }
}
