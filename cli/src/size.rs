//! `describe`, `workspace` and `torque`: a platform sized before it is built, with the
//! kinematics toolkit (`kinematics-core`): the IK with the servo limits as the test of what is
//! reachable, `workspace::Limits` for the reach along each axis, `statics` for stiffness and
//! the holding torques of a payload, `dynamics::actuation` for the torques along a trajectory
//! (inertia included). Nothing here re-derives the kinematics.
//!
//! Units: mm, degrees for what users read (rad inside), s; torques N mm inside and kgf cm
//! (`statics::N_MM_PER_KGF_CM`) in reports, like servo ratings.

use std::path::Path;

use control::settings::Settings;
use kinematics_core::dynamics::{actuation, Acceleration};
use kinematics_core::ik::{IkError, Solver};
use kinematics_core::jacobian::Jacobian;
use kinematics_core::pose::Axis;
use kinematics_core::rates::Twist;
use kinematics_core::statics::{self, servo_holding_torques, N_MM_PER_KGF_CM};
use kinematics_core::workspace::{self, Grid, Limit, Limits, Reach};
use kinematics_core::{Libm, Pose, Vec3, LEGS};

use crate::configure::read_build_file;
use crate::draw::write_scene;
use crate::messages::{self, Problem};
use crate::picture::{Anchor, Scene, Shape, Style};
use crate::plot::{self, Axes, PALETTE};
use crate::sizing::Sizing;
use crate::trajectory::{self, Mode, Row};

/// A platform to size: its settings (the board's) and sizing (the host's).
#[derive(Debug, Clone, PartialEq)]
pub struct Platform {
    /// Where it comes from (a file, or the default platform).
    pub source: String,
    /// The board's settings.
    pub settings: Settings,
    /// Payload and servo rating.
    pub sizing: Sizing,
    /// The IK of its geometry.
    pub solver: Solver,
}

impl Platform {
    /// The platform of a build file, or the default platform.
    pub fn load(build: Option<&Path>) -> Result<Platform, Problem> {
        let (source, settings, sizing) = match build {
            Some(path) => {
                let file = read_build_file(path)?;
                (path.display().to_string(), file.settings, file.sizing)
            }
            None => (
                messages::DEFAULT_PLATFORM.to_string(),
                Settings::default(),
                Sizing::default(),
            ),
        };
        // A build file's settings are valid (checked as it was read); the defaults are.
        let solver = settings.validate().map_err(|e| Problem::Key {
            file: source.clone(),
            line: 0,
            key: String::new(),
            why: messages::KeyProblem::Refused(Box::new(e.into())),
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

    /// The holding torques of the payload at a pose, N mm (positive lifting the arm).
    pub fn holding_nmm(&self, pose: &Pose) -> Option<[f32; LEGS]> {
        let arm_rad = self.reachable(pose).ok()?;
        servo_holding_torques::<Libm>(&self.solver, pose, &arm_rad, &self.sizing.payload()).ok()
    }
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
    /// The torque, N mm (signed).
    pub torque_nmm: f32,
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
        let Some(torques) = platform.holding_nmm(pose) else {
            continue;
        };
        reached += 1;
        for (i, &t) in torques.iter().enumerate() {
            if worst[i].is_none_or(|w| t.abs() > w.torque_nmm.abs()) {
                worst[i] = Some(Worst {
                    servo: i as u8 + 1,
                    torque_nmm: t,
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
        .max_by(|a, b| a.torque_nmm.abs().total_cmp(&b.torque_nmm.abs()))
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
    /// How far the payload's weight moves the platform at home: mm, and rad.
    pub sag: Option<statics::Displacement>,
    /// Holding torques at home, N mm.
    pub home_torques_nmm: Option<[f32; LEGS]>,
    /// The worst holding torque over the sizing grid, and how many of its poses are reachable
    /// out of how many.
    pub worst: Option<Worst>,
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
    let payload = platform.sizing.payload();
    let weight = payload.gravity_wrench::<Libm>(&home, anchors.rotation_centre_mm);
    let sag =
        statics::displacement::<Libm, Solver>(&platform.solver, &Pose::HOME, &k, &weight).ok();
    let home_torques_nmm = platform.holding_nmm(&Pose::HOME);
    let grid = sizing_grid(&reach);
    let (per_servo, reached) = worst_per_servo(&platform, &grid);
    Description {
        leg_lengths_mm,
        reach,
        stiffness_diagonal,
        sag,
        home_torques_nmm,
        worst: overall(&per_servo),
        grid_reached: (reached, grid.len()),
        platform,
    }
}

/// `hexapod describe`.
pub fn describe_command(build: Option<&Path>) -> Result<String, Problem> {
    Ok(messages::description(&describe(Platform::load(build)?)))
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

/// The three workspace plots in one picture.
pub fn workspace_scene(platform: &Platform) -> Scene {
    let mut scene = Scene::new(1560.0, 560.0);
    scene.text(
        "title",
        [14.0, 26.0],
        &messages::workspace_title(&platform.source),
        17.0,
        Anchor::Start,
    );
    let reach = reach_from_home(platform);
    // 1. x-y sections at several heights.
    let heights = [-10.0f32, -5.0, 0.0, 5.0, 10.0];
    let limit = reach
        .iter()
        .filter(|r| !r.axis.is_angle())
        .map(|r| r.distance)
        .fold(10.0f32, f32::max)
        * 1.2;
    let sections: Vec<(f32, Option<Vec<[f64; 2]>>)> = heights
        .iter()
        .map(|&z| (z, section(platform, z, limit)))
        .collect();
    let extent = sections
        .iter()
        .filter_map(|(_, s)| s.as_ref())
        .flatten()
        .fold(5.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()));
    let (lo, hi) = plot::nice_range(-extent, extent);
    let axes = Axes {
        left: 80.0,
        top: 80.0,
        width: 380.0,
        height: 380.0,
        x: (lo, hi),
        y: (lo, hi),
        y_ticks: true,
    };
    axes.draw(&mut scene, messages::SECTIONS_TITLE, "x (mm)", "y (mm)");
    let mut entries = Vec::new();
    for (k, (z, points)) in sections.iter().enumerate() {
        let colour = PALETTE[k];
        match points {
            Some(points) => {
                let mut closed = points.clone();
                closed.push(points[0]);
                axes.line(&mut scene, "section", &closed, Style::stroke(colour, 2.0));
                entries.push((colour, messages::section_label(*z, true), false));
            }
            None => entries.push((colour, messages::section_label(*z, false), true)),
        }
    }
    plot::legend(&mut scene, [axes.left + 10.0, axes.top + 14.0], &entries);

    // 2. Vertical travel against roll and pitch.
    let tilt = 20.0;
    let count = 21;
    let cells = travel_grid(platform, tilt, count, limit.max(20.0));
    let most = cells.iter().map(|c| c.2).fold(1.0f32, f32::max);
    let axes = Axes {
        left: 600.0,
        top: 80.0,
        width: 380.0,
        height: 380.0,
        x: (-f64::from(tilt), f64::from(tilt)),
        y: (-f64::from(tilt), f64::from(tilt)),
        y_ticks: true,
    };
    let cell = 2.0 * f64::from(tilt) / (count - 1) as f64;
    for &(roll, pitch, travel) in &cells {
        let (r, p) = (f64::from(roll), f64::from(pitch));
        let a = axes.px(
            (r - cell / 2.0).max(axes.x.0),
            (p - cell / 2.0).max(axes.y.0),
        );
        let b = axes.px(
            (r + cell / 2.0).min(axes.x.1),
            (p + cell / 2.0).min(axes.y.1),
        );
        let fill = if travel < 0.0 {
            "#bbbbbb"
        } else {
            plot::colour_scale(f64::from(travel / most))
        };
        let item = scene.add(
            "travel",
            Shape::Path {
                points: vec![[a[0], a[1]], [b[0], a[1]], [b[0], b[1]], [a[0], b[1]]],
                closed: true,
            },
            Style::fill(fill),
        );
        item.data.extend([
            ("roll-deg".to_string(), format!("{roll:.2}")),
            ("pitch-deg".to_string(), format!("{pitch:.2}")),
            ("travel-mm".to_string(), format!("{travel:.2}")),
        ]);
    }
    axes.draw(
        &mut scene,
        messages::TRAVEL_TITLE,
        "roll (degrees)",
        "pitch (degrees)",
    );
    plot::colour_bar(
        &mut scene,
        [1000.0, 90.0],
        360.0,
        0.0,
        f64::from(most),
        messages::TRAVEL_UNIT,
    );

    // 3. Reach along each axis from home.
    let farthest = reach
        .iter()
        .map(|r| f64::from(display(r)))
        .fold(1.0, f64::max);
    let axes = Axes {
        left: 1180.0,
        top: 80.0,
        width: 340.0,
        height: 380.0,
        x: plot::nice_range(-farthest, farthest),
        y: (0.0, 6.0),
        y_ticks: false,
    };
    axes.draw(&mut scene, messages::REACH_TITLE, messages::REACH_UNIT, "");
    for (k, axis) in Axis::ALL.into_iter().enumerate() {
        let (minus, plus) = (&reach[2 * k], &reach[2 * k + 1]);
        let y = 5.5 - k as f64;
        let a = axes.px(-f64::from(display(minus)), y + 0.3);
        let b = axes.px(f64::from(display(plus)), y - 0.3);
        let item = scene.add(
            "reach",
            Shape::Path {
                points: vec![[a[0], a[1]], [b[0], a[1]], [b[0], b[1]], [a[0], b[1]]],
                closed: true,
            },
            Style::fill(PALETTE[if axis.is_angle() { 1 } else { 0 }]).opacity(0.8),
        );
        item.data.extend([
            ("axis".to_string(), axis.name().to_string()),
            ("min".to_string(), format!("{:.3}", -display(minus))),
            ("max".to_string(), format!("{:.3}", display(plus))),
        ]);
        scene.text(
            "reach-label",
            [axes.left - 8.0, axes.px(0.0, y)[1] + 4.0],
            &messages::axis_with_unit(axis),
            12.0,
            Anchor::End,
        );
        scene.text(
            "reach-value",
            [b[0] + 4.0, axes.px(0.0, y)[1] + 4.0],
            &messages::reach_span(-display(minus), display(plus)),
            10.0,
            Anchor::Start,
        );
    }
    plot::legend(
        &mut scene,
        [axes.left + 10.0, axes.top + axes.height + 48.0],
        &[
            (PALETTE[0], messages::TRANSLATIONS.to_string(), false),
            (PALETTE[1], messages::ROTATIONS.to_string(), false),
        ],
    );
    scene
}

/// A reach in the unit users read: mm or degrees.
fn display(reach: &Reach<IkError>) -> f32 {
    if reach.axis.is_angle() {
        reach.distance.to_degrees()
    } else {
        reach.distance
    }
}

/// What stops a reach, in the board's words.
pub fn limit_words(limit: &Limit<IkError>) -> String {
    match limit {
        Limit::Blocked(e) | Limit::Start(e) => messages::board_words(&(*e).into()),
        Limit::Range => messages::SEARCH_RANGE.to_string(),
    }
}

/// `hexapod workspace`.
pub fn workspace_command(
    build: Option<&Path>,
    stem: &Path,
    svg: bool,
    png: bool,
) -> Result<String, Problem> {
    let platform = Platform::load(build)?;
    let written = write_scene(&workspace_scene(&platform), stem, svg, png)?;
    Ok(messages::wrote_pictures(&written))
}

// ----- torque -----

/// The torques along a trajectory: per row, each servo's torque (N mm), gravity and inertia.
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
    let payload = platform.sizing.payload();
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
            .map_err(|e| (rows[i].line, messages::kinematics_words(&e)))
        })
        .collect()
}

/// `hexapod torque`: over the sizing grid, or along a trajectory.
pub fn torque_command(
    build: Option<&Path>,
    trajectory_file: Option<&Path>,
    stem: &Path,
    svg: bool,
    png: bool,
) -> Result<String, Problem> {
    let platform = Platform::load(build)?;
    let (scene, report) = match trajectory_file {
        None => {
            let reach = reach_from_home(&platform);
            let grid = sizing_grid(&reach);
            let (worst, reached) = worst_per_servo(&platform, &grid);
            let report = messages::grid_torque_report(&platform, &worst, reached, grid.len());
            (grid_torque_scene(&platform, &worst), report)
        }
        Some(path) => {
            let file = path.display().to_string();
            let rows = trajectory::read(path)?;
            trajectory::prepare(&file, &rows, &platform.settings, Mode::Text)?;
            let torques =
                trajectory_torques(&platform, &rows).map_err(|(line, why)| Problem::Row {
                    file: file.clone(),
                    line,
                    field: None,
                    why: messages::RowProblem::Refused(why),
                })?;
            let mut worst: Option<Worst> = None;
            for (row, t) in rows.iter().zip(&torques) {
                for (i, &v) in t.iter().enumerate() {
                    if worst.is_none_or(|w| v.abs() > w.torque_nmm.abs()) {
                        let [x, y, z, roll, pitch, yaw] = row.pose.map(|v| v as f32);
                        worst = Some(Worst {
                            servo: i as u8 + 1,
                            torque_nmm: v,
                            pose: Pose::from_degrees(x, y, z, roll, pitch, yaw),
                            at: Some((row.time_s, row.line)),
                        });
                    }
                }
            }
            let report = messages::trajectory_torque_report(&file, &platform, worst, rows.len());
            (
                trajectory_torque_scene(&platform, &file, &rows, &torques),
                report,
            )
        }
    };
    let written = write_scene(&scene, stem, svg, png)?;
    Ok(format!("{report}\n{}", messages::wrote_pictures(&written)))
}

fn kgcm(nmm: f32) -> f64 {
    f64::from(nmm / N_MM_PER_KGF_CM)
}

/// Bars: each servo's worst holding torque over the grid, against the rating.
fn grid_torque_scene(platform: &Platform, worst: &[Option<Worst>; LEGS]) -> Scene {
    let mut scene = Scene::new(760.0, 480.0);
    let rating = f64::from(platform.sizing.servo_torque_kgcm);
    let top = worst
        .iter()
        .flatten()
        .map(|w| kgcm(w.torque_nmm).abs())
        .fold(rating, f64::max);
    let axes = Axes {
        left: 90.0,
        top: 60.0,
        width: 460.0,
        height: 340.0,
        x: (0.5, 6.5),
        y: plot::nice_range(0.0, top * 1.1),
        y_ticks: true,
    };
    axes.draw(
        &mut scene,
        &messages::grid_torque_title(&platform.source, &platform.sizing),
        messages::SERVO_AXIS,
        messages::TORQUE_AXIS,
    );
    for (i, w) in worst.iter().enumerate() {
        let x = i as f64 + 1.0;
        let value = w.map_or(0.0, |w| kgcm(w.torque_nmm).abs());
        let a = axes.px(x - 0.3, value);
        let b = axes.px(x + 0.3, 0.0);
        let over = value > rating;
        let item = scene.add(
            "torque-bar",
            Shape::Path {
                points: vec![[a[0], a[1]], [b[0], a[1]], [b[0], b[1]], [a[0], b[1]]],
                closed: true,
            },
            Style::fill(if over { "#d55e00" } else { PALETTE[0] }).opacity(0.85),
        );
        item.data.extend([
            ("servo".to_string(), (i + 1).to_string()),
            ("kgf-cm".to_string(), format!("{value:.4}")),
        ]);
        scene.text(
            "bar-value",
            [(a[0] + b[0]) / 2.0, a[1] - 5.0],
            &format!("{value:.2}"),
            11.0,
            Anchor::Middle,
        );
    }
    let y = axes.px(0.0, rating)[1];
    scene.add(
        "rating",
        Shape::Line([axes.left, y], [axes.left + axes.width, y]),
        Style::stroke("#d00000", 2.0).dashed(),
    );
    plot::legend(
        &mut scene,
        [axes.left + axes.width + 20.0, axes.top + 10.0],
        &[
            (PALETTE[0], messages::WORST_HOLDING.to_string(), false),
            ("#d55e00", messages::OVER_RATING.to_string(), false),
            (
                "#d00000",
                messages::rating_label(platform.sizing.servo_torque_kgcm),
                true,
            ),
        ],
    );
    scene
}

/// Lines: each servo's torque against time along a trajectory, and the rating either way.
fn trajectory_torque_scene(
    platform: &Platform,
    file: &str,
    rows: &[Row],
    torques: &[[f32; LEGS]],
) -> Scene {
    let mut scene = Scene::new(900.0, 480.0);
    let rating = f64::from(platform.sizing.servo_torque_kgcm);
    let top = torques
        .iter()
        .flatten()
        .map(|t| kgcm(*t).abs())
        .fold(rating, f64::max)
        * 1.1;
    let (t0, t1) = (
        rows[0].time_s,
        rows[rows.len() - 1].time_s.max(rows[0].time_s + 1e-3),
    );
    let axes = Axes {
        left: 90.0,
        top: 60.0,
        width: 600.0,
        height: 340.0,
        x: (t0, t1),
        y: plot::nice_range(-top, top),
        y_ticks: true,
    };
    axes.draw(
        &mut scene,
        &messages::trajectory_torque_title(file, &platform.sizing),
        messages::TIME_AXIS,
        messages::TORQUE_AXIS,
    );
    let mut entries = Vec::new();
    for i in 0..LEGS {
        let points: Vec<[f64; 2]> = rows
            .iter()
            .zip(torques)
            .map(|(r, t)| [r.time_s, kgcm(t[i])])
            .collect();
        axes.line(
            &mut scene,
            "torque",
            &points,
            Style::stroke(PALETTE[i], 1.6),
        );
        entries.push((PALETTE[i], messages::servo_label(i + 1), false));
    }
    for sign in [1.0, -1.0] {
        let y = axes.px(0.0, sign * rating)[1];
        scene.add(
            "rating",
            Shape::Line([axes.left, y], [axes.left + axes.width, y]),
            Style::stroke("#d00000", 1.5).dashed(),
        );
    }
    entries.push((
        "#d00000",
        messages::rating_label(platform.sizing.servo_torque_kgcm),
        true,
    ));
    plot::legend(
        &mut scene,
        [axes.left + axes.width + 20.0, axes.top + 10.0],
        &entries,
    );
    scene
}

/// The platform's joints' height at home, for tests: h0, mm.
pub fn home_height_mm(platform: &Platform) -> f32 {
    platform.solver.geometry().home_height_mm()
}

/// The centre of mass at home, base frame, mm (for the report).
pub fn payload_at_home(platform: &Platform) -> Vec3 {
    let anchors = platform.solver.anchors();
    let placement = anchors.place::<Libm>(&Pose::HOME);
    platform
        .sizing
        .payload()
        .centre_of_mass_at::<Libm>(&placement, anchors.rotation_centre_mm)
}
