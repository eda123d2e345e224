//! Plays the token game on a 1000-place ring holding 1000 tokens and prints how many
//! firings per second one core sustains, with the time-average tokens of one place (the
//! steady state is uniform, so every place averages 1 token).
//!
//! ```text
//! cargo bench --bench token_game_ring -- [FIRINGS]
//! ```

#[path = "support/args.rs"]
mod bench_args;

use std::time::Instant;

use gspn::net::{NetBuilder, Servers};
use gspn::sim::Simulator;

fn main() {
    let firings: u64 = bench_args::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_000_000);
    let n = 1000;
    let mut b = NetBuilder::new("ring");
    let places: Vec<_> = (0..n).map(|i| b.place(format!("p{i}"), 1)).collect();
    for i in 0..n {
        let t = b.exponential(format!("t{i}"), 1.0, Servers::Single);
        b.input(places[i], t, 1);
        b.output(t, places[(i + 1) % n], 1);
    }
    let net = b.build().expect("the ring is a valid net");

    let mut sim = Simulator::new(net, 1);
    let start = Instant::now();
    sim.run_steps(firings)
        .expect("a ring has no immediate transitions");
    let secs = start.elapsed().as_secs_f64();

    let stats = sim.statistics();
    println!(
        "{firings} firings in {secs:.3} s: {:.2} M firings/s ({:.1} ns each)",
        firings as f64 / secs / 1e6,
        secs * 1e9 / firings as f64
    );
    println!(
        "virtual time {:.1}, mean tokens in p0 {:.3}",
        stats.time, stats.mean_tokens[0]
    );
}
