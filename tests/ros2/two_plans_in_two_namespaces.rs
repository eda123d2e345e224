//! Names as ROS does them (issue 25): two plans on one DDS domain, one under
//! `--ros-args -r __ns:=/fleet_a`, the other under `/fleet_b`, each with its own supervisor
//! and robots `r1`–`r3` (the same ids in both), run side by side without a single crossed
//! message: each namespace's firings topic carries its own run's firings only, nothing is
//! published under the default names, and each robot hears the end of its own run.

use crate::ros2_support as support;

use std::time::Duration;

use futures_util::StreamExt;
use gspn::ros2::DdsConfig;
use gspn::ros2::firings::FiringListener;
use gspn::ros2::msgs::Firing;
use tokio::sync::mpsc;

use support::{PLAN, domain, finish, listen, repo, robot_with, supervisor_with, take};

/// A subscriber of `<namespace>/gspn/firings` on `domain`.
fn listen_in(domain: u16, namespace: &str) -> mpsc::UnboundedReceiver<Firing> {
    let cfg = DdsConfig {
        domain_id: domain,
        namespace: namespace.to_string(),
        ..DdsConfig::default()
    };
    let mut node = cfg.node("test_listener", None).expect("a DDS node");
    let listener = FiringListener::new(&mut node).expect("subscriptions");
    let (tx, rx) = mpsc::unbounded_channel();
    tokio::spawn(async move {
        let _node = node;
        let firings = listener.firings();
        futures_util::pin_mut!(firings);
        while let Some(f) = firings.next().await {
            let _ = tx.send(f);
        }
    });
    rx
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_plans_share_a_domain_under_two_namespaces() {
    let d = domain(18);
    let plan = repo(PLAN);
    let fleets = [("/fleet_a", 60u64), ("/fleet_b", 40u64)];
    let mut default_names = listen(d).0;
    let mut runs = Vec::new();
    for (ns, n) in fleets {
        let dir = tempfile::tempdir().unwrap();
        let firings = listen_in(d, ns);
        let ros = ["--ros-args", "-r", &format!("__ns:={ns}")].map(str::to_string);
        let ros: Vec<&str> = ros.iter().map(String::as_str).collect();
        let robots: Vec<_> = ["r1", "r2", "r3"]
            .iter()
            .map(|r| robot_with(dir.path(), r, &plan, d, &ros))
            .collect();
        let mut extra = vec!["--max-firings", "1", "--ros2-wait-subscribers", "1"];
        let n_text = n.to_string();
        extra[1] = &n_text;
        extra.extend(&ros);
        extra.extend(["-r", "__node:=supervisor"]);
        let sup = supervisor_with(dir.path(), &plan, d, &extra);
        runs.push((ns, n, dir, firings, robots, sup));
    }
    for (ns, n, _dir, firings, robots, sup) in &mut runs {
        let mut got = take(firings, *n as usize, Duration::from_secs(90)).await;
        // Nothing more: a crossed firing would come on top.
        got.extend(take(firings, 1, Duration::from_millis(500)).await);
        let seqs: Vec<u64> = got.iter().map(|f| f.seq).collect();
        assert_eq!(
            seqs,
            (1..=*n).collect::<Vec<_>>(),
            "{ns}: its own run's firings, once each\n{}",
            sup.log()
        );
        for r in robots.iter() {
            assert!(
                r.log().contains(&format!("robot {}: serving", r.name)),
                "{ns} {}: {}",
                r.name,
                r.log()
            );
        }
    }
    for (ns, n, _dir, _firings, robots, sup) in runs {
        let log = sup.log.clone();
        let (code, out) = finish(sup, Duration::from_secs(30)).await;
        let text = std::fs::read_to_string(log).unwrap_or_default();
        assert_eq!(code, Some(0), "{ns}: {out}\n{text}");
        let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
        assert_eq!(summary["firings"], n, "{ns}");
        for r in robots {
            support::assert_leaves(
                r,
                Duration::from_secs(20),
                &format!("the supervisor's run is over (max_firings after {n} firings)"),
            )
            .await;
        }
    }
    let stray = take(&mut default_names, 1, Duration::from_millis(300)).await;
    assert!(stray.is_empty(), "published under /gspn/firings: {stray:?}");
}
