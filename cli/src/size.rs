//! The numbers of `describe`, `workspace` and `torque`: a platform sized before it is built,
//! with the kinematics toolkit (`kinematics-core`): the IK with the servo limits as the test of what is
//! reachable, `workspace::Limits` for the reach along each axis, `statics` for stiffness and
//! the holding torques of a payload, `dynamics::actuation` for the torques along a trajectory
//! (inertia included). Nothing here re-derives the kinematics.
//!
//! The payload and the servos' torque ratings are the board's settings (`payload_g`,
//! `payload_com_*_mm`, `servoN.torque_kgcm`), and so are the holding torques: computed by the
//! board's own code (`control::payload::PayloadSettings`), judged against a rating by the
//! board's rule (over when the torque's magnitude exceeds it; a servo without a rating is never
//! over). Only the servos' stiffness is the host's (`[sizing]`).
//!
//! Units: mm, degrees for what users read (rad inside), s; torques in kgf cm
//! (`statics::N_MM_PER_KGF_CM`), like servo ratings. The words both `describe` and `torque`
//! write (a pose, the payload, the ratings' verdict) are at the end; the plots are
//! `workspace_plot` and `torque_plot`, each subcommand's own text its `cmd/` file's.

use std::path::Path;

use control::payload::PayloadSettings;
use control::report::kinematics_refusal;
use control::settings::Settings;
use kinematics_core::dynamics::{actuation, Acceleration};
use kinematics_core::ik::{IkError, Solver};
use kinematics_core::jacobian::Jacobian;
use kinematics_core::pose::Axis;
use kinematics_core::rates::Twist;
use kinematics_core::statics::{self, N_MM_PER_KGF_CM};
use kinematics_core::workspace::{self, Grid, Limit, Limits, Reach};
use kinematics_core::{Libm, Pose, LEGS};

use crate::build_file::{self, DEFAULT_PLATFORM};
use crate::error::{board_words, Error, KeyError};
use crate::sizing::Sizing;
use crate::trajectory::Row;

/// A platform to size: its settings (the board's, payload and ratings included) and sizing
/// (the host's).
#[derive(Debug, Clone, PartialEq)]
pub struct Platform {
    /// Where it comes from (a file, or the default platform).
    pub source: String,
    /// The board's settings.
    pub settings: Settings,
    /// The servos' stiffness.
    pub sizing: Sizing,
    /// The IK of its geometry.
    pub solver: Solver,
}

impl Platform {
    /// The platform of a build file, or the default platform.
    pub fn load(build: Option<&Path>) -> Result<Platform, Error> {
        let (source, settings, sizing) = match build {
            Some(path) => {
                let file = build_file::read(path)?;
                (path.display().to_string(), file.settings, file.sizing)
            }
            None => (
                DEFAULT_PLATFORM.to_string(),
                Settings::default(),
                Sizing::default(),
            ),
        };
        // A build file's settings are valid (checked as it was read); the defaults are.
        let solver = settings.validate().map_err(|e| Error::Key {
            file: source.clone(),
            line: 0,
            key: String::new(),
            why: KeyError::Refused(Box::new(e.into())),
        })?;
        Ok(Platform {
            source,
            settings,
            sizing,
            solver,
        })
    }

    /// Whether the platform takes a pose within its servo limits.
    pub fn reachable(&self, pose: &Pose) -> Result<[f32; LEGS], IkError> {
        self.solver
            .solve::<Libm>(&self.settings.servos, pose)
            .map(|s| s.arm_rad)
    }

    /// The payload and the ratings (the board's settings).
    pub fn payload(&self) -> &PayloadSettings {
        &self.settings.payload
    }

    /// The holding torques of the payload at a pose, kgf cm (positive lifting the arm), as the
    /// board computes them for `check` and `status`.
    pub fn holding_kgcm(&self, pose: &Pose) -> Option<[f32; LEGS]> {
        let arm_rad = self.reachable(pose).ok()?;
        self.payload()
            .holding_torques_kgcm::<Libm>(&self.solver, pose, &arm_rad)
            .ok()
    }

    /// A servo's torque (kgf cm) against its rating.
    pub fn verdict(&self, servo: u8, torque_kgcm: f32) -> Verdict {
        let i = usize::from(servo - 1);
        let rating_kgcm = self.payload().torque_kgcm[i];
        if rating_kgcm <= 0.0 {
            return Verdict::NotRated;
        }
        let percent = 100.0 * torque_kgcm.abs() / rating_kgcm;
        // The board's rule, for this servo alone (the others need nothing).
        let mut alone = [0.0; LEGS];
        alone[i] = torque_kgcm;
        if self.payload().within_ratings(&alone).is_ok() {
            Verdict::Within {
                rating_kgcm,
                percent,
            }
        } else {
            Verdict::Over {
                rating_kgcm,
                percent,
            }
        }
    }
}

/// A servo's torque against its rating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Verdict {
    /// The servo has no rating (`servoN.torque_kgcm` off): the board checks nothing.
    NotRated,
    /// Within the rating: the torque is this many percent of it.
    Within {
        /// The rating, kgf cm.
        rating_kgcm: f32,
        /// The torque's magnitude, percent of the rating.
        percent: f32,
    },
    /// Over the rating: the board refuses such a pose.
    Over {
        /// The rating, kgf cm.
        rating_kgcm: f32,
        /// The torque's magnitude, percent of the rating.
        percent: f32,
    },
}

/// The reach along the twelve axis-directions from home (x-, x+, ..., yaw-, yaw+).
pub fn reach_from_home(platform: &Platform) -> [Reach<IkError>; 12] {
    let mut limits = Limits::new(Pose::HOME, workspace::Options::default());
    loop {
        if let Some(found) = limits.step(|p| platform.reachable(p).map(|_| ())) {
            return found;
        }
    }
}

/// The worst holding torque over a set of poses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Worst {
    /// Servo 1..=6.
    pub servo: u8,
    /// The torque, kgf cm (signed).
    pub torque_kgcm: f32,
    /// Where.
    pub pose: Pose,
    /// When (along a trajectory), s; and the row's line.
    pub at: Option<(f64, u64)>,
}

/// The poses of the sizing grid: 9 points along each translation (x, y, z, level) and each
/// rotation (roll, pitch, yaw, at home height), over the reach from home.
pub fn sizing_grid(reach: &[Reach<IkError>; 12]) -> Vec<Pose> {
    let half = |axis: Axis| {
        let k = axis as usize;
        reach[2 * k].distance.max(reach[2 * k + 1].distance)
    };
    let grid = |axes: [Axis; 3]| Grid {
        centre: Pose::HOME,
        axes,
        half_range: axes.map(half),
        counts: [9, 9, 9],
    };
    let mut poses: Vec<Pose> = grid([Axis::X, Axis::Y, Axis::Z]).poses().collect();
    poses.extend(grid([Axis::Roll, Axis::Pitch, Axis::Yaw]).poses());
    poses
}

/// Each servo's largest holding torque (by magnitude) over the poses the platform reaches, and
/// how many it reaches.
pub fn worst_per_servo(platform: &Platform, poses: &[Pose]) -> ([Option<Worst>; LEGS], usize) {
    let mut worst: [Option<Worst>; LEGS] = [None; LEGS];
    let mut reached = 0;
    for pose in poses {
        let Some(torques) = platform.holding_kgcm(pose) else {
            continue;
        };
        reached += 1;
        for (i, &t) in torques.iter().enumerate() {
            if worst[i].is_none_or(|w| t.abs() > w.torque_kgcm.abs()) {
                worst[i] = Some(Worst {
                    servo: i as u8 + 1,
                    torque_kgcm: t,
                    pose: *pose,
                    at: None,
                });
            }
        }
    }
    (worst, reached)
}

/// The worst of all servos.
pub fn overall(worst: &[Option<Worst>]) -> Option<Worst> {
    worst
        .iter()
        .flatten()
        .copied()
        .max_by(|a, b| a.torque_kgcm.abs().total_cmp(&b.torque_kgcm.abs()))
}

/// Everything `describe` says, computed.
#[derive(Debug, Clone)]
pub struct Description {
    /// The platform.
    pub platform: Platform,
    /// Leg lengths from shaft to platform joint at home, mm.
    pub leg_lengths_mm: [f32; LEGS],
    /// The reach from home.
    pub reach: [Reach<IkError>; 12],
    /// The stiffness's diagonal at home: x, y, z in N/mm, roll, pitch, yaw in N mm/rad.
    pub stiffness_diagonal: Option<[f32; 6]>,
    /// What the payload needs (`None` without one: `payload_g` 0).
    pub holding: Option<Holding>,
}

/// What holding the payload takes: `describe`'s payload section.
#[derive(Debug, Clone)]
pub struct Holding {
    /// How far the payload's weight moves the platform at home: mm, and rad.
    pub sag: Option<statics::Displacement>,
    /// Holding torques at home, kgf cm.
    pub home_kgcm: Option<[f32; LEGS]>,
    /// Each servo's worst holding torque over the sizing grid.
    pub per_servo: [Option<Worst>; LEGS],
    /// Poses of the grid reached, and in it.
    pub grid_reached: (usize, usize),
}

/// `describe`'s numbers.
pub fn describe(platform: Platform) -> Description {
    let anchors = platform.solver.anchors();
    let home = anchors.place::<Libm>(&Pose::HOME);
    let leg_lengths_mm = core::array::from_fn(|i| (home.joints_mm[i] - anchors.base_mm[i]).norm());
    let reach = reach_from_home(&platform);
    let k = [platform.sizing.servo_stiffness_nmm_rad; LEGS];
    let stiffness = Jacobian::at::<Libm, Solver>(&platform.solver, &Pose::HOME)
        .and_then(|j| statics::stiffness(&j, &k))
        .ok();
    let stiffness_diagonal = stiffness.map(|s| core::array::from_fn(|i| s[(i, i)]));
    let holding = platform.payload().carried().then(|| {
        let weight = platform
            .payload()
            .payload()
            .gravity_wrench::<Libm>(&home, anchors.rotation_centre_mm);
        let grid = sizing_grid(&reach);
        let (per_servo, reached) = worst_per_servo(&platform, &grid);
        Holding {
            sag: statics::displacement::<Libm, Solver>(&platform.solver, &Pose::HOME, &k, &weight)
                .ok(),
            home_kgcm: platform.holding_kgcm(&Pose::HOME),
            per_servo,
            grid_reached: (reached, grid.len()),
        }
    });
    Description {
        leg_lengths_mm,
        reach,
        stiffness_diagonal,
        holding,
        platform,
    }
}

// ----- workspace -----

/// How far the platform reaches from `from` along a direction (unit, in pose coordinates: mm
/// and rad), up to `limit`: bisection to 0.01 mm (or rad), the IK with servo limits the test.
pub fn reach_along(platform: &Platform, from: &Pose, direction: [f32; 6], limit: f32) -> f32 {
    let at = |d: f32| {
        let base = from.to_array();
        Pose::from_array(core::array::from_fn(|i| base[i] + direction[i] * d))
    };
    if platform.reachable(from).is_err() {
        return 0.0;
    }
    // March out to the first failure, then bisect.
    let step = limit / 40.0;
    let mut inside = 0.0;
    let mut outside = limit;
    let mut d = step;
    while d <= limit {
        if platform.reachable(&at(d)).is_err() {
            outside = d;
            break;
        }
        inside = d;
        d += step;
    }
    if outside == limit && inside >= limit - step {
        return inside;
    }
    while outside - inside > 0.01 {
        let mid = (inside + outside) / 2.0;
        if platform.reachable(&at(mid)).is_ok() {
            inside = mid;
        } else {
            outside = mid;
        }
    }
    inside
}

/// The x-y section of the workspace at height `z_mm` (level): its edge as points, mm, every 4
/// degrees around the centre; `None` if the platform cannot be there at all.
pub fn section(platform: &Platform, z_mm: f32, limit_mm: f32) -> Option<Vec<[f64; 2]>> {
    let centre = Pose::from_degrees(0.0, 0.0, z_mm, 0.0, 0.0, 0.0);
    platform.reachable(&centre).ok()?;
    Some(
        (0..90)
            .map(|k| {
                let t = (k as f32 * 4.0).to_radians();
                let r = reach_along(
                    platform,
                    &centre,
                    [t.cos(), t.sin(), 0.0, 0.0, 0.0, 0.0],
                    limit_mm,
                );
                [f64::from(r * t.cos()), f64::from(r * t.sin())]
            })
            .collect(),
    )
}

/// The vertical travel (mm) at each roll and pitch (degrees) of a square grid, at x = y = yaw =
/// 0: the span of the z values reachable, scanned in 0.5 mm steps over +-`z_limit_mm`.
pub fn travel_grid(
    platform: &Platform,
    tilt_deg: f32,
    count: usize,
    z_limit_mm: f32,
) -> Vec<(f32, f32, f32)> {
    let mut cells = Vec::with_capacity(count * count);
    for i in 0..count {
        for j in 0..count {
            let roll = -tilt_deg + 2.0 * tilt_deg * i as f32 / (count - 1) as f32;
            let pitch = -tilt_deg + 2.0 * tilt_deg * j as f32 / (count - 1) as f32;
            let steps = (2.0 * z_limit_mm / 0.5) as usize;
            let mut lo = f32::MAX;
            let mut hi = f32::MIN;
            for s in 0..=steps {
                let z = -z_limit_mm + 0.5 * s as f32;
                if platform
                    .reachable(&Pose::from_degrees(0.0, 0.0, z, roll, pitch, 0.0))
                    .is_ok()
                {
                    lo = lo.min(z);
                    hi = hi.max(z);
                }
            }
            cells.push((roll, pitch, if hi >= lo { hi - lo } else { -1.0 }));
        }
    }
    cells
}

/// What stops a reach, in the board's words.
pub fn limit_words(limit: &Limit<IkError>) -> String {
    match limit {
        Limit::Blocked(e) | Limit::Start(e) => board_words(&(*e).into()),
        Limit::Range => SEARCH_RANGE.to_string(),
    }
}

// ----- torque -----

/// The torques along a trajectory: per row, each servo's torque (kgf cm), gravity and inertia.
pub fn trajectory_torques(
    platform: &Platform,
    rows: &[Row],
) -> Result<Vec<[f32; LEGS]>, (u64, String)> {
    let poses: Vec<Pose> = rows
        .iter()
        .map(|r| {
            let [x, y, z, roll, pitch, yaw] = r.pose.map(|v| v as f32);
            Pose::from_degrees(x, y, z, roll, pitch, yaw)
        })
        .collect();
    let n = rows.len();
    // Pose rates by central differences (one-sided at the ends), mm/s and rad/s.
    let rate = |i: usize| -> [f32; 6] {
        let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
        if a == b {
            return [0.0; 6];
        }
        let dt = (rows[b].time_s - rows[a].time_s) as f32;
        let (pa, pb) = (poses[a].to_array(), poses[b].to_array());
        core::array::from_fn(|k| (pb[k] - pa[k]) / dt)
    };
    let twists: Vec<Twist> = (0..n)
        .map(|i| Twist::from_pose_rate::<Libm>(&poses[i], &rate(i)))
        .collect();
    let payload = platform.payload().payload();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let acceleration = if a == b {
                Acceleration::ZERO
            } else {
                let dt = (rows[b].time_s - rows[a].time_s) as f32;
                Acceleration {
                    linear_mm_s2: (twists[b].linear_mm_s - twists[a].linear_mm_s) / dt,
                    angular_rad_s2: (twists[b].angular_rad_s - twists[a].angular_rad_s) / dt,
                }
            };
            actuation::<Libm, Solver>(
                &platform.solver,
                &poses[i],
                &payload,
                &twists[i],
                &acceleration,
            )
            .map(|t| t.map(|nmm| nmm / N_MM_PER_KGF_CM))
            .map_err(|e| (rows[i].line, kinematics_refusal(&e).to_string()))
        })
        .collect()
}

/// Each servo's largest torque (by magnitude) along a trajectory.
pub fn worst_along(rows: &[Row], torques: &[[f32; LEGS]]) -> [Option<Worst>; LEGS] {
    let mut worst: [Option<Worst>; LEGS] = [None; LEGS];
    for (row, t) in rows.iter().zip(torques) {
        for (i, &v) in t.iter().enumerate() {
            if worst[i].is_none_or(|w| v.abs() > w.torque_kgcm.abs()) {
                let [x, y, z, roll, pitch, yaw] = row.pose.map(|v| v as f32);
                worst[i] = Some(Worst {
                    servo: i as u8 + 1,
                    torque_kgcm: v,
                    pose: Pose::from_degrees(x, y, z, roll, pitch, yaw),
                    at: Some((row.time_s, row.line)),
                });
            }
        }
    }
    worst
}

/// The servos that have a rating, grouped by rating (kgf cm), in servo order: each rating with
/// its servos (1..=6).
pub fn ratings(platform: &Platform) -> Vec<(f32, Vec<usize>)> {
    let mut groups: Vec<(f32, Vec<usize>)> = Vec::new();
    for (i, &rating) in platform.payload().torque_kgcm.iter().enumerate() {
        if rating <= 0.0 {
            continue;
        }
        match groups.iter_mut().find(|(r, _)| *r == rating) {
            Some((_, servos)) => servos.push(i + 1),
            None => groups.push((rating, vec![i + 1])),
        }
    }
    groups
}

/// The platform's joints' height at home, for tests: h0, mm.
pub fn home_height_mm(platform: &Platform) -> f32 {
    platform.solver.geometry().home_height_mm()
}

// ----- words shared by describe and torque -----

/// What stops a search that found no limit.
const SEARCH_RANGE: &str = "nothing within the search range (100 mm, 180 degrees)";

/// A pose in words: mm and degrees, one decimal.
pub fn pose_words(pose: &Pose) -> String {
    let [x, y, z, roll, pitch, yaw] = pose.to_array();
    format!(
        "x={x:.1} y={y:.1} z={z:.1} mm, roll={:.1} pitch={:.1} yaw={:.1} degrees",
        roll.to_degrees(),
        pitch.to_degrees(),
        yaw.to_degrees()
    )
}

/// Servos `1, 2, 4` as words: `servo 2`, `servos 1, 2, 4`, `servos 1-6`.
pub fn servo_list(servos: &[usize]) -> String {
    match servos {
        [one] => format!("servo {one}"),
        [1, 2, 3, 4, 5, 6] => "servos 1-6".to_string(),
        _ => {
            let numbers: Vec<String> = servos.iter().map(ToString::to_string).collect();
            format!("servos {}", numbers.join(", "))
        }
    }
}

/// The payload: its mass and centre of mass.
pub fn payload_words(payload: &PayloadSettings) -> String {
    let [x, y, z] = payload.com_mm;
    format!(
        "{} g at ({x}, {y}, {z}) mm in the platform frame",
        payload.mass_g
    )
}

/// Every servo's worst torque against its rating, in a line: which are over, or the one
/// nearest its rating; the servos without one.
pub fn ratings_summary(p: &Platform, per_servo: &[Option<Worst>; 6]) -> String {
    let head = "ratings (servoN.torque_kgcm):";
    let unrated: Vec<usize> = (1..=6)
        .filter(|&n| p.verdict(n as u8, 0.0) == Verdict::NotRated)
        .collect();
    if unrated.len() == 6 {
        return format!("{head} the servos are not rated: torques without a verdict");
    }
    let judged: Vec<(u8, f32, Verdict)> = per_servo
        .iter()
        .flatten()
        .map(|w| {
            let t = w.torque_kgcm.abs();
            (w.servo, t, p.verdict(w.servo, t))
        })
        .collect();
    let over: Vec<String> = judged
        .iter()
        .filter_map(|&(servo, t, v)| match v {
            Verdict::Over {
                rating_kgcm,
                percent,
            } => Some(format!(
                "servo {servo} needs {t:.3} kgf cm, rated {rating_kgcm} ({percent:.0}%)"
            )),
            _ => None,
        })
        .collect();
    let mut out = if !over.is_empty() {
        format!("{head} OVER: {}", over.join("; "))
    } else {
        let nearest = judged
            .iter()
            .filter_map(|&(servo, t, v)| match v {
                Verdict::Within {
                    rating_kgcm,
                    percent,
                } => Some((servo, t, rating_kgcm, percent)),
                _ => None,
            })
            .max_by(|a, b| a.3.total_cmp(&b.3));
        match nearest {
            Some((servo, t, rating, percent)) => format!(
                "{head} all within: servo {servo} nearest its rating, {t:.3} of {rating} kgf cm \
                 ({percent:.0}%)"
            ),
            None => format!("{head} no torque to judge (no reachable pose)"),
        }
    };
    if !unrated.is_empty() {
        out += &format!("; {} not rated", servo_list(&unrated));
    }
    out
}
