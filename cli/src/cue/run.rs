//! `hexapod cue`'s loop: telemetry in, cues out as binary stream frames, newest first.
//!
//! - Each valid sample goes through the washout at once (its time step the simulation's) and
//!   its cue through the limits; the frame goes as soon as the rate allows (one frame per
//!   `1 / rate`), so a sample that finds the link free is sent within the pass that took it,
//!   and samples that come faster than the rate are superseded by the newest (counted late).
//! - A stall (no valid sample for `stall_s`) or the end of the telemetry eases the platform
//!   home over `ease_s` (a smooth blend from where it is, frames at the rate); telemetry that
//!   comes back eases into the cues the same way. The board's own `link_timeout_s` remains the
//!   last line of defence if the tool itself stops.
//! - Stopped by the user (Ctrl-C, [`Options::stop`]), it eases home the same way before it
//!   returns, taking no more telemetry.
//! - Times are `Instant`s (the host's) for the rate, stalls and latency; the washout runs on the
//!   simulation's time (a time that goes back, or jumps by more than a second, restarts it).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use control::settings::Settings;

use super::config::CueSettings;
use super::reach::Reach;
use super::record::Recorder;
use super::telemetry::{Line, Listener, Sample, NAMES};
use super::washout::{Cue, Motion, Washout};
use crate::board;
use crate::error::{CueError, Dropped, Error};
use crate::link::Link;
use crate::streamer::min_median_max;
use crate::trajectory;

/// A sample whose time is within this of the previous one's is not a new sample, s.
pub const MIN_STEP_S: f64 = 1e-4;
/// A simulation time jump larger than this restarts the washout, s.
pub const RESTART_STEP_S: f64 = 1.0;
/// How often the progress is reported.
const LIVE_EVERY: Duration = Duration::from_millis(500);
/// Most datagrams taken in one pass before a frame may go.
const DRAIN: usize = 1000;

/// How `cue` runs.
#[derive(Debug, Clone)]
pub struct Options {
    /// Where to listen for telemetry (`ADDR:PORT`).
    pub listen: String,
    /// Frames per second; the board's `frame_hz` if not given (and never above it).
    pub rate_hz: Option<f64>,
    /// Where to record what came in and what was sent (CSV).
    pub record: Option<PathBuf>,
    /// Nothing valid within this is an error, s.
    pub wait_s: f64,
    /// Stop once home this long after the last valid sample, s (`None`: run until stopped).
    pub idle_exit_s: Option<f64>,
    /// Once set (by a Ctrl-C handler), ease home and stop.
    pub stop: Option<&'static AtomicBool>,
}

/// What the loop reports as it goes (the caller words it).
#[derive(Debug, Clone, Copy)]
pub enum Progress<'a> {
    /// Listening, with the board's settings read.
    Started {
        /// Where telemetry is awaited.
        address: &'a str,
        /// The board's port.
        port: &'a str,
        /// Frames per second at most.
        rate_hz: f64,
        /// Each axis' limit, mm and degrees.
        limits: &'a [f64; 6],
    },
    /// The counts so far (every half second).
    Live {
        /// The counts.
        counts: &'a Counts,
        /// Since the first frame, s.
        elapsed_s: f64,
    },
    /// Stopped by the user: easing home.
    Stopping,
}

/// Telemetry and frames counted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Counts {
    /// Datagrams received.
    pub datagrams: u64,
    /// Samples taken.
    pub samples: u64,
    /// What was dropped, by why.
    pub dropped: Dropped,
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
    /// Stopped by the user (Ctrl-C), after easing home.
    pub stopped: bool,
}

/// Whether the platform follows the cues or eases home.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Live,
    Stalled,
}

/// A smooth step 0 -> 1 (zero slope at both ends).
fn smooth(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The cueing state between passes.
struct Cueing {
    washout: Washout,
    reach: Reach,
    settings: Settings,
    counts: Counts,
    mode: Mode,
    /// The newest limited cue (live) and whether a limit changed it.
    target: (Cue, bool),
    /// A sample whose frame has not gone yet: when it arrived.
    pending: Option<Instant>,
    /// The newest sample.
    last_sample: Option<Sample>,
    last_valid_at: Option<Instant>,
    /// Easing from this pose, since then.
    blend: Option<(Cue, Instant)>,
    last_out: Cue,
    labels: Option<Vec<String>>,
    ease_s: f64,
}

impl Cueing {
    /// Takes one line of a datagram that arrived `at`.
    fn take(&mut self, line: Line, at: Instant) {
        let sample = match line {
            Line::Sample(s) => s,
            Line::Labels(names) => {
                self.labels = Some(names);
                return;
            }
            Line::Bad(kind, _) => {
                self.counts.dropped.count(kind);
                return;
            }
        };
        let dt = match &self.last_sample {
            None => 0.0,
            Some(last) => {
                let dt = sample.time_s - last.time_s;
                if !(-RESTART_STEP_S..=RESTART_STEP_S).contains(&dt) {
                    self.washout.reset();
                    self.counts.restarts += 1;
                    0.0
                } else if dt < MIN_STEP_S {
                    self.counts.dropped.stale += 1;
                    return;
                } else {
                    dt
                }
            }
        };
        self.counts.samples += 1;
        let cue = self.washout.step(&sample.motion, dt);
        self.target = self.reach.limit(&cue);
        if self.pending.is_some() {
            self.counts.late += 1;
        }
        self.pending = Some(at);
        self.last_sample = Some(sample);
        self.last_valid_at = Some(at);
        if self.mode == Mode::Stalled {
            self.mode = Mode::Live;
            self.blend = Some((self.last_out, at));
        }
    }

    /// The pose to send now, whether a limit changed it, and whether it is eased.
    fn output(&mut self, now: Instant) -> (Cue, bool, bool) {
        let (target, limited) = match self.mode {
            Mode::Live => self.target,
            Mode::Stalled => ([0.0; 6], false),
        };
        match self.blend {
            Some((from, start)) => {
                let w = smooth(now.saturating_duration_since(start).as_secs_f64() / self.ease_s);
                if w >= 1.0 {
                    self.blend = None;
                }
                let out = core::array::from_fn(|i| from[i] + (target[i] - from[i]) * w);
                (out, limited, true)
            }
            None => (target, limited, false),
        }
    }
}

/// `hexapod cue`: runs until the telemetry has ended and the platform is home
/// (`idle_exit_s`), or until stopped (`stop`, then home too); what it did.
pub fn run(
    link: &mut Link,
    cue: &CueSettings,
    options: &Options,
    progress: &mut dyn FnMut(Progress<'_>),
) -> Result<Summary, Error> {
    let listener = Listener::bind(&options.listen).map_err(|e| {
        Error::from(CueError::Listen {
            address: options.listen.clone(),
            why: e.to_string(),
        })
    })?;
    link.start()?;
    let settings = board::read_settings(link)?;
    let reach = Reach::new(&settings, cue.margin, cue.knee, cue.pivot_mm)
        .ok_or(Error::from(CueError::NotAPlatform))?;
    let board_hz = f64::from(settings.frame_hz);
    let rate = options.rate_hz.unwrap_or(board_hz).clamp(1.0, board_hz);
    let period = Duration::from_secs_f64(1.0 / rate);
    let stall = Duration::from_secs_f64(cue.stall_s);
    let before = board::read_counters(link)?;
    let mut recorder = match &options.record {
        Some(path) => Some(Recorder::create(path)?),
        None => None,
    };
    let limits = reach.limit;
    progress(Progress::Started {
        address: &listener.address.to_string(),
        port: link.port(),
        rate_hz: rate,
        limits: &limits,
    });
    let mut state = Cueing {
        washout: Washout::new(cue.tuning),
        reach,
        settings,
        counts: Counts::default(),
        mode: Mode::Stalled,
        target: ([0.0; 6], false),
        pending: None,
        last_sample: None,
        last_valid_at: None,
        blend: None,
        last_out: [0.0; 6],
        labels: None,
        ease_s: cue.ease_s,
    };
    let start = Instant::now();
    let mut first_frame: Option<Instant> = None;
    let mut last_sent = start - period;
    let mut last_live = start;
    let mut latencies_ms: Vec<f64> = Vec::new();
    let mut stopped = false;
    loop {
        if !stopped && options.stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            // The user stopped it: home from wherever the platform is, nothing more taken.
            stopped = true;
            progress(Progress::Stopping);
            if state.mode == Mode::Live || state.blend.is_some() {
                state.mode = Mode::Stalled;
                state.blend = Some((state.last_out, Instant::now()));
            }
            state.pending = None;
        }
        if stopped && state.blend.is_none() {
            break;
        }
        let now = Instant::now();
        let sending = state.pending.is_some() || state.blend.is_some();
        let mut wake = now + Duration::from_millis(100);
        if sending {
            wake = wake.min(last_sent + period);
        }
        if let (Mode::Live, Some(at)) = (state.mode, state.last_valid_at) {
            wake = wake.min(at + stall);
        }
        let taking = if stopped { None } else { listener.next(wake) };
        if stopped {
            // Frames at the rate until home.
            std::thread::sleep(wake.saturating_duration_since(Instant::now()));
        }
        if let Some(datagram) = taking {
            let mut next = Some(datagram);
            let mut taken = 0;
            while let Some(d) = next {
                state.counts.datagrams += 1;
                for line in d.lines {
                    state.take(line, d.at);
                }
                taken += 1;
                next = if taken < DRAIN {
                    listener.next(Instant::now())
                } else {
                    None
                };
            }
        }
        state.counts.dropped.overflowed = listener.overflowed();
        let now = Instant::now();
        if let (Mode::Live, Some(at)) = (state.mode, state.last_valid_at) {
            if now.saturating_duration_since(at) > stall {
                state.mode = Mode::Stalled;
                state.blend = Some((state.last_out, now));
                state.pending = None;
            }
        }
        if (state.pending.is_some() || state.blend.is_some()) && now >= last_sent + period {
            let (out, limited, easing) = state.output(now);
            // Within the limits, so within the full scales: a frame always exists.
            if let Ok(frame) = trajectory::binary_frame(&state.settings, &out) {
                link.write(&frame)?;
                let sent = Instant::now();
                let latency_ms = state
                    .pending
                    .take()
                    .map(|at| sent.saturating_duration_since(at).as_secs_f64() * 1e3);
                if let Some(ms) = latency_ms {
                    latencies_ms.push(ms);
                }
                state.counts.frames += 1;
                if limited {
                    state.counts.limited += 1;
                }
                let first = *first_frame.get_or_insert(sent);
                if let Some(recorder) = recorder.as_mut() {
                    let motion = state
                        .last_sample
                        .map_or(Motion::REST, |s| s.motion)
                        .in_platform_axes();
                    recorder.row(
                        sent.duration_since(first).as_secs_f64(),
                        state.last_sample.map(|s| s.time_s),
                        &motion,
                        &out,
                        limited,
                        easing,
                        latency_ms,
                    )?;
                }
                state.last_out = out;
                last_sent = sent;
            }
        }
        // Replies and notices the board sends meanwhile (none expected): let them go by.
        while link.try_line()?.is_some() {}
        if now.duration_since(last_live) >= LIVE_EVERY {
            last_live = now;
            let elapsed_s = first_frame.map_or(0.0, |f| now.duration_since(f).as_secs_f64());
            progress(Progress::Live {
                counts: &state.counts,
                elapsed_s,
            });
        }
        match state.last_valid_at {
            None if !stopped && now.duration_since(start).as_secs_f64() > options.wait_s => {
                return Err(Error::from(CueError::NoTelemetry {
                    address: listener.address.to_string(),
                    waited_s: options.wait_s,
                    datagrams: state.counts.datagrams,
                    dropped: state.counts.dropped.clone(),
                    fields: &NAMES,
                    labels: state.labels.clone(),
                }));
            }
            Some(at)
                if state.mode == Mode::Stalled
                    && state.blend.is_none()
                    && options
                        .idle_exit_s
                        .is_some_and(|s| now.duration_since(at).as_secs_f64() > s) =>
            {
                break;
            }
            _ => {}
        }
    }
    if let Some(recorder) = recorder.as_mut() {
        recorder.finish()?;
    }
    let after = board::read_counters(link)?;
    let c = after.since(&before);
    let latency_ms = percentiles(&latencies_ms);
    let summary = Summary {
        address: listener.address.to_string(),
        port: link.port().to_string(),
        counts: state.counts,
        duration_s: first_frame.map_or(0.0, |f| f.elapsed().as_secs_f64()),
        latency_ms,
        board: Some([c.frames, c.applied, c.damaged, c.clamped, c.refused]),
        limits,
        record: options.record.as_ref().map(|p| p.display().to_string()),
        stopped,
    };
    Ok(summary)
}

/// Min, median, 99th percentile and max.
fn percentiles(values: &[f64]) -> Option<[f64; 4]> {
    let (min, median, max) = min_median_max(values)?;
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let p99 = sorted[((sorted.len() - 1) as f64 * 0.99).round() as usize];
    Some([min, median, p99, max])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ease_is_smooth_and_ends_where_it_should() {
        assert_eq!(smooth(0.0), 0.0);
        assert_eq!(smooth(1.0), 1.0);
        assert_eq!(smooth(2.0), 1.0);
        assert_eq!(smooth(0.5), 0.5);
        // Zero slope at both ends.
        assert!(smooth(0.01) < 0.001 && smooth(0.99) > 0.999);
    }

    #[test]
    fn percentiles_of_a_hundred() {
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(percentiles(&v), Some([1.0, 50.5, 99.0, 100.0]));
        assert_eq!(percentiles(&[]), None);
    }
}
