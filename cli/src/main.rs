//! `hexapod`, the host tool of hexapod-fw: its subcommands, one per job, are the table of
//! contents below, each with its help line. Each is a file of `hexapod::cmd` (its options, its
//! run, its words), carried out by the library's modules; `hexapod::messages` writes the
//! outcome.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use hexapod::cmd::{
    apply, boards, calibrate, cue, cue_plot, demo, describe, draw, init, pull, send, shell, stream,
    torque, uf2, view, workspace,
};
use hexapod::messages;

#[derive(Parser)]
#[command(
    name = "hexapod",
    version,
    about = "The host tool of hexapod-fw: describe, draw and \
    size a Stewart platform; configure and drive its board"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    // One build file.
    /// Write a commented build file (TOML, keys the firmware's `set` names) of the default
    /// platform
    Init(init::Cmd),
    /// Check a build file with the firmware's own code, and with --port send it to a board:
    /// `defaults`, each `set`, then `save`; stops at the first refusal
    Apply(apply::Cmd),
    /// Write a board's settings (`config`) to a build file
    Pull(pull::Cmd),
    /// Calibrate a board, guided: servo by servo, bring its arm level with +/- steps (the trim
    /// is taken from it), check the platform at a few poses, write the build file and `save`;
    /// q or Ctrl-C puts everything back
    Calibrate(calibrate::Cmd),

    // See and size it.
    /// Describe a platform: geometry, reach from home, stiffness, and with a payload its holding
    /// torques, against the servos' ratings where they have one
    Describe(describe::Cmd),
    /// Plot the reachable workspace (SVG and PNG): x-y sections, vertical travel against roll
    /// and pitch, reach along each axis
    Workspace(workspace::Cmd),
    /// Servo torques holding the payload (payload_g) over a grid of poses, or carrying it along
    /// a trajectory (gravity and inertia); the worst named, each against its servo's rating
    /// (torque_kgcm) where it has one; a plot
    Torque(torque::Cmd),
    /// Draw the platform at a pose (SVG and PNG): top, front, side and perspective views
    Draw(draw::Cmd),

    // Drive it.
    /// List the serial ports, the boards first with their ids (the USB serial number the
    /// firmware makes from its flash chip's unique ID)
    Boards(boards::Cmd),
    /// Send lines to a board and print its replies (the lines given, or standard input's);
    /// stops at the first refusal
    Send(send::Cmd),
    /// Talk to a board line by line: type commands, read replies (Ctrl-D quits)
    Shell(shell::Cmd),
    /// The live 3D view of a board (a web page on 127.0.0.1): the platform drawn from its own
    /// geometry and the pulses it outputs, jogging, home, stop and a terminal on the same link
    View(view::Cmd),

    /// Stream a trajectory (CSV: time,x,y,z,roll,pitch,yaw in s, mm, degrees) at its own
    /// timing; every row is checked against the board's settings before anything is sent
    Stream(stream::Cmd),
    /// Built-in trajectories, streamed to a board (--port) or written as CSV (--output)
    Demo(demo::Cmd),

    /// Fly it: a flight simulator's telemetry (UDP: JSBSim, FlightGear, or a bridge; see
    /// docs/cueing.md) turned into motion cues by a washout filter and streamed to the board as
    /// binary frames; a stall or the end of the telemetry, or Ctrl-C, eases the platform home
    Cue(cue::Cmd),
    /// Plot a `cue --record` file (SVG and PNG): per axis the aircraft's specific force or
    /// rate beside what the platform delivers
    CuePlot(cue_plot::Cmd),

    // Flash it.
    /// Write a UF2 file of the firmware (and, with --settings, of a build file's settings):
    /// hold BOOTSEL while plugging the Pico in, then copy the file onto the RPI-RP2 drive
    Uf2(uf2::Cmd),
}

fn main() -> ExitCode {
    messages::finish(match Cli::parse().command {
        Command::Init(cmd) => cmd.run(),
        Command::Apply(cmd) => cmd.run(),
        Command::Pull(cmd) => cmd.run(),
        Command::Calibrate(cmd) => cmd.run(),
        Command::Boards(cmd) => cmd.run(),
        Command::Describe(cmd) => cmd.run(),
        Command::Workspace(cmd) => cmd.run(),
        Command::Torque(cmd) => cmd.run(),
        Command::Draw(cmd) => cmd.run(),
        Command::Send(cmd) => cmd.run(),
        Command::Shell(cmd) => cmd.run(),
        Command::View(cmd) => cmd.run(),
        Command::Stream(cmd) => cmd.run(),
        Command::Demo(cmd) => cmd.run(),
        Command::Cue(cmd) => cmd.run(),
        Command::CuePlot(cmd) => cmd.run(),
        Command::Uf2(cmd) => cmd.run(),
    })
}
