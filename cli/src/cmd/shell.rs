//! `hexapod shell`: lines typed (or piped) in, each reply printed as the board wrote it, until
//! end of input. Refusals are printed and the shell goes on.

use std::io::{BufRead, IsTerminal, Write};

use clap::Args;

use super::Port;
use crate::error::Error;
use crate::messages;

/// The prompt.
const PROMPT: &str = "hexapod> ";

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    port: Port,
}

impl Cmd {
    /// Talks to the board until end of input; no summary.
    pub fn run(self) -> Result<String, Error> {
        let mut link = self.port.open()?;
        link.start()?;
        let stdin = std::io::stdin();
        let interactive = stdin.is_terminal();
        let mut out = std::io::stdout().lock();
        if interactive {
            let _ = writeln!(out, "{}", greeting(link.port()));
        }
        let mut input = stdin.lock();
        loop {
            if interactive {
                let _ = write!(out, "{PROMPT}");
                let _ = out.flush();
            }
            let mut line = String::new();
            match input.read_line(&mut line) {
                Ok(0) => return Ok(String::new()),
                Ok(_) => {}
                Err(error) => {
                    return Err(Error::File {
                        path: "standard input".into(),
                        error,
                    })
                }
            }
            let line = line.trim_end_matches(['\r', '\n']);
            if line.trim().is_empty() {
                continue;
            }
            let reply = link.request(line)?;
            messages::reply(&mut out, &reply);
        }
    }
}

/// The greeting.
fn greeting(port: &str) -> String {
    format!(
        "# connected to {port} (echo off: the tool shows each reply); type commands, help for \
         the board's list, Ctrl-D to quit"
    )
}
