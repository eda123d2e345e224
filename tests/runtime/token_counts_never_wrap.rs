//! Regression (issue 14, defect 3): `run` used to wrap a token count at 2³². Now the firing
//! is refused, an `error` event says which place, and the run stops as a failure with the
//! marking as it was.

use gspn::net::{MAX_TOKENS, NetBuilder, Servers};
use gspn::runtime::{Runtime, StopReason};

#[tokio::test(start_paused = true)]
async fn a_firing_past_the_maximum_count_stops_the_run_with_an_error() {
    let mut b = NetBuilder::new("overflow");
    let full = b.place("full", MAX_TOKENS);
    let one = b.place("one", 1);
    let t = b.exponential("t", 1.0, Servers::Single);
    b.input(one, t, 1);
    b.output(t, full, 1);
    let h = Runtime::builder(b.build().unwrap())
        .seed(3)
        .spawn()
        .unwrap();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::Failure);
    assert_eq!(s.exit_code(), 1);
    assert_eq!(s.firings, 0);
    assert_eq!(s.final_marking["full"], MAX_TOKENS);
    assert_eq!(s.final_marking["one"], 1);
    assert_eq!(
        s.errors,
        vec![
            "firing `t` would put 4294967296 tokens in place `full`, which exceeds the maximum token count 4294967295"
                .to_string()
        ]
    );
}
