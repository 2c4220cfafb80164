//! hexapod-fw: the RP2040 board layer.
//!
//! Data flows one way: UART0 bytes -> controller (lines, commands, motion) -> six pulse
//! widths per servo frame (and right after a command that jumps) -> PWM registers. This file
//! only wires the pieces together: clocks and watchdog, UART0 ([`serial`]) with its link
//! [`control::Session`], the six servo outputs ([`servo_pwm`]) and the hardware-independent
//! [`control::Controller`], which runs on the boot ROM's float routines
//! ([`firmware::rom_math`]).

#![no_std]
#![no_main]

mod serial;
mod servo_pwm;

use defmt_rtt as _;
use panic_probe as _;
use rp2040_hal::{self as hal, clocks::Clock, fugit::ExtU32, pac, Sio, Watchdog};

use control::{Session, Settings};
use firmware::rom_math::RomMath;
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
/// Most received bytes handed to the controller in one pass (a line end ends the pass's input
/// early, so at most one command runs per pass).
const RX_BYTES_PER_PASS: usize = 64;

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

    let mut controller = Controller::with_math(Settings::default());
    let mut serial = Serial::new(
        p.UART0,
        pins.gpio0,
        pins.gpio1,
        &mut p.RESETS,
        clocks.peripheral_clock.freq(),
        controller.baud(),
    )
    .expect("the default baud rate is in range");
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
    .expect("the default frame rate is in range");
    watchdog.start(WATCHDOG_TIMEOUT_MS.millis());

    // UART0's line assembly, echo and prompt (the platform's state is the controller's).
    let mut uart = Session::new();
    controller.banner(&mut uart, &mut serial);
    defmt::info!("ready");

    // The main loop. Every pass is short, whatever arrives: it runs at most one command, or
    // one slice of a command's long work (a path check a few IK solutions at a time, a listing
    // a line at a time: the controller splits it, see `control::Controller::work`), plus the
    // frame that came due. The longest pass is measured in the emulator (well under 1 ms,
    // against a 3 ms frame at 333 Hz and the 500 ms watchdog; BENCHMARKS.md).
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
            // A slice of the work in progress; its reply comes with the last slice.
            if serial.has_room_for_step() {
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
                        controller.on_byte(&mut uart, byte, &mut serial);
                        // A jump (speed limits off) is written now, not at the next frame; the
                        // compare registers latch it at the next period start.
                        write_new_pulses(&mut controller, &mut servos);
                        if byte == b'\r' || byte == b'\n' || controller.is_busy() {
                            break;
                        }
                    }
                    // The gap where bytes were lost: the line it cuts is refused at its end.
                    Some(Received::Lost(lost)) => controller.on_rx_overflow(&mut uart, lost),
                    None => break,
                }
            }
        }

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
        let baud_change_pending = baud != serial.baud();
        if baud_change_pending && serial.tx_idle() {
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
        // awake: the TX interrupt wakes the loop when the FIFO has drained.
        let room = serial.has_room_for_step();
        // A baud change waiting for the UART's last bytes to leave: stay awake (they leave within
        // 32 character times, and no interrupt marks the end). Not `&& !tx_idle()`: the UART
        // may have gone idle since the check above, and then nothing would wake the loop.
        let waiting_for_tx = baud_change_pending && !serial.tx_pending();
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
