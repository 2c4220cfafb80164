//! `stream` (and `demo --port`): a trajectory sent to a board at its own timing, each row when
//! its time comes (wall clock, from a start 100 ms after the last check), after every row was
//! checked against the board's own settings ([`stream_checked`]); the summary in words.
//!
//! - **Binary** (default): a compact stream frame per row (README, "Streaming from
//!   motion-simulator software"). Frames get no reply, so their own latency cannot be seen from
//!   the host; what can be measured is measured: a `status` line every `status_every`
//!   (between two frames, never inside one), whose round trip (line sent to its final reply
//!   received) says how long the board takes to answer while streaming, and the board's own
//!   counters (frames received, applied, damaged, clamped, refused) before and after.
//! - **Text** (`--text`): a `pose` line per row, each answered: its round trip is that row's
//!   latency, and a refusal is that row's error (named with its line; the stream goes on and
//!   the summary counts it).
//!
//! A row is late when it was sent more than `late_after` after its time (the previous reply
//! took too long, or the host was busy). Times are `Instant`s and `Duration`s; the summary
//! gives milliseconds.

use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

use crate::board::{self, StreamCounters};
use crate::error::Error;
use crate::link::{is_final, is_notice, Link};
use crate::messages;
use crate::trajectory::{self, Message, Mode, Row};

/// When the first row goes, after the checks.
const START_DELAY: Duration = Duration::from_millis(100);

/// How a stream is run.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    /// Binary frames or `pose` lines.
    pub mode: Mode,
    /// How often a `status` is sent during a binary stream.
    pub status_every: Duration,
    /// A row sent later than this after its time is late.
    pub late_after: Duration,
    /// Show a progress bar (on a terminal).
    pub progress: bool,
}

/// The progress bar of `stream` (indicatif's template).
const PROGRESS_TEMPLATE: &str = "{bar:40} {pos}/{len} rows  {elapsed_precise}";

/// A row the board refused during a stream.
fn row_refused(line: u64, sent: &str, reply: &str) -> String {
    format!("line {line}: the board refused '{sent}': {reply}")
}

/// A refused row: its line in the file and the board's reply.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RowRefusal {
    /// The row's line.
    pub line: u64,
    /// The board's reply.
    pub reply: String,
}

/// What a stream did.
#[derive(Debug, Clone)]
pub struct Summary {
    /// How rows were sent.
    pub mode: Mode,
    /// Rows sent.
    pub sent: usize,
    /// From the first row sent to the last reply, s.
    pub duration_s: f64,
    /// Round trips measured, ms (each `pose` line, or each `status` during a binary stream).
    pub round_trips_ms: Vec<f64>,
    /// Rows sent more than `late_after` after their time.
    pub late: usize,
    /// The threshold, ms.
    pub late_after_ms: f64,
    /// The latest a row was sent after its time, ms.
    pub worst_late_ms: f64,
    /// Refused lines (text mode), and refused `status` lines.
    pub refusals: Vec<RowRefusal>,
    /// Notices the board sent meanwhile (`# warning: ...`).
    pub notices: Vec<String>,
    /// The board's stream counters over the stream (binary mode).
    pub counters: Option<StreamCounters>,
}

impl Summary {
    /// Whether anything went wrong: a refusal, a notice, a damaged or refused frame.
    pub fn has_errors(&self) -> bool {
        !self.refusals.is_empty()
            || !self.notices.is_empty()
            || self
                .counters
                .is_some_and(|c| c.damaged > 0 || c.refused > 0 || c.frames != self.sent as u64)
    }

    /// The summary in words: `file` streamed to `port`.
    pub fn words(&self, file: &str, port: &str) -> String {
        let s = self;
        let mut out = String::new();
        let how = match s.mode {
            Mode::Binary => "binary frames",
            Mode::Text => "pose lines",
        };
        out += &format!(
            "{file}: {} rows sent to {port} as {how} in {:.2} s\n",
            s.sent, s.duration_s
        );
        match (s.mode, &s.counters) {
            (Mode::Binary, Some(c)) => {
                out += &format!(
                    "  frames sent: {}; the board counted frames={} applied={} damaged={} \
                     clamped={} refused={}\n",
                    s.sent, c.frames, c.applied, c.damaged, c.clamped, c.refused
                );
            }
            _ => {
                out += &format!(
                    "  lines sent: {}, ok: {}, refused: {}\n",
                    s.sent,
                    s.sent - s.refusals.len(),
                    s.refusals.len()
                );
            }
        }
        let what = match s.mode {
            Mode::Binary => {
                "status lines sent during the stream, line to reply; frames get no \
                             reply, so their own latency cannot be seen from the host"
            }
            Mode::Text => "each pose line to its reply",
        };
        match min_median_max(&s.round_trips_ms) {
            Some((min, median, max)) => {
                out += &format!(
                    "  round trip ({what}): {} samples, min {min:.2} ms, median {median:.2} ms, \
                     max {max:.2} ms\n",
                    s.round_trips_ms.len()
                )
            }
            None => out += &format!("  round trip ({what}): no samples\n"),
        }
        out += &format!(
            "  late rows (sent more than {:.1} ms after their time): {} (latest {:.2} ms)\n",
            s.late_after_ms, s.late, s.worst_late_ms
        );
        let errors = s.refusals.len() + s.notices.len();
        out += &format!("  errors: {errors}");
        if let Some(first) = s.refusals.first() {
            out += &format!(" (first: line {}: {})", first.line, first.reply);
        } else if let Some(first) = s.notices.first() {
            out += &format!(" (first: {first})");
        }
        out
    }
}

/// Reads the board's settings (`config`), checks every row against them as the board will get
/// it (`trajectory::prepare`), streams them; the summary, or, if the stream did not go through
/// whole, the summary printed and an error.
pub fn stream_checked(
    link: &mut Link,
    file: &str,
    rows: &[Row],
    options: &Options,
) -> Result<String, Error> {
    let settings = board::read_settings(link)?;
    let to_send = trajectory::prepare(file, rows, &settings, options.mode)?;
    let summary = run(link, rows, &to_send, options)?;
    let text = summary.words(file, link.port());
    if !summary.has_errors() {
        return Ok(text);
    }
    messages::summary(&text);
    let c = summary.counters.unwrap_or_default();
    Err(Error::StreamTrouble {
        file: file.to_string(),
        refused: summary.refusals.len(),
        notices: summary.notices.len(),
        lost_frames: (summary.sent as u64).saturating_sub(c.frames) + c.damaged,
        refused_frames: c.refused,
    })
}

/// Sends `messages` (one per row of `rows`) at the rows' times. The link must be started.
pub fn run(
    link: &mut Link,
    rows: &[Row],
    messages: &[Message],
    options: &Options,
) -> Result<Summary, Error> {
    let before = match options.mode {
        Mode::Binary => Some(board::read_counters(link)?),
        Mode::Text => None,
    };
    let bar = if options.progress {
        let bar = ProgressBar::new(rows.len() as u64);
        if let Ok(style) = ProgressStyle::with_template(PROGRESS_TEMPLATE) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar
    } else {
        ProgressBar::hidden()
    };
    let mut summary = Summary {
        mode: options.mode,
        sent: 0,
        duration_s: 0.0,
        round_trips_ms: Vec::new(),
        late: 0,
        late_after_ms: options.late_after.as_secs_f64() * 1e3,
        worst_late_ms: 0.0,
        refusals: Vec::new(),
        notices: Vec::new(),
        counters: None,
    };
    let first_time_s = rows.first().map_or(0.0, |r| r.time_s);
    let start = Instant::now() + START_DELAY;
    // The `status` in flight (binary mode): when it was sent.
    let mut status_sent: Option<Instant> = None;
    let mut last_status = start;
    for (row, message) in rows.iter().zip(messages) {
        let due = start + Duration::from_secs_f64(row.time_s - first_time_s);
        // Until the row's time: what the board says (status replies, notices).
        while let Some(received) = link.next_line(due)? {
            take_line(
                &received.line,
                received.at,
                &mut status_sent,
                &mut summary,
                &bar,
            );
        }
        let now = Instant::now();
        let late = now.saturating_duration_since(due);
        summary.worst_late_ms = summary.worst_late_ms.max(late.as_secs_f64() * 1e3);
        if late > options.late_after {
            summary.late += 1;
        }
        match message {
            Message::Frame(frame) => {
                link.write(frame)?;
                if status_sent.is_none() && now.duration_since(last_status) >= options.status_every
                {
                    link.send_line("status")?;
                    status_sent = Some(Instant::now());
                    last_status = now;
                }
            }
            Message::Line(line) => {
                link.send_line(line)?;
                let reply = link.read_reply(line)?;
                summary
                    .round_trips_ms
                    .push(reply.at.saturating_duration_since(now).as_secs_f64() * 1e3);
                for notice in &reply.notices {
                    bar.suspend(|| eprintln!("{notice}"));
                    summary.notices.push(notice.clone());
                }
                if !reply.is_ok() {
                    bar.suspend(|| eprintln!("{}", row_refused(row.line, line, &reply.last)));
                    summary.refusals.push(RowRefusal {
                        line: row.line,
                        reply: reply.last,
                    });
                }
            }
        }
        summary.sent += 1;
        bar.inc(1);
    }
    // The last `status` in flight, then the board's counters.
    if status_sent.is_some() {
        let until = Instant::now() + link.timeout;
        while status_sent.is_some() {
            let Some(received) = link.next_line(until)? else {
                return Err(link.no_reply("status"));
            };
            take_line(
                &received.line,
                received.at,
                &mut status_sent,
                &mut summary,
                &bar,
            );
        }
    }
    if let Some(before) = before {
        let after = board::read_counters(link)?;
        summary.counters = Some(after.since(&before));
    }
    summary.duration_s = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    Ok(summary)
}

/// A line received during a binary stream: a `status` reply's end, a notice, or data.
fn take_line(
    line: &str,
    at: Instant,
    status_sent: &mut Option<Instant>,
    summary: &mut Summary,
    bar: &ProgressBar,
) {
    if is_final(line) {
        if let Some(sent) = status_sent.take() {
            summary
                .round_trips_ms
                .push(at.saturating_duration_since(sent).as_secs_f64() * 1e3);
        }
        if line != "ok" {
            summary.refusals.push(RowRefusal {
                line: 0,
                reply: line.to_string(),
            });
        }
    } else if is_notice(line) {
        bar.suspend(|| eprintln!("{line}"));
        summary.notices.push(line.to_string());
    }
}

/// Min, median and max of some numbers (`None` if there are none).
pub fn min_median_max(values: &[f64]) -> Option<(f64, f64, f64)> {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    let median = match n {
        0 => return None,
        _ if n % 2 == 1 => sorted[n / 2],
        _ => (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0,
    };
    Some((sorted[0], median, sorted[n - 1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_median_max_of_odd_even_and_none() {
        assert_eq!(min_median_max(&[3.0, 1.0, 2.0]), Some((1.0, 2.0, 3.0)));
        assert_eq!(min_median_max(&[4.0, 1.0, 2.0, 3.0]), Some((1.0, 2.5, 4.0)));
        assert_eq!(min_median_max(&[]), None);
    }
}
