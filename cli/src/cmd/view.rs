//! `hexapod view`: the live 3D view of a board on a cable, the page `./dev run` serves for the
//! emulator, served here for the board on `--port` (the work: `crate::view`). Runs until the
//! link fails (the page is told why) or Ctrl-C.

use std::sync::Arc;
use std::thread;

use clap::Args;

use super::Port;
use crate::error::Error;
use crate::view::{self, Assets, Server};

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    port: Port,
    /// The page's port on 127.0.0.1 (0: any free port; if 2040 is taken, any free one)
    #[arg(long, default_value_t = 2040)]
    view_port: u16,
}

impl Cmd {
    /// Serves the page until the link stops; that is the error it ends with.
    pub fn run(self) -> Result<String, Error> {
        let assets = Assets::default();
        if let Some(why) = assets.missing() {
            return Err(Error::View {
                doing: "serve the 3D view's page".into(),
                why,
            });
        }
        let link = self.port.open()?;
        let port = link.port().to_string();
        let server = Server::bind(self.view_port, self.view_port == 2040)?;
        eprintln!("{}", serving(&server.url(), &port));
        let (jobs, pages, follower) = view::start(link);
        let shared = Arc::clone(&pages);
        thread::spawn(move || view::serve(server, assets, jobs, shared));
        let error = follower.join().unwrap_or_else(|_| Error::View {
            doing: format!("follow the board on {port}"),
            why: "its thread failed".into(),
        });
        Err(error)
    }
}

/// What the user is told at the start.
fn serving(url: &str, port: &str) -> String {
    format!(
        "3D view: {url}  (open it in a browser) of the board on {port}, following its pulses; \
         Ctrl-C quits"
    )
}
