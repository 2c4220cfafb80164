//! The Jacobians (struts: the Simscape documentation's `computeJacobian`; servo arms: the
//! differentiated rod closure) and the rates built on them, against central finite
//! differences of the f64 reference's IK; and what happens at and near singular poses. Run
//! with `--nocapture` to see the measured errors.

// Legs are numbered; index loops over them read like the equations.
#![allow(clippy::needless_range_loop)]

use host_tests::fixtures::{cases, solver_about, strut_cases, Rng, CENTRES_MM};
use host_tests::platform::{fd_jacobian, moved, RefAnchors, RefArms, M6};
use host_tests::reference::{mat_mul, transpose, RefPose};
use kinematics_core::jacobian::Jacobian;
use kinematics_core::legs::ArmState;
use kinematics_core::linalg::Vec6;
use kinematics_core::rates::{joint_rates, twist_from_joint_rates, Twist};
use kinematics_core::{ik, KinematicsError, Libm, Pose, Vec3, LEGS};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

/// Finite-difference steps: small enough that the truncation error (`h^2` times third
/// derivatives of order 1e-4 per mm^2) is below 1e-9, large enough that the f64 rounding
/// (1e-16 / h) is too.
const H_MM: f64 = 1e-3;
const H_RAD: f64 = 1e-5;

/// Largest difference between the core's `J` and the finite differences, relative to the
/// largest entry of the row (with the angular columns divided by the lever scale, so all
/// entries have the same unit): a few `f32` roundings of the anchors and of the products.
/// Measured: up to 3.6e-7.
const STRUT_REL_TOL: f64 = 2e-6;
/// The same for servo arms away from dead centre: the row is divided by `d . t`, which loses
/// digits to cancellation as the arm approaches dead centre; poses with every leg at least
/// [`SERVO_MARGIN_MM`] inside its workspace. Measured: up to 8.7e-6 (a shaft off the base
/// plane, a centre 118 mm below the platform).
const SERVO_REL_TOL: f64 = 5e-5;
const SERVO_MARGIN_MM: f64 = 1.0;

/// `max |core - fd| / max |row|` per row, angular columns scaled by `1/lever` (so that both
/// halves of a row are per mm of motion of the farthest joint).
fn row_errors(core: &Jacobian, fd: &M6) -> f64 {
    let scale = f64::from(core.lever_scale_mm);
    let mut worst = 0.0f64;
    for i in 0..LEGS {
        let unit = |k: usize| if k < 3 { 1.0 } else { 1.0 / scale };
        let row_max = (0..6)
            .map(|k| (fd[i][k] * unit(k)).abs())
            .fold(0.0, f64::max);
        let d = (0..6)
            .map(|k| ((f64::from(core.matrix[(i, k)]) - fd[i][k]) * unit(k)).abs())
            .fold(0.0, f64::max);
        worst = worst.max(d / row_max);
    }
    worst
}

#[test]
fn strut_jacobian_matches_finite_differences_of_the_lengths() {
    eprintln!();
    for case in strut_cases() {
        let reference = RefAnchors::from_core(&case.struts.anchors());
        let mut rng = Rng::new(21);
        let mut worst = 0.0f64;
        for _ in 0..500 {
            let pose = rng.pose(&case.range);
            let j = Jacobian::at::<Libm, _>(&case.struts, &pose).expect("a Jacobian");
            let fd = fd_jacobian(
                |p| Some(reference.strut_lengths(p)),
                &RefPose::from_core(&pose),
                H_MM,
                H_RAD,
            )
            .expect("lengths everywhere");
            let e = row_errors(&j, &fd);
            worst = worst.max(e);
            assert!(
                e <= STRUT_REL_TOL,
                "{} {pose:?}: {e:e}\n{}",
                case.name,
                j.matrix
            );
        }
        eprintln!(
            "{:<46} strut J vs f64 FD: {worst:.1e} (relative)",
            case.name
        );
    }
}

#[test]
fn servo_jacobian_matches_finite_differences_of_the_arm_angles() {
    eprintln!();
    for case in cases() {
        for c in CENTRES_MM {
            let solver = solver_about(case.geometry.clone(), Vec3::from(c));
            let reference = RefArms::from_solver(&solver);
            let mut rng = Rng::new(23);
            let (mut tested, mut worst) = (0, 0.0f64);
            for _ in 0..400 {
                let pose = rng.pose(&case.range);
                let exact = RefPose::from_core(&pose);
                let margins = reference.margins_mm(&exact);
                if margins.iter().any(|m| *m < SERVO_MARGIN_MM) {
                    continue;
                }
                let j = Jacobian::at::<Libm, _>(&solver, &pose).expect("inside the workspace");
                let fd = fd_jacobian(|p| reference.arm_angles(p), &exact, H_MM, H_RAD)
                    .expect("inside the workspace");
                let e = row_errors(&j, &fd);
                worst = worst.max(e);
                tested += 1;
                assert!(
                    e <= SERVO_REL_TOL,
                    "{} c={c:?} {pose:?}: {e:e}\ncore {}\nfd {fd:?}",
                    case.name,
                    j.matrix
                );
            }
            assert!(tested > 100, "{}: {tested}", case.name);
            eprintln!(
                "{:<46} c={:<18} servo J vs f64 FD: {worst:.1e} (relative), {tested} poses",
                case.name,
                format!("{c:?}")
            );
        }
    }
}

/// The joint rates of a twist are the rates at which the f64 IK's joint values change along
/// that motion (finite differences along the twist), and the twist back from those rates is
/// the twist.
#[test]
fn rates_follow_the_motion_and_invert() {
    let solver = solver_about(cases()[0].geometry.clone(), Vec3::new(0.0, 0.0, 30.0));
    let reference = RefArms::from_solver(&solver);
    let mut rng = Rng::new(29);
    let mut worst = 0.0f64;
    for _ in 0..300 {
        let pose = rng.pose(&cases()[0].range);
        let exact = RefPose::from_core(&pose);
        if reference
            .margins_mm(&exact)
            .iter()
            .any(|m| *m < SERVO_MARGIN_MM)
        {
            continue;
        }
        let twist = Twist {
            linear_mm_s: Vec3::new(rng.symmetric(40.0) as f32, rng.symmetric(40.0) as f32, 0.0)
                + Vec3::new(0.0, 0.0, rng.symmetric(30.0) as f32),
            angular_rad_s: rng.vec3([0.5, 0.5, 1.0]),
        };
        let rates = joint_rates::<Libm, _>(&solver, &pose, &twist).unwrap();
        let dt = 1e-5;
        let step = |s: f64| {
            let t = twist.to_vec6();
            let dx: [f64; 6] = core::array::from_fn(|k| s * dt * f64::from(t[k]));
            reference.arm_angles(&moved(&exact, &dx)).unwrap()
        };
        let (plus, minus) = (step(1.0), step(-1.0));
        for i in 0..LEGS {
            let fd = (plus[i] - minus[i]) / (2.0 * dt);
            let e = (f64::from(rates[i]) - fd).abs() / fd.abs().max(1.0);
            worst = worst.max(e);
            assert!(e < 1e-5, "{pose:?} leg {}: {} vs {fd}", i + 1, rates[i]);
        }
        let back = twist_from_joint_rates::<Libm, _>(&solver, &pose, &rates).unwrap();
        assert!((back.to_vec6() - twist.to_vec6()).amax() < 1e-3 * twist.to_vec6().amax());
    }
    eprintln!("\nservo rates vs f64 FD along the twist: {worst:.1e} (relative)");
}

/// `omega = E (roll', pitch', yaw')`: checked against the rotation matrices of eq. 1 at
/// nearby angles, `omega_x = (R' R^T)_21` and so on, in f64.
#[test]
fn pose_rates_and_twists_agree_with_the_rotation_matrices() {
    let mut rng = Rng::new(31);
    for _ in 0..500 {
        let pose = rng.pose(&[0.0, 0.0, 0.0, 60.0, 60.0, 180.0]);
        let rate = [0.0, 0.0, 0.0, 0.3, -0.7, 1.1f32];
        let twist = Twist::from_pose_rate::<Libm>(&pose, &rate);
        let exact = RefPose::from_core(&pose);
        let at = |s: f64| {
            let mut p = exact;
            p.roll += s * f64::from(rate[3]);
            p.pitch += s * f64::from(rate[4]);
            p.yaw += s * f64::from(rate[5]);
            p.rotation()
        };
        let h = 1e-6;
        let (plus, minus) = (at(h), at(-h));
        let mut r_dot = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                r_dot[i][j] = (plus[i][j] - minus[i][j]) / (2.0 * h);
            }
        }
        let skew = mat_mul(&r_dot, &transpose(&exact.rotation()));
        let omega = [skew[2][1], skew[0][2], skew[1][0]];
        for k in 0..3 {
            assert!((f64::from(twist.angular_rad_s[k]) - omega[k]).abs() < 1e-5);
        }
        let back = twist.to_pose_rate::<Libm>(&pose).unwrap();
        for k in 3..6 {
            assert!((back[k] - rate[k]).abs() < 1e-4, "{pose:?}: {back:?}");
        }
    }
}

/// Lowering a strut platform until its struts lie flat: the condition number grows without
/// bound, and at the flat pose the Jacobian is refused, never divided by.
#[test]
fn struts_lying_flat_are_singular() {
    let case = &strut_cases()[0];
    // Base joints 15 mm up, platform joints 15 mm below the platform frame, 90 mm up at home:
    // flat at z = -60.
    let mut last = 0.0f32;
    for z in [-30.0, -50.0, -58.0, -59.9, -59.999f32] {
        let pose = Pose::from_degrees(0.0, 0.0, z, 0.0, 0.0, 0.0);
        let k = Jacobian::at::<Libm, _>(&case.struts, &pose)
            .unwrap()
            .condition_number::<Libm>();
        assert!(k > last, "z {z}: {k} after {last}");
        last = k;
    }
    assert!(last > 1e4, "{last}");
    let flat = Pose::from_degrees(0.0, 0.0, -60.0, 0.0, 0.0, 0.0);
    let j = Jacobian::at::<Libm, _>(&case.struts, &flat).unwrap();
    assert_eq!(j.condition_number::<Libm>(), f32::INFINITY);
    assert!(matches!(
        j.factor::<Libm>(),
        Err(KinematicsError::Singular { .. })
    ));
    let rates = [1.0f32; 6];
    assert!(matches!(
        twist_from_joint_rates::<Libm, _>(&case.struts, &flat, &rates),
        Err(KinematicsError::Singular { .. })
    ));
}

/// Raising a servo platform to the edge of its reach: the arms come to dead centre. The last
/// poses before are reported (dead centre, or a transmission near zero and arm rates per mm
/// far above home's), never with a NaN.
#[test]
fn servo_arms_at_dead_centre_are_reported() {
    let solver = ik::Solver::new(cases()[0].geometry.clone()).unwrap();
    let home = Jacobian::at::<Libm, _>(&solver, &Pose::HOME)
        .unwrap()
        .matrix
        .amax();
    // Bisect for the highest reachable z.
    let (mut lo, mut hi) = (0.0f32, 60.0f32);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        let pose = Pose::from_degrees(0.0, 0.0, mid, 0.0, 0.0, 0.0);
        if solver.arm_angles::<Libm>(&pose).is_ok() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let edge = Pose::from_degrees(0.0, 0.0, lo, 0.0, 0.0, 0.0);
    let arms = ArmState::new::<Libm>(&solver, &edge).unwrap();
    let transmission = arms
        .transmission()
        .iter()
        .fold(1.0f32, |m, t| m.min(t.abs()));
    assert!(transmission < 0.01, "{transmission}");
    match Jacobian::at::<Libm, _>(&solver, &edge) {
        Err(KinematicsError::DeadCentre { .. }) => {}
        Ok(j) => {
            assert!(
                j.matrix.amax() > 30.0 * home,
                "{} vs {home} at home",
                j.matrix.amax()
            );
            assert!(j.matrix.iter().all(|v| v.is_finite()));
        }
        Err(e) => panic!("{e}"),
    }
    // At home arm and rod are square: the transmission is the cosine of the rod's slant out
    // of the arm's plane, which the f64 reference measures from the joints.
    let home_arms = ArmState::new::<Libm>(&solver, &Pose::HOME).unwrap();
    let reference = RefArms::from_solver(&solver);
    let q = reference.anchors.joints(&RefPose::default());
    for (i, t) in home_arms.transmission().iter().enumerate() {
        let leg = &reference.legs[i];
        let tip = leg.arm_tip(reference.arm, reference.alpha0[i]);
        let rod: Vec<f64> = (0..3).map(|k| q[i][k] - tip[k]).collect();
        // The arm plane's normal is (-sin(beta), cos(beta), 0).
        let out = (-leg.beta.sin() * rod[0] + leg.beta.cos() * rod[1]) / reference.rod;
        let expected = (1.0 - out * out).sqrt();
        assert!(
            (f64::from(*t) - expected).abs() < 1e-5,
            "leg {}: {t} vs {expected}",
            i + 1
        );
    }
}

fn config(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    }
}

/// Poses from ordinary to absurd: large turns, the platform sunk to the base and below.
fn any_pose() -> impl Strategy<Value = Pose> {
    (
        -80.0f32..80.0,
        -80.0f32..80.0,
        -150.0f32..80.0,
        -180.0f32..180.0,
        -100.0f32..100.0,
        -180.0f32..180.0,
    )
        .prop_map(|(x, y, z, r, p, w)| Pose::from_degrees(x, y, z, r, p, w))
}

fn finite(v: &[f32]) -> bool {
    v.iter().all(|x| x.is_finite())
}

proptest! {
    #![proptest_config(config(512, 41))]

    /// Wherever the platform is: no panic, and every answer is an error or finite numbers
    /// (Jacobian, condition number or infinity, rates and twists back).
    #[test]
    fn no_pose_gives_a_nan(case in 0..4usize, servo in any::<bool>(), pose in any_pose()) {
        let twist = Twist {
            linear_mm_s: Vec3::new(3.0, -2.0, 1.0),
            angular_rad_s: Vec3::new(0.1, 0.2, -0.3),
        };
        let check = |j: Result<Jacobian, KinematicsError>| -> Result<(), TestCaseError> {
            if let Ok(j) = j {
                prop_assert!(finite(j.matrix.as_slice()));
                let k = j.condition_number::<Libm>();
                prop_assert!(!k.is_nan() && k >= 1.0 - 1e-3, "{k}");
                let rates = j.joint_rates::<Libm>(&twist.to_vec6());
                prop_assert!(finite(rates.as_slice()));
                if let Ok(lu) = j.factor::<Libm>() {
                    let back = lu.solve::<Libm>(&rates);
                    prop_assert!(finite(back.as_slice()));
                }
            }
            Ok(())
        };
        if servo {
            let solver = ik::Solver::new(cases()[case].geometry.clone()).unwrap();
            check(Jacobian::at::<Libm, _>(&solver, &pose))?;
        } else {
            let struts = strut_cases()[case].struts;
            check(Jacobian::at::<Libm, _>(&struts, &pose))?;
            let rates = [1.0f32, -1.0, 2.0, 0.0, 0.5, -3.0];
            if let Ok(t) = twist_from_joint_rates::<Libm, _>(&struts, &pose, &rates) {
                prop_assert!(finite(t.to_vec6().as_slice()));
            }
        }
        let nan = Vec6::from_element(f32::NAN);
        let nan_twist = Twist::from_vec6(&nan);
        prop_assert!(joint_rates::<Libm, _>(&strut_cases()[0].struts, &pose, &nan_twist).is_err());
    }
}
