// The watchdog, gap 4 of rp2040js 1.4.1 (numbered as in index.js).
//
// The chip: when the watchdog counter reaches 0 the chip resets (as WDSEL selects).
// rp2040js and the model:
//
// 4. Watchdog expiry: rp2040js calls `onWatchdogTrigger`, then re-arms the alarm of a counter
//    that sits at 0, so it fires again at the same instant forever and emulated time stops.
//    `onWatchdogExpiry` stops the watchdog timer when it fires and reports it once (a real
//    chip would reset; a reset through the boot ROM is not possible here, so board.js either
//    fails the run or, with `onWatchdog: 'reset'`, emulates the reset with a fresh chip).

const WATCHDOG_BASE = 0x40058;

/** Gap 4: calls `callback()` once when the watchdog expires, and stops it. */
export function onWatchdogExpiry(mcu, callback) {
  const watchdog = mcu.peripherals[WATCHDOG_BASE];
  watchdog.onWatchdogTrigger = () => {
    watchdog.alarm.enable = false;
    watchdog.timer.enable = false;
    callback();
  };
}
