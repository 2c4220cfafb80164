// A SimTools text stream (`128,128,150,128,128,128X...`, no line end ever) through UART0 of the
// real firmware, hit by line noise (docs/streaming.md "Line noise"): bytes outside ASCII, a NUL,
// printable garbage, a lost comma, a frame with five counts. Each costs its frame and no more:
// `status` counts the damaged ones, the whole frames are all received, the pins end on the last
// frame's pose (solved by the host core from the documented format), and nothing of the stream
// is echoed though echo is on, as after power-up.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import {
  assertPins,
  bootQuiet,
  bootTerminal,
  defaultSettings,
  firmwareBootrom,
  ok,
  runFrames,
  status,
} from '../src/test-support/e2e-support.js';
import { HostReference } from '../src/test-support/host-reference.js';

let bootrom;
let reference;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
});

/** A text frame for heave count `z` (8 bits, default axis order x y z roll pitch yaw). */
const frame = (z) => `128,128,${z},128,128,128X`;

test('a text stream survives any byte: damaged frames counted, never applied or echoed', () => {
  const board = bootTerminal(bootrom); // UART0, echo on, no command sent
  board.runMs(50);
  const before = board.output.length;
  // Each damages the frame it is put in (the frame's own counts stay 130..).
  const damage = [
    (f) => f.replace(',128,128X', ',1\xC228,128X'), // a byte outside ASCII
    (f) => f.replace('128,', '12\x008,'), // a NUL
    (f) => f.replace(',128,', ',12q8,'), // printable garbage
    (f) => f.replace(',', ''), // a lost comma
    (f) => f.replace('128,128X', '128X'), // five counts
    (f) => `\xFF\xFE${f}`.replace('X', '\x1bX'), // garbage before it, ESC before its X
  ];
  let whole = 0;
  for (let k = 0; k < 24; k++) {
    let bytes = frame(130 + k);
    if (k % 4 === 1) {
      bytes = damage[(k - 1) / 4](bytes);
    } else {
      whole += 1;
    }
    board.sendBytes(bytes);
    board.runMs(10);
  }
  runFrames(board, 50); // the default speed limits: let the tracker arrive
  const echoed = board.output.slice(before);
  assert.equal(echoed, '', 'nothing of the stream is echoed or answered');
  const z = ((130 + 23 - 128) / 128) * 15; // the last frame's heave, mm
  const [answer] = reference.solve(defaultSettings(), [[0, 0, z, 0, 0, 0]]);
  assert.ok(answer.ok);
  assertPins(board, answer.pulse_us, 'on the last frame');
  board.sendLine('set echo off');
  board.waitForLine(/^ok$/);
  const counts = status(board).stream;
  assert.equal(counts.damaged, damage.length, JSON.stringify(counts));
  assert.equal(counts.frames, whole, JSON.stringify(counts));
});

test('the step guard (pass-through): a frame with a lost digit is dropped and counted, the next good one applied', () => {
  const board = bootQuiet(bootrom);
  for (const line of ['set speed_mm_s off', 'set speed_deg_s off', 'set stream.max_step_pct 10']) {
    ok(board, line);
  }
  const heave = (count) => ((count - 128) / 128) * 15; // mm, default z full scale
  const pins = (count) => {
    const [answer] = reference.solve(defaultSettings(), [[0, 0, heave(count), 0, 0, 0]]);
    assert.ok(answer.ok);
    return answer.pulse_us;
  };
  board.sendBytes(frame(140));
  runFrames(board, 2);
  assertPins(board, pins(140), 'on the first frame');
  board.sendBytes(frame(14)); // "140" lost its last digit: 98 % of full scale away
  runFrames(board, 2);
  assertPins(board, pins(140), 'the lost digit is not applied');
  board.sendBytes(frame(145));
  runFrames(board, 2);
  assertPins(board, pins(145), 'the next good frame is applied');
  const counts = status(board).stream;
  assert.deepEqual(
    [counts.frames, counts.applied, counts.damaged],
    [2, 2, 1],
    JSON.stringify(counts),
  );
  // Off again (the default), the same lost digit reaches the pins.
  ok(board, 'set stream.max_step_pct off');
  board.sendBytes(frame(14));
  runFrames(board, 2);
  assertPins(board, pins(14), 'without the guard');
});

test('status after a stream has ended: idle, with how long since its last frame, until the next frame', () => {
  const board = bootQuiet(bootrom);
  ok(board, 'set speed_mm_s off');
  ok(board, 'set speed_deg_s off');
  board.sendBytes(frame(140));
  runFrames(board, 50); // 1 s after the frame
  assert.equal(status(board).state, 'streaming (pass-through)');
  runFrames(board, 100); // 3 s after it
  assert.match(
    status(board).state,
    /^idle \(stream: no frame for 3\.\d s; holding its last pose, the next frame resumes it\)$/,
  );
  board.sendBytes(frame(141));
  runFrames(board, 2);
  assert.equal(status(board).state, 'streaming (pass-through)');
});
