// Motion cueing end to end: a real flight-dynamics engine nobody here wrote (JSBSim, the `jsbsim`
// package from PyPI, pinned in ./dev) flies a Cessna 172 (cli/sim/jsbsim-flight.py: a take-off
// run, rotation, a sustained turn), JSBSim itself sends its telemetry over UDP on the loopback
// with the shipped output directive (cli/sim/jsbsim-output.xml), `hexapod cue` turns it into
// binary stream frames for the real firmware in the emulator (`./dev run --pty --no-view`, as
// in cli.test.js), and everything is judged on the pins: the six measured pulse widths, turned
// back into poses by the host build of the kinematics core's forward kinematics. The platform
// moves; the pulses stay inside the servo limits and the board clamps nothing; the take-off
// run's forward acceleration tilts the nose up (tilt coordination: negative pitch, the board's
// pitch lowering +x); the sustained turn washes back towards level; the end of the telemetry
// brings the platform home. The latency from a packet's arrival to its frame leaving the tool
// is reported.

import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { createSocket } from 'node:dgram';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, test } from 'node:test';

import {
  COUNT_US,
  defaultSettings,
  firmwareBootrom,
  numbersIn,
} from '../src/test-support/e2e-support.js';
import { HostReference } from '../src/test-support/host-reference.js';
import { buildTool, REPO, runProgram, startPtyRunner } from '../src/test-support/pty-runner.js';

const FLIGHT = join(REPO, 'cli', 'sim', 'jsbsim-flight.py');
// Twice real time (the washout runs on the simulation's clock), 30 telemetry lines per
// simulated second: 60 a second on the wall, below the board's 100 Hz frames here, so each
// packet's frame goes as it arrives.
const SPEED = 2;
const TELEMETRY_HZ = 30;
const END_S = 50;
const FRAME_HZ = 100;

let tool;
let dir;
let runner;
let port;
/** Every pin reading the runner printed: `{ at: ms (wall), us: [six widths] }`. */
const pins = [];

before(async () => {
  const python = spawnSync('python3', ['-c', 'import jsbsim; print(jsbsim.__version__)'], {
    encoding: 'utf8',
  });
  assert.equal(
    python.status,
    0,
    `JSBSim is missing: pip install jsbsim==1.3.3 (./dev test installs it)\n${python.stderr}`,
  );
  firmwareBootrom();
  tool = buildTool();
  dir = mkdtempSync(join(tmpdir(), 'hexapod-cue-e2e-'));
  let partial = '';
  ({ runner, port } = await startPtyRunner({
    onText: (text) => {
      const at = Date.now();
      const lines = (partial + text).split('\n');
      partial = lines.pop();
      for (const line of lines) {
        if (line.startsWith('servos us:')) {
          pins.push({ at, us: numbersIn(line.replace(/\|.*$/, '')) });
        }
      }
    },
  }));
});

after(() => {
  runner?.kill();
  if (dir) {
    rmSync(dir, { recursive: true, force: true });
  }
});

/**
 * Runs a program; resolves to its outcome. `onLine` sees each stdout or stderr line as it comes.
 * @param {string} program
 * @param {string[]} args
 * @param {(line: string, at: number) => void} [onLine]
 */
function run(program, args, onLine = () => {}) {
  return runProgram(program, args, { cwd: dir, onLine });
}

/** A UDP port free on the loopback now. */
function freeUdpPort() {
  return new Promise((resolve) => {
    const socket = createSocket('udp4');
    socket.bind(0, '127.0.0.1', () => {
      const { port: free } = socket.address();
      socket.close(() => resolve(free));
    });
  });
}

test('a JSBSim flight drives the emulated platform through hexapod cue, judged on the pins', async (t) => {
  const setup = await run(tool, [
    'send',
    '--port',
    port,
    '--timeout-s',
    '30',
    'set speed_mm_s off',
    'set speed_deg_s off',
    `set frame_hz ${FRAME_HZ}`,
  ]);
  assert.equal(setup.status, 0, setup.stdout + setup.stderr);
  const udp = await freeUdpPort();
  let listening;
  const ready = new Promise((resolve) => {
    listening = resolve;
  });
  const cue = run(
    tool,
    [
      'cue',
      '--port',
      port,
      '--timeout-s',
      '30',
      '--listen',
      `127.0.0.1:${udp}`,
      '--record',
      'flight.csv',
      '--idle-exit-s',
      '2',
      '--wait-s',
      '120',
    ],
    (line) => {
      if (line.startsWith('cue: listening')) {
        listening();
      }
    },
  );
  await ready;
  /** @type {Record<string, number>} */
  const phases = {};
  const flight = await run(
    'python3',
    [
      FLIGHT,
      '--port',
      String(udp),
      '--speed',
      String(SPEED),
      '--rate',
      String(TELEMETRY_HZ),
      '--end-s',
      String(END_S),
    ],
    (line, at) => {
      const found = line.match(/^phase (\S+) /);
      if (found) {
        phases[found[1]] = at;
      }
    },
  );
  assert.equal(flight.status, 0, flight.stdout + flight.stderr);
  const done = await cue;
  assert.equal(done.status, 0, done.stdout + done.stderr);
  done.stdout
    .trim()
    .split('\n')
    .forEach((line) => t.diagnostic(line));
  for (const phase of ['take-off-run', 'rotate', 'turn', 'end']) {
    assert.ok(phases[phase], `the flight reached ${phase}: ${flight.stdout}`);
  }

  // The tool's account: every frame the board received whole, none clamped.
  const sent = Number(done.stdout.match(/frames sent: (\d+)/)?.[1]);
  assert.ok(sent > 1000, done.stdout);
  assert.match(
    done.stdout,
    new RegExp(`the board counted frames=${sent} applied=\\d+ damaged=0 clamped=0 refused=0`),
  );
  assert.match(done.stdout, /dropped: none/);
  const latency = done.stdout.match(
    /latency \(packet arrival to frame written\): min ([\d.]+) ms, median ([\d.]+) ms, 99% ([\d.]+) ms, max ([\d.]+) ms/,
  );
  assert.ok(latency, done.stdout);
  // The aim (issue 24): under 2 ms from a packet's arrival to its frame leaving the tool.
  assert.ok(Number(latency[2]) < 2, `median latency ${latency[2]} ms`);

  // The pins during the flight: within the servo limits, never at them; moving.
  const flying = pins.filter((p) => p.at >= phases['take-off-run'] && p.at <= phases.end);
  assert.ok(flying.length > 200, `${flying.length} pin readings`);
  const settings = defaultSettings();
  let widest = 0;
  for (const { us } of flying) {
    us.forEach((w, i) => {
      const { min_us: lo, max_us: hi } = settings.servos[i];
      assert.ok(w > lo + 20 && w < hi - 20, `servo ${i + 1} at ${w} us`);
      widest = Math.max(widest, Math.abs(w - 1500));
    });
  }
  assert.ok(widest > 30, `the platform moved: ${widest} us from home at most`);

  // Poses from the pins (every 4th reading), by the core's forward kinematics.
  const sampled = flying.filter((_, i) => i % 4 === 0);
  const poses = new HostReference()
    .runWith(
      settings,
      sampled.map((p) => `fk ${p.us.join(' ')} 0 0 0 0 0 0`),
    )
    .map((answer, i) => {
      assert.ok(answer.ok, `${sampled[i].us}: ${JSON.stringify(answer)}`);
      return { at: sampled[i].at, pose: answer.pose };
    });
  const during = (from, to) => poses.filter((p) => p.at >= from && p.at <= to).map((p) => p.pose);
  const PITCH = 4;
  const ROLL = 3;
  const YAW = 5;

  // The take-off run: a forward acceleration felt as the nose tilted up.
  const run1 = during(phases['take-off-run'], phases.rotate);
  const noseUp = Math.min(...run1.map((p) => p[PITCH]));
  t.diagnostic(`take-off run: pitch down to ${noseUp.toFixed(2)} deg (nose up)`);
  assert.ok(noseUp < -3, `take-off run pitch reached only ${noseUp}`);

  // The turn: rolled and yawed on the way in, back towards level while it lasts. Yaw washes
  // back all the way; roll keeps the small tilt of the turn's slight sideways force (about
  // 0.1 m/s^2, 0.3 degrees with the default tilt.scale 0.6).
  const turn = during(phases.turn, phases.end);
  const peak = (poseList, axis) => Math.max(...poseList.map((p) => Math.abs(p[axis])));
  const lastSeconds = during(phases.end - 4000, phases.end);
  /** @type {[string, number, number][]} the axis, its index, the fraction of its peak left */
  const washes = [
    ['roll', ROLL, 0.5],
    ['yaw', YAW, 0.25],
  ];
  for (const [name, axis, left] of washes) {
    const most = peak(turn, axis);
    const late = peak(lastSeconds, axis);
    t.diagnostic(
      `turn: ${name} up to ${most.toFixed(2)} deg, ${late.toFixed(2)} deg in its last 4 s`,
    );
    assert.ok(most > 0.8, `${name} moved in the turn: ${most}`);
    assert.ok(late < left * most && late < 0.6, `${name} washed back: ${late} of ${most}`);
  }

  // The end: home, on every pin, within one PWM count.
  const last = pins.at(-1).us;
  last.forEach((w, i) => {
    assert.ok(
      Math.abs(w - settings.servos[i].trim_us) <= COUNT_US + 1e-9,
      `servo ${i + 1} at ${w} us`,
    );
  });

  // The record plotted (the picture docs/cueing.md shows is made the same way).
  const record = readFileSync(join(dir, 'flight.csv'), 'utf8').trim().split('\n');
  assert.equal(record.length - 2, sent);
  const plot = await run(tool, ['cue-plot', 'flight.csv', '-o', 'flight']);
  assert.equal(plot.status, 0, plot.stderr);
});
