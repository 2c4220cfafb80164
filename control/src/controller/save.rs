//! `save`, a job whose flash I/O is the board's: the controller prepares the record (the A/B
//! choice of sector and the sequence number are [`crate::store`]'s), the board takes it with
//! [`Controller::take_flash_write`](super::Controller::take_flash_write), erases, programs and
//! reads back, and hands the outcome to
//! [`Controller::flash_written`](super::Controller::flash_written); the reply follows in
//! [`Controller::work`](super::Controller::work). The controller knows which settings are saved
//! (for `config`) and never touches the flash.

use crate::store::{SaveError, Write};

/// How far a `save` has got.
#[derive(Debug, Clone)]
pub(super) enum Save {
    /// The write waits for the board to take it.
    Waiting(Write),
    /// The board has taken it and is writing.
    Writing(Write),
    /// The board has written and read it back.
    Written(Write, Result<(), SaveError>),
}

impl Save {
    /// A save of the record `write` holds, waiting for the board.
    pub fn new(write: Write) -> Save {
        Save::Waiting(write)
    }

    /// True while the board's flash write is awaited (taken or not).
    pub fn awaits_flash(&self) -> bool {
        matches!(self, Save::Waiting(_) | Save::Writing(_))
    }

    /// The write for the board, once: then it is being written.
    pub fn take_write(&mut self) -> Option<Write> {
        match *self {
            Save::Waiting(write) => {
                *self = Save::Writing(write);
                Some(write)
            }
            _ => None,
        }
    }

    /// The board's outcome of the write it took (ignored if it took none).
    pub fn written(&mut self, result: Result<(), SaveError>) {
        if let Save::Writing(write) = *self {
            *self = Save::Written(write, result);
        }
    }

    /// A slice: `None` while the board has not written, then the outcome (the write made, to
    /// commit to the store, or why it failed).
    pub fn step(&self) -> Option<Result<Write, SaveError>> {
        match self {
            Save::Written(write, Ok(())) => Some(Ok(*write)),
            Save::Written(_, Err(e)) => Some(Err(*e)),
            Save::Waiting(_) | Save::Writing(_) => None,
        }
    }
}
