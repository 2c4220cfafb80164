// The core's sleep (WFI/WFE), gap 5 of rp2040js 1.4.1 (numbered as in index.js).
//
// 5. WFI with an interrupt already pending: the ARM wakes at once (also with PRIMASK set, which
//    is how firmware closes the check-then-sleep race: `cpsid; if idle { wfi }; cpsie`).
//    rp2040js only wakes a waiting core when an interrupt *becomes* pending, so an interrupt
//    that arrived between the check and the WFI leaves the core asleep until some other
//    interrupt (e.g. the next servo frame, up to 20 ms) while the UART's 32-byte FIFO
//    overflows. `wakeIfInterruptPending` is called before each sleep step.

/** Gap 5: ends a WFI/WFE sleep if an enabled interrupt is already pending (true if it did). */
export function wakeIfInterruptPending(core) {
  if (core.waiting && (core.pendingInterrupts & core.enabledInterrupts) !== 0) {
    core.waiting = false;
    return true;
  }
  return false;
}
