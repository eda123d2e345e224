//! `plan-runner conform`: a net-timed run of cyc3 is consistent with its net and `--fit`
//! learns its rates back; a run of the patrol on simulated robots diverges on the transitions
//! out of the places that drive (`goto`), not exponential; bad arguments exit with 2;
//! `--fail-on-drift` exits 1 when a row diverges and 0 when none does (rows without a
//! prediction do not count); `simulate`/`analyze --from JOURNAL:SEQ` start from the
//! journal's marking.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

fn ok_json(out: &Output) -> Value {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    serde_json::from_slice(&out.stdout).unwrap()
}

fn row<'a>(report: &'a Value, kind: &str, item: &str) -> &'a Value {
    report["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["kind"] == kind && r["item"] == item)
        .unwrap_or_else(|| panic!("no {kind} row for {item}"))
}

/// A journal of `plan` run with `extra` arguments, in `dir`.
fn journal(dir: &Path, plan: &str, extra: &[&str]) -> PathBuf {
    let j = dir.join("run.jsonl");
    journal_to(&j, plan, extra);
    j
}

/// Writes the journal of `plan` run with `extra` arguments to `j`.
fn journal_to(j: &Path, plan: &str, extra: &[&str]) {
    let plan = repo(plan);
    let mut args = vec![
        "run",
        plan.to_str().unwrap(),
        "--journal",
        j.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let out = run(&args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_net_timed_run_of_cyc3_is_consistent_and_fit_learns_its_rates() {
    let dir = tempfile::tempdir().unwrap();
    let j = journal(dir.path(), "plans/cyc3.toml", &["--until", "3000"]);
    let plan = repo("plans/cyc3.toml");
    let fitted = dir.path().join("fitted.PNPRO");
    let report = ok_json(&run(&[
        "conform",
        j.to_str().unwrap(),
        "--plan",
        plan.to_str().unwrap(),
        "--json",
        "--fit",
        fitted.to_str().unwrap(),
    ]));
    assert_eq!(report["net"], "cyc3");
    assert_eq!(report["predictions"], "steady state of the net");
    // 3 places, 3 throughputs, 2 rates, 2 shapes (t2 alone decides nothing).
    assert_eq!(report["rows"].as_array().unwrap().len(), 10);
    for (kind, item, truth) in [("rate", "T1", 1.0), ("rate", "T3", 2.0)] {
        let r = row(&report, kind, item);
        let [lo, hi] = [
            r["interval"][0].as_f64().unwrap(),
            r["interval"][1].as_f64().unwrap(),
        ];
        assert!(lo <= truth && truth <= hi, "{item}: [{lo}, {hi}]");
        assert!(r["n"].as_u64().unwrap() > 2000, "{r}");
    }
    let p1 = row(&report, "mean_tokens", "P1");
    assert!((p1["predicted"].as_f64().unwrap() - 10.0 / 7.0).abs() < 1e-12);
    assert!((p1["observed"].as_f64().unwrap() - 10.0 / 7.0).abs() < 0.05);
    // The fitted net: T3's rate is the observed one, within its interval of 2.
    let params = &report["fitted"]["parameters"];
    let t3 = params
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["transition"] == "T3")
        .unwrap();
    assert_eq!(t3["kept"], false);
    let text = std::fs::read_to_string(&fitted).unwrap();
    let net = gspn::io::read_net(&fitted, &gspn::io::ReadOptions::default())
        .unwrap()
        .net;
    let id = net.transition_by_name("T3").unwrap();
    let gspn::net::Timing::Exponential { rate, .. } = net.transition(id).timing else {
        panic!("T3 is exponential: {text}");
    };
    assert!((rate - t3["new"].as_f64().unwrap()).abs() < 1e-9 * rate);
    assert!((rate - 2.0).abs() < 0.15, "fitted T3 rate {rate}");

    // The text table names every row and ends with the count of diverging rows.
    let out = run(&[
        "conform",
        j.to_str().unwrap(),
        "--plan",
        plan.to_str().unwrap(),
    ]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("rate          T3"), "{text}");
    assert!(
        text.contains("tested rows diverge at the 5% level"),
        "{text}"
    );
}

#[cfg(feature = "sim")]
#[test]
fn a_run_on_simulated_robots_diverges_on_the_goto_transitions() {
    let dir = tempfile::tempdir().unwrap();
    let plan = "plans/temperature-patrol/plan.toml";
    let j = journal(dir.path(), plan, &["--robots", "2", "--until", "1200"]);
    let report = ok_json(&run(&[
        "conform",
        j.to_str().unwrap(),
        "--plan",
        repo(plan).to_str().unwrap(),
        "--json",
    ]));
    // The transitions out of Check_Temperature (drive there, then measure) at every location.
    for t in [
        "t1:Temperature_High_L1",
        "t3:Temperature_Low_L1",
        "t9:Temperature_Low_L2",
        "t15:Temperature_Low_L3",
        "t21:Temperature_Low_L4",
    ] {
        let shape = row(&report, "shape", t);
        assert_eq!(shape["verdict"], "diverges", "{t}: {shape}");
    }
    let diverging_rates = report["rows"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["kind"] == "rate" && r["verdict"] == "diverges")
        .count();
    assert!(diverging_rates >= 4, "{diverging_rates} rate rows diverge");
    // The plan has a policy: the steady-state rows are predicted under it.
    // (Not ergodic: the policy leaves some markings transient; the limiting distribution from
    // the initial marking is the prediction.)
    assert_eq!(
        report["predictions"],
        "limiting distribution of the net under the plan's policy (not ergodic)"
    );
    let throughput = row(&report, "throughput", "t1:Temperature_High_L1");
    assert!(
        throughput["predicted"].as_f64().unwrap() > 0.0,
        "{throughput}"
    );
}

#[test]
fn bad_arguments_exit_with_2() {
    let dir = tempfile::tempdir().unwrap();
    let j = journal(dir.path(), "plans/cyc3.toml", &["--until", "50"]);
    let plan = repo("plans/cyc3.toml");
    let out = run(&[
        "conform",
        j.to_str().unwrap(),
        "--plan",
        plan.to_str().unwrap(),
        "--fit",
        "out.txt",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--fit out.txt"));
    // A journal of another net.
    let other = repo("plans/temperature-patrol/temperature_patrol.xml");
    let out = run(&[
        "conform",
        j.to_str().unwrap(),
        "--net",
        other.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("not of this net"), "{stderr}");
    // Neither --plan nor --net.
    assert_eq!(
        run(&["conform", j.to_str().unwrap()]).status.code(),
        Some(2)
    );
}

/// A plan of cyc3 (2 agents, single servers) whose P3 runs `action`, written in `dir`.
fn cyc3_plan_with_p3(dir: &Path, action: &str) -> PathBuf {
    let plan = dir.join("p3.toml");
    let net = repo("plans/nets/cyc3_ss.PNPRO");
    let text = format!(
        "net = {net:?}\npage = \"cyc3\"\nseed = 3\ntime_scale = 0.0\n\n\
         [places.P3]\naction = {action:?}\n"
    );
    std::fs::write(&plan, text).unwrap();
    plan
}

#[test]
fn fail_on_drift_exits_1_when_a_row_diverges_and_0_when_none_does() {
    let dir = tempfile::tempdir().unwrap();
    // P3's agents fire T3 (rate 2) at once: P3 is never seen holding a token, where the
    // steady state says 4/7 on average.
    let plan = cyc3_plan_with_p3(dir.path(), "fire T3");
    let j = dir.path().join("fast.jsonl");
    let out = run(&[
        "run",
        plan.to_str().unwrap(),
        "--until",
        "600",
        "--journal",
        j.to_str().unwrap(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let conform = |extra: &[&str]| {
        let mut args = vec![
            "conform",
            j.to_str().unwrap(),
            "--plan",
            plan.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        run(&args)
    };
    // Without the flag the report is all: exit 0.
    let report = ok_json(&conform(&["--json"]));
    let diverging = report["rows"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["verdict"] == "diverges")
        .count();
    // (Microseconds: the real time an action takes still leaks into virtual time, issue 24.)
    let p3 = row(&report, "mean_tokens", "P3");
    assert!(p3["observed"].as_f64().unwrap() < 1e-3, "{p3}");
    assert!((p3["predicted"].as_f64().unwrap() - 4.0 / 7.0).abs() < 1e-12);
    assert_eq!(p3["verdict"], "diverges");
    assert!(p3["p_value"].as_f64().unwrap() < 1e-9, "{p3}");
    // Two agents can share P3 and T3 has one server: how long one stays depends on the
    // other, which the net does not say.
    let holding = row(&report, "holding", "P3 -> T3");
    assert_eq!(holding["verdict"], "no_prediction", "{holding}");
    assert_eq!(
        holding["detail"],
        "T3 has a single server and the place up to 2 tokens: a stay depends on the queue"
    );
    // With it: exit 1, the same report on stdout, the count on stderr.
    let out = conform(&["--json", "--fail-on-drift"]);
    assert_eq!(out.status.code(), Some(1));
    let again: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(again, report);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&format!("{diverging} row(s) diverge")),
        "{stderr}"
    );
    let out = conform(&["--fail-on-drift"]);
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.lines()
            .any(|l| l.starts_with("mean_tokens   P3") && l.ends_with("diverges")),
        "{text}"
    );
    assert!(
        text.contains("no prediction (T3 has a single server and the place up to 2 tokens"),
        "{text}"
    );

    // A run with nothing to flag: 8 time units, too few firings for a rate (10) and no
    // steady state within 1 marking: every row is `too little data` or `no prediction`,
    // and neither fails the gate.
    let short = dir.path().join("short.jsonl");
    journal_to(&short, "plans/cyc3.toml", &["--until", "8"]);
    let cyc3 = repo("plans/cyc3.toml");
    let args = [
        "conform",
        short.to_str().unwrap(),
        "--plan",
        cyc3.to_str().unwrap(),
        "--max-states",
        "1",
        "--fail-on-drift",
    ];
    let out = run(&args);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(text.contains("# 0 of 0 tested rows diverge"), "{text}");
    let mut json = args.to_vec();
    json.push("--json");
    let report = ok_json(&run(&json));
    let verdicts: Vec<&str> = report["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["verdict"].as_str().unwrap())
        .collect();
    assert!(verdicts.contains(&"no_prediction") && verdicts.contains(&"too_little_data"));
    assert!(
        verdicts
            .iter()
            .all(|v| *v == "no_prediction" || *v == "too_little_data")
    );

    // Bad input still exits 2 with the flag.
    let out = run(&[
        "conform",
        "no-such.jsonl",
        "--plan",
        cyc3.to_str().unwrap(),
        "--fail-on-drift",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read no-such.jsonl"));
}

#[test]
fn simulate_and_analyze_start_from_a_journal_point() {
    let dir = tempfile::tempdir().unwrap();
    let j = journal(dir.path(), "plans/cyc3.toml", &["--until", "50"]);
    let plan = repo("plans/cyc3.toml");
    let text = std::fs::read_to_string(&j).unwrap();
    // The first firing of t2 (transition 1): a tangible marking, its seq and tokens.
    let first: Value = text
        .lines()
        .skip(1)
        .map(|l| serde_json::from_str::<Value>(l).unwrap())
        .find(|e| e["event"] == "fired" && e["transition"] == 1)
        .unwrap();
    let seq = first["seq"].as_u64().unwrap();
    let marking: Vec<u64> = first["marking"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect();
    let from = format!("{}:{seq}", j.display());
    let out = run(&[
        "analyze",
        repo("plans/nets/cyc3_ss.PNPRO").to_str().unwrap(),
        "--page",
        "cyc3",
        "--from",
        &from,
        "--transient",
        "0",
        "--json",
    ]);
    let v = ok_json(&out);
    let at0 = &v["transient"][0]["mean_tokens"];
    for (p, k) in ["P1", "P2", "P3"].iter().zip(&marking) {
        assert_eq!(at0[p].as_f64().unwrap(), *k as f64, "{v}");
    }
    let out = run(&[
        "simulate",
        plan.to_str().unwrap(),
        "--from",
        &from,
        "--steps",
        "0",
        "--json",
    ]);
    let v = ok_json(&out);
    assert_eq!(v["trace"].as_array().unwrap().len(), 0);
    let out = run(&[
        "simulate",
        plan.to_str().unwrap(),
        "--from",
        "no-such.jsonl:3",
    ]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn run_monitor_reports_no_drift_on_a_net_timed_run() {
    let out = run(&[
        "run",
        repo("plans/cyc3.toml").to_str().unwrap(),
        "--until",
        "1500",
        "--monitor",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("monitor: 0 drift(s)"), "{stderr}");
    assert!(!stderr.contains("drift:"), "{stderr}");
}

#[cfg(feature = "sim")]
#[test]
fn run_monitor_reports_drift_on_the_goto_transitions_of_robots() {
    let out = run(&[
        "run",
        repo("plans/temperature-patrol/plan.toml").to_str().unwrap(),
        "--robots",
        "3",
        "--until",
        "1200",
        "--monitor",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let drifts: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("drift: "))
        .collect();
    // The transitions that drift are the ones out of the drives (places drift too: their
    // mean tokens follow the drives' times, not the net's).
    let rates: Vec<&&str> = drifts
        .iter()
        .filter(|l| l.contains("firings per unit of enabled time"))
        .collect();
    assert!(rates.len() >= 4, "{stderr}");
    assert!(
        rates.iter().all(|l| l.contains(":Temperature_")),
        "{stderr}"
    );
    // Once per transition or place.
    let mut names: Vec<&str> = drifts
        .iter()
        .map(|l| l.split(' ').nth(1).unwrap())
        .collect();
    names.sort();
    names.dedup();
    assert_eq!(names.len(), drifts.len(), "{stderr}");
}

/// The patrol's location checks per second (the four `Go_Check` transitions) in a JSON
/// `throughput` object.
fn checks_per_second(throughput: &Value) -> f64 {
    let total: f64 = [
        "t6:Go_Check_L2",
        "t12:Go_Check_L3",
        "t18:Go_Check_L4",
        "t24:Go_Check_L1",
    ]
    .iter()
    .map(|t| throughput[t].as_f64().unwrap_or_else(|| panic!("{t}")))
    .sum();
    total
}

/// What the net fitted (`--fit`, at most `max_stages` stages) from journal `j` of the patrol
/// predicts: the steady-state checks per second of a copy of the plan naming the fitted net.
fn fitted_prediction(dir: &Path, j: &Path, max_stages: &str) -> f64 {
    let plan = repo("plans/temperature-patrol/plan.toml");
    let fitted = dir.join(format!("fitted-{max_stages}.xml"));
    ok_json(&run(&[
        "conform",
        j.to_str().unwrap(),
        "--plan",
        plan.to_str().unwrap(),
        "--fit",
        fitted.to_str().unwrap(),
        "--max-stages",
        max_stages,
        "--json",
    ]));
    let text = std::fs::read_to_string(&plan).unwrap();
    let copy = text.replace(
        "net = \"temperature_patrol.xml\"",
        &format!("net = \"fitted-{max_stages}.xml\""),
    );
    assert_ne!(copy, text);
    let copy_path = dir.join(format!("fitted-{max_stages}.toml"));
    std::fs::write(&copy_path, copy).unwrap();
    let v = ok_json(&run(&["analyze", copy_path.to_str().unwrap(), "--json"]));
    // A copy of a plan with a [map] simulates too (the token game ignores the map).
    let sim = ok_json(&run(&[
        "simulate",
        copy_path.to_str().unwrap(),
        "--steps",
        "5",
        "--json",
    ]));
    assert_eq!(sim["trace"].as_array().unwrap().len(), 5);
    checks_per_second(&v["steady_state"]["throughput"])
}

/// The Must-show: the net fitted from one run of the patrol on 3 simulated robots predicts
/// a fresh run's throughput within 5%. The Check stays are a drive (about 11.5 s, spread
/// 0.5 s) after `Go_Check` and a short re-measure (about 0.5 s, exponential) after `AlarmOff`:
/// an exponential holding time (`--max-stages 1`) makes the robots queue behind one another
/// far more than they do and misses by more than 20%; one Erlang chain per way in (20
/// stages for the drive, 1 for the re-measure) comes within 5%.
#[cfg(feature = "sim")]
#[test]
fn the_net_fitted_from_a_robot_run_predicts_a_fresh_runs_throughput() {
    let dir = tempfile::tempdir().unwrap();
    let j = journal(
        dir.path(),
        "plans/temperature-patrol/plan.toml",
        &["--robots", "3", "--until", "2400", "--seed", "1"],
    );
    let fresh = ok_json(&run(&[
        "run",
        repo("plans/temperature-patrol/plan.toml").to_str().unwrap(),
        "--robots",
        "3",
        "--until",
        "2400",
        "--seed",
        "2",
        "--json",
    ]));
    let observed = checks_per_second(&fresh["throughput"]);
    assert!((0.2..0.24).contains(&observed), "{observed}");
    let erlang = fitted_prediction(dir.path(), &j, "20");
    let exponential = fitted_prediction(dir.path(), &j, "1");
    assert!(
        (erlang / observed - 1.0).abs() < 0.05,
        "fitted {erlang} vs observed {observed}"
    );
    assert!(
        exponential / observed < 0.8,
        "exponential fit {exponential} vs observed {observed}"
    );
}
