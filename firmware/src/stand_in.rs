//! Stand-in for `control::Controller` until the real command interpreter is wired in.
//!
//! It has the same board-facing shape (banner, bytes in with replies out, receive overflow,
//! six pulse widths per frame, settings getters) so swapping it for the real one touches
//! only `main.rs`. Behaviour, like the real one's defaults: echoes what is typed (backspace
//! or DEL erases), ends a line at LF, CRLF or a lone CR, answers every non-blank line with
//! exactly one final reply followed by a `> ` prompt, and holds all six servos at the home
//! pulse. It knows no commands.

use core::fmt::Write;

use heapless::Vec;

use crate::servo_pwm::{PulseWindowUs, FRAME_HZ_DEFAULT, SERVO_COUNT};

const LINE_MAX_BYTES: usize = 96;
const HOME_PULSE_US: f32 = 1500.0;
const EOL: &str = "\r\n";
const PROMPT: &str = "> ";

pub struct Controller {
    line: Vec<u8, LINE_MAX_BYTES>,
    line_too_long: bool,
    rx_overflow: bool,
    last_was_cr: bool,
}

impl Controller {
    pub const fn new() -> Self {
        Controller {
            line: Vec::new(),
            line_too_long: false,
            rx_overflow: false,
            last_was_cr: false,
        }
    }

    /// The start-up banner, then the prompt.
    pub fn banner(&mut self, out: &mut impl Write) {
        let _ = write!(
            out,
            "hexapod-fw {} ready - type 'help'{EOL}{PROMPT}",
            env!("CARGO_PKG_VERSION")
        );
    }

    /// Feeds one received byte: echo, line editing, and at the end of a line its reply.
    /// (Writing into the serial buffer cannot fail, so results are ignored.)
    pub fn on_byte(&mut self, byte: u8, out: &mut impl Write) {
        let after_cr = core::mem::replace(&mut self.last_was_cr, byte == b'\r');
        match byte {
            b'\n' if after_cr => {} // the LF of a CRLF: the CR already ended the line
            b'\r' | b'\n' => {
                let _ = out.write_str(EOL);
                self.reply(out);
                let _ = out.write_str(PROMPT);
                self.line.clear();
                self.line_too_long = false;
                self.rx_overflow = false;
            }
            0x08 | 0x7f => {
                if self.line.pop().is_some() {
                    let _ = out.write_str("\x08 \x08");
                }
            }
            _ => {
                if self.line.push(byte).is_ok() {
                    let _ = out.write_char(printable(byte));
                } else {
                    self.line_too_long = true;
                }
            }
        }
    }

    /// The board dropped received bytes: the line they belonged to is refused when it ends.
    pub fn on_rx_overflow(&mut self, _dropped: u32, _out: &mut impl Write) {
        self.rx_overflow = true;
    }

    /// Pulse widths (us) for the frame that starts next.
    pub fn on_frame(&mut self) -> [f32; SERVO_COUNT] {
        [HOME_PULSE_US; SERVO_COUNT]
    }

    pub fn frame_hz(&self) -> u16 {
        FRAME_HZ_DEFAULT
    }

    pub fn baud(&self) -> u32 {
        115_200
    }

    /// The range each servo's pulse must stay in (the board clamps to it as a last resort).
    pub fn pulse_windows_us(&self) -> [PulseWindowUs; SERVO_COUNT] {
        [PulseWindowUs {
            min_us: 500.0,
            max_us: 2500.0,
        }; SERVO_COUNT]
    }

    fn reply(&self, out: &mut impl Write) {
        let word = self
            .line
            .split(|b| b.is_ascii_whitespace())
            .find(|word| !word.is_empty());
        let _ = match word {
            _ if self.rx_overflow => write!(out, "error:rx-overflow{EOL}"),
            _ if self.line_too_long => write!(out, "error:line-too-long{EOL}"),
            None => Ok(()), // blank line: no reply
            Some(b"help") => write!(out, "placeholder firmware: no commands yet{EOL}ok{EOL}"),
            Some(word) => {
                let _ = out.write_str("error:unknown-command ");
                word.iter().for_each(|&b| {
                    let _ = out.write_char(printable(b));
                });
                out.write_str(EOL)
            }
        };
    }
}

fn printable(byte: u8) -> char {
    if byte.is_ascii_graphic() || byte == b' ' {
        char::from(byte)
    } else {
        '?'
    }
}
