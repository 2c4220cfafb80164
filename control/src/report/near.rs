//! "Did you mean": the known name closest to a mistyped command or setting name. Close means a
//! few edits away (a letter added, dropped, changed, or two neighbours swapped: one edit each;
//! at most one edit per three letters typed) or the start of exactly one name (`rod` for
//! `rod_mm`). The names come from the types (`Verb::ALL`, `SettingId::GLOBAL`, the servo
//! fields), never from a list of their own. Only a refusal calls this: the work (a hundred
//! short comparisons) is no cost to the loop.

use core::fmt::Write;

use crate::command::Verb;
use crate::settings::{ServoParam, ServoSel, SettingId};

/// The longest word compared; a longer one gets no suggestion (a name is at most 20 letters).
const LONGEST: usize = 32;

/// Words shorter than this get no suggestion: too many names are a couple of edits away.
const SHORTEST: usize = 3;

/// The command whose name is closest to `typed`, if one is close.
pub fn nearest_verb(typed: &str) -> Option<Verb> {
    nearest(typed, Verb::ALL.into_iter(), |v, name| {
        name.push_str(v.name()).is_ok()
    })
}

/// The setting whose name is closest to `typed` (lowercase), if one is close.
pub fn nearest_setting(typed: &str) -> Option<SettingId> {
    let servos = [ServoSel::All]
        .into_iter()
        .chain((1..=6).map(ServoSel::One))
        .flat_map(|sel| ServoParam::ALL.map(|p| SettingId::Servo(sel, p)));
    nearest(
        typed,
        SettingId::GLOBAL.into_iter().chain(servos),
        |id, name| write!(name, "{id}").is_ok(),
    )
}

/// A name being compared.
type Name = heapless::String<LONGEST>;

/// The candidate closest to `typed`: the first at the fewest edits (within one per three
/// letters), else the only one `typed` begins.
fn nearest<T: Copy>(
    typed: &str,
    candidates: impl Iterator<Item = T> + Clone,
    name_of: impl Fn(T, &mut Name) -> bool,
) -> Option<T> {
    if typed.len() < SHORTEST || typed.len() > LONGEST {
        return None;
    }
    let allowed = typed.len() / 3;
    let mut best: Option<(usize, T)> = None;
    let mut prefix_of: Option<T> = None;
    let mut prefixes = 0;
    for candidate in candidates {
        let mut name = Name::new();
        if !name_of(candidate, &mut name) {
            continue;
        }
        if name.starts_with(typed) {
            prefixes += 1;
            prefix_of = Some(candidate);
        }
        let d = distance_within(typed.as_bytes(), name.as_bytes(), allowed);
        if d <= allowed && best.is_none_or(|(b, _)| d < b) {
            best = Some((d, candidate));
        }
    }
    best.map(|(_, c)| c)
        .or(if prefixes == 1 { prefix_of } else { None })
}

/// Edits from `a` to `b` (optimal string alignment: insert, delete, substitute, swap two
/// neighbours), both at most [`LONGEST`] bytes (longer: `usize::MAX`).
#[cfg(test)]
fn distance(a: &[u8], b: &[u8]) -> usize {
    distance_within(a, b, LONGEST)
}

/// [`distance`] where it is at most `limit`; else some number above `limit`, found as soon as
/// it is certain: names whose lengths differ by more than `limit` are never compared, and the
/// table stops at the first row whose every entry is above it. A refusal runs this for every
/// name inside one main-loop pass, so it must stay cheap: three rows of bytes used in turn, no
/// copies (a 27-letter word against every command was 2 ms of a 1 ms pass before).
fn distance_within(a: &[u8], b: &[u8], limit: usize) -> usize {
    if a.len() > LONGEST || b.len() > LONGEST {
        return usize::MAX;
    }
    let over = limit.saturating_add(1);
    if a.len().abs_diff(b.len()) > limit {
        return over;
    }
    // Rows i-2, i-1 and i of the table, at rows[(i + 1) % 3] etc.; entries never exceed 32.
    let mut rows = [[0u8; LONGEST + 1]; 3];
    for (j, entry) in rows[0].iter_mut().enumerate() {
        *entry = j as u8;
    }
    for (i, &ca) in a.iter().enumerate() {
        let (now, last, before) = ((i + 1) % 3, i % 3, (i + 2) % 3);
        rows[now][0] = (i + 1) as u8;
        let mut least = rows[now][0];
        for (j, &cb) in b.iter().enumerate() {
            let change = u8::from(ca != cb);
            let mut d = (rows[last][j] + change)
                .min(rows[last][j + 1] + 1)
                .min(rows[now][j] + 1);
            if i > 0 && j > 0 && ca == b[j - 1] && a[i - 1] == cb {
                d = d.min(rows[before][j - 1] + 1);
            }
            rows[now][j + 1] = d;
            least = least.min(d);
        }
        if usize::from(least) > limit {
            return over;
        }
    }
    usize::from(rows[a.len() % 3][b.len()])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::LayoutParam;

    #[test]
    fn distance_counts_edits() {
        // By hand: each pair differs by the edits named.
        for (a, b, d) in [
            ("rod_mm", "rod_mm", 0),
            ("rdo_mm", "rod_mm", 1),  // swap
            ("rod_m", "rod_mm", 1),   // insert
            ("rodd_mm", "rod_mm", 1), // delete
            ("rod_km", "rod_mm", 1),  // change
            ("kitten", "sitting", 3),
            ("", "abc", 3),
            ("ab", "", 2),
            ("ca", "abc", 3), // optimal string alignment, not full Damerau (2)
        ] {
            assert_eq!(distance(a.as_bytes(), b.as_bytes()), d, "{a} -> {b}");
        }
    }

    #[test]
    fn a_close_command_is_suggested() {
        assert_eq!(nearest_verb("stauts"), Some(Verb::Status));
        assert_eq!(nearest_verb("hme"), Some(Verb::Home));
        assert_eq!(nearest_verb("geom"), Some(Verb::Geometry));
        assert_eq!(nearest_verb("defualts"), Some(Verb::Defaults));
        // Nothing close, too short to tell, or too long to compare.
        assert_eq!(nearest_verb("fly"), None);
        assert_eq!(nearest_verb("st"), None);
        assert_eq!(nearest_verb("calibrate"), None);
        assert_eq!(nearest_verb(&"s".repeat(40)), None);
    }

    #[test]
    fn a_close_setting_is_suggested() {
        let rod = SettingId::Layout(LayoutParam::RodMm);
        assert_eq!(nearest_setting("rdo_mm"), Some(rod));
        assert_eq!(nearest_setting("rod"), Some(rod));
        assert_eq!(nearest_setting("rod_cm"), Some(rod));
        assert_eq!(
            nearest_setting("servo3.trim"),
            Some(SettingId::Servo(ServoSel::One(3), ServoParam::TrimUs))
        );
        assert_eq!(
            nearest_setting("servos.dirr"),
            Some(SettingId::Servo(ServoSel::All, ServoParam::Dir))
        );
        assert_eq!(nearest_setting("speed_mm"), Some(SettingId::SpeedMmS));
        // `speed` starts two names and is five letters from each: no guess.
        assert_eq!(nearest_setting("speed"), None);
        assert_eq!(nearest_setting("colour"), None);
    }
}
