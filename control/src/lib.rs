//! The hardware-independent heart of the hexapod firmware: everything between "bytes arrived
//! on a serial link" and "six pulse widths to put on the PWM pins". `no_std`, no allocation,
//! `f32`.
//!
//! ```text
//! bytes -> session (the link's line assembly, echo) -> command (parse) -> Controller (check
//!       target and path with the IK, settings) -> motion (one pose per frame) -> IK -> pulses
//!                              every word the user reads: report
//! ```
//!
//! This list is the crate's one map (ARCHITECTURE.md and `control/README.md` link here):
//!
//! - [`session`]: one serial link's state: line buffer ([`protocol`]), echo, prompt, notices
//!   shown; a fresh start when the link opens again.
//! - [`protocol`]: bytes -> lines (terminal line editing, like grbl's `protocol`/`serial`) and
//!   stream frames among them; [`stream`]: the stream frames' grammar (binary, SimTools text),
//!   `Frame`, and what their counts mean (the `stream.*` settings); a leaf `protocol` uses.
//! - [`number`]: strict decimal parsing (short decimals by one exact `f32` division, the rest
//!   by core's parser); [`word`]: quoting what the user typed.
//! - [`command`]: one line -> one [`command::Command`] or a [`command::ParseError`] (like
//!   grbl's `gcode`); [`command::Verb`] is the list of command words.
//! - [`settings`]: [`Settings`] (the platform's) and [`settings::LinkSettings`] (`baud`,
//!   `echo`): names, meanings, ranges and defaults for `set`, [`settings::SettingError`];
//!   [`record`]: their binary form for flash (magic, version, sequence number, CRC-32);
//!   [`store`]: the two flash sectors used in turn (A/B) over a small [`store::NorFlash`]
//!   trait the board implements, so a power cut during a save never loses the last good one.
//! - [`motion`]: straight-line moves at bounded speed and acceleration (trapezoid), path
//!   checks; `motion::blend`: a new target while moving, from the pose and velocity there
//!   into the straight line, within the acceleration limits; [`tracker`]: the stream tracker (per-axis speed and acceleration limits,
//!   time-optimal, no overshoot; in integers: fixed-point positions, an exact discrete braking
//!   rule with an integer square root).
//! - [`payload`]: the payload carried and the servos' torque ratings: holding torques in
//!   kgf cm from `kinematics_core::statics`, [`payload::TorqueError`].
//! - [`servo_speed`]: the servos' rated speeds, and how moves and stream steps are slowed so
//!   that no arm turns faster than its rating ([`servo_speed::ServoSpeeds`], the path time a
//!   path check measures).
//! - [`safety`]: the e-stop input's and servo-power output's settings, the e-stop latch.
//! - [`error`]: [`Error`], why a line is refused (each layer's error type gathered).
//! - [`report`]: every reply, error code and message, data line and notice, worded once (the
//!   output conventions are documented there): `errors` (codes and messages, and the
//!   generated list `docs/error-codes.md`), `format` (numbers, poses, values), `replies` (the
//!   writers: status, config, help, notices, echo).
//! - [`controller`]: [`Controller`], the platform's state, which ties them together. `mod.rs`
//!   holds the state, the public API and the dispatch (a line to its command in `run`, a slice
//!   to the job in progress in `work`, a frame to the motion in `on_frame`). The jobs done a
//!   slice at a time are one state machine per file, each its own type with a `step`, knowing
//!   nothing of the controller: `path` (a target's straight path checked), `stream_goal`
//!   (what a stream follows; the clamp of a target out of reach), `locate` (`servo`'s forward
//!   kinematics along a continuation), `rebuild` (new build numbers' geometry and IK), `save`
//!   (the board's flash write), `listing` (a listing a line per slice; `status`' torques),
//!   `limits`, sharing `pose_check` (whether a pose can be taken); `loss_burst` (a burst of
//!   UART receive errors, counted for one notice). What the controller does
//!   with them is one `impl Controller` file per job: `moves`, `streaming`, `servo`,
//!   `settings_change`, `link_loss`, `estop`, `status`, `notices`.
//!
//! Each layer returns an error enum with the payload (which field, leg, servo, limit) and words
//! nothing; [`report`] words everything, and host programs print the board's own words through
//! it ([`report::refusal`]). `examples/repl.rs` talks to the controller on the host
//! (`cargo run -p control --example repl`); `examples/documents.rs` writes the generated
//! documents.
//!
//! The board keeps one [`Session`] per serial link and uses it like this, in a main loop whose
//! every pass does little (a command's long work is done a slice per pass):
//!
//! ```
//! # use core::fmt::Write;
//! let mut out = String::new(); // the board writes into the link's transmit queue
//! let mut ctl = control::Controller::new(control::Settings::default());
//! let mut uart = control::Session::new();
//! ctl.banner(&mut uart, &mut out);
//! let mut received = b"pose 0 0 5 0 0 0\r".iter();
//! loop {
//!     if ctl.is_busy() {
//!         ctl.work(&mut uart, &mut out); // a slice of a command's work; its reply at the end
//!     } else if let Some(&byte) = received.next() {
//!         ctl.on_byte(&mut uart, byte, &mut out); // echo, editing; at a line end, the command
//!     } else {
//!         break;
//!     }
//! }
//! assert!(out.contains("\r\nok\r\n"));
//! let generation = ctl.settings_generation();
//! // once per servo frame (1 / frame_hz s):
//! let pulses_us: [f32; 6] = ctl.on_frame();
//! assert!(pulses_us.iter().all(|w| w.is_finite()));
//! ctl.write_notices(&mut uart, &mut out); // for every link
//! // after a reply, reconfigure if the settings changed:
//! if ctl.settings_generation() != generation {
//!     let (_baud, _frame_hz) = (ctl.baud(), ctl.frame_hz());
//! }
//! ```
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

pub mod command;
pub mod controller;
pub mod error;
pub mod motion;
pub mod number;
pub mod payload;
pub mod protocol;
pub mod record;
pub mod report;
pub mod safety;
pub mod servo_speed;
pub mod session;
pub mod settings;
pub mod store;
pub mod stream;
pub mod tracker;
pub mod word;

pub use controller::Controller;
pub use error::Error;
pub use report::Code;
pub use session::Session;
pub use settings::Settings;

pub use kinematics_core::Pose;

/// Helpers shared by the unit tests.
#[cfg(test)]
mod test_support {
    /// A xorshift32 sequence from `seed` (seeded, reproducible test inputs): each call the next.
    pub(crate) fn xorshift(mut seed: u32) -> impl FnMut() -> u32 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        }
    }
}
