//! Integer square root: `sqrt(D)` of eq. 9's discriminant in the IK's half-angle root (see
//! [`crate::ik`]), in its fixed-point path.
//!
//! Units: `D` and the root are integers (the IK's `D` is in one power-of-two step of mm^4, the
//! root in that step's square root, mm^2); the result is `sqrt(D)` within 1 below 2^60 (every
//! `D` of the IK: below 2^59), within 2 above.
//!
//! Method: Newton-Raphson iterations (J.-M. Muller, "Elementary Functions: Algorithms and
//! Implementation", chapter "Newton-Raphson and Goldschmidt iterations"; P. Markstein, "IA-64
//! and Elementary Functions", for the coupled form). `D` is shifted left by an even count `2k`
//! into `[2^62, 2^64)`; its top 32 bits, `h`, index an 8-bit table of `1/sqrt` (within 2^-8),
//! which one step `y <- y (3 - h y^2) / 2` in 16-bit products takes to about 2^-13. Then the
//! root itself, `s = h y` (16-bit factors), and twice the coupled step
//! `s <- s + (h - s^2) y / 2`, all in 32-bit words: the residual `h - s^2` in steps of 2^32 of
//! the shifted `D` (within one step), the product with `y` cut so it fits 31 bits (13 bits of
//! `y` in the first step, 16 in the second). Each step multiplies the error by about
//! `|1 - y sqrt(h)|` and adds its own cuts; after the second the 32-bit root is within 2 of
//! `sqrt(D << 2k)`. Shifted back by `k` (rounded: `k >= 1` below 2^60), the result is within
//! 1 of `sqrt(D)`.
//!
//! Error bound: 2, and 1 below 2^60 (`(s - 1)^2 <= D <= (s + 1)^2`), tested exhaustively for
//! every `D < 2^20`, at and around every 4093rd square up to 2^64 and by proptest. The
//! IK needs far less: a relative error `e` of the root moves the half-angle of eq. 9 by at
//! most `e` rad (module `crate::ik`). Integer instructions only, 32-bit products only (no
//! 64-bit multiply, divide or variable shift): 129 cycles a call on the M0+ (measured in the
//! IK benchmark), where the previous form (64-bit residuals and products) took 236.

use super::{leading_zeros, table};

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

/// `sqrt(d)` within 2, and within 1 for `d < 2^60` (see the module docs for the method and
/// the bound).
pub fn sqrt(d: u64) -> u32 {
    let (high, low) = ((d >> 32) as u32, d as u32);
    // The top 32 bits `h` of d << 2k in [2^62, 2^64) (the rest, below 2^32 of it, moves the
    // root by less than one step of 2^-32 of its size: within the bound).
    let (h, k) = if high != 0 {
        let k = leading_zeros(high) / 2;
        match 2 * k {
            0 => (high, 0),
            shift => ((high << shift) | (low >> (32 - shift)), k),
        }
    } else if low != 0 {
        let k = 16 + leading_zeros(low) / 2;
        (low << (2 * k - 32), k)
    } else {
        return 0;
    };
    // y0 ~ 2^15 / sqrt(u), u = h / 2^32 in [1/4, 1): y0 in (2^15, 2^16).
    let y0 = u32::from(INVERSE_ROOTS[(h >> 24) as usize - 64]);
    // y = y0 (3 - u y0^2) / 2 ~ 2^30 / sqrt(u), in (2^30, 2^31]: u y0^2 in steps of 2^-30
    // (near 2^30) from 16-bit factors; 3 - u y0^2 near 2, in steps of 2^-14 after the shift, so
    // the product is y0 (3 - u y0^2) in steps of 2^-29: y in steps of 2^-30.
    let u_y0_squared = (h >> 16) * ((y0 * y0) >> 16);
    let y = y0 * ((3u32 << 30).wrapping_sub(u_y0_squared) >> 16);
    // s ~ sqrt(h 2^32) = 2^32 sqrt(u) = 2 (h / 2^16)(y / 2^15), below 2^32.
    let mut s = ((h >> 16) * (y >> 15)).min(0x7fff_ffff) << 1;
    // Two steps s + (h 2^32 - s^2) / (2 sqrt(h 2^32)), with 1 / (2 sqrt(h 2^32)) = y / 2^63:
    // the residual in steps of 2^32, `h - floor(s^2 / 2^32)` within 1, from the 16-bit halves
    // of `s` (`a^2 + 2ab / 2^16`, the `b^2` below one step), in wrapping 32-bit words (its true
    // value is below 2^19 in magnitude); times `y` cut to 13 bits in the first step (the
    // product below 2^30.1), to 16 bits in the second (below 2^22.2).
    for (y_cut, product_cut) in [(19, 12), (16, 15)] {
        let (a, b) = (s >> 16, s & 0xffff);
        let residual = h.wrapping_sub(a * a).wrapping_sub((a * b) >> 15) as i32;
        s = s.saturating_add_signed((residual * (y >> y_cut) as i32) >> product_cut);
    }
    // Back by k, rounded (k = 0 only for d >= 2^62).
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

    /// The bound of the module docs: 1 below 2^60, 2 above.
    fn bound(d: u64) -> u32 {
        if d < 1 << 60 {
            1
        } else {
            2
        }
    }

    /// `|s - sqrt(d)| <=` [`bound`], exactly: `(s - b)^2 <= d <= (s + b)^2`.
    fn is_root_within_bound(d: u64, s: u32) -> bool {
        let b = u128::from(bound(d));
        let (s, d) = (u128::from(s), u128::from(d));
        s.saturating_sub(b).pow(2) <= d && d <= (s + b).pow(2)
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
            assert!(is_root_within_bound(d, sqrt(d)), "{d}");
        }
    }

    #[test]
    fn within_the_bound_around_squares_and_powers_of_two() {
        // s^2 - 1, s^2, s^2 + 1 for s spread over the whole range (every 2^12-th s, then the
        // top), and every power of two and its neighbours.
        let mut s = 1u64;
        while s <= u64::from(u32::MAX) {
            let square = s * s;
            for d in [square - 1, square, square + 1] {
                assert!(is_root_within_bound(d, sqrt(d)), "{d}");
            }
            s += if s < 1 << 16 { 1 } else { 4093 };
        }
        for shift in 0..64 {
            let p = 1u64 << shift;
            for d in [p - 1, p, p + 1] {
                assert!(is_root_within_bound(d, sqrt(d)), "{d}");
            }
        }
        assert!(is_root_within_bound(u64::MAX, sqrt(u64::MAX)));
    }

    #[test]
    fn within_the_bound_over_the_whole_shifted_range() {
        // Every 2^10-th top word `h` of a shifted `D` in [2^62, 2^64), with the low bits empty
        // and full, at k = 0 (`D` itself) and k = 2 (`D / 16`, as the IK's): the products of
        // the coupled steps stay within 31 bits (this debug build would panic on an overflow).
        let mut h = 1u64 << 30;
        while h < 1 << 32 {
            for d in [h << 32, h << 32 | 0xffff_ffff] {
                assert!(is_root_within_bound(d, sqrt(d)), "{d}");
                assert!(is_root_within_bound(d >> 4, sqrt(d >> 4)), "{}", d >> 4);
            }
            h += 1 << 10;
        }
    }

    proptest! {
        #[test]
        fn within_the_bound_anywhere(d in any::<u64>(), shift in 0u32..64) {
            let d = d >> shift;
            prop_assert!(is_root_within_bound(d, sqrt(d)), "{}", d);
            // And against f64 (which rounds d, so only within the bound).
            let f = libm::sqrt(d as f64);
            prop_assert!((f64::from(sqrt(d)) - f).abs() <= f64::from(bound(d)));
        }
    }
}
