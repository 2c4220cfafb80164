//! `hexapod cue` and `cue-plot` as a user runs them, against the firmware's own controller on a
//! pseudo-terminal (`support::SimBoard`), with telemetry sent over UDP on the loopback by the
//! test (in the format JSBSim's socket output sends, bad lines among it): the frames the board
//! received, where it ended, what was counted, and the plot of the record. The flight of a real
//! flight-dynamics engine against the real firmware is `emulator/test/cue.test.js`.

mod support;

use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::thread;
use std::time::{Duration, Instant};

use support::{hexapod, pass_through_board, scratch, text, SimBoard};

/// A UDP port free on the loopback now (bound, then released for the tool).
fn free_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A flight's set-up: a scratch folder holding `build.toml` (easing home over `ease_s`, the
/// tilt at 8 deg/s), a board passing frames through, and a free port for the tool to listen on.
struct Flight {
    dir: PathBuf,
    board: SimBoard,
    port: u16,
    /// `127.0.0.1:port`.
    listen: String,
}

fn flight(name: &str, ease_s: &str) -> Flight {
    let dir = scratch(name);
    let board = pass_through_board(&dir);
    std::fs::write(
        dir.join("build.toml"),
        format!("[cue]\nease_s = {ease_s}\n[cue.tilt]\nrate_deg_s = 8\n"),
    )
    .unwrap();
    let port = free_port();
    let listen = format!("127.0.0.1:{port}");
    Flight {
        dir,
        board,
        port,
        listen,
    }
}

impl Flight {
    /// `cue` on this flight's board, port and build file, recording to `flight.csv`; then `more`.
    fn cue_args<'a>(&'a self, more: &[&'a str]) -> Vec<&'a str> {
        let mut args = vec![
            "cue",
            "--port",
            &self.board.path,
            "--listen",
            &self.listen,
            "--settings",
            "build.toml",
            "--record",
            "flight.csv",
        ];
        args.extend_from_slice(more);
        args
    }
}

/// The rows of a `cue --record` file (after its two header lines), every field a number (NaN
/// where one is not).
fn record_rows(dir: &Path) -> Vec<Vec<f64>> {
    let record = std::fs::read_to_string(dir.join("flight.csv")).unwrap();
    record
        .lines()
        .skip(2)
        .map(|l| {
            l.split(',')
                .map(|f| f.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

/// Gravity, and the forward push the flights make (3 m/s^2), in the telemetry's ft/s^2.
const G_FT_S2: f64 = 9.80665 / 0.3048;
const PUSH_FT_S2: f64 = 3.0 / 0.3048;

/// A telemetry line: time, specific force (ft/s^2, body axes), rates (rad/s), attitude.
fn line(time_s: f64, force_ft_s2: [f64; 3]) -> String {
    format!(
        "{time_s:.4},{:.5},{:.5},{:.5},0,0,0,0,0,0",
        force_ft_s2[0], force_ft_s2[1], force_ft_s2[2]
    )
}

/// Sends, in real time at 100 lines a second: 0.5 s at rest, 1.5 s of 3 m/s^2 forward, 0.5 s
/// at rest; with four bad lines and a repeated time among them.
fn fly(port: u16) {
    let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
    let to = ("127.0.0.1", port);
    let start = Instant::now();
    for k in 0..250 {
        let t = f64::from(k) * 0.01;
        let ax = if (0.5..2.0).contains(&t) {
            PUSH_FT_S2
        } else {
            0.0
        };
        socket
            .send_to(line(t, [ax, 0.0, -G_FT_S2]).as_bytes(), to)
            .unwrap();
        match k {
            20 => {
                socket.send_to(b"hello", to).unwrap();
            }
            40 => {
                socket.send_to(b"0.4,1,2,3", to).unwrap();
            }
            60 => {
                socket.send_to(b"0.6,0,0,-32.17,NaN,0,0,0,0,0", to).unwrap();
            }
            80 => {
                socket
                    .send_to(b"0.8,0,0,-32.17,zero,0,0,0,0,0", to)
                    .unwrap();
                // The same time again: not a new sample.
                socket
                    .send_to(line(t, [0.0, 0.0, -G_FT_S2]).as_bytes(), to)
                    .unwrap();
            }
            _ => {}
        }
        let due = start + Duration::from_secs_f64(t + 0.01);
        thread::sleep(due.saturating_duration_since(Instant::now()));
    }
}

#[test]
fn telemetry_becomes_frames_bad_lines_are_counted_and_the_end_eases_home() {
    let flight = flight("cue", "0.5");
    let port = flight.port;
    let sender = thread::spawn(move || {
        // Time for the tool to start and read the board's settings.
        thread::sleep(Duration::from_millis(700));
        fly(port);
    });
    let cue = hexapod(
        &flight.dir,
        &flight.cue_args(&["--idle-exit-s", "0.5", "--wait-s", "10"]),
    );
    let Flight {
        dir, board, listen, ..
    } = flight;
    sender.join().unwrap();
    let (out, err) = text(&cue);
    assert!(cue.status.success(), "{out}{err}");
    assert!(
        out.contains(&format!("cue: telemetry from {listen} to ")),
        "{out}"
    );
    assert!(out.contains("250 samples"), "{out}");
    assert!(
        out.contains(
            "dropped: 2 not 10 fields, 1 a field not a number, 1 NaN or infinite, 1 whose \
             time did not advance"
        ),
        "{out}"
    );
    assert!(out.contains("damaged=0 clamped=0 refused=0"), "{out}");
    let frames: u64 = out
        .split("frames sent: ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    // 2.5 s of telemetry at the board's 50 Hz, then easing home (0.5 s): about 150.
    assert!((100..=200).contains(&frames), "{out}");
    assert!(
        out.contains(&format!("the board counted frames={frames} ")),
        "{out}"
    );
    assert!(
        out.contains("latency (packet arrival to frame written): min "),
        "{out}"
    );

    // The record: the forward push tilted the nose up (negative pitch, the board's pitch
    // lowering +x) and pushed the platform forward first.
    let rows = record_rows(&dir);
    assert_eq!(rows.len() as u64, frames);
    let most_nose_up = rows.iter().map(|r| r[12]).fold(f64::MAX, f64::min);
    let most_forward = rows.iter().map(|r| r[8]).fold(f64::MIN, f64::max);
    assert!(most_nose_up < -3.0, "pitch reached {most_nose_up}");
    assert!(most_forward > 2.0, "x reached {most_forward}");

    // The board, at the end: home, having received every frame whole.
    let finished = board.finish();
    let received = finished
        .received
        .windows(2)
        .filter(|w| w == &[0xA5, 0x5A])
        .count();
    assert_eq!(received as u64, frames);
    let pose = finished.pose.to_array();
    assert!(pose.iter().all(|v| v.abs() < 1e-3), "{pose:?}");

    // The plot of that record: six panels, each with the aircraft and the platform.
    let plot = hexapod(&dir, &["cue-plot", "flight.csv", "-o", "flight"]);
    let (out, err) = text(&plot);
    assert!(plot.status.success(), "{out}{err}");
    assert!(out.contains(&format!(
        "{frames} frames plotted to flight.svg and flight.png"
    )));
    let svg = std::fs::read_to_string(dir.join("flight.svg")).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap();
    for class in ["aircraft", "platform"] {
        let n = doc
            .descendants()
            .filter(|n| n.attribute("class") == Some(class))
            .count();
        assert_eq!(n, 6, "{class}");
    }
    assert!(std::fs::metadata(dir.join("flight.png")).unwrap().len() > 10_000);
}

#[test]
fn nothing_valid_is_an_error_that_says_what_came() {
    let dir = scratch("cue-garbage");
    let board = SimBoard::start();
    let port = free_port();
    let listen = format!("127.0.0.1:{port}");
    let sender = thread::spawn(move || {
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        for _ in 0..40 {
            for bytes in [&b"\xff\xfe"[..], b"1,2,3", b"1,0,0,-32,0,inf,0,0,0,0"] {
                socket.send_to(bytes, ("127.0.0.1", port)).unwrap();
            }
            thread::sleep(Duration::from_millis(50));
        }
    });
    let cue = hexapod(
        &dir,
        &[
            "cue",
            "--port",
            &board.path,
            "--listen",
            &listen,
            "--wait-s",
            "1.5",
        ],
    );
    sender.join().unwrap();
    let (out, err) = text(&cue);
    assert!(!cue.status.success(), "{out}{err}");
    assert!(
        err.starts_with(&format!("cue: listening for telemetry on {listen}; ")),
        "{err}"
    );
    let err = err.lines().nth(1).unwrap_or_default().to_string();
    assert!(
        err.starts_with(&format!(
            "hexapod: no valid telemetry on {listen} in 1.5 s: "
        )),
        "{err}"
    );
    assert!(err.contains(" not text, "), "{err}");
    assert!(err.contains(" not 10 fields, "), "{err}");
    assert!(err.contains(" NaN or infinite."), "{err}");
    assert!(err.contains("time_s,ax,ay,az,p,q,r,phi,theta,psi"), "{err}");
    let finished = board.finish();
    assert!(!finished.received.contains(&0xA5), "no frame was sent");
}

#[test]
fn a_bad_cue_key_is_named_before_anything_is_sent() {
    let dir = scratch("cue-key");
    std::fs::write(
        dir.join("b.toml"),
        "rod_mm = 120\n[cue.x]\nscale = 0.3\norder = 4\n",
    )
    .unwrap();
    let cue = hexapod(
        &dir,
        &["cue", "--port", "/nonexistent", "--settings", "b.toml"],
    );
    assert!(!cue.status.success());
    assert_eq!(
        text(&cue).1.trim_end(),
        "hexapod: b.toml:4: cue.x.order: must be a whole number 2..3"
    );
    // The board's own check of the same file passes the [cue] table by.
    let apply = hexapod(&dir, &["apply", "b.toml"]);
    assert!(apply.status.success(), "{:?}", text(&apply));
}

/// Ctrl-C mid-flight (SIGINT, as a terminal sends it): the tool takes no more telemetry, eases
/// the platform home over `ease_s` in frames at its rate, and then exits normally, saying so.
#[cfg(unix)]
#[test]
fn ctrl_c_eases_the_platform_home_before_exiting() {
    use std::process::{Command, Stdio};
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    let flight = flight("cue-ctrl-c", "1.0");
    let port = flight.port;
    let child = Command::new(env!("CARGO_BIN_EXE_hexapod"))
        .args(flight.cue_args(&["--wait-s", "10"]))
        .current_dir(&flight.dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("hexapod runs");
    let Flight { dir, board, .. } = flight;
    // A sustained forward push, sent until the test stops it (also after the Ctrl-C: it must
    // not be taken).
    let sending = Arc::new(AtomicBool::new(true));
    let sender = {
        let sending = sending.clone();
        thread::spawn(move || {
            thread::sleep(Duration::from_millis(700));
            let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
            let mut k = 0u32;
            while sending.load(Ordering::Relaxed) {
                let t = f64::from(k) * 0.01;
                let ax = if t < 0.3 { 0.0 } else { PUSH_FT_S2 };
                let _ =
                    socket.send_to(line(t, [ax, 0.0, -G_FT_S2]).as_bytes(), ("127.0.0.1", port));
                k += 1;
                thread::sleep(Duration::from_millis(10));
            }
        })
    };
    // Mid-push: the platform is away from home (tilted nose up, forward).
    thread::sleep(Duration::from_millis(2200));
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(kill.success());
    let cue = child.wait_with_output().expect("hexapod exits");
    sending.store(false, Ordering::Relaxed);
    sender.join().unwrap();
    let (out, err) = text(&cue);
    assert!(cue.status.success(), "{:?}: {out}{err}", cue.status);
    assert!(
        err.contains("cue: stopping (Ctrl-C): easing the platform home"),
        "{err}"
    );
    assert!(
        out.contains("stopped by Ctrl-C, the platform eased home"),
        "{out}"
    );
    assert!(out.contains("damaged=0 clamped=0 refused=0"), "{out}");

    // The record: away from home when stopped, then eased rows at the frame rate, ending at
    // home with no step larger than a smooth second-long ease allows.
    let rows = record_rows(&dir);
    let last_live = rows
        .iter()
        .rposition(|r| r[15] == 0.0)
        .expect("frames followed the cues");
    let away = &rows[last_live];
    assert!(away[12] < -3.0, "pitch when stopped: {}", away[12]);
    let easing = &rows[last_live + 1..];
    // One second at the board's 50 Hz.
    assert!(
        (40..=60).contains(&easing.len()),
        "{} easing frames",
        easing.len()
    );
    let end = easing.last().unwrap();
    assert!(end[8..14].iter().all(|v| v.abs() < 1e-6), "{end:?}");
    // A smooth ease of a pitch p over 1 s moves at most 1.5 p per second: at 50 Hz, 0.03 p
    // a frame (a little more for the frames' jitter).
    let most_step = easing
        .windows(2)
        .map(|w| (w[1][12] - w[0][12]).abs())
        .fold(0.0, f64::max);
    assert!(
        most_step < 0.05 * away[12].abs(),
        "{most_step} of {}",
        away[12]
    );

    // The board, at the end: home, every frame received whole.
    let finished = board.finish();
    let pose = finished.pose.to_array();
    assert!(pose.iter().all(|v| v.abs() < 1e-3), "{pose:?}");
}
