// `./dev bench`: the IK and firmware benchmarks in the emulator; writes BENCHMARKS.md.
//
//   node src/bench/bench.js [--poses N] [--seed S] [--lines N] [--out PATH]
//
// Expects `cargo fw` to have built the firmware and the benchmark firmware (./dev bench does).

import { writeFileSync } from 'node:fs';
import { cpus, loadavg } from 'node:os';
import { dirname, join, relative } from 'node:path';
import { fileURLToPath } from 'node:url';
import { parseArgs } from 'node:util';

import { DEFAULT_ELF } from '../chip/board.js';
import { sectionSizes, sizedSymbols, symbolSizes, symbolValues } from '../chip/elf.js';
import {
  measureClampedStream,
  measureKinematicsCommands,
  measureLatency,
  measureLockStep,
  measureSave,
  measureLongestPass,
  measureLongestPassBothLinks,
  measureMotionLimitsPass,
  measureStream,
  measureUsbStream,
  measureWorstCommand,
  stackHighWaterBytes,
} from './firmware-bench.js';
import { BULK_PACKETS_PER_FRAME, setXipCacheByDefault } from '../gaps/index.js';
import {
  GUARD_FILE,
  GUARD_TOLERANCE,
  guardPoses,
  BENCH_HEADLINES,
  HEADLINE_SIZES,
  HEADLINES,
  measureHeadlines,
  pathPoses,
  writeGuard,
} from './headline.js';
import {
  benchPoses,
  profileIk,
  runIkBench,
  runKinematicsBench,
  runStreamBench,
} from './ik-bench.js';
import { highestFrameRate, measureFrameLatency, measureStreamCpu } from './stream-bench.js';
import { measureCueLatency } from './cue-bench.js';

const REPO = join(dirname(fileURLToPath(import.meta.url)), '..', '..', '..');
const CLOCK_HZ = 125e6;
const WATCHDOG_MS = 500;
const STREAM_BAUD = 921600;
/**
 * The IK before the fast path (commit 2e2bad8: rp2040-hal's `float_funcs` wrappers, `fsin` and
 * `fcos` called separately, all arithmetic through the hal's intrinsics), measured once with
 * this harness on the same 200 poses (seed 1).
 */
const BEFORE = { commit: '2e2bad8', mean: 40582, min: 40325, max: 40872 };
/**
 * The IK on the boot ROM's float routines called directly (commit eb271cd, the last before the
 * fixed-point routines: `fatan2`, `fsin`, `fsqrt`, `fadd`, `fmul`), measured once with this
 * harness on the same 200 poses (seed 1): cycles, largest error against the f64 reference (us)
 * and where the cycles went.
 */
const BEFORE_ROM = {
  commit: 'eb271cd',
  mean: 18079,
  min: 17968,
  max: 18228,
  worstUs: 2.85e-4,
  profile:
    'firmware code 8,253, `fatan2` 4,075 (6 calls), `fadd` 2,185 (32), `fsin` 1,729 (3), `fmul` 1,502 (27), `fsqrt` 374 (6)',
};
/** The largest pulse error the IK may have against the f64 reference, us. */
const TARGET_US = 0.01;
/** Cycles in one servo frame at the highest frame rate (333 Hz) at 125 MHz. */
const FRAME_333_CYCLES = 125e6 / 333;
/** What each variant of the IK benchmark is, for its row. */
const VARIANT_ROWS = {
  rom: "the boot ROM's `f32` `fsin`, `fsqrt`, `fatan2` in place of the integer routines",
  libm: "`libm`'s `f32` routines in their place (straightforward port)",
  micromath: "`micromath`'s (2.1) sin/cos, sqrt and atan2 in their place",
  'micromath-sin-cos': "`micromath`'s sin/cos alone",
  'micromath-sqrt': "`micromath`'s sqrt alone",
  'micromath-atan2': "`micromath`'s atan2 alone",
};
/** The variant with `micromath`'s routine alone, by routine. */
const MICROMATH_ALONE = {
  sin: 'micromath-sin-cos',
  cos: 'micromath-sin-cos',
  sqrt: 'micromath-sqrt',
  atan2: 'micromath-atan2',
};
/**
 * The firmware just before the settings storage (`save`, the store, the flash routines) was
 * merged in (commit b7187c2: streaming and the safety pins, UART0 only), measured once with
 * this harness's section sums: flash and static RAM bytes.
 */
const BEFORE_STORAGE = { commit: 'b7187c2', flash: 158_696, ram: 5_288 };
/**
 * The firmware with the settings storage merged in (commit 20de6a3: b7187c2 and the storage,
 * UART0 only), measured once the same way: flash and static RAM, bytes.
 */
const WITH_STORAGE = { commit: '20de6a3', flash: 177_772, ram: 5_652 };
/**
 * USB serial's merge (commit c4c7568) and its first parent, the firmware just before it
 * (7496619, UART0 only), measured once the same way: what USB added, against what it was
 * merged into (the firmware has grown since, for other reasons).
 */
const WITHOUT_USB = { commit: '7496619', flash: 181_064, ram: 5_652 };
const WITH_USB = { commit: 'c4c7568', flash: 208_304, ram: 12_128 };
/** The USB code and data in the ELF's symbol table (rust names; the handler by its own). */
const USB_SYMBOL =
  /usb_serial|usb_device|usbd_serial|rp2040_hal\.\.usb\.\.|rp2040_hal3usb|USBCTRL_IRQ/;
/** Where the RP2040's SRAM starts: symbols below it are in flash. */
const RAM_START = 0x20000000;

const { values: args } = parseArgs({
  options: {
    poses: { type: 'string', default: '200' },
    seed: { type: 'string', default: '1' },
    lines: { type: 'string', default: '2000' },
    'cue-seconds': { type: 'string', default: '20' },
    out: { type: 'string', default: join(REPO, 'BENCHMARKS.md') },
    'update-guard': { type: 'boolean', default: false },
  },
});

const log = (text) => process.stderr.write(`${text}\n`);
const us = (cycles) => (cycles / CLOCK_HZ) * 1e6;
const fmt = (x, digits = 0) =>
  x.toLocaleString('en-US', { maximumFractionDigits: digits, minimumFractionDigits: digits });

/** A smooth streaming path: small steps in all six coordinates (mm, degrees). */
function streamLines(count) {
  return pathPoses(count).map((pose) => `pose ${pose}`);
}

// ---- the guard's table (./dev bench --update-guard): only that ----
if (args['update-guard']) {
  log('the headline figures on the guard sizes, the XIP cache modelled ...');
  setXipCacheByDefault(true);
  const { figures } = measureHeadlines(guardPoses());
  writeGuard(figures);
  log(`wrote ${relative(REPO, GUARD_FILE)}:`);
  log(JSON.stringify(figures, null, 2));
  process.exit(0);
}

// ---- the headline figures with the XIP cache model and without ----
log('headline figures, the XIP cache modelled and not ...');
const headlinePoses = benchPoses(HEADLINE_SIZES.poses, Number(args.seed));
setXipCacheByDefault(true);
const withCache = measureHeadlines(headlinePoses, HEADLINE_SIZES);
setXipCacheByDefault(false);
const noCache = measureHeadlines(headlinePoses, HEADLINE_SIZES);
// Every later figure with the model, as every test and `./dev run` has it.
setXipCacheByDefault(true);
log(JSON.stringify({ withCache: withCache.figures, noCache: noCache.figures }, null, 2));

// ---- IK ----
log(`IK: ${args.poses} random reachable poses (seed ${args.seed}) ...`);
const poses = benchPoses(Number(args.poses), Number(args.seed));
const ik = runIkBench(poses);
if (ik.failures.length > 0) {
  throw new Error(
    `the chip refused ${ik.failures.length} poses the host solved: ${JSON.stringify(ik.failures[0])}`,
  );
}

const PROFILE_POSES = 5;
const profile = profileIk(poses.slice(0, PROFILE_POSES));
const variant = (name) => ik.variants.find((v) => v.name === name);
const [firmware] = ik.variants;
const romProfile = profileIk(poses.slice(0, PROFILE_POSES), {
  variant: ik.variants.indexOf(variant('rom')),
});
if (!variant('micromath')) {
  throw new Error(
    'the benchmark firmware was built without `micromath`: cargo fw --features micromath',
  );
}
if (firmware.worstVsRef > TARGET_US) {
  throw new Error(`the firmware's IK is off by ${firmware.worstVsRef} us, beyond ${TARGET_US} us`);
}

// ---- the stream pipeline: clamping and tracking ----
log('stream: clamps and tracker frames ...');
const STREAM_POSES = 40;
const TRACK_FRAMES = 3;
const CLAMP_DZ_MM = 60;
const stream = runStreamBench(poses.slice(0, STREAM_POSES), {
  frames: TRACK_FRAMES,
  dzMm: CLAMP_DZ_MM,
});

// ---- the rest of the kinematics ----
const LIMITS_POSES = 20;
log('forward kinematics, Jacobian, torque, limits ...');
const kin = runKinematicsBench(poses, { limitsPoses: LIMITS_POSES });
const kinParts = { fk: kin.fk, jacobian: kin.jacobian, torque: kin.torque };
for (const [name, part] of Object.entries(kinParts)) {
  if (part.failures > 0) {
    throw new Error(`${name}: the chip failed on ${part.failures} poses the host solved`);
  }
}
const histogram = Object.entries(kin.fk.histogram)
  .map(([n, count]) => `${count} in ${n}`)
  .join(', ');

// ---- latency ----
log('latency ...');
const steps = streamLines(41).map((line) => line.slice('pose '.length));
const latencySmall = measureLatency(steps.slice(1), { from: steps[0] });
const latencyJump = measureLatency(['5 0 0 0 0 0', '0 0 0 0 0 0', '0 0 5 0 0 0']);
const latencySmallFast = measureLatency(steps.slice(1), { baud: STREAM_BAUD, from: steps[0] });
const latencySmallUsb = measureLatency(steps.slice(1), { usb: true, from: steps[0] });
const latencyJumpUsb = measureLatency(['5 0 0 0 0 0', '0 0 0 0 0 0', '0 0 5 0 0 0'], { usb: true });

// ---- stream frames ----
log('stream frames ...');
const frameCountsFor = (i) => [
  32768 + (i % 5) * 300 + 7,
  32768 + i,
  32768 + (i % 3) * 500,
  32768,
  32768 + (i % 2) * 200,
  32768 + (i % 4) * 200,
];
const frameSet = Array.from({ length: 40 }, (_, i) => frameCountsFor(i));
const frameFastUs = measureFrameLatency(frameSet, { baud: STREAM_BAUD });
const frameSlowUs = measureFrameLatency(frameSet, { baud: 115200 });
const frameRate = highestFrameRate([1000, 2000, 3000, 3500, 4000, 4500, 5000, 5500, 5760]);
const streamCpu = [
  { rate: 100, seconds: 1, allAxes: false },
  { rate: 333, seconds: 0.5, allAxes: false },
  { rate: 100, seconds: 1, allAxes: true },
  { rate: 333, seconds: 0.5, allAxes: true },
  { rate: 100, seconds: 1, allAxes: true, edge: true },
  { rate: 333, seconds: 0.5, allAxes: true, edge: true },
  { rate: 100, seconds: 1, allAxes: true, edge: true, inOut: true },
  { rate: 333, seconds: 0.5, allAxes: true, edge: true, inOut: true },
].map(({ rate, seconds, allAxes, edge = false, inOut = false }) => ({
  allAxes,
  edge,
  inOut,
  ...measureStreamCpu({ framesPerSecond: rate, seconds, allAxes, edge, inOut }),
}));
const streamCpu333 = streamCpu.find(
  (run) => run.allAxes && !run.edge && run.framesPerSecond === 333,
);
const streamCpuEdge333 = streamCpu.find(
  (run) => run.edge && !run.inOut && run.framesPerSecond === 333,
);
const streamCpuInOut333 = streamCpu.find((run) => run.inOut && run.framesPerSecond === 333);

// ---- sustained ----
const lines = streamLines(Number(args.lines));
const bytesPerLine = lines.reduce((n, line) => n + line.length + 1, 0) / lines.length;
log(`sustained: ${lines.length} lines at ${STREAM_BAUD} baud ...`);
const rates = [];
for (const linesPerSecond of [1000, 1200, 1400, 1600, 1800, Infinity]) {
  const result = measureStream(lines, { baud: STREAM_BAUD, linesPerSecond });
  rates.push({ offered: linesPerSecond, ...result });
  log(
    `  offered ${linesPerSecond}/s: ${result.ok}/${result.lines} ok, ${fmt(result.linesPerSecond)} lines/s`,
  );
  if (result.ok !== result.lines) {
    break;
  }
}
const lockStep = measureLockStep(lines.slice(0, 500), { baud: STREAM_BAUD });
log(`USB: ${lines.length} lines ...`);
const usbRates = [];
for (const linesPerSecond of [1000, 1500, 2000, 2500, Infinity]) {
  const result = measureUsbStream(lines, { linesPerSecond });
  usbRates.push({ offered: linesPerSecond, ...result });
  const answered = `${result.ok}/${result.lines} ok, ${fmt(result.linesPerSecond)} lines/s`;
  log(`  offered ${linesPerSecond}/s: ${answered}`);
}
const usbLockStep = measureLockStep(lines.slice(0, 500), { usb: true });

// ---- worst case ----
log('worst-case command ...');
const worst = measureWorstCommand();
log('longest main-loop pass ...');
const passes = measureLongestPass();
const passesBoth = measureLongestPassBothLinks();
log('servo, limits, torque-checked paths ...');
const kinCommands = measureKinematicsCommands();
for (const c of kinCommands) {
  log(
    `  ${c.line}: ${fmt(c.micros / 1000, 2)} ms, longest pass ${fmt(c.longestPassCycles)} cycles`,
  );
}
const clampedStream = measureClampedStream();
log('blends and servo speed ratings ...');
const motionLimits = measureMotionLimitsPass();
for (const p of motionLimits.phases) {
  log(
    `  ${p.what}: longest pass ${fmt(p.longestPassCycles)} cycles, ${p.missed} of ${p.frames} frames missed`,
  );
}
const kinLongest = Math.max(
  ...kinCommands.map((c) => c.longestPassCycles),
  clampedStream.longestPassCycles,
);
log('save ...');
const saves = /** @type {('typical' | 'max')[]} */ (['typical', 'max']).map((timing) => ({
  timing,
  ...measureSave({ timing }),
}));

// ---- motion cueing: host-side latency (wall clock) ----
log(`hexapod cue: ${args['cue-seconds']} s of telemetry at 60 Hz ...`);
const cue = await measureCueLatency({ seconds: Number(args['cue-seconds']) });
const cueLoad = loadavg()[0];
log(`  ${JSON.stringify({ all: [cue.min, cue.median, cue.p99, cue.max], live: cue.live })}`);
const ms = (x) => (x === null || x === undefined ? 'none' : `${fmt(x, 3)} ms`);
const cueRow = (what, count, q) =>
  q ? `| ${what} | ${count} | ${ms(q[1])} | ${ms(q[2])} | ${ms(q[3])} | ${ms(q[0])} |` : '';

// ---- sizes ----
const sizes = (elf) => {
  const s = sectionSizes(elf);
  const get = (name) => s[name] ?? 0;
  const flash = get('.vector_table') + get('.boot2') + get('.text') + get('.rodata') + get('.data');
  const ram = get('.data') + get('.bss') + get('.uninit');
  return { s, get, flash, ram };
};
const fw = sizes(DEFAULT_ELF);
const symbols = symbolValues(DEFAULT_ELF, ['_stack_end', '_stack_start']);
const usbSymbols = sizedSymbols(DEFAULT_ELF).filter((symbol) => USB_SYMBOL.test(symbol.name));
const usbRam = usbSymbols.filter((s) => s.value >= RAM_START).reduce((n, s) => n + s.size, 0);
const usbCode = usbSymbols.filter((s) => s.value < RAM_START).reduce((n, s) => n + s.size, 0);
// What USB added, at its merge.
const usbFlash = WITH_USB.flash - WITHOUT_USB.flash;
const usbRamTotal = WITH_USB.ram - WITHOUT_USB.ram;
const stackBytes = stackHighWaterBytes(worst.board, {
  stackEnd: symbols._stack_end,
  stackStart: symbols._stack_start,
});
const saveStackBytes = stackHighWaterBytes(saves[0].board, {
  stackEnd: symbols._stack_end,
  stackStart: symbols._stack_start,
});
// The storage's RAM parts by symbol: the erase and program routines (in .data: RAM, and
// their copy in flash) and the boot2 copy (.bss).
const storageSymbols = symbolSizes(DEFAULT_ELF, (name) => name.startsWith('_ZN8firmware5flash'));

// ---- report ----
const passing = rates.filter((r) => r.ok === r.lines);
const best = passing[passing.length - 1];
const rateRows = rates
  .map((r) => {
    const offered = Number.isFinite(r.offered)
      ? `${fmt(r.offered)}/s`
      : `back to back (wire limit ${fmt(r.wireLinesPerSecond)}/s)`;
    const outcome =
      r.ok === r.lines
        ? 'all `ok`'
        : `refused lines; ${r.droppedBytes} bytes lost in the UART FIFO; first error: \`${r.errors[0] ?? ''}\``;
    const accepted =
      r.ok === r.lines ? `${fmt(r.linesPerSecond)}/s` : `${r.ok} of ${r.lines} lines`;
    return `| ${offered} | ${accepted} | ${outcome} |`;
  })
  .join('\n');
const stat = (values) => {
  const sum = values.reduce((a, b) => a + b, 0);
  return { mean: sum / values.length, min: Math.min(...values), max: Math.max(...values) };
};
const small = stat(latencySmall);
const frameFast = stat(frameFastUs);
const frameSlow = stat(frameSlowUs);
const smallFast = stat(latencySmallFast);
const jump = stat(latencyJump);
const smallUsb = stat(latencySmallUsb);
const jumpUsb = stat(latencyJumpUsb);
const usbRateRows = usbRates
  .map((r) => {
    const offered = Number.isFinite(r.offered)
      ? `${fmt(r.offered)}/s`
      : 'all at once (as fast as the firmware takes them)';
    const outcome =
      r.ok === r.lines
        ? 'all `ok`'
        : `${r.ok} of ${r.lines} \`ok\`; first other reply: \`${r.errors[0] ?? ''}\``;
    return `| ${offered} | ${fmt(r.linesPerSecond)}/s | ${outcome} |`;
  })
  .join('\n');
const usbBest = usbRates
  .filter((r) => r.ok === r.lines)
  .reduce((a, r) => (a && a.linesPerSecond > r.linesPerSecond ? a : r), null);
const rel = (path) => relative(REPO, path);

const headlineRows = Object.entries({ ...HEADLINES, ...BENCH_HEADLINES })
  .map(([name, what]) => {
    const on = withCache.figures[name];
    const off = noCache.figures[name];
    const digits = name.endsWith('Percent') ? 1 : 0;
    return `| ${what} | ${fmt(on, digits)} | ${fmt(off, digits)} | ${(on / off).toFixed(2)}x |`;
  })
  .join('\n');
const xipIk = withCache.xip;
const missCycles = 46;

const report = `# Benchmarks

Written by \`./dev bench\` (${new Date().toISOString().slice(0, 10)}). Everything is measured in the rp2040js emulator (1.4.1, boot ROM B1)
running the release ELFs \`cargo fw\` builds: cycle counts and emulated time are those of the
emulated Cortex-M0+ at 125 MHz, so **they are the same on every machine and every run** (the
wall-clock time the run takes is irrelevant). The emulator counts documented M0+ instruction
timings. rp2040js charges nothing for reading the flash; the harness's model of the RP2040's
XIP cache (below) charges what a Pico's cache misses cost, and **every figure here is measured
with it**, as every test and \`./dev run\` runs. The headline figures come first, with the
cache modelled and without (the best case: all code and tables already in the cache, or in
RAM), so the difference is visible.

## Headline figures: the XIP flash cache modelled, and not

| | XIP cache modelled | no cache model | ratio |
|---|---:|---:|---:|
${headlineRows}

Measured on the first ${HEADLINE_SIZES.poses} poses of the IK benchmark (seed ${args.seed}), ${HEADLINE_SIZES.streamPoses} for the clamp and the
tracker, ${HEADLINE_SIZES.lines} \`pose\` lines of the streaming path sent one at a time (each waits for its \`ok\`) for
a line's CPU cycles, ${HEADLINE_SIZES.frames} stream frames, ${HEADLINE_SIZES.latencyLines} \`pose\` lines for the latency, and the longest-pass
session of "The longest main-loop pass" (\`src/bench/headline.js\`). The IK "in the benchmark
sequence" follows the previous pose's other IK variants (which evict much of it); "cold"
empties the cache as it starts; "warm" is the same IK run again at once (the benchmark
firmware's \`i\`). ${
  xipIk.accessesPerIk > 0
    ? `The firmware's IK touches ${fmt(xipIk.accessesPerIk)} flash words per IK in the sequence, ${fmt(
        (100 * xipIk.hitsPerIk) / xipIk.accessesPerIk,
        1,
      )} % of them hits.`
    : "The firmware's IK reads no flash at all (its code and tables run from RAM: `memory.x`), so the cache cannot slow it."
}

Targets with the cache modelled (issue 23): the IK at most 8,000 cycles, a tracker frame at most
15,000, a \`pose\` line at most 30,000 CPU cycles, a 5 mm jump to the PWM under 1 ms ("Command to
output" below), a \`pose\` line to PWM under 500 us at 115,200 baud, a stream frame to PWM under
200 us at 921,600 baud, a main-loop pass under 1 ms (125,000 cycles), the stream pipeline's
worst case under 30 % of the CPU at 333 Hz. \`./dev test\` checks these figures (on fewer poses, \`GUARD_SIZES\`) against
\`emulator/bench-guard.json\`: any more than ${GUARD_TOLERANCE * 100} % above its committed value fails
(\`test/bench-guard.test.js\`); \`./dev bench --update-guard\` rewrites the table when a change is
meant. The same test also fails on a figure past its target (the IK, a tracker frame, the two
latencies, the longest pass; and a \`pose\` line's cycles over 200 lines, as here), so no figure
can creep past a target within the table's tolerance.

### The cache model (\`emulator/src/gaps/xip-cache.js\`, gap 13)

- **Geometry**: 16 kB, two-way set-associative, 8-byte lines: 1,024 sets (RP2040 datasheet
  2.6.3.1, and 2.6.3.2's flush length "16 kB total size / 8 bytes per line / 2 ways per set");
  a hit takes one cycle (2.6.3.1), as rp2040js charges every access already.
- **Replacement**: the least recently used way of the set (an invalid way first). The
  datasheet sections read for the model do not state a policy: an assumption, which the
  counters on a Pico can check.
- **Fill**: one 32-bit half of the 8-byte line per miss (a valid bit per half): boot2 sets the
  SSI to 32-bit frames (\`CTRLR0.DFS_32\` 31) and one frame per transfer (\`CTRLR1.NDF\` 0,
  "single 32b read" in \`boot2_w25q080.S\`); measured on chips in raspberrypi/pico-feedback#307
  ("lines are 8 but filled one half at a time") and Klipper PR #6464 ("a 32bit flash read takes a
  minimum of 320ns (20 flash cycles, 2 cpu cycles per each flash cycle)").
- **Miss cost: ${missCycles} cycles**, computed from the SSI registers the firmware's boot2
  (\`rp2040_boot2::BOOT_LOADER_W25Q080\`, rp2040-boot2 0.3, assembled with
  \`PICO_FLASH_SPI_CLKDIV=2\`) programs: SCK = clk_sys / 2 (\`BAUDR\` 2); quad I/O continuous read
  (0xEB once in boot2, then no instruction: \`SPI_CTRLR0.INST_L\` 0, mode bits 0xA0 in \`XIP_CMD\`);
  24 address bits and 8 mode bits in quad (\`ADDR_L\` 8, \`TRANS_TYPE\` 2C2A): 8 SCK; 4 dummy SCK
  (\`WAIT_CYCLES\` 4); 32 data bits in quad: 8 SCK. 20 SCK = 40 cycles, + 1 (\`RX_SAMPLE_DLY\`),
  + 5 assumed for the bus and the SSI (the XIP block takes the miss and starts the SSI, chip
  select a clock ahead of SCK, the data back through the cache to the bus).
- **What goes through it**: every read the core makes in the flash window: instruction fetches
  (the M0+ fetches a 32-bit word: one access per word of straight code, and after each jump;
  the word it prefetches after a taken branch is not modelled) and loads (literal pools,
  tables, \`.rodata\`, the vector table). The aliases 0x11/0x12/0x13.. and \`CTRL.EN\` behave as
  2.6.3.1 says; \`FLUSH\` and the ROM's \`flash_flush_cache\` (after a \`save\`) empty it (1,024 cycles).
- **Check it on a Pico**: the counters \`CTR_HIT\` and \`CTR_ACC\` (XIP_CTRL 0x1400000c, 0x14000010)
  are modelled; the benchmark firmware's \`x\` prints and clears them, so \`x\`, a line, \`x\` on a
  Pico gives that line's flash accesses and hits. In the emulator, \`x\` around one \`p\` line (all
  IK variants, the line's handling): ${
    xipIk.xipCounters
      ? `hit=${xipIk.xipCounters.hits} acc=${xipIk.xipCounters.accesses}`
      : 'not available'
  }.
- **Not modelled**: the M0+'s discarded prefetch after a taken branch, the second core and DMA
  (not used), the streaming FIFO; boot2 itself runs from SRAM on the chip and is not charged.

The emulator runs with the model by default: every end-to-end test (with their timing bounds), every table
below and \`./dev run\`. \`HEXAPOD_XIP_CACHE=off\`, a board's \`xipCache: false\` or
\`./dev run --no-xip-cache\` takes it out (the "no cache model" column).

## IK: pose -> six pulse widths

The firmware's own IK (\`kinematics_core::ik::Solver::solve\` with
\`firmware::rom_math::RomMath\`, the code path \`control::Controller\` runs for every pose:
rotation, six legs, six pulse widths, limits) in a benchmark firmware
(\`firmware/src/bin/bench.rs\`) that shares the same code. GP16 is high exactly while one IK
runs; the harness reads the emulator's cycle counter at its edges and subtracts an empty bracket
(the marker's own cost). ${ik.poses} random poses reachable within the default servo limits
(seed ${args.seed}, from \`cargo run -p host-tests --example bench_poses\`).

The IK runs in fixed point (\`kinematics_core::fixed\`): the pose's sines and cosines (table and
sum formulas), the leg terms of eq. 9 within 2^29 steps, the discriminant exactly, its square
root (Newton-Raphson) and the half-angle arc tangent (table, exact rotation, series), the pulses
of eq. 13, 14: integer instructions only, no float routine at all. The other rows are the same
IK with another library's routines in place of the three integer ones
(\`kinematics_core::FloatRoutines\`: arguments converted to \`f32\` and back), each with its own
solver (home angles from its own routines), so the choice of routines is a measured one.

| | cycles per IK, mean | min | max | us at 125 MHz (mean) | max error vs f64 |
|---|---:|---:|---:|---:|---:|
| **firmware: the core's fixed-point routines** | **${fmt(firmware.mean)}** | **${fmt(firmware.min)}** | **${fmt(firmware.max)}** | **${fmt(us(firmware.mean), 1)}** | **${firmware.worstVsRef.toExponential(2)} us** |
| before: boot ROM float routines called directly (commit ${BEFORE_ROM.commit}, measured once) | ${fmt(BEFORE_ROM.mean)} | ${fmt(BEFORE_ROM.min)} | ${fmt(BEFORE_ROM.max)} | ${fmt(us(BEFORE_ROM.mean), 1)} | ${BEFORE_ROM.worstUs.toExponential(2)} us |
| before that: ROM through rp2040-hal's wrappers (commit ${BEFORE.commit}, measured once) | ${fmt(BEFORE.mean)} | ${fmt(BEFORE.min)} | ${fmt(BEFORE.max)} | ${fmt(us(BEFORE.mean), 1)} | |
${ik.variants
  .slice(1)
  .map(
    (v) =>
      `| ${VARIANT_ROWS[v.name] ?? v.name} | ${fmt(v.mean)} | ${fmt(v.min)} | ${fmt(v.max)} | ${fmt(us(v.mean), 1)} | ${v.worstVsRef.toExponential(2)} us${v.worstVsRef > TARGET_US ? ' (beyond the target)' : ''}${v.refused ? `, ${v.refused} poses refused` : ''} |`,
  )
  .join('\n')}

Speed-up: ${fmt(BEFORE_ROM.mean / firmware.mean, 2)}x over the ROM routines (commit ${BEFORE_ROM.commit}), ${fmt(BEFORE.mean / firmware.mean, 2)}x over the firmware before them. Target: at most 8,000 cycles (issue 23; 12,000 before), at no loss of accuracy (at most ${TARGET_US} us against the f64 reference; it was ${BEFORE_ROM.worstUs.toExponential(2)} us).

Where the firmware's cycles go (per IK, ${PROFILE_POSES} poses, instruction by instruction; the
routines by their symbols' address ranges):

| | cycles | calls |
|---|---:|---:|
${profile.map((row) => `| ${row.name} | ${fmt(row.cycles)} | ${row.calls ? fmt(row.calls, 1) : ''} |`).join('\n')}

The same IK on the boot ROM's float routines (the \`rom\` row), for comparison:

| | cycles | calls |
|---|---:|---:|
${romProfile.map((row) => `| ${row.name} | ${fmt(row.cycles)} | ${row.calls ? fmt(row.calls, 1) : ''} |`).join('\n')}

(At commit ${BEFORE_ROM.commit}, with float arithmetic in the hot loop too: ${BEFORE_ROM.profile}.)

Accuracy, largest pulse-width difference over the ${ik.poses} poses:

| | max error |
|---|---:|
| firmware on the chip vs independent f64 reference (\`host-tests/src/reference.rs\`, numeric) | ${firmware.worstVsRef.toExponential(2)} us |
| firmware on the chip vs the host's IK (\`libm\` build, same fixed-point path) | ${ik.firmwareVsHost.differing === 0 ? 'identical bits for every pose' : `${ik.firmwareVsHost.differing} poses differ, by up to ${ik.firmwareVsHost.worst.toExponential(2)} us`} |

Target: at most ${TARGET_US} us (one PWM count is 0.32 us). An \`f32\` pulse near 1500 us has steps
of 1.2e-4 us, so half a step, 6.1e-5 us, is the least any \`f32\` result can be off.

The routines themselves on the chip, largest error against \`libm\`'s \`f64\` over a grid
(\`m\` in \`firmware/src/bin/bench.rs\`; sin and cos on [-pi, pi], sqrt relative (the integer
one's absolute), atan2 all round the circle), and the IK's error with each of \`micromath\`'s
alone in place of the integer one (the rows above):

| routine | fixed point (firmware; bound tested on the host) | boot ROM \`f32\` | \`micromath\` | IK with \`micromath\`'s alone | enough for ${TARGET_US} us? |
|---|---:|---:|---:|---:|---|
${['sin', 'cos', 'sqrt', 'atan2']
  .map((routine, k) => {
    const alone = variant(MICROMATH_ALONE[routine]);
    const fixed =
      k === 2
        ? `${ik.mathErrors.fixed[k].toFixed(2)} (bound: 1)`
        : `${ik.mathErrors.fixed[k].toExponential(1)} (bound: 1.9e-9)`;
    const sqrtUnit = k === 2 ? ' (relative)' : '';
    return `| ${routine} | ${fixed} | ${ik.mathErrors.rom[k].toExponential(1)}${sqrtUnit} | ${ik.mathErrors.micromath[k].toExponential(1)}${sqrtUnit} | ${alone.worstVsRef.toExponential(1)} us | ${alone.worstVsRef <= TARGET_US ? 'yes' : 'no'} |`;
  })
  .join('\n')}

\`micromath\` (2.1) is not accurate enough for the IK anywhere: each of its routines alone puts
the pulses microseconds off (its sines are off by about 1e-3, its square root by several per
cent), hundreds of times the target; nor is it faster here, since its routines compute in \`f32\`
(library calls on this chip) where the integer ones need none. The firmware does not use it; it
is an optional dependency of the benchmark only (feature \`micromath\` of the \`firmware\` crate).

## The stream pipeline: clamping and tracking

The firmware's own \`control::Controller<RomMath>\` in the benchmark firmware, fed binary stream
frames (\`c\` and \`k\` in \`firmware/src/bin/bench.rs\`), on the first ${stream.poses} poses:

| | cycles, mean | min | max | us at 125 MHz (mean) | share of a 333 Hz frame (max) |
|---|---:|---:|---:|---:|---:|
| clamp: a frame ${CLAMP_DZ_MM} mm above the pose, out of reach, in pass-through (\`Controller::apply_stream\` and the clamp job it starts, run to its end: 1 + \`CLAMP_STEPS\` = 7 IK solutions, bisection on the straight line, at most \`CHECKS_PER_SLICE\` = 3 per main-loop pass; ${stream.clamp.clamped} of ${stream.poses} clamped) | ${fmt(stream.clamp.mean)} | ${fmt(stream.clamp.min)} | ${fmt(stream.clamp.max)} | ${fmt(us(stream.clamp.mean), 1)} | ${fmt((100 * stream.clamp.max) / FRAME_333_CYCLES, 1)}% |
| tracker frame: \`Controller::on_frame\` while streaming with the tracker's limits on (\`Tracker::step\` on six axes and one IK; ${stream.track.moved} of ${stream.track.frames} frames) | ${fmt(stream.track.mean)} | ${fmt(stream.track.min)} | ${fmt(stream.track.max)} | ${fmt(us(stream.track.mean), 1)} | ${fmt((100 * stream.track.max) / FRAME_333_CYCLES, 1)}% |
${stream.trackClamped.frames > 0 ? `| tracker frame whose step left the workspace: the step and its IK, which fails, so the tracker holds a step short of the edge (the goal itself was clamped when it came; ${stream.trackClamped.frames} of ${stream.track.frames} frames) | ${fmt(stream.trackClamped.mean)} | ${fmt(stream.trackClamped.min)} | ${fmt(stream.trackClamped.max)} | ${fmt(us(stream.trackClamped.mean), 1)} | ${fmt((100 * stream.trackClamped.max) / FRAME_333_CYCLES, 1)}% |\n` : ''}
A clamp's IK solutions that fail stop at the first leg that cannot reach, so a clamp costs less
than 7 full IKs. The tracker's step computes in integers (fixed point, an exact discrete braking
rule with an integer square root and two divisions per axis: \`control/src/tracker.rs\`); the
IK is most of a frame's cycles. (The \`f32\` step before it: 37,394 cycles a frame, measured
once.) \`node emulator/src/bench/quick-bench.js tracker-profile\` shows where a frame's cycles go.

## The rest of the kinematics

The same benchmark firmware and poses, each computation with \`RomMath\` bracketed by the
marker like the IK (\`firmware/src/bin/bench.rs\`, commands \`f\`, \`j\`, \`q\`, \`w\`):

| | cycles, mean | min | max | ms at 125 MHz (mean) |
|---|---:|---:|---:|---:|
| forward kinematics: six pulses -> pose, from the previous frame's pose (\`forward::Closure::pulses\` + \`forward::solve\`; ${fmt(kin.fk.iterations.mean, 2)} iterations on average, at most ${kin.fk.iterations.max}: ${histogram}) | ${fmt(kin.fk.mean)} | ${fmt(kin.fk.min)} | ${fmt(kin.fk.max)} | ${fmt(us(kin.fk.mean) / 1000, 3)} |
| servo Jacobian (\`jacobian::Jacobian::at\`: the IK, the arm tips, six rows) | ${fmt(kin.jacobian.mean)} | ${fmt(kin.jacobian.min)} | ${fmt(kin.jacobian.max)} | ${fmt(us(kin.jacobian.mean) / 1000, 3)} |
| holding torques of a payload from the pose (\`statics::holding_loads\`: the IK, the Jacobian, a 6x6 solve) | ${fmt(kin.torque.mean)} | ${fmt(kin.torque.min)} | ${fmt(kin.torque.max)} | ${fmt(us(kin.torque.mean) / 1000, 3)} |
| the same from the IK's arm angles (\`statics::servo_holding_torques\`, no IK) | ${fmt(kin.torque.fromAngles.mean)} | ${fmt(kin.torque.fromAngles.min)} | ${fmt(kin.torque.fromAngles.max)} | ${fmt(us(kin.torque.fromAngles.mean) / 1000, 3)} |
| \`limits\`: the reach along all 12 axis-directions within the servo limits (\`workspace::Limits\`, ${fmt(kin.limits.tests.mean)} IKs on average, ${kin.limits.tests.min} to ${kin.limits.tests.max}; first ${kin.limits.poses} poses) | ${fmt(kin.limits.mean)} | ${fmt(kin.limits.min)} | ${fmt(kin.limits.max)} | ${fmt(us(kin.limits.mean) / 1000, 1)} |

Targets: forward kinematics under 150,000 cycles (1.2 ms), in at most 8 iterations. Each
iteration evaluates the six closures (no IK) and at most one Jacobian and one 6x6
factorisation, so a firmware can run one per main-loop pass (\`forward::Newton::step\`), and
\`limits\` one IK per step (\`workspace::Limits::step\`).

Accuracy on the chip, against the f64 reference (\`host-tests\`, via \`bench_poses\`):

| | largest error |
|---|---:|
| forward kinematics from the f64 reference's pulses, vs the pose they came from | ${kin.fk.worstMm.toExponential(1)} mm, ${kin.fk.worstRad.toExponential(1)} rad (per coordinate) |
| servo Jacobian vs f64 central finite differences (per row and half, relative to its largest entry) | ${kin.jacobian.worst.toExponential(1)} |
| holding torques vs f64 \`J^T tau = w\` with a finite-difference \`J\` (relative to the largest) | ${kin.torque.worst.toExponential(1)} |

Payload of the torque benchmark: 1 kg, 30 mm above the platform's centre.

## Command to output

The real firmware (\`target/thumbv6m-none-eabi/release/firmware\`), echo off, speed limits off
(jumps, the streaming mode). Latency is from the last byte (LF) of a \`pose\` line entering the
UART's RX FIFO to the moment all six new compare values have been written to the PWM registers
(the wait for the UART's receive interrupt, which the PL011 raises at the firmware's FIFO level
or, for a line's last bytes below that level, after its receive timeout of 32 bit periods:
278 us at 115,200 baud, 35 us at 921,600; then parse, validation, IK of the target and its
path check, reply, write); the harness hooks the emulator's PWM register writes. The registers are double-buffered: the pulses change at the
next PWM period start (at most one frame, 20 ms at 50 Hz, later; no pulse is cut short).

| pose lines | latency mean | min | max |
|---|---:|---:|---:|
| streaming steps (${latencySmall.length} lines, <= 0.5 mm / 0.25 deg apart: one IK) at 115,200 baud | ${fmt(small.mean)} us | ${fmt(small.min)} us | ${fmt(small.max)} us |
| the same at 921,600 baud | ${fmt(smallFast.mean)} us | ${fmt(smallFast.min)} us | ${fmt(smallFast.max)} us |
| 5 mm jumps (path checked every 0.5 mm: 10 IKs) | ${fmt(jump.mean)} us | ${fmt(jump.min)} us | ${fmt(jump.max)} us |

Target: under 500 us (a 5 mm jump: under 1 ms). With a speed limit set, the first step of a move comes with the next
servo frame instead (up to one frame later), so that no frame moves more than the limit.

## Stream frames

Binary frames (\`A5 5A\`, six 16-bit counts, \`0D 0A\`; docs/streaming.md), echo off, all
speed and acceleration limits off (pass-through):
from the frame's last byte entering the UART to all six new compare values written.

| binary frames | latency mean | min | max |
|---|---:|---:|---:|
| 40 frames of small steps at 921,600 baud | ${fmt(frameFast.mean)} us | ${fmt(frameFast.min)} us | ${fmt(frameFast.max)} us |
| the same at 115,200 baud | ${fmt(frameSlow.mean)} us | ${fmt(frameSlow.min)} us | ${fmt(frameSlow.max)} us |

Target: under 200 us at 921,600 baud.

Frames sent evenly for 0.5 s at 921,600 baud (the wire carries 5,760 frames/s), pass-through:
${frameRate.results.map((r) => `${fmt(r.framesPerSecond)}/s: ${r.applied}/${r.sent} applied`).join('; ')}.
Highest rate tried with every frame applied: **${frameRate.best ? `${fmt(frameRate.best.framesPerSecond)} frames/s` : 'none'}**
(above it the newest frame wins: frames arriving while one is applied are superseded, never
queued).

The whole stream pipeline with clamping active: \`frame_hz 333\`, the tracker on
(200 mm/s, 2000 mm/s^2, 200 deg/s, 2000 deg/s^2), every frame's target beyond the workspace
(so each is clamped by bisection: up to 7 IK solutions), the tracker stepping every 3 ms; x
and z moving (the other four axes still, as when a sim drives fewer axes: an axis at rest on
its target costs the tracker nothing), and all six moving every frame; then the honest worst
case (issue 23): all six moving with z just past the servo limits (14.3 to 14.9 mm, the reach
from home 13.99 mm: each target fails only after a full IK, where targets far out of reach fail
at the first leg), with a payload of 2 kg 30 mm above the centre and torque ratings of 20 kgf cm
(the servo limit stays the boundary, but every target within reach and the furthest drivable
pose of every clamp have their holding torques checked: \`measureStreamCpu\`'s \`edge\`,
\`src/bench/stream-bench.js\`; alone: \`node emulator/src/bench/quick-bench.js edge\`, and
where its cycles go, per function: \`edge-profile\`). There the platform stays at the edge, so
most clamps find nothing to drive and few poses have their torques checked; the last rows are
the other extreme, z in and out of reach in turn (8 mm, then just past the limits): every
clamp starts inside and finds a drivable pose, and every other target is within reach, so
every frame's target has its torques checked (\`measureStreamCpu\`'s \`inOut\`):

| axes moving | frames in | CPU busy | cycles per servo frame | frames applied / clamped | longest pass |
|---|---|---:|---:|---:|---:|
${streamCpu
  .map(
    (run) =>
      `| ${run.inOut ? 'all six, z in and out of reach in turn, payload and ratings' : run.edge ? 'all six, z just past the servo limits, payload and ratings' : run.allAxes ? 'all six' : 'x, z'} | ${run.framesPerSecond}/s | ${fmt(run.cpuShare * 100, 1)} % | ${fmt(run.cyclesPerServoFrame)} | ${run.applied} / ${run.clamped} | ${fmt(run.longestPassCycles)} cycles = ${fmt(us(run.longestPassCycles))} us |`,
  )
  .join('\n')}

Target: under 30 % of the CPU at 333 Hz with clamping active (all six axes moving:
${fmt(streamCpu333.cpuShare * 100, 2)} %; just past the servo limits with a payload and ratings:
${fmt(streamCpuEdge333.cpuShare * 100, 2)} %; in and out of reach in turn:
${fmt(streamCpuInOut333.cpuShare * 100, 2)} %). A tracker frame's own step is integer arithmetic
(\`control/src/tracker.rs\`); the IK is most of it.

## Sustained pose lines per second

${lines.length} \`pose\` lines of a smooth path (${fmt(bytesPerLine, 1)} bytes each on average), echo off, speeds off, at ${fmt(STREAM_BAUD)}
baud, sent evenly spaced at the offered rate without waiting for replies; every line must get
\`ok\` (and no byte may be lost).

| offered | accepted and applied | outcome |
|---|---:|---|
${rateRows}

Highest rate with every line accepted: **${best ? fmt(best.linesPerSecond) : 'none'} lines/s**. A host that waits for each \`ok\` before
sending the next line gets ${fmt(lockStep.linesPerSecond)} lines/s (${lockStep.ok}/${lockStep.lines} ok). Target: at least 1,000 lines/s.

## USB serial

The same firmware with a USB host on its USB port (\`emulator/src/gaps/usb.js\`, gaps
9-12): the host has enumerated the firmware and opened the port, echo off there, speed limits
off. The host's packets share a full-speed bus of at most ${BULK_PACKETS_PER_FRAME} bulk packets of 64 bytes
per 1 ms frame, each transaction holding the bus for 1/${BULK_PACKETS_PER_FRAME} ms whatever its length (a short
packet is shorter on the wire: these figures err on the slow side). rp2040js itself counts an
armed IN packet as sent at once, which would flatter the firmware; here the host takes it in
its bus slot. Not in these figures: the host's own latency (its USB controller's scheduling
and its OS, typically up to a millisecond or two each way on a PC), which the firmware cannot
change.

Latency, from the USB packet carrying a \`pose\` line's end reaching the firmware's endpoint
buffer to all six new compare values written to the PWM registers (the USB interrupt, the
line's parse and check, its IK and path check, the reply, the write):

| pose lines over USB | latency mean | min | max |
|---|---:|---:|---:|
| streaming steps (${latencySmallUsb.length} lines, one IK each) | ${fmt(smallUsb.mean)} us | ${fmt(smallUsb.min)} us | ${fmt(smallUsb.max)} us |
| 5 mm jumps (10 IKs) | ${fmt(jumpUsb.mean)} us | ${fmt(jumpUsb.min)} us | ${fmt(jumpUsb.max)} us |

Sustained: the ${fmt(lines.length)} \`pose\` lines above, sent by the host at the offered rate without
waiting for replies. USB loses nothing: what the firmware cannot take yet waits in the host
(flow control), so every line gets \`ok\` and the rate is the firmware's own: lines answered
per second from the first line sent to the last reply.

| offered | answered | outcome |
|---|---:|---|
${usbRateRows}

Highest rate with every line answered \`ok\`: **${usbBest ? fmt(usbBest.linesPerSecond) : 'none'} lines/s**, the firmware's limit
(the bus could carry about ${fmt((BULK_PACKETS_PER_FRAME * 64 * 1000) / bytesPerLine)}/s of these lines). A host that waits for each \`ok\`
before sending the next line gets ${fmt(usbLockStep.linesPerSecond)} lines/s (${usbLockStep.ok}/${usbLockStep.lines} ok).

What USB costs: the firmware just before its merge (commit ${WITHOUT_USB.commit}, UART0 only) took
${fmt(WITHOUT_USB.flash)} bytes of flash and ${fmt(WITHOUT_USB.ram)} of static RAM, the merge (${WITH_USB.commit}) ${fmt(WITH_USB.flash)} and
${fmt(WITH_USB.ram)} (both measured once): **${fmt(usbFlash)} bytes of flash and ${fmt(usbRamTotal)} of static RAM** for USB serial (usb-device,
usbd-serial, rp2040-hal's USB driver, \`firmware/src/usb_serial.rs\`, the second link in the
main loop). In this firmware, the symbols named for USB hold ${fmt(usbCode)} bytes of code (the rest is inlined
into callers, descriptors and tables) and ${fmt(usbRam)} bytes of RAM: the receive queue (1 KB), the
transmit queue (4 KB), usbd-serial's two 128-byte buffers and the USB device's state.

## The longest main-loop pass vs the watchdog and the frames

No command keeps the main loop: work that is long is done a slice per pass (a path check
\`control::controller::CHECKS_PER_SLICE\` poses at a time, a listing a line at a time), so frames, the
watchdog and the links are served between slices, and a command's reply comes when its work
is done. The bound a pass must stay under is **1 ms** (125,000 cycles): a third of the 3 ms
frame at the highest frame rate (333 Hz), so a frame's new pulses (one IK, ${fmt(us(firmware.mean) / 1000, 2)} ms) are always
written well before the next period starts; the ${WATCHDOG_MS} ms watchdog is 500 times as long.

| | longest pass | frames | missed |
|---|---:|---:|---:|
| the longest command: a move whose path check solves the IK at every one of ${worst.checks} frames (the budget, \`control::motion::MAX_PATH_CHECKS\`), 20.48 mm at 1 mm/s, 50 Hz; its line end to its reply's last byte at the host: ${fmt(worst.micros / 1000, 1)} ms (${fmt(worst.cycles)} cycles) | ${fmt(worst.longestPassCycles)} cycles = ${fmt(worst.longestPassCycles / 125, 0)} us | ${worst.frames} | ${worst.missed} |
| ${passes.lines} lines: every long command class back to back at 333 Hz with echo on (checks of 1,000 poses, config, help, geometry, status, geometry changes, defaults, a move checked while moving, refusals), then 20 moves of 1,000 checks each in flight at 921,600 baud | **${fmt(passes.longestPassCycles)} cycles = ${fmt(passes.longestPassCycles / 125, 0)} us** | ${passes.frames} | ${passes.missed} |
| both links at once, 333 Hz: ${passesBoth.lines} lines, UART0 pipelining moves of 1,000 checks at 921,600 baud while USB (echo on) pipelines listings and checks of 1,000 poses | **${fmt(passesBoth.longestPassCycles)} cycles = ${fmt(passesBoth.longestPassCycles / 125, 0)} us** | ${passesBoth.frames} | ${passesBoth.missed} |

The longest interrupt handler over the UART0 session: ${fmt(passes.longestHandlerCycles)} cycles; over the session on
both links (the USB interrupt among them): ${fmt(passesBoth.longestHandlerCycles)} cycles. A pass is
measured from one watchdog feed to the next (the loop feeds it at its top), in CPU cycles, which
the emulator does not count while the core sleeps; interrupt handlers inside a pass count in it.
A missed frame is a frame period in which the firmware wrote no new compare values
(\`emulator/src/chip/loop-meter.js\`); \`emulator/test/main-loop.test.js\` asserts the bound and no
missed frame for these cases and others.

### \`servo\`, \`limits\` and torque-checked paths

The real firmware, echo off, 921,600 baud, 333 Hz (the path checks at 50 Hz): each
command's line end to its reply at the host, the CPU cycles the firmware spent meanwhile, and the longest main-loop pass. \`servo\`
finds the pose of the six pulses (forward kinematics along a continuation, arm angles in steps
of at most 5 degrees from the pose the platform was at, \`control::controller::FK_STEP_RAD\`;
a Newton iteration per pass, then the IK's check); \`status\` shows that pose (found by
\`servo\`) and, with a payload, the holding torques (a pass of their own). \`limits\` and
path checks solve \`CHECKS_PER_SLICE\` IKs per pass, or, with a payload and torque ratings,
one pose and its holding torques per pass. Payload: 2 kg, 30 mm above the platform's centre.

| command | line end to reply | CPU cycles | longest pass | frames missed |
|---|---:|---:|---:|---:|
${kinCommands
  .map(
    (c) =>
      `| ${c.what} | ${fmt(c.micros / 1000, 2)} ms | ${fmt(c.cycles)} | ${fmt(c.longestPassCycles)} cycles = ${fmt(c.longestPassCycles / 125, 0)} us | ${c.missed} of ${c.frames} |`,
  )
  .join('\n')}
| ${clampedStream.sent} pass-through stream frames at 921,600 baud beyond the ratings (rated 1 kgf cm): ${clampedStream.applied} applied, ${clampedStream.clamped} clamped, a pose with its torques per pass | - | - | ${fmt(clampedStream.longestPassCycles)} cycles = ${fmt(clampedStream.longestPassCycles / 125, 0)} us | ${clampedStream.missed} of ${clampedStream.frames} |

Longest pass of these: **${fmt(kinLongest)} cycles = ${fmt(kinLongest / 125, 0)} us** (bound: 125,000 cycles).

### Blends and the servos' rated speed

The real firmware at 333 Hz, echo off, 115,200 baud, speed limits 100 mm/s and 60 deg/s,
acceleration limits 200 mm/s^2 and 120 deg/s^2: new targets while moving (each a blend from the
motion in progress, checked while it goes on), then the same with the servos' rated speed set
(0.1 s per 60 degrees, servo 4 0.3 s: every path measured against the ratings), then a stream
stepped by the tracker within the ratings (\`measureMotionLimitsPass\`, \`src/bench/firmware-bench.js\`).

| session | lines answered \`ok\` | longest pass | frames missed |
|---|---:|---:|---:|
${motionLimits.phases
  .map(
    (p) =>
      `| ${p.what} | ${p.lines ? `${p.ok} of ${p.lines}` : '-'} | ${fmt(p.longestPassCycles)} cycles = ${fmt(p.longestPassCycles / 125, 0)} us | ${p.missed} of ${p.frames} |`,
  )
  .join('\n')}

Longest pass of these: **${fmt(Math.max(...motionLimits.phases.map((p) => p.longestPassCycles)))} cycles** (bound: 125,000 cycles).

## Saving the settings: the one long pass

A \`save\` erases one 4 KiB flash sector and programs one 256-byte page through the boot ROM,
from RAM with interrupts masked (flash cannot be read meanwhile), alone in its main-loop pass:
that pass is over the 1 ms bound by design, the watchdog is given 2 s around it, and the PWM
hardware holds the pulses (a save is refused while the platform moves). The emulator times the
flash as the W25Q80DV datasheet gives it (gaps/flash.js, gap 7), the core busy in the ROM
meanwhile: sector erase ${saves[0].times.sectorEraseMs} ms typical, ${saves[1].times.sectorEraseMs} ms maximum; page program ${saves[0].times.pageProgramMs} ms typical, ${saves[1].times.pageProgramMs} ms maximum
(the other ROM calls and the SPI transfers are taken as instant). Echo off, 115,200 baud, 50 Hz.

| flash timing | the save's pass | the flash chip's part | the firmware's part | \`save\` line end to \`ok\` at the host | frames missed (pulses held) |
|---|---:|---:|---:|---:|---:|
${saves
  .map(
    (s) =>
      `| ${s.timing} | ${fmt(s.passCycles)} cycles = ${fmt(s.passCycles / 125e3, 1)} ms | ` +
      `${fmt(s.flashCycles)} cycles | ${fmt(s.passCycles - s.flashCycles)} cycles = ` +
      `${fmt((s.passCycles - s.flashCycles) / 125)} us | ${fmt(s.replyMicros / 1000, 1)} ms | ` +
      `${s.missed} of ${s.frames} |`,
  )
  .join('\n')}

In both runs the save's pass was the only one over 1 ms${saves.every((s) => s.longPasses === 1) ? '' : ` (NOT SO here: ${saves.map((s) => s.longPasses).join(' and ')} passes)`};
\`emulator/test/main-loop.test.js\` checks that every pass over 1 ms is a save's. The
firmware's part is the page built and read back and fast XIP restored by boot2 from RAM. No
input is read during the write: a host waits for \`save\`'s \`ok\` (docs/settings.md,
"Saving the settings").

## Motion cueing: telemetry packet to frame

\`hexapod cue\` against this firmware in the emulator (\`./dev run --pty --no-view\`,
\`frame_hz ${cue.frameHz}\`, speed limits off), fed ${fmt(cue.packets)} telemetry lines at ${cue.hz} Hz from a
loopback UDP socket (a gentle synthetic surge and roll in the documented telemetry format:
\`emulator/src/bench/cue-bench.js\`). The tool measures it itself: from the moment its socket
reader returns the packet (the host's monotonic clock) to the moment the port's \`write\` of the
frame made from it returns (\`cli/src/cue/run.rs\`). **Wall-clock times on the machine that
ran the bench, not emulated cycles**: the host's scheduler and load move them (this run:
load average ${cueLoad.toFixed(1)} on ${cpus().length} CPUs).

| frames | count | median | 99 % | max | min |
|---|---:|---:|---:|---:|---:|
| all (the tool's own summary) | ${fmt(cue.liveCount + cue.easingCount)} | ${ms(cue.median)} | ${ms(cue.p99)} | ${ms(cue.max)} | ${ms(cue.min)} |
${cueRow('live (following the telemetry)', fmt(cue.liveCount), cue.live)}
${cueRow('easing (the blend in at the start and home at the end)', fmt(cue.easingCount), cue.easing)}

Aim: under 2 ms. What makes the tail: frames never go faster than the board's frame rate, so
a sample that comes less than a frame (${fmt(1000 / cue.frameHz, 0)} ms) after the previous frame waits for the
next one (the sender's timing jitter; ${fmt(cue.late)} times a sample even replaced one still waiting);
while easing, frames go on the tool's own clock at the frame rate and a sample waits up to one
frame for its tick; and on a loaded host, the scheduler (the kernel wakes the tool's reader
thread, then its loop). The tool's own work (washout, limits, frame, write) is about the
minimum.

## Firmware size

From the ELF sections of \`${rel(DEFAULT_ELF)}\` (release, LTO):

| section | bytes |
|---|---:|
${Object.entries(fw.s)
  .map(([name, size]) => `| \`${name}\` | ${fmt(size)} |`)
  .join('\n')}
| **flash** (vector table + boot2 + text + rodata + data) | **${fmt(fw.flash)}** of 2,097,152 |
| **static RAM** (data + bss + uninit) | **${fmt(fw.ram)}** of 264 KiB |

The controller and UART0's transmit buffer live on the stack of \`main\` (not in the static
figure); the receive queues and USB's transmit queue are static. Stack high-water mark after
the worst-case command above (the deepest non-zero RAM word below the stack top; RAM starts
zeroed): **${fmt(stackBytes)} bytes**; on a board that booted and saved: ${fmt(saveStackBytes)} bytes.

The settings storage (\`save\`, \`control::store\` and \`control::record\`, the flash routines,
the power-up load and their words): commit ${WITH_STORAGE.commit}, which merged it in, against
commit ${BEFORE_STORAGE.commit} just before (both measured once with the same sums): flash
**+${fmt(WITH_STORAGE.flash - BEFORE_STORAGE.flash)} bytes**, static RAM **+${fmt(WITH_STORAGE.ram - BEFORE_STORAGE.ram)} bytes**. Its RAM by symbol:
${Object.entries(storageSymbols)
  .map(([name, size]) => `\`${name}\` ${fmt(size)} bytes`)
  .join(', ')} (the two routines also have their copy in flash, in \`.data\`'s load image).

## How to run

\`\`\`sh
./dev bench                  # builds, runs everything above, rewrites BENCHMARKS.md (a few minutes)
node emulator/src/bench/bench.js --poses 1000 --seed 7   # more poses, another seed
node emulator/src/bench/bench.js --cue-seconds 60        # a longer hexapod cue latency run
node emulator/src/bench/cue-bench.js 20                  # that run alone (JSON)
\`\`\`

Files: \`firmware/src/bin/bench.rs\` (IK, kinematics and stream benchmark firmware; \`./dev bench\`
builds it with \`--features micromath\`),
\`host-tests/examples/bench_poses.rs\` (poses, f64 reference pulses, Jacobians and torques), \`emulator/src/bench/ik-bench.js\`, \`emulator/src/bench/firmware-bench.js\`,
\`emulator/src/bench/cue-bench.js\` (\`hexapod cue\`'s latency), \`emulator/src/bench/bench.js\` (this report). \`emulator/test/rom-math.test.js\` runs a small IK
comparison in \`./dev test\` (no timing assertions).
`;
writeFileSync(args.out, report);
log(`wrote ${rel(args.out)}`);
log(
  `FK ${fmt(kin.fk.mean)} cycles (${fmt(kin.fk.iterations.mean, 2)} iterations), ` +
    `Jacobian ${fmt(kin.jacobian.mean)}, torque ${fmt(kin.torque.mean)}, limits ${fmt(kin.limits.mean)}`,
);
log(`servo/limits/torque: longest pass ${fmt(kinLongest)} cycles`);
log(
  `IK ${fmt(firmware.mean)} cycles (max ${fmt(firmware.max)}; micromath ${fmt(variant('micromath').mean)}), max error ${firmware.worstVsRef.toExponential(2)} us; clamp ${fmt(stream.clamp.mean)}, tracker frame ${fmt(stream.track.mean)} cycles; latency ${fmt(small.mean)} us (USB ${fmt(smallUsb.mean)} us); sustained ${best ? fmt(best.linesPerSecond) : 'none'} lines/s (USB ${usbBest ? fmt(usbBest.linesPerSecond) : 'none'}); worst command ${fmt(worst.micros / 1000, 1)} ms`,
);
