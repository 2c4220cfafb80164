// The flash cache (XIP), gap 13 of rp2040js 1.4.1 (numbered as in index.js).
//
// The chip: code and read-only data are read from the QSPI flash through the XIP block's cache.
// A hit takes one cycle (no more than SRAM, which is what rp2040js charges every flash access);
// a miss stalls the bus master for a serial transfer from the flash. rp2040js has no cache and
// charges nothing for the flash, so every figure measured without this model is a warm-cache,
// best-case figure.
//
// 13. `XipCache` is the cache, in front of every flash-window access the core makes (instruction
//    fetches and data loads), and `XipCtrl` its registers at XIP_CTRL_BASE 0x14000000:
//
//    - Geometry (RP2040 datasheet, 2.6.3.1 and 2.6.3.2): 16 kB, two-way set-associative,
//      8-byte lines, so 1,024 sets ("16 kB total size / 8 bytes per line / 2 ways per set", the
//      flush's length in 2.6.3.2); a 1-cycle hit. The set is flash offset bits 12:3, the tag
//      the bits above.
//    - Replacement: the datasheet pages read for this model do not state a policy; a two-way
//      set's least-recently-used way is replaced (one bit per set), an invalid way first. An
//      assumption; the counters below let a real Pico settle it.
//    - Fill: the transfer the SSI makes is the one boot2 programmed: `CTRLR0.DFS_32` 31 and
//      `CTRLR1.NDF` 0 ("single 32b read", boot2_w25q080.S), so a miss fills one 32-bit half of
//      its 8-byte line (each half has its own valid bit), as measured on chips (raspberrypi/
//      pico-feedback#307: "lines are 8 but filled one half at a time"; Klipper#6464: "a 32bit
//      flash read takes a minimum of 320ns (20 flash cycles, 2 cpu cycles per each flash
//      cycle)"). A fill of a whole line (two frames) would be read from the same registers.
//    - Miss cost, from the SSI registers as the firmware left them (rp2040js's SSI keeps what
//      is written; rp2040-boot2 0.3's `BOOT_LOADER_W25Q080`, assembled with
//      `PICO_FLASH_SPI_CLKDIV=2`, writes them): SCK = clk_sys / `BAUDR` (2); no instruction
//      (`SPI_CTRLR0.INST_L` 0: the W25Q080 stays in continuous-read mode, mode bits 0xA0 in
//      `XIP_CMD`, after the first 0xEB); `ADDR_L` 8 nibbles (24 address bits and the 8 mode
//      bits) in quad (`TRANS_TYPE` 2C2A): 8 clocks; `WAIT_CYCLES` 4 dummy clocks; the data
//      (32 bits) in quad (`CTRLR0.SPI_FRF` 2): 8 clocks. 20 SCK clocks = 40 clk_sys cycles,
//      plus `RX_SAMPLE_DLY` (1 cycle), plus `MISS_OVERHEAD_CYCLES` (5, assumed: the XIP block
//      sees the miss and hands the SSI its request, the SSI asserts chip select a clock before
//      the first SCK edge, the data goes back through the cache to the bus): 46 cycles.
//    - Core fetches: the Cortex-M0+ fetches instructions a 32-bit word at a time, so one
//      access per word of sequential code and one after every jump; rp2040js reads a halfword
//      per instruction, and the model counts a fetch only for a new word or a jump (the M0+'s
//      fetch of the word after a taken branch, which it throws away, is not modelled). A data
//      load is one access (LDM: one per word).
//    - Aliases (2.6.3.1): 0x10.. looks up and allocates; 0x11.. looks up, no allocation;
//      0x12.. does not look up, allocates; 0x13.. neither. `CTRL.EN` 0: nothing looked up.
//    - Registers: `CTRL` (EN, ERR_BADWRITE, POWER_DOWN: kept, EN obeyed), `FLUSH` (a write of
//      1 empties the cache, taking 1,024 cycles of stall, 2.6.3.2), `STAT` (FLUSH_READY and an
//      empty stream FIFO), `CTR_HIT` (0x0c) and `CTR_ACC` (0x10): 32-bit saturating counters of
//      hits and of accesses (noncacheable ones too), a write clears. No streaming FIFO.
//    - The ROM's `flash_flush_cache` (gap 7 traps it) empties the cache as the FLUSH write it
//      makes does, and costs the same 1,024 cycles.
//    - Boot2: on the chip the boot ROM copies it into SRAM and runs it there; here it runs at
//      0x10000000 (gap 6), so the model starts at the first fetch past boot2's 256 bytes.
//
//    On by default: every board, test, benchmark and `./dev run` has it. Board option
//    `xipCache: false` (or HEXAPOD_XIP_CACHE=off in the environment, which child processes
//    such as `./dev run --pty` inherit; `./dev run --no-xip-cache`; or
//    `setXipCacheByDefault(false)`) takes it out: flash then costs nothing, as in rp2040js
//    alone (the registers still answer, the counters stay 0). `./dev bench` measures the
//    headline figures both ways (the "no cache model" column); `./dev test` guards them with
//    it (test/bench-guard.test.js).
//    Stall cycles go to the core's cycle count at once and to emulated time after the
//    instruction (or interrupt entry) that stalled, as rp2040js charges an instruction's own
//    cycles: whoever runs the core adds `takeUnclockedCycles()` to its clock tick.

const FLASH_WINDOW_SHIFT = 26; // 0x10000000..0x13ffffff >>> 26 === 4
const FLASH_WINDOW_TOP = 4;
const BOOT2_END = 0x10000100;
/** Sets: 16 kB / 8-byte lines / 2 ways (RP2040 datasheet 2.6.3.2). */
export const XIP_CACHE_SETS = 1024;
export const XIP_CACHE_LINE_BYTES = 8;
/** Cycles a flush stalls the bus ("just over 1024 clock cycles", 2.6.3.2). */
export const XIP_FLUSH_CYCLES = 1024;
/** A miss's cycles beyond the serial transfer and RX_SAMPLE_DLY (assumed; see above). */
export const MISS_OVERHEAD_CYCLES = 5;
/** XIP_CTRL_BASE's page as rp2040js indexes its peripherals (address >>> 14 << 2). */
const XIP_CTRL_PAGE = 0x14000;
const CTRL = 0x00;
const FLUSH = 0x04;
const STAT = 0x08;
const CTR_HIT = 0x0c;
const CTR_ACC = 0x10;
const CTRL_EN = 1;
const CTRL_POWER_DOWN = 8;
const STAT_FLUSH_READY = 1;
const STAT_FIFO_EMPTY = 2;
/** rp2040js's SSI (XIP_SSI_BASE 0x18000000) keeps what the firmware wrote to these. */
const SSI_PAGE = 0x18000;

let modelByDefault = process.env.HEXAPOD_XIP_CACHE !== 'off';

/** Whether boards made from now on get the cache model unless told (the bench's switch). */
export function setXipCacheByDefault(on) {
  modelByDefault = on;
}

export function xipCacheByDefault() {
  return modelByDefault;
}

/**
 * The miss cost in clk_sys cycles for the SSI's current set-up, with what it is made of:
 * `{ cycles, sckDivider, clocks: { instruction, address, wait, data }, fillBytes }`, or null
 * while the SSI is not set up for XIP (disabled or no clock divider).
 */
export function missCost(ssi) {
  const baud = ssi.baudr & 0xffff;
  if (!(ssi.ssienr & 1) || baud === 0) {
    return null;
  }
  const lanes = [1, 2, 4, 4][(ssi.crtlr0 >>> 21) & 3];
  const transType = ssi.spictlr0 & 3;
  const instBits = [0, 4, 8, 16][(ssi.spictlr0 >>> 8) & 3];
  const addrBits = ((ssi.spictlr0 >>> 2) & 0xf) * 4;
  const wait = (ssi.spictlr0 >>> 11) & 0x1f;
  const frameBits = ((ssi.crtlr0 >>> 16) & 0x1f) + 1;
  const frames = (ssi.crtlr1 & 0xffff) + 1;
  const clocks = {
    instruction: instBits / (transType === 2 ? lanes : 1),
    address: addrBits / (transType === 0 ? 1 : lanes),
    wait,
    data: (frameBits * frames) / lanes,
  };
  const sck = clocks.instruction + clocks.address + clocks.wait + clocks.data;
  const sampleDelay = ssi.rxsampldly & 0xff;
  return {
    cycles: Math.ceil(sck * baud) + sampleDelay + MISS_OVERHEAD_CYCLES,
    sckDivider: baud,
    sampleDelay,
    clocks,
    fillBytes: Math.min(XIP_CACHE_LINE_BYTES, Math.max(4, (frameBits * frames) / 8)),
  };
}

/** Gap 13: the XIP cache (see the header). */
export class XipCache {
  /**
   * @param {import('./index.js').Mcu} mcu
   * @param {{ ssi?: object }} [options] `ssi`: the SSI registers to time misses by (default:
   *   rp2040js's SSI of `mcu`)
   */
  constructor(mcu, { ssi } = {}) {
    this.mcu = mcu;
    this.ssi = ssi ?? /** @type {any} */ (mcu.peripherals)[SSI_PAGE];
    /** Per set and way (index set * 2 + way): the tag, -1 when empty. */
    this.tags = new Int32Array(XIP_CACHE_SETS * 2).fill(-1);
    /** Per set and way: valid bits of the line's two 32-bit halves. */
    this.valid = new Uint8Array(XIP_CACHE_SETS * 2);
    /** Per set: the way used last (the other is replaced). */
    this.lastWay = new Uint8Array(XIP_CACHE_SETS);
    this.enabled = true;
    this.started = false;
    /** CTR_HIT, CTR_ACC (saturating when read). */
    this.hitCounter = 0;
    this.accessCounter = 0;
    /** Totals since power-on, never cleared: accesses, hits, misses, stall cycles. */
    this.stats = { accesses: 0, hits: 0, misses: 0, stallCycles: 0, flushes: 0 };
    this.cost = null;
    /** Stall cycles charged to the core but not yet to emulated time (`takeUnclockedCycles`). */
    this.unclockedCycles = 0;
    /** Charges stall cycles to the core, and to emulated time later (set by `attachXipCache`). */
    this.stall = (/** @type {number} */ cycles) => {};
  }

  /**
   * One bus access to flash-window `address` (a fetch of its word, or a load). Returns the
   * stall cycles it costs (0 on a hit).
   */
  access(address) {
    if (!this.started) {
      return 0;
    }
    this.stats.accesses++;
    this.accessCounter++;
    const alias = (address >>> 24) & 3;
    const offset = address & 0xffffff;
    const line = offset >>> 3;
    const set = line & (XIP_CACHE_SETS - 1);
    const tag = line >>> 10;
    const half = 1 << ((offset >>> 2) & 1);
    const i = set << 1;
    const { tags, valid } = this;
    if (this.enabled && (alias & 2) === 0) {
      if (tags[i] === tag && valid[i] & half) {
        this.lastWay[set] = 0;
        this.stats.hits++;
        this.hitCounter++;
        return 0;
      }
      if (tags[i + 1] === tag && valid[i + 1] & half) {
        this.lastWay[set] = 1;
        this.stats.hits++;
        this.hitCounter++;
        return 0;
      }
    }
    const cost = this.missCost();
    if (this.enabled && (alias & 1) === 0) {
      let way;
      if (tags[i] === tag) {
        way = 0;
      } else if (tags[i + 1] === tag) {
        way = 1;
      } else {
        way = valid[i] === 0 ? 0 : valid[i + 1] === 0 ? 1 : this.lastWay[set] ^ 1;
        tags[i + way] = tag;
        valid[i + way] = 0;
      }
      valid[i + way] |= cost.fillBytes === 8 ? 3 : half;
      this.lastWay[set] = way;
    }
    this.stats.misses++;
    this.stats.stallCycles += cost.cycles;
    return cost.cycles;
  }

  /** The miss cost now (from the SSI's registers; the last good one if it is switched off). */
  missCost() {
    const cost = missCost(this.ssi);
    if (cost) {
      this.cost = cost;
    }
    return this.cost ?? { cycles: 0, fillBytes: 4 };
  }

  /**
   * The stall cycles since the last call, which emulated time has not passed yet: whoever runs
   * the core ticks its clock by them after the instruction (`EmulatedBoard.runSlice`).
   */
  takeUnclockedCycles() {
    const cycles = this.unclockedCycles;
    this.unclockedCycles = 0;
    return cycles;
  }

  /** Empties the cache (FLUSH, the ROM's flash_flush_cache); returns the stall cycles. */
  flush() {
    this.tags.fill(-1);
    this.valid.fill(0);
    this.lastWay.fill(0);
    this.stats.flushes++;
    return this.started ? XIP_FLUSH_CYCLES : 0;
  }
}

/** Gap 13: the XIP block's registers (XIP_CTRL_BASE), for a cache model or none. */
class XipCtrl {
  constructor(cache, stall) {
    this.cache = cache;
    this.stall = stall;
    this.ctrl = 0x3; // reset: EN, ERR_BADWRITE
  }

  readUint32(offset) {
    switch (offset & 0xfff) {
      case CTRL:
        return this.ctrl;
      case FLUSH:
      case STAT:
        return offset === STAT ? STAT_FLUSH_READY | STAT_FIFO_EMPTY : 0;
      case CTR_HIT:
        return Math.min(this.cache?.hitCounter ?? 0, 0xffffffff);
      case CTR_ACC:
        return Math.min(this.cache?.accessCounter ?? 0, 0xffffffff);
    }
    return 0;
  }

  writeUint32(offset, value) {
    switch (offset & 0xfff) {
      case CTRL:
        this.ctrl = value & 0xb;
        if (this.ctrl & CTRL_POWER_DOWN) {
          this.ctrl &= ~CTRL_EN;
        }
        if (this.cache) {
          this.cache.enabled = (this.ctrl & CTRL_EN) !== 0;
        }
        break;
      case FLUSH:
        if (value & 1 && this.cache) {
          this.stall(this.cache.flush());
        }
        break;
      case CTR_HIT:
        if (this.cache) this.cache.hitCounter = 0;
        break;
      case CTR_ACC:
        if (this.cache) this.cache.accessCounter = 0;
        break;
    }
  }

  writeUint32Atomic(offset, value) {
    this.writeUint32(offset, value); // an AHB block: no atomic set/clear aliases
  }
}

/**
 * Gap 13: puts the XIP registers on `mcu` and, if `model`, the cache in front of its flash
 * reads. Returns the `XipCache` (or null). Call on a fresh chip, before anything wraps its
 * read methods (gap 7 wraps whatever it finds, and puts it back).
 */
export function attachXipCache(mcu, { model = modelByDefault } = {}) {
  const { core } = mcu;
  const cache = model ? new XipCache(mcu) : null;
  // The core's cycle count at once; emulated time with the instruction that stalled (the
  // board's loop ticks the clock by `takeUnclockedCycles()` after it). Never a clock tick from
  // here: a stall can happen inside one (rp2040js enters an interrupt handler, reading its
  // vector from flash, from the peripheral's alarm that raised it while the core slept), and a
  // tick inside a tick moved that alarm's rescheduling late (a PWM wrap 368 ns late, a pulse
  // 48 ns short of its whole counts) and then set the clock back.
  const stall = (cycles) => {
    if (cycles > 0) {
      core.cycles += cycles;
      cache.unclockedCycles += cycles;
    }
  };
  /** @type {any} */ (mcu.peripherals)[XIP_CTRL_PAGE] = new XipCtrl(cache, stall);
  if (!cache) {
    return null;
  }
  const { registers } = core;
  const read32 = mcu.readUint32;
  const read16 = mcu.readUint16;
  const read8 = mcu.readUint8;
  // The word the core's fetch holds, and where the next sequential fetch would be.
  let fetchWord = -1;
  let nextFetch = -1;
  mcu.readUint16 = function (address) {
    if (address >>> FLASH_WINDOW_SHIFT !== FLASH_WINDOW_TOP) {
      return read16.call(this, address);
    }
    const pc = registers[15] & ~1;
    if (address === pc || address === pc + 2) {
      // An instruction fetch (rp2040js reads the halfwords at PC and PC + 2).
      const word = address & ~3;
      if (word !== fetchWord || address !== nextFetch) {
        if (!cache.started && address >= BOOT2_END) {
          cache.started = true;
        }
        fetchWord = word;
        stall(cache.access(address));
      }
      nextFetch = address + 2;
    } else {
      stall(cache.access(address));
    }
    return mcu.flashView.getUint16(address & 0xffffff, true);
  };
  mcu.readUint32 = function (address) {
    address = address >>> 0;
    if (address >>> FLASH_WINDOW_SHIFT !== FLASH_WINDOW_TOP) {
      return read32.call(this, address);
    }
    stall(cache.access(address));
    return mcu.flashView.getUint32(address & 0xffffff, true);
  };
  mcu.readUint8 = function (address) {
    if (address >>> FLASH_WINDOW_SHIFT !== FLASH_WINDOW_TOP) {
      return read8.call(this, address);
    }
    stall(cache.access(address));
    return mcu.flash[address & 0xffffff];
  };
  cache.stall = stall;
  return cache;
}
