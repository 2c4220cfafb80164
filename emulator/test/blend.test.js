// A new target while the platform moves blends in (docs/commands.md, "A new target while
// moving"), measured on the pins of the real firmware: with acceleration limits set, targets
// sent every 50 ms (a jog of `nudge`s, a turn back) and `pose` lines at 60 Hz never make the
// platform stop dead or hold still mid-way, and no frame's change of velocity exceeds the limit.
// Poses are read back from the pulses with the host core's IK (heaveReader: pure heave, so
// each frame's pulses give one z); speeds and accelerations are differences of those readings,
// with the tolerance of assertWithinLimits (one PWM count is about 1/40 mm of heave: 0.012 mm
// of reading noise, 4 x 0.012 mm / (20 ms)^2 = 120 mm/s2 on a second difference), well below
// what a stop dead gives (40 mm/s to 0 in a frame: 2,000 mm/s2).

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { FINAL_REPLY } from '../src/chip/board.js';
import {
  assertPins,
  assertWithinLimits,
  bootQuiet,
  defaultSettings,
  firmwareBootrom,
  heaveReader,
  heaveTrace,
  COUNT_US,
  ok,
} from '../src/test-support/e2e-support.js';
import { binaryFrame } from '../src/bench/firmware-bench.js';
import { HostReference } from '../src/test-support/host-reference.js';

const HZ = 50;

let bootrom;
let reference;
let read;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
  read = heaveReader(reference, -6.5, 12);
});

/**
 * Sends each line at its time (ms from now, in order) without waiting for replies, as a
 * program streaming targets does, then runs `afterMs`; records the pins all along. Returns
 * the z trace (one reading per frame) and the final replies.
 */
function sendTimed(board, timed, afterMs) {
  const from = board.lines.length;
  const recording = board.recordPulses();
  let now = 0;
  try {
    for (const { atMs, line, bytes } of timed) {
      board.runMs(atMs - now);
      now = atMs;
      board.sendBytes(bytes ?? `${line}\n`);
    }
    board.runMs(afterMs);
  } finally {
    recording.stop();
  }
  const pulses = recording.servos.map((servo) =>
    servo.map(({ widthNanos }) => ({ widthNanos: Math.round(widthNanos) })),
  );
  const replies = board.lines.slice(from).filter((l) => FINAL_REPLY.test(l));
  board.lineCursor = board.lines.length;
  return { zs: heaveTrace(pulses, read), replies, widths: framesUs(pulses) };
}

/** The six widths of each frame period, us (the pins pulse in step). */
function framesUs(pulses) {
  const n = Math.min(...pulses.map((servo) => servo.length));
  return Array.from({ length: n }, (_, j) => pulses.map((servo) => servo[j].widthNanos / 1000));
}

/**
 * Never held still mid-way: from the first step to arrival, the pins never stay the same for
 * three frames in a row (a turn back passes through rest, which can show as two equal frames
 * at most: 200 mm/s2 moves 0.16 mm, six PWM counts, in two frames from rest).
 */
function assertNeverHeld(zs, label) {
  const first = zs.findIndex((z) => Math.abs(z - zs[0]) > 0.02);
  const last = zs.length - 1 - [...zs].reverse().findIndex((z) => Math.abs(z - zs.at(-1)) > 0.02);
  assert.ok(first > 0 && last > first, `${label}: it moved`);
  for (let k = first; k + 2 <= last; k += 1) {
    const still = Math.abs(zs[k + 1] - zs[k]) < 1e-6 && Math.abs(zs[k + 2] - zs[k + 1]) < 1e-6;
    assert.ok(!still, `${label}: held still at frames ${k}..${k + 2}, z ${zs[k].toFixed(3)}`);
  }
}

test('a jog of nudges every 50 ms and a turn back: every frame within 40 mm/s and 200 mm/s2, never held', () => {
  const board = bootQuiet(bootrom);
  ok(board, 'set speed_mm_s 40');
  ok(board, 'set accel_mm_s2 200');
  const timed = [];
  // Up by 1.5 mm every 50 ms (30 mm/s of targets) to z = 10.5, then back down to -4, all 50
  // ms apart.
  for (let i = 0; i < 7; i += 1) {
    timed.push({ atMs: 50 * i, line: 'nudge z=1.5' });
  }
  timed.push({ atMs: 350, line: 'pose 0 0 -4 0 0 0' });
  timed.push({ atMs: 400, line: 'nudge z=1' });
  const { zs, replies } = sendTimed(board, timed, 1500);
  assert.deepEqual(
    replies,
    timed.map(() => 'ok'),
  );
  assertWithinLimits(zs, { hz: HZ, speed: 40, accel: 200, top: 10.5, label: 'jog' });
  assertNeverHeld(zs, 'jog');
  // It went up past 6 mm at speed, faster than stopping at each target allows (from rest, a
  // 1.5 mm move at 200 mm/s2 peaks at sqrt(200 x 1.5) = 17 mm/s), then down to -3.
  assert.ok(Math.max(...zs) > 6, `top ${Math.max(...zs)}`);
  const v = zs.slice(1).map((z, k) => (z - zs[k]) * HZ);
  assert.ok(Math.max(...v) > 20, `fastest up ${Math.max(...v)} mm/s`);
  assertPins(board, reference.solve(defaultSettings(), [[0, 0, -3, 0, 0, 0]])[0].pulse_us);
});

test('pose lines at 60 Hz along a heave wave: within the limits, never held, each line ok', () => {
  const board = bootQuiet(bootrom);
  ok(board, 'set speed_mm_s 40');
  ok(board, 'set accel_mm_s2 200');
  // z = 6 sin(2 pi 0.6 t): at most 22.6 mm/s and 85 mm/s2, within the limits; 2.5 s.
  const timed = Array.from({ length: 150 }, (_, i) => {
    const t = i / 60;
    const z = 6 * Math.sin(2 * Math.PI * 0.6 * t);
    return { atMs: (1000 * i) / 60, line: `pose 0 0 ${z.toFixed(3)} 0 0 0` };
  });
  const { zs, replies } = sendTimed(board, timed, 1000);
  assert.deepEqual(
    replies,
    timed.map(() => 'ok'),
  );
  assertWithinLimits(zs, { hz: HZ, speed: 40, accel: 200, top: 6, label: '60 Hz wave' });
  assertNeverHeld(zs, '60 Hz wave');
  // It follows the wave (both crests reached within a millimetre).
  assert.ok(Math.max(...zs) > 5 && Math.min(...zs) < -5, `${Math.min(...zs)}..${Math.max(...zs)}`);
});

test("without an acceleration limit a retarget is today's: a new line from rest (speed steps at once)", () => {
  const board = bootQuiet(bootrom);
  ok(board, 'set speed_mm_s 40');
  const { zs, replies } = sendTimed(
    board,
    [
      { atMs: 0, line: 'pose 0 0 12 0 0 0' },
      { atMs: 150, line: 'pose 0 0 -4 0 0 0' },
    ],
    1000,
  );
  assert.deepEqual(replies, ['ok', 'ok']);
  // At 40 mm/s up, then 40 mm/s down within a frame or two: 4,000 mm/s2, no ramp.
  const v = zs.slice(1).map((z, k) => (z - zs[k]) * HZ);
  const flip = v.findIndex((s, k) => k > 0 && v[k - 1] > 30 && s < 0);
  assert.ok(
    flip > 0 && v.slice(flip, flip + 2).some((s) => s < -30),
    `${v.map((s) => s.toFixed(0))}`,
  );
});

// With the servos' rated speeds set as well (docs/commands.md, the blend "With servo speed
// ratings"): the same retargets blend in, and no arm turns by more than its rating in any
// frame, read from the pins (eq. 13, 14: an arm turns by |dW| / r for a pulse change dW at the
// servo rate r, the default 1600 / pi us/rad), within two PWM counts.
const RATE_US_RAD = 1600 / Math.PI;

/**
 * Asserts no arm turns by more than its rating (s per 60 degrees) in a frame; returns the
 * largest share of it seen.
 */
function assertWithinRatings(widths, rating, label) {
  const maxTurn = Math.PI / 3 / rating / HZ;
  let most = 0;
  for (let j = 1; j < widths.length; j += 1) {
    for (let i = 0; i < 6; i += 1) {
      const turn = Math.abs(widths[j][i] - widths[j - 1][i]) / RATE_US_RAD;
      assert.ok(
        turn <= maxTurn + (2 * COUNT_US) / RATE_US_RAD,
        `${label}: frame ${j}, servo ${i + 1} turns ${turn} rad, rated ${maxTurn} rad a frame`,
      );
      most = Math.max(most, turn / maxTurn);
    }
  }
  return most;
}

/** A board with fast limits that the ratings (s per 60 degrees), not the speed limit, slow. */
function ratedBoard(rating) {
  const board = bootQuiet(bootrom);
  ok(board, 'set speed_mm_s 80');
  ok(board, 'set accel_mm_s2 400');
  ok(board, `set servos.speed_s_60deg ${rating}`);
  return board;
}

test('with ratings, nudges every 50 ms and a turn back blend in within the limits and the ratings, never held', () => {
  const board = ratedBoard(0.25);
  const timed = [];
  for (let i = 0; i < 6; i += 1) {
    timed.push({ atMs: 50 * i, line: 'nudge z=2' });
  }
  timed.push({ atMs: 300, line: 'pose 0 0 -5 0 0 0' });
  timed.push({ atMs: 350, line: 'nudge z=1' });
  const { zs, replies, widths } = sendTimed(board, timed, 1500);
  assert.deepEqual(
    replies,
    timed.map(() => 'ok'),
  );
  assertWithinLimits(zs, { hz: HZ, speed: 80, accel: 400, top: 12, label: 'rated jog' });
  assertNeverHeld(zs, 'rated jog');
  const most = assertWithinRatings(widths, 0.25, 'rated jog');
  assert.ok(most > 0.8, `the ratings set the pace (fastest arm at ${most} of its)`);
  assertPins(board, reference.solve(defaultSettings(), [[0, 0, -4, 0, 0, 0]])[0].pulse_us);
});

test('with ratings, pose lines at 60 Hz along a heave wave: within the limits and the ratings, never held', () => {
  // Rated 0.6 s per 60 degrees: the arms follow about 40 mm/s of heave.
  const board = ratedBoard(0.6);
  // z = 6 sin(2 pi 1.2 t): up to 45 mm/s and 340 mm/s2, within the limits, faster than the
  // ratings let the arms follow at the crossings; 2 s.
  const timed = Array.from({ length: 120 }, (_, i) => {
    const t = i / 60;
    const z = 6 * Math.sin(2 * Math.PI * 1.2 * t);
    return { atMs: (1000 * i) / 60, line: `pose 0 0 ${z.toFixed(3)} 0 0 0` };
  });
  const { zs, replies, widths } = sendTimed(board, timed, 1000);
  assert.deepEqual(
    replies,
    timed.map(() => 'ok'),
  );
  assertWithinLimits(zs, { hz: HZ, speed: 80, accel: 400, top: 6, label: 'rated wave' });
  assertNeverHeld(zs, 'rated wave');
  const most = assertWithinRatings(widths, 0.6, 'rated wave');
  assert.ok(most > 0.8, `the ratings set the pace (fastest arm at ${most} of its)`);
});

test('with ratings, a pose line while a stream is tracked takes over from its motion: within the limits and the ratings, never held', () => {
  const board = ratedBoard(0.25);
  // A heave stream at 60 Hz (binary frames, z full scale 15 mm) climbing at 15 mm/s for
  // 0.6 s, then, with the tracker moving, `pose 0 0 -5 0 0 0`, and the stream stops.
  const count = (z) => Math.round(32768 + (z / 15) * 32768);
  /** @type {{ atMs: number, line?: string, bytes?: Buffer }[]} */
  const timed = Array.from({ length: 36 }, (_, i) => {
    const z = 15 * (i / 60);
    return {
      atMs: (1000 * i) / 60,
      bytes: binaryFrame([32768, 32768, count(z), 32768, 32768, 32768]),
    };
  });
  timed.push({ atMs: 600, line: 'pose 0 0 -5 0 0 0' });
  const { zs, replies, widths } = sendTimed(board, timed, 1500);
  assert.deepEqual(replies, ['ok']);
  assertWithinLimits(zs, { hz: HZ, speed: 80, accel: 400, top: 9.5, label: 'stream, then pose' });
  assertNeverHeld(zs, 'stream, then pose');
  const most = assertWithinRatings(widths, 0.25, 'stream, then pose');
  assert.ok(most > 0.8, `the ratings set the pace (fastest arm at ${most} of its)`);
  assertPins(board, reference.solve(defaultSettings(), [[0, 0, -5, 0, 0, 0]])[0].pulse_us);
});
