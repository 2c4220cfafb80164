//! `hexapod describe`, `workspace` and `torque` as a user runs them, checked against what
//! they claim: a reach is the last pose the firmware's controller accepts (`check`), the
//! holding torque at home of the build file's payload (`payload_g`, `payload_com_*_mm`) is what
//! virtual work gives from the IK's arm angles alone and what `kinematics_core::statics` gives,
//! and what the board itself reports (`check`); ratings (`servoN.torque_kgcm`) judged as the
//! board judges them, none without a rating; the plots show the numbers the reports give, a
//! still trajectory needs exactly the holding torques; no payload, no torques.

mod support;

use control::{Controller, Session};
use kinematics_core::statics::{servo_holding_torques, Payload, N_MM_PER_KGF_CM};
use kinematics_core::{Libm, Pose, Vec3};
use support::{hexapod, scratch, text};

/// `check x y z roll pitch yaw` on the firmware's own controller with these settings: its
/// reply's lines, if accepted.
fn board_check(settings: control::Settings, pose: [f32; 6]) -> Option<String> {
    let mut ctl: Controller = Controller::new(settings);
    let mut session = Session::new();
    let mut out = String::new();
    let [x, y, z, r, p, w] = pose;
    ctl.execute_line(
        &mut session,
        &format!("check {x} {y} {z} {r} {p} {w}"),
        &mut out,
    );
    // (Echo is on: a prompt follows the reply.)
    out.lines().any(|l| l == "ok").then_some(out)
}

/// `check` on the default platform: accepted?
fn board_accepts(pose: [f32; 6]) -> bool {
    board_check(control::Settings::default(), pose).is_some()
}

/// The numbers after `key` in a line of `text` that contains it.
fn numbers_on_line(text: &str, key: &str) -> Vec<f64> {
    let line = text
        .lines()
        .find(|l| l.contains(key))
        .unwrap_or_else(|| panic!("{key} in {text}"));
    line[line.find(key).unwrap() + key.len()..]
        .split_whitespace()
        .filter_map(|w| w.parse().ok())
        .collect()
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
fn describe_names_the_pivot_and_its_reaches_turn_about_it_as_the_board_does() {
    let dir = scratch("describe-pivot");
    std::fs::write(dir.join("b.toml"), "pivot_y_mm = -10\npivot_z_mm = 60\n").unwrap();
    let out = hexapod(&dir, &["describe", "--settings", "b.toml"]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stdout.contains("  pivot: (0.000, -10.000, 60.000) mm in the platform frame"),
        "{stdout}"
    );
    // The pitch reach is about the pivot: the board, with the same pivot, accepts it and
    // refuses a little more; about the platform's centre the reach is another.
    let settings = control::Settings {
        pivot_mm: [0.0, -10.0, 60.0],
        ..control::Settings::default()
    };
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("pitch "))
        .unwrap();
    let pitch = number_after(line, "..") as f32;
    assert!(board_check(settings, [0.0, 0.0, 0.0, 0.0, pitch - 0.001, 0.0]).is_some());
    assert!(board_check(settings, [0.0, 0.0, 0.0, 0.0, pitch + 0.02, 0.0]).is_none());
    let plain = hexapod(&dir, &["describe"]);
    let (plain, _) = text(&plain);
    let line = plain
        .lines()
        .find(|l| l.trim_start().starts_with("pitch "))
        .unwrap();
    assert!(
        (number_after(line, "..") as f32 - pitch).abs() > 0.5,
        "{line}"
    );
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

    assert!(
        stdout.contains("  pivot: the platform frame's origin (roll, pitch and yaw turn about"),
        "{stdout}"
    );

    // The default platform carries nothing (payload_g 0, the board's default).
    assert!(
        stdout.contains("Payload: none (payload_g = 0): no holding torques"),
        "{stdout}"
    );
    assert!(!stdout.contains("holding torque at home"), "{stdout}");
    assert!(!stdout.contains("ratings"), "{stdout}");

    // 1 kg, 20 mm above the platform's centre, from the build file's settings.
    std::fs::write(
        dir.join("b.toml"),
        "payload_g = 1000\npayload_com_z_mm = 20\n",
    )
    .unwrap();
    let out = hexapod(&dir, &["describe", "--settings", "b.toml"]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stdout.contains("Payload 1000 g at (0, 0, 20) mm in the platform frame:"),
        "{stdout}"
    );
    // Holding it at home: by virtual work the six equal torques t satisfy m g dz = 6 t
    // dalpha, dalpha from the IK's arm angles at z = +-h.
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
    let values = numbers_on_line(&stdout, "holding torque at home, servos 1-6:");
    assert_eq!(values.len(), 6, "{stdout}");
    for &v in &values {
        assert!(
            (v - torque_kgf_cm).abs() < 0.01 * torque_kgf_cm,
            "{v} vs {torque_kgf_cm}"
        );
    }
    // And exactly (to the 3 decimals printed) the toolkit's statics for that payload.
    let arm_rad = solver.arm_angles::<Libm>(&Pose::HOME).unwrap();
    let payload = Payload::point(1.0, Vec3::new(0.0, 0.0, 20.0));
    let statics = servo_holding_torques::<Libm>(&solver, &Pose::HOME, &arm_rad, &payload).unwrap();
    for (v, t) in values.iter().zip(statics) {
        assert!(
            (v - f64::from(t / N_MM_PER_KGF_CM)).abs() <= 0.0005,
            "{v} vs {t} N mm"
        );
    }
    assert!(stdout.contains("worst over the workspace"), "{stdout}");
    // No rating set (the board's default): no verdict.
    assert!(
        stdout.contains(
            "ratings (servoN.torque_kgcm): the servos are not rated: torques without a verdict"
        ),
        "{stdout}"
    );
    assert!(
        !stdout.contains("OVER") && !stdout.contains("its rating"),
        "{stdout}"
    );
}

#[test]
fn an_off_centre_payload_loads_the_servos_as_the_board_reports_it() {
    let dir = scratch("off-centre");
    std::fs::write(
        dir.join("b.toml"),
        "payload_g = 2000\npayload_com_x_mm = 15\npayload_com_y_mm = -10\n\
         payload_com_z_mm = 30\n",
    )
    .unwrap();
    let out = hexapod(&dir, &["describe", "--settings", "b.toml"]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    let described = numbers_on_line(&stdout, "holding torque at home, servos 1-6:");
    // The firmware's controller with the same settings: `check`'s torque_kgcm line at home.
    let settings = hexapod::build_file::parse(
        "b.toml",
        &std::fs::read_to_string(dir.join("b.toml")).unwrap(),
    )
    .unwrap()
    .settings;
    let reply = board_check(settings, [0.0; 6]).expect("home is accepted");
    let reported = numbers_on_line(&reply, "# torque_kgcm:");
    assert_eq!(described, reported, "{stdout}\n{reply}");
    // An off-centre load: not all alike.
    assert!(
        described.iter().any(|&t| (t - described[0]).abs() > 0.01),
        "{described:?}"
    );
    // The toolkit's statics, independently: a 2 kg point mass there.
    let solver = settings.validate().unwrap();
    let arm_rad = solver.arm_angles::<Libm>(&Pose::HOME).unwrap();
    let payload = Payload::point(2.0, Vec3::new(15.0, -10.0, 30.0));
    let statics = servo_holding_torques::<Libm>(&solver, &Pose::HOME, &arm_rad, &payload).unwrap();
    for (v, t) in described.iter().zip(statics) {
        assert!(
            (v - f64::from(t / N_MM_PER_KGF_CM)).abs() <= 0.0005,
            "{v} vs {t} N mm"
        );
    }
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
        "payload_g = 500\nservos.torque_kgcm = 10\n",
    )
    .unwrap();
    let out = hexapod(&dir, &["torque", "--settings", "b.toml", "-o", "grid"]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stdout.contains("holding 500 g at (0, 0, 0) mm in the platform frame"),
        "{stdout}"
    );
    let worst = stdout
        .lines()
        .find(|l| l.starts_with("worst: servo"))
        .unwrap();
    assert!(worst.contains("within its rating of 10 kgf cm"), "{worst}");
    assert!(
        stdout.contains("ratings (servoN.torque_kgcm): all within: servo "),
        "{stdout}"
    );
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
    // Each servo's rating over its bar.
    let ratings: Vec<(&str, &str)> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("rating"))
        .map(|n| {
            (
                n.attribute("data-servo").unwrap(),
                n.attribute("data-kgf-cm").unwrap(),
            )
        })
        .collect();
    assert_eq!(
        ratings,
        ["1", "2", "3", "4", "5", "6"].map(|servo| (servo, "10.00"))
    );
    assert!(svg.contains("rating 10 kgf cm (servos 1-6)"), "{svg}");

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
    let out = hexapod(
        &dir,
        &["torque", "--settings", "b.toml", "--trajectory", "bad.csv"],
    );
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
fn ratings_judge_each_servo_as_the_board_does_and_none_without_a_rating() {
    let dir = scratch("ratings");
    // Micro servos but servo 2 a stronger one and servo 3 not rated.
    std::fs::write(
        dir.join("mixed.toml"),
        "payload_g = 1000\npayload_com_z_mm = 20\nservos.torque_kgcm = 1.8\n[servo2]\n\
         torque_kgcm = 10\n[servo3]\ntorque_kgcm = \"off\"\n",
    )
    .unwrap();
    let out = hexapod(&dir, &["torque", "--settings", "mixed.toml", "-o", "mixed"]);
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    let servo = |n: u8| {
        stdout
            .lines()
            .find(|l| l.starts_with(&format!("  servo {n}: ")))
            .unwrap_or_else(|| panic!("servo {n} in {stdout}"))
    };
    // The percentages are the torques over the ratings.
    for n in [1, 4, 5, 6] {
        let line = servo(n);
        let t = number_after(line, ":");
        let percent = number_after(line, "1.8 kgf cm (");
        assert!(line.contains("; OVER its rating of 1.8 kgf cm ("), "{line}");
        assert!((percent - 100.0 * t / 1.8).abs() <= 0.5, "{line}");
    }
    assert!(
        servo(2).contains("; within its rating of 10 kgf cm ("),
        "{}",
        servo(2)
    );
    assert!(servo(3).ends_with("; not rated"), "{}", servo(3));
    let summary = stdout.lines().find(|l| l.starts_with("ratings")).unwrap();
    assert!(
        summary.starts_with("ratings (servoN.torque_kgcm): OVER: servo 1 needs "),
        "{summary}"
    );
    assert!(summary.ends_with("; servo 3 not rated"), "{summary}");
    assert!(!summary.contains("servo 2"), "{summary}");
    let svg = std::fs::read_to_string(dir.join("mixed.svg")).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap();
    let over: Vec<&str> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("torque-bar"))
        .filter(|n| n.attribute("fill") == Some("#d55e00"))
        .map(|n| n.attribute("data-servo").unwrap())
        .collect();
    assert_eq!(over, ["1", "4", "5", "6"]);
    let rated: Vec<&str> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("rating"))
        .map(|n| n.attribute("data-servo").unwrap())
        .collect();
    assert_eq!(rated, ["1", "2", "4", "5", "6"]);
    assert!(
        svg.contains("rating 1.8 kgf cm (servos 1, 4, 5, 6)"),
        "{svg}"
    );
    assert!(svg.contains("rating 10 kgf cm (servo 2)"), "{svg}");

    // A trajectory through poses the board would refuse for their torques: reported, not
    // refused (the ratings are what `torque` judges).
    std::fs::write(
        dir.join("far.csv"),
        "time,x,y,z,roll,pitch,yaw\n0,0,0,0,0,0,0\n1,-20,-30,-10,0,0,0\n2,-20,-30,-10,0,0,0\n",
    )
    .unwrap();
    let out = hexapod(
        &dir,
        &[
            "torque",
            "--settings",
            "mixed.toml",
            "--trajectory",
            "far.csv",
            "-o",
            "far",
        ],
    );
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stdout.contains("; OVER its rating of 1.8 kgf cm ("),
        "{stdout}"
    );
    assert!(
        stdout.contains("\nratings (servoN.torque_kgcm): OVER: servo "),
        "{stdout}"
    );

    // A payload, no ratings (the board's default): torques, no verdict, no rating drawn.
    std::fs::write(dir.join("unrated.toml"), "payload_g = 1000\n").unwrap();
    let out = hexapod(
        &dir,
        &["torque", "--settings", "unrated.toml", "-o", "unrated"],
    );
    let (stdout, stderr) = text(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stdout.contains(
            "ratings (servoN.torque_kgcm): the servos are not rated: torques without a verdict"
        ),
        "{stdout}"
    );
    assert!(
        stdout
            .lines()
            .filter(|l| l.ends_with("; not rated"))
            .count()
            == 6,
        "{stdout}"
    );
    assert!(stdout.contains("\nworst: servo "), "{stdout}");
    let svg = std::fs::read_to_string(dir.join("unrated.svg")).unwrap();
    assert!(!svg.contains("class=\"rating\""), "{svg}");
    assert!(svg.contains("servos not rated"), "{svg}");
}

#[test]
fn no_payload_no_torques() {
    let dir = scratch("no-payload");
    // The default platform, and a build file that rates its servos but carries nothing.
    std::fs::write(dir.join("b.toml"), "servos.torque_kgcm = 10\n").unwrap();
    for (args, source) in [
        (vec!["torque"], "the default platform"),
        (vec!["torque", "--settings", "b.toml"], "b.toml"),
    ] {
        let out = hexapod(&dir, &args);
        assert!(!out.status.success());
        assert_eq!(
            text(&out).1.trim_end(),
            format!(
                "hexapod: {source}: no payload (payload_g = 0): the servos hold nothing, so \
                 every torque is 0; give payload_g (g) and payload_com_x_mm, payload_com_y_mm, \
                 payload_com_z_mm (mm, platform frame) in the build file (--settings)"
            )
        );
    }
    assert!(!dir.join("torque.svg").exists());
    let describe = text(&hexapod(&dir, &["describe", "--settings", "b.toml"])).0;
    assert!(
        describe.contains("Payload: none (payload_g = 0)"),
        "{describe}"
    );
    assert!(describe.contains("Stiffness at home"), "{describe}");
}

#[test]
fn the_old_sizing_keys_are_named_with_the_setting_to_write() {
    let dir = scratch("sizing");
    std::fs::write(
        dir.join("b.toml"),
        "frame_hz = 50\n[sizing]\npayload_kg = 2\nservo_stiffness_nmm_rad = 6000\n",
    )
    .unwrap();
    let out = hexapod(&dir, &["describe", "--settings", "b.toml"]);
    assert!(!out.status.success());
    assert_eq!(
        text(&out).1.trim_end(),
        "hexapod: b.toml:3: sizing.payload_kg: now the board's setting payload_g (g): write \
         `payload_g = 2000` above the file's first [table] instead"
    );
    std::fs::write(
        dir.join("b.toml"),
        "frame_hz = 50\n[sizing]\nservo_stiffness_nmm_rad = -1\n",
    )
    .unwrap();
    let out = hexapod(&dir, &["describe", "--settings", "b.toml"]);
    assert_eq!(
        text(&out).1.trim_end(),
        "hexapod: b.toml:3: sizing.servo_stiffness_nmm_rad: must be a number 1..1000000000 \
         N mm/rad"
    );
}
