//! `plan-runner conform JOURNAL (--plan PLAN | --net NET) [--json] [--fit OUT]
//! [--fail-on-drift]`: a recorded run beside its model's predictions, row by row with a
//! verdict (see `gspn::conform` and docs/conformance.md); `--fit` writes the net with the
//! rates and weights the run shows. Exit status: 2 for bad input; with `--fail-on-drift`, 1
//! when a row diverges; 0 otherwise.

use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use gspn::conform::{
    Fitted, Monitor, Options, Predictions, Report, RowKind, Trace, TraceBuilder, Verdict, compare,
    fit, marking_before, observe, steady_predictions,
};
use gspn::io::{Format, write_net};
use gspn::net::Net;
use gspn::plan::open;
use gspn::policy::Policy;
use gspn::runtime::journal::Entry;
use gspn::runtime::{Event, EventKind, Events, Received};

use crate::common::{BadInput, NetArgs};

/// Arguments of `conform`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// The journal (`plan-runner run --journal FILE`).
    journal: PathBuf,
    /// The plan the run was made from (its net and policy).
    #[arg(
        long,
        value_name = "PLAN",
        conflicts_with = "net",
        required_unless_present = "net"
    )]
    plan: Option<PathBuf>,
    /// The net the run was made from (no policy).
    #[arg(long, value_name = "NET")]
    net: Option<PathBuf>,
    /// Print JSON: `net, predictions, time, firings, batches, rows` (and `fitted`).
    #[arg(long)]
    json: bool,
    /// Write the net with the fitted rates and weights (.PNPRO, .pnml or .xml).
    #[arg(long, value_name = "OUT")]
    fit: Option<PathBuf>,
    /// Batches of batch means.
    #[arg(long, value_name = "N", default_value_t = 20)]
    batches: usize,
    /// Most stages of a fitted Erlang holding time (`--fit`; 1 fits rates only).
    #[arg(long, value_name = "K", default_value_t = 20)]
    max_stages: u32,
    /// Most reachable markings for the steady-state prediction.
    #[arg(long, value_name = "N", default_value_t = 1_000_000)]
    max_states: usize,
    /// Exit with status 1 when any row diverges (0 when none does): a gate for CI or a
    /// deployment. The report is printed either way.
    #[arg(long)]
    fail_on_drift: bool,
    #[command(flatten)]
    net_args: NetArgs,
}

/// The net and policy of `--plan` or `--net`.
pub(crate) fn model(
    plan: Option<&Path>,
    net: Option<&Path>,
    args: &NetArgs,
) -> anyhow::Result<(Net, Policy)> {
    let path = plan.or(net).expect("clap requires --plan or --net");
    let plan = open(path, &args.read_options())?.into_plan();
    for w in &plan.warnings {
        eprintln!("warning: {w}");
    }
    Ok((plan.net, plan.policy))
}

/// A journal of a run of `net`, read a line at a time into a trace (a last line cut short by
/// a kill is skipped with a warning, as `replay` does).
pub(crate) fn journal_trace(path: &Path, net: &Net) -> anyhow::Result<Trace> {
    let mut journal = crate::replay::read_journal(path, net, None)?;
    let mut trace = TraceBuilder::new(net);
    for entry in journal.by_ref() {
        match entry.map_err(|e| BadInput(format!("{}: {e}", path.display())))? {
            Entry::Event(e) => trace.push(&e),
            Entry::Record(_) => {}
        }
    }
    crate::replay::warn_torn(path, journal.torn());
    Ok(trace.finish())
}

/// `net` with the initial marking a run started from when it was not the net's (a plan run
/// with `--robots N` scales it, and the journal's hash is of the scaled net): the marking
/// before the journal's first firing (read from `journal` up to it).
pub(crate) fn scaled_net(journal: impl BufRead, net: &Net) -> Option<Net> {
    let (t, marking) = journal
        .lines()
        .map_while(Result::ok)
        .skip(1)
        .find_map(|l| {
            let e: Event = serde_json::from_str(&l).ok()?;
            match e.kind {
                EventKind::Fired {
                    transition,
                    marking,
                    ..
                } if transition.index() < net.transition_count()
                    && marking.len() == net.place_count() =>
                {
                    Some((transition, marking))
                }
                _ => None,
            }
        })?;
    net.with_initial_marking(&marking_before(net, t, &marking)?)
        .ok()
}

/// The output format of `--fit`, by extension.
pub(crate) fn fit_format(path: &Path) -> anyhow::Result<Format> {
    match Format::from_extension(path) {
        Some(f @ (Format::Pnpro | Format::Pnml | Format::Pipe)) => Ok(f),
        _ => Err(BadInput(format!(
            "--fit {}: the extension must be .PNPRO, .pnml or .xml",
            path.display()
        ))
        .into()),
    }
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    if args.batches < 2 {
        return Err(BadInput(format!("--batches {}: at least 2 are needed", args.batches)).into());
    }
    let format = args.fit.as_deref().map(fit_format).transpose()?;
    let (net, policy) = model(args.plan.as_deref(), args.net.as_deref(), &args.net_args)?;
    let trace = journal_trace(&args.journal, &net)?;
    if args.max_stages < 1 {
        return Err(BadInput("--max-stages 0: at least 1 is needed".into()).into());
    }
    let opts = Options {
        batches: args.batches,
        max_stages: args.max_stages,
        ..Options::default()
    };
    let policy = (!policy.is_empty()).then_some(policy);
    let obs = observe(&net, policy.as_ref(), &trace, &opts)
        .map_err(|e| BadInput(format!("{}: {e}", args.journal.display())))?;
    // A run that did not start from the net's initial marking (`run --robots N` scales it)
    // is predicted from the marking it started from.
    let started = (trace.initial != net.initial_marking().as_slice())
        .then(|| net.with_initial_marking(&trace.initial).ok())
        .flatten();
    let pred = steady_predictions(
        started.as_ref().unwrap_or(&net),
        policy.as_ref(),
        args.max_states,
    )
    .unwrap_or_else(|e| Predictions::none(&format!("none: {e}")));
    let report = compare(&net, &obs, &pred, &opts);
    let fitted = match (&args.fit, format) {
        (Some(out), Some(format)) => {
            let (fitted_net, params) = fit(&net, &obs, &opts);
            write_net(&fitted_net, out, format)?;
            Some((out, params))
        }
        _ => None,
    };
    if args.json {
        let mut v = serde_json::to_value(&report)?;
        if let Some((out, params)) = &fitted {
            v["fitted"] = serde_json::json!({"file": out, "parameters": params});
        }
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        print_report(&report);
        if let Some((out, params)) = &fitted {
            print_fitted(out, params);
        }
    }
    let diverging = report.diverging().count();
    if args.fail_on_drift && diverging > 0 {
        eprintln!("conform: {diverging} row(s) diverge at the 5% level (--fail-on-drift): exit 1");
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

fn num(x: f64) -> String {
    if x != 0.0 && (x.abs() >= 1e6 || x.abs() < 1e-3) {
        format!("{x:.3e}")
    } else {
        format!("{x:.4}")
    }
}

fn print_report(r: &Report) {
    println!(
        "# {}: {} firings over {} time units, {} batches; predictions: {}",
        r.net,
        r.firings,
        num(r.time),
        r.batches,
        r.predictions
    );
    let width = r
        .rows
        .iter()
        .map(|x| x.item.chars().count())
        .max()
        .unwrap_or(4)
        .max(4);
    println!(
        "{:<13} {:<width$} {:>10} {:>23} {:>10} {:>7} {:>9}  verdict",
        "row", "item", "observed", "95% interval", "predicted", "n", "p"
    );
    for x in &r.rows {
        let kind = serde_json::to_value(x.kind)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        let interval = x
            .interval
            .map_or("-".into(), |[lo, hi]| format!("[{}, {}]", num(lo), num(hi)));
        let verdict = match x.verdict {
            Verdict::Consistent => "consistent",
            Verdict::Diverges if matches!(x.kind, RowKind::Shape | RowKind::HoldingShape) => {
                "diverges: not exponential"
            }
            Verdict::Diverges => "diverges",
            Verdict::TooLittleData => "too little data",
            Verdict::NoPrediction => "no prediction",
        };
        println!(
            "{:<13} {:<width$} {:>10} {:>23} {:>10} {:>7} {:>9}  {verdict}{}",
            kind,
            x.item,
            num(x.observed),
            interval,
            x.predicted.map_or("-".into(), num),
            x.n,
            x.p_value.map_or("-".into(), |p| format!("{p:.4}")),
            x.detail
                .as_ref()
                .map_or(String::new(), |d| format!(" ({d})")),
        );
    }
    let tested = r.tested().count();
    let diverging = r.diverging().count();
    println!("# {diverging} of {tested} tested rows diverge at the 5% level");
}

fn print_fitted(out: &Path, params: &[Fitted]) {
    println!("\n# fitted net written to {}", out.display());
    let w = params
        .iter()
        .map(|f| f.transition.chars().count())
        .max()
        .unwrap_or(0)
        .max(24);
    println!(
        "{:<w$} {:<10} {:>10} {:>10} {:>23} {:>7}",
        "item", "param", "old", "fitted", "95% interval", "n"
    );
    for f in params {
        println!(
            "{:<w$} {:<10} {:>10} {:>10} {:>23} {:>7}{}",
            f.transition,
            f.parameter,
            num(f.old),
            num(f.new),
            f.interval
                .map_or("-".into(), |[lo, hi]| format!("[{}, {}]", num(lo), num(hi))),
            f.n,
            if f.kept {
                "  kept: too little data"
            } else {
                ""
            }
        );
    }
    let kept: Vec<&str> = params
        .iter()
        .filter(|f| f.kept)
        .map(|f| f.transition.as_str())
        .collect();
    if !kept.is_empty() {
        println!("# kept (too little data): {}", kept.join(", "));
    }
}

/// `--from JOURNAL[:SEQ]` of `simulate` and `analyze`: `net` started from the marking after
/// the last firing with sequence number ≤ SEQ (the end of the run without one); the point
/// (its model time and marking) is reported on stderr.
pub(crate) fn start_from(spec: &str, net: &Net) -> anyhow::Result<Net> {
    let (path, seq) = match spec.rsplit_once(':') {
        Some((p, s)) if !p.is_empty() && !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()) => {
            let seq = s
                .parse::<u64>()
                .map_err(|e| BadInput(format!("--from {spec}: sequence number `{s}`: {e}")))?;
            (p, Some(seq))
        }
        _ => (spec, None),
    };
    let trace = journal_trace(Path::new(path), net)?;
    let (marking, time) = trace.at(seq);
    let started = net
        .with_initial_marking(&marking)
        .map_err(|e| BadInput(format!("--from {spec}: {e}")))?;
    eprintln!(
        "starting from {spec}: time {time}, {}",
        started.format_marking(&marking)
    );
    Ok(started)
}

/// `run --monitor`: the watcher the run's supervisor feeds every firing — transitions'
/// rates against the net's, places' mean tokens against the steady state (of the net under
/// `policy`) when it can be computed within `max_states` markings (else a warning says the
/// places are not watched).
pub(crate) fn monitor_for(net: &Net, policy: &Policy, max_states: usize) -> Monitor {
    let mon = Monitor::new(net, net.initial_marking().into_vec(), Default::default());
    let policy = (!policy.is_empty()).then_some(policy);
    match steady_predictions(net, policy, max_states) {
        Ok(Predictions {
            mean_tokens: Some(m),
            ..
        }) => mon.with_mean_tokens(m),
        Ok(_) => mon,
        Err(e) => {
            eprintln!("warning: --monitor watches transitions only: {e}");
            mon
        }
    }
}

/// `run --monitor`: prints each `drift` event of the run on stderr; the number of drifts.
/// (The journal holds every one; a line missed because this reader fell behind the event
/// bus is reported.)
pub(crate) async fn print_drifts(net: std::sync::Arc<Net>, mut events: Events) -> u64 {
    let mut drifts = 0;
    while let Some(r) = events.recv().await {
        match r {
            Received::Event(Event {
                time,
                kind: EventKind::Drift(d),
                ..
            }) => {
                drifts += 1;
                eprintln!("drift: {} (at time {time:.3})", d.describe(&net));
            }
            Received::Lagged(n) => {
                eprintln!(
                    "warning: --monitor fell {n} events behind: drifts among them are in the journal only"
                );
            }
            Received::Event(_) => {}
        }
    }
    drifts
}
