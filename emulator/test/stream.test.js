// Stream frames through the real firmware, as motion-simulator software sends them: the
// pulses on the pins, read back into poses with the host core's IK, must follow the
// documented tracker limits (docs/streaming.md: per-axis speed and acceleration limits, no
// overshoot), clamp unreachable targets, survive garbage, and stop for the e-stop. Expected
// values come from the documented frame format and the host core, never from the firmware. The
// last tests stream over the USB port (docs/commands.md "Serial links"): the same frames, beside
// commands on UART0, and keeping the link alive.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import {
  assertPins,
  assertWithinLimits,
  bootQuiet,
  bootQuietUsb,
  bootWith,
  capture,
  COUNT_US,
  defaultSettings,
  firmwareBootrom,
  heaveReader,
  heaveTrace,
  ok,
  refused,
  runFrames,
  status,
} from '../src/test-support/e2e-support.js';
import { binaryFrame } from '../src/bench/firmware-bench.js';
import { HostReference } from '../src/test-support/host-reference.js';

let bootrom;
let reference;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
});

/**
 * The 16-bit count for a value on an axis of full scale `scale` (docs/streaming.md:
 * c = 32768 + v/scale*32768).
 */
function count(value, scale) {
  return Math.round(32768 + (value / scale) * 32768);
}

/** A binary frame for a pose (mm, degrees) with the default full scales (25 25 15 mm, 15 15 20 deg). */
const SCALES = [25, 25, 15, 15, 15, 20];
function frameFor(pose) {
  return binaryFrame(pose.map((v, i) => count(v, SCALES[i])));
}
/** The pose a frame for `pose` really carries (counts are whole numbers). */
function carried(pose) {
  return pose.map((v, i) => ((count(v, SCALES[i]) - 32768) / 32768) * SCALES[i]);
}

function solve(pose, settings = defaultSettings()) {
  const [answer] = reference.solve(settings, [pose]);
  assert.ok(answer.ok, `host core refuses ${pose}: ${JSON.stringify(answer)}`);
  return answer.pulse_us;
}

function trackingBoard({ hz = 50, speed = 40, accel = 400 } = {}) {
  return bootWith({ frame_hz: hz, speed_mm_s: speed, accel_mm_s2: accel });
}

test('a step: the pins follow within the speed and acceleration limits, settle on the target, never overshoot', () => {
  const hz = 50;
  const board = trackingBoard({ hz });
  const read = heaveReader(reference, -0.5, 6.5);
  const target = [0, 0, 6, 0, 0, 0];
  const pulses = capture(board, () => board.sendBytes(frameFor(target)), 60, hz);
  const zs = heaveTrace(pulses, read);
  assertWithinLimits(zs, { hz, speed: 40, accel: 400, top: carried(target)[2], label: 'step' });
  // It moved, and it took at least the time a trapezoid needs: 6 mm at 400 mm/s2 peaking at
  // 40 mm/s: 0.1 s ramps and 0.05 s cruise = 0.25 s = 12.5 frames.
  const started = zs.findIndex((z) => z > 0.05);
  const arrived = zs.findIndex((z) => Math.abs(z - 6) < 0.02);
  assert.ok(started >= 0 && arrived > started, `never arrived: ${zs.map((z) => z.toFixed(2))}`);
  assert.ok(
    arrived - started >= 11,
    `arrived in ${arrived - started} frames: faster than the limits allow`,
  );
  // Settled exactly on the host core's pulses for the frame's pose.
  assertPins(board, solve(carried(target)));
  const s = status(board);
  assert.equal(s.state, 'streaming (tracking)');
  assert.deepEqual(s.stream, { frames: 1, applied: 1, damaged: 0, clamped: 0, refused: 0 });
  assert.equal(s.servo_power, 'on');
});

test('a 60 Hz staircase becomes smooth motion at the frame rate within the limits', () => {
  const hz = 200;
  const board = trackingBoard({ hz, speed: 40, accel: 400 });
  const read = heaveReader(reference, -0.5, 6.5);
  const steps = [];
  for (let k = 1; k <= 12; k++) steps.push(k * 0.5);
  for (let k = 11; k >= 4; k--) steps.push(k * 0.5);
  const pulses = capture(
    board,
    () => {
      for (const z of steps) {
        board.sendBytes(frameFor([0, 0, z, 0, 0, 0]));
        board.runMs(1000 / 60);
      }
    },
    200,
    hz,
  );
  const zs = heaveTrace(pulses, read);
  assertWithinLimits(zs, {
    hz,
    speed: 40,
    accel: 400,
    top: carried([0, 0, 6, 0, 0, 0])[2],
    label: 'staircase',
  });
  // Smooth: at 200 Hz the pins change on most frames while the stairs come (not only every
  // 60 Hz step).
  const moving = zs.slice(0, 70);
  const changes = moving.slice(1).filter((z, k) => Math.abs(z - moving[k]) > 0.004).length;
  assert.ok(changes > 40, `only ${changes} of 69 frames changed: not smoothed`);
  assertPins(board, solve(carried([0, 0, 2, 0, 0, 0])));
  assert.deepEqual(status(board).stream.frames, steps.length);
});

test('pass-through: with every limit off a frame is on the pins at the next period', () => {
  const board = bootWith({ speed_mm_s: 'off', speed_deg_s: 'off' });
  const pose = [3, -2, 1.5, 2, -1, 4];
  const pulses = capture(board, () => board.sendBytes(frameFor(pose)), 3);
  const want = solve(carried(pose));
  // The first period that starts after the frame has arrived (16 bytes, 1.4 ms at 115,200
  // baud, plus the computation) already carries the new widths: one period of latency at most.
  pulses.forEach((servo, i) => {
    const changed = servo.findIndex((p) => Math.abs(p.widthNanos / 1000 - want[i]) <= COUNT_US);
    assert.ok(changed >= 0 && changed <= 1, `servo ${i + 1}: new width at period ${changed}`);
  });
  assert.equal(status(board).state, 'streaming (pass-through)');
});

test('garbage, truncated frames and random bytes mid-stream: resynchronised, counted, nothing wrong applied', () => {
  const board = bootWith({ speed_mm_s: 'off', speed_deg_s: 'off' });
  const good = [
    [1, 0, 1, 0, 0, 0],
    [2, 1, 0, 1, 0, 0],
    [0, 2, 2, 0, 1, 2],
  ];
  const allowed = [
    defaultSettings().servos.map((s) => s.trim_us),
    ...good.map((p) => solve(carried(p))),
  ];
  const bytes = [];
  const truncated = frameFor([9, 9, 9, 9, 9, 9]).subarray(0, 9); // a frame cut short
  bytes.push(...frameFor(good[0]), ...truncated, ...frameFor(good[1]));
  bytes.push(0x13, 0xa5, 0x00, 0xff, 0x7f, 0xa5, 0xa5, 0x0d); // line noise
  const damaged = Buffer.from(frameFor([-9, -9, -9, -9, -9, -9]));
  damaged[14] = 0x00; // wrong trailer
  bytes.push(...damaged, ...frameFor(good[2]));
  const linesBefore = board.lines.length;
  const pulses = capture(board, () => board.sendBytes(Buffer.from(bytes)), 3);
  // The noise held a CR: the bytes before it were a (spoiled) line, refused as such, once;
  // frames get no reply.
  assert.deepEqual(board.lines.slice(linesBefore), [
    'error:bad-character byte 0xA5 is not printable ASCII; the line was discarded',
  ]);
  board.lineCursor = board.lines.length;
  // Every width on the pins belongs to home or to one of the good frames, never to the bad.
  const periods = Math.min(...pulses.map((servo) => servo.length));
  for (let k = 0; k < periods; k++) {
    const widths = pulses.map((servo) => servo[k].widthNanos / 1000);
    assert.ok(
      allowed.some((want) => want.every((w, i) => Math.abs(w - widths[i]) <= COUNT_US)),
      `period ${k}: ${widths} is no good frame's pose`,
    );
  }
  assertPins(board, allowed[3]);
  const s = status(board).stream;
  assert.ok(s.damaged >= 2, `damaged ${s.damaged}`);
  assert.ok(s.frames >= 3 && s.frames <= 4, `frames ${s.frames}`); // the garbage may hide one
  // The link still takes commands.
  ok(board, 'home');
});

test('a target outside the workspace is clamped on the way to it, counted, pulses within limits', () => {
  const board = bootWith({ speed_mm_s: 'off', speed_deg_s: 'off' });
  ok(board, 'set stream.z_mm 100');
  board.sendBytes(binaryFrame([32768, 32768, count(80, 100), 32768, 32768, 32768]));
  runFrames(board, 3);
  const s = status(board);
  assert.equal(s.stream.clamped, 1);
  const [x, y, z, roll, pitch, yaw] = s.pose;
  assert.deepEqual([x, y, roll, pitch, yaw], [0, 0, 0, 0, 0]);
  assert.ok(z > 0 && z < 80, `clamped to z ${z}`);
  // The pins are the host core's for the clamped pose (reachable), within every limit; a
  // little further along is not reachable (the clamp went as far as it could, within 1/64).
  assertPins(board, solve(s.pose));
  const [beyond] = reference.solve(defaultSettings(), [[0, 0, z + 80 / 64 + 0.01, 0, 0, 0]]);
  assert.equal(beyond.ok, false, `z ${z} was clamped too early`);
  for (const servo of board.servos()) {
    assert.ok(servo.widthUs >= 1100 - COUNT_US && servo.widthUs <= 1900 + COUNT_US);
  }
});

test('text frames: an existing SimTools profile (8 bits, its own axis order) works unchanged', () => {
  const board = bootWith({ speed_mm_s: 'off', speed_deg_s: 'off' });
  // The profile sends roll, pitch, heave, yaw, surge, sway.
  const order = ['roll', 'pitch', 'z', 'yaw', 'x', 'y'];
  order.forEach((_, i) => ok(board, `set stream.axis${i + 1} none`));
  order.forEach((axis, i) => ok(board, `set stream.axis${i + 1} ${axis}`));
  board.sendBytes('160,96,144,128,128,112X');
  runFrames(board, 2);
  // 8 bits: (c - 128) / 128 of the full scale.
  const f = (c) => (c - 128) / 128;
  const want = [f(128) * 25, f(112) * 25, f(144) * 15, f(160) * 15, f(96) * 15, f(128) * 20];
  assertPins(board, solve(want));
  assert.equal(status(board).stream.applied, 1);
});

test('e-stop in the middle of a stream: frozen, power off, frames refused until closed and reset', () => {
  const board = bootQuiet(bootrom);
  board.drivePin(15, false); // the e-stop switch, closed
  ok(board, 'set speed_mm_s off');
  ok(board, 'set speed_deg_s off');
  ok(board, 'set estop_pin 15');
  ok(board, 'set power_pin 16');
  assert.equal(board.pinOutput(16), false, 'servo power off until the first pose');
  board.sendBytes(frameFor([2, 0, 1, 0, 0, 0]));
  runFrames(board, 2);
  assert.equal(board.pinOutput(16), true, 'servo power on with the first frame');
  const frozen = solve(carried([2, 0, 1, 0, 0, 0]));
  assertPins(board, frozen);
  board.drivePin(15, null); // the switch opens: the pull-up takes the pin high
  const pulses = capture(
    board,
    () => {
      for (let k = 0; k < 5; k++) {
        board.sendBytes(frameFor([-2, 1, k * 0.3, 0, 0, 0]));
        board.runMs(10);
      }
    },
    2,
  );
  pulses.forEach((servo, i) => {
    for (const p of servo) {
      assert.ok(
        Math.abs(p.widthNanos / 1000 - frozen[i]) <= COUNT_US,
        `servo ${i + 1} moved after the e-stop`,
      );
    }
  });
  assert.equal(board.pinOutput(16), false, 'servo power off on e-stop');
  const s = status(board);
  assert.equal(s['e-stop'], 'open');
  assert.equal(s.stream.refused, 5);
  assert.ok(
    s.lines.some((l) => l.startsWith('emergency stop: input open')),
    'the notice',
  );
  refused(board, 'reset', 'e-stop');
  board.drivePin(15, false);
  runFrames(board, 1);
  board.sendBytes(frameFor([-2, 1, 0, 0, 0, 0]));
  runFrames(board, 2);
  assertPins(board, frozen); // closed is not enough
  ok(board, 'reset');
  board.sendBytes(frameFor([-2, 1, 0, 0, 0, 0]));
  runFrames(board, 2);
  assertPins(board, solve(carried([-2, 1, 0, 0, 0, 0])));
  assert.equal(board.pinOutput(16), true);
});

test('e-stop during a commanded move: the pins stop within a frame, moves refused with the reason', () => {
  const board = bootQuiet(bootrom);
  board.drivePin(15, false);
  ok(board, 'set estop_pin 15');
  ok(board, 'set power_pin 16');
  ok(board, 'set speed_mm_s 10');
  ok(board, 'pose 0 0 8 0 0 0'); // 0.8 s
  runFrames(board, 10);
  board.drivePin(15, null);
  runFrames(board, 1);
  const held = board.pulseWidthsUs();
  const pulses = capture(board, () => {}, 10);
  pulses.forEach((servo, i) => {
    for (const p of servo) {
      assert.ok(Math.abs(p.widthNanos / 1000 - held[i]) <= COUNT_US, `servo ${i + 1} kept moving`);
    }
  });
  const s = status(board);
  assert.ok(s.pose[2] > 1 && s.pose[2] < 7, `stopped part way: z ${s.pose[2]}`);
  assert.equal(board.pinOutput(16), false);
  refused(board, 'home', 'e-stop');
});

test('a stream that is clamped on every frame keeps every main-loop pass under 1 ms and misses no frame', () => {
  const board = trackingBoard({ hz: 333, speed: 200, accel: 2000 });
  ok(board, 'set speed_deg_s 200');
  ok(board, 'set accel_deg_s2 2000');
  ok(board, 'set stream.z_mm 200');
  board.loop.reset();
  board.frames.reset();
  // 300 frames/s, their targets alternately far above and far below reach: each clamped.
  for (let k = 0; k < 90; k++) {
    board.sendBytes(
      binaryFrame([32768 + (k % 7) * 200, 32768, k % 2 ? 0 : 65535, 32768, 32768, 32768]),
    );
    board.runMs(1000 / 300);
  }
  const { longestPassCycles } = board.loop;
  assert.ok(longestPassCycles < 125_000, `a pass took ${longestPassCycles} cycles (bound: 1 ms)`);
  assert.ok(board.frames.frames > 80, `${board.frames.frames} frames seen`);
  assert.equal(board.frames.missed, 0, 'servo frames missed');
  const s = status(board).stream;
  assert.ok(s.clamped >= 80, `clamped ${s.clamped}`);
  for (const servo of board.servos()) {
    assert.ok(servo.widthUs >= 1100 - COUNT_US && servo.widthUs <= 1900 + COUNT_US);
  }
});

test('over USB: a frame with LF and CR bytes in its counts, then a line, in one packet: both taken', () => {
  // Helpers speak over USB; board.uart is UART0.
  const board = bootWith({ speed_mm_s: 'off', speed_deg_s: 'off' }, { usb: true });
  // Every count's low byte is LF (0x0A) or CR (0x0D): the frame's bytes hold line ends that
  // are not line ends (docs/streaming.md: binary frames are `A5 5A`, six counts, `0D 0A`).
  const counts = [0x800a, 0x7f0d, 0x8a0a, 0x800d, 0x7f0a, 0x8a0d];
  const pose = counts.map((c, i) => ((c - 32768) / 32768) * SCALES[i]);
  const from = board.lines.length;
  // One USB packet: the frame, then a line.
  board.sendBytes(Buffer.concat([binaryFrame(counts), Buffer.from('status\n', 'latin1')]));
  board.waitForLine(/^ok$/);
  // The packet is fed in one pass: its LF bytes inside the frame did not end the pass's input
  // (a line end does), so `status` ran in that pass, after the frame was stored and before the
  // pass applied it. A board ending its input at any LF would have applied it passes earlier.
  const stat = board.lines.slice(from).find((l) => l.startsWith('# stream: '));
  assert.equal(stat, '# stream: frames=1 applied=0 damaged=0 clamped=0 refused=0');
  runFrames(board, 2);
  assertPins(board, solve(pose));
  const s = status(board);
  assert.equal(s.state, 'streaming (pass-through)');
  assert.deepEqual(s.stream, { frames: 1, applied: 1, damaged: 0, clamped: 0, refused: 0 });
});

test('a stream on USB beside commands on UART0: both served, frames keep the link alive, notices on both', () => {
  const board = bootQuietUsb(bootrom);
  const uart = board.uart;
  assert.equal(uart.request('set echo off').reply, 'ok');
  ok(board, 'set speed_mm_s off');
  ok(board, 'set speed_deg_s off');
  assert.equal(uart.request('set link_timeout_s 0.2').reply, 'ok');
  // 100 Hz frames on USB for 0.6 s (three link timeouts) while UART0 asks for its status.
  const path = Array.from({ length: 60 }, (_, k) => [0, 0, 3 * Math.sin(k / 10), 0, 0, 2]);
  let uartReplies = 0;
  for (const [k, pose] of path.entries()) {
    board.sendBytes(frameFor(pose));
    if (k % 10 === 5) {
      const { reply, lines } = uart.request('status');
      assert.equal(reply, 'ok');
      assert.ok(
        lines.some((l) => l === '# state: streaming (pass-through)'),
        JSON.stringify(lines),
      );
      uartReplies += 1;
    }
    board.runMs(10);
  }
  assert.equal(uartReplies, 6);
  runFrames(board, 2);
  assertPins(board, solve(carried(path.at(-1))));
  const lost = /^# link lost: /;
  assert.ok(!uart.lines.some((l) => lost.test(l)), 'frames on USB are a sign of life');
  assert.ok(!board.lines.some((l) => lost.test(l)));
  assert.equal(status(board).stream.frames, path.length);
  // Silence on both links: link loss, told on both.
  uart.waitForLine(lost, { timeoutMs: 400 });
  board.waitForLine(lost, { timeoutMs: 5 });
  // The e-stop's notices reach both links too, and frames on USB are refused while it is open.
  board.drivePin(15, false);
  ok(board, 'set estop_pin 15');
  board.drivePin(15, null);
  const opened = /^# emergency stop: input open/;
  uart.waitForLine(opened, { timeoutMs: 100 });
  board.waitForLine(opened, { timeoutMs: 5 });
  board.sendBytes(frameFor([0, 0, 1, 0, 0, 0]));
  runFrames(board, 2);
  assert.equal(status(board).stream.refused, 1);
});
