//! Every command and every error class, through the byte interface.

mod common;

use common::{code_of, is_final, pose_values, six, Host};
use control::settings::SettingId;
use control::store::{RamFlash, SaveError, Store};
use control::Settings;
use kinematics_core::geometry::PairedLayout;
use kinematics_core::{ik, Libm, Pose, ServoSet};

/// A reachable pose whose straight path from home is clear, and a reachable pose whose
/// straight path from the first crosses a region the legs cannot reach (found by search).
const BLOCKED_FROM: &str = "pose -28 19 -2.5 11 2 -20";
const BLOCKED_TO: &str = "30 -12 -13.5 5 -13 28";

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn banner_then_prompt_when_echo_is_on() {
    let ctl = control::Controller::new(Settings::default());
    let mut out = String::new();
    ctl.banner(&mut control::Session::new(), &mut out);
    assert!(out.starts_with("# hexapod control"), "{out:?}");
    assert!(out.ends_with("\r\n> "), "{out:?}");
    assert!(!out.contains("ok") && !out.contains("error:"));
}

#[test]
fn typed_characters_are_echoed_and_backspace_erases() {
    let mut s = Host::with(Settings::default());
    let out = s.feed(b"hoxx\x08\x7fme\r");
    assert_eq!(out, "hoxx\x08 \x08\x08 \x08me\r\nok\r\n> ");
    // Ctrl-C abandons the line without a reply.
    let out = s.feed(b"pose 1\x03");
    assert_eq!(out, "pose 1^C\r\n> ");
    // Ctrl-U erases the whole line on the screen.
    let out = s.feed(b"ab\x15");
    assert_eq!(out, "ab\x08 \x08\x08 \x08");
    // A blank line is just a fresh prompt.
    assert_eq!(s.feed(b"\r"), "\r\n> ");
    assert_eq!(s.feed(b"   \r\n"), "   \r\n> ");
}

#[test]
fn echo_off_is_for_programs() {
    let mut s = Host::with(Settings::default());
    assert_eq!(s.feed(b"set echo off\r\n"), "set echo off\r\nok\r\n");
    assert!(!s.link.echo());
    assert_eq!(s.feed(b"home\r\n"), "ok\r\n");
    assert_eq!(s.feed(b"\r\n \n"), "");
    assert_eq!(s.feed(b"ab\x08c\x03"), "");
    assert_eq!(s.feed(b"set echo on\n"), "ok\r\n> ");
}

#[test]
fn every_line_end_gets_one_reply() {
    let mut s = Host::quiet();
    for end in ["\r", "\n", "\r\n"] {
        let out = s.feed(format!("status{end}").as_bytes());
        assert_eq!(out.lines().filter(|l| is_final(l)).count(), 1, "{end:?}");
    }
    // Two lines in one burst, LF CR between them (a CR after an LF is a blank line).
    let out = s.feed(b"home\n\rstop\r\n");
    assert_eq!(out, "ok\r\nok\r\n");
}

#[test]
fn commands_are_case_insensitive() {
    let mut s = Host::quiet();
    s.ok("POSE 0 0 2 0 0 0");
    s.ok("Set Speed_MM_S 20");
    s.ok("STATUS");
    s.ok("?");
}

#[test]
fn status_shows_pose_target_state_angles_and_pulses() {
    let mut s = Host::quiet();
    let data = s.ok("status");
    let keys: Vec<&str> = data
        .iter()
        .map(|l| l.trim_start_matches("# ").split(':').next().unwrap())
        .collect();
    assert_eq!(
        keys,
        [
            "state",
            "pose",
            "target",
            "arm_deg",
            "pulse_us",
            "stream",
            "e-stop",
            "servo_power"
        ]
    );
    assert_eq!(
        s.status_field("stream"),
        "frames=0 applied=0 damaged=0 clamped=0 refused=0"
    );
    assert_eq!(s.status_field("e-stop"), "clear");
    assert_eq!(s.status_field("servo_power"), "off");
    assert_eq!(s.status_field("state"), "idle");
    // Arm angles with 3 decimals, pulses with 2.
    for (key, decimals) in [("arm_deg", 3), ("pulse_us", 2)] {
        let text = s.status_field(key);
        for v in text.split(' ') {
            assert_eq!(
                v.split('.').nth(1).map(str::len),
                Some(decimals),
                "{key}: {text}"
            );
        }
    }
    // At home the pulses are the trims and the arms are at alpha0.
    let g = ik::Solver::new(PairedLayout::default().build().unwrap()).unwrap();
    let arm = six(&s.status_field("arm_deg"));
    for (i, a) in arm.iter().enumerate() {
        assert!(close(*a, g.alpha0_rad(i).to_degrees(), 1e-3));
    }
    assert_eq!(six(&s.status_field("pulse_us")), [1500.0; 6]);
}

#[test]
fn pose_moves_there_and_status_reports_it() {
    let mut s = Host::quiet();
    s.ok("pose 3 -2 5 4 -3 6");
    assert!(s.ctl.is_moving());
    assert!(s.status_field("state").starts_with("moving"));
    assert_eq!(
        pose_values(&s.status_field("target")),
        [3.0, -2.0, 5.0, 4.0, -3.0, 6.0]
    );
    s.run_until_idle();
    s.frames(1);
    assert_eq!(s.status_field("state"), "idle");
    assert_eq!(
        pose_values(&s.status_field("pose")),
        [3.0, -2.0, 5.0, 4.0, -3.0, 6.0]
    );
    // The pulses are what the IK says for that pose.
    let expected = ik::Solver::new(PairedLayout::default().build().unwrap())
        .expect("a valid geometry")
        .solve::<Libm>(
            &ServoSet::default(),
            &Pose::from_degrees(3.0, -2.0, 5.0, 4.0, -3.0, 6.0),
        )
        .unwrap();
    let shown = six(&s.status_field("pulse_us"));
    let given = s.ctl.on_frame();
    for i in 0..6 {
        assert!(close(shown[i], expected.pulse_us[i], 0.006));
        assert!(close(given[i], expected.pulse_us[i], 1e-3));
    }
}

#[test]
fn move_changes_only_the_named_axes() {
    let mut s = Host::quiet();
    s.ok("pose 1 2 3 4 5 6");
    s.ok("move z=-4 yaw=-2");
    assert_eq!(
        pose_values(&s.status_field("target")),
        [1.0, 2.0, -4.0, 4.0, 5.0, -2.0]
    );
    s.run_until_idle();
    assert_eq!(
        pose_values(&s.status_field("pose")),
        [1.0, 2.0, -4.0, 4.0, 5.0, -2.0]
    );
}

#[test]
fn nudge_is_relative_to_the_target_and_accumulates() {
    let mut s = Host::quiet();
    s.ok("pose 1 2 3 4 5 6");
    s.ok("nudge x=1 roll=-1");
    s.ok("nudge x=1.5");
    assert_eq!(
        pose_values(&s.status_field("target")),
        [3.5, 2.0, 3.0, 3.0, 5.0, 6.0]
    );
    s.run_until_idle();
    assert_eq!(
        pose_values(&s.status_field("pose")),
        [3.5, 2.0, 3.0, 3.0, 5.0, 6.0]
    );
}

#[test]
fn home_returns_and_stop_freezes() {
    let mut s = Host::quiet();
    s.ok("set speed_mm_s 10");
    s.ok("pose 0 0 10 0 0 0");
    s.frames(10);
    s.ok("stop");
    let here = pose_values(&s.status_field("pose"));
    assert!(close(here[2], 2.0, 1e-3), "{here:?}");
    assert_eq!(pose_values(&s.status_field("target")), here);
    assert_eq!(s.status_field("state"), "idle");
    let held = s.ctl.on_frame();
    assert_eq!(s.frames(20), vec![held; 20]);
    s.ok("home");
    s.run_until_idle();
    assert_eq!(pose_values(&s.status_field("pose")), [0.0; 6]);
    assert_eq!(s.ctl.on_frame(), [1500.0; 6]);
}

#[test]
fn check_reports_pulses_and_nothing_moves() {
    let mut s = Host::quiet();
    let data = s.ok("check 5 0 -3 2 0 -4");
    let field = |key: &str| {
        data.iter()
            .find_map(|l| l.strip_prefix(&format!("# {key}: ")))
            .unwrap()
            .to_owned()
    };
    let expected = ik::Solver::new(PairedLayout::default().build().unwrap())
        .expect("a valid geometry")
        .solve::<Libm>(
            &ServoSet::default(),
            &Pose::from_degrees(5.0, 0.0, -3.0, 2.0, 0.0, -4.0),
        )
        .unwrap();
    let pulses = six(&field("pulse_us"));
    let arm = six(&field("arm_deg"));
    for i in 0..6 {
        assert!(close(pulses[i], expected.pulse_us[i], 0.006));
        assert!(close(arm[i], expected.arm_rad[i].to_degrees(), 6e-4));
    }
    // sqrt(25 + 9) mm at 50 mm/s vs sqrt(4 + 16) deg at 60 deg/s: linear is slower.
    let duration: f32 = field("duration_s").parse().unwrap();
    let needed = 34f32.sqrt() / 50.0;
    assert!(duration >= needed && duration < needed + 0.02, "{duration}");
    assert!(!s.ctl.is_moving());
    s.frames(50);
    assert_eq!(pose_values(&s.status_field("pose")), [0.0; 6]);
    // The same refusals as pose.
    assert_eq!(s.code("check 0 0 60 0 0 0"), "unreachable");
    assert_eq!(s.code("check 0 0 0 0 0"), "missing-field");
}

#[test]
fn geometry_lists_the_build() {
    let mut s = Host::quiet();
    let data = s.ok("geometry");
    let solver = ik::Solver::new(PairedLayout::default().build().unwrap()).unwrap();
    let g = solver.geometry();
    let h0: f32 = data
        .iter()
        .find_map(|l| l.strip_prefix("# home_height_mm (h0): "))
        .unwrap()
        .parse()
        .unwrap();
    assert!(close(h0, g.home_height_mm(), 6e-4));
    assert!(data.iter().any(|l| l == "# arm_mm (a): 20.000"));
    assert!(data.iter().any(|l| l == "# rod_mm (s): 120.000"));
    for (i, leg) in g.legs().iter().enumerate() {
        let line = data
            .iter()
            .find(|l| l.starts_with(&format!("# leg {}: ", i + 1)))
            .unwrap();
        let beta = format!("beta_deg={:.3}", leg.beta_rad.to_degrees());
        let alpha0 = format!("alpha0_deg={:.3}", solver.alpha0_rad(i).to_degrees());
        assert!(line.contains(&beta) && line.contains(&alpha0), "{line}");
        assert!(line.contains("b_mm=(") && line.contains("p_mm=("), "{line}");
    }
}

#[test]
fn config_values_can_be_set_back_unchanged() {
    let mut s = Host::quiet();
    s.ok("set servo3.trim_us 1512.5");
    s.ok("set link_timeout_s 4");
    s.ok("set accel_mm_s2 250");
    s.ok("set stream.axis1 none");
    s.ok("set stream.axis4 x");
    s.ok("set stream.pitch_deg -12.5");
    s.ok("set stream.bits 10");
    s.ok("set estop_pin 15");
    s.ok("set estop_action home");
    s.ok("set power_pin 16");
    s.ok("set payload_g 850");
    s.ok("set payload_com_z_mm 25.5");
    s.ok("set servo2.torque_kgcm 4.25");
    let before = *s.ctl.settings();
    let mut data = s.ok("config");
    // The last line says how the settings stand against those saved; it is not a setting.
    assert_eq!(
        data.pop().as_deref(),
        Some("# saved: none (nothing saved in flash: the defaults at power-up)")
    );
    let mut commands = Vec::new();
    for line in &data {
        let line = line.strip_prefix("# ").unwrap();
        let (name, rest) = line.split_once(':').unwrap();
        if let Some(servo) = name.strip_prefix("servo") {
            for kv in rest.split_whitespace() {
                let (field, value) = kv.split_once('=').unwrap();
                commands.push(format!("set servo{servo}.{field} {value}"));
            }
        } else {
            commands.push(format!("set {name} {}", rest.trim()));
        }
    }
    assert_eq!(
        commands.len(),
        SettingId::GLOBAL.len() + 6 * control::settings::ServoParam::ALL.len()
    );
    s.ok("defaults");
    for c in &commands {
        s.ok(c);
    }
    let after = *s.ctl.settings();
    assert_eq!(after.stream, before.stream);
    assert_eq!(after.safety, before.safety);
    assert_eq!(after.payload, before.payload);
    assert_eq!(after.accel_mm_s2, 250.0);
    // Values shown with 2-3 decimals come back within that rounding.
    assert_eq!(after.servos.0[2].home_us, 1512.5);
    assert_eq!(after.link_timeout_s, 4.0);
    assert_eq!(after.frame_hz, before.frame_hz);
    assert_eq!((s.ctl.baud(), s.link.echo()), (115_200, false));
    for (a, b) in after.servos.0.iter().zip(before.servos.0.iter()) {
        assert!(close(a.rate_us_per_rad, b.rate_us_per_rad, 6e-4));
        assert_eq!(a.direction, b.direction);
        assert!(close(a.min_us, b.min_us, 6e-3) && close(a.max_us, b.max_us, 6e-3));
    }
}

#[test]
fn pulses_is_one_short_line_of_what_the_pins_carry() {
    let mut s = Host::quiet();
    // At home: the trims, one data line, and the whole answer fits the budget docs/commands.md
    // gives (63 bytes with its `ok`: what `hexapod view` counts on over UART0).
    let out = s.feed(b"pulses\n");
    assert_eq!(
        out,
        "# pulse_us: 1500.00 1500.00 1500.00 1500.00 1500.00 1500.00\r\nok\r\n"
    );
    assert_eq!(out.replace("\r\n", "\n").len(), 63);

    // During a move it follows the frames: each answer is the pulses of the frame before it,
    // the very widths on_frame hands the PWM.
    s.ok("pose 10 -5 8 4 -3 6");
    let mut seen = Vec::new();
    for _ in 0..20 {
        let written = s.frames(3)[2];
        let data = s.ok("pulses");
        assert_eq!(data.len(), 1, "{data:?}");
        let shown = six(data[0].strip_prefix("# pulse_us: ").unwrap());
        for (a, b) in shown.iter().zip(written) {
            assert!(close(*a, b, 0.006), "{shown:?} vs {written:?}");
        }
        seen.push(shown);
    }
    assert!(
        seen.windows(2).any(|w| w[0] != w[1]),
        "never moved: {seen:?}"
    );
    s.run_until_idle();
    s.frames(1);
    // At rest the pulses are the status' pulses (the pose's IK).
    assert_eq!(
        s.ok("pulses")[0],
        format!("# pulse_us: {}", s.status_field("pulse_us"))
    );
    // It moves nothing and changes nothing: still idle, same target.
    assert_eq!(s.status_field("state"), "idle");
}

#[test]
fn help_lists_every_command() {
    let mut s = Host::quiet();
    let help = s.ok("help").join("\n");
    for cmd in [
        "pose", "move", "nudge", "check", "home", "stop", "reset", "status", "?", "pulses",
        "geometry", "config", "set", "defaults", "save", "help",
    ] {
        assert!(
            help.contains(&format!("  {cmd} "))
                || help.contains(&format!("({cmd} "))
                || help.contains(&format!("or {cmd})")),
            "{cmd}"
        );
    }
}

#[test]
fn settings_change_bumps_the_generation() {
    let mut s = Host::quiet();
    let g0 = s.ctl.settings_generation();
    s.ok("set frame_hz 200");
    s.ok("set baud 921600");
    assert_eq!((s.ctl.frame_hz(), s.ctl.baud()), (200, 921_600));
    assert_eq!(s.ctl.settings_generation(), g0 + 2);
}

#[test]
fn refused_settings_change_nothing() {
    let mut s = Host::quiet();
    let before = *s.ctl.settings();
    let generation = s.ctl.settings_generation();
    for (line, code) in [
        ("set frame_hz 49", "out-of-range"),
        ("set frame_hz 334", "out-of-range"),
        ("set frame_hz 60.5", "bad-value"),
        ("set baud 100000", "bad-value"),
        ("set baud 1e3", "bad-value"),
        ("set echo sometimes", "bad-value"),
        ("set speed_mm_s -3", "out-of-range"),
        ("set speed_deg_s inf", "not-finite"),
        ("set link_timeout_s 1e39", "number-too-large"),
        ("set servo1.trim_us 2700", "out-of-range"),
        ("set servo1.trim_us 1950", "bad-servo-config"),
        ("set servo6.min_us 1600", "bad-servo-config"),
        ("set servos.max_us 1400", "bad-servo-config"),
        ("set servo2.rate_us_rad 50", "out-of-range"),
        ("set servo2.dir up", "bad-value"),
        ("set servo7.dir normal", "unknown-setting"),
        ("set rod_mm 15", "bad-geometry"),
        ("set arm_mm 0", "out-of-range"),
        ("set colour red", "unknown-setting"),
        ("set frame_hz", "missing-field"),
        ("set frame_hz 100 200", "extra-field"),
        ("set frame_hz abc", "bad-number"),
    ] {
        assert_eq!(s.code(line), code, "{line}");
        assert_eq!(*s.ctl.settings(), before, "{line}");
        assert_eq!(s.ctl.settings_generation(), generation, "{line}");
    }
}

#[test]
fn error_messages_name_the_setting_servo_and_limit() {
    let mut s = Host::quiet();
    let e = s.err("set servo4.trim_us 1950");
    assert!(
        e.contains("servo4.trim_us") && e.contains("1950.00") && e.contains("1900.00"),
        "{e}"
    );
    let e = s.err("set frame_hz 20");
    assert!(
        e.contains("frame_hz") && e.contains("50") && e.contains("333"),
        "{e}"
    );
    let e = s.err("set rod_mm 15");
    assert!(e.contains("rod_mm"), "{e}");
}

#[test]
fn trim_and_direction_apply_at_once() {
    let mut s = Host::quiet();
    s.ok("pose 0 0 5 0 0 0");
    s.run_until_idle();
    let before = s.ctl.on_frame();
    s.ok("set servo2.trim_us 1520");
    let after = s.ctl.on_frame();
    assert!(close(after[1] - before[1], 20.0, 1e-3));
    assert_eq!(after[0], before[0]);
    // Reversing servo 2 mirrors its pulse about the trim.
    s.ok("set servo2.dir reversed");
    let mirrored = s.ctl.on_frame();
    assert!(close(mirrored[1] - 1520.0, -(before[1] - 1500.0), 1e-2));
    s.ok("set baud 921600");
    s.ok("defaults");
    // Everything back to the defaults except the link settings.
    assert_eq!(*s.ctl.settings(), Settings::default());
    assert_eq!((s.ctl.baud(), s.link.echo()), (921_600, false));
}

#[test]
fn settings_that_would_drop_the_held_pose_are_refused() {
    let mut s = Host::quiet();
    s.ok("pose 0 0 -8 0 0 0");
    s.run_until_idle();
    let pulses = s.ctl.on_frame();
    // Servo 1's pulse here is well above 1600 us.
    assert!(pulses[0] > 1650.0, "{pulses:?}");
    let before = *s.ctl.settings();
    let e = s.err("set servo1.max_us 1600");
    assert_eq!(code_of(&e), "pose-conflict");
    assert!(e.contains("servo 1"), "{e}");
    assert_eq!(*s.ctl.settings(), before);
    s.ok("home");
    s.run_until_idle();
    s.ok("set servo1.max_us 1600");
}

#[test]
fn motion_settings_are_busy_while_moving_but_others_are_not() {
    let mut s = Host::quiet();
    s.ok("set speed_mm_s 5");
    s.ok("pose 0 0 5 0 0 0");
    assert!(s.ctl.is_moving());
    for line in [
        "set servo1.trim_us 1510",
        "set frame_hz 100",
        "set arm_mm 21",
        "defaults",
    ] {
        assert_eq!(s.code(line), "busy", "{line}");
    }
    s.ok("set speed_mm_s 10");
    s.ok("set link_timeout_s 5");
    s.ok("stop");
    s.ok("set frame_hz 100");
}

#[test]
fn every_pose_error_class_and_the_next_line_works() {
    let mut s = Host::quiet();
    s.ok("pose 1 1 1 1 1 1");
    s.run_until_idle();
    let target = s.status_field("target");
    for (line, code) in [
        ("pose 0 0 80 0 0 0", "unreachable"),
        ("pose 0 0 -15 0 0 0", "servo-limit"),
        ("pose 0 0 0 181 0 0", "angle-too-large"),
        ("pose 1 2 3", "missing-field"),
        ("pose 1 2 3 4 5 6 7", "extra-field"),
        ("pose 1 2 three 4 5 6", "bad-number"),
        ("pose 0x10 0 0 0 0 0", "bad-number"),
        ("pose 1 2 3 nan 5 6", "not-finite"),
        ("pose inf 2 3 4 5 6", "not-finite"),
        ("pose 1e39 0 0 0 0 0", "number-too-large"),
        ("move", "missing-field"),
        ("move z", "bad-assignment"),
        ("move q=1", "unknown-axis"),
        ("move z=1 z=2", "duplicate-axis"),
        ("nudge z=1e39", "number-too-large"),
        ("nudge z=100", "unreachable"),
        ("home now", "extra-field"),
        ("fly 1 2 3", "unknown-command"),
    ] {
        assert_eq!(s.code(line), code, "{line}");
        assert!(!s.ctl.is_moving(), "{line}");
        assert_eq!(s.status_field("target"), target, "{line}");
    }
    s.ok("pose 0 0 2 0 0 0");
}

#[test]
fn pose_errors_name_the_field_leg_or_servo() {
    let mut s = Host::quiet();
    let e = s.err("pose 1 2 3 nan 5 6");
    assert!(e.contains("roll") && e.contains("'nan'"), "{e}");
    let e = s.err("pose 1 2");
    assert!(e.contains("missing z"), "{e}");
    let e = s.err("pose 0 0 80 0 0 0");
    assert!(e.contains("leg "), "{e}");
    let e = s.err("pose 0 0 -15 0 0 0");
    assert!(
        e.contains("servo ") && e.contains("1100.00..1900.00"),
        "{e}"
    );
    let e = s.err("move yaw=200");
    assert!(e.contains("yaw 200.000 deg"), "{e}");
}

#[test]
fn path_through_unreachable_space_is_refused_before_anything_moves() {
    let mut s = Host::quiet();
    s.ok(BLOCKED_FROM);
    s.run_until_idle();
    s.frames(1);
    let pose = s.status_field("pose");
    let pulses = s.ctl.on_frame();
    // The target itself is fine ...
    let to: Vec<f32> = BLOCKED_TO.split(' ').map(|v| v.parse().unwrap()).collect();
    let target = Pose::from_degrees(to[0], to[1], to[2], to[3], to[4], to[5]);
    let geometry = PairedLayout::default().build().unwrap();
    let solver = ik::Solver::new(geometry.clone()).expect("a valid geometry");
    assert!(solver.solve::<Libm>(&ServoSet::default(), &target).is_ok());
    // ... but the straight line to it from here is not.
    let e = s.err(&format!("pose {BLOCKED_TO}"));
    assert_eq!(code_of(&e), "path-blocked");
    assert!(e.contains("% of the way"), "{e}");
    assert!(!s.ctl.is_moving());
    assert_eq!(s.frames(10), vec![pulses; 10]);
    assert_eq!(s.status_field("pose"), pose);
    assert_eq!(s.status_field("target"), pose);
    // check says the same, and a jump is refused too.
    assert_eq!(s.code(&format!("check {BLOCKED_TO}")), "path-blocked");
    s.ok("set speed_mm_s off");
    s.ok("set speed_deg_s off");
    assert_eq!(s.code(&format!("pose {BLOCKED_TO}")), "path-blocked");
    assert_eq!(s.frames(3), vec![pulses; 3]);
}

#[test]
fn too_long_line_gets_one_error_and_the_next_line_works() {
    let mut s = Host::quiet();
    // Exactly 128 characters is fine.
    let line = format!("{:<128}", "pose 0 0 1 0 0 0");
    assert_eq!(s.ok(&line), Vec::<String>::new());
    let long = format!("{line}x");
    let out = s.send(&long);
    assert_eq!(out.len(), 1, "{out:?}");
    assert_eq!(code_of(&out[0]), "line-too-long");
    let very_long = "pose ".repeat(100);
    assert_eq!(s.code(&very_long), "line-too-long");
    s.ok("status");
}

#[test]
fn non_ascii_is_refused() {
    let mut s = Host::quiet();
    assert_eq!(s.code("pose 0 0 1 0 0 0°"), "bad-character");
    s.ok("status");
}

#[test]
fn rx_overflow_warns_at_once_and_refuses_the_line() {
    let mut s = Host::quiet();
    s.feed(b"pose 1 2");
    let mut out = String::new();
    s.ctl.on_input_lost(&mut s.link, 17, false, &mut out);
    assert!(out.starts_with("# ") && out.contains("17 bytes"), "{out:?}");
    s.ctl.on_rx_overflow(
        &mut s.link,
        control::protocol::Lost {
            bytes: 17,
            in_uart: false,
        },
    );
    assert!(!out.contains("ok") && !out.contains("error:"));
    let out = s.feed(b" 3 0 0 0\r\n");
    assert_eq!(out.lines().count(), 1, "{out:?}");
    assert_eq!(code_of(out.trim_end()), "rx-overflow");
    assert!(!s.ctl.is_moving());
    s.ok("status");
}

#[test]
fn invalid_start_up_settings_fall_back_to_defaults_and_say_so() {
    let mut bad = Settings::default();
    bad.layout.rod_mm = 5.0;
    let ctl = control::Controller::new(bad);
    assert_eq!(*ctl.settings(), Settings::default());
    let mut out = String::new();
    ctl.banner(&mut control::Session::new(), &mut out);
    assert!(
        out.contains("# warning: stored settings refused (error:bad-geometry"),
        "{out}"
    );
    assert!(control::Controller::<Libm>::try_with_math(bad).is_err());
}

/// A controller powered up from `flash`, as the board starts one; its banner (with any
/// warning) and a program's link.
fn power_up(flash: &mut RamFlash) -> (Host, String) {
    let loaded = Store::load(flash);
    let mut host = Host::quiet();
    host.ctl = control::Controller::power_up(loaded);
    host.flash = flash.clone();
    let mut banner = String::new();
    host.ctl.banner(&mut host.link, &mut banner);
    (host, banner)
}

fn saved_line(host: &mut Host) -> String {
    host.ok("config").pop().expect("config has lines")
}

#[test]
fn save_keeps_the_settings_for_the_next_power_up() {
    let mut flash = RamFlash::new();
    let (mut s, banner) = power_up(&mut flash);
    assert_eq!(
        banner,
        "# hexapod control 0.1.0: poses in mm and degrees; type help\r\n\
         # warning: no settings saved in flash; using the defaults\r\n"
    );
    assert_eq!(
        saved_line(&mut s),
        "# saved: none (nothing saved in flash: the defaults at power-up)"
    );
    s.ok("set servo3.trim_us 1512.5");
    s.ok("set speed_mm_s 20");
    s.ok("save");
    assert_eq!(
        saved_line(&mut s),
        "# saved: yes (these settings are the ones saved in flash)"
    );
    s.ok("set servo3.trim_us 1513");
    assert_eq!(
        saved_line(&mut s),
        "# saved: no (changed since the last save; save keeps them)"
    );
    // Power off without saving the last change: the saved settings come back, quietly.
    let expected = {
        let mut e = Settings::default();
        e.servos.0[2].home_us = 1512.5;
        e.speed_mm_s = 20.0;
        e
    };
    let mut flash = s.flash.clone();
    let (mut s, banner) = power_up(&mut flash);
    assert_eq!(*s.ctl.settings(), expected);
    assert!(!banner.contains("warning"), "{banner}");
    assert_eq!(
        s.ctl.pulses_us()[2],
        1512.5,
        "servo 3 at its saved trim at power-up"
    );
    assert!(saved_line(&mut s).starts_with("# saved: yes"));
    // defaults, then save: back to the factory settings at the next power-up.
    s.ok("defaults");
    assert!(saved_line(&mut s).starts_with("# saved: no"));
    s.ok("save");
    let mut flash = s.flash.clone();
    let (s, _) = power_up(&mut flash);
    assert_eq!(*s.ctl.settings(), Settings::default());
}

#[test]
fn save_keeps_uart0_s_rate_for_the_next_power_up_and_defaults_keeps_it() {
    let mut flash = RamFlash::new();
    let (mut s, _) = power_up(&mut flash);
    assert_eq!(s.ctl.baud(), 115_200, "nothing saved: the default rate");
    s.ok("set baud 921600");
    s.ok("save");
    assert!(saved_line(&mut s).starts_with("# saved: yes"));
    // A rate changed since the save is a change `config` reports.
    s.ok("set baud 460800");
    assert!(saved_line(&mut s).starts_with("# saved: no"));
    // Power off: UART0 comes back at the saved rate, which `defaults` leaves alone.
    let mut flash = s.flash.clone();
    let (mut s, banner) = power_up(&mut flash);
    assert_eq!(s.ctl.baud(), 921_600);
    assert!(!banner.contains("warning"), "{banner}");
    assert!(s.ok("config").contains(&"# baud: 921600".to_string()));
    s.ok("defaults");
    assert_eq!(s.ctl.baud(), 921_600);
    s.ok("set baud 115200");
    s.ok("save");
    let mut flash = s.flash.clone();
    let (s, _) = power_up(&mut flash);
    assert_eq!(s.ctl.baud(), 115_200);
}

#[test]
fn save_is_refused_while_moving_and_writes_nothing() {
    let mut s = Host::quiet();
    s.ok("set speed_mm_s 5");
    s.ok("pose 10 0 0 0 0 0");
    s.frames(3);
    assert_eq!(
        s.err("save"),
        "error:busy the platform is moving; wait for it or send stop first"
    );
    assert_eq!(s.flash, RamFlash::new(), "nothing was written");
    s.run_until_idle();
    s.ok("save");
    assert_eq!(s.flash.erases, [1, 0]);
}

#[test]
fn the_reply_to_save_waits_for_the_board_to_write_and_verify() {
    let mut s = Host::quiet();
    let mut out = String::new();
    for &b in b"save\n" {
        s.ctl.on_byte(&mut s.link, b, &mut out);
    }
    assert!(s.ctl.is_busy() && s.ctl.awaits_flash());
    // No reply however much work is done until the board has written.
    for _ in 0..10 {
        s.ctl.work(&mut s.link, &mut out);
    }
    assert_eq!(out, "");
    let write = s.ctl.take_flash_write().expect("a write to perform");
    assert!(s.ctl.take_flash_write().is_none(), "handed over once");
    assert_eq!((write.sector(), write.record().sequence), (0, 1));
    assert_eq!(write.record().settings, *s.ctl.settings());
    s.ctl.work(&mut s.link, &mut out);
    assert_eq!(out, "", "still writing");
    s.ctl.flash_written(write.perform(&mut s.flash));
    s.ctl.work(&mut s.link, &mut out);
    assert_eq!(out, "ok\r\n");
    assert!(!s.ctl.is_busy());
    // execute_line stops where the board's write is due.
    let mut out = String::new();
    s.ctl.execute_line(&mut s.link, "save", &mut out);
    assert!(out.is_empty() && s.ctl.awaits_flash());
    let write = s.ctl.take_flash_write().unwrap();
    assert_eq!((write.sector(), write.record().sequence), (1, 2));
}

#[test]
fn a_failed_save_is_an_error_and_the_save_before_is_kept() {
    let mut s = Host::quiet();
    s.ok("save");
    s.ok("set servo1.trim_us 1490");
    let mut out = String::new();
    s.ctl.execute_line(&mut s.link, "save", &mut out);
    let _ = s.ctl.take_flash_write().unwrap();
    s.ctl.flash_written(Err(SaveError::Verify {
        offset: 4100,
        wrote: 0x00,
        read: 0x10,
    }));
    s.ctl.work(&mut s.link, &mut out);
    assert_eq!(
        out,
        "error:save-failed the flash did not keep what was written (byte 4100 of the settings \
         storage read 0x10, not 0x00); the settings saved before are kept\r\n"
    );
    assert!(saved_line(&mut s).starts_with("# saved: no"));
    assert_eq!(
        s.ctl.store().newest().map(|(i, r)| (i, r.sequence)),
        Some((0, 1))
    );
}

#[test]
fn power_up_says_why_the_defaults_or_an_older_copy_are_used() {
    // A save, then a second one damaged after it was written.
    let mut s = Host::quiet();
    s.ok("set servo2.trim_us 1480");
    s.ok("save");
    s.ok("set servo2.trim_us 1470");
    s.ok("save");
    let mut flash = s.flash.clone();
    flash.bytes[4096 + 30] ^= 0x04;
    let (mut s, banner) = power_up(&mut flash);
    assert!(
        banner.ends_with(
            "# warning: one of the two saved copies of the settings cannot be used (damaged: \
             checksum mismatch); loaded the other, save 1: check config\r\n"
        ),
        "{banner}"
    );
    assert_eq!(s.ctl.settings().servos.0[1].home_us, 1480.0);
    assert!(saved_line(&mut s).starts_with("# saved: yes"));
    // Both damaged: the defaults.
    flash.bytes[30] ^= 0x04;
    let (s, banner) = power_up(&mut flash);
    assert!(
        banner.ends_with(
            "# warning: the settings saved in flash cannot be used (damaged: checksum \
             mismatch); using the defaults\r\n"
        ),
        "{banner}"
    );
    assert_eq!(*s.ctl.settings(), Settings::default());
}
