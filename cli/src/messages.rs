//! How the tool writes, not what: a subcommand's summary on standard output, its error on
//! standard error after `hexapod: ` (with the exit status), and a board's reply as the board
//! wrote it. The words are their owners': each subcommand's in its `cmd/` file, the errors' on
//! [`Error`]'s variants, the board's from the board (or `control::report`).

use std::io::Write;
use std::process::ExitCode;

use crate::error::Error;
use crate::link::Reply;

/// Writes a summary on standard output (nothing for an empty one).
pub fn summary(text: &str) {
    if !text.is_empty() {
        println!("{text}");
    }
}

/// Writes a subcommand's outcome, its summary or its error, and gives the exit status.
pub fn finish(outcome: Result<String, Error>) -> ExitCode {
    match outcome {
        Ok(text) => {
            summary(&text);
            ExitCode::SUCCESS
        }
        Err(why) => {
            eprintln!("hexapod: {why}");
            ExitCode::FAILURE
        }
    }
}

/// Writes a reply's lines as the board wrote them: notices, data, then the final reply.
pub fn reply(out: &mut impl Write, reply: &Reply) {
    for line in reply.notices.iter().chain(&reply.data) {
        let _ = writeln!(out, "{line}");
    }
    let _ = writeln!(out, "{}", reply.last);
}
