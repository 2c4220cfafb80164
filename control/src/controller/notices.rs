//! Notices (faults, link loss, warnings, the e-stop): kept for every link to show, the latest
//! [`NOTICE_QUEUE`](super::NOTICE_QUEUE) of them, each with its sequence number; each link's
//! [`Session`] remembers which it has shown. They are written by
//! [`Controller::write_notices`](super::Controller::write_notices) and before a link's next
//! reply; a link that is closed is shown the latest few by its banner when it opens again.

use core::fmt::Write;

use kinematics_core::Math;

use super::Controller;
use crate::report::{self, Notice};
use crate::session::Session;

impl<M: Math> Controller<M> {
    /// Keeps a notice for every link to show (only the latest
    /// [`NOTICE_QUEUE`](super::NOTICE_QUEUE)).
    pub(super) fn notify(&mut self, notice: Notice) {
        if self.notices.is_full() {
            self.notices.pop_front();
        }
        let _ = self.notices.push_back((self.next_notice, notice));
        self.next_notice = self.next_notice.wrapping_add(1);
    }

    pub(super) fn has_notices_for(&self, session: &Session) -> bool {
        self.notices
            .back()
            .is_some_and(|(seq, _)| session.has_not_seen(*seq))
    }

    /// Writes the notices `session` has not shown yet.
    pub(super) fn flush_notices(&self, session: &mut Session, out: &mut impl Write) {
        for (seq, notice) in &self.notices {
            if session.has_not_seen(*seq) {
                report::write_notice(out, notice);
            }
        }
        session.saw_notices_until(self.next_notice);
    }
}

#[cfg(test)]
mod tests {
    use crate::controller::test_support::*;
    use crate::controller::NOTICE_QUEUE;
    use crate::report::{self, Notice};

    #[test]
    fn notice_queue_keeps_the_latest() {
        let (mut c, mut link) = (quiet(), program());
        for at_least in 1..=10 {
            c.notify(Notice::InputLost {
                at_least,
                in_uart: false,
            });
        }
        let mut out = std::string::String::new();
        c.write_notices(&mut link, &mut out);
        assert_eq!(out.lines().count(), NOTICE_QUEUE);
        assert!(
            out.contains("at least 10 bytes") && !out.contains("at least 1 byte "),
            "{out}"
        );
        // Shown once per link: the same link gets nothing more, another link gets them too.
        out.clear();
        c.write_notices(&mut link, &mut out);
        assert_eq!(out, "");
        assert_eq!(notices(&c, &mut program()).lines().count(), NOTICE_QUEUE);
    }

    #[test]
    fn a_reopened_link_starts_afresh_and_shows_only_what_came_while_it_was_closed() {
        let mut c = quiet();
        let mut usb = program();
        let mut out = std::string::String::new();
        c.on_input_lost(&mut usb, 3, false, &mut out);
        for &b in b"pose 1" {
            c.on_byte(&mut usb, b, &mut out);
        }
        // Closed (the host dropped DTR); a notice comes meanwhile, then the host opens again.
        c.notify(Notice::InputLost {
            at_least: 7,
            in_uart: true,
        });
        usb.reopen();
        assert!(usb.echo(), "a new terminal: echo on");
        assert_eq!(usb.typed(), "", "the partial line is abandoned");
        out.clear();
        c.banner(&mut usb, &mut out);
        assert_eq!(
            out,
            std::format!(
                "# hexapod control {}: poses in mm and degrees; type help\r\n\
                 # warning: UART receive error, input lost (at least 7 bytes)\r\n> ",
                report::VERSION
            )
        );
        // The new terminal's first line is a line of its own.
        out.clear();
        for &b in b"home\r" {
            c.on_byte(&mut usb, b, &mut out);
        }
        finish(&mut c, &mut usb, &mut out);
        assert_eq!(out, "home\r\nok\r\n> ");
    }
}
