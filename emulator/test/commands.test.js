// Every command through the real firmware binary, over UART0 and over the USB port: the exact
// reply shape, the data lines, and the servo pins. Expected pulses come from the host build of
// kinematics-core (src/test-support/host-reference.js), expected formats and defaults from docs/.

import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { before, test } from 'node:test';

import { EmulatedBoard } from '../src/chip/board.js';
import {
  assertClose,
  assertConstant,
  assertPins,
  capture,
  COUNT_US,
  defaultSettings,
  firmwareBootrom,
  HOME,
  lerpPose,
  linkTest,
  ok,
  periodsUs,
  plannedFrames,
  poseText,
  refused,
  runFrames,
  status,
  widthsNanos,
} from '../src/test-support/e2e-support.js';
import { HostReference } from '../src/test-support/host-reference.js';

// Reported numbers vs the host core: the firmware computes in f32 with the ROM's routines, the
// reference with libm; they print with 3 (angles) and 2 (pulses) decimals.
const ARM_TOLERANCE_DEG = 0.002;
const PULSE_TOLERANCE_US = 0.01;
const DEFAULTS = defaultSettings();

let bootrom;
let reference;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
});

/** The reference's solution for one pose with the default settings (must be reachable). */
function solve(pose, settings = DEFAULTS) {
  const [answer] = reference.solve(settings, [pose]);
  assert.ok(answer.ok, `reference refuses ${pose}: ${JSON.stringify(answer)}`);
  return answer;
}

/** Sends a move and runs until it must have finished (its planned frames + 3). */
function moveAndSettle(board, line, from, to, settings = DEFAULTS) {
  assert.deepEqual(ok(board, line), [], `'${line}' has no data lines`);
  runFrames(board, plannedFrames(from, to, settings) + 3, settings.frame_hz);
}

test('banner names the firmware version and says to type help', () => {
  const board = new EmulatedBoard({ bootrom });
  const banner = board.boot();
  const cargo = readFileSync(new URL('../../Cargo.toml', import.meta.url), 'utf8');
  const version = cargo.match(/\[workspace\.package\][^[]*?\bversion\s*=\s*"([^"]+)"/)[1];
  assert.equal(board.lines[0], banner);
  assert.match(banner, /^# /, 'not a reply: the banner is a # line');
  assert.ok(banner.includes(version), `banner '${banner}' lacks version ${version}`);
  assert.match(banner, /\bhelp\b/);
  // A new board has nothing saved in flash, and says so (docs/settings.md, "Saving the settings").
  const warning = board.waitForLine(/^#/);
  assert.equal(warning, '# warning: no settings saved in flash; using the defaults');
  // Echo is on by default: a prompt follows.
  board.runMs(2);
  assert.equal(board.partialLine, '> ');
});

test('at power-up every servo gets its home pulse (the reference at the home pose)', () => {
  const board = new EmulatedBoard({ bootrom });
  board.boot();
  runFrames(board, 3);
  assertPins(board, solve(HOME).pulse_us);
  assert.deepEqual(periodsUs(board), Array(6).fill(20_000));
});

linkTest('help lists every command, all on # lines, then ok', (link) => {
  const board = link.quiet(bootrom);
  const text = ok(board, 'help').join('\n');
  const commands = ['pose', 'move', 'nudge', 'check', 'home', 'stop', 'status', '?', 'pulses'];
  commands.push('geometry');
  for (const command of [...commands, 'config', 'set', 'defaults', 'save', 'help']) {
    assert.ok(text.includes(command), `help does not mention ${command}`);
  }
  assert.match(text, /echo off/);
});

linkTest(
  'pose: ok alone, then the pins reach the host core pulses for that pose within one count',
  (link) => {
    const board = link.quiet(bootrom);
    const poses = [
      [10, 0, 0, 0, 0, 5],
      [-5, 8, -6, 3, -4, 10],
      [0, 0, 12, 0, 0, 0],
      [4, -3, 2, -8, 6, -15],
      [0.25, -0.125, 0.5, 0.75, -1.5, 2.25],
    ];
    let from = HOME;
    let worstUs = 0;
    for (const pose of poses) {
      moveAndSettle(board, `pose ${poseText(pose)}`, from, pose);
      const expected = solve(pose);
      assertPins(board, expected.pulse_us, `after pose ${pose}`);
      board.servos().forEach((servo, i) => {
        worstUs = Math.max(worstUs, Math.abs(servo.widthUs - expected.pulse_us[i]));
      });
      const s = status(board);
      assert.equal(s.state, 'idle');
      assertClose(s.pose, pose, 0.0005, 'status pose');
      assertClose(s.target, pose, 0.0005, 'status target');
      assertClose(s.arm_deg, expected.arm_deg, ARM_TOLERANCE_DEG, 'status arm_deg');
      assertClose(s.pulse_us, expected.pulse_us, PULSE_TOLERANCE_US, 'status pulse_us');
      from = pose;
    }
    assert.ok(worstUs <= COUNT_US, `worst pin error ${worstUs} us`);
  },
);

linkTest(
  'check: reports the host core arm angles, pulses and planned duration; nothing moves',
  (link) => {
    const board = link.quiet(bootrom);
    const before = status(board);
    const widths = widthsNanos(board);
    for (const pose of [
      [10, 0, 0, 0, 0, 5],
      [3, -5, 2, 4, -2, -10],
      [2, 2, -4, 0, 6, -20],
      [0, 0, -9, 0, 0, 0],
    ]) {
      let data;
      const pulses = capture(
        board,
        () => {
          data = ok(board, `check ${poseText(pose)}`);
        },
        5,
      );
      assertConstant(pulses, widths, `during check ${pose}`);
      assert.equal(data.length, 3, JSON.stringify(data));
      assert.match(data[0], /^arm_deg: (-?\d+\.\d{3} ){5}-?\d+\.\d{3}$/);
      assert.match(data[1], /^pulse_us: (\d+\.\d{2} ){5}\d+\.\d{2}$/);
      assert.match(data[2], /^duration_s: \d+\.\d{3}$/);
      const expected = solve(pose);
      assertClose(
        data[0].split(' ').slice(1).map(Number),
        expected.arm_deg,
        ARM_TOLERANCE_DEG,
        'arm_deg',
      );
      assertClose(
        data[1].split(' ').slice(1).map(Number),
        expected.pulse_us,
        PULSE_TOLERANCE_US,
        'pulse_us',
      );
      const seconds = plannedFrames(HOME, pose, DEFAULTS) / DEFAULTS.frame_hz;
      assert.equal(
        Number(data[2].split(' ')[1]),
        Number(seconds.toFixed(3)),
        `duration of ${pose}`,
      );
    }
    // Refused like pose, and still nothing moved.
    const reply = refused(board, 'check 0 0 80 0 0 0', 'unreachable');
    assert.match(reply, /\bleg \d\b/);
    const after = status(board);
    assert.deepEqual(after.pose, before.pose);
    assert.deepEqual(after.target, before.target);
    assert.deepEqual(widthsNanos(board), widths);
  },
);

linkTest(
  'move sets only the named axes (absolute), nudge moves them relative to the target',
  (link) => {
    const board = link.quiet(bootrom);
    const start = [2, -3, 4, 1, -2, 3];
    moveAndSettle(board, `pose ${poseText(start)}`, HOME, start);

    const moved = [2, -3, 8, 4, -2, 3];
    moveAndSettle(board, 'move z=8 roll=4', start, moved);
    assertClose(status(board).target, moved, 0.0005, 'after move');
    assertPins(board, solve(moved).pulse_us, 'after move');

    const nudged = [0.5, -3, 8, 4, -2, 5];
    moveAndSettle(board, 'nudge x=-1.5 yaw=2', moved, nudged);
    assertClose(status(board).target, nudged, 0.0005, 'after nudge');
    assertPins(board, solve(nudged).pulse_us, 'after nudge');

    // Nudges add up from the target, even while the move is still under way.
    ok(board, 'nudge z=-1');
    ok(board, 'nudge z=-1');
    const twice = [0.5, -3, 6, 4, -2, 5];
    assertClose(status(board).target, twice, 0.0005, 'two nudges');
    runFrames(board, 10);
    assertPins(board, solve(twice).pulse_us, 'after two nudges');
  },
);

linkTest('pulses: one short line, the widths the pins carry, at rest and while moving', (link) => {
  const board = link.quiet(bootrom);
  const widths = (line) => {
    assert.match(line, /^pulse_us: (\d+\.\d{2} ){5}\d+\.\d{2}$/);
    return line.slice('pulse_us: '.length).split(' ').map(Number);
  };
  const [home] = ok(board, 'pulses');
  // The budget `hexapod view` counts on (docs/commands.md): 63 bytes with its `ok`.
  assert.equal(`# ${home}\nok\n`.length, 63);
  assertPins(board, widths(home), 'at home');
  assertPins(
    board,
    DEFAULTS.servos.map((servo) => servo.trim_us),
    'home = trims',
  );
  // While a move runs, each answer is one frame's six widths as the pins carried them.
  ok(board, 'set speed_mm_s 20');
  const answers = [];
  const recorded = capture(
    board,
    () => {
      ok(board, 'pose 15 0 0 0 0 0');
      for (let i = 0; i < 12; i++) {
        board.runMs(30);
        answers.push(widths(ok(board, 'pulses')[0]));
      }
    },
    2,
  );
  const frames = recorded[0].map((_, k) => recorded.map((servo) => servo[k]?.widthNanos / 1000));
  for (const answer of answers) {
    const seen = frames.some((frame) =>
      frame.every((us, i) => Math.abs(us - answer[i]) <= COUNT_US + 0.005),
    );
    assert.ok(seen, `pulses ${answer} is no frame the pins carried`);
  }
  assert.ok(new Set(answers.map(String)).size > 5, `it did not follow: ${answers.join(' | ')}`);
  assert.match(status(board).state, /^moving/, 'the answers came during the move');
  // Asked in lock-step, as `hexapod view` does, in emulated time (UART0's wire modelled at
  // 115,200 baud: 70 bytes a round trip, 6.1 ms): at least 10 a second on UART0, 30 on USB.
  const started = board.nanos;
  for (let i = 0; i < 20; i++) {
    widths(ok(board, 'pulses')[0]);
  }
  const perSecond = 20 / ((board.nanos - started) / 1e9);
  assert.ok(perSecond >= (link.name === 'USB' ? 30 : 10), `${perSecond.toFixed(1)} a second`);
});

linkTest('home returns to the home pulses', (link) => {
  const board = link.quiet(bootrom);
  const pose = [-6, 4, 5, 2, 3, -8];
  moveAndSettle(board, `pose ${poseText(pose)}`, HOME, pose);
  moveAndSettle(board, 'home', pose, HOME);
  const s = status(board);
  assert.deepEqual(s.pose, HOME);
  assert.equal(s.state, 'idle');
  assertPins(board, solve(HOME).pulse_us);
  assertPins(
    board,
    DEFAULTS.servos.map((servo) => servo.trim_us),
    'home = trims',
  );
});

linkTest(
  'status while moving: state with elapsed and planned duration, target ahead of pose',
  (link) => {
    const board = link.quiet(bootrom);
    const target = [15, 0, 0, 0, 0, 0]; // 15 mm at 50 mm/s: 0.3 s = 15 frames
    const frames = plannedFrames(HOME, target, DEFAULTS);
    assert.equal(frames, 15);
    ok(board, `pose ${poseText(target)}`);
    runFrames(board, 5);
    const s = status(board);
    const match = s.state.match(/^moving (\d+\.\d{3}) of (\d+\.\d{3}) s$/);
    assert.ok(match, s.state);
    assert.equal(Number(match[2]), frames / 50);
    assert.ok(Number(match[1]) > 0 && Number(match[1]) < Number(match[2]), s.state);
    assertClose(s.target, target, 0.0005);
    assert.ok(s.pose[0] > 0 && s.pose[0] < 15, `pose x ${s.pose[0]} between start and target`);
    // The reported pulses are those of the reported pose.
    assertClose(s.pulse_us, solve(s.pose).pulse_us, 0.05, 'pulses of the reported pose');
  },
);

linkTest(
  'stop mid-move freezes where it is: pins constant, pose on the line between start and target',
  (link) => {
    const board = link.quiet(bootrom);
    ok(board, 'set speed_mm_s 10');
    const settings = { ...DEFAULTS, speed_mm_s: 10 };
    const target = [12, -6, 9, 0, 0, 0]; // 16.2 mm at 10 mm/s: 1.62 s
    ok(board, `pose ${poseText(target)}`);
    runFrames(board, 30);
    ok(board, 'stop');
    runFrames(board, 2); // the frame in flight
    const held = widthsNanos(board);
    const pulses = capture(board, () => {}, 20);
    assertConstant(pulses, held, 'after stop');

    const s = status(board);
    assert.equal(s.state, 'idle');
    assert.deepEqual(s.target, s.pose, 'target = where it stopped');
    // On the straight line HOME -> target, strictly between.
    const t = s.pose[0] / target[0];
    assert.ok(t > 0.1 && t < 0.9, `stopped at fraction ${t}`);
    assertClose(s.pose, lerpPose(HOME, target, t), 0.002, 'on the line');
    assertPins(board, solve(s.pose, settings).pulse_us, 'pins = pulses of the stopped pose');
    // Stop while standing still is fine too; the next move starts from the stopped pose.
    ok(board, 'stop');
    moveAndSettle(board, 'home', s.pose, HOME, settings);
    assertPins(board, solve(HOME).pulse_us);
  },
);

/**
 * The default paired layout (docs/geometry-and-calibration.md: three pairs of servos 120 apart;
 * kinematics-core PairedLayout), computed here in f64: servo 2k+1 at 120k - 20 deg, 2k+2 at
 * 120k + 20 deg on r = 75 mm, their joints at 120k - 60 + 20 and 120k + 60 - 20 deg on
 * r = 60 mm, arms tangential pointing away from the pair centre (beta = angle -+ 90 deg);
 * h0 from seed eq. 10 and alpha0 from eq. 9 at the home pose (eq. 12).
 */
function documentedGeometry() {
  const rad = (deg) => (deg * Math.PI) / 180;
  const a = 20;
  const s = 120;
  const legs = [];
  for (let k = 0; k < 3; k++) {
    const c = 120 * k;
    legs.push({ base: c - 20, platform: c - 60 + 20, beta: c - 20 - 90 });
    legs.push({ base: c + 20, platform: c + 60 - 20, beta: c + 20 + 90 });
  }
  return legs.map(({ base, platform, beta }) => {
    const b = [75 * Math.cos(rad(base)), 75 * Math.sin(rad(base)), 0];
    const p = [60 * Math.cos(rad(platform)), 60 * Math.sin(rad(platform)), 0];
    const h0 = Math.sqrt(s * s + a * a - (p[0] - b[0]) ** 2 - (p[1] - b[1]) ** 2) - p[2];
    const L = 2 * a * a;
    const M = 2 * a * (h0 + p[2] - b[2]);
    const N = 2 * a * (Math.cos(rad(beta)) * (p[0] - b[0]) + Math.sin(rad(beta)) * (p[1] - b[1]));
    const alpha0 = Math.asin(L / Math.hypot(M, N)) - Math.atan2(N, M);
    return { b, p, beta, h0, alpha0Deg: (alpha0 * 180) / Math.PI };
  });
}

linkTest(
  'geometry reports b_i, p_i, beta_i, a, s, h0 and alpha0 of the documented default build',
  (link) => {
    const board = link.quiet(bootrom);
    const data = ok(board, 'geometry');
    const expected = documentedGeometry();
    // The documented figures (docs/geometry-and-calibration.md): h0 118.458 mm, alpha0 -0.252 deg.
    assert.equal(expected[0].h0.toFixed(3), '118.458');
    assert.equal(expected[0].alpha0Deg.toFixed(3), '-0.252');

    const value = (key) => {
      const line = data.find((text) => text.startsWith(key));
      assert.ok(line, `no '${key}' in ${JSON.stringify(data)}`);
      return line;
    };
    assert.match(
      value('layout:'),
      /paired base_radius_mm=75\.000 base_half_angle_deg=20\.000 platform_radius_mm=60\.000 platform_half_angle_deg=20\.000/,
    );
    assert.equal(value('arm_mm'), 'arm_mm (a): 20.000');
    assert.equal(value('rod_mm'), 'rod_mm (s): 120.000');
    assert.equal(value('home_height_mm'), `home_height_mm (h0): ${expected[0].h0.toFixed(3)}`);
    const legLines = data.filter((text) => text.startsWith('leg '));
    assert.equal(legLines.length, 6);
    legLines.forEach((text, i) => {
      const m = text.match(
        /^leg (\d): b_mm=\((\S+), (\S+), (\S+)\) p_mm=\((\S+), (\S+), (\S+)\) beta_deg=(\S+) alpha0_deg=(\S+)$/,
      );
      assert.ok(m, text);
      assert.equal(Number(m[1]), i + 1);
      const e = expected[i];
      assertClose(m.slice(2, 5).map(Number), e.b, 0.0011, `leg ${i + 1} b`);
      assertClose(m.slice(5, 8).map(Number), e.p, 0.0011, `leg ${i + 1} p`);
      // beta as an angle: equal modulo 360.
      const dBeta = ((((Number(m[8]) - e.beta) % 360) + 540) % 360) - 180;
      assert.ok(Math.abs(dBeta) < 0.0011, `leg ${i + 1} beta ${m[8]} vs ${e.beta}`);
      assert.ok(
        Math.abs(Number(m[9]) - e.alpha0Deg) < 0.0011,
        `leg ${i + 1} alpha0 ${m[9]} vs ${e.alpha0Deg}`,
      );
    });
    // ... and the same as the host core's geometry.
    const core = reference.geometry(DEFAULTS);
    assert.ok(Math.abs(core.h0_mm - expected[0].h0) < 0.001, `core h0 ${core.h0_mm}`);
  },
);

linkTest('config lists every documented setting with its documented default', (link) => {
  const board = link.quiet(bootrom);
  const data = ok(board, 'config');
  const expected = [
    'frame_hz: 50',
    'baud: 115200', // UART0's rate, whichever link asks
    'echo: off', // turned off by link.quiet, on the asking link
    'speed_mm_s: 50.000',
    'speed_deg_s: 60.000',
    'accel_mm_s2: off',
    'accel_deg_s2: off',
    'link_timeout_s: off',
    'base_radius_mm: 75.000',
    'base_half_angle_deg: 20.000',
    'platform_radius_mm: 60.000',
    'platform_half_angle_deg: 20.000',
    'arm_mm: 20.000',
    'rod_mm: 120.000',
    'stream.x_mm: 25.000',
    'stream.y_mm: 25.000',
    'stream.z_mm: 15.000',
    'stream.roll_deg: 15.000',
    'stream.pitch_deg: 15.000',
    'stream.yaw_deg: 20.000',
    'stream.bits: 8',
    'stream.axis1: x',
    'stream.axis2: y',
    'stream.axis3: z',
    'stream.axis4: roll',
    'stream.axis5: pitch',
    'stream.axis6: yaw',
    'stream.max_step_pct: off',
    'estop_pin: off',
    'estop_action: freeze',
    'power_pin: off',
    'payload_g: 0.0',
    'payload_com_x_mm: 0.000',
    'payload_com_y_mm: 0.000',
    'payload_com_z_mm: 0.000',
    'pivot_x_mm: 0.000',
    'pivot_y_mm: 0.000',
    'pivot_z_mm: 0.000',
    ...[1, 2, 3, 4, 5, 6].map(
      (n) =>
        `servo${n}: trim_us=1500.00 rate_us_rad=${(1600 / Math.PI).toFixed(3)} dir=${n % 2 ? 'reversed' : 'normal'} min_us=1100.00 max_us=1900.00 torque_kgcm=off speed_s_60deg=off`,
    ),
    // Then how they stand against the saved ones: a new board has nothing saved.
    'saved: none (nothing saved in flash: the defaults at power-up)',
  ];
  assert.deepEqual(data, expected);
});

linkTest('commands are case-insensitive', (link) => {
  const board = link.quiet(bootrom);
  const pose = [3, 1, 4, 0, 0, 5];
  moveAndSettle(board, `POSE ${poseText(pose)}`, HOME, pose);
  assertPins(board, solve(pose).pulse_us);
  const moved = [3, 1, 6, 2, 0, 5];
  moveAndSettle(board, 'Move Z=6 ROLL=2', pose, moved);
  assertPins(board, solve(moved).pulse_us);
  assert.equal(status(board).state, 'idle');
  assert.equal(board.request('STATUS').reply, 'ok');
  // `?` is status.
  assert.deepEqual(ok(board, '?'), ok(board, 'status'));
  assert.equal(board.request('Set Speed_MM_S 40').reply, 'ok');
  assert.ok(ok(board, 'CONFIG').includes('speed_mm_s: 40.000'));
  assert.equal(board.request('HoMe').reply, 'ok');
});

linkTest('LF, CRLF and CR each end a line, with the same replies', (link) => {
  const board = link.quiet(bootrom);
  const answers = [];
  for (const end of ['\n', '\r\n', '\r']) {
    const first = board.lines.length;
    board.sendBytes(`check 1 2 3 4 5 6${end}`);
    board.waitForLine(/^(ok|error:)/);
    answers.push(board.lines.slice(first));
  }
  assert.deepEqual(answers[1], answers[0]);
  assert.deepEqual(answers[2], answers[0]);
  assert.equal(answers[0].at(-1), 'ok');
  // A CRLF is one line end, not a line and a blank line: exactly three replies so far.
  board.runMs(20);
  assert.equal(board.lines.filter((line) => line === 'ok').length, 1 + 3); // + set echo off
});

linkTest(
  'echo on: typed characters come back, backspace and DEL erase, a prompt follows each reply',
  (link) => {
    const board = link.terminal(bootrom);
    assert.ok(
      board.runUntil(() => board.partialLine === '> ', { timeoutMs: 20 }),
      'no prompt',
    );
    const start = board.outputBytes.length;
    // "statux" <BS> "s": the line is "status". Then "cheq" <DEL> "ck 0 0 1 0 0 0".
    board.sendBytes('statux\x08s\n');
    board.waitForLine(/^ok$/);
    board.sendBytes('cheq\x7fck 0 0 1 0 0 0\r\n');
    board.waitForLine(/^ok$/);
    board.runMs(5);
    const text = Buffer.from(board.outputBytes.slice(start)).toString('latin1');
    assert.ok(text.startsWith('statux\x08 \x08s\r\n# state: idle\r\n'), JSON.stringify(text));
    assert.ok(
      text.includes('ok\r\n> cheq\x08 \x08ck 0 0 1 0 0 0\r\n# arm_deg: '),
      JSON.stringify(text),
    );
    assert.ok(text.endsWith('ok\r\n> '), JSON.stringify(text));

    // Echo off: no echo, no prompt; only the replies.
    board.sendBytes('set echo off\n');
    board.waitForLine(/^ok$/);
    const quiet = board.outputBytes.length;
    board.sendBytes('help\n');
    board.waitForLine(/^ok$/);
    board.runMs(5);
    const replies = Buffer.from(board.outputBytes.slice(quiet)).toString('latin1');
    const replyLines = replies.split('\r\n');
    assert.equal(replyLines.pop(), '', 'ends with a line end, no prompt');
    assert.equal(replyLines.pop(), 'ok');
    assert.ok(
      replyLines.length > 5 && replyLines.every((line) => line.startsWith('# ')),
      JSON.stringify(replies),
    );
    // And back on.
    board.sendBytes('set echo on\n');
    board.waitForLine(/^ok$/);
    board.runMs(5);
    assert.equal(board.partialLine, '> ');
  },
);

linkTest('a blank line gets no reply; every other line exactly one, last', (link) => {
  const board = link.quiet(bootrom);
  const first = board.lines.length;
  board.sendBytes('\n   \n\t\nstatus\n');
  board.waitForLine(/^ok$/);
  board.runMs(20);
  const lines = board.lines.slice(first);
  assert.equal(lines.filter((line) => /^(ok|error:)/.test(line)).length, 1, JSON.stringify(lines));
  assert.ok(
    lines.slice(0, -1).every((line) => line.startsWith('# ')),
    JSON.stringify(lines),
  );
});

linkTest(
  'line editing: ctrl-u erases the line, ctrl-c abandons it (no reply), arrow keys and other control bytes are ignored',
  (link) => {
    const board = link.quiet(bootrom);
    const first = board.lines.length;
    // "fly" erased by ctrl-u, then "status": one ok with the status lines.
    board.sendBytes('fly\x15status\n');
    board.waitForLine(/^(ok|error:)/);
    // Abandoned with ctrl-c: no reply at all; then an arrow key (ESC [ A) and a bell (0x07)
    // inside a good line change nothing.
    board.sendBytes('pose 0 0 80 0 0 0\x03');
    board.sendBytes('che\x1b[Ack 1 2\x07 3 0 0 0\n');
    board.waitForLine(/^(ok|error:)/);
    board.runMs(20);
    const replies = board.lines.slice(first).filter((line) => !line.startsWith('# '));
    assert.deepEqual(replies, ['ok', 'ok']);
    assert.ok(
      board.lines.slice(first).some((line) => line.startsWith('# state: ')),
      'the first line was status',
    );
    assert.ok(
      board.lines.slice(first).some((line) => line.startsWith('# duration_s: ')),
      'the second was check',
    );
  },
);

linkTest(
  'ctrl-x abandons a line like ctrl-c: no reply, and what follows starts a new line',
  (link) => {
    const board = link.quiet(bootrom);
    const first = board.lines.length;
    board.sendBytes('home\x18');
    board.runMs(50);
    assert.deepEqual(board.lines.slice(first), [], 'no reply to an abandoned line');
    board.sendBytes('st\x18atus\n');
    const reply = board.waitForLine(/^(ok|error:)/);
    assert.equal(reply, "error:unknown-command 'atus' is not a command; type help");
  },
);

linkTest('what terminals send for keys is ignored whole; a lone ESC swallows nothing', (link) => {
  const board = link.quiet(bootrom);
  // The Esc key, then a command: the command runs whole.
  assert.equal(board.request('\x1bhome').reply, 'ok');
  assert.equal(board.request('\x1b\x1bstop').reply, 'ok');
  // Keys inside a line, as xterm and friends send them: arrows in both modes, Home, End,
  // Delete, PgUp, F1, F5, F12, Ctrl-Right, Shift-F3, and bracketed paste around the line.
  const keys = [
    '\x1b[A',
    '\x1bOB',
    '\x1b[H',
    '\x1b[F',
    '\x1b[1~',
    '\x1b[4~',
    '\x1b[3~',
    '\x1b[5~',
    '\x1bOP',
    '\x1b[15~',
    '\x1b[24~',
    '\x1b[1;5C',
    '\x1b[1;2R',
  ];
  for (const key of keys) {
    const { reply, lines } = board.request(`st${key}atus`);
    assert.equal(reply, 'ok', `${JSON.stringify(key)}: ${JSON.stringify(lines)}`);
    assert.ok(
      lines.some((l) => l.startsWith('# state: ')),
      JSON.stringify(key),
    );
  }
  assert.equal(board.request('\x1b[200~home\x1b[201~').reply, 'ok');
});

linkTest('a line of separators only is not blank: it is refused, in words', (link) => {
  const board = link.quiet(bootrom);
  assert.equal(
    board.request(' , ,').reply,
    'error:unknown-command only separators, no command; type help',
  );
  assert.equal(board.request('status').reply, 'ok');
});
