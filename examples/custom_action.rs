//! A custom [`Action`] type: a "robot" that inspects a room, takes a random time, and reports
//! which way the inspection went (`ok` or `alarm`); an alarm is handled by a second action
//! that honours cancellation. Runs on virtual time, so it finishes at once.
//!
//! ```text
//! cargo run --example custom_action
//! ```

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use gspn::net::{NetBuilder, Servers};
use gspn::runtime::{
    Action, ActionContext, ActionFuture, EventKind, Outcome, Received, Runtime, action_fn,
};

/// Inspects for `minutes`, then says `alarm` every third time.
struct Inspect {
    minutes: u64,
    count: Arc<AtomicU64>,
}

impl Action for Inspect {
    fn run(&self, ctx: ActionContext) -> ActionFuture {
        let n = self.count.fetch_add(1, Ordering::Relaxed);
        let wait = Duration::from_secs(60 * self.minutes);
        Box::pin(async move {
            tokio::select! {
                _ = ctx.cancel.cancelled() => Outcome::Cancelled,
                _ = tokio::time::sleep(wait) => ctx.fire(if n % 3 == 2 { "alarm" } else { "ok" }),
            }
        })
    }
}

#[tokio::main(flavor = "current_thread", start_paused = true)]
async fn main() {
    let mut b = NetBuilder::new("inspection");
    let inspect = b.place("Inspect", 2);
    let handle = b.place("HandleAlarm", 0);
    let ok = b.exponential("ok", 1.0, Servers::Infinite);
    let alarm = b.exponential("alarm", 1.0, Servers::Infinite);
    let cleared = b.exponential("cleared", 1.0, Servers::Infinite);
    b.input(inspect, ok, 1);
    b.output(ok, inspect, 1);
    b.input(inspect, alarm, 1);
    b.output(alarm, handle, 1);
    b.input(handle, cleared, 1);
    b.output(cleared, inspect, 1);
    let net = b.build().expect("valid net");

    let mut h = Runtime::builder(net)
        .action(
            "inspect",
            Inspect {
                minutes: 5,
                count: Arc::default(),
            },
        )
        .action(
            "handle_alarm",
            action_fn(move |_ctx| async move { Outcome::Fire(cleared) }),
        )
        .bind("Inspect", "inspect")
        .bind("HandleAlarm", "handle_alarm")
        .seed(5)
        .max_firings(12)
        .spawn()
        .expect("spawn");
    let mut events = h.events();
    while let Some(Received::Event(e)) = events.recv().await {
        if let EventKind::Fired {
            transition,
            consumed,
            ..
        } = &e.kind
        {
            let name = &h.net().transition(*transition).name;
            println!("t={:>6.0}s  {name:<8} agents {consumed:?}", e.time);
        }
    }
    let s = h.wait().await;
    println!("{} firings, stopped: {}", s.firings, s.stopped);
}
