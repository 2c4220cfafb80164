//! UF2 files for the RP2040's USB bootloader (hold BOOTSEL while plugging the Pico in: the
//! `RPI-RP2` drive; copy a `.uf2` onto it). A UF2 file is a run of 512-byte blocks, each with
//! a header, up to 476 bytes of data and an end magic (the UF2 specification). For the RP2040
//! every block carries 256 bytes (one flash page) for a page-aligned flash address, and the
//! RP2040 family id (flag 0x2000: family id present).
//!
//! The RP2040 boot ROM decides which 4 KiB flash sectors to erase from the blocks it is given,
//! so a file must hold every page of each sector it touches, from the sector's first page on
//! (zeros where the ELF has nothing), up to its last page: elf2uf2-rs and picotool write files
//! the same way, and `tests/uf2.rs` compares with elf2uf2-rs 2.2.0 byte for byte.

use std::collections::BTreeMap;
use std::fmt;

use crate::elf::Segment;

/// Bytes in a block.
pub const BLOCK_BYTES: usize = 512;
/// Data bytes a block carries for the RP2040: one flash page.
pub const PAYLOAD_BYTES: usize = 256;
/// First magic number ("UF2\n").
pub const MAGIC_START0: u32 = 0x0A32_4655;
/// Second magic number.
pub const MAGIC_START1: u32 = 0x9E5D_5157;
/// Final magic number, the block's last four bytes.
pub const MAGIC_END: u32 = 0x0AB1_6F30;
/// The flag saying the header's file-size word holds a family id.
pub const FLAG_FAMILY_ID_PRESENT: u32 = 0x0000_2000;
/// The RP2040's family id.
pub const RP2040_FAMILY_ID: u32 = 0xE48B_FF56;
/// Where the RP2040 maps its flash (execute-in-place), as the bootloader accepts it.
pub const FLASH: std::ops::Range<u32> = 0x1000_0000..0x1100_0000;
const SECTOR_BYTES: u32 = 4096;
const DATA_BYTES: usize = 476;

/// Why no UF2 file could be written, or a file read back is not a good one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Uf2Error {
    /// The ELF has no bytes to load.
    Empty,
    /// A segment's bytes lie (partly) outside the flash: `address..end`.
    NotInFlash { address: u32, end: u64 },
    /// Two segments put a byte at the same address.
    Overlap { address: u32 },
    /// A file whose length is not a positive multiple of 512 bytes.
    Length(usize),
    /// Block `index` is not a well-formed UF2 block: what is wrong.
    Block { index: usize, what: &'static str },
}

impl fmt::Display for Uf2Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Uf2Error::Empty => f.write_str("the ELF file has nothing to load"),
            Uf2Error::NotInFlash { address, end } => write!(
                f,
                "bytes at {address:#010x}..{end:#010x} are not in the RP2040's flash \
                 ({:#010x}..{:#010x})",
                FLASH.start, FLASH.end
            ),
            Uf2Error::Overlap { address } => {
                write!(f, "two segments both load a byte at {address:#010x}")
            }
            Uf2Error::Length(n) => write!(f, "{n} bytes is not a whole number of 512-byte blocks"),
            Uf2Error::Block { index, what } => write!(f, "block {index}: {what}"),
        }
    }
}

/// The UF2 file that writes `segments` (load addresses in flash) to an RP2040.
pub fn from_segments(segments: &[Segment]) -> Result<Vec<u8>, Uf2Error> {
    // Each page touched, with which of its bytes a segment has set.
    let mut pages: BTreeMap<u32, ([u8; PAYLOAD_BYTES], [bool; PAYLOAD_BYTES])> = BTreeMap::new();
    for segment in segments {
        let end = u64::from(segment.address) + segment.bytes.len() as u64;
        if segment.address < FLASH.start || end > u64::from(FLASH.end) {
            return Err(Uf2Error::NotInFlash {
                address: segment.address,
                end,
            });
        }
        for (address, &byte) in (segment.address..).zip(&segment.bytes) {
            let (page, set) = pages
                .entry(address & !(PAYLOAD_BYTES as u32 - 1))
                .or_insert(([0; PAYLOAD_BYTES], [false; PAYLOAD_BYTES]));
            let at = address as usize % PAYLOAD_BYTES;
            if std::mem::replace(&mut set[at], true) {
                return Err(Uf2Error::Overlap { address });
            }
            page[at] = byte;
        }
    }
    let Some(&last) = pages.keys().next_back() else {
        return Err(Uf2Error::Empty);
    };
    // Every page of each sector touched, up to the last page (see the module docs).
    let sectors: Vec<u32> = pages.keys().map(|a| a & !(SECTOR_BYTES - 1)).collect();
    for sector in sectors {
        for page in (sector..sector + SECTOR_BYTES)
            .step_by(PAYLOAD_BYTES)
            .take_while(|&p| p < last)
        {
            pages
                .entry(page)
                .or_insert(([0; PAYLOAD_BYTES], [false; PAYLOAD_BYTES]));
        }
    }
    let count = pages.len() as u32;
    let mut file = Vec::with_capacity(pages.len() * BLOCK_BYTES);
    for (number, (address, (page, _))) in (0u32..).zip(&pages) {
        let header = [
            MAGIC_START0,
            MAGIC_START1,
            FLAG_FAMILY_ID_PRESENT,
            *address,
            PAYLOAD_BYTES as u32,
            number,
            count,
            RP2040_FAMILY_ID,
        ];
        header
            .iter()
            .for_each(|word| file.extend_from_slice(&word.to_le_bytes()));
        file.extend_from_slice(page);
        file.resize(file.len() + DATA_BYTES - PAYLOAD_BYTES, 0);
        file.extend_from_slice(&MAGIC_END.to_le_bytes());
    }
    Ok(file)
}

/// One block of a UF2 file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Block {
    /// Flags (0x2000: `family_id` is a family id).
    pub flags: u32,
    /// Where the payload goes.
    pub target_address: u32,
    /// Its number in the file, from 0.
    pub block_number: u32,
    /// How many blocks the file has.
    pub block_count: u32,
    /// The family id (or the file size, without flag 0x2000).
    pub family_id: u32,
    /// The data, `payload_size` bytes.
    pub payload: Vec<u8>,
}

/// Reads a UF2 file back into its blocks, refusing anything that is not whole blocks with
/// both magic numbers at both ends and a payload that fits.
pub fn parse(file: &[u8]) -> Result<Vec<Block>, Uf2Error> {
    if file.is_empty() || file.len() % BLOCK_BYTES != 0 {
        return Err(Uf2Error::Length(file.len()));
    }
    file.chunks_exact(BLOCK_BYTES)
        .enumerate()
        .map(|(index, block)| {
            let word = |i: usize| {
                u32::from_le_bytes([
                    block[4 * i],
                    block[4 * i + 1],
                    block[4 * i + 2],
                    block[4 * i + 3],
                ])
            };
            let bad = |what| Uf2Error::Block { index, what };
            if word(0) != MAGIC_START0 || word(1) != MAGIC_START1 {
                return Err(bad("bad start magic"));
            }
            if word(127) != MAGIC_END {
                return Err(bad("bad end magic"));
            }
            let size = word(4) as usize;
            if size > DATA_BYTES {
                return Err(bad("payload larger than 476 bytes"));
            }
            Ok(Block {
                flags: word(2),
                target_address: word(3),
                block_number: word(5),
                block_count: word(6),
                family_id: word(7),
                payload: block[32..32 + size].to_vec(),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn segment(address: u32, bytes: &[u8]) -> Segment {
        Segment {
            address,
            bytes: bytes.to_vec(),
        }
    }

    /// Little-endian word `i` of block `b`.
    fn word(file: &[u8], b: usize, i: usize) -> u32 {
        let at = b * 512 + 4 * i;
        u32::from_le_bytes(file[at..at + 4].try_into().unwrap())
    }

    #[test]
    fn blocks_follow_the_uf2_layout() {
        // 300 bytes from 0x10000000: two pages, the second 44 bytes then zeros.
        let bytes: Vec<u8> = (0..300).map(|i| (i % 200) as u8 + 1).collect();
        let file = from_segments(&[segment(0x1000_0000, &bytes)]).unwrap();
        assert_eq!(file.len(), 2 * 512);
        for b in 0..2 {
            // The UF2 specification's header: magics, flags, address, size, number, count,
            // family; the end magic in the last word.
            assert_eq!(word(&file, b, 0), 0x0A32_4655);
            assert_eq!(word(&file, b, 1), 0x9E5D_5157);
            assert_eq!(word(&file, b, 2), 0x2000);
            assert_eq!(word(&file, b, 3), 0x1000_0000 + 256 * b as u32);
            assert_eq!(word(&file, b, 4), 256);
            assert_eq!(word(&file, b, 5), b as u32);
            assert_eq!(word(&file, b, 6), 2);
            assert_eq!(word(&file, b, 7), 0xE48B_FF56);
            assert_eq!(word(&file, b, 127), 0x0AB1_6F30);
            assert!(file[b * 512 + 32 + 256..b * 512 + 508]
                .iter()
                .all(|&x| x == 0));
        }
        assert_eq!(&file[32..32 + 256], &bytes[..256]);
        assert_eq!(&file[512 + 32..512 + 32 + 44], &bytes[256..]);
        assert!(file[512 + 32 + 44..512 + 32 + 256].iter().all(|&x| x == 0));
    }

    #[test]
    fn every_page_of_a_touched_sector_is_written_up_to_the_last_page() {
        // One byte at the start of flash and one in the middle of the second sector: pages
        // 0x000..0xF00 (all of sector 0), then sector 1 from its start to its byte's page.
        let file =
            from_segments(&[segment(0x1000_0000, &[1]), segment(0x1000_1310, &[2])]).unwrap();
        let addresses: Vec<u32> = parse(&file)
            .unwrap()
            .iter()
            .map(|b| b.target_address)
            .collect();
        let expected: Vec<u32> = (0..16)
            .chain(16..20)
            .map(|p| 0x1000_0000 + 256 * p)
            .collect();
        assert_eq!(addresses, expected);
    }

    #[test]
    fn what_cannot_be_written_is_refused() {
        assert_eq!(from_segments(&[]), Err(Uf2Error::Empty));
        assert!(matches!(
            from_segments(&[segment(0x2000_0000, &[1, 2])]),
            Err(Uf2Error::NotInFlash {
                address: 0x2000_0000,
                ..
            })
        ));
        assert!(matches!(
            from_segments(&[segment(0x10FF_FFFF, &[1, 2])]),
            Err(Uf2Error::NotInFlash { .. })
        ));
        assert_eq!(
            from_segments(&[segment(0x1000_0000, &[1, 2, 3]), segment(0x1000_0002, &[4])]),
            Err(Uf2Error::Overlap {
                address: 0x1000_0002
            })
        );
    }

    #[test]
    fn damaged_files_are_refused_when_read_back() {
        let file = from_segments(&[segment(0x1000_0000, &[7; 10])]).unwrap();
        assert_eq!(parse(&file[..511]), Err(Uf2Error::Length(511)));
        assert_eq!(parse(&[]), Err(Uf2Error::Length(0)));
        let mut bad = file.clone();
        bad[0] ^= 1;
        assert!(matches!(parse(&bad), Err(Uf2Error::Block { index: 0, .. })));
        let mut bad = file.clone();
        bad[511] ^= 1;
        assert!(matches!(parse(&bad), Err(Uf2Error::Block { index: 0, .. })));
        let mut bad = file;
        bad[16..20].copy_from_slice(&477u32.to_le_bytes());
        assert!(matches!(parse(&bad), Err(Uf2Error::Block { index: 0, .. })));
    }
}
