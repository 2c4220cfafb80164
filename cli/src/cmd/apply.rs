//! `hexapod apply`: a build file checked with the firmware's own code, and with `--port` sent
//! to a board: `defaults`, each `set` in an order the board accepts, then `save` (unless
//! `--no-save`); stops at the first refusal with the board's words.

use std::path::PathBuf;

use clap::Args;

use super::OptionalPort;
use crate::build_file;
use crate::error::Error;

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// The build file
    file: PathBuf,
    #[command(flatten)]
    port: OptionalPort,
    /// Do not `save` (the settings last until the board restarts)
    #[arg(long)]
    no_save: bool,
}

impl Cmd {
    /// Checks the file, and with a port applies it; the summary.
    pub fn run(self) -> Result<String, Error> {
        let link = self.port.open()?;
        let file = build_file::read(&self.file)?;
        let name = self.file.display().to_string();
        let Some(mut link) = link else {
            return Ok(good(&name, file.steps.len()));
        };
        let save = !self.no_save;
        link.start()?;
        link.request_ok("defaults")?;
        for step in &file.steps {
            let command = step.command();
            let reply = link.request(&command)?;
            if !reply.is_ok() {
                return Err(Error::Refused {
                    at: Some(format!("{name}:{}", step.line)),
                    port: link.port().to_string(),
                    line: command,
                    reply: reply.last,
                });
            }
        }
        if save {
            link.request_ok("save")?;
        }
        Ok(applied(&name, link.port(), file.steps.len(), save))
    }
}

/// Done.
fn applied(file: &str, port: &str, settings: usize, saved: bool) -> String {
    let saved = if saved {
        "and saved in flash (the board starts with them at power-up)"
    } else {
        "not saved (--no-save): they last until the board restarts"
    };
    format!("{file}: {settings} settings applied to the board on {port}, {saved}")
}

/// Without a port: the file is good.
fn good(file: &str, settings: usize) -> String {
    format!("{file}: {settings} settings, all accepted by the firmware's own checks")
}
