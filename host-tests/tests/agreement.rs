//! The core's f32 IK against the numeric f64 reference, over thousands of seeded random poses
//! on several geometries. Run with `--nocapture` to see the measured errors.

use host_tests::fixtures::{cases, Case, Rng};
use host_tests::reference::{Expectation, RefGeometry, RefPose};
use kinematics_core::{ik, IkError, Libm, Pose, ServoSet, LEGS};

// The arm-angle tolerance within the servo travel is per geometry: `Case::angle_tol_deg`.
/// Largest pulse error accepted, us (eq. 13/14 difference `alpha - alpha0`, where much of the
/// f32 error cancels).
const PULSE_TOL_US: f64 = 0.01;
/// Where arm angles are ill-conditioned (near the workspace boundary, arm and rod in line), an
/// angle error is judged by the joint displacement it is equivalent to:
/// `|d alpha| * |dg/dalpha| / (2 s)`, mm. This is the f32 resolution of the joint position.
const JOINT_TOL_MM: f64 = 1e-4;
/// Legs within this distance of the workspace boundary may be judged either way, mm.
const BAND_MM: f64 = 1e-4;
/// Pulses within this distance of a servo limit may be judged either way, us.
const BAND_US: f64 = 0.01;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Judged {
    Yes,
    No,
    Either,
}

fn judge(margin: f64, band: f64) -> Judged {
    if margin > band {
        Judged::Yes
    } else if margin < -band {
        Judged::No
    } else {
        Judged::Either
    }
}

#[derive(Debug, Default)]
struct Tally {
    poses: usize,
    ok: usize,
    unreachable: usize,
    servo_limit: usize,
    in_band: usize,
    max_angle_deg: f64,
    max_pulse_us: f64,
    max_joint_mm: f64,
    max_eq9_rad: f64,
    worst_angle_pose: Option<Pose>,
}

impl Tally {
    fn print(&self, name: &str) {
        let mut line = format!(
            "{name:<46} {:>6} poses: {:>6} ok, {:>5} unreachable, {:>5} servo limit, {:>3} in band | \
             max |d alpha| {:.2e} deg, max joint-equivalent {:.2e} mm",
            self.poses,
            self.ok,
            self.unreachable,
            self.servo_limit,
            self.in_band,
            self.max_angle_deg,
            self.max_joint_mm,
        );
        // Pulses and eq. 9 are only compared by the `solve` checks.
        if self.max_pulse_us > 0.0 {
            line += &format!(
                ", max |d W| {:.2e} us, eq. 9 vs numeric {:.1e} rad",
                self.max_pulse_us, self.max_eq9_rad
            );
        }
        eprintln!("{line}");
    }
}

/// Checks `ik::Solver::solve` for one pose against the reference; returns a description on
/// failure. `solver` is the IK of `case.geometry`.
fn check_solve(
    case: &Case,
    solver: &ik::Solver,
    reference: &RefGeometry,
    servos: &ServoSet,
    pose: &Pose,
    tally: &mut Tally,
) -> Result<(), String> {
    let rpose = RefPose::from_core(pose);
    let expect = Expectation::new(reference, servos, &rpose);
    let reach: [Judged; LEGS] = core::array::from_fn(|i| judge(expect.leg_margin_mm(i), BAND_MM));
    let limit: [Judged; LEGS] = core::array::from_fn(|i| match reach[i] {
        Judged::No => Judged::No,
        _ if expect.limit_margin_us[i].is_nan() => Judged::Either,
        _ => judge(expect.limit_margin_us[i], BAND_US),
    });
    if reach.contains(&Judged::Either) || limit.contains(&Judged::Either) {
        tally.in_band += 1;
    }
    let got = solver.solve::<Libm>(servos, pose);
    tally.poses += 1;
    match got {
        Ok(sol) => {
            tally.ok += 1;
            if let Some(i) = (0..LEGS).find(|&i| reach[i] == Judged::No) {
                return Err(format!(
                    "Ok, but the reference says leg {} cannot reach",
                    i + 1
                ));
            }
            if let Some(i) = (0..LEGS).find(|&i| limit[i] == Judged::No) {
                return Err(format!(
                    "Ok, but the reference puts servo {} at {:.4} us, outside its limits",
                    i + 1,
                    expect.pulse_us[i]
                ));
            }
            let eq9 = reference.eq9_arm_angles(&rpose);
            for (i, e9) in eq9.iter().enumerate() {
                let Ok(root) = expect.legs[i] else { continue };
                let d_alpha = (f64::from(sol.arm_rad[i]) - root.alpha).abs();
                let d_pulse = (f64::from(sol.pulse_us[i]) - expect.pulse_us[i]).abs();
                let joint_mm = d_alpha * root.slope.abs() / (2.0 * reference.rod);
                if d_alpha.to_degrees() > tally.max_angle_deg {
                    tally.max_angle_deg = d_alpha.to_degrees();
                    tally.worst_angle_pose = Some(*pose);
                }
                tally.max_pulse_us = tally.max_pulse_us.max(d_pulse);
                tally.max_joint_mm = tally.max_joint_mm.max(joint_mm);
                if d_alpha.to_degrees() > case.angle_tol_deg || d_pulse > PULSE_TOL_US {
                    return Err(format!(
                        "leg {}: core alpha {:.7} deg W {:.4} us, reference {:.7} deg {:.4} us",
                        i + 1,
                        f64::from(sol.arm_rad[i]).to_degrees(),
                        sol.pulse_us[i],
                        root.alpha.to_degrees(),
                        expect.pulse_us[i]
                    ));
                }
                // The physical branch is also the solution nearer the home arm angle.
                let alpha0 = reference.alpha0[i];
                if (root.alpha - alpha0).abs() >= (root.other - alpha0).abs() {
                    return Err(format!("leg {}: the other root is nearer alpha0", i + 1));
                }
                // Both references agree: the literal eq. 9 gives the same root.
                let e9 = e9.ok_or(format!("leg {}: eq. 9 has no solution", i + 1))?;
                tally.max_eq9_rad = tally.max_eq9_rad.max((e9 - root.alpha).abs());
                if (e9 - root.alpha).abs() > 1e-9 {
                    return Err(format!(
                        "leg {}: eq. 9 gives {e9}, numeric root {}",
                        i + 1,
                        root.alpha
                    ));
                }
            }
        }
        Err(IkError::Unreachable { leg }) => {
            tally.unreachable += 1;
            let k = usize::from(leg) - 1;
            if reach[k] == Judged::Yes {
                return Err(format!(
                    "Unreachable {{ leg: {leg} }}, but the reference reaches it with {:.3e} mm to spare",
                    expect.leg_margin_mm(k)
                ));
            }
            if let Some(i) = (0..k).find(|&i| reach[i] == Judged::No) {
                return Err(format!(
                    "Unreachable {{ leg: {leg} }}, but leg {} is the first that cannot reach",
                    i + 1
                ));
            }
        }
        Err(IkError::ServoLimit {
            servo,
            pulse_us,
            min_us,
            max_us,
        }) => {
            tally.servo_limit += 1;
            let k = usize::from(servo) - 1;
            if let Some(i) = (0..LEGS).find(|&i| reach[i] == Judged::No) {
                return Err(format!(
                    "ServoLimit {{ servo: {servo} }}, but leg {} cannot reach at all",
                    i + 1
                ));
            }
            if limit[k] == Judged::Yes {
                return Err(format!(
                    "ServoLimit {{ servo: {servo}, pulse_us: {pulse_us} }}, but the reference needs {:.4} us, within limits",
                    expect.pulse_us[k]
                ));
            }
            if let Some(i) = (0..k).find(|&i| limit[i] == Judged::No) {
                return Err(format!(
                    "ServoLimit {{ servo: {servo} }}, but servo {} is the first outside its limits",
                    i + 1
                ));
            }
            // Far outside the servo travel the arm may be close to in line with its rod, where
            // the angle is ill-conditioned: allow the joint-equivalent tolerance there.
            let tol_us = match expect.legs[k] {
                Ok(root) => PULSE_TOL_US.max(
                    f64::from(servos.0[k].rate_us_per_rad) * JOINT_TOL_MM * 2.0 * reference.rod
                        / root.slope.abs(),
                ),
                Err(_) => PULSE_TOL_US,
            };
            if (f64::from(pulse_us) - expect.pulse_us[k]).abs() > tol_us {
                return Err(format!(
                    "ServoLimit reports {pulse_us} us, the reference needs {:.4} us",
                    expect.pulse_us[k]
                ));
            }
            if (min_us, max_us) != (servos.0[k].min_us, servos.0[k].max_us) {
                return Err("ServoLimit reports the wrong limits".to_string());
            }
        }
        Err(other) => return Err(format!("unexpected error {other:?}")),
    }
    Ok(())
}

#[test]
fn solve_agrees_with_the_numeric_reference_over_realistic_poses() {
    let servos = ServoSet::default();
    eprintln!("\nsolve() vs the numeric f64 reference (default servos, +-45 deg travel):");
    for (n, case) in cases().iter().enumerate() {
        let reference = RefGeometry::from_core(&case.geometry);
        let solver = ik::Solver::new(case.geometry.clone()).expect("a valid geometry");
        // The default geometry gets the most poses; the others a few thousand each.
        let samples = if n == 0 { 9000 } else { 2500 };
        let mut rng = Rng::new(0x5EED_0001 + n as u64);
        let mut tally = Tally::default();
        for _ in 0..samples {
            let pose = rng.pose(&case.range);
            if let Err(why) = check_solve(case, &solver, &reference, &servos, &pose, &mut tally) {
                panic!("{}: pose {pose:?}: {why}", case.name);
            }
        }
        tally.print(case.name);
        if n == 0 {
            assert!(tally.ok >= 5000, "too few reachable poses: {}", tally.ok);
            eprintln!("  worst angle at {:?}", tally.worst_angle_pose);
        } else {
            assert!(tally.ok >= 500, "{}: too few reachable poses", case.name);
        }
        assert!(
            tally.unreachable + tally.servo_limit > 0,
            "{}: no errors exercised",
            case.name
        );
    }
}

#[test]
fn solve_names_the_right_leg_or_servo_outside_the_realistic_range() {
    // Twice the realistic box: most poses fail, by reach or by servo limit.
    let servos = ServoSet::default();
    for (n, case) in cases().iter().enumerate() {
        let reference = RefGeometry::from_core(&case.geometry);
        let solver = ik::Solver::new(case.geometry.clone()).expect("a valid geometry");
        let mut rng = Rng::new(0x5EED_0100 + n as u64);
        let range = case.range.map(|r| 2.0 * r);
        let mut tally = Tally::default();
        for _ in 0..1500 {
            let pose = rng.pose(&range);
            if let Err(why) = check_solve(case, &solver, &reference, &servos, &pose, &mut tally) {
                panic!("{}: pose {pose:?}: {why}", case.name);
            }
        }
        assert!(
            tally.unreachable > 50 && tally.servo_limit > 50 && tally.ok > 10,
            "{}: {tally:?}",
            case.name
        );
    }
}

/// Checks `ik::Solver::arm_angles` (no servo limits) against the reference: same reachability
/// (up to the band), the first unreachable leg named, angles to the f32 resolution of the
/// joint.
fn check_arm_angles(
    solver: &ik::Solver,
    reference: &RefGeometry,
    pose: &Pose,
    tally: &mut Tally,
) -> Result<(), String> {
    let rpose = RefPose::from_core(pose);
    let legs = reference.arm_angles(&rpose);
    let margin = |i: usize| match legs[i] {
        Ok(r) => r.margin_mm,
        Err(u) => u.margin_mm,
    };
    let reach: [Judged; LEGS] = core::array::from_fn(|i| judge(margin(i), BAND_MM));
    if reach.contains(&Judged::Either) {
        tally.in_band += 1;
    }
    tally.poses += 1;
    match solver.arm_angles::<Libm>(pose) {
        Ok(alpha) => {
            tally.ok += 1;
            if let Some(i) = (0..LEGS).find(|&i| reach[i] == Judged::No) {
                return Err(format!(
                    "Ok, but leg {} is {:.3e} mm outside the workspace",
                    i + 1,
                    -margin(i)
                ));
            }
            for i in 0..LEGS {
                let Ok(root) = legs[i] else { continue };
                let d_alpha = (f64::from(alpha[i]) - root.alpha).abs();
                let joint_mm = d_alpha * root.slope.abs() / (2.0 * reference.rod);
                tally.max_angle_deg = tally.max_angle_deg.max(d_alpha.to_degrees());
                tally.max_joint_mm = tally.max_joint_mm.max(joint_mm);
                if joint_mm > JOINT_TOL_MM {
                    return Err(format!(
                        "leg {}: core {:.6} deg, reference {:.6} deg ({joint_mm:.2e} mm at the joint)",
                        i + 1,
                        f64::from(alpha[i]).to_degrees(),
                        root.alpha.to_degrees()
                    ));
                }
            }
        }
        Err(IkError::Unreachable { leg }) => {
            tally.unreachable += 1;
            let k = usize::from(leg) - 1;
            if reach[k] == Judged::Yes {
                return Err(format!(
                    "Unreachable {{ leg: {leg} }}, but it reaches with {:.3e} mm to spare",
                    margin(k)
                ));
            }
            if let Some(i) = (0..k).find(|&i| reach[i] == Judged::No) {
                return Err(format!(
                    "Unreachable {{ leg: {leg} }}, but leg {} is the first that cannot reach",
                    i + 1
                ));
            }
        }
        Err(other) => return Err(format!("unexpected error {other:?}")),
    }
    Ok(())
}

#[test]
fn arm_angles_reach_exactly_where_the_reference_does() {
    eprintln!("\narm_angles() (no servo limits) vs the reference, wide random poses:");
    for (n, case) in cases().iter().enumerate() {
        let reference = RefGeometry::from_core(&case.geometry);
        let solver = ik::Solver::new(case.geometry.clone()).expect("a valid geometry");
        let mut rng = Rng::new(0x5EED_0200 + n as u64);
        let range = case.range.map(|r| 1.8 * r);
        let mut tally = Tally::default();
        for _ in 0..1500 {
            let pose = rng.pose(&range);
            if let Err(why) = check_arm_angles(&solver, &reference, &pose, &mut tally) {
                panic!("{}: pose {pose:?}: {why}", case.name);
            }
        }
        tally.print(case.name);
        assert!(tally.ok > 100 && tally.unreachable > 100, "{tally:?}");
    }
}

#[test]
fn workspace_boundary_is_where_the_reference_puts_it() {
    // Walk out from home along random directions, find the reference's workspace boundary by
    // bisection, then probe just inside and just outside it at relative steps 1e-2 .. 1e-7.
    // Disagreement is allowed only within BAND_MM of the boundary; we report how many probes
    // fell in the band and how far from the boundary the core and reference still disagreed.
    eprintln!("\nworkspace boundary probes:");
    for (n, case) in cases().iter().enumerate() {
        let reference = RefGeometry::from_core(&case.geometry);
        let solver = ik::Solver::new(case.geometry.clone()).expect("a valid geometry");
        let mut rng = Rng::new(0x5EED_0300 + n as u64);
        let mut tally = Tally::default();
        let mut disagreements = 0;
        let mut widest_disagreement_mm: f64 = 0.0;
        for _ in 0..60 {
            let dir: [f64; 6] = core::array::from_fn(|i| rng.symmetric(case.range[i]));
            let at = |t: f64| {
                let v = dir.map(|d| d * t);
                RefPose::from_degrees(v[0], v[1], v[2], v[3], v[4], v[5])
            };
            let reaches = |t: f64| reference.arm_angles(&at(t)).iter().all(Result::is_ok);
            let (mut lo, mut hi) = (0.0, 8.0);
            if reaches(hi) {
                continue;
            }
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if reaches(mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            for k in 2..=7 {
                for side in [-1.0, 1.0] {
                    let pose = at(lo * (1.0 + side * 10f64.powi(-k))).to_core();
                    let before = (tally.ok, tally.unreachable);
                    if let Err(why) = check_arm_angles(&solver, &reference, &pose, &mut tally) {
                        panic!("{}: pose {pose:?}: {why}", case.name);
                    }
                    let core_ok = tally.ok > before.0;
                    let rpose = RefPose::from_core(&pose);
                    let legs = reference.arm_angles(&rpose);
                    let ref_ok = legs.iter().all(Result::is_ok);
                    if core_ok != ref_ok {
                        disagreements += 1;
                        let closest = legs
                            .iter()
                            .map(|l| match l {
                                Ok(r) => r.margin_mm.abs(),
                                Err(u) => u.margin_mm.abs(),
                            })
                            .fold(f64::INFINITY, f64::min);
                        widest_disagreement_mm = widest_disagreement_mm.max(closest);
                    }
                }
            }
        }
        eprintln!(
            "{:<46} {:>4} probes, {:>3} within {BAND_MM:.0e} mm of the boundary, {:>3} judged differently \
             (at most {:.1e} mm from it); max joint-equivalent angle error {:.2e} mm",
            case.name,
            tally.poses,
            tally.in_band,
            disagreements,
            widest_disagreement_mm,
            tally.max_joint_mm
        );
        assert!(tally.poses > 300, "{}: too few boundary probes", case.name);
    }
}

/// A geometry whose six legs are all the same leg: any pose then asks the core about that one
/// leg, so its arm angle can be probed wherever the joint can be put, not only where all six
/// legs of a real layout happen to reach at once.
fn single_leg(leg: kinematics_core::Leg, arm: f32, rod: f32) -> kinematics_core::Geometry {
    kinematics_core::Geometry::new([leg; LEGS], arm, rod).expect("six equal legs agree")
}

/// The pose (no rotation) that puts every joint of a [`single_leg`] geometry at `q`.
fn pose_for_joint(reference: &RefGeometry, q: [f64; 3]) -> Pose {
    let p = reference.legs[0].p;
    Pose {
        x_mm: (q[0] - p[0]) as f32,
        y_mm: (q[1] - p[1]) as f32,
        z_mm: (q[2] - p[2] - reference.h0) as f32,
        ..Pose::HOME
    }
}

#[test]
fn one_leg_agrees_with_the_reference_wherever_its_joint_can_be() {
    // Joints all round the shaft, in the whole shell the rod can reach (and a little beyond
    // both ways): above, level with and below the shaft, in and out of the arm's plane.
    eprintln!("\none leg, joint anywhere within reach (arm_angles, no servo limits):");
    for (n, case) in cases().iter().enumerate() {
        let leg = *case.geometry.leg(n % LEGS);
        let g = single_leg(leg, case.geometry.arm_mm(), case.geometry.rod_mm());
        let reference = RefGeometry::from_core(&g);
        let solver = ik::Solver::new(g.clone()).expect("a valid geometry");
        let (a, s) = (reference.arm, reference.rod);
        let b = reference.legs[0].b;
        let mut rng = Rng::new(0x5EED_0400 + n as u64);
        let mut tally = Tally::default();
        let mut below = 0;
        while tally.poses < 6000 {
            let dir = [rng.symmetric(1.0), rng.symmetric(1.0), rng.symmetric(1.0)];
            let len = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
            if !(0.1..=1.0).contains(&len) {
                continue;
            }
            let radius = s - a - 2.0 + (2.0 * a + 4.0) * rng.unit();
            let q = core::array::from_fn(|c| b[c] + dir[c] * radius / len);
            if q[2] < b[2] {
                below += 1;
            }
            let pose = pose_for_joint(&reference, q);
            if let Err(why) = check_arm_angles(&solver, &reference, &pose, &mut tally) {
                panic!(
                    "{} (leg {} alone): joint at {q:?}: {why}",
                    case.name,
                    n % LEGS + 1
                );
            }
        }
        tally.print(case.name);
        assert!(
            tally.ok > 1000 && tally.unreachable > 1000 && below > 1000,
            "{tally:?}"
        );
    }
}

#[test]
fn half_angle_singularity_below_the_shaft_is_handled() {
    // With the joint below the shaft (M = 2a l_z < 0) there is a surface on which
    // L - N = 0 and M + sqrt(M^2 + N^2 - L^2) = 0 at once: the true angle is alpha = 2 phi
    // (phi = atan2(M, N)), but a half-angle formula tan(alpha/2) = (L - N) / (M + sqrt(...))
    // is 0/0 there and turns f32 rounding noise into any angle. Put the joint on (and a few
    // f32 ulps around) that surface, in the arm's plane (w = 0) and just out of it.
    let g0 = kinematics_core::Geometry::default();
    let g = single_leg(*g0.leg(0), 20.0, 120.0);
    let reference = RefGeometry::from_core(&g);
    let leg = reference.legs[0];
    let (a, s) = (reference.arm, reference.rod);
    let u = [leg.beta.cos(), leg.beta.sin(), 0.0];
    let v = [-leg.beta.sin(), leg.beta.cos(), 0.0];
    let mut tally = Tally::default();
    let solver = ik::Solver::new(g.clone()).expect("a valid geometry");
    for phi_deg in [
        -2.0, -5.0, -10.0, -20.0, -22.0, -30.0, -45.0, -60.0, -80.0, -89.0,
    ] {
        let phi = f64::to_radians(phi_deg);
        // In the arm's plane at distance rho, direction phi: L = R cos(phi) gives
        // rho^2 - 2 a rho cos(phi) + a^2 - s^2 + w^2 = 0.
        for w in [-0.02, -0.003, -0.0004, 0.0, 0.0004, 0.003, 0.02] {
            let half = a * phi.cos();
            let rho = half + (half * half - a * a + s * s - w * w).sqrt();
            let q = core::array::from_fn(|c| {
                leg.b[c]
                    + rho * phi.cos() * u[c]
                    + w * v[c]
                    + if c == 2 { rho * phi.sin() } else { 0.0 }
            });
            let pose = pose_for_joint(&reference, q);
            if let Err(why) = check_arm_angles(&solver, &reference, &pose, &mut tally) {
                panic!(
                    "phi {phi_deg} deg, w {w} mm (true alpha ~ {} deg): {why}",
                    2.0 * phi_deg
                );
            }
        }
    }
    assert_eq!(tally.ok, tally.poses, "{tally:?}");
}
