//! [`Math`] for the RP2040: the boot ROM's float routines (`fsin`, `fcos`, `fsqrt`, `fatan2`).
//!
//! The M0+ has no FPU; `libm`'s `sinf`/`cosf` compute in f64 and cost thousands of cycles per
//! call, while the ROM routines are accurate to about 1e-7 and several times faster. The ROM
//! wants `|x| < 128` rad for sin/cos (the kinematics keeps angles within `2 pi`) and needs
//! boot ROM version 2 or later for `fatan2` (every RP2040 sold as B1 or later; B0 was never on
//! a Pico). All angles in radians.

use kinematics_core::Math;
use rp2040_hal::rom_data::float_funcs;

/// The boot ROM's float library.
#[derive(Debug, Clone, Copy, Default)]
pub struct RomMath;

impl Math for RomMath {
    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        if x.is_finite() && x.abs() < 128.0 {
            (float_funcs::fsin(x), float_funcs::fcos(x))
        } else {
            (f32::NAN, f32::NAN)
        }
    }

    #[inline]
    fn sqrt(x: f32) -> f32 {
        // The ROM returns -inf for negative input; the trait promises NaN.
        if x >= 0.0 {
            float_funcs::fsqrt(x)
        } else {
            f32::NAN
        }
    }

    #[inline]
    fn atan2(y: f32, x: f32) -> f32 {
        float_funcs::fatan2(y, x)
    }
}
