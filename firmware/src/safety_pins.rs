//! The safety pins on whichever free GPIOs the settings name: the emergency-stop input
//! (`estop_pin`: SIO input with the pull-up on, so an open switch or a cut wire reads high =
//! open) and the servo-power enable output (`power_pin`: SIO output, high = power on, low at
//! start-up). Pins not in use are left as after reset (no function). What the pins mean is
//! [`control::safety`]'s; this module only configures, reads and drives them.

use control::safety::{SafetySettings, FREE_GPIOS};
use rp2040_hal::gpio::{DynFunction, DynPinId, DynPullType, DynSioConfig, FunctionSioOutput, Pin};

/// A free GPIO, its function and pull chosen at run time.
pub type FreePin = Pin<DynPinId, DynFunction, DynPullType>;

/// The free GPIOs and the safety roles given to them.
pub struct SafetyPins {
    /// The pins of [`FREE_GPIOS`], in that order.
    pins: [Option<FreePin>; FREE_GPIOS.len()],
    /// What the pins are configured for now.
    applied: SafetySettings,
}

impl SafetyPins {
    /// Takes the free GPIOs ([`FREE_GPIOS`] order); none is used until [`SafetyPins::apply`].
    pub fn new(pins: [FreePin; FREE_GPIOS.len()]) -> Self {
        SafetyPins {
            pins: pins.map(Some),
            applied: SafetySettings::default(),
        }
    }

    /// Configures the pins for these settings (releasing pins no longer used). The power
    /// output starts low (off).
    pub fn apply(&mut self, safety: &SafetySettings) {
        let old = self.applied;
        if old.estop_pin == safety.estop_pin && old.power_pin == safety.power_pin {
            return;
        }
        for gpio in [old.estop_pin, old.power_pin].into_iter().flatten() {
            self.with_pin(gpio, |pin| {
                // Low first, so a released power output does not float high for a moment.
                pin.set_function(DynFunction::Null);
                pin.set_pull(DynPullType::Down);
            });
        }
        if let Some(gpio) = safety.estop_pin {
            self.with_pin(gpio, |pin| {
                pin.set_pull(DynPullType::Up);
                pin.set_function(DynFunction::Sio(DynSioConfig::Input));
            });
        }
        if let Some(gpio) = safety.power_pin {
            self.with_pin(gpio, |pin| {
                pin.set_pull(DynPullType::None);
                pin.drive(false);
            });
        }
        self.applied = *safety;
    }

    /// The e-stop input: `Some(true)` when open (the pin reads high), `None` when there is no
    /// e-stop pin.
    pub fn estop_open(&self) -> Option<bool> {
        let gpio = self.applied.estop_pin?;
        let pin = self.slot(gpio)?.as_ref()?;
        use embedded_hal::digital::InputPin;
        Some(pin.as_input().is_high().unwrap_or(true))
    }

    /// Drives the power output (if there is one).
    pub fn set_power(&mut self, on: bool) {
        if let Some(gpio) = self.applied.power_pin {
            self.with_pin(gpio, |pin| pin.drive(on));
        }
    }

    fn slot(&self, gpio: u8) -> Option<&Option<FreePin>> {
        let index = FREE_GPIOS.iter().position(|&g| g == u32::from(gpio))?;
        self.pins.get(index)
    }

    /// Runs `f` on a free pin (nothing for a GPIO that is not free: the settings refuse those).
    fn with_pin(&mut self, gpio: u8, f: impl FnOnce(&mut PinSlot)) {
        if let Some(index) = FREE_GPIOS.iter().position(|&g| g == u32::from(gpio)) {
            if let Some(slot) = self.pins.get_mut(index) {
                f(&mut PinSlot(slot));
            }
        }
    }
}

/// One free pin being reconfigured.
struct PinSlot<'a>(&'a mut Option<FreePin>);

impl PinSlot<'_> {
    fn set_function(&mut self, function: DynFunction) {
        if let Some(pin) = self.0.as_mut() {
            // SIO and no function are valid on every bank-0 GPIO.
            let _ = pin.try_set_function(function);
        }
    }

    fn set_pull(&mut self, pull: DynPullType) {
        if let Some(pin) = self.0.as_mut() {
            pin.set_pull_type(pull);
        }
    }

    /// Makes the pin an SIO output at this level.
    fn drive(&mut self, high: bool) {
        let Some(pin) = self.0.take() else {
            return;
        };
        *self.0 = Some(match pin.try_into_function::<FunctionSioOutput>() {
            Ok(mut output) => {
                use embedded_hal::digital::OutputPin;
                let _ = if high {
                    output.set_high()
                } else {
                    output.set_low()
                };
                output.into_function()
            }
            Err(pin) => pin,
        });
    }
}
