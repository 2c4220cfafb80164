// Every workaround for a gap in rp2040js 1.4.1 lives here, each with the reason.
//
// 1. Logging: the default logger prints debug messages for every unimplemented register
//    access, which slows a run ~15x and floods the terminal. Errors only (and errors throw,
//    so a real emulator fault stops the run instead of scrolling past).
// 2. UARTRSR (offset 0x04, receive status / error clear) is not implemented: reads return all
//    ones, so rp2040-hal's reader sees a FIFO overrun on every read of an empty FIFO and
//    reports an error forever. The real register reads 0 when no error happened, which is
//    always true here (the emulated line has no framing/parity errors), so reads return 0
//    and the firmware's write-to-clear is accepted silently.
// 3. Receive timing: `uart.feedByte()` puts a byte into the 32-entry RX FIFO at once, and
//    drops it silently when the FIFO is full. A real host's bytes arrive one per 10 bit times
//    (8N1). `PacedUartInput` delivers queued bytes at the baud rate the firmware programmed
//    (following run-time changes), in emulated time, as a real serial line would; a byte that
//    finds the FIFO full is lost, as on hardware (an overrun), and counted.
//    (Transmit has no timing in rp2040js: TX bytes appear the instant they are written.)
//    rp2040js has no overrun flag either; the PL011 marks the first byte that enters the FIFO
//    after a loss with OE (UARTDR bit 11), which is how firmware learns of the lost bytes:
//    `PacedUartInput` records that flag per byte and UARTDR reads return it. (UARTRSR's OE
//    bit stays 0: see 2.)
// 4. Watchdog expiry: rp2040js calls `onWatchdogTrigger`, then re-arms the alarm of a counter
//    that sits at 0, so it fires again at the same instant forever and emulated time stops.
//    `onWatchdogExpiry` stops the watchdog timer when it fires and reports it once (a real
//    chip would reset; a reset through the boot ROM is not possible here, so board.js either
//    fails the run or, with `onWatchdog: 'reset'`, emulates the reset with a fresh chip).
// 5. WFI with an interrupt already pending: the ARM wakes at once (also with PRIMASK set, which
//    is how firmware closes the check-then-sleep race: `cpsid; if idle { wfi }; cpsie`).
//    rp2040js only wakes a waiting core when an interrupt *becomes* pending, so an interrupt
//    that arrived between the check and the WFI leaves the core asleep until some other
//    interrupt (e.g. the next servo frame, up to 20 ms) while the UART's 32-byte FIFO
//    overflows. `wakeIfInterruptPending` is called before each sleep step.

import { ConsoleLogger, LogLevel } from 'rp2040js';

const UARTDR = 0x00;
const UARTRSR = 0x04;
const UARTDR_OE = 1 << 11;
const WATCHDOG_BASE = 0x40058;
const BITS_PER_BYTE_8N1 = 10;
const DEFAULT_BAUD = 115200;

/** Applies gaps 1 and 2 to a fresh `RP2040`. */
export function patchEmulatorGaps(mcu) {
  mcu.logger = new ConsoleLogger(LogLevel.Error, true);
  for (const uart of mcu.uart) {
    const readRegister = uart.readUint32.bind(uart);
    const writeRegister = uart.writeUint32.bind(uart);
    // Error flags of the bytes in the RX FIFO, oldest first (see gap 3).
    uart.rxFifoFlags = [];
    uart.readUint32 = (offset) => {
      if (offset === UARTRSR) {
        return 0;
      }
      if (offset === UARTDR) {
        // Keep the flags in step should the FIFO have been emptied some other way.
        const flags = uart.rxFifoFlags;
        while (flags.length > uart.rxFIFO.itemCount) {
          flags.shift();
        }
        const flag = uart.rxFIFO.empty ? 0 : (flags.shift() ?? 0);
        return readRegister(offset) | flag;
      }
      return readRegister(offset);
    };
    uart.writeUint32 = (offset, value) => {
      if (offset !== UARTRSR) {
        writeRegister(offset, value);
      }
    };
  }
}

/** Gap 4: calls `callback()` once when the watchdog expires, and stops it. */
export function onWatchdogExpiry(mcu, callback) {
  const watchdog = mcu.peripherals[WATCHDOG_BASE];
  watchdog.onWatchdogTrigger = () => {
    watchdog.alarm.enable = false;
    watchdog.timer.enable = false;
    callback();
  };
}

/** Gap 3: a host sending into a UART's RX pin at the firmware's baud rate. */
export class PacedUartInput {
  constructor(mcu, uart) {
    this.uart = uart;
    this.clock = mcu.clock;
    this.queue = [];
    this.queueHead = 0;
    /** Bytes that arrived while the RX FIFO was full (lost, like a hardware overrun). */
    this.droppedBytes = 0;
    /** Bytes were lost since the last one that entered the FIFO: flag the next with OE. */
    this.overrun = false;
    this.lastDeliveryNanos = -Infinity;
    this.alarm = mcu.clock.createAlarm(() => this.deliverOne());
    this.scheduled = false;
  }

  /** The rate the firmware programmed into the divider registers (nominal until it has). */
  get baud() {
    const baud = this.uart.baudRate;
    return Number.isFinite(baud) && baud > 0 ? baud : DEFAULT_BAUD;
  }

  get byteNanos() {
    return (BITS_PER_BYTE_8N1 * 1e9) / this.baud;
  }

  /** Bytes queued but not on the wire yet. */
  get pending() {
    return this.queue.length - this.queueHead;
  }

  /** Queues bytes; each reaches the RX FIFO one byte time after the previous one. */
  send(bytes) {
    for (const byte of bytes) {
      this.queue.push(byte & 0xff);
    }
    if (!this.scheduled && this.pending > 0) {
      // A byte takes one byte time on the wire, counted from now or from the previous byte.
      const start = Math.max(this.clock.nanos, this.lastDeliveryNanos);
      this.schedule(start + this.byteNanos - this.clock.nanos);
    }
  }

  deliverOne() {
    this.scheduled = false;
    const byte = this.queue[this.queueHead++];
    if (this.queueHead === this.queue.length) {
      this.queue = [];
      this.queueHead = 0;
    }
    if (this.uart.rxFIFO.full) {
      this.droppedBytes++;
      this.overrun = true;
    } else {
      this.uart.rxFifoFlags?.push(this.overrun ? UARTDR_OE : 0);
      this.overrun = false;
      this.uart.feedByte(byte);
    }
    this.lastDeliveryNanos = this.clock.nanos;
    if (this.pending > 0) {
      this.schedule(this.byteNanos);
    }
  }

  schedule(deltaNanos) {
    this.scheduled = true;
    this.alarm.schedule(deltaNanos);
  }
}

/** Gap 5: ends a WFI/WFE sleep if an enabled interrupt is already pending (true if it did). */
export function wakeIfInterruptPending(core) {
  if (core.waiting && (core.pendingInterrupts & core.enabledInterrupts) !== 0) {
    core.waiting = false;
    return true;
  }
  return false;
}
