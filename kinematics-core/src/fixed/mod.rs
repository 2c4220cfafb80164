//! Fixed-point arithmetic for the IK's hot loop on a chip without an FPU (the RP2040's
//! Cortex-M0+), in integer instructions only.
//!
//! Formats, each an integer counting steps of a power of two:
//! - lengths, mm: `i32` in steps of 2^-[`MM_FRAC`] mm (2^-20 mm, about 1e-6 mm);
//! - rotation matrix entries (no unit) and sines and cosines: `i32` in steps of
//!   2^-[`ROT_FRAC`];
//! - squared lengths, mm^2: `i64` in steps of 2^-[`SQ_FRAC`] mm^2 (2^-36 mm^2), or, on the
//!   IK's 32-bit path (every usual leg: the `NARROW_*` bounds), `i32` in steps of
//!   2^-[`NARROW_SQ_FRAC`] mm^2 (2^-15 mm^2);
//! - angles, rad: `i32` in steps of 2^-[`ANGLE_FRAC`] rad (the half-angles of eq. 9), which
//!   are the arm angles in steps of 2^-[`ARM_FRAC`] rad.
//!
//! The `MAX_FIXED_*` bounds say which values the formats take without overflow anywhere in the
//! IK's sums; the IK checks them and falls back to `f32` arithmetic beyond them. Integer
//! arithmetic is the same on every machine, so the host runs exactly what the chip runs.
//!
//! The functions the IK needs, each in its own module with its method, its source and its
//! error bound: [`sin_cos`] (the pose's rotation, eq. 1), [`sqrt`] and [`atan2`] (the arm
//! angle, eq. 9). They are the default of [`crate::math::Math`]'s fixed-point functions.
//! They build on this module's formats, products and conversions, which import none of them.

pub mod atan2;
pub mod sin_cos;
pub mod sqrt;
mod table;

/// Fraction bits of the rotation entries `R_kj` (eq. 1 of "The Mathematics of the Stewart
/// Platform") in fixed point.
pub(crate) const ROT_FRAC: u32 = 30;
/// Fraction bits of lengths (mm): steps of 2^-20 mm ~ 1e-6 mm, finer than an `f32` of the leg
/// lengths (~100 mm, ulp 7.6e-6 mm) resolves.
pub(crate) const MM_FRAC: u32 = 20;
/// Bound (exclusive) on `|p_i|`, `|offset_i|` (per coordinate) and on `|x|, |y|, |z|` for the
/// fixed-point part of the IK, mm. With `|R_kj| < 1 + 2^-4` ([`MAX_ROTATION_ENTRY`]),
/// `|l_k| < 2 * 1.0625 * 384 + 384 + 384 < 1600 mm`, inside the 2048 mm an `i32` with
/// [`MM_FRAC`] fraction bits holds. Larger geometries and poses take the float path (such a
/// pose is far outside any workspace anyway).
pub(crate) const MAX_FIXED_MM: f32 = 384.0;
/// Fraction bits of the squared lengths (mm^2) `|l|^2`, `L`, `M`, `N` of eq. 9: the exact
/// products of two [`MM_FRAC`] numbers (2^-40 mm^2) cut to 2^-36 mm^2 (3e-11 mm^2, while an
/// `f32` of ~1e4 mm^2 has steps of 1e-3 mm^2), which leaves an `i64` room for every sum:
/// `|l|^2 < 3 * 1600^2 mm^2` is below 2^59 of these steps.
pub(crate) const SQ_FRAC: u32 = 36;
/// Bound (exclusive) on `2a` for the fixed-point part, mm: `|N|, |M| < 2a |l| < 2^21 mm^2`.
pub(crate) const MAX_FIXED_TWO_ARM_MM: f32 = 2.0 * MAX_FIXED_MM;
/// Bound (exclusive) on `|s^2 - a^2|` for the fixed-point part, mm^2 (a rod up to ~6 m):
/// `|L +- N| < 2^23 + 4e7 + 2^21 < 2^26 mm^2`, which is 2^62 steps of [`SQ_FRAC`].
pub(crate) const MAX_FIXED_ROD_TERM_MM2: f32 = 4.0e7;
/// Fraction bits of the squared lengths (mm^2) of the IK's 32-bit path (the usual one, see
/// [`crate::ik`]): steps of 2^-15 mm^2 (3.1e-5 mm^2), so that `|l|^2` below 2^16 mm^2 (a leg
/// shorter than 256 mm) fits 31 bits. Each product there is within 0.51 of a step, while the
/// error of `l` itself (each coordinate within 2^-19 mm, [`rotate_mm_split`]) already moves
/// `|l|^2` by up to about `|l|` 2^-17 mm^2 (30 steps for a 120 mm leg; the pose's own `f32`
/// steps are coarser still): the coarser step costs the arm angle nothing measurable.
pub(crate) const NARROW_SQ_FRAC: u32 = 15;
/// Bound (exclusive) on each coordinate of `l` for the 32-bit path, in steps of 2^-[`MM_FRAC`]
/// mm: 256 mm. A larger one takes the 64-bit path.
pub(crate) const NARROW_LEG_Q: u32 = 1 << 28;
/// Bound (exclusive) on `2a` (and so on `|n_i|`) for the 32-bit path, mm: 128 mm, so that
/// `|N|, |M| < 2a |l_k| < 2^15 mm^2` (2^30 steps) each. A larger arm takes the 64-bit path.
pub(crate) const MAX_NARROW_TWO_ARM_MM: f32 = 128.0;
/// Bound (exclusive) on `s^2 - a^2` for the 32-bit path, mm^2 (it must also be `>= 0`): 2^16
/// mm^2, 2^31 steps of 2^-[`NARROW_SQ_FRAC`], so `L = |l|^2 - (s^2 - a^2)` fits an `i32`.
pub(crate) const MAX_NARROW_ROD_TERM_MM2: f64 = 65536.0;

/// Fraction bits of an angle from [`atan2`] (rad): `|angle| <= pi` fits an `i32`.
pub(crate) const ANGLE_FRAC: u32 = 29;
/// Fraction bits of an arm angle `alpha = 2 atan2(...)` (eq. 9; rad): the same integer as its
/// half-angle in steps of 2^-[`ANGLE_FRAC`].
pub(crate) const ARM_FRAC: u32 = ANGLE_FRAC - 1;
/// Bound (exclusive) on `|R_kj|` for the fixed-point part, in steps of 2^-[`ROT_FRAC`]: 1 plus
/// far more than any rounding (even a coarse library's sines, see [`crate::math::FloatRoutines`]).
pub(crate) const MAX_ROTATION_ENTRY: i32 = (1 << ROT_FRAC) + (1 << (ROT_FRAC - 4));

/// `x * 2^frac` rounded to the nearest integer (halves away from zero), in integer
/// instructions. `|x| * 2^frac` must be below 2^31 (the callers bound `x` first). Always
/// inlined: the IK converts the pose's position with it, where a call costs a third more.
#[inline(always)]
pub(crate) fn to_fixed(x: f32, frac: u32) -> i32 {
    let bits = x.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32;
    if exponent == 0 {
        return 0; // zero or subnormal: far below 2^-frac
    }
    let mantissa = ((bits & 0x7f_ffff) | 0x80_0000) as i32;
    // x = mantissa * 2^(exponent - 150).
    let shift = exponent - 150 + frac as i32;
    let magnitude = if shift >= 0 {
        mantissa << shift
    } else if shift > -26 {
        ((mantissa >> (-shift - 1)) + 1) >> 1
    } else {
        0
    };
    if bits >> 31 != 0 {
        -magnitude
    } else {
        magnitude
    }
}

/// `x * 2^frac` rounded to the nearest integer (halves away from zero), in integer
/// instructions, as [`to_fixed`] but wider: `|x| * 2^frac` must be below 2^62. (The exact form
/// `fixed::sin_cos`'s 32-bit conversion is tested against.)
#[cfg(test)]
pub(crate) fn to_fixed_wide(x: f32, frac: u32) -> i64 {
    let bits = x.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32;
    if exponent == 0 {
        return 0; // zero or subnormal
    }
    let mantissa = (bits & 0x7f_ffff) | 0x80_0000;
    // x = mantissa * 2^(exponent - 150); the shifts are of 32-bit words (a variable 64-bit
    // shift is a library call on the M0+).
    let shift = exponent - 150 + frac as i32;
    let magnitude = if shift >= 32 {
        i64::from(mantissa << (shift - 32)) << 32
    } else if shift > 0 {
        ((i64::from(mantissa >> (32 - shift))) << 32) | i64::from(mantissa << shift)
    } else if shift == 0 {
        i64::from(mantissa)
    } else if shift > -26 {
        i64::from(((mantissa >> -shift) + ((mantissa >> (-shift - 1)) & 1)) as i32)
    } else {
        0
    };
    if bits >> 31 != 0 {
        -magnitude
    } else {
        magnitude
    }
}

/// A squared length `x_mm2` (mm^2, given in `f64`) in steps of 2^-[`SQ_FRAC`] mm^2, rounded
/// to nearest (halves away from zero). `|x_mm2|` must be below [`MAX_FIXED_ROD_TERM_MM2`].
pub(crate) fn to_fixed_sq(x_mm2: f64) -> i64 {
    libm::round(x_mm2 * (1u64 << SQ_FRAC) as f64) as i64
}

/// `a * b` exactly, for any `i32`s, from four 16 x 16 -> 32-bit products: the M0+ multiplies
/// 32 x 32 -> 32 bits in one cycle, while the library's 64-bit multiply takes ~55. With
/// `a = a_hi 2^16 + a_lo` (`a_hi` signed, `a_lo` in `[0, 2^16)`), every partial product fits
/// 32 bits: `|a_hi b_hi| <= 2^30`, `|a_hi b_lo| < 2^31`, `a_lo b_lo < 2^32` (unsigned).
#[inline]
pub(crate) fn wide_mul(a: i32, b: i32) -> i64 {
    let (a_hi, a_lo) = (a >> 16, a & 0xffff);
    let (b_hi, b_lo) = (b >> 16, b & 0xffff);
    let low = (a_lo as u32) * (b_lo as u32);
    (i64::from(a_hi * b_hi) << 32)
        + ((i64::from(a_hi * b_lo) + i64::from(a_lo * b_hi)) << 16)
        + i64::from(low)
}

/// [`rotate_mm_split`] of factors not yet split (the tests' form).
#[cfg(test)]
pub(crate) fn rotate_mm(row: [i32; 2], p_mm: [i32; 2]) -> i32 {
    rotate_mm_split(row.map(split15), p_mm.map(split15))
}

/// `v` split at bit 15: `[v >> 15, v & 0x7fff]` (`v = hi 2^15 + lo`, `0 <= lo < 2^15`), the
/// factors of [`rotate_mm_split`].
#[inline(always)]
pub(crate) const fn split15(v: i32) -> [i32; 2] {
    [v >> 15, v & 0x7fff]
}

/// `R_k0 p_0 + R_k1 p_1` for a row `(R_k0, R_k1)` in steps of 2^-[`ROT_FRAC`] (below
/// [`MAX_ROTATION_ENTRY`]) and a point `(p_0, p_1)` in steps of 2^-[`MM_FRAC`] mm (below
/// [`MAX_FIXED_MM`]), in steps of 2^-[`MM_FRAC`] mm, within 2 steps (1.9e-6 mm) of the exact sum
/// and unbiased, in 32-bit products only: each factor split at bit 15 (`R = R_hi 2^15 + R_lo`,
/// `p` alike, the lows in `[0, 2^15)`), the whole part `R_hi p_hi` exact, the cross products
/// `R_hi p_lo + R_lo p_hi` exact in steps of 2^-35 mm, the two columns' fractions halved before
/// they are summed (so the sum fits 32 bits). The low products `R_lo p_lo`, each in `[0, 1)`
/// step, are not computed (three instructions each, 36 a pose): their sum, in `[0, 2)` steps,
/// is taken as its mean, half a step (a product of two lows spread evenly averages a quarter),
/// so before the rounding to nearest the result is within `(-1.5, 0.5]` steps of the exact
/// sum, after it within `(-2, 1]` (and the halvings' 2^-13). The leg vector comes from a pose
/// given in `f32` (steps of 7.6e-6 mm at 100 mm): this costs the IK nothing it could resolve
/// (`tests::rotation_products_are_within_two_steps`, and the IK's accuracy tests).
///
/// Both factors come split ([`split15`]): the IK splits each pose's rows once and each leg's
/// point when the solver is built, not in every product.
#[inline(always)]
pub(crate) fn rotate_mm_split(row: [[i32; 2]; 2], p_mm: [[i32; 2]; 2]) -> i32 {
    // |R_hi| <= 2^15 + 2^11, |p_hi| < 2^13.6, the lows below 2^15: every product and the
    // fraction (below 2^30.6) fit 32 bits.
    let part =
        |[r_hi, r_lo]: [i32; 2], [p_hi, p_lo]: [i32; 2]| (r_hi * p_hi, r_hi * p_lo + r_lo * p_hi);
    let (whole_0, fraction_0) = part(row[0], p_mm[0]);
    let (whole_1, fraction_1) = part(row[1], p_mm[1]);
    // Halved fractions in steps of 2^-14 of a step: half a step to round to nearest (2^13)
    // and the low products' mean, half a step (2^13).
    whole_0 + whole_1 + (((fraction_0 >> 1) + (fraction_1 >> 1) + (1 << 14)) >> 14)
}

/// `a * b / 2^30` rounded to nearest (halves up), exactly as `(a b + 2^29) >> 30` in 64 bits,
/// for `|a| < 2^30` and `0 <= b < 2^30`, from four 32-bit products (a 64-bit product costs
/// several times as much on the M0+): with `a = a_hi 2^15 + a_lo`, `b = b_hi 2^15 + b_lo` (the
/// lows in `[0, 2^15)`), `a b = a_hi b_hi 2^30 + (a_hi b_lo + a_lo b_hi) 2^15 + a_lo b_lo`, and
/// `floor((x 2^15 + y) / 2^30) = floor((x + floor(y / 2^15)) / 2^15)`; the middle sum stays
/// below 2^31 - 2^16.
#[inline(always)]
pub(crate) fn mul_q30(a: i32, b: i32) -> i32 {
    let [a_hi, a_lo] = split15(a);
    let [b_hi, b_lo] = split15(b);
    let low = ((a_lo * b_lo) as u32 + (1 << 29)) >> 15;
    a_hi * b_hi + ((a_hi * b_lo + a_lo * b_hi + low as i32) >> 15)
}

/// `a * b / 2^30` rounded to nearest, for `|a|, |b| <= 2^30 + 2^28` (sines, cosines and their
/// products in steps of 2^-30: the pose's rotation), from four 32-bit products (a 64-bit
/// product and its rounding cost several times as much on the M0+): with `a = a_hi 2^15 + a_lo`,
/// `b` alike (the lows in `[0, 2^15)`), `a b / 2^30 = a_hi b_hi + m / 2^14` with
/// `m = (a_hi b_lo + a_lo b_hi) / 2 + a_lo b_lo / 2^16`, each of its three terms cut (so within
/// 3 steps of 2^-14 below the exact `m`); `|a_hi b_hi| <= 2^30.7` and `|m| < 2^30.4`. Within
/// 0.5 + 2^-12 of a step of the exact product.
#[inline(always)]
pub(crate) fn mul_rot(a: i32, b: i32) -> i32 {
    let [a_hi, a_lo] = split15(a);
    let [b_hi, b_lo] = split15(b);
    let m = ((a_hi * b_lo) >> 1) + ((a_lo * b_hi) >> 1) + ((a_lo * b_lo) >> 16);
    a_hi * b_hi + ((m + (1 << 13)) >> 14)
}

/// `a * a` exactly, from three 16 x 16 -> 32-bit products (see [`wide_mul`]).
#[inline]
pub(crate) fn square(a: i32) -> i64 {
    let (a_hi, a_lo) = (a >> 16, a & 0xffff);
    let low = (a_lo as u32) * (a_lo as u32);
    (i64::from(a_hi * a_hi) << 32) + (i64::from(a_hi * a_lo) << 17) + i64::from(low)
}

/// The square of a length in steps of 2^-[`MM_FRAC`] mm, as [`mul_mm`].
#[inline(always)]
pub(crate) fn square_mm(a: i32) -> i64 {
    square(a) >> (2 * MM_FRAC - SQ_FRAC)
}

/// The product of two lengths in steps of 2^-[`MM_FRAC`] mm, exact, cut (rounded towards
/// minus infinity) to steps of 2^-[`SQ_FRAC`] mm^2.
#[inline(always)]
pub(crate) fn mul_mm(a: i32, b: i32) -> i64 {
    wide_mul(a, b) >> (2 * MM_FRAC - SQ_FRAC)
}

/// `|l|^2 = l_x^2 + l_y^2 + l_z^2` of a leg vector `l` in steps of 2^-[`MM_FRAC`] mm, every
/// `|l_k| < 2^28` (256 mm), in steps of 2^-[`NARROW_SQ_FRAC`] mm^2, rounded to nearest once
/// (within 0.51 of a step), from nine 32-bit products (the IK's 32-bit path); `None` if it is
/// 2^31 steps (2^16 mm^2) or more. With `|l_k| = h_k 2^13 + r_k` (`h_k < 2^15`, `r_k < 2^13`):
/// `|l|^2 / 2^25 = 2 sum h_k^2 + (sum h_k r_k + (sum r_k^2) / 2^14) / 2^11`, where
/// `sum h_k^2 < 2^31.6` (and only below 2^30 can the result be below 2^31), `sum h_k r_k` below
/// 2^29.6 and `(sum r_k^2) / 2^14` below 2^13.6, cut (within 2^-11 of a step): one rounding for
/// the sum, where three squares rounded on their own took three and a 64-bit sum.
#[inline(always)]
pub(crate) fn leg_square_narrow(l: [i32; 3]) -> Option<u32> {
    let [(h_x, r_x), (h_y, r_y), (h_z, r_z)] = l.map(|v| {
        let u = v.unsigned_abs();
        (u >> 13, u & 0x1fff)
    });
    let whole = h_x * h_x + h_y * h_y + h_z * h_z;
    if whole >= 1 << 30 {
        return None;
    }
    let fraction = h_x * r_x + h_y * r_y + h_z * r_z + ((r_x * r_x + r_y * r_y + r_z * r_z) >> 14);
    let sum = 2 * whole + ((fraction + (1 << 10)) >> 11);
    (sum < 1 << 31).then_some(sum)
}

/// The product of two lengths in steps of 2^-[`MM_FRAC`] mm, `|a| < 2^27` (128 mm) and
/// `|b| < 2^28` (256 mm), in steps of 2^-[`NARROW_SQ_FRAC`] mm^2, rounded to nearest within
/// 0.51 of a step, from four 32-bit products (the IK's 32-bit path). With `a = h_a 2^13 + r_a`
/// (`h_a` signed, `|h_a| <= 2^14`, `0 <= r_a < 2^13`) and `b` alike (`|h_b| <= 2^15`):
/// `a b / 2^25 = 2 h_a h_b + (h_a r_b + r_a h_b + r_a r_b / 2^13) / 2^12`, every product and
/// sum below 2^30 in magnitude, the result within 2^30 + 2^17.
/// `a` comes split ([`split13`]): the IK splits its constant factors (`2a`, `n_i`) once, when
/// the solver is built.
#[inline(always)]
pub(crate) fn mul_mm_narrow([a_hi, a_lo]: [i32; 2], b: i32) -> i32 {
    let [b_hi, b_lo] = split13(b);
    2 * a_hi * b_hi + ((a_hi * b_lo + a_lo * b_hi + ((a_lo * b_lo) >> 13) + (1 << 11)) >> 12)
}

/// `v` split at bit 13: `[v >> 13, v & 0x1fff]` (`v = hi 2^13 + lo`, `0 <= lo < 2^13`), the
/// factors of [`mul_mm_narrow`].
#[inline(always)]
pub(crate) const fn split13(v: i32) -> [i32; 2] {
    [v >> 13, v & 0x1fff]
}

/// The leading zeros of every byte value (8 for 0).
static BYTE_LEADING_ZEROS: [u8; 256] = byte_leading_zeros();

const fn byte_leading_zeros() -> [u8; 256] {
    let mut table = [8; 256];
    let mut b = 1;
    while b < 256 {
        let mut zeros = 0;
        while b << zeros < 128 {
            zeros += 1;
        }
        table[b] = zeros;
        b += 1;
    }
    table
}

/// `m.leading_zeros()` (32 for 0) from the leading byte and a table: the M0+ has no
/// count-leading-zeros instruction, and the library's binary search takes several times as long.
#[inline(always)]
pub(crate) fn leading_zeros(m: u32) -> u32 {
    let (base, byte) = if m >= 1 << 16 {
        if m >= 1 << 24 {
            (0, m >> 24)
        } else {
            (8, m >> 16)
        }
    } else if m >= 1 << 8 {
        (16, m >> 8)
    } else {
        (24, m)
    };
    base + u32::from(BYTE_LEADING_ZEROS[byte as usize])
}

/// `m` shifted so its leading one is bit 31, and the shift. `m != 0`.
#[inline(always)]
pub(crate) fn normalise(m: u32) -> (u32, u32) {
    let shift = leading_zeros(m);
    (m << shift, shift)
}

/// The `f32` nearest (ties to even) to `sign * m * 2^(exponent - 158)`, where `m` has its
/// leading one in bit 31, `sticky` says whether non-zero bits were cut off below `m`, and the
/// result is a normal number. In integer instructions: a carry out of the mantissa moves into
/// the exponent field, which is then right.
#[inline(always)]
fn pack(sign: u32, m: u32, sticky: bool, exponent: u32) -> f32 {
    // Up exactly when the cut bits are above half, or at half with sticky bits or an odd
    // mantissa: `rest + (odd | sticky) >= 0x81`, without a branch (the sum is below 0x180).
    let mantissa = m >> 8;
    let rest = m & 0xff;
    let mantissa = mantissa + ((rest + ((mantissa & 1) | u32::from(sticky)) + 0x7f) >> 8);
    f32::from_bits(sign | ((exponent << 23) + mantissa - (1 << 23)))
}

/// `v * 2^-frac` rounded to the nearest `f32` (ties to even), in integer instructions, as
/// [`from_fixed`] for an `i32` (shorter on the M0+). `frac <= 100`.
#[inline]
pub(crate) fn from_fixed32(v: i32, frac: u32) -> f32 {
    if v == 0 {
        return 0.0;
    }
    let sign = v as u32 & 0x8000_0000;
    let (m, shift) = normalise(v.unsigned_abs());
    pack(sign, m, false, 127 + 31 - frac - shift)
}

/// `v * 2^-frac` rounded to the nearest `f32` (ties to even), in integer instructions.
/// `frac <= 100` (the result is then a normal number or zero).
#[inline]
pub(crate) fn from_fixed(v: i64, frac: u32) -> f32 {
    let sign = (v >> 32) as u32 & 0x8000_0000;
    let magnitude = v.unsigned_abs();
    let (high, low) = ((magnitude >> 32) as u32, magnitude as u32);
    if high == 0 {
        if low == 0 {
            return 0.0;
        }
        let (m, shift) = normalise(low);
        return pack(sign, m, false, 127 + 31 - frac - shift);
    }
    let (_, shift) = normalise(high);
    let (m, sticky) = if shift == 0 {
        (high, low != 0)
    } else {
        ((high << shift) | (low >> (32 - shift)), low << shift != 0)
    };
    pack(sign, m, sticky, 127 + 63 - frac - shift)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::xorshift;

    /// `from_fixed` of `w` and `from_fixed32` of its low half are Rust's own `as f32`
    /// conversions (one rounding, to nearest even) scaled by an exact power of two.
    fn assert_converts_as_rust_rounds(w: i64) {
        let expected = w as f32 * (-(SQ_FRAC as f32)).exp2();
        assert_eq!(from_fixed(w, SQ_FRAC).to_bits(), expected.to_bits(), "{w}");
        let v = w as i32;
        let expected = v as f32 * (-(ARM_FRAC as f32)).exp2();
        assert_eq!(
            from_fixed32(v, ARM_FRAC).to_bits(),
            expected.to_bits(),
            "{v}"
        );
    }

    #[test]
    fn fixed_point_conversions_and_products_are_exact() {
        let mut seed = 0x1234_5678_u32;
        let mut next = || xorshift(&mut seed);
        for _ in 0..100_000 {
            let (a, b) = (next() as i32 >> (next() % 8), next() as i32 >> (next() % 8));
            if a == i32::MIN || b == i32::MIN {
                continue;
            }
            assert_eq!(wide_mul(a, b), i64::from(a) * i64::from(b), "{a} * {b}");
            let scale = f64::from(1u32 << MM_FRAC);
            // `i64 as f32` rounds once, to nearest even; the power of two scales exactly.
            let w = ((u64::from(next()) << 32 | u64::from(next())) as i64) >> (next() % 64);
            assert_converts_as_rust_rounds(w);
            let x = f32::from_bits(next()) % MAX_FIXED_MM;
            if x.is_finite() {
                let expected = (f64::from(x) * scale).round() as i32;
                assert_eq!(to_fixed(x, MM_FRAC), expected, "{x}");
                let r = x / MAX_FIXED_MM;
                let expected = (f64::from(r) * f64::from(1u32 << ROT_FRAC)).round() as i32;
                assert_eq!(to_fixed(r, ROT_FRAC), expected, "{r}");
            }
        }
    }

    #[test]
    fn products_leading_zeros_and_wide_conversions_are_exact() {
        let mut seed = 0x8765_4321_u32;
        let mut next = || xorshift(&mut seed);
        let extremes = [0, 1, -1, i32::MAX, i32::MIN, 0xffff, -0x10000, 0x7fff_0000];
        for &a in &extremes {
            for &b in &extremes {
                assert_eq!(wide_mul(a, b), i64::from(a) * i64::from(b), "{a} * {b}");
            }
            assert_eq!(square(a), i64::from(a) * i64::from(a), "{a}^2");
        }
        for _ in 0..100_000 {
            let (a, b) = (next(), next() >> (next() % 32));
            assert_eq!(square(a as i32), i64::from(a as i32).pow(2), "{a}^2");
            assert_eq!(leading_zeros(b), b.leading_zeros(), "{b}");
            let x = f32::from_bits(next()) % 4.0;
            if x.is_finite() {
                for frac in [36, 46, 58] {
                    let expected = libm::round(f64::from(x) * (frac as f64).exp2()) as i64;
                    assert_eq!(to_fixed_wide(x, frac), expected, "{x} {frac}");
                }
            }
        }
        assert_eq!(leading_zeros(0), 32);
    }

    #[test]
    fn rotation_products_are_within_two_steps() {
        // Against the exact sum of exact products, over random rows and points within the
        // bounds and at their extremes: within 2 steps (the low products taken as their mean,
        // then the rounding to nearest; see `rotate_mm_split`), and unbiased: the mean error
        // within 0.01 of a step.
        let mut seed = 0x2468_ace1_u32;
        let mut next = || xorshift(&mut seed);
        let r_max = MAX_ROTATION_ENTRY - 1;
        let p_max = to_fixed(MAX_FIXED_MM, MM_FRAC) - 1;
        let (mut worst, mut sum) = (0.0f64, 0.0f64);
        for i in 0..200_000 {
            let (row, p) = if i < 16 {
                let sign = |b: u32, v: i32| if i >> b & 1 == 0 { v } else { -v };
                (
                    [sign(0, r_max), sign(1, r_max)],
                    [sign(2, p_max), sign(3, p_max)],
                )
            } else {
                let spread = |n: u32, max: i32| {
                    (i64::from(n) % (2 * i64::from(max)) - i64::from(max)) as i32
                };
                let (r, q) = (|n| spread(n, r_max), |n| spread(n, p_max));
                ([r(next()), r(next())], [q(next()), q(next())])
            };
            let exact = (i128::from(row[0]) * i128::from(p[0])
                + i128::from(row[1]) * i128::from(p[1])) as f64
                / f64::from(1u32 << ROT_FRAC);
            let error = f64::from(rotate_mm(row, p)) - exact;
            worst = worst.max(error.abs());
            sum += error;
        }
        assert!(worst <= 2.0, "{worst} steps");
        assert!(
            (sum / 200_000.0).abs() < 0.01,
            "mean error {} steps",
            sum / 200_000.0
        );
    }

    #[test]
    fn q30_products_are_exactly_rounded() {
        let mut seed = 0x0bad_cafe_u32;
        let mut next = || xorshift(&mut seed);
        let (a_max, b_max) = ((1i32 << 30) - 1, (1i32 << 30) - 1);
        let exact = |a: i32, b: i32| ((i64::from(a) * i64::from(b) + (1 << 29)) >> 30) as i32;
        for a in [a_max, -a_max, 0, 1, -1, 1 << 15, -(1 << 15), 0x7fff] {
            for b in [b_max, 0, 1, 0x7fff, 1 << 15, 1 << 29] {
                assert_eq!(mul_q30(a, b), exact(a, b), "{a} * {b}");
            }
        }
        for _ in 0..200_000 {
            let a = (next() as i32 >> 2) >> (next() % 16);
            let b = (next() >> 2) as i32 >> (next() % 16);
            assert_eq!(mul_q30(a, b), exact(a, b), "{a} * {b}");
        }
    }

    #[test]
    fn rotation_entry_products_round_to_nearest() {
        // Against the exact products (i64), over random factors within the bound and at its
        // extremes (this debug build would panic on an overflow): within half a step and 2^-12
        // of one.
        let mut seed = 0x0dd_ba11_u32;
        let mut next = || xorshift(&mut seed);
        let max = (1i32 << 30) + (1 << 28);
        let exact = |a: i32, b: i32| (i64::from(a) * i64::from(b)) as f64 / f64::from(1u32 << 30);
        let mut worst = 0.0f64;
        let mut check = |a: i32, b: i32| {
            worst = worst.max((f64::from(mul_rot(a, b)) - exact(a, b)).abs());
        };
        for a in [max, -max, 0, 1, -1, 1 << 30, -(1 << 30), 0x7fff, -0x8000] {
            for b in [max, -max, 0, 1, -1, 1 << 30, -(1 << 30), 0x7fff, -0x8000] {
                check(a, b);
            }
        }
        for _ in 0..400_000 {
            let spread = |n: u32| (i64::from(n) % (2 * i64::from(max) + 1) - i64::from(max)) as i32;
            let (a, b) = (spread(next()), spread(next()));
            check(a, b);
            check(a >> (next() % 30), b);
        }
        assert!(worst <= 0.5 + 1.0 / 4096.0, "{worst} steps");
        assert!(worst > 0.49, "rounding seen: {worst}");
    }

    #[test]
    fn narrow_products_round_to_nearest() {
        // Against the exact products (i64), over random lengths within the bounds and at their
        // extremes: within half a step and 2^-7 of one (the bound of the docs is 0.51).
        let mut seed = 0x1357_9bdf_u32;
        let mut next = || xorshift(&mut seed);
        let (a_max, b_max) = ((1i32 << 27) - 1, (1i32 << 28) - 1);
        let step = f64::from(1u32 << (2 * MM_FRAC - NARROW_SQ_FRAC));
        let (mut worst_square, mut worst_product) = (0.0f64, 0.0f64);
        for i in 0..400_000u32 {
            let (a, b) = if i < 16 {
                let sign = |bit: u32, v: i32| if i >> bit & 1 == 0 { v } else { -v };
                (sign(0, a_max >> (i >> 2 & 1)), sign(1, b_max >> (i >> 3)))
            } else {
                let shift = next() % 28;
                (
                    ((next() as i32) >> 4) >> (shift % 27),
                    ((next() as i32) >> 3) >> shift,
                )
            };
            // The square of one length: `leg_square_narrow` of a vector along an axis (`None`
            // only at 2^31 steps or more).
            let square = (i64::from(b) * i64::from(b)) as f64 / step;
            match leg_square_narrow([0, b, 0]) {
                Some(s) => worst_square = worst_square.max((f64::from(s) - square).abs()),
                None => assert!(square > 2f64.powi(31) - 0.51, "{b}"),
            }
            let product = (i64::from(a) * i64::from(b)) as f64 / step;
            worst_product =
                worst_product.max((f64::from(mul_mm_narrow(split13(a), b)) - product).abs());
        }
        assert!(worst_square <= 0.51, "square: {worst_square} steps");
        assert!(worst_product <= 0.51, "product: {worst_product} steps");
        assert!(worst_square > 0.4 && worst_product > 0.4, "rounding seen");
    }

    #[test]
    fn leg_squares_round_to_nearest_or_are_refused() {
        // Against the exact sum of squares (i64), over random vectors within the bound, short
        // and long: within 0.51 of a step, or `None` exactly from 2^31 steps on (within the
        // rounding).
        let mut seed = 0x0a11_5eed_u32;
        let mut next = || xorshift(&mut seed);
        let step = f64::from(1u32 << (2 * MM_FRAC - NARROW_SQ_FRAC));
        let (mut worst, mut refused) = (0.0f64, 0);
        for i in 0..300_000u32 {
            let shift = if i % 2 == 0 { 3 } else { 3 + next() % 12 };
            let l = [0; 3].map(|_: i32| (next() as i32) >> shift);
            let exact = l
                .iter()
                .map(|&v| (i64::from(v) * i64::from(v)) as f64)
                .sum::<f64>()
                / step;
            match leg_square_narrow(l) {
                Some(s) => {
                    assert!(f64::from(s) < 2f64.powi(31), "{l:?}");
                    worst = worst.max((f64::from(s) - exact).abs());
                }
                None => {
                    refused += 1;
                    assert!(exact > 2f64.powi(31) - 0.51, "{l:?}: {exact}");
                }
            }
        }
        assert!(worst <= 0.51, "{worst} steps");
        assert!(worst > 0.4, "rounding seen");
        assert!(refused > 1000, "{refused}");
    }

    #[test]
    fn wide_conversion_rounds_ties_to_even() {
        // 2^40 + 2^16 (a tie, even stays), + 1 (above the tie), 2^40 + 3 * 2^16 (a tie, odd
        // rounds up), and the extremes.
        for w in [
            (1i64 << 40) + (1 << 16),
            (1i64 << 40) + (1 << 16) + 1,
            (1i64 << 40) + 3 * (1 << 16),
            -((1i64 << 40) + 3 * (1 << 16)),
            i64::MAX,
            -i64::MAX,
            1,
            -1,
            0,
            (1 << 32) - 1,
            1 << 32,
        ] {
            assert_converts_as_rust_rounds(w);
        }
    }
}
