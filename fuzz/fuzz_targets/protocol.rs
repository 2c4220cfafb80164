//! Fuzz target `protocol`: see `robustness::targets::protocol` for what it feeds and checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| robustness::targets::protocol(data));
