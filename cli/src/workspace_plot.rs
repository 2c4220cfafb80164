//! `hexapod workspace`'s picture: three plots of where the platform reaches within its servo
//! limits (the IK the test, `crate::size` the searches): x-y sections at several heights, the
//! vertical travel at each roll and pitch, the reach along each axis from home. Lengths in mm,
//! angles in degrees; each plotted item carries its numbers in `data-*` attributes.

use kinematics_core::ik::IkError;
use kinematics_core::pose::Axis;
use kinematics_core::workspace::Reach;

use crate::picture::{Anchor, Scene, Shape, Style};
use crate::plot::{self, Axes, PALETTE};
use crate::size::{reach_from_home, section, travel_grid, Platform};

/// The three workspace plots in one picture.
pub fn scene(platform: &Platform) -> Scene {
    let mut scene = Scene::new(1560.0, 560.0);
    scene.text(
        "title",
        [14.0, 26.0],
        &workspace_title(&platform.source),
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
    axes.draw(&mut scene, SECTIONS_TITLE, "x (mm)", "y (mm)");
    let mut entries = Vec::new();
    for (k, (z, points)) in sections.iter().enumerate() {
        let colour = PALETTE[k];
        match points {
            Some(points) => {
                let mut closed = points.clone();
                closed.push(points[0]);
                axes.line(&mut scene, "section", &closed, Style::stroke(colour, 2.0));
                entries.push((colour, section_label(*z, true), false));
            }
            None => entries.push((colour, section_label(*z, false), true)),
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
        TRAVEL_TITLE,
        "roll (degrees)",
        "pitch (degrees)",
    );
    plot::colour_bar(
        &mut scene,
        [1000.0, 90.0],
        360.0,
        0.0,
        f64::from(most),
        TRAVEL_UNIT,
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
    axes.draw(&mut scene, REACH_TITLE, REACH_UNIT, "");
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
            &axis_with_unit(axis),
            12.0,
            Anchor::End,
        );
        scene.text(
            "reach-value",
            [b[0] + 4.0, axes.px(0.0, y)[1] + 4.0],
            &reach_span(-display(minus), display(plus)),
            10.0,
            Anchor::Start,
        );
    }
    plot::legend(
        &mut scene,
        [axes.left + 10.0, axes.top + axes.height + 48.0],
        &[
            (PALETTE[0], TRANSLATIONS.to_string(), false),
            (PALETTE[1], ROTATIONS.to_string(), false),
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

// ----- the picture's words -----

/// The workspace picture's title.
fn workspace_title(source: &str) -> String {
    format!("Workspace of {source}: reachable within the servo limits")
}
/// Plot titles and axis labels of `workspace`.
const SECTIONS_TITLE: &str = "x-y sections, level, at heights z";
/// See [`SECTIONS_TITLE`].
const TRAVEL_TITLE: &str = "vertical travel at each roll and pitch (x = y = yaw = 0)";
/// See [`SECTIONS_TITLE`].
const TRAVEL_UNIT: &str = "z travel (mm); grey: none";
/// See [`SECTIONS_TITLE`].
const REACH_TITLE: &str = "reach from home along each axis";
/// See [`SECTIONS_TITLE`].
const REACH_UNIT: &str = "mm (x y z) or degrees (roll pitch yaw)";
/// See [`SECTIONS_TITLE`].
const TRANSLATIONS: &str = "translation (mm)";
/// See [`SECTIONS_TITLE`].
const ROTATIONS: &str = "rotation (degrees)";

/// A section's legend entry.
fn section_label(z_mm: f32, reachable: bool) -> String {
    if reachable {
        format!("z = {z_mm} mm")
    } else {
        format!("z = {z_mm} mm: not reachable")
    }
}

/// An axis with its unit.
fn axis_with_unit(axis: kinematics_core::pose::Axis) -> String {
    let unit = if axis.is_angle() { "deg" } else { "mm" };
    format!("{} ({unit})", axis.name())
}

/// A reach's span.
fn reach_span(lo: f32, hi: f32) -> String {
    format!("{lo:.1} .. {hi:.1}")
}
