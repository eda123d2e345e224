//! `plan-runner analyze FILE [--steady] [--transient T1,T2,..] [--json] [--export-prism PREFIX]
//! [--max-states N] [--prob EXPR]`: state space and properties, steady state (limiting
//! distribution for non-ergodic nets), transient measures, PRISM export.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use gspn::analysis::invariants::{Invariants, p_invariants, t_invariants};
use gspn::analysis::measures::{Measures, Solver, SolverOptions};
use gspn::analysis::properties::Properties;
use gspn::analysis::state_space::{AnalysisError, Options, StateSpace};
use gspn::io::prism::Explicit;
use gspn::net::Net;
use gspn::net::predicate::Predicate;
use serde_json::{Map, Value, json};

use crate::common::{BadInput, NetArgs, load_net};

/// Arguments of `analyze`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// A net (.xml, .pnml, .PNPRO).
    file: PathBuf,
    /// Compute the steady state (the limiting distribution from the initial marking). The
    /// default when neither --steady nor --transient is given.
    #[arg(long)]
    steady: bool,
    /// Transient measures at these times (comma-separated).
    #[arg(long, value_name = "T1,T2,..", value_delimiter = ',')]
    transient: Vec<f64>,
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
    #[command(flatten)]
    net: NetArgs,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    let loaded = load_net(&args.file, &args.net)?;
    let net = &loaded.net;
    if let Some(t) = args
        .transient
        .iter()
        .find(|t| !(t.is_finite() && **t >= 0.0))
    {
        return Err(BadInput(format!("--transient: {t} is not a time ≥ 0")).into());
    }
    let predicates = args
        .prob
        .iter()
        .map(|p| Predicate::parse(net, p).map_err(|e| BadInput(format!("--prob `{p}`: {e}"))))
        .collect::<Result<Vec<_>, _>>()?;
    let opts = Options {
        max_states: args.max_states,
        progress: !args.json && std::io::stderr().is_terminal(),
        threads: 0,
        max_memory: args.max_memory.saturating_mul(1 << 20),
    };
    let ss = match StateSpace::build(net, &opts) {
        Ok(ss) => ss,
        Err(AnalysisError::Unbounded { places }) => {
            report_unbounded(&args, &places);
            return Ok(ExitCode::SUCCESS);
        }
        Err(e) => return Err(e).context(format!("{}", args.file.display())),
    };
    let props = Properties::compute(net, &ss);
    let pinv = p_invariants(net, 10_000);
    let tinv = t_invariants(net, 10_000);
    let solver = Solver::new(net, &ss);
    if let Some(prefix) = &args.export_prism {
        let markings: Vec<Vec<u32>> = (0..ss.tangible_count()).map(|s| ss.marking(s)).collect();
        let names: Vec<&str> = net.places().iter().map(|p| p.name.as_str()).collect();
        let initial: Vec<u32> = ss.initial().iter().map(|&(s, _)| s).collect();
        Explicit::new(&names, solver.chain(), &markings, &initial)
            .write(prefix)
            .with_context(|| format!("writing {}.tra/.sta/.lab", prefix.display()))?;
    }
    let want_steady = args.steady || !args.prob.is_empty() || args.transient.is_empty();
    let steady = if want_steady {
        let l = solver
            .steady_state(&SolverOptions::default())
            .context("steady state")?;
        let m = solver.measures(&l.pi);
        let probs: Vec<f64> = predicates
            .iter()
            .map(|p| solver.probability(&l.pi, p))
            .collect();
        Some((l.ergodic, m, probs))
    } else {
        None
    };
    let transient: Vec<(f64, Measures, Vec<f64>)> = solver
        .transient(&args.transient, 1e-12)
        .into_iter()
        .zip(&args.transient)
        .map(|(pi, &t)| {
            let probs = predicates
                .iter()
                .map(|p| solver.probability(&pi, p))
                .collect();
            (t, solver.measures(&pi), probs)
        })
        .collect();
    if args.json {
        let mut out = Map::new();
        out.insert(
            "state_space".into(),
            state_space_json(net, &props, &pinv, &tinv),
        );
        out.insert(
            "steady_state".into(),
            match &steady {
                Some((ergodic, m, probs)) => {
                    let mut v = json!({
                        "ergodic": ergodic,
                        "mean_tokens": per_place(net, &m.mean_tokens),
                        "prob_nonempty": per_place(net, &m.prob_nonempty),
                        "throughput": per_transition(net, &m.throughput),
                        "mean_wait": net.places().iter().zip(&m.mean_wait)
                            .map(|(p, w)| (p.name.clone(), json!(w))).collect::<Map<_, _>>(),
                    });
                    if !predicates.is_empty() {
                        v["probability"] = prob_json(&args.prob, probs);
                    }
                    v
                }
                None => Value::Null,
            },
        );
        let tr: Vec<Value> = transient
            .iter()
            .map(|(t, m, probs)| {
                let mut v = json!({
                    "t": t,
                    "mean_tokens": per_place(net, &m.mean_tokens),
                    "throughput": per_transition(net, &m.throughput),
                });
                if !predicates.is_empty() {
                    v["probability"] = prob_json(&args.prob, probs);
                }
                v
            })
            .collect();
        out.insert("transient".into(), Value::Array(tr));
        println!("{}", serde_json::to_string_pretty(&Value::Object(out))?);
        return Ok(ExitCode::SUCCESS);
    }
    print_state_space(&args, net, &props, &pinv, &tinv);
    if let Some((ergodic, m, probs)) = &steady {
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
    }
    for (t, m, probs) in &transient {
        println!("\nat t = {t}:");
        print_measures(net, m, false);
        for (e, p) in args.prob.iter().zip(probs) {
            println!("  P({e}) = {p:.9}");
        }
    }
    if let Some(prefix) = &args.export_prism {
        println!("\nwrote {0}.tra, {0}.sta, {0}.lab", prefix.display());
    }
    Ok(ExitCode::SUCCESS)
}

fn per_place(net: &Net, v: &[f64]) -> Value {
    Value::Object(
        net.places()
            .iter()
            .zip(v)
            .map(|(p, x)| (p.name.clone(), json!(x)))
            .collect(),
    )
}

fn per_transition(net: &Net, v: &[f64]) -> Value {
    Value::Object(
        net.transitions()
            .iter()
            .zip(v)
            .map(|(t, x)| (t.name.clone(), json!(x)))
            .collect(),
    )
}

fn prob_json(exprs: &[String], probs: &[f64]) -> Value {
    Value::Object(
        exprs
            .iter()
            .zip(probs)
            .map(|(e, p)| (e.clone(), json!(p)))
            .collect(),
    )
}

fn invariants_json(inv: &Invariants, names: &[&str]) -> Value {
    Value::Array(
        inv.vectors
            .iter()
            .map(|v| {
                Value::Object(
                    v.entries()
                        .iter()
                        .map(|&(i, w)| (names[i as usize].to_string(), json!(w)))
                        .collect(),
                )
            })
            .collect(),
    )
}

fn names_of(net: &Net, ts: &[gspn::net::TransitionId]) -> Vec<String> {
    ts.iter().map(|&t| net.transition(t).name.clone()).collect()
}

fn state_space_json(net: &Net, p: &Properties, pinv: &Invariants, tinv: &Invariants) -> Value {
    let places: Vec<&str> = net.places().iter().map(|p| p.name.as_str()).collect();
    let transitions: Vec<&str> = net.transitions().iter().map(|t| t.name.as_str()).collect();
    json!({
        "reachable": p.reachable,
        "tangible": p.tangible,
        "vanishing": p.vanishing,
        "edges": p.edges,
        "dead_markings": p.dead_markings.iter().map(|d| net.format_marking(&d.marking)).collect::<Vec<_>>(),
        "bounded": true,
        "unbounded_places": Vec::<String>::new(),
        "place_bounds": places.iter().zip(&p.place_bounds).map(|(n, b)| (n.to_string(), json!(b))).collect::<Map<_, _>>(),
        "max_tokens_in_place": p.max_tokens_in_place,
        "max_tokens_per_marking": p.max_tokens_per_marking,
        "safe": p.safe,
        "reversible": p.reversible,
        "deadlock_free": p.deadlock_free,
        "live_transitions": names_of(net, &p.live_transitions()),
        "dead_transitions": names_of(net, &p.dead_transitions()),
        "p_invariants": invariants_json(pinv, &places),
        "t_invariants": invariants_json(tinv, &transitions),
    })
}

fn report_unbounded(args: &Args, places: &[String]) {
    if args.json {
        let v = json!({
            "state_space": {
                "reachable": null, "tangible": null, "vanishing": null, "edges": null,
                "dead_markings": null, "bounded": false, "unbounded_places": places,
                "place_bounds": null, "max_tokens_in_place": null,
                "max_tokens_per_marking": null, "safe": false, "reversible": null,
                "deadlock_free": null, "live_transitions": null, "dead_transitions": null,
                "p_invariants": null, "t_invariants": null,
            },
            "steady_state": null,
            "transient": [],
        });
        println!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
    } else {
        println!(
            "{}: unbounded — these places can grow without limit: {}",
            args.file.display(),
            places.join(", ")
        );
        println!("(no state space, steady state or transient analysis for an unbounded net)");
    }
}

fn print_state_space(args: &Args, net: &Net, p: &Properties, pinv: &Invariants, tinv: &Invariants) {
    println!(
        "{}: {} places, {} transitions",
        args.file.display(),
        net.place_count(),
        net.transition_count()
    );
    println!(
        "state space: {} reachable markings ({} tangible, {} vanishing), {} edges",
        p.reachable, p.tangible, p.vanishing, p.edges
    );
    let bounds: Vec<String> = net
        .places()
        .iter()
        .zip(&p.place_bounds)
        .map(|(pl, b)| format!("{}≤{b}", pl.name))
        .collect();
    println!("bounded: yes; bounds {}", bounds.join(", "));
    println!(
        "safe: {}; max tokens in a place {}, in a marking {}; reversible: {}",
        yes(p.safe),
        p.max_tokens_in_place,
        p.max_tokens_per_marking,
        yes(p.reversible)
    );
    if p.dead_markings.is_empty() {
        println!("deadlock-free: yes");
    } else {
        println!(
            "deadlock-free: no — {} dead marking(s):",
            p.dead_markings.len()
        );
        for d in p.dead_markings.iter().take(10) {
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
        if p.dead_markings.len() > 10 {
            println!("  … and {} more", p.dead_markings.len() - 10);
        }
    }
    let live = names_of(net, &p.live_transitions());
    let dead = names_of(net, &p.dead_transitions());
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
