// The UF2 file `hexapod uf2` writes of the firmware (cli/, what `./dev uf2` gives a user),
// read back by this test's own reader of the UF2 specification's blocks and programmed into
// the emulated flash instead of the ELF's segments, as the RP2040's USB bootloader would:
// the chip boots from it and works, and its flash holds every byte of the ELF's load
// segments (and zeros where the file pads a sector).

import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { after, before, test } from 'node:test';

import { DEFAULT_ELF, EmulatedBoard } from '../src/chip/board.js';
import { loadSegments } from '../src/chip/elf.js';
import { firmwareBootrom, ok, runFrames, status } from '../src/test-support/e2e-support.js';

const REPO = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const UF2_MAGIC_START0 = 0x0a324655;
const UF2_MAGIC_START1 = 0x9e5d5157;
const UF2_MAGIC_END = 0x0ab16f30;
const FAMILY_ID_PRESENT = 0x2000;
const RP2040_FAMILY = 0xe48bff56;

let bootrom;
let dir;
let blocks;
before(() => {
  bootrom = firmwareBootrom();
  dir = mkdtempSync(join(tmpdir(), 'hexapod-uf2-'));
  const file = join(dir, 'hexapod-fw.uf2');
  execFileSync('cargo', ['run', '-q', '-p', 'hexapod', '--', 'uf2', DEFAULT_ELF, '-o', file], {
    cwd: REPO,
    stdio: ['ignore', 'ignore', 'inherit'],
  });
  blocks = readBlocks(readFileSync(file));
});

after(() => {
  rmSync(dir, { recursive: true, force: true });
});

/** The UF2 specification's 512-byte blocks: header words, data, end magic. */
function readBlocks(file) {
  assert.equal(file.length % 512, 0, 'whole blocks');
  const view = new DataView(file.buffer, file.byteOffset, file.byteLength);
  return Array.from({ length: file.length / 512 }, (_, i) => {
    const word = (w) => view.getUint32(i * 512 + 4 * w, true);
    assert.equal(word(0), UF2_MAGIC_START0, `block ${i} magic 0`);
    assert.equal(word(1), UF2_MAGIC_START1, `block ${i} magic 1`);
    assert.equal(word(127), UF2_MAGIC_END, `block ${i} end magic`);
    const size = word(4);
    return {
      flags: word(2),
      address: word(3),
      size,
      number: word(5),
      count: word(6),
      family: word(7),
      payload: file.subarray(i * 512 + 32, i * 512 + 32 + size),
    };
  });
}

test('the firmware UF2: 256-byte pages, RP2040 family, numbered, every ELF byte in it', () => {
  assert.ok(blocks.length > 100, `${blocks.length} blocks`);
  const image = new Map();
  blocks.forEach((block, i) => {
    assert.equal(block.flags, FAMILY_ID_PRESENT);
    assert.equal(block.family, RP2040_FAMILY);
    assert.equal(block.size, 256);
    assert.equal(block.address % 256, 0);
    assert.equal(block.number, i);
    assert.equal(block.count, blocks.length);
    block.payload.forEach((byte, j) => {
      assert.ok(!image.has(block.address + j), 'a byte written twice');
      image.set(block.address + j, byte);
    });
  });
  for (const { address, bytes } of loadSegments(DEFAULT_ELF)) {
    bytes.forEach((byte, j) => {
      assert.equal(image.get(address + j), byte, `byte at 0x${(address + j).toString(16)}`);
      image.delete(address + j);
    });
  }
  assert.ok(
    [...image.values()].every((b) => b === 0),
    'the rest is zero padding',
  );
});

test('the chip boots from the UF2 and works as from the ELF', () => {
  const segments = blocks.map((b) => ({ address: b.address, bytes: b.payload }));
  const fromUf2 = new EmulatedBoard({ bootrom, segments });
  const fromElf = new EmulatedBoard({ bootrom });
  const boards = [fromUf2, fromElf];
  for (const board of boards) {
    board.boot();
    assert.equal(board.request('set echo off').reply, 'ok');
  }
  // The same flash: the ELF's bytes, and zeros (UF2 padding) or erased bytes (ELF) elsewhere.
  const elfBytes = new Set();
  for (const { address, bytes } of loadSegments(DEFAULT_ELF)) {
    bytes.forEach((_, j) => elfBytes.add(address - 0x10000000 + j));
  }
  const [a, b] = boards.map((board) => board.flash.image);
  for (let offset = 0; offset < 2 * 1024 * 1024; offset++) {
    if (a[offset] !== b[offset]) {
      assert.ok(!elfBytes.has(offset) && a[offset] === 0, `flash byte 0x${offset.toString(16)}`);
    }
  }
  // And the same behaviour: a move, the pins, a save.
  for (const board of boards) {
    ok(board, 'pose 0 0 5 0 3 0');
    runFrames(board, 20);
    assert.equal(status(board).state, 'idle');
    ok(board, 'save');
  }
  assert.deepEqual(fromUf2.pulseWidthsUs(), fromElf.pulseWidthsUs());
  assert.deepEqual(ok(fromUf2, 'config'), ok(fromElf, 'config'));
});
