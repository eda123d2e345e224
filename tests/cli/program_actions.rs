//! `plan-runner run`: the quickstart spawns agents running built-in actions.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

fn repo(p: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

#[test]
fn the_quickstart_spawns_agents_running_built_in_actions() {
    let out = bin()
        .args([
            "run",
            repo("plans/quickstart.toml").to_str().unwrap(),
            "--json",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["agents_spawned"], 2);
    assert_eq!(summary["stopped"], "max_firings");
    assert_eq!(summary["firings"], 500);
    assert_eq!(
        summary["final_marking"]
            .as_object()
            .unwrap()
            .values()
            .map(|v| v.as_u64().unwrap())
            .sum::<u64>(),
        3
    );
}
