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

    /// `(speed, acceleration)` for axis `index` (0..=5, [`Pose::to_array`] order).
    fn of_axis(&self, index: usize) -> (f32, f32) {
        if index < 3 {
            (self.mm_per_s, self.mm_per_s2)
        } else {
            (self.rad_per_s, self.rad_per_s2)
        }
    }
}

/// Where the tracker is and how fast it goes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tracker {
    pose: [f32; 6],
    velocity: [f32; 6],
}

impl Tracker {
    /// At rest at `pose`.
    pub fn new(pose: &Pose) -> Tracker {
        Tracker {
            pose: pose.to_array(),
            velocity: [0.0; 6],
        }
    }

    /// The pose of the last step.
    pub fn pose(&self) -> Pose {
        Pose::from_array(self.pose)
    }

    /// True if every axis is at rest.
    pub fn at_rest(&self) -> bool {
        self.velocity.iter().all(|&v| v == 0.0)
    }

    /// The tracker one frame (`dt_s`, > 0) later, chasing `target` within `limits`. `self` is
    /// unchanged: the caller keeps the new one once it has checked its pose can be driven.
    pub fn step<M: Math>(&self, target: &Pose, limits: &TrackLimits, dt_s: f32) -> Tracker {
        let target = target.to_array();
        let mut next = *self;
        for (i, &goal) in target.iter().enumerate() {
            let (pose, velocity) = axis_step::<M>(
                self.pose[i],
                self.velocity[i],
                goal,
                limits.of_axis(i),
                dt_s,
            );
            next.pose[i] = pose;
            next.velocity[i] = velocity;
        }
        next
    }

    /// Stops at `pose` (where the platform is held, e.g. after a clamp or a stop).
    pub fn hold_at(&mut self, pose: &Pose) {
        *self = Tracker::new(pose);
    }
}

/// The fastest speed for this frame from which the axis still stops exactly on the target,
/// slowing by at most `h = a_max dt` per frame: the discrete form of `sqrt(2 a_max d)`.
/// `frames_of_distance` is the distance over `dt`.
///
/// Moving at `v` this frame and then at `v - h`, `v - 2h`, ... (while positive) covers
/// `dt ((n + 1) v - h n (n + 1) / 2)` with `n = floor(v / h)`. Setting that to the distance
/// `d = D dt` and solving: `n` is the largest whole number with `h n (n + 1) / 2 <= D`, and
/// `v = D / (n + 1) + h n / 2`. The last frame of a stop then moves at most `h`, so the speed
/// changes by at most `h` every frame, landing included.
fn braking_speed<M: Math>(frames_of_distance: f32, h: f32) -> f32 {
    let d = frames_of_distance;
    // (Truncation is floor here: the value is not negative; `as` saturates.)
    let root = (M::sqrt(1.0 + 8.0 * d / h) - 1.0) * 0.5;
    let mut n = (if root > 0.0 { root } else { 0.0 } as u32) as f32;
    // Rounding of the square root: make sure n is the largest whole number that fits.
    if h * n * (n + 1.0) * 0.5 > d {
        n -= 1.0;
    } else if h * (n + 1.0) * (n + 2.0) * 0.5 <= d {
        n += 1.0;
    }
    d / (n + 1.0) + h * n * 0.5
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

/// `a.min(b)` for a finite `a` (one comparison where `f32::min` is a library call with NaN
/// handling on the RP2040; a NaN `b` leaves `a`, as `min` does).
fn smaller(a: f32, b: f32) -> f32 {
    if b < a {
        b
    } else {
        a
    }
}

/// One axis, one frame: `(position, velocity)` after it.
fn axis_step<M: Math>(
    position: f32,
    velocity: f32,
    target: f32,
    (v_max, a_max): (f32, f32),
    dt: f32,
) -> (f32, f32) {
    // At rest on its target, an axis stays there (what the steps below give too, without a
    // float operation: on the RP2040 each is a library call, and a stream often leaves some
    // axes still).
    if target.to_bits() == position.to_bits() && velocity.to_bits() << 1 == 0 {
        return (position, 0.0);
    }
    let error = target - position;
    if !(finite(error) && finite(velocity)) {
        // Not reachable from finite inputs; hold rather than pass a NaN on.
        return (position, 0.0);
    }
    // A limit that is not a positive finite number is off.
    let (speed_limited, accel_limited) = (positive_finite(v_max), positive_finite(a_max));
    if !speed_limited && !accel_limited {
        return (target, 0.0);
    }
    let distance = error.abs();
    // The direction to the target, -1 or 1, as a flag: `error < 0.0` by the bits (finite
    // here: the sign bit, and not -0); multiplying by the direction is then a negation.
    let backwards = error.to_bits() > 0x8000_0000;
    // The speed aimed at: what reaches the target this frame, what can still stop on it
    // ([`braking_speed`]), and the speed limit.
    let reach_speed = distance / dt;
    let mut wanted = reach_speed;
    if accel_limited {
        wanted = smaller(wanted, braking_speed::<M>(reach_speed, a_max * dt));
    }
    if speed_limited {
        wanted = smaller(wanted, v_max);
    }
    let wanted = if backwards { -wanted } else { wanted };
    let new_velocity = if accel_limited {
        let change = a_max * dt;
        velocity + (wanted - velocity).clamp(-change, change)
    } else {
        wanted
    };
    let new_position = position + new_velocity * dt;
    // Never past the target: a step that would cross it ends on it. Its velocity is that of
    // the step it took (not zero: the next steps slow from it within the limit, staying on
    // the target, so a target that then moves away is not chased from a standstill that never
    // happened).
    let ahead = target - new_position;
    let reached = if backwards {
        ahead >= 0.0
    } else {
        ahead <= 0.0
    };
    if reached {
        return (target, error / dt);
    }
    (new_position, new_velocity)
}

#[cfg(test)]
mod tests {
    use super::*;
    use kinematics_core::Libm;

    const DT: f32 = 1.0 / 333.0;

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
        let mut seed = 0x2545_f491_u32;
        let random = (0..100_000).map(|_| {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            f32::from_bits(seed)
        });
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
        #[test]
        fn never_nan_never_beyond_the_limits(
            from in -1e3f32..1e3, to in -1e3f32..1e3, v0 in -100f32..100.0,
            v_max in 0f32..500.0, a_max in 0f32..5000.0, hz in 50f32..333.0,
        ) {
            let dt = 1.0 / hz;
            let l = TrackLimits { mm_per_s: v_max, mm_per_s2: a_max, rad_per_s: 0.0, rad_per_s2: 0.0 };
            let mut t = Tracker::new(&Pose::from_degrees(from, 0.0, 0.0, 0.0, 0.0, 0.0));
            t.velocity[0] = v0.clamp(-v_max.max(0.0), v_max.max(0.0));
            let target = Pose::from_degrees(to, 0.0, 0.0, 0.0, 0.0, 0.0);
            let mut x = t.pose().x_mm;
            let mut v = t.velocity[0];
            for _ in 0..200 {
                t = t.step::<Libm>(&target, &l, dt);
                let (nx, nv) = (t.pose().x_mm, t.velocity[0]);
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
}
