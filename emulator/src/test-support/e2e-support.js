// Shared helpers for the end-to-end tests (kept out of test/ so `node --test test/` does not
// run this file as a test). Everything the firmware should do is restated here from the
// documentation (docs/), never read back from the firmware.

import assert from 'node:assert/strict';
import { existsSync } from 'node:fs';
import { test } from 'node:test';

import { BANNER, DEFAULT_ELF, EmulatedBoard } from '../chip/board.js';
import { loadBootrom } from '../chip/bootrom.js';

/** The boot ROM words for a test file, after checking that the firmware ELF has been built. */
export function firmwareBootrom() {
  assert.ok(
    existsSync(DEFAULT_ELF),
    `no firmware ELF at ${DEFAULT_ELF}: build it with \`cargo fw\``,
  );
  return loadBootrom();
}

/** One servo frame at the default 50 Hz, ms. */
export const FRAME_MS = 20;

/**
 * Runs `frames` frames asserting that the pins hold still and keep pulsing; returns their
 * widths, us.
 */
export function steadyPulses(board, frames = 3) {
  const first = board.pulseWidthsUs();
  for (let i = 0; i < frames; i++) {
    board.runMs(FRAME_MS);
    assert.deepEqual(board.pulseWidthsUs(), first, `pins moved at ${board.millis} ms`);
  }
  for (const servo of board.servos()) {
    assert.ok(servo.live, `servo ${servo.servo} stopped pulsing`);
  }
  return first;
}

/** One PWM count: 125 MHz / divider 40. */
export const COUNT_US = 0.32;
export const COUNT_NANOS = 320;
/** PWM counts per second (125 MHz / 40). */
export const COUNTS_PER_SECOND = 3_125_000;
/** The six servos. */
export const SERVOS = [1, 2, 3, 4, 5, 6];

/** The documented default settings (docs/settings.md), in `set` names and units. */
export function defaultSettings() {
  return {
    frame_hz: 50,
    baud: 115200,
    echo: 'on',
    speed_mm_s: 50,
    speed_deg_s: 60,
    link_timeout_s: 'off',
    layout: {
      base_radius_mm: 75,
      base_half_angle_deg: 20,
      platform_radius_mm: 60,
      platform_half_angle_deg: 20,
      arm_mm: 20,
      rod_mm: 120,
    },
    // Even servos normal, odd reversed; 1600/pi us/rad; 1100..1900 us; not rated (torque or
    // speed).
    servos: SERVOS.map((n) => ({
      trim_us: 1500,
      rate_us_rad: 1600 / Math.PI,
      dir: n % 2 === 0 ? 'normal' : 'reversed',
      min_us: 1100,
      max_us: 1900,
      /** @type {number | 'off'} */
      torque_kgcm: 'off',
      /** @type {number | 'off'} */
      speed_s_60deg: 'off',
    })),
    // No payload.
    payload: { payload_g: 0, payload_com_x_mm: 0, payload_com_y_mm: 0, payload_com_z_mm: 0 },
  };
}

export function copySettings(settings) {
  return structuredClone(settings);
}

/** A pose as six numbers: x y z (mm) roll pitch yaw (deg). */
export const HOME = [0, 0, 0, 0, 0, 0];

/** Frame period at `hz`: TOP + 1 = floor(3_125_000 / hz) counts of 320 ns. */
export function framePeriodNanos(hz) {
  return Math.floor(COUNTS_PER_SECOND / hz) * COUNT_NANOS;
}

/** The width the PWM produces for `us`: the nearest count (half up), in us. */
export function quantisedUs(us) {
  return (Math.floor(us / COUNT_US + 0.5) * COUNT_NANOS) / 1000;
}

/**
 * Frames a straight move takes (docs/commands.md "Motion"): the larger of linear distance /
 * speed_mm_s and angular distance / speed_deg_s (Euclidean, mm and degrees), times the frame
 * rate, rounded up, at least 1. A speed of 0 / 'off' does not constrain.
 */
export function plannedFrames(from, to, { speed_mm_s, speed_deg_s, frame_hz }) {
  const linear = Math.hypot(to[0] - from[0], to[1] - from[1], to[2] - from[2]);
  const angular = Math.hypot(to[3] - from[3], to[4] - from[4], to[5] - from[5]);
  let seconds = 0;
  if (Number(speed_mm_s) > 0) {
    seconds = Math.max(seconds, linear / speed_mm_s);
  }
  if (Number(speed_deg_s) > 0) {
    seconds = Math.max(seconds, angular / speed_deg_s);
  }
  // A tiny allowance so an exact whole number of frames is not rounded up by f64 noise.
  return Math.max(1, Math.ceil(seconds * frame_hz * (1 - 1e-9)));
}

export function lerpPose(a, b, t) {
  return a.map((v, i) => v + (b[i] - v) * t);
}

/** The pose of frame k of n from a to b (frame n is b exactly). */
export function framePoses(a, b, n) {
  return Array.from({ length: n }, (_, i) => (i + 1 === n ? [...b] : lerpPose(a, b, (i + 1) / n)));
}

export function poseText(pose) {
  return pose.join(' ');
}

/** Boots the firmware as it comes (echo on, the banner read). */
export function bootedBoard(bootrom) {
  const board = new EmulatedBoard({ bootrom });
  board.boot();
  return board;
}

/** Boots the firmware, turns echo off (as a program would) and runs until every pin pulsed. */
export function bootQuiet(bootrom) {
  const board = bootedBoard(bootrom);
  assert.equal(board.request('set echo off').reply, 'ok');
  board.runUntil(() => board.servos().every((servo) => servo.live), { timeoutMs: 100 });
  return board;
}

/**
 * Boots the firmware with a USB host plugged in, waits until the host has its port open and
 * the banner has come over USB, turns echo off there (as a program would) and runs until every
 * pin pulsed. Returns the board as the USB host sees it (`board.through(board.usb)`: the
 * helpers here speak over USB; `.usb` is the link, `.uart` UART0's).
 */
export function bootQuietUsb(bootrom) {
  const board = new EmulatedBoard({ bootrom, usb: true });
  board.boot();
  board.usb.waitUntilOpen();
  board.usb.waitForLine(BANNER);
  const viaUsb = board.through(board.usb);
  assert.equal(viaUsb.request('set echo off').reply, 'ok');
  board.runUntil(() => board.servos().every((servo) => servo.live), { timeoutMs: 100 });
  return viaUsb;
}

let sharedBootrom;

/**
 * Boots the firmware quiet (`bootQuiet`; over USB, `bootQuietUsb`, with `usb`) and sets
 * `settings` in order, each `set name value` answered `ok`: `bootWith({ speed_mm_s: 'off',
 * speed_deg_s: 'off' })`. The boot ROM is loaded once (`firmwareBootrom`) for every caller.
 * @param {Record<string, string | number>} [settings]
 * @param {{ usb?: boolean }} [options]
 */
export function bootWith(settings = {}, { usb = false } = {}) {
  sharedBootrom ??= firmwareBootrom();
  const board = usb ? bootQuietUsb(sharedBootrom) : bootQuiet(sharedBootrom);
  for (const [name, value] of Object.entries(settings)) {
    ok(board, `set ${name} ${value}`);
  }
  return board;
}

/**
 * Boots the firmware as a terminal meets it, echo on: on UART0, after the power-up banner; or,
 * with `usb`, on the USB port once the host has opened it and its banner came. Returns the
 * board as that link's host sees it.
 */
export function bootTerminal(bootrom, { usb = false } = {}) {
  const board = new EmulatedBoard({ bootrom, usb });
  board.boot();
  if (!usb) {
    return board;
  }
  board.usb.waitUntilOpen();
  board.usb.waitForLine(BANNER);
  return board.through(board.usb);
}

/** The serial links the command checks run through: UART0 and the Pico's USB port. */
export const LINKS = [
  { name: 'UART0', suffix: '', quiet: bootQuiet, terminal: (bootrom) => bootTerminal(bootrom) },
  {
    name: 'USB',
    suffix: ' (USB)',
    quiet: bootQuietUsb,
    terminal: (bootrom) => bootTerminal(bootrom, { usb: true }),
  },
];

/** A test run once per link in `LINKS`: `fn(link)`, its name suffixed for USB. */
export function linkTest(name, fn) {
  for (const link of LINKS) {
    test(`${name}${link.suffix}`, () => fn(link));
  }
}

/** Sends a line that must succeed; returns its data lines (`# ` removed). */
export function ok(board, line, { timeoutMs = 2000 } = {}) {
  const { reply, lines } = board.request(line, { timeoutMs });
  assert.equal(reply, 'ok', `'${line}' -> ${JSON.stringify(lines)}`);
  return lines.slice(0, -1).map((text) => {
    assert.match(text, /^# /, `'${line}': data line without '# '`);
    return text.slice(2);
  });
}

/** Sends a line that must fail with `code`; returns the whole reply (checked for shape). */
export function refused(board, line, code, { timeoutMs = 2000 } = {}) {
  const { reply, lines } = board.request(line, { timeoutMs });
  assert.equal(
    lines.length,
    1,
    `'${line}' -> ${JSON.stringify(lines)}: the error is the only line`,
  );
  assert.match(reply, new RegExp(`^error:${code} \\S.*$`), `'${line}'`);
  return reply;
}

/** Numbers in a data line's value (`key: 1.0 2.0 ...`). */
export function numbersIn(text) {
  return (text.match(/-?\d+(?:\.\d+)?/g) ?? []).map(Number);
}

/**
 * The pins' widths, us, that `./dev run` printed last in `log` (its `servos us: ...` lines, as
 * `startPtyRunner`'s `log()` returns them).
 * @param {string} log
 */
export function pinsUs(log) {
  const lines = log.split(/[\r\n]/).filter((line) => line.startsWith('servos us:'));
  assert.ok(lines.length > 0, 'the runner printed no pins yet');
  return numbersIn(lines.at(-1).replace(/\|.*$/, ''));
}

/**
 * Waits (generously: 30 s) until the pins the runner prints (`log()`) show `expected` within
 * one PWM count; returns the pins then, us (the caller asserts they arrived).
 * @param {() => string} log
 * @param {number[]} expected
 */
export async function pinsReach(log, expected) {
  const until = Date.now() + 30_000;
  const near = () => pinsUs(log()).every((w, i) => Math.abs(w - expected[i]) <= COUNT_US + 1e-9);
  while (!near() && Date.now() < until) {
    await new Promise((resolve) => setTimeout(resolve, 100));
  }
  return pinsUs(log());
}

/**
 * Each servo's home arm angle `alpha0` (rad, from `geometry`'s `# leg N:` lines), `trim` (us),
 * `rate` (us/rad) and direction `sign` (from `config`'s `# servoN:` lines), out of the lines of
 * both listings (docs/commands.md).
 * @param {string[]} lines
 */
export function servosFromListings(lines) {
  return SERVOS.map((n) => {
    const leg = lines.find((l) => l.startsWith(`# leg ${n}:`));
    const servo = lines.find((l) => l.startsWith(`# servo${n}:`));
    return {
      alpha0: (Number(leg.match(/alpha0_deg=(\S+)/)[1]) * Math.PI) / 180,
      trim: Number(servo.match(/trim_us=(\S+)/)[1]),
      rate: Number(servo.match(/rate_us_rad=(\S+)/)[1]),
      sign: servo.includes('dir=reversed') ? -1 : 1,
    };
  });
}

/**
 * The trim a calibration must take for a servo (`servosFromListings`) whose arm is made level
 * `steps` us from where it starts: eq. 13 / 14 at alpha = 0 give the level pulse W0 - d r alpha0
 * (where the flow starts, to 0.01 us), and the trim of an arm level at W is W + d r alpha0.
 */
export function expectedTrim(servo, steps) {
  const start = Math.round((servo.trim - servo.sign * servo.rate * servo.alpha0) * 100) / 100;
  return start + steps + servo.sign * servo.rate * servo.alpha0;
}

/** `key=value` pairs of a pose line as six numbers in pose order. */
export function poseIn(text) {
  const values = {};
  for (const [, key, value] of text.matchAll(/(\w+)=(-?\d+\.\d{3})\b/g)) {
    values[key] = Number(value);
  }
  const pose = ['x', 'y', 'z', 'roll', 'pitch', 'yaw'].map((axis) => values[axis]);
  assert.ok(pose.every(Number.isFinite), `not a pose with 3 decimals: ${text}`);
  return pose;
}

/** `status` through the wire, parsed; checks every documented field is there, in format. */
export function status(board) {
  const lines = ok(board, 'status');
  const field = (key) => {
    const line = lines.find((text) => text.startsWith(`${key}: `));
    assert.ok(line, `status has no '${key}:' line: ${JSON.stringify(lines)}`);
    return line.slice(key.length + 2);
  };
  const six = (key, decimals) => {
    const text = field(key);
    assert.match(
      text,
      new RegExp(`^(-?\\d+\\.\\d{${decimals}} ){5}-?\\d+\\.\\d{${decimals}}$`),
      key,
    );
    return text.split(' ').map(Number);
  };
  return {
    lines,
    state: field('state'),
    pose: poseIn(field('pose')),
    target: poseIn(field('target')),
    arm_deg: six('arm_deg', 3),
    pulse_us: six('pulse_us', 2),
    /** `{ frames, applied, damaged, clamped, refused }`. */
    stream: Object.fromEntries(
      field('stream')
        .split(' ')
        .map((kv) => {
          const [key, value] = kv.split('=');
          return [key, Number(value)];
        }),
    ),
    'e-stop': field('e-stop'),
    servo_power: field('servo_power'),
  };
}

/** Asserts the pins' latest widths equal `expectedUs` within one PWM count. */
export function assertPins(board, expectedUs, message = '') {
  const servos = board.servos();
  for (const servo of servos) {
    const expected = expectedUs[servo.servo - 1];
    assert.ok(servo.live, `servo ${servo.servo} is not pulsing ${message}`);
    assert.ok(
      Math.abs(servo.widthUs - expected) <= COUNT_US + 1e-9,
      `servo ${servo.servo}: pin ${servo.widthUs} us, expected ${expected} us (+-1 count) ${message}`,
    );
  }
}

/** Asserts six numbers agree within `tolerance`. */
export function assertClose(actual, expected, tolerance, message = '') {
  assert.equal(actual.length, expected.length, message);
  actual.forEach((value, i) => {
    assert.ok(
      Math.abs(value - expected[i]) <= tolerance,
      `[${i}] ${value} vs ${expected[i]} (tolerance ${tolerance}) ${message}: ${JSON.stringify(actual)} vs ${JSON.stringify(expected)}`,
    );
  });
}

/** Runs `frames` frame periods of emulated time at `hz`. */
export function runFrames(board, frames, hz = 50) {
  board.runMs((frames * 1000) / hz);
}

/**
 * Records every pulse on the six pins while `action()` runs and then for `frames` frames at
 * `hz`; returns per servo the list of pulses ({ riseNanos, widthNanos, periodNanos }).
 */
export function capture(board, action, frames, hz = 50) {
  const recording = board.recordPulses();
  try {
    action();
    runFrames(board, frames, hz);
  } finally {
    recording.stop();
  }
  // Emulated time is a float sum: instants carry ~1e-8 ns of noise. To the nanosecond.
  return recording.servos.map((servo) =>
    servo.map(({ riseNanos, widthNanos, periodNanos }) => ({
      riseNanos: Math.round(riseNanos),
      widthNanos: Math.round(widthNanos),
      periodNanos: periodNanos === null ? null : Math.round(periodNanos),
    })),
  );
}

/** Asserts that every pulse recorded has width `widthsUs[servo]` (to the nanosecond). */
export function assertConstant(pulses, widthsNanos, message = '') {
  pulses.forEach((servo, i) => {
    assert.ok(servo.length > 0, `servo ${i + 1}: no pulses ${message}`);
    for (const pulse of servo) {
      assert.equal(pulse.widthNanos, widthsNanos[i], `servo ${i + 1} changed ${message}`);
    }
  });
}

/** The six current widths in ns (after at least one pulse), to the nanosecond. */
export function widthsNanos(board) {
  return board.servos().map((servo) => Math.round(servo.widthNanos));
}

/** The six latest frame periods in us, to the nanosecond. */
export function periodsUs(board) {
  return board.servos().map((servo) => Math.round(servo.periodNanos) / 1000);
}

/**
 * Checks a captured move frame by frame, as a logic analyser would see it: every period is
 * exactly `periodNanos`; each pin shows its start width, then frame k's expected width
 * (`framesUs[k]`, the host core's pulses for the pose of frame k) for exactly one period each,
 * in order, within one count, and then holds the last frame's width. So no frame is skipped,
 * repeated or cut short, the move takes exactly `framesUs.length` frames, and every pulse lies
 * within `[min_us, max_us]` of its servo. Returns the period index where the move began.
 */
export function assertMoveOnPins(
  pulses,
  startNanos,
  framesUs,
  { periodNanos, servos, maxStretch = 0 },
) {
  const n = framesUs.length;
  if (maxStretch > 0) {
    return assertMoveOnPinsStretched(pulses, startNanos, framesUs, {
      periodNanos,
      servos,
      maxStretch,
    });
  }
  const first = Math.min(
    ...pulses.map((servo, i) => {
      const index = servo.findIndex((pulse) => pulse.widthNanos !== startNanos[i]);
      return index < 0 ? Infinity : index;
    }),
  );
  assert.ok(Number.isFinite(first), 'nothing moved');
  pulses.forEach((servo, i) => {
    const label = `servo ${i + 1}`;
    assert.ok(servo.length >= first + n + 2, `${label}: only ${servo.length} pulses captured`);
    servo.forEach((pulse, j) => {
      if (pulse.periodNanos !== null) {
        assert.equal(pulse.periodNanos, periodNanos, `${label} period ${j}`);
      }
      const us = pulse.widthNanos / 1000;
      assert.ok(
        us >= servos[i].min_us - COUNT_US / 2 && us <= servos[i].max_us + COUNT_US / 2,
        `${label} pulse ${j}: ${us} us outside its limits`,
      );
      if (j < first) {
        assert.equal(pulse.widthNanos, startNanos[i], `${label} changed before the move`);
      } else if (j < first + n) {
        const expected = framesUs[j - first][i];
        assert.ok(
          Math.abs(us - expected) <= COUNT_US + 1e-9,
          `${label} frame ${j - first + 1}/${n}: ${us} us, host core ${expected} us`,
        );
      } else {
        assert.equal(
          pulse.widthNanos,
          servo[first + n - 1].widthNanos,
          `${label} moved after the last frame`,
        );
      }
    });
  });
  // The move was still under way one frame before its end (it did not finish early).
  if (n >= 2) {
    assert.ok(
      pulses.some((servo) => servo[first + n - 2].widthNanos !== servo[first + n - 1].widthNanos),
      `no pin changed on frame ${n}: the move ended early`,
    );
  }
  return first;
}

/**
 * Like `assertMoveOnPins`, but a frame may stay on the pins for more than one period, at most
 * `maxStretch` extra periods per move (the move took longer: never faster than planned). No
 * frame may be skipped: each pin goes through every frame's width in order.
 */
function assertMoveOnPinsStretched(
  pulses,
  startNanos,
  framesUs,
  { periodNanos, servos, maxStretch },
) {
  const n = framesUs.length;
  const near = (us, expected) => Math.abs(us - expected) <= COUNT_US + 1e-9;
  pulses.forEach((servo, i) => {
    const label = `servo ${i + 1}`;
    let k = -1; // frame on the pin; -1 = still the start width
    let extra = 0;
    servo.forEach((pulse, j) => {
      if (pulse.periodNanos !== null) {
        assert.equal(pulse.periodNanos, periodNanos, `${label} period ${j}`);
      }
      const us = pulse.widthNanos / 1000;
      assert.ok(
        us >= servos[i].min_us - COUNT_US / 2 && us <= servos[i].max_us + COUNT_US / 2,
        `${label} pulse ${j}: ${us} us outside its limits`,
      );
      if (k === -1 && pulse.widthNanos === startNanos[i]) {
        return;
      }
      // The same width as the previous period and still frame k's: held (a stretch).
      const held =
        k >= 0 && pulse.widthNanos === servo[j - 1].widthNanos && near(us, framesUs[k][i]);
      if (!held && k + 1 < n && near(us, framesUs[k + 1][i])) {
        k += 1;
        return;
      }
      assert.ok(
        k >= 0 && near(us, framesUs[k][i]),
        `${label} pulse ${j}: ${us} us is neither ${k < 0 ? 'the start width' : `frame ${k + 1}`} nor frame ${k + 2} of ${n} (a skipped frame?)`,
      );
      if (k < n - 1) {
        extra += 1;
      }
    });
    assert.equal(k, n - 1, `${label} never reached the last frame`);
    assert.ok(extra <= maxStretch, `${label}: ${extra} frames held longer than one period`);
  });
}

// ---- heave read back from the pins ----

/**
 * z (mm) from the six widths on the pins, for poses with only z non-zero: the host core's
 * (`reference`, a HostReference) pulses on a 1 um grid of z, interpolated per servo, averaged
 * over the six. One PWM count is about 1/40 mm of heave with the default platform.
 */
export function heaveReader(reference, fromMm, toMm) {
  const grid = [];
  for (let z = fromMm; z <= toMm + 1e-9; z += 0.001) {
    grid.push(Number(z.toFixed(3)));
  }
  const answers = reference.solve(
    defaultSettings(),
    grid.map((z) => [0, 0, z, 0, 0, 0]),
  );
  const table = answers.map((a, i) => {
    assert.ok(a.ok, `z ${grid[i]}`);
    return a.pulse_us;
  });
  return (widthsUs) => {
    const zs = widthsUs.map((w, servo) => {
      const column = table.map((row) => row[servo]);
      const rising = column[column.length - 1] > column[0];
      // Binary search in the monotonic column.
      let lo = 0;
      let hi = column.length - 1;
      const below = (k) => (rising ? column[k] <= w : column[k] >= w);
      if (!below(lo)) return grid[0];
      if (below(hi)) return grid[hi];
      while (hi - lo > 1) {
        const mid = (lo + hi) >> 1;
        if (below(mid)) lo = mid;
        else hi = mid;
      }
      const t = (w - column[lo]) / (column[hi] - column[lo]);
      return grid[lo] + t * (grid[hi] - grid[lo]);
    });
    return zs.reduce((a, b) => a + b, 0) / zs.length;
  };
}

/** Per-frame z from captured pulses (one value per period, in order). */
export function heaveTrace(pulses, read) {
  const periods = Math.min(...pulses.map((servo) => servo.length));
  return Array.from({ length: periods }, (_, k) =>
    read(pulses.map((servo) => servo[k].widthNanos / 1000)),
  );
}

/** Checks a z trace against the limits: speed, acceleration (with the PWM count's noise), overshoot. */
export function assertWithinLimits(zs, { hz, speed, accel, top, label }) {
  const dt = 1 / hz;
  // One PWM count is about 1/40 mm of heave here; speeds and accelerations from differences of
  // such readings carry that noise (averaged over six servos).
  const zNoise = 0.012;
  const v = zs.slice(1).map((z, k) => (z - zs[k]) / dt);
  v.forEach((s, k) => {
    assert.ok(
      Math.abs(s) <= speed + (2 * zNoise) / dt,
      `${label}: ${s.toFixed(1)} mm/s at frame ${k + 1} (limit ${speed})`,
    );
  });
  v.slice(1).forEach((s, k) => {
    const a = (s - v[k]) / dt;
    assert.ok(
      Math.abs(a) <= accel + (4 * zNoise) / dt / dt,
      `${label}: ${a.toFixed(0)} mm/s2 at frame ${k + 2} (limit ${accel})`,
    );
  });
  zs.forEach((z, k) =>
    assert.ok(
      z <= top + zNoise,
      `${label}: overshoot to ${z.toFixed(3)} mm at frame ${k} (top ${top})`,
    ),
  );
}
