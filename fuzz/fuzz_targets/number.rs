//! Fuzz target `number`: see `robustness::targets::number` for what it feeds and checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| robustness::targets::number(data));
