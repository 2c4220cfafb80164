//! Notices (faults, link loss, warnings, the e-stop): kept for every link to show, the latest
//! [`NOTICE_QUEUE`](super::NOTICE_QUEUE) of them, each with its sequence number; each link's
//! [`Session`] remembers which it has shown. They are written by
//! [`Controller::write_notices`](super::Controller::write_notices) and before a link's next
//! reply; a link that is closed is shown the latest few by its banner when it opens again.
//!
//! UART receive errors come in bursts: the first loss of a burst is announced at once, the
//! others are counted for one notice ([`LossBurst`](super::loss_burst::LossBurst)).

use core::fmt::Write;

use kinematics_core::Math;

use super::loss_burst::LossBurst;
use super::Controller;
use crate::report::{self, Notice};
use crate::session::Session;

impl<M: Math> Controller<M> {
    /// A UART loss of `at_least` bytes: counted (true) if a burst is going on, else the start
    /// of one (false: announce it).
    pub(super) fn count_in_burst(&mut self, at_least: u32) -> bool {
        LossBurst::count(&mut self.uart_burst, at_least)
    }

    /// A servo frame of `frame_us` passed: a burst that has ended (or gone on for
    /// [`BURST_REPORT_US`](super::loss_burst::BURST_REPORT_US)) gets its notice, if it lost
    /// more than its first announced loss.
    pub(super) fn time_burst(&mut self, frame_us: u32) {
        if let Some(notice) = LossBurst::tick(&mut self.uart_burst, frame_us) {
            self.notify(notice);
        }
    }

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

    #[test]
    fn a_burst_of_uart_errors_gives_one_warning_at_once_and_one_with_its_count() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        // A sender at the wrong baud rate: a garbled byte every millisecond for 286 ms (the
        // servo frames, 20 ms, come between).
        for ms in 0..286u32 {
            c.on_input_lost(&mut link, 1, true, &mut out);
            if ms % 20 == 19 {
                c.on_frame();
                c.write_notices(&mut link, &mut out);
            }
        }
        assert_eq!(
            out, "# warning: UART receive error, input lost (at least 1 byte)\r\n",
            "the first loss at once, the others only counted while the burst goes on"
        );
        // 0.2 s without a loss ends the burst: one notice with the count.
        for _ in 0..10 {
            c.on_frame();
            c.write_notices(&mut link, &mut out);
        }
        let lines: std::vec::Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), 2, "{out}");
        assert_eq!(
            lines[1],
            "# warning: UART receive errors went on: 285 more, input lost (at least 285 bytes) \
             in 0.28 s"
        );
        // The next loss is a new burst: announced at once.
        out.clear();
        c.on_input_lost(&mut link, 2, true, &mut out);
        assert_eq!(
            out,
            "# warning: UART receive error, input lost (at least 2 bytes)\r\n"
        );
        // A lone loss ends its burst without a second word.
        out.clear();
        for _ in 0..20 {
            c.on_frame();
            c.write_notices(&mut link, &mut out);
        }
        assert_eq!(out, "");
    }

    #[test]
    fn a_burst_that_goes_on_is_reported_every_two_seconds_and_queue_overflows_at_once() {
        let (mut c, mut link) = (quiet(), program());
        let mut out = std::string::String::new();
        // 5 s of garble, 5 losses a frame.
        for _ in 0..250 {
            for _ in 0..5 {
                c.on_input_lost(&mut link, 1, true, &mut out);
            }
            c.on_frame();
            c.write_notices(&mut link, &mut out);
        }
        let lines: std::vec::Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), 3, "{out}");
        assert!(lines[1].contains("went on: 499 more") && lines[1].ends_with("in 2.00 s"));
        assert!(lines[2].contains("went on: 500 more"), "{}", lines[2]);
        // A receive queue overflow is not a UART error: announced at once, burst or not.
        out.clear();
        c.on_input_lost(&mut link, 40, false, &mut out);
        assert!(out.contains("receive queue overflowed"), "{out}");
    }
}
