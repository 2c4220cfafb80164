//! A burst of UART receive errors (a sender at the wrong baud rate garbles every few bytes;
//! line noise): the first loss of a burst is announced at once, the others only counted, and
//! when the burst ends ([`BURST_QUIET_US`] without a loss), or every [`BURST_REPORT_US`] while
//! it goes on, one notice gives their count. Time is counted in servo frames. Knows nothing of
//! the controller (`controller/notices.rs` keeps one and shows its notices).

use crate::report::Notice;

/// A burst ends after this long without a UART receive error, us.
pub const BURST_QUIET_US: u32 = 200_000;
/// A burst that goes on is reported this often, us.
pub const BURST_REPORT_US: u32 = 2_000_000;

/// A burst of UART receive errors: the losses since its first (announced) one.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct LossBurst {
    /// Losses not announced yet.
    losses: u32,
    /// Bytes they lost, at least.
    bytes: u32,
    /// Time since the last loss, us (counted in servo frames).
    quiet_us: u32,
    /// Time since the burst began or was last reported, us.
    age_us: u32,
}

impl LossBurst {
    /// A UART loss of `at_least` bytes: counted (true) if a burst is going on, else the start
    /// of one (false: announce it).
    pub(super) fn count(burst: &mut Option<LossBurst>, at_least: u32) -> bool {
        match burst.as_mut() {
            Some(burst) => {
                burst.losses = burst.losses.saturating_add(1);
                burst.bytes = burst.bytes.saturating_add(at_least);
                burst.quiet_us = 0;
                true
            }
            None => {
                *burst = Some(LossBurst::default());
                false
            }
        }
    }

    /// A servo frame of `frame_us` passed: a burst that has ended (or gone on for
    /// [`BURST_REPORT_US`]) gives its notice, if it lost more than its first announced loss.
    pub(super) fn tick(burst: &mut Option<LossBurst>, frame_us: u32) -> Option<Notice> {
        let mut b = (*burst)?;
        b.quiet_us = b.quiet_us.saturating_add(frame_us);
        b.age_us = b.age_us.saturating_add(frame_us);
        let ended = b.quiet_us >= BURST_QUIET_US;
        if !ended && b.age_us < BURST_REPORT_US {
            *burst = Some(b);
            return None;
        }
        *burst = (!ended).then(|| LossBurst {
            quiet_us: b.quiet_us,
            ..LossBurst::default()
        });
        (b.losses > 0).then(|| Notice::InputLostBurst {
            losses: b.losses,
            at_least: b.bytes,
            over_s: b.age_us.saturating_sub(if ended { b.quiet_us } else { 0 }) as f32 / 1e6,
        })
    }
}
