//! The board's side of `hexapod view`: one thread owns the serial link and follows the board
//! with `pulses` (see the module above for the wire's arithmetic), the page's jobs between two
//! queries, the listings asked at the start and after a line that may change them.

use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use super::json;
use super::pages::{lock, Job, Pages};
use crate::error::Error;
use crate::link::{Link, Reply};

/// Most updates a second the view asks for (a page draws at most about 60 frames a second).
pub const MAX_RATE_HZ: f64 = 60.0;

/// The rule of which listings a command line can change, shared with `./dev run`'s view server
/// (`emulator/src/view-server/listing-changes.js` reads the same file): a rule a line, the
/// line's first words (`*` at a word's end: any word that starts so), `->`, the listings.
const LISTING_CHANGES: &str = include_str!("../../../emulator/src/view-server/listing-changes.txt");

/// A line's words as the board reads them: split at spaces, tabs and commas.
fn words(line: &str) -> impl Iterator<Item = &str> {
    line.split([' ', '\t', ',']).filter(|w| !w.is_empty())
}

/// Which listings a line may change (so they are asked again), by the first rule of
/// `LISTING_CHANGES` whose words begin the line (compared without case): `defaults`, a `set`
/// of a geometry, servo or pivot setting; anything else changes neither.
pub fn listings_changed_by(line: &str) -> Vec<&'static str> {
    let lower = line.trim().to_ascii_lowercase();
    let said: Vec<&str> = words(&lower).collect();
    let matches = |pattern: &str, word: &str| match pattern.strip_suffix('*') {
        Some(start) => word.starts_with(start),
        None => word == pattern,
    };
    LISTING_CHANGES
        .lines()
        .filter(|rule| !rule.trim().is_empty() && !rule.starts_with('#'))
        .filter_map(|rule| rule.split_once("->"))
        .find(|(pattern, _)| {
            let pattern: Vec<&str> = words(pattern).collect();
            pattern.len() <= said.len()
                && pattern
                    .iter()
                    .zip(&said)
                    .all(|(p, w)| matches(&p.to_ascii_lowercase(), w))
        })
        .map(|(_, listings)| words(listings).collect())
        .unwrap_or_default()
}

/// The six widths of a `pulses` reply (`# pulse_us: 1500.00 ...`), or `None`.
pub fn pulse_widths(reply: &Reply) -> Option<[f32; 6]> {
    let text = reply.value("pulse_us")?;
    let values: Vec<f32> = text
        .split(' ')
        .map(str::parse)
        .collect::<Result<_, _>>()
        .ok()?;
    values.try_into().ok()
}

/// The board's side: follows it until the link fails; then tells the pages why.
pub fn follow(mut link: Link, jobs: Receiver<Job>, pages: Arc<Mutex<Pages>>) -> Error {
    let error = match follow_until_error(&mut link, &jobs, &pages) {
        Ok(never) => match never {},
        Err(error) => error,
    };
    lock(&pages).stop(&error.to_string());
    error
}

enum Never {}

fn follow_until_error(
    link: &mut Link,
    jobs: &Receiver<Job>,
    pages: &Mutex<Pages>,
) -> Result<Never, Error> {
    link.start()?;
    ask_listings(link, pages, &["geometry", "config"])?;
    let started = Instant::now();
    let period = Duration::from_secs_f64(1.0 / MAX_RATE_HZ);
    // Updates counted over the last second, for the rate the page shows.
    let mut recent: Vec<Instant> = Vec::new();
    loop {
        let began = Instant::now();
        while let Ok(job) = jobs.try_recv() {
            run_job(link, pages, job)?;
        }
        let reply = link.request("pulses")?;
        show_notices(pages, &reply);
        let Some(widths) = pulse_widths(&reply) else {
            return Err(link.unreadable("pulses", &reply.last));
        };
        let now = Instant::now();
        recent.retain(|t| now.duration_since(*t) < Duration::from_secs(1));
        recent.push(now);
        let rate =
            (recent.len() - 1) as f64 / now.duration_since(recent[0]).as_secs_f64().max(1e-3);
        let rate = if recent.len() < 2 {
            0.0
        } else {
            rate.min(MAX_RATE_HZ * 1.5)
        };
        lock(pages).pins(started, &widths, rate);
        // Paced: at most MAX_RATE_HZ; a job that comes meanwhile goes at once.
        let rest = period.saturating_sub(began.elapsed());
        if let Ok(job) = jobs.recv_timeout(rest) {
            run_job(link, pages, job)?;
        }
    }
}

fn ask_listings(link: &mut Link, pages: &Mutex<Pages>, which: &[&str]) -> Result<(), Error> {
    for kind in which {
        let reply = link.request(kind)?;
        show_notices(pages, &reply);
        lock(pages).listing(kind, &reply);
    }
    Ok(())
}

/// Notices the board sent meanwhile (a fault, lost input) belong in the terminal.
fn show_notices(pages: &Mutex<Pages>, reply: &Reply) {
    if !reply.notices.is_empty() {
        let text: String = reply.notices.iter().map(|n| format!("{n}\r\n")).collect();
        lock(pages).terminal(&text);
    }
}

fn run_job(link: &mut Link, pages: &Mutex<Pages>, job: Job) -> Result<(), Error> {
    let line = match &job {
        Job::Typed(line) | Job::Command(line, _) => line.clone(),
    };
    let reply = link.request(&line)?;
    match job {
        Job::Typed(_) => {
            // As a terminal with echo on would show it: the line, its reply, a prompt.
            let mut text = format!("{line}\r\n");
            for l in reply.notices.iter().chain(&reply.data) {
                text.push_str(l);
                text.push_str("\r\n");
            }
            text.push_str(&reply.last);
            text.push_str("\r\n> ");
            lock(pages).terminal(&text);
        }
        Job::Command(_, answer) => {
            show_notices(pages, &reply);
            let _ = answer.send(reply);
        }
    }
    ask_listings(link, pages, &listings_changed_by(&line))
}

/// Starts following the board on `link` in a thread of its own; returns the jobs' sender, the
/// pages' state and the thread (its result: why the link stopped).
pub fn start(link: Link) -> (Sender<Job>, Arc<Mutex<Pages>>, thread::JoinHandle<Error>) {
    let hello = format!(
        "{{\"link\":\"board\",\"source\":\"board\",\"port\":{},\"frameMs\":{}}}",
        json::string(link.port()),
        1000.0 / MAX_RATE_HZ
    );
    let pages = Arc::new(Mutex::new(Pages {
        hello,
        scrollback: format!("# hexapod view: the board on {}\r\n> ", link.port()),
        ..Pages::default()
    }));
    let (sender, jobs) = mpsc::channel();
    let shared = Arc::clone(&pages);
    let thread = thread::spawn(move || follow(link, jobs, shared));
    (sender, pages, thread)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_listings_a_line_can_change() {
        assert_eq!(listings_changed_by("set rod_mm 130"), ["geometry"]);
        assert_eq!(listings_changed_by("SET base_radius_mm 70"), ["geometry"]);
        assert_eq!(listings_changed_by("set servo3.trim_us 1520"), ["config"]);
        assert_eq!(
            listings_changed_by("set servos.rate_us_rad 600"),
            ["config"]
        );
        assert_eq!(listings_changed_by("defaults"), ["geometry", "config"]);
        assert!(listings_changed_by("set speed_mm_s 10").is_empty());
        assert!(listings_changed_by("pose 0 0 5 0 0 0").is_empty());
        // The pivot is in `config` (the page's kinematics turn about it).
        assert_eq!(listings_changed_by("set pivot_z_mm 100"), ["config"]);
        assert_eq!(
            listings_changed_by("set\tplatform_radius_mm,55"),
            ["geometry"]
        );
        assert!(listings_changed_by("").is_empty());
        assert!(listings_changed_by("set").is_empty());
    }

    #[test]
    fn every_rule_is_words_then_known_listings() {
        let rules: Vec<&str> = LISTING_CHANGES
            .lines()
            .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
            .collect();
        assert!(rules.len() >= 7, "{rules:?}");
        for rule in rules {
            let (pattern, listings) = rule.split_once("->").expect("words -> listings");
            assert!(words(pattern).next().is_some(), "{rule}");
            let listings: Vec<&str> = words(listings).collect();
            assert!(!listings.is_empty(), "{rule}");
            assert!(
                listings.iter().all(|l| ["geometry", "config"].contains(l)),
                "{rule}"
            );
        }
    }

    #[test]
    fn a_pulses_reply_gives_six_widths_and_nothing_else_does() {
        let reply = |data: &str| Reply {
            data: vec![data.to_string()],
            notices: vec![],
            last: "ok".into(),
            at: Instant::now(),
        };
        let widths = pulse_widths(&reply(
            "# pulse_us: 1500.00 1483.74 1493.28 1517.69 1482.31 1506.72",
        ));
        assert_eq!(
            widths,
            Some([1500.0, 1483.74, 1493.28, 1517.69, 1482.31, 1506.72])
        );
        assert_eq!(pulse_widths(&reply("# pulse_us: 1500.00 1500.00")), None);
        assert_eq!(pulse_widths(&reply("# state: idle")), None);
    }
}
