// The headline figures of BENCHMARKS.md in one call: what `./dev bench` reports with and
// without the XIP cache model (gaps/xip-cache.js, gap 13), and what `./dev test` guards against
// a committed table (emulator/bench-guard.json, test/bench-guard.test.js) on a few poses.
//
// Every figure is "lower is better" and deterministic (emulated cycles and time).

import { readFileSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

import {
  measureFrameLatency,
  measureLatency,
  measureLockStep,
  measureLongestPass,
} from './firmware-bench.js';
import { benchPoses, runIkBench, runStreamBench, runWarmIk } from './ik-bench.js';
import { measureStreamCpu } from './stream-bench.js';

const EMULATOR = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
/** The committed table `./dev test` checks (`./dev bench --update-guard` rewrites it). */
export const GUARD_FILE = join(EMULATOR, 'bench-guard.json');
/** A figure more than this fraction above its committed value fails `./dev test`. */
export const GUARD_TOLERANCE = 0.03;
/** The guard's sizes: a few of each, so `./dev test` stays about as long as before. */
export const GUARD_SIZES = { poses: 6, streamPoses: 3, lines: 40, frames: 8, latencyLines: 8 };

/** What each figure is, with its unit, for the tables. */
export const HEADLINES = {
  ikCycles: "IK (`ik::Solver::solve`, the firmware's), cycles, mean, in the benchmark sequence",
  ikColdCycles: 'IK with the cache emptied as it starts (cold), cycles, mean',
  ikWarmCycles: 'IK right after the same IK (warm), cycles, mean',
  trackerFrameCycles: 'tracker frame (`Controller::on_frame`, a step and one IK), cycles, mean',
  clampCycles: 'clamp of a frame 60 mm out of reach, to its end, cycles, mean',
  poseLineCycles: '`pose` line, the CPU cycles it costs (lock-step at 921,600 baud, echo off)',
  frameLatencyUs: 'stream frame to PWM at 921,600 baud, us, mean',
  frameLatencyMaxUs: 'stream frame to PWM at 921,600 baud, us, max',
  poseLatencyUs: '`pose` line to PWM at 115,200 baud (PL011 receive rules), us, mean',
  poseLatencyMaxUs: '`pose` line to PWM at 115,200 baud (PL011 receive rules), us, max',
  longestPassCycles: 'longest main-loop pass (41 long commands at 333 Hz, then 20 moves), cycles',
};

/** Headline figures `./dev bench` reports beside those and the guard leaves out (longer runs). */
export const BENCH_HEADLINES = {
  streamEdgeCpuPercent:
    'stream pipeline at 333 Hz, targets just past the servo limits, payload and ratings, % of the CPU (the worse of: the platform staying at the edge, or z in and out of reach in turn)',
};

/**
 * `./dev bench`'s sizes: more of each than the guard's, and the stream pipeline's worst case
 * (`edgeSeconds` of it; the guard leaves it out, to keep `./dev test` as long as before).
 */
export const HEADLINE_SIZES = {
  poses: 40,
  streamPoses: 10,
  lines: 200,
  frames: 20,
  latencyLines: 20,
  edgeSeconds: 0.5,
};

/** A smooth path of `count` pose arguments (mm, degrees), as the bench's streaming lines. */
export function pathPoses(count) {
  return Array.from({ length: count }, (_, i) => {
    const a = i * 0.01;
    const v = [
      10 * Math.cos(a),
      10 * Math.sin(a),
      2 * Math.sin(3 * a),
      3 * Math.sin(a),
      3 * Math.cos(2 * a),
      5 * Math.sin(a / 2),
    ];
    return v.map((x) => x.toFixed(3)).join(' ');
  });
}

/** Six stream-frame counts for frame `i` (the bench's frame set). */
export const frameCounts = (i) => [
  32768 + (i % 5) * 300 + 7,
  32768 + i,
  32768 + (i % 3) * 500,
  32768,
  32768 + (i % 2) * 200,
  32768 + (i % 4) * 200,
];

const mean = (values) => values.reduce((a, b) => a + b, 0) / values.length;
const round = (x, digits) => Math.round(x * 10 ** digits) / 10 ** digits;

/**
 * Measures every headline figure with boards as the process makes them (the cache model on or
 * off: `setXipCacheByDefault`). `poses`: from `benchPoses`; sizes as in `GUARD_SIZES`.
 * Returns `{ figures, xip }` (`xip`: the IK's flash accesses and hits per IK, and the chip's
 * counters around one pose line, from `runIkBench`; null without the model).
 */
export function measureHeadlines(poses, sizes = GUARD_SIZES) {
  const ikPoses = poses.slice(0, sizes.poses);
  const ik = runIkBench(ikPoses, { errors: false });
  const cold = runIkBench(ikPoses, { errors: false, cold: true });
  const warm = runWarmIk(ikPoses);
  const stream = runStreamBench(poses.slice(0, sizes.streamPoses));
  const path = pathPoses(Math.max(sizes.lines, sizes.latencyLines + 1));
  const lockStep = measureLockStep(path.slice(0, sizes.lines).map((p) => `pose ${p}`));
  const frames = measureFrameLatency(
    Array.from({ length: sizes.frames }, (_, i) => frameCounts(i)),
  );
  const steps = path.slice(0, sizes.latencyLines + 1);
  const latency = measureLatency(steps.slice(1), { from: steps[0] });
  const passes = measureLongestPass();
  const figures = {
    ikCycles: round(ik.variants[0].mean, 1),
    ikColdCycles: round(cold.variants[0].mean, 1),
    ikWarmCycles: round(warm.warm.mean, 1),
    trackerFrameCycles: round(stream.track.mean, 1),
    clampCycles: round(stream.clamp.mean, 1),
    poseLineCycles: round(lockStep.cyclesPerLine, 1),
    frameLatencyUs: round(mean(frames), 3),
    frameLatencyMaxUs: round(Math.max(...frames), 3),
    poseLatencyUs: round(mean(latency), 3),
    poseLatencyMaxUs: round(Math.max(...latency), 3),
    longestPassCycles: passes.longestPassCycles,
  };
  if (sizes.edgeSeconds) {
    const shares = [false, true].map(
      (inOut) =>
        measureStreamCpu({
          framesPerSecond: 333,
          seconds: sizes.edgeSeconds,
          allAxes: true,
          edge: true,
          inOut,
        }).cpuShare,
    );
    figures.streamEdgeCpuPercent = round(Math.max(...shares) * 100, 2);
  }
  return { figures, xip: ik.xip };
}

/** The guard's poses (seed 1, as the bench's). */
export function guardPoses() {
  return benchPoses(GUARD_SIZES.poses, 1);
}

/** The committed table: `{ tolerance, sizes, xipCache, figures }`, or null if there is none. */
export function readGuard() {
  try {
    return JSON.parse(readFileSync(GUARD_FILE, 'utf8'));
  } catch (error) {
    if (error.code === 'ENOENT') {
      return null;
    }
    throw error;
  }
}

/** Writes `figures` as the committed table. */
export function writeGuard(figures) {
  const table = {
    about:
      'Headline figures ./dev test checks (test/bench-guard.test.js), the XIP cache modelled, ' +
      'on the guard sizes; a figure more than tolerance above its value fails. ' +
      'Rewrite with ./dev bench --update-guard when a change is meant.',
    tolerance: GUARD_TOLERANCE,
    sizes: GUARD_SIZES,
    figures,
  };
  writeFileSync(GUARD_FILE, `${JSON.stringify(table, null, 2)}\n`);
}

/**
 * The figures that regressed: `[{ name, was, now, ratio }]`, those more than `tolerance` above
 * the table's; and those that improved as much (a hint to update the table).
 */
export function compareWithGuard(figures, table) {
  const regressions = [];
  const improvements = [];
  for (const [name, was] of Object.entries(table.figures)) {
    const now = figures[name];
    const ratio = now / was;
    if (ratio > 1 + table.tolerance) {
      regressions.push({ name, was, now, ratio });
    } else if (ratio < 1 - table.tolerance) {
      improvements.push({ name, was, now, ratio });
    }
  }
  return { regressions, improvements };
}
