//! `hexapod init`: a commented build file of the default platform.

use std::path::PathBuf;

use clap::Args;
use control::settings::Settings;

use super::wrote_build_file;
use crate::build_file::{self, DEFAULT_PLATFORM};
use crate::error::Error;
use crate::files::write_new;
use crate::sizing::Sizing;

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// The file to write
    #[arg(default_value = "build.toml")]
    file: PathBuf,
    /// Replace the file if it exists
    #[arg(long)]
    force: bool,
}

impl Cmd {
    /// Writes the file; the summary.
    pub fn run(self) -> Result<String, Error> {
        let text = build_file::write(&Settings::default(), &Sizing::default(), DEFAULT_PLATFORM);
        write_new(&self.file, text.as_bytes(), self.force)?;
        Ok(wrote_build_file(
            &self.file.display().to_string(),
            DEFAULT_PLATFORM,
        ))
    }
}
