// `hexapod calibrate` (the guided calibration in the terminal, docs/geometry-and-calibration.md)
// against the real firmware through `./dev run --pty --no-view`, its keys scripted on standard
// input. Quitting midway (the end of input, or q at a check pose) leaves the board's settings
// and pulses as they were; the whole flow writes the trims into the user's build file (its
// other keys and comments kept), `save`s them, `config` lists them and they survive a power
// cycle. The expected trims are worked out here from the documents' pulse equation (eq. 13 /
// 14: W = W0 + d r (alpha - alpha0)) with the board's own `geometry` and `config` listings,
// not from the tool's code.

import assert from 'node:assert/strict';
import { existsSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, test } from 'node:test';

import {
  COUNT_US,
  expectedTrim,
  firmwareBootrom,
  pinsReach,
  servosFromListings,
} from '../src/test-support/e2e-support.js';
import { buildTool, runProgram, startPtyRunner } from '../src/test-support/pty-runner.js';

let tool;
let dir;
let board;

before(async () => {
  firmwareBootrom(); // the ELF is built and the boot ROM cached before the runner needs them
  tool = buildTool();
  dir = mkdtempSync(join(tmpdir(), 'hexapod-calibrate-e2e-'));
  board = await startPtyRunner();
});

after(() => {
  board?.runner.kill();
  if (dir) {
    rmSync(dir, { recursive: true, force: true });
  }
});

const onPort = () => ['--port', board.port, '--timeout-s', '30'];

/** `hexapod send` lines; their replies' lines. */
async function send(...lines) {
  const outcome = await runProgram(tool, ['send', ...onPort(), ...lines], { cwd: dir, input: '' });
  assert.equal(outcome.status, 0, outcome.stderr);
  return outcome.stdout.split('\n').filter((line) => line !== '');
}

const round2 = (us) => Math.round(us * 100) / 100;

/** Each servo's trim, rate (us/rad) and direction sign from `config`, alpha0 (rad) from `geometry`. */
async function servos() {
  return servosFromListings(await send('geometry', 'config'));
}

/** `config`'s lines that are the settings and whether they are saved. */
async function config() {
  return (await send('config')).filter((line) => line.startsWith('# '));
}

test('the end of input midway puts the pulses back and leaves the settings as they were', async () => {
  const before = await config();
  const start = await servos();
  // Servo 1 trimmed, servo 2 moved 20 us, then the input ends.
  const run = await runProgram(tool, ['calibrate', ...onPort(), '-o', 'quit.toml'], {
    cwd: dir,
    input: ']]+\n\n]]\n',
  });
  assert.equal(run.status, 0, run.stderr);
  assert.match(run.stdout, /servo 1: trim_us /);
  assert.match(run.stdout, /calibration stopped: the pulses and trims are as they were/);
  assert.deepEqual(await config(), before);
  assert.ok(!existsSync(join(dir, 'quit.toml')), 'no build file written');
  const status = await send('status');
  assert.ok(status.includes('# state: idle'), status.join('\n'));
  assert.ok(status.includes('# pose: x=0.000 y=0.000 z=0.000 roll=0.000 pitch=0.000 yaw=0.000'));
  const pins = await pinsReach(
    board.log,
    start.map((s) => s.trim),
  );
  start.forEach((s, i) => assert.ok(Math.abs(pins[i] - s.trim) <= COUNT_US + 1e-9, `${pins}`));
});

test('q at a check pose puts the six trims back', async () => {
  const before = await config();
  const run = await runProgram(tool, ['calibrate', ...onPort(), '-o', 'quit.toml'], {
    cwd: dir,
    input: ']\n\n[\n\n]\n\n[\n\n+\n\n-\n\nq\n',
  });
  assert.equal(run.status, 0, run.stderr);
  assert.match(run.stdout, /Trims set on the board \(not saved yet\)/);
  assert.match(run.stdout, /pose 0 0 0 0 0 0: home: a spirit level/);
  assert.match(run.stdout, /calibration stopped/);
  assert.deepEqual(await config(), before);
  assert.ok(!existsSync(join(dir, 'quit.toml')), 'no build file written');
});

test('the whole flow: trims in the build file (the rest kept), saved, listed, kept over a power cycle', async () => {
  const start = await servos();
  writeFileSync(
    join(dir, 'build.toml'),
    '# my platform, measured\nrod_mm = 120.0   # from the drawing\n[servo4]\nmin_us = 1150.0\n',
  );
  // Per servo: the keys, then Enter alone (level); then Enter at each of the five check poses.
  const keys = [']]+', '-', '1490', '', '[ +', ']'];
  const steps = [21, -1, null, 0, -9, 10];
  const run = await runProgram(tool, ['calibrate', ...onPort()], {
    cwd: dir,
    input: keys.flatMap((k) => (k === '' ? [''] : [k, ''])).join('\n') + '\n' + '\n'.repeat(5),
  });
  assert.equal(run.status, 0, `${run.stdout}\n${run.stderr}`);
  // Servo 3 was sent to 1490 us, so its steps are 1490 minus where it started.
  steps[2] = 1490 - round2(start[2].trim - start[2].sign * start[2].rate * start[2].alpha0);
  const expected = start.map((s, i) => expectedTrim(s, steps[i]));

  const file = readFileSync(join(dir, 'build.toml'), 'utf8');
  assert.ok(
    file.startsWith('# my platform, measured\nrod_mm = 120.0   # from the drawing\n'),
    file,
  );
  assert.match(file, /\[servo4\]\ntrim_us = [\d.]+\nmin_us = 1150\.0\n/);
  for (let n = 1; n <= 6; n += 1) {
    const written = Number(file.match(new RegExp(`\\[servo${n}\\]\\ntrim_us = (\\S+)`))[1]);
    assert.ok(Math.abs(written - expected[n - 1]) <= 0.011, `servo${n}: ${written} ${expected}`);
  }
  assert.match(run.stdout, /saved in flash/);

  const listed = async () => {
    const lines = await config();
    return {
      trims: [1, 2, 3, 4, 5, 6].map((n) =>
        Number(lines.find((l) => l.startsWith(`# servo${n}:`)).match(/trim_us=(\S+)/)[1]),
      ),
      saved: lines.find((l) => l.startsWith('# saved:')),
    };
  };
  const after = await listed();
  after.trims.forEach((t, i) => assert.ok(Math.abs(t - expected[i]) <= 0.011, `${after.trims}`));
  assert.match(after.saved, /^# saved: yes/);
  // At home, each servo at its new trim.
  const pins = await pinsReach(board.log, after.trims);
  after.trims.forEach((t, i) => assert.ok(Math.abs(pins[i] - t) <= COUNT_US + 1e-9, `${pins}`));

  // A change left unsaved, then the board power-cycled: the saved trims come back, not it.
  await send('set servo4.trim_us 1555');
  board.runner.kill('SIGUSR2');
  const until = Date.now() + 30_000;
  while (!board.log().includes('power cycled') && Date.now() < until) {
    await new Promise((resolve) => setTimeout(resolve, 100));
  }
  const again = await listed();
  assert.deepEqual(again.trims, after.trims);
  assert.match(again.saved, /^# saved: yes/);
});
