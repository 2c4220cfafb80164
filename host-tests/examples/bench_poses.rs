//! Poses for the IK benchmark (`./dev bench`, `emulator/src/bench.js`), with what the chip's
//! answers are judged against.
//!
//! `cargo run -p host-tests --example bench_poses -- COUNT SEED` prints one JSON object per line
//! for `COUNT` random poses, all reachable by the default build within the default servo
//! limits: the pose as f32 bit patterns (mm, rad, what the chip is sent), the independent f64
//! reference's pulses (`ref_us`, see `host_tests::reference`) and the host's own f32 IK with
//! `libm` (`host_us`, and as f32 bit patterns `host_us_bits`: the firmware's fixed-point path
//! computes the very same bits on the chip).
//!
//! For the rest of the kinematics, also: the reference pulses as f32 bit patterns
//! (`ref_us_bits`, what the forward kinematics starts from), a reachable pose a frame's step
//! away (`start_bits`: up to 0.5 mm and 0.25 degree per axis, the previous frame's pose of a
//! fast move), and from `host_tests::platform` the f64 Jacobian by central finite differences
//! (`ref_j`, row by row) and the f64 holding torques for the benchmark's payload (`ref_torque`,
//! N mm: 1 kg, 30 mm above the platform's centre, by `J^T tau = w` in f64).

use host_tests::fixtures::Rng;
use host_tests::platform::{apply, fd_jacobian, solve6, transpose6, RefArms};
use host_tests::reference::{Expectation, RefGeometry, RefPose};
use kinematics_core::{ik, Geometry, Libm, Pose, ServoSet};

/// Pose box sampled, mm and degrees (x, y, z, roll, pitch, yaw).
const RANGE: [f64; 6] = [25.0, 25.0, 15.0, 15.0, 15.0, 20.0];
/// Poses this close to the workspace boundary (mm) or a servo limit (us) are skipped: there the
/// f32 and f64 answers may legitimately disagree about reachability.
const MARGIN_MM: f64 = 0.01;
const MARGIN_US: f64 = 0.1;
/// The previous frame's pose is up to this far away, mm and degrees per axis.
const FRAME_STEP: [f64; 6] = [0.5, 0.5, 0.5, 0.25, 0.25, 0.25];
/// The torque benchmark's payload: kg, and its centre of mass in the platform frame, mm.
const PAYLOAD_KG: f64 = 1.0;
const PAYLOAD_COM_MM: [f64; 3] = [0.0, 0.0, 30.0];

/// Hex f32 bit patterns as JSON strings.
fn bits(values: &[f32]) -> String {
    let words: Vec<String> = values
        .iter()
        .map(|v| format!("\"{:08x}\"", v.to_bits()))
        .collect();
    words.join(",")
}

/// f64 values as JSON numbers.
fn numbers(values: &[f64]) -> String {
    let words: Vec<String> = values.iter().map(|v| format!("{v:e}")).collect();
    words.join(",")
}

fn main() {
    let mut args = std::env::args().skip(1);
    let count: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(200);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    let geometry = Geometry::default();
    let solver = ik::Solver::new(geometry.clone()).expect("a valid geometry");
    let servos = ServoSet::default();
    let reference = RefGeometry::from_core(&geometry);
    let arms = RefArms::from_solver(&solver);
    let mut rng = Rng::new(seed);
    let mut found = 0;
    while found < count {
        let pose = rng.pose(&RANGE);
        let expected = Expectation::new(&reference, &servos, &RefPose::from_core(&pose));
        let clear = (0..6).all(|i| {
            expected.leg_margin_mm(i) > MARGIN_MM && expected.limit_margin_us[i] > MARGIN_US
        });
        let Ok(host) = solver.solve::<Libm>(&servos, &pose) else {
            continue;
        };
        if !clear {
            continue;
        }
        // The previous frame's pose: a frame's step away, and one the platform can be at.
        let start = loop {
            let d = rng.pose(&FRAME_STEP).to_array();
            let p = pose.to_array();
            let start = Pose::from_array(core::array::from_fn(|k| p[k] + d[k]));
            if solver.solve::<Libm>(&servos, &start).is_ok() {
                break start;
            }
        };
        let exact = RefPose::from_core(&pose);
        let j = fd_jacobian(|p| arms.arm_angles(p), &exact, 1e-3, 1e-5).expect("reachable");
        // The payload's weight about the centre (the platform frame's origin here), in f64.
        let transform = arms.anchors.transform(&exact);
        let com = apply(&transform, PAYLOAD_COM_MM);
        let centre = arms.anchors.centre_position(&exact);
        let lever: Vec<f64> = (0..3).map(|k| com[k] - centre[k]).collect();
        let lift_n = PAYLOAD_KG * 9.806_65;
        // Holding means applying +m g up at the centre of mass: moment lever x (0, 0, m g).
        let wrench = [0.0, 0.0, lift_n, lever[1] * lift_n, -lever[0] * lift_n, 0.0];
        let torque = solve6(&transpose6(&j), &wrench).expect("not singular");
        found += 1;
        let values: Vec<String> = pose.to_array().iter().map(|v| format!("{v:e}")).collect();
        let refs: Vec<String> = expected
            .pulse_us
            .iter()
            .map(|v| format!("{v:.9}"))
            .collect();
        let hosts: Vec<String> = host.pulse_us.iter().map(|v| format!("{v:e}")).collect();
        let ref_bits: Vec<f32> = expected.pulse_us.iter().map(|v| *v as f32).collect();
        println!(
            "{{\"pose_bits\":[{}],\"pose\":[{}],\"ref_us\":[{}],\"host_us\":[{}],\
             \"host_us_bits\":[{}],\
             \"ref_us_bits\":[{}],\"start_bits\":[{}],\"ref_j\":[{}],\"ref_torque\":[{}]}}",
            bits(&pose.to_array()),
            values.join(","),
            refs.join(","),
            hosts.join(","),
            bits(&host.pulse_us),
            bits(&ref_bits),
            bits(&start.to_array()),
            numbers(j.as_flattened()),
            numbers(&torque),
        );
    }
}
