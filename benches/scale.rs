//! Scale benchmark of the runtime: a ring of K action places, N agents, no-op actions.
//!
//! ```text
//! cargo bench --bench scale -- --places 4 --agents 100000 --firings 1000000
//! cargo bench --bench scale -- --places 1000 --agents 1000 --firings 1000000 --net-timed
//! cargo bench --bench scale -- --places 4 --agents 100000 --firings 100000 --mode light
//! ```
//!
//! `--mode actor` (the default: one kameo actor per agent, running its actions) or `light`
//! (a record per agent, actions as tasks of the place actor).
//!
//! Prints one JSON line: `{places, agents, startup_s, firings, firings_per_s, peak_rss_mb,
//! idle_cpu_percent, ...}`. Two phases: (1) an idle plan — every action waiting — measured
//! for CPU over a few seconds of real time, memory per agent from the resident set before and
//! after its start; (2) start N agents and fire F times in virtual time, each action returning
//! at once (`--net-timed`: no actions, the supervisor's own ceiling).

#[path = "support/args.rs"]
mod bench_args;

use std::time::{Duration, Instant};

use gspn::net::{Net, NetBuilder, Servers, TransitionId};
use gspn::runtime::{AgentMode, Outcome, Runtime, action_fn};

fn ring(k: usize, n: usize) -> (Net, Vec<TransitionId>) {
    let mut b = NetBuilder::new(format!("ring{k}"));
    let places: Vec<_> = (0..k)
        .map(|i| b.place(format!("p{i}"), (n / k + usize::from(i < n % k)) as u32))
        .collect();
    let ts: Vec<_> = (0..k)
        .map(|i| {
            let t = b.exponential(format!("t{i}"), 1.0, Servers::Infinite);
            b.input(places[i], t, 1);
            b.output(t, places[(i + 1) % k], 1);
            t
        })
        .collect();
    (b.build().expect("a ring is a valid net"), ts)
}

fn proc_status(key: &str) -> f64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with(key))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse::<f64>().ok())
        .unwrap_or(0.0)
        / 1024.0
}

/// CPU seconds (user + system) of this process.
fn cpu_seconds() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = s.rsplit(')').next().unwrap_or("");
    let f: Vec<f64> = after
        .split_whitespace()
        .map(|x| x.parse().unwrap_or(0.0))
        .collect();
    // Fields 14 and 15 of stat (utime, stime) are at 11 and 12 after the command name.
    (f.get(11).copied().unwrap_or(0.0) + f.get(12).copied().unwrap_or(0.0)) / 100.0
}

async fn wait_started(h: &gspn::runtime::RuntimeHandle) {
    let p = h.progress();
    while !p.started() {
        tokio::time::sleep(Duration::from_micros(200)).await;
    }
}

fn arg(args: &[String], name: &str, default: u64) -> u64 {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

#[tokio::main]
async fn main() {
    let args: Vec<String> = bench_args::args().collect();
    let k = arg(&args, "--places", 4) as usize;
    let n = arg(&args, "--agents", 1000) as usize;
    let f = arg(&args, "--firings", 100_000);
    let idle_secs = arg(&args, "--idle-secs", 3);
    let net_timed = args.iter().any(|a| a == "--net-timed");
    let mode = match args
        .iter()
        .position(|a| a == "--mode")
        .map(|i| args[i + 1].as_str())
    {
        Some("light") => AgentMode::Light,
        _ => AgentMode::Actor,
    };
    let (net, ts) = ring(k, n);

    // Phase 1: an idle plan (every action sleeping), real time.
    let rss_before = proc_status("VmRSS:");
    let mut b = Runtime::builder(net.clone())
        .seed(2)
        .time_scale(1.0)
        .agent_mode(mode)
        .subscribe_at_start(false)
        .action(
            "sleep",
            action_fn(|ctx| async move {
                ctx.cancel.cancelled().await;
                Outcome::Cancelled
            }),
        );
    for i in 0..k {
        b = b.bind(format!("p{i}"), "sleep");
    }
    let h = b.spawn().expect("spawn");
    wait_started(&h).await;
    tokio::time::sleep(Duration::from_millis(500)).await;
    let rss_after = proc_status("VmRSS:");
    let c0 = cpu_seconds();
    let w0 = Instant::now();
    tokio::time::sleep(Duration::from_secs(idle_secs)).await;
    let idle_cpu = 100.0 * (cpu_seconds() - c0) / w0.elapsed().as_secs_f64();
    h.stop();
    h.wait().await;

    // Phase 2: start-up and firing rate, virtual time.
    let next = ts.clone();
    let mut b = Runtime::builder(net)
        .seed(1)
        .max_firings(f)
        .agent_mode(mode)
        .subscribe_at_start(false);
    if !net_timed {
        b = b.action(
            "noop",
            action_fn(move |ctx| {
                let t = next[ctx.place.index()];
                async move { Outcome::Fire(t) }
            }),
        );
        for i in 0..k {
            b = b.bind(format!("p{i}"), "noop");
        }
    }
    let t0 = Instant::now();
    let h = b.spawn().expect("spawn");
    wait_started(&h).await;
    let startup_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let s = h.wait().await;
    let run_s = t1.elapsed().as_secs_f64();
    drop(h);

    println!(
        "{}",
        serde_json::json!({
            "places": k,
            "agents": n,
            "startup_s": startup_s,
            "firings": s.firings,
            "firings_per_s": s.firings as f64 / run_s,
            "peak_rss_mb": proc_status("VmHWM:"),
            "idle_cpu_percent": idle_cpu,
            "kb_per_agent": if n > 0 { (rss_after - rss_before) * 1024.0 / n as f64 } else { 0.0 },
            "mode": if mode == AgentMode::Actor { "actor" } else { "light" },
            "net_timed": net_timed,
        })
    );
}
