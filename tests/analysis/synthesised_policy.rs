//! A synthesised policy, written as `[[policy]]` rules, is worth what the solver said: its
//! exact evaluation (the CTMC it induces) equals the optimum to 1e-9; its compressed rules
//! choose like the exact table in every reachable decision marking; and a long seeded token
//! game under it earns the optimal long-run reward rate (within its 95% interval).

use gspn::analysis::decision::{
    Action, Controls, DecisionModel, Kind, Objective, PlaceMode, RewardSpec, SolveOptions,
    compress, evaluate_lra, solve,
};
use gspn::analysis::measures::SolverOptions;
use gspn::analysis::state_space::{Monitor, Options};
use gspn::analysis::under_policy::{Regime, analyse};
use gspn::net::{Net, TransitionId};
use gspn::policy::{Pattern, Policy, Rule};
use gspn::sim::Simulator;

use super::decision_model::gspnr;

/// Home cleaning with `name`'s robots: 1 per unit of time per room being mopped, 0.5 per room
/// being vacuumed, 2 per mopping of L2 finished.
fn home(name: &str) -> (Net, Controls, RewardSpec) {
    let (net, mut controls, _) = gspnr(name);
    controls.wait = false;
    let mut spec = RewardSpec {
        name: "cleaning".into(),
        ..RewardSpec::default()
    };
    for l in ["L1", "L2", "L3"] {
        let mop = net.place_by_name(&format!("Mopping_{l}")).unwrap();
        let vac = net.place_by_name(&format!("Vacuuming_{l}")).unwrap();
        spec.places.push((mop, 1.0, PlaceMode::Marked));
        spec.places.push((vac, 0.5, PlaceMode::Marked));
    }
    let fin = net.transition_by_name("FinishedMop_L2").unwrap();
    spec.transitions.push((fin, 2.0));
    (net, controls, spec)
}

/// [`home`]'s net and reward, its decision model (no WAIT) and the model's rewards.
fn home_model(
    name: &str,
) -> (
    Net,
    RewardSpec,
    DecisionModel,
    gspn::analysis::decision::Rewards,
) {
    let (net, controls, spec) = home(name);
    let model = DecisionModel::build(&net, &controls, &Default::default()).unwrap();
    let rewards = model.rewards(&spec);
    (net, spec, model, rewards)
}

/// The exact table of a solution: (decision marking, transition fired).
fn table(model: &DecisionModel, policy: &[u32]) -> Vec<(Vec<u32>, TransitionId)> {
    (0..model.state_count())
        .filter(|&s| model.kind(s) == Kind::Instant && model.choices(s).len() > 1)
        .filter_map(|s| match model.action(policy[s] as usize) {
            Action::Fire(t) => Some((model.marking(s), t)),
            _ => None,
        })
        .collect()
}

fn exact_rules(table: &[(Vec<u32>, TransitionId)]) -> Vec<Rule> {
    table
        .iter()
        .map(|(m, t)| Rule {
            pattern: Pattern::Exact(m.clone()),
            choose: vec![(*t, 1.0)],
        })
        .collect()
}

/// The policy's choice in model state `s`, through the policy lookup `run` uses.
fn lookup(model: &DecisionModel, net: &Net, policy: &Policy, s: usize) -> Vec<(usize, f64)> {
    let m = model.marking(s);
    let firable = net.firable(&m);
    let d = policy
        .distribution(&m, &firable)
        .expect("a rule for every decision marking");
    d.iter()
        .map(|&(t, p)| {
            let c = model
                .choices(s)
                .find(|&c| model.action(c) == Action::Fire(t))
                .expect("the chosen transition is a choice");
            (c, p)
        })
        .collect()
}

#[test]
fn the_written_policy_is_worth_the_optimum_exactly() {
    let (net, _, model, rewards) = home_model("home_n03");
    let sol = solve(
        &model,
        &rewards,
        &Objective::Lra { max: true },
        &SolveOptions::default(),
    )
    .unwrap();
    assert!(sol.upper - sol.lower <= 1e-9 * sol.value.abs());
    let table = table(&model, &sol.policy);
    assert!(!table.is_empty());
    let policy = Policy::new(&net, exact_rules(&table)).unwrap();
    let v = evaluate_lra(&model, &rewards, |s| lookup(&model, &net, &policy, s)).unwrap();
    assert!(
        (v.lra - sol.value).abs() <= 1e-9 * sol.value.abs(),
        "policy {} vs optimum {} [{}, {}]",
        v.lra,
        sol.value,
        sol.lower,
        sol.upper
    );
    // A worse policy (always the first choice) is worth less: the test can tell them apart.
    let first = evaluate_lra(&model, &rewards, |s| vec![(model.choices(s).start, 1.0)]).unwrap();
    assert!(
        first.lra < sol.lower - 1e-3,
        "{} vs {}",
        first.lra,
        sol.lower
    );
}

/// `analyze PLAN`'s library function: the net under the written policy (state space with the
/// policy in vanishing markings, steady state, throughputs) earns the optimum, where the bare
/// net (its weights: a uniform choice among zero-weight transitions) earns less.
#[test]
fn the_net_under_the_written_policy_earns_the_optimum() {
    let (net, spec, model, rewards) = home_model("home_n03");
    let sol = solve(
        &model,
        &rewards,
        &Objective::Lra { max: true },
        &SolveOptions::default(),
    )
    .unwrap();
    let policy = Policy::new(&net, exact_rules(&table(&model, &sol.policy))).unwrap();
    let run = |policy: &Policy| {
        analyse(
            &net,
            policy,
            std::slice::from_ref(&spec),
            &Options::default(),
            &SolverOptions::default(),
        )
        .unwrap()
    };
    let under = run(&policy);
    assert_eq!(under.regime, Regime::UnderPolicy);
    assert_eq!(under.regime.label(), "net under plan policy");
    assert_eq!(under.rewards.len(), 1);
    let r = &under.rewards[0];
    assert_eq!(r.name, "cleaning");
    assert!(
        (r.rate - sol.value).abs() <= 1e-9 * sol.value.abs(),
        "analysis {} vs optimum {}",
        r.rate,
        sol.value
    );
    assert!((r.places + r.transitions - r.rate).abs() < 1e-15);
    // The impulse part is 2 × the throughput of FinishedMop_L2.
    let fin = net.transition_by_name("FinishedMop_L2").unwrap();
    assert!((r.transitions - 2.0 * under.measures.throughput[fin.index()]).abs() < 1e-15);
    let bare = run(&Policy::empty());
    assert_eq!(bare.regime, Regime::BareNet);
    assert_eq!(bare.regime.label(), "bare net");
    assert!(
        bare.rewards[0].rate < sol.lower - 1e-3,
        "bare {} vs optimum {}",
        bare.rewards[0].rate,
        sol.lower
    );
}

#[test]
fn compressed_rules_choose_like_the_exact_table_everywhere() {
    for name in ["home_n03", "home_n05"] {
        let (net, _, model, rewards) = home_model(name);
        let sol = solve(
            &model,
            &rewards,
            &Objective::Lra { max: true },
            &SolveOptions::default(),
        )
        .unwrap();
        let table = table(&model, &sol.policy);
        let rules = compress(&table);
        assert!(
            rules.len() < table.len(),
            "{name}: {} rules for {} markings",
            rules.len(),
            table.len()
        );
        let policy = Policy::new(&net, rules).unwrap();
        for (m, t) in &table {
            let d = policy.distribution(m, &net.firable(m)).unwrap();
            assert_eq!(d, vec![(*t, 1.0)], "{name}: {m:?}");
        }
    }
}

#[test]
fn a_long_token_game_under_the_policy_earns_the_optimal_rate() {
    let (net, spec, model, rewards) = home_model("home_n02");
    let sol = solve(
        &model,
        &rewards,
        &Objective::Lra { max: true },
        &SolveOptions::default(),
    )
    .unwrap();
    let policy = Policy::new(&net, exact_rules(&table(&model, &sol.policy))).unwrap();
    // Batch means: 40 batches of 500 time units, each the reward earned per unit of time.
    let (batches, len) = (40usize, 500.0);
    let mut earned = vec![0.0f64; batches];
    let mut sim = Simulator::new(net.clone(), 2024).with_policy(policy.clone());
    let rate = |m: &[u32]| -> f64 {
        spec.places
            .iter()
            .map(|&(p, r, _)| if m[p.index()] > 0 { r } else { 0.0 })
            .sum()
    };
    let impulse = |t: TransitionId| -> f64 {
        spec.transitions
            .iter()
            .filter(|&&(u, _)| u == t)
            .map(|&(_, r)| r)
            .sum()
    };
    let end = batches as f64 * len;
    loop {
        // The rate of the marking held until the next firing, spread over the batches.
        let held = if sim.is_vanishing() {
            0.0
        } else {
            rate(sim.marking().as_slice())
        };
        let mut from = sim.time();
        let step = sim.step_until(end).unwrap();
        let to = sim.time();
        while from < to {
            let b = ((from / len) as usize).min(batches - 1);
            let stop = to.min((b + 1) as f64 * len);
            let stop = if b == batches - 1 { to } else { stop };
            earned[b] += held * (stop - from);
            from = stop;
        }
        match step {
            Some(s) => earned[((s.time / len) as usize).min(batches - 1)] += impulse(s.transition),
            None => break,
        }
    }
    let xs: Vec<f64> = earned.iter().map(|e| e / len).collect();
    let measured = xs.iter().sum::<f64>() / batches as f64;
    let var = xs.iter().map(|x| (x - measured).powi(2)).sum::<f64>() / (batches - 1) as f64;
    // Student t, 39 degrees of freedom, 97.5%.
    let half = 2.0227 * (var / batches as f64).sqrt();
    assert!(
        half < 0.05 * sol.value,
        "interval too wide to tell: ± {half}"
    );
    assert!(
        (measured - sol.value).abs() <= half,
        "measured {measured} (± {half}) vs optimum {}",
        sol.value
    );
}

/// The optimal long-run average by `algorithm`.
fn lra(
    model: &DecisionModel,
    rewards: &gspn::analysis::decision::Rewards,
    max: bool,
    algorithm: gspn::analysis::decision::Algorithm,
) -> Result<gspn::analysis::decision::Solution, gspn::analysis::decision::DecisionError> {
    let opts = SolveOptions {
        algorithm,
        ..SolveOptions::default()
    };
    solve(model, rewards, &Objective::Lra { max }, &opts)
}

/// Policy iteration (exact evaluation, then one bounding step) and value
/// iteration agree to 1e-9 on the fixtures Storm checks (`storm_cross_check.rs`) and on the
/// home model with the cleaning rewards, max and min (relative to the value, absolute below
/// 1: some minima are 0); each says which method ran, and the policy iteration's policy is
/// worth its value exactly.
#[test]
fn policy_iteration_agrees_with_value_iteration() {
    use super::decision_model::fixture_rewards;
    use gspn::analysis::decision::{Algorithm, Method};
    let mut cases: Vec<(String, Net, Controls, RewardSpec)> = Vec::new();
    for name in [
        "tiny_cycle",
        "home_n03",
        "home_meeting_place_rewards",
        "solarfarm_notimeouts",
    ] {
        let (net, controls, table) = gspnr(name);
        let spec = fixture_rewards(&net, &table);
        cases.push((name.to_string(), net, controls, spec));
    }
    let (net, controls, spec) = home("home_n04");
    cases.push(("home_n04 cleaning".into(), net, controls, spec));
    for (name, net, controls, spec) in &cases {
        let model = DecisionModel::build(net, controls, &Default::default()).unwrap();
        let rewards = model.rewards(spec);
        for max in [true, false] {
            let run = |algorithm| {
                lra(&model, &rewards, max, algorithm)
                    .unwrap_or_else(|e| panic!("{name} max={max} {algorithm:?}: {e}"))
            };
            let vi = run(Algorithm::ValueIteration);
            let pi = run(Algorithm::PolicyIteration);
            assert_eq!(vi.method, Method::RelativeValueIteration);
            assert_eq!(pi.method, Method::PolicyIteration);
            assert!(
                (vi.value - pi.value).abs() <= 1e-9 * vi.value.abs().max(1.0),
                "{name} max={max}: value iteration {} [{}, {}], policy iteration {} [{}, {}]",
                vi.value,
                vi.lower,
                vi.upper,
                pi.value,
                pi.lower,
                pi.upper
            );
            assert!(pi.lower <= pi.upper && pi.upper - pi.lower <= 1e-9 * pi.value.abs().max(1.0));
            let exact =
                evaluate_lra(&model, &rewards, |s| vec![(pi.policy[s] as usize, 1.0)]).unwrap();
            assert!(
                (exact.lra - pi.value).abs() <= 1e-9 * pi.value.abs().max(1.0),
                "{name} max={max}: the policy is worth {}, policy iteration said {}",
                exact.lra,
                pi.value
            );
        }
    }
}

/// Policy iteration solves the policy's equations component by component (dense LU up to 48
/// states, sparse LU above): a token leaves a transient ring of 55 places (a component of 55
/// states), then chooses for ever between ring A (60 places, rates 1–3, reward `i mod 5`
/// while on place `i`) and ring B (20 places, reward 1). Each ring's gain is
/// `Σ reward/rate ÷ Σ 1/rate`; policy iteration finds the better (max) and the worse (min)
/// to 1e-12, value iteration to its precision 1e-9.
#[test]
fn policy_iteration_solves_large_components_exactly() {
    use gspn::analysis::decision::{Algorithm, Method};
    use gspn::net::{NetBuilder, Servers};
    let mut b = NetBuilder::new("rings");
    let choose = b.place("Choose", 0);
    let mut spec = RewardSpec {
        name: "r".into(),
        ..RewardSpec::default()
    };
    // A ring of `k` places entered from Choose by controllable `enter`, back to Choose.
    let mut ring = |b: &mut NetBuilder,
                    name: &str,
                    k: usize,
                    rate: &dyn Fn(usize) -> f64,
                    reward: &dyn Fn(usize) -> f64| {
        let places: Vec<_> = (0..k).map(|i| b.place(format!("{name}{i}"), 0)).collect();
        let enter = b.immediate(format!("enter_{name}"), 0.0, 1);
        b.input(choose, enter, 1);
        b.output(enter, places[0], 1);
        for i in 0..k {
            let t = b.exponential(format!("t{name}{i}"), rate(i), Servers::Single);
            b.input(places[i], t, 1);
            b.output(t, if i + 1 < k { places[i + 1] } else { choose }, 1);
            spec.places.push((places[i], reward(i), PlaceMode::Marked));
        }
        let time: f64 = (0..k).map(|i| 1.0 / rate(i)).sum();
        (0..k).map(|i| reward(i) / rate(i)).sum::<f64>() / time
    };
    let g_a = ring(&mut b, "a", 60, &|i| 1.0 + (i % 3) as f64, &|i| {
        (i % 5) as f64
    });
    let g_b = ring(&mut b, "b", 20, &|i| 2.0 + (i % 2) as f64, &|_| 1.0);
    // The transient ring: c0 → … → c54 → c0, and c0 leaves to Choose at rate 0.5.
    let c: Vec<_> = (0..55)
        .map(|i| b.place(format!("c{i}"), u32::from(i == 0)))
        .collect();
    for i in 0..55 {
        let t = b.exponential(format!("tc{i}"), 1.0, Servers::Single);
        b.input(c[i], t, 1);
        b.output(t, c[(i + 1) % 55], 1);
    }
    let leave = b.exponential("leave", 0.5, Servers::Single);
    b.input(c[0], leave, 1);
    b.output(leave, choose, 1);
    let net = b.build().unwrap();
    let model =
        DecisionModel::build(&net, &Controls::zero_weight(&net), &Default::default()).unwrap();
    assert_eq!((model.state_count(), model.decision_count()), (136, 1));
    let rewards = model.rewards(&spec);
    assert!((g_a - g_b).abs() > 0.1, "{g_a} {g_b}");
    for max in [true, false] {
        let expected = if max { g_a.max(g_b) } else { g_a.min(g_b) };
        for (algorithm, method, tol) in [
            (Algorithm::PolicyIteration, Method::PolicyIteration, 1e-12),
            (
                Algorithm::ValueIteration,
                Method::RelativeValueIteration,
                1e-9,
            ),
        ] {
            let sol = lra(&model, &rewards, max, algorithm).unwrap();
            assert_eq!(sol.method, method);
            assert!(
                (sol.value - expected).abs() <= tol * expected,
                "max={max} {method:?}: {} vs {expected}",
                sol.value
            );
        }
    }
}

/// The cancel flag stops the solver: value iteration on the home model with 6 robots (11,046
/// states, thousands of sweeps) ends with `Cancelled` soon after another thread sets the
/// flag, after some sweeps and short of convergence; policy iteration and the search stop
/// at once on a flag already set.
#[test]
fn the_cancel_flag_stops_the_solver_and_the_search() {
    use gspn::analysis::decision::{Algorithm, BuildOptions, DecisionError};
    use gspn::analysis::state_space::AnalysisError;
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::time::{Duration, Instant};
    let (net, controls, spec) = home("home_n06");
    let model = DecisionModel::build(&net, &controls, &Default::default()).unwrap();
    let rewards = model.rewards(&spec);
    let flag = Arc::new(AtomicBool::new(false));
    let opts = |algorithm| SolveOptions {
        algorithm,
        cancel: Some(Arc::clone(&flag)),
        ..SolveOptions::default()
    };
    let setter = {
        let flag = Arc::clone(&flag);
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(300));
            flag.store(true, Ordering::Relaxed);
            Instant::now()
        })
    };
    let r = solve(
        &model,
        &rewards,
        &Objective::Lra { max: true },
        &opts(Algorithm::ValueIteration),
    );
    let stopped = Instant::now();
    let set = setter.join().unwrap();
    match r {
        Err(DecisionError::Cancelled { iterations }) => assert!(iterations > 0),
        other => panic!("expected Cancelled, got {other:?}"),
    }
    // Within a few sweeps of the flag (a sweep takes milliseconds).
    assert!(stopped.duration_since(set) < Duration::from_secs(2));
    let r = solve(
        &model,
        &rewards,
        &Objective::Lra { max: true },
        &opts(Algorithm::PolicyIteration),
    );
    assert!(
        matches!(r, Err(DecisionError::Cancelled { iterations: 0 })),
        "{r:?}"
    );
    let monitor = Arc::new(Monitor::new());
    monitor.cancel();
    let opts = BuildOptions {
        monitor: Some(monitor),
        ..BuildOptions::default()
    };
    let r = DecisionModel::build(&net, &controls, &opts);
    assert!(
        matches!(
            r,
            Err(DecisionError::Analysis(AnalysisError::Cancelled { .. }))
        ),
        "{r:?}"
    );
}
