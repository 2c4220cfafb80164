//! How numbers, poses and setting values are written: poses in mm and degrees with 3 decimals,
//! arm angles in degrees with 3 decimals, pulse widths in microseconds with 2 decimals, and
//! never a `-0.000`.

use core::fmt::{self, Display, Formatter, Write};

use kinematics_core::pose::Axis;
use kinematics_core::{Direction, Pose, Vec3, LEGS};

use crate::settings::{Kind, SettingId, SettingValue};

/// A number with a fixed count of decimals (at most 6), never shown as `-0.000`. The same
/// digits as `format!("{:.decimals$}")` (the exact value rounded half to even), computed in
/// integers: core's float formatting costs thousands of cycles per number on a chip without
/// an FPU, and a `status` or `config` reply writes dozens of them.
#[derive(Debug, Clone, Copy)]
pub struct Fixed(pub f32, pub usize);

/// Powers of ten up to the most decimals [`Fixed`] writes in integers.
const POW10: [u64; 7] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000];

impl Display for Fixed {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let Fixed(value, decimals) = *self;
        match rounded_scaled(value, decimals) {
            Some((negative, scaled)) => {
                let scale = POW10[decimals];
                // A value that rounds to zero prints as an unsigned zero.
                if negative && scaled != 0 {
                    f.write_char('-')?;
                }
                write!(f, "{}", scaled / scale)?;
                if decimals > 0 {
                    write!(f, ".{:0width$}", scaled % scale, width = decimals)?;
                }
                Ok(())
            }
            None => {
                // Large, not finite, or many decimals: core's formatting (and the same zero
                // rule).
                const HALF_STEP: [f32; 7] = [0.5, 0.05, 5e-3, 5e-4, 5e-5, 5e-6, 5e-7];
                let half_step = HALF_STEP.get(decimals).copied().unwrap_or(0.0);
                let value = if value.abs() < half_step { 0.0 } else { value };
                write!(f, "{value:.decimals$}")
            }
        }
    }
}

/// `|value| * 10^decimals` rounded half to even to an integer, and the sign; `None` where
/// the integer computation does not apply (not finite, `|value| >= 2^40`, or more than 6
/// decimals).
fn rounded_scaled(value: f32, decimals: usize) -> Option<(bool, u64)> {
    let scale = *POW10.get(decimals)?;
    let bits = value.to_bits();
    let negative = bits >> 31 != 0;
    let exponent = ((bits >> 23) & 0xff) as i32;
    if exponent == 0xff {
        return None;
    }
    // |value| = mantissa * 2^shift, exactly.
    let (mantissa, shift) = if exponent == 0 {
        (u64::from(bits & 0x7f_ffff), -149)
    } else {
        (u64::from((bits & 0x7f_ffff) | 0x80_0000), exponent - 150)
    };
    // mantissa < 2^24 and scale <= 10^6 < 2^20: the product fits in 44 bits.
    let n = mantissa * scale;
    if shift >= 0 {
        // |value| < 2^40 keeps n << shift within 64 bits.
        return (shift <= 16).then(|| (negative, n << shift));
    }
    let right = shift.unsigned_abs();
    if right >= 64 {
        // Below 2^-20 of a step: rounds to zero (n < 2^44 is less than half of 2^right).
        return Some((negative, 0));
    }
    let quotient = n >> right;
    let rest = n & ((1u64 << right) - 1);
    let half = 1u64 << (right - 1);
    let up = rest > half || (rest == half && quotient & 1 == 1);
    Some((negative, quotient + u64::from(up)))
}

/// A number the user typed, shown as given: the fewest decimals (at least the given count, at most 6) whose
/// text reads back as the same `f32`. `1900.004` shows as `1900.004`, where [`Fixed`] with 2
/// decimals would round it onto the limit it exceeds (`1900.00`).
#[derive(Debug, Clone, Copy)]
pub struct AsGiven(pub f32, pub usize);

impl Display for AsGiven {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let AsGiven(value, least) = *self;
        let most = least.max(6);
        for decimals in least..most {
            let mut text = Buffer::new();
            if write!(text, "{}", Fixed(value, decimals)).is_ok()
                && text.as_str().parse::<f32>() == Ok(value)
            {
                return f.write_str(text.as_str());
            }
        }
        Fixed(value, most).fmt(f)
    }
}

/// A short text on the stack, for [`AsGiven`]'s read-back (a number with at most 6 decimals
/// below 2^40 is under 24 characters; a longer text is an error, not cut).
struct Buffer {
    bytes: [u8; 32],
    len: usize,
}

impl Buffer {
    fn new() -> Self {
        Buffer {
            bytes: [0; 32],
            len: 0,
        }
    }

    fn as_str(&self) -> &str {
        core::str::from_utf8(self.bytes.get(..self.len).unwrap_or_default()).unwrap_or_default()
    }
}

impl Write for Buffer {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let end = self.len + s.len();
        let room = self.bytes.get_mut(self.len..end).ok_or(fmt::Error)?;
        room.copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

/// Six values in servo order with a fixed number of decimals, separated by spaces.
pub struct Six<'a>(pub &'a [f32; LEGS], pub usize);

impl Display for Six<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        for (i, v) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_char(' ')?;
            }
            Fixed(*v, self.1).fmt(f)?;
        }
        Ok(())
    }
}

/// A pose in user units: `x=.. y=.. z=.. roll=.. pitch=.. yaw=..` (mm, degrees, 3 decimals).
pub struct PoseText<'a>(pub &'a Pose);

impl Display for PoseText<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        for (i, axis) in Axis::ALL.into_iter().enumerate() {
            let v = self.0.get(axis);
            let v = if axis.is_angle() { v.to_degrees() } else { v };
            if i > 0 {
                f.write_char(' ')?;
            }
            write!(f, "{}={}", axis.name(), Fixed(v, 3))?;
        }
        Ok(())
    }
}

/// A vector as `(x, y, z)` with 3 decimals.
pub struct Vector<'a>(pub &'a Vec3);

impl Display for Vector<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "({}, {}, {})",
            Fixed(self.0.x, 3),
            Fixed(self.0.y, 3),
            Fixed(self.0.z, 3)
        )
    }
}

/// Six angles, rad -> degrees.
pub fn degrees(angles_rad: &[f32; LEGS]) -> [f32; LEGS] {
    angles_rad.map(f32::to_degrees)
}

/// A setting's value as `config` shows it and `set` accepts it.
pub struct ValueText(pub SettingId, pub SettingValue);

impl Display for ValueText {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match (self.0.kind(), self.1) {
            (_, SettingValue::Flag(on)) => f.write_str(if on { "on" } else { "off" }),
            (_, SettingValue::Dir(Direction::Normal)) => f.write_str("normal"),
            (_, SettingValue::Dir(Direction::Reversed)) => f.write_str("reversed"),
            (_, SettingValue::Whole(v)) => write!(f, "{v}"),
            (
                Kind::Number {
                    off_allowed: true, ..
                },
                SettingValue::Number(0.0),
            ) => f.write_str("off"),
            (Kind::Number { decimals, .. }, SettingValue::Number(v)) => {
                Fixed(v, usize::from(decimals)).fmt(f)
            }
            (_, SettingValue::Number(v)) => write!(f, "{v}"),
            (Kind::Choice(words), SettingValue::Choice(i)) => {
                f.write_str(words.get(usize::from(i)).copied().unwrap_or("?"))
            }
            (_, SettingValue::Choice(i)) => write!(f, "{i}"),
            (_, SettingValue::Pin(Some(gpio))) => write!(f, "{gpio}"),
            (_, SettingValue::Pin(None)) => f.write_str("off"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_writes_the_digits_core_writes() {
        // core's float formatting is the reference: the exact value, rounded half to even.
        let mut next = crate::test_support::xorshift(0x2545_f491);
        let check = |v: f32| {
            for decimals in 0..=6 {
                let core = std::format!("{v:.decimals$}");
                let core = if core
                    .trim_start_matches('-')
                    .bytes()
                    .all(|b| b == b'0' || b == b'.')
                {
                    core.trim_start_matches('-').to_owned()
                } else {
                    core
                };
                assert_eq!(
                    std::format!("{}", Fixed(v, decimals)),
                    core,
                    "{v:e} .{decimals}"
                );
            }
        };
        for v in [
            0.0,
            -0.0,
            0.5,
            1.5,
            2.5,
            -2.5,
            0.125,
            0.375,
            1e-45,
            -1e-45,
            1500.0,
            1499.999,
            0.0005,
            -0.0005,
            0.00049999,
            509.2958,
            118.458,
            3e38,
            -3e38,
            1.0e12,
            1099511627775.0,
        ] {
            check(v);
        }
        for _ in 0..200_000 {
            let v = f32::from_bits(next());
            if v.is_finite() {
                check(v);
                // Values where the digits matter: typical magnitudes.
                check(v % 5000.0);
                check((v % 1.0) * 0.01);
            }
        }
        assert_eq!(std::format!("{}", Fixed(f32::NAN, 2)), "NaN");
        assert_eq!(std::format!("{}", Fixed(1.23456, 9)), "1.234560013");
    }

    #[test]
    fn fixed_never_prints_negative_zero() {
        assert_eq!(std::format!("{}", Fixed(-0.0001, 3)), "0.000");
        assert_eq!(std::format!("{}", Fixed(-0.0, 2)), "0.00");
        assert_eq!(std::format!("{}", Fixed(-0.0006, 3)), "-0.001");
        assert_eq!(std::format!("{}", Fixed(1500.0, 2)), "1500.00");
    }

    #[test]
    fn as_given_keeps_the_digits_typed() {
        // Each text, read as an f32 (core's correctly rounded parser, as `number` uses), shows
        // as itself: never rounded onto a neighbouring limit.
        for (typed, shown) in [
            ("1900.004", "1900.004"),
            ("1900.0004", "1900.0004"),
            ("1900.0001", "1900.0001"),
            ("2000", "2000.00"),
            ("1099.9", "1099.90"),
            ("-12.5", "-12.50"),
            ("0.000001", "0.000001"),
        ] {
            let value: f32 = typed.parse().unwrap();
            assert_eq!(std::format!("{}", AsGiven(value, 2)), shown, "{typed}");
        }
        // Past 6 decimals the nearest 6-decimal text (what Fixed writes).
        assert_eq!(std::format!("{}", AsGiven(1e-7, 2)), "0.000000");
        assert_eq!(std::format!("{}", AsGiven(f32::NAN, 2)), "NaN");
    }

    #[test]
    fn pose_text_is_in_user_units() {
        let p = Pose::from_degrees(1.0, -2.5, 3.0, 10.0, 0.0, -45.0);
        assert_eq!(
            std::format!("{}", PoseText(&p)),
            "x=1.000 y=-2.500 z=3.000 roll=10.000 pitch=0.000 yaw=-45.000"
        );
    }
}
