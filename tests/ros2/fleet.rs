//! Fleets on one host: 64 robot processes and the supervisor, started in a random order
//! (the supervisor after three quarters of them: discovery well beyond 12 participants), run
//! the temperature patrol to 100 firings; then every robot leaves by itself when the
//! supervisor says the run is over. `GSPN_FLEET=N` runs the same test with N robots, to
//! measure (docs/ros2.md, "Fleet limits").
//!
//! 64 fit 2 cores because robots' participants ignore each other (DdsConfig::context): before
//! that, every participant matched every other and the reliable built-in endpoints'
//! HEARTBEAT/ACKNACK traffic grew with the square of the fleet; 40 robots were ready after
//! 18–34 s or never, 64 never.
#![cfg(feature = "ros2")]

use crate::ros2_support as support;

use std::collections::BTreeSet;
use std::time::{Duration, Instant};

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use rustdds::RTPSEntity;
use support::{domain, finish, listen, repo, robot_with, supervisor_with, take, wait_for_log};

/// The patrol's net with `counts` robots at the three initial Check places (p1, p5, p9).
fn patrol_net(counts: [usize; 3]) -> String {
    const ONE: &str = "<initialMarking>\n      <value>Default,1</value>";
    let xml = std::fs::read_to_string(repo("plans/nets/temperature_patrol.xml")).unwrap();
    let mut out = String::new();
    let mut rest = xml.as_str();
    for n in counts {
        let at = rest.find(ONE).expect("an initial robot token");
        out.push_str(&rest[..at]);
        out.push_str(&ONE.replace("Default,1", &format!("Default,{n}")));
        rest = &rest[at + ONE.len()..];
    }
    assert!(!rest.contains(ONE), "more than three initial robot tokens");
    out.push_str(rest);
    out
}

/// The ROS 2 patrol plan for robots `ids` (net written beside it).
fn fleet_plan(dir: &std::path::Path, ids: &[String]) -> std::path::PathBuf {
    let n = ids.len();
    let counts = [n - 2 * (n / 3), n / 3, n / 3];
    std::fs::write(dir.join("patrol.xml"), patrol_net(counts)).unwrap();
    let robots: Vec<String> = ids.iter().map(|r| format!("{r:?}")).collect();
    let text = std::fs::read_to_string(repo(support::PLAN))
        .unwrap()
        .replace("nets/temperature_patrol.xml", "patrol.xml")
        .replace(
            "robots = [\"r1\", \"r2\", \"r3\"]",
            &format!("robots = [{}]", robots.join(", ")),
        )
        .replace("startup = 30.0", "startup = 240.0")
        // Heartbeats of a fleet of debug processes on 2 cores: a loaded machine must not lose a
        // robot.
        .replace("lost_after = 1.0", "lost_after = 10.0");
    let plan = dir.join("fleet.toml");
    std::fs::write(&plan, text).unwrap();
    plan
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_fleet_started_in_random_order_runs_the_patrol() {
    let _fleet = support::FLEET.lock().await;
    let fleet: usize = std::env::var("GSPN_FLEET")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(64);
    const FIRINGS: usize = 100;
    let dir = tempfile::tempdir().unwrap();
    // `GSPN_FLEET_KEEP=1`: the processes' logs stay in the directory printed, to measure.
    if std::env::var_os("GSPN_FLEET_KEEP").is_some() {
        println!("logs in {}", dir.path().display());
    }
    let dir = Keep(Some(dir));
    let d = domain(7);
    let ids: Vec<String> = (1..=fleet).map(|k| format!("r{k}")).collect();
    let plan = fleet_plan(dir.path(), &ids);

    // The robots in a random order (seeded: repeatable), the supervisor after three quarters
    // of them.
    let mut order: Vec<Option<&String>> = ids.iter().map(Some).collect();
    order.shuffle(&mut ChaCha8Rng::seed_from_u64(17));
    order.insert(3 * fleet / 4, None);
    let sup_at = 3 * fleet / 4;
    println!(
        "supervisor started as process {} of {}",
        sup_at + 1,
        order.len()
    );
    assert!(
        fleet < 16 || sup_at > 12,
        "the order must put the supervisor beyond index 12"
    );

    let (mut firings, _markings) = listen(d);
    let start = Instant::now();
    let mut robots = Vec::new();
    let mut sup = None;
    for who in &order {
        match who {
            Some(id) => robots.push(robot_with(dir.path(), id, &plan, d, &[])),
            None => {
                sup = Some(supervisor_with(
                    dir.path(),
                    &plan,
                    d,
                    &["--max-firings", &FIRINGS.to_string()],
                ))
            }
        }
        // One process at a time takes the next participant index.
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let sup = sup.unwrap();
    assert!(
        wait_for_log(&sup, "ros2: robots ready", Duration::from_secs(240)).await,
        "{}",
        sup.log()
    );
    let ready = start.elapsed();
    let got = take(&mut firings, FIRINGS, Duration::from_secs(120)).await;
    let log = sup.log();
    let (code, out) = finish(sup, Duration::from_secs(60)).await;
    let ran = start.elapsed();
    assert_eq!(code, Some(0), "{out}\n{log}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["stopped"], "max_firings");
    assert_eq!(summary["firings"], FIRINGS as u64);
    assert_eq!(got.len(), FIRINGS, "firings received");
    let seqs: Vec<u64> = got.iter().map(|f| f.seq).collect();
    assert_eq!(seqs, (1..=FIRINGS as u64).collect::<Vec<_>>());
    let movers: BTreeSet<&str> = got
        .iter()
        .flat_map(|f| f.robots.iter().map(String::as_str))
        .collect();
    assert!(
        movers.len() >= fleet / 2,
        "{} robots moved: {movers:?}",
        movers.len()
    );
    for f in &got {
        assert_eq!(f.marking.iter().sum::<u32>(), fleet as u32, "{f:?}");
    }

    // The run is over: every robot process leaves by itself, exit code 0.
    assert_eq!(robots.len(), fleet);
    for r in robots {
        let says = "the supervisor's run is over (max_firings after 100 firings)";
        support::assert_leaves(r, Duration::from_secs(60), says).await;
    }
    let all_left = start.elapsed();
    println!(
        "{fleet} robots + supervisor: all ready after {ready:.1?}, {FIRINGS} firings done after \
         {ran:.1?}, every robot gone after {all_left:.1?} ({} robots moved)",
        movers.len()
    );
}

/// A directory removed when dropped unless `GSPN_FLEET_KEEP` is set.
struct Keep(Option<tempfile::TempDir>);

impl Keep {
    fn path(&self) -> &std::path::Path {
        self.0.as_ref().expect("the directory").path()
    }
}

impl Drop for Keep {
    fn drop(&mut self) {
        if std::env::var_os("GSPN_FLEET_KEEP").is_some()
            && let Some(d) = self.0.take()
        {
            let _ = d.keep();
        }
    }
}

/// The participants (GUID prefixes, as text) whose writers `ctx` has discovered.
fn writers_seen(ctx: &ros2_client::Context) -> BTreeSet<String> {
    ctx.domain_participant()
        .discovered_writers()
        .iter()
        .map(|w| format!("{:?}", w.writer_proxy.remote_writer_guid.prefix))
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn robots_ignore_each_other_and_see_everyone_else() {
    let cfg = gspn::ros2::DdsConfig {
        domain_id: domain(13),
        ..gspn::ros2::DdsConfig::default()
    };
    let (a, b, sup) = (
        cfg.context(Some("a")).unwrap(),
        cfg.context(Some("b")).unwrap(),
        cfg.context(None).unwrap(),
    );
    let prefix = |c: &ros2_client::Context| format!("{:?}", c.domain_participant().guid().prefix);
    let (pa, pb, ps) = (prefix(&a), prefix(&b), prefix(&sup));
    // Every context has a writer (ROS 2's graph topic): the supervisor sees both robots'.
    let start = Instant::now();
    while !(writers_seen(&sup).contains(&pa) && writers_seen(&sup).contains(&pb)) {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "the supervisor never discovered both robots"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    // Each robot sees the supervisor, and still not the other robot a second later.
    while !(writers_seen(&a).contains(&ps) && writers_seen(&b).contains(&ps)) {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "a robot never discovered the supervisor"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    tokio::time::sleep(Duration::from_secs(1)).await;
    assert!(
        !writers_seen(&a).contains(&pb),
        "robot a discovered robot b"
    );
    assert!(
        !writers_seen(&b).contains(&pa),
        "robot b discovered robot a"
    );
    assert!(writers_seen(&a).contains(&ps) && writers_seen(&b).contains(&ps));
}
