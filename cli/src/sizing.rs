//! The `[sizing]` table of a build file: what the host's sizing tools (`describe`, `torque`)
//! need beyond the board's settings: the payload (mass in kg, centre of mass in the platform
//! frame in mm) and the servos (rated torque in kgf cm, holding stiffness in N mm/rad). Not
//! settings of the board: `apply` never sends them.

use kinematics_core::statics::Payload;
use kinematics_core::Vec3;

use crate::messages::SizingProblem;

/// The table's name with the dot of its keys.
pub const SIZING_TABLE: &str = "sizing.";

/// Its keys, in file order.
pub const KEYS: [&str; 6] = [
    "payload_kg",
    "payload_x_mm",
    "payload_y_mm",
    "payload_z_mm",
    "servo_torque_kgcm",
    "servo_stiffness_nmm_rad",
];

/// The payload and the servos' rating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sizing {
    /// Payload mass, kg.
    pub payload_kg: f32,
    /// Payload centre of mass, platform frame, mm.
    pub payload_com_mm: [f32; 3],
    /// Each servo's rated torque, kgf cm.
    pub servo_torque_kgcm: f32,
    /// Each servo's holding stiffness, N mm/rad.
    pub servo_stiffness_nmm_rad: f32,
}

impl Default for Sizing {
    /// 1 kg, 20 mm above the platform's centre, on micro servos (1.8 kgf cm, e.g. an SG90),
    /// holding 5000 N mm/rad (about 1.8 kgf cm per 2 degrees).
    fn default() -> Sizing {
        Sizing {
            payload_kg: 1.0,
            payload_com_mm: [0.0, 0.0, 20.0],
            servo_torque_kgcm: 1.8,
            servo_stiffness_nmm_rad: 5000.0,
        }
    }
}

impl Sizing {
    /// Sets one key (without `sizing.`) to a number, refusing unknown keys and values out of
    /// range.
    pub fn set(&mut self, key: &str, value: Option<f32>) -> Result<(), SizingProblem> {
        let (slot, min, max, unit) = match key {
            "payload_kg" => (&mut self.payload_kg, 0.0, 1000.0, "kg"),
            "payload_x_mm" => (&mut self.payload_com_mm[0], -2000.0, 2000.0, "mm"),
            "payload_y_mm" => (&mut self.payload_com_mm[1], -2000.0, 2000.0, "mm"),
            "payload_z_mm" => (&mut self.payload_com_mm[2], -2000.0, 2000.0, "mm"),
            "servo_torque_kgcm" => (&mut self.servo_torque_kgcm, 0.01, 1000.0, "kgf cm"),
            "servo_stiffness_nmm_rad" => (&mut self.servo_stiffness_nmm_rad, 1.0, 1e9, "N mm/rad"),
            _ => return Err(SizingProblem::Unknown),
        };
        match value {
            Some(v) if (min..=max).contains(&v) => {
                *slot = v;
                Ok(())
            }
            _ => Err(SizingProblem::Range { min, max, unit }),
        }
    }

    /// Every key with its value, in [`KEYS`] order.
    pub fn entries(&self) -> [(&'static str, f32); 6] {
        let [x, y, z] = self.payload_com_mm;
        [
            (KEYS[0], self.payload_kg),
            (KEYS[1], x),
            (KEYS[2], y),
            (KEYS[3], z),
            (KEYS[4], self.servo_torque_kgcm),
            (KEYS[5], self.servo_stiffness_nmm_rad),
        ]
    }

    /// The payload as the toolkit takes it (a point mass).
    pub fn payload(&self) -> Payload {
        let [x, y, z] = self.payload_com_mm;
        Payload::point(self.payload_kg, Vec3::new(x, y, z))
    }
}
