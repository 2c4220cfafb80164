//! What `hexapod uf2` writes besides the firmware's load segments: with `--settings build.toml`
//! the settings sectors, written exactly as the board's own `save` leaves them, so that one drag and
//! drop flashes firmware and calibration together.
//!
//! Where the sectors are is the firmware's: `memory.x` reserves them and names them
//! `_settings_start`/`_settings_end`, read here from the ELF's symbol table. What goes in them
//! is `control::store`'s: the first save a board makes (`Store::empty().prepare`, sequence 1,
//! into sector 0: a `control::record` followed by erased bytes) and the other sector erased, so
//! at power-up `Store::load` finds that save and nothing else (an older save left in the other
//! sector by a previous `save` could otherwise be newer). The RP2040's bootloader erases each
//! 4 KiB sector a file writes into, then programs the file's pages.

use std::fmt;

use control::settings::Settings;
use control::store::{Store, PAGE_BYTES, SECTORS, SECTOR_BYTES, STORAGE_BYTES};

use crate::elf::{self, Segment};

/// The linker script's symbols for the settings storage.
pub const SETTINGS_START: &str = "_settings_start";
/// See [`SETTINGS_START`].
pub const SETTINGS_END: &str = "_settings_end";

/// Why the settings sectors cannot be written for an ELF.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StorageError {
    /// The ELF does not define the symbols (a firmware without settings storage).
    NoSymbols,
    /// The symbols do not enclose two aligned sectors: `start..end`.
    BadStorage {
        /// `_settings_start`.
        start: u32,
        /// `_settings_end`.
        end: u32,
    },
}

impl fmt::Display for StorageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StorageError::NoSymbols => write!(
                f,
                "no {SETTINGS_START}/{SETTINGS_END} symbols: not a firmware with settings storage \
                 (memory.x)"
            ),
            StorageError::BadStorage { start, end } => write!(
                f,
                "{SETTINGS_START}..{SETTINGS_END} = {start:#010x}..{end:#010x} is not two aligned \
                 4 KiB sectors"
            ),
        }
    }
}

/// The settings storage of a firmware ELF: its first address.
pub fn storage_start(elf_file: &[u8]) -> Result<Result<u32, StorageError>, elf::ElfError> {
    let start = elf::symbol(elf_file, SETTINGS_START)?;
    let end = elf::symbol(elf_file, SETTINGS_END)?;
    Ok(match (start, end) {
        (Some(start), Some(end))
            if end.checked_sub(start) == Some(STORAGE_BYTES) && start % SECTOR_BYTES == 0 =>
        {
            Ok(start)
        }
        (Some(start), Some(end)) => Err(StorageError::BadStorage { start, end }),
        _ => Err(StorageError::NoSymbols),
    })
}

/// The pages that put `settings` in the storage at `start` as the first save: the record's page
/// in sector 0, an erased page in each other sector.
pub fn settings_segments(start: u32, settings: &Settings) -> Vec<Segment> {
    let write = Store::empty().prepare(settings);
    (0..SECTORS)
        .map(|sector| {
            let offset = sector as u32 * SECTOR_BYTES;
            let bytes = if offset == write.offset() {
                write.page().to_vec()
            } else {
                vec![0xFF; PAGE_BYTES]
            };
            Segment {
                address: start + offset,
                bytes,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use control::store::{Found, NorFlash, RamFlash};

    #[test]
    fn the_pages_load_as_the_saved_settings_whatever_the_sectors_held() {
        let file =
            crate::build_file::parse("t", "rod_mm = 130\n[servo2]\ntrim_us = 1510\n").unwrap();
        let pages = settings_segments(0x101F_E000, &file.settings);
        assert_eq!(pages.len(), 2);
        assert_eq!(pages[1].address, 0x101F_F000);
        // A board that had saved many times before: its sectors as they were, then the
        // bootloader erases each sector written and programs the pages.
        let mut flash = RamFlash::new();
        let mut store = Store::empty();
        for _ in 0..5 {
            store.save(&mut flash, &Settings::default()).unwrap();
        }
        for page in &pages {
            let offset = page.address - 0x101F_E000;
            flash.erase_sector(offset).unwrap();
            let bytes: [u8; PAGE_BYTES] = page.bytes.as_slice().try_into().unwrap();
            flash.program_page(offset, &bytes).unwrap();
        }
        let loaded = Store::load(&mut flash);
        assert_eq!(loaded.found, Found::Saved { sequence: 1 });
        assert_eq!(loaded.settings(), Some(&file.settings));
    }
}
