// How long the firmware keeps its CPU busy at a stretch, measured on the emulated chip: the
// main loop's passes (from one watchdog feed to the next: the loop feeds the watchdog once per
// pass, at its top) and the interrupt handlers (from exception entry to the return to thread
// mode). In CPU cycles, which rp2040js counts per instruction and does not advance while the
// core sleeps in WFI, so a pass is the work it did, not the time it slept. Interrupt handlers
// that run inside a pass count in that pass too.
//
// The one pass allowed to be long is a `save`'s flash write (an erase keeps the core in the
// boot ROM for tens to hundreds of milliseconds): every pass of at least `boundCycles` is
// listed (`longPasses`, with when it ended), so a test can check that each is a save's.
//
// And whether the firmware serves every servo frame: it writes the frame's new compare values
// after each frame starts (a rising edge on servo 1's pin), so a frame period in which it wrote
// none is a frame it missed (its pins held the old pulses one period longer).

const WATCHDOG_BASE = 0x40058;
const WATCHDOG_LOAD = 0x04;
/** PWM slice 1 (servos 1 and 2), its compare register: slices are 0x14 bytes apart. */
const SLICE1_CC = 0x14 + 0x0c;
/** Servo 1's pin. */
const SERVO1_GPIO = 2;

/** The documented bound on a main-loop pass: 1 ms at 125 MHz. */
export const PASS_BOUND_CYCLES = 125_000;

/**
 * Attaches the meter to a fresh `RP2040`. Returns the live statistics:
 * `{ passes, longestPassCycles, longestPassAtNanos, longestHandlerCycles, longestHandler,
 *    longPasses, reset() }` (`longestHandler` is the exception number, 16 + IRQ number for
 * interrupts; `longPasses`: `{ cycles, startNanos, endNanos }` of every pass of at least
 * `boundCycles`).
 */
export function attachLoopMeter(mcu, { boundCycles = PASS_BOUND_CYCLES } = {}) {
  const { core } = mcu;
  const stats = {
    passes: 0,
    longestPassCycles: 0,
    longestPassAtNanos: 0,
    longestHandlerCycles: 0,
    longestHandler: 0,
    longPasses: [],
    reset() {
      this.passes = 0;
      this.longestPassCycles = 0;
      this.longestPassAtNanos = 0;
      this.longestHandlerCycles = 0;
      this.longestHandler = 0;
      this.longPasses = [];
      lastFeedCycles = null;
    },
  };

  let lastFeedCycles = null;
  let lastFeedNanos = 0;
  const watchdog = mcu.peripherals[WATCHDOG_BASE];
  const writeRegister = watchdog.writeUint32.bind(watchdog);
  watchdog.writeUint32 = (offset, value) => {
    if (offset === WATCHDOG_LOAD) {
      if (lastFeedCycles !== null) {
        const pass = core.cycles - lastFeedCycles;
        stats.passes++;
        if (pass > stats.longestPassCycles) {
          stats.longestPassCycles = pass;
          stats.longestPassAtNanos = mcu.clock.nanos;
        }
        if (pass >= boundCycles) {
          const endNanos = mcu.clock.nanos;
          stats.longPasses.push({ cycles: pass, startNanos: lastFeedNanos, endNanos });
        }
      }
      lastFeedCycles = core.cycles;
      lastFeedNanos = mcu.clock.nanos;
    }
    writeRegister(offset, value);
  };

  // Handlers: from the entry that leaves thread mode to the return into it (nested handlers
  // count in the outer one).
  let handlerStart = null;
  let handlerNumber = 0;
  const entry = core.exceptionEntry.bind(core);
  core.exceptionEntry = (exceptionNumber) => {
    if (core.IPSR === 0) {
      handlerStart = core.cycles;
      handlerNumber = exceptionNumber;
    }
    entry(exceptionNumber);
  };
  const exit = core.exceptionReturn.bind(core);
  core.exceptionReturn = (excReturn) => {
    exit(excReturn);
    if (core.IPSR === 0 && handlerStart !== null) {
      const length = core.cycles - handlerStart;
      if (length > stats.longestHandlerCycles) {
        stats.longestHandlerCycles = length;
        stats.longestHandler = handlerNumber;
      }
      handlerStart = null;
    }
  };
  return stats;
}

/**
 * Attaches the frame meter to a fresh `RP2040`. Returns the live statistics:
 * `{ frames, missed, missedAtNanos, reset() }`: frame periods seen whole, and those in which
 * the firmware wrote no compare value for servos 1 and 2 (missed frames).
 */
export function attachFrameMeter(mcu) {
  const stats = {
    frames: 0,
    missed: 0,
    missedAtNanos: [],
    reset() {
      this.frames = 0;
      this.missed = 0;
      this.missedAtNanos = [];
      started = false;
    },
  };
  let started = false; // a frame start seen since the last reset
  let writes = 0; // compare writes since the last frame start
  const pwm = mcu.pwm;
  const writeRegister = pwm.writeUint32.bind(pwm);
  pwm.writeUint32 = (offset, value) => {
    if (offset === SLICE1_CC) {
      writes++;
    }
    writeRegister(offset, value);
  };
  let high = false;
  mcu.gpio[SERVO1_GPIO].addListener((state) => {
    const rising = state && !high;
    high = !!state;
    if (!rising) {
      return;
    }
    if (started) {
      stats.frames++;
      if (writes === 0) {
        stats.missed++;
        stats.missedAtNanos.push(mcu.clock.nanos);
      }
    }
    started = true;
    writes = 0;
  });
  return stats;
}
