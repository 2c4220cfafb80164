//! Every word the tool itself writes for a user: its errors ([`Problem`]) and its summaries.
//! The board's words are not here: a refusal is quoted as the board wrote it, or, for what the
//! tool checks before sending (a build file, a trajectory), worded by `control::report` exactly
//! as the board would word it ([`board_words`]). Units are part of the wording: mm, degrees,
//! seconds, milliseconds, microseconds, kg and N·m, written out in each message.

use std::fmt::{self, Display, Formatter};
use std::io;

use control::report::refusal;

/// The board's own words for a refusal: `error:<code> <message>` as the firmware writes it.
pub fn board_words(error: &control::Error) -> String {
    refusal(error).to_string()
}

/// Why a subcommand could not do its job. Each names where the trouble is: the file and line
/// (and key or field), or the port.
#[derive(Debug)]
pub enum Problem {
    /// A file could not be read or written.
    File {
        /// The file.
        path: String,
        /// What the system said.
        error: io::Error,
    },
    /// A build file that is not TOML at all.
    Toml {
        /// The file.
        file: String,
        /// Line, from 1.
        line: usize,
        /// The TOML parser's description (its own words).
        message: String,
    },
    /// A key of a build file.
    Key {
        /// The file.
        file: String,
        /// Line, from 1.
        line: usize,
        /// The key as a `set` name.
        key: String,
        /// What is wrong with it.
        why: KeyProblem,
    },
    /// The serial port or the board behind it.
    Port {
        /// The port's name.
        port: String,
        /// What went wrong.
        why: PortProblem,
    },
    /// The board refused a line: the line and the board's reply.
    Refused {
        /// Where the line came from (`build.toml:4`), if from a file.
        at: Option<String>,
        /// The port.
        port: String,
        /// The line sent.
        line: String,
        /// The board's final reply (`error:...`).
        reply: String,
    },
    /// A row (or the header) of a trajectory file.
    Row {
        /// The file.
        file: String,
        /// Line, from 1.
        line: u64,
        /// The column at fault, if one is.
        field: Option<String>,
        /// What is wrong.
        why: RowProblem,
    },
    /// An ELF file the UF2 writer cannot use.
    Elf {
        /// The file.
        path: String,
        /// Why (the reader's words).
        why: String,
    },
    /// A command-line value that is not usable (the option and why).
    Option {
        /// The option, as typed (`--radius-mm`).
        option: &'static str,
        /// Why.
        why: String,
    },
    /// A stream that ended with rows refused, frames lost or notices (the summary says which).
    StreamTrouble {
        /// The trajectory.
        file: String,
        /// Rows (or `status` lines) refused.
        refused: usize,
        /// Notices the board sent (`# warning: ...`).
        notices: usize,
        /// Frames the board did not count as received whole (damaged or never seen).
        lost_frames: u64,
        /// Frames the board refused (e-stop).
        refused_frames: u64,
    },
    /// A pose the platform cannot take (the board's words for why).
    Pose {
        /// The pose, as typed.
        pose: String,
        /// The board's words.
        why: String,
    },
}

/// What is wrong with a key of a build file.
#[derive(Debug)]
pub enum KeyProblem {
    /// Refused by the firmware's own checks (an unknown name, a bad or out-of-range value, a
    /// servo set or geometry that does not hold together): the board's words.
    Refused(Box<control::Error>),
    /// `baud` or `echo`: the link's, not the platform's.
    LinkSetting,
    /// A value that is not a number or a word (an array, a date, a table too deep).
    NotAValue,
}

/// What went wrong with a serial port.
#[derive(Debug)]
pub enum PortProblem {
    /// It could not be opened (the system's words).
    Open(String),
    /// Reading or writing failed (the system's words).
    Io(String),
    /// No final reply to a line in time.
    NoReply {
        /// The line sent.
        line: String,
        /// How long the tool waited, s.
        waited_s: f64,
    },
    /// Bytes were lost on the way to the board (a `# warning:`) and the line got no reply.
    LineLost {
        /// The line sent.
        line: String,
    },
    /// A reply the tool cannot read (`config` without a value it knows, `status` without a
    /// counter).
    Unreadable {
        /// The line sent.
        line: String,
        /// The reply line at fault.
        reply: String,
    },
}

/// What is wrong with a row of a trajectory file.
#[derive(Debug)]
pub enum RowProblem {
    /// The CSV reader could not read it (its words).
    Unreadable(String),
    /// The header does not name the seven columns.
    Header {
        /// The columns found.
        found: String,
    },
    /// Fewer or more fields than the header has.
    FieldCount {
        /// How many the row has.
        found: usize,
    },
    /// A field that is not a decimal number (as found).
    NotANumber(String),
    /// `nan` or `inf`.
    NotFinite(String),
    /// Time does not increase.
    TimeNotIncreasing {
        /// The row's time, s.
        time_s: f64,
        /// The previous row's, s.
        previous_s: f64,
    },
    /// A value beyond the board's stream full scale for the axis (the board would clamp it).
    BeyondFullScale {
        /// The value, mm or degrees.
        value: f64,
        /// The setting that holds the full scale.
        setting: String,
        /// The full scale, mm or degrees.
        full_scale: f32,
    },
    /// The pose would be refused by the board: its words.
    Refused(String),
    /// A file with no rows.
    Empty,
}

fn file_line(f: &mut Formatter<'_>, file: &str, line: impl Display) -> fmt::Result {
    write!(f, "{file}:{line}: ")
}

impl Display for Problem {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Problem::File { path, error } => write!(f, "{path}: {error}"),
            Problem::Toml {
                file,
                line,
                message,
            } => {
                file_line(f, file, line)?;
                write!(f, "not a TOML file: {}", message.trim_end())
            }
            Problem::Key {
                file,
                line,
                key,
                why,
            } => {
                file_line(f, file, line)?;
                match why {
                    KeyProblem::Refused(error) => write!(f, "{key}: {}", board_words(error)),
                    KeyProblem::LinkSetting => write!(
                        f,
                        "{key}: belongs to the serial link, not the platform (it is not saved); \
                         a build file does not set it"
                    ),
                    KeyProblem::NotAValue => write!(
                        f,
                        "{key}: not a setting value (a setting takes a number or a word; \
                         settings go in [servoN], [servos] or [stream] tables at most)"
                    ),
                }
            }
            Problem::Port { port, why } => match why {
                PortProblem::Open(e) => write!(f, "{port}: cannot open the serial port: {e}"),
                PortProblem::Io(e) => write!(f, "{port}: serial port error: {e}"),
                PortProblem::NoReply { line, waited_s } => write!(
                    f,
                    "{port}: the board did not answer '{line}' within {waited_s:.1} s (is it \
                     powered, on this port, at this baud rate?)"
                ),
                PortProblem::LineLost { line } => write!(
                    f,
                    "{port}: bytes were lost on the way to the board and '{line}' got no \
                     reply; nothing more was sent"
                ),
                PortProblem::Unreadable { line, reply } => {
                    write!(f, "{port}: cannot read the reply to '{line}': '{reply}'")
                }
            },
            Problem::Refused {
                at,
                port,
                line,
                reply,
            } => {
                if let Some(at) = at {
                    write!(f, "{at}: ")?;
                }
                write!(f, "{port}: the board refused '{line}': {reply}")
            }
            Problem::Row {
                file,
                line,
                field,
                why,
            } => {
                file_line(f, file, line)?;
                if let Some(field) = field {
                    write!(f, "{field}: ")?;
                }
                match why {
                    RowProblem::Unreadable(e) => write!(f, "unreadable row: {e}"),
                    RowProblem::Header { found } => write!(
                        f,
                        "the header must name the columns time,x,y,z,roll,pitch,yaw (s, mm, \
                         degrees); found '{found}'"
                    ),
                    RowProblem::FieldCount { found } => {
                        write!(f, "{found} fields; a row has 7 (time,x,y,z,roll,pitch,yaw)")
                    }
                    RowProblem::NotANumber(text) => write!(f, "'{text}' is not a number"),
                    RowProblem::NotFinite(text) => write!(f, "'{text}' is not a finite number"),
                    RowProblem::TimeNotIncreasing { time_s, previous_s } => write!(
                        f,
                        "time {time_s} s is not after the previous row's {previous_s} s"
                    ),
                    RowProblem::BeyondFullScale {
                        value,
                        setting,
                        full_scale,
                    } => write!(
                        f,
                        "{value} is beyond the board's stream full scale {setting} = \
                         {full_scale} (the board would clamp it); raise {setting} or use --text"
                    ),
                    RowProblem::Refused(words) => {
                        write!(
                            f,
                            "the board would refuse this pose: {words}; nothing was sent"
                        )
                    }
                    RowProblem::Empty => f.write_str("no rows: nothing to do"),
                }
            }
            Problem::Elf { path, why } => write!(f, "{path}: {why}"),
            Problem::Option { option, why } => write!(f, "{option}: {why}"),
            Problem::Pose { pose, why } => write!(f, "pose {pose}: {why}"),
            Problem::StreamTrouble {
                file,
                refused,
                notices,
                lost_frames,
                refused_frames,
            } => write!(
                f,
                "{file}: the stream did not go through whole: {refused} lines refused,                  {lost_frames} frames damaged or lost, {refused_frames} frames refused,                  {notices} notices from the board (see above)"
            ),
        }
    }
}

impl std::error::Error for Problem {}

/// `init`, `pull`: a build file was written.
pub fn wrote_build_file(path: &str, source: &str) -> String {
    format!("{path}: the build file of {source}; edit it, then `hexapod apply {path} --port PORT`")
}

/// Where the settings of `init` come from.
pub const DEFAULT_PLATFORM: &str = "the default platform";

/// `pull`: the settings' source.
pub fn board_on(port: &str) -> String {
    format!("the board on {port}")
}

/// `apply`: done.
pub fn applied(file: &str, port: &str, settings: usize, saved: bool) -> String {
    let saved = if saved {
        "and saved in flash (the board starts with them at power-up)"
    } else {
        "not saved (--no-save): they last until the board restarts"
    };
    format!("{file}: {settings} settings applied to the board on {port}, {saved}")
}

/// `apply` without a port: the file is good.
pub fn build_file_good(file: &str, settings: usize) -> String {
    format!("{file}: {settings} settings, all accepted by the firmware's own checks")
}

/// `uf2`: the file written.
pub fn wrote_uf2(
    output: &str,
    blocks: usize,
    kib: usize,
    elf: &str,
    settings: Option<&str>,
) -> String {
    let with = match settings {
        Some(file) => format!(" and the settings of {file} (saved, as if by `save`)"),
        None => String::new(),
    };
    format!(
        "{output}: {blocks} blocks, {kib} KiB of flash from {elf}{with}; hold BOOTSEL while \
         plugging the Pico in, then copy it onto the RPI-RP2 drive"
    )
}

/// `demo -o`: the CSV written.
pub fn wrote_trajectory(path: &str, rows: usize, duration_s: f64) -> String {
    format!("{path}: {rows} rows, {duration_s:.2} s (time,x,y,z,roll,pitch,yaw in s, mm, degrees)")
}

/// `draw`: the pictures written.
pub fn wrote_pictures(paths: &[String]) -> String {
    format!("wrote {}", paths.join(", "))
}

/// `send`, `shell`: a notice the board sent on its own, shown as it came.
pub fn board_notice(line: &str) -> String {
    line.to_string()
}

/// `shell`: the greeting.
pub fn shell_greeting(port: &str) -> String {
    format!(
        "# connected to {port} (echo off: the tool shows each reply); type commands, help for \
         the board's list, Ctrl-D to quit"
    )
}

/// `shell`: the prompt.
pub const SHELL_PROMPT: &str = "hexapod> ";

/// The first lines of a build file (`init`, `pull`).
pub fn build_file_header(source: &str) -> String {
    format!(
        "# hexapod build file: the settings of {source}.\n\
         # Keys are the firmware's `set` names (README, \"Settings\"): `[servo3] trim_us = 1512` is\n\
         # `set servo3.trim_us 1512`. Lengths in mm, angles in degrees, pulses in microseconds.\n\
         # A key left out is the firmware's default. `hexapod apply FILE` (no port) checks it;\n\
         # `hexapod apply FILE --port PORT` sends `defaults`, every `set`, then `save`.\n\n"
    )
}

/// What a setting is, for a build file's comments (its range comes from the firmware).
pub fn setting_meaning(id: control::settings::SettingId) -> &'static str {
    use control::settings::{LayoutParam as L, ServoParam as P, SettingId as S};
    use kinematics_core::pose::Axis;
    match id {
        S::FrameHz => "servo frame rate",
        S::Baud => "UART0 baud rate",
        S::Echo => "echo and prompt on the link",
        S::SpeedMmS => "linear speed limit",
        S::SpeedDegS => "angular speed limit",
        S::AccelMmS2 => "linear acceleration limit",
        S::AccelDegS2 => "angular acceleration limit",
        S::LinkTimeoutS => "return home after this long without a command",
        S::Layout(L::BaseRadiusMm) => "servo shaft circle radius",
        S::Layout(L::BaseHalfAngleDeg) => "half the angle between a servo pair",
        S::Layout(L::PlatformRadiusMm) => "platform joint circle radius",
        S::Layout(L::PlatformHalfAngleDeg) => "half the angle between a joint pair",
        S::Layout(L::ArmMm) => "servo arm (horn) length a",
        S::Layout(L::RodMm) => "rod length s",
        S::Servo(_, P::TrimUs) => "home pulse W0",
        S::Servo(_, P::RateUsRad) => "servo rate r",
        S::Servo(_, P::Dir) => "direction",
        S::Servo(_, P::MinUs) => "lowest pulse",
        S::Servo(_, P::MaxUs) => "highest pulse",
        S::StreamScale(Axis::X | Axis::Y | Axis::Z) => "stream full scale of the axis",
        S::StreamScale(_) => "stream full scale of the axis",
        S::StreamBits => "bits of a text frame's counts",
        S::StreamAxis(_) => "the axis this text-frame count drives",
        S::EstopPin => "emergency-stop input",
        S::EstopAction => "what an open e-stop does",
        S::PowerPin => "servo-power enable output",
    }
}

/// Why the settings sectors of a firmware ELF cannot be written.
pub fn storage_problem(e: &crate::flash_image::StorageError) -> String {
    use crate::flash_image::{StorageError, SETTINGS_END, SETTINGS_START};
    match e {
        StorageError::NoSymbols => format!(
            "no {SETTINGS_START}/{SETTINGS_END} symbols: not a firmware with settings storage \
             (memory.x)"
        ),
        StorageError::BadStorage { start, end } => format!(
            "{SETTINGS_START}..{SETTINGS_END} = {start:#010x}..{end:#010x} is not two aligned \
             4 KiB sectors"
        ),
    }
}

/// The progress bar of `stream` (indicatif's template).
pub const PROGRESS_TEMPLATE: &str = "{bar:40} {pos}/{len} rows  {elapsed_precise}";

/// A row the board refused during a stream.
pub fn row_refused(line: u64, sent: &str, reply: &str) -> String {
    format!("line {line}: the board refused '{sent}': {reply}")
}

/// The summary of a stream.
pub fn stream_summary(file: &str, port: &str, s: &crate::streamer::Summary) -> String {
    use crate::streamer::min_median_max;
    use crate::trajectory::Mode;
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

/// What a demo is called in messages (its rows' "file").
pub fn demo_name(kind: crate::demo::Kind) -> String {
    use clap::ValueEnum;
    let name = kind
        .to_possible_value()
        .map_or_else(|| "?".to_string(), |v| v.get_name().to_string());
    format!("demo {name}")
}

/// `demo` with neither a port nor an output file.
pub const DEMO_NEEDS_A_PLACE: &str =
    "give --port PORT to stream the demo to a board, or --output FILE.csv to write it";

/// `demo`: a time that is not positive.
pub const MUST_BE_POSITIVE: &str = "must be a positive number of seconds";
/// `demo`: the row rate.
pub const RATE_RANGE: &str = "must be 1..1000 rows per second";
/// `demo`: the size.
pub const AMPLITUDE_RANGE: &str = "must be 0..500 mm";
/// `demo`: the tour's fraction of the reach.
pub const FRACTION_RANGE: &str = "must be more than 0 and at most 1";

/// A drawing's title.
pub fn drawing_title(pose: &str) -> String {
    format!("pose {pose}  (x y z mm, roll pitch yaw degrees)")
}

/// A drawing of a pose the platform takes.
pub const DRAWING_REACHABLE: &str =
    "reachable: every leg reaches its joint within its servo's limits";

/// A drawing of a pose the platform cannot take: its lines.
pub fn drawing_refused(words: &str, arms_at: f64) -> Vec<String> {
    let mut lines = vec![format!("refused: {words}")];
    if arms_at < 1.0 {
        lines.push(format!(
            "the arms are drawn at the last reachable pose on the straight way from home ({:.0}% \
             of the way); the dashed rod cannot meet its joint",
            arms_at * 100.0
        ));
    }
    lines
}

/// A view's title.
pub fn view_title(view: crate::draw::View) -> &'static str {
    use crate::draw::View;
    match view {
        View::Top => "top (looking down; x right, y up)",
        View::Front => "front (looking along +y; x right, z up)",
        View::Side => "side (looking along -x; y right, z up)",
        View::Perspective => "perspective",
    }
}

/// A scale bar's label.
pub fn scale_bar(mm: f64) -> String {
    format!("{mm:.0} mm")
}

/// A pose text that the firmware's parser read as something else.
pub const NOT_A_POSE: &str = "not six numbers x y z roll pitch yaw";

/// `draw` of a pose the platform cannot take.
pub fn drew_refused(summary: &str, words: &str) -> String {
    format!("{summary}\nthe platform cannot take this pose: {words}")
}
