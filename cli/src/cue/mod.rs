//! Motion cueing: a flight simulator's telemetry (UDP) turned into platform poses by the
//! classical washout filter and sent to the board as binary stream frames (`hexapod cue`);
//! a record of a flight plotted (`hexapod cue-plot`). The board decides nothing new: frames
//! are made with its own full scales (read with `config`) and checked against its own reach.
//!
//! - [`washout`]: the filters (specific force and rates in, a pose out);
//! - [`reach`]: the pivot and the limits that keep the cues inside the platform's reach;
//! - [`telemetry`]: the UDP line format JSBSim and FlightGear send, parsed robustly;
//! - [`config`]: the build file's `[cue]` table;
//! - [`run`]: the loop (newest cue first, easing home on a stall);
//! - [`record`]: `--record`'s CSV and `cue-plot`;
//! - [`words`]: every word of the above.

pub mod config;
pub mod reach;
pub mod record;
pub mod run;
pub mod telemetry;
pub mod washout;
pub mod words;

use std::path::Path;

use crate::messages::Problem;

/// The `[cue]` table of a build file, or the defaults without one.
pub fn settings(build: Option<&Path>) -> Result<config::CueSettings, Problem> {
    match build {
        Some(path) => {
            let text = crate::configure::read_text(path)?;
            // The rest of the file is the board's: checked as `apply` checks it.
            crate::build_file::parse(&path.display().to_string(), &text)?;
            config::parse(&path.display().to_string(), &text).map_err(Problem::from)
        }
        None => Ok(config::CueSettings::default()),
    }
}
