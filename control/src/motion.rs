//! Motion planning: straight lines in pose space at bounded speed, one pose per servo frame.
//!
//! A move from pose `P0` to `P1` interpolates all six coordinates linearly:
//! `P(t) = P0 + t (P1 - P0)`, `t` in `0..=1`. Its duration is the larger of
//! - linear distance / linear speed limit, where the linear distance is the Euclidean length of
//!   `(dx, dy, dz)` in mm (the true path length of the platform centre), and
//! - angular distance / angular speed limit, where the angular distance is the Euclidean length
//!   of `(d roll, d pitch, d yaw)` in degrees,
//!
//! so both limits hold and the slower group sets the pace. A limit of 0 means "no limit"; with
//! both off a move is a jump (one frame). The duration is rounded up to whole frames, so the
//! speeds are never exceeded (beyond f32 rounding, at most 0.001 %); frame `k` of `N` commands
//! `P(k / N)` and the last frame commands `P1` exactly.
//!
//! With acceleration limits (linear mm/s^2, angular deg/s^2, again the slower group sets the
//! pace) the move follows the same straight line with a trapezoidal speed profile: it speeds
//! up at the limit, cruises at the speed limit, and slows down at the limit to stop on the
//! target (a triangle when the move is too short to reach the speed limit; without a speed
//! limit it is always a triangle). Frame `k` commands `P(u(k / N))`, where `u` is the profile's
//! distance fraction; the duration is rounded up to whole frames by slowing the whole profile
//! down a little, so neither limit is exceeded.
//!
//! Before a move starts, [`Segment::check_path`] runs a caller-supplied check (the IK) along
//! the path. Checked poses, with `S` = path length / (0.5 mm or 0.25 deg, whichever needs more
//! samples) and at most [`MAX_PATH_CHECKS`] checks in total:
//! - if the move has at most [`MAX_PATH_CHECKS`] frames: every pose the move will command,
//!   exactly as it will command it, and, when the frames are further apart than the sample
//!   spacing, evenly spaced poses between them (as many as fit in the budget), because the
//!   servos sweep through those on the way. Those between two frames are stepped: one step is
//!   `(current - previous) / sub` per coordinate, and each pose is the one before plus a step
//!   (six additions instead of a fresh interpolation: this is most of a jump's path check
//!   after its IK solutions). The additions round, so a stepped pose may be off the evenly
//!   spaced one by up to half a unit in the last place of its coordinate per step: with at
//!   most [`MAX_PATH_CHECKS`] steps, positions below 256 mm and angles below 4 rad, under
//!   0.008 mm and 0.007 degree (a sixtieth and a thirtieth of the spacing); the frame poses
//!   themselves are exact;
//! - otherwise (slow moves, frames closer than the spacing): `min(S, MAX_PATH_CHECKS)` evenly
//!   spaced poses. A pose between two checks that still fails is caught by the controller
//!   when its frame comes (it holds the last good pose and stops).
//!
//! The cost of a check is therefore bounded by [`MAX_PATH_CHECKS`] IK solutions per command.
//!
//! A move that starts while the platform moves, with an acceleration limit set, is a
//! [`blend::Blend`] instead: from the pose and velocity the motion in progress has at a chosen
//! frame, into the straight line to the target, within the acceleration limits at every frame
//! (see that module). [`Plan`] is either; [`Motion`] runs one and can hold the next, queued to
//! start at a given frame (the hand-over).

use kinematics_core::{Math, Pose};

pub mod blend;

use self::blend::{Blend, BlendCheckpoints, CheckRule};

/// Largest spacing between path checks along the linear coordinates, mm.
pub const PATH_STEP_MM: f32 = 0.5;
/// Largest spacing between path checks along the angular coordinates, degrees.
pub const PATH_STEP_DEG: f32 = 0.25;
/// Most poses checked for one move (bounds the time a command takes).
pub const MAX_PATH_CHECKS: u32 = 1024;
/// Most frames one move may take (2^24, about 14 h at 333 Hz; keeps `k / N` exact in f32).
pub const MAX_FRAMES: u32 = 1 << 24;

/// Relative allowance when rounding a duration up to whole frames.
const FRAME_ROUNDING_ALLOWANCE: f32 = 1e-5;

/// Speed and acceleration limits; 0 (or anything not positive) means no limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedLimits {
    /// Linear speed of the platform centre, mm/s.
    pub mm_per_s: f32,
    /// Angular speed (Euclidean norm of the Euler angle rates), deg/s.
    pub deg_per_s: f32,
    /// Linear acceleration along the path, mm/s^2.
    pub mm_per_s2: f32,
    /// Angular acceleration along the path, deg/s^2.
    pub deg_per_s2: f32,
}

impl SpeedLimits {
    /// Speed limits only, no acceleration limit.
    pub const fn speeds(mm_per_s: f32, deg_per_s: f32) -> SpeedLimits {
        SpeedLimits {
            mm_per_s,
            deg_per_s,
            mm_per_s2: 0.0,
            deg_per_s2: 0.0,
        }
    }
}

/// Euclidean distance between the positions of two poses, mm.
pub fn linear_distance_mm(a: &Pose, b: &Pose) -> f32 {
    let (dx, dy, dz) = (b.x_mm - a.x_mm, b.y_mm - a.y_mm, b.z_mm - a.z_mm);
    sqrt(dx * dx + dy * dy + dz * dz)
}

/// Euclidean distance between the Euler angles of two poses, degrees.
pub fn angular_distance_deg(a: &Pose, b: &Pose) -> f32 {
    let (dr, dp, dy) = (
        b.roll_rad - a.roll_rad,
        b.pitch_rad - a.pitch_rad,
        b.yaw_rad - a.yaw_rad,
    );
    sqrt(dr * dr + dp * dp + dy * dy).to_degrees()
}

/// `sqrt(x)` correctly rounded (IEEE 754's square root, as `libm::sqrtf` gives it), in
/// integers for a positive normal `x`: its 24-bit mantissa, shifted so the exponent is even,
/// into `M` in `[2^46, 2^48)`, whose integer root `q` (from the IK's fixed-point root, within 1,
/// made exact with two squares) has the result's 24 bits; it rounds up when `M - q^2 > q`
/// (then `sqrt(M) > q + 1/2`, as `(q + 1/2)^2 = q^2 + q + 1/4`; never a tie). About a
/// third of `libm`'s cost on the M0+ (its 64-bit products are library calls). Zero,
/// subnormal, negative and non-finite `x` go to `libm`.
fn sqrt(x: f32) -> f32 {
    let bits = x.to_bits();
    let biased = bits >> 23; // sign and exponent
    if biased == 0 || biased >= 0xff {
        return libm::sqrtf(x);
    }
    let mantissa = u64::from((bits & 0x7f_ffff) | 0x80_0000);
    // x = mantissa 2^(biased - 150); M = mantissa 2^shift with biased - 150 - shift even.
    let shift: i32 = if biased % 2 == 0 { 24 } else { 23 };
    let m = mantissa << shift;
    // The root of M (below 2^24), exact: within 1 of the fixed-point root.
    let mut q = kinematics_core::fixed::sqrt::sqrt(m);
    if square(q) > m {
        q -= 1;
    } else if square(q + 1) <= m {
        q += 1;
    }
    let up = m - square(q) > u64::from(q);
    // sqrt(x) = q 2^((biased - 150 - shift) / 2); q + up in [2^23, 2^24] (2^24 carries into
    // the exponent, as it should).
    let exponent = (biased as i32 - 150 - shift) / 2 + 150; // (an even count halved)
    f32::from_bits(((exponent as u32) << 23) + (q + u32::from(up)) - 0x80_0000)
}

/// `q^2` for `q < 2^25` from 32-bit products (a 64-bit product is a library call on the M0+).
fn square(q: u32) -> u64 {
    let (high, low) = (q >> 16, q & 0xffff);
    (u64::from(high * high) << 32) + (u64::from(2 * high * low) << 16) + u64::from(low * low)
}

/// How many evenly spaced samples keep checks within [`PATH_STEP_MM`] and [`PATH_STEP_DEG`]
/// along a path of these distances (mm, degrees): `ceil(max(mm / 0.5, deg / 0.25))`, at
/// least 1 and at most [`MAX_FRAMES`] (a NaN distance is ignored, as `f32::max` does; both:
/// 1). In integers, each distance on its own (`ceil` and the bounds keep the order, so the
/// larger count is the larger distance's); the divisions by 0.5 and 0.25 are exact.
fn spacing_samples(linear_mm: f32, angular_deg: f32) -> u32 {
    const _: () = assert!(PATH_STEP_MM == 0.5 && PATH_STEP_DEG == 0.25);
    samples_of(linear_mm, 1).max(samples_of(angular_deg, 2))
}

/// `ceil(x 2^k)` within `1..=MAX_FRAMES` (1 for NaN, zero and negative `x`), on the bits.
fn samples_of(x: f32, k: u32) -> u32 {
    let bits = x.to_bits();
    if bits & 0x8000_0000 != 0 || bits > 0x7f80_0000 {
        return 1; // negative or NaN
    }
    // x 2^k = mantissa 2^(exponent - 23), exponent unbiased; zero and subnormals are below 1.
    let exponent = (bits >> 23) as i32 - 127 + k as i32;
    if exponent < 0 || bits >> 23 == 0 {
        return 1; // below 1 (ceil: 1 unless zero, which is 1 too)
    }
    if exponent >= 24 {
        return MAX_FRAMES; // at least 2^24 (or infinite)
    }
    let mantissa = (bits & 0x7f_ffff) | 0x80_0000;
    let cut = 23 - exponent as u32;
    let whole = mantissa >> cut;
    let ceiling = whole + u32::from(mantissa & ((1 << cut) - 1) != 0);
    ceiling.min(MAX_FRAMES)
}

/// The pose a fraction `t` of the way from `a` to `b` (all six coordinates linearly).
pub fn lerp(a: &Pose, b: &Pose, t: f32) -> Pose {
    let (va, vb) = (a.to_array(), b.to_array());
    Pose::from_array(core::array::from_fn(|i| va[i] + (vb[i] - va[i]) * t))
}

/// Where along a path a check failed, and why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathError<E> {
    /// Fraction of the path (0..=1) at the failing pose.
    pub fraction: f32,
    /// The pose that failed.
    pub pose: Pose,
    /// What the check said.
    pub error: E,
}

/// One planned straight move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    start: Pose,
    target: Pose,
    frames: u32,
    /// The fraction of the move's time spent speeding up (and as much slowing down): 0 for
    /// constant speed, up to 1/2 (a triangle).
    ramp: f32,
    /// How many evenly spaced samples keep path checks within [`PATH_STEP_MM`] and
    /// [`PATH_STEP_DEG`] (from the distances, computed once, when planned).
    samples: u32,
}

/// Whether every position moves by less than 0.25 mm and every angle by less than 2^-9 rad
/// (0.11 degree): then the path check's spacing needs one sample, as [`spacing_samples`] would
/// find: the linear distance is below `sqrt(3) / 4` = 0.433 mm (within f32 rounding, far
/// from 0.5), the angular one below `sqrt(3) 2^-9` rad = 0.194 degree (far from 0.25). Six
/// differences, each compared on its bits (stopping at the first that is not small), instead
/// of two sums of squares and their square roots: what a host streaming `pose` lines sends.
fn small_step(start: &Pose, target: &Pose) -> bool {
    const QUARTER: u32 = 0x3e80_0000; // 0.25
    const TWO_TO_MINUS_9: u32 = 0x3b00_0000;
    let (a, b) = (start.to_array(), target.to_array());
    // |d| < bound on the magnitude's bits (NaN's are above every bound).
    let small = |i: usize, bound: u32| (b[i] - a[i]).to_bits() & 0x7fff_ffff < bound;
    (0..3).all(|i| small(i, QUARTER)) && (3..6).all(|i| small(i, TWO_TO_MINUS_9))
}

/// `x > 0.0` on the bits (a float comparison is a library call on the RP2040): positive and
/// not NaN.
fn positive(x: f32) -> bool {
    let bits = x.to_bits() as i32;
    bits > 0 && bits <= 0x7f80_0000
}

/// The smallest ramp fraction treated as one (below, the profile is constant speed).
const MIN_RAMP: f32 = 1e-6;

impl Segment {
    /// Plans a move at the given limits for a frame rate (Hz, > 0).
    pub fn plan(start: Pose, target: Pose, limits: SpeedLimits, frame_hz: f32) -> Segment {
        if !(positive(limits.mm_per_s)
            || positive(limits.deg_per_s)
            || positive(limits.mm_per_s2)
            || positive(limits.deg_per_s2))
        {
            // No limit: a jump (as below: infinite speed and acceleration, zero duration); its
            // distances matter only for the path check's spacing, and not at all for a small
            // step (one sample, see `small_step`).
            let samples = if small_step(&start, &target) {
                1
            } else {
                spacing_samples(
                    linear_distance_mm(&start, &target),
                    angular_distance_deg(&start, &target),
                )
            };
            return Segment {
                start,
                target,
                frames: 1,
                ramp: 0.0,
                samples,
            };
        }
        // Both distances once: the speeds' fractions below and the path check's spacing
        // ([`Segment::checkpoints`]) need them (square roots in software on the chip).
        let linear_mm = linear_distance_mm(&start, &target);
        let angular_deg = angular_distance_deg(&start, &target);
        let samples = spacing_samples(linear_mm, angular_deg);
        // In path fraction u (0..=1) per second: the tighter group's speed and acceleration
        // (infinite where no limit applies).
        let fraction_per = |limit: f32, distance: f32| {
            if limit > 0.0 && distance > 0.0 {
                limit / distance
            } else {
                f32::INFINITY
            }
        };
        let speed = fraction_per(limits.mm_per_s, linear_mm)
            .min(fraction_per(limits.deg_per_s, angular_deg));
        let accel = fraction_per(limits.mm_per_s2, linear_mm)
            .min(fraction_per(limits.deg_per_s2, angular_deg));
        // Duration and ramp time: constant speed, a trapezoid, or a triangle.
        let (duration_s, ramp_s) = if accel.is_infinite() {
            (if speed.is_finite() { 1.0 / speed } else { 0.0 }, 0.0)
        } else if speed.is_finite() && speed * speed / accel < 1.0 {
            (1.0 / speed + speed / accel, speed / accel)
        } else {
            let half = libm::sqrtf(1.0 / accel);
            (2.0 * half, half)
        };
        // Rounding up to whole frames keeps both speeds within their limits. The small
        // relative allowance absorbs f32 rounding (6 deg -> rad -> deg is 6.0000005 deg), so
        // a move that needs exactly N frames does not take N + 1; it can exceed a limit by
        // at most 0.001 %.
        let frames = libm::ceilf(duration_s * frame_hz * (1.0 - FRAME_ROUNDING_ALLOWANCE));
        // NaN (never expected: poses are finite) falls back to a single frame.
        let frames = if frames >= MAX_FRAMES as f32 {
            MAX_FRAMES
        } else if frames >= 1.0 {
            frames as u32
        } else {
            1
        };
        let ramp = if duration_s > 0.0 {
            (ramp_s / duration_s).clamp(0.0, 0.5)
        } else {
            0.0
        };
        Segment {
            start,
            target,
            frames,
            ramp: if ramp < MIN_RAMP { 0.0 } else { ramp },
            samples,
        }
    }

    /// Where the move starts.
    pub fn start(&self) -> &Pose {
        &self.start
    }

    /// Where the move ends.
    pub fn target(&self) -> &Pose {
        &self.target
    }

    /// Frames the move takes (at least 1).
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The pose commanded at frame `k` (`0` = start, `frames` and beyond = target exactly).
    pub fn pose_at(&self, k: u32) -> Pose {
        if k >= self.frames {
            self.target
        } else {
            let time = k as f32 / self.frames as f32;
            let fraction = if self.ramp == 0.0 {
                time
            } else {
                trapezoid(time, self.ramp)
            };
            lerp(&self.start, &self.target, fraction)
        }
    }

    /// The velocity at frame `k` (mm and rad per frame, the profile's own, not a difference of
    /// frames; zero from `frames` on), where a blend that takes over at that frame starts.
    pub fn rate_at(&self, k: u32) -> [f32; 6] {
        if k >= self.frames {
            return [0.0; 6];
        }
        let n = self.frames as f32;
        let time = k as f32 / n;
        // d fraction / d time fraction, then per frame.
        let slope = if self.ramp == 0.0 {
            1.0
        } else {
            let peak = 1.0 / (1.0 - self.ramp);
            let accel = peak / self.ramp;
            if time < self.ramp {
                accel * time
            } else if time <= 1.0 - self.ramp {
                peak
            } else {
                accel * (1.0 - time)
            }
        } / n;
        let (a, b) = (self.start.to_array(), self.target.to_array());
        core::array::from_fn(|i| (b[i] - a[i]) * slope)
    }

    /// The poses a path check visits (see the module docs for which), in order. The start
    /// pose is not among them (it is where the platform already is).
    pub fn checkpoints(&self) -> Checkpoints {
        let n = self.frames;
        let samples = self.samples;
        let walk = if n <= MAX_PATH_CHECKS {
            // Every commanded pose, plus `sub - 1` poses inside each frame step.
            let sub = if samples > n {
                samples.div_ceil(n).min(MAX_PATH_CHECKS / n).max(1)
            } else {
                1
            };
            Walk::EveryFrame {
                sub,
                k: 1,
                i: 1,
                previous: self.start,
                current: self.pose_at(1),
                step: [0.0; 6],
            }
        } else {
            Walk::Evenly {
                m: samples.min(MAX_PATH_CHECKS),
                j: 1,
            }
        };
        Checkpoints {
            segment: *self,
            walk,
        }
    }

    /// Runs `check` on the [`Segment::checkpoints`], stopping at the first failure.
    pub fn check_path<E>(
        &self,
        mut check: impl FnMut(&Pose) -> Result<(), E>,
    ) -> Result<(), PathError<E>> {
        for (pose, fraction) in self.checkpoints() {
            check(&pose).map_err(|error| PathError {
                fraction,
                pose,
                error,
            })?;
        }
        Ok(())
    }
}

/// The distance fraction at time fraction `t` (0..=1) of a trapezoidal speed profile that
/// spends the fraction `ramp` (0 < ramp <= 1/2) of its time speeding up and as much slowing
/// down: peak speed `1 / (1 - ramp)`, acceleration `peak / ramp`, both per unit time.
fn trapezoid(t: f32, ramp: f32) -> f32 {
    let peak = 1.0 / (1.0 - ramp);
    let accel = peak / ramp;
    if t < ramp {
        0.5 * accel * t * t
    } else if t <= 1.0 - ramp {
        0.5 * peak * ramp + peak * (t - ramp)
    } else {
        let left = 1.0 - t;
        1.0 - 0.5 * accel * left * left
    }
}

/// The poses a path check visits, `(pose, fraction of the path)` in order: an iterator, so a
/// check can run a few poses at a time (see [`Segment::checkpoints`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Checkpoints {
    segment: Segment,
    walk: Walk,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Walk {
    /// Every commanded pose `k` of `n`, with `sub - 1` poses before it inside its frame step,
    /// stepped from the frame before (`previous`: that frame's pose, then the last pose
    /// stepped to) by `step`.
    EveryFrame {
        sub: u32,
        k: u32,
        i: u32,
        previous: Pose,
        current: Pose,
        step: [f32; 6],
    },
    /// `m` evenly spaced poses, the last the target.
    Evenly { m: u32, j: u32 },
}

impl Checkpoints {
    /// How many poses the whole walk visits (from its start), without walking it.
    pub fn total(&self) -> u32 {
        match self.walk {
            Walk::EveryFrame { sub, .. } => self.segment.frames.saturating_mul(sub),
            Walk::Evenly { m, .. } => m,
        }
    }
}

impl Checkpoints {
    /// The next checkpoint and where along the path it lies ([`Fraction`], computed only if
    /// asked: a path check needs it only where it fails, or with servo speed ratings).
    pub fn next_checkpoint(&mut self) -> Option<(Pose, Fraction)> {
        let n = self.segment.frames;
        match &mut self.walk {
            Walk::EveryFrame {
                sub,
                k,
                i,
                previous,
                current,
                step,
            } => {
                if *k > n {
                    return None;
                }
                let item = if *i < *sub {
                    // From the frame before, then from the last pose stepped to.
                    let from = previous.to_array();
                    if *i == 1 {
                        let (to, parts) = (current.to_array(), *sub as f32);
                        *step = core::array::from_fn(|c| (to[c] - from[c]) / parts);
                    }
                    let pose = Pose::from_array(core::array::from_fn(|c| from[c] + step[c]));
                    *previous = pose;
                    (
                        pose,
                        Fraction::Within {
                            k: *k,
                            i: *i,
                            sub: *sub,
                            n,
                        },
                    )
                } else {
                    (*current, Fraction::Of { j: *k, m: n })
                };
                *i += 1;
                if *i > *sub {
                    *i = 1;
                    *k += 1;
                    *previous = *current;
                    if *k <= n {
                        *current = self.segment.pose_at(*k);
                    }
                }
                Some(item)
            }
            Walk::Evenly { m, j } => {
                if *j > *m {
                    return None;
                }
                let fraction = Fraction::Of { j: *j, m: *m };
                let pose = if *j == *m {
                    self.segment.target
                } else {
                    lerp(&self.segment.start, &self.segment.target, fraction.get())
                };
                *j += 1;
                Some((pose, fraction))
            }
        }
    }
}

impl Iterator for Checkpoints {
    type Item = (Pose, f32);

    fn next(&mut self) -> Option<(Pose, f32)> {
        self.next_checkpoint().map(|(pose, f)| (pose, f.get()))
    }
}

/// Where along its path a checkpoint lies (0..=1), as [`Checkpoints::next_checkpoint`] gives
/// it: the numbers it is computed from, so that only a check that needs it pays for the
/// division (float divisions are library calls on the RP2040).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fraction {
    /// The `i`-th of the `sub - 1` poses inside frame step `k` of `n`: `((k - 1) + i / sub) / n`.
    Within {
        /// The frame step (1-based).
        k: u32,
        /// The pose inside it (1-based).
        i: u32,
        /// Its parts.
        sub: u32,
        /// The frames.
        n: u32,
    },
    /// `j / m` (frame `j` of `m`, or the `j`-th of `m` evenly spaced poses).
    Of {
        /// Which (1-based).
        j: u32,
        /// Of how many.
        m: u32,
    },
    /// Computed already (a blend's).
    Value(f32),
}

impl Fraction {
    /// The fraction, in `f32`.
    pub fn get(self) -> f32 {
        match self {
            Fraction::Within { k, i, sub, n } => {
                let t = i as f32 / sub as f32;
                ((k - 1) as f32 + t) / n as f32
            }
            Fraction::Of { j, m } => j as f32 / m as f32,
            Fraction::Value(v) => v,
        }
    }
}

/// The rule a blend's path check follows: the straight moves' spacing and budget.
pub const CHECK_RULE: CheckRule = CheckRule {
    step_mm: PATH_STEP_MM,
    step_deg: PATH_STEP_DEG,
    max_checks: MAX_PATH_CHECKS,
    max_frames: MAX_FRAMES,
};

impl From<SpeedLimits> for blend::Limits {
    fn from(l: SpeedLimits) -> blend::Limits {
        blend::Limits {
            mm_per_s: l.mm_per_s,
            deg_per_s: l.deg_per_s,
            mm_per_s2: l.mm_per_s2,
            deg_per_s2: l.deg_per_s2,
            corner_scale: 1.0,
        }
    }
}

/// A planned move: a straight line from rest, or a blend from a moving state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Plan {
    /// From rest ([`Segment`]).
    Straight(Segment),
    /// From the motion in progress ([`Blend`]).
    Blend(Blend),
}

impl Plan {
    /// The move to `target` from `start` moving at `rate` (mm and rad per frame): a blend
    /// ([`Blend::plan`], square roots by `M`), or the straight move when none is needed.
    pub fn after<M: Math>(
        start: Pose,
        rate: [f32; 6],
        target: Pose,
        limits: SpeedLimits,
        frame_hz: f32,
    ) -> Plan {
        Plan::after_within::<M>(start, rate, target, limits, 1.0, frame_hz)
    }

    /// [`Plan::after`], a blend taking `corner_scale` (0..=1) of the largest velocity at its
    /// corner ([`blend::Limits::corner_scale`]: less to keep the servos' rated speeds).
    pub fn after_within<M: Math>(
        start: Pose,
        rate: [f32; 6],
        target: Pose,
        limits: SpeedLimits,
        corner_scale: f32,
        frame_hz: f32,
    ) -> Plan {
        let blend_limits = blend::Limits {
            corner_scale,
            ..limits.into()
        };
        match Blend::plan::<M>(start, rate, target, blend_limits, frame_hz, CHECK_RULE) {
            Some(blend) => Plan::Blend(blend),
            None => Plan::Straight(Segment::plan(start, target, limits, frame_hz)),
        }
    }

    /// The fastest it goes, per frame: the largest speed of the linear group (mm) and of the
    /// angular group (rad) along the way.
    pub fn fastest_per_frame(&self) -> [f32; 2] {
        match self {
            Plan::Straight(s) => {
                let a = (*s.start()).to_array();
                let b = (*s.target()).to_array();
                let norm = |r: core::ops::Range<usize>| {
                    libm::sqrtf(r.map(|i| (b[i] - a[i]) * (b[i] - a[i])).sum())
                };
                // The profile's top speed: 1 / (1 - ramp) of the average.
                let peak = 1.0 / ((1.0 - s.ramp) * s.frames as f32);
                [norm(0..3) * peak, norm(3..6) * peak]
            }
            Plan::Blend(b) => b.fastest_per_frame(),
        }
    }

    /// The fewest frames the motion takes between two of its checkpoints `fractions` apart
    /// (the difference of their fractions, as [`Plan::checkpoints`] gives them): a blend's
    /// fractions, and a straight move's when it checks every frame, are of its frames; a
    /// longer straight move's are of its path, which it covers at most at its top speed.
    pub fn frames_spanned(&self, fractions: f32) -> f32 {
        match self {
            Plan::Straight(s) if s.frames > MAX_PATH_CHECKS => {
                fractions * s.frames as f32 * (1.0 - s.ramp)
            }
            _ => fractions * self.frames() as f32,
        }
    }

    /// True if its path check visits every frame's pose (the frames are at most
    /// [`MAX_PATH_CHECKS`]).
    pub fn checks_every_frame(&self) -> bool {
        self.frames() <= MAX_PATH_CHECKS
    }

    /// Where the move starts.
    pub fn start(&self) -> Pose {
        match self {
            Plan::Straight(s) => *s.start(),
            Plan::Blend(b) => b.start(),
        }
    }

    /// Where the move ends.
    pub fn target(&self) -> &Pose {
        match self {
            Plan::Straight(s) => s.target(),
            Plan::Blend(b) => b.target(),
        }
    }

    /// Frames the move takes (at least 1).
    pub fn frames(&self) -> u32 {
        match self {
            Plan::Straight(s) => s.frames(),
            Plan::Blend(b) => b.frames(),
        }
    }

    /// The pose commanded at frame `k` (`0` = start, `frames` and beyond = target exactly).
    pub fn pose_at(&self, k: u32) -> Pose {
        match self {
            Plan::Straight(s) => s.pose_at(k),
            Plan::Blend(b) => b.pose_at(k),
        }
    }

    /// The velocity at frame `k` (mm and rad per frame; zero from `frames` on).
    pub fn rate_at(&self, k: u32) -> [f32; 6] {
        match self {
            Plan::Straight(s) => s.rate_at(k),
            Plan::Blend(b) => b.rate_at(k),
        }
    }

    /// How many poses its path check visits (without walking them).
    pub fn check_count(&self) -> u32 {
        match self {
            Plan::Straight(s) => s.checkpoints().total(),
            Plan::Blend(b) => b.check_count(),
        }
    }

    /// The poses its path check visits, in order.
    pub fn checkpoints(&self) -> PlanCheckpoints {
        match self {
            Plan::Straight(s) => PlanCheckpoints::Straight(s.checkpoints()),
            Plan::Blend(b) => PlanCheckpoints::Blend(b.checkpoints()),
        }
    }
}

/// The poses a [`Plan`]'s path check visits, `(pose, fraction)` in order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlanCheckpoints {
    /// A straight move's ([`Segment::checkpoints`]).
    Straight(Checkpoints),
    /// A blend's ([`Blend::checkpoints`]).
    Blend(BlendCheckpoints),
}

impl PlanCheckpoints {
    /// How many poses the whole check visits (from its start), without walking it.
    pub fn total(&self) -> u32 {
        match self {
            PlanCheckpoints::Straight(c) => c.total(),
            PlanCheckpoints::Blend(c) => c.total(),
        }
    }
}

impl PlanCheckpoints {
    /// The next checkpoint and where along the path it lies (see
    /// [`Checkpoints::next_checkpoint`]).
    pub fn next_checkpoint(&mut self) -> Option<(Pose, Fraction)> {
        match self {
            PlanCheckpoints::Straight(c) => c.next_checkpoint(),
            PlanCheckpoints::Blend(c) => c.next().map(|(pose, f)| (pose, Fraction::Value(f))),
        }
    }
}

impl Iterator for PlanCheckpoints {
    type Item = (Pose, f32);

    fn next(&mut self) -> Option<(Pose, f32)> {
        match self {
            PlanCheckpoints::Straight(c) => c.next(),
            PlanCheckpoints::Blend(c) => c.next(),
        }
    }
}

/// The pose being commanded and the move in progress, if any (and the next, queued).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    pose: Pose,
    active: Option<(Plan, u32)>,
    /// A move to start after this many more frames of the one in progress (see
    /// [`Motion::start_after`]).
    queued: Option<(Plan, u32)>,
}

impl Motion {
    /// Standing still at `pose`.
    pub const fn new(pose: Pose) -> Motion {
        Motion {
            pose,
            active: None,
            queued: None,
        }
    }

    /// The pose commanded on the last frame.
    pub fn pose(&self) -> &Pose {
        &self.pose
    }

    /// Where the platform is going (the current pose when standing still).
    pub fn target(&self) -> &Pose {
        match (&self.queued, &self.active) {
            (Some((plan, _)), _) | (None, Some((plan, _))) => plan.target(),
            (None, None) => &self.pose,
        }
    }

    /// True while a move is in progress (or queued).
    pub fn is_moving(&self) -> bool {
        self.active.is_some() || self.queued.is_some()
    }

    /// `(frames done, frames total)` of the move in progress.
    pub fn progress(&self) -> Option<(u32, u32)> {
        self.active.map(|(plan, done)| (done, plan.frames()))
    }

    /// Starts a move (planned from the current pose), replacing any move in progress.
    pub fn start(&mut self, segment: Segment) {
        self.active = Some((Plan::Straight(segment), 0));
        self.queued = None;
    }

    /// Queues `plan` to take over after `frames` more frames of the motion in progress (0: from
    /// the next frame on); it must start where and how fast [`Motion::state_after`]`(frames)`
    /// says the motion will be then. Replaces any move queued before, so `frames` must be at
    /// most [`Motion::queued_after`] (else the frames between would not be the ones planned
    /// from).
    pub fn start_after(&mut self, plan: Plan, frames: u32) {
        self.queued = Some((plan, frames));
    }

    /// The frames until a queued move takes over, if one is queued.
    pub fn queued_after(&self) -> Option<u32> {
        self.queued.map(|(_, wait)| wait)
    }

    /// The pose and velocity (mm and rad per frame) `frames` frames from now, if nothing else
    /// changes: what a move taking over then starts from.
    pub fn state_after(&self, frames: u32) -> (Pose, [f32; 6]) {
        if let Some((plan, wait)) = &self.queued {
            if frames >= *wait {
                let k = frames - wait;
                return (plan.pose_at(k), plan.rate_at(k));
            }
        }
        match &self.active {
            Some((plan, done)) => {
                let k = done.saturating_add(frames);
                (plan.pose_at(k), plan.rate_at(k))
            }
            None => (self.pose, [0.0; 6]),
        }
    }

    /// Freezes at the current pose.
    pub fn stop(&mut self) {
        self.active = None;
        self.queued = None;
    }

    /// The pose for the next frame (the current pose when standing still). Nothing changes
    /// until [`Motion::commit`].
    pub fn next_pose(&self) -> Pose {
        match (&self.queued, &self.active) {
            (Some((plan, 0)), _) => plan.pose_at(1),
            (_, Some((plan, done))) => plan.pose_at(done + 1),
            (_, None) => self.pose,
        }
    }

    /// Makes the pose from [`Motion::next_pose`] current; the move ends on its last frame (a
    /// queued move takes over when its wait is over).
    pub fn commit(&mut self) {
        let next = self.next_pose();
        self.pose = next;
        match &mut self.queued {
            Some((plan, 0)) => {
                self.active = Some((*plan, 0));
                self.queued = None;
            }
            Some((_, wait)) => *wait -= 1,
            None => {}
        }
        if let Some((plan, done)) = &mut self.active {
            *done += 1;
            if *done >= plan.frames() {
                self.active = None;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const OFF: SpeedLimits = SpeedLimits::speeds(0.0, 0.0);

    fn limits(mm_per_s: f32, deg_per_s: f32) -> SpeedLimits {
        SpeedLimits::speeds(mm_per_s, deg_per_s)
    }

    #[test]
    fn with_acceleration_limits_the_speed_ramps_up_and_down_within_them() {
        let a = Pose::from_degrees(1.0, -2.0, 3.0, 0.5, 1.0, -1.5);
        for (b, l) in [
            // A trapezoid: 40 mm at 50 mm/s, 200 mm/s^2 (0.25 s ramps, 0.55 s cruise).
            (
                Pose::from_degrees(41.0, -2.0, 3.0, 0.5, 1.0, -1.5),
                SpeedLimits {
                    mm_per_s: 50.0,
                    deg_per_s: 0.0,
                    mm_per_s2: 200.0,
                    deg_per_s2: 0.0,
                },
            ),
            // A triangle: 2 mm never reaches 50 mm/s at 200 mm/s^2.
            (
                Pose::from_degrees(3.0, -2.0, 3.0, 0.5, 1.0, -1.5),
                SpeedLimits {
                    mm_per_s: 50.0,
                    deg_per_s: 0.0,
                    mm_per_s2: 200.0,
                    deg_per_s2: 0.0,
                },
            ),
            // Both groups limited, the angular one slower.
            (
                Pose::from_degrees(-7.3, 4.1, -9.9, 13.3, -12.2, 17.7),
                SpeedLimits {
                    mm_per_s: 100.0,
                    deg_per_s: 30.0,
                    mm_per_s2: 500.0,
                    deg_per_s2: 60.0,
                },
            ),
        ] {
            for hz in [50.0, 333.0] {
                let s = Segment::plan(a, b, l, hz);
                let dt = 1.0 / hz;
                let poses: std::vec::Vec<Pose> =
                    (0..=s.frames() + 1).map(|k| s.pose_at(k)).collect();
                let (mut v_lin, mut v_ang) = (0.0f32, 0.0f32);
                for w in poses.windows(2) {
                    let nl = linear_distance_mm(&w[0], &w[1]) / dt;
                    let na = angular_distance_deg(&w[0], &w[1]) / dt;
                    assert!(nl <= l.mm_per_s * 1.0001 || l.mm_per_s == 0.0, "{nl} mm/s");
                    assert!(
                        na <= l.deg_per_s * 1.0001 || l.deg_per_s == 0.0,
                        "{na} deg/s"
                    );
                    // Speed changes by at most the limit each frame (a frame's speed is the
                    // average over it, so allow one frame of the ramp's curvature).
                    assert!(
                        (nl - v_lin).abs() <= l.mm_per_s2 * dt * 1.01 + 1e-3,
                        "{nl} after {v_lin}"
                    );
                    if l.deg_per_s2 > 0.0 {
                        assert!((na - v_ang).abs() <= l.deg_per_s2 * dt * 1.01 + 1e-3);
                    }
                    v_lin = nl;
                    v_ang = na;
                }
                assert_eq!(v_lin, 0.0, "at rest after the last frame");
                assert_eq!(s.pose_at(s.frames()), b);
                // Along the straight line, and every commanded pose among the checkpoints.
                let checked: std::vec::Vec<Pose> = s.checkpoints().map(|(p, _)| p).collect();
                for k in 1..=s.frames() {
                    assert!(checked.contains(&s.pose_at(k)), "frame {k}");
                }
            }
        }
    }

    #[test]
    fn an_acceleration_limit_sets_the_duration_as_documented() {
        let b = Pose::from_degrees(0.0, 0.0, 40.0, 0.0, 0.0, 0.0);
        let l = SpeedLimits {
            mm_per_s: 50.0,
            deg_per_s: 0.0,
            mm_per_s2: 200.0,
            deg_per_s2: 0.0,
        };
        // 40 / 50 + 50 / 200 = 1.05 s: 53 frames at 50 Hz (52.5 rounded up).
        assert_eq!(Segment::plan(Pose::HOME, b, l, 50.0).frames(), 53);
        // Without a speed limit: a triangle, 2 sqrt(40 / 200) = 0.894 s: 45 frames.
        let tri = SpeedLimits { mm_per_s: 0.0, ..l };
        assert_eq!(Segment::plan(Pose::HOME, b, tri, 50.0).frames(), 45);
    }

    #[test]
    fn duration_follows_the_slower_group() {
        let a = Pose::HOME;
        // 30 mm at 10 mm/s = 3 s; 20 deg at 40 deg/s = 0.5 s -> 3 s = 150 frames at 50 Hz.
        let b = Pose::from_degrees(0.0, 0.0, 30.0, 20.0, 0.0, 0.0);
        assert_eq!(Segment::plan(a, b, limits(10.0, 40.0), 50.0).frames(), 150);
        // 20 deg at 4 deg/s = 5 s is now the slower -> 250 frames.
        assert_eq!(Segment::plan(a, b, limits(10.0, 4.0), 50.0).frames(), 250);
        // Only one limit set: the other group is unconstrained.
        assert_eq!(Segment::plan(a, b, limits(0.0, 4.0), 50.0).frames(), 250);
        assert_eq!(Segment::plan(a, b, limits(10.0, 0.0), 50.0).frames(), 150);
        // 3-4-5 triangle: linear distance is Euclidean.
        let c = Pose::from_degrees(3.0, 4.0, 0.0, 0.0, 0.0, 0.0);
        assert_eq!(Segment::plan(a, c, limits(1.0, 0.0), 100.0).frames(), 500);
    }

    #[test]
    fn speeds_are_never_exceeded_per_frame() {
        let a = Pose::from_degrees(1.0, -2.0, 3.0, 0.5, 1.0, -1.5);
        let b = Pose::from_degrees(-7.3, 4.1, -9.9, 3.3, -2.2, 7.7);
        for hz in [50.0, 60.0, 200.0, 333.0] {
            for (v, w) in [(13.0, 17.0), (100.0, 5.0), (2.5, 300.0)] {
                let s = Segment::plan(a, b, limits(v, w), hz);
                for k in 1..=s.frames() {
                    let (p, q) = (s.pose_at(k - 1), s.pose_at(k));
                    assert!(linear_distance_mm(&p, &q) <= v / hz * 1.0001);
                    assert!(angular_distance_deg(&p, &q) <= w / hz * 1.0001);
                }
                // ... and the move is not slower than it has to be (within one frame).
                let needed = (linear_distance_mm(&a, &b) / v).max(angular_distance_deg(&a, &b) / w);
                assert!((s.frames() as f32 / hz - needed) < 1.0 / hz + 1e-4);
            }
        }
    }

    #[test]
    fn speed_off_is_a_jump() {
        let b = Pose::from_degrees(5.0, 0.0, 0.0, 0.0, 0.0, 10.0);
        let s = Segment::plan(Pose::HOME, b, OFF, 50.0);
        assert_eq!(s.frames(), 1);
        let mut m = Motion::new(Pose::HOME);
        m.start(s);
        assert_eq!(m.next_pose(), b);
        m.commit();
        assert_eq!(*m.pose(), b);
        assert!(!m.is_moving());
    }

    #[test]
    fn zero_length_move_takes_one_frame() {
        let s = Segment::plan(Pose::HOME, Pose::HOME, limits(10.0, 10.0), 50.0);
        assert_eq!(s.frames(), 1);
    }

    #[test]
    fn interpolation_is_a_straight_line_ending_exactly_on_target() {
        let a = Pose::from_degrees(1.0, 2.0, 3.0, 4.0, 5.0, 6.0);
        let b = Pose::from_degrees(-3.0, 7.0, 0.5, -2.0, 9.0, 1.0);
        let s = Segment::plan(a, b, limits(7.0, 11.0), 50.0);
        let mut m = Motion::new(a);
        m.start(s);
        let total = s.frames();
        let mut frames = 0;
        while m.is_moving() {
            m.commit();
            frames += 1;
            let t = frames as f32 / total as f32;
            let (va, vb, vp) = (a.to_array(), b.to_array(), m.pose().to_array());
            for i in 0..6 {
                let expected = va[i] + t * (vb[i] - va[i]);
                assert!((vp[i] - expected).abs() < 1e-5, "frame {frames} coord {i}");
            }
        }
        assert_eq!(frames, total);
        assert_eq!(*m.pose(), b);
        // Standing still afterwards.
        m.commit();
        assert_eq!(*m.pose(), b);
    }

    #[test]
    fn stop_freezes_at_the_current_pose() {
        let b = Pose::from_degrees(0.0, 0.0, 10.0, 0.0, 0.0, 0.0);
        let mut m = Motion::new(Pose::HOME);
        m.start(Segment::plan(Pose::HOME, b, limits(10.0, 0.0), 50.0));
        for _ in 0..10 {
            m.commit();
        }
        assert_eq!(m.progress(), Some((10, 50)));
        let here = *m.pose();
        m.stop();
        assert_eq!(*m.target(), here);
        m.commit();
        assert_eq!(*m.pose(), here);
        assert!((here.z_mm - 2.0).abs() < 1e-5);
    }

    fn checked_poses(s: &Segment) -> std::vec::Vec<(Pose, f32)> {
        let mut seen = std::vec::Vec::new();
        s.check_path(|p| {
            seen.push(*p);
            Ok::<(), ()>(())
        })
        .unwrap();
        // Recover the fractions by failing at each index in turn would be slow; compute them
        // from the z coordinate instead (all test paths move along z).
        let dz = s.target().z_mm - s.start().z_mm;
        seen.into_iter()
            .map(|p| (p, (p.z_mm - s.start().z_mm) / dz))
            .collect()
    }

    #[test]
    fn path_check_covers_every_commanded_pose_of_a_short_move() {
        let b = Pose::from_degrees(0.0, 0.0, 2.0, 0.0, 0.0, 0.0);
        let s = Segment::plan(Pose::HOME, b, limits(20.0, 0.0), 50.0); // 5 frames of 0.4 mm
        assert_eq!(s.frames(), 5);
        let seen: std::vec::Vec<Pose> = checked_poses(&s).into_iter().map(|(p, _)| p).collect();
        let commanded: std::vec::Vec<Pose> = (1..=5).map(|k| s.pose_at(k)).collect();
        assert_eq!(seen, commanded);
    }

    #[test]
    fn path_check_of_a_jump_is_dense() {
        let b = Pose::from_degrees(0.0, 0.0, 10.0, 0.0, 0.0, 0.0);
        let s = Segment::plan(Pose::HOME, b, OFF, 50.0);
        let seen = checked_poses(&s);
        assert_eq!(seen.len(), 20); // 10 mm / 0.5 mm
        assert_eq!(seen.last().unwrap().0, b);
        let mut last = 0.0;
        for (p, _) in &seen {
            assert!(p.z_mm - last <= PATH_STEP_MM + 1e-4);
            last = p.z_mm;
        }
    }

    #[test]
    fn path_check_budget_is_bounded_and_spacing_kept_when_possible() {
        // Slow: 40 mm at 1 mm/s = 2000 frames > budget -> 80 evenly spaced checks.
        let b = Pose::from_degrees(0.0, 0.0, 40.0, 0.0, 0.0, 0.0);
        let s = Segment::plan(Pose::HOME, b, limits(1.0, 0.0), 50.0);
        assert_eq!(s.frames(), 2000);
        let seen = checked_poses(&s);
        assert_eq!(seen.len(), 80);
        assert_eq!(seen.last().unwrap().0, b);
        // Huge jump: capped at the budget.
        let far = Pose::from_degrees(0.0, 0.0, 4000.0, 0.0, 0.0, 0.0);
        let s = Segment::plan(Pose::HOME, far, OFF, 50.0);
        assert_eq!(checked_poses(&s).len(), MAX_PATH_CHECKS as usize);
        // Fast with few frames: each frame step subdivided, within budget.
        let s = Segment::plan(Pose::HOME, b, limits(400.0, 0.0), 50.0); // 5 frames of 8 mm
        let seen = checked_poses(&s);
        assert_eq!(seen.len(), 80);
        for k in 1..=5 {
            assert!(seen.iter().any(|(p, _)| *p == s.pose_at(k)), "frame {k}");
        }
    }

    /// The poses of the documented rule, by nested loops as the module docs state it.
    fn documented_checkpoints(s: &Segment) -> std::vec::Vec<(Pose, f32)> {
        let n = s.frames();
        let by_mm = linear_distance_mm(s.start(), s.target()) / PATH_STEP_MM;
        let by_deg = angular_distance_deg(s.start(), s.target()) / PATH_STEP_DEG;
        let samples = (libm::ceilf(by_mm.max(by_deg)) as u32).max(1);
        let mut out = std::vec::Vec::new();
        if n <= MAX_PATH_CHECKS {
            let sub = if samples > n {
                samples.div_ceil(n).min(MAX_PATH_CHECKS / n).max(1)
            } else {
                1
            };
            let mut previous = *s.start();
            for k in 1..=n {
                let current = s.pose_at(k);
                // Stepped: each pose the one before plus (current - previous) / sub.
                let (a, b) = (previous.to_array(), current.to_array());
                let step: [f32; 6] = core::array::from_fn(|c| (b[c] - a[c]) / sub as f32);
                let mut at = a;
                for i in 1..sub {
                    let t = i as f32 / sub as f32;
                    for c in 0..6 {
                        at[c] += step[c];
                    }
                    out.push((Pose::from_array(at), ((k - 1) as f32 + t) / n as f32));
                }
                out.push((current, k as f32 / n as f32));
                previous = current;
            }
        } else {
            let m = samples.min(MAX_PATH_CHECKS);
            for j in 1..=m {
                let t = j as f32 / m as f32;
                let pose = if j == m {
                    *s.target()
                } else {
                    lerp(s.start(), s.target(), t)
                };
                out.push((pose, t));
            }
        }
        out
    }

    #[test]
    fn checkpoints_are_the_documented_poses_in_order() {
        let a = Pose::from_degrees(1.0, -2.0, 3.0, 0.5, 1.0, -1.5);
        let cases = [
            (
                Pose::from_degrees(0.0, 0.0, 2.0, 0.0, 0.0, 0.0),
                limits(20.0, 0.0),
            ),
            (Pose::from_degrees(0.0, 0.0, 10.0, 0.0, 0.0, 0.0), OFF),
            (
                Pose::from_degrees(0.0, 0.0, 40.0, 0.0, 0.0, 0.0),
                limits(1.0, 0.0),
            ),
            (
                Pose::from_degrees(0.0, 0.0, 40.0, 0.0, 0.0, 0.0),
                limits(400.0, 0.0),
            ),
            (
                Pose::from_degrees(-7.3, 4.1, -9.9, 3.3, -2.2, 7.7),
                limits(13.0, 17.0),
            ),
            (Pose::from_degrees(0.0, 0.0, 4000.0, 0.0, 0.0, 0.0), OFF),
            (a, limits(5.0, 5.0)),
        ];
        for (b, l) in cases {
            let s = Segment::plan(a, b, l, 50.0);
            let got: std::vec::Vec<(Pose, f32)> = s.checkpoints().collect();
            assert_eq!(got, documented_checkpoints(&s), "{b:?} {l:?}");
            assert!(got.len() <= MAX_PATH_CHECKS as usize);
        }
    }

    #[test]
    fn square_roots_are_libms_bit_for_bit() {
        // libm's sqrtf is correctly rounded: the same bits for every input class, random
        // normal numbers over the whole range, and around squares and midpoints.
        let mut next = crate::test_support::xorshift(0x9e37_79b9_u32);
        let mut inputs = std::vec![
            0.0,
            -0.0,
            1.0,
            2.0,
            4.0,
            0.25,
            f32::MIN_POSITIVE,
            f32::MAX,
            f32::INFINITY,
            f32::NAN,
            -1.0,
            1e-40,
        ];
        for _ in 0..1_000_000 {
            inputs.push(f32::from_bits(next() & 0x7fff_ffff));
        }
        for q in (1u32..20_000).chain((0x7f_0000..0x80_0000).step_by(997)) {
            let square = (q as f32) * (q as f32);
            for d in -2i32..=2 {
                inputs.push(f32::from_bits(square.to_bits().wrapping_add_signed(d)));
            }
        }
        for x in inputs {
            let (got, expected) = (sqrt(x), libm::sqrtf(x));
            assert!(
                got.to_bits() == expected.to_bits() || (got.is_nan() && expected.is_nan()),
                "sqrt({x:e}) = {got:e}, libm {expected:e}"
            );
        }
    }

    #[test]
    fn spacing_samples_are_the_documented_ceiling() {
        // Against the float formula, over random distances of every size.
        let mut next = crate::test_support::xorshift(0x2545_f491_u32);
        let formula = |mm: f32, deg: f32| {
            let n = libm::ceilf((mm / PATH_STEP_MM).max(deg / PATH_STEP_DEG));
            if n >= MAX_FRAMES as f32 {
                MAX_FRAMES
            } else if n >= 1.0 {
                n as u32
            } else {
                1
            }
        };
        let special = [
            0.0, -0.0, 0.5, 0.25, 1.0, 1e-30, 8388608.0, 4194304.0, 4194303.5,
        ];
        let mut values: std::vec::Vec<f32> = special.into();
        values.extend([f32::NAN, f32::INFINITY, -3.0, 1e-40, 16777215.0, 16777216.0]);
        for _ in 0..200_000 {
            // Mostly 0..2^25, some anywhere.
            let bits = next();
            values.push(if bits & 1 == 0 {
                (bits >> 7) as f32 / (1 << (bits % 24)) as f32
            } else {
                f32::from_bits(bits)
            });
        }
        for pair in values.windows(2) {
            let (mm, deg) = (pair[0], pair[1]);
            assert_eq!(spacing_samples(mm, deg), formula(mm, deg), "{mm:e} {deg:e}");
        }
    }

    #[test]
    fn a_small_step_needs_one_sample_as_the_distances_say() {
        // Random jumps around the small step's bounds (each coordinate's move up to twice its
        // bound, from random poses): the shortcut never disagrees with the distances.
        let mut xorshift = crate::test_support::xorshift(0x0bad_5eed);
        let mut next = move || f64::from(xorshift()) / f64::from(u32::MAX);
        let mut small = 0;
        for _ in 0..200_000 {
            let a: [f32; 6] = core::array::from_fn(|i| {
                let range = if i < 3 { 100.0 } else { 0.6 };
                ((next() * 2.0 - 1.0) * range) as f32
            });
            let b: [f32; 6] = core::array::from_fn(|i| {
                let bound = if i < 3 { 0.25 } else { 1.0 / 512.0 };
                a[i] + ((next() * 2.0 - 1.0) * 2.0 * bound) as f32
            });
            let (a, b) = (Pose::from_array(a), Pose::from_array(b));
            let samples = spacing_samples(linear_distance_mm(&a, &b), angular_distance_deg(&a, &b));
            if small_step(&a, &b) {
                small += 1;
                assert_eq!(samples, 1, "{a:?} {b:?}");
            }
            assert_eq!(Segment::plan(a, b, OFF, 50.0).samples, samples);
        }
        // Both sides were visited.
        assert!(small > 1_000 && small < 199_000, "{small}");
        // The largest small step of each group, every coordinate at once, is one sample.
        let edge = Pose::from_array([0.2499, -0.2499, 0.2499, 0.00195, -0.00195, 0.00195]);
        assert!(small_step(&Pose::HOME, &edge));
        assert_eq!(Segment::plan(Pose::HOME, edge, OFF, 50.0).samples, 1);
    }

    #[test]
    fn stepped_checkpoints_stay_on_the_straight_line_within_the_documented_rounding() {
        // A long jump: hundreds of stepped poses in one frame step, every coordinate moving.
        let a = Pose {
            x_mm: -100.0,
            y_mm: 80.0,
            z_mm: -30.0,
            roll_rad: 0.3,
            pitch_rad: -0.2,
            yaw_rad: 0.4,
        };
        let b = Pose {
            x_mm: 120.0,
            y_mm: -90.0,
            z_mm: 40.0,
            roll_rad: -0.3,
            pitch_rad: 0.25,
            yaw_rad: -0.5,
        };
        let s = Segment::plan(a, b, OFF, 50.0);
        let seen: std::vec::Vec<(Pose, f32)> = s.checkpoints().collect();
        assert!(seen.len() > 500, "{}", seen.len());
        assert_eq!(seen.last().unwrap().0, b);
        let (va, vb) = (a.to_array(), b.to_array());
        let n = seen.len() as f64;
        for (j, (p, fraction)) in seen.iter().enumerate() {
            // The exact point, in f64.
            let t = (j + 1) as f64 / n;
            assert!((f64::from(*fraction) - t).abs() < 1e-6, "{j}");
            for (c, &v) in p.to_array().iter().enumerate() {
                let exact = f64::from(va[c]) + (f64::from(vb[c]) - f64::from(va[c])) * t;
                let allowed = if c < 3 { 0.008 } else { 0.007f64.to_radians() };
                assert!(
                    (f64::from(v) - exact).abs() <= allowed,
                    "checkpoint {j} coordinate {c}: {v} vs {exact}"
                );
            }
        }
    }

    #[test]
    fn path_check_reports_where_it_failed() {
        let b = Pose::from_degrees(0.0, 0.0, 10.0, 0.0, 0.0, 0.0);
        let s = Segment::plan(Pose::HOME, b, limits(5.0, 0.0), 50.0);
        let err = s
            .check_path(|p| {
                if p.z_mm > 4.0 {
                    Err("too high")
                } else {
                    Ok(())
                }
            })
            .unwrap_err();
        assert_eq!(err.error, "too high");
        assert!(err.pose.z_mm > 4.0 && err.pose.z_mm < 4.0 + 0.5);
        assert!((err.fraction - err.pose.z_mm / 10.0).abs() < 1e-4);
    }
}
