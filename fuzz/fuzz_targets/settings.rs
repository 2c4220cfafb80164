//! Fuzz target `settings`: see `robustness::targets::settings` for what it feeds and checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| robustness::targets::settings(data));
