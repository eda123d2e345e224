//! `plan-runner run` with program actions from the plan file: `action = { command = … }`
//! runs a process per action and records its output; Ctrl-C (SIGINT) leaves no child
//! process alive; an unknown action name is refused at load (exit 2, line and column); the
//! quickstart spawns agents running built-in actions.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use serde_json::Value;

pub(crate) fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

pub(crate) fn repo(p: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

/// The quickstart's two-robot patrol with `Patrol_A` and `Patrol_B` running `command`.
fn patrol_plan(dir: &Path, command: &str, extra: &str) -> std::path::PathBuf {
    let net = repo("plans/nets/two_robot_patrol.xml");
    let plan = dir.join("plan.toml");
    std::fs::write(
        &plan,
        format!(
            "net = {net:?}\nseed = 4\n\n[places.Patrol_A]\naction = {{ command = [\"sh\", \"-c\", {command:?}]{extra} }}\n\
             [places.Patrol_B]\naction = {{ command = [\"sh\", \"-c\", {command:?}]{extra} }}\n\
             [places.Decide]\naction = \"wait\"\n[places.Charging]\naction = \"wait\"\n\
             [places.Charger]\nrole = \"resource\"\n\n[stop]\nmax_firings = 12\n",
            net = net.display().to_string()
        ),
    )
    .unwrap();
    plan
}

/// The journal at `path`, one JSON value per line.
pub(crate) fn journal(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn command_actions_from_a_plan_run_per_agent_and_their_output_is_journalled() {
    let dir = tempfile::tempdir().unwrap();
    let plan = patrol_plan(
        dir.path(),
        "echo \"robot $GSPN_AGENT patrols $GSPN_PLACE\"; echo $GSPN_OUTPUTS",
        "",
    );
    let j = dir.path().join("run.jsonl");
    let out = bin()
        .args(["run", plan.to_str().unwrap(), "--json", "--journal"])
        .arg(&j)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["stopped"], "max_firings");
    assert_eq!(summary["agents_spawned"], 2);
    let lines = journal(&j);
    let places = lines[0]["places"].as_array().unwrap().clone();
    let said: Vec<&Value> = lines
        .iter()
        .filter(|l| l["event"] == "action_output")
        .collect();
    assert!(said.len() >= 6, "{said:?}");
    // Each action printed two lines, in order: who it is, then the transition to fire.
    for agent in [0, 1] {
        let mine: Vec<&&Value> = said.iter().filter(|l| l["agent"] == agent).collect();
        assert!(mine.len() >= 2 && mine.len().is_multiple_of(2), "{mine:?}");
        for pair in mine.chunks(2) {
            let place = places[pair[0]["place"].as_u64().unwrap() as usize]
                .as_str()
                .unwrap();
            assert_eq!(pair[0]["line"], format!("robot {agent} patrols {place}"));
            let done = if place == "Patrol_A" {
                "T_A_done"
            } else {
                "T_B_done"
            };
            assert_eq!(pair[1]["line"], done, "{}", pair[1]);
        }
    }
    // Each patrol ended by firing the transition the program printed.
    let fires = lines
        .iter()
        .filter(|l| l["event"] == "action_ended" && l["outcome"]["kind"] == "fire")
        .count();
    assert!(fires >= 4, "{fires}");
}

fn alive(pid: i32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Ok(s) => !s
            .rsplit(')')
            .next()
            .unwrap_or("")
            .trim_start()
            .starts_with('Z'),
        Err(_) => false,
    }
}

#[test]
fn ctrl_c_leaves_no_action_process_alive() {
    let dir = tempfile::tempdir().unwrap();
    let pids = dir.path().join("pids");
    // Each action: a shell whose child ignores SIGTERM, both hanging.
    let command = format!(
        "sh -c 'trap \"\" TERM; sleep 60' & echo $! >> {p}; echo $$ >> {p}; wait",
        p = pids.display()
    );
    let plan = patrol_plan(dir.path(), &command, ", kill_grace = 0.3");
    let child = bin()
        .args(["run", plan.to_str().unwrap(), "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut n = 0;
    for _ in 0..400 {
        std::thread::sleep(Duration::from_millis(25));
        n = std::fs::read_to_string(&pids).map_or(0, |s| s.lines().count());
        if n >= 4 {
            break;
        }
    }
    assert_eq!(n, 4, "both robots' actions started");
    let all: Vec<i32> = std::fs::read_to_string(&pids)
        .unwrap()
        .lines()
        .map(|l| l.trim().parse().unwrap())
        .collect();
    assert!(all.iter().all(|&p| alive(p)));
    let out = interrupt(child);
    assert_eq!(
        out.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["stopped"], "interrupted");
    // Every process of the actions' groups is gone, the TERM-ignoring one included.
    let mut left = all.clone();
    for _ in 0..100 {
        left.retain(|&p| alive(p));
        if left.is_empty() {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(left.is_empty(), "still alive: {left:?} of {all:?}");
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

#[test]
fn an_unknown_action_name_is_bad_input_at_its_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let net = repo("plans/nets/two_robot_patrol.xml");
    let plan = dir.path().join("plan.toml");
    std::fs::write(
        &plan,
        format!(
            "net = {:?}\n\n[places.Patrol_A]\naction = \"patrl\"\n",
            net.display().to_string()
        ),
    )
    .unwrap();
    for cmd in ["run", "check", "simulate"] {
        let out = bin().args([cmd, plan.to_str().unwrap()]).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{cmd}: {err}");
        assert!(
            err.contains(&format!(
                "{}:4:10: place `Patrol_A`: unknown action `patrl`",
                plan.display()
            )),
            "{cmd}: {err}"
        );
        assert!(err.contains("known actions: `wait [S]`"), "{cmd}: {err}");
    }
}

/// Sends SIGINT (Ctrl-C) to `child` and waits for it.
pub(crate) fn interrupt(child: std::process::Child) -> std::process::Output {
    assert!(
        Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .unwrap()
            .success()
    );
    child.wait_with_output().unwrap()
}

#[test]
fn the_text_summary_lists_places_and_transitions_in_net_order() {
    let path = repo("plans/quickstart.toml");
    let out = bin()
        .args(["run", path.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8(out.stdout).unwrap();
    let net = gspn::io::read_net(
        &repo("plans/nets/two_robot_patrol.xml"),
        &gspn::io::ReadOptions::default(),
    )
    .unwrap()
    .net;
    let first_words = |header: &str, stop: &str| -> Vec<String> {
        text.lines()
            .skip_while(|l| !l.starts_with(header))
            .skip(1)
            .take_while(|l| l.starts_with("  ") && !l.starts_with(stop))
            .map(|l| l.split_whitespace().next().unwrap().to_string())
            .collect()
    };
    let places: Vec<String> = net.places().iter().map(|p| p.name.clone()).collect();
    let transitions: Vec<String> = net.transitions().iter().map(|t| t.name.clone()).collect();
    assert_eq!(first_words("place ", "transition"), places, "{text}");
    assert_eq!(first_words("transition ", "error"), transitions, "{text}");
    // Net order is not name order here (the test would prove nothing otherwise).
    let mut sorted = places.clone();
    sorted.sort();
    assert_ne!(sorted, places);
}

/// Issue 30, snag 6: a program that logs after answering (print, then exit 0) used to fail
/// the run (`answered "…", which is not a transition`). A `gspn: fire T` line answers
/// whatever follows it; without one, the last line still answers, and the error says how
/// to answer on the separate channel.
#[test]
fn a_gspn_fire_line_answers_even_when_the_program_logs_after_it() {
    let dir = tempfile::tempdir().unwrap();
    let plan = patrol_plan(
        dir.path(),
        "echo \"gspn: fire $GSPN_OUTPUTS\"; echo \"agent $GSPN_AGENT driving on\"",
        "",
    );
    let j = dir.path().join("run.jsonl");
    let out = bin()
        .args(["run", plan.to_str().unwrap(), "--json", "--journal"])
        .arg(&j)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["stopped"], "max_firings");
    let lines = journal(&j);
    let ended: Vec<&Value> = lines
        .iter()
        .filter(|l| l["event"] == "action_ended")
        .collect();
    // Every patrol (the programs) ended by firing; Decide and Charging are `wait`.
    let patrols: Vec<&&Value> = ended
        .iter()
        .filter(|l| l["place_name"] == "Patrol_A" || l["place_name"] == "Patrol_B")
        .collect();
    assert!(patrols.len() >= 4, "{ended:?}");
    assert!(
        patrols.iter().all(|l| l["outcome"]["kind"] == "fire"),
        "{patrols:?}"
    );

    // The same program without the prefix: the log line is the answer, and the run fails
    // with a message that names the other channel.
    let plan = patrol_plan(
        dir.path(),
        "echo \"$GSPN_OUTPUTS\"; echo \"agent $GSPN_AGENT driving on\"",
        "",
    );
    let out = bin()
        .args(["run", plan.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    let all = format!("{err}{}", String::from_utf8_lossy(&out.stdout));
    assert_eq!(out.status.code(), Some(1), "{all}");
    assert!(
        all.contains("answered `agent 0 driving on`, which is not a transition of the net")
            || all.contains("answered `agent 1 driving on`, which is not a transition of the net"),
        "{all}"
    );
    assert!(all.contains("print `gspn: fire T`"), "{all}");
}

/// Issue 30, snag 7: a run that reached `max_firings` while the last firing's agent was
/// starting a program waited for that program (or its timeout) before stopping. The firing
/// that ends the run starts no action: the program never runs.
#[test]
fn the_firing_that_ends_the_run_starts_no_program() {
    let dir = tempfile::tempdir().unwrap();
    let marker = dir.path().join("started");
    let net = repo("plans/nets/two_robot_patrol.xml");
    let plan = dir.path().join("plan.toml");
    std::fs::write(
        &plan,
        format!(
            "net = {net:?}\nseed = 4\ntime_scale = 0.0\n\n[places.Patrol_A]\naction = \"wait\"\n\
             [places.Patrol_B]\naction = \"wait\"\n\
             [places.Decide]\naction = {{ command = [\"sh\", \"-c\", \"touch {marker}; sleep 20\"] }}\ntimeout = 30.0\n\
             [places.Charging]\naction = \"wait\"\n[places.Charger]\nrole = \"resource\"\n\n[stop]\nmax_firings = 1\n",
            net = net.display().to_string(),
            marker = marker.display()
        ),
    )
    .unwrap();
    let j = dir.path().join("run.jsonl");
    let out = bin()
        .args(["run", plan.to_str().unwrap(), "--json", "--journal"])
        .arg(&j)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["stopped"], "max_firings");
    assert_eq!(summary["firings"], 1);
    assert_eq!(summary["final_marking"]["Decide"], 1);
    assert!(!marker.exists(), "the program ran");
    let lines = journal(&j);
    let fired = lines.iter().position(|l| l["event"] == "fired").unwrap();
    assert!(
        lines[fired..]
            .iter()
            .all(|l| l["event"] != "action_started"),
        "{:?}",
        &lines[fired..]
    );
}
