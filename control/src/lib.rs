//! The hardware-independent heart of the hexapod firmware: everything between "bytes arrived
//! on the UART" and "six pulse widths to put on the PWM pins". `no_std`, no allocation, `f32`.
//!
//! ```text
//! bytes -> protocol (lines, editing, echo) -> command (parse) -> Controller (check target
//!       and path with the IK, settings) -> motion (one pose per frame) -> IK -> pulses
//!                                  everything the user sees: report
//! ```
//!
//! - [`protocol`]: line assembly and line editing (like grbl's `protocol`/`serial`).
//! - [`number`]: strict decimal parsing.
//! - [`command`]: one line -> one [`command::Command`] (like grbl's `gcode`).
//! - [`settings`]: [`Settings`], names and ranges for `set`, binary form for flash.
//! - [`motion`]: straight-line moves at bounded speed, path checks.
//! - [`report`]: every reply, error code, data line and notice (the output conventions are
//!   documented there).
//! - [`controller`]: [`Controller`], which ties them together.
//!
//! The board uses it like this:
//!
//! ```
//! # use core::fmt::Write;
//! let mut out = String::new(); // the board writes into its UART transmit queue
//! let mut ctl = control::Controller::new(control::Settings::default());
//! ctl.banner(&mut out);
//! for &byte in b"pose 0 0 5 0 0 0\r" {
//!     ctl.on_byte(byte, &mut out); // echo, editing, and at the line end one reply
//! }
//! assert!(out.contains("\r\nok\r\n"));
//! let generation = ctl.settings_generation();
//! // once per servo frame (1 / frame_hz s):
//! let pulses_us: [f32; 6] = ctl.on_frame();
//! assert!(pulses_us.iter().all(|w| w.is_finite()));
//! // after a reply, reconfigure if the settings changed:
//! if ctl.settings_generation() != generation {
//!     let (_baud, _frame_hz) = (ctl.baud(), ctl.frame_hz());
//! }
//! ```
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

pub mod command;
pub mod controller;
pub mod motion;
pub mod number;
pub mod protocol;
pub mod report;
pub mod settings;

pub use controller::Controller;
pub use report::{Code, Error};
pub use settings::Settings;

pub use kinematics_core::Pose;
