//! The host tool `hexapod`'s library: its subcommands ([`cmd`], one file each, listed by
//! `main.rs`) and what they are made of, each testable on its own.
//!
//! - [`cmd`]: each subcommand's options, run and words;
//! - [`error`]: [`error::Error`], the one error type, worded on its variants; [`messages`]:
//!   how the outcome is written (the words are their owners');
//! - [`build_file`]: the TOML build file, keys the firmware's `set` names, checked by the
//!   firmware's own code, and written commented; [`sizing`]: its host-only `[sizing]` table;
//!   [`files`]: files read and written whole;
//! - [`link`]: a serial link to a board, honouring its protocol; [`board`]: what its replies
//!   say (`config` as settings, `status`'s counters);
//! - [`trajectory`]: trajectory CSV files, and each row as the board will get it, checked;
//!   [`demo`]: built-in trajectories; [`streamer`]: sending them at their own timing;
//! - [`size`]: a platform's reach, stiffness and servo torques; [`draw`], [`workspace_plot`],
//!   [`torque_plot`]: the pictures, on [`picture`] scenes with [`plot`]'s axes;
//! - [`flash_image`]: the settings sectors as the board's `save` leaves them; [`elf`]: the load
//!   segments of an ELF file; [`uf2`]: a UF2 file of segments, for the RP2040's USB
//!   drag-and-drop bootloader, and the file read back.
//!
//! No module imports one that imports it back: `error` is a leaf, the library's modules never
//! use `cmd`, and `cmd/mod.rs` (the shared options) never uses its subcommands.

pub mod board;
pub mod build_file;
pub mod cmd;
pub mod demo;
pub mod draw;
pub mod elf;
pub mod error;
pub mod files;
pub mod flash_image;
pub mod link;
pub mod messages;
pub mod picture;
pub mod plot;
pub mod size;
pub mod sizing;
pub mod streamer;
pub mod torque_plot;
pub mod trajectory;
pub mod uf2;
pub mod workspace_plot;
