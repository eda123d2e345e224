//! A plan with no user actions is the GSPN's own token game: run long in virtual time, its
//! mean tokens and throughputs contain the analytic steady state within 95% confidence
//! intervals (batch means over one long run).

use crate::support as common;

use gspn::net::{Net, Servers};
use gspn::runtime::{EventKind, Received, Runtime};

/// cyc3, single server (fixtures/greatspn/cyc3/cyc3_ss.PNPRO): P1 (2) → T1 (1) → P2 → t2 →
/// P3 → T3 (2) → P1. E[P1] = 10/7, E[P3] = 4/7, throughput 6/7.
fn cyc3() -> Net {
    common::cyc3(Servers::Single)
}

#[tokio::test(start_paused = true)]
async fn cyc3_runtime_matches_the_steady_state() {
    let net = cyc3();
    let batches = 30;
    let batch_len = 2000.0;
    let mut h = Runtime::builder(net.clone())
        .seed(2024)
        .until(batches as f64 * batch_len)
        .event_capacity(1 << 20)
        .spawn()
        .unwrap();
    let mut events = h.events();
    // Per batch: time integral of P1 and P3, and firings of T1.
    let mut stats = common::BatchMeans::new(batches, batch_len, 3);
    let t1 = net.transition_by_name("T1").unwrap();
    let mut last_marking = net.initial_marking().to_vec();
    while let Some(r) = events.recv().await {
        let Received::Event(e) = r else {
            panic!("the test subscriber lagged");
        };
        match e.kind {
            EventKind::Fired {
                transition,
                marking,
                ..
            } => {
                stats.advance(e.time, &[last_marking[0] as f64, last_marking[2] as f64]);
                if transition == t1 {
                    stats.count(e.time, 2);
                }
                last_marking = marking.to_vec();
            }
            EventKind::Stopped { .. } => {
                stats.advance(e.time, &[last_marking[0] as f64, last_marking[2] as f64]);
            }
            _ => {}
        }
    }
    let s = h.wait().await;
    let checks = [
        (0, 10.0 / 7.0, "E[P1]"),
        (1, 4.0 / 7.0, "E[P3]"),
        (2, 6.0 / 7.0, "X(T1)"),
    ];
    for (k, exact, what) in checks {
        let (mean, half) = stats.interval(k);
        assert!(
            (mean - exact).abs() <= half,
            "{what}: {mean} ± {half} does not contain {exact}"
        );
        assert!(half < 0.05 * exact, "{what}: interval too wide ({half})");
    }
    // The summary's own time averages agree with the batch means.
    assert!((s.mean_tokens["P1"] - stats.interval(0).0).abs() < 1e-6);
    assert!((s.throughput["T1"] - stats.interval(2).0).abs() < 1e-6);
}
