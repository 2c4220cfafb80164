//! Fuzz target `stream`: see `robustness::targets::stream` for what it feeds and checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| robustness::targets::stream(data));
