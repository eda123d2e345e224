//! The ROS 2 backend as 1 + 3 processes on loopback (feature `ros2`): `plan-runner run` as
//! the supervisor, three `plan-runner robot` processes serving ExecPlace, and a subscriber in
//! this test. Every wait is bounded; each test has its own DDS domain.
#![cfg(feature = "ros2")]

use crate::ros2_support as support;

use std::collections::BTreeSet;
use std::time::{Duration, Instant};

use gspn::io::{Format, ReadOptions, read_net, write_net};
use gspn::net::{NetBuilder, Servers};
use support::{
    domain, finish, listen, repo, robot, robot_with, supervisor, supervisor_with, take, terminate,
};

const ROBOTS: [&str; 3] = ["r1", "r2", "r3"];

fn place_and_transition_names() -> (Vec<String>, BTreeSet<String>) {
    let net = read_net(
        &repo("plans/nets/temperature_patrol.xml"),
        &ReadOptions::default(),
    )
    .expect("the patrol net")
    .net;
    (
        net.places().iter().map(|p| p.name.clone()).collect(),
        net.transitions().iter().map(|t| t.name.clone()).collect(),
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_firing_reaches_a_subscriber_exactly_once_in_order() {
    const N: usize = 60;
    let dir = tempfile::tempdir().unwrap();
    let d = domain(1);
    let (mut firings, mut markings) = listen(d);
    let _robots: Vec<_> = ROBOTS.iter().map(|r| robot(dir.path(), r, d)).collect();
    // 3 robots and this test subscribe to /gspn/firings: no firing before all 4 match.
    let sup = supervisor(
        dir.path(),
        d,
        &[
            "--max-firings",
            &N.to_string(),
            "--ros2-wait-subscribers",
            "4",
        ],
    );
    let got = take(&mut firings, N, Duration::from_secs(90)).await;
    let log = sup.log();
    let (code, out) = finish(sup, Duration::from_secs(30)).await;
    assert_eq!(got.len(), N, "firings received; supervisor log:\n{log}");
    assert_eq!(code, Some(0), "supervisor: {out}\n{log}");
    // Nothing more arrives: each firing exactly once.
    let extra = take(&mut firings, 1, Duration::from_millis(700)).await;
    assert!(extra.is_empty(), "a firing arrived twice: {extra:?}");

    let seqs: Vec<u64> = got.iter().map(|f| f.seq).collect();
    assert_eq!(seqs, (1..=N as u64).collect::<Vec<_>>());
    let (places, transitions) = place_and_transition_names();
    for f in &got {
        assert!(transitions.contains(&f.transition), "{}", f.transition);
        assert_eq!(f.marking.len(), places.len());
        // Three robots, each one token: every marking holds exactly 3.
        assert_eq!(f.marking.iter().sum::<u32>(), 3, "{f:?}");
        // Each firing of the patrol moves one robot.
        assert_eq!(f.robots.len(), 1, "{f:?}");
        assert!(ROBOTS.contains(&f.robots[0].as_str()), "{f:?}");
        assert!(f.header.stamp.sec > 1_700_000_000);
    }
    let movers: BTreeSet<&str> = got.iter().map(|f| f.robots[0].as_str()).collect();
    assert_eq!(movers.len(), 3, "all three robots move: {movers:?}");

    // The supervisor's own summary agrees with what was published.
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["stopped"], "max_firings");
    assert_eq!(summary["firings"], N as u64);
    let last = got.last().unwrap();
    for (p, k) in places.iter().zip(&last.marking) {
        assert_eq!(summary["final_marking"][p], *k, "place {p}");
    }
    // The marking topic ends on the last firing's marking.
    let mut last_marking = None;
    while let Ok(m) = markings.try_recv() {
        last_marking = Some(m);
    }
    let m = last_marking.expect("markings were published");
    assert_eq!(m.seq, N as u64);
    assert_eq!(m.places, places);
    assert_eq!(m.tokens, last.marking);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_robot_is_detected_and_the_failure_policy_stops_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = domain(2);
    let (mut firings, _markings) = listen(d);
    let mut robots: Vec<_> = ROBOTS.iter().map(|r| robot(dir.path(), r, d)).collect();
    let sup = supervisor(
        dir.path(),
        d,
        &["--max-firings", "1000000", "--ros2-wait-subscribers", "4"],
    );
    // Let the patrol run a little, then kill robot r2 (SIGKILL: no goodbye on DDS).
    let before = take(&mut firings, 20, Duration::from_secs(90)).await;
    assert_eq!(before.len(), 20, "supervisor log:\n{}", sup.log());
    robots[1].child.start_kill().expect("kill r2");
    let killed = Instant::now();
    // Detection: the supervisor says so on stderr (polled; bounded).
    let mut detected = None;
    while killed.elapsed() < Duration::from_secs(20) {
        if sup.log().contains("robot `r2` lost") {
            detected = Some(killed.elapsed());
            break;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let sup_log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(20)).await;
    let ended = killed.elapsed();
    let detected = detected.expect("the supervisor reports robot r2 lost");
    // The ROS 2 layer's own warning reaches stderr (a log subscriber is installed).
    let log = std::fs::read_to_string(&sup_log).unwrap();
    assert!(
        log.contains("WARN gspn::ros2::heartbeat: robot `r2`: no heartbeat for 1s: lost"),
        "{log}"
    );
    println!(
        "robot r2 killed → reported lost after {detected:?}, supervisor ended after {ended:?}"
    );
    // on_failure = "stop": the run ends as a failure, naming the lost robot.
    assert_eq!(code, Some(1), "{out}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["stopped"], "failure");
    let errors = summary["errors"].as_array().expect("errors");
    assert!(
        errors
            .iter()
            .any(|e| e.as_str().unwrap_or("").contains("robot `r2` lost")),
        "{errors:?}"
    );
    assert!(
        !errors
            .iter()
            .any(|e| e.as_str().unwrap_or("").contains("robot `r1` lost")
                || e.as_str().unwrap_or("").contains("robot `r3` lost")),
        "{errors:?}"
    );
    // The other robot processes leave by themselves: the supervisor said the run is over.
    let mut robots = robots.into_iter();
    let (r1, _r2, r3) = (
        robots.next().unwrap(),
        robots.next(),
        robots.next().unwrap(),
    );
    for r in [r1, r3] {
        let (name, log) = (r.name.clone(), r.log.clone());
        let (code, _) = finish(r, Duration::from_secs(20)).await;
        let log = std::fs::read_to_string(log).unwrap();
        assert_eq!(code, Some(0), "{name}: {log}");
        assert!(
            log.contains("the supervisor's run is over (failure after"),
            "{name}: {log}"
        );
    }
    // Every firing before the stop was published once, in order.
    let mut all = before;
    all.extend(take(&mut firings, usize::MAX, Duration::from_millis(700)).await);
    let seqs: Vec<u64> = all.iter().map(|f| f.seq).collect();
    assert_eq!(seqs, (1..=all.len() as u64).collect::<Vec<_>>());
    assert_eq!(summary["firings"], all.len() as u64);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_place_timeout_fails_the_action_and_every_running_goal_is_cancelled_on_its_robot() {
    let dir = tempfile::tempdir().unwrap();
    let d = domain(3);
    // The patrol plan with a 5-unit timeout (0.1 s at time_scale 0.02) on every place.
    let text = std::fs::read_to_string(repo(support::PLAN))
        .unwrap()
        .replace("timeout = 500.0", "timeout = 5.0")
        .replace(
            "net = \"nets/temperature_patrol.xml\"",
            &format!(
                "net = {:?}",
                repo("plans/nets/temperature_patrol.xml").to_string_lossy()
            ),
        );
    let plan = dir.path().join("short_timeout.toml");
    std::fs::write(&plan, text).unwrap();
    // Robots 10,000 s per model unit: their goals outlast the timeout by far. `--stay`: a
    // robot that heard "the run is over" before the cancel would leave without counting it.
    let robots: Vec<_> = ROBOTS
        .iter()
        .map(|r| {
            robot_with(
                dir.path(),
                r,
                &plan,
                d,
                &["--time-scale", "10000", "--stay"],
            )
        })
        .collect();
    let sup = supervisor_with(dir.path(), &plan, d, &[]);
    let (code, out) = finish(sup, Duration::from_secs(60)).await;
    assert_eq!(code, Some(1), "{out}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["stopped"], "failure");
    assert_eq!(summary["firings"], 0);
    let errors = summary["errors"].as_array().expect("errors");
    assert!(
        errors
            .iter()
            .any(|e| e.as_str().unwrap_or("").contains("timed out")),
        "{errors:?}"
    );
    // Each robot got its agent's goal and a cancel for it (the timed-out one through the
    // action's drop guard, the others because the run stopped).
    for r in robots {
        let name = r.name.clone();
        let log = terminate(r, Duration::from_secs(10)).await;
        assert!(
            log.contains(&format!("robot {name}: 1 goals, 1 cancelled")),
            "{name}: {log}"
        );
    }
}

/// Robots alternate between `Work` and `Move`; a failure in either sends the robot's agent to
/// `Broken` (no outputs) through `fail_w` / `fail_m`, whose rates are so small that robots
/// never pick them themselves.
fn write_work_move_plan(dir: &std::path::Path) -> std::path::PathBuf {
    let mut b = NetBuilder::new("work_move_broken");
    let work = b.place("Work", 3);
    let mv = b.place("Move", 0);
    let broken = b.place("Broken", 0);
    for (name, from, to, rate) in [
        ("done", work, mv, 1.0),
        ("arrive", mv, work, 1.0),
        ("fail_w", work, broken, 1e-6),
        ("fail_m", mv, broken, 1e-6),
    ] {
        let t = b.exponential(name, rate, Servers::Infinite);
        b.input(from, t, 1);
        b.output(t, to, 1);
    }
    write_net(&b.build().unwrap(), &dir.join("wm.pnml"), Format::Pnml).unwrap();
    let plan = dir.join("wm.toml");
    std::fs::write(
        &plan,
        "net = \"wm.pnml\"\nseed = 3\ntime_scale = 0.02\nrobots = [\"r1\", \"r2\", \"r3\"]\n\n\
         [places.Work]\naction = \"ros2\"\non_failure = \"fire fail_w\"\n\n\
         [places.Move]\naction = \"ros2\"\non_failure = \"fire fail_m\"\n",
    )
    .unwrap();
    plan
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn with_a_fire_policy_the_other_robots_carry_on_without_the_killed_one() {
    const N: usize = 150;
    let dir = tempfile::tempdir().unwrap();
    let plan = write_work_move_plan(dir.path());
    let d = domain(4);
    let (mut firings, _markings) = listen(d);
    let mut robots: Vec<_> = ROBOTS
        .iter()
        .map(|r| robot_with(dir.path(), r, &plan, d, &[]))
        .collect();
    let sup = supervisor_with(
        dir.path(),
        &plan,
        d,
        &[
            "--max-firings",
            &N.to_string(),
            "--ros2-wait-subscribers",
            "4",
        ],
    );
    let before = take(&mut firings, 20, Duration::from_secs(90)).await;
    assert_eq!(before.len(), 20, "supervisor log:\n{}", sup.log());
    robots[1].child.start_kill().expect("kill r2");
    let after = take(&mut firings, N - 20, Duration::from_secs(90)).await;
    let log = sup.log();
    let (code, out) = finish(sup, Duration::from_secs(30)).await;
    assert_eq!(code, Some(0), "{out}\n{log}");
    assert!(log.contains("robot `r2` lost"), "{log}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["stopped"], "max_firings");
    assert_eq!(summary["firings"], N as u64);
    assert_eq!(summary["final_marking"]["Broken"], 1);

    let all: Vec<_> = before.into_iter().chain(after).collect();
    let seqs: Vec<u64> = all.iter().map(|f| f.seq).collect();
    assert_eq!(seqs, (1..=N as u64).collect::<Vec<_>>());
    // Exactly one firing takes r2's agent to Broken; r2 never moves again; r1 and r3 do.
    let broke: Vec<usize> = (0..N)
        .filter(|&k| all[k].transition.starts_with("fail_"))
        .collect();
    assert_eq!(
        broke.len(),
        1,
        "{:?}",
        all.iter().map(|f| &f.transition).collect::<Vec<_>>()
    );
    let k = broke[0];
    assert_eq!(all[k].robots, vec!["r2".to_string()]);
    assert!(k >= 20, "r2 broke before it was killed");
    let later: BTreeSet<&str> = all[k + 1..]
        .iter()
        .flat_map(|f| f.robots.iter().map(String::as_str))
        .collect();
    assert_eq!(later, BTreeSet::from(["r1", "r3"]));
}

#[test]
fn bad_ros2_input_is_refused_with_exit_code_2() {
    let dir = tempfile::tempdir().unwrap();
    let net = repo("plans/nets/temperature_patrol.xml");
    let plan = |name: &str, body: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, format!("net = {:?}\n{body}", net.to_string_lossy())).unwrap();
        p
    };
    let run = |args: &[&std::ffi::OsStr]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_plan-runner"))
            .args(args)
            .output()
            .unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let bad_server = plan(
        "bad_server.toml",
        "[places.\"p2:Alarm_L1\"]\naction = \"ros2\"\nserver = \"bad name\"\n",
    );
    let (code, err) = run(&["run".as_ref(), bad_server.as_os_str()]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("bad_server.toml:4:10"), "{err}");
    assert!(
        err.contains("server `bad name` is not a ROS 2 name"),
        "{err}"
    );
    let no_robots = plan(
        "no_robots.toml",
        "[places.\"p2:Alarm_L1\"]\naction = \"ros2\"\n",
    );
    let (code, err) = run(&["run".as_ref(), no_robots.as_os_str()]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("no `robots = [...]`"), "{err}");
    let no_ros2 = repo("plans/temperature_patrol.toml");
    let (code, err) = run(&[
        "robot".as_ref(),
        "--id".as_ref(),
        "r1".as_ref(),
        "--plan".as_ref(),
        no_ros2.as_os_str(),
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("no place has action = \"ros2\""), "{err}");
}
