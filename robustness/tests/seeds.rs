//! Replays the committed fuzz seed corpus (`fuzz/seeds/<target>/`) through the fuzz targets'
//! checks on stable Rust, so every seed (and every crash input added there after a fix) stays
//! a regression test in `cargo test`.

use std::fs;
use std::path::PathBuf;

/// The committed seeds of `target`, plus, if `FUZZ_CORPUS` names a directory, the inputs in
/// its `<target>/` (e.g. `fuzz/corpus`, for `fuzz/coverage.sh`).
fn seeds(target: &str) -> Vec<(String, Vec<u8>)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/seeds")
        .join(target);
    let mut files: Vec<_> = fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.expect("readable seed directory").path())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no seeds in {}", dir.display());
    if let Some(corpus) = std::env::var_os("FUZZ_CORPUS") {
        let dir = PathBuf::from(corpus).join(target);
        if let Ok(entries) = fs::read_dir(&dir) {
            files.extend(entries.map(|entry| entry.expect("readable corpus").path()));
        }
    }
    files
        .into_iter()
        .map(|p| {
            let data = fs::read(&p).expect("readable seed");
            (p.display().to_string(), data)
        })
        .collect()
}

fn replay(target: &str, run: fn(&[u8])) {
    for (name, data) in seeds(target) {
        let result = std::panic::catch_unwind(|| run(&data));
        assert!(result.is_ok(), "seed {name} broke a guarantee");
    }
}

#[test]
fn protocol_seeds() {
    replay("protocol", robustness::targets::protocol);
}

#[test]
fn command_seeds() {
    replay("command", robustness::targets::command);
}

#[test]
fn number_seeds() {
    replay("number", robustness::targets::number);
}

#[test]
fn settings_seeds() {
    replay("settings", robustness::targets::settings);
}

#[test]
fn controller_seeds() {
    replay("controller", robustness::targets::controller);
}

/// The stored-settings seeds were written by an independent encoder
/// (`fuzz/seeds/settings-records.py`: Python `struct` and `zlib.crc32`, from the format table
/// in `control::record`): they must decode, so the fuzzer starts from records that get past
/// the checksum.
#[test]
fn settings_record_seeds_decode() {
    for (name, data) in seeds("settings") {
        if data.starts_with(b"HXPS") {
            let record = control::record::decode(&data).unwrap_or_else(|e| panic!("{name}: {e:?}"));
            let s = record.settings;
            // The baud rate each was written with (format 3 has none: the default rate).
            if name.ends_with("/record-custom") {
                assert_eq!(record.baud, 921_600, "{name}");
                assert_eq!(s.pivot_mm, [10.0, -5.0, 300.0], "{name}");
            }
            if name.ends_with("/record-default") {
                assert_eq!(record.baud, 115_200, "{name}");
            }
            if name.ends_with("/record-custom") {
                // Speed ratings in hundredths of a second per 60 degrees, as written.
                assert_eq!(
                    s.servo_speed.s_per_60deg,
                    [0.1, 0.1, 0.12, 0.0, 2.55, 0.01],
                    "{name}"
                );
            }
            if name.ends_with("/record-v3-custom") || name.ends_with("/record-v4-custom") {
                // Format 3 has no baud rate (the default), format 4 has it; neither a pivot
                // nor speed ratings.
                let baud = if name.ends_with("v3-custom") {
                    115_200
                } else {
                    921_600
                };
                assert_eq!(record.baud, baud, "{name}");
                // The same settings as record-custom but the pivot (the origin) and the speed
                // ratings (none), in the formats boards in the field hold.
                let new = seeds("settings")
                    .into_iter()
                    .find(|(n, _)| n.ends_with("/record-custom"))
                    .expect("record-custom is a seed");
                let new = control::record::decode(&new.1).expect("record-custom decodes");
                let expected = control::Settings {
                    pivot_mm: [0.0; 3],
                    servo_speed: Default::default(),
                    ..new.settings
                };
                assert_eq!((record.sequence, s), (new.sequence, expected), "{name}");
            }
            if name.ends_with("record-default") {
                // The first save of a board (the encoder's sequence number 1).
                assert_eq!(record.sequence, 1);
                let d = control::Settings::default();
                assert_eq!(s.frame_hz, d.frame_hz);
                assert_eq!(
                    (s.speed_mm_s, s.speed_deg_s, s.link_timeout_s),
                    (d.speed_mm_s, d.speed_deg_s, d.link_timeout_s)
                );
                assert_eq!(s.layout, d.layout);
                for (a, b) in s.servos.0.iter().zip(d.servos.0.iter()) {
                    assert_eq!(
                        (a.home_us, a.min_us, a.max_us),
                        (b.home_us, b.min_us, b.max_us)
                    );
                    assert_eq!(a.direction, b.direction);
                    assert!((a.rate_us_per_rad - b.rate_us_per_rad).abs() < 1e-3);
                }
            }
        }
    }
}
