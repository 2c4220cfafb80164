//! `hexapod torque`: the servo torques of holding the payload over a grid of poses, or of
//! carrying it along a trajectory (gravity and inertia), each servo's worst against its rating;
//! a plot (`crate::torque_plot`). Torques in kgf cm.

use std::path::PathBuf;

use clap::Args;
use kinematics_core::LEGS;

use super::{wrote_pictures, Formats};
use crate::error::{Error, RowError};
use crate::picture::write_scene;
use crate::size::{
    overall, payload_words, pose_words, ratings_summary, reach_from_home, sizing_grid,
    trajectory_torques, worst_along, worst_per_servo, Platform, Verdict, Worst,
};
use crate::torque_plot;
use crate::trajectory::{self, Mode};

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// The platform (a build file with a payload: payload_g above 0, payload_com_*_mm)
    #[arg(long)]
    settings: Option<PathBuf>,
    /// A trajectory (CSV: time,x,y,z,roll,pitch,yaw) instead of the grid
    #[arg(long)]
    trajectory: Option<PathBuf>,
    /// Where to write the plot: FILE.svg and FILE.png
    #[arg(short, long, default_value = "torque")]
    output: PathBuf,
    #[command(flatten)]
    formats: Formats,
}

impl Cmd {
    /// Over the sizing grid, or along a trajectory: the report and the files written. Needs a
    /// payload (`payload_g` above 0): without one every torque is 0 and nothing is plotted.
    pub fn run(self) -> Result<String, Error> {
        let platform = Platform::load(self.settings.as_deref())?;
        if !platform.payload().carried() {
            return Err(Error::NoPayload {
                source: platform.source,
            });
        }
        let (scene, report) = match &self.trajectory {
            None => {
                let reach = reach_from_home(&platform);
                let grid = sizing_grid(&reach);
                let (worst, reached) = worst_per_servo(&platform, &grid);
                let report = grid_report(&platform, &worst, reached, grid.len());
                (torque_plot::grid_scene(&platform, &worst), report)
            }
            Some(path) => {
                let file = path.display().to_string();
                let rows = trajectory::read(path)?;
                // Every row within reach; the ratings are what this reports on, not a refusal.
                let mut unrated = platform.settings;
                unrated.payload.torque_kgcm = [0.0; LEGS];
                trajectory::prepare(&file, &rows, &unrated, Mode::Text)?;
                let torques =
                    trajectory_torques(&platform, &rows).map_err(|(line, why)| Error::Row {
                        file: file.clone(),
                        line,
                        field: None,
                        why: RowError::Refused(why),
                    })?;
                let worst = worst_along(&rows, &torques);
                let report = trajectory_report(&file, &platform, &worst, rows.len());
                (
                    torque_plot::trajectory_scene(&platform, &file, &rows, &torques),
                    report,
                )
            }
        };
        let written = write_scene(&scene, &self.output, self.formats.svg(), self.formats.png())?;
        Ok(format!("{report}\n{}", wrote_pictures(&written)))
    }
}

/// A servo's torque against its rating.
fn verdict_words(v: Verdict) -> String {
    match v {
        Verdict::NotRated => "not rated".to_string(),
        Verdict::Within {
            rating_kgcm,
            percent,
        } => format!("within its rating of {rating_kgcm} kgf cm ({percent:.0}%)"),
        Verdict::Over {
            rating_kgcm,
            percent,
        } => format!("OVER its rating of {rating_kgcm} kgf cm ({percent:.0}%)"),
    }
}

/// `torque` over the grid: each servo's worst, and the worst of all, against the ratings.
fn grid_report(p: &Platform, worst: &[Option<Worst>; 6], reached: usize, total: usize) -> String {
    let mut out = format!(
        "{}: holding {}, over {reached} reachable poses of a {total}-pose grid (9 steps along \
         x, y, z and along roll, pitch, yaw):\n",
        p.source,
        payload_words(p.payload())
    );
    for w in worst.iter().flatten() {
        let t = w.torque_kgcm.abs();
        out += &format!(
            "  servo {}: {t:.3} kgf cm at {}; {}\n",
            w.servo,
            pose_words(&w.pose),
            verdict_words(p.verdict(w.servo, t))
        );
    }
    match overall(worst) {
        Some(w) => {
            let t = w.torque_kgcm.abs();
            out += &format!(
                "worst: servo {}, {t:.3} kgf cm, {}\n",
                w.servo,
                verdict_words(p.verdict(w.servo, t))
            );
        }
        None => out += "worst: none (no reachable pose)\n",
    }
    out + &ratings_summary(p, worst)
}

/// `torque` along a trajectory: the worst, and each servo's worst against its rating.
fn trajectory_report(file: &str, p: &Platform, worst: &[Option<Worst>; 6], rows: usize) -> String {
    match overall(worst) {
        Some(w) => {
            let t = w.torque_kgcm.abs();
            let (time, line) = w.at.unwrap_or((0.0, 0));
            format!(
                "{file}: {rows} rows carrying {} (gravity and inertia): worst servo {}, \
                 {t:.3} kgf cm at {time:.3} s (line {line}), {}; {}\n{}",
                payload_words(p.payload()),
                w.servo,
                pose_words(&w.pose),
                verdict_words(p.verdict(w.servo, t)),
                ratings_summary(p, worst)
            )
        }
        None => format!("{file}: no rows"),
    }
}
