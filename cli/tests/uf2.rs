//! `hexapod uf2` against what it must write: the fixture ELF's UF2 byte for byte as
//! elf2uf2-rs 2.2.0 wrote it (`tests/fixtures/README.md`), and every byte of every load segment
//! read back from the file at its load address (the ELF read here by a reader of this test's
//! own, not the tool's). The firmware's own UF2 boots in the emulator
//! (`emulator/test/uf2.test.js`).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Command;

use hexapod::{elf, uf2};

fn fixture(name: &str) -> Vec<u8> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `(load address, bytes)` of each PT_LOAD segment with file contents (ELF32 little-endian
/// program headers: type, offset, vaddr, paddr, filesz, memsz).
fn load_segments(elf: &[u8]) -> Vec<(u32, Vec<u8>)> {
    let word = |at: usize| u32::from_le_bytes(elf[at..at + 4].try_into().unwrap()) as usize;
    let half = |at: usize| u16::from_le_bytes(elf[at..at + 2].try_into().unwrap()) as usize;
    let (table, size, count) = (word(0x1c), half(0x2a), half(0x2c));
    (0..count)
        .map(|i| table + i * size)
        .filter(|&h| word(h) == 1 && word(h + 16).min(word(h + 20)) > 0)
        .map(|h| {
            let len = word(h + 16).min(word(h + 20));
            (
                word(h + 12) as u32,
                elf[word(h + 4)..word(h + 4) + len].to_vec(),
            )
        })
        .collect()
}

#[test]
fn the_fixture_uf2_is_elf2uf2_rs_s_byte_for_byte() {
    let segments = elf::load_segments(&fixture("tiny.elf")).unwrap();
    let ours = uf2::from_segments(&segments).unwrap();
    let reference = fixture("tiny.uf2");
    assert_eq!(ours.len(), reference.len());
    if let Some(at) = ours.iter().zip(&reference).position(|(a, b)| a != b) {
        panic!("differs from elf2uf2-rs at byte {at} (block {})", at / 512);
    }
}

#[test]
fn the_fixture_uf2_reads_back_as_the_elf_load_segments() {
    let elf = fixture("tiny.elf");
    let segments = load_segments(&elf);
    // The fixture exercises what a firmware has: four segments, one stored in flash for RAM
    // (.data), one after a gap straddling a page boundary.
    assert_eq!(segments.len(), 4);
    let file = uf2::from_segments(&elf::load_segments(&elf).unwrap()).unwrap();
    let blocks = uf2::parse(&file).unwrap();
    let mut image: BTreeMap<u32, u8> = BTreeMap::new();
    for (n, block) in blocks.iter().enumerate() {
        assert_eq!(block.block_number as usize, n, "numbered in order from 0");
        assert_eq!(block.block_count as usize, blocks.len());
        assert_eq!((block.flags, block.family_id), (0x2000, 0xE48B_FF56));
        assert_eq!(block.payload.len(), 256);
        assert_eq!(block.target_address % 256, 0);
        for (address, &byte) in (block.target_address..).zip(&block.payload) {
            assert!(
                image.insert(address, byte).is_none(),
                "{address:#x} written twice"
            );
        }
    }
    let mut loaded = 0;
    for (address, bytes) in &segments {
        for (a, &b) in (*address..).zip(bytes) {
            assert_eq!(image.remove(&a), Some(b), "byte at {a:#x}");
            loaded += 1;
        }
    }
    assert_eq!(loaded, 0x108 + 0x14 + 4 + 300);
    // The rest is padding: zeros, in pages of the sectors the segments touch.
    assert!(image.values().all(|&b| b == 0));
    let first = blocks.first().unwrap().target_address;
    let last = blocks.last().unwrap().target_address;
    assert_eq!((first, last), (0x1000_0000, 0x1000_2000));
    assert_eq!(blocks.len(), 33, "every page from 0x10000000 to 0x10002000");
}

#[test]
fn hexapod_uf2_writes_the_file_and_says_what_to_do_with_it() {
    let dir = std::env::temp_dir().join(format!("hexapod-uf2-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("tiny.uf2");
    let elf = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/tiny.elf");
    let run = Command::new(env!("CARGO_BIN_EXE_hexapod"))
        .args([
            "uf2".as_ref(),
            elf.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ])
        .output()
        .unwrap();
    assert!(run.status.success(), "{run:?}");
    let said = String::from_utf8_lossy(&run.stdout);
    assert!(
        said.contains("33 blocks") && said.contains("RPI-RP2"),
        "{said}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), fixture("tiny.uf2"));

    // Not an ELF: an error naming the file, no file written, a failing exit.
    let bad = dir.join("bad.uf2");
    let run = Command::new(env!("CARGO_BIN_EXE_hexapod"))
        .args([
            "uf2".as_ref(),
            out.as_os_str(),
            "-o".as_ref(),
            bad.as_os_str(),
        ])
        .output()
        .unwrap();
    assert!(!run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("not an ELF file"));
    assert!(!bad.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_subcommands_are_listed() {
    let run = Command::new(env!("CARGO_BIN_EXE_hexapod"))
        .arg("--help")
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&run.stdout);
    assert!(help.contains("uf2"), "{help}");
}

#[test]
fn a_damaged_elf_is_refused_never_a_panic() {
    let elf = fixture("tiny.elf");
    // Every truncation, and every byte of the headers replaced by 0xFF.
    for len in 0..elf.len() {
        let _ = elf::load_segments(&elf[..len]).map(|s| uf2::from_segments(&s));
    }
    for at in 0..0x60.min(elf.len()) {
        let mut bad = elf.clone();
        bad[at] = 0xFF;
        let _ = elf::load_segments(&bad).map(|s| uf2::from_segments(&s));
    }
}
