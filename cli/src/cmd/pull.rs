//! `hexapod pull`: a board's settings (`config`) written as a build file.

use std::path::PathBuf;

use clap::Args;

use super::{wrote_build_file, Port};
use crate::board;
use crate::build_file;
use crate::error::Error;
use crate::files::write_new;
use crate::sizing::Sizing;

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    port: Port,
    /// The file to write
    #[arg(short, long, default_value = "build.toml")]
    output: PathBuf,
    /// Replace the file if it exists
    #[arg(long)]
    force: bool,
}

impl Cmd {
    /// Reads the board's `config`, writes the file; the summary.
    pub fn run(self) -> Result<String, Error> {
        let mut link = self.port.open()?;
        link.start()?;
        let settings = board::read_settings(&mut link)?;
        let source = board_on(link.port());
        write_new(
            &self.output,
            build_file::write(&settings, &Sizing::default(), &source).as_bytes(),
            self.force,
        )?;
        Ok(wrote_build_file(
            &self.output.display().to_string(),
            &source,
        ))
    }
}

/// The settings' source.
fn board_on(port: &str) -> String {
    format!("the board on {port}")
}
