// The Pico's USB port as a serial port (docs/commands.md), through the real firmware ELF
// and a USB host on the emulated chip's USB controller (src/gaps/usb.js, gaps 9-12): it
// enumerates as a CDC ACM device, speaks the protocol of UART0 beside UART0 (each link its own
// line, echo and prompt; replies to the asking link, notices to every open link), never loses
// input, greets each opening of the port, and neither a closed port, an unplugged cable nor a
// host that stops reading holds up UART0, the servo frames or the main loop. The every-command
// checks run over USB too (commands.test.js, errors.test.js).

import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { before, test } from 'node:test';

import { BANNER, EmulatedBoard, FINAL_REPLY } from '../src/chip/board.js';
import {
  assertPins,
  bootQuietUsb,
  defaultSettings,
  firmwareBootrom,
  FRAME_MS,
  ok,
} from '../src/test-support/e2e-support.js';
import { HostReference } from '../src/test-support/host-reference.js';

/** The documented bound on a main-loop pass: 1 ms at 125 MHz (main-loop.test.js). */
const PASS_BOUND_CYCLES = 125_000;
/** The firmware's USB receive queue holds fewer bytes than this (docs/commands.md). */
const RX_QUEUE_BYTES = 1024;
/** A UART framing error on a received byte (PL011 UARTDR bit 8; src/gaps/uart.js, gap 2). */
const UART_FRAMING_ERROR = 1 << 8;

// USB 2.0 chapter 9 and the CDC 1.2 / PSTN 1.2 class codes.
const DESCRIPTOR_DEVICE = 1;
const DESCRIPTOR_STRING = 3;
const DESCRIPTOR_INTERFACE = 4;
const DESCRIPTOR_ENDPOINT = 5;
const CLASS_CDC = 0x02;
const SUBCLASS_ACM = 0x02;
const CLASS_CDC_DATA = 0x0a;
const ENDPOINT_BULK = 2;
const LANG_EN_US = 0x0409;

let bootrom;
let reference;
before(() => {
  bootrom = firmwareBootrom();
  reference = new HostReference();
});

/** A board with a USB host that has opened the port and read its banner; echo on both links. */
function bothLinks() {
  const board = new EmulatedBoard({ bootrom, usb: true });
  board.boot();
  // UART0's power-up, all of it (at 115,200 baud it may end after the USB banner).
  board.waitForLine(/^# warning: no settings saved in flash/);
  board.usb.waitUntilOpen();
  board.usb.waitForLine(BANNER);
  board.runMs(2);
  return board;
}

/** The final replies on `link` from line index `from` on. */
function finals(link, from) {
  return link.lines.slice(from).filter((line) => FINAL_REPLY.test(line));
}

/** Starts measuring main-loop passes and frames. */
function measure(board) {
  board.loop.reset();
  board.frames.reset();
}

/** No pass over the bound, no handler over a tenth of it, no frame missed since `measure`. */
function assertNoStall(board, what) {
  const { longestPassCycles, longestHandlerCycles } = board.loop;
  const { frames, missed } = board.frames;
  assert.ok(longestPassCycles < PASS_BOUND_CYCLES, `${what}: a ${longestPassCycles}-cycle pass`);
  assert.ok(
    longestHandlerCycles < PASS_BOUND_CYCLES / 10,
    `${what}: a handler took ${longestHandlerCycles} cycles`,
  );
  assert.ok(frames > 0, `${what}: no frames seen`);
  assert.equal(missed, 0, `${what}: ${missed} of ${frames} frames missed`);
}

/** The descriptors in a configuration descriptor: [{ type, bytes }]. */
function descriptors(bytes) {
  const list = [];
  for (let i = 0; i + 2 <= bytes.length && bytes[i] >= 2; i += bytes[i]) {
    list.push({ type: bytes[i + 1], bytes: bytes.slice(i, i + bytes[i]) });
  }
  return list;
}

test('the USB port enumerates as a CDC ACM serial port named as the firmware', () => {
  const board = new EmulatedBoard({ bootrom, usb: true });
  board.boot();
  board.usb.waitUntilOpen();
  assert.equal(board.usb.host.enumerations, 1);

  const device = board.usb.readDescriptor(DESCRIPTOR_DEVICE, 0);
  assert.equal(device[4], CLASS_CDC, 'device class CDC');
  assert.equal(device[7], 64, 'endpoint 0 max packet size 64');
  const string = (index) => {
    assert.ok(index > 0, 'no string');
    const bytes = board.usb.readDescriptor(DESCRIPTOR_STRING, index, { langId: LANG_EN_US });
    return Buffer.from(bytes.slice(2, bytes[0])).toString('utf16le');
  };
  const replies = readFileSync(
    new URL('../../control/src/report/replies.rs', import.meta.url),
    'utf8',
  );
  const named = (name) => replies.match(new RegExp(`pub const ${name}: &str = "([^"]+)";`))[1];
  assert.equal(string(device[14]), named('USB_MANUFACTURER'));
  assert.equal(string(device[15]), named('USB_PRODUCT'));
  // The IDs the host tool finds boards by (`hexapod boards`), little-endian at offsets 8 and 10.
  const id = (name) =>
    Number(replies.match(new RegExp(`pub const ${name}: u16 = (0x[0-9A-Fa-f]+);`))[1]);
  assert.equal(device[8] | (device[9] << 8), id('USB_VID'));
  assert.equal(device[10] | (device[11] << 8), id('USB_PID'));

  // A communication interface of the ACM subclass, and a data interface with a bulk IN and a
  // bulk OUT endpoint of 64 bytes: what /dev/ttyACM0 and COMx drivers bind to.
  const list = descriptors(board.usb.configurationDescriptor);
  const interfaces = list.filter((d) => d.type === DESCRIPTOR_INTERFACE).map((d) => d.bytes);
  assert.ok(
    interfaces.some((i) => i[5] === CLASS_CDC && i[6] === SUBCLASS_ACM),
    'ACM',
  );
  const data = list.findIndex(
    (d) => d.type === DESCRIPTOR_INTERFACE && d.bytes[5] === CLASS_CDC_DATA,
  );
  assert.ok(data >= 0, 'a CDC data interface');
  const endpoints = list.slice(data + 1, data + 3).map((d) => d.bytes);
  assert.deepEqual(
    endpoints.map((e) => e[1]),
    [DESCRIPTOR_ENDPOINT, DESCRIPTOR_ENDPOINT],
  );
  assert.deepEqual(
    endpoints.map((e) => e[3] & 3),
    [ENDPOINT_BULK, ENDPOINT_BULK],
  );
  assert.deepEqual(
    endpoints.map((e) => e[4] | (e[5] << 8)),
    [64, 64],
  );
  assert.deepEqual(endpoints.map((e) => e[2] & 0x80).sort(), [0, 0x80], 'one IN, one OUT');
});

test('opening the port shows the banner and a prompt, echo on; UART0 is not told', () => {
  const board = new EmulatedBoard({ bootrom, usb: true });
  board.boot();
  board.waitForLine(/^# warning: no settings saved in flash/); // UART0's power-up, all of it
  const uartLines = board.lines.length;
  board.usb.waitUntilOpen();
  board.runMs(5);
  // The banner, then the notices this link has not been shown: a new board's flash holds no
  // settings, which power-up told UART0 (docs/settings.md, "Saving the settings").
  assert.deepEqual(board.usb.lines.slice(1), [
    '# warning: no settings saved in flash; using the defaults',
  ]);
  assert.match(board.usb.lines[0], BANNER);
  assert.equal(board.usb.partialLine, '> ');
  // Echo: what is typed comes back, then the reply, then a prompt.
  board.usb.sendBytes('statux\x7fs\r');
  board.usb.waitForLine(/^ok$/);
  board.runMs(2);
  const echoed = '> statux\x08 \x08s\r\n# state: idle\r\n';
  assert.ok(board.usb.output.includes(echoed), JSON.stringify(board.usb.output));
  assert.ok(board.usb.output.endsWith('ok\r\n> '));
  assert.equal(board.lines.length, uartLines, 'nothing on UART0');
});

test('UART0 and USB at once: each its own lines; replies to the asker, notices to both', () => {
  const board = bothLinks();
  const [uartFrom, usbFrom] = [board.lines.length, board.usb.lines.length];
  // Interleaved byte by byte on the two links, ending together.
  const uartLine = 'status\n';
  const usbLine = 'geometry\n';
  for (let i = 0; i < Math.max(uartLine.length, usbLine.length); i++) {
    board.uart.sendBytes(uartLine.slice(i, i + 1));
    board.usb.sendBytes(usbLine.slice(i, i + 1));
    board.runMs(0.1);
  }
  board.waitForLine(/^ok$/);
  board.usb.waitForLine(/^ok$/);
  const uartText = board.lines.slice(uartFrom).join('\n');
  const usbText = board.usb.lines.slice(usbFrom).join('\n');
  assert.match(uartText, /^> status\n# state: idle\n/);
  assert.doesNotMatch(uartText, /home_height_mm/);
  assert.match(usbText, /^> geometry\n# layout: /);
  assert.match(usbText, /# home_height_mm \(h0\): 118\.458\n/);
  assert.doesNotMatch(usbText, /# state:/);

  // Echo is each link's own.
  assert.equal(board.usb.request('set echo off').reply, 'ok');
  const uartBefore = board.outputBytes.length;
  board.sendLine('help');
  board.waitForLine(/^ok$/);
  board.runMs(2);
  assert.ok(board.uart.output.slice(uartBefore).startsWith('help\r\n'), 'UART0 still echoes');
  assert.ok(board.uart.output.endsWith('ok\r\n> '), 'and prompts');

  // Notices: a UART receive error (a byte with a framing error) reaches both links at once;
  // the UART0 line it cut is refused on UART0 alone (a line end closes it, as documented).
  board.mcu.uart[0].feedByte(0x41 | UART_FRAMING_ERROR);
  const warning = /^# warning: UART receive error, input lost \(at least 1 byte\)$/;
  board.usb.waitForLine(warning, { timeoutMs: 5 });
  board.waitForLine(warning, { timeoutMs: 50 }); // 70 bytes at 115,200 baud
  board.sendLine('');
  assert.match(board.waitForLine(FINAL_REPLY), /^error:rx-overflow /);
  // Link loss, set from USB, after a move from UART0: both links hear it.
  assert.equal(board.usb.request('set link_timeout_s 0.2').reply, 'ok');
  assert.equal(board.request('pose 0 0 3 0 0 0').reply, 'ok');
  const lost = /^# link lost: no command for 0\.2 s; returning home$/;
  board.waitForLine(lost, { timeoutMs: 1000 });
  board.usb.waitForLine(lost, { timeoutMs: 5 });
  board.runMs(20);
  assert.deepEqual(
    finals(board.usb, usbFrom),
    ['ok', 'ok', 'ok'],
    "USB: geometry, set echo off, set link_timeout_s; nothing of UART0's",
  );
});

test('a burst far larger than the receive queue comes whole, in order, every line answered', () => {
  const board = bootQuietUsb(bootrom);
  ok(board, 'set speed_mm_s off');
  ok(board, 'set speed_deg_s off');
  // Refusals that quote their line's own word, and jumps, alternately: the replies show the
  // order; 900 lines of about 12 bytes, ten times the queue.
  const lines = Array.from({ length: 900 }, (_, i) =>
    i % 2 ? `pose 0 0 ${(i % 9) - 4} 0 0 ${i % 5}` : `frob${i}`,
  );
  const bytes = lines.reduce((n, line) => n + line.length + 1, 0);
  assert.ok(bytes > 10 * RX_QUEUE_BYTES, `${bytes} bytes`);
  const from = board.lines.length;
  measure(board);
  board.sendBytes(lines.map((line) => `${line}\n`).join(''));
  const answered = () => finals(board.usb, from).length >= lines.length;
  assert.ok(board.runUntil(answered, { timeoutMs: 5000 }));
  board.runMs(50);
  const replies = finals(board.usb, from);
  assert.equal(replies.length, lines.length, 'one final reply per line, no more');
  replies.forEach((reply, i) => {
    const expected = i % 2 ? 'ok' : `error:unknown-command 'frob${i}' is not a command; type help`;
    assert.equal(reply, expected, `line ${i}: ${lines[i]}`);
  });
  const warnings = board.lines.slice(from).filter((line) => line.startsWith('# warning'));
  assert.deepEqual(warnings, [], 'nothing lost, nothing to warn of');
  assert.equal(board.usb.unsent, 0);
  assertNoStall(board, 'a USB burst');
  // The pins hold the last pose's pulses (the host core's).
  const last = lines.at(-1).split(' ').slice(1).map(Number);
  const [expected] = reference.solve(defaultSettings(), [last]);
  board.runMs(2 * FRAME_MS);
  assertPins(board, expected.pulse_us, `after ${lines.at(-1)}`);
});

test('closing the port drops its output and abandons its line; opening it greets afresh', () => {
  const board = bothLinks();
  assert.equal(board.usb.request('set echo off').reply, 'ok');
  board.usb.sendBytes('pose 0 0 5');
  board.runMs(5);
  board.usb.close();
  board.runMs(5);
  assert.equal(board.usb.isOpen, false);
  const closedAt = board.usb.outputBytes.length;
  // While closed: a notice comes (a UART receive error), UART0 works, the platform moves.
  board.mcu.uart[0].feedByte(0x42 | UART_FRAMING_ERROR);
  board.waitForLine(/^# warning: UART receive error/);
  board.sendLine(''); // closes the line the error cut, which is refused
  assert.match(board.waitForLine(FINAL_REPLY), /^error:rx-overflow /);
  assert.equal(board.request('pose 0 0 2 0 0 0').reply, 'ok');
  board.runMs(200);
  assert.equal(board.usb.outputBytes.length, closedAt, 'nothing sent to a closed port');

  board.usb.open();
  board.usb.waitUntilOpen();
  assert.match(board.usb.waitForLine(BANNER), BANNER);
  // The notice that came while it was closed, once, then a prompt: echo is on again.
  assert.match(board.usb.waitForLine(/^# /), /^# warning: UART receive error, input lost/);
  board.runMs(5);
  assert.equal(board.usb.partialLine, '> ');
  // The line typed before closing was abandoned: " 0 0 0" alone is no command.
  board.usb.sendBytes(' 0 0 0\r');
  const refusal = "error:unknown-command '0' is not a command; type help";
  assert.equal(board.usb.waitForLine(FINAL_REPLY), refusal);
  board.runMs(2);
  assert.ok(board.usb.output.endsWith(` 0 0 0\r\n${refusal}\r\n> `));
  // Closed and opened again and again, the last times at once while a long check keeps the
  // main loop busy on UART0 (both requests answered within one of its passes): each opening
  // gets one banner.
  for (let i = 0; i < 3; i++) {
    board.usb.close();
    board.runMs(3);
    board.usb.open();
    board.usb.waitForLine(BANNER);
  }
  assert.equal(board.request('set speed_mm_s 1').reply, 'ok');
  for (let i = 0; i < 3; i++) {
    board.sendLine('check 20 0 0 0 0 0');
    board.runMs(10);
    board.usb.close();
    board.usb.open();
    board.usb.waitForLine(BANNER);
    board.waitForLine(FINAL_REPLY, { timeoutMs: 1000 });
  }
  board.runMs(5);
  assert.equal(board.usb.lines.filter((line) => BANNER.test(line)).length, 1 + 1 + 3 + 3);
  assert.equal(board.usb.request('status').reply, 'ok');
});

test('unplugging and plugging in again: UART0 and the frames go on, the port comes back', () => {
  const board = bothLinks();
  measure(board);
  assert.equal(board.request('set speed_mm_s 1').reply, 'ok');
  // A long listing and a long check under way on USB when the cable is pulled.
  board.usb.sendLine('help');
  board.usb.sendLine('check 20 0 0 0 0 0');
  board.runMs(3);
  board.usb.unplug();
  board.runMs(50);
  assert.equal(board.request('pose 0 0 4 0 0 0').reply, 'ok');
  board.runMs(500);
  const state = board.request('status').lines.find((l) => l.startsWith('# state:'));
  assert.match(state, /^# state: moving /);
  assertNoStall(board, 'unplugged');

  const before = board.usb.lines.length;
  board.usb.replug();
  board.usb.waitUntilOpen({ timeoutMs: 200 });
  assert.equal(board.usb.host.enumerations, 2);
  board.usb.waitForLine(BANNER);
  // A new session: the banner first, nothing left over from the work cut off by the unplug.
  assert.match(board.usb.lines[before], BANNER, JSON.stringify(board.usb.lines.slice(before - 2)));
  const { reply, lines } = board.usb.request('status');
  assert.equal(reply, 'ok');
  assert.ok(
    lines.some((l) => /^# state: moving /.test(l)),
    JSON.stringify(lines),
  );
  assert.equal(board.request('stop').reply, 'ok');
  assertNoStall(board, 'unplugged and back');
});

test('a host that stops reading holds up neither UART0, nor the frames, nor its own input', () => {
  const board = bothLinks();
  assert.equal(board.usb.request('set echo off').reply, 'ok');
  measure(board);
  board.usb.stopReading();
  // Far more output than any buffer holds: 40 help listings (about 70 KB).
  for (let i = 0; i < 40; i++) {
    board.usb.sendLine('help');
  }
  board.runMs(20);
  // UART0 is served meanwhile, and moves the platform.
  for (const z of [3, -3, 0]) {
    assert.equal(board.request(`pose 0 0 ${z} 0 0 0`, { timeoutMs: 1000 }).reply, 'ok');
  }
  board.runMs(500);
  const [home] = reference.solve(defaultSettings(), [[0, 0, 0, 0, 0, 0]]);
  assertPins(board, home.pulse_us, 'UART0 moved it');
  // The USB host's lines were all taken (and run) although their output had nowhere to go.
  const allTaken = board.runUntil(() => board.usb.unsent === 0, { timeoutMs: 2000 });
  assert.ok(allTaken, `${board.usb.unsent} bytes not taken`);
  assertNoStall(board, 'a host that does not read');

  // Reading again: what was held comes, and the link answers again.
  board.usb.startReading();
  board.runMs(50);
  const reply = board.usb.request('frob', { final: /^error:unknown-command 'frob'/ });
  assert.match(reply.reply, /^error:unknown-command 'frob' is not a command/);
  assert.equal(board.request('status').reply, 'ok');
});

test("baud is UART0's: set on USB it switches UART0, and USB goes on as before", () => {
  const board = bothLinks();
  const { reply, lines } = board.usb.request('set baud 230400');
  assert.equal(reply, 'ok');
  assert.equal(lines.at(-1), 'ok');
  board.runMs(5);
  assert.equal(board.usb.partialLine, '> ', 'the USB prompt does not wait for UART0');
  assert.ok(Math.abs(board.baud - 230400) / 230400 < 0.02, `UART0 at ${board.baud}`);
  assert.equal(board.request('status').reply, 'ok', 'UART0 talks at the new rate');
  const config = board.usb.request('config').lines;
  assert.ok(config.includes('# baud: 230400'), JSON.stringify(config));
  assert.ok(config.includes('# echo: on'), "the USB link's own echo");
  assert.equal(board.usb.request('set echo off').reply, 'ok');
  assert.ok(board.request('config').lines.includes('# echo: on'), 'UART0 keeps its echo');
  // A terminal opening the USB port at some rate (SET_LINE_CODING) changes nothing: UART0
  // stays where `set baud` put it, and the USB link goes on at its own pace.
  for (const rate of [9600, 921600]) {
    board.usb.setLineCoding(rate);
    board.runMs(2);
    assert.ok(Math.abs(board.baud - 230400) / 230400 < 0.02, `UART0 at ${board.baud}`);
    assert.ok(board.usb.request('config').lines.includes('# baud: 230400'));
  }
  assert.equal(board.request('status').reply, 'ok');
});
