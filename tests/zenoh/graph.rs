//! What a ROS 2 graph tool on rmw_zenoh sees of a run: one liveliness token per node and per
//! endpoint, in rmw_zenoh's format (`@ros2_lv/<domain>/<zid>/<node id>/<entity id>/<kind>/
//! <enclave>/<namespace>/<node>/<name>/<type>/<type hash>/<qos>`), and each robot's action
//! server publishing its goals' status and feedback as rclcpp's does.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Duration;

use gspn::zenoh::action::{FeedbackMessage, GoalStatusArray};
use gspn::zenoh::wire::decode;
use zenoh::handlers::FifoChannel;
use zenoh::sample::SampleKind;

use super::{PATROL, finish, plan_runner, router};

/// The chunks of a token after the session id: (node id, entity id, the rest).
fn chunks(token: &str) -> (String, String, String) {
    let parts: Vec<&str> = token.splitn(6, '/').collect();
    (
        parts[3].to_string(),
        parts[4].to_string(),
        parts[5].to_string(),
    )
}

/// `RIHS01_` and 64 hex digits.
fn is_hash(s: &str) -> bool {
    s.strip_prefix("RIHS01_")
        .is_some_and(|h| h.len() == 64 && h.bytes().all(|b| b.is_ascii_hexdigit()))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_endpoint_has_its_token_and_the_action_servers_publish_status_and_feedback() {
    let dir = tempfile::tempdir().unwrap();
    let e = super::endpoint();
    let _router = router(dir.path(), "router", &e).await;
    let session = gspn::zenoh::client(&e).await.unwrap();
    let tokens = session
        .liveliness()
        .declare_subscriber("@ros2_lv/0/**")
        .history(true)
        .with(FifoChannel::new(10_000))
        .await
        .unwrap();
    let status = session
        .declare_subscriber("0/r1/exec_place/_action/status/**")
        .with(FifoChannel::new(10_000))
        .await
        .unwrap();
    let feedback = session
        .declare_subscriber("0/r1/exec_place/_action/feedback/**")
        .with(FifoChannel::new(10_000))
        .await
        .unwrap();
    // The robots at 1 s per unit of model time: goals of Exp(1) and Exp(2) seconds, some
    // longer than the 1 s between feedbacks (the draws are seeded: the same every run).
    let _robots: Vec<super::Proc> = ["r1", "r2", "r3"]
        .iter()
        .map(|id| {
            plan_runner(
                dir.path(),
                id,
                &[
                    "robot",
                    "--id",
                    id,
                    "--plan",
                    PATROL,
                    "--zenoh",
                    &e,
                    "--time-scale",
                    "1",
                ],
                false,
            )
        })
        .collect();
    let sup = plan_runner(
        dir.path(),
        "supervisor",
        &[
            "run",
            PATROL,
            "--json",
            "--zenoh",
            &e,
            "--max-firings",
            "24",
        ],
        true,
    );
    let log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(120)).await;
    assert_eq!(
        code,
        Some(0),
        "{out}\n{}",
        std::fs::read_to_string(log).unwrap()
    );

    // Every token declared while the run went on (the supervisor's are withdrawn by now).
    let mut seen = BTreeSet::new();
    while let Ok(Some(s)) = tokens.try_recv() {
        if s.kind() == SampleKind::Put {
            seen.insert(s.key_expr().as_str().to_string());
        }
    }
    let of = |ns: &str| -> Vec<(String, String, String)> {
        seen.iter()
            .map(|t| chunks(t))
            .filter(|(_, _, rest)| rest.split('/').nth(2) == Some(ns))
            .collect()
    };
    // r1: its node, the three services and two topics of its action server, its two
    // subscriptions; one node id, an entity id each.
    let r1 = of("%r1");
    let rest: BTreeSet<String> = r1
        .iter()
        .map(|(_, _, rest)| {
            // The type hash checked apart: replaced by H.
            rest.split('/')
                .map(|c| if is_hash(c) { "H" } else { c })
                .collect::<Vec<_>>()
                .join("/")
        })
        .collect();
    let want: BTreeSet<String> = [
        "NN/%/%r1/gspn_robot",
        "SS/%/%r1/gspn_robot/%r1%exec_place%_action%send_goal/gspn_msgs::action::dds_::ExecPlace_SendGoal_/H/::,10:,:,:,,",
        "SS/%/%r1/gspn_robot/%r1%exec_place%_action%get_result/gspn_msgs::action::dds_::ExecPlace_GetResult_/H/::,10:,:,:,,",
        "SS/%/%r1/gspn_robot/%r1%exec_place%_action%cancel_goal/action_msgs::srv::dds_::CancelGoal_/H/::,10:,:,:,,",
        "MP/%/%r1/gspn_robot/%r1%exec_place%_action%feedback/gspn_msgs::action::dds_::ExecPlace_FeedbackMessage_/H/::,10:,:,:,,",
        "MP/%/%r1/gspn_robot/%r1%exec_place%_action%status/action_msgs::msg::dds_::GoalStatusArray_/H/:1:,1:,:,:,,",
        "MS/%/%r1/gspn_robot/%gspn%run/gspn_msgs::msg::dds_::RunState_/H/:1:,1:,:,:,,",
        "MS/%/%r1/gspn_robot/%gspn%firings/gspn_msgs::msg::dds_::Firing_/H/::2,:,:,:,,",
    ]
    .into_iter()
    .map(String::from)
    .collect();
    assert_eq!(rest, want, "{seen:#?}");
    let nodes: BTreeSet<&String> = r1.iter().map(|(n, _, _)| n).collect();
    let entities: BTreeSet<&String> = r1.iter().map(|(_, e, _)| e).collect();
    assert_eq!(nodes.len(), 1, "{r1:?}");
    assert_eq!(entities.len(), 8, "{r1:?}");
    // The hashes ROS 2 gives the standard types, and the same hashes as the key
    // expressions of r1's services.
    let hash_of = |kind_and_name: &str| -> String {
        seen.iter()
            .find(|t| t.contains(kind_and_name))
            .and_then(|t| t.split('/').find(|c| is_hash(c)))
            .unwrap_or_else(|| panic!("no {kind_and_name} in {seen:#?}"))
            .to_string()
    };
    assert_eq!(
        hash_of("SS/%/%r1/gspn_robot/%r1%exec_place%_action%cancel_goal"),
        "RIHS01_573d8b0a534451d7bc2ac8c5ffde8ac14b8593b7001175d0cd6516dcbeb8689a"
    );
    assert_eq!(
        hash_of("MP/%/%r1/gspn_robot/%r1%exec_place%_action%status"),
        "RIHS01_6c1684b00f177d37438febe6e709fc4e2b0d4248dca4854946f9ed8b30cda83e"
    );
    let send_goal_key = gspn::zenoh::keys::exec_place(
        0,
        "r1",
        "exec_place",
        gspn::zenoh::keys::ActionService::SendGoal,
    )
    .unwrap();
    assert!(
        send_goal_key.ends_with(&hash_of(
            "SS/%/%r1/gspn_robot/%r1%exec_place%_action%send_goal"
        )),
        "{send_goal_key}"
    );
    // The supervisor: its node, its four publishers, three service clients per robot.
    let sup: BTreeSet<String> = of("%gspn")
        .into_iter()
        .map(|(_, _, rest)| {
            let c: Vec<&str> = rest.split('/').collect();
            match c.as_slice() {
                [kind, _, _, node] => format!("{kind} {node}"),
                [kind, _, _, _, name, _, _, qos] => format!("{kind} {name} {qos}"),
                _ => panic!("{rest}"),
            }
        })
        .collect();
    let mut want: BTreeSet<String> = [
        "NN supervisor",
        "MP %gspn%firings ::2,:,:,:,,",
        "MP %gspn%drift ::2,:,:,:,,",
        "MP %gspn%marking :1:,1:,:,:,,",
        "MP %gspn%run :1:,1:,:,:,,",
    ]
    .into_iter()
    .map(String::from)
    .collect();
    for r in ["r1", "r2", "r3"] {
        for s in ["send_goal", "get_result", "cancel_goal"] {
            want.insert(format!("SC %{r}%exec_place%_action%{s} ::,10:,:,:,,"));
        }
    }
    assert_eq!(sup, want, "{seen:#?}");

    // r1's status: each goal executing, then succeeded (or cancelled when the run stopped);
    // feedback only for goals still running, a whole number of seconds in.
    let mut goals: BTreeMap<[u8; 16], Vec<i8>> = BTreeMap::new();
    while let Ok(Some(s)) = status.try_recv() {
        let a: GoalStatusArray = decode(&s.payload().to_bytes()).unwrap();
        for g in a.status_list {
            let seq = goals.entry(g.goal_info.goal_id).or_default();
            if seq.last() != Some(&g.status) {
                seq.push(g.status);
            }
        }
    }
    assert!(goals.len() >= 3, "{goals:?}");
    for (id, seq) in &goals {
        assert!(
            seq == &[2, 4] || seq == &[2, 5] || seq == &[2],
            "goal {id:?}: {seq:?}"
        );
    }
    let mut fed = 0;
    while let Ok(Some(s)) = feedback.try_recv() {
        let f: FeedbackMessage = decode(&s.payload().to_bytes()).unwrap();
        assert!(goals.contains_key(&f.goal_id), "{f:?}");
        let e = f.feedback.elapsed;
        assert!(e.round() >= 1.0 && (e - e.round()).abs() < 0.4, "{e}");
        fed += 1;
    }
    assert!(fed >= 1, "no feedback: {goals:?}");
}
