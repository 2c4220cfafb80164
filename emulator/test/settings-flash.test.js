// Settings saved in flash, through the real firmware ELF and the flash model (gap 7 of
// src/gaps/flash.js: the boot ROM's erase and program as the W25Q080 does them, its rules
// enforced): `save`, power cycles (a fresh chip, the same flash), power cuts at every step of a
// save, a damaged copy, a thousand saves, what the firmware does meanwhile (the pins hold,
// the watchdog stays quiet), and a sim rig that streams at its saved rate after a power cycle. What to expect comes from docs/settings.md ("Saving the settings")
// and the record layout documented in control/src/record.rs, read here by an independent decoder.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { BANNER, EmulatedBoard } from '../src/chip/board.js';
import { binaryFrame } from '../src/bench/firmware-bench.js';
import { HostReference } from '../src/test-support/host-reference.js';
import {
  assertConstant,
  assertPins,
  bootQuietUsb,
  capture,
  firmwareBootrom,
  FRAME_MS,
  defaultSettings,
  ok,
  quantisedUs,
  refused,
  runFrames,
  status,
  widthsNanos,
} from '../src/test-support/e2e-support.js';

let bootrom;
let reference;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
});

const SECTOR_BYTES = 4096;
/**
 * The record (control/src/record.rs), format 5: 252 bytes, UART0's baud rate at 228, the pivot
 * at 232, sequence number at 244, CRC-32 at 248 (each servo's speed rating in its block's byte
 * 17).
 */
const RECORD_BYTES = 252;
const FORMAT_VERSION = 5;
const BAUD_AT = 228;
const PIVOT_AT = 232;
const SEQUENCE_AT = 244;
const CRC_AT = 248;
const NOTHING_SAVED = '# warning: no settings saved in flash; using the defaults';
const USING_DEFAULTS = /^# warning: .*using the defaults$/;
const OTHER_COPY = new RegExp(
  '^# warning: one of the two saved copies of the settings cannot be used \\((.*)\\); ' +
    'loaded the other, save (\\d+): check config$',
);

/** CRC-32 (IEEE 802.3), bit by bit. */
function crc32(bytes) {
  let crc = 0xffffffff;
  for (const b of bytes) {
    crc ^= b;
    for (let k = 0; k < 8; k++) {
      crc = crc & 1 ? (crc >>> 1) ^ 0xedb88320 : crc >>> 1;
    }
  }
  return (crc ^ 0xffffffff) >>> 0;
}

/**
 * What a sector holds: 'erased', `{ sequence }` of a good record, or 'unusable'.
 * @returns {any}
 */
function sectorState(board, sector) {
  const { offset } = board.settingsStorage;
  const page = board.flash.read(offset + sector * SECTOR_BYTES, 256);
  if (page.every((b) => b === 0xff)) {
    return 'erased';
  }
  const view = new DataView(page.buffer);
  const good =
    String.fromCharCode(...page.subarray(0, 4)) === 'HXPS' &&
    view.getUint16(4, true) === FORMAT_VERSION &&
    view.getUint32(CRC_AT, true) === crc32(page.subarray(0, CRC_AT));
  return good ? { sequence: view.getUint32(SEQUENCE_AT, true) } : 'unusable';
}

/** A new board (erased settings sectors), booted, echo off. */
function freshBoard(options = {}) {
  const board = new EmulatedBoard({ bootrom, ...options });
  boot(board);
  return board;
}

/** Boots (up to the next banner), turns echo off; returns the `# ` lines after the banner. */
function boot(board) {
  board.waitForLine(BANNER, { timeoutMs: 1000 });
  // The banner's notices follow it, before the prompt; `set echo off` answers after them.
  const { lines } = board.request('set echo off');
  board.runUntil(() => board.servos().every((servo) => servo.live), { timeoutMs: 100 });
  return lines.filter((l) => l.startsWith('# '));
}

/** Power off and on; the lines written at boot. */
function powerCycle(board) {
  board.powerCycle();
  return boot(board);
}

/** `config` as text lines, without the last (`saved`) line; and that line. */
function config(board) {
  const lines = ok(board, 'config');
  const saved = lines.pop();
  assert.match(saved, /^saved: (yes|no|none) \(/);
  return { settings: lines, saved: saved.split(' ')[1] };
}

/** Changes that make settings tell apart: servo 1's and 4's trims, a speed. */
function apply(board, n) {
  ok(board, `set servo1.trim_us ${1500 + n}`);
  ok(board, `set servo4.trim_us ${1500 - n}`);
  ok(board, `set speed_mm_s ${10 + n}`);
}

test('save keeps the settings across a power cycle; the pins start at the saved trims', () => {
  const board = freshBoard();
  assert.deepEqual(
    board.lines.filter((l) => l.startsWith('# warning')),
    [NOTHING_SAVED],
    'a new board says nothing is saved',
  );
  assert.equal(config(board).saved, 'none');
  ok(board, 'set servo1.trim_us 1520');
  ok(board, 'set servo4.trim_us 1480.64');
  ok(board, 'set servo6.dir reversed');
  ok(board, 'set rod_mm 122');
  ok(board, 'set pivot_z_mm 80'); // where the record puts it: checked below
  ok(board, 'set frame_hz 100');
  ok(board, 'set stream.max_step_pct 7.5'); // in the record's bytes 10..12
  ok(board, 'set baud 230400'); // a link setting, saved too
  ok(board, 'set servo3.speed_s_60deg 0.12'); // format 5's speed rating
  board.runMs(5);
  assert.equal(config(board).saved, 'none', 'changed, but still nothing saved');
  ok(board, 'save');
  const saved = config(board);
  assert.equal(saved.saved, 'yes');
  assert.deepEqual(
    board.flash.ops.map((o) => o.routine),
    ['erase', 'program'],
  );

  const { offset } = board.settingsStorage;
  const pivot = new DataView(board.flash.read(offset, 256).buffer, PIVOT_AT, 12);
  assert.deepEqual(
    [0, 4, 8].map((at) => pivot.getFloat32(at, true)),
    [0, 0, 80],
  );

  const warnings = powerCycle(board).filter((l) => l.startsWith('# warning'));
  assert.deepEqual(warnings, [], 'the last save loads without a word');
  const after = config(board);
  assert.equal(after.saved, 'yes');
  // The same settings, UART0 at the saved rate (echo, the link's own, turned off by boot).
  assert.deepEqual(after.settings, saved.settings);
  assert.ok(saved.settings.includes('baud: 230400'), JSON.stringify(saved.settings));
  assert.ok(saved.settings.includes('pivot_z_mm: 80.000'), JSON.stringify(saved.settings));
  assert.ok(
    saved.settings.some((l) => /^servo3: .* speed_s_60deg=0\.12$/.test(l)),
    JSON.stringify(saved.settings),
  );
  assert.ok(saved.settings.includes('stream.max_step_pct: 7.5'), JSON.stringify(saved.settings));
  assert.ok(Math.abs(board.baud - 230400) / 230400 < 0.01, `UART0 at ${board.baud} baud`);
  // At power-up every servo gets its home pulse: its saved trim
  // (docs/geometry-and-calibration.md, "Calibration"), at the saved frame rate.
  runFrames(board, 5, 100);
  assertPins(board, [1520, 1500, 1500, 1480.64, 1500, 1500].map(quantisedUs));
  assert.ok(
    board.servos().every((s) => Math.abs(s.periodUs - 10_000) < 1),
    'saved frame rate',
  );

  // defaults (which keeps the link's rate) and 115200, then save: the factory settings at the
  // next power-up.
  ok(board, 'defaults');
  ok(board, 'set baud 115200');
  board.runMs(2);
  ok(board, 'save');
  powerCycle(board);
  const defaults = config(board);
  assert.equal(defaults.saved, 'yes');
  assert.deepEqual(defaults.settings, config(freshBoard()).settings);
});

test('save while moving is error:busy and writes nothing', () => {
  const board = freshBoard();
  ok(board, 'set speed_mm_s 5');
  ok(board, 'pose 10 0 0 0 0 0');
  board.runMs(100);
  const reply = refused(board, 'save', 'busy');
  assert.equal(reply, 'error:busy the platform is moving; wait for it or send stop first');
  assert.deepEqual(board.flash.ops, []);
  assert.match(status(board).state, /^moving /);
  ok(board, 'stop');
  ok(board, 'save');
  assert.equal(board.flash.ops.length, 2);
});

/**
 * Every step of a save a power cut can fall on, with what the documented layout says the next
 * power-up loads: the old settings until the record is complete to its last byte (252 bytes,
 * the baud rate at 228, the pivot at 232, the sequence number at 244 and the CRC last), the new
 * ones from then on.
 */
const CUTS = [
  { routine: 'erase', bytes: 0, loads: 'old', what: 'before the erase' },
  { routine: 'erase', bytes: 100, mask: 0x0f, loads: 'old', what: 'early in the erase' },
  { routine: 'erase', bytes: 2048, loads: 'old', what: 'half-way through the erase' },
  { routine: 'erase', bytes: SECTOR_BYTES, loads: 'old', what: 'after the erase' },
  { routine: 'program', bytes: 0, mask: 0x01, loads: 'old', what: 'at the first byte' },
  { routine: 'program', bytes: 4, loads: 'old', what: 'after the magic' },
  { routine: 'program', bytes: 100, mask: 0xa5, loads: 'old', what: 'mid-program' },
  { routine: 'program', bytes: BAUD_AT + 1, loads: 'old', what: 'mid baud rate' },
  { routine: 'program', bytes: PIVOT_AT + 6, loads: 'old', what: 'mid pivot' },
  { routine: 'program', bytes: SEQUENCE_AT, loads: 'old', what: 'before the sequence number' },
  { routine: 'program', bytes: SEQUENCE_AT + 2, loads: 'old', what: 'mid sequence number' },
  { routine: 'program', bytes: CRC_AT, loads: 'old', what: 'before the CRC' },
  // Half of the last byte's bits: whether that completes the record depends on its value.
  {
    routine: 'program',
    bytes: RECORD_BYTES - 1,
    mask: 0x7f,
    loads: 'either',
    what: 'in the last byte',
  },
  { routine: 'program', bytes: RECORD_BYTES, loads: 'new', what: 'after the record' },
  { routine: 'program', bytes: 256, loads: 'new', what: 'after the program, before the reply' },
];

for (const cut of CUTS) {
  const loads = cut.loads === 'either' ? 'old or the new' : cut.loads;
  test(`a power cut ${cut.what} of a save boots with the ${loads} settings, never defaults`, () => {
    const board = freshBoard();
    // Two saves: sector 0 holds save 1, sector 1 save 2 (the newest), so the cut save (3)
    // erases and programs sector 0, over save 1.
    apply(board, 1);
    ok(board, 'save');
    apply(board, 2);
    ok(board, 'save');
    const old = config(board).settings;
    apply(board, 3);
    const fresh = config(board).settings;
    board.cutPowerDuring({ routine: cut.routine, bytes: cut.bytes, mask: cut.mask ?? 0 });
    board.sendLine('save');
    assert.ok(
      board.runUntil(() => board.powerCycles.length > 0, { timeoutMs: 1000 }),
      'no cut',
    );
    assert.ok(board.powerCycles[0].cut);
    const bootLines = boot(board);
    const after = config(board);
    const state = sectorState(board, 0);
    const loads = cut.loads === 'either' ? (state.sequence === 3 ? 'new' : 'old') : cut.loads;
    assert.deepEqual(after.settings, loads === 'new' ? fresh : old, 'the settings loaded');
    assert.equal(after.saved, 'yes');
    const defaults = bootLines.filter((l) => USING_DEFAULTS.test(l));
    assert.deepEqual(defaults, [], 'defaults although a good copy exists');
    // A sector left holding something that is not a record is reported; an erased one is not.
    const warning = bootLines.find((l) => OTHER_COPY.test(l));
    if (state === 'unusable') {
      assert.ok(warning, `no warning about the cut copy: ${JSON.stringify(bootLines)}`);
      assert.equal(warning.match(OTHER_COPY)[2], '2', 'loaded save 2');
    } else {
      assert.equal(warning, undefined);
    }
    // Saving goes on: the next save lands (in sector 0 again if the cut one was not complete).
    // The power cut took the unsaved changes with it: made again.
    apply(board, 3);
    ok(board, 'save');
    powerCycle(board);
    assert.deepEqual(config(board).settings, fresh);
    assert.deepEqual(sectorState(board, loads === 'new' ? 1 : 0), {
      sequence: loads === 'new' ? 4 : 3,
    });
  });
}

test('a flipped bit in the newest copy is found; the other copy loads, with the warning', () => {
  const board = freshBoard();
  apply(board, 1);
  ok(board, 'save');
  const first = config(board).settings;
  apply(board, 2);
  ok(board, 'save');
  const { offset } = board.settingsStorage;
  assert.deepEqual(sectorState(board, 1), { sequence: 2 });
  board.flash.image[offset + SECTOR_BYTES + 57] ^= 0x10; // in servo 1's record
  const bootLines = powerCycle(board);
  assert.ok(
    bootLines.includes(
      '# warning: one of the two saved copies of the settings cannot be used ' +
        '(damaged: checksum mismatch); loaded the other, save 1: check config',
    ),
    JSON.stringify(bootLines),
  );
  assert.deepEqual(config(board).settings, first);
  // The next save goes over the damaged copy, never over the good one.
  const ops = board.flash.ops.length;
  ok(board, 'save');
  assert.deepEqual(
    board.flash.ops.slice(ops).map((o) => [o.routine, o.offset]),
    [
      ['erase', offset + SECTOR_BYTES],
      ['program', offset + SECTOR_BYTES],
    ],
  );
  assert.deepEqual(
    powerCycle(board).filter((l) => l.startsWith('# warning')),
    [],
  );
});

test('1,000 saves in a row alternate between the two sectors, each erasing only the older', () => {
  const board = freshBoard();
  ok(board, 'set baud 921600');
  board.runMs(2);
  const { offset } = board.settingsStorage;
  for (let n = 1; n <= 1000; n++) {
    ok(board, `set servo2.trim_us ${1400 + (n % 200)}`);
    const ops = board.flash.ops.length;
    ok(board, 'save');
    // Save n goes to sector (n - 1) % 2: an erase then a program of its first page.
    const sector = offset + ((n - 1) % 2) * SECTOR_BYTES;
    assert.deepEqual(
      board.flash.ops.slice(ops).map((o) => [o.routine, o.offset, o.bytes]),
      [
        ['erase', sector, SECTOR_BYTES],
        ['program', sector, 256],
      ],
      `save ${n}`,
    );
    if (n % 100 === 0 || n < 4) {
      // The newest is save n, the other sector still holds save n - 1.
      assert.deepEqual(sectorState(board, (n - 1) % 2), { sequence: n });
      assert.deepEqual(sectorState(board, n % 2), n > 1 ? { sequence: n - 1 } : 'erased');
    }
  }
  assert.deepEqual(
    board.flash.ops.map((o) => o.offset).filter((o) => o < offset),
    [],
    'nothing outside the settings sectors was touched',
  );
  powerCycle(board);
  const trim = config(board).settings.find((l) => l.startsWith('servo2: '));
  assert.match(trim, /^servo2: trim_us=1400\.00 /); // save 1000: 1400 + 1000 % 200
});

test('during a save at the maximum erase time the pins hold and the watchdog is quiet', () => {
  // 400 ms for the sector, 3 ms for the page: the W25Q80DV's maxima. The board fails the run
  // if the watchdog expires (its default `onWatchdog: 'fail'`).
  const board = freshBoard({ flashTiming: 'max' });
  ok(board, 'pose 0 0 5 0 3 0');
  board.runMs(500);
  const widths = widthsNanos(board);
  let elapsedMs;
  const pulses = capture(
    board,
    () => {
      const start = board.millis;
      ok(board, 'save');
      elapsedMs = board.millis - start;
    },
    3,
  );
  assert.ok(elapsedMs > 403, `the save took ${elapsedMs} ms`);
  // Every pulse during the save had the held width and came exactly one frame after the last.
  assertConstant(pulses, widths, 'during the save');
  for (const servo of pulses) {
    assert.ok(servo.length >= 20, `${servo.length} pulses in ${elapsedMs} ms`);
    for (const { periodNanos } of servo) {
      assert.ok(periodNanos === null || periodNanos === FRAME_MS * 1e6, `period ${periodNanos}`);
    }
  }
  assert.deepEqual(board.resets, []);
});

test('the watchdog has time for a flash slower than its datasheet, and 500 ms again after', () => {
  // A sector erase of 1.5 s, beyond the 500 ms the watchdog normally allows: the firmware gives
  // it 2 s around the write. (Without that the run fails with "watchdog expired".)
  const board = freshBoard({
    flashTiming: { sectorEraseMs: 1500, pageProgramMs: 3 },
    onWatchdog: 'reset',
  });
  ok(board, 'save', { timeoutMs: 3000 });
  assert.deepEqual(board.resets, []);
  // Afterwards a stall is caught at 500 ms as before: every interrupt masked, the loop asleep.
  board.runMs(50);
  const stalledAt = board.millis;
  board.mcu.core.enabledInterrupts = 0;
  assert.ok(
    board.runUntil(() => board.resets.length > 0, { timeoutMs: 600 }),
    'no reset',
  );
  const after = board.resets[0].nanos / 1e6 - stalledAt;
  assert.ok(after <= 500, `reset ${after} ms after the stall`);
});

test('lines sent during a save without waiting for its ok are lost, and said so', () => {
  // No input is read while the flash is written (interrupts masked): what arrives beyond the
  // UART's 32-byte FIFO is lost. docs/settings.md asks hosts to wait for save's ok; a host that
  // does not hears of the loss at once, and no line runs with bytes missing.
  const board = freshBoard();
  const from = board.lines.length;
  board.sendBytes(`save\n${'status\n'.repeat(20)}`);
  board.runMs(300);
  const lines = board.lines.slice(from);
  assert.ok(
    lines.some((l) =>
      /^# warning: UART receive error, input lost \(at least \d+ bytes?\)$/.test(l),
    ),
    JSON.stringify(lines),
  );
  const finals = lines.filter((l) => /^(ok|error:)/.test(l));
  assert.equal(finals[0], 'ok', 'the save itself');
  assert.ok(finals.length < 21, 'some lines were lost whole');
  for (const reply of finals.slice(1)) {
    assert.ok(reply === 'ok' || reply.startsWith('error:rx-overflow '), reply);
  }
  assert.ok(board.rxFifoDroppedBytes > 0);
  // The documented resync: a line end, then a command whose reply is awaited.
  board.sendLine('');
  board.runMs(20);
  board.lineCursor = board.lines.length;
  assert.equal(status(board).state, 'idle');
});

test('over USB, lines sent during a save wait in the host: none lost, every one answered', () => {
  // The USB interrupt is masked during the write too: the USB controller refuses the host's
  // packets (NAK) and the host sends them again afterwards (docs/settings.md, "Saving the
  // settings").
  const board = bootQuietUsb(bootrom); // over USB; board.uart is UART0
  const from = board.lines.length;
  board.loop.reset();
  // 700 bytes of lines after the save: more than the bus carries before the write begins.
  board.sendBytes(`save\n${'status\n'.repeat(100)}`);
  assert.ok(
    board.runUntil(() => board.flash.ops.length > 0, { timeoutMs: 100 }),
    'no erase',
  );
  // The erase is done (45 ms): the firmware took nothing meanwhile, the host still holds bytes.
  assert.ok(board.usb.unsent > 0, 'the host had nothing left to send during the erase');
  const finals = () => board.lines.slice(from).filter((l) => /^(ok|error:)/.test(l));
  const answered = board.runUntil(() => finals().length >= 101, { timeoutMs: 1000 });
  assert.ok(answered, JSON.stringify(finals()));
  board.runMs(20);
  assert.deepEqual(finals(), Array(101).fill('ok'));
  assert.ok(!board.lines.slice(from).some((l) => l.startsWith('# warning')), 'nothing lost');
  assert.deepEqual(
    board.flash.ops.map((op) => op.routine),
    ['erase', 'program'],
  );
  assert.equal(board.loop.longPasses.length, 1, "the save's pass, the only long one");
  board.lineCursor = board.lines.length; // the replies above were read
  // Saved, as UART0 sees it too.
  assert.equal(config(board).saved, 'yes');
  assert.equal(board.uart.request('set echo off').reply, 'ok');
  const uartConfig = board.uart.request('config').lines;
  assert.ok(uartConfig.includes('# saved: yes (these settings are the ones saved in flash)'));
});

test('a sim rig comes back: saved at 921600 with its stream set-up, it streams after a power cycle with no command first', () => {
  const board = freshBoard();
  // The FlyPT Mover steps (docs/streaming.md): pass-through, the full scales, the rate, save.
  ok(board, 'set speed_mm_s off');
  ok(board, 'set speed_deg_s off');
  ok(board, 'set stream.z_mm 12');
  ok(board, 'set stream.roll_deg 10');
  ok(board, 'set baud 921600');
  board.runMs(2);
  ok(board, 'save');
  // The record holds the rate where the documented layout puts it.
  const { offset } = board.settingsStorage;
  const page = board.flash.read(offset, 256);
  assert.deepEqual(sectorState(board, 0), { sequence: 1 });
  assert.equal(new DataView(page.buffer).getUint32(BAUD_AT, true), 921600);

  // Off and on: nothing is sent but the frames, at the saved rate.
  board.powerCycle();
  board.waitForLine(BANNER, { timeoutMs: 1000 });
  assert.ok(Math.abs(board.baud - 921600) / 921600 < 0.01, `UART0 at ${board.baud} baud`);
  board.runUntil(() => board.servos().every((servo) => servo.live), { timeoutMs: 100 });
  const scales = [25, 25, 12, 10, 15, 20];
  const count = (v, i) => Math.round(32768 + (v / scales[i]) * 32768);
  const carried = (pose) => pose.map((v, i) => ((count(v, i) - 32768) / 32768) * scales[i]);
  for (const pose of [
    [0, 0, 6, 0, 0, 0],
    [0, 0, -4, 5, 0, 0],
    [0, 0, 4, -3, 0, 0],
  ]) {
    board.sendBytes(binaryFrame(pose.map(count)));
    runFrames(board, 3, 50);
    const [answer] = reference.solve(defaultSettings(), [carried(pose)]);
    assert.ok(answer.ok, JSON.stringify(answer));
    // Pass-through (the saved limits are off): the pins are at the frame's pose at once.
    assertPins(board, answer.pulse_us, `after the frame for ${pose}`);
  }
  // Then a person at a terminal (echo on since power-up; off for the reply's parsing).
  board.request('set echo off');
  assert.deepEqual(status(board).stream, {
    frames: 3,
    applied: 3,
    damaged: 0,
    clamped: 0,
    refused: 0,
  });
});
