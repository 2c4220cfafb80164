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
//! - [`session`]: one link's state: line assembly ([`protocol`]), echo, prompt, notices shown.
//! - [`protocol`]: line assembly and line editing (like grbl's `protocol`/`serial`).
//! - [`number`]: strict decimal parsing; [`word`]: quoting what the user typed.
//! - [`command`]: one line -> one [`command::Command`] (like grbl's `gcode`).
//! - [`settings`]: [`Settings`], names, ranges and defaults for `set`; [`record`]: their
//!   binary form for flash; [`store`]: the two flash sectors used in turn (A/B), so a power cut
//!   during a save never loses the last good one.
//! - [`motion`]: straight-line moves at bounded speed, path checks.
//! - [`error`]: [`Error`], why a line is refused (each layer's error type gathered).
//! - [`report`]: every reply, error code and message, data line and notice, worded once (the
//!   output conventions are documented there).
//! - [`controller`]: [`Controller`], the platform's state, which ties them together.
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
pub mod protocol;
pub mod record;
pub mod report;
pub mod safety;
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
