//! The subcommands, one file each: its options (a clap `Cmd`), its `run` and its own words (the
//! summary it prints). `main.rs` lists them; the work is the library's modules. Here: the
//! options several share (a board's port, the picture formats, how to stream) and the summaries
//! several write.

pub mod apply;
pub mod boards;
pub mod calibrate;
pub mod cue;
pub mod cue_plot;
pub mod demo;
pub mod describe;
pub mod draw;
pub mod init;
pub mod pull;
pub mod send;
pub mod shell;
pub mod stream;
pub mod torque;
pub mod uf2;
pub mod view;
pub mod workspace;

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use clap::Args;

use crate::error::Error;
use crate::link::Link;
use crate::streamer;
use crate::trajectory::Mode;

/// A serial port to a board.
#[derive(Args)]
pub struct Port {
    /// The board's serial port (e.g. /dev/ttyACM0, /dev/ttyUSB0, COM3, or the path
    /// `./dev run --pty` prints)
    #[arg(short, long)]
    port: String,
    #[command(flatten)]
    link: LinkOptions,
}

impl Port {
    /// The port opened.
    fn open(&self) -> Result<Link, Error> {
        self.link.open(&self.port)
    }
}

/// A serial port, if the job needs a board.
#[derive(Args)]
pub struct OptionalPort {
    /// The board's serial port; without it the file is only checked
    #[arg(short, long)]
    port: Option<String>,
    #[command(flatten)]
    link: LinkOptions,
}

impl OptionalPort {
    /// The port opened, if one was given.
    fn open(&self) -> Result<Option<Link>, Error> {
        self.port
            .as_deref()
            .map(|name| self.link.open(name))
            .transpose()
    }
}

#[derive(Args)]
pub struct LinkOptions {
    /// The port's baud rate (the board's `baud`; USB ports ignore it)
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// How long to wait for a reply, s
    #[arg(long, default_value_t = 5.0)]
    timeout_s: f64,
}

impl LinkOptions {
    fn open(&self, port: &str) -> Result<Link, Error> {
        let timeout = Duration::try_from_secs_f64(self.timeout_s).map_err(|e| Error::Option {
            option: "--timeout-s",
            why: e.to_string(),
        })?;
        Link::open(port, self.baud, timeout)
    }
}

#[derive(Args)]
pub struct Formats {
    /// Write only the SVG
    #[arg(long, conflicts_with = "png_only")]
    svg_only: bool,
    /// Write only the PNG
    #[arg(long)]
    png_only: bool,
}

impl Formats {
    fn svg(&self) -> bool {
        !self.png_only
    }

    fn png(&self) -> bool {
        !self.svg_only
    }
}

#[derive(Args)]
pub struct StreamOptions {
    /// Send `pose` lines, each answered (round trip per row), instead of binary frames
    #[arg(long)]
    text: bool,
    /// A row sent later than this after its time counts as late, ms
    #[arg(long, default_value_t = 10.0)]
    late_ms: f64,
    /// How often a `status` is sent during a binary stream (its round trip is measured), s
    #[arg(long, default_value_t = 0.5)]
    status_every_s: f64,
}

impl StreamOptions {
    fn options(&self) -> Result<streamer::Options, Error> {
        let duration = |option: &'static str, seconds: f64| {
            Duration::try_from_secs_f64(seconds).map_err(|e| Error::Option {
                option,
                why: e.to_string(),
            })
        };
        Ok(streamer::Options {
            mode: if self.text { Mode::Text } else { Mode::Binary },
            status_every: duration("--status-every-s", self.status_every_s)?,
            late_after: duration("--late-ms", self.late_ms / 1e3)?,
            progress: true,
        })
    }
}

/// `init`, `pull`: a build file was written.
fn wrote_build_file(path: &str, source: &str) -> String {
    format!("{path}: the build file of {source}; edit it, then `hexapod apply {path} --port PORT`")
}

/// `draw`, `workspace`, `torque`: the pictures written.
fn wrote_pictures(paths: &[String]) -> String {
    format!("wrote {}", paths.join(", "))
}

/// Set by the first Ctrl-C once [`on_ctrl_c`] is called (`cue` eases home, `calibrate` puts
/// back what it changed).
static CTRL_C: AtomicBool = AtomicBool::new(false);

/// Ctrl-C (SIGINT) sets [`CTRL_C`]; a second one exits at once. Elsewhere than Unix, Ctrl-C
/// keeps its usual meaning.
fn on_ctrl_c() {
    #[cfg(unix)]
    {
        extern "C" fn handler(_: libc::c_int) {
            if CTRL_C.swap(true, Ordering::SeqCst) {
                // Async-signal-safe: no unwinding, no allocation.
                unsafe { libc::_exit(130) };
            }
        }
        // SAFETY: the handler only touches an atomic and calls `_exit`, both async-signal-safe.
        unsafe {
            libc::signal(
                libc::SIGINT,
                handler as extern "C" fn(libc::c_int) as libc::sighandler_t,
            );
        }
    }
    #[cfg(not(unix))]
    let _ = &CTRL_C.load(Ordering::Relaxed);
}
