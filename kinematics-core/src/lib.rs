//! The kinematics of six-legged Stewart platforms ("hexapods"), `no_std`, `f32`, no allocation:
//! RC-servo platforms (the firmware's) and platforms of linear struts.
//!
//! The servo IK follows "The Mathematics of the Stewart Platform" (a rotary RC-servo platform);
//! equation numbers in comments are that document's. The configurations, frames, struts,
//! Jacobian, stiffness and approximate forward kinematics follow the Stewart platform Simscape
//! model documentation (cited by function name), link motions and actuation the ROBOOP
//! `LinkStewart` class reference, statics the report on a force applied at the centre of a
//! Stewart platform, and the forward kinematics the lesson of the planar 3-RPR forward
//! kinematics project. The servo IK's data flows one way:
//!
//! [`Pose`] (mm, rad) -> rotation `R` (eq. 1) -> platform joints `q_i` and leg vectors `l_i`
//! (eq. 2, 3) -> servo arm angles `alpha_i` (eq. 9) -> pulse widths `W_i` (eq. 13, 14).
//!
//! - [`geometry`]: where the servos and rod joints are; derived home height `h0` (eq. 10).
//! - [`configuration`]: the anchors of either kind of leg, the frames and the rotation centre a
//!   pose turns the platform about; the general and cubic configuration generators.
//! - [`pose`]: the platform pose and its rotation matrix.
//! - [`servo`]: per-servo pulse mapping (home pulse, rate, direction, limits).
//! - [`ik`]: pose -> arm angles -> pulse widths, all-or-nothing with errors naming the leg/servo;
//!   an [`ik::Solver`] is the IK of one geometry: it owns it (and its rotation centre), derives
//!   the home arm angles `alpha0` (eq. 12) and holds what it computes once per geometry: a
//!   float table for every build, and a fixed-point table exactly where the build takes that
//!   path (`Option`).
//! - [`legs`]: the legs at a pose: linear [`legs::Struts`] (lengths, unit vectors, strokes) and
//!   servo arms ([`legs::ArmState`]).
//! - [`jacobian`]: joint rates per unit twist, condition number, Euler-angle rates; the
//!   [`jacobian::Actuators`] trait both kinds of leg implement (joint values and Jacobian),
//!   which the modules below take.
//! - [`rates`]: joint rates from a twist and back, servo speed limits.
//! - [`statics`]: joint forces for a wrench, holding torques of a payload, stiffness, compliance.
//! - [`dynamics`]: link and arm motions along a trajectory, actuation with inertia.
//! - [`forward`]: forward kinematics, approximate and by Newton's method, a step at a time.
//! - [`workspace`]: the reach along each axis, a test at a time, and sampled grids.
//! - [`linalg`]: the 6x6 linear algebra; [`error`]: [`KinematicsError`].
//! - [`types`]: [`LEGS`], [`Vec3`], [`Mat3`]: a leaf every module imports (this root only
//!   re-exports; no module imports it).
//! - [`math`]: the few transcendental functions the kinematics need, behind a trait so the
//!   firmware can supply the RP2040 boot ROM's fast routines while the host uses `libm`; and
//!   their fixed-point forms for the IK's hot loop (by default [`fixed`]'s, the same bits
//!   everywhere).
//! - [`fixed`]: the fixed-point arithmetic of the IK's hot loop (integer instructions for a chip
//!   without an FPU): its sine and cosine, square root and arc tangent, each with its method
//!   and error bound (the defaults of [`Math`]'s fixed-point functions).
//!
//! Lengths are mm, angles rad, forces N, moments and servo torques N mm, masses kg, unless a
//! name says otherwise. Legs and servos are numbered 1..=6 in everything a user sees (errors,
//! reports) and indexed 0..=5 in arrays. Leg `i` is driven by servo `i`.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

pub mod configuration;
pub mod dynamics;
pub mod error;
pub mod fixed;
pub mod forward;
pub mod geometry;
pub mod ik;
pub mod jacobian;
pub mod legs;
pub mod linalg;
pub mod math;
pub mod pose;
pub mod rates;
pub mod servo;
pub mod statics;
pub mod types;
pub mod workspace;

pub use error::KinematicsError;
pub use geometry::{Geometry, GeometryError, Leg};
pub use ik::{IkError, Solution, Solver};
pub use math::{FloatRoutines, Libm, Math};
pub use pose::Pose;
pub use servo::{Direction, ServoConfig, ServoError, ServoSet};
pub use types::{Mat3, Vec3, LEGS};

/// Helpers shared by the unit tests.
#[cfg(test)]
mod test_support {
    /// The next number of a xorshift32 sequence (seeded, reproducible test inputs).
    pub(crate) fn xorshift(seed: &mut u32) -> u32 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 17;
        *seed ^= *seed << 5;
        *seed
    }

    /// Seeded numbers in -`scale`..`scale` (uniform, from [`xorshift`]), one per call.
    pub(crate) fn uniform(mut seed: u32) -> impl FnMut(f32) -> f32 {
        move |scale| (xorshift(&mut seed) as f32 / u32::MAX as f32 * 2.0 - 1.0) * scale
    }
}
