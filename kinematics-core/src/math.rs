//! The transcendental functions the IK needs, behind a trait.
//!
//! The core is generic over [`Math`] so that the same algorithm runs with `libm` on the host (and
//! in host tests) and with the RP2040 boot ROM's faster float routines in the firmware. All
//! angles are in radians.

/// Scalar functions used by the kinematics. Implementations must return NaN (never panic) for
/// inputs outside their domain; callers check results for finiteness.
pub trait Math {
    /// `(sin x, cos x)`. Callers keep `|x| <= 2*pi` (the ROM routines need `|x| < 128`).
    fn sin_cos(x: f32) -> (f32, f32);
    /// Square root; NaN for negative input.
    fn sqrt(x: f32) -> f32;
    /// Four-quadrant arc tangent of `y / x`, in `(-pi, pi]`.
    fn atan2(y: f32, x: f32) -> f32;
}

/// [`Math`] backed by the portable `libm` crate (correctly rounded or nearly so).
#[derive(Debug, Clone, Copy, Default)]
pub struct Libm;

impl Math for Libm {
    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        libm::sincosf(x)
    }

    #[inline]
    fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }

    #[inline]
    fn atan2(y: f32, x: f32) -> f32 {
        libm::atan2f(y, x)
    }
}
