//! The controller's pulse widths (us) onto the six servo outputs ([`ServoPwm`]): each servo
//! frame's, a jump's at once, the per-servo limits the PWM clamps to as a last resort, and the
//! frame rate (Hz) the settings ask for.

use firmware::Controller;

use crate::servo_pwm::{PulseWindowUs, ServoPwm, SERVO_COUNT};

/// Writes the pulses a command changed outside the frame rhythm (a jump), if any: the compare
/// registers latch them at the next period start.
pub fn write_new(controller: &mut Controller, servos: &mut ServoPwm) {
    if let Some(pulses_us) = controller.take_new_pulses() {
        servos.set_pulse_widths_us_now(&pulses_us, &windows_us(controller));
    }
}

/// Advances the controller by one servo frame and writes its six pulse widths.
pub fn write_frame(controller: &mut Controller, servos: &mut ServoPwm) {
    let pulses_us = controller.on_frame();
    servos.set_frame_pulse_widths_us(&pulses_us, &windows_us(controller));
}

/// Each servo's configured pulse limits: the PWM layer clamps to them as a last resort.
pub fn windows_us(controller: &Controller) -> [PulseWindowUs; SERVO_COUNT] {
    controller.settings().servos.0.map(|servo| PulseWindowUs {
        min_us: servo.min_us,
        max_us: servo.max_us,
    })
}

/// Makes the PWM follow the controller's frame rate.
pub fn follow_frame_rate(controller: &Controller, servos: &mut ServoPwm) {
    let frame_hz = controller.frame_hz();
    if frame_hz != servos.frame_rate_hz() && servos.set_frame_rate_hz(frame_hz).is_err() {
        defmt::error!("frame rate {} Hz out of range", frame_hz);
    }
}
