//! Where the shared fixtures are, for benchmarks and benchmark programs: `$GSPN_FIXTURES`
//! when set, else `../shared/fixtures` relative to the crate (the layout CI uses).

#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The fixtures directory.
pub fn root() -> PathBuf {
    match std::env::var_os("GSPN_FIXTURES") {
        Some(dir) => PathBuf::from(dir),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/fixtures"),
    }
}

/// A fixture by its path under the fixtures directory.
pub fn fixture(rel: &str) -> PathBuf {
    root().join(rel)
}
