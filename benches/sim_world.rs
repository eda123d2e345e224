//! Benchmark of the simulated robots (feature `sim`): physics steps per second of the rapier2d
//! room with ORCA for 64, 256 and 1,000 robots crossing a free room, and the real-time factor
//! of the whole temperature patrol (plans/temperature-patrol) for 4, 16 and 64 robots in
//! virtual time. Medians of 3 runs; the results are in docs/benchmarks.md.
//!
//! `cargo bench --bench sim_world`

use std::time::Instant;

use gspn::io::ReadOptions;
use gspn::plan::read_plan;
use gspn::world::Fleet;
use gspn::world::map::{Map, QueueSpec, RobotSpec};
use gspn::world::room::{Room, Vec2};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// `n` robots on a grid 1 m apart in an open walled room; each drives to the point opposite
/// its start through the centre, so every robot meets every other one's traffic.
fn steps_per_second(n: usize) -> (f64, u64) {
    let side = (n as f64).sqrt().ceil() as usize;
    let size = side as f64 + 2.0;
    let map = Map {
        locations: vec![],
        edges: vec![],
        patrol: vec![],
        walls: vec![
            [0.0, 0.0, size, 0.0],
            [size, 0.0, size, size],
            [size, size, 0.0, size],
            [0.0, size, 0.0, 0.0],
        ],
        obstacles: vec![],
        robot: RobotSpec::default(),
        queue: QueueSpec {
            lanes: 1,
            spacing: 0.5,
        },
        step_hz: 20.0,
        stuck_after: 30.0,
    };
    let starts: Vec<Vec2> = (0..n)
        .map(|i| Vec2::new(1.5 + (i % side) as f32, 1.5 + (i / side) as f32))
        .collect();
    let mut room = Room::new(&map, &starts);
    let c = Vec2::splat(size as f32 / 2.0);
    for b in &mut room.bodies {
        b.target = c * 2.0 - b.pos;
    }
    let steps = 400;
    let t = Instant::now();
    for _ in 0..steps {
        room.step();
    }
    (steps as f64 / t.elapsed().as_secs_f64(), room.collisions)
}

/// The patrol with `n` robots for 1,200 simulated seconds: (real-time factor, min cycles).
fn patrol(n: usize) -> (f64, u32, u64) {
    let plan = read_plan(
        std::path::Path::new("plans/temperature-patrol/plan.toml"),
        &ReadOptions::default(),
    )
    .expect("run from the repository root");
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .unwrap();
    rt.block_on(async {
        let fleet = Fleet::new(plan, Some(n)).unwrap();
        let handle = fleet.builder.subscribe_at_start(false).spawn().unwrap();
        handle.wait().await;
        let m = fleet.world.metrics().await.unwrap();
        fleet.world.stop();
        let min = m.cycles_per_robot.iter().copied().min().unwrap_or(0);
        (m.real_time_factor, min, m.collisions)
    })
}

fn main() {
    println!("| robots | physics steps/s (median of 3) | contact episodes |");
    println!("|---|---|---|");
    for n in [64, 256, 1000] {
        let runs: Vec<(f64, u64)> = (0..3).map(|_| steps_per_second(n)).collect();
        let sps = median(runs.iter().map(|r| r.0).collect());
        println!("| {n} | {sps:.0} | {} |", runs[0].1);
    }
    println!();
    println!(
        "| robots | real-time factor (median of 3) | min patrol loops in 1,200 s | collisions |"
    );
    println!("|---|---|---|---|");
    for n in [4, 16, 64] {
        let runs: Vec<(f64, u32, u64)> = (0..3).map(|_| patrol(n)).collect();
        let rtf = median(runs.iter().map(|r| r.0).collect());
        println!("| {n} | {rtf:.0}× | {} | {} |", runs[0].1, runs[0].2);
    }
}
