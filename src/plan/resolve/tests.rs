//! Unit tests of plan resolution: names, positions, roles, policy, ROS 2 keys.

use super::*;
use crate::net::{NetBuilder, PlaceId, Servers};
use crate::ros2::DEFAULT_SERVER;
use crate::ros2::settings::ServiceMapping;
use crate::runtime::FailurePolicy;

/// P1 -T1-> P2 -t2|t3-> P3|P1 ; P3 -T4-> P1. Names with `:` as in the thesis.
fn net() -> Net {
    let mut b = NetBuilder::new("n");
    let p1 = b.place("p1:Start", 2);
    let p2 = b.place("P2", 0);
    let p3 = b.place("P3", 0);
    let t1 = b.exponential("T1", 1.0, Servers::Single);
    let t2 = b.immediate("t2", 1.0, 1);
    let t3 = b.immediate("t3", 1.0, 1);
    let t4 = b.exponential("T4", 2.0, Servers::Single);
    b.moves(p1, t1, p2);
    b.moves(p2, t2, p3);
    b.moves(p2, t3, p1);
    b.moves(p3, t4, p1);
    b.build().unwrap()
}

fn load(text: &str) -> Result<Plan, LoadError> {
    let path = Path::new("dir/plan.toml");
    PlanFile::parse(path, text)?.resolve(path, text, net())
}

fn err_at(text: &str) -> (u32, u32, String) {
    let e = load(text).unwrap_err();
    let s = e.span.expect("a span");
    (s.line, s.column, e.kind.to_string())
}

/// `text` is refused at `(line, column)` with a message containing `says`.
#[track_caller]
fn refused(text: &str, at: (u32, u32), says: &str) {
    let (l, c, m) = err_at(text);
    assert_eq!((l, c), at, "{m}");
    assert!(m.contains(says), "{m}");
}

#[test]
fn a_full_plan_resolves_to_ids() {
    let plan = load(
        r#"net = "n.xml"
seed = 7
time_scale = 0.0
[places."p1:Start"]
action = "work"
timeout = 5.0
on_failure = "fire T1"
robot = "r1"
[places.P3]
role = "resource"
[[policy]]
marking = { P2 = 1 }
partial = true
choose = { t2 = 0.25, t3 = 0.75 }
[[policy]]
marking = { "p1:Start" = 1, P2 = 1 }
choose = { t3 = 1 }
[stop]
when = "P3 >= 2 || `p1:Start` == 0"
time_limit = 100.0
max_firings = 500
"#,
    )
    .unwrap();
    assert_eq!(plan.net_path, Path::new("dir/n.xml"));
    assert_eq!(plan.seed, Some(7));
    assert_eq!(plan.time_scale, Some(0.0));
    assert_eq!(
        plan.roles[0],
        Some(Role::Action {
            name: "work".into(),
            timeout: Some(5.0),
            on_failure: FailurePolicy::Fire(TransitionId(0)),
            robot: Some("r1".into()),
        })
    );
    assert_eq!(plan.roles[1], None);
    assert_eq!(plan.roles[2], Some(Role::Resource));
    let rules = plan.policy.rules();
    assert_eq!(rules[0].pattern, Pattern::Partial(vec![(PlaceId(1), 1)]));
    assert_eq!(rules[1].pattern, Pattern::Exact(vec![1, 1, 0]));
    assert_eq!(rules[1].choose, vec![(TransitionId(2), 1.0)]);
    assert_eq!(plan.rule_spans[0].line, 11);
    assert_eq!(plan.rule_spans[1].line, 15);
    // Exact rule first: marking (1,1,0) → t3 only.
    let t = [TransitionId(1), TransitionId(2)];
    assert_eq!(
        plan.policy.distribution(&[1, 1, 0], &t),
        Some(vec![(TransitionId(2), 1.0)])
    );
    assert_eq!(
        plan.policy.distribution(&[0, 1, 1], &t),
        Some(vec![(TransitionId(1), 0.25), (TransitionId(2), 0.75)])
    );
    let when = plan.stop.when.as_ref().unwrap();
    assert!(when.eval(&[1, 0, 2]) && when.eval(&[0, 1, 0]) && !when.eval(&[1, 1, 0]));
    assert_eq!(plan.stop.time_limit, Some(100.0));
    assert_eq!(plan.stop.max_firings, Some(500));
}

#[test]
fn unknown_keys_are_refused_with_line_and_column() {
    refused("net = \"n.xml\"\nsede = 3\n", (2, 1), "sede");
    refused(
        "net = \"n.xml\"\n[places.P2]\naction = \"a\"\ntimeot = 3\n",
        (4, 1),
        "timeot",
    );
}

#[test]
fn unknown_names_are_load_errors_at_their_position() {
    refused(
        "net = \"n.xml\"\n[places.P9]\naction = \"a\"\n",
        (2, 9),
        "place `P9` does not exist",
    );
    refused(
        "net = \"n.xml\"\n[[policy]]\nmarking = { P2 = 1, Q = 0 }\nchoose = { t2 = 1 }\n",
        (3, 21),
        "place `Q` does not exist",
    );
    refused(
        "net = \"n.xml\"\n[[policy]]\nmarking = { P2 = 1 }\nchoose = { t9 = 1 }\n",
        (4, 12),
        "transition `t9` does not exist",
    );
    refused(
        "net = \"n.xml\"\n[places.P2]\naction = \"a\"\non_failure = \"fire t9\"\n",
        (4, 14),
        "transition `t9` does not exist",
    );
}

#[test]
fn predicate_errors_point_inside_the_string() {
    refused(
        "net = \"n.xml\"\n[stop]\nwhen = \"P2 > 0 && Nope == 1\"\n",
        (3, 19),
        "place `Nope` does not exist",
    );
    refused(
        "net = \"n.xml\"\n[stop]\nwhen = \"P2 = 0\"\n",
        (3, 12),
        "stop.when:",
    );
}

#[test]
fn bad_probabilities_and_exponential_choices_are_refused() {
    refused(
        "net = \"n.xml\"\n[[policy]]\nmarking = {}\npartial = true\nchoose = { t2 = 0.5, t3 = 0.6 }\n",
        (2, 1),
        "sum to 1.1",
    );
    refused(
        "net = \"n.xml\"\n[[policy]]\nmarking = {}\npartial = true\nchoose = { t2 = 1.5 }\n",
        (5, 17),
        "must be in [0, 1]",
    );
    refused(
        "net = \"n.xml\"\n[[policy]]\nmarking = {}\nchoose = { T1 = 1 }\n",
        (4, 12),
        "exponential",
    );
}

#[test]
fn role_mistakes_are_refused() {
    let (l, _, m) = err_at("net = \"n.xml\"\n[places.P2]\ntimeout = 3.0\n");
    assert_eq!(l, 2);
    assert!(m.contains("`action`"), "{m}");
    refused(
        "net = \"n.xml\"\n[places.P2]\nrole = \"resource\"\ntimeout = 3.0\n",
        (4, 11),
        "resource",
    );
    let (l, c, _) = err_at("net = \"n.xml\"\n[places.P2]\naction = \"a\"\ntimeout = -1.0\n");
    assert_eq!((l, c), (4, 11));
    let (_, _, m) =
        err_at("net = \"n.xml\"\n[places.P2]\naction = \"a\"\non_failure = \"fire T4\"\n");
    assert!(m.contains("not an output"), "{m}");
    let (_, _, m) =
        err_at("net = \"n.xml\"\n[places.P2]\naction = \"a\"\non_failure = \"retry x\"\n");
    assert!(m.contains("`x` is not a number"), "{m}");
    let plan =
        load("net = \"n.xml\"\n[places.P2]\naction = \"a\"\non_failure = \"retry 3\"\n").unwrap();
    assert!(matches!(
        plan.roles[1],
        Some(Role::Action {
            on_failure: FailurePolicy::Retry(3),
            ..
        })
    ));
}

#[test]
fn ros2_places_and_settings_resolve() {
    let plan = load(
        "net = \"n.xml\"\n[ros2]\ndomain_id = 42\nnetworks = [\"127.0.0.1\"]\nlost_after = 0.5\n\
         service_mapping = \"cyclone\"\nrosout = true\n\
         [places.P2]\naction = \"ros2\"\nserver = \"exec_p2\"\ntarget = [1.5, -2.0]\n\
         args = { speed = \"0.5\", sensor = \"t1\" }\n[places.P3]\naction = \"ros2\"\n",
    )
    .unwrap();
    assert_eq!(
        plan.ros2.args,
        vec![(
            PlaceId(1),
            crate::ros2::settings::PlaceArgs {
                target: Some([1.5, -2.0, 0.0]),
                args: vec![
                    ("sensor".to_string(), "t1".to_string()),
                    ("speed".to_string(), "0.5".to_string())
                ],
            }
        )]
    );
    assert_eq!(plan.ros2.domain_id, Some(42));
    assert_eq!(
        plan.ros2.networks,
        vec![std::net::IpAddr::from([127, 0, 0, 1])]
    );
    assert_eq!(plan.ros2.lost_after, Some(0.5));
    assert_eq!(plan.ros2.heartbeat, None);
    assert_eq!(plan.ros2.service_mapping, ServiceMapping::Cyclone);
    assert_eq!(plan.ros2.rosout, Some(true));
    assert_eq!(
        plan.ros2.servers,
        vec![
            (PlaceId(1), "exec_p2".to_string()),
            (PlaceId(2), DEFAULT_SERVER.to_string())
        ]
    );
}

#[test]
fn ros2_mistakes_are_refused_at_their_position() {
    refused(
        "net = \"n.xml\"\n[places.P2]\naction = \"a\"\nserver = \"s\"\n",
        (4, 10),
        "`server` applies to places with action = \"ros2\"",
    );
    refused(
        "net = \"n.xml\"\n[places.P2]\naction = \"a\"\ntarget = [1.0, 2.0]\n",
        (4, 10),
        "place `P2`: `target` applies to places with action = \"ros2\" only",
    );
    refused(
        "net = \"n.xml\"\n[places.P2]\naction = \"ros2\"\ntarget = [1.0]\n",
        (4, 10),
        "place `P2`: target must be [x, y] or [x, y, yaw] (finite numbers)",
    );
    refused(
        "net = \"n.xml\"\n[places.P2]\naction = \"a\"\nargs = { a = \"b\" }\n",
        (4, 8),
        "place `P2`: `args` applies to places with action = \"ros2\" only",
    );
    refused(
        "net = \"n.xml\"\n[places.P2]\naction = \"ros2\"\nserver = \"a b\"\n",
        (4, 10),
        "server `a b` is not a ROS 2 name",
    );
    refused(
        "net = \"n.xml\"\n[ros2]\ntransport = \"zenoh\"\n[places.P2]\naction = \"ros2\"\n\
         server = \"navigate_to_pose\"\ntarget = [1.0, 2.0]\n",
        (6, 10),
        "place `P2`: server \"navigate_to_pose\" sends Nav2 goals over DDS only, and the plan says transport = \"zenoh\"",
    );
    refused(
        "net = \"n.xml\"\n[ros2]\nnetworks = [\"127.0.0.1\", \"lo\"]\n",
        (3, 26),
        "`lo` is not an IP address",
    );
    refused("net = \"n.xml\"\n[ros2]\ndomain_id = 300\n", (3, 13), "");
    refused("net = \"n.xml\"\n[ros2]\nlost_after = 0.0\n", (3, 14), "");
    refused(
        "net = \"n.xml\"\n[ros2]\nservice_mapping = \"basic\"\n",
        (3, 19),
        "ros2.service_mapping: `basic` is not \"enhanced\" or \"cyclone\"",
    );
    refused(
        "net = \"n.xml\"\n[ros2]\nrosout = \"yes\"\n",
        (3, 10),
        "boolean",
    );
    refused(
        "net = \"n.xml\"\n[ros2]\ndomian_id = 3\n",
        (3, 1),
        "domian_id",
    );
}

#[test]
fn time_values_are_checked() {
    let (l, c, _) = err_at("net = \"n.xml\"\ntime_scale = -1.0\n");
    assert_eq!((l, c), (2, 14));
    let (l, c, _) = err_at("net = \"n.xml\"\n[stop]\ntime_limit = 0.0\n");
    assert_eq!((l, c), (3, 14));
}
