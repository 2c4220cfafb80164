//! Stand-in for `control::Controller` until the real command interpreter is wired in.
//!
//! It has the same shape (bytes in, replies out, six pulse widths per frame, settings
//! getters) so swapping it for the real one touches only `main.rs`. Behaviour: assembles
//! lines (LF, CRLF or a lone CR end a line; backspace or DEL deletes the last character),
//! answers every line with exactly one final reply, and holds all six servos at the home
//! pulse.

use core::fmt::Write;

use heapless::Vec;

use crate::servo_pwm::{PulseWindowUs, FRAME_HZ_DEFAULT, SERVO_COUNT};

const LINE_MAX_BYTES: usize = 96;
const HOME_PULSE_US: f32 = 1500.0;

pub struct Controller {
    line: Vec<u8, LINE_MAX_BYTES>,
    line_too_long: bool,
    last_was_cr: bool,
}

impl Controller {
    pub const fn new() -> Self {
        Controller {
            line: Vec::new(),
            line_too_long: false,
            last_was_cr: false,
        }
    }

    /// Feeds one received byte; writes the reply when it completes a line.
    pub fn on_byte(&mut self, byte: u8, out: &mut impl Write) {
        let after_cr = core::mem::replace(&mut self.last_was_cr, byte == b'\r');
        match byte {
            b'\n' if after_cr => {} // the LF of a CRLF: the CR already ended the line
            b'\r' | b'\n' => {
                self.reply(out);
                self.line.clear();
                self.line_too_long = false;
            }
            0x08 | 0x7f => {
                self.line.pop();
            }
            _ => {
                if self.line.push(byte).is_err() {
                    self.line_too_long = true;
                }
            }
        }
    }

    /// Pulse widths (us) for the frame that starts next.
    pub fn on_frame(&mut self) -> [f32; SERVO_COUNT] {
        [HOME_PULSE_US; SERVO_COUNT]
    }

    pub fn frame_rate_hz(&self) -> u16 {
        FRAME_HZ_DEFAULT
    }

    pub fn baud(&self) -> u32 {
        115_200
    }

    pub fn pulse_window_us(&self) -> PulseWindowUs {
        PulseWindowUs {
            min_us: 500.0,
            max_us: 2500.0,
        }
    }

    fn reply(&self, out: &mut impl Write) {
        let line = self.line.as_slice();
        let word = line
            .split(|b| b.is_ascii_whitespace())
            .find(|word| !word.is_empty())
            .unwrap_or(&[]);
        // Writing into the serial buffer cannot fail.
        let _ = if self.line_too_long {
            out.write_str("error:line-too-long\r\n")
        } else if word.is_empty() {
            out.write_str("ok\r\n")
        } else if word == b"help" {
            out.write_str("placeholder firmware: no commands yet\r\nok\r\n")
        } else {
            write_unknown(word, out)
        };
    }
}

fn write_unknown(word: &[u8], out: &mut impl Write) -> core::fmt::Result {
    out.write_str("error:unknown-command ")?;
    for &byte in word {
        let shown = if byte.is_ascii_graphic() {
            char::from(byte)
        } else {
            '?'
        };
        out.write_char(shown)?;
    }
    out.write_str("\r\n")
}
