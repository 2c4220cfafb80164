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
//! - [`record`]: `--record`'s CSV and `cue-plot`'s picture, with its labels.
//!
//! The subcommands' options, runs and summaries are `crate::cmd::cue` and `cue_plot`'s; the
//! errors are `crate::error::CueError`'s (and `KeyError::Cue`'s).

pub mod config;
pub mod reach;
pub mod record;
pub mod run;
pub mod telemetry;
pub mod washout;
