//! `hexapod send`: lines sent to a board (those given, or standard input's), each reply printed
//! as the board wrote it; stops at the first refusal (an error naming it).

use std::io::BufRead;

use clap::Args;

use super::Port;
use crate::error::Error;
use crate::messages;

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    port: Port,
    /// The lines, e.g. "pose 0 0 5 0 0 0" status
    lines: Vec<String>,
}

impl Cmd {
    /// Sends the lines; no summary (the replies are printed as they come).
    pub fn run(self) -> Result<String, Error> {
        let mut link = self.port.open()?;
        link.start()?;
        let mut out = std::io::stdout().lock();
        let lines = if self.lines.is_empty() {
            std::io::stdin()
                .lock()
                .lines()
                .collect::<Result<_, _>>()
                .map_err(|error| Error::File {
                    path: "standard input".into(),
                    error,
                })?
        } else {
            self.lines
        };
        for line in lines.iter().filter(|l| !l.trim().is_empty()) {
            let reply = link.request(line)?;
            messages::reply(&mut out, &reply);
            if !reply.is_ok() {
                return Err(Error::Refused {
                    at: None,
                    port: link.port().to_string(),
                    line: line.clone(),
                    reply: reply.last,
                });
            }
        }
        Ok(String::new())
    }
}
