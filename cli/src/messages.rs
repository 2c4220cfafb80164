//! Every word the tool itself writes for a user: its errors ([`Problem`]) and its summaries.
//! The board's words are not here: a refusal is quoted as the board wrote it, or, for what the
//! tool checks before sending (a build file, a trajectory), worded by `control::report` exactly
//! as the board would word it ([`board_words`]). Units are part of the wording: mm, degrees,
//! seconds, milliseconds, microseconds, grams and kgf cm, written out in each message.

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
    /// `cue` and `cue-plot`'s (their words are `crate::cue::words`').
    Cue(Box<crate::cue::words::CueProblem>),
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
    /// `torque` of a platform that carries nothing (`payload_g` 0).
    NoPayload {
        /// The platform (a build file, or the default platform).
        source: String,
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
    /// A `[sizing]` key that is not one, or its value out of range: why.
    Sizing(SizingProblem),
    /// With the payload and ratings so far, a servo would need more than its rating to hold
    /// the platform at home: the board, holding home, refuses the setting (`pose-conflict`).
    OverloadedAtHome(control::payload::TorqueError),
}

/// What is wrong with a `[sizing]` key.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SizingProblem {
    /// Not one of the sizing keys.
    Unknown,
    /// A key the table once had, now a setting of the board.
    Moved {
        /// The setting to write instead.
        setting: control::settings::SettingId,
        /// The key's value in the setting's unit, if it was a number.
        value: Option<f32>,
    },
    /// Not a number in `min..=max` (of the key's unit).
    Range {
        /// Smallest.
        min: f32,
        /// Largest.
        max: f32,
        /// Unit.
        unit: &'static str,
    },
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
            Problem::Cue(why) => write!(f, "{why}"),
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
                    KeyProblem::Sizing(SizingProblem::Unknown) => write!(
                        f,
                        "{key}: not a sizing key; [sizing] takes {}",
                        crate::sizing::KEYS.join(", ")
                    ),
                    KeyProblem::Sizing(SizingProblem::Range { min, max, unit }) => {
                        write!(f, "{key}: must be a number {min}..{max} {unit}")
                    }
                    KeyProblem::Sizing(SizingProblem::Moved { setting, value }) => {
                        write!(
                            f,
                            "{key}: now the board's setting {setting} ({}): write {} instead",
                            setting_unit(*setting),
                            setting_placement(*setting, *value)
                        )
                    }
                    KeyProblem::OverloadedAtHome(cause) => write!(
                        f,
                        "{key}: at home {}; the board, holding home, refuses this setting \
                         (error:pose-conflict)",
                        torque_words(cause)
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
            Problem::NoPayload { source } => write!(
                f,
                "{source}: no payload (payload_g = 0): the servos hold nothing, so every torque \
                 is 0; give payload_g (g) and payload_com_x_mm, payload_com_y_mm, \
                 payload_com_z_mm (mm, platform frame) in the build file (--settings)"
            ),
            Problem::StreamTrouble {
                file,
                refused,
                notices,
                lost_frames,
                refused_frames,
            } => write!(
                f,
                "{file}: the stream did not go through whole: {refused} lines refused, \
                 {lost_frames} frames damaged or lost, {refused_frames} frames refused, \
                 {notices} notices from the board (see above)"
            ),
        }
    }
}

impl std::error::Error for Problem {}

/// The unit of a setting, from the firmware's own [`Kind`](control::settings::Kind).
fn setting_unit(id: control::settings::SettingId) -> &'static str {
    match id.kind() {
        control::settings::Kind::Number { unit, .. } => unit,
        _ => "",
    }
}

/// Where and how a build file says a setting: `payload_g = 2500` above the first table, and
/// for a name with a dot (`servos.torque_kgcm`) either the dotted key or the table.
fn setting_placement(id: control::settings::SettingId, value: Option<f32>) -> String {
    let name = id.to_string();
    let value = value.map_or_else(String::new, |v| {
        // To a thousandth: the unit changed (2.5 kg is 2500 g), not the number's precision.
        format!(" = {}", (v * 1000.0).round() / 1000.0)
    });
    let above = format!("`{name}{value}` above the file's first [table]");
    match name.split_once('.') {
        Some((table, key)) => format!("{above} (or `{key}{value}` in a [{table}] table)"),
        None => above,
    }
}

/// A torque refusal in the board's words, without its code.
fn torque_words(cause: &control::payload::TorqueError) -> String {
    control::Error::Torque(*cause).to_string()
}

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
         # Keys are the firmware's `set` names (README, \"Settings\"):\n\
         # `[servo3] trim_us = 1512` is `set servo3.trim_us 1512`.\n\
         # Lengths in mm, angles in degrees, pulses in microseconds.\n\
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
        S::Servo(_, P::TorqueKgcm) => "rated torque",
        S::StreamScale(Axis::X | Axis::Y | Axis::Z) => "stream full scale of the axis",
        S::StreamScale(_) => "stream full scale of the axis",
        S::StreamBits => "bits of a text frame's counts",
        S::StreamAxis(_) => "the axis this text-frame count drives",
        S::EstopPin => "emergency-stop input",
        S::EstopAction => "what an open e-stop does",
        S::PowerPin => "servo-power enable output",
        S::PayloadG => "mass the platform carries (0: none)",
        S::PayloadCom(0) => "payload centre of mass, platform frame x",
        S::PayloadCom(1) => "payload centre of mass, platform frame y",
        S::PayloadCom(_) => "payload centre of mass, platform frame z (up)",
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

/// A build file without a payload: how to give one (commented, so the file still says the
/// board's defaults).
pub const PAYLOAD_EXAMPLE: &str = "\
# No payload: the board shows and checks no holding torques. To give one, e.g. 500 g whose\n\
# centre of mass is 20 mm above the platform, on micro servos rated 1.8 kgf cm (an SG90):\n\
#   payload_g = 500\n\
#   payload_com_z_mm = 20\n\
#   and torque_kgcm = 1.8 in each [servoN] below\n";

/// The `[sizing]` table's heading in a build file.
pub const SIZING_HEADER: &str = "\n\
# Host-only: the servos' holding stiffness, for `describe` (the platform's stiffness, how far\n\
# the payload's weight moves it). The board has no such setting: `apply` never sends it.\n\
[sizing]\n";

/// What a `[sizing]` key is, for a build file's comments.
pub fn sizing_meaning(key: &str) -> &'static str {
    match key {
        "servo_stiffness_nmm_rad" => "each servo's holding stiffness, N mm/rad",
        _ => "",
    }
}

// ----- describe, workspace, torque -----

fn pose_words(pose: &kinematics_core::Pose) -> String {
    let [x, y, z, roll, pitch, yaw] = pose.to_array();
    format!(
        "x={x:.1} y={y:.1} z={z:.1} mm, roll={:.1} pitch={:.1} yaw={:.1} degrees",
        roll.to_degrees(),
        pitch.to_degrees(),
        yaw.to_degrees()
    )
}

/// A toolkit error that is not the IK's (those are the board's words).
pub fn kinematics_words(e: &kinematics_core::KinematicsError) -> String {
    use kinematics_core::KinematicsError as K;
    match e {
        K::Ik(ik) => board_words(&(*ik).into()),
        K::DeadCentre { leg } => {
            format!("leg {leg}'s arm is at dead centre (it cannot move its rod)")
        }
        K::Singular { .. } => {
            "the platform is at a singular pose (it cannot hold a load there)".into()
        }
        K::GimbalLock { .. } => "pitch at +-90 degrees: roll and yaw rates are undefined".into(),
        other => other.to_string(),
    }
}

/// What stops a search that found no limit.
pub const SEARCH_RANGE: &str = "nothing within the search range (100 mm, 180 degrees)";

/// `describe`'s text.
pub fn description(d: &crate::size::Description) -> String {
    use kinematics_core::pose::Axis;
    let p = &d.platform;
    let l = &p.settings.layout;
    let g = p.solver.geometry();
    let mut out = format!("Platform: {}\n", p.source);
    out += &format!(
        "  base: servo shafts on a {:.3} mm circle, pairs {:.3} degrees either side of 0, 120 and \
         240 degrees\n  platform: joints on a {:.3} mm circle, {:.3} degrees either side of 60, \
         180 and 300 degrees\n",
        l.base_radius_mm, l.base_half_angle_deg, l.platform_radius_mm, l.platform_half_angle_deg
    );
    out += &format!(
        "  arm a = {:.3} mm, rod s = {:.3} mm; home height h0 = {:.3} mm (eq. 10)\n",
        g.arm_mm(),
        g.rod_mm(),
        g.home_height_mm()
    );
    out += concat!(
        "  leg  shaft b (mm)                 joint p (mm, platform frame)  beta (deg)",
        "  alpha0 (deg)  shaft to joint at home (mm)\n"
    );
    for i in 0..6 {
        let leg = g.leg(i);
        let v = |v: kinematics_core::Vec3| format!("({:8.3} {:8.3} {:6.3})", v.x, v.y, v.z);
        out += &format!(
            "  {}    {}  {}    {:9.3}  {:12.3}  {:10.3}\n",
            i + 1,
            v(leg.base_mm),
            v(leg.platform_mm),
            leg.beta_rad.to_degrees(),
            p.solver.alpha0_rad(i).to_degrees(),
            d.leg_lengths_mm[i]
        );
    }
    out += "Reach from home, one axis at a time, within the servo limits:\n";
    for (k, axis) in Axis::ALL.into_iter().enumerate() {
        let (minus, plus) = (&d.reach[2 * k], &d.reach[2 * k + 1]);
        let (unit, f): (&str, fn(f32) -> f32) = if axis.is_angle() {
            ("degrees", f32::to_degrees)
        } else {
            ("mm", |v| v)
        };
        out += &format!(
            "  {:<5} {:8.3} .. {:7.3} {unit}   (- {}; + {})\n",
            axis.name(),
            -f(minus.distance),
            f(plus.distance),
            crate::size::limit_words(&minus.limit),
            crate::size::limit_words(&plus.limit)
        );
    }
    let k = p.sizing.servo_stiffness_nmm_rad;
    match d.stiffness_diagonal {
        Some(s) => {
            out += &format!(
                "Stiffness at home, servos holding {k} N mm/rad each (K = J^T diag(k) J, \
                 diagonal):\n  x {:.2}, y {:.2}, z {:.2} N/mm; roll {:.0}, pitch {:.0}, yaw {:.0} \
                 N mm/rad\n",
                s[0], s[1], s[2], s[3], s[4], s[5]
            );
        }
        None => out += "Stiffness at home: none (a singular pose)\n",
    }
    match &d.holding {
        None => {
            out += "Payload: none (payload_g = 0): no holding torques; give payload_g and \
                        payload_com_x_mm, payload_com_y_mm, payload_com_z_mm to size the servos"
        }
        Some(h) => out += &holding_words(p, h),
    }
    out
}

/// `describe`'s payload section.
fn holding_words(p: &crate::size::Platform, h: &crate::size::Holding) -> String {
    let mut out = format!("Payload {}:\n", payload_words(p.payload()));
    if let Some(sag) = &h.sag {
        out += &format!(
            "  its weight moves the platform at home by {:.3} mm down ({:.4} degrees of tilt)\n",
            -sag.translation_mm.z,
            sag.rotation_rad.norm().to_degrees()
        );
    }
    if let Some(t) = h.home_kgcm {
        let list: Vec<String> = t.iter().map(|v| format!("{v:.3}")).collect();
        out += &format!(
            "  holding torque at home, servos 1-6: {} kgf cm\n",
            list.join(" ")
        );
    }
    let (reached, total) = h.grid_reached;
    match crate::size::overall(&h.per_servo) {
        Some(w) => {
            out += &format!(
                "  worst over the workspace ({reached} reachable poses of a {total}-pose grid): \
                 servo {} {:.3} kgf cm at {}\n",
                w.servo,
                w.torque_kgcm.abs(),
                pose_words(&w.pose)
            );
        }
        None => out += "  worst over the workspace: no reachable pose in the grid\n",
    }
    out += &format!("  {}", ratings_summary(p, &h.per_servo));
    out
}

/// The workspace picture's title.
pub fn workspace_title(source: &str) -> String {
    format!("Workspace of {source}: reachable within the servo limits")
}
/// Plot titles and axis labels of `workspace`.
pub const SECTIONS_TITLE: &str = "x-y sections, level, at heights z";
/// See [`SECTIONS_TITLE`].
pub const TRAVEL_TITLE: &str = "vertical travel at each roll and pitch (x = y = yaw = 0)";
/// See [`SECTIONS_TITLE`].
pub const TRAVEL_UNIT: &str = "z travel (mm); grey: none";
/// See [`SECTIONS_TITLE`].
pub const REACH_TITLE: &str = "reach from home along each axis";
/// See [`SECTIONS_TITLE`].
pub const REACH_UNIT: &str = "mm (x y z) or degrees (roll pitch yaw)";
/// See [`SECTIONS_TITLE`].
pub const TRANSLATIONS: &str = "translation (mm)";
/// See [`SECTIONS_TITLE`].
pub const ROTATIONS: &str = "rotation (degrees)";

/// A section's legend entry.
pub fn section_label(z_mm: f32, reachable: bool) -> String {
    if reachable {
        format!("z = {z_mm} mm")
    } else {
        format!("z = {z_mm} mm: not reachable")
    }
}

/// An axis with its unit.
pub fn axis_with_unit(axis: kinematics_core::pose::Axis) -> String {
    let unit = if axis.is_angle() { "deg" } else { "mm" };
    format!("{} ({unit})", axis.name())
}

/// A reach's span.
pub fn reach_span(lo: f32, hi: f32) -> String {
    format!("{lo:.1} .. {hi:.1}")
}

/// Torque plots' words.
pub const SERVO_AXIS: &str = "servo";
/// See [`SERVO_AXIS`].
pub const TORQUE_AXIS: &str = "torque (kgf cm)";
/// See [`SERVO_AXIS`].
pub const TIME_AXIS: &str = "time (s)";
/// See [`SERVO_AXIS`].
pub const WORST_HOLDING: &str = "worst holding torque";
/// See [`SERVO_AXIS`].
pub const OVER_RATING: &str = "over the rating";

/// Servos `1, 2, 4` as words: `servo 2`, `servos 1, 2, 4`, `servos 1-6`.
fn servo_list(servos: &[usize]) -> String {
    match servos {
        [one] => format!("servo {one}"),
        [1, 2, 3, 4, 5, 6] => "servos 1-6".to_string(),
        _ => {
            let numbers: Vec<String> = servos.iter().map(ToString::to_string).collect();
            format!("servos {}", numbers.join(", "))
        }
    }
}

/// A rating's legend entry: the rating and its servos.
pub fn rating_label(kgcm: f32, servos: &[usize]) -> String {
    format!("rating {kgcm} kgf cm ({})", servo_list(servos))
}

/// The legend of a torque plot without ratings.
pub const NOT_RATED: &str = "servos not rated (torque_kgcm off)";

/// A servo's legend entry.
pub fn servo_label(servo: usize) -> String {
    format!("servo {servo}")
}

/// The payload: its mass and centre of mass.
fn payload_words(payload: &control::payload::PayloadSettings) -> String {
    let [x, y, z] = payload.com_mm;
    format!(
        "{} g at ({x}, {y}, {z}) mm in the platform frame",
        payload.mass_g
    )
}

/// The grid torque plot's title.
pub fn grid_torque_title(source: &str, payload: &control::payload::PayloadSettings) -> String {
    format!(
        "{source}: holding {} g over the workspace grid",
        payload.mass_g
    )
}

/// The trajectory torque plot's title.
pub fn trajectory_torque_title(file: &str, payload: &control::payload::PayloadSettings) -> String {
    format!(
        "{file}: torques carrying {} g (gravity and inertia)",
        payload.mass_g
    )
}

/// A servo's torque against its rating.
fn verdict_words(v: crate::size::Verdict) -> String {
    use crate::size::Verdict;
    match v {
        Verdict::NotRated => "not rated".to_string(),
        Verdict::Within {
            rating_kgcm,
            percent,
        } => format!("within its rating of {rating_kgcm} kgf cm ({percent:.0}%)"),
        Verdict::Over {
            rating_kgcm,
            percent,
        } => format!("OVER its rating of {rating_kgcm} kgf cm ({percent:.0}%)"),
    }
}

/// Every servo's worst torque against its rating, in a line: which are over, or the one
/// nearest its rating; the servos without one.
pub fn ratings_summary(
    p: &crate::size::Platform,
    per_servo: &[Option<crate::size::Worst>; 6],
) -> String {
    use crate::size::Verdict;
    let head = "ratings (servoN.torque_kgcm):";
    let unrated: Vec<usize> = (1..=6)
        .filter(|&n| p.verdict(n as u8, 0.0) == Verdict::NotRated)
        .collect();
    if unrated.len() == 6 {
        return format!("{head} the servos are not rated: torques without a verdict");
    }
    let judged: Vec<(u8, f32, Verdict)> = per_servo
        .iter()
        .flatten()
        .map(|w| {
            let t = w.torque_kgcm.abs();
            (w.servo, t, p.verdict(w.servo, t))
        })
        .collect();
    let over: Vec<String> = judged
        .iter()
        .filter_map(|&(servo, t, v)| match v {
            Verdict::Over {
                rating_kgcm,
                percent,
            } => Some(format!(
                "servo {servo} needs {t:.3} kgf cm, rated {rating_kgcm} ({percent:.0}%)"
            )),
            _ => None,
        })
        .collect();
    let mut out = if !over.is_empty() {
        format!("{head} OVER: {}", over.join("; "))
    } else {
        let nearest = judged
            .iter()
            .filter_map(|&(servo, t, v)| match v {
                Verdict::Within {
                    rating_kgcm,
                    percent,
                } => Some((servo, t, rating_kgcm, percent)),
                _ => None,
            })
            .max_by(|a, b| a.3.total_cmp(&b.3));
        match nearest {
            Some((servo, t, rating, percent)) => format!(
                "{head} all within: servo {servo} nearest its rating, {t:.3} of {rating} kgf cm \
                 ({percent:.0}%)"
            ),
            None => format!("{head} no torque to judge (no reachable pose)"),
        }
    };
    if !unrated.is_empty() {
        out += &format!("; {} not rated", servo_list(&unrated));
    }
    out
}

/// `torque` over the grid: each servo's worst, and the worst of all, against the ratings.
pub fn grid_torque_report(
    p: &crate::size::Platform,
    worst: &[Option<crate::size::Worst>; 6],
    reached: usize,
    total: usize,
) -> String {
    let mut out = format!(
        "{}: holding {}, over {reached} reachable poses of a {total}-pose grid (9 steps along \
         x, y, z and along roll, pitch, yaw):\n",
        p.source,
        payload_words(p.payload())
    );
    for w in worst.iter().flatten() {
        let t = w.torque_kgcm.abs();
        out += &format!(
            "  servo {}: {t:.3} kgf cm at {}; {}\n",
            w.servo,
            pose_words(&w.pose),
            verdict_words(p.verdict(w.servo, t))
        );
    }
    match crate::size::overall(worst) {
        Some(w) => {
            let t = w.torque_kgcm.abs();
            out += &format!(
                "worst: servo {}, {t:.3} kgf cm, {}\n",
                w.servo,
                verdict_words(p.verdict(w.servo, t))
            );
        }
        None => out += "worst: none (no reachable pose)\n",
    }
    out + &ratings_summary(p, worst)
}

/// `torque` along a trajectory: the worst, and each servo's worst against its rating.
pub fn trajectory_torque_report(
    file: &str,
    p: &crate::size::Platform,
    worst: &[Option<crate::size::Worst>; 6],
    rows: usize,
) -> String {
    match crate::size::overall(worst) {
        Some(w) => {
            let t = w.torque_kgcm.abs();
            let (time, line) = w.at.unwrap_or((0.0, 0));
            format!(
                "{file}: {rows} rows carrying {} (gravity and inertia): worst servo {}, \
                 {t:.3} kgf cm at {time:.3} s (line {line}), {}; {}\n{}",
                payload_words(p.payload()),
                w.servo,
                pose_words(&w.pose),
                verdict_words(p.verdict(w.servo, t)),
                ratings_summary(p, worst)
            )
        }
        None => format!("{file}: no rows"),
    }
}
