//! `cargo +nightly fuzz run predicate`: arbitrary bytes through [`gspn_fuzz::predicate`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| gspn_fuzz::predicate(data));
