//! `hexapod describe`, `workspace` and `torque` as a user runs them, checked against what
//! they claim: a reach is the last pose the firmware's controller accepts (`check`), the
//! holding torque at home is what virtual work gives from the IK's arm angles alone, the plots
//! show the numbers the reports give, a still trajectory needs exactly the holding torques.

mod support;

use control::{Controller, Session};
use kinematics_core::{Libm, Pose};
use support::{hexapod, scratch, text};

/// `check x y z roll pitch yaw` on the firmware's own controller: accepted?
fn board_accepts(pose: [f32; 6]) -> bool {
    let mut ctl: Controller = Controller::new(control::Settings::default());
    let mut session = Session::new();
    let mut out = String::new();
    let [x, y, z, r, p, w] = pose;
    ctl.execute_line(
        &mut session,
        &format!("check {x} {y} {z} {r} {p} {w}"),
        &mut out,
    );
    // (Echo is on: a prompt follows the reply.)
    out.lines().any(|l| l == "ok")
}

/// A number following `key` in `text`.
fn number_after(text: &str, key: &str) -> f64 {
    let rest = &text[text.find(key).unwrap_or_else(|| panic!("{key} in {text}")) + key.len()..];
    let token: String = rest
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.' || *c == '-')
        .collect();
    token
        .parse()
        .unwrap_or_else(|_| panic!("a number after {key}: {rest}"))
}

#[test]
fn describe_gives_the_geometry_reaches_the_board_agrees_with_and_torques_virtual_work_gives() {
    let dir = scratch("describe");
    let out = hexapod(&dir, &["describe"]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("home height h0 = 118.458 mm"), "{stdout}");
    // The +x reach (found to 0.01 mm, printed to 0.001): the board accepts it and refuses a
    // little more.
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("x "))
        .unwrap();
    let plus_x = number_after(line, "..") as f32;
    assert!(
        board_accepts([plus_x - 0.001, 0.0, 0.0, 0.0, 0.0, 0.0]),
        "{line}"
    );
    assert!(
        !board_accepts([plus_x + 0.02, 0.0, 0.0, 0.0, 0.0, 0.0]),
        "{line}"
    );
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("roll "))
        .unwrap();
    let roll = number_after(line, "..") as f32;
    assert!(board_accepts([0.0, 0.0, 0.0, roll - 0.001, 0.0, 0.0]));
    assert!(!board_accepts([0.0, 0.0, 0.0, roll + 0.02, 0.0, 0.0]));

    // Holding 1 kg at home (the default sizing, centred): by virtual work the six equal
    // torques t satisfy m g dz = 6 t dalpha, dalpha from the IK's arm angles at z = +-h.
    let solver = control::Settings::default().validate().unwrap();
    let h = 0.01f32;
    let up = solver
        .arm_angles::<Libm>(&Pose::from_degrees(0.0, 0.0, h, 0.0, 0.0, 0.0))
        .unwrap();
    let down = solver
        .arm_angles::<Libm>(&Pose::from_degrees(0.0, 0.0, -h, 0.0, 0.0, 0.0))
        .unwrap();
    let dalpha: f64 = up
        .iter()
        .zip(&down)
        .map(|(a, b)| f64::from(a - b))
        .sum::<f64>()
        / 6.0;
    let weight_n = 1.0 * 9.806_65;
    let torque_kgf_cm = weight_n * f64::from(2.0 * h) / (6.0 * dalpha) / 98.066_5;
    let line = stdout
        .lines()
        .find(|l| l.contains("holding torque at home"))
        .unwrap();
    let values: Vec<f64> = line
        .split(':')
        .nth(1)
        .unwrap()
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect();
    assert_eq!(values.len(), 6, "{line}");
    for v in values {
        assert!(
            (v - torque_kgf_cm).abs() < 0.01 * torque_kgf_cm,
            "{v} vs {torque_kgf_cm}"
        );
    }
    assert!(stdout.contains("worst over the workspace"), "{stdout}");
}

#[test]
fn the_workspace_plot_shows_the_sections_travel_and_the_reaches_describe_reports() {
    let dir = scratch("workspace");
    let out = hexapod(&dir, &["workspace", "-o", "ws"]);
    assert!(out.status.success(), "{:?}", text(&out));
    assert!(std::fs::metadata(dir.join("ws.png")).unwrap().len() > 10_000);
    let svg = std::fs::read_to_string(dir.join("ws.svg")).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap();
    let class = |c: &str| -> Vec<roxmltree::Node> {
        doc.descendants()
            .filter(|n| n.attribute("class") == Some(c))
            .collect()
    };
    assert_eq!(class("section").len(), 5, "five heights, each reachable");
    assert_eq!(class("travel").len(), 21 * 21);
    for label in ["x (mm)", "y (mm)", "roll (degrees)", "pitch (degrees)"] {
        assert!(svg.contains(&format!(">{label}</text>")), "{label}");
    }
    // The travel at level is the z reach both ways (describe's z line).
    let level = class("travel")
        .into_iter()
        .find(|n| {
            n.attribute("data-roll-deg") == Some("0.00")
                && n.attribute("data-pitch-deg") == Some("0.00")
        })
        .unwrap();
    let travel: f64 = level.attribute("data-travel-mm").unwrap().parse().unwrap();
    let describe = text(&hexapod(&dir, &["describe"])).0;
    let z = describe
        .lines()
        .find(|l| l.trim_start().starts_with("z "))
        .unwrap();
    let lo: f64 = z.split_whitespace().nth(1).unwrap().parse().unwrap();
    let hi = number_after(z, "..");
    // Scanned in 0.5 mm steps: up to a step short at either end.
    assert!(
        travel <= hi - lo && travel >= hi - lo - 1.0,
        "travel {travel} vs {lo}..{hi}"
    );
    let bars = class("reach");
    assert_eq!(bars.len(), 6);
    let x = &bars[0];
    assert_eq!(x.attribute("data-axis"), Some("x"));
    let x_line = describe
        .lines()
        .find(|l| l.trim_start().starts_with("x "))
        .unwrap();
    assert!(
        (x.attribute("data-max").unwrap().parse::<f64>().unwrap() - number_after(x_line, ".."))
            .abs()
            < 1e-3
    );
}

#[test]
fn torque_over_the_grid_and_along_a_trajectory() {
    let dir = scratch("torque");
    std::fs::write(
        dir.join("b.toml"),
        "[sizing]\npayload_kg = 0.5\nservo_torque_kgcm = 10\n",
    )
    .unwrap();
    let out = hexapod(&dir, &["torque", "--settings", "b.toml", "-o", "grid"]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(stdout.contains("holding 0.5 kg"), "{stdout}");
    let worst = stdout
        .lines()
        .find(|l| l.starts_with("worst: servo"))
        .unwrap();
    assert!(worst.contains("within the rating of 10 kgf cm"), "{worst}");
    let svg = std::fs::read_to_string(dir.join("grid.svg")).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap();
    let bars: Vec<f64> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("torque-bar"))
        .map(|n| n.attribute("data-kgf-cm").unwrap().parse().unwrap())
        .collect();
    assert_eq!(bars.len(), 6);
    let largest = bars.iter().copied().fold(0.0, f64::max);
    assert!(
        (largest - number_after(worst, ",")).abs() < 1e-3,
        "{bars:?} {worst}"
    );

    // Still at home for a second: no inertia, the holding torques exactly.
    let mut csv = String::from("time,x,y,z,roll,pitch,yaw\n");
    for i in 0..=10 {
        csv += &format!("{},0,0,0,0,0,0\n", f64::from(i) / 10.0);
    }
    std::fs::write(dir.join("still.csv"), csv).unwrap();
    let out = hexapod(
        &dir,
        &[
            "torque",
            "--settings",
            "b.toml",
            "--trajectory",
            "still.csv",
            "-o",
            "still",
        ],
    );
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    let describe = text(&hexapod(&dir, &["describe", "--settings", "b.toml"])).0;
    let home = describe
        .lines()
        .find(|l| l.contains("holding torque at home"))
        .unwrap();
    let at_home: f64 = home
        .split_whitespace()
        .rev()
        .nth(2)
        .unwrap()
        .parse()
        .unwrap();
    let worst = number_after(&stdout, "worst servo ");
    assert!((1.0..=6.0).contains(&worst));
    let torque = number_after(&stdout[stdout.find("worst servo").unwrap()..], ",");
    assert!(
        (torque - at_home).abs() < 1e-3,
        "{torque} vs {at_home}: {stdout}"
    );

    // A row the platform cannot take is named.
    std::fs::write(
        dir.join("bad.csv"),
        "time,x,y,z,roll,pitch,yaw\n0,0,0,0,0,0,0\n1,0,0,60,0,0,0\n",
    )
    .unwrap();
    let out = hexapod(&dir, &["torque", "--trajectory", "bad.csv"]);
    assert!(!out.status.success());
    assert!(
        text(&out)
            .1
            .starts_with("hexapod: bad.csv:3: the board would refuse this pose: error:unreachable"),
        "{:?}",
        text(&out)
    );
}

#[test]
fn bad_sizing_keys_are_named() {
    let dir = scratch("sizing");
    std::fs::write(
        dir.join("b.toml"),
        "frame_hz = 50\n[sizing]\npayload_kg = -2\n",
    )
    .unwrap();
    let out = hexapod(&dir, &["describe", "--settings", "b.toml"]);
    assert!(!out.status.success());
    assert_eq!(
        text(&out).1.trim_end(),
        "hexapod: b.toml:3: sizing.payload_kg: must be a number 0..1000 kg"
    );
}
