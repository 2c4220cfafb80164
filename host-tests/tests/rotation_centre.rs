//! The rotation centre: the core's IK (servo arms and struts) with a centre set, against the
//! f64 reference's chain of frames base -> {A} -> {B} -> platform (`host_tests::platform`),
//! and the default centre changing nothing. Run with `--nocapture` to see the measured errors.

// Legs are numbered; index loops over them read like the equations.
#![allow(clippy::needless_range_loop)]

use host_tests::fixtures::{cases, solver_about, strut_cases, Rng, CENTRES_MM};
use host_tests::platform::{RefAnchors, RefArms};
use host_tests::reference::{solve_leg, RefPose};
use kinematics_core::configuration::ConfigurationError;
use kinematics_core::jacobian::Actuators;
use kinematics_core::{ik, IkError, Libm, ServoSet, Vec3, LEGS};

/// Arm angles, as the joint displacement the angle error is equivalent to
/// (`|d alpha| |dg/d alpha| / 2s`, as in `tests/agreement.rs`), mm: the f32 resolution of
/// joint coordinates, a little more where the centre is far (`c - R c` adds roundings of
/// coordinates of that size).
const JOINT_TOL_MM: f64 = 1e-4;
/// Reachability may differ this close to the workspace boundary, mm.
const BAND_MM: f64 = 1e-3;
/// Strut lengths, mm: a few roundings of coordinates of 100-200 mm (ulp 8-15 nm).
const LENGTH_TOL_MM: f64 = 1e-4;

#[test]
fn servo_ik_turns_the_platform_about_the_centre() {
    eprintln!();
    for case in cases() {
        for c in CENTRES_MM {
            let solver = solver_about(case.geometry.clone(), Vec3::from(c));
            let reference = RefArms::from_solver(&solver);
            let mut rng = Rng::new(11);
            let (mut ok, mut worst_mm, mut worst_deg) = (0, 0.0f64, 0.0f64);
            for _ in 0..1500 {
                let pose = rng.pose(&case.range);
                let exact = RefPose::from_core(&pose);
                let q = reference.anchors.joints(&exact);
                let roots: Vec<_> = (0..LEGS)
                    .map(|i| {
                        let leg = &reference.legs[i];
                        solve_leg(leg, reference.arm, reference.rod, q[i], reference.alpha0[i])
                    })
                    .collect();
                let margin = reference
                    .margins_mm(&exact)
                    .iter()
                    .fold(f64::INFINITY, |m, v| m.min(*v));
                match solver.arm_angles::<Libm>(&pose) {
                    Ok(alpha) => {
                        if roots.iter().any(|r| r.is_err()) {
                            assert!(
                                margin.abs() < BAND_MM,
                                "{} c={c:?} {pose:?}: core reaches, reference does not",
                                case.name
                            );
                            continue;
                        }
                        ok += 1;
                        for (i, root) in roots.iter().enumerate() {
                            let root = root.expect("checked");
                            let d = (f64::from(alpha[i]) - root.alpha).abs();
                            let joint_mm = d * root.slope.abs() / (2.0 * reference.rod);
                            worst_mm = worst_mm.max(joint_mm);
                            worst_deg = worst_deg.max(d.to_degrees());
                            assert!(
                                joint_mm <= JOINT_TOL_MM,
                                "{} c={c:?} {pose:?} leg {}: {} deg vs {} deg",
                                case.name,
                                i + 1,
                                f64::from(alpha[i]).to_degrees(),
                                root.alpha.to_degrees()
                            );
                        }
                    }
                    Err(IkError::Unreachable { leg }) => {
                        let i = usize::from(leg) - 1;
                        let m = reference.margins_mm(&exact)[i];
                        assert!(
                            m < BAND_MM,
                            "{} c={c:?} {pose:?}: leg {leg} unreachable, reference margin {m}",
                            case.name
                        );
                    }
                    Err(e) => panic!("{} {pose:?}: {e}", case.name),
                }
            }
            assert!(ok > 300, "{} c={c:?}: only {ok} reachable poses", case.name);
            eprintln!(
                "{:<46} c={:<18} {ok:>5} ok, max joint-equivalent {worst_mm:.1e} mm \
                 ({worst_deg:.1e} deg)",
                case.name,
                format!("{c:?}")
            );
        }
    }
}

#[test]
fn default_centre_changes_nothing() {
    let servos = ServoSet::default();
    for case in cases() {
        let plain = ik::Solver::new(case.geometry.clone()).expect("a valid geometry");
        let mut moved = plain.clone();
        moved
            .set_rotation_centre_mm(Vec3::new(0.0, 0.0, 50.0))
            .unwrap();
        moved.set_rotation_centre_mm(Vec3::zeros()).unwrap();
        let mut rng = Rng::new(3);
        for _ in 0..2000 {
            let pose = rng.pose(&case.range);
            let (a, b) = (
                plain.solve::<Libm>(&servos, &pose),
                moved.solve::<Libm>(&servos, &pose),
            );
            match (a, b) {
                (Ok(a), Ok(b)) => {
                    for i in 0..LEGS {
                        assert_eq!(a.pulse_us[i].to_bits(), b.pulse_us[i].to_bits());
                        assert_eq!(a.arm_rad[i].to_bits(), b.arm_rad[i].to_bits());
                    }
                }
                (a, b) => assert_eq!(a, b, "{}", case.name),
            }
        }
    }
}

#[test]
fn a_rotation_alone_leaves_the_centre_where_it_was() {
    // The point the platform turns about does not move when only the angles change: in the
    // core's placement, and in the reference's chain of frames.
    let solver = solver_about(cases()[0].geometry.clone(), Vec3::new(12.0, -7.5, -35.0));
    let anchors = solver.anchors();
    let reference = RefAnchors::from_core(&anchors);
    let mut rng = Rng::new(5);
    let home = anchors
        .place::<Libm>(&kinematics_core::Pose::HOME)
        .centre_mm;
    for _ in 0..200 {
        let mut pose = rng.pose(&[0.0, 0.0, 0.0, 20.0, 20.0, 30.0]);
        pose.x_mm = 0.0;
        let placed = anchors.place::<Libm>(&pose);
        assert!((placed.centre_mm - home).norm() < 1e-5);
        let c = reference.centre_position(&RefPose::from_core(&pose));
        assert!((c[0] - 12.0).abs() + (c[1] + 7.5).abs() < 1e-9);
        for i in 0..LEGS {
            let q = reference.joints(&RefPose::from_core(&pose))[i];
            let d: f64 = (0..3)
                .map(|k| (f64::from(placed.joints_mm[i][k]) - q[k]).abs())
                .fold(0.0, f64::max);
            assert!(d < 1e-4, "leg {}: {d} mm", i + 1);
        }
    }
}

#[test]
fn strut_lengths_turn_about_the_centre() {
    eprintln!();
    for case in strut_cases() {
        let reference = RefAnchors::from_core(&case.struts.anchors());
        let mut rng = Rng::new(17);
        let mut worst = 0.0f64;
        for _ in 0..3000 {
            let pose = rng.pose(&case.range);
            let lengths = case.struts.joint_values::<Libm>(&pose).expect("a length");
            let exact = reference.strut_lengths(&RefPose::from_core(&pose));
            for i in 0..LEGS {
                let d = (f64::from(lengths[i]) - exact[i]).abs();
                worst = worst.max(d);
                assert!(
                    d <= LENGTH_TOL_MM,
                    "{} {pose:?} leg {}: {d} mm",
                    case.name,
                    i + 1
                );
            }
        }
        eprintln!("{:<46} strut lengths: max error {worst:.1e} mm", case.name);
    }
}

#[test]
fn bad_centres_are_refused() {
    let mut solver = ik::Solver::new(cases()[0].geometry.clone()).unwrap();
    for c in [
        Vec3::new(f32::NAN, 0.0, 0.0),
        Vec3::new(0.0, f32::INFINITY, 0.0),
        Vec3::new(0.0, 0.0, -2e4),
    ] {
        assert!(matches!(
            solver.set_rotation_centre_mm(c),
            Err(ConfigurationError::BadCentre { .. })
        ));
    }
    assert_eq!(solver.rotation_centre_mm(), Vec3::zeros());
}
