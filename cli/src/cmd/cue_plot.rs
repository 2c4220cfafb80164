//! `hexapod cue-plot`: a `cue --record` file plotted (`crate::cue::record`), per axis the
//! aircraft's specific force or rate beside what the platform delivers; the files written.

use std::path::PathBuf;

use clap::Args;

use super::Formats;
use crate::cue::record;
use crate::error::Error;

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// The record (CSV)
    record: PathBuf,
    /// Where to write: FILE.svg and FILE.png
    #[arg(short, long, default_value = "cue")]
    output: PathBuf,
    #[command(flatten)]
    formats: Formats,
}

impl Cmd {
    /// Plots the record; the files written.
    pub fn run(self) -> Result<String, Error> {
        let (written, rows) = record::plot(
            &self.record,
            &self.output,
            self.formats.svg(),
            self.formats.png(),
        )?;
        Ok(wrote_plot(&written, rows))
    }
}

/// The plot written.
fn wrote_plot(written: &[String], rows: usize) -> String {
    format!(
        "cue-plot: {rows} frames plotted to {}",
        written.join(" and ")
    )
}
