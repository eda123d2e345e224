use super::*;
use crate::net::{NetBuilder, Servers};

#[test]
fn ring_wraps_into_bands_without_overlaps() {
    let mut b = NetBuilder::new("ring");
    let n = 400;
    let places: Vec<_> = (0..n)
        .map(|i| b.place(format!("p{i}"), u32::from(i == 0)))
        .collect();
    for i in 0..n {
        let t = b.exponential(format!("t{i}"), 1.0, Servers::Single);
        b.input(places[i], t, 1);
        b.output(t, places[(i + 1) % n], 1);
    }
    let l = layout(&b.build().unwrap());
    let mut all: Vec<(i64, i64)> = l
        .places
        .iter()
        .chain(&l.transitions)
        .map(|p| (p.x as i64, p.y as i64))
        .collect();
    let width = all.iter().map(|p| p.0).max().unwrap();
    let height = all.iter().map(|p| p.1).max().unwrap();
    all.sort_unstable();
    all.dedup();
    assert_eq!(all.len(), 2 * n);
    assert!(width < 6000 && height < 8000, "{width} x {height}");
}

#[test]
fn long_names_spread_the_layers() {
    let mut b = NetBuilder::new("names");
    let p = b.place("p1:Check_Temperature_L1", 1);
    let q = b.place("p2:Alarm_L1_with_a_long_name", 0);
    let t = b.exponential("t1:Temperature_High_L1", 1.0, Servers::Single);
    b.input(p, t, 1);
    b.output(t, q, 1);
    let l = layout(&b.build().unwrap());
    // The longest name has 28 characters.
    let gap = 28.0 * CHAR_WIDTH + LANES + 16.0;
    assert!((l.transitions[0].x - l.places[0].x - gap).abs() < 1e-9);
    assert!((l.places[1].x - l.transitions[0].x - gap).abs() < 1e-9);
    assert!(l.arcs.iter().all(Vec::is_empty), "{:?}", l.arcs);
}

/// A patrol of `k` locations like the thesis's: check (with an alarm loop), decide (with
/// a wait loop), go to the next location.
fn patrol(k: usize) -> Net {
    let mut b = NetBuilder::new("patrol");
    let mut checks = Vec::new();
    let mut decides = Vec::new();
    for i in 0..k {
        checks.push(b.place(format!("check{i}"), 1));
        decides.push(b.place(format!("decide{i}"), 0));
    }
    for i in 0..k {
        let alarm = b.place(format!("alarm{i}"), 0);
        let wait = b.place(format!("wait{i}"), 0);
        let loop2 = |b: &mut NetBuilder, from, to, name: &str| {
            let t = b.exponential(format!("{name}{i}"), 1.0, Servers::Single);
            b.input(from, t, 1);
            b.output(t, to, 1);
        };
        loop2(&mut b, checks[i], alarm, "high");
        loop2(&mut b, alarm, checks[i], "off");
        loop2(&mut b, checks[i], decides[i], "low");
        loop2(&mut b, decides[i], wait, "go_wait");
        loop2(&mut b, wait, decides[i], "done");
        loop2(&mut b, decides[i], checks[(i + 1) % k], "go");
    }
    b.build().unwrap()
}

/// The polyline of arc `i` between the centres of its nodes.
fn polyline(net: &Net, l: &Layout, i: usize) -> Vec<Position> {
    let a = &net.arcs()[i];
    let (p, t) = (
        l.places[a.place.index()],
        l.transitions[a.transition.index()],
    );
    let (from, to) = if a.kind == ArcKind::Output {
        (t, p)
    } else {
        (p, t)
    };
    let mut pts = vec![from];
    pts.extend(l.arcs[i].iter().copied());
    pts.push(to);
    pts
}

/// Whether the segment a–b comes within `r` of `c`.
fn near(a: Position, b: Position, c: Position, r: f64) -> bool {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len2 = dx * dx + dy * dy;
    let s = if len2 == 0.0 {
        0.0
    } else {
        (((c.x - a.x) * dx + (c.y - a.y) * dy) / len2).clamp(0.0, 1.0)
    };
    let (px, py) = (a.x + s * dx - c.x, a.y + s * dy - c.y);
    px * px + py * py < r * r
}

#[test]
fn routed_arcs_miss_every_node_they_do_not_join() {
    for k in [1, 2, 4, 7] {
        let net = patrol(k);
        let l = layout(&net);
        let nodes: Vec<Position> = l.places.iter().chain(&l.transitions).copied().collect();
        let np = net.place_count();
        for (i, a) in net.arcs().iter().enumerate() {
            let own = [a.place.index(), np + a.transition.index()];
            let pts = polyline(&net, &l, i);
            for (v, &c) in nodes.iter().enumerate() {
                if own.contains(&v) {
                    continue;
                }
                for w in pts.windows(2) {
                    assert!(!near(w[0], w[1], c, 20.0), "k={k}: arc {i} passes node {v}");
                }
            }
            // Orthogonal: every bend changes only one coordinate.
            for w in pts[1..pts.len() - 1].windows(2) {
                assert!(
                    w[0].x == w[1].x || w[0].y == w[1].y,
                    "k={k} arc {i}: {pts:?}"
                );
            }
        }
    }
}

#[test]
fn a_cycle_closes_on_itself() {
    // The arc that closes the patrol's big cycle (`go3` → `check0`) runs round the side
    // of the drawing to the first column, not back along the whole cycle.
    let net = patrol(4);
    let l = layout(&net);
    let i = net
        .arcs()
        .iter()
        .position(|a| {
            net.transition(a.transition).name == "go3" && net.place(a.place).name == "check0"
        })
        .unwrap();
    let length: f64 = polyline(&net, &l, i)
        .windows(2)
        .map(|w| (w[1].x - w[0].x).abs() + (w[1].y - w[0].y).abs())
        .sum();
    let height = l.places.iter().map(|p| p.y).fold(0.0, f64::max);
    let width = l.places.iter().map(|p| p.x).fold(0.0, f64::max);
    assert!(
        length < height + width / 2.0,
        "{length}: {width} x {height}"
    );
}

#[test]
fn helpers() {
    assert_eq!(inversions(&mut [3, 1, 2]), 2);
    assert_eq!(inversions(&mut [0, 1, 2]), 0);
    let y = spaced(&[0.0, 0.0, 100.0], 10.0);
    assert_eq!(y, vec![-5.0, 5.0, 100.0]);
}

/// The README's home-cleaning plan (GSPNR grid positions: arcs through nodes), MCC's
/// Peterson (every node at one point) and Dekker: the file's positions are set aside, and
/// the automatic layout draws no two nodes on each other and no arc through a node.
#[test]
fn useless_file_positions_give_way_to_a_readable_automatic_layout() {
    use crate::io::{ReadOptions, read_net};
    let read = |rel: &str| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
        read_net(&path, &ReadOptions::default()).unwrap().net
    };
    let home = read("plans/home-cleaning/net.PNPRO");
    let file = choose(&home, Choice::File).0;
    let before = quality::measure(&home, &file);
    let (auto, why) = choose(&home, Choice::Default);
    let after = quality::measure(&home, &auto);
    let mixing = quality::group_mixing(&home, &auto);
    let ungrouped = layered_with(&home, false);
    eprintln!(
        "home-cleaning: file {before:?} mixing {:?}, automatic {after:?} mixing {mixing:?}, \
         without groups {:?} mixing {:?}; {why:?}",
        quality::group_mixing(&home, &file),
        quality::measure(&home, &ungrouped),
        quality::group_mixing(&home, &ungrouped),
    );
    assert_eq!(auto.source, LayoutSource::Layered);
    assert!(
        why.unwrap()
            .contains("arc segments pass through other nodes")
    );
    assert_eq!((after.overlaps, after.through_nodes), (0, 0), "{after:?}");
    assert!(after.crossings <= 40, "{after:?}");

    for rel in [
        "mcc/Peterson-PT-2/model.pnml",
        "mcc/Dekker-PT-010/model.pnml",
    ] {
        // The shared fixtures: `$GSPN_FIXTURES`, else `../shared/fixtures` (as tests/support).
        let root = std::env::var("GSPN_FIXTURES")
            .unwrap_or_else(|_| format!("{}/../shared/fixtures", env!("CARGO_MANIFEST_DIR")));
        let net = read_net(
            &std::path::Path::new(&root).join(rel),
            &ReadOptions::default(),
        )
        .unwrap()
        .net;
        let (l, why) = choose(&net, Choice::Default);
        let q = quality::measure(&net, &l);
        eprintln!("{rel}: {q:?}, {why:?}");
        assert_eq!(l.source, LayoutSource::Layered);
        assert_eq!((q.overlaps, q.through_nodes), (0, 0), "{rel}: {q:?}");
    }
}

/// Locations kept together: the thesis patrol's `L1`…`L4` (names like `p3:Decide_L2`) drawn
/// with half as many nodes inside another location's box as without groups, and fewer
/// crossings; the home-cleaning plan's three locations each in a box of their own (they
/// were already) with no more crossings than the 40 the browser test allows.
#[test]
fn locations_stay_together() {
    use crate::io::{ReadOptions, read_net};
    let read = |rel: &str| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
        read_net(&path, &ReadOptions::default()).unwrap().net
    };
    let patrol = read("plans/temperature-patrol/temperature_patrol.xml");
    let (grouped, free) = (layered_with(&patrol, true), layered_with(&patrol, false));
    let measured = |l: &Layout| {
        (
            quality::group_mixing(&patrol, l).unwrap(),
            quality::measure(&patrol, l).crossings,
        )
    };
    eprintln!(
        "patrol: grouped {:?}, without groups {:?}",
        measured(&grouped),
        measured(&free)
    );
    assert_eq!(measured(&grouped), ((13, 4), 15));
    assert_eq!(measured(&free), ((27, 4), 19));

    let home = read("plans/home-cleaning/net.PNPRO");
    let l = layered_with(&home, true);
    assert_eq!(quality::group_mixing(&home, &l), Some((0, 3)));
    assert!(quality::measure(&home, &l).crossings <= 40);
}
