//! The host tool's library: what `hexapod`'s subcommands are made of, each testable on its own.
//!
//! - [`messages`]: every word the tool itself writes (the board's words come from
//!   `control::report`);
//! - [`build_file`]: the TOML build file, keys the firmware's `set` names, checked by the
//!   firmware's own code;
//! - [`link`]: a serial link to a board, honouring its protocol; [`board`]: what its replies
//!   say (`config` as settings, `status`'s counters);
//! - [`configure`]: `init`, `apply`, `pull`, `send`, `shell`;
//! - [`trajectory`]: trajectory CSV files, and each row as the board will get it, checked;
//!   [`demo`]: built-in trajectories; [`streamer`]: sending them at their own timing;
//!   [`drive`]: `stream` and `demo`;
//! - [`cue`]: `cue` and `cue-plot`: a flight simulator's telemetry to motion cues (washout
//!   filter) to stream frames;
//! - [`flash_image`]: `uf2`, with the settings sectors written as the board's `save` does;
//! - [`elf`]: the load segments of an ELF file, where a programmer writes them;
//! - [`uf2`]: a UF2 file of those segments, for the RP2040's USB drag-and-drop bootloader, and
//!   the file read back.

pub mod board;
pub mod build_file;
pub mod configure;
pub mod cue;
pub mod demo;
pub mod draw;
pub mod drive;
pub mod elf;
pub mod flash_image;
pub mod link;
pub mod messages;
pub mod picture;
pub mod plot;
pub mod size;
pub mod sizing;
pub mod streamer;
pub mod trajectory;
pub mod uf2;
