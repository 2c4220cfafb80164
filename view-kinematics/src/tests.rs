//! The view's kinematics against numbers from outside the code: the firmware's `geometry` and
//! `config` listings for the default build (as the page receives them, rounded to 0.001 mm),
//! and the golden pulses of `docs/geometry-and-calibration.md` (computed by an independent f64
//! script) for known poses.

use super::*;
use core::f32::consts::PI;
use kinematics_core::Direction;

/// `geometry` on a board with the default settings: `(b_mm, p_mm, beta_deg)` per leg.
const LISTED_LEGS: [([f32; 3], [f32; 3], f32); LEGS] = [
    ([70.477, -25.652, 0.0], [45.963, -38.567, 0.0], -110.0),
    ([70.477, 25.652, 0.0], [45.963, 38.567, 0.0], 110.0),
    ([-13.024, 73.861, 0.0], [10.419, 59.088, 0.0], 10.0),
    ([-57.453, 48.209, 0.0], [-56.382, 20.521, 0.0], 230.0),
    ([-57.453, -48.209, 0.0], [-56.382, -20.521, 0.0], 130.0),
    ([-13.024, -73.861, 0.0], [10.419, -59.088, 0.0], 350.0),
];

/// `config`'s servo lines for the defaults: trim 1500 us, 509.296 us/rad, odd servos reversed,
/// 1100..1900 us.
fn listed_servo(servo: u8) -> ServoConfig {
    ServoConfig {
        home_us: 1500.0,
        rate_us_per_rad: 509.296,
        direction: if servo % 2 == 0 {
            Direction::Normal
        } else {
            Direction::Reversed
        },
        min_us: 1100.0,
        max_us: 1900.0,
    }
}

fn default_view() -> View {
    let mut view = View::new();
    for (i, (b, p, beta_deg)) in LISTED_LEGS.iter().enumerate() {
        assert!(view.set_leg(
            i,
            Leg {
                base_mm: Vec3::from(*b),
                platform_mm: Vec3::from(*p),
                beta_rad: beta_deg.to_radians(),
            }
        ));
    }
    view.build(20.0, 120.0)
        .expect("the listed default geometry builds");
    for i in 0..LEGS {
        assert!(view.set_servo(i, listed_servo(i as u8 + 1)));
    }
    view
}

/// `(x, y, z, roll, pitch, yaw)` in mm and degrees, and its golden pulses
/// (`docs/geometry-and-calibration.md`).
const GOLDEN: [([f32; 6], [f32; LEGS]); 5] = [
    ([0.0; 6], [1500.0; LEGS]),
    (
        [0.0, 0.0, 10.0, 0.0, 0.0, 0.0],
        [1232.46, 1767.54, 1232.46, 1767.54, 1232.46, 1767.54],
    ),
    (
        [10.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1527.14, 1472.86, 1481.13, 1540.90, 1459.10, 1518.87],
    ),
    (
        [0.0, 0.0, 0.0, 8.0, 0.0, 0.0],
        [1637.87, 1638.89, 1281.34, 1573.53, 1572.42, 1287.02],
    ),
    (
        [4.0, -6.0, 5.0, 3.0, -4.0, 6.0],
        [1365.01, 1778.15, 1243.26, 1611.33, 1491.79, 1572.23],
    ),
];

fn pose_in_degrees(pose: &Pose) -> [f32; 6] {
    let p = pose.to_array();
    [
        p[0],
        p[1],
        p[2],
        p[3].to_degrees(),
        p[4].to_degrees(),
        p[5].to_degrees(),
    ]
}

#[test]
fn golden_pulses_give_their_poses() {
    // Pulses are given to 0.01 us (0.001 degree of arm): the poses within 0.01 mm / degree.
    let mut view = default_view();
    for (expected, pulses) in GOLDEN {
        assert_eq!(view.solve(pulses), Status::Solved, "{expected:?}");
        let found = pose_in_degrees(&view.frame().pose);
        for k in 0..6 {
            assert!(
                (found[k] - expected[k]).abs() < 0.01,
                "pulses {pulses:?}: pose {found:?}, expected {expected:?}"
            );
        }
        assert!(view.frame().rod_error_mm < 1e-3, "{:?}", view.frame());
    }
}

/// Pitch 5 degrees about a pivot 100 mm above the platform's centre: the pulses of the f64
/// reference of `host-tests` (its chain of frames about the pivot, numeric rod closures;
/// `pulse_reference`'s `f64` request), to 0.01 us.
const PIVOT_PITCH_PULSES: [f32; LEGS] = [1549.79, 1450.21, 1512.26, 1618.92, 1381.08, 1487.74];

#[test]
fn with_the_pivot_config_lists_the_pose_found_is_the_pose_about_it() {
    let mut view = default_view();
    assert!(view.set_pivot(Vec3::new(0.0, 0.0, 100.0)));
    assert_eq!(view.solve(PIVOT_PITCH_PULSES), Status::Solved);
    let found = pose_in_degrees(&view.frame().pose);
    let expected = [0.0, 0.0, 0.0, 0.0, 5.0, 0.0];
    for k in 0..6 {
        assert!((found[k] - expected[k]).abs() < 0.01, "{found:?}");
    }
    // The plate's origin has swung under the pivot by (I - R) c: (-100 sin 5, 0,
    // 100 (1 - cos 5)) from (0, 0, h0).
    let pitch = 5f32.to_radians();
    let origin = [
        -100.0 * pitch.sin(),
        0.0,
        118.458 + 100.0 * (1.0 - pitch.cos()),
    ];
    for (got, want) in view.frame().origin_mm.iter().zip(origin) {
        assert!((got - want).abs() < 0.01, "{:?}", view.frame());
    }
    // Without the pivot the same pulses are that placement as a pose about the centre.
    assert!(view.set_pivot(Vec3::zeros()));
    assert_eq!(view.solve(PIVOT_PITCH_PULSES), Status::Solved);
    let found = pose_in_degrees(&view.frame().pose);
    let expected = [origin[0], 0.0, origin[2] - 118.458, 0.0, 5.0, 0.0];
    for k in 0..6 {
        assert!((found[k] - expected[k]).abs() < 0.01, "{found:?}");
    }
    // A pivot the core refuses changes nothing.
    assert!(!view.set_pivot(Vec3::new(f32::NAN, 0.0, 0.0)));
    assert!(!view.set_pivot(Vec3::new(0.0, 0.0, 20_000.0)));
    assert_eq!(
        view.solver().map(|s| s.rotation_centre_mm()),
        Some(Vec3::zeros())
    );
}

#[test]
fn arm_angles_invert_eq_13_14() {
    let mut view = default_view();
    // Servo 1 is reversed, servo 2 normal: 100 us is 100 / 509.296 rad either way.
    let step_deg = (100.0 / 509.296f32).to_degrees();
    view.solve([1400.0, 1600.0, 1500.0, 1500.0, 1500.0, 1500.0]);
    let alpha0_deg = view.solver().map(|s| s.alpha0_rad(0).to_degrees());
    let alpha0_deg = alpha0_deg.expect("built");
    assert!(
        (alpha0_deg - -0.252).abs() < 0.001,
        "listed alpha0: {alpha0_deg}"
    );
    let arm = view.frame().arm_rad.map(f32::to_degrees);
    assert!((arm[0] - (alpha0_deg + step_deg)).abs() < 1e-3, "{arm:?}");
    assert!((arm[1] - (alpha0_deg + step_deg)).abs() < 1e-3, "{arm:?}");
    assert!((arm[2] - alpha0_deg).abs() < 1e-3, "{arm:?}");
}

#[test]
fn arm_tips_follow_eq_4_to_6() {
    let mut view = default_view();
    assert_eq!(view.solve(GOLDEN[1].1), Status::Solved);
    let frame = *view.frame();
    for (i, (b, _, beta_deg)) in LISTED_LEGS.iter().enumerate() {
        let (alpha, beta) = (frame.arm_rad[i], beta_deg.to_radians());
        let expected = [
            b[0] + 20.0 * alpha.cos() * beta.cos(),
            b[1] + 20.0 * alpha.cos() * beta.sin(),
            b[2] + 20.0 * alpha.sin(),
        ];
        for (tip, expected) in frame.tips_mm[i].iter().zip(expected) {
            assert!((tip - expected).abs() < 1e-3, "leg {}", i + 1);
        }
        // And each rod closes: |q_i - A_i| = s.
        assert!(((frame.joints_mm[i] - frame.tips_mm[i]).norm() - 120.0).abs() < 1e-3);
    }
}

#[test]
fn nothing_is_solved_before_the_listings() {
    let mut view = View::new();
    assert_eq!(view.solve([1500.0; LEGS]), Status::NoGeometry);
    let mut view = default_view();
    view.servos[3] = None;
    assert_eq!(view.solve([1500.0; LEGS]), Status::NoServos);
    assert!(!view.set_servo(6, listed_servo(1)), "servo 7");
    let mut bad = listed_servo(1);
    bad.rate_us_per_rad = 0.0;
    assert!(!view.set_servo(0, bad), "a zero rate is refused");
}

#[test]
fn a_pin_without_a_pulse_is_no_pose() {
    let mut view = default_view();
    let mut pulses = [1500.0; LEGS];
    pulses[4] = f32::NAN;
    assert_eq!(view.solve(pulses), Status::BadPulse);
}

#[test]
fn a_missing_leg_is_named() {
    let mut view = View::new();
    for i in [0, 1, 2, 4, 5] {
        view.set_leg(
            i,
            Leg {
                base_mm: Vec3::from(LISTED_LEGS[i].0),
                platform_mm: Vec3::from(LISTED_LEGS[i].1),
                beta_rad: 0.0,
            },
        );
    }
    assert_eq!(
        view.build(20.0, 120.0),
        Err(BuildError::MissingLeg { leg: 4 })
    );
    assert_eq!(view.solve([1500.0; LEGS]), Status::NoGeometry);
}

#[test]
fn impossible_arm_angles_are_no_solution_and_keep_the_last_pose() {
    // The default layout with rods of only s = 30 mm (a valid build: h0 = 23 mm). Turned half a
    // turn from home, the arms of servos 1 and 2 point at each other and their tips are 13.7 mm
    // apart, while their platform joints are 77.1 mm apart: two 30 mm rods cannot span that.
    let mut view = default_view();
    view.build(20.0, 30.0).expect("a valid geometry");
    assert_eq!(view.solve([1500.0; LEGS]), Status::Solved);
    let home = view.frame().pose;
    assert!(
        pose_in_degrees(&home).iter().all(|v| v.abs() < 1e-3),
        "{home:?}"
    );

    let alpha0 = view.solver().map(|s| [s.alpha0_rad(0), s.alpha0_rad(1)]);
    let alpha0 = alpha0.expect("built");
    let mut pulses = [1500.0; LEGS];
    pulses[0] = 1500.0 - 509.296 * (PI - alpha0[0]); // servo 1 reversed (eq. 14)
    pulses[1] = 1500.0 + 509.296 * (PI - alpha0[1]); // servo 2 normal (eq. 13)
    assert_eq!(view.solve(pulses), Status::NoSolution);
    let frame = view.frame();
    let tips_apart = (frame.tips_mm[0] - frame.tips_mm[1]).norm();
    let joints_apart = (Vec3::from(LISTED_LEGS[0].1) - Vec3::from(LISTED_LEGS[1].1)).norm();
    assert!(
        tips_apart + 2.0 * 30.0 < joints_apart,
        "{tips_apart} mm, {joints_apart} mm"
    );
    assert_eq!(frame.pose, home, "the last pose found is kept");

    // Back to possible pulses, the platform is found again.
    assert_eq!(view.solve([1500.0; LEGS]), Status::Solved);
}
