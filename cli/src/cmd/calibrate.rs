//! `hexapod calibrate`: the guided calibration in the terminal (docs/geometry-and-calibration.md,
//! "Calibration"). Servo by servo, the user brings the arm level with `servo N us` steps (keys
//! typed, a line at a time: `+ - [ ]`, a pulse, Enter, `q`); the trim is taken from that pulse
//! (`crate::calibration`); the six trims are set; the platform is checked at home and at a few
//! poses against a level and a ruler; then the build file is written (its other keys and
//! comments kept) and the board `save`s.
//!
//! Safe throughout: every pulse sent is within the servo's limits; quitting (`q`, Ctrl-C, the
//! end of input) or an error midway puts back what was changed, the pulses and the trims, and
//! leaves the board's settings as they were, unsaved, the platform at home.
//!
//! Every word the flow writes is here (its prompts and summary); the board's words as it wrote
//! them.

use std::io::{BufRead, Write};
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::thread;
use std::time::{Duration, Instant};

use clap::Args;
use control::settings::{ServoParam, ServoSel, SettingId, SettingValue, Settings};
use kinematics_core::LEGS;

use super::{on_ctrl_c, Port, CTRL_C};
use crate::board;
use crate::build_file;
use crate::calibration::{
    self, level_pulse, read_line, trim_from_level, within_limits, Typed, CHECKS,
};
use crate::error::{Error, PortError};
use crate::files::{read_text, write_new};
use crate::link::Link;
use crate::sizing::Sizing;

/// How long the platform may take to come to rest after a move.
const SETTLE_TIMEOUT: Duration = Duration::from_secs(60);
/// How often `status` is asked while waiting for rest.
const SETTLE_POLL: Duration = Duration::from_millis(100);

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    port: Port,
    /// The build file to write: if it exists, its trims are replaced and its other keys and
    /// comments kept; otherwise a commented file of the board's settings
    #[arg(short, long, default_value = "build.toml")]
    output: PathBuf,
    /// Do not `save` on the board at the end (the trims last until it restarts)
    #[arg(long)]
    no_save: bool,
}

impl Cmd {
    /// The flow; the summary (or, quit, what was put back).
    pub fn run(self) -> Result<String, Error> {
        let name = self.output.display().to_string();
        // A build file that exists must read before anything moves.
        let existing = match self.output.exists() {
            true => {
                let text = read_text(&self.output)?;
                build_file::parse(&name, &text)?;
                Some(text)
            }
            false => None,
        };
        let mut link = self.port.open()?;
        link.start()?;
        let settings = board::read_settings(&mut link)?;
        on_ctrl_c();
        let mut flow = Flow {
            link,
            settings,
            input: Input::start(),
            driven: [false; LEGS],
            trims_set: false,
        };
        let outcome = flow.run();
        let trims = match outcome {
            Ok(Some(trims)) => trims,
            Ok(None) => {
                flow.put_back()?;
                return Ok(PUT_BACK.to_string());
            }
            Err(error) => {
                // Best effort: the error is what the user must read.
                let _ = flow.put_back();
                return Err(error);
            }
        };
        // The build file, then `save`.
        let mut settings = flow.settings;
        for (i, trim) in trims.iter().enumerate() {
            settings = settings.with(trim_id(i), SettingValue::Number(*trim));
        }
        let text = match &existing {
            Some(text) => {
                let text = calibration::with_trims(text, &trims);
                let file = build_file::parse(&name, &text)?;
                if (0..LEGS).any(|i| file.settings.servos.0[i].home_us != trims[i]) {
                    return Err(Error::TrimsNotWritten { file: name });
                }
                text
            }
            None => build_file::write(
                &settings,
                &Sizing::default(),
                &format!("the board on {}, calibrated", flow.link.port()),
            ),
        };
        write_new(&self.output, text.as_bytes(), true)?;
        let differ = existing.map(|_| differences(&settings, &name));
        if !self.no_save {
            flow.link.request_ok("save")?;
        }
        Ok(summary(
            &trims,
            &name,
            flow.link.port(),
            !self.no_save,
            differ.transpose()?.unwrap_or_default(),
        ))
    }
}

/// `servoN.trim_us` for servo index `i` (0-based).
fn trim_id(i: usize) -> SettingId {
    SettingId::Servo(ServoSel::One(i as u8 + 1), ServoParam::TrimUs)
}

/// The settings the file written says other than the board's (names), none if it says the same.
fn differences(board: &Settings, file: &str) -> Result<Vec<String>, Error> {
    let written = build_file::read(std::path::Path::new(file))?.settings;
    let mut ids: Vec<SettingId> = SettingId::GLOBAL.to_vec();
    for servo in 1..=LEGS as u8 {
        for param in ServoParam::ALL {
            ids.push(SettingId::Servo(ServoSel::One(servo), param));
        }
    }
    Ok(ids
        .into_iter()
        .filter(|&id| {
            let text = |s: &Settings| {
                s.get(id)
                    .map(|v| control::report::ValueText(id, v).to_string())
            };
            text(board) != text(&written)
        })
        .map(|id| id.to_string())
        .collect())
}

/// The flow's state: what it changed, so that it can put it back.
struct Flow {
    link: Link,
    /// The board's settings at the start.
    settings: Settings,
    input: Input,
    /// Servos driven with `servo` (index from 0).
    driven: [bool; LEGS],
    /// The new trims are set on the board.
    trims_set: bool,
}

/// A step's outcome: go on, or the user quit.
type Step<T> = Result<Option<T>, Error>;

impl Flow {
    /// The whole flow; the trims, or `None` if the user quit.
    fn run(&mut self) -> Step<[f32; LEGS]> {
        let solver = self.settings.validate().map_err(|_| {
            self.link
                .unreadable("config", "settings the board could not hold")
        })?;
        say(&intro(self.link.port()));
        self.home_from_anywhere()?;
        let mut trims = [0.0; LEGS];
        for (i, trim) in trims.iter_mut().enumerate() {
            match self.trim_servo(i, solver.alpha0_rad(i))? {
                Some(t) => *trim = t,
                None => return Ok(None),
            }
        }
        for (i, trim) in trims.iter().enumerate() {
            self.link
                .request_ok(&format!("set {} {trim}", trim_id(i)))?;
            self.trims_set = true;
        }
        self.link.request_ok("home")?;
        self.settle()?;
        say(&trimmed(&trims, &self.settings));
        let h0 = solver.geometry().home_height_mm();
        for check in &CHECKS {
            let reply = self.link.request(&check.line())?;
            if !reply.is_ok() {
                say(&check_refused(&check.line(), &reply.last));
                continue;
            }
            self.settle()?;
            say(&check_prompt(check, h0));
            if !self.enter_or_quit()? {
                return Ok(None);
            }
        }
        self.link.request_ok("home")?;
        self.settle()?;
        Ok(Some(trims))
    }

    /// The platform at home before the first servo: `home`, or, when the pulses set with
    /// `servo` put the platform at no pose (`home` is then refused), each servo to its trim.
    fn home_from_anywhere(&mut self) -> Result<(), Error> {
        if self.link.request("stop")?.is_ok() && self.link.request("home")?.is_ok() {
            return self.settle();
        }
        for (i, servo) in self.settings.servos.0.iter().enumerate() {
            self.link
                .request_ok(&format!("servo {} {}", i + 1, servo.home_us))?;
        }
        self.link.request_ok("home")?;
        self.settle()
    }

    /// One servo brought level; its trim, or `None` if the user quit.
    fn trim_servo(&mut self, i: usize, alpha0_rad: f32) -> Step<f32> {
        let servo = self.settings.servos.0[i];
        let mut pulse = level_pulse(&servo, alpha0_rad);
        self.drive(i, pulse)?;
        say(&servo_intro(i + 1, alpha0_rad.to_degrees()));
        loop {
            prompt(&servo_prompt(i + 1, pulse));
            let Some(line) = self.input.line() else {
                return Ok(None);
            };
            let wanted = match read_line(&line) {
                Typed::Quit => return Ok(None),
                Typed::Unknown => {
                    say(KEYS);
                    continue;
                }
                Typed::Accept => {
                    let trim = trim_from_level(&servo, alpha0_rad, pulse);
                    if !servo.allows(trim) {
                        say(&trim_outside(i + 1, trim, servo.min_us, servo.max_us));
                        continue;
                    }
                    say(&servo_done(i + 1, trim, servo.home_us));
                    return Ok(Some(trim));
                }
                Typed::Step(step) => pulse + step,
                Typed::Pulse(us) => us,
            };
            if !servo.allows(wanted) {
                say(&at_limit(i + 1, servo.min_us, servo.max_us));
            }
            let next = within_limits(&servo, wanted);
            if next != pulse {
                pulse = next;
                self.drive(i, pulse)?;
            }
        }
    }

    /// `servo N us`.
    fn drive(&mut self, i: usize, pulse: f32) -> Result<(), Error> {
        self.driven[i] = true;
        self.link
            .request_ok(&format!("servo {} {pulse}", i + 1))
            .map(|_| ())
    }

    /// Enter: `true`; `q`, Ctrl-C or the end of input: `false`.
    fn enter_or_quit(&mut self) -> Result<bool, Error> {
        loop {
            prompt(NEXT);
            let Some(line) = self.input.line() else {
                return Ok(false);
            };
            match read_line(&line) {
                Typed::Accept => return Ok(true),
                Typed::Quit => return Ok(false),
                _ => say(NEXT_KEYS),
            }
        }
    }

    /// Waits until the platform is at rest (`status`: not moving).
    fn settle(&mut self) -> Result<(), Error> {
        let until = Instant::now() + SETTLE_TIMEOUT;
        loop {
            let reply = self.link.request_ok("status")?;
            let state = reply.value("state").unwrap_or("");
            let moving = ["moving", "returning", "going"]
                .iter()
                .any(|w| state.starts_with(w));
            if !moving {
                return Ok(());
            }
            if Instant::now() > until {
                return Err(Error::Port {
                    port: self.link.port().to_string(),
                    why: PortError::StillMoving {
                        waited_s: SETTLE_TIMEOUT.as_secs_f64(),
                    },
                });
            }
            thread::sleep(SETTLE_POLL);
        }
    }

    /// Puts back what the flow changed: the trims, the pulses, the platform at home.
    fn put_back(&mut self) -> Result<(), Error> {
        // A move in progress (a check pose) ends first: settings wait for rest.
        self.settle()?;
        if self.trims_set {
            self.link.request_ok("home")?;
            self.settle()?;
            for (i, servo) in self.settings.servos.0.iter().enumerate() {
                self.link
                    .request_ok(&format!("set {} {}", trim_id(i), servo.home_us))?;
            }
            self.trims_set = false;
        }
        for (i, servo) in self.settings.servos.0.iter().enumerate() {
            if self.driven[i] {
                self.link
                    .request_ok(&format!("servo {} {}", i + 1, servo.home_us))?;
                self.driven[i] = false;
            }
        }
        self.link.request_ok("home")?;
        self.settle()
    }
}

/// Standard input's lines, read on a thread so that Ctrl-C is seen while waiting.
struct Input {
    lines: Receiver<String>,
}

impl Input {
    fn start() -> Input {
        let (sender, lines) = mpsc::channel();
        thread::spawn(move || {
            for line in std::io::stdin().lock().lines() {
                let Ok(line) = line else { return };
                if sender.send(line).is_err() {
                    return;
                }
            }
        });
        Input { lines }
    }

    /// The next line; `None` at the end of input or on Ctrl-C.
    fn line(&mut self) -> Option<String> {
        loop {
            if CTRL_C.load(Ordering::SeqCst) {
                return None;
            }
            match self.lines.recv_timeout(Duration::from_millis(50)) {
                Ok(line) => return Some(line),
                Err(RecvTimeoutError::Timeout) => continue,
                Err(RecvTimeoutError::Disconnected) => return None,
            }
        }
    }
}

/// A line for the user.
fn say(text: &str) {
    println!("{text}");
}

/// A prompt (no line end).
fn prompt(text: &str) {
    let mut out = std::io::stdout().lock();
    let _ = write!(out, "{text}");
    let _ = out.flush();
}

// The words.

/// Before anything moves.
fn intro(port: &str) -> String {
    format!(
        "Calibrating the board on {port}.\n\
         Servos powered, rods unhooked from the arms (the arms turn freely); a small spirit \
         level or a square for the arms, a level and a ruler for the platform.\n\
         Quit at any time with q (or Ctrl-C): the pulses and trims are put back, nothing is \
         saved.\n\
         The platform goes home first."
    )
}

/// The keys, once per servo.
const KEYS: &str = "keys, then Enter: + or - a 1 us step, ] or [ a 10 us step (several in a \
                    line add up, e.g. ]]+), a number goes to that pulse in us; Enter alone: the \
                    arm is level, take it; q: quit";

/// A servo's turn.
fn servo_intro(servo: usize, alpha0_deg: f32) -> String {
    format!(
        "\nServo {servo}: bring its arm level (horizontal: a level on the arm, or the arm \
         parallel to the base plate), pointing as in `geometry`. Its home angle alpha0 is \
         {alpha0_deg:.3} degrees; the tool turns level into the trim for you.\n{KEYS}"
    )
}

/// The prompt while stepping a servo.
fn servo_prompt(servo: usize, pulse: f32) -> String {
    format!("servo {servo} at {pulse:.2} us> ")
}

/// A step clamped.
fn at_limit(servo: usize, min_us: f32, max_us: f32) -> String {
    format!(
        "servo {servo}: kept within its limits {min_us:.2}..{max_us:.2} us (servo{servo}.min_us, \
         max_us): if the arm cannot reach level within them, remount it a spline tooth closer"
    )
}

/// A trim outside the servo's limits.
fn trim_outside(servo: usize, trim: f32, min_us: f32, max_us: f32) -> String {
    format!(
        "servo {servo}: that makes trim_us {trim:.2}, outside its limits {min_us:.2}..{max_us:.2} \
         us: remount the arm a spline tooth closer to level, or widen the limits first"
    )
}

/// A servo done.
fn servo_done(servo: usize, trim: f32, was: f32) -> String {
    format!("servo {servo}: trim_us {trim:.2} (was {was:.2})")
}

/// The six trims set.
fn trimmed(trims: &[f32; LEGS], settings: &Settings) -> String {
    let list: Vec<String> = trims.iter().map(|t| format!("{t:.2}")).collect();
    let was: Vec<String> = settings
        .servos
        .0
        .iter()
        .map(|s| format!("{:.2}", s.home_us))
        .collect();
    format!(
        "\nTrims set on the board (not saved yet): {} us (were {}).\n\
         Now hook the rods to the arms (the platform stays at home), then check it at a few \
         poses.",
        list.join(" "),
        was.join(" ")
    )
}

/// A check pose reached.
fn check_prompt(check: &calibration::Check, h0_mm: f32) -> String {
    let mut text = format!("\n{}: {}", check.line(), check.measure);
    if check.pose == [0.0; 6] {
        text.push_str(&format!(
            " (the rod joints' centres are h0 = {h0_mm:.1} mm above the servo shafts)"
        ));
    }
    text.push_str(
        ".\nIf it is off: an arm a tooth off (redo its servo), a servo turning the wrong way \
         (servoN.dir), the servo rate (servos.rate_us_rad) or the geometry (docs/\
         geometry-and-calibration.md).",
    );
    text
}

/// A check pose refused.
fn check_refused(line: &str, reply: &str) -> String {
    format!("\n{line}: the board refused it ({reply}); the next check")
}

/// The prompt between checks.
const NEXT: &str = "Enter: good, the next; q: quit (the trims are put back)> ";
/// Anything else typed there.
const NEXT_KEYS: &str = "Enter alone goes on; q quits";

/// Quit: what was put back.
const PUT_BACK: &str = "calibration stopped: the pulses and trims are as they were, the \
                        platform at home, nothing saved";

/// Done.
fn summary(
    trims: &[f32; LEGS],
    file: &str,
    port: &str,
    saved: bool,
    differ: Vec<String>,
) -> String {
    let list: Vec<String> = trims
        .iter()
        .enumerate()
        .map(|(i, t)| format!("servo{}.trim_us = {t:.2}", i + 1))
        .collect();
    let saved = if saved {
        "saved in flash (the board starts with them at power-up)"
    } else {
        "not saved (--no-save): they last until the board restarts"
    };
    let mut text = format!(
        "calibrated: {}\n{file}: written with these trims; on the board on {port}, {saved}",
        list.join(", ")
    );
    if !differ.is_empty() {
        text.push_str(&format!(
            "\n{file} says other values than the board for: {} (the file keeps its own; \
             `hexapod apply {file} --port {port}` would send them)",
            differ.join(", ")
        ));
    }
    text
}
