//! UART0 on GP0 (TX) / GP1 (RX), 8N1, baud rate changeable at run time.
//!
//! Receive: the `UART0_IRQ` handler (RX FIFO level and RX timeout interrupts) moves bytes from
//! the 32-byte hardware FIFO into a lock-free queue ([`crate::rx_ring`]) that the main loop reads
//! (a command line's characters a run at a time, [`Serial::take_plain`]). While bytes keep
//! coming at the slower rates, a timer alarm (`TIMER_IRQ_0`) also empties the FIFO every
//! [`rx_poll_period_us`] (100 us): the PL011 raises its interrupt only at the FIFO level
//! (8 bytes) or after 32 bit times of silence (278 us at 115,200 baud), so without the poll the
//! end of a line could wait that long in the FIFO. The poll stops at the first alarm that
//! finds the FIFO empty (the level and timeout interrupts take over again). From 460,800 baud
//! on the timeout (69 us, 35 us at 921,600) comes sooner than a poll could (every 4 character
//! times, 87 us, 43 us): there is no poll, and the FIFO is emptied every 8 bytes, half as many
//! interrupts and main-loop passes as with it. Neither handler waits:
//! when the queue is full it drops the byte and counts it, and the main loop is told where in
//! the byte stream the loss happened ([`Received::Lost`]), so exactly the damaged line can be
//! refused, and, at once, that a loss happened ([`Serial::take_new_loss`]), so the host hears
//! of it without waiting for the main loop to get there.
//!
//! Losses in the UART itself count the same way, with what the PL011 can tell: a byte with a
//! framing, parity or break error is lost; an overrun (bytes that found the hardware FIFO full)
//! loses an unknown number of bytes (at least one) just before the byte that carries the OE
//! flag, which is itself good and kept. rp2040-hal also reports an overrun from the status
//! register when it finds the FIFO empty; the OE flag on the next byte is then the same loss
//! again, not counted twice.
//!
//! A gap is one contiguous stretch at one known position: should more bytes be lost before the
//! main loop has reached the first loss, the bytes received between the two are dropped too (the
//! gap grows to the latest loss). Bytes after the latest loss are kept: a line end the host sends
//! to close the cut line does arrive.
//!
//! Transmit: the main loop writes replies into a software buffer (`core::fmt::Write`) and calls
//! [`Serial::send_some`] each pass, which moves only what fits into the 32-byte TX FIFO. While
//! output waits for room, the TX FIFO interrupt (at half full) wakes the main loop, so it sleeps
//! instead of spinning.

use core::{
    cell::RefCell,
    fmt,
    sync::atomic::{AtomicBool, AtomicU32, Ordering},
};

use control::protocol::{self, Lost};
use control::Session;
use critical_section::Mutex;
use heapless::Deque;
use rp2040_hal::{
    fugit::{HertzU32, MicrosDurationU32, RateExtU32},
    gpio::{bank0, DefaultTypeState, FunctionUart, Pin, PullNone, PullUp},
    pac::{self, interrupt},
    timer::{Alarm, Alarm0},
    uart::{DataBits, Enabled, FifoWatermark, StopBits, UartConfig, UartPeripheral},
};

use crate::rx_ring::{RxConsumer, RxProducer, RxRing};

/// Receive queue size; holds `RX_QUEUE_BYTES - 1` bytes (355 ms of input at 115,200 baud,
/// 44 ms at 921,600): a host's burst of lines waits here while the replies, which are often
/// longer than the lines (echo, `status`, error messages), go out at the same baud rate.
pub const RX_QUEUE_BYTES: usize = 4096;
/// The most one step of the controller may write (a byte with its echo and, at a line end, a
/// quick command's reply; one slice of work; with up to four notices before it).
pub const LONGEST_STEP_BYTES: usize = 2048;
/// Transmit buffer: room for four of the longest steps.
pub const TX_BUFFER_BYTES: usize = 4 * LONGEST_STEP_BYTES;

/// The UART accepts the controller's baud rates (`set baud`), slowest to fastest.
pub const BAUD_MIN: u32 = control::settings::BAUD_RATES[0];
pub const BAUD_MAX: u32 = control::settings::BAUD_RATES[control::settings::BAUD_RATES.len() - 1];

type TxPin = Pin<bank0::Gpio0, FunctionUart, PullNone>;
/// Pulled up so an unconnected RX line idles high instead of reading breaks.
type RxPin = Pin<bank0::Gpio1, FunctionUart, PullUp>;
type Uart = UartPeripheral<Enabled, pac::UART0, (TxPin, RxPin)>;
type DefaultPin<Id> =
    Pin<Id, <Id as DefaultTypeState>::Function, <Id as DefaultTypeState>::PullType>;

/// State shared by `UART0_IRQ`, `TIMER_IRQ_0` and the main loop, only ever touched inside a
/// critical section.
struct Shared {
    /// `None` only during a baud-rate change, which happens inside one critical section.
    uart: Option<Uart>,
    rx: Receiver,
    /// The alarm that polls the RX FIFO while bytes keep coming.
    poll: Alarm0,
    /// Its period at the current baud rate; `None`: no poll at this rate.
    poll_period_us: Option<u32>,
}

/// How often the RX FIFO is polled while bytes keep coming, us: 4 character times (8N1),
/// within 20..=100 us (100 us at 230,400 baud and below); `None` where the PL011's receive
/// timeout (32 bit times) comes sooner than that (460,800 baud and up): the poll would only
/// add interrupts.
pub fn rx_poll_period_us(baud: u32) -> Option<u32> {
    let baud = baud.max(1);
    let period_us = (4 * 10 * 1_000_000 / baud).clamp(20, 100);
    let timeout_us = 32 * 1_000_000 / baud;
    (period_us < timeout_us).then_some(period_us)
}

/// The interrupt's side of the receive queue.
struct Receiver {
    queue: RxProducer<RX_QUEUE_BYTES>,
    /// Bytes put into the queue so far (wrapping): positions in the received stream.
    enqueued: u32,
    /// Bytes lost that the main loop has not reached yet.
    loss: Option<Loss>,
    /// rp2040-hal reported an overrun from the status register (the FIFO was empty): the OE
    /// flag on the next byte is the same loss.
    overrun_counted: bool,
}

static SHARED: Mutex<RefCell<Option<Shared>>> = Mutex::new(RefCell::new(None));
/// `Receiver::loss` is set: lets the main loop skip the critical section otherwise.
static RX_LOSS_PENDING: AtomicBool = AtomicBool::new(false);
/// A loss began that the main loop has not announced yet ([`Serial::take_new_loss`]).
static RX_LOSS_NEW: AtomicBool = AtomicBool::new(false);
/// Framing, parity, break and hardware-FIFO overrun errors (wrapping). Only the interrupt
/// handlers write it (inside their critical section); the main loop reads it every pass
/// without one.
static RX_LINE_ERRORS: AtomicU32 = AtomicU32::new(0);

/// Lost bytes, and where: the gap begins after the first `after` bytes ever enqueued and ends
/// after the first `resume` (bytes enqueued in between are dropped when the gap is reached).
#[derive(Clone, Copy)]
struct Loss {
    after: u32,
    resume: u32,
    lost: Lost,
}

/// What the receiver delivers next, in stream order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Received {
    Byte(u8),
    /// Bytes were lost here (the receive queue was full, or the UART lost them).
    Lost(Lost),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub struct BaudOutOfRange;

/// The main loop's side of UART0.
pub struct Serial {
    rx_queue: RxConsumer<RX_QUEUE_BYTES>,
    /// Bytes taken from the queue so far (wrapping), to match `Loss::after`.
    rx_dequeued: u32,
    /// The gap just reached: queued bytes before this position are dropped.
    rx_skip_until: Option<u32>,
    tx_buffer: Deque<u8, TX_BUFFER_BYTES>,
    baud: u32,
    peripheral_clock: HertzU32,
    /// Line errors counted when [`Serial::take_new_line_errors`] last saw a change.
    rx_line_errors_seen: u32,
}

impl Serial {
    /// Configures UART0 at `baud` (8N1) and starts interrupt-driven receive.
    /// Call once: the receive queue is a static singleton.
    pub fn new(
        uart0: pac::UART0,
        tx_pin: DefaultPin<bank0::Gpio0>,
        rx_pin: DefaultPin<bank0::Gpio1>,
        resets: &mut pac::RESETS,
        peripheral_clock: HertzU32,
        baud: u32,
        mut poll: Alarm0,
    ) -> Result<Self, BaudOutOfRange> {
        check_baud(baud)?;
        let queue = cortex_m::singleton!(: RxRing<RX_QUEUE_BYTES> = RxRing::new())
            .expect("Serial::new is called once");
        let (producer, consumer) = queue.split();

        let pins = (tx_pin.reconfigure(), rx_pin.reconfigure());
        let mut uart = UartPeripheral::new(uart0, pins, resets)
            .enable(config(baud), peripheral_clock)
            .map_err(|_| BaudOutOfRange)?;
        // Interrupt when the FIFO holds 8 of 32 bytes (time to spare at 921,600 baud), or
        // after 32 bit times of silence with anything left in it.
        uart.set_rx_watermark(FifoWatermark::Bytes8);
        uart.enable_rx_interrupt();
        poll.enable_interrupt();

        critical_section::with(|cs| {
            SHARED.borrow(cs).replace(Some(Shared {
                uart: Some(uart),
                rx: Receiver {
                    queue: producer,
                    enqueued: 0,
                    loss: None,
                    overrun_counted: false,
                },
                poll,
                poll_period_us: rx_poll_period_us(baud),
            }));
        });
        // SAFETY: the handlers only use `SHARED`, which is initialised above.
        unsafe {
            pac::NVIC::unmask(pac::Interrupt::UART0_IRQ);
            pac::NVIC::unmask(pac::Interrupt::TIMER_IRQ_0);
        }

        Ok(Serial {
            rx_queue: consumer,
            rx_dequeued: 0,
            rx_skip_until: None,
            tx_buffer: Deque::new(),
            baud,
            peripheral_clock,
            rx_line_errors_seen: 0,
        })
    }

    /// The next received byte, or a note that bytes were lost at this point; `None` if
    /// nothing is waiting.
    pub fn read(&mut self) -> Option<Received> {
        if RX_LOSS_PENDING.load(Ordering::Relaxed) {
            if let Some(loss) = self.take_loss_at(self.rx_dequeued) {
                if loss.resume != loss.after {
                    self.rx_skip_until = Some(loss.resume);
                }
                return Some(Received::Lost(loss.lost));
            }
        }
        loop {
            let byte = self.rx_queue.dequeue()?;
            self.rx_dequeued = self.rx_dequeued.wrapping_add(1);
            match self.rx_skip_until {
                // Inside the gap (received between two losses): dropped with it.
                Some(resume) => {
                    if self.rx_dequeued == resume {
                        self.rx_skip_until = None;
                    }
                }
                None => return Some(Received::Byte(byte)),
            }
        }
    }

    /// Takes the plain characters of a command line at the front of the bytes received
    /// ([`Session::take_plain`]: into `session`'s line, echoed to this port's output), at most
    /// `most` of them; returns how many. None if bytes were lost and the main loop has not
    /// reached the gap yet (up to the gap, and past it, bytes go one by one, [`Serial::read`]),
    /// nor without room for a step's output ([`Serial::has_room_for_step`]: the echo).
    #[inline(always)]
    pub fn take_plain(&mut self, session: &mut Session, most: usize) -> usize {
        let Serial {
            rx_queue,
            rx_dequeued,
            rx_skip_until,
            tx_buffer,
            ..
        } = self;
        // One look at the bytes waiting, before the loss flag: a loss recorded after the look
        // is at a later position than any of them. The first byte decides at once for a line
        // end or a control byte (their latency).
        let run = rx_queue.waiting();
        if !run
            .first()
            .is_some_and(|&byte| protocol::is_plain_char(byte))
            || !session.may_take_plain()
            || !room_for_step(tx_buffer)
            || RX_LOSS_PENDING.load(Ordering::Acquire)
            || rx_skip_until.is_some()
        {
            return 0;
        }
        let run = &run[..run.len().min(most)];
        let taken = session.take_plain(run, &mut TxWriter(tx_buffer));
        rx_queue.consume(taken);
        *rx_dequeued = rx_dequeued.wrapping_add(taken as u32);
        taken
    }

    pub fn rx_pending(&self) -> bool {
        self.rx_queue.ready() || RX_LOSS_PENDING.load(Ordering::Relaxed)
    }

    /// If a loss began since the last call: how many bytes it has lost so far and whether the
    /// UART lost any (then the count is only a lower bound). For a warning at once; the gap
    /// itself comes later from [`Serial::read`].
    pub fn take_new_loss(&mut self) -> Option<Lost> {
        if !RX_LOSS_NEW.load(Ordering::Relaxed) {
            return None;
        }
        critical_section::with(|cs| {
            // Cleared with the interrupt masked, so a loss beginning now is not missed (the
            // M0+ has no atomic swap).
            RX_LOSS_NEW.store(false, Ordering::Relaxed);
            let shared = SHARED.borrow_ref(cs);
            shared.as_ref()?.rx.loss.map(|loss| loss.lost)
        })
    }

    fn take_loss_at(&self, position: u32) -> Option<Loss> {
        critical_section::with(|cs| {
            let mut shared = SHARED.borrow_ref_mut(cs);
            let shared = shared.as_mut()?;
            let loss = shared.rx.loss.filter(|loss| loss.after == position)?;
            shared.rx.loss = None;
            RX_LOSS_PENDING.store(false, Ordering::Relaxed);
            Some(loss)
        })
    }

    /// If the receiver has seen framing, parity, break or hardware-FIFO overrun errors since
    /// the last call: how many so far (for the log).
    pub fn take_new_line_errors(&mut self) -> Option<u32> {
        let errors = self.rx_line_errors();
        if errors == self.rx_line_errors_seen {
            return None;
        }
        self.rx_line_errors_seen = errors;
        Some(errors)
    }

    /// Framing, parity, break and hardware-FIFO overrun errors seen by the receiver.
    fn rx_line_errors(&self) -> u32 {
        RX_LINE_ERRORS.load(Ordering::Relaxed)
    }

    /// True if the transmit buffer can take [`LONGEST_STEP_BYTES`] without waiting.
    pub fn has_room_for_step(&self) -> bool {
        room_for_step(&self.tx_buffer)
    }

    /// True once everything written has left the UART (FIFO empty, last stop bit sent).
    pub fn tx_idle(&self) -> bool {
        !self.tx_pending()
            && critical_section::with(|cs| {
                let shared = SHARED.borrow_ref(cs);
                shared
                    .as_ref()
                    .and_then(|shared| shared.uart.as_ref())
                    .is_none_or(|uart| !uart.uart_is_busy())
            })
    }

    /// True while buffered output has not all gone into the TX FIFO yet.
    pub fn tx_pending(&self) -> bool {
        !self.tx_buffer.is_empty()
    }

    /// Moves as much buffered output into the TX FIFO as fits; never waits. If output is left
    /// (the FIFO is full), the TX interrupt is armed to wake the main loop when the FIFO has
    /// drained to half.
    #[inline(always)]
    pub fn send_some(&mut self) {
        if !self.tx_buffer.is_empty() {
            send_some(&mut self.tx_buffer);
        }
    }

    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// Switches to `baud`. Call it once everything written has gone out at the old rate
    /// ([`Serial::tx_idle`]: the reply that announces a change must arrive readably); output
    /// still waiting then would go out at the new rate.
    pub fn set_baud(&mut self, baud: u32) -> Result<(), BaudOutOfRange> {
        check_baud(baud)?;
        if baud == self.baud {
            return Ok(());
        }
        let peripheral_clock = self.peripheral_clock;
        critical_section::with(|cs| {
            let mut shared = SHARED.borrow_ref_mut(cs);
            let Some(shared) = shared.as_mut() else {
                return;
            };
            let Some(uart) = shared.uart.take() else {
                return;
            };
            // The last byte has left the shift register (tx_idle); should it not have, wait
            // for it (at most one character time) rather than garble it.
            while uart.uart_is_busy() {}
            // Cannot fail: `check_baud` keeps the divider in range for a 125 MHz clk_peri.
            let Ok(uart) = uart.disable().enable(config(baud), peripheral_clock) else {
                panic!("UART0 rejected a checked baud rate");
            };
            // The interrupt mask and FIFO watermark survive disable/enable.
            shared.uart = Some(uart);
            shared.poll_period_us = rx_poll_period_us(baud);
        });
        self.baud = baud;
        Ok(())
    }
}

/// Buffers output. Should the buffer fill up anyway (the main loop checks
/// [`Serial::has_room_for_step`] first), it waits for the line to take bytes: back-pressure,
/// never silent loss, since a host relies on every reply arriving whole.
impl fmt::Write for Serial {
    fn write_str(&mut self, text: &str) -> fmt::Result {
        TxWriter(&mut self.tx_buffer).write_str(text)
    }
}

/// The transmit buffer as output: what [`Serial`]'s `fmt::Write` does, for code that holds
/// the buffer beside the receive queue ([`Serial::take_plain`]).
struct TxWriter<'a>(&'a mut Deque<u8, TX_BUFFER_BYTES>);

impl fmt::Write for TxWriter<'_> {
    fn write_str(&mut self, text: &str) -> fmt::Result {
        for &byte in text.as_bytes() {
            while self.0.push_back(byte).is_err() {
                send_some(self.0);
            }
        }
        Ok(())
    }
}

/// [`Serial::has_room_for_step`], on the transmit buffer.
#[inline(always)]
fn room_for_step(tx_buffer: &Deque<u8, TX_BUFFER_BYTES>) -> bool {
    tx_buffer.capacity() - tx_buffer.len() >= LONGEST_STEP_BYTES
}

/// [`Serial::send_some`], on the transmit buffer.
fn send_some(tx_buffer: &mut Deque<u8, TX_BUFFER_BYTES>) {
    if tx_buffer.is_empty() {
        return;
    }
    let written = critical_section::with(|cs| {
        let mut shared = SHARED.borrow_ref_mut(cs);
        let Some(uart) = shared.as_mut().and_then(|shared| shared.uart.as_mut()) else {
            return 0;
        };
        let mut written = 0;
        // Both halves of the ring buffer, as far as the FIFO takes them.
        let (front, back) = tx_buffer.as_slices();
        for part in [front, back] {
            match uart.write_raw(part) {
                Ok(rest) => {
                    written += part.len() - rest.len();
                    if !rest.is_empty() {
                        break;
                    }
                }
                Err(_) => break, // nb::WouldBlock: FIFO full
            }
        }
        if written < tx_buffer.len() {
            uart.enable_tx_interrupt();
        }
        written
    });
    for _ in 0..written {
        tx_buffer.pop_front();
    }
}

fn check_baud(baud: u32) -> Result<(), BaudOutOfRange> {
    if (BAUD_MIN..=BAUD_MAX).contains(&baud) {
        Ok(())
    } else {
        Err(BaudOutOfRange)
    }
}

fn config(baud: u32) -> UartConfig {
    UartConfig::new(baud.Hz(), DataBits::Eight, None, StopBits::One)
}

impl Shared {
    /// Masks the TX interrupt if it fired (the main loop, now awake, refills the FIFO and arms
    /// it again if it must), then empties the RX FIFO.
    fn service(&mut self) {
        let Some(uart) = self.uart.as_mut() else {
            return;
        };
        // SAFETY: a read of UART0's masked interrupt status, which has no side effect.
        let tx_fired = unsafe { (*pac::UART0::ptr()).uartmis().read().txmis().bit_is_set() };
        if tx_fired {
            uart.disable_tx_interrupt();
        }
        self.receive_and_poll();
    }

    /// Empties the RX FIFO; if it held anything, more may be on the way: polls again after
    /// [`rx_poll_period_us`] (at the rates that poll).
    fn receive_and_poll(&mut self) {
        if self.receive() > 0 {
            if let Some(period_us) = self.poll_period_us {
                // Cannot fail: the period is far below the alarm's range.
                let _ = self.poll.schedule(MicrosDurationU32::micros(period_us));
            }
        }
    }

    /// Empties the RX FIFO into the queue; this also clears the level and timeout interrupts.
    /// Returns how many bytes (or errors) it took.
    ///
    /// Reads the PL011's registers directly, a byte at a time straight into the queue, as
    /// rp2040-hal's `read_raw` reads them (its loop, its error precedence and its overrun
    /// check of the status register when the FIFO is empty; by way of a 32-byte buffer and
    /// an error value per fault, it cost four times the cycles a byte).
    fn receive(&mut self) -> usize {
        if self.uart.is_none() {
            return 0;
        }
        // SAFETY: reads of UART0's flag and data registers, and the write that clears its
        // receive status, on the receiving side the handlers own (inside their critical
        // section); the HAL's `UartPeripheral` is only used to transmit and configure.
        let uart = unsafe { &*pac::UART0::ptr() };
        let mut taken = 0;
        // Good bytes go straight into the queue, staged (`held` of them) and handed over
        // together when something else comes (an error, an empty FIFO) or the queue is full.
        let mut room = self.rx.queue.room();
        let mut held = 0;
        // Bounded: a FIFO holds 32 bytes, so a few rounds empty it; should a (broken) UART keep
        // reporting errors, the interrupt returns and fires again instead of hanging here.
        for _ in 0..RX_READS_PER_INTERRUPT {
            if uart.uartfr().read().rxfe().bit_is_set() {
                self.rx.publish(held);
                held = 0;
                // An overrun with the FIFO empty shows only in the status register: the next
                // byte will carry its flag too (counted once, below). Cleared, or it sticks.
                if uart.uartrsr().read().oe().bit_is_clear() {
                    break;
                }
                // SAFETY: any write clears the receive status (PL011 UARTECR).
                unsafe { uart.uartrsr().write_with_zero(|w| w) };
                taken += 1;
                self.rx.uart_loss();
                self.rx.overrun_counted = true;
                room = self.rx.queue.room();
                continue;
            }
            let read = uart.uartdr().read().bits();
            taken += 1;
            if read & (DR_OE | DR_BE | DR_PE | DR_FE) == 0 {
                if held < room {
                    self.rx.queue.stage(held, read as u8);
                    held += 1;
                } else {
                    // The queue is full: this byte is lost, after those staged.
                    self.rx.publish(held);
                    held = 0;
                    self.rx.push(read as u8);
                    room = self.rx.queue.room();
                }
                continue;
            }
            self.rx.publish(held);
            held = 0;
            // A break, parity or framing error loses the byte. An overrun flags a good byte:
            // the bytes the full FIFO could not take were lost just before it, how many the
            // UART cannot tell. Either way the line the loss cuts must be refused, so it goes
            // in at its place.
            if read & (DR_BE | DR_PE | DR_FE) != 0 {
                self.rx.uart_loss();
                room = self.rx.queue.room();
                continue;
            }
            if !core::mem::take(&mut self.rx.overrun_counted) {
                self.rx.uart_loss();
            }
            self.rx.push(read as u8);
            room = self.rx.queue.room();
        }
        self.rx.publish(held);
        taken
    }
}

/// Most reads of the RX FIFO (bytes or errors) in one interrupt: eight FIFOs' worth.
const RX_READS_PER_INTERRUPT: usize = 256;
/// UARTDR's error flags (PL011): overrun, break, parity, framing.
const DR_OE: u32 = 1 << 11;
const DR_BE: u32 = 1 << 10;
const DR_PE: u32 = 1 << 9;
const DR_FE: u32 = 1 << 8;

impl Receiver {
    /// Hands the `count` bytes staged in the queue to the main loop (see [`Shared::receive`]).
    #[inline(always)]
    fn publish(&mut self, count: usize) {
        if count > 0 {
            self.queue.publish(count);
            self.enqueued = self.enqueued.wrapping_add(count as u32);
        }
    }

    /// Queues `byte` after the bytes published; without room it is lost, here.
    fn push(&mut self, byte: u8) {
        if self.queue.room() > 0 {
            self.queue.stage(0, byte);
            self.publish(1);
        } else {
            self.lose(1, false);
        }
    }

    /// The UART lost at least one byte here.
    fn uart_loss(&mut self) {
        // Only the handlers write it, never two at once (they run in a critical section).
        let errors = RX_LINE_ERRORS.load(Ordering::Relaxed);
        RX_LINE_ERRORS.store(errors.wrapping_add(1), Ordering::Relaxed);
        self.lose(1, true);
    }

    /// `bytes` were lost here. A gap the main loop has not reached yet grows to this point (the
    /// bytes queued since its start are dropped with it, and counted), so it stays one stretch
    /// at one known position: the line it cuts is refused, and no line is ever pieced together
    /// from fragments around a gap the main loop was not told of.
    fn lose(&mut self, bytes: u32, in_uart: bool) {
        let at = self.enqueued;
        let loss = self.loss.get_or_insert_with(|| {
            RX_LOSS_NEW.store(true, Ordering::Relaxed);
            Loss {
                after: at,
                resume: at,
                lost: Lost {
                    bytes: 0,
                    in_uart: false,
                },
            }
        });
        let dropped_between = at.wrapping_sub(loss.resume);
        loss.resume = at;
        loss.lost.bytes = loss
            .lost
            .bytes
            .wrapping_add(bytes)
            .wrapping_add(dropped_between);
        loss.lost.in_uart |= in_uart;
        RX_LOSS_PENDING.store(true, Ordering::Relaxed);
    }
}

#[interrupt]
fn UART0_IRQ() {
    critical_section::with(|cs| {
        if let Some(shared) = SHARED.borrow_ref_mut(cs).as_mut() {
            shared.service();
        }
    });
}

/// The RX poll (see the module documentation).
#[interrupt]
fn TIMER_IRQ_0() {
    critical_section::with(|cs| {
        if let Some(shared) = SHARED.borrow_ref_mut(cs).as_mut() {
            shared.poll.clear_interrupt();
            shared.receive_and_poll();
        }
    });
}
