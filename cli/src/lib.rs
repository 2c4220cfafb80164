//! The host tool's library: what `hexapod`'s subcommands are made of, each testable on its own.
//!
//! - [`elf`]: the load segments of an ELF file, where a programmer writes them;
//! - [`uf2`]: a UF2 file of those segments, for the RP2040's USB drag-and-drop bootloader, and
//!   the file read back.

pub mod elf;
pub mod uf2;
