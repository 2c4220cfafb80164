//! `hexapod view`: the live 3D view (the page `./dev run` serves, `emulator/view/`) for a board
//! on a cable. One thread owns the serial link and follows the board with its one-line query
//! `pulses` (docs/commands.md), as fast as the link answers and at most [`MAX_RATE_HZ`] times a
//! second; between two queries it sends the lines typed on the page (their replies go to the
//! page's terminal) and the page's own commands (the jog: their replies go back to the page
//! only). The board's `geometry` and `config` listings are asked at the start and after a line
//! that may change them (the rule shared with `./dev run`'s server, a data file both read:
//! `emulator/src/view-server/listing-changes.txt`), and passed to the page as the board wrote them (the page reads them
//! with `board-listings.js`). The query traffic never shows in the page's terminal.
//!
//! The wire, per update: `pulses` and its line end out (7 bytes), `# pulse_us: ` and six widths
//! of 7 characters with spaces, a line end and `ok` and a line end back (63 bytes). At 115,200
//! baud (8N1, 11,520 bytes a second) that is 5.5 ms back and 0.6 ms out, so UART0 can carry
//! about 150 round trips a second (measured in the emulator: 150); USB full speed carries 64
//! bytes a packet, one round trip per 1 ms frame or two. [`MAX_RATE_HZ`] bounds both.
//!
//! Times are wall-clock (`Instant`), rates per second, pulse widths in microseconds.

mod follow;
mod http;
pub mod json;
pub mod pages;

pub use follow::{listings_changed_by, pulse_widths, start, MAX_RATE_HZ};
pub use http::{serve, Assets, Server};
