//! `hexapod`, the host tool of hexapod-fw. Its subcommands, one per job, are the table of
//! contents below (more are to come: describe, draw, workspace, torque, send, stream, demo).

use std::fs;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use cli::{elf, uf2};

#[derive(Parser)]
#[command(name = "hexapod", version, about = "The host tool of hexapod-fw")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Write a UF2 file of the firmware: hold BOOTSEL while plugging the Pico in, then copy
    /// the file onto the RPI-RP2 drive
    Uf2(Uf2Args),
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Command::Uf2(args) => write_uf2(&args),
    };
    match result {
        Ok(summary) => {
            println!("{summary}");
            ExitCode::SUCCESS
        }
        Err(why) => {
            eprintln!("hexapod: {why}");
            ExitCode::FAILURE
        }
    }
}

#[derive(clap::Args)]
struct Uf2Args {
    /// The firmware ELF (what `cargo fw` builds)
    #[arg(default_value = "target/thumbv6m-none-eabi/release/firmware")]
    elf: PathBuf,
    /// The UF2 file to write
    #[arg(short, long, default_value = "hexapod-fw.uf2")]
    output: PathBuf,
}

/// `hexapod uf2`: the ELF's load segments as a UF2 file.
fn write_uf2(args: &Uf2Args) -> Result<String, String> {
    let elf_name = args.elf.display();
    let file = fs::read(&args.elf).map_err(|e| format!("{elf_name}: {e}"))?;
    let segments = elf::load_segments(&file).map_err(|e| format!("{elf_name}: {e}"))?;
    let image = uf2::from_segments(&segments).map_err(|e| format!("{elf_name}: {e}"))?;
    fs::write(&args.output, &image).map_err(|e| format!("{}: {e}", args.output.display()))?;
    let blocks = image.len() / uf2::BLOCK_BYTES;
    Ok(format!(
        "{}: {blocks} blocks, {} KiB of flash from {elf_name}; hold BOOTSEL while plugging the \
         Pico in, then copy it onto the RPI-RP2 drive",
        args.output.display(),
        blocks * uf2::PAYLOAD_BYTES / 1024
    ))
}
