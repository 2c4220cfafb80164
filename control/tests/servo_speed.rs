//! The servos' rated speeds (`servoN.speed_s_60deg`) through the controller: moves and stream
//! steps never turn an arm faster than its rating, and keep their path. The arm turns are read
//! from the pulses the controller gives (eq. 13, 14: `|d W| = r |d alpha|`), the path from the
//! poses it commands; the time a path needs is computed here independently, by the IK at 2,000
//! poses along it.
#![allow(clippy::needless_range_loop)] // six servos side by side, by number

mod common;

use common::Host;
use control::motion::lerp;
use kinematics_core::{ik, Libm, Pose, LEGS};

const SIXTY_DEG_RAD: f32 = core::f32::consts::FRAC_PI_3;

/// Echo off, the servos rated (s per 60 degrees), servo 4 slower than the rest.
fn rated(all: &str, servo4: &str) -> Host {
    let mut s = Host::quiet();
    s.ok(&format!("set servos.speed_s_60deg {all}"));
    s.ok(&format!("set servo4.speed_s_60deg {servo4}"));
    s
}

fn solver(s: &Host) -> ik::Solver {
    s.ctl.settings().validate().unwrap()
}

/// Each servo's largest turn in one frame by its rating, rad.
fn max_turn_rad(s: &Host) -> [f32; LEGS] {
    let settings = s.ctl.settings();
    let dt = 1.0 / f32::from(settings.frame_hz);
    settings.servo_speed.s_per_60deg.map(|t| {
        if t > 0.0 {
            SIXTY_DEG_RAD / t * dt
        } else {
            f32::INFINITY
        }
    })
}

/// Each servo's arm turn between two frames' pulses, rad.
fn turns_rad(s: &Host, a: &[f32; LEGS], b: &[f32; LEGS]) -> [f32; LEGS] {
    let servos = &s.ctl.settings().servos.0;
    core::array::from_fn(|i| (b[i] - a[i]).abs() / servos[i].rate_us_per_rad)
}

/// Stretches the straight paths below are cut into.
const STRETCHES: usize = 2000;

/// The arm angles (the host's IK) at the ends of the `STRETCHES` stretches of the straight
/// path from `a` to `b`, `a` first, rad.
fn arms_along(s: &Host, a: &Pose, b: &Pose) -> Vec<[f32; LEGS]> {
    let solver = solver(s);
    (0..=STRETCHES)
        .map(|k| {
            let p = lerp(a, b, k as f32 / STRETCHES as f32);
            solver
                .solve::<Libm>(&s.ctl.settings().servos, &p)
                .unwrap()
                .arm_rad
        })
        .collect()
}

/// The least time the servos need for the straight path from `a` to `b` at their ratings,
/// s: the steepest of 2,000 stretches along it.
fn path_time_s(s: &Host, a: &Pose, b: &Pose) -> f32 {
    let ratings = s.ctl.settings().servo_speed.s_per_60deg;
    let mut worst = 0.0f32;
    for w in arms_along(s, a, b).windows(2) {
        for i in 0..LEGS {
            worst = worst
                .max((w[1][i] - w[0][i]).abs() * ratings[i] / SIXTY_DEG_RAD * STRETCHES as f32);
        }
    }
    worst
}

/// The fraction of the way from `a` to `b` at which `p` lies, if it lies on the straight line
/// between them (every coordinate within `tol_mm` / `tol_rad`).
fn on_line(a: &Pose, b: &Pose, p: &Pose, tol_mm: f32, tol_rad: f32) -> Option<f32> {
    let (a, b, p) = (a.to_array(), b.to_array(), p.to_array());
    let along = (0..6)
        .max_by(|&i, &j| (b[i] - a[i]).abs().total_cmp(&(b[j] - a[j]).abs()))
        .unwrap();
    let u = (p[along] - a[along]) / (b[along] - a[along]);
    (0..6)
        .all(|i| {
            let tol = if i < 3 { tol_mm } else { tol_rad };
            (a[i] + u * (b[i] - a[i]) - p[i]).abs() <= tol
        })
        .then_some(u)
}

/// The least time any step-by-step motion along the straight path from `a` to `b` takes at the
/// ratings, s: the servo whose arm turns furthest along it (its total turn, by the IK at 2,000
/// poses) for its rating.
fn turning_time_s(s: &Host, a: &Pose, b: &Pose) -> f32 {
    let ratings = s.ctl.settings().servo_speed.s_per_60deg;
    let mut turned = [0.0f32; LEGS];
    for w in arms_along(s, a, b).windows(2) {
        for i in 0..LEGS {
            turned[i] += (w[1][i] - w[0][i]).abs();
        }
    }
    (0..LEGS)
        .map(|i| turned[i] * ratings[i] / SIXTY_DEG_RAD)
        .fold(0.0, f32::max)
}

/// Runs a move to its end: every frame's pulses and pose, the start first.
fn run_move(s: &mut Host) -> Vec<([f32; LEGS], Pose)> {
    let mut seen = vec![(s.ctl.pulses_us(), *s.ctl.pose())];
    while s.ctl.is_moving() {
        let pulses = s.ctl.on_frame();
        seen.push((pulses, *s.ctl.pose()));
        assert!(seen.len() < 100_000, "the move never ends");
    }
    seen
}

/// Asserts every step of `seen` (each frame's pulses and pose, the start first) turns no arm
/// further than its rating allows in a frame, lands on the straight line from `start` to
/// `target`, no less far along it than the step before and not past it, and gives the pulses
/// the IK gives for its pose (within `pulse_tol_us`).
fn assert_rated_steps_along_line(
    s: &Host,
    seen: &[([f32; LEGS], Pose)],
    start: &Pose,
    target: &Pose,
    pulse_tol_us: f32,
    label: &str,
) {
    let solver = solver(s);
    let limit = max_turn_rad(s);
    let mut last_u = 0.0;
    for (frame, w) in seen.windows(2).enumerate().map(|(k, w)| (k + 1, w)) {
        let (pulses, pose) = w[1];
        let turns = turns_rad(s, &w[0].0, &pulses);
        for i in 0..LEGS {
            assert!(
                turns[i] <= limit[i] * 1.0001,
                "{label} frame {frame}: servo {} turns {} rad, rated {} rad a frame",
                i + 1,
                turns[i],
                limit[i]
            );
        }
        let u = on_line(start, target, &pose, 1e-4, 1e-6)
            .unwrap_or_else(|| panic!("{label} frame {frame}: {pose:?} off the line"));
        assert!(
            u >= last_u - 1e-6 && u <= 1.0 + 1e-6,
            "{label} frame {frame}: {u}"
        );
        last_u = u;
        let want = solver
            .solve::<Libm>(&s.ctl.settings().servos, &pose)
            .unwrap();
        for i in 0..LEGS {
            assert!(
                (pulses[i] - want.pulse_us[i]).abs() < pulse_tol_us,
                "{label} frame {frame} servo {}: {} vs {}",
                i + 1,
                pulses[i],
                want.pulse_us[i]
            );
        }
    }
}

#[test]
fn a_fast_move_turns_no_arm_faster_than_its_rating_and_keeps_its_straight_path() {
    // Moves whose arms turn unevenly along the way (x across, yaw across: some arms turn out
    // and back, so the ends alone understate the time), and one with acceleration limits.
    let targets = [
        ("pose 20 0 0 0 0 0", "pose -20 0 0 0 0 0"),
        ("pose 0 0 0 0 0 20", "pose 0 0 0 0 0 -20"),
        ("pose 0 15 0 -10 0 0", "pose 0 -15 0 10 0 0"),
    ];
    for (limits, accel) in [("off", false), ("400", false), ("off", true)] {
        for (first, second) in targets {
            let mut s = rated("0.3", "0.5");
            s.ok(&format!("set speed_mm_s {limits}"));
            s.ok(&format!("set speed_deg_s {limits}"));
            if accel {
                s.ok("set accel_mm_s2 2000");
                s.ok("set accel_deg_s2 3000");
            }
            s.ok(first);
            assert!(
                s.ctl.take_new_pulses().is_none(),
                "with ratings a move is never a jump"
            );
            run_move(&mut s);
            let start = *s.ctl.pose();
            s.ok(second);
            let target = *s.ctl.target();
            let seen = run_move(&mut s);
            assert_rated_steps_along_line(
                &s,
                &seen,
                &start,
                &target,
                0.01,
                &format!("{second} ({limits}, accel {accel})"),
            );
            assert_eq!(*s.ctl.pose(), target);
            // No slower than the ratings need (at the 97 % the plan uses, plus the rounding
            // to whole frames), where the ratings are what limits it.
            let needed = path_time_s(&s, &start, &target);
            let took = (seen.len() - 1) as f32 / 50.0;
            assert!(took >= needed * 0.999, "{second}: {took} s < {needed} s");
            if limits == "off" && !accel {
                assert!(
                    took <= needed / 0.97 * 1.01 + 0.02,
                    "{second}: {took} s, needs {needed} s"
                );
            }
        }
    }
}

#[test]
fn check_reports_the_duration_the_ratings_give() {
    let mut s = rated("0.3", "0.3");
    s.ok("set speed_mm_s off");
    s.ok("set speed_deg_s off");
    let data = s.ok("check 20 0 0 0 0 0");
    let duration: f32 = data
        .iter()
        .find_map(|l| l.strip_prefix("# duration_s: "))
        .unwrap()
        .parse()
        .unwrap();
    let needed = path_time_s(
        &s,
        &Pose::HOME,
        &Pose::from_degrees(20.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    );
    assert!(
        duration >= needed && duration <= needed / 0.97 + 0.03,
        "{duration} s for {needed} s"
    );
    // Unrated, the same check is a jump.
    s.ok("set servos.speed_s_60deg off");
    let data = s.ok("check 20 0 0 0 0 0");
    assert!(data.contains(&"# duration_s: 0.020".to_owned()), "{data:?}");
}

#[test]
fn without_ratings_moves_and_streams_are_as_before() {
    // Rated then unrated: a move with its speed limits off is a jump again, made at once.
    let mut s = rated("0.3", "0.3");
    s.ok("set servos.speed_s_60deg off");
    s.ok("set speed_mm_s off");
    s.ok("set speed_deg_s off");
    s.ok("pose 20 0 0 0 0 0");
    assert!(s.ctl.take_new_pulses().is_some());
    assert!(!s.ctl.is_moving());
    // And a move at the default limits takes the frames its limits give: 20 mm at 50 mm/s.
    let mut s = rated("0.3", "off");
    s.ok("set servos.speed_s_60deg off");
    s.ok("pose 0 0 10 0 0 0");
    assert_eq!(run_move(&mut s).len() - 1, 10);
}

/// A binary stream frame of six fractions (-1..1) of the axes' full scales.
fn frame_of(fractions: [f32; 6]) -> Vec<u8> {
    let mut bytes = vec![0xA5, 0x5A];
    for f in fractions {
        let c = (32768.0 + f * 32768.0).round().clamp(0.0, 65535.0) as u16;
        bytes.extend_from_slice(&c.to_be_bytes());
    }
    bytes.extend_from_slice(b"\r\n");
    bytes
}

#[test]
fn a_rated_stream_steps_within_the_ratings_along_its_line() {
    // Every limit off: unrated, this is pass-through (one jump); rated, the tracker steps
    // at the frame rate, each step the way to the target shortened to the ratings.
    let mut s = rated("0.3", "0.6");
    s.ok("set speed_mm_s off");
    s.ok("set speed_deg_s off");
    let start = *s.ctl.pose();
    s.feed(&frame_of([0.5, -0.3, 0.3, 0.3, -0.3, 0.4]));
    s.apply_stream();
    assert!(s.ctl.take_new_pulses().is_none(), "not passed through");
    // Until it settles (on the target: the last pose).
    let mut seen = vec![(s.ctl.pulses_us(), start)];
    while s.ctl.is_moving() {
        let pulses = s.ctl.on_frame();
        seen.push((pulses, *s.ctl.pose()));
        assert!(seen.len() < 500, "the stream never gets there");
    }
    let target = seen.last().unwrap().1;
    assert!(
        target.x_mm > 12.4 && target.yaw_rad.to_degrees() > 7.9,
        "{target:?}"
    );
    // A shortened step is solved where it ends.
    assert_rated_steps_along_line(&s, &seen, &start, &target, 0.05, "stream");
    let frames = seen.len() - 1;
    assert!(frames > 3, "the ratings slowed it: {frames} frames");
    let needed = turning_time_s(&s, &start, &target);
    assert!(
        frames as f32 / 50.0 >= needed * 0.999,
        "{frames} frames for {needed} s"
    );
}

#[test]
fn a_rated_stream_with_limits_keeps_both() {
    let mut s = rated("0.2", "0.2");
    s.ok("set speed_mm_s 1000");
    s.ok("set speed_deg_s 1000");
    s.ok("set accel_mm_s2 20000");
    s.ok("set accel_deg_s2 20000");
    let limit = max_turn_rad(&s);
    // A target that jumps about, as a sim's may.
    let mut before = s.ctl.pulses_us();
    for k in 0..120 {
        if k % 20 == 0 {
            let sign = if k % 40 == 0 { 1.0 } else { -1.0 };
            s.feed(&frame_of([
                0.7 * sign,
                0.3,
                -0.5 * sign,
                0.4,
                0.6 * sign,
                -0.3,
            ]));
            s.apply_stream();
        }
        let pulses = s.ctl.on_frame();
        let turns = turns_rad(&s, &before, &pulses);
        for i in 0..LEGS {
            assert!(turns[i] <= limit[i] * 1.0001, "frame {k} servo {}", i + 1);
        }
        before = pulses;
    }
}
