//! Motion through the controller: durations from the speed limits, straight lines, stop,
//! jumps, re-targeting, link loss. Time is counted in frames (no wall clock).

mod common;

use common::{pose_values, Host};
use control::motion::{angular_distance_deg, linear_distance_mm};
use control::Pose;

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

fn session(speed_mm_s: &str, speed_deg_s: &str) -> Host {
    let mut s = Host::quiet();
    s.ok(&format!("set speed_mm_s {speed_mm_s}"));
    s.ok(&format!("set speed_deg_s {speed_deg_s}"));
    s
}

#[test]
fn linear_limit_sets_the_duration() {
    // 5 mm at 10 mm/s = 0.5 s = 25 frames at 50 Hz.
    let mut s = session("10", "off");
    s.ok("pose 0 0 5 0 0 0");
    assert_eq!(s.run_until_idle(), 25);
    // 3-4-5: the linear distance is Euclidean; 5 mm back at 10 mm/s.
    let mut s = session("10", "off");
    s.ok("pose 3 4 0 0 0 0");
    assert_eq!(s.run_until_idle(), 25);
}

#[test]
fn angular_limit_sets_the_duration_when_slower() {
    // 1 mm at 50 mm/s = 0.02 s, 6 deg at 10 deg/s = 0.6 s -> 30 frames.
    let mut s = session("50", "10");
    s.ok("pose 0 0 1 6 0 0");
    assert_eq!(s.run_until_idle(), 30);
    // Now the linear group is slower: 5 mm at 5 mm/s = 1 s vs 2 deg at 10 deg/s = 0.2 s.
    let mut s = session("5", "10");
    s.ok("pose 0 0 5 2 0 0");
    assert_eq!(s.run_until_idle(), 50);
}

#[test]
fn duration_scales_with_the_frame_rate() {
    let mut s = session("10", "off");
    s.ok("set frame_hz 200");
    s.ok("pose 0 0 5 0 0 0");
    assert_eq!(s.run_until_idle(), 100);
    let state = s.status_field("state");
    assert_eq!(state, "idle");
}

#[test]
fn status_reports_progress() {
    let mut s = session("10", "off");
    s.ok("pose 0 0 5 0 0 0");
    s.frames(10);
    assert_eq!(s.status_field("state"), "moving 0.200 of 0.500 s");
}

#[test]
fn every_frame_is_on_the_straight_line_within_the_speed_limits() {
    let mut s = session("20", "15");
    s.ok("pose 4 -3 2 1 2 -3");
    s.run_until_idle();
    let start = *s.ctl.pose();
    let target = Pose::from_degrees(-6.0, 5.0, -4.0, -3.0, 4.0, 5.0);
    s.ok("pose -6 5 -4 -3 4 5");
    let (a, b) = (start.to_array(), target.to_array());
    let mut previous = start;
    let mut last_t = 0.0;
    while s.ctl.is_moving() {
        s.ctl.on_frame();
        let p = *s.ctl.pose();
        // On the line: every coordinate at the same fraction t of the way.
        let v = p.to_array();
        let t = (v[0] - a[0]) / (b[0] - a[0]);
        for i in 0..6 {
            assert!(
                close(v[i], a[i] + t * (b[i] - a[i]), 1e-4),
                "coord {i} t {t}"
            );
        }
        assert!(t > last_t);
        last_t = t;
        assert!(linear_distance_mm(&previous, &p) <= 20.0 / 50.0 + 1e-4);
        assert!(angular_distance_deg(&previous, &p) <= 15.0 / 50.0 + 1e-3);
        previous = p;
    }
    assert_eq!(*s.ctl.pose(), target);
}

#[test]
fn speed_off_jumps_at_once_and_hands_the_board_the_new_pulses() {
    let mut s = session("off", "off");
    let home = s.ctl.on_frame();
    assert_eq!(s.ctl.take_new_pulses(), None);
    s.ok("pose 5 0 -5 3 0 2");
    // Already there, before any frame: nothing left to move.
    assert!(!s.ctl.is_moving());
    assert_eq!(
        *s.ctl.pose(),
        Pose::from_degrees(5.0, 0.0, -5.0, 3.0, 0.0, 2.0)
    );
    let now = s
        .ctl
        .take_new_pulses()
        .expect("a jump gives new pulses at once");
    assert_ne!(now, home);
    // Once only; the following frames command the same pulses.
    assert_eq!(s.ctl.take_new_pulses(), None);
    assert_eq!(s.frames(3), vec![now; 3]);
    // A refused target changes nothing.
    assert!(!s.err("pose 0 0 80 0 0 0").is_empty());
    assert_eq!(s.ctl.take_new_pulses(), None);
}

#[test]
fn with_a_speed_limit_the_first_step_waits_for_the_frame() {
    let mut s = session("10", "off");
    s.ok("pose 0 0 5 0 0 0");
    assert_eq!(s.ctl.take_new_pulses(), None);
    assert!(s.ctl.is_moving());
    assert_eq!(s.run_until_idle(), 25);
}

#[test]
fn a_trim_change_hands_the_board_the_new_pulses_at_once() {
    let mut s = Host::quiet();
    s.ok("set servo3.trim_us 1520");
    let now = s
        .ctl
        .take_new_pulses()
        .expect("the held pose's pulses changed");
    // At home every servo gets its trim.
    assert_eq!(now, [1500.0, 1500.0, 1520.0, 1500.0, 1500.0, 1500.0]);
}

#[test]
fn stop_freezes_at_the_interpolated_pose() {
    let mut s = session("10", "off");
    s.ok("pose 0 0 10 0 0 0");
    s.frames(25);
    s.ok("stop");
    let here = pose_values(&s.status_field("pose"));
    assert!(close(here[2], 5.0, 1e-3), "{here:?}");
    let held = s.ctl.on_frame();
    for pulses in s.frames(100) {
        assert_eq!(pulses, held);
    }
    assert_eq!(pose_values(&s.status_field("pose")), here);
}

#[test]
fn a_new_target_while_moving_starts_from_the_current_pose() {
    let mut s = session("10", "off");
    s.ok("pose 0 0 10 0 0 0");
    s.frames(25); // at z = 5
    s.ok("pose 0 0 0 0 0 0");
    // 5 mm back at 10 mm/s.
    assert_eq!(s.run_until_idle(), 25);
    assert_eq!(*s.ctl.pose(), Pose::HOME);
}

#[test]
fn speed_changes_apply_to_the_next_move() {
    let mut s = session("10", "off");
    s.ok("pose 0 0 5 0 0 0");
    s.frames(5);
    s.ok("set speed_mm_s 50");
    assert_eq!(s.run_until_idle(), 20); // the running move keeps its plan
    s.ok("home");
    assert_eq!(s.run_until_idle(), 5); // 5 mm at 50 mm/s
}

#[test]
fn link_loss_is_off_by_default() {
    let mut s = Host::quiet();
    s.ok("pose 0 0 5 0 0 0");
    s.frames(50 * 600); // ten minutes
    assert_eq!(
        *s.ctl.pose(),
        Pose::from_degrees(0.0, 0.0, 5.0, 0.0, 0.0, 0.0)
    );
}

#[test]
fn link_loss_eases_home_after_the_timeout() {
    let mut s = session("10", "off");
    s.ok("set link_timeout_s 2");
    s.ok("pose 0 0 5 0 0 0");
    // The timer runs in whole frames from the first frame that starts after the last line
    // (the one the line ended in counts nothing, so link loss is never early): 2 s = 100
    // frames after that one, moving or not.
    s.frames(100);
    assert!(!s.ctl.is_moving());
    assert_eq!(s.ctl.target().z_mm, 5.0);
    s.frames(1);
    assert!(s.ctl.is_moving());
    assert_eq!(*s.ctl.target(), Pose::HOME);
    // At the configured speed: 5 mm at 10 mm/s, from the next frame (the way home was
    // checked after the frame that noticed the silence).
    assert_eq!(s.run_until_idle(), 25);
    assert_eq!(*s.ctl.pose(), Pose::HOME);
    // The notice comes out now (write_notices) ...
    let out = s.notices();
    assert!(
        out.starts_with("# link lost: no command for 2 s"),
        "{out:?}"
    );
    // ... and only once.
    assert_eq!(s.notices(), "");
}

#[test]
fn link_loss_notice_comes_before_the_next_reply_if_not_fetched() {
    let mut s = session("10", "off");
    s.ok("set link_timeout_s 0.5");
    s.ok("pose 0 0 2 0 0 0");
    s.frames(26);
    let (data, reply) = s.exchange("status");
    assert_eq!(reply, "ok");
    assert!(data[0].starts_with("# link lost:"), "{data:?}");
    assert!(
        data.iter()
            .any(|l| l.starts_with("# state: returning home")),
        "{data:?}"
    );
}

#[test]
fn any_line_resets_the_link_timer() {
    let mut s = session("10", "off");
    s.ok("set link_timeout_s 1");
    s.ok("pose 0 0 2 0 0 0");
    s.frames(40);
    s.err("nonsense"); // an erroneous line is still a sign of life
    s.frames(40);
    s.ok("?");
    s.frames(50);
    assert_eq!(s.ctl.target().z_mm, 2.0);
    s.frames(1);
    assert_eq!(*s.ctl.target(), Pose::HOME);
    // Once per silence: back home it stays put, and a new command re-arms it.
    s.run_until_idle();
    s.ok("pose 0 0 1 0 0 0");
    s.frames(51);
    assert_eq!(*s.ctl.target(), Pose::HOME);
}

#[test]
fn link_loss_with_speed_off_still_eases() {
    let mut s = session("off", "off");
    s.ok("set link_timeout_s 1");
    s.ok("pose 0 0 5 0 0 0");
    s.frames(51);
    assert!(s.ctl.is_moving());
    // 5 mm at the 10 mm/s fallback: 25 frames.
    assert_eq!(s.run_until_idle(), 25);
}

#[test]
fn a_command_during_the_return_takes_over() {
    let mut s = session("10", "off");
    s.ok("set link_timeout_s 1");
    s.ok("pose 0 0 5 0 0 0");
    s.frames(55);
    assert!(s.status_field("state").starts_with("returning home"));
    s.ok("stop");
    assert!(!s.ctl.is_moving());
    s.frames(49);
    assert!(!s.ctl.is_moving());
}
