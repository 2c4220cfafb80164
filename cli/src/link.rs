//! Talking to a board over a serial port (a Pico's USB or UART port, or the emulator's
//! pseudo-terminal from `./dev run --pty`), honouring the firmware's protocol (README,
//! "Command reference"):
//!
//! - every non-blank line gets exactly one final reply, its last line: `ok` or
//!   `error:<code> <message>`; every other line starts with `# `;
//! - a program sends `set echo off` first (no echo, no prompt), and waits for each reply;
//! - after a `# warning:` (bytes were lost on the way to the board) it resynchronises: a line
//!   end (which closes a cut line, then refused), then `status`, and waits for that reply.
//!
//! A thread reads the port and hands over whole lines with the instant each arrived, so a
//! caller can write (stream frames, say) while replies come in. Times are `Instant`s; time-outs
//! are `Duration`s.

use std::io::{Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::Arc;
use std::thread;
use std::time::{Duration, Instant};

use serialport::SerialPort;

use crate::boards;
use crate::error::{Error, PortError};

/// How long a read on the port blocks before the reader thread checks it is still wanted.
const READ_POLL: Duration = Duration::from_millis(20);
/// How long to listen for what the board said before we spoke (banner, prompt, echo).
const SETTLE: Duration = Duration::from_millis(150);
/// Ctrl-C: the board abandons a partly received line (no reply).
const ABANDON_LINE: u8 = 0x03;

/// Lines starting with these are notices the board sends on its own, not a reply's data.
pub const NOTICE_PREFIXES: [&str; 4] = [
    "# warning:",
    "# fault:",
    "# link lost:",
    "# emergency stop:",
];

/// What the board's warnings about lost input say (README, "Command reference": `# warning:
/// receive queue overflowed, input lost ...`, `# warning: UART receive error, input lost ...`):
/// after one, the link is resynchronised. Other warnings (e.g. about the settings found in
/// flash at power-up) need nothing.
pub const INPUT_LOST: &str = "input lost";

/// Whether a line is the board's warning that input was lost.
pub fn is_input_lost(line: &str) -> bool {
    line.starts_with("# warning:") && line.contains(INPUT_LOST)
}

/// Whether a line is a final reply.
pub fn is_final(line: &str) -> bool {
    line == "ok" || line.starts_with("error:")
}

/// Whether a line is a notice (see [`NOTICE_PREFIXES`]).
pub fn is_notice(line: &str) -> bool {
    NOTICE_PREFIXES.iter().any(|p| line.starts_with(p))
}

/// The reply to one line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Reply {
    /// Its data lines (`# key: value`), in order.
    pub data: Vec<String>,
    /// Notices that came meanwhile (`# warning: ...`).
    pub notices: Vec<String>,
    /// The final reply: `ok` or `error:<code> <message>`.
    pub last: String,
    /// When the final reply arrived.
    pub at: Instant,
}

impl Reply {
    /// Whether the board accepted the line.
    pub fn is_ok(&self) -> bool {
        self.last == "ok"
    }

    /// The value of data line `# key: value`, if the reply has one.
    pub fn value(&self, key: &str) -> Option<&str> {
        self.data.iter().find_map(|line| {
            line.strip_prefix("# ")?
                .strip_prefix(key)?
                .strip_prefix(": ")
        })
    }
}

/// A line received, with the instant it arrived.
#[derive(Debug, Clone)]
pub struct Received {
    /// When its line end arrived.
    pub at: Instant,
    /// The line, without its line end or a prompt before it.
    pub line: String,
}

/// Why a port did not open, with the ports the system does list, boards first with their ids
/// (none if it cannot list them).
fn not_opened(error: &serialport::Error) -> PortError {
    PortError::Open {
        why: error.to_string(),
        present: boards::present().iter().map(boards::Found::short).collect(),
        denied: error.kind() == serialport::ErrorKind::Io(std::io::ErrorKind::PermissionDenied),
    }
}

/// An open link to a board.
pub struct Link {
    port: String,
    writer: Box<dyn SerialPort>,
    lines: Receiver<Result<Received, String>>,
    /// Cleared when the link is dropped: the reader thread ends.
    wanted: Arc<AtomicBool>,
    /// How long to wait for a final reply.
    pub timeout: Duration,
}

impl Link {
    /// Opens `port` at `baud` (8N1). Nothing is sent yet: see [`Link::start`].
    pub fn open(port: &str, baud: u32, timeout: Duration) -> Result<Link, Error> {
        let problem = |why| Error::Port {
            port: port.to_string(),
            why,
        };
        let writer = serialport::new(port, baud)
            .timeout(READ_POLL)
            .open()
            .map_err(|e| problem(not_opened(&e)))?;
        let reader = writer.try_clone().map_err(|e| problem(not_opened(&e)))?;
        let (sender, lines) = mpsc::channel();
        let wanted = Arc::new(AtomicBool::new(true));
        let still_wanted = Arc::clone(&wanted);
        thread::spawn(move || read_lines(reader, sender, still_wanted));
        Ok(Link {
            port: port.to_string(),
            writer,
            lines,
            wanted,
            timeout,
        })
    }

    /// The port's name.
    pub fn port(&self) -> &str {
        &self.port
    }

    fn problem(&self, why: PortError) -> Error {
        Error::Port {
            port: self.port.clone(),
            why,
        }
    }

    /// Makes the link a program's: abandons any partly typed line, lets what the board had to
    /// say go by, turns echo off and checks the board answers.
    pub fn start(&mut self) -> Result<(), Error> {
        self.write(&[ABANDON_LINE])?;
        let until = Instant::now() + SETTLE;
        while self.next_line(until)?.is_some() {}
        self.request_ok("set echo off")?;
        Ok(())
    }

    /// Moves the port to `baud` (after the board's `ok` to `set baud`: the board switches once
    /// that `ok` has left). On a USB port it changes nothing the board sees.
    pub fn set_baud(&mut self, baud: u32) -> Result<(), Error> {
        self.writer
            .set_baud_rate(baud)
            .map_err(|e| self.problem(PortError::Io(e.to_string())))
    }

    /// Writes bytes as they are. (The port has no buffer of ours to flush; a serial port's
    /// `flush` would wait until the bytes have left, which is not this call's business.)
    pub fn write(&mut self, bytes: &[u8]) -> Result<(), Error> {
        self.writer
            .write_all(bytes)
            .map_err(|e| self.problem(PortError::Io(e.to_string())))
    }

    /// Sends one line (a line end is added).
    pub fn send_line(&mut self, line: &str) -> Result<(), Error> {
        let mut bytes = Vec::with_capacity(line.len() + 1);
        bytes.extend_from_slice(line.as_bytes());
        bytes.push(b'\n');
        self.write(&bytes)
    }

    /// The next line received before `until`, or `None` if none came by then.
    pub fn next_line(&mut self, until: Instant) -> Result<Option<Received>, Error> {
        let wait = until.saturating_duration_since(Instant::now());
        match self.lines.recv_timeout(wait) {
            Ok(Ok(received)) => Ok(Some(received)),
            Ok(Err(e)) => Err(self.problem(PortError::Io(e))),
            Err(RecvTimeoutError::Timeout) => Ok(None),
            Err(RecvTimeoutError::Disconnected) => {
                Err(self.problem(PortError::Io("the port closed".to_string())))
            }
        }
    }

    /// A line received already, if any (does not wait).
    pub fn try_line(&mut self) -> Result<Option<Received>, Error> {
        self.next_line(Instant::now())
    }

    /// Sends a line and reads its reply (resynchronising after a `# warning:`, see the module
    /// documentation).
    pub fn request(&mut self, line: &str) -> Result<Reply, Error> {
        self.send_line(line)?;
        self.read_reply(line)
    }

    /// Reads the reply to `line`, just sent.
    pub fn read_reply(&mut self, line: &str) -> Result<Reply, Error> {
        let until = Instant::now() + self.timeout;
        let mut reply = Reply {
            data: Vec::new(),
            notices: Vec::new(),
            last: String::new(),
            at: Instant::now(),
        };
        loop {
            let Some(received) = self.next_line(until)? else {
                return Err(self.no_reply(line));
            };
            let text = received.line;
            if is_final(&text) {
                reply.last = text;
                reply.at = received.at;
                return Ok(reply);
            }
            if is_notice(&text) {
                let lost = is_input_lost(&text);
                reply.notices.push(text);
                if lost {
                    return self.resynchronise(line, reply);
                }
            } else {
                reply.data.push(text);
            }
        }
    }

    /// After a warning: a line end, `status`, and its reply; the first final reply before it
    /// is `line`'s, if it got one.
    fn resynchronise(&mut self, line: &str, mut reply: Reply) -> Result<Reply, Error> {
        self.send_line("")?;
        self.send_line("status")?;
        let until = Instant::now() + self.timeout;
        let mut ours: Option<String> = None;
        let mut in_status = false;
        loop {
            let Some(received) = self.next_line(until)? else {
                return Err(self.no_reply("status"));
            };
            let text = received.line;
            if text.starts_with("# state:") {
                in_status = true;
            } else if is_final(&text) {
                if in_status {
                    break;
                }
                if ours.is_none() {
                    ours = Some(text);
                    reply.at = received.at;
                }
            } else if is_notice(&text) {
                reply.notices.push(text);
            } else if !in_status {
                reply.data.push(text);
            }
        }
        match ours {
            Some(last) => {
                reply.last = last;
                Ok(reply)
            }
            None => Err(self.problem(PortError::LineLost {
                line: line.to_string(),
            })),
        }
    }

    /// [`Link::request`], and a refusal is an error (the board's words).
    pub fn request_ok(&mut self, line: &str) -> Result<Reply, Error> {
        let reply = self.request(line)?;
        if reply.is_ok() {
            Ok(reply)
        } else {
            Err(Error::Refused {
                at: None,
                port: self.port.clone(),
                line: line.to_string(),
                reply: reply.last,
            })
        }
    }

    /// The error for a line that got no reply in time.
    pub fn no_reply(&self, line: &str) -> Error {
        self.problem(PortError::NoReply {
            line: line.to_string(),
            waited_s: self.timeout.as_secs_f64(),
        })
    }

    /// The error for a reply that cannot be read.
    pub fn unreadable(&self, line: &str, reply: &str) -> Error {
        self.problem(PortError::Unreadable {
            line: line.to_string(),
            reply: reply.to_string(),
        })
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        self.wanted.store(false, Ordering::Relaxed);
    }
}

/// The reader thread: bytes -> lines (CR LF, LF or CR), prompts (`> `) taken off, blank lines
/// dropped. Ends when the port fails (after saying why) or nobody listens any more.
fn read_lines(
    mut port: Box<dyn SerialPort>,
    lines: mpsc::Sender<Result<Received, String>>,
    wanted: Arc<AtomicBool>,
) {
    let mut buffer = [0u8; 512];
    let mut line: Vec<u8> = Vec::new();
    loop {
        let n = match port.read(&mut buffer) {
            Ok(0) => continue,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {
                if !wanted.load(Ordering::Relaxed) {
                    return; // the link was dropped
                }
                continue;
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => {
                let _ = lines.send(Err(e.to_string()));
                return;
            }
        };
        let at = Instant::now();
        for &byte in &buffer[..n] {
            if byte != b'\n' && byte != b'\r' {
                line.push(byte);
                continue;
            }
            let text = String::from_utf8_lossy(&line).into_owned();
            line.clear();
            let mut text = text.as_str();
            while let Some(rest) = text.strip_prefix("> ") {
                text = rest;
            }
            if text.is_empty() {
                continue;
            }
            if lines
                .send(Ok(Received {
                    at,
                    line: text.to_string(),
                }))
                .is_err()
            {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use control::report::{write_notice, Notice};

    #[test]
    fn the_board_s_lost_input_warnings_are_recognised_and_nothing_else() {
        for in_uart in [false, true] {
            let mut text = String::new();
            write_notice(
                &mut text,
                &Notice::InputLost {
                    at_least: 7,
                    in_uart,
                },
            );
            let line = text.trim_end();
            assert!(is_notice(line) && is_input_lost(line), "{line}");
        }
        // The count at the end of a burst of UART errors: input was lost after the first
        // warning too (the host resynchronises again).
        let mut text = String::new();
        write_notice(
            &mut text,
            &Notice::InputLostBurst {
                losses: 3,
                at_least: 5,
                over_s: 0.5,
            },
        );
        let line = text.trim_end();
        assert!(is_notice(line) && is_input_lost(line), "{line}");
        let mut text = String::new();
        write_notice(&mut text, &Notice::NoSavedSettings(None));
        let line = text.trim_end();
        assert!(is_notice(line) && !is_input_lost(line), "{line}");
        assert!(is_final("ok") && is_final("error:busy x") && !is_final("# ok"));
    }
}
