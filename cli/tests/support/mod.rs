//! A board for the tool's tests, without hardware or emulator: the firmware's own controller
//! (`control::Controller`, the code the Pico runs, with `libm` maths) behind a pseudo-terminal,
//! driven like the firmware's main loop (bytes fed up to a line end, long work a slice at a
//! time, stream frames applied, a servo frame every 1 / frame_hz s, `save` into an in-memory
//! NOR flash). The tool opens the pseudo-terminal's path as it would a real port. The end-to-end
//! tests of the real firmware in the emulator are `emulator/test/cli.test.js`.

#![allow(dead_code)]

use std::collections::VecDeque;
use std::io::{Read, Write};
use std::path::PathBuf;
use std::process::{Command, Output};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::thread::{self, JoinHandle};
use std::time::{Duration, Instant};

use control::controller::Fed;
use control::store::{RamFlash, Store};
use control::{Controller, Session};
use serialport::{SerialPort, TTYPort};

/// What the board was left with when it stopped.
pub struct Finished {
    /// Its settings.
    pub settings: control::Settings,
    /// Its flash.
    pub flash: RamFlash,
    /// The pulses of its last servo frame, us.
    pub pulses_us: [f32; 6],
    /// The pose it holds.
    pub pose: control::Pose,
    /// Every byte it received.
    pub received: Vec<u8>,
}

/// A simulated board on a pseudo-terminal.
pub struct SimBoard {
    /// The port path to give the tool.
    pub path: String,
    stop: Arc<AtomicBool>,
    /// Lines answered so far.
    pub answered: Arc<AtomicUsize>,
    thread: Option<JoinHandle<Finished>>,
    _terminal: TTYPort,
}

impl SimBoard {
    /// A board with nothing saved, answering every line.
    pub fn start() -> SimBoard {
        SimBoard::start_with(RamFlash::new(), None)
    }

    /// A board with this flash, that stops answering after `answer_lines` lines (if given).
    pub fn start_with(flash: RamFlash, answer_lines: Option<usize>) -> SimBoard {
        SimBoard::start_full(flash, answer_lines, None)
    }

    /// A board that loses the bytes of line number `lost_line` (from 0, counting every line
    /// received) as the firmware's receive queue loses bytes: a `# warning:` at once, and the
    /// line the gap cuts refused (`error:rx-overflow`).
    pub fn start_losing(lost_line: usize) -> SimBoard {
        SimBoard::start_full(RamFlash::new(), None, Some(lost_line))
    }

    fn start_full(
        flash: RamFlash,
        answer_lines: Option<usize>,
        lost_line: Option<usize>,
    ) -> SimBoard {
        let (controller_side, terminal) = TTYPort::pair().expect("a pseudo-terminal pair");
        let path = terminal.name().expect("the pseudo-terminal's path");
        let stop = Arc::new(AtomicBool::new(false));
        let answered = Arc::new(AtomicUsize::new(0));
        let thread = {
            let (stop, answered) = (Arc::clone(&stop), Arc::clone(&answered));
            thread::spawn(move || {
                run(
                    controller_side,
                    flash,
                    stop,
                    answered,
                    answer_lines,
                    lost_line,
                )
            })
        };
        SimBoard {
            path,
            stop,
            answered,
            thread: Some(thread),
            _terminal: terminal,
        }
    }

    /// Stops the board and returns what it was left with.
    pub fn finish(mut self) -> Finished {
        self.stop.store(true, Ordering::Relaxed);
        self.thread
            .take()
            .expect("running")
            .join()
            .expect("the board thread did not panic")
    }
}

impl Drop for SimBoard {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

/// What the board's receive queue holds: a byte, or the place where bytes were lost.
enum Input {
    Byte(u8),
    Gap(u32),
}

/// The board's main loop (see firmware/src/main.rs and control/README.md).
fn run(
    mut port: TTYPort,
    mut flash: RamFlash,
    stop: Arc<AtomicBool>,
    answered: Arc<AtomicUsize>,
    answer_lines: Option<usize>,
    lost_line: Option<usize>,
) -> Finished {
    port.set_timeout(Duration::from_millis(1)).expect("timeout");
    let mut ctl: Controller = Controller::power_up(Store::load(&mut flash));
    let mut session = Session::new();
    let mut out = String::new();
    let mut received = Vec::new();
    // Bytes waiting to be fed, and where bytes were lost (the firmware's receive queue).
    let mut waiting: VecDeque<Input> = VecDeque::new();
    let mut lines_received = 0usize;
    let mut dropped = 0u32;
    let mut pulses_us = ctl.pulses_us();
    ctl.banner(&mut session, &mut out);
    let mut next_frame = Instant::now();
    let mut buffer = [0u8; 256];
    let mut lines = 0usize;
    while !stop.load(Ordering::Relaxed) {
        let silent = answer_lines.is_some_and(|n| lines >= n);
        if let Ok(n) = port.read(&mut buffer) {
            received.extend_from_slice(&buffer[..n]);
            for &byte in &buffer[..n] {
                if lost_line == Some(lines_received) {
                    dropped += 1;
                    if byte == b'\n' {
                        ctl.on_input_lost(&mut session, dropped, false, &mut out);
                        waiting.push_back(Input::Gap(dropped));
                    }
                } else if !silent {
                    waiting.push_back(Input::Byte(byte));
                }
                if byte == b'\n' {
                    lines_received += 1;
                }
            }
        }
        if ctl.is_busy() {
            ctl.work(&mut session, &mut out);
        } else {
            while let Some(input) = waiting.pop_front() {
                match input {
                    Input::Byte(byte) => {
                        if ctl.on_byte(&mut session, byte, &mut out) == Fed::LineEnded {
                            lines += 1;
                            break;
                        }
                    }
                    Input::Gap(bytes) => ctl.on_rx_overflow(
                        &mut session,
                        control::protocol::Lost {
                            bytes,
                            in_uart: false,
                        },
                    ),
                }
            }
            ctl.apply_stream();
        }
        if let Some(write) = ctl.take_flash_write() {
            ctl.flash_written(write.perform(&mut flash));
        }
        if let Some(new) = ctl.take_new_pulses() {
            pulses_us = new;
        }
        if Instant::now() >= next_frame {
            next_frame += Duration::from_secs_f64(1.0 / f64::from(ctl.frame_hz()));
            pulses_us = ctl.on_frame();
            ctl.write_notices(&mut session, &mut out);
        }
        if !out.is_empty() {
            answered.store(lines, Ordering::Relaxed);
            let _ = port.write_all(out.as_bytes());
            out.clear();
        }
    }
    Finished {
        settings: *ctl.settings(),
        flash,
        pulses_us,
        pose: *ctl.pose(),
        received,
    }
}

/// Runs `hexapod` with these arguments, in `dir`.
pub fn hexapod(dir: &std::path::Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hexapod"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("hexapod runs")
}

/// A board with both speed limits off (pass-through), as streaming programs want it, set up
/// through the tool as a user would (`hexapod send`, run in `dir`).
pub fn pass_through_board(dir: &std::path::Path) -> SimBoard {
    let board = SimBoard::start();
    let setup = hexapod(
        dir,
        &[
            "send",
            "--port",
            &board.path,
            "set speed_mm_s off",
            "set speed_deg_s off",
        ],
    );
    assert!(setup.status.success(), "{:?}", text(&setup));
    board
}

/// Its standard output and error as text.
pub fn text(output: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

/// A fresh directory for a test's files.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hexapod-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    dir
}
