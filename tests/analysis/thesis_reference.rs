//! Every net of `reference/thesis_nets_reference.json` (an independent solver's answers)
//! matches to 1e-9: counts, dead markings, bounds, ergodicity, steady or limiting
//! distribution, expected tokens, P(N=1), throughputs, mean waiting times, and π(t) at
//! t = 0.5, 1, 5.

use crate::support::fixtures as shared_fixtures;

use std::collections::BTreeMap;

use gspn::analysis::measures::{Solver, SolverOptions, TransientOptions};
use gspn::analysis::state_space::{Options, StateSpace};
use gspn::io::{ReadOptions, read_net};
use serde_json::Value;
use shared_fixtures::fixture;

const TOL: f64 = 1e-9;

fn check_distribution(
    what: &str,
    net: &gspn::net::Net,
    ss: &StateSpace,
    pi: &[f64],
    expected: &Value,
) -> Vec<String> {
    let mut errors = Vec::new();
    let mut ours: BTreeMap<String, f64> = BTreeMap::new();
    for (s, &p) in pi.iter().enumerate() {
        *ours.entry(net.format_marking(&ss.marking(s))).or_default() += p;
    }
    let exp = expected.as_object().expect("a distribution");
    for (m, v) in exp {
        let e = v.as_f64().unwrap();
        let o = ours.get(m).copied().unwrap_or(0.0);
        if (o - e).abs() > TOL {
            errors.push(format!("{what}: P({m}) = {o}, expected {e}"));
        }
    }
    for (m, &o) in &ours {
        if !exp.contains_key(m) && o.abs() > TOL {
            errors.push(format!("{what}: P({m}) = {o}, expected 0"));
        }
    }
    errors
}

fn check_net(path: &str, r: &Value) -> Vec<String> {
    let mut errors = Vec::new();
    let loaded = match read_net(&fixture(path), &ReadOptions::default()) {
        Ok(l) => l,
        Err(e) => return vec![format!("does not load: {e}")],
    };
    let net = &loaded.net;
    let ss = match StateSpace::build(net, &Options::default()) {
        Ok(ss) => ss,
        Err(e) => return vec![format!("no state space: {e}")],
    };
    let count = |k: &str| r[k].as_u64().unwrap() as usize;
    if ss.reachable_count() != count("reachable_markings")
        || ss.tangible_count() != count("tangible")
        || ss.vanishing_count() != count("vanishing")
    {
        errors.push(format!(
            "counts {}/{}/{}",
            ss.reachable_count(),
            ss.tangible_count(),
            ss.vanishing_count()
        ));
    }
    let mut dead: Vec<String> = ss
        .dead_states()
        .iter()
        .map(|&s| net.format_marking(&ss.marking(s as usize)))
        .collect();
    dead.sort();
    let mut exp_dead: Vec<String> = r["dead_markings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    exp_dead.sort();
    if dead != exp_dead {
        errors.push(format!("dead markings {dead:?}, expected {exp_dead:?}"));
    }
    let mut bounds = vec![0u32; net.place_count()];
    for g in 0..ss.reachable_count() {
        for (b, k) in bounds.iter_mut().zip(ss.global_marking(g)) {
            *b = (*b).max(k);
        }
    }
    let place = |name: &str| {
        net.place_by_name(name)
            .unwrap_or_else(|| panic!("{path}: place {name}"))
    };
    let transition = |name: &str| {
        net.transition_by_name(name)
            .unwrap_or_else(|| panic!("{path}: transition {name}"))
    };
    for (p, v) in r["place_bounds"].as_object().unwrap() {
        if bounds[place(p).index()] as u64 != v.as_u64().unwrap() {
            errors.push(format!("bound of {p}: {}", bounds[place(p).index()]));
        }
    }
    let solver = Solver::new(net, &ss);
    let steady = solver
        .steady_state(&SolverOptions::default())
        .expect("steady state");
    if steady.ergodic != r["ergodic"].as_bool().unwrap() {
        errors.push(format!("ergodic = {}", steady.ergodic));
    }
    assert!(solver.chain().residual(&steady.pi) <= 1e-10);
    errors.extend(check_distribution(
        "steady",
        net,
        &ss,
        &steady.pi,
        &r["steady_state"],
    ));
    let m = solver.measures(&steady.pi);
    for (p, v) in r["expected_tokens"].as_object().unwrap() {
        let o = m.mean_tokens[place(p).index()];
        if (o - v.as_f64().unwrap()).abs() > TOL {
            errors.push(format!("E[{p}] = {o}, expected {v}"));
        }
    }
    for (p, v) in r["prob_exactly_one_token"].as_object().unwrap() {
        let o = m.token_distribution[place(p).index()]
            .get(1)
            .copied()
            .unwrap_or(0.0);
        if (o - v.as_f64().unwrap()).abs() > TOL {
            errors.push(format!("P({p}=1) = {o}, expected {v}"));
        }
    }
    for (t, v) in r["throughput"].as_object().unwrap() {
        let o = m.throughput[transition(t).index()];
        if (o - v.as_f64().unwrap()).abs() > TOL {
            errors.push(format!("X({t}) = {o}, expected {v}"));
        }
    }
    for (p, v) in r["mean_wait_time"].as_object().unwrap() {
        let o = m.mean_wait[place(p).index()];
        let ok = match (o, v.as_f64()) {
            (None, None) => true,
            (Some(a), Some(b)) => (a - b).abs() <= TOL * b.abs().max(1.0),
            _ => false,
        };
        if !ok {
            errors.push(format!("W({p}) = {o:?}, expected {v}"));
        }
    }
    let times: Vec<(String, f64)> = r["transient"]
        .as_object()
        .unwrap()
        .keys()
        .map(|k| (k.clone(), k.parse().unwrap()))
        .collect();
    let opts = TransientOptions {
        eps: 1e-13,
        ..TransientOptions::default()
    };
    let at = solver
        .transient(&times.iter().map(|t| t.1).collect::<Vec<_>>(), &opts)
        .unwrap();
    for ((key, _), pi) in times.iter().zip(&at) {
        errors.extend(check_distribution(
            &format!("π({key})"),
            net,
            &ss,
            pi,
            &r["transient"][key],
        ));
    }
    errors
}

#[test]
fn every_reference_net_matches_the_independent_solver() {
    let text = std::fs::read_to_string(fixture("reference/thesis_nets_reference.json")).unwrap();
    let all: Value = serde_json::from_str(&text).unwrap();
    let mut failures = Vec::new();
    let mut checked = 0;
    for (path, r) in all.as_object().unwrap() {
        if path.starts_with('_') {
            continue;
        }
        checked += 1;
        let errors = check_net(path, r);
        if !errors.is_empty() {
            failures.push(format!("{path}:\n  {}", errors.join("\n  ")));
        }
    }
    assert_eq!(checked, 16);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn cyc3(file: &str) -> (gspn::net::Net, StateSpace) {
    let net = read_net(&fixture(file), &ReadOptions::default())
        .unwrap()
        .net;
    let ss = StateSpace::build(&net, &Options::default()).unwrap();
    (net, ss)
}

#[test]
fn cyc3_single_server_matches_its_closed_form() {
    let (net, ss) = cyc3("greatspn/cyc3/cyc3_ss.PNPRO");
    assert_eq!(ss.tangible_count(), 3);
    let solver = Solver::new(&net, &ss);
    let steady = solver.steady_state(&SolverOptions::default()).unwrap();
    assert!(steady.ergodic);
    // π over (P1,P2,P3) = (2,0,0), (1,0,1), (0,0,2) is (4,2,1)/7.
    for (s, &p) in steady.pi.iter().enumerate() {
        let expect = match ss.marking(s).as_slice() {
            [2, 0, 0] => 4.0 / 7.0,
            [1, 0, 1] => 2.0 / 7.0,
            [0, 0, 2] => 1.0 / 7.0,
            m => panic!("unexpected marking {m:?}"),
        };
        assert!((p - expect).abs() < 1e-12);
    }
    let m = solver.measures(&steady.pi);
    let p = |n: &str| net.place_by_name(n).unwrap().index();
    assert!((m.mean_tokens[p("P1")] - 10.0 / 7.0).abs() < 1e-12);
    assert_eq!(m.mean_tokens[p("P2")], 0.0);
    assert!((m.mean_tokens[p("P3")] - 4.0 / 7.0).abs() < 1e-12);
    for x in &m.throughput {
        assert!((x - 6.0 / 7.0).abs() < 1e-12, "{:?}", m.throughput);
    }
}

#[test]
fn cyc3_infinite_server_matches_its_closed_form() {
    let (net, ss) = cyc3("greatspn/cyc3/cyc3.PNPRO");
    let solver = Solver::new(&net, &ss);
    let steady = solver.steady_state(&SolverOptions::default()).unwrap();
    let m = solver.measures(&steady.pi);
    let p = |n: &str| net.place_by_name(n).unwrap().index();
    assert!((m.mean_tokens[p("P1")] - 4.0 / 3.0).abs() < 1e-12);
    assert!((m.mean_tokens[p("P3")] - 2.0 / 3.0).abs() < 1e-12);
}
