//! The flash store's A/B policy against an in-memory NOR flash with power cuts injected at every
//! byte a save writes (and in the middle of that byte's bits): whatever the moment, the next
//! power-up loads the settings saved before or the settings being saved, never garbage, and
//! never nothing when a good copy existed. Then the saves go on as before.
//!
//! The expectations come from the documented policy (control/src/store.rs, docs/settings.md
//! "Saving the settings"): saves alternate between the two sectors, a save never touches the
//! sector holding the newest good record, a record cut short does not decode.

use control::record::{self, DecodeError, Record, ENCODED_LEN};
use control::settings::DEFAULT_BAUD;
use control::store::{
    Found, NorFlash, RamFlash, SaveError, Store, PAGE_BYTES, SECTOR_BYTES, STORAGE_BYTES,
};
use control::Settings;

/// Settings that differ from save to save (servo 3's trim).
fn settings(n: u32) -> Settings {
    let mut s = Settings::default();
    s.servos.0[2].home_us = 1400.0 + (n % 400) as f32 * 0.5;
    s.speed_mm_s = 1.0 + (n / 400) as f32;
    s
}

/// The power went off.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct PowerCut;

/// NOR flash whose power is cut after `budget` byte writes: an erase sets its sector's bytes to
/// 0xFF in address order, a program ANDs its page's bytes in, in order. At the cut the byte being
/// written is left half done (only the bits in `partial` of its change happen) and nothing more
/// is written until `power_on`.
#[derive(Clone)]
struct CutFlash {
    bytes: Vec<u8>,
    budget: Option<usize>,
    partial: u8,
    off: bool,
}

impl CutFlash {
    fn new() -> Self {
        CutFlash {
            bytes: vec![0xFF; STORAGE_BYTES as usize],
            budget: None,
            partial: 0,
            off: false,
        }
    }

    fn cut_after(&mut self, writes: usize, partial: u8) {
        self.budget = Some(writes);
        self.partial = partial;
    }

    fn power_on(&mut self) {
        self.budget = None;
        self.off = false;
    }

    /// Writes `target` at `at`, unless the power is (or now goes) off.
    fn step(&mut self, at: usize, target: u8) -> Result<(), PowerCut> {
        if self.off {
            return Err(PowerCut);
        }
        match self.budget {
            Some(0) => {
                let old = self.bytes[at];
                self.bytes[at] = old ^ ((old ^ target) & self.partial);
                self.off = true;
                Err(PowerCut)
            }
            Some(n) => {
                self.budget = Some(n - 1);
                self.bytes[at] = target;
                Ok(())
            }
            None => {
                self.bytes[at] = target;
                Ok(())
            }
        }
    }
}

impl NorFlash for CutFlash {
    type Error = PowerCut;

    fn read(&mut self, offset: u32, buf: &mut [u8]) {
        let start = offset as usize;
        buf.copy_from_slice(&self.bytes[start..start + buf.len()]);
    }

    fn erase_sector(&mut self, offset: u32) -> Result<(), PowerCut> {
        assert_eq!(offset % SECTOR_BYTES, 0, "erase of an unaligned sector");
        let start = offset as usize;
        for at in start..start + SECTOR_BYTES as usize {
            self.step(at, 0xFF)?;
        }
        Ok(())
    }

    fn program_page(&mut self, offset: u32, data: &[u8; PAGE_BYTES]) -> Result<(), PowerCut> {
        assert_eq!(
            offset % PAGE_BYTES as u32,
            0,
            "program of an unaligned page"
        );
        let start = offset as usize;
        for (i, d) in data.iter().enumerate() {
            let target = self.bytes[start + i] & d;
            self.step(start + i, target)?;
        }
        Ok(())
    }
}

/// Byte writes one save makes: a sector erased, a page programmed.
const WRITES_PER_SAVE: usize = SECTOR_BYTES as usize + PAGE_BYTES;

/// The flash after saves 1..=n, uncut.
fn after_saves(n: u32) -> (CutFlash, Store) {
    let mut flash = CutFlash::new();
    let mut store = Store::empty();
    for k in 1..=n {
        store
            .save(&mut flash, &settings(k), DEFAULT_BAUD)
            .expect("no cut");
    }
    (flash, store)
}

#[test]
fn a_power_cut_at_every_byte_of_a_save_boots_the_old_or_the_new_settings() {
    // The first save (nothing to keep), then saves into sector 1, 0 and 1 again.
    for n in 1..=4u32 {
        let old = (n > 1).then(|| settings(n - 1));
        let new = settings(n);
        let (before, store) = after_saves(n - 1);
        let mut loaded_new = 0;
        for cut in 0..=WRITES_PER_SAVE {
            for partial in [0x00, 0x0F, 0xA5, 0xFF] {
                let mut flash = before.clone();
                flash.cut_after(cut, partial);
                let mut s = store.clone();
                let result = s.save(&mut flash, &new, DEFAULT_BAUD);
                assert_eq!(
                    result.is_ok(),
                    cut == WRITES_PER_SAVE,
                    "save {n}, cut {cut}"
                );
                flash.power_on();
                let loaded = Store::load(&mut flash);
                let got = loaded.settings().copied();
                if got == Some(new) {
                    loaded_new += 1;
                    // Only a record complete to its last byte is the new one: the cut came
                    // within the erased bytes after it.
                    assert!(
                        cut >= SECTOR_BYTES as usize + ENCODED_LEN - 1,
                        "save {n}: the new settings loaded from a record cut at write {cut}"
                    );
                } else {
                    assert_eq!(
                        got, old,
                        "save {n} cut at write {cut} (partial {partial:#04x})"
                    );
                }
                if n > 1 {
                    assert!(
                        got.is_some(),
                        "save {n}: a good copy existed, nothing loaded"
                    );
                }
                // And saving goes on: the next save lands and is loaded.
                let mut next = loaded.store.clone();
                next.save(&mut flash, &settings(100 + n), DEFAULT_BAUD)
                    .expect("no cut now");
                assert_eq!(Store::load(&mut flash).settings(), Some(&settings(100 + n)));
            }
        }
        assert!(loaded_new > 0, "save {n} never completed");
    }
}

#[test]
fn a_page_programmed_only_in_part_never_loads_as_anything_but_old_or_new() {
    // NOR programming clears bits; cut short, an arbitrary subset of the 1 -> 0 changes has
    // happened, not necessarily in byte order. Seeded pseudo-random subsets.
    let (mut flash, store) = after_saves(2);
    let old = settings(2);
    let new = settings(3);
    let write = store.prepare(&new, DEFAULT_BAUD);
    flash.erase_sector(write.offset()).unwrap();
    let erased = flash.clone();
    let page = write.page();
    let mut x = 0x2545_F491u32;
    let mut next = || {
        // xorshift32
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x
    };
    for trial in 0..5000 {
        let mut flash = erased.clone();
        let density = trial % 8; // how many of the changes happened: 1/8 .. all
        let mut partial = [0xFFu8; PAGE_BYTES];
        for (p, d) in partial.iter_mut().zip(page) {
            let mut keep = 0u8;
            for _ in 0..=density {
                keep |= next() as u8;
            }
            // Bits of `d` that are 0 are cleared only where `keep` is set.
            *p = d | !keep;
        }
        flash.program_page(write.offset(), &partial).unwrap();
        let got = Store::load(&mut flash).settings().copied();
        if got == Some(new) {
            let start = write.offset() as usize;
            assert_eq!(
                &flash.bytes[start..start + PAGE_BYTES],
                &page[..],
                "trial {trial}"
            );
        } else {
            assert_eq!(got, Some(old), "trial {trial}");
        }
    }
}

#[test]
fn a_thousand_saves_alternate_sectors_and_each_is_loaded() {
    let mut flash = RamFlash::new();
    let mut store = Store::empty();
    for n in 1..=1000u32 {
        let write = store.prepare(&settings(n), DEFAULT_BAUD);
        // Save 1 into sector 0, save 2 into sector 1, and so on.
        assert_eq!(write.sector(), ((n - 1) % 2) as usize, "save {n}");
        assert_eq!(write.record().sequence, n);
        write.perform(&mut flash).expect("RAM flash");
        store.commit(&write);
        let loaded = Store::load(&mut flash);
        assert_eq!(loaded.settings(), Some(&settings(n)), "save {n}");
        assert_eq!(loaded.found, Found::Saved { sequence: n });
        // The other sector still holds the save before.
        if n > 1 {
            let other = (n % 2) as usize;
            let mut page = [0u8; PAGE_BYTES];
            flash.read(other as u32 * SECTOR_BYTES, &mut page);
            let previous = record::decode(&page).expect("the previous save is intact");
            assert_eq!(
                previous,
                Record {
                    sequence: n - 1,
                    settings: settings(n - 1),
                    baud: DEFAULT_BAUD,
                }
            );
        }
    }
    assert_eq!(flash.erases, [500, 500]);
}

#[test]
fn sequence_numbers_run_on_across_the_wrap() {
    let mut flash = RamFlash::new();
    let late = Record {
        sequence: u32::MAX - 1,
        settings: settings(1),
        baud: DEFAULT_BAUD,
    };
    let mut page = [0xFF; PAGE_BYTES];
    page[..ENCODED_LEN].copy_from_slice(&record::encode(&late));
    flash.program_page(SECTOR_BYTES, &page).unwrap();
    let mut store = Store::load(&mut flash).store;
    for (n, sequence) in [(2, u32::MAX), (3, 0), (4, 1)] {
        store.save(&mut flash, &settings(n), DEFAULT_BAUD).unwrap();
        let loaded = Store::load(&mut flash);
        assert_eq!(loaded.settings(), Some(&settings(n)));
        assert_eq!(loaded.found, Found::Saved { sequence });
    }
}

#[test]
fn a_flipped_bit_in_either_copy_is_found_and_the_other_copy_loaded() {
    let (flash, _) = after_saves(2); // save 1 in sector 0, save 2 (newest) in sector 1
    for sector in [0u32, 1] {
        for byte in (0..ENCODED_LEN).step_by(7) {
            for bit in [0, 3, 7] {
                let mut damaged = flash.clone();
                damaged.bytes[(sector * SECTOR_BYTES) as usize + byte] ^= 1 << bit;
                let loaded = Store::load(&mut damaged);
                // Sector 1's damage leaves save 1; sector 0's leaves save 2.
                let (good, sequence) = if sector == 1 { (1, 1) } else { (2, 2) };
                assert_eq!(
                    loaded.settings(),
                    Some(&settings(good)),
                    "{sector}/{byte}/{bit}"
                );
                let other_unusable = matches!(
                    loaded.found,
                    Found::SavedOtherUnusable { sequence: s, .. } if s == sequence
                );
                assert!(other_unusable, "{:?}", loaded.found);
                // The next save overwrites the damaged copy, never the good one.
                let mut store = loaded.store.clone();
                let write = store.prepare(&settings(9), DEFAULT_BAUD);
                assert_eq!(write.sector() as u32, sector);
                write.perform(&mut damaged).unwrap();
                store.commit(&write);
                let after = Store::load(&mut damaged);
                assert_eq!(after.settings(), Some(&settings(9)));
                assert!(matches!(after.found, Found::Saved { .. }));
            }
        }
    }
}

#[test]
fn nothing_saved_damaged_and_other_versions_are_told_apart() {
    let mut flash = CutFlash::new();
    assert_eq!(Store::load(&mut flash).found, Found::Nothing);

    // A record of format version 2 (what this firmware's predecessor would have written).
    let mut bytes = record::encode(&Record {
        sequence: 1,
        settings: Settings::default(),
        baud: DEFAULT_BAUD,
    });
    bytes[4] = 2;
    let crc = record::crc32(&bytes[..record::CRC_OFFSET]);
    bytes[record::CRC_OFFSET..].copy_from_slice(&crc.to_le_bytes());
    flash.bytes[SECTOR_BYTES as usize..][..ENCODED_LEN].copy_from_slice(&bytes);
    assert_eq!(
        Store::load(&mut flash).found,
        Found::Unusable(DecodeError::UnsupportedVersion(2))
    );
    // Damage in the other sector: the version is still what is reported.
    flash.bytes[0] = 0x12;
    assert_eq!(
        Store::load(&mut flash).found,
        Found::Unusable(DecodeError::UnsupportedVersion(2))
    );
    // Damage alone.
    flash.bytes[SECTOR_BYTES as usize..].fill(0xFF);
    assert_eq!(
        Store::load(&mut flash).found,
        Found::Unusable(DecodeError::BadMagic)
    );
    let mut flash = CutFlash::new();
    let mut store = Store::empty();
    store.save(&mut flash, &settings(1), DEFAULT_BAUD).unwrap();
    flash.bytes[100] ^= 0x40;
    assert_eq!(
        Store::load(&mut flash).found,
        Found::Unusable(DecodeError::BadChecksum)
    );
}

/// A flash whose page at `stuck` will not clear bit 0 of its byte 5 (a worn cell).
struct Worn {
    inner: RamFlash,
    stuck: u32,
}

impl NorFlash for Worn {
    type Error = control::store::RamFlashError;
    fn read(&mut self, offset: u32, buf: &mut [u8]) {
        self.inner.read(offset, buf);
    }
    fn erase_sector(&mut self, offset: u32) -> Result<(), Self::Error> {
        self.inner.erase_sector(offset)
    }
    fn program_page(&mut self, offset: u32, data: &[u8; PAGE_BYTES]) -> Result<(), Self::Error> {
        let mut data = *data;
        if offset == self.stuck {
            data[5] |= 1;
        }
        self.inner.program_page(offset, &data)
    }
}

#[test]
fn a_write_that_does_not_read_back_fails_and_is_never_loaded() {
    let mut flash = Worn {
        inner: RamFlash::new(),
        stuck: SECTOR_BYTES,
    };
    let mut store = Store::empty();
    store.save(&mut flash, &settings(1), DEFAULT_BAUD).unwrap();
    let before = store.clone();
    // Save 2 goes to sector 1, whose byte 5 (the format version's high byte, 0) sticks at 1.
    let err = store
        .save(&mut flash, &settings(2), DEFAULT_BAUD)
        .unwrap_err();
    assert_eq!(
        err,
        SaveError::Verify {
            offset: SECTOR_BYTES + 5,
            wrote: 0x00,
            read: 0x01
        }
    );
    assert_eq!(
        store, before,
        "a failed save changes nothing the store knows"
    );
    let loaded = Store::load(&mut flash);
    assert_eq!(loaded.settings(), Some(&settings(1)));
    // The failed copy was cleared, so it reads as damaged, not as a save.
    assert!(matches!(
        loaded.found,
        Found::SavedOtherUnusable { sequence: 1, .. }
    ));
    // The next try goes to the same sector again (the good copy stays untouched).
    assert_eq!(store.prepare(&settings(2), DEFAULT_BAUD).sector(), 1);
}

fn any_byte() -> proptest::num::u8::Any {
    proptest::num::u8::ANY
}

proptest::proptest! {
    /// Flash contents are outside data: whatever the two sectors hold (here: two good saves
    /// with random bytes overwritten, or random pages), loading never panics, a loaded record
    /// is valid, and the next save goes to the other sector than the one loaded.
    #[test]
    fn loading_any_flash_contents_never_panics(
        damage in proptest::collection::vec((0usize..2 * PAGE_BYTES, any_byte()), 0..40),
        random in proptest::option::of(proptest::collection::vec(any_byte(), 512)),
    ) {
        let (mut flash, _) = after_saves(2);
        if let Some(bytes) = random {
            flash.bytes[..256].copy_from_slice(&bytes[..256]);
            flash.bytes[4096..4096 + 256].copy_from_slice(&bytes[256..]);
        }
        for (at, value) in damage {
            let sector = at / PAGE_BYTES;
            flash.bytes[sector * SECTOR_BYTES as usize + at % PAGE_BYTES] = value;
        }
        let loaded = Store::load(&mut flash);
        if let Some((sector, record)) = loaded.store.newest() {
            proptest::prop_assert!(record.settings.validate().is_ok());
            proptest::prop_assert_ne!(loaded.store.prepare(&settings(7), DEFAULT_BAUD).sector(), sector);
        }
    }
}

/// A board in the field holds a format-3 record (no baud rate). Written here from the format-3
/// table (control::record's docs): the format-5 bytes without `baud`'s four and the pivot's
/// twelve, re-headed and checksummed again.
#[test]
fn a_format_3_save_from_the_field_loads_at_the_default_rate_and_the_next_save_follows_it() {
    let mut flash = RamFlash::new();
    let new = record::encode(&Record {
        sequence: 17,
        settings: settings(3),
        baud: 921_600,
    });
    let mut old = Vec::new();
    old.extend_from_slice(&new[..228]);
    old.extend_from_slice(&new[244..248]); // the sequence number
    old[4..8].copy_from_slice(&[3, 0, 220, 0]);
    let crc = record::crc32(&old);
    old.extend_from_slice(&crc.to_le_bytes());
    let mut page = [0xFF; PAGE_BYTES];
    page[..old.len()].copy_from_slice(&old);
    flash.program_page(0, &page).unwrap();

    let loaded = Store::load(&mut flash);
    assert_eq!(loaded.found, Found::Saved { sequence: 17 });
    assert_eq!(loaded.settings(), Some(&settings(3)));
    assert_eq!(loaded.store.saved_baud(), Some(115_200));
    // The next save is format 5, save 18, in the other sector; the old one stays as it was.
    let mut store = loaded.store;
    store.save(&mut flash, &settings(4), 921_600).unwrap();
    let mut first = [0u8; PAGE_BYTES];
    flash.read(0, &mut first);
    assert_eq!(first, page, "the format-3 record untouched");
    let loaded = Store::load(&mut flash);
    assert_eq!(loaded.found, Found::Saved { sequence: 18 });
    assert_eq!(loaded.store.newest().map(|(i, _)| i), Some(1));
    assert_eq!(loaded.settings(), Some(&settings(4)));
    assert_eq!(loaded.store.saved_baud(), Some(921_600));
}
