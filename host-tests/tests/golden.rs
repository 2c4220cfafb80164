//! The core against the golden table in `host-tests/golden.md` (written by
//! `host-tests/scripts/golden.py` in f64, independently of the core and of the Rust
//! reference). The table is parsed here, so the documented numbers and the test cannot drift.

use std::collections::BTreeMap;

use host_tests::reference::{Expectation, RefGeometry, RefPose};
use kinematics_core::{ik, Geometry, Libm, Pose, ServoSet, LEGS};

/// The table's rounding: angles to 3 decimals, pulses to 2, so a correct value may differ from
/// the printed one by half the last digit.
const ANGLE_ROUNDING_DEG: f64 = 0.0005;
const PULSE_ROUNDING_US: f64 = 0.005;
/// The core's own error on top (see `tests/agreement.rs`): f32 arithmetic.
const CORE_ANGLE_DEG: f64 = 1e-4;
const CORE_PULSE_US: f64 = 0.01;
/// The Rust reference reads the core's f32 build coordinates; the script uses exact ones.
const F32_GEOMETRY_DEG: f64 = 2e-5;
const F32_GEOMETRY_US: f64 = 2e-4;

/// The tables of `golden.md`: section heading -> row label -> cells.
type Tables = BTreeMap<String, BTreeMap<String, Vec<f64>>>;

fn parse(markdown: &str) -> Tables {
    let mut tables = Tables::new();
    let mut section = String::new();
    for line in markdown.lines() {
        if let Some(heading) = line.strip_prefix("## ") {
            section = heading.trim().to_string();
            continue;
        }
        let Some(row) = line.trim().strip_prefix('|') else {
            continue;
        };
        let cells: Vec<&str> = row
            .trim_end_matches('|')
            .split('|')
            .map(str::trim)
            .collect();
        let Some((label, values)) = cells.split_first() else {
            continue;
        };
        // Header and alignment rows have no numbers.
        let Ok(values) = values
            .iter()
            .map(|v| v.parse::<f64>())
            .collect::<Result<Vec<_>, _>>()
        else {
            continue;
        };
        let previous = tables
            .entry(section.clone())
            .or_default()
            .insert(label.to_string(), values);
        assert!(previous.is_none(), "duplicate row {label:?} in {section:?}");
    }
    tables
}

fn golden() -> Tables {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/golden.md");
    let text = std::fs::read_to_string(path).expect("host-tests/golden.md exists");
    parse(&text)
}

fn table<'a>(tables: &'a Tables, prefix: &str) -> &'a BTreeMap<String, Vec<f64>> {
    tables
        .iter()
        .find(|(name, _)| name.starts_with(prefix))
        .map(|(_, t)| t)
        .unwrap_or_else(|| panic!("golden.md has no section {prefix:?}"))
}

#[test]
fn golden_table_is_complete() {
    let tables = golden();
    let poses = table(&tables, "Poses");
    assert!((6..=12).contains(&poses.len()), "{} poses", poses.len());
    for (section, width) in [("Poses", 6), ("Arm angles", LEGS), ("Pulse widths", LEGS)] {
        let t = table(&tables, section);
        assert_eq!(
            t.keys().collect::<Vec<_>>(),
            poses.keys().collect::<Vec<_>>(),
            "{section}"
        );
        assert!(t.values().all(|row| row.len() == width), "{section}");
    }
    for name in [
        "home",
        "heave up",
        "heave down",
        "surge",
        "sway",
        "roll",
        "pitch",
        "yaw",
    ] {
        assert!(poses.contains_key(name), "missing pose {name:?}");
    }
}

#[test]
fn core_matches_the_golden_table() {
    let tables = golden();
    let poses = table(&tables, "Poses");
    let angles = table(&tables, "Arm angles");
    let pulses = table(&tables, "Pulse widths");
    let constants = table(&tables, "Derived constants");
    let g = Geometry::default();
    let solver = ik::Solver::new(g.clone()).expect("a valid geometry");
    let servos = ServoSet::default();

    let h0 = constants["h0 (mm)"][0];
    let alpha0 = constants["alpha0 (deg)"][0];
    assert!((f64::from(g.home_height_mm()) - h0).abs() <= 0.0005 + 1e-4);
    for i in 0..LEGS {
        let a0 = f64::from(solver.alpha0_rad(i)).to_degrees();
        assert!(
            (a0 - alpha0).abs() <= ANGLE_ROUNDING_DEG + CORE_ANGLE_DEG,
            "leg {}: {a0}",
            i + 1
        );
    }

    let mut worst_deg: f64 = 0.0;
    let mut worst_us: f64 = 0.0;
    for (name, v) in poses {
        let pose = Pose::from_degrees(
            v[0] as f32,
            v[1] as f32,
            v[2] as f32,
            v[3] as f32,
            v[4] as f32,
            v[5] as f32,
        );
        let sol = solver
            .solve::<Libm>(&servos, &pose)
            .unwrap_or_else(|e| panic!("{name}: the core refuses a golden pose: {e}"));
        for i in 0..LEGS {
            let a = f64::from(sol.arm_rad[i]).to_degrees();
            let w = f64::from(sol.pulse_us[i]);
            let (da, dw) = ((a - angles[name][i]).abs(), (w - pulses[name][i]).abs());
            worst_deg = worst_deg.max(da);
            worst_us = worst_us.max(dw);
            assert!(
                da <= ANGLE_ROUNDING_DEG + CORE_ANGLE_DEG,
                "{name}, servo {}: alpha {a:.6} deg, table {}",
                i + 1,
                angles[name][i]
            );
            assert!(
                dw <= PULSE_ROUNDING_US + CORE_PULSE_US,
                "{name}, servo {}: W {w:.4} us, table {}",
                i + 1,
                pulses[name][i]
            );
        }
    }
    eprintln!(
        "golden table: {} poses, core within {worst_deg:.1e} deg and {worst_us:.1e} us of the printed values",
        poses.len()
    );
}

#[test]
fn rust_reference_matches_the_golden_table() {
    // Two independent f64 implementations (the Python script's eq. 9 and the Rust numeric
    // reference) agree to the table's rounding.
    let tables = golden();
    let poses = table(&tables, "Poses");
    let angles = table(&tables, "Arm angles");
    let pulses = table(&tables, "Pulse widths");
    let reference = RefGeometry::from_core(&Geometry::default());
    let servos = ServoSet::default();
    for (name, v) in poses {
        let pose = RefPose::from_degrees(v[0], v[1], v[2], v[3], v[4], v[5]);
        let e = Expectation::new(&reference, &servos, &pose);
        let alpha = e.alphas().unwrap_or_else(|| panic!("{name}: unreachable"));
        for i in 0..LEGS {
            let da = (alpha[i].to_degrees() - angles[name][i]).abs();
            let dw = (e.pulse_us[i] - pulses[name][i]).abs();
            assert!(
                da <= ANGLE_ROUNDING_DEG + F32_GEOMETRY_DEG,
                "{name} servo {}: {da}",
                i + 1
            );
            assert!(
                dw <= PULSE_ROUNDING_US + F32_GEOMETRY_US,
                "{name} servo {}: {dw}",
                i + 1
            );
        }
    }
}

#[test]
fn parser_reads_rows_and_skips_headers() {
    let t = parse(
        "# T\n\n## Poses\n\n| pose | x |\n| --- | ---: |\n| home | 0 |\n| up | -1.5 |\n\n## Other\n| a | 2 |\n",
    );
    assert_eq!(t["Poses"]["home"], vec![0.0]);
    assert_eq!(t["Poses"]["up"], vec![-1.5]);
    assert_eq!(t["Other"]["a"], vec![2.0]);
    assert_eq!(t["Poses"].len(), 2);
}
