// Stalls and resets, through the real firmware ELF: a main loop that stops (stuck in a busy
// loop with interrupts still running, or asleep with every interrupt masked) is caught by the
// watchdog after its 500 ms; the reset restarts the firmware, whose servos come back at their
// home pulses and which then takes commands again.
//
// What is emulated and what is real: the watchdog's countdown and expiry are rp2040js's model
// of the firmware's own register programming (LOAD, CTRL, tick), and the firmware's choice of
// what a watchdog reset resets (PSM WDSEL) is read from the chip and checked. The reset itself
// cannot go through the boot ROM in rp2040js (no flash interface model), so the harness
// performs it (`onWatchdog: 'reset'`): a fresh chip, the same flash image, from boot2, at the
// same emulated time. The stall is injected from outside (a test-only fault, not a firmware
// command): the core is sent into a `b .` loop in unused SRAM, or every NVIC interrupt is
// masked.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { BANNER, EmulatedBoard, WDSEL_FULL_RESET } from '../src/chip/board.js';
import { firmwareBootrom, FRAME_MS, steadyPulses } from '../src/test-support/e2e-support.js';

const WATCHDOG_MS = 500; // the firmware's documented watchdog period
const HANG_ADDRESS = 0x20041000; // SRAM bank 5: outside the firmware's 256 KiB RAM region
const BRANCH_TO_SELF = 0xe7fe; // Thumb `b .`

let bootrom;
before(() => {
  bootrom = firmwareBootrom();
});

/** Boots with resets enabled, measures the power-on pulses, then moves away from home. */
function movedBoard() {
  const board = new EmulatedBoard({ bootrom, onWatchdog: 'reset' });
  board.boot();
  board.runMs(3 * FRAME_MS);
  const home = steadyPulses(board);
  assert.equal(board.request('pose 0 0 10 0 0 5').reply, 'ok');
  board.runMs(1000);
  const moved = steadyPulses(board);
  assert.notDeepEqual(moved, home);
  return { board, home, moved };
}

const stalls = {
  'stuck in a busy loop (interrupts still served)': (board) => {
    board.mcu.sramView.setUint16(HANG_ADDRESS - 0x20000000, BRANCH_TO_SELF, true);
    board.mcu.core.PC = HANG_ADDRESS;
    board.mcu.core.waiting = false;
  },
  'asleep with every interrupt masked': (board) => {
    board.mcu.core.enabledInterrupts = 0;
  },
};

for (const [name, stall] of Object.entries(stalls)) {
  test(`a main loop ${name} is reset by the watchdog; the servos come back home`, () => {
    const { board, home, moved } = movedBoard();
    const bannersBefore = board.lines.filter((l) => BANNER.test(l)).length;
    const stalledAt = board.millis;
    stall(board);

    // Until the watchdog fires, the PWM hardware keeps the last pulses (the CPU is not needed).
    board.runMs(WATCHDOG_MS - 2 * FRAME_MS);
    assert.equal(board.resets.length, 0, 'reset too early');
    assert.deepEqual(board.pulseWidthsUs(), moved);

    // The last feed was at most one main-loop pass (well under a frame) before the stall.
    assert.ok(
      board.runUntil(() => board.resets.length > 0, { timeoutMs: 3 * FRAME_MS }),
      'no reset',
    );
    const resetAfterMs = board.resets[0].nanos / 1e6 - stalledAt;
    assert.ok(
      resetAfterMs > WATCHDOG_MS - FRAME_MS && resetAfterMs <= WATCHDOG_MS,
      `reset ${resetAfterMs} ms after the stall`,
    );
    assert.equal(
      board.resets[0].wdsel & WDSEL_FULL_RESET,
      WDSEL_FULL_RESET,
      'WDSEL: not a full reset',
    );

    // The firmware starts again: banner, then home pulses on every servo.
    board.waitForLine(BANNER, { timeoutMs: 100 });
    assert.equal(board.lines.filter((l) => BANNER.test(l)).length, bannersBefore + 1);
    board.runMs(3 * FRAME_MS);
    assert.deepEqual(steadyPulses(board), home, 'not at the power-on pulses after the reset');
    for (const servo of board.servos()) {
      assert.ok(servo.live, `servo ${servo.servo} not pulsing after the reset`);
    }

    // And it works: a command moves the platform again, and it runs on without more resets.
    assert.equal(board.request('pose 0 0 10 0 0 5').reply, 'ok');
    board.runMs(1000);
    assert.deepEqual(steadyPulses(board), moved);
    board.runMs(2000);
    assert.equal(board.resets.length, 1);
  });
}

test('a busy but healthy firmware is never reset', () => {
  const board = new EmulatedBoard({ bootrom, onWatchdog: 'reset' });
  board.boot();
  // Back-to-back long moves and full listings for a few seconds.
  for (let i = 0; i < 20; i++) {
    const x = i % 2 === 0 ? 30 : -30;
    assert.equal(board.request(`pose ${x} 0 0 0 0 ${i / 4}`).reply, 'ok');
    assert.equal(board.request('help').reply, 'ok');
    assert.equal(board.request('config').reply, 'ok');
    board.runMs(100);
  }
  board.runMs(1000);
  assert.deepEqual(board.resets, []);
});
