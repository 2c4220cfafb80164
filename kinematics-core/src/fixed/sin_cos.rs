//! Sine and cosine in fixed point: the three angles of a pose, for the rotation `R` of eq. 1
//! of "The Mathematics of the Stewart Platform" in the IK's fixed-point path.
//!
//! Units: the angle `x` in rad (an `f32`, `|x| < 4`: a checked pose has `|x| <= pi`); `sin x`
//! and `cos x` in steps of 2^-30 (the format of `R`'s entries, [`super::ROT_FRAC`]).
//!
//! Method: table look-up and the sum formulas, the table-driven method of P. T. P. Tang
//! ("Table-lookup algorithms for elementary functions and their error analysis", 10th IEEE
//! Symposium on Computer Arithmetic, 1991; J.-M. Muller, "Elementary Functions: Algorithms and
//! Implementation", chapter "Table-based methods"). With `k` the whole number nearest to
//! `x / (pi/128)` and `d = x - k pi/128` (`|d| <= pi/256`, 0.0123 rad):
//!
//! `sin x = S cos d + C sin d = S + C sin d - S (1 - cos d)`,
//! `cos x = C cos d - S sin d = C - S sin d - C (1 - cos d)`,
//!
//! where `S = sin(k pi/128)` and `C = cos(k pi/128)` come from a quarter-wave table of 65 sines
//! (the quadrant is `k`'s two top bits: `sin(pi/2 + a) = cos a`, ...), and `sin d`, `1 - cos d`
//! from their Taylor series: `sin d = d - d^3/6` (the next term, `d^5/120`, is below 2.4e-12)
//! and `1 - cos d = d^2/2 - d^4/24` (the next, `d^6/720`, is below 2e-15).
//!
//! Error bound: 2^-29 (1.9e-9) against the exact sine and cosine of the `f32` given, tested on
//! a dense grid and by proptest against `f64`. Its parts: each table entry is rounded to 2^-31
//! (4.7e-10); `x` is exact in steps of 2^-36 rad but below 2^-13 rad (rounded there: 7e-12);
//! `k pi/128` is off by at most 163 times `pi/128`'s rounding to 2^-36 (1.6e-10 in all); the
//! series' terms and products are cut to 2^-36 or finer (below 2e-10 together); the results are
//! rounded once, to 2^-30 (4.7e-10). Integer instructions only, and 32-bit products only (the
//! M0+ multiplies 32 x 32 -> 32 bits in one cycle, a 64-bit product takes four of them and
//! more), so every machine gives the same bits.

use core::f64::consts::PI;

use super::table;

/// `sin(k pi/128)` for `k` = 0..=64 (a quarter turn), in steps of 2^-30, rounded to nearest;
/// the cosines are the same entries backwards.
static SINES: [i32; 65] = sines();

const fn sines() -> [i32; 65] {
    let mut sines = [0; 65];
    let mut k = 0;
    while k <= 64 {
        sines[k] = table::round(table::sin(k as f64 * PI / 128.0) * (1u64 << 30) as f64) as i32;
        k += 1;
    }
    sines
}

/// `pi` in steps of 2^-29, rounded (`pi * 2^29` is 0.065 above it): also `pi/128` in steps of
/// 2^-36.
const PI_Q29: i32 = table::round(PI * (1u64 << 29) as f64) as i32;
/// `128/pi` (table steps per rad) in steps of 2^-8, rounded.
const STEPS_PER_RAD_Q8: i32 = table::round(128.0 / PI * 256.0) as i32;

/// `(sin x, cos x)` in steps of 2^-30 for `x` in rad, `|x| < 4` (see the module docs for the
/// method and the error bound). Outside that range `libm` answers (slowly), and a NaN or
/// infinite `x` gives `(0, 0)`: the IK only passes the angles of a checked pose.
pub fn sin_cos(x_rad: f32) -> (i32, i32) {
    // |x| < 4 in integer instructions (non-negative floats order like their bit patterns; NaN
    // is above every finite bound).
    if x_rad.to_bits() & 0x7fff_ffff >= 4.0f32.to_bits() {
        return outside_range(x_rad);
    }
    // x in steps of 2^-36 rad (exact down to 2^-13 rad), below 2^38, in 32-bit words: its low
    // word and `x >> 21` (floored; [`front_end`]).
    let (x_low, x_q15) = front_end(x_rad);
    // k = round(x / (pi/128)): x in steps of 2^-15 times 128/pi in steps of 2^-8 (below 2^31;
    // a rough k only makes |d| a little larger, which the series allow for).
    let k = (x_q15 * STEPS_PER_RAD_Q8 + (1 << 22)) >> 23;
    // d = x - k pi/128 in steps of 2^-36 rad: |d| < 0.0124 rad, below 2^30 steps, so the
    // difference of the low words of x and of k pi/128 (`k PI_Q29`, |k| <= 163) is d exactly.
    let d = x_low.wrapping_sub(k.wrapping_mul(PI_Q29));
    // From here on 32-bit products only, each operand cut to 15 or 16 bits where the term
    // allows (the M0+ multiplies 32 x 32 -> 32 bits in one cycle): every cut is stated with
    // its effect, below 2^-36 in all.
    let (d_hi, d_lo) = (d >> 15, d & 0x7fff);
    // d^2 in steps of 2^-40 (below 2^28): d_hi^2 2^30 + 2 d_hi d_lo 2^15 (+ d_lo^2, below a
    // quarter step), over 2^32.
    let d2 = ((d_hi * d_hi) >> 2) + ((d_hi * d_lo) >> 16);
    // d^3 in steps of 2^-49 from d and d^2 cut to 16 bits (2^-15 of a term below 2e-6), then
    // d^3/6 in steps of 2^-36 (5461 / 2^15 is 1/6 within 6e-5).
    let d3 = d_hi * (d2 >> 12);
    let sin_d = d - (((d3 >> 13) * 5461 + (1 << 14)) >> 15);
    // 1 - cos d = d^2/2 - d^4/24 in steps of 2^-40 (d^4 < 9.5e-10 needs no more than d^2's top
    // 14 bits; 2731 / 2^16 is 1/24 within 1.2e-4).
    let d4 = {
        let top = d2 >> 14;
        (top * top) >> 12
    };
    let one_minus_cos_d = (d2 >> 1) - ((d4 * 2731 + (1 << 15)) >> 16);
    let (s, c) = table_sin_cos(k);
    // S sin d - C (1 - cos d) and S sin d + C (1 - cos d) in steps of 2^-36, then rounded once
    // to 2^-30 and added to C and S.
    let to_sin = mul_by_sin_d(c, sin_d) - mul_by_one_minus_cos_d(s, one_minus_cos_d);
    let to_cos = mul_by_sin_d(s, sin_d) + mul_by_one_minus_cos_d(c, one_minus_cos_d);
    (
        s + ((to_sin + (1 << 5)) >> 6),
        c - ((to_cos + (1 << 5)) >> 6),
    )
}

/// `x` (rad, `|x| < 4`, finite) in steps of 2^-36, rounded to nearest (halves away from zero),
/// as two 32-bit words: its low 32 bits (two's complement) and `floor(x / 2^21)` (below 2^17 in
/// magnitude), what [`sin_cos`] needs of the 39-bit value: with `x = m 2^(e - 150)` (`m` the
/// 24-bit mantissa), `m 2^(e - 114)` is an integer for `e >= 114` (`|x| >= 2^-13`; its low word
/// `m << (e - 114)`, `e - 114 <= 14`), else rounded; a negative `x`'s floor is one below its
/// magnitude's (negated) where bits below 2^21 are cut. No 64-bit shift or sum.
#[inline(always)]
fn front_end(x_rad: f32) -> (i32, i32) {
    let bits = x_rad.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32;
    let mantissa = (bits & 0x7f_ffff) | 0x80_0000;
    let shift = exponent - 114;
    let (low, high) = if exponent == 0 {
        (0, 0) // zero or subnormal: far below 2^-36
    } else if shift >= 0 {
        (mantissa << shift, mantissa >> (21 - shift))
    } else if shift > -26 {
        let rounded = (mantissa >> -shift) + ((mantissa >> (-shift - 1)) & 1);
        (rounded, rounded >> 21)
    } else {
        (0, 0)
    };
    if bits >> 31 != 0 {
        let cut = u32::from(low & 0x1f_ffff != 0);
        ((low as i32).wrapping_neg(), -((high + cut) as i32))
    } else {
        (low as i32, high as i32)
    }
}

/// `t sin d` in steps of 2^-36 for a table value `t` (steps of 2^-30, `|t| <= 2^30`) and
/// `sin d` (steps of 2^-36, below 2^29.7): with both split at bit 15, three 32-bit products
/// (the fourth, below 2^30 in steps of 2^-66, is less than a step), within 2 steps.
#[inline(always)]
fn mul_by_sin_d(t: i32, sin_d: i32) -> i32 {
    let (t_hi, t_lo) = (t >> 15, t & 0x7fff);
    let (s_hi, s_lo) = (sin_d >> 15, sin_d & 0x7fff);
    // Each product below 2^30, their sum below 2^31.
    t_hi * s_hi + ((t_hi * s_lo + t_lo * s_hi) >> 15)
}

/// `t (1 - cos d)` in steps of 2^-36 for a table value `t` (steps of 2^-30) and `1 - cos d`
/// (steps of 2^-40, in `[0, 2^26.4)`): split at bit 15, three 32-bit products (the fourth is
/// below 2^-4 steps), within 2 steps.
#[inline(always)]
fn mul_by_one_minus_cos_d(t: i32, one_minus_cos_d: i32) -> i32 {
    let (t_hi, t_lo) = (t >> 15, t & 0x7fff);
    let (e_hi, e_lo) = (one_minus_cos_d >> 15, one_minus_cos_d & 0x7fff);
    ((t_hi * e_hi) >> 4) + ((t_hi * e_lo + t_lo * e_hi) >> 19)
}

/// `(sin, cos)` of `k pi/128` from the quarter-wave table, in steps of 2^-30.
#[inline(always)]
fn table_sin_cos(k: i32) -> (i32, i32) {
    let k = (k & 255) as usize; // k mod 256: a whole turn
    let j = k & 63;
    let (s, c) = (SINES[j], SINES[64 - j]);
    match k >> 6 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// [`sin_cos`] for `|x| >= 4` or not finite.
#[cold]
fn outside_range(x_rad: f32) -> (i32, i32) {
    if !x_rad.is_finite() {
        return (0, 0);
    }
    let (s, c) = libm::sincos(f64::from(x_rad));
    let scale = (1u64 << 30) as f64;
    (libm::round(s * scale) as i32, libm::round(c * scale) as i32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The error bound of the module docs, in steps of 2^-30.
    const BOUND: f64 = 2.0;

    /// The larger error of `sin_cos(x)` against `f64`, in steps of 2^-30.
    fn error_steps(x: f32) -> f64 {
        let (s, c) = sin_cos(x);
        let (es, ec) = libm::sincos(f64::from(x));
        let scale = (1u64 << 30) as f64;
        (f64::from(s) - es * scale)
            .abs()
            .max((f64::from(c) - ec * scale).abs())
    }

    #[test]
    fn front_end_is_the_wide_conversion() {
        // Against `to_fixed_wide` (steps of 2^-36, in 64 bits): its low word and its floor at
        // 2^21, for every exponent below 4 with random mantissas, both signs, and a dense
        // sweep.
        let check = |x: f32| {
            let wide = super::super::to_fixed_wide(x, 36);
            assert_eq!(front_end(x), (wide as i32, (wide >> 21) as i32), "{x:e}");
        };
        let mut seed = 0x51de_cafe_u32;
        for exponent in 0..=128u32 {
            for _ in 0..2000 {
                let m = crate::test_support::xorshift(&mut seed);
                for sign in [0, 1u32 << 31] {
                    check(f32::from_bits(sign | exponent << 23 | (m & 0x7f_ffff)));
                }
            }
        }
        for i in -100_000..=100_000 {
            check(i as f32 * 3.999_999 / 100_000.0);
        }
    }

    #[test]
    fn table_entries_are_rounded_sines() {
        for (k, &entry) in SINES.iter().enumerate() {
            let exact = libm::sin(k as f64 * PI / 128.0) * (1u64 << 30) as f64;
            assert!((f64::from(entry) - exact).abs() <= 0.5, "k = {k}");
        }
        assert_eq!(SINES[64], 1 << 30);
        assert_eq!(PI_Q29, 1_686_629_713);
    }

    #[test]
    fn within_the_bound_on_a_dense_grid() {
        // 2^21 + 1 angles evenly over [-pi, pi] (every table interval about 4,000 times), each
        // table boundary and its neighbours, and the largest inputs.
        let mut worst = (0.0f64, 0.0f32);
        let n = 1 << 20;
        let mut check = |x: f32| {
            let e = error_steps(x);
            if e > worst.0 {
                worst = (e, x);
            }
        };
        for i in -n..=n {
            check((f64::from(i) / f64::from(n) * PI) as f32);
        }
        for k in (-163..=163).filter(|&k| k != 0) {
            // The boundary between two table entries, and the floats either side of it.
            let x = (f64::from(k) * PI / 256.0) as f32;
            for x in [
                x,
                f32::from_bits(x.to_bits() + 1),
                f32::from_bits(x.to_bits() - 1),
            ] {
                check(x);
            }
        }
        for x in [3.999_999_8f32, -3.999_999_8, 0.0, -0.0, 1e-30, 1e-6, -1e-6] {
            check(x);
        }
        assert!(worst.0 <= BOUND, "{} steps at x = {}", worst.0, worst.1);
        // Measured: 1.1 steps (1.0e-9).
        eprintln!("sin_cos: largest error {:.3} steps of 2^-30", worst.0);
    }

    #[test]
    fn outside_the_range_and_not_finite() {
        assert!(error_steps(4.0) <= 1.0);
        assert!(error_steps(-100.0) <= 1.0);
        assert_eq!(sin_cos(f32::NAN), (0, 0));
        assert_eq!(sin_cos(f32::INFINITY), (0, 0));
    }

    proptest! {
        #[test]
        fn within_the_bound_anywhere(x in -3.999_999_8f32..3.999_999_8) {
            prop_assert!(error_steps(x) <= BOUND, "x = {}", x);
        }
    }
}
