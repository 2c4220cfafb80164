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
//!   anything. Frames are not lines: no echo, no reply; garbage and damaged frames are
//!   reported as such, to count. A binary frame whose bytes stop coming for more than a whole
//!   servo frame (a stream cut mid-frame) is dropped as damaged, so what comes next (a command
//!   typed after a stream software crashed) is read as it was meant ([`LineBuffer::feed_at`]).
//! - Text frames (a SimTools stream never sends a line end): a line that begins with a digit
//!   is not echoed as it comes (only whole, if a line end shows it is a line: refused as a
//!   command). An `X` ends the line in progress as a text frame when the line began with a
//!   digit (or with no character kept yet), right after a digit, or in a spoiled line; in a
//!   command line otherwise it is a character (`MOVE X=1`). The frame is applied only if every
//!   byte since the last sync point (the `X` that ended the line before, a line end) was a
//!   digit or comma, six counts, and what came before that sync point cannot have been the
//!   start of the frame's first count cut there (see `judge_trust`); anything else
//!   ending at an `X` is a damaged frame. So any byte, in any place, costs its frame and no
//!   more, and a stream picks up again at the next whole frame; a stray `X` in a count (a
//!   bit flip of `8`) may cost one frame more. A digit lost or changed, or an `X` cutting the
//!   last count short, still makes well-formed counts: no format can tell.
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

/// What the line in progress began as (its first kept character).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// Nothing kept yet.
    Start,
    /// A digit first: a text frame (an `X` ends it), or a line refused at its line end.
    Frame,
    /// Another printable character first: a command line.
    Command,
}

/// Assembles bytes into lines.
#[derive(Debug, Clone)]
pub struct LineBuffer {
    buf: Vec<u8, MAX_LINE>,
    spoiled: Option<Spoiled>,
    after_cr: bool,
    escape: Escape,
    kind: Kind,
    /// Every byte since the last sync point (an `X` that ended a line, a line end) was a digit
    /// or a comma: an `X` now ends a text frame that may be applied.
    pure: bool,
    /// Commas since the last sync point (at most 255 counted).
    commas: u8,
    /// The next text frame may be applied: what came before its sync point cannot have been
    /// the start of a frame cut there (its first count; see [`LineBuffer::sync`]).
    trusted: bool,
    /// The last sync point was an `X` (not a line end), or there was none yet: the first bytes
    /// may be the middle of a frame (a stream already running at power-up), as after an `X`.
    after_x: bool,
    /// The last byte was a digit.
    after_digit: bool,
    /// A byte outside printable ASCII (a line abandoned with Ctrl-C or Ctrl-X among them), or
    /// an `X`, came since the last sync point: the line is not a plain one (see
    /// [`LineBuffer::judge_trust`]).
    unusual: bool,
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
            kind: Kind::Start,
            pure: true,
            commas: 0,
            trusted: true,
            after_x: true,
            after_digit: false,
            unusual: false,
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
        self.kind = Kind::Start;
    }

    /// True while the line in progress began with a digit (it may be a text frame): its
    /// characters are not echoed as they come.
    pub fn holds_echo(&self) -> bool {
        self.kind == Kind::Frame
    }

    /// Records that bytes were lost on the way in: the current line is spoiled.
    pub fn rx_overflow(&mut self, lost: Lost) {
        self.pure = false;
        self.after_digit = false;
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
    #[inline]
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
    #[inline]
    pub fn feed(&mut self, byte: u8) -> Feed {
        if self.is_plain(byte) {
            self.add_plain(byte)
        } else {
            self.feed_any(byte)
        }
    }

    /// Feeds one byte the whole way (any byte; [`LineBuffer::feed`] takes plain ones short).
    /// Not inlined there: its register saves would slow the short way down.
    #[inline(never)]
    fn feed_any(&mut self, byte: u8) -> Feed {
        let frame_starts = byte == stream::BINARY_HEADER[0]
            && (self.at_line_start() || matches!(self.spoiled, Some(Spoiled::BadByte(_))));
        if !self.frame.is_empty() || frame_starts {
            self.pure = false;
            self.after_digit = false;
            return self.feed_frame(byte);
        }
        if byte == stream::TEXT_FRAME_END && self.x_ends_line() {
            return self.end_text_frame();
        }
        self.after_digit = byte.is_ascii_digit();
        if byte == b',' {
            self.commas = self.commas.saturating_add(1);
        } else if !byte.is_ascii_digit() && byte != b'\r' && byte != b'\n' {
            // (A line end is a sync point itself; the LF of a CRLF is swallowed.)
            self.pure = false;
        }
        let line_end = byte == b'\r' || byte == b'\n';
        if (!(0x20..=0x7E).contains(&byte) && !line_end) || byte == stream::TEXT_FRAME_END {
            self.unusual = true;
        }
        self.feed_line(byte)
    }

    /// Whether `byte` is a plain character of a command line: the line began as a command, is
    /// not spoiled, no escape sequence or binary frame is in progress, the byte is printable
    /// ASCII other than `X` and there is room for it. What such a byte does is
    /// [`LineBuffer::add_plain`]; every other byte takes the whole way through
    /// [`LineBuffer::feed`].
    #[inline]
    fn is_plain(&self, byte: u8) -> bool {
        (0x20..=0x7E).contains(&byte)
            && byte != stream::TEXT_FRAME_END
            && self.kind == Kind::Command
            && self.spoiled.is_none()
            && self.escape == Escape::None
            && self.frame.is_empty()
            && !self.buf.is_full()
    }

    /// A plain byte ([`LineBuffer::is_plain`]): what the whole way through [`LineBuffer::feed`],
    /// [`LineBuffer::feed_line`] and [`LineBuffer::add`] does with it, in short (most of the
    /// bytes of every command line; the short way is a fifth of the cycles).
    #[inline]
    fn add_plain(&mut self, byte: u8) -> Feed {
        self.after_digit = byte.is_ascii_digit();
        if byte == b',' {
            self.commas = self.commas.saturating_add(1);
        } else if !self.after_digit {
            self.pure = false;
        }
        self.after_cr = false;
        match self.buf.push(byte) {
            Ok(()) => Feed::Added(byte),
            // Not full (checked): never here.
            Err(_) => {
                self.spoiled = Some(Spoiled::TooLong);
                Feed::Overflowed
            }
        }
    }

    /// Takes the plain bytes ([`LineBuffer::is_plain`]) at the start of `bytes` at once, as
    /// many as come before the first byte that is not plain (or the line is full): the run a
    /// line's characters arrive in; with the line's first character, if it begins a command
    /// line (printable, not a digit, not `X`). Returns how many it took; each did what
    /// [`LineBuffer::feed`] does with it ([`Feed::Added`]), and the rest are to be fed one by
    /// one. (A plain byte never ends a line or a frame, and no binary frame is in progress, so
    /// no time needs passing: [`LineBuffer::feed_at`] would do the same.) The short way's
    /// short way: a few cycles a byte, where feeding each costs a call and a [`Feed`].
    #[inline]
    pub fn take_plain(&mut self, bytes: &[u8]) -> usize {
        // A line's first character too, when it begins a command line (not a digit, which may
        // begin a text frame): that is all it does besides being added.
        let starts_line = self.kind == Kind::Start
            && bytes
                .first()
                .is_some_and(|&b| !stream::starts_text_frame(b));
        if !(self.may_take_plain() && (self.kind == Kind::Command || starts_line)) {
            return 0;
        }
        let room = MAX_LINE - self.buf.len();
        let bytes = &bytes[..bytes.len().min(room)];
        let (run, commas) = plain_run(bytes);
        let taken = &bytes[..run];
        let Some(&last) = taken.last() else {
            return 0;
        };
        // What `add_plain` does with each byte, for the run: commas add up (saturating, as one
        // by one); a byte other than a digit or a comma makes the stretch since the sync point
        // impure (looked for only while it is pure: a command line is not, from its first
        // letter on); the last byte says whether the next comes after a digit.
        if self.pure && taken.iter().any(|&b| b != b',' && !b.is_ascii_digit()) {
            self.pure = false;
        }
        self.commas = self
            .commas
            .saturating_add(u8::try_from(commas).unwrap_or(u8::MAX));
        self.after_digit = last.is_ascii_digit();
        self.after_cr = false;
        if starts_line {
            self.kind = Kind::Command;
        }
        // Fits: at most `room` bytes.
        let _ = self.buf.extend_from_slice(taken);
        run
    }

    /// Whether [`LineBuffer::take_plain`] may take anything now (a few comparisons, for a caller
    /// to skip the rest when it cannot: in a stream frame, in an escape sequence, in a spoiled
    /// line or one that began with a digit).
    #[inline]
    pub fn may_take_plain(&self) -> bool {
        self.frame.is_empty()
            && self.kind != Kind::Frame
            && self.spoiled.is_none()
            && self.escape == Escape::None
    }

    /// Whether an `X` now ends the line as a text frame: unless the line is a command line
    /// (it began with a printable character other than a digit), not spoiled, and the `X` does
    /// not follow a digit (`MOVE X=1` stays a command).
    fn x_ends_line(&self) -> bool {
        self.kind != Kind::Command || self.spoiled.is_some() || self.after_digit
    }

    /// An `X` ended the line: a text frame if everything since the last sync point was six
    /// counts and the frame is trusted; otherwise a damaged frame (dropped without a reply).
    fn end_text_frame(&mut self) -> Feed {
        let whole = self.pure && self.trusted && self.spoiled.is_none();
        let frame = whole
            .then(|| core::str::from_utf8(&self.buf).ok())
            .flatten()
            .and_then(stream::parse_text_frame);
        self.judge_trust(false);
        self.sync();
        self.after_x = true;
        self.clear();
        frame.map_or(Feed::DamagedFrame, |counts| {
            Feed::Frame(Frame::Text(counts))
        })
    }

    /// At a sync point: whether the text frame after it may be applied. Not if what came since
    /// the last sync point may have been the start of a frame's first count, cut here (by a
    /// stray `X` or line end): the rest of that frame would then look like six counts. That
    /// is a stretch without a comma that was not plain digits after a line end (a frame's
    /// last count, cut from the rest by a line end, is), unless it was a plain command line or
    /// an empty one. A comma since the last sync point trusts what follows again: the rest of
    /// a frame cut after one of its commas has fewer than six counts. But not a whole frame's
    /// commas (five or more) before a line end: the frame's `X` may have been lost and the
    /// line end have cut the next frame's first count (`...,0,07` LF `000,...X`): what follows
    /// is not applied up to the next `X`, which ends a frame, so the frame after it is.
    fn judge_trust(&mut self, at_line_end: bool) {
        let plain_line = match self.kind {
            // An empty line, unless a line was abandoned (Ctrl-C, Ctrl-X) or garbage came since
            // the sync point: `8`, Ctrl-X, LF before `000,...X` may be a frame's first count
            // cut by the garbage, as in a line `8` ended by the LF.
            Kind::Start => self.spoiled.is_none() && !self.unusual,
            Kind::Command => !self.unusual,
            Kind::Frame => false,
        };
        // An `X` ending digits and commas that came after a line end: that `X` ends a frame
        // (cut by the line end, or whole), so a frame begins after it.
        let x_after_line_end = !at_line_end && !self.after_x && self.pure && self.spoiled.is_none();
        if x_after_line_end {
            self.trusted = true;
        } else if at_line_end && usize::from(self.commas) >= stream::COUNTS - 1 {
            if !plain_line {
                self.trusted = false;
            }
        } else if self.commas > 0 {
            self.trusted = true;
        } else if (!self.pure || self.after_x) && !plain_line {
            self.trusted = false;
        }
    }

    /// A sync point (an `X` that ended a line, a line end): a text frame may begin.
    fn sync(&mut self) {
        self.pure = true;
        self.commas = 0;
        self.after_digit = false;
        self.unusual = false;
        self.after_cr = false;
        self.escape = Escape::None;
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
            BinaryFeed::Frame(counts) => {
                self.sync();
                self.after_x = false;
                Feed::Frame(Frame::Binary(counts))
            }
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
        if self.kind == Kind::Start {
            self.kind = if stream::starts_text_frame(byte) {
                Kind::Frame
            } else {
                Kind::Command
            };
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
        self.judge_trust(true);
        let after_cr = self.after_cr;
        self.sync();
        self.after_cr = after_cr;
        self.after_x = false;
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

/// Whether `byte` may be a plain character of a command line ([`LineBuffer::take_plain`]):
/// printable ASCII other than `X`. (A byte that is not can never be taken: a caller holding
/// bytes may look at the first before handing them over.)
#[inline]
pub fn is_plain_char(byte: u8) -> bool {
    byte.wrapping_sub(0x20) <= 0x7E - 0x20 && byte != stream::TEXT_FRAME_END
}

/// How many bytes at the start of `bytes` are plain characters ([`is_plain_char`]), and how
/// many of those are commas. A loop of its own, so that it runs in registers.
#[inline(never)]
fn plain_run(bytes: &[u8]) -> (usize, usize) {
    let mut commas = 0;
    for (at, &byte) in bytes.iter().enumerate() {
        if !is_plain_char(byte) {
            return (at, commas);
        }
        commas += usize::from(byte == b',');
    }
    (bytes.len(), commas)
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
        assert_eq!(inputs(b"MOVE X=1\n"), ["line MOVE X=1"]);
        // A line that began with a digit is ended by any `X`: a damaged frame, no reply (it
        // was a command line up to a line end before; a stream never sends one).
        assert_eq!(inputs(b"0a0 X1\n"), ["damaged", "line 1"]);
        // So is a command line by an `X` right after a digit.
        assert_eq!(inputs(b"move z=1X\n"), ["damaged", "empty"]);
    }

    /// A SimTools text frame for these counts.
    fn text(counts: &[u32; 6]) -> std::vec::Vec<u8> {
        let fields: std::vec::Vec<std::string::String> = counts
            .iter()
            .map(std::string::ToString::to_string)
            .collect();
        std::format!("{}X", fields.join(",")).into_bytes()
    }

    /// Feeds a byte stream; returns the text frames applied, in order.
    fn applied(input: &[u8]) -> std::vec::Vec<[u32; 6]> {
        let mut lb = LineBuffer::new();
        let mut out = std::vec::Vec::new();
        for &b in input {
            match lb.feed(b) {
                Feed::Line => lb.clear(),
                Feed::Frame(Frame::Text(c)) => out.push(c),
                _ => {}
            }
        }
        out
    }

    /// Whether `got` is `sent` in order with some left out, all of `must` (indices) kept.
    fn kept_in_order(
        sent: &[[u32; 6]],
        got: &[[u32; 6]],
        must: &[bool],
    ) -> Result<(), std::string::String> {
        let mut next = 0;
        for (i, frame) in sent.iter().enumerate() {
            if got.get(next) == Some(frame) {
                next += 1;
            } else if must[i] {
                return Err(std::format!("frame {i} {frame:?} was not applied: {got:?}"));
            }
        }
        if next == got.len() {
            Ok(())
        } else {
            Err(std::format!(
                "{:?} was applied though no frame sent was that",
                got[next]
            ))
        }
    }

    /// Six counts, distinct between frames by the first (whatever its digits).
    fn counts(i: usize, rest: [u32; 6]) -> [u32; 6] {
        let mut c = rest;
        c[0] = i as u32 * 1000 + rest[0] % 1000;
        c
    }

    #[test]
    fn a_count_cut_by_an_abandoned_line_does_not_make_a_frame() {
        // `8000,...X` with Ctrl-X and LF after its first digit (line noise): what follows the LF
        // looks like six counts (`000,5603,...`) but is the rest of a cut frame: dropped, as
        // after a line `8` ended by the LF alone. The next whole frame is applied.
        for noise in [b"\x18\n".as_slice(), b"\x03\n", b"\n", b"\x01\n"] {
            let input = [
                b"1,2,3,4,5,6X8".as_slice(),
                noise,
                b"000,5603,6,61971,579,0X1,2,3,4,5,7X",
            ]
            .concat();
            assert_eq!(
                applied(&input),
                [[1, 2, 3, 4, 5, 6], [1, 2, 3, 4, 5, 7]],
                "{noise:?}"
            );
        }
    }

    #[test]
    fn a_count_cut_by_a_line_end_after_a_frame_that_lost_its_x_does_not_make_a_frame() {
        // `6000,0,0,0,0,0X` lost its `X`, then a LF fell after the next frame's first digit:
        // the line ends `...,0,07`, and `000,7178,...X` after it is the rest of a cut frame.
        let input = b"1,2,3,4,5,6X6000,0,0,0,0,07\n000,7178,88,4810,65,61X1,2,3,4,5,7X";
        assert_eq!(applied(input), [[1, 2, 3, 4, 5, 6], [1, 2, 3, 4, 5, 7]]);
        // A frame cut after one of its commas by a line end still lets the next one through.
        let input = b"1,2,3,4,5,6X6000,0,\n0,0,0,0X1,2,3,4,5,7X";
        assert_eq!(applied(input), [[1, 2, 3, 4, 5, 6], [1, 2, 3, 4, 5, 7]]);
    }

    #[test]
    fn a_first_count_cut_by_a_line_end_at_the_streams_start_does_not_make_a_frame() {
        // The first frame the board hears, `802,83,...X`, cut after `80` by a line end.
        assert_eq!(
            applied(b"80\n2,83,8,99,505,53X1,2,3,4,5,6X"),
            [[1, 2, 3, 4, 5, 6]]
        );
    }

    #[test]
    fn one_stray_byte_anywhere_costs_only_its_frame() {
        let sent: std::vec::Vec<[u32; 6]> = (0..5)
            .map(|i| counts(i + 1, [127 + i as u32, 0, 255, 9, 12, 130]))
            .collect();
        let frames: std::vec::Vec<std::vec::Vec<u8>> = sent.iter().map(text).collect();
        let damaged = 2;
        // Every byte value but digits and `X` (a stray digit makes a wrong count, well-formed,
        // that no format can tell; so does an `X` in the last count, cutting it short: see
        // below), before each byte of frame 2 (its X included).
        for byte in (0..=255u8).filter(|&b| !b.is_ascii_digit() && b != b'X') {
            for at in 0..frames[damaged].len() {
                let mut input = std::vec::Vec::new();
                for (i, frame) in frames.iter().enumerate() {
                    if i == damaged {
                        input.extend_from_slice(&frame[..at]);
                        input.push(byte);
                        input.extend_from_slice(&frame[at..]);
                    } else {
                        input.extend_from_slice(frame);
                    }
                }
                let got = applied(&input);
                let must = [true, true, false, true, true];
                if let Err(e) = kept_in_order(&sent, &got, &must) {
                    panic!("byte {byte:#04x} before byte {at} of frame 2: {e}");
                }
                // Frame 2 itself only if the byte came before it, not inside it.
                assert!(
                    at == 0 || !got.contains(&sent[damaged]),
                    "{byte:#04x} at {at}"
                );
            }
        }
    }

    #[test]
    fn a_lost_comma_or_x_costs_its_frame_and_a_lost_digit_no_more() {
        let sent: std::vec::Vec<[u32; 6]> = (0..4)
            .map(|i| counts(i + 1, [0, 11, 22, 33, 44, 55]))
            .collect();
        let frames: std::vec::Vec<std::vec::Vec<u8>> = sent.iter().map(text).collect();
        for at in 0..frames[1].len() {
            let mut input = frames[0].clone();
            let mut cut = frames[1].clone();
            let lost = cut.remove(at);
            input.extend(cut);
            input.extend(frames[2].clone());
            input.extend(frames[3].clone());
            let got = applied(&input);
            match lost {
                // Frames 1 and 2 run together: both lost, 3 applied.
                b'X' => assert_eq!(got, [sent[0], sent[3]]),
                b',' => assert_eq!(got, [sent[0], sent[2], sent[3]]),
                // A wrong count, but the stream stays in step.
                _ => {
                    assert_eq!(got.len(), 4, "{got:?}");
                    assert_eq!([got[0], got[2], got[3]], [sent[0], sent[2], sent[3]]);
                }
            }
        }
    }

    #[test]
    fn a_stray_x_cuts_a_frame_in_two() {
        // In the last count: the first part is six counts, a wrong frame no format can tell
        // (like a lost digit; see the stream guard); the rest is dropped, and so is the frame
        // after it (those digits could as well have been a frame's first count, cut short).
        assert_eq!(
            applied(b"1,2,3,4,5,6X1,2,3,4,5,1X38X1,2,3,4,5,7X1,2,3,4,5,8X"),
            [[1, 2, 3, 4, 5, 6], [1, 2, 3, 4, 5, 1], [1, 2, 3, 4, 5, 8]]
        );
        // Elsewhere: both parts dropped, the next frame applied.
        assert_eq!(
            applied(b"1,2,3,4,5,6X1,2,3X,4,5,6X1,2,3,4,5,7X"),
            [[1, 2, 3, 4, 5, 6], [1, 2, 3, 4, 5, 7]]
        );
    }

    #[test]
    fn a_frame_cut_in_its_first_count_never_leaves_six_counts_applied() {
        // `X`, CR or LF inside the first count: what follows has six counts but is the rest of
        // a frame; it is dropped, and the next frame is applied.
        for cut in [b"X", b"\r", b"\n"] {
            let mut input = b"180,1,2,3,4,5X1".to_vec();
            input.extend_from_slice(cut);
            input.extend_from_slice(b"80,1,2,3,4,5X181,1,2,3,4,5X");
            assert_eq!(
                applied(&input),
                [[180, 1, 2, 3, 4, 5], [181, 1, 2, 3, 4, 5]],
                "{cut:?}"
            );
        }
        // Through a line that garbage started (a letter) and a stray `X` before it ended.
        assert_eq!(
            applied(b"179,1,2,3,4,5X180,1,2,3,4,5\rqX1\r81,1,2,3,4,5X182,1,2,3,4,5X"),
            [[179, 1, 2, 3, 4, 5], [182, 1, 2, 3, 4, 5]]
        );
    }

    #[test]
    fn a_text_stream_recovers_from_anything_a_byte_outside_ascii_included() {
        // One byte of 0x80 or above used to spoil the stream for good (no line end ever came).
        let mut input = b"1,2,3,4,5,6X".to_vec();
        input.extend_from_slice(b"7,\xC2,9,10,11,12X");
        for i in 0..50u32 {
            input.extend(text(&[i, 1, 2, 3, 4, 5]));
        }
        let got = applied(&input);
        assert_eq!(got.len(), 51, "{got:?}");
        assert_eq!(got[1], [0, 1, 2, 3, 4, 5]);
        // The same with the other kinds of garbage: control characters, NUL, a too-long line.
        for garbage in [
            &b"\x00"[..],
            b"\x03",
            b"\x1b[",
            b"\x08\x08",
            b"\x15",
            &[b'a'; 200],
        ] {
            let mut input = b"1,2,3,4,5,6X7,".to_vec();
            input.extend_from_slice(garbage);
            input.extend_from_slice(b"8,9,10,11,12X13,14,15,16,17,18X");
            assert_eq!(
                applied(&input),
                [[1, 2, 3, 4, 5, 6], [13, 14, 15, 16, 17, 18]],
                "{garbage:?}"
            );
        }
    }

    /// Garbage for the property test: any byte but digits, commas and `X` (those can make
    /// wrong but well-formed counts), and never the binary frame's header (a frame would
    /// begin).
    fn garbage(bytes: std::vec::Vec<u8>) -> std::vec::Vec<u8> {
        let mut out: std::vec::Vec<u8> = bytes
            .into_iter()
            .map(|b| {
                if b.is_ascii_digit() || b == b',' || b == b'X' {
                    b'#'
                } else {
                    b
                }
            })
            .collect();
        for i in 1..out.len() {
            if out[i - 1] == 0xA5 && out[i] == 0x5A {
                out[i] = 0;
            }
        }
        out
    }

    proptest::proptest! {
        /// The short way of a plain byte ([`LineBuffer::add_plain`]) does what the whole way
        /// does: the same feeds and the same state after every byte, for any bytes (lines,
        /// frames, escapes, garbage, long lines), mostly printable.
        #[test]
        fn plain_bytes_taken_short_do_what_the_whole_way_does(
            bytes in proptest::collection::vec(
                proptest::prop_oneof![
                    6 => 0x20u8..=0x7E,
                    1 => proptest::sample::select(std::vec![
                        b'X', b'\r', b'\n', 0x1B, b'[', 0x08, 0x15, 0x03, 0xA5, 0x5A, b','
                    ]),
                    1 => proptest::num::u8::ANY,
                ],
                0..400,
            ),
        ) {
            let (mut short, mut whole) = (LineBuffer::new(), LineBuffer::new());
            for &b in &bytes {
                let (a, w) = (short.feed(b), whole.feed_any(b));
                proptest::prop_assert_eq!(a, w, "byte {:#04x}", b);
                proptest::prop_assert_eq!(std::format!("{short:?}"), std::format!("{whole:?}"));
                if a == Feed::Line {
                    short.clear();
                    whole.clear();
                }
            }
        }
    }

    proptest::proptest! {
        /// A run of plain bytes taken at once ([`LineBuffer::take_plain`]) does what feeding
        /// each does: each taken byte is one [`LineBuffer::feed`] would add, the byte it stops
        /// at is one that is not plain (or the run was all it was given), and the state after
        /// the run is the same; for any bytes, handed over in runs of any length.
        #[test]
        fn plain_runs_taken_at_once_do_what_feeding_each_byte_does(
            bytes in proptest::collection::vec(
                proptest::prop_oneof![
                    8 => 0x20u8..=0x7E,
                    1 => proptest::sample::select(std::vec![
                        b'X', b'\r', b'\n', 0x1B, b'[', 0x08, 0x15, 0x03, 0xA5, 0x5A, b','
                    ]),
                    1 => proptest::num::u8::ANY,
                ],
                0..600,
            ),
            runs in proptest::collection::vec(0usize..200, 1..20),
        ) {
            let (mut at_once, mut each) = (LineBuffer::new(), LineBuffer::new());
            let mut at = 0;
            let mut run = runs.iter().cycle();
            while at < bytes.len() {
                let end = (at + run.next().copied().unwrap_or(1)).min(bytes.len());
                let taken = at_once.take_plain(&bytes[at..end]);
                proptest::prop_assert!(taken <= end - at);
                for &b in &bytes[at..at + taken] {
                    proptest::prop_assert_eq!(each.feed(b), Feed::Added(b));
                }
                at += taken;
                if at < end {
                    proptest::prop_assert!(!each.is_plain(bytes[at]), "{:#04x} left", bytes[at]);
                }
                proptest::prop_assert_eq!(std::format!("{at_once:?}"), std::format!("{each:?}"));
                if at < bytes.len() {
                    let b = bytes[at];
                    let (a, e) = (at_once.feed(b), each.feed(b));
                    proptest::prop_assert_eq!(a, e, "byte {:#04x}", b);
                    if a == Feed::Line {
                        at_once.clear();
                        each.clear();
                    }
                    at += 1;
                }
            }
            proptest::prop_assert_eq!(std::format!("{at_once:?}"), std::format!("{each:?}"));
        }
    }

    /// A command line's characters, its first included, are taken as one run, up to what is
    /// not plain (so the property above is not a test of nothing).
    #[test]
    fn a_command_lines_characters_are_taken_as_one_run() {
        let mut lb = LineBuffer::new();
        assert_eq!(
            lb.take_plain(b"1,2,3"),
            0,
            "a digit first may begin a text frame"
        );
        assert_eq!(lb.take_plain(b"X=1"), 0);
        assert_eq!(lb.take_plain(b"\n"), 0);
        assert_eq!(lb.take_plain(b"p"), 1, "a command line's first character");
        assert_eq!(lb.take_plain(b"ose 1,2 x=3\n"), 11);
        assert_eq!(lb.line(), "pose 1,2 x=3");
        assert_eq!(lb.take_plain(b"X=1"), 0, "an X goes the whole way");
        assert_eq!(lb.feed(b'\n'), Feed::Line);
        assert_eq!(lb.line(), "pose 1,2 x=3");
        lb.clear();
        let long = [b'a'; 200];
        assert_eq!(
            lb.take_plain(&long),
            MAX_LINE,
            "no more than the line holds"
        );
        assert_eq!(lb.take_plain(&long), 0);
        assert_eq!(lb.feed(b'a'), Feed::Overflowed);
    }

    /// The short way is taken (so the property above is not a test of nothing; random input
    /// may spoil its only line at its first byte, so it cannot tell): every byte of
    /// a command line after its first, but an `X` and the line end, is plain.
    #[test]
    fn a_command_lines_bytes_after_the_first_take_the_short_way() {
        let mut lb = LineBuffer::new();
        let plain: std::vec::Vec<bool> = b"move x=1 X=2\n"
            .iter()
            .map(|&b| {
                let plain = lb.is_plain(b);
                lb.feed(b);
                plain
            })
            .collect();
        let expected: std::vec::Vec<bool> = b"move x=1 X=2\n"
            .iter()
            .enumerate()
            .map(|(i, &b)| i > 0 && b != b'X' && b != b'\n')
            .collect();
        assert_eq!(plain, expected);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(512))]
        /// A text stream with garbage inserted at random places (one burst, or one lost comma
        /// or `X`, per frame at most): no frame is applied that was not sent as it is, and
        /// every frame that came whole after a frame that came whole is applied.
        #[test]
        fn a_text_stream_with_garbage_applies_every_whole_frame_and_nothing_else(
            rest in proptest::collection::vec(proptest::array::uniform6(0u32..=65535), 2..14),
            damage in proptest::collection::vec(
                proptest::option::weighted(
                    0.4,
                    (
                        proptest::bool::weighted(0.8),
                        proptest::sample::select(std::vec![1usize, 2, 3, 5, 30]),
                        proptest::num::usize::ANY,
                        proptest::collection::vec(proptest::num::u8::ANY, 1..8),
                    ),
                ),
                14,
            ),
        ) {
            let sent: std::vec::Vec<[u32; 6]> = rest
                .iter()
                .enumerate()
                .map(|(i, r)| counts(i, r.map(|c| c >> (c % 13))))
                .collect();
            let mut input = std::vec::Vec::new();
            let mut touched = std::vec::Vec::new();
            for (frame, damage) in sent.iter().zip(&damage) {
                let mut bytes = text(frame);
                if let Some((insert, _, at, junk)) = damage {
                    if *insert {
                        let at = at % bytes.len();
                        let junk = garbage(junk.clone());
                        bytes.splice(at..at, junk);
                    } else {
                        let seps: std::vec::Vec<usize> = (0..bytes.len())
                            .filter(|&i| bytes[i] == b',' || bytes[i] == b'X')
                            .collect();
                        bytes.remove(seps[at % seps.len()]);
                    }
                }
                touched.push(damage.is_some());
                input.extend(bytes);
            }
            let must: std::vec::Vec<bool> = (0..sent.len())
                .map(|i| !touched[i] && (i == 0 || !touched[i - 1]))
                .collect();
            let got = applied(&input);
            if let Err(e) = kept_in_order(&sent, &got, &must) {
                proptest::prop_assert!(false, "{}", e);
            }
        }
    }
}
