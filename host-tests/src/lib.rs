//! Host tests of `kinematics-core` against independent f64 references.
//!
//! - [`mod@reference`]: the f64 reference written from "The Mathematics of the Stewart
//!   Platform" (numeric arm angles, literal eq. 9,
//!   eq. 10, 12, 13, 14). Nothing there reuses the core's closed form.
//! - [`platform`]: the f64 reference for the rest (rotation centre as a chain of frames,
//!   struts, finite-difference Jacobians, an f64 Newton forward kinematics), also written
//!   from the documents and not from the core.
//! - [`fixtures`]: the geometries the tests run on, a seeded random number generator and pose
//!   samplers, shared by the test files in `tests/`.
//!
//! The tests (`cargo test -p host-tests -- --nocapture` prints the measured errors):
//! - `tests/agreement.rs`: `solve` and `arm_angles` against the numeric reference over
//!   thousands of seeded poses on seven geometries, reachability and the named leg/servo of
//!   every error, the workspace boundary, one leg probed all round its shaft;
//! - `tests/properties.rs`: proptest properties (rod closure, exact home pulses, symmetries,
//!   garbage inputs, servo limits, error naming) and eq. 1-3, 13, 14 directly;
//! - `tests/golden.rs`: the core against `golden.md` (written by `scripts/golden.py`);
//! - `tests/geometry.rs`: h0 and alpha0 against eq. 10 and 12, every `GeometryError`;
//! - `tests/rotation_centre.rs`: the IK (servos and struts) with a rotation centre against the
//!   chain of frames;
//! - `tests/jacobian.rs`: Jacobians and rates against finite differences of the f64 IK, and
//!   singular poses (never a NaN);
//! - `tests/statics.rs`: joint forces by virtual work, holding torques by the work of lifting,
//!   stiffness as the Hessian of the spring energy, the cubic configuration's orthogonality,
//!   link and arm motions along f64 trajectories, actuation with inertia by Newton-Euler;
//! - `tests/forward.rs`: IK -> FK round trips against the f64 IK, against an f64 Newton, the
//!   solution nearest the start, the errors;
//! - `tests/workspace.rs`: every reported reach along the twelve axis-directions checked with
//!   the f64 IK on both sides of its bound and all along the way; the sampled grid.

pub mod fixtures;
pub mod platform;
pub mod reference;
