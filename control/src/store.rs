//! Settings kept in flash: two sectors used in turn, so the last good save is never lost.
//!
//! The storage is two 4 KiB sectors of NOR flash ([`NorFlash`]: an erase sets a whole sector to
//! `0xFF`; programming a 256-byte page can only clear bits). A save writes one [`record`] with
//! the next sequence number into the first page of the sector that does *not* hold the newest
//! good record: it erases that sector, programs the page and reads it back ([`Write::perform`]).
//! The newest good copy is never touched, so a power cut at any moment of a save leaves it as it
//! was, and at power-up [`Store::load`] finds the new record (the save got to its end) or the
//! old one (it did not): never garbage (a record cut short fails its CRC, see [`record`]) and
//! never nothing where a good copy exists.
//!
//! The policy and the codec are here, hardware-independent and tested on the host against an
//! in-memory NOR flash with power cuts injected at every byte written (`tests/store.rs`). The
//! board implements [`NorFlash`] over the two sectors it reserves (`memory.x`; the RP2040's are
//! written through its boot ROM, `firmware/src/flash.rs`) and performs a [`Write`] when the
//! controller asks for it ([`crate::Controller::take_flash_write`]): the controller hands over
//! the record and gets the verified result back.
//!
//! Offsets given to [`NorFlash`] are bytes from the start of the storage (sector 0 at 0,
//! sector 1 at [`SECTOR_BYTES`]); where the storage lies in the chip is the board's business.

use kinematics_core::{Libm, Math};

use crate::record::{self, DecodeError, Record, ENCODED_LEN};
use crate::settings::Settings;

/// Bytes in a sector, the unit of erase.
pub const SECTOR_BYTES: u32 = 4096;
/// Bytes in a page, the unit of programming.
pub const PAGE_BYTES: usize = 256;
/// Sectors of storage: used in turn.
pub const SECTORS: usize = 2;
/// Bytes of storage.
pub const STORAGE_BYTES: u32 = SECTORS as u32 * SECTOR_BYTES;

/// NOR flash as the store uses it: read anything, erase a sector, program a page.
pub trait NorFlash {
    /// Why an erase or a program did not happen (or did not finish).
    type Error;
    /// Reads `buf.len()` bytes from `offset` on.
    fn read(&mut self, offset: u32, buf: &mut [u8]);
    /// Erases the sector at `offset` (a multiple of [`SECTOR_BYTES`]): every byte `0xFF`.
    fn erase_sector(&mut self, offset: u32) -> Result<(), Self::Error>;
    /// Programs the page at `offset` (a multiple of [`PAGE_BYTES`]): bits can only go from 1
    /// to 0, so the page then holds what it held AND `data`.
    fn program_page(&mut self, offset: u32, data: &[u8; PAGE_BYTES]) -> Result<(), Self::Error>;
}

/// What a sector holds.
// Read once per sector at power-up; no heap to box the record into.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum Sector {
    /// Nothing: its record page reads all `0xFF`.
    Erased,
    /// A good record.
    Saved(Record),
    /// Something that is not a good record (a save cut short, damage, another format version).
    Unusable(DecodeError),
}

/// What power-up found in the storage, for the controller to say.
#[derive(Debug, Clone, PartialEq)]
pub enum Found {
    /// Nothing was ever saved: both sectors are erased.
    Nothing,
    /// A good record (the newer of two, or the only one, the other sector being erased).
    Saved {
        /// Its sequence number.
        sequence: u32,
    },
    /// A good record, but the other sector holds one that cannot be used (a save cut short, a
    /// damaged or foreign record), which may have been the newer one.
    SavedOtherUnusable {
        /// The good record's sequence number.
        sequence: u32,
        /// Why the other cannot be used.
        other: DecodeError,
    },
    /// No good record: why (another format version if either sector holds one, as that is what
    /// a user can act on; otherwise the first unusable sector's reason).
    Unusable(DecodeError),
}

/// What [`Store::load`] found: the store to save with next, and what to say about it.
#[derive(Debug, Clone, PartialEq)]
pub struct Loaded {
    /// The store, knowing which sector holds the newest good record.
    pub store: Store,
    /// What was found.
    pub found: Found,
}

impl Loaded {
    /// The saved settings to start with, if there are any.
    pub fn settings(&self) -> Option<&Settings> {
        self.store.saved()
    }
}

/// Why a save did not complete. The newest good record is untouched either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SaveError {
    /// The flash refused the erase or the program.
    Flash,
    /// Reading the page back did not give what was programmed (the page is then cleared, so
    /// that what is there is never taken for a save).
    Verify {
        /// Offset in the storage of the first byte that differs.
        offset: u32,
        /// What was programmed there.
        wrote: u8,
        /// What was read back.
        read: u8,
    },
}

/// The A/B policy: which sector holds the newest good record, so the next save goes to the
/// other. Holds no flash: the board does the I/O.
#[derive(Debug, Clone, PartialEq)]
pub struct Store {
    /// The sector holding the newest good record, and the record.
    newest: Option<(usize, Record)>,
}

impl Store {
    /// A store that knows of no saved record (the next save goes to sector 0): for a
    /// controller that was not started from flash.
    pub const fn empty() -> Store {
        Store { newest: None }
    }

    /// Reads both sectors: the newest good record, and what to say about the other.
    pub fn load<F: NorFlash>(flash: &mut F) -> Loaded {
        Self::load_with::<Libm, F>(flash)
    }

    /// [`Store::load`], the records' geometry validated with `M`'s maths
    /// ([`record::decode_with`]).
    pub fn load_with<M: Math, F: NorFlash>(flash: &mut F) -> Loaded {
        let first = read_sector::<M, F>(flash, 0);
        let second = read_sector::<M, F>(flash, SECTOR_BYTES);
        // The newest good record, and what the other sector holds.
        let (newest, other) = match (first, second) {
            (Sector::Saved(a), Sector::Saved(b)) if record::is_newer(b.sequence, a.sequence) => {
                (Some((1, b)), Sector::Saved(a))
            }
            (Sector::Saved(a), other) => (Some((0, a)), other),
            (other, Sector::Saved(b)) => (Some((1, b)), other),
            // Another format version is what a user can act on.
            (Sector::Unusable(_), Sector::Unusable(e @ DecodeError::UnsupportedVersion(_))) => {
                (None, Sector::Unusable(e))
            }
            (Sector::Unusable(e), _) | (Sector::Erased, Sector::Unusable(e)) => {
                (None, Sector::Unusable(e))
            }
            (Sector::Erased, Sector::Erased) => (None, Sector::Erased),
        };
        let found = match (&newest, other) {
            (Some((_, r)), Sector::Unusable(other)) => Found::SavedOtherUnusable {
                sequence: r.sequence,
                other,
            },
            (Some((_, r)), _) => Found::Saved {
                sequence: r.sequence,
            },
            (None, Sector::Unusable(e)) => Found::Unusable(e),
            (None, _) => Found::Nothing,
        };
        Loaded {
            store: Store { newest },
            found,
        }
    }

    /// The settings of the newest good record, if any.
    pub fn saved(&self) -> Option<&Settings> {
        self.newest.as_ref().map(|(_, r)| &r.settings)
    }

    /// The newest good record and its sector, if any.
    pub fn newest(&self) -> Option<(usize, &Record)> {
        self.newest.as_ref().map(|(i, r)| (*i, r))
    }

    /// UART0's baud rate in the newest good record, if any.
    pub fn saved_baud(&self) -> Option<u32> {
        self.newest.as_ref().map(|(_, r)| r.baud)
    }

    /// The write that saves `settings` and UART0's `baud`: the next sequence number, into the
    /// sector that does not hold the newest good record.
    pub fn prepare(&self, settings: &Settings, baud: u32) -> Write {
        let (sector, sequence) = match &self.newest {
            Some((i, r)) => (1 - *i, r.sequence.wrapping_add(1)),
            None => (0, 1),
        };
        Write {
            sector,
            record: Record {
                sequence,
                settings: *settings,
                baud,
            },
        }
    }

    /// A write has been performed and verified: its record is now the newest.
    pub fn commit(&mut self, write: &Write) {
        self.newest = Some((write.sector, write.record));
    }

    /// Saves `settings` and `baud` at once: [`Store::prepare`], [`Write::perform`],
    /// [`Store::commit`].
    pub fn save<F: NorFlash>(
        &mut self,
        flash: &mut F,
        settings: &Settings,
        baud: u32,
    ) -> Result<(), SaveError> {
        let write = self.prepare(settings, baud);
        write.perform(flash)?;
        self.commit(&write);
        Ok(())
    }
}

/// One save's flash I/O: erase a sector, program its first page with a record, read it back.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Write {
    sector: usize,
    record: Record,
}

impl Write {
    /// The sector written (0 or 1).
    pub fn sector(&self) -> usize {
        self.sector
    }

    /// Its offset in the storage.
    pub fn offset(&self) -> u32 {
        self.sector as u32 * SECTOR_BYTES
    }

    /// The record written.
    pub fn record(&self) -> &Record {
        &self.record
    }

    /// The page programmed: the record, then erased bytes.
    pub fn page(&self) -> [u8; PAGE_BYTES] {
        let mut page = [0xFF; PAGE_BYTES];
        page[..ENCODED_LEN].copy_from_slice(&record::encode(&self.record));
        page
    }

    /// Erases the sector, programs the page and reads it back. If the read-back differs, the
    /// page is cleared to zeros (a zero page never decodes), so that a save reported as failed
    /// is never loaded at the next power-up.
    pub fn perform<F: NorFlash>(&self, flash: &mut F) -> Result<(), SaveError> {
        let offset = self.offset();
        let page = self.page();
        flash.erase_sector(offset).map_err(|_| SaveError::Flash)?;
        flash
            .program_page(offset, &page)
            .map_err(|_| SaveError::Flash)?;
        let mut back = [0u8; PAGE_BYTES];
        flash.read(offset, &mut back);
        let Some(at) = page.iter().zip(&back).position(|(w, r)| w != r) else {
            return Ok(());
        };
        let _ = flash.program_page(offset, &[0; PAGE_BYTES]);
        Err(SaveError::Verify {
            offset: offset + at as u32,
            wrote: page[at],
            read: back[at],
        })
    }
}

/// What the sector at `offset` holds (its geometry validated with `M`'s maths).
#[inline(never)] // once in the firmware, for both sectors
pub fn read_sector<M: Math, F: NorFlash>(flash: &mut F, offset: u32) -> Sector {
    let mut page = [0u8; PAGE_BYTES];
    flash.read(offset, &mut page);
    if page.iter().all(|&b| b == 0xFF) {
        return Sector::Erased;
    }
    match record::decode_with::<M>(&page) {
        Ok(r) => Sector::Saved(r),
        Err(e) => Sector::Unusable(e),
    }
}

/// Why [`RamFlash`] refused an erase or a program.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RamFlashError {
    /// The offset is not a multiple of the sector (erase) or page (program) size.
    Misaligned,
    /// Beyond the storage.
    OutOfRange,
}

/// An in-memory NOR flash the size of the storage, with the chip's rules (aligned erase to
/// `0xFF`, aligned program as AND): for hosts (tests, fuzzers, the REPL example).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RamFlash {
    /// The contents.
    pub bytes: [u8; STORAGE_BYTES as usize],
    /// Erases done, per sector.
    pub erases: [u32; SECTORS],
}

impl Default for RamFlash {
    fn default() -> Self {
        Self::new()
    }
}

impl RamFlash {
    /// A new, erased flash.
    pub const fn new() -> RamFlash {
        RamFlash {
            bytes: [0xFF; STORAGE_BYTES as usize],
            erases: [0; SECTORS],
        }
    }

    fn range(
        offset: u32,
        len: usize,
        align: u32,
    ) -> Result<core::ops::Range<usize>, RamFlashError> {
        if offset % align != 0 {
            return Err(RamFlashError::Misaligned);
        }
        let start = offset as usize;
        match start.checked_add(len) {
            Some(end) if end <= STORAGE_BYTES as usize => Ok(start..end),
            _ => Err(RamFlashError::OutOfRange),
        }
    }
}

impl NorFlash for RamFlash {
    type Error = RamFlashError;

    fn read(&mut self, offset: u32, buf: &mut [u8]) {
        for (i, b) in buf.iter_mut().enumerate() {
            *b = self.bytes.get(offset as usize + i).copied().unwrap_or(0xFF);
        }
    }

    fn erase_sector(&mut self, offset: u32) -> Result<(), RamFlashError> {
        let range = Self::range(offset, SECTOR_BYTES as usize, SECTOR_BYTES)?;
        self.bytes[range].fill(0xFF);
        self.erases[(offset / SECTOR_BYTES) as usize] += 1;
        Ok(())
    }

    fn program_page(&mut self, offset: u32, data: &[u8; PAGE_BYTES]) -> Result<(), RamFlashError> {
        let range = Self::range(offset, PAGE_BYTES, PAGE_BYTES as u32)?;
        for (cell, d) in self.bytes[range].iter_mut().zip(data) {
            *cell &= d;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::DEFAULT_BAUD;

    fn with_trim(trim_us: f32) -> Settings {
        let mut s = Settings::default();
        s.servos.0[2].home_us = trim_us;
        s
    }

    #[test]
    fn a_fresh_flash_holds_nothing_and_the_first_save_goes_to_sector_0_as_save_1() {
        let mut flash = RamFlash::new();
        let loaded = Store::load(&mut flash);
        assert_eq!(loaded.found, Found::Nothing);
        assert_eq!(loaded.settings(), None);
        let write = loaded.store.prepare(&with_trim(1510.0), DEFAULT_BAUD);
        assert_eq!(
            (write.sector(), write.offset(), write.record().sequence),
            (0, 0, 1)
        );
        // The page: the record, then erased bytes.
        let page = write.page();
        assert_eq!(&page[..4], b"HXPS");
        assert!(page[ENCODED_LEN..].iter().all(|&b| b == 0xFF));
    }

    #[test]
    fn saves_alternate_and_the_newest_is_loaded() {
        let mut flash = RamFlash::new();
        let mut store = Store::empty();
        for n in 1..=5u32 {
            let s = with_trim(1500.0 + n as f32);
            let baud = crate::settings::BAUD_RATES[n as usize];
            store.save(&mut flash, &s, baud).unwrap();
            let loaded = Store::load(&mut flash);
            assert_eq!(loaded.settings(), Some(&s), "after save {n}");
            assert_eq!(loaded.store.saved_baud(), Some(baud), "after save {n}");
            assert_eq!(loaded.found, Found::Saved { sequence: n });
            // Save n went to sector (n - 1) % 2; the store picks up where it left off.
            assert_eq!(
                loaded.store.newest().map(|(i, _)| i),
                Some((n as usize - 1) % 2)
            );
            assert_eq!(loaded.store, store);
        }
        assert_eq!(flash.erases, [3, 2]);
    }

    #[test]
    fn a_misaligned_or_out_of_range_write_is_refused_by_the_ram_flash() {
        let mut flash = RamFlash::new();
        assert_eq!(flash.erase_sector(100), Err(RamFlashError::Misaligned));
        assert_eq!(flash.erase_sector(8192), Err(RamFlashError::OutOfRange));
        assert_eq!(
            flash.program_page(8, &[0; 256]),
            Err(RamFlashError::Misaligned)
        );
        assert_eq!(
            flash.program_page(8192, &[0; 256]),
            Err(RamFlashError::OutOfRange)
        );
        assert_eq!(flash, RamFlash::new());
    }
}
