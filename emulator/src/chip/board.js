// A Raspberry Pi Pico running the real firmware ELF in rp2040js, with a host on UART0, a USB
// host on its USB port (optional) and a logic analyser on the six servo pins. Everything runs
// in emulated time: the same calls give the same results on every run and machine, however
// fast the host is.

import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

import { RP2040 } from 'rp2040js';

import { loadBootrom } from './bootrom.js';
import { loadSegments, symbolValues } from './elf.js';
import { attachFrameMeter, attachLoopMeter } from './loop-meter.js';
import {
  attachFlashChip,
  attachXipCache,
  FlashChip,
  onWatchdogExpiry,
  PadPulls,
  PacedUartInput,
  patchEmulatorGaps,
  UsbCdcHost,
  wakeIfInterruptPending,
  xipCacheByDefault,
} from '../gaps/index.js';
import { ServoPulseMeter } from './servo-pulses.js';

const REPO = join(dirname(fileURLToPath(import.meta.url)), '..', '..', '..');
/** The ELF `cargo fw` builds; FIRMWARE_ELF=path overrides. */
export const DEFAULT_ELF =
  process.env.FIRMWARE_ELF ?? join(REPO, 'target', 'thumbv6m-none-eabi', 'release', 'firmware');

const FLASH_START = 0x10000000;
const FLASH_BYTES = 16 * 1024 * 1024; // what rp2040js models; the Pico has 2 MiB
/** Every command line gets exactly one final reply: `ok` or `error:...`. */
export const FINAL_REPLY = /^(ok|error:)/;
/**
 * The boot banner's line, e.g.
 * `# hexapod control 0.1.0 on board E660C0D1C7AB2F28: poses in mm and degrees; type help`.
 */
export const BANNER = /hexapod\b.*\bhelp\b/;
/** How often `runUntil` looks at its condition, besides on every received line. */
const CHECK_EVERY_NANOS = 100_000;

/**
 * PSM WDSEL bits a watchdog reset must select to restart the chip like a power-on (every
 * domain except the oscillators ROSC and XOSC: clocks, resets, bus fabric, ROM, SRAM, XIP,
 * chip reset, SIO, both processors).
 */
export const WDSEL_FULL_RESET = 0x1fffc;
const PSM_BASE = 0x40010;

export class EmulatedBoard {
  /**
   * @param {object} [options]
   * @param {string} [options.elf] firmware ELF (default: the `cargo fw` output)
   * @param {Uint32Array} [options.bootrom] boot ROM words (default: `loadBootrom()`)
   * @param {'fail'|'reset'} [options.onWatchdog] what a watchdog expiry does: `'fail'`
   *   (default) stops the run with an error; `'reset'` restarts the chip as the watchdog
   *   reset would (see `watchdogReset`).
   * @param {'typical'|'max'|{sectorEraseMs: number, pageProgramMs: number}} [options.flashTiming]
   *   the flash chip's erase and program times (../gaps/flash.js, gap 7, `W25Q080_TIMING`)
   * @param {{address: number, bytes: Uint8Array}[]} [options.segments] what to program into
   *   the flash instead of the ELF's load segments (e.g. a UF2's blocks)
   * @param {bigint} [options.flashId] the flash chip's 64-bit unique ID, the board's id
   *   (../gaps/flash.js, gap 13; default `DEFAULT_FLASH_UNIQUE_ID`)
   * @param {boolean|{open?: boolean}} [options.usb] plug a USB host into the USB port at
   *   power-on (default: nothing plugged in). It enumerates the firmware and opens its serial
   *   port (DTR) unless `{ open: false }`; `board.usb` is that link.
   * @param {boolean} [options.xipCache] model the XIP flash cache (../gaps/xip-cache.js, gap
   *   13; default: on, unless HEXAPOD_XIP_CACHE=off or `setXipCacheByDefault(false)`)
   */
  constructor({
    elf = DEFAULT_ELF,
    bootrom = loadBootrom(),
    onWatchdog = 'fail',
    flashTiming = 'typical',
    flashId = undefined,
    segments,
    usb = false,
    xipCache = xipCacheByDefault(),
  } = {}) {
    this.flashId = flashId;
    this.elf = elf;
    this.xipCacheModelled = xipCache;
    this.segments = segments ?? loadSegments(elf);
    this.bootrom = bootrom;
    this.onWatchdog = onWatchdog;
    this.flashTiming = flashTiming;
    /** The flash chip (gap 7), made at the first power-on; its contents survive power cycles. */
    this.flash = null;
    /** Watchdog resets so far: `{ nanos, wdsel }` each. */
    this.resets = [];
    this.resetPending = false;
    /** Power cycles so far: `{ offNanos, onNanos, cut }` (`cut`: during a flash write). */
    this.powerCycles = [];
    this.powerCutPending = false;

    this.fault = null;
    this.eventPending = false;

    // What each host saw survives resets.
    /** UART0's host. */
    this.uart = new SerialLink(this, (bytes) => this.input.send(bytes));
    /** The USB host's serial port, or null when nothing is plugged into the USB port. */
    this.usb = usb ? new UsbLink(this, usb === true ? {} : usb) : null;
    this.servoChangeListener = null;
    /** @type {Map<number, boolean | null> | undefined} GPIO -> level driven (`drivePin`). */
    this.pinDrives = undefined;

    this.powerOn(0);
  }

  /**
   * A fresh chip starting in boot2 at emulated time `startNanos`, with the host on UART0 and
   * the logic analyser on the servo pins. The first power-on programs the firmware into the
   * flash; later ones find the flash as the last chip left it.
   */
  powerOn(startNanos) {
    const mcu = /** @type {import('../gaps/index.js').Mcu} */ (new RP2040());
    this.mcu = mcu;
    patchEmulatorGaps(mcu);
    // loadBootrom resets the chip and wipes flash: the firmware goes in after it.
    mcu.loadBootrom(this.bootrom);
    if (!this.flash) {
      for (const { address, bytes } of this.segments) {
        const offset = address - FLASH_START;
        if (offset < 0 || offset + bytes.length > FLASH_BYTES) {
          throw new Error(`${this.elf}: segment at 0x${address.toString(16)} is not in flash`);
        }
        mcu.flash.set(bytes, offset);
      }
      this.flash = new FlashChip(mcu.flash, { timing: this.flashTiming, uniqueId: this.flashId });
    }
    // Emulated time runs on across a reset (nothing is scheduled on a fresh chip yet).
    mcu.clock.tick(startNanos);
    // Start in boot2, as the boot ROM would after finding it valid (a reset through the ROM
    // needs a flash interface rp2040js does not model).
    mcu.core.PC = FLASH_START;

    this.nanosPerCycle = 1e9 / mcu.clkSys;
    mcu.addClockListener((clkSys) => {
      this.nanosPerCycle = 1e9 / clkSys;
    });

    mcu.onBreak = (code) => {
      this.fail(
        `firmware stopped: breakpoint/UDF #${code} at PC 0x${mcu.core.PC.toString(16)} (a panic?)`,
      );
    };
    // Gap 13: the XIP cache in front of the flash (a fresh chip's is empty), its registers.
    /** The XIP cache model (gap 13), or null when the board was made without it. */
    this.xip = attachXipCache(mcu, { model: this.xipCacheModelled });
    // Gap 7: the flash chip (the same array as before a reset), written through the ROM.
    attachFlashChip(mcu, this.flash, {
      onFlushCache: () => {
        const cycles = this.xip?.flush() ?? 0;
        if (cycles) {
          this.xip.stall(cycles);
        }
      },
      onFault: (message) => this.fail(message),
      onPowerCut: () => {
        this.powerCutPending = true;
        this.eventPending = true;
      },
    });
    onWatchdogExpiry(mcu, () => {
      if (this.onWatchdog === 'reset') {
        this.resetPending = true;
        this.eventPending = true;
      } else {
        this.fail('watchdog expired: the firmware main loop stalled');
      }
    });

    // UART0: what the firmware sends, split into lines; what we send, paced.
    mcu.uart[0].onByte = (byte) => this.uart.received(byte);
    this.uart0 = mcu.uart[0].pl011;
    this.uart0.onTxLost = (byte) => {
      // The PL011 drops a byte written while TXFF is set; firmware must check TXFF first.
      this.fail(
        `firmware wrote 0x${byte.toString(16)} to UART0 while its TX FIFO was full: byte lost`,
      );
    };
    this.input = new PacedUartInput(mcu, mcu.uart[0]);
    this.usb?.host.attach(mcu);

    /** The main loop's longest pass and the longest interrupt handler (see loop-meter.js). */
    this.loop = attachLoopMeter(mcu);
    /** Servo frames seen and frames the firmware missed (see loop-meter.js). */
    this.frames = attachFrameMeter(mcu);

    /** The world outside the other GPIOs: switches and loads (gap 8); kept across resets. */
    this.pins = new PadPulls(mcu);
    for (const [n, level] of this.pinDrives ?? new Map()) {
      this.pins.drive(n, level);
    }

    this.servoMeter = new ServoPulseMeter(mcu);
    if (this.servoChangeListener) {
      this.servoMeter.onChange = this.servoChangeListener;
    }
  }

  /**
   * What the watchdog's reset does to the chip, emulated: rp2040js cannot reset through the
   * boot ROM (no flash interface model), and its own `reset()` resets only the core and PWM.
   * The firmware programs PSM WDSEL to choose what a watchdog reset resets; if it selects the
   * whole chip (`WDSEL_FULL_RESET`: all but the oscillators), that is a restart from boot2
   * with every peripheral at its reset state, which is what this does: a fresh emulated chip
   * with the same flash image, at the same emulated time. Bytes still on their way from the
   * host are lost (the UART is reset), as they would be. Anything less than a full reset
   * fails the run: the harness cannot say what a partial reset would leave.
   */
  watchdogReset() {
    this.resetPending = false;
    // rp2040js's PSM keeps WDSEL as a field its `Peripheral` type does not declare.
    const wdsel = /** @type {any} */ (this.mcu.peripherals[PSM_BASE]).wdsel;
    const nanos = this.mcu.clock.nanos;
    this.resets.push({ nanos, wdsel });
    if ((wdsel & WDSEL_FULL_RESET) !== WDSEL_FULL_RESET) {
      this.fail(
        `watchdog expired, but PSM WDSEL 0x${wdsel.toString(16)} does not select a full ` +
          `chip reset (0x${WDSEL_FULL_RESET.toString(16)})`,
      );
      return;
    }
    this.powerOn(nanos);
  }

  /**
   * Power off now and on again after `offMs` of emulated time: a fresh chip with the same flash
   * (what the last one left in it), starting in boot2. What the host had received stays in
   * `output`/`lines`; bytes still on their way to the board are lost. Also how an armed power
   * cut ends (`cutPowerDuring`).
   */
  powerCycle({ offMs = 50 } = {}) {
    const offNanos = this.mcu.clock.nanos;
    const cut = this.powerCutPending;
    this.powerCutPending = false;
    const onNanos = offNanos + offMs * 1e6;
    this.powerCycles.push({ offNanos, onNanos, cut });
    this.powerOn(onNanos);
  }

  /**
   * Arms a power cut during the firmware's next flash `routine` ('erase' or 'program'; the
   * `call`-th from now) after `bytes` bytes of it (0 = before any; the whole erase or program
   * = after it), with the bits in `mask` of the next byte's change done. The chip stops at
   * once and comes back on after `offMs` (see `powerCycle`).
   */
  cutPowerDuring({ routine, call = 1, bytes, mask = 0, offMs = 50 }) {
    this.cutOffMs = offMs;
    this.flash.cutPowerDuring({ routine, call, bytes, mask });
  }

  /** The settings sectors (memory.x): `{ offset, bytes }` from the start of flash. */
  get settingsStorage() {
    const { _settings_start: start, _settings_end: end } = symbolValues(this.elf, [
      '_settings_start',
      '_settings_end',
    ]);
    if (start === undefined || end === undefined) {
      throw new Error(`${this.elf} has no _settings_start/_settings_end (memory.x)`);
    }
    return { offset: start - FLASH_START, bytes: end - start };
  }

  // ---- time ----

  /** Emulated time since power-on. */
  get nanos() {
    return this.mcu.clock.nanos;
  }

  get millis() {
    return this.mcu.clock.nanos / 1e6;
  }

  /** CPU cycles executed (not counting sleep in WFI). */
  get cycles() {
    return this.mcu.core.cycles;
  }

  /** Advances emulated time by `ms`. */
  runMs(ms) {
    this.runUntil(() => false, { timeoutMs: ms });
  }

  /**
   * Runs until `condition()` is true (checked on every received line and every 0.1 ms) or
   * `timeoutMs` of emulated time have passed. Returns whether the condition was met.
   */
  runUntil(condition, { timeoutMs }) {
    const end = this.nanos + timeoutMs * 1e6;
    if (condition()) {
      return true;
    }
    while (this.nanos < end) {
      if (this.runSlice(Math.min(end, this.nanos + CHECK_EVERY_NANOS), condition)) {
        return true;
      }
      if (condition()) {
        return true;
      }
    }
    return false;
  }

  /** Executes instructions (or skips sleep to the next timer event) until `endNanos`. */
  runSlice(endNanos, condition) {
    let { core, clock } = this.mcu;
    let { xip } = this;
    while (clock.nanos < endNanos) {
      if (core.waiting && !wakeIfInterruptPending(core)) {
        // Asleep in WFI: nothing happens until the next timer event (or the end).
        const next = clock.nextAlarm;
        const toEnd = endNanos - clock.nanos;
        clock.tick(next ? Math.min(Math.max(next.nanos - clock.nanos, 0), toEnd) : toEnd);
      } else {
        let cycles = core.executeInstruction();
        if (xip !== null) {
          // Gap 13: the flash's stalls, emulated time with the instruction (or handler entry).
          cycles += xip.takeUnclockedCycles();
        }
        clock.tick(cycles * this.nanosPerCycle);
      }
      if (this.eventPending) {
        this.eventPending = false;
        if (this.resetPending) {
          this.watchdogReset();
          ({ core, clock } = this.mcu);
          ({ xip } = this);
        }
        if (this.powerCutPending) {
          this.powerCycle({ offMs: this.cutOffMs ?? 50 });
          ({ core, clock } = this.mcu);
          ({ xip } = this);
        }
        if (this.fault) {
          throw this.fault;
        }
        if (condition()) {
          return true;
        }
      }
    }
    return false;
  }

  fail(message) {
    this.fault ??= new Error(`${message} (at ${this.millis.toFixed(3)} ms emulated)`);
    this.eventPending = true;
  }

  // ---- UART0 ----

  /** Runs until the boot banner; returns it. */
  boot({ timeoutMs = 1000 } = {}) {
    return this.waitForLine(BANNER, { timeoutMs });
  }

  /** Sends raw bytes (a string is sent as latin1), paced at the firmware's baud rate. */
  sendBytes(data) {
    const bytes = typeof data === 'string' ? Buffer.from(data, 'latin1') : data;
    this.input.send(bytes);
  }

  /** Sends `text` and a LF, paced at the firmware's baud rate. */
  sendLine(text) {
    this.sendBytes(`${text}\n`);
  }

  /**
   * Sends bytes that each arrive with a UART framing error (what a sender at another baud rate
   * produces), paced at the firmware's baud rate.
   */
  sendGarbled(data) {
    const bytes = typeof data === 'string' ? Buffer.from(data, 'latin1') : data;
    this.input.sendWithFramingErrors(bytes);
  }

  /** See `SerialLink.waitForLine` (UART0). */
  waitForLine(matcher, options) {
    return this.uart.waitForLine(matcher, options);
  }

  /** See `SerialLink.request` (UART0). */
  request(text, options) {
    return this.uart.request(text, options);
  }

  /** Everything the firmware sent on UART0 so far, as text. */
  get output() {
    return this.uart.output;
  }

  get outputBytes() {
    return this.uart.outputBytes;
  }

  /** UART0's lines so far, and the cursor `waitForLine` searches from. */
  get lines() {
    return this.uart.lines;
  }

  get lineCursor() {
    return this.uart.lineCursor;
  }

  set lineCursor(index) {
    this.uart.lineCursor = index;
  }

  get partialLine() {
    return this.uart.partialLine;
  }

  /** Calls `listener(byte)` for every byte the firmware sends on UART0; returns an unsubscribe. */
  onOutput(listener) {
    return this.uart.onOutput(listener);
  }

  /**
   * The board as a host on `link` sees it (`board.through(board.usb)`): every call of the
   * board (pins, time, ...), with the serial ones (`sendLine`, `sendBytes`, `request`,
   * `waitForLine`, `lines`, `lineCursor`, `partialLine`, `output`, `outputBytes`,
   * `onOutput`) going over `link`. The e2e helpers take it in place of the board.
   */
  through(link) {
    const board = this;
    return new Proxy(board, {
      get(target, property) {
        const source = LINK_CALLS.has(property) ? link : target;
        const value = Reflect.get(source, property, source);
        return typeof value === 'function' ? value.bind(source) : value;
      },
      set(target, property, value) {
        Reflect.set(LINK_CALLS.has(property) ? link : target, property, value);
        return true;
      },
    });
  }

  /** Bytes lost because they arrived while the 32-byte RX FIFO was full (overruns). */
  get rxFifoDroppedBytes() {
    return this.uart0.rxOverrunBytes;
  }

  /** Bytes that arrived while the firmware had UART0's receiver disabled (lost). */
  get rxDisabledDroppedBytes() {
    return this.uart0.rxDisabledBytes;
  }

  /** UART0 has nothing left to send: TX FIFO empty and the last stop bit sent (not BUSY). */
  get uartTxIdle() {
    return !this.uart0.busy;
  }

  /** Bytes the firmware wrote to UART0 while TXFF was set (lost; each also fails the run). */
  get uartTxLostBytes() {
    return this.uart0.txLostBytes;
  }

  /** Bytes queued by `sendBytes` that are not on the wire yet. */
  get inputPending() {
    return this.input.pending;
  }

  // ---- servos ----

  /** Per servo (1..6): widthUs, periodUs, widthNanos, periodNanos, widthCounts, pulses, live. */
  servos() {
    return this.servoMeter.read();
  }

  /** The six most recent pulse widths in microseconds (null before the first pulse). */
  pulseWidthsUs() {
    return this.servos().map((servo) => servo.widthUs);
  }

  /** The six most recent frame periods in microseconds (null before two pulses). */
  periodsUs() {
    return this.servos().map((servo) => servo.periodUs);
  }

  /** Calls `listener(board)` whenever a servo's measured pulse width changes. */
  onServoChange(listener) {
    this.servoChangeListener = () => listener(this);
    this.servoMeter.onChange = this.servoChangeListener;
  }

  /**
   * Records every complete pulse that rises from now on (see below), like a logic analyser
   * capture started between frames. Returns
   * `{ servos, stop }`: `servos[i]` (servo i + 1) is an array of `{ riseNanos, widthNanos,
   * periodNanos }` in order (`periodNanos` = rise to the previous rise); `stop()` ends it.
   */
  recordPulses() {
    const servos = this.servoMeter.pins.map(() => []);
    // A pulse already high when the recording starts belongs to the frame before it: left
    // out for every servo alike (else a recording that starts mid-frame holds that frame's
    // longer pulses only, and the servos' pulse k are not all frame k). The slices rise within
    // a few microseconds of each other, so a pulse that rose up to 100 us before the start
    // counts as this frame's, for all of them.
    const fromNanos = this.nanos - 100_000;
    const listener = (index, pulse) => {
      if (pulse.riseNanos >= fromNanos) {
        servos[index].push(pulse);
      }
    };
    this.servoMeter.pulseListeners.add(listener);
    return { servos, stop: () => this.servoMeter.pulseListeners.delete(listener) };
  }

  // ---- other pins ----

  /**
   * Drives GPIO `n` from outside: `true` high, `false` low (e.g. a switch to ground), `null`
   * open (the pin reads its pad's pull: an open e-stop switch on a pulled-up input is high).
   */
  drivePin(n, level) {
    this.pinDrives ??= new Map();
    this.pinDrives.set(n, level);
    this.pins.drive(n, level);
  }

  /** What the firmware drives on GPIO `n`: `null` when it is not an output, else its level. */
  pinOutput(n) {
    const pin = this.mcu.gpio[n];
    return pin.outputEnable ? pin.outputValue : null;
  }

  /** The baud rate the firmware latched into UART0, rounded (what the paced input follows). */
  get baud() {
    return Math.round(this.input.baud);
  }
}

/**
 * What `EmulatedBoard.through` sends over the link instead of UART0.
 * @type {Set<string | symbol>}
 */
const LINK_CALLS = new Set([
  'sendBytes',
  'sendLine',
  'request',
  'waitForLine',
  'lines',
  'lineCursor',
  'partialLine',
  'output',
  'outputBytes',
  'onOutput',
]);

/**
 * One serial link's host side: what the firmware sent, split into lines, and the host's
 * sending. UART0's (`board.uart`, also reachable as `board.sendLine`, `board.request`, ...) and
 * the USB port's (`board.usb`) have the same calls, so a test can speak through either.
 */
export class SerialLink {
  constructor(board, send) {
    this.board = board;
    this.send = send;
    this.outputBytes = [];
    this.lines = [];
    this.partialLine = '';
    this.lineCursor = 0;
    this.outputListeners = new Set();
  }

  /** Sends raw bytes (a string is sent as latin1). */
  sendBytes(data) {
    this.send(typeof data === 'string' ? Buffer.from(data, 'latin1') : data);
  }

  /** Sends `text` and a LF. */
  sendLine(text) {
    this.sendBytes(`${text}\n`);
  }

  /**
   * Waits for the next received line (without its CR/LF) that matches `matcher` (a RegExp or
   * a predicate on the line). Lines are consumed in order: the search starts after the line
   * the previous wait returned, and lines skipped on the way are consumed too.
   * Throws if none arrives within `timeoutMs` of emulated time.
   */
  waitForLine(matcher, { timeoutMs = 1000 } = {}) {
    const matches = typeof matcher === 'function' ? matcher : (line) => matcher.test(line);
    let found;
    const seen = () => {
      for (; this.lineCursor < this.lines.length; this.lineCursor++) {
        if (matches(this.lines[this.lineCursor])) {
          found = this.lines[this.lineCursor++];
          return true;
        }
      }
      return false;
    };
    if (!this.board.runUntil(seen, { timeoutMs })) {
      throw new Error(
        `no line matching ${matcher} within ${timeoutMs} ms (emulated); ` +
          `last lines: ${JSON.stringify(this.lines.slice(-5))}, ` +
          `partial: ${JSON.stringify(this.partialLine)}`,
      );
    }
    return found;
  }

  /**
   * Sends a command line and waits for its final reply (`ok` / `error:...`).
   * Returns `{ reply, lines }`: the final reply and every line received up to it.
   */
  request(text, { timeoutMs = 1000, final = FINAL_REPLY } = {}) {
    const first = this.lineCursor;
    this.sendLine(text);
    const reply = this.waitForLine(final, { timeoutMs });
    return { reply, lines: this.lines.slice(first, this.lineCursor) };
  }

  /** Everything the firmware sent on this link so far, as text. */
  get output() {
    return Buffer.from(this.outputBytes).toString('latin1');
  }

  /** Calls `listener(byte)` for every byte the firmware sends; returns an unsubscribe. */
  onOutput(listener) {
    this.outputListeners.add(listener);
    return () => this.outputListeners.delete(listener);
  }

  /** Runs emulated time (the board's). */
  runUntil(condition, options) {
    return this.board.runUntil(condition, options);
  }

  received(byte) {
    this.outputBytes.push(byte);
    for (const listener of this.outputListeners) {
      listener(byte);
    }
    if (byte === 0x0a) {
      this.lines.push(this.partialLine.replace(/\r$/, ''));
      this.partialLine = '';
      this.board.eventPending = true;
    } else {
      this.partialLine += String.fromCharCode(byte);
    }
  }
}

/**
 * The USB port's serial link (`board.usb`): a USB host (`UsbCdcHost`, ../gaps/usb.js, gaps
 * 9-12) with the firmware's CDC ACM port. Besides the `SerialLink` calls: open and close the
 * port (DTR), stop and resume reading, unplug and plug in again.
 */
export class UsbLink extends SerialLink {
  constructor(board, { open = true } = {}) {
    super(board, (bytes) => this.host.send(bytes));
    this.host = new UsbCdcHost({
      open,
      onData: (bytes) => {
        for (const byte of bytes) {
          this.received(byte);
        }
      },
    });
  }

  /** The device is enumerated (configured) and the host has its port open (DTR up). */
  get isOpen() {
    return this.host.open;
  }

  /** The host has enumerated (configured) the device since it was last plugged in. */
  get configured() {
    return this.host.configured;
  }

  /** Runs until the port is open (enumerated, DTR up); throws after `timeoutMs`. */
  waitUntilOpen({ timeoutMs = 1000 } = {}) {
    if (!this.board.runUntil(() => this.host.open, { timeoutMs })) {
      throw new Error(`the USB port did not open within ${timeoutMs} ms (emulated)`);
    }
  }

  /** Reads a descriptor (GET_DESCRIPTOR: `type` 1 device, 3 string), running until it came. */
  readDescriptor(type, index, { langId = 0, timeoutMs = 100 } = {}) {
    let bytes = null;
    this.host.readDescriptor(type, index, (data) => (bytes = data), { langId });
    if (!this.board.runUntil(() => bytes !== null, { timeoutMs })) {
      throw new Error(`descriptor ${type}/${index} did not come within ${timeoutMs} ms (emulated)`);
    }
    return bytes;
  }

  /** The configuration descriptor (with its interfaces and endpoints) read at enumeration. */
  get configurationDescriptor() {
    return Uint8Array.from(this.host.cdc.descriptors);
  }

  /** Sets the port's line coding to `baud` 8N1 (SET_LINE_CODING), running until acknowledged. */
  setLineCoding(baud, { timeoutMs = 100 } = {}) {
    let done = false;
    this.host.setLineCoding(baud, () => (done = true));
    if (!this.board.runUntil(() => done, { timeoutMs })) {
      throw new Error(`SET_LINE_CODING was not acknowledged within ${timeoutMs} ms (emulated)`);
    }
  }

  /** Opens the port (DTR up), as a terminal program does. */
  open() {
    this.host.openPort();
  }

  /** Closes the port (DTR down). */
  close() {
    this.host.closePort();
  }

  /** The host's program stops reading: the device's IN buffer stays full. */
  stopReading() {
    this.host.setReading(false);
  }

  startReading() {
    this.host.setReading(true);
  }

  /** The host's program reads slowly: one 64-byte IN packet per `ms` at most (0: at once). */
  readSlowly(ms) {
    this.host.setReadInterval(ms);
  }

  unplug() {
    this.host.unplug();
  }

  /** Plugs the cable in again; the host opens the port once enumerated unless `open: false`. */
  replug({ open = true } = {}) {
    this.host.replug({ open });
  }

  /** Bytes sent that the device has not taken yet (USB's flow control holds them). */
  get unsent() {
    return this.host.unsent;
  }
}
