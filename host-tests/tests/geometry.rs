//! Geometry validation: the core's derived constants h0 (eq. 10) and alpha0 (eq. 12) against
//! f64 references, and every `GeometryError` variant produced by a suitable input and
//! confirmed by the reference where it is a statement about the geometry.

use host_tests::fixtures::{cases, simscape_layout};
use host_tests::reference::{add, dot, solve_leg, sub, RefGeometry, RefGeometryError, RefLeg};
use kinematics_core::geometry::{CircularLayout, Length, PairedLayout, HOME_HEIGHT_TOLERANCE_MM};
use kinematics_core::ik::Solver;
use kinematics_core::{Geometry, GeometryError, Leg, LEGS};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

/// h0 agreement: eq. 10 takes the square root of `s^2 + a^2 - dx^2 - dy^2`; in f32 each of
/// those squares is rounded (relative error 2^-24), so h0 may be off by about
/// `eps (s^2 + a^2 + dx^2 + dy^2) / (2 h0)` - large when the radicand is a small difference
/// of large squares - plus the rounding of h0 itself. We allow 4 such roundings.
fn h0_tolerance(r: &RefGeometry) -> f64 {
    let eps = f64::from(f32::EPSILON);
    let squares = r
        .legs
        .iter()
        .map(|l| {
            let (dx, dy) = (l.p[0] - l.b[0], l.p[1] - l.b[1]);
            r.rod * r.rod + r.arm * r.arm + dx * dx + dy * dy
        })
        .fold(0.0, f64::max);
    4.0 * eps * (squares / (2.0 * r.h0) + r.h0)
}
/// alpha0 agreement for the fixture geometries, degrees (see `tests/agreement.rs`).
const ALPHA0_TOL_DEG: f64 = 1e-4;
/// alpha0 agreement for random layouts, as the joint displacement it is equivalent to
/// (`|d alpha| |dg/dalpha| / 2s`), mm: random layouts include 8 mm arms and rods running far
/// out of the arm's plane, where one f32 ulp of a joint coordinate moves alpha0 much more.
const ALPHA0_JOINT_TOL_MM: f64 = 5e-5;

fn ref_legs(legs: &[Leg; LEGS]) -> [RefLeg; LEGS] {
    core::array::from_fn(|i| RefLeg::from_core(&legs[i]))
}

fn reference_for(legs: &[Leg; LEGS], arm: f32, rod: f32) -> Result<RefGeometry, RefGeometryError> {
    RefGeometry::new(
        ref_legs(legs),
        f64::from(arm),
        f64::from(rod),
        f64::from(HOME_HEIGHT_TOLERANCE_MM),
    )
}

/// How alpha0 is judged.
#[derive(Clone, Copy, PartialEq)]
enum Alpha0Tol {
    Degrees,
    JointEquivalent,
}

/// The IK of a geometry (which derives alpha0 and refuses a home pose out of reach).
fn solver(geometry: &Geometry) -> Solver {
    Solver::new(geometry.clone()).expect("a valid geometry")
}

/// Checks a core geometry's h0 and its IK's alpha0 against eq. 10 / eq. 12 and the numeric
/// root.
fn check_constants(name: &str, solver: &Solver, tol: Alpha0Tol) -> Result<(f64, f64), String> {
    let g = solver.geometry();
    let r = RefGeometry::from_core(g);
    let h0 = f64::from(g.home_height_mm());
    let dh = (h0 - r.h0).abs();
    if dh > h0_tolerance(&r) {
        return Err(format!("{name}: h0 {h0} vs eq. 10 {}", r.h0));
    }
    let mut worst_deg: f64 = 0.0;
    for i in 0..LEGS {
        let a0 = f64::from(solver.alpha0_rad(i));
        let d = (a0 - r.alpha0[i]).abs().to_degrees();
        worst_deg = worst_deg.max(d);
        let leg = &r.legs[i];
        let q = add(leg.p, [0.0, 0.0, r.h0]);
        let slope = solve_leg(leg, r.arm, r.rod, q, 0.0)
            .map_err(|_| format!("{name}, leg {}: home unreachable", i + 1))?
            .slope;
        let joint_mm = d.to_radians() * slope.abs() / (2.0 * r.rod);
        let bad = match tol {
            Alpha0Tol::Degrees => d > ALPHA0_TOL_DEG,
            Alpha0Tol::JointEquivalent => joint_mm > ALPHA0_JOINT_TOL_MM,
        };
        if bad {
            return Err(format!(
                "{name}, leg {}: alpha0 {} deg vs numeric {} deg",
                i + 1,
                a0.to_degrees(),
                r.alpha0[i].to_degrees()
            ));
        }
        // The two f64 references agree: eq. 12 (each leg at its own eq. 10 height) and the
        // numeric root at the common h0 differ only by the legs' f32-sized height spread.
        let spread = (r.leg_home_heights[i] - r.h0).abs();
        if (r.alpha0_eq12[i] - r.alpha0[i]).abs() > 1e-9 + spread / r.arm {
            return Err(format!(
                "{name}, leg {}: eq. 12 disagrees with the numeric root",
                i + 1
            ));
        }
        // Home is where arm and rod are at right angles (the definition behind eq. 10), exactly
        // so when the legs agree on h0.
        let tip = leg.arm_tip(r.arm, a0);
        let (arm, rod) = (sub(tip, leg.b), sub(q, tip));
        let cos = dot(arm, rod) / (r.arm * r.rod);
        if spread < 1e-4 && cos.abs() > 1e-5 {
            return Err(format!(
                "{name}, leg {}: arm/rod cosine {cos:e} at home",
                i + 1
            ));
        }
    }
    Ok((dh, worst_deg))
}

#[test]
fn home_height_and_arm_angle_match_eq_10_and_12() {
    eprintln!();
    for case in cases() {
        let solver = solver(&case.geometry);
        let (dh, da) = check_constants(case.name, &solver, Alpha0Tol::Degrees)
            .unwrap_or_else(|e| panic!("{e}"));
        eprintln!(
            "{:<46} h0 {:>9.4} mm (off by {dh:.1e}), alpha0 {:>8.4} deg (off by {da:.1e})",
            case.name,
            case.geometry.home_height_mm(),
            f64::from(solver.alpha0_rad(0)).to_degrees()
        );
    }
}

#[test]
fn paired_layout_arms_are_level_when_the_documented_condition_holds() {
    // PairedLayout's documentation: alpha0 = 0 exactly when
    // platform_radius * sin(60 - base_half_angle - platform_half_angle) = arm.
    for (rb, hb, rp, hp, s) in [
        (75.0, 20.0, 60.0, 20.0, 120.0),
        (100.0, 10.0, 80.0, 15.0, 160.0),
    ] {
        let arm = (rp * (60.0f64 - hb - hp).to_radians().sin()) as f32;
        let layout = PairedLayout {
            base_radius_mm: rb as f32,
            base_half_angle_deg: hb as f32,
            platform_radius_mm: rp as f32,
            platform_half_angle_deg: hp as f32,
            arm_mm: arm,
            rod_mm: s as f32,
        };
        let g = solver(&layout.build().expect("valid"));
        let r = RefGeometry::from_core(g.geometry());
        for i in 0..LEGS {
            assert!(
                r.alpha0[i].to_degrees().abs() < 1e-4,
                "reference leg {}: {}",
                i + 1,
                r.alpha0[i]
            );
            assert!(
                f64::from(g.alpha0_rad(i)).to_degrees().abs() < 2e-4,
                "core leg {}",
                i + 1
            );
        }
    }
}

proptest! {
    #![proptest_config(Config {
        cases: 256,
        rng_seed: RngSeed::Fixed(7),
        failure_persistence: None,
        ..Config::default()
    })]

    /// Random paired and circular layouts: the core accepts exactly what the reference
    /// accepts, and then agrees on h0 and alpha0.
    #[test]
    fn random_layouts_are_judged_and_derived_like_the_reference(
        rb in 30.0f32..160.0, hb in 0.0f32..55.0, rp in 20.0f32..140.0, hp in 0.0f32..55.0,
        arm in 8.0f32..45.0, rod in 40.0f32..260.0,
    ) {
        let layout = PairedLayout {
            base_radius_mm: rb,
            base_half_angle_deg: hb,
            platform_radius_mm: rp,
            platform_half_angle_deg: hp,
            arm_mm: arm,
            rod_mm: rod,
        };
        let legs = layout.circular().legs();
        let reference = reference_for(&legs, arm, rod);
        match (layout.build().and_then(Solver::new), reference) {
            (Ok(g), Ok(_)) => {
                check_constants("random layout", &g, Alpha0Tol::JointEquivalent).map_err(TestCaseError::fail)?;
            }
            (Err(GeometryError::NoHomeHeight { leg }), Err(RefGeometryError::NoHomeHeight { leg: r })) => {
                prop_assert_eq!(usize::from(leg), r);
            }
            (Err(GeometryError::HomeUnreachable { leg }), Err(RefGeometryError::HomeUnreachable { leg: r })) => {
                prop_assert_eq!(usize::from(leg), r);
            }
            (core, reference) => {
                // A symmetric layout never has disagreeing legs; anything else must be a
                // borderline case (a radicand or reach margin at f32 rounding level).
                let radicand = |l: &RefLeg| {
                    let (dx, dy) = (l.p[0] - l.b[0], l.p[1] - l.b[1]);
                    f64::from(rod).powi(2) + f64::from(arm).powi(2) - dx * dx - dy * dy
                };
                let closest = ref_legs(&legs).iter().map(|l| radicand(l).abs()).fold(f64::INFINITY, f64::min);
                prop_assert!(closest < 1e-2, "core {core:?} vs reference {reference:?}");
            }
        }
    }
}

#[test]
fn every_geometry_error_variant_is_produced_and_named() {
    let paired = PairedLayout::default();
    let legs = paired.circular().legs();

    // BadLength, for each length, for zero, negative, NaN and infinite values.
    for bad in [0.0, -1.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let arm = Geometry::new(legs, bad, 120.0);
        assert!(
            matches!(arm, Err(GeometryError::BadLength { which: Length::Arm, value_mm }) if value_mm.to_bits() == bad.to_bits()),
            "{arm:?}"
        );
        let rod = Geometry::new(legs, 20.0, bad);
        assert!(
            matches!(
                rod,
                Err(GeometryError::BadLength {
                    which: Length::Rod,
                    ..
                })
            ),
            "{rod:?}"
        );
        let base = CircularLayout {
            base_radius_mm: bad,
            ..paired.circular()
        }
        .build();
        assert!(
            matches!(
                base,
                Err(GeometryError::BadLength {
                    which: Length::BaseRadius,
                    ..
                })
            ),
            "{base:?}"
        );
        let platform = PairedLayout {
            platform_radius_mm: bad,
            ..paired
        }
        .build();
        assert!(
            matches!(
                platform,
                Err(GeometryError::BadLength {
                    which: Length::PlatformRadius,
                    ..
                })
            ),
            "{platform:?}"
        );
    }
    // The smallest positive lengths are lengths (they then fail for geometric reasons).
    assert!(!matches!(
        Geometry::new(legs, f32::MIN_POSITIVE, 120.0),
        Err(GeometryError::BadLength { .. })
    ));

    // NonFiniteLeg: each leg, each kind of field.
    for leg in 0..LEGS {
        for field in 0..3 {
            let mut l = legs;
            match field {
                0 => l[leg].base_mm.y = f32::NAN,
                1 => l[leg].platform_mm.z = f32::INFINITY,
                _ => l[leg].beta_rad = f32::NEG_INFINITY,
            }
            assert_eq!(
                Geometry::new(l, 20.0, 120.0),
                Err(GeometryError::NonFiniteLeg { leg: leg as u8 + 1 })
            );
        }
    }

    // NoHomeHeight: the rod too short for every leg (leg 1 named first), or one joint moved
    // out of reach of its rod; the reference agrees which leg.
    for (l, rod, want) in [
        (legs, 10.0, 1),
        (moved(legs, 3, |leg| leg.platform_mm.y += 200.0), 120.0, 4),
    ] {
        assert_eq!(
            Geometry::new(l, 20.0, rod),
            Err(GeometryError::NoHomeHeight { leg: want })
        );
        assert_eq!(
            reference_for(&l, 20.0, rod),
            Err(RefGeometryError::NoHomeHeight {
                leg: usize::from(want)
            })
        );
    }

    // LegsDisagree: raising one platform joint by dz lowers that leg's eq. 10 height by
    // exactly dz. Within the tolerance the geometry is accepted with h0 the legs' mean.
    let tol = f64::from(HOME_HEIGHT_TOLERANCE_MM);
    let within = moved(legs, 2, |leg| leg.platform_mm.z = 0.09);
    let g = solver(&Geometry::new(within, 20.0, 120.0).expect("0.09 mm is within the tolerance"));
    check_constants("leg 3 raised 0.09 mm", &g, Alpha0Tol::Degrees)
        .unwrap_or_else(|e| panic!("{e}"));
    let beyond = moved(legs, 2, |leg| leg.platform_mm.z = 0.11);
    match Geometry::new(beyond, 20.0, 120.0) {
        Err(GeometryError::LegsDisagree {
            leg: 3,
            home_height_mm,
            leg1_home_height_mm,
        }) => {
            let r = ref_legs(&beyond);
            let h = |i: usize| r[i].eq10_home_height(20.0, 120.0).expect("has a height");
            assert!(
                (f64::from(home_height_mm) - h(2)).abs() < 1e-4,
                "{home_height_mm} vs {}",
                h(2)
            );
            assert!((f64::from(leg1_home_height_mm) - h(0)).abs() < 1e-4);
            assert!((h(0) - h(2) - 0.11).abs() < 1e-5);
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        reference_for(&beyond, 20.0, 120.0),
        Err(RefGeometryError::LegsDisagree { leg: 3, diff_mm }) if diff_mm > tol
    ));
    let far = moved(legs, 5, |leg| leg.platform_mm.x += 10.0);
    assert!(matches!(
        Geometry::new(far, 20.0, 120.0),
        Err(GeometryError::LegsDisagree { leg: 6, .. })
    ));

    // HomeUnreachable: the platform joints straight out from the shafts, 121.5 mm away
    // horizontally, arms tangential (across the offset). Eq. 10 still gives a height (6.1 mm),
    // but then the joint is 6.1 mm above the shaft in the arm's plane and 121.5 mm out of it:
    // the nearest arm-tip position is sqrt(121.5^2 + (20 - 6.1)^2) = 122.3 mm > s away.
    let angles = [0.0, 60.0, 120.0, 180.0, 240.0, 300.0];
    let out_of_reach = CircularLayout {
        base_radius_mm: 10.0,
        platform_radius_mm: 131.5,
        base_angles_deg: angles,
        platform_angles_deg: angles,
        beta_deg: angles.map(|a| a + 90.0),
        arm_mm: 20.0,
        rod_mm: 120.0,
    };
    assert_eq!(
        out_of_reach.build().and_then(Solver::new),
        Err(GeometryError::HomeUnreachable { leg: 1 })
    );
    assert_eq!(
        reference_for(&out_of_reach.legs(), 20.0, 120.0),
        Err(RefGeometryError::HomeUnreachable { leg: 1 })
    );
    // ...and a shorter offset (121 mm is still beyond, 110 mm is not) is fine again.
    let reachable = CircularLayout {
        platform_radius_mm: 120.0,
        ..out_of_reach
    };
    let g = solver(&reachable.build().expect("reachable"));
    check_constants("radial rods", &g, Alpha0Tol::JointEquivalent)
        .unwrap_or_else(|e| panic!("{e}"));

    // Every error displays something that names what is wrong.
    for e in [
        GeometryError::NonFiniteLeg { leg: 2 },
        GeometryError::NoHomeHeight { leg: 5 },
        GeometryError::HomeUnreachable { leg: 6 },
    ] {
        let text = e.to_string();
        let leg = match e {
            GeometryError::NonFiniteLeg { leg }
            | GeometryError::NoHomeHeight { leg }
            | GeometryError::HomeUnreachable { leg } => leg,
            _ => unreachable!(),
        };
        assert!(text.contains(&format!("leg {leg}")), "{text}");
    }
}

#[test]
fn simscape_layouts_both_ways_round_share_h0_not_alpha0() {
    // h0 (eq. 10) does not depend on the arm direction; alpha0 (eq. 12) does.
    let out = solver(&simscape_layout(true).build().expect("valid"));
    let inward = solver(&simscape_layout(false).build().expect("valid"));
    assert_eq!(
        out.geometry().home_height_mm(),
        inward.geometry().home_height_mm()
    );
    let (a, b) = (
        RefGeometry::from_core(out.geometry()).alpha0[0],
        RefGeometry::from_core(inward.geometry()).alpha0[0],
    );
    assert!((a - b).abs() > 0.1, "{a} vs {b}");
    assert!((f64::from(out.alpha0_rad(0)) - a).abs().to_degrees() < ALPHA0_TOL_DEG);
    assert!((f64::from(inward.alpha0_rad(0)) - b).abs().to_degrees() < ALPHA0_TOL_DEG);
}

fn moved(mut legs: [Leg; LEGS], index: usize, change: impl FnOnce(&mut Leg)) -> [Leg; LEGS] {
    change(&mut legs[index]);
    legs
}
