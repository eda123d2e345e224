//! The decision model of the GSPNR toolbox's fixtures has the toolbox's MDP size: every
//! reachable marking plus one WAIT copy per hybrid marking (../shared/fixtures/gspnr/README.md,
//! S1–S4), and its uniformisation constant eta (S7).

use gspn::analysis::decision::{Controls, DecisionModel, Kind};
use gspn::io::{ReadOptions, read_net};
use gspn::net::Net;

use crate::support::fixture;

/// The net and the toolbox's controls (`controllable`, `wait`) of a fixture.
pub(crate) fn gspnr(name: &str) -> (Net, Controls, toml::Table) {
    let net = read_net(
        &fixture(&format!("gspnr/{name}/net.PNPRO")),
        &ReadOptions::default(),
    )
    .unwrap()
    .net;
    let text = std::fs::read_to_string(fixture(&format!("gspnr/{name}/rewards.toml"))).unwrap();
    let table: toml::Table = text.parse().unwrap();
    let names: Vec<_> = table["controllable"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| net.transition_by_name(v.as_str().unwrap()).unwrap())
        .collect();
    let mut controls = Controls::of(&net, &names);
    controls.wait = table["wait"].as_bool().unwrap();
    // The fixtures' controllable transitions are exactly the zero-weight ones (S1).
    assert_eq!(
        controls,
        Controls {
            wait: controls.wait,
            ..Controls::zero_weight(&net)
        }
    );
    (net, controls, table)
}

fn recorded(name: &str) -> serde_json::Value {
    let text =
        std::fs::read_to_string(fixture(&format!("gspnr/{name}/toolbox_recorded.json"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn build(net: &Net, controls: &Controls) -> DecisionModel {
    DecisionModel::build(net, controls, &Default::default()).unwrap()
}

#[test]
fn home_model_without_wait_has_the_toolbox_state_counts_for_1_to_6_robots() {
    let expected = [13, 86, 389, 1385, 4167, 11046];
    for (i, &n) in expected.iter().enumerate() {
        let name = format!("home_n{:02}", i + 1);
        let (net, mut controls, _) = gspnr(&name);
        controls.wait = false;
        let model = build(&net, &controls);
        assert_eq!(model.toolbox_state_count(), n, "{name}");
        assert_eq!(
            recorded(&name)["mdp_states_without_wait"].as_u64(),
            Some(n as u64)
        );
        // No weighted immediate transitions: nothing is eliminated, every marking is a state.
        assert_eq!((model.state_count(), model.wait_copies()), (n, 0), "{name}");
    }
}

#[test]
fn home_model_with_10_robots_has_238403_states_and_eta_35_3() {
    let (net, mut controls, _) = gspnr("home_n10");
    controls.wait = false;
    let model = build(&net, &controls);
    assert_eq!(model.toolbox_state_count(), 238_403);
    assert!((model.eta() - 35.3).abs() < 1e-9, "eta {}", model.eta());
}

#[test]
fn fixtures_with_wait_have_the_toolbox_state_and_wait_copy_counts() {
    for name in [
        "home_meeting_place_rewards",
        "solarfarm_2timeouts_experiment",
        "solarfarm_notimeouts",
        "home_timeouts_meeting",
        "solarfarm_globalcounter_2robots",
        "solarfarm_2timeouts",
    ] {
        let (net, controls, _) = gspnr(name);
        assert!(controls.wait, "{name}");
        let model = build(&net, &controls);
        let mdp = &recorded(name)["mdp"];
        assert_eq!(
            model.toolbox_state_count() as u64,
            mdp["nStates"].as_u64().unwrap(),
            "{name}"
        );
        assert_eq!(
            model.wait_copies() as u64,
            mdp["n_wait_states"].as_u64().unwrap(),
            "{name}"
        );
        assert!(
            (model.eta() - mdp["eta"].as_f64().unwrap()).abs() < 1e-9,
            "{name}: eta {}",
            model.eta()
        );
    }
}

#[test]
fn fixtures_with_weighted_races_count_every_marking_and_eliminate_the_races() {
    for name in ["solarfarm_battery_1uav", "solarfarm_battery_4th"] {
        let (net, controls, _) = gspnr(name);
        let model = build(&net, &controls);
        let mdp = &recorded(name)["mdp"];
        assert_eq!(
            model.toolbox_state_count() as u64,
            mdp["nStates"].as_u64().unwrap(),
            "{name}"
        );
        assert!(
            (model.eta() - mdp["eta"].as_f64().unwrap()).abs() < 1e-9,
            "{name}"
        );
        assert!(model.eliminated_count() > 0, "{name}");
        assert_eq!(
            model.state_count() + model.eliminated_count(),
            model.marking_count(),
            "{name}"
        );
        // Kept races give the toolbox's MDP exactly.
        let kept = DecisionModel::build(
            &net,
            &Controls {
                keep_races: true,
                ..controls
            },
            &Default::default(),
        )
        .unwrap();
        assert_eq!(kept.state_count(), kept.toolbox_state_count(), "{name}");
    }
}

#[test]
fn small_fixtures_have_the_states_their_readme_describes() {
    // tiny_cycle: p1 (decision t1) → p2+p3 (Markovian, rate 1) → p4 (decision t3) → p1.
    let (net, controls, _) = gspnr("tiny_cycle");
    let model = build(&net, &controls);
    assert_eq!((model.state_count(), model.wait_copies()), (3, 0));
    // small_hybrid with WAIT: p1 offers t1, t2 and WAIT; the copy races t3; three dead ends.
    let (net, controls, _) = gspnr("small_hybrid");
    let model = build(&net, &controls);
    assert_eq!((model.state_count(), model.wait_copies()), (5, 1));
    assert_eq!(model.choices(0).len(), 3);
    let dead = (0..model.state_count())
        .filter(|&s| model.kind(s) == Kind::Dead)
        .count();
    assert_eq!(dead, 3);
    // tomdp_test: sizes with and without WAIT.
    let (net, mut controls, _) = gspnr("tomdp_test");
    let with = build(&net, &controls);
    controls.wait = false;
    let without = build(&net, &controls);
    assert!(with.toolbox_state_count() > without.toolbox_state_count());
    assert_eq!(without.wait_copies(), 0);
}

/// The fixture's reward structure (`[places]` marked, `[transitions]` impulses).
pub(crate) fn fixture_rewards(
    net: &Net,
    table: &toml::Table,
) -> gspn::analysis::decision::RewardSpec {
    use gspn::analysis::decision::{PlaceMode, RewardSpec};
    let mut spec = RewardSpec {
        name: "r".into(),
        ..RewardSpec::default()
    };
    for (name, v) in table["places"].as_table().unwrap() {
        let p = net.place_by_name(name).unwrap();
        spec.places.push((
            p,
            v.as_float().or(v.as_integer().map(|i| i as f64)).unwrap(),
            PlaceMode::Marked,
        ));
    }
    for (name, v) in table["transitions"].as_table().unwrap() {
        let t = net.transition_by_name(name).unwrap();
        spec.transitions.push((
            t,
            v.as_float().or(v.as_integer().map(|i| i as f64)).unwrap(),
        ));
    }
    spec
}
