//! What the view's pages are sent and ask for: the pages connected, each a queue of
//! Server-Sent Events (a page that reads slowly misses pin updates, one that stopped reading is
//! dropped), and what a newcomer gets first (the latest listings and pins, the terminal's
//! scrollback); the [`Job`]s a page gives the board's side. Text is the board's, as it wrote
//! it; widths in microseconds on the wire to the page in nanoseconds, as `./dev run`'s.

use std::sync::mpsc::{self, Receiver, Sender, SyncSender, TrySendError};
use std::sync::Mutex;
use std::time::Instant;

use super::json;
use crate::link::Reply;

/// What the page asks of the board.
pub enum Job {
    /// A line typed in the page's terminal: sent, its reply shown in the terminal.
    Typed(String),
    /// One of the page's own commands (the jog): its reply goes back to the page only.
    Command(String, Sender<Reply>),
}

/// Terminal output kept for a page that connects later, bytes.
const SCROLLBACK_BYTES: usize = 16 * 1024;
/// Events queued for a page that reads slowly; pin updates beyond it are dropped for it.
const CLIENT_QUEUE: usize = 256;

/// The pages connected and what a newcomer is sent first: the latest listings and pins, and
/// the terminal's scrollback.
#[derive(Default)]
pub struct Pages {
    pub(super) clients: Vec<SyncSender<String>>,
    /// `hello`'s data.
    pub(super) hello: String,
    /// The last `listing` event of each kind (geometry, config).
    pub(super) listings: Vec<(String, String)>,
    /// The last `pins` event.
    pub(super) pins: Option<String>,
    pub(super) scrollback: String,
    /// Set when the link stopped (the reason).
    pub(super) stopped: Option<String>,
}

/// One Server-Sent Event.
fn event(name: &str, data: &str) -> String {
    format!("event: {name}\ndata: {data}\n\n")
}

impl Pages {
    /// A new page: what it needs first, then its queue.
    pub fn join(&mut self) -> Receiver<String> {
        let (sender, receiver) = mpsc::sync_channel(CLIENT_QUEUE);
        if let Some(reason) = &self.stopped {
            let _ = sender.try_send(event(
                "stopped",
                &format!("{{\"reason\":{}}}", json::string(reason)),
            ));
            return receiver;
        }
        let mut first = vec![event("hello", &self.hello)];
        first.extend(self.listings.iter().map(|(_, e)| e.clone()));
        first.push(event(
            "uart",
            &format!("{{\"text\":{}}}", json::string(&self.scrollback)),
        ));
        first.extend(self.pins.clone());
        for message in first {
            let _ = sender.try_send(message);
        }
        self.clients.push(sender);
        receiver
    }

    /// Sends an event to every page; a page whose queue is full misses it (`droppable`) or is
    /// dropped (it stopped reading: its connection ends).
    pub(super) fn broadcast(&mut self, message: &str, droppable: bool) {
        self.clients
            .retain(|client| match client.try_send(message.to_string()) {
                Ok(()) => true,
                Err(TrySendError::Full(_)) => droppable,
                Err(TrySendError::Disconnected(_)) => false,
            });
    }

    pub(super) fn terminal(&mut self, text: &str) {
        self.scrollback.push_str(text);
        if self.scrollback.len() > 2 * SCROLLBACK_BYTES {
            let mut cut = self.scrollback.len() - SCROLLBACK_BYTES;
            while !self.scrollback.is_char_boundary(cut) {
                cut += 1;
            }
            self.scrollback.drain(..cut);
        }
        self.broadcast(
            &event("uart", &format!("{{\"text\":{}}}", json::string(text))),
            false,
        );
    }

    pub(super) fn listing(&mut self, kind: &str, reply: &Reply) {
        let mut lines = reply.data.clone();
        lines.push(reply.last.clone());
        let message = event(
            "listing",
            &format!("{{\"lines\":{}}}", json::strings(&lines)),
        );
        self.listings.retain(|(k, _)| k != kind);
        self.listings.push((kind.to_string(), message.clone()));
        self.broadcast(&message, false);
    }

    pub(super) fn pins(&mut self, started: Instant, widths_us: &[f32; 6], rate_hz: f64) {
        let nanos = started.elapsed().as_nanos();
        let widths: Vec<String> = widths_us
            .iter()
            .map(|w| format!("{}", f64::from(*w) * 1e3))
            .collect();
        let data = format!(
            "{{\"nanos\":{nanos},\"widthNs\":[{}],\"periodNs\":[null,null,null,null,null,null],\
             \"live\":[true,true,true,true,true,true],\"rateHz\":{rate_hz:.1}}}",
            widths.join(",")
        );
        let message = event("pins", &data);
        self.pins = Some(message.clone());
        self.broadcast(&message, true);
    }

    pub(super) fn stop(&mut self, reason: &str) {
        self.stopped = Some(reason.to_string());
        let message = event(
            "stopped",
            &format!("{{\"reason\":{}}}", json::string(reason)),
        );
        self.broadcast(&message, false);
        self.clients.clear();
    }
}

/// The pages' state, even after a page's thread panicked holding it.
pub fn lock(pages: &Mutex<Pages>) -> std::sync::MutexGuard<'_, Pages> {
    pages
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}
