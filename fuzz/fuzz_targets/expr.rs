//! `cargo +nightly fuzz run expr`: arbitrary bytes through [`gspn_fuzz::expr`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| gspn_fuzz::expr(data));
