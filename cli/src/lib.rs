//! The host tool `hexapod`'s library: its subcommands ([`cmd`], one file each, listed by
//! `main.rs`) and what they are made of, each testable on its own.
//!
//! This table is the crate's one module map (ARCHITECTURE.md links here):
//!
//! | module | job |
//! | --- | --- |
//! | `main.rs` | the table of contents: each subcommand with its help line, dispatched to its `Cmd::run` |
//! | `cmd/<subcommand>.rs` | one per subcommand (`init`, `apply`, `pull`, `calibrate`, `boards`, `describe`, `workspace`, `torque`, `draw`, `send`, `shell`, `stream`, `demo`, `cue`, `cue_plot`, `uf2`, `view`): its options (a clap `Cmd`), its `run`, its own words (the summary it prints) |
//! | `cmd/mod.rs` | the options several share (a board's port and link, picture formats, stream options, Ctrl-C taken as a flag: `cue`, `calibrate`) and the summaries several write |
//! | `error.rs` | `Error`, the one error type, each variant worded in its `Display` (the file, line and key or field, or the port); `board_words`: a refusal as the board writes it |
//! | `messages.rs` | how the outcome is written (mechanism, no content): the summary on standard output, the error after `hexapod: ` on standard error, a reply's lines as the board wrote them |
//! | `build_file.rs` | the TOML build file: keys are `set` names (the payload and torque ratings too; `baud` kept apart, for `apply` to send last, before `save`), each checked by `control::settings`, a payload's holding torques at home by `control::payload`; an order of `set`s the board accepts one by one; `read`; writing a commented file (each setting's meaning and range) |
//! | `sizing.rs` | the build file's `[sizing]` table: what the board has no setting for (the servos' holding stiffness); its old payload and rating keys named with the settings that replaced them |
//! | `files.rs` | the user's files read and written whole, errors naming the file |
//! | `link.rs` | a serial port to a board (`serialport`, no libudev): a reader thread hands over lines; echo off, one final reply per line, resynchronisation after `# warning:` |
//! | `boards.rs` | the serial ports the system lists, the boards first: a USB port with the firmware's USB IDs (`control::report::USB_VID`, `USB_PID`) named by its serial number (the board's id) |
//! | `calibration.rs` | the guided calibration's pieces: keys to pulse steps within the servo's limits, the trim from the pulse that holds the arm level (`ServoConfig`'s eq. 13 / 14), the check poses, a build file's trims replaced with the rest of its text kept |
//! | `board.rs` | what replies say: `config` as `Settings` (read with `SettingId::parse`/`parse_value`), `status`'s counters and pulses |
//! | `trajectory.rs` | trajectory CSV files; each row as the board will get it (a binary frame or a `pose` line), checked with the firmware's decoder, the IK and the torque check (`control::payload`) |
//! | `demo.rs` | built-in trajectories (circle, figure eight, sines, a tour of the workspace edge) |
//! | `streamer.rs` | rows checked against the board's settings and sent at their own timing; round trips, late rows, the board's counters; the stream's summary |
//! | `size.rs` | a platform sized: reach (`workspace::Limits`), stiffness (`statics`), the payload's holding torques and the ratings' verdict as the board computes them (`control::payload`), torques along a trajectory (`dynamics::actuation`); the words `describe` and `torque` share |
//! | `draw.rs` | the platform at a pose in four views (`legs::ArmState` for the arm tips and joints), with its labels |
//! | `workspace_plot.rs`, `torque_plot.rs` | `workspace`'s three plots; `torque`'s bars over the grid or lines along a trajectory, with the ratings; each with its labels |
//! | `plot.rs` | axes with round ticks and units, legends, colour scales, on a `picture::Scene` |
//! | `picture.rs` | a scene of lines, polygons, circles and text; SVG by hand; PNG by `resvg` with DejaVu Sans embedded (`dejavu` crate); `write_scene` writes the files asked for |
//! | `cue/` | the work of `cue` and `cue-plot` (docs/cueing.md): `washout.rs` the classical washout filter (specific force and rates at the pilot's head -> high-pass, double integration; low-pass -> rate-limited tilt coordination; rates -> high-pass, integration), each channel a transfer function stepped by the trapezoidal rule at the telemetry's own time step; `reach.rs` the pivot and the limits (soft limit per axis within a margin of `workspace::Limits`' reach and the board's full scales, then the board's IK on the whole pose); `telemetry.rs` the UDP line format JSBSim and FlightGear send (`cli/sim/`), bad lines dropped and counted (why, worded on `error::BadLine`); `config.rs` the build file's `[cue]` table (`build_file` passes it by), each key's range and meaning; `run.rs` the loop (newest cue first, easing home on a stall, the end of the telemetry or Ctrl-C), reporting its progress to `cmd/cue.rs`, which words it; `record.rs` the CSV record and its plot with its labels (what the platform delivers, from the poses sent) |
//! | `view/` | `view`: the live 3D view for a board on a cable (`mod.rs`: the wire's arithmetic; `follow.rs`: one thread owns the link and follows the board with `pulses`, the page's typed lines and jog commands between queries, the listings passed on as the board wrote them, asked again after a line that can change them by the rule `./dev run`'s server reads too, `emulator/src/view-server/listing-changes.txt`, built in; `pages.rs`: the pages' event queues and what a newcomer gets first; `http.rs`: the page's server on `std::net`, the same addresses as `./dev run`'s, the page embedded by `build.rs` from `emulator/view/`, three.js, xterm.js and the WebAssembly read from the checkout; `json.rs`: the little JSON they exchange) |
//! | `flash_image.rs`, `uf2.rs`, `elf.rs` | `uf2`: the ELF's load segments, and with `--settings` the settings sectors (found by the `_settings_start`/`_settings_end` symbols `memory.x` defines) as `Store::empty().prepare` writes them |
//!
//! No module imports one that imports it back: `error` is a leaf, the library's modules never
//! use `cmd`, and `cmd/mod.rs` (the shared options) never uses its subcommands.

pub mod board;
pub mod boards;
pub mod build_file;
pub mod calibration;
pub mod cmd;
pub mod cue;
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
pub mod view;
pub mod workspace_plot;
