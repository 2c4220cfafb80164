//! Built-in trajectories (`hexapod demo`): a circle and a figure eight in the x-y plane, heave,
//! sway and surge sines, and a slow tour of the edge of the reachable x-y section at home
//! height. Each starts and ends at home: its size grows from 0 over the first `ramp_s` and
//! shrinks back over the last (a smooth step), so the platform never jumps.
//!
//! Sizes: `amplitude_mm` is the radius (circle, figure eight, tour: at most this far, and
//! within `edge_fraction` of the reach in each direction) or the sine's amplitude, mm.
//! Times in s, rates in Hz, poses in mm and degrees.

use std::f64::consts::TAU;

use control::settings::Settings;
use kinematics_core::ik::Solver;
use kinematics_core::{Libm, Pose};

use crate::trajectory::Row;

/// Which trajectory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Kind {
    /// A circle in the x-y plane.
    Circle,
    /// A figure eight in the x-y plane (x at the period, y at twice the rate).
    FigureEight,
    /// Up and down (z).
    Heave,
    /// Side to side (y).
    Sway,
    /// Forward and back (x).
    Surge,
    /// Once around the edge of the reachable x-y section at home height, slowly.
    Tour,
}

/// The shape and timing of a demo.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shape {
    /// Which.
    pub kind: Kind,
    /// Size, mm (see the module documentation).
    pub amplitude_mm: f64,
    /// One turn or one sine period, s (the tour takes the whole duration for one turn).
    pub period_s: f64,
    /// Length, s.
    pub duration_s: f64,
    /// Rows per second, Hz.
    pub rate_hz: f64,
    /// Time to grow from home to full size (and back at the end), s.
    pub ramp_s: f64,
    /// The tour stays within this fraction of the reach in each direction.
    pub edge_fraction: f64,
}

/// 0 at home, 1 at full size: a smooth step over the first and last `ramp_s`.
fn envelope(t: f64, duration: f64, ramp: f64) -> f64 {
    let edge = t.min(duration - t).max(0.0);
    if ramp <= 0.0 || edge >= ramp {
        return 1.0;
    }
    let u = edge / ramp;
    u * u * (3.0 - 2.0 * u)
}

/// How far from home the platform reaches along the x-y direction `angle_rad` (at home height
/// and level), mm: the largest distance whose pose the IK accepts with the servo limits, found
/// by bisection to 0.01 mm.
pub fn reach_mm(settings: &Settings, solver: &Solver, angle_rad: f64, limit_mm: f64) -> f64 {
    let ok = |r: f64| {
        let pose = Pose::from_degrees(
            (r * angle_rad.cos()) as f32,
            (r * angle_rad.sin()) as f32,
            0.0,
            0.0,
            0.0,
            0.0,
        );
        solver.solve::<Libm>(&settings.servos, &pose).is_ok()
    };
    let (mut inside, mut outside) = (0.0, limit_mm);
    if ok(outside) {
        return outside;
    }
    while outside - inside > 0.01 {
        let mid = (inside + outside) / 2.0;
        if ok(mid) {
            inside = mid;
        } else {
            outside = mid;
        }
    }
    inside
}

/// The rows of a demo for a platform with these settings (the tour needs its reach).
pub fn rows(shape: &Shape, settings: &Settings) -> Vec<Row> {
    let count = (shape.duration_s * shape.rate_hz).floor() as usize + 1;
    let w = TAU / shape.period_s;
    let solver = settings.validate().ok();
    (0..count)
        .map(|i| {
            let t = i as f64 / shape.rate_hz;
            let e = envelope(t, shape.duration_s, shape.ramp_s);
            let a = shape.amplitude_mm * e;
            let mut pose = [0.0; 6];
            match shape.kind {
                Kind::Circle => {
                    // Starts at home and grows outwards: (sin, 1 - cos) would not be centred.
                    pose[0] = a * (w * t).cos();
                    pose[1] = a * (w * t).sin();
                }
                Kind::FigureEight => {
                    pose[0] = a * (w * t).sin();
                    pose[1] = a / 2.0 * (2.0 * w * t).sin();
                }
                Kind::Heave => pose[2] = a * (w * t).sin(),
                Kind::Sway => pose[1] = a * (w * t).sin(),
                Kind::Surge => pose[0] = a * (w * t).sin(),
                Kind::Tour => {
                    let angle = TAU * t / shape.duration_s;
                    let reach = solver.as_ref().map_or(0.0, |solver| {
                        reach_mm(settings, solver, angle, shape.amplitude_mm)
                    });
                    let r = e * reach * shape.edge_fraction;
                    pose[0] = r * angle.cos();
                    pose[1] = r * angle.sin();
                }
            }
            Row {
                line: i as u64 + 2,
                time_s: t,
                pose,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape(kind: Kind) -> Shape {
        Shape {
            kind,
            amplitude_mm: 10.0,
            period_s: 4.0,
            duration_s: 12.0,
            rate_hz: 50.0,
            ramp_s: 1.0,
            edge_fraction: 0.9,
        }
    }

    #[test]
    fn demos_start_and_end_at_home_and_reach_their_size() {
        for kind in [
            Kind::Circle,
            Kind::FigureEight,
            Kind::Heave,
            Kind::Sway,
            Kind::Surge,
            Kind::Tour,
        ] {
            let rows = rows(&shape(kind), &Settings::default());
            assert_eq!(rows.len(), 601);
            assert_eq!(rows[0].pose, [0.0; 6], "{kind:?}");
            assert!(rows[600].pose.iter().all(|v| v.abs() < 1e-9), "{kind:?}");
            assert!((rows[600].time_s - 12.0).abs() < 1e-9);
            let largest = rows
                .iter()
                .map(|r| r.pose.iter().map(|v| v * v).sum::<f64>().sqrt())
                .fold(0.0, f64::max);
            assert!(
                largest > 8.0 && largest <= 10.0 + 1e-9,
                "{kind:?}: {largest}"
            );
        }
        // The circle keeps its radius once grown.
        let circle = rows(&shape(Kind::Circle), &Settings::default());
        let r = |i: usize| circle[i].pose[0].hypot(circle[i].pose[1]);
        assert!((r(300) - 10.0).abs() < 1e-9);
    }

    #[test]
    fn the_tour_follows_the_edge_of_the_reach() {
        let settings = Settings::default();
        let solver = settings.validate().unwrap();
        // Along +x the default platform reaches some tens of mm, and no further.
        let reach = reach_mm(&settings, &solver, 0.0, 200.0);
        assert!(reach > 10.0 && reach < 200.0, "{reach}");
        let beyond = Pose::from_degrees(reach as f32 + 0.05, 0.0, 0.0, 0.0, 0.0, 0.0);
        assert!(solver.solve::<Libm>(&settings.servos, &beyond).is_err());
        let mut wide = shape(Kind::Tour);
        wide.amplitude_mm = 200.0;
        let rows = rows(&wide, &settings);
        // Half way: the direction is pi, at 0.9 of the reach that way.
        let mid = &rows[300];
        let want = 0.9 * reach_mm(&settings, &solver, std::f64::consts::PI, 200.0);
        assert!(
            (mid.pose[0] + want).abs() < 0.05,
            "{:?} vs {want}",
            mid.pose
        );
    }
}
