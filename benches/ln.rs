//! Measures the portable logarithms the sampler could use on the inputs it sees (`1 − U`,
//! `U` uniform in `[0, 1)`): the `libm` crate's software `log` (what `gspn::sample::ln` is),
//! the hand-written series the sampler used before, and the platform's `f64::ln` for
//! reference. Prints nanoseconds per call, the median of 5 rounds each.
//!
//! ```text
//! cargo bench --bench ln -- [CALLS]
//! ```

#[path = "support/args.rs"]
mod bench_args;

use std::hint::black_box;
use std::time::Instant;

use rand::SeedableRng;

fn main() {
    let calls: usize = bench_args::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000_000);
    let mut rng = gspn::sample::Rng::seed_from_u64(1);
    let xs: Vec<f64> = (0..calls)
        .map(|_| 1.0 - gspn::sample::uniform(&mut rng))
        .collect();
    // Each call site is its own monomorphised loop, so every logarithm is inlined as in the
    // sampler.
    report(
        "libm::log (gspn::sample::ln)",
        measure(&xs, gspn::sample::ln),
    );
    report("hand-written series", measure(&xs, gspn::sample::ln_series));
    report("f64::ln (platform, not portable)", measure(&xs, f64::ln));
}

fn measure(xs: &[f64], f: impl Fn(f64) -> f64) -> f64 {
    let mut rounds: Vec<f64> = (0..5)
        .map(|_| {
            let start = Instant::now();
            let mut sum = 0.0;
            for &x in xs {
                sum += f(black_box(x));
            }
            black_box(sum);
            start.elapsed().as_secs_f64() * 1e9 / xs.len() as f64
        })
        .collect();
    rounds.sort_by(f64::total_cmp);
    rounds[2]
}

fn report(name: &str, ns: f64) {
    println!("{name:34} {ns:.2} ns/call (median of 5)");
}
