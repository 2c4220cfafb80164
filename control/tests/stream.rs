//! Stream frames through the controller, as motion-simulator software sends them: decoding,
//! scaling, the newest frame winning, clamping to the workspace, the tracker's limits, and the
//! emergency stop. Expected poses come from the frame format (counts -> fractions of the full
//! scale), expected pulses from an independent IK solve of those poses.

mod common;

use common::{code_of, Host};
use control::safety::Estop;
use control::Settings;
use kinematics_core::{ik, Libm, Pose};

/// A binary frame of six 16-bit counts.
fn binary(counts: [u16; 6]) -> Vec<u8> {
    let mut bytes = vec![0xA5, 0x5A];
    for c in counts {
        bytes.extend_from_slice(&c.to_be_bytes());
    }
    bytes.extend_from_slice(b"\r\n");
    bytes
}

/// The 16-bit count for a fraction (-1..1) of the full scale.
fn count(fraction: f32) -> u16 {
    (32768.0 + fraction * 32768.0).round().clamp(0.0, 65535.0) as u16
}

/// A binary frame of six fractions (-1..1) of the axes' full scales.
fn frame_of(fractions: [f32; 6]) -> Vec<u8> {
    binary(fractions.map(count))
}

/// Pass-through: every speed and acceleration limit off.
fn pass_through() -> Host {
    let mut s = Host::quiet();
    s.ok("set speed_mm_s off");
    s.ok("set speed_deg_s off");
    s
}

fn solve(s: &Host, pose: &Pose) -> Result<ik::Solution, ik::IkError> {
    s.ctl
        .settings()
        .validate()
        .unwrap()
        .solve::<Libm>(&s.ctl.settings().servos, pose)
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

fn poses_close(a: &Pose, b: &Pose, mm: f32, rad: f32) -> bool {
    let (a, b) = (a.to_array(), b.to_array());
    (0..3).all(|i| close(a[i], b[i], mm)) && (3..6).all(|i| close(a[i], b[i], rad))
}

#[test]
fn a_binary_frame_is_applied_at_once_in_pass_through() {
    let mut s = pass_through();
    // A fifth of each default full scale (25, 25, 15 mm; 15, 15, 20 deg), some negative.
    let counts = [
        count(-0.2),
        count(0.2),
        count(0.2),
        count(0.2),
        count(-0.2),
        count(0.2),
    ];
    let out = s.feed(&binary(counts));
    assert_eq!(out, "", "frames get no reply");
    assert!(s.ctl.take_new_pulses().is_none(), "applied by apply_stream");
    s.apply_stream();
    let want = Pose::from_degrees(-5.0, 5.0, 3.0, 3.0, -3.0, 4.0);
    assert!(
        poses_close(s.ctl.pose(), &want, 1e-3, 1e-4),
        "{:?}",
        s.ctl.pose()
    );
    let pulses = s.ctl.take_new_pulses().expect("new pulses at once");
    let reference = solve(&s, &want).unwrap();
    for (got, want) in pulses.iter().zip(reference.pulse_us) {
        assert!(
            close(*got, want, 0.05),
            "{pulses:?} vs {:?}",
            reference.pulse_us
        );
    }
    assert!(s.ctl.servo_power(), "the first frame powers the servos");
    assert_eq!(s.status_field("state"), "streaming (pass-through)");
    assert_eq!(
        s.status_field("stream"),
        "frames=1 applied=1 damaged=0 clamped=0 refused=0"
    );
    // The frame rhythm holds it.
    let held = s.frames(3);
    assert!(held.iter().all(|p| *p == pulses));
}

#[test]
fn the_newest_frame_wins() {
    let mut s = pass_through();
    for z in [0.1, 0.2, 0.3] {
        s.feed(&frame_of([0.0, 0.0, z, 0.0, 0.0, 0.0]));
    }
    s.apply_stream();
    assert!(close(s.ctl.pose().z_mm, 0.3 * 15.0, 1e-3));
    let c = s.ctl.stream_counts();
    assert_eq!((c.frames, c.applied), (3, 1));
    // Nothing fresh: nothing more applied.
    s.apply_stream();
    assert_eq!(s.ctl.stream_counts().applied, 1);
}

#[test]
fn text_frames_use_the_bit_depth_and_axis_order_of_the_profile() {
    let mut s = pass_through();
    s.ok("set stream.bits 10");
    // The profile sends roll, pitch, yaw, x, y, z (say).
    for (n, axis) in ["roll", "pitch", "yaw", "x", "y", "z"].iter().enumerate() {
        s.ok(&format!("set stream.axis{} none", n + 1));
        let _ = axis;
    }
    for (n, axis) in ["roll", "pitch", "yaw", "x", "y", "z"].iter().enumerate() {
        s.ok(&format!("set stream.axis{} {axis}", n + 1));
    }
    // 10 bits: 512 is the middle, 768 is +half, 256 is -half.
    s.feed(b"768,512,256,512,768,512X");
    s.apply_stream();
    let want = Pose::from_degrees(0.0, 12.5, 0.0, 7.5, 0.0, -10.0);
    assert!(
        poses_close(s.ctl.pose(), &want, 1e-3, 1e-4),
        "{:?}",
        s.ctl.pose()
    );
    // A count that does not fit 10 bits: damaged, not applied.
    s.feed(b"1024,512,512,512,512,512X");
    s.apply_stream();
    assert!(poses_close(s.ctl.pose(), &want, 1e-3, 1e-4));
    assert_eq!(s.ctl.stream_counts().damaged, 1);
    // Commands still work on the same link, and a frame keeps no line open.
    s.ok("status");
}

#[test]
fn damaged_frames_and_garbage_are_counted_and_never_applied() {
    let mut s = pass_through();
    let good = frame_of([0.0, 0.0, 0.2, 0.0, 0.0, 0.0]);
    let mut bytes = good.clone();
    bytes.remove(6); // a lost byte: this frame and no other is damaged
    bytes.extend_from_slice(&[0x00, 0xFF, 0x13, 0xA5, 0x00]); // garbage
    bytes.extend(good.clone());
    let out = s.feed(&bytes);
    assert_eq!(out, "", "garbage between frames gets no reply");
    s.apply_stream();
    assert!(close(s.ctl.pose().z_mm, 0.2 * 15.0, 1e-3));
    let c = s.ctl.stream_counts();
    assert_eq!(c.frames, 1);
    assert!(c.damaged >= 1, "{c:?}");
    s.ok("status");
}

#[test]
fn a_text_stream_with_echo_on_is_never_echoed_and_survives_a_byte_outside_ascii() {
    // Echo on, as after power-up: a sim streams into the board without any set-up command.
    let mut s = pass_through();
    s.link.set_echo(true);
    // Text frames (8 bits, 128 is home), one of them hit by 0xC2 and one by a NUL.
    let frame = |z: u32| format!("128,128,{z},128,128,128X").into_bytes();
    let mut bytes = frame(160);
    bytes.extend_from_slice(b"128,128,\xC2170,128,128,128X");
    bytes.extend(frame(150));
    bytes.extend_from_slice(b"128,1\x0028,170,128,128,128X");
    bytes.extend(frame(140));
    let out = s.feed(&bytes);
    assert_eq!(
        out, "",
        "frames and damaged frames are neither echoed nor answered"
    );
    s.apply_stream();
    // 140 of 8 bits: (140 - 128) / 128 of stream.z_mm (15 mm).
    assert!(
        close(s.ctl.pose().z_mm, 12.0 / 128.0 * 15.0, 1e-3),
        "{:?}",
        s.ctl.pose()
    );
    let c = s.ctl.stream_counts();
    assert_eq!((c.frames, c.damaged), (3, 2), "{c:?}");
    // A line that began with a digit is echoed whole when its line end shows it is one.
    let out = s.feed(b"12\r");
    assert!(out.starts_with("12\r\nerror:unknown-command"), "{out:?}");
}

#[test]
fn an_unreachable_target_is_clamped_on_the_way_to_it_and_counted() {
    let mut s = pass_through();
    s.ok("set stream.z_mm 100");
    // z = +80 mm is far outside the default workspace.
    s.feed(&frame_of([0.0, 0.0, 0.8, 0.0, 0.0, 0.0]));
    // The target's IK at once; CLAMP_STEPS bisection steps, CHECKS_PER_SLICE a pass.
    let passes = s.apply_stream();
    assert_eq!(
        passes,
        1 + control::controller::CLAMP_STEPS.div_ceil(control::controller::CHECKS_PER_SLICE)
    );
    let z = s.ctl.pose().z_mm;
    assert!(z > 0.0 && z < 80.0, "{z}");
    assert_eq!((s.ctl.pose().x_mm, s.ctl.pose().roll_rad), (0.0, 0.0));
    // Reachable, and the next 1/64 of the way is not: the last reachable pose, found by
    // bisection.
    let here = *s.ctl.pose();
    assert!(solve(&s, &here).is_ok());
    let beyond = Pose {
        z_mm: z + 80.0 / 64.0,
        ..here
    };
    assert!(solve(&s, &beyond).is_err(), "clamped too early: z {z}");
    assert_eq!(s.ctl.stream_counts().clamped, 1);
    let pulses = s.ctl.take_new_pulses().unwrap();
    let limits = s.ctl.settings().servos.0;
    for (w, servo) in pulses.iter().zip(limits) {
        assert!(w.is_finite() && *w >= servo.min_us && *w <= servo.max_us);
    }
    assert!(s.status_field("stream").contains("clamped=1"));
}

#[test]
fn the_tracker_respects_speed_and_acceleration_and_does_not_overshoot() {
    let mut s = Host::quiet();
    s.ok("set frame_hz 200");
    s.ok("set speed_mm_s 40");
    s.ok("set accel_mm_s2 400");
    s.ok("set speed_deg_s 60");
    s.ok("set accel_deg_s2 600");
    // A step to z = +6 mm and roll = +6 deg.
    s.feed(&frame_of([0.0, 0.0, 0.4, 0.4, 0.0, 0.0]));
    s.apply_stream();
    assert_eq!(
        *s.ctl.pose(),
        Pose::HOME,
        "tracking: nothing moves before a frame"
    );
    assert_eq!(s.status_field("state"), "streaming (tracking)");
    let dt = 1.0 / 200.0;
    let (mut z, mut v) = (0.0f32, 0.0f32);
    let mut frames = 0;
    while s.ctl.is_moving() {
        s.frames(1);
        frames += 1;
        assert!(frames < 1000, "never settled");
        let nz = s.ctl.pose().z_mm;
        let nv = (nz - z) / dt;
        assert!(nv <= 40.0 * 1.001, "speed {nv} mm/s at frame {frames}");
        assert!(
            (nv - v).abs() / dt <= 400.0 * 1.01,
            "accel at frame {frames}"
        );
        assert!(nz <= 6.0 * 1.0001, "overshoot: {nz}");
        assert!(s.ctl.pose().roll_rad <= 6f32.to_radians() * 1.0001);
        (z, v) = (nz, nv);
    }
    // The counts' exact values (0.4 of the full scale, to 1/32768).
    let fraction = (f32::from(count(0.4)) - 32768.0) / 32768.0;
    assert!(close(z, fraction * 15.0, 1e-5), "{z}");
    let roll = (fraction * 15.0).to_radians();
    assert!(close(s.ctl.pose().roll_rad, roll, 1e-7));
    // At least the time a trapezoid needs (6 mm at 400 mm/s^2 peaking below 40 mm/s: 2
    // sqrt(6/400) s = 245 ms = 49 frames).
    assert!(frames >= 49, "{frames}");
    // The pulses follow the poses (solved each frame).
    let reference = solve(&s, s.ctl.pose()).unwrap();
    assert_eq!(s.ctl.pulses_us(), reference.pulse_us);
}

#[test]
fn a_command_ends_the_stream_and_a_frame_starts_it_again() {
    let mut s = pass_through();
    s.feed(&frame_of([0.1, 0.0, 0.0, 0.0, 0.0, 0.0]));
    s.apply_stream();
    assert!(s.ctl.is_streaming());
    s.ok("pose 0 0 2 0 0 0");
    assert!(!s.ctl.is_streaming());
    assert_eq!(
        *s.ctl.pose(),
        Pose::from_degrees(0.0, 0.0, 2.0, 0.0, 0.0, 0.0)
    );
    s.feed(&frame_of([0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    s.apply_stream();
    assert!(s.ctl.is_streaming());
    assert_eq!(*s.ctl.pose(), Pose::HOME);
    s.ok("stop");
    assert!(!s.ctl.is_streaming());
}

#[test]
fn the_e_stop_freezes_refuses_moves_and_frames_until_closed_and_reset() {
    let mut s = pass_through();
    s.ok("set estop_pin 15");
    s.ok("set power_pin 16");
    assert!(!s.ctl.servo_power(), "off at start-up");
    s.feed(&frame_of([0.2, 0.0, 0.0, 0.0, 0.0, 0.0]));
    s.apply_stream();
    assert!(s.ctl.servo_power());
    let frozen = *s.ctl.pose();
    s.ctl.set_estop_input(true);
    assert_eq!(s.ctl.estop(), Estop::Open);
    assert!(!s.ctl.servo_power(), "power off on e-stop");
    assert!(!s.ctl.is_streaming());
    let notice = s.notices();
    assert!(
        notice.starts_with("# emergency stop: input open; platform frozen, servo power off"),
        "{notice:?}"
    );
    // Frames are refused and counted; moves are refused with the reason.
    s.feed(&frame_of([-0.2, 0.0, 0.0, 0.0, 0.0, 0.0]));
    s.apply_stream();
    assert_eq!(*s.ctl.pose(), frozen);
    assert_eq!(s.ctl.stream_counts().refused, 1);
    let refusal = s.err("home");
    assert_eq!(code_of(&refusal), "e-stop");
    assert!(refusal.contains("input is open"), "{refusal}");
    assert_eq!(s.code("reset"), "e-stop", "reset while the input is open");
    s.ok("check 0 0 1 0 0 0"); // nothing moves: allowed
    s.ok("status");
    assert_eq!(s.status_field("e-stop"), "open");
    // Closing the input is not enough.
    s.ctl.set_estop_input(false);
    assert!(s
        .notices()
        .contains("emergency stop: input closed; send reset"));
    assert!(s.err("pose 0 0 1 0 0 0").contains("send reset"));
    assert_eq!(*s.ctl.pose(), frozen);
    s.ok("reset");
    assert_eq!(s.ctl.estop(), Estop::Clear);
    s.ok("home");
    assert!(
        s.ctl.servo_power(),
        "the next accepted move powers the servos"
    );
}

#[test]
fn the_e_stop_can_ease_home_then_power_off() {
    let mut s = Host::quiet();
    s.ok("set estop_pin 15");
    s.ok("set estop_action home");
    s.ok("set power_pin 16");
    s.ok("pose 5 0 3 0 0 4");
    s.frames(200);
    assert!(s.ctl.servo_power() && !s.ctl.is_moving());
    s.ctl.set_estop_input(true);
    let mut out = String::new();
    while s.ctl.is_busy() {
        s.ctl.work(&mut s.link, &mut out);
    }
    assert_eq!(out, "", "the e-stop's own move replies to nobody");
    assert!(s.ctl.is_moving(), "going home");
    assert!(s.ctl.servo_power(), "powered until home");
    assert!(s.status_field("state").starts_with("going home (e-stop)"));
    s.frames(400);
    assert_eq!(*s.ctl.pose(), Pose::HOME);
    assert!(!s.ctl.servo_power(), "power off once home");
}

#[test]
fn a_stream_that_stops_eases_home_after_the_link_timeout() {
    let mut s = pass_through();
    s.ok("set link_timeout_s 0.2");
    s.feed(&frame_of([0.0, 0.0, 0.3, 0.0, 0.0, 0.0]));
    s.apply_stream();
    s.frames(5);
    assert!(s.ctl.is_streaming(), "frames are a sign of life");
    s.frames(30);
    assert!(s.notices().contains("link lost"));
    s.frames(100);
    assert_eq!(*s.ctl.pose(), Pose::HOME);
    assert!(!s.ctl.is_streaming());
}

#[test]
fn defaults_for_a_fresh_board_have_no_safety_pins() {
    let s = Settings::default();
    assert_eq!(s.safety.estop_pin, None);
    assert_eq!(s.safety.power_pin, None);
}

#[test]
fn a_clamp_is_the_controllers_own_work_a_slice_at_a_time() {
    let mut s = pass_through();
    s.ok("set stream.z_mm 100");
    s.feed(&frame_of([0.0, 0.0, 0.8, 0.0, 0.0, 0.0]));
    s.ctl.apply_stream();
    // The target's own IK failed: the bisection (6 IK solutions) is left to `work`, a few per
    // slice, so the pass that fed the frame stays short; nothing moved yet.
    assert!(s.ctl.is_busy());
    assert_eq!(*s.ctl.pose(), Pose::HOME);
    let mut slices = 0;
    let mut out = String::new();
    while s.ctl.is_busy() {
        s.ctl.work(&mut s.link, &mut out);
        slices += 1;
    }
    assert_eq!(out, "", "the controller's own work replies to nobody");
    assert!(slices >= 2, "{slices} slice(s) for 6 IK solutions");
    assert!(s.ctl.pose().z_mm > 0.0);
    assert!(s.ctl.take_new_pulses().is_some());
}

/// Feeds bytes as the board's main loop does in one pass: up to the end of a line, or until a
/// command's work begins; then applies the newest stream frame. Returns what was written.
fn one_pass(s: &mut Host, bytes: &[u8]) -> String {
    let mut out = String::new();
    for &b in bytes {
        s.ctl.on_byte(&mut s.link, b, &mut out);
        if s.ctl.is_busy() {
            break;
        }
    }
    s.ctl.apply_stream();
    out
}

/// Then the passes until the work in progress is done, one with no input, and the passes of
/// the work that one may start.
fn passes_until_idle(s: &mut Host) -> String {
    let work = |s: &mut Host, out: &mut String| {
        while s.ctl.is_busy() {
            s.ctl.work(&mut s.link, out);
        }
    };
    let mut out = String::new();
    work(s, &mut out);
    out += &one_pass(s, b"");
    work(s, &mut out);
    out
}

#[test]
fn a_frame_fed_with_a_command_in_the_same_pass_is_applied_after_the_command_s_work() {
    // The stream's last frame and the host's `status` after it, in one pass: the frame is
    // applied once the listing is done, whatever its target needs first (a torque check, a
    // clamp), never dropped.
    // (case, with torque ratings, z as a fraction of its full scale of 15 mm, the least z the
    // platform must reach, mm)
    let cases = [
        ("reachable, no ratings", false, 0.2, 3.0),
        ("reachable, torque-checked", true, 0.2, 3.0),
        ("beyond reach, clamped", false, 1.0, 13.5),
    ];
    for (case, rated, z, at_least_mm) in cases {
        let mut s = pass_through();
        if rated {
            s.ok("set payload_g 1000");
            s.ok("set servos.torque_kgcm 20");
        }
        let mut bytes = frame_of([0.0, 0.0, z, 0.0, 0.0, 0.0]);
        bytes.extend_from_slice(b"status\r\n");
        one_pass(&mut s, &bytes);
        let out = passes_until_idle(&mut s);
        assert!(out.ends_with("ok\r\n"), "{case}: {out:?}");
        let c = s.ctl.stream_counts();
        assert_eq!((c.frames, c.applied), (1, 1), "{case}");
        let zmm = s.ctl.pose().z_mm;
        assert!(
            zmm >= at_least_mm - 1e-3 && zmm <= z * 15.0 + 1e-3,
            "{case}: z = {zmm} mm"
        );
    }
}
