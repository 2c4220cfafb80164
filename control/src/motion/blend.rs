//! Blends: a move that starts while the platform moves, from its pose and velocity, within
//! the acceleration limits at every frame (units: mm and rad, time in frames).
//!
//! A new target `C` that arrives while the platform moves (with an acceleration limit set)
//! does not start from rest: the move starts at a chosen frame (the hand-over, see
//! `controller/moves.rs`) from the pose `p` and velocity `v` the motion in progress has there,
//! in two phases:
//! 1. the blend, `T` frames at constant acceleration: `P(t) = p + v t + (w - v) t^2 / (2 T)`,
//!    velocity turning straight from `v` into `w` (a parabola in pose space), to the corner
//!    `E = p + (v + w) T / 2`;
//! 2. the tail, the straight line from `E` to `C`, with a speed profile that starts at `w`
//!    (which points from `E` to `C`), speeds up to the speed limit (or not), and slows to
//!    rest on `C` at the acceleration limit (a trapezoid or triangle that starts moving).
//!
//! `T` is the time the faster group (linear, angular; Euclidean norms, as in
//! [`super`]) needs to brake to rest at its limit, `max |v_g| / a_g`, so `w = 0` is always a
//! valid choice (brake, then start from rest: a reversal, or a turn of 90 degrees or more). The
//! largest `w = lambda u` along `u = C - p - v T / 2` (so that `C - E` is parallel to `w`) is
//! taken that keeps, for each group, the blend's acceleration `|w_g - v_g| / T` within `a_g`,
//! `|w_g|` within the speed limit, and the tail able to stop on `C` (`|w_g|^2 / (2 a_g)` within
//! its length). A target straight ahead (a jog of repeated `nudge`s) keeps its speed; a gentle
//! turn keeps most of it. A share of it may be taken instead ([`Limits::corner_scale`]: the
//! servos' rated speeds; 0 brakes to rest at the corner): any `lambda` from 0 to the largest
//! keeps every constraint.
//!
//! Both phases are continuous-time curves whose velocity is continuous (at the hand-over, the
//! corner and the end) and whose acceleration stays within each group's limit; frame `k`
//! commands the curve at `k` exactly (no rounding to whole frames: the frame after the end
//! commands `C`). So the change in velocity between two frames (poses differenced per frame)
//! is at most the limit times one frame, through the transition too.
//!
//! The path check visits the poses the blend will command: every frame (and chords between
//! frames further apart than the check spacing, within the budget: [`CheckRule`], which
//! [`super`] gives, its straight moves' rule), or for longer blends, evenly spaced frames (at most the budget,
//! as many as the path's length at that spacing needs).

use kinematics_core::{Math, Pose};

/// The limits a blend keeps (a leaf: [`super`] hands them over; 0 or less: no limit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Linear speed, mm/s.
    pub mm_per_s: f32,
    /// Angular speed, deg/s.
    pub deg_per_s: f32,
    /// Linear acceleration, mm/s^2.
    pub mm_per_s2: f32,
    /// Angular acceleration, deg/s^2.
    pub deg_per_s2: f32,
    /// The share (0..=1) of the largest velocity at the corner that is taken: 1 normally;
    /// less to keep the servos within their rated speeds, 0 to brake to rest at the corner
    /// (see `controller/moves.rs`).
    pub corner_scale: f32,
}

/// How densely a path is checked and how long a move may be (the straight moves' rule, which
/// [`super`] gives).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckRule {
    /// Largest spacing between checks along the linear coordinates, mm.
    pub step_mm: f32,
    /// Largest spacing between checks along the angular coordinates, degrees.
    pub step_deg: f32,
    /// Most poses checked for one move.
    pub max_checks: u32,
    /// Most frames one move may take.
    pub max_frames: u32,
}

/// The pose a fraction `t` of the way from `a` to `b` (a chord between two frames' poses).
fn chord(a: &Pose, b: &Pose, t: f32) -> Pose {
    let (va, vb) = (a.to_array(), b.to_array());
    Pose::from_array(core::array::from_fn(|i| va[i] + (vb[i] - va[i]) * t))
}

/// Six coordinates (mm and rad) or their rates (per frame).
type Six = [f32; 6];

/// The groups: linear (x, y, z, mm) and angular (roll, pitch, yaw, rad).
const GROUPS: [core::ops::Range<usize>; 2] = [0..3, 3..6];

fn dot(a: &Six, b: &Six, g: usize) -> f32 {
    let r = GROUPS[g].clone();
    a[r.clone()].iter().zip(&b[r]).map(|(x, y)| x * y).sum()
}

/// The limits per frame, per group (mm or rad per frame, per frame^2); infinite where off.
#[derive(Debug, Clone, Copy)]
struct FrameLimits {
    speed: [f32; 2],
    accel: [f32; 2],
}

impl FrameLimits {
    fn new(limits: Limits, frame_hz: f32) -> FrameLimits {
        let dt = 1.0 / frame_hz;
        let per = |limit: f32, scale: f32| {
            if limit > 0.0 {
                limit * scale
            } else {
                f32::INFINITY
            }
        };
        FrameLimits {
            speed: [
                per(limits.mm_per_s, dt),
                per(limits.deg_per_s.to_radians(), dt),
            ],
            accel: [
                per(limits.mm_per_s2, dt * dt),
                per(limits.deg_per_s2.to_radians(), dt * dt),
            ],
        }
    }
}

/// A rest-ending speed profile along a straight line, in fractions of its length: starts at
/// speed `f0`, speeds up at `accel` to `peak`, cruises, slows at `accel` to rest on 1.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Tail {
    f0: f32,
    accel: f32,
    peak: f32,
    /// Ends of the speeding-up and the cruise, and the whole duration (frames).
    t1: f32,
    t2: f32,
    end: f32,
}

impl Tail {
    /// The profile from speed `f0` with acceleration `accel` and speed `speed` (fractions per
    /// frame, per frame^2; infinite: no limit).
    fn plan<M: Math>(f0: f32, accel: f32, speed: f32) -> Tail {
        if accel.is_infinite() {
            // No acceleration limit applies to this line: constant speed (or a jump).
            let (peak, end) = if speed.is_finite() {
                (speed, 1.0 / speed)
            } else {
                (f32::INFINITY, 0.0)
            };
            return Tail {
                f0: peak,
                accel,
                peak,
                t1: 0.0,
                t2: end,
                end,
            };
        }
        // The highest speed that still stops on 1: (2 peak^2 - f0^2) / (2 a) = 1.
        let peak = M::sqrt(accel + 0.5 * f0 * f0).min(speed).max(f0);
        let t1 = (peak - f0) / accel;
        let d1 = (peak * peak - f0 * f0) / (2.0 * accel);
        let d3 = peak * peak / (2.0 * accel);
        let cruise = (1.0 - d1 - d3).max(0.0);
        let t2 = t1 + cruise / peak;
        Tail {
            f0,
            accel,
            peak,
            t1,
            t2,
            end: t2 + peak / accel,
        }
    }

    /// Fraction of the line done `s` frames in.
    fn position(&self, s: f32) -> f32 {
        if s >= self.end {
            1.0
        } else if s < self.t1 {
            self.f0 * s + 0.5 * self.accel * s * s
        } else if s < self.t2 {
            let d1 = (self.peak * self.peak - self.f0 * self.f0) / (2.0 * self.accel);
            let d1 = if d1.is_finite() { d1 } else { 0.0 };
            d1 + self.peak * (s - self.t1)
        } else {
            let left = self.end - s;
            1.0 - 0.5 * self.accel * left * left
        }
    }

    /// Speed `s` frames in, fractions per frame.
    fn speed(&self, s: f32) -> f32 {
        if s >= self.end {
            0.0
        } else if s < self.t1 {
            self.f0 + self.accel * s
        } else if s < self.t2 {
            self.peak
        } else {
            self.accel * (self.end - s)
        }
    }
}

/// A planned blend from a moving state into a straight line to the target (see the module
/// docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blend {
    start: Six,
    /// Velocity at the start and at the corner, per frame.
    v: Six,
    w: Six,
    /// The blend phase's length, frames (not whole).
    t_blend: f32,
    corner: Six,
    target: Pose,
    tail: Tail,
    frames: u32,
    /// Checkpoints: frames sampled, and chords per sampled frame.
    samples: u32,
    sub: u32,
}

impl Blend {
    /// Plans the move from `start` moving at `rate` (mm and rad per frame, as
    /// [`super::Segment::rate_at`] gives) to `target` within `limits` at `frame_hz`, checked
    /// by `rule`, square roots by `M`. `None` when no blend is needed: standing still, or no acceleration limit
    /// applies to the motion in progress (then a move from rest, [`super::Segment`], is the
    /// same thing).
    pub fn plan<M: Math>(
        start: Pose,
        rate: [f32; 6],
        target: Pose,
        limits: Limits,
        frame_hz: f32,
        rule: CheckRule,
    ) -> Option<Blend> {
        let l = FrameLimits::new(limits, frame_hz);
        let p = start.to_array();
        let v = rate;
        let c = target.to_array();
        let v_norm = [M::sqrt(dot(&v, &v, 0)), M::sqrt(dot(&v, &v, 1))];
        // The time the faster group needs to brake at its limit.
        let mut t_blend = 0.0f32;
        for (vn, a) in v_norm.iter().zip(l.accel) {
            if a.is_finite() {
                t_blend = t_blend.max(vn / a);
            }
        }
        if !(t_blend > 0.0 && t_blend.is_finite()) {
            return None;
        }
        let u: Six = core::array::from_fn(|i| c[i] - p[i] - v[i] * t_blend * 0.5);
        let u_norm = [M::sqrt(dot(&u, &u, 0)), M::sqrt(dot(&u, &u, 1))];
        // The largest lambda in [0, 1 / T] (w = lambda u) within every group's constraints.
        let mut lambda = 1.0 / t_blend;
        for g in 0..2 {
            let un = u_norm[g];
            if un == 0.0 {
                continue;
            }
            let (uu, uv) = (un * un, dot(&u, &v, g));
            let a = l.accel[g];
            if a.is_finite() {
                // |lambda u - v| <= a T: lambda^2 uu - 2 lambda uv + vv - (a T)^2 <= 0.
                let reach = a * t_blend;
                let vv = v_norm[g] * v_norm[g];
                let disc = (uv * uv - uu * (vv - reach * reach)).max(0.0);
                lambda = lambda.min(((uv + M::sqrt(disc)) / uu).max(0.0));
                // The tail stops on C: lambda^2 |u| / (2 a) + lambda T / 2 <= 1.
                let (c2, c1) = (un / (2.0 * a), 0.5 * t_blend);
                lambda = lambda.min((-c1 + M::sqrt(c1 * c1 + 4.0 * c2)) / (2.0 * c2));
            }
            // |w_g| within the speed limit.
            lambda = lambda.min(l.speed[g] / un);
        }
        // (Any lambda from 0 to the largest keeps every constraint: each holds at both ends
        // of that range and is convex in lambda.)
        let lambda = if lambda.is_finite() {
            lambda.max(0.0) * limits.corner_scale.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let w: Six = core::array::from_fn(|i| lambda * u[i]);
        let corner: Six = core::array::from_fn(|i| p[i] + (v[i] + w[i]) * t_blend * 0.5);
        // C - E = u (1 - lambda T / 2), w = f0 (C - E): the tail's lengths and start speed.
        let shrink = 1.0 - 0.5 * lambda * t_blend;
        let d_norm = [u_norm[0] * shrink, u_norm[1] * shrink];
        let f0 = lambda / shrink;
        // The tail in fractions of its line: the tighter group's limits.
        let (mut accel, mut speed) = (f32::INFINITY, f32::INFINITY);
        for ((dn, a), v) in d_norm.iter().zip(l.accel).zip(l.speed) {
            if *dn > 0.0 {
                accel = accel.min(a / dn);
                speed = speed.min(v / dn);
            }
        }
        let tail = Tail::plan::<M>(f0, accel, speed);
        let total = libm::ceilf(t_blend + tail.end);
        let frames = if total >= rule.max_frames as f32 {
            rule.max_frames
        } else if total >= 1.0 {
            total as u32
        } else {
            1
        };
        // Checkpoints: per group, the fastest a frame can go and the path's length.
        let (mut step, mut length) = (0.0f32, 0.0f32);
        for (g, spacing) in [rule.step_mm, rule.step_deg.to_radians()]
            .into_iter()
            .enumerate()
        {
            let fastest = v_norm[g].max(lambda * u_norm[g]);
            let dn = d_norm[g];
            let tail_fastest = if tail.peak.is_finite() {
                tail.peak * dn
            } else {
                dn
            };
            step = step.max(fastest.max(tail_fastest) / spacing);
            length = length.max((fastest * t_blend + dn) / spacing);
        }
        let (samples, sub) = if frames <= rule.max_checks {
            let sub = libm::ceilf(step).clamp(1.0, (rule.max_checks / frames) as f32);
            (frames, sub as u32)
        } else {
            let m = libm::ceilf(length).clamp(1.0, rule.max_checks as f32);
            (m as u32, 1)
        };
        Some(Blend {
            start: p,
            v,
            w,
            t_blend,
            corner,
            target,
            tail,
            frames,
            samples,
            sub,
        })
    }

    /// Where the blend starts.
    pub fn start(&self) -> Pose {
        Pose::from_array(self.start)
    }

    /// Where it ends.
    pub fn target(&self) -> &Pose {
        &self.target
    }

    /// Frames it takes (at least 1).
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The pose commanded at frame `k` (`0` = start, `frames` and beyond = target exactly).
    pub fn pose_at(&self, k: u32) -> Pose {
        if k >= self.frames {
            return self.target;
        }
        let t = k as f32;
        if t <= self.t_blend {
            let half = 0.5 * t * t / self.t_blend;
            Pose::from_array(core::array::from_fn(|i| {
                self.start[i] + self.v[i] * t + (self.w[i] - self.v[i]) * half
            }))
        } else {
            let f = self.tail.position(t - self.t_blend);
            let c = self.target.to_array();
            Pose::from_array(core::array::from_fn(|i| {
                self.corner[i] + (c[i] - self.corner[i]) * f
            }))
        }
    }

    /// The velocity at frame `k` (mm and rad per frame; zero from `frames` on).
    pub fn rate_at(&self, k: u32) -> [f32; 6] {
        if k >= self.frames {
            return [0.0; 6];
        }
        let t = k as f32;
        if t <= self.t_blend {
            let s = t / self.t_blend;
            core::array::from_fn(|i| self.v[i] + (self.w[i] - self.v[i]) * s)
        } else {
            let f = self.tail.speed(t - self.t_blend);
            let f = if f.is_finite() { f } else { 0.0 };
            let c = self.target.to_array();
            core::array::from_fn(|i| (c[i] - self.corner[i]) * f)
        }
    }

    /// The fastest it goes, per frame: the largest speed of the linear group (mm) and of the
    /// angular group (rad) along the way (the start's, the corner's or the tail's top speed).
    pub fn fastest_per_frame(&self) -> [f32; 2] {
        let c = self.target.to_array();
        let d: Six = core::array::from_fn(|i| c[i] - self.corner[i]);
        let peak = if self.tail.peak.is_finite() {
            self.tail.peak
        } else {
            1.0
        };
        core::array::from_fn(|g| {
            let norm = |x: &Six| libm::sqrtf(dot(x, x, g));
            norm(&self.v).max(norm(&self.w)).max(norm(&d) * peak)
        })
    }

    /// The poses a path check visits, `(pose, fraction of the frames)`, in order (see the
    /// module docs).
    pub fn checkpoints(&self) -> BlendCheckpoints {
        BlendCheckpoints {
            blend: *self,
            j: 1,
            i: 1,
            previous: self.start(),
            previous_k: 0,
            current: self.pose_at(self.sampled(1)),
        }
    }

    /// How many poses [`Blend::checkpoints`] visits (without walking them).
    pub fn check_count(&self) -> u32 {
        self.samples.saturating_mul(self.sub)
    }

    /// The frame of the `j`-th sampled frame (1-based; the last is `frames`).
    fn sampled(&self, j: u32) -> u32 {
        if self.samples == self.frames {
            j
        } else {
            // ceil(j frames / samples), in u64 (frames up to 2^24, samples up to 2^10).
            (u64::from(j) * u64::from(self.frames)).div_ceil(u64::from(self.samples)) as u32
        }
    }
}

/// The poses a blend's path check visits (see [`Blend::checkpoints`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlendCheckpoints {
    blend: Blend,
    /// The sampled frame being reached (1-based), and the chord point within its step.
    j: u32,
    i: u32,
    previous: Pose,
    previous_k: u32,
    /// The pose of the sampled frame being reached (computed once for its chords).
    current: Pose,
}

impl BlendCheckpoints {
    /// How many poses the whole check visits (from its start), without walking it.
    pub fn total(&self) -> u32 {
        self.blend.check_count()
    }
}

impl Iterator for BlendCheckpoints {
    type Item = (Pose, f32);

    fn next(&mut self) -> Option<(Pose, f32)> {
        let b = &self.blend;
        if self.j > b.samples {
            return None;
        }
        let k = b.sampled(self.j);
        let n = b.frames as f32;
        if self.i < b.sub {
            let t = self.i as f32 / b.sub as f32;
            self.i += 1;
            let at = self.previous_k as f32 + (k - self.previous_k) as f32 * t;
            return Some((chord(&self.previous, &self.current, t), at / n));
        }
        let reached = self.current;
        self.previous = reached;
        self.previous_k = k;
        self.i = 1;
        self.j += 1;
        if self.j <= b.samples {
            self.current = b.pose_at(b.sampled(self.j));
        }
        Some((reached, k as f32 / n))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{
        angular_distance_deg, linear_distance_mm, Motion, Plan, Segment, SpeedLimits, CHECK_RULE,
        MAX_PATH_CHECKS, PATH_STEP_DEG, PATH_STEP_MM,
    };
    use super::*;
    use kinematics_core::Libm;

    const HZ: f32 = 50.0;

    fn limits(mm_per_s: f32, deg_per_s: f32, mm_per_s2: f32, deg_per_s2: f32) -> SpeedLimits {
        SpeedLimits {
            mm_per_s,
            deg_per_s,
            mm_per_s2,
            deg_per_s2,
        }
    }

    /// Retargets `motion` to `target` as the controller does: a blend taking over `lead`
    /// frames from now, from the state the motion will have then (or a move from rest).
    fn retarget(m: &mut Motion, target: Pose, l: SpeedLimits, lead: u32) {
        // A move queued and not started yet is replaced: take over no later than it would.
        let lead = lead.min(m.queued_after().unwrap_or(u32::MAX));
        let (pose, rate) = m.state_after(lead);
        let plan = Plan::after::<Libm>(pose, rate, target, l, HZ);
        assert_eq!(plan.start(), pose);
        if m.is_moving() {
            m.start_after(plan, lead);
        } else {
            match plan {
                Plan::Straight(s) => m.start(s),
                Plan::Blend(_) => panic!("a blend from rest"),
            }
        }
    }

    /// The six coordinates as (mm, deg) vectors, per group.
    fn groups(p: &Pose) -> [[f32; 3]; 2] {
        let a = p.to_array();
        [
            [a[0], a[1], a[2]],
            [a[3].to_degrees(), a[4].to_degrees(), a[5].to_degrees()],
        ]
    }

    /// Checks a run of frame poses against the limits, from the poses alone (the frames'
    /// differences are velocities, their differences accelerations): per group, no frame's
    /// speed above its limit and no frame's change of velocity above the acceleration limit
    /// times a frame. Tolerance: f32 rounding of poses of tens of mm (about 1e-5 mm a pose),
    /// far below a limit's step (200 mm/s2 is 0.08 mm of second difference at 50 Hz).
    fn assert_within(poses: &[Pose], l: SpeedLimits, label: &str) {
        let dt = 1.0 / HZ;
        let speed = [l.mm_per_s, l.deg_per_s];
        let accel = [l.mm_per_s2, l.deg_per_s2];
        let tolerance = [2e-4f32, 2e-4];
        let v: std::vec::Vec<[[f32; 3]; 2]> = poses
            .windows(2)
            .map(|w| {
                let (a, b) = (groups(&w[0]), groups(&w[1]));
                core::array::from_fn(|g| core::array::from_fn(|i| b[g][i] - a[g][i]))
            })
            .collect();
        let len = |x: [f32; 3]| libm::sqrtf(x.iter().map(|c| c * c).sum());
        for (k, d) in v.iter().enumerate() {
            for g in 0..2 {
                if speed[g] > 0.0 {
                    assert!(
                        len(d[g]) <= speed[g] * dt + tolerance[g],
                        "{label}: frame {k} group {g}: {} per frame",
                        len(d[g])
                    );
                }
            }
        }
        for (k, w) in v.windows(2).enumerate() {
            for g in 0..2 {
                if accel[g] > 0.0 {
                    let dv = core::array::from_fn(|i| w[1][g][i] - w[0][g][i]);
                    assert!(
                        len(dv) <= accel[g] * dt * dt + tolerance[g],
                        "{label}: frame {} group {g}: change {} > {}",
                        k + 1,
                        len(dv),
                        accel[g] * dt * dt
                    );
                }
            }
        }
    }

    /// Runs `m` for `frames` frames, retargeting at the frames listed; the poses from the
    /// current one on.
    fn run(
        m: &mut Motion,
        l: SpeedLimits,
        frames: u32,
        retargets: &[(u32, Pose, u32)],
    ) -> std::vec::Vec<Pose> {
        let mut poses = std::vec![*m.pose()];
        for f in 0..frames {
            for &(at, target, lead) in retargets {
                if at == f {
                    retarget(m, target, l, lead);
                }
            }
            m.commit();
            poses.push(*m.pose());
        }
        poses
    }

    #[test]
    fn retargets_keep_every_frame_within_the_speed_and_acceleration_limits() {
        let p = |x, y, z, r, pi, yw| Pose::from_degrees(x, y, z, r, pi, yw);
        let cases = [
            // Ahead, behind (a reversal), sideways, and a turn with a rotation, at each lead.
            limits(40.0, 30.0, 200.0, 90.0),
            limits(50.0, 60.0, 150.0, 0.0),
            limits(0.0, 20.0, 300.0, 40.0),
            limits(30.0, 0.0, 0.0, 45.0),
        ];
        let targets = [
            p(0.0, 0.0, 20.0, 0.0, 0.0, 0.0),
            p(0.0, 0.0, -5.0, 0.0, 0.0, 0.0),
            p(12.0, 3.0, 4.0, 0.0, 0.0, 0.0),
            p(-6.0, 8.0, 2.0, 5.0, -4.0, 9.0),
            p(-6.0, 8.5, 2.0, -3.0, 2.0, 0.0),
            p(0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        ];
        for l in cases {
            for lead in [1, 3] {
                for every in [2u32, 5, 9] {
                    let mut m = Motion::new(Pose::HOME);
                    m.start(Segment::plan(Pose::HOME, targets[0], l, HZ));
                    let retargets: std::vec::Vec<(u32, Pose, u32)> = targets[1..]
                        .iter()
                        .enumerate()
                        .map(|(i, t)| ((i as u32 + 1) * every, *t, lead))
                        .collect();
                    let poses = run(&mut m, l, 600, &retargets);
                    let label = std::format!("{l:?} lead {lead} every {every}");
                    assert_within(&poses, l, &label);
                    assert!(!m.is_moving(), "{label}: still moving");
                    assert_eq!(*m.pose(), Pose::HOME, "{label}: on the last target");
                }
            }
        }
    }

    #[test]
    fn a_target_straight_ahead_keeps_the_speed_and_a_jog_never_stops_midway() {
        // A jog: `nudge z=2` every 2 frames (50 mm/s of targets at 50 Hz, 40 mm/s allowed):
        // the platform speeds up and keeps going, never still until the end.
        let l = limits(40.0, 0.0, 200.0, 0.0);
        let mut m = Motion::new(Pose::HOME);
        let first = Pose::from_degrees(0.0, 0.0, 2.0, 0.0, 0.0, 0.0);
        m.start(Segment::plan(Pose::HOME, first, l, HZ));
        let retargets: std::vec::Vec<(u32, Pose, u32)> = (2..=10)
            .map(|i| {
                let z = 2.0 * i as f32;
                (
                    2 * (i - 1),
                    Pose::from_degrees(0.0, 0.0, z, 0.0, 0.0, 0.0),
                    2,
                )
            })
            .collect();
        let poses = run(&mut m, l, 300, &retargets);
        assert_within(&poses, l, "jog");
        let end = poses
            .iter()
            .position(|p| (p.z_mm - 20.0).abs() < 1e-4)
            .expect("arrives");
        for (k, w) in poses[..=end].windows(2).enumerate() {
            let step = w[1].z_mm - w[0].z_mm;
            assert!(step > 0.0, "still (or back) at frame {k}: {step} mm");
        }
        // Past 30 mm/s (0.6 mm a frame), which 2 mm moves from rest never reach (a triangle
        // at 200 mm/s2 peaks at sqrt(200 * 2) = 20 mm/s): it does not stop at each target.
        let steps: std::vec::Vec<f32> = poses.windows(2).map(|w| w[1].z_mm - w[0].z_mm).collect();
        assert!(steps.iter().any(|s| *s > 0.6), "{steps:?}");
    }

    #[test]
    fn a_reversal_brakes_at_the_limit_and_a_sharp_turn_comes_to_rest_at_the_corner() {
        let l = limits(40.0, 0.0, 200.0, 0.0);
        let dt = 1.0 / HZ;
        let mut m = Motion::new(Pose::HOME);
        let up = Pose::from_degrees(0.0, 0.0, 20.0, 0.0, 0.0, 0.0);
        m.start(Segment::plan(Pose::HOME, up, l, HZ));
        for _ in 0..20 {
            m.commit();
        }
        let (pose, rate) = m.state_after(0);
        // 0.4 s in: at 40 mm/s (the ramp took 0.2 s).
        assert!((rate[2] / dt - 40.0).abs() < 0.01, "{rate:?}");
        let down = Pose::from_degrees(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let b = Blend::plan::<Libm>(pose, rate, down, l.into(), HZ, CHECK_RULE).unwrap();
        // Braking from 40 mm/s at 200 mm/s2 takes 0.2 s (10 frames) and 4 mm: the corner is
        // where it comes to rest, straight ahead, then it comes back from rest.
        assert!((b.t_blend - 10.0).abs() < 1e-3, "{}", b.t_blend);
        assert_eq!(b.w, [0.0; 6]);
        assert!((b.corner[2] - (pose.z_mm + 4.0)).abs() < 1e-3);
        // A right angle: also to rest at the corner.
        let side = Pose::from_degrees(10.0, 0.0, pose.z_mm + 2.0, 0.0, 0.0, 0.0);
        let b = Blend::plan::<Libm>(pose, rate, side, l.into(), HZ, CHECK_RULE).unwrap();
        let e = b.corner;
        let u = [
            side.x_mm - pose.x_mm,
            0.0,
            side.z_mm - pose.z_mm - rate[2] * b.t_blend / 2.0,
        ];
        assert!(u[2] <= 0.0 && b.w == [0.0; 6], "{u:?} {:?} {e:?}", b.w);
        // 45 degrees ahead: it keeps moving, within the limits.
        let ahead = Pose::from_degrees(10.0, 0.0, pose.z_mm + 14.0, 0.0, 0.0, 0.0);
        let b = Blend::plan::<Libm>(pose, rate, ahead, l.into(), HZ, CHECK_RULE).unwrap();
        let w = libm::sqrtf(b.w.iter().map(|c| c * c).sum()) / dt;
        assert!(w > 10.0 && w <= 40.0 + 1e-3, "{w} mm/s at the corner");
    }

    #[test]
    fn standing_still_or_no_acceleration_limit_means_no_blend() {
        let l = limits(40.0, 30.0, 200.0, 0.0);
        let t = Pose::from_degrees(0.0, 0.0, 5.0, 0.0, 0.0, 0.0);
        assert!(Blend::plan::<Libm>(Pose::HOME, [0.0; 6], t, l.into(), HZ, CHECK_RULE).is_none());
        // Turning about an axis with no angular acceleration limit: the rotation's speed may
        // change at once, so the move from rest is the same thing.
        let turning = [0.0, 0.0, 0.0, 0.01, 0.0, 0.0];
        assert!(Blend::plan::<Libm>(Pose::HOME, turning, t, l.into(), HZ, CHECK_RULE).is_none());
        let off = limits(40.0, 30.0, 0.0, 0.0);
        assert!(Blend::plan::<Libm>(
            Pose::HOME,
            [0.0, 0.0, 0.5, 0.0, 0.0, 0.0],
            t,
            off.into(),
            HZ,
            CHECK_RULE
        )
        .is_none());
    }

    #[test]
    fn checkpoints_include_every_commanded_pose_of_a_short_blend_and_stay_within_budget() {
        let l = limits(40.0, 30.0, 200.0, 90.0);
        let mut m = Motion::new(Pose::HOME);
        let up = Pose::from_degrees(0.0, 0.0, 20.0, 0.0, 0.0, 0.0);
        m.start(Segment::plan(Pose::HOME, up, l, HZ));
        for _ in 0..12 {
            m.commit();
        }
        let (pose, rate) = m.state_after(2);
        for target in [
            Pose::from_degrees(5.0, -3.0, 2.0, 4.0, 0.0, -6.0),
            Pose::from_degrees(0.0, 0.0, 30.0, 0.0, 0.0, 0.0),
        ] {
            let b = Blend::plan::<Libm>(pose, rate, target, l.into(), HZ, CHECK_RULE).unwrap();
            let checked: std::vec::Vec<(Pose, f32)> = b.checkpoints().collect();
            assert_eq!(checked.len() as u32, b.checkpoints().total());
            assert!(checked.len() as u32 <= MAX_PATH_CHECKS);
            for k in 1..=b.frames() {
                assert!(checked.iter().any(|(p, _)| *p == b.pose_at(k)), "frame {k}");
            }
            assert_eq!(checked.last().unwrap().0, target);
            // In order, and close enough together.
            for w in checked.windows(2) {
                assert!(w[1].1 >= w[0].1);
                assert!(linear_distance_mm(&w[0].0, &w[1].0) <= PATH_STEP_MM + 1e-3);
                assert!(angular_distance_deg(&w[0].0, &w[1].0) <= PATH_STEP_DEG + 1e-3);
            }
        }
        // A slow, long blend: evenly spaced frames, within the budget, ending on the target.
        let slow = limits(1.0, 0.0, 0.5, 0.0);
        let (pose, rate) = (Pose::HOME, [0.0, 0.0, 1.0 / HZ, 0.0, 0.0, 0.0]);
        let far = Pose::from_degrees(0.0, 0.0, -30.0, 0.0, 0.0, 0.0);
        let b = Blend::plan::<Libm>(pose, rate, far, slow.into(), HZ, CHECK_RULE).unwrap();
        assert!(b.frames() > MAX_PATH_CHECKS);
        let checked: std::vec::Vec<(Pose, f32)> = b.checkpoints().collect();
        assert!(checked.len() as u32 <= MAX_PATH_CHECKS && checked.len() >= 60);
        assert_eq!(checked.last().unwrap().0, far);
    }
}
