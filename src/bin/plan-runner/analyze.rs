//! `plan-runner analyze FILE [--steady] [--transient T1,A:B:STEP,..] [--states-only] [--json]
//! [--export-prism PREFIX] [--max-states N] [--prob EXPR] [--query Q] [--csv FILE]
//! [--plot FILE.svg]`: state space and properties, steady state (limiting distribution for
//! non-ergodic nets), transient measures (as a table and a plot over time), queries in
//! Storm's syntax, PRISM export. FILE is a net (the bare net) or a plan (its net under its
//! policy, with its reward rates: `gspn::analysis::under_policy`); the output says which.

mod census;
mod queries;
pub(crate) mod series;

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::Context;
use gspn::analysis::ctmc::Limiting;
use gspn::analysis::invariants::{Invariants, p_invariants, t_invariants};
use gspn::analysis::measures::{
    Measures, Solver, SolverOptions, TransientOptions, TransientPoint, bad_time,
};
use gspn::analysis::properties::{DeadMarking, Properties};
use gspn::analysis::report::{
    MeasuresReport, QueryAnswer, Report, StateSpaceReport, transition_names,
};
use gspn::analysis::state_space::{AnalysisError, Monitor, Options, StateSpace};
use gspn::analysis::under_policy::{PolicyAnalysisError, Regime, RewardRate, analyse};
use gspn::io::prism::Explicit;
use gspn::net::Net;
use gspn::net::predicate::Predicate;
use gspn::plan::{Plan, open};

use crate::common::{BadInput, NetArgs};
use crate::progress::Spinner;

/// Arguments of `analyze`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// A net (.xml, .pnml, .PNPRO), or a plan (.toml): its net under its `[[policy]]`
    /// rules, with its `[rewards.NAME]` rates.
    file: PathBuf,
    /// Compute the steady state (the limiting distribution from the initial marking). The
    /// default when neither --steady nor --transient is given.
    #[arg(long)]
    steady: bool,
    /// Transient measures at these times (comma-separated; `A:B:STEP` is A, A+STEP, … ≤ B).
    #[arg(long, value_name = "T1,A:B:STEP,..", value_delimiter = ',')]
    transient: Vec<String>,
    /// Only the state space's counts (markings, arcs), place bounds and dead markings: the
    /// cheapest question, answered by a search that stores no arc (no CTMC, no solve, no
    /// liveness or reversibility). Not with --steady, --transient, --prob, --query, --csv,
    /// --plot or --export-prism.
    #[arg(long)]
    states_only: bool,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Write the CTMC as PREFIX.tra, PREFIX.sta and PREFIX.lab (PRISM explicit format).
    #[arg(long, value_name = "PREFIX")]
    export_prism: Option<PathBuf>,
    /// Most reachable markings before giving up.
    #[arg(long, value_name = "N", default_value_t = 10_000_000)]
    max_states: usize,
    /// Most memory the state space may take, in MiB (estimated before each allocation).
    #[arg(long, value_name = "MIB", default_value_t = 4096)]
    max_memory: usize,
    /// Probability of a marking predicate, e.g. `P1>0 && P3==0` (repeatable).
    #[arg(long = "prob", value_name = "EXPR")]
    prob: Vec<String>,
    /// A query in Storm's/PRISM's syntax (repeatable): `P=? [F<=600 done=1]`, `P=? [F φ]`,
    /// `P=? [φ1 U<=t φ2]`, `P=? [G<=t φ]`, `T=? [F φ]`, `S=? [φ]`, `R{"name"}=? [S]`,
    /// `R{"name"}=? [C<=t]`, `R{"name"}=? [F φ]`; `Pmax=?`/`Pmin=?`/`Tmax=?`/`Tmin=?` over the
    /// plan's controllable transitions. φ: place names, `=`/`==`, `&`, `|`, `!`.
    #[arg(long = "query", value_name = "Q")]
    query: Vec<String>,
    /// Write the transient measures as CSV, one row per --transient time: E[tokens] of each
    /// place, P of each --prob, and each time-bounded `P=? [F<=t φ]` --query at that time.
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Draw the same table as an SVG line plot: the probabilities when any were asked, else
    /// E[tokens] of every place.
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<PathBuf>,
    /// Start from the marking of a recorded run (`plan-runner run --journal`): after the last
    /// firing with sequence number ≤ SEQ (the end of the run without one); transient times
    /// count from that point.
    #[arg(long, value_name = "JOURNAL[:SEQ]")]
    from: Option<String>,
    #[command(flatten)]
    net: NetArgs,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    let mut plan = open(&args.file, &args.net.read_options())?.into_plan();
    if let Some(spec) = &args.from {
        plan.net = crate::conform::start_from(spec, &plan.net)?;
    }
    let net = &plan.net;
    let regime = if plan.policy.is_empty() {
        Regime::BareNet
    } else {
        Regime::UnderPolicy
    };
    let times = series::times(&args.transient)?;
    if let Some(t) = bad_time(&times) {
        return Err(BadInput(format!("--transient: {t} is not a time ≥ 0")).into());
    }
    if times.is_empty() && (args.csv.is_some() || args.plot.is_some()) {
        return Err(BadInput(
            "--csv and --plot write measures over time: give --transient times (e.g. 0:600:10)"
                .into(),
        )
        .into());
    }
    if args.states_only {
        return census::main(&args, &plan, regime);
    }
    let queries = queries::parse(&plan, &args.query)?;
    let predicates = args
        .prob
        .iter()
        .map(|p| {
            Predicate::parse(net, p)
                .map_err(|e| BadInput(format!("--prob `{}`: {e}", gspn::io::excerpt(p, 80))))
        })
        .collect::<Result<Vec<_>, _>>()?;
    // `--transient T` asks for the distribution at T only (its --prob values included);
    // the steady state comes with --steady, or when no time is asked for.
    let want_steady = args.steady || times.is_empty();
    let Some((ss, analysed)) = explore(&args, &plan, regime, want_steady)? else {
        return Ok(ExitCode::SUCCESS);
    };
    let props = Properties::compute(net, &ss);
    let pinv = p_invariants(net, 10_000);
    let tinv = t_invariants(net, 10_000);
    let solver = Solver::new(net, &ss);
    if let Some(prefix) = &args.export_prism {
        export_prism(&plan, &ss, &solver, prefix)?;
    }
    let limiting = analysed.as_ref().map(|(l, _, _)| l.clone());
    let steady = analysed.map(|(l, m, rewards)| {
        let probs = solver.probabilities(&l.pi, &predicates);
        (l.ergodic, m, probs, rewards)
    });
    if let Some(e) = solver.too_far(&times) {
        return Err(BadInput(format!("--transient: {e}")).into());
    }
    let transient = solver
        .transient_points(&times, &predicates, &TransientOptions::default())
        .context("transient")?;
    let answers = queries::answer(&plan, &ss, limiting.clone(), &queries, args.max_states)?;
    if args.csv.is_some() || args.plot.is_some() {
        let ev = gspn::analysis::query::Evaluator::new(net, &ss, &plan.rewards);
        let (table, plotted) = series::table(net, &transient, &args.prob, &queries, &ev)?;
        series::write(
            &table,
            &plotted,
            &format!("{} ({regime})", args.file.display()),
            args.csv.as_deref(),
            args.plot.as_deref(),
        )?;
    }
    if args.json {
        let report = Report {
            analysed: regime.label().to_string(),
            state_space: StateSpaceReport::new(net, &props, &pinv, &tinv),
            steady_state: steady.as_ref().map(|(ergodic, m, probs, rewards)| {
                MeasuresReport::steady(net, *ergodic, m)
                    .with_probabilities(&args.prob, probs)
                    .with_rewards(rewards)
            }),
            transient: transient
                .iter()
                .map(|p| MeasuresReport::point(net, p, &args.prob))
                .collect(),
            queries: answers,
        };
        print_json(&report)?;
        return Ok(ExitCode::SUCCESS);
    }
    print_state_space(&args, regime, &plan, &props, &pinv, &tinv);
    print_results(&args, regime, &plan, steady.as_ref(), &transient, &answers);
    Ok(ExitCode::SUCCESS)
}

/// The state space under the plan's policy, with its steady state and reward rates when
/// `want_steady`; `None` when the net is unbounded (reported already: not an error).
fn explore(
    args: &Args,
    plan: &Plan,
    regime: Regime,
    want_steady: bool,
) -> anyhow::Result<Option<(StateSpace, Option<Steady>)>> {
    let net = &plan.net;
    let monitor = Arc::new(Monitor::new());
    let opts = Options {
        max_states: args.max_states,
        threads: 0,
        max_memory: args.max_memory.saturating_mul(1 << 20),
        monitor: Some(Arc::clone(&monitor)),
    };
    let _spinner = Spinner::start(!args.json && std::io::stderr().is_terminal(), &monitor);
    let unbounded = |e: AnalysisError| match e {
        AnalysisError::Unbounded { places } => {
            report_unbounded(args, regime, &places);
            Ok(None)
        }
        e => Err(e).context(format!("{}", args.file.display())),
    };
    // The steady state and the rewards through the library's analysis under the policy
    // (the viewer and `conform` call the same function); the state space alone otherwise.
    if want_steady {
        match analyse(
            net,
            &plan.policy,
            &plan.rewards,
            &opts,
            &SolverOptions::default(),
        ) {
            Ok(a) => Ok(Some((a.space, Some((a.limiting, a.measures, a.rewards))))),
            Err(PolicyAnalysisError::StateSpace(e)) => unbounded(e),
            Err(e) => Err(e).context("steady state"),
        }
    } else {
        match StateSpace::build_under_policy(net, &plan.policy, &opts) {
            Ok(ss) => Ok(Some((ss, None))),
            Err(e) => unbounded(e),
        }
    }
}

/// The limiting distribution, its measures and the reward rates.
type Steady = (Limiting, Measures, Vec<RewardRate>);

/// `--export-prism PREFIX`: the chain as PRISM's explicit files, with the plan's rewards.
fn export_prism(
    plan: &Plan,
    ss: &StateSpace,
    solver: &Solver,
    prefix: &std::path::Path,
) -> anyhow::Result<()> {
    let net = &plan.net;
    let markings: Vec<Vec<u32>> = (0..ss.tangible_count()).map(|s| ss.marking(s)).collect();
    let names: Vec<&str> = net.places().iter().map(|p| p.name.as_str()).collect();
    let initial: Vec<u32> = ss.initial().iter().map(|&(s, _)| s).collect();
    let rewards = plan
        .rewards
        .iter()
        .map(|r| {
            (
                r.name.clone(),
                gspn::analysis::query::state_rewards(net, ss, r),
            )
        })
        .collect();
    Explicit::new(&names, solver.chain(), &markings, &initial)
        .with_rewards(rewards)
        .write(prefix)
        .with_context(|| format!("writing {}.tra/.sta/.lab", prefix.display()))?;
    Ok(())
}

/// The text report after the state space: steady state, rewards, transient points,
/// queries, the files written.
fn print_results(
    args: &Args,
    regime: Regime,
    plan: &Plan,
    steady: Option<&(bool, Measures, Vec<f64>, Vec<RewardRate>)>,
    transient: &[TransientPoint],
    answers: &[QueryAnswer],
) {
    let net = &plan.net;
    if let Some((ergodic, m, probs, rewards)) = steady {
        println!(
            "\nsteady state ({}):",
            if *ergodic {
                "ergodic"
            } else {
                "not ergodic: limiting distribution from the initial marking"
            }
        );
        print_measures(net, m, true);
        for (e, p) in args.prob.iter().zip(probs) {
            println!("  P({e}) = {p:.9}");
        }
        if !rewards.is_empty() {
            println!("\nrewards (long-run rate per unit of time, {regime}):");
            for r in rewards {
                println!(
                    "  {:<24} {:>14.9}   (places {:.9}, transitions {:.9})",
                    r.name, r.rate, r.places, r.transitions
                );
            }
        }
    }
    for point in transient {
        println!("\nat t = {}:", point.t);
        print_measures(net, &point.measures, false);
        for (e, p) in args.prob.iter().zip(&point.probabilities) {
            println!("  P({e}) = {p:.9}");
        }
    }
    if !answers.is_empty() {
        println!("\nqueries ({regime}):");
        for a in answers {
            println!("  {}  = {}", a.query, a.value);
        }
    }
    if let Some(prefix) = &args.export_prism {
        println!("\nwrote {0}.tra, {0}.sta, {0}.lab", prefix.display());
        for r in &plan.rewards {
            println!(
                "wrote {}.{}.srew",
                prefix.display(),
                gspn::io::prism::identifier(&r.name)
            );
        }
    }
}

/// Prints a report as the CLI always has: a JSON value, so keys come out sorted.
fn print_json(report: &Report) -> anyhow::Result<()> {
    let v = serde_json::to_value(report)?;
    println!("{}", serde_json::to_string_pretty(&v)?);
    Ok(())
}

fn report_unbounded(args: &Args, regime: Regime, places: &[String]) {
    if args.json {
        let report = Report {
            analysed: regime.label().to_string(),
            state_space: StateSpaceReport::unbounded(places),
            steady_state: None,
            transient: Vec::new(),
            queries: Vec::new(),
        };
        let _ = print_json(&report);
    } else {
        println!(
            "{}: unbounded — these places can grow without limit: {}",
            args.file.display(),
            places.join(", ")
        );
        println!("(no state space, steady state or transient analysis for an unbounded net)");
    }
}

fn print_state_space(
    args: &Args,
    regime: Regime,
    plan: &Plan,
    p: &Properties,
    pinv: &Invariants,
    tinv: &Invariants,
) {
    let net = &plan.net;
    println!(
        "{}: {} places, {} transitions",
        args.file.display(),
        net.place_count(),
        net.transition_count()
    );
    match regime {
        Regime::BareNet => println!("analysed: {regime} (the net's own weights)"),
        Regime::UnderPolicy => println!(
            "analysed: {regime} ({} rules choose in vanishing markings; the net's weights where none applies)",
            plan.policy.rules().len()
        ),
    }
    println!(
        "state space: {} reachable markings ({} tangible, {} vanishing), {} labelled edges ({} distinct successor pairs)",
        p.reachable, p.tangible, p.vanishing, p.edges, p.successor_pairs
    );
    println!(
        "bounded: yes; bounds {}",
        crate::common::place_bounds(net, &p.place_bounds)
    );
    println!(
        "safe: {}; max tokens in a place {}, in a marking {}; reversible: {}",
        yes(p.safe),
        p.max_tokens_in_place,
        p.max_tokens_per_marking,
        yes(p.reversible)
    );
    print_dead_markings(net, &p.dead_markings);
    let live = transition_names(net, &p.live_transitions());
    let dead = transition_names(net, &p.dead_transitions());
    println!(
        "live transitions: {}/{}",
        live.len(),
        net.transition_count()
    );
    if !dead.is_empty() {
        println!("dead transitions: {}", dead.join(", "));
    }
    println!(
        "invariants: {} P-invariant(s){}, {} T-invariant(s)",
        pinv.vectors.len(),
        if pinv.covers_all(net.place_count()) {
            " covering every place"
        } else {
            ""
        },
        tinv.vectors.len()
    );
}

/// Whether the net is deadlock-free, and the first ten dead markings with a shortest firing
/// sequence to each.
fn print_dead_markings(net: &Net, dead: &[DeadMarking]) {
    if dead.is_empty() {
        println!("deadlock-free: yes");
    } else {
        println!("deadlock-free: no — {} dead marking(s):", dead.len());
        for d in dead.iter().take(10) {
            let path: Vec<&str> = d
                .path
                .iter()
                .map(|&t| net.transition(t).name.as_str())
                .collect();
            println!(
                "  {}  after {}",
                net.format_marking(&d.marking),
                if path.is_empty() {
                    "nothing".into()
                } else {
                    path.join(" ")
                }
            );
        }
        if dead.len() > 10 {
            println!("  … and {} more", dead.len() - 10);
        }
    }
}

fn print_measures(net: &Net, m: &Measures, wait: bool) {
    println!(
        "  {:<24} {:>14} {:>12} {:>14}",
        "place", "E[tokens]", "P(>0)", "mean wait"
    );
    for (i, p) in net.places().iter().enumerate() {
        let w = match m.mean_wait[i] {
            Some(w) if wait => format!("{w:.6}"),
            _ => "-".into(),
        };
        println!(
            "  {:<24} {:>14.9} {:>12.9} {:>14}",
            p.name, m.mean_tokens[i], m.prob_nonempty[i], w
        );
    }
    println!("  {:<24} {:>14}", "transition", "throughput");
    for (i, t) in net.transitions().iter().enumerate() {
        println!("  {:<24} {:>14.9}", t.name, m.throughput[i]);
    }
}

fn yes(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}
