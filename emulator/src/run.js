#!/usr/bin/env node
// Interactive runner: the firmware in the emulator, in (roughly) real time, with its USB
// serial port (or UART0) on your terminal or on a pseudo-terminal, the six measured servo
// pulse widths as a status line, and the live 3D view's web server (view-server.js) unless
// --no-view. Usually started with `./dev run [--uart] [--pty]`.

import { spawn } from 'node:child_process';
import { dirname, join } from 'node:path';
import { parseArgs } from 'node:util';
import { fileURLToPath } from 'node:url';

import { DEFAULT_ELF, EmulatedBoard } from './chip/board.js';
import { loadBootrom } from './chip/bootrom.js';
import { SharedInput } from './view-server/shared-input.js';
import { DEFAULT_VIEW_PORT, startViewServer } from './view-server/view-server.js';

const USAGE = `usage: ./dev run [--uart] [--pty] [--local-echo] [--no-view] [--view-port N] [--elf PATH]
                 [--no-xip-cache]

Runs the firmware in the emulator with a USB cable in the Pico's USB port and this terminal
on the serial port it brings (as picocom /dev/ttyACM0 would be, in raw mode): the port opens
at once and the board greets it. Enter sends LF. The firmware echoes what you type; if its
echo is off, --local-echo shows typed characters here. Ctrl-] or Ctrl-C quits.
  --uart     this terminal on UART0 (GP0/GP1, 115200 baud) instead, no USB cable
  --pty      put the port on a pseudo-terminal instead and print its path, for picocom,
             screen or a host program (e.g. picocom --omap crlf /dev/pts/N). The board
             greets the port before you connect: press Enter for a prompt. Ctrl-C quits.
  --no-view  do not serve the live 3D view (by default its address is printed at start:
             http://127.0.0.1:${DEFAULT_VIEW_PORT}/, or a free port if that one is taken).
             The page's terminal shares your link (lines typed there go to the board on it);
             the view's own questions (\`geometry\`, \`config\`) and the page's jog
             buttons use the other link (UART0, or with --uart the USB port), never yours:
             use --no-view to have that link free.
  --view-port N  the view's port (0: any free port)
  --elf PATH firmware ELF (default: ${DEFAULT_ELF})
  --no-xip-cache  flash reads cost nothing (no XIP cache model, emulator gap 13; also
             HEXAPOD_XIP_CACHE=off): by default a cache miss stalls the core as on a Pico
The status line (stderr) shows the six measured servo pulse widths in microseconds.
kill -USR2 <pid> power-cycles the emulated board (its flash, and saved settings, kept).`;

const CTRL_C = 0x03;
const CTRL_RIGHT_BRACKET = 0x1d;
const CR = 0x0d;
const LF = 0x0a;
const BACKSPACE = 0x08;
const DELETE = 0x7f;

/** Emulated time run per step, so keystrokes and output stay responsive. */
const STEP_NANOS = 10e6;
/** If the emulator falls this far behind the wall clock, it stops trying to catch up. */
const MAX_LAG_NANOS = 200e6;

async function main() {
  let options;
  try {
    ({ values: options } = parseArgs({
      options: {
        uart: { type: 'boolean', default: false },
        pty: { type: 'boolean', default: false },
        'local-echo': { type: 'boolean', default: false },
        'no-view': { type: 'boolean', default: false },
        'view-port': { type: 'string', default: String(DEFAULT_VIEW_PORT) },
        elf: { type: 'string', default: DEFAULT_ELF },
        'no-xip-cache': { type: 'boolean', default: false },
        help: { type: 'boolean', short: 'h', default: false },
      },
    }));
  } catch (error) {
    console.error(`${error.message}\n\n${USAGE}`);
    process.exit(2);
  }
  if (options.help) {
    console.log(USAGE);
    return;
  }

  const board = new EmulatedBoard({
    elf: options.elf,
    bootrom: loadBootrom({ log: (message) => process.stderr.write(`${message}\n`) }),
    // With the view, the USB port is there with --uart too: the view's own link.
    usb: !options.uart || !options['no-view'],
    ...(options['no-xip-cache'] ? { xipCache: false } : {}),
  });
  // The serial link on this terminal: the USB port's, as a Pico owner uses it, or UART0's.
  const serial = options.uart ? board.uart : board.usb;
  const name = options.uart ? 'UART0' : 'The USB serial port';
  const status = new StatusLine(process.stderr);
  // With the view, the terminal's bytes and the page's lines share that link
  // (shared-input.js).
  const input = options['no-view'] ? null : new SharedInput(serial);
  const link = input
    ? {
        sendBytes: (bytes) => input.typed(bytes),
        onOutput: (listener) => serial.onOutput(listener),
      }
    : serial;
  // The view's questions go on the other link, so your terminal never sees them.
  const queries = options.uart ? board.usb : board.uart;
  const view = input && (await startView(board, serial, queries, input, options, status));
  const connection = options.pty
    ? new PtyConnection(link, name, status)
    : new TerminalConnection(link, { echo: options['local-echo'] });

  let quitting = false;
  const quit = async (code, message) => {
    if (quitting) {
      return;
    }
    quitting = true;
    connection.close();
    status.close();
    if (message) {
      process.stderr.write(`${message}\n`);
    }
    await view?.close(
      message ? message.trim() : 'the runner was stopped (Ctrl-C, or its input ended)',
    );
    process.exit(code);
  };
  connection.onQuit = () => quit(0);
  process.on('SIGINT', () => quit(0));
  process.on('SIGTERM', () => quit(0));
  process.on('SIGHUP', () => quit(0));
  // SIGUSR2 turns the board off and on again (its flash kept, as a real board's): a test's
  // reset, e.g. to see saved settings come back.
  process.on('SIGUSR2', () => {
    board.powerCycle();
    status.message('power cycled (SIGUSR2)');
  });

  board.onServoChange(() => status.update(board));
  runInRealTime(board, status, (error) => quit(1, `\n${error.message}`));
}

/** Starts the 3D view's server and prints its address; exits with a message if it cannot. */
async function startView(board, serial, queries, input, options, status) {
  const port = Number(options['view-port']);
  if (!Number.isInteger(port) || port < 0 || port > 65535) {
    console.error(`--view-port: not a port number: ${options['view-port']}\n\n${USAGE}`);
    process.exit(2);
  }
  try {
    const view = await startViewServer({
      board,
      serial,
      queries,
      input,
      port,
      link: options.pty ? 'pty' : 'terminal',
    });
    status.message(`3D view: ${view.url}  (open it in a browser; --no-view skips it)`);
    return view;
  } catch (error) {
    console.error(
      `cannot start the 3D view on port ${port}: ${error.message} (--no-view skips it)`,
    );
    process.exit(1);
  }
}

/**
 * Keeps emulated time in step with the wall clock. The firmware sleeps (WFI) whenever it
 * is idle and the emulator skips such sleep instantly, so it is usually ahead and waits on
 * a timer (little CPU); when busy it may be slower than real time and runs flat out.
 */
function runInRealTime(board, status, onFault) {
  let wallStart = performance.now();
  let emulatedStart = board.nanos;
  let lastStatus = 0;
  const step = () => {
    const now = performance.now();
    const wallNanos = emulatedStart + (now - wallStart) * 1e6;
    const lead = board.nanos - wallNanos;
    if (lead > 0) {
      setTimeout(step, lead / 1e6); // ahead of the wall clock: sleep it off
      return;
    }
    try {
      // Run a step into the future, then sleep (above) until the wall clock gets there.
      board.runMs(Math.min(wallNanos + STEP_NANOS - board.nanos, STEP_NANOS) / 1e6);
    } catch (error) {
      onFault(error);
      return;
    }
    if (wallNanos - board.nanos > MAX_LAG_NANOS) {
      // Slower than real time: run flat out from here rather than race to catch up later.
      wallStart = performance.now();
      emulatedStart = board.nanos;
    }
    if (now - lastStatus > 1000) {
      lastStatus = now;
      status.update(board); // keeps the emulated clock on it moving
    }
    setImmediate(step);
  };
  step();
}

/** A serial link (`board.uart`, `board.usb`) <-> this terminal in raw mode. */
class TerminalConnection {
  constructor(link, { echo }) {
    this.link = link;
    this.echo = echo;
    this.onQuit = () => {};
    this.previousByte = null;
    link.onOutput((byte) => this.show(byte));
    if (process.stdin.isTTY) {
      process.stdin.setRawMode(true);
    }
    process.stdin.on('data', (data) => this.typed(data));
    process.stdin.on('end', () => this.onQuit());
  }

  typed(data) {
    for (const byte of data) {
      if (byte === CTRL_RIGHT_BRACKET || byte === CTRL_C) {
        this.onQuit();
        return;
      }
      // Enter gives CR in raw mode; lines end with LF on the wire.
      const sent = byte === CR ? LF : byte;
      this.link.sendBytes([sent]);
      if (this.echo) {
        if (sent === LF) {
          process.stdout.write('\r\n');
        } else if (byte === BACKSPACE || byte === DELETE) {
          process.stdout.write('\b \b');
        } else {
          process.stdout.write(Buffer.from([byte]));
        }
      }
    }
  }

  /** Firmware output; a bare LF is shown as CR LF so raw mode does not staircase. */
  show(byte) {
    if (byte === LF && this.previousByte !== CR) {
      process.stdout.write('\r\n');
    } else {
      process.stdout.write(Buffer.from([byte]));
    }
    this.previousByte = byte;
  }

  close() {
    if (process.stdin.isTTY) {
      process.stdin.setRawMode(false);
    }
    process.stdin.pause();
  }
}

/** A serial link <-> a pseudo-terminal, through a tiny Python bridge (pty-bridge.py). */
class PtyConnection {
  constructor(link, name, status) {
    this.onQuit = () => {};
    const bridgeScript = join(dirname(fileURLToPath(import.meta.url)), 'pty-bridge.py');
    this.bridge = spawn('python3', [bridgeScript], { stdio: ['pipe', 'pipe', 'inherit'] });
    this.bridge.on('error', (error) => {
      process.stderr.write(
        `cannot start the pty bridge (python3 ${bridgeScript}): ${error.message}\n`,
      );
      this.onQuit();
    });
    this.bridge.on('exit', () => this.onQuit());
    this.bridge.stdin.on('error', () => {}); // the bridge exiting is reported by 'exit'

    let path = null;
    let pending = Buffer.alloc(0);
    this.bridge.stdout.on('data', (data) => {
      if (path !== null) {
        link.sendBytes(data);
        return;
      }
      // The first line is the pty's path; anything after it is already input.
      pending = Buffer.concat([pending, data]);
      const newline = pending.indexOf(LF);
      if (newline < 0) {
        return;
      }
      path = pending.subarray(0, newline).toString();
      status.message(`${name} is on ${path}  (e.g. picocom --omap crlf ${path}); Ctrl-C quits`);
      const rest = pending.subarray(newline + 1);
      if (rest.length > 0) {
        link.sendBytes(rest);
      }
    });
    link.onOutput((byte) => this.bridge.stdin.write(Buffer.from([byte])));
  }

  close() {
    this.bridge.removeAllListeners('exit');
    this.bridge.kill();
  }
}

/**
 * The last terminal row shows the servo pulse widths (stderr). On a terminal, the rows
 * above it scroll on their own (a scroll region), so UART text never overwrites it;
 * otherwise each change is printed as a line.
 */
class StatusLine {
  constructor(stream) {
    this.stream = stream;
    this.isTTY = Boolean(stream.isTTY);
    this.text = '';
    this.printed = '';
    if (this.isTTY) {
      this.reserveLastRow();
      stream.on('resize', () => {
        this.reserveLastRow();
        this.draw();
      });
    }
  }

  reserveLastRow() {
    const rows = this.stream.rows || 24;
    // Make sure the cursor is above the last row (scroll once if it is on it), then set the
    // scroll region to all rows but the last; that homes the cursor, so save and restore it.
    this.stream.write(`\n\x1b[1A\x1b7\x1b[1;${rows - 1}r\x1b8`);
  }

  message(text) {
    if (this.isTTY) {
      this.stream.write(`${text}\r\n`);
    } else {
      this.stream.write(`${text}\n`);
    }
  }

  update(board) {
    const servos = board.servos();
    const widths = servos.map((servo) => (servo.live ? servo.widthUs.toFixed(2) : '-'));
    const period = servos.find((servo) => servo.live)?.periodNanos;
    const frameHz = period ? (1e9 / period).toFixed(1) : '-';
    this.text =
      `servos us: ${widths.join(' ')} | ${frameHz} Hz | ` +
      `emulated ${(board.millis / 1000).toFixed(1)} s`;
    this.draw();
  }

  draw() {
    if (this.isTTY) {
      const rows = this.stream.rows || 24;
      const columns = this.stream.columns || 80;
      // Save cursor, go to the last row, clear it, write, restore cursor.
      this.stream.write(`\x1b7\x1b[${rows};1H\x1b[2K${this.text.slice(0, columns - 1)}\x1b8`);
    } else {
      // Not a terminal: one line per change of the widths, not per clock tick.
      const widths = this.text.replace(/ \| emulated.*$/, '');
      if (widths !== this.printed) {
        this.printed = widths;
        this.stream.write(`${widths}\n`);
      }
    }
  }

  close() {
    if (this.isTTY) {
      const rows = this.stream.rows || 24;
      // Whole screen scrolls again; leave the status visible above the shell prompt.
      this.stream.write(`\x1b7\x1b[r\x1b8\x1b[${rows};1H\r\n`);
    }
  }
}

await main();
