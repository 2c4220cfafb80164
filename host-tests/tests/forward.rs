//! Forward kinematics: IK -> FK round trips against the f64 reference's IK, the core's Newton
//! against an independent f64 Newton (`host_tests::platform::newton_fk`), the solution nearest
//! the start where there are several, the errors, and the Simscape documentation's
//! approximation. Run with `--nocapture` to see the measured errors and iteration counts.

// Legs are numbered; index loops over them read like the equations.
#![allow(clippy::needless_range_loop)]

use host_tests::fixtures::{cases, solver_about, strut_cases, Rng, CENTRES_MM};
use host_tests::platform::{newton_fk, rotation_between, translation_between, RefAnchors, RefArms};
use host_tests::reference::RefPose;
use kinematics_core::forward::{
    approximate, arm_angles_for_pulses, arms, struts, Closure, Newton, Options,
};
use kinematics_core::jacobian::Actuators;
use kinematics_core::{ik, KinematicsError, Libm, Pose, ServoSet, Vec3, LEGS};

/// The round trip's bound (the issue's): 1e-3 mm and 1e-4 rad.
const TRANSLATION_TOL_MM: f64 = 1e-3;
const ROTATION_TOL_RAD: f64 = 1e-4;
/// Iterations allowed from a pose a frame's step away.
const MAX_ITERATIONS: u8 = 8;

/// A pose near `pose`: up to `mm` along each axis and `deg` about each (a frame's step of a
/// fast move: 1 mm and 0.5 degree at 50 Hz is 50 mm/s and 25 deg/s).
fn nearby(rng: &mut Rng, pose: &Pose, mm: f64, deg: f64) -> Pose {
    let d = rng.pose(&[mm, mm, mm, deg, deg, deg]);
    let (a, b) = (pose.to_array(), d.to_array());
    Pose::from_array(core::array::from_fn(|k| a[k] + b[k]))
}

#[derive(Default)]
struct Tally {
    solves: usize,
    worst_mm: f64,
    worst_rad: f64,
    iterations: [usize; 9],
}

impl Tally {
    fn add(&mut self, found: &RefPose, truth: &RefPose, iterations: u8) {
        self.solves += 1;
        self.worst_mm = self.worst_mm.max(translation_between(found, truth));
        self.worst_rad = self.worst_rad.max(rotation_between(found, truth));
        self.iterations[usize::from(iterations).min(8)] += 1;
    }

    fn print(&self, name: &str, what: &str) {
        eprintln!(
            "{name:<46} {what}: {:>5} solves, max {:.1e} mm, {:.1e} rad; iterations {:?}",
            self.solves,
            self.worst_mm,
            self.worst_rad,
            &self.iterations[1..]
        );
    }

    fn check(&self, name: &str) {
        assert!(
            self.worst_mm <= TRANSLATION_TOL_MM,
            "{name}: {} mm",
            self.worst_mm
        );
        assert!(
            self.worst_rad <= ROTATION_TOL_RAD,
            "{name}: {} rad",
            self.worst_rad
        );
    }
}

/// Servo arm angles from the f64 reference IK -> the core's FK from a frame's step away -> the
/// pose the reference started from.
#[test]
fn servo_round_trip_from_a_frame_away() {
    eprintln!();
    let options = Options {
        max_iterations: MAX_ITERATIONS,
        ..Options::default()
    };
    for case in cases() {
        for c in CENTRES_MM {
            let solver = solver_about(case.geometry.clone(), Vec3::from(c));
            let reference = RefArms::from_solver(&solver);
            let mut rng = Rng::new(43);
            let mut tally = Tally::default();
            while tally.solves < 300 {
                let pose = rng.pose(&case.range);
                let exact = RefPose::from_core(&pose);
                // Away from the workspace boundary, where arm angles stop fixing the pose.
                if reference.margins_mm(&exact).iter().any(|m| *m < 1.0) {
                    continue;
                }
                let alpha = reference
                    .arm_angles(&exact)
                    .expect("reachable")
                    .map(|a| a as f32);
                // The previous frame's pose: one the platform was at.
                let start = nearby(&mut rng, &pose, 1.0, 0.5);
                if solver.arm_angles::<Libm>(&start).is_err() {
                    continue;
                }
                let found = arms::<Libm>(&solver, &alpha, &start, options)
                    .unwrap_or_else(|e| panic!("{} c={c:?} {pose:?}: {e}", case.name));
                tally.add(&RefPose::from_core(&found.pose), &exact, found.iterations);
            }
            tally.print(case.name, &format!("c={c:?}"));
            tally.check(case.name);
        }
    }
}

/// The same for struts, lengths from the f64 reference.
#[test]
fn strut_round_trip_from_a_frame_away() {
    eprintln!();
    for case in strut_cases() {
        let reference = RefAnchors::from_core(&case.struts.anchors());
        let mut rng = Rng::new(47);
        let mut tally = Tally::default();
        for _ in 0..1000 {
            let pose = rng.pose(&case.range);
            let exact = RefPose::from_core(&pose);
            let lengths = reference.strut_lengths(&exact).map(|l| l as f32);
            let start = nearby(&mut rng, &pose, 1.0, 0.5);
            let found = struts::<Libm>(&case.struts, &lengths, &start, Options::default())
                .unwrap_or_else(|e| panic!("{} {pose:?}: {e}", case.name));
            tally.add(&RefPose::from_core(&found.pose), &exact, found.iterations);
        }
        tally.print(case.name, "struts");
        tally.check(case.name);
    }
}

/// The core's Newton and an independent f64 Newton (finite-difference Jacobians, its own
/// elimination) find the same pose for the same joint values from the same start, here from
/// farther away (5 mm, 3 degrees).
#[test]
fn core_newton_agrees_with_an_independent_f64_newton() {
    eprintln!();
    let solver = solver_about(cases()[0].geometry.clone(), Vec3::new(12.0, -7.5, -35.0));
    let reference = RefArms::from_solver(&solver);
    let mut rng = Rng::new(53);
    let mut tally = Tally::default();
    while tally.solves < 200 {
        let pose = rng.pose(&cases()[0].range);
        let alpha = match solver.arm_angles::<Libm>(&pose) {
            Ok(a) => a,
            Err(_) => continue,
        };
        if reference
            .margins_mm(&RefPose::from_core(&pose))
            .iter()
            .any(|m| *m < 1.0)
        {
            continue;
        }
        let start = nearby(&mut rng, &pose, 5.0, 3.0);
        if reference.arm_angles(&RefPose::from_core(&start)).is_none() {
            continue;
        }
        let target = alpha.map(f64::from);
        let exact = newton_fk(
            |p| reference.arm_angles(p),
            &target,
            &RefPose::from_core(&start),
        )
        .expect("the f64 Newton converges");
        let found = arms::<Libm>(&solver, &alpha, &start, Options::default()).unwrap();
        tally.add(&RefPose::from_core(&found.pose), &exact, found.iterations);
    }
    tally.print("default, centre off-axis", "vs f64 Newton");
    tally.check("vs f64 Newton");

    let cubic = strut_cases()[2].struts;
    let reference = RefAnchors::from_core(&cubic.anchors());
    let mut tally = Tally::default();
    for _ in 0..200 {
        let pose = rng.pose(&strut_cases()[2].range);
        let lengths = cubic.joint_values::<Libm>(&pose).unwrap();
        let start = nearby(&mut rng, &pose, 5.0, 3.0);
        let exact = newton_fk(
            |p| Some(reference.strut_lengths(p)),
            &lengths.map(f64::from),
            &RefPose::from_core(&start),
        )
        .expect("the f64 Newton converges");
        let found = struts::<Libm>(&cubic, &lengths, &start, Options::default()).unwrap();
        tally.add(&RefPose::from_core(&found.pose), &exact, found.iterations);
    }
    tally.print("Simscape cubic", "vs f64 Newton");
    tally.check("struts vs f64 Newton");
}

/// Several solutions (the 3-RPR project's lesson): struts whose base joints lie in one plane
/// and whose platform joints lie in another have the same lengths when the platform is
/// mirrored through the base joints' plane. From near each, the FK finds that one; from the
/// flat pose between them, where the struts lie in the plane, it reports the singularity.
#[test]
fn of_several_solutions_the_nearest_is_found() {
    let case = &strut_cases()[0]; // base joints at z = 15, platform joints 15 mm below.
    let reference = RefAnchors::from_core(&case.struts.anchors());
    let mut rng = Rng::new(59);
    for _ in 0..50 {
        let pose = rng.pose(&[5.0, 5.0, 5.0, 4.0, 4.0, 8.0]);
        let exact = RefPose::from_core(&pose);
        // The mirror image through z = 15 (base frame): joints q -> M q + (0, 0, 30) with
        // M = diag(1, 1, -1). With R' = M R M, joints p (platform frame, z = -15) land there
        // when the platform frame's origin is at M T + (0, 0, 30) - M R (0, 0, 30).
        let r = exact.rotation();
        let m = |v: [f64; 3]| [v[0], v[1], -v[2]];
        let mut rm = r;
        for (i, row) in rm.iter_mut().enumerate() {
            for (j, cell) in row.iter_mut().enumerate() {
                let s = if (i == 2) != (j == 2) { -1.0 } else { 1.0 };
                *cell *= s;
            }
        }
        let t = [exact.x, exact.y, 90.0 + exact.z];
        let r_up = [r[0][2] * 30.0, r[1][2] * 30.0, r[2][2] * 30.0];
        let t_mirror: Vec<f64> = (0..3)
            .map(|k| m(t)[k] + [0.0, 0.0, 30.0][k] - m(r_up)[k])
            .collect();
        let (roll, pitch, yaw) = RefPose::angles_of(&rm);
        let mirror = RefPose {
            x: t_mirror[0],
            y: t_mirror[1],
            z: t_mirror[2] - 90.0,
            roll,
            pitch,
            yaw,
        };
        let (a, b) = (
            reference.strut_lengths(&exact),
            reference.strut_lengths(&mirror),
        );
        for i in 0..LEGS {
            assert!(
                (a[i] - b[i]).abs() < 1e-9,
                "the mirror has the same lengths"
            );
        }
        let lengths = a.map(|l| l as f32);
        for (truth, other) in [(exact, mirror), (mirror, exact)] {
            let start = nearby(&mut rng, &truth.to_core(), 3.0, 2.0);
            let found = struts::<Libm>(&case.struts, &lengths, &start, Options::default())
                .expect("converges");
            let found = RefPose::from_core(&found.pose);
            assert!(
                translation_between(&found, &truth) < 1e-3,
                "{found:?} vs {truth:?}"
            );
            assert!(translation_between(&found, &other) > 50.0);
        }
    }
    let flat = Pose::from_degrees(0.0, 0.0, -60.0, 0.0, 0.0, 0.0);
    let lengths = case.struts.joint_values::<Libm>(&Pose::HOME).unwrap();
    assert!(matches!(
        struts::<Libm>(&case.struts, &lengths, &flat, Options::default()),
        Err(KinematicsError::Singular { .. })
    ));
}

#[test]
fn no_solution_is_an_error_within_the_iterations_allowed() {
    let options = Options::default();
    // Struts far longer than any assembly allows.
    let s = strut_cases()[0].struts;
    let long = s.home_lengths_mm().map(|l| 10.0 * l);
    assert!(struts::<Libm>(&s, &long, &Pose::HOME, options).is_err());
    // A NaN target, and a start too far for one iteration.
    let mut nan = s.home_lengths_mm();
    nan[4] = f32::NAN;
    assert_eq!(
        struts::<Libm>(&s, &nan, &Pose::HOME, options),
        Err(KinematicsError::NonFinite {
            input: kinematics_core::error::Input::Joint { leg: 5 }
        })
    );
    let one = Options {
        max_iterations: 1,
        ..options
    };
    let far = Pose::from_degrees(5.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    assert!(matches!(
        struts::<Libm>(&s, &s.home_lengths_mm(), &far, one),
        Err(KinematicsError::NotConverged { iterations: 1, .. })
    ));
    let solver = ik::Solver::new(cases()[0].geometry.clone()).unwrap();
    let home: [f32; LEGS] = core::array::from_fn(|i| solver.alpha0_rad(i));
    assert!(matches!(
        arms::<Libm>(&solver, &home, &far, one),
        Err(KinematicsError::NotConverged { iterations: 1, .. })
    ));
    // Arms the rods close with, but only with an elbow folded through its rod: the closures
    // are solved, the IK check refuses the pose.
    let mut flipped = home;
    let pose = Pose::from_degrees(0.0, 0.0, 3.0, 0.0, 0.0, 0.0);
    let reference = RefArms::from_solver(&solver);
    let q = reference.anchors.joints(&RefPose::from_core(&pose));
    for (i, a) in flipped.iter_mut().enumerate() {
        let leg = &reference.legs[i];
        let root =
            host_tests::reference::solve_leg(leg, reference.arm, reference.rod, q[i], 0.0).unwrap();
        *a = if i == 0 { root.other } else { root.alpha } as f32;
    }
    assert_eq!(
        arms::<Libm>(&solver, &flipped, &pose, options),
        Err(KinematicsError::ElbowFlipped { leg: 1 })
    );
}

/// [`Newton`] stepped one iteration at a time (as a main loop would) ends where [`solve`]
/// does, and says so once.
#[test]
fn stepping_the_solve_gives_the_same_answer() {
    let solver = ik::Solver::new(cases()[0].geometry.clone()).unwrap();
    let servos = ServoSet::default();
    let pose = Pose::from_degrees(4.0, 3.0, -2.0, 2.0, 1.0, -5.0);
    let pulses = solver.solve::<Libm>(&servos, &pose).unwrap().pulse_us;
    let target = arm_angles_for_pulses(&solver, &servos, &pulses).unwrap();
    let whole = arms::<Libm>(&solver, &target, &Pose::HOME, Options::default()).unwrap();
    let closure = Closure::pulses::<Libm>(&solver, &servos, &pulses).unwrap();
    let mut newton = Newton::new(closure, Pose::HOME, Options::default());
    let mut steps = 0;
    let stepped = loop {
        steps += 1;
        if let Some(outcome) = newton.step::<Libm>() {
            break outcome.unwrap();
        }
    };
    assert_eq!(stepped, whole);
    assert_eq!(steps, usize::from(whole.iterations));
    assert_eq!(newton.step::<Libm>(), None);
    let d = translation_between(
        &RefPose::from_core(&stepped.pose),
        &RefPose::from_core(&pose),
    );
    assert!(d < 1e-3, "{d}");
}

/// The Simscape documentation's `dX = J^-1 dL` is right to first order: its error shrinks
/// with the square of the motion.
#[test]
fn approximation_is_first_order() {
    let case = &strut_cases()[0];
    let reference = RefAnchors::from_core(&case.struts.anchors());
    let direction = [1.0, -0.6, 0.8, 0.5, -0.3, 0.7];
    let error_at = |scale: f64| {
        let truth = RefPose::from_degrees(
            direction[0] * scale,
            direction[1] * scale,
            direction[2] * scale,
            direction[3] * scale,
            direction[4] * scale,
            direction[5] * scale,
        );
        let lengths = reference.strut_lengths(&truth).map(|l| l as f32);
        let found = approximate::<Libm, _>(&case.struts, &Pose::HOME, &lengths).unwrap();
        translation_between(&RefPose::from_core(&found), &truth)
            + 100.0 * rotation_between(&RefPose::from_core(&found), &truth)
    };
    let (big, small) = (error_at(2.0), error_at(0.5));
    // Four times smaller motion, about sixteen times smaller error.
    assert!(big / small > 10.0 && big / small < 25.0, "{big} / {small}");
    assert!(big < 0.2, "{big}");
}
