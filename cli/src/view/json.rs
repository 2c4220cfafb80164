//! The little JSON the view's page and server exchange: strings written with their escapes, and
//! the one string field a page's request carries (`{"line": "..."}`) read back.

use std::fmt::Write as _;

/// `text` as a JSON string, quotes included.
pub fn string(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 || c == '\u{7f}' => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A list of strings as a JSON array.
pub fn strings<S: AsRef<str>>(items: &[S]) -> String {
    let parts: Vec<String> = items.iter().map(|s| string(s.as_ref())).collect();
    format!("[{}]", parts.join(","))
}

/// The string value of `key` in a flat JSON object (`{"line": "pose 0 0 5 0 0 0"}`), or `None`
/// if the body is not such an object or the value is not a string.
pub fn string_field(body: &str, key: &str) -> Option<String> {
    let body = body.trim();
    let inner = body.strip_prefix('{')?.strip_suffix('}')?;
    let mut rest = inner.trim_start();
    loop {
        let (name, after) = parse_string(rest)?;
        let after = after.trim_start().strip_prefix(':')?.trim_start();
        if after.starts_with('"') {
            let (value, after) = parse_string(after)?;
            if name == key {
                return Some(value);
            }
            rest = after.trim_start();
        } else {
            // Another kind of value: skipped up to the next comma (numbers, true, null).
            let end = after.find(',').unwrap_or(after.len());
            rest = &after[end..];
        }
        rest = rest.strip_prefix(',')?.trim_start();
    }
}

/// A JSON string at the start of `text`: its value and what follows it.
fn parse_string(text: &str) -> Option<(String, &str)> {
    let mut chars = text.strip_prefix('"')?.char_indices();
    let mut value = String::new();
    while let Some((i, c)) = chars.next() {
        match c {
            '"' => return Some((value, &text[i + 2..])),
            '\\' => {
                let (_, escaped) = chars.next()?;
                match escaped {
                    '"' => value.push('"'),
                    '\\' => value.push('\\'),
                    '/' => value.push('/'),
                    'b' => value.push('\u{8}'),
                    'f' => value.push('\u{c}'),
                    'n' => value.push('\n'),
                    'r' => value.push('\r'),
                    't' => value.push('\t'),
                    'u' => {
                        let hex: String = (0..4)
                            .filter_map(|_| chars.next().map(|(_, h)| h))
                            .collect();
                        let code = u32::from_str_radix(&hex, 16).ok()?;
                        value.push(char::from_u32(code).unwrap_or('\u{fffd}'));
                    }
                    _ => return None,
                }
            }
            c => value.push(c),
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strings_round_trip_with_their_escapes() {
        for text in [
            "pose 0 0 5 0 0 0",
            "a \"quoted\" \\ back",
            "tab\there",
            "ctl \u{1} x",
        ] {
            let body = format!("{{\"line\": {}}}", string(text));
            assert_eq!(string_field(&body, "line").as_deref(), Some(text), "{body}");
        }
        assert_eq!(string(""), "\"\"");
        assert_eq!(strings(&["a", "b\"c"]), "[\"a\",\"b\\\"c\"]");
    }

    #[test]
    fn the_field_is_found_among_others_and_nothing_else_passes() {
        let body = r#"{ "n": 3, "other": "x", "line" : "home\u0021" }"#;
        assert_eq!(string_field(body, "line").as_deref(), Some("home!"));
        for bad in [
            "",
            "home",
            "{\"line\": 3}",
            "{\"line\": \"open",
            "[\"line\"]",
            "{\"x\": \"y\"}",
        ] {
            assert_eq!(string_field(bad, "line"), None, "{bad}");
        }
    }
}
