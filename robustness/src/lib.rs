//! Robustness checks for the firmware's input side, shared by the coverage-guided fuzz targets
//! (`fuzz/`, libFuzzer) and by `cargo test` (property tests and a replay of the committed seed
//! corpus, so every seed and every fixed crash stays a regression test on stable Rust).
//!
//! - [`line_model`]: an independent model of the documented line protocol (where lines end,
//!   which get a reply, which are refused and why), written from `control`'s documentation.
//! - [`checked`]: [`checked::Checked`], a [`control::Controller`] that checks the firmware's
//!   guarantees after every byte, line and frame, and panics with a message when one breaks.
//! - [`ops`]: structure-aware inputs ([`arbitrary::Arbitrary`]): real commands with good and
//!   hostile numbers, raw bytes, frames and receive-queue losses, interleaved.
//! - [`targets`]: one function per fuzz target; each takes the fuzzer's bytes.
//!
//! Invariants checked (the reliability guarantees):
//! 1. no panic, whatever the input;
//! 2. every completed non-blank line (and every refused line) gets exactly one final reply
//!    (`ok` / `error:<code> ...`), blank lines none, and nothing else ever looks like one;
//! 3. the pulses of every frame are finite and inside each servo's configured limits;
//! 4. a rejected command changes nothing (settings, target, pose, motion, generation);
//! 5. the settings always validate; decoded settings always validate and re-encode to the
//!    same bytes;
//! 6. output is printable ASCII plus CR, LF, backspace and bell.

pub mod checked;
pub mod line_model;
pub mod ops;
pub mod targets;
