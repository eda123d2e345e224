//! `cargo +nightly fuzz run thesis_json`: arbitrary bytes through [`gspn_fuzz::thesis_json`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| gspn_fuzz::thesis_json(data));
