//! Reading GreatSPN `.PNPRO` projects: the largest fixture, and a generated ring big enough
//! to show the streaming reader's throughput.
//!
//! `cargo bench --bench pnpro`; figures in docs/benchmarks.md ("Reading PNPRO").

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use gspn::io::{ReadOptions, pnpro};
use gspn::net::{NetBuilder, Position, Servers};

#[path = "support/fixtures.rs"]
mod fixtures;
use fixtures::fixture;

/// A ring of `n` places and `n` transitions (alternating exponential and immediate), with
/// positions and one token per place: about 270 bytes of PNPRO per place.
fn ring(n: usize) -> String {
    let mut b = NetBuilder::new("ring");
    let places: Vec<_> = (0..n).map(|i| b.place(format!("p{i}"), 1)).collect();
    for i in 0..n {
        let t = if i % 2 == 0 {
            b.exponential(format!("t{i}"), 1.0 + i as f64 / n as f64, Servers::Single)
        } else {
            b.immediate(format!("t{i}"), 1.0, 1)
        };
        b.input(places[i], t, 1);
        b.output(t, places[(i + 1) % n], 1);
        let (x, y) = ((i % 100) as f64 * 4.0, (i / 100) as f64 * 4.0);
        b.set_place_position(places[i], Position { x, y });
        b.set_transition_position(t, Position { x: x + 2.0, y });
    }
    pnpro::write(&b.build().expect("ring builds"))
}

fn bench(c: &mut Criterion) {
    let opts = ReadOptions::default();
    let mut g = c.benchmark_group("read_pnpro");
    let path = fixture("greatspn/gspnr_toolbox/video_GSPNR.PNPRO");
    let bytes = std::fs::read(&path).expect("fixture");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("video_GSPNR (38 KB, 12 pages)", |b| {
        b.iter(|| pnpro::read(&path, black_box(&bytes), &opts).expect("reads"))
    });
    for n in [10_000, 100_000] {
        let text = ring(n);
        let mb = text.len() as f64 / 1e6;
        g.sample_size(10);
        g.throughput(Throughput::Bytes(text.len() as u64));
        g.bench_function(format!("ring {n} places ({mb:.1} MB)"), |b| {
            b.iter(|| {
                pnpro::read(Path::new("ring.PNPRO"), black_box(text.as_bytes()), &opts)
                    .expect("reads")
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
