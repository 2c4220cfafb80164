// The IK benchmark firmware (`firmware/src/bin/bench.rs`) in the emulator: cycles per IK from
// the marker pin, pulses compared with the host's f64 reference and the host's own f32 IK.

import { execFileSync } from 'node:child_process';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

import { EmulatedBoard } from '../chip/board.js';
import { symbolRanges } from '../chip/elf.js';

const REPO = join(dirname(fileURLToPath(import.meta.url)), '..', '..', '..');
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

/** The variants of the IK the benchmark firmware runs, from its ready line. */
function readyVariants(board) {
  const ready = board.waitForLine(/^bench ready/, { timeoutMs: 1000 });
  const match = / variants=(\S+)/.exec(ready);
  if (!match) {
    throw new Error(`no variants in the benchmark firmware's ready line: ${ready}`);
  }
  return match[1].split(',');
}

const f32Bits = (x) => {
  const view = new DataView(new ArrayBuffer(4));
  view.setFloat32(0, x);
  return view.getUint32(0);
};

/**
 * Runs every pose through the benchmark firmware: each variant of the IK (`firmware` first:
 * the firmware's own maths; then the same IK with other libraries' routines, see
 * `firmware/src/bin/bench.rs`). Returns, per variant, cycle statistics, the largest pulse
 * difference (us) against the f64 reference and the poses it refused that the host solved;
 * the firmware's pulses against the host's own IK bit for bit (`firmwareVsHost`: poses that
 * differ, largest difference); and the routines' errors on the chip (`mathErrors`: for
 * `rom`, `fixed` and, if built with it, `micromath`: [sin, cos, sqrt (relative), atan2]).
 */
/**
 * @param {any[]} poses from `benchPoses`
 * @param {{ elf?: string, cold?: boolean, errors?: boolean, xipCache?: boolean }} [options]
 *   `cold`: the XIP cache (gaps/xip-cache.js) emptied at every marker edge, so each IK starts
 *   with nothing cached; `errors: false` skips the routines' error grid (`m`, slow);
 *   `xipCache`: the board's cache model (default: the process's default)
 */
export function runIkBench(poses, { elf = BENCH_ELF, cold = false, errors = true, xipCache } = {}) {
  const board = new EmulatedBoard({ elf, ...(xipCache === undefined ? {} : { xipCache }) });
  const edges = [];
  board.mcu.gpio[MARKER_GPIO].addListener((state) => {
    if (cold) {
      board.xip?.flush();
    }
    const xip = board.xip?.stats;
    edges.push({ state, cycles: board.cycles, accesses: xip?.accesses, hits: xip?.hits });
  });
  /** The firmware IK's flash accesses and hits (the XIP model's), per pose. */
  const flash = { accesses: [], hits: [] };
  const names = readyVariants(board);
  const variants = names.map((name) => ({ name, cycles: [], worstVsRef: 0, refused: [] }));
  const firmwareVsHost = { differing: 0, worst: 0 };
  const failures = [];
  for (const [index, pose] of poses.entries()) {
    edges.length = 0;
    const line = board.request(`p ${pose.pose_bits.join(' ')}`, {
      final: /^(r |error)/,
      timeoutMs: 1000,
    }).reply;
    let words = line.split(' ');
    if (words[0] !== 'r') {
      throw new Error(`pose ${index}: ${line}`);
    }
    words = words.slice(1);
    const highs = [];
    for (let i = 0; i + 1 < edges.length; i += 2) {
      highs.push(edges[i + 1].cycles - edges[i].cycles);
    }
    if (highs.length !== names.length + 1) {
      throw new Error(
        `pose ${index}: expected ${names.length + 1} marker pulses, saw ${highs.length}`,
      );
    }
    if (board.xip) {
      flash.accesses.push(edges[3].accesses - edges[2].accesses);
      flash.hits.push(edges[3].hits - edges[2].hits);
    }
    for (const [v, variant] of variants.entries()) {
      const parsed = parsePulses(words);
      words = parsed.rest;
      variant.cycles.push(highs[v + 1] - highs[0]);
      if (!parsed.pulses) {
        variant.refused.push(index);
        continue;
      }
      for (let i = 0; i < 6; i++) {
        variant.worstVsRef = Math.max(
          variant.worstVsRef,
          Math.abs(parsed.pulses[i] - pose.ref_us[i]),
        );
      }
      if (v === 0) {
        const bits = parsed.pulses.map(f32Bits);
        if (bits.some((b, i) => b !== parseInt(pose.host_us_bits[i], 16))) {
          firmwareVsHost.differing++;
        }
        for (let i = 0; i < 6; i++) {
          firmwareVsHost.worst = Math.max(
            firmwareVsHost.worst,
            Math.abs(parsed.pulses[i] - pose.host_us[i]),
          );
        }
      }
    }
    if (variants[0].refused.at(-1) === index) {
      failures.push({ index, pose: pose.pose, line });
    }
  }
  // The chip's own XIP counters around one pose line (`x`, `p`, `x`): what a real Pico
  // running the benchmark firmware reports the same way.
  board.request('x', { final: /^x /, timeoutMs: 1000 });
  board.request(`p ${poses[0].pose_bits.join(' ')}`, { final: /^(r |error)/, timeoutMs: 1000 });
  const counters = board.request('x', { final: /^x /, timeoutMs: 1000 }).reply;
  const [, hit, acc] = counters.match(/^x hit=(\d+) acc=(\d+)$/) ?? [];
  const xipCounters = hit === undefined ? null : { hits: Number(hit), accesses: Number(acc) };
  let mathErrors = null;
  if (errors) {
    const math = board.request('m', { final: /^m /, timeoutMs: 60000 }).reply;
    mathErrors = Object.fromEntries(
      math
        .split(' ')
        .slice(1)
        .map((kv) => kv.split('='))
        .map(([k, v]) => [k, v.split(',').map(Number)]),
    );
  }
  const perIk = (values) => values.reduce((a, b) => a + b, 0) / Math.max(values.length, 1);
  return {
    xip: board.xip
      ? { accessesPerIk: perIk(flash.accesses), hitsPerIk: perIk(flash.hits), xipCounters }
      : null,
    poses: poses.length,
    failures,
    variants: variants.map(({ name, cycles, worstVsRef, refused }) => ({
      name,
      ...summary(cycles),
      worstVsRef,
      refused: refused.length,
    })),
    firmwareVsHost,
    mathErrors,
  };
}

/**
 * The firmware's IK alone, twice per pose (the benchmark firmware's `i`): `{ first, warm }`,
 * each a summary of cycles (marker brackets less the empty one). The second finds in the XIP
 * cache what the first brought in.
 * @param {any[]} poses from `benchPoses`
 * @param {{ elf?: string, xipCache?: boolean }} [options]
 */
export function runWarmIk(poses, { elf = BENCH_ELF, xipCache } = {}) {
  const board = new EmulatedBoard({ elf, ...(xipCache === undefined ? {} : { xipCache }) });
  const edges = [];
  board.mcu.gpio[MARKER_GPIO].addListener((state) => edges.push({ state, cycles: board.cycles }));
  readyVariants(board);
  const first = [];
  const warm = [];
  for (const pose of poses) {
    edges.length = 0;
    const reply = board.request(`i ${pose.pose_bits.join(' ')}`, {
      final: /^(i|error)/,
      timeoutMs: 1000,
    }).reply;
    if (!reply.startsWith('i')) {
      throw new Error(`warm IK: ${reply}`);
    }
    const [a, b] = measuredBrackets(edges, 2, 'warm IK');
    first.push(a);
    warm.push(b);
  }
  return { first: summary(first), warm: summary(warm) };
}

const ROM_END = 0x4000;

/** The core's fixed-point routines the IK calls, by the path in their symbol's name. */
const FIXED_ROUTINES = [
  ['fixed::sin_cos::sin_cos', 'sin/cos (`fixed::sin_cos`)'],
  ['fixed::sqrt::sqrt', 'sqrt (`fixed::sqrt`)'],
  ['fixed::atan2::atan2', 'atan2 (`fixed::atan2`)'],
];

/**
 * Where one variant's IK cycles go, per IK over `poses` (`variant`: its index in the ready
 * line's list, 0 = the firmware's): each boot ROM routine it calls (attributed by the routine
 * entered from flash), each of the core's fixed-point routines (by their symbols' address
 * ranges; a routine the compiler inlined would show no row), and the firmware's own code.
 * Steps the emulator instruction by instruction while the marker is high: slow, use few poses.
 */
export function profileIk(poses, { elf = BENCH_ELF, variant = 0 } = {}) {
  const board = new EmulatedBoard({ elf });
  const variants = readyVariants(board);
  const names = new Map(
    board
      .request('t', { final: /^t /, timeoutMs: 1000 })
      .reply.split(' ')
      .slice(1)
      .map((kv) => kv.split('='))
      .map(([name, address]) => [parseInt(address, 16), name]),
  );
  const ranges = symbolRanges(elf, () => true).flatMap(({ name, start, end }) => {
    const routine = FIXED_ROUTINES.find(([path]) => name.endsWith(path));
    return routine ? [{ name: routine[1], start, end }] : [];
  });
  const inRoutine = (pc) => ranges.find((r) => pc >= r.start && pc < r.end);
  let high = false;
  let brackets = 0;
  board.mcu.gpio[MARKER_GPIO].addListener((state) => {
    high = state === 1;
    brackets += high ? 1 : 0;
  });
  const perPose = variants.length + 1;
  const core = board.mcu.core;
  const execute = core.executeInstruction.bind(core);
  const rows = new Map();
  const count = (name, cycles, call) => {
    const row = rows.get(name) ?? { cycles: 0, calls: 0 };
    row.cycles += cycles;
    row.calls += call ? 1 : 0;
    rows.set(name, row);
  };
  let entered = 'firmware code';
  let previousPc = ROM_END;
  let previousRoutine;
  core.executeInstruction = () => {
    const pc = core.PC;
    const before = core.cycles;
    const result = execute();
    if (high && brackets % perPose === (variant + 2) % perPose) {
      const cycles = core.cycles - before;
      const routine = pc >= ROM_END ? inRoutine(pc) : undefined;
      if (pc < ROM_END) {
        const call = previousPc >= ROM_END;
        if (call) {
          entered =
            names.get(pc) ??
            "other ROM routines (int/float conversions; a first call's table look-up)";
        }
        count(entered, cycles, call);
      } else if (routine) {
        count(routine.name, cycles, routine !== previousRoutine);
      } else {
        count('firmware code (IK, calls, loads)', cycles, false);
      }
      previousRoutine = routine;
    }
    previousPc = pc;
    return result;
  };
  for (const pose of poses) {
    board.request(`p ${pose.pose_bits.join(' ')}`, { final: /^(r |error)/, timeoutMs: 1000 });
  }
  return [...rows]
    .map(([name, { cycles, calls }]) => ({
      name,
      cycles: cycles / poses.length,
      calls: calls / poses.length,
    }))
    .sort((a, b) => b.cycles - a.cycles);
}

/**
 * The stream pipeline of the firmware's controller on the chip (`c`, `k` in
 * `firmware/src/bin/bench.rs`): per pose, a clamp in pass-through of a target `dzMm` above the
 * pose (`Controller::apply_stream`: 1 + `CLAMP_STEPS` IK solutions), and `frames` tracker
 * frames towards the pose (`Controller::on_frame`: the tracker's step and one IK). Returns
 * cycle statistics of the clamps and how many clamped, of the tracker frames that moved
 * (`track`) and of those whose step left the workspace and was clamped (`trackClamped`).
 */
/**
 * @param {any[]} poses from `benchPoses`
 * @param {{ elf?: string, dzMm?: number, frames?: number, xipCache?: boolean }} [options]
 */
export function runStreamBench(poses, { elf = BENCH_ELF, dzMm = 60, frames = 3, xipCache } = {}) {
  const board = new EmulatedBoard({ elf, ...(xipCache === undefined ? {} : { xipCache }) });
  const edges = [];
  board.mcu.gpio[MARKER_GPIO].addListener((state) => edges.push({ state, cycles: board.cycles }));
  readyVariants(board);
  const clamp = { cycles: [], clamped: 0 };
  const track = { cycles: [], clamped: [], still: 0 };
  const f32Hex = (x) => f32Bits(x).toString(16).padStart(8, '0');
  for (const pose of poses) {
    edges.length = 0;
    const c = board.request(`c ${[...pose.pose_bits, f32Hex(dzMm)].join(' ')}`, {
      final: /^(c |error)/,
      timeoutMs: 2000,
    }).reply;
    if (!c.startsWith('c ')) {
      throw new Error(`clamp: ${c}`);
    }
    clamp.cycles.push(...measuredBrackets(edges, 1, 'clamp'));
    clamp.clamped += Number(c.split('n=')[1]);
    edges.length = 0;
    const k = board.request(`k ${[...pose.pose_bits, f32Hex(frames)].join(' ')}`, {
      final: /^(k |error)/,
      timeoutMs: 2000,
    }).reply;
    if (!k.startsWith('k ')) {
      throw new Error(`tracker: ${k}`);
    }
    const flags = k.split(' ')[1];
    measuredBrackets(edges, frames, 'tracker').forEach((cycles, i) => {
      if (flags[i] === 'c') {
        track.clamped.push(cycles);
      } else if (flags[i] === 'm') {
        track.cycles.push(cycles);
      } else {
        track.still++;
      }
    });
  }
  return {
    poses: poses.length,
    clamp: { ...summary(clamp.cycles), clamped: clamp.clamped },
    track: { ...summary(track.cycles), frames: poses.length * frames, moved: track.cycles.length },
    trackClamped: { ...summary(track.clamped), frames: track.clamped.length },
  };
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
        for (const [from, to] of [
          [0, 3],
          [3, 6],
        ]) {
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
