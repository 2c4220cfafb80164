//! Poses for the IK benchmark (`./dev bench`, `emulator/src/bench.js`), with what the chip's
//! answers are judged against.
//!
//! `cargo run -p host-tests --example bench_poses -- COUNT SEED` prints one JSON object per line
//! for `COUNT` random poses, all reachable by the default build within the default servo
//! limits: the pose as f32 bit patterns (mm, rad, what the chip is sent), the independent f64
//! reference's pulses (`ref_us`, see `host_tests::reference`) and the host's own f32 IK with
//! `libm` (`host_us`, what the ROM-backed path on the chip must agree with).

use host_tests::fixtures::Rng;
use host_tests::reference::{Expectation, RefGeometry, RefPose};
use kinematics_core::{ik, Geometry, Libm, ServoSet};

/// Pose box sampled, mm and degrees (x, y, z, roll, pitch, yaw).
const RANGE: [f64; 6] = [25.0, 25.0, 15.0, 15.0, 15.0, 20.0];
/// Poses this close to the workspace boundary (mm) or a servo limit (us) are skipped: there the
/// f32 and f64 answers may legitimately disagree about reachability.
const MARGIN_MM: f64 = 0.01;
const MARGIN_US: f64 = 0.1;

fn main() {
    let mut args = std::env::args().skip(1);
    let count: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(200);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    let geometry = Geometry::default();
    let solver = ik::Solver::new(geometry.clone()).expect("a valid geometry");
    let servos = ServoSet::default();
    let reference = RefGeometry::from_core(&geometry);
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
        found += 1;
        let bits: Vec<String> = pose
            .to_array()
            .iter()
            .map(|v| format!("\"{:08x}\"", v.to_bits()))
            .collect();
        let values: Vec<String> = pose.to_array().iter().map(|v| format!("{v:e}")).collect();
        let refs: Vec<String> = expected
            .pulse_us
            .iter()
            .map(|v| format!("{v:.9}"))
            .collect();
        let hosts: Vec<String> = host.pulse_us.iter().map(|v| format!("{v:e}")).collect();
        println!(
            "{{\"pose_bits\":[{}],\"pose\":[{}],\"ref_us\":[{}],\"host_us\":[{}]}}",
            bits.join(","),
            values.join(","),
            refs.join(","),
            hosts.join(",")
        );
    }
}
