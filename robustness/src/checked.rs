//! [`Checked`]: a controller driven like the board drives it, checking the firmware's
//! guarantees after every step. A broken guarantee panics with a description (which is what a
//! fuzzer or a test harness catches).

use control::report::Code;
use control::store::{RamFlash, Store};
use control::{Controller, Pose, Session, Settings};

use crate::line_model::{LineEnd, LineModel};

/// What a rejected command must leave as it was.
#[derive(Debug, Clone, PartialEq)]
struct State {
    settings: Settings,
    baud: u32,
    echo: bool,
    generation: u32,
    pose: Pose,
    target: Pose,
    moving: bool,
    pulses_us: [f32; 6],
}

/// A controller plus the reference line model, checked at every step.
pub struct Checked {
    /// The controller under test.
    pub ctl: Controller,
    /// The link the bytes arrive on.
    pub link: Session,
    model: LineModel,
    /// Everything written so far (capped, for failure messages).
    pub log: String,
    /// Final replies seen so far.
    pub replies: usize,
    /// `ok` replies seen so far.
    pub oks: usize,
    /// Frames run so far.
    pub frames: u64,
    /// The flash `save` writes to, as the board's.
    pub flash: RamFlash,
}

const LOG_CAP: usize = 4096;

/// True for a line that is a final reply.
pub fn is_final(line: &str) -> bool {
    line == "ok" || line.starts_with("ok ") || line.starts_with("error:")
}

/// The code of an `error:<code> <message>` line.
pub fn code_of(line: &str) -> Option<&str> {
    let rest = line.strip_prefix("error:")?;
    Some(rest.split(' ').next().unwrap_or(""))
}

fn known_code(code: &str) -> bool {
    Code::ALL.iter().any(|c| c.as_str() == code)
}

/// Checks that `pulses` are finite and inside each servo's configured limits.
pub fn check_pulses(settings: &Settings, pulses: &[f32; 6], when: &str) {
    for (i, (w, s)) in pulses.iter().zip(settings.servos.0.iter()).enumerate() {
        assert!(
            w.is_finite() && *w >= s.min_us && *w <= s.max_us,
            "{when}: servo {} commanded {w} us outside {}..={} us",
            i + 1,
            s.min_us,
            s.max_us
        );
    }
}

/// Checks output text: printable ASCII plus CR, LF, backspace, bell; CR only before LF
/// (except the echo's erase sequences, which use backspace).
pub fn check_output_bytes(out: &str) {
    for (i, b) in out.bytes().enumerate() {
        assert!(
            (0x20..=0x7E).contains(&b) || matches!(b, b'\r' | b'\n' | 0x08 | 0x07),
            "output byte {b:#04x} at {i} in {out:?}"
        );
    }
}

impl Checked {
    /// A controller with `settings` (which must be valid) on a link with `echo` on or off,
    /// banner written and checked.
    pub fn new(settings: Settings, echo: bool) -> Checked {
        let mut link = Session::new();
        link.set_echo(echo);
        let mut c = Checked {
            ctl: Controller::new(settings),
            link,
            model: LineModel::new(),
            log: String::new(),
            replies: 0,
            oks: 0,
            frames: 0,
            flash: RamFlash::new(),
        };
        let mut out = String::new();
        c.ctl.banner(&mut c.link, &mut out);
        check_output_bytes(&out);
        assert_eq!(
            Self::finals(&out, false).len(),
            0,
            "the banner holds a final reply: {out:?}"
        );
        c.after_step("banner");
        // At power-on the servos are commanded to their home (trim) pulses.
        let home: [f32; 6] = core::array::from_fn(|i| c.ctl.settings().servos.0[i].home_us);
        assert_eq!(c.ctl.pulses_us(), home, "power-on pulses are not the trims");
        c
    }

    fn state(&self) -> State {
        State {
            settings: *self.ctl.settings(),
            baud: self.ctl.baud(),
            echo: self.link.echo(),
            generation: self.ctl.settings_generation(),
            pose: *self.ctl.pose(),
            target: *self.ctl.target(),
            moving: self.ctl.is_moving(),
            pulses_us: self.ctl.pulses_us(),
        }
    }

    /// One slice of the controller's work as the board's main loop does it: the flash write a
    /// `save` asks for (then the store the controller knows must be what the flash holds), or
    /// a slice of work.
    fn work(&mut self, out: &mut String) {
        if let Some(write) = self.ctl.take_flash_write() {
            self.ctl.flash_written(write.perform(&mut self.flash));
            self.ctl.work(&mut self.link, out);
            let loaded = Store::load(&mut self.flash);
            assert_eq!(
                &loaded.store,
                self.ctl.store(),
                "after a save the controller's store differs from what the flash holds"
            );
            assert_eq!(
                loaded.settings(),
                Some(self.ctl.settings()),
                "save saved other settings"
            );
        } else {
            self.ctl.work(&mut self.link, out);
        }
    }

    fn record(&mut self, out: &str) {
        if self.log.len() > LOG_CAP {
            let cut = self.log.len() - LOG_CAP / 2;
            self.log.drain(..cut);
        }
        self.log.push_str(out);
    }

    /// The complete final-reply lines in a chunk of output written while handling one byte.
    /// A chunk starts mid-line when echo is on (the typed character), at a line start when off.
    fn finals(out: &str, echo_before: bool) -> Vec<&str> {
        let mut parts: Vec<&str> = out.split("\r\n").collect();
        // The last part is not terminated: not a complete line.
        parts.pop();
        parts
            .into_iter()
            .enumerate()
            .filter(|(i, l)| (*i > 0 || !echo_before) && is_final(l))
            .map(|(_, l)| l)
            .collect()
    }

    /// Invariants that hold between any two steps.
    fn after_step(&self, what: &str) {
        let s = self.ctl.settings();
        if let Err(e) = s.validate() {
            panic!("{what}: settings no longer validate: {e:?}\n{s:?}");
        }
        check_pulses(s, &self.ctl.pulses_us(), what);
        assert!(
            self.ctl.pose().first_non_finite().is_none()
                && self.ctl.target().first_non_finite().is_none(),
            "{what}: non-finite pose {:?} / target {:?}",
            self.ctl.pose(),
            self.ctl.target()
        );
        if !self.ctl.is_moving() {
            assert_eq!(
                self.ctl.pose(),
                self.ctl.target(),
                "{what}: stopped away from the target"
            );
        }
    }

    /// Feeds one byte, as the board does; checks the reply count against the line model, and
    /// that a refused line (or rejected command) changed nothing.
    pub fn byte(&mut self, b: u8) {
        let echo_before = self.link.echo();
        let before = self.state();
        let expected = self.model.byte(b);
        let mut out = String::new();
        self.ctl.on_byte(&mut self.link, b, &mut out);
        // As the board does: the command's work, a slice at a time, before the next byte; the
        // reply comes at its end. (Frames between slices are left out here, so that "a refused
        // command changes nothing" can be checked; the controller's tests cover them.)
        let mut slices = 0u32;
        while self.ctl.is_busy() {
            self.work(&mut out);
            slices += 1;
            assert!(slices < 100_000, "a command's work never ends: {out:?}");
        }
        // As the board does after feeding: the newest stream frame, if one came (a clamp's
        // bisection then runs as the controller's own work, a slice per pass).
        self.ctl.apply_stream();
        while self.ctl.is_busy() && !self.link.awaits_reply() {
            self.ctl.work(&mut self.link, &mut out);
        }
        if let Some(pulses) = self.ctl.take_new_pulses() {
            check_pulses(self.ctl.settings(), &pulses, "stream frame");
        }
        self.record(&out);
        check_output_bytes(&out);
        let finals = Self::finals(&out, echo_before);
        let want = usize::from(expected.wants_reply());
        assert_eq!(
            finals.len(),
            want,
            "byte {b:#04x} ({expected:?}) gave {} final replies: {out:?}\nlog: {:?}",
            finals.len(),
            self.log
        );
        if let Some(&reply) = finals.first() {
            self.replies += 1;
            match code_of(reply) {
                None => {
                    self.oks += 1;
                    if let LineEnd::Refused(r) = expected {
                        panic!("line refused for {r:?} got {reply:?}");
                    }
                }
                Some(code) => {
                    assert!(known_code(code), "unknown error code in {reply:?}");
                    if let LineEnd::Refused(r) = expected {
                        assert_eq!(code, r.code(), "refused line: {reply:?}");
                    } else {
                        assert!(
                            !matches!(code, "rx-overflow" | "line-too-long"),
                            "{expected:?} refused as {reply:?}"
                        );
                    }
                    // A rejected line changes nothing.
                    let after = self.state();
                    assert_eq!(
                        before, after,
                        "rejected line {expected:?} ({reply:?}) changed the state"
                    );
                }
            }
            // The reply is the last complete line written for this byte.
            let last_line = out.trim_end_matches("> ").trim_end_matches("\r\n");
            assert!(
                last_line.ends_with(reply),
                "the final reply is not last: {out:?}"
            );
        } else if !matches!(
            expected,
            LineEnd::Line(_) | LineEnd::Refused(_) | LineEnd::Frame
        ) {
            // No line completed: nothing a host could see as a command may have changed.
            let after = self.state();
            assert_eq!(
                before.settings, after.settings,
                "byte {b:#04x} changed settings"
            );
            assert_eq!(
                before.target, after.target,
                "byte {b:#04x} changed the target"
            );
            assert_eq!(before.pose, after.pose, "byte {b:#04x} moved the platform");
        }
        self.after_step("byte");
    }

    /// Feeds bytes one by one.
    pub fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.byte(b);
        }
    }

    /// Sends `text` and a line end.
    pub fn line(&mut self, text: &str, end: &[u8]) {
        self.bytes(text.as_bytes());
        self.bytes(end);
    }

    /// The board's receive queue lost `dropped` bytes: the line in progress must be refused.
    pub fn rx_overflow(&mut self, dropped: u32) {
        let before = self.state();
        self.model.lost();
        let mut out = String::new();
        self.ctl
            .on_input_lost(&mut self.link, dropped, false, &mut out);
        let lost = control::protocol::Lost {
            bytes: dropped,
            in_uart: false,
        };
        self.ctl.on_rx_overflow(&mut self.link, lost);
        self.record(&out);
        check_output_bytes(&out);
        let bytes = if dropped == 1 { "byte" } else { "bytes" };
        assert!(
            out.contains(&format!(
                "# warning: receive queue overflowed, input lost (at least {dropped} {bytes} so far)"
            )),
            "a loss of {dropped} bytes was not reported at once: {out:?}"
        );
        assert_eq!(
            Self::finals(&out, true).len() + Self::finals(&out, false).len(),
            0,
            "a loss produced a final reply: {out:?}"
        );
        assert_eq!(before, self.state(), "a loss changed the state");
        self.after_step("rx overflow");
    }

    /// Runs `n` frames; every frame's pulses must be finite and within the limits.
    pub fn frames(&mut self, n: u32) {
        for _ in 0..n {
            self.model.tick();
            let pulses = self.ctl.on_frame();
            self.frames += 1;
            check_pulses(self.ctl.settings(), &pulses, "frame");
            assert_eq!(
                pulses,
                self.ctl.pulses_us(),
                "frame pulses differ from pulses_us"
            );
            let mut out = String::new();
            // The controller's own work (the return home after link loss), as the main loop
            // runs it between frames.
            while self.ctl.is_busy() && !self.link.awaits_reply() {
                self.work(&mut out);
            }
            self.ctl.write_notices(&mut self.link, &mut out);
            self.record(&out);
            check_output_bytes(&out);
            assert_eq!(
                Self::finals(&out, true).len(),
                0,
                "notices hold a final reply: {out:?}"
            );
            self.after_step("frame");
        }
    }

    /// The e-stop input opens or closes: no reply; the pulses stay valid, and while it is on
    /// nothing is streaming.
    pub fn estop(&mut self, open: bool) {
        self.ctl.set_estop_input(open);
        let mut out = String::new();
        while self.ctl.is_busy() && !self.link.awaits_reply() {
            self.ctl.work(&mut self.link, &mut out);
        }
        self.ctl.write_notices(&mut self.link, &mut out);
        self.record(&out);
        check_output_bytes(&out);
        assert_eq!(
            Self::finals(&out, true).len(),
            0,
            "e-stop gave a reply: {out:?}"
        );
        if self.ctl.estop().stops_motion() {
            assert!(!self.ctl.is_streaming(), "streaming through an e-stop");
        }
        self.after_step("e-stop");
    }

    /// Runs frames until the motion ends (at most `limit`); returns whether it ended.
    pub fn settle(&mut self, limit: u32) -> bool {
        for _ in 0..limit {
            if !self.ctl.is_moving() {
                return true;
            }
            self.frames(1);
        }
        !self.ctl.is_moving()
    }

    /// Runs one line through `execute_line` (the non-byte transport): exactly one final
    /// reply for a non-blank line, none for a blank one; a rejected line changes nothing.
    pub fn execute(&mut self, line: &str) {
        let before = self.state();
        let mut out = String::new();
        self.ctl.execute_line(&mut self.link, line, &mut out);
        // A save's flash write is the board's; then its reply.
        while self.ctl.is_busy() {
            self.work(&mut out);
        }
        self.record(&out);
        check_output_bytes(&out);
        let blank = line.bytes().all(|b| b == b' ' || b == b'\t');
        let finals = Self::finals(&out, false);
        assert_eq!(
            finals.len(),
            usize::from(!blank),
            "execute_line({line:?}) gave {out:?}"
        );
        if let Some(code) = finals.first().and_then(|r| code_of(r)) {
            assert!(known_code(code), "unknown code in {out:?}");
            assert_eq!(before, self.state(), "rejected {line:?} changed the state");
        }
        if !finals.is_empty() {
            self.replies += 1;
        }
        self.after_step("execute_line");
    }
}
