//! Running a TOML plan inside your own service. The plan file (`plans/ros_example.toml`) says
//! what each place does (built-in actions); the service puts its own Rust action on the
//! decision place `p6` (it hands the choice back to the plan's policy), leaves the others to
//! the plan, counts the firings from the run's events beside its own work, and stops the plan on Ctrl-C. The plan runs on virtual time, so it ends at once.
//!
//! ```text
//! cargo run --example plan_in_service
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use gspn::io::ReadOptions;
use gspn::plan::read_plan;
use gspn::runtime::{EventKind, Outcome, Received, action_fn};

#[tokio::main]
async fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("plans/ros_example.toml");
    let plan = read_plan(&path, &ReadOptions::default())?;
    for w in &plan.warnings {
        eprintln!("warning: {w}");
    }
    let net = plan.net.clone();

    // The plan brings the net, the roles, the policy, the seed and the stop condition; the
    // service brings the code of the action it implements (registered under its own name,
    // put on `p6` in place of the plan's `log` action).
    let decide = action_fn(|_ctx| async { Outcome::Decide });
    let mut handle = plan
        .runtime_builder()
        .action("service_decide", decide)
        .bind("p6", "service_decide")
        .spawn()?;
    for w in handle.warnings() {
        println!("note: {w}");
    }

    // The service's own task: count firings per transition from the event stream.
    let mut events = handle.events();
    let counter = tokio::spawn(async move {
        let mut fired: BTreeMap<_, u64> = BTreeMap::new();
        while let Some(r) = events.recv().await {
            if let Received::Event(e) = r
                && let EventKind::Fired { transition, .. } = e.kind
            {
                *fired.entry(transition).or_default() += 1;
            }
        }
        fired
    });

    let summary = tokio::select! {
        s = handle.wait() => s,
        _ = tokio::signal::ctrl_c() => {
            handle.stop();
            handle.wait().await
        }
    };
    println!(
        "stopped: {} after {} firings at time {:.3} (seed {})",
        summary.stopped,
        summary.firings,
        summary.time,
        handle.seed()
    );
    for (t, n) in counter.await? {
        println!("  {:<6} fired {n:>4} times", net.transition(t).name);
    }
    Ok(())
}
