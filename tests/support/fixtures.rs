//! Where the shared fixtures are: `$GSPN_FIXTURES` when set, else `../shared/fixtures`
//! relative to the crate (CI: a clone with `shared/` beside it).

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
    let p = root().join(rel);
    assert!(p.exists(), "fixture {} not found", p.display());
    p
}

/// Every file under `rel` (recursively) whose name ends with one of `exts`, sorted.
pub fn files_under(rel: &str, exts: &[&str]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![fixture(rel)];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("readable fixture dir") {
            let p = e.expect("dir entry").path();
            if p.is_dir() {
                stack.push(p);
            } else if let Some(name) = p.file_name().and_then(|n| n.to_str())
                && exts.iter().any(|x| name.ends_with(x))
            {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// A file under this crate's `tests/data/`.
pub fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(rel)
}
