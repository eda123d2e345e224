//! `plan-runner synthesize`: the optimal policy of a plan or a net with rewards, as JSON and
//! as `[[policy]]` rules that load back; the robot sweep; the DRN export; bad input refused
//! with exit code 2 and the line and column of a plan key.

use assert_cmd::Command;
use serde_json::Value;

use crate::support::fixture;

fn synthesize(args: &[&str]) -> (i32, String, String) {
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .arg("synthesize")
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).to_string(),
        String::from_utf8_lossy(&out.stderr).to_string(),
    )
}

fn home_plan() -> String {
    format!(
        "{}/plans/home-cleaning/plan.toml",
        env!("CARGO_MANIFEST_DIR")
    )
}

#[test]
fn the_home_plan_gives_an_optimal_policy_that_loads_back_as_a_plan() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("policy.toml");
    let rules_json = dir.path().join("rules.json");
    let (code, stdout, err) = synthesize(&[
        &home_plan(),
        "--objective",
        "lra-max",
        "--json",
        "--out",
        out.to_str().unwrap(),
        "--rules-json",
        rules_json.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    let (v, lo, hi) = (
        j["value"].as_f64().unwrap(),
        j["lower"].as_f64().unwrap(),
        j["upper"].as_f64().unwrap(),
    );
    assert!(lo <= v && v <= hi && hi - lo <= 1e-9 * v, "{j}");
    // 3 robots without WAIT: the toolbox's count for N = 3.
    assert_eq!(j["toolbox_states"], 389);
    // The summary counts the rules; the rules themselves are in --rules-json's file.
    assert!(j.get("rules").is_none(), "{j}");
    let written: Value =
        serde_json::from_str(&std::fs::read_to_string(&rules_json).unwrap()).unwrap();
    assert_eq!(written["net_hash"], j["net_hash"]);
    let rules = written["rules"].as_array().unwrap();
    assert_eq!(j["exact_rules"].as_u64().unwrap(), rules.len() as u64);
    assert_eq!(
        j["decision_markings"].as_u64().unwrap(),
        rules.len() as u64 + j["wait_markings"].as_u64().unwrap()
    );
    assert!(!rules.is_empty());
    assert!(rules.iter().all(
        |r| r["choose"].is_string() && r["marking"].as_object().is_some_and(|m| !m.is_empty())
    ));
    assert!(j["compressed_rules"].as_u64().unwrap() < rules.len() as u64);
    // The written file is a plan with one exact rule per decision marking, and it loads.
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("# objective: lra-max, optimal value"),
        "{text}"
    );
    assert_eq!(text.matches("[[policy]]").count(), rules.len());
    let plan = gspn::plan::read_plan(&out, &Default::default()).unwrap();
    assert_eq!(plan.policy.rules().len(), rules.len());
}

#[test]
fn compact_rules_are_fewer_and_load() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("compact.toml");
    let (code, _, err) = synthesize(&[&home_plan(), "--compact", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let plan = gspn::plan::read_plan(&out, &Default::default()).unwrap();
    assert!(!plan.policy.rules().is_empty());
    assert!(
        plan.policy.rules().len() < 150,
        "{}",
        plan.policy.rules().len()
    );
}

#[test]
fn a_sweep_prints_one_row_per_robot_count() {
    let net = fixture("gspnr/home_n01/net.PNPRO");
    let rewards = fixture("gspnr/home_n01/rewards.toml");
    let (code, stdout, err) = synthesize(&[
        net.to_str().unwrap(),
        "--rewards",
        rewards.to_str().unwrap(),
        "--sweep",
        "robots=1..4",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let rows: Vec<Value> = serde_json::from_str(&stdout).unwrap();
    let states: Vec<u64> = rows.iter().map(|r| r["states"].as_u64().unwrap()).collect();
    assert_eq!(states, vec![13, 86, 389, 1385]);
}

#[test]
fn drn_export_names_the_model_type_and_every_state() {
    let dir = tempfile::tempdir().unwrap();
    let drn = dir.path().join("m.drn");
    let net = fixture("gspnr/tiny_cycle/net.PNPRO");
    let rewards = fixture("gspnr/tiny_cycle/rewards.toml");
    let (code, stdout, err) = synthesize(&[
        net.to_str().unwrap(),
        "--rewards",
        rewards.to_str().unwrap(),
        "--export-drn",
        drn.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    assert!((j["value"].as_f64().unwrap() - 6.0).abs() < 1e-9, "{j}");
    let text = std::fs::read_to_string(&drn).unwrap();
    assert!(text.contains("@type: Markov Automaton"));
    assert_eq!(text.matches("\nstate ").count(), 3);
}

/// Issue 33: `--sweep` with `--export-drn F` writes one model per robot count, named by it;
/// the options that write a policy are refused with exit code 2 (they used to write nothing).
#[test]
fn a_sweep_exports_one_drn_per_robot_count_and_refuses_policy_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let net = fixture("gspnr/home_n01/net.PNPRO");
    let rewards = fixture("gspnr/home_n01/rewards.toml");
    let drn = dir.path().join("home.drn");
    let (code, stdout, err) = synthesize(&[
        net.to_str().unwrap(),
        "--rewards",
        rewards.to_str().unwrap(),
        "--sweep",
        "robots=1..2",
        "--export-drn",
        drn.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let rows: Vec<Value> = serde_json::from_str(&stdout).unwrap();
    assert!(!drn.exists());
    for (row, (n, states)) in rows.iter().zip([(1, 13), (2, 86)]) {
        let file = dir.path().join(format!("home-n{n}.drn"));
        assert_eq!(row["drn"], file.display().to_string());
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(text.contains("@type: Markov Automaton"));
        assert_eq!(text.matches("\nstate ").count(), states, "{n} robots");
    }
    let out = dir.path().join("policy.toml");
    let (code, stdout, err) = synthesize(&[
        net.to_str().unwrap(),
        "--rewards",
        rewards.to_str().unwrap(),
        "--sweep",
        "robots=1..2",
        "--out",
        out.to_str().unwrap(),
        "--rules-json",
        dir.path().join("r.json").to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(stdout.is_empty(), "{stdout}");
    assert!(
        err.contains("--sweep writes no policy, so --out and --rules-json would write nothing"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn bad_input_is_refused_with_exit_code_2() {
    let net = fixture("gspnr/tiny_cycle/net.PNPRO");
    let (code, _, err) = synthesize(&[net.to_str().unwrap(), "--objective", "fastest-max"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("unknown objective `fastest`"), "{err}");
    let (code, _, err) = synthesize(&[net.to_str().unwrap(), "--objective", "reach-max"]);
    assert_eq!(code, 2);
    assert!(err.contains("--goal"), "{err}");
    let (code, _, err) = synthesize(&[
        net.to_str().unwrap(),
        "--objective",
        "reach-max",
        "--goal",
        "p9 > 0",
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("p9"), "{err}");
}

#[test]
fn a_plan_naming_an_unknown_place_in_rewards_is_refused_at_its_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let net = fixture("gspnr/tiny_cycle/net.PNPRO");
    let plan = dir.path().join("plan.toml");
    std::fs::write(
        &plan,
        format!(
            "net = {:?}\n\n[rewards.r]\nmarked = {{ p3 = 1.0, p7 = 2.0 }}\n",
            net.to_str().unwrap()
        ),
    )
    .unwrap();
    let (code, _, err) = synthesize(&[plan.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(":4:22"), "{err}");
    assert!(err.contains("p7"), "{err}");
    std::fs::write(
        &plan,
        format!(
            "net = {:?}\ncontrollable = [\"t1\", \"t2\"]\n",
            net.to_str().unwrap()
        ),
    )
    .unwrap();
    let (code, _, err) = synthesize(&[plan.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(":2:23"), "{err}");
    assert!(err.contains("exponential"), "{err}");
}

/// `analyze PLAN` analyses the net under the plan's policy: the written optimal policy earns
/// the synthesised value (to 1e-9), the plan without a policy is the bare net and earns
/// less; the output says which. Policy iteration (`--method policy`, and the default `auto`
/// for lra) and value iteration (`--method value`) find the same value.
#[test]
fn analyze_of_the_written_policy_gives_the_synthesised_value() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("policy.toml");
    let (code, stdout, err) = synthesize(&[
        &home_plan(),
        "--json",
        "--method",
        "policy",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(j["method"], "PolicyIteration");
    let optimum = j["value"].as_f64().unwrap();
    let analyze = |plan: &str, json: bool| {
        let mut cmd = Command::cargo_bin("plan-runner").unwrap();
        cmd.arg("analyze").arg(plan);
        if json {
            cmd.arg("--json");
        }
        let o = cmd.output().unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8(o.stdout).unwrap()
    };
    let under: Value = serde_json::from_str(&analyze(out.to_str().unwrap(), true)).unwrap();
    assert_eq!(under["analysed"], "net under plan policy");
    let rate = under["steady_state"]["rewards"]["cleaning"]["rate"]
        .as_f64()
        .unwrap();
    assert!(
        (rate - optimum).abs() <= 1e-9 * optimum,
        "analyze {rate} vs synthesize {optimum}"
    );
    let bare: Value = serde_json::from_str(&analyze(&home_plan(), true)).unwrap();
    assert_eq!(bare["analysed"], "bare net");
    let bare_rate = bare["steady_state"]["rewards"]["cleaning"]["rate"]
        .as_f64()
        .unwrap();
    assert!(bare_rate < optimum - 1e-3, "{bare_rate} vs {optimum}");
    let text = analyze(out.to_str().unwrap(), false);
    assert!(text.contains("analysed: net under plan policy ("), "{text}");
    assert!(text.contains("rewards (long-run rate per unit of time, net under plan policy):"));
    // Value iteration agrees with policy iteration; `auto` runs policy iteration for lra.
    let (code, stdout, err) = synthesize(&[&home_plan(), "--json", "--method", "value"]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["method"], "RelativeValueIteration");
    assert!((v["value"].as_f64().unwrap() - optimum).abs() <= 1e-9 * optimum);
    let (code, stdout, err) = synthesize(&[&home_plan(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let a: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(a["method"], "PolicyIteration");
    assert!((a["value"].as_f64().unwrap() - optimum).abs() <= 1e-9 * optimum);
}

#[test]
fn policy_iteration_for_another_objective_is_refused() {
    let (code, _, err) = synthesize(&[
        &home_plan(),
        "--objective",
        "discounted-max",
        "--discount",
        "0.1",
        "--method",
        "policy",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(
            "--method policy: policy iteration is implemented for lra-max and lra-min only"
        ),
        "{err}"
    );
}

/// Whether process `pid` has a handler for SIGINT (Linux: bit 1 of `SigCgt` in its status).
fn catches_sigint(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("SigCgt:"))
                .and_then(|m| u64::from_str_radix(m.trim(), 16).ok())
        })
        .is_some_and(|mask| mask & (1 << (libc::SIGINT - 1)) != 0)
}

/// Ctrl-C stops a long synthesis (value iteration on 7 robots, 26,511 states: tens of
/// seconds in the test build) in the search or the solver, with a message saying which and
/// exit code 130 — well before it could have finished.
#[test]
fn ctrl_c_stops_the_solver_with_exit_code_130() {
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    let net = fixture("gspnr/home_n07/net.PNPRO");
    let rewards = fixture("gspnr/home_n07/rewards.toml");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_plan-runner"))
        .args(["synthesize", net.to_str().unwrap(), "--rewards"])
        .arg(&rewards)
        .args(["--method", "value"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Once the handler is in place (registered before any work), let it work a moment.
    let start = Instant::now();
    while !catches_sigint(child.id()) {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no SIGINT handler"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(1500));
    let sent = Instant::now();
    let out = crate::program_actions::interrupt(child);
    let took = sent.elapsed();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted by SIGINT"), "{err}");
    assert!(
        err.contains("stopped solving after") || err.contains("stopped building the model"),
        "{err}"
    );
    assert!(
        out.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    // About a second on an idle machine; generous for a loaded one.
    assert!(took < Duration::from_secs(10), "{took:?}");
}

/// Runs `plan-runner run PLAN --json` with `extra` arguments: (exit code, summary, stderr).
fn run_json(plan: &std::path::Path, extra: &[&str]) -> (i32, Value, String) {
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .arg("run")
        .arg(plan)
        .args(["--json", "--quiet"])
        .args(extra)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    let v = serde_json::from_slice(&out.stdout).unwrap_or(Value::Null);
    (out.status.code().unwrap_or(-1), v, err)
}

/// The whole loop: `synthesize --out policy.toml`, then `run policy.toml` in virtual time
/// (20,000 time units, the plan's `[stop]`): the run's summary counts the plan's reward,
/// and its measured rate holds the optimal long-run average within its own 95% interval
/// (batch means); every decision the run met was in the written table (no warning).
#[test]
fn a_run_with_the_synthesised_policy_earns_the_optimal_rate() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("policy.toml");
    let (code, stdout, err) = synthesize(&[&home_plan(), "--json", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let optimum = serde_json::from_str::<Value>(&stdout).unwrap()["value"]
        .as_f64()
        .unwrap();
    let (code, summary, err) = run_json(&out, &["--seed", "11"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(summary["time"].as_f64().unwrap(), 20000.0, "{summary}");
    let r = &summary["rewards"]["cleaning"];
    let (rate, half, total) = (
        r["rate"].as_f64().unwrap(),
        r["half_width"].as_f64().unwrap(),
        r["total"].as_f64().unwrap(),
    );
    assert!((total / 20000.0 - rate).abs() <= 1e-9 * rate, "{r}");
    assert!(r["batches"].as_u64().unwrap() >= 32, "{r}");
    assert!(half > 0.0 && half < 0.05 * optimum, "{r}");
    assert!(
        (rate - optimum).abs() <= half,
        "measured {rate} ± {half} vs optimum {optimum}"
    );
    assert!(summary.get("warnings").is_none(), "{summary}");
    assert!(!err.contains("warning: no [[policy]] rule"), "{err}");
}

/// A policy that misses decision markings: the run goes on by the net's weights (all 0
/// there: uniformly), says so once — a `warning` event in the journal, one line on stderr —
/// and counts the decisions taken outside the table in the summary's `warnings`.
#[test]
fn a_marking_outside_the_policy_table_falls_back_to_the_weights_with_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    let full = dir.path().join("policy.toml");
    let (code, _, err) = synthesize(&[&home_plan(), "--out", full.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    // Keep the plan and its first rule only.
    let text = std::fs::read_to_string(&full).unwrap();
    let mut parts = text.split("[[policy]]");
    let head = parts.next().unwrap();
    let first = parts.next().unwrap();
    assert!(parts.next().is_some(), "more than one rule written");
    let partial = dir.path().join("partial.toml");
    std::fs::write(&partial, format!("{head}[[policy]]{first}")).unwrap();
    let journal = dir.path().join("run.jsonl");
    let (code, summary, err) = run_json(
        &partial,
        &[
            "--seed",
            "3",
            "--max-firings",
            "500",
            "--journal",
            journal.to_str().unwrap(),
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(summary["firings"], 500, "{summary}");
    assert_eq!(
        err.matches("warning: no [[policy]] rule applies in marking")
            .count(),
        1,
        "{err}"
    );
    let warnings = summary["warnings"].as_array().unwrap();
    assert_eq!(warnings.len(), 2, "{summary}");
    assert!(
        warnings[0]
            .as_str()
            .unwrap()
            .contains("the net's weights decide")
    );
    let misses: u64 = warnings[1]
        .as_str()
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(misses > 1, "{summary}");
    let events = std::fs::read_to_string(&journal).unwrap();
    let warning_events: Vec<&str> = events
        .lines()
        .filter(|l| l.contains("\"event\":\"warning\""))
        .collect();
    assert_eq!(warning_events.len(), 1, "{events}");
    assert!(warning_events[0].contains("no [[policy]] rule applies"));
}

/// The quickstart's patrol (two robots, one charger: `role = "resource"`) as a plan with a
/// reward and its three decisions controllable, written beside a copy of its net whose
/// `Patrol_A` starts with `patrol_a` robots.
fn patrol_with_charger(dir: &std::path::Path, patrol_a: u32) -> std::path::PathBuf {
    let xml = std::fs::read_to_string(format!(
        "{}/plans/nets/two_robot_patrol.xml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    // Patrol_A's initial marking is the first `Default,1` of the file.
    let xml = xml.replacen("Default,1", &format!("Default,{patrol_a}"), 1);
    std::fs::write(dir.join("net.xml"), xml).unwrap();
    let plan = dir.join(format!("patrol{patrol_a}.toml"));
    std::fs::write(
        &plan,
        r#"net = "net.xml"
controllable = ["t_go_A", "t_go_B", "t_charge"]

[places.Charger]
role = "resource"

[rewards.patrolling]
per_token = { Patrol_A = 1.0, Patrol_B = 1.0 }
"#,
    )
    .unwrap();
    plan
}

fn lra_value(plan: &std::path::Path) -> f64 {
    let (code, stdout, err) = synthesize(&[plan.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    j["value"].as_f64().unwrap()
}

/// Issue 30, snag 1: the sweep counted the charger's token as a robot ("robots 3" was the
/// 2-robot model). Each row must be the model with that many robots and the one charger.
#[test]
fn a_sweep_scales_the_robots_and_keeps_the_resources() {
    let dir = tempfile::tempdir().unwrap();
    let two = patrol_with_charger(dir.path(), 1);
    let (code, stdout, err) =
        synthesize(&[two.to_str().unwrap(), "--sweep", "robots=2..3", "--json"]);
    assert_eq!(code, 0, "{err}");
    let rows: Vec<Value> = serde_json::from_str(&stdout).unwrap();
    let swept: Vec<f64> = rows.iter().map(|r| r["value"].as_f64().unwrap()).collect();
    // Two robots: the plan as written. Three: Patrol_A gets the extra robot (largest
    // remainder, net order breaks the tie), the charger keeps its one token.
    let direct_two = lra_value(&two);
    let three_dir = tempfile::tempdir().unwrap();
    let direct_three = lra_value(&patrol_with_charger(three_dir.path(), 2));
    assert!(
        (swept[0] - direct_two).abs() < 1e-9,
        "{swept:?} vs {direct_two}"
    );
    assert!(
        (swept[1] - direct_three).abs() < 1e-9,
        "{swept:?} vs {direct_three}"
    );
    assert!(
        direct_three > direct_two + 0.1,
        "{direct_two} {direct_three}"
    );
}

/// Issue 30, snag 4: no rewards, or no decision, used to print `lra-max: 0` and exit 0.
#[test]
fn nothing_to_optimise_is_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let plan = patrol_with_charger(dir.path(), 1);
    let text = std::fs::read_to_string(&plan).unwrap();
    let no_rewards = dir.path().join("no_rewards.toml");
    std::fs::write(&no_rewards, text.split("[rewards.").next().unwrap()).unwrap();
    let (code, stdout, err) = synthesize(&[no_rewards.to_str().unwrap()]);
    assert_eq!(code, 2, "{stdout}{err}");
    assert!(
        err.contains("nothing to optimise: --objective lra-max needs rewards"),
        "{err}"
    );
    // A probability needs no rewards.
    let (code, _, err) = synthesize(&[
        no_rewards.to_str().unwrap(),
        "--objective",
        "reach-max",
        "--goal",
        "Charging > 0",
    ]);
    assert_eq!(code, 0, "{err}");
    let no_decision = dir.path().join("no_decision.toml");
    std::fs::write(
        &no_decision,
        text.replace(
            "controllable = [\"t_go_A\", \"t_go_B\", \"t_charge\"]\n",
            "",
        ),
    )
    .unwrap();
    let (code, stdout, err) = synthesize(&[no_decision.to_str().unwrap()]);
    assert_eq!(code, 2, "{stdout}{err}");
    assert!(
        err.contains("nothing to optimise: the net has no decision"),
        "{err}"
    );
}

/// The fenced block of `lang` that follows `marker` in `text`.
fn block_after(text: &str, marker: &str, lang: &str) -> String {
    let rest = &text[text.find(marker).expect("marker") + marker.len()..];
    let open = format!("```{lang}\n");
    let body = &rest[rest.find(&open).expect("block") + open.len()..];
    body[..body.find("```").expect("block end")].to_string()
}

/// Issue 30, snag 5: docs/synthesis.md's Storm snippet named the reward model `reward`,
/// but a plan's DRN names it after the plan's reward, so it failed as written. Both of its
/// blocks run here as written, and Storm's value is ours.
#[test]
fn the_storm_snippet_of_the_docs_runs_as_written() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = root.join("target/venv-ros2/bin/python");
    assert!(
        python.exists(),
        "{} missing: run ./test.sh (it makes the venv and installs stormpy)",
        python.display()
    );
    let doc = std::fs::read_to_string(root.join("docs/synthesis.md")).unwrap();
    let marker = "## Checking us with Storm";
    let command = block_after(&doc, marker, "sh");
    let script = block_after(&doc, marker, "python");
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        root.join("plans/home-cleaning/plan.toml"),
        dir.path().join("plan.toml"),
    )
    .unwrap();
    std::fs::copy(
        root.join("plans/home-cleaning/net.PNPRO"),
        dir.path().join("net.PNPRO"),
    )
    .unwrap();
    let args: Vec<String> = command
        .split_whitespace()
        .skip(1)
        .map(|a| a.replace("plans/home-cleaning/", ""))
        .collect();
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .current_dir(dir.path())
        .args(&args)
        .arg("--json")
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let ours: Value = serde_json::from_slice(&out.stdout).unwrap();
    let ours = ours["value"].as_f64().unwrap();
    let storm = std::process::Command::new(&python)
        .current_dir(dir.path())
        .arg("-c")
        .arg(&script)
        .output()
        .unwrap();
    let printed = String::from_utf8_lossy(&storm.stdout);
    assert!(
        storm.status.success(),
        "{printed}{}",
        String::from_utf8_lossy(&storm.stderr)
    );
    let theirs: f64 = printed
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("{printed}"));
    assert!(
        (theirs - ours).abs() <= 1e-6 * ours.abs().max(1.0),
        "{theirs} vs {ours}"
    );
}

/// Issue 30, snag 7: `--compact` wrote a catch-all rule as `marking = {  }`; reach-max
/// printed `1.000000000124984` (the solver's bound past 1): a probability is shown clamped to
/// [0, 1] with its bounds.
#[test]
fn compact_catch_all_and_reach_values_print_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let plan = patrol_with_charger(dir.path(), 1);
    let out = dir.path().join("compact.toml");
    let (code, _, err) = synthesize(&[
        plan.to_str().unwrap(),
        "--compact",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(!text.contains("{  }"), "{text}");
    assert!(text.contains("\nmarking = {}\npartial = true\n"), "{text}");
    assert_eq!(
        gspn::plan::read_plan(&out, &Default::default())
            .unwrap()
            .policy
            .rules()
            .len(),
        2
    );
    let (code, stdout, err) = synthesize(&[
        plan.to_str().unwrap(),
        "--objective",
        "reach-max",
        "--goal",
        "Charging > 0",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&stdout).unwrap();
    let (v, lo, hi) = (
        j["value"].as_f64().unwrap(),
        j["lower"].as_f64().unwrap(),
        j["upper"].as_f64().unwrap(),
    );
    assert!(
        (0.0..=1.0).contains(&lo) && lo <= v && v <= hi && hi <= 1.0,
        "{j}"
    );
    assert!((v - 1.0).abs() < 1e-9, "{j}");
}
