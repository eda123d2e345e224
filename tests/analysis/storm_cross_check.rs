//! Storm (stormpy from PyPI, in the venv `.ci/run` makes at target/venv-ros2) loads our DRN
//! export of GSPNR fixtures and finds the same optimal long-run average reward to 1e-6.

use std::path::Path;
use std::process::Command;

use gspn::analysis::decision::{DecisionModel, Objective, SolveOptions, solve};
use gspn::io::drn;

use super::decision_model::{fixture_rewards, gspnr};

const SCRIPT: &str = r#"
import sys, stormpy
env = stormpy.Environment()
prop = stormpy.parse_properties('R{"r"}max=? [LRA]')[0]
for path in sys.argv[1:]:
    m = stormpy.build_model_from_drn(path)
    r = stormpy.model_checking(m, prop, environment=env)
    print(repr(r.get_value(m.initial_states[0])))
"#;

#[test]
fn storm_finds_our_optimal_long_run_average_on_four_fixtures() {
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/venv-ros2/bin/python");
    assert!(
        python.exists(),
        "{} missing: run .ci/run (it makes the venv and installs stormpy)",
        python.display()
    );
    let dir = tempfile::tempdir().unwrap();
    let mut ours = Vec::new();
    let mut files = Vec::new();
    for name in [
        "tiny_cycle",
        "home_n03",
        "home_meeting_place_rewards",
        "solarfarm_notimeouts",
    ] {
        let (net, controls, table) = gspnr(name);
        let model = DecisionModel::build(&net, &controls, &Default::default()).unwrap();
        let rewards = model.rewards(&fixture_rewards(&net, &table));
        let sol = solve(
            &model,
            &rewards,
            &Objective::Lra { max: true },
            &SolveOptions::default(),
        )
        .unwrap();
        let path = dir.path().join(format!("{name}.drn"));
        std::fs::write(&path, drn::to_string(&net, &model, &[("r", &rewards)], &[])).unwrap();
        ours.push((name, sol.value));
        files.push(path);
    }
    let out = Command::new(&python)
        .arg("-c")
        .arg(SCRIPT)
        .args(&files)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "stormpy failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let storm: Vec<f64> = text.lines().map(|l| l.trim().parse().unwrap()).collect();
    assert_eq!(storm.len(), ours.len(), "{text}");
    for ((name, v), s) in ours.iter().zip(&storm) {
        assert!(
            (v - s).abs() <= 1e-6 * v.abs().max(1.0),
            "{name}: ours {v}, Storm {s}"
        );
    }
    // Not all trivially zero: the fixtures earn something.
    assert!(ours.iter().all(|&(_, v)| v > 0.0), "{ours:?}");
}
