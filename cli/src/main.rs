//! `hexapod`, the host tool of hexapod-fw. Its subcommands, one per job, are the table of
//! contents below; each is carried out by a module of the library (`cli::...`), and every
//! word the tool writes is `cli::messages`' (the board's words are the board's).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args, Parser, Subcommand};

use cli::link::Link;
use cli::messages::Problem;
use cli::trajectory::Mode;
use cli::{configure, cue, demo, draw, drive, flash_image, size, streamer};

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
    Init {
        /// The file to write
        #[arg(default_value = "build.toml")]
        file: PathBuf,
        /// Replace the file if it exists
        #[arg(long)]
        force: bool,
    },
    /// Check a build file with the firmware's own code, and with --port send it to a board:
    /// `defaults`, each `set`, then `save`; stops at the first refusal
    Apply {
        /// The build file
        file: PathBuf,
        #[command(flatten)]
        port: OptionalPort,
        /// Do not `save` (the settings last until the board restarts)
        #[arg(long)]
        no_save: bool,
    },
    /// Write a board's settings (`config`) to a build file
    Pull {
        #[command(flatten)]
        port: Port,
        /// The file to write
        #[arg(short, long, default_value = "build.toml")]
        output: PathBuf,
        /// Replace the file if it exists
        #[arg(long)]
        force: bool,
    },

    // See and size it.
    /// Describe a platform: geometry, reach from home, stiffness, and with a payload its holding
    /// torques, against the servos' ratings where they have one
    Describe {
        /// The platform (a build file: payload_g, payload_com_*_mm, torque_kgcm and the rest,
        /// the servos' stiffness in [sizing]); the default platform (no payload) without it
        #[arg(long)]
        settings: Option<PathBuf>,
    },
    /// Plot the reachable workspace (SVG and PNG): x-y sections, vertical travel against roll
    /// and pitch, reach along each axis
    Workspace {
        /// The platform (a build file); the default platform without it
        #[arg(long)]
        settings: Option<PathBuf>,
        /// Where to write: FILE.svg and FILE.png
        #[arg(short, long, default_value = "workspace")]
        output: PathBuf,
        #[command(flatten)]
        formats: Formats,
    },
    /// Servo torques holding the payload (payload_g) over a grid of poses, or carrying it along
    /// a trajectory (gravity and inertia); the worst named, each against its servo's rating
    /// (torque_kgcm) where it has one; a plot
    Torque {
        /// The platform (a build file with a payload: payload_g above 0, payload_com_*_mm)
        #[arg(long)]
        settings: Option<PathBuf>,
        /// A trajectory (CSV: time,x,y,z,roll,pitch,yaw) instead of the grid
        #[arg(long)]
        trajectory: Option<PathBuf>,
        /// Where to write the plot: FILE.svg and FILE.png
        #[arg(short, long, default_value = "torque")]
        output: PathBuf,
        #[command(flatten)]
        formats: Formats,
    },
    /// Draw the platform at a pose (SVG and PNG): top, front, side and perspective views
    Draw {
        /// The platform (a build file); the default platform without it
        #[arg(long)]
        settings: Option<PathBuf>,
        /// The pose: x y z roll pitch yaw (mm, degrees), as `pose` takes it
        #[arg(long, default_value = "0 0 0 0 0 0", allow_hyphen_values = true)]
        pose: String,
        /// Where to write: FILE.svg and FILE.png
        #[arg(short, long, default_value = "platform")]
        output: PathBuf,
        #[command(flatten)]
        formats: Formats,
    },

    // Drive it.
    /// Send lines to a board and print its replies (the lines given, or standard input's);
    /// stops at the first refusal
    Send {
        #[command(flatten)]
        port: Port,
        /// The lines, e.g. "pose 0 0 5 0 0 0" status
        lines: Vec<String>,
    },
    /// Talk to a board line by line: type commands, read replies (Ctrl-D quits)
    Shell {
        #[command(flatten)]
        port: Port,
    },

    /// Stream a trajectory (CSV: time,x,y,z,roll,pitch,yaw in s, mm, degrees) at its own
    /// timing; every row is checked against the board's settings before anything is sent
    Stream {
        /// The trajectory file
        file: PathBuf,
        #[command(flatten)]
        port: Port,
        #[command(flatten)]
        stream: StreamOptions,
    },
    /// Built-in trajectories, streamed to a board (--port) or written as CSV (--output)
    Demo {
        /// Which
        #[arg(value_enum)]
        kind: demo::Kind,
        #[command(flatten)]
        port: OptionalPort,
        /// Write the trajectory to this CSV file instead
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// The platform (a build file) the CSV is checked against; the default platform
        /// without it (a board's own settings when streaming)
        #[arg(long)]
        settings: Option<PathBuf>,
        /// Radius or amplitude, mm (the tour: the farthest it goes)
        #[arg(long, default_value_t = 10.0)]
        amplitude_mm: f64,
        /// One turn or sine period, s
        #[arg(long, default_value_t = 4.0)]
        period_s: f64,
        /// Length, s
        #[arg(long, default_value_t = 12.0)]
        duration_s: f64,
        /// Rows per second, Hz
        #[arg(long, default_value_t = 50.0)]
        rate_hz: f64,
        /// The tour keeps within this fraction of the reach
        #[arg(long, default_value_t = 0.9)]
        edge_fraction: f64,
        #[command(flatten)]
        stream: StreamOptions,
    },

    /// Fly it: a flight simulator's telemetry (UDP: JSBSim, FlightGear, or a bridge; see
    /// docs/cueing.md) turned into motion cues by a washout filter and streamed to the board as
    /// binary frames; a stall or the end of the telemetry eases the platform home
    Cue {
        #[command(flatten)]
        port: Port,
        /// Where to listen for telemetry
        #[arg(long, default_value = "127.0.0.1:5139")]
        listen: String,
        /// Frames per second (at most, and by default, the board's frame_hz)
        #[arg(long)]
        rate: Option<f64>,
        /// The build file whose [cue] table tunes the washout (the defaults without it)
        #[arg(long)]
        settings: Option<PathBuf>,
        /// Write what came in and what was sent to this CSV file (see cue-plot)
        #[arg(long)]
        record: Option<PathBuf>,
        /// No valid telemetry within this long is an error, s
        #[arg(long, default_value_t = 30.0)]
        wait_s: f64,
        /// Stop this long after the telemetry ends (once home), s; without it, run until
        /// stopped
        #[arg(long)]
        idle_exit_s: Option<f64>,
    },
    /// Plot a `cue --record` file (SVG and PNG): per axis the aircraft's specific force or
    /// rate beside what the platform delivers
    CuePlot {
        /// The record (CSV)
        record: PathBuf,
        /// Where to write: FILE.svg and FILE.png
        #[arg(short, long, default_value = "cue")]
        output: PathBuf,
        #[command(flatten)]
        formats: Formats,
    },

    // Flash it.
    /// Write a UF2 file of the firmware (and, with --settings, of a build file's settings):
    /// hold BOOTSEL while plugging the Pico in, then copy the file onto the RPI-RP2 drive
    Uf2 {
        /// The firmware ELF (what `cargo fw` builds)
        #[arg(default_value = "target/thumbv6m-none-eabi/release/firmware")]
        elf: PathBuf,
        /// The UF2 file to write
        #[arg(short, long, default_value = "hexapod-fw.uf2")]
        output: PathBuf,
        /// Also write these settings (a build file) into the settings sectors, saved as by
        /// `save`: the board starts with them
        #[arg(long)]
        settings: Option<PathBuf>,
    },
}

/// A serial port to a board.
#[derive(Args)]
struct Port {
    /// The board's serial port (e.g. /dev/ttyACM0, /dev/ttyUSB0, COM3, or the path
    /// `./dev run --pty` prints)
    #[arg(short, long)]
    port: String,
    #[command(flatten)]
    link: LinkOptions,
}

/// A serial port, if the job needs a board.
#[derive(Args)]
struct OptionalPort {
    /// The board's serial port; without it the file is only checked
    #[arg(short, long)]
    port: Option<String>,
    #[command(flatten)]
    link: LinkOptions,
}

#[derive(Args)]
struct Formats {
    /// Write only the SVG
    #[arg(long, conflicts_with = "png_only")]
    svg_only: bool,
    /// Write only the PNG
    #[arg(long)]
    png_only: bool,
}

#[derive(Args)]
struct StreamOptions {
    /// Send `pose` lines, each answered (round trip per row), instead of binary frames
    #[arg(long)]
    text: bool,
    /// A row sent later than this after its time counts as late, ms
    #[arg(long, default_value_t = 10.0)]
    late_ms: f64,
    /// How often a `status` is sent during a binary stream (its round trip is measured), s
    #[arg(long, default_value_t = 0.5)]
    status_every_s: f64,
}

impl StreamOptions {
    fn options(&self) -> Result<streamer::Options, Problem> {
        let duration = |option: &'static str, seconds: f64| {
            Duration::try_from_secs_f64(seconds).map_err(|e| Problem::Option {
                option,
                why: e.to_string(),
            })
        };
        Ok(streamer::Options {
            mode: if self.text { Mode::Text } else { Mode::Binary },
            status_every: duration("--status-every-s", self.status_every_s)?,
            late_after: duration("--late-ms", self.late_ms / 1e3)?,
            progress: true,
        })
    }
}

#[derive(Args)]
struct LinkOptions {
    /// The port's baud rate (the board's `baud`; USB ports ignore it)
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// How long to wait for a reply, s
    #[arg(long, default_value_t = 5.0)]
    timeout_s: f64,
}

impl LinkOptions {
    fn open(&self, port: &str) -> Result<Link, Problem> {
        let timeout = Duration::try_from_secs_f64(self.timeout_s).map_err(|e| Problem::Option {
            option: "--timeout-s",
            why: e.to_string(),
        })?;
        Link::open(port, self.baud, timeout)
    }
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Command::Init { file, force } => configure::init(&file, force),
        Command::Apply {
            file,
            port,
            no_save,
        } => match &port.port {
            Some(name) => port
                .link
                .open(name)
                .and_then(|mut link| configure::apply(&file, Some(&mut link), !no_save)),
            None => configure::apply(&file, None, false),
        },
        Command::Pull {
            port,
            output,
            force,
        } => port
            .link
            .open(&port.port)
            .and_then(|mut link| configure::pull(&mut link, &output, force)),
        Command::Describe { settings } => size::describe_command(settings.as_deref()),
        Command::Workspace {
            settings,
            output,
            formats,
        } => size::workspace_command(
            settings.as_deref(),
            &output,
            !formats.png_only,
            !formats.svg_only,
        ),
        Command::Torque {
            settings,
            trajectory,
            output,
            formats,
        } => size::torque_command(
            settings.as_deref(),
            trajectory.as_deref(),
            &output,
            !formats.png_only,
            !formats.svg_only,
        ),
        Command::Draw {
            settings,
            pose,
            output,
            formats,
        } => draw::draw(
            settings.as_deref(),
            &pose,
            &output,
            !formats.png_only,
            !formats.svg_only,
        ),
        Command::Send { port, lines } => port
            .link
            .open(&port.port)
            .and_then(|mut link| configure::send(&mut link, &lines))
            .map(|()| String::new()),
        Command::Shell { port } => port
            .link
            .open(&port.port)
            .and_then(|mut link| configure::shell(&mut link))
            .map(|()| String::new()),
        Command::Stream { file, port, stream } => stream.options().and_then(|options| {
            let mut link = port.link.open(&port.port)?;
            drive::stream(&mut link, &file, &options)
        }),
        Command::Demo {
            kind,
            port,
            output,
            settings,
            amplitude_mm,
            period_s,
            duration_s,
            rate_hz,
            edge_fraction,
            stream,
        } => stream.options().and_then(|options| {
            let shape = demo::Shape {
                kind,
                amplitude_mm,
                period_s,
                duration_s,
                rate_hz,
                ramp_s: period_s.min(duration_s / 4.0),
                edge_fraction,
            };
            demo::check(&shape)?;
            let mut link = match &port.port {
                Some(name) => Some(port.link.open(name)?),
                None => None,
            };
            drive::demo(
                &shape,
                link.as_mut(),
                output.as_deref(),
                settings.as_deref(),
                &options,
            )
        }),
        Command::Cue {
            port,
            listen,
            rate,
            settings,
            record,
            wait_s,
            idle_exit_s,
        } => cue::settings(settings.as_deref()).and_then(|tuning| {
            let options = cue::run::Options {
                listen,
                rate_hz: rate,
                record,
                wait_s,
                idle_exit_s,
                live: true,
            };
            let mut link = port.link.open(&port.port)?;
            cue::run::run(&mut link, &tuning, &options)
        }),
        Command::CuePlot {
            record,
            output,
            formats,
        } => cue::record::plot(&record, &output, !formats.png_only, !formats.svg_only),
        Command::Uf2 {
            elf,
            output,
            settings,
        } => flash_image::write_uf2(&elf, &output, settings.as_deref()),
    };
    match result {
        Ok(summary) => {
            if !summary.is_empty() {
                println!("{summary}");
            }
            ExitCode::SUCCESS
        }
        Err(why) => {
            eprintln!("hexapod: {why}");
            ExitCode::FAILURE
        }
    }
}
