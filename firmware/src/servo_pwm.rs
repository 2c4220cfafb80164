//! Six hobby-servo outputs: servo i (1..=6) on GP(i+1), PWM slices 1-3, channels A and B.
//!
//! The counters run at 125 MHz / 40 = 3.125 MHz, so one count is 320 ns and a frame of
//! `TOP + 1` counts lasts `(TOP + 1) * 320 ns`; `TOP = 3_125_000 / frame_hz - 1` (62,499 at
//! 50 Hz). A pin is high from the start of the frame for `CC` counts. `CC` and `TOP` are
//! double-buffered by the hardware (latched at the wrap), so a new pulse width takes effect at
//! the next frame and never cuts a pulse short. The six widths are written as one `CC` word per
//! slice, never across a wrap ([`clear_of_wrap`]), so every frame shows all six old widths or
//! all six new ones (emulator/test/pwm-wrap.test.js places a jump at the wrap).
//!
//! Every frame start (slice 1 wrapping) raises `PWM_IRQ_WRAP`; the handler only counts frames,
//! so the main loop can run the motion controller once per frame and knows if it missed any.

use core::sync::atomic::{compiler_fence, AtomicU32, Ordering};

use control::settings::{FRAME_HZ_MAX, FRAME_HZ_MIN};
use rp2040_hal::{
    gpio::{bank0, DefaultTypeState, Pin},
    pac::{self, interrupt},
    pwm::{FreeRunning, Pwm1, Pwm2, Pwm3, Slice, SliceId, Slices},
};

pub const SERVO_COUNT: usize = 6;

/// Integer clock divider: 125 MHz / 40 = 3.125 MHz, no fractional jitter.
const CLOCK_DIVIDER: u8 = 40;
/// PWM counts per second at 125 MHz / [`CLOCK_DIVIDER`].
const COUNTS_PER_SECOND: u32 = 3_125_000;

/// Frames started so far (slice 1 wraps). Written only by `PWM_IRQ_WRAP`.
static FRAMES_STARTED: AtomicU32 = AtomicU32::new(0);

/// The pins in their reset state; servo i is `.i-1` (GP2..GP7).
pub type ServoPins = (
    DefaultPin<bank0::Gpio2>,
    DefaultPin<bank0::Gpio3>,
    DefaultPin<bank0::Gpio4>,
    DefaultPin<bank0::Gpio5>,
    DefaultPin<bank0::Gpio6>,
    DefaultPin<bank0::Gpio7>,
);
type DefaultPin<Id> =
    Pin<Id, <Id as DefaultTypeState>::Function, <Id as DefaultTypeState>::PullType>;

/// Allowed pulse widths in microseconds; every pulse is clamped into `[min_us, max_us]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PulseWindowUs {
    pub min_us: f32,
    pub max_us: f32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub struct FrameRateOutOfRange;

pub struct ServoPwm {
    /// Slices 1-3, configured: held so that nothing else can take them. Their compare and
    /// `TOP` registers are written directly ([`write_compares`]): a whole `CC` word per slice.
    _slices: (
        Slice<Pwm1, FreeRunning>,
        Slice<Pwm2, FreeRunning>,
        Slice<Pwm3, FreeRunning>,
    ),
    frame_hz: u16,
    /// `TOP` as last written, and as written before it: the counters wrap at one of the two
    /// (the hardware latches a new `TOP` at the next wrap), so writes keep clear of both.
    tops: [u16; 2],
    /// Compare value (pulse width in counts) per servo, as last written.
    counts: [u16; SERVO_COUNT],
    frames_seen: u32,
}

impl ServoPwm {
    /// Takes PWM slices 1-3 and pins GP2..GP7, starts all six outputs at `frame_hz` with the
    /// given first pulse widths (see [`ServoPwm::set_pulse_widths_us`]; a non-finite width
    /// means no pulse) and enables the frame-start interrupt.
    pub fn new(
        pwm: pac::PWM,
        resets: &mut pac::RESETS,
        pins: ServoPins,
        frame_hz: u16,
        first_widths_us: &[f32; SERVO_COUNT],
        windows: &[PulseWindowUs; SERVO_COUNT],
    ) -> Result<Self, FrameRateOutOfRange> {
        let top = top_for(frame_hz)?;
        let mut slices = Slices::new(pwm, resets);
        let (gp2, gp3, gp4, gp5, gp6, gp7) = pins;
        slices.pwm1.channel_a.output_to(gp2);
        slices.pwm1.channel_b.output_to(gp3);
        slices.pwm2.channel_a.output_to(gp4);
        slices.pwm2.channel_b.output_to(gp5);
        slices.pwm3.channel_a.output_to(gp6);
        slices.pwm3.channel_b.output_to(gp7);
        configure(&mut slices.pwm1, top);
        configure(&mut slices.pwm2, top);
        configure(&mut slices.pwm3, top);
        let mut counts = [0; SERVO_COUNT];
        for ((count, &width_us), &window) in counts.iter_mut().zip(first_widths_us).zip(windows) {
            *count = pulse_counts(width_us, window, top).unwrap_or(0);
        }
        // The counters are stopped at 0: no wrap can come.
        write_compares(&[top, top], counts);
        slices.pwm1.clear_interrupt();
        slices.pwm1.enable_interrupt();
        // Start the three counters in the same cycle so the six pulses share one frame.
        slices.enable_simultaneous(0b1110);

        let servos = ServoPwm {
            _slices: (slices.pwm1, slices.pwm2, slices.pwm3),
            frame_hz,
            tops: [top, top],
            counts,
            frames_seen: 0,
        };
        // SAFETY: the handler below touches only the slice-1 interrupt flag and an atomic.
        unsafe { pac::NVIC::unmask(pac::Interrupt::PWM_IRQ_WRAP) };
        Ok(servos)
    }

    pub fn frame_rate_hz(&self) -> u16 {
        self.frame_hz
    }

    /// Changes the frame rate (50..=333 Hz) from the next frame on. Pulse widths keep their
    /// microseconds (counts do not depend on the frame rate) but are cut to the new frame.
    pub fn set_frame_rate_hz(&mut self, frame_hz: u16) -> Result<(), FrameRateOutOfRange> {
        let top = top_for(frame_hz)?;
        self.frame_hz = frame_hz;
        self.tops = [top, self.tops[0]];
        self.counts = self.counts.map(|count| count.min(top));
        let compares = compare_words(self.counts);
        clear_of_wrap(&self.tops, || {
            // SAFETY: plain register writes to the three slices this driver owns.
            let pwm = unsafe { &*pac::PWM::ptr() };
            for (slice, compare) in SLICES.into_iter().zip(compares) {
                pwm.ch(slice)
                    .top()
                    .write(|w| unsafe { w.bits(u32::from(top)) });
                pwm.ch(slice).cc().write(|w| unsafe { w.bits(compare) });
            }
        });
        Ok(())
    }

    /// Sets the six pulse widths computed for the frame that [`ServoPwm::frames_since_last_poll`]
    /// reported (see [`ServoPwm::set_pulse_widths_us_now`] for the rules on widths).
    pub fn set_frame_pulse_widths_us(
        &mut self,
        widths_us: &[f32; SERVO_COUNT],
        windows: &[PulseWindowUs; SERVO_COUNT],
    ) {
        self.set_pulse_widths_us_now(widths_us, windows);
        // Not before the register writes above.
        compiler_fence(Ordering::SeqCst);
        // These widths latch at the next frame start. A frame that started while they were
        // being computed (after the caller polled) still shows the previous widths, so it
        // counts as served: otherwise the next poll would report it and the next widths would
        // overwrite these before any pin showed them, and the servos would skip a step.
        self.frames_seen = FRAMES_STARTED.load(Ordering::Relaxed);
    }

    /// Sets the six pulse widths from the next frame start on, outside the frame rhythm (a
    /// jump commanded just now); frames still to be served stay pending. A non-finite width
    /// keeps that servo's previous pulse; finite widths are clamped into the servo's window
    /// (and into the frame) and rounded to the nearest count, so no NaN or out-of-window value
    /// reaches a register.
    pub fn set_pulse_widths_us_now(
        &mut self,
        widths_us: &[f32; SERVO_COUNT],
        windows: &[PulseWindowUs; SERVO_COUNT],
    ) {
        let top = self.tops[0];
        let mut counts = self.counts;
        for ((count, &width_us), &window) in counts.iter_mut().zip(widths_us).zip(windows) {
            if let Some(new) = pulse_counts(width_us, window, top) {
                *count = new;
            }
        }
        self.write_counts(counts);
    }

    /// How many frames started since the last call (or since the last
    /// [`ServoPwm::set_frame_pulse_widths_us`], which counts frames that started while its
    /// widths were being computed as served): 0 = none yet, 1 = the normal case, more = the
    /// main loop missed frames.
    pub fn frames_since_last_poll(&mut self) -> u32 {
        let started = FRAMES_STARTED.load(Ordering::Relaxed);
        let new = started.wrapping_sub(self.frames_seen);
        self.frames_seen = started;
        new
    }

    /// True if a frame started that [`ServoPwm::frames_since_last_poll`] has not reported.
    pub fn frame_pending(&self) -> bool {
        FRAMES_STARTED.load(Ordering::Relaxed) != self.frames_seen
    }

    fn write_counts(&mut self, counts: [u16; SERVO_COUNT]) {
        write_compares(&self.tops, counts);
        self.counts = counts;
    }
}

/// The servo slices: servo 1..6 = slice 1 A, 1 B, 2 A, 2 B, 3 A, 3 B.
const SLICES: [usize; 3] = [1, 2, 3];

/// Counts before a wrap in which no compare or `TOP` register is written: the writes (three
/// stores from RAM, interrupts masked: a few dozen cycles) take less than one count (40
/// cycles), so four leave a wide margin.
const WRAP_GUARD_COUNTS: u16 = 4;

/// Each slice's `CC` word: channel A's count in bits 0-15, B's in 16-31 (datasheet 4.5.3).
fn compare_words(counts: [u16; SERVO_COUNT]) -> [u32; 3] {
    let word = |a: u16, b: u16| u32::from(a) | u32::from(b) << 16;
    [
        word(counts[0], counts[1]),
        word(counts[2], counts[3]),
        word(counts[4], counts[5]),
    ]
}

/// The six compare values, one 32-bit write per slice, all in one frame (see [`clear_of_wrap`]).
fn write_compares(tops: &[u16; 2], counts: [u16; SERVO_COUNT]) {
    let compares = compare_words(counts);
    clear_of_wrap(tops, || {
        // SAFETY: plain register writes to the three slices this driver owns.
        let pwm = unsafe { &*pac::PWM::ptr() };
        for (slice, compare) in SLICES.into_iter().zip(compares) {
            pwm.ch(slice).cc().write(|w| unsafe { w.bits(compare) });
        }
    });
}

/// Runs `write` (a few register stores) where no wrap can fall inside it. The compare and `TOP`
/// registers latch at the wrap, so a wrap between two stores would show the servos a mix of
/// old and new widths for a frame (a pose nothing checked) or, for `TOP`, put the slices out of
/// phase. With interrupts masked, and if slice 1's counter (the three run in phase) is within
/// [`WRAP_GUARD_COUNTS`] of either `TOP` it may wrap at, after that count passes: a wait of at
/// most five counts (1.6 us) with interrupts masked.
fn clear_of_wrap(tops: &[u16; 2], write: impl FnOnce()) {
    cortex_m::interrupt::free(|_| {
        // SAFETY: a read of slice 1's counter, which has no side effect.
        let counter = || unsafe { (*pac::PWM::ptr()).ch(1).ctr().read().bits() } as u16;
        let near_wrap = |count: u16| {
            tops.iter()
                .any(|&top| count <= top && count >= top.saturating_sub(WRAP_GUARD_COUNTS))
        };
        while near_wrap(counter()) {}
        write();
    });
}

/// Divider 40, edge-aligned, pins not inverted, counter at 0, no pulse yet.
fn configure<I: SliceId>(slice: &mut Slice<I, FreeRunning>, top: u16) {
    slice.default_config();
    slice.set_div_int(CLOCK_DIVIDER);
    slice.set_top(top);
}

/// `TOP = 3_125_000 / frame_hz - 1` for a frame rate in range.
fn top_for(frame_hz: u16) -> Result<u16, FrameRateOutOfRange> {
    if !(FRAME_HZ_MIN..=FRAME_HZ_MAX).contains(&frame_hz) {
        return Err(FrameRateOutOfRange);
    }
    let top = COUNTS_PER_SECOND / u32::from(frame_hz) - 1;
    u16::try_from(top).map_err(|_| FrameRateOutOfRange)
}

/// Microseconds -> compare counts, or `None` for a non-finite width. Clamps to `window`, then
/// to `0..=top` (a pulse never outlasts its frame), and rounds half up.
fn pulse_counts(width_us: f32, window: PulseWindowUs, top: u16) -> Option<u16> {
    if !is_finite(width_us) {
        return None;
    }
    // As `f32::max`/`min` would (a NaN bound is ignored, so a broken window cannot produce NaN
    // either), compared as integers: no soft-float calls, six times a frame.
    let mut clamped_us = width_us;
    if !is_nan(window.min_us) && order_key(clamped_us) < order_key(window.min_us) {
        clamped_us = window.min_us;
    }
    if !is_nan(window.max_us) && order_key(clamped_us) > order_key(window.max_us) {
        clamped_us = window.max_us;
    }
    Some(counts_of_us(clamped_us).min(u32::from(top)) as u16)
}

/// `width_us * 3.125` (counts of 320 ns) rounded half up, exactly, for a `width_us` that is not
/// NaN (negative -> 0, too large -> `u32::MAX`), on the bits: the value is `m * 2^(e - 150)`
/// (`m` the 24-bit significand, `e` the biased exponent), so times 25/8 it is
/// `25 m * 2^(e - 153)`, and `25 m < 2^29` shifts without loss. (In `f32`, `w * 3.125 + 0.5`
/// rounds the product first, which can carry a value just below a half up to it.)
fn counts_of_us(width_us: f32) -> u32 {
    let bits = width_us.to_bits();
    let exponent = (bits >> 23) & 0xFF;
    if bits & 0x8000_0000 != 0 || exponent == 0 {
        return 0; // negative, zero, or far below half a count
    }
    let scaled = ((bits & 0x007F_FFFF) | 0x0080_0000) * 25;
    match 153 - exponent as i32 {
        // Below a quarter of a count.
        31.. => 0,
        shift @ 1..=30 => (scaled + (1 << (shift - 1))) >> shift,
        // Whole already: times 2, 4 or 8 stays below 2^32.
        shift @ -3..=0 => scaled << -shift,
        _ => u32::MAX,
    }
}

/// `f32::is_finite` on the bits (no soft-float comparison).
fn is_finite(x: f32) -> bool {
    x.to_bits() & 0x7F80_0000 != 0x7F80_0000
}

/// `f32::is_nan` on the bits.
fn is_nan(x: f32) -> bool {
    x.to_bits() & 0x7FFF_FFFF > 0x7F80_0000
}

/// An integer that orders floats that are not NaN as their values (IEEE 754 sign and
/// magnitude, made two's complement-like: negative values flipped below the positive ones;
/// -0 just below +0, which the rounding above maps to the same count).
fn order_key(x: f32) -> u32 {
    let bits = x.to_bits();
    if bits & 0x8000_0000 != 0 {
        !bits
    } else {
        bits | 0x8000_0000
    }
}

#[interrupt]
fn PWM_IRQ_WRAP() {
    // SAFETY: INTR is write-1-to-clear; writing only slice 1's bit touches no other state.
    unsafe { (*pac::PWM::ptr()).intr().write(|w| w.bits(1 << 1)) };
    // Only this handler writes the counter, so load + store cannot lose a count.
    let frames = FRAMES_STARTED.load(Ordering::Relaxed);
    FRAMES_STARTED.store(frames.wrapping_add(1), Ordering::Relaxed);
}
