//! What the controller's unit tests share: a controller with the default settings, a link
//! that talks like a program, running lines and reading notices as the board does.

use kinematics_core::{Pose, LEGS};

use super::Controller;
use crate::session::Session;
use crate::settings::Settings;

pub(super) fn quiet() -> Controller {
    Controller::new(Settings::default())
}

/// A link with echo off, as a program talks.
pub(super) fn program() -> Session {
    let mut session = Session::new();
    session.set_echo(false);
    session
}

pub(super) fn run(c: &mut Controller, link: &mut Session, line: &str) -> std::string::String {
    let mut out = std::string::String::new();
    c.execute_line(link, line, &mut out);
    out
}

pub(super) fn notices(c: &Controller, link: &mut Session) -> std::string::String {
    let mut out = std::string::String::new();
    c.write_notices(link, &mut out);
    out
}

pub(super) fn within_limits(c: &Controller, pulses: &[f32; LEGS]) -> bool {
    pulses
        .iter()
        .zip(c.settings().servos.0.iter())
        .all(|(w, s)| w.is_finite() && *w >= s.min_us && *w <= s.max_us)
}

/// Reachable, but the straight line between them is not (found by search).
pub(super) const FROM: [f32; 6] = [-28.0, 19.0, -2.5, 11.0, 2.0, -20.0];
pub(super) const TO: [f32; 6] = [30.0, -12.0, -13.5, 5.0, -13.0, 28.0];

pub(super) fn pose_command(v: [f32; 6]) -> std::string::String {
    std::format!("pose {} {} {} {} {} {}", v[0], v[1], v[2], v[3], v[4], v[5])
}

pub(super) fn pose(v: [f32; 6]) -> Pose {
    Pose::from_degrees(v[0], v[1], v[2], v[3], v[4], v[5])
}

/// Runs the work of `link`'s command to its end, as the board's main loop does.
pub(super) fn finish(c: &mut Controller, link: &mut Session, out: &mut std::string::String) {
    while link.awaits_reply() {
        c.work(link, out);
    }
}

/// Each frame's change of pose (mm for x, y, z; degrees for roll, pitch, yaw): the velocity
/// per frame, between consecutive poses.
pub(super) fn frame_velocities(poses: &[Pose]) -> std::vec::Vec<[f32; 6]> {
    poses
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0].to_array(), w[1].to_array());
            core::array::from_fn(|i| {
                let d = b[i] - a[i];
                if i < 3 {
                    d
                } else {
                    d.to_degrees()
                }
            })
        })
        .collect()
}
