//! Steady state of the Kanban GSPN with N = 4 (454,475 tangible states): read the net, build
//! the tangible state space, solve πQ = 0 (Gauss–Seidel with a residual check), and print the
//! mean tokens per place, the time taken and the peak memory (VmHWM).
//!
//! ```text
//! cargo bench --bench steady_kanban -- [path/to/kanban_gspn_N4.pnml]
//! ```

#[path = "support/args.rs"]
mod bench_args;

use std::time::Instant;

#[path = "../benches/support/fixtures.rs"]
mod fixtures;

use gspn::analysis::measures::{Solver, SolverOptions};
use gspn::analysis::state_space::{Options, StateSpace};
use gspn::io::{ReadOptions, read_net};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = bench_args::args().nth(1).unwrap_or_else(|| {
        fixtures::fixture("kanban/kanban_gspn_N4.pnml")
            .display()
            .to_string()
    });
    let start = Instant::now();
    let net = read_net(path.as_ref(), &ReadOptions::default())?.net;
    let ss = StateSpace::build(&net, &Options::default())?;
    let built = start.elapsed().as_secs_f64();
    let rss_built = peak_rss_kb() / 1024;
    let solver = Solver::new(&net, &ss);
    let steady = solver.steady_state(&SolverOptions::default())?;
    let solved = start.elapsed().as_secs_f64();
    let m = solver.measures(&steady.pi);
    let total = start.elapsed().as_secs_f64();
    println!(
        "{} tangible states, {} moves, ergodic: {}",
        ss.tangible_count(),
        ss.tangible_edge_count(),
        steady.ergodic
    );
    for (p, e) in net.places().iter().zip(&m.mean_tokens) {
        println!("  E[{}] = {e:.9}", p.name);
    }
    println!("residual ‖πQ‖∞ = {:.2e}", solver.residual(&steady.pi));
    println!(
        "state space {built:.3} s (peak RSS {rss_built} MB, state space {} MB), solve {:.3} s, \
         total {total:.3} s, peak RSS {} MB",
        ss.heap_bytes() >> 20,
        solved - built,
        peak_rss_kb() / 1024
    );
    Ok(())
}

/// Peak resident memory of this process in kB (`VmHWM` in /proc/self/status; 0 elsewhere).
fn peak_rss_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}
