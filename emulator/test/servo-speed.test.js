// The servos' rated speeds (`servoN.speed_s_60deg`, docs/settings.md "Servo speed") through the
// real firmware: with a rating set, a fast move and a stream never turn any arm by more than
// its rating per servo frame, read from the pulses measured on the pins (eq. 13, 14: an arm
// turns by |dW| / r for a pulse change dW at the servo rate r, the settings' `rate_us_rad`),
// and they keep their straight path: every frame's six pulses are the host core's IK of a
// pose on the straight line from start to target, further along frame after frame. With the
// ratings off, the same move and stream jump in one frame, as before.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import {
  assertPins,
  bootQuiet,
  capture,
  COUNT_US,
  defaultSettings,
  firmwareBootrom,
  ok,
  quantisedUs,
  widthsNanos,
} from '../src/test-support/e2e-support.js';
import { binaryFrame } from '../src/bench/firmware-bench.js';
import { HostReference } from '../src/test-support/host-reference.js';

let bootrom;
let reference;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
});

const HZ = 50;
const RATE_US_RAD = 1600 / Math.PI; // the default servo rate (docs/settings.md)
/** Seconds per 60 degrees: servo 4 slower than the rest. */
const RATINGS = [0.5, 0.5, 0.5, 0.8, 0.5, 0.5];

/** Each servo's largest arm turn in one frame by its rating, rad. */
const MAX_TURN_RAD = RATINGS.map((t) => Math.PI / 3 / t / HZ);

/** A board with every speed limit off (unrated, a move is a jump) and the ratings set. */
function ratedBoard() {
  const board = bootQuiet(bootrom);
  ok(board, 'set speed_mm_s off');
  ok(board, 'set speed_deg_s off');
  ok(board, 'set servos.speed_s_60deg 0.5');
  ok(board, 'set servo4.speed_s_60deg 0.8');
  return board;
}

/** The six widths of each captured frame period, us (the pins pulse in step). */
function framesUs(pulses) {
  const n = Math.min(...pulses.map((servo) => servo.length));
  return Array.from({ length: n }, (_, j) => pulses.map((servo) => servo[j].widthNanos / 1000));
}

/**
 * Asserts no arm turns by more than its rating in any frame (within the two pulses' PWM
 * counts); returns the largest turn seen as a fraction of its rating.
 */
function assertWithinRatings(frames, label) {
  let most = 0;
  for (let j = 1; j < frames.length; j++) {
    for (let i = 0; i < 6; i++) {
      const turn = Math.abs(frames[j][i] - frames[j - 1][i]) / RATE_US_RAD;
      assert.ok(
        turn <= MAX_TURN_RAD[i] + (2 * COUNT_US) / RATE_US_RAD,
        `${label}: frame ${j}, servo ${i + 1} turns ${turn} rad, rated ${MAX_TURN_RAD[i]} rad a frame`,
      );
      most = Math.max(most, turn / MAX_TURN_RAD[i]);
    }
  }
  return most;
}

/**
 * Asserts every frame's pulses are the host core's IK of a pose on the straight line from
 * `from` to `to` (mm, degrees) within `toleranceUs`, the poses in order; returns the fraction
 * of the way of each frame. The line is sampled at 2,000 poses by the host core, linearly
 * between them.
 */
function assertOnLine(frames, from, to, label, toleranceUs = 0.5) {
  const n = 2000;
  const poses = Array.from({ length: n + 1 }, (_, k) =>
    from.map((v, i) => v + ((to[i] - v) * k) / n),
  );
  const grid = reference.solve(defaultSettings(), poses).map((answer, k) => {
    assert.ok(answer.ok, `host core refuses ${poses[k]}`);
    return answer.pulse_us;
  });
  let last = 0;
  return frames.map((widths, j) => {
    let best = { error: Infinity, u: 0 };
    for (let k = 0; k < n; k++) {
      for (let s = 0; s <= 10; s++) {
        const t = s / 10;
        const error = Math.max(
          ...widths.map((w, i) => Math.abs(w - (grid[k][i] + (grid[k + 1][i] - grid[k][i]) * t))),
        );
        if (error < best.error) {
          best = { error, u: (k + t) / n };
        }
      }
    }
    assert.ok(
      best.error <= toleranceUs,
      `${label}: frame ${j} (${widths}) is ${best.error} us from the line's poses`,
    );
    assert.ok(best.u >= last - 1e-3, `${label}: frame ${j} goes back (${best.u} after ${last})`);
    last = best.u;
    return best.u;
  });
}

test('a fast move turns no arm faster than its rating and keeps its straight path', () => {
  const board = ratedBoard();
  const legs = [
    [
      [0, 0, 0, 0, 0, 0],
      [20, 0, 0, 0, 0, 0],
    ],
    // Across: some arms turn out and back, so the ends alone understate the time.
    [
      [20, 0, 0, 0, 0, 0],
      [-20, 0, 0, 0, 0, 0],
    ],
    [
      [-20, 0, 0, 0, 0, 0],
      [0, 0, 0, 0, 0, 20],
    ],
  ];
  for (const [from, to] of legs) {
    const label = `${from} -> ${to}`;
    const pulses = capture(board, () => ok(board, `pose ${to.join(' ')}`), 40);
    const frames = framesUs(pulses);
    const most = assertWithinRatings(frames, label);
    assert.ok(most > 0.8, `${label}: the ratings set the pace (fastest arm at ${most} of its)`);
    const us = assertOnLine(frames, from, to, label);
    assert.ok(us.at(-1) > 1 - 1e-3, `${label}: ends on the target`);
    const moving = frames.filter((w, j) => j > 0 && w.some((v, i) => v !== frames[j - 1][i]));
    assert.ok(moving.length >= 3, `${label}: ${moving.length} frames`);
  }
  const [target] = reference.solve(defaultSettings(), [[0, 0, 0, 0, 0, 20]]);
  assertPins(board, target.pulse_us.map(quantisedUs));

  // Ratings off: the same move is a jump, one frame (faster than the ratings allowed). The
  // widths before the line count as its first frame: the jump may reach the pins in the first
  // frame recorded, when the line's work ends before that frame's pulse starts.
  ok(board, 'set servos.speed_s_60deg off');
  const held = widthsNanos(board).map((w) => w / 1000);
  const pulses = capture(board, () => ok(board, 'pose -20 0 0 0 0 0'), 3);
  const frames = [held, ...framesUs(pulses)];
  const changed = frames.filter((w, j) => j > 0 && w.some((v, i) => v !== frames[j - 1][i]));
  assert.equal(changed.length, 1, 'a jump');
  assert.throws(() => assertWithinRatings(frames, 'unrated'));
});

test('a rated stream steps within the ratings along its line; unrated, it passes through', () => {
  const board = ratedBoard();
  // Every limit off: unrated this is pass-through. A target an eighth-multiple of each full
  // scale (25 25 15 mm, 15 15 20 deg), so the frame carries it exactly.
  const target = [6.25, -3.125, 3.75, 3.75, -3.75, 7.5];
  const counts = target.map((v, i) => 32768 + (v / [25, 25, 15, 15, 15, 20][i]) * 32768);
  const home = [0, 0, 0, 0, 0, 0];
  const pulses = capture(board, () => board.sendBytes(binaryFrame(counts)), 40);
  const frames = framesUs(pulses);
  const most = assertWithinRatings(frames, 'stream');
  assert.ok(most > 0.8, `the ratings set the pace (fastest arm at ${most} of its)`);
  const us = assertOnLine(frames, home, target, 'stream');
  assert.ok(us.at(-1) > 1 - 1e-3, 'reaches the target');
  const [there] = reference.solve(defaultSettings(), [target]);
  assertPins(board, there.pulse_us.map(quantisedUs));

  // Ratings off: the next frame is passed through, in one frame.
  ok(board, 'set servos.speed_s_60deg off');
  const back = capture(board, () => board.sendBytes(binaryFrame(home.map(() => 32768))), 3);
  const jumped = framesUs(back);
  const changed = jumped.filter((w, j) => j > 0 && w.some((v, i) => v !== jumped[j - 1][i]));
  assert.ok(changed.length <= 1, `${changed.length} frames`);
  const [atHome] = reference.solve(defaultSettings(), [home]);
  assertPins(board, atHome.pulse_us.map(quantisedUs));
});
