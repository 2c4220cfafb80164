//! Statics: the joint forces for a wrench on the platform, the holding load of every actuator
//! for a payload, stiffness, compliance and the displacement under a load.
//!
//! Units: forces in N, moments and servo torques in N mm, lengths in mm, masses in kg; gravity
//! is [`GRAVITY_MM_S2`] along -z of the base frame. A wrench is taken about the rotation
//! centre `C`, in base axes, like the twist of [`crate::jacobian`].
//!
//! Joint forces `f` (N along each strut, positive pushing the platform away from the base; or
//! N mm on each servo arm, positive turning it towards larger `alpha`) apply the wrench
//! `w = J^T f` to the platform: by virtual work, `f . dL = w . dX` for every small motion `dX`
//! and the joint motions `dL = J dX` it makes. So `f = J^-T w` (the report on a force applied
//! at the centre of a Stewart platform: the load reaches the legs through the Jacobian's
//! transpose). Legs and rods are taken as massless two-force members, joints frictionless.
//!
//! Stiffness (the Stewart platform Simscape model documentation, `computeJacobian`):
//! joint stiffnesses `k_i` (N/mm for struts, N mm/rad for servos) give the platform the
//! stiffness `K = J^T diag(k) J` (a small motion `dX` from equilibrium meets the restoring
//! wrench `-K dX`) and the compliance `C = K^-1`; a wrench `w` then moves the platform by
//! `dX = C w` (translation of `C` in mm, rotation vector in rad).

use core::marker::PhantomData;

use crate::configuration::Placement;
use crate::error::{Input, KinematicsError};
use crate::fixed::{from_fixed32, ROT_FRAC};
use crate::ik::Solver;
use crate::jacobian::{Actuators, Jacobian, DEAD_CENTRE_TOLERANCE};
use crate::legs::ArmState;
use crate::linalg::{Lu6, Mat6, Vec6};
use crate::math::{abs_bits, cross, dot, forward_math, lt, mul_mat_vec, Math, Real};
use crate::pose::Pose;
use crate::types::{Mat3, Vec3, LEGS};

/// Standard gravity, mm/s^2, along -z of the base frame.
pub const GRAVITY_MM_S2: f32 = 9_806.65;
/// N mm in one kgf cm (the unit hobby servo torques are rated in).
pub const N_MM_PER_KGF_CM: f32 = 98.066_5;

/// A force and a moment on the platform, about the rotation centre, base axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wrench {
    /// Force, N.
    pub force_n: Vec3,
    /// Moment about the rotation centre, N mm.
    pub moment_n_mm: Vec3,
}

impl Wrench {
    /// The wrench of a force `force_n` (N) acting at `point_mm` (base frame): moment
    /// `(point - C) x F` about the rotation centre `C` of `placement`.
    pub fn force_at(placement: &Placement, point_mm: Vec3, force_n: Vec3) -> Wrench {
        Wrench {
            force_n,
            moment_n_mm: (point_mm - placement.centre_mm).cross(&force_n),
        }
    }

    /// `(F_x, F_y, F_z, M_x, M_y, M_z)`: the order that pairs with a twist's.
    pub fn to_vec6(&self) -> Vec6 {
        let (f, m) = (self.force_n, self.moment_n_mm);
        Vec6::new(f.x, f.y, f.z, m.x, m.y, m.z)
    }

    /// The wrench of a 6-vector `(F, M)`.
    pub fn from_vec6(v: &Vec6) -> Wrench {
        Wrench {
            force_n: Vec3::new(v[0], v[1], v[2]),
            moment_n_mm: Vec3::new(v[3], v[4], v[5]),
        }
    }

    fn check(&self) -> Result<(), KinematicsError> {
        if self.to_vec6().iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(KinematicsError::NonFinite {
                input: Input::Wrench,
            })
        }
    }
}

/// A load carried by the platform: a rigid body fixed to it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Payload {
    /// Mass, kg (the platform plate's own may be included).
    pub mass_kg: f32,
    /// Centre of mass, platform frame, mm.
    pub centre_of_mass_mm: Vec3,
    /// Inertia tensor about the centre of mass, platform axes, kg mm^2 (zero for a point mass;
    /// only the dynamics use it).
    pub inertia_kg_mm2: Mat3,
}

impl Payload {
    /// A point mass `mass_kg` at `centre_of_mass_mm` (platform frame).
    pub fn point(mass_kg: f32, centre_of_mass_mm: Vec3) -> Payload {
        Payload {
            mass_kg,
            centre_of_mass_mm,
            inertia_kg_mm2: Mat3::zeros(),
        }
    }

    /// Refuses NaN or infinite numbers and a negative mass.
    pub fn check(&self) -> Result<(), KinematicsError> {
        let finite = self.mass_kg.is_finite()
            && self.mass_kg >= 0.0
            && self.centre_of_mass_mm.iter().all(|v| v.is_finite())
            && self.inertia_kg_mm2.iter().all(|v| v.is_finite());
        if finite {
            Ok(())
        } else {
            Err(KinematicsError::NonFinite {
                input: Input::Payload,
            })
        }
    }

    /// Where the centre of mass is, base frame, mm.
    pub fn centre_of_mass_at<M: Math>(&self, placement: &Placement, centre_mm: Vec3) -> Vec3 {
        let lever = mul_mat_vec::<M>(&placement.rotation, self.centre_of_mass_mm - centre_mm);
        placement.centre_mm + lever
    }

    /// The wrench gravity puts on the platform through this payload, about the rotation centre
    /// of `placement` (`centre_mm`: the rotation centre in the platform frame).
    pub fn gravity_wrench<M: Math>(&self, placement: &Placement, centre_mm: Vec3) -> Wrench {
        let weight_n = Vec3::new(0.0, 0.0, -self.mass_kg * GRAVITY_MM_S2 * 1e-3);
        Wrench::force_at(
            placement,
            self.centre_of_mass_at::<M>(placement, centre_mm),
            weight_n,
        )
    }
}

/// The joint forces that apply `wrench` to the platform at `pose`: `f = J^-T w` (N per strut,
/// N mm per servo arm; see the module docs for signs). Refused near a singular pose.
pub fn joint_forces<M: Math, A: Actuators>(
    actuators: &A,
    pose: &Pose,
    wrench: &Wrench,
) -> Result<[f32; LEGS], KinematicsError> {
    wrench.check()?;
    let j = actuators.linearise::<M>(pose)?.jacobian;
    joint_forces_for::<M>(&j, wrench)
}

/// [`joint_forces`] with a Jacobian already at hand.
pub fn joint_forces_for<M: Math>(
    jacobian: &Jacobian,
    wrench: &Wrench,
) -> Result<[f32; LEGS], KinematicsError> {
    wrench.check()?;
    let lu = jacobian.factor::<M>()?;
    Ok(lu.solve_transposed::<M>(&wrench.to_vec6()).into())
}

/// What each actuator must exert to hold `payload` still at `pose` against gravity: the joint
/// forces that cancel its weight's wrench (N per strut; N mm per servo arm, positive lifting
/// the arm; divide by [`N_MM_PER_KGF_CM`] for kgf cm). Compare their magnitudes with the
/// actuators' ratings.
pub fn holding_loads<M: Math, A: Actuators>(
    actuators: &A,
    pose: &Pose,
    payload: &Payload,
) -> Result<[f32; LEGS], KinematicsError> {
    payload.check()?;
    let centre_mm = actuators.anchors().rotation_centre_mm;
    let linear = actuators.linearise::<M>(pose)?;
    let weight = payload.gravity_wrench::<M>(&linear.placement, centre_mm);
    let hold = Wrench {
        force_n: -weight.force_n,
        moment_n_mm: -weight.moment_n_mm,
    };
    joint_forces_for::<M>(&linear.jacobian, &hold)
}

/// [`holding_loads`] for a servo platform whose arm angles at `pose` are at hand (the IK's
/// `Solution::arm_rad`, solved anyway to drive the servos): the same torques (N mm) without
/// solving the IK again. What a firmware checks for every pose it may drive with a payload
/// and torque ratings, so it takes the servo Jacobian's structure rather than the matrix:
///
/// row `i` of `J` is `g_i^T / (d_i . t_i)` with `g_i = [d_i, r_i x d_i]` (see
/// [`crate::jacobian`]), so `J^T tau = w` is `G^T u = w` with `u_i = tau_i / (d_i . t_i)`:
/// the six rods' "forces" `u_i d_i`, whose sum holds the payload's force and whose moments
/// about `C` hold its moment. `G` (rows `g_i`) is factored and `G^T u = w` solved, then
/// `tau_i = (d_i . t_i) u_i`: no row is divided (six divisions and 36 multiplications
/// fewer than `J`). The hold, `-w` of the weight `W = m g` at the centre of mass' lever
/// `l = R (com - c)`, is `(0, 0, W, W l_y, -W l_x, 0)` (the cross product with a vertical
/// force written out). Refused where [`Jacobian::of_arms`] and [`joint_forces_for`] refuse:
/// an arm at dead centre ([`crate::jacobian::DEAD_CENTRE_TOLERANCE`]), a singular pose (each
/// pivot measured against its column of `G` instead of `J`'s).
pub fn servo_holding_torques<M: Math>(
    solver: &Solver,
    pose: &Pose,
    arm_rad: &[f32; LEGS],
    payload: &Payload,
) -> Result<[f32; LEGS], KinematicsError> {
    let r = Real::<M>::new;
    payload.check()?;
    crate::ik::check_pose(pose)?;
    let geometry = solver.geometry();
    let state = ArmState::at_angles::<FixedSines<M>>(solver, pose, *arm_rad);
    let threshold = (r(DEAD_CENTRE_TOLERANCE) * r(geometry.rod_mm()) * r(geometry.arm_mm())).0;
    // `G`: row `i` is `g_i` (rows are legs, as in `J`: each column's pivot is chosen among
    // entries of one unit, mm or mm^2).
    let mut g = Mat6::zeros();
    let mut along = [0.0f32; LEGS];
    for i in 0..LEGS {
        let d = state.rods_mm[i];
        along[i] = dot::<M>(d, state.tip_rates_mm[i]);
        if !lt(threshold, along[i].abs()) {
            return Err(KinematicsError::DeadCentre { leg: i as u8 + 1 });
        }
        let moment = cross::<M>(state.placement.levers_mm[i], d);
        for k in 0..3 {
            g[(i, k)] = d[k];
            g[(i, k + 3)] = moment[k];
        }
    }
    let c = solver.rotation_centre_mm();
    let com = payload.centre_of_mass_mm;
    let lever = mul_mat_vec::<M>(
        &state.placement.rotation,
        Vec3::new(
            (r(com.x) - r(c.x)).0,
            (r(com.y) - r(c.y)).0,
            (r(com.z) - r(c.z)).0,
        ),
    );
    let weight_n = r(payload.mass_kg) * r(GRAVITY_MM_S2 * 1e-3);
    let hold = Vec6::new(
        0.0,
        0.0,
        weight_n.0,
        (weight_n * r(lever.y)).0,
        (-(weight_n * r(lever.x))).0,
        0.0,
    );
    let u = Lu6::factor::<M>(&g)?.solve_transposed::<M>(&hold);
    Ok(core::array::from_fn(|i| (r(along[i]) * r(u[i])).0))
}

/// `M` with the core's integer sine and cosine ([`Math::sin_cos_fixed`]: within 2^-29, the same
/// bits on every machine), each rounded once to `f32`, in place of `M::sin_cos`, for the nine
/// sines and cosines of a holding-torque check (the pose's three angles, the six arms'): on the
/// RP2040 about half the cost of the boot ROM's `fsin` and as accurate. `M`'s own beyond
/// `|x| < 4` rad (which the checked pose and the IK's arm angles never reach).
struct FixedSines<M>(PhantomData<M>);

impl<M: Math> Math for FixedSines<M> {
    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        if abs_bits(x) < 4.0f32.to_bits() {
            let (s, c) = M::sin_cos_fixed(x);
            (from_fixed32(s, ROT_FRAC), from_fixed32(c, ROT_FRAC))
        } else {
            M::sin_cos(x)
        }
    }

    forward_math!(M => sqrt, atan2, add, sub, mul, sin_cos_fixed, sqrt_fixed, atan2_fixed);
}

/// The platform's stiffness `K = J^T diag(k) J` for joint stiffnesses `k` (N/mm for struts,
/// N mm/rad for servo arms). Units of `K`: N/mm, N/rad, N mm/mm, N mm/rad by block.
pub fn stiffness(jacobian: &Jacobian, k: &[f32; LEGS]) -> Result<Mat6, KinematicsError> {
    for (i, k) in k.iter().enumerate() {
        if !(k.is_finite() && *k >= 0.0) {
            return Err(KinematicsError::NonFinite {
                input: Input::Stiffness { leg: i as u8 + 1 },
            });
        }
    }
    let j = &jacobian.matrix;
    let mut kj = *j;
    for (i, k) in k.iter().enumerate() {
        let row = kj.row(i) * *k;
        kj.set_row(i, &row);
    }
    Ok(j.transpose() * kj)
}

/// The compliance `C = K^-1`; refused if `K` is singular (some motion meets no stiffness).
pub fn compliance<M: Math>(stiffness: &Mat6) -> Result<Mat6, KinematicsError> {
    Ok(Lu6::factor::<M>(stiffness)?.inverse::<M>())
}

/// A small displacement of the platform: the translation of the rotation centre and a
/// rotation vector (axis times angle), base axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Displacement {
    /// Translation of the rotation centre, mm.
    pub translation_mm: Vec3,
    /// Rotation vector, rad.
    pub rotation_rad: Vec3,
}

impl Displacement {
    /// The displacement of a 6-vector `(translation, rotation)`.
    pub fn from_vec6(v: &Vec6) -> Displacement {
        Displacement {
            translation_mm: Vec3::new(v[0], v[1], v[2]),
            rotation_rad: Vec3::new(v[3], v[4], v[5]),
        }
    }
}

/// How far `wrench` moves the platform at `pose` when its joints have stiffnesses `k`:
/// `dX = K^-1 w` (small displacements).
pub fn displacement<M: Math, A: Actuators>(
    actuators: &A,
    pose: &Pose,
    k: &[f32; LEGS],
    wrench: &Wrench,
) -> Result<Displacement, KinematicsError> {
    wrench.check()?;
    let j = actuators.linearise::<M>(pose)?.jacobian;
    let lu = Lu6::factor::<M>(&stiffness(&j, k)?)?;
    Ok(Displacement::from_vec6(&lu.solve::<M>(&wrench.to_vec6())))
}

/// The case of the report on a force applied at the centre of a Stewart platform: the
/// displacement under `force_n` (N) applied at the platform's centre (the platform frame's
/// origin), with joint stiffnesses `k`.
pub fn displacement_under_central_force<M: Math, A: Actuators>(
    actuators: &A,
    pose: &Pose,
    k: &[f32; LEGS],
    force_n: Vec3,
) -> Result<Displacement, KinematicsError> {
    let centre_mm = actuators.anchors().rotation_centre_mm;
    let linear = actuators.linearise::<M>(pose)?;
    // The platform frame's origin is at C + R (0 - c).
    let lever = mul_mat_vec::<M>(&linear.placement.rotation, -centre_mm);
    let wrench = Wrench {
        force_n,
        moment_n_mm: cross::<M>(lever, force_n),
    };
    wrench.check()?;
    let lu = Lu6::factor::<M>(&stiffness(&linear.jacobian, k)?)?;
    Ok(Displacement::from_vec6(&lu.solve::<M>(&wrench.to_vec6())))
}
