//! Workspace: every excursion the core reports along the twelve axis-directions is checked
//! with the f64 reference on both sides of its bound (reachable within the servo limits at
//! the bound, not one tolerance beyond) and all along the way; the sampled grid likewise.
//! Run with `--nocapture` to see the reaches and the number of IKs they took.

// Legs are numbered; index loops over them read like the equations.
#![allow(clippy::needless_range_loop)]

use host_tests::fixtures::{cases, solver_about, strut_cases, Rng};
use host_tests::platform::{RefAnchors, RefArms};
use host_tests::reference::{pulse_us, RefPose};
use kinematics_core::workspace::{axis_directions, Grid, Limit, Limits, Options, Reach};
use kinematics_core::{ik, IkError, Libm, Pose, ServoSet, Vec3, LEGS};

/// Legs this close to the workspace boundary (mm) or pulses this close to a servo limit (us)
/// may be judged either way by the f32 IK and the f64 reference.
const BAND_MM: f64 = 1e-3;
const BAND_US: f64 = 0.01;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Judged {
    Yes,
    No,
    Either,
}

/// The f64 reference's verdict: every leg reaches and every pulse is within its limits.
fn judge(reference: &RefArms, servos: &ServoSet, pose: &Pose) -> Judged {
    let exact = RefPose::from_core(pose);
    let margins = reference.margins_mm(&exact);
    let leg = margins.iter().fold(f64::INFINITY, |m, v| m.min(*v));
    if leg < -BAND_MM {
        return Judged::No;
    }
    if leg <= BAND_MM {
        return Judged::Either;
    }
    if [pose.roll_rad, pose.pitch_rad, pose.yaw_rad]
        .iter()
        .any(|a| a.abs() > core::f32::consts::PI)
    {
        return Judged::No;
    }
    let alpha = reference.arm_angles(&exact).expect("every leg reaches");
    let mut limit = f64::INFINITY;
    for i in 0..LEGS {
        let s = &servos.0[i];
        let w = pulse_us(s, alpha[i], reference.alpha0[i]);
        limit = limit.min((w - f64::from(s.min_us)).min(f64::from(s.max_us) - w));
    }
    if limit > BAND_US {
        Judged::Yes
    } else if limit < -BAND_US {
        Judged::No
    } else {
        Judged::Either
    }
}

fn run_limits(solver: &ik::Solver, servos: &ServoSet, start: Pose) -> ([Reach<IkError>; 12], u32) {
    let mut limits = Limits::new(start, Options::default());
    let mut tests = 0;
    loop {
        let done = limits.step(|p| {
            tests += 1;
            solver.solve::<Libm>(servos, p).map(|_| ())
        });
        if let Some(all) = done {
            return (all, tests);
        }
    }
}

#[test]
fn every_reported_edge_is_an_edge_for_the_reference() {
    eprintln!();
    let options = Options::default();
    let servos = ServoSet::default();
    for case in cases() {
        for centre in [[0.0, 0.0, 0.0], [0.0, 0.0, 50.0f32]] {
            let solver = solver_about(case.geometry.clone(), Vec3::from(centre));
            let reference = RefArms::from_solver(&solver);
            let mut rng = Rng::new(97);
            let mut starts = vec![Pose::HOME];
            while starts.len() < 4 {
                let p = rng.pose(&case.range.map(|r| 0.5 * r));
                if judge(&reference, &servos, &p) == Judged::Yes
                    && solver.solve::<Libm>(&servos, &p).is_ok()
                {
                    starts.push(p);
                }
            }
            for start in starts {
                let (all, tests) = run_limits(&solver, &servos, start);
                for reach in all {
                    let edge = |d: f32| {
                        let mut p = start;
                        p.set(reach.axis, start.get(reach.axis) + reach.sense.sign() * d);
                        p
                    };
                    let tolerance = if reach.axis.is_angle() {
                        options.tolerance_rad
                    } else {
                        options.tolerance_mm
                    };
                    let at = judge(&reference, &servos, &edge(reach.distance));
                    assert_ne!(at, Judged::No, "{} {start:?} {reach:?}", case.name);
                    // All the way there, at a resolution finer than the march.
                    for k in 0..60 {
                        let d = reach.distance * k as f32 / 60.0;
                        assert_ne!(
                            judge(&reference, &servos, &edge(d)),
                            Judged::No,
                            "{} {start:?} {reach:?} at {d}",
                            case.name
                        );
                    }
                    match reach.limit {
                        Limit::Blocked(cause) => {
                            let beyond =
                                judge(&reference, &servos, &edge(reach.distance + tolerance));
                            assert_ne!(beyond, Judged::Yes, "{} {start:?} {reach:?}", case.name);
                            // The cause is the core's answer one tolerance out.
                            assert!(matches!(
                                cause,
                                IkError::Unreachable { .. }
                                    | IkError::ServoLimit { .. }
                                    | IkError::AngleTooLarge { .. }
                            ));
                        }
                        Limit::Range => {
                            let far = if reach.axis.is_angle() {
                                options.range_rad
                            } else {
                                options.range_mm
                            };
                            assert_eq!(reach.distance, far);
                        }
                        Limit::Start(e) => panic!("{}: start refused: {e}", case.name),
                    }
                }
                if start == Pose::HOME {
                    let words: Vec<String> = all
                        .iter()
                        .map(|r| {
                            let v = if r.axis.is_angle() {
                                r.extreme(&start).to_degrees()
                            } else {
                                r.extreme(&start)
                            };
                            format!("{}{:+.2}", r.axis.name(), v)
                        })
                        .collect();
                    eprintln!(
                        "{:<46} c={centre:?} home, {tests} IKs: {}",
                        case.name,
                        words.join(" ")
                    );
                }
            }
        }
    }
}

#[test]
fn a_start_out_of_reach_is_reported_for_every_direction() {
    let solver = ik::Solver::new(cases()[0].geometry.clone()).unwrap();
    let servos = ServoSet::default();
    let far = Pose::from_degrees(0.0, 0.0, 80.0, 0.0, 0.0, 0.0);
    let (all, tests) = run_limits(&solver, &servos, far);
    assert_eq!(tests, 1);
    for (reach, (axis, sense)) in all.iter().zip(axis_directions()) {
        assert_eq!((reach.axis, reach.sense), (axis, sense));
        assert!(matches!(
            reach.limit,
            Limit::Start(IkError::Unreachable { .. })
        ));
        assert_eq!(reach.distance, 0.0);
    }
}

/// Struts with strokes: the edges are where a strut reaches the end of its stroke, by the f64
/// lengths.
#[test]
fn strut_edges_are_stroke_ends() {
    let case = &strut_cases()[0];
    let home = case.struts.home_lengths_mm();
    let stroke = kinematics_core::legs::Stroke {
        min_mm: home[0] - 12.0,
        max_mm: home[0] + 12.0,
    };
    let struts = case.struts.with_strokes(stroke);
    let reference = RefAnchors::from_core(&struts.anchors());
    let options = Options::default();
    let mut limits = Limits::new(Pose::HOME, options);
    let all = loop {
        if let Some(all) = limits.step(|p| struts.solve::<Libm>(p).map(|_| ())) {
            break all;
        }
    };
    for reach in all {
        let Limit::Blocked(_) = reach.limit else {
            panic!("{reach:?}");
        };
        let tolerance = if reach.axis.is_angle() {
            options.tolerance_rad
        } else {
            options.tolerance_mm
        };
        let within = |d: f32| {
            let mut p = Pose::HOME;
            p.set(reach.axis, reach.sense.sign() * d);
            let l = reference.strut_lengths(&RefPose::from_core(&p));
            l.iter()
                .map(|l| (l - f64::from(stroke.min_mm)).min(f64::from(stroke.max_mm) - l))
                .fold(f64::INFINITY, f64::min)
        };
        assert!(within(reach.distance) > -1e-4, "{reach:?}");
        assert!(within(reach.distance + tolerance) < 1e-4, "{reach:?}");
    }
}

#[test]
fn the_grid_samples_what_the_reference_reaches() {
    let solver = ik::Solver::new(cases()[0].geometry.clone()).unwrap();
    let reference = RefArms::from_solver(&solver);
    let servos = ServoSet::default();
    let grid = Grid {
        centre: Pose::HOME,
        axes: [
            kinematics_core::pose::Axis::X,
            kinematics_core::pose::Axis::Y,
            kinematics_core::pose::Axis::Z,
        ],
        half_range: [40.0, 40.0, 30.0],
        counts: [21, 21, 11],
    };
    let (mut inside, mut visited) = (0, 0);
    grid.sample(
        |p| solver.solve::<Libm>(&servos, p).map(|_| ()),
        |p, outcome| {
            visited += 1;
            match judge(&reference, &servos, p) {
                Judged::Yes => assert!(outcome.is_ok(), "{p:?}: {outcome:?}"),
                Judged::No => assert!(outcome.is_err(), "{p:?}"),
                Judged::Either => {}
            }
            inside += usize::from(outcome.is_ok());
        },
    );
    assert_eq!(visited, grid.len());
    assert!(inside > 100 && inside < visited, "{inside} of {visited}");
}
