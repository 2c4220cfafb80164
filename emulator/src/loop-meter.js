// How long the firmware keeps its CPU busy at a stretch, measured on the emulated chip: the
// main loop's passes (from one watchdog feed to the next: the loop feeds the watchdog once per
// pass, at its top) and the interrupt handlers (from exception entry to the return to thread
// mode). In CPU cycles, which rp2040js counts per instruction and does not advance while the
// core sleeps in WFI, so a pass is the work it did, not the time it slept. Interrupt handlers
// that run inside a pass count in that pass too.

const WATCHDOG_BASE = 0x40058;
const WATCHDOG_LOAD = 0x04;

/**
 * Attaches the meter to a fresh `RP2040`. Returns the live statistics:
 * `{ passes, longestPassCycles, longestPassAtNanos, longestHandlerCycles, longestHandler,
 *    reset() }` (`longestHandler` is the exception number, 16 + IRQ number for interrupts).
 */
export function attachLoopMeter(mcu) {
  const { core } = mcu;
  const stats = {
    passes: 0,
    longestPassCycles: 0,
    longestPassAtNanos: 0,
    longestHandlerCycles: 0,
    longestHandler: 0,
    reset() {
      this.passes = 0;
      this.longestPassCycles = 0;
      this.longestPassAtNanos = 0;
      this.longestHandlerCycles = 0;
      this.longestHandler = 0;
      lastFeedCycles = null;
    },
  };

  let lastFeedCycles = null;
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
      }
      lastFeedCycles = core.cycles;
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
