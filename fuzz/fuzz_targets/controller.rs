//! Fuzz target `controller`: see `robustness::targets::controller` for what it feeds and checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| robustness::targets::controller(data));
