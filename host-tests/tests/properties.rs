//! Property tests of the core's IK (proptest, fixed seeds so failures reproduce).
//!
//! Symmetry properties are checked core-against-core (no reference needed) where the pose
//! transformation is exact in f32, and with a tolerance derived from the reference where the
//! transformed pose has to be rounded to f32.

use core::f32::consts::PI;

use host_tests::fixtures::{cases, Rng};
use host_tests::reference::{
    mat_mul, pulse_us, rot_z, transpose, Expectation, RefGeometry, RefPose,
};
use kinematics_core::geometry::PairedLayout;
use kinematics_core::pose::Axis;
use kinematics_core::servo::{Direction, ServoConfig};
use kinematics_core::{ik, Geometry, IkError, Libm, Pose, ServoSet, Vec3, LEGS};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn config(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        // The seed is fixed, so a failure reproduces without a regressions file.
        failure_persistence: None,
        ..Config::default()
    }
}

/// A pose within the realistic box of the default geometry, times `k`.
fn pose_in(k: f32) -> impl Strategy<Value = Pose> {
    (
        -15.0f32..15.0,
        -15.0f32..15.0,
        -12.0f32..12.0,
        -8.0f32..8.0,
        -8.0f32..8.0,
        -15.0f32..15.0,
    )
        .prop_map(move |(x, y, z, r, p, w)| {
            Pose::from_degrees(k * x, k * y, k * z, k * r, k * p, k * w)
        })
}

/// A valid servo set: random trims, limits, rates and directions (biased towards sets that
/// accept a fair share of poses: limits at least 40% of the way out, moderate rates).
fn servo_set() -> impl Strategy<Value = ServoSet> {
    let servo = (
        1000.0f32..2000.0,
        0.0f32..0.6,
        0.0f32..0.6,
        100.0f32..2000.0,
        any::<bool>(),
    )
        .prop_map(|(home_us, lo, hi, rate, reversed)| ServoConfig {
            home_us,
            rate_us_per_rad: rate,
            direction: if reversed {
                Direction::Reversed
            } else {
                Direction::Normal
            },
            min_us: home_us - (1.0 - lo) * (home_us - 400.0),
            max_us: home_us + (1.0 - hi) * (2600.0 - home_us),
        });
    proptest::array::uniform6(servo).prop_map(|s| {
        let set = ServoSet(s);
        assert_eq!(set.validate(), Ok(()), "strategy makes valid servos");
        set
    })
}

/// A random valid paired layout (rejects the few invalid combinations).
fn paired_geometry() -> impl Strategy<Value = (PairedLayout, Geometry)> {
    (
        40.0f32..150.0,
        5.0f32..40.0,
        30.0f32..130.0,
        5.0f32..40.0,
        10.0f32..40.0,
        60.0f32..250.0,
    )
        .prop_filter_map("invalid layout", |(rb, hb, rp, hp, a, s)| {
            let layout = PairedLayout {
                base_radius_mm: rb,
                base_half_angle_deg: hb,
                platform_radius_mm: rp,
                platform_half_angle_deg: hp,
                arm_mm: a,
                rod_mm: s,
            };
            // A geometry the IK can drive: its home pose within reach of every arm.
            let geometry = layout.build().ok()?;
            ik::Solver::new(geometry.clone()).ok()?;
            Some((layout, geometry))
        })
}

/// The rod-closure residual `| |q_i - A_i(alpha_i)| - s |` allowed, mm: the f32 resolution of
/// joint coordinates of 100-250 mm is 4-8 nm; the IK's roundings stay within 1e-4 mm
/// whatever the conditioning (the residual is the joint-equivalent of the angle error).
const CLOSURE_TOL_MM: f64 = 1e-4;

proptest! {
    #![proptest_config(config(256, 1))]

    /// Every arm angle the core returns puts the rod's far end on the platform joint, to f32
    /// precision, for every geometry and for poses far beyond the servo travel.
    #[test]
    fn rods_close_for_every_ok_pose(case in 0..cases().len(), pose in pose_in(1.4)) {
        let case = &cases()[case];
        let reference = RefGeometry::from_core(&case.geometry);
        if let Ok(alpha) = ik::Solver::new(case.geometry.clone()).expect("a valid geometry").arm_angles::<Libm>(&pose) {
            let alpha = alpha.map(f64::from);
            let residual = reference.rod_closure_errors(&RefPose::from_core(&pose), &alpha);
            for (i, r) in residual.iter().enumerate() {
                prop_assert!(*r <= CLOSURE_TOL_MM, "{}: leg {} misses by {r:e} mm", case.name, i + 1);
            }
        }
    }

    /// Home is exactly W0 on every servo, whatever the trims, rates and directions, on random
    /// valid geometries.
    #[test]
    fn home_gives_exactly_the_home_pulses(servos in servo_set(), (_, geometry) in paired_geometry()) {
        let solver = ik::Solver::new(geometry).expect("a valid geometry");
        let sol = solver.solve::<Libm>(&servos, &Pose::HOME);
        let sol = sol.map_err(|e| TestCaseError::fail(format!("{e:?}")))?;
        for i in 0..LEGS {
            prop_assert_eq!(sol.pulse_us[i], servos.0[i].home_us, "servo {}", i + 1);
            prop_assert_eq!(sol.arm_rad[i], solver.alpha0_rad(i), "servo {}", i + 1);
        }
    }

    /// Pure heave in the default (mirror- and 3-fold symmetric) layout moves the odd and the
    /// even servos' pulses by equal and opposite amounts: eq. 13 adds, eq. 14 subtracts.
    #[test]
    fn pure_heave_moves_odd_and_even_pulses_as_mirror_images(z in -25.0f32..25.0) {
        let g = Geometry::default();
        let solver = ik::Solver::new(g.clone()).expect("a valid geometry");
        let servos = ServoSet::default();
        let pose = Pose { z_mm: z, ..Pose::HOME };
        let Ok(sol) = solver.solve::<Libm>(&servos, &pose) else {
            // Beyond the servo travel: the reference must agree.
            let e = Expectation::new(&RefGeometry::from_core(&g), &servos, &RefPose::from_core(&pose));
            prop_assert!(e.limit_margin_us.iter().any(|m| m.is_nan() || *m <= 0.01), "z = {z}");
            return Ok(());
        };
        let dev = |i: usize| f64::from(sol.pulse_us[i]) - 1500.0;
        for i in 0..LEGS {
            let (odd, even) = (i - i % 2, i - i % 2 + 1);
            prop_assert!((dev(odd) + dev(even)).abs() <= 2e-3, "z {z}: {:?}", sol.pulse_us);
            // All six arms move alike, and up for a rise: even pulses grow.
            prop_assert!((dev(i).abs() - dev(0).abs()).abs() <= 2e-3, "z {z}: {:?}", sol.pulse_us);
            if z > 0.01 {
                prop_assert!(dev(even) > 0.0 && dev(odd) < 0.0, "z {z}: {:?}", sol.pulse_us);
            }
        }
    }

    /// Mirroring a pose in the x-z plane (y, roll and yaw change sign; exact in f32) mirrors
    /// the default layout's legs: 1<->2, 3<->6, 4<->5, and so flips every pulse about W0.
    #[test]
    fn mirrored_pose_mirrors_the_legs(pose in pose_in(1.5)) {
        let g = Geometry::default();
        let solver = ik::Solver::new(g.clone()).expect("a valid geometry");
        let servos = ServoSet::default();
        let mirror = Pose { y_mm: -pose.y_mm, roll_rad: -pose.roll_rad, yaw_rad: -pose.yaw_rad, ..pose };
        let partner = [1, 0, 5, 4, 3, 2];
        match (solver.arm_angles::<Libm>(&pose), solver.arm_angles::<Libm>(&mirror)) {
            (Ok(a), Ok(b)) => {
                for i in 0..LEGS {
                    let d = f64::from(a[i] - b[partner[i]]).abs().to_degrees();
                    // Pair 1 is mirrored exactly in f32; pairs 2, 3 (at 100/140 and 220/260
                    // degrees) only to the rounding of their coordinates.
                    prop_assert!(d <= 2e-4, "leg {} vs {}: {d:e} deg", i + 1, partner[i] + 1);
                }
                let mirrored = solver.solve::<Libm>(&servos, &mirror);
                if let (Ok(s), Ok(t)) = (solver.solve::<Libm>(&servos, &pose), mirrored) {
                    for (i, &j) in partner.iter().enumerate() {
                        let sum = f64::from(s.pulse_us[i] - 1500.0) + f64::from(t.pulse_us[j] - 1500.0);
                        prop_assert!(sum.abs() <= 2e-3, "servo {}: {} vs {}", i + 1, s.pulse_us[i], t.pulse_us[j]);
                    }
                }
            }
            (Err(IkError::Unreachable { .. }), Err(IkError::Unreachable { .. })) => {}
            (a, b) => {
                // Only acceptable right at the workspace boundary.
                let e = Expectation::new(&RefGeometry::from_core(&g), &servos, &RefPose::from_core(&pose));
                let closest = (0..LEGS).map(|i| e.leg_margin_mm(i).abs()).fold(f64::INFINITY, f64::min);
                prop_assert!(closest < 1e-4, "pose {pose:?}: {a:?} but mirrored {b:?}");
            }
        }
    }

    /// Turning the whole situation by +120 degrees about z maps pair k onto pair k+1: leg i's
    /// joint, shaft and arm plane become leg i+2's. So the pose with translation
    /// `Rz(120) (x, y)` (z unchanged) and rotation `Rz(120) R Rz(-120)` gives leg i+2 the arm
    /// angle (and servo i+2 the pulse) that leg i had.
    #[test]
    fn yaw_by_120_degrees_permutes_the_legs(pose in pose_in(1.5), turns in 1usize..3) {
        let g = Geometry::default();
        let solver = ik::Solver::new(g.clone()).expect("a valid geometry");
        let servos = ServoSet::default();
        let reference = RefGeometry::from_core(&g);
        let turned = turn_pose(&pose, turns);
        let shift = |i: usize| (i + 2 * turns) % LEGS;
        // How much rounding the turned pose to f32 (and the legs' own f32 coordinates, which
        // are 3-fold symmetric only to rounding) moves the exact answer, per the reference.
        let exact = reference.arm_angles(&RefPose::from_core(&pose));
        let exact_turned = reference.arm_angles(&RefPose::from_core(&turned));
        match (solver.solve::<Libm>(&servos, &pose), solver.solve::<Libm>(&servos, &turned)) {
            (Ok(a), Ok(b)) => {
                for i in 0..LEGS {
                    let (Ok(e), Ok(f)) = (exact[i], exact_turned[shift(i)]) else {
                        return Err(TestCaseError::fail("reference cannot reach an Ok pose"));
                    };
                    let slack = (e.alpha - f.alpha).abs();
                    let d = f64::from(a.arm_rad[i] - b.arm_rad[shift(i)]).abs();
                    prop_assert!(
                        d <= slack + 2.0 * 1e-4f64.to_radians(),
                        "leg {} -> {}: {:e} deg (rounding slack {:e} deg)",
                        i + 1, shift(i) + 1, d.to_degrees(), slack.to_degrees()
                    );
                    let dw = f64::from(a.pulse_us[i] - b.pulse_us[shift(i)]).abs();
                    prop_assert!(dw <= 1600.0 / core::f64::consts::PI * slack + 0.01, "servo {}: {dw} us", i + 1);
                }
            }
            (Err(_), Err(_)) => {}
            (a, b) => {
                // Only acceptable where the reference puts a servo at its limit or a leg at the
                // workspace boundary.
                let e = Expectation::new(&reference, &servos, &RefPose::from_core(&pose));
                let tight = (0..LEGS).any(|i| e.leg_margin_mm(i).abs() < 1e-4 || e.limit_margin_us[i].is_nan() || e.limit_margin_us[i].abs() <= 0.01);
                prop_assert!(tight, "pose {pose:?}: {a:?}, turned {turned:?}: {b:?}");
            }
        }
    }

    /// Garbage in: NaN, infinities, huge, tiny and subnormal numbers, angles past +-180
    /// degrees. Never a panic; the error names the first bad coordinate; finite poses are
    /// judged as the reference judges them; any Ok is finite and within the servo limits.
    #[test]
    fn any_input_is_an_answer_or_a_named_error(v in prop_oneof![
        proptest::array::uniform6(wild_f32()),
        proptest::array::uniform6(tame_f32()),
    ]) {
        let g = Geometry::default();
        let solver = ik::Solver::new(g.clone()).expect("a valid geometry");
        let servos = ServoSet::default();
        let pose = Pose::from_array(v);
        let got = solver.solve::<Libm>(&servos, &pose);
        let axes = Axis::ALL;
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            prop_assert_eq!(got, Err(IkError::NonFinite { axis: axes[k] }));
            return Ok(());
        }
        if let Some(k) = (3..6).find(|&k| v[k].abs() > PI) {
            prop_assert!(matches!(got, Err(IkError::AngleTooLarge { axis, value_rad }) if axis == axes[k] && value_rad == v[k]), "{got:?}");
            return Ok(());
        }
        let e = Expectation::new(&RefGeometry::from_core(&g), &servos, &RefPose::from_core(&pose));
        let clearly_unreachable = (0..LEGS).any(|i| e.leg_margin_mm(i) < -1e-4);
        let clearly_outside = (0..LEGS).any(|i| e.limit_margin_us[i] < -0.01);
        let clearly_fine = (0..LEGS).all(|i| e.leg_margin_mm(i) > 1e-4 && e.limit_margin_us[i] > 0.01);
        match got {
            Ok(sol) => {
                prop_assert!(!clearly_unreachable && !clearly_outside, "Ok for {pose:?}");
                for (w, s) in sol.pulse_us.iter().zip(servos.0.iter()) {
                    prop_assert!(w.is_finite() && s.min_us <= *w && *w <= s.max_us);
                }
            }
            Err(IkError::Unreachable { .. }) | Err(IkError::ServoLimit { .. }) => {
                prop_assert!(!clearly_fine, "{got:?} for {pose:?}");
            }
            Err(other) => prop_assert!(false, "{other:?} for a finite pose within +-180 degrees"),
        }
    }

    /// Whenever `solve` is Ok, every pulse is finite and within its own servo's limits, for
    /// random valid servo sets and poses well beyond the usual travel.
    #[test]
    fn ok_pulses_are_finite_and_within_each_servos_limits(servos in servo_set(), pose in pose_in(0.8)) {
        let g = Geometry::default();
        let solver = ik::Solver::new(g.clone()).expect("a valid geometry");
        match solver.solve::<Libm>(&servos, &pose) {
            Ok(sol) => {
                let reference = RefGeometry::from_core(&g);
                let e = Expectation::new(&reference, &servos, &RefPose::from_core(&pose));
                for (i, (w, s)) in sol.pulse_us.iter().zip(servos.0.iter()).enumerate() {
                    prop_assert!(w.is_finite() && s.min_us <= *w && *w <= s.max_us, "servo {}: {w}", i + 1);
                    // And it is the reference's pulse for this servo's own settings (the
                    // tolerance grows with the servo's rate, up to 5000 us/rad).
                    let tol = 1e-4f64.to_radians() * f64::from(s.rate_us_per_rad) + 1e-3;
                    prop_assert!((f64::from(*w) - e.pulse_us[i]).abs() <= tol, "servo {}: {w} vs {}", i + 1, e.pulse_us[i]);
                }
            }
            Err(IkError::ServoLimit { servo, pulse_us, min_us, max_us }) => {
                let s = &servos.0[usize::from(servo) - 1];
                prop_assert!(!(min_us..=max_us).contains(&pulse_us));
                prop_assert_eq!((min_us, max_us), (s.min_us, s.max_us));
            }
            Err(IkError::Unreachable { .. }) => {}
            Err(other) => prop_assert!(false, "{other:?}"),
        }
    }

    /// Lowering one servo's upper limit just below the pulse a pose needs (or raising its
    /// lower limit just above it) makes exactly that servo the error.
    #[test]
    fn a_tightened_limit_names_exactly_that_servo(pose in pose_in(1.0), k in 0..LEGS) {
        let g = Geometry::default();
        let solver = ik::Solver::new(g.clone()).expect("a valid geometry");
        let servos = ServoSet::default();
        let Ok(sol) = solver.solve::<Libm>(&servos, &pose) else { return Ok(()) };
        let need = sol.pulse_us[k];
        let mut tight = servos;
        if need >= servos.0[k].home_us {
            tight.0[k].max_us = need - 0.05;
        } else {
            tight.0[k].min_us = need + 0.05;
        }
        match solver.solve::<Libm>(&tight, &pose) {
            Err(IkError::ServoLimit { servo, pulse_us, min_us, max_us }) => {
                prop_assert_eq!(usize::from(servo), k + 1);
                prop_assert_eq!(pulse_us, need);
                prop_assert_eq!((min_us, max_us), (tight.0[k].min_us, tight.0[k].max_us));
            }
            other => prop_assert!(false, "expected servo {} at its limit, got {other:?}", k + 1),
        }
    }
}

/// `pose` turned `turns` times by +120 degrees about z (translation and rotation).
fn turn_pose(pose: &Pose, turns: usize) -> Pose {
    let p = RefPose::from_core(pose);
    let g = rot_z((120.0 * turns as f64).to_radians());
    let r = mat_mul(&mat_mul(&g, &p.rotation()), &transpose(&g));
    let (roll, pitch, yaw) = RefPose::angles_of(&r);
    RefPose {
        x: g[0][0] * p.x + g[0][1] * p.y,
        y: g[1][0] * p.x + g[1][1] * p.y,
        z: p.z,
        roll,
        pitch,
        yaw,
    }
    .to_core()
}

/// Small numbers, mostly ones that still reach: subnormals, signed zeros, tiny and modest.
fn tame_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        2 => -0.1f32..0.1,
        1 => prop::sample::select(vec![1e-45, -1e-45, 1e-40, f32::MIN_POSITIVE, 0.0, -0.0, 1e-30]),
        1 => -3.0f32..3.0,
    ]
}

/// Numbers that break naive code: NaN, infinities, extremes, subnormals, signed zeros, values
/// around +-pi, and ordinary ones.
fn wild_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => any::<f32>(),
        3 => -20.0f32..20.0,
        1 => -0.2f32..0.2,
        1 => prop::sample::select(vec![
            f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX, f32::MIN, f32::MIN_POSITIVE,
            1e-45, -1e-45, 0.0, -0.0, 1e30, -1e30, 1e19, 1e15, 4e3, PI, -PI, f32::from_bits(PI.to_bits() + 1), 7.0,
        ]),
    ]
}

#[test]
fn the_rotation_is_the_product_of_the_elementary_rotations() {
    // Eq. 1 in the core against the numeric product Rz Ry Rx, over random angles within
    // +-180 degrees.
    let mut rng = Rng::new(42);
    for _ in 0..2000 {
        let pose = Pose::from_array(core::array::from_fn(|i| {
            if i < 3 {
                0.0
            } else {
                rng.symmetric(core::f64::consts::PI) as f32
            }
        }));
        let core_r = pose.rotation::<Libm>();
        let ref_r = RefPose::from_core(&pose).rotation();
        for r in 0..3 {
            for c in 0..3 {
                let d = (f64::from(core_r[(r, c)]) - ref_r[r][c]).abs();
                assert!(
                    d <= 4e-7,
                    "{pose:?} R[{r}][{c}]: {} vs {}",
                    core_r[(r, c)],
                    ref_r[r][c]
                );
            }
        }
    }
}

#[test]
fn platform_joints_and_legs_match_eq_2_and_3() {
    let mut rng = Rng::new(43);
    for case in cases() {
        let reference = RefGeometry::from_core(&case.geometry);
        // The joints as the kinematics place them (`Anchors::place`, rotation centre at the
        // platform frame's origin as in eq. 2), the legs from the solver's base joints.
        let anchors = ik::Solver::new(case.geometry.clone())
            .expect("a valid geometry")
            .anchors();
        for _ in 0..300 {
            let pose = rng.pose(&case.range.map(|r| 2.0 * r));
            let q = anchors.place::<Libm>(&pose).joints_mm;
            let l: [Vec3; LEGS] = core::array::from_fn(|i| q[i] - anchors.base_mm[i]);
            let q_ref = reference.platform_joints(&RefPose::from_core(&pose));
            for i in 0..LEGS {
                for c in 0..3 {
                    let b = reference.legs[i].b[c];
                    assert!(
                        (f64::from(q[i][c]) - q_ref[i][c]).abs() <= 1e-4,
                        "{}: q",
                        case.name
                    );
                    assert!(
                        (f64::from(l[i][c]) - (q_ref[i][c] - b)).abs() <= 1e-4,
                        "{}: l",
                        case.name
                    );
                }
            }
        }
    }
}

#[test]
fn angle_limit_is_180_degrees_inclusive() {
    let g = Geometry::default();
    let solver = ik::Solver::new(g.clone()).expect("a valid geometry");
    let servos = ServoSet::default();
    for axis in [Axis::Roll, Axis::Pitch, Axis::Yaw] {
        for v in [PI, -PI] {
            let mut pose = Pose::HOME;
            pose.set(axis, v);
            let got = solver.solve::<Libm>(&servos, &pose);
            assert!(
                !matches!(got, Err(IkError::AngleTooLarge { .. })),
                "{axis:?} {v}: {got:?}"
            );
        }
        let mut pose = Pose::HOME;
        pose.set(axis, f32::from_bits(PI.to_bits() + 1));
        assert!(matches!(
            solver.solve::<Libm>(&servos, &pose),
            Err(IkError::AngleTooLarge { axis: a, .. }) if a == axis
        ));
    }
}

#[test]
fn default_servos_follow_eq_13_and_14() {
    // Even servos add (eq. 13), odd servos subtract (eq. 14), 1600/pi us/rad, 1500 us home.
    let servos = ServoSet::default();
    for (i, s) in servos.0.iter().enumerate() {
        let number = i + 1;
        assert_eq!(s.home_us, 1500.0);
        assert!((f64::from(s.rate_us_per_rad) - 1600.0 / core::f64::consts::PI).abs() < 1e-4);
        let alpha0 = 0.01;
        let alpha = 0.2;
        let w_document = host_tests::reference::eq13_14_pulse_us(
            number,
            1500.0,
            1600.0 / core::f64::consts::PI,
            alpha,
            alpha0,
        );
        let w_ref = pulse_us(s, alpha, alpha0);
        // (The servo's rate is 1600/pi rounded to f32.)
        assert!((w_document - w_ref).abs() < 1e-4, "servo {number}");
        let w_core = f64::from(s.pulse_us(alpha as f32, alpha0 as f32));
        assert!(
            (w_core - w_document).abs() < 1e-3,
            "servo {number}: {w_core} vs {w_document}"
        );
    }
}
