//! A reference model of the documented line protocol (`control::protocol` module docs and
//! `docs/commands.md`), written independently of its implementation: it says, for every
//! received byte, whether a line ends there and what that line is, so the checkers can demand
//! exactly one final reply where one is due and none elsewhere.
//!
//! The rules modelled:
//! - CR, LF and CRLF each end a line (an LF right after a CR belongs to it);
//! - BS / DEL erase the last character, Ctrl-U the whole line (not on a refused line);
//!   Ctrl-C / Ctrl-X abandon the line (no reply);
//! - tab is a space; other control bytes are ignored;
//! - ESC `[` starts a CSI sequence: parameter and intermediate bytes (0x20..=0x3F) and a final
//!   byte (0x40..=0x7E), all swallowed; ESC `O` swallows one more printable byte (SS3); ESC
//!   followed by anything else is a lone ESC, dropped, and that byte counts as typed (ESC ESC:
//!   the second ESC starts anew). A byte that is not printable ends a sequence and then counts
//!   on its own;
//! - at most 128 characters are kept; a longer line is refused (`line-too-long`) once it ends;
//! - a byte outside printable ASCII refuses the line (`bad-character`);
//! - bytes lost by the receive queue refuse the line (`rx-overflow`, which wins over the
//!   other reasons, since the lost bytes may have been anything);
//! - a line of nothing but spaces is blank: no reply;
//! - stream frames (`control::stream` docs) are not lines and get no reply: `A5 5A` at a line
//!   start, or in a line refused for a byte outside ASCII (which is then dropped without a
//!   reply), begins a 16-byte binary frame, whole if it ends `0D 0A`, else damaged, and then
//!   decoding goes on from the next `A5 5A` (or a last lone `A5`) among its bytes; an `A5` not
//!   followed by `5A` is a byte outside ASCII; a binary frame whose bytes stop for two servo
//!   frames is dropped; an `X` ends the line as a text frame (whole or damaged) when the line
//!   began with a digit or has kept no character yet, when the byte before it was a digit, or
//!   when the line is refused; elsewhere it is a character like any other.

/// The longest line kept, in characters (documented: 128).
pub const MAX_LINE: usize = 128;

/// Why the model expects a line to be refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// More than [`MAX_LINE`] characters.
    TooLong,
    /// A byte outside printable ASCII.
    BadCharacter,
    /// The receive queue lost bytes.
    RxOverflow,
}

impl Refusal {
    /// The documented error code.
    pub fn code(self) -> &'static str {
        match self {
            Refusal::TooLong => "line-too-long",
            Refusal::BadCharacter => "bad-character",
            Refusal::RxOverflow => "rx-overflow",
        }
    }
}

/// What a byte completed, if anything.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LineEnd {
    /// No line ended here.
    None,
    /// A blank line ended (no reply).
    Blank,
    /// A line ended; it gets exactly one final reply. The text as kept.
    Line(String),
    /// A refused line ended; it gets exactly one `error:` reply with this reason.
    Refused(Refusal),
    /// A stream frame ended (whole or damaged): no reply.
    Frame,
}

impl LineEnd {
    /// True if exactly one final reply is due.
    pub fn wants_reply(&self) -> bool {
        matches!(self, LineEnd::Line(_) | LineEnd::Refused(_))
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Esc {
    Off,
    /// Just after ESC.
    Start,
    /// Inside ESC [ ...
    Csi,
    /// After ESC O.
    Ss3,
}

/// The model's state.
#[derive(Debug, Clone)]
pub struct LineModel {
    text: Vec<u8>,
    too_long: bool,
    bad_character: bool,
    lost: bool,
    previous_was_cr: bool,
    esc: Esc,
    /// The first character kept since the line began (erasing does not forget it).
    first: Option<u8>,
    /// The byte before was a digit (read as part of a line).
    previous_was_digit: bool,
    /// The binary frame in progress (from its `A5`), if any.
    frame: Option<Vec<u8>>,
    /// Servo frames so far, and when the frame in progress last got a byte.
    ticks: u64,
    frame_byte_tick: u64,
}

impl Default for LineModel {
    fn default() -> Self {
        Self::new()
    }
}

impl LineModel {
    /// Nothing received yet.
    pub fn new() -> Self {
        LineModel {
            text: Vec::new(),
            too_long: false,
            bad_character: false,
            lost: false,
            previous_was_cr: false,
            esc: Esc::Off,
            first: None,
            previous_was_digit: false,
            frame: None,
            ticks: 0,
            frame_byte_tick: 0,
        }
    }

    /// A servo frame passed.
    pub fn tick(&mut self) {
        self.ticks += 1;
    }

    /// The characters kept so far on the current line.
    pub fn pending(&self) -> &[u8] {
        &self.text
    }

    /// The receive queue lost bytes here.
    pub fn lost(&mut self) {
        self.lost = true;
        self.previous_was_digit = false;
    }

    /// One received byte.
    pub fn byte(&mut self, b: u8) -> LineEnd {
        if self.frame.is_some() && self.ticks - self.frame_byte_tick >= 2 {
            self.frame = None; // its bytes stopped coming: dropped
        }
        self.frame_byte_tick = self.ticks;
        let at_line_start = self.text.is_empty() && !self.refused() && self.esc == Esc::Off;
        let in_garbage = self.bad_character && !self.too_long && !self.lost;
        if self.frame.is_some() || (b == 0xA5 && (at_line_start || in_garbage)) {
            return self.frame_byte(b);
        }
        self.line_byte(b)
    }

    fn frame_byte(&mut self, b: u8) -> LineEnd {
        self.previous_was_cr = false;
        self.previous_was_digit = false;
        let mut bytes = self.frame.take().unwrap_or_default();
        if bytes.len() == 1 && b != 0x5A {
            // A stray A5: a byte outside ASCII in the line; this byte is read afresh.
            if !self.refused() {
                self.bad_character = true;
            }
            return self.byte(b);
        }
        bytes.push(b);
        if bytes.len() == 2 && self.refused() {
            // A header after garbage: the garbage line is dropped without a reply (counted
            // as a damaged frame).
            self.reset();
            self.frame = Some(bytes);
            return LineEnd::Frame;
        }
        if bytes.len() < 16 {
            self.frame = Some(bytes);
            return LineEnd::None;
        }
        if bytes[14..] == [0x0D, 0x0A] {
            // A whole frame is a sync point: an escape sequence begun before it is over (ESC,
            // garbage, a frame, then another frame at a line start). A damaged one is not.
            self.esc = Esc::Off;
        } else {
            // Damaged: go on from the next A5 5A, or a last lone A5, among its bytes.
            let next = (1..16).find(|&i| bytes[i] == 0xA5 && (i == 15 || bytes[i + 1] == 0x5A));
            if let Some(i) = next {
                self.frame = Some(bytes[i..].to_vec());
            }
        }
        LineEnd::Frame
    }

    fn line_byte(&mut self, b: u8) -> LineEnd {
        let began_as_command = self.first.is_some_and(|c| !c.is_ascii_digit());
        if b == b'X' && (self.refused() || !began_as_command || self.previous_was_digit) {
            // A text frame ends here (whole or damaged: the model does not tell them apart).
            self.reset();
            self.esc = Esc::Off;
            self.previous_was_cr = false;
            self.previous_was_digit = false;
            return LineEnd::Frame;
        }
        self.previous_was_digit = b.is_ascii_digit();
        let previous_was_cr = self.previous_was_cr;
        self.previous_was_cr = b == b'\r';
        match (self.esc, b) {
            (Esc::Start, b'[') => {
                self.esc = Esc::Csi;
                return LineEnd::None;
            }
            (Esc::Start, b'O') => {
                self.esc = Esc::Ss3;
                return LineEnd::None;
            }
            (Esc::Csi, 0x20..=0x3F) => return LineEnd::None,
            (Esc::Csi, 0x40..=0x7E) | (Esc::Ss3, 0x20..=0x7E) => {
                self.esc = Esc::Off;
                return LineEnd::None;
            }
            // Off, a lone ESC before any other byte, or a control byte ending a sequence: the
            // byte counts on its own (an ESC below starts anew).
            _ => self.esc = Esc::Off,
        }
        match b {
            b'\n' if previous_was_cr => LineEnd::None,
            b'\r' | b'\n' => self.end(),
            0x08 | 0x7F => {
                if !self.refused() {
                    self.text.pop();
                }
                LineEnd::None
            }
            0x15 => {
                if !self.refused() {
                    self.text.clear();
                }
                LineEnd::None
            }
            0x03 | 0x18 => {
                self.reset();
                LineEnd::None
            }
            0x1B => {
                self.esc = Esc::Start;
                LineEnd::None
            }
            b'\t' => self.add(b' '),
            0x20..=0x7E => self.add(b),
            0x80..=0xFF => {
                if !self.refused() {
                    self.bad_character = true;
                }
                LineEnd::None
            }
            _ => LineEnd::None,
        }
    }

    fn refused(&self) -> bool {
        self.too_long || self.bad_character || self.lost
    }

    fn add(&mut self, b: u8) -> LineEnd {
        if self.refused() {
            return LineEnd::None;
        }
        self.first.get_or_insert(b);
        if self.text.len() == MAX_LINE {
            self.too_long = true;
        } else {
            self.text.push(b);
        }
        LineEnd::None
    }

    fn reset(&mut self) {
        self.text.clear();
        self.first = None;
        self.too_long = false;
        self.bad_character = false;
        self.lost = false;
    }

    fn end(&mut self) -> LineEnd {
        // At most one of `too_long` / `bad_character` is ever set (the first one refuses the
        // line); a loss wins over both.
        let end = if self.lost {
            LineEnd::Refused(Refusal::RxOverflow)
        } else if self.too_long {
            LineEnd::Refused(Refusal::TooLong)
        } else if self.bad_character {
            LineEnd::Refused(Refusal::BadCharacter)
        } else if self.text.iter().all(|&c| c == b' ') {
            LineEnd::Blank
        } else {
            LineEnd::Line(String::from_utf8(self.text.clone()).expect("printable ASCII"))
        };
        self.reset();
        end
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ends(bytes: &[u8]) -> Vec<LineEnd> {
        let mut m = LineModel::new();
        bytes
            .iter()
            .map(|&b| m.byte(b))
            .filter(|e| *e != LineEnd::None)
            .collect()
    }

    #[test]
    fn the_model_follows_the_documented_examples() {
        let line = |s: &str| LineEnd::Line(s.into());
        assert_eq!(
            ends(b"a\r\nb\rc\n\n"),
            [line("a"), line("b"), line("c"), LineEnd::Blank]
        );
        assert_eq!(ends(b"hoxx\x08\x7fme\r"), [line("home")]);
        assert_eq!(ends(b"junk\x15stop\n"), [line("stop")]);
        assert_eq!(ends(b"pose\x03\n"), [LineEnd::Blank]);
        assert_eq!(ends(b"ho\x1b[Ame\x1bOP\x1b[3~\x1b[1;5C\n"), [line("home")]);
        assert_eq!(ends(b"\x1bhome\x1b\x1b\n"), [line("home")]);
        assert_eq!(ends(b"st\x18atus\n"), [line("atus")]);
        assert_eq!(ends(b"\x1b\r"), [LineEnd::Blank]);
        let long = [b'x'; 129];
        assert_eq!(ends(&long), []);
        assert_eq!(
            ends(&[&long[..], b"\n"].concat()),
            [LineEnd::Refused(Refusal::TooLong)]
        );
        assert_eq!(
            ends("5\u{b0}\n".as_bytes()),
            [LineEnd::Refused(Refusal::BadCharacter)]
        );
    }

    #[test]
    fn the_model_follows_the_documented_stream_frames() {
        let line = |s: &str| LineEnd::Line(s.into());
        let mut frame = vec![0xA5, 0x5A];
        frame.extend_from_slice(&[0x0D, 0x0A, 0xA5, 0x5A, 1, 2, 3, 4, 5, 6, 7, 8]);
        frame.extend_from_slice(b"\r\n");
        let input = [b"home\n".as_slice(), &frame, b"1,2,3,4,5,6X?\n"].concat();
        assert_eq!(
            ends(&input),
            [line("home"), LineEnd::Frame, LineEnd::Frame, line("?")]
        );
        // A stray A5 is a bad character; garbage before a header is dropped silently.
        assert_eq!(
            ends(b"\xA5home\n"),
            [LineEnd::Refused(Refusal::BadCharacter)]
        );
        let garbage = [b"\x80\x81".as_slice(), &frame].concat();
        assert_eq!(ends(&garbage), [LineEnd::Frame, LineEnd::Frame]);
        // An X ends whatever a digit began (a damaged frame), and a command line right after a
        // digit; elsewhere in a command line it is a character.
        assert_eq!(ends(b"0a X\n"), [LineEnd::Frame, LineEnd::Blank]);
        assert_eq!(ends(b"MOVE X=1\n"), [line("MOVE X=1")]);
        assert_eq!(ends(b"move z=1X\n"), [LineEnd::Frame, LineEnd::Blank]);
        assert_eq!(ends(b"a\x08X\n"), [line("X")]);
    }
}
