//! `cue --record FILE`: a CSV row per frame sent (what came in, what went out; columns in
//! [`RECORD_COLUMNS`]), and `cue-plot`: per axis, the aircraft's specific force or rate
//! beside what the platform delivers, worked out from the poses sent alone: the translation's
//! acceleration (second differences) plus gravity, both seen in the tilted platform's axes
//! (`f = R^T (a + g z)`), and the angles' rates (first differences).
//!
//! Units: s, m/s^2, deg/s, mm, degrees.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use super::reach::rotation;
use super::washout::{Cue, Motion, G};
use crate::error::{CueError, Error, RecordError};
use crate::picture::{write_scene, Anchor, Scene, Style};
use crate::plot::{legend, nice_range, Axes, PALETTE};

/// The record's columns (CSV header).
pub const RECORD_COLUMNS: [&str; 17] = [
    "time_s",
    "sim_time_s",
    "fx_ms2",
    "fy_ms2",
    "fz_ms2",
    "p_deg_s",
    "q_deg_s",
    "r_deg_s",
    "x_mm",
    "y_mm",
    "z_mm",
    "roll_deg",
    "pitch_deg",
    "yaw_deg",
    "limited",
    "easing",
    "latency_ms",
];

/// The record's comment line: what the columns are.
pub const RECORD_COMMENT: &str = "# hexapod cue record: time_s since the first frame; \
    sim_time_s and the aircraft's specific force (m/s^2) and rates (deg/s) of the newest \
    sample, in the platform's axes (x forward, y left, z up); the pose sent (mm, deg); \
    limited 1 when a limit changed it; easing 1 while easing home or back; latency_ms \
    from the sample's arrival to its frame written (empty if the frame carried no new sample)";

/// The plot's panels: title and y label, x y z then roll pitch yaw.
pub const PANELS: [(&str, &str); 6] = [
    ("x (surge): specific force", "m/s²"),
    ("y (sway): specific force", "m/s²"),
    ("z (heave): specific force", "m/s²"),
    ("roll rate", "deg/s"),
    ("pitch rate", "deg/s"),
    ("yaw rate", "deg/s"),
];
/// The plot's legend.
pub const LEGEND_AIRCRAFT: &str = "aircraft (at the pilot's head)";
/// The plot's legend.
pub const LEGEND_SCALED: &str = "aircraft × the axis' scale";
/// The plot's legend.
pub const LEGEND_PLATFORM: &str = "platform delivers (from the poses sent)";
/// The plot's x axis.
pub const TIME_LABEL: &str = "time (s)";
/// The plot's title.
pub fn plot_title(file: &str) -> String {
    format!(
        "Motion cues of {file}: what the aircraft felt, what the platform gave \
         (platform axes: x forward, y left, z up)"
    )
}

/// Writes the record.
pub struct Recorder {
    path: String,
    out: BufWriter<File>,
}

fn file_problem(path: &str, error: std::io::Error) -> Error {
    Error::File {
        path: path.to_string(),
        error,
    }
}

impl Recorder {
    /// Creates (or replaces) the file and writes its header.
    pub fn create(path: &Path) -> Result<Recorder, Error> {
        let name = path.display().to_string();
        let file = File::create(path).map_err(|e| file_problem(&name, e))?;
        let mut recorder = Recorder {
            path: name,
            out: BufWriter::new(file),
        };
        let header = format!("{RECORD_COMMENT}\n{}\n", RECORD_COLUMNS.join(","));
        recorder.write(&header)?;
        Ok(recorder)
    }

    fn write(&mut self, text: &str) -> Result<(), Error> {
        self.out
            .write_all(text.as_bytes())
            .map_err(|e| file_problem(&self.path, e))
    }

    /// One frame: when (s since the first), the newest sample's time, its motion (platform
    /// axes, m/s^2 and rad/s), the pose sent, and how it came about.
    #[allow(clippy::too_many_arguments)]
    pub fn row(
        &mut self,
        time_s: f64,
        sim_time_s: Option<f64>,
        motion: &Motion,
        pose: &Cue,
        limited: bool,
        easing: bool,
        latency_ms: Option<f64>,
    ) -> Result<(), Error> {
        let mut line = format!("{time_s:.5},");
        if let Some(t) = sim_time_s {
            let _ = write!(line, "{t:.5}");
        }
        for f in motion.force {
            let _ = write!(line, ",{f:.5}");
        }
        for r in motion.rates {
            let _ = write!(line, ",{:.4}", r.to_degrees());
        }
        for v in pose {
            let _ = write!(line, ",{v:.4}");
        }
        let _ = write!(line, ",{},{},", u8::from(limited), u8::from(easing));
        if let Some(ms) = latency_ms {
            let _ = write!(line, "{ms:.4}");
        }
        line.push('\n');
        self.write(&line)
    }

    /// Flushes the file.
    pub fn finish(&mut self) -> Result<(), Error> {
        self.out.flush().map_err(|e| file_problem(&self.path, e))
    }
}

/// One row of a record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// s since the first frame.
    pub time_s: f64,
    /// The aircraft's specific force, platform axes, m/s^2.
    pub force: [f64; 3],
    /// Its rates, platform axes, deg/s.
    pub rates_deg_s: [f64; 3],
    /// The pose sent, mm and degrees.
    pub pose: Cue,
}

/// Reads a record's text; `file` names it in errors.
pub fn parse(file: &str, text: &str) -> Result<Vec<Row>, Error> {
    let problem = |line: usize, why: RecordError| {
        Error::from(CueError::Record {
            file: file.to_string(),
            line: line as u64,
            why,
        })
    };
    let mut rows = Vec::new();
    let mut header = false;
    for (n, line) in text.lines().enumerate() {
        let line_no = n + 1;
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if !header {
            if fields != RECORD_COLUMNS {
                return Err(problem(
                    line_no,
                    RecordError::Header {
                        columns: &RECORD_COLUMNS,
                    },
                ));
            }
            header = true;
            continue;
        }
        if fields.len() != RECORD_COLUMNS.len() {
            return Err(problem(line_no, RecordError::FieldCount(fields.len())));
        }
        let number = |i: usize| -> Result<f64, Error> {
            fields[i]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    problem(
                        line_no,
                        RecordError::NotFinite {
                            column: RECORD_COLUMNS[i],
                            text: fields[i].to_string(),
                        },
                    )
                })
        };
        let mut v = [0.0; 12];
        for (k, slot) in v.iter_mut().enumerate() {
            *slot = number(2 + k)?;
        }
        rows.push(Row {
            time_s: number(0)?,
            force: [v[0], v[1], v[2]],
            rates_deg_s: [v[3], v[4], v[5]],
            pose: [v[6], v[7], v[8], v[9], v[10], v[11]],
        });
    }
    if rows.is_empty() {
        return Err(problem(1, RecordError::Empty));
    }
    Ok(rows)
}

/// Rows either side of the differences' middle row: wider than one frame, so that the jitter
/// of the frames' times (the host's) does not swamp the second differences.
pub const SPAN: usize = 2;

/// What the platform delivers at each row (specific force m/s^2 in its axes, rates deg/s),
/// from the poses alone; `None` at the ends (and where time does not advance).
pub fn delivered(rows: &[Row]) -> Vec<Option<([f64; 3], [f64; 3])>> {
    let mut out = vec![None; rows.len()];
    for i in SPAN..rows.len().saturating_sub(SPAN) {
        let (a, b, c) = (&rows[i - SPAN], &rows[i], &rows[i + SPAN]);
        let (h1, h2) = (b.time_s - a.time_s, c.time_s - b.time_s);
        if h1 <= 0.0 || h2 <= 0.0 {
            continue;
        }
        // Second difference on uneven steps, mm -> m.
        let acc: [f64; 3] = core::array::from_fn(|k| {
            let d1 = (b.pose[k] - a.pose[k]) / h1;
            let d2 = (c.pose[k] - b.pose[k]) / h2;
            2.0 * (d2 - d1) / (h1 + h2) * 1e-3
        });
        let r = rotation(b.pose[3], b.pose[4], b.pose[5]);
        let world = [acc[0], acc[1], acc[2] + G];
        // R^T world: the force in the platform's own axes.
        let force = core::array::from_fn(|k| (0..3).map(|j| r[j][k] * world[j]).sum());
        let rates = core::array::from_fn(|k| (c.pose[3 + k] - a.pose[3 + k]) / (h1 + h2));
        out[i] = Some((force, rates));
    }
    out
}

/// The plot of a record: six panels (x y z force, roll pitch yaw rate).
pub fn scene(rows: &[Row], title: &str) -> Scene {
    let (w, h) = (1200.0, 900.0);
    let mut scene = Scene::new(w, h);
    scene.text("title", [w / 2.0, 28.0], title, 16.0, Anchor::Middle);
    let delivered = delivered(rows);
    let t0 = rows.first().map_or(0.0, |r| r.time_s);
    let t1 = rows.last().map_or(1.0, |r| r.time_s).max(t0 + 1e-3);
    for (panel, (name, unit)) in PANELS.iter().enumerate() {
        let aircraft: Vec<[f64; 2]> = rows
            .iter()
            .map(|r| {
                let v = if panel < 3 {
                    r.force[panel]
                } else {
                    r.rates_deg_s[panel - 3]
                };
                [r.time_s, v]
            })
            .collect();
        let platform: Vec<[f64; 2]> = rows
            .iter()
            .zip(&delivered)
            .filter_map(|(r, d)| {
                let (force, rates) = (*d)?;
                let v = if panel < 3 {
                    force[panel]
                } else {
                    rates[panel - 3]
                };
                Some([r.time_s, v])
            })
            .collect();
        let (lo, hi) = aircraft
            .iter()
            .chain(&platform)
            .fold((f64::MAX, f64::MIN), |(lo, hi), p| {
                (lo.min(p[1]), hi.max(p[1]))
            });
        let (lo, hi) = if hi - lo < 0.2 {
            ((lo + hi) / 2.0 - 0.1, (lo + hi) / 2.0 + 0.1)
        } else {
            (lo, hi)
        };
        let col = (panel / 3) as f64;
        let row = (panel % 3) as f64;
        let axes = Axes {
            left: 90.0 + col * 580.0,
            top: 105.0 + row * 265.0,
            width: 480.0,
            height: 190.0,
            x: (t0, t1),
            y: nice_range(lo, hi),
            y_ticks: true,
        };
        axes.draw(&mut scene, name, TIME_LABEL, unit);
        axes.line(
            &mut scene,
            "aircraft",
            &aircraft,
            Style::stroke(PALETTE[0], 1.5),
        );
        axes.line(
            &mut scene,
            "platform",
            &platform,
            Style::stroke(PALETTE[5], 1.5),
        );
    }
    legend(
        &mut scene,
        [440.0, 46.0],
        &[
            (PALETTE[0], LEGEND_AIRCRAFT.to_string(), false),
            (PALETTE[5], LEGEND_PLATFORM.to_string(), false),
        ],
    );
    scene
}

/// `hexapod cue-plot RECORD -o STEM`: the files written, and the frames plotted.
pub fn plot(
    record: &Path,
    stem: &Path,
    svg: bool,
    png: bool,
) -> Result<(Vec<String>, usize), Error> {
    let file = record.display().to_string();
    let text = std::fs::read_to_string(record).map_err(|e| file_problem(&file, e))?;
    let rows = parse(&file, &text)?;
    let name = record
        .file_name()
        .map_or(file.clone(), |n| n.to_string_lossy().into_owned());
    let written = write_scene(&scene(&rows, &plot_title(&name)), stem, svg, png)?;
    Ok((written, rows.len()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(time_s: f64, pose: Cue) -> Row {
        Row {
            time_s,
            force: [0.0, 0.0, G],
            rates_deg_s: [0.0; 3],
            pose,
        }
    }

    #[test]
    fn a_still_level_platform_delivers_one_g_up_and_no_rate() {
        let rows: Vec<Row> = (0..5).map(|i| row(f64::from(i) * 0.02, [0.0; 6])).collect();
        let d = delivered(&rows);
        assert!(d[1].is_none() && d[3].is_none());
        let (f, r) = d[2].unwrap();
        assert_eq!(f, [0.0, 0.0, G]);
        assert_eq!(r, [0.0; 3]);
    }

    #[test]
    fn a_parabola_in_x_and_a_pitch_ramp_are_read_back() {
        // x = 1000 * 0.5 a t^2 mm with a = 2 m/s^2; pitch ramps at 3 deg/s, held at 5 deg in
        // the middle row's pose; uneven steps.
        let times = [0.0, 0.01, 0.025, 0.04, 0.05];
        let rows: Vec<Row> = times
            .iter()
            .map(|&t| row(t, [1000.0 * t * t, 0.0, 0.0, 0.0, 5.0 + 3.0 * t, 0.0]))
            .collect();
        let (f, r) = delivered(&rows)[2].unwrap();
        // Pitch 5 degrees (nose down about y): R^T (a, 0, g) with a = 2.
        let p = (5.0 + 3.0 * 0.025f64).to_radians();
        let want_x = 2.0 * p.cos() - G * p.sin();
        let want_z = 2.0 * p.sin() + G * p.cos();
        assert!((f[0] - want_x).abs() < 1e-9, "{f:?} vs {want_x}");
        assert!(f[1].abs() < 1e-12);
        assert!((f[2] - want_z).abs() < 1e-9, "{f:?} vs {want_z}");
        assert!((r[1] - 3.0).abs() < 1e-9);
    }

    #[test]
    fn a_record_is_read_back_and_bad_ones_are_named() {
        let dir = std::env::temp_dir().join(format!("cue-record-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("r.csv");
        let mut rec = Recorder::create(&path).unwrap();
        let motion = Motion::REST.in_platform_axes();
        rec.row(
            0.0,
            Some(1.0),
            &motion,
            &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            false,
            false,
            Some(0.25),
        )
        .unwrap();
        rec.row(0.02, None, &motion, &[0.0; 6], true, true, None)
            .unwrap();
        rec.finish().unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let rows = parse("r.csv", &text).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].pose, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert!((rows[0].force[2] - G).abs() < 1e-4);
        assert_eq!(rows[1].time_s, 0.02);
        let bad = format!("{}\n1,2,3\n", RECORD_COLUMNS.join(","));
        assert_eq!(
            parse("r.csv", &bad).unwrap_err().to_string(),
            "r.csv:2: 3 fields"
        );
        assert!(parse("r.csv", "time,x\n")
            .unwrap_err()
            .to_string()
            .starts_with("r.csv:1: not a cue record"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
