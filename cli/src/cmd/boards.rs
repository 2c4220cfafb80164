//! `hexapod boards`: the serial ports present, the boards first with their ids (`crate::boards`).

use clap::Args;

use crate::boards::{self, Found};
use crate::error::Error;

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {}

impl Cmd {
    /// The list, a port a line, as the summary.
    pub fn run(self) -> Result<String, Error> {
        Ok(listing(&boards::present()))
    }
}

/// The ports, a line each, and what to do with them.
fn listing(found: &[Found]) -> String {
    if found.is_empty() {
        return NONE.to_string();
    }
    let mut out: Vec<String> = found.iter().map(Found::to_string).collect();
    out.push(if found.iter().any(Found::is_board) {
        USE.to_string()
    } else {
        NO_BOARD.to_string()
    });
    out.join("\n")
}

/// No port at all.
const NONE: &str = "no serial ports found: is the board plugged in (a data cable, not a \
                    charging-only one)? For the emulated board, `./dev run --pty` prints the port";
/// After a list with a board.
const USE: &str = "give a board's port as --port (on Linux /dev/serial/by-id/ names each board \
                   by its id too; the id is in the board's banner)";
/// After a list without one.
const NO_BOARD: &str = "no hexapod-fw board on USB: a board's UART0 through a USB-serial adapter \
                        is one of the other ports; for the emulated board, `./dev run --pty` \
                        prints the port";

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boards::Kind;

    #[test]
    fn the_listing_ends_with_what_to_do() {
        assert_eq!(listing(&[]), NONE);
        let other = Found {
            port: "/dev/ttyS0".into(),
            kind: Kind::Other,
        };
        assert!(listing(std::slice::from_ref(&other)).ends_with(NO_BOARD));
        let board = Found {
            port: "/dev/ttyACM0".into(),
            kind: Kind::Board {
                serial: Some("E660C0D1C7AB2F28".into()),
            },
        };
        let both = listing(&[board, other]);
        assert!(both.starts_with("/dev/ttyACM0: a hexapod-fw board, id E660C0D1C7AB2F28\n"));
        assert!(both.ends_with(USE), "{both}");
    }
}
