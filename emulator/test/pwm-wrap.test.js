// A jump's six new pulse widths reach the pins in one frame, wherever the frame start falls
// while the firmware writes them. The PWM's compare (CC) and TOP registers latch at the wrap
// (RP2040 datasheet 4.5.2.3, double buffering; rp2040js models it), so a wrap that fell
// between the writes of one slice's channels, or of two slices, would show some servos the new
// widths and the others the old ones for a frame: a mix of two poses that nothing checked.
//
// A jump (speed limits off) is written as soon as its line is checked, at any moment of the
// frame. The test places that moment at the wrap: when the firmware starts writing (its first
// access to a slice's counter or compare register once the line has been sent), it sets the
// three counters (in phase, as the firmware starts them) a few counts before their TOP, as if
// the line had come a little later, and the pins then show frame by frame which widths each
// servo had.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import {
  bootQuiet,
  capture,
  firmwareBootrom,
  ok,
  poseText,
  runFrames,
  widthsNanos,
} from '../src/test-support/e2e-support.js';

/** Slices 1-3 (servos 1-6); each slice's registers are 0x14 bytes apart: CSR DIV CTR CC TOP. */
const SLICES = [1, 2, 3];
const SLICE_BYTES = 0x14;
const CTR = 0x08;
const CC = 0x0c;

let bootrom;
before(() => {
  bootrom = firmwareBootrom();
});

/**
 * Arms a one-shot hook on the board's PWM: at the firmware's first read or write of a servo
 * slice's counter or compare register, every servo slice's counter is set to `countsBeforeTop`
 * counts before its TOP (before the access is carried out). Returns `{ fired }`.
 */
function wrapAtNextWrite(board, countsBeforeTop) {
  const pwm = board.mcu.pwm;
  const state = { fired: false };
  const isServoCounterOrCompare = (offset) => {
    const slice = Math.floor(offset / SLICE_BYTES);
    const register = offset % SLICE_BYTES;
    return SLICES.includes(slice) && (register === CTR || register === CC);
  };
  const fire = (offset) => {
    if (state.fired || !isServoCounterOrCompare(offset)) {
      return;
    }
    state.fired = true;
    for (const slice of SLICES) {
      const channel = pwm.channels[slice];
      channel.timer.set(channel.timer.top - countsBeforeTop);
    }
  };
  const { readUint32, writeUint32 } = pwm;
  pwm.readUint32 = (offset) => {
    fire(offset);
    return readUint32.call(pwm, offset);
  };
  pwm.writeUint32 = (offset, value) => {
    fire(offset);
    writeUint32.call(pwm, offset, value);
  };
  return state;
}

/** Which of `from` or `to` (nanoseconds) each width is, or null for neither (within a count). */
function sideOf(width, from, to) {
  const near = (a, b) => Math.abs(a - b) <= 320;
  if (near(width, from)) {
    return 'old';
  }
  return near(width, to) ? 'new' : null;
}

test('a jump written as a frame starts: every frame shows all six old widths or all six new ones', () => {
  const poses = [
    [6, -5, 4, 3, -2, 5],
    [-6, 5, -4, -3, 2, -5],
  ];
  // The firmware's writes of six widths take a few dozen cycles; a count is 40. Placing the
  // wrap 0 to 5 counts after the first access covers a wrap before, inside and after them.
  for (let countsBeforeTop = 0; countsBeforeTop <= 5; countsBeforeTop += 1) {
    const board = bootQuiet(bootrom);
    ok(board, 'set speed_mm_s off');
    ok(board, 'set speed_deg_s off');
    for (const [k, pose] of poses.entries()) {
      runFrames(board, 2);
      const from = widthsNanos(board);
      // The frame's own write is done (it follows the wrap): the next access is the jump's.
      runFrames(board, 0.1);
      const hook = wrapAtNextWrite(board, countsBeforeTop);
      const pulses = capture(board, () => ok(board, `pose ${poseText(pose)}`), 4);
      assert.ok(hook.fired, 'the jump wrote the PWM');
      const to = widthsNanos(board);
      for (let servo = 0; servo < 6; servo += 1) {
        assert.ok(
          Math.abs(to[servo] - from[servo]) > 1000,
          `pose ${k}: servo ${servo + 1} changes (${from[servo]} -> ${to[servo]} ns)`,
        );
      }
      const frames = Math.min(...pulses.map((servo) => servo.length));
      assert.ok(frames >= 4, `${frames} frames recorded`);
      for (let frame = 0; frame < frames; frame += 1) {
        const sides = pulses.map((servo, i) => sideOf(servo[frame].widthNanos, from[i], to[i]));
        assert.ok(
          sides.every((side) => side === sides[0]) && sides[0] !== null,
          `wrap ${countsBeforeTop} counts after the first write, pose ${k}, frame ${frame}: ` +
            `servos show ${sides.join(' ')} (widths ${pulses.map((s) => s[frame].widthNanos)} ns)`,
        );
      }
      // The new widths arrive, and stay.
      assert.ok(pulses.every((servo) => servo.at(-1).widthNanos === servo.at(-2).widthNanos));
    }
  }
});

test('a width becomes the nearest count, half up, from the exact value of its f32', () => {
  // Widths just below a half count (as typed: their nearest f32s lie a hair below it), where
  // the product w * 3.125 rounded to f32 before adding 0.5 lands on the half and rounds up:
  // picked here by that very property, so the test tells the exact rule from the f32 one.
  const f32 = Math.fround;
  const widths = [];
  for (let k = 4600; widths.length < 4; k += 1) {
    const w = f32((k + 0.5) / 3.125);
    const viaF32 = Math.floor(f32(f32(w * 3.125) + 0.5));
    const exact = Math.floor(w * 3.125 + 0.5); // exact in f64: 24 bits times 25/8, plus 0.5
    if (viaF32 !== exact) {
      widths.push({ w, text: w.toPrecision(9), exact });
    }
  }
  const board = bootQuiet(bootrom);
  for (const { w, text, exact } of widths) {
    assert.equal(f32(Number(text)), w, `${text} is the f32 meant`);
    ok(board, `servo 1 ${text}`);
    runFrames(board, 2);
    assert.equal(board.servos()[0].widthCounts, exact, `servo 1 ${text} us`);
  }
});
