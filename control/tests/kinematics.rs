//! `servo` (and the pose of its pulses), `limits` and the payload's holding torques, through
//! the byte interface. Expected values come from `kinematics-core` called directly (forward
//! kinematics, the IK, the workspace search, the statics), and from properties the answers must
//! have (the IK at a reported pose gives the pulses; a reported reach passes and a little
//! beyond it does not).

#![allow(clippy::needless_range_loop)] // six-vectors compared index by index

mod common;

use common::{code_of, pose_values, six, Host};
use control::controller::{CHECKS_PER_SLICE, CLAMP_STEPS};
use kinematics_core::forward::{self, arm_angles_for_pulses};
use kinematics_core::geometry::PairedLayout;
use kinematics_core::statics::{servo_holding_torques, Payload, N_MM_PER_KGF_CM};
use kinematics_core::workspace::{self, Limit};
use kinematics_core::{ik, IkError, Libm, Pose, ServoSet, Solution, Vec3};

fn solver() -> ik::Solver {
    ik::Solver::new(PairedLayout::default().build().unwrap()).unwrap()
}

fn solve(pose: &Pose) -> Result<Solution, IkError> {
    solver().solve::<Libm>(&ServoSet::default(), pose)
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

fn pose_of(v: [f32; 6]) -> Pose {
    Pose::from_degrees(v[0], v[1], v[2], v[3], v[4], v[5])
}

fn values_of(p: &Pose) -> [f32; 6] {
    let v = p.to_array();
    [
        v[0],
        v[1],
        v[2],
        v[3].to_degrees(),
        v[4].to_degrees(),
        v[5].to_degrees(),
    ]
}

/// The line `# key: ...` of a listing, without the key.
fn field<'a>(data: &'a [String], key: &str) -> &'a str {
    let prefix = format!("# {key}: ");
    data.iter()
        .find_map(|l| l.strip_prefix(&prefix))
        .unwrap_or_else(|| panic!("no {key} in {data:?}"))
}

/// Sends a line and counts the slices of work it took (as the board's main loop does them).
fn slices(s: &mut Host, line: &str) -> (usize, String) {
    let mut out = String::new();
    for &b in format!("{line}\n").as_bytes() {
        s.ctl.on_byte(&mut s.link, b, &mut out);
    }
    let mut n = 0;
    while s.ctl.is_busy() {
        s.work(&mut out);
        n += 1;
    }
    (n, out)
}

/// The core's forward kinematics of six pulses with the default settings, reached from
/// `start` as the platform moves there: the arm angles turn from the IK's at `start` to the
/// pulses' in 0.25 degree steps (the firmware takes 5 degree steps), each solved from the last.
fn core_fk(pulses: &[f32; 6], start: &Pose) -> Result<Pose, kinematics_core::KinematicsError> {
    let solver = solver();
    let to = arm_angles_for_pulses(&solver, &ServoSet::default(), pulses)?;
    let from = solver.arm_angles::<Libm>(start)?;
    let steps = 720;
    let mut pose = *start;
    for k in 1..=steps {
        let t = k as f32 / steps as f32;
        let arm: [f32; 6] = core::array::from_fn(|i| from[i] + (to[i] - from[i]) * t);
        let closure = forward::Closure::arms::<Libm>(&solver, &arm)?;
        pose = forward::solve::<Libm>(&closure, &pose, forward::Options::default())?.pose;
    }
    forward::check_arms::<Libm>(&solver, &pose, &to)?;
    Ok(pose)
}

// ----- servo -----

#[test]
fn servo_drives_one_servo_and_status_shows_the_pose_of_the_pulses() {
    let mut s = Host::quiet();
    assert!(s.ok("servo 3 1620").is_empty(), "no data lines");
    let pulses = s.frames(1)[0];
    assert_eq!(pulses, [1500.0, 1500.0, 1620.0, 1500.0, 1500.0, 1500.0]);
    assert!(s.ctl.servo_power(), "servo powers the servos like a move");
    let data = s.ok("status");
    assert_eq!(field(&data, "state"), "direct (pulses set with servo)");
    assert_eq!(six(field(&data, "pulse_us")), pulses);
    let shown = pose_values(field(&data, "pulse_pose"));
    // The pose the forward kinematics of the core finds from home, to the 3 decimals shown.
    let expected = values_of(&core_fk(&pulses, &Pose::HOME).unwrap());
    for k in 0..6 {
        assert!(
            close(shown[k], expected[k], 1.5e-3),
            "{shown:?} vs {expected:?}"
        );
    }
    // It is that pose: the IK there gives the pulses (within what 3 decimals allow).
    let back = solve(&pose_of(shown)).unwrap();
    for k in 0..6 {
        assert!(
            close(back.pulse_us[k], pulses[k], 0.1),
            "{:?}",
            back.pulse_us
        );
    }
    // Moves start from there: pose and target are that pose; the arm angles are the pulses'.
    assert_eq!(pose_values(field(&data, "pose")), shown);
    assert_eq!(pose_values(field(&data, "target")), shown);
    let arm = six(field(&data, "arm_deg"));
    assert!(
        close(arm[2], -0.252 - 120.0 / (1600.0 / 180.0), 2e-3),
        "{arm:?}"
    );
}

#[test]
fn after_servo_a_move_starts_from_the_pose_found_without_a_jump() {
    let mut s = Host::quiet();
    s.ok("set speed_mm_s 5");
    s.ok("set speed_deg_s 5");
    s.ok("servo 1 1560");
    let start = s.frames(1)[0];
    let found = pose_of(pose_values(&s.status_field("pulse_pose")));
    s.ok("home");
    let first = s.frames(1)[0];
    // The first frame of the move is a small step from the pulses set, not a jump to home.
    for k in 0..6 {
        assert!(close(first[k], start[k], 5.0), "{first:?} from {start:?}");
    }
    s.run_until_idle();
    assert_eq!(s.frames(1)[0], [1500.0; 6]);
    let data = s.ok("status");
    assert_eq!(field(&data, "state"), "idle");
    assert!(
        !data.iter().any(|l| l.starts_with("# pulse_pose")),
        "{data:?}"
    );
    assert!(found.x_mm.abs() > 0.1 || found.z_mm.abs() > 0.1);
}

#[test]
fn servo_refusals_change_nothing() {
    let mut s = Host::quiet();
    s.ok("pose 2 0 1 0 0 0");
    s.run_until_idle();
    let before = s.frames(1)[0];
    let status = s.ok("status");
    for (line, code, message) in [
        (
            "servo 2 2000",
            "servo-limit",
            "servo 2: 2000.00 us is outside its limits 1100.00..1900.00 us (servo2.min_us, max_us)",
        ),
        (
            "servo 7 1500",
            "bad-value",
            "'7' is not a servo number; servos are 1 to 6",
        ),
        (
            "servo 1",
            "missing-field",
            "missing pulse_us; usage: servo <1-6> <us>",
        ),
        (
            "servo",
            "missing-field",
            "missing servo number; usage: servo <1-6> <us>",
        ),
        (
            "servo 1 abc",
            "bad-number",
            "pulse_us: 'abc' is not a decimal number",
        ),
        (
            "servo 1 nan",
            "not-finite",
            "pulse_us: 'nan' is not a finite number",
        ),
        (
            "servo 1 1500 x",
            "extra-field",
            "unexpected 'x'; usage: servo <1-6> <us>",
        ),
    ] {
        let reply = s.err(line);
        assert_eq!(reply, format!("error:{code} {message}"), "{line}");
        assert_eq!(s.frames(1)[0], before);
        assert_eq!(s.ok("status"), status, "{line}");
    }
    // While a move is in progress: busy. With the e-stop open: e-stop.
    s.ok("set speed_mm_s 1");
    s.ok("pose 0 0 0 0 0 0");
    assert_eq!(s.code("servo 1 1500"), "busy");
    s.ok("stop");
    s.ctl.set_estop_input(true);
    assert_eq!(s.code("servo 1 1500"), "e-stop");
}

#[test]
fn an_estop_that_opens_while_the_pose_is_found_refuses_the_servo() {
    let mut s = Host::quiet();
    let mut out = String::new();
    for &b in b"servo 2 1700\n" {
        s.ctl.on_byte(&mut s.link, b, &mut out);
    }
    assert!(s.ctl.is_busy());
    s.ctl.work(&mut s.link, &mut out);
    s.ctl.set_estop_input(true);
    while s.ctl.is_busy() {
        s.work(&mut out);
    }
    let reply = out.lines().last().unwrap();
    assert!(reply.starts_with("error:e-stop "), "{out}");
    assert_eq!(s.frames(1)[0], [1500.0; 6]);
    assert!(s.ctl.direct().is_none());
}

#[test]
fn servo_ends_a_stream_like_stop() {
    let mut s = Host::quiet();
    s.ok("set speed_mm_s off");
    s.ok("set speed_deg_s off");
    let frame = [
        0xA5, 0x5A, 0x80, 0, 0x80, 0, 0x90, 0, 0x80, 0, 0x80, 0, 0x80, 0, 0x0D, 0x0A,
    ];
    s.feed(&frame);
    s.apply_stream();
    assert!(s.ctl.is_streaming());
    s.ok("servo 4 1450");
    assert!(!s.ctl.is_streaming());
    assert_eq!(s.status_field("state"), "direct (pulses set with servo)");
    assert_eq!(s.frames(1)[0][3], 1450.0);
}

#[test]
fn the_pose_is_found_a_newton_iteration_per_slice() {
    let mut s = Host::quiet();
    let (n, out) = slices(&mut s, "servo 5 1580");
    assert_eq!(out, "ok\r\n");
    // At least one iteration, the IK's check, at most the 8 iterations Newton is allowed.
    assert!((2..=10).contains(&n), "{n} slices");
}

#[test]
fn pulses_that_close_no_pose_are_kept_but_nothing_moves_from_them() {
    let mut s = Host::quiet();
    s.ok("servo 1 1900");
    s.ok("servo 2 1900");
    let pulses = s.frames(1)[0];
    assert_eq!(&pulses[..2], &[1900.0, 1900.0]);
    let start = pose_of(pose_values(&s.status_field("pose")));
    assert!(
        core_fk(&pulses, &start).is_err(),
        "the core finds no pose either"
    );
    let shown = s.status_field("pulse_pose");
    assert!(shown.starts_with("none ("), "{shown}");
    for line in [
        "home",
        "pose 0 0 1 0 0 0",
        "check 0 0 1 0 0 0",
        "limits",
        "nudge x=1",
    ] {
        let reply = s.err(line);
        assert_eq!(code_of(&reply), "no-pose", "{line}");
        assert!(
            reply.contains("drive the servos back with servo"),
            "{reply}"
        );
        assert_eq!(s.frames(1)[0], pulses);
    }
    // Back within reach: a pose again, and moves work.
    s.ok("servo 2 1500");
    assert!(!s.status_field("pulse_pose").starts_with("none"));
    s.ok("servo 1 1500");
    s.ok("home");
    s.run_until_idle();
    assert_eq!(s.frames(1)[0], [1500.0; 6]);
}

#[test]
fn settings_changed_after_servo_keep_the_pulses_and_find_their_pose_again() {
    let mut s = Host::quiet();
    s.ok("servo 3 1512");
    let before = pose_values(&s.status_field("pulse_pose"));
    assert!(before.iter().any(|v| v.abs() > 0.01), "{before:?}");
    // Calibrating the trim: the pulse stays, and with 1512 us as servo 3's home pulse the
    // six pulses are those of home.
    s.ok("set servo3.trim_us 1512");
    assert_eq!(s.frames(1)[0][2], 1512.0);
    let after = pose_values(&s.status_field("pulse_pose"));
    for v in after {
        assert!(v.abs() <= 1e-3, "{after:?}");
    }
    // A limit that excludes a pulse held is refused.
    s.ok("servo 4 1700");
    assert_eq!(s.code("set servo4.max_us 1650"), "pose-conflict");
    assert_eq!(s.frames(1)[0][3], 1700.0);
}

// ----- limits -----

/// `limits`' twelve lines parsed: (distance, extreme, cause).
fn limits(s: &mut Host) -> Vec<(String, f32, f32, String)> {
    let data = s.ok("limits");
    assert_eq!(data.len(), 12, "{data:?}");
    let names = ["x", "y", "z", "roll", "pitch", "yaw"];
    data.iter()
        .enumerate()
        .map(|(k, line)| {
            let want = format!("# {}{}: ", names[k / 2], if k % 2 == 0 { '-' } else { '+' });
            let rest = line.strip_prefix(&want).unwrap_or_else(|| panic!("{line}"));
            let (distance, rest) = rest.split_once(' ').unwrap();
            let unit = if k < 6 { "mm to " } else { "deg to " };
            let rest = rest.strip_prefix(unit).unwrap_or_else(|| panic!("{line}"));
            let (extreme, cause) = rest.split_once(" (").unwrap();
            let extreme = extreme.split_once('=').unwrap().1;
            (
                names[k / 2].to_owned(),
                distance.parse().unwrap(),
                extreme.parse().unwrap(),
                cause.trim_end_matches(')').to_owned(),
            )
        })
        .collect()
}

#[test]
fn limits_name_the_reach_of_every_axis_direction_and_what_stops_it() {
    let mut s = Host::quiet();
    let start_values = [2.0, -3.0, 4.0, 1.0, -2.0, 5.0];
    s.ok("pose 2 -3 4 1 -2 5");
    s.run_until_idle();
    let got = limits(&mut s);
    let start = pose_of(start_values);
    let reaches = {
        let solver = solver();
        let mut search = workspace::Limits::new(start, workspace::Options::default());
        loop {
            let test = |p: &Pose| solver.solve::<Libm>(&ServoSet::default(), p).map(|_| ());
            if let Some(r) = search.step(test) {
                break r;
            }
        }
    };
    for (k, ((axis, distance, extreme, cause), reach)) in got.iter().zip(reaches).enumerate() {
        let scale = if k >= 6 { 1.0f32.to_degrees() } else { 1.0 };
        assert!(
            close(*distance, reach.distance * scale, 1e-3),
            "{axis}: {distance} vs {reach:?}"
        );
        let start_value = start_values[k / 2];
        let sign = if k % 2 == 0 { -1.0 } else { 1.0 };
        assert!(
            close(*extreme, start_value + sign * distance, 2e-3),
            "{axis}"
        );
        // What stops it: the core's reason at the first failing pose.
        let expected = match reach.limit {
            Limit::Blocked(IkError::Unreachable { leg }) => format!("leg {leg} out of reach"),
            Limit::Blocked(IkError::ServoLimit {
                servo,
                pulse_us,
                max_us,
                ..
            }) if pulse_us > max_us => format!("servo {servo} at max_us 1900.00 us"),
            Limit::Blocked(IkError::ServoLimit { servo, .. }) => {
                format!("servo {servo} at min_us 1100.00 us")
            }
            other => panic!("{other:?}"),
        };
        assert_eq!(*cause, expected, "{axis}");
        // Independently: the reach can be driven, a hundredth further cannot.
        let mut at = start;
        let step = if k >= 6 { 2e-4 } else { 0.02 };
        at.set(reach.axis, reach.extreme(&start));
        assert!(solve(&at).is_ok(), "{axis} at its reach");
        at.set(reach.axis, reach.extreme(&start) + sign * step);
        assert!(solve(&at).is_err(), "{axis} beyond its reach");
    }
}

#[test]
fn the_command_reference_shows_limits_from_home_as_they_are() {
    let doc = include_str!("../../docs/commands.md");
    let start = doc
        .find("```text\nlimits\n")
        .expect("docs/commands.md shows limits")
        + 8;
    let block = &doc[start..];
    let block = &block[..block.find("```").unwrap()];
    let mut s = Host::quiet();
    let out = s.feed(b"limits\n");
    assert_eq!(block.replace('\n', "\r\n"), format!("limits\r\n{out}"));
}

#[test]
fn limits_are_searched_a_few_poses_per_slice_and_change_nothing() {
    let mut s = Host::quiet();
    let before = s.ok("status");
    let (n, out) = slices(&mut s, "limits");
    assert_eq!(out.matches("\r\n").count(), 13);
    // About 160 IK solutions, CHECKS_PER_SLICE a slice, then a line a slice.
    assert!(n > 40 && n < 100, "{n} slices");
    assert_eq!(s.ok("status"), before);
}

// ----- payload and torque -----

fn payload(mass_g: f32, com_mm: [f32; 3]) -> Payload {
    Payload::point(mass_g / 1000.0, Vec3::new(com_mm[0], com_mm[1], com_mm[2]))
}

/// The core's holding torques (kgf cm) at a pose, default settings.
fn core_torques(pose: &Pose, p: &Payload) -> [f32; 6] {
    let solver = solver();
    let arm = solver.arm_angles::<Libm>(pose).unwrap();
    servo_holding_torques::<Libm>(&solver, pose, &arm, p)
        .unwrap()
        .map(|t| t / N_MM_PER_KGF_CM)
}

#[test]
fn with_a_payload_check_and_status_show_the_holding_torques() {
    let mut s = Host::quiet();
    // None without a payload.
    assert!(!s.ok("status").iter().any(|l| l.contains("torque")));
    assert_eq!(s.ok("check 1 2 3 0 0 0").len(), 3);
    s.ok("set payload_g 2000");
    s.ok("set payload_com_x_mm 15");
    s.ok("set payload_com_z_mm 30");
    let p = payload(2000.0, [15.0, 0.0, 30.0]);
    let data = s.ok("check 10 0 0 0 0 0");
    let keys: Vec<&str> = data.iter().map(|l| l.split(':').next().unwrap()).collect();
    assert_eq!(
        keys,
        ["# arm_deg", "# pulse_us", "# torque_kgcm", "# duration_s"]
    );
    let shown = six(field(&data, "torque_kgcm"));
    let expected = core_torques(&pose_of([10.0, 0.0, 0.0, 0.0, 0.0, 0.0]), &p);
    for k in 0..6 {
        assert!(
            close(shown[k], expected[k], 1.5e-3),
            "{shown:?} vs {expected:?}"
        );
    }
    // status: at the pose being held.
    s.ok("pose -3 4 2 1 2 3");
    s.run_until_idle();
    let shown = six(&s.status_field("torque_kgcm"));
    let expected = core_torques(&pose_of([-3.0, 4.0, 2.0, 1.0, 2.0, 3.0]), &p);
    for k in 0..6 {
        assert!(
            close(shown[k], expected[k], 1.5e-3),
            "{shown:?} vs {expected:?}"
        );
    }
    // Independently, by virtual work: holding torques and arm motions balance the work done
    // on the payload's weight, tau . d(alpha) = m g dz (small motions).
    let here = pose_of([-3.0, 4.0, 2.0, 1.0, 2.0, 3.0]);
    let com_z = |pose: &Pose| (pose.rotation::<Libm>() * Vec3::new(15.0, 0.0, 30.0)).z + pose.z_mm;
    for k in 0..6 {
        let mut there = here;
        let d = if k < 3 { 1e-2 } else { 1e-4 };
        let mut v = there.to_array();
        v[k] += d;
        there = Pose::from_array(v);
        let (a, b) = (solve(&here).unwrap(), solve(&there).unwrap());
        let work: f32 = (0..6)
            .map(|i| shown[i] * N_MM_PER_KGF_CM * (b.arm_rad[i] - a.arm_rad[i]))
            .sum();
        let lift = 2.0 * 9.80665 * (com_z(&there) - com_z(&here));
        assert!(
            close(work, lift, 0.02 * lift.abs() + 2e-3),
            "axis {k}: {work} vs {lift}"
        );
    }
}

#[test]
fn a_pose_that_would_overload_a_servo_is_refused_naming_it() {
    let mut s = Host::quiet();
    s.ok("set payload_g 2000");
    s.ok("set payload_com_z_mm 30");
    s.ok("set servos.torque_kgcm 1");
    let p = payload(2000.0, [0.0, 0.0, 30.0]);
    let target = pose_of([10.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let need = core_torques(&target, &p);
    let (servo, worst) = need
        .iter()
        .enumerate()
        .find(|(_, t)| t.abs() > 1.0)
        .expect("over the rating");
    let before = s.ok("status");
    for line in ["pose 10 0 0 0 0 0", "check 10 0 0 0 0 0", "move x=10"] {
        assert_eq!(
            s.err(line),
            format!(
                "error:torque-limit servo {} would need {:.3} kgf cm to hold the payload, over its rating 1.00 kgf cm",
                servo + 1,
                worst.abs()
            ),
            "{line}"
        );
        assert_eq!(s.ok("status"), before);
    }
    // Below the rating: fine.
    s.ok("pose 0 0 -10 0 0 0");
    s.run_until_idle();
}

#[test]
fn a_path_through_poses_that_would_overload_a_servo_is_refused() {
    let p = payload(2000.0, [0.0, 0.0, 30.0]);
    let from = [-1.0, 5.5, 6.0, -0.5, -4.5, 13.0];
    let to = [-9.0, 10.5, -4.5, -5.0, 7.5, 8.0];
    let rating = 2.5;
    // Found by search: both ends within the rating, the middle of the way not.
    let most = |v: [f32; 6]| {
        core_torques(&pose_of(v), &p)
            .iter()
            .fold(0.0f32, |m, t| m.max(t.abs()))
    };
    assert!(most(from) < rating && most(to) < rating);
    let mid: [f32; 6] = core::array::from_fn(|k| 0.5 * (from[k] + to[k]));
    assert!(most(mid) > rating);
    let mut s = Host::quiet();
    s.ok("set payload_g 2000");
    s.ok("set payload_com_z_mm 30");
    s.ok("pose -1 5.5 6 -0.5 -4.5 13");
    s.run_until_idle();
    s.ok("set servos.torque_kgcm 2.5");
    let before = s.ok("status");
    let reply = s.err("pose -9 10.5 -4.5 -5 7.5 8");
    assert!(
        reply.starts_with("error:path-blocked the straight path from the current pose is blocked ")
            && reply
                .contains("kgf cm to hold the payload, over its rating 2.50 kgf cm; nothing moved"),
        "{reply}"
    );
    assert_eq!(s.ok("status"), before);
    // Without the rating the same move is accepted.
    s.ok("set servos.torque_kgcm off");
    s.ok("pose -9 10.5 -4.5 -5 7.5 8");
}

#[test]
fn a_torque_checked_path_checks_one_pose_per_slice() {
    let mut s = Host::quiet();
    s.ok("set speed_mm_s 10");
    let (plain, _) = slices(&mut s, "check 5 0 0 0 0 0");
    s.ok("set payload_g 500");
    s.ok("set servos.torque_kgcm 5");
    let (checked, out) = slices(&mut s, "check 5 0 0 0 0 0");
    assert!(out.ends_with("ok\r\n"), "{out}");
    // 0.5 s at 50 Hz: 25 frames, the target solved when the command came: 24 poses, three a
    // slice by the IK alone, then a slice that finds the last checkpoint is the target;
    // one a slice with torques, after the target's torques. Then the data lines (the torque
    // line among them with a payload) a slice each, and the reply.
    assert_eq!(
        plain,
        (24u32.div_ceil(CHECKS_PER_SLICE) + 1 + 3 + 1) as usize
    );
    assert_eq!(checked, 1 + 24 + 1 + 4 + 1);
}

#[test]
fn settings_that_would_overload_the_held_pose_are_refused() {
    let mut s = Host::quiet();
    s.ok("set payload_g 2000");
    // At home each servo needs 0.667 kgf cm (a sixth of 2 kgf on a 2 cm arm).
    assert_eq!(s.code("set servos.torque_kgcm 0.5"), "pose-conflict");
    assert_eq!(s.ctl.settings().payload.torque_kgcm, [0.0; 6]);
    s.ok("set servos.torque_kgcm 0.7");
    assert_eq!(s.code("set payload_g 2200"), "pose-conflict");
    assert_eq!(s.ctl.settings().payload.mass_g, 2000.0);
    // Payload and ratings are busy while moving, like the servo settings.
    s.ok("set speed_mm_s 1");
    s.ok("pose 0 0 1 0 0 0");
    assert_eq!(s.code("set payload_g 100"), "busy");
    assert_eq!(s.code("set servo1.torque_kgcm 3"), "busy");
}

#[test]
fn limits_stop_where_a_servo_reaches_its_torque_rating() {
    let mut s = Host::quiet();
    s.ok("set payload_g 2000");
    s.ok("set payload_com_z_mm 30");
    s.ok("set servos.torque_kgcm 1");
    let p = payload(2000.0, [0.0, 0.0, 30.0]);
    let got = limits(&mut s);
    let by_torque: Vec<_> = got
        .iter()
        .filter(|l| l.3.contains("torque rating"))
        .collect();
    assert!(!by_torque.is_empty(), "{got:?}");
    for (k, (axis, distance, _, cause)) in got.iter().enumerate() {
        if !cause.contains("torque rating") {
            continue;
        }
        let sign = if k % 2 == 0 { -1.0 } else { 1.0 };
        let (d, beyond) = if k < 6 {
            (*distance, 0.02)
        } else {
            (distance.to_radians(), 2e-4)
        };
        let mut at = Pose::HOME;
        let axis_k = kinematics_core::pose::Axis::ALL[k / 2];
        at.set(axis_k, sign * d);
        let servo: usize = cause[6..7].parse().unwrap();
        let need = core_torques(&at, &p);
        assert!(
            need.iter().all(|t| t.abs() <= 1.0 + 1e-3),
            "{axis} at its reach: {need:?}"
        );
        at.set(axis_k, sign * (d + beyond));
        let need = core_torques(&at, &p);
        assert!(
            need[servo - 1].abs() > 1.0,
            "{axis} beyond its reach: {need:?}"
        );
    }
}

#[test]
fn a_stream_target_that_would_overload_is_clamped_one_pose_per_pass() {
    let mut s = Host::quiet();
    s.ok("set speed_mm_s off");
    s.ok("set speed_deg_s off");
    s.ok("set payload_g 2000");
    s.ok("set payload_com_z_mm 30");
    s.ok("set servos.torque_kgcm 1");
    let p = payload(2000.0, [0.0, 0.0, 30.0]);
    // x = +0.4 of 25 mm = 10 mm: reachable, but servo 1 would need 4.8 kgf cm.
    let x = 0.4f32;
    let c = (32768.0 + x * 32768.0) as u16;
    let mut frame = vec![0xA5, 0x5A];
    for v in [c, 32768, 32768, 32768, 32768, 32768] {
        frame.extend_from_slice(&v.to_be_bytes());
    }
    frame.extend_from_slice(b"\r\n");
    s.feed(&frame);
    // The target's IK at once; its torques, then each of the CLAMP_STEPS halvings with its
    // torques, a pass each.
    let passes = s.apply_stream();
    assert_eq!(
        passes,
        1 + 1 + CLAMP_STEPS,
        "one pose with its torques per pass"
    );
    assert_eq!(s.ctl.stream_counts().clamped, 1);
    let here = *s.ctl.pose();
    assert!(here.x_mm > 0.5 && here.x_mm < 10.0, "{here:?}");
    assert!(core_torques(&here, &p).iter().all(|t| t.abs() <= 1.0));
    let beyond = Pose {
        x_mm: here.x_mm + 10.0 / 64.0,
        ..here
    };
    assert!(core_torques(&beyond, &p).iter().any(|t| t.abs() > 1.0));
}
