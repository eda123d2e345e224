//! The journal format is stable: a journal written before the firing core and the typed
//! reader (by `plan-runner run plans/temperature-patrol/plan.toml --robots 3 --max-firings 30
//! --journal …`, stored in tests/data/journal/) is read back into typed events, every line
//! re-serialises to the same bytes, and it replays to the marking after each firing.

use std::path::Path;

use gspn::io::ReadOptions;
use gspn::plan::read_plan;
use gspn::runtime::journal::{read_events, read_journal};
use gspn::runtime::{EventKind, StopReason};

#[test]
fn a_journal_written_before_the_typed_reader_still_replays() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text =
        std::fs::read_to_string(root.join("tests/data/journal/patrol_robots_before_issue12.jsonl"))
            .unwrap();
    let plan = read_plan(
        &root.join("plans/temperature-patrol/plan.toml"),
        &ReadOptions::default(),
    )
    .unwrap();
    let net = &plan.net;

    let events = read_events(&text, net).unwrap();
    assert_eq!(events.len(), 100);
    // Byte-compatible: each event written again is the line it was read from.
    for (e, line) in events.iter().zip(text.lines().skip(1)) {
        assert_eq!(serde_json::to_string(e).unwrap(), line);
    }
    let count = |f: fn(&EventKind) -> bool| events.iter().filter(|e| f(&e.kind)).count();
    assert_eq!(count(|k| matches!(k, EventKind::Fired { .. })), 30);
    assert_eq!(count(|k| matches!(k, EventKind::ActionStarted { .. })), 33);
    assert_eq!(count(|k| matches!(k, EventKind::ActionEnded { .. })), 33);
    let robots: Vec<String> = events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::AgentSpawned { robot, .. } => robot.as_deref().map(str::to_string),
            _ => None,
        })
        .collect();
    assert_eq!(robots.len(), 3);
    assert_eq!(
        events.last().unwrap().kind,
        EventKind::Stopped {
            reason: StopReason::MaxFirings
        }
    );

    let frames = read_journal(&text, net).unwrap();
    assert_eq!(frames.len(), 31);
    assert_eq!(frames[0].tokens, net.initial_marking().into_vec());
    for w in frames.windows(2) {
        let t = net
            .transition_by_name(w[1].transition.as_deref().unwrap())
            .unwrap();
        let mut m = w[0].tokens.clone();
        net.fire(&mut m, t).unwrap();
        assert_eq!(m, w[1].tokens);
        assert!(w[1].time >= w[0].time);
    }
}
