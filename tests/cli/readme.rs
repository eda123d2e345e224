//! The README's two set-up commands stay in sync with CI and with the repository.

use std::path::Path;

fn read(rel: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The first command in the ```sh block that follows `marker`.
fn command_after(readme: &str, marker: &str) -> String {
    let rest = &readme[readme.find(marker).expect("marker present") + marker.len()..];
    let block = &rest[rest.find("```sh\n").expect("sh block") + 6..];
    block.lines().next().expect("a command").trim().to_string()
}

#[test]
fn ci_runs_the_readme_test_command() {
    let readme = read("README.md");
    let test_cmd = command_after(&readme, "Run the tests:");
    assert_eq!(test_cmd, "cargo test --all-features");
    let ci = read(".ci/run");
    assert!(
        ci.lines().any(|l| l.trim() == test_cmd),
        ".ci/run must run `{test_cmd}`"
    );
}

#[test]
fn the_main_command_names_an_existing_plan() {
    let readme = read("README.md");
    let main_cmd = command_after(&readme, "Run the example plan");
    let plan = main_cmd
        .split_whitespace()
        .find(|w| w.ends_with(".toml"))
        .expect("the main command runs a plan");
    assert!(plan.starts_with("plans/"), "{plan}");
    assert!(
        Path::new(env!("CARGO_MANIFEST_DIR")).join(plan).is_file(),
        "{plan} is missing"
    );
    let ci = read(".ci/run");
    assert!(
        ci.contains(plan),
        ".ci/run must run the main command's plan {plan}"
    );
}
