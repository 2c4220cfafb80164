//! The payload the platform carries and the servos' torque ratings: the holding torque each
//! servo needs at a pose, and whether that overloads a servo.
//!
//! The settings (`payload_g`, `payload_com_x_mm` .. `payload_com_z_mm`, `servoN.torque_kgcm`)
//! describe a point mass fixed to the platform (its centre of mass in the platform frame, mm)
//! and each servo's rated torque (kgf cm, as hobby servo datasheets give it; 0 = not rated).
//! The holding torques are the statics of the report on a force applied at the centre of a
//! Stewart platform, `tau = J^-T w` for the payload's weight `w`
//! ([`kinematics_core::statics::servo_holding_torques`], N mm), written here in kgf cm:
//! positive lifts the arm (towards a larger arm angle `alpha`). A servo is overloaded where
//! `|tau_i|` exceeds its rating.
//!
//! Costs (RP2040): one torque computation is about 47,000 cycles, 0.38 ms, some five IK
//! solutions (the arms' rows, a 6x6 factorisation and a solve), so the controller gives it a
//! slice of work of its own.

use kinematics_core::error::KinematicsError;
use kinematics_core::ik::Solver;
use kinematics_core::statics::{servo_holding_torques, Payload, N_MM_PER_KGF_CM};
use kinematics_core::{Math, Pose, Vec3, LEGS};

/// Heaviest payload accepted, g.
pub const MAX_PAYLOAD_G: f32 = 100_000.0;
/// Farthest centre of mass from the platform frame's origin along each axis, mm.
pub const MAX_COM_MM: f32 = 1000.0;
/// Smallest torque rating (besides 0 = not rated), kgf cm.
pub const MIN_TORQUE_KGCM: f32 = 0.01;
/// Largest torque rating, kgf cm (the flash record keeps hundredths in 16 bits).
pub const MAX_TORQUE_KGCM: f32 = 600.0;

/// The payload and the servos' torque ratings.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PayloadSettings {
    /// Mass carried by the platform, g (0: none; torques are then neither shown nor checked).
    pub mass_g: f32,
    /// Its centre of mass in the platform frame (origin at the platform joints' centre, z up),
    /// mm.
    pub com_mm: [f32; 3],
    /// Rated torque of servo `i + 1`, kgf cm, a whole number of hundredths; 0 = not rated.
    pub torque_kgcm: [f32; LEGS],
}

impl PayloadSettings {
    /// True if a payload is set: `check` and `status` show the holding torques.
    pub fn carried(&self) -> bool {
        positive(self.mass_g)
    }

    /// True if a payload is set and at least one servo has a rating: poses are checked for
    /// torque too. (Asked several times for every stream frame and clamp halving: in integer
    /// instructions, where each `f32` comparison is a library call on the RP2040.)
    pub fn checked(&self) -> bool {
        self.carried() && self.torque_kgcm.iter().any(|&t| positive(t))
    }

    /// The payload as the statics take it (kg, mm).
    pub fn payload(&self) -> Payload {
        let [x, y, z] = self.com_mm;
        Payload::point(self.mass_g / 1000.0, Vec3::new(x, y, z))
    }

    /// The holding torque each servo needs at `pose` with its arms at `arm_rad` (the IK's
    /// solution there), kgf cm; zero without a payload.
    pub fn holding_torques_kgcm<M: Math>(
        &self,
        solver: &Solver,
        pose: &Pose,
        arm_rad: &[f32; LEGS],
    ) -> Result<[f32; LEGS], KinematicsError> {
        if !self.carried() {
            return Ok([0.0; LEGS]);
        }
        // The torques are proportional to the mass: with the mass in units of
        // 1 / N_MM_PER_KGF_CM kg they come out in kgf cm (one multiplication by a constant
        // instead of six divisions, each a library call on the RP2040).
        let [x, y, z] = self.com_mm;
        let scaled = Payload::point(
            M::mul(self.mass_g, 1.0 / (1000.0 * N_MM_PER_KGF_CM)),
            Vec3::new(x, y, z),
        );
        servo_holding_torques::<M>(solver, pose, arm_rad, &scaled)
    }

    /// Whether holding torques (kgf cm) stay within every rating: the first servo over its
    /// rating otherwise.
    pub fn within_ratings(&self, torque_kgcm: &[f32; LEGS]) -> Result<(), TorqueError> {
        for (i, (&needed, &rated)) in torque_kgcm.iter().zip(&self.torque_kgcm).enumerate() {
            // NaN needs are over any rating (their magnitude's bits are above infinity's; the
            // magnitudes of non-negative floats order like their bits).
            if positive(rated) && needed.abs().to_bits() > rated.to_bits() {
                return Err(TorqueError::Over {
                    servo: i as u8 + 1,
                    needed_kgcm: needed,
                    rated_kgcm: rated,
                });
            }
        }
        Ok(())
    }

    /// The torque check of a pose the IK accepted: `Ok` if no payload is checked, or if every
    /// servo's holding torque is within its rating.
    pub fn check<M: Math>(
        &self,
        solver: &Solver,
        pose: &Pose,
        arm_rad: &[f32; LEGS],
    ) -> Result<(), TorqueError> {
        if !self.checked() {
            return Ok(());
        }
        let torques = self
            .holding_torques_kgcm::<M>(solver, pose, arm_rad)
            .map_err(TorqueError::Unknown)?;
        self.within_ratings(&torques)
    }

    /// A rating kept to hundredths of a kgf cm (what the flash record holds): `value` rounded
    /// to the nearest hundredth (for the values the settings accept, 0..=600).
    pub fn quantise_kgcm(value: f32) -> f32 {
        if value.is_nan() || value <= 0.0 {
            return 0.0;
        }
        hundredths(value) as f32 / 100.0
    }
}

/// `x > 0.0` in integer instructions: a positive number or +infinity (not NaN, not a zero).
fn positive(x: f32) -> bool {
    let bits = x.to_bits();
    bits != 0 && bits <= f32::INFINITY.to_bits()
}

/// `value` (kgf cm, not negative) in hundredths, rounded to the nearest (saturating at the
/// `u16` range the flash record keeps).
pub fn hundredths(value: f32) -> u16 {
    // `as` saturates (and takes NaN to 0).
    (value * 100.0 + 0.5) as u16
}

/// Why a pose the IK accepts is refused for its torques.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TorqueError {
    /// A servo would need more than its rating to hold the payload there.
    Over {
        /// Servo number, 1..=6.
        servo: u8,
        /// The holding torque it would need, kgf cm (signed: positive lifts the arm).
        needed_kgcm: f32,
        /// Its rating, kgf cm.
        rated_kgcm: f32,
    },
    /// The holding torques cannot be computed there (a singular pose, an arm at dead centre):
    /// some servo would need an unbounded torque.
    Unknown(KinematicsError),
}

#[cfg(test)]
mod tests {
    use super::*;
    use kinematics_core::{Geometry, Libm};

    fn solver() -> Solver {
        Solver::new(Geometry::default()).unwrap()
    }

    #[test]
    fn no_payload_needs_no_torque_and_is_never_checked() {
        let s = solver();
        let p = PayloadSettings {
            torque_kgcm: [0.01; LEGS],
            ..PayloadSettings::default()
        };
        assert!(!p.carried() && !p.checked());
        let arm = s.arm_angles::<Libm>(&Pose::HOME).unwrap();
        assert_eq!(
            p.holding_torques_kgcm::<Libm>(&s, &Pose::HOME, &arm),
            Ok([0.0; LEGS])
        );
        assert_eq!(p.check::<Libm>(&s, &Pose::HOME, &arm), Ok(()));
    }

    #[test]
    fn a_centred_payload_at_home_loads_the_six_servos_alike() {
        let s = solver();
        let p = PayloadSettings {
            mass_g: 1200.0,
            ..PayloadSettings::default()
        };
        let arm = s.arm_angles::<Libm>(&Pose::HOME).unwrap();
        let t = p
            .holding_torques_kgcm::<Libm>(&s, &Pose::HOME, &arm)
            .unwrap();
        // 1.2 kgf shared by six rods, each nearly vertical on a 20 mm arm: about
        // 0.2 kgf x 2 cm = 0.4 kgf cm each, lifting.
        for v in t {
            assert!((v - t[0]).abs() < 1e-3 && v > 0.3 && v < 0.5, "{t:?}");
        }
        let rated = |r: f32| PayloadSettings {
            torque_kgcm: [r; LEGS],
            ..p
        };
        assert_eq!(rated(0.5).check::<Libm>(&s, &Pose::HOME, &arm), Ok(()));
        assert!(matches!(
            rated(0.3).check::<Libm>(&s, &Pose::HOME, &arm),
            Err(TorqueError::Over { servo: 1, rated_kgcm, .. }) if rated_kgcm == 0.3
        ));
    }

    #[test]
    fn positive_is_greater_than_zero_for_every_kind_of_float() {
        for x in [
            0.0f32,
            -0.0,
            1e-45,
            -1e-45,
            0.01,
            -0.01,
            600.0,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ] {
            assert_eq!(positive(x), x > 0.0, "{x}");
        }
    }

    #[test]
    fn ratings_keep_hundredths() {
        assert_eq!(PayloadSettings::quantise_kgcm(2.505), 2.51);
        assert_eq!(PayloadSettings::quantise_kgcm(0.01), 0.01);
        assert_eq!(PayloadSettings::quantise_kgcm(600.0), 600.0);
        assert_eq!(PayloadSettings::quantise_kgcm(0.0), 0.0);
        assert_eq!(PayloadSettings::quantise_kgcm(f32::NAN), 0.0);
        for c in 1..=60_000u16 {
            let v = c as f32 / 100.0;
            assert_eq!(hundredths(v), c);
            assert_eq!(PayloadSettings::quantise_kgcm(v), v);
        }
    }
}
