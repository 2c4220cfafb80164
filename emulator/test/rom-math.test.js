// The firmware's maths on the emulated chip agree with the host: the IK benchmark firmware
// (`firmware/src/bin/bench.rs`, the firmware's own IK code) solves a few random poses and its
// pulses are compared with the host's IK (the same fixed-point path: the same bits) and with
// the independent f64 reference (`host-tests`); so are the same IK on the boot ROM's and
// `libm`'s float routines, and the routines themselves. Accuracy only; timing is
// `./dev bench`'s job.

import assert from 'node:assert/strict';
import { existsSync } from 'node:fs';
import { before, test } from 'node:test';

import { BENCH_ELF, benchPoses, runIkBench, runKinematicsBench } from '../src/bench/ik-bench.js';

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

test('the firmware IK on the chip computes the host IK bit for bit, within 0.01 us of f64', () => {
  assert.equal(result.variants[0].name, 'firmware');
  assert.deepEqual(result.firmwareVsHost, { differing: 0, worst: result.firmwareVsHost.worst });
  for (const name of ['firmware', 'rom', 'libm']) {
    const variant = result.variants.find((v) => v.name === name);
    assert.equal(variant.refused, 0, name);
    assert.ok(variant.worstVsRef <= PULSE_TOL_US, `${name} vs f64: ${variant.worstVsRef} us`);
  }
});

test('fsin leaves the cosine in r1; the ROM and the fixed-point routines match libm', () => {
  // Over a grid: sin and cos on [-pi, pi] (cos is the r1 result of the sin call), sqrt, atan2
  // all round the circle. The ROM is documented accurate to ~1e-7; the fixed-point routines'
  // bounds (kinematics-core/src/fixed/) are 2^-29 for sin, cos and atan2 (rad) and 1 for the
  // integer square root.
  const [sin, cos, sqrt, atan2] = result.mathErrors.rom;
  for (const [name, value] of Object.entries({ sin, cos, sqrt, atan2 })) {
    assert.ok(Number.isFinite(value) && value <= 1e-6, `ROM ${name}: ${value}`);
  }
  const bounds = [2 ** -29, 2 ** -29, 1, 2 ** -29].map((b) => b * 1.01);
  result.mathErrors.fixed.forEach((value, k) => {
    assert.ok(Number.isFinite(value) && value <= bounds[k], `fixed-point routine ${k}: ${value}`);
  });
});

test('the rest of the kinematics on the chip agrees with the f64 reference', () => {
  // Forward kinematics from the reference's pulses back to their pose, a frame's step away
  // (the bound of host-tests/tests/forward.rs), the Jacobian against finite differences, the
  // torques against an f64 solve (see emulator/src/bench/ik-bench.js).
  const { fk, jacobian, torque, limits } = kinematics;
  assert.equal(fk.failures + jacobian.failures + torque.failures, 0);
  assert.ok(fk.iterations.max <= 8, `${fk.iterations.max} iterations`);
  assert.ok(fk.worstMm <= 1e-3 && fk.worstRad <= 1e-4, `${fk.worstMm} mm, ${fk.worstRad} rad`);
  assert.ok(jacobian.worst <= 1e-4, `Jacobian: ${jacobian.worst}`);
  assert.ok(torque.worst <= 1e-4, `torque: ${torque.worst}`);
  assert.equal(limits.poses, 1);
});
