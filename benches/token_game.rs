//! Token game speed: firings per second of one [`Simulator`] on one core.
//!
//! - the thesis temperature-patrol net (16 places, 24 transitions, vanishing markings with
//!   immediate choices), read from the shared fixtures;
//! - a 1000-place ring with 1000 tokens (one per place): 1000 single-server exponential
//!   transitions, nearly all enabled at once — the case a linear scan would make slow.
//!
//! `cargo bench --bench token_game`; figures in docs/benchmarks.md ("Token game").

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use gspn::io::{ReadOptions, read_net};
use gspn::net::{Net, NetBuilder, Servers};
use gspn::sim::Simulator;

/// Firings per measured iteration.
const BATCH: u64 = 100_000;

#[path = "support/fixtures.rs"]
mod fixtures_root;

fn fixtures() -> PathBuf {
    fixtures_root::root()
}

fn temperature_patrol() -> Net {
    let path = fixtures()
        .join("thesis/caldeira_2020_package/ros_TemperaturePatrolV2/gspn_temperature_patrol.xml");
    read_net(&path, &ReadOptions::default())
        .expect("the temperature-patrol fixture loads")
        .net
}

fn ring(places: usize, tokens_per_place: u32) -> Net {
    let mut b = NetBuilder::new("ring");
    let ps: Vec<_> = (0..places)
        .map(|i| b.place(format!("p{i}"), tokens_per_place))
        .collect();
    for i in 0..places {
        let t = b.exponential(format!("t{i}"), 1.0, Servers::Single);
        b.input(ps[i], t, 1);
        b.output(t, ps[(i + 1) % places], 1);
    }
    b.build().expect("ring builds")
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("token_game");
    g.throughput(Throughput::Elements(BATCH));
    for (name, net) in [
        ("temperature_patrol", temperature_patrol()),
        ("ring_1000x1000", ring(1000, 1)),
    ] {
        let mut sim = Simulator::new(net.clone(), 1);
        g.bench_function(name, |b| {
            b.iter(|| {
                sim.run_steps(black_box(BATCH)).expect("no timeless trap");
            })
        });
        black_box(sim.statistics());
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
