//! The build file's `[cue]` table: the washout's tuning and the cues' limits, for `hexapod
//! cue`. Not a setting of the board (`apply` never sends it): the board only ever sees poses.
//!
//! ```toml
//! [cue]
//! margin = 0.8          # cues keep within this fraction of the reach and full scales
//! pivot_z_mm = 60       # rotations about the pilot's head, 60 mm above the platform centre
//! [cue.x]
//! scale = 0.3           # gain on the aircraft's forward specific force
//! hp_hz = 1.0
//! [cue.tilt]
//! rate_deg_s = 4
//! ```
//!
//! Every key and its range is in [`KEYS`], with what it does in [`key_meaning`];
//! a key left out is the default ([`CueSettings::default`]). Units are those of the names.

use std::path::Path;

use toml::de::{DeTable, DeValue};

use super::washout::Tuning;
use crate::build_file;
use crate::error::{CueKeyError, Error, KeyError};
use crate::files::read_text;

/// The table's name (the build file leaves it to `hexapod cue`).
pub const TABLE: &str = build_file::CUE_TABLE;

/// The axes' sub-tables, in pose order.
pub const AXES: [&str; 6] = ["x", "y", "z", "roll", "pitch", "yaw"];

/// Everything `hexapod cue` takes from a build file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CueSettings {
    /// The washout filter's tuning.
    pub tuning: Tuning,
    /// Cues keep within this fraction of the platform's reach from home and of the board's
    /// stream full scales.
    pub margin: f64,
    /// The soft limit bends from this fraction of an axis' limit on.
    pub knee: f64,
    /// No valid telemetry for this long is a stall: the platform eases home, s.
    pub stall_s: f64,
    /// How long easing home (or back into the cues) takes, s.
    pub ease_s: f64,
    /// The centre of the rotations (the pilot's head) in the platform's frame at home, from
    /// the board's own rotation centre, mm.
    pub pivot_mm: [f64; 3],
}

impl Default for CueSettings {
    fn default() -> CueSettings {
        CueSettings {
            tuning: Tuning::default(),
            margin: 0.8,
            knee: 0.6,
            stall_s: 0.25,
            ease_s: 3.0,
            pivot_mm: [0.0; 3],
        }
    }
}

/// A key's place and range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeySpec {
    /// Its name under `cue.`.
    pub name: &'static str,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Whether only whole numbers (orders) or +-1 (signs) are meant.
    pub kind: KeyKind,
}

/// What a key's value may be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyKind {
    /// Any number in range.
    Number,
    /// A whole number in range.
    Whole,
    /// 1 or -1.
    Sign,
}

const fn key(name: &'static str, min: f64, max: f64, kind: KeyKind) -> KeySpec {
    KeySpec {
        name,
        min,
        max,
        kind,
    }
}

use KeyKind::{Number, Sign, Whole};

impl KeySpec {
    /// The error for a value out of this key's range.
    fn range_error(&self) -> CueKeyError {
        let (min, max) = (self.min, self.max);
        match self.kind {
            Number => CueKeyError::Number { min, max },
            Whole => CueKeyError::Whole { min, max },
            Sign => CueKeyError::Sign,
        }
    }
}

/// The keys of `[cue]`: the general ones, then each translation axis' filter (x y z), each
/// rotation axis' (roll pitch yaw), then the tilt's; an axis' keys are written once here for
/// all three of its kind.
macro_rules! cue_keys {
    ([$($general:expr),* $(,)?], [$($translation:literal),*], [$($rotation:literal),*],
     [$($tilt:expr),* $(,)?]) => {
        [
            $($general,)*
            $(
                key(concat!($translation, ".scale"), 0.0, 10.0, Number),
                key(concat!($translation, ".order"), 2.0, 3.0, Whole),
                key(concat!($translation, ".hp_hz"), 0.01, 20.0, Number),
                key(concat!($translation, ".zeta"), 0.1, 3.0, Number),
                key(concat!($translation, ".hp3_hz"), 0.001, 20.0, Number),
                key(concat!($translation, ".sign"), -1.0, 1.0, Sign),
            )*
            $(
                key(concat!($rotation, ".scale"), 0.0, 10.0, Number),
                key(concat!($rotation, ".order"), 1.0, 2.0, Whole),
                key(concat!($rotation, ".hp_hz"), 0.01, 20.0, Number),
                key(concat!($rotation, ".zeta"), 0.1, 3.0, Number),
                key(concat!($rotation, ".sign"), -1.0, 1.0, Sign),
            )*
            $($tilt,)*
        ]
    };
}

/// Every key, in the order `init` would write them.
pub const KEYS: [KeySpec; 46] = cue_keys!(
    [
        key("margin", 0.1, 1.0, Number),
        key("knee", 0.0, 1.0, Number),
        key("stall_s", 0.02, 10.0, Number),
        key("ease_s", 0.1, 30.0, Number),
        key("pivot_x_mm", -1000.0, 1000.0, Number),
        key("pivot_y_mm", -1000.0, 1000.0, Number),
        key("pivot_z_mm", -1000.0, 1000.0, Number),
    ],
    ["x", "y", "z"],
    ["roll", "pitch", "yaw"],
    [
        key("tilt.scale", 0.0, 10.0, Number),
        key("tilt.order", 1.0, 2.0, Whole),
        key("tilt.lp_hz", 0.01, 20.0, Number),
        key("tilt.zeta", 0.1, 3.0, Number),
        key("tilt.rate_deg_s", 0.1, 90.0, Number),
        key("tilt.max_deg", 0.0, 45.0, Number),
    ]
);

impl CueSettings {
    /// The value of a key (its name under `cue.`), if it is one.
    pub fn get(&self, name: &str) -> Option<f64> {
        let mut copy = *self;
        copy.slot(name).map(|v| *v)
    }

    /// Where a key's value lives.
    fn slot(&mut self, name: &str) -> Option<&mut f64> {
        Some(match name {
            "margin" => &mut self.margin,
            "knee" => &mut self.knee,
            "stall_s" => &mut self.stall_s,
            "ease_s" => &mut self.ease_s,
            "pivot_x_mm" => &mut self.pivot_mm[0],
            "pivot_y_mm" => &mut self.pivot_mm[1],
            "pivot_z_mm" => &mut self.pivot_mm[2],
            "tilt.scale" => &mut self.tuning.tilt.scale,
            "tilt.lp_hz" => &mut self.tuning.tilt.lp_hz,
            "tilt.zeta" => &mut self.tuning.tilt.zeta,
            "tilt.rate_deg_s" => &mut self.tuning.tilt.rate_deg_s,
            "tilt.max_deg" => &mut self.tuning.tilt.max_deg,
            _ => {
                let (axis, field) = name.split_once('.')?;
                let i = AXES.iter().position(|a| *a == axis)?;
                let c = &mut self.tuning.axes[i];
                match field {
                    "scale" => &mut c.scale,
                    "hp_hz" => &mut c.hp_hz,
                    "zeta" => &mut c.zeta,
                    "hp3_hz" if i < 3 => &mut c.hp3_hz,
                    "sign" => &mut c.sign,
                    _ => return None,
                }
            }
        })
    }

    /// Sets one key (its name under `cue.`): refuses unknown keys and values out of range.
    pub fn set(&mut self, name: &str, value: Option<f64>) -> Result<(), CueKeyError> {
        let spec = KEYS
            .iter()
            .find(|k| k.name == name)
            .ok_or(CueKeyError::Unknown)?;
        let ok = value.filter(|v| {
            (spec.min..=spec.max).contains(v)
                && match spec.kind {
                    Number => true,
                    Whole => v.fract() == 0.0,
                    Sign => v.abs() == 1.0,
                }
        });
        let Some(v) = ok else {
            return Err(spec.range_error());
        };
        if let Some(prefix) = name.strip_suffix(".order") {
            // A whole number in 1..=3 (its range says).
            let order = v as u8;
            match AXES.iter().position(|a| *a == prefix) {
                Some(i) => self.tuning.axes[i].order = order,
                None => self.tuning.tilt.order = order,
            }
            return Ok(());
        }
        let slot = self.slot(name).ok_or(CueKeyError::Unknown)?;
        *slot = v;
        Ok(())
    }
}

/// The `[cue]` table of a build file (the rest of it checked as `apply` checks it), or the
/// defaults without one.
pub fn read(build: Option<&Path>) -> Result<CueSettings, Error> {
    match build {
        Some(path) => {
            let text = read_text(path)?;
            let file = path.display().to_string();
            build_file::parse(&file, &text)?;
            parse(&file, &text)
        }
        None => Ok(CueSettings::default()),
    }
}

/// Reads the `[cue]` table of a build file's text (the rest is `build_file`'s); `file` names
/// it in errors. No table: the defaults.
pub fn parse(file: &str, text: &str) -> Result<CueSettings, Error> {
    let line_of = |offset: usize| text[..offset.min(text.len())].matches('\n').count() + 1;
    let mut settings = CueSettings::default();
    // A file that is not TOML is build_file's to report; here it has no [cue] table.
    let Ok(table) = DeTable::parse(text) else {
        return Ok(settings);
    };
    let Some(cue) = table.get_ref().get(TABLE) else {
        return Ok(settings);
    };
    let mut found = Vec::new();
    flatten(
        "",
        cue.get_ref(),
        line_of(cue.span().start),
        &line_of,
        &mut found,
    );
    for (name, line, value) in found {
        let number = match value {
            Some(DeValue::Integer(i)) if i.radix() == 10 => {
                i.as_str().replace('_', "").parse().ok()
            }
            Some(DeValue::Float(x)) => x.as_str().replace('_', "").parse().ok(),
            _ => None,
        };
        let name = name.to_ascii_lowercase();
        settings.set(&name, number).map_err(|why| Error::Key {
            file: file.to_string(),
            line,
            key: format!("{TABLE}.{name}"),
            why: KeyError::Cue(why),
        })?;
    }
    Ok(settings)
}

type Found<'a> = Vec<(String, usize, Option<&'a DeValue<'a>>)>;

fn flatten<'a>(
    prefix: &str,
    value: &'a DeValue<'a>,
    line: usize,
    line_of: &dyn Fn(usize) -> usize,
    found: &mut Found<'a>,
) {
    match value {
        DeValue::Table(inner) => {
            for (k, v) in inner {
                let name = if prefix.is_empty() {
                    k.get_ref().to_string()
                } else {
                    format!("{prefix}.{}", k.get_ref())
                };
                flatten(&name, v.get_ref(), line_of(k.span().start), line_of, found);
            }
        }
        DeValue::Integer(_) | DeValue::Float(_) => {
            found.push((prefix.to_string(), line, Some(value)))
        }
        _ => found.push((prefix.to_string(), line, None)),
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cue_table_is_read_nested_or_dotted_and_the_rest_left_to_the_board() {
        let text = "rod_mm = 125\n[cue]\nmargin = 0.7\npivot_z_mm = 60\nx.scale = 0.25\n\
                    [cue.tilt]\nrate_deg_s = 3\norder = 1\n[cue.yaw]\nsign = -1\norder = 1\n";
        let s = parse("b.toml", text).unwrap();
        assert_eq!(s.margin, 0.7);
        assert_eq!(s.pivot_mm, [0.0, 0.0, 60.0]);
        assert_eq!(s.tuning.axes[0].scale, 0.25);
        assert_eq!(s.tuning.tilt.rate_deg_s, 3.0);
        assert_eq!(s.tuning.tilt.order, 1);
        assert_eq!(s.tuning.axes[5].sign, -1.0);
        assert_eq!(s.tuning.axes[5].order, 1);
        // What is not given is the default.
        assert_eq!(s.tuning.axes[1], CueSettings::default().tuning.axes[1]);
        // The board's part of the same file is the board's, without the table.
        let board = crate::build_file::parse("b.toml", text).unwrap();
        assert_eq!(board.settings.layout.rod_mm, 125.0);
        // No table: the defaults.
        assert_eq!(
            parse("b.toml", "rod_mm = 125\n").unwrap(),
            CueSettings::default()
        );
    }

    #[test]
    fn bad_keys_name_file_line_key_and_range() {
        let err = |text: &str| parse("b.toml", text).unwrap_err().to_string();
        assert_eq!(
            err("[cue]\nmargin = 2\n"),
            "b.toml:2: cue.margin: must be a number 0.1..1"
        );
        assert_eq!(
            err("[cue]\n\n[cue.x]\norder = 1\n"),
            "b.toml:4: cue.x.order: must be a whole number 2..3"
        );
        assert_eq!(
            err("[cue.roll]\norder = 1.5\n"),
            "b.toml:2: cue.roll.order: must be a whole number 1..2"
        );
        assert_eq!(
            err("[cue.z]\nsign = 0.5\n"),
            "b.toml:2: cue.z.sign: must be 1 or -1"
        );
        assert!(err("[cue]\nx.colour = 1\n").starts_with("b.toml:2: cue.x.colour: not a [cue] key"));
        assert!(err("[cue.roll]\nhp3_hz = 1\n").starts_with("b.toml:2: cue.roll.hp3_hz: not a"));
        assert_eq!(
            err("[cue]\nknee = \"soft\"\n"),
            "b.toml:2: cue.knee: must be a number 0..1"
        );
    }

    #[test]
    fn every_key_has_a_meaning_and_a_value() {
        let s = CueSettings::default();
        for k in KEYS {
            assert!(!key_meaning(k.name).is_empty(), "{}", k.name);
            if !k.name.ends_with(".order") {
                let v = s.get(k.name).unwrap_or_else(|| panic!("{}", k.name));
                assert!((k.min..=k.max).contains(&v), "{} = {v}", k.name);
            }
        }
    }

    #[test]
    fn the_documented_defaults_are_the_defaults_and_name_every_key() {
        let doc =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/cueing.md"))
                .unwrap();
        let block = doc
            .split("<!-- the defaults, written out")
            .nth(1)
            .and_then(|rest| rest.split("```toml\n").nth(1))
            .and_then(|rest| rest.split("```").next())
            .unwrap();
        assert_eq!(
            parse("docs/cueing.md", block).unwrap(),
            CueSettings::default()
        );
        let keys = block.lines().filter(|l| l.contains(" = ")).count();
        assert_eq!(keys, KEYS.len(), "{block}");
    }
}
