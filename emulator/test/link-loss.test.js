// Link loss for streaming users, through the real firmware ELF: with `link_timeout_s` set and
// no command for that long, the platform eases back home at the configured speed. Off by
// default. Expected timings come from the settings (distance / speed), expected pulses from
// measurement (the power-on pulses are home).

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { EmulatedBoard } from '../src/chip/board.js';
import {
  bootedBoard,
  firmwareBootrom,
  FRAME_MS,
  steadyPulses,
} from '../src/test-support/e2e-support.js';

const COUNT_US = 0.32; // one PWM count

let bootrom;
before(() => {
  bootrom = firmwareBootrom();
});

function bootedAndPulsing() {
  const board = bootedBoard(bootrom);
  board.runMs(3 * FRAME_MS);
  return { board, home: steadyPulses(board) };
}

/** Samples the pins once per frame for `ms`: [{ ms, us: [6 widths] }]. */
function record(board, ms) {
  const samples = [];
  const end = board.millis + ms;
  while (board.millis < end) {
    board.runMs(FRAME_MS);
    samples.push({ ms: board.millis, us: board.pulseWidthsUs() });
  }
  return samples;
}

const same = (a, b) => a.every((w, i) => w === b[i]);

test('link loss is off by default: a silent host leaves the platform where it is', () => {
  const { board, home } = bootedAndPulsing();
  assert.equal(board.request('pose 0 0 10 0 0 0').reply, 'ok');
  board.runMs(1000);
  const held = steadyPulses(board);
  assert.ok(!same(held, home));
  board.runMs(10_000);
  assert.deepEqual(steadyPulses(board), held);
  assert.ok(!board.lines.some((l) => l.startsWith('# link lost')));
});

test('after link_timeout_s of silence the platform eases home at the configured speed', (t) => {
  const { board, home } = bootedAndPulsing();
  const TIMEOUT_S = 1;
  const SPEED_MM_S = 20;
  const DISTANCE_MM = 10;
  assert.equal(board.request(`set link_timeout_s ${TIMEOUT_S}`).reply, 'ok');
  assert.equal(board.request(`set speed_mm_s ${SPEED_MM_S}`).reply, 'ok');
  // A streaming host sends a few poses, the last one 10 mm up, then goes silent.
  for (const z of [2, 4, 6, 8]) {
    assert.equal(board.request(`pose 0 0 ${z} 0 0 0`).reply, 'ok');
    board.runMs(100);
  }
  assert.equal(board.request(`pose 0 0 ${DISTANCE_MM} 0 0 0`).reply, 'ok');
  const silentFrom = board.millis;

  const samples = record(board, 3000);
  const at = (ms) => samples.find((s) => s.ms >= silentFrom + ms).us;
  // It got there (a 10 mm move at 20 mm/s ends well before the timeout) and held.
  const up = at(900);
  assert.ok(!same(up, home));
  assert.deepEqual(at(600), up);

  // Not before the timeout.
  const moving = samples.filter((s) => !same(s.us, up) && s.ms > silentFrom + 600);
  assert.ok(moving.length > 0, 'never left after the timeout');
  // Emulated time is a float sum of instruction times: to the nanosecond (the bound is exact).
  const startedMs = Math.round((moving[0].ms - silentFrom) * 1e6) / 1e6;
  assert.ok(
    startedMs >= TIMEOUT_S * 1000 && startedMs <= TIMEOUT_S * 1000 + 3 * FRAME_MS,
    `started home ${startedMs} ms after the last command`,
  );
  assert.ok(
    board.lines.some((l) => /^# link lost\b/.test(l)),
    'no link-lost notice',
  );

  // Gradually, at the configured speed: distance / speed, to a frame or two.
  const arrived = samples.find((s) => s.ms - silentFrom > startedMs && same(s.us, home));
  assert.ok(arrived, 'never arrived home');
  const tookMs = arrived.ms - silentFrom - startedMs;
  const expectedMs = (DISTANCE_MM / SPEED_MM_S) * 1000;
  assert.ok(
    Math.abs(tookMs - expectedMs) <= 2 * FRAME_MS,
    `took ${tookMs} ms, expected ${expectedMs}`,
  );
  t.diagnostic(
    `home run started ${startedMs.toFixed(1)} ms after the last command, took ${tookMs.toFixed(1)} ms`,
  );
  const way = samples.filter(
    (s) => s.ms - silentFrom >= startedMs - FRAME_MS && s.ms <= arrived.ms,
  );
  assert.ok(way.length >= expectedMs / FRAME_MS, `${way.length} frames on the way`);
  for (let servo = 0; servo < 6; servo++) {
    const total = Math.abs(home[servo] - up[servo]);
    const steps = way.slice(1).map((s, k) => s.us[servo] - way[k].us[servo]);
    const direction = Math.sign(home[servo] - up[servo]);
    for (const step of steps) {
      // Always towards home (monotonic), and no jump: no frame covers much more than its
      // share of the way (straight line at constant speed; pulses are nearly linear in z).
      assert.ok(step * direction >= 0, `servo ${servo + 1} moved away from home: ${steps}`);
      assert.ok(
        Math.abs(step) <= (2 * total * FRAME_MS) / expectedMs + COUNT_US,
        `servo ${servo + 1} jumped ${step} us of ${total}`,
      );
    }
  }
  // Exactly at the power-on pulses, and it stays there.
  assert.deepEqual(steadyPulses(board, 10), home);

  // The host comes back: commands work again (and the link loss can be turned off).
  assert.equal(board.request('set link_timeout_s off').reply, 'ok');
  assert.equal(board.request(`pose 0 0 ${DISTANCE_MM} 0 0 0`).reply, 'ok');
  board.runMs(1000);
  assert.deepEqual(steadyPulses(board), up);
});

test('every completed line, even a refused one, restarts the link timer', () => {
  const { board, home } = bootedAndPulsing();
  assert.equal(board.request('set link_timeout_s 1').reply, 'ok');
  assert.equal(board.request('pose 0 0 10 0 0 0').reply, 'ok'); // 0.2 s at 50 mm/s
  board.runMs(600);
  const held = board.pulseWidthsUs();
  assert.ok(!same(held, home));
  board.runMs(300);
  for (const line of ['status', 'frobnicate', 'pose nan 0 0 0 0 0', 'check 0 0 5 0 0 0']) {
    board.request(line);
    board.runMs(900); // 0.9 s since this line: not yet
    assert.deepEqual(board.pulseWidthsUs(), held, `moved 0.9 s after ${line}`);
  }
  // A partial line is not a sign of life: the timer runs out while it is being typed.
  board.sendBytes('pose 0 0 ');
  board.runMs(2500);
  assert.deepEqual(steadyPulses(board), home);
});

test('link loss never comes before link_timeout_s, wherever in a frame the last line ended', () => {
  const { board } = bootedAndPulsing();
  assert.equal(board.request('set echo off').reply, 'ok');
  assert.equal(board.request('set link_timeout_s 0.1').reply, 'ok');
  // When each line's last byte reached the chip.
  const lineEnds = [];
  const uart = board.mcu.uart[0];
  const feedByte = uart.feedByte.bind(uart);
  uart.feedByte = (value) => {
    if ((value & 0xff) === 0x0a) {
      lineEnds.push(board.nanos);
    }
    feedByte(value);
  };
  let earliestMs = Infinity;
  let latestMs = 0;
  for (let phase = 0; phase < 20; phase++) {
    // Lines ending at every millisecond of the 20 ms frame; each moves off home, so that the
    // link loss has somewhere to go.
    board.runMs(phase * 1.05);
    assert.equal(board.request(`pose 0 0 ${1 + (phase % 2)} 0 0 0`).reply, 'ok');
    const lineEnd = lineEnds.at(-1);
    const notice = board.waitForLine(/^# link lost: /, { timeoutMs: 500 });
    assert.ok(notice, 'no link loss');
    const afterMs = (board.nanos - lineEnd) / 1e6;
    earliestMs = Math.min(earliestMs, afterMs);
    latestMs = Math.max(latestMs, afterMs);
    assert.ok(afterMs >= 100, `link loss ${afterMs.toFixed(3)} ms after the line (phase ${phase})`);
    board.runMs(300); // home again
  }
  // Up to one frame late (whole frames from the first one after the line's reply), plus the
  // time the line's reply and the notice's own 50 bytes take (about 5 ms at 115,200 baud).
  assert.ok(latestMs <= 100 + FRAME_MS + 10, `link loss ${latestMs} ms after the line`);
});

test('lines on UART0 or USB keep the link alive; silence on both is link loss', () => {
  const board = new EmulatedBoard({ bootrom, usb: true });
  board.boot();
  board.usb.waitUntilOpen();
  board.usb.waitForLine(/hexapod/);
  board.runMs(3 * FRAME_MS);
  const home = steadyPulses(board);
  assert.equal(board.usb.request('set link_timeout_s 1').reply, 'ok');
  assert.equal(board.request('pose 0 0 10 0 0 0').reply, 'ok');
  board.runMs(500);
  const held = board.pulseWidthsUs();
  assert.ok(!same(held, home));
  // Only USB speaks, then only UART0, and again: lines 0.9 s apart, never a loss.
  for (const link of [board.usb, board.uart, board.usb, board.uart]) {
    for (let i = 0; i < 2; i++) {
      assert.equal(link.request('status').reply, 'ok');
      board.runMs(900);
      assert.deepEqual(board.pulseWidthsUs(), held, 'moved while a link spoke');
    }
  }
  assert.ok(!board.lines.concat(board.usb.lines).some((l) => l.startsWith('# link lost')));
  // Then neither: home, and both links hear why.
  board.runMs(1500);
  assert.deepEqual(steadyPulses(board), home);
  assert.ok(
    board.lines.some((l) => /^# link lost: no command for 1 s/.test(l)),
    'UART0 told',
  );
  assert.ok(
    board.usb.lines.some((l) => /^# link lost: no command for 1 s/.test(l)),
    'USB told',
  );
});
