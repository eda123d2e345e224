//! The live monitor's false alarms on one long run of the model itself (issue 32, item 8:
//! 83 drift alarms over 61 million firings, when a sliding window was tested after every
//! firing at a fixed level). A token-game run of cyc3 feeds every firing to a
//! `gspn::conform::Monitor` with the default options (transitions and places against the
//! steady state); printed: the alarms, and what the design allows — the sum of the levels of
//! the tests each item made (`alpha / (k (k + 1))` for its k-th test, at most `alpha` per
//! item whatever the length; docs/conformance.md).
//!
//! ```text
//! cargo bench --bench monitor_false_alarms -- [FIRINGS] [SEED]
//! ```

#[path = "support/args.rs"]
mod bench_args;

use std::sync::Arc;
use std::time::Instant;

use gspn::conform::{Monitor, MonitorOptions, steady_predictions};
use gspn::net::{NetBuilder, Servers};
use gspn::sim::Simulator;

fn main() {
    let mut args = bench_args::args().skip(1);
    let firings: u64 = args
        .next()
        .and_then(|s| s.parse().ok())
        .unwrap_or(61_000_000);
    let seed: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(1);
    // cyc3: P1 -T1-> P2 -t2-> P3 -T3-> P1 with 2 tokens (t2 immediate: not tested).
    let mut b = NetBuilder::new("cyc3");
    let (p1, p2, p3) = (b.place("P1", 2), b.place("P2", 0), b.place("P3", 0));
    let t1 = b.exponential("T1", 1.0, Servers::Single);
    let t2 = b.immediate("t2", 1.0, 1);
    let t3 = b.exponential("T3", 2.0, Servers::Single);
    for (p, t, q) in [(p1, t1, p2), (p2, t2, p3), (p3, t3, p1)] {
        b.input(p, t, 1);
        b.output(t, q, 1);
    }
    let net = b.build().unwrap();
    let steady = steady_predictions(&net, None, 10_000).unwrap();
    let opts = MonitorOptions::default();
    let mut monitor = Monitor::new(&net, net.initial_marking().into_vec(), opts.clone())
        .with_mean_tokens(steady.mean_tokens.unwrap());
    let mut sim = Simulator::new(Arc::new(net.clone()), seed);
    let mut fired = [0u64; 3];
    let mut alarms = Vec::new();
    let started = Instant::now();
    for _ in 0..firings {
        let s = sim.step().unwrap().expect("cyc3 never deadlocks");
        fired[s.transition.index()] += 1;
        for d in monitor.fired(s.time, s.transition, sim.marking().as_slice()) {
            alarms.push((s.time, d));
        }
    }
    let secs = started.elapsed().as_secs_f64();
    // The design: each item's tests' levels added up.
    let level = |k: u64| opts.alpha / (k as f64 * (k as f64 + 1.0));
    let sum = |tests: u64| (1..=tests).map(level).sum::<f64>();
    let transitions =
        sum(fired[t1.index()] / opts.block as u64) + sum(fired[t3.index()] / opts.block as u64);
    let windows = firings / opts.batch_firings / opts.batches as u64;
    let places = 3.0 * sum(windows);
    println!(
        "{firings} firings (seed {seed}) in {secs:.1} s: {} alarms; the design allows \
         {transitions:.6} (2 transitions) + {places:.6} (3 places) on average",
        alarms.len()
    );
    for (t, d) in &alarms {
        println!("  at {t:.3}: {d:?}");
    }
}
