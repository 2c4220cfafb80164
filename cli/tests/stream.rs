//! `hexapod stream` and `hexapod demo` as a user runs them, against the firmware's own
//! controller on a pseudo-terminal (`support::SimBoard`): what the board received and where it
//! ended, the summary, and refusals (by the host's check before anything is sent, and by the
//! board during a text stream).

mod support;

use control::settings::Settings;
use kinematics_core::{Libm, Pose};
use support::{hexapod, pass_through_board, scratch, text, SimBoard};

/// A trajectory: from home up to `end` over 1 s at 50 rows/s, then holding it for 0.2 s.
fn ramp_to(end: [f64; 6]) -> String {
    let mut csv = String::from("time,x,y,z,roll,pitch,yaw\n");
    for i in 0..=60 {
        let f = (f64::from(i) / 50.0).min(1.0);
        let v: Vec<String> = end.iter().map(|e| format!("{:.4}", e * f)).collect();
        csv += &format!("{:.2},{}\n", f64::from(i) / 50.0, v.join(","));
    }
    csv
}

/// The pulses the host IK gives for a pose (mm, degrees).
fn host_pulses(pose: [f32; 6]) -> [f32; 6] {
    let settings = Settings::default();
    let [x, y, z, roll, pitch, yaw] = pose;
    settings
        .validate()
        .unwrap()
        .solve::<Libm>(
            &settings.servos,
            &Pose::from_degrees(x, y, z, roll, pitch, yaw),
        )
        .unwrap()
        .pulse_us
}

#[test]
fn a_binary_stream_arrives_whole_and_leaves_the_platform_at_the_last_row() {
    let dir = scratch("binary");
    std::fs::write(dir.join("t.csv"), ramp_to([4.0, -3.0, 5.0, 2.0, -1.5, 6.0])).unwrap();
    let board = pass_through_board(&dir);
    let stream = hexapod(
        &dir,
        &[
            "stream",
            "t.csv",
            "--port",
            &board.path,
            "--status-every-s",
            "0.2",
        ],
    );
    let (out, err) = text(&stream);
    assert!(stream.status.success(), "{out}{err}");
    assert!(out.contains("61 rows sent"), "{out}");
    assert!(out.contains("the board counted frames=61 "), "{out}");
    assert!(out.contains("damaged=0 clamped=0 refused=0"), "{out}");
    assert!(out.contains("errors: 0"), "{out}");
    let samples: usize = out
        .split("round trip (status lines")
        .nth(1)
        .and_then(|s| s.split("): ").nth(1))
        .and_then(|s| s.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    assert!(
        samples >= 3,
        "status round trips measured during 1.2 s: {out}"
    );
    let finished = board.finish();
    // 61 frames of 16 bytes, each A5 5A ... 0D 0A.
    let frames = finished
        .received
        .windows(2)
        .filter(|w| w == &[0xA5, 0x5A])
        .count();
    assert_eq!(frames, 61);
    // The last row, as the board decodes its counts, solved by the host's IK: within the
    // rounding of one count (25 mm / 32768, 15 degrees / 32768).
    let want = host_pulses([4.0, -3.0, 5.0, 2.0, -1.5, 6.0]);
    for (got, want) in finished.pulses_us.iter().zip(want) {
        assert!(
            (got - want).abs() < 0.05,
            "{:?} vs {want:?}",
            finished.pulses_us
        );
    }
}

#[test]
fn a_text_stream_answers_every_line_with_a_round_trip_each() {
    let dir = scratch("text");
    std::fs::write(dir.join("t.csv"), ramp_to([0.0, 5.0, -4.0, 0.0, 3.0, 0.0])).unwrap();
    let board = SimBoard::start();
    let stream = hexapod(&dir, &["stream", "t.csv", "--text", "--port", &board.path]);
    let (out, err) = text(&stream);
    assert!(stream.status.success(), "{out}{err}");
    assert!(out.contains("lines sent: 61, ok: 61, refused: 0"), "{out}");
    assert!(
        out.contains("(each pose line to its reply): 61 samples"),
        "{out}"
    );
    let finished = board.finish();
    let sent = String::from_utf8_lossy(&finished.received);
    assert_eq!(sent.matches("pose ").count(), 61);
    assert!(
        sent.contains("pose 0.000 5.000 -4.000 0.000 3.000 0.000\n"),
        "{sent}"
    );
}

#[test]
fn an_unreachable_row_is_named_before_anything_is_sent() {
    let dir = scratch("unreachable");
    let mut csv = ramp_to([0.0, 0.0, 5.0, 0.0, 0.0, 0.0]);
    csv += "1.3,0,0,60,0,0,0\n1.4,0,0,80,0,0,0\n";
    std::fs::write(dir.join("t.csv"), csv).unwrap();
    for mode in [None, Some("--text")] {
        let board = SimBoard::start();
        let mut args = vec!["stream", "t.csv", "--port", &board.path];
        args.extend(mode);
        let stream = hexapod(&dir, &args);
        assert!(!stream.status.success());
        let err = text(&stream).1;
        // Line 63 (the header is line 1): beyond the z full scale (binary), or unreachable.
        assert!(err.starts_with("hexapod: t.csv:63: "), "{err}");
        let expected = match mode {
            None => "z: 60 is beyond the board's stream full scale stream.z_mm = 15",
            Some(_) => "the board would refuse this pose: error:unreachable leg 1",
        };
        assert!(err.contains(expected), "{err}");
        let received = board.finish().received;
        assert!(!received.contains(&0xA5), "no frame was sent");
        let sent = String::from_utf8_lossy(&received).into_owned();
        assert!(!sent.contains("pose"), "{sent}");
    }
}

#[test]
fn a_row_a_rated_servo_cannot_hold_is_named_in_the_board_s_words_before_anything_is_sent() {
    let dir = scratch("overloaded-row");
    // 2 kg, 30 mm up, on servos rated 1 kgf cm: home holds (about 0.7 each), 5 mm along x
    // (the first row beyond home) does not.
    std::fs::write(
        dir.join("t.csv"),
        "time,x,y,z,roll,pitch,yaw\n0,0,0,0,0,0,0\n0.1,5,0,0,0,0,0\n0.2,10,0,0,0,0,0\n",
    )
    .unwrap();
    for mode in [None, Some("--text")] {
        let board = SimBoard::start();
        let check = hexapod(
            &dir,
            &[
                "send",
                "--port",
                &board.path,
                "set payload_g 2000",
                "set payload_com_z_mm 30",
                "set servos.torque_kgcm 1",
                "check 5 0 0 0 0 0",
            ],
        );
        // The board's own refusal of that pose.
        let (out, _) = text(&check);
        let words = out
            .lines()
            .find(|l| l.starts_with("error:torque-limit "))
            .unwrap_or_else(|| panic!("{out}"))
            .to_string();
        let mut args = vec!["stream", "t.csv", "--port", &board.path];
        args.extend(mode);
        let stream = hexapod(&dir, &args);
        assert!(!stream.status.success());
        let err = text(&stream).1;
        assert_eq!(
            err.trim_end(),
            format!(
                "hexapod: t.csv:3: the board would refuse this pose: {words}; nothing was sent"
            )
        );
        let received = board.finish().received;
        assert!(!received.contains(&0xA5), "no frame was sent");
        let sent = String::from_utf8_lossy(&received).into_owned();
        assert!(!sent.contains("pose"), "{sent}");
    }
}

#[test]
fn a_row_the_board_refuses_is_reported_and_the_rest_still_goes() {
    let dir = scratch("refused-row");
    // docs/error-codes.md: from the first pose the straight path to the second leaves the
    // workspace (error:path-blocked); each pose alone is reachable.
    std::fs::write(
        dir.join("t.csv"),
        "time,x,y,z,roll,pitch,yaw\n0,-28,19,-2.5,11,2,-20\n3,30,-12,-13.5,5,-13,28\n\
         3.1,0,0,2,0,0,0\n",
    )
    .unwrap();
    let board = SimBoard::start();
    let stream = hexapod(
        &dir,
        &[
            "stream",
            "t.csv",
            "--text",
            "--port",
            &board.path,
            "--timeout-s",
            "10",
        ],
    );
    let (out, err) = text(&stream);
    assert!(!stream.status.success(), "{out}{err}");
    assert!(
        err.contains("line 3: the board refused 'pose 30.000"),
        "{err}"
    );
    assert!(err.contains("error:path-blocked"), "{err}");
    assert!(out.contains("lines sent: 3, ok: 2, refused: 1"), "{out}");
    assert!(
        err.contains("t.csv: the stream did not go through whole: 1 lines refused"),
        "{err}"
    );
    let sent = String::from_utf8_lossy(&board.finish().received).into_owned();
    assert!(
        sent.contains("pose 0.000 0.000 2.000 0.000 0.000 0.000"),
        "{sent}"
    );
}

#[test]
fn unreadable_trajectories_name_file_line_and_field() {
    let dir = scratch("bad-csv");
    std::fs::write(
        dir.join("t.csv"),
        "time,x,y,z,roll,pitch,yaw\n0,0,0,0,0,0,0\n0.1,0,0,1,0,pitch?,0\n",
    )
    .unwrap();
    let board = SimBoard::start();
    let stream = hexapod(&dir, &["stream", "t.csv", "--port", &board.path]);
    assert!(!stream.status.success());
    assert_eq!(
        text(&stream).1.trim_end(),
        "hexapod: t.csv:3: pitch: 'pitch?' is not a number"
    );
    assert!(
        board.finish().received.is_empty(),
        "the file is read before the port is used"
    );
}

#[test]
fn demos_are_written_as_csv_that_streams_back() {
    let dir = scratch("demo");
    let demo = hexapod(
        &dir,
        &[
            "demo",
            "figure-eight",
            "--duration-s",
            "2",
            "--period-s",
            "1",
            "-o",
            "eight.csv",
        ],
    );
    assert!(demo.status.success(), "{:?}", text(&demo));
    let csv = std::fs::read_to_string(dir.join("eight.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 101);
    let rows = hexapod::trajectory::parse("eight.csv", &csv).unwrap();
    assert_eq!(rows.last().unwrap().time_s, 2.0);
    let nowhere = hexapod(&dir, &["demo", "circle"]);
    assert!(
        text(&nowhere).1.contains("--port/--output"),
        "{:?}",
        text(&nowhere)
    );
    let board = SimBoard::start();
    let stream = hexapod(
        &dir,
        &["demo", "heave", "--duration-s", "1", "--port", &board.path],
    );
    assert!(stream.status.success(), "{:?}", text(&stream));
    assert!(
        text(&stream).0.contains("demo heave: 51 rows sent"),
        "{:?}",
        text(&stream)
    );
}
