//! Every synthesis objective answers, and every interval it prints holds the answer
//! (issue 27, part 4): the cases that used to fail or answer wrongly, against Storm's values
//! or exact fractions, and random small models against an exact referee that evaluates every
//! deterministic policy in rational arithmetic.

use gspn::analysis::decision::{
    Controls, DecisionModel, Objective, PlaceMode, RewardSpec, Rewards, Solution, SolveOptions,
    solve,
};
use gspn::analysis::query::{Query, extreme};
use gspn::net::predicate::Predicate;
use gspn::net::{Net, NetBuilder, Servers};

use super::decision_model::{fixture_rewards, gspnr};

fn holds(sol: &Solution, exact: f64, tol: f64, what: &str) {
    assert!(
        sol.lower <= exact + tol && exact <= sol.upper + tol,
        "{what}: [{}, {}] misses {exact}",
        sol.lower,
        sol.upper
    );
    assert!(
        (sol.value - exact).abs() <= tol * exact.abs().max(1.0),
        "{what}: {} vs {exact}",
        sol.value
    );
}

fn goal(net: &Net, model: &DecisionModel, expr: &str) -> Vec<bool> {
    let p = Predicate::parse(net, expr).unwrap();
    model.states_where(|m| p.eval(m))
}

/// A GSPNR fixture's model and rewards; `keep_races` for the per-step objective.
fn fixture(name: &str, wait: Option<bool>, keep_races: bool) -> (Net, DecisionModel, Rewards) {
    let (net, mut controls, table) = gspnr(name);
    if let Some(w) = wait {
        controls.wait = w;
    }
    controls.keep_races = keep_races;
    let model = DecisionModel::build(&net, &controls, &Default::default()).unwrap();
    let rewards = model.rewards(&fixture_rewards(&net, &table));
    (net, model, rewards)
}

#[test]
fn discounted_with_a_negative_reward_gets_an_upper_bound_tiny_cycle() {
    // Was [8, inf] and exit 1: the upper bound never left ∞.
    let (net, controls, table) = gspnr("tiny_cycle");
    let model = DecisionModel::build(&net, &controls, &Default::default()).unwrap();
    let mut spec = fixture_rewards(&net, &table);
    let p3 = net.place_by_name("p3").unwrap();
    spec.places = vec![(p3, -1.0, PlaceMode::Marked)];
    let rewards = model.rewards(&spec);
    let sol = solve(
        &model,
        &rewards,
        &Objective::Discounted {
            max: true,
            rate: 0.5,
        },
        &SolveOptions::default(),
    )
    .unwrap();
    holds(&sol, 8.0, 1e-8, "tiny_cycle");
}

#[test]
fn the_toolbox_objective_with_negative_rewards_equals_storm() {
    // Storm's values (issue 27); the toolbox's γ = 0.99 per uniformised step, races kept.
    for (name, storm) in [
        ("robocup_initial", 0.1894461726025),
        ("solarfarm_battery_1uav", 1.05477908),
    ] {
        let (_, model, rewards) = fixture(name, None, true);
        let sol = solve(
            &model,
            &rewards,
            &Objective::DiscountedPerStep {
                max: true,
                gamma: 0.99,
            },
            &SolveOptions::default(),
        )
        .unwrap();
        holds(&sol, storm, 1e-6, name);
    }
}

#[test]
fn total_min_leaves_a_zero_reward_end_component_solarfarm() {
    // Was 0 in [0, 0]: the robots could roam for ever at no cost. Storm: 5, the impulse of
    // the only way into the goal.
    let (net, model, rewards) = fixture("solarfarm_2timeouts_experiment", Some(false), false);
    let g = goal(&net, &model, "Inspecting_panel5 >= 1");
    let sol = solve(
        &model,
        &rewards,
        &Objective::Total {
            max: false,
            goal: g,
        },
        &SolveOptions::default(),
    )
    .unwrap();
    holds(&sol, 5.0, 1e-6, "total-min");
}

/// Two robots; each chooses route A (succeeds with 2/3) or route B (succeeds with 2/3 per
/// try and retries with 3/5 after a failure: 5/6 in all). A failed robot stops for good.
fn two_routes() -> Net {
    let mut b = NetBuilder::new("two_routes");
    let goal = b.place("Goal", 0);
    for i in 0..2 {
        let start = b.place(format!("Start{i}"), 1);
        let (ra, rb) = (b.place(format!("A{i}"), 0), b.place(format!("B{i}"), 0));
        let (retry, failed) = (
            b.place(format!("Retry{i}"), 0),
            b.place(format!("Failed{i}"), 0),
        );
        let (a, bb) = (
            b.immediate(format!("take_a{i}"), 0.0, 1),
            b.immediate(format!("take_b{i}"), 0.0, 1),
        );
        b.moves(start, a, ra);
        b.moves(start, bb, rb);
        for (from, to, rate, name) in [
            (ra, goal, 2.0, "a_ok"),
            (ra, failed, 1.0, "a_fail"),
            (rb, goal, 2.0, "b_ok"),
            (rb, retry, 1.0, "b_fail"),
            (retry, rb, 3.0, "retry"),
            (retry, failed, 2.0, "give_up"),
        ] {
            let t = b.exponential(format!("{name}{i}"), rate, Servers::Single);
            b.moves(from, t, to);
        }
    }
    b.build().unwrap()
}

#[test]
fn reach_both_robots_upper_bound_converges() {
    // Was "no convergence after 626 iterations (interval [0.694…, inf])".
    let net = two_routes();
    let model =
        DecisionModel::build(&net, &Controls::zero_weight(&net), &Default::default()).unwrap();
    let rewards = model.rewards(&RewardSpec::default());
    let g = goal(&net, &model, "Goal >= 2");
    for (max, exact) in [(true, 25.0 / 36.0), (false, 4.0 / 9.0)] {
        let sol = solve(
            &model,
            &rewards,
            &Objective::Reach {
                max,
                goal: g.clone(),
            },
            &SolveOptions::default(),
        )
        .unwrap();
        holds(
            &sol,
            exact,
            1e-9,
            if max { "reach-max" } else { "reach-min" },
        );
    }
}

#[test]
fn pmax_and_pmin_queries_ask_the_synthesis_engine_two_routes() {
    // `Pmax=?`/`Pmin=?` on a net with controllable transitions: the same optimum as
    // `synthesize`'s reach objectives, (5/6)² and (2/3)²; `=?` has no policy to ask.
    let net = two_routes();
    let controls = Controls::zero_weight(&net);
    let ask = |text: &str| {
        let q = Query::parse(&net, &[], text).unwrap();
        extreme::evaluate(&net, &controls, &[], &q, &Default::default())
    };
    let pmax = ask("Pmax=? [F Goal>=2]").unwrap();
    let pmin = ask("Pmin=? [F `Goal` = 2]").unwrap();
    assert!((pmax - 25.0 / 36.0).abs() < 1e-9, "{pmax}");
    assert!((pmin - 4.0 / 9.0).abs() < 1e-9, "{pmin}");
    let err = ask("Pmax=? [F<=1 Goal>=2]").unwrap_err().to_string();
    assert!(
        err.contains("a time bound is not computed for max/min"),
        "{err}"
    );
}
