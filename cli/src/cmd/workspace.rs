//! `hexapod workspace`: the reachable workspace plotted (`crate::workspace_plot`), as SVG and
//! PNG.

use std::path::PathBuf;

use clap::Args;

use super::{wrote_pictures, Formats};
use crate::error::Error;
use crate::picture::write_scene;
use crate::size::Platform;
use crate::workspace_plot;

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// The platform (a build file); the default platform without it
    #[arg(long)]
    settings: Option<PathBuf>,
    /// Where to write: FILE.svg and FILE.png
    #[arg(short, long, default_value = "workspace")]
    output: PathBuf,
    #[command(flatten)]
    formats: Formats,
}

impl Cmd {
    /// Plots the workspace; the files written.
    pub fn run(self) -> Result<String, Error> {
        let platform = Platform::load(self.settings.as_deref())?;
        let written = write_scene(
            &workspace_plot::scene(&platform),
            &self.output,
            self.formats.svg(),
            self.formats.png(),
        )?;
        Ok(wrote_pictures(&written))
    }
}
