//! [`KinematicsError`]: why the kinematics beyond the servo IK (legs, Jacobian, rates, statics,
//! dynamics, forward kinematics, workspace) give no answer.
//!
//! Every case names what it is about (a leg, a limit, a quantity given) with the values in the
//! units of its fields. `Display` is one short line for developers; the wording users see is
//! `control::report`'s.

use core::fmt;

use crate::ik::IkError;

/// Which input of a computation a [`KinematicsError::NonFinite`] is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Input {
    /// The platform's twist (linear and angular velocity).
    Twist,
    /// The platform's acceleration (linear and angular).
    Acceleration,
    /// A wrench (force and moment) on the platform.
    Wrench,
    /// The joint rates (leg length rates or arm angular rates).
    JointRates,
    /// The joint values of leg `leg` (1..=6): a length, an arm angle or a pulse.
    Joint {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// The stiffness of leg `leg` (1..=6).
    Stiffness {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// The payload (mass, centre of mass, inertia).
    Payload,
}

impl fmt::Display for Input {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Input::Twist => f.write_str("twist"),
            Input::Acceleration => f.write_str("acceleration"),
            Input::Wrench => f.write_str("wrench"),
            Input::JointRates => f.write_str("joint rates"),
            Input::Joint { leg } => write!(f, "joint value of leg {leg}"),
            Input::Stiffness { leg } => write!(f, "stiffness of leg {leg}"),
            Input::Payload => f.write_str("payload"),
        }
    }
}

/// Why a kinematic quantity cannot be computed at a pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum KinematicsError {
    /// The pose is not usable (non-finite, angle too large), or for a servo platform a leg
    /// cannot reach or a servo would leave its limits: the IK's own error.
    Ik(IkError),
    /// A strut would be longer or shorter than its stroke allows.
    Stroke {
        /// Leg number, 1..=6.
        leg: u8,
        /// The length the pose needs, mm.
        length_mm: f32,
        /// The strut's shortest length, mm.
        min_mm: f32,
        /// The strut's longest length, mm.
        max_mm: f32,
    },
    /// A strut of (nearly) zero length: its direction, and so the Jacobian, is undefined.
    ZeroLength {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// A servo arm at dead centre: its rod is square to the arm tip's path, so the arm cannot
    /// move the rod (`d alpha / d pose` is unbounded). This is the leg's workspace boundary.
    DeadCentre {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// The forward kinematics closed leg `leg`'s rod with its arm at the angle asked for, but
    /// there the IK puts the arm on eq. 9's other root (the elbow folded through the rod): not
    /// a pose this servo platform takes.
    ElbowFlipped {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// The Jacobian (or stiffness) is singular or too nearly so to be inverted in `f32`: the
    /// platform is at or next to a singular pose.
    Singular {
        /// The smallest pivot of the elimination relative to its column's largest entry (0 if
        /// one vanished): below [`crate::linalg::PIVOT_TOLERANCE`].
        pivot_ratio: f32,
    },
    /// Pitch at +-90 degrees: roll and yaw rates are undefined (gimbal lock of the Euler
    /// angles of eq. 1).
    GimbalLock {
        /// The pitch, rad.
        pitch_rad: f32,
    },
    /// The forward kinematics did not converge within the iterations allowed.
    NotConverged {
        /// Iterations made.
        iterations: u8,
        /// The largest joint residual left, in the joint's unit (mm for struts, rad for
        /// servo arms).
        residual: f32,
    },
    /// An input is NaN or infinite.
    NonFinite {
        /// Which input.
        input: Input,
    },
}

impl From<IkError> for KinematicsError {
    fn from(e: IkError) -> Self {
        KinematicsError::Ik(e)
    }
}

impl fmt::Display for KinematicsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            KinematicsError::Ik(e) => e.fmt(f),
            KinematicsError::Stroke {
                leg,
                length_mm,
                min_mm,
                max_mm,
            } => write!(
                f,
                "leg {leg}: length {length_mm} mm outside its stroke {min_mm}..={max_mm} mm"
            ),
            KinematicsError::ZeroLength { leg } => write!(f, "leg {leg}: zero length"),
            KinematicsError::DeadCentre { leg } => write!(f, "leg {leg}: arm at dead centre"),
            KinematicsError::ElbowFlipped { leg } => {
                write!(f, "leg {leg}: the pose needs the arm on eq. 9's other root")
            }
            KinematicsError::Singular { pivot_ratio } => {
                write!(f, "singular Jacobian (pivot ratio {pivot_ratio:e})")
            }
            KinematicsError::GimbalLock { pitch_rad } => {
                write!(f, "pitch {pitch_rad} rad: Euler angles at gimbal lock")
            }
            KinematicsError::NotConverged {
                iterations,
                residual,
            } => write!(
                f,
                "no convergence in {iterations} iterations (residual {residual:e})"
            ),
            KinematicsError::NonFinite { input } => write!(f, "non-finite {input}"),
        }
    }
}

impl core::error::Error for KinematicsError {}
