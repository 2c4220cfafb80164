//! Keeping the cues inside what the platform can do, so the board never has to clamp a frame:
//!
//! 1. the rotations turned about the pivot (the pilot's head): a rotation `R` about point `c`
//!    is the same rotation about the platform's centre and a translation `(I - R) c`;
//! 2. each axis softly limited ([`soft_limit`]) to `margin` times the smaller of the platform's
//!    reach from home that way (`kinematics_core::workspace::Limits`, the IK with the board's
//!    geometry and servo limits) and the board's stream full scale (`stream.*`);
//! 3. the whole pose then checked with the board's IK, with room to spare: if the pose scaled
//!    by `1 / margin` is out of reach, the pose is scaled towards home until it is not.
//!
//! Poses are mm and degrees, in the board's `pose` order (x, y, z, roll, pitch, yaw).

use control::settings::Settings;
use kinematics_core::ik::Solver;
use kinematics_core::workspace::{self, Limits};
use kinematics_core::{Libm, Pose};

use super::washout::{soft_limit, Cue};

/// Bisection steps when scaling a pose back into reach.
const SCALE_STEPS: usize = 12;

/// The platform's reach, as the cues use it.
#[derive(Debug, Clone)]
pub struct Reach {
    settings: Settings,
    solver: Solver,
    /// Each axis' limit, mm or degrees (symmetric).
    pub limit: [f64; 6],
    /// Fraction of the reach the cues keep within.
    pub margin: f64,
    /// Fraction of the limit where the soft limit bends.
    pub knee: f64,
    /// The pivot, mm.
    pub pivot_mm: [f64; 3],
}

/// A pose in the board's units as the kinematics take it.
pub fn pose_of(cue: &Cue) -> Pose {
    let v = cue.map(|x| x as f32);
    Pose::from_degrees(v[0], v[1], v[2], v[3], v[4], v[5])
}

/// The rotation matrix `Rz(yaw) Ry(pitch) Rx(roll)` (the board's), angles in degrees.
pub fn rotation(roll_deg: f64, pitch_deg: f64, yaw_deg: f64) -> [[f64; 3]; 3] {
    let (sr, cr) = roll_deg.to_radians().sin_cos();
    let (sp, cp) = pitch_deg.to_radians().sin_cos();
    let (sy, cy) = yaw_deg.to_radians().sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

impl Reach {
    /// The reach of a board with these settings, `margin` and `knee` as `[cue]` gives them.
    /// `None` if the settings are not a platform (the board's never are not).
    pub fn new(settings: &Settings, margin: f64, knee: f64, pivot_mm: [f64; 3]) -> Option<Reach> {
        let solver = settings.validate().ok()?;
        let reachable = |p: &Pose| solver.solve::<Libm>(&settings.servos, p).map(|_| ());
        let mut search = Limits::new(Pose::HOME, workspace::Options::default());
        let found = loop {
            if let Some(found) = search.step(reachable) {
                break found;
            }
        };
        let mut limit = [0.0f64; 6];
        for (i, slot) in limit.iter_mut().enumerate() {
            // found: x-, x+, y-, y+, ... (two per axis).
            let reach = found[2 * i].distance.min(found[2 * i + 1].distance);
            let reach = if i < 3 {
                f64::from(reach)
            } else {
                f64::from(reach).to_degrees()
            };
            let full_scale = f64::from(settings.stream.full_scale[i].abs());
            *slot = margin * reach.min(full_scale);
        }
        Some(Reach {
            settings: *settings,
            solver,
            limit,
            margin,
            knee,
            pivot_mm,
        })
    }

    /// Whether the board's IK takes a pose.
    pub fn reachable(&self, cue: &Cue) -> bool {
        self.solver
            .solve::<Libm>(&self.settings.servos, &pose_of(cue))
            .is_ok()
    }

    /// The cue as it is sent, and whether a limit changed it (more than the soft limit's
    /// gentle start, below its knee, would).
    pub fn limit(&self, cue: &Cue) -> (Cue, bool) {
        let mut out = *cue;
        // 1. The pivot.
        let r = rotation(cue[3], cue[4], cue[5]);
        for (i, row) in r.iter().enumerate() {
            let rc: f64 = row.iter().zip(&self.pivot_mm).map(|(a, b)| a * b).sum();
            out[i] += self.pivot_mm[i] - rc;
        }
        // 2. Each axis.
        let mut limited = false;
        for (value, &limit) in out.iter_mut().zip(&self.limit) {
            if value.abs() > self.knee * limit {
                limited = true;
            }
            *value = soft_limit(*value, limit, self.knee);
        }
        // 3. The whole pose, with room to spare.
        let spare = |c: &Cue, s: f64| c.map(|v| v * s / self.margin);
        if !self.reachable(&spare(&out, 1.0)) {
            limited = true;
            let (mut inside, mut outside) = (0.0, 1.0);
            for _ in 0..SCALE_STEPS {
                let mid = (inside + outside) / 2.0;
                if self.reachable(&spare(&out, mid)) {
                    inside = mid;
                } else {
                    outside = mid;
                }
            }
            out = out.map(|v| v * inside);
        }
        (out, limited)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_are_the_margin_of_the_reach_or_the_full_scale() {
        let settings = Settings::default();
        let reach = Reach::new(&settings, 0.8, 0.6, [0.0; 3]).unwrap();
        // README, "Reach": x- 39.5 mm, y 41.2 mm, z- 14.29 / z+ 13.99 mm, roll 13.46 deg,
        // pitch+ 14.2 deg, yaw 40.4 deg; full scales 25 25 15 mm, 15 15 20 deg.
        let want = [25.0, 25.0, 13.994, 13.457, 14.204, 20.0].map(|v| 0.8 * v);
        for (i, (got, want)) in reach.limit.iter().zip(want).enumerate() {
            assert!((got - want).abs() < 0.02, "axis {i}: {got} vs {want}");
        }
    }

    #[test]
    fn a_cue_far_out_comes_back_inside_and_reachable() {
        let reach = Reach::new(&Settings::default(), 0.8, 0.6, [0.0; 3]).unwrap();
        let (out, limited) = reach.limit(&[100.0, -100.0, 50.0, 40.0, -40.0, 90.0]);
        assert!(limited);
        for (v, l) in out.iter().zip(&reach.limit) {
            assert!(v.abs() < *l, "{out:?}");
        }
        assert!(reach.reachable(&out.map(|v| v / 0.8)), "{out:?}");
        // A small cue passes unchanged.
        let small = [1.0, -1.0, 0.5, 0.3, -0.2, 1.0];
        assert_eq!(reach.limit(&small), (small, false));
    }

    #[test]
    fn rotations_about_a_pivot_above_move_the_platform_under_it() {
        let reach = Reach::new(&Settings::default(), 0.8, 0.6, [0.0, 0.0, 100.0]).unwrap();
        // Pitch 3 degrees (nose down, about y) about a point 100 mm up: the head stays put, so
        // the platform's centre moves back by 100 sin(3 deg) = 5.23 mm... in x by
        // -(R c - c)_x = -100 sin 3 deg, and up by 100 (1 - cos 3 deg).
        let (out, _) = reach.limit(&[0.0, 0.0, 0.0, 0.0, 3.0, 0.0]);
        let s = 3f64.to_radians();
        assert!((out[0] + 100.0 * s.sin()).abs() < 1e-9, "{out:?}");
        assert!((out[2] - 100.0 * (1.0 - s.cos())).abs() < 1e-9, "{out:?}");
    }
}
