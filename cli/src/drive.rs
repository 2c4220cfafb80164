//! `stream` and `demo`: trajectories from a file or built in, checked against the board's own
//! settings (read with `config`) before anything is sent, then streamed (see
//! [`crate::streamer`]) or written as CSV.

use std::path::Path;

use control::settings::Settings;

use crate::board;
use crate::configure::{read_build_file, write_new};
use crate::demo::{self, Shape};
use crate::link::Link;
use crate::messages::{self, Problem};
use crate::streamer::{self, Options};
use crate::trajectory::{self, Mode, Row};

/// Streams checked rows; prints the summary; an error if the stream did not go through whole.
fn stream_rows(
    link: &mut Link,
    file: &str,
    rows: &[Row],
    options: &Options,
) -> Result<String, Problem> {
    let settings = board::read_settings(link)?;
    let messages = trajectory::prepare(file, rows, &settings, options.mode)?;
    let summary = streamer::run(link, rows, &messages, options)?;
    let text = messages::stream_summary(file, link.port(), &summary);
    if !summary.has_errors() {
        return Ok(text);
    }
    println!("{text}");
    let c = summary.counters.unwrap_or_default();
    Err(Problem::StreamTrouble {
        file: file.to_string(),
        refused: summary.refusals.len(),
        notices: summary.notices.len(),
        lost_frames: (summary.sent as u64).saturating_sub(c.frames) + c.damaged,
        refused_frames: c.refused,
    })
}

/// `stream FILE --port PORT`.
pub fn stream(link: &mut Link, path: &Path, options: &Options) -> Result<String, Problem> {
    let rows = trajectory::read(path)?;
    link.start()?;
    stream_rows(link, &path.display().to_string(), &rows, options)
}

/// `demo KIND`: streamed to a board (its settings), or written to `output` (the settings of a
/// build file, or the defaults).
pub fn demo(
    shape: &Shape,
    link: Option<&mut Link>,
    output: Option<&Path>,
    build: Option<&Path>,
    options: &Options,
) -> Result<String, Problem> {
    let name = messages::demo_name(shape.kind);
    match (link, output) {
        (Some(link), _) => {
            link.start()?;
            let settings = board::read_settings(link)?;
            let rows = demo::rows(shape, &settings);
            stream_rows(link, &name, &rows, options)
        }
        (None, Some(output)) => {
            let settings = match build {
                Some(path) => read_build_file(path)?.settings,
                None => Settings::default(),
            };
            let rows = demo::rows(shape, &settings);
            trajectory::prepare(&name, &rows, &settings, Mode::Text)?;
            write_new(output, trajectory::write(&rows).as_bytes(), true)?;
            Ok(messages::wrote_trajectory(
                &output.display().to_string(),
                rows.len(),
                shape.duration_s,
            ))
        }
        (None, None) => Err(Problem::Option {
            option: "--port/--output",
            why: messages::DEMO_NEEDS_A_PLACE.to_string(),
        }),
    }
}
