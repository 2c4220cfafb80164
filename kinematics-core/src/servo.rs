//! Servo pulse mapping: arm angle (rad) -> pulse width (us), eq. 13 and 14 of "The Mathematics
//! of the Stewart Platform".
//!
//! `W_i = W0_i + d_i (alpha_i - alpha0_i) r_i`, where `W0_i` is the pulse that holds servo `i`
//! at home (its trim), `r_i` the servo rate in us per radian and `d_i` its direction: `+1` for
//! even servos (eq. 13) and `-1` for odd servos (eq. 14) by default, because the servos of a
//! pair are mounted in mirror image. Every servo also has pulse limits it is never driven past.

use core::f32::consts::PI;
use core::fmt;

use crate::fixed::{from_fixed, from_fixed32, mul_q30, to_fixed, wide_mul, ARM_FRAC};
use crate::math::{abs_bits, Libm, Math, Real};
use crate::types::LEGS;

/// Default home pulse `W0`, us ("nominally 1500 us" in "The Mathematics of the Stewart
/// Platform").
pub const DEFAULT_HOME_US: f32 = 1500.0;
/// Default servo rate `r`, us per radian: 400 us per 45 degrees, `1600 / pi` (as in "The
/// Mathematics of the Stewart Platform").
pub const DEFAULT_RATE_US_PER_RAD: f32 = 1600.0 / PI;
/// Default travel either side of home, rad ("The Mathematics of the Stewart Platform" restricts
/// the servos to +-45 degrees).
pub const DEFAULT_TRAVEL_RAD: f32 = PI / 4.0;
/// No servo limit may go below this, us: shorter pulses are outside any RC servo's range.
pub const MIN_PULSE_US: f32 = 400.0;
/// No servo limit may go above this, us: longer pulses are outside any RC servo's range
/// (and must fit in the frame at the highest frame rate, 333 Hz = 3003 us).
pub const MAX_PULSE_US: f32 = 2600.0;
/// Smallest magnitude allowed for a servo rate, us/rad.
pub const MIN_RATE_US_PER_RAD: f32 = 100.0;
/// Largest magnitude allowed for a servo rate, us/rad.
pub const MAX_RATE_US_PER_RAD: f32 = 5000.0;

/// Whether a servo's pulse grows or shrinks as its arm rises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// Pulse grows as the arm angle grows (eq. 13, default for even servos).
    Normal,
    /// Pulse shrinks as the arm angle grows (eq. 14, default for odd servos).
    Reversed,
}

impl Direction {
    /// `+1.0` or `-1.0`.
    pub const fn sign(self) -> f32 {
        match self {
            Direction::Normal => 1.0,
            Direction::Reversed => -1.0,
        }
    }

    /// The default for servo number `servo` (1..=6), as in eq. 13, 14: even servos add, odd
    /// subtract.
    pub const fn default_for(servo: u8) -> Direction {
        if servo % 2 == 0 {
            Direction::Normal
        } else {
            Direction::Reversed
        }
    }
}

/// One servo's pulse mapping and limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoConfig {
    /// Pulse at the home pose `W0`, us (the trim).
    pub home_us: f32,
    /// Servo rate `r`, us per radian of arm.
    pub rate_us_per_rad: f32,
    /// Sense of rotation.
    pub direction: Direction,
    /// Shortest pulse this servo may get, us.
    pub min_us: f32,
    /// Longest pulse this servo may get, us.
    pub max_us: f32,
}

impl ServoConfig {
    /// The default for servo number `servo` (1..=6), as in "The Mathematics of the Stewart
    /// Platform": 1500 us home, `1600/pi` us/rad, odd/even direction and +-45 degrees of arm
    /// travel (1100..1900 us).
    pub fn default_for(servo: u8) -> ServoConfig {
        let travel_us = DEFAULT_TRAVEL_RAD * DEFAULT_RATE_US_PER_RAD;
        ServoConfig {
            home_us: DEFAULT_HOME_US,
            rate_us_per_rad: DEFAULT_RATE_US_PER_RAD,
            direction: Direction::default_for(servo),
            min_us: DEFAULT_HOME_US - travel_us,
            max_us: DEFAULT_HOME_US + travel_us,
        }
    }

    /// Pulse width for an arm angle, us (eq. 13 / 14). Not limited; see [`ServoConfig::allows`].
    #[inline]
    pub fn pulse_us(&self, alpha_rad: f32, alpha0_rad: f32) -> f32 {
        self.pulse_us_with::<Libm>(alpha_rad, alpha0_rad)
    }

    /// [`ServoConfig::pulse_us`] with `M`'s arithmetic (the IK's hot path); the same
    /// operations, so the same result. The direction's sign is applied exactly (negation).
    /// The angles must be finite (see [`Math::add`]).
    #[inline]
    pub fn pulse_us_with<M: Math>(&self, alpha_rad: f32, alpha0_rad: f32) -> f32 {
        self.pulse_us_for_offset::<M>((Real::<M>::new(alpha_rad) - Real::new(alpha0_rad)).0)
    }

    /// Pulse width for an arm angle `alpha0 + offset_rad` (eq. 13 / 14) given the offset from
    /// home, us, with `M`'s arithmetic. The offset must be finite (see [`Math::add`]).
    #[inline]
    pub fn pulse_us_for_offset<M: Math>(&self, offset_rad: f32) -> f32 {
        let offset_rad = Real::<M>::new(offset_rad);
        let signed_rad = match self.direction {
            Direction::Normal => offset_rad,
            Direction::Reversed => -offset_rad,
        };
        (Real::new(self.home_us) + signed_rad * Real::new(self.rate_us_per_rad)).0
    }

    /// [`ServoConfig::pulse_us_for_offset`] for an offset from the IK's fixed-point path, in
    /// steps of 2^-28 rad (`|offset| <= pi`), in fixed point: `d r (alpha - alpha0)` exactly
    /// (`r` in steps of 2^-18 us/rad: every valid rate is exact there) and `W0` (steps of 2^-16
    /// us: every valid one is exact), their sum rounded to 2^-16 us and then to the nearest
    /// `f32`: within 0.6 of an `f32` step (at 1500 us, 1.2e-4 us) of the exact pulse of that
    /// offset, with no float operation (library calls on the chip). A servo whose `W0` or `r`
    /// is beyond 4096 us or 8192 us/rad (no valid one is) or not finite takes `M`'s float
    /// arithmetic instead.
    #[inline]
    pub(crate) fn pulse_us_for_fixed_offset<M: Math>(&self, offset: i32) -> f32 {
        const RATE_FRAC: u32 = 18;
        const PULSE_FRAC: u32 = 16;
        let (home_us, rate) = (self.home_us, self.rate_us_per_rad);
        if abs_bits(home_us) < 4096.0f32.to_bits() && abs_bits(rate) < 8192.0f32.to_bits() {
            // |offset r| < pi 2^28 2^31 in steps of 2^-46 us, below 2^30.7 steps of 2^-16 us;
            // |W0| < 2^28 of them: the sum fits an i32.
            // Rounded to 2^-16 us: in 32-bit products for a rate below 4096 us/rad (every
            // usual one), else in 64 bits; the same value either way.
            const SHIFT: u32 = ARM_FRAC + RATE_FRAC - PULSE_FRAC;
            let rate_q = to_fixed(rate, RATE_FRAC);
            let product = if (rate_q as u32) < 1 << 30 && offset.unsigned_abs() < 1 << 30 {
                mul_q30(offset, rate_q)
            } else {
                ((wide_mul(offset, rate_q) + (1 << (SHIFT - 1))) >> SHIFT) as i32
            };
            let signed = match self.direction {
                Direction::Normal => product,
                Direction::Reversed => -product,
            };
            from_fixed32(to_fixed(home_us, PULSE_FRAC) + signed, PULSE_FRAC)
        } else {
            self.pulse_us_for_offset::<M>(from_fixed(i64::from(offset), ARM_FRAC))
        }
    }

    /// Arm angle for a pulse width, rad (the inverse of [`ServoConfig::pulse_us`]).
    pub fn alpha_rad(&self, pulse_us: f32, alpha0_rad: f32) -> f32 {
        alpha0_rad + (pulse_us - self.home_us) / (self.direction.sign() * self.rate_us_per_rad)
    }

    /// True if `pulse_us` is finite and within `[min_us, max_us]`.
    #[inline]
    pub fn allows(&self, pulse_us: f32) -> bool {
        // Integer comparisons, exactly IEEE's (float ones are library calls on the chip).
        crate::math::within(pulse_us, self.min_us, self.max_us)
    }

    /// Checks this servo's numbers; `servo` (1..=6) names it in the error.
    pub fn validate(&self, servo: u8) -> Result<(), ServoError> {
        let in_range = |v: f32| (MIN_PULSE_US..=MAX_PULSE_US).contains(&v);
        for (field, value) in [
            (ServoField::Home, self.home_us),
            (ServoField::Min, self.min_us),
            (ServoField::Max, self.max_us),
        ] {
            if !in_range(value) {
                return Err(ServoError::PulseOutOfRange {
                    servo,
                    field,
                    value_us: value,
                });
            }
        }
        if !(MIN_RATE_US_PER_RAD..=MAX_RATE_US_PER_RAD).contains(&self.rate_us_per_rad) {
            return Err(ServoError::RateOutOfRange {
                servo,
                value: self.rate_us_per_rad,
            });
        }
        if !(self.min_us <= self.home_us && self.home_us <= self.max_us) {
            return Err(ServoError::HomeOutsideLimits {
                servo,
                home_us: self.home_us,
                min_us: self.min_us,
                max_us: self.max_us,
            });
        }
        Ok(())
    }
}

/// The six servos' mappings, servo `i + 1` at index `i`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoSet(pub [ServoConfig; LEGS]);

impl Default for ServoSet {
    fn default() -> ServoSet {
        ServoSet(core::array::from_fn(|i| {
            ServoConfig::default_for(i as u8 + 1)
        }))
    }
}

impl ServoSet {
    /// Checks every servo; the first bad one is named.
    pub fn validate(&self) -> Result<(), ServoError> {
        self.0
            .iter()
            .enumerate()
            .try_for_each(|(i, s)| s.validate(i as u8 + 1))
    }

    /// Servo number `servo` (1..=6), if it exists.
    pub fn servo(&self, servo: u8) -> Option<&ServoConfig> {
        self.0.get(usize::from(servo).wrapping_sub(1))
    }
}

/// Which pulse setting of a servo a [`ServoError`] is about.
///
/// `Display` gives its name for developers; the wording users see is `control::report`'s.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ServoField {
    /// Home pulse `W0`.
    Home,
    /// Lower pulse limit.
    Min,
    /// Upper pulse limit.
    Max,
}

impl fmt::Display for ServoField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ServoField::Home => "home pulse",
            ServoField::Min => "minimum pulse",
            ServoField::Max => "maximum pulse",
        })
    }
}

/// Why a servo configuration is refused.
///
/// `Display` gives one short line for developers (the case and its values, in the units of the
/// fields); the wording users see is `control::report`'s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ServoError {
    /// A pulse setting is not a number within [`MIN_PULSE_US`]..=[`MAX_PULSE_US`].
    PulseOutOfRange {
        /// Servo number, 1..=6.
        servo: u8,
        /// Which setting.
        field: ServoField,
        /// The value given, us.
        value_us: f32,
    },
    /// The rate is not within [`MIN_RATE_US_PER_RAD`]..=[`MAX_RATE_US_PER_RAD`].
    RateOutOfRange {
        /// Servo number, 1..=6.
        servo: u8,
        /// The value given, us/rad.
        value: f32,
    },
    /// The home pulse is not between the limits (or the limits are reversed).
    HomeOutsideLimits {
        /// Servo number, 1..=6.
        servo: u8,
        /// Home pulse, us.
        home_us: f32,
        /// Lower limit, us.
        min_us: f32,
        /// Upper limit, us.
        max_us: f32,
    },
}

impl fmt::Display for ServoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ServoError::PulseOutOfRange {
                servo,
                field,
                value_us,
            } => write!(
                f,
                "servo {servo}: {field} {value_us} us outside {MIN_PULSE_US}..={MAX_PULSE_US} us"
            ),
            ServoError::RateOutOfRange { servo, value } => write!(
                f,
                "servo {servo}: rate {value} us/rad outside \
                 {MIN_RATE_US_PER_RAD}..={MAX_RATE_US_PER_RAD} us/rad"
            ),
            ServoError::HomeOutsideLimits {
                servo,
                home_us,
                min_us,
                max_us,
            } => write!(
                f,
                "servo {servo}: home pulse {home_us} us outside its limits {min_us}..={max_us} us"
            ),
        }
    }
}

impl core::error::Error for ServoError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn allows_is_ieee_within_the_limits() {
        let values = [
            f32::NEG_INFINITY,
            -1500.0,
            -0.0,
            0.0,
            1e-45,
            1100.0,
            1500.0,
            1900.0,
            f32::INFINITY,
            f32::NAN,
        ];
        for min_us in values {
            for max_us in values {
                let servo = ServoConfig {
                    min_us,
                    max_us,
                    ..ServoConfig::default_for(1)
                };
                for pulse in values {
                    let ieee = min_us <= pulse && pulse <= max_us;
                    assert_eq!(servo.allows(pulse), ieee, "{min_us} <= {pulse} <= {max_us}");
                }
            }
        }
    }

    #[test]
    fn defaults_follow_the_source_document() {
        let set = ServoSet::default();
        set.validate().unwrap();
        for (i, s) in set.0.iter().enumerate() {
            let number = i as u8 + 1;
            let expected = if number % 2 == 0 { 1.0 } else { -1.0 };
            assert_eq!(s.direction.sign(), expected, "servo {number}");
            // +-45 degrees at 400 us per 45 degrees.
            assert!((s.min_us - 1100.0).abs() < 1e-3 && (s.max_us - 1900.0).abs() < 1e-3);
        }
    }

    #[test]
    fn pulse_and_angle_are_inverse() {
        let s = ServoConfig::default_for(3);
        let w = s.pulse_us(0.3, 0.1);
        // Odd servo: arm up by 0.2 rad shortens the pulse by 0.2 * 1600/pi us.
        assert!((w - (1500.0 - 0.2 * 1600.0 / PI)).abs() < 1e-3);
        assert!((s.alpha_rad(w, 0.1) - 0.3).abs() < 1e-6);
    }

    #[test]
    fn validation_names_servo_and_field() {
        let mut set = ServoSet::default();
        set.0[4].max_us = 3000.0;
        assert!(matches!(
            set.validate(),
            Err(ServoError::PulseOutOfRange {
                servo: 5,
                field: ServoField::Max,
                ..
            })
        ));
        let mut set = ServoSet::default();
        set.0[1].home_us = 1950.0;
        assert!(matches!(
            set.validate(),
            Err(ServoError::HomeOutsideLimits { servo: 2, .. })
        ));
        let mut set = ServoSet::default();
        set.0[0].rate_us_per_rad = f32::NAN;
        assert!(matches!(
            set.validate(),
            Err(ServoError::RateOutOfRange { servo: 1, .. })
        ));
    }
}
