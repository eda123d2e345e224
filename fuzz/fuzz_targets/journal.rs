//! `cargo +nightly fuzz run journal`: arbitrary bytes through [`gspn_fuzz::journal`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| gspn_fuzz::journal(data));
