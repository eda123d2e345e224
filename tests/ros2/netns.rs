//! The ROS 2 backend across "hosts": the supervisor and the robots in their own network
//! namespaces, joined by veth pairs to a bridge (itself in a namespace of its own, so nothing
//! of the machine's network changes), with 10.77.0.x addresses that exist only inside them.
//! DDS then runs as it would across machines: multicast discovery on the bridge, every
//! socket bound to the host's 10.x address.
//!
//! (a) 16 robots over 4 hosts run a fleet plan to its firing limit; (b) one host's link goes
//! down for 5 s: its robot is reported lost after `lost_after`, the place's `on_failure`
//! takes its agent to `Repair`, and after the link returns the robot serves new goals;
//! (c) lossy, slow links (`hub.rs`): every firing still reaches each robot once, in order.
//!
//! Needs root and `ip` (iproute2; `.ci/run` installs it when missing); fails, saying so,
//! without them.
#![cfg(feature = "ros2")]

use crate::ros2_support as support;

use std::collections::{BTreeMap, BTreeSet};
use std::net::{IpAddr, Ipv4Addr};
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use crate::ros2_hub::{Hub, Impairment, open_tap};
use gspn::io::{Format, write_net};
use gspn::net::{NetBuilder, Servers};
use support::{Proc, finish, terminate, udp_sockets, wait_for_log};

/// Runs `ip ARGS`, failing the test with its stderr when it fails.
pub fn ip(args: &[&str]) {
    let out = std::process::Command::new("ip")
        .args(args)
        .output()
        .unwrap_or_else(|e| {
            panic!("the netns tests need root and `ip` (iproute2; .ci/run installs it): {e}")
        });
    assert!(
        out.status.success(),
        "ip {}: {} (the netns tests need root)",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A host: a network namespace with one interface `eth0` at `addr`.
pub struct Host {
    pub ns: String,
    pub addr: Ipv4Addr,
}

/// Network namespaces for one test: `hosts` host namespaces joined by a bridge (in a
/// namespace of its own, through veth pairs) or by the user-space [`Hub`] (through TAP
/// devices); deleted, with their interfaces, when dropped.
pub struct Lab {
    bridge: Option<String>,
    pub hosts: Vec<Host>,
    pub hub: Option<Hub>,
}

/// Deletes namespace `ns` if it exists (left over from a killed run of the same pid).
fn del_ns(ns: &str) {
    let _ = std::process::Command::new("ip")
        .args(["netns", "del", ns])
        .output();
}

impl Lab {
    /// Hosts `h0 … h{n-1}` at 10.77.0.10, .11, … on a bridge; `tag` keeps namespaces of
    /// tests in parallel (and of other test processes) apart.
    pub fn new(tag: &str, n: usize) -> Lab {
        let base = format!("gspn{}{tag}", std::process::id());
        let bridge = format!("{base}-br");
        del_ns(&bridge);
        ip(&["netns", "add", &bridge]);
        let mut lab = Lab {
            bridge: Some(bridge.clone()),
            hosts: Vec::new(),
            hub: None,
        };
        ip(&["-n", &bridge, "link", "add", "br0", "type", "bridge"]);
        // No IGMP snooping: the bridge floods multicast (DDS discovery) to every port.
        ip(&[
            "-n",
            &bridge,
            "link",
            "set",
            "br0",
            "type",
            "bridge",
            "mcast_snooping",
            "0",
        ]);
        ip(&["-n", &bridge, "link", "set", "br0", "up"]);
        for k in 0..n {
            let ns = format!("{base}-h{k}");
            del_ns(&ns);
            ip(&["netns", "add", &ns]);
            let port = format!("p{k}");
            ip(&[
                "link", "add", "eth0", "netns", &ns, "type", "veth", "peer", "name", &port,
                "netns", &bridge,
            ]);
            ip(&["-n", &bridge, "link", "set", &port, "master", "br0", "up"]);
            lab.hosts.push(configure_host(ns, k));
        }
        lab
    }

    /// Hosts `h0 … h{n-1}` at 10.77.0.10, .11, … joined by a [`Hub`] that impairs every
    /// frame with `imp`.
    pub fn with_hub(tag: &str, n: usize, imp: Impairment) -> Lab {
        let base = format!("gspn{}{tag}", std::process::id());
        let mut lab = Lab {
            bridge: None,
            hosts: Vec::new(),
            hub: None,
        };
        let mut taps = Vec::new();
        for k in 0..n {
            let ns = format!("{base}-h{k}");
            del_ns(&ns);
            ip(&["netns", "add", &ns]);
            let tap = format!("g{}{tag}t{k}", std::process::id() % 100_000);
            taps.push(open_tap(&tap));
            ip(&["link", "set", &tap, "netns", &ns]);
            ip(&["-n", &ns, "link", "set", &tap, "name", "eth0"]);
            lab.hosts.push(configure_host(ns, k));
        }
        lab.hub = Some(Hub::start(taps, imp));
        lab
    }

    /// Takes host `k`'s link down (`up = false`) or up again.
    pub fn link(&self, k: usize, up: bool) {
        let state = if up { "up" } else { "down" };
        ip(&["-n", &self.hosts[k].ns, "link", "set", "eth0", state]);
        if up {
            // Bringing the link up again drops its routes: put the multicast one back.
            ip(&[
                "-n",
                &self.hosts[k].ns,
                "route",
                "replace",
                "224.0.0.0/4",
                "dev",
                "eth0",
            ]);
        }
    }
}

/// Host `k` in namespace `ns`, whose interface `eth0` exists: its address 10.77.0.(10+k),
/// the link up, and multicast (SPDP discovery to 239.255.0.1) routed through it.
fn configure_host(ns: String, k: usize) -> Host {
    let addr = Ipv4Addr::new(10, 77, 0, 10 + k as u8);
    let cidr = format!("{addr}/24");
    ip(&["-n", &ns, "addr", "add", &cidr, "dev", "eth0"]);
    ip(&["-n", &ns, "link", "set", "eth0", "up"]);
    ip(&["-n", &ns, "link", "set", "lo", "up"]);
    ip(&["-n", &ns, "route", "add", "224.0.0.0/4", "dev", "eth0"]);
    Host { ns, addr }
}

impl Drop for Lab {
    fn drop(&mut self) {
        self.hub = None;
        for h in &self.hosts {
            del_ns(&h.ns);
        }
        if let Some(b) = &self.bridge {
            del_ns(b);
        }
    }
}

/// `plan-runner ARGS` inside `host`'s namespace, DDS bound to its address; stderr to
/// `dir/<name>.log`, stdout piped; killed when dropped.
pub fn spawn_in(
    host: &Host,
    dir: &Path,
    name: &str,
    args: &[String],
    env: &[(&str, &str)],
) -> Proc {
    let log = dir.join(format!("{name}.log"));
    let child = tokio::process::Command::new("ip")
        .args(["netns", "exec", &host.ns, env!("CARGO_BIN_EXE_plan-runner")])
        .args(args)
        .args(["--ros2-networks", &host.addr.to_string()])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("RUST_LOG")
        .envs(env.iter().copied())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(std::fs::File::create(&log).expect("log file"))
        .kill_on_drop(true)
        .spawn()
        .expect("ip netns exec starts");
    Proc {
        name: name.to_string(),
        child,
        log,
    }
}

/// A fleet of `n` robots: agents alternate between `Work` and `Move` (ros2 places, the
/// robots time them: exponential, rate 1); a lost robot's agent goes to `Repair` (`wait
/// 60`, 60 model seconds) and then back to `Work`.
pub fn write_fleet_plan(dir: &Path, n: usize, time_scale: f64, stop: &str) -> PathBuf {
    let mut b = NetBuilder::new("fleet");
    let work = b.place("Work", n as u32);
    let mv = b.place("Move", 0);
    let repair = b.place("Repair", 0);
    for (name, from, to, rate) in [
        ("done", work, mv, 1.0),
        ("arrive", mv, work, 1.0),
        ("lose_w", work, repair, 1e-6),
        ("lose_m", mv, repair, 1e-6),
        ("back", repair, work, 1.0),
    ] {
        let t = b.exponential(name, rate, Servers::Infinite);
        b.input(from, t, 1);
        b.output(t, to, 1);
    }
    write_net(&b.build().unwrap(), &dir.join("fleet.pnml"), Format::Pnml).unwrap();
    let robots: Vec<String> = (1..=n).map(|k| format!("\"r{k}\"")).collect();
    let plan = dir.join("fleet.toml");
    std::fs::write(
        &plan,
        format!(
            "net = \"fleet.pnml\"\nseed = 7\ntime_scale = {time_scale}\nrobots = [{}]\n\n\
             [ros2]\nlost_after = 1.0\nstartup = 90.0\n\n\
             [places.Work]\naction = \"ros2\"\non_failure = \"fire lose_w\"\n\n\
             [places.Move]\naction = \"ros2\"\non_failure = \"fire lose_m\"\n\n\
             [places.Repair]\naction = \"wait 60\"\n\n[stop]\n{stop}\n",
            robots.join(", ")
        ),
    )
    .unwrap();
    plan
}

fn args(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

/// `plan-runner robot --id ID --plan PLAN --ros2-domain 0 EXTRA…` on `host`.
fn robot_on(host: &Host, dir: &Path, id: &str, plan: &str, extra: &[&str]) -> Proc {
    let mut a = args(&["robot", "--id", id, "--plan", plan, "--ros2-domain", "0"]);
    a.extend(args(extra));
    spawn_in(host, dir, id, &a, &[])
}

/// The journal's firings: (transition, robots).
fn firings(journal: &Path) -> Vec<(String, Vec<String>)> {
    std::fs::read_to_string(journal)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|e| e["event"] == "fired")
        .map(|e| {
            let robots = e["robots"]
                .as_array()
                .map(|a| a.iter().map(|r| r.as_str().unwrap().to_string()).collect())
                .unwrap_or_default();
            (e["transition"].as_u64().unwrap().to_string(), robots)
        })
        .collect()
}

/// Transition names of the fleet net, by index (the journal names transitions by index).
fn transition_names(dir: &Path) -> Vec<String> {
    let net = gspn::io::read_net(&dir.join("fleet.pnml"), &gspn::io::ReadOptions::default())
        .unwrap()
        .net;
    net.transitions().iter().map(|t| t.name.clone()).collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sixteen_robots_on_four_hosts_run_the_fleet_plan() {
    let _fleet = support::FLEET.lock().await;
    const N: u64 = 200;
    let dir = tempfile::tempdir().unwrap();
    let plan = write_fleet_plan(dir.path(), 16, 0.02, &format!("max_firings = {N}"));
    let lab = Lab::new("a", 5);
    let d = "0";
    let plan_s = plan.to_string_lossy().into_owned();
    let mut robots = Vec::new();
    for k in 1..=16 {
        let host = &lab.hosts[1 + (k - 1) % 4];
        let id = format!("r{k}");
        robots.push((
            1 + (k - 1) % 4,
            robot_on(host, dir.path(), &id, &plan_s, &[]),
        ));
    }
    let journal = dir.path().join("journal.jsonl");
    let a = args(&[
        "run",
        &plan_s,
        "--json",
        "--ros2-domain",
        d,
        "--journal",
        journal.to_str().unwrap(),
        "--ros2-linger",
        "2",
    ]);
    let sup = spawn_in(&lab.hosts[0], dir.path(), "supervisor", &a, &[]);
    let started = Instant::now();
    assert!(
        wait_for_log(&sup, "ros2: robots ready", Duration::from_secs(120)).await,
        "{}",
        sup.log()
    );
    let ready = started.elapsed();
    // Every DDS socket of every process is bound to its host's address.
    for (k, r) in robots.iter().map(|(h, p)| (*h, p)).chain([(0, &sup)]) {
        let socks = udp_sockets(r.child.id().expect("running"));
        assert!(socks.len() >= 3, "{}: {socks:?}", r.name);
        let mine = IpAddr::V4(lab.hosts[k].addr);
        let group = IpAddr::V4(Ipv4Addr::new(239, 255, 0, 1));
        for s in &socks {
            assert!(s.addr == mine || s.addr == group, "{}: {socks:?}", r.name);
        }
    }
    let log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(120)).await;
    let done = started.elapsed();
    let log = std::fs::read_to_string(log).unwrap();
    assert_eq!(code, Some(0), "{out}\n{log}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["firings"], N);
    // Every robot, on every host, moved.
    let moved: BTreeSet<String> = firings(&journal).into_iter().flat_map(|(_, r)| r).collect();
    let all: BTreeSet<String> = (1..=16).map(|k| format!("r{k}")).collect();
    assert_eq!(moved, all);
    // And every robot leaves when the run is over.
    for (_, r) in robots {
        let (name, log) = (r.name.clone(), r.log.clone());
        let (code, _) = finish(r, Duration::from_secs(30)).await;
        let text = std::fs::read_to_string(log).unwrap();
        assert_eq!(code, Some(0), "{name}: {text}");
        assert!(
            text.contains("the supervisor's run is over"),
            "{name}: {text}"
        );
    }
    println!(
        "netns (a): 16 robots on 4 hosts + the supervisor's: ready after {ready:?}, {N} firings after {done:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_host_cut_off_for_5_s_is_lost_repaired_and_serves_again() {
    let _fleet = support::FLEET.lock().await;
    let dir = tempfile::tempdir().unwrap();
    // 4 robots, one per host; 25 s of real time (250 model seconds × 0.1).
    let plan = write_fleet_plan(dir.path(), 4, 0.1, "time_limit = 250.0");
    let lab = Lab::new("b", 5);
    let plan_s = plan.to_string_lossy().into_owned();
    let mut robots = Vec::new();
    for k in 1..=4 {
        let id = format!("r{k}");
        // --stay: a robot cut off from its supervisor keeps serving for when it is back.
        robots.push(robot_on(
            &lab.hosts[k],
            dir.path(),
            &id,
            &plan_s,
            &["--stay"],
        ));
    }
    let journal = dir.path().join("journal.jsonl");
    let a = args(&[
        "run",
        &plan_s,
        "--json",
        "--ros2-domain",
        "0",
        "--journal",
        journal.to_str().unwrap(),
    ]);
    let sup = spawn_in(&lab.hosts[0], dir.path(), "supervisor", &a, &[]);
    assert!(
        wait_for_log(&sup, "ros2: robots ready", Duration::from_secs(120)).await,
        "{}",
        sup.log()
    );
    tokio::time::sleep(Duration::from_secs(2)).await;
    // Robot r2's host (h2) is cut off for 5 s.
    lab.link(2, false);
    let down = Instant::now();
    assert!(
        wait_for_log(&sup, "ros2: robot `r2` lost", Duration::from_secs(20)).await,
        "{}",
        sup.log()
    );
    let lost = down.elapsed();
    let wait = Duration::from_secs(5).saturating_sub(down.elapsed());
    tokio::time::sleep(wait).await;
    lab.link(2, true);
    let up = Instant::now();
    assert!(
        wait_for_log(&sup, "ros2: robot `r2` is back", Duration::from_secs(30)).await,
        "{}",
        sup.log()
    );
    let back = up.elapsed();
    let log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(60)).await;
    let log = std::fs::read_to_string(log).unwrap();
    assert_eq!(code, Some(0), "{out}\n{log}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["stopped"], "time_limit", "{summary}");
    // Lost `lost_after` (1 s) after its last heartbeat, which came at most one heartbeat
    // period (0.1 s) before the link went down.
    assert!(lost >= Duration::from_millis(900), "lost after {lost:?}");

    let names = transition_names(dir.path());
    let fired: Vec<(String, Vec<String>)> = firings(&journal)
        .into_iter()
        .map(|(t, r)| (names[t.parse::<usize>().unwrap()].clone(), r))
        .collect();
    let r2 = vec!["r2".to_string()];
    let of_r2: Vec<&str> = fired
        .iter()
        .filter(|(_, r)| *r == r2)
        .map(|(t, _)| t.as_str())
        .collect();
    // on_failure: r2's agent went to Repair once (lose_w or lose_m), came back, and its
    // robot served new goals (done / arrive) afterwards; no other robot was lost.
    let lose = of_r2
        .iter()
        .position(|t| t.starts_with("lose_"))
        .unwrap_or_else(|| panic!("r2 never lost: {of_r2:?}\n{log}"));
    assert_eq!(of_r2[lose + 1], "back", "{of_r2:?}");
    assert!(
        of_r2[lose + 2..]
            .iter()
            .any(|t| *t == "done" || *t == "arrive"),
        "r2 served no goal after it came back: {of_r2:?}\n{log}"
    );
    let losses: BTreeMap<String, usize> = fired
        .iter()
        .filter(|(t, _)| t.starts_with("lose_"))
        .fold(BTreeMap::new(), |mut m, (_, r)| {
            *m.entry(r.join(",")).or_default() += 1;
            m
        });
    assert_eq!(losses, BTreeMap::from([("r2".to_string(), 1)]), "{log}");
    for r in robots {
        terminate(r, Duration::from_secs(10)).await;
    }
    println!(
        "netns (b): r2's host down 5 s: reported lost after {lost:?}, back {back:?} after the link returned; r2 fired {} times ({} after its repair)",
        of_r2.len(),
        of_r2.len() - lose - 2
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn over_lossy_slow_links_every_firing_reaches_every_robot_once_in_order() {
    let _fleet = support::FLEET.lock().await;
    const N: usize = 100;
    let dir = tempfile::tempdir().unwrap();
    let plan = write_fleet_plan(dir.path(), 4, 0.02, &format!("max_firings = {N}"));
    // 10% of the frames lost and 50 ms of delay on every delivery, on every link.
    let imp = Impairment {
        loss: 0.10,
        delay: Duration::from_millis(50),
        seed: 17,
    };
    let lab = Lab::with_hub("c", 5, imp);
    let plan_s = plan.to_string_lossy().into_owned();
    let mut robots = Vec::new();
    for k in 1..=4 {
        let id = format!("r{k}");
        let lat = dir.path().join(format!("latency_{id}.txt"));
        // --stay: a robot that hears "over" before the last firings' repairs keeps
        // receiving them.
        let extra = ["--stay", "--latency-log", lat.to_str().unwrap()];
        let r = robot_on(&lab.hosts[k], dir.path(), &id, &plan_s, &extra);
        robots.push((lat, r));
    }
    // The 4 robots subscribe to /gspn/firings: no firing before they are all matched.
    let a = args(&[
        "run",
        &plan_s,
        "--json",
        "--ros2-domain",
        "0",
        "--ros2-wait-subscribers",
        "4",
        "--ros2-linger",
        "20",
    ]);
    let sup = spawn_in(&lab.hosts[0], dir.path(), "supervisor", &a, &[]);
    let started = Instant::now();
    let log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(240)).await;
    let took = started.elapsed();
    let log = std::fs::read_to_string(log).unwrap();
    assert_eq!(code, Some(0), "{out}\n{log}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["firings"], N as u64);

    let mut latencies = Vec::new();
    for (lat, r) in robots {
        // Every firing, once, in order: seq 1..=N (waiting, bounded, for late repairs).
        let end = Instant::now() + Duration::from_secs(30);
        let lines = loop {
            let text = std::fs::read_to_string(&lat).unwrap_or_default();
            let lines: Vec<(u64, i128, i128)> = text
                .lines()
                .map(|l| {
                    let f: Vec<&str> = l.split_whitespace().collect();
                    (
                        f[0].parse().unwrap(),
                        f[1].parse().unwrap(),
                        f[2].parse().unwrap(),
                    )
                })
                .collect();
            if lines.len() >= N || Instant::now() > end {
                break lines;
            }
            tokio::time::sleep(Duration::from_millis(100)).await;
        };
        let seqs: Vec<u64> = lines.iter().map(|l| l.0).collect();
        assert_eq!(seqs, (1..=N as u64).collect::<Vec<_>>(), "{}", r.name);
        latencies.extend(lines.iter().map(|&(_, sent, got)| got - sent));
        terminate(r, Duration::from_secs(10)).await;
    }
    latencies.sort_unstable();
    let ms = |q: f64| latencies[((latencies.len() - 1) as f64 * q) as usize] as f64 / 1e6;
    let hub = lab.hub.as_ref().unwrap();
    let (sent, lost) = (
        hub.stats
            .delivered
            .load(std::sync::atomic::Ordering::Relaxed),
        hub.stats.dropped.load(std::sync::atomic::Ordering::Relaxed),
    );
    println!(
        "netns (c): 4 robots on 4 hosts, 10% loss + 50 ms delay per delivered frame ({lost} of {} frames dropped): {N} firings in {took:?}; firing → robot latency p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms",
        sent + lost,
        ms(0.5),
        ms(0.99),
        ms(1.0)
    );
    // The impairment was in force: no firing reached a robot in less than the delay.
    assert!(ms(0.0) >= 50.0, "fastest firing {:.1} ms", ms(0.0));
    assert!(lost > 0);
}
