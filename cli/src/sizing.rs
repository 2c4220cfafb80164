//! The `[sizing]` table of a build file: what the host's sizing tools need that the board has
//! no setting for: each servo's holding stiffness (N mm/rad), for `describe`'s stiffness and
//! how far the payload's weight moves the platform. Not a setting of the board: `apply` never
//! sends it.
//!
//! The payload and the servos' torque ratings are the board's own settings (`payload_g`,
//! `payload_com_x_mm` .. `payload_com_z_mm`, `servoN.torque_kgcm`): they were keys of this
//! table once, and a file that still has them is refused with the setting to write instead
//! ([`moved`]).

use control::settings::{ServoParam, ServoSel, SettingId};

use crate::error::SizingError;

/// The table's name with the dot of its keys.
pub const SIZING_TABLE: &str = "sizing.";

/// Its keys, in file order.
pub const KEYS: [&str; 1] = ["servo_stiffness_nmm_rad"];

/// The table's heading in a build file, with what it is for.
pub const HEADER: &str = "\n\
# Host-only: the servos' holding stiffness, for `describe` (the platform's stiffness, how far\n\
# the payload's weight moves it). The board has no such setting: `apply` never sends it.\n\
[sizing]\n";

/// What a key is, for a build file's comments.
pub fn meaning(key: &str) -> &'static str {
    match key {
        "servo_stiffness_nmm_rad" => "each servo's holding stiffness, N mm/rad",
        _ => "",
    }
}

/// The host-only numbers of a platform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sizing {
    /// Each servo's holding stiffness, N mm/rad.
    pub servo_stiffness_nmm_rad: f32,
}

impl Default for Sizing {
    /// A micro servo's: about 5000 N mm/rad (1.8 kgf cm per 2 degrees).
    fn default() -> Sizing {
        Sizing {
            servo_stiffness_nmm_rad: 5000.0,
        }
    }
}

/// The board setting that replaced a key this table once had, and the factor from the old
/// key's unit to the setting's (`payload_kg` 2.5 is `payload_g` 2500).
pub fn moved(key: &str) -> Option<(SettingId, f32)> {
    Some(match key {
        "payload_kg" => (SettingId::PayloadG, 1000.0),
        "payload_x_mm" => (SettingId::PayloadCom(0), 1.0),
        "payload_y_mm" => (SettingId::PayloadCom(1), 1.0),
        "payload_z_mm" => (SettingId::PayloadCom(2), 1.0),
        "servo_torque_kgcm" => (SettingId::Servo(ServoSel::All, ServoParam::TorqueKgcm), 1.0),
        _ => return None,
    })
}

impl Sizing {
    /// Sets one key (without `sizing.`) to a number, refusing unknown keys, keys that are the
    /// board's settings now, and values out of range.
    pub fn set(&mut self, key: &str, value: Option<f32>) -> Result<(), SizingError> {
        let (slot, min, max, unit) = match key {
            "servo_stiffness_nmm_rad" => (&mut self.servo_stiffness_nmm_rad, 1.0, 1e9, "N mm/rad"),
            _ => {
                return Err(match moved(key) {
                    Some((setting, factor)) => SizingError::Moved {
                        setting,
                        value: value.map(|v| v * factor),
                    },
                    None => SizingError::Unknown { keys: &KEYS },
                })
            }
        };
        match value {
            Some(v) if (min..=max).contains(&v) => {
                *slot = v;
                Ok(())
            }
            _ => Err(SizingError::Range { min, max, unit }),
        }
    }

    /// Every key with its value, in [`KEYS`] order.
    pub fn entries(&self) -> [(&'static str, f32); 1] {
        [(KEYS[0], self.servo_stiffness_nmm_rad)]
    }
}
