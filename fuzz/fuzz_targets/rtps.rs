//! `cargo +nightly fuzz run rtps`: arbitrary UDP datagrams through [`gspn_fuzz::rtps`], the
//! DDS receive path. Run it in a network namespace of its own (`ip netns exec`): the readers
//! answer HEARTBEATs with ACKNACKs to 127.0.0.1 ports the datagrams name.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| gspn_fuzz::rtps(data));
