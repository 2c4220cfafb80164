//! Every word `hexapod cue` and `cue-plot` write (beside `crate::messages`, which carries them
//! as `Problem::Cue`): their errors, the live line, the summary, the `[cue]` keys' meanings,
//! the record's columns and the plot's labels.

use std::fmt::{self, Display, Formatter};

use super::config::{KeyKind, KeySpec};
use super::telemetry::{Bad, NAMES};

/// What went wrong in `cue` or `cue-plot`.
#[derive(Debug)]
pub enum CueProblem {
    /// A `[cue]` key that is not one.
    UnknownKey,
    /// A `[cue]` key's value that is not in its range.
    KeyRange(KeySpec),
    /// A `[cue]` key of a build file: where, and what.
    Key {
        /// The file.
        file: String,
        /// Its line, from 1.
        line: usize,
        /// `cue.` and the key.
        key: String,
        /// Why.
        why: Box<CueProblem>,
    },
    /// The telemetry address cannot be listened on.
    Listen {
        /// The address.
        address: String,
        /// What the system said.
        why: String,
    },
    /// Nothing valid came.
    NoTelemetry {
        /// Where it listened.
        address: String,
        /// How long it waited, s.
        waited_s: f64,
        /// What came instead.
        counts: Box<Counts>,
        /// JSBSim's field names, if it sent them.
        labels: Option<Vec<String>>,
    },
    /// The board's settings are not a platform (never: the board checks them).
    NotAPlatform,
    /// A record file that cannot be read for a plot.
    Record {
        /// The file.
        file: String,
        /// Its line, from 1.
        line: u64,
        /// Why.
        why: String,
    },
}

impl From<CueProblem> for crate::messages::Problem {
    fn from(why: CueProblem) -> Self {
        crate::messages::Problem::Cue(Box::new(why))
    }
}

/// Telemetry and frames counted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Counts {
    /// Datagrams received.
    pub datagrams: u64,
    /// Samples taken.
    pub samples: u64,
    /// Lines dropped, per [`Bad::ALL`] kind.
    pub bad: [u64; 5],
    /// Samples dropped because their time did not advance (repeated, out of order, or a
    /// storm faster than the washout takes them).
    pub stale: u64,
    /// Datagrams dropped because the queue was full (a storm).
    pub overflowed: u64,
    /// The simulation restarted (time went back, or jumped).
    pub restarts: u64,
    /// Frames sent.
    pub frames: u64,
    /// Frames sent whose cue a limit changed.
    pub limited: u64,
    /// Samples that arrived while the previous one's frame was not due yet (sent later, or
    /// superseded).
    pub late: u64,
}

impl Counts {
    /// Lines dropped, all kinds.
    pub fn dropped(&self) -> u64 {
        self.bad.iter().sum::<u64>() + self.stale + self.overflowed
    }

    fn bad_text(&self) -> String {
        let mut parts: Vec<String> = Bad::ALL
            .iter()
            .zip(self.bad)
            .filter(|(_, n)| *n > 0)
            .map(|(kind, n)| format!("{n} {}", bad_name(*kind)))
            .collect();
        if self.stale > 0 {
            parts.push(format!("{} whose time did not advance", self.stale));
        }
        if self.overflowed > 0 {
            parts.push(format!("{} in a storm (queue full)", self.overflowed));
        }
        if parts.is_empty() {
            "none".to_string()
        } else {
            parts.join(", ")
        }
    }
}

/// A kind of bad line, in words.
pub fn bad_name(kind: Bad) -> &'static str {
    match kind {
        Bad::NotText => "not text",
        Bad::FieldCount => "not 10 fields",
        Bad::NotANumber => "a field not a number",
        Bad::NotFinite => "NaN or infinite",
        Bad::OutOfRange => "beyond 30 g or 30 rad/s",
    }
}

impl Display for CueProblem {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            CueProblem::UnknownKey => write!(
                f,
                "not a [cue] key; see docs/cueing.md for the keys (margin, knee, stall_s, \
                 ease_s, pivot_*_mm, x.scale ... tilt.max_deg)"
            ),
            CueProblem::KeyRange(spec) => match spec.kind {
                KeyKind::Number => write!(f, "must be a number {}..{}", spec.min, spec.max),
                KeyKind::Whole => {
                    write!(f, "must be a whole number {}..{}", spec.min, spec.max)
                }
                KeyKind::Sign => write!(f, "must be 1 or -1"),
            },
            CueProblem::Key {
                file,
                line,
                key,
                why,
            } => write!(f, "{file}:{line}: {key}: {why}"),
            CueProblem::Listen { address, why } => {
                write!(f, "cannot listen for telemetry on {address}: {why}")
            }
            CueProblem::NoTelemetry {
                address,
                waited_s,
                counts,
                labels,
            } => {
                write!(
                    f,
                    "no valid telemetry on {address} in {waited_s} s: {} datagrams, lines \
                     dropped: {}. Each line must be {} numbers: {} (docs/cueing.md)",
                    counts.datagrams,
                    counts.bad_text(),
                    NAMES.len(),
                    NAMES.join(",")
                )?;
                if let Some(labels) = labels {
                    write!(f, "; the sender named its fields {}", labels.join(","))?;
                }
                Ok(())
            }
            CueProblem::NotAPlatform => write!(f, "the board's settings are not a platform"),
            CueProblem::Record { file, line, why } => write!(f, "{file}:{line}: {why}"),
        }
    }
}

/// The line at the start: where telemetry is awaited, where frames go, the limits.
pub fn started(address: &str, port: &str, rate_hz: f64, l: &[f64; 6]) -> String {
    format!(
        "cue: listening for telemetry on {address}; frames to {port} at up to {rate_hz:.0} Hz; \
         limits x {:.1} y {:.1} z {:.1} mm, roll {:.1} pitch {:.1} yaw {:.1} deg",
        l[0], l[1], l[2], l[3], l[4], l[5]
    )
}

/// The live line: packets in, frames out, rate, late, dropped, at the limit.
pub fn live(counts: &Counts, elapsed_s: f64) -> String {
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
        counts.dropped(),
        counts.late,
        counts.frames,
        counts.limited
    )
}

/// What a `cue` run did.
#[derive(Debug, Clone)]
pub struct Summary {
    /// Where telemetry came from.
    pub address: String,
    /// The port.
    pub port: String,
    /// Counts.
    pub counts: Counts,
    /// From the first frame to the end, s.
    pub duration_s: f64,
    /// Packet arrival to frame written, min, median, 99th percentile, max, ms.
    pub latency_ms: Option<[f64; 4]>,
    /// The board's counters over the run: frames, applied, damaged, clamped, refused.
    pub board: Option<[u64; 5]>,
    /// Each axis' limit, mm and degrees.
    pub limits: [f64; 6],
    /// The record written, if any.
    pub record: Option<String>,
}

/// The summary at the end of `cue`.
pub fn summary(s: &Summary) -> String {
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
        c.bad_text(),
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
    out.trim_end().to_string()
}

/// The record's columns (CSV header).
pub const RECORD_COLUMNS: [&str; 17] = [
    "time_s",
    "sim_time_s",
    "fx_ms2",
    "fy_ms2",
    "fz_ms2",
    "p_deg_s",
    "q_deg_s",
    "r_deg_s",
    "x_mm",
    "y_mm",
    "z_mm",
    "roll_deg",
    "pitch_deg",
    "yaw_deg",
    "limited",
    "easing",
    "latency_ms",
];

/// The record's comment line: what the columns are.
pub const RECORD_COMMENT: &str = "# hexapod cue record: time_s since the first frame; \
    sim_time_s and the aircraft's specific force (m/s^2) and rates (deg/s) of the newest \
    sample, in the platform's axes (x forward, y left, z up); the pose sent (mm, deg); \
    limited 1 when a limit changed it; easing 1 while easing home or back; latency_ms \
    from the sample's arrival to its frame written (empty if the frame carried no new sample)";

/// The plot's panels: title and y label, x y z then roll pitch yaw.
pub const PANELS: [(&str, &str); 6] = [
    ("x (surge): specific force", "m/s²"),
    ("y (sway): specific force", "m/s²"),
    ("z (heave): specific force", "m/s²"),
    ("roll rate", "deg/s"),
    ("pitch rate", "deg/s"),
    ("yaw rate", "deg/s"),
];
/// The plot's legend.
pub const LEGEND_AIRCRAFT: &str = "aircraft (at the pilot's head)";
/// The plot's legend.
pub const LEGEND_SCALED: &str = "aircraft × the axis' scale";
/// The plot's legend.
pub const LEGEND_PLATFORM: &str = "platform delivers (from the poses sent)";
/// The plot's x axis.
pub const TIME_LABEL: &str = "time (s)";
/// The plot's title.
pub fn plot_title(file: &str) -> String {
    format!(
        "Motion cues of {file}: what the aircraft felt, what the platform gave \
         (platform axes: x forward, y left, z up)"
    )
}

/// The plot written.
pub fn wrote_plot(written: &[String], rows: usize) -> String {
    format!(
        "cue-plot: {rows} frames plotted to {}",
        written.join(" and ")
    )
}

/// What each `[cue]` key does (for the documentation's table and `init`'s comments).
pub fn key_meaning(name: &str) -> &'static str {
    let field = name.rsplit('.').next().unwrap_or(name);
    match (name, field) {
        ("margin", _) => "cues keep within this fraction of the reach from home and of the stream full scales",
        ("knee", _) => "the soft limit bends from this fraction of an axis' limit, approaching the limit smoothly",
        ("stall_s", _) => "no valid telemetry for this long is a stall: the platform eases home",
        ("ease_s", _) => "how long easing home, or back into the cues, takes (s)",
        ("pivot_x_mm" | "pivot_y_mm" | "pivot_z_mm", _) => {
            "the centre of the rotations (the pilot's head) from the board's rotation centre (mm)"
        }
        ("tilt.scale", _) => "gain on the specific force that tilt coordination turns into a sustained tilt (0: none)",
        ("tilt.order", _) => "the tilt's low-pass order, 1 or 2",
        ("tilt.lp_hz", _) => "the tilt's low-pass break frequency (Hz)",
        ("tilt.zeta", _) => "the tilt's low-pass damping ratio",
        ("tilt.rate_deg_s", _) => "the most the tilt changes per second (deg/s), below what a pilot feels as a rotation",
        ("tilt.max_deg", _) => "the largest tilt (deg)",
        (_, "scale") => "gain on the aircraft's specific force (x y z) or rate (roll pitch yaw)",
        (_, "order") => "high-pass order: 2 or 3 for x y z (3 washes a sustained force back to centre), 1 or 2 for roll pitch yaw",
        (_, "hp_hz") => "the high-pass break frequency (Hz): higher washes out sooner and needs less travel",
        (_, "zeta") => "the high-pass damping ratio",
        (_, "hp3_hz") => "a 3rd-order high-pass' first-order break frequency (Hz)",
        (_, "sign") => "1, or -1 to move the platform the other way on this axis",
        _ => "",
    }
}
