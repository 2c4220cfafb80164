//! The servos' own speed: each servo's rated no-load speed (`servoN.speed_s_60deg`, seconds per
//! 60 degrees of turn, as hobby servo datasheets give it: e.g. 0.10 s/60 deg; 0 = not rated,
//! the default), and how motion is slowed so that no arm is asked to turn faster than that.
//!
//! A servo asked to turn faster than it can lags, the legs disagree and the platform twists off
//! its path. So, with at least one servo rated:
//! - a move (`pose`, `move`, `nudge`, `home`, and the controller's own ways home) takes its
//!   straight path no faster than the slowest-turning arm allows: the move's speed limits are
//!   tightened ([`ServoSpeeds::capped_limits`]) so that the whole path takes at least the
//!   *path time* `T` (s), the time the arms need to follow it at their ratings. `T` is first
//!   estimated from the arm angles at the two ends; the path check then measures it along the
//!   path from the arm angles its IK solutions give at every checkpoint
//!   ([`PathTime`]: `max_i |d alpha_i| / w_i` per fraction of the path between checkpoints), and
//!   if the path needs longer than estimated, the move is planned again with the measured time
//!   and its path checked again (so the path taken is the one checked). The plan uses
//!   [`PLAN_MARGIN`] of each rating, for what lies between checkpoints. With every speed limit
//!   off such a move is no longer a jump. A move taken over while moving (a blend,
//!   [`crate::motion::blend`]) is measured per frame instead: its check finds the largest
//!   share of its rating any arm turns by in a frame, from the IK's arm angles at every frame
//!   it will command, and if that is over 1 the blend is planned again with its speeds and its
//!   corner velocity slowed by it (`controller/path.rs`, `FrameTurns`).
//! - a stream's step ([`crate::tracker`]) that would turn an arm by more than its rating times
//!   the frame period is shortened, all axes alike, to the fraction of it the slowest arm can
//!   follow ([`ServoSpeeds::step_scale`], at [`PLAN_MARGIN`]), so the platform keeps the step's
//!   direction, and the tracker goes on from there. The shortened step is solved by the IK (one
//!   solution more, only in a frame that is shortened); should an arm still turn too far there,
//!   the arm angles and pulses are taken the fraction of the way that keeps them within
//!   (pulses are linear in arm angles, eq. 13, 14). Without ratings nothing of this runs; with
//!   ratings that a step keeps, it costs six differences. With every speed and acceleration
//!   limit off a rated stream is tracked (one step per frame) instead of passed through, so
//!   each frame's step is capped the same way.
//!
//! Units: the ratings in s per 60 degrees (kept to hundredths, as the flash record holds them:
//! 0.01..=2.55), arm angles in rad, times in s. Off (no servo rated), nothing here runs.

use kinematics_core::{Pose, LEGS};

use crate::motion::{angular_distance_deg, linear_distance_mm, SpeedLimits};

/// Fastest rating accepted (besides 0 = not rated), s per 60 degrees.
pub const MIN_S_PER_60DEG: f32 = 0.01;
/// Slowest rating accepted, s per 60 degrees (the flash record keeps hundredths in a byte).
pub const MAX_S_PER_60DEG: f32 = 2.55;
/// The fraction of each rating a move is planned at: the path time is measured between
/// checkpoints (at most 0.5 mm or 0.25 degree apart, see [`crate::motion`]), and an arm may
/// turn a little faster between two of them than on average.
pub const PLAN_MARGIN: f32 = 0.97;

/// Radians in 60 degrees.
const RAD_PER_60DEG: f32 = core::f32::consts::FRAC_PI_3;

/// The servos' rated speeds.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ServoSpeeds {
    /// Time servo `i + 1` takes to turn 60 degrees unloaded, s, a whole number of hundredths;
    /// 0 = not rated.
    pub s_per_60deg: [f32; LEGS],
}

impl ServoSpeeds {
    /// True if at least one servo is rated: motion is then slowed to the ratings.
    pub fn rated(&self) -> bool {
        // (Bits: a rating is 0.0 or positive; float comparisons are library calls on the
        // RP2040.)
        self.s_per_60deg.iter().any(|r| r.to_bits() != 0)
    }

    /// A rating kept to hundredths of a second (what the flash record holds): `value` rounded
    /// to the nearest hundredth (for the values the settings accept, 0..=2.55); 0 for 0, a
    /// negative value or NaN.
    pub fn quantise(value: f32) -> f32 {
        if value.is_nan() || value <= 0.0 {
            return 0.0;
        }
        f32::from(hundredths(value)) / 100.0
    }

    /// The least time, s, in which the arms can turn from `from` to `to` (rad), each at its
    /// rating: `max_i |to_i - from_i| t_i / (pi / 3)` over the rated servos (0 if none is).
    pub fn least_time_s(&self, from: &[f32; LEGS], to: &[f32; LEGS]) -> f32 {
        let mut worst = 0.0f32;
        for i in 0..LEGS {
            let rating = self.s_per_60deg[i];
            if rating.to_bits() == 0 {
                continue;
            }
            let t = libm::fabsf(to[i] - from[i]) * rating;
            // NaN (never expected: arm angles are finite) counts as the slowest.
            if t.is_nan() || t > worst {
                worst = if t.is_nan() { f32::INFINITY } else { t };
            }
        }
        worst / RAD_PER_60DEG
    }

    /// The fraction (in `(0, 1]`) of a frame's step from arm angles `from` to `to` that the
    /// servos can turn within the frame of `dt_s` seconds: 1 if all can follow it, otherwise
    /// `dt_s` over [`ServoSpeeds::least_time_s`], so no arm turns by more than its rating
    /// times `dt_s`.
    pub fn step_scale(&self, from: &[f32; LEGS], to: &[f32; LEGS], dt_s: f32) -> f32 {
        let least = self.least_time_s(from, to);
        if least <= dt_s {
            1.0
        } else if least.is_finite() {
            dt_s / least
        } else {
            0.0
        }
    }

    /// `limits` tightened so that the straight move from `start` to `target` takes at least
    /// `path_time_s / PLAN_MARGIN` seconds: each speed limit at most its distance over that
    /// time (a limit that is off becomes that one). The acceleration limits stay as they are
    /// (a trapezoid's top speed is its speed limit). A path time of 0 (no arm turns) leaves
    /// them as they are.
    pub fn capped_limits(
        limits: SpeedLimits,
        start: &Pose,
        target: &Pose,
        path_time_s: f32,
    ) -> SpeedLimits {
        if path_time_s.is_nan() || path_time_s <= 0.0 {
            return limits;
        }
        let time_s = path_time_s / PLAN_MARGIN;
        let cap = |limit: f32, distance: f32| {
            if distance > 0.0 {
                let fastest = distance / time_s;
                if limit > 0.0 && limit < fastest {
                    limit
                } else {
                    fastest
                }
            } else {
                limit
            }
        };
        SpeedLimits {
            mm_per_s: cap(limits.mm_per_s, linear_distance_mm(start, target)),
            deg_per_s: cap(limits.deg_per_s, angular_distance_deg(start, target)),
            ..limits
        }
    }
}

/// A rating (s per 60 degrees, not negative) in hundredths, rounded to the nearest (saturating
/// at the byte the flash record keeps: 2.55 s).
pub fn hundredths(value: f32) -> u8 {
    // `as` saturates (and takes NaN to 0).
    (value * 100.0 + 0.5) as u8
}

/// The path time of a straight path measured along it: the arm angles at successive poses of
/// the path (in order, each with its fraction of the way), and the longest time per whole path
/// that any stretch between two of them needs at the servos' ratings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathTime {
    start: [f32; 6],
    /// `target - start` per coordinate ([`Pose::to_array`] order) and the coordinate that
    /// changes most, to tell a pose's fraction of the way.
    span: [f32; 6],
    along: usize,
    /// The last pose's fraction of the way and arm angles.
    fraction: f32,
    arm_rad: [f32; LEGS],
    /// The longest so far, s.
    time_s: f32,
}

impl PathTime {
    /// Measuring the path from `start` (whose arm angles are `start_arm_rad`) to `target`.
    pub fn new(start: &Pose, target: &Pose, start_arm_rad: &[f32; LEGS]) -> PathTime {
        let (a, b) = (start.to_array(), target.to_array());
        let span: [f32; 6] = core::array::from_fn(|i| b[i] - a[i]);
        let mut along = 0;
        for i in 1..6 {
            if libm::fabsf(span[i]) > libm::fabsf(span[along]) {
                along = i;
            }
        }
        PathTime {
            start: a,
            span,
            along,
            fraction: 0.0,
            arm_rad: *start_arm_rad,
            time_s: 0.0,
        }
    }

    /// The next pose along the path (further than the last) and its arm angles.
    pub fn visit(&mut self, speeds: &ServoSpeeds, pose: &Pose, arm_rad: &[f32; LEGS]) {
        let span = self.span[self.along];
        if span == 0.0 {
            return; // a path of no length
        }
        let fraction = (pose.to_array()[self.along] - self.start[self.along]) / span;
        let step = fraction - self.fraction;
        if step > 0.0 {
            let time = speeds.least_time_s(&self.arm_rad, arm_rad) / step;
            if time > self.time_s {
                self.time_s = time;
            }
        }
        self.fraction = fraction;
        self.arm_rad = *arm_rad;
    }

    /// The longest time per whole path measured so far, s.
    pub fn time_s(&self) -> f32 {
        self.time_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RATED: ServoSpeeds = ServoSpeeds {
        s_per_60deg: [0.1, 0.2, 0.0, 0.1, 0.1, 0.1],
    };

    #[test]
    fn off_is_not_rated_and_costs_no_time() {
        let off = ServoSpeeds::default();
        assert!(!off.rated() && RATED.rated());
        assert_eq!(off.least_time_s(&[0.0; 6], &[1.0; 6]), 0.0);
        assert_eq!(off.step_scale(&[0.0; 6], &[1.0; 6], 0.02), 1.0);
    }

    #[test]
    fn the_least_time_is_the_slowest_arm_at_its_rating() {
        // 60 degrees at 0.1 s: 0.1 s; servo 2 turns 30 degrees at 0.2 s / 60: 0.1 s too;
        // servo 3 is not rated (whatever it turns costs no time).
        let sixty = core::f32::consts::FRAC_PI_3;
        let to = [sixty, -sixty / 2.0, 10.0, 0.0, 0.0, 0.0];
        assert!((RATED.least_time_s(&[0.0; 6], &to) - 0.1).abs() < 1e-6);
        // Servo 2, 90 degrees back: 0.3 s.
        let to = [0.0, -1.5 * sixty, 0.0, 0.0, 0.0, 0.0];
        assert!((RATED.least_time_s(&[0.0; 6], &to) - 0.3).abs() < 1e-6);
        // A frame of 20 ms covers a fifteenth of that.
        let k = RATED.step_scale(&[0.0; 6], &to, 0.02);
        assert!((k - 0.02 / 0.3).abs() < 1e-6, "{k}");
        assert_eq!(RATED.step_scale(&[0.0; 6], &[0.01; 6], 0.02), 1.0);
        assert_eq!(RATED.step_scale(&[0.0; 6], &[f32::NAN; 6], 0.02), 0.0);
    }

    #[test]
    fn limits_are_capped_to_the_path_time_and_never_loosened() {
        let a = Pose::HOME;
        let b = Pose::from_degrees(30.0, 40.0, 0.0, 0.0, 0.0, 12.0); // 50 mm, 12 degrees
        let off = SpeedLimits::speeds(0.0, 0.0);
        let c = ServoSpeeds::capped_limits(off, &a, &b, 0.97);
        // 1 s of path time at the margin: 50 mm/s and 12 deg/s.
        assert!((c.mm_per_s - 50.0).abs() < 1e-3 && (c.deg_per_s - 12.0).abs() < 1e-3);
        let slow = SpeedLimits::speeds(10.0, 100.0);
        let c = ServoSpeeds::capped_limits(slow, &a, &b, 0.97);
        assert_eq!(c.mm_per_s, 10.0);
        assert!((c.deg_per_s - 12.0).abs() < 1e-3);
        assert_eq!(ServoSpeeds::capped_limits(slow, &a, &b, 0.0), slow);
        // A pure rotation leaves the linear limit alone.
        let r = Pose::from_degrees(0.0, 0.0, 0.0, 6.0, 0.0, 0.0);
        let c = ServoSpeeds::capped_limits(off, &a, &r, 0.97);
        assert_eq!(c.mm_per_s, 0.0);
        assert!((c.deg_per_s - 6.0).abs() < 1e-3);
    }

    #[test]
    fn the_path_time_is_the_steepest_stretch() {
        let a = Pose::HOME;
        let b = Pose::from_degrees(0.0, 0.0, 10.0, 0.0, 0.0, 0.0);
        let speeds = ServoSpeeds {
            s_per_60deg: [0.1; 6],
        };
        let sixty = core::f32::consts::FRAC_PI_3;
        let mut t = PathTime::new(&a, &b, &[0.0; 6]);
        // The first half turns servo 1 by 60 degrees (0.1 s for half the path: 0.2 s per
        // path), the second by 60 more over a quarter (0.4 s per path), then nothing.
        t.visit(
            &speeds,
            &motion_lerp(&a, &b, 0.5),
            &[sixty, 0.0, 0.0, 0.0, 0.0, 0.0],
        );
        assert!((t.time_s() - 0.2).abs() < 1e-5);
        t.visit(
            &speeds,
            &motion_lerp(&a, &b, 0.75),
            &[2.0 * sixty, 0.0, 0.0, 0.0, 0.0, 0.0],
        );
        t.visit(&speeds, &b, &[2.0 * sixty, 0.0, 0.0, 0.0, 0.0, 0.0]);
        assert!((t.time_s() - 0.4).abs() < 1e-5, "{}", t.time_s());
        // A path of no length measures nothing.
        let mut none = PathTime::new(&a, &a, &[0.0; 6]);
        none.visit(&speeds, &a, &[1.0; 6]);
        assert_eq!(none.time_s(), 0.0);
    }

    #[test]
    fn ratings_keep_hundredths() {
        assert_eq!(ServoSpeeds::quantise(0.105), 0.11);
        assert_eq!(ServoSpeeds::quantise(0.0), 0.0);
        assert_eq!(ServoSpeeds::quantise(-1.0), 0.0);
        assert_eq!(ServoSpeeds::quantise(f32::NAN), 0.0);
        for c in 1..=255u8 {
            // Each hundredth as a user types it ("0.07", "2.55"), parsed as the board does.
            let text = std::format!("{}.{:02}", c / 100, c % 100);
            let v = crate::number::parse_f32(&text).unwrap();
            assert_eq!(hundredths(v), c, "{text}");
            assert_eq!(ServoSpeeds::quantise(v), v, "{text}");
        }
    }

    fn motion_lerp(a: &Pose, b: &Pose, t: f32) -> Pose {
        crate::motion::lerp(a, b, t)
    }
}
