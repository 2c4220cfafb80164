//! UART0 on GP0 (TX) / GP1 (RX), 8N1, baud rate changeable at run time.
//!
//! Receive: the `UART0_IRQ` handler (RX FIFO level and RX timeout interrupts) moves bytes from
//! the 32-byte hardware FIFO into a lock-free queue that the main loop reads. It never waits:
//! when the queue is full it drops the byte and counts it, and the main loop is told where in
//! the byte stream the loss happened ([`Received::Lost`]), so exactly the damaged line can be
//! refused. After a loss, bytes are dropped until the main loop has reached it, so a loss is
//! always one contiguous gap. A byte with a line error (framing, parity, break, overrun) counts
//! as lost the same way.
//!
//! Transmit: the main loop writes replies into a software buffer (`core::fmt::Write`) and calls
//! [`Serial::send_some`] each pass, which moves only what fits into the 32-byte TX FIFO.

use core::{
    cell::RefCell,
    fmt,
    sync::atomic::{AtomicBool, Ordering},
};

use critical_section::Mutex;
use heapless::{
    spsc::{Consumer, Producer, Queue},
    Deque,
};
use rp2040_hal::{
    fugit::{HertzU32, RateExtU32},
    gpio::{bank0, DefaultTypeState, FunctionUart, Pin, PullNone, PullUp},
    pac::{self, interrupt},
    uart::{DataBits, Enabled, FifoWatermark, ReadErrorType, StopBits, UartConfig, UartPeripheral},
};

/// Receive queue size; holds `RX_QUEUE_BYTES - 1` bytes (~44 ms of input at 115,200 baud).
pub const RX_QUEUE_BYTES: usize = 512;
/// The longest reply one received byte may produce (the command interpreter's help or
/// settings listing).
pub const LONGEST_REPLY_BYTES: usize = 2048;
/// Transmit buffer: room for two of the longest replies.
pub const TX_BUFFER_BYTES: usize = 2 * LONGEST_REPLY_BYTES;

/// The UART accepts the controller's baud rates (`set baud`), slowest to fastest.
pub const BAUD_MIN: u32 = control::settings::BAUD_RATES[0];
pub const BAUD_MAX: u32 = control::settings::BAUD_RATES[control::settings::BAUD_RATES.len() - 1];

type TxPin = Pin<bank0::Gpio0, FunctionUart, PullNone>;
/// Pulled up so an unconnected RX line idles high instead of reading breaks.
type RxPin = Pin<bank0::Gpio1, FunctionUart, PullUp>;
type Uart = UartPeripheral<Enabled, pac::UART0, (TxPin, RxPin)>;
type DefaultPin<Id> =
    Pin<Id, <Id as DefaultTypeState>::Function, <Id as DefaultTypeState>::PullType>;

/// State shared by `UART0_IRQ` and the main loop, only ever touched inside a critical section.
struct Shared {
    /// `None` only during a baud-rate change, which happens inside one critical section.
    uart: Option<Uart>,
    rx: Receiver,
}

/// The interrupt's side of the receive queue.
struct Receiver {
    queue: Producer<'static, u8, RX_QUEUE_BYTES>,
    /// Bytes put into the queue so far (wrapping): positions in the received stream.
    enqueued: u32,
    /// Bytes dropped (queue full) that the main loop has not been told about yet.
    loss: Option<Loss>,
    /// Framing, parity, break and hardware-FIFO overrun errors.
    line_errors: u32,
}

static SHARED: Mutex<RefCell<Option<Shared>>> = Mutex::new(RefCell::new(None));
/// `Receiver::loss` is set: lets the main loop skip the critical section otherwise.
static RX_LOSS_PENDING: AtomicBool = AtomicBool::new(false);

/// Dropped bytes, and where: after the first `after` bytes ever enqueued.
#[derive(Clone, Copy)]
struct Loss {
    after: u32,
    bytes: u32,
}

/// What the receiver delivers next, in stream order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Received {
    Byte(u8),
    /// This many bytes were lost here because the main loop fell behind (queue full).
    Lost(u32),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub struct BaudOutOfRange;

/// The main loop's side of UART0.
pub struct Serial {
    rx_queue: Consumer<'static, u8, RX_QUEUE_BYTES>,
    /// Bytes taken from the queue so far (wrapping), to match `Loss::after`.
    rx_dequeued: u32,
    tx_buffer: Deque<u8, TX_BUFFER_BYTES>,
    baud: u32,
    peripheral_clock: HertzU32,
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
    ) -> Result<Self, BaudOutOfRange> {
        check_baud(baud)?;
        let queue = cortex_m::singleton!(: Queue<u8, RX_QUEUE_BYTES> = Queue::new())
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

        critical_section::with(|cs| {
            SHARED.borrow(cs).replace(Some(Shared {
                uart: Some(uart),
                rx: Receiver {
                    queue: producer,
                    enqueued: 0,
                    loss: None,
                    line_errors: 0,
                },
            }));
        });
        // SAFETY: the handler only uses `SHARED`, which is initialised above.
        unsafe { pac::NVIC::unmask(pac::Interrupt::UART0_IRQ) };

        Ok(Serial {
            rx_queue: consumer,
            rx_dequeued: 0,
            tx_buffer: Deque::new(),
            baud,
            peripheral_clock,
        })
    }

    /// The next received byte, or a note that bytes were lost at this point; `None` if
    /// nothing is waiting.
    pub fn read(&mut self) -> Option<Received> {
        if RX_LOSS_PENDING.load(Ordering::Relaxed) {
            if let Some(bytes) = self.take_loss_at(self.rx_dequeued) {
                return Some(Received::Lost(bytes));
            }
        }
        let byte = self.rx_queue.dequeue()?;
        self.rx_dequeued = self.rx_dequeued.wrapping_add(1);
        Some(Received::Byte(byte))
    }

    pub fn rx_pending(&self) -> bool {
        self.rx_queue.ready() || RX_LOSS_PENDING.load(Ordering::Relaxed)
    }

    fn take_loss_at(&self, position: u32) -> Option<u32> {
        critical_section::with(|cs| {
            let mut shared = SHARED.borrow_ref_mut(cs);
            let shared = shared.as_mut()?;
            let loss = shared.rx.loss.filter(|loss| loss.after == position)?;
            shared.rx.loss = None;
            RX_LOSS_PENDING.store(false, Ordering::Relaxed);
            Some(loss.bytes)
        })
    }

    /// Framing, parity, break and hardware-FIFO overrun errors seen by the receiver.
    pub fn rx_line_errors(&self) -> u32 {
        critical_section::with(|cs| {
            SHARED
                .borrow_ref(cs)
                .as_ref()
                .map_or(0, |shared| shared.rx.line_errors)
        })
    }

    /// True if the transmit buffer can take [`LONGEST_REPLY_BYTES`] without waiting.
    pub fn has_room_for_reply(&self) -> bool {
        self.tx_buffer.capacity() - self.tx_buffer.len() >= LONGEST_REPLY_BYTES
    }

    /// True while buffered output has not all gone into the TX FIFO yet.
    pub fn tx_pending(&self) -> bool {
        !self.tx_buffer.is_empty()
    }

    /// Moves as much buffered output into the TX FIFO as fits; never waits.
    pub fn send_some(&mut self) {
        if self.tx_buffer.is_empty() {
            return;
        }
        let written = critical_section::with(|cs| {
            let shared = SHARED.borrow_ref(cs);
            let Some(uart) = shared.as_ref().and_then(|shared| shared.uart.as_ref()) else {
                return 0;
            };
            let (front, _) = self.tx_buffer.as_slices();
            match uart.write_raw(front) {
                Ok(rest) => front.len() - rest.len(),
                Err(_) => 0, // nb::WouldBlock: FIFO full
            }
        });
        for _ in 0..written {
            self.tx_buffer.pop_front();
        }
    }

    pub fn baud(&self) -> u32 {
        self.baud
    }

    /// Switches to `baud` after everything already buffered has been sent at the old rate
    /// (so the reply that announces a change arrives readably). Blocks for that long.
    pub fn set_baud(&mut self, baud: u32) -> Result<(), BaudOutOfRange> {
        check_baud(baud)?;
        if baud == self.baud {
            return Ok(());
        }
        while self.tx_pending() {
            self.send_some();
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
            // Let the last byte leave the shift register before changing its clock.
            while uart.uart_is_busy() {}
            // Cannot fail: `check_baud` keeps the divider in range for a 125 MHz clk_peri.
            let Ok(uart) = uart.disable().enable(config(baud), peripheral_clock) else {
                panic!("UART0 rejected a checked baud rate");
            };
            // The interrupt mask and FIFO watermark survive disable/enable.
            shared.uart = Some(uart);
        });
        self.baud = baud;
        Ok(())
    }
}

/// Buffers output. Should the buffer fill up anyway (the main loop checks
/// [`Serial::has_room_for_reply`] first), it waits for the line to take bytes: back-pressure,
/// never silent loss, since a host relies on every reply arriving whole.
impl fmt::Write for Serial {
    fn write_str(&mut self, text: &str) -> fmt::Result {
        for &byte in text.as_bytes() {
            while self.tx_buffer.push_back(byte).is_err() {
                self.send_some();
            }
        }
        Ok(())
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
    /// Empties the RX FIFO into the queue; this also clears the level and timeout interrupts.
    fn receive(&mut self) {
        let Some(uart) = self.uart.as_ref() else {
            return;
        };
        let mut chunk = [0u8; 32];
        // Bounded: a FIFO holds 32 bytes, so a few rounds empty it; should a (broken) UART keep
        // reporting errors, the interrupt returns and fires again instead of hanging here.
        for _ in 0..8 {
            match uart.read_raw(&mut chunk) {
                Ok(count) => self.rx.enqueue(&chunk[..count]),
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(error)) => {
                    self.rx.line_errors = self.rx.line_errors.wrapping_add(1);
                    // `discarded` holds the good bytes read before the error. A framing,
                    // parity or break error loses the byte after them. An overrun flags a
                    // good byte (the last one in `discarded`, if any): the bytes the full
                    // hardware FIFO could not take were lost just before it. Either way the
                    // line they belong to must be refused, so the loss goes in at its place.
                    let (before, after) = match error.err_type {
                        ReadErrorType::Overrun if !error.discarded.is_empty() => {
                            error.discarded.split_at(error.discarded.len() - 1)
                        }
                        _ => (error.discarded, &[][..]),
                    };
                    self.rx.enqueue(before);
                    self.rx.lose(1);
                    self.rx.enqueue(after);
                }
            }
        }
    }
}

impl Receiver {
    fn enqueue(&mut self, bytes: &[u8]) {
        for &byte in bytes {
            // Once a byte is lost, every byte is dropped until the main loop has reached the
            // gap (the queue is then empty) and taken the loss: the gap stays one contiguous
            // stretch at one known position, so the line it cuts is refused and no line is
            // ever pieced together from fragments around a gap the main loop was not told of.
            if self.loss.is_none() && self.queue.enqueue(byte).is_ok() {
                self.enqueued = self.enqueued.wrapping_add(1);
                continue;
            }
            self.lose(1);
        }
    }

    fn lose(&mut self, bytes: u32) {
        let loss = self.loss.get_or_insert(Loss {
            after: self.enqueued,
            bytes: 0,
        });
        loss.bytes = loss.bytes.wrapping_add(bytes);
        RX_LOSS_PENDING.store(true, Ordering::Relaxed);
    }
}

#[interrupt]
fn UART0_IRQ() {
    critical_section::with(|cs| {
        if let Some(shared) = SHARED.borrow_ref_mut(cs).as_mut() {
            shared.receive();
        }
    });
}
