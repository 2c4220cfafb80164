//! Fuzz target `command`: see `robustness::targets::command` for what it feeds and checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| robustness::targets::command(data));
