// The XIP cache model of src/gaps/xip-cache.js (gap 13) on its own: a bare RP2040, no
// firmware, its SSI set up as the firmware's boot2 leaves it, and known access patterns whose
// hits, misses and cycles are counted by hand from the model's stated rules (16 kB, two ways,
// 8-byte lines filled a 32-bit half at a time, least recently used way replaced; 46 cycles a
// miss; the aliases of RP2040 datasheet 2.6.3.1), read back through CTR_HIT and CTR_ACC as
// firmware would read them.

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { RP2040 } from 'rp2040js';

import { attachXipCache, missCost, patchEmulatorGaps } from '../src/gaps/index.js';

const SSI = 0x18000000;
const XIP_CTRL = 0x14000000;
const CTR_HIT = XIP_CTRL + 0x0c;
const CTR_ACC = XIP_CTRL + 0x10;
const NOP = 0xbf00;
const B_SELF = 0xe7fe;
/** Where the core runs when it makes a data load (not a flash fetch). */
const SRAM_CODE = 0x20001000;
/** Three flash addresses 8 KiB apart: the same set (offset bits 12:3), three tags. */
const A = 0x10004000;
const B = 0x10006000;
const C = 0x10008000;

/**
 * The SSI registers as rp2040-boot2's boot2_w25q080.S (PICO_FLASH_SPI_CLKDIV=2) leaves them:
 * quad frames of 32 bits (CTRLR0: SPI_FRF 2, DFS_32 31, TMOD EEPROM read), one frame
 * (CTRLR1.NDF 0), no instruction, 8 nibbles of address and mode bits, 4 wait cycles, address
 * in quad (SPI_CTRLR0: XIP_CMD 0xa0, WAIT_CYCLES 4, INST_L 0, ADDR_L 8, TRANS_TYPE 2C2A),
 * SCK = clk_sys / 2, RX sample delay 1.
 */
function boot2Ssi(mcu, { baud = 2 } = {}) {
  mcu.writeUint32(SSI + 0x08, 0);
  mcu.writeUint32(SSI + 0x14, baud);
  mcu.writeUint32(SSI + 0xf0, 1);
  mcu.writeUint32(SSI + 0x00, (2 << 21) | (31 << 16) | (3 << 8));
  mcu.writeUint32(SSI + 0x04, 0);
  mcu.writeUint32(SSI + 0xf4, (0xa0 << 24) | (4 << 11) | (0 << 8) | (8 << 2) | 2);
  mcu.writeUint32(SSI + 0x08, 1);
}

/** A bare chip with the cache model, started (as after boot2) and its counters cleared. */
function bareChip() {
  const mcu = /** @type {import('../src/gaps/index.js').Mcu} */ (new RP2040());
  patchEmulatorGaps(mcu);
  const cache = attachXipCache(mcu, { model: true });
  boot2Ssi(mcu);
  // One instruction fetched past boot2 starts the model (a set none of the tests use).
  mcu.flash.set([0x00, 0xbf, 0xfe, 0xe7], 0x200);
  mcu.core.PC = 0x10000200;
  mcu.core.executeInstruction();
  mcu.writeUint32(CTR_HIT, 0);
  mcu.writeUint32(CTR_ACC, 0);
  mcu.core.PC = SRAM_CODE;
  return { mcu, cache };
}

/** Loads a word as the core's LDR does (the PC in SRAM); returns the stall cycles. */
function load(mcu, address) {
  const before = mcu.core.cycles;
  mcu.readUint32(address);
  return mcu.core.cycles - before;
}

const counters = (mcu) => ({ hits: mcu.readUint32(CTR_HIT), accesses: mcu.readUint32(CTR_ACC) });

test('a miss costs 46 cycles with boot2 set-up: 2 x (8 address + 4 wait + 8 data clocks) + 1 + 5', () => {
  const { mcu } = bareChip();
  const cost = missCost(/** @type {any} */ (mcu.peripherals)[0x18000]);
  assert.deepEqual(cost.clocks, { instruction: 0, address: 8, wait: 4, data: 8 });
  assert.equal(cost.cycles, 46);
  assert.equal(cost.fillBytes, 4);
  // The Pico SDK's default divider (4): 4 x 20 + 1 + 5.
  boot2Ssi(mcu, { baud: 4 });
  assert.equal(missCost(/** @type {any} */ (mcu.peripherals)[0x18000]).cycles, 86);
  assert.equal(load(mcu, A), 86);
});

test('sequential code: a fetch per 32-bit word, each word a miss the first time and a hit after', () => {
  const { mcu } = bareChip();
  const code = 0x10001000;
  for (let i = 0; i < 32; i++) {
    mcu.flash[code - 0x10000000 + 2 * i] = NOP & 0xff;
    mcu.flash[code - 0x10000000 + 2 * i + 1] = NOP >> 8;
  }
  const run = () => {
    mcu.core.PC = code;
    const before = mcu.core.cycles;
    for (let i = 0; i < 32; i++) {
      mcu.core.executeInstruction();
    }
    return mcu.core.cycles - before;
  };
  // 32 NOPs = 64 bytes = 16 words = 8 lines; every word is a half line not yet filled.
  assert.equal(run(), 32 + 16 * 46);
  assert.deepEqual(counters(mcu), { hits: 0, accesses: 16 });
  assert.equal(run(), 32);
  assert.deepEqual(counters(mcu), { hits: 16, accesses: 32 });
});

test('two addresses in one set share its two ways: after two misses, every access hits', () => {
  const { mcu } = bareChip();
  const stalls = [A, B, A, B, A, B].map((address) => load(mcu, address));
  assert.deepEqual(stalls, [46, 46, 0, 0, 0, 0]);
  assert.deepEqual(counters(mcu), { hits: 4, accesses: 6 });
});

test('three addresses in one set thrash two ways: the least recently used is always the next', () => {
  const { mcu } = bareChip();
  const stalls = [A, B, C, A, B, C, A, B, C].map((address) => load(mcu, address));
  assert.deepEqual(stalls, Array(9).fill(46));
  assert.deepEqual(counters(mcu), { hits: 0, accesses: 9 });
  // A B A C: A was used after B, so C replaces B; then A hits and B misses.
  const { mcu: other } = bareChip();
  assert.deepEqual(
    [A, B, A, C, A, B].map((address) => load(other, address)),
    [46, 46, 0, 46, 0, 46],
  );
});

test("a line's two halves are filled one at a time, in the same way", () => {
  const { mcu } = bareChip();
  assert.deepEqual(
    [A, A + 4, A, A + 4, B, A + 4].map((address) => load(mcu, address)),
    [46, 46, 0, 0, 46, 0],
  );
});

test('the aliases: 0x11 looks up without allocating, 0x12 allocates without looking, 0x13 neither', () => {
  const { mcu } = bareChip();
  const alias = (n, address) => address + n * 0x01000000;
  assert.deepEqual(
    [
      A, // miss, allocated
      alias(3, A), // bypass: a miss although cached
      alias(1, A), // hit
      alias(1, B), // miss, not allocated
      B, // so a miss again
      alias(2, C), // no look-up: a miss, allocated (replacing A, the least recently used)
      C, // hit
      A, // miss
    ].map((address) => load(mcu, address)),
    [46, 46, 0, 46, 46, 46, 0, 46],
  );
  assert.deepEqual(counters(mcu), { hits: 2, accesses: 8 });
});

test('FLUSH empties the cache (1,024 cycles), CTRL.EN 0 bypasses it, a counter write clears', () => {
  const { mcu } = bareChip();
  assert.deepEqual(
    [A, A].map((address) => load(mcu, address)),
    [46, 0],
  );
  let before = mcu.core.cycles;
  mcu.writeUint32(XIP_CTRL + 0x04, 1);
  assert.equal(mcu.core.cycles - before, 1024);
  assert.equal(mcu.readUint32(XIP_CTRL + 0x08) & 1, 1, 'STAT.FLUSH_READY');
  assert.deepEqual(
    [A, A].map((address) => load(mcu, address)),
    [46, 0],
  );
  mcu.writeUint32(XIP_CTRL, 0x2); // EN off
  assert.deepEqual(
    [A, A].map((address) => load(mcu, address)),
    [46, 46],
  );
  assert.deepEqual(counters(mcu), { hits: 2, accesses: 6 });
  mcu.writeUint32(XIP_CTRL, 0x3);
  assert.equal(load(mcu, A), 0, 'what was cached stays while the cache is off');
  mcu.writeUint32(CTR_HIT, 12345);
  assert.deepEqual(counters(mcu), { hits: 0, accesses: 7 });
  before = mcu.core.cycles;
  mcu.readUint32(0x20000000);
  mcu.readUint16(0x20000000);
  mcu.readUint8(0x20000000);
  assert.equal(mcu.core.cycles, before, 'SRAM reads cost nothing and are not counted');
  assert.deepEqual(counters(mcu), { hits: 0, accesses: 7 });
});

test('without the model the registers answer and nothing is charged', () => {
  const mcu = /** @type {import('../src/gaps/index.js').Mcu} */ (new RP2040());
  patchEmulatorGaps(mcu);
  assert.equal(attachXipCache(mcu, { model: false }), null);
  boot2Ssi(mcu);
  const before = mcu.core.cycles;
  mcu.readUint32(A);
  assert.equal(mcu.core.cycles, before);
  assert.equal(mcu.readUint32(XIP_CTRL), 0x3, 'CTRL at reset: EN, ERR_BADWRITE');
  assert.deepEqual(counters(mcu), { hits: 0, accesses: 0 });
});
