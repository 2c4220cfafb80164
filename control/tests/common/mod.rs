//! A test host on one link: bytes in, text out, with helpers to pick replies apart.
#![allow(dead_code)] // each test file uses a different subset

use control::store::RamFlash;
use control::{Controller, Session, Settings};

/// True for a final reply line (`ok...` or `error:...`).
pub fn is_final(line: &str) -> bool {
    line.starts_with("ok") || line.starts_with("error:")
}

/// The code of an `error:<code> <message>` line.
pub fn code_of(line: &str) -> &str {
    line.strip_prefix("error:")
        .and_then(|rest| rest.split(' ').next())
        .unwrap_or_else(|| panic!("not an error reply: {line:?}"))
}

pub struct Host {
    pub ctl: Controller,
    /// The host's link.
    pub link: Session,
    /// Everything written so far.
    pub log: String,
    /// The flash a `save` writes to, as the board's.
    pub flash: RamFlash,
}

impl Host {
    /// Echo off (as a program would talk to it).
    pub fn quiet() -> Host {
        let mut host = Host::with(Settings::default());
        host.link.set_echo(false);
        host
    }

    /// Echo on (as a terminal would talk to it).
    pub fn with(settings: Settings) -> Host {
        Host {
            ctl: Controller::new(settings),
            link: Session::new(),
            log: String::new(),
            flash: RamFlash::new(),
        }
    }

    /// Does a slice of the controller's work as the board's main loop does: the flash write a
    /// `save` asks for, or a slice of work.
    pub fn work(&mut self, out: &mut String) {
        if let Some(write) = self.ctl.take_flash_write() {
            self.ctl.flash_written(write.perform(&mut self.flash));
        } else {
            self.ctl.work(&mut self.link, out);
        }
    }

    /// Feeds raw bytes as the board does (a command's work runs to its end before the next
    /// byte is read); returns what was written meanwhile.
    pub fn feed(&mut self, bytes: &[u8]) -> String {
        let mut out = String::new();
        for &b in bytes {
            self.ctl.on_byte(&mut self.link, b, &mut out);
            while self.ctl.is_busy() {
                self.work(&mut out);
            }
        }
        self.log.push_str(&out);
        out
    }

    /// As the board does after feeding bytes: applies the newest stream frame, and runs the
    /// controller's own work that may start (a clamp's bisection) to its end.
    pub fn apply_stream(&mut self) {
        self.ctl.apply_stream();
        let mut out = String::new();
        while self.ctl.is_busy() {
            self.ctl.work(&mut self.link, &mut out);
        }
        assert_eq!(out, "", "applying a stream frame wrote something");
    }

    /// Sends a line with CR LF; returns the output lines (without line ends).
    pub fn send(&mut self, line: &str) -> Vec<String> {
        let out = self.feed(format!("{line}\r\n").as_bytes());
        out.split("\r\n")
            .filter(|l| !l.is_empty())
            .map(str::to_owned)
            .collect()
    }

    /// Sends a line that must get exactly one final reply, as the last line; returns
    /// (data lines, final reply).
    pub fn exchange(&mut self, line: &str) -> (Vec<String>, String) {
        let mut lines = self.send(line);
        let finals = lines.iter().filter(|l| is_final(l)).count();
        assert_eq!(finals, 1, "{line:?} got {lines:?}");
        let last = lines.pop().unwrap();
        assert!(
            is_final(&last),
            "{line:?}: reply not last in {lines:?} {last:?}"
        );
        for l in &lines {
            assert!(
                l.starts_with("# "),
                "{line:?}: data line without '# ': {l:?}"
            );
        }
        (lines, last)
    }

    /// Sends a line that must succeed; returns its data lines.
    pub fn ok(&mut self, line: &str) -> Vec<String> {
        let (data, reply) = self.exchange(line);
        assert_eq!(reply, "ok", "{line:?} -> {data:?}");
        data
    }

    /// Sends a line that must fail; returns the whole error line.
    pub fn err(&mut self, line: &str) -> String {
        let (_, reply) = self.exchange(line);
        assert!(reply.starts_with("error:"), "{line:?} -> {reply:?}");
        reply
    }

    /// The error code a line gets.
    pub fn code(&mut self, line: &str) -> String {
        code_of(&self.err(line)).to_owned()
    }

    /// The notices this link has not shown yet, as the board writes them.
    pub fn notices(&mut self) -> String {
        let mut out = String::new();
        self.ctl.write_notices(&mut self.link, &mut out);
        self.log.push_str(&out);
        out
    }

    /// Runs `n` frames; returns their pulses. Between frames, work the controller started on
    /// its own (the return home after link loss) runs to its end, as on a board whose main
    /// loop gets through a check within a frame.
    pub fn frames(&mut self, n: usize) -> Vec<[f32; 6]> {
        (0..n)
            .map(|_| {
                let pulses = self.ctl.on_frame();
                let mut out = String::new();
                while self.ctl.is_busy() {
                    self.work(&mut out);
                }
                self.log.push_str(&out);
                pulses
            })
            .collect()
    }

    /// Runs frames until the move ends; returns how many it took.
    pub fn run_until_idle(&mut self) -> usize {
        let mut n = 0;
        while self.ctl.is_moving() {
            self.ctl.on_frame();
            n += 1;
            assert!(n < 10_000_000, "move never ends");
        }
        n
    }

    /// The value after `key: ` in the `status` output.
    pub fn status_field(&mut self, key: &str) -> String {
        let data = self.ok("status");
        let prefix = format!("# {key}: ");
        data.iter()
            .find_map(|l| l.strip_prefix(&prefix))
            .unwrap_or_else(|| panic!("no {key} in {data:?}"))
            .to_owned()
    }
}

/// Parses `x=1.000 y=...` into six numbers (mm, degrees).
pub fn pose_values(text: &str) -> [f32; 6] {
    let v: Vec<f32> = text
        .split(' ')
        .map(|kv| kv.split_once('=').unwrap().1.parse().unwrap())
        .collect();
    v.try_into().unwrap()
}

/// Parses six space-separated numbers.
pub fn six(text: &str) -> [f32; 6] {
    let v: Vec<f32> = text.split(' ').map(|n| n.parse().unwrap()).collect();
    v.try_into().unwrap()
}
