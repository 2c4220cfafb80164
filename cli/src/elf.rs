//! The load segments of a 32-bit little-endian ARM ELF file (what `cargo fw` builds), at their
//! load (physical) addresses: where a programmer writes them. `.data`'s initial values, run in
//! RAM, are stored in flash after the code: their load address is in flash. And the value of
//! a symbol (e.g. `_settings_start`, which `memory.x` defines), from the symbol table.

use std::fmt;

/// Bytes to put at an address.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Segment {
    /// The load address of the first byte.
    pub address: u32,
    /// The contents (the file's bytes of the segment).
    pub bytes: Vec<u8>,
}

/// Why a file is not an ELF file this tool can read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ElfError {
    /// Not an ELF file at all.
    NotElf,
    /// An ELF file, but not 32-bit little-endian ARM (the RP2040's).
    NotArm32,
    /// A header or a segment reaches past the end of the file.
    Truncated,
}

impl fmt::Display for ElfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ElfError::NotElf => "not an ELF file",
            ElfError::NotArm32 => "not a 32-bit little-endian ARM ELF file (the RP2040's)",
            ElfError::Truncated => "the ELF file is cut short (a header or segment past its end)",
        })
    }
}

const PT_LOAD: u32 = 1;
const EM_ARM: u16 = 40;

fn u16_at(file: &[u8], at: usize) -> Result<u16, ElfError> {
    let b = file
        .get(at..at.saturating_add(2))
        .ok_or(ElfError::Truncated)?;
    Ok(u16::from_le_bytes([b[0], b[1]]))
}

fn u32_at(file: &[u8], at: usize) -> Result<u32, ElfError> {
    let b = file
        .get(at..at.saturating_add(4))
        .ok_or(ElfError::Truncated)?;
    Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// The `PT_LOAD` segments with contents, in file order: their load address and the bytes the
/// file holds for them (the part of a segment beyond its file size is zero-initialised at run
/// time, not stored).
pub fn load_segments(file: &[u8]) -> Result<Vec<Segment>, ElfError> {
    if file.get(..4) != Some(b"\x7fELF".as_slice()) {
        return Err(ElfError::NotElf);
    }
    // ELFCLASS32, ELFDATA2LSB, machine ARM.
    if file.get(4..6) != Some([1u8, 1].as_slice()) || u16_at(file, 0x12)? != EM_ARM {
        return Err(ElfError::NotArm32);
    }
    let table = u32_at(file, 0x1c)? as usize;
    let entry_size = usize::from(u16_at(file, 0x2a)?);
    let count = usize::from(u16_at(file, 0x2c)?);
    let mut segments = Vec::new();
    for i in 0..count {
        let header = table.saturating_add(i.saturating_mul(entry_size));
        let field = |at: usize| u32_at(file, header.saturating_add(at));
        if field(0)? != PT_LOAD {
            continue;
        }
        let offset = field(4)? as usize;
        let address = field(12)?;
        let size = field(16)?.min(field(20)?) as usize;
        if size == 0 {
            continue;
        }
        let end = offset.checked_add(size).ok_or(ElfError::Truncated)?;
        let bytes = file.get(offset..end).ok_or(ElfError::Truncated)?.to_vec();
        segments.push(Segment { address, bytes });
    }
    Ok(segments)
}

const SHT_SYMTAB: u32 = 2;
const SYMBOL_BYTES: usize = 16;

/// The value of the symbol `name` (an address, for the linker script's symbols), if the file's
/// symbol table has it.
pub fn symbol(file: &[u8], name: &str) -> Result<Option<u32>, ElfError> {
    load_segments(file)?; // the same checks of the file
    let table = u32_at(file, 0x20)? as usize;
    let entry_size = usize::from(u16_at(file, 0x2e)?);
    let count = usize::from(u16_at(file, 0x30)?);
    let section = |i: usize, at: usize| {
        u32_at(
            file,
            table
                .saturating_add(i.saturating_mul(entry_size))
                .saturating_add(at),
        )
    };
    for i in 0..count {
        if section(i, 4)? != SHT_SYMTAB {
            continue;
        }
        let (offset, size) = (section(i, 16)? as usize, section(i, 20)? as usize);
        let strings = section(section(i, 24)? as usize, 16)? as usize;
        for entry in (offset..offset.saturating_add(size)).step_by(SYMBOL_BYTES) {
            let name_at = strings.saturating_add(u32_at(file, entry)? as usize);
            let rest = file.get(name_at..).ok_or(ElfError::Truncated)?;
            let end = rest
                .iter()
                .position(|&b| b == 0)
                .ok_or(ElfError::Truncated)?;
            if &rest[..end] == name.as_bytes() {
                return Ok(Some(u32_at(file, entry + 4)?));
            }
        }
    }
    Ok(None)
}
