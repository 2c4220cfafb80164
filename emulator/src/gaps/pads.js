// The pads' pulls, gap 8 of rp2040js 1.4.1 (numbered as in index.js).
//
// 8. Pad pulls: rp2040js reads an input pin nobody drives as low, whatever its pad's pull-up
//    or pull-down (it only reports them in `value`). On the chip a pin left open reads its
//    pull: a high through the pull-up, which is how an open e-stop switch or a cut wire reads
//    "open". `PadPulls` is the world outside the pins: each GPIO is driven high or low by the
//    test (`drive(n, level)`), or left open (`drive(n, null)`, the default), and then reads
//    its pad's pull (pull-up high, pull-down low; both or neither: the last level, as the bus
//    keeper or a floating input would).

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
