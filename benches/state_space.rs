//! Builds the full reachability graph of a net file and prints its size, how long it took,
//! states per second and the peak memory of the process.
//!
//! ```text
//! cargo bench --bench state_space -- ../shared/fixtures/mcc/Kanban-PT-00005/model.pnml
//! cargo bench --bench state_space -- FILE --threads 1
//! cargo bench --bench state_space -- FILE --census    # counts only, no arc stored
//! ```

#[path = "support/args.rs"]
mod bench_args;

use std::path::PathBuf;
use std::time::Instant;

use gspn::analysis::properties::Properties;
use gspn::analysis::state_space::{Census, Options, StateSpace};
use gspn::io::{ReadOptions, read_net};

/// Peak resident memory (VmHWM) in MB, from /proc/self/status.
fn peak_rss_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = bench_args::args().skip(1);
    let mut file: Option<PathBuf> = None;
    let mut opts = Options::default();
    let mut props = false;
    let mut census = false;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--threads" => opts.threads = args.next().ok_or("--threads N")?.parse()?,
            "--properties" => props = true,
            "--census" => census = true,
            _ => file = Some(a.into()),
        }
    }
    let file = file.ok_or("usage: state_space FILE [--threads N] [--properties] [--census]")?;
    let t0 = Instant::now();
    let net = read_net(&file, &ReadOptions::default())?.net;
    let read = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    if census {
        let c = Census::build(&net, &opts)?;
        let secs = t1.elapsed().as_secs_f64();
        let peak = peak_rss_mb();
        println!("net        {} (census: no arc stored)", net.name());
        println!(
            "states     {} ({} tangible, {} vanishing)",
            c.reachable, c.tangible, c.vanishing
        );
        println!(
            "arcs       {} ({} successor pairs)",
            c.arcs, c.successor_pairs
        );
        println!("dead       {}", c.dead_markings.len());
        println!("read       {read:.3} s");
        println!("seconds    {secs:.3}");
        println!(
            "heap       {:.0} MB at the end ({:.1} B/state)",
            c.heap_bytes as f64 / 1e6,
            c.heap_bytes as f64 / c.reachable as f64
        );
        println!(
            "peak RSS   {peak:.0} MB ({:.1} B/state)",
            peak * 1048576.0 / c.reachable as f64
        );
        return Ok(());
    }
    let ss = StateSpace::build(&net, &opts)?;
    let secs = t1.elapsed().as_secs_f64();
    let n = ss.reachable_count();
    println!("net        {}", net.name());
    println!(
        "states     {n} ({} tangible, {} vanishing)",
        ss.tangible_count(),
        ss.vanishing_count()
    );
    println!("edges      {}", ss.edge_count());
    println!("read       {read:.3} s");
    println!("seconds    {secs:.3}");
    println!("states/s   {:.0}", n as f64 / secs);
    println!(
        "heap       {:.0} MB (state space)",
        ss.heap_bytes() as f64 / 1e6
    );
    if props {
        let t2 = Instant::now();
        let p = Properties::compute(&net, &ss);
        println!(
            "properties {:.3} s: {} dead, max tokens in place {}, per marking {}, reversible {}",
            t2.elapsed().as_secs_f64(),
            p.dead_markings.len(),
            p.max_tokens_in_place,
            p.max_tokens_per_marking,
            p.reversible
        );
    }
    println!("peak RSS   {:.0} MB", peak_rss_mb());
    Ok(())
}
