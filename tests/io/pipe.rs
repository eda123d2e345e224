//! Every PIPE net of the thesis framework and of `generated/` loads, with its counts,
//! `Default,k` weights, inhibitor arcs, immediate weights / priorities and server defaults.

use crate::support::fixtures as shared_fixtures;

use gspn::io::{Format, ReadOptions, read_net};
use gspn::net::{ArcKind, Net, Servers, Timing};
use shared_fixtures::{data, files_under, fixture};

fn load(path: &std::path::Path) -> Net {
    let loaded = read_net(path, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{} does not load: {e}", path.display()));
    loaded.net
}

fn counts(net: &Net) -> (usize, usize, u64, usize, usize) {
    let immediate = net
        .transitions()
        .iter()
        .filter(|t| t.is_immediate())
        .count();
    (
        net.place_count(),
        net.transition_count(),
        net.initial_tokens(),
        immediate,
        net.arcs().len(),
    )
}

#[test]
fn every_thesis_and_generated_pipe_net_loads() {
    let mut files = files_under("thesis", &[".xml"]);
    files.extend(files_under("generated", &[".xml"]));
    let bad = "gspn_thesis_test_case.xml";
    let mut loaded = 0;
    for f in &files {
        let r = read_net(f, &ReadOptions::default());
        if f.ends_with(format!("azevedo_2020/ros/{bad}")) {
            assert!(
                r.is_err(),
                "{bad} names a missing place and must be refused"
            );
            continue;
        }
        let l = r.unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_eq!(l.format, Format::Pipe, "{}", f.display());
        assert!(l.net.place_count() > 0, "{}", f.display());
        loaded += 1;
    }
    assert_eq!(
        loaded, 28,
        "25 thesis .xml nets + 4 generated rings, minus the bad one"
    );
}

#[test]
fn temperature_patrol_has_16_places_24_transitions_3_robots() {
    let net = load(&fixture(
        "thesis/caldeira_2020_package/ros_TemperaturePatrolV2/gspn_temperature_patrol.xml",
    ));
    assert_eq!(counts(&net), (16, 24, 3, 8, 48));
    let p1 = net.place_by_name("p1:Check_Temperature_L1").unwrap();
    assert_eq!(net.place(p1).initial, 1);
    let t1 = net.transition_by_name("t1:Temperature_High_L1").unwrap();
    assert_eq!(
        net.transition(t1).timing,
        Timing::Exponential {
            rate: 1.0,
            servers: Servers::Single
        },
        "infiniteServer false → single server"
    );
    for t in net.transitions() {
        if let Timing::Exponential { servers, .. } = t.timing {
            assert_eq!(servers, Servers::Single, "{}", t.name);
        }
    }
}

#[test]
fn other_thesis_nets_have_their_documented_sizes() {
    let cases = [
        // (file, places, transitions, tokens, immediate, arcs)
        (
            "thesis/caldeira_2020_package/standalone_example/example_gspn.xml",
            (3, 2, 2, 0, 4),
        ),
        (
            "thesis/caldeira_2020_package/ros_NoGazeboPlaces/no_gazebo_p_gspn.xml",
            (16, 16, 5, 0, 32),
        ),
        (
            "thesis/caldeira_2020_package/ros_NoGazeboPlacesOneToken/no_gazebo_p_1_t_gspn.xml",
            (100, 100, 1, 0, 200),
        ),
        (
            "thesis/caldeira_2020_package/ros_NoGazeboTokens/no_gazebo_t_gspn.xml",
            (7, 7, 15, 2, 15),
        ),
        (
            "thesis/azevedo_2023/gspn_temperature_patrol.xml",
            (12, 20, 3, 8, 40),
        ),
        (
            "thesis/azevedo_2023/solar_farm_inspection.xml",
            (13, 20, 0, 10, 40),
        ),
        ("generated/ring_K4_N1000.xml", (4, 4, 1000, 0, 8)),
    ];
    for (file, want) in cases {
        let net = load(&fixture(file));
        assert_eq!(counts(&net), want, "{file}");
    }
}

#[test]
fn positions_and_bend_points_are_kept() {
    let net = load(&fixture("thesis/caldeira_2020_dev/example_gspn.xml"));
    let p1 = net.place(net.place_by_name("p1").unwrap());
    let pos = p1.position.expect("p1 has a position");
    assert_eq!((pos.x, pos.y), (315.0, 375.0));
    let a = &net.arcs()[0];
    assert_eq!(a.points.len(), 2);
    assert_eq!((a.points[1].x, a.points[1].y), (282.0, 312.0));
}

#[test]
fn default_k_weights_inhibitors_immediates_and_servers_are_honoured() {
    let net = load(&data("pipe_weights.xml"));
    let buffer = net.place_by_name("Buffer").expect("names, not ids");
    let done = net.place_by_name("Done").unwrap();
    let stop = net.place_by_name("Stop").unwrap();
    assert_eq!(net.place(buffer).initial, 5);
    assert_eq!(net.place(buffer).capacity, None, "capacity 0 = unbounded");
    assert_eq!(net.place(done).capacity, Some(7));
    let work = net.transition_by_name("work").unwrap();
    let choose = net.transition_by_name("choose").unwrap();
    let slow = net.transition_by_name("slow").unwrap();
    assert_eq!(
        net.transition(work).timing,
        Timing::Exponential {
            rate: 2.5,
            servers: Servers::Infinite
        }
    );
    assert_eq!(
        net.transition(choose).timing,
        Timing::Immediate {
            weight: 0.25,
            priority: 3
        }
    );
    assert_eq!(
        net.transition(slow).timing,
        Timing::Exponential {
            rate: 4.0,
            servers: Servers::Single
        }
    );
    assert_eq!(net.inputs(work), &[(buffer, 2)]);
    assert_eq!(net.outputs(work), &[(done, 3)]);
    assert_eq!(net.inhibitors(work), &[(stop, 1)]);
    let inhibitors = net
        .arcs()
        .iter()
        .filter(|a| a.kind == ArcKind::Inhibitor)
        .count();
    assert_eq!(inhibitors, 1);
    // Weight 2 input, 5 tokens, infinite server: degree 2, rate 5.
    let m = net.initial_marking();
    assert_eq!(net.enabling_degree(&m, work), 2);
    assert_eq!(net.exp_rate(&m, work), 5.0);
}

/// Issue 30, snag 8: PIPE writes `<initialMarking><value></value>` for a place never given
/// tokens; it was refused (`'' is not a number`). Empty is 0: the same net, hash for hash.
#[test]
fn an_empty_initial_marking_value_is_zero() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("plans/nets/two_robot_patrol.xml");
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(text.matches("<value>Default,0</value>").count(), 2);
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty_marking.xml");
    std::fs::write(
        &empty,
        text.replace("<value>Default,0</value>", "<value></value>"),
    )
    .unwrap();
    let (a, b) = (load(&path), load(&empty));
    assert_eq!(b.initial_tokens(), 3);
    assert_eq!(
        gspn::runtime::journal::net_hash(&a),
        gspn::runtime::journal::net_hash(&b)
    );
}
