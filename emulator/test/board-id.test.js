// Two boards on one computer are told apart (README.md, "The USB port"), through the real
// firmware ELF: the board's id is its flash chip's unique ID (the W25Q080's Read Unique ID,
// modelled per board in src/gaps/flash.js, gap 14), read at power-up; the USB device's serial
// number (its device descriptor's iSerialNumber string, read by the scripted host) and the
// banner on both links show it, as 16 upper-case hexadecimal digits, most significant first.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { BANNER, EmulatedBoard } from '../src/chip/board.js';
import { DEFAULT_FLASH_UNIQUE_ID } from '../src/gaps/index.js';
import { firmwareBootrom } from '../src/test-support/e2e-support.js';

// USB 2.0, 9.6.1 and 9.6.7: the device descriptor's iSerialNumber, string descriptors.
const DESCRIPTOR_DEVICE = 1;
const DESCRIPTOR_STRING = 3;
const I_SERIAL_NUMBER = 16;
const LANG_EN_US = 0x0409;

let bootrom;
before(() => {
  bootrom = firmwareBootrom();
});

/** The id as README.md says it is shown. */
function digits(id) {
  return id.toString(16).toUpperCase().padStart(16, '0');
}

/** A board with flash unique ID `flashId` and its USB port open; returns what it shows. */
function shown(flashId) {
  const board = new EmulatedBoard({ bootrom, usb: true, flashId });
  const uartBanner = board.boot();
  board.usb.waitUntilOpen();
  const usbBanner = board.usb.waitForLine(BANNER);
  const device = board.usb.readDescriptor(DESCRIPTOR_DEVICE, 0);
  const index = device[I_SERIAL_NUMBER];
  assert.ok(index > 0, 'the device descriptor names a serial number');
  const bytes = board.usb.readDescriptor(DESCRIPTOR_STRING, index, { langId: LANG_EN_US });
  const serial = Buffer.from(bytes.slice(2, bytes[0])).toString('utf16le');
  // The board works as before: a command on each link.
  assert.equal(board.request('status').reply, 'ok');
  assert.equal(board.usb.request('status').reply, 'ok');
  return { serial, uartBanner, usbBanner };
}

test('two boards with different flash IDs give different USB serial numbers and banners', () => {
  const ids = [0x0123456789abcdefn, 0xe6616408432b1f29n];
  const seen = ids.map(shown);
  for (const [i, id] of ids.entries()) {
    const { serial, uartBanner, usbBanner } = seen[i];
    assert.equal(serial, digits(id));
    for (const banner of [uartBanner, usbBanner]) {
      assert.match(banner, new RegExp(`^# hexapod control \\S+ on board ${digits(id)}: `));
    }
  }
  assert.notEqual(seen[0].serial, seen[1].serial);
});

test('a board the harness gives no id has the fixed default one', () => {
  const { serial, uartBanner } = shown(undefined);
  assert.equal(serial, digits(DEFAULT_FLASH_UNIQUE_ID));
  assert.ok(uartBanner.includes(`on board ${digits(DEFAULT_FLASH_UNIQUE_ID)}:`), uartBanner);
});
