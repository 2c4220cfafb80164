//! One serial link's session: line assembly and editing ([`crate::protocol`]), the link's echo
//! and prompt, and which notices it has been shown. The board keeps one [`Session`] per link
//! (UART0, USB) and hands it to the controller with every byte, so each link types its own
//! lines, a reply goes to the link that asked, and notices reach every link once.

use core::fmt::Write;

use crate::protocol::{Feed, LineBuffer, Lost};
use crate::report;

/// The state of one link.
#[derive(Debug, Clone)]
pub struct Session {
    line: LineBuffer,
    echo: bool,
    /// Sequence number of the first notice this link has not been shown.
    next_notice: u32,
    /// A command from this link is being carried out; its reply is still to come.
    awaiting_reply: bool,
    /// The prompt after the last reply waits for the board to switch the baud rate.
    prompt_deferred: bool,
}

impl Default for Session {
    fn default() -> Self {
        Self::new()
    }
}

impl Session {
    /// A link with echo on (for a terminal), nothing typed yet, every notice still to show.
    pub const fn new() -> Self {
        Session {
            line: LineBuffer::new(),
            echo: true,
            next_notice: 0,
            awaiting_reply: false,
            prompt_deferred: false,
        }
    }

    /// Whether typed characters are echoed and a prompt follows every reply.
    pub fn echo(&self) -> bool {
        self.echo
    }

    /// Turns echo and prompt on or off (`set echo`).
    pub fn set_echo(&mut self, on: bool) {
        self.echo = on;
    }

    /// What has been typed of the current line.
    pub fn typed(&self) -> &str {
        self.line.line()
    }

    /// True while a command this link sent is being carried out: its final reply is still to
    /// come (from [`crate::Controller::work`], which must be given this session).
    pub fn awaits_reply(&self) -> bool {
        self.awaiting_reply
    }

    /// The link was closed and has been opened again (a USB host opened its port): a new
    /// terminal on the same link. Nothing typed (a partial line is abandoned), echo on, no
    /// prompt held back. Which notices it has shown is kept: the notices that came while it
    /// was closed are shown once, by the next [`crate::Controller::banner`]. Call it only while
    /// no reply is awaited ([`Session::awaits_reply`]): the reply would go to the new terminal.
    pub fn reopen(&mut self) {
        debug_assert!(!self.awaiting_reply, "reopened with a reply still to come");
        self.line = LineBuffer::new();
        self.echo = true;
        self.prompt_deferred = false;
    }

    /// Writes the prompt held back after `set baud` changed the rate (echo on): call it once
    /// the board has switched the UART to the new rate, so the prompt arrives readable.
    pub fn write_deferred_prompt(&mut self, out: &mut impl Write) {
        if core::mem::take(&mut self.prompt_deferred) {
            self.prompt(out);
        }
    }

    pub(crate) fn set_awaiting_reply(&mut self, awaiting: bool) {
        self.awaiting_reply = awaiting;
    }

    /// The next prompt waits for [`Session::write_deferred_prompt`].
    pub(crate) fn defer_prompt(&mut self) {
        self.prompt_deferred = true;
    }

    /// Feeds one received byte to the line, echoing it when echo is on; `tick` is the number
    /// of servo frames so far (see [`LineBuffer::feed_at`]).
    pub(crate) fn feed(&mut self, byte: u8, tick: u32, out: &mut impl Write) -> Feed {
        // A line that began with a digit may be a text frame: it is not echoed as it comes,
        // only whole if it turns out to be a line.
        let held = self.line.holds_echo();
        let feed = self.line.feed_at(byte, tick);
        if self.echo {
            match feed {
                Feed::Line if held => report::write_held_echo(out, self.line.line()),
                Feed::Added(_) | Feed::Erased | Feed::ErasedLine(_) | Feed::Overflowed
                    if held || self.line.holds_echo() => {}
                _ => report::write_echo(out, feed),
            }
        }
        feed
    }

    /// Takes the plain characters at the start of `bytes` into the line at once
    /// ([`LineBuffer::take_plain`]: a command line's characters, up to anything else), echoing
    /// them when echo is on, exactly as feeding each would ([`crate::Controller::on_byte`]: a
    /// plain character only adds to the line, for the controller nothing happens). Returns how
    /// many it took; the rest are for [`crate::Controller::on_byte`], one by one.
    pub fn take_plain(&mut self, bytes: &[u8], out: &mut impl Write) -> usize {
        let taken = self.line.take_plain(bytes);
        if self.echo && taken > 0 {
            report::write_echo_chars(out, &bytes[..taken]);
        }
        taken
    }

    /// Whether [`Session::take_plain`] may take anything now ([`LineBuffer::may_take_plain`]).
    #[inline]
    pub fn may_take_plain(&self) -> bool {
        self.line.may_take_plain()
    }

    /// True (once) if a binary frame was dropped because its bytes stopped coming.
    pub(crate) fn take_abandoned_frame(&mut self) -> bool {
        self.line.take_abandoned()
    }

    /// Forgets the completed line (after [`Feed::Line`], once read with
    /// [`Session::typed`]): the buffer is free again.
    pub(crate) fn clear_line(&mut self) {
        self.line.clear();
    }

    /// Bytes were lost on this link's way in: the line being received is refused when it ends.
    pub(crate) fn rx_overflow(&mut self, lost: Lost) {
        self.line.rx_overflow(lost);
    }

    /// Writes the prompt if echo is on (unless it waits for a baud-rate switch).
    pub(crate) fn prompt(&self, out: &mut impl Write) {
        if self.echo && !self.prompt_deferred {
            report::write_prompt(out);
        }
    }

    /// Whether notice number `seq` has not been shown on this link yet.
    pub(crate) fn has_not_seen(&self, seq: u32) -> bool {
        // Sequence numbers wrap; only the last few notices are kept, so the difference is small.
        (seq.wrapping_sub(self.next_notice) as i32) >= 0
    }

    /// Every notice before number `next` has been shown.
    pub(crate) fn saw_notices_until(&mut self, next: u32) {
        self.next_notice = next;
    }
}
