//! The two flash sectors that keep the settings (`memory.x`: the last 8 KiB of the Pico's
//! 2 MiB flash) as a [`NorFlash`] for [`control::store`]: read through the XIP window, erased
//! and programmed through the boot ROM's flash routines.
//!
//! Erasing or programming takes the flash chip out of execute-in-place: from `flash_exit_xip`
//! until XIP is back, nothing may be fetched or read from flash. So each erase or program runs
//! in a short routine placed in RAM (section `.data`, copied there at start-up), with interrupts
//! masked (every handler and the vector table are in flash), calling the ROM through pointers
//! looked up beforehand (the lookup code is in flash), on data copied onto the stack (RAM):
//!
//! 1. `connect_internal_flash`: the QSPI pins to the flash chip;
//! 2. `flash_exit_xip`: the chip to command mode;
//! 3. `flash_range_erase` (one 4 KiB sector) or `flash_range_program` (one 256-byte page);
//! 4. `flash_flush_cache`: nothing stale stays in the XIP cache;
//! 5. `flash_enter_cmd_xip`: XIP again, in the ROM's slow serial read mode;
//! 6. a copy of boot2 in RAM, called as a function, as the pico-sdk does: the fast quad-SPI
//!    XIP mode boot2 set up at power-on (without it the firmware would run from flash at the
//!    slow mode's speed until the next reset).
//!
//! A sector erase takes the Pico's flash chip up to 400 ms (W25Q080 datasheet): `main` gives
//! the watchdog time for it. The PWM runs on (hardware), so the servos hold their pulses.
//!
//! The flash chip's unique ID (the board's id: its USB serial number) is read the same way,
//! with step 3 a command of our own: the boot ROM has no routine for it. With XIP off, the SSI
//! is a plain SPI master (8-bit frames, transmit and receive, as `flash_exit_xip` leaves it):
//! the chip select is forced low through the QSPI SS pad's output override, the W25Q080's
//! "Read Unique ID" (0x4B), four dummy bytes and eight more are clocked through the data
//! register (each byte sent brings one back), and the chip select is forced high again
//! (`flash_flush_cache` then hands it back to the SSI). The last eight bytes received are the
//! ID (W25Q080 datasheet, Read Unique ID Number).

use control::store::{NorFlash, PAGE_BYTES, SECTOR_BYTES, STORAGE_BYTES};
use rp2040_hal::rom_data;

/// Where the flash appears in the address space (execute-in-place, cached).
const XIP_BASE: u32 = 0x1000_0000;
/// boot2's size: the first 256 bytes of flash.
const BOOT2_BYTES: usize = 256;
/// What the ROM's erase may use for whole 64 KiB blocks (the W25Q080's block erase, 0xD8);
/// a single 4 KiB sector is always erased with the sector erase command.
const BLOCK_BYTES: u32 = 1 << 16;
const BLOCK_ERASE_CMD: u8 = 0xD8;

/// The W25Q080's Read Unique ID Number command, the dummy bytes that follow it, and the ID.
const READ_UNIQUE_ID_CMD: u8 = 0x4B;
const UNIQUE_ID_DUMMY_BYTES: usize = 4;
const UNIQUE_ID_BYTES: usize = 8;
/// The SSI's status and data registers (RP2040 datasheet, 4.10.13: XIP_SSI at 0x18000000).
const SSI_SR: *const u32 = 0x1800_0028 as *const u32;
const SSI_DR0: *mut u32 = 0x1800_0060 as *mut u32;
/// SR: transmit FIFO not full, receive FIFO not empty.
const SSI_SR_TFNF: u32 = 1 << 1;
const SSI_SR_RFNE: u32 = 1 << 3;
/// Bytes sent and not yet received back, at most: the FIFOs hold 16 each (the pico-sdk
/// keeps two spare, so the receive FIFO never overflows).
const SSI_MAX_IN_FLIGHT: usize = 14;
/// IO_QSPI's GPIO_QSPI_SS_CTRL (RP2040 datasheet, 2.19.6.2: IO_QSPI at 0x40018000) and its
/// OUTOVER field (bits 9:8): drive the chip select low or high.
const QSPI_SS_CTRL: *mut u32 = 0x4001_800C as *mut u32;
const QSPI_SS_OUTOVER_MASK: u32 = 0b11 << 8;
const QSPI_SS_OUTOVER_LOW: u32 = 0b10 << 8;
const QSPI_SS_OUTOVER_HIGH: u32 = 0b11 << 8;

// `memory.x`: the settings sectors (never filled by the linker).
unsafe extern "C" {
    static _settings_start: u8;
    static _settings_end: u8;
}

/// The boot ROM's flash routines, looked up while the code that looks them up can still run.
#[derive(Clone, Copy)]
#[repr(C)]
struct Rom {
    connect_internal_flash: unsafe extern "C" fn(),
    flash_exit_xip: unsafe extern "C" fn(),
    flash_range_erase: unsafe extern "C" fn(u32, usize, u32, u8),
    flash_range_program: unsafe extern "C" fn(u32, *const u8, usize),
    flash_flush_cache: unsafe extern "C" fn(),
    flash_enter_cmd_xip: unsafe extern "C" fn(),
    /// boot2, copied into RAM, called to restore the fast XIP mode.
    boot2: unsafe extern "C" fn(),
}

/// A copy of boot2 in RAM (word-aligned Thumb code).
static mut BOOT2_COPY: [u32; BOOT2_BYTES / 4] = [0; BOOT2_BYTES / 4];

/// An erase or program outside the settings sectors, or not aligned to its unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub struct OutOfRange;

/// The settings sectors.
pub struct SettingsFlash {
    /// Offset of the first sector from the start of flash.
    base: u32,
    rom: Rom,
}

impl SettingsFlash {
    /// Finds the sectors (from the linker) and the ROM routines, and copies boot2 into RAM.
    /// Call once, at start-up.
    pub fn new() -> SettingsFlash {
        let start = &raw const _settings_start as u32;
        let end = &raw const _settings_end as u32;
        assert!(
            end - start == STORAGE_BYTES && start % SECTOR_BYTES == 0,
            "memory.x reserves two aligned 4 KiB sectors for the settings"
        );
        // SAFETY: read once here before any flash write, from the XIP window (boot2 is the
        // first 256 bytes of flash); nothing else touches the copy.
        let boot2 = unsafe {
            let copy = &raw mut BOOT2_COPY;
            for i in 0..BOOT2_BYTES / 4 {
                let word = core::ptr::read_volatile((XIP_BASE as *const u32).add(i));
                (*copy)[i] = word;
            }
            // Thumb code: the address with bit 0 set.
            core::mem::transmute::<usize, unsafe extern "C" fn()>(copy as usize | 1)
        };
        SettingsFlash {
            base: start - XIP_BASE,
            rom: Rom {
                connect_internal_flash: rom_data::connect_internal_flash::ptr(),
                flash_exit_xip: rom_data::flash_exit_xip::ptr(),
                flash_range_erase: rom_data::flash_range_erase::ptr(),
                flash_range_program: rom_data::flash_range_program::ptr(),
                flash_flush_cache: rom_data::flash_flush_cache::ptr(),
                flash_enter_cmd_xip: rom_data::flash_enter_cmd_xip::ptr(),
                boot2,
            },
        }
    }

    /// The flash chip's 64-bit unique ID (its eight bytes in the order the chip sends them,
    /// most significant first). A few microseconds with interrupts masked; call at start-up.
    pub fn unique_id(&mut self) -> u64 {
        let rom = self.rom;
        let mut id = [0u8; UNIQUE_ID_BYTES];
        // SAFETY: as for the erase; `id` is on the stack.
        cortex_m::interrupt::free(|_| unsafe { unique_id_from_ram(&rom, &mut id) });
        u64::from_be_bytes(id)
    }

    /// The first sector's offset from the start of flash (for the log).
    pub fn base(&self) -> u32 {
        self.base
    }

    /// `offset..offset + len` within the storage and `offset` a multiple of `align`.
    fn check(offset: u32, len: u32, align: u32) -> Result<(), OutOfRange> {
        match offset.checked_add(len) {
            Some(end) if end <= STORAGE_BYTES && offset % align == 0 => Ok(()),
            _ => Err(OutOfRange),
        }
    }
}

impl NorFlash for SettingsFlash {
    type Error = OutOfRange;

    fn read(&mut self, offset: u32, buf: &mut [u8]) {
        for (i, b) in buf.iter_mut().enumerate() {
            let at = offset as usize + i;
            *b = if at < STORAGE_BYTES as usize {
                // SAFETY: inside the settings sectors, read through the XIP window.
                unsafe { core::ptr::read_volatile((XIP_BASE + self.base + at as u32) as *const u8) }
            } else {
                0xFF
            };
        }
    }

    fn erase_sector(&mut self, offset: u32) -> Result<(), OutOfRange> {
        Self::check(offset, SECTOR_BYTES, SECTOR_BYTES)?;
        let rom = self.rom;
        let address = self.base + offset;
        // SAFETY: interrupts masked for the whole time XIP is off; the routine and everything
        // it touches (its arguments, `rom`, the boot2 copy) are in RAM.
        cortex_m::interrupt::free(|_| unsafe { erase_from_ram(&rom, address) });
        Ok(())
    }

    fn program_page(&mut self, offset: u32, data: &[u8; PAGE_BYTES]) -> Result<(), OutOfRange> {
        Self::check(offset, PAGE_BYTES as u32, PAGE_BYTES as u32)?;
        // `data` may be a constant in flash, which cannot be read while XIP is off: a copy on
        // the stack.
        let page = *data;
        let rom = self.rom;
        let address = self.base + offset;
        // SAFETY: as for the erase; the page is on the stack.
        cortex_m::interrupt::free(|_| unsafe { program_from_ram(&rom, address, &page) });
        Ok(())
    }
}

/// Erases the 4 KiB sector at `address` (offset from the start of flash). Runs from RAM.
///
/// # Safety
/// Interrupts masked; `rom` in RAM; `address` a sector the firmware's code is not in.
#[inline(never)]
#[unsafe(link_section = ".data.ram_func.erase_from_ram")]
unsafe extern "C" fn erase_from_ram(rom: &Rom, address: u32) {
    unsafe {
        (rom.connect_internal_flash)();
        (rom.flash_exit_xip)();
        (rom.flash_range_erase)(address, SECTOR_BYTES as usize, BLOCK_BYTES, BLOCK_ERASE_CMD);
        (rom.flash_flush_cache)();
        (rom.flash_enter_cmd_xip)();
        (rom.boot2)();
    }
}

/// Programs the 256-byte page at `address` (offset from the start of flash). Runs from RAM.
///
/// # Safety
/// As [`erase_from_ram`], and `page` in RAM.
#[inline(never)]
#[unsafe(link_section = ".data.ram_func.program_from_ram")]
unsafe extern "C" fn program_from_ram(rom: &Rom, address: u32, page: &[u8; PAGE_BYTES]) {
    unsafe {
        (rom.connect_internal_flash)();
        (rom.flash_exit_xip)();
        (rom.flash_range_program)(address, page.as_ptr(), PAGE_BYTES);
        (rom.flash_flush_cache)();
        (rom.flash_enter_cmd_xip)();
        (rom.boot2)();
    }
}

/// Reads the flash chip's unique ID into `id` (see the module docs). Runs from RAM.
///
/// # Safety
/// Interrupts masked; `rom` and `id` in RAM.
#[inline(never)]
#[unsafe(link_section = ".data.ram_func.unique_id_from_ram")]
unsafe extern "C" fn unique_id_from_ram(rom: &Rom, id: &mut [u8; UNIQUE_ID_BYTES]) {
    const HEADER: usize = 1 + UNIQUE_ID_DUMMY_BYTES;
    const TOTAL: usize = HEADER + UNIQUE_ID_BYTES;
    unsafe {
        (rom.connect_internal_flash)();
        (rom.flash_exit_xip)();
        force_chip_select(QSPI_SS_OUTOVER_LOW);
        let (mut sent, mut received) = (0, 0);
        while received < TOTAL {
            let status = core::ptr::read_volatile(SSI_SR);
            if status & SSI_SR_TFNF != 0 && sent < TOTAL && sent - received < SSI_MAX_IN_FLIGHT {
                let byte = if sent == 0 { READ_UNIQUE_ID_CMD } else { 0 };
                core::ptr::write_volatile(SSI_DR0, u32::from(byte));
                sent += 1;
            }
            if status & SSI_SR_RFNE != 0 && received < sent {
                let byte = core::ptr::read_volatile(SSI_DR0) as u8;
                if let Some(slot) = id.get_mut(received.wrapping_sub(HEADER)) {
                    *slot = byte;
                }
                received += 1;
            }
        }
        force_chip_select(QSPI_SS_OUTOVER_HIGH);
        (rom.flash_flush_cache)();
        (rom.flash_enter_cmd_xip)();
        (rom.boot2)();
    }
}

/// Sets the QSPI chip select's output override. Inlined into the routine in RAM.
///
/// # Safety
/// Only while XIP is off (the SSI drives the chip select otherwise).
#[inline(always)]
unsafe fn force_chip_select(outover: u32) {
    unsafe {
        let ctrl = core::ptr::read_volatile(QSPI_SS_CTRL);
        core::ptr::write_volatile(QSPI_SS_CTRL, (ctrl & !QSPI_SS_OUTOVER_MASK) | outover);
    }
}
