//! Behaviour tests of the `io` layer: one test binary, one module per behaviour.

#[path = "../support/mod.rs"]
mod support;

mod bad_input;
mod convert_pnpro;
mod deep_nesting;
mod fuzz_corpus;
mod pipe;
mod pnml;
mod pnpro;
mod roundtrip_pnpro;
mod roundtrip_xml;
