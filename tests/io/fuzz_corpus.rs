//! Every input the fuzzers were seeded with or found (`fuzz/corpus/<target>/`) and every past
//! crash (`fuzz/artifacts/<target>/`, kept as regression inputs) goes through the same
//! reader as its fuzz target, on the stable toolchain: none may panic.

use std::path::{Path, PathBuf};

#[allow(dead_code, unreachable_pub)]
#[path = "../../fuzz/src/lib.rs"]
mod targets;

fn files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut v: Vec<PathBuf> = entries
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    v.sort();
    v
}

#[test]
fn every_corpus_input_and_past_crash_is_read_without_a_panic() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    let mut replayed = Vec::new();
    for &(name, read) in targets::TARGETS {
        let mut inputs = files(&root.join("corpus").join(name));
        let seeds = inputs.len();
        inputs.extend(files(&root.join("artifacts").join(name)));
        for input in &inputs {
            let bytes = std::fs::read(input).unwrap();
            let outcome = std::panic::catch_unwind(|| read(&bytes));
            assert!(outcome.is_ok(), "{name} panicked on {}", input.display());
        }
        replayed.push((name, seeds, inputs.len() - seeds));
    }
    // Every target has a corpus to replay: an empty directory would make this test vacuous.
    for (name, seeds, _) in &replayed {
        assert!(*seeds > 0, "fuzz/corpus/{name} is empty (run fuzz/seed.sh)");
    }
}
