// End-to-end: the real firmware ELF in the emulator, observed only from outside (UART0 bytes
// and servo pin edges), in emulated time.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { EmulatedBoard, FINAL_REPLY } from '../src/chip/board.js';
import { bootedBoard, firmwareBootrom } from '../src/test-support/e2e-support.js';

// The wiring and timing the firmware promises (docs: CONTEXT "Wiring"), restated here from
// the spec rather than taken from the firmware: 125 MHz / divider 40 -> 320 ns per count.
const NANOS_PER_COUNT = 320;
const COUNTS_PER_SECOND = 125_000_000 / 40;
const HOME_PULSE_US = 1500;
const DEFAULT_FRAME_HZ = 50;

let bootrom;
before(() => {
  bootrom = firmwareBootrom();
});

/** Final replies (`ok` / `error:...`) received after the banner. */
function finalReplies(board) {
  return board.lines.slice(1).filter((line) => FINAL_REPLY.test(line));
}

test('boot prints the banner as its first line', () => {
  const board = new EmulatedBoard({ bootrom });
  const banner = board.boot();
  assert.match(banner, /hexapod.* \d+\.\d+\.\d+\b.*\bhelp\b/);
  assert.equal(board.lines[0], banner);
  assert.ok(board.millis < 100, `banner after ${board.millis} ms`);
});

test('at boot all six servos get 1500 us pulses at 50 Hz, exact to the count', () => {
  const board = bootedBoard(bootrom);
  board.runMs(3.5 * (1000 / DEFAULT_FRAME_HZ)); // at least two whole frames on every pin

  const periodNanos = (COUNTS_PER_SECOND / DEFAULT_FRAME_HZ) * NANOS_PER_COUNT;
  const widthNanos = Math.round((HOME_PULSE_US * 1000) / NANOS_PER_COUNT) * NANOS_PER_COUNT;
  assert.equal(periodNanos, 20_000_000);

  const servos = board.servos();
  assert.deepEqual(
    servos.map((servo) => [servo.servo, servo.gpio]),
    [
      [1, 2],
      [2, 3],
      [3, 4],
      [4, 5],
      [5, 6],
      [6, 7],
    ],
  );
  for (const servo of servos) {
    assert.ok(servo.pulses >= 2, `servo ${servo.servo}: ${servo.pulses} pulses`);
    assert.ok(servo.live, `servo ${servo.servo} stopped pulsing`);
    assert.equal(servo.periodNanos, periodNanos, `servo ${servo.servo} period`);
    assert.equal(servo.widthNanos, widthNanos, `servo ${servo.servo} width`);
  }
  assert.deepEqual(board.pulseWidthsUs(), Array(6).fill(widthNanos / 1000));
  assert.deepEqual(board.periodsUs(), Array(6).fill(20_000));
});

test('a line gets exactly one final reply', () => {
  const board = bootedBoard(bootrom);
  const { reply, lines } = board.request('frobnicate 1 2 3');
  assert.match(reply, /^error:unknown-command\b.*\bfrobnicate\b/);
  assert.equal(lines.at(-1), reply);

  board.runMs(50); // nothing else may follow
  assert.deepEqual(finalReplies(board), [reply]);
});

test('LF and CRLF each end one line; back-to-back lines are answered in order', () => {
  const board = bootedBoard(bootrom);
  board.sendBytes('one\r\ntwo\nthree\r\n');
  board.waitForLine(/three/);
  board.runMs(20);
  const replies = finalReplies(board);
  assert.equal(replies.length, 3, JSON.stringify(replies));
  ['one', 'two', 'three'].forEach((word, i) => {
    assert.match(replies[i], new RegExp(`^error:unknown-command\\b.*\\b${word}\\b`));
  });
  assert.equal(board.rxFifoDroppedBytes, 0);
});

test('input is paced at the baud rate: a line of n bytes takes n byte times', () => {
  const board = bootedBoard(bootrom);
  // Echo off: the reply is then only sent after the whole line is in, and the reply's own
  // bytes take their byte times on the way back (the same rate both ways).
  assert.equal(board.request('set echo off').reply, 'ok');
  board.runMs(5);
  const start = board.nanos;
  const outputBefore = board.outputBytes.length;
  board.request('x'.repeat(39)); // 40 bytes with the LF
  const bytes = 40 + board.outputBytes.length - outputBefore;
  const byteNanos = 1e9 * (10 / 115_200); // 8N1
  const elapsed = board.nanos - start;
  assert.ok(
    elapsed >= bytes * byteNanos * 0.99,
    `reply after ${elapsed} ns (${bytes} bytes both ways)`,
  );
  assert.ok(
    elapsed < bytes * byteNanos + 1e6,
    `reply after ${elapsed} ns (${bytes} bytes both ways)`,
  );
});

test('runs are deterministic', () => {
  const script = () => {
    const board = bootedBoard(bootrom);
    const replies = ['help', 'pose 1 2 3', 'xyzzy'].map((line) => board.request(line).reply);
    board.runMs(45);
    return {
      replies,
      nanos: board.nanos,
      cycles: board.cycles,
      output: board.output,
      servos: board.servos(),
    };
  };
  assert.deepEqual(script(), script());
});

test('the watchdog runs: a main loop that stops feeding it fails the run', () => {
  const board = bootedBoard(bootrom);
  board.runMs(1000); // an idle second: fed every frame, no expiry
  // Mask every interrupt in the emulated NVIC: the main loop sleeps in WFI for good.
  board.mcu.core.enabledInterrupts = 0;
  assert.throws(() => board.runMs(2000), /watchdog expired/);
});
