// Every workaround for a gap in rp2040js 1.4.1 lives here, each with the reason.
//
// 1. Logging: the default logger prints debug messages for every unimplemented register
//    access, which slows a run ~15x and floods the terminal. Errors only (and errors throw,
//    so a real emulator fault stops the run instead of scrolling past).
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
//    wire (`feedByte` accepts FE/PE/BE bits in 8..10 to inject them), sending breaks, modem
//    lines and flow control, loopback (UARTCR.LBE fails the run), IrDA, DMA requests (as
//    rp2040js: TX always requested while enabled, RX never). Received bytes enter the FIFO
//    at the end of their stop bit (a PL011 stores them at its middle: half a bit earlier).
// 3. Receive timing: `uart.feedByte()` in rp2040js puts a byte into the RX FIFO at once. A
//    real host's bytes arrive one per 10 bit times (8N1). `PacedUartInput` is that host: it
//    delivers queued bytes at the baud rate the firmware latched (following run-time
//    changes), in emulated time, as a real serial line would; what happens to a byte that
//    finds the FIFO full (an overrun) is the model's business (gap 2).
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
// 6. (The chip reset lives in board.js, `watchdogReset` and `powerOn`.)
// 7. Flash writes. rp2040js has no flash interface: its SSI is a stub, so the boot ROM's flash
//    routines run to their end and change nothing; and a plain CPU store into the flash window
//    (0x10000000..0x13ffffff) changes its flash array, which on a real chip never reaches the
//    flash. `FlashChip` is the Pico's flash as firmware sees it through the boot ROM: the ROM
//    function table's entries for connect_internal_flash (IF), flash_exit_xip (EX),
//    flash_range_erase (RE), flash_range_program (RP), flash_flush_cache (FC) and
//    flash_enter_cmd_xip (CX) lead to `BKPT #n; BX LR`, and the breakpoint does the routine's
//    work on the flash array: an erase sets 4096-aligned sectors to 0xFF, a program ANDs
//    256-aligned pages in (NOR: bits only go from 1 to 0). Each takes the flash chip's time
//    in emulated time, the core busy in the ROM meanwhile (its cycles count): the Winbond
//    W25Q80DV datasheet's 4 KiB sector erase (tSE) and page program (tPP) times,
//    `W25Q080_TIMING`, typical (45 ms, 0.7 ms) by default, maximum (400 ms, 3 ms) on request;
//    the other four routines and the SPI transfer take no time here. The chip's rules are
//    enforced and a breach fails the run: every routine is called from SRAM (LR) with PRIMASK
//    set; EX comes after IF, RE and RP after EX; from EX until CX nothing in the flash window
//    is fetched, read or written (the chip is in command mode); the data to program is in
//    SRAM; erase and program are aligned and within the Pico's 2 MiB. A CPU store into the
//    flash window fails the run at any time. The array survives power cycles (board.js keeps
//    it), a power cut can be armed at a chosen byte of an erase or a program
//    (`cutPowerDuring`), and bits can be worn out (`wearOut`: a program cannot clear them).
// 8. Pad pulls: rp2040js reads an input pin nobody drives as low, whatever its pad's pull-up
//    or pull-down (it only reports them in `value`). On the chip a pin left open reads its
//    pull: a high through the pull-up, which is how an open e-stop switch or a cut wire reads
//    "open". `PadPulls` is the world outside the pins: each GPIO is driven high or low by the
//    test (`drive(n, level)`), or left open (`drive(n, null)`, the default), and then reads
//    its pad's pull (pull-up high, pull-down low; both or neither: the last level, as the bus
//    keeper or a floating input would).
// 9-12. USB. rp2040js has a device-mode USB controller and a scripted host, `USBCDC`, which
//    enumerates a CDC ACM device (only with EP0's max packet size 64, which the firmware uses)
//    and then exchanges bytes. `UsbCdcHost` drives `USBCDC` and fills its gaps:
// 9. OUT arms before enumeration: `USBCDC` hands bytes to an OUT buffer only when the firmware
//    arms it after enumeration (`onEndpointRead` once the endpoint is known); rp2040-hal arms
//    its bulk OUT buffer at bus reset, before that, so host-to-device bytes never arrived.
//    `UsbCdcHost` keeps each OUT arm (endpoint, size) and completes it with the host's next
//    bytes when it has some (`endpointReadDone`). That is also USB's flow control, as on the
//    wire: a device that does not re-arm its buffer gets nothing more; the host waits (NAK).
// 10. The line state: `USBCDC` sends SET_CONTROL_LINE_STATE with recipient Device, which
//    usbd-serial (rightly: CDC PSTN 6.3.12 addresses it to the communication interface)
//    rejects, so the device never saw DTR. `UsbCdcHost` sends its own request, recipient
//    Interface, wIndex 0 (the communication interface), whenever the host opens (DTR and RTS
//    up) or closes (both down) its port, one control transfer at a time.
// 11. IN timing: an IN buffer the firmware arms counts as taken at once (its buffer-status bit
//    is set on the spot, the data reaches the host 10 us later), whatever the host or the bus.
//    That flatters the firmware: it never waits for the bus and never meets a host that does
//    not read. `UsbCdcHost` takes each armed IN packet only while its host reads, on a
//    full-speed bus that carries at most 19 bulk packets of 64 bytes per 1 ms frame: every
//    bulk transaction, IN or OUT, whatever its length, holds the bus for 1/19 ms, one after
//    the other, and a packet completes (reaches the host, or the device's buffer) at the end
//    of its slot. A short packet takes the whole slot (on the wire it is shorter), so figures
//    err on the slow side. A host that stops reading leaves the IN buffer armed, as a real
//    host whose program and OS buffers are full does.
// 12. Suspend and unplugging: on the chip SIE_STATUS.SUSPENDED is write-one-to-clear;
//    rp2040js does not clear it, so the suspend interrupt would fire for ever. Writing it now
//    clears it. Unplugging (`UsbCdcHost.unplug`) stops all traffic, and 3 ms later the device
//    sees the suspend an idle bus signals; replugging is a new host: a bus reset (10 ms, as
//    rp2040js's `resetDevice`) and a new enumeration. `USBCDC` can enumerate only once, so
//    each plug-in gets a fresh one.
//    Not modelled: resume signalling, VBUS (the firmware forces VBUS detect, as a Pico must),
//    EP0 traffic's share of the bus, errors and retries on the wire.

import {
  ConsoleLogger,
  createSetupPacket,
  DataDirection,
  LogLevel,
  SetupRecipient,
  SetupType,
  USBCDC,
} from 'rp2040js';

const WATCHDOG_BASE = 0x40058;

/** Applies gaps 1 and 2 to a fresh `RP2040`: `uart.pl011` is each UART's model. */
export function patchEmulatorGaps(mcu) {
  mcu.logger = new ConsoleLogger(LogLevel.Error, true);
  for (const uart of mcu.uart) {
    uart.pl011 = new Pl011(mcu, uart);
  }
}

// ---- Gap 2: the PL011 ----

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

/** Gap 8: what drives each GPIO from outside the chip (see the header). */
export class PadPulls {
  constructor(mcu) {
    this.mcu = mcu;
    /** Per GPIO: `true`/`false` driven from outside, `null` open. */
    this.external = mcu.gpio.map(() => null);
    mcu.gpio.forEach((pin, n) => {
      pin.addListener(() => this.settle(n));
    });
  }

  /** Drives GPIO `n` from outside at `level`, or leaves it open (`null`). */
  drive(n, level) {
    this.external[n] = level;
    this.settle(n);
  }

  /** The level GPIO `n` reads now (its input, before any input override). */
  level(n) {
    return this.mcu.gpio[n].rawInputValue;
  }

  settle(n) {
    const pin = this.mcu.gpio[n];
    let level = this.external[n];
    if (level === null) {
      if (pin.pullupEnabled && !pin.pulldownEnabled) {
        level = true;
      } else if (pin.pulldownEnabled && !pin.pullupEnabled) {
        level = false;
      } else {
        return; // floating or bus keeper: stays where it was
      }
    }
    if (level !== pin.rawInputValue) {
      pin.setInputValue(level);
    }
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

/** Gap 5: ends a WFI/WFE sleep if an enabled interrupt is already pending (true if it did). */
export function wakeIfInterruptPending(core) {
  if (core.waiting && (core.pendingInterrupts & core.enabledInterrupts) !== 0) {
    core.waiting = false;
    return true;
  }
  return false;
}

// ---- Gap 7: flash writes through the boot ROM ----

/** The Pico's flash: 2 MiB (rp2040js maps 16 MiB). */
export const PICO_FLASH_BYTES = 2 * 1024 * 1024;
export const FLASH_SECTOR_BYTES = 4096;
export const FLASH_PAGE_BYTES = 256;
const FLASH_WINDOW_START = 0x10000000;
const FLASH_WINDOW_END = 0x14000000;
const SRAM_START = 0x20000000;
const SRAM_END = 0x20042000;
const ROM_BYTES = 0x4000;
/** Where the boot ROM keeps the 16-bit pointer to its function table. */
const ROM_FUNCTION_TABLE_POINTER = 0x14;
const THUMB_BX_LR = 0x4770;
const THUMB_BKPT = 0xbe00;
/**
 * The Pico's flash chip's erase and program times: Winbond W25Q80DV datasheet, AC electrical
 * characteristics, sector erase (4 KiB) tSE and page program tPP, typical and maximum.
 */
export const W25Q080_TIMING = {
  typical: { sectorEraseMs: 45, pageProgramMs: 0.7 },
  max: { sectorEraseMs: 400, pageProgramMs: 3 },
};
/** The routines modelled: ROM table code, name, breakpoint number. */
const FLASH_ROUTINES = [
  ['IF', 'connect_internal_flash'],
  ['EX', 'flash_exit_xip'],
  ['RE', 'flash_range_erase'],
  ['RP', 'flash_range_program'],
  ['FC', 'flash_flush_cache'],
  ['CX', 'flash_enter_cmd_xip'],
].map(([code, name], i) => ({ code, name, bkpt: 0xf0 + i }));

const hex = (value) => `0x${(value >>> 0).toString(16)}`;
const inFlashWindow = (address) =>
  address >>> 0 >= FLASH_WINDOW_START && address >>> 0 < FLASH_WINDOW_END;

/**
 * The flash chip: its contents (which survive power cycles), its timing, the erases and
 * programs done (`ops`), an armed power cut, worn bits.
 */
export class FlashChip {
  /**
   * @param {Uint8Array} image the flash array (rp2040js's, of the first chip powered on)
   * @param {object} [options]
   * @param {'typical'|'max'|{sectorEraseMs: number, pageProgramMs: number}} [options.timing]
   */
  constructor(image, { timing = 'typical' } = {}) {
    this.image = image;
    this.timing = timing;
    /** Every erase and program: `{ routine: 'erase'|'program', offset, bytes, nanos }`. */
    this.ops = [];
    this.cut = null;
    /** Offset -> bits a program cannot clear. */
    this.worn = new Map();
  }

  /** The erase and program times in use, ms. */
  get times() {
    return typeof this.timing === 'string' ? W25Q080_TIMING[this.timing] : this.timing;
  }

  /**
   * Arms a power cut: during the `call`-th `routine` ('erase' or 'program') from now, after
   * `bytes` bytes of its work (in address order; 0 = before any), with the bits in `mask` of
   * the next byte's change done (0 = none). The chip then stops at once (board.js powers it
   * off); nothing more is written.
   */
  cutPowerDuring({ routine, call = 1, bytes, mask = 0 }) {
    if (routine !== 'erase' && routine !== 'program') {
      throw new Error(`cutPowerDuring: routine must be 'erase' or 'program', not ${routine}`);
    }
    this.cut = { routine, call, bytes, mask, calls: 0 };
  }

  /** Bits of the byte at `offset` that no program can clear any more (a worn-out cell). */
  wearOut(offset, mask) {
    this.worn.set(offset, (this.worn.get(offset) ?? 0) | mask);
  }

  /** A copy of `length` bytes from `offset`. */
  read(offset, length) {
    return Uint8Array.from(this.image.subarray(offset, offset + length));
  }

  /** The armed cut if it falls in this call of `routine` (counting the call). */
  cutIn(routine) {
    if (!this.cut || this.cut.routine !== routine) {
      return null;
    }
    this.cut.calls++;
    if (this.cut.calls !== this.cut.call) {
      return null;
    }
    const cut = this.cut;
    this.cut = null;
    return cut;
  }
}

/** A view of the flash array whose stores fail the run (rp2040js writes flash through it). */
class StoreGuardedView extends DataView {
  constructor(buffer, onStore) {
    super(buffer);
    this.onStore = onStore;
  }

  setUint32(offset, value) {
    this.onStore(offset, value);
  }
}

/**
 * Gap 7: connects a fresh `RP2040` (after `loadBootrom`) to `chip`: the chip's array becomes
 * its flash, the six ROM routines trap into the model, stores into the flash window fail.
 * `onFault(message)` fails the run; `onPowerCut()` powers the chip off after this instruction.
 * Call after the board has set `mcu.onBreak` (breakpoints the model does not own go there).
 */
export function attachFlashChip(mcu, chip, { onFault, onPowerCut }) {
  const { core } = mcu;
  const buffer = chip.image.buffer;
  mcu.flash = chip.image;
  mcu.flash16 = new Uint16Array(buffer);
  mcu.flashView = new StoreGuardedView(buffer, (offset, value) => {
    const at = hex(FLASH_WINDOW_START + offset);
    onFault(
      `CPU store of ${hex(value)} into the flash window at ${at} (PC ${hex(core.PC)}): ` +
        'a real chip never writes flash that way',
    );
  });

  // The ROM function table: (code, 16-bit pointer) pairs, ending with code 0.
  const rom = new DataView(mcu.bootrom.buffer);
  const routines = new Map();
  for (let entry = rom.getUint16(ROM_FUNCTION_TABLE_POINTER, true); ; entry += 4) {
    const code = rom.getUint16(entry, true);
    if (code === 0) {
      break;
    }
    const name = String.fromCharCode(code & 0xff, code >> 8);
    const routine = FLASH_ROUTINES.find((r) => r.code === name);
    if (routine) {
      const address = rom.getUint16(entry + 2, true) & ~1;
      rom.setUint16(address, THUMB_BKPT | routine.bkpt, true);
      rom.setUint16(address + 2, THUMB_BX_LR, true);
      routines.set(routine.bkpt, routine);
    }
  }
  if (routines.size !== FLASH_ROUTINES.length) {
    const found = `${routines.size} of the ${FLASH_ROUTINES.length}`;
    throw new Error(`boot ROM function table: found ${found} flash routines`);
  }

  let connected = false;
  let xipOff = false;
  let saved = null;
  const guardReads = () => {
    saved = { readUint32: mcu.readUint32, readUint16: mcu.readUint16, readUint8: mcu.readUint8 };
    for (const [method, read] of Object.entries(saved)) {
      mcu[method] = (address) => {
        if (inFlashWindow(address)) {
          onFault(
            `flash read at ${hex(address)} while XIP is off (PC ${hex(core.PC)}): ` +
              'the chip is in command mode',
          );
        }
        return read.call(mcu, address);
      };
    }
  };
  const unguardReads = () => {
    for (const method of Object.keys(saved)) {
      delete mcu[method]; // back to rp2040js's own (prototype) methods
    }
    saved = null;
  };
  const busy = (ms) => {
    const nanos = ms * 1e6;
    core.cycles += Math.round((nanos * mcu.clkSys) / 1e9);
    mcu.clock.tick(nanos);
  };

  const erase = (offset, count) => {
    if (offset % FLASH_SECTOR_BYTES !== 0 || count % FLASH_SECTOR_BYTES !== 0 || count === 0) {
      return onFault(`flash_range_erase(${hex(offset)}, ${count}): not whole 4096-byte sectors`);
    }
    if (offset + count > PICO_FLASH_BYTES) {
      return onFault(`flash_range_erase(${hex(offset)}, ${count}): beyond the Pico's 2 MiB flash`);
    }
    chip.ops.push({ routine: 'erase', offset, bytes: count, nanos: mcu.clock.nanos });
    const cut = chip.cutIn('erase');
    for (let i = 0; i < count; i++) {
      if (cut && i === cut.bytes) {
        const old = chip.image[offset + i];
        chip.image[offset + i] = old | (~old & cut.mask & 0xff);
        return onPowerCut();
      }
      chip.image[offset + i] = 0xff;
    }
    busy((count / FLASH_SECTOR_BYTES) * chip.times.sectorEraseMs);
    if (cut) {
      onPowerCut(); // after the whole erase
    }
  };

  const program = (offset, data, count) => {
    if (offset % FLASH_PAGE_BYTES !== 0 || count % FLASH_PAGE_BYTES !== 0 || count === 0) {
      return onFault(`flash_range_program(${hex(offset)}, ${count}): not whole 256-byte pages`);
    }
    if (offset + count > PICO_FLASH_BYTES) {
      return onFault(`flash_range_program(${hex(offset)}, ${count}): beyond the 2 MiB flash`);
    }
    if (data < SRAM_START || data + count > SRAM_END) {
      return onFault(
        `flash_range_program: data at ${hex(data)} is not in SRAM ` +
          '(flash cannot be read while XIP is off)',
      );
    }
    chip.ops.push({ routine: 'program', offset, bytes: count, nanos: mcu.clock.nanos });
    const cut = chip.cutIn('program');
    for (let i = 0; i < count; i++) {
      const at = offset + i;
      const value = mcu.sram[data - SRAM_START + i] | (chip.worn.get(at) ?? 0);
      if (cut && i === cut.bytes) {
        chip.image[at] &= value | (~cut.mask & 0xff);
        return onPowerCut();
      }
      chip.image[at] &= value;
    }
    busy((count / FLASH_PAGE_BYTES) * chip.times.pageProgramMs);
    if (cut) {
      onPowerCut(); // after the whole program
    }
  };

  const otherBreak = mcu.onBreak;
  mcu.onBreak = (code) => {
    const routine = routines.get(code);
    if (!routine || core.PC >>> 0 >= ROM_BYTES) {
      return otherBreak(code); // not one of the patched entries
    }
    const lr = core.LR >>> 0;
    if (lr < SRAM_START || lr >= SRAM_END) {
      return onFault(
        `${routine.name} called from ${hex(lr)}, not from SRAM: ` +
          "the caller's code would be fetched from flash while XIP is off",
      );
    }
    if (!core.PM) {
      return onFault(
        `${routine.name} called with interrupts enabled (PRIMASK clear): ` +
          'a handler in flash could run while XIP is off',
      );
    }
    const [r0, r1, r2] = core.registers;
    switch (routine.code) {
      case 'IF':
        connected = true;
        break;
      case 'EX':
        if (!connected) {
          return onFault('flash_exit_xip before connect_internal_flash');
        }
        if (!xipOff) {
          xipOff = true;
          guardReads();
        }
        break;
      case 'RE':
      case 'RP':
        if (!xipOff) {
          return onFault(`${routine.name} while XIP is on (flash_exit_xip first)`);
        }
        if (routine.code === 'RE') {
          return erase(r0 >>> 0, r1 >>> 0);
        }
        return program(r0 >>> 0, r1 >>> 0, r2 >>> 0);
      case 'FC':
        break;
      case 'CX':
        connected = false;
        if (xipOff) {
          xipOff = false;
          unguardReads();
        }
        break;
    }
  };
}

// ---- Gaps 9-12: USB ----

// USB controller registers and DPRAM (RP2040 datasheet, 4.1.4).
const SIE_STATUS = 0x50;
const SIE_SUSPENDED = 1 << 4;
const EP0_IN_BUFFER_CONTROL = 0x80;
const BUF_CTRL_AVAILABLE = 1 << 10;
const BUF_CTRL_FULL = 1 << 15;
const BUF_CTRL_LEN_MASK = 0x3ff;
/** CDC PSTN SET_CONTROL_LINE_STATE; DTR is bit 0 of its value, RTS bit 1. */
const SET_CONTROL_LINE_STATE = 0x22;
const SET_LINE_CODING = 0x20;
const GET_DESCRIPTOR = 6;
const DTR_AND_RTS = 0b11;
/** The communication interface of the firmware's CDC ACM function. */
const CDC_COMM_INTERFACE = 0;
/** Full speed: at most 19 bulk packets of 64 bytes per 1 ms frame (USB 2.0, table 5-10). */
export const BULK_PACKETS_PER_FRAME = 19;
const FRAME_NANOS = 1e6;
/** One bulk transaction's share of the bus, either direction (gap 11). */
export const BULK_PACKET_NANOS = FRAME_NANOS / BULK_PACKETS_PER_FRAME;
export const BULK_PACKET_BYTES = 64;
/** An idle bus for this long makes a device suspend (USB 2.0, 7.1.7.6). */
const SUSPEND_AFTER_NANOS = 3e6;

/**
 * A USB host with a CDC ACM (serial) port on the emulated chip's USB controller: it
 * enumerates the firmware, opens and closes its port (DTR), sends bytes and receives what the
 * firmware sends, on a full-speed bus, and can stop reading, be unplugged and plugged in again
 * (gaps 9-12). `onData(bytes)` receives the device's bytes in order.
 */
export class UsbCdcHost {
  /**
   * @param {object} options
   * @param {boolean} [options.open] open the port (DTR) as soon as the device is configured,
   *   as a terminal program waiting for the port does (default true)
   * @param {(bytes: Uint8Array) => void} [options.onData]
   */
  constructor({ open = true, onData = () => {} } = {}) {
    this.wantOpen = open;
    this.onData = onData;
    this.plugged = true;
    /** The host's program reads (IN packets are taken). */
    this.reading = true;
    /** Bytes waiting to be sent, in order. */
    this.pending = [];
    this.pendingHead = 0;
    /** Times the device was configured (one per plug-in or chip reset). */
    this.enumerations = 0;
    /** Packets each way so far, and bytes. */
    this.inPackets = 0;
    this.outPackets = 0;
    this.inBytes = 0;
    this.outBytes = 0;
    /** Called with (bytes, nanos) when an OUT packet reaches the device's buffer. */
    this.onOutDelivered = null;
  }

  /** Puts the host on a fresh chip's USB port (at power-on, or after a chip reset). */
  attach(mcu) {
    this.mcu = mcu;
    this.usb = mcu.usbCtrl;
    this.clock = mcu.clock;
    this.busFreeNanos = 0;
    this.inAlarm = this.clock.createAlarm(() => this.inTaken());
    this.outAlarm = this.clock.createAlarm(() => this.outDelivered());
    this.suspendAlarm = this.clock.createAlarm(() => this.suspendDevice());
    // Gap 12: SUSPENDED is write-one-to-clear.
    const usb = this.usb;
    const writeRegister = usb.writeUint32.bind(usb);
    usb.writeUint32 = (offset, value) => {
      writeRegister(offset, value);
      if (offset === SIE_STATUS && usb.rawWriteValue & SIE_SUSPENDED) {
        usb.sieStatus &= ~SIE_SUSPENDED;
        usb.sieStatusUpdated();
      }
    };
    // Gap 11: bulk IN buffers are taken by the host, not by the controller on its own.
    const dpramUpdated = usb.DPRAMUpdated.bind(usb);
    usb.DPRAMUpdated = (offset, value) => {
      if (!this.inBufferWrite(offset, value)) {
        dpramUpdated(offset, value);
      }
    };
    this.newBus();
    if (this.plugged) {
      this.plugIn(false);
    }
  }

  /** Nothing armed, nothing in flight: a chip just reset or a host just plugged in. */
  newBus() {
    this.outArms = new Map(); // endpoint -> size (gap 9)
    this.outPacket = null; // { endpoint, bytes } on the wire
    this.outAlarm.cancel();
    this.inArm = null; // { endpoint, offset } (gap 11)
    this.inScheduled = false;
    this.inAlarm.cancel();
    this.controlQueue = [];
    this.control = null;
    this.configured = false;
    this.portOpen = false;
  }

  /**
   * A fresh `USBCDC` enumerates the device. `reset`: the host resets the bus itself (a
   * replug); at power-on the firmware's enabling the controller does (rp2040js's
   * `onUSBEnabled`).
   */
  plugIn(reset) {
    const cdc = new USBCDC(this.usb);
    this.cdc = cdc;
    // Gap 10: the line state goes to the interface, when the host wants it.
    cdc.cdcSetControlLineState = () => {
      cdc.initialized = true;
    };
    cdc.onDeviceConnected = () => {
      this.configured = true;
      this.enumerations++;
      if (this.wantOpen) {
        this.setLineState(true);
      }
      this.nextControl();
      this.sendSome();
    };
    // Gap 9: keep OUT arms (the bulk OUT endpoint is armed before `USBCDC` knows it).
    cdc.usb.onEndpointRead = (endpoint, size) => {
      if (endpoint !== 0) {
        this.outArms.set(endpoint, size);
        this.sendSome();
      } else if (this.control?.out) {
        // The data stage of our control OUT request.
        this.usb.endpointReadDone(0, this.control.out);
        this.control.out = null;
      }
    };
    const endpointWrite = this.usb.onEndpointWrite;
    this.usb.onEndpointWrite = (endpoint, buffer) => {
      if (endpoint === 0 && this.control) {
        this.controlPacket(buffer); // ours, not `USBCDC`'s enumeration
        return;
      }
      endpointWrite(endpoint, buffer);
    };
    if (reset) {
      this.usb.resetDevice();
    }
  }

  // ---- the host's side: the port ----

  /** The device is configured and the host has its port open (DTR up). */
  get open() {
    return this.portOpen;
  }

  /** Opens the port (DTR and RTS up), as a terminal program does. */
  openPort() {
    this.wantOpen = true;
    if (this.configured && this.plugged) {
      this.setLineState(true);
    }
  }

  /** Closes the port (DTR and RTS down). */
  closePort() {
    this.wantOpen = false;
    if (this.configured && this.plugged) {
      this.setLineState(false);
    }
  }

  /** Queues bytes to send; they go as the device takes them, at most 64 to a packet. */
  send(bytes) {
    for (const byte of bytes) {
      this.pending.push(byte & 0xff);
    }
    this.sendSome();
  }

  /** Bytes queued by `send` that the device has not taken yet. */
  get unsent() {
    return this.pending.length - this.pendingHead;
  }

  /** Stops or resumes reading (a stopped host leaves the device's IN buffer full). */
  setReading(reading) {
    this.reading = reading;
    this.scheduleIn();
  }

  /** Pulls the cable: all traffic stops; the device sees a suspend 3 ms later. */
  unplug() {
    if (!this.plugged) {
      return;
    }
    this.plugged = false;
    this.configured = false;
    this.portOpen = false;
    this.inAlarm.cancel();
    this.inScheduled = false;
    this.outAlarm.cancel();
    this.outPacket = null;
    this.pending = [];
    this.pendingHead = 0;
    this.suspendAlarm.schedule(SUSPEND_AFTER_NANOS);
  }

  /** Plugs the cable back in: a new host session (bus reset, enumeration, port per `open`). */
  replug({ open = true } = {}) {
    if (this.plugged) {
      return;
    }
    this.suspendAlarm.cancel();
    this.wantOpen = open;
    this.plugged = true;
    this.newBus();
    this.plugIn(true);
  }

  suspendDevice() {
    if (!this.plugged) {
      this.usb.sieStatus |= SIE_SUSPENDED;
      this.usb.sieStatusUpdated();
    }
  }

  // ---- control transfers (gap 10; one at a time, after enumeration) ----

  setLineState(open) {
    this.controlQueue.push({
      setup: {
        dataDirection: DataDirection.HostToDevice,
        type: SetupType.Class,
        recipient: SetupRecipient.Interface,
        bRequest: SET_CONTROL_LINE_STATE,
        wValue: open ? DTR_AND_RTS : 0,
        wIndex: CDC_COMM_INTERFACE,
        wLength: 0,
      },
      done: () => {
        this.portOpen = open;
        this.scheduleIn();
      },
    });
    this.nextControl();
  }

  /**
   * Sets the port's line coding (SET_LINE_CODING, as a terminal program does when opening a
   * serial port at `baud`, 8N1); calls `done()` when the device has acknowledged it.
   */
  setLineCoding(baud, done = () => {}) {
    const coding = new Uint8Array(7);
    new DataView(coding.buffer).setUint32(0, baud, true);
    coding[6] = 8; // 1 stop bit, no parity, 8 data bits
    this.controlQueue.push({
      setup: {
        dataDirection: DataDirection.HostToDevice,
        type: SetupType.Class,
        recipient: SetupRecipient.Interface,
        bRequest: SET_LINE_CODING,
        wValue: 0,
        wIndex: CDC_COMM_INTERFACE,
        wLength: coding.length,
      },
      out: coding,
      done,
    });
    this.nextControl();
  }

  /**
   * Reads a descriptor with GET_DESCRIPTOR (`type` 1 device, 3 string; `index`; `langId` for
   * strings) once the device is configured; calls `done(bytes)`.
   */
  readDescriptor(type, index, done, { langId = 0, length = 255 } = {}) {
    this.controlQueue.push({
      setup: {
        dataDirection: DataDirection.DeviceToHost,
        type: SetupType.Standard,
        recipient: SetupRecipient.Device,
        bRequest: GET_DESCRIPTOR,
        wValue: (type << 8) | index,
        wIndex: langId,
        wLength: length,
      },
      data: [],
      done,
    });
    this.nextControl();
  }

  nextControl() {
    if (this.control || this.controlQueue.length === 0 || !this.configured || !this.plugged) {
      return;
    }
    this.control = this.controlQueue.shift();
    this.usb.sendSetupPacket(createSetupPacket(this.control.setup));
  }

  /** A packet the device sent on endpoint 0 for our request: data, or the status stage. */
  controlPacket(buffer) {
    const control = this.control;
    if (control.data) {
      control.data.push(...buffer);
      // The data stage ends with a short packet or when the length asked for has come (the
      // status stage, an OUT ZLP, is not sent: usb-device takes the next SETUP all the same).
      if (buffer.length === BULK_PACKET_BYTES && control.data.length < control.setup.wLength) {
        return;
      }
    }
    this.control = null;
    control.done(control.data && Uint8Array.from(control.data));
    this.nextControl();
  }

  // ---- the bus (gap 11) ----

  /** Reserves the bus for one bulk transaction; returns when it ends. */
  busSlot() {
    const start = Math.max(this.clock.nanos, this.busFreeNanos);
    this.busFreeNanos = start + BULK_PACKET_NANOS;
    return this.busFreeNanos;
  }

  get trafficAllowed() {
    return this.plugged && this.configured && this.cdc?.outEndpoint > 0;
  }

  /** Sends the next packet if the device has an OUT buffer armed and bytes wait. */
  sendSome() {
    if (!this.trafficAllowed || this.outPacket || this.unsent === 0) {
      return;
    }
    const endpoint = this.cdc.outEndpoint;
    const size = this.outArms.get(endpoint);
    if (size === undefined) {
      return; // the device has not re-armed: it cannot take more, the host waits (NAK)
    }
    this.outArms.delete(endpoint);
    const count = Math.min(size, BULK_PACKET_BYTES, this.unsent);
    const bytes = Uint8Array.from(this.pending.slice(this.pendingHead, this.pendingHead + count));
    this.pendingHead += count;
    if (this.pendingHead === this.pending.length) {
      this.pending = [];
      this.pendingHead = 0;
    }
    this.outPacket = { endpoint, bytes };
    this.outAlarm.schedule(this.busSlot() - this.clock.nanos);
  }

  /** The OUT packet's slot ended: it is in the device's buffer (buffer-status bit set). */
  outDelivered() {
    const { endpoint, bytes } = this.outPacket;
    this.outPacket = null;
    this.outPackets++;
    this.outBytes += bytes.length;
    this.usb.finishRead(endpoint, bytes);
    this.onOutDelivered?.(bytes, this.clock.nanos);
    this.sendSome();
  }

  /**
   * A write to an IN endpoint's buffer control (endpoints 1..15; endpoint 0 is `USBCDC`'s):
   * arming it (AVAILABLE) waits for the host; a write that clears AVAILABLE (the firmware
   * resetting its endpoints) withdraws the arm. Returns whether this was such a write.
   */
  inBufferWrite(offset, value) {
    const index = (offset - EP0_IN_BUFFER_CONTROL) >> 3;
    const isIn =
      offset >= EP0_IN_BUFFER_CONTROL && offset < EP0_IN_BUFFER_CONTROL + 16 * 8 && !(offset & 4);
    if (!isIn || index === 0) {
      return false;
    }
    this.inAlarm.cancel();
    this.inScheduled = false;
    this.inArm = value & BUF_CTRL_AVAILABLE ? { endpoint: index, offset } : null;
    this.scheduleIn();
    return true;
  }

  /** Has the host take the armed IN packet in the next free bus slot, if it reads. */
  scheduleIn() {
    const takes = this.reading && this.portOpen && this.trafficAllowed;
    if (!this.inArm || this.inScheduled || !takes) {
      return;
    }
    this.inScheduled = true;
    this.inAlarm.schedule(this.busSlot() - this.clock.nanos);
  }

  inTaken() {
    this.inScheduled = false;
    const arm = this.inArm;
    if (!arm || !this.reading || !this.plugged) {
      return;
    }
    const view = this.mcu.usbDPRAMView;
    const control = view.getUint32(arm.offset, true);
    const length = control & BUF_CTRL_LEN_MASK;
    const start = this.usb.getEndpointBufferOffset(arm.endpoint, false);
    const data = this.mcu.usbDPRAM.slice(start, start + length);
    view.setUint32(arm.offset, control & ~(BUF_CTRL_AVAILABLE | BUF_CTRL_FULL), true);
    this.inArm = null;
    this.inPackets++;
    this.inBytes += length;
    this.usb.indicateBufferReady(arm.endpoint, false);
    if (length > 0) {
      this.onData(data);
    }
  }
}
