//! How numbers, poses and setting values are written: poses in mm and degrees with 3 decimals,
//! arm angles in degrees with 3 decimals, pulse widths in microseconds with 2 decimals, and
//! never a `-0.000`.

use core::fmt::{self, Display, Formatter, Write};

use kinematics_core::pose::Axis;
use kinematics_core::{Direction, Pose, Vec3, LEGS};

use crate::settings::{Kind, SettingId, SettingValue};

/// A number with a fixed count of decimals, never shown as `-0.000`.
#[derive(Debug, Clone, Copy)]
pub struct Fixed(pub f32, pub usize);

impl Display for Fixed {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        let Fixed(value, decimals) = *self;
        // Values that round to zero print as an unsigned zero.
        const HALF_STEP: [f32; 7] = [0.5, 0.05, 5e-3, 5e-4, 5e-5, 5e-6, 5e-7];
        let half_step = HALF_STEP.get(decimals).copied().unwrap_or(0.0);
        let value = if value.abs() < half_step { 0.0 } else { value };
        write!(f, "{value:.decimals$}")
    }
}

/// Six values in servo order with a fixed number of decimals, separated by spaces.
pub struct Six<'a>(pub &'a [f32; LEGS], pub usize);

impl Display for Six<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        for (i, v) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_char(' ')?;
            }
            Fixed(*v, self.1).fmt(f)?;
        }
        Ok(())
    }
}

/// A pose in user units: `x=.. y=.. z=.. roll=.. pitch=.. yaw=..` (mm, degrees, 3 decimals).
pub struct PoseText<'a>(pub &'a Pose);

impl Display for PoseText<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        for (i, axis) in Axis::ALL.into_iter().enumerate() {
            let v = self.0.get(axis);
            let v = if axis.is_angle() { v.to_degrees() } else { v };
            if i > 0 {
                f.write_char(' ')?;
            }
            write!(f, "{}={}", axis.name(), Fixed(v, 3))?;
        }
        Ok(())
    }
}

/// A vector as `(x, y, z)` with 3 decimals.
pub struct Vector<'a>(pub &'a Vec3);

impl Display for Vector<'_> {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "({}, {}, {})",
            Fixed(self.0.x, 3),
            Fixed(self.0.y, 3),
            Fixed(self.0.z, 3)
        )
    }
}

/// Six angles, rad -> degrees.
pub fn degrees(angles_rad: &[f32; LEGS]) -> [f32; LEGS] {
    angles_rad.map(f32::to_degrees)
}

/// A setting's value as `config` shows it and `set` accepts it.
pub struct ValueText(pub SettingId, pub SettingValue);

impl Display for ValueText {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match (self.0.kind(), self.1) {
            (_, SettingValue::Flag(on)) => f.write_str(if on { "on" } else { "off" }),
            (_, SettingValue::Dir(Direction::Normal)) => f.write_str("normal"),
            (_, SettingValue::Dir(Direction::Reversed)) => f.write_str("reversed"),
            (_, SettingValue::Whole(v)) => write!(f, "{v}"),
            (
                Kind::Number {
                    off_allowed: true, ..
                },
                SettingValue::Number(0.0),
            ) => f.write_str("off"),
            (Kind::Number { decimals, .. }, SettingValue::Number(v)) => {
                Fixed(v, usize::from(decimals)).fmt(f)
            }
            (_, SettingValue::Number(v)) => write!(f, "{v}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_never_prints_negative_zero() {
        assert_eq!(std::format!("{}", Fixed(-0.0001, 3)), "0.000");
        assert_eq!(std::format!("{}", Fixed(-0.0, 2)), "0.00");
        assert_eq!(std::format!("{}", Fixed(-0.0006, 3)), "-0.001");
        assert_eq!(std::format!("{}", Fixed(1500.0, 2)), "1500.00");
    }

    #[test]
    fn pose_text_is_in_user_units() {
        let p = Pose::from_degrees(1.0, -2.5, 3.0, 10.0, 0.0, -45.0);
        assert_eq!(
            std::format!("{}", PoseText(&p)),
            "x=1.000 y=-2.500 z=3.000 roll=10.000 pitch=0.000 yaw=-45.000"
        );
    }
}
