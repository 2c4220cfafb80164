// The main loop never stalls, whatever arrives: through the real firmware ELF, lines whose work
// is long (path checks of 1,000 poses, listings, geometry changes, the return home after link
// loss) sent back to back, pipelined, at 115,200 and 921,600 baud, and over UART0 and USB at
// once. Each case asserts that the watchdog never fires (the board fails the run if it does),
// that no servo frame is missed (the firmware writes new compare values in every frame period),
// that every line gets its reply in order (also with the servos' speed ratings slowing moves
// and stream steps), and that the longest main-loop pass stays under the
// bound the documents state (docs/testing.md):
// 1 ms (125,000 cycles at 125 MHz), a third of a frame at the highest frame rate (333 Hz).
// The one pass allowed to be longer is a `save`'s flash write (a sector erase keeps the core in
// the boot ROM with interrupts masked, 45 ms in the emulator's typical W25Q080 timing): the
// last test checks that each long pass is exactly a save's, and that the pins hold meanwhile.
// Pass lengths are CPU cycles between watchdog feeds (the loop feeds it at the top of every
// pass; emulator/src/chip/loop-meter.js), which the emulator counts the same on every run.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { EmulatedBoard, FINAL_REPLY } from '../src/chip/board.js';
import {
  bootQuiet,
  firmwareBootrom,
  FRAME_MS,
  ok,
  status,
} from '../src/test-support/e2e-support.js';
import { binaryFrame } from '../src/bench/firmware-bench.js';

/** The documented bound on a main-loop pass: 1 ms at 125 MHz. */
const PASS_BOUND_CYCLES = 125_000;

let bootrom;
before(() => {
  bootrom = firmwareBootrom();
});

function quietBoard() {
  return bootQuiet(bootrom);
}

/** With echo on: sends a line that must succeed. */
function typed(board, line) {
  assert.equal(board.request(line).reply, 'ok', line);
}

/** The final replies from line index `from` on. */
function finalsFrom(board, from) {
  return board.lines.slice(from).filter((l) => FINAL_REPLY.test(l));
}

/** Sends `lines` back to back and waits for as many final replies; returns them. */
function pipeline(board, lines, { timeoutMs = 5000 } = {}) {
  const from = board.lines.length;
  board.sendBytes(lines.map((l) => `${l}\n`).join(''));
  const done = board.runUntil(() => finalsFrom(board, from).length >= lines.length, { timeoutMs });
  const replies = finalsFrom(board, from);
  assert.ok(done, `${replies.length} of ${lines.length} replies: ${JSON.stringify(replies)}`);
  board.lineCursor = board.lines.length;
  return replies;
}

/** Starts measuring passes and frames from now. */
function measure(board) {
  board.loop.reset();
  board.frames.reset();
}

/** The bound held and no frame was missed since `measure`. */
function assertNoStall(board, what) {
  const { longestPassCycles, longestHandlerCycles } = board.loop;
  assert.ok(
    longestPassCycles < PASS_BOUND_CYCLES,
    `${what}: a main-loop pass took ${longestPassCycles} cycles (${(longestPassCycles / 125e3).toFixed(2)} ms)`,
  );
  assert.ok(
    longestHandlerCycles < PASS_BOUND_CYCLES / 10,
    `${what}: a handler took ${longestHandlerCycles} cycles`,
  );
  assert.ok(board.frames.frames > 0, `${what}: no frames seen`);
  assert.equal(
    board.frames.missed,
    0,
    `${what}: ${board.frames.missed} of ${board.frames.frames} frames missed, at ${board.frames.missedAtNanos.map((n) => (n / 1e6).toFixed(1))} ms`,
  );
  assert.equal(board.resets.length, 0, `${what}: the watchdog reset the chip`);
}

test('four moves in flight at 1 mm/s (each checked at 1,000 poses): no stall, every reply in order', () => {
  const board = quietBoard();
  ok(board, 'set speed_mm_s 1');
  ok(board, 'pose 10.2 0 0 0 0 0');
  board.runMs(10_500); // until it arrives (10.2 mm at 1 mm/s)
  measure(board);
  const replies = pipeline(board, ['move x=-10.2', 'move x=-10.1', 'move x=-10.2', 'move x=-10.1']);
  assert.deepEqual(replies, ['ok', 'ok', 'ok', 'ok']);
  board.runMs(200);
  assertNoStall(board, 'four moves');
});

test('new targets blended into while moving (acceleration limits) at 333 Hz, pipelined: no stall', () => {
  const board = quietBoard();
  ok(board, 'set frame_hz 333');
  ok(board, 'set speed_mm_s 100');
  ok(board, 'set accel_mm_s2 50');
  ok(board, 'set accel_deg_s2 40');
  ok(board, 'pose 12 0 0 0 0 0');
  board.runMs(300);
  measure(board);
  // Each a blend from the motion in progress over hundreds of frames, checked at every one of
  // them while the platform moves on, its hand-over learnt from the checks before.
  const lines = ['pose -10 5 2 0 0 4', 'nudge yaw=-6', 'move x=9', 'nudge z=-3', 'home'];
  const replies = pipeline(board, lines);
  assert.deepEqual(
    replies,
    lines.map(() => 'ok'),
  );
  board.runMs(3000);
  assertNoStall(board, 'blends');
  assert.equal(status(board).state, 'idle');
});

test('three moves in flight at 0.5 mm/s at 115,200 baud', () => {
  const board = quietBoard();
  ok(board, 'set speed_mm_s 0.5');
  measure(board);
  const replies = pipeline(board, ['move x=10.2', 'move x=-10.2', 'move x=10.2']);
  assert.deepEqual(replies, ['ok', 'ok', 'ok']);
  board.runMs(200);
  assertNoStall(board, 'three moves');
});

test('twenty moves in flight at 921,600 baud', () => {
  const board = quietBoard();
  ok(board, 'set speed_mm_s 1');
  ok(board, 'set baud 921600');
  board.runMs(5);
  measure(board);
  const lines = Array.from({ length: 20 }, (_, i) => `move x=${i % 2 ? '-10.1' : '-10.2'}`);
  const replies = pipeline(board, lines, { timeoutMs: 10_000 });
  assert.deepEqual(
    replies,
    lines.map(() => 'ok'),
  );
  board.runMs(200);
  assertNoStall(board, 'twenty moves');
});

test('every long command class back to back at 333 Hz, echo on: no stall, replies in order', () => {
  const board = new EmulatedBoard({ bootrom });
  board.boot();
  typed(board, 'set frame_hz 333');
  typed(board, 'set speed_mm_s 1');
  board.runMs(2 * FRAME_MS);
  measure(board);
  const lines = [
    ['check 20 0 0 0 0 0', 'ok'], // 1,000 path checks, nothing moves
    ['config', 'ok'],
    ['help', 'ok'],
    ['geometry', 'ok'],
    ['status', 'ok'],
    ['set rod_mm 121', 'ok'], // a new geometry and IK
    ['set rod_mm 120', 'ok'],
    ['defaults', 'ok'],
    ['set frame_hz 333', 'ok'],
    ['set speed_mm_s 1', 'ok'],
    ['pose 20 0 0 0 0 0', 'ok'], // 1,000 path checks, then a slow move
    ['move x=-20', 'ok'], // checked while moving: holds, then turns back
    ['pulses', 'ok'], // the short query `hexapod view` repeats, while moving
    ['defaults', 'error:busy'],
    ['pose 0 0 80 0 0 0', 'error:unreachable'],
    ['set speed_mm_s off', 'ok'],
    ['pose 0 0 0 0 0 0', 'ok'], // a jump, 40 path checks
    ['check 30 -12 -13.5 5 -13 28', 'ok'],
  ];
  const replies = pipeline(
    board,
    lines.map(([l]) => l),
    { timeoutMs: 10_000 },
  );
  replies.forEach((reply, i) => {
    assert.ok(reply.startsWith(lines[i][1]), `${lines[i][0]}: ${reply}`);
  });
  board.runMs(100);
  assertNoStall(board, 'every class');
});

test('servo (its pose found), limits, holding torques and torque-checked paths and clamps: no stall', () => {
  const board = new EmulatedBoard({ bootrom });
  board.boot();
  typed(board, 'set frame_hz 333');
  typed(board, 'set speed_mm_s 1');
  board.runMs(2 * FRAME_MS);
  measure(board);
  const lines = [
    ['servo 3 1620', 'ok'], // the forward kinematics, a Newton iteration per pass
    ['status', 'ok'],
    ['servo 1 1900', 'ok'],
    ['servo 2 1900', 'ok'], // no pose: the continuation fails part way
    ['servo 2 1500', 'ok'],
    ['servo 1 1500', 'ok'],
    ['servo 3 1500', 'ok'],
    ['limits', 'ok'], // about 160 IK solutions, three per pass
    ['set payload_g 2000', 'ok'],
    ['set payload_com_z_mm 30', 'ok'],
    ['status', 'ok'], // the holding torques, a pass of their own
    ['set servos.torque_kgcm 2', 'ok'], // the held pose's torques
    ['check 0 0 -12 0 0 0', 'ok'], // 600 checkpoints, each with its torques, one per pass
    ['limits', 'ok'], // every pose with its torques, one per pass
    ['servo 4 1520', 'ok'], // the pose found, then its torques
    ['set rod_mm 121', 'ok'], // with pulses set by servo: their pose found again
    ['defaults', 'ok'],
  ];
  const replies = pipeline(
    board,
    lines.map(([l]) => l),
    { timeoutMs: 20_000 },
  );
  replies.forEach((reply, i) => {
    assert.ok(reply.startsWith(lines[i][1]), `${lines[i][0]}: ${reply}`);
  });
  board.runMs(100);
  assertNoStall(board, 'servo, limits, torques');
});

test('stream targets clamped to the torque ratings, a pose per pass: no stall', () => {
  const board = quietBoard();
  for (const line of [
    'set speed_mm_s off',
    'set speed_deg_s off',
    'set payload_g 2000',
    'set payload_com_z_mm 30',
    'set servos.torque_kgcm 1',
  ]) {
    ok(board, line);
  }
  ok(board, 'set baud 921600');
  board.runMs(5);
  measure(board);
  // Every frame beyond the ratings (x from 5 to 25 mm): each clamped by bisection, one pose
  // with its torques per pass; frames come faster than that, the newest wins.
  for (let i = 0; i < 40; i++) {
    board.sendBytes(
      binaryFrame([
        32768 + Math.round((0.2 + i * 0.02) * 32768),
        32768,
        32768,
        32768,
        32768,
        32768,
      ]),
    );
    board.runMs(2);
  }
  board.runMs(50);
  const s = ok(board, 'status').find((l) => l.startsWith('stream: '));
  assert.match(s, /clamped=[1-9]/);
  assertNoStall(board, 'clamped stream');
});

test('moves and stream steps slowed to the servos rated speeds, at 333 Hz: no stall', () => {
  const board = quietBoard();
  for (const line of [
    'set frame_hz 333',
    'set speed_mm_s off',
    'set speed_deg_s off',
    'set servos.speed_s_60deg 0.1',
    'set servo4.speed_s_60deg 0.3',
  ]) {
    ok(board, line);
  }
  ok(board, 'set baud 921600');
  board.runMs(5);
  measure(board);
  // Rated moves sent back to back (each its path measured, then planned again and checked
  // again where the arms turn unevenly: x across, yaw across), one checked while the last
  // moves, and a check.
  const lines = [
    ['pose 20 0 0 0 0 0', 'ok'],
    ['pose -20 0 0 0 0 0', 'ok'],
    ['pose 0 0 0 0 0 20', 'ok'],
    ['check 0 0 0 0 0 -20', 'ok'],
    ['home', 'ok'],
  ];
  const replies = pipeline(
    board,
    lines.map(([l]) => l),
    { timeoutMs: 5000 },
  );
  replies.forEach((reply, i) => {
    assert.ok(reply.startsWith(lines[i][1]), `${lines[i][0]}: ${reply}`);
  });
  board.runMs(300);
  // A rated stream whose target jumps about every 6 ms: every step shortened to the ratings
  // (the tracker's step, solved again where it is shortened).
  for (let i = 0; i < 60; i++) {
    const s = i % 2 === 0 ? 1 : -1;
    board.sendBytes(
      binaryFrame([
        32768 + s * 0.6 * 32768,
        32768 - s * 0.3 * 32768,
        32768 + 0.2 * 32768,
        32768 + s * 0.3 * 32768,
        32768 - s * 0.3 * 32768,
        32768 + s * 0.5 * 32768,
      ]),
    );
    board.runMs(6);
  }
  board.runMs(50);
  const s = ok(board, 'status').find((l) => l.startsWith('stream: '));
  assert.match(s, /applied=[1-9]/);
  assertNoStall(board, 'servo speed');
});

test('rated blends, and a move over a rated tracked stream, at 333 Hz: no stall', () => {
  const board = quietBoard();
  for (const line of [
    'set frame_hz 333',
    'set speed_mm_s 100',
    'set speed_deg_s 100',
    'set accel_mm_s2 400',
    'set accel_deg_s2 400',
    'set servos.speed_s_60deg 0.1',
    'set servo4.speed_s_60deg 0.3',
  ]) {
    ok(board, line);
  }
  ok(board, 'set baud 921600');
  ok(board, 'pose 12 0 0 0 0 0');
  board.runMs(100);
  measure(board);
  // Each a blend from the motion in progress, its frames' arm turns measured against the
  // ratings, planned again (slower) where they are over them, while the platform moves on.
  const lines = ['pose -10 5 2 0 0 4', 'nudge yaw=-6', 'move x=9', 'check 0 0 -3 0 0 5', 'home'];
  const replies = pipeline(board, lines);
  assert.deepEqual(
    replies,
    lines.map(() => 'ok'),
  );
  // A stream tracked (frames every 6 ms), then a pose while the tracker moves: the stream
  // becomes a planned motion in the line's pass, and the pose blends in from it.
  for (let i = 0; i < 20; i++) {
    board.sendBytes(
      binaryFrame([32768 + i * 800, 32768, 32768 + i * 500, 32768, 32768, 32768 - i * 600]),
    );
    board.runMs(6);
  }
  assert.deepEqual(pipeline(board, ['pose 0 0 -4 0 0 0']), ['ok']);
  board.runMs(1500);
  assertNoStall(board, 'rated blends');
  assert.equal(status(board).state, 'idle');
});

test('the return home after link loss is checked in slices too', () => {
  const board = quietBoard();
  ok(board, 'set speed_mm_s 1');
  ok(board, 'set link_timeout_s 8');
  ok(board, 'pose 10 0 0 0 0 0');
  measure(board);
  // Silence: the move goes on, then link loss at about x = 8 mm: a check of the way home at
  // every one of its 400 frames, a few poses per pass.
  board.waitForLine(/^# link lost: no command for 8 s/, { timeoutMs: 9000 });
  board.runMs(500);
  assert.match(
    ok(board, 'status').find((l) => l.startsWith('state:')),
    /returning home/,
  );
  assertNoStall(board, 'link loss');
});

test('while a long reply drains at 9,600 baud the main loop sleeps instead of spinning', () => {
  const board = new EmulatedBoard({ bootrom });
  board.boot();
  typed(board, 'set baud 9600');
  board.runMs(10);
  board.runMs(100);
  const from = board.lines.length;
  board.sendLine('help');
  // The line's own bytes and the start of the reply.
  board.runMs(20);
  measure(board);
  const start = board.cycles;
  assert.ok(board.runUntil(() => finalsFrom(board, from).length > 0, { timeoutMs: 5000 }));
  const bytes = board.lines.slice(from).join('\n').length;
  assert.ok(bytes > 1000, `${bytes} bytes`);
  // About a second of transmission (10 bit times a byte). Awake only when the TX FIFO has
  // room (an interrupt per 16 bytes sent) and for frames: a few hundred passes, not the
  // hundred thousand a spinning loop makes.
  assert.ok(board.loop.passes < 400, `${board.loop.passes} passes while ${bytes} bytes went out`);
  const busyCycles = board.cycles - start;
  assert.ok(busyCycles < 5_000_000, `${busyCycles} cycles busy while the reply drained`);
});

test('both links busy at once at 333 Hz: UART0 and USB pipelining long commands, no stall', () => {
  const board = new EmulatedBoard({ bootrom, usb: true });
  board.boot();
  board.usb.waitUntilOpen();
  board.usb.waitForLine(/hexapod/);
  typed(board, 'set frame_hz 333');
  typed(board, 'set speed_mm_s 1');
  typed(board, 'set echo off');
  typed(board, 'set baud 921600');
  board.runMs(5);
  measure(board);
  // UART0: moves of 1,000 checks each, pipelined; USB (echo on): every long command class.
  const moves = Array.from({ length: 12 }, (_, i) => `move x=${i % 2 ? '-10.1' : '-10.2'}`);
  const usbLines = [
    'check 20 0 0 0 0 0',
    'config',
    'help',
    'geometry',
    'status',
    'check -20 0 0 0 0 0',
    'help',
    'config',
  ];
  const [uartFrom, usbFrom] = [board.lines.length, board.usb.lines.length];
  board.sendBytes(moves.map((l) => `${l}\n`).join(''));
  board.usb.sendBytes(usbLines.map((l) => `${l}\r`).join(''));
  const done = () =>
    finalsFrom(board, uartFrom).length >= moves.length &&
    board.usb.lines.slice(usbFrom).filter((l) => FINAL_REPLY.test(l)).length >= usbLines.length;
  assert.ok(board.runUntil(done, { timeoutMs: 10_000 }));
  assert.deepEqual(
    finalsFrom(board, uartFrom),
    moves.map(() => 'ok'),
  );
  // USB: each line echoed after a prompt, then its data, then its ok, in order.
  const usbText = board.usb.lines.slice(usbFrom);
  const echoes = usbText.filter((l) => l.startsWith('> ')).map((l) => l.slice(2));
  assert.deepEqual(echoes, usbLines);
  assert.deepEqual(
    usbText.filter((l) => FINAL_REPLY.test(l)),
    usbLines.map(() => 'ok'),
  );
  board.runMs(100);
  assertNoStall(board, 'both links');
});

test('a save is the one pass over 1 ms: its erase and program; the pins hold meanwhile', () => {
  const board = quietBoard();
  ok(board, 'pose 0 0 5 0 3 0');
  board.runMs(500);
  measure(board);
  const before = board.pulseWidthsUs();
  // Each reply awaited: no input is read during a save's write (docs/settings.md).
  for (const line of ['save', 'status', 'config', 'check 20 0 0 0 0 0', 'save', 'help', 'save']) {
    ok(board, line);
  }
  board.runMs(100);
  const writes = [];
  for (let i = 0; i < board.flash.ops.length; i += 2) {
    const [erase, program] = board.flash.ops.slice(i, i + 2);
    assert.deepEqual([erase.routine, program.routine], ['erase', 'program']);
    writes.push([erase.nanos, program.nanos]);
  }
  assert.equal(writes.length, 3);
  // One long pass per save, holding both its erase and its program; none other.
  const long = board.loop.longPasses;
  assert.equal(long.length, 3, JSON.stringify(long));
  long.forEach((pass, i) => {
    const [erase, program] = writes[i];
    assert.ok(pass.startNanos <= erase && program <= pass.endNanos, `save ${i + 1}: not its pass`);
    // The erase (45 ms) and the program (0.7 ms) with the core busy in the boot ROM.
    assert.ok(pass.cycles >= 45.7e-3 * 125e6, `${pass.cycles} cycles`);
  });
  // Frames missed only while a save's interrupts were masked; the pins held all along.
  for (const at of board.frames.missedAtNanos) {
    assert.ok(
      long.some((pass) => at >= pass.startNanos && at <= pass.endNanos + FRAME_MS * 1e6),
      `a frame missed at ${at / 1e6} ms, outside a save`,
    );
  }
  assert.deepEqual(board.pulseWidthsUs(), before);
  assert.equal(board.resets.length, 0);
});
