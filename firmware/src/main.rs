//! hexapod-fw: the RP2040 board layer.
//!
//! Data flows one way: UART0 bytes -> controller (lines, commands, stream frames, motion) ->
//! six pulse widths per servo frame (and right after a command that jumps or a stream frame in
//! pass-through) -> PWM registers. This file only wires the pieces together: clocks and
//! watchdog, UART0 ([`serial`]) with its link [`control::Session`], the six servo outputs
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
/// Most received bytes handed to the controller in one pass (a line end ends the pass's input
/// early, so at most one command runs per pass; stream frames do not end it, so the newest of
/// the frames waiting is the one applied). 128 bytes are 8 binary frames, 1.4 ms of a stream
/// at 921,600 baud: more than a pass takes, so a stream never falls behind.
const RX_BYTES_PER_PASS: usize = 128;

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

    // UART0's line assembly, echo and prompt (the platform's state is the controller's).
    let mut uart = Session::new();
    controller.banner(&mut uart, &mut serial);
    defmt::info!("ready");

    // The main loop. Every pass is short, whatever arrives: it runs at most one command, or
    // one slice of a command's long work (a path check a few IK solutions at a time, a listing
    // a line at a time: the controller splits it, see `control::Controller::work`), plus the
    // frame that came due. The longest pass is measured in the emulator (well under 1 ms,
    // against a 3 ms frame at 333 Hz and the 500 ms watchdog; BENCHMARKS.md). The one
    // exception is a `save`'s flash write (a sector erase: tens to hundreds of milliseconds
    // with interrupts masked), alone in its pass, with the watchdog given longer.
    let mut rx_line_errors_reported = 0;
    loop {
        watchdog.feed();

        // Lost input is announced at once, to every link; the line it cut is refused when the
        // loop reaches the gap.
        if let Some(lost) = serial.take_new_loss() {
            defmt::warn!("serial receive: input lost (at least {} bytes)", lost.bytes);
            controller.on_input_lost(&mut uart, lost.bytes, lost.in_uart, &mut serial);
        }

        if controller.is_busy() {
            if let Some(write) = controller.take_flash_write() {
                // `save`: erase the older sector, program its page, read it back. The PWM
                // holds the pulses meanwhile (nothing moves: save is refused while moving);
                // input waits in the UART's FIFO. The reply comes in the next pass.
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
            } else if serial.has_room_for_step() {
                // A slice of the work in progress; its reply comes with the last slice.
                controller.work(&mut uart, &mut serial);
                write_new_pulses(&mut controller, &mut servos);
                // The controller's own work (the return home after link loss) may notify.
                controller.write_notices(&mut uart, &mut serial);
            }
        } else {
            // Serial bytes -> controller, up to the end of one line. Input waits in the receive
            // queue while the transmit buffer lacks room for a step's output, so replies are
            // never cut.
            for _ in 0..RX_BYTES_PER_PASS {
                if !serial.has_room_for_step() {
                    break;
                }
                match serial.read() {
                    Some(Received::Byte(byte)) => {
                        let fed = controller.on_byte(&mut uart, byte, &mut serial);
                        // A jump (speed limits off) is written now, not at the next frame; the
                        // compare registers latch it at the next period start.
                        write_new_pulses(&mut controller, &mut servos);
                        if fed == Fed::LineEnded || controller.is_busy() {
                            break;
                        }
                    }
                    // The gap where bytes were lost: the line it cuts is refused at its end.
                    Some(Received::Lost(lost)) => controller.on_rx_overflow(&mut uart, lost),
                    None => break,
                }
            }
            // The newest stream frame among those just fed (in pass-through, written now).
            controller.apply_stream();
            write_new_pulses(&mut controller, &mut servos);
        }

        // The e-stop input (read every pass: within a servo frame of it opening) and the
        // servo-power output.
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
            controller.write_notices(&mut uart, &mut serial);
            if frames > 1 {
                defmt::warn!("missed {} servo frames", frames - 1);
            }
        }

        apply_frame_rate(&controller, &mut servos);
        // A baud change waits for the reply announcing it to have left the UART at the old
        // rate; then the prompt held back for it goes out at the new one.
        let baud = controller.baud();
        if baud != serial.baud() && serial.tx_idle() {
            match serial.set_baud(baud) {
                Ok(()) => uart.write_deferred_prompt(&mut serial),
                Err(_) => defmt::error!("baud rate {} out of range", baud),
            }
        }
        serial.send_some();

        let rx_line_errors = serial.rx_line_errors();
        if rx_line_errors != rx_line_errors_reported {
            rx_line_errors_reported = rx_line_errors;
            defmt::warn!("serial receive: {} line errors so far", rx_line_errors);
        }

        // Sleep until an interrupt (bytes received, TX FIFO half empty, a frame) unless there
        // is something to do now. Output waiting for room in the TX FIFO is no reason to stay
        // awake: the TX interrupt wakes the loop when the FIFO has drained. A baud change
        // waiting for the last bytes to leave is: no interrupt says when the UART goes idle,
        // so the loop stays awake until it has switched (decided after the switch above, so
        // the UART going idle between the two cannot put the loop to sleep with the switch
        // still to do).
        let room = serial.has_room_for_step();
        let waiting_for_tx = controller.baud() != serial.baud() && !serial.tx_pending();
        sleep_unless(|| {
            (room && (controller.is_busy() || serial.rx_pending()))
                || servos.frame_pending()
                || waiting_for_tx
        });
    }
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
