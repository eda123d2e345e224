//! Measures the viewer's step request (`POST /api/sim/step`) after a long run: 10 million
//! token-game steps are played through the API first, then single steps are timed. The
//! session keeps its simulator between requests, so a step costs the same at step 10 million
//! as at step 1 (it used to replay every step since the reset: seconds per request).
//!
//! ```text
//! cargo bench --bench viewer_step -- [STEPS]
//! ```

#[path = "support/args.rs"]
mod bench_args;

use std::time::Instant;

use axum::body::Body;
use axum::http::{Request, header};
use gspn::net::{NetBuilder, Servers};
use gspn::web::{WebState, router};
use tower::ServiceExt;

#[tokio::main(flavor = "current_thread")]
async fn main() {
    let steps: u64 = bench_args::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000_000);
    // cyc3: P1 -T1-> P2 -t2-> P3 -T3-> P1 with 2 tokens (one immediate transition).
    let mut b = NetBuilder::new("cyc3");
    let (p1, p2, p3) = (b.place("P1", 2), b.place("P2", 0), b.place("P3", 0));
    let t1 = b.exponential("T1", 1.0, Servers::Single);
    let t2 = b.immediate("t2", 1.0, 1);
    let t3 = b.exponential("T3", 2.0, Servers::Single);
    for (p, t, q) in [(p1, t1, p2), (p2, t2, p3), (p3, t3, p1)] {
        b.input(p, t, 1);
        b.output(t, q, 1);
    }
    let app = router(WebState::new(b.build().unwrap(), None, 1));
    let step = |n: u64| {
        let app = app.clone();
        async move {
            let req = Request::post("/api/sim/step")
                .header(header::CONTENT_TYPE, "application/json")
                .body(Body::from(format!("{{\"n\":{n}}}")))
                .unwrap();
            let res = app.oneshot(req).await.unwrap();
            assert!(res.status().is_success());
            axum::body::to_bytes(res.into_body(), usize::MAX)
                .await
                .unwrap()
                .len()
        }
    };
    let start = Instant::now();
    let mut done = 0;
    while done < steps {
        let n = (steps - done).min(1_000_000);
        step(n).await;
        done += n;
    }
    println!(
        "{steps} steps through the API in {:.2} s",
        start.elapsed().as_secs_f64()
    );
    let mut times: Vec<f64> = Vec::new();
    for _ in 0..101 {
        let t = Instant::now();
        step(1).await;
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    println!(
        "one step request after {steps} steps: median {:.3} ms, max {:.3} ms (101 requests)",
        times[50], times[100]
    );
}
