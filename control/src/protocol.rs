//! Line assembly: received bytes -> complete lines, with terminal-style line editing.
//!
//! - A line ends at CR, LF or CRLF (the LF right after a CR is swallowed, so CRLF is one end).
//! - Backspace (0x08) and DEL (0x7F) erase the last character; Ctrl-U (0x15) erases the whole
//!   line; Ctrl-C (0x03) and Ctrl-X (0x18) abandon the line (no reply: it never completed).
//! - Tab counts as a space. Other control characters are ignored, and so are the escape
//!   sequences terminals send for arrow, editing and function keys, whole: CSI (ESC `[`, then
//!   parameter and intermediate bytes 0x20..=0x3F, then a final byte 0x40..=0x7E: arrows
//!   `ESC [ A`, Delete `ESC [ 3 ~`, F5 `ESC [ 1 5 ~`, Ctrl-Right `ESC [ 1 ; 5 C`, the
//!   bracketed-paste markers `ESC [ 2 0 0 ~`) and SS3 (ESC `O` and one byte: F1 `ESC O P`,
//!   arrows in application mode `ESC O A`). ESC followed by anything else is a lone ESC (the
//!   Esc key): it is ignored and the next byte counts as typed, so `ESC home` is `home`.
//!   Any byte other than printable ASCII ends a sequence and then counts on its own: a line
//!   end always ends the line.
//! - At most [`MAX_LINE`] characters are kept. A longer line is discarded up to its end and
//!   then reported once as too long. A byte outside printable ASCII, or bytes lost by the UART
//!   queue, spoil the line the same way.
//!
//! This module only classifies bytes; the controller decides what to echo and reply.

use heapless::Vec;

/// Longest line kept, in characters (excluding the line end).
pub const MAX_LINE: usize = 128;

const BACKSPACE: u8 = 0x08;
const DELETE: u8 = 0x7F;
const CTRL_C: u8 = 0x03;
const CTRL_U: u8 = 0x15;
const CTRL_X: u8 = 0x18;
const ESCAPE: u8 = 0x1B;

/// Why a line is being discarded up to its end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spoiled {
    /// More than [`MAX_LINE`] characters.
    TooLong,
    /// A byte that is not printable ASCII (first one seen).
    BadByte(u8),
    /// Bytes were lost while the line was being received.
    RxOverflow(Lost),
}

/// Bytes lost on their way in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lost {
    /// How many; exact unless `in_uart`.
    pub bytes: u32,
    /// Some were lost in the UART's hardware (a FIFO overrun, or a framing, parity or break
    /// error): `bytes` is only a lower bound, since the UART cannot tell how many it missed.
    pub in_uart: bool,
}

/// What one received byte did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feed {
    /// Nothing visible (ignored byte, swallowed LF, part of an escape sequence, or a byte of a
    /// line being discarded).
    Nothing,
    /// The character was added to the line (echo it).
    Added(u8),
    /// The last character was erased (echo backspace-space-backspace).
    Erased,
    /// This many characters were erased at once (Ctrl-U).
    ErasedLine(usize),
    /// The line was abandoned (Ctrl-C / Ctrl-X).
    Cancelled,
    /// The line just became too long; the rest of it is being discarded.
    Overflowed,
    /// A line ended with nothing but spaces in it.
    Empty,
    /// A line ended; read it with [`LineBuffer::line`], then call [`LineBuffer::clear`].
    Line,
    /// A spoiled line ended.
    Spoiled(Spoiled),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Escape {
    None,
    /// After ESC.
    Started,
    /// After ESC `[`, until the final byte.
    Csi,
    /// After ESC `O`: one more byte.
    Ss3,
}

/// Assembles bytes into lines.
#[derive(Debug, Clone)]
pub struct LineBuffer {
    buf: Vec<u8, MAX_LINE>,
    spoiled: Option<Spoiled>,
    after_cr: bool,
    escape: Escape,
}

impl Default for LineBuffer {
    fn default() -> Self {
        Self::new()
    }
}

impl LineBuffer {
    /// An empty buffer.
    pub const fn new() -> Self {
        LineBuffer {
            buf: Vec::new(),
            spoiled: None,
            after_cr: false,
            escape: Escape::None,
        }
    }

    /// The completed line (valid after [`Feed::Line`]); printable ASCII only.
    pub fn line(&self) -> &str {
        // Only printable ASCII is ever stored, so this never fails.
        core::str::from_utf8(&self.buf).unwrap_or("")
    }

    /// Characters in the line so far.
    pub fn len(&self) -> usize {
        self.buf.len()
    }

    /// True if no characters are pending.
    pub fn is_empty(&self) -> bool {
        self.buf.is_empty()
    }

    /// Forgets the current line (call after handling [`Feed::Line`]).
    pub fn clear(&mut self) {
        self.buf.clear();
        self.spoiled = None;
    }

    /// Records that bytes were lost on the way in: the current line is spoiled.
    pub fn rx_overflow(&mut self, lost: Lost) {
        self.spoiled = Some(Spoiled::RxOverflow(match self.spoiled {
            Some(Spoiled::RxOverflow(before)) => Lost {
                bytes: before.bytes.saturating_add(lost.bytes),
                in_uart: before.in_uart || lost.in_uart,
            },
            _ => lost,
        }));
    }

    /// Feeds one received byte.
    pub fn feed(&mut self, byte: u8) -> Feed {
        let after_cr = core::mem::replace(&mut self.after_cr, byte == b'\r');
        match self.escape {
            Escape::Started => match byte {
                b'[' => {
                    self.escape = Escape::Csi;
                    return Feed::Nothing;
                }
                b'O' => {
                    self.escape = Escape::Ss3;
                    return Feed::Nothing;
                }
                // ESC ESC: the first was a lone ESC, the second may start a sequence.
                ESCAPE => return Feed::Nothing,
                // A lone ESC (the Esc key): ignored, and this byte counts as typed. A line end
                // above all: Esc then Enter still ends the line.
                _ => self.escape = Escape::None,
            },
            Escape::Csi => {
                if (0x20..=0x7E).contains(&byte) {
                    if byte >= 0x40 {
                        self.escape = Escape::None; // the final byte
                    }
                    return Feed::Nothing;
                }
                // A control byte inside a sequence ends it and counts on its own.
                self.escape = Escape::None;
            }
            Escape::Ss3 => {
                self.escape = Escape::None;
                if (0x20..=0x7E).contains(&byte) {
                    return Feed::Nothing;
                }
            }
            Escape::None => {}
        }
        match byte {
            b'\n' if after_cr => Feed::Nothing,
            b'\r' | b'\n' => self.end_line(),
            BACKSPACE | DELETE => {
                if self.spoiled.is_none() && self.buf.pop().is_some() {
                    Feed::Erased
                } else {
                    Feed::Nothing
                }
            }
            CTRL_U => {
                let n = self.buf.len();
                if self.spoiled.is_none() && n > 0 {
                    self.buf.clear();
                    Feed::ErasedLine(n)
                } else {
                    Feed::Nothing
                }
            }
            CTRL_C | CTRL_X => {
                self.clear();
                Feed::Cancelled
            }
            ESCAPE => {
                self.escape = Escape::Started;
                Feed::Nothing
            }
            b'\t' => self.add(b' '),
            0x20..=0x7E => self.add(byte),
            0x80..=0xFF => {
                if self.spoiled.is_none() {
                    self.spoiled = Some(Spoiled::BadByte(byte));
                }
                Feed::Nothing
            }
            _ => Feed::Nothing, // other control characters
        }
    }

    fn add(&mut self, byte: u8) -> Feed {
        if self.spoiled.is_some() {
            return Feed::Nothing;
        }
        match self.buf.push(byte) {
            Ok(()) => Feed::Added(byte),
            Err(_) => {
                self.spoiled = Some(Spoiled::TooLong);
                Feed::Overflowed
            }
        }
    }

    fn end_line(&mut self) -> Feed {
        if let Some(why) = self.spoiled {
            self.clear();
            Feed::Spoiled(why)
        } else if self.buf.iter().all(|&b| b == b' ') {
            self.clear();
            Feed::Empty
        } else {
            Feed::Line
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Feeds bytes; returns every completed line (or its fate) in order.
    fn lines(input: &[u8]) -> std::vec::Vec<Result<std::string::String, Feed>> {
        let mut lb = LineBuffer::new();
        let mut out = std::vec::Vec::new();
        for &b in input {
            match lb.feed(b) {
                Feed::Line => {
                    out.push(Ok(lb.line().into()));
                    lb.clear();
                }
                f @ (Feed::Empty | Feed::Spoiled(_)) => out.push(Err(f)),
                _ => {}
            }
        }
        out
    }

    #[test]
    fn every_line_end_style_ends_one_line() {
        assert_eq!(
            lines(b"a\nb\r\nc\rd\n\re\r\r\n"),
            [
                Ok("a".into()),
                Ok("b".into()),
                Ok("c".into()),
                Ok("d".into()),
                Err(Feed::Empty), // the CR after "d\n" is a line of its own
                Ok("e".into()),
                Err(Feed::Empty), // "\r\r\n": the second CR ends an empty line
            ]
        );
    }

    #[test]
    fn backspace_and_delete_erase() {
        assert_eq!(lines(b"hoxx\x08\x7Fme\n"), [Ok("home".into())]);
        // Erasing past the start does nothing.
        assert_eq!(lines(b"\x08\x08ok\n"), [Ok("ok".into())]);
        let mut lb = LineBuffer::new();
        assert_eq!(lb.feed(0x08), Feed::Nothing);
        lb.feed(b'a');
        assert_eq!(lb.feed(0x7F), Feed::Erased);
    }

    #[test]
    fn ctrl_u_erases_and_ctrl_c_cancels() {
        assert_eq!(lines(b"junk\x15stop\n"), [Ok("stop".into())]);
        let mut lb = LineBuffer::new();
        for &b in b"abc" {
            lb.feed(b);
        }
        assert_eq!(lb.feed(CTRL_U), Feed::ErasedLine(3));
        lb.feed(b'x');
        assert_eq!(lb.feed(CTRL_C), Feed::Cancelled);
        assert!(lb.is_empty());
        assert_eq!(
            lines(b"pose 1\x03\nhome\n"),
            [Err(Feed::Empty), Ok("home".into())]
        );
    }

    #[test]
    fn tabs_are_spaces_and_blank_lines_are_empty() {
        assert_eq!(lines(b"a\tb\n"), [Ok("a b".into())]);
        assert_eq!(lines(b"  \t \r\n"), [Err(Feed::Empty)]);
        assert_eq!(lines(b"\x01\x02\n"), [Err(Feed::Empty)]);
    }

    #[test]
    fn escape_sequences_are_ignored_whole() {
        // Up arrow, left arrow, F1 (ESC O P), Delete key (ESC [ 3 ~).
        assert_eq!(
            lines(b"ho\x1b[A\x1b[Dme\x1bOP\x1b[3~\n"),
            [Ok("home".into())]
        );
        // What terminals send for other keys: Home/End in both modes, PgUp, F5, F12,
        // Ctrl-Right, Shift-F3, application-mode arrows, bracketed paste around a line.
        let keys: [&[u8]; 12] = [
            b"\x1b[H",
            b"\x1b[F",
            b"\x1b[1~",
            b"\x1b[4~",
            b"\x1b[5~",
            b"\x1b[15~",
            b"\x1b[24~",
            b"\x1b[1;5C",
            b"\x1b[1;2R",
            b"\x1bOA",
            b"\x1bOH",
            b"\x1b[200~",
        ];
        for key in keys {
            let mut input = b"st".to_vec();
            input.extend_from_slice(key);
            input.extend_from_slice(b"op\r");
            assert_eq!(lines(&input), [Ok("stop".into())], "{key:?}");
        }
        assert_eq!(
            lines(b"\x1b[200~pose 1 2 3 4 5 6\x1b[201~\n"),
            [Ok("pose 1 2 3 4 5 6".into())]
        );
    }

    #[test]
    fn a_lone_esc_is_ignored_and_what_follows_is_typed() {
        // The Esc key, then a command: nothing of the command is swallowed.
        assert_eq!(lines(b"\x1bhome\n"), [Ok("home".into())]);
        assert_eq!(lines(b"st\x1batus\n"), [Ok("status".into())]);
        assert_eq!(lines(b"\x1b\x1b\x1bstop\n"), [Ok("stop".into())]);
        assert_eq!(lines(b"\x1b1 \x1b?\n"), [Ok("1 ?".into())]);
        // A line end inside a sequence still ends the line.
        assert_eq!(lines(b"stop\x1b[\n"), [Ok("stop".into())]);
        // So does one right after ESC (Esc, then Enter): it is not swallowed as an Alt-key,
        // and the LF of CRLF after it stays part of the same line end.
        assert_eq!(
            lines(b"home\x1b\r\nstop\n"),
            [Ok("home".into()), Ok("stop".into())]
        );
        // A non-ASCII byte after ESC is not hidden by it either.
        assert_eq!(
            lines(b"home\x1b\x9b\n"),
            [Err(Feed::Spoiled(Spoiled::BadByte(0x9b)))]
        );
        // ESC ESC: the second starts a new sequence.
        assert_eq!(lines(b"ho\x1b\x1b[Ame\n"), [Ok("home".into())]);
        // Ctrl-X abandons the line like Ctrl-C: what follows is a new line.
        assert_eq!(lines(b"home\x18\n"), [Err(Feed::Empty)]);
        assert_eq!(lines(b"st\x18atus\n"), [Ok("atus".into())]);
    }

    #[test]
    fn too_long_line_is_reported_once_and_the_next_line_works() {
        let mut input = std::vec![b'x'; MAX_LINE];
        input.extend_from_slice(b"yyyy\x08\x08\r\nhome\r\n");
        assert_eq!(
            lines(&input),
            [Err(Feed::Spoiled(Spoiled::TooLong)), Ok("home".into())]
        );
        // Exactly MAX_LINE characters is fine.
        let mut input = std::vec![b'x'; MAX_LINE];
        input.push(b'\n');
        assert_eq!(lines(&input), [Ok("x".repeat(MAX_LINE))]);
    }

    #[test]
    fn overflow_is_signalled_once() {
        let mut lb = LineBuffer::new();
        for _ in 0..MAX_LINE {
            assert!(matches!(lb.feed(b'a'), Feed::Added(b'a')));
        }
        assert_eq!(lb.feed(b'a'), Feed::Overflowed);
        assert_eq!(lb.feed(b'a'), Feed::Nothing);
        assert_eq!(lb.feed(0x08), Feed::Nothing);
        assert_eq!(lb.feed(b'\n'), Feed::Spoiled(Spoiled::TooLong));
    }

    #[test]
    fn non_ascii_spoils_the_line() {
        assert_eq!(
            lines("pose 1 2 3 0 0 0°\nhome\n".as_bytes()),
            [
                Err(Feed::Spoiled(Spoiled::BadByte(0xC2))),
                Ok("home".into())
            ]
        );
    }

    #[test]
    fn rx_overflow_spoils_the_current_line_and_adds_up() {
        let mut lb = LineBuffer::new();
        lb.feed(b'p');
        let lost = |bytes, in_uart| Lost { bytes, in_uart };
        lb.rx_overflow(lost(3, false));
        lb.rx_overflow(lost(4, true));
        lb.feed(b'q');
        assert_eq!(
            lb.feed(b'\n'),
            Feed::Spoiled(Spoiled::RxOverflow(lost(7, true)))
        );
        lb.feed(b'?');
        assert_eq!(lb.feed(b'\n'), Feed::Line);
        assert_eq!(lb.line(), "?");
    }
}
