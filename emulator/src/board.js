// A Raspberry Pi Pico running the real firmware ELF in rp2040js, with a host on UART0 and a
// logic analyser on the six servo pins. Everything runs in emulated time: the same calls give
// the same results on every run and machine, however fast the host is.

import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

import { RP2040 } from 'rp2040js';

import { loadBootrom } from './bootrom.js';
import { loadSegments, symbolValues } from './elf.js';
import { attachFrameMeter, attachLoopMeter } from './loop-meter.js';
import {
  attachFlashChip,
  FlashChip,
  onWatchdogExpiry,
  PadPulls,
  PacedUartInput,
  patchEmulatorGaps,
  wakeIfInterruptPending,
} from './rp2040js-gaps.js';
import { ServoPulseMeter } from './servo-pulses.js';

const REPO = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
/** The ELF `cargo fw` builds; FIRMWARE_ELF=path overrides. */
export const DEFAULT_ELF =
  process.env.FIRMWARE_ELF ?? join(REPO, 'target', 'thumbv6m-none-eabi', 'release', 'firmware');

const FLASH_START = 0x10000000;
const FLASH_BYTES = 16 * 1024 * 1024; // what rp2040js models; the Pico has 2 MiB
/** Every command line gets exactly one final reply: `ok` or `error:...`. */
export const FINAL_REPLY = /^(ok|error:)/;
/** The boot banner's line, e.g. `# hexapod control 0.1.0: poses in mm and degrees; type help`. */
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
   * @param {'typical'|'max'|object} [options.flashTiming] the flash chip's erase and program
   *   times (rp2040js-gaps.js, gap 7, `W25Q080_TIMING`)
   * @param {{address: number, bytes: Uint8Array}[]} [options.segments] what to program into
   *   the flash instead of the ELF's load segments (e.g. a UF2's blocks)
   */
  constructor({
    elf = DEFAULT_ELF,
    bootrom = loadBootrom(),
    onWatchdog = 'fail',
    flashTiming = 'typical',
    segments,
  } = {}) {
    this.elf = elf;
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

    // UART0 output survives resets (it is what the host saw).
    this.outputBytes = [];
    this.lines = [];
    this.partialLine = '';
    this.lineCursor = 0;
    this.outputListeners = new Set();
    this.servoChangeListener = null;

    this.powerOn(0);
  }

  /**
   * A fresh chip starting in boot2 at emulated time `startNanos`, with the host on UART0 and
   * the logic analyser on the servo pins. The first power-on programs the firmware into the
   * flash; later ones find the flash as the last chip left it.
   */
  powerOn(startNanos) {
    const mcu = new RP2040();
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
      this.flash = new FlashChip(mcu.flash, { timing: this.flashTiming });
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
      this.fail(`firmware stopped: breakpoint/UDF #${code} at PC 0x${mcu.core.PC.toString(16)} (a panic?)`);
    };
    // Gap 7: the flash chip (the same array as before a reset), written through the ROM.
    attachFlashChip(mcu, this.flash, {
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
    mcu.uart[0].onByte = (byte) => this.received(byte);
    this.uart0 = mcu.uart[0].pl011;
    this.uart0.onTxLost = (byte) => {
      // The PL011 drops a byte written while TXFF is set; firmware must check TXFF first.
      this.fail(`firmware wrote 0x${byte.toString(16)} to UART0 while its TX FIFO was full: byte lost`);
    };
    this.input = new PacedUartInput(mcu, mcu.uart[0]);

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
    const wdsel = this.mcu.peripherals[PSM_BASE].wdsel;
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
    while (clock.nanos < endNanos) {
      if (core.waiting && !wakeIfInterruptPending(core)) {
        // Asleep in WFI: nothing happens until the next timer event (or the end).
        const next = clock.nextAlarm;
        const toEnd = endNanos - clock.nanos;
        clock.tick(next ? Math.min(Math.max(next.nanos - clock.nanos, 0), toEnd) : toEnd);
      } else {
        clock.tick(core.executeInstruction() * this.nanosPerCycle);
      }
      if (this.eventPending) {
        this.eventPending = false;
        if (this.resetPending) {
          this.watchdogReset();
          ({ core, clock } = this.mcu);
        }
        if (this.powerCutPending) {
          this.powerCycle({ offMs: this.cutOffMs ?? 50 });
          ({ core, clock } = this.mcu);
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
    if (!this.runUntil(seen, { timeoutMs })) {
      throw new Error(
        `no line matching ${matcher} within ${timeoutMs} ms (emulated); ` +
          `last lines: ${JSON.stringify(this.lines.slice(-5))}, partial: ${JSON.stringify(this.partialLine)}`,
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

  /** Everything the firmware sent on UART0 so far, as text. */
  get output() {
    return Buffer.from(this.outputBytes).toString('latin1');
  }

  /** Calls `listener(byte)` for every byte the firmware sends; returns an unsubscribe. */
  onOutput(listener) {
    this.outputListeners.add(listener);
    return () => this.outputListeners.delete(listener);
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

  received(byte) {
    this.outputBytes.push(byte);
    for (const listener of this.outputListeners) {
      listener(byte);
    }
    if (byte === 0x0a) {
      this.lines.push(this.partialLine.replace(/\r$/, ''));
      this.partialLine = '';
      this.eventPending = true;
    } else {
      this.partialLine += String.fromCharCode(byte);
    }
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
   * Records every complete pulse from now on, like a logic analyser capture. Returns
   * `{ servos, stop }`: `servos[i]` (servo i + 1) is an array of `{ riseNanos, widthNanos,
   * periodNanos }` in order (`periodNanos` = rise to the previous rise); `stop()` ends it.
   */
  recordPulses() {
    const servos = this.servoMeter.pins.map(() => []);
    const listener = (index, pulse) => servos[index].push(pulse);
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
