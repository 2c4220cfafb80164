//! `hexapod cue`: a flight simulator's telemetry (UDP) turned into motion cues by the washout
//! filter (`crate::cue`) and streamed to a board as binary frames; its start line, live line
//! and summary. Ctrl-C eases the platform home before the tool exits (a second Ctrl-C exits at
//! once; the board's own `link_timeout_s` is the last line of defence).

use std::io::IsTerminal;
use std::path::PathBuf;

use clap::Args;

use super::{on_ctrl_c, Port, CTRL_C};
use crate::cue::config;
use crate::cue::run::{self, Counts, Options, Progress, Summary};
use crate::error::Error;

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    port: Port,
    /// Where to listen for telemetry
    #[arg(long, default_value = "127.0.0.1:5139")]
    listen: String,
    /// Frames per second (at most, and by default, the board's frame_hz)
    #[arg(long)]
    rate: Option<f64>,
    /// The build file whose [cue] table tunes the washout (the defaults without it)
    #[arg(long)]
    settings: Option<PathBuf>,
    /// Write what came in and what was sent to this CSV file (see cue-plot)
    #[arg(long)]
    record: Option<PathBuf>,
    /// No valid telemetry within this long is an error, s
    #[arg(long, default_value_t = 30.0)]
    wait_s: f64,
    /// Stop this long after the telemetry ends (once home), s; without it, run until
    /// stopped (Ctrl-C, which eases the platform home first)
    #[arg(long)]
    idle_exit_s: Option<f64>,
}

impl Cmd {
    /// Cues until the telemetry ends (`--idle-exit-s`) or Ctrl-C; the summary.
    pub fn run(self) -> Result<String, Error> {
        let tuning = config::read(self.settings.as_deref())?;
        let options = Options {
            listen: self.listen,
            rate_hz: self.rate,
            record: self.record,
            wait_s: self.wait_s,
            idle_exit_s: self.idle_exit_s,
            stop: Some(&CTRL_C),
        };
        let mut link = self.port.open()?;
        on_ctrl_c();
        let terminal = std::io::stderr().is_terminal();
        let mut live_shown = false;
        let mut progress = |p: Progress<'_>| match p {
            Progress::Started {
                address,
                port,
                rate_hz,
                limits,
            } => eprintln!("{}", started(address, port, rate_hz, limits)),
            Progress::Live { counts, elapsed_s } if terminal => {
                live_shown = true;
                eprint!("\r{}", live(counts, elapsed_s));
            }
            Progress::Live { .. } => {}
            Progress::Stopping => {
                if std::mem::take(&mut live_shown) {
                    eprintln!();
                }
                eprintln!("{STOPPING}");
            }
        };
        let outcome = run::run(&mut link, &tuning, &options, &mut progress);
        if live_shown {
            eprintln!();
        }
        Ok(summary(&outcome?))
    }
}

/// Ctrl-C taken.
const STOPPING: &str =
    "cue: stopping (Ctrl-C): easing the platform home; Ctrl-C again to quit at once";

/// The line at the start: where telemetry is awaited, where frames go, the limits.
fn started(address: &str, port: &str, rate_hz: f64, l: &[f64; 6]) -> String {
    format!(
        "cue: listening for telemetry on {address}; frames to {port} at up to {rate_hz:.0} Hz; \
         limits x {:.1} y {:.1} z {:.1} mm, roll {:.1} pitch {:.1} yaw {:.1} deg",
        l[0], l[1], l[2], l[3], l[4], l[5]
    )
}

/// The live line: packets in, frames out, rate, late, dropped, at the limit.
fn live(counts: &Counts, elapsed_s: f64) -> String {
    let rate = if elapsed_s > 0.0 {
        counts.frames as f64 / elapsed_s
    } else {
        0.0
    };
    format!(
        "cue: {} packets in ({} samples, {} dropped, {} late), {} frames out ({rate:.1} Hz), \
         {} at a limit",
        counts.datagrams,
        counts.samples,
        counts.dropped.total(),
        counts.late,
        counts.frames,
        counts.limited
    )
}

/// The summary at the end of `cue`.
fn summary(s: &Summary) -> String {
    let c = &s.counts;
    let mut out = format!(
        "cue: telemetry from {} to {} for {:.2} s\n  telemetry: {} datagrams, {} samples, \
         {} simulation restarts; dropped: {}\n  frames sent: {} ({:.1} Hz), {} with a cue \
         at a limit; late samples {}\n",
        s.address,
        s.port,
        s.duration_s,
        c.datagrams,
        c.samples,
        c.restarts,
        c.dropped,
        c.frames,
        if s.duration_s > 0.0 {
            c.frames as f64 / s.duration_s
        } else {
            0.0
        },
        c.limited,
        c.late,
    );
    let l = s.limits;
    out.push_str(&format!(
        "  limits (margin of the reach and full scales): x {:.1} y {:.1} z {:.1} mm, roll \
         {:.1} pitch {:.1} yaw {:.1} deg\n",
        l[0], l[1], l[2], l[3], l[4], l[5]
    ));
    match s.latency_ms {
        Some([min, median, p99, max]) => out.push_str(&format!(
            "  latency (packet arrival to frame written): min {min:.3} ms, median \
             {median:.3} ms, 99% {p99:.3} ms, max {max:.3} ms\n"
        )),
        None => out.push_str("  latency: no frame carried a new sample\n"),
    }
    if let Some([frames, applied, damaged, clamped, refused]) = s.board {
        out.push_str(&format!(
            "  the board counted frames={frames} applied={applied} damaged={damaged} \
             clamped={clamped} refused={refused}\n"
        ));
    }
    if let Some(record) = &s.record {
        out.push_str(&format!("  recorded to {record}\n"));
    }
    if s.stopped {
        out.push_str("  stopped by Ctrl-C, the platform eased home\n");
    }
    out.trim_end().to_string()
}
