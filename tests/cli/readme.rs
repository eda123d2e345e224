//! The README's two set-up commands stay in sync with CI and with the repository: the test
//! command is `./test.sh`, which sets up what the suite needs and ends by running the suite;
//! `.ci/run` runs both commands exactly as written; the tour's journals stay out of the
//! checkout and its live viewer example runs in real time.

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

/// The lines of a shell script that are commands (not comments, not blank).
fn commands(script: &str) -> Vec<&str> {
    script
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .collect()
}

#[test]
fn ci_runs_the_readme_test_command_which_sets_up_and_runs_the_suite() {
    let readme = read("README.md");
    let test_cmd = command_after(&readme, "Run the tests:");
    assert_eq!(test_cmd, "./test.sh");
    // CI runs the test command as its three steps, in order, `cargo test` among them.
    let ci = read(".ci/run");
    let ci_cmds = commands(&ci);
    let steps = [
        "./test.sh --setup",
        "cargo test --all-features",
        "./test.sh --python",
    ];
    let at: Vec<Option<usize>> = steps
        .iter()
        .map(|s| ci_cmds.iter().position(|c| c == s))
        .collect();
    assert!(
        at.iter().all(Option::is_some) && at.windows(2).all(|w| w[0] < w[1]),
        ".ci/run must run {steps:?} in order: {ci_cmds:?}"
    );
    // CI installs nothing itself: the test command does, for a user as for CI.
    assert!(
        !ci.contains("apt-get") && !ci.contains("pip install"),
        "{ci}"
    );
    let script = read("test.sh");
    let run = commands(&script);
    // Without flags: the same three steps — the set-up, the suite (with the arguments, if
    // any), then the Python package's.
    let tail: Vec<&str> = run.iter().rev().take(7).rev().copied().collect();
    assert_eq!(
        tail,
        [
            "setup",
            "echo \"== cargo test --all-features $*\"",
            "cargo test --all-features \"$@\"",
            "if [ \"$#\" -gt 0 ]; then",
            "exit 0",
            "fi",
            "python_tests",
        ],
        "{script}"
    );
    assert!(script.contains("pytest -q python/tests"), "{script}");
    for needed in [
        "chromium",
        "chromium-driver",
        "iproute2",
        "python3-venv",
        "target/venv-ros2",
        "cyclonedds==11.0.1",
        "stormpy==2.0.0",
        "mcap==1.6.0 mcap-ros2-support==0.6.0",
        "eclipse-zenoh==1.10.2",
        "./python pytest matplotlib",
    ] {
        assert!(script.contains(needed), "test.sh must install {needed}");
    }
    let mode = std::fs::metadata(Path::new(env!("CARGO_MANIFEST_DIR")).join("test.sh"))
        .unwrap()
        .permissions();
    assert!(
        std::os::unix::fs::PermissionsExt::mode(&mode) & 0o111 != 0,
        "test.sh is executable"
    );
}

#[test]
fn ci_runs_the_main_command_as_written_on_an_existing_plan() {
    let readme = read("README.md");
    let main_cmd = command_after(&readme, "Run the example plan");
    // The build the README tells a user to make (`--all-features`) is the one it runs.
    assert!(
        main_cmd.starts_with("cargo run --release --all-features -- "),
        "{main_cmd}"
    );
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
        commands(&ci).contains(&main_cmd.as_str()),
        ".ci/run must run `{main_cmd}`"
    );
    // Exactly two set-up commands.
    let setup = &readme[readme.find("## Set up").unwrap()..readme.find("## CLI tour").unwrap()];
    assert_eq!(setup.matches("```sh\n").count(), 2, "{setup}");
}

#[test]
fn the_tour_writes_journals_outside_the_checkout_and_watches_live_runs_in_real_time() {
    let readme = read("README.md");
    let tour = &readme[readme.find("## CLI tour").unwrap()..];
    let tour = &tour[..tour[3..].find("\n## ").map_or(tour.len(), |i| i + 3)];
    for line in commands(tour) {
        let words: Vec<&str> = line.split_whitespace().collect();
        if let Some(i) = words.iter().position(|w| *w == "--journal") {
            let path = words[i + 1];
            assert!(
                path.starts_with("target/") || path.starts_with("/tmp/"),
                "{line}: a journal inside the checkout"
            );
        }
        if words.get(1) == Some(&"run") && words.contains(&"--web") {
            let plan = read(words[2]);
            let virtual_time = plan.contains("time_scale = 0.0");
            assert!(
                !virtual_time || words.contains(&"--time-scale"),
                "{line}: a live viewer of a virtual-time run is over before the page opens"
            );
        }
    }
}

/// Issue 30, snag 9: docs/benchmarks.md was an 800-line log; it starts with one table of
/// current figures, each with its command, machine and date.
#[test]
fn benchmarks_start_with_one_table_of_current_figures() {
    let doc = read("docs/benchmarks.md");
    let first = doc.find("\n## ").expect("a section");
    assert_eq!(&doc[first..first + 20], "\n## Current figures\n");
    let section = &doc[first + 1..];
    let section = &section[..section[3..].find("\n## ").unwrap() + 3];
    let rows: Vec<&str> = section.lines().filter(|l| l.starts_with('|')).collect();
    assert_eq!(rows[0], "| what | figure | command | machine | date |");
    assert!(rows.len() > 10, "{rows:?}");
    for row in &rows[2..] {
        let cells: Vec<&str> = row.trim_matches('|').split(" | ").map(str::trim).collect();
        assert_eq!(cells.len(), 5, "{row}");
        assert!(cells[2].starts_with('`'), "no command: {row}");
        let date = cells[4].as_bytes();
        assert!(
            date.len() == 10 && date[4] == b'-' && date[7] == b'-',
            "no date: {row}"
        );
    }
}
