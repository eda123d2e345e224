//! Every objective on Markov automata small enough to solve by hand, values to 1e-12, and the
//! GSPNR fixtures whose README gives a hand value.

use gspn::analysis::decision::{
    Action, Controls, DecisionModel, Objective, PlaceMode, RewardSpec, Rewards, Solution,
    SolveOptions, evaluate_lra, solve,
};
use gspn::net::{Net, NetBuilder, Servers, TransitionId};

use super::decision_model::gspnr;

/// Three states: Work (Markovian, rate 1 to Choose, earns 1 per unit of time), Choose (a
/// decision: `stop` → Done, impulse 3; `again` → Work) and Done (dead, the goal).
fn work_or_stop() -> (Net, DecisionModel, Rewards, TransitionId, TransitionId) {
    let mut b = NetBuilder::new("work_or_stop");
    let work = b.place("Work", 1);
    let choose = b.place("Choose", 0);
    let done = b.place("Done", 0);
    let t = b.exponential("t", 1.0, Servers::Single);
    let stop = b.immediate("stop", 0.0, 1);
    let again = b.immediate("again", 0.0, 1);
    b.input(work, t, 1);
    b.output(t, choose, 1);
    b.input(choose, stop, 1);
    b.output(stop, done, 1);
    b.input(choose, again, 1);
    b.output(again, work, 1);
    let net = b.build().unwrap();
    let model =
        DecisionModel::build(&net, &Controls::zero_weight(&net), &Default::default()).unwrap();
    let spec = RewardSpec {
        name: "r".into(),
        places: vec![(work, 1.0, PlaceMode::Marked)],
        transitions: vec![(stop, 3.0)],
    };
    let rewards = model.rewards(&spec);
    (net, model, rewards, stop, again)
}

fn precise() -> SolveOptions {
    SolveOptions {
        precision: 1e-14,
        ..SolveOptions::default()
    }
}

fn check(sol: &Solution, exact: f64) {
    assert!(
        (sol.value - exact).abs() <= 1e-12 * exact.abs().max(1.0),
        "value {} vs {exact}",
        sol.value
    );
    assert!(
        sol.lower <= exact + 1e-12 && exact <= sol.upper + 1e-12,
        "{sol:?}"
    );
    assert!(sol.upper - sol.lower <= 1e-12 * exact.abs().max(1.0));
}

/// The choice the solution takes in the decision state.
fn choice(model: &DecisionModel, sol: &Solution) -> Action {
    let d = (0..model.state_count())
        .find(|&s| model.choices(s).len() == 2)
        .unwrap();
    model.action(sol.policy[d] as usize)
}

#[test]
fn the_hand_model_has_three_states() {
    let (_, model, ..) = work_or_stop();
    assert_eq!(model.state_count(), 3);
    assert_eq!(model.decision_count(), 1);
    assert_eq!(model.choice_count(), 4);
}

#[test]
fn long_run_average_max_works_for_ever_and_min_stops() {
    let (_, model, rewards, stop, again) = work_or_stop();
    let max = solve(&model, &rewards, &Objective::Lra { max: true }, &precise()).unwrap();
    check(&max, 1.0);
    assert_eq!(choice(&model, &max), Action::Fire(again));
    let min = solve(&model, &rewards, &Objective::Lra { max: false }, &precise()).unwrap();
    check(&min, 0.0);
    assert_eq!(choice(&model, &min), Action::Fire(stop));
}

#[test]
fn reachability_max_is_one_and_min_is_zero() {
    let (_, model, rewards, stop, again) = work_or_stop();
    let goal = model.states_where(|m| m[2] == 1);
    let max = solve(
        &model,
        &rewards,
        &Objective::Reach {
            max: true,
            goal: goal.clone(),
        },
        &precise(),
    )
    .unwrap();
    check(&max, 1.0);
    assert_eq!(choice(&model, &max), Action::Fire(stop));
    let min = solve(
        &model,
        &rewards,
        &Objective::Reach { max: false, goal },
        &precise(),
    )
    .unwrap();
    check(&min, 0.0);
    assert_eq!(choice(&model, &min), Action::Fire(again));
}

#[test]
fn accumulated_reward_and_time_until_the_goal() {
    let (_, model, rewards, stop, _) = work_or_stop();
    let goal = model.states_where(|m| m[2] == 1);
    // One sojourn of mean 1 earning 1 per unit of time, then the impulse 3.
    let min = solve(
        &model,
        &rewards,
        &Objective::Total {
            max: false,
            goal: goal.clone(),
        },
        &precise(),
    )
    .unwrap();
    check(&min, 4.0);
    assert_eq!(choice(&model, &min), Action::Fire(stop));
    // Working for ever never reaches the goal: infinite.
    let max = solve(
        &model,
        &rewards,
        &Objective::Total {
            max: true,
            goal: goal.clone(),
        },
        &precise(),
    )
    .unwrap();
    assert_eq!(max.value, f64::INFINITY);
    let time = model.time_rewards();
    let t = solve(
        &model,
        &time,
        &Objective::Total { max: false, goal },
        &precise(),
    )
    .unwrap();
    check(&t, 1.0);
}

#[test]
fn continuous_discount_rate_one_half() {
    let (_, model, rewards, stop, again) = work_or_stop();
    // Stop: x = 1/(1+α) + 3/(1+α) = 8/3. Again: x = 1/α = 2.
    let max = solve(
        &model,
        &rewards,
        &Objective::Discounted {
            max: true,
            rate: 0.5,
        },
        &precise(),
    )
    .unwrap();
    check(&max, 8.0 / 3.0);
    assert_eq!(choice(&model, &max), Action::Fire(stop));
    let min = solve(
        &model,
        &rewards,
        &Objective::Discounted {
            max: false,
            rate: 0.5,
        },
        &precise(),
    )
    .unwrap();
    check(&min, 2.0);
    assert_eq!(choice(&model, &min), Action::Fire(again));
}

#[test]
fn per_step_discount_under_the_toolbox_uniformisation() {
    let (_, model, rewards, stop, again) = work_or_stop();
    // eta = 1 + 1 = 2. Work: x = 1/2 + γ(x_D/2 + x/2). Again: x_D = γx → x = 0.5/0.145.
    // Stop: x_D = 3 → x = (0.5 + 0.45·3)/0.55.
    assert_eq!(model.eta(), 2.0);
    let max = solve(
        &model,
        &rewards,
        &Objective::DiscountedPerStep {
            max: true,
            gamma: 0.9,
        },
        &precise(),
    )
    .unwrap();
    check(&max, 100.0 / 29.0);
    assert_eq!(choice(&model, &max), Action::Fire(again));
    let min = solve(
        &model,
        &rewards,
        &Objective::DiscountedPerStep {
            max: false,
            gamma: 0.9,
        },
        &precise(),
    )
    .unwrap();
    check(&min, 37.0 / 11.0);
    assert_eq!(choice(&model, &min), Action::Fire(stop));
}

#[test]
fn exact_policy_evaluation_agrees_with_the_solver() {
    let (_, model, rewards, ..) = work_or_stop();
    for max in [true, false] {
        let sol = solve(&model, &rewards, &Objective::Lra { max }, &precise()).unwrap();
        let v = evaluate_lra(&model, &rewards, |s| vec![(sol.policy[s] as usize, 1.0)]).unwrap();
        assert!(
            (v.lra - sol.value).abs() < 1e-12,
            "{} vs {}",
            v.lra,
            sol.value
        );
    }
}

#[test]
fn tiny_cycle_earns_six_per_unit_of_time() {
    let (net, controls, _) = gspnr("tiny_cycle");
    let model = DecisionModel::build(&net, &controls, &Default::default()).unwrap();
    let p3 = net.place_by_name("p3").unwrap();
    let t3 = net.transition_by_name("t3").unwrap();
    let spec = RewardSpec {
        name: "r".into(),
        places: vec![(p3, 1.0, PlaceMode::Marked)],
        transitions: vec![(t3, 5.0)],
    };
    let rewards = model.rewards(&spec);
    let sol = solve(&model, &rewards, &Objective::Lra { max: true }, &precise()).unwrap();
    check(&sol, 6.0);
}

#[test]
fn small_hybrid_total_reward_is_five_with_wait_and_three_without() {
    let (net, mut controls, _) = gspnr("small_hybrid");
    let p1 = net.place_by_name("p1").unwrap();
    let t1 = net.transition_by_name("t1").unwrap();
    let spec = RewardSpec {
        name: "r".into(),
        places: vec![(p1, 5.0, PlaceMode::Marked)],
        transitions: vec![(t1, 3.0)],
    };
    for (wait, exact) in [(true, 5.0), (false, 3.0)] {
        controls.wait = wait;
        let model = DecisionModel::build(&net, &controls, &Default::default()).unwrap();
        let rewards = model.rewards(&spec);
        let goal = model.states_where(|m| !net.is_vanishing(m) && net.firable(m).is_empty());
        let sol = solve(
            &model,
            &rewards,
            &Objective::Total { max: true, goal },
            &precise(),
        )
        .unwrap();
        check(&sol, exact);
    }
}
