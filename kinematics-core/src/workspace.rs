//! The workspace: how far the platform can go from a pose along each single axis (x, y, z in
//! mm, roll, pitch, yaw in rad, both ways) before a leg or actuator limit stops it, and a
//! sampled workspace on a grid for plots.
//!
//! Both ask a caller's `reachable(pose)` test, so they serve any platform and limit: for a
//! servo platform within its servo limits,
//! `|p| solver.solve::<M>(&servos, p).map(|_| ())` (the IK of "The Mathematics of the
//! Stewart Platform" with eq. 13, 14's pulse limits); for struts, `Struts::solve`.
//!
//! An excursion ([`Excursion`]) marches out from the pose in steps ([`Options::step_mm`],
//! [`Options::step_rad`]) to the first pose that fails, then bisects between the last pose
//! that passed and it down to [`Options::tolerance_mm`] / [`Options::tolerance_rad`]: the
//! reach reported passes the test, and a pose at most one tolerance farther fails it. A gap in
//! the workspace narrower than a march step could be stepped over. One test per
//! [`Excursion::step`] (one IK), so a main loop can spread the work over several passes;
//! [`Limits`] does all twelve axis-directions the same way.

use crate::pose::{Axis, Pose};

/// Which way along an axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sense {
    /// Towards smaller values.
    Minus,
    /// Towards larger values.
    Plus,
}

impl Sense {
    /// `-1.0` or `1.0`.
    pub const fn sign(self) -> f32 {
        match self {
            Sense::Minus => -1.0,
            Sense::Plus => 1.0,
        }
    }
}

/// How excursions are searched.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Farthest a translation is searched, mm.
    pub range_mm: f32,
    /// Farthest a rotation is searched, rad.
    pub range_rad: f32,
    /// March step for translations, mm.
    pub step_mm: f32,
    /// March step for rotations, rad.
    pub step_rad: f32,
    /// Bisection ends within this, mm.
    pub tolerance_mm: f32,
    /// Bisection ends within this, rad.
    pub tolerance_rad: f32,
}

impl Default for Options {
    /// Translations to 100 mm in 5 mm steps, to 0.01 mm; rotations to 180 degrees in 5 degree
    /// steps, to 1e-4 rad (0.006 degrees).
    fn default() -> Options {
        Options {
            range_mm: 100.0,
            range_rad: core::f32::consts::PI,
            step_mm: 5.0,
            step_rad: 5.0f32.to_radians(),
            tolerance_mm: 0.01,
            tolerance_rad: 1e-4,
        }
    }
}

/// Why an excursion ends where it does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Limit<E> {
    /// The first pose beyond fails the test, for this reason (which leg, servo, stroke).
    Blocked(E),
    /// Nothing failed within the search range ([`Options::range_mm`], [`Options::range_rad`]).
    Range,
    /// The starting pose itself fails the test (reach 0).
    Start(E),
}

/// The reach along one axis-direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach<E> {
    /// The axis.
    pub axis: Axis,
    /// Which way.
    pub sense: Sense,
    /// How far the platform can go that way, mm or rad (not negative).
    pub distance: f32,
    /// What stops it there.
    pub limit: Limit<E>,
}

impl<E> Reach<E> {
    /// The farthest value of the axis's coordinate reachable that way (start `+- distance`).
    pub fn extreme(&self, start: &Pose) -> f32 {
        start.get(self.axis) + self.sense.sign() * self.distance
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase<E> {
    /// The last march point passed at `passed`.
    March { passed: f32 },
    /// Between `passed` (passes) and `failed` (fails, for `cause`).
    Bisect { passed: f32, failed: f32, cause: E },
}

/// The search for the reach along one axis-direction from a pose (which must pass the test),
/// one test per [`Excursion::step`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Excursion<E> {
    start: Pose,
    axis: Axis,
    sense: Sense,
    range: f32,
    step: f32,
    tolerance: f32,
    phase: Phase<E>,
}

impl<E: Copy> Excursion<E> {
    /// A search along `axis` from `start` (a pose that passes the test).
    pub fn new(start: Pose, axis: Axis, sense: Sense, options: &Options) -> Excursion<E> {
        let (range, step, tolerance) = if axis.is_angle() {
            (options.range_rad, options.step_rad, options.tolerance_rad)
        } else {
            (options.range_mm, options.step_mm, options.tolerance_mm)
        };
        Excursion {
            start,
            axis,
            sense,
            range,
            step,
            tolerance,
            phase: Phase::March { passed: 0.0 },
        }
    }

    /// The pose `distance` along the axis from the start.
    pub fn pose_at(&self, distance: f32) -> Pose {
        let mut pose = self.start;
        pose.set(
            self.axis,
            self.start.get(self.axis) + self.sense.sign() * distance,
        );
        pose
    }

    fn reach(&self, distance: f32, limit: Limit<E>) -> Reach<E> {
        Reach {
            axis: self.axis,
            sense: self.sense,
            distance,
            limit,
        }
    }

    /// Tests one more pose: `None` while searching, then the reach.
    pub fn step(&mut self, mut reachable: impl FnMut(&Pose) -> Result<(), E>) -> Option<Reach<E>> {
        match self.phase {
            Phase::March { passed } => {
                let next = (passed + self.step).min(self.range);
                match reachable(&self.pose_at(next)) {
                    Ok(()) if next >= self.range => Some(self.reach(next, Limit::Range)),
                    Ok(()) => {
                        self.phase = Phase::March { passed: next };
                        None
                    }
                    Err(cause) => self.bisect(passed, next, cause),
                }
            }
            Phase::Bisect {
                passed,
                failed,
                cause,
            } => {
                let middle = 0.5 * (passed + failed);
                match reachable(&self.pose_at(middle)) {
                    Ok(()) => self.bisect(middle, failed, cause),
                    Err(cause) => self.bisect(passed, middle, cause),
                }
            }
        }
    }

    fn bisect(&mut self, passed: f32, failed: f32, cause: E) -> Option<Reach<E>> {
        let middle = 0.5 * (passed + failed);
        if failed - passed <= self.tolerance || middle <= passed || middle >= failed {
            return Some(self.reach(passed, Limit::Blocked(cause)));
        }
        self.phase = Phase::Bisect {
            passed,
            failed,
            cause,
        };
        None
    }
}

/// The twelve axis-directions in report order: x-, x+, y-, y+, ..., yaw-, yaw+.
pub fn axis_directions() -> [(Axis, Sense); 12] {
    core::array::from_fn(|k| {
        let sense = if k % 2 == 0 {
            Sense::Minus
        } else {
            Sense::Plus
        };
        (Axis::ALL[k / 2], sense)
    })
}

/// The reach along all twelve axis-directions from a pose, one test per [`Limits::step`]:
/// first the start itself, then [`axis_directions`] in order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits<E> {
    start: Pose,
    options: Options,
    /// The start has been tested (and passed).
    started: bool,
    /// The axis-direction being searched, 0..12.
    index: usize,
    excursion: Excursion<E>,
    done: [Option<Reach<E>>; 12],
    finished: bool,
}

impl<E: Copy> Limits<E> {
    /// A search from `start`.
    pub fn new(start: Pose, options: Options) -> Limits<E> {
        let (axis, sense) = axis_directions()[0];
        Limits {
            start,
            options,
            started: false,
            index: 0,
            excursion: Excursion::new(start, axis, sense, &options),
            done: [None; 12],
            finished: false,
        }
    }

    /// The reaches found so far, in [`axis_directions`] order.
    pub fn found(&self) -> &[Option<Reach<E>>; 12] {
        &self.done
    }

    /// Tests one more pose: `None` while searching, then the twelve reaches (in
    /// [`axis_directions`] order), once.
    pub fn step(
        &mut self,
        mut reachable: impl FnMut(&Pose) -> Result<(), E>,
    ) -> Option<[Reach<E>; 12]> {
        if self.finished {
            return None;
        }
        let directions = axis_directions();
        if !self.started {
            self.started = true;
            if let Err(cause) = reachable(&self.start) {
                self.finished = true;
                let all = directions.map(|(axis, sense)| Reach {
                    axis,
                    sense,
                    distance: 0.0,
                    limit: Limit::Start(cause),
                });
                self.done = all.map(Some);
                return Some(all);
            }
            return None;
        }
        let reach = self.excursion.step(&mut reachable)?;
        self.done[self.index] = Some(reach);
        self.index += 1;
        if let Some(&(axis, sense)) = directions.get(self.index) {
            self.excursion = Excursion::new(self.start, axis, sense, &self.options);
            return None;
        }
        self.finished = true;
        let all = self.done;
        Some(core::array::from_fn(|i| all[i].unwrap_or(reach)))
    }
}

/// A regular grid of poses for plotting the workspace: up to three axes varied about a centre
/// pose, the others held.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// The pose at the grid's centre (the held coordinates).
    pub centre: Pose,
    /// The axes varied.
    pub axes: [Axis; 3],
    /// Half the extent along each axis, mm or rad.
    pub half_range: [f32; 3],
    /// Points along each axis (1 holds the axis at the centre).
    pub counts: [u16; 3],
}

impl Grid {
    /// How many poses the grid has.
    pub fn len(&self) -> usize {
        self.counts.iter().map(|&c| usize::from(c)).product()
    }

    /// True if the grid has no pose.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Pose number `index` (0..len), the first axis varying fastest.
    pub fn pose(&self, index: usize) -> Pose {
        let mut pose = self.centre;
        let mut rest = index;
        for k in 0..3 {
            let n = usize::from(self.counts[k].max(1));
            let i = rest % n;
            rest /= n;
            let offset = if n == 1 {
                0.0
            } else {
                self.half_range[k] * (2.0 * i as f32 / (n - 1) as f32 - 1.0)
            };
            pose.set(self.axes[k], self.centre.get(self.axes[k]) + offset);
        }
        pose
    }

    /// The grid's poses, in [`Grid::pose`] order.
    pub fn poses(&self) -> impl Iterator<Item = Pose> + '_ {
        (0..self.len()).map(|i| self.pose(i))
    }

    /// Tests every pose of the grid and hands each with its outcome to `visit` (no storage:
    /// a plot draws as it goes).
    pub fn sample<E>(
        &self,
        mut reachable: impl FnMut(&Pose) -> Result<(), E>,
        mut visit: impl FnMut(&Pose, Result<(), E>),
    ) {
        for pose in self.poses() {
            let outcome = reachable(&pose);
            visit(&pose, outcome);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fake workspace: |x| <= 7.3, |roll| <= 0.25 rad.
    fn test(pose: &Pose) -> Result<(), Axis> {
        if pose.x_mm.abs() > 7.3 {
            Err(Axis::X)
        } else if pose.roll_rad.abs() > 0.25 {
            Err(Axis::Roll)
        } else {
            Ok(())
        }
    }

    #[test]
    fn limits_find_each_edge_within_tolerance() {
        let start = Pose::from_degrees(1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut limits = Limits::new(start, Options::default());
        let mut tests = 0;
        let all = loop {
            tests += 1;
            if let Some(all) = limits.step(test) {
                break all;
            }
        };
        // 8 directions run to the end of the range (20 or 36 steps each).
        assert!(tests < 300, "{tests}");
        let x_plus = all[1];
        assert_eq!(x_plus.limit, Limit::Blocked(Axis::X));
        assert!((x_plus.extreme(&start) - 7.3).abs() <= 0.01);
        assert!((all[0].extreme(&start) + 7.3).abs() <= 0.01);
        assert!((all[7].distance - 0.25).abs() <= 1e-4);
        assert_eq!(all[3].limit, Limit::Range);
        let mut bad = Limits::new(
            Pose::from_degrees(9.0, 0.0, 0.0, 0.0, 0.0, 0.0),
            Options::default(),
        );
        assert!(matches!(bad.step(test), Some(r) if r[5].limit == Limit::Start(Axis::X)));
    }

    #[test]
    fn grid_visits_every_pose() {
        let grid = Grid {
            centre: Pose::HOME,
            axes: [Axis::X, Axis::Y, Axis::Yaw],
            half_range: [10.0, 5.0, 0.1],
            counts: [3, 2, 1],
        };
        assert_eq!(grid.len(), 6);
        let xs: Vec<f32> = grid.poses().map(|p| p.x_mm).collect();
        assert_eq!(&xs[..3], &[-10.0, 0.0, 10.0]);
        let mut passed = 0;
        grid.sample(test, |_, outcome| passed += usize::from(outcome.is_ok()));
        assert_eq!(passed, 2);
    }
}
