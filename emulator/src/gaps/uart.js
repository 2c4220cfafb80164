// The UART, gaps 2 and 3 of rp2040js 1.4.1 (numbered as in index.js, which installs them).
//
// The chip: each UART is an ARM PL011 (RP2040 datasheet, chapter 4.2; PL011 TRM r1p5) with
// 32-entry FIFOs, interrupts at programmed FIFO levels and a receive timeout, fed by a host
// whose bytes arrive one per 10 bit times (8N1). rp2040js: a stub that flatters the firmware
// (below). Here: `Pl011`, the PL011 in emulated time, installed over each of rp2040js's
// UARTs, and `PacedUartInput`, a host that sends at the rate the firmware latched.
//
// 2. The UART is a stub, and the stub flatters firmware. rp2040js 1.4.1 raises the RX
//    interrupt on every received byte (a PL011 raises it at the programmed FIFO level, or
//    after 32 bit periods of silence with data waiting); it transmits a byte the instant it
//    is written (no FIFO, TXFE always set, BUSY never, the TX interrupt always pending);
//    UARTIFLS is missing (reads all ones) and so is UARTRSR (reads all ones, which rp2040-hal
//    takes as an overrun on every read of an empty FIFO); nothing reports an overrun.
//    `Pl011` replaces those parts with a model of the ARM PL011 as the RP2040 has it (RP2040
//    datasheet, chapter 4.2; PL011 TRM r1p5), in emulated time:
//    - RX FIFO of 32 entries of 12 bits (data, FE, PE, BE, OE). A byte that arrives while it
//      is full is lost and counted (an overrun): UARTRSR.OE and UARTRIS.OERIS are set, and
//      the next byte that gets into the FIFO carries OE in its UARTDR read. UARTRSR shows OE
//      until any write to UARTRSR/UARTECR; its FE/PE/BE are those of the last byte read.
//    - RX interrupts: RXRIS when the fill reaches the UARTIFLS level (4, 8, 16, 24, 28) as a
//      byte arrives, cleared when reads take it below the level; RTRIS when the FIFO is not
//      empty and nothing has arrived for 32 bit periods (every byte restarts the count),
//      cleared by reading the FIFO empty. An ICR write clears both; a timeout whose
//      condition still holds (data waiting, nothing new) comes back one bit period later, as
//      the count is not restarted by the clear (embassy-rp's BufferedUart fixes, PR 1142,
//      report the RP2040's timeout interrupt returning after a clear while data stays in the
//      FIFO; how soon is this model's choice: the next bit tick).
//    - TX FIFO of 32 entries; the shift register takes the next byte when the previous one's
//      stop bit ends, and the first after idle at the next Baud16 tick (1/16 bit; the baud
//      generator restarts at the UARTLCR_H write that latches the divisor). A byte reaches
//      the host (`uart.onByte`) when its stop bit ends: 1 + WLEN + parity + stop bits (10 for
//      8N1) at the latched rate. TXFE/TXFF/BUSY follow the FIFO and the shift register; a
//      write while TXFF is lost, as on the chip, and counted (`txLostBytes`, `onTxLost`).
//      TXRIS is set when the transmitter's taking a byte brings the fill from above the
//      UARTIFLS level to at or below it (the PL011 TX interrupt is edge-based: it is not set
//      on an empty FIFO nobody wrote to), cleared by writes that take the fill above it.
//    - UARTIBRD/UARTFBRD take effect at the next UARTLCR_H write (the PL011 latches them
//      there): for the next byte shifted out, the receive timeout and the host's pacing.
//    - UARTRIS, UARTMIS = RIS & IMSC, UARTICR (write 1 to clear); the NVIC line follows
//      MIS != 0. A receiver or transmitter that UARTCR disables stops (bytes arriving then
//      are ignored and counted; a byte being shifted out completes).
//    Not modelled (no emulated line can produce them): framing/parity/break errors from the
//    wire (`feedByte` accepts FE/PE/BE bits in 8..10 to inject them, and
//    `PacedUartInput.sendWithFramingErrors` sends bytes flagged FE, as a sender at another
//    rate does), sending breaks, modem lines and flow control, loopback (UARTCR.LBE fails the run), IrDA, DMA requests (as
//    rp2040js: TX always requested while enabled, RX never). Received bytes enter the FIFO
//    at the end of their stop bit (a PL011 stores them at its middle: half a bit earlier).
// 3. Receive timing: `uart.feedByte()` in rp2040js puts a byte into the RX FIFO at once. A
//    real host's bytes arrive one per 10 bit times (8N1). `PacedUartInput` is that host: it
//    delivers queued bytes at the baud rate the firmware latched (following run-time
//    changes), in emulated time, as a real serial line would; what happens to a byte that
//    finds the FIFO full (an overrun) is the model's business (gap 2).

// Register offsets (RP2040 datasheet, 4.2.8).
const UARTDR = 0x00;
const UARTRSR = 0x04; // UARTECR when written
const UARTFR = 0x18;
const UARTLCR_H = 0x2c;
const UARTCR = 0x30;
const UARTIFLS = 0x34;
const UARTIMSC = 0x38;
const UARTRIS = 0x3c;
const UARTMIS = 0x40;
const UARTICR = 0x44;

// UARTDR error bits of a received entry; UARTRSR has the same four in bits 0..3.
const DR_ERRORS_SHIFT = 8;
const DR_FE = 1 << 8;
const DR_PE = 1 << 9;
const DR_BE = 1 << 10;
const DR_OE = 1 << 11;
const RSR_OE = 1 << 3;
// UARTFR
const FR_BUSY = 1 << 3;
const FR_RXFE = 1 << 4;
const FR_TXFF = 1 << 5;
const FR_RXFF = 1 << 6;
const FR_TXFE = 1 << 7;
// UARTLCR_H
const LCR_H_PEN = 1 << 1;
const LCR_H_STP2 = 1 << 3;
const LCR_H_FEN = 1 << 4;
const LCR_H_WLEN_SHIFT = 5;
// UARTCR
const CR_UARTEN = 1 << 0;
const CR_LBE = 1 << 7;
const CR_TXE = 1 << 8;
const CR_RXE = 1 << 9;
// UARTRIS / UARTIMSC / UARTMIS / UARTICR
const INT_RX = 1 << 4;
const INT_TX = 1 << 5;
const INT_RT = 1 << 6;
const INT_FE = 1 << 7;
const INT_PE = 1 << 8;
const INT_BE = 1 << 9;
const INT_OE = 1 << 10;
const INT_ALL = 0x7ff;

const FIFO_DEPTH = 32;
/** UARTIFLS RXIFLSEL / TXIFLSEL 0..4: 1/8, 1/4, 1/2, 3/4, 7/8 of the 32 entries. */
const FIFO_LEVELS = [4, 8, 16, 24, 28];
const UARTIFLS_RESET = 0x12; // both at 1/2
const RX_TIMEOUT_BITS = 32;
const BAUD16_PER_BIT = 16;
/** Float noise allowed when placing an instant on the Baud16 grid, in ticks. */
const GRID_SLACK = 1e-6;
/** A host sends 8N1: start, 8 data, stop. */
const BITS_PER_BYTE_8N1 = 10;
/** What the host assumes before the firmware has programmed a divisor. */
const DEFAULT_BAUD = 115200;

/**
 * The ARM PL011 of an RP2040 UART, in emulated time (see gap 2). Installed over rp2040js's
 * `RPUART` by replacing its `readUint32`, `writeUint32`, `feedByte` and `checkInterrupts`;
 * the divisor, line control and control registers stay in rp2040js's object (it stores them),
 * everything with timing or a FIFO is here.
 */
export class Pl011 {
  constructor(mcu, uart) {
    this.mcu = mcu;
    this.uart = uart;
    this.clock = mcu.clock;

    // Receive: FIFO entries are data | FE | PE | BE | OE (UARTDR bits 0..11).
    this.rxFifo = new Uint16Array(FIFO_DEPTH);
    this.rxHead = 0;
    this.rxCount = 0;
    /** UARTRSR bits 0..3. */
    this.rsr = 0;
    /** A byte was lost since the last one that got in: flag the next with OE. */
    this.rxOverrunPending = false;
    /** Bytes lost because they arrived with the RX FIFO full (overruns). */
    this.rxOverrunBytes = 0;
    /** Bytes that arrived while UARTCR had the receiver (or the UART) disabled. */
    this.rxDisabledBytes = 0;
    /** Bytes put into the RX FIFO. */
    this.rxBytes = 0;
    // The receive timeout count: `rxTimeoutBits` bit periods from `rxTimeoutFrom`.
    this.rxTimeoutAlarm = this.clock.createAlarm(() => this.rxTimeoutExpired());
    this.rxTimeoutScheduled = false;
    this.rxTimeoutFrom = 0;
    this.rxTimeoutBits = 0;
    this.rxTimeoutBitNanos = 0;

    // Transmit.
    this.txFifo = new Uint8Array(FIFO_DEPTH);
    this.txHead = 0;
    this.txCount = 0;
    this.txShifting = false;
    this.txShiftByte = 0;
    this.txAlarm = this.clock.createAlarm(() => this.shiftedOut());
    /** Bytes whose stop bit has ended (delivered to `uart.onByte`). */
    this.txBytes = 0;
    /** Bytes written to UARTDR while TXFF was set: lost, a firmware bug. */
    this.txLostBytes = 0;
    /** Called with each byte lost that way (the board fails the run). */
    this.onTxLost = null;

    // Registers with state here.
    this.ris = 0;
    this.imsc = 0;
    this.ifls = UARTIFLS_RESET;
    /** The divisor latched by the last UARTLCR_H write (0: none yet) and when. */
    this.divisor = 0;
    this.baudAnchorNanos = 0;

    const readRegister = uart.readUint32.bind(uart);
    const writeRegister = uart.writeUint32.bind(uart);
    uart.readUint32 = (offset) => this.read(offset, readRegister);
    uart.writeUint32 = (offset, value) => this.write(offset, value, writeRegister);
    uart.feedByte = (value) => this.receive(value);
    uart.checkInterrupts = () => this.updateInterrupt();
  }

  // ---- configuration ----

  get lineControl() {
    return this.uart.lineCtrlRegister;
  }

  get control() {
    return this.uart.ctrlRegister;
  }

  get fifoDepth() {
    return this.lineControl & LCR_H_FEN ? FIFO_DEPTH : 1;
  }

  /** RX FIFO fill at which RXRIS is set (1 with the FIFOs disabled). */
  get rxLevel() {
    return this.lineControl & LCR_H_FEN ? FIFO_LEVELS[(this.ifls >> 3) & 7] : 1;
  }

  /** TX FIFO fill at or below which TXRIS is set. */
  get txLevel() {
    return this.lineControl & LCR_H_FEN ? FIFO_LEVELS[this.ifls & 7] : 0;
  }

  get rxEnabled() {
    return (this.control & (CR_UARTEN | CR_RXE)) === (CR_UARTEN | CR_RXE);
  }

  get txEnabled() {
    return (this.control & (CR_UARTEN | CR_TXE)) === (CR_UARTEN | CR_TXE);
  }

  /** The latched rate, bits per second (`DEFAULT_BAUD` before a divisor was latched). */
  get baud() {
    return this.divisor ? this.mcu.clkPeri / (BAUD16_PER_BIT * this.divisor) : DEFAULT_BAUD;
  }

  get bitNanos() {
    return 1e9 / this.baud;
  }

  /** Bits per character as UARTLCR_H sets them: start, 5..8 data, parity, 1 or 2 stop. */
  get frameBits() {
    const lcr = this.lineControl;
    const dataBits = 5 + ((lcr >> LCR_H_WLEN_SHIFT) & 3);
    return 1 + dataBits + (lcr & LCR_H_PEN ? 1 : 0) + (lcr & LCR_H_STP2 ? 2 : 1);
  }

  /** A host's 8N1 byte time at the latched rate. */
  get hostByteNanos() {
    return BITS_PER_BYTE_8N1 * this.bitNanos;
  }

  /** UARTFR.BUSY: the TX FIFO is not empty or the shift register is sending. */
  get busy() {
    return this.txCount > 0 || this.txShifting;
  }

  get flags() {
    const depth = this.fifoDepth;
    return (
      (this.busy ? FR_BUSY : 0) |
      (this.rxCount === 0 ? FR_RXFE : 0) |
      (this.txCount >= depth ? FR_TXFF : 0) |
      (this.rxCount >= depth ? FR_RXFF : 0) |
      (this.txCount === 0 ? FR_TXFE : 0)
    );
  }

  // ---- registers ----

  read(offset, readRegister) {
    switch (offset) {
      case UARTDR:
        return this.readData();
      case UARTRSR:
        return this.rsr;
      case UARTFR:
        return this.flags;
      case UARTIFLS:
        return this.ifls;
      case UARTIMSC:
        return this.imsc;
      case UARTRIS:
        return this.ris;
      case UARTMIS:
        return this.ris & this.imsc;
      default:
        return readRegister(offset);
    }
  }

  write(offset, value, writeRegister) {
    switch (offset) {
      case UARTDR:
        this.writeData(value & 0xff);
        break;
      case UARTRSR:
        this.rsr = 0; // UARTECR: any write clears the four error bits
        break;
      case UARTIFLS:
        if ((value & 7) > 4 || ((value >> 3) & 7) > 4) {
          this.mcu.logger.error(this.uart.name, `UARTIFLS 0x${value.toString(16)}: reserved level`);
        }
        this.ifls = value & 0x3f;
        break;
      case UARTIMSC:
        this.imsc = value & INT_ALL;
        this.updateInterrupt();
        break;
      case UARTICR:
        this.clearInterrupts(value & INT_ALL);
        break;
      case UARTLCR_H:
        writeRegister(offset, value);
        this.latchDivisor();
        break;
      case UARTCR:
        if (value & CR_LBE) {
          this.mcu.logger.error(this.uart.name, 'UARTCR.LBE: loopback is not modelled');
        }
        writeRegister(offset, value);
        this.startShifting();
        this.updateInterrupt();
        break;
      default:
        writeRegister(offset, value); // UARTIBRD, UARTFBRD (latched at UARTLCR_H), ...
    }
  }

  /** The PL011 takes UARTIBRD/UARTFBRD at a UARTLCR_H write; its baud generator restarts. */
  latchDivisor() {
    const { intDivisor, fracDivisor } = this.uart;
    const divisor = intDivisor ? intDivisor + fracDivisor / 64 : 0;
    this.baudAnchorNanos = this.clock.nanos;
    if (divisor === this.divisor) {
      return;
    }
    this.divisor = divisor;
    if (this.rxTimeoutScheduled) {
      // What is left of the count runs at the new rate.
      const elapsedBits = (this.clock.nanos - this.rxTimeoutFrom) / this.rxTimeoutBitNanos;
      this.scheduleRxTimeout(Math.max(this.rxTimeoutBits - elapsedBits, 0));
    }
  }

  // ---- interrupts ----

  updateInterrupt() {
    this.mcu.setInterrupt(this.uart.irq, (this.ris & this.imsc) !== 0);
  }

  clearInterrupts(bits) {
    this.ris &= ~bits;
    if (bits & INT_RT && this.rxCount > 0 && !this.rxTimeoutScheduled) {
      // The timeout's condition still holds (the count is not restarted): it comes back.
      this.scheduleRxTimeout(1);
    }
    this.updateInterrupt();
  }

  // ---- receive ----

  /**
   * A character whose stop bit has just ended on the RX pin: `value` is the data byte, with
   * FE/PE/BE in bits 8..10 to inject a line error (an emulated line has none).
   */
  receive(value) {
    if (!this.rxEnabled) {
      this.rxDisabledBytes++;
      return;
    }
    // Line activity: the timeout count starts again.
    this.scheduleRxTimeout(RX_TIMEOUT_BITS);
    if (this.rxCount >= this.fifoDepth) {
      this.rxOverrunBytes++;
      this.rxOverrunPending = true;
      this.rsr |= RSR_OE;
      this.ris |= INT_OE;
    } else {
      const entry = (value & (DR_FE | DR_PE | DR_BE | 0xff)) | (this.rxOverrunPending ? DR_OE : 0);
      this.rxOverrunPending = false;
      this.rxFifo[(this.rxHead + this.rxCount) % FIFO_DEPTH] = entry;
      this.rxCount++;
      this.rxBytes++;
      this.ris |=
        (entry & DR_FE ? INT_FE : 0) | (entry & DR_PE ? INT_PE : 0) | (entry & DR_BE ? INT_BE : 0);
      if (this.rxCount >= this.rxLevel) {
        this.ris |= INT_RX;
      }
    }
    this.updateInterrupt();
  }

  readData() {
    if (this.rxCount === 0) {
      return 0;
    }
    const entry = this.rxFifo[this.rxHead];
    this.rxHead = (this.rxHead + 1) % FIFO_DEPTH;
    this.rxCount--;
    // FE/PE/BE in UARTRSR belong to the character just read; OE is set by the overrun itself.
    this.rsr = (this.rsr & RSR_OE) | ((entry >> DR_ERRORS_SHIFT) & 7);
    if (this.rxCount < this.rxLevel) {
      this.ris &= ~INT_RX;
    }
    if (this.rxCount === 0) {
      this.ris &= ~INT_RT;
    }
    this.updateInterrupt();
    return entry;
  }

  scheduleRxTimeout(bits) {
    this.rxTimeoutFrom = this.clock.nanos;
    this.rxTimeoutBits = bits;
    this.rxTimeoutBitNanos = this.bitNanos;
    this.rxTimeoutScheduled = true;
    this.rxTimeoutAlarm.schedule(bits * this.rxTimeoutBitNanos);
  }

  rxTimeoutExpired() {
    this.rxTimeoutScheduled = false;
    if (this.rxCount > 0) {
      this.ris |= INT_RT;
      this.updateInterrupt();
    }
  }

  // ---- transmit ----

  writeData(byte) {
    if (this.txCount >= this.fifoDepth) {
      this.txLostBytes++;
      this.onTxLost?.(byte);
      return;
    }
    this.txFifo[(this.txHead + this.txCount) % FIFO_DEPTH] = byte;
    this.txCount++;
    if (this.txCount > this.txLevel) {
      this.ris &= ~INT_TX;
    }
    this.startShifting();
    this.updateInterrupt();
  }

  /** Loads the shift register from the FIFO if it is idle and the transmitter enabled. */
  startShifting() {
    if (this.txShifting || this.txCount === 0 || !this.txEnabled) {
      return;
    }
    const level = this.txLevel;
    const above = this.txCount > level;
    this.txShiftByte = this.txFifo[this.txHead];
    this.txHead = (this.txHead + 1) % FIFO_DEPTH;
    this.txCount--;
    if (above && this.txCount <= level) {
      this.ris |= INT_TX;
    }
    this.txShifting = true;
    // The start bit begins at a Baud16 tick (the transmitter runs on them); back to back,
    // the previous stop bit ended on one.
    const now = this.clock.nanos;
    const bitNanos = this.bitNanos;
    const tick = bitNanos / BAUD16_PER_BIT;
    const ticks = Math.max(Math.ceil((now - this.baudAnchorNanos) / tick - GRID_SLACK), 0);
    const start = this.baudAnchorNanos + ticks * tick;
    this.txAlarm.schedule(start - now + this.frameBits * bitNanos);
  }

  shiftedOut() {
    this.txShifting = false;
    const dataBits = 5 + ((this.lineControl >> LCR_H_WLEN_SHIFT) & 3);
    const byte = this.txShiftByte & ((1 << dataBits) - 1);
    this.txBytes++;
    this.startShifting();
    this.updateInterrupt();
    this.uart.onByte?.(byte);
  }
}

/**
 * Gap 3: a host sending 8N1 into a UART's RX pin at the rate the firmware latched. Each byte
 * is handed to `uart.feedByte` (the model, gap 2) when its stop bit ends.
 */
export class PacedUartInput {
  constructor(mcu, uart) {
    this.uart = uart;
    this.clock = mcu.clock;
    this.queue = [];
    this.queueHead = 0;
    this.lastDeliveryNanos = -Infinity;
    this.alarm = mcu.clock.createAlarm(() => this.deliverOne());
    this.scheduled = false;
  }

  /** The rate the firmware latched into the divisor (nominal until it has). */
  get baud() {
    return this.uart.pl011.baud;
  }

  get byteNanos() {
    return this.uart.pl011.hostByteNanos;
  }

  /** Bytes lost because they arrived while the RX FIFO was full (overruns). */
  get droppedBytes() {
    return this.uart.pl011.rxOverrunBytes;
  }

  /** Bytes queued but not on the wire yet. */
  get pending() {
    return this.queue.length - this.queueHead;
  }

  /** Queues bytes; each reaches the RX FIFO one byte time after the previous one. */
  send(bytes) {
    this.queueEntries(bytes, 0);
  }

  /**
   * Queues bytes that arrive with a framing error (FE, bit 8 of a FIFO entry), as a sender at
   * another baud rate (or line noise) produces: each one the firmware must count as lost.
   */
  sendWithFramingErrors(bytes) {
    this.queueEntries(bytes, 0x100);
  }

  queueEntries(bytes, errorBits) {
    for (const byte of bytes) {
      this.queue.push((byte & 0xff) | errorBits);
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
    this.lastDeliveryNanos = this.clock.nanos;
    this.uart.feedByte(byte);
    if (this.pending > 0) {
      this.schedule(this.byteNanos);
    }
  }

  schedule(deltaNanos) {
    this.scheduled = true;
    this.alarm.schedule(deltaNanos);
  }
}
