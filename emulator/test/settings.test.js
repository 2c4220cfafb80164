// Settings through the real firmware: `set` changes what `config` lists and what the pins do
// (servo mappings and geometry as the host core predicts, frame rate on every pin without a
// cut pulse, baud rate on the line), `defaults` restores them. Refusals are in errors.test.js.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { EmulatedBoard } from '../src/chip/board.js';

import {
  assertConstant,
  assertPins,
  bootQuiet,
  capture,
  COUNT_NANOS,
  defaultSettings,
  firmwareBootrom,
  framePeriodNanos,
  HOME,
  ok,
  periodsUs,
  plannedFrames,
  poseText,
  quantisedUs,
  refused,
  runFrames,
  status,
  widthsNanos,
} from '../src/test-support/e2e-support.js';
import { HostReference } from '../src/test-support/host-reference.js';

let bootrom;
let reference;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
});

function solve(settings, pose) {
  const [answer] = reference.solve(settings, [pose]);
  assert.ok(answer.ok, `reference refuses ${pose}: ${JSON.stringify(answer)}`);
  return answer.pulse_us;
}

function moveTo(board, from, to, settings) {
  ok(board, `pose ${poseText(to)}`);
  runFrames(board, plannedFrames(from, to, settings) + 3, settings.frame_hz);
}

/** `config` as a map: name -> value text (servo lines: `servoN.field`). */
function config(board) {
  const values = new Map();
  for (const line of ok(board, 'config')) {
    const [name, rest] = line.split(': ');
    if (/^servo\d$/.test(name)) {
      for (const pair of rest.split(' ')) {
        const [field, value] = pair.split('=');
        values.set(`${name}.${field}`, value);
      }
    } else {
      values.set(name, rest);
    }
  }
  return values;
}

test('set changes exactly the named setting, as config lists it (units and decimals as documented)', () => {
  const board = bootQuiet(bootrom);
  board.drivePin(15, false); // an e-stop switch, closed, for `estop_pin 15` below
  const changes = [
    ['speed_mm_s 42.5', 'speed_mm_s', '42.500'],
    ['speed_mm_s off', 'speed_mm_s', 'off'],
    ['speed_deg_s 0', 'speed_deg_s', 'off'],
    ['speed_deg_s 3600', 'speed_deg_s', '3600.000'],
    ['link_timeout_s 2.5', 'link_timeout_s', '2.500'],
    ['link_timeout_s off', 'link_timeout_s', 'off'],
    ['frame_hz 333', 'frame_hz', '333'],
    ['frame_hz 50', 'frame_hz', '50'],
    ['servo3.trim_us 1512.34', 'servo3.trim_us', '1512.34'],
    ['servo5.rate_us_rad 600', 'servo5.rate_us_rad', '600.000'],
    ['servo2.dir reversed', 'servo2.dir', 'reversed'],
    ['servo2.dir normal', 'servo2.dir', 'normal'],
    ['servo6.min_us 1000', 'servo6.min_us', '1000.00'],
    ['servo6.max_us 2000', 'servo6.max_us', '2000.00'],
    ['rod_mm 121', 'rod_mm', '121.000'],
    ['arm_mm 21', 'arm_mm', '21.000'],
    ['base_radius_mm 76', 'base_radius_mm', '76.000'],
    ['platform_radius_mm 61', 'platform_radius_mm', '61.000'],
    ['base_half_angle_deg 19', 'base_half_angle_deg', '19.000'],
    ['platform_half_angle_deg 21', 'platform_half_angle_deg', '21.000'],
    ['accel_mm_s2 250', 'accel_mm_s2', '250.000'],
    ['accel_deg_s2 off', 'accel_deg_s2', 'off'],
    ['stream.z_mm -12.5', 'stream.z_mm', '-12.500'],
    ['stream.bits 12', 'stream.bits', '12'],
    ['stream.axis1 none', 'stream.axis1', 'none'],
    ['stream.axis4 x', 'stream.axis4', 'x'],
    ['stream.axis1 roll', 'stream.axis1', 'roll'],
    ['estop_pin 15', 'estop_pin', '15'],
    ['estop_action home', 'estop_action', 'home'],
    ['power_pin 16', 'power_pin', '16'],
    ['estop_pin off', 'estop_pin', 'off'],
    ['payload_g 1250', 'payload_g', '1250.0'],
    ['payload_com_y_mm -12.5', 'payload_com_y_mm', '-12.500'],
    ['payload_com_z_mm 40', 'payload_com_z_mm', '40.000'],
    // Ratings are kept to hundredths of a kgf cm (docs/settings.md).
    ['servo4.torque_kgcm 12.345', 'servo4.torque_kgcm', '12.35'],
    ['servo4.torque_kgcm off', 'servo4.torque_kgcm', 'off'],
    // Speed ratings too, as given (more decimals are refused: errors.test.js).
    ['servo3.speed_s_60deg 0.12', 'servo3.speed_s_60deg', '0.12'],
    ['servo3.speed_s_60deg off', 'servo3.speed_s_60deg', 'off'],
    // The step guard is kept to tenths of a percent (docs/settings.md).
    ['stream.max_step_pct 12.34', 'stream.max_step_pct', '12.3'],
    ['stream.max_step_pct off', 'stream.max_step_pct', 'off'],
  ];
  let expected = config(board);
  for (const [args, name, shown] of changes) {
    assert.ok(expected.has(name), `config lists ${name}`);
    ok(board, `set ${args}`);
    expected = new Map(expected).set(name, shown);
    assert.deepEqual(config(board), expected, `after set ${args}`);
  }
  // servos.<field> sets all six.
  ok(board, 'set servos.max_us 2100');
  for (let n = 1; n <= 6; n++) {
    expected.set(`servo${n}.max_us`, '2100.00');
  }
  assert.deepEqual(config(board), expected, 'after set servos.max_us');
});

test('servo trim, direction, rate and limits change the pins as the host core predicts', () => {
  const settings = defaultSettings();
  const board = bootQuiet(bootrom);
  const pose = [3, -2, 2, 2, -1, 4];
  moveTo(board, HOME, pose, settings);
  assertPins(board, solve(settings, pose), 'defaults');

  // Each change applies at once to the pose being held.
  /** @type {[string, (settings: any) => void][]} */
  const steps = [
    [
      'servo2.trim_us 1520',
      (s) => {
        s.servos[1].trim_us = 1520;
      },
    ],
    [
      'servo3.dir normal',
      (s) => {
        s.servos[2].dir = 'normal';
      },
    ],
    [
      'servo4.rate_us_rad 600',
      (s) => {
        s.servos[3].rate_us_rad = 600;
      },
    ],
    [
      'servos.trim_us 1490',
      (s) => {
        s.servos.forEach((servo) => {
          servo.trim_us = 1490;
        });
      },
    ],
    [
      'servo1.dir normal',
      (s) => {
        s.servos[0].dir = 'normal';
      },
    ],
    [
      'servo6.rate_us_rad 450.5',
      (s) => {
        s.servos[5].rate_us_rad = 450.5;
      },
    ],
  ];
  for (const [args, change] of steps) {
    const before = widthsNanos(board);
    ok(board, `set ${args}`);
    change(settings);
    runFrames(board, 3);
    const expected = solve(settings, pose);
    assertPins(board, expected, `after set ${args}`);
    assert.notDeepEqual(widthsNanos(board), before, `set ${args} changed nothing on the pins`);
  }

  // Limits: a pose beyond servo 1's 1900 us is refused, and accepted once the limit allows it.
  const deep = [0, 0, -15, 0, 0, 0];
  const [core] = reference.solve(settings, [deep]);
  assert.equal(core.code, 'servo-limit');
  refused(board, `pose ${poseText(deep)}`, 'servo-limit');
  ok(board, 'set servos.max_us 2100');
  ok(board, 'set servos.min_us 900');
  settings.servos.forEach((servo) => {
    servo.min_us = 900;
    servo.max_us = 2100;
  });
  moveTo(board, pose, deep, settings);
  assertPins(board, solve(settings, deep), 'beyond the old limits');
  assert.ok(
    solve(settings, deep).some((us) => us > 1900 || us < 1100),
    'the pose needs the wider limits',
  );
  // Every measured pulse respects the new limits.
  for (const servo of board.servos()) {
    assert.ok(servo.widthUs >= 900 && servo.widthUs <= 2100);
  }
});

test('geometry settings change the IK: geometry output and pins follow the host core', () => {
  const settings = defaultSettings();
  const board = bootQuiet(bootrom);
  ok(board, 'set rod_mm 125');
  ok(board, 'set platform_radius_mm 58');
  settings.layout.rod_mm = 125;
  settings.layout.platform_radius_mm = 58;
  const core = reference.geometry(settings);
  const data = ok(board, 'geometry');
  assert.ok(data.includes(`home_height_mm (h0): ${core.h0_mm.toFixed(3)}`), JSON.stringify(data));
  assert.ok(data.includes('rod_mm (s): 125.000'));
  data
    .filter((line) => line.startsWith('leg '))
    .forEach((line, i) => {
      const alpha0 = Number(line.match(/alpha0_deg=(\S+)/)[1]);
      assert.ok(Math.abs(alpha0 - core.legs[i].alpha0_deg) < 0.0011, line);
    });
  // At home every servo still gets its trim; elsewhere the new geometry's pulses.
  assertPins(
    board,
    settings.servos.map((servo) => servo.trim_us),
    'home',
  );
  const pose = [-4, 5, 3, -2, 3, -6];
  moveTo(board, HOME, pose, settings);
  assertPins(board, solve(settings, pose), 'new geometry');
  assert.notDeepEqual(
    solve(defaultSettings(), pose).map(Math.round),
    solve(settings, pose).map(Math.round),
  );
});

test('frame_hz: every pin changes period at a frame boundary, no pulse cut or stretched', () => {
  const board = bootQuiet(bootrom);
  ok(board, 'pose 2 1 3 1 2 3');
  runFrames(board, 10);
  const widths = widthsNanos(board);
  for (const [from, to] of [
    [50, 200],
    [200, 333],
    [333, 50],
    [50, 123],
  ]) {
    const pulses = capture(board, () => ok(board, `set frame_hz ${to}`), 6, Math.min(from, to));
    const oldPeriod = framePeriodNanos(from);
    const newPeriod = framePeriodNanos(to);
    assertConstant(pulses, widths, `across ${from} -> ${to} Hz`);
    pulses.forEach((servo, i) => {
      const periods = servo.map((pulse) => pulse.periodNanos);
      const switchAt = periods.indexOf(newPeriod);
      assert.ok(switchAt >= 0, `servo ${i + 1} never reached ${to} Hz: ${periods}`);
      periods.forEach((period, j) => {
        assert.equal(
          period,
          j < switchAt ? oldPeriod : newPeriod,
          `servo ${i + 1} period ${j} (${from} -> ${to} Hz)`,
        );
      });
      assert.ok(periods.length - switchAt >= 3);
    });
  }
  assert.equal(framePeriodNanos(333), 9384 * COUNT_NANOS);
  assert.deepEqual(periodsUs(board), Array(6).fill(framePeriodNanos(123) / 1000));
});

test('set baud: the board listens at the new rate once the ok has left; config shows it', () => {
  const board = bootQuiet(bootrom);
  for (const baud of [921600, 9600, 57600, 115200]) {
    const old = board.baud;
    ok(board, `set baud ${baud}`);
    // The reply ("ok" CR LF) takes 4 byte times at the old rate; by then the board has switched
    // (a host may talk at the new rate as soon as it has read the ok).
    board.runMs((4 * 10 * 1000) / old);
    assert.ok(
      Math.abs(board.baud - baud) / baud < 0.02,
      `UART0 at ${board.baud} baud, want ${baud}`,
    );
    // A line is paced at the new rate: n bytes take n byte times, and so do the n bytes of
    // the reply on the way back (echo is off: the reply starts once the line is in). The
    // line's last bytes (107 is not a multiple of the firmware's FIFO level of 8) wait in the
    // UART's FIFO for its receive timeout, 32 bit periods, before the firmware sees them.
    const start = board.nanos;
    const outputBefore = board.outputBytes.length;
    const line = `${' '.repeat(100)}status`; // 107 bytes with the LF; status is quick
    assert.equal(ok(board, line, { timeoutMs: 1000 }).length, 8);
    const bytes = line.length + 1 + board.outputBytes.length - outputBefore;
    const byteNanos = (10 * 1e9) / board.baud;
    const rxTimeoutNanos = (32 * 1e9) / board.baud;
    const elapsed = board.nanos - start;
    assert.ok(
      elapsed >= bytes * byteNanos * 0.99 && elapsed < bytes * byteNanos + rxTimeoutNanos + 1e6,
      `${elapsed} ns for ${bytes} bytes at ${baud}`,
    );
    assert.equal(config(board).get('baud'), String(baud));
  }
});

test('set baud with echo on: nothing follows the ok at the old rate; the prompt comes at the new one', () => {
  const board = new EmulatedBoard({ bootrom });
  board.boot();
  board.runMs(20);
  // Each byte the host receives, with the rate the UART sent it at (the divisor latches when
  // the firmware switches, between bytes).
  const received = [];
  board.onOutput((byte) => received.push({ byte, baud: Math.round(board.baud) }));
  board.sendBytes('set baud 230400\r');
  board.runMs(50);
  const text = String.fromCharCode(...received.map((r) => r.byte));
  const okEnd = text.indexOf('ok\r\n') + 4;
  assert.ok(okEnd >= 4, JSON.stringify(text));
  for (const r of received.slice(0, okEnd)) {
    assert.ok(Math.abs(r.baud - 115200) / 115200 < 0.02, `the reply went out at ${r.baud}`);
  }
  const after = received.slice(okEnd);
  assert.equal(String.fromCharCode(...after.map((r) => r.byte)), '> ');
  for (const r of after) {
    assert.ok(Math.abs(r.baud - 230400) / 230400 < 0.02, `the prompt went out at ${r.baud}`);
  }
  // And the board talks at the new rate.
  assert.equal(board.request('status').reply, 'ok');
});

test('defaults restores every setting except baud and echo, and the pins follow', () => {
  const settings = defaultSettings();
  const board = bootQuiet(bootrom);
  const pristine = config(board);
  for (const args of [
    'frame_hz 100',
    'speed_mm_s 10',
    'servos.trim_us 1510',
    'servo2.dir reversed',
    'rod_mm 122',
    'link_timeout_s 60',
    'baud 57600',
  ]) {
    ok(board, `set ${args}`);
  }
  board.runMs(1);
  runFrames(board, 3);
  assert.deepEqual(periodsUs(board), Array(6).fill(10_000));
  assertPins(board, Array(6).fill(1510), 'trims at home');
  ok(board, 'defaults');
  runFrames(board, 4);
  const restored = config(board);
  assert.equal(restored.get('baud'), '57600', 'baud kept');
  assert.equal(restored.get('echo'), 'off', 'echo kept');
  assert.deepEqual(restored, new Map(pristine).set('baud', '57600'));
  assert.deepEqual(periodsUs(board), Array(6).fill(20_000));
  assertPins(board, solve(settings, HOME));
  assert.ok(Math.abs(board.baud - 57600) / 57600 < 0.02);
  // And a move uses the default speed again.
  const pose = [10, 0, 0, 0, 0, 0];
  ok(board, `pose ${poseText(pose)}`);
  runFrames(board, plannedFrames(HOME, pose, settings) + 2);
  assert.equal(status(board).state, 'idle');
  assertPins(board, solve(settings, pose));
});

test('sub-microsecond resolution: trims a third of a microsecond apart give widths one 320 ns count apart', () => {
  const board = bootQuiet(bootrom);
  const widths = [];
  for (const trim of [1500.5, 1500.82, 1501.14]) {
    ok(board, `set servo1.trim_us ${trim}`);
    runFrames(board, 3);
    const width = board.servos()[0].widthNanos;
    assert.equal(Math.round(width), Math.round(quantisedUs(trim) * 1000), `trim ${trim}`);
    widths.push(Math.round(width));
  }
  assert.deepEqual([widths[1] - widths[0], widths[2] - widths[1]], [COUNT_NANOS, COUNT_NANOS]);
});
