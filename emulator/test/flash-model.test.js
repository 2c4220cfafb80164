// The flash model of src/gaps/flash.js (gap 7) on its own: a bare RP2040 with the boot ROM
// and no firmware, its patched ROM flash routines called as firmware calls them (registers,
// a return address in SRAM), and every rule it enforces broken once on purpose. Expected
// contents follow NOR flash semantics (an erase sets bytes to 0xFF, a program can only clear
// bits); expected durations are the W25Q80DV datasheet's figures the model states. The unique
// ID (gap 14) is read as the W25Q080 datasheet's Read Unique ID describes it.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { RP2040 } from 'rp2040js';

import { loadBootrom } from '../src/chip/bootrom.js';
import { attachFlashChip, FlashChip, patchEmulatorGaps } from '../src/gaps/index.js';

const SRAM = 0x20000000;
const FLASH = 0x10000000;
const RETURN_ADDRESS = 0x20010000; // `b .`, where the routines return to
const CODE = 0x20010100; // a few instructions of our own
const PAGE_DATA = 0x20020000;
const B_SELF = 0xe7fe;
const LDR_R0_R1 = 0x6808; // ldr r0, [r1]
const STR_R0_R1 = 0x6008; // str r0, [r1]
const SECTOR = 0x1fe000; // a sector near the end of the 2 MiB
// Gap 13: the SSI's status and data registers, the QSPI chip select's control and its
// OUTOVER field's values (RP2040 datasheet, 4.10.13 and 2.19.6.2).
const SSI_SR = 0x18000028;
const SSI_DR0 = 0x18000060;
const SSI_SR_RFNE = 1 << 3;
const QSPI_SS_CTRL = 0x4001800c;
const CS_LOW = 2 << 8;
const CS_HIGH = 3 << 8;

let bootromWords;
before(() => {
  bootromWords = loadBootrom();
});

/** A bare chip with the flash model: `{ mcu, chip, faults, cuts, call(code, args) }`. */
/**
 * @param {{
 *   timing?: 'typical' | 'max' | { sectorEraseMs: number, pageProgramMs: number },
 *   uniqueId?: bigint,
 * }} [options]
 */
function bareChip({ timing = 'typical', uniqueId = undefined } = {}) {
  const mcu = new RP2040();
  patchEmulatorGaps(mcu);
  mcu.loadBootrom(bootromWords);
  const chip = new FlashChip(mcu.flash, { timing, uniqueId });
  const faults = [];
  let cuts = 0;
  mcu.onBreak = (code) => faults.push(`breakpoint ${code}`);
  attachFlashChip(mcu, chip, {
    onFault: (message) => faults.push(message),
    onPowerCut: () => {
      cuts++;
    },
  });
  mcu.sramView.setUint16(RETURN_ADDRESS - SRAM, B_SELF, true);
  // The ROM function table, as firmware reads it: 16-bit pointer at 0x14, (code, address).
  const rom = new DataView(Uint32Array.from(bootromWords).buffer);
  const address = (code) => {
    for (let entry = rom.getUint16(0x14, true); ; entry += 4) {
      const c = rom.getUint16(entry, true);
      assert.notEqual(c, 0, `no ${code} in the ROM table`);
      if (c === code.charCodeAt(0) + (code.charCodeAt(1) << 8)) {
        return rom.getUint16(entry + 2, true);
      }
    }
  };
  /** Calls ROM routine `code` with `args` in r0.., returning to SRAM; `primask` set or not. */
  const call = (code, args = [], { primask = true, lr = RETURN_ADDRESS | 1 } = {}) => {
    const { core } = mcu;
    args.forEach((value, i) => {
      core.registers[i] = value;
    });
    core.PM = primask;
    core.LR = lr;
    core.PC = address(code) & ~1;
    for (let i = 0; i < 10 && core.PC !== (lr & ~1); i++) {
      mcu.step();
    }
  };
  return {
    mcu,
    chip,
    faults,
    get cuts() {
      return cuts;
    },
    call,
  };
}

/** connect, exit XIP, `op`, flush, enter XIP: the sequence firmware runs. */
function sequence(c, op) {
  c.call('IF');
  c.call('EX');
  op();
  c.call('FC');
  c.call('CX');
}

function page(fill) {
  return Uint8Array.from({ length: 256 }, (_, i) => fill(i));
}

function putPage(mcu, bytes) {
  mcu.sram.set(bytes, PAGE_DATA - SRAM);
}

test('erase: 0xFF over 4 KiB sectors; program: AND over pages; each in the datasheet time', () => {
  const c = bareChip();
  c.chip.image.fill(0x5a, SECTOR - 16, SECTOR + 8192 + 16);
  let before = c.mcu.clock.nanos;
  sequence(c, () => c.call('RE', [SECTOR, 4096, 1 << 16, 0xd8]));
  assert.deepEqual(c.faults, []);
  assert.ok(
    c.chip.read(SECTOR, 4096).every((b) => b === 0xff),
    'the sector is erased',
  );
  assert.equal(c.chip.image[SECTOR - 1], 0x5a, 'the byte before it is not');
  assert.equal(c.chip.image[SECTOR + 4096], 0x5a, 'the next sector is not');
  // W25Q80DV tSE typical: 45 ms (and the core was busy in the ROM all that time).
  assert.ok(Math.abs(c.mcu.clock.nanos - before - 45e6) < 1e4, `${c.mcu.clock.nanos - before} ns`);
  assert.ok(c.mcu.core.cycles >= 45e-3 * 125e6);

  putPage(
    c.mcu,
    page((i) => i),
  );
  before = c.mcu.clock.nanos;
  sequence(c, () => c.call('RP', [SECTOR, PAGE_DATA, 256]));
  assert.deepEqual(c.faults, []);
  assert.deepEqual(
    c.chip.read(SECTOR, 256),
    page((i) => i),
  );
  assert.ok(Math.abs(c.mcu.clock.nanos - before - 0.7e6) < 1e4, 'tPP typical 0.7 ms');
  // Programming again can only clear bits: 0x0F over i gives i & 0x0F.
  putPage(
    c.mcu,
    page(() => 0x0f),
  );
  sequence(c, () => c.call('RP', [SECTOR, PAGE_DATA, 256]));
  assert.deepEqual(
    c.chip.read(SECTOR, 256),
    page((i) => i & 0x0f),
  );
  assert.deepEqual(
    c.chip.ops.map(({ routine, offset, bytes }) => [routine, offset, bytes]),
    [
      ['erase', SECTOR, 4096],
      ['program', SECTOR, 256],
      ['program', SECTOR, 256],
    ],
  );
});

test('the maximum timing is the datasheet maximum: 400 ms a sector, 3 ms a page', () => {
  const c = bareChip({ timing: 'max' });
  const before = c.mcu.clock.nanos;
  sequence(c, () => {
    c.call('RE', [SECTOR, 8192, 1 << 16, 0xd8]);
    c.call('RP', [SECTOR, PAGE_DATA, 512]);
  });
  assert.deepEqual(c.faults, []);
  assert.ok(Math.abs(c.mcu.clock.nanos - before - (2 * 400e6 + 2 * 3e6)) < 1e4);
});

/** Clocks `bytes` through the SSI with the chip select forced low; returns the bytes back. */
function spiCommand(mcu, bytes) {
  mcu.writeUint32(QSPI_SS_CTRL, CS_LOW);
  const back = [];
  for (const byte of bytes) {
    mcu.writeUint32(SSI_DR0, byte);
    assert.ok(mcu.readUint32(SSI_SR) & SSI_SR_RFNE, 'a byte came back');
    back.push(mcu.readUint32(SSI_DR0) & 0xff);
  }
  assert.equal(mcu.readUint32(SSI_SR) & SSI_SR_RFNE, 0, 'nothing more came back');
  mcu.writeUint32(QSPI_SS_CTRL, CS_HIGH);
  return back;
}

test("Read Unique ID (0x4B, four dummy bytes) returns the chip's ID, most significant first", () => {
  const c = bareChip({ uniqueId: 0x0123456789abcdefn });
  let back = [];
  sequence(c, () => {
    back = spiCommand(c.mcu, [0x4b, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
  });
  assert.deepEqual(c.faults, []);
  assert.deepEqual(back.slice(5), [0x01, 0x23, 0x45, 0x67, 0x89, 0xab, 0xcd, 0xef]);
});

test('the SSI model fails the run on the chip select forced low with XIP on', () => {
  const c = bareChip();
  c.mcu.writeUint32(QSPI_SS_CTRL, CS_LOW);
  assert.match(c.faults.join('\n'), /chip select forced low with XIP on/);
});

test('the SSI model fails the run on a command it does not model', () => {
  const c = bareChip();
  sequence(c, () => {
    c.mcu.writeUint32(QSPI_SS_CTRL, CS_LOW);
    c.mcu.writeUint32(SSI_DR0, 0x9f); // JEDEC ID: not modelled
    c.mcu.writeUint32(QSPI_SS_CTRL, CS_HIGH);
  });
  assert.match(c.faults.join('\n'), /flash command 0x9f through the SSI: not modelled/);
});

const BROKEN_RULES = {
  'interrupts enabled': (c) => c.call('IF', [], { primask: false }),
  'a caller in flash': (c) => c.call('IF', [], { lr: (FLASH + 0x1000) | 1 }),
  'exit XIP before connecting': (c) => c.call('EX'),
  'an erase with XIP on': (c) => {
    c.call('IF');
    c.call('RE', [SECTOR, 4096, 1 << 16, 0xd8]);
  },
  'an unaligned erase': (c) => sequence(c, () => c.call('RE', [SECTOR + 256, 4096, 1 << 16, 0xd8])),
  'an erase of part of a sector': (c) =>
    sequence(c, () => c.call('RE', [SECTOR, 1024, 1 << 16, 0xd8])),
  'an erase beyond 2 MiB': (c) => sequence(c, () => c.call('RE', [0x200000, 4096, 1 << 16, 0xd8])),
  'an unaligned program': (c) => sequence(c, () => c.call('RP', [SECTOR + 16, PAGE_DATA, 256])),
  'a program of part of a page': (c) => sequence(c, () => c.call('RP', [SECTOR, PAGE_DATA, 100])),
  'program data in flash': (c) => sequence(c, () => c.call('RP', [SECTOR, FLASH + 0x100, 256])),
  'an instruction fetched from flash with XIP off': (c) => {
    c.call('IF');
    c.call('EX');
    c.chip.image.set([0xfe, 0xe7], 0x1000);
    c.mcu.core.PC = FLASH + 0x1000;
    c.mcu.step();
  },
  'data read from flash with XIP off': (c) => {
    c.call('IF');
    c.call('EX');
    c.mcu.sramView.setUint16(CODE - SRAM, LDR_R0_R1, true);
    c.mcu.core.registers[1] = FLASH + 0x100;
    c.mcu.core.PC = CODE;
    c.mcu.step();
  },
  'a CPU store into the flash window': (c) => {
    c.mcu.sramView.setUint16(CODE - SRAM, STR_R0_R1, true);
    c.mcu.core.registers[0] = 0x12345678;
    c.mcu.core.registers[1] = FLASH + SECTOR;
    c.mcu.core.PC = CODE;
    c.mcu.step();
    assert.equal(c.chip.image[SECTOR], 0xff, 'the store changed nothing');
  },
};

for (const [rule, breakIt] of Object.entries(BROKEN_RULES)) {
  test(`the model fails the run on ${rule}`, () => {
    const c = bareChip();
    const erased = c.chip.read(SECTOR, 8192);
    breakIt(c);
    assert.equal(c.faults.length >= 1, true, 'no fault reported');
    assert.deepEqual(c.chip.read(SECTOR, 8192), erased, 'the flash changed');
  });
}

test('after flash_enter_cmd_xip the flash reads again without a fault', () => {
  const c = bareChip();
  sequence(c, () => {});
  c.mcu.sramView.setUint16(CODE - SRAM, LDR_R0_R1, true);
  c.mcu.core.registers[1] = FLASH + 0x100;
  c.mcu.core.PC = CODE;
  c.mcu.step();
  assert.deepEqual(c.faults, []);
});

test('a power cut stops an erase or a program at the chosen byte, half-way through it', () => {
  const c = bareChip();
  c.chip.image.fill(0x00, SECTOR, SECTOR + 4096);
  c.chip.cutPowerDuring({ routine: 'erase', bytes: 100, mask: 0x0f });
  sequence(c, () => c.call('RE', [SECTOR, 4096, 1 << 16, 0xd8]));
  assert.equal(c.cuts, 1);
  assert.ok(
    c.chip.read(SECTOR, 100).every((b) => b === 0xff),
    'the first 100 bytes erased',
  );
  assert.equal(c.chip.image[SECTOR + 100], 0x0f, 'byte 100 half erased');
  assert.ok(
    c.chip.read(SECTOR + 101, 4096 - 101).every((b) => b === 0),
    'the rest untouched',
  );

  const d = bareChip();
  putPage(
    d.mcu,
    page(() => 0x00),
  );
  d.chip.cutPowerDuring({ routine: 'program', call: 2, bytes: 10, mask: 0xf0 });
  sequence(d, () => d.call('RP', [SECTOR, PAGE_DATA, 256])); // the first call: whole
  sequence(d, () => d.call('RP', [SECTOR + 256, PAGE_DATA, 256]));
  assert.equal(d.cuts, 1);
  assert.ok(d.chip.read(SECTOR, 256).every((b) => b === 0));
  assert.ok(d.chip.read(SECTOR + 256, 10).every((b) => b === 0));
  assert.equal(d.chip.image[SECTOR + 256 + 10], 0x0f, 'the high bits cleared, not the low');
  assert.ok(d.chip.read(SECTOR + 256 + 11, 245).every((b) => b === 0xff));
});

test('worn bits cannot be cleared by a program', () => {
  const c = bareChip();
  c.chip.wearOut(SECTOR + 3, 0x81);
  putPage(
    c.mcu,
    page(() => 0x00),
  );
  sequence(c, () => c.call('RP', [SECTOR, PAGE_DATA, 256]));
  assert.deepEqual([...c.chip.read(SECTOR, 5)], [0, 0, 0, 0x81, 0]);
});
