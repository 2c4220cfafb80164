//! A path check: the job of a reachable target whose path (a straight line from the current
//! pose, or a blend from the motion in progress, [`crate::motion::blend`]) is checked by the
//! IK at up to [`crate::motion::MAX_PATH_CHECKS`] checkpoints, a few per slice
//! ([`PoseCheck::per_slice`]). With a payload to check against ratings or to report (`check`),
//! the target's holding torques come first, in a slice of their own. What a checked path leads
//! to (a move, a jump, `check`'s listing, the way home) is the controller's
//! (`controller/moves.rs`). With servo speed ratings ([`crate::servo_speed`]) the check also
//! measures the path time from its IK solutions ([`ServoTime`]), and if the move was planned
//! too fast for it, plans it again and checks the new plan's poses; a move taken over while
//! moving (a blend, `controller/moves.rs`) has its frames' arm turns measured instead
//! ([`FrameTurns`]), and is planned again, slower, until they are within the ratings.

use kinematics_core::ik::Solution;
use kinematics_core::{Math, Pose, LEGS};

use super::pose_check::{PoseCheck, Torques};
use crate::error::Error;
use crate::motion::{Fraction, Plan, PlanCheckpoints, Segment, SpeedLimits};
use crate::payload::TorqueError;
use crate::servo_speed::{PathTime, ServoSpeeds, PLAN_MARGIN};
use crate::settings::Settings;

/// What a checked path is for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Purpose {
    /// `pose`, `move`, `nudge`, `home`: start the move (a jump if `jump`).
    Move { jump: bool },
    /// `check`: report, move nothing.
    Check,
    /// Link loss: return home.
    ReturnHome,
    /// The e-stop opened with `estop_action home`: go home.
    EstopHome,
}

impl Purpose {
    /// The controller's own (no command waits for its reply).
    pub fn is_own(self) -> bool {
        matches!(self, Purpose::ReturnHome | Purpose::EstopHome)
    }

    /// Whether a path check for this starts with the target's holding torques: with ratings to
    /// check, or for `check` to report.
    pub fn needs_target_torque(self, settings: &Settings) -> bool {
        let payload = &settings.payload;
        payload.checked() || (self == Purpose::Check && payload.carried())
    }
}

/// When a blend checked while the motion in progress goes on takes over (frame counts, as
/// the controller counts frames, wrapping).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct HandOver {
    /// The frame count when the check began.
    pub begun: u32,
    /// The frame count after which the blend's first frame comes.
    pub at: u32,
    /// The pose and velocity (per frame) the motion was to have then, where the blend starts.
    pub pose: Pose,
    pub rate: [f32; 6],
}

/// A reachable target whose path is being checked.
#[derive(Debug, Clone, Copy)]
pub(super) struct PathCheck {
    pub purpose: Purpose,
    /// The target's solution (solved when the command came).
    pub solution: Solution,
    /// The move checked: from rest, or a blend from the motion in progress.
    pub plan: Plan,
    /// For a blend: the frame (the controller's frame count) at which it takes over, and the
    /// frame count when the check began.
    pub hand_over: Option<HandOver>,
    /// IK solutions of the path done so far (the controller learns how many fit in a frame).
    pub solved: u32,
    /// The plan is stale (a missed hand-over): the next slice plans it again.
    pub replan: bool,
    checkpoints: PlanCheckpoints,
    /// The target's holding torques: `None` until computed (the first slice, when there is a
    /// payload to check or report), then what `check` reports.
    torque: Option<Option<Torques>>,
    /// With servo speed ratings, on the first pass over the path: its time being measured.
    servo_time: Option<ServoTime>,
    /// With servo speed ratings, a move taken over while moving: its frames' arm turns being
    /// measured, on every pass.
    pub frame_turns: Option<FrameTurns>,
}

/// What an ended path check leaves for what follows it (`controller/moves.rs`): copied out of
/// the job, which is more than twice its size (its checkpoints, its measures).
#[derive(Debug, Clone, Copy)]
pub(super) struct Checked {
    pub purpose: Purpose,
    /// The target's solution.
    pub solution: Solution,
    /// The move checked.
    pub plan: Plan,
    /// For a blend: when it takes over.
    pub hand_over: Option<HandOver>,
    /// IK solutions of the path.
    pub solved: u32,
    /// The target's holding torques for `check` to report (`None` when there are none to
    /// report, or they were not reached).
    pub torque: Option<Torques>,
}

/// The most passes a rated move taken over while moving is planned and checked (the last
/// plan brakes to rest at its corner, then goes on from rest, and is taken as measured).
pub(super) const MAX_RATED_PASSES: u32 = 4;

/// With servo speed ratings, a move taken over while moving (a blend from the motion in
/// progress, or a straight move from where it ends): the arm turns between its checkpoints,
/// from their IK solutions, over the fewest frames the plan takes between them
/// ([`Plan::frames_spanned`]), against each servo's rating; and the limits it was planned with,
/// which a pass that finds an arm too fast tightens for the next plan (see
/// [`FrameTurns::tightened`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct FrameTurns {
    /// The speed limits the plan was made with (the move's own, capped).
    pub limits: SpeedLimits,
    /// The share of the blend's largest corner velocity it takes (see
    /// [`crate::motion::blend::Limits::corner_scale`]).
    pub corner_scale: f32,
    /// Which pass this is (1 for the first plan).
    pub pass: u32,
    /// A servo frame, s.
    pub frame_s: f32,
    /// The last checkpoint's fraction and arm angles (`None` before the start's are solved).
    last: Option<(f32, [f32; LEGS])>,
    /// The largest share of its rating any arm has needed so far.
    worst: f32,
}

impl FrameTurns {
    /// The first pass of a plan made with `limits` and `corner_scale`.
    pub fn new(limits: SpeedLimits, corner_scale: f32, frame_hz: f32) -> FrameTurns {
        FrameTurns {
            limits,
            corner_scale,
            pass: 1,
            frame_s: 1.0 / frame_hz,
            last: None,
            worst: 0.0,
        }
    }

    /// The same limits, measured from the start again (the plan was made again from another
    /// hand-over).
    fn restarted(self) -> FrameTurns {
        FrameTurns {
            last: None,
            worst: 0.0,
            ..self
        }
    }

    /// One more checkpoint, in order: its fraction and its arm angles.
    fn visit(&mut self, speeds: &ServoSpeeds, plan: &Plan, fraction: f32, arm_rad: &[f32; LEGS]) {
        if let Some((before, arms)) = self.last {
            let frames = plan.frames_spanned(fraction - before);
            if frames > 0.0 {
                let share = speeds.least_time_s(&arms, arm_rad) / (frames * self.frame_s);
                if share.is_nan() || share > self.worst {
                    self.worst = if share.is_nan() { f32::INFINITY } else { share };
                }
            }
        }
        self.last = Some((fraction, *arm_rad));
    }

    /// At the end of a pass: `None` if no arm turned faster than its rating (within
    /// [`PLAN_MARGIN`] where the check did not visit every frame), or if this was the last pass;
    /// else the next pass's limits: every speed of the plan (the fastest it went, or the limit)
    /// and the share of the corner velocity, slowed by the share measured (at [`PLAN_MARGIN`]);
    /// on the last pass the corner velocity is 0 (brake to rest there, then start from rest).
    fn tightened(&self, plan: &Plan) -> Option<FrameTurns> {
        let allowed = if plan.checks_every_frame() {
            1.0
        } else {
            PLAN_MARGIN
        };
        if self.worst <= allowed || self.pass >= MAX_RATED_PASSES {
            return None;
        }
        let scale = PLAN_MARGIN / self.worst;
        let hz = 1.0 / self.frame_s;
        let fastest = plan.fastest_per_frame();
        let slower = |limit: f32, fastest: f32| {
            let top = if limit > 0.0 && limit < fastest {
                limit
            } else {
                fastest
            };
            if top > 0.0 {
                top * scale
            } else {
                limit
            }
        };
        let pass = self.pass + 1;
        Some(FrameTurns {
            limits: SpeedLimits {
                mm_per_s: slower(self.limits.mm_per_s, fastest[0] * hz),
                deg_per_s: slower(self.limits.deg_per_s, (fastest[1] * hz).to_degrees()),
                ..self.limits
            },
            corner_scale: if pass >= MAX_RATED_PASSES {
                0.0
            } else {
                self.corner_scale * scale
            },
            pass,
            ..self.restarted()
        })
    }
}

/// The path time of a move with servo speed ratings, measured on the first pass of its check
/// (see [`crate::servo_speed`]), and what a new plan needs.
#[derive(Debug, Clone, Copy)]
pub(super) struct ServoTime {
    /// Measured along the path so far.
    pub measured: PathTime,
    /// The path time the segment was planned for, s.
    pub planned_s: f32,
    /// The move's own limits, before the ratings' cap.
    pub limits: SpeedLimits,
    /// The frame rate, Hz.
    pub frame_hz: f32,
}

impl PathCheck {
    /// The check of `plan`, whose target has `solution`, for `purpose` with `settings`.
    pub fn new(
        purpose: Purpose,
        solution: Solution,
        plan: Plan,
        hand_over: Option<HandOver>,
        settings: &Settings,
        servo_time: Option<ServoTime>,
        frame_turns: Option<FrameTurns>,
    ) -> PathCheck {
        PathCheck {
            purpose,
            solution,
            plan,
            hand_over,
            solved: 0,
            replan: false,
            checkpoints: plan.checkpoints(),
            // The target's torques take a slice of their own, if they are needed at all.
            torque: if purpose.needs_target_torque(settings) {
                None
            } else {
                Some(None)
            },
            servo_time,
            frame_turns,
        }
    }

    /// The same check of another plan (the target's torques kept, if computed): a blend whose
    /// hand-over was missed, planned again.
    pub fn replanned(&self, plan: Plan, hand_over: Option<HandOver>) -> PathCheck {
        PathCheck {
            plan,
            hand_over,
            solved: 0,
            replan: false,
            checkpoints: plan.checkpoints(),
            frame_turns: self.frame_turns.map(FrameTurns::restarted),
            ..*self
        }
    }

    /// The same check, its plan marked stale (a missed hand-over): the next slice plans again.
    pub fn to_replan(self) -> PathCheck {
        PathCheck {
            replan: true,
            ..self
        }
    }

    /// What the check leaves, once it has ended.
    pub fn checked(&self) -> Checked {
        Checked {
            purpose: self.purpose,
            solution: self.solution,
            plan: self.plan,
            hand_over: self.hand_over,
            solved: self.solved,
            torque: self.torque.flatten(),
        }
    }

    /// One slice: the target's holding torques, or [`PoseCheck::per_slice`] more poses of the
    /// path. `None` while poses remain, `Some(Ok)` if the whole path is clear, `Some(Err)` at
    /// the first pose that is not (or if the target's torques exceed the ratings).
    pub fn step<M: Math>(&mut self, check: PoseCheck<'_>) -> Option<Result<(), Error>> {
        if self.torque.is_none() {
            // The target's holding torques first, in a slice of their own.
            return match self.target_torque::<M>(check) {
                Ok(torque) => {
                    self.torque = Some(torque);
                    None
                }
                Err(e) => Some(Err(e)),
            };
        }
        self.check_slice::<M>(check)
    }

    /// The first slice of a path check: the target's holding torques, if there is a payload
    /// to check against ratings (refused if one is exceeded) or to report (`check`);
    /// `Ok(None)` otherwise.
    fn target_torque<M: Math>(&self, check: PoseCheck<'_>) -> Result<Option<Torques>, Error> {
        let payload = &check.settings.payload;
        let report = self.purpose == Purpose::Check && payload.carried();
        if !self.purpose.needs_target_torque(check.settings) {
            return Ok(None);
        }
        let torques = payload.holding_torques_kgcm::<M>(
            check.solver,
            self.plan.target(),
            &self.solution.arm_rad,
        );
        if payload.checked() {
            match torques {
                Ok(t) => payload.within_ratings(&t)?,
                Err(e) => return Err(TorqueError::Unknown(e).into()),
            }
        }
        Ok(report.then_some(torques))
    }

    /// Checks [`PoseCheck::per_slice`] more poses of the path: `None` if poses remain,
    /// `Some(Ok)` if the whole path is clear, `Some(Err)` at the first that is not.
    fn check_slice<M: Math>(&mut self, check: PoseCheck<'_>) -> Option<Result<(), Error>> {
        let torque = check.settings.payload.checked();
        let per_slice = check.per_slice();
        let target = *self.plan.target();
        let mut solved = 0;
        if let Some(turns) = &mut self.frame_turns {
            if turns.last.is_none() {
                // The arm angles where the plan starts, to measure its first frame from.
                solved += 1;
                self.solved += 1;
                let start = self.plan.start();
                match check.pose::<M>(&start, false) {
                    Ok(there) => turns.last = Some((0.0, there.arm_rad)),
                    Err(cause) => {
                        return Some(Err(Error::PathBlocked {
                            percent: 0.0,
                            cause,
                        }))
                    }
                }
            }
        }
        while solved < per_slice {
            let Some((pose, fraction)) = self.checkpoints.next_checkpoint() else {
                return if self.planned_again() || self.tightened() {
                    None // the new plan's poses are checked next
                } else {
                    Some(Ok(()))
                };
            };
            // Compared bit for bit (float comparisons are library calls on the RP2040): a pose
            // equal but for the sign of a zero is solved again, never one less.
            if same_bits(&pose, &target) {
                // Checked when the command came and in the first slice.
                let arm_rad = self.solution.arm_rad;
                self.measure(&check.settings.servo_speed, &pose, fraction, &arm_rad);
                continue;
            }
            solved += 1;
            self.solved += 1;
            match check.pose::<M>(&pose, torque) {
                Ok(solution) => {
                    let arm_rad = solution.arm_rad;
                    self.measure(&check.settings.servo_speed, &pose, fraction, &arm_rad);
                }
                Err(cause) => {
                    return Some(Err(Error::PathBlocked {
                        percent: fraction.get() * 100.0,
                        cause,
                    }))
                }
            }
        }
        None
    }

    /// With servo speed ratings, on the first pass: the path time measured at one more pose of
    /// the path (in order), from its IK solution's arm angles.
    fn measure(
        &mut self,
        speeds: &ServoSpeeds,
        pose: &Pose,
        fraction: Fraction,
        arm_rad: &[f32; LEGS],
    ) {
        if let Some(time) = &mut self.servo_time {
            time.measured.visit(speeds, pose, arm_rad);
        }
        if let Some(turns) = &mut self.frame_turns {
            turns.visit(speeds, &self.plan, fraction.get(), arm_rad);
        }
    }

    /// At the end of a pass over a move taken over while moving with servo speed ratings: if
    /// an arm turned faster than its rating, the limits tightened and the plan marked stale
    /// (the controller plans it again, slower, from the motion as it is then: true); false if
    /// the plan stands.
    fn tightened(&mut self) -> bool {
        let Some(next) = self.frame_turns.and_then(|t| t.tightened(&self.plan)) else {
            return false;
        };
        self.frame_turns = Some(next);
        self.replan = true;
        true
    }

    /// At the end of the first pass with servo speed ratings: if the path needs longer than the
    /// move was planned for, the move planned again for the time measured, its checkpoints to
    /// be checked next (true); false if the plan stands (or this was the second pass).
    fn planned_again(&mut self) -> bool {
        let Some(time) = self.servo_time.take() else {
            return false;
        };
        let measured_s = time.measured.time_s();
        if measured_s <= time.planned_s {
            return false;
        }
        // Only straight moves from where the platform is are measured this way (a move taken
        // over while moving is measured frame by frame: `FrameTurns`).
        let Plan::Straight(planned) = self.plan else {
            return false;
        };
        let (start, target) = (*planned.start(), *planned.target());
        let limits = ServoSpeeds::capped_limits(time.limits, &start, &target, measured_s);
        let segment = Segment::plan(start, target, limits, time.frame_hz);
        if segment == planned {
            return false;
        }
        self.plan = Plan::Straight(segment);
        self.checkpoints = self.plan.checkpoints();
        true
    }
}

/// Whether two poses are the same bit for bit (a float comparison is a library call on the
/// RP2040; this stops at the first coordinate that differs, usually the first).
fn same_bits(a: &Pose, b: &Pose) -> bool {
    a.x_mm.to_bits() == b.x_mm.to_bits()
        && a.y_mm.to_bits() == b.y_mm.to_bits()
        && a.z_mm.to_bits() == b.z_mm.to_bits()
        && a.roll_rad.to_bits() == b.roll_rad.to_bits()
        && a.pitch_rad.to_bits() == b.pitch_rad.to_bits()
        && a.yaw_rad.to_bits() == b.yaw_rad.to_bits()
}
