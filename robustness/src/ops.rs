//! Structure-aware inputs: what a host (or line noise) can do to the firmware, built by
//! [`arbitrary`] from the fuzzer's bytes (or by proptest from its own generators, which map
//! onto the same types), so that most inputs are real commands with good, edge and hostile
//! values rather than random text the parser refuses at the first word.

use arbitrary::Arbitrary;

/// Numbers as a user (or a broken program) might type them.
#[derive(Debug, Clone, Arbitrary)]
pub enum Num {
    /// A small whole number.
    Int(i8),
    /// A decimal with two places: `units.hundredths`.
    Fixed(i16),
    /// Any `f32`, printed with Rust's shortest round-trip formatting (may be `NaN`, `inf`).
    Float(f32),
    /// An exponent form `mantissa e exponent`.
    Exp(i8, i8),
    /// A hostile or edge-case spelling.
    Edge(Edge),
}

/// Spellings that must be handled exactly as documented.
#[derive(Debug, Clone, Copy, Arbitrary)]
pub enum Edge {
    /// `1e39` (does not fit an f32)
    Huge,
    /// `-1e39`
    NegHuge,
    /// `-0`
    NegZero,
    /// `nan`
    Nan,
    /// `inf`
    Inf,
    /// `-infinity`
    NegInfinity,
    /// `0x10`
    Hex,
    /// `1e-50` (rounds to 0)
    Tiny,
    /// `+5`
    Plus,
    /// `.5`
    LeadingDot,
    /// `5.`
    TrailingDot,
    /// `1e`
    BareExp,
    /// `--1`
    DoubleSign,
    /// `1_000`
    Underscore,
    /// `3.4028235e38` (f32::MAX)
    Max,
    /// `340282356779733661637539395458142568448` (rounds past f32::MAX)
    JustTooBig,
    /// 60 digits
    LongDigits,
    /// ``
    Empty,
}

impl Edge {
    /// The text.
    pub fn text(self) -> &'static str {
        match self {
            Edge::Huge => "1e39",
            Edge::NegHuge => "-1e39",
            Edge::NegZero => "-0",
            Edge::Nan => "nan",
            Edge::Inf => "inf",
            Edge::NegInfinity => "-infinity",
            Edge::Hex => "0x10",
            Edge::Tiny => "1e-50",
            Edge::Plus => "+5",
            Edge::LeadingDot => ".5",
            Edge::TrailingDot => "5.",
            Edge::BareExp => "1e",
            Edge::DoubleSign => "--1",
            Edge::Underscore => "1_000",
            Edge::Max => "3.4028235e38",
            Edge::JustTooBig => "340282356779733661637539395458142568448",
            Edge::LongDigits => "000000000000000000000000000000000000000000000000000000000001",
            Edge::Empty => "",
        }
    }
}

impl Num {
    /// The text as typed.
    pub fn text(&self) -> String {
        match self {
            Num::Int(v) => format!("{v}"),
            Num::Fixed(v) => {
                let sign = if *v < 0 { "-" } else { "" };
                let a = v.unsigned_abs();
                format!("{sign}{}.{:02}", a / 100, a % 100)
            }
            Num::Float(v) => format!("{v}"),
            Num::Exp(m, e) => format!("{m}e{e}"),
            Num::Edge(e) => e.text().to_owned(),
        }
    }
}

/// The six axes' names, and one that is not an axis.
pub const AXES: [&str; 7] = ["x", "y", "z", "roll", "pitch", "yaw", "w"];

/// Every setting name the firmware documents, plus near misses.
pub const SETTING_NAMES: &[&str] = &[
    "frame_hz",
    "baud",
    "echo",
    "speed_mm_s",
    "speed_deg_s",
    "link_timeout_s",
    "base_radius_mm",
    "platform_radius_mm",
    "base_half_angle_deg",
    "platform_half_angle_deg",
    "arm_mm",
    "rod_mm",
    "accel_mm_s2",
    "accel_deg_s2",
    "stream.x_mm",
    "stream.roll_deg",
    "stream.bits",
    "stream.axis1",
    "stream.axis4",
    "estop_action",
    "servo1.trim_us",
    "servo2.rate_us_rad",
    "servo3.dir",
    "servo4.min_us",
    "servo5.max_us",
    "servo6.trim_us",
    "servos.trim_us",
    "servos.rate_us_rad",
    "servos.dir",
    "servos.min_us",
    "servos.max_us",
    "payload_g",
    "payload_com_x_mm",
    "payload_com_z_mm",
    "pivot_x_mm",
    "pivot_z_mm",
    "servo2.torque_kgcm",
    "servos.torque_kgcm",
    "servo3.speed_s_60deg",
    "servos.speed_s_60deg",
    "servo0.trim_us",
    "servo7.min_us",
    "servo1.colour",
    "servo12.dir",
    "speed",
];

/// Setting values that are not numbers.
pub const WORDS: &[&str] = &[
    "on", "off", "1", "0", "normal", "reversed", "+1", "-1", "maybe", "9600", "115200", "921600",
    "x", "roll", "none", "freeze", "home",
];

/// A setting value.
#[derive(Debug, Clone, Arbitrary)]
pub enum Value {
    /// A number.
    Num(Num),
    /// A word from [`WORDS`].
    Word(u8),
}

impl Value {
    fn text(&self) -> String {
        match self {
            Value::Num(n) => n.text(),
            Value::Word(i) => WORDS[usize::from(*i) % WORDS.len()].to_owned(),
        }
    }
}

/// A command line, mostly well formed.
#[derive(Debug, Clone, Arbitrary)]
pub enum Cmd {
    /// `pose` with six numbers (or fewer / more).
    Pose(Vec<Num>),
    /// `check` with numbers.
    Check(Vec<Num>),
    /// `move axis=value ...` (axis index into [`AXES`]).
    Move(Vec<(u8, Num)>),
    /// `nudge axis=value ...`.
    Nudge(Vec<(u8, Num)>),
    /// `servo n us` (n as typed: mostly 1..=6, sometimes not a servo).
    Servo(u8, Num),
    /// `limits`
    Limits,
    /// `home`
    Home,
    /// `stop`
    Stop,
    /// `status`
    Status,
    /// `?`
    Query,
    /// `geometry`
    Geometry,
    /// `config`
    Config,
    /// `help`
    Help,
    /// `defaults`
    Defaults,
    /// `save`
    Save,
    /// `set name value` (name index into [`SETTING_NAMES`]).
    Set(u8, Value),
    /// Printable text as typed.
    Text(String),
    /// `pulses` (last, so the fuzzers' seeds keep their meaning).
    Pulses,
}

/// How words are separated.
#[derive(Debug, Clone, Copy, Arbitrary)]
pub enum Sep {
    /// one space
    Space,
    /// a comma
    Comma,
    /// a tab
    Tab,
    /// three spaces
    Spaces,
}

impl Sep {
    fn text(self) -> &'static str {
        match self {
            Sep::Space => " ",
            Sep::Comma => ",",
            Sep::Tab => "\t",
            Sep::Spaces => "   ",
        }
    }
}

impl Cmd {
    /// The line as typed (no line end).
    pub fn text(&self, sep: Sep, upper: bool) -> String {
        let s = sep.text();
        let join = |head: &str, rest: Vec<String>| {
            let mut line = head.to_owned();
            for w in rest {
                line.push_str(s);
                line.push_str(&w);
            }
            line
        };
        let assignments = |v: &Vec<(u8, Num)>| {
            v.iter()
                .map(|(a, n)| format!("{}={}", AXES[usize::from(*a) % AXES.len()], n.text()))
                .collect()
        };
        let line = match self {
            Cmd::Pose(v) => join("pose", v.iter().map(Num::text).collect()),
            Cmd::Check(v) => join("check", v.iter().map(Num::text).collect()),
            Cmd::Move(v) => join("move", assignments(v)),
            Cmd::Nudge(v) => join("nudge", assignments(v)),
            Cmd::Servo(n, us) => {
                // Mostly a servo, and pulses near the servo range (which Int and Fixed rarely
                // reach on their own).
                let servo = match n % 8 {
                    0 => "0".to_owned(),
                    7 => "7".to_owned(),
                    k => k.to_string(),
                };
                let pulse = match us {
                    Num::Int(v) => format!("{}", 1500 + i32::from(*v) * 4),
                    Num::Fixed(v) => format!("{:.2}", 1500.0 + f32::from(*v) / 40.0),
                    other => other.text(),
                };
                join("servo", vec![servo, pulse])
            }
            Cmd::Limits => "limits".into(),
            Cmd::Home => "home".into(),
            Cmd::Stop => "stop".into(),
            Cmd::Status => "status".into(),
            Cmd::Query => "?".into(),
            Cmd::Pulses => "pulses".into(),
            Cmd::Geometry => "geometry".into(),
            Cmd::Config => "config".into(),
            Cmd::Help => "help".into(),
            Cmd::Defaults => "defaults".into(),
            Cmd::Save => "save".into(),
            Cmd::Set(i, v) => join(
                "set",
                vec![
                    SETTING_NAMES[usize::from(*i) % SETTING_NAMES.len()].to_owned(),
                    v.text(),
                ],
            ),
            Cmd::Text(t) => t.clone(),
        };
        if upper {
            line.to_ascii_uppercase()
        } else {
            line
        }
    }
}

/// A line end style.
#[derive(Debug, Clone, Copy, Arbitrary)]
pub enum End {
    /// CR
    Cr,
    /// LF
    Lf,
    /// CR LF
    CrLf,
    /// LF CR (two line ends: the second line is blank)
    LfCr,
}

impl End {
    /// The bytes.
    pub fn bytes(self) -> &'static [u8] {
        match self {
            End::Cr => b"\r",
            End::Lf => b"\n",
            End::CrLf => b"\r\n",
            End::LfCr => b"\n\r",
        }
    }
}

/// One thing that happens to the firmware.
#[derive(Debug, Clone, Arbitrary)]
pub enum Op {
    /// A command line with a line end.
    Line(Cmd, Sep, bool, End),
    /// Raw bytes (garbage, partial lines, editing keys, escapes).
    Bytes(Vec<u8>),
    /// Servo frames pass (1 + n).
    Frames(u8),
    /// Frames until the motion ends (at most ~20 s of frames).
    Settle,
    /// The receive queue lost this many bytes (1 + n).
    Lost(u16),
    /// A line through `execute_line` (other transports).
    Execute(Cmd, Sep),
    /// A binary stream frame of these counts (`A5 5A`, big-endian counts, `0D 0A`).
    Binary([u16; 6]),
    /// A text stream frame of these counts (`c1,c2,...,c6X`).
    TextFrame([u16; 6]),
    /// The e-stop input opens (`true`) or closes.
    Estop(bool),
}

impl Op {
    /// The bytes of a stream frame op (empty for the others).
    pub fn frame_bytes(&self) -> Vec<u8> {
        match self {
            Op::Binary(counts) => {
                let mut bytes = vec![0xA5, 0x5A];
                for c in counts {
                    bytes.extend_from_slice(&c.to_be_bytes());
                }
                bytes.extend_from_slice(b"\r\n");
                bytes
            }
            Op::TextFrame(counts) => {
                let text: Vec<String> = counts.iter().map(u16::to_string).collect();
                format!("{}X", text.join(",")).into_bytes()
            }
            _ => Vec::new(),
        }
    }
}

/// A whole session: start-up settings choice and a list of operations.
#[derive(Debug, Clone, Arbitrary)]
pub struct Session {
    /// Echo on at start-up.
    pub echo: bool,
    /// What happens.
    pub ops: Vec<Op>,
}
