//! Analysing a plan and synthesising its policy from Rust — what `plan-runner analyze` and
//! `plan-runner synthesize` do, through the library. The plan is the home-cleaning one
//! (`plans/home-cleaning/plan.toml`: three robots, three rooms, every choice a decision):
//!
//! 1. the bare net (a fair coin at every decision): its long-run reward and a CSL question
//!    in Storm's syntax;
//! 2. the policy that maximises the long-run reward, as rules over token counts;
//! 3. the net analysed again under that policy: it earns what the synthesis promised.
//!
//! ```text
//! cargo run --example analyse_and_synthesise
//! ```

use std::path::Path;

use gspn::analysis::decision::{
    DecisionModel, Objective, PolicyTable, SolveOptions, compress, solve,
};
use gspn::analysis::measures::SolverOptions;
use gspn::analysis::query::{Evaluator, Query};
use gspn::analysis::state_space::Options;
use gspn::analysis::under_policy::analyse;
use gspn::io::ReadOptions;
use gspn::net::Net;
use gspn::plan::read_plan;
use gspn::policy::{Pattern, Policy, Rule};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("plans/home-cleaning/plan.toml");
    let plan = read_plan(&path, &ReadOptions::default())?;
    let net = &plan.net;
    let reward = &plan.rewards[0];

    // 1. The bare net: the state space, its steady state and the reward's long-run rate.
    let bare = analyse(
        net,
        &plan.policy,
        &plan.rewards,
        &Options::default(),
        &SolverOptions::default(),
    )?;
    println!(
        "bare net: {} tangible states, reward {} = {:.9} per unit of time",
        bare.space.tangible_count(),
        reward.name,
        bare.rewards[0].rate
    );
    // A question as a Storm or PRISM user writes it: is room L2 being mopped within 5 time
    // units of the start?
    let query = Query::parse(net, &plan.rewards, "P=? [F<=5 Mopping_L2>=1]")?;
    let p = Evaluator::new(net, &bare.space, &plan.rewards).evaluate(&query)?;
    println!("{query} = {p:.9}");

    // 2. The policy that maximises the long-run reward: the Markov automaton of the plan's
    // controllable transitions, solved by policy iteration (the interval holds the optimum).
    let model = DecisionModel::build(net, &plan.controls, &Default::default())?;
    let rewards = model.rewards(reward);
    let best = solve(
        &model,
        &rewards,
        &Objective::Lra { max: true },
        &SolveOptions::default(),
    )?;
    println!(
        "optimal: {:.9} in [{:.9}, {:.9}] over {} states ({:?})",
        best.value,
        best.lower,
        best.upper,
        model.state_count(),
        best.method
    );
    // Where the policy decides, what it fires; compressed into a decision tree over token
    // counts — the rules a plan's `[[policy]]` holds.
    let PolicyTable { fires, waits } = model.policy_table(&best.policy);
    let rules = compress(&fires);
    println!(
        "policy: {} decision markings ({waits} wait), {} rules",
        fires.len(),
        rules.len()
    );
    for rule in rules.iter().take(3) {
        println!("  {}", show(net, rule));
    }

    // 3. The net under that policy earns the optimum.
    let policy = Policy::new(net, rules)?;
    let under = analyse(
        net,
        &policy,
        &plan.rewards,
        &Options::default(),
        &SolverOptions::default(),
    )?;
    println!(
        "under the policy: reward {} = {:.9} per unit of time",
        reward.name, under.rewards[0].rate
    );
    assert!(
        (under.rewards[0].rate - best.value).abs() <= 1e-6,
        "the policy earns its promise"
    );
    Ok(())
}

/// A rule as `Place=count, … → transition`.
fn show(net: &Net, rule: &Rule) -> String {
    let when = match &rule.pattern {
        Pattern::Partial(counts) => counts
            .iter()
            .map(|&(p, n)| format!("{}={n}", net.place(p).name))
            .collect::<Vec<_>>()
            .join(", "),
        Pattern::Exact(_) => "one marking".to_string(),
    };
    let then = rule
        .choose
        .iter()
        .map(|&(t, _)| net.transition(t).name.as_str())
        .collect::<Vec<_>>()
        .join(" | ");
    format!("{when} → {then}")
}
