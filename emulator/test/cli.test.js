// The host tool `hexapod` (cli/) against the real firmware, as a user runs it: `./dev run --pty
// --no-view` (src/run.js) boots the firmware ELF in the emulator with UART0 on a pseudo-terminal
// (and no live view, whose own lines would share it), and the tool talks to that terminal as to
// a board's serial port. `apply` a build file (a payload and torque ratings among its
// settings), read it back, the board's holding torques against the tool's `describe`,
// stream a 10-second trajectory as binary frames and a shorter one as `pose` lines (every reply
// checked), then the final pulse widths, as the firmware reports them and as the emulator
// measures them on the pins, against the host build of the kinematics. And `uf2 --settings`:
// the chip booted from that file starts with the build file's settings.

import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, test } from 'node:test';

import { DEFAULT_ELF, EmulatedBoard } from '../src/chip/board.js';
import {
  COUNT_US,
  defaultSettings,
  firmwareBootrom,
  numbersIn,
  ok,
  pinsReach,
} from '../src/test-support/e2e-support.js';
import { HostReference } from '../src/test-support/host-reference.js';
import { buildTool, runProgram, startPtyRunner } from '../src/test-support/pty-runner.js';

// The build file: speed limits off (stream frames pass straight through), stream full scales
// that make the trajectory's last row exact in counts (32 mm / 32768 counts: 1/1024 mm), one
// servo trimmed; 1.5 kg 20 mm above the platform on servos rated 20 kgf cm (servo 3: 25), three
// times the worst holding torque over the workspace, so the board checks every target and
// clamps none. The same geometry and servos for the host reference (the payload moves no pulse).
const BUILD = `# a test build
speed_mm_s = "off"
speed_deg_s = "off"
payload_g = 1500
payload_com_z_mm = 20
servos.torque_kgcm = 20
[stream]
x_mm = 32
y_mm = 32
z_mm = 16
roll_deg = 16
pitch_deg = 16
yaw_deg = 32
[servo3]
trim_us = 1510
torque_kgcm = 25
`;
const END = [5, -3, 4, 2, -1.5, 6];

function referenceSettings() {
  const settings = defaultSettings();
  settings.servos[2].trim_us = 1510;
  return settings;
}

let tool;
let dir;
let runner;
let port;
/** Everything the runner wrote to stderr so far. */
let runnerLog = () => '';
const reference = () => new HostReference();

before(async () => {
  firmwareBootrom(); // the ELF is built and the boot ROM cached before the runner needs them
  tool = buildTool();
  dir = mkdtempSync(join(tmpdir(), 'hexapod-cli-e2e-'));
  ({ runner, port, log: runnerLog } = await startPtyRunner());
});

after(() => {
  runner?.kill();
  if (dir) {
    rmSync(dir, { recursive: true, force: true });
  }
});

/** Runs the tool (asynchronously, so the runner keeps emulating); resolves to its outcome. */
function hexapod(args) {
  return runProgram(tool, args, { cwd: dir });
}

/** `--port PORT` with a time-out for an emulator that may run slower than real time. */
function onPort() {
  return ['--port', port, '--timeout-s', '30'];
}

test('apply a build file through the pty: every setting on the board, saved', async () => {
  writeFileSync(join(dir, 'build.toml'), BUILD);
  const apply = await hexapod(['apply', 'build.toml', '--port', port, '--timeout-s', '30']);
  assert.equal(apply.status, 0, apply.stdout + apply.stderr);
  assert.match(apply.stdout, /saved in flash/);
  const config = await hexapod(['send', '--port', port, '--timeout-s', '30', 'config']);
  assert.equal(config.status, 0, config.stderr);
  for (const line of [
    '# speed_mm_s: off',
    '# stream.x_mm: 32.000',
    '# stream.yaw_deg: 32.000',
    '# payload_g: 1500.0',
    '# payload_com_x_mm: 0.000',
    '# payload_com_z_mm: 20.000',
    '# servo3: trim_us=1510.00 rate_us_rad=509.296 dir=reversed min_us=1100.00 max_us=1900.00 ' +
      'torque_kgcm=25.00 speed_s_60deg=off',
    '# servo4: trim_us=1500.00 rate_us_rad=509.296 dir=normal min_us=1100.00 max_us=1900.00 ' +
      'torque_kgcm=20.00 speed_s_60deg=off',
    '# saved: yes (these settings are the ones saved in flash)',
  ]) {
    assert.ok(config.stdout.split('\n').includes(line), `${line} in ${config.stdout}`);
  }
  const pull = await hexapod(['pull', '--port', port, '-o', 'pulled.toml', '--timeout-s', '30']);
  assert.equal(pull.status, 0, pull.stderr);
  const pulled = readFileSync(join(dir, 'pulled.toml'), 'utf8');
  assert.match(pulled, /\[servo3\]\ntrim_us = 1510\.0 /);
  assert.match(pulled, /\nz_mm = 16\.0 /);
  assert.match(pulled, /\npayload_g = 1500\.0 /);
  assert.match(pulled, /\npayload_com_z_mm = 20\.0 /);
  assert.match(pulled, /\[servo3\]\n(?:[^[].*\n)*torque_kgcm = 25\.0 /);
  assert.equal(pulled.match(/\ntorque_kgcm = 20\.0 /g)?.length, 5, pulled);
  assert.doesNotMatch(pulled, /saved/);
  assert.doesNotMatch(pulled, /No payload/);
});

test("the board's holding torques at home are those describe gives for the file", async () => {
  const check = await hexapod(['send', ...onPort(), 'check 0 0 0 0 0 0']);
  assert.equal(check.status, 0, check.stderr);
  const board = numbersIn(check.stdout.split('\n').find((l) => l.startsWith('# torque_kgcm:')));
  const describe = await hexapod(['describe', '--settings', 'build.toml']);
  assert.equal(describe.status, 0, describe.stderr);
  const line = describe.stdout.split('\n').find((l) => l.includes('holding torque at home'));
  const host = numbersIn(line.slice(line.indexOf(':') + 1));
  assert.equal(host.length, 6, line);
  // The same code: on the chip with the boot ROM's float routines, on the host with libm.
  board.forEach((t, i) => {
    assert.ok(Math.abs(t - host[i]) <= 0.002, `servo ${i + 1}: board ${t}, describe ${host[i]}`);
  });
  assert.match(describe.stdout, /ratings \(servoN\.torque_kgcm\): all within: servo \d/);
});

test('a text stream: a pose line per row, every reply ok', async () => {
  // 2 s at 50 rows/s: a sway there and back.
  const rows = ['time,x,y,z,roll,pitch,yaw'];
  for (let i = 0; i <= 100; i++) {
    const t = i / 50;
    rows.push(`${t},0,${(6 * Math.sin(Math.PI * t)).toFixed(3)},0,0,0,0`);
  }
  writeFileSync(join(dir, 'sway.csv'), `${rows.join('\n')}\n`);
  const stream = await hexapod(['stream', 'sway.csv', '--text', ...onPort()]);
  assert.equal(stream.status, 0, stream.stdout + stream.stderr);
  assert.match(stream.stdout, /lines sent: 101, ok: 101, refused: 0/);
  assert.match(stream.stdout, /\(each pose line to its reply\): 101 samples/);
  assert.match(stream.stdout, /errors: 0$/m);
});

test("a 10-second binary stream arrives whole; the pins end at the host IK's pulses", async () => {
  // 10 s at 50 rows/s: from home to END along a smooth step, with a circle on the way.
  const rows = ['time,x,y,z,roll,pitch,yaw'];
  for (let i = 0; i <= 500; i++) {
    const t = i / 50;
    const u = t / 10;
    const s = u * u * (3 - 2 * u);
    const wiggle = Math.sin(Math.PI * u);
    const pose = END.map((e) => e * s);
    pose[0] += 4 * wiggle * Math.sin((2 * Math.PI * t) / 2.5);
    pose[1] += 4 * wiggle * (1 - Math.cos((2 * Math.PI * t) / 2.5));
    rows.push([t.toFixed(2), ...pose.map((v) => v.toFixed(4))].join(','));
  }
  writeFileSync(join(dir, 'ten.csv'), `${rows.join('\n')}\n`);
  const stream = await hexapod(['stream', 'ten.csv', '--port', port, '--timeout-s', '30']);
  assert.equal(stream.status, 0, stream.stdout + stream.stderr);
  assert.match(stream.stdout, /501 rows sent to \S+ as binary frames/);
  assert.match(
    stream.stdout,
    /the board counted frames=501 applied=\d+ damaged=0 clamped=0 refused=0/,
  );
  assert.match(stream.stdout, /round trip \(status lines[^)]*\): \d+ samples/);
  assert.match(stream.stdout, /errors: 0$/m);

  const [expected] = reference().solve(referenceSettings(), [END]);
  assert.ok(expected.ok, JSON.stringify(expected));
  const status = await hexapod(['send', '--port', port, '--timeout-s', '30', 'status']);
  assert.equal(status.status, 0, status.stderr);
  assert.match(
    status.stdout,
    /# pose: x=5\.000 y=-3\.000 z=4\.000 roll=2\.000 pitch=-1\.500 yaw=6\.000/,
  );
  const reported = numbersIn(status.stdout.split('\n').find((l) => l.startsWith('# pulse_us:')));
  reported.forEach((w, i) => {
    const want = expected.pulse_us[i];
    assert.ok(Math.abs(w - want) <= 0.01, `servo ${i + 1}: ${w} vs ${want}`);
  });
  const pins = await pinsReach(runnerLog, expected.pulse_us);
  pins.forEach((w, i) => {
    assert.ok(
      Math.abs(w - expected.pulse_us[i]) <= COUNT_US + 1e-9,
      `servo ${i + 1}: pin ${w} us, host IK ${expected.pulse_us[i]} us`,
    );
  });
});

test('a text stream: a row the board refuses is reported, the rows after it still go', async () => {
  // With speed limits (the board checks the straight path of each move): from the first pose
  // the path to the second leaves the workspace (docs/error-codes.md, path-blocked); each pose
  // alone is reachable, so the host's check passes them and the board refuses the second.
  const limits = await hexapod(['send', ...onPort(), 'set speed_mm_s 50', 'set speed_deg_s 60']);
  assert.equal(limits.status, 0, limits.stderr);
  // The rows go at wall-clock times, while the emulator may run far slower than real time: the
  // platform is brought to the first row's pose (and seen there on the pins) before the stream,
  // so the second row's path starts from the first pose however slow the emulation is.
  const first = [-28, 19, -2.5, 11, 2, -20];
  const start = await hexapod(['send', ...onPort(), `pose ${first.join(' ')}`]);
  assert.equal(start.status, 0, start.stderr);
  const [there] = reference().solve(referenceSettings(), [first]);
  assert.ok(there.ok, JSON.stringify(there));
  const reached = await pinsReach(runnerLog, there.pulse_us);
  reached.forEach((w, i) => {
    assert.ok(Math.abs(w - there.pulse_us[i]) <= COUNT_US + 1e-9, `servo ${i + 1}: pin ${w} us`);
  });
  writeFileSync(
    join(dir, 'blocked.csv'),
    'time,x,y,z,roll,pitch,yaw\n0,-28,19,-2.5,11,2,-20\n3,30,-12,-13.5,5,-13,28\n3.1,0,0,2,0,0,0\n',
  );
  const stream = await hexapod(['stream', 'blocked.csv', '--text', ...onPort()]);
  assert.notEqual(stream.status, 0);
  const refused = "line 3: the board refused 'pose 30.000 -12.000 -13.500 5.000 -13.000 28.000': ";
  assert.ok(stream.stderr.includes(`${refused}error:path-blocked `), stream.stderr);
  assert.match(stream.stdout, /lines sent: 3, ok: 2, refused: 1/);
  assert.match(stream.stderr, /blocked\.csv: the stream did not go through whole: 1 lines refused/);
  const status = await hexapod(['send', '--port', port, '--timeout-s', '30', 'status']);
  assert.match(
    status.stdout,
    /# target: x=0\.000 y=0\.000 z=2\.000 roll=0\.000 pitch=0\.000 yaw=0\.000/,
  );
});

test('uf2 --settings: the chip booted from the file starts with the build file saved', () => {
  writeFileSync(join(dir, 'build.toml'), BUILD);
  execFileSync(tool, ['uf2', DEFAULT_ELF, '-o', 'fw.uf2', '--settings', 'build.toml'], {
    cwd: dir,
  });
  const file = readFileSync(join(dir, 'fw.uf2'));
  // The UF2 specification's blocks: 256-byte payloads at their target addresses.
  const view = new DataView(file.buffer, file.byteOffset, file.byteLength);
  const segments = Array.from({ length: file.length / 512 }, (_, i) => ({
    address: view.getUint32(i * 512 + 12, true),
    bytes: file.subarray(i * 512 + 32, i * 512 + 32 + view.getUint32(i * 512 + 16, true)),
  }));
  const board = new EmulatedBoard({ bootrom: firmwareBootrom(), segments });
  const { offset } = board.settingsStorage;
  const sector = 0x10000000 + offset;
  assert.ok(
    segments.some((s) => s.address === sector),
    'the settings sector is in the file',
  );
  board.boot();
  board.runMs(50);
  assert.doesNotMatch(board.output, /# warning/);
  assert.equal(board.request('set echo off').reply, 'ok');
  const config = ok(board, 'config');
  for (const line of [
    'speed_deg_s: off',
    'stream.z_mm: 16.000',
    'payload_g: 1500.0',
    'servo3: trim_us=1510.00 rate_us_rad=509.296 dir=reversed min_us=1100.00 max_us=1900.00 ' +
      'torque_kgcm=25.00 speed_s_60deg=off',
    'saved: yes (these settings are the ones saved in flash)',
  ]) {
    assert.ok(config.includes(line), `${line} in ${JSON.stringify(config)}`);
  }
  // And the pins: servo 3 at its new home pulse.
  board.runMs(60);
  assert.ok(Math.abs(board.pulseWidthsUs()[2] - 1510) <= COUNT_US, `${board.pulseWidthsUs()}`);
});

test('a missing port is named; nothing is left running', async () => {
  const missing = await hexapod(['send', '--port', `${port}-none`, 'status']);
  assert.notEqual(missing.status, 0);
  assert.match(missing.stderr, /^hexapod: \S+-none: cannot open the serial port/);
  const spare = spawnSync(tool, ['--help'], { encoding: 'utf8' });
  assert.match(spare.stdout, /apply/);
});
