//! Policy synthesis end to end on a GSPNR fixture: read the net and its `rewards.toml`, build
//! the decision model, solve an objective; prints states, choices, the times of each phase,
//! the value and the peak memory of the process.
//!
//! ```text
//! cargo bench --bench synthesis -- ../shared/fixtures/gspnr/home_n06
//! cargo bench --bench synthesis -- DIR --objective per-step --gamma 0.99
//! cargo bench --bench synthesis -- DIR --method policy --threads 1
//! ```

#[path = "support/args.rs"]
mod bench_args;

use std::path::PathBuf;
use std::time::Instant;

use gspn::analysis::decision::{
    Algorithm, BuildOptions, Controls, DecisionModel, Objective, PlaceMode, RewardSpec,
    SolveOptions, solve,
};
use gspn::io::{ReadOptions, read_net};
use gspn::net::Net;

/// Peak resident memory (VmHWM) in MB, from /proc/self/status.
fn peak_rss_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// The fixture's rewards (place rates while marked, transition impulses), controllable
/// transitions and WAIT flag.
fn rewards(net: &Net, text: &str) -> Result<(RewardSpec, Controls), Box<dyn std::error::Error>> {
    let table: toml::Table = text.parse()?;
    let number = |v: &toml::Value| v.as_float().or(v.as_integer().map(|i| i as f64));
    let mut spec = RewardSpec {
        name: "reward".into(),
        ..RewardSpec::default()
    };
    if let Some(places) = table.get("places").and_then(|v| v.as_table()) {
        for (name, v) in places {
            let p = net.place_by_name(name).ok_or("unknown place")?;
            spec.places
                .push((p, number(v).ok_or("not a number")?, PlaceMode::Marked));
        }
    }
    if let Some(ts) = table.get("transitions").and_then(|v| v.as_table()) {
        for (name, v) in ts {
            let t = net.transition_by_name(name).ok_or("unknown transition")?;
            spec.transitions.push((t, number(v).ok_or("not a number")?));
        }
    }
    let mut controls = Controls::zero_weight(net);
    controls.wait = table.get("wait").and_then(|v| v.as_bool()).unwrap_or(false);
    Ok((spec, controls))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = bench_args::args().skip(1);
    let mut dir: Option<PathBuf> = None;
    let mut objective = "lra".to_string();
    let mut gamma = 0.99;
    let mut threads = 0;
    let mut wait: Option<bool> = None;
    let mut algorithm = Algorithm::default();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--objective" => objective = args.next().ok_or("--objective lra|per-step")?,
            "--gamma" => gamma = args.next().ok_or("--gamma G")?.parse()?,
            "--threads" => threads = args.next().ok_or("--threads N")?.parse()?,
            "--wait" => wait = Some(args.next().ok_or("--wait BOOL")?.parse()?),
            "--method" => {
                algorithm = match args.next().ok_or("--method value|policy")?.as_str() {
                    "value" => Algorithm::ValueIteration,
                    "policy" => Algorithm::PolicyIteration,
                    other => return Err(format!("unknown method {other}").into()),
                }
            }
            "--seq" => faer::set_global_parallelism(faer::Par::Seq),
            _ => dir = Some(a.into()),
        }
    }
    let dir = dir.ok_or("usage: bench_synthesis FIXTURE_DIR [--objective lra|per-step]")?;
    let t0 = Instant::now();
    let net = read_net(&dir.join("net.PNPRO"), &ReadOptions::default())?.net;
    let (spec, mut controls) = rewards(&net, &std::fs::read_to_string(dir.join("rewards.toml"))?)?;
    if let Some(w) = wait {
        controls.wait = w;
    }
    let obj = match objective.as_str() {
        "lra" => Objective::Lra { max: true },
        "per-step" => {
            controls.keep_races = true;
            Objective::DiscountedPerStep { max: true, gamma }
        }
        other => return Err(format!("unknown objective {other}").into()),
    };
    let read = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let opts = BuildOptions {
        threads,
        ..BuildOptions::default()
    };
    let model = DecisionModel::build(&net, &controls, &opts)?;
    let build = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let r = model.rewards(&spec);
    let sol = solve(
        &model,
        &r,
        &obj,
        &SolveOptions {
            algorithm,
            ..SolveOptions::default()
        },
    )?;
    let solve_s = t2.elapsed().as_secs_f64();
    println!("fixture    {}", dir.display());
    println!(
        "states     {} ({} markings, {} choices, {} toolbox states)",
        model.state_count(),
        model.marking_count(),
        model.choice_count(),
        model.toolbox_state_count()
    );
    println!(
        "value      {} in [{}, {}] ({:?}, {} iterations)",
        sol.value, sol.lower, sol.upper, sol.method, sol.iterations
    );
    println!("read       {read:.4} s");
    println!("build      {build:.4} s");
    println!("solve      {solve_s:.4} s");
    println!("total      {:.4} s", t0.elapsed().as_secs_f64());
    println!("peak RSS   {:.0} MB", peak_rss_mb());
    Ok(())
}
