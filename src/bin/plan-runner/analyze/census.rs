//! `analyze --states-only`: the state space's counts, bounds and dead markings from a search
//! that stores no arc ([`Census`]).

use std::io::IsTerminal;
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::Context;
use gspn::analysis::report::{Report, StateSpaceReport};
use gspn::analysis::state_space::{AnalysisError, Census, Monitor, Options};
use gspn::analysis::under_policy::Regime;
use gspn::plan::Plan;

use super::{Args, print_dead_markings, print_json, report_unbounded, yes};
use crate::common::BadInput;
use crate::progress::Spinner;

/// The options that need more than the markings, refused with --states-only.
fn refuse_solver_options(args: &Args) -> anyhow::Result<()> {
    let given = crate::common::given_flags(&[
        (args.steady, "--steady"),
        (!args.transient.is_empty(), "--transient"),
        (!args.prob.is_empty(), "--prob"),
        (!args.query.is_empty(), "--query"),
        (args.csv.is_some(), "--csv"),
        (args.plot.is_some(), "--plot"),
        (args.export_prism.is_some(), "--export-prism"),
    ]);
    if given.is_empty() {
        return Ok(());
    }
    Err(BadInput(format!(
        "--states-only stores no arc and solves nothing: {} cannot be answered with it",
        given.join(", ")
    ))
    .into())
}

pub(super) fn main(args: &Args, plan: &Plan, regime: Regime) -> anyhow::Result<ExitCode> {
    refuse_solver_options(args)?;
    let net = &plan.net;
    let monitor = Arc::new(Monitor::new());
    let opts = Options {
        max_states: args.max_states,
        threads: 0,
        max_memory: args.max_memory.saturating_mul(1 << 20),
        monitor: Some(Arc::clone(&monitor)),
    };
    let spinner = Spinner::start(!args.json && std::io::stderr().is_terminal(), &monitor);
    // A policy chooses among the immediate transitions but reaches the same markings: the
    // census is the net's.
    let census = match Census::build(net, &opts) {
        Ok(c) => c,
        Err(AnalysisError::Unbounded { places }) => {
            drop(spinner);
            report_unbounded(args, regime, &places);
            return Ok(ExitCode::SUCCESS);
        }
        Err(e) => return Err(e).context(format!("{}", args.file.display())),
    };
    drop(spinner);
    if args.json {
        print_json(&Report {
            analysed: regime.label().to_string(),
            state_space: StateSpaceReport::census(net, &census),
            steady_state: None,
            transient: Vec::new(),
            queries: Vec::new(),
        })?;
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "{}: {} places, {} transitions",
        args.file.display(),
        net.place_count(),
        net.transition_count()
    );
    println!(
        "state space: {} reachable markings ({} tangible, {} vanishing), {} labelled arcs ({} distinct successor pairs), vanishing markings not eliminated",
        census.reachable, census.tangible, census.vanishing, census.arcs, census.successor_pairs
    );
    println!(
        "bounded: yes; bounds {}",
        crate::common::place_bounds(net, &census.place_bounds)
    );
    let max_in_place = census.place_bounds.iter().copied().max().unwrap_or(0);
    println!(
        "safe: {}; max tokens in a place {max_in_place}, in a marking {}",
        yes(max_in_place <= 1),
        census.max_tokens_per_marking
    );
    print_dead_markings(net, &census.dead_markings);
    Ok(ExitCode::SUCCESS)
}
