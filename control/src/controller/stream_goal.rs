//! What a stream follows ([`Streaming`]: the newest frame's target, the goal, the tracker) and
//! how a target out of reach (or, with torque ratings, beyond them) becomes a goal: a clamp
//! ([`Clamp`]), a job of the controller's own that bisects the straight line from the current
//! pose to the target, [`CLAMP_STEPS`] halvings, a few per slice. How frames become targets and
//! goals is the controller's (`controller/streaming.rs`).

use kinematics_core::ik::Solution;
use kinematics_core::{Math, Pose};

use super::pose_check::{PoseCheck, CHECKS_PER_SLICE};
use crate::report::StreamCounts;
use crate::tracker::{TrackLimits, Tracker};

/// Halvings of a clamp's bisection: the clamped pose is within 1/64 of the way from the
/// current pose to the target (a clamp costs 1 + 6 IK solutions, the 6 as the controller's
/// own job, [`CHECKS_PER_SLICE`](super::CHECKS_PER_SLICE) per pass).
pub const CLAMP_STEPS: u32 = 6;

/// The stream being followed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Streaming {
    /// The newest frame's pose, as sent.
    pub target: Pose,
    /// A frame arrived since the last
    /// [`Controller::apply_stream`](super::Controller::apply_stream).
    pub fresh: bool,
    /// What the tracker follows: the target, clamped to the workspace.
    pub goal: Pose,
    /// Where the tracker is and how fast it goes.
    pub tracker: Tracker,
    /// The step guard's memory ([`crate::stream::StreamSettings::step_allowed`]): the last
    /// frame taken and the last well-formed frame, each axis' share of its full scale.
    pub taken: [f32; 6],
    pub seen: [f32; 6],
    /// [`frame_ticks`](super::Controller) when the last frame came (for `status`).
    pub last_frame_tick: u32,
    /// The tracker's limits and frame time as the settings give them, worked out once per
    /// change of the settings (`None` until the first frame needs them), not every frame.
    pub timing: Option<TrackTiming>,
}

/// The tracker's limits and frame time from the settings of one
/// [`Controller::settings_generation`](super::Controller::settings_generation): converting
/// them is float arithmetic (library calls on the RP2040), which a servo frame need not repeat.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct TrackTiming {
    /// The settings generation they were worked out for.
    pub generation: u32,
    pub limits: TrackLimits,
    /// Every limit off: stream frames are applied as they come (pass-through).
    pub pass_through: bool,
    /// A servo frame, s.
    pub frame_s: f32,
}

/// A clamp in progress: bisection on the straight line from `from` (which can be driven) to
/// `to` (which cannot), [`CLAMP_STEPS`] halvings in all.
#[derive(Debug, Clone, Copy)]
pub(super) struct Clamp {
    from: Pose,
    to: Pose,
    /// `to` is within reach with this solution, but its holding torques are still to be
    /// checked against the ratings (the first slice); if they are within them, `to` is the
    /// goal, else the bisection goes on.
    unchecked: Option<Solution>,
    /// The halvings check the holding torques of each pose (one pose a slice). Otherwise, with
    /// ratings, the bisection first finds the reach alone (IK solutions only, as without
    /// ratings), then checks the furthest pose's torques, a slice of its own (`held`): within
    /// the ratings, that pose is the goal (the servo limits were the boundary: one torque check
    /// instead of one per halving, where each costs several IK solutions); beyond them, the
    /// bisection starts again with the torques of each pose. A target within reach but beyond
    /// the ratings starts with them.
    torques_each: bool,
    /// The ends of the stretch still bisected: a pose known to be drivable (or `from`) and one
    /// known not to be (or `to`); each halving tries their midpoint.
    near: Pose,
    far: Pose,
    /// The furthest drivable pose found and its solution (`None`: only `from`).
    best: Option<(Pose, Solution)>,
    /// Halvings done.
    steps: u32,
}

impl Clamp {
    /// A bisection on the straight line from `from` to `to`.
    pub fn new(from: Pose, to: Pose, unchecked: Option<Solution>) -> Clamp {
        Clamp {
            from,
            to,
            torques_each: unchecked.is_some(),
            unchecked,
            near: from,
            far: to,
            best: None,
            steps: 0,
        }
    }

    /// The midpoint of the stretch still bisected, `(near + far) / 2` per axis (a fraction
    /// `k / 2^n` of the way from `from` to `to`, as [`crate::motion::lerp`] would give it, to
    /// rounding): one addition through `M`'s arithmetic per axis and an exact halving in
    /// integer instructions, where `from + (to - from) t` with the compiler's library calls
    /// cost a clamp's six halvings about 8,000 cycles on the RP2040.
    fn midpoint<M: Math>(&self) -> Pose {
        let (a, b) = (self.near.to_array(), self.far.to_array());
        Pose::from_array(core::array::from_fn(|i| half::<M>(M::add(a[i], b[i]))))
    }

    /// A slice of a clamp: the target's holding torques if they are to be checked (then the
    /// target is the goal if they are within the ratings; else it counts as clamped), else
    /// more halvings of the bisection ([`PoseCheck::per_slice`] with each pose's torques,
    /// [`CHECKS_PER_SLICE`] by the reach alone), or the torques of the furthest pose the reach
    /// alone allows (see `torques_each`). `Some` when it is done: the goal and its solution
    /// (`None`: where the bisection started, whose solution is the current one).
    pub fn step<M: Math>(
        &mut self,
        check: PoseCheck<'_>,
        counts: &mut StreamCounts,
    ) -> Option<(Pose, Option<Solution>)> {
        let torque = check.settings.payload.checked();
        if let Some(solution) = self.unchecked.take() {
            let held = check
                .settings
                .payload
                .check::<M>(check.solver, &self.to, &solution.arm_rad);
            if held.is_ok() {
                return Some((self.to, Some(solution)));
            }
            counts.clamped = counts.clamped.wrapping_add(1);
            return None;
        }
        let each = torque && self.torques_each;
        if self.steps >= CLAMP_STEPS && torque && !each {
            // The reach is found: the furthest pose's torques, a slice of their own.
            if let Some((pose, solution)) = self.best {
                let held =
                    check
                        .settings
                        .payload
                        .check::<M>(check.solver, &pose, &solution.arm_rad);
                if held.is_err() {
                    *self = Clamp {
                        torques_each: true,
                        ..Clamp::new(self.from, self.to, None)
                    };
                    return None;
                }
            }
            return Some(self.goal());
        }
        let per_slice = if each {
            check.per_slice()
        } else {
            CHECKS_PER_SLICE
        };
        for _ in 0..per_slice {
            if self.steps >= CLAMP_STEPS {
                break;
            }
            self.steps += 1;
            let pose = self.midpoint::<M>();
            // By the reach alone, the IK's own result (no error to convert, a smaller copy).
            let drivable = if each {
                check.pose::<M>(&pose, true).ok()
            } else {
                check.solver.solve::<M>(&check.settings.servos, &pose).ok()
            };
            match drivable {
                Some(solution) => {
                    self.near = pose;
                    self.best = Some((pose, solution));
                }
                None => self.far = pose,
            }
        }
        // (With ratings, the reach alone is done in the next slice, by its torques.)
        (self.steps >= CLAMP_STEPS && (each || !torque)).then(|| self.goal())
    }

    /// The bisection's result: the furthest drivable pose found and its solution, or where it
    /// started (`None`: the current solution).
    fn goal(&self) -> (Pose, Option<Solution>) {
        self.best
            .map_or((self.from, None), |(pose, solution)| (pose, Some(solution)))
    }
}

/// `x / 2`, exactly: the exponent lowered by one in integer instructions where the result is a
/// normal number (a multiplication is a library call on the RP2040), through `M` otherwise
/// (zero, numbers near the smallest, which the poses here never are; and non-finite ones).
fn half<M: Math>(x: f32) -> f32 {
    let bits = x.to_bits();
    let exponent = (bits >> 23) & 0xff;
    if exponent > 1 && exponent < 0xff {
        f32::from_bits(bits - (1 << 23))
    } else {
        M::mul(x, 0.5)
    }
}

#[cfg(test)]
mod tests {
    use super::half;
    use kinematics_core::Libm;

    #[test]
    fn half_is_exact_for_every_kind_of_float() {
        for x in [
            0.0f32,
            -0.0,
            1.0,
            -3.0,
            13.99,
            -0.261_799,
            f32::MIN_POSITIVE,
            f32::MIN_POSITIVE * 2.0,
            f32::MIN_POSITIVE * 3.0,
            1e-40,
            f32::MAX,
            -f32::MAX,
        ] {
            assert_eq!(half::<Libm>(x).to_bits(), (x * 0.5).to_bits(), "{x}");
        }
    }
}
