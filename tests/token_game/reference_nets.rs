//! The token game agrees with an independent solver (fixtures/reference/
//! thesis_nets_reference.json) on the thesis's temperature-patrol net: every place's
//! expected tokens and every transition's throughput lie within 4 half-widths of the
//! Monte-Carlo 95% interval (4 rather than 1, so that 40 quantities checked at once do not
//! fail by chance).

use crate::support::fixtures as shared_fixtures;

use gspn::io::{ReadOptions, read_net};
use gspn::sim::{Horizon, MonteCarlo};
use serde_json::Value;
use shared_fixtures::fixture;

#[test]
fn temperature_patrol_matches_the_reference_solver() {
    let key = "thesis/caldeira_2020_package/ros_TemperaturePatrolV2/gspn_temperature_patrol.xml";
    let net = read_net(&fixture(key), &ReadOptions::default())
        .unwrap()
        .net;
    let reference: Value = serde_json::from_str(
        &std::fs::read_to_string(fixture("reference/thesis_nets_reference.json")).unwrap(),
    )
    .unwrap();
    let reference = &reference[key];
    let est = MonteCarlo::new(&net, Horizon::Until(1000.0))
        .runs(100)
        .seed(2)
        .run()
        .unwrap();
    assert_eq!(est.dead_runs, 0);
    let mut checked = 0;
    for (i, p) in net.places().iter().enumerate() {
        let exact = reference["expected_tokens"][&p.name].as_f64().unwrap();
        let e = est.mean_tokens[i];
        assert!(
            (e.mean - exact).abs() <= 4.0 * e.half_width + 1e-12,
            "{}: {} ± {} vs {exact}",
            p.name,
            e.mean,
            e.half_width
        );
        checked += 1;
    }
    for (i, t) in net.transitions().iter().enumerate() {
        let exact = reference["throughput"][&t.name].as_f64().unwrap();
        let e = est.throughput[i];
        assert!(
            (e.mean - exact).abs() <= 4.0 * e.half_width + 1e-12,
            "{}: {} ± {} vs {exact}",
            t.name,
            e.mean,
            e.half_width
        );
        checked += 1;
    }
    assert_eq!(checked, 16 + 24);
}
