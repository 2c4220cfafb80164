// Abuse through the real firmware ELF in the emulator: whatever arrives on UART0 (overlong
// lines, binary garbage, bursts, pauses mid-line, every line-end style, NUL, UTF-8, numbers
// that are not numbers), the servos stay where the last good command put them, every line
// gets at most one final reply (exactly one where one is due), and the next good command
// works. Bytes the firmware cannot take in time are reported, never lost silently.
//
// Expected replies come from the documented protocol and error codes (docs/commands.md and
// docs/error-codes.md);
// expected pulse widths come from measurement: the pins before the abuse, or a separate
// reference board that was only ever sent the good command.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { FINAL_REPLY } from '../src/chip/board.js';
import {
  bootedBoard,
  firmwareBootrom,
  FRAME_MS,
  steadyPulses,
} from '../src/test-support/e2e-support.js';

const MAX_LINE = 128; // documented line buffer
const BYTE_MS = (10 / 115_200) * 1000; // 8N1 at the default baud rate

let bootrom;
before(() => {
  bootrom = firmwareBootrom();
});

function bootedAndPulsing() {
  const board = bootedBoard(bootrom);
  board.runMs(3 * FRAME_MS);
  return board;
}

/** Runs until the pins have held still for five frames (a move has ended); returns them. */
function settle(board, { timeoutMs = 5000 } = {}) {
  let last = board.pulseWidthsUs();
  let still = 0;
  const end = board.millis + timeoutMs;
  while (still < 5) {
    assert.ok(board.millis < end, 'the servos never settled');
    board.runMs(FRAME_MS);
    const now = board.pulseWidthsUs();
    still = JSON.stringify(now) === JSON.stringify(last) ? still + 1 : 0;
    last = now;
  }
  return last;
}

/** Final replies (`ok` / `error:...`) received from line index `from` on. */
function finalsFrom(board, from) {
  return board.lines.slice(from).filter((line) => FINAL_REPLY.test(line));
}

/** The code of an `error:<code> ...` reply. */
function codeOf(reply) {
  return /^error:(\S+)/.exec(reply)?.[1] ?? null;
}

// Pins of poses reached on a board that was only ever sent good pose commands.
let referenceBoard = null;
const referenceCache = new Map();
function referencePulses(command) {
  if (!referenceCache.has(command)) {
    referenceBoard ??= bootedAndPulsing();
    assert.equal(referenceBoard.request(command).reply, 'ok', command);
    referenceCache.set(command, settle(referenceBoard));
  }
  return referenceCache.get(command);
}

/** The next good command is understood and moves the pins where it says. */
function goodCommandWorks(board, held, command = 'pose 0 0 7 0 0 0') {
  // End whatever partial line the abuse left (its reply, if any, is not the one wanted here).
  board.sendBytes('\r\n');
  board.runMs(20);
  board.lineCursor = board.lines.length;
  const { reply } = board.request(command);
  assert.equal(reply, 'ok', `${command} after the abuse`);
  const pins = settle(board);
  assert.deepEqual(pins, referencePulses(command), `${command} did not arrive`);
  assert.notDeepEqual(pins, held, `${command} did not move the pins`);
}

/** Deterministic PRNG (mulberry32) for reproducible garbage. */
function prng(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

function randomBytes(seed, n, { exclude = [] } = {}) {
  const next = prng(seed);
  const out = [];
  while (out.length < n) {
    const b = Math.floor(next() * 256);
    if (!exclude.includes(b)) {
      out.push(b);
    }
  }
  return Buffer.from(out);
}

/**
 * Accounts for every sent line in the output that followed it: each reply is preceded by its
 * echo ("> " + the line as the firmware kept it). A line the firmware ran must be exactly a
 * line that was sent, in order, with the reply `expectedReply(line)`. Whenever sent lines
 * were skipped, the loss must have been reported in between: by an rx-overflow refusal, or,
 * for a gap that swallowed the rest of the input (no line end followed yet), by the warning
 * written the moment the loss began (so it comes before the replies to the lines received
 * ahead of the gap; a refusal answers it); that cut line is then refused as soon as a line
 * end arrives. Returns the last line that ran.
 */
/** The last `pose` line that ran (its echo followed by `ok`) in the output from `from` on. */
function lastPoseRun(board, from) {
  return board.lines
    .slice(from)
    .filter((l, k, all) => l.startsWith('> pose') && all[k + 1] === 'ok')
    .at(-1)
    .slice(2);
}

function accountForEveryLine(board, from, sent, expectedReply) {
  const out = board.lines.slice(from);
  let next = 0; // index in `sent` of the next line not yet accounted for
  let refusedSinceLastRun = false;
  let noticeUnanswered = false;
  let lastRun = null;
  let overflowErrors = 0;
  out.forEach((line, k) => {
    if (
      line.startsWith('# warning: receive queue overflowed') ||
      line.startsWith('# warning: UART receive error')
    ) {
      noticeUnanswered = true;
      return;
    }
    if (!FINAL_REPLY.test(line)) {
      return;
    }
    if (codeOf(line) === 'rx-overflow') {
      overflowErrors++;
      refusedSinceLastRun = true;
      noticeUnanswered = false;
      return;
    }
    const echo = out[k - 1];
    assert.ok(echo.startsWith('> '), `no echo before ${line}: ${echo}`);
    const text = echo.slice(2);
    const index = sent.indexOf(text, next);
    assert.ok(
      index >= 0,
      `ran a line that was never sent (or out of order): ${JSON.stringify(text)}`,
    );
    if (index > next) {
      assert.ok(refusedSinceLastRun, `lines ${next}..${index - 1} vanished without an rx-overflow`);
    }
    assert.ok(line.startsWith(expectedReply(text)), `${text}: ${line}`);
    lastRun = text;
    next = index + 1;
    refusedSinceLastRun = false;
  });
  assert.ok(next < sent.length || overflowErrors > 0, 'nothing was lost: the test did not test');
  if (next < sent.length) {
    assert.ok(
      refusedSinceLastRun || noticeUnanswered,
      `the last ${sent.length - next} lines vanished silently`,
    );
  }
  if (!refusedSinceLastRun && next < sent.length) {
    // The line cut by the gap is refused as soon as a line end arrives.
    board.lineCursor = board.lines.length;
    const { reply } = board.request('');
    assert.equal(codeOf(reply), 'rx-overflow', reply);
    overflowErrors++;
  }
  assert.ok(overflowErrors > 0, 'bytes were lost but no line was refused');
  return lastRun;
}

test('lines ten times the buffer get one line-too-long each and nothing moves', () => {
  const board = bootedAndPulsing();
  const held = steadyPulses(board);
  const from = board.lines.length;
  for (const line of [
    'x'.repeat(10 * MAX_LINE),
    `pose 0 0 9 0 0 0${' '.repeat(10 * MAX_LINE)}`, // a good command made too long
    `pose 0 0 9 0 0 ${'0'.repeat(10 * MAX_LINE)}`,
  ]) {
    const { reply } = board.request(line, { timeoutMs: 2000 });
    assert.equal(codeOf(reply), 'line-too-long', reply);
    assert.deepEqual(steadyPulses(board), held);
  }
  assert.equal(finalsFrom(board, from).length, 3);
  assert.equal(board.rxFifoDroppedBytes, 0);
  goodCommandWorks(board, held);
});

test('binary garbage (seeded) is refused and never moves a servo', () => {
  const board = bootedAndPulsing();
  const held = steadyPulses(board);

  // Without line ends: one line, refused once when it ends.
  let from = board.lines.length;
  const noEnds = randomBytes(0x5eed, 2048, { exclude: [0x0a, 0x0d, 0x03, 0x18] });
  board.sendBytes(noEnds);
  board.runMs(noEnds.length * BYTE_MS + 50);
  assert.deepEqual(finalsFrom(board, from), [], 'a reply before the line ended');
  const { reply } = board.request('');
  assert.match(codeOf(reply) ?? reply, /^(bad-character|line-too-long)$/);
  assert.deepEqual(finalsFrom(board, from).length, 1);
  assert.deepEqual(steadyPulses(board), held);

  // Anything at all, line ends included: only refusals, at most one per line end.
  from = board.lines.length;
  const garbage = randomBytes(0xbad5eed, 8192);
  const lineEnds = [...garbage].filter((b) => b === 0x0a || b === 0x0d).length;
  board.sendBytes(garbage);
  board.runMs(garbage.length * BYTE_MS + 100);
  const replies = finalsFrom(board, from);
  assert.ok(
    replies.length > 0 && replies.length <= lineEnds,
    `${replies.length} replies, ${lineEnds} line ends`,
  );
  for (const r of replies) {
    assert.ok(codeOf(r) !== null, `garbage was accepted: ${r}`);
  }
  assert.deepEqual(steadyPulses(board), held);
  assert.equal(board.rxFifoDroppedBytes, 0);
  goodCommandWorks(board, held);
});

test('a burst at the line rate is answered in order, one final reply per line', () => {
  const board = bootedAndPulsing();
  const held = steadyPulses(board);
  // Valid and invalid commands back to back with no pause; expected replies from the docs.
  const kinds = [
    (i) => [`move z=${(i / 10).toFixed(1)}`, 'ok'],
    () => ['status', 'ok'],
    () => ['pose 1e39 0 0 0 0 0', 'number-too-large'],
    (i) => [`frobnicate ${i}`, 'unknown-command'],
    () => ['check 0 0 5 0 0 0', 'ok'],
    () => ['nudge yaw=nan', 'not-finite'],
  ];
  const burst = [];
  for (let i = 0; i < 120; i++) {
    burst.push(kinds[i % kinds.length](i));
  }
  const lastMove = burst.filter(([line]) => line.startsWith('move')).at(-1)[0];

  const from = board.lines.length;
  board.sendBytes(burst.map(([line]) => `${line}\n`).join(''));
  assert.ok(
    board.runUntil(() => finalsFrom(board, from).length >= burst.length, { timeoutMs: 5000 }),
    `only ${finalsFrom(board, from).length} of ${burst.length} replies`,
  );
  board.runMs(100);
  const replies = finalsFrom(board, from);
  assert.equal(replies.length, burst.length);
  replies.forEach((reply, i) => {
    const want = burst[i][1];
    assert.equal(
      want === 'ok' ? reply : codeOf(reply),
      want,
      `line ${i} (${burst[i][0]}): ${reply}`,
    );
  });
  assert.ok(
    !board.lines.slice(from).some((l) => l.includes('overflow')),
    'overflow at the line rate',
  );
  assert.equal(board.rxFifoDroppedBytes, 0);

  // Where the last move put it (z = 11.4 mm: the moves only touch z).
  const pins = settle(board);
  assert.equal(lastMove, 'move z=11.4');
  assert.deepEqual(pins, referencePulses('pose 0 0 11.4 0 0 0'));
  goodCommandWorks(board, held);
});

test('faster than the firmware can act: lost bytes are reported, never lost silently', () => {
  const board = bootedAndPulsing();
  // Long moves make the firmware check ~120 poses on each path while the rest of the burst
  // keeps arriving at the line rate, and the error replies to the junk lines are far longer
  // than the lines: the firmware takes input only as fast as its replies leave, and its
  // 4,096-byte receive queue must overflow.
  const heavy = [
    'pose 30 0 0 0 0 0',
    'pose -30 0 0 0 0 0',
    'pose 0 30 0 0 0 0',
    'pose 0 -30 0 0 0 0',
    'pose 30 0 0 0 0 1',
    'pose -30 0 0 0 0 1',
  ];
  const sent = [...heavy];
  for (let i = 0; i < 600; i++) {
    sent.push(`xyzzy ${i}`);
  }
  sent.push('pose 0 0 6 0 0 0');
  const totalBytes = sent.reduce((n, line) => n + line.length + 1, 0);

  const from = board.lines.length;
  board.sendBytes(sent.map((line) => `${line}\n`).join(''));
  board.runMs(totalBytes * BYTE_MS + 6000);
  assert.equal(board.inputPending, 0);
  assert.equal(
    board.rxFifoDroppedBytes,
    0,
    'bytes lost in the hardware FIFO, where nobody can see it',
  );

  const out = board.lines.slice(from);
  const notices = out.filter((l) =>
    /^# warning: receive queue overflowed, input lost \(at least \d+ bytes? so far\)$/.test(l),
  );
  assert.ok(notices.length > 0, 'no overflow notice');
  accountForEveryLine(board, from, sent, (text) =>
    text.startsWith('pose') ? 'ok' : 'error:unknown-command',
  );
  // The exact counts come with the refusals of the lines the gaps cut.
  const lostReported = board.lines
    .slice(from)
    .map((l) => /^error:rx-overflow receive queue overflowed, (\d+) bytes? lost/.exec(l))
    .filter(Boolean)
    .reduce((n, m) => n + Number(m[1]), 0);
  const lastPose = lastPoseRun(board, from);
  assert.ok(lostReported > 0 && lostReported < totalBytes, `${lostReported} bytes reported lost`);

  // The platform is where the last pose that ran put it.
  assert.deepEqual(settle(board), referencePulses(lastPose), `not at ${lastPose}`);
  goodCommandWorks(board, referencePulses(lastPose));
});

test('bytes the hardware FIFO could not take (interrupts held off) are reported', () => {
  const board = bootedAndPulsing();
  const sent = [];
  for (let i = 1; i <= 12; i++) {
    sent.push(`pose 0 0 ${i} 0 0 0`);
  }
  const from = board.lines.length;
  board.sendBytes(sent.map((line) => `${line}\n`).join(''));
  // Part way into the third line, hold every interrupt off for 10 ms (as a long critical
  // section would): the 32-byte RX FIFO fills and the UART loses the bytes after that (an
  // overrun), which only the OE flag on the next byte tells the firmware.
  board.runMs(40 * BYTE_MS);
  const { core } = board.mcu;
  const enabled = core.enabledInterrupts;
  core.enabledInterrupts = 0;
  board.runMs(10);
  core.enabledInterrupts = enabled;
  core.interruptsUpdated = true;
  core.waiting = false;
  board.runMs(sent.length * 20 * BYTE_MS + 500);
  assert.ok(board.rxFifoDroppedBytes > 32, `${board.rxFifoDroppedBytes} bytes lost in the FIFO`);
  // The UART cannot tell how many bytes an overrun lost: the warning and the refusal say
  // "at least".
  assert.ok(
    board.lines
      .slice(from)
      .some((l) => /^# warning: UART receive error, input lost \(at least \d+ bytes?\)$/.test(l)),
    `no notice in ${JSON.stringify(board.lines.slice(from))}`,
  );
  // The lines before the gap ran; the one it cut was refused; after the loss the firmware
  // drops input until it has caught up with the gap (so a gap is never skipped over).
  accountForEveryLine(board, from, sent, () => 'ok');
  const lastPose = lastPoseRun(board, from);
  assert.ok(sent.indexOf(lastPose) >= 2, `only ${lastPose} ran`);
  assert.deepEqual(settle(board), referencePulses(lastPose));
  goodCommandWorks(board, referencePulses(lastPose));
});

test('after a UART overrun, a lone line end closes the cut line and a resync works as documented', () => {
  const board = bootedAndPulsing();
  assert.equal(board.request('set echo off').reply, 'ok');
  const from = board.lines.length;
  // Half a line, then, with every interrupt held off (a long critical section), more than the
  // 32-byte RX FIFO holds: the UART loses the rest (an overrun), which it cannot count.
  board.sendBytes('pose 0 0 5 0 0 0 ');
  board.runMs(20 * BYTE_MS);
  const { core } = board.mcu;
  const enabled = core.enabledInterrupts;
  core.enabledInterrupts = 0;
  board.sendBytes('y'.repeat(60));
  board.runMs(70 * BYTE_MS);
  core.enabledInterrupts = enabled;
  core.interruptsUpdated = true;
  core.waiting = false;
  board.runMs(5);
  assert.ok(board.rxFifoDroppedBytes >= 28, `${board.rxFifoDroppedBytes} bytes lost in the FIFO`);
  // The warning says what the UART can know: at least one byte.
  const warning = board.waitForLine(/^# warning: /, { timeoutMs: 100 });
  assert.match(warning, /^# warning: UART receive error, input lost \(at least \d+ bytes?\)$/);
  // The documented resync: a lone line end to close the cut line (it is the first byte into the
  // FIFO after the loss, so it carries the PL011's overrun flag, and it is good), then
  // `status`, reading until its final reply.
  const cut = board.request('');
  assert.match(
    cut.reply,
    /^error:rx-overflow input lost \(at least \d+ bytes?, some in the UART\); the line was discarded/,
  );
  const { reply, lines } = board.request('status');
  assert.equal(reply, 'ok', JSON.stringify(board.lines.slice(from)));
  assert.ok(lines.some((l) => l.startsWith('# state: ')));
  assert.deepEqual(
    board.lines.slice(from).filter((l) => FINAL_REPLY.test(l)),
    [cut.reply, 'ok'],
  );
});

test('a line split across long pauses is one line', () => {
  const board = bootedAndPulsing();
  const held = steadyPulses(board);
  const from = board.lines.length;
  board.sendBytes('pose 0 0 ');
  board.runMs(3000);
  assert.deepEqual(finalsFrom(board, from), []);
  assert.deepEqual(steadyPulses(board), held);
  board.sendBytes('5 0 0');
  board.runMs(2000);
  assert.deepEqual(finalsFrom(board, from), []);
  assert.deepEqual(steadyPulses(board), held);
  board.sendBytes(' 0\r\n');
  const reply = board.waitForLine(FINAL_REPLY);
  assert.equal(reply, 'ok');
  assert.deepEqual(settle(board), referencePulses('pose 0 0 5 0 0 0'));
  goodCommandWorks(board, held);
});

test('CR, LF, CRLF and LF CR each end exactly one line', () => {
  const board = bootedAndPulsing();
  const held = steadyPulses(board);
  const from = board.lines.length;
  const cases = [
    ['pose 0 0 2 0 0 0', '\r'],
    ['pose 0 0 4 0 0 0', '\n'],
    ['pose 0 0 6 0 0 0', '\r\n'],
    ['pose 0 0 8 0 0 0', '\n\r'], // two line ends: the second line is blank (no reply)
  ];
  cases.forEach(([line, end], i) => {
    board.sendBytes(line + end);
    board.runMs((line.length + end.length) * BYTE_MS + 50);
    assert.deepEqual(finalsFrom(board, from), Array(i + 1).fill('ok'), JSON.stringify(end));
    assert.deepEqual(
      settle(board),
      referencePulses(line),
      `${JSON.stringify(end)} did not run ${line}`,
    );
  });
  // All styles mixed back to back.
  const mixed = board.lines.length;
  board.sendBytes('frobnicate\rhome\nstatus\r\n?\n\r\r\n');
  board.runMs(100);
  const replies = finalsFrom(board, mixed);
  assert.equal(replies.length, 4, JSON.stringify(replies));
  assert.equal(codeOf(replies[0]), 'unknown-command');
  assert.deepEqual(replies.slice(1), ['ok', 'ok', 'ok']);
  assert.deepEqual(settle(board), held, 'home did not return to the power-on pulses');
  goodCommandWorks(board, held);
});

test('NUL bytes are ignored like other control bytes and move nothing on their own', () => {
  const board = bootedAndPulsing();
  const held = steadyPulses(board);
  const from = board.lines.length;
  board.sendBytes('\0\0\0\n\0\r\n');
  board.runMs(50);
  assert.deepEqual(finalsFrom(board, from), [], 'NUL-only lines are blank: no reply');
  const { reply } = board.request('po\0se 0 0 1e39\0 0 0 0');
  assert.equal(codeOf(reply), 'number-too-large');
  assert.equal(board.request('\0status\0').reply, 'ok');
  assert.deepEqual(steadyPulses(board), held);
  goodCommandWorks(board, held);
});

test('UTF-8 and other non-ASCII bytes refuse the line', () => {
  const board = bootedAndPulsing();
  const held = steadyPulses(board);
  for (const line of [
    'pose 0 0 5 0 0 0°',
    'pose ５ 0 0 0 0 0', // fullwidth digit
    'pose 0 0 5 0 0 0 🙂',
    'home\u00a0', // no-break space
  ]) {
    board.sendBytes(Buffer.from(`${line}\n`, 'utf8'));
    const reply = board.waitForLine(FINAL_REPLY);
    assert.equal(codeOf(reply), 'bad-character', `${line}: ${reply}`);
    assert.deepEqual(steadyPulses(board), held);
  }
  // A lone continuation byte and an overlong encoding.
  board.sendBytes(Buffer.from([0x68, 0x6f, 0x80, 0x6d, 0x65, 0x0a, 0xc0, 0xaf, 0x0a]));
  assert.equal(codeOf(board.waitForLine(FINAL_REPLY)), 'bad-character');
  assert.equal(codeOf(board.waitForLine(FINAL_REPLY)), 'bad-character');
  assert.deepEqual(steadyPulses(board), held);
  goodCommandWorks(board, held);
});

test('numbers that are not decimals are refused with the right code', () => {
  const board = bootedAndPulsing();
  const held = steadyPulses(board);
  for (const [line, code] of [
    ['pose 1e39 0 0 0 0 0', 'number-too-large'],
    ['pose 0 0 -1e39 0 0 0', 'number-too-large'],
    ['nudge z=1e39', 'number-too-large'],
    ['pose 0 0 0 nan 0 0', 'not-finite'],
    ['pose 0 0 inf 0 0 0', 'not-finite'],
    ['move x=-infinity', 'not-finite'],
    ['set speed_mm_s NaN', 'not-finite'],
    ['pose 0x10 0 0 0 0 0', 'bad-number'],
    ['move z=0x10', 'bad-number'],
    ['set servo1.trim_us 0x5dc', 'bad-number'],
    ['pose 1_0 0 0 0 0 0', 'bad-number'],
    ['pose 0 0 1e 0 0 0', 'bad-number'],
    ['pose 0 0 --1 0 0 0', 'bad-number'],
    ['set frame_hz 1e39', 'number-too-large'],
    ['set frame_hz 50.5', 'bad-value'],
  ]) {
    const { reply } = board.request(line);
    assert.equal(codeOf(reply), code, `${line}: ${reply}`);
    assert.deepEqual(steadyPulses(board), held, line);
  }
  // Negative zero is zero: home, exactly.
  assert.equal(board.request('pose -0 -0 -0 -0 -0 -0').reply, 'ok');
  assert.equal(board.request('move x=-0 roll=-0.0e5').reply, 'ok');
  assert.deepEqual(steadyPulses(board, 5), held);
  goodCommandWorks(board, held);
});
