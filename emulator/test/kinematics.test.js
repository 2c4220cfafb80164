// `servo`, `limits` and the payload's holding torques through the real firmware binary: the
// pins, the pose the pulses correspond to, the reach of each axis and the torques, compared
// with the host build of kinematics-core (src/test-support/host-reference.js: its forward kinematics, IK,
// workspace search and statics), formats and rules from docs/. Refusals (torque-limit,
// no-pose, servo-limit, ...) are in errors.test.js.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import {
  assertClose,
  assertMoveOnPins,
  assertPins,
  bootQuiet,
  capture,
  COUNT_US,
  defaultSettings,
  firmwareBootrom,
  framePeriodNanos,
  framePoses,
  HOME,
  ok,
  plannedFrames,
  poseIn,
  poseText,
  quantisedUs,
  runFrames,
  status,
  widthsNanos,
} from '../src/test-support/e2e-support.js';
import { binaryFrame } from '../src/bench/firmware-bench.js';
import { HostReference } from '../src/test-support/host-reference.js';

// The firmware's numbers (boot ROM floats) vs the host core's (libm), as printed.
const POSE_TOLERANCE = 0.005; // mm and degrees: the forward kinematics stops within 1e-3 mm
const TORQUE_TOLERANCE_KGCM = 0.002;

let bootrom;
let reference;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
});

function field(lines, key) {
  const line = lines.find((text) => text.startsWith(`${key}: `));
  assert.ok(line, `no '${key}:' in ${JSON.stringify(lines)}`);
  return line.slice(key.length + 2);
}

function solve(pose, settings = defaultSettings()) {
  const [answer] = reference.solve(settings, [pose]);
  assert.ok(answer.ok, `host core refuses ${pose}: ${JSON.stringify(answer)}`);
  return answer;
}

/**
 * The default settings with a payload and (optionally) a rating on every servo.
 * @param {{ g?: number, com?: number[], rating?: number | 'off' }} [options]
 */
function withPayload({ g = 2000, com = [0, 0, 30], rating = 'off' } = {}) {
  const settings = defaultSettings();
  settings.payload = {
    payload_g: g,
    payload_com_x_mm: com[0],
    payload_com_y_mm: com[1],
    payload_com_z_mm: com[2],
  };
  for (const servo of settings.servos) {
    servo.torque_kgcm = rating;
  }
  return settings;
}

/**
 * @param {import('../src/chip/board.js').EmulatedBoard} board
 * @param {{ g?: number, com?: number[], rating?: number | 'off' }} [options]
 */
function setPayload(board, { g = 2000, com = [0, 0, 30], rating = 'off' } = {}) {
  ok(board, `set payload_g ${g}`);
  ['x', 'y', 'z'].forEach((axis, i) => ok(board, `set payload_com_${axis}_mm ${com[i]}`));
  ok(board, `set servos.torque_kgcm ${rating}`);
}

test('servo drives one pin to its pulse, the others hold; status shows the pose of the six pulses', () => {
  const board = bootQuiet(bootrom);
  const before = widthsNanos(board);
  const pulses = capture(board, () => ok(board, 'servo 3 1620'), 3);
  // Servo 3 goes straight to 1620 us (to the count); the others never change.
  pulses.forEach((servo, i) => {
    const last = servo[servo.length - 1].widthNanos;
    if (i === 2) {
      assert.equal(last / 1000, quantisedUs(1620));
    } else {
      assert.ok(
        servo.every((p) => p.widthNanos === before[i]),
        `servo ${i + 1} moved`,
      );
    }
  });
  const lines = ok(board, 'status');
  assert.equal(field(lines, 'state'), 'direct (pulses set with servo)');
  assert.equal(field(lines, 'pulse_us'), '1500.00 1500.00 1620.00 1500.00 1500.00 1500.00');
  assert.equal(field(lines, 'servo_power'), 'on');
  const shown = poseIn(field(lines, 'pulse_pose'));
  const core = reference.forwardKinematics(
    defaultSettings(),
    [1500, 1500, 1620, 1500, 1500, 1500],
    HOME,
  );
  assert.ok(core.ok, JSON.stringify(core));
  assertClose(shown, core.pose, POSE_TOLERANCE, 'pulse_pose vs the host core');
  // That pose is where moves start from: pose and target show it.
  assert.deepEqual(poseIn(field(lines, 'pose')), shown);
  assert.deepEqual(poseIn(field(lines, 'target')), shown);
  // The host core's IK at that pose gives the pulses back.
  assertClose(solve(shown).pulse_us, [1500, 1500, 1620, 1500, 1500, 1500], 0.1, 'IK of pulse_pose');
});

test('after servo, a move runs from the pose of the pulses, frame by frame as the host core says', () => {
  const settings = defaultSettings();
  const board = bootQuiet(bootrom);
  ok(board, 'servo 1 1560');
  ok(board, 'servo 4 1450');
  runFrames(board, 2);
  const from = status(board).pose;
  const core = reference.forwardKinematics(settings, [1560, 1500, 1500, 1450, 1500, 1500], HOME);
  assertClose(from, core.pose, POSE_TOLERANCE, 'the pose of the pulses');
  const to = [2, -1, 3, 1, 0, -2];
  const n = plannedFrames(from, to, settings);
  const framesUs = reference.solve(settings, framePoses(from, to, n)).map((a) => a.pulse_us);
  const start = widthsNanos(board);
  const pulses = capture(board, () => ok(board, `pose ${poseText(to)}`), n + 4);
  // No jump: the first frame is a step along the line from the pose found (the printed pose
  // is within 0.0005 mm of the firmware's, a small fraction of a count).
  assertMoveOnPins(pulses, start, framesUs, {
    periodNanos: framePeriodNanos(50),
    servos: settings.servos,
  });
  const s = status(board);
  assert.equal(s.state, 'idle');
  assert.ok(!s.lines.some((l) => l.startsWith('pulse_pose')), 'a move ends direct driving');
  assertPins(board, solve(to).pulse_us);
});

test('servo pulses that correspond to no pose: status says so, the pins hold them', () => {
  const board = bootQuiet(bootrom);
  ok(board, 'servo 1 1900');
  ok(board, 'servo 2 1900');
  runFrames(board, 3);
  assertPins(board, [1900, 1900, 1500, 1500, 1500, 1500]);
  const lines = ok(board, 'status');
  assert.match(
    field(lines, 'pulse_pose'),
    /^none \(the rods cannot all reach their joints: no pose found in 8 iterations\)$/,
  );
  const core = reference.forwardKinematics(
    defaultSettings(),
    [1900, 1900, 1500, 1500, 1500, 1500],
    status(board).pose,
  );
  assert.equal(core.ok, false);
});

/** `limits` parsed: [{ axis, sense, distance, extreme, stop }]. */
function limits(board) {
  const lines = ok(board, 'limits');
  assert.equal(lines.length, 12, JSON.stringify(lines));
  return lines.map((line) => {
    const m = line.match(
      /^(x|y|z|roll|pitch|yaw)([-+]): (\d+\.\d{3}) (mm|deg) to (\w+)=(-?\d+\.\d{3}) \((.*)\)$/,
    );
    assert.ok(m, `limits line: ${line}`);
    assert.equal(m[5], m[1]);
    assert.equal(m[4], ['x', 'y', 'z'].includes(m[1]) ? 'mm' : 'deg');
    return { axis: m[1], sense: m[2], distance: Number(m[3]), extreme: Number(m[6]), stop: m[7] };
  });
}

/** What stops an excursion, in the firmware's words, from the host core's answer. */
function stopText(limit) {
  switch (limit.code) {
    case 'unreachable':
      return `leg ${limit.leg} out of reach`;
    case 'servo-limit':
      return `servo ${limit.servo} at ${limit.bound} ${limit.limit_us.toFixed(2)} us`;
    case 'torque-limit':
      return `servo ${limit.servo} at its torque rating ${limit.rated_kgcm.toFixed(2)} kgf cm`;
    default:
      throw new Error(`unexpected limit ${JSON.stringify(limit)}`);
  }
}

function assertLimits(got, want, label) {
  got.forEach((line, k) => {
    const core = want[k];
    const where = `${label} ${line.axis}${line.sense}`;
    assert.equal(line.axis, core.axis, where);
    assert.equal(line.sense, core.sense, where);
    // The same search (march, then bisection to 0.01 mm / 1e-4 rad) with ROM floats: the same
    // answer but for a bisection step where a pose lies within rounding of the boundary.
    const tolerance = ['x', 'y', 'z'].includes(line.axis) ? 0.011 : 0.012;
    assert.ok(
      Math.abs(line.distance - core.distance) <= tolerance,
      `${where}: ${line.distance} vs host core ${core.distance}`,
    );
    assert.ok(
      Math.abs(line.extreme - core.extreme) <= tolerance,
      `${where}: to ${line.extreme} vs ${core.extreme}`,
    );
    assert.equal(core.limit.kind, 'blocked', where);
    assert.equal(line.stop, stopText(core.limit), where);
  });
}

test('limits: the reach of each axis both ways and what stops it, as the host core finds them', () => {
  const board = bootQuiet(bootrom);
  const pose = [2, -3, 4, 1, -2, 5];
  ok(board, `pose ${poseText(pose)}`);
  runFrames(board, plannedFrames(HOME, pose, defaultSettings()) + 3);
  const widths = widthsNanos(board);
  assertLimits(limits(board), reference.limits(defaultSettings(), pose), 'from a pose');
  // Nothing moved.
  assert.deepEqual(widthsNanos(board), widths);
  assert.deepEqual(status(board).pose, pose);
});

test('limits with a payload and ratings stop where a servo reaches its rating', () => {
  const board = bootQuiet(bootrom);
  setPayload(board, { rating: 1 });
  const got = limits(board);
  assert.ok(
    got.some((l) => l.stop.includes('torque rating')),
    JSON.stringify(got),
  );
  assertLimits(got, reference.limits(withPayload({ rating: 1 }), HOME), 'rated');
});

test('check and status show the holding torques of the payload, as the host core computes them', () => {
  const board = bootQuiet(bootrom);
  // Without a payload: no torque line.
  assert.ok(!status(board).lines.some((l) => l.startsWith('torque_kgcm')));
  const com = [15, -5, 30];
  setPayload(board, { g: 1500, com });
  const settings = withPayload({ g: 1500, com });
  const target = [10, 0, 0, 0, 0, 0];
  const lines = ok(board, `check ${poseText(target)}`);
  assert.deepEqual(
    lines.map((l) => l.split(':')[0]),
    ['arm_deg', 'pulse_us', 'torque_kgcm', 'duration_s'],
  );
  const torque = (text) => {
    assert.match(text, /^(-?\d+\.\d{3} ){5}-?\d+\.\d{3}$/);
    return text.split(' ').map(Number);
  };
  const [core] = reference.torques(settings, [target]);
  assertClose(
    torque(field(lines, 'torque_kgcm')),
    core.torque_kgcm,
    TORQUE_TOLERANCE_KGCM,
    'check',
  );
  const held = [-3, 4, 2, 1, 2, 3];
  ok(board, `pose ${poseText(held)}`);
  runFrames(board, plannedFrames(HOME, held, settings) + 3);
  const [atHeld] = reference.torques(settings, [held]);
  assertClose(
    torque(field(ok(board, 'status'), 'torque_kgcm')),
    atHeld.torque_kgcm,
    TORQUE_TOLERANCE_KGCM,
    'status',
  );
});

test('with ratings, a move whose every checkpoint is within them runs as without', () => {
  const settings = withPayload({ rating: 2 });
  const board = bootQuiet(bootrom);
  setPayload(board, { rating: 2 });
  const to = [3, 2, -4, 1, -1, 2];
  const n = plannedFrames(HOME, to, settings);
  const poses = framePoses(HOME, to, n);
  const torques = reference.torques(settings, poses);
  assert.ok(torques.every((a) => a.ok && a.torque_kgcm.every((t) => Math.abs(t) <= 2)));
  const framesUs = reference.solve(settings, poses).map((a) => a.pulse_us);
  const start = widthsNanos(board);
  const pulses = capture(board, () => ok(board, `pose ${poseText(to)}`), n + 4);
  assertMoveOnPins(pulses, start, framesUs, {
    periodNanos: framePeriodNanos(50),
    servos: settings.servos,
  });
});

test('a stream target that would overload a servo is clamped to the last pose within the ratings', () => {
  const settings = withPayload({ rating: 1 });
  const board = bootQuiet(bootrom);
  ok(board, 'set speed_mm_s off');
  ok(board, 'set speed_deg_s off');
  setPayload(board, { rating: 1 });
  // x = 10 mm (0.4 of the 25 mm full scale): reachable, but servo 1 would need 4.8 kgf cm.
  const target = [10, 0, 0, 0, 0, 0];
  assert.ok(solve(target, settings).ok);
  board.sendBytes(binaryFrame([32768 + 0.4 * 32768, 32768, 32768, 32768, 32768, 32768]));
  runFrames(board, 3);
  const s = status(board);
  assert.equal(s.stream.clamped, 1);
  const x = s.pose[0];
  assert.ok(x > 0.5 && x < 10, `clamped to x ${x}`);
  assert.deepEqual(s.pose.slice(1), [0, 0, 0, 0, 0]);
  assertPins(board, solve(s.pose, settings).pulse_us);
  const [here, beyond] = reference.torques(settings, [s.pose, [x + 10 / 64 + 0.01, 0, 0, 0, 0, 0]]);
  assert.ok(
    here.torque_kgcm.every((t) => Math.abs(t) <= 1 + TORQUE_TOLERANCE_KGCM),
    `${here.torque_kgcm}`,
  );
  assert.ok(
    beyond.torque_kgcm.some((t) => Math.abs(t) > 1),
    `x ${x} was clamped too early`,
  );
  for (const servo of board.servos()) {
    assert.ok(servo.widthUs >= 1100 - COUNT_US && servo.widthUs <= 1900 + COUNT_US);
  }
});
