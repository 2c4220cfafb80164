//! [`Error`]: why a subcommand could not do its job, one type for the whole tool, each variant
//! worded in its `Display` (the tool prints `hexapod: ` and that line). Each names where the
//! trouble is: the file and line (and key or field), or the port; units are written out (mm,
//! degrees, s, ms, g, kgf cm).
//!
//! The board's words are not reworded here: a refusal is quoted as the board wrote it, or, for
//! what the tool checks before sending (a build file, a trajectory), worded by
//! `control::report` exactly as the board would word it ([`board_words`]). A leaf: it uses
//! nothing of the tool's own modules.
use std::fmt::{self, Display, Formatter};
use std::io;

use control::report::{refusal, Code};

/// Where the list of settings is, for a user who is not at a terminal.
const SETTINGS_DOC: &str = "docs/settings.md of the firmware's repository";

/// The board's own words for a refusal: `error:<code> <message>` as the firmware writes it.
pub fn board_words(error: &control::Error) -> String {
    refusal(error).to_string()
}

/// Why a subcommand could not do its job. Each names where the trouble is: the file and line
/// (and key or field), or the port.
#[derive(Debug)]
pub enum Error {
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
        why: KeyError,
    },
    /// The serial port or the board behind it.
    Port {
        /// The port's name.
        port: String,
        /// What went wrong.
        why: PortError,
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
        why: RowError,
    },
    /// `uf2`: no firmware ELF where it was looked for (not built yet).
    NoFirmware {
        /// The path looked at.
        path: String,
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
    /// `view`: the page's address cannot be listened on, or its files are not there.
    View {
        /// What it was doing (`listen on 127.0.0.1:2040`).
        doing: String,
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
    /// `cue`'s telemetry or board, or `cue-plot`'s record.
    Cue(Box<CueError>),
    /// `calibrate`: the trims could not be put in the build file as it is written (a trim in a
    /// form the tool does not edit, e.g. an inline table); the file is left as it was.
    TrimsNotWritten {
        /// The build file.
        file: String,
    },
}

/// What is wrong with a key of a build file.
#[derive(Debug)]
pub enum KeyError {
    /// Refused by the firmware's own checks (an unknown name, a bad or out-of-range value, a
    /// servo set or geometry that does not hold together): the board's words.
    Refused(Box<control::Error>),
    /// Not a setting name; the closest one, if one is close
    /// ([`control::report::nearest_setting`]).
    UnknownSetting {
        /// The setting the key is probably meant to be.
        near: Option<control::settings::SettingId>,
    },
    /// `echo`: the typing link's own, not the platform's.
    LinkSetting,
    /// A value that is not a number or a word (an array, a date, a table too deep).
    NotAValue,
    /// A `[sizing]` key that is not one, or its value out of range: why.
    Sizing(SizingError),
    /// With the payload and ratings so far, a servo would need more than its rating to hold
    /// the platform at home: the board, holding home, refuses the setting (`pose-conflict`).
    OverloadedAtHome(control::payload::TorqueError),
    /// A `[cue]` key (`hexapod cue`'s) that is not one, or its value out of range.
    Cue(CueKeyError),
}

/// What is wrong with a `[cue]` key.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CueKeyError {
    /// Not one of the table's keys.
    Unknown,
    /// Not a number in `min..=max`.
    Number {
        /// Smallest.
        min: f64,
        /// Largest.
        max: f64,
    },
    /// Not a whole number in `min..=max` (a filter's order).
    Whole {
        /// Smallest.
        min: f64,
        /// Largest.
        max: f64,
    },
    /// Not 1 or -1 (an axis' sign).
    Sign,
}

/// What went wrong in `cue` (its telemetry, its board) or `cue-plot` (its record).
#[derive(Debug)]
pub enum CueError {
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
        /// Datagrams received.
        datagrams: u64,
        /// What was dropped, by why.
        dropped: Dropped,
        /// The fields a line must have, in order.
        fields: &'static [&'static str],
        /// The sender's own names for its fields, if it sent them (JSBSim's `<LABELS>`).
        labels: Option<Vec<String>>,
    },
    /// The board's settings are not a platform (never: the board checks them).
    NotAPlatform,
    /// A record file that cannot be plotted.
    Record {
        /// The file.
        file: String,
        /// Its line, from 1.
        line: u64,
        /// Why.
        why: RecordError,
    },
}

/// Why a telemetry line was dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BadLine {
    /// Not UTF-8 text.
    NotText,
    /// Not as many fields as a line has.
    FieldCount,
    /// A field that is not a number.
    NotANumber,
    /// NaN or infinite.
    NotFinite,
    /// Beyond what an aircraft does (30 g, 30 rad/s).
    OutOfRange,
}

impl BadLine {
    /// Every kind, in the order summaries list them.
    pub const ALL: [BadLine; 5] = [
        BadLine::NotText,
        BadLine::FieldCount,
        BadLine::NotANumber,
        BadLine::NotFinite,
        BadLine::OutOfRange,
    ];
}

impl Display for BadLine {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BadLine::NotText => "not text",
            BadLine::FieldCount => "not 10 fields",
            BadLine::NotANumber => "a field not a number",
            BadLine::NotFinite => "NaN or infinite",
            BadLine::OutOfRange => "beyond 30 g or 30 rad/s",
        })
    }
}

/// Telemetry dropped, by why.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Dropped {
    /// Lines, per [`BadLine::ALL`] kind.
    pub bad: [u64; 5],
    /// Samples whose time did not advance (repeated, out of order, or a storm faster than
    /// the washout takes them).
    pub stale: u64,
    /// Datagrams dropped because the queue was full (a storm).
    pub overflowed: u64,
}

impl Dropped {
    /// Counts a bad line.
    pub fn count(&mut self, kind: BadLine) {
        if let Some(i) = BadLine::ALL.iter().position(|k| *k == kind) {
            self.bad[i] += 1;
        }
    }

    /// Everything dropped.
    pub fn total(&self) -> u64 {
        self.bad.iter().sum::<u64>() + self.stale + self.overflowed
    }
}

impl Display for Dropped {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let mut parts: Vec<String> = BadLine::ALL
            .iter()
            .zip(self.bad)
            .filter(|(_, n)| *n > 0)
            .map(|(kind, n)| format!("{n} {kind}"))
            .collect();
        if self.stale > 0 {
            parts.push(format!("{} whose time did not advance", self.stale));
        }
        if self.overflowed > 0 {
            parts.push(format!("{} in a storm (queue full)", self.overflowed));
        }
        if parts.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&parts.join(", "))
        }
    }
}

/// What is wrong with a `cue --record` file.
#[derive(Debug, Clone, PartialEq)]
pub enum RecordError {
    /// The header is not the record's.
    Header {
        /// The columns it must name.
        columns: &'static [&'static str],
    },
    /// Fewer or more fields than the header.
    FieldCount(usize),
    /// A field that is not a finite number.
    NotFinite {
        /// Its column.
        column: &'static str,
        /// As found.
        text: String,
    },
    /// No rows.
    Empty,
}

/// What is wrong with a `[sizing]` key.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SizingError {
    /// Not one of the sizing keys.
    Unknown {
        /// The keys the table takes.
        keys: &'static [&'static str],
    },
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
pub enum PortError {
    /// It could not be opened.
    Open {
        /// The system's words.
        why: String,
        /// The serial ports the system lists (`serialport::available_ports`).
        present: Vec<String>,
        /// The system refused for want of permission (on Linux: the `dialout` group).
        denied: bool,
    },
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
    /// The platform was still moving after this long (`status`).
    StillMoving {
        /// How long the tool waited, s.
        waited_s: f64,
    },
}

/// What is wrong with a row of a trajectory file.
#[derive(Debug)]
pub enum RowError {
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

impl Display for Error {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            Error::File { path, error } => write!(f, "{path}: {error}"),
            Error::Toml {
                file,
                line,
                message,
            } => {
                file_line(f, file, line)?;
                write!(f, "not a TOML file: {}", message.trim_end())
            }
            Error::Key {
                file,
                line,
                key,
                why,
            } => {
                file_line(f, file, line)?;
                match why {
                    KeyError::Refused(error) => write!(f, "{key}: {}", board_words(error)),
                    KeyError::UnknownSetting { near } => {
                        // The board's code, then the file's words: a file is not a terminal
                        // to type `config` on, so the list is where the docs keep it.
                        write!(f, "{key}: error:{} not a setting", Code::UnknownSetting)?;
                        if let Some(id) = near {
                            write!(f, "; did you mean {id}?")?;
                        }
                        write!(f, " (the settings are listed in {SETTINGS_DOC})")
                    }
                    KeyError::LinkSetting => write!(
                        f,
                        "{key}: belongs to the serial link, not the platform (it is not saved); \
                         a build file does not set it"
                    ),
                    KeyError::Sizing(SizingError::Unknown { keys }) => write!(
                        f,
                        "{key}: not a sizing key; [sizing] takes {}",
                        keys.join(", ")
                    ),
                    KeyError::Sizing(SizingError::Range { min, max, unit }) => {
                        write!(f, "{key}: must be a number {min}..{max} {unit}")
                    }
                    KeyError::Sizing(SizingError::Moved { setting, value }) => {
                        write!(
                            f,
                            "{key}: now the board's setting {setting} ({}): write {} instead",
                            setting_unit(*setting),
                            setting_placement(*setting, *value)
                        )
                    }
                    KeyError::OverloadedAtHome(cause) => write!(
                        f,
                        "{key}: at home {}; the board, holding home, refuses this setting \
                         (error:pose-conflict)",
                        torque_words(cause)
                    ),
                    KeyError::Cue(why) => write!(f, "{key}: {why}"),
                    KeyError::NotAValue => write!(
                        f,
                        "{key}: not a setting value (a setting takes a number or a word; \
                         settings go in [servoN], [servos] or [stream] tables at most)"
                    ),
                }
            }
            Error::Port { port, why } => match why {
                PortError::Open {
                    why,
                    present,
                    denied,
                } => {
                    write!(f, "{port}: cannot open the serial port: {why}")?;
                    if *denied && cfg!(target_os = "linux") {
                        write!(
                            f,
                            "; your user may not use serial ports: add it to the `dialout` group \
                             (`sudo usermod -aG dialout $USER`), then log in again"
                        )?;
                    }
                    if present.is_empty() {
                        write!(f, "; no serial ports found (is the board plugged in?)")?;
                    } else {
                        write!(f, "; serial ports present: {}", present.join(", "))?;
                    }
                    write!(
                        f,
                        "; for the emulated board, `./dev run --pty` prints the port to give"
                    )
                }
                PortError::Io(e) => write!(f, "{port}: serial port error: {e}"),
                PortError::NoReply { line, waited_s } => write!(
                    f,
                    "{port}: the board did not answer '{line}' within {waited_s:.1} s (is it \
                     powered, on this port, at this baud rate?)"
                ),
                PortError::LineLost { line } => write!(
                    f,
                    "{port}: bytes were lost on the way to the board and '{line}' got no \
                     reply; nothing more was sent"
                ),
                PortError::Unreadable { line, reply } => {
                    write!(f, "{port}: cannot read the reply to '{line}': '{reply}'")
                }
                PortError::StillMoving { waited_s } => write!(
                    f,
                    "{port}: the platform was still moving after {waited_s:.0} s (`status`)"
                ),
            },
            Error::Refused {
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
            Error::Row {
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
                    RowError::Unreadable(e) => write!(f, "unreadable row: {e}"),
                    RowError::Header { found } => write!(
                        f,
                        "the header must name the columns time,x,y,z,roll,pitch,yaw (s, mm, \
                         degrees); found '{found}'"
                    ),
                    RowError::FieldCount { found } => {
                        write!(f, "{found} fields; a row has 7 (time,x,y,z,roll,pitch,yaw)")
                    }
                    RowError::NotANumber(text) => write!(f, "'{text}' is not a number"),
                    RowError::NotFinite(text) => write!(f, "'{text}' is not a finite number"),
                    RowError::TimeNotIncreasing { time_s, previous_s } => write!(
                        f,
                        "time {time_s} s is not after the previous row's {previous_s} s"
                    ),
                    RowError::BeyondFullScale {
                        value,
                        setting,
                        full_scale,
                    } => write!(
                        f,
                        "{value} is beyond the board's stream full scale {setting} = \
                         {full_scale} (the board would clamp it); raise {setting} or use --text"
                    ),
                    RowError::Refused(words) => {
                        write!(
                            f,
                            "the board would refuse this pose: {words}; nothing was sent"
                        )
                    }
                    RowError::Empty => f.write_str("no rows: nothing to do"),
                }
            }
            Error::NoFirmware { path } => write!(
                f,
                "{path}: no firmware there; build it first with `cargo fw` (at the top of the \
                 firmware's repository), or run `./dev uf2`, which builds it and writes the UF2"
            ),
            Error::Elf { path, why } => write!(f, "{path}: {why}"),
            Error::Option { option, why } => write!(f, "{option}: {why}"),
            Error::View { doing, why } => write!(f, "cannot {doing}: {why}"),
            Error::Pose { pose, why } => write!(f, "pose {pose}: {why}"),
            Error::NoPayload { source } => write!(
                f,
                "{source}: no payload (payload_g = 0): the servos hold nothing, so every torque \
                 is 0; give payload_g (g) and payload_com_x_mm, payload_com_y_mm, \
                 payload_com_z_mm (mm, platform frame) in the build file (--settings)"
            ),
            Error::Cue(why) => write!(f, "{why}"),
            Error::TrimsNotWritten { file } => write!(
                f,
                "{file}: the trims could not be written into this file as it is (a trim_us in a \
                 form the tool does not edit, such as an inline table); the file is unchanged and \
                 the board keeps the new trims unsaved: write them by hand (`[servoN] trim_us`), \
                 or give another --output"
            ),
            Error::StreamTrouble {
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

impl std::error::Error for Error {}

impl Display for CueKeyError {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            CueKeyError::Unknown => write!(
                f,
                "not a [cue] key; see docs/cueing.md for the keys (margin, knee, stall_s, \
                 ease_s, pivot_*_mm, x.scale ... tilt.max_deg)"
            ),
            CueKeyError::Number { min, max } => write!(f, "must be a number {min}..{max}"),
            CueKeyError::Whole { min, max } => write!(f, "must be a whole number {min}..{max}"),
            CueKeyError::Sign => write!(f, "must be 1 or -1"),
        }
    }
}

impl Display for CueError {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            CueError::Listen { address, why } => {
                write!(f, "cannot listen for telemetry on {address}: {why}")
            }
            CueError::NoTelemetry {
                address,
                waited_s,
                datagrams,
                dropped,
                fields,
                labels,
            } => {
                write!(
                    f,
                    "no valid telemetry on {address} in {waited_s} s: {datagrams} datagrams, \
                     lines dropped: {dropped}. Each line must be {} numbers: {} \
                     (docs/cueing.md)",
                    fields.len(),
                    fields.join(",")
                )?;
                if let Some(labels) = labels {
                    write!(f, "; the sender named its fields {}", labels.join(","))?;
                }
                Ok(())
            }
            CueError::NotAPlatform => write!(f, "the board's settings are not a platform"),
            CueError::Record { file, line, why } => {
                file_line(f, file, line)?;
                match why {
                    RecordError::Header { columns } => write!(
                        f,
                        "not a cue record: the header must be {}",
                        columns.join(",")
                    ),
                    RecordError::FieldCount(n) => write!(f, "{n} fields"),
                    RecordError::NotFinite { column, text } => {
                        write!(f, "{column}: '{text}' is not a finite number")
                    }
                    RecordError::Empty => f.write_str("no rows: nothing to plot"),
                }
            }
        }
    }
}

impl From<CueError> for Error {
    fn from(why: CueError) -> Error {
        Error::Cue(Box::new(why))
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;

    fn not_opened(present: &[&str], denied: bool) -> String {
        Error::Port {
            port: "/dev/ttyACM0".into(),
            why: PortError::Open {
                why: "Permission denied".into(),
                present: present.iter().map(|p| p.to_string()).collect(),
                denied,
            },
        }
        .to_string()
    }

    #[test]
    fn a_port_that_does_not_open_says_what_to_try() {
        let denied = not_opened(&["/dev/ttyACM0", "/dev/ttyS0"], true);
        assert!(
            denied.starts_with("/dev/ttyACM0: cannot open the serial port: Permission denied; "),
            "{denied}"
        );
        assert_eq!(
            denied.contains("`dialout` group"),
            cfg!(target_os = "linux"),
            "{denied}"
        );
        assert!(
            denied.contains("; serial ports present: /dev/ttyACM0, /dev/ttyS0;"),
            "{denied}"
        );
        assert!(denied.ends_with("`./dev run --pty` prints the port to give"));
        let none = not_opened(&[], false);
        assert!(none.contains("; no serial ports found"), "{none}");
        assert!(!none.contains("dialout"), "{none}");
    }
}
