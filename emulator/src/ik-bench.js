// The IK benchmark firmware (`firmware/src/bin/bench.rs`) in the emulator: cycles per IK from
// the marker pin, pulses compared with the host's f64 reference and the host's own f32 IK.

import { execFileSync } from 'node:child_process';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

import { EmulatedBoard } from './board.js';

const REPO = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
/** The benchmark ELF `cargo fw` builds next to the firmware; BENCH_ELF=path overrides. */
export const BENCH_ELF =
  process.env.BENCH_ELF ?? join(REPO, 'target', 'thumbv6m-none-eabi', 'release', 'bench');
/** GP16 is high exactly while the benchmark runs one IK. */
const MARKER_GPIO = 16;

/**
 * Random reachable poses with the f64 reference's pulses and the host's f32 `libm` pulses,
 * from `cargo run -p host-tests --example bench_poses` (see that file).
 */
export function benchPoses(count, seed, { release = false } = {}) {
  const args = ['run', '-q', ...(release ? ['--release'] : []), '-p', 'host-tests'];
  args.push('--example', 'bench_poses', '--', String(count), String(seed));
  const text = execFileSync('cargo', args, { cwd: REPO, encoding: 'utf8', maxBuffer: 1 << 26 });
  return text
    .trim()
    .split('\n')
    .map((line) => JSON.parse(line));
}

const bitsToF32 = (hex) => {
  const view = new DataView(new ArrayBuffer(4));
  view.setUint32(0, parseInt(hex, 16));
  return view.getFloat32(0);
};

function parsePulses(words) {
  if (words[0] === 'x') {
    return { pulses: null, rest: words.slice(1) };
  }
  return { pulses: words.slice(0, 6).map(bitsToF32), rest: words.slice(6) };
}

const summary = (values) => {
  const sum = values.reduce((a, b) => a + b, 0);
  return { mean: sum / values.length, min: Math.min(...values), max: Math.max(...values) };
};

/**
 * Runs every pose through the benchmark firmware. Returns per-IK cycle statistics for the ROM
 * path and the `libm` path, and the largest pulse differences (us) of the ROM path against the
 * f64 reference and against the host's f32 IK (and of `libm` on the chip against f64).
 */
export function runIkBench(poses, { elf = BENCH_ELF } = {}) {
  const board = new EmulatedBoard({ elf });
  const edges = [];
  board.mcu.gpio[MARKER_GPIO].addListener((state) => edges.push({ state, cycles: board.cycles }));
  board.waitForLine(/^bench ready/, { timeoutMs: 1000 });

  const romCycles = [];
  const libmCycles = [];
  const worst = { romVsRef: 0, romVsHost: 0, libmVsRef: 0 };
  const failures = [];
  for (const [index, pose] of poses.entries()) {
    edges.length = 0;
    const line = board.request(`p ${pose.pose_bits.join(' ')}`, {
      final: /^(r |error)/,
      timeoutMs: 1000,
    }).reply;
    const words = line.split(' ');
    if (words[0] !== 'r') {
      throw new Error(`pose ${index}: ${line}`);
    }
    const rom = parsePulses(words.slice(1));
    const libm = parsePulses(rom.rest.slice(1));
    if (!rom.pulses || !libm.pulses) {
      failures.push({ index, pose: pose.pose, line });
      continue;
    }
    // Three brackets: empty (the marker's own cost), ROM IK, libm IK.
    const highs = [];
    for (let i = 0; i + 1 < edges.length; i += 2) {
      highs.push(edges[i + 1].cycles - edges[i].cycles);
    }
    if (highs.length !== 3) {
      throw new Error(`pose ${index}: expected 3 marker pulses, saw ${highs.length}`);
    }
    romCycles.push(highs[1] - highs[0]);
    libmCycles.push(highs[2] - highs[0]);
    for (let i = 0; i < 6; i++) {
      worst.romVsRef = Math.max(worst.romVsRef, Math.abs(rom.pulses[i] - pose.ref_us[i]));
      worst.romVsHost = Math.max(worst.romVsHost, Math.abs(rom.pulses[i] - pose.host_us[i]));
      worst.libmVsRef = Math.max(worst.libmVsRef, Math.abs(libm.pulses[i] - pose.ref_us[i]));
    }
  }
  const math = board.request('m', { final: /^m /, timeoutMs: 20000 }).reply;
  const mathDiff = Object.fromEntries(
    math
      .split(' ')
      .slice(1)
      .map((kv) => kv.split('='))
      .map(([k, v]) => [k, Number(v)]),
  );
  return {
    poses: poses.length,
    failures,
    rom: summary(romCycles),
    libm: summary(libmCycles),
    worst,
    mathDiff,
  };
}

const ROM_END = 0x4000;

/**
 * Where the ROM-path IK's cycles go, per IK over `poses`: each boot ROM routine it calls
 * (cycles and calls, attributed by the routine entered from flash) and the firmware's own code.
 * Steps the emulator instruction by instruction while the marker is high: slow, use few poses.
 */
export function profileIk(poses, { elf = BENCH_ELF } = {}) {
  const board = new EmulatedBoard({ elf });
  board.waitForLine(/^bench ready/, { timeoutMs: 1000 });
  const names = new Map(
    board
      .request('t', { final: /^t /, timeoutMs: 1000 })
      .reply.split(' ')
      .slice(1)
      .map((kv) => kv.split('='))
      .map(([name, address]) => [parseInt(address, 16), name]),
  );
  let high = false;
  let brackets = 0;
  board.mcu.gpio[MARKER_GPIO].addListener((state) => {
    high = state === 1;
    brackets += high ? 1 : 0;
  });
  const core = board.mcu.core;
  const execute = core.executeInstruction.bind(core);
  const rows = new Map();
  let entered = 'firmware code';
  let previousPc = ROM_END;
  core.executeInstruction = () => {
    const pc = core.PC;
    const before = core.cycles;
    const result = execute();
    if (high && brackets % 3 === 2) {
      let name = 'firmware code (IK, calls, loads)';
      if (pc < ROM_END) {
        if (previousPc >= ROM_END) {
          entered = names.get(pc) ?? 'other ROM routines (first call: table look-up)';
          const row = rows.get(entered) ?? { cycles: 0, calls: 0 };
          row.calls++;
          rows.set(entered, row);
        }
        name = entered;
      }
      const row = rows.get(name) ?? { cycles: 0, calls: 0 };
      row.cycles += core.cycles - before;
      rows.set(name, row);
    }
    previousPc = pc;
    return result;
  };
  for (const pose of poses) {
    board.request(`p ${pose.pose_bits.join(' ')}`, { final: /^(r |error)/, timeoutMs: 1000 });
  }
  return [...rows]
    .map(([name, { cycles, calls }]) => ({ name, cycles: cycles / poses.length, calls: calls / poses.length }))
    .sort((a, b) => b.cycles - a.cycles);
}

/** Cycles of each marker bracket after the first, minus the first (the empty one). */
function measuredBrackets(edges, count, what) {
  const highs = [];
  for (let i = 0; i + 1 < edges.length; i += 2) {
    highs.push(edges[i + 1].cycles - edges[i].cycles);
  }
  if (highs.length !== count + 1) {
    throw new Error(`${what}: expected ${count + 1} marker pulses, saw ${highs.length}`);
  }
  return highs.slice(1).map((h) => h - highs[0]);
}

const words = (line) => line.split(' ');
const floats = (list) => list.map(bitsToF32);

/**
 * The rest of the kinematics on the chip, with the firmware's ROM maths (see
 * `firmware/src/bin/bench.rs`): per pose, the forward kinematics from the f64 reference's
 * pulses starting a frame's step away, the servo Jacobian and the holding torques of the
 * benchmark payload; on the first `limitsPoses` poses the twelve excursions (`limits`).
 * Returns cycle statistics and the largest errors against the f64 reference (the pose itself
 * for the forward kinematics; `ref_j`, `ref_torque` from `bench_poses`).
 */
export function runKinematicsBench(poses, { elf = BENCH_ELF, limitsPoses = 20 } = {}) {
  const board = new EmulatedBoard({ elf });
  const edges = [];
  board.mcu.gpio[MARKER_GPIO].addListener((state) => edges.push({ state, cycles: board.cycles }));
  board.waitForLine(/^bench ready/, { timeoutMs: 1000 });
  const ask = (line, prefix, { timeoutMs = 2000, brackets = 1 } = {}) => {
    edges.length = 0;
    const final = new RegExp(`^(${prefix} |error)`);
    const reply = board.request(line, { final, timeoutMs }).reply;
    if (!reply.startsWith(`${prefix} `)) {
      throw new Error(`${line}: ${reply}`);
    }
    const cycles = measuredBrackets(edges, brackets, line);
    return { reply: words(reply).slice(1), cycles: cycles[0], more: cycles.slice(1) };
  };
  const fk = { cycles: [], iterations: [], failures: 0, worstMm: 0, worstRad: 0 };
  const jac = { cycles: [], failures: 0, worst: 0 };
  const torque = { cycles: [], fromAngles: [], failures: 0, worst: 0 };
  const limits = { cycles: [], tests: [] };
  for (const [index, pose] of poses.entries()) {
    const f = ask(`f ${[...pose.ref_us_bits, ...pose.start_bits].join(' ')}`, 'f');
    if (f.reply[0] === 'x') {
      fk.failures++;
    } else {
      const found = floats(f.reply.slice(0, 6));
      fk.cycles.push(f.cycles);
      fk.iterations.push(Number(f.reply[6].slice(2)));
      for (let k = 0; k < 6; k++) {
        const d = Math.abs(found[k] - pose.pose[k]);
        if (k < 3) {
          fk.worstMm = Math.max(fk.worstMm, d);
        } else {
          fk.worstRad = Math.max(fk.worstRad, d);
        }
      }
    }
    const j = ask(`j ${pose.pose_bits.join(' ')}`, 'j');
    if (j.reply[0] === 'x') {
      jac.failures++;
    } else {
      jac.cycles.push(j.cycles);
      const values = floats(j.reply);
      // Per row and per half (per mm, per rad): the error relative to the half's largest entry.
      for (let row = 0; row < 6; row++) {
        for (const [from, to] of [[0, 3], [3, 6]]) {
          let scale = 0;
          let error = 0;
          for (let k = from; k < to; k++) {
            scale = Math.max(scale, Math.abs(pose.ref_j[6 * row + k]));
            error = Math.max(error, Math.abs(values[6 * row + k] - pose.ref_j[6 * row + k]));
          }
          jac.worst = Math.max(jac.worst, error / scale);
        }
      }
    }
    const q = ask(`q ${pose.pose_bits.join(' ')}`, 'q', { brackets: 2 });
    if (q.reply[0] === 'x') {
      torque.failures++;
    } else {
      torque.cycles.push(q.cycles);
      torque.fromAngles.push(q.more[0]);
      const values = floats(q.reply);
      const scale = Math.max(...pose.ref_torque.map(Math.abs));
      for (let i = 0; i < 12; i++) {
        torque.worst = Math.max(torque.worst, Math.abs(values[i] - pose.ref_torque[i % 6]) / scale);
      }
    }
    if (index < limitsPoses) {
      const w = ask(`w ${pose.pose_bits.join(' ')}`, 'w', { timeoutMs: 60000 });
      limits.cycles.push(w.cycles);
      limits.tests.push(Number(w.reply[12].slice(2)));
    }
  }
  const histogram = {};
  for (const n of fk.iterations) {
    histogram[n] = (histogram[n] ?? 0) + 1;
  }
  return {
    poses: poses.length,
    fk: {
      ...summary(fk.cycles),
      iterations: summary(fk.iterations),
      histogram,
      failures: fk.failures,
      worstMm: fk.worstMm,
      worstRad: fk.worstRad,
    },
    jacobian: { ...summary(jac.cycles), failures: jac.failures, worst: jac.worst },
    torque: {
      ...summary(torque.cycles),
      fromAngles: summary(torque.fromAngles),
      failures: torque.failures,
      worst: torque.worst,
    },
    limits: {
      ...summary(limits.cycles),
      poses: limits.cycles.length,
      tests: summary(limits.tests),
    },
  };
}
