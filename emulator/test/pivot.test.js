// The pivot (`pivot_x_mm`, `pivot_y_mm`, `pivot_z_mm`, docs/settings.md "The pivot") through the
// real firmware binary: the pins of poses about it against the independent f64 reference
// (`host-tests`' chain of frames and numeric rod closures, not kinematics-core), the chip's
// fixed-point IK against the host core with the same pivot to the 0.01 us `status` shows,
// `status`' forward kinematics in the convention of the pose commanded, and a stream's
// rotations about it.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { binaryFrame } from '../src/bench/firmware-bench.js';
import {
  assertClose,
  assertPins,
  bootWith,
  defaultSettings,
  ok,
  poseIn,
  quantisedUs,
  refused,
  runFrames,
  status,
} from '../src/test-support/e2e-support.js';
import { HostReference } from '../src/test-support/host-reference.js';

let reference;
before(() => {
  reference = new HostReference();
});

const PIVOT = { pivot_x_mm: 10, pivot_y_mm: -20, pivot_z_mm: 100 };

/**
 * The default settings with a pivot (`PIVOT` unless given), as the reference takes them.
 * @param {Record<string, number>} [pivot]
 */
function withPivot(pivot = PIVOT) {
  return { ...defaultSettings(), pivot };
}

/**
 * A board with the speed limits off (poses jump) and a pivot (`PIVOT` unless given) set.
 * @param {Record<string, number>} [pivot]
 */
function pivotBoard(pivot = PIVOT) {
  return bootWith({ speed_mm_s: 'off', speed_deg_s: 'off', ...pivot });
}

/**
 * The f64 reference's pulses for a pose about `settings`' pivot.
 * @param {number[]} pose
 * @param {any} [settings]
 */
function f64Pulses(pose, settings = withPivot()) {
  const [answer] = reference.f64(settings, [pose]);
  assert.ok(answer.ok, `the f64 reference cannot reach ${pose}: ${JSON.stringify(answer)}`);
  return answer.pulse_us;
}

const POSES = [
  [0, 0, 0, 0, 5, 0],
  [0, 0, 0, 4, 0, 0],
  [0, 0, 0, 0, 0, 8],
  [2, -3, 1, 2, -3, 6],
];

test('a pose turns the platform about the pivot: the pins are the f64 reference, the chip the host core', () => {
  const board = pivotBoard();
  // Home does not depend on the pivot.
  runFrames(board, 2);
  assertPins(board, [1500, 1500, 1500, 1500, 1500, 1500].map(quantisedUs), 'home');
  const core = reference.solve(withPivot(), POSES);
  for (const [k, pose] of POSES.entries()) {
    ok(board, `pose ${pose.join(' ')}`);
    runFrames(board, 2);
    const want = f64Pulses(pose);
    assertPins(board, want, `pose ${pose} about the pivot`);
    // The pose about the platform's centre is another: at least one servo far from it.
    const centre = f64Pulses(pose, defaultSettings());
    assert.ok(
      want.some((w, i) => Math.abs(w - centre[i]) > 5),
      `${pose}: the pivot changes nothing?`,
    );
    // The chip's fixed-point IK computes what the host core does with the same pivot (the
    // same integer path, bit for bit): to the 0.01 us `status` prints, the same digits.
    const s = status(board);
    assert.ok(core[k].ok, JSON.stringify(core[k]));
    assert.deepEqual(
      s.pulse_us.map((w) => w.toFixed(2)),
      core[k].pulse_us.map((w) => w.toFixed(2)),
      `pose ${pose}: status vs the host core`,
    );
    // `status` reports the pose as commanded.
    assert.deepEqual(s.pose, pose);
  }
});

test("status' forward kinematics answers about the pivot, in the convention of the pose commanded", () => {
  const board = pivotBoard();
  const pose = [1, 2, 3, 3, -4, 5];
  ok(board, `pose ${pose.join(' ')}`);
  runFrames(board, 2);
  const held = status(board).pulse_us;
  // Servo 1 driven to the pulse it holds: nothing moves, the pose of the pulses is found by
  // the forward kinematics.
  ok(board, `servo 1 ${held[0].toFixed(2)}`);
  const lines = ok(board, 'status');
  const line = lines.find((text) => text.startsWith('pulse_pose: '));
  assert.ok(line, JSON.stringify(lines));
  assertClose(poseIn(line), pose, 0.01, 'pulse_pose vs the pose commanded');
  // The IK about the pivot (the f64 reference's) at the pose found gives the pulses held.
  assertClose(f64Pulses(poseIn(line)), held, 0.05, 'the f64 IK of pulse_pose');
});

test("a stream's roll, pitch and yaw turn about the pivot", () => {
  const board = pivotBoard();
  // Default full scales 25 25 15 mm, 15 15 20 degrees (docs/streaming.md); counts for a pose
  // that carries exactly 3.75 degrees of roll and -2.5 of pitch and 5 of yaw.
  const counts = [32768, 32768, 32768, 32768 + 8192, 32768 - 5461, 32768 + 8192];
  const carried = [0, 0, 0, 3.75, (-5461 / 32768) * 15, 5];
  board.sendBytes(binaryFrame(counts));
  runFrames(board, 3);
  assertPins(board, f64Pulses(carried), 'stream frame about the pivot');
  const s = status(board);
  assert.equal(s.state, 'streaming (pass-through)');
  assertClose(s.pose, carried, 0.0005, 'the stream pose');
});

test('a pivot change keeps the pose, is refused while moving and when the held pose would be out of reach', () => {
  const board = bootWith({ speed_deg_s: 10 });
  ok(board, 'pose 0 0 0 0 6 0');
  refused(board, 'set pivot_z_mm 50', 'busy');
  board.runMs(1000); // 6 degrees at 10 deg/s, and then some
  assert.equal(status(board).state, 'idle');
  ok(board, 'set pivot_z_mm 50');
  runFrames(board, 2);
  assertPins(board, f64Pulses([0, 0, 0, 0, 6, 0], withPivot({ pivot_z_mm: 50 })));
  assert.deepEqual(status(board).pose, [0, 0, 0, 0, 6, 0]);
  refused(board, 'set pivot_z_mm 1000', 'pose-conflict');
  refused(board, 'set pivot_x_mm 1000.5', 'out-of-range');
  runFrames(board, 2);
  assertPins(board, f64Pulses([0, 0, 0, 0, 6, 0], withPivot({ pivot_z_mm: 50 })), 'unchanged');
  assert.ok(ok(board, 'config').includes('pivot_z_mm: 50.000'));
});
