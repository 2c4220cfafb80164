// Every error class through the real firmware binary, over UART0 and over the USB port (the
// USB link cannot lose input, so rx-overflow is UART0's alone): the reply is exactly one line
// `error:<code> <message>` naming what is wrong, nothing moves (pins constant over the
// following frames, status and config unchanged), and the next good line works. The codes
// come from docs/error-codes.md (written from the firmware's `Code::ALL`, kept up to date by
// control/tests/documents.rs); the last test checks that each code that can be produced
// through the wire was produced here.

import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { before, test } from 'node:test';

import {
  assertConstant,
  bootQuiet,
  capture,
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

const ERROR_CODES = readFileSync(new URL('../../docs/error-codes.md', import.meta.url), 'utf8');
/** Documented as impossible from typed input (typed non-finite numbers are `not-finite`). */
const NOT_REACHABLE_FROM_THE_WIRE = new Set(['pose-not-finite']);

const observed = new Set();
let bootrom;
let reference;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
});

/**
 * Sends `line` and expects `error:<code> <message>` with the message matching `message`;
 * nothing may change: pins constant for 5 frames, status (pose, target, pulses) and config
 * identical; then a good line works (`next`, with that many data lines: `check` by default,
 * which has a fourth line, the holding torques, with a payload; `status` where there is no
 * pose to check from).
 */
function expectRefusal(board, line, code, message, { next = ['check 1 1 1 1 1 1', 3] } = {}) {
  const before = { status: status(board), config: ok(board, 'config'), widths: widthsNanos(board) };
  let reply;
  const pulses = capture(
    board,
    () => {
      reply = refused(board, line, code);
    },
    5,
  );
  observed.add(code);
  assert.match(reply.slice(`error:${code} `.length), message, reply);
  assertConstant(pulses, before.widths, `after '${line}'`);
  const after = status(board);
  assert.deepEqual(after.pose, before.status.pose, 'pose unchanged');
  assert.deepEqual(after.target, before.status.target, 'target unchanged');
  assert.deepEqual(after.pulse_us, before.status.pulse_us, 'pulses unchanged');
  assert.deepEqual(ok(board, 'config'), before.config, 'settings unchanged');
  const [good, lines] = next;
  const data = ok(board, good);
  if (lines !== null) {
    assert.equal(data.length, lines, 'the next good line works');
  }
  return reply;
}

function quietBoardAt(link, pose) {
  const board = link.quiet(bootrom);
  if (pose) {
    ok(board, `pose ${poseText(pose)}`);
    runFrames(board, plannedFrames(HOME, pose, defaultSettings()) + 3);
  }
  return board;
}

// Words with a regexp-special character escaped.
const esc = (text) => text.replace(/[.*+?^${}()|[\]\\]/g, '\\$&');

const PARSE_CASES = [
  [
    'line-too-long',
    `pose ${'1 '.repeat(70)}`,
    /^line longer than 128 characters; it was discarded$/,
  ],
  [
    'bad-character',
    'pose 0 0 1 0 0 0\xb0',
    /^byte 0xB0 is not printable ASCII; the line was discarded$/,
  ],
  ['bad-character', 'sta\xfftus', /^byte 0xFF is not printable ASCII/],
  ['unknown-command', 'fly', /^'fly' is not a command; type help$/],
  [
    'unknown-command',
    'poses 1 2 3 4 5 6',
    /^'poses' is not a command; did you mean pose\? type help$/,
  ],
  ['missing-field', 'pose 1 2 3', /^missing roll; usage: pose <x> <y> <z> <roll> <pitch> <yaw>$/],
  ['missing-field', 'check', /^missing x; usage: check /],
  ['missing-field', 'move', /^missing axis=value; usage: move /],
  ['missing-field', 'set echo', /^missing .*usage: set <name> <value>/],
  ['extra-field', 'home now', /^unexpected 'now'; usage: home$/],
  ['extra-field', 'pose 1 2 3 4 5 6 7', /^unexpected '7'; usage: pose /],
  ['extra-field', 'status 1', /^unexpected '1'/],
  ['extra-field', 'set echo on off', /^unexpected 'off'/],
  ['bad-number', 'pose 1 2 three 4 5 6', /^z: 'three' is not a decimal number$/],
  ['bad-number', 'pose 0x10 0 0 0 0 0', /^x: '0x10' is not a decimal number$/],
  ['bad-number', 'move yaw=1_000', /^yaw: '1_000' is not a decimal number$/],
  ['bad-number', 'set speed_mm_s fast', /^speed_mm_s: 'fast' is not a decimal number$/],
  ['not-finite', 'pose 1 2 3 nan 5 6', /^roll: 'nan' is not a finite number$/],
  ['not-finite', 'pose inf 0 0 0 0 0', /^x: 'inf' is not a finite number$/],
  ['not-finite', 'nudge pitch=-Infinity', /^pitch: '-infinity' is not a finite number$/],
  ['number-too-large', 'pose 1e39 0 0 0 0 0', /^x: '1e39' is too large$/],
  ['unknown-axis', 'move q=1', /^'q' is not an axis; axes are x y z roll pitch yaw$/],
  ['duplicate-axis', 'move z=1 z=2', /^z is given twice$/],
  ['bad-assignment', 'move z 10', /^'z' should be axis=value, for example z=10$/],
  ['unknown-setting', 'set colour red', /^'colour' is not a setting; type config for the list$/],
  ['unknown-setting', 'set servo7.trim_us 1500', /^'servo7.trim_us' is not a setting/],
  [
    'unknown-setting',
    'set rdo_mm 120',
    /^'rdo_mm' is not a setting; did you mean rod_mm\? type config for the list$/,
  ],
  ['bad-value', 'set echo sometimes', /^echo: 'sometimes' is not on or off \(1 \/ 0\)$/],
  [
    'bad-value',
    'set baud 100000',
    /^baud: '100000' is not one of 9600 19200 38400 57600 115200 230400 460800 921600$/,
  ],
  [
    'bad-value',
    'set servo1.dir sideways',
    /^servo1\.dir: 'sideways' is not normal or reversed \(1 \/ \+1 \/ -1\)$/,
  ],
  [
    'bad-value',
    'set servos.dir 0',
    /^servos\.dir: '0' is not normal or reversed \(1 \/ \+1 \/ -1\)$/,
  ],
  ['bad-value', 'set frame_hz 60.5', /^frame_hz: '60\.5' is not a whole number$/],
  ['out-of-range', 'set frame_hz 20', /^frame_hz 20 is outside 50\.\.333 Hz$/],
  ['out-of-range', 'set frame_hz 334', /^frame_hz 334 is outside 50\.\.333 Hz$/],
  ['out-of-range', 'set frame_hz -50', /^frame_hz -50 is outside 50\.\.333 Hz$/],
  [
    'bad-value',
    'set baud -9600',
    /^baud: '-9600' is not one of 9600 19200 38400 57600 115200 230400 460800 921600$/,
  ],
  [
    'out-of-range',
    'set speed_mm_s 2000',
    /^speed_mm_s 2000 is outside 0\.1\.\.1000 mm\/s \(or 0\/off\)$/,
  ],
  ['out-of-range', 'set servo2.trim_us 3000', /^servo2\.trim_us 3000 is outside 400\.\.2600 us$/],
  [
    'out-of-range',
    'set servos.rate_us_rad 50',
    /^servos\.rate_us_rad 50 is outside 100\.\.5000 us\/rad$/,
  ],
  ['out-of-range', 'set arm_mm 0', /^arm_mm 0 is outside 1\.\.500 mm$/],
  [
    'bad-servo-config',
    'set servo1.trim_us 1950',
    /^servo1\.trim_us 1950\.00 us must lie within servo1\.min_us\.\.max_us = 1100\.00\.\.1900\.00 us; nothing changed$/,
  ],
  [
    'bad-servo-config',
    'set servo4.max_us 1400',
    /^servo4\.trim_us 1500\.00 us must lie within servo4\.min_us\.\.max_us = 1100\.00\.\.1400\.00 us; nothing changed$/,
  ],
  ['bad-geometry', 'set rod_mm 15', /^leg \d: .*rod_mm too short.*; nothing changed$/],
  [
    'bad-value',
    'set stream.axis3 heave',
    /^stream\.axis3: 'heave' is not one of x y z roll pitch yaw none$/,
  ],
  [
    'bad-value',
    'set estop_pin 3',
    /^estop_pin: '3' is not off or a free GPIO: 8 9 10 .* 22 26 27 28$/,
  ],
  ['out-of-range', 'set stream.bits 7', /^stream\.bits 7 is outside 8\.\.16 bits$/],
  [
    'setting-conflict',
    'set stream.axis2 x',
    /^stream\.axis1 and stream\.axis2 would both be x; .*; nothing changed$/,
  ],
  ['angle-too-large', 'pose 0 0 0 181 0 0', /^roll 181\.000 deg is beyond \+-180 deg$/],
  ['angle-too-large', 'check 0 0 0 0 -200 0', /^pitch -200\.000 deg is beyond \+-180 deg$/],
  [
    'servo-limit',
    'servo 2 2000',
    /^servo 2: 2000\.00 us is outside its limits 1100\.00\.\.1900\.00 us \(servo2\.min_us, max_us\)$/,
  ],
  [
    'servo-limit',
    'servo 5 1099.9',
    /^servo 5: 1099\.90 us is outside its limits 1100\.00\.\.1900\.00 us/,
  ],
  [
    'servo-limit',
    'servo 2 1900.004',
    /^servo 2: 1900\.004 us is outside its limits 1100\.00\.\.1900\.00 us/,
  ],
  ['bad-value', 'servo 7 1500', /^'7' is not a servo number; servos are 1 to 6$/],
  ['bad-value', 'servo x 1500', /^'x' is not a servo number; servos are 1 to 6$/],
  ['missing-field', 'servo 3', /^missing pulse_us; usage: servo <1-6> <us>$/],
  ['bad-number', 'servo 3 wide', /^pulse_us: 'wide' is not a decimal number$/],
  ['not-finite', 'servo 3 inf', /^pulse_us: 'inf' is not a finite number$/],
  ['extra-field', 'limits now', /^unexpected 'now'; usage: limits$/],
  [
    'out-of-range',
    'set servo2.torque_kgcm 700',
    /^servo2\.torque_kgcm 700 is outside 0\.01\.\.600 kgf cm \(or 0\/off\)$/,
  ],
  ['out-of-range', 'set payload_g -5', /^payload_g -5 is outside 0\.\.100000 g$/],
  [
    'out-of-range',
    'set servos.speed_s_60deg 3',
    /^servos\.speed_s_60deg 3 is outside 0\.01\.\.2\.55 s\/60deg \(or 0\/off\)$/,
  ],
  [
    'bad-value',
    'set servo2.speed_s_60deg 0.125',
    /^servo2\.speed_s_60deg: '0\.125' is not a number of hundredths \(at most two decimals: /,
  ],
];

// One board for these: each refusal must leave it exactly as it was (which each checks), so
// the next case starts from the same state. Away from home, so "nothing moved" is not just
// "still at home".
const parseBoards = new Map();
for (const [code, line, message] of PARSE_CASES) {
  linkTest(`${code}: ${JSON.stringify(line).slice(0, 60)}`, (link) => {
    if (!parseBoards.has(link)) {
      parseBoards.set(link, quietBoardAt(link, [3, -2, 1, 2, -1, 4]));
    }
    expectRefusal(parseBoards.get(link), line, code, message);
  });
}

linkTest('unreachable: names the leg the host core names; pose and check alike', (link) => {
  const settings = defaultSettings();
  const board = quietBoardAt(link, null);
  for (const pose of [
    [0, 0, 80, 0, 0, 0],
    [60, 0, 0, 0, 0, 0],
    [0, -45, 10, 0, 0, 90],
  ]) {
    const [core] = reference.solve(settings, [pose]);
    assert.equal(core.code, 'unreachable', `${pose}: ${JSON.stringify(core)}`);
    const message = new RegExp(
      `^leg ${core.leg} cannot reach \\(arm and rod cannot meet the platform joint\\)$`,
    );
    expectRefusal(board, `pose ${poseText(pose)}`, 'unreachable', message);
    expectRefusal(board, `check ${poseText(pose)}`, 'unreachable', message);
  }
});

linkTest(
  'servo-limit: names the servo, the pulse it would need (as the host core computes it) and its limits',
  (link) => {
    const settings = defaultSettings();
    const board = quietBoardAt(link, null);
    for (const pose of [
      [0, 0, -15, 0, 0, 0],
      [0, 0, 15, 0, 0, 0],
      [0, 0, 0, 14, 0, 0],
    ]) {
      const [core] = reference.solve(settings, [pose]);
      assert.equal(core.code, 'servo-limit', `${pose}: ${JSON.stringify(core)}`);
      const reply = expectRefusal(
        board,
        `pose ${poseText(pose)}`,
        'servo-limit',
        new RegExp(
          `^servo ${core.servo} would need \\d+\\.\\d{2} us, outside its limits 1100\\.00\\.\\.1900\\.00 us$`,
        ),
      );
      const needed = Number(reply.match(/need (\d+\.\d{2}) us/)[1]);
      assert.ok(
        Math.abs(needed - core.pulse_us) <= 0.01,
        `${needed} vs host core ${core.pulse_us}`,
      );
    }
  },
);

linkTest('path-blocked: both ends reachable, the straight line between them not', (link) => {
  const settings = defaultSettings();
  const from = [-28, 19, -2.5, 11, 2, -20];
  const to = [30, -12, -13.5, 5, -13, 28];
  const answers = reference.solve(
    settings,
    Array.from({ length: 501 }, (_, i) => lerpPose(from, to, i / 500)),
  );
  assert.ok(answers[0].ok && answers[500].ok && answers.some((a) => !a.ok));
  const board = quietBoardAt(link, from);
  expectRefusal(
    board,
    `pose ${poseText(to)}`,
    'path-blocked',
    /^the straight path from the current pose is blocked \d+\.\d% of the way: (servo \d would need|leg \d cannot reach).*; nothing moved$/,
  );
  expectRefusal(
    board,
    `move x=${to[0]} y=${to[1]} z=${to[2]} roll=${to[3]} pitch=${to[4]} yaw=${to[5]}`,
    'path-blocked',
    /blocked/,
  );
});

linkTest('pose-conflict: a setting the held pose could not be driven with is refused', (link) => {
  const settings = defaultSettings();
  const pose = [0, 0, -8, 0, 0, 0];
  const [core] = reference.solve(settings, [pose]);
  assert.ok(core.pulse_us[0] > 1600, `servo 1 at ${pose} needs ${core.pulse_us[0]} us`);
  const board = quietBoardAt(link, pose);
  expectRefusal(
    board,
    'set servo1.max_us 1600',
    'pose-conflict',
    /^with that setting the current pose could not be held: servo 1 would need \d+\.\d{2} us, outside its limits 1100\.00\.\.1600\.00 us; send home first$/,
  );
  // The same setting is fine at home, where servo 1 needs 1500 us.
  ok(board, 'home');
  runFrames(board, 12);
  ok(board, 'set servo1.max_us 1600');
});

linkTest(
  'busy while moving: frame rate, geometry, servos, defaults, save; the move goes on',
  (link) => {
    const settings = defaultSettings();
    const board = link.quiet(bootrom);
    ok(board, 'set speed_mm_s 5');
    const target = [0, 0, 10, 0, 0, 0]; // 2 s
    const config = ok(board, 'config');
    ok(board, `pose ${poseText(target)}`);
    const refusedWhileMoving = ['set frame_hz 100', 'set rod_mm 121', 'set servo3.trim_us 1510'];
    const alsoRefused = [
      'set servos.dir normal',
      'defaults',
      'save',
      'servo 3 1600',
      'set payload_g 500',
      'set servo2.torque_kgcm 5',
    ];
    for (const line of [...refusedWhileMoving, ...alsoRefused]) {
      const reply = refused(board, line, 'busy');
      observed.add('busy');
      assert.equal(reply, 'error:busy the platform is moving; wait for it or send stop first');
      assert.match(status(board).state, /^moving /);
    }
    // Speeds and echo may change while moving.
    ok(board, 'set speed_deg_s 30');
    ok(board, 'set speed_deg_s 60');
    assert.deepEqual(ok(board, 'config'), config);
    assert.deepEqual(periodsUs(board), Array(6).fill(20_000));
    runFrames(board, plannedFrames(HOME, target, { ...settings, speed_mm_s: 5 }) + 5);
    const s = status(board);
    assert.equal(s.state, 'idle');
    assert.deepEqual(s.pose, target);
    // Afterwards the same settings are accepted.
    ok(board, 'set frame_hz 100');
  },
);

test('rx-overflow: bytes lost while the firmware was busy refuse the line they fell into', () => {
  const board = bootQuiet(bootrom);
  ok(board, 'set baud 921600');
  board.runMs(1);
  assert.ok(Math.abs(board.baud - 921600) / 921600 < 0.02, `baud ${board.baud}`);
  const widths = widthsNanos(board);
  const first = board.lines.length;
  ok(board, 'set speed_mm_s 1');
  const pulses = capture(
    board,
    () => {
      // A check of a slow 20 mm move: its path checked at all 1,000 frames, a few poses per
      // pass, keeps the firmware from taking lines for about 90 ms (1,000 IKs and their
      // slices) while 6,000 bytes of `stop` lines arrive at 921,600 baud in 65 ms: more than the
      // 4,096-byte receive queue holds, and all of them before the check's reply, so the loss
      // runs to the burst's end and the line it fell into stays open.
      board.sendBytes(`check 20 0 0 0 0 0\n${'stop\n'.repeat(1200)}`);
      board.runMs(600);
    },
    10,
  );
  const lines = board.lines.slice(first);
  const warningAt = lines.findIndex((l) =>
    /^# warning: receive queue overflowed, input lost \(at least \d+ bytes? so far\)$/.test(l),
  );
  assert.ok(warningAt >= 0, `no warning in ${JSON.stringify(lines.slice(0, 5))}...`);
  const soFar = Number(lines[warningAt].match(/at least (\d+)/)[1]);
  // The warning came at once: while the lines before the gap were still being answered.
  const repliesAfter = lines.slice(warningAt).filter((l) => l === 'ok').length;
  assert.ok(repliesAfter > 10, `the warning came only ${repliesAfter} replies before the gap`);
  // Every reply so far is ok: the lines that arrived whole ran, the lost ones got nothing.
  assert.ok(lines.filter((line) => !line.startsWith('# ')).every((line) => line === 'ok'));
  // The line the loss fell into ends with the next LF: refused, naming the loss.
  board.lineCursor = board.lines.length;
  const reply = refused(board, 'status', 'rx-overflow');
  observed.add('rx-overflow');
  const lost = Number(reply.match(/overflowed, (\d+) bytes lost/)?.[1]);
  assert.ok(lost >= soFar, `${lost} lost, the warning said at least ${soFar}`);
  assert.equal(
    reply,
    `error:rx-overflow receive queue overflowed, ${lost} bytes lost; the line was discarded (wait for each reply before sending more)`,
  );
  assertConstant(pulses, widths, 'nothing moved');
  assert.equal(ok(board, 'check 1 1 1 1 1 1').length, 3, 'the next good line works');
  assert.equal(
    board.rxFifoDroppedBytes,
    0,
    'the loss was in the firmware queue, not the UART FIFO',
  );
});

linkTest(
  'e-stop: with the input open, moves are refused until it is closed and reset is sent',
  (link) => {
    const board = quietBoardAt(link, [3, -2, 1, 2, -1, 4]);
    ok(board, 'set estop_pin 15');
    board.drivePin(15, false); // the switch closed: the pin held low
    runFrames(board, 2);
    board.drivePin(15, null); // the switch opens: the pull-up takes the pin high
    runFrames(board, 2);
    assert.equal(status(board)['e-stop'], 'open');
    expectRefusal(
      board,
      'home',
      'e-stop',
      /^emergency stop: the e-stop input is open; close it, then send reset$/,
    );
    expectRefusal(board, 'servo 1 1600', 'e-stop', /^emergency stop: the e-stop input is open/);
    board.drivePin(15, false);
    runFrames(board, 2);
    expectRefusal(
      board,
      'pose 0 0 1 0 0 0',
      'e-stop',
      /^emergency stop: the e-stop input is closed again; send reset to move again$/,
    );
    ok(board, 'reset');
    ok(board, 'home');
  },
);

test('save-failed: the flash did not keep what was written; the last save stays and loads', () => {
  const board = bootQuiet(bootrom);
  ok(board, 'set servo1.trim_us 1510');
  ok(board, 'save'); // save 1, sector 0
  ok(board, 'set servo1.trim_us 1520');
  // A worn cell in sector 1, where save 2 goes: byte 5 (the format version's high byte, 0)
  // keeps its bit 0 set, whatever is programmed.
  const { offset } = board.settingsStorage;
  board.flash.wearOut(offset + 4096 + 5, 0x01);
  const reply = expectRefusal(board, 'save', 'save-failed', /^the flash did not keep what/);
  assert.equal(
    reply,
    'error:save-failed the flash did not keep what was written (byte 4101 of the settings ' +
      'storage read 0x01, not 0x00); the settings saved before are kept',
  );
  // At the next power-up: save 1, and a word about the copy that failed (cleared to zeros).
  board.powerCycle();
  board.waitForLine(/hexapod\b.*\bhelp\b/);
  assert.equal(
    board.waitForLine(/^# warning/),
    '# warning: one of the two saved copies of the settings cannot be used (damaged: not a ' +
      'settings record); loaded the other, save 1: check config',
  );
  assert.equal(board.request('set echo off').reply, 'ok');
  const servo1 = ok(board, 'config').find((l) => l.startsWith('servo1: '));
  assert.match(servo1, /^servo1: trim_us=1510\.00 /);
});

/** A payload of 2 kg, 30 mm above the platform's centre (docs/settings.md, "Payload ..."). */
function withPayload(settings, ratingKgcm) {
  const s = structuredClone(settings);
  s.payload = { payload_g: 2000, payload_com_x_mm: 0, payload_com_y_mm: 0, payload_com_z_mm: 30 };
  for (const servo of s.servos) {
    servo.torque_kgcm = ratingKgcm;
  }
  return s;
}

function setPayload(board, ratingKgcm) {
  ok(board, 'set payload_g 2000');
  ok(board, 'set payload_com_z_mm 30');
  if (ratingKgcm !== 'off') {
    ok(board, `set servos.torque_kgcm ${ratingKgcm}`);
  }
}

/** The most any servo needs at a pose (the host core), kgf cm. */
function mostTorque(settings, pose) {
  const [answer] = reference.torques(settings, [pose]);
  assert.ok(answer.ok, `${pose}: ${JSON.stringify(answer)}`);
  return Math.max(...answer.torque_kgcm.map(Math.abs));
}

linkTest(
  'torque-limit: names the servo, the torque it would need (as the host core computes it) and its rating',
  (link) => {
    const settings = withPayload(defaultSettings(), 1);
    const board = quietBoardAt(link, null);
    setPayload(board, 1);
    const check = { next: ['check 0 0 -1 0 0 0', 4] }; // with the torque line
    for (const pose of [
      [10, 0, 0, 0, 0, 0],
      [0, -8, 0, 0, 0, 0],
      [0, 0, 0, 0, 0, 9],
    ]) {
      assert.ok(reference.solve(settings, [pose])[0].ok, `${pose} is reachable`);
      const [core] = reference.torques(settings, [pose]);
      const servo = core.torque_kgcm.findIndex((t) => Math.abs(t) > 1) + 1;
      assert.ok(servo > 0, `${pose}: ${core.torque_kgcm}`);
      for (const line of [`pose ${poseText(pose)}`, `check ${poseText(pose)}`]) {
        const reply = expectRefusal(
          board,
          line,
          'torque-limit',
          new RegExp(
            `^servo ${servo} would need \\d+\\.\\d{3} kgf cm to hold the payload, over its rating 1\\.00 kgf cm$`,
          ),
          check,
        );
        const needed = Number(reply.match(/need (\d+\.\d{3}) kgf/)[1]);
        assert.ok(
          Math.abs(needed - Math.abs(core.torque_kgcm[servo - 1])) <= 0.002,
          `${needed} vs host core ${core.torque_kgcm}`,
        );
      }
    }
  },
);

linkTest(
  'path-blocked by torque: both ends within the ratings, the middle of the way not',
  (link) => {
    const settings = withPayload(defaultSettings(), 2.5);
    const from = [-1, 5.5, 6, -0.5, -4.5, 13];
    const to = [-9, 10.5, -4.5, -5, 7.5, 8];
    assert.ok(mostTorque(settings, from) < 2.5 && mostTorque(settings, to) < 2.5);
    assert.ok(mostTorque(settings, lerpPose(from, to, 0.5)) > 2.5);
    const board = quietBoardAt(link, from);
    setPayload(board, 2.5);
    expectRefusal(
      board,
      `pose ${poseText(to)}`,
      'path-blocked',
      /^the straight path from the current pose is blocked \d+\.\d% of the way: servo \d would need \d+\.\d{3} kgf cm to hold the payload, over its rating 2\.50 kgf cm; nothing moved$/,
      { next: ['check 0 0 -1 0 0 0', 4] },
    );
  },
);

linkTest('pose-conflict: a rating or payload the held pose would exceed is refused', (link) => {
  const board = quietBoardAt(link, [0, 0, -8, 0, 0, 0]);
  ok(board, 'set payload_g 2000');
  // At z = -8 each servo needs about 0.6 kgf cm (a sixth of 2 kgf on a 2 cm arm, less the rods' lean).
  const need = mostTorque(withPayload(defaultSettings(), 'off'), [0, 0, -8, 0, 0, 0]);
  assert.ok(need > 0.5 && need < 0.7, `${need}`);
  expectRefusal(
    board,
    'set servos.torque_kgcm 0.5',
    'pose-conflict',
    /^with that setting the current pose could not be held: servo 1 would need \d\.\d{3} kgf cm to hold the payload, over its rating 0\.50 kgf cm; send home first$/,
    { next: ['check 0 0 -1 0 0 0', 4] },
  );
});

linkTest(
  'no-pose: pulses set with servo that correspond to no pose refuse moves until driven back',
  (link) => {
    const settings = defaultSettings();
    const board = quietBoardAt(link, null);
    ok(board, 'servo 1 1900');
    ok(board, 'servo 2 1900');
    runFrames(board, 2); // the pins take the new pulses at their next period
    const pulses = [1900, 1900, 1500, 1500, 1500, 1500];
    assert.equal(
      reference.forwardKinematics(settings, pulses, status(board).pose).ok,
      false,
      'the host core finds none either',
    );
    assert.match(
      ok(board, 'status').find((l) => l.startsWith('pulse_pose: ')),
      /^pulse_pose: none \(the rods cannot all reach their joints/,
    );
    for (const line of ['home', 'pose 0 0 1 0 0 0', 'check 0 0 1 0 0 0', 'limits']) {
      expectRefusal(
        board,
        line,
        'no-pose',
        /^the pulses set with servo correspond to no pose of the platform \(.*\); drive the servos back with servo first \(servoN\.trim_us is home\)$/,
        { next: ['status', null] },
      );
    }
    ok(board, 'servo 2 1500');
    ok(board, 'servo 1 1500');
    ok(board, 'home');
  },
);

test('every documented error code exists in the firmware and was produced above through the wire', () => {
  // The list is the firmware's own (docs/error-codes.md = Code::ALL: control/tests/documents.rs).
  const documented = [...ERROR_CODES.matchAll(/^\| `error:([a-z-]+)` \|/gm)].map((m) => m[1]);
  assert.ok(documented.length >= 20, `found ${documented.length} codes in docs/error-codes.md`);
  const missing = documented.filter(
    (code) => !observed.has(code) && !NOT_REACHABLE_FROM_THE_WIRE.has(code),
  );
  assert.deepEqual(missing, [], 'documented codes no test produced');
});
