// Measures the servo outputs the way a logic analyser would: from the pins' edges, in
// emulated time. rp2040js drives a PWM pin at the exact instants its counter wraps and
// passes the compare value, so widths and periods come out exact to the nanosecond, the
// meter's resolution: emulated time is a sum of floats (a clock of 12 MHz, a UART bit at
// 115,200 baud are fractions of a nanosecond), so an instant carries noise of about 1e-8 ns,
// and a width or period is rounded to the nanosecond (20,000,000, not 20,000,000.000000007).

import { GPIOPinState } from 'rp2040js';

/** Servo i (1..6) is on GP(i+1). */
export const SERVO_GPIOS = [2, 3, 4, 5, 6, 7];
/** One PWM count: 125 MHz / divider 40. */
export const NANOS_PER_COUNT = 320;

export class ServoPulseMeter {
  constructor(mcu, gpios = SERVO_GPIOS) {
    this.clock = mcu.clock;
    this.pins = gpios.map((gpio) => ({
      gpio,
      lastRiseNanos: null,
      widthNanos: null, // last complete high time
      periodNanos: null, // last rise-to-rise time
      pulses: 0, // complete pulses seen
    }));
    /** Called after a pulse completes with a width different from the previous one. */
    this.onChange = null;
    /** Called after every complete pulse: `(servoIndex, { riseNanos, widthNanos, periodNanos })`. */
    this.pulseListeners = new Set();
    for (const pin of this.pins) {
      mcu.gpio[pin.gpio].addListener((state) => this.edge(pin, state));
    }
  }

  edge(pin, state) {
    const now = this.clock.nanos;
    if (state === GPIOPinState.High) {
      if (pin.lastRiseNanos !== null) {
        pin.periodNanos = Math.round(now - pin.lastRiseNanos);
      }
      pin.lastRiseNanos = now;
    } else if (state === GPIOPinState.Low && pin.lastRiseNanos !== null) {
      const width = Math.round(now - pin.lastRiseNanos);
      const changed = width !== pin.widthNanos;
      pin.widthNanos = width;
      pin.pulses++;
      if (this.pulseListeners.size > 0) {
        const pulse = {
          riseNanos: pin.lastRiseNanos,
          widthNanos: width,
          periodNanos: pin.periodNanos,
        };
        const index = this.pins.indexOf(pin);
        for (const listener of this.pulseListeners) {
          listener(index, pulse);
        }
      }
      if (changed && this.onChange) {
        this.onChange(this);
      }
    }
  }

  /**
   * Per servo: last width and period in ns and us, the width in PWM counts, pulses seen, and
   * `live`: false once the pin has not risen for two periods (no pulses any more: the
   * width shown is then the last one seen).
   */
  read() {
    const now = this.clock.nanos;
    return this.pins.map((pin, index) => ({
      servo: index + 1,
      gpio: pin.gpio,
      widthNanos: pin.widthNanos,
      periodNanos: pin.periodNanos,
      widthUs: pin.widthNanos === null ? null : pin.widthNanos / 1000,
      periodUs: pin.periodNanos === null ? null : pin.periodNanos / 1000,
      widthCounts: pin.widthNanos === null ? null : pin.widthNanos / NANOS_PER_COUNT,
      pulses: pin.pulses,
      live:
        pin.lastRiseNanos !== null &&
        pin.periodNanos !== null &&
        now - pin.lastRiseNanos <= 2 * pin.periodNanos,
    }));
  }
}
