// A move may start at any instant within a servo frame, including while a frame is being
// computed across the PWM wrap: every frame of it must still reach the pins, once each, in
// order (a frame overwritten before it was latched would make the servos jump two steps).

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import {
  assertMoveOnPins,
  bootQuiet,
  capture,
  defaultSettings,
  firmwareBootrom,
  framePeriodNanos,
  framePoses,
  HOME,
  ok,
  plannedFrames,
  poseText,
  widthsNanos,
} from '../src/test-support/e2e-support.js';
import { HostReference } from '../src/test-support/host-reference.js';

let bootrom;
let reference;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
});

test('moves started at every offset within a frame show every frame in order, none skipped', () => {
  // At 333 Hz (3 ms frames) the command and path check of this 2-frame rotation take longer
  // than a frame, so its first frame is computed after a missed frame start, and for some
  // start offsets right across the next frame start.
  const settings = { ...defaultSettings(), frame_hz: 333, speed_deg_s: 420 };
  const board = bootQuiet(bootrom);
  ok(board, 'set frame_hz 333');
  ok(board, 'set speed_deg_s 420');
  board.runMs(25);
  const away = [0, 0, 0, 0, 0, 2.5];
  const moves = [
    { line: `pose ${poseText(away)}`, from: HOME, to: away },
    { line: 'home', from: away, to: HOME },
  ];
  for (const move of moves) {
    move.frames = reference
      .solve(settings, framePoses(move.from, move.to, plannedFrames(move.from, move.to, settings)))
      .map((answer) => answer.pulse_us);
    assert.equal(move.frames.length, 2);
  }
  const period = framePeriodNanos(settings.frame_hz);
  const byteNanos = (10 * 1e9) / board.baud;
  const step = 60_000;
  for (let trial = 0; trial * step < period; trial++) {
    const move = moves[trial % 2];
    // The line's last byte arrives `trial * step` after a frame start.
    const lastRise = board.servoMeter.pins[0].lastRiseNanos;
    const lineNanos = (move.line.length + 1) * byteNanos;
    let sendAt = lastRise + trial * step - lineNanos;
    while (sendAt < board.nanos + 1000) {
      sendAt += period;
    }
    board.runUntil(() => board.nanos >= sendAt, { timeoutMs: 50 });
    const start = widthsNanos(board);
    const pulses = capture(
      board,
      () => {
        board.sendLine(move.line);
        assert.equal(board.waitForLine(/^(ok|error:)/), 'ok');
      },
      move.frames.length + 4,
      settings.frame_hz,
    );
    // A frame computed right at a frame start may be held one period longer (never skipped).
    assertMoveOnPins(pulses, start, move.frames, {
      periodNanos: period,
      servos: settings.servos,
      maxStretch: 1,
    });
  }
});
