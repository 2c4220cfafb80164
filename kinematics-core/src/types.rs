//! The shapes every module of the kinematics shares: the number of legs and the vector and
//! matrix types (mm in the base or platform frame, as each value's name says).
//!
//! A leaf: it imports nothing of this crate, so any module may import it (the crate root
//! re-exports these for other crates, and imports every module itself).

/// Number of legs (and servos) of a Stewart platform.
pub const LEGS: usize = 6;

/// A 3-vector in millimetres (base or platform frame, as the name of the value says).
pub type Vec3 = nalgebra::Vector3<f32>;
/// A 3x3 rotation matrix.
pub type Mat3 = nalgebra::Matrix3<f32>;
