//! `cargo +nightly fuzz run pnpro`: arbitrary bytes through [`gspn_fuzz::pnpro`].
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| gspn_fuzz::pnpro(data));
