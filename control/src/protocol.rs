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
//! - Stream frames share the link ([`crate::stream`]): at a line start, `A5` begins a binary
//!   frame (if `5A` does not follow, the `A5` was a stray byte and spoils the line like any
//!   byte outside ASCII); in a line already spoiled by such bytes (garbage), `A5 5A` begins a
//!   frame too and the garbage is dropped without a reply, so a binary stream recovers from
//!   anything; digits and commas, starting with a digit, then `X`, are a text frame. Frames are
//!   not lines: no echo, no reply; garbage and damaged frames are reported as such, to count.
//!   A binary frame whose bytes stop coming for more than a whole servo frame (a stream cut
//!   mid-frame) is dropped as damaged, so what comes next (a command typed after a stream
//!   software crashed) is read as it was meant ([`LineBuffer::feed_at`]).
//!
//! This module only classifies bytes; the controller decides what to echo and reply.

use heapless::Vec;

use crate::stream::{self, BinaryFeed, BinaryFrame, Frame};

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
    /// A whole stream frame arrived.
    Frame(Frame),
    /// Bytes that began a stream frame turned out not to be one (dropped, to be counted).
    DamagedFrame,
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
    /// A binary stream frame in progress.
    frame: BinaryFrame,
    /// The servo-frame count when the frame in progress last got a byte.
    frame_tick: u32,
    /// A frame in progress was dropped because its bytes stopped coming.
    abandoned: bool,
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
            frame: BinaryFrame::new(),
            frame_tick: 0,
            abandoned: false,
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

    /// Feeds one received byte, `tick` being the number of servo frames so far: a binary frame
    /// in progress whose last byte came two or more ticks ago (more than a whole servo frame,
    /// while a frame's 16 bytes take at most 17 ms, at 9600 baud) is dropped first
    /// ([`LineBuffer::take_abandoned`] says so) and this byte read afresh.
    pub fn feed_at(&mut self, byte: u8, tick: u32) -> Feed {
        if !self.frame.is_empty() && tick.wrapping_sub(self.frame_tick) >= 2 {
            self.frame = BinaryFrame::new();
            self.abandoned = true;
        }
        self.frame_tick = tick;
        self.feed(byte)
    }

    /// True (once) if [`LineBuffer::feed_at`] dropped a frame whose bytes stopped coming.
    pub fn take_abandoned(&mut self) -> bool {
        core::mem::take(&mut self.abandoned)
    }

    /// Feeds one received byte (no time passes: see [`LineBuffer::feed_at`]).
    pub fn feed(&mut self, byte: u8) -> Feed {
        let frame_starts = byte == stream::BINARY_HEADER[0]
            && (self.at_line_start() || matches!(self.spoiled, Some(Spoiled::BadByte(_))));
        if !self.frame.is_empty() || frame_starts {
            return self.feed_frame(byte);
        }
        self.feed_line(byte)
    }

    /// A byte of a binary frame (or of what may begin one).
    fn feed_frame(&mut self, byte: u8) -> Feed {
        self.after_cr = false;
        match self.frame.feed(byte) {
            BinaryFeed::Pending if self.frame.len() == stream::BINARY_HEADER.len() => {
                // The header is whole: a frame. A line spoiled by garbage before it is dropped
                // (it never ended, so it gets no reply).
                if self.spoiled.is_some() {
                    self.clear();
                    return Feed::DamagedFrame;
                }
                Feed::Nothing
            }
            BinaryFeed::Pending => Feed::Nothing,
            BinaryFeed::Frame(counts) => Feed::Frame(Frame::Binary(counts)),
            BinaryFeed::Damaged => Feed::DamagedFrame,
            // `A5` then not `5A`: a stray byte, not a frame: it spoils the line (if nothing
            // did already). This byte is read afresh (another `A5` may begin a frame).
            BinaryFeed::NotAFrame => {
                if self.spoiled.is_none() {
                    self.spoiled = Some(Spoiled::BadByte(stream::BINARY_HEADER[0]));
                }
                self.feed(byte)
            }
        }
    }

    /// A byte of a line.
    fn feed_line(&mut self, byte: u8) -> Feed {
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

    /// Nothing of a line has arrived yet (a stream frame may begin).
    fn at_line_start(&self) -> bool {
        self.buf.is_empty() && self.spoiled.is_none() && self.escape == Escape::None
    }

    fn add(&mut self, byte: u8) -> Feed {
        if self.spoiled.is_some() {
            return Feed::Nothing;
        }
        if byte == stream::TEXT_FRAME_END && stream::is_text_frame_so_far(&self.buf) {
            // A line that began with a digit and ends with `X`: a text frame, whole or damaged.
            let frame = core::str::from_utf8(&self.buf)
                .ok()
                .and_then(stream::parse_text_frame);
            self.buf.clear();
            return frame.map_or(Feed::DamagedFrame, |counts| {
                Feed::Frame(Frame::Text(counts))
            });
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

    /// Feeds bytes; returns the frames, damaged frames and lines in order.
    fn inputs(input: &[u8]) -> std::vec::Vec<std::string::String> {
        let mut lb = LineBuffer::new();
        let mut out = std::vec::Vec::new();
        for &b in input {
            match lb.feed(b) {
                Feed::Line => {
                    out.push(std::format!("line {}", lb.line()));
                    lb.clear();
                }
                Feed::Frame(Frame::Binary(c)) => out.push(std::format!("binary {c:?}")),
                Feed::Frame(Frame::Text(c)) => out.push(std::format!("text {c:?}")),
                Feed::DamagedFrame => out.push("damaged".into()),
                Feed::Spoiled(why) => out.push(std::format!("spoiled {why:?}")),
                Feed::Empty => out.push("empty".into()),
                _ => {}
            }
        }
        out
    }

    fn binary(counts: [u16; 6]) -> std::vec::Vec<u8> {
        let mut bytes = std::vec![0xA5, 0x5A];
        for c in counts {
            bytes.extend_from_slice(&c.to_be_bytes());
        }
        bytes.extend_from_slice(b"\r\n");
        bytes
    }

    #[test]
    fn stream_frames_share_the_link_with_lines() {
        let mut input = b"status\n".to_vec();
        input.extend(binary([1, 2, 3, 4, 5, 6]));
        input.extend(binary([0x0D0A, 0x0A0D, 0xA5A5, 0x5A5A, 0, 65535]));
        input.extend_from_slice(b"home\n127,128,129,130,131,132X");
        input.extend_from_slice(b"1,2,3,4,5,6X?\n");
        assert_eq!(
            inputs(&input),
            [
                "line status",
                "binary [1, 2, 3, 4, 5, 6]",
                "binary [3338, 2573, 42405, 23130, 0, 65535]",
                "line home",
                "text [127, 128, 129, 130, 131, 132]",
                "text [1, 2, 3, 4, 5, 6]",
                "line ?",
            ]
        );
    }

    #[test]
    fn a_stray_a5_is_a_bad_byte_in_its_line() {
        // Not followed by 5A: the line it starts (or is in) is refused as before.
        assert_eq!(
            inputs(b"\xA5status\nhome\n"),
            ["spoiled BadByte(165)", "line home"]
        );
        assert_eq!(inputs(b"sta\xA5tus\n"), ["spoiled BadByte(165)"]);
        // A5 A5 5A: the first is stray, the second begins a frame.
        let mut input = b"\xA5".to_vec();
        input.extend(binary([4; 6]));
        assert_eq!(inputs(&input), ["damaged", "binary [4, 4, 4, 4, 4, 4]"]);
    }

    #[test]
    fn garbage_before_a_frame_is_dropped_without_a_reply() {
        // A binary stream that lost bytes: the rest of a frame (binary garbage, a spoiled line)
        // is dropped when the next frame's header arrives; nothing asks for a reply.
        let frame = binary([7; 6]);
        let mut input = frame[5..].to_vec();
        input.extend(binary([8; 6]));
        input.extend(binary([9; 6]));
        let got = inputs(&input);
        assert!(
            !got.iter()
                .any(|g| g.starts_with("spoiled") || g.starts_with("line")),
            "{got:?}"
        );
        assert_eq!(
            got.last().map(std::string::String::as_str),
            Some("binary [9, 9, 9, 9, 9, 9]")
        );
        assert!(got.contains(&"binary [8, 8, 8, 8, 8, 8]".into()), "{got:?}");
    }

    #[test]
    fn a_frame_whose_bytes_stop_coming_is_dropped_and_what_follows_is_read_afresh() {
        let mut lb = LineBuffer::new();
        for &b in &binary([1; 6])[..9] {
            assert_eq!(lb.feed_at(b, 100), Feed::Nothing);
        }
        // One servo frame later the frame is still expected...
        assert_eq!(lb.feed_at(0, 101), Feed::Nothing);
        assert!(!lb.take_abandoned());
        // ...then nothing for two: a typed line is a line.
        let mut last = Feed::Nothing;
        for &b in b"status\n" {
            last = lb.feed_at(b, 103);
        }
        assert!(lb.take_abandoned());
        assert!(!lb.take_abandoned(), "once");
        assert_eq!(last, Feed::Line);
        assert_eq!(lb.line(), "status");
    }

    #[test]
    fn text_frames_need_six_counts_and_lines_starting_with_digits_stay_lines() {
        assert_eq!(
            inputs(b"1,2,3X4,5,6,7,8,9X"),
            ["damaged", "text [4, 5, 6, 7, 8, 9]"]
        );
        // A line end instead of X: a command line (the controller refuses it as one).
        assert_eq!(inputs(b"123,4\n"), ["line 123,4"]);
        // X elsewhere is just a character, also after a digit when other characters came.
        assert_eq!(inputs(b"move x=1\n"), ["line move x=1"]);
        assert_eq!(inputs(b"0a0 X1\n"), ["line 0a0 X1"]);
    }
}
