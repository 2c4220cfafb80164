//! A picture of a platform at a pose (`hexapod draw`), in four views (top, front, side and
//! perspective), like the architecture plot of the Stewart platform Simscape model
//! documentation: base plate, servo bodies and arms, rods, the platform plate, the base and
//! platform frames, leg and servo numbers.
//!
//! Every position comes from the kinematics toolkit: the IK's arm angles
//! (`Solver::arm_angles`), and the arm tips and platform joints at them
//! (`legs::ArmState::at_angles`, eq. 2 and 4-6 of "The Mathematics of the Stewart Platform").
//! A pose the platform cannot take is still drawn, at the requested pose, with the failing leg
//! or servo marked in red and the board's words for why: the platform where it was asked to be,
//! the arms at the last pose the IK accepts on the straight way there from home (found by
//! bisection), so the failing leg's rod visibly does not meet its joint.
//!
//! Lengths are mm in the model and px in the picture; a view's px per mm and origin are in its
//! panel's `data-*` attributes, and each joint, tip and shaft carries its mm coordinates.

use control::settings::Settings;
use kinematics_core::ik::{IkError, Solver};
use kinematics_core::legs::ArmState;
use kinematics_core::{Libm, Pose, Vec3, LEGS};

use crate::error::board_words;
use crate::picture::{Anchor, Scene, Shape, Style};

/// A view: how a point in the base frame (mm) lands on the panel (mm, y down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum View {
    /// Looking down: x right, y up.
    Top,
    /// Looking along +y: x right, z up.
    Front,
    /// Looking along -x: y right, z up.
    Side,
    /// From the front left, above, in perspective.
    Perspective,
}

impl View {
    /// All four, in panel order.
    pub const ALL: [View; 4] = [View::Top, View::Front, View::Side, View::Perspective];

    /// Its name (the panel's `data-view`).
    pub fn name(self) -> &'static str {
        match self {
            View::Top => "top",
            View::Front => "front",
            View::Side => "side",
            View::Perspective => "perspective",
        }
    }

    /// A point of the base frame projected onto the view, mm, y down; and its distance from the
    /// viewer (for the perspective).
    pub fn project(self, p: Vec3, eye_distance_mm: f64) -> [f64; 2] {
        let (x, y, z) = (f64::from(p.x), f64::from(p.y), f64::from(p.z));
        match self {
            View::Top => [x, -y],
            View::Front => [x, -z],
            View::Side => [y, -z],
            View::Perspective => {
                // Camera at azimuth -55 degrees (front left), 25 degrees above the horizon.
                let (az, el) = ((-55f64).to_radians(), 25f64.to_radians());
                // Right and up unit vectors of the camera, and the viewing direction.
                let right = [-az.sin(), az.cos(), 0.0];
                let forward = [-el.cos() * az.cos(), -el.cos() * az.sin(), -el.sin()];
                let up = [
                    right[1] * forward[2] - right[2] * forward[1],
                    right[2] * forward[0] - right[0] * forward[2],
                    right[0] * forward[1] - right[1] * forward[0],
                ];
                let dot = |a: [f64; 3]| a[0] * x + a[1] * y + a[2] * (z - 60.0);
                let depth = eye_distance_mm + dot(forward);
                let f = eye_distance_mm / depth.max(1.0);
                [f * dot(right), -f * dot(up)]
            }
        }
    }
}

/// What the picture shows about the pose.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// The platform takes it.
    Reachable,
    /// It cannot: the leg or servo at fault (1..=6), the board's words, and how far along the
    /// way from home the arms are drawn (0..=1).
    Refused {
        /// The leg (unreachable) or servo (beyond its limits) at fault.
        leg: u8,
        /// The board's words.
        words: String,
        /// Where the arms are drawn: the last accepted fraction of the way.
        arms_at: f64,
    },
}

/// The platform at a pose, in millimetres (base frame).
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    /// Servo shaft centres `b_i`.
    pub shafts: [Vec3; LEGS],
    /// Arm tips.
    pub tips: [Vec3; LEGS],
    /// Platform joints `q_i` at the requested pose.
    pub joints: [Vec3; LEGS],
    /// The platform frame's origin and axes (unit vectors).
    pub platform_origin: Vec3,
    /// The platform frame's axes, base frame.
    pub platform_axes: [Vec3; 3],
    /// The pivot (the rotation centre, `pivot_*_mm`), base frame; `None` at the platform
    /// frame's origin (the default, not marked).
    pub pivot: Option<Vec3>,
    /// Each arm plane's horizontal direction (cos beta, sin beta).
    pub arm_directions: [[f32; 2]; LEGS],
    /// Arm length a and rod length s.
    pub arm_mm: f32,
    /// See `arm_mm`.
    pub rod_mm: f32,
    /// The platform's joint circle radius and the base's shaft circle radius.
    pub platform_radius_mm: f32,
    /// See `platform_radius_mm`.
    pub base_radius_mm: f32,
    /// Whether the pose can be taken.
    pub verdict: Verdict,
}

/// The model of a platform at a pose; `Err` with the board's words if the settings are not
/// a platform or the pose is not a pose (angles beyond 180 degrees, not finite).
pub fn model(settings: &Settings, pose: &Pose) -> Result<Model, String> {
    let solver: Solver = settings.validate().map_err(|e| board_words(&e.into()))?;
    kinematics_core::ik::check_pose(pose).map_err(|e| board_words(&e.into()))?;
    let (arm_rad, verdict) = match solver.solve::<Libm>(&settings.servos, pose) {
        Ok(solution) => (solution.arm_rad, Verdict::Reachable),
        Err(error) => {
            let leg = match error {
                IkError::Unreachable { leg } => leg,
                IkError::ServoLimit { servo, .. } => servo,
                _ => 0,
            };
            let words = board_words(&error.into());
            // The last pose on the way from home whose arm angles the IK gives.
            let along = |t: f64| {
                let home = Pose::HOME.to_array();
                let to = pose.to_array();
                Pose::from_array(core::array::from_fn(|i| {
                    home[i] + (to[i] - home[i]) * t as f32
                }))
            };
            let (mut inside, mut outside) = (0.0, 1.0);
            let mut arms = solver
                .arm_angles::<Libm>(&Pose::HOME)
                .map_err(|e| e.to_string())?;
            if let Ok(at_pose) = solver.arm_angles::<Libm>(pose) {
                // Reachable, but beyond a servo's limits: the arms are where the pose puts them.
                arms = at_pose;
                inside = 1.0;
            } else {
                for _ in 0..30 {
                    let mid = (inside + outside) / 2.0;
                    match solver.arm_angles::<Libm>(&along(mid)) {
                        Ok(a) => {
                            inside = mid;
                            arms = a;
                        }
                        Err(_) => outside = mid,
                    }
                }
            }
            (
                arms,
                Verdict::Refused {
                    leg,
                    words,
                    arms_at: inside,
                },
            )
        }
    };
    let state = ArmState::at_angles::<Libm>(&solver, pose, arm_rad);
    let rotation = state.placement.rotation;
    let platform_origin = state.placement.centre_mm - rotation * solver.rotation_centre_mm();
    let geometry = solver.geometry();
    Ok(Model {
        shafts: core::array::from_fn(|i| geometry.leg(i).base_mm),
        tips: state.tips_mm,
        joints: state.placement.joints_mm,
        platform_origin,
        platform_axes: core::array::from_fn(|i| rotation.column(i).into_owned()),
        pivot: (settings.pivot_mm != [0.0; 3]).then_some(state.placement.centre_mm),
        arm_directions: core::array::from_fn(|i| solver.arm_plane(i)),
        arm_mm: geometry.arm_mm(),
        rod_mm: geometry.rod_mm(),
        platform_radius_mm: settings.layout.platform_radius_mm,
        base_radius_mm: settings.layout.base_radius_mm,
        verdict,
    })
}

/// A servo body: the eight corners of a box around the shaft (standard servo proportions
/// scaled to the arm: 2a long in the arm's plane, a wide along the shaft, 1.9a tall, the shaft
/// near its top and one end, on the side of the arm's plane towards the base's centre).
fn servo_box(model: &Model, i: usize) -> [Vec3; 8] {
    let a = model.arm_mm;
    let b = model.shafts[i];
    let [c, s] = model.arm_directions[i];
    let along = Vec3::new(c, s, 0.0);
    let mut shaft_axis = Vec3::new(-s, c, 0.0);
    if shaft_axis.dot(&(-b)) < 0.0 {
        shaft_axis = -shaft_axis;
    }
    let up = Vec3::new(0.0, 0.0, 1.0);
    let (length, width, height) = (2.0 * a, a, 1.9 * a);
    let gap = 0.15 * a;
    core::array::from_fn(|k| {
        let l = if k & 1 == 0 {
            -0.3 * length
        } else {
            0.7 * length
        };
        let w = if k & 2 == 0 { gap } else { gap + width };
        let h = if k & 4 == 0 {
            -0.75 * height
        } else {
            0.25 * height
        };
        b + along * l + shaft_axis * w + up * h
    })
}

/// The z of the base plate's top (under the servos), mm.
fn base_plate_z(model: &Model) -> f32 {
    -0.75 * 1.9 * model.arm_mm
}

/// Every point the picture shows (to fit the views).
fn all_points(model: &Model) -> Vec<Vec3> {
    let mut points: Vec<Vec3> = Vec::new();
    points.extend(model.shafts);
    points.extend(model.tips);
    points.extend(model.joints);
    for i in 0..LEGS {
        points.extend(servo_box(model, i));
    }
    points.extend(base_plate(model));
    // The frames' axes.
    let axis_mm = axis_length_mm(model);
    points.extend([Vec3::x(), Vec3::y(), Vec3::z()].map(|u| u * axis_mm));
    points.extend(
        model
            .platform_axes
            .map(|u| model.platform_origin + u * axis_mm),
    );
    points.extend(model.pivot);
    points
}

/// How long the frames' axes are drawn, mm.
fn axis_length_mm(model: &Model) -> f32 {
    0.35 * model.platform_radius_mm
}

/// The base plate's outline (a circle around the servos), mm.
fn base_plate(model: &Model) -> Vec<Vec3> {
    let r = model.base_radius_mm + 1.6 * model.arm_mm;
    let z = base_plate_z(model);
    (0..48)
        .map(|k| {
            let t = k as f32 / 48.0 * std::f32::consts::TAU;
            Vec3::new(r * t.cos(), r * t.sin(), z)
        })
        .collect()
}

/// Panel size, px.
const PANEL: [f64; 2] = [480.0, 400.0];
/// Room for the title above the panels, px.
const HEADER_PX: f64 = 76.0;

const RED: &str = "#d00000";

// The picture's words.

/// A view's title.
fn view_title(view: View) -> &'static str {
    match view {
        View::Top => "top (looking down; x right, y up)",
        View::Front => "front (looking along +y; x right, z up)",
        View::Side => "side (looking along -x; y right, z up)",
        View::Perspective => "perspective",
    }
}

/// A scale bar's label.
fn scale_bar(mm: f64) -> String {
    format!("{mm:.0} mm")
}

/// A drawing's title.
fn drawing_title(pose: &str) -> String {
    format!("pose {pose}  (x y z mm, roll pitch yaw degrees)")
}

/// The pivot's label.
const PIVOT_LABEL: &str = "pivot";

/// A drawing of a pose the platform takes.
const DRAWING_REACHABLE: &str = "reachable: every leg reaches its joint within its servo's limits";

/// A drawing of a pose the platform cannot take: its lines.
fn drawing_refused(words: &str, arms_at: f64) -> Vec<String> {
    let mut lines = vec![format!("refused: {words}")];
    if arms_at < 1.0 {
        lines.push(format!(
            "the arms are drawn at the last reachable pose on the straight way from home ({:.0}% \
             of the way); the dashed rod cannot meet its joint",
            arms_at * 100.0
        ));
    }
    lines
}

/// The picture of a model: four panels and a header with the pose and the verdict.
pub fn scene(model: &Model, pose_text: &str) -> Scene {
    let mut scene = Scene::new(2.0 * PANEL[0], HEADER_PX + 2.0 * PANEL[1]);
    scene.text(
        "title",
        [12.0, 24.0],
        &drawing_title(pose_text),
        18.0,
        Anchor::Start,
    );
    let (verdict_lines, colour) = match &model.verdict {
        Verdict::Reachable => (vec![DRAWING_REACHABLE.to_string()], "#1a7f37"),
        Verdict::Refused { words, arms_at, .. } => (drawing_refused(words, *arms_at), RED),
    };
    for (k, text) in verdict_lines.into_iter().enumerate() {
        scene.add(
            "verdict",
            Shape::Text {
                at: [12.0, 46.0 + 18.0 * k as f64],
                text,
                size_px: 13.0,
                anchor: Anchor::Start,
                rotate_deg: 0.0,
            },
            Style::fill(colour),
        );
    }
    let eye = 6.0 * f64::from(model.base_radius_mm + model.rod_mm);
    for (k, view) in View::ALL.into_iter().enumerate() {
        let left = (k % 2) as f64 * PANEL[0];
        let top = HEADER_PX + (k / 2) as f64 * PANEL[1];
        panel(&mut scene, model, view, [left, top], eye);
    }
    scene
}

/// One view in the panel whose top left corner is `corner` (px).
fn panel(scene: &mut Scene, model: &Model, view: View, corner: [f64; 2], eye: f64) {
    // Fit every point with a margin.
    let projected: Vec<[f64; 2]> = all_points(model)
        .into_iter()
        .map(|p| view.project(p, eye))
        .collect();
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    for p in &projected {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let (margin, title) = (36.0, 26.0);
    let scale = ((PANEL[0] - 2.0 * margin) / (hi[0] - lo[0]))
        .min((PANEL[1] - 2.0 * margin - title) / (hi[1] - lo[1]));
    let origin = [
        corner[0] + PANEL[0] / 2.0 - scale * (lo[0] + hi[0]) / 2.0,
        corner[1] + title + (PANEL[1] - title) / 2.0 - scale * (lo[1] + hi[1]) / 2.0,
    ];
    let px = |p: Vec3| {
        let q = view.project(p, eye);
        [origin[0] + scale * q[0], origin[1] + scale * q[1]]
    };
    let frame = scene.add(
        "panel",
        Shape::Path {
            points: vec![
                corner,
                [corner[0] + PANEL[0], corner[1]],
                [corner[0] + PANEL[0], corner[1] + PANEL[1]],
                [corner[0], corner[1] + PANEL[1]],
            ],
            closed: true,
        },
        Style::stroke("#bbb", 1.0),
    );
    frame.data.extend([
        ("view".to_string(), view.name().to_string()),
        ("px-per-mm".to_string(), format!("{scale:.6}")),
        ("origin-x".to_string(), format!("{:.4}", origin[0])),
        ("origin-y".to_string(), format!("{:.4}", origin[1])),
    ]);
    scene.text(
        "view-title",
        [corner[0] + 10.0, corner[1] + 20.0],
        view_title(view),
        14.0,
        Anchor::Start,
    );
    let mm = |p: Vec3| {
        vec![
            ("x-mm".to_string(), format!("{:.3}", p.x)),
            ("y-mm".to_string(), format!("{:.3}", p.y)),
            ("z-mm".to_string(), format!("{:.3}", p.z)),
        ]
    };
    let failing = match model.verdict {
        Verdict::Refused { leg, .. } => Some(usize::from(leg)),
        Verdict::Reachable => None,
    };
    // Base plate.
    scene.add(
        "base-plate",
        Shape::Path {
            points: base_plate(model).into_iter().map(px).collect(),
            closed: true,
        },
        Style::fill("#e4e4e4").outlined("#999", 1.0),
    );
    // Servo bodies: their faces, far ones first (roughly: by the face centre's depth).
    const FACES: [[usize; 4]; 6] = [
        [0, 1, 3, 2],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 3, 7, 5],
    ];
    for i in 0..LEGS {
        let corners = servo_box(model, i);
        let bad = failing == Some(i + 1);
        for face in FACES {
            let item = scene.add(
                "servo",
                Shape::Path {
                    points: face.iter().map(|&k| px(corners[k])).collect(),
                    closed: true,
                },
                Style::fill(if bad { "#f2b8b8" } else { "#9fb3d6" })
                    .outlined(if bad { RED } else { "#3b5b92" }, 0.8)
                    .opacity(0.55),
            );
            item.data.push(("servo".into(), (i + 1).to_string()));
        }
    }
    // Platform plate: the polygon through the joints.
    scene.add(
        "platform-plate",
        Shape::Path {
            points: model.joints.iter().map(|&q| px(q)).collect(),
            closed: true,
        },
        Style::fill("#6fa8dc")
            .outlined("#2f6aa3", 1.2)
            .opacity(0.35),
    );
    for i in 0..LEGS {
        let bad = failing == Some(i + 1);
        let (b, a, q) = (model.shafts[i], model.tips[i], model.joints[i]);
        let arm = scene.add(
            "arm",
            Shape::Line(px(b), px(a)),
            Style::stroke(if bad { RED } else { "#222" }, 3.0),
        );
        arm.data.push(("servo".into(), (i + 1).to_string()));
        arm.data.extend(mm(a));
        let mut rod_style = Style::stroke(if bad { RED } else { "#c07a00" }, 2.0);
        if bad {
            rod_style = rod_style.dashed();
        }
        let rod = scene.add("rod", Shape::Line(px(a), px(q)), rod_style);
        rod.data.push(("leg".into(), (i + 1).to_string()));
        let shaft = scene.add("shaft", Shape::Circle(px(b), 2.5), Style::fill("#222"));
        shaft.data.push(("servo".into(), (i + 1).to_string()));
        shaft.data.extend(mm(b));
        let joint = scene.add(
            "joint",
            Shape::Circle(px(q), if bad { 5.0 } else { 3.0 }),
            Style::fill(if bad { RED } else { "#2f6aa3" }),
        );
        joint.data.push(("leg".into(), (i + 1).to_string()));
        joint.data.extend(mm(q));
    }
    // Frames: base at the origin, platform at its origin; x red, y green, z blue.
    let axis_mm = axis_length_mm(model);
    let units = [Vec3::x(), Vec3::y(), Vec3::z()];
    for (class, origin_mm, axes, names) in [
        ("base-frame", Vec3::zeros(), units, ["x", "y", "z"]),
        (
            "platform-frame",
            model.platform_origin,
            model.platform_axes,
            ["x'", "y'", "z'"],
        ),
    ] {
        for (k, (axis, colour)) in axes
            .iter()
            .zip(["#d62728", "#2ca02c", "#1f77b4"])
            .enumerate()
        {
            let tip = origin_mm + axis * axis_mm;
            let (from, to) = (px(origin_mm), px(tip));
            if (to[0] - from[0]).hypot(to[1] - from[1]) < 3.0 {
                continue; // seen end on
            }
            scene.add(class, Shape::Line(from, to), Style::stroke(colour, 2.0));
            scene.add(
                class,
                Shape::Text {
                    at: [to[0] + 3.0, to[1] - 3.0],
                    text: names[k].to_string(),
                    size_px: 11.0,
                    anchor: Anchor::Start,
                    rotate_deg: 0.0,
                },
                Style::fill(colour),
            );
        }
    }
    // The pivot: a ring with its name, and its mm coordinates.
    if let Some(pivot) = model.pivot {
        let at = px(pivot);
        let ring = scene.add(
            "pivot",
            Shape::Circle(at, 5.0),
            Style::stroke("#7b2fa3", 2.0),
        );
        ring.data.extend(mm(pivot));
        scene.add(
            "pivot",
            Shape::Text {
                at: [at[0] + 8.0, at[1] - 6.0],
                text: PIVOT_LABEL.to_string(),
                size_px: 11.0,
                anchor: Anchor::Start,
                rotate_deg: 0.0,
            },
            Style::fill("#7b2fa3"),
        );
    }
    // Numbers: the leg beside its rod's middle, the servo beside its shaft (away from the
    // centre of the picture's base).
    let centre = px(Vec3::zeros());
    for i in 0..LEGS {
        let bad = failing == Some(i + 1);
        let mid = px((model.tips[i] + model.joints[i]) / 2.0);
        let leg = scene.add(
            "leg-number",
            Shape::Text {
                at: [mid[0] + 5.0, mid[1] + 4.0],
                text: (i + 1).to_string(),
                size_px: 13.0,
                anchor: Anchor::Start,
                rotate_deg: 0.0,
            },
            Style::fill(if bad { RED } else { "#8a5200" }),
        );
        leg.data.push(("leg".into(), (i + 1).to_string()));
        if matches!(view, View::Front | View::Side) {
            continue; // the servos stand in line there: their numbers would overlap
        }
        let s = px(model.shafts[i]);
        let (dx, dy) = (s[0] - centre[0], s[1] - centre[1]);
        let d = dx.hypot(dy).max(1.0);
        let servo = scene.add(
            "servo-number",
            Shape::Text {
                at: [s[0] + 22.0 * dx / d, s[1] + 22.0 * dy / d + 4.0],
                text: format!("S{}", i + 1),
                size_px: 11.0,
                anchor: Anchor::Middle,
                rotate_deg: 0.0,
            },
            Style::fill(if bad { RED } else { "#3b5b92" }),
        );
        servo.data.push(("servo".into(), (i + 1).to_string()));
    }
    // A scale bar (not in perspective, where scale varies with depth).
    if view != View::Perspective {
        let bar_mm = if scale * 50.0 > 160.0 { 20.0 } else { 50.0 };
        let y = corner[1] + PANEL[1] - 14.0;
        let x0 = corner[0] + PANEL[0] - 20.0 - bar_mm * scale;
        scene.add(
            "scale-bar",
            Shape::Line([x0, y], [x0 + bar_mm * scale, y]),
            Style::stroke("#444", 2.0),
        );
        scene.text(
            "scale-bar",
            [x0 + bar_mm * scale / 2.0, y - 5.0],
            &scale_bar(bar_mm),
            11.0,
            Anchor::Middle,
        );
    }
}
