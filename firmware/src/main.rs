//! hexapod-fw: the RP2040 board layer.
//!
//! Data flows one way: serial bytes (UART0 and the USB port) -> controller (lines, commands,
//! stream frames, motion) -> six pulse widths per servo frame (and right after a command that
//! jumps or a stream frame in pass-through) -> PWM registers. This file only wires the pieces
//! together: the board brought up ([`firmware::Board`]: clocks, GPIOs), the watchdog, the
//! serial links ([`link`]: UART0, [`serial`], and USB CDC, [`usb_serial`], each with its own
//! [`control::Session`]), the six servo outputs ([`servo_pwm`], fed by [`pulses`]), the e-stop
//! input and servo-power output ([`safety_pins`]), the settings saved in flash ([`flash`]) and
//! the hardware-independent [`firmware::Controller`], which runs on the boot ROM's float
//! routines ([`firmware::rom_math`]) where it computes in `f32` (its IK runs in fixed point,
//! `kinematics_core::fixed`).

#![no_std]
#![no_main]

mod flash;
mod link;
mod pulses;
mod rx_ring;
mod safety_pins;
mod serial;
mod servo_pwm;
mod usb_serial;

use defmt_rtt as _;
use panic_probe as _;
use rp2040_hal::{self as hal, clocks::Clock, fugit::ExtU32, Timer, Watchdog};

use control::store::{self, Store};
use firmware::rom_math::RomMath;
use firmware::{Board, Controller};
use flash::SettingsFlash;
use link::{HoldUpWatch, Link, Links};
use safety_pins::{FreePin, SafetyPins};
use serial::Serial;
use servo_pwm::ServoPwm;
use usb_serial::UsbSerial;

/// Reset the chip if the main loop stalls this long. A pass takes well under a millisecond
/// (see [`main`]), so only a hang can starve the watchdog.
const WATCHDOG_TIMEOUT_MS: u32 = 500;
/// The watchdog's time for a `save`'s flash write: a 4 KiB sector erase takes the W25Q080 up
/// to 400 ms and a page program up to 3 ms (datasheet maxima), with interrupts masked; 2 s
/// leaves a wide margin and still resets a write that hangs.
const SAVE_WATCHDOG_MS: u32 = 2000;
/// Most received bytes handed to the controller in one pass, all links together (a line end
/// ends the pass's input early, so at most one command runs per pass; stream frames do not end
/// it, so the newest of the frames waiting is the one applied). 128 bytes are 8 binary frames,
/// 1.4 ms of a stream at 921,600 baud: more than a pass takes, so a UART stream never falls
/// behind (a USB host that sends faster waits: USB's flow control).
const RX_BYTES_PER_PASS: usize = 128;

/// The board's links (see [`Links`]): UART0 first (the controller's own work writes to it),
/// then the USB port.
type BoardLinks = (Link<Serial>, (Link<UsbSerial>, ()));

#[hal::entry]
fn main() -> ! {
    let board = Board::take();
    // The newest good settings saved in flash, or the defaults (with a warning saying why).
    let mut settings_flash = SettingsFlash::new();
    let mut controller = Controller::power_up(Store::load_with::<RomMath, _>(&mut settings_flash));
    // The board's id: the flash chip's unique ID, handed to the controller (the banner) and
    // to the USB device (its serial number).
    let board_id = settings_flash.unique_id();
    controller.set_board_id(board_id);
    defmt::info!(
        "settings storage at flash offset {=u32:#x}",
        settings_flash.base()
    );
    let Drivers {
        mut watchdog,
        timer,
        serial,
        usb,
        mut servos,
        mut safety,
        mut hold_up,
    } = Drivers::new(board, &controller, board_id);

    // The links: each its port and its own line assembly, echo and prompt (the platform's
    // state is the controller's). UART0 is greeted now; the USB port when a host opens it.
    let mut links: BoardLinks = (Link::new(serial), (Link::new(usb), ()));
    links.0.greet(&controller);
    defmt::info!("ready");

    // The main loop. Every pass is short, whatever arrives on any link: it runs at most one
    // command (from one link or another, the link that goes first taking turns), or one slice
    // of a command's long work (a path check a few IK solutions at a time, a listing a line at
    // a time: the controller splits it, see `control::Controller::work`), plus the newest
    // stream frame and the frame that came due. A reply goes to the link that sent the line,
    // notices to every open link. The longest pass is measured in the emulator (well under
    // 1 ms, against a 3 ms frame at 333 Hz and the 500 ms watchdog; BENCHMARKS.md). The one
    // exception is a `save`'s flash write (a sector erase: tens to hundreds of milliseconds
    // with interrupts masked, USB's too), alone in its pass, with the watchdog given longer.
    //
    // The link whose input went first in the last pass that read input (they take turns).
    let mut turn = 0;
    loop {
        watchdog.feed();
        links.open_or_close(&controller, &timer);
        // A command whose output waits for a slow or stopped USB host holds up the other
        // link's input 0.05 s at most (link::HOLD_UP_US): then that output is given up.
        hold_up.watch(&mut links, &controller, &timer);
        // Lost input (only UART0 loses any) is announced at once, to every link; the line it
        // cut is refused when the loop reaches the gap.
        if links.announce_losses(&mut controller) {
            links.write_notices(&controller);
        }
        if controller.is_busy() {
            match controller.take_flash_write() {
                Some(write) => save(&mut controller, &write, &mut settings_flash, &mut watchdog),
                None => work(&mut controller, &mut links, &mut servos),
            }
        } else {
            turn = feed_input(&mut controller, &mut links, &mut servos, turn);
        }
        drive_safety_pins(&mut controller, &mut safety);
        next_frame(&mut controller, &mut servos, &mut links);
        pulses::follow_frame_rate(&controller, &mut servos);
        links.send(controller.baud());
        hold_up.before_sleep(&links, &controller);
        sleep_unless_due(&controller, &mut links, &servos);
    }
}

/// The board's drivers, set up for the controller's power-up settings (the USB device named
/// with the board's id).
struct Drivers {
    /// Started, with [`WATCHDOG_TIMEOUT_MS`].
    watchdog: Watchdog,
    /// The 1 MHz timer: its alarm 0 polls UART0's RX FIFO, its alarm 1 is the hold-up
    /// watch's, its counter times the USB host's reading and the hold-up.
    timer: Timer,
    serial: Serial,
    usb: UsbSerial,
    servos: ServoPwm,
    safety: SafetyPins,
    /// With the timer's alarm 1, which wakes the loop at the hold-up deadline.
    hold_up: HoldUpWatch,
}

impl Drivers {
    fn new(board: Board, controller: &Controller, board_id: u64) -> Drivers {
        let Board {
            mut watchdog,
            clocks,
            pins,
            mut resets,
            uart0,
            pwm,
            timer,
            usbctrl_regs,
            usbctrl_dpram,
            xip_ctrl: _,
        } = board;
        let mut timer = Timer::new(timer, &mut resets, &clocks);
        let rx_poll = timer.alarm_0().expect("alarm 0 is taken once, here");
        let hold_up = HoldUpWatch::new(timer.alarm_1().expect("alarm 1 is taken once, here"));
        let serial = Serial::new(
            uart0,
            pins.gpio0,
            pins.gpio1,
            &mut resets,
            clocks.peripheral_clock.freq(),
            controller.baud(),
            rx_poll,
        )
        .expect("the power-up baud rate is in range");
        let servos = ServoPwm::new(
            pwm,
            &mut resets,
            (
                pins.gpio2, pins.gpio3, pins.gpio4, pins.gpio5, pins.gpio6, pins.gpio7,
            ),
            controller.frame_hz(),
            &controller.pulses_us(),
            &pulses::windows_us(controller),
        )
        .expect("the settings' frame rate is in range (they are validated)");
        // The GPIOs left free for the e-stop input and the servo-power output
        // (control::safety::FREE_GPIOS, in that order).
        let free = |pin: FreePin| pin;
        let mut safety = SafetyPins::new([
            free(pins.gpio8.reconfigure().into_dyn_pin()),
            free(pins.gpio9.reconfigure().into_dyn_pin()),
            free(pins.gpio10.reconfigure().into_dyn_pin()),
            free(pins.gpio11.reconfigure().into_dyn_pin()),
            free(pins.gpio12.reconfigure().into_dyn_pin()),
            free(pins.gpio13.reconfigure().into_dyn_pin()),
            free(pins.gpio14.reconfigure().into_dyn_pin()),
            free(pins.gpio15.reconfigure().into_dyn_pin()),
            free(pins.gpio16.reconfigure().into_dyn_pin()),
            free(pins.gpio17.reconfigure().into_dyn_pin()),
            free(pins.gpio18.reconfigure().into_dyn_pin()),
            free(pins.gpio19.reconfigure().into_dyn_pin()),
            free(pins.gpio20.reconfigure().into_dyn_pin()),
            free(pins.gpio21.reconfigure().into_dyn_pin()),
            free(pins.gpio22.reconfigure().into_dyn_pin()),
            free(pins.gpio26.reconfigure().into_dyn_pin()),
            free(pins.gpio27.reconfigure().into_dyn_pin()),
            free(pins.gpio28.reconfigure().into_dyn_pin()),
        ]);
        safety.apply(&controller.settings().safety);
        watchdog.start(WATCHDOG_TIMEOUT_MS.millis());
        let serial_number =
            cortex_m::singleton!(: [u8; 16] = control::report::board_id_digits(board_id))
                .expect("Drivers::new is called once");
        let serial_number =
            core::str::from_utf8(serial_number).expect("hexadecimal digits are ASCII");
        let usb = UsbSerial::new(
            usbctrl_regs,
            usbctrl_dpram,
            clocks.usb_clock,
            &mut resets,
            serial_number,
        );
        Drivers {
            watchdog,
            timer,
            serial,
            usb,
            servos,
            safety,
            hold_up,
        }
    }
}

/// `save`: erase the older sector, program its page, read it back. The PWM holds the pulses
/// meanwhile (nothing moves: save is refused while moving); input waits in the UART's FIFO,
/// and in the USB host (interrupts are masked, so the USB hardware refuses the host's packets
/// with NAK and the host tries again). The reply comes in the next pass, on the link that sent
/// `save`.
fn save(
    controller: &mut Controller,
    write: &store::Write,
    settings_flash: &mut SettingsFlash,
    watchdog: &mut Watchdog,
) {
    watchdog.start(SAVE_WATCHDOG_MS.millis());
    let result = write.perform(settings_flash);
    watchdog.start(WATCHDOG_TIMEOUT_MS.millis());
    match result {
        Ok(()) => defmt::info!(
            "settings saved: save {} in sector {}",
            write.record().sequence,
            write.sector()
        ),
        Err(_) => defmt::error!("settings not saved: the flash did not keep them"),
    }
    controller.flash_written(result);
}

/// A slice of the work in progress, with the link that sent the command, if that link has
/// room for its output. Its reply comes with the last slice. The controller's own work (the
/// return home after link loss) may notify: notices to every link.
fn work(controller: &mut Controller, links: &mut BoardLinks, servos: &mut ServoPwm) {
    if links.work(controller) {
        pulses::write_new(controller, servos);
        links.write_notices(controller);
    }
}

/// Received bytes -> controller, up to the end of one line, from one link and then, if no
/// line ended, the next (stream frames do not end the input). The links take turns going
/// first: the one after `turn`, which went first last time, goes first now (and is returned).
/// Input waits (in the receive queue, or for USB in the host) while its link lacks room for a
/// step's output, so replies are never cut. Then the newest stream frame among those just fed,
/// from any link (in pass-through, written now).
fn feed_input(
    controller: &mut Controller,
    links: &mut BoardLinks,
    servos: &mut ServoPwm,
    turn: usize,
) -> usize {
    let first = if turn + 1 < BoardLinks::COUNT {
        turn + 1
    } else {
        0
    };
    let mut budget = RX_BYTES_PER_PASS;
    links.feed_from(first, controller, servos, &mut budget);
    controller.apply_stream();
    pulses::write_new(controller, servos);
    first
}

/// The e-stop input (read every pass: within a servo frame of it opening) and the servo-power
/// output. Its notices go to every open link with the next frame's.
fn drive_safety_pins(controller: &mut Controller, safety: &mut SafetyPins) {
    safety.apply(&controller.settings().safety);
    if let Some(open) = safety.estop_open() {
        controller.set_estop_input(open);
    }
    safety.set_power(controller.servo_power());
}

/// Once per servo frame (the PWM wrap interrupt counts them): the controller's next six pulse
/// widths, and the notices to every link.
fn next_frame(controller: &mut Controller, servos: &mut ServoPwm, links: &mut BoardLinks) {
    let frames = servos.frames_since_last_poll();
    if frames > 0 {
        pulses::write_frame(controller, servos);
        links.write_notices(controller);
        if frames > 1 {
            defmt::warn!("missed {} servo frames", frames - 1);
        }
    }
}

/// Sleeps until an interrupt (bytes received on a link, TX FIFO half empty, USB output taken,
/// a frame) unless there is something to do now: input a link has room to take, work whose
/// link has room, a frame, or what a port wants a pass for ([`link::Port::wants_pass`]: a
/// baud switch waiting for the UART to go idle, a USB port opened or closed). Output waiting
/// for room is no reason to stay awake: the UART's TX interrupt, or the USB interrupt when the
/// host takes a packet, wakes the loop. (Decided after the baud switch, so the UART going idle
/// between the two cannot put the loop to sleep with the switch still to do.)
///
/// Woken, it returns for a pass only if one has something to do: received bytes that only add
/// characters to a command line (most of a line's bytes: they come 8 at a time at the faster
/// rates) are taken into their line here ([`Links::take_plain_input`]) and the core sleeps
/// again, unless something else is due when the check runs again (a line end or any other
/// byte after them, a frame, a USB event, a loss). A wake that brought no such characters (a
/// line end alone, a control byte, room for output...) gets a pass at once, as does every
/// wake while a command's work runs (the hold-up watch), in a stream frame, or with echo on
/// (an interactive user sees every byte echoed at once).
fn sleep_unless_due(controller: &Controller, links: &mut BoardLinks, servos: &ServoPwm) {
    // Whether characters could be taken between passes at all (see above): if not, a wake goes
    // straight to its pass.
    let quiet = !controller.is_busy() && links.may_take_plain();
    loop {
        let port_wants_pass = links.wants_pass(controller.baud());
        // Interrupts stay masked from the check to the WFI: one arriving in between stays
        // pending, so WFI returns at once instead of sleeping through it; its handler runs
        // right after.
        let slept = cortex_m::interrupt::free(|_| {
            let input_or_work = if controller.is_busy() {
                links.work_has_room()
            } else {
                links.input_waiting()
            };
            let due = input_or_work || servos.frame_pending() || port_wants_pass;
            if !due {
                cortex_m::asm::wfi();
            }
            !due
        });
        if !(slept && quiet && links.take_plain_input()) {
            return;
        }
    }
}
