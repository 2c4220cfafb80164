// One link never holds up the other (README.md, "Serial links"), through the real firmware
// ELF: a USB host that stops reading, or reads slowly (one 64-byte packet every 5, 20 or
// 90 ms: src/gaps/usb.js, gap 11), while a long listing of its own is under way, delays
// UART0's next line by 0.1 s at most, from the line's end to its reply's first byte, in
// emulated time. The host changes its pace, and the line is sent at once, at several moments
// of the servo frame (a deadline checked only when a frame wakes the loop shows up as up to a
// frame late; a host that has just stopped reading is not yet 0.1 s stalled).

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { BANNER, EmulatedBoard } from '../src/chip/board.js';
import { firmwareBootrom, FRAME_MS } from '../src/test-support/e2e-support.js';

/** README.md, "Serial links": UART0's next line waits 0.1 s at most. */
const PROMISED_WAIT_MS = 100;
/**
 * USB listings sent: about 70 KB of output (1.7 KB each), far more than the firmware's 4 KB
 * queue, and about 60 ms of a full-speed bus: still under way when the host changes its pace.
 */
const USB_LISTINGS = 40;

let bootrom;
before(() => {
  bootrom = firmwareBootrom();
});

/** Both links open, echo off on both (so UART0's first byte after a line is its reply). */
function quietLinks() {
  const board = new EmulatedBoard({ bootrom, usb: true });
  board.boot();
  board.usb.waitUntilOpen();
  board.usb.waitForLine(BANNER);
  assert.equal(board.usb.request('set echo off').reply, 'ok');
  assert.equal(board.request('set echo off').reply, 'ok');
  board.runMs(2);
  return board;
}

/**
 * Sends `line` on UART0 and runs until its final reply; returns the emulated milliseconds
 * from the line's last byte reaching the chip to the reply's first byte.
 */
function uartReplyDelayMs(board, line) {
  let endNanos = null;
  let firstNanos = null;
  const unsubscribe = board.onOutput(() => {
    if (firstNanos === null) {
      firstNanos = board.nanos;
    }
  });
  const from = board.lines.length;
  board.sendLine(line);
  assert.ok(
    board.runUntil(() => board.inputPending === 0, { timeoutMs: 100 }),
    'line sent',
  );
  // The last byte's stop bit ended then (src/gaps/uart.js, gap 3).
  endNanos = board.input.lastDeliveryNanos;
  const answered = board.runUntil(
    () => board.lines.slice(from).some((text) => /^(ok|error:)/.test(text)),
    { timeoutMs: 3000 },
  );
  unsubscribe();
  assert.ok(answered, `no reply to '${line}' on UART0`);
  assert.ok(board.lines.slice(from).includes('ok'), JSON.stringify(board.lines.slice(from)));
  return (firstNanos - endNanos) / 1e6;
}

/**
 * A USB host with `USB_LISTINGS` listings of its own under way, read at the bus's pace until
 * `afterMs`, then as `setUp` makes it read (stopped, or slowly); UART0's `status` sent at
 * once: its reply's delay, ms.
 */
function delayBehindUsb(setUp, afterMs) {
  const board = quietLinks();
  for (let i = 0; i < USB_LISTINGS; i++) {
    board.usb.sendLine('help');
  }
  board.runMs(afterMs);
  setUp(board.usb);
  const delayMs = uartReplyDelayMs(board, 'status');
  // UART0's next line waits no longer, and the USB link answers again once its host has
  // read what was queued for it (README.md: its output is dropped until then).
  assert.ok(uartReplyDelayMs(board, 'status') <= PROMISED_WAIT_MS, 'a second status');
  board.usb.readSlowly(0);
  board.usb.startReading();
  board.runMs(200);
  const reply = board.usb.request('frob', { final: /^error:unknown-command 'frob'/ });
  assert.match(reply.reply, /^error:unknown-command 'frob'/);
  return delayMs;
}

/** Moments after the USB listings were sent, a quarter frame apart: all before they end. */
const PHASES_MS = [30, 30 + FRAME_MS / 4, 30 + FRAME_MS / 2, 30 + (3 * FRAME_MS) / 4];

test('a USB host that stops reading delays UART0 by 0.1 s at most, in every frame phase', () => {
  for (const afterMs of PHASES_MS) {
    const delayMs = delayBehindUsb((usb) => usb.stopReading(), afterMs);
    assert.ok(delayMs <= PROMISED_WAIT_MS, `sent ${afterMs} ms after: ${delayMs.toFixed(1)} ms`);
  }
});

for (const intervalMs of [5, 20, 90]) {
  test(`a USB host reading a packet every ${intervalMs} ms delays UART0 by 0.1 s at most`, () => {
    for (const afterMs of PHASES_MS) {
      const delayMs = delayBehindUsb((usb) => usb.readSlowly(intervalMs), afterMs);
      assert.ok(delayMs <= PROMISED_WAIT_MS, `sent ${afterMs} ms after: ${delayMs.toFixed(1)} ms`);
    }
  });
}
