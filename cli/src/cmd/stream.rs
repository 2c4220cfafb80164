//! `hexapod stream`: a trajectory file streamed to a board at its own timing, every row checked
//! against the board's own settings (read with `config`) before anything is sent.

use std::path::PathBuf;

use clap::Args;

use super::{Port, StreamOptions};
use crate::error::Error;
use crate::streamer;
use crate::trajectory;

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// The trajectory file
    file: PathBuf,
    #[command(flatten)]
    port: Port,
    #[command(flatten)]
    stream: StreamOptions,
}

impl Cmd {
    /// Streams the file; the stream's summary.
    pub fn run(self) -> Result<String, Error> {
        let options = self.stream.options()?;
        let mut link = self.port.open()?;
        let rows = trajectory::read(&self.file)?;
        link.start()?;
        streamer::stream_checked(&mut link, &self.file.display().to_string(), &rows, &options)
    }
}
