// The firmware's ROM-backed maths on the emulated chip agree with the host: the IK benchmark
// firmware (`firmware/src/bin/bench.rs`, the firmware's own IK code) solves a few random poses
// and its pulses are compared with the host's f32 `libm` IK (the same algorithm) and with the
// independent f64 reference (`host-tests`). Accuracy only; timing is `./dev bench`'s job.

import assert from 'node:assert/strict';
import { existsSync } from 'node:fs';
import { before, test } from 'node:test';

import { BENCH_ELF, benchPoses, runIkBench, runKinematicsBench } from '../src/ik-bench.js';

/** Largest pulse difference accepted, us (the PWM resolution is 0.32 us). */
const PULSE_TOL_US = 0.01;

let result;
let kinematics;
before(() => {
  assert.ok(existsSync(BENCH_ELF), `no benchmark ELF at ${BENCH_ELF}: build it with \`cargo fw\``);
  const poses = benchPoses(12, 2024);
  result = runIkBench(poses);
  kinematics = runKinematicsBench(poses.slice(0, 6), { limitsPoses: 1 });
});

test('the chip solves every pose the host solves', () => {
  assert.equal(result.poses, 12);
  assert.deepEqual(result.failures, []);
});

test('ROM-backed IK on the chip agrees with the host libm IK and the f64 reference', () => {
  assert.ok(result.worst.romVsHost <= PULSE_TOL_US, `vs host: ${result.worst.romVsHost} us`);
  assert.ok(result.worst.romVsRef <= PULSE_TOL_US, `vs f64: ${result.worst.romVsRef} us`);
  assert.ok(result.worst.libmVsRef <= PULSE_TOL_US, `libm on chip vs f64: ${result.worst.libmVsRef} us`);
});

test('fsin leaves the cosine in r1, and the ROM routines match libm', () => {
  // Over a grid: sin and cos on [-2 pi, 2 pi] (cos is the r1 result of the sin call), sqrt
  // relative, atan2 all round the circle. The ROM is documented accurate to ~1e-7.
  const { sin, cos, sqrt, atan2 } = result.mathDiff;
  for (const [name, value] of Object.entries({ sin, cos, sqrt, atan2 })) {
    assert.ok(Number.isFinite(value) && value <= 1e-6, `${name}: ${value}`);
  }
});

test('the rest of the kinematics on the chip agrees with the f64 reference', () => {
  // Forward kinematics from the reference's pulses back to their pose, a frame's step away
  // (the bound of host-tests/tests/forward.rs), the Jacobian against finite differences, the
  // torques against an f64 solve (see emulator/src/ik-bench.js).
  const { fk, jacobian, torque, limits } = kinematics;
  assert.equal(fk.failures + jacobian.failures + torque.failures, 0);
  assert.ok(fk.iterations.max <= 8, `${fk.iterations.max} iterations`);
  assert.ok(fk.worstMm <= 1e-3 && fk.worstRad <= 1e-4, `${fk.worstMm} mm, ${fk.worstRad} rad`);
  assert.ok(jacobian.worst <= 1e-4, `Jacobian: ${jacobian.worst}`);
  assert.ok(torque.worst <= 1e-4, `torque: ${torque.worst}`);
  assert.equal(limits.poses, 1);
});
