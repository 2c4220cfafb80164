//! hexapod-fw: the RP2040 board layer.
//!
//! Data flows one way: serial bytes (UART0 and the USB port) -> controller (lines, commands,
//! stream frames, motion) -> six pulse widths per servo frame (and right after a command that
//! jumps or a stream frame in pass-through) -> PWM registers. This file only wires the pieces
//! together: clocks and watchdog, the two serial links, UART0 ([`serial`]) and USB CDC
//! ([`usb_serial`]), each with its own [`control::Session`], the six servo outputs
//! ([`servo_pwm`]), the e-stop input and servo-power output ([`safety_pins`]), the settings
//! saved in flash ([`flash`]) and the hardware-independent [`control::Controller`], which runs
//! on the boot ROM's float routines ([`firmware::rom_math`]) where it computes in `f32` (its IK
//! runs in fixed point, `kinematics_core::fixed`).

#![no_std]
#![no_main]

mod flash;
mod safety_pins;
mod serial;
mod servo_pwm;
mod usb_serial;

use core::fmt;

use defmt_rtt as _;
use panic_probe as _;
use rp2040_hal::{self as hal, clocks::Clock, fugit::ExtU32, pac, Sio, Watchdog};

use control::controller::Fed;
use control::store::Store;
use control::Session;
use firmware::rom_math::RomMath;
use flash::SettingsFlash;
use safety_pins::{FreePin, SafetyPins};
use serial::{Received, Serial};
use servo_pwm::{PulseWindowUs, ServoPwm, SERVO_COUNT};
use usb_serial::UsbSerial;

type Controller = control::Controller<RomMath>;

/// Second-stage bootloader for the Pico's W25Q080 flash: the first 256 bytes of flash.
#[unsafe(link_section = ".boot2")]
#[used]
pub static BOOT2: [u8; 256] = rp2040_boot2::BOOT_LOADER_W25Q080;

/// Reset the chip if the main loop stalls this long. A pass takes well under a millisecond
/// (see [`main`]), so only a hang can starve the watchdog.
const WATCHDOG_TIMEOUT_MS: u32 = 500;
/// The watchdog's time for a `save`'s flash write: a 4 KiB sector erase takes the W25Q080 up
/// to 400 ms and a page program up to 3 ms (datasheet maxima), with interrupts masked; 2 s
/// leaves a wide margin and still resets a write that hangs.
const SAVE_WATCHDOG_MS: u32 = 2000;
/// Most received bytes handed to the controller in one pass, both links together (a line end
/// ends the pass's input early, so at most one command runs per pass; stream frames do not end
/// it, so the newest of the frames waiting is the one applied). 128 bytes are 8 binary frames,
/// 1.4 ms of a stream at 921,600 baud: more than a pass takes, so a UART stream never falls
/// behind (a USB host that sends faster waits: USB's flow control).
const RX_BYTES_PER_PASS: usize = 128;

/// A serial link's port, as the main loop uses it: received bytes in, output written.
trait Port: fmt::Write {
    /// The output of one controller step fits (or is dropped anyway): the step may be taken.
    fn has_room_for_step(&self) -> bool;
    /// The next received byte, or where bytes were lost.
    fn receive(&mut self) -> Option<Received>;
}

impl Port for Serial {
    fn has_room_for_step(&self) -> bool {
        Serial::has_room_for_step(self)
    }
    fn receive(&mut self) -> Option<Received> {
        self.read()
    }
}

impl Port for UsbSerial {
    fn has_room_for_step(&self) -> bool {
        UsbSerial::has_room_for_step(self)
    }
    fn receive(&mut self) -> Option<Received> {
        self.read()
    }
}

#[hal::entry]
fn main() -> ! {
    let mut p = pac::Peripherals::take().expect("peripherals are taken once, here");
    let mut watchdog = Watchdog::new(p.WATCHDOG);
    let clocks = firmware::init_clocks(
        p.XOSC,
        p.CLOCKS,
        p.PLL_SYS,
        p.PLL_USB,
        &mut p.RESETS,
        &mut watchdog,
    );
    let sio = Sio::new(p.SIO);
    let pins = hal::gpio::Pins::new(p.IO_BANK0, p.PADS_BANK0, sio.gpio_bank0, &mut p.RESETS);

    // The newest good settings saved in flash, or the defaults (with a warning saying why).
    let mut settings_flash = SettingsFlash::new();
    let mut controller = Controller::power_up(Store::load_with::<RomMath, _>(&mut settings_flash));
    defmt::info!(
        "settings storage at flash offset {=u32:#x}",
        settings_flash.base()
    );
    // The 1 MHz timer: its alarm 0 polls UART0's RX FIFO, its counter times the USB host's
    // reading.
    let mut timer = hal::Timer::new(p.TIMER, &mut p.RESETS, &clocks);
    let rx_poll = timer.alarm_0().expect("alarm 0 is taken once, here");
    let mut serial = Serial::new(
        p.UART0,
        pins.gpio0,
        pins.gpio1,
        &mut p.RESETS,
        clocks.peripheral_clock.freq(),
        controller.baud(),
        rx_poll,
    )
    .expect("the power-up baud rate is in range");
    let mut servos = ServoPwm::new(
        p.PWM,
        &mut p.RESETS,
        (
            pins.gpio2, pins.gpio3, pins.gpio4, pins.gpio5, pins.gpio6, pins.gpio7,
        ),
        controller.frame_hz(),
        &controller.pulses_us(),
        &pulse_windows_us(&controller),
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
    let mut usb = UsbSerial::new(
        p.USBCTRL_REGS,
        p.USBCTRL_DPRAM,
        clocks.usb_clock,
        &mut p.RESETS,
    );

    // Each link's line assembly, echo and prompt (the platform's state is the controller's).
    // UART0 is greeted now; the USB port when a host opens it.
    let mut uart_link = Session::new();
    let mut usb_link = Session::new();
    controller.banner(&mut uart_link, &mut serial);
    defmt::info!("ready");

    // The main loop. Every pass is short, whatever arrives on either link: it runs at most one
    // command (from one link or the other, the link that goes first alternating), or one slice
    // of a command's long work (a path check a few IK solutions at a time, a listing a line at
    // a time: the controller splits it, see `control::Controller::work`), plus the newest
    // stream frame and the frame that came due. A reply goes to the link that sent the line,
    // notices to every open link. The longest pass is measured in the emulator (well under
    // 1 ms, against a 3 ms frame at 333 Hz and the 500 ms watchdog; BENCHMARKS.md). The one
    // exception is a `save`'s flash write (a sector erase: tens to hundreds of milliseconds
    // with interrupts masked, USB's too), alone in its pass, with the watchdog given longer.
    let mut rx_line_errors_reported = 0;
    let mut usb_first = false;
    loop {
        watchdog.feed();

        // The USB host opened its port (DTR): a new terminal, greeted like UART0 at power-up;
        // or closed it (its output is dropped from now on). A host that stopped reading has its
        // output dropped too, after a while, so that it holds up nothing else.
        if usb.take_open_change(usb_link.awaits_reply()) == Some(true) {
            usb_link.reopen();
            controller.banner(&mut usb_link, &mut usb);
        }
        usb.watch_output(timer.get_counter_low());

        // Lost input (only UART0 loses any) is announced at once, to every link; the line it
        // cut is refused when the loop reaches the gap.
        if let Some(lost) = serial.take_new_loss() {
            defmt::warn!("serial receive: input lost (at least {} bytes)", lost.bytes);
            controller.on_input_lost(&mut uart_link, lost.bytes, lost.in_uart, &mut serial);
            if usb.takes_notices() {
                controller.write_notices(&mut usb_link, &mut usb);
            }
        }

        if controller.is_busy() {
            if let Some(write) = controller.take_flash_write() {
                // `save`: erase the older sector, program its page, read it back. The PWM
                // holds the pulses meanwhile (nothing moves: save is refused while moving);
                // input waits in the UART's FIFO, and in the USB host (interrupts are masked,
                // so the USB hardware refuses the host's packets with NAK and the host tries
                // again). The reply comes in the next pass, on the link that sent `save`.
                watchdog.start(SAVE_WATCHDOG_MS.millis());
                let result = write.perform(&mut settings_flash);
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
            } else {
                // A slice of the work in progress, with the link that sent the command (the
                // controller's own work, the return home after link loss or an e-stop, goes
                // with UART0's). Its reply comes with the last slice.
                let usb_job = usb_link.awaits_reply();
                let room = if usb_job {
                    usb.has_room_for_step()
                } else {
                    serial.has_room_for_step()
                };
                if room {
                    if usb_job {
                        controller.work(&mut usb_link, &mut usb);
                    } else {
                        controller.work(&mut uart_link, &mut serial);
                    }
                    write_new_pulses(&mut controller, &mut servos);
                    // The controller's own work (the return home after link loss) may notify.
                    controller.write_notices(&mut uart_link, &mut serial);
                    if usb.takes_notices() {
                        controller.write_notices(&mut usb_link, &mut usb);
                    }
                }
            }
        } else {
            // Received bytes -> controller, up to the end of one line, from one link and then,
            // if no line ended, the other (stream frames do not end the input). Input waits (in
            // the receive queue, or for USB in the host) while its link lacks room for a step's
            // output, so replies are never cut.
            usb_first = !usb_first;
            let mut budget = RX_BYTES_PER_PASS;
            for usb_turn in [usb_first, !usb_first] {
                let input_ends = if usb_turn {
                    feed(
                        &mut controller,
                        &mut usb_link,
                        &mut usb,
                        &mut servos,
                        &mut budget,
                    )
                } else {
                    feed(
                        &mut controller,
                        &mut uart_link,
                        &mut serial,
                        &mut servos,
                        &mut budget,
                    )
                };
                if input_ends {
                    break;
                }
            }
            // The newest stream frame among those just fed, from either link (in pass-through,
            // written now).
            controller.apply_stream();
            write_new_pulses(&mut controller, &mut servos);
        }

        // The e-stop input (read every pass: within a servo frame of it opening) and the
        // servo-power output. Its notices go to every open link with the next frame's.
        safety.apply(&controller.settings().safety);
        if let Some(open) = safety.estop_open() {
            controller.set_estop_input(open);
        }
        safety.set_power(controller.servo_power());

        // Once per servo frame: the controller's next six pulse widths.
        let frames = servos.frames_since_last_poll();
        if frames > 0 {
            let pulses_us = controller.on_frame();
            servos.set_frame_pulse_widths_us(&pulses_us, &pulse_windows_us(&controller));
            controller.write_notices(&mut uart_link, &mut serial);
            if usb.takes_notices() {
                controller.write_notices(&mut usb_link, &mut usb);
            }
            if frames > 1 {
                defmt::warn!("missed {} servo frames", frames - 1);
            }
        }

        apply_frame_rate(&controller, &mut servos);
        // A baud change (UART0's, from either link) waits for the reply announcing it to have
        // left the UART at the old rate; then the prompt held back for it goes out at the new
        // one. USB has no rate: a prompt held back there goes out at once.
        let baud = controller.baud();
        if baud != serial.baud() && serial.tx_idle() {
            match serial.set_baud(baud) {
                Ok(()) => uart_link.write_deferred_prompt(&mut serial),
                Err(_) => defmt::error!("baud rate {} out of range", baud),
            }
        }
        usb_link.write_deferred_prompt(&mut usb);
        serial.send_some();
        usb.send_some();

        let rx_line_errors = serial.rx_line_errors();
        if rx_line_errors != rx_line_errors_reported {
            rx_line_errors_reported = rx_line_errors;
            defmt::warn!("serial receive: {} line errors so far", rx_line_errors);
        }

        // Sleep until an interrupt (bytes received on either link, TX FIFO half empty, USB
        // output taken, a frame) unless there is something to do now. Output waiting for room
        // is no reason to stay awake: the UART's TX interrupt, or the USB interrupt when the
        // host takes a packet, wakes the loop. A baud change waiting for the UART's last bytes
        // to leave is: no interrupt says when the UART goes idle, so the loop stays awake until
        // it has switched (decided after the switch above, so the UART going idle between the
        // two cannot put the loop to sleep with the switch still to do).
        let uart_room = serial.has_room_for_step();
        let usb_room = usb.has_room_for_step();
        let job_can_go = if usb_link.awaits_reply() {
            usb_room
        } else {
            uart_room
        };
        let waiting_for_tx = controller.baud() != serial.baud() && !serial.tx_pending();
        let usb_opens_or_closes = usb.open_change_pending(usb_link.awaits_reply());
        sleep_unless(|| {
            let input_or_work = if controller.is_busy() {
                job_can_go
            } else {
                (uart_room && serial.rx_pending()) || (usb_room && usb.rx_pending())
            };
            input_or_work || servos.frame_pending() || waiting_for_tx || usb_opens_or_closes
        });
    }
}

/// Feeds bytes received on one link to the controller until a line ends (or a command's work
/// begins), `budget` bytes have been fed, the link lacks room for a step's output or has
/// nothing more. Stream frames do not end the feeding: binary frames contain line-end bytes,
/// and the newest of the frames waiting is the one applied. Returns whether the pass's input
/// ends here (a line ended).
fn feed(
    controller: &mut Controller,
    link: &mut Session,
    port: &mut impl Port,
    servos: &mut ServoPwm,
    budget: &mut usize,
) -> bool {
    while *budget > 0 && port.has_room_for_step() {
        match port.receive() {
            Some(Received::Byte(byte)) => {
                *budget -= 1;
                let fed = controller.on_byte(link, byte, port);
                // A jump (speed limits off) is written now, not at the next frame; the compare
                // registers latch it at the next period start.
                write_new_pulses(controller, servos);
                if fed == Fed::LineEnded || controller.is_busy() {
                    return true;
                }
            }
            // The gap where bytes were lost: the line it cuts is refused at its end.
            Some(Received::Lost(lost)) => controller.on_rx_overflow(link, lost),
            None => return false,
        }
    }
    false
}

/// Writes the pulses a command changed outside the frame rhythm (a jump), if any.
fn write_new_pulses(controller: &mut Controller, servos: &mut ServoPwm) {
    if let Some(pulses_us) = controller.take_new_pulses() {
        servos.set_pulse_widths_us_now(&pulses_us, &pulse_windows_us(controller));
    }
}

/// Each servo's configured pulse limits: the PWM layer clamps to them as a last resort.
fn pulse_windows_us(controller: &Controller) -> [PulseWindowUs; SERVO_COUNT] {
    controller.settings().servos.0.map(|servo| PulseWindowUs {
        min_us: servo.min_us,
        max_us: servo.max_us,
    })
}

/// Makes the PWM follow the controller's frame rate.
fn apply_frame_rate(controller: &Controller, servos: &mut ServoPwm) {
    let frame_hz = controller.frame_hz();
    if frame_hz != servos.frame_rate_hz() && servos.set_frame_rate_hz(frame_hz).is_err() {
        defmt::error!("frame rate {} Hz out of range", frame_hz);
    }
}

/// Sleeps until the next interrupt (received bytes, servo frame start) unless `busy()`.
fn sleep_unless(busy: impl FnOnce() -> bool) {
    // Interrupts stay masked from the check to the WFI: one arriving in between stays pending,
    // so WFI returns at once instead of sleeping through it; its handler runs right after.
    cortex_m::interrupt::free(|_| {
        if !busy() {
            cortex_m::asm::wfi();
        }
    });
}
