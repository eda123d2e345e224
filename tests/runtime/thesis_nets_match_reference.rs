//! Runtime against analysis on the thesis nets: multi_escort_run and the temperature patrol,
//! run as plans with no user actions in virtual time, give mean tokens and throughputs whose
//! 95% batch-means intervals contain the reference steady state
//! (fixtures/reference/thesis_nets_reference.json, an independent solver).

use crate::support as common;

use gspn::io::{ReadOptions, read_net};
use gspn::runtime::{EventKind, Received, Runtime};
use serde_json::Value;

async fn check(rel: &str, seed: u64, batches: usize, batch_len: f64) {
    let path = common::fixture(rel);
    let net = read_net(&path, &ReadOptions::default()).unwrap().net;
    let reference: Value = serde_json::from_str(
        &std::fs::read_to_string(common::fixture("reference/thesis_nets_reference.json")).unwrap(),
    )
    .unwrap();
    let reference = &reference[rel];
    let (np, nt) = (net.place_count(), net.transition_count());
    let mut h = Runtime::builder(net.clone())
        .seed(seed)
        .until(batches as f64 * batch_len)
        .event_capacity(1 << 22)
        .spawn()
        .unwrap();
    let mut events = h.events();
    let mut stats = common::BatchMeans::new(batches, batch_len, np + nt);
    let mut m: Vec<f64> = net.initial_marking().iter().map(|&k| k as f64).collect();
    let mut values = vec![0.0; np + nt];
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
                values[..np].copy_from_slice(&m);
                stats.advance(e.time, &values);
                stats.count(e.time, np + transition.index());
                m = marking.iter().map(|&k| k as f64).collect();
            }
            EventKind::Stopped { .. } => {
                values[..np].copy_from_slice(&m);
                stats.advance(e.time, &values);
            }
            _ => {}
        }
    }
    h.wait().await;
    let mut checked = 0;
    for (i, p) in net.places().iter().enumerate() {
        let exact = reference["expected_tokens"][&p.name].as_f64().unwrap();
        let (mean, half) = stats.interval(i);
        assert!(
            (mean - exact).abs() <= half.max(1e-12),
            "{rel}: E[{}] = {mean} ± {half} does not contain {exact}",
            p.name
        );
        checked += 1;
    }
    for (j, t) in net.transitions().iter().enumerate() {
        let exact = reference["throughput"][&t.name].as_f64().unwrap();
        let (mean, half) = stats.interval(np + j);
        assert!(
            (mean - exact).abs() <= half.max(1e-12),
            "{rel}: X({}) = {mean} ± {half} does not contain {exact}",
            t.name
        );
        checked += 1;
    }
    assert_eq!(checked, np + nt);
}

#[tokio::test(start_paused = true)]
async fn multi_escort_run_matches_the_reference_steady_state() {
    check(
        "thesis/caldeira_2020_dev/multi_escort_run.xml",
        7,
        30,
        2000.0,
    )
    .await;
}

#[tokio::test(start_paused = true)]
async fn temperature_patrol_matches_the_reference_steady_state() {
    check(
        "thesis/caldeira_2020_package/ros_TemperaturePatrolV2/gspn_temperature_patrol.xml",
        7,
        30,
        2000.0,
    )
    .await;
}
