//! `hexapod`, the host tool of hexapod-fw. Its subcommands, one per job, are the table of
//! contents below; each is carried out by a module of the library (`cli::...`), and every
//! word the tool writes is `cli::messages`' (the board's words are the board's).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args, Parser, Subcommand};

use cli::link::Link;
use cli::messages::Problem;
use cli::{configure, flash_image};

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
