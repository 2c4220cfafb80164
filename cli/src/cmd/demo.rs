//! `hexapod demo`: a built-in trajectory (`crate::demo`) streamed to a board (`--port`, checked
//! against its own settings) or written as CSV (`--output`, checked against a build file's
//! settings or the defaults).

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use control::settings::Settings;

use super::{OptionalPort, StreamOptions};
use crate::build_file;
use crate::demo::{self, Kind, Shape};
use crate::error::Error;
use crate::files::write_new;
use crate::streamer;
use crate::trajectory::{self, Mode};

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// Which
    #[arg(value_enum)]
    kind: Kind,
    #[command(flatten)]
    port: OptionalPort,
    /// Write the trajectory to this CSV file instead
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// The platform (a build file) the CSV is checked against; the default platform
    /// without it (a board's own settings when streaming)
    #[arg(long)]
    settings: Option<PathBuf>,
    /// Radius or amplitude, mm (the tour: the farthest it goes)
    #[arg(long, default_value_t = 10.0)]
    amplitude_mm: f64,
    /// One turn or sine period, s
    #[arg(long, default_value_t = 4.0)]
    period_s: f64,
    /// Length, s
    #[arg(long, default_value_t = 12.0)]
    duration_s: f64,
    /// Rows per second, Hz
    #[arg(long, default_value_t = 50.0)]
    rate_hz: f64,
    /// The tour keeps within this fraction of the reach
    #[arg(long, default_value_t = 0.9)]
    edge_fraction: f64,
    #[command(flatten)]
    stream: StreamOptions,
}

impl Cmd {
    /// Streams or writes the demo; the summary.
    pub fn run(self) -> Result<String, Error> {
        let options = self.stream.options()?;
        let shape = Shape {
            kind: self.kind,
            amplitude_mm: self.amplitude_mm,
            period_s: self.period_s,
            duration_s: self.duration_s,
            rate_hz: self.rate_hz,
            ramp_s: self.period_s.min(self.duration_s / 4.0),
            edge_fraction: self.edge_fraction,
        };
        check(&shape)?;
        let link = self.port.open()?;
        let name = demo_name(shape.kind);
        match (link, self.output) {
            (Some(mut link), _) => {
                link.start()?;
                let settings = crate::board::read_settings(&mut link)?;
                let rows = demo::rows(&shape, &settings);
                streamer::stream_checked(&mut link, &name, &rows, &options)
            }
            (None, Some(output)) => {
                let settings = match &self.settings {
                    Some(path) => build_file::read(path)?.settings,
                    None => Settings::default(),
                };
                let rows = demo::rows(&shape, &settings);
                trajectory::prepare(&name, &rows, &settings, Mode::Text)?;
                write_new(&output, trajectory::write(&rows).as_bytes(), true)?;
                Ok(wrote_trajectory(
                    &output.display().to_string(),
                    rows.len(),
                    shape.duration_s,
                ))
            }
            (None, None) => Err(Error::Option {
                option: "--port/--output",
                why: NEEDS_A_PLACE.to_string(),
            }),
        }
    }
}

/// Checks a shape's numbers: positive finite times, a rate of 1..=1000 Hz, an amplitude of
/// 0..=500 mm, an edge fraction in (0, 1].
fn check(shape: &Shape) -> Result<(), Error> {
    let bad = |option, why: &str| {
        Err(Error::Option {
            option,
            why: why.to_string(),
        })
    };
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if !positive(shape.period_s) {
        return bad("--period-s", MUST_BE_POSITIVE);
    }
    if !positive(shape.duration_s) {
        return bad("--duration-s", MUST_BE_POSITIVE);
    }
    if !(1.0..=1000.0).contains(&shape.rate_hz) {
        return bad("--rate-hz", RATE_RANGE);
    }
    if !(0.0..=500.0).contains(&shape.amplitude_mm) {
        return bad("--amplitude-mm", AMPLITUDE_RANGE);
    }
    if !(shape.edge_fraction > 0.0 && shape.edge_fraction <= 1.0) {
        return bad("--edge-fraction", FRACTION_RANGE);
    }
    Ok(())
}

/// What a demo is called in messages (its rows' "file").
fn demo_name(kind: Kind) -> String {
    let name = kind
        .to_possible_value()
        .map_or_else(|| "?".to_string(), |v| v.get_name().to_string());
    format!("demo {name}")
}

/// `-o`: the CSV written.
fn wrote_trajectory(path: &str, rows: usize, duration_s: f64) -> String {
    format!("{path}: {rows} rows, {duration_s:.2} s (time,x,y,z,roll,pitch,yaw in s, mm, degrees)")
}

/// Neither a port nor an output file.
const NEEDS_A_PLACE: &str =
    "give --port PORT to stream the demo to a board, or --output FILE.csv to write it";

/// A time that is not positive.
const MUST_BE_POSITIVE: &str = "must be a positive number of seconds";
/// The row rate.
const RATE_RANGE: &str = "must be 1..1000 rows per second";
/// The size.
const AMPLITUDE_RANGE: &str = "must be 0..500 mm";
/// The tour's fraction of the reach.
const FRACTION_RANGE: &str = "must be more than 0 and at most 1";
