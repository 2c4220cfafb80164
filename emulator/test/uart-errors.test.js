// UART receive errors through the real firmware: a sender at the wrong baud rate garbles most
// of its bytes (each arrives with a framing error, injected into the emulated PL011's FIFO).
// docs/commands.md: the first loss of a burst is announced at once, the rest counted and
// reported in one notice when the burst ends; the board answers the next line at once.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { bootQuiet, firmwareBootrom, ok, steadyPulses } from '../src/test-support/e2e-support.js';

let bootrom;
before(() => {
  bootrom = firmwareBootrom();
});

const BYTE_MS = (10 / 115_200) * 1000; // 8N1 at the default baud rate

test('a burst of UART receive errors gives one warning at once and one with its count, not one per byte', () => {
  const board = bootQuiet(bootrom);
  const held = steadyPulses(board);
  const timed = () => {
    const start = board.millis;
    ok(board, 'status');
    return board.millis - start;
  };
  const quiet = timed(); // a status on a clean line: its reply takes this long to leave
  const from = board.lines.length;
  // 1,600 bytes, as from a sender at 921,600 against the board's 115,200: every one arrives
  // with a framing error (lost).
  const bytes = [];
  for (let i = 0; i < 1600; i++) {
    bytes.push(0x40 + (i % 32));
  }
  board.sendGarbled(Buffer.from(bytes));
  board.runMs(1600 * BYTE_MS + 1);
  const during = board.lines.slice(from);
  // While the burst goes on: its first loss, at once, and nothing more.
  assert.equal(during.length, 1, JSON.stringify(during));
  assert.match(during[0], /^# warning: UART receive error, input lost \(at least (\d+) bytes?\)$/);
  const first = Number(during[0].match(/least (\d+)/)[1]);
  board.runMs(300); // more than the 0.2 s that end a burst
  const reported = board.lines.slice(from);
  assert.equal(reported.length, 2, JSON.stringify(reported));
  const m = reported[1].match(
    /^# warning: UART receive errors went on: (\d+) more, input lost \(at least (\d+) bytes?\) in (\d+\.\d\d) s$/,
  );
  assert.ok(m, reported[1]);
  const [more, lost, seconds] = [Number(m[1]), Number(m[2]), Number(m[3])];
  // Each loss the firmware noticed on its own (a gap it had not reached yet grows instead).
  assert.ok(more >= 1 && more <= 1599, `${more} more`);
  assert.ok(lost >= more && first + lost <= 1600, `${first} + ${lost} bytes`);
  assert.ok(seconds > 0 && seconds <= (1600 * BYTE_MS) / 1000 + 0.03, `${seconds} s`);
  // Nothing moved; the cut line is refused at its end, and the next line runs at once.
  assert.deepEqual(steadyPulses(board), held);
  const cut = board.request('');
  assert.match(cut.reply, /^error:rx-overflow /);
  const after = timed();
  assert.ok(after < quiet + 3, `status took ${after} ms, ${quiet} ms on a clean line`);
});
