//! The state space agrees with published answers: the Model Checking Contest oracles
//! (states, arcs, max tokens in a place and per marking, deadlock verdict), the Kanban GSPN
//! tangible counts, the thesis nets' reference counts, dead markings and bounds, and the
//! unbounded resource place of the thesis's ROS example.

use crate::support::fixtures as shared_fixtures;

use std::collections::BTreeSet;

use gspn::analysis::properties::Properties;
use gspn::analysis::state_space::{AnalysisError, Options, StateSpace};
use gspn::io::{ReadOptions, read_net};
use shared_fixtures::{fixture, root};

fn load(rel: &str) -> gspn::net::Net {
    read_net(&fixture(rel), &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{rel}: {e}"))
        .net
}

fn oracle_value(text: &str, key: &str) -> u64 {
    text.lines()
        .find_map(|l| {
            let mut w = l.split_whitespace();
            (w.next() == Some("STATE_SPACE") && w.next() == Some(key))
                .then(|| w.next().and_then(|v| v.parse().ok()))
                .flatten()
        })
        .unwrap_or_else(|| panic!("no {key} in oracle"))
}

#[test]
fn every_mcc_model_with_an_oracle_matches_it_exactly() {
    let mut checked = 0;
    let mut dirs: Vec<_> = std::fs::read_dir(root().join("mcc"))
        .expect("mcc fixtures")
        .map(|e| e.expect("entry").path())
        .collect();
    dirs.sort();
    for dir in dirs {
        let Ok(oracle) = std::fs::read_to_string(dir.join("StateSpace-oracle-2021.out")) else {
            continue;
        };
        let name = dir.file_name().unwrap().to_string_lossy().to_string();
        let net = read_net(&dir.join("model.pnml"), &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .net;
        let ss =
            StateSpace::build(&net, &Options::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let p = Properties::compute(&net, &ss);
        assert_eq!(
            p.reachable as u64,
            oracle_value(&oracle, "STATES"),
            "{name} states"
        );
        assert_eq!(
            p.edges as u64,
            oracle_value(&oracle, "TRANSITIONS"),
            "{name} arcs"
        );
        assert_eq!(
            p.max_tokens_in_place as u64,
            oracle_value(&oracle, "MAX_TOKEN_IN_PLACE"),
            "{name} max tokens in a place"
        );
        assert_eq!(
            p.max_tokens_per_marking,
            oracle_value(&oracle, "MAX_TOKEN_PER_MARKING"),
            "{name} max tokens per marking"
        );
        if let Ok(rd) = std::fs::read_to_string(dir.join("RD-oracle-2018.out")) {
            let deadlock = rd
                .lines()
                .find(|l| l.starts_with("FORMULA"))
                .map(|l| l.split_whitespace().nth(2) == Some("TRUE"))
                .expect("a verdict");
            assert_eq!(!p.deadlock_free, deadlock, "{name} deadlock verdict");
        }
        checked += 1;
    }
    assert_eq!(checked, 10, "MCC models with a StateSpace oracle");
}

#[test]
fn kanban_gspn_tangible_counts() {
    for (n, want) in [(1, 160), (2, 4_600), (3, 58_400)] {
        let net = load(&format!("kanban/kanban_gspn_N{n}.pnml"));
        let ss = StateSpace::build(&net, &Options::default()).unwrap();
        assert_eq!(ss.tangible_count(), want, "Kanban N={n}");
    }
}

#[test]
fn thesis_nets_match_the_reference_counts_dead_markings_and_bounds() {
    let text = std::fs::read_to_string(fixture("reference/thesis_nets_reference.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut checked = 0;
    for (rel, r) in reference.as_object().unwrap() {
        if rel == "_about" {
            continue;
        }
        let net = load(rel);
        let ss =
            StateSpace::build(&net, &Options::default()).unwrap_or_else(|e| panic!("{rel}: {e}"));
        let p = Properties::compute(&net, &ss);
        assert_eq!(
            p.reachable as u64,
            r["reachable_markings"].as_u64().unwrap(),
            "{rel}"
        );
        assert_eq!(p.tangible as u64, r["tangible"].as_u64().unwrap(), "{rel}");
        assert_eq!(
            p.vanishing as u64,
            r["vanishing"].as_u64().unwrap(),
            "{rel}"
        );
        let dead: BTreeSet<String> = p
            .dead_markings
            .iter()
            .map(|d| net.format_marking(&d.marking))
            .collect();
        let want: BTreeSet<String> = r["dead_markings"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().to_string())
            .collect();
        assert_eq!(dead, want, "{rel} dead markings");
        for (place, bound) in r["place_bounds"].as_object().unwrap() {
            let pid = net
                .place_by_name(place)
                .unwrap_or_else(|| panic!("{rel}: {place}"));
            assert_eq!(
                p.place_bounds[pid.index()] as u64,
                bound.as_u64().unwrap(),
                "{rel} bound of {place}"
            );
        }
        for d in &p.dead_markings {
            // The firing sequence really leads there.
            let mut m = net.initial_marking();
            for &t in &d.path {
                assert!(
                    net.is_enabled(&m, t),
                    "{rel}: path fires a disabled transition"
                );
                net.fire(&mut m, t).unwrap();
            }
            assert_eq!(m.as_slice(), d.marking.as_slice(), "{rel}");
        }
        checked += 1;
    }
    assert_eq!(checked, 16);
}

#[test]
fn ros_example_is_unbounded_through_its_resource_place() {
    let net = load("thesis/caldeira_2020_package/ros_Example/example_gspn.xml");
    assert_eq!(
        StateSpace::build(&net, &Options::default()).err(),
        Some(AnalysisError::Unbounded {
            places: vec!["p4".into()]
        })
    );
}
