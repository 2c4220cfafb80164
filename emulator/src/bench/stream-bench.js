// Streaming benchmarks of the real firmware in the emulator (emulated time): binary stream
// frames' latency to the PWM registers, the highest frame rate at which every frame is
// applied, and the CPU the stream pipeline takes at 333 Hz with the tracker on and every
// target clamped. The frame format and settings are docs/streaming.md's.

import { binaryFrame, measureFrameLatency, streamingBoard } from './firmware-bench.js';

export { measureFrameLatency };

const CLOCK_HZ = 125e6;

function expectOk(board, line) {
  const { reply } = board.request(line);
  if (reply !== 'ok') {
    throw new Error(`${line}: ${reply}`);
  }
}

/** The `stream:` counters of `status`: { frames, applied, damaged, clamped, refused }. */
export function streamCounters(board) {
  const { reply, lines } = board.request('status');
  if (reply !== 'ok') {
    throw new Error(`status: ${reply}`);
  }
  const line = lines.find((l) => l.startsWith('# stream: '));
  return Object.fromEntries(
    line
      .slice('# stream: '.length)
      .split(' ')
      .map((kv) => kv.split('='))
      .map(([k, v]) => [k, Number(v)]),
  );
}

/** A small reachable pose's frame counts: x, z and yaw moving with `k`. */
function frameCounts(k) {
  return [
    32768 + (k % 40) * 100,
    32768,
    32768 + (k % 17) * 150,
    32768,
    32768,
    32768 + (k % 23) * 80,
  ];
}

/**
 * Binary frames sent evenly at `framesPerSecond` (pass-through) for `seconds`: how many were
 * received, applied, damaged. Every frame is applied when the firmware keeps up (the newest
 * frame wins, so a frame superseded before it was applied counts as not applied).
 */
export function measureFrameRate(framesPerSecond, { baud = 921600, seconds = 0.5 } = {}) {
  const { board } = streamingBoard({ baud });
  const before = streamCounters(board);
  const count = Math.round(framesPerSecond * seconds);
  const periodNanos = 1e9 / framesPerSecond;
  const start = board.nanos;
  for (let k = 0; k < count; k++) {
    board.runUntil(() => board.nanos >= start + k * periodNanos, { timeoutMs: 1000 });
    board.sendBytes(binaryFrame(frameCounts(k)));
  }
  board.runMs(20);
  const after = streamCounters(board);
  return {
    framesPerSecond,
    sent: count,
    frames: after.frames - before.frames,
    applied: after.applied - before.applied,
    damaged: after.damaged - before.damaged,
    droppedBytes: board.rxFifoDroppedBytes,
  };
}

/**
 * The highest of `rates` (frames per second, ascending) at which every frame sent was
 * received and applied; with the result for each rate tried.
 */
export function highestFrameRate(rates, options) {
  const results = [];
  let best = null;
  for (const rate of rates) {
    const r = measureFrameRate(rate, options);
    results.push(r);
    if (r.frames === r.sent && r.applied === r.sent && r.damaged === 0) {
      best = r;
    } else {
      break;
    }
  }
  return { best, results };
}

/**
 * The CPU the stream pipeline takes: frame_hz 333, the tracker on (speed and acceleration
 * limits set), binary frames at `framesPerSecond` whose targets lie beyond the workspace (z
 * far above reach, alternating with far below), so every frame's target is clamped and the
 * tracker runs every servo frame. Returns the share of the CPU's cycles executed (the core
 * does not count cycles while asleep in WFI) over `seconds` of streaming, and the counters.
 *
 * `edge`: the honest worst case instead (issue 23): z just past the servo limits (14.3 to 14.9
 * mm, where the default build's reach from home is 13.99 mm, a servo at its limit: found only
 * after a full IK, where targets far out of reach fail at the first leg), every axis moving,
 * and a payload with torque ratings (2 kg 30 mm above the centre, 20 kgf cm: the servo limit
 * stays the boundary, but every target within reach and the furthest drivable pose of every
 * clamp have their holding torques checked).
 *
 * `inOut` (with `edge`): z inside the reach (8 mm) and just past it in turn, so every clamp
 * starts inside and finds a drivable pose, whose holding torques are checked, and every other
 * target is within reach and checked too: a torque check for every frame's target, where
 * `edge` alone (the platform staying at the edge, its clamps finding nothing to drive) has few.
 *
 * `instrument`: `{ start(board), stop(board) }`, called around the measured stretch (a
 * profile of it: `quick-bench.js edge-profile`).
 */
export function measureStreamCpu({
  framesPerSecond = 100,
  seconds = 1,
  baud = 921600,
  allAxes = false,
  edge = false,
  inOut = false,
  instrument = null,
} = {}) {
  const { board } = streamingBoard({ baud });
  for (const line of [
    'set frame_hz 333',
    'set speed_mm_s 200',
    'set accel_mm_s2 2000',
    'set speed_deg_s 200',
    'set accel_deg_s2 2000',
    ...(edge
      ? ['set payload_g 2000', 'set payload_com_z_mm 30', 'set servos.torque_kgcm 20']
      : ['set stream.z_mm 200']),
  ]) {
    expectOk(board, line);
  }
  const before = streamCounters(board);
  const count = Math.round(framesPerSecond * seconds);
  const periodNanos = 1e9 / framesPerSecond;
  // Prime: the first target, then settle to the steady state before measuring.
  // x and z move (z far out of reach, so every target is clamped); with `allAxes` the other
  // four move too, so no axis of the tracker ever rests.
  const moving = (k, n, step) => (allAxes || edge ? 32768 + (k % n) * step : 32768);
  // z: far above reach and far below in turn, or (edge) just past the top of reach (the
  // default stream.z_mm, 15 mm full scale).
  const zEdgeMm = (k) => (inOut && k % 2 === 0 ? 8 : 14.3 + (k % 4) * 0.2);
  const z = (k) => (edge ? 32768 + Math.round((zEdgeMm(k) / 15) * 32768) : k % 2 === 0 ? 65535 : 0);
  const far = (k) => [
    32768 + (k % 7) * 200,
    moving(k, 5, 200),
    z(k),
    moving(k, 3, 300),
    moving(k, 4, 300),
    moving(k, 6, 300),
  ];
  board.sendBytes(binaryFrame(far(0)));
  board.runMs(50);
  const startNanos = board.nanos;
  const startCycles = board.cycles;
  instrument?.start(board);
  for (let k = 1; k <= count; k++) {
    board.runUntil(() => board.nanos >= startNanos + k * periodNanos, { timeoutMs: 1000 });
    board.sendBytes(binaryFrame(far(k)));
  }
  instrument?.stop(board);
  const busyCycles = board.cycles - startCycles;
  const elapsedCycles = ((board.nanos - startNanos) / 1e9) * CLOCK_HZ;
  const after = streamCounters(board);
  return {
    framesPerSecond,
    seconds,
    cpuShare: busyCycles / elapsedCycles,
    cyclesPerServoFrame: busyCycles / (((board.nanos - startNanos) / 1e9) * 333),
    frames: after.frames - before.frames,
    applied: after.applied - before.applied,
    clamped: after.clamped - before.clamped,
    longestPassCycles: board.loop.longestPassCycles,
  };
}
