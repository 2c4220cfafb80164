//! Trajectory files: CSV with a header naming the columns `time,x,y,z,roll,pitch,yaw` (any
//! order): time in s, x y z in mm, roll pitch yaw in degrees (the pose convention of the
//! firmware: z from the home height, R = Rz(yaw) Ry(pitch) Rx(roll)). Lines starting with `#`
//! are comments. Time must increase from row to row; it may start anywhere.
//!
//! Before anything is sent, every row is turned into what the board will get (a binary stream
//! frame's counts, or a `pose` line with 3 decimals) and that is checked with the firmware's
//! own code: the counts decoded by `control::stream::StreamSettings::to_pose`, the line's
//! numbers read by `control::number::parse_f32`, the pose solved by the IK with the board's
//! geometry and servo limits, and with the board's payload and torque ratings, its holding
//! torques checked as the board checks a target (`control::payload::PayloadSettings::check`).
//! The first row that would not be driven as written is the error.

use std::fmt::Write as _;
use std::path::Path;

use control::number::parse_f32;
use control::settings::{SettingId, Settings};
use control::stream::{Frame, BINARY_FRAME_LEN, BINARY_HEADER, BINARY_TRAILER};
use kinematics_core::ik::Solver;
use kinematics_core::pose::Axis;
use kinematics_core::{Libm, Pose};

use crate::error::{board_words, Error, RowError};

/// The columns, in pose order after time.
pub const COLUMNS: [&str; 7] = ["time", "x", "y", "z", "roll", "pitch", "yaw"];

/// One row of a trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Its line in the file, from 1 (0 for rows made by the tool).
    pub line: u64,
    /// When, s.
    pub time_s: f64,
    /// x, y, z in mm; roll, pitch, yaw in degrees.
    pub pose: [f64; 6],
}

/// How rows go to the board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Binary stream frames (no reply).
    Binary,
    /// `pose` lines (each answered).
    Text,
}

/// What the board is sent for a row.
#[derive(Debug, Clone, PartialEq)]
pub enum Message {
    /// A binary frame.
    Frame([u8; BINARY_FRAME_LEN]),
    /// A command line.
    Line(String),
}

/// Reads a trajectory file.
pub fn read(path: &Path) -> Result<Vec<Row>, Error> {
    let file = path.display().to_string();
    let text = crate::files::read_text(path)?;
    parse(&file, &text)
}

/// Reads a trajectory's text; `file` names it in errors.
pub fn parse(file: &str, text: &str) -> Result<Vec<Row>, Error> {
    let problem = |line: u64, field: Option<&str>, why| Error::Row {
        file: file.to_string(),
        line,
        field: field.map(str::to_string),
        why,
    };
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(text.as_bytes());
    let header = reader
        .headers()
        .map_err(|e| problem(1, None, RowError::Unreadable(e.to_string())))?
        .clone();
    let header_line = header.position().map_or(1, |p| p.line());
    let names: Vec<String> = header.iter().map(str::to_ascii_lowercase).collect();
    // Column index of each of COLUMNS.
    let mut index = [0usize; 7];
    for (slot, column) in index.iter_mut().zip(COLUMNS) {
        let found = names.iter().position(|n| n == column);
        match found {
            Some(i) if names.len() == COLUMNS.len() => *slot = i,
            _ => {
                return Err(problem(
                    header_line,
                    None,
                    RowError::Header {
                        found: names.join(","),
                    },
                ))
            }
        }
    }
    // The line of a record: csv's own count skips blank lines, so count from its byte offset,
    // past the blank and comment lines before the record.
    let line_at = |byte: u64| {
        let mut at = (byte as usize).min(text.len());
        loop {
            let rest = &text[at..];
            if rest.starts_with(['\r', '\n']) {
                at += 1;
            } else if rest.starts_with('#') {
                at += rest.find('\n').map_or(rest.len(), |n| n + 1);
            } else {
                break;
            }
        }
        text[..at].matches('\n').count() as u64 + 1
    };
    let mut rows: Vec<Row> = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| line_at(p.byte()));
            problem(line, None, RowError::Unreadable(e.to_string()))
        })?;
        let line = record.position().map_or(0, |p| line_at(p.byte()));
        if record.len() != COLUMNS.len() {
            return Err(problem(
                line,
                None,
                RowError::FieldCount {
                    found: record.len(),
                },
            ));
        }
        let mut values = [0.0f64; 7];
        for (value, (&i, column)) in values.iter_mut().zip(index.iter().zip(COLUMNS)) {
            let field = &record[i];
            let number: f64 = field
                .parse()
                .map_err(|_| problem(line, Some(column), RowError::NotANumber(field.into())))?;
            if !number.is_finite() {
                return Err(problem(
                    line,
                    Some(column),
                    RowError::NotFinite(field.into()),
                ));
            }
            *value = number;
        }
        let [time_s, pose @ ..] = values;
        if let Some(previous) = rows.last() {
            if time_s <= previous.time_s {
                return Err(problem(
                    line,
                    Some("time"),
                    RowError::TimeNotIncreasing {
                        time_s,
                        previous_s: previous.time_s,
                    },
                ));
            }
        }
        rows.push(Row { line, time_s, pose });
    }
    if rows.is_empty() {
        return Err(problem(header_line, None, RowError::Empty));
    }
    Ok(rows)
}

/// A trajectory as CSV text.
pub fn write(rows: &[Row]) -> String {
    let mut out = COLUMNS.join(",");
    out.push('\n');
    for row in rows {
        let _ = write!(out, "{:.4}", row.time_s);
        for v in row.pose {
            let _ = write!(out, ",{:.3}", if v.abs() < 5e-4 { 0.0 } else { v });
        }
        out.push('\n');
    }
    out
}

/// The binary frame of a pose (mm, degrees) with the board's stream full scales, or the axis
/// whose value does not fit them.
pub fn binary_frame(
    settings: &Settings,
    pose: &[f64; 6],
) -> Result<[u8; BINARY_FRAME_LEN], (Axis, f64, f32)> {
    let mut frame = [0u8; BINARY_FRAME_LEN];
    frame[..2].copy_from_slice(&BINARY_HEADER);
    frame[BINARY_FRAME_LEN - 2..].copy_from_slice(&BINARY_TRAILER);
    for (i, axis) in Axis::ALL.into_iter().enumerate() {
        let full_scale = settings.stream.full_scale[i];
        let value = pose[i];
        // count c means (c - 32768) / 32768 of the full scale (README, "Streaming").
        let count = if full_scale == 0.0 {
            if value.abs() > 1e-9 {
                return Err((axis, value, full_scale));
            }
            32768.0
        } else {
            (32768.0 + value / f64::from(full_scale) * 32768.0).round()
        };
        // The top count is 65535: a value at exactly the full scale is one count short.
        let count = if count == 65536.0 { 65535.0 } else { count };
        if !(0.0..=65535.0).contains(&count) {
            return Err((axis, value, full_scale));
        }
        let count = count as u16;
        frame[2 + 2 * i..4 + 2 * i].copy_from_slice(&count.to_be_bytes());
    }
    Ok(frame)
}

/// The `pose` line for a pose (mm, degrees, 3 decimals).
pub fn pose_line(pose: &[f64; 6]) -> String {
    let mut line = String::from("pose");
    for v in pose {
        let _ = write!(line, " {:.3}", if v.abs() < 5e-4 { 0.0 } else { *v });
    }
    line
}

/// The pose the board takes from a message, decoded by the firmware's own code.
pub fn board_pose(settings: &Settings, message: &Message) -> Option<Pose> {
    match message {
        Message::Frame(frame) => {
            let counts = core::array::from_fn(|i| {
                u32::from(u16::from_be_bytes([frame[2 + 2 * i], frame[3 + 2 * i]]))
            });
            settings.stream.to_pose(Frame::Binary(counts)).ok()
        }
        Message::Line(line) => {
            let v: Vec<f32> = line
                .split_whitespace()
                .skip(1)
                .map(parse_f32)
                .collect::<Result<_, _>>()
                .ok()?;
            let [x, y, z, roll, pitch, yaw] = v.try_into().ok()?;
            Some(Pose::from_degrees(x, y, z, roll, pitch, yaw))
        }
    }
}

/// Every row's message, each checked as the board would take it (see the module
/// documentation); `file` names the file in errors.
pub fn prepare(
    file: &str,
    rows: &[Row],
    settings: &Settings,
    mode: Mode,
) -> Result<Vec<Message>, Error> {
    let solver: Solver = settings.validate().map_err(|e| Error::Row {
        file: file.to_string(),
        line: 0,
        field: None,
        why: RowError::Refused(board_words(&control::Error::from(e))),
    })?;
    rows.iter()
        .map(|row| {
            let problem = |field: Option<&str>, why| Error::Row {
                file: file.to_string(),
                line: row.line,
                field: field.map(str::to_string),
                why,
            };
            let message = match mode {
                Mode::Binary => binary_frame(settings, &row.pose)
                    .map(Message::Frame)
                    .map_err(|(axis, value, full_scale)| {
                        problem(
                            Some(axis.name()),
                            RowError::BeyondFullScale {
                                value,
                                setting: SettingId::StreamScale(axis).to_string(),
                                full_scale,
                            },
                        )
                    })?,
                Mode::Text => Message::Line(pose_line(&row.pose)),
            };
            let pose = board_pose(settings, &message).unwrap_or(Pose::HOME);
            let refused = |e: control::Error| problem(None, RowError::Refused(board_words(&e)));
            let solution = solver
                .solve::<Libm>(&settings.servos, &pose)
                .map_err(|e| refused(e.into()))?;
            settings
                .payload
                .check::<Libm>(&solver, &pose, &solution.arm_rad)
                .map_err(|e| refused(control::Error::Torque(e)))?;
            Ok(message)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_read_in_any_column_order_with_comments() {
        let rows = parse(
            "t.csv",
            "# a test\nx,y,z,roll,pitch,yaw,time\n1,2,3,4,5,6,0.5\n\n#\n 1.5 , 0,0,0,0,0 ,0.75\n",
        )
        .unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].time_s, 0.5);
        assert_eq!(rows[0].pose, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(rows[0].line, 3);
        assert_eq!(rows[1].line, 6);
        assert_eq!(rows[1].pose[0], 1.5);
        let again = parse("t.csv", &write(&rows)).unwrap();
        assert_eq!(again[1].pose, rows[1].pose);
    }

    #[test]
    fn bad_rows_name_file_line_and_field() {
        let err = |text: &str| parse("t.csv", text).unwrap_err().to_string();
        let head = "time,x,y,z,roll,pitch,yaw\n";
        assert_eq!(
            err(&format!("{head}0,0,0,0,0,0,0\n0.1,0,zero,0,0,0,0\n")),
            "t.csv:3: y: 'zero' is not a number"
        );
        assert_eq!(
            err(&format!("{head}0,0,0,0,0,0\n")),
            "t.csv:2: 6 fields; a row has 7 (time,x,y,z,roll,pitch,yaw)"
        );
        assert_eq!(
            err(&format!("{head}0,0,0,0,0,0,0\n0,0,0,0,0,0,0\n")),
            "t.csv:3: time: time 0 s is not after the previous row's 0 s"
        );
        assert!(err(&format!("{head}0,0,0,NaN,0,0,0\n"))
            .starts_with("t.csv:2: z: 'NaN' is not a finite"));
        assert!(err("t,x,y,z,roll,pitch,yaw\n").starts_with("t.csv:1: the header must name"));
        assert_eq!(err(head), "t.csv:1: no rows: nothing to do");
    }

    #[test]
    fn frames_decode_with_the_board_s_code_to_the_pose_within_a_count() {
        let settings = Settings::default();
        let pose = [3.2, -7.75, 4.0, 2.5, -1.25, 10.0];
        let frame = binary_frame(&settings, &pose).unwrap();
        assert_eq!(&frame[..2], &[0xA5, 0x5A]);
        assert_eq!(&frame[14..], &[0x0D, 0x0A]);
        // x: 32768 + 3.2 / 25 * 32768 = 36962.3 -> 36962 = 0x9062.
        assert_eq!(&frame[2..4], &[0x90, 0x62]);
        let decoded = board_pose(&settings, &Message::Frame(frame)).unwrap();
        let back = decoded.to_array();
        for (i, (&want, got)) in pose.iter().zip(back).enumerate() {
            let got = if i < 3 {
                f64::from(got)
            } else {
                f64::from(got).to_degrees()
            };
            let count = f64::from(settings.stream.full_scale[i]) / 32768.0;
            assert!((got - want).abs() <= count, "axis {i}: {got} vs {want}");
        }
        // Beyond the full scale (25 mm for x), or any value on an axis whose scale is 0.
        assert!(binary_frame(&settings, &[25.1, 0.0, 0.0, 0.0, 0.0, 0.0]).is_err());
        assert!(binary_frame(&settings, &[25.0, 0.0, 0.0, 0.0, 0.0, 0.0]).is_ok());
    }

    #[test]
    fn the_first_row_the_board_would_refuse_is_named_before_anything_is_sent() {
        let rows = parse(
            "t.csv",
            "time,x,y,z,roll,pitch,yaw\n0,0,0,0,0,0,0\n1,0,0,5,0,0,0\n2,0,0,80,0,0,0\n\
             3,0,0,90,0,0,0\n",
        )
        .unwrap();
        let text = prepare("t.csv", &rows, &Settings::default(), Mode::Text).unwrap_err();
        assert_eq!(
            text.to_string(),
            "t.csv:4: the board would refuse this pose: error:unreachable leg 1 cannot reach \
             (arm and rod cannot meet the platform joint); nothing was sent"
        );
        // In binary mode 80 mm is beyond the z full scale first.
        let binary = prepare("t.csv", &rows, &Settings::default(), Mode::Binary).unwrap_err();
        assert!(
            binary.to_string().starts_with(
                "t.csv:4: z: 80 is beyond the board's stream full scale stream.z_mm = 15"
            ),
            "{binary}"
        );
        let ok = prepare("t.csv", &rows[..2], &Settings::default(), Mode::Text).unwrap();
        assert_eq!(
            ok[1],
            Message::Line("pose 0.000 0.000 5.000 0.000 0.000 0.000".into())
        );
    }
}
