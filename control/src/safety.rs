//! The safety input and output: an emergency-stop input (a GPIO, active low with the pull-up
//! on, so a switch or a cut wire opens it) and a servo-power enable output (a GPIO driven high
//! to power the servos, e.g. through a MOSFET or a relay module). Both are optional (`off` by
//! default). This module holds their settings and the e-stop's state; the board reads and
//! drives the pins, the controller decides.
//!
//! The e-stop's rules:
//! - when the input opens the platform stops ([`EstopAction::Freeze`]: it holds where it is;
//!   or [`EstopAction::Home`]: it eases home at the link-loss speeds), the stream ends, and
//!   the power output goes off (after reaching home, for `home`);
//! - from then on every motion command (`pose`, `move`, `nudge`, `home`) and every stream
//!   frame is refused, until the input is closed again **and** `reset` is sent: closing it
//!   alone never moves anything;
//! - the power output is off at start-up and goes on with the first accepted move or stream
//!   frame (not before: the servos would jump to whatever the board drives at power-on).

/// GPIOs the e-stop and power pins may use: the Pico's GPIOs that the firmware leaves free
/// (UART0 is on 0 and 1, the servos on 2 to 7) and that the Pico board does not wire itself
/// (23: power-supply mode, 24: VBUS sense, 25: the LED, 29: VSYS sense).
pub const FREE_GPIOS: [u32; 18] = [
    8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 26, 27, 28,
];

/// What the platform does when the e-stop input opens (`estop_action`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EstopAction {
    /// Stop and hold where it is (`freeze`).
    #[default]
    Freeze,
    /// Ease home at the link-loss speeds, then hold (`home`).
    Home,
}

/// The safety pins (`estop_pin`, `estop_action`, `power_pin`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SafetySettings {
    /// The e-stop input's GPIO; `None`: no e-stop input.
    pub estop_pin: Option<u8>,
    /// What the e-stop does.
    pub estop_action: EstopAction,
    /// The servo-power output's GPIO; `None`: no power output.
    pub power_pin: Option<u8>,
}

/// The e-stop's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Estop {
    /// Not stopped: motion allowed.
    #[default]
    Clear,
    /// The input is open.
    Open,
    /// The input was opened and is closed again: `reset` clears it.
    Latched,
}

impl Estop {
    /// The state after the board read the input (`open`: the pin reads high, or there is no
    /// e-stop input: never).
    pub fn with_input(self, open: bool) -> Estop {
        match (self, open) {
            (_, true) => Estop::Open,
            (Estop::Open, false) => Estop::Latched,
            (other, false) => other,
        }
    }

    /// True while motion is refused.
    pub fn stops_motion(self) -> bool {
        self != Estop::Clear
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_closing_then_reset_clears_it() {
        let mut e = Estop::Clear;
        e = e.with_input(false);
        assert_eq!(e, Estop::Clear);
        e = e.with_input(true);
        assert_eq!(e, Estop::Open);
        assert!(e.stops_motion());
        e = e.with_input(true);
        assert_eq!(e, Estop::Open);
        e = e.with_input(false);
        assert_eq!(e, Estop::Latched);
        assert!(
            e.stops_motion(),
            "closing the input alone does not clear it"
        );
        assert_eq!(e.with_input(false), Estop::Latched);
        assert_eq!(e.with_input(true), Estop::Open);
    }

    #[test]
    fn free_gpios_avoid_the_firmware_and_the_board() {
        for used in [0, 1, 2, 3, 4, 5, 6, 7, 23, 24, 25, 29] {
            assert!(!FREE_GPIOS.contains(&used), "GPIO {used}");
        }
        assert!(FREE_GPIOS.iter().all(|&p| p < 30));
    }
}
