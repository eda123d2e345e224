//! The ROS 2 layer as an attacker on the machine sees it: every DDS socket of a default run
//! is bound to 127.0.0.1 (nothing listens on other interfaces), and malformed RTPS packets
//! (a peer claiming sequence numbers up to ~6·10¹³) do not make a robot's memory grow.
#![cfg(feature = "ros2")]

use crate::ros2_rtps as rtps;
use crate::ros2_support as support;

use std::net::{IpAddr, Ipv4Addr, UdpSocket};
use std::time::Duration;

use support::{
    domain, finish, robot, robot_with_data_limit, rss, supervisor, try_rss, udp_sockets,
    wait_for_log,
};

const LOOPBACK: IpAddr = IpAddr::V4(Ipv4Addr::LOCALHOST);

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_dds_socket_of_a_default_run_is_bound_to_loopback() {
    let dir = tempfile::tempdir().unwrap();
    let d = domain(5);
    let robots: Vec<_> = ["r1", "r2", "r3"]
        .iter()
        .map(|r| robot(dir.path(), r, d))
        .collect();
    let sup = supervisor(
        dir.path(),
        d,
        &["--max-firings", "30", "--ros2-linger", "3"],
    );
    assert!(
        wait_for_log(&sup, "ros2: robots ready", Duration::from_secs(60)).await,
        "{}",
        sup.log()
    );
    let mut all = Vec::new();
    for p in robots.iter().chain(std::iter::once(&sup)) {
        let pid = p.child.id().expect("running");
        let socks = udp_sockets(pid);
        // Discovery and user traffic listeners (unicast; no multicast on loopback) and the
        // unicast sender, per participant.
        assert!(socks.len() >= 3, "{}: {socks:?}", p.name);
        for s in &socks {
            assert_eq!(
                s.addr, LOOPBACK,
                "{} has a socket on {s:?}: {socks:?}",
                p.name
            );
        }
        all.push((p.name.clone(), socks));
    }
    println!("UDP sockets of a default run: {all:?}");
    // Bound to loopback, the run works: the patrol reaches its firing limit.
    let log = sup.log();
    let (code, out) = finish(sup, Duration::from_secs(60)).await;
    assert_eq!(code, Some(0), "{out}\n{log}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["firings"], 30);
    drop(robots);
}

/// A robot's memory before and after hostile packets: an SPDP announcement of a fake
/// participant, then HEARTBEATs from its SEDP announcers claiming sequence numbers
/// 1..=6·10¹³ (and a GAP over 2..6·10¹³), then DATA_FRAGs claiming samples of 3 GB;
/// unpatched RustDDS listed every "missing" number (over 1 GB in a second) and allocated
/// every claimed sample on its first fragment. The robot runs with its data segment
/// limited to 300 MB, so a regression makes it die at once (the test fails) rather than eat
/// the machine's memory.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn malformed_rtps_packets_do_not_make_a_robot_grow() {
    const HUGE: i64 = 60_000_000_000_000;
    let dir = tempfile::tempdir().unwrap();
    let d = domain(6);
    let mut r = robot_with_data_limit(dir.path(), "r1", d, 300 << 20);
    assert!(
        wait_for_log(&r, "serving on domain", Duration::from_secs(30)).await,
        "{}",
        r.log()
    );
    let pid = r.child.id().expect("running");
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let socks = udp_sockets(pid);
    assert!(!socks.is_empty());
    let baseline = rss(pid);

    let attacker = UdpSocket::bind((Ipv4Addr::LOCALHOST, 0)).unwrap();
    let reply = (Ipv4Addr::LOCALHOST, attacker.local_addr().unwrap().port());
    let prefix = *b"hostile-peer";
    let announce = rtps::spdp_announcement(prefix, reply);
    let beats = rtps::heartbeats(prefix, 1, HUGE, 1);
    println!(
        "packets: SPDP {} bytes, HEARTBEATs {} bytes, to ports {:?}",
        announce.len(),
        beats.len(),
        socks.iter().map(|s| s.port).collect::<Vec<_>>()
    );
    for s in &socks {
        attacker.send_to(&announce, (s.addr, s.port)).unwrap();
    }
    // Discovery matches the fake participant's announcers with the robot's detectors.
    tokio::time::sleep(Duration::from_millis(500)).await;
    for s in &socks {
        attacker.send_to(&beats, (s.addr, s.port)).unwrap();
        attacker
            .send_to(&rtps::gap(prefix, 2, HUGE), (s.addr, s.port))
            .unwrap();
        attacker
            .send_to(&rtps::heartbeats(prefix, 1, HUGE, 2), (s.addr, s.port))
            .unwrap();
        for sn in 1..=4 {
            attacker
                .send_to(&rtps::data_frag(prefix, sn, 3 << 30), (s.addr, s.port))
                .unwrap();
        }
    }
    // The robot answers the heartbeats (an ACKNACK to the announced locator): the packets
    // were processed, not dropped as garbage.
    attacker
        .set_read_timeout(Some(Duration::from_secs(5)))
        .unwrap();
    let mut buf = [0u8; 65536];
    let (n, _) = attacker
        .recv_from(&mut buf)
        .expect("the robot answers the fake participant");
    assert_eq!(&buf[..4], b"RTPS");
    assert!(n > 20);

    let mut peak = baseline;
    for _ in 0..30 {
        tokio::time::sleep(Duration::from_millis(100)).await;
        let now = try_rss(pid).filter(|_| r.child.try_wait().unwrap().is_none());
        let Some(now) = now else {
            let status = r.child.wait().await.unwrap();
            panic!(
                "the robot died ({status}, peak RSS {} MB before): {}",
                peak >> 20,
                r.log()
            );
        };
        peak = peak.max(now);
    }
    println!(
        "robot RSS: baseline {} MB, peak after the packets {} MB",
        baseline >> 20,
        peak >> 20
    );
    assert!(
        peak < baseline + (50 << 20),
        "RSS grew from {baseline} to {peak} bytes"
    );
    let log = r.log();
    assert!(!log.contains("panicked"), "{log}");
}
