// One benchmark of `./dev bench` alone, printed rather than written to BENCHMARKS.md: a quick
// figure while working on one part (seconds to a minute instead of the whole bench's minutes).
//
//   node src/bench/quick-bench.js ik|stream|tracker-profile|pose-profile|jump [--poses N] [--seed S]
//
//   ik               cycles per IK on the benchmark firmware (every variant it carries)
//   stream           a clamp and tracker frames (`Controller::on_frame` while streaming), as
//                    BENCHMARKS.md's "The stream pipeline" table measures them (first 40 poses)
//   tracker-profile  where a tracker frame's cycles go: per function of the ELF's symbol table
//                    (inlined code counts in the function it was inlined into; the boot ROM as
//                    one), per measured frame
//   pose-profile     where a `pose` line's cycles go on the real firmware (echo and speeds
//                    off, 921,600 baud, 200 lines of small steps each answered before the
//                    next): every cycle the core runs from a line's first byte to its reply, per
//                    function, per line
//   edge             the honest stream worst case (`measureStreamCpu`'s `edge`: all six axes,
//                    z just past the servo limits, a payload and torque ratings, 333 frames/s
//                    for 0.5 s): CPU share and cycles per servo frame, as BENCHMARKS.md's
//                    "Stream CPU" table (HEXAPOD_XIP_CACHE=on for the cache model)
//   edge-profile     where that worst case's cycles go, per function, per servo frame (and
//                    inclusive for a few functions: with what they call)
//   jump             BENCHMARKS.md's 5 mm jumps (`pose` lines whose path is checked every 0.5 mm:
//                    10 IKs): from the line end to the PWM at 115,200 baud, PL011 receive rules
//   latency          BENCHMARKS.md's "Command to output" steps (40 `pose` lines, one IK each) at
//                    115,200 and 921,600 baud, and "Stream frames"' 40 binary frames at 921,600
//                    and 115,200: from the last byte to the PWM
//   sustained        BENCHMARKS.md's "Sustained pose lines per second", back to back only
//                    (`--poses` lines, 2000 in the bench; every line must be `ok`), and a host
//                    that waits for each `ok` (500 lines)
//
// Expects `cargo fw` to have built the firmware and the benchmark firmware. The same
// measurements, in the same harness, as `./dev bench` (emulator/src/bench/ik-bench.js).

import { parseArgs } from 'node:util';

import { DEFAULT_ELF, EmulatedBoard } from '../chip/board.js';
import {
  measureFrameLatency,
  measureLatency,
  measureLockStep,
  measureStream,
  streamingBoard,
} from './firmware-bench.js';
import { measureStreamCpu } from './stream-bench.js';
import { symbolRanges } from '../chip/elf.js';
import { BENCH_ELF, benchPoses, runIkBench, runStreamBench } from './ik-bench.js';
import { frameCounts, pathPoses } from './headline.js';

const { values: args, positionals } = parseArgs({
  allowPositionals: true,
  options: {
    poses: { type: 'string', default: '40' },
    seed: { type: 'string', default: '1' },
  },
});

const fmt = (x) => Math.round(x).toLocaleString('en-US');
const row = (what, s) =>
  `${what}: mean ${fmt(s.mean)}, min ${fmt(s.min)}, max ${fmt(s.max)} cycles`;

/** Functions also measured with what they call, when they are not inlined. */
const INCLUSIVE =
  /^(control::tracker::Tracker::step|kinematics_core::ik::Solver::solve|kinematics_core::statics::servo_holding_torques|kinematics_core::linalg::Lu6::|control::payload::)/;

const which = positionals[0];
const poses = ['pose-profile', 'latency', 'sustained'].includes(which)
  ? []
  : benchPoses(Number(args.poses), Number(args.seed));
if (which === 'ik') {
  for (const v of runIkBench(poses).variants) {
    console.log(row(`IK (${v.name})`, v));
  }
} else if (which === 'stream') {
  const stream = runStreamBench(poses.slice(0, 40), { frames: 3, dzMm: 60 });
  console.log(row(`clamp (${stream.clamp.clamped} clamped)`, stream.clamp));
  console.log(
    row(`tracker frame (${stream.track.moved} of ${stream.track.frames} moved)`, stream.track),
  );
  if (stream.trackClamped.frames > 0) {
    console.log(
      row(
        `tracker frame, step left the workspace (${stream.trackClamped.frames})`,
        stream.trackClamped,
      ),
    );
  }
} else if (which === 'pose-profile') {
  profilePoseLines(200);
} else if (which === 'jump') {
  const us = measureLatency(['5 0 0 0 0 0', '0 0 0 0 0 0', '0 0 5 0 0 0']);
  console.log(
    `5 mm jumps to PWM at 115,200 baud: ${us.map((u) => `${u.toFixed(1)} us`).join(', ')}`,
  );
} else if (which === 'latency') {
  const steps = pathPoses(41);
  const stat = (list) =>
    `mean ${(list.reduce((a, b) => a + b, 0) / list.length).toFixed(1)}, min ${Math.min(...list).toFixed(1)}, max ${Math.max(...list).toFixed(1)} us`;
  for (const baud of [115200, 921600]) {
    const us = measureLatency(steps.slice(1), { baud, from: steps[0] });
    console.log(`pose line (one IK) to PWM at ${baud} baud: ${stat(us)}`);
  }
  const frames = Array.from({ length: 40 }, (_, i) => frameCounts(i));
  for (const baud of [921600, 115200]) {
    console.log(
      `stream frame to PWM at ${baud} baud: ${stat(measureFrameLatency(frames, { baud }))}`,
    );
  }
} else if (which === 'sustained') {
  const count = args.poses === '40' ? 2000 : Number(args.poses);
  const lines = pathPoses(count).map((pose) => `pose ${pose}`);
  const result = measureStream(lines, { baud: 921600 });
  console.log(
    `back to back at 921,600 baud: ${result.ok}/${result.lines} ok, ${fmt(result.linesPerSecond)} lines/s`,
  );
  const lockStep = measureLockStep(lines.slice(0, 500), { baud: 921600 });
  console.log(
    `waiting for each ok: ${lockStep.ok}/${lockStep.lines} ok, ${fmt(lockStep.linesPerSecond)} lines/s, ${fmt(lockStep.cyclesPerLine)} cycles a line`,
  );
} else if (which === 'tracker-profile') {
  profileTracker(poses.slice(0, 40), 3);
} else if (which === 'edge') {
  const run = measureStreamCpu({ framesPerSecond: 333, seconds: 0.5, allAxes: true, edge: true });
  console.log(
    `edge at 333/s: CPU ${(run.cpuShare * 100).toFixed(2)} %, ${fmt(run.cyclesPerServoFrame)} cycles per servo frame, ${run.applied} applied / ${run.clamped} clamped, longest pass ${fmt(run.longestPassCycles)} cycles`,
  );
} else if (which === 'edge-profile') {
  profileEdge();
} else {
  console.error(
    'usage: node src/bench/quick-bench.js ik|stream|tracker-profile|pose-profile|jump|edge|edge-profile [--poses N] [--seed S]',
  );
  process.exit(2);
}

/** The cycles of `frames` tracker frames towards each pose, per function. */
function profileTracker(list, frames) {
  const MARKER_GPIO = 16;
  const board = new EmulatedBoard({ elf: BENCH_ELF });
  board.waitForLine(/^bench ready/, { timeoutMs: 1000 });
  const tally = callTally(BENCH_ELF);
  let high = false;
  board.mcu.gpio[MARKER_GPIO].addListener((state) => {
    high = state === 1;
  });
  const core = board.mcu.core;
  const execute = core.executeInstruction.bind(core);
  core.executeInstruction = () => {
    const pc = core.PC;
    const lr = core.registers[14];
    const before = core.cycles;
    const result = execute();
    if (high) {
      tally.count(pc, lr, core.cycles - before);
    }
    return result;
  };
  const f32Hex = (x) => {
    const view = new DataView(new ArrayBuffer(4));
    view.setFloat32(0, x);
    return view.getUint32(0).toString(16).padStart(8, '0');
  };
  for (const pose of list) {
    board.request(`k ${[...pose.pose_bits, f32Hex(frames)].join(' ')}`, {
      final: /^(k |error)/,
      timeoutMs: 2000,
    });
  }
  const perFrame = list.length * frames;
  const { rows, inclusive } = tally;
  printPerFunction(rows, perFrame, (total) => {
    return `per frame (${perFrame} frames, empty brackets included): ${fmt(total)} cycles`;
  });
  console.log('inclusive (with what they call):');
  for (const [name, cycles] of inclusive) {
    console.log(`${fmt(cycles / perFrame).padStart(8)}  ${name}`);
  }
}

/** Where the stream's honest worst case (`edge`, 333 frames/s) spends its cycles. */
function profileEdge() {
  const tally = callTally(DEFAULT_ELF);
  const { rows, inclusive } = tally;
  // Every function's entry (to fold the float routines and the boot ROM into their callers).
  const starts = new Map(
    symbolRanges(DEFAULT_ELF, () => true)
      .filter((r) => r.end > r.start)
      .map((r) => [r.start, r.name]),
  );
  const FOLDED = /^(__aeabi_|__.*(add|sub|mul|div|cmp|fix|float)[sd]f|f(min|max)f?$|memcpy|memset)/;
  const folded = new Map();
  let restore = null;
  const instrument = {
    start(board) {
      const core = board.mcu.core;
      const execute = core.executeInstruction.bind(core);
      const stack = [];
      restore = () => {
        core.executeInstruction = execute;
      };
      core.executeInstruction = () => {
        const pc = core.PC;
        const lr = core.registers[14];
        const before = core.cycles;
        const result = execute();
        const cycles = core.cycles - before;
        const name = tally.count(pc, lr, cycles);
        while (stack.length > 0 && stack[stack.length - 1].back === pc) {
          stack.pop();
        }
        const callee = starts.get(pc);
        if (callee && !FOLDED.test(callee)) {
          stack.push({ name: callee, back: lr & ~1 });
        }
        const owner =
          pc < 0x4000 || FOLDED.test(name) ? (stack[stack.length - 1]?.name ?? name) : name;
        folded.set(owner, (folded.get(owner) ?? 0) + cycles);
        return result;
      };
    },
    stop() {
      restore();
    },
  };
  const run = measureStreamCpu({
    framesPerSecond: 333,
    seconds: 0.5,
    allAxes: true,
    edge: true,
    instrument,
  });
  const frames = run.seconds * 333;
  printPerFunction(
    rows,
    frames,
    (total) =>
      `per servo frame (${Math.round(frames)} frames, CPU ${(run.cpuShare * 100).toFixed(2)} %): ${fmt(total)} cycles`,
    40,
  );
  printPerFunction(
    folded,
    frames,
    () => 'the same with the float routines and the boot ROM counted in their callers:',
    30,
  );
  console.log('inclusive (with what they call), per servo frame:');
  for (const [name, cycles] of inclusive) {
    console.log(`${fmt(cycles / frames).padStart(8)}  ${name}`);
  }
}

/**
 * Cycles per function of `elf` (inlined code counts in the function it was inlined into, the
 * boot ROM as one: `rows`) and, for the functions `INCLUSIVE` names, with what they call
 * (from their entry to the return to their caller: `inclusive`). `count(pc, lr, cycles)`
 * takes one executed instruction and returns its function's name.
 */
function callTally(elf) {
  const nameOf = functionNames(elf);
  const entries = new Map(
    symbolRanges(elf, () => true)
      .filter((r) => r.end > r.start && INCLUSIVE.test(r.name))
      .map((r) => [r.start, r.name]),
  );
  const rows = new Map();
  const inclusive = new Map();
  const open = [];
  return {
    rows,
    inclusive,
    count(pc, lr, cycles) {
      const name = nameOf(pc);
      rows.set(name, (rows.get(name) ?? 0) + cycles);
      while (open.length > 0 && open[open.length - 1].back === pc) {
        open.pop();
      }
      const entered = entries.get(pc);
      if (entered) {
        open.push({ name: entered, back: lr & ~1 });
      }
      for (const n of new Set(open.map((o) => o.name))) {
        inclusive.set(n, (inclusive.get(n) ?? 0) + cycles);
      }
      return name;
    },
  };
}

/** Names the function of a PC from the ELF's symbol table (the boot ROM as one). */
function functionNames(elf) {
  const ranges = symbolRanges(elf, () => true)
    .filter((r) => r.end > r.start)
    .sort((a, b) => a.start - b.start);
  return (pc) => {
    if (pc < 0x4000) {
      return 'boot ROM';
    }
    let lo = 0;
    let hi = ranges.length - 1;
    while (lo <= hi) {
      const mid = (lo + hi) >> 1;
      if (ranges[mid].end <= pc) {
        lo = mid + 1;
      } else if (ranges[mid].start > pc) {
        hi = mid - 1;
      } else {
        return ranges[mid].name;
      }
    }
    return `? ${pc.toString(16)}`;
  };
}

/** Every cycle from each `pose` line's first byte to its `ok`, per function, per line. */
function profilePoseLines(count) {
  const { board } = streamingBoard({ baud: 921600 });
  const nameOf = functionNames(DEFAULT_ELF);
  const core = board.mcu.core;
  const execute = core.executeInstruction.bind(core);
  const rows = new Map();
  let on = false;
  core.executeInstruction = () => {
    const pc = core.PC;
    const before = core.cycles;
    const result = execute();
    if (on) {
      const name = nameOf(pc);
      rows.set(name, (rows.get(name) ?? 0) + core.cycles - before);
    }
    return result;
  };
  let bytes = 0;
  let passes = 0;
  for (const pose of pathPoses(count)) {
    const line = `pose ${pose}`;
    bytes += line.length + 1;
    board.runMs(3); // a quiet stretch between lines (frames run there, not counted)
    on = true;
    const passesBefore = board.loop.passes;
    const { reply } = board.request(line);
    passes += board.loop.passes - passesBefore;
    on = false;
    if (reply !== 'ok') {
      throw new Error(`${line}: ${reply}`);
    }
  }
  printPerFunction(
    rows,
    count,
    (total) =>
      `per line (${count} lines, ${(bytes / count).toFixed(1)} bytes each): ${fmt(total)} cycles`,
    40,
  );
  console.log(`main-loop passes per line: ${(passes / count).toFixed(1)}`);
}

/**
 * Prints cycles per function (`rows`: name -> cycles) divided by `per`, most first (the first
 * `limit`), under a heading `heading(total / per)`.
 */
function printPerFunction(rows, per, heading, limit = Infinity) {
  const sorted = [...rows].sort((a, b) => b[1] - a[1]);
  const total = sorted.reduce((sum, [, c]) => sum + c, 0);
  console.log(heading(total / per));
  for (const [name, cycles] of sorted.slice(0, limit)) {
    console.log(`${fmt(cycles / per).padStart(8)}  ${name}`);
  }
}
