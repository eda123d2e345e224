//! `cargo +nightly fuzz run pipe_xml`: arbitrary bytes through [`gspn_fuzz::pipe_xml`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| gspn_fuzz::pipe_xml(data));
