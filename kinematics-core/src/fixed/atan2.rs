//! Four-quadrant arc tangent in fixed point: the half-angle root of eq. 9 of "The Mathematics
//! of the Stewart Platform", `alpha = 2 atan2(y, x)` (see [`crate::ik`]), in the IK's
//! fixed-point path.
//!
//! Units: `y` and `x` are integers of any common scale (the IK's `L - N`, `M + sqrt(D)`, ...
//! in one power-of-two step of mm^2); the angle is in rad, in steps of 2^-29, within
//! `(-pi, pi]`.
//!
//! Method: octant reduction, then table look-up with an exact rotation, then a short series.
//! 1. Symmetry: with `a = max(|x|, |y|)` and `b = min(|x|, |y|)`, `atan2(y, x)` is
//!    `phi = atan(b/a)` in `[0, pi/4]`, or `pi/2 - phi` when `|y| > |x|`, then `pi - ...` when
//!    `x < 0`, then negated when `y < 0`.
//! 2. Table: `j`, the whole number nearest to `64 b/a` (from a 9-bit table of reciprocals;
//!    `|64 b/a - j| < 0.63`), and `phi = atan(j/64) + atan(t)` with `t = tan(phi - atan(j/64))`.
//!    This is the reduction of P. T. P. Tang's table-driven arc tangent
//!    (`atan u = atan c + atan((u - c) / (1 + u c))`; J.-M. Muller, "Elementary Functions:
//!    Algorithms and Implementation", chapter "Table-based methods"), done exactly in integers:
//!    the vector `(a, b)` turned back by `atan(j/64)` is `(a + i b)(64 - i j)` (a Gaussian
//!    integer product: only shifts, two small multiplications and adds), so
//!    `t = (64 b - j a) / (64 a + j b)` exactly, `|t| < 0.0099`.
//! 3. The quotient from a reciprocal by Newton-Raphson, `r <- r (2 - A r)` twice from the same
//!    9-bit table (J.-M. Muller, chapter "Newton-Raphson and Goldschmidt iterations"), to a
//!    relative error below 2^-26; then `atan t = t - t^3/3` (the next term, `t^5/5`, is below
//!    2e-11 rad).
//!
//! Error bound: 2^-29 rad (1.9e-9, one step of the result) against the exact `atan2` of the
//! integers given, tested on dense sweeps of the circle at many radii and by proptest against
//! `f64`. Its parts: the table of `atan(j/64)` is rounded to 2^-33 rad; `t` to 2^-37 after
//! `64 b - j a` is rounded to 2^-32 of `64 a + j b` (together below 5e-10 rad, with the
//! reciprocal's 2^-26 of `|t|` and the series' cut); the result is rounded once, to 2^-29 rad
//! (9.3e-10). Integer instructions only, the same bits on every machine.

use core::f64::consts::PI;

use super::{normalise, table};

/// `2^16 / (1 + (i + 1/2) / 256)` for `i` = 0..=255, rounded: for a normalised `a` in
/// `[2^31, 2^32)` whose bits 30..23 are `i`, an estimate of `2^47 / a` within 2^-9 (relative).
static RECIPROCALS: [u16; 256] = reciprocals();

const fn reciprocals() -> [u16; 256] {
    let mut table = [0; 256];
    let mut i = 0;
    while i < 256 {
        let a = 1.0 + (i as f64 + 0.5) / 256.0;
        table[i] = table::round(65536.0 / a) as u16;
        i += 1;
    }
    table
}

/// `atan(j / 64)` for `j` = 0..=64, in steps of 2^-32 rad, rounded.
static ARC_TANGENTS: [u32; 65] = arc_tangents();

const fn arc_tangents() -> [u32; 65] {
    let mut table = [0; 65];
    let mut j = 0;
    while j <= 64 {
        table[j] = table::round(table::atan(j as f64 / 64.0) * (1u64 << 32) as f64) as u32;
        j += 1;
    }
    table
}

/// `pi/2` and `pi` in steps of 2^-32 rad, rounded.
const HALF_PI_Q32: i64 = table::round(PI / 2.0 * (1u64 << 32) as f64);
const PI_Q32: i64 = table::round(PI * (1u64 << 32) as f64);

/// A constant angle `c` (steps of 2^-32 rad) plus 4 (the rounding to 2^-29) as
/// `c + 4 = 8 whole + part`: then `(c + 4 + phi) >> 3 = whole + ((part + phi) >> 3)` and
/// `(c + 4 - phi) >> 3 = whole - ((phi + 7 - part) >> 3)`, exactly, in 32-bit words.
const fn rounding_split(c: i64) -> (i32, u32) {
    (((c + 4) >> 3) as i32, ((c + 4) & 7) as u32)
}
const ROUNDED_ZERO: (i32, u32) = rounding_split(0);
const ROUNDED_HALF_PI: (i32, u32) = rounding_split(HALF_PI_Q32);
const ROUNDED_PI: (i32, u32) = rounding_split(PI_Q32);
const ROUNDED_PI_MINUS_HALF_PI: (i32, u32) = rounding_split(PI_Q32 - HALF_PI_Q32);

/// `atan2(y, x)`: the angle of the vector `(x, y)` in rad, in steps of 2^-29, within
/// `(-pi, pi]` (`pi` for `y = 0`, `x < 0`), 0 for `(0, 0)`. Any `i32`s (see the module docs for
/// the method and the error bound).
pub fn atan2(y: i32, x: i32) -> i32 {
    let (ax, ay) = (x.unsigned_abs(), y.unsigned_abs());
    let swap = ay > ax;
    let (a, b) = if swap { (ay, ax) } else { (ax, ay) };
    if a == 0 {
        return 0;
    }
    // The angle of (|x|, |y|) in steps of 2^-32 rad, then the quadrant: `theta` is `phi`,
    // `pi/2 - phi`, `pi - phi` or `pi/2 + phi` (y >= 0 and x >= 0, the octant past the
    // diagonal, x < 0, both), rounded to 2^-29 rad as a magnitude (so atan2(-y, x) =
    // -atan2(y, x) exactly): `(theta + 4) >> 3`, in 32-bit words (`theta` may pass 2^32).
    let phi = atan_of_ratio(a, b);
    let ((whole, part), add) = match (swap, x < 0) {
        (false, false) => (ROUNDED_ZERO, true),
        (true, false) => (ROUNDED_HALF_PI, false),
        (false, true) => (ROUNDED_PI, false),
        (true, true) => (ROUNDED_PI_MINUS_HALF_PI, true),
    };
    let rounded = if add {
        whole + ((part + phi) >> 3) as i32
    } else {
        whole - ((phi + 7 - part) >> 3) as i32
    };
    if y < 0 {
        -rounded
    } else {
        rounded
    }
}

/// `atan(b / a)` in steps of 2^-32 rad, for `0 <= b <= a`, `a > 0`.
#[inline(always)]
fn atan_of_ratio(a: u32, b: u32) -> u32 {
    let (a, shift) = normalise(a);
    // b <= a: no bit lost.
    let b = b << shift;
    // j = round(64 b / a), with a's reciprocal from the table: q ~ (b/a) 2^31 within 2^-9.
    let q = (b >> 16) * u32::from(RECIPROCALS[((a >> 23) & 0xff) as usize]);
    let j = ((q + (1 << 24)) >> 25).min(64);
    // (a + i b)(64 - i j): the vector turned back by atan(j/64), exactly, A = 64 a + j b in
    // [2^37, 2^39) and B = 64 b - j a (|B| < 0.0099 A), then both scaled by 2^-6 (2^-7 when A
    // passes 2^38) into [2^31, 2^32), B rounded. In 32-bit words: `floor(A / 64) = a + floor(j
    // b / 64)` (a carry out of 32 bits is A passing 2^38), and with `w = b - j floor(a / 64)`
    // (|w| < 2^26, so its wrapping difference is exact) and `c = j (a mod 64)` (below 2^12),
    // `B = 64 w - c`: `(B + 32) >> 6 = w + ((32 - c) >> 6)` and `(B + 64) >> 7 =
    // (w + ((64 - c) >> 6)) >> 1`.
    let jb = (b >> 6) * j + (((b & 63) * j) >> 6);
    let (a_scaled, carry) = a.overflowing_add(jb);
    let w = b.wrapping_sub((a >> 6) * j) as i32;
    let c = ((a & 63) * j) as i32;
    let (a32, b32) = if carry {
        ((a_scaled >> 1) | (1 << 31), (w + ((64 - c) >> 6)) >> 1)
    } else {
        (a_scaled, w + ((32 - c) >> 6))
    };
    // t = B / A in steps of 2^-36 (|t| < 0.0099: below 2^30 steps): B r / 2^25 with the
    // reciprocal r ~ 2^61 / A (below 2^30.01), in 32-bit products of B split at bit 13
    // (|B| < 2^25.4) and r at bit 15: `B r / 2^25 = 8 B_hi r_hi + (B_hi r_lo + 4 B_lo r_hi +
    // B_lo r_lo / 2^13) / 2^12`, every product and the sum below 2^30.2; the low product cut
    // (within a step of 2^-36 of B r / 2^25 rounded).
    let r = reciprocal(a32) as i32;
    let (b_hi, b_lo, r_hi, r_lo) = (b32 >> 13, b32 & 0x1fff, r >> 15, r & 0x7fff);
    let t = ((b_hi * r_hi) << 3)
        + ((b_hi * r_lo + ((b_lo * r_hi) << 2) + ((b_lo * r_lo) >> 13) + (1 << 11)) >> 12);
    // t^3/3 from t's top bits (steps of 2^-22, then 2^-28, 2^-50, 2^-36; 21845 / 2^16 is 1/3
    // within 1.6e-5 of a term below 3.3e-7).
    let t22 = t >> 14;
    let t_squared = (t22 * t22) >> 16;
    let t_cubed_over_3 = (((t_squared * t22) >> 14) * 21845) >> 16;
    // atan(j/64) + atan t, in steps of 2^-32 (within [0, pi/4]: the wrapping sum is exact).
    let atan_t = ((t - t_cubed_over_3) + 8) >> 4;
    ARC_TANGENTS[j as usize].wrapping_add(atan_t as u32)
}

/// `2^61 / a` for `a` in `[2^31, 2^32)`, within 2^-26 (relative): the table's 9-bit estimate,
/// one Newton-Raphson step `r <- r (2 - a r)` on `a`'s top 16 bits (to about 2^-13), and one on
/// all of them with the residual `2^61 - a r`, in 32-bit words: the residual is below 2^48, so
/// `(2^61 - a r) / 2^18` is the wrapping difference of `2^43` and `a r / 2^18` taken modulo
/// 2^32 (from the four 16-bit partial products, each cut on its own: within 3 of the exact
/// quotient), and the correction `r residual / 2^61` comes from `r`'s top 14 bits and the
/// residual's top 16 (below 2^30, within 2^-13 of the correction, itself below 2^18).
#[inline(always)]
fn reciprocal(a: u32) -> u32 {
    // r0 ~ 2^47 / a; a's top 16 bits times r0 ~ 2^31 (1 + e), so 2^32 minus it is 2^31 (1 - e).
    let r0 = u32::from(RECIPROCALS[((a >> 23) & 0xff) as usize]);
    let r1 = r0 * (0u32.wrapping_sub((a >> 16) * r0) >> 17); // ~ 2^61 / a, below 2^30.01
    let (a_hi, a_lo) = (a >> 16, a & 0xffff);
    let (r_hi, r_lo) = (r1 >> 16, r1 & 0xffff);
    // a r1 / 2^18 modulo 2^32 (a_hi r_hi < 2^30: its 2^14 multiple wraps as it must).
    let a_r = ((a_hi * r_hi) << 14)
        .wrapping_add((a_hi * r_lo) >> 2)
        .wrapping_add((a_lo * r_hi) >> 2)
        .wrapping_add((a_lo * r_lo) >> 18);
    // 2^43 is 0 modulo 2^32.
    let residual = 0u32.wrapping_sub(a_r) as i32;
    let correction = ((r1 >> 16) as i32 * (residual >> 14)) >> 13;
    r1.wrapping_add(correction as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The error bound of the module docs, in steps of 2^-29 rad.
    const BOUND: f64 = 1.0;

    /// The error of `atan2(y, x)` against `f64`, in steps of 2^-29 rad.
    fn error_steps(y: i32, x: i32) -> f64 {
        let exact = libm::atan2(f64::from(y), f64::from(x)) * (1u64 << 29) as f64;
        (f64::from(atan2(y, x)) - exact).abs()
    }

    #[test]
    fn quadrants_rounded_in_32_bits_as_in_64() {
        // The quadrant and the rounding in 32-bit words give what `theta` in 64 bits gives.
        let in_64_bits = |y: i32, x: i32| {
            let (ax, ay) = (x.unsigned_abs(), y.unsigned_abs());
            let swap = ay > ax;
            let (a, b) = if swap { (ay, ax) } else { (ax, ay) };
            if a == 0 {
                return 0;
            }
            let phi = i64::from(atan_of_ratio(a, b));
            let mut theta = if swap { HALF_PI_Q32 - phi } else { phi };
            if x < 0 {
                theta = PI_Q32 - theta;
            }
            let rounded = ((theta + 4) >> 3) as i32;
            if y < 0 {
                -rounded
            } else {
                rounded
            }
        };
        let mut seed = 0x7a7a_0001_u32;
        let mut next = || crate::test_support::xorshift(&mut seed) as i32;
        for i in 0..300_000 {
            let (y, x) = if i < 40_000 {
                (i % 200 - 100, i / 200 - 100)
            } else {
                (next() >> (i % 31), next() >> (i / 7 % 31))
            };
            assert_eq!(atan2(y, x), in_64_bits(y, x), "({y}, {x})");
        }
    }

    #[test]
    fn tables_are_rounded() {
        for (j, &entry) in ARC_TANGENTS.iter().enumerate() {
            let exact = libm::atan(j as f64 / 64.0) * (1u64 << 32) as f64;
            assert!((f64::from(entry) - exact).abs() <= 0.5, "j = {j}");
        }
        for (i, &entry) in RECIPROCALS.iter().enumerate() {
            let exact = 65536.0 / (1.0 + (i as f64 + 0.5) / 256.0);
            assert!((f64::from(entry) - exact).abs() <= 0.5, "i = {i}");
        }
    }

    #[test]
    fn reciprocal_within_its_bound() {
        // Every 2^12-th a in [2^31, 2^32), and the ends.
        let mut worst = 0.0f64;
        let mut a = 1u64 << 31;
        while a < 1 << 32 {
            let exact = (1u64 << 61) as f64 / a as f64;
            worst = worst.max((f64::from(reciprocal(a as u32)) - exact).abs() / exact);
            a += 1 << 12;
        }
        let last = u32::MAX;
        let exact = (1u64 << 61) as f64 / f64::from(last);
        worst = worst.max((f64::from(reciprocal(last)) - exact).abs() / exact);
        assert!(worst < (-26.0f64).exp2(), "{worst:e}");
    }

    #[test]
    fn exact_at_the_axes_and_diagonals() {
        let step = (1u64 << 29) as f64;
        let pi = libm::round(PI * step) as i32;
        for r in [1, 7, 1000, 1 << 20, i32::MAX] {
            assert_eq!(atan2(0, r), 0);
            assert_eq!(atan2(0, -r), pi);
            assert_eq!(atan2(r, 0), libm::round(PI / 2.0 * step) as i32);
            assert_eq!(atan2(-r, 0), -libm::round(PI / 2.0 * step) as i32);
            assert!(error_steps(r, r) <= BOUND && error_steps(-r, -r) <= BOUND);
        }
        assert_eq!(atan2(0, 0), 0);
        assert!(error_steps(i32::MIN, i32::MIN) <= BOUND);
        assert!(error_steps(i32::MIN, 1) <= BOUND);
    }

    #[test]
    fn within_the_bound_around_the_circle() {
        // 2^18 directions evenly round the circle at radii from 2^4 to 2^31 (the IK's are about
        // 2^29), and exhaustively every (x, y) with |x|, |y| <= 100 (small integers: the
        // coarsest inputs).
        let mut worst = (0.0f64, 0, 0);
        let mut check = |y: i32, x: i32| {
            let e = error_steps(y, x);
            if e > worst.0 {
                worst = (e, y, x);
            }
        };
        let n = 1 << 18;
        for radius_log2 in [4.0, 12.0, 20.0, 27.3, 28.0, 29.0, 29.5, 30.0, 30.99] {
            let radius = f64::exp2(radius_log2);
            for i in 0..n {
                let angle = f64::from(i) / f64::from(n) * 2.0 * PI;
                check(
                    (radius * libm::sin(angle)) as i32,
                    (radius * libm::cos(angle)) as i32,
                );
            }
        }
        for y in -100..=100 {
            for x in -100..=100 {
                check(y, x);
            }
        }
        assert!(
            worst.0 <= BOUND,
            "{} steps at (y, x) = {:?}",
            worst.0,
            (worst.1, worst.2)
        );
        eprintln!("atan2: largest error {:.3} steps of 2^-29 rad", worst.0);
    }

    proptest! {
        #[test]
        fn within_the_bound_anywhere(y in any::<i32>(), x in any::<i32>()) {
            prop_assert!(error_steps(y, x) <= BOUND, "(y, x) = ({}, {})", y, x);
        }

        #[test]
        fn within_the_bound_for_nearly_equal_and_tiny_ratios(
            a in 1i32..=i32::MAX, d in -1000i32..=1000, small in 0i32..=1000
        ) {
            let b = a.saturating_add(d);
            prop_assert!(error_steps(b, a) <= BOUND, "({}, {})", b, a);
            prop_assert!(error_steps(small, a) <= BOUND, "({}, {})", small, a);
            prop_assert!(error_steps(a, -small) <= BOUND, "({}, {})", a, -small);
        }
    }
}
