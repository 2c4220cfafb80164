// Motion cueing latency (issue 24): how long `hexapod cue` takes from a telemetry packet's
// arrival on its UDP socket to the stream frame it makes leaving the tool (written to the
// serial port). The tool measures it itself (cli/src/cue/run.rs: the socket reader thread
// stamps each datagram with the host's monotonic clock as `recv` returns it; the cueing loop
// stamps the frame after the port's `write` returns) and prints the minimum, median, 99th
// percentile and maximum. Here it runs against the emulated board on a pseudo-terminal
// (`./dev run --pty --no-view`), fed by telemetry lines a loopback UDP socket sends at a
// steady rate: a gentle synthetic manoeuvre in the documented format (cli/src/cue/telemetry.rs),
// so no flight simulator is needed. These are wall-clock times on the machine running the
// bench (the only figures in BENCHMARKS.md that are): the host's scheduler and load move them.

import { createSocket } from 'node:dgram';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

import { buildTool, runProgram, startPtyRunner } from '../test-support/pty-runner.js';

/** A UDP port free on the loopback now. */
function freeUdpPort() {
  return new Promise((resolve) => {
    const socket = createSocket('udp4');
    socket.bind(0, '127.0.0.1', () => {
      const { port } = socket.address();
      socket.close(() => resolve(port));
    });
  });
}

/**
 * Telemetry line `k` at `hz`: time, specific force (ft/s^2), rates (rad/s), attitude (rad),
 * body axes; a slow surge and a gentle roll rate, both well inside the washout's reach.
 */
function telemetryLine(k, hz) {
  const t = k / hz;
  const ax = 4 * Math.sin(2 * Math.PI * 0.3 * t);
  const p = 0.1 * Math.sin(2 * Math.PI * 0.2 * t);
  const phi = (0.1 / (2 * Math.PI * 0.2)) * (1 - Math.cos(2 * Math.PI * 0.2 * t));
  const values = [t, ax, 0, -32.17, p, 0, 0, phi, 0, 0];
  return `${values.map((v) => v.toFixed(5)).join(',')}\n`;
}

/** `[min, median, p99, max]` of `values` (as the tool computes them), or null. */
function percentiles(values) {
  if (values.length === 0) {
    return null;
  }
  const sorted = [...values].sort((a, b) => a - b);
  const n = sorted.length;
  const median = n % 2 ? sorted[(n - 1) / 2] : (sorted[n / 2 - 1] + sorted[n / 2]) / 2;
  return [sorted[0], median, sorted[Math.round((n - 1) * 0.99)], sorted[n - 1]];
}

/**
 * The latencies in the tool's record (`--record`), split by whether the frame was eased (the
 * blend from home to the live cue when telemetry starts, and back when it stops: frames then go
 * at the board's frame rate on the tool's own clock, and a sample waits for the next one).
 */
function recordedLatencies(csv) {
  const rows = csv.split('\n').filter((line) => line && !line.startsWith('#'));
  const header = rows.shift().split(',');
  const easing = header.indexOf('easing');
  const latency = header.indexOf('latency_ms');
  const split = { live: [], easing: [] };
  for (const row of rows) {
    const cells = row.split(',');
    if (cells[latency] !== '' && cells[latency] !== undefined) {
      split[cells[easing] === '1' ? 'easing' : 'live'].push(Number(cells[latency]));
    }
  }
  return { live: percentiles(split.live), easing: percentiles(split.easing), split };
}

/** Sends `count` telemetry lines to `port` at `hz`, paced on the wall clock (no drift). */
async function sendTelemetry(port, count, hz) {
  const socket = createSocket('udp4');
  const start = performance.now();
  for (let k = 0; k < count; k++) {
    const due = start + (k * 1000) / hz;
    const wait = due - performance.now();
    if (wait > 0) {
      await new Promise((resolve) => setTimeout(resolve, wait));
    }
    await new Promise((resolve) => socket.send(telemetryLine(k, hz), port, '127.0.0.1', resolve));
  }
  socket.close();
}

/**
 * Runs `hexapod cue` against the emulated board for `seconds` of telemetry at `hz` (the board
 * at `frameHz`, pass-through). Returns `{ min, median, p99, max }` in ms, the packets sent,
 * the frames the tool sent and its summary lines.
 */
export async function measureCueLatency({ seconds = 20, hz = 60, frameHz = 100 } = {}) {
  const tool = buildTool();
  const dir = mkdtempSync(join(tmpdir(), 'hexapod-cue-bench-'));
  const { runner, port } = await startPtyRunner();
  try {
    const on = ['--port', port, '--timeout-s', '30'];
    const setup = await runProgram(
      tool,
      ['send', ...on, 'set speed_mm_s off', 'set speed_deg_s off', `set frame_hz ${frameHz}`],
      { cwd: dir },
    );
    if (setup.status !== 0) {
      throw new Error(`hexapod send failed: ${setup.stdout}${setup.stderr}`);
    }
    const udp = await freeUdpPort();
    let listening;
    const ready = new Promise((resolve) => {
      listening = resolve;
    });
    const args = ['cue', ...on, '--listen', `127.0.0.1:${udp}`, '--idle-exit-s', '1'];
    args.push('--record', 'cue.csv');
    const cue = runProgram(tool, [...args, '--wait-s', '60'], {
      cwd: dir,
      onLine: (line) => {
        if (line.startsWith('cue: listening')) {
          listening();
        }
      },
    });
    await ready;
    const packets = Math.round(seconds * hz);
    await sendTelemetry(udp, packets, hz);
    const done = await cue;
    if (done.status !== 0) {
      throw new Error(`hexapod cue failed: ${done.stdout}${done.stderr}`);
    }
    const found = done.stdout.match(
      /latency \(packet arrival to frame written\): min ([\d.]+) ms, median ([\d.]+) ms, 99% ([\d.]+) ms, max ([\d.]+) ms/,
    );
    if (!found) {
      throw new Error(`no latency in hexapod cue's summary: ${done.stdout}`);
    }
    const [min, median, p99, max] = found.slice(1).map(Number);
    const frames = Number(done.stdout.match(/frames sent: (\d+)/)?.[1]);
    const late = Number(done.stdout.match(/late samples (\d+)/)?.[1]);
    const recorded = recordedLatencies(readFileSync(join(dir, 'cue.csv'), 'utf8'));
    return {
      min,
      median,
      p99,
      max,
      packets,
      frames,
      late,
      live: recorded.live,
      easing: recorded.easing,
      liveCount: recorded.split.live.length,
      easingCount: recorded.split.easing.length,
      hz,
      frameHz,
      summary: done.stdout.trim().split('\n'),
    };
  } finally {
    runner.kill();
    rmSync(dir, { recursive: true, force: true });
  }
}

// `node emulator/src/bench/cue-bench.js [seconds]`: this measurement alone.
if (import.meta.url === `file://${process.argv[1]}`) {
  const seconds = Number(process.argv[2] ?? 20);
  const result = await measureCueLatency({ seconds });
  process.stdout.write(`${JSON.stringify(result)}\n`);
}
