//! `import-thesis` on the thesis's standalone example, then `run`, with real `python3`: the
//! thesis-shaped functions (`functions.work_place_N(token_id)`: print, sleep, return a
//! transition) run unchanged in a worker, the journal shows each one's printed line and the
//! firings they chose; `plans/thesis-standalone/` is what the importer writes; the
//! `plans/python-workers/` example runs its Python worker.

use serde_json::Value;
use std::path::{Path, PathBuf};

use crate::program_actions::{journal, repo};

/// `plan-runner`, with the checkout's Python package on the path: the imported plans'
/// worker (`thesis_functions.py`) runs on `gspn.worker`, which `pip install ./python`
/// installs for users.
fn bin() -> std::process::Command {
    let mut cmd = crate::program_actions::bin();
    cmd.env("PYTHONPATH", repo("python"));
    cmd
}

fn ok(out: &std::process::Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(0), "{err}");
    err
}

/// The thesis-standalone inputs (JSON, net, functions.py) copied into a fresh directory
/// `in/`, imported into `out/` by the CLI.
fn import_standalone(dir: &Path, project: Option<&Path>) -> PathBuf {
    let input = dir.join("in");
    std::fs::create_dir_all(&input).unwrap();
    for f in [
        "gspn_execution_input.json",
        "example_gspn.xml",
        "functions.py",
    ] {
        std::fs::copy(repo("plans/thesis-standalone").join(f), input.join(f)).unwrap();
    }
    let out = dir.join("out");
    let mut cmd = bin();
    cmd.arg("import-thesis")
        .arg(input.join("gspn_execution_input.json"))
        .arg("--out")
        .arg(&out);
    if let Some(p) = project {
        cmd.arg("--project-path").arg(p);
    }
    ok(&cmd.output().unwrap());
    out.join("plan.toml")
}

#[test]
fn the_imported_standalone_example_runs_its_python_functions() {
    let dir = tempfile::tempdir().unwrap();
    let plan = import_standalone(dir.path(), None);
    let text = std::fs::read_to_string(&plan).unwrap();
    // The functions' module is beside the JSON, one directory over from the plan.
    assert!(
        text.contains("command = [\"python3\", \"thesis_functions.py\", \"../in\"]"),
        "{text}"
    );
    let j = dir.path().join("run.jsonl");
    // From another directory: the worker runs in the plan's directory.
    let out = bin()
        .current_dir(dir.path())
        .args([
            "run",
            plan.to_str().unwrap(),
            "--seed",
            "3",
            "--json",
            "--journal",
        ])
        .arg(&j)
        .output()
        .unwrap();
    ok(&out);
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["agents_spawned"], 2);
    assert_eq!(summary["stopped"], "dead");
    assert_eq!(summary["firings"], 3, "{summary}");
    assert_eq!(summary["final_marking"]["p3"], 2);

    let lines = journal(&j);
    let places: Vec<String> = lines[0]["places"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    let transitions: Vec<String> = lines[0]["transitions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    let said: Vec<(u64, String, String)> = lines
        .iter()
        .filter(|l| l["event"] == "action_output")
        .map(|l| {
            (
                l["agent"].as_u64().unwrap(),
                places[l["place"].as_u64().unwrap() as usize].clone(),
                l["line"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    // Agent 0 starts in p1, agent 1 in p2 (the net's initial tokens, in place order): each
    // function printed its line, with the agent's id as the token id.
    let mut sorted = said.clone();
    sorted.sort();
    assert_eq!(
        sorted,
        [
            (0, "p1".into(), "token 0 works in place 1".into()),
            (0, "p2".into(), "token 0 works in place 2".into()),
            (1, "p2".into(), "token 1 works in place 2".into()),
        ]
    );
    // The firings are the ones the functions returned: t1 once (agent 0 out of p1), t2 twice.
    let ended: Vec<(u64, String)> = lines
        .iter()
        .filter(|l| l["event"] == "action_ended")
        .map(|l| {
            assert_eq!(l["outcome"]["kind"], "fire", "{l}");
            let t = l["outcome"]["detail"].as_u64().unwrap() as usize;
            (l["agent"].as_u64().unwrap(), transitions[t].clone())
        })
        .collect();
    let mut ended_sorted = ended.clone();
    ended_sorted.sort();
    assert_eq!(
        ended_sorted,
        [(0, "t1".into()), (0, "t2".into()), (1, "t2".into())],
        "{ended:?}"
    );
    // Every event with a place or a transition names it too (`place_name`, `transition_name`).
    let mut named = 0;
    for l in &lines[1..] {
        if let Some(p) = l["place"].as_u64() {
            assert_eq!(l["place_name"], places[p as usize].as_str(), "{l}");
            named += 1;
        }
        if let Some(t) = l["transition"].as_u64() {
            assert_eq!(
                l["transition_name"],
                transitions[t as usize].as_str(),
                "{l}"
            );
            named += 1;
        }
        if l["event"] == "action_ended" {
            let t = l["outcome"]["detail"].as_u64().unwrap() as usize;
            assert_eq!(l["transition_name"], transitions[t].as_str(), "{l}");
        }
    }
    assert!(named >= 12, "{named}");
    let mut fired: Vec<String> = lines
        .iter()
        .filter(|l| l["event"] == "fired")
        .map(|l| transitions[l["transition"].as_u64().unwrap() as usize].clone())
        .collect();
    fired.sort();
    assert_eq!(fired, ["t1", "t2", "t2"]);
}

#[test]
fn project_path_names_where_the_functions_are() {
    let dir = tempfile::tempdir().unwrap();
    // A module of the same name elsewhere, whose work_place_1 fires nothing but says so.
    let elsewhere = dir.path().join("elsewhere");
    std::fs::create_dir_all(&elsewhere).unwrap();
    std::fs::write(
        elsewhere.join("functions.py"),
        "def work_place_1(i):\n    print('elsewhere', i)\n    return 't1'\n\
         def work_place_2(i):\n    raise RuntimeError('arm stuck')\n\
         def work_place_3(i):\n    return None\n",
    )
    .unwrap();
    let plan = import_standalone(dir.path(), Some(&elsewhere));
    let j = dir.path().join("run.jsonl");
    let out = bin()
        .args([
            "run",
            plan.to_str().unwrap(),
            "--seed",
            "3",
            "--json",
            "--journal",
        ])
        .arg(&j)
        .output()
        .unwrap();
    // work_place_2 raises: the action fails and the place's on_failure (stop) ends the run.
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["stopped"], "failure", "{summary}");
    let errors = summary["errors"].to_string();
    assert!(errors.contains("RuntimeError: arm stuck"), "{errors}");
}

#[test]
fn plans_thesis_standalone_is_what_the_importer_writes() {
    let dir = tempfile::tempdir().unwrap();
    let plan = import_standalone(dir.path(), None);
    let out = plan.parent().unwrap();
    let committed = repo("plans/thesis-standalone");
    // The committed plan imports its functions from its own directory ("."); the fresh
    // one from ../in: otherwise the same text.
    let fresh = std::fs::read_to_string(&plan)
        .unwrap()
        .replace("\"../in\"", "\".\"");
    assert_eq!(
        std::fs::read_to_string(committed.join("plan.toml")).unwrap(),
        fresh,
        "plans/thesis-standalone/plan.toml is stale: run `plan-runner import-thesis plans/thesis-standalone/gspn_execution_input.json --out plans/thesis-standalone`"
    );
    let f = "thesis_functions.py";
    assert_eq!(
        std::fs::read_to_string(committed.join(f)).unwrap(),
        std::fs::read_to_string(out.join(f)).unwrap(),
        "{f}"
    );
    assert_eq!(
        std::fs::read_to_string(repo("python").join(f)).unwrap(),
        std::fs::read_to_string(out.join(f)).unwrap(),
        "{f}"
    );
}

#[test]
fn the_python_workers_example_runs_its_worker() {
    let dir = tempfile::tempdir().unwrap();
    let j = dir.path().join("run.jsonl");
    let out = bin()
        .current_dir(dir.path())
        .args([
            "run",
            repo("plans/python-workers/plan.toml").to_str().unwrap(),
            "--json",
            "--journal",
        ])
        .arg(&j)
        .output()
        .unwrap();
    ok(&out);
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["agents_spawned"], 2);
    assert_eq!(summary["stopped"], "max_firings");
    assert_eq!(summary["firings"], 200);
    let lines = journal(&j);
    let places = lines[0]["places"].as_array().unwrap().clone();
    let patrols: Vec<&Value> = lines
        .iter()
        .filter(|l| l["event"] == "action_output")
        .collect();
    assert!(patrols.len() >= 10, "{}", patrols.len());
    for l in patrols {
        let place = places[l["place"].as_u64().unwrap() as usize]
            .as_str()
            .unwrap();
        assert_eq!(
            l["line"],
            format!("robot {} patrols {place}", l["agent"]),
            "{l}"
        );
    }
}
