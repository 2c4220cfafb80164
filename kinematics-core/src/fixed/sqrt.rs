//! Integer square root: `sqrt(D)` of eq. 9's discriminant in the IK's half-angle root (see
//! [`crate::ik`]), in its fixed-point path.
//!
//! Units: `D` and the root are integers (the IK's `D` is in one power-of-two step of mm^4, the
//! root in that step's square root, mm^2); the result is `sqrt(D)` rounded to a neighbouring
//! integer (within 1).
//!
//! Method: Newton-Raphson iterations (J.-M. Muller, "Elementary Functions: Algorithms and
//! Implementation", chapter "Newton-Raphson and Goldschmidt iterations"; P. Markstein, "IA-64
//! and Elementary Functions", for the coupled form). `D` is shifted left by an even count `2k`
//! into `[2^62, 2^64)`; its top 32 bits, `h`, index an 8-bit table of `1/sqrt` (within 2^-8),
//! which one step `y <- y (3 - h y^2) / 2` in 16-bit products takes to about 2^-13. Then the
//! root itself, `s = h y` (16-bit factors), and twice the coupled step
//! `s <- s + (D - s^2) y / 2`, whose residual `D - s^2` is exact: each step multiplies the
//! error by about `|1 - y sqrt(D)|` (2^-13) and adds `e^2 / 2s`, from 2^20 to about 2^7, then
//! well below 1; the step is rounded to nearest. Shifted back by `k` (rounded), the result is
//! within 1 of `sqrt(D)`.
//!
//! Error bound: 1 (`(s - 1)^2 <= D <= (s + 1)^2`), tested exhaustively for every `D < 2^20`, at
//! and around every 4093rd square up to 2^64 and by proptest. Integer instructions only (no
//! 64-bit multiply, divide or variable shift: [`super::wide_mul`]).

use super::{leading_zeros, table, wide_mul};

/// `2^15 / sqrt((i + 1/2) / 256)` for `i` = 64..=255, rounded: for `h` in `[2^30, 2^32)` with
/// `i = h >> 24`, an estimate of `2^15 / sqrt(h / 2^32)` within 2^-8 (relative).
static INVERSE_ROOTS: [u16; 192] = inverse_roots();

const fn inverse_roots() -> [u16; 192] {
    let mut table = [0; 192];
    let mut i = 0;
    while i < 192 {
        let u = (i as f64 + 64.5) / 256.0;
        table[i] = table::round(32768.0 / table::sqrt(u)) as u16;
        i += 1;
    }
    table
}

/// `s * s` exactly, from three 16 x 16 -> 32-bit products.
#[inline(always)]
fn square_u(s: u32) -> u64 {
    let (hi, lo) = (s >> 16, s & 0xffff);
    (u64::from(hi * hi) << 32) + (u64::from(hi * lo) << 17) + u64::from(lo * lo)
}

/// `sqrt(d)` within 1 (see the module docs for the method).
pub fn sqrt(d: u64) -> u32 {
    let (high, low) = ((d >> 32) as u32, d as u32);
    // d << 2k in [2^62, 2^64), as its two 32-bit words (h on top).
    let (h, l, k) = if high != 0 {
        let k = leading_zeros(high) / 2;
        match 2 * k {
            0 => (high, low, 0),
            shift => ((high << shift) | (low >> (32 - shift)), low << shift, k),
        }
    } else if low != 0 {
        let k = 16 + leading_zeros(low) / 2;
        (low << (2 * k - 32), 0, k)
    } else {
        return 0;
    };
    let d = (u64::from(h) << 32) | u64::from(l);
    // y0 ~ 2^15 / sqrt(u), u = h / 2^32 in [1/4, 1): y0 in (2^15, 2^16).
    let y0 = u32::from(INVERSE_ROOTS[(h >> 24) as usize - 64]);
    // y = y0 (3 - u y0^2) / 2 ~ 2^30 / sqrt(u): u y0^2 in steps of 2^-30 (near 2^30) from
    // 16-bit factors; 3 - u y0^2 near 2, in steps of 2^-14 after the shift, so the product
    // (below 2^31.1) is y0 (3 - u y0^2) in steps of 2^-29: y in steps of 2^-30.
    let u_y0_squared = (h >> 16) * ((y0 * y0) >> 16);
    let y = y0 * ((3u32 << 30).wrapping_sub(u_y0_squared) >> 16);
    // s ~ sqrt(d) = 2^32 sqrt(u) = 2 (h / 2^16)(y / 2^15), below 2^32.
    let mut s = i64::from(((h >> 16) * (y >> 15)).min(0x7fff_ffff) << 1);
    // Coupled steps: s + (d - s^2) / (2 sqrt(d)), with 1 / (2 sqrt(d)) = y / 2^63; the
    // residual is below 2^53 (first step) and 2^42 (second), so r / 2^23 fits 31 bits.
    for _ in 0..2 {
        let r = d.wrapping_sub(square_u(s as u32)) as i64;
        s += (wide_mul((r >> 23) as i32, (y >> 1) as i32) + (1 << 38)) >> 39;
        s = s.clamp(0, i64::from(u32::MAX));
    }
    // Back by k, rounded (k = 0 only for d >= 2^62).
    let s = s as u32;
    if k == 0 {
        s
    } else {
        (s >> k) + ((s >> (k - 1)) & 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// `|s - sqrt(d)| <= 1`, exactly: `(s - 1)^2 <= d <= (s + 1)^2`.
    fn is_root_within_1(d: u64, s: u32) -> bool {
        let (s, d) = (u128::from(s), u128::from(d));
        s.saturating_sub(1).pow(2) <= d && d <= (s + 1).pow(2)
    }

    #[test]
    fn table_is_rounded() {
        for (i, &entry) in INVERSE_ROOTS.iter().enumerate() {
            let exact = 32768.0 / libm::sqrt((i as f64 + 64.5) / 256.0);
            assert!((f64::from(entry) - exact).abs() <= 0.5, "i = {i}");
        }
    }

    #[test]
    fn within_1_for_every_small_input() {
        for d in 0..1u64 << 20 {
            assert!(is_root_within_1(d, sqrt(d)), "{d}");
        }
    }

    #[test]
    fn within_1_around_squares_and_powers_of_two() {
        // s^2 - 1, s^2, s^2 + 1 for s spread over the whole range (every 2^12-th s, then the
        // top), and every power of two and its neighbours.
        let mut s = 1u64;
        while s <= u64::from(u32::MAX) {
            let square = s * s;
            for d in [square - 1, square, square + 1] {
                assert!(is_root_within_1(d, sqrt(d)), "{d}");
            }
            s += if s < 1 << 16 { 1 } else { 4093 };
        }
        for shift in 0..64 {
            let p = 1u64 << shift;
            for d in [p - 1, p, p + 1] {
                assert!(is_root_within_1(d, sqrt(d)), "{d}");
            }
        }
        assert!(is_root_within_1(u64::MAX, sqrt(u64::MAX)));
    }

    proptest! {
        #[test]
        fn within_1_anywhere(d in any::<u64>(), shift in 0u32..64) {
            let d = d >> shift;
            prop_assert!(is_root_within_1(d, sqrt(d)), "{}", d);
            // And against f64 (which rounds d, so only within a unit).
            let f = libm::sqrt(d as f64);
            prop_assert!((f64::from(sqrt(d)) - f).abs() <= 1.0);
        }
    }
}
