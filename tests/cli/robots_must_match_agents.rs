//! Regression (issue 24, item 4): a plan naming more robots than there are initial agents
//! passed `plan-runner check` and was refused by `run` without a location. Now `check` and
//! `run` both refuse it when the plan is read, at the `robots` key's line and column, with
//! exit code 2, saying both counts. Every initial token outside `role = "resource"` places is
//! an initial agent (agents keep their identity through places without actions). A plan with
//! a `[map]` still runs with `--robots N`, which renames and rescales its robots.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

/// `Idle` (3 tokens) -go-> `Work` -back-> `Idle`; `back` also takes and returns the one
/// token of `Charger`.
const NET: &str = r#"<?xml version="1.0" encoding="UTF-8" standalone="no"?>
<project name="idle_work" version="121">
  <gspn name="idle_work">
    <nodes>
      <place marking="3" name="Idle" x="1.0" y="1.0"/>
      <place name="Work" x="3.0" y="1.0"/>
      <place marking="1" name="Charger" x="2.0" y="3.0"/>
      <transition name="go" type="EXP" delay="1.0" nservers="1" x="2.0" y="0.0"/>
      <transition name="back" type="EXP" delay="1.0" nservers="1" x="2.0" y="2.0"/>
    </nodes>
    <edges>
      <arc head="go" kind="INPUT" tail="Idle"/>
      <arc head="Work" kind="OUTPUT" tail="go"/>
      <arc head="back" kind="INPUT" tail="Work"/>
      <arc head="back" kind="INPUT" tail="Charger"/>
      <arc head="Idle" kind="OUTPUT" tail="back"/>
      <arc head="Charger" kind="OUTPUT" tail="back"/>
    </edges>
  </gspn>
</project>
"#;

/// A plan over [`NET`] naming `robots` (line 3), with `places` (TOML tables) after it.
fn plan(dir: &Path, robots: &[&str], places: &str) -> PathBuf {
    std::fs::write(dir.join("n.PNPRO"), NET).unwrap();
    let names: Vec<String> = robots.iter().map(|r| format!("{r:?}")).collect();
    let path = dir.join("plan.toml");
    std::fs::write(
        &path,
        format!(
            "net = \"n.PNPRO\"\nseed = 1\nrobots = [{}]\n\n[places.Charger]\nrole = \"resource\"\n\n\
             {places}\n[stop]\nmax_firings = 20\n",
            names.join(", ")
        ),
    )
    .unwrap();
    path
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

const COUNTS: &str = "`robots` names 4 robot(s) but the net starts with 3 agent(s) \
                      (initial tokens outside resource places: Idle 3)";

#[test]
fn check_refuses_more_robots_than_agents_at_the_robots_key() {
    let dir = tempfile::tempdir().unwrap();
    // `Idle` has no action: its tokens are agents all the same; `Charger`'s token is not.
    let plan = plan(
        dir.path(),
        &["r1", "r2", "r3", "r4"],
        "[places.Work]\naction = \"wait 1\"\n",
    );
    let out = bin().arg("check").arg(&plan).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    let at = format!("error: {}:3:1: {COUNTS}", plan.display());
    assert!(err.starts_with(&at), "{err}");
}

#[test]
fn check_refuses_fewer_robots_than_agents_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let plan = plan(
        dir.path(),
        &["r1", "r2"],
        "[places.Work]\naction = \"wait 1\"\n",
    );
    let out = bin().arg("check").arg(&plan).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).starts_with(&format!(
            "error: {}:3:1: `robots` names 2 robot(s) but the net starts with 3 agent(s) \
             (initial tokens outside resource places: Idle 3)",
            plan.display()
        )),
        "{}",
        stderr(&out)
    );
}

#[test]
fn the_key_is_found_wherever_it_is_written() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("n.PNPRO"), NET).unwrap();
    let path = dir.path().join("plan.toml");
    // Indented, after a comment, and quoted: the position is the key's, not the value's.
    // `Charger` is not declared a resource here: its token is an agent too.
    std::fs::write(
        &path,
        "# robots below\nnet = \"n.PNPRO\"\n\n   \"robots\" = [\"a\"]\n\n[places.Idle]\naction = \"wait\"\n",
    )
    .unwrap();
    let out = bin().arg("check").arg(&path).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).starts_with(&format!(
            "error: {}:4:4: `robots` names 1 robot(s) but the net starts with 4 agent(s) \
             (initial tokens outside resource places: Idle 3, Charger 1)",
            path.display()
        )),
        "{}",
        stderr(&out)
    );
}

#[test]
fn run_refuses_it_when_the_plan_is_read_before_the_runtime_starts() {
    let dir = tempfile::tempdir().unwrap();
    let plan = plan(
        dir.path(),
        &["r1", "r2", "r3", "r4"],
        "[places.Idle]\naction = \"wait\"\n[places.Work]\naction = \"wait 1\"\n",
    );
    let journal = dir.path().join("run.jsonl");
    let out = bin()
        .arg("run")
        .arg(&plan)
        .arg("--journal")
        .arg(&journal)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let at = format!("error: {}:3:1: {COUNTS}", plan.display());
    assert!(stderr(&out).starts_with(&at), "{}", stderr(&out));
    // The runtime never started: it writes the journal's header first thing.
    assert!(!journal.exists());
}

#[test]
fn a_matching_list_passes_check_and_runs() {
    let dir = tempfile::tempdir().unwrap();
    let plan = plan(
        dir.path(),
        &["r1", "r2", "r3"],
        "[places.Idle]\naction = \"wait\"\n[places.Work]\naction = \"wait 1\"\n",
    );
    let out = bin().arg("check").arg(&plan).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let journal = dir.path().join("run.jsonl");
    let out = bin()
        .arg("run")
        .arg(&plan)
        .args(["--json", "--quiet", "--journal"])
        .arg(&journal)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["stopped"], "max_firings");
    assert_eq!(summary["firings"], 20);
    let header: Value = serde_json::from_str(
        std::fs::read_to_string(&journal)
            .unwrap()
            .lines()
            .next()
            .unwrap(),
    )
    .unwrap();
    assert_eq!(header["robots"], serde_json::json!(["r1", "r2", "r3"]));
}

/// The simulated patrol (3 start tokens) with a `robots` list of `names`, beside a copy of
/// its net.
#[cfg(feature = "sim")]
fn patrol_with_robots(dir: &Path, names: &str) -> PathBuf {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("plans/temperature-patrol");
    std::fs::copy(
        src.join("temperature_patrol.xml"),
        dir.join("temperature_patrol.xml"),
    )
    .unwrap();
    let text = std::fs::read_to_string(src.join("plan.toml")).unwrap();
    let text = text.replacen(
        "time_scale = 0.0\n",
        &format!("time_scale = 0.0\nrobots = [{names}]\n"),
        1,
    );
    let plan = dir.join("plan.toml");
    std::fs::write(&plan, text).unwrap();
    plan
}

#[cfg(feature = "sim")]
#[test]
fn a_map_plan_with_a_matching_list_still_runs_with_more_robots() {
    let dir = tempfile::tempdir().unwrap();
    let plan = patrol_with_robots(dir.path(), "\"a\", \"b\", \"c\"");
    let out = bin().arg("check").arg(&plan).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // `--robots 5` rescales the start tokens and names the robots r1 … r5.
    let out = bin()
        .arg("run")
        .arg(&plan)
        .args(["--robots", "5", "--until", "30", "--json", "--quiet"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["sim"]["robots"], 5);
    assert_eq!(v["stopped"], "time_limit");
    // With a list that does not match, `run --robots 5` refuses the plan as `check` does.
    let plan = patrol_with_robots(dir.path(), "\"a\", \"b\"");
    let out = bin()
        .arg("run")
        .arg(&plan)
        .args(["--robots", "5", "--until", "30"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let line = std::fs::read_to_string(&plan)
        .unwrap()
        .lines()
        .position(|l| l.starts_with("robots"))
        .unwrap()
        + 1;
    assert!(
        stderr(&out).contains(&format!(
            "{}:{line}:1: `robots` names 2 robot(s) but the net starts with 3 agent(s)",
            plan.display()
        )),
        "{}",
        stderr(&out)
    );
}
