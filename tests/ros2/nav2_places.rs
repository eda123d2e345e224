//! Nav2 places on real robots (issue 25, part 3): a `ros2` place with
//! `server = "navigate_to_pose"` and a `target` sends its agent's robot a Nav2
//! `NavigateToPose` goal at `/<robot>/navigate_to_pose` (frame `map`), follows the result
//! (succeeded → the policy decides; aborted → `Failed`, the place's `on_failure`) and cancels
//! the goal when the run stops. The robots' Nav2 is a `NavigateToPose` server in the test
//! (ros2-client, Nav2's types from `gspn::ros2::msgs::nav2`); the other places go to
//! `plan-runner robot` processes as ExecPlace goals.
#![cfg(feature = "ros2")]

use crate::ros2_support as support;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use gspn::ros2::DdsConfig;
use gspn::ros2::msgs::nav2::{
    NavigateToPoseFeedback, NavigateToPoseGoal, NavigateToPoseResult, navigate_to_pose_type,
};
use gspn::ros2::settings::{Ros2Settings, ServiceMapping};
use ros2_client::Name;
use ros2_client::action::{AsyncActionServer, GoalEndStatus, GoalId};
use support::{domain, finish, repo, robot_with, supervisor_with};

type Server = AsyncActionServer<NavigateToPoseGoal, NavigateToPoseResult, NavigateToPoseFeedback>;

/// What the fake Nav2 saw: (robot, x, y, frame, yaw), and the goals cancelled.
#[derive(Default)]
struct Seen {
    goals: Vec<(String, f64, f64, String, f64)>,
    cancelled: usize,
}

/// The patrol plan with its four Check_Temperature places as Nav2 places: location k's
/// target is `[k, 2, 0.5]`.
fn nav2_plan(dir: &Path) -> PathBuf {
    let mut text = std::fs::read_to_string(repo(support::PLAN))
        .unwrap()
        .replace(
            "net = \"nets/temperature_patrol.xml\"",
            &format!(
                "net = {:?}",
                repo("plans/nets/temperature_patrol.xml").to_string_lossy()
            ),
        );
    for (k, p) in [(1, "p1"), (2, "p5"), (3, "p9"), (4, "p13")] {
        let head = format!("[places.\"{p}:Check_Temperature_L{k}\"]\naction = \"ros2\"\n");
        let old = format!("{head}server = \"exec_place\"");
        assert!(text.contains(&old), "{old}");
        let new = format!("{head}server = \"navigate_to_pose\"\ntarget = [{k}.0, 2.0, 0.5]");
        text = text.replace(&old, &new);
    }
    let plan = dir.join("nav2.toml");
    std::fs::write(&plan, text).unwrap();
    plan
}

/// Serves `/<robot>/navigate_to_pose` for `robots` on domain `d`: a goal to x = `hold_x`
/// runs until cancelled, one to x = `abort_x` is aborted after 0.3 s (error 9000 `blocked`), any other
/// succeeds after 20 ms.
fn fake_nav2(
    d: u16,
    robots: &[&str],
    abort_x: f64,
    hold_x: f64,
) -> (
    Arc<Mutex<Seen>>,
    Vec<tokio::task::JoinHandle<()>>,
    ros2_client::Node,
) {
    let settings = Ros2Settings {
        domain_id: Some(d),
        service_mapping: ServiceMapping::Enhanced,
        ..Ros2Settings::default()
    };
    let cfg = DdsConfig::resolve(&settings).unwrap().for_fleet(8);
    let mut node = cfg.node("nav2_fake", None).unwrap();
    let spinner = node.spinner().unwrap();
    let mut tasks = vec![tokio::spawn(async move {
        let _ = spinner.spin().await;
    })];
    let seen = Arc::new(Mutex::new(Seen::default()));
    for r in robots {
        let server = node
            .create_action_server::<NavigateToPoseGoal, NavigateToPoseResult, NavigateToPoseFeedback>(
                cfg.service_mapping,
                &Name::new(&format!("/{r}"), "navigate_to_pose").unwrap(),
                &navigate_to_pose_type(),
                gspn::ros2::nav2::server_qos(),
            )
            .unwrap();
        let server = Arc::new(AsyncActionServer::new(server));
        tasks.push(tokio::spawn(serve(
            server,
            r.to_string(),
            Arc::clone(&seen),
            abort_x,
            hold_x,
        )));
    }
    (seen, tasks, node)
}

/// A goal held until cancelled, and the sender that ends it.
type Held = (GoalId, tokio::sync::oneshot::Sender<()>);

async fn serve(
    server: Arc<Server>,
    robot: String,
    seen: Arc<Mutex<Seen>>,
    abort_x: f64,
    hold_x: f64,
) {
    let held: Arc<Mutex<Vec<Held>>> = Arc::default();
    loop {
        tokio::select! {
            g = server.receive_new_goal() => {
                let Ok(handle) = g else { continue };
                let Some(goal) = server.get_new_goal(handle.clone()) else { continue };
                let p = &goal.pose;
                let (x, y) = (p.pose.position.x, p.pose.position.y);
                seen.lock().unwrap().goals.push((
                    robot.clone(),
                    x,
                    y,
                    p.header.frame_id.clone(),
                    p.pose.orientation.yaw(),
                ));
                let (tx, rx) = tokio::sync::oneshot::channel();
                held.lock().unwrap().push((handle.goal_id(), tx));
                let (server, seen) = (Arc::clone(&server), Arc::clone(&seen));
                tokio::spawn(async move {
                    let Ok(accepted) = server.accept_goal(handle).await else { return };
                    let Ok(executing) = server.start_executing_goal(accepted).await else {
                        return;
                    };
                    let (status, result) = if x == abort_x {
                        // Later than the other robots' first goals, which are then held.
                        tokio::time::sleep(Duration::from_millis(300)).await;
                        let r = NavigateToPoseResult {
                            error_code: NavigateToPoseResult::UNKNOWN,
                            error_msg: "blocked".into(),
                        };
                        (GoalEndStatus::Aborted, r)
                    } else if x == hold_x {
                        let _ = rx.await;
                        seen.lock().unwrap().cancelled += 1;
                        (GoalEndStatus::Canceled, NavigateToPoseResult::default())
                    } else {
                        tokio::time::sleep(Duration::from_millis(20)).await;
                        (GoalEndStatus::Succeeded, NavigateToPoseResult::default())
                    };
                    let send = server.send_result_response(executing, status, result);
                    let _ = tokio::time::timeout(Duration::from_secs(5), send).await;
                });
            }
            c = server.receive_cancel_request() => {
                let Ok(cancel) = c else { continue };
                let ids: Vec<GoalId> = {
                    let mut h = held.lock().unwrap();
                    let (hit, keep): (Vec<_>, Vec<_>) =
                        std::mem::take(&mut *h).into_iter().partition(|(id, _)| cancel.contains_goal(id));
                    *h = keep;
                    hit.into_iter().map(|(id, tx)| { let _ = tx.send(()); id }).collect()
                };
                let _ = server.respond_to_cancel_requests(&cancel, ids.into_iter()).await;
            }
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn nav2_places_send_navigate_to_pose_and_an_aborted_goal_fails_the_place() {
    let d = domain(0);
    let dir = tempfile::tempdir().unwrap();
    let plan = nav2_plan(dir.path());
    // The robots serve the other places (ExecPlace) and stay for the second run.
    let _robots: Vec<_> = ["r1", "r2", "r3"]
        .iter()
        .map(|r| robot_with(dir.path(), r, &plan, d, &["--stay"]))
        .collect();

    // 1. Every Nav2 goal succeeds: the patrol runs to 30 firings.
    let (seen, tasks, node) = fake_nav2(d, &["r1", "r2", "r3"], -1.0, -1.0);
    let sup = supervisor_with(dir.path(), &plan, d, &["--max-firings", "30"]);
    let log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(90)).await;
    let log = std::fs::read_to_string(&log).unwrap_or_default();
    assert_eq!(code, Some(0), "{out}\n{log}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("a JSON summary");
    assert_eq!(summary["firings"], 30, "{out}");
    {
        let s = seen.lock().unwrap();
        // The agents start in Check_Temperature L1, L2, L3 with robots r1, r2, r3.
        for (r, k) in [("r1", 1.0), ("r2", 2.0), ("r3", 3.0)] {
            let first = s.goals.iter().find(|g| g.0 == r).expect("a goal per robot");
            assert_eq!((first.1, first.2), (k, 2.0), "{r}: {first:?}");
        }
        for g in &s.goals {
            assert_eq!(g.3, "map", "{g:?}");
            assert!((g.4 - 0.5).abs() < 1e-12, "yaw {g:?}");
            assert!([1.0, 2.0, 3.0, 4.0].contains(&g.1) && g.2 == 2.0, "{g:?}");
        }
        assert_eq!(s.cancelled, 0);
    }
    for t in tasks {
        t.abort();
    }
    drop(node);

    // 2. Nav2 aborts the goal to L2 and holds the one to L1 until cancelled: r2's place
    //    fails (on_failure = "stop"), the run stops, and r1's goal is cancelled.
    let (seen, _tasks, _node) = fake_nav2(d, &["r1", "r2", "r3"], 2.0, 1.0);
    let sup = supervisor_with(dir.path(), &plan, d, &["--max-firings", "30"]);
    let log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(90)).await;
    let log = std::fs::read_to_string(&log).unwrap_or_default();
    assert_eq!(code, Some(1), "{out}\n{log}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("a JSON summary");
    assert_eq!(summary["stopped"], "failure", "{out}");
    let errors = summary["errors"].to_string();
    assert!(
        errors.contains("robot `r2`: Nav2 Aborted: error 9000 blocked"),
        "{errors}"
    );
    let s = seen.lock().unwrap();
    assert_eq!(
        s.cancelled, 1,
        "r1's goal to L1 is cancelled when the run stops"
    );
}
