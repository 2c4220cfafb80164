//! The pivot (`pivot_x_mm`, `pivot_y_mm`, `pivot_z_mm`): poses turn about it, `status`' forward
//! kinematics answers in the same convention, changing it keeps the pose's numbers, `save`
//! keeps it.
//!
//! The expected pulses come from a pose about the platform frame's origin that puts every
//! platform joint where the pose about the pivot does: the translation `(x, y, z) + c - R c`,
//! computed here in f64 from the documented rotation (eq. 1 of "The Mathematics of the Stewart
//! Platform"), not by the controller.

// Servos are numbered; index loops over them read like the equations.
#![allow(clippy::needless_range_loop)]

mod common;

use common::{pose_values, six, Host};
use control::store::{RamFlash, Store};
use control::Settings;
use kinematics_core::geometry::PairedLayout;
use kinematics_core::{ik, Libm, Pose, ServoSet};

/// `R = Rz(yaw) Ry(pitch) Rx(roll)` (eq. 1), degrees in, f64.
fn rotation(roll: f64, pitch: f64, yaw: f64) -> [[f64; 3]; 3] {
    let (sr, cr) = roll.to_radians().sin_cos();
    let (sp, cp) = pitch.to_radians().sin_cos();
    let (sy, cy) = yaw.to_radians().sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

/// The pose about the platform frame's origin that places the platform as `pose` (mm, degrees)
/// about the pivot `c` does.
fn about_origin(pose: [f64; 6], c: [f64; 3]) -> Pose {
    let r = rotation(pose[3], pose[4], pose[5]);
    let t: [f64; 3] = core::array::from_fn(|k| {
        pose[k] + c[k] - (r[k][0] * c[0] + r[k][1] * c[1] + r[k][2] * c[2])
    });
    Pose::from_degrees(
        t[0] as f32,
        t[1] as f32,
        t[2] as f32,
        pose[3] as f32,
        pose[4] as f32,
        pose[5] as f32,
    )
}

fn plain_solver() -> ik::Solver {
    ik::Solver::new(PairedLayout::default().build().unwrap()).unwrap()
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn a_pose_turns_the_platform_about_the_pivot() {
    let mut s = Host::quiet();
    s.ok("set speed_mm_s off");
    s.ok("set speed_deg_s off");
    // At home nothing moves: the pivot changes where rotations turn, not home.
    s.ok("set pivot_x_mm 10");
    s.ok("set pivot_y_mm -20");
    s.ok("set pivot_z_mm 100");
    assert_eq!(s.frames(1)[0], [1500.0; 6]);
    assert!(s
        .ok("config")
        .contains(&"# pivot_z_mm: 100.000".to_string()));
    for pose in [
        [0.0, 0.0, 0.0, 0.0, 5.0, 0.0],
        [0.0, 0.0, 0.0, 4.0, 0.0, 0.0],
        [2.0, -3.0, 1.0, 2.0, -3.0, 6.0],
    ] {
        let line = format!(
            "pose {} {} {} {} {} {}",
            pose[0], pose[1], pose[2], pose[3], pose[4], pose[5]
        );
        s.ok(&line);
        let given = s.frames(1)[0];
        let expected = plain_solver()
            .solve::<Libm>(
                &ServoSet::default(),
                &about_origin(pose, [10.0, -20.0, 100.0]),
            )
            .unwrap();
        for i in 0..6 {
            assert!(
                close(given[i], expected.pulse_us[i], 2e-3),
                "{line}: servo {}: {} vs {}",
                i + 1,
                given[i],
                expected.pulse_us[i]
            );
        }
        // `status` reports the pose as commanded.
        let shown = pose_values(&s.status_field("pose"));
        for k in 0..6 {
            assert!(close(shown[k], pose[k] as f32, 1e-3), "{shown:?}");
        }
    }
    // Back at the origin, the same pose is the platform turned about its own centre: the
    // pulses change to the IK's for the pose itself, and `status` shows them.
    let about_pivot = s.frames(1)[0];
    s.ok("set pivot_x_mm 0");
    s.ok("set pivot_y_mm 0");
    s.ok("set pivot_z_mm 0");
    let about_centre = s.frames(1)[0];
    let expected = plain_solver()
        .solve::<Libm>(
            &ServoSet::default(),
            &Pose::from_degrees(2.0, -3.0, 1.0, 2.0, -3.0, 6.0),
        )
        .unwrap();
    for i in 0..6 {
        assert!(close(about_centre[i], expected.pulse_us[i], 1e-3));
        assert!(
            (about_centre[i] - about_pivot[i]).abs() > 1.0,
            "servo {}",
            i + 1
        );
    }
    let shown = six(&s.status_field("pulse_us"));
    for i in 0..6 {
        assert!(close(shown[i], about_centre[i], 0.006));
    }
}

#[test]
fn status_finds_the_pose_of_pulses_set_by_servo_about_the_pivot() {
    let mut s = Host::quiet();
    s.ok("set speed_mm_s off");
    s.ok("set speed_deg_s off");
    s.ok("set pivot_z_mm 80");
    s.ok("pose 1 2 3 3 -4 5");
    let held = s.frames(1)[0];
    // Driving servo 1 to the pulse it holds moves nothing; its pose is found by the forward
    // kinematics, which must answer in the convention of the pose commanded.
    s.ok(&format!("servo 1 {:.2}", held[0]));
    assert!(s.status_field("state").starts_with("direct"));
    let found = pose_values(&s.status_field("pulse_pose"));
    let commanded = [1.0, 2.0, 3.0, 3.0, -4.0, 5.0];
    for k in 0..6 {
        assert!(
            close(found[k], commanded[k], 0.01),
            "{found:?} vs {commanded:?}"
        );
    }
    // Changing the pivot keeps the pulses set by `servo` (nothing moves) and finds their pose
    // about the new pivot: the same placement, other numbers.
    s.ok("set pivot_z_mm 0");
    assert_eq!(s.frames(1)[0][1..], held[1..]);
    let again = pose_values(&s.status_field("pulse_pose"));
    let expected = about_origin([1.0, 2.0, 3.0, 3.0, -4.0, 5.0], [0.0, 0.0, 80.0]);
    let expected = [expected.x_mm, expected.y_mm, expected.z_mm, 3.0, -4.0, 5.0];
    for k in 0..6 {
        assert!(
            close(again[k], expected[k], 0.01),
            "{again:?} vs {expected:?}"
        );
    }
}

#[test]
fn a_pivot_change_keeps_the_pose_and_is_refused_while_moving_or_out_of_reach() {
    let mut s = Host::quiet();
    s.ok("set speed_deg_s 5");
    s.ok("pose 0 0 0 0 6 0");
    assert!(s.ctl.is_moving());
    assert_eq!(s.code("set pivot_z_mm 50"), "busy");
    s.run_until_idle();
    // Away from home, the same pose about another pivot: the platform moves there.
    let before = s.frames(1)[0];
    s.ok("set pivot_z_mm 50");
    let after = s.frames(1)[0];
    assert!(before != after);
    assert_eq!(
        pose_values(&s.status_field("pose")),
        [0.0, 0.0, 0.0, 0.0, 6.0, 0.0]
    );
    // A pivot that would take the held pose out of reach is refused, nothing changes.
    assert_eq!(s.code("set pivot_z_mm 1000"), "pose-conflict");
    assert_eq!(s.ctl.settings().pivot_mm, [0.0, 0.0, 50.0]);
    assert_eq!(s.frames(1)[0], after);
    assert_eq!(s.code("set pivot_z_mm 1000.001"), "out-of-range");
    // At home any pivot in range is taken (home does not depend on it).
    s.ok("home");
    s.run_until_idle();
    s.ok("set pivot_z_mm 1000");
    s.ok("set pivot_x_mm -1000");
    assert_eq!(s.frames(1)[0], [1500.0; 6]);
    // `defaults` puts it back at the origin.
    s.ok("defaults");
    assert_eq!(s.ctl.settings().pivot_mm, [0.0; 3]);
}

#[test]
fn save_keeps_the_pivot_for_the_next_power_up() {
    let mut flash = RamFlash::new();
    let mut s = Host::quiet();
    s.ctl = control::Controller::power_up(Store::load(&mut flash));
    s.ok("set pivot_x_mm 12.5");
    s.ok("set pivot_z_mm 250");
    s.ok("save");
    let mut flash = s.flash.clone();
    let ctl = control::Controller::<Libm>::power_up(Store::load(&mut flash));
    let expected = Settings {
        pivot_mm: [12.5, 0.0, 250.0],
        ..Settings::default()
    };
    assert_eq!(*ctl.settings(), expected);
}
