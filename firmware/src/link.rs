//! A serial link as the main loop drives it: one value holding its port and its
//! [`control::Session`] (line assembly, echo, prompt), and what the loop does with it each pass
//! (greet it when it opens, announce its lost input, write it the notices, feed its bytes to the
//! controller, run the work of its command, send its output).
//!
//! The loop does the same for every link; what differs between ports is each one's [`Port`]
//! impl, here: UART0 ([`Serial`]) is always open, loses bytes when its queue overflows and has
//! a baud rate; the USB port ([`UsbSerial`]) is opened and closed by its host, loses nothing
//! and has no rate. The loop holds its links in a table ([`Links`]: nested pairs, so that each
//! step on every link is unrolled at compile time, with direct calls and no trait object).
//!
//! A new link is its port's [`Port`] impl here and one more entry in `main`'s table.
//!
//! The steps are `#[inline(always)]`: each has one call site, in the main loop, the hot path of
//! every received byte. Left to itself the compiler made functions of some (one called twice
//! per pass, with a long prologue even when nothing was received), and the emulator measured
//! every pass slower than with the two links written out by hand; inlined, it is faster.

use core::fmt;

use control::controller::Fed;
use control::protocol::Lost;
use control::Session;
use firmware::Controller;
use rp2040_hal::{
    fugit::ExtU32,
    pac::{self, interrupt},
    timer::{Alarm, Alarm1},
    Timer,
};

use crate::pulses;
use crate::serial::{Received, Serial};
use crate::servo_pwm::ServoPwm;
use crate::usb_serial::UsbSerial;

/// A link's port, as the main loop uses it: received bytes in, output written, and what each
/// kind of port needs besides.
pub trait Port: fmt::Write {
    /// The output of one controller step fits (or is dropped anyway): the step may be taken.
    fn has_room_for_step(&self) -> bool;
    /// The next received byte, or where bytes were lost.
    fn receive(&mut self) -> Option<Received>;
    /// Takes the plain characters of a command line at the front of the bytes received into
    /// `session`'s line at once ([`Session::take_plain`], echoed to this port, if it has room
    /// for a step's output), at most `most`; returns how many. A port may take none (they then
    /// come one by one from [`Port::receive`]): one whose `TAKES_PLAIN` is false never does.
    fn take_plain(&mut self, _session: &mut Session, _most: usize) -> usize {
        0
    }
    /// Whether [`Port::take_plain`] may take anything (the loop skips it where not).
    const TAKES_PLAIN: bool = false;
    /// Something waits to be received.
    fn rx_pending(&self) -> bool;
    /// Notices may be written now. (A port that says no, closed, gets them later: the
    /// controller keeps the latest few for its banner.)
    fn takes_notices(&self) -> bool;
    /// If input was lost since the last call: how much, to announce at once (the line it cut
    /// is refused later, when [`Port::receive`] reaches the gap).
    fn take_new_loss(&mut self) -> Option<Lost>;
    /// If the port was opened (`Some(true)`: a new terminal, to greet) or closed since the last
    /// call. An opening waits while `reply_awaited` (a command of the terminal that closed
    /// still runs).
    fn take_open_change(&mut self, reply_awaited: bool) -> Option<bool>;
    /// The port's own upkeep, once per pass (`timer`: the 1 MHz timer).
    fn watch(&mut self, timer: &Timer);
    /// Follows the controller's baud rate where the port has one. Returns whether a prompt
    /// held back for a baud change may go out now.
    fn follow_baud(&mut self, baud: u32) -> bool;
    /// The port has something for the next pass that no interrupt will announce: the loop
    /// must not sleep.
    fn wants_pass(&self, baud: u32, reply_awaited: bool) -> bool;
    /// Hands written output on to the hardware, as much as it takes now; never waits.
    fn send_some(&mut self);
    /// Another link's input has waited [`HOLD_UP_US`] behind this port's output (a command of
    /// this link runs, and its next step waits for room): drop this port's output from now on,
    /// until what it has queued has gone, so that the command ends and the other link is
    /// served. A port whose output always goes on by itself may ignore it.
    fn give_up_output(&mut self);
}

/// UART0: open from power-up (greeted then), never closed.
impl Port for Serial {
    fn has_room_for_step(&self) -> bool {
        Serial::has_room_for_step(self)
    }
    fn receive(&mut self) -> Option<Received> {
        self.read()
    }
    #[inline(always)]
    fn take_plain(&mut self, session: &mut Session, most: usize) -> usize {
        Serial::take_plain(self, session, most)
    }
    const TAKES_PLAIN: bool = true;
    fn rx_pending(&self) -> bool {
        Serial::rx_pending(self)
    }
    /// Always: the wire takes what is written (a closed terminal at the other end hears
    /// nothing anyway).
    fn takes_notices(&self) -> bool {
        true
    }
    /// Only UART0 loses input: its receive queue overflowed, or the UART lost bytes.
    fn take_new_loss(&mut self) -> Option<Lost> {
        let lost = Serial::take_new_loss(self)?;
        defmt::warn!("serial receive: input lost (at least {} bytes)", lost.bytes);
        Some(lost)
    }
    fn take_open_change(&mut self, _reply_awaited: bool) -> Option<bool> {
        None
    }
    /// Logs framing, parity, break and overrun errors as they come.
    fn watch(&mut self, _timer: &Timer) {
        if let Some(errors) = self.take_new_line_errors() {
            defmt::warn!("serial receive: {} line errors so far", errors);
        }
    }
    /// A baud change (from either link) waits for the reply announcing it to have left the
    /// UART at the old rate; then the prompt held back for it goes out at the new one.
    fn follow_baud(&mut self, baud: u32) -> bool {
        if baud == self.baud() || !self.tx_idle() {
            return false;
        }
        match self.set_baud(baud) {
            Ok(()) => true,
            Err(_) => {
                defmt::error!("baud rate {} out of range", baud);
                false
            }
        }
    }
    /// A baud change waits only for the UART's last bytes to leave, and no interrupt says when
    /// the UART goes idle: the loop stays awake until it has switched. (Output still waiting
    /// for room in the TX FIFO is no reason: the TX interrupt wakes the loop.)
    fn wants_pass(&self, baud: u32, _reply_awaited: bool) -> bool {
        baud != self.baud() && !self.tx_pending()
    }
    fn send_some(&mut self) {
        Serial::send_some(self)
    }
    /// Ignored: UART0's output always leaves, at the baud rate (a step's output, at most
    /// [`crate::serial::LONGEST_STEP_BYTES`], takes 0.18 s at 115,200 baud), whoever listens.
    fn give_up_output(&mut self) {}
}

/// The USB port: open while the host has it open (DTR); its output is dropped meanwhile, and
/// when its host stopped reading.
impl Port for UsbSerial {
    fn has_room_for_step(&self) -> bool {
        UsbSerial::has_room_for_step(self)
    }
    fn receive(&mut self) -> Option<Received> {
        self.read()
    }
    fn rx_pending(&self) -> bool {
        UsbSerial::rx_pending(self)
    }
    fn takes_notices(&self) -> bool {
        UsbSerial::takes_notices(self)
    }
    /// USB loses nothing (the host waits when the receive queue is full).
    fn take_new_loss(&mut self) -> Option<Lost> {
        None
    }
    fn take_open_change(&mut self, reply_awaited: bool) -> Option<bool> {
        UsbSerial::take_open_change(self, reply_awaited)
    }
    /// A host that stopped reading has its output dropped, after a while, so that it holds up
    /// nothing else.
    fn watch(&mut self, timer: &Timer) {
        self.watch_output(timer.get_counter_low());
    }
    /// USB has no rate: a prompt held back there goes out at once.
    fn follow_baud(&mut self, _baud: u32) -> bool {
        true
    }
    /// The host opened or closed the port: greeting or dropping is the loop's to do.
    fn wants_pass(&self, _baud: u32, reply_awaited: bool) -> bool {
        self.open_change_pending(reply_awaited)
    }
    fn send_some(&mut self) {
        UsbSerial::send_some(self)
    }
    fn give_up_output(&mut self) {
        UsbSerial::give_up_output(self)
    }
}

/// One serial link: its port and its session.
pub struct Link<P: Port> {
    port: P,
    session: Session,
}

impl<P: Port> Link<P> {
    pub fn new(port: P) -> Self {
        Link {
            port,
            session: Session::new(),
        }
    }

    /// The banner and a prompt, with the notices kept for a new terminal.
    pub fn greet(&mut self, controller: &Controller) {
        controller.banner(&mut self.session, &mut self.port);
    }

    /// A port the host opened is a new terminal (a fresh session, then the banner); one it
    /// closed has its output dropped from now on (the port's doing). Then the port's upkeep.
    #[inline(always)]
    fn open_or_close(&mut self, controller: &Controller, timer: &Timer) {
        if self.port.take_open_change(self.session.awaits_reply()) == Some(true) {
            self.session.reopen();
            self.greet(controller);
        }
        self.port.watch(timer);
    }

    /// Input lost since the last pass: announced to this link now. Returns whether there was
    /// any (then the other links are to hear of it too).
    #[inline(always)]
    fn announce_loss(&mut self, controller: &mut Controller) -> bool {
        let Some(lost) = self.port.take_new_loss() else {
            return false;
        };
        controller.on_input_lost(&mut self.session, lost.bytes, lost.in_uart, &mut self.port);
        true
    }

    /// The notices this link has not shown yet, if its port takes them now.
    #[inline(always)]
    fn write_notices(&mut self, controller: &Controller) {
        if self.port.takes_notices() {
            controller.write_notices(&mut self.session, &mut self.port);
        }
    }

    /// A slice of the controller's work, replying on this link, if its output fits. Returns
    /// whether the slice was done.
    #[inline(always)]
    fn work(&mut self, controller: &mut Controller) -> bool {
        if !self.port.has_room_for_step() {
            return false;
        }
        controller.work(&mut self.session, &mut self.port);
        true
    }

    /// Feeds received bytes to the controller until a line ends (or a command's work begins),
    /// `budget` bytes have been fed, the port lacks room for a step's output or has nothing
    /// more. Stream frames do not end the feeding: binary frames contain line-end bytes, and
    /// the newest of the frames waiting is the one applied. Returns whether the pass's input
    /// ends here (a line ended).
    #[inline(always)]
    fn feed(
        &mut self,
        controller: &mut Controller,
        servos: &mut ServoPwm,
        budget: &mut usize,
    ) -> bool {
        let Link { port, session } = self;
        while *budget > 0 && port.has_room_for_step() {
            // A command line's characters, as many as have come, go into its line at once
            // (for the controller they do nothing, see `Session::take_plain`); what ends the
            // run (the line end, a byte that is not plain) goes the whole way below.
            // (In a stream frame the line says so at once: its bytes go the whole way.)
            if P::TAKES_PLAIN && session.may_take_plain() {
                *budget -= port.take_plain(session, *budget);
                if *budget == 0 {
                    break;
                }
            }
            match port.receive() {
                Some(Received::Byte(byte)) => {
                    *budget -= 1;
                    let fed = controller.on_byte(session, byte, port);
                    // A jump (speed limits off) is written now, not at the next frame.
                    pulses::write_new(controller, servos);
                    if fed == Fed::LineEnded || controller.is_busy() {
                        return true;
                    }
                }
                // The gap where bytes were lost: the line it cuts is refused at its end.
                Some(Received::Lost(lost)) => controller.on_rx_overflow(session, lost),
                None => return false,
            }
        }
        false
    }

    /// Between passes: the plain characters of a command line waiting, into its line (echo is
    /// off: see [`Link::may_take_plain`]). Returns whether it took any.
    #[inline(always)]
    fn take_plain_input(&mut self) -> bool {
        P::TAKES_PLAIN && self.port.take_plain(&mut self.session, usize::MAX) > 0
    }

    /// Whether [`Link::take_plain_input`] may take anything now: the port takes plain
    /// characters, the line is one that may take them, and echo is off (with echo on, an
    /// interactive user's every byte gets its pass, echoed at once).
    #[inline(always)]
    fn may_take_plain(&self) -> bool {
        P::TAKES_PLAIN && !self.session.echo() && self.session.may_take_plain()
    }

    /// The port follows the baud rate, then a prompt held back for a baud change goes out if
    /// it may, then output goes to the hardware.
    #[inline(always)]
    fn send(&mut self, baud: u32) {
        if self.port.follow_baud(baud) {
            self.session.write_deferred_prompt(&mut self.port);
        }
        self.port.send_some();
    }
}

/// A table of links: nested pairs ending in `()`, e.g. `(Link<Serial>, (Link<UsbSerial>, ()))`.
/// Each step is done on every link in table order, unrolled at compile time (the pair's link,
/// then the rest): every call is direct, and a byte's way from its port to the controller is
/// the port's own code, inlined. The first link is the one the controller's own work (the
/// return home after link loss or an e-stop) writes to.
pub trait Links {
    /// How many links.
    const COUNT: usize;

    /// [`Link::open_or_close`] on every link.
    fn open_or_close(&mut self, controller: &Controller, timer: &Timer);

    /// [`Link::announce_loss`] on every link; whether any had lost input.
    fn announce_losses(&mut self, controller: &mut Controller) -> bool;

    /// [`Link::write_notices`] on every link.
    fn write_notices(&mut self, controller: &Controller);

    /// A link's command awaits its reply (its work runs).
    fn awaits_reply(&self) -> bool;

    /// [`Link::work`] on the link whose command runs (at most one: input waits while a
    /// command's work runs), or on the first. Returns whether the slice was done.
    fn work(&mut self, controller: &mut Controller) -> bool;

    /// [`Link::work`] on the first link whose command runs; false if none.
    fn work_awaited(&mut self, controller: &mut Controller) -> bool;

    /// Whether the link [`Links::work`] would choose has room for a step's output.
    fn work_has_room(&self) -> bool;

    /// The same for the first link whose command runs; false if none.
    fn awaited_has_room(&self) -> bool;

    /// [`Port::give_up_output`] on the link [`Links::work`] would choose.
    fn give_up_work_output(&mut self);

    /// The same for the first link whose command runs.
    fn give_up_awaited_output(&mut self);

    /// [`Link::feed`] on the links from `first` on, then on those before it, until one ends the
    /// pass's input. Returns whether one did.
    fn feed_from(
        &mut self,
        first: usize,
        controller: &mut Controller,
        servos: &mut ServoPwm,
        budget: &mut usize,
    ) -> bool {
        (first..first + Self::COUNT).any(|turn| {
            let index = if turn < Self::COUNT {
                turn
            } else {
                turn - Self::COUNT
            };
            self.feed_at(index, controller, servos, budget)
        })
    }

    /// [`Link::feed`] on link number `index`.
    fn feed_at(
        &mut self,
        index: usize,
        controller: &mut Controller,
        servos: &mut ServoPwm,
        budget: &mut usize,
    ) -> bool;

    /// [`Link::send`] on every link.
    fn send(&mut self, baud: u32);

    /// [`Link::take_plain_input`] on every link (between passes, no command running); whether
    /// any took input.
    fn take_plain_input(&mut self) -> bool;

    /// Whether [`Links::take_plain_input`] may take anything on some link now.
    fn may_take_plain(&self) -> bool;

    /// A link has input waiting and room for a step's output.
    fn input_waiting(&self) -> bool;

    /// A port wants a pass ([`Port::wants_pass`]).
    fn wants_pass(&self, baud: u32) -> bool;
}

/// The end of the table: no link.
impl Links for () {
    const COUNT: usize = 0;
    fn open_or_close(&mut self, _: &Controller, _: &Timer) {}
    fn announce_losses(&mut self, _: &mut Controller) -> bool {
        false
    }
    fn write_notices(&mut self, _: &Controller) {}
    fn awaits_reply(&self) -> bool {
        false
    }
    fn work(&mut self, _: &mut Controller) -> bool {
        false
    }
    fn work_awaited(&mut self, _: &mut Controller) -> bool {
        false
    }
    fn work_has_room(&self) -> bool {
        false
    }
    fn awaited_has_room(&self) -> bool {
        false
    }
    fn give_up_work_output(&mut self) {}
    fn give_up_awaited_output(&mut self) {}
    fn feed_at(&mut self, _: usize, _: &mut Controller, _: &mut ServoPwm, _: &mut usize) -> bool {
        false
    }
    fn send(&mut self, _: u32) {}
    fn take_plain_input(&mut self) -> bool {
        false
    }
    fn may_take_plain(&self) -> bool {
        false
    }
    fn input_waiting(&self) -> bool {
        false
    }
    fn wants_pass(&self, _: u32) -> bool {
        false
    }
}

/// A link, then the rest of the table.
impl<P: Port, Rest: Links> Links for (Link<P>, Rest) {
    const COUNT: usize = 1 + Rest::COUNT;

    #[inline(always)]
    fn open_or_close(&mut self, controller: &Controller, timer: &Timer) {
        self.0.open_or_close(controller, timer);
        self.1.open_or_close(controller, timer);
    }

    #[inline(always)]
    fn announce_losses(&mut self, controller: &mut Controller) -> bool {
        let lost = self.0.announce_loss(controller);
        self.1.announce_losses(controller) || lost
    }

    #[inline(always)]
    fn write_notices(&mut self, controller: &Controller) {
        self.0.write_notices(controller);
        self.1.write_notices(controller);
    }

    #[inline(always)]
    fn awaits_reply(&self) -> bool {
        self.0.session.awaits_reply() || self.1.awaits_reply()
    }

    /// Each link's work has one call site (this link's here, the others' in
    /// [`Links::work_awaited`]), so that it is inlined.
    #[inline(always)]
    fn work(&mut self, controller: &mut Controller) -> bool {
        if self.0.session.awaits_reply() || !self.1.awaits_reply() {
            self.0.work(controller)
        } else {
            self.1.work_awaited(controller)
        }
    }

    #[inline(always)]
    fn work_awaited(&mut self, controller: &mut Controller) -> bool {
        if self.0.session.awaits_reply() {
            self.0.work(controller)
        } else {
            self.1.work_awaited(controller)
        }
    }

    #[inline(always)]
    fn work_has_room(&self) -> bool {
        if self.0.session.awaits_reply() || !self.1.awaits_reply() {
            self.0.port.has_room_for_step()
        } else {
            self.1.awaited_has_room()
        }
    }

    #[inline(always)]
    fn awaited_has_room(&self) -> bool {
        if self.0.session.awaits_reply() {
            self.0.port.has_room_for_step()
        } else {
            self.1.awaited_has_room()
        }
    }

    fn give_up_work_output(&mut self) {
        if self.0.session.awaits_reply() || !self.1.awaits_reply() {
            self.0.port.give_up_output()
        } else {
            self.1.give_up_awaited_output()
        }
    }

    fn give_up_awaited_output(&mut self) {
        if self.0.session.awaits_reply() {
            self.0.port.give_up_output()
        } else {
            self.1.give_up_awaited_output()
        }
    }

    #[inline(always)]
    fn feed_at(
        &mut self,
        index: usize,
        controller: &mut Controller,
        servos: &mut ServoPwm,
        budget: &mut usize,
    ) -> bool {
        if index == 0 {
            self.0.feed(controller, servos, budget)
        } else {
            self.1.feed_at(index - 1, controller, servos, budget)
        }
    }

    #[inline(always)]
    fn send(&mut self, baud: u32) {
        self.0.send(baud);
        self.1.send(baud);
    }

    #[inline(always)]
    fn take_plain_input(&mut self) -> bool {
        let taken = self.0.take_plain_input();
        self.1.take_plain_input() || taken
    }

    #[inline(always)]
    fn may_take_plain(&self) -> bool {
        self.0.may_take_plain() || self.1.may_take_plain()
    }

    #[inline(always)]
    fn input_waiting(&self) -> bool {
        (self.0.port.has_room_for_step() && self.0.port.rx_pending()) || self.1.input_waiting()
    }

    #[inline(always)]
    fn wants_pass(&self, baud: u32) -> bool {
        let link = &self.0;
        link.port.wants_pass(baud, link.session.awaits_reply()) || self.1.wants_pass(baud)
    }
}

/// How long one link's input may wait behind another link's output: while a command of link A
/// runs and its next step waits for room in A's output (A's host reads slowly, or not at all),
/// input waiting on link B waits at most this long; then A's output is given up
/// ([`Port::give_up_output`]), A's command ends and B is served. With the time a pass, the
/// rest of A's command and B's own take, B's reply begins within 0.1 s of its line's end
/// (README.md, "Serial links").
pub const HOLD_UP_US: u32 = 50_000;

/// Watches for one link's output holding up another link's input (see [`HOLD_UP_US`]), and
/// wakes the loop at the deadline with the timer's alarm 1 (`TIMER_IRQ_1`), so that the
/// deadline does not wait for the next servo frame or byte.
pub struct HoldUpWatch {
    alarm: Alarm1,
    /// When the input began to wait (the timer's microseconds), while it waits.
    since_us: Option<u32>,
    /// The work has waited for room on its link since the input began to wait.
    starved: bool,
}

impl HoldUpWatch {
    pub fn new(mut alarm: Alarm1) -> Self {
        alarm.enable_interrupt();
        // SAFETY: the handler only clears alarm 1's interrupt, which only this watch uses.
        unsafe { pac::NVIC::unmask(pac::Interrupt::TIMER_IRQ_1) };
        HoldUpWatch {
            alarm,
            since_us: None,
            starved: false,
        }
    }

    /// Once per pass, before the work: while input waits behind a command's work, starts the
    /// clock (and the alarm); at the deadline, if the work has had to wait for room on its
    /// link meanwhile, gives up that link's output. (Whether it had to wait at any time, not
    /// only now: a slow reader makes room a packet at a time, and the pass its packet wakes
    /// finds room for one step, which fills it again.)
    #[inline(always)]
    pub fn watch<L: Links>(&mut self, links: &mut L, controller: &Controller, timer: &Timer) {
        if !(controller.is_busy() && links.input_waiting()) {
            self.since_us = None;
            self.starved = false;
            return;
        }
        self.starved |= !links.work_has_room();
        let now_us = timer.get_counter_low();
        let Some(since_us) = self.since_us else {
            self.since_us = Some(now_us);
            // Cannot fail: the delay is far below the alarm's range.
            let _ = self.alarm.schedule(HOLD_UP_US.micros());
            return;
        };
        if now_us.wrapping_sub(since_us) >= HOLD_UP_US && self.starved {
            defmt::warn!("a link's output held up another's input: given up");
            links.give_up_work_output();
            self.since_us = None;
            self.starved = false;
        }
    }

    /// Before the loop sleeps: notes whether the work waits for room on its link (the reason
    /// to sleep with work to do).
    #[inline(always)]
    pub fn before_sleep<L: Links>(&mut self, links: &L, controller: &Controller) {
        if self.since_us.is_some() && controller.is_busy() && !links.work_has_room() {
            self.starved = true;
        }
    }
}

/// The hold-up deadline ([`HoldUpWatch`]): only wakes the main loop.
#[interrupt]
fn TIMER_IRQ_1() {
    // SAFETY: INTR is write-one-to-clear: this clears alarm 1's interrupt alone.
    unsafe { (*pac::TIMER::ptr()).intr().write(|w| w.bits(1 << 1)) };
}
