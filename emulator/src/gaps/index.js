// Every workaround for a gap in rp2040js 1.4.1, one file per peripheral, each numbered and
// explained in its file: what the real chip does, what rp2040js lacks, what the model does.
//
// 1. Logging (here): the default logger prints debug messages for every unimplemented
//    register access, which slows a run ~15x and floods the terminal. Errors only (and errors
//    throw, so a real emulator fault stops the run instead of scrolling past).
// 2. The UART's PL011 (`uart.js`, `Pl011`).
// 3. The UART's receive timing (`uart.js`, `PacedUartInput`).
// 4. Watchdog expiry (`watchdog.js`, `onWatchdogExpiry`).
// 5. WFI with an interrupt already pending (`wfi.js`, `wakeIfInterruptPending`).
// 6. (The chip reset lives in ../chip/board.js, `watchdogReset` and `powerOn`.)
// 7. Flash writes through the boot ROM (`flash.js`, `FlashChip`, `attachFlashChip`).
// 8. Pad pulls (`pads.js`, `PadPulls`).
// 9-12. USB: OUT arms before enumeration, the line state, IN timing, suspend and unplugging
//    (`usb.js`, `UsbCdcHost`).
// 13. The XIP flash cache and its registers (`xip-cache.js`, `XipCache`, `attachXipCache`).
// 14. The flash chip's unique ID, read through the SSI (`flash.js`, `FlashChip.uniqueId`).
//
// `patchEmulatorGaps` installs gaps 1 and 2 on a fresh `RP2040`; the board (../chip/board.js)
// installs the others where it wires the chip up (they need its callbacks).

import { ConsoleLogger, LogLevel } from 'rp2040js';

import { Pl011 } from './uart.js';

export {
  attachFlashChip,
  DEFAULT_FLASH_UNIQUE_ID,
  FLASH_PAGE_BYTES,
  FLASH_SECTOR_BYTES,
  FlashChip,
  PICO_FLASH_BYTES,
  W25Q080_TIMING,
} from './flash.js';
export { PadPulls } from './pads.js';
export { PacedUartInput, Pl011 } from './uart.js';
export { BULK_PACKET_BYTES, BULK_PACKET_NANOS, BULK_PACKETS_PER_FRAME, UsbCdcHost } from './usb.js';
export { onWatchdogExpiry } from './watchdog.js';
export { wakeIfInterruptPending } from './wfi.js';
export {
  attachXipCache,
  missCost,
  setXipCacheByDefault,
  XipCache,
  xipCacheByDefault,
  XIP_CACHE_SETS,
} from './xip-cache.js';

/**
 * rp2040js's `RP2040` as this harness uses it, with what its declared types leave out: its
 * clock is a `SimulationClock` (`tick`, `nextAlarm`), and after `patchEmulatorGaps` each UART
 * carries its PL011 model (`uart.pl011`).
 * @typedef {import('rp2040js').RP2040 & {
 *   clock: { tick(deltaNanos: number): void, nextAlarm: { nanos: number } | null },
 *   uart: Array<import('rp2040js').RP2040['uart'][number] & { pl011: Pl011 }>,
 * }} Mcu
 */

/** Applies gaps 1 and 2 to a fresh `RP2040`: `uart.pl011` is each UART's model. */
export function patchEmulatorGaps(mcu) {
  mcu.logger = new ConsoleLogger(LogLevel.Error, true);
  for (const uart of mcu.uart) {
    uart.pl011 = new Pl011(mcu, uart);
  }
}
