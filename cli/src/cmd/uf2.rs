//! `hexapod uf2`: the firmware's UF2 file (`crate::uf2` of its load segments, `crate::elf`),
//! and with `--settings build.toml` the settings sectors as the board's `save` leaves them
//! (`crate::flash_image`).

use std::fs;
use std::path::PathBuf;

use clap::Args;

use crate::build_file;
use crate::elf;
use crate::error::Error;
use crate::flash_image::{settings_segments, storage_start};
use crate::uf2;

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
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
}

impl Cmd {
    /// Writes the UF2 file; the summary.
    pub fn run(self) -> Result<String, Error> {
        let elf_name = self.elf.display().to_string();
        let elf_problem = |why: String| Error::Elf {
            path: elf_name.clone(),
            why,
        };
        let file = fs::read(&self.elf).map_err(|error| Error::File {
            path: elf_name.clone(),
            error,
        })?;
        let mut segments = elf::load_segments(&file).map_err(|e| elf_problem(e.to_string()))?;
        let firmware_bytes: usize = segments.iter().map(|s| s.bytes.len()).sum();
        if let Some(path) = &self.settings {
            let build = build_file::read(path)?;
            let start = storage_start(&file)
                .map_err(|e| elf_problem(e.to_string()))?
                .map_err(|e| elf_problem(e.to_string()))?;
            segments.extend(settings_segments(start, &build.settings));
        }
        let image = uf2::from_segments(&segments).map_err(|e| elf_problem(e.to_string()))?;
        fs::write(&self.output, &image).map_err(|error| Error::File {
            path: self.output.display().to_string(),
            error,
        })?;
        let settings_name = self.settings.as_ref().map(|p| p.display().to_string());
        Ok(wrote(
            &self.output.display().to_string(),
            image.len() / uf2::BLOCK_BYTES,
            firmware_bytes.div_ceil(1024),
            &elf_name,
            settings_name.as_deref(),
        ))
    }
}

/// The file written.
fn wrote(output: &str, blocks: usize, kib: usize, elf: &str, settings: Option<&str>) -> String {
    let with = match settings {
        Some(file) => format!(" and the settings of {file} (saved, as if by `save`)"),
        None => String::new(),
    };
    format!(
        "{output}: {blocks} blocks, {kib} KiB of flash from {elf}{with}; hold BOOTSEL while \
         plugging the Pico in, then copy it onto the RPI-RP2 drive"
    )
}
