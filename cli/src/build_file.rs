//! The build file: one TOML file that describes a user's platform with the firmware's own `set`
//! names as keys, so that a file the tool accepts is one the board accepts.
//!
//! ```toml
//! frame_hz = 50
//! rod_mm = 120.0
//! servos.rate_us_rad = 600    # a dotted key is the same name
//! [servo3]
//! trim_us = 1512              # servo3.trim_us
//! [stream]
//! z_mm = 15                   # stream.z_mm
//! ```
//!
//! Every key is looked up with `control::settings::SettingId::parse`, every value parsed with
//! `SettingId::parse_value` and every resulting set of settings checked with
//! `Settings::with` and `Settings::validate`: the code the firmware runs for `set`. The
//! settings start from the firmware's defaults (as after `defaults`), so the file says the
//! whole platform: what it leaves out is the default.
//!
//! The payload and the servos' torque ratings are settings like the others (`payload_g = 500`,
//! `payload_com_z_mm = 20`, `[servo3] torque_kgcm = 1.8` or `servos.torque_kgcm = 1.8`). The
//! board also refuses a payload or rating that its servos could not hold where the platform is:
//! here, at home (where a board is after `defaults` from power-up), with the board's own torque
//! check (`control::payload::PayloadSettings::check`).
//!
//! The board checks each `set` on its own, so each step must leave valid settings (e.g.
//! `servo1.min_us = 1600` is refused while `servo1.trim_us` is still 1500). The file's keys
//! are therefore put in an order in which every step is accepted ([`BuildFile::steps`]),
//! keeping the file's order where it can and never reordering two keys that set the same
//! value (`servos.trim_us` then `servo3.trim_us`). If no order works, the first key that
//! cannot be applied is the error, in the board's words, with its file, line and key.
//!
//! The `[sizing]` table holds what the board has no setting for (`crate::sizing`); the `[cue]`
//! table is `hexapod cue`'s (`crate::cue::config`), skipped here.
//!
//! `baud` (UART0's rate, a link setting that `save` keeps) may be given: `apply` sends it after
//! every other `set` and before `save`, and moves its own port to the new rate as soon as the
//! board's `ok` comes (the board switches once that `ok` has left), so `save` goes at the new
//! rate and its `ok` shows the link works there. Over USB the rate changes nothing on the link.
//! Left out, the board's rate stays as it is (`defaults` keeps it). `echo` is the typing
//! link's own and is refused.
//!
//! A file is written commented ([`write`]: `init`, `pull`): each key with what it is and its
//! range, taken from the firmware's own [`Kind`] (the free GPIOs from
//! `control::safety::FREE_GPIOS`).
//!
//! Values: numbers as typed (TOML's `1_000` and `0x10` are the numbers they mean), words as
//! strings (`dir = "reversed"`, `speed_mm_s = "off"`). Units are those of the names (`_mm`,
//! `_deg`, `_us`, `_s`, `_hz`).

use std::path::Path;

use control::report::{nearest_setting, ValueText};
use control::safety::FREE_GPIOS;
use control::settings::{
    Kind, ServoParam, ServoSel, SettingId, SettingValue, Settings, BAUD_RATES, DEFAULT_BAUD,
};
use kinematics_core::{Libm, Pose, LEGS};
use toml::de::{DeTable, DeValue};

use crate::error::{Error, KeyError};
use crate::files::read_text;
use crate::sizing::{self, Sizing, SIZING_TABLE};

/// Where the settings come from without a build file (`init`, and `--settings` left out).
pub const DEFAULT_PLATFORM: &str = "the default platform";

/// One `set` of a build file.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// The setting.
    pub id: SettingId,
    /// Its value as `set` takes it (lowercase).
    pub value: String,
    /// The line of its key in the file, from 1.
    pub line: usize,
}

impl Step {
    /// The command line the board is sent: `set <name> <value>`.
    pub fn command(&self) -> String {
        format!("set {} {}", self.id, self.value)
    }
}

/// A build file read and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct BuildFile {
    /// The `set`s, in an order the board accepts one by one from its defaults.
    pub steps: Vec<Step>,
    /// The settings they make.
    pub settings: Settings,
    /// UART0's baud rate (`baud`), if the file gives it: sent last, after [`BuildFile::steps`].
    pub baud: Option<u32>,
    /// The `[sizing]` table: the servos' stiffness, for the host's sizing tools (not a setting
    /// of the board, never sent to it).
    pub sizing: Sizing,
}

/// Reads and checks a build file.
pub fn read(path: &Path) -> Result<BuildFile, Error> {
    parse(&path.display().to_string(), &read_text(path)?)
}

/// The `[cue]` table's name: `hexapod cue`'s (`crate::cue::config` reads it), skipped here.
pub const CUE_TABLE: &str = "cue";

/// Reads and checks a build file's text; `file` names it in errors.
pub fn parse(file: &str, text: &str) -> Result<BuildFile, Error> {
    let line_of = |offset: usize| text[..offset.min(text.len())].matches('\n').count() + 1;
    let table = DeTable::parse(text).map_err(|e| Error::Toml {
        file: file.to_string(),
        line: e.span().map_or(1, |s| line_of(s.start)),
        message: e.message().to_string(),
    })?;
    let mut found = Vec::new();
    for (key, value) in table.get_ref() {
        if key.get_ref() == CUE_TABLE {
            continue; // `hexapod cue`'s (crate::cue::config), never the board's
        }
        let line = line_of(key.span().start);
        match value.get_ref() {
            DeValue::Table(inner) => {
                for (sub, value) in inner {
                    let name = format!("{}.{}", key.get_ref(), sub.get_ref());
                    found.push((name, line_of(sub.span().start), value.get_ref()));
                }
            }
            other => found.push((key.get_ref().to_string(), line, other)),
        }
    }
    let problem = |name: &str, line, why| Error::Key {
        file: file.to_string(),
        line,
        key: name.to_string(),
        why,
    };
    let mut pending = Vec::new();
    let mut baud = None;
    let mut sizing = Sizing::default();
    for (name, line, value) in found {
        let name = name.to_ascii_lowercase();
        if let Some(key) = name.strip_prefix(SIZING_TABLE) {
            let number = match value {
                DeValue::Integer(_) | DeValue::Float(_) => {
                    value_text(value).and_then(|t| t.parse::<f32>().ok())
                }
                _ => None,
            };
            sizing
                .set(key, number)
                .map_err(|why| problem(&name, line, KeyError::Sizing(why)))?;
            continue;
        }
        let refused = |e: control::Error| problem(&name, line, KeyError::Refused(Box::new(e)));
        let id = SettingId::parse(&name).ok_or_else(|| {
            let near = nearest_setting(&name);
            problem(&name, line, KeyError::UnknownSetting { near })
        })?;
        if id.is_link() && id != SettingId::Baud {
            return Err(problem(&name, line, KeyError::LinkSetting));
        }
        let value = value_text(value).ok_or_else(|| problem(&name, line, KeyError::NotAValue))?;
        let parsed = id
            .parse_value(&value)
            .map_err(|e| refused(control::Error::from(e)))?;
        match parsed {
            SettingValue::Whole(rate) if id == SettingId::Baud => baud = Some(rate),
            _ => pending.push((Step { id, value, line }, parsed)),
        }
    }
    // Apply in an order the board accepts (see the module documentation).
    let mut settings = Settings::default();
    let mut steps = Vec::with_capacity(pending.len());
    while !pending.is_empty() {
        let next = (0..pending.len()).find(|&i| {
            let (step, value) = &pending[i];
            let blocked = pending[..i]
                .iter()
                .any(|(earlier, _)| overlap(earlier.id, step.id));
            !blocked && accepted(&settings.with(step.id, *value)).is_ok()
        });
        match next {
            Some(i) => {
                let (step, value) = pending.remove(i);
                settings = settings.with(step.id, value);
                steps.push(step);
            }
            None => {
                let (step, value) = &pending[0];
                let why = accepted(&settings.with(step.id, *value))
                    .err()
                    // The first key is never blocked, so it was refused.
                    .unwrap_or(KeyError::Refused(Box::new(control::Error::Busy)));
                return Err(problem(&step.id.to_string(), step.line, why));
            }
        }
    }
    Ok(BuildFile {
        steps,
        settings,
        baud,
        sizing,
    })
}

/// Whether the board, holding home, accepts these settings: valid ([`Settings::validate`]),
/// and with a payload and ratings, every servo within its rating at home.
fn accepted(settings: &Settings) -> Result<(), KeyError> {
    let solver = settings
        .validate()
        .map_err(|e| KeyError::Refused(Box::new(e.into())))?;
    if settings.payload.checked() {
        // Valid settings reach home (their trims are within their limits).
        if let Ok(home) = solver.solve::<Libm>(&settings.servos, &Pose::HOME) {
            settings
                .payload
                .check::<Libm>(&solver, &Pose::HOME, &home.arm_rad)
                .map_err(KeyError::OverloadedAtHome)?;
        }
    }
    Ok(())
}

/// Whether two settings set a common value (`servos.x` and `servoN.x`).
fn overlap(a: SettingId, b: SettingId) -> bool {
    match (a, b) {
        (SettingId::Servo(sa, pa), SettingId::Servo(sb, pb)) => {
            pa == pb && (sa == sb || sa == ServoSel::All || sb == ServoSel::All)
        }
        _ => a == b,
    }
}

/// A TOML value as the text `set` takes, or `None` for what is no setting value.
fn value_text(value: &DeValue<'_>) -> Option<String> {
    Some(match value {
        DeValue::String(s) => s.to_ascii_lowercase(),
        DeValue::Integer(i) => {
            let digits: String = i.as_str().chars().filter(|&c| c != '_').collect();
            let (sign, digits) = match digits.strip_prefix('-') {
                Some(rest) => ("-", rest.to_string()),
                None => ("", digits.trim_start_matches('+').to_string()),
            };
            let digits = if i.radix() == 10 {
                digits
            } else {
                // 0x, 0o, 0b: the number it means, in decimal.
                let bare = ["0x", "0o", "0b"]
                    .iter()
                    .find_map(|p| digits.strip_prefix(p))
                    .unwrap_or(&digits);
                let n = u128::from_str_radix(bare, i.radix()).ok()?;
                n.to_string()
            };
            format!("{sign}{digits}")
        }
        DeValue::Float(x) => x
            .as_str()
            .chars()
            .filter(|&c| c != '_')
            .collect::<String>()
            .to_ascii_lowercase(),
        DeValue::Boolean(b) => if *b { "on" } else { "off" }.to_string(),
        DeValue::Datetime(_) | DeValue::Array(_) | DeValue::Table(_) => return None,
    })
}

/// A value as a build file writes it: numbers bare (the shortest text that reads back as the
/// same `f32`), words quoted.
fn toml_value(id: SettingId, value: SettingValue) -> String {
    match (id.kind(), value) {
        (Kind::Number { off_allowed, .. }, SettingValue::Number(v))
            if !(off_allowed && v == 0.0) =>
        {
            let text = format!("{v}");
            if text.contains('.') || text.contains('e') {
                text
            } else {
                format!("{text}.0")
            }
        }
        (_, SettingValue::Whole(v)) => v.to_string(),
        _ => format!("\"{}\"", ValueText(id, value)),
    }
}

/// What a setting is, with its range from the firmware's own [`Kind`], for the comments.
fn describe(id: SettingId) -> String {
    let what = id.meaning();
    match id.kind() {
        Kind::Whole {
            min,
            max,
            list: [],
            unit,
        } => {
            format!("{what}, {min}..{max} {unit}")
        }
        Kind::Number {
            min,
            max,
            unit,
            off_allowed,
            ..
        } => {
            let off = if off_allowed { ", or \"off\"" } else { "" };
            format!("{what}, {min}..{max} {unit}{off}")
        }
        Kind::Dir => format!("{what}: \"normal\" or \"reversed\""),
        Kind::Choice(words) => {
            let quoted: Vec<String> = words.iter().map(|w| format!("\"{w}\"")).collect();
            format!("{what}: {}", quoted.join(" "))
        }
        Kind::Pin => format!("{what}: a GPIO ({}) or \"off\"", runs(&FREE_GPIOS)),
        _ => what.to_string(),
    }
}

/// The first lines of a build file (`init`, `pull`).
fn header(source: &str) -> String {
    format!(
        "# hexapod build file: the settings of {source}.\n\
         # Keys are the firmware's `set` names (docs/settings.md in the firmware's repository):\n\
         # `[servo3] trim_us = 1512` is `set servo3.trim_us 1512`.\n\
         # Lengths in mm, angles in degrees, pulses in microseconds.\n\
         # A key left out is the firmware's default. `hexapod apply FILE` (no port) checks it;\n\
         # `hexapod apply FILE --port PORT` sends `defaults`, every `set`, then `save`.\n\n"
    )
}

/// A build file without a payload: how to give one (commented, so the file still says the
/// board's defaults).
pub const PAYLOAD_EXAMPLE: &str = "\
# No payload: the board shows and checks no holding torques. To give one, e.g. 500 g whose\n\
# centre of mass is 20 mm above the platform, on micro servos rated 1.8 kgf cm (an SG90):\n\
#   payload_g = 500\n\
#   payload_com_z_mm = 20\n\
#   and torque_kgcm = 1.8 in each [servoN] below\n";

/// Whole numbers as runs: `8..22, 26..28` for 8 to 22 and 26 to 28 (a run of one is its number).
fn runs(numbers: &[u32]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut i = 0;
    while i < numbers.len() {
        let first = numbers[i];
        while i + 1 < numbers.len() && numbers[i + 1] == numbers[i] + 1 {
            i += 1;
        }
        out.push(if numbers[i] == first {
            first.to_string()
        } else {
            format!("{first}..{}", numbers[i])
        });
        i += 1;
    }
    out.join(", ")
}

/// A key and its value, the comment after them (in a column, at least a space away).
fn commented(text: &str, comment: &str) -> String {
    format!("{text:<31} # {comment}\n")
}

/// A commented build file of `settings` and `sizing`; `source` says where they come from.
/// Without a payload, commented lines show how to give one.
pub fn write(settings: &Settings, sizing: &Sizing, source: &str) -> String {
    let mut out = header(source);
    let line = |out: &mut String, key: &str, id: SettingId| {
        if let Some(value) = settings.get(id) {
            let text = format!("{key} = {}", toml_value(id, value));
            out.push_str(&commented(&text, &describe(id)));
        }
    };
    let mut stream = Vec::new();
    for id in SettingId::GLOBAL {
        if id == SettingId::Baud {
            // Left out, `apply` leaves the board's rate alone: shown commented.
            let rates: Vec<String> = BAUD_RATES.iter().map(u32::to_string).collect();
            let what = format!(
                "{}: {}; `save` keeps it; left out, apply leaves the board's rate as it is",
                id.meaning(),
                rates.join(" ")
            );
            out.push_str(&commented(&format!("# baud = {DEFAULT_BAUD}"), &what));
        }
        if id.is_link() {
            continue;
        }
        let name = id.to_string();
        match name.strip_prefix("stream.") {
            Some(short) => stream.push((short.to_string(), id)),
            None => line(&mut out, &name, id),
        }
    }
    if !settings.payload.carried() {
        out.push_str(PAYLOAD_EXAMPLE);
    }
    out.push_str("\n[stream]\n");
    for (short, id) in stream {
        line(&mut out, &short, id);
    }
    for servo in 1..=LEGS as u8 {
        out.push_str(&format!("\n[servo{servo}]\n"));
        for param in ServoParam::ALL {
            line(
                &mut out,
                param.name(),
                SettingId::Servo(ServoSel::One(servo), param),
            );
        }
    }
    out.push_str(sizing::HEADER);
    for (key, value) in sizing.entries() {
        let text = format!("{key} = {value:?}");
        out.push_str(&commented(&text, sizing::meaning(key)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(text: &str) -> BuildFile {
        parse("b.toml", text).unwrap_or_else(|e| panic!("{e}"))
    }

    fn err(text: &str) -> String {
        parse("b.toml", text).unwrap_err().to_string()
    }

    #[test]
    fn baud_is_kept_apart_to_be_sent_last_and_left_out_leaves_the_rate_alone() {
        let file = ok("baud = 921_600\nframe_hz = 100\n");
        assert_eq!(file.baud, Some(921_600));
        let commands: Vec<String> = file.steps.iter().map(Step::command).collect();
        assert_eq!(
            commands,
            ["set frame_hz 100"],
            "baud is not among the steps"
        );
        assert_eq!(ok("frame_hz = 100\n").baud, None);
        // A written file shows it commented out, so that it reads back without it.
        let written = write(&Settings::default(), &Sizing::default(), "t");
        assert!(written.contains("\n# baud = 115200 "), "{written}");
        assert!(written.contains("9600 19200 38400 57600 115200 230400 460800 921600"));
        assert_eq!(ok(&written).baud, None);
    }

    #[test]
    fn keys_are_the_set_names_in_every_toml_form() {
        let file = ok(
            "frame_hz = 100\nservos.rate_us_rad = 600\n[servo3]\ntrim_us = 1512\n\
                       [stream]\nz_mm = 12.5\naxis1 = \"none\"\n",
        );
        let s = &file.settings;
        assert_eq!(s.frame_hz, 100);
        assert!(s.servos.0.iter().all(|c| c.rate_us_per_rad == 600.0));
        assert_eq!(s.servos.0[2].home_us, 1512.0);
        assert_eq!(s.stream.full_scale[2], 12.5);
        assert_eq!(s.stream.text_order[0], None);
        let commands: Vec<String> = file.steps.iter().map(Step::command).collect();
        assert_eq!(
            commands,
            [
                "set frame_hz 100",
                "set servos.rate_us_rad 600",
                "set servo3.trim_us 1512",
                "set stream.z_mm 12.5",
                "set stream.axis1 none"
            ]
        );
        assert_eq!(file.steps[2].line, 4);
    }

    #[test]
    fn errors_name_file_line_and_key_in_the_board_s_words() {
        assert_eq!(
            err("frame_hz = 50\n\n[servo2]\ntrim_us = 3000\n"),
            "b.toml:4: servo2.trim_us: error:out-of-range servo2.trim_us 3000 is outside \
             400..2600 us"
        );
        assert!(err("colour = \"red\"").starts_with("b.toml:1: colour: error:unknown-setting"));
        assert!(err("[servo7]\ndir = \"normal\"")
            .starts_with("b.toml:2: servo7.dir: error:unknown-setting"));
        // Not "type config": a file is no terminal; where the list is, and a close name.
        assert_eq!(
            err("colour = \"red\""),
            "b.toml:1: colour: error:unknown-setting not a setting (the settings are listed in \
             docs/settings.md of the firmware's repository)"
        );
        assert_eq!(
            err("frame_hz = 50\nrdo_mm = 120\n"),
            "b.toml:2: rdo_mm: error:unknown-setting not a setting; did you mean rod_mm? (the \
             settings are listed in docs/settings.md of the firmware's repository)"
        );
        assert!(err("[servo3]\ntrim = 1500").contains("did you mean servo3.trim_us?"));
        assert!(err("speed_mm_s = \"fast\"").contains("error:bad-number"));
        assert!(err("echo = \"off\"").contains("belongs to the serial link"));
        assert!(err("baud = 100000").starts_with("b.toml:1: baud: error:bad-value baud"));
        assert!(err("rod_mm = [1, 2]").contains("not a setting value"));
        assert!(err("frame_hz = \n").starts_with("b.toml:1: not a TOML file"));
        assert!(
            err("a = 1\na = 2\n").starts_with("b.toml:2: not a TOML file"),
            "{}",
            err("a = 1\na = 2\n")
        );
        // Valid on its own, but no home height: the board's geometry check.
        assert!(err("rod_mm = 10").starts_with("b.toml:1: rod_mm: error:bad-geometry"));
    }

    #[test]
    fn steps_are_ordered_so_the_board_accepts_each() {
        // min_us 1600 is refused while trim_us is 1500: trim_us goes first.
        let file = ok("[servo1]\nmin_us = 1600\nmax_us = 2000\ntrim_us = 1700\n");
        let names: Vec<String> = file.steps.iter().map(|s| s.id.to_string()).collect();
        assert_eq!(names, ["servo1.max_us", "servo1.trim_us", "servo1.min_us"]);
        // The same result as the board: each step from the defaults, validated.
        let mut s = Settings::default();
        for step in &file.steps {
            s = s.with(step.id, step.id.parse_value(&step.value).unwrap());
            s.validate().unwrap();
        }
        assert_eq!(s, file.settings);
        // Overlapping keys keep their order: servos first, then servo3 wins.
        let file = ok("[servo3]\ntrim_us = 1510\n[servos]\ntrim_us = 1490\n");
        assert_eq!(file.settings.servos.0[2].home_us, 1490.0);
        let file = ok("servos.trim_us = 1490\n[servo3]\ntrim_us = 1510\n");
        assert_eq!(file.settings.servos.0[2].home_us, 1510.0);
        assert_eq!(file.settings.servos.0[0].home_us, 1490.0);
        // Impossible whatever the order: the first key that cannot go.
        assert!(err("[servo1]\nmin_us = 1600\n")
            .starts_with("b.toml:2: servo1.min_us: error:bad-servo-config"));
    }

    #[test]
    fn numbers_in_toml_forms_mean_what_toml_says() {
        let file =
            ok("frame_hz = 0x64\nrod_mm = 1_20.5\nspeed_mm_s = \"OFF\"\nlink_timeout_s = 5e-1\n");
        assert_eq!(file.settings.frame_hz, 100);
        assert_eq!(file.settings.layout.rod_mm, 120.5);
        assert_eq!(file.settings.speed_mm_s, 0.0);
        assert_eq!(file.settings.link_timeout_s, 0.5);
        assert!(err("rod_mm = nan").contains("error:not-finite"));
        assert!(err("rod_mm = 1e39").contains("error:number-too-large"));
    }

    #[test]
    fn a_written_file_reads_back_as_the_same_settings() {
        let written = write(
            &Settings::default(),
            &Sizing::default(),
            "the default platform",
        );
        let defaults = ok(&written);
        assert_eq!(defaults.settings, Settings::default());
        assert_eq!(defaults.sizing, Sizing::default());
        // Every key's comment is at least a space away, even after the longest key.
        assert!(
            written.contains("servo_stiffness_nmm_rad = 5000.0 # "),
            "{written}"
        );
        let custom = ok(
            "frame_hz = 200\nspeed_mm_s = \"off\"\nestop_pin = 15\npayload_g = 1250.5\n\
             payload_com_z_mm = -4\n[servo4]\ndir = \"normal\"\ntrim_us = 1520.25\n\
             torque_kgcm = 2.5\n[stream]\naxis1 = \"none\"\n[sizing]\n\
             servo_stiffness_nmm_rad = 8000\n",
        );
        assert_eq!(custom.sizing.servo_stiffness_nmm_rad, 8000.0);
        let again = ok(&write(&custom.settings, &custom.sizing, "a test"));
        assert_eq!(again.settings, custom.settings);
        assert_eq!(again.sizing, custom.sizing);
        assert!(err("[sizing]\nservo_stiffness_nmm_rad = 0\n")
            .starts_with("b.toml:2: sizing.servo_stiffness_nmm_rad: must be a number"));
        assert!(err("[sizing]\ncolour = 1\n").starts_with("b.toml:2: sizing.colour: "));
    }

    #[test]
    fn the_pivot_is_three_keys_the_board_takes_and_a_written_file_keeps_it() {
        let file = ok("pivot_z_mm = 250\npivot_x_mm = -12.5\n");
        assert_eq!(file.settings.pivot_mm, [-12.5, 0.0, 250.0]);
        let commands: Vec<String> = file.steps.iter().map(Step::command).collect();
        assert_eq!(commands, ["set pivot_z_mm 250", "set pivot_x_mm -12.5"]);
        // The IK the file's settings make turns about it.
        let solver = file.settings.validate().unwrap();
        assert_eq!(
            solver.rotation_centre_mm(),
            kinematics_core::Vec3::new(-12.5, 0.0, 250.0)
        );
        let written = write(&file.settings, &Sizing::default(), "a test");
        assert!(
            written.contains("\npivot_z_mm = 250.0 ") && written.contains("\npivot_y_mm = 0.0 "),
            "{written}"
        );
        assert!(
            written.contains("rotation centre (pivot), platform frame z (up), -1000..1000 mm"),
            "{written}"
        );
        assert_eq!(ok(&written).settings, file.settings);
        assert_eq!(
            err("pivot_y_mm = 1001\n"),
            "b.toml:1: pivot_y_mm: error:out-of-range pivot_y_mm 1001 is outside -1000..1000 mm"
        );
    }

    #[test]
    fn the_pins_comment_names_the_free_gpios_the_readme_lists() {
        // README, "Settings": estop_pin and power_pin take 8..=22 or 26..=28.
        let written = write(&Settings::default(), &Sizing::default(), "a test");
        let pin = "emergency-stop input: a GPIO (8..22, 26..28) or \"off\"";
        assert!(written.contains(pin), "{written}");
        assert_eq!(runs(&[3, 5, 6, 7, 9]), "3, 5..7, 9");
        assert_eq!(runs(&[]), "");
    }

    #[test]
    fn the_servos_speed_ratings_are_the_board_s_settings() {
        let file = ok("servos.speed_s_60deg = 0.1\n[servo3]\nspeed_s_60deg = 0.25\n");
        assert_eq!(
            file.settings.servo_speed.s_per_60deg,
            [0.1, 0.1, 0.25, 0.1, 0.1, 0.1]
        );
        let commands: Vec<String> = file.steps.iter().map(Step::command).collect();
        assert_eq!(
            commands,
            [
                "set servos.speed_s_60deg 0.1",
                "set servo3.speed_s_60deg 0.25"
            ]
        );
        // The board's refusals: more decimals than its flash keeps, a rating out of range.
        assert!(err("[servo2]\nspeed_s_60deg = 0.125\n")
            .starts_with("b.toml:2: servo2.speed_s_60deg: error:bad-value "));
        assert!(err("servos.speed_s_60deg = 3\n")
            .starts_with("b.toml:1: servos.speed_s_60deg: error:out-of-range"));
        // Written in [servoN] as `config` lists them, off by default, and read back the same.
        let written = write(&file.settings, &Sizing::default(), "a test");
        assert!(written.contains("\nspeed_s_60deg = 0.25 "), "{written}");
        assert_eq!(ok(&written).settings, file.settings);
        let default = write(&Settings::default(), &Sizing::default(), "a test");
        assert_eq!(
            default.matches("\nspeed_s_60deg = \"off\" ").count(),
            6,
            "{default}"
        );
    }

    #[test]
    fn the_payload_and_ratings_are_the_board_s_settings() {
        let file = ok(
            "payload_g = 1500\npayload_com_z_mm = 25\nservos.torque_kgcm = 10\n\
                       [servo3]\ntorque_kgcm = 12.345\n",
        );
        let p = &file.settings.payload;
        assert_eq!(p.mass_g, 1500.0);
        assert_eq!(p.com_mm, [0.0, 0.0, 25.0]);
        // Kept to hundredths, as by the board.
        assert_eq!(p.torque_kgcm, [10.0, 10.0, 12.35, 10.0, 10.0, 10.0]);
        let commands: Vec<String> = file.steps.iter().map(Step::command).collect();
        assert_eq!(
            commands,
            [
                "set payload_g 1500",
                "set payload_com_z_mm 25",
                "set servos.torque_kgcm 10",
                "set servo3.torque_kgcm 12.345"
            ]
        );
        // The board's ranges and words.
        assert_eq!(
            err("payload_g = 100001\n"),
            "b.toml:1: payload_g: error:out-of-range payload_g 100001 is outside 0..100000 g"
        );
        assert!(err("[servo2]\ntorque_kgcm = 601\n")
            .starts_with("b.toml:2: servo2.torque_kgcm: error:out-of-range"));
        // Written with the settings, in [servoN] as `config` lists them; the example of a
        // payload only where there is none.
        let written = write(&file.settings, &Sizing::default(), "a test");
        assert!(written.contains("\npayload_g = 1500.0 "), "{written}");
        assert!(written.contains("\n[servo3]\n"), "{written}");
        assert!(written.contains("\ntorque_kgcm = 12.35 "), "{written}");
        assert!(!written.contains("No payload"), "{written}");
        let default = write(&Settings::default(), &Sizing::default(), "a test");
        assert!(default.contains("\npayload_g = 0.0 "), "{default}");
        assert!(default.contains("\ntorque_kgcm = \"off\" "), "{default}");
        assert!(default.contains(PAYLOAD_EXAMPLE), "{default}");
        // The example, uncommented, is a file the board takes.
        let example: String = PAYLOAD_EXAMPLE
            .lines()
            .filter_map(|l| l.strip_prefix("#   "))
            .filter(|l| {
                l.split_once(" = ")
                    .is_some_and(|(key, _)| !key.contains(' '))
            })
            .map(|l| format!("{l}\n"))
            .collect();
        assert_eq!(ok(&example).settings.payload.mass_g, 500.0);
    }

    #[test]
    fn a_payload_a_servo_cannot_hold_at_home_is_refused_as_the_board_refuses_it() {
        // 5 kg centred: about 1.67 kgf cm per servo at home (1.2 kg gives 0.4, control's
        // payload tests), over a 1 kgf cm rating, whichever key comes last.
        let expected = "servo 1 would need 1.667 kgf cm to hold the payload, over its rating \
                        1.00 kgf cm; the board, holding home, refuses this setting \
                        (error:pose-conflict)";
        assert_eq!(
            err("payload_g = 5000\nservos.torque_kgcm = 1\n"),
            format!("b.toml:2: servos.torque_kgcm: at home {expected}")
        );
        assert_eq!(
            err("servos.torque_kgcm = 1\npayload_g = 5000\n"),
            format!("b.toml:2: payload_g: at home {expected}")
        );
        // A rating the payload needs less than, or no payload: accepted.
        ok("payload_g = 5000\nservos.torque_kgcm = 1.7\n");
        ok("servos.torque_kgcm = 0.01\n");
    }

    #[test]
    fn the_old_sizing_keys_name_the_setting_that_replaced_them() {
        assert_eq!(
            err("frame_hz = 50\n[sizing]\npayload_kg = 2.5\n"),
            "b.toml:3: sizing.payload_kg: now the board's setting payload_g (g): write \
             `payload_g = 2500` above the file's first [table] instead"
        );
        assert_eq!(
            err("[sizing]\npayload_x_mm = -3\n"),
            "b.toml:2: sizing.payload_x_mm: now the board's setting payload_com_x_mm (mm): \
             write `payload_com_x_mm = -3` above the file's first [table] instead"
        );
        assert!(err("[sizing]\npayload_y_mm = 1\n").contains("`payload_com_y_mm = 1`"));
        assert!(err("[sizing]\npayload_z_mm = 20\n").contains("`payload_com_z_mm = 20`"));
        assert_eq!(
            err("[sizing]\nservo_torque_kgcm = 1.8\n"),
            "b.toml:2: sizing.servo_torque_kgcm: now the board's setting servos.torque_kgcm \
             (kgf cm): write `servos.torque_kgcm = 1.8` above the file's first [table] (or \
             `torque_kgcm = 1.8` in a [servos] table) instead"
        );
        // Not a number: the setting all the same.
        assert!(err("[sizing]\npayload_kg = \"heavy\"\n").contains(
            "sizing.payload_kg: now the board's setting payload_g (g): write \
                       `payload_g` above"
        ));
    }
}
