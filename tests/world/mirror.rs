//! A mirror world (`Fleet::mirror`, `run --nav2`): robots that drive themselves — here a
//! navigator in the test that takes 4 s per leg and reports a pose half-way, as Nav2's
//! feedback would — run the temperature patrol's built-in actions unchanged. The world
//! steps no physics: it keeps the queues, turns and draws, counts the arrivals, and shows
//! each robot where it was told. In virtual time, so the same seed gives the same run.
#![cfg(feature = "sim")]

use std::path::PathBuf;
use std::pin::Pin;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use gspn::io::ReadOptions;
use gspn::plan::read_plan;
use gspn::runtime::StopReason;
use gspn::world::map::Map;
use gspn::world::{DriveError, Fleet, Navigator, WorldHandle};

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// Robots that drive themselves: 2 s to half-way (reported), 2 s more to the location.
/// Every leg is logged as (robot, location).
#[derive(Debug)]
struct SelfDriving {
    world: WorldHandle,
    map: Arc<Map>,
    legs: Arc<Mutex<Vec<(String, usize)>>>,
}

impl Navigator for SelfDriving {
    fn goto(
        &self,
        robot: Arc<str>,
        location: usize,
    ) -> Pin<Box<dyn std::future::Future<Output = Result<(), DriveError>> + Send>> {
        let world = self.world.clone();
        let (x, y) = (
            self.map.locations[location].x,
            self.map.locations[location].y,
        );
        let legs = Arc::clone(&self.legs);
        Box::pin(async move {
            legs.lock().unwrap().push((robot.to_string(), location));
            let drive = async {
                tokio::time::sleep(Duration::from_secs(2)).await;
                world.set_pose(Arc::clone(&robot), x - 1.5, y);
                tokio::time::sleep(Duration::from_secs(2)).await;
                world.set_pose(Arc::clone(&robot), x, y);
                Ok(())
            };
            world.mirror_goto(Arc::clone(&robot), location, drive).await
        })
    }
}

/// The patrol on `n` self-driving robots for 120 firings: the summary's firings and final
/// marking, the legs driven, the metrics' loops and order violations, the last poses.
async fn mirrored_patrol(
    n: usize,
) -> (
    u64,
    Vec<u32>,
    Vec<(String, usize)>,
    Vec<u32>,
    u64,
    Vec<(f64, f64)>,
) {
    let mut plan = read_plan(
        &repo("plans/temperature-patrol/plan.toml"),
        &ReadOptions::default(),
    )
    .unwrap();
    plan.stop.max_firings = Some(120);
    let fleet = Fleet::mirror(plan, Some(n)).unwrap();
    let legs = Arc::default();
    let nav = SelfDriving {
        world: fleet.world.clone(),
        map: Arc::clone(&fleet.map),
        legs: Arc::clone(&legs),
    };
    let fleet = fleet.navigate_with(Arc::new(nav));
    let view = fleet.world.view();
    let handle = fleet.builder.subscribe_at_start(false).spawn().unwrap();
    let summary = handle.wait().await;
    assert_eq!(
        summary.stopped,
        StopReason::MaxFirings,
        "{:?}",
        summary.errors
    );
    assert!(summary.errors.is_empty(), "{:?}", summary.errors);
    let m = fleet.world.metrics().await.unwrap();
    let poses = view.borrow().robots.iter().map(|r| (r.x, r.y)).collect();
    fleet.world.stop();
    let legs = legs.lock().unwrap().clone();
    (
        summary.firings,
        summary.final_marking.iter().map(|(_, &k)| k).collect(),
        legs,
        m.cycles_per_robot,
        m.order_violations,
        poses,
    )
}

#[tokio::test(start_paused = true)]
async fn the_patrol_runs_on_robots_that_drive_themselves() {
    let (firings, _, legs, cycles, violations, poses) = mirrored_patrol(3).await;
    assert_eq!(firings, 120);
    // Every robot drove, every leg to a patrol location; arrivals are counted as loops.
    for r in ["r1", "r2", "r3"] {
        assert!(
            legs.iter().filter(|l| l.0 == r).count() >= 3,
            "{r}: {legs:?}"
        );
    }
    assert!(cycles.iter().all(|&c| c >= 1), "{cycles:?}");
    assert_eq!(
        violations, 0,
        "robots leave a location in the order they came"
    );
    // The world shows the robots where they were told (a location or half-way to one),
    // not where physics would have put them.
    let plan = read_plan(
        &repo("plans/temperature-patrol/plan.toml"),
        &ReadOptions::default(),
    )
    .unwrap();
    let map = plan.map.unwrap();
    let start_slots = 3;
    let told = |&(x, y): &(f64, f64)| {
        map.locations.iter().any(|l| {
            ((l.x - x).abs() < 1e-3 || (l.x - 1.5 - x).abs() < 1e-3) && (l.y - y).abs() < 1e-3
        })
    };
    let moved = poses.iter().filter(|p| told(p)).count();
    assert!(
        moved + start_slots >= poses.len() && moved >= 1,
        "{poses:?}"
    );
}

#[tokio::test(start_paused = true)]
async fn the_same_seed_gives_the_same_mirrored_run() {
    let a = mirrored_patrol(2).await;
    let b = mirrored_patrol(2).await;
    assert_eq!((a.0, &a.1, &a.2, &a.3), (b.0, &b.1, &b.2, &b.3));
}
