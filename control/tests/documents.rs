//! The user's documents (`docs/`) against the firmware's own lists, so no table is kept in step
//! by hand: every command, setting and error code is documented; each setting's meaning is the
//! firmware's (`SettingId::meaning`) and its range the one `set` checks (`SettingId::kind`);
//! `docs/error-codes.md` is exactly what `cargo run -p control --example documents` writes
//! from `Code::ALL`.

use control::report::{write_error_codes_doc, Code};
use control::settings::{Kind, ServoParam, SettingId};

const COMMANDS: &str = include_str!("../../docs/commands.md");
const SETTINGS: &str = include_str!("../../docs/settings.md");
const ERROR_CODES: &str = include_str!("../../docs/error-codes.md");

#[test]
fn every_error_code_command_and_setting_is_documented() {
    for code in Code::ALL {
        assert!(
            ERROR_CODES.contains(&format!("| `error:{}` |", code.as_str())),
            "docs/error-codes.md does not document error:{code}"
        );
    }
    for verb in control::command::Verb::ALL {
        let name = verb.name();
        assert!(
            COMMANDS.contains(&format!("| `{name}")),
            "docs/commands.md's command table does not document {name}"
        );
    }
    for id in SettingId::GLOBAL {
        assert!(
            SETTINGS.contains(&format!("`{id}`")),
            "docs/settings.md does not document setting {id}"
        );
    }
    for field in ServoParam::ALL {
        let name = format!("`servoN.{}`", field.name());
        assert!(
            SETTINGS.contains(&name),
            "docs/settings.md does not document {name}"
        );
    }
}

#[test]
fn the_error_code_list_is_up_to_date() {
    let mut expected = String::new();
    write_error_codes_doc(&mut expected).unwrap();
    assert!(
        ERROR_CODES == expected,
        "docs/error-codes.md is out of date: run `cargo run -p control --example documents`"
    );
    // And it lists every code once, in Code::ALL's order, each with a meaning and an example.
    let rows: Vec<&str> = ERROR_CODES
        .lines()
        .filter(|l| l.starts_with("| `error:"))
        .collect();
    assert_eq!(rows.len(), Code::ALL.len());
    for (row, code) in rows.iter().zip(Code::ALL) {
        let cells = cells(row);
        assert_eq!(cells[0], format!("`error:{code}`"));
        assert!(
            cells.len() == 3 && cells.iter().all(|c| !c.is_empty()),
            "{row}"
        );
    }
}

/// The cells of a Markdown table row, trimmed.
fn cells(row: &str) -> Vec<&str> {
    row.trim()
        .trim_start_matches('|')
        .trim_end_matches('|')
        .split(" | ")
        .map(str::trim)
        .collect()
}

/// The setting a name in the table stands for (`servoN.x`: servo 1's, whose meaning and range
/// every servo shares).
fn setting(name: &str) -> SettingId {
    let name = name.replace("servoN.", "servo1.");
    SettingId::parse(&name).unwrap_or_else(|| panic!("docs/settings.md: no setting {name}"))
}

/// What the value column must say for a setting of this kind: its range (or every value it
/// takes), as `set` checks it.
fn range_words(kind: Kind) -> Vec<String> {
    match kind {
        Kind::Whole {
            min, max, list: [], ..
        } => vec![format!("{min}..={max}")],
        Kind::Whole { list, .. } => list.iter().map(|v| v.to_string()).collect(),
        Kind::Number { min, max, unit, .. } => vec![format!("{min}..={max} {unit}")],
        Kind::Flag => vec!["`on`".into(), "`off`".into()],
        Kind::Dir => vec!["`normal`".into(), "`reversed`".into()],
        Kind::Choice(words) => words.iter().map(|w| format!("`{w}`")).collect(),
        Kind::Pin => {
            // The free GPIOs as runs of consecutive numbers: `8..=22`, `26..=28`.
            let pins = control::safety::FREE_GPIOS;
            let mut runs = Vec::new();
            let mut start = pins[0];
            for (i, &pin) in pins.iter().enumerate() {
                let last = i + 1 == pins.len() || pins[i + 1] != pin + 1;
                if last {
                    runs.push(format!("{start}..={pin}"));
                    if let Some(&next) = pins.get(i + 1) {
                        start = next;
                    }
                }
            }
            runs.push("`off`".into());
            runs
        }
    }
}

#[test]
fn the_settings_table_gives_each_setting_its_firmware_meaning_and_range() {
    let table: Vec<Vec<&str>> = SETTINGS
        .lines()
        .skip_while(|l| !l.starts_with("| name | meaning | value | default |"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(cells)
        .collect();
    let mut seen = Vec::new();
    for row in &table {
        assert_eq!(row.len(), 4, "{row:?}");
        let names: Vec<&str> = row[0].split('`').skip(1).step_by(2).collect();
        assert!(!names.is_empty(), "{row:?}");
        for name in names {
            let id = setting(name);
            assert_eq!(
                row[1],
                id.meaning(),
                "the meaning of {name} in docs/settings.md"
            );
            for words in range_words(id.kind()) {
                assert!(
                    row[2].contains(&words),
                    "docs/settings.md: {name}'s value should say {words}: {}",
                    row[2]
                );
            }
            assert!(!seen.contains(&name), "{name} twice in docs/settings.md");
            seen.push(name);
        }
    }
    // Every setting has its row: each global one by name, each servo field as `servoN.x`.
    let mut expected: Vec<String> = SettingId::GLOBAL.iter().map(|id| id.to_string()).collect();
    expected.extend(
        ServoParam::ALL
            .iter()
            .map(|p| format!("servoN.{}", p.name())),
    );
    let mut seen: Vec<String> = seen.iter().map(|s| s.to_string()).collect();
    seen.sort();
    expected.sort();
    assert_eq!(seen, expected);
}
