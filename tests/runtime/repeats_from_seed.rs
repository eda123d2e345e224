//! Virtual time: a run repeats exactly from its seed — with user actions that sleep on the
//! paused clock, immediate choices, forks and joins.

use std::time::Duration;

use gspn::net::{NetBuilder, Servers};
use gspn::runtime::{Event, Outcome, Runtime, action_fn};

async fn run(seed: u64) -> Vec<Event> {
    let mut b = NetBuilder::new("fork-join");
    let a = b.place("a", 2);
    let l = b.place("left", 0);
    let r = b.place("right", 0);
    let c = b.place("counter", 1);
    let fork = b.exponential("fork", 1.0, Servers::Infinite);
    let join = b.exponential("join", 2.0, Servers::Single);
    let x = b.immediate("x", 1.0, 1);
    let y = b.immediate("y", 3.0, 1);
    let tick = b.exponential("tick", 0.5, Servers::Single);
    let d = b.place("d", 0);
    b.input(a, fork, 1);
    b.output(fork, l, 1);
    b.output(fork, r, 1);
    b.input(l, join, 1);
    b.input(r, join, 1);
    b.output(join, d, 1);
    b.input(d, x, 1);
    b.output(x, a, 1);
    b.input(d, y, 1);
    b.output(y, a, 1);
    b.input(c, tick, 1);
    b.output(tick, c, 1);
    let net = b.build().unwrap();
    let mut h = Runtime::builder(net)
        .action(
            "walk",
            action_fn(|ctx| async move {
                let ms = 100 + 37 * (ctx.agent.0 % 5) + 11 * ctx.attempt as u64;
                tokio::time::sleep(Duration::from_millis(ms)).await;
                Outcome::Decide
            }),
        )
        .bind("left", "walk")
        .bind("right", "walk")
        .bind("d", "walk")
        .seed(seed)
        .max_firings(400)
        .event_capacity(1 << 16)
        .spawn()
        .unwrap();
    let events = h.events();
    h.wait().await;
    events.collect().await
}

#[tokio::test(start_paused = true)]
async fn the_same_seed_gives_the_same_run() {
    let first = run(17).await;
    let second = run(17).await;
    assert!(first.len() > 400);
    assert_eq!(first, second);
    let other = run(18).await;
    assert_ne!(first, other);
}
