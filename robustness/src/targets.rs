//! One function per fuzz target. Each takes the fuzzer's raw bytes, never panics on its own
//! account, and panics (with a description) only when a guarantee breaks.

use arbitrary::{Arbitrary, Unstructured};
use control::command::{self, Command};
use control::number::{parse_f32, parse_u32, NumberError};
use control::protocol::{Feed, LineBuffer, Spoiled};
use control::record::{self, ENCODED_LEN};
use control::report;
use control::settings::{SettingId, Settings};

use crate::checked::{check_output_bytes, check_pulses, code_of, Checked};
use crate::line_model::{LineEnd, LineModel, Refusal};
use crate::ops::{Op, Session, Value};

/// Frames `Op::Settle` runs at most (20 s at 50 Hz).
const SETTLE_FRAMES: u32 = 1000;
/// Operations per session at most (keeps one input's run time bounded).
const MAX_OPS: usize = 64;

// ----- line assembly -----

/// Line assembly ([`LineBuffer`]) against the reference [`LineModel`]: the same line ends,
/// the same kept text, the same refusal reasons. Input: raw received bytes; or, after a
/// leading `0xFE`, bytes in which `0xFF` stands for "the receive queue lost bytes here"
/// (every other non-ASCII byte behaves like `0xFF` would as data).
pub fn protocol(data: &[u8]) {
    let (with_losses, bytes) = match data.split_first() {
        Some((0xFE, rest)) => (true, rest),
        _ => (false, data),
    };
    let mut lb = LineBuffer::new();
    let mut model = LineModel::new();
    let feed_byte = |b: u8, lb: &mut LineBuffer, model: &mut LineModel| {
        let feed = lb.feed(b);
        let expected = model.byte(b);
        match (&expected, feed) {
            (LineEnd::None, Feed::Added(_) | Feed::Erased | Feed::ErasedLine(_)) => {
                assert_eq!(lb.line().as_bytes(), model.pending(), "after byte {b:#04x}");
            }
            (LineEnd::None, Feed::Nothing | Feed::Cancelled | Feed::Overflowed) => {}
            (LineEnd::Blank, Feed::Empty) => {}
            (LineEnd::Frame, Feed::Frame(_) | Feed::DamagedFrame) => {}
            (LineEnd::Line(text), Feed::Line) => {
                assert_eq!(lb.line(), text, "line text");
                assert!(lb.line().len() <= control::protocol::MAX_LINE);
                lb.clear();
            }
            (LineEnd::Refused(r), Feed::Spoiled(why)) => {
                let matches = matches!(
                    (r, why),
                    (Refusal::TooLong, Spoiled::TooLong)
                        | (Refusal::BadCharacter, Spoiled::BadByte(_))
                        | (Refusal::RxOverflow, Spoiled::RxOverflow(_))
                );
                assert!(matches, "byte {b:#04x}: model {r:?}, line buffer {why:?}");
            }
            (e, f) => panic!("byte {b:#04x}: model {e:?}, line buffer {f:?}"),
        }
    };
    for &b in bytes {
        if with_losses && b == 0xFF {
            lb.rx_overflow(control::protocol::Lost {
                bytes: 1,
                in_uart: false,
            });
            model.lost();
        } else {
            feed_byte(b, &mut lb, &mut model);
        }
    }
}

// ----- command parsing -----

/// Parses arbitrary text as a command line: results are finite and range-checked, parsing
/// is case-insensitive and treats `,` and tab like spaces, and every error prints as one
/// well-formed `error:<code> ...` line.
pub fn command(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let line: &str = &text;
    let result = command::parse(line);
    match &result {
        Ok(Command::Pose(p) | Command::Check(p)) => {
            assert!(p.first_non_finite().is_none(), "{line:?} -> {p:?}");
        }
        Ok(Command::Move(v) | Command::Nudge(v)) => {
            assert!(v.0.iter().any(Option::is_some), "{line:?}: no axis");
            assert!(
                v.0.iter().flatten().all(|x| x.is_finite()),
                "{line:?} -> {v:?}"
            );
        }
        Ok(Command::Set(id, value)) => {
            assert!(
                id.check(*value).is_ok(),
                "{line:?}: unchecked value {value:?}"
            );
        }
        Ok(_) => {}
        Err(e) => {
            let mut out = String::new();
            let e = control::Error::from(e.clone());
            report::write_error(&mut out, &e);
            check_output_bytes(&out);
            assert!(out.ends_with("\r\n"), "{out:?}");
            let body = &out[..out.len() - 2];
            assert!(!body.contains(['\r', '\n']), "error spans lines: {out:?}");
            let code = code_of(body).unwrap_or_else(|| panic!("not an error line: {out:?}"));
            assert_eq!(code, e.code().as_str());
        }
    }
    if line.is_ascii() {
        assert_eq!(
            result,
            command::parse(&line.to_ascii_uppercase()),
            "case matters in {line:?}"
        );
        let spaced = line.replace([',', '\t'], " ");
        assert_eq!(
            result,
            command::parse(&spaced),
            "separators matter in {line:?}"
        );
    }
}

// ----- numbers -----

/// The documented decimal grammar, checked independently of `control::number`:
/// `[sign] (digits [. digits*] | . digits) [(e|E) [sign] digits]`.
pub fn is_documented_decimal(text: &str) -> bool {
    let b = text.as_bytes();
    let mut i = 0;
    let digits_from = |i: &mut usize| {
        let start = *i;
        while *i < b.len() && b[*i].is_ascii_digit() {
            *i += 1;
        }
        *i - start
    };
    if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
        i += 1;
    }
    let mut mantissa = digits_from(&mut i);
    if i < b.len() && b[i] == b'.' {
        i += 1;
        mantissa += digits_from(&mut i);
    }
    if mantissa == 0 {
        return false;
    }
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        i += 1;
        if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
            i += 1;
        }
        if digits_from(&mut i) == 0 {
            return false;
        }
    }
    i == b.len()
}

fn is_nan_or_inf_word(text: &str) -> bool {
    let t = text
        .strip_prefix(['+', '-'])
        .unwrap_or(text)
        .to_ascii_lowercase();
    t == "nan" || t == "inf" || t == "infinity"
}

/// Number parsing against the documented grammar and the standard library's correctly
/// rounded parser.
pub fn number(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let text: &str = &text;
    let got = parse_f32(text);
    let want = if is_nan_or_inf_word(text) {
        Err(NumberError::NotFinite)
    } else if is_documented_decimal(text) {
        let v: f32 = text.parse().expect("the grammar is a subset of Rust's");
        if v.is_finite() {
            Ok(v)
        } else {
            Err(NumberError::TooLarge)
        }
    } else {
        Err(NumberError::Syntax)
    };
    match (got, want) {
        (Ok(a), Ok(b)) => assert_eq!(a.to_bits(), b.to_bits(), "{text:?}"),
        (a, b) => assert_eq!(a, b, "parse_f32({text:?})"),
    }

    let got = parse_u32(text);
    let all_digits = !text.is_empty() && text.bytes().all(|c| c.is_ascii_digit());
    let want = if all_digits {
        let trimmed = text.trim_start_matches('0');
        if trimmed.len() > 10 {
            Err(NumberError::TooLarge)
        } else {
            let v: u64 = if trimmed.is_empty() {
                0
            } else {
                trimmed.parse().expect("at most 10 digits")
            };
            u32::try_from(v).map_err(|_| NumberError::TooLarge)
        }
    } else {
        match parse_f32(text) {
            Ok(_) => Err(NumberError::NotWhole),
            Err(e) => Err(e),
        }
    };
    assert_eq!(got, want, "parse_u32({text:?})");
}

// ----- settings -----

#[derive(Debug, Arbitrary)]
enum SettingsInput {
    /// Stored bytes as they are.
    Raw(Vec<u8>),
    /// The default record with some bytes changed, checksum fixed (or not).
    Patched {
        patches: Vec<(u8, u8)>,
        fix_checksum: bool,
    },
    /// `set` lines a user might type, applied one after another like the controller does.
    Set(Vec<(SetName, SetValue)>),
}

#[derive(Debug, Arbitrary)]
enum SetName {
    Known(u8),
    Text(String),
}

#[derive(Debug, Arbitrary)]
enum SetValue {
    Typed(Value),
    Text(String),
}

/// `s` as the record of a save (its sequence number does not matter here).
fn saved(settings: Settings) -> record::Record {
    record::Record {
        sequence: 42,
        settings,
        baud: control::settings::DEFAULT_BAUD,
    }
}

/// A decoded record: valid, re-encodes to the same bytes, and a controller starts on it at
/// its home pulses.
fn check_decoded(bytes: &[u8]) {
    if let Ok(r) = record::decode(bytes) {
        let s = r.settings;
        if let Err(e) = s.validate() {
            panic!("decoded settings do not validate: {e:?}");
        }
        if bytes[4..6] != record::FORMAT_VERSION.to_le_bytes() {
            // Formats 3 and 4 are read, never written: a save writes them again in the new
            // format. Neither holds a pivot or speed ratings; format 3 no baud rate either.
            assert_eq!(r.settings.pivot_mm, [0.0; 3]);
            assert_eq!(r.settings.servo_speed, Default::default());
            if bytes[4..6] == record::FORMAT_VERSION_NO_BAUD.to_le_bytes() {
                assert_eq!(r.baud, control::settings::DEFAULT_BAUD);
            }
            assert_eq!(record::decode(&record::encode(&r)), Ok(r));
        } else {
            assert_eq!(
                &record::encode(&r)[..],
                &bytes[..ENCODED_LEN],
                "decode/encode is not the identity"
            );
        }
        let mut c = Checked::new(s, true);
        c.frames(2);
        c.line("status", b"\r");
    }
}

/// Settings: binary decoding of anything (damaged, patched with a valid checksum) and `set`
/// name/value parsing applied like the controller applies it.
///
/// Input: a stored record (starts with the magic `HXPS`), `set` lines as typed (starts with
/// `set `: each line goes through the command parser and is applied if the result validates,
/// like the controller does), or anything else: structured (damaged records, patched records
/// with a fixed checksum, `set` name/value pairs).
pub fn settings(data: &[u8]) {
    if data.starts_with(b"HXPS") {
        check_decoded(data);
        return;
    }
    if data.starts_with(b"set ") {
        let text = String::from_utf8_lossy(data);
        let mut s = Settings::default();
        for line in text.split(['\r', '\n']) {
            if let Ok(Command::Set(id, v)) = command::parse(line) {
                let candidate = s.with(id, v);
                if candidate.validate().is_ok() {
                    s = candidate;
                    assert_eq!(
                        record::decode(&record::encode(&saved(s))),
                        Ok(saved(s)),
                        "round trip of {s:?}"
                    );
                }
            }
        }
        let mut c = Checked::new(s, true);
        c.frames(2);
        return;
    }
    let u = Unstructured::new(data);
    let Ok(input) = SettingsInput::arbitrary_take_rest(u) else {
        return;
    };
    match input {
        SettingsInput::Raw(bytes) => check_decoded(&bytes),
        SettingsInput::Patched {
            patches,
            fix_checksum,
        } => {
            let mut bytes = record::encode(&saved(Settings::default()));
            for (at, v) in patches {
                bytes[usize::from(at) % ENCODED_LEN] = v;
            }
            if fix_checksum {
                let end = ENCODED_LEN - 4;
                let crc = record::crc32(&bytes[..end]);
                bytes[end..].copy_from_slice(&crc.to_le_bytes());
            }
            check_decoded(&bytes);
        }
        SettingsInput::Set(changes) => {
            let mut s = Settings::default();
            for (name, value) in changes {
                let name = match name {
                    SetName::Known(i) => crate::ops::SETTING_NAMES
                        [usize::from(i) % crate::ops::SETTING_NAMES.len()]
                    .to_owned(),
                    SetName::Text(t) => t.to_ascii_lowercase(),
                };
                let value = match value {
                    SetValue::Typed(v) => match v {
                        Value::Num(n) => n.text(),
                        Value::Word(i) => {
                            crate::ops::WORDS[usize::from(i) % crate::ops::WORDS.len()].to_owned()
                        }
                    },
                    SetValue::Text(t) => t.to_ascii_lowercase(),
                };
                let Some(id) = SettingId::parse(&name) else {
                    continue;
                };
                let Ok(v) = id.parse_value(&value) else {
                    continue;
                };
                assert!(
                    id.check(v).is_ok(),
                    "{name} {value}: parsed but out of range"
                );
                let candidate = s.with(id, v);
                if candidate.validate().is_ok() {
                    s = candidate;
                    let bytes = record::encode(&saved(s));
                    assert_eq!(record::decode(&bytes), Ok(saved(s)), "round trip of {s:?}");
                }
            }
            let c = Checked::new(s, true);
            check_pulses(c.ctl.settings(), &c.ctl.pulses_us(), "start-up");
        }
    }
}

// ----- the whole controller -----

/// Runs one structured session through a [`Checked`] controller.
pub fn run_session(session: &Session) {
    let mut c = Checked::new(Settings::default(), session.echo);
    for op in session.ops.iter().take(MAX_OPS) {
        match op {
            Op::Line(cmd, sep, upper, end) => c.line(&cmd.text(*sep, *upper), end.bytes()),
            Op::Bytes(bytes) => c.bytes(bytes),
            Op::Frames(n) => c.frames(1 + u32::from(*n)),
            Op::Settle => {
                c.settle(SETTLE_FRAMES);
            }
            Op::Lost(n) => c.rx_overflow(1 + u32::from(*n)),
            Op::Execute(cmd, sep) => c.execute(&cmd.text(*sep, false)),
            Op::Binary(_) | Op::TextFrame(_) => c.bytes(&op.frame_bytes()),
            Op::Estop(open) => c.estop(*open),
        }
    }
    // Whatever happened, a fresh line is understood: after a pause (a binary frame cut short
    // is dropped after two servo frames) cancel any partial line, then `stop`.
    c.frames(2);
    let replies = c.replies;
    c.bytes(b"\x03");
    c.line("stop", b"\r\n");
    assert_eq!(c.replies, replies + 1);
    assert!(
        c.log.trim_end_matches("> ").ends_with("ok\r\n"),
        "stop after the session was not ok: {:?}",
        c.log
    );
}

/// The whole command interpreter with the kinematics behind it.
///
/// Input: a script of real command lines (starts with a printable byte, CR or LF): fed byte
/// by byte with echo on, the motion run to its end after every line end; or anything else:
/// a structured [`Session`] (bytes, command lines, frames, losses and `execute_line` calls
/// interleaved, echo on or off).
pub fn controller(data: &[u8]) {
    match data.first() {
        Some(&b) if (0x20..=0x7E).contains(&b) || b == b'\r' || b == b'\n' => script(data),
        _ => {
            if let Ok(session) = Session::arbitrary_take_rest(Unstructured::new(data)) {
                run_session(&session);
            }
        }
    }
}

/// Feeds a script of lines, running the motion to its end after each line end.
pub fn script(data: &[u8]) {
    let mut c = Checked::new(Settings::default(), true);
    for &b in data {
        c.byte(b);
        if b == b'\r' || b == b'\n' {
            c.settle(SETTLE_FRAMES);
            c.frames(1);
        }
    }
    c.bytes(b"\x03");
    c.line("stop", b"\n");
}

// ----- stream frames and the tracker -----

/// The stream frame decoders and the tracker. The first bytes choose tracker limits and a
/// frame rate (any values, zero, negative and huge included); the rest are received bytes:
/// through the line assembler (frames reported must have the documented shape: binary counts
/// from the frame's own bytes, text counts below 2^16) and, as counts, targets for the
/// tracker, which must never produce a non-finite pose, never pass a target it approaches,
/// and keep to the speed limit on every frame and to the acceleration limit on every frame
/// but a hard stop on a target that jumped back.
pub fn stream(data: &[u8]) {
    use control::stream::Frame;
    use control::tracker::{TrackLimits, Tracker};
    use kinematics_core::{Libm, Pose};

    let mut u = Unstructured::new(data);
    let mut limit = || -> f32 {
        match u.int_in_range(0u8..=3).unwrap_or(0) {
            0 => 0.0,
            1 => f32::from(u.int_in_range(1u16..=5000).unwrap_or(1)),
            2 => f32::arbitrary(&mut u).unwrap_or(0.0),
            _ => 1e30,
        }
    };
    let limits = TrackLimits {
        mm_per_s: limit(),
        mm_per_s2: limit(),
        rad_per_s: limit(),
        rad_per_s2: limit(),
    };
    let hz = f32::from(u.int_in_range(50u16..=333).unwrap_or(50));
    let dt = 1.0 / hz;
    let bytes = u.take_rest();

    let mut lb = LineBuffer::new();
    let mut tracker = Tracker::new(&Pose::HOME);
    // Each axis' speed over the last step (position change / dt).
    let mut velocity = [0.0f32; 6];
    for (i, &b) in bytes.iter().enumerate() {
        let counts = match lb.feed_at(b, (i / 64) as u32) {
            Feed::Frame(Frame::Binary(c)) => {
                // The counts are the frame's own bytes: it ended with 0D 0A at this byte.
                assert!(
                    i >= 15 && bytes[i - 1] == 0x0D && b == 0x0A,
                    "binary frame at {i}"
                );
                assert!(c.iter().all(|&v| v <= 0xFFFF));
                c
            }
            Feed::Frame(Frame::Text(c)) => {
                assert_eq!(b, b'X');
                assert!(c.iter().all(|&v| v <= 0xFFFF));
                c
            }
            Feed::Line | Feed::Spoiled(_) | Feed::Empty => {
                lb.clear();
                continue;
            }
            _ => continue,
        };
        // Counts -> a target of up to +-500 mm / +-pi rad.
        let target: [f32; 6] = core::array::from_fn(|k| {
            let fraction = (counts[k] as f32 - 32768.0) / 32768.0;
            fraction * if k < 3 { 500.0 } else { core::f32::consts::PI }
        });
        let target = Pose::from_array(target);
        for _ in 0..8 {
            let next = tracker.step::<Libm>(&target, &limits, dt);
            let (p0, p1, goal) = (
                tracker.pose().to_array(),
                next.pose().to_array(),
                target.to_array(),
            );
            for k in 0..6 {
                assert!(p1[k].is_finite(), "axis {k}: {p1:?} from {p0:?}");
                let (v_max, a_max) = if k < 3 {
                    (limits.mm_per_s, limits.mm_per_s2)
                } else {
                    (limits.rad_per_s, limits.rad_per_s2)
                };
                let speed = (p1[k] - p0[k]).abs() / dt;
                if v_max > 0.0 && v_max.is_finite() {
                    let rounding = 4.0 * f32::EPSILON * p0[k].abs().max(p1[k].abs()).max(1.0) / dt;
                    assert!(
                        speed <= v_max * 1.001 + rounding,
                        "axis {k}: {speed} > {v_max}"
                    );
                }
                // The acceleration limit holds on every step that does not end on the target
                // (one that does may be a hard stop on a target that jumped back).
                let v1 = (p1[k] - p0[k]) / dt;
                if a_max > 0.0 && a_max.is_finite() && p1[k] != goal[k] {
                    let change = (v1 - velocity[k]).abs();
                    let allowed = a_max * dt;
                    // Speeds measured from f32 positions: a few units in the last place of the
                    // position, per frame time.
                    let rounding = 8.0 * f32::EPSILON * p0[k].abs().max(p1[k].abs()).max(1.0) / dt;
                    assert!(
                        change <= allowed * 1.001 + rounding,
                        "axis {k}: speed {} -> {v1} in one frame, limit {allowed}",
                        velocity[k]
                    );
                }
                velocity[k] = v1;
                // Never past the target from the side it was on.
                if (goal[k] - p0[k]) * (goal[k] - p1[k]) < 0.0 {
                    panic!(
                        "axis {k} passed its target: {} -> {} past {}",
                        p0[k], p1[k], goal[k]
                    );
                }
            }
            tracker = next;
        }
    }
}
