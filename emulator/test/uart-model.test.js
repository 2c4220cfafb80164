// The PL011 model of src/gaps/uart.js (gap 2) on its own: a bare RP2040 with no firmware,
// UART0 programmed and read through its registers as firmware would, bytes sent by the paced
// host (gap 3), time advanced on the emulated clock. Expected figures come from the RP2040
// datasheet (4.2, UART) and the PL011 TRM: 10 bit periods per 8N1 byte, FIFO levels of
// 1/8..7/8 of 32 entries, the receive timeout after 32 bit periods, 32-entry TX FIFO.

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { RP2040 } from 'rp2040js';

import { PacedUartInput, patchEmulatorGaps } from '../src/gaps/index.js';

const UARTDR = 0x00;
const UARTRSR = 0x04;
const UARTFR = 0x18;
const UARTIBRD = 0x24;
const UARTFBRD = 0x28;
const UARTLCR_H = 0x2c;
const UARTCR = 0x30;
const UARTIFLS = 0x34;
const UARTIMSC = 0x38;
const UARTRIS = 0x3c;
const UARTMIS = 0x40;
const UARTICR = 0x44;

const FR_BUSY = 1 << 3;
const FR_RXFE = 1 << 4;
const FR_TXFF = 1 << 5;
const FR_RXFF = 1 << 6;
const FR_TXFE = 1 << 7;
const INT_RX = 1 << 4;
const INT_TX = 1 << 5;
const INT_RT = 1 << 6;
const INT_OE = 1 << 10;
const DR_OE = 1 << 11;
const RSR_OE = 1 << 3;
const LCR_H_8N1_FIFO = 0x70; // WLEN 8 bits, FEN
const CR_ENABLED = 0x301; // UARTEN, TXE, RXE
const UART0_IRQ = 20;

/** IBRD/FBRD for `baud` as the RP2040 SDK and rp2040-hal compute them. */
function divisors(clkPeri, baud) {
  const div = Math.floor((8 * clkPeri) / baud);
  return { ibrd: div >> 7, fbrd: ((div & 0x7f) + 1) >> 1 };
}

/** The exact bit period of the divisors for `baud` at 125 MHz, ns. */
function bitNanos(baud) {
  const { ibrd, fbrd } = divisors(125e6, baud);
  return (16 * (ibrd + fbrd / 64) * 1e9) / 125e6;
}

/** A bare chip with UART0 set up like firmware does: 8N1, FIFOs on, `baud`, levels `ifls`. */
function bareUart({ baud = 115200, ifls = 0x12, imsc = 0 } = {}) {
  const mcu = /** @type {import('../src/gaps/index.js').Mcu} */ (new RP2040());
  patchEmulatorGaps(mcu);
  const uart = mcu.uart[0];
  const chip = {
    mcu,
    uart,
    model: uart.pl011,
    host: new PacedUartInput(mcu, uart),
    sent: [], // { byte, nanos } as each stop bit ended
    read: (offset) => uart.readUint32(offset),
    write: (offset, value) => uart.writeUint32(offset, value),
    /** Advances emulated time to `nanos` (absolute), firing alarms on the way. */
    runTo: (nanos) => mcu.clock.tick(nanos - mcu.clock.nanos),
    get nanos() {
      return mcu.clock.nanos;
    },
    get irq() {
      return (mcu.core.pendingInterrupts & (1 << UART0_IRQ)) !== 0;
    },
    setBaud(rate) {
      const { ibrd, fbrd } = divisors(mcu.clkPeri, rate);
      chip.write(UARTIBRD, ibrd);
      chip.write(UARTFBRD, fbrd);
      chip.write(UARTLCR_H, chip.read(UARTLCR_H)); // the PL011 latches the divisor here
    },
  };
  uart.onByte = (byte) => chip.sent.push({ byte, nanos: mcu.clock.nanos });
  const { ibrd, fbrd } = divisors(mcu.clkPeri, baud);
  chip.write(UARTIBRD, ibrd);
  chip.write(UARTFBRD, fbrd);
  chip.write(UARTLCR_H, LCR_H_8N1_FIFO);
  chip.write(UARTIFLS, ifls);
  chip.write(UARTIMSC, imsc);
  chip.write(UARTCR, CR_ENABLED);
  return chip;
}

/** Reads the RX FIFO empty: the UARTDR values, oldest first. */
function drain(chip) {
  const values = [];
  while (!(chip.read(UARTFR) & FR_RXFE)) {
    values.push(chip.read(UARTDR));
  }
  return values;
}

const near = (actual, expected, what) =>
  assert.ok(Math.abs(actual - expected) < 1, `${what}: ${actual} ns, expected ${expected} ns`);

test('bit periods: 8,680 ns at 115,200 baud and 1,086 ns at 921,600 (the divisors the SDK picks)', () => {
  near(bitNanos(115200), 8680, '115,200');
  near(bitNanos(921600), 1086, '921,600');
  const chip = bareUart();
  near(chip.model.bitNanos, 8680, 'model');
  near(chip.host.byteNanos, 86_800, 'host byte time');
});

for (const baud of [115200, 921600]) {
  const byte = 10 * bitNanos(baud);

  test(`RX level interrupt at ${baud} baud: RXRIS when the 8th byte arrives, not before`, () => {
    const chip = bareUart({ baud, ifls: 1 << 3, imsc: INT_RX }); // RX level 1/4: 8 entries
    chip.host.send(Buffer.from('abcdefghij'));
    chip.runTo(7 * byte + 1);
    assert.equal(chip.read(UARTRIS) & INT_RX, 0, '7 bytes in');
    assert.equal(chip.irq, false);
    chip.runTo(8 * byte - 1);
    assert.equal(chip.read(UARTRIS) & INT_RX, 0, 'just before the 8th stop bit ends');
    chip.runTo(8 * byte + 1);
    assert.equal(chip.read(UARTRIS) & INT_RX, INT_RX, 'the 8th byte is in');
    assert.equal(chip.read(UARTMIS), INT_RX);
    assert.equal(chip.irq, true, 'the NVIC line follows MIS');
    // Reading takes the fill below the level: RXRIS clears, and the line drops.
    assert.equal(chip.read(UARTDR), 'a'.charCodeAt(0));
    assert.equal(chip.read(UARTRIS) & INT_RX, 0);
    assert.equal(chip.irq, false);
    // The 9th byte takes it back to 8.
    chip.runTo(9 * byte + 1);
    assert.equal(chip.read(UARTRIS) & INT_RX, INT_RX);
    // Masked: raw status stays, MIS and the line do not.
    chip.write(UARTIMSC, 0);
    assert.equal(chip.read(UARTRIS) & INT_RX, INT_RX);
    assert.equal(chip.read(UARTMIS), 0);
    assert.equal(chip.irq, false);
  });

  test(`RX timeout at ${baud} baud: RTRIS 32 bit periods after the last byte, while data waits`, () => {
    const chip = bareUart({ baud, ifls: 1 << 3, imsc: INT_RX | INT_RT });
    const timeout = 32 * bitNanos(baud);
    chip.host.send(Buffer.from('xyz'));
    const lastByte = 3 * byte;
    chip.runTo(lastByte + timeout - 1);
    assert.equal(chip.read(UARTRIS) & (INT_RX | INT_RT), 0, 'below the level, before the timeout');
    assert.equal(chip.irq, false);
    chip.runTo(lastByte + timeout + 1);
    assert.equal(chip.read(UARTRIS) & INT_RT, INT_RT, 'timed out');
    assert.equal(chip.irq, true);
    // Reading some leaves it set; reading the FIFO empty clears it.
    chip.read(UARTDR);
    assert.equal(chip.read(UARTRIS) & INT_RT, INT_RT);
    assert.deepEqual(drain(chip), [...Buffer.from('yz')]);
    assert.equal(chip.read(UARTRIS) & INT_RT, 0);
    assert.equal(chip.irq, false);

    // Each byte restarts the count: bytes 20 bit periods apart never time out.
    const start = chip.nanos;
    for (let i = 0; i < 5; i++) {
      chip.runTo(start + i * 20 * bitNanos(baud));
      chip.host.send([0x41 + i]);
    }
    const last = start + 4 * 20 * bitNanos(baud) + byte;
    chip.runTo(last + timeout - 1);
    assert.equal(chip.read(UARTRIS) & INT_RT, 0, 'timed out between bytes');
    chip.runTo(last + timeout + 1);
    assert.equal(chip.read(UARTRIS) & INT_RT, INT_RT);

    // UARTICR clears it, but with data still waiting and nothing new it comes back (the count
    // is not restarted by the clear): one bit period later.
    chip.write(UARTICR, INT_RT);
    assert.equal(chip.read(UARTRIS) & INT_RT, 0);
    assert.equal(chip.irq, false);
    chip.runTo(chip.nanos + bitNanos(baud) + 1);
    assert.equal(chip.read(UARTRIS) & INT_RT, INT_RT, 'the timeout condition still holds');
    drain(chip);
    chip.write(UARTICR, INT_RT);
    chip.runTo(chip.nanos + 100 * bitNanos(baud));
    assert.equal(chip.read(UARTRIS) & INT_RT, 0, 'an empty FIFO does not time out');
  });
}

test('RX levels 1/8, 1/4, 1/2, 3/4, 7/8 of 32 entries: 4, 8, 16, 24, 28', () => {
  for (const [select, level] of [
    [0, 4],
    [1, 8],
    [2, 16],
    [3, 24],
    [4, 28],
  ]) {
    const chip = bareUart({ ifls: select << 3 });
    chip.host.send(Buffer.alloc(32, 0x55));
    chip.runTo((level - 1) * 86_800 + 1);
    assert.equal(chip.read(UARTRIS) & INT_RX, 0, `level ${level}: set early`);
    chip.runTo(level * 86_800 + 1);
    assert.equal(chip.read(UARTRIS) & INT_RX, INT_RX, `level ${level}: not set`);
  }
  // Reserved selections are a firmware bug: the run stops.
  assert.throws(() => bareUart({ ifls: 5 << 3 }), /UARTIFLS/);
});

test('overrun: a byte that finds the FIFO full is lost and counted; RSR.OE, OERIS, OE on the next byte', () => {
  const chip = bareUart({ imsc: INT_OE });
  const bytes = Buffer.from('0123456789abcdefghijklmnopqrstuvwxyzABCD'); // 40
  chip.host.send(bytes);
  chip.runTo(32 * 86_800 + 1);
  assert.equal(chip.read(UARTFR) & FR_RXFF, FR_RXFF, '32 entries: full');
  assert.equal(chip.read(UARTRSR), 0, 'no overrun yet');
  chip.runTo(33 * 86_800 + 1);
  assert.equal(chip.model.rxOverrunBytes, 1);
  assert.equal(chip.read(UARTRSR) & RSR_OE, RSR_OE, 'RSR.OE set at the overrun');
  assert.equal(chip.read(UARTRIS) & INT_OE, INT_OE);
  assert.equal(chip.irq, true);
  chip.runTo(40 * 86_800 + 1);
  assert.equal(chip.model.rxOverrunBytes, 8, 'bytes 33..40 lost');

  // The 32 in the FIFO are the first 32 sent, unflagged.
  const values = drain(chip);
  assert.deepEqual(values, [...bytes.subarray(0, 32)]);
  // RSR.OE stays until written (reading does not clear it).
  assert.equal(chip.read(UARTRSR) & RSR_OE, RSR_OE);
  // The next byte that gets in carries OE; the one after it does not.
  chip.host.send(Buffer.from('!?'));
  chip.runTo(chip.nanos + 2 * 86_800 + 1);
  assert.deepEqual(drain(chip), ['!'.charCodeAt(0) | DR_OE, '?'.charCodeAt(0)]);
  // Any write to UARTRSR (UARTECR) clears it; UARTICR clears OERIS.
  chip.write(UARTRSR, 0);
  assert.equal(chip.read(UARTRSR), 0);
  chip.write(UARTICR, INT_OE);
  assert.equal(chip.read(UARTRIS) & INT_OE, 0);
  assert.equal(chip.irq, false);
  assert.equal(chip.model.rxBytes, 34);
});

test('a receiver that UARTCR disables ignores what arrives (counted)', () => {
  const chip = bareUart();
  chip.write(UARTCR, 0x101); // UARTEN, TXE: RXE off
  chip.host.send(Buffer.from('abc'));
  chip.runTo(4 * 86_800);
  assert.equal(chip.read(UARTFR) & FR_RXFE, FR_RXFE);
  assert.equal(chip.model.rxDisabledBytes, 3);
});

test('TX: 100 bytes through the FIFO take 100 x 86.8 us at 115,200; TXFF, TXFE and BUSY follow', () => {
  const chip = bareUart();
  assert.equal(chip.read(UARTFR) & (FR_TXFE | FR_BUSY | FR_TXFF), FR_TXFE, 'idle');
  const data = Buffer.from(Array.from({ length: 100 }, (_, i) => 0x20 + (i % 90)));
  let written = 0;
  const start = chip.nanos;
  // Fill the FIFO as firmware does: write while TXFF is clear.
  const fill = () => {
    while (written < data.length && !(chip.read(UARTFR) & FR_TXFF)) {
      chip.write(UARTDR, data[written++]);
    }
  };
  fill();
  // The first byte went straight to the shift register: 33 bytes in flight.
  assert.equal(written, 33);
  assert.equal(chip.read(UARTFR) & (FR_TXFF | FR_BUSY | FR_TXFE), FR_TXFF | FR_BUSY);
  while (chip.sent.length < data.length) {
    chip.runTo(chip.nanos + 10_000);
    fill();
  }
  assert.deepEqual(Buffer.from(chip.sent.map((s) => s.byte)), data);
  // One byte every 10 bit periods, back to back; the first starts within 1/16 bit.
  const first = chip.sent[0].nanos - start;
  assert.ok(first >= 86_800 - 1 && first <= 86_800 + 8680 / 16 + 1, `first byte after ${first} ns`);
  for (let i = 1; i < chip.sent.length; i++) {
    near(chip.sent[i].nanos - chip.sent[i - 1].nanos, 86_800, `byte ${i}`);
  }
  near(chip.sent[99].nanos - chip.sent[0].nanos, 99 * 86_800, 'total');
  // BUSY until the last stop bit has ended.
  assert.equal(chip.model.txBytes, 100);
  assert.equal(chip.read(UARTFR) & (FR_TXFE | FR_BUSY), FR_TXFE);
});

test('TX: a byte written while TXFF is lost (counted, reported)', () => {
  const chip = bareUart();
  const lost = [];
  chip.model.onTxLost = (byte) => lost.push(byte);
  for (let i = 0; i < 35; i++) {
    chip.write(UARTDR, 0x30 + i);
  }
  assert.equal(chip.model.txLostBytes, 2);
  assert.deepEqual(lost, [0x30 + 33, 0x30 + 34]);
  chip.runTo(40 * 86_800);
  assert.equal(chip.sent.length, 33);
});

test('TX interrupt: set when the transmitter takes the fill to the level or below, cleared by writes above it', () => {
  const chip = bareUart({ ifls: 2, imsc: INT_TX }); // TX level 1/2: 16
  // Never set on a FIFO nobody wrote to (the PL011's TX interrupt is edge-based).
  chip.runTo(1e6);
  assert.equal(chip.read(UARTRIS) & INT_TX, 0);
  // Nor by bytes that never took the fill above the level.
  for (let i = 0; i < 3; i++) {
    chip.write(UARTDR, 0x41);
  }
  chip.runTo(2e6);
  assert.equal(chip.sent.length, 3);
  assert.equal(chip.read(UARTRIS) & INT_TX, 0);
  for (let i = 0; i < 21; i++) {
    chip.write(UARTDR, 0x41);
  }
  // 1 shifting, 20 in the FIFO: the fill reaches 16 when the 5th byte starts shifting.
  const start = chip.nanos;
  chip.runTo(start + 3 * 86_800 + 1000);
  assert.equal(chip.read(UARTRIS) & INT_TX, 0, '17 in the FIFO');
  chip.runTo(start + 4 * 86_800 + 1000);
  assert.equal(chip.read(UARTRIS) & INT_TX, INT_TX, '16 in the FIFO');
  assert.equal(chip.irq, true);
  chip.write(UARTDR, 0x42); // 17: above the level again
  assert.equal(chip.read(UARTRIS) & INT_TX, 0);
  chip.runTo(chip.nanos + 86_800);
  assert.equal(chip.read(UARTRIS) & INT_TX, INT_TX);
  chip.write(UARTICR, INT_TX);
  assert.equal(chip.read(UARTRIS) & INT_TX, 0);
  assert.equal(chip.irq, false);
});

test('a baud change (IBRD, FBRD, then LCR_H) applies from the next byte shifted out', () => {
  const chip = bareUart();
  chip.write(UARTDR, 0x31);
  chip.write(UARTDR, 0x32);
  // Half-way through the first byte the firmware switches to 921,600.
  chip.runTo(40_000);
  chip.setBaud(921600);
  chip.runTo(200_000);
  assert.equal(chip.sent.length, 2);
  near(chip.sent[0].nanos, 86_800, 'the byte on the wire keeps its rate');
  // The second starts at the next Baud16 tick of the new rate after the first ended.
  const tick = 1086 / 16;
  const gap = chip.sent[1].nanos - chip.sent[0].nanos;
  assert.ok(gap >= 10_860 - 1 && gap <= 10_860 + tick + 1, `second byte ${gap} ns later`);
  // The host follows the latched rate too.
  near(chip.host.byteNanos, 10_860, 'host byte time');
  assert.equal(Math.round(chip.host.baud), 920810);
});

test('frame length from UARTLCR_H: 8N2 is 11 bits, 7E1 is 10 bits (7 data bits reach the host)', () => {
  const chip = bareUart();
  chip.write(UARTLCR_H, LCR_H_8N1_FIFO | (1 << 3)); // STP2
  chip.write(UARTDR, 0xff);
  chip.write(UARTDR, 0xff);
  chip.runTo(1e6);
  near(chip.sent[1].nanos - chip.sent[0].nanos, 11 * 8680, '8N2');
  chip.write(UARTLCR_H, 0x50 | (1 << 1) | (1 << 2)); // WLEN 7, FEN, PEN, EPS
  chip.write(UARTDR, 0xff);
  chip.write(UARTDR, 0xff);
  chip.runTo(2e6);
  near(chip.sent[3].nanos - chip.sent[2].nanos, 10 * 8680, '7E1');
  assert.equal(chip.sent[3].byte, 0x7f);
});

test('the same inputs give the same instants (deterministic)', () => {
  const script = () => {
    const chip = bareUart({ baud: 921600, ifls: 1 << 3, imsc: INT_RX | INT_RT });
    const events = [];
    chip.host.send(Buffer.from('pose 1 2 3 4 5 6\n'));
    for (let t = 0; t < 400_000; t += 997) {
      chip.runTo(t);
      if (chip.irq) {
        const values = drain(chip);
        events.push([chip.nanos, values.length]);
        for (const v of values) {
          chip.write(UARTDR, v);
        }
      }
    }
    return { events, sent: chip.sent };
  };
  assert.deepEqual(script(), script());
});
