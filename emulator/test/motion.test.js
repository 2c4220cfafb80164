// Smooth motion measured on the pins of the real firmware: straight lines in pose space at the
// configured speeds, one IK per servo frame, no glitches, and paths that leave the workspace
// refused before anything moves. Frame counts are computed here from the documented rule
// (docs/commands.md "Motion"); per-frame pulses come from the host core (src/test-support/host-reference.js).

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import {
  assertConstant,
  assertMoveOnPins,
  assertPins,
  assertWithinLimits,
  bootQuiet,
  capture,
  defaultSettings,
  firmwareBootrom,
  framePeriodNanos,
  framePoses,
  heaveReader,
  heaveTrace,
  HOME,
  lerpPose,
  ok,
  periodsUs,
  plannedFrames,
  poseText,
  refused,
  runFrames,
  status,
  widthsNanos,
} from '../src/test-support/e2e-support.js';
import { HostReference } from '../src/test-support/host-reference.js';

let bootrom;
let reference;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
});

/** The host core's pulses for each frame of the straight move from -> to. */
function expectedFrames(from, to, settings) {
  const n = plannedFrames(from, to, settings);
  const answers = reference.solve(settings, framePoses(from, to, n));
  return answers.map((answer, k) => {
    assert.ok(
      answer.ok,
      `reference refuses frame ${k + 1} of ${from} -> ${to}: ${JSON.stringify(answer)}`,
    );
    return answer.pulse_us;
  });
}

/** Sends `line` (a move from -> to) and checks every frame of it on the pins. */
function checkMove(board, line, from, to, settings) {
  const frames = expectedFrames(from, to, settings);
  const start = widthsNanos(board);
  const pulses = capture(board, () => ok(board, line), frames.length + 4, settings.frame_hz);
  assertMoveOnPins(pulses, start, frames, {
    periodNanos: framePeriodNanos(settings.frame_hz),
    servos: settings.servos,
  });
  return frames;
}

test('a move at the default linear speed: distance / 50 mm/s in whole frames, every frame the host core pose', () => {
  const settings = defaultSettings();
  const board = bootQuiet(bootrom);
  const target = [12, -6, 4, 0, 0, 0]; // 14 mm: 0.28 s = 14 frames at 50 Hz
  assert.equal(plannedFrames(HOME, target, settings), 14);
  checkMove(board, `pose ${poseText(target)}`, HOME, target, settings);
  // And back, from a non-home start.
  checkMove(board, 'home', target, HOME, settings);
});

test('a rotation is paced by the angular limit (Euclidean in roll, pitch, yaw at 60 deg/s)', () => {
  const settings = defaultSettings();
  const board = bootQuiet(bootrom);
  const target = [2, 0, 0, 6, -8, 18]; // 20.59 deg: 0.343 s -> 18 frames (2 mm alone: 2)
  assert.equal(plannedFrames(HOME, target, settings), 18);
  checkMove(board, `pose ${poseText(target)}`, HOME, target, settings);
  // move/nudge follow the same rule, from the current pose.
  const nudged = [2, 0, 0, 6, -8, 8];
  checkMove(board, 'nudge yaw=-10', target, nudged, settings);
});

test('speed settings change the pace; off/0 for both makes a move a one-frame jump', () => {
  const settings = defaultSettings();
  const board = bootQuiet(bootrom);
  ok(board, 'set speed_mm_s 100');
  settings.speed_mm_s = 100;
  const a = [12, -6, 4, 0, 0, 0];
  assert.equal(plannedFrames(HOME, a, settings), 7);
  checkMove(board, `pose ${poseText(a)}`, HOME, a, settings);

  ok(board, 'set speed_mm_s off');
  ok(board, 'set speed_deg_s 0');
  settings.speed_mm_s = 0;
  settings.speed_deg_s = 0;
  const b = [-8, 5, -3, 4, -3, 10];
  assert.equal(plannedFrames(a, b, settings), 1);
  checkMove(board, `pose ${poseText(b)}`, a, b, settings);

  // Only the angular limit set: a pure translation jumps, a rotation is paced.
  ok(board, 'set speed_deg_s 30');
  settings.speed_deg_s = 30;
  const c = [4, 4, 4, 4, -3, 10];
  assert.equal(plannedFrames(b, c, settings), 1);
  checkMove(board, `pose ${poseText(c)}`, b, c, settings);
  const d = [4, 4, 4, 4, -3, 1]; // 9 deg at 30 deg/s: 0.3 s = 15 frames
  assert.equal(plannedFrames(c, d, settings), 15);
  checkMove(board, `pose ${poseText(d)}`, c, d, settings);
});

test('at 200 Hz a move takes its duration in 5 ms frames, IK on every frame', () => {
  const settings = defaultSettings();
  const board = bootQuiet(bootrom);
  ok(board, 'set frame_hz 200');
  settings.frame_hz = 200;
  runFrames(board, 3); // the old 20 ms frame ends, then 5 ms frames
  assert.deepEqual(periodsUs(board), Array(6).fill(5000));
  const target = [-6, 3, 2, 0, 0, 0]; // 7 mm: 0.14 s = 28 frames at 200 Hz
  assert.equal(plannedFrames(HOME, target, settings), 28);
  checkMove(board, `pose ${poseText(target)}`, HOME, target, settings);
});

/**
 * Two reachable poses whose straight line is not (docs/error-codes.md's example), verified with
 * the host core: both ends solve, some pose between them does not. Returns the first failing
 * fraction of a dense sampling and the core's error there.
 */
function blockedPair(settings) {
  const from = [-28, 19, -2.5, 11, 2, -20];
  const to = [30, -12, -13.5, 5, -13, 28];
  const samples = 2000;
  const poses = Array.from({ length: samples + 1 }, (_, i) => lerpPose(from, to, i / samples));
  const answers = reference.solve(settings, poses);
  assert.ok(answers[0].ok && answers[samples].ok, 'both ends of the pair are reachable');
  const firstBad = answers.findIndex((answer) => !answer.ok);
  assert.ok(firstBad > 0, 'the straight line between them is blocked somewhere');
  return { from, to, fraction: firstBad / samples, cause: answers[firstBad] };
}

test('a target whose straight path leaves the workspace is refused before anything moves', () => {
  const settings = defaultSettings();
  const { from, to, fraction, cause } = blockedPair(settings);
  const board = bootQuiet(bootrom);
  checkMove(board, `pose ${poseText(from)}`, HOME, from, settings);
  // The target alone is fine (check looks at the path from the current pose too).
  const held = widthsNanos(board);
  let reply;
  const pulses = capture(
    board,
    () => {
      reply = refused(board, `pose ${poseText(to)}`, 'path-blocked');
    },
    25,
  );
  assertConstant(pulses, held, 'after the refused move');
  const m = reply.match(/blocked (\d+\.\d)% of the way: (.*); nothing moved$/);
  assert.ok(m, reply);
  assert.ok(
    Math.abs(Number(m[1]) / 100 - fraction) < 0.03,
    `${m[1]}% vs the core's first failure at ${(fraction * 100).toFixed(1)}%`,
  );
  if (cause.code === 'servo-limit') {
    assert.match(
      m[2],
      new RegExp(
        `^servo ${cause.servo} would need \\d+\\.\\d{2} us, outside its limits 1100\\.00\\.\\.1900\\.00 us$`,
      ),
    );
  } else {
    assert.equal(cause.code, 'unreachable');
    assert.match(m[2], new RegExp(`^leg ${cause.leg} cannot reach`));
  }
  const s = status(board);
  assert.equal(s.state, 'idle');
  assert.deepEqual(s.target, s.pose);
  assert.deepEqual(s.pose, from);
  refused(board, `check ${poseText(to)}`, 'path-blocked');
  // From home the same target is reachable in a straight line: check accepts it there.
  checkMove(board, 'home', from, HOME, settings);
  assert.equal(ok(board, `check ${poseText(to)}`).length, 3);
});

test('a new target while moving starts a new straight line from where the platform is', () => {
  const settings = defaultSettings();
  const board = bootQuiet(bootrom);
  ok(board, 'set speed_mm_s 10');
  settings.speed_mm_s = 10;
  ok(board, 'pose 0 0 10 0 0 0');
  runFrames(board, 20);
  const redirect = [8, 0, 5, 0, 0, 0];
  ok(board, `pose ${poseText(redirect)}`);
  const s1 = status(board);
  assert.deepEqual(s1.target, redirect);
  runFrames(board, 5);
  const s2 = status(board);
  // s1, s2 and the target lie on one straight line, which starts on the first line
  // (x = y = 0, no rotation, 0 < z < 10): extend it back to x = 0.
  const t = s2.pose[0] / redirect[0]; // fraction of the second line done at s2, from x
  const z0 = (s2.pose[2] - t * redirect[2]) / (1 - t);
  assert.ok(t > 0 && t < 1 && z0 > 0 && z0 < 10, `redirected from z = ${z0}, t = ${t}`);
  const u = s1.pose[0] / redirect[0];
  assert.ok(
    Math.abs(s1.pose[2] - (z0 + u * (redirect[2] - z0))) < 0.003,
    `${s1.pose} on the line from z0 = ${z0}`,
  );
  for (const p of [s1.pose, s2.pose]) {
    assert.deepEqual([p[1], p[3], p[4], p[5]], [0, 0, 0, 0]);
  }
  const s = s2;
  // It arrives within the time the new line needs from where it was redirected.
  runFrames(board, plannedFrames(s.pose, redirect, settings) + 3);
  assert.deepEqual(status(board).pose, redirect);
  assertPins(board, reference.solve(settings, [redirect])[0].pulse_us);
});

test('with accel_mm_s2 a move ramps its speed up and down along the line, within both limits', () => {
  const board = bootQuiet(bootrom);
  ok(board, 'set speed_mm_s 40');
  ok(board, 'set accel_mm_s2 200');
  const read = heaveReader(reference, -0.5, 8.5);
  const pulses = capture(board, () => ok(board, 'pose 0 0 8 0 0 0'), 45);
  const zs = heaveTrace(pulses, read);
  assertWithinLimits(zs, { hz: 50, speed: 40, accel: 200, top: 8, label: 'ramped move' });
  // docs/commands.md: 8 mm at 40 mm/s with 200 mm/s2 ramps takes 8/40 + 40/200 = 0.4 s
  // (20 frames); the first steps are small (speeding up), and it lands on the target.
  const started = zs.findIndex((z) => z > 0.01);
  const arrived = zs.findIndex((z) => Math.abs(z - 8) < 0.02);
  assert.ok(arrived - started >= 19 && arrived - started <= 21, `${arrived - started} frames`);
  assert.ok(zs[started] < 0.2, `first step ${zs[started]} mm: no ramp`);
  assertPins(board, reference.solve(defaultSettings(), [[0, 0, 8, 0, 0, 0]])[0].pulse_us);
});
