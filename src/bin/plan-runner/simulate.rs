//! `plan-runner simulate FILE [--seed S] [--until T | --steps N] [--runs R] [--json]
//! [--transient TIMES --csv FILE --plot FILE.svg]`.
//!
//! One run prints its trace (time, transition, marking); `--runs R` prints Monte-Carlo
//! estimates (mean tokens per place, throughput per transition, and the rate of each of a
//! plan's `[rewards.NAME]`) with 95% confidence intervals instead; with `--transient`,
//! E[tokens] of each place at those times, with their intervals, as CSV and a plot.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use gspn::analysis::decision::RewardSpec;
use gspn::net::Net;
use gspn::net::predicate::Predicate;

use gspn::policy::Policy;
use gspn::sim::{Estimate, Horizon, MonteCarlo, SimError, Simulator};
use serde_json::{Map, Value, json};

use crate::common::{BadInput, NetArgs};

/// Arguments of `simulate`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// A net (.xml, .pnml, .PNPRO) or a plan (.toml: its policy, seed and stop limits apply).
    file: PathBuf,
    /// Seed of the run (Monte-Carlo run i uses stream i of it) [default: the plan's seed, else 0].
    #[arg(long)]
    seed: Option<u64>,
    /// Simulate until this virtual time [default: the plan's time limit, else 1000 with --runs].
    #[arg(long, value_name = "T", conflicts_with = "steps")]
    until: Option<f64>,
    /// Fire this many transitions (per run) [default: the plan's firing limit, else 100 for a trace].
    #[arg(long, value_name = "N")]
    steps: Option<u64>,
    /// Monte-Carlo: this many independent runs, estimates with 95% confidence intervals
    /// (a plan's `stop.when` ends a trace only; Monte-Carlo runs use the time or step limit).
    #[arg(long, value_name = "R")]
    runs: Option<u64>,
    /// Print JSON: `runs, firings, mean_tokens, throughput, ci95`, and `rewards` for a plan
    /// with `[rewards.NAME]` and --runs (a single run adds `trace`).
    #[arg(long)]
    json: bool,
    /// With --runs: estimate E[tokens] of every place at these times (comma-separated;
    /// `A:B:STEP` is A, A+STEP, … ≤ B), for --csv and --plot.
    #[arg(
        long,
        value_name = "T1,A:B:STEP,..",
        value_delimiter = ',',
        requires = "runs"
    )]
    transient: Vec<String>,
    /// Write the --transient estimates as CSV: per place `E[p]`, `E[p] lo`, `E[p] hi` (the
    /// 95% interval).
    #[arg(long, value_name = "FILE", requires = "transient")]
    csv: Option<PathBuf>,
    /// Draw the --transient estimates (the means) as an SVG line plot.
    #[arg(long, value_name = "FILE.svg", requires = "transient")]
    plot: Option<PathBuf>,
    /// Start from the marking of a recorded run: after the last firing with sequence number
    /// ≤ SEQ (the end of the run without one); times count from that point.
    #[arg(long, value_name = "JOURNAL[:SEQ]")]
    from: Option<String>,
    #[command(flatten)]
    net: NetArgs,
}

/// What the file gave: the net and, for a plan, its policy, seed and limits.
struct Input {
    net: Net,
    policy: Option<Policy>,
    seed: Option<u64>,
    time_limit: Option<f64>,
    max_firings: Option<u64>,
    stop_when: Option<Predicate>,
    rewards: Vec<RewardSpec>,
}

fn load(args: &Args) -> anyhow::Result<Input> {
    let plan = crate::common::open_checked(&args.file, &args.net)?.into_plan();
    for w in &plan.warnings {
        eprintln!("warning: {w}");
    }
    Ok(Input {
        policy: (!plan.policy.is_empty()).then_some(plan.policy),
        seed: plan.seed,
        time_limit: plan.stop.time_limit,
        max_firings: plan.stop.max_firings,
        stop_when: plan.stop.when,
        rewards: plan.rewards,
        net: plan.net,
    })
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    if let Some(t) = args.until
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(BadInput(format!("--until {t}: must be a finite number ≥ 0")).into());
    }
    if args.runs == Some(0) {
        return Err(BadInput("--runs 0: at least one run is needed".into()).into());
    }
    let mut input = load(&args)?;
    if let Some(spec) = &args.from {
        input.net = crate::conform::start_from(spec, &input.net)?;
    }
    let seed = args.seed.or(input.seed).unwrap_or(0);
    let horizon = match (args.until, args.steps) {
        (Some(t), _) => Horizon::Until(t),
        (None, Some(n)) => Horizon::Steps(n),
        (None, None) => match (input.time_limit, input.max_firings) {
            (Some(t), _) => Horizon::Until(t),
            (None, Some(n)) => Horizon::Steps(n),
            (None, None) if args.runs.is_some() => Horizon::Until(1000.0),
            (None, None) => Horizon::Steps(100),
        },
    };
    if let Some(runs) = args.runs
        && !args.transient.is_empty()
    {
        return over_time(&args, &input, runs, seed);
    }
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    match args.runs {
        Some(runs) => monte_carlo(&args, &input, runs, horizon, seed, &mut out)?,
        None => trace(&args, &input, horizon, seed, &mut out)?,
    }
    out.flush()?;
    Ok(ExitCode::SUCCESS)
}

/// A timeless trap is a defect of the net: bad input.
fn sim_error(e: SimError) -> anyhow::Error {
    BadInput(e.to_string()).into()
}

fn horizon_text(h: Horizon) -> String {
    match h {
        Horizon::Until(t) => format!("until {t}"),
        Horizon::Steps(n) => format!("{n} steps"),
    }
}

fn trace(
    args: &Args,
    input: &Input,
    horizon: Horizon,
    seed: u64,
    out: &mut impl Write,
) -> anyhow::Result<()> {
    let net = &input.net;
    let mut sim = Simulator::new(net.clone(), seed);
    if let Some(p) = &input.policy {
        sim = sim.with_policy(p.clone());
    }
    let (until, max_steps) = match horizon {
        Horizon::Until(t) => (t, u64::MAX),
        Horizon::Steps(n) => (f64::INFINITY, n),
    };
    let mut rows = Vec::new();
    if !args.json {
        writeln!(
            out,
            "# {}: seed {seed}, {}",
            net.name(),
            horizon_text(horizon)
        )?;
        writeln!(out, "{:>14}  {:<24}  marking", "time", "transition")?;
        writeln!(
            out,
            "{:>14.6}  {:<24}  {}",
            0.0,
            "(initial)",
            net.format_marking(sim.marking())
        )?;
    }
    let mut end = "limit";
    while sim.firings() < max_steps {
        if input
            .stop_when
            .as_ref()
            .is_some_and(|p| p.eval(sim.marking()))
        {
            end = "stop_when";
            break;
        }
        match sim.step_until(until).map_err(sim_error)? {
            Some(step) => {
                let name = &net.transition(step.transition).name;
                let marking = net.format_marking(sim.marking());
                if args.json {
                    rows.push(json!({"time": step.time, "transition": name, "marking": marking}));
                } else {
                    writeln!(out, "{:>14.6}  {:<24}  {}", step.time, name, marking)?;
                }
            }
            None => {
                if sim.is_dead() {
                    end = "dead";
                }
                break;
            }
        }
    }
    if sim.is_dead() && until.is_finite() {
        sim.run_until(until).map_err(sim_error)?;
    }
    let stats = sim.statistics();
    if args.json {
        let mut v = summary_json(
            net,
            1,
            sim.firings(),
            &stats.mean_tokens,
            &stats.throughput,
            None,
        );
        v["trace"] = Value::Array(rows);
        v["end"] = json!(end);
        v["time"] = json!(sim.time());
        serde_json::to_writer_pretty(&mut *out, &v)?;
        writeln!(out)?;
    } else {
        let why = match end {
            "dead" => "dead marking (nothing can fire again)",
            "stop_when" => "the plan's stop condition holds",
            _ => "limit reached",
        };
        writeln!(
            out,
            "# end at time {:.6} after {} firings: {why}",
            sim.time(),
            sim.firings()
        )?;
    }
    Ok(())
}

/// One table of estimates: a header, then a row per name with the mean and its interval.
fn section<'a>(
    out: &mut impl Write,
    width: usize,
    (what, measure): (&str, &str),
    rows: impl Iterator<Item = (&'a str, &'a Estimate)>,
) -> std::io::Result<()> {
    writeln!(out, "{what:<width$}  {measure:>12}  95% interval")?;
    for (name, e) in rows {
        writeln!(out, "{name:<width$}  {:>12.6}  {}", e.mean, interval(e))?;
    }
    Ok(())
}

fn monte_carlo(
    args: &Args,
    input: &Input,
    runs: u64,
    horizon: Horizon,
    seed: u64,
    out: &mut impl Write,
) -> anyhow::Result<()> {
    let net = &input.net;
    let mut mc = MonteCarlo::new(net, horizon)
        .runs(runs)
        .seed(seed)
        .rewards(&input.rewards);
    if let Some(p) = &input.policy {
        mc = mc.policy(p);
    }
    let est = mc
        .run()
        .map_err(sim_error)
        .with_context(|| format!("{}: Monte-Carlo simulation", args.file.display()))?;
    let mean: Vec<f64> = est.mean_tokens.iter().map(|e| e.mean).collect();
    let thr: Vec<f64> = est.throughput.iter().map(|e| e.mean).collect();
    if args.json {
        let mut v = summary_json(
            net,
            est.runs,
            est.firings,
            &mean,
            &thr,
            Some((&est.mean_tokens, &est.throughput)),
        );
        if !input.rewards.is_empty() {
            let named = |f: &dyn Fn(&Estimate) -> Value| -> Value {
                Value::Object(
                    input
                        .rewards
                        .iter()
                        .zip(&est.rewards)
                        .map(|(r, e)| (r.name.clone(), f(e)))
                        .collect(),
                )
            };
            v["rewards"] = named(&|e| json!(e.mean));
            v["ci95"]["rewards"] = named(&|e| {
                if e.half_width.is_nan() {
                    json!([null, null])
                } else {
                    json!([e.lo(), e.hi()])
                }
            });
        }
        serde_json::to_writer_pretty(&mut *out, &v)?;
        writeln!(out)?;
        return Ok(());
    }
    writeln!(
        out,
        "# {}: {} runs, seed {seed}, {}: {} firings, {} runs ended dead, mean time {:.6}",
        net.name(),
        est.runs,
        horizon_text(horizon),
        est.firings,
        est.dead_runs,
        est.mean_time
    )?;
    let width = net
        .places()
        .iter()
        .map(|p| p.name.len())
        .chain(net.transitions().iter().map(|t| t.name.len()))
        .max()
        .unwrap_or(0)
        .max(10);
    let places = net.places().iter().map(|p| p.name.as_str());
    let transitions = net.transitions().iter().map(|t| t.name.as_str());
    section(
        out,
        width,
        ("place", "mean tokens"),
        places.zip(&est.mean_tokens),
    )?;
    section(
        out,
        width,
        ("transition", "throughput"),
        transitions.zip(&est.throughput),
    )?;
    if !input.rewards.is_empty() {
        let names = input.rewards.iter().map(|r| r.name.as_str());
        section(out, width, ("reward", "rate"), names.zip(&est.rewards))?;
    }
    Ok(())
}

/// `--runs R --transient TIMES`: E[tokens] per place at each time with its interval, as a
/// table on stdout and, when asked, CSV and SVG.
fn over_time(args: &Args, input: &Input, runs: u64, seed: u64) -> anyhow::Result<ExitCode> {
    let net = &input.net;
    let times = crate::analyze::series::times(&args.transient)?;
    let mut mc = MonteCarlo::new(net, Horizon::Until(0.0))
        .runs(runs)
        .seed(seed);
    if let Some(p) = &input.policy {
        mc = mc.policy(p);
    }
    let at = mc
        .transient(&times)
        .map_err(sim_error)
        .with_context(|| format!("{}: Monte-Carlo simulation", args.file.display()))?;
    let mut columns = Vec::new();
    for p in net.places() {
        columns.extend([
            format!("E[{}]", p.name),
            format!("E[{}] lo", p.name),
            format!("E[{}] hi", p.name),
        ]);
    }
    let mut table = gspn::io::series::Series::new(columns);
    for (t, est) in times.iter().zip(&at) {
        table.push(
            *t,
            est.iter().flat_map(|e| [e.mean, e.lo(), e.hi()]).collect(),
        );
    }
    let means: Vec<usize> = (0..net.place_count()).map(|p| 3 * p).collect();
    crate::analyze::series::write(
        &table,
        &means,
        &format!("{}: {runs} runs, seed {seed}", net.name()),
        args.csv.as_deref(),
        args.plot.as_deref(),
    )?;
    if args.csv.is_none() {
        print!("{}", table.to_csv());
    }
    Ok(ExitCode::SUCCESS)
}

fn interval(e: &Estimate) -> String {
    if e.half_width.is_nan() {
        "(one run: no interval)".into()
    } else {
        format!("[{:.6}, {:.6}]", e.lo(), e.hi())
    }
}

/// `runs, firings, mean_tokens {place: x}, throughput {transition: x}, ci95 {mean_tokens
/// {p: [lo, hi]}, throughput {t: [lo, hi]}}`; intervals are `[null, null]` for one run.
fn summary_json(
    net: &Net,
    runs: u64,
    firings: u64,
    mean_tokens: &[f64],
    throughput: &[f64],
    ci: Option<(&[Estimate], &[Estimate])>,
) -> Value {
    let named = |names: Vec<&String>, f: &dyn Fn(usize) -> Value| -> Value {
        let row = |(i, name): (usize, &String)| (name.clone(), f(i));
        Value::Object(
            names
                .into_iter()
                .enumerate()
                .map(row)
                .collect::<Map<_, _>>(),
        )
    };
    let by_place =
        |f: &dyn Fn(usize) -> Value| named(net.places().iter().map(|p| &p.name).collect(), f);
    let by_transition =
        |f: &dyn Fn(usize) -> Value| named(net.transitions().iter().map(|t| &t.name).collect(), f);
    let pair = |e: Option<&Estimate>| match e {
        Some(e) if !e.half_width.is_nan() => json!([e.lo(), e.hi()]),
        _ => json!([null, null]),
    };
    json!({
        "runs": runs,
        "firings": firings,
        "mean_tokens": by_place(&|i| json!(mean_tokens[i])),
        "throughput": by_transition(&|i| json!(throughput[i])),
        "ci95": {
            "mean_tokens": by_place(&|i| pair(ci.map(|c| &c.0[i]))),
            "throughput": by_transition(&|i| pair(ci.map(|c| &c.1[i]))),
        },
    })
}
