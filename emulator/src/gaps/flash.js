// The flash, gap 7 of rp2040js 1.4.1 (numbered as in index.js).
//
// The chip: the Pico's 2 MiB W25Q080-class QSPI flash, written only through the SSI in
// command mode (the boot ROM's routines, run with XIP off); a store into the flash window
// never reaches it. rp2040js and the model:
//
// 7. Flash writes. rp2040js has no flash interface: its SSI is a stub, so the boot ROM's flash
//    routines run to their end and change nothing; and a plain CPU store into the flash window
//    (0x10000000..0x13ffffff) changes its flash array, which on a real chip never reaches the
//    flash. `FlashChip` is the Pico's flash as firmware sees it through the boot ROM: the ROM
//    function table's entries for connect_internal_flash (IF), flash_exit_xip (EX),
//    flash_range_erase (RE), flash_range_program (RP), flash_flush_cache (FC) and
//    flash_enter_cmd_xip (CX) lead to `BKPT #n; BX LR`, and the breakpoint does the routine's
//    work on the flash array: an erase sets 4096-aligned sectors to 0xFF, a program ANDs
//    256-aligned pages in (NOR: bits only go from 1 to 0). Each takes the flash chip's time
//    in emulated time, the core busy in the ROM meanwhile (its cycles count): the Winbond
//    W25Q80DV datasheet's 4 KiB sector erase (tSE) and page program (tPP) times,
//    `W25Q080_TIMING`, typical (45 ms, 0.7 ms) by default, maximum (400 ms, 3 ms) on request;
//    the other four routines and the SPI transfer take no time here (flash_flush_cache empties
//    the XIP cache model, gap 13, which costs its flush). The chip's rules are
//    enforced and a breach fails the run: every routine is called from SRAM (LR) with PRIMASK
//    set; EX comes after IF, RE and RP after EX; from EX until CX nothing in the flash window
//    is fetched, read or written (the chip is in command mode); the data to program is in
//    SRAM; erase and program are aligned and within the Pico's 2 MiB. A CPU store into the
//    flash window fails the run at any time. The array survives power cycles (board.js keeps
//    it), a power cut can be armed at a chosen byte of an erase or a program
//    (`cutPowerDuring`), and bits can be worn out (`wearOut`: a program cannot clear them).
// 14. The flash chip's unique ID. rp2040js's SSI is a stub (its status register always says
//    data waits, its data register reads back a constant) and IO_QSPI is not modelled, so a
//    command the firmware clocks through the SSI itself (the W25Q080's Read Unique ID, 0x4B,
//    which the boot ROM has no routine for) gets nothing. The model: while the firmware
//    forces the QSPI chip select low (GPIO_QSPI_SS_CTRL's OUTOVER = low) with XIP off (after
//    flash_exit_xip), each byte written to the SSI's data register is a byte on the wire and
//    one byte comes back into a receive FIFO the status register reports (RFNE), as on the
//    chip in its SPI mode; after 0x4B and four dummy bytes the chip returns its 64-bit
//    unique ID, most significant byte first (`FlashChip.uniqueId`, per board, settable by the
//    harness, a fixed value by default). Forcing the chip select high ends the command. Any
//    other command, or the chip select forced low with XIP on, fails the run (not modelled).
//    SPI clock time is not modelled (13 bytes at the ROM's SSI rate take microseconds).

/** The Pico's flash: 2 MiB (rp2040js maps 16 MiB). */
export const PICO_FLASH_BYTES = 2 * 1024 * 1024;
export const FLASH_SECTOR_BYTES = 4096;
export const FLASH_PAGE_BYTES = 256;
const FLASH_WINDOW_START = 0x10000000;
const FLASH_WINDOW_END = 0x14000000;
const SRAM_START = 0x20000000;
const SRAM_END = 0x20042000;
const ROM_BYTES = 0x4000;
/** Where the boot ROM keeps the 16-bit pointer to its function table. */
const ROM_FUNCTION_TABLE_POINTER = 0x14;
const THUMB_BX_LR = 0x4770;
/** rp2040js's peripheral keys (address >>> 14 << 2): XIP_SSI and IO_QSPI. */
const SSI_KEY = 0x18000;
const IO_QSPI_KEY = 0x40018;
/** SSI registers (RP2040 datasheet, 4.10.13) and status bits. */
const SSI_SR = 0x28;
const SSI_DR0 = 0x60;
const SSI_SR_TFNF = 1 << 1;
const SSI_SR_TFE = 1 << 2;
const SSI_SR_RFNE = 1 << 3;
/** IO_QSPI GPIO_QSPI_SS_CTRL and its OUTOVER field (RP2040 datasheet, 2.19.6.2). */
const QSPI_SS_CTRL = 0x0c;
const OUTOVER_SHIFT = 8;
const OUTOVER_LOW = 2;
/** W25Q080 Read Unique ID Number: the command, then four dummy bytes, then the 8-byte ID. */
const CMD_READ_UNIQUE_ID = 0x4b;
const UNIQUE_ID_HEADER_BYTES = 5;
const UNIQUE_ID_BYTES = 8;
/** The unique ID of a board the harness gives none (an arbitrary fixed value). */
export const DEFAULT_FLASH_UNIQUE_ID = 0xe660c0d1c7ab2f28n;
const THUMB_BKPT = 0xbe00;
/**
 * The Pico's flash chip's erase and program times: Winbond W25Q80DV datasheet, AC electrical
 * characteristics, sector erase (4 KiB) tSE and page program tPP, typical and maximum.
 */
export const W25Q080_TIMING = {
  typical: { sectorEraseMs: 45, pageProgramMs: 0.7 },
  max: { sectorEraseMs: 400, pageProgramMs: 3 },
};
/** The routines modelled: ROM table code, name, breakpoint number. */
const FLASH_ROUTINES = [
  ['IF', 'connect_internal_flash'],
  ['EX', 'flash_exit_xip'],
  ['RE', 'flash_range_erase'],
  ['RP', 'flash_range_program'],
  ['FC', 'flash_flush_cache'],
  ['CX', 'flash_enter_cmd_xip'],
].map(([code, name], i) => ({ code, name, bkpt: 0xf0 + i }));

const hex = (value) => `0x${(value >>> 0).toString(16)}`;
const inFlashWindow = (address) =>
  address >>> 0 >= FLASH_WINDOW_START && address >>> 0 < FLASH_WINDOW_END;

/**
 * The flash chip: its contents (which survive power cycles), its timing, the erases and
 * programs done (`ops`), an armed power cut, worn bits.
 */
export class FlashChip {
  /**
   * @param {Uint8Array} image the flash array (rp2040js's, of the first chip powered on)
   * @param {object} [options]
   * @param {'typical'|'max'|{sectorEraseMs: number, pageProgramMs: number}} [options.timing]
   * @param {bigint} [options.uniqueId] the chip's 64-bit unique ID (gap 14)
   */
  constructor(image, { timing = 'typical', uniqueId = DEFAULT_FLASH_UNIQUE_ID } = {}) {
    this.image = image;
    this.timing = timing;
    this.uniqueId = BigInt.asUintN(64, uniqueId);
    /** Every erase and program: `{ routine: 'erase'|'program', offset, bytes, nanos }`. */
    this.ops = [];
    this.cut = null;
    /** Offset -> bits a program cannot clear. */
    this.worn = new Map();
  }

  /** The erase and program times in use, ms. */
  get times() {
    return typeof this.timing === 'string' ? W25Q080_TIMING[this.timing] : this.timing;
  }

  /**
   * Arms a power cut: during the `call`-th `routine` ('erase' or 'program') from now, after
   * `bytes` bytes of its work (in address order; 0 = before any), with the bits in `mask` of
   * the next byte's change done (0 = none). The chip then stops at once (board.js powers it
   * off); nothing more is written.
   */
  cutPowerDuring({ routine, call = 1, bytes, mask = 0 }) {
    if (routine !== 'erase' && routine !== 'program') {
      throw new Error(`cutPowerDuring: routine must be 'erase' or 'program', not ${routine}`);
    }
    this.cut = { routine, call, bytes, mask, calls: 0 };
  }

  /** Bits of the byte at `offset` that no program can clear any more (a worn-out cell). */
  wearOut(offset, mask) {
    this.worn.set(offset, (this.worn.get(offset) ?? 0) | mask);
  }

  /** The byte the chip sends back as the `index`-th byte (from 0) of command `command`. */
  respond(command, index) {
    if (index < UNIQUE_ID_HEADER_BYTES || command !== CMD_READ_UNIQUE_ID) {
      return 0xff; // the chip's output is undriven while the command goes in
    }
    const byte = UNIQUE_ID_HEADER_BYTES + UNIQUE_ID_BYTES - 1 - index;
    return byte < 0 ? 0xff : Number((this.uniqueId >> BigInt(8 * byte)) & 0xffn);
  }

  /** A copy of `length` bytes from `offset`. */
  read(offset, length) {
    return Uint8Array.from(this.image.subarray(offset, offset + length));
  }

  /** The armed cut if it falls in this call of `routine` (counting the call). */
  cutIn(routine) {
    if (!this.cut || this.cut.routine !== routine) {
      return null;
    }
    this.cut.calls++;
    if (this.cut.calls !== this.cut.call) {
      return null;
    }
    const cut = this.cut;
    this.cut = null;
    return cut;
  }
}

/** A view of the flash array whose stores fail the run (rp2040js writes flash through it). */
/** @extends {DataView<ArrayBufferLike>} */
class StoreGuardedView extends DataView {
  constructor(buffer, onStore) {
    super(buffer);
    this.onStore = onStore;
  }

  setUint32(offset, value) {
    this.onStore(offset, value);
  }
}

/**
 * Gap 7: connects a fresh `RP2040` (after `loadBootrom`) to `chip`: the chip's array becomes
 * its flash, the six ROM routines trap into the model, stores into the flash window fail.
 * `onFault(message)` fails the run; `onPowerCut()` powers the chip off after this instruction;
 * `onFlushCache()` is flash_flush_cache's work on the XIP cache (gap 13).
 * Call after the board has set `mcu.onBreak` (breakpoints the model does not own go there).
 */
export function attachFlashChip(mcu, chip, { onFault, onPowerCut, onFlushCache = () => {} }) {
  const { core } = mcu;
  const buffer = chip.image.buffer;
  mcu.flash = chip.image;
  mcu.flash16 = new Uint16Array(buffer);
  mcu.flashView = new StoreGuardedView(buffer, (offset, value) => {
    const at = hex(FLASH_WINDOW_START + offset);
    onFault(
      `CPU store of ${hex(value)} into the flash window at ${at} (PC ${hex(core.PC)}): ` +
        'a real chip never writes flash that way',
    );
  });

  // The ROM function table: (code, 16-bit pointer) pairs, ending with code 0.
  const rom = new DataView(mcu.bootrom.buffer);
  const routines = new Map();
  for (let entry = rom.getUint16(ROM_FUNCTION_TABLE_POINTER, true); ; entry += 4) {
    const code = rom.getUint16(entry, true);
    if (code === 0) {
      break;
    }
    const name = String.fromCharCode(code & 0xff, code >> 8);
    const routine = FLASH_ROUTINES.find((r) => r.code === name);
    if (routine) {
      const address = rom.getUint16(entry + 2, true) & ~1;
      rom.setUint16(address, THUMB_BKPT | routine.bkpt, true);
      rom.setUint16(address + 2, THUMB_BX_LR, true);
      routines.set(routine.bkpt, routine);
    }
  }
  if (routines.size !== FLASH_ROUTINES.length) {
    const found = `${routines.size} of the ${FLASH_ROUTINES.length}`;
    throw new Error(`boot ROM function table: found ${found} flash routines`);
  }

  let connected = false;
  let xipOff = false;
  let saved = null;
  const guardReads = () => {
    saved = { readUint32: mcu.readUint32, readUint16: mcu.readUint16, readUint8: mcu.readUint8 };
    for (const [method, read] of Object.entries(saved)) {
      mcu[method] = (address) => {
        if (inFlashWindow(address)) {
          onFault(
            `flash read at ${hex(address)} while XIP is off (PC ${hex(core.PC)}): ` +
              'the chip is in command mode',
          );
        }
        return read.call(mcu, address);
      };
    }
  };
  const unguardReads = () => {
    // Back to what was there (rp2040js's own methods, or the cache model's, gap 13).
    for (const [method, read] of Object.entries(saved)) {
      if (Object.getPrototypeOf(mcu)[method] === read) {
        delete mcu[method];
      } else {
        mcu[method] = read;
      }
    }
    saved = null;
  };
  const busy = (ms) => {
    const nanos = ms * 1e6;
    core.cycles += Math.round((nanos * mcu.clkSys) / 1e9);
    mcu.clock.tick(nanos);
  };

  const erase = (offset, count) => {
    if (offset % FLASH_SECTOR_BYTES !== 0 || count % FLASH_SECTOR_BYTES !== 0 || count === 0) {
      return onFault(`flash_range_erase(${hex(offset)}, ${count}): not whole 4096-byte sectors`);
    }
    if (offset + count > PICO_FLASH_BYTES) {
      return onFault(`flash_range_erase(${hex(offset)}, ${count}): beyond the Pico's 2 MiB flash`);
    }
    chip.ops.push({ routine: 'erase', offset, bytes: count, nanos: mcu.clock.nanos });
    const cut = chip.cutIn('erase');
    for (let i = 0; i < count; i++) {
      if (cut && i === cut.bytes) {
        const old = chip.image[offset + i];
        chip.image[offset + i] = old | (~old & cut.mask & 0xff);
        return onPowerCut();
      }
      chip.image[offset + i] = 0xff;
    }
    busy((count / FLASH_SECTOR_BYTES) * chip.times.sectorEraseMs);
    if (cut) {
      onPowerCut(); // after the whole erase
    }
  };

  const program = (offset, data, count) => {
    if (offset % FLASH_PAGE_BYTES !== 0 || count % FLASH_PAGE_BYTES !== 0 || count === 0) {
      return onFault(`flash_range_program(${hex(offset)}, ${count}): not whole 256-byte pages`);
    }
    if (offset + count > PICO_FLASH_BYTES) {
      return onFault(`flash_range_program(${hex(offset)}, ${count}): beyond the 2 MiB flash`);
    }
    if (data < SRAM_START || data + count > SRAM_END) {
      return onFault(
        `flash_range_program: data at ${hex(data)} is not in SRAM ` +
          '(flash cannot be read while XIP is off)',
      );
    }
    chip.ops.push({ routine: 'program', offset, bytes: count, nanos: mcu.clock.nanos });
    const cut = chip.cutIn('program');
    for (let i = 0; i < count; i++) {
      const at = offset + i;
      const value = mcu.sram[data - SRAM_START + i] | (chip.worn.get(at) ?? 0);
      if (cut && i === cut.bytes) {
        chip.image[at] &= value | (~cut.mask & 0xff);
        return onPowerCut();
      }
      chip.image[at] &= value;
    }
    busy((count / FLASH_PAGE_BYTES) * chip.times.pageProgramMs);
    if (cut) {
      onPowerCut(); // after the whole program
    }
  };

  // Gap 14: commands clocked through the SSI with the chip select forced low.
  const ssi = mcu.peripherals[SSI_KEY];
  const ioQspi = mcu.peripherals[IO_QSPI_KEY];
  let ssCtrl = 0;
  /** The command on the wire: its bytes so far, and the bytes received not read yet. */
  let wire = null;
  const ioQspiWrite = ioQspi.writeUint32.bind(ioQspi);
  const ioQspiRead = ioQspi.readUint32.bind(ioQspi);
  ioQspi.writeUint32 = (offset, value) => {
    if (offset !== QSPI_SS_CTRL) {
      return ioQspiWrite(offset, value);
    }
    ssCtrl = value >>> 0;
    const selected = ((ssCtrl >>> OUTOVER_SHIFT) & 3) === OUTOVER_LOW;
    if (selected && !xipOff) {
      return onFault('QSPI chip select forced low with XIP on (flash_exit_xip first)');
    }
    wire = selected ? { bytes: [], rx: [] } : null;
  };
  ioQspi.readUint32 = (offset) => (offset === QSPI_SS_CTRL ? ssCtrl : ioQspiRead(offset));
  const ssiWrite = ssi.writeUint32.bind(ssi);
  const ssiRead = ssi.readUint32.bind(ssi);
  ssi.writeUint32 = (offset, value) => {
    if (!wire || offset !== SSI_DR0) {
      return ssiWrite(offset, value);
    }
    const byte = value & 0xff;
    if (wire.bytes.length === 0 && byte !== CMD_READ_UNIQUE_ID) {
      return onFault(`flash command ${hex(byte)} through the SSI: not modelled (gap 14)`);
    }
    wire.rx.push(chip.respond(wire.bytes[0] ?? byte, wire.bytes.length));
    wire.bytes.push(byte);
  };
  ssi.readUint32 = (offset) => {
    if (!wire) {
      return ssiRead(offset);
    }
    if (offset === SSI_SR) {
      return SSI_SR_TFNF | SSI_SR_TFE | (wire.rx.length > 0 ? SSI_SR_RFNE : 0);
    }
    if (offset === SSI_DR0) {
      return wire.rx.shift() ?? 0;
    }
    return ssiRead(offset);
  };

  const otherBreak = mcu.onBreak;
  mcu.onBreak = (code) => {
    const routine = routines.get(code);
    if (!routine || core.PC >>> 0 >= ROM_BYTES) {
      return otherBreak(code); // not one of the patched entries
    }
    const lr = core.LR >>> 0;
    if (lr < SRAM_START || lr >= SRAM_END) {
      return onFault(
        `${routine.name} called from ${hex(lr)}, not from SRAM: ` +
          "the caller's code would be fetched from flash while XIP is off",
      );
    }
    if (!core.PM) {
      return onFault(
        `${routine.name} called with interrupts enabled (PRIMASK clear): ` +
          'a handler in flash could run while XIP is off',
      );
    }
    const [r0, r1, r2] = core.registers;
    switch (routine.code) {
      case 'IF':
        connected = true;
        break;
      case 'EX':
        if (!connected) {
          return onFault('flash_exit_xip before connect_internal_flash');
        }
        if (!xipOff) {
          xipOff = true;
          guardReads();
        }
        break;
      case 'RE':
      case 'RP':
        if (!xipOff) {
          return onFault(`${routine.name} while XIP is on (flash_exit_xip first)`);
        }
        if (routine.code === 'RE') {
          return erase(r0 >>> 0, r1 >>> 0);
        }
        return program(r0 >>> 0, r1 >>> 0, r2 >>> 0);
      case 'FC':
        onFlushCache(); // the XIP cache (gap 13)
        break;
      case 'CX':
        connected = false;
        if (xipOff) {
          xipOff = false;
          unguardReads();
        }
        break;
    }
  };
}
