//! One semantics: the temperature-patrol plan with no user actions, on virtual time, fires the
//! same transitions at the same times in the runtime and in the token game from the same seed
//! — both drive the one firing core (`gspn::firing`) and draw through the one sampler
//! (`gspn::sample`). The first 10,000 firings are pinned by hash, so a change in the firing
//! rules or in the sampler's numbers shows up here.

use std::path::Path;

use gspn::io::ReadOptions;
use gspn::plan::{Plan, read_plan};
use gspn::runtime::{EventKind, Received};
use gspn::sim::Simulator;

const FIRINGS: usize = 10_000;

/// FNV-1a over each firing's transition index and the bits of its time.
const TRACE_HASH: u64 = 0x3f76_94b2_3e89_f26c;

fn plan() -> Plan {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("plans/temperature_patrol.toml");
    read_plan(&path, &ReadOptions::default()).unwrap()
}

fn hash(trace: &[(u32, f64)]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &(t, time) in trace {
        for b in t
            .to_le_bytes()
            .into_iter()
            .chain(time.to_bits().to_le_bytes())
        {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

fn token_game(plan: &Plan) -> Vec<(u32, f64)> {
    let mut sim =
        Simulator::new(plan.net.clone(), plan.seed.unwrap()).with_policy(plan.policy.clone());
    (0..FIRINGS)
        .map(|_| {
            let step = sim.step().unwrap().expect("the patrol never dies");
            (step.transition.0, step.time)
        })
        .collect()
}

async fn runtime(plan: Plan) -> Vec<(u32, f64)> {
    let mut h = plan
        .runtime_builder()
        .max_firings(FIRINGS as u64)
        .until(1e12)
        .event_capacity(1 << 16)
        .subscribe_at_start(true)
        .spawn()
        .unwrap();
    let mut events = h.events();
    let mut trace = Vec::new();
    while let Some(r) = events.recv().await {
        match r {
            Received::Event(e) => {
                if let EventKind::Fired { transition, .. } = e.kind {
                    trace.push((transition.0, e.time));
                }
            }
            Received::Lagged(n) => panic!("{n} events lost"),
        }
    }
    h.wait().await;
    trace
}

#[tokio::test(start_paused = true)]
async fn the_runtime_and_the_token_game_fire_the_same_trace() {
    let plan = plan();
    assert_eq!(plan.seed, Some(2020));
    assert_eq!(plan.time_scale, Some(0.0));
    assert!(plan.roles.iter().all(Option::is_none), "no user actions");
    let game = token_game(&plan);
    let run = runtime(plan).await;
    assert_eq!(run.len(), FIRINGS);
    let first = game.iter().zip(&run).position(|(a, b)| a != b);
    assert_eq!(first, None, "first difference at firing {first:?}");
    assert_eq!(hash(&game), TRACE_HASH, "{:#x}", hash(&game));
    assert_eq!(hash(&run), TRACE_HASH);
}
