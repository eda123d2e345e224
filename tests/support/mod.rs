//! Shared helpers for behaviour tests (every layer's test binary includes this module).
#![allow(dead_code, unused_imports)]

use gspn::net::{Net, NetBuilder, Servers};

#[cfg(feature = "web")]
pub mod browser;

/// Serves `state` (the viewer) on an ephemeral loopback port: its address and the server task.
#[cfg(feature = "web")]
pub async fn start_server(
    state: gspn::web::WebState,
) -> (std::net::SocketAddr, tokio::task::JoinHandle<()>) {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let task = tokio::spawn(async move {
        let _ = gspn::web::serve(listener, state).await;
    });
    (addr, task)
}
pub mod fixtures;
/// A fixture file under the fixture root (see [`fixtures::root`]); one lookup for every
/// behaviour test.
pub use fixtures::fixture;

/// Batch means over a single run: the time axis cut into `n` batches of length `len`; each
/// statistic is either a time integral (`advance`) or a count (`count`), divided by `len`.
pub struct BatchMeans {
    len: f64,
    sums: Vec<Vec<f64>>,
    last: f64,
}

impl BatchMeans {
    pub fn new(n: usize, len: f64, stats: usize) -> Self {
        BatchMeans {
            len,
            sums: vec![vec![0.0; n]; stats],
            last: 0.0,
        }
    }

    /// Adds `values[k]` (held constant since the last call) integrated up to time `t`.
    pub fn advance(&mut self, t: f64, values: &[f64]) {
        let n = self.sums[0].len();
        let mut from = self.last;
        while from < t {
            let b = ((from / self.len) as usize).min(n - 1);
            let end = t.min((b + 1) as f64 * self.len);
            let end = if b == n - 1 { t } else { end };
            for (k, v) in values.iter().enumerate() {
                self.sums[k][b] += v * (end - from);
            }
            from = end;
        }
        self.last = t;
    }

    /// Counts one event of statistic `k` at time `t`.
    pub fn count(&mut self, t: f64, k: usize) {
        let n = self.sums[k].len();
        let b = ((t / self.len) as usize).min(n - 1);
        self.sums[k][b] += 1.0;
    }

    /// Mean and half-width of the 95% interval (Student t) of statistic `k` per unit time.
    pub fn interval(&self, k: usize) -> (f64, f64) {
        let xs: Vec<f64> = self.sums[k].iter().map(|s| s / self.len).collect();
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, t975(xs.len() - 1) * (var / n).sqrt())
    }
}

/// The 97.5% quantile of Student's t with `df` degrees of freedom (table, df ≥ 9).
fn t975(df: usize) -> f64 {
    match df {
        0..=9 => 2.262,
        10..=14 => 2.228,
        15..=19 => 2.131,
        20..=24 => 2.086,
        25..=29 => 2.060,
        30..=39 => 2.042,
        40..=59 => 2.021,
        60..=119 => 2.000,
        _ => 1.980,
    }
}

/// cyc3 of the GreatSPN fixtures (`greatspn/cyc3`), built in code: two tokens cycle through
/// P1 --T1 (rate 1)--> P2 --t2 (immediate)--> P3 --T3 (rate 2)--> P1. With single servers
/// π over (2,0,0), (1,0,1), (0,0,2) is (4,2,1)/7: E[P1] = 10/7, E[P3] = 4/7, throughputs 6/7.
pub fn cyc3(servers: Servers) -> Net {
    let mut b = NetBuilder::new("cyc3");
    let (p1, p2, p3) = (b.place("P1", 2), b.place("P2", 0), b.place("P3", 0));
    let t1 = b.exponential("T1", 1.0, servers);
    let t2 = b.immediate("t2", 1.0, 1);
    let t3 = b.exponential("T3", 2.0, servers);
    b.input(p1, t1, 1);
    b.output(t1, p2, 1);
    b.input(p2, t2, 1);
    b.output(t2, p3, 1);
    b.input(p3, t3, 1);
    b.output(t3, p1, 1);
    b.build().expect("cyc3 is a valid net")
}

/// Runs a scenario `async fn NAME(mode: AgentMode)` as two tests, `NAME::light` and
/// `NAME::actor`: every behaviour holds with light agents and with one kameo actor per agent.
#[allow(unused_macros)]
macro_rules! in_both_agent_modes {
    ($($name:ident),* $(,)?) => {$(
        mod $name {
            #[tokio::test(start_paused = true)]
            async fn light() {
                super::$name(gspn::runtime::AgentMode::Light).await
            }
            #[tokio::test(start_paused = true)]
            async fn actor() {
                super::$name(gspn::runtime::AgentMode::Actor).await
            }
        }
    )*};
}

/// A ring p0 → t0 → p1 → … → p{k-1} → t{k-1} → p0 with `tokens(i)` tokens in place `i` and
/// exponential transitions of rate `rate(i)`; returns the net and its transitions in order.
pub fn ring(
    k: usize,
    tokens: impl Fn(usize) -> u32,
    rate: impl Fn(usize) -> f64,
    servers: Servers,
) -> (Net, Vec<gspn::net::TransitionId>) {
    let mut b = NetBuilder::new(format!("ring{k}"));
    let places: Vec<_> = (0..k)
        .map(|i| b.place(format!("p{i}"), tokens(i)))
        .collect();
    let ts = (0..k)
        .map(|i| {
            let t = b.exponential(format!("t{i}"), rate(i), servers);
            b.input(places[i], t, 1);
            b.output(t, places[(i + 1) % k], 1);
            t
        })
        .collect();
    (b.build().expect("a ring is a valid net"), ts)
}

/// `plan-runner run plans/temperature-patrol/plan.toml --robots N --seed S --max-firings F
/// --journal PATH` (the binary cargo built for this test run); panics unless it exits 0.
pub fn journal_of_patrol_on_robots(path: &std::path::Path, robots: usize, seed: u64, firings: u64) {
    let plan =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("plans/temperature-patrol/plan.toml");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_plan-runner"))
        .arg("run")
        .arg(&plan)
        .args(["--robots", &robots.to_string(), "--seed", &seed.to_string()])
        .args(["--max-firings", &firings.to_string(), "--journal"])
        .arg(path)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
