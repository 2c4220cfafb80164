// Timing of the real firmware in the emulator (emulated time): command-to-output latency,
// sustained pose lines per second, the worst-case command against the watchdog.

import { BANNER, EmulatedBoard } from '../chip/board.js';

const RAM_START = 0x20000000;

const CHANNEL_BYTES = 0x14; // one PWM slice's registers
const CHANNEL_CC = 0x0c; // compare values (channel A low half, B high half)
const SERVO_SLICES = [1, 2, 3]; // servo 1..6 = slices 1..3, channels A and B
const LF = 0x0a;

/** Time-stamps the emulator's PWM compare-register writes: `[{ nanos, slice, value }]`. */
function recordCompareWrites(board) {
  const ccWrites = [];
  const pwm = board.mcu.pwm;
  const writeRegister = pwm.writeUint32.bind(pwm);
  pwm.writeUint32 = (offset, value) => {
    const slice = Math.floor(offset / CHANNEL_BYTES);
    if (offset < 8 * CHANNEL_BYTES && offset % CHANNEL_BYTES === CHANNEL_CC) {
      ccWrites.push({ nanos: board.nanos, slice, value: value >>> 0 });
    }
    writeRegister(offset, value);
  };
  return ccWrites;
}

/**
 * The real firmware, booted, echo off, speed limits off (jumps), at `baud`, with the
 * emulator's PWM compare-register writes and UART RX deliveries time-stamped. `link` is UART0
 * (`board.uart`).
 */
/**
 * @param {object} [options]
 * @param {number} [options.baud]
 * @param {string} [options.elf] firmware ELF (default: the board's)
 * @param {'typical'|'max'} [options.flashTiming] (default: the board's)
 */
export function streamingBoard({ baud = 115200, elf, flashTiming } = {}) {
  const board = new EmulatedBoard({
    ...(elf ? { elf } : {}),
    ...(flashTiming ? { flashTiming } : {}),
  });
  const ccWrites = recordCompareWrites(board);
  const lineEnds = [];
  /** When each byte reached the UART (emulated ns), in order. */
  const byteTimes = [];
  const uart = board.mcu.uart[0];
  const feedByte = uart.feedByte.bind(uart);
  uart.feedByte = (byte) => {
    if (byte === LF) {
      lineEnds.push(board.nanos);
    }
    byteTimes.push(board.nanos);
    feedByte(byte);
  };
  board.boot();
  for (const line of ['set echo off', 'set speed_mm_s off', 'set speed_deg_s off']) {
    expectOk(board, line);
  }
  if (baud !== 115200) {
    expectOk(board, `set baud ${baud}`);
    board.runMs(5); // the reply goes out at the old rate, then the UART switches
  }
  return { board, link: board.uart, ccWrites, lineEnds, byteTimes };
}

/**
 * The same over USB: a USB host plugged in at power-on has opened the port; echo off there,
 * speed limits off. `lineEnds` are the instants the OUT packets carrying a line end reached
 * the firmware's endpoint buffer (the end of their bus slot, gaps/usb.js, gap 11).
 */
/** @param {{ elf?: string }} [options] */
export function usbStreamingBoard({ elf } = {}) {
  const board = new EmulatedBoard({ ...(elf ? { elf } : {}), usb: true });
  const ccWrites = recordCompareWrites(board);
  const lineEnds = [];
  board.usb.host.onOutDelivered = (bytes, nanos) => {
    if (bytes.includes(LF)) {
      lineEnds.push(nanos);
    }
  };
  board.boot();
  board.usb.waitUntilOpen();
  board.usb.waitForLine(BANNER);
  for (const line of ['set echo off', 'set speed_mm_s off', 'set speed_deg_s off']) {
    expectOk(board.usb, line);
  }
  return { board, link: board.usb, ccWrites, lineEnds };
}

/** Sends `line` on `link` (a board is UART0's link too) and expects `ok`. */
function expectOk(link, line, options) {
  const { reply } = link.request(line, options);
  if (reply !== 'ok') {
    throw new Error(`${line}: ${reply}`);
  }
}

/** The compare registers of the servo slices as they stand, `{ slice: value }`. */
function ccState(board) {
  return Object.fromEntries(
    SERVO_SLICES.map((slice) => [slice, board.mcu.pwm.channels[slice].readRegister(CHANNEL_CC)]),
  );
}

/**
 * Latency of `pose` lines: from the line's last byte (LF) reaching the UART (with `usb`: the
 * USB packet carrying it reaching the firmware's endpoint buffer) to the moment the compare
 * registers all hold the new pose's values (they latch at the next PWM period). Starts at pose
 * `from` (mm, degrees as typed; default home). Returns microseconds per pose.
 */
/**
 * @param {string[]} poses
 * @param {{ baud?: number, from?: string, elf?: string, usb?: boolean }} [options]
 */
export function measureLatency(poses, { baud = 115200, from, elf, usb = false } = {}) {
  const { board, link, ccWrites, lineEnds } = usb
    ? usbStreamingBoard({ elf })
    : streamingBoard({ baud, elf });
  if (from) {
    expectOk(link, `pose ${from}`); // where the measured lines start from (not measured)
  }
  const latenciesUs = [];
  for (const [i, pose] of poses.entries()) {
    // Lines land at spread-out phases of the 20 ms servo frame (a frame may coincide).
    board.runMs((i * 7.3) % 20);
    const before = ccState(board);
    const writesBefore = ccWrites.length;
    expectOk(link, `pose ${pose}`);
    const lineEnd = lineEnds[lineEnds.length - 1];
    board.runMs(1);
    const final = ccState(board);
    if (SERVO_SLICES.every((s) => final[s] === before[s])) {
      throw new Error(`pose ${pose} did not change the compare registers`);
    }
    // Replay the writes since the line ended: when did the registers first all hold `final`?
    const state = { ...before };
    let doneNanos = null;
    for (const write of ccWrites.slice(writesBefore)) {
      state[write.slice] = write.value;
      if (write.nanos >= lineEnd && SERVO_SLICES.every((s) => state[s] === final[s])) {
        doneNanos = write.nanos;
        break;
      }
    }
    if (doneNanos === null) {
      throw new Error(`pose ${pose}: new compare values not seen`);
    }
    latenciesUs.push((doneNanos - lineEnd) / 1000);
  }
  return latenciesUs;
}

/** A binary stream frame (`A5 5A`, six big-endian 16-bit counts, `0D 0A`). */
export function binaryFrame(counts) {
  const bytes = [0xa5, 0x5a];
  for (const c of counts) {
    bytes.push((c >> 8) & 0xff, c & 0xff);
  }
  bytes.push(0x0d, 0x0a);
  return Buffer.from(bytes);
}

/**
 * Latency of binary stream frames in pass-through (every limit off): from the frame's last
 * byte reaching the UART to the moment the compare registers all hold the new pose's values.
 * `counts` is a list of frames (six counts each), sent one at a time at spread-out phases of
 * the servo frame. Returns microseconds per frame.
 */
export function measureFrameLatency(frames, { baud = 921600 } = {}) {
  const { board, ccWrites, byteTimes } = streamingBoard({ baud });
  const latenciesUs = [];
  for (const [i, counts] of frames.entries()) {
    board.runMs((i * 7.3) % 20);
    const before = ccState(board);
    const writesBefore = ccWrites.length;
    const frame = binaryFrame(counts);
    // The frame's last byte (counts may hold 0x0A bytes too: count bytes, not line ends).
    const last = byteTimes.length + frame.length - 1;
    board.sendBytes(frame);
    board.runUntil(() => byteTimes.length > last, { timeoutMs: 100 });
    const frameEnd = byteTimes[last];
    board.runMs(2);
    const final = ccState(board);
    if (SERVO_SLICES.every((s) => final[s] === before[s])) {
      throw new Error(`frame ${counts} did not change the compare registers`);
    }
    const state = { ...before };
    let doneNanos = null;
    for (const write of ccWrites.slice(writesBefore)) {
      state[write.slice] = write.value;
      if (write.nanos >= frameEnd && SERVO_SLICES.every((s) => state[s] === final[s])) {
        doneNanos = write.nanos;
        break;
      }
    }
    if (doneNanos === null) {
      throw new Error(`frame ${counts}: new compare values not seen`);
    }
    latenciesUs.push((doneNanos - frameEnd) / 1000);
  }
  return latenciesUs;
}

/**
 * Streams `lines` at `baud`, `linesPerSecond` evenly spaced (`Infinity`: back to back, as fast
 * as the wire allows), without waiting for replies, and counts the replies.
 * Returns { lines, ok, errors, droppedBytes, seconds, linesPerSecond, wireLinesPerSecond }.
 */
export function measureStream(lines, { baud = 921600, linesPerSecond = Infinity } = {}) {
  const { board } = streamingBoard({ baud });
  const first = board.lines.length;
  const startNanos = board.nanos;
  const bytes = lines.reduce((n, line) => n + line.length + 1, 0);
  const wireSeconds = (bytes * 10) / baud;
  if (Number.isFinite(linesPerSecond)) {
    const periodNanos = 1e9 / linesPerSecond;
    for (const [i, line] of lines.entries()) {
      board.runUntil(() => board.nanos >= startNanos + i * periodNanos, { timeoutMs: 1000 });
      board.sendLine(line);
    }
  } else {
    board.sendBytes(lines.map((line) => `${line}\n`).join(''));
  }
  const replies = () => board.lines.length - first;
  board.runUntil(() => replies() >= lines.length, { timeoutMs: 2000 });
  const seconds = (board.nanos - startNanos) / 1e9;
  const got = board.lines.slice(first);
  const ok = got.filter((line) => line === 'ok').length;
  return {
    lines: lines.length,
    ok,
    errors: got.filter((line) => line !== 'ok').slice(0, 3),
    droppedBytes: board.rxFifoDroppedBytes,
    seconds,
    linesPerSecond: ok / seconds,
    wireLinesPerSecond: lines.length / wireSeconds,
  };
}

/**
 * Over USB: the host sends `lines` at `linesPerSecond` (`Infinity`: all at once, as fast as the
 * firmware takes them), without waiting for replies; USB's flow control holds back what the
 * firmware cannot take yet, so nothing is lost and every line must get `ok`. Returns
 * { lines, ok, errors, seconds, linesPerSecond }, the rate being lines answered per second
 * from the first line sent to the last reply.
 */
export function measureUsbStream(lines, { linesPerSecond = Infinity } = {}) {
  const { board, link } = usbStreamingBoard();
  const first = link.lines.length;
  const startNanos = board.nanos;
  if (Number.isFinite(linesPerSecond)) {
    const periodNanos = 1e9 / linesPerSecond;
    for (const [i, line] of lines.entries()) {
      board.runUntil(() => board.nanos >= startNanos + i * periodNanos, { timeoutMs: 1000 });
      link.sendLine(line);
    }
  } else {
    link.sendBytes(lines.map((line) => `${line}\n`).join(''));
  }
  const replies = () => link.lines.length - first;
  board.runUntil(() => replies() >= lines.length, { timeoutMs: 5000 });
  const seconds = (board.nanos - startNanos) / 1e9;
  const got = link.lines.slice(first);
  const ok = got.filter((line) => line === 'ok').length;
  return {
    lines: lines.length,
    ok,
    errors: got.filter((line) => line !== 'ok').slice(0, 3),
    seconds,
    linesPerSecond: ok / seconds,
  };
}

/**
 * Sends each line when the previous reply has arrived (a host that waits for `ok`), on UART0
 * at `baud`, or with `usb` over the USB port.
 */
export function measureLockStep(lines, { baud = 921600, usb = false } = {}) {
  const { board, link } = usb ? usbStreamingBoard() : streamingBoard({ baud });
  const startNanos = board.nanos;
  const startCycles = board.cycles;
  let ok = 0;
  for (const line of lines) {
    if (link.request(line).reply === 'ok') {
      ok++;
    }
  }
  const seconds = (board.nanos - startNanos) / 1e9;
  // The CPU's cycles per line (asleep in WFI costs none): the line's whole cost on the chip,
  // its bytes' interrupts, parse, checks, IK, reply.
  const cyclesPerLine = (board.cycles - startCycles) / lines.length;
  return { lines: lines.length, ok, seconds, linesPerSecond: ok / seconds, cyclesPerLine };
}

/**
 * The longest command: a move whose path check solves the IK for the most poses (one per
 * frame of a 1024-frame move, the budget), timed from its line end to its reply, with the
 * longest main-loop pass and the frames missed meanwhile.
 * Returns { checks, micros, cycles, longestPassCycles, frames, missed }.
 */
export function measureWorstCommand() {
  const { board, lineEnds } = streamingBoard();
  expectOk(board, 'pose 0 0 -10 0 0 0');
  board.runMs(50);
  // 20.48 mm at 1 mm/s and 50 Hz: 1024 frames, each checked.
  expectOk(board, 'set speed_mm_s 1');
  board.loop.reset();
  board.frames.reset();
  const cyclesBefore = board.cycles;
  const { reply } = board.request('pose 0 0 10.48 0 0 0', { timeoutMs: 2000 });
  if (reply !== 'ok') {
    throw new Error(`worst-case move refused: ${reply}`);
  }
  const replyNanos = board.nanos;
  return {
    checks: 1024,
    micros: (replyNanos - lineEnds[lineEnds.length - 1]) / 1000,
    cycles: board.cycles - cyclesBefore,
    longestPassCycles: board.loop.longestPassCycles,
    frames: board.frames.frames,
    missed: board.frames.missed,
    board,
  };
}

/**
 * One command through the wire on a board that ran `setup` first: from its line end to its
 * reply at the host, the CPU cycles meanwhile (the emulator does not count sleep), the longest
 * main-loop pass and the frames missed. Returns { line, reply, micros, cycles,
 * longestPassCycles, frames, missed }.
 */
function measureCommand(setup, line, { frameHz = 50 } = {}) {
  const { board, lineEnds } = streamingBoard({ baud: 921600 });
  if (frameHz !== 50) {
    expectOk(board, `set frame_hz ${frameHz}`);
  }
  for (const l of setup) {
    expectOk(board, l, { timeoutMs: 5000 });
  }
  board.runMs(50);
  board.loop.reset();
  board.frames.reset();
  const cyclesBefore = board.cycles;
  const { reply } = board.request(line, { timeoutMs: 5000 });
  if (!reply.startsWith('ok')) {
    throw new Error(`${line}: ${reply}`);
  }
  const micros = (board.nanos - lineEnds[lineEnds.length - 1]) / 1000;
  const cycles = board.cycles - cyclesBefore;
  board.runMs(20);
  return {
    line,
    reply,
    micros,
    cycles,
    longestPassCycles: board.loop.longestPassCycles,
    frames: board.frames.frames,
    missed: board.frames.missed,
  };
}

/** A 2 kg payload 30 mm above the platform's centre, every servo rated `rating` kgf cm. */
const PAYLOAD = ['set payload_g 2000', 'set payload_com_z_mm 30'];

/**
 * `servo` (the pose of the pulses found: forward kinematics along a continuation, a Newton
 * iteration per pass), `status` after it, `limits` (a few IK solutions per pass, or one pose
 * with its holding torques), and path checks with torque ratings (one pose with its torques
 * per pass), each through the wire at 333 Hz. Returns a list of
 * { what, ...measureCommand }.
 */
export function measureKinematicsCommands() {
  const rated = (r) => [...PAYLOAD, `set servos.torque_kgcm ${r}`];
  // From z = -10 mm, 20.48 mm at 1 mm/s at 50 Hz: 1,024 frames, each checked (the budget).
  const longest = ['pose 0 0 -10 0 0 0', 'set speed_mm_s 1'];
  /** @type {[string, string[], string, number][]} */
  const cases = [
    [
      '`servo 3 1520` from home (2.2 degrees of arm: one continuation step)',
      [],
      'servo 3 1520',
      333,
    ],
    ['`servo 1 1900` from home (45 degrees: nine steps of 5 degrees)', [], 'servo 1 1900', 333],
    [
      '`status` after `servo 1 1900`, with a payload (the pose is known since `servo`; the holding torques take a pass of their own)',
      ['servo 1 1900', ...PAYLOAD],
      'status',
      333,
    ],
    ['`limits` from home, within the servo limits', [], 'limits', 333],
    [
      '`limits` from home with a payload and ratings of 1 kgf cm (each pose with its holding torques)',
      rated(1),
      'limits',
      333,
    ],
    [
      '`check 0 0 10.48 0 0 0` from z = -10 at 1 mm/s, 50 Hz: 1,024 checkpoints by the IK',
      longest,
      'check 0 0 10.48 0 0 0',
      50,
    ],
    [
      'the same with a payload and ratings of 2 kgf cm: each checkpoint with its holding torques (the longest command)',
      [...longest, ...rated(2)],
      'check 0 0 10.48 0 0 0',
      50,
    ],
  ];
  return cases.map(([what, setup, line, frameHz]) => ({
    what,
    ...measureCommand(setup, line, { frameHz }),
  }));
}

/**
 * Pass-through stream frames beyond the torque ratings at 921,600 baud, every one clamped (a
 * pose with its holding torques per pass): the longest main-loop pass meanwhile. Returns {
 * frames, clamped, longestPassCycles, missed, frameCount }.
 */
export function measureClampedStream() {
  const { board } = streamingBoard({ baud: 921600 });
  for (const l of [...PAYLOAD, 'set servos.torque_kgcm 1']) {
    expectOk(board, l);
  }
  board.runMs(20);
  board.loop.reset();
  board.frames.reset();
  const sent = 100;
  for (let i = 0; i < sent; i++) {
    // x from 5 to 25 mm: beyond what a 1 kgf cm rating holds with 2 kg (about 3 mm).
    board.sendBytes(
      binaryFrame([
        32768 + Math.round((0.2 + i * 0.008) * 32768),
        32768,
        32768,
        32768,
        32768,
        32768,
      ]),
    );
    board.runMs(2);
  }
  board.runMs(50);
  const { lines } = board.request('status');
  const counts = Object.fromEntries(
    lines
      .find((l) => l.startsWith('# stream: '))
      .slice('# stream: '.length)
      .split(' ')
      .map((kv) => kv.split('=').map((v, i) => (i ? Number(v) : v))),
  );
  return {
    sent,
    applied: counts.applied,
    clamped: counts.clamped,
    longestPassCycles: board.loop.longestPassCycles,
    frames: board.frames.frames,
    missed: board.frames.missed,
  };
}

/**
 * The longest main-loop pass and interrupt handler over a hostile session: every long command
 * class back to back at 333 Hz with echo on, then moves pipelined at 921,600 baud, each checked
 * at 1,000 poses, and a long reply draining at 9,600 baud. Returns { longestPassCycles,
 * longestHandlerCycles, frames, missed, lines }.
 */
export function measureLongestPass() {
  const board = new EmulatedBoard();
  board.boot();
  const lines = [
    'set frame_hz 333',
    'set speed_mm_s 1',
    'check 20 0 0 0 0 0',
    'config',
    'help',
    'geometry',
    'status',
    'set rod_mm 121',
    'set rod_mm 120',
    'defaults',
    'set frame_hz 333',
    'set speed_mm_s 1',
    'pose 20 0 0 0 0 0',
    'move x=-20',
    'pose 0 0 80 0 0 0',
    'set speed_mm_s off',
    'pose 0 0 0 0 0 0',
    'check 30 -12 -13.5 5 -13 28',
    'set speed_mm_s 1',
    'set echo off',
    'set baud 921600',
  ];
  board.runMs(20);
  board.loop.reset();
  board.frames.reset();
  let worst = { pass: 0, handler: 0, frames: 0, missed: 0 };
  const keep = () => {
    worst = {
      pass: Math.max(worst.pass, board.loop.longestPassCycles),
      handler: Math.max(worst.handler, board.loop.longestHandlerCycles),
      frames: worst.frames + board.frames.frames,
      missed: worst.missed + board.frames.missed,
    };
  };
  const replies = (from) => board.lines.slice(from).filter((l) => /^(ok|error:)/.test(l)).length;
  let from = board.lines.length;
  board.sendBytes(lines.map((l) => `${l}\n`).join(''));
  board.runUntil(() => replies(from) >= lines.length, { timeoutMs: 20_000 });
  board.runMs(10);
  keep();
  // The UART switched to 921,600 baud (the board follows the programmed rate).
  board.loop.reset();
  board.frames.reset();
  const moves = Array.from({ length: 20 }, (_, i) => `move x=${i % 2 ? '-10.1' : '-10.2'}`);
  from = board.lines.length;
  board.sendBytes(moves.map((l) => `${l}\n`).join(''));
  board.runUntil(() => replies(from) >= moves.length, { timeoutMs: 20_000 });
  board.runMs(50);
  keep();
  return {
    longestPassCycles: worst.pass,
    longestHandlerCycles: worst.handler,
    frames: worst.frames,
    missed: worst.missed,
    lines: lines.length + moves.length,
  };
}

/**
 * The longest main-loop pass while motion limits are busiest (issue 22's bound): at 333 Hz
 * with acceleration limits, a `nudge` every 50 ms (a person jogging) and then `pose` lines at
 * 60 Hz (a program), each a new target while moving; then the same with the servos' rated
 * speeds set (every move slowed to the ratings, its path measured); then a stream followed
 * by the tracker within the ratings. Returns { phases: [{ what, lines, ok, longestPassCycles,
 * frames, missed }] }.
 */
export function measureMotionLimitsPass() {
  const board = new EmulatedBoard();
  board.boot();
  for (const l of [
    'set echo off',
    'set frame_hz 333',
    'set speed_mm_s 100',
    'set speed_deg_s 60',
    'set accel_mm_s2 200',
    'set accel_deg_s2 120',
  ]) {
    expectOk(board, l);
  }
  const phases = [];
  /** Sends `lines` one every `everyMs` without waiting, then counts the replies. */
  const session = (what, lines, everyMs) => {
    board.runMs(100);
    board.loop.reset();
    board.frames.reset();
    const from = board.lines.length;
    for (const l of lines) {
      board.sendBytes(`${l}\n`);
      board.runMs(everyMs);
    }
    const replies = () => board.lines.slice(from).filter((l) => /^(ok|error:)/.test(l));
    board.runUntil(() => replies().length >= lines.length, { timeoutMs: 10_000 });
    board.runMs(20);
    phases.push({
      what,
      lines: lines.length,
      ok: replies().filter((l) => l === 'ok').length,
      longestPassCycles: board.loop.longestPassCycles,
      frames: board.frames.frames,
      missed: board.frames.missed,
    });
  };
  const nudges = Array.from({ length: 20 }, (_, i) => (i % 10 < 7 ? 'nudge x=2' : 'nudge yaw=-2'));
  const poseLines = Array.from({ length: 60 }, (_, i) => {
    const t = i / 60;
    const f = (v) => v.toFixed(2);
    return `pose ${f(8 * Math.sin(2 * Math.PI * t))} ${f(6 * Math.cos(2 * Math.PI * t))} ${f(3 * Math.sin(4 * Math.PI * t))} 0 ${f(4 * Math.sin(2 * Math.PI * t))} ${f(5 * Math.cos(2 * Math.PI * t))}`;
  });
  session('a `nudge` every 50 ms (20), acceleration limits', nudges, 50);
  session('`pose` lines at 60 Hz (60), acceleration limits', poseLines, 1000 / 60);
  expectOk(board, 'home');
  board.runMs(1000);
  expectOk(board, 'set servos.speed_s_60deg 0.1');
  expectOk(board, 'set servo4.speed_s_60deg 0.3');
  session('a `nudge` every 50 ms (20), acceleration limits and servo speed ratings', nudges, 50);
  session(
    '`pose` lines at 60 Hz (60), acceleration limits and servo speed ratings',
    poseLines,
    1000 / 60,
  );
  // A stream followed by the tracker within the ratings, its target jumping every 6 ms.
  board.runMs(2000);
  board.loop.reset();
  board.frames.reset();
  for (let i = 0; i < 60; i++) {
    const s = i % 2 === 0 ? 1 : -1;
    board.sendBytes(
      binaryFrame([
        32768 + s * 0.4 * 32768,
        32768 - s * 0.2 * 32768,
        32768,
        32768,
        32768,
        32768 + s * 0.3 * 32768,
      ]),
    );
    board.runMs(6);
  }
  board.runMs(100);
  phases.push({
    what: 'a stream (60 frames, every 6 ms) stepped by the tracker within the ratings',
    lines: 0,
    ok: 0,
    longestPassCycles: board.loop.longestPassCycles,
    frames: board.frames.frames,
    missed: board.frames.missed,
  });
  return { phases };
}

/**
 * A `save` with the flash model's `timing` ('typical' or 'max', gaps/flash.js, gap 7): its
 * one long main-loop pass (the sector erase and the page program in the boot ROM with
 * interrupts masked, and the firmware's own work in that pass), the time from its line end to
 * its `ok` at the host, and the frames the loop missed meanwhile (the PWM hardware held the
 * pulses). Returns { passCycles, flashCycles, replyMicros, frames, missed, longPasses, board }.
 */
/** @param {{ timing?: 'typical'|'max' }} [options] */
export function measureSave({ timing = 'typical' } = {}) {
  const { board, lineEnds } = streamingBoard({ flashTiming: timing });
  board.runMs(50);
  board.loop.reset();
  board.frames.reset();
  expectOk(board, 'save');
  const replyNanos = board.nanos;
  const lineEnd = lineEnds[lineEnds.length - 1];
  board.runMs(50);
  const { sectorEraseMs, pageProgramMs } = board.flash.times;
  const [pass] = board.loop.longPasses;
  if (!pass) {
    throw new Error('a save with no long pass');
  }
  return {
    passCycles: pass.cycles,
    flashCycles: Math.round((sectorEraseMs + pageProgramMs) * 1e-3 * 125e6),
    replyMicros: (replyNanos - lineEnd) / 1000,
    frames: board.frames.frames,
    missed: board.frames.missed,
    longPasses: board.loop.longPasses.length,
    times: board.flash.times,
    board,
  };
}

/**
 * The longest main-loop pass and interrupt handler with both links busy at once, at 333 Hz:
 * UART0 pipelining moves checked at 1,000 poses each at 921,600 baud while a USB host (echo on)
 * pipelines every long listing and checks of 1,000 poses. Returns { longestPassCycles,
 * longestHandlerCycles, frames, missed, lines }.
 */
export function measureLongestPassBothLinks() {
  const board = new EmulatedBoard({ usb: true });
  board.boot();
  board.usb.waitUntilOpen();
  board.usb.waitForLine(BANNER);
  for (const line of ['set frame_hz 333', 'set speed_mm_s 1', 'set echo off', 'set baud 921600']) {
    expectOk(board, line, { final: /^(ok|error:)/ });
  }
  board.runMs(5);
  board.loop.reset();
  board.frames.reset();
  const moves = Array.from({ length: 12 }, (_, i) => `move x=${i % 2 ? '-10.1' : '-10.2'}`);
  const usbLines = ['check 20 0 0 0 0 0', 'config', 'help', 'geometry', 'status'];
  const usbAll = [...usbLines, 'check -20 0 0 0 0 0', ...usbLines.slice(1)];
  const finals = (link, from) => link.lines.slice(from).filter((l) => /^(ok|error:)/.test(l));
  const [uartFrom, usbFrom] = [board.lines.length, board.usb.lines.length];
  board.sendBytes(moves.map((l) => `${l}\n`).join(''));
  board.usb.sendBytes(usbAll.map((l) => `${l}\r`).join(''));
  const done = () =>
    finals(board.uart, uartFrom).length >= moves.length &&
    finals(board.usb, usbFrom).length >= usbAll.length;
  if (!board.runUntil(done, { timeoutMs: 20_000 })) {
    throw new Error('both links: not every line was answered');
  }
  board.runMs(50);
  return {
    longestPassCycles: board.loop.longestPassCycles,
    longestHandlerCycles: board.loop.longestHandlerCycles,
    frames: board.frames.frames,
    missed: board.frames.missed,
    lines: moves.length + usbAll.length,
  };
}

/**
 * The stack's high-water mark so far, bytes: RAM starts zeroed, so the lowest non-zero word
 * between `stackEnd` (the end of the static data) and `stackStart` (the top) bounds how deep
 * the stack has reached (a lower bound: the deepest words might have been written as zero).
 */
export function stackHighWaterBytes(board, { stackEnd, stackStart }) {
  const sram = board.mcu.sram;
  for (let address = stackEnd; address < stackStart; address += 4) {
    const offset = address - RAM_START;
    if (sram[offset] | sram[offset + 1] | sram[offset + 2] | sram[offset + 3]) {
      return stackStart - address;
    }
  }
  return 0;
}
