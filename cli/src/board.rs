//! What the tool reads back from a board's replies: `config`'s listing as [`Settings`] (read
//! with the firmware's own `SettingId::parse` and `parse_value`, exactly as `set` would take
//! each value), and `status`'s stream counters and pulse widths (us).
//!
//! `config` lists `# name: value` for each setting, then `# servoN: trim_us=.. rate_us_rad=..
//! dir=.. min_us=.. max_us=..`, then `# saved: ...`, which is not a setting and is skipped.

use control::settings::{SettingId, Settings};
use kinematics_core::LEGS;

use crate::link::{Link, Reply};

/// `status`'s stream counters (`# stream: frames=.. applied=.. damaged=.. clamped=..
/// refused=..`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StreamCounters {
    /// Frames received.
    pub frames: u64,
    /// Frames applied (the newest of those waiting).
    pub applied: u64,
    /// Frames dropped as damaged.
    pub damaged: u64,
    /// Frames clamped to the workspace.
    pub clamped: u64,
    /// Frames refused (e-stop).
    pub refused: u64,
}

impl StreamCounters {
    /// The counts since `before` (the board's counters wrap at 2^32).
    pub fn since(&self, before: &StreamCounters) -> StreamCounters {
        let d = |a: u64, b: u64| a.wrapping_sub(b) & 0xFFFF_FFFF;
        StreamCounters {
            frames: d(self.frames, before.frames),
            applied: d(self.applied, before.applied),
            damaged: d(self.damaged, before.damaged),
            clamped: d(self.clamped, before.clamped),
            refused: d(self.refused, before.refused),
        }
    }
}

/// The settings a `config` reply lists, or the reply line that cannot be read.
pub fn settings_from_config(reply: &Reply) -> Result<Settings, String> {
    let mut settings = Settings::default();
    let mut set = |name: &str, value: &str, line: &str| -> Result<(), String> {
        let id = SettingId::parse(name).ok_or_else(|| line.to_string())?;
        if id.is_link() {
            return Ok(());
        }
        let value = id.parse_value(value).map_err(|_| line.to_string())?;
        settings = settings.with(id, value);
        Ok(())
    };
    for line in &reply.data {
        let Some((name, value)) = line.strip_prefix("# ").and_then(|l| l.split_once(": ")) else {
            return Err(line.clone());
        };
        if name == "saved" {
            continue;
        }
        if name.starts_with("servo") && value.contains('=') {
            for field in value.split_whitespace() {
                let (param, value) = field.split_once('=').ok_or_else(|| line.clone())?;
                set(&format!("{name}.{param}"), value, line)?;
            }
        } else {
            set(name, value, line)?;
        }
    }
    settings.validate().map_err(|_| reply.data.join(" / "))?;
    Ok(settings)
}

/// Asks the board for `config` and reads it.
pub fn read_settings(link: &mut Link) -> Result<Settings, crate::error::Error> {
    let reply = link.request_ok("config")?;
    settings_from_config(&reply).map_err(|line| link.unreadable("config", &line))
}

/// `status`'s stream counters.
pub fn stream_counters(reply: &Reply) -> Option<StreamCounters> {
    let text = reply.value("stream")?;
    let mut counters = StreamCounters::default();
    for field in text.split_whitespace() {
        let (name, value) = field.split_once('=')?;
        let value: u64 = value.parse().ok()?;
        match name {
            "frames" => counters.frames = value,
            "applied" => counters.applied = value,
            "damaged" => counters.damaged = value,
            "clamped" => counters.clamped = value,
            "refused" => counters.refused = value,
            _ => {}
        }
    }
    Some(counters)
}

/// Six numbers of a data line (`# pulse_us: ...`, `# arm_deg: ...`).
pub fn six(reply: &Reply, key: &str) -> Option<[f32; LEGS]> {
    let values: Vec<f32> = reply
        .value(key)?
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .ok()?;
    values.try_into().ok()
}

/// Asks the board for `status` and reads its stream counters.
pub fn read_counters(link: &mut Link) -> Result<StreamCounters, crate::error::Error> {
    let reply = link.request_ok("status")?;
    stream_counters(&reply).ok_or_else(|| link.unreadable("status", &reply.data.join(" / ")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use control::report::{Listing, Saved};
    use control::settings::LinkSettings;

    /// `config` as the firmware's own writer lists it.
    fn config_reply(settings: &Settings) -> Reply {
        let mut text = String::new();
        Listing::Config(LinkSettings::default(), Saved::Differs).write(
            settings,
            &settings.validate().unwrap(),
            &mut text,
        );
        Reply {
            data: text.lines().map(str::to_string).collect(),
            notices: vec![],
            last: "ok".into(),
            at: std::time::Instant::now(),
        }
    }

    #[test]
    fn config_reads_back_as_the_settings_it_lists() {
        // `config` lists the rate with 3 decimals: rates with 3 decimals read back exactly.
        let file = crate::build_file::parse(
            "t",
            "servos.rate_us_rad = 509.296\nframe_hz = 200\nspeed_deg_s = \"off\"\npower_pin = 9\n\
             [servo5]\ntrim_us = 1520\ndir = \"normal\"\n[stream]\nyaw_deg = -30\n\
             axis2 = \"none\"\n",
        )
        .unwrap();
        assert_eq!(
            settings_from_config(&config_reply(&file.settings)),
            Ok(file.settings)
        );
    }

    #[test]
    fn unreadable_config_lines_are_named() {
        let mut reply = config_reply(&Settings::default());
        reply.data[3] = "# colour: red".into();
        assert_eq!(settings_from_config(&reply), Err("# colour: red".into()));
    }

    #[test]
    fn status_counters_and_pulses_are_read() {
        let reply = Reply {
            data: vec![
                "# state: idle".into(),
                "# pulse_us: 1500.00 1499.50 1500.00 1500.00 1500.00 1510.25".into(),
                "# stream: frames=12 applied=10 damaged=1 clamped=2 refused=0".into(),
            ],
            notices: vec![],
            last: "ok".into(),
            at: std::time::Instant::now(),
        };
        let c = stream_counters(&reply).unwrap();
        assert_eq!((c.frames, c.applied, c.damaged, c.clamped), (12, 10, 1, 2));
        assert_eq!(six(&reply, "pulse_us").unwrap()[5], 1510.25);
        let later = StreamCounters { frames: 2, ..c };
        assert_eq!(
            later
                .since(&StreamCounters {
                    frames: 0xFFFF_FFFF,
                    ..c
                })
                .frames,
            3
        );
    }
}
