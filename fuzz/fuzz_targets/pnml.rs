//! `cargo +nightly fuzz run pnml`: arbitrary bytes through [`gspn_fuzz::pnml`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| gspn_fuzz::pnml(data));
