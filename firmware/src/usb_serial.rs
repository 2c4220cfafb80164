//! The Pico's own USB port as a CDC ACM serial port (`/dev/ttyACM0`, `COMx`), the second link
//! beside UART0, speaking the same protocol. Sizes are in bytes, times in microseconds of the
//! RP2040's 1 MHz timer.
//!
//! The USB device is serviced from its interrupt (`USBCTRL_IRQ`), never from the main loop, so
//! enumeration and the host's control requests are answered within microseconds even while the
//! main loop is busy. The handler is short: it polls the device, moves received bytes into a
//! lock-free receive queue and queued output into the endpoint, and returns.
//!
//! Receive is lossless. A bulk OUT packet is taken from its endpoint buffer only when the
//! receive queue has room for a whole packet; otherwise it stays there, unacknowledged, and the
//! host's further packets are refused (NAK) and retried by the host: USB's own flow control.
//! The main loop reads the queue, and when it has made room again it takes the packet that
//! waited. So nothing is ever lost on USB and there is no `rx-overflow` here.
//!
//! Transmit: the main loop writes replies into a transmit queue (`core::fmt::Write`) and hands
//! what it wrote to the port once per pass; the interrupt hands on the rest, a packet at a time,
//! as the host takes them. The main loop feeds the controller a step only with room for the
//! step's output ([`UsbSerial::has_room_for_step`]), so a host that reads slowly slows its own
//! link down and nothing else. Output is not kept for nobody:
//! - while the host does not have the port open (DTR low, not configured, suspended or
//!   unplugged) output is dropped: no one would read it, and a terminal opening the port later
//!   wants a fresh start (the banner and a prompt), not an old backlog. (What the USB hardware
//!   and usbd-serial already held when the port closed, at most a packet and 128 bytes, reaches
//!   the next opener before its banner: neither can be taken back. Programs read up to the
//!   banner after opening the port, README.md says.)
//! - a host that has the port open but stops reading for [`STALL_US`] while output waits (its
//!   program reads nothing and its OS buffers are full) is taken to have stopped listening:
//!   what is queued stays queued (up to [`TX_QUEUE_BYTES`]), further output is dropped until
//!   the host takes a packet again. Input from such a host is still taken (a program that
//!   streams poses and never reads the `ok`s keeps working).
//! - a host that reads, but too slowly for a command of its own under way while input waits
//!   on the other link (or that stopped reading less than [`STALL_US`] ago), has its output
//!   given up by the main loop ([`UsbSerial::give_up_output`], after
//!   [`crate::link::HOLD_UP_US`]): dropped until it has taken all that was queued. Without
//!   that, a reply to this link could keep the controller waiting as long as the host takes
//!   to read it (seconds, for ever) and with it the other link's commands.
//!
//! Opening and closing are the host's doing (DTR, `SET_CONTROL_LINE_STATE`): the main loop asks
//! [`UsbSerial::take_open_change`] and greets a newly opened port with the banner and a prompt.
//! `baud` is UART0's setting; the line coding a host sets on this port changes nothing.

use core::{
    cell::RefCell,
    fmt,
    sync::atomic::{AtomicBool, AtomicU32, Ordering},
};

use critical_section::Mutex;
use heapless::spsc::{Consumer, Producer, Queue};
use rp2040_hal::{
    clocks::UsbClock,
    pac::{self, interrupt},
    usb::UsbBus,
};
use usb_device::{
    class_prelude::UsbBusAllocator,
    device::{StringDescriptors, UsbDevice, UsbDeviceBuilder, UsbDeviceState, UsbVidPid},
};
use usbd_serial::{SerialPort, USB_CLASS_CDC};

use crate::serial::{Received, LONGEST_STEP_BYTES};

/// The USB IDs (`control::report::USB_VID`, `USB_PID`: the pid.codes test vendor and product,
/// by which the host tool finds boards).
const VID_PID: UsbVidPid = UsbVidPid(control::report::USB_VID, control::report::USB_PID);
/// Control endpoint 0's packet size: the largest a full-speed device may use (rp2040-hal
/// recommends it; smaller sizes trip a Windows enumeration quirk).
const EP0_PACKET_BYTES: u8 = 64;
/// A full-speed bulk packet.
const PACKET_BYTES: usize = 64;

/// Receive queue size; holds `RX_QUEUE_BYTES - 1` bytes: room for a host to send well ahead of
/// the main loop (about 20 `pose` lines) while a command's work runs; beyond it the host waits.
pub const RX_QUEUE_BYTES: usize = 1024;
/// Transmit queue size; holds `TX_QUEUE_BYTES - 1` bytes: a step's output always fits when
/// [`UsbSerial::has_room_for_step`], and a full-speed host takes 4 KB in about 4 ms.
pub const TX_QUEUE_BYTES: usize = 2 * LONGEST_STEP_BYTES;
/// A host with the port open that takes no output for this long while some waits has stopped
/// reading: output to it is dropped until it reads again. Real hosts poll the endpoint every
/// millisecond and buffer tens of kilobytes, so only a program that has stopped reading for good
/// (or a stalled bus) gets here.
pub const STALL_US: u32 = 100_000;

/// The bulk OUT endpoints' bits in BUFF_STATUS (odd bits, endpoint 0's excepted).
const DATA_OUT_BUFFER_BITS: u32 = 0xAAAA_AAA8;

/// What the interrupt owns, only ever touched inside a critical section.
struct Shared {
    device: UsbDevice<'static, UsbBus>,
    port: SerialPort<'static, UsbBus>,
    rx: Producer<'static, u8, RX_QUEUE_BYTES>,
    tx: Consumer<'static, u8, TX_QUEUE_BYTES>,
    /// `HOST_OPEN` as this handler last set it.
    was_open: bool,
    /// Output taken from the transmit queue that the port has not accepted yet.
    tx_packet: [u8; PACKET_BYTES],
    tx_packet_len: usize,
    tx_packet_sent: usize,
}

static SHARED: Mutex<RefCell<Option<Shared>>> = Mutex::new(RefCell::new(None));
/// The host has the port open: configured and DTR set (written by the interrupt).
static HOST_OPEN: AtomicBool = AtomicBool::new(false);
/// Times the host has opened the port (wrapping; written by the interrupt): an opening the
/// main loop did not see `HOST_OPEN` low for (closed and opened again within a pass) still
/// counts as a new terminal.
static OPENINGS: AtomicU32 = AtomicU32::new(0);
/// The interrupt left received data unread for lack of room in the receive queue.
static RX_HELD: AtomicBool = AtomicBool::new(false);
/// Bytes the port has accepted for sending so far (wrapping): progress of the output.
static TX_TAKEN: AtomicU32 = AtomicU32::new(0);

/// The main loop's side of the USB serial port.
pub struct UsbSerial {
    rx: Consumer<'static, u8, RX_QUEUE_BYTES>,
    tx: Producer<'static, u8, TX_QUEUE_BYTES>,
    /// The link as the main loop treats it: open (the banner has been written) or not.
    open: bool,
    /// `OPENINGS` when the link was last opened.
    openings_seen: u32,
    /// The host stopped reading: output is dropped until it takes some again.
    stalled: bool,
    /// Output was given up ([`UsbSerial::give_up_output`]): dropped until the queue is empty.
    given_up: bool,
    /// `TX_TAKEN` when output last moved (or nothing waited), and when that was.
    taken_seen: u32,
    moved_at_us: u32,
    /// Output was queued since the interrupt was last asked to send it.
    unsent: bool,
    /// Output dropped (port closed, host not reading), for the log.
    dropped_bytes: u32,
}

impl UsbSerial {
    /// Brings up the USB device (full speed, CDC ACM, named with `serial_number`: the board's
    /// id, so that `/dev/serial/by-id/` tells boards apart) and starts servicing it from its
    /// interrupt. Call once: the queues and the bus are static singletons.
    pub fn new(
        regs: pac::USBCTRL_REGS,
        dpram: pac::USBCTRL_DPRAM,
        usb_clock: UsbClock,
        resets: &mut pac::RESETS,
        serial_number: &'static str,
    ) -> Self {
        // The Pico does not route VBUS to the USB controller's detect input: force it.
        let bus = UsbBus::new(regs, dpram, usb_clock, true, resets);
        let allocator = cortex_m::singleton!(: UsbBusAllocator<UsbBus> = UsbBusAllocator::new(bus))
            .expect("UsbSerial::new is called once");
        let port = SerialPort::new(allocator);
        let strings = StringDescriptors::default()
            .manufacturer(control::report::USB_MANUFACTURER)
            .product(control::report::USB_PRODUCT)
            .serial_number(serial_number);
        let device = UsbDeviceBuilder::new(allocator, VID_PID)
            .strings(&[strings])
            .expect("one language")
            .device_class(USB_CLASS_CDC)
            .max_packet_size_0(EP0_PACKET_BYTES)
            .expect("64 is a valid control packet size")
            .build();

        let rx_queue = cortex_m::singleton!(: Queue<u8, RX_QUEUE_BYTES> = Queue::new())
            .expect("UsbSerial::new is called once");
        let tx_queue = cortex_m::singleton!(: Queue<u8, TX_QUEUE_BYTES> = Queue::new())
            .expect("UsbSerial::new is called once");
        let (rx_producer, rx_consumer) = rx_queue.split();
        let (tx_producer, tx_consumer) = tx_queue.split();

        critical_section::with(|cs| {
            SHARED.borrow(cs).replace(Some(Shared {
                device,
                port,
                rx: rx_producer,
                tx: tx_consumer,
                was_open: false,
                tx_packet: [0; PACKET_BYTES],
                tx_packet_len: 0,
                tx_packet_sent: 0,
            }));
        });
        // SAFETY: the handler only uses `SHARED`, which is initialised above.
        unsafe { pac::NVIC::unmask(pac::Interrupt::USBCTRL_IRQ) };

        UsbSerial {
            rx: rx_consumer,
            tx: tx_producer,
            open: false,
            openings_seen: 0,
            stalled: false,
            given_up: false,
            taken_seen: 0,
            moved_at_us: 0,
            unsent: false,
            dropped_bytes: 0,
        }
    }

    /// If the host opened or closed the port since the last call: `Some(true)` when it opened
    /// (write the banner now), `Some(false)` when it closed (closed and opened again: the next
    /// call says it opened). A closing counts at once (output is dropped from now on); an
    /// opening waits while `reply_awaited` (the link's command still runs: its reply belongs to
    /// the terminal that closed, and is dropped with it).
    pub fn take_open_change(&mut self, reply_awaited: bool) -> Option<bool> {
        let change = self.open_change(reply_awaited)?;
        self.open = change;
        self.stalled = false;
        self.given_up = false;
        if change {
            self.openings_seen = OPENINGS.load(Ordering::Relaxed);
        }
        Some(change)
    }

    /// Whether [`UsbSerial::take_open_change`] has something to say now.
    pub fn open_change_pending(&self, reply_awaited: bool) -> bool {
        self.open_change(reply_awaited).is_some()
    }

    fn open_change(&self, reply_awaited: bool) -> Option<bool> {
        let host_open = HOST_OPEN.load(Ordering::Relaxed);
        let reopened = OPENINGS.load(Ordering::Relaxed) != self.openings_seen;
        if self.open && (!host_open || reopened) {
            Some(false)
        } else if !self.open && host_open && !reply_awaited {
            Some(true)
        } else {
            None
        }
    }

    /// Watches the output: a host that has the port open and has taken none of it for
    /// [`STALL_US`] has stopped reading, and output to it is dropped until it takes some again.
    /// Call once per main-loop pass with the timer's microseconds.
    pub fn watch_output(&mut self, now_us: u32) {
        let taken = TX_TAKEN.load(Ordering::Relaxed);
        let drained = self.tx.len() == 0 || !self.open;
        if taken != self.taken_seen || drained {
            self.taken_seen = taken;
            self.moved_at_us = now_us;
            if self.stalled && (drained || !self.given_up) {
                defmt::info!(
                    "USB host reads again ({} bytes dropped)",
                    self.dropped_bytes
                );
                self.stalled = false;
                self.given_up = false;
            }
        } else if !self.stalled && now_us.wrapping_sub(self.moved_at_us) >= STALL_US {
            defmt::warn!("USB host stopped reading: output dropped until it reads again");
            self.stalled = true;
        }
    }

    /// Another link's input waited too long behind this link's output (the host reads too
    /// slowly, or not at all, for the command under way: [`crate::link::HOLD_UP_US`]): output
    /// is dropped from now on, until the host has taken all that was queued.
    pub fn give_up_output(&mut self) {
        if !self.stalled {
            defmt::warn!("USB host reads too slowly: output dropped until it has caught up");
        }
        self.stalled = true;
        self.given_up = true;
    }

    /// True if the controller may take a step on this link: its output fits in the transmit
    /// queue, or is dropped anyway (the port is closed, or its host stopped reading).
    pub fn has_room_for_step(&self) -> bool {
        !self.open || self.stalled || self.tx.capacity() - self.tx.len() >= LONGEST_STEP_BYTES
    }

    /// True if notices should be written to this link now. A closed link keeps them (in the
    /// controller: the latest few) for the banner when it opens.
    pub fn takes_notices(&self) -> bool {
        self.open && self.has_room_for_step()
    }

    /// The next received byte, if any. Never [`Received::Lost`]: USB loses nothing.
    pub fn read(&mut self) -> Option<Received> {
        let byte = self.rx.dequeue()?;
        // Received data waits in the endpoint for room: there is room now.
        if RX_HELD.load(Ordering::Relaxed) && self.rx.capacity() - self.rx.len() >= PACKET_BYTES {
            with_shared(Shared::receive);
        }
        Some(Received::Byte(byte))
    }

    pub fn rx_pending(&self) -> bool {
        self.rx.ready()
    }

    /// Hands what was written since the last call to the port (as much as it takes now; the
    /// interrupt sends the rest as the host takes packets). Call once per pass.
    pub fn send_some(&mut self) {
        if core::mem::take(&mut self.unsent) {
            with_shared(|shared| shared.transmit(HOST_OPEN.load(Ordering::Relaxed)));
        }
    }
}

/// Runs `f` on the interrupt's state, with the interrupt masked (a few microseconds: it moves
/// at most a few packets).
fn with_shared(f: impl FnOnce(&mut Shared)) {
    critical_section::with(|cs| {
        if let Some(shared) = SHARED.borrow_ref_mut(cs).as_mut() {
            f(shared);
        }
    });
}

/// Queues output while the port is open and its host reads; drops it otherwise (see the
/// module docs). Never waits.
impl fmt::Write for UsbSerial {
    fn write_str(&mut self, text: &str) -> fmt::Result {
        if !self.open || self.stalled {
            self.dropped_bytes = self.dropped_bytes.wrapping_add(text.len() as u32);
            return Ok(());
        }
        for &byte in text.as_bytes() {
            if self.tx.enqueue(byte).is_err() {
                // Not reached while the main loop checks `has_room_for_step` first.
                self.dropped_bytes = self.dropped_bytes.wrapping_add(1);
            }
        }
        self.unsent = true;
        Ok(())
    }
}

impl Shared {
    fn service(&mut self) {
        self.device.poll(&mut [&mut self.port]);
        let open = self.device.state() == UsbDeviceState::Configured && self.port.dtr();
        if open && !self.was_open {
            // Only this handler writes it (the M0+ has no atomic add).
            let openings = OPENINGS.load(Ordering::Relaxed).wrapping_add(1);
            OPENINGS.store(openings, Ordering::Relaxed);
        }
        self.was_open = open;
        HOST_OPEN.store(open, Ordering::Relaxed);
        self.receive();
        self.transmit(open);
    }

    /// Moves received packets into the queue while a whole packet fits. A packet that does not
    /// fit stays in its endpoint buffer, unacknowledged (the host is refused until it is read),
    /// and its buffer-status bit is cleared so the interrupt does not fire again and again for
    /// it meanwhile; the main loop reads it when it has made room (`RX_HELD`).
    fn receive(&mut self) {
        RX_HELD.store(false, Ordering::Relaxed);
        let mut chunk = [0u8; PACKET_BYTES];
        loop {
            if self.rx.capacity() - self.rx.len() < PACKET_BYTES {
                RX_HELD.store(true, Ordering::Relaxed);
                break;
            }
            // Reads at most one packet from the endpoint (which re-arms it) per call.
            match self.port.read(&mut chunk) {
                Ok(count) => {
                    for &byte in &chunk[..count] {
                        // Cannot fail: a whole packet's room was checked.
                        let _ = self.rx.enqueue(byte);
                    }
                }
                Err(_) => break, // WouldBlock: nothing more received
            }
        }
        // SAFETY: BUFF_STATUS is write-one-to-clear: this clears only the bits of OUT packets
        // left in their buffers (rp2040-hal reads an OUT buffer by its FULL flag, not by this
        // bit, so the packet is still read later), inside the same critical section as every
        // use of the bus.
        let regs = unsafe { &*pac::USBCTRL_REGS::ptr() };
        let held = regs.buff_status().read().bits() & DATA_OUT_BUFFER_BITS;
        if held != 0 {
            regs.buff_status().write(|w| unsafe { w.bits(held) });
            RX_HELD.store(true, Ordering::Relaxed);
        }
    }

    /// Hands queued output to the port while it takes it; drops it if the host has no port open.
    fn transmit(&mut self, open: bool) {
        if !open {
            while self.tx.dequeue().is_some() {}
            self.tx_packet_len = 0;
            self.tx_packet_sent = 0;
            return;
        }
        loop {
            if self.tx_packet_sent == self.tx_packet_len {
                self.tx_packet_len = 0;
                self.tx_packet_sent = 0;
                while self.tx_packet_len < PACKET_BYTES {
                    let Some(byte) = self.tx.dequeue() else {
                        break;
                    };
                    self.tx_packet[self.tx_packet_len] = byte;
                    self.tx_packet_len += 1;
                }
                if self.tx_packet_len == 0 {
                    return;
                }
            }
            match self
                .port
                .write(&self.tx_packet[self.tx_packet_sent..self.tx_packet_len])
            {
                Ok(count) => {
                    self.tx_packet_sent += count;
                    // Only this handler writes it (the M0+ has no atomic add).
                    let taken = TX_TAKEN.load(Ordering::Relaxed).wrapping_add(count as u32);
                    TX_TAKEN.store(taken, Ordering::Relaxed);
                }
                Err(_) => return, // WouldBlock: the port's buffer is full until a packet goes
            }
        }
    }
}

#[interrupt]
fn USBCTRL_IRQ() {
    with_shared(Shared::service);
}
