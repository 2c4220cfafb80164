//! `hexapod torque`'s pictures: bars of each servo's worst holding torque over the sizing grid,
//! or lines of each servo's torque along a trajectory; each servo's rating (`torque_kgcm`) as a
//! dashed mark where it has one. Torques in kgf cm, time in s; each bar and mark carries its
//! numbers in `data-*` attributes.

use control::payload::PayloadSettings;
use kinematics_core::LEGS;

use crate::picture::{Anchor, Scene, Shape, Style};
use crate::plot::{self, Axes, PALETTE};
use crate::size::{ratings, servo_list, Platform, Verdict, Worst};
use crate::trajectory::Row;

/// Bars: each servo's worst holding torque over the grid, each against its own rating (a
/// dashed mark over its bar; none where it has no rating).
pub fn grid_scene(platform: &Platform, worst: &[Option<Worst>; LEGS]) -> Scene {
    let mut scene = Scene::new(860.0, 480.0);
    let rated = platform.payload().torque_kgcm.map(f64::from);
    let top = worst
        .iter()
        .flatten()
        .map(|w| f64::from(w.torque_kgcm.abs()))
        .chain(rated)
        .fold(0.01, f64::max);
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
        &grid_torque_title(&platform.source, platform.payload()),
        SERVO_AXIS,
        TORQUE_AXIS,
    );
    for (i, w) in worst.iter().enumerate() {
        let x = i as f64 + 1.0;
        let value = w.map_or(0.0, |w| w.torque_kgcm.abs());
        let a = axes.px(x - 0.3, f64::from(value));
        let b = axes.px(x + 0.3, 0.0);
        let over = matches!(platform.verdict(i as u8 + 1, value), Verdict::Over { .. });
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
        if rated[i] > 0.0 {
            let left = axes.px(x - 0.45, rated[i]);
            let right = axes.px(x + 0.45, rated[i]);
            let item = scene.add(
                "rating",
                Shape::Line(left, right),
                Style::stroke("#d00000", 2.0).dashed(),
            );
            item.data.extend([
                ("servo".to_string(), (i + 1).to_string()),
                ("kgf-cm".to_string(), format!("{:.2}", rated[i])),
            ]);
        }
    }
    let mut entries = vec![(PALETTE[0], WORST_HOLDING.to_string(), false)];
    let groups = ratings(platform);
    if groups.is_empty() {
        entries.push(("#bbbbbb", NOT_RATED.to_string(), false));
    } else {
        entries.push(("#d55e00", OVER_RATING.to_string(), false));
        entries.extend(
            groups
                .into_iter()
                .map(|(r, servos)| ("#d00000", rating_label(r, &servos), true)),
        );
    }
    plot::legend(
        &mut scene,
        [axes.left + axes.width + 20.0, axes.top + 10.0],
        &entries,
    );
    scene
}

/// Lines: each servo's torque against time along a trajectory, and each rating either way.
pub fn trajectory_scene(
    platform: &Platform,
    file: &str,
    rows: &[Row],
    torques: &[[f32; LEGS]],
) -> Scene {
    let mut scene = Scene::new(990.0, 480.0);
    let groups = ratings(platform);
    let top = torques
        .iter()
        .flatten()
        .map(|t| f64::from(t.abs()))
        .chain(groups.iter().map(|(r, _)| f64::from(*r)))
        .fold(0.01, f64::max)
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
        &trajectory_torque_title(file, platform.payload()),
        TIME_AXIS,
        TORQUE_AXIS,
    );
    let mut entries = Vec::new();
    for i in 0..LEGS {
        let points: Vec<[f64; 2]> = rows
            .iter()
            .zip(torques)
            .map(|(r, t)| [r.time_s, f64::from(t[i])])
            .collect();
        axes.line(
            &mut scene,
            "torque",
            &points,
            Style::stroke(PALETTE[i], 1.6),
        );
        entries.push((PALETTE[i], servo_label(i + 1), false));
    }
    for (rating, servos) in &groups {
        for sign in [1.0, -1.0] {
            let y = axes.px(0.0, sign * f64::from(*rating))[1];
            let item = scene.add(
                "rating",
                Shape::Line([axes.left, y], [axes.left + axes.width, y]),
                Style::stroke("#d00000", 1.5).dashed(),
            );
            item.data.push((
                "kgf-cm".to_string(),
                format!("{:.2}", sign * f64::from(*rating)),
            ));
        }
        entries.push(("#d00000", rating_label(*rating, servos), true));
    }
    if groups.is_empty() {
        entries.push(("#bbbbbb", NOT_RATED.to_string(), false));
    }
    plot::legend(
        &mut scene,
        [axes.left + axes.width + 20.0, axes.top + 10.0],
        &entries,
    );
    scene
}

// ----- the pictures' words -----

/// Torque plots' words.
const SERVO_AXIS: &str = "servo";
/// See [`SERVO_AXIS`].
const TORQUE_AXIS: &str = "torque (kgf cm)";
/// See [`SERVO_AXIS`].
const TIME_AXIS: &str = "time (s)";
/// See [`SERVO_AXIS`].
const WORST_HOLDING: &str = "worst holding torque";
/// See [`SERVO_AXIS`].
const OVER_RATING: &str = "over the rating";

/// A rating's legend entry: the rating and its servos.
fn rating_label(kgcm: f32, servos: &[usize]) -> String {
    format!("rating {kgcm} kgf cm ({})", servo_list(servos))
}

/// The legend of a torque plot without ratings.
const NOT_RATED: &str = "servos not rated (torque_kgcm off)";

/// A servo's legend entry.
fn servo_label(servo: usize) -> String {
    format!("servo {servo}")
}

/// The grid torque plot's title.
fn grid_torque_title(source: &str, payload: &PayloadSettings) -> String {
    format!(
        "{source}: holding {} g over the workspace grid",
        payload.mass_g
    )
}

/// The trajectory torque plot's title.
fn trajectory_torque_title(file: &str, payload: &PayloadSettings) -> String {
    format!(
        "{file}: torques carrying {} g (gravity and inertia)",
        payload.mass_g
    )
}
