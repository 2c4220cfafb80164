//! `hexapod draw` as a user runs it, its SVG read back: four views, six legs in each, every
//! platform joint where "The Mathematics of the Stewart Platform" puts it (computed here in
//! f64 from the documented geometry, not by the tool's code), every rod as long as the build
//! says, and an unreachable pose drawn with the failing leg marked.

mod support;

use support::{hexapod, scratch, text};

/// The default geometry (docs/geometry-and-calibration.md; the paired layout of `kinematics-core`'s
/// geometry docs): platform joints on a 60 mm circle, joint `2k+1` at `120k - 60 + 20` and
/// joint `2k+2` at `120k + 60 - 20` degrees (each rod crosses over to the next pair);
/// h0 = 118.458 mm.
const PLATFORM_RADIUS_MM: f64 = 60.0;
const HOME_HEIGHT_MM: f64 = 118.458;
const ROD_MM: f64 = 120.0;

/// q_i = T + R p_i (eq. 1, 2) with R = Rz(yaw) Ry(pitch) Rx(roll), mm and degrees.
fn joints(pose: [f64; 6]) -> Vec<[f64; 3]> {
    let [x, y, z, roll, pitch, yaw] = pose;
    let (a, b, c) = (roll.to_radians(), pitch.to_radians(), yaw.to_radians());
    let r = [
        [
            c.cos() * b.cos(),
            c.cos() * b.sin() * a.sin() - c.sin() * a.cos(),
            c.cos() * b.sin() * a.cos() + c.sin() * a.sin(),
        ],
        [
            c.sin() * b.cos(),
            c.sin() * b.sin() * a.sin() + c.cos() * a.cos(),
            c.sin() * b.sin() * a.cos() - c.cos() * a.sin(),
        ],
        [-b.sin(), b.cos() * a.sin(), b.cos() * a.cos()],
    ];
    (0..6)
        .map(|i| {
            let k = (i / 2) as f64;
            let angle = if i % 2 == 0 {
                120.0 * k - 40.0
            } else {
                120.0 * k + 40.0
            }
            .to_radians();
            let p = [
                PLATFORM_RADIUS_MM * angle.cos(),
                PLATFORM_RADIUS_MM * angle.sin(),
                0.0,
            ];
            let t = [x, y, HOME_HEIGHT_MM + z];
            core::array::from_fn(|k| t[k] + (0..3).map(|j| r[k][j] * p[j]).sum::<f64>())
        })
        .collect()
}

fn number(node: &roxmltree::Node, name: &str) -> f64 {
    node.attribute(name)
        .unwrap_or_else(|| panic!("{name} missing"))
        .parse()
        .unwrap()
}

fn mm(node: &roxmltree::Node) -> [f64; 3] {
    [
        number(node, "data-x-mm"),
        number(node, "data-y-mm"),
        number(node, "data-z-mm"),
    ]
}

#[test]
fn four_views_six_legs_joints_where_the_kinematics_put_them() {
    let dir = scratch("draw");
    let pose = [5.0, -3.0, 6.0, 4.0, -3.0, 8.0];
    let out = hexapod(&dir, &["draw", "--pose", "5 -3 6 4 -3 8", "-o", "p"]);
    assert!(out.status.success(), "{:?}", text(&out));
    assert!(dir.join("p.png").exists());
    let svg = std::fs::read_to_string(dir.join("p.svg")).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap();
    let class = |c: &str| -> Vec<roxmltree::Node> {
        doc.descendants()
            .filter(|n| n.attribute("class") == Some(c))
            .collect()
    };
    let panels = class("panel");
    let views: Vec<&str> = panels
        .iter()
        .map(|p| p.attribute("data-view").unwrap())
        .collect();
    assert_eq!(views, ["top", "front", "side", "perspective"]);
    for c in ["rod", "arm", "joint", "shaft", "leg-number"] {
        assert_eq!(class(c).len(), 4 * 6, "{c}");
    }
    assert_eq!(class("servo").len(), 4 * 6 * 6, "six faces per servo body");
    let want = joints(pose);
    let joints_drawn = class("joint");
    for (k, joint) in joints_drawn.iter().enumerate() {
        let leg: usize = joint.attribute("data-leg").unwrap().parse().unwrap();
        assert_eq!(leg, k % 6 + 1);
        let got = mm(joint);
        for d in 0..3 {
            assert!(
                (got[d] - want[leg - 1][d]).abs() < 0.01,
                "leg {leg}: {got:?} vs {:?}",
                want[leg - 1]
            );
        }
    }
    // In the top view each joint circle is at origin + px-per-mm * (x, -y).
    let top = &panels[0];
    let (scale, ox, oy) = (
        number(top, "data-px-per-mm"),
        number(top, "data-origin-x"),
        number(top, "data-origin-y"),
    );
    for (joint, q) in joints_drawn.iter().take(6).zip(&want) {
        assert!((number(joint, "cx") - (ox + scale * q[0])).abs() < 0.05);
        assert!((number(joint, "cy") - (oy - scale * q[1])).abs() < 0.05);
    }
    // Each rod runs from its arm's tip to its joint and is as long as the build's rod.
    for (arm, joint) in class("arm").iter().zip(&joints_drawn).take(6) {
        let (tip, q) = (mm(arm), mm(joint));
        let length = ((0..3).map(|d| (tip[d] - q[d]).powi(2)).sum::<f64>()).sqrt();
        assert!((length - ROD_MM).abs() < 0.01, "rod {length} mm");
    }
    let verdict = class("verdict");
    assert!(verdict[0].text().unwrap().starts_with("reachable"));
}

/// `R c` for `R = Rz(yaw) Ry(pitch) Rx(roll)` (eq. 1), degrees: each elementary rotation in
/// turn, innermost first.
fn rotate(roll: f64, pitch: f64, yaw: f64, c: [f64; 3]) -> [f64; 3] {
    let turn = |v: [f64; 3], i: usize, j: usize, angle: f64| {
        let (s, co) = angle.to_radians().sin_cos();
        let mut out = v;
        out[i] = co * v[i] - s * v[j];
        out[j] = s * v[i] + co * v[j];
        out
    };
    // Rx turns y towards z, Ry turns z towards x, Rz turns x towards y.
    let v = turn(c, 1, 2, roll);
    let v = turn(v, 2, 0, pitch);
    turn(v, 0, 1, yaw)
}

#[test]
fn with_a_pivot_the_platform_turns_about_it_and_the_pivot_is_marked() {
    let dir = scratch("draw-pivot");
    std::fs::write(dir.join("b.toml"), "pivot_x_mm = 5\npivot_z_mm = 80\n").unwrap();
    let out = hexapod(
        &dir,
        &[
            "draw",
            "--settings",
            "b.toml",
            "--pose",
            "2 -1 3 4 -3 6",
            "-o",
            "p",
        ],
    );
    assert!(out.status.success(), "{:?}", text(&out));
    let svg = std::fs::read_to_string(dir.join("p.svg")).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap();
    let class = |c: &str| -> Vec<roxmltree::Node> {
        doc.descendants()
            .filter(|n| n.attribute("class") == Some(c))
            .collect()
    };
    // q_i = (x, y, h0 + z) + c + R (p_i - c): the joints about the platform's centre, moved by
    // c - R c.
    let c = [5.0, 0.0, 80.0];
    let rc = rotate(4.0, -3.0, 6.0, c);
    let want: Vec<[f64; 3]> = joints([2.0, -1.0, 3.0, 4.0, -3.0, 6.0])
        .into_iter()
        .map(|q| core::array::from_fn(|k| q[k] + c[k] - rc[k]))
        .collect();
    for joint in class("joint") {
        let leg: usize = joint.attribute("data-leg").unwrap().parse().unwrap();
        let got = mm(&joint);
        for d in 0..3 {
            assert!(
                (got[d] - want[leg - 1][d]).abs() < 0.01,
                "leg {leg}: {got:?} vs {:?}",
                want[leg - 1]
            );
        }
    }
    // The pivot, marked in every view: where it was at home, moved by x y z.
    let rings: Vec<_> = class("pivot")
        .into_iter()
        .filter(|n| n.has_attribute("data-x-mm"))
        .collect();
    assert_eq!(rings.len(), 4);
    let at = [2.0 + 5.0, -1.0, HOME_HEIGHT_MM + 3.0 + 80.0];
    for ring in rings {
        let got = mm(&ring);
        for d in 0..3 {
            assert!((got[d] - at[d]).abs() < 0.01, "{got:?} vs {at:?}");
        }
    }
    // Without a pivot, none is marked.
    let out = hexapod(&dir, &["draw", "--pose", "2 -1 3 4 -3 6", "-o", "q"]);
    assert!(out.status.success(), "{:?}", text(&out));
    let svg = std::fs::read_to_string(dir.join("q.svg")).unwrap();
    assert!(!svg.contains("class=\"pivot\""));
}

#[test]
fn an_unreachable_pose_is_drawn_with_the_failing_leg_marked() {
    let dir = scratch("draw-unreachable");
    let out = hexapod(
        &dir,
        &["draw", "--pose", "0 0 40 0 0 0", "-o", "u", "--svg-only"],
    );
    let (stdout, _) = text(&out);
    assert!(out.status.success(), "{:?}", text(&out));
    assert!(
        stdout.contains("error:unreachable leg 1 cannot reach"),
        "{stdout}"
    );
    assert!(!dir.join("u.png").exists());
    let svg = std::fs::read_to_string(dir.join("u.svg")).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap();
    let rods: Vec<roxmltree::Node> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("rod"))
        .collect();
    for rod in &rods {
        let failing = rod.attribute("data-leg") == Some("1");
        assert_eq!(rod.attribute("stroke-dasharray").is_some(), failing);
        assert_eq!(rod.attribute("stroke") == Some("#d00000"), failing);
    }
    // The platform is drawn where it was asked to be: joints at h0 + 40 mm.
    let joint = doc
        .descendants()
        .find(|n| n.attribute("class") == Some("joint"))
        .unwrap();
    assert!((mm(&joint)[2] - (HOME_HEIGHT_MM + 40.0)).abs() < 0.01);
    let verdict = doc
        .descendants()
        .find(|n| n.attribute("class") == Some("verdict"))
        .unwrap();
    assert!(verdict.text().unwrap().contains("error:unreachable leg 1"));
}

#[test]
fn a_bad_pose_is_refused_in_the_board_s_words() {
    let dir = scratch("draw-bad");
    let out = hexapod(&dir, &["draw", "--pose", "1 2 three 0 0 0"]);
    assert!(!out.status.success());
    assert_eq!(
        text(&out).1.trim_end(),
        "hexapod: pose 1 2 three 0 0 0: error:bad-number z: 'three' is not a decimal number"
    );
}
