//! The stream tracker: follows the newest streamed target pose one servo frame at a time, each
//! of the six axes limited in speed and acceleration, without overshoot, so 60-100 Hz input
//! from motion-simulator software becomes smooth motion at the frame rate (up to 333 Hz).
//!
//! Per axis, with position `p`, velocity `v`, target `x`, limits `v_max`, `a_max` and frame
//! time `dt`: the fastest velocity from which the axis can still stop at the target is
//! `sqrt(2 a_max |x - p|)` in continuous time, and its exact discrete form here (see
//! `braking_speed`), so the speed changes by at most `a_max dt` every frame, the last one of a
//! stop included; the velocity aimed at is that, capped at `v_max` and at what reaches the
//! target within this frame (`|x - p| / dt`), and the velocity changes towards it by at most
//! `a_max dt` per frame. This is time-optimal, "bang-bang" tracking: critically damped in the
//! sense that matters here, it never overshoots. A target that moves on is chased the same
//! way, every frame; one that jumps back closer than the axis can stop in is met with a
//! harder stop on it (the one case where the acceleration limit gives way) rather than
//! passed.
//!
//! Units: mm, mm/s, mm/s^2 for x, y, z; radians, rad/s, rad/s^2 for roll, pitch, yaw (the
//! [`Pose`]'s units). A limit of 0 (or below, or not finite) is off: without a speed limit the speed is only
//! bounded by the acceleration; with both off the axis follows its target at once
//! (pass-through).
//!
//! The step computes in integers (the RP2040 has no FPU: in `f32` every operation is a library
//! call, and six axes cost ~28,000 cycles). Each axis counts in whole *units*: 2^-20 mm
//! (about 1e-6 mm) for x, y, z and 2^-28 rad (about 4e-9 rad) for roll, pitch, yaw, in an
//! `i32`, within +-2^30 units (+-1024 mm, +-4 rad; an axis whose position or target lies
//! beyond is held where it is: no platform reaches that far). Velocities are units per frame;
//! each frame the limits become whole units per frame, `v_max dt`, and per frame per frame,
//! `h = a_max dt^2` (the products in `f32`, then rounded down to a whole unit; kept while the
//! limits and the frame time stay the same), so the rule
//! above holds exactly in these units: the braking speed is the exact floor of its formula (an
//! integer square root and two integer divisions), and every velocity change, the landing
//! included, is at most `h`. A target lands exactly: the axis' pose is then the target's own
//! `f32`. (Velocities are per frame: if the frame time changes, they are rescaled to it.)

use kinematics_core::{Math, Pose};

/// Speed and acceleration limits, per group of axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackLimits {
    /// Speed of x, y and z each, mm/s (0 = off).
    pub mm_per_s: f32,
    /// Acceleration of x, y and z each, mm/s^2 (0 = off).
    pub mm_per_s2: f32,
    /// Speed of roll, pitch and yaw each, rad/s (0 = off).
    pub rad_per_s: f32,
    /// Acceleration of roll, pitch and yaw each, rad/s^2 (0 = off).
    pub rad_per_s2: f32,
}

impl TrackLimits {
    /// Every limit off: pass-through.
    pub const OFF: TrackLimits = TrackLimits {
        mm_per_s: 0.0,
        mm_per_s2: 0.0,
        rad_per_s: 0.0,
        rad_per_s2: 0.0,
    };
}

/// Fraction bits of x, y and z: units of 2^-20 mm.
const MM_FRAC: u32 = 20;
/// Fraction bits of roll, pitch and yaw: units of 2^-28 rad.
const RAD_FRAC: u32 = 28;
/// Bound (exclusive) on a position, in units: 2^30. A distance is then below 2^31, and so is
/// every velocity (never faster than a distance or the velocity before it).
const MAX_UNITS: u32 = 1 << 30;
/// The position of an axis that is beyond [`MAX_UNITS`] (held where it is).
const OUTSIDE: i32 = i32::MIN;
/// Limits, and the frame time, beyond these (2^30 per second or per second squared, 8 s) are
/// taken as these: the products stay finite, and a limit this large is already more than a
/// whole range per frame.
const MAX_LIMIT: f32 = 1_073_741_824.0;
const MAX_FRAME_S: f32 = 8.0;

/// Fraction bits of axis `index` (0..=5, [`Pose::to_array`] order).
fn frac_of(index: usize) -> u32 {
    if index < 3 {
        MM_FRAC
    } else {
        RAD_FRAC
    }
}

/// Where the tracker is and how fast it goes.
#[derive(Debug, Clone, Copy)]
pub struct Tracker {
    /// The pose of the last step, as the IK gets it: an axis on its target holds the target's
    /// own `f32`.
    pose: [f32; 6],
    /// Each axis' position in its units ([`OUTSIDE`] if beyond their range).
    position: [i32; 6],
    /// Each axis' velocity, units per frame of `frame_s`.
    velocity: [i32; 6],
    /// The frame time the velocities are per, s (0 before the first step).
    frame_s: f32,
    /// The bits of the limits and the frame time [`Tracker::per_frame`] was computed from
    /// ([`TrackLimits`]' fields in order, then the frame time; none before the first step).
    limits_from: [u32; 5],
    /// The limits per frame of x, y, z and of roll, pitch, yaw: computed when the limits or
    /// the frame time change (the products are library calls on the RP2040), else kept.
    per_frame: [FrameLimits; 2],
}

impl PartialEq for Tracker {
    /// The same state: poses of the same bits (no float comparisons: library calls on the
    /// RP2040), positions, velocities and their frame time.
    fn eq(&self, other: &Tracker) -> bool {
        // (Word by word, all of them: an array comparison is a `memcmp` call.)
        let differ = (0..6).fold(self.frame_s.to_bits() ^ other.frame_s.to_bits(), |d, i| {
            d | (self.pose[i].to_bits() ^ other.pose[i].to_bits())
                | (self.position[i] ^ other.position[i]) as u32
                | (self.velocity[i] ^ other.velocity[i]) as u32
        });
        differ == 0
    }
}

impl Tracker {
    /// At rest at `pose`.
    pub fn new(pose: &Pose) -> Tracker {
        let pose = pose.to_array();
        Tracker {
            pose,
            position: core::array::from_fn(|i| to_units(pose[i], frac_of(i)).unwrap_or(OUTSIDE)),
            velocity: [0; 6],
            frame_s: 0.0,
            // (Not the bits of a frame time: a NaN.)
            limits_from: [u32::MAX; 5],
            per_frame: [FrameLimits::OFF; 2],
        }
    }

    /// Moving from `pose` at `rate` (mm and rad per frame of `dt_s` s, each axis rounded to
    /// its units): a stream that takes over from a planned move goes on at its velocity.
    pub fn moving(pose: &Pose, rate: &[f32; 6], dt_s: f32) -> Tracker {
        let mut tracker = Tracker::new(pose);
        if positive_finite(dt_s) {
            tracker.frame_s = dt_s;
            for (i, r) in rate.iter().enumerate() {
                // (An axis beyond its range is held where it is.)
                if tracker.position[i] != OUTSIDE {
                    tracker.velocity[i] = to_units(*r, frac_of(i)).unwrap_or(0);
                }
            }
        }
        tracker
    }

    /// The velocity, mm and rad per frame of `dt_s` s (0 at rest, or before the first step).
    pub fn rate_per_frame(&self, dt_s: f32) -> [f32; 6] {
        if self.at_rest() || !positive_finite(self.frame_s) {
            return [0.0; 6];
        }
        let ratio = dt_s / self.frame_s;
        core::array::from_fn(|i| to_f32(self.velocity[i], frac_of(i)) * ratio)
    }

    /// The pose of the last step.
    pub fn pose(&self) -> Pose {
        Pose::from_array(self.pose)
    }

    /// True if every axis is at rest.
    pub fn at_rest(&self) -> bool {
        self.velocity.iter().fold(0, |d, &v| d | v) == 0
    }

    /// The tracker one frame (`dt_s`, > 0) later, chasing `target` within `limits`. `self` is
    /// unchanged: the caller keeps the new one once it has checked its pose can be driven. (A
    /// `dt_s` that is not a positive number is no time at all: nothing moves.) `M`'s `f32`
    /// multiplication turns the limits into units (six products, when the limits or the frame
    /// time change).
    pub fn step<M: Math>(&self, target: &Pose, limits: &TrackLimits, dt_s: f32) -> Tracker {
        if !positive_finite(dt_s) {
            return *self;
        }
        let dt = capped(dt_s, MAX_FRAME_S);
        let target = target.to_array();
        let mut next = *self;
        if dt.to_bits() != self.frame_s.to_bits() {
            next.velocity = self.velocity_per(dt);
            next.frame_s = dt;
        }
        let from = [
            limits.mm_per_s.to_bits(),
            limits.mm_per_s2.to_bits(),
            limits.rad_per_s.to_bits(),
            limits.rad_per_s2.to_bits(),
            dt.to_bits(),
        ];
        if (0..5).fold(0, |d, i| d | (from[i] ^ self.limits_from[i])) != 0 {
            next.limits_from = from;
            next.per_frame = [
                FrameLimits::new::<M>(limits.mm_per_s, limits.mm_per_s2, dt, MM_FRAC),
                FrameLimits::new::<M>(limits.rad_per_s, limits.rad_per_s2, dt, RAD_FRAC),
            ];
        }
        for (i, &goal) in target.iter().enumerate() {
            // At rest on its target, an axis stays there (most axes of a stream often are).
            if goal.to_bits() == self.pose[i].to_bits() && next.velocity[i] == 0 {
                continue;
            }
            let limits = next.per_frame[usize::from(i >= 3)];
            let axis = Axis {
                pose: self.pose[i],
                position: self.position[i],
                velocity: next.velocity[i],
            }
            .step(goal, limits, frac_of(i));
            next.pose[i] = axis.pose;
            next.position[i] = axis.position;
            next.velocity[i] = axis.velocity;
        }
        next
    }

    /// The state a fraction `k` (`0..1`) of the way from this one to `next`, this one's step:
    /// every axis that fraction of its step (rounded towards this one, to a unit), its
    /// velocity the step so taken. A step shortened to the servos' rated speeds
    /// ([`crate::servo_speed`]) keeps its direction, and the next step goes on from there,
    /// within the limits, from the speed actually reached.
    pub fn part_way(&self, next: &Tracker, k: f32) -> Tracker {
        let mut out = *next;
        for i in 0..6 {
            let (from, to) = (self.position[i], next.position[i]);
            if from == to {
                continue; // not moving (or landed on its target's own f32)
            }
            if from == OUTSIDE || to == OUTSIDE {
                // Beyond the range (held where it is).
                out.pose[i] = self.pose[i];
                out.position[i] = from;
                out.velocity[i] = 0;
                continue;
            }
            // Both within +-2^30: the step fits; `as` rounds towards zero.
            let step = ((to - from) as f32 * k) as i32;
            let position = from + step;
            out.pose[i] = to_f32(position, frac_of(i));
            out.position[i] = position;
            out.velocity[i] = step;
        }
        out
    }

    /// Stops at `pose` (where the platform is held, e.g. after a clamp or a stop).
    pub fn hold_at(&mut self, pose: &Pose) {
        *self = Tracker::new(pose);
    }

    /// The velocities in units per frame of `dt` (> 0) instead of `frame_s`, rounded towards
    /// zero: the same speeds when the frame time changes.
    #[cold]
    fn velocity_per(&self, dt: f32) -> [i32; 6] {
        if self.at_rest() || !positive_finite(self.frame_s) {
            return [0; 6];
        }
        let ratio = dt / self.frame_s;
        // (`as` saturates; the bound keeps |v| below 2^31.)
        self.velocity
            .map(|v| ((v as f32 * ratio) as i32).clamp(-i32::MAX, i32::MAX))
    }
}

/// One group's limits for one frame, in its units (`None`: off).
#[derive(Debug, Clone, Copy)]
struct FrameLimits {
    /// `v_max dt`, units per frame, rounded down.
    speed: Option<u32>,
    /// `h = a_max dt^2`, units per frame per frame, rounded down.
    accel: Option<u32>,
}

impl FrameLimits {
    const OFF: FrameLimits = FrameLimits {
        speed: None,
        accel: None,
    };

    /// From `speed` (per s) and `accel` (per s^2) for a frame of `dt` s (positive, at most
    /// [`MAX_FRAME_S`]), in units of 2^-`frac`.
    fn new<M: Math>(speed: f32, accel: f32, dt: f32, frac: u32) -> FrameLimits {
        FrameLimits {
            speed: positive_finite(speed)
                .then(|| units_below(M::mul(capped(speed, MAX_LIMIT), dt), frac)),
            accel: positive_finite(accel)
                .then(|| units_below(M::mul(M::mul(capped(accel, MAX_LIMIT), dt), dt), frac)),
        }
    }
}

/// One axis' state.
#[derive(Debug, Clone, Copy)]
struct Axis {
    /// As the IK gets it.
    pose: f32,
    /// Units ([`OUTSIDE`]: beyond the range).
    position: i32,
    /// Units per frame.
    velocity: i32,
}

impl Axis {
    /// One frame towards `target` within `limits`, in units of 2^-`frac`.
    fn step(self, target: f32, limits: FrameLimits, frac: u32) -> Axis {
        if limits.speed.is_none() && limits.accel.is_none() {
            // Pass-through: the target itself (its position only as far as the range goes).
            return Axis {
                pose: target,
                position: to_units(target, frac).unwrap_or(OUTSIDE),
                velocity: 0,
            };
        }
        self.limited(target, limits, frac).unwrap_or(Axis {
            velocity: 0,
            ..self
        })
    }

    /// A step with at least one limit on; `None` if the position or the target is beyond the
    /// range.
    fn limited(self, target: f32, limits: FrameLimits, frac: u32) -> Option<Axis> {
        let goal = to_units(target, frac)?;
        if self.position == OUTSIDE {
            return None;
        }
        // Both within +-2^30: the difference fits.
        let error = goal - self.position;
        let landed = |velocity| Axis {
            pose: target,
            position: goal,
            velocity,
        };
        if error == 0 {
            // On the target (to the unit): there, exactly.
            return Some(landed(0));
        }
        let distance = error.unsigned_abs();
        // The speed aimed at: what reaches the target this frame, what can still stop on it
        // ([`braking_speed`]), and the speed limit; all at most `distance`, below 2^31.
        let mut wanted = distance;
        if let Some(h) = limits.accel {
            wanted = wanted.min(braking_speed(distance, h));
        }
        if let Some(speed) = limits.speed {
            wanted = wanted.min(speed);
        }
        let wanted = if error < 0 {
            -(wanted as i32)
        } else {
            wanted as i32
        };
        let velocity = match limits.accel {
            // Towards the one wanted by at most h (h <= 2^31: saturated, as i32 at 2^31 - 1,
            // which no velocity needs to change by).
            Some(h) => {
                let h = h.min(i32::MAX as u32) as i32;
                if wanted > self.velocity {
                    wanted.min(self.velocity.saturating_add(h))
                } else {
                    wanted.max(self.velocity.saturating_sub(h))
                }
            }
            None => wanted,
        };
        // Never past the target: a step that would reach or cross it ends on it. Its velocity
        // is that of the step it took (not zero: the next steps slow from it within the limit,
        // staying on the target, so a target that then moves away is not chased from a
        // standstill that never happened).
        let reached = if error < 0 {
            velocity <= error
        } else {
            velocity >= error
        };
        if reached {
            return Some(landed(error));
        }
        // Short of the target, or (braking after the target jumped behind) moving away from
        // it: then kept within the range.
        let bound = i64::from(MAX_UNITS) - 1;
        let position = (i64::from(self.position) + i64::from(velocity)).clamp(-bound, bound) as i32;
        Some(Axis {
            pose: to_f32(position, frac),
            position,
            velocity: position - self.position,
        })
    }
}

/// The fastest whole speed (units per frame) from which the axis still stops exactly on a
/// target `distance` units away (> 0), slowing by at most `h` units per frame each frame: the
/// discrete form of `sqrt(2 a_max d)`.
///
/// Moving at `v` this frame and then at `v - h`, `v - 2h`, ... (while positive) covers
/// `(n + 1) v - h n (n + 1) / 2` with `n = floor(v / h)`. Setting that to the distance `d` and
/// solving: `n` is the largest whole number with `h n (n + 1) / 2 <= d`, and
/// `v = d / (n + 1) + h n / 2`, here rounded down (a whole speed at most that stops in time
/// too: the sum is increasing in `v`). The last frame of a stop then moves at most `h`, so the
/// speed changes by at most `h` every frame, landing included. With `h = 0` (an acceleration
/// limit below a unit per frame per frame) no speed can stop: 0.
fn braking_speed(distance: u32, h: u32) -> u32 {
    if h == 0 {
        return 0;
    }
    if distance <= h {
        return distance; // n = 0
    }
    // n (n + 1) / 2 <= d / h, a whole number on the left: <= q = floor(d / h), i.e.
    // n (n + 1) <= 2q (below 2^32: d < 2^31). With r = floor(sqrt(2q)), n is r if r (r + 1)
    // fits, else r - 1 (r >= 1 here; r (r + 1) < 2^32 for r < 2^16).
    let twice = 2 * (distance / h);
    let r = isqrt(twice);
    let n = if r * (r + 1) <= twice { r } else { r - 1 };
    // floor(d / (n + 1) + h n / 2), exactly, from d = whole (n + 1) + rest (h n <= d here).
    let (whole, rest) = (distance / (n + 1), distance % (n + 1));
    let hn = h * n;
    let half = u32::from(hn % 2 == 1 && 2 * rest > n);
    whole + hn / 2 + half
}

/// `floor(sqrt(x))`, digit by digit (two bits of `x` per result bit).
fn isqrt(x: u32) -> u32 {
    if x == 0 {
        return 0;
    }
    // The highest power of four at most x.
    let mut bit = 1u32 << ((31 - normalise(x).1) & !1);
    let (mut rest, mut root) = (x, 0u32);
    while bit != 0 {
        if rest >= root + bit {
            rest -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    root
}

/// `x` (not 0) shifted left until its leading one is bit 31, and the shift (its leading zeros):
/// a few compares in line, where `leading_zeros` is a library call on the M0+ (no such
/// instruction).
fn normalise(x: u32) -> (u32, u32) {
    let (mut x, mut zeros) = (x, 0);
    for width in [16, 8, 4, 2, 1] {
        if x >> (32 - width) == 0 {
            x <<= width;
            zeros += width;
        }
    }
    (x, zeros)
}

/// `x * 2^frac` rounded to the nearest whole unit (halves away from zero), by its bits; `None`
/// if `x` is not finite or that is [`MAX_UNITS`] or more in size.
fn to_units(x: f32, frac: u32) -> Option<i32> {
    if !finite(x) {
        return None;
    }
    let bits = x.to_bits();
    let exponent = (bits >> 23) & 0xff;
    if exponent == 0 {
        return Some(0); // zero or below 2^-126: far below a unit
    }
    let mantissa = (bits & 0x7f_ffff) | 0x80_0000;
    // |x| 2^frac = mantissa 2^shift.
    let shift = exponent as i32 - 150 + frac as i32;
    let units = if shift >= 0 {
        if shift > 6 {
            return None; // at least 2^23 2^7 = 2^30
        }
        mantissa << shift
    } else if shift > -25 {
        let down = (-shift) as u32;
        (mantissa + (1 << (down - 1))) >> down
    } else {
        0
    };
    if units >= MAX_UNITS {
        return None;
    }
    let units = units as i32;
    Some(if bits >> 31 == 1 { -units } else { units })
}

/// The `f32` nearest (ties to even) to `units * 2^-frac` (`|units| < 2^31`, `frac <= 28`), by
/// its bits.
fn to_f32(units: i32, frac: u32) -> f32 {
    if units == 0 {
        return 0.0;
    }
    let sign = units as u32 & 0x8000_0000;
    let (normal, zeros) = normalise(units.unsigned_abs()); // leading one in bit 31
    let mantissa = normal >> 8; // 24 bits, the leading one in bit 23
    let cut = normal & 0xff;
    let up = u32::from(cut > 0x80 || (cut == 0x80 && mantissa & 1 == 1));
    // The leading one's biased exponent is 127 + 31 - zeros - frac (at least 99: normal); the
    // mantissa's leading one adds the 1 the exponent field lacks, and a carry out of rounding
    // moves into the exponent, which is then right.
    let exponent = 127 + 31 - zeros - frac;
    f32::from_bits(sign | (((exponent - 1) << 23) + mantissa + up))
}

/// A positive finite `x * 2^frac` rounded down to a whole unit, at most 2^31 (which is more
/// than any distance: no limit at all), by its bits.
fn units_below(x: f32, frac: u32) -> u32 {
    let bits = x.to_bits();
    let exponent = (bits >> 23) & 0xff;
    if exponent == 0 || bits >> 31 == 1 {
        return 0; // zero or below 2^-126 (or, not reached, negative)
    }
    let mantissa = (bits & 0x7f_ffff) | 0x80_0000;
    let shift = exponent as i32 - 150 + frac as i32;
    let units = if shift >= 8 {
        1 << 31
    } else if shift >= 0 {
        mantissa << shift
    } else if shift > -24 {
        mantissa >> (-shift) as u32
    } else {
        0
    };
    units.min(1 << 31)
}

/// `x` (positive) or `max` if that is less, by the bits (which order positive floats as
/// their values).
fn capped(x: f32, max: f32) -> f32 {
    if x.to_bits() > max.to_bits() {
        max
    } else {
        x
    }
}

/// `x` is finite, by its bit pattern: the exponent is not all ones. (The tests below, on the
/// bits, cost a few integer instructions where a float comparison is a library call on the
/// RP2040.)
fn finite(x: f32) -> bool {
    x.to_bits() & 0x7f80_0000 != 0x7f80_0000
}

/// `x` is a positive (above zero) finite number, by its bit pattern.
fn positive_finite(x: f32) -> bool {
    (1..0x7f80_0000).contains(&x.to_bits())
}

#[cfg(test)]
mod tests {
    use super::*;
    use kinematics_core::Libm;

    const DT: f32 = 1.0 / 333.0;

    /// `t` with x moving at `mm_per_s` in frames of `dt` s, as a step would leave it.
    fn moving(mut t: Tracker, mm_per_s: f32, dt: f32) -> Tracker {
        t.velocity[0] = (f64::from(mm_per_s) * f64::from(dt) * f64::from(1u32 << MM_FRAC)) as i32;
        t.frame_s = dt;
        t
    }

    /// The speed of x, mm/s.
    fn speed_x(t: &Tracker) -> f32 {
        (f64::from(t.velocity[0]) / f64::from(1u32 << MM_FRAC) / f64::from(t.frame_s)) as f32
    }

    #[test]
    fn the_bit_tests_are_the_float_comparisons() {
        let specials = [
            0.0f32,
            -0.0,
            f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            1.0,
            -1.0,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        let mut next = crate::test_support::xorshift(0x2545_f491);
        let random = (0..100_000).map(|_| f32::from_bits(next()));
        for x in specials.into_iter().chain(random) {
            assert_eq!(finite(x), x.is_finite(), "{x:?}");
            assert_eq!(positive_finite(x), x > 0.0 && x.is_finite(), "{x:?}");
            if x.is_finite() {
                assert_eq!(x.to_bits() > 0x8000_0000, x < 0.0, "{x:?}");
            }
        }
    }

    fn limits(mm_per_s: f32, mm_per_s2: f32) -> TrackLimits {
        TrackLimits {
            mm_per_s,
            mm_per_s2,
            rad_per_s: 1.0,
            rad_per_s2: 10.0,
        }
    }

    /// Runs frames until at rest on the target (at most `max`); returns the x of each frame.
    fn run(from: f32, to: f32, l: &TrackLimits, max: usize) -> std::vec::Vec<f32> {
        let mut t = Tracker::new(&Pose::from_degrees(from, 0.0, 0.0, 0.0, 0.0, 0.0));
        let target = Pose::from_degrees(to, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut xs = std::vec![from];
        for _ in 0..max {
            t = t.step::<Libm>(&target, l, DT);
            xs.push(t.pose().x_mm);
            if t.at_rest() && t.pose() == target {
                break;
            }
        }
        xs
    }

    #[test]
    fn a_step_is_reached_within_the_limits_without_overshoot() {
        let l = limits(50.0, 500.0);
        let xs = run(0.0, 20.0, &l, 10_000);
        assert_eq!(*xs.last().unwrap(), 20.0, "arrived exactly");
        let v: std::vec::Vec<f32> = xs.windows(2).map(|w| (w[1] - w[0]) / DT).collect();
        for (k, pair) in v.windows(2).enumerate() {
            let a = (pair[1] - pair[0]) / DT;
            // The landing too.
            assert!(a.abs() <= 500.0 * 1.001, "frame {k}: {a} mm/s^2");
        }
        assert!(
            v.iter().all(|&s| (-1e-3..=50.0 * 1.001).contains(&s)),
            "{v:?}"
        );
        assert!(xs.iter().all(|&x| x <= 20.0), "overshoot");
        // Time-optimal: 20 mm at 50 mm/s with 500 mm/s^2 ramps: 0.1 s up, 0.3 s cruise,
        // 0.1 s down = 0.5 s, within a few frames.
        let seconds = (xs.len() - 1) as f32 * DT;
        assert!((seconds - 0.5).abs() < 0.02, "{seconds} s");
    }

    #[test]
    fn limits_off_pass_the_target_through() {
        assert_eq!(run(0.0, 20.0, &TrackLimits::OFF, 10), [0.0, 20.0]);
        // Speed limit alone: constant speed, no ramp.
        let xs = run(0.0, 1.0, &limits(33.3, 0.0), 100);
        assert!((xs[1] - 0.1).abs() < 1e-4, "{xs:?}");
    }

    #[test]
    fn a_moving_target_is_chased_and_a_reversal_does_not_overshoot() {
        let l = limits(100.0, 1000.0);
        let mut t = Tracker::new(&Pose::HOME);
        // 60 Hz staircase: the target steps every 5.55 frames.
        let mut worst_over: f32 = 0.0;
        for k in 0..2000 {
            let step = (k as f32 * DT * 60.0).floor();
            let target_x = if step < 30.0 {
                step * 0.5
            } else {
                15.0 - (step - 30.0) * 0.5
            };
            let target = Pose::from_degrees(target_x.max(0.0), 0.0, 0.0, 0.0, 0.0, 0.0);
            let before = t.pose().x_mm;
            t = t.step::<Libm>(&target, &l, DT);
            let after = t.pose().x_mm;
            // A step never moves past the target from the side it came from.
            if before <= target.x_mm {
                worst_over = worst_over.max(after - target.x_mm);
            } else {
                worst_over = worst_over.max(target.x_mm - after);
            }
        }
        assert!(worst_over <= 1e-5, "overshoot {worst_over}");
    }

    proptest::proptest! {
        // Positions within +-600 mm: 200 frames of at most 100 mm/s away from the target (v0)
        // reach at most 400 mm further, inside the tracker's +-1024 mm range; beyond it an axis
        // is held (`beyond_the_range_an_axis_is_held`), which no platform reaches.
        #[test]
        fn never_nan_never_beyond_the_limits(
            from in -600f32..600.0, to in -600f32..600.0, v0 in -100f32..100.0,
            v_max in 0f32..500.0, a_max in 0f32..5000.0, hz in 50f32..333.0,
        ) {
            let dt = 1.0 / hz;
            let l = TrackLimits { mm_per_s: v_max, mm_per_s2: a_max, rad_per_s: 0.0, rad_per_s2: 0.0 };
            let t = Tracker::new(&Pose::from_degrees(from, 0.0, 0.0, 0.0, 0.0, 0.0));
            let mut t = moving(t, v0.clamp(-v_max.max(0.0), v_max.max(0.0)), dt);
            let target = Pose::from_degrees(to, 0.0, 0.0, 0.0, 0.0, 0.0);
            let mut x = t.pose().x_mm;
            let mut v = speed_x(&t);
            for _ in 0..200 {
                t = t.step::<Libm>(&target, &l, dt);
                let (nx, nv) = (t.pose().x_mm, speed_x(&t));
                proptest::prop_assert!(nx.is_finite() && nv.is_finite());
                if v_max > 0.0 {
                    proptest::prop_assert!(nv.abs() <= v_max * 1.0001 + 1e-3, "speed {}", nv);
                }
                if a_max > 0.0 && nx != to {
                    proptest::prop_assert!((nv - v).abs() <= a_max * dt * 1.0001 + 1e-3, "accel");
                }
                // Between where it was and the target, or on it.
                let lo = x.min(to) - 1e-3;
                let hi = x.max(to) + 1e-3;
                if v.signum() == (to - x).signum() || v == 0.0 {
                    proptest::prop_assert!(nx >= lo && nx <= hi, "{} not in {}..{}", nx, lo, hi);
                }
                x = nx;
                v = nv;
            }
        }
    }

    // ----- the integer arithmetic against f64 -----

    /// xorshift32: reproducible random words.
    struct Rng(u32);

    impl Rng {
        fn word(&mut self) -> u32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 17;
            self.0 ^= self.0 << 5;
            self.0
        }

        /// Uniform in `[0, 1)`.
        fn unit(&mut self) -> f64 {
            f64::from(self.word()) / 4_294_967_296.0
        }

        /// A whole number of up to `bits` bits, its size spread evenly over them.
        fn spread(&mut self, bits: u32) -> u32 {
            let size = self.word() % (bits + 1);
            if size == 0 {
                0
            } else {
                self.word() >> (32 - size)
            }
        }
    }

    #[test]
    fn units_are_the_values_rounded() {
        let mut rng = Rng(0x1234_5678);
        for frac in [MM_FRAC, RAD_FRAC] {
            let scale = f64::from(1u32 << frac);
            for k in 0..200_000 {
                // Any bits, or values around the range's edge and a unit's.
                let x = match k % 3 {
                    0 => f32::from_bits(rng.word()),
                    1 => ((rng.unit() - 0.5) * 2.2 * f64::from(MAX_UNITS) / scale) as f32,
                    _ => ((rng.unit() - 0.5) * 64.0 / scale) as f32,
                };
                let exact = f64::from(x) * scale; // exact in f64
                let expected = (x.is_finite() && exact.round().abs() < f64::from(MAX_UNITS))
                    .then(|| exact.round() as i32);
                assert_eq!(to_units(x, frac), expected, "{x:e}");
                if x.is_finite() && x > 0.0 {
                    let below = exact.floor().min(2_147_483_648.0) as u32;
                    assert_eq!(units_below(x, frac), below, "{x:e}");
                }
            }
            for k in 0..200_000 {
                let units = match k % 2 {
                    0 => rng.word() as i32 >> 1,
                    _ => rng.spread(30) as i32 * if rng.word() & 1 == 1 { -1 } else { 1 },
                };
                let expected = (f64::from(units) / scale) as f32; // rounds to nearest even
                assert_eq!(to_f32(units, frac).to_bits(), expected.to_bits(), "{units}");
            }
        }
    }

    #[test]
    fn the_square_root_is_the_floor_and_the_leading_zeros_are_counted() {
        let mut rng = Rng(0x9e37_79b9);
        let edges = [
            0,
            1,
            2,
            3,
            4,
            15,
            16,
            17,
            u32::MAX,
            u32::MAX - 1,
            0xffff * 0xffff,
        ];
        for x in edges
            .into_iter()
            .chain((0..200_000).map(|_| rng.spread(32)))
        {
            if x != 0 {
                assert_eq!(
                    normalise(x),
                    (x << x.leading_zeros(), x.leading_zeros()),
                    "{x}"
                );
            }
            let r = u64::from(isqrt(x));
            assert!(
                r * r <= u64::from(x) && (r + 1) * (r + 1) > u64::from(x),
                "{x}: {r}"
            );
        }
    }

    /// The braking speed by its definition, computed another way: `n` from an `f64` square
    /// root, corrected by exact `u128` sums; the speed as one exact `u128` division.
    fn braking_reference(d: u32, h: u32) -> u32 {
        if h == 0 {
            return 0;
        }
        let (d, h) = (u128::from(d), u128::from(h));
        let fits = |n: u128| h * n * (n + 1) / 2 <= d;
        // (`as` saturates: a negative estimate is 0.)
        let mut n = (((1.0 + 8.0 * d as f64 / h as f64).sqrt() - 1.0) / 2.0) as u128;
        while n > 0 && !fits(n) {
            n -= 1;
        }
        while fits(n + 1) {
            n += 1;
        }
        ((2 * d + h * n * (n + 1)) / (2 * (n + 1))) as u32
    }

    #[test]
    fn the_braking_speed_is_its_formula_and_stops_exactly() {
        let mut rng = Rng(0x0bad_cafe);
        for _ in 0..300_000 {
            let d = rng.spread(31).max(1);
            let h = rng.spread(32).min(1 << 31);
            assert_eq!(braking_speed(d, h), braking_reference(d, h), "d {d} h {h}");
        }
        // What it means, on small numbers: braking by h each frame from that speed covers at
        // most d (the axis lands), and from one unit more it would cover more.
        let covered = |v: u32, h: u32| -> u64 { (0..=v / h).map(|j| u64::from(v - j * h)).sum() };
        for h in 1..40 {
            for d in 1..400 {
                let v = braking_speed(d, h);
                assert!(covered(v, h) <= u64::from(d), "d {d} h {h} v {v}");
                assert!(
                    covered(v + 1, h) > u64::from(d),
                    "d {d} h {h} v {v}: slower than needed"
                );
            }
        }
    }

    /// The rule of the module docs in `f64`, for one axis and one frame, in units: position
    /// `p`, velocity `v` (per frame), target `x`, limits per frame (`None` off, any value).
    fn rule_f64(p: f64, v: f64, x: f64, speed: Option<f64>, h: Option<f64>) -> (f64, f64) {
        let error = x - p;
        if error == 0.0 {
            return (x, 0.0);
        }
        let d = error.abs();
        let mut wanted = d;
        if let Some(h) = h {
            let braking = if h > 0.0 {
                let mut n = ((1.0 + 8.0 * d / h).sqrt() - 1.0) / 2.0;
                n = n.floor().max(0.0);
                while n > 0.0 && h * n * (n + 1.0) / 2.0 > d {
                    n -= 1.0;
                }
                while h * (n + 1.0) * (n + 2.0) / 2.0 <= d {
                    n += 1.0;
                }
                d / (n + 1.0) + h * n / 2.0
            } else {
                0.0
            };
            wanted = wanted.min(braking);
        }
        if let Some(s) = speed {
            wanted = wanted.min(s);
        }
        let wanted = wanted.copysign(error);
        let nv = match h {
            Some(h) => v + (wanted - v).clamp(-h, h),
            None => wanted,
        };
        if (error > 0.0 && nv >= error) || (error < 0.0 && nv <= error) {
            return (x, error);
        }
        (p + nv, nv)
    }

    /// Random limits for a group: off, or spread over the settings' ranges and beyond.
    fn random_limit(rng: &mut Rng, low: f64, high: f64) -> f32 {
        match rng.word() % 5 {
            0 => 0.0,
            _ => (low * (high / low).powf(rng.unit())) as f32,
        }
    }

    #[test]
    fn a_step_is_the_f64_rule_within_a_unit() {
        // Each case: a random state, target, limits and frame time; the step in integers
        // against the rule in f64 with the same limits per frame (the integer ones: their own
        // rounding is checked below), from the same position in units. The integer step rounds
        // the braking speed down (by less than a unit); the rest is exact.
        let mut rng = Rng(0x5eed_0001);
        let mut worst: f64 = 0.0;
        for case in 0..200_000 {
            let axis = (case % 6) as usize;
            let frac = frac_of(axis);
            let scale = f64::from(1u32 << frac);
            let hz = 50.0 + 283.0 * rng.unit();
            let dt = (1.0 / hz) as f32;
            let (speed, accel) = if axis < 3 {
                (
                    random_limit(&mut rng, 0.1, 1000.0),
                    random_limit(&mut rng, 1.0, 1e5),
                )
            } else {
                (
                    random_limit(&mut rng, 1e-3, 60.0),
                    random_limit(&mut rng, 0.017, 2e4),
                )
            };
            let limits = FrameLimits::new::<Libm>(speed, accel, dt, frac);
            if limits.speed.is_none() && limits.accel.is_none() {
                continue;
            }
            let range = f64::from(MAX_UNITS) / 8.0;
            let position = ((rng.unit() - 0.5) * range) as i32;
            // Near the position (a stop in progress) or anywhere.
            let reach = if rng.word() & 1 == 0 {
                1e-4 * range
            } else {
                range
            };
            let target = ((f64::from(position) + (rng.unit() - 0.5) * reach) / scale) as f32;
            let goal = to_units(target, frac).unwrap();
            // A velocity within the speed limit, or at the braking speed (so the stop is
            // on), or any.
            let cap = f64::from(limits.speed.unwrap_or(1 << 20).min(1 << 20));
            let velocity = (match rng.word() % 3 {
                0 => (rng.unit() - 0.5) * 2.0 * cap,
                1 => {
                    let d = (goal - position).unsigned_abs().max(1);
                    let b = f64::from(braking_speed(d, limits.accel.unwrap_or(u32::MAX)));
                    b.copysign(f64::from(goal - position)) * rng.unit()
                }
                _ => (rng.unit() - 0.5) * f64::from(1u32 << 24),
            }) as i32;
            let axis_state = Axis {
                pose: to_f32(position, frac),
                position,
                velocity,
            };
            let next = axis_state.step(target, limits, frac);
            let (p, v) = rule_f64(
                f64::from(position),
                f64::from(velocity),
                f64::from(goal),
                limits.speed.map(f64::from),
                limits.accel.map(f64::from),
            );
            let error = (f64::from(next.position) - p)
                .abs()
                .max((f64::from(next.velocity) - v).abs());
            assert!(
                error < 1.0,
                "case {case}: {next:?} vs ({p}, {v}); from {axis_state:?} to {goal} within {limits:?}"
            );
            worst = worst.max(error);
            if next.position == goal {
                assert_eq!(next.pose.to_bits(), target.to_bits(), "landed exactly");
            } else {
                assert_eq!(next.pose, to_f32(next.position, frac));
            }
        }
        assert!(worst > 0.0, "the braking speed's rounding shows somewhere");
    }

    #[test]
    fn the_limits_per_frame_are_the_products_rounded_down() {
        // Off-by: the two f32 products' rounding (2^-24 each, relative), then down to a unit.
        let mut rng = Rng(0x5eed_0002);
        for _ in 0..100_000 {
            let frac = if rng.word() & 1 == 0 {
                MM_FRAC
            } else {
                RAD_FRAC
            };
            let scale = f64::from(1u32 << frac);
            let dt = (1.0 / (50.0 + 283.0 * rng.unit())) as f32;
            let speed = random_limit(&mut rng, 1e-3, 1e6);
            let accel = random_limit(&mut rng, 1e-3, 1e7);
            let l = FrameLimits::new::<Libm>(speed, accel, dt, frac);
            let check = |got: Option<u32>, exact: f64, on: bool| {
                if !on {
                    assert_eq!(got, None);
                    return;
                }
                let got = f64::from(got.unwrap());
                let exact = (exact * scale).min(2_147_483_648.0);
                assert!(got <= exact * (1.0 + 2.0f64.powi(-22)), "{got} > {exact}");
                assert!(
                    got > exact * (1.0 - 2.0f64.powi(-22)) - 1.0,
                    "{got} << {exact}"
                );
            };
            let dt64 = f64::from(dt);
            check(l.speed, f64::from(speed) * dt64, speed > 0.0);
            check(l.accel, f64::from(accel) * dt64 * dt64, accel > 0.0);
        }
    }

    #[test]
    fn whole_moves_follow_the_f64_rule_with_exact_limits() {
        // Whole moves, the integer tracker against the rule in f64 with the limits unrounded
        // (real units per frame). Rounding the limits down to whole units makes the integer
        // tracker slower by up to `1 / h` (and `1 / (v_max dt)`) relatively (`h` in units: 94
        // at 10 mm/s^2 and 333 Hz): the positions stay within that fraction of the distance
        // plus 2e-5 mm, and the arrivals within a frame plus that fraction of the time.
        let mut rng = Rng(0x5eed_0003);
        for case in 0..2_000 {
            let hz = [50.0f32, 100.0, 200.0, 333.0][case % 4];
            let dt = 1.0 / hz;
            let (speed, accel) = (
                random_limit(&mut rng, 1.0, 1000.0),
                (10.0 * 1e4f64.powf(rng.unit())) as f32,
            );
            let l = TrackLimits {
                mm_per_s: speed,
                mm_per_s2: accel,
                rad_per_s: 0.0,
                rad_per_s2: 0.0,
            };
            let from = ((rng.unit() - 0.5) * 200.0) as f32;
            let to = ((rng.unit() - 0.5) * 200.0) as f32;
            let scale = f64::from(1u32 << MM_FRAC);
            let dt64 = f64::from(dt);
            let speed_units = (speed > 0.0).then(|| f64::from(speed) * dt64 * scale);
            let h_units = Some(f64::from(accel) * dt64 * dt64 * scale);
            let mut t = Tracker::new(&Pose::from_degrees(from, 0.0, 0.0, 0.0, 0.0, 0.0));
            let target = Pose::from_degrees(to, 0.0, 0.0, 0.0, 0.0, 0.0);
            let (mut p, mut v) = (f64::from(from) * scale, 0.0);
            let x = f64::from(to) * scale;
            // What rounding the limits down to whole units costs, relatively.
            let rounding = h_units.map_or(0.0, |h| 1.0 / h.floor())
                + speed_units.map_or(0.0, |s| 1.0 / s.floor());
            let bound = rounding * f64::from((to - from).abs()) + 2e-5;
            let (mut arrived, mut arrived_f64) = (None, None);
            for frame in 0..100_000u32 {
                t = t.step::<Libm>(&target, &l, dt);
                (p, v) = rule_f64(p, v, x, speed_units, h_units);
                let off = (f64::from(t.pose().x_mm) - p / scale).abs();
                assert!(off <= bound, "case {case} frame {frame}: {off} mm");
                if arrived.is_none() && t.pose() == target {
                    arrived = Some(frame);
                }
                if arrived_f64.is_none() && p == x {
                    arrived_f64 = Some(frame);
                }
                if arrived.is_some() && arrived_f64.is_some() {
                    break;
                }
            }
            let (a, b) = (arrived.unwrap(), arrived_f64.unwrap());
            assert!(
                f64::from(a.abs_diff(b)) <= 1.0 + rounding * f64::from(b),
                "case {case}: arrived at frame {a}, f64 at {b}"
            );
        }
    }

    #[test]
    fn a_new_frame_time_keeps_the_speed() {
        let l = limits(100.0, 1000.0);
        let target = Pose::from_degrees(50.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut t = Tracker::new(&Pose::HOME);
        for _ in 0..20 {
            t = t.step::<Libm>(&target, &l, 1.0 / 50.0);
        }
        let before = speed_x(&t);
        assert!((before - 100.0).abs() < 1e-3, "{before}");
        let (x0, next) = (t.pose().x_mm, t.step::<Libm>(&target, &l, 1.0 / 333.0));
        let moved = (next.pose().x_mm - x0) * 333.0;
        assert!(
            (moved - 100.0).abs() < 0.01,
            "{moved} mm/s after the change"
        );
    }

    #[test]
    fn beyond_the_range_an_axis_is_held() {
        let l = limits(100.0, 1000.0);
        let far = Pose::from_degrees(2000.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let t = Tracker::new(&Pose::HOME).step::<Libm>(&far, &l, DT);
        assert_eq!(t.pose(), Pose::HOME);
        let t = Tracker::new(&far).step::<Libm>(&Pose::HOME, &l, DT);
        assert_eq!(t.pose(), far);
        // Pass-through needs no range.
        let t = Tracker::new(&Pose::HOME).step::<Libm>(&far, &TrackLimits::OFF, DT);
        assert_eq!(t.pose(), far);
    }
}
