//! Telemetry from a flight simulator over UDP: one text line per sample, ten comma-separated
//! decimal numbers (spaces around them allowed, several lines in one datagram allowed):
//!
//! ```text
//! time_s, ax, ay, az, p, q, r, phi, theta, psi
//! ```
//!
//! - `time_s`: the simulation's time, s (it gives the washout its time step);
//! - `ax ay az`: the specific force at the pilot's head in the aircraft's body axes (x forward,
//!   y right, z down), ft/s^2: about `0, 0, -32.17` standing still;
//! - `p q r`: the body angular rates, rad/s;
//! - `phi theta psi`: roll, pitch and heading, rad (recorded, not used by the washout).
//!
//! It is what JSBSim's socket output sends with `cli/sim/jsbsim-output.xml` (JSBSim starts each
//! run with a `<LABELS>` line naming the fields, taken here and recorded) and FlightGear's
//! generic protocol with `cli/sim/flightgear-hexapod.xml`; any other simulator is bridged by a
//! few lines of script writing the same line.
//!
//! Bad telemetry never reaches the washout: a line that is not ten finite numbers, or with a
//! value no aircraft reaches (beyond 30 g, 30 rad/s), is dropped and counted by kind.

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, SyncSender, TrySendError};
use std::sync::Arc;
use std::thread;
use std::time::{Duration, Instant};

use super::washout::Motion;

/// Fields in a line.
pub const FIELDS: usize = 10;
/// The fields' names, in order (as the documentation and the record name them).
pub const NAMES: [&str; FIELDS] = [
    "time_s", "ax", "ay", "az", "p", "q", "r", "phi", "theta", "psi",
];
/// Feet to metres.
pub const FT: f64 = 0.3048;
/// The largest specific force taken, ft/s^2 (30 g).
pub const MAX_FORCE_FT_S2: f64 = 30.0 * 32.174;
/// The largest angular rate taken, rad/s.
pub const MAX_RATE_RAD_S: f64 = 30.0;
/// The largest attitude angle taken, rad (headings may run to 2 pi, or a little past).
pub const MAX_ANGLE_RAD: f64 = 4.0 * std::f64::consts::PI;
/// Datagrams waiting for the cueing loop; more are dropped (and counted).
pub const QUEUE: usize = 4096;
/// How long a read on the socket blocks before the reader checks it is still wanted.
const READ_POLL: Duration = Duration::from_millis(50);

/// One sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Simulation time, s.
    pub time_s: f64,
    /// Specific force (m/s^2) and rates (rad/s), body axes.
    pub motion: Motion,
    /// Roll, pitch, heading, rad.
    pub attitude: [f64; 3],
}

/// Why a line was dropped (worded with the tool's errors).
pub use crate::error::BadLine as Bad;

/// What one line is.
#[derive(Debug, Clone, PartialEq)]
pub enum Line {
    /// A sample.
    Sample(Sample),
    /// JSBSim's `<LABELS>` line: the field names it sends.
    Labels(Vec<String>),
    /// Dropped: why, and which field (from 0) if one is at fault.
    Bad(Bad, Option<usize>),
}

/// Reads one line (without its line end).
pub fn parse_line(line: &str) -> Line {
    let line = line.trim();
    if let Some(rest) = line.strip_prefix("<LABELS>") {
        return Line::Labels(
            rest.split(',')
                .map(str::trim)
                .filter(|f| !f.is_empty())
                .map(str::to_string)
                .collect(),
        );
    }
    let fields: Vec<&str> = line.split(',').map(str::trim).collect();
    if fields.len() != FIELDS {
        return Line::Bad(Bad::FieldCount, None);
    }
    let mut v = [0.0f64; FIELDS];
    for (i, (slot, field)) in v.iter_mut().zip(&fields).enumerate() {
        let Ok(x) = field.parse::<f64>() else {
            return Line::Bad(Bad::NotANumber, Some(i));
        };
        if !x.is_finite() {
            return Line::Bad(Bad::NotFinite, Some(i));
        }
        let max = match i {
            0 => f64::MAX,
            1..=3 => MAX_FORCE_FT_S2,
            4..=6 => MAX_RATE_RAD_S,
            _ => MAX_ANGLE_RAD,
        };
        if x.abs() > max {
            return Line::Bad(Bad::OutOfRange, Some(i));
        }
        *slot = x;
    }
    Line::Sample(Sample {
        time_s: v[0],
        motion: Motion {
            force: [v[1] * FT, v[2] * FT, v[3] * FT],
            rates: [v[4], v[5], v[6]],
        },
        attitude: [v[7], v[8], v[9]],
    })
}

/// Reads a datagram: its lines (blank ones skipped).
pub fn parse_datagram(bytes: &[u8]) -> Vec<Line> {
    match std::str::from_utf8(bytes) {
        Ok(text) => text
            .split(['\n', '\r'])
            .filter(|l| !l.trim().is_empty())
            .map(parse_line)
            .collect(),
        Err(_) => vec![Line::Bad(Bad::NotText, None)],
    }
}

/// A datagram received: when, and its lines.
#[derive(Debug, Clone)]
pub struct Datagram {
    /// When `recv` returned it.
    pub at: Instant,
    /// Its lines.
    pub lines: Vec<Line>,
}

/// A UDP socket listening for telemetry, read by a thread of its own.
pub struct Listener {
    /// Where it listens.
    pub address: SocketAddr,
    datagrams: Receiver<Datagram>,
    /// Datagrams dropped because the cueing loop had not taken the ones before (a storm).
    overflowed: Arc<AtomicU64>,
    /// Cleared when dropped: the thread ends.
    wanted: Arc<AtomicU64>,
}

impl Listener {
    /// Binds `address` (e.g. `127.0.0.1:5139`, or `0.0.0.0:5139` for another machine's).
    pub fn bind(address: &str) -> std::io::Result<Listener> {
        let socket = UdpSocket::bind(address)?;
        socket.set_read_timeout(Some(READ_POLL))?;
        let address = socket.local_addr()?;
        let (sender, datagrams) = mpsc::sync_channel(QUEUE);
        let overflowed = Arc::new(AtomicU64::new(0));
        let wanted = Arc::new(AtomicU64::new(1));
        let (o, w) = (Arc::clone(&overflowed), Arc::clone(&wanted));
        thread::spawn(move || read(socket, sender, o, w));
        Ok(Listener {
            address,
            datagrams,
            overflowed,
            wanted,
        })
    }

    /// The next datagram before `until`, if one comes.
    pub fn next(&self, until: Instant) -> Option<Datagram> {
        let wait = until.saturating_duration_since(Instant::now());
        self.datagrams.recv_timeout(wait).ok()
    }

    /// Datagrams dropped so far because the queue was full.
    pub fn overflowed(&self) -> u64 {
        self.overflowed.load(Ordering::Relaxed)
    }
}

impl Drop for Listener {
    fn drop(&mut self) {
        self.wanted.store(0, Ordering::Relaxed);
    }
}

fn read(
    socket: UdpSocket,
    sender: SyncSender<Datagram>,
    overflowed: Arc<AtomicU64>,
    wanted: Arc<AtomicU64>,
) {
    let mut buffer = vec![0u8; 65536];
    while wanted.load(Ordering::Relaxed) != 0 {
        let n = match socket.recv(&mut buffer) {
            Ok(n) => n,
            // Time-outs (to look at `wanted`) and errors a peer's ICMP can cause: go on.
            Err(_) => continue,
        };
        let datagram = Datagram {
            at: Instant::now(),
            lines: parse_datagram(&buffer[..n]),
        };
        match sender.try_send(datagram) {
            Ok(()) => {}
            Err(TrySendError::Full(_)) => {
                overflowed.fetch_add(1, Ordering::Relaxed);
            }
            Err(TrySendError::Disconnected(_)) => return,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_jsbsim_line_is_a_sample_in_si_units() {
        // As JSBSim 1.3.3 sends it (padded fields).
        let line = "    0.049998,   0.1825977,-4.416776e-08,   -32.16402,6.269609e-11,\
                    -0.0001136744,5.738519e-11,8.160825e-12, 0.005268709,    5.759587";
        let Line::Sample(s) = parse_line(line) else {
            panic!("{:?}", parse_line(line));
        };
        assert_eq!(s.time_s, 0.049998);
        assert!((s.motion.force[2] - (-32.16402 * 0.3048)).abs() < 1e-12);
        assert!((s.motion.force[2] + 9.8036).abs() < 1e-3);
        assert_eq!(s.motion.rates[1], -0.0001136744);
        assert_eq!(s.attitude[2], 5.759587);
    }

    #[test]
    fn the_labels_line_is_recognised() {
        assert_eq!(
            parse_line("<LABELS> ,Time,a-pilot-x-ft sec2,p-rad sec"),
            Line::Labels(vec![
                "Time".into(),
                "a-pilot-x-ft sec2".into(),
                "p-rad sec".into()
            ])
        );
    }

    #[test]
    fn garbage_nan_and_missing_fields_are_dropped_by_kind() {
        let ok = "1,0,0,-32.17,0,0,0,0,0,0";
        assert!(matches!(parse_line(ok), Line::Sample(_)));
        assert_eq!(
            parse_line("1,0,0,-32.17,0,0,0,0,0"),
            Line::Bad(Bad::FieldCount, None)
        );
        assert_eq!(
            parse_line("1,0,0,-32.17,0,0,0,0,0,0,0"),
            Line::Bad(Bad::FieldCount, None)
        );
        assert_eq!(parse_line(""), Line::Bad(Bad::FieldCount, None));
        assert_eq!(
            parse_line("1,0,,-32.17,0,0,0,0,0,0"),
            Line::Bad(Bad::NotANumber, Some(2))
        );
        assert_eq!(
            parse_line("1,0,0,-32.17,NaN,0,0,0,0,0"),
            Line::Bad(Bad::NotFinite, Some(4))
        );
        assert_eq!(
            parse_line("1,0,0,-32.17,0,inf,0,0,0,0"),
            Line::Bad(Bad::NotFinite, Some(5))
        );
        assert_eq!(
            parse_line("1,0,0,-32.17,0,0,0,0,0,1e300"),
            Line::Bad(Bad::OutOfRange, Some(9))
        );
        assert_eq!(
            parse_line("1,2000,0,-32.17,0,0,0,0,0,0"),
            Line::Bad(Bad::OutOfRange, Some(1))
        );
        assert_eq!(
            parse_datagram(&[0xff, 0xfe, b'1']),
            vec![Line::Bad(Bad::NotText, None)]
        );
        // Two lines in one datagram, CR LF and blank lines between.
        let lines = parse_datagram(b"1,0,0,-32,0,0,0,0,0,0\r\n\r\n2,0,0,-32,0,0,0,0,0,0\n");
        assert_eq!(lines.len(), 2);
        assert!(lines.iter().all(|l| matches!(l, Line::Sample(_))));
    }

    #[test]
    fn datagrams_arrive_through_the_socket_in_order() {
        let listener = Listener::bind("127.0.0.1:0").unwrap();
        let sender = UdpSocket::bind("127.0.0.1:0").unwrap();
        sender
            .send_to(b"1,0,0,-32.17,0,0,0,0,0,0", listener.address)
            .unwrap();
        sender.send_to(b"garbage", listener.address).unwrap();
        let until = Instant::now() + Duration::from_secs(5);
        let first = listener.next(until).unwrap();
        assert!(matches!(first.lines[..], [Line::Sample(_)]));
        let second = listener.next(until).unwrap();
        assert_eq!(second.lines, vec![Line::Bad(Bad::FieldCount, None)]);
        assert!(listener
            .next(Instant::now() + Duration::from_millis(50))
            .is_none());
    }
}
