//! `hexapod describe`: a platform in words: its geometry, its reach from home along each axis,
//! its stiffness at home, the servos' rated speeds and how fast they let the platform go from
//! home, and with a payload the holding torques against the servos' ratings (the numbers are
//! `crate::size`'s, the speeds `kinematics_core::rates`').

use std::path::PathBuf;

use clap::Args;
use kinematics_core::pose::Axis;
use kinematics_core::rates::{joint_rates, Twist};
use kinematics_core::{Libm, Pose, Vec3, LEGS};

use crate::error::Error;
use crate::size::{
    self, limit_words, overall, payload_words, pose_words, ratings_summary, Description, Holding,
    Platform,
};

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// The platform (a build file: payload_g, payload_com_*_mm, torque_kgcm and the rest,
    /// the servos' stiffness in [sizing]); the default platform (no payload) without it
    #[arg(long)]
    settings: Option<PathBuf>,
}

impl Cmd {
    /// The description.
    pub fn run(self) -> Result<String, Error> {
        let platform = Platform::load(self.settings.as_deref())?;
        Ok(description(&size::describe(platform)))
    }
}

/// `describe`'s text.
fn description(d: &Description) -> String {
    let p = &d.platform;
    let l = &p.settings.layout;
    let g = p.solver.geometry();
    let mut out = format!("Platform: {}\n", p.source);
    out += &format!(
        "  base: servo shafts on a {:.3} mm circle, pairs {:.3} degrees either side of 0, 120 and \
         240 degrees\n  platform: joints on a {:.3} mm circle, {:.3} degrees either side of 60, \
         180 and 300 degrees\n",
        l.base_radius_mm, l.base_half_angle_deg, l.platform_radius_mm, l.platform_half_angle_deg
    );
    out += &format!(
        "  arm a = {:.3} mm, rod s = {:.3} mm; home height h0 = {:.3} mm (eq. 10)\n",
        g.arm_mm(),
        g.rod_mm(),
        g.home_height_mm()
    );
    out += &pivot_words(p.settings.pivot_mm);
    out += concat!(
        "  leg  shaft b (mm)                 joint p (mm, platform frame)  beta (deg)",
        "  alpha0 (deg)  shaft to joint at home (mm)\n"
    );
    for i in 0..6 {
        let leg = g.leg(i);
        let v = |v: Vec3| format!("({:8.3} {:8.3} {:6.3})", v.x, v.y, v.z);
        out += &format!(
            "  {}    {}  {}    {:9.3}  {:12.3}  {:10.3}\n",
            i + 1,
            v(leg.base_mm),
            v(leg.platform_mm),
            leg.beta_rad.to_degrees(),
            p.solver.alpha0_rad(i).to_degrees(),
            d.leg_lengths_mm[i]
        );
    }
    out += "Reach from home, one axis at a time, within the servo limits:\n";
    for (k, axis) in Axis::ALL.into_iter().enumerate() {
        let (minus, plus) = (&d.reach[2 * k], &d.reach[2 * k + 1]);
        let (unit, f): (&str, fn(f32) -> f32) = if axis.is_angle() {
            ("degrees", f32::to_degrees)
        } else {
            ("mm", |v| v)
        };
        out += &format!(
            "  {:<5} {:8.3} .. {:7.3} {unit}   (- {}; + {})\n",
            axis.name(),
            -f(minus.distance),
            f(plus.distance),
            limit_words(&minus.limit),
            limit_words(&plus.limit)
        );
    }
    let k = p.sizing.servo_stiffness_nmm_rad;
    match d.stiffness_diagonal {
        Some(s) => {
            out += &format!(
                "Stiffness at home, servos holding {k} N mm/rad each (K = J^T diag(k) J, \
                 diagonal):\n  x {:.2}, y {:.2}, z {:.2} N/mm; roll {:.0}, pitch {:.0}, yaw {:.0} \
                 N mm/rad\n",
                s[0], s[1], s[2], s[3], s[4], s[5]
            );
        }
        None => out += "Stiffness at home: none (a singular pose)\n",
    }
    out += &servo_speed_words(p);
    match &d.holding {
        None => {
            out += "Payload: none (payload_g = 0): no holding torques; give payload_g and \
                        payload_com_x_mm, payload_com_y_mm, payload_com_z_mm to size the servos"
        }
        Some(h) => out += &holding_words(p, h),
    }
    out
}

/// The pivot's line: where the rotations turn.
fn pivot_words(pivot_mm: [f32; 3]) -> String {
    if pivot_mm == [0.0; 3] {
        return "  pivot: the platform frame's origin (roll, pitch and yaw turn about the platform's \
                centre; pivot_x_mm, pivot_y_mm, pivot_z_mm move it)\n"
            .to_string();
    }
    let [x, y, z] = pivot_mm;
    format!(
        "  pivot: ({x:.3}, {y:.3}, {z:.3}) mm in the platform frame (roll, pitch and yaw turn \
         about it; x y z move it)\n"
    )
}

/// `describe`'s servo speed section: the ratings, and from home the fastest the platform can go
/// along each axis alone with no arm turning faster than its rating (the arms' rates at a unit
/// speed along the axis, `J` of `kinematics_core::rates`, against each rating's `pi/3 / t`).
fn servo_speed_words(p: &Platform) -> String {
    let ratings = p.settings.servo_speed.s_per_60deg;
    if !p.settings.servo_speed.rated() {
        return "Servo speed: not rated (servoN.speed_s_60deg off): moves are limited by \
                speed_mm_s and speed_deg_s alone\n"
            .to_string();
    }
    let list: Vec<String> = ratings
        .iter()
        .map(|&t| {
            if t > 0.0 {
                format!("{t:.2}")
            } else {
                "off".to_string()
            }
        })
        .collect();
    let mut out = format!(
        "Servo speed: servos 1-6 turn 60 degrees in {} s (servoN.speed_s_60deg)\n  \
         fastest from home along each axis alone, no arm faster than its rating:",
        list.join(" ")
    );
    for (k, axis) in Axis::ALL.into_iter().enumerate() {
        let mut rate = [0.0f32; 6];
        rate[k] = 1.0; // 1 mm/s or 1 rad/s
        let twist = Twist::from_pose_rate::<Libm>(&Pose::HOME, &rate);
        let words = match joint_rates::<Libm, _>(&p.solver, &Pose::HOME, &twist) {
            Ok(arms) => {
                let fastest = (0..LEGS)
                    .filter(|&i| ratings[i] > 0.0 && arms[i] != 0.0)
                    .map(|i| core::f32::consts::FRAC_PI_3 / ratings[i] / arms[i].abs())
                    .fold(f32::INFINITY, f32::min);
                match (fastest.is_finite(), axis.is_angle()) {
                    (false, _) => "no rated arm turns".to_string(),
                    (true, true) => format!("{:.1} deg/s", fastest.to_degrees()),
                    (true, false) => format!("{fastest:.1} mm/s"),
                }
            }
            Err(_) => "none (a singular pose)".to_string(),
        };
        out += &format!(" {} {words}{}", axis.name(), if k < 5 { "," } else { "\n" });
    }
    out
}

/// `describe`'s payload section.
fn holding_words(p: &Platform, h: &Holding) -> String {
    let mut out = format!("Payload {}:\n", payload_words(p.payload()));
    if let Some(sag) = &h.sag {
        out += &format!(
            "  its weight moves the platform at home by {:.3} mm down ({:.4} degrees of tilt)\n",
            -sag.translation_mm.z,
            sag.rotation_rad.norm().to_degrees()
        );
    }
    if let Some(t) = h.home_kgcm {
        let list: Vec<String> = t.iter().map(|v| format!("{v:.3}")).collect();
        out += &format!(
            "  holding torque at home, servos 1-6: {} kgf cm\n",
            list.join(" ")
        );
    }
    let (reached, total) = h.grid_reached;
    match overall(&h.per_servo) {
        Some(w) => {
            out += &format!(
                "  worst over the workspace ({reached} reachable poses of a {total}-pose grid): \
                 servo {} {:.3} kgf cm at {}\n",
                w.servo,
                w.torque_kgcm.abs(),
                pose_words(&w.pose)
            );
        }
        None => out += "  worst over the workspace: no reachable pose in the grid\n",
    }
    out += &format!("  {}", ratings_summary(p, &h.per_servo));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use control::settings::{ServoParam, ServoSel, SettingId, SettingValue};

    fn platform(rating: f32) -> Platform {
        let mut p = Platform::load(None).unwrap();
        let id = SettingId::Servo(ServoSel::All, ServoParam::SpeedS60Deg);
        p.settings = p.settings.with(id, SettingValue::Number(rating));
        p
    }

    #[test]
    fn the_fastest_speeds_from_home_are_the_ratings_over_the_arm_rates() {
        assert!(servo_speed_words(&platform(0.0)).starts_with("Servo speed: not rated"));
        let p = platform(0.2);
        let words = servo_speed_words(&p);
        assert!(
            words.starts_with("Servo speed: servos 1-6 turn 60 degrees in 0.20 0.20 0.20 0.20"),
            "{words}"
        );
        // Independently, by finite differences of the IK: heave by 1 um from home, the arm
        // that turns most sets the pace.
        let servos = &p.settings.servos;
        let at = |z: f32| {
            p.solver
                .solve::<Libm>(servos, &Pose::from_degrees(0.0, 0.0, z, 0.0, 0.0, 0.0))
                .unwrap()
                .arm_rad
        };
        let (a, b) = (at(-0.001), at(0.001));
        let per_mm = (0..6)
            .map(|i| (b[i] - a[i]).abs() / 0.002)
            .fold(0.0, f32::max);
        let fastest = core::f32::consts::FRAC_PI_3 / 0.2 / per_mm;
        let shown: f32 = words
            .split(" z ")
            .nth(1)
            .and_then(|w| w.split(" mm/s").next())
            .unwrap()
            .parse()
            .unwrap();
        assert!(
            (shown - fastest).abs() <= 0.05 + fastest * 1e-3,
            "{shown} vs {fastest}: {words}"
        );
    }
}
