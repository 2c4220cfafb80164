//! Statics and dynamics against the f64 reference: joint forces by virtual work
//! (`f . dL = w . dX` with `dL` from the reference's IK), holding torques against the work of
//! lifting the payload, stiffness against the Hessian of the legs' spring energy, the
//! displacement under a force at the platform's centre (the report's case) against an f64
//! equilibrium, the cubic configuration against its defining property, and link and arm
//! motions against finite differences along f64 trajectories. Run with `--nocapture` to see the
//! measured errors.

// Legs are numbered; index loops over them read like the equations.
#![allow(clippy::needless_range_loop)]

use host_tests::fixtures::{cases, solver_about, strut_cases, Rng, CENTRES_MM};
use host_tests::platform::{apply, moved, solve6, RefAnchors, RefArms, M6};
use host_tests::reference::{RefPose, V3};
use kinematics_core::configuration::CubicConfiguration;
use kinematics_core::dynamics::{actuation, arm_motions, strut_motions, Acceleration};
use kinematics_core::jacobian::Jacobian;
use kinematics_core::legs::Struts;
use kinematics_core::rates::Twist;
use kinematics_core::statics::{
    compliance, displacement_under_central_force, holding_loads, joint_forces,
    servo_holding_torques, stiffness, Payload, Wrench, GRAVITY_MM_S2,
};
use kinematics_core::{ik, Libm, Mat3, Pose, Vec3, LEGS};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

type JointFn = Box<dyn Fn(&RefPose) -> Option<[f64; LEGS]>>;
type ForceFn = Box<dyn Fn(&Pose, &Wrench) -> Option<[f32; LEGS]>>;

/// A platform the statics run on: the core's joint forces and the f64 joint function (strut
/// lengths, or arm angles away from dead centre), with the pose box.
struct Platform {
    name: String,
    forces: ForceFn,
    joints: JointFn,
    range: [f64; 6],
}

/// Struts, and servos with centres.
fn platforms() -> Vec<Platform> {
    let mut out = Vec::new();
    for case in strut_cases() {
        let struts = case.struts;
        let reference = RefAnchors::from_core(&struts.anchors());
        out.push(Platform {
            name: case.name.to_string(),
            forces: Box::new(move |p, w| joint_forces::<Libm, _>(&struts, p, w).ok()),
            joints: Box::new(move |p| Some(reference.strut_lengths(p))),
            range: case.range,
        });
    }
    for case in cases().into_iter().take(3) {
        for c in CENTRES_MM {
            let solver = solver_about(case.geometry.clone(), Vec3::from(c));
            let reference = RefArms::from_solver(&solver);
            let s2 = solver.clone();
            out.push(Platform {
                name: format!("{} c={c:?}", case.name),
                forces: Box::new(move |p, w| joint_forces::<Libm, _>(&s2, p, w).ok()),
                joints: Box::new(move |p| {
                    // Away from dead centre only: there joint forces are unbounded.
                    let m = reference.margins_mm(p);
                    m.iter()
                        .all(|m| *m > 1.0)
                        .then(|| reference.arm_angles(p))?
                }),
                range: case.range,
            });
        }
    }
    out
}

/// A small random motion `(dv, dw)`, mm and rad.
fn small_motion(rng: &mut Rng, mm: f64, rad: f64) -> [f64; 6] {
    core::array::from_fn(|k| rng.symmetric(if k < 3 { mm } else { rad }))
}

/// The joint motions of a small motion `dx` by central differences of `f`.
fn joint_change(
    f: &dyn Fn(&RefPose) -> Option<[f64; LEGS]>,
    pose: &RefPose,
    dx: &[f64; 6],
) -> Option<[f64; LEGS]> {
    let plus = f(&moved(pose, dx))?;
    let minus = f(&moved(pose, &dx.map(|d| -d)))?;
    Some(core::array::from_fn(|i| (plus[i] - minus[i]) / 2.0))
}

/// Virtual work: the joint forces for a wrench do, along any small motion, the work the wrench
/// does: `f . dL = w . dX`, with `dL` from the f64 reference's IK.
#[test]
fn joint_forces_do_the_work_of_the_wrench() {
    eprintln!();
    for Platform {
        name,
        forces,
        joints,
        range,
    } in platforms()
    {
        let mut rng = Rng::new(61);
        let (mut tested, mut worst) = (0, 0.0f64);
        while tested < 200 {
            let pose = rng.pose(&range);
            let exact = RefPose::from_core(&pose);
            if joints(&exact).is_none() {
                continue;
            }
            let w = Wrench {
                force_n: rng.vec3([20.0, 20.0, 40.0]),
                moment_n_mm: rng.vec3([800.0, 800.0, 800.0]),
            };
            let Some(f) = forces(&pose, &w) else { continue };
            // The work of each part separately, so that neither hides the other's error.
            let mut scale = 0.0f64;
            let mut error = 0.0f64;
            for _ in 0..4 {
                let dx = small_motion(&mut rng, 1e-3, 1e-5);
                let Some(dl) = joint_change(&*joints, &exact, &dx) else {
                    continue;
                };
                let work_f: f64 = (0..LEGS).map(|i| f64::from(f[i]) * dl[i]).sum();
                let wv = w.to_vec6();
                let work_w: f64 = (0..6).map(|k| f64::from(wv[k]) * dx[k]).sum();
                let magnitude: f64 = (0..6).map(|k| (f64::from(wv[k]) * dx[k]).abs()).sum();
                scale = scale.max(magnitude);
                error = error.max((work_f - work_w).abs());
            }
            let e = error / scale;
            worst = worst.max(e);
            tested += 1;
            // Measured: up to 4.5e-6 (servo rows lose digits to `d . t`).
            assert!(e < 3e-5, "{name} {pose:?}: relative work error {e:e}");
        }
        eprintln!("{name:<56} virtual work: {worst:.1e} (relative)");
    }
}

/// Holding a payload still: along any small motion the servos' work `tau . d alpha` is the
/// work of lifting the payload's weight, `m g dz_G`, with the centre of mass carried through
/// the f64 chain of frames.
#[test]
fn holding_torques_do_the_work_of_lifting_the_payload() {
    let payload = Payload::point(1.2, Vec3::new(15.0, -10.0, 35.0));
    let mut worst = 0.0f64;
    for c in CENTRES_MM {
        let solver = solver_about(cases()[0].geometry.clone(), Vec3::from(c));
        let reference = RefArms::from_solver(&solver);
        let com: V3 = core::array::from_fn(|k| f64::from(payload.centre_of_mass_mm[k]));
        let weight_n = f64::from(payload.mass_kg) * 9.806_65;
        let mut rng = Rng::new(67);
        let mut tested = 0;
        while tested < 100 {
            let pose = rng.pose(&cases()[0].range);
            let exact = RefPose::from_core(&pose);
            if reference.margins_mm(&exact).iter().any(|m| *m < 1.0) {
                continue;
            }
            let tau = holding_loads::<Libm, _>(&solver, &pose, &payload).unwrap();
            // The same from the IK's arm angles (what a firmware has after driving the pose).
            let arm_rad = solver.arm_angles::<Libm>(&pose).unwrap();
            let again = servo_holding_torques::<Libm>(&solver, &pose, &arm_rad, &payload).unwrap();
            for i in 0..LEGS {
                assert!((tau[i] - again[i]).abs() <= 1e-4 * tau[i].abs().max(1.0));
            }
            for _ in 0..3 {
                let dx = small_motion(&mut rng, 1e-3, 1e-5);
                let dl = joint_change(&|p| reference.arm_angles(p), &exact, &dx).unwrap();
                let work: f64 = (0..LEGS).map(|i| f64::from(tau[i]) * dl[i]).sum();
                let z = |s: f64| {
                    apply(
                        &reference
                            .anchors
                            .transform(&moved(&exact, &dx.map(|d| s * d))),
                        com,
                    )[2]
                };
                let lift = weight_n * (z(1.0) - z(-1.0)) / 2.0;
                let scale = weight_n
                    * (dx[0].abs()
                        + dx[1].abs()
                        + dx[2].abs()
                        + 200.0 * (dx[3].abs() + dx[4].abs() + dx[5].abs()));
                let e = (work - lift).abs() / scale;
                worst = worst.max(e);
                // Measured: up to 3.2e-7.
                assert!(e < 1e-5, "c={c:?} {pose:?}: {work} vs {lift}");
            }
            tested += 1;
        }
    }
    eprintln!("\nholding torques vs the work of lifting: {worst:.1e} (relative)");
    // At home, symmetric payload on the axis: six equal torques, and the default build's
    // (servos at 1500 us, 20 mm arms) need m g / 6 at about the arm's length each.
    let solver = ik::Solver::new(cases()[0].geometry.clone()).unwrap();
    let centred = Payload::point(1.2, Vec3::zeros());
    let tau = holding_loads::<Libm, _>(&solver, &Pose::HOME, &centred).unwrap();
    for t in tau {
        assert!((t - tau[0]).abs() < 1e-3 * tau[0].abs(), "{tau:?}");
    }
    let per_arm = 1.2 * GRAVITY_MM_S2 * 1e-3 / 6.0 * 20.0;
    assert!(
        tau[0] > 0.5 * per_arm && tau[0] < 2.0 * per_arm,
        "{} vs {per_arm}",
        tau[0]
    );
}

/// The spring energy `U = sum k_i (L_i - L_i0)^2 / 2` of the legs about a pose, from the f64
/// IK; its Hessian there (where its gradient vanishes) is the stiffness.
fn energy_hessian(
    joints: &dyn Fn(&RefPose) -> Option<[f64; LEGS]>,
    pose: &RefPose,
    k: &[f64; LEGS],
) -> M6 {
    let rest = joints(pose).unwrap();
    let energy = |dx: &[f64; 6]| {
        let l = joints(&moved(pose, dx)).unwrap();
        (0..LEGS)
            .map(|i| 0.5 * k[i] * (l[i] - rest[i]).powi(2))
            .sum::<f64>()
    };
    let h = |j: usize| if j < 3 { 1e-3 } else { 1e-5 };
    let mut out = [[0.0; 6]; 6];
    for a in 0..6 {
        for b in 0..6 {
            let at = |sa: f64, sb: f64| {
                let mut dx = [0.0; 6];
                dx[a] += sa * h(a);
                dx[b] += sb * h(b);
                energy(&dx)
            };
            out[a][b] = (at(1.0, 1.0) - at(1.0, -1.0) - at(-1.0, 1.0) + at(-1.0, -1.0))
                / (4.0 * h(a) * h(b));
        }
    }
    out
}

/// `K = J^T diag(k) J` is the Hessian of the legs' spring energy (finite differences of the f64
/// IK), for struts (N/mm) and servos (N mm/rad).
#[test]
fn stiffness_is_the_hessian_of_the_spring_energy() {
    eprintln!();
    let k_struts = [2000.0, 2500.0, 1800.0, 2200.0, 3000.0, 2000.0f32];
    let k_servos = [4.0e4, 5.0e4, 4.5e4, 4.0e4, 6.0e4, 5.0e4f32];
    let mut rng = Rng::new(71);
    let check = |name: &str,
                 j: &Jacobian,
                 joints: &dyn Fn(&RefPose) -> Option<[f64; LEGS]>,
                 pose: &RefPose,
                 k: &[f32; LEGS]| {
        let core = stiffness(j, k).unwrap();
        let exact = energy_hessian(joints, pose, &k.map(f64::from));
        let scale = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut worst = 0.0f64;
        for a in 0..6 {
            for b in 0..6 {
                // Rows and columns in mm or rad: compare each entry to the largest entry of its
                // own block.
                let block = (0..6)
                    .flat_map(|x| (0..6).map(move |y| (x, y)))
                    .filter(|&(x, y)| (x < 3) == (a < 3) && (y < 3) == (b < 3))
                    .map(|(x, y)| exact[x][y].abs())
                    .fold(1e-9 * scale, f64::max);
                let e = (f64::from(core[(a, b)]) - exact[a][b]).abs() / block;
                worst = worst.max(e);
            }
        }
        assert!(
            // Measured: up to 1.8e-6.
            worst < 2e-5,
            "{name}: {worst:e}\ncore {core}\nexact {exact:?}"
        );
        worst
    };
    for case in strut_cases() {
        let reference = RefAnchors::from_core(&case.struts.anchors());
        let mut worst = 0.0f64;
        for _ in 0..20 {
            let pose = rng.pose(&case.range);
            let j = Jacobian::at::<Libm, _>(&case.struts, &pose).unwrap();
            worst = worst.max(check(
                case.name,
                &j,
                &|p| Some(reference.strut_lengths(p)),
                &RefPose::from_core(&pose),
                &k_struts,
            ));
        }
        eprintln!("{:<56} stiffness vs f64 Hessian: {worst:.1e}", case.name);
    }
    let solver = solver_about(cases()[0].geometry.clone(), Vec3::new(0.0, 0.0, 50.0));
    let reference = RefArms::from_solver(&solver);
    let mut worst = 0.0f64;
    let mut tested = 0;
    while tested < 20 {
        let pose = rng.pose(&cases()[0].range);
        let exact = RefPose::from_core(&pose);
        if reference.margins_mm(&exact).iter().any(|m| *m < 2.0) {
            continue;
        }
        let j = Jacobian::at::<Libm, _>(&solver, &pose).unwrap();
        worst = worst.max(check(
            "servos",
            &j,
            &|p| reference.arm_angles(p),
            &exact,
            &k_servos,
        ));
        tested += 1;
    }
    eprintln!(
        "{:<56} stiffness vs f64 Hessian: {worst:.1e}",
        "default servo build, centre +50"
    );
}

/// The report's case: a force at the platform's centre (the platform frame's origin) moves
/// the platform by `C w`; the f64 reference solves `H dX = w` with the Hessian of the spring
/// energy and the moment of the force about the centre from its chain of frames.
#[test]
fn a_force_at_the_centre_moves_the_platform_by_the_compliance() {
    let k = [2000.0f32; LEGS];
    let force = Vec3::new(3.0, -2.0, -25.0);
    let mut rng = Rng::new(73);
    for case in strut_cases() {
        let reference = RefAnchors::from_core(&case.struts.anchors());
        for _ in 0..10 {
            let pose = rng.pose(&case.range);
            let exact = RefPose::from_core(&pose);
            let core = displacement_under_central_force::<Libm, _>(&case.struts, &pose, &k, force)
                .unwrap();
            let h = energy_hessian(
                &|p| Some(reference.strut_lengths(p)),
                &exact,
                &[2000.0; LEGS],
            );
            let origin = apply(&reference.transform(&exact), [0.0; 3]);
            let centre = reference.centre_position(&exact);
            let f: V3 = core::array::from_fn(|k| f64::from(force[k]));
            let arm: V3 = core::array::from_fn(|k| origin[k] - centre[k]);
            let w = [
                f[0],
                f[1],
                f[2],
                arm[1] * f[2] - arm[2] * f[1],
                arm[2] * f[0] - arm[0] * f[2],
                arm[0] * f[1] - arm[1] * f[0],
            ];
            let expected = solve6(&h, &w).unwrap();
            let got = [core.translation_mm, core.rotation_rad];
            for kk in 0..6 {
                let g = f64::from(got[kk / 3][kk % 3]);
                let scale = if kk < 3 { 1e-4 } else { 1e-6 };
                assert!(
                    (g - expected[kk]).abs() < 1e-3 * expected[kk].abs() + scale,
                    "{} {pose:?}: {g} vs {}",
                    case.name,
                    expected[kk]
                );
            }
        }
    }
    // Compliance is the inverse of stiffness.
    let j = Jacobian::at::<Libm, _>(&strut_cases()[0].struts, &Pose::HOME).unwrap();
    let kk = stiffness(&j, &k).unwrap();
    let c = compliance::<Libm>(&kk).unwrap();
    assert!((kk * c - kinematics_core::linalg::Mat6::identity()).amax() < 1e-3);
}

/// The cubic configuration's defining property (the Simscape documentation): at home the
/// struts run along three mutually orthogonal edges of a cube, 1 and 4, 2 and 5, 3 and 6
/// parallel; so about the cube's centre the translational stiffness is `2k` in every direction
/// and uncoupled from rotations. The joints are also compared with a literal f64 transcription
/// of `generateCubicConfiguration`.
#[test]
fn cubic_struts_are_mutually_orthogonal() {
    for cube in [
        CubicConfiguration::SIMSCAPE,
        CubicConfiguration {
            cube_height_mm: 45.0,
            cube_centre_height_mm: 70.0,
            base_height_mm: 10.0,
            platform_depth_mm: 5.0,
            home_height_mm: 120.0,
        },
    ] {
        let struts = Struts::from_cubic(&cube).unwrap();
        let reference = RefAnchors::from_core(&struts.anchors());
        let q = reference.joints(&RefPose::default());
        let unit = |i: usize| {
            let d: V3 = core::array::from_fn(|k| q[i][k] - reference.base[i][k]);
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            d.map(|v| v / n)
        };
        for i in 0..LEGS {
            for j in i + 1..LEGS {
                let dot: f64 = (0..3).map(|k| unit(i)[k] * unit(j)[k]).sum();
                let expected = if j == i + 3 { 1.0 } else { 0.0 };
                assert!(
                    (dot - expected).abs() < 1e-6,
                    "struts {} and {}: {dot}",
                    i + 1,
                    j + 1
                );
            }
        }
        // The documentation's construction, in metres there, mm here.
        let (hc, foc, fha, mhb, h) = (
            f64::from(cube.cube_height_mm),
            f64::from(cube.cube_centre_height_mm),
            f64::from(cube.base_height_mm),
            f64::from(cube.platform_depth_mm),
            f64::from(cube.home_height_mm),
        );
        let norm = |v: V3| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let (sx, sy, sz) = ([2.0, -1.0, -1.0], [0.0, 1.0, -1.0], [1.0, 1.0, 1.0]);
        let rows = [
            sx.map(|v| v / norm(sx)),
            sy.map(|v| v / norm(sy)),
            sz.map(|v| v / norm(sz)),
        ];
        let l = hc * 3f64.sqrt();
        let vertices = [
            [0.0, 0.0, l],
            [l, 0.0, l],
            [l, 0.0, 0.0],
            [l, l, 0.0],
            [0.0, l, 0.0],
            [0.0, l, l],
        ];
        // Cc = R' * vertices - [0; 0; 1.5 Hc], R = [sx sy sz] (columns): R' v = (sx.v, sy.v, sz.v).
        let cc: Vec<V3> = vertices
            .iter()
            .map(|v| {
                let p: V3 = core::array::from_fn(|r| (0..3).map(|k| rows[r][k] * v[k]).sum());
                [p[0], p[1], p[2] - 1.5 * hc]
            })
            .collect();
        let ccf = [cc[0], cc[2], cc[2], cc[4], cc[4], cc[0]];
        let ccm = [cc[1], cc[1], cc[3], cc[3], cc[5], cc[5]];
        for i in 0..LEGS {
            let d: V3 = core::array::from_fn(|k| ccm[i][k] - ccf[i][k]);
            let s = d.map(|v| v / norm(d));
            let fa: V3 = core::array::from_fn(|k| {
                ccf[i][k] + [0.0, 0.0, foc][k] + (fha - (foc - hc / 2.0)) / s[2] * s[k]
            });
            let mb: V3 = core::array::from_fn(|k| {
                ccf[i][k] + [0.0, 0.0, foc - h][k] + (h - mhb - (foc - hc / 2.0)) / s[2] * s[k]
            });
            for k in 0..3 {
                assert!(
                    (reference.base[i][k] - fa[k]).abs() < 1e-4,
                    "leg {} Fa {k}",
                    i + 1
                );
                assert!(
                    (reference.platform[i][k] - mb[k]).abs() < 1e-4,
                    "leg {} Mb {k}",
                    i + 1
                );
            }
        }
        let mut centred = struts;
        centred
            .set_rotation_centre_mm(cube.cube_centre_mm())
            .unwrap();
        let j = Jacobian::at::<Libm, _>(&centred, &Pose::HOME).unwrap();
        let stiff = stiffness(&j, &[1000.0; LEGS]).unwrap();
        for a in 0..3 {
            for b in 0..6 {
                let expected = if a == b { 2000.0 } else { 0.0 };
                assert!(
                    (stiff[(a, b)] - expected).abs() < 0.05,
                    "K[{a}][{b}] = {}",
                    stiff[(a, b)]
                );
            }
        }
    }
}

/// Arm rates and accelerations along a trajectory through a pose with a given twist and
/// acceleration, against second-order finite differences of the f64 IK along it; and the
/// struts' length, joint and link motions likewise.
#[test]
fn motions_follow_the_trajectory() {
    let mut rng = Rng::new(79);
    let motion = |rng: &mut Rng| {
        let twist = Twist {
            linear_mm_s: rng.vec3([50.0, 50.0, 50.0]),
            angular_rad_s: rng.vec3([1.0, 1.0, 1.0]),
        };
        let acceleration = Acceleration {
            linear_mm_s2: rng.vec3([500.0, 500.0, 500.0]),
            angular_rad_s2: rng.vec3([10.0, 10.0, 10.0]),
        };
        (twist, acceleration)
    };
    // The pose at time t: centre at C + v t + a t^2 / 2, orientation exp([w t + alpha t^2 / 2]) R.
    let along = |pose: &RefPose, t: &Twist, a: &Acceleration, time: f64| {
        let (tv, av) = (t.to_vec6(), [a.linear_mm_s2, a.angular_rad_s2]);
        let dx: [f64; 6] = core::array::from_fn(|k| {
            f64::from(tv[k]) * time + 0.5 * f64::from(av[k / 3][k % 3]) * time * time
        });
        moved(pose, &dx)
    };
    // Truncation errors of the differences are dt^2 times third derivatives (up to 1e3 per
    // s^3 here); rounding is 1e-15 / dt^2.
    let dt = 1e-4;
    let solver = solver_about(cases()[0].geometry.clone(), Vec3::new(12.0, -7.5, -35.0));
    let reference = RefArms::from_solver(&solver);
    let mut tested = 0;
    while tested < 200 {
        let pose = rng.pose(&cases()[0].range);
        let exact = RefPose::from_core(&pose);
        if reference.margins_mm(&exact).iter().any(|m| *m < 2.0) {
            continue;
        }
        let (twist, acceleration) = motion(&mut rng);
        let arms = arm_motions::<Libm>(&solver, &pose, &twist, &acceleration).unwrap();
        let at = |s: f64| {
            reference
                .arm_angles(&along(&exact, &twist, &acceleration, s * dt))
                .unwrap()
        };
        let (minus, zero, plus) = (at(-1.0), at(0.0), at(1.0));
        for i in 0..LEGS {
            let rate = (plus[i] - minus[i]) / (2.0 * dt);
            let accel = (plus[i] - 2.0 * zero[i] + minus[i]) / (dt * dt);
            assert!(
                (f64::from(arms[i].rate_rad_s) - rate).abs() < 1e-4 * rate.abs().max(1.0),
                "leg {}: {} vs {rate}",
                i + 1,
                arms[i].rate_rad_s
            );
            assert!(
                (f64::from(arms[i].acceleration_rad_s2) - accel).abs()
                    < 1e-3 * accel.abs().max(1.0),
                "leg {}: {} vs {accel}",
                i + 1,
                arms[i].acceleration_rad_s2
            );
        }
        tested += 1;
    }
    let case = &strut_cases()[1];
    let reference = RefAnchors::from_core(&case.struts.anchors());
    for _ in 0..200 {
        let pose = rng.pose(&case.range);
        let exact = RefPose::from_core(&pose);
        let (twist, acceleration) = motion(&mut rng);
        let links = strut_motions::<Libm>(&case.struts, &pose, &twist, &acceleration).unwrap();
        let lengths =
            |s: f64| reference.strut_lengths(&along(&exact, &twist, &acceleration, s * dt));
        let joints = |s: f64| reference.joints(&along(&exact, &twist, &acceleration, s * dt));
        let (lm, l0, lp) = (lengths(-1.0), lengths(0.0), lengths(1.0));
        let (qm, q0, qp) = (joints(-1.0), joints(0.0), joints(1.0));
        for i in 0..LEGS {
            let link = &links[i];
            let rate = (lp[i] - lm[i]) / (2.0 * dt);
            let accel = (lp[i] - 2.0 * l0[i] + lm[i]) / (dt * dt);
            assert!((f64::from(link.length_rate_mm_s) - rate).abs() < 1e-4 * rate.abs().max(1.0));
            assert!(
                (f64::from(link.length_acceleration_mm_s2) - accel).abs()
                    < 1e-3 * accel.abs().max(10.0),
                "{} vs {accel}",
                link.length_acceleration_mm_s2
            );
            for k in 0..3 {
                let v = (qp[i][k] - qm[i][k]) / (2.0 * dt);
                let a = (qp[i][k] - 2.0 * q0[i][k] + qm[i][k]) / (dt * dt);
                assert!(
                    (f64::from(link.joint.velocity_mm_s[k]) - v).abs() < 1e-4 * v.abs().max(1.0)
                );
                assert!(
                    (f64::from(link.joint.acceleration_mm_s2[k]) - a).abs()
                        < 1e-3 * a.abs().max(10.0)
                );
            }
            // The link turns as its unit vector does: n' = omega x n, omega square to n.
            let unit = |q: &[V3; LEGS]| {
                let d: V3 = core::array::from_fn(|k| q[i][k] - reference.base[i][k]);
                let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                d.map(|v| v / n)
            };
            let (nm, n0, np) = (unit(&qm), unit(&q0), unit(&qp));
            let n_rate: V3 = core::array::from_fn(|k| (np[k] - nm[k]) / (2.0 * dt));
            let omega = [
                n0[1] * n_rate[2] - n0[2] * n_rate[1],
                n0[2] * n_rate[0] - n0[0] * n_rate[2],
                n0[0] * n_rate[1] - n0[1] * n_rate[0],
            ];
            for k in 0..3 {
                assert!(
                    (f64::from(link.angular_velocity_rad_s[k]) - omega[k]).abs()
                        < 1e-4 * omega[k].abs().max(0.1)
                );
            }
        }
    }
}

/// The joint forces that carry a payload along a trajectory do the work of the wrench
/// Newton-Euler asks (written here in f64 from the payload's motion), along any small motion.
#[test]
fn actuation_carries_the_payload_with_its_inertia() {
    let payload = Payload {
        mass_kg: 2.0,
        centre_of_mass_mm: Vec3::new(10.0, 5.0, 40.0),
        inertia_kg_mm2: Mat3::new(
            9000.0, 100.0, 0.0, 100.0, 11000.0, -50.0, 0.0, -50.0, 15000.0,
        ),
    };
    let solver = solver_about(cases()[0].geometry.clone(), Vec3::new(0.0, 0.0, 50.0));
    let reference = RefArms::from_solver(&solver);
    let mut rng = Rng::new(83);
    let mut tested = 0;
    while tested < 100 {
        let pose = rng.pose(&cases()[0].range);
        let exact = RefPose::from_core(&pose);
        if reference.margins_mm(&exact).iter().any(|m| *m < 1.0) {
            continue;
        }
        let v = rng.vec3([50.0, 50.0, 50.0]);
        let w = rng.vec3([1.0, 1.0, 2.0]);
        let a = rng.vec3([2000.0, 2000.0, 2000.0]);
        let alpha = rng.vec3([20.0, 20.0, 20.0]);
        let twist = Twist {
            linear_mm_s: v,
            angular_rad_s: w,
        };
        let accel = Acceleration {
            linear_mm_s2: a,
            angular_rad_s2: alpha,
        };
        let tau = actuation::<Libm, _>(&solver, &pose, &payload, &twist, &accel).unwrap();
        // Newton-Euler in f64, about the centre C.
        let r = exact.rotation();
        let f64v = |u: Vec3| -> V3 { core::array::from_fn(|k| f64::from(u[k])) };
        let cross = |p: V3, q: V3| -> V3 {
            [
                p[1] * q[2] - p[2] * q[1],
                p[2] * q[0] - p[0] * q[2],
                p[0] * q[1] - p[1] * q[0],
            ]
        };
        let c = reference.anchors.centre;
        let com = f64v(payload.centre_of_mass_mm);
        let local: V3 = core::array::from_fn(|k| com[k] - c[k]);
        let rho: V3 = core::array::from_fn(|k| (0..3).map(|j| r[k][j] * local[j]).sum());
        let (v, w, a, alpha) = (f64v(v), f64v(w), f64v(a), f64v(alpha));
        let _ = v;
        let w_rho = cross(w, rho);
        let a_g: V3 = core::array::from_fn(|k| a[k] + cross(alpha, rho)[k] + cross(w, w_rho)[k]);
        let m = f64::from(payload.mass_kg);
        let force: V3 =
            core::array::from_fn(|k| m * (a_g[k] + if k == 2 { 9806.65 } else { 0.0 }) * 1e-3);
        let inertia_local: [[f64; 3]; 3] = core::array::from_fn(|i| {
            core::array::from_fn(|j| f64::from(payload.inertia_kg_mm2[(i, j)]))
        });
        // I = R I_local R^T.
        let mut inertia = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                inertia[i][j] = (0..3)
                    .flat_map(|p| (0..3).map(move |q| (p, q)))
                    .map(|(p, q)| r[i][p] * inertia_local[p][q] * r[j][q])
                    .sum();
            }
        }
        let times = |m: &[[f64; 3]; 3], u: V3| -> V3 {
            core::array::from_fn(|i| (0..3).map(|j| m[i][j] * u[j]).sum())
        };
        let spin = cross(w, times(&inertia, w));
        let i_alpha = times(&inertia, alpha);
        let moment: V3 =
            core::array::from_fn(|k| cross(rho, force)[k] + (i_alpha[k] + spin[k]) * 1e-3);
        let wrench = [
            force[0], force[1], force[2], moment[0], moment[1], moment[2],
        ];
        for _ in 0..3 {
            let dx = small_motion(&mut rng, 1e-3, 1e-5);
            let dl = joint_change(&|p| reference.arm_angles(p), &exact, &dx).unwrap();
            let work_tau: f64 = (0..LEGS).map(|i| f64::from(tau[i]) * dl[i]).sum();
            let work_w: f64 = (0..6).map(|k| wrench[k] * dx[k]).sum();
            let scale: f64 = (0..6).map(|k| (wrench[k] * dx[k]).abs()).sum();
            assert!(
                (work_tau - work_w).abs() < 1e-4 * scale,
                "{work_tau} vs {work_w}"
            );
        }
        tested += 1;
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

proptest! {
    #![proptest_config(config(512, 89))]

    /// Wherever the platform is (struts lying flat, arms at dead centre, absurd turns): no
    /// panic, and forces, torques and displacements are errors or finite numbers.
    #[test]
    fn statics_never_give_a_nan(
        case in 0..4usize,
        (x, y, z) in (-80.0f32..80.0, -80.0f32..80.0, -150.0f32..80.0),
        (r, p, w) in (-180.0f32..180.0, -100.0f32..100.0, -180.0f32..180.0),
    ) {
        let pose = Pose::from_degrees(x, y, z, r, p, w);
        let wrench = Wrench {
            force_n: Vec3::new(1.0, 2.0, -30.0),
            moment_n_mm: Vec3::new(100.0, 0.0, -50.0),
        };
        let payload = Payload::point(1.0, Vec3::new(5.0, 0.0, 20.0));
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        let struts = strut_cases()[case].struts;
        let solver = ik::Solver::new(cases()[case].geometry.clone()).unwrap();
        if let Ok(f) = joint_forces::<Libm, _>(&struts, &pose, &wrench) {
            prop_assert!(finite(&f));
        }
        if let Ok(f) = joint_forces::<Libm, _>(&solver, &pose, &wrench) {
            prop_assert!(finite(&f));
        }
        if let Ok(t) = holding_loads::<Libm, _>(&solver, &pose, &payload) {
            prop_assert!(finite(&t));
        }
        let down = Vec3::new(0.0, 0.0, -10.0);
        let k = [1000.0; LEGS];
        if let Ok(d) = displacement_under_central_force::<Libm, _>(&struts, &pose, &k, down) {
            prop_assert!(finite(d.translation_mm.as_slice()));
            prop_assert!(finite(d.rotation_rad.as_slice()));
        }
        if let Ok(j) = Jacobian::at::<Libm, _>(&struts, &pose) {
            let k = stiffness(&j, &[1000.0; LEGS]).unwrap();
            if let Ok(c) = compliance::<Libm>(&k) { prop_assert!(finite(c.as_slice())); }
        }
    }
}
