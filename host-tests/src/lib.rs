//! Host tests of `kinematics-core` against independent f64 references.
//!
//! - [`reference`]: the f64 reference written from seed 001 (numeric arm angles, literal eq. 9,
//!   eq. 10, 12, 13, 14). Nothing there reuses the core's closed form.
//! - [`fixtures`]: the geometries the tests run on, a seeded random number generator and pose
//!   samplers, shared by the test files in `tests/`.

pub mod fixtures;
pub mod reference;
