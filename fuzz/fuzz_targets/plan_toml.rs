//! `cargo +nightly fuzz run plan_toml`: arbitrary bytes through [`gspn_fuzz::plan_toml`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| gspn_fuzz::plan_toml(data));
