//! Conformance on the runtime: the agents' own stays read from a run's events (`holding`
//! rows), an Erlang fit of a place whose stays are not exponential, and the live monitor's
//! `drift` events — in the journal and on the bus, right after the firing that showed them —
//! when an action slows down half-way, and none when it does not.

use gspn::conform::{
    Monitor, Monitored, Options, RowKind, Trace, Verdict, compare, fit, observe, steady_predictions,
};
use gspn::net::{Net, NetBuilder, Servers, Timing};
use gspn::runtime::journal::read_events;
use gspn::runtime::{Event, EventKind, FailurePolicy, Role, Runtime, action_fn};

fn role(name: &str) -> Role {
    Role::Action {
        name: name.into(),
        timeout: None,
        on_failure: FailurePolicy::Stop,
        robot: None,
    }
}

/// One agent cycles A -> B -> A: out of A by `Ta` (rate 2) or `Tc` (rate 1), out of B by
/// `Tb` (rate 1).
fn stays_net() -> Net {
    let mut b = NetBuilder::new("stays");
    let (a, bb) = (b.place("A", 1), b.place("B", 0));
    let ta = b.exponential("Ta", 2.0, Servers::Infinite);
    let tc = b.exponential("Tc", 1.0, Servers::Infinite);
    let tb = b.exponential("Tb", 1.0, Servers::Infinite);
    for t in [ta, tc] {
        b.input(a, t, 1);
        b.output(t, bb, 1);
    }
    b.input(bb, tb, 1);
    b.output(tb, a, 1);
    b.build().unwrap()
}

/// The events of a run of [`stays_net`]: A lets the net's race decide (`wait`), B fires `Tb`
/// after exactly 3 s.
async fn stays_run() -> Vec<Event> {
    let net = stays_net();
    let (a, b) = (
        net.place_by_name("A").unwrap(),
        net.place_by_name("B").unwrap(),
    );
    let mut h = Runtime::builder(net)
        .role(a, role("wait"))
        .role(b, role("fire Tb after 3"))
        .until(3000.0)
        .seed(7)
        .spawn()
        .unwrap();
    let events = h.events().collect().await;
    h.wait().await;
    events
}

fn row<'a>(rows: &'a [gspn::conform::Row], kind: RowKind, item: &str) -> &'a gspn::conform::Row {
    rows.iter()
        .find(|r| r.kind == kind && r.item == item)
        .unwrap_or_else(|| panic!("no {kind:?} row for {item}: {rows:#?}"))
}

#[tokio::test(start_paused = true)]
async fn the_agents_own_stays_are_tested_per_place_and_exit_and_a_fixed_delay_is_fitted_erlang() {
    let net = stays_net();
    let events = stays_run().await;
    let trace = Trace::from_events(&net, &events);
    let opts = Options::default();
    let obs = observe(&net, None, &trace, &opts).unwrap();
    let pred = steady_predictions(&net, None, 1000).unwrap();
    let report = compare(&net, &obs, &pred, &opts);
    let rows = &report.rows;

    // B: every stay lasts exactly 3 s; the net says exponential with mean 1.
    let b = row(rows, RowKind::Holding, "B -> Tb");
    assert!((b.observed - 3.0).abs() < 1e-9, "{b:?}");
    let [lo, hi] = b.interval.unwrap();
    assert!((lo - 3.0).abs() < 1e-9 && (hi - 3.0).abs() < 1e-9, "{b:?}");
    assert_eq!(b.predicted, Some(1.0));
    assert_eq!(b.verdict, Verdict::Diverges);
    assert!(b.p_value.unwrap() < 1e-12, "{b:?}");
    assert_eq!(
        row(rows, RowKind::HoldingShape, "B").verdict,
        Verdict::Diverges
    );

    // A: the net's race, exponential with rate 3, left by Ta two times in three.
    let (ta, tc) = (
        row(rows, RowKind::Holding, "A -> Ta"),
        row(rows, RowKind::Holding, "A -> Tc"),
    );
    // One cycle takes 3 + 1/3 s: about 900 in 3000 s, every one through B (the run may end
    // between the two stays of a cycle).
    assert!(
        (ta.n + tc.n).abs_diff(b.n) <= 1,
        "{} + {} vs {}",
        ta.n,
        tc.n,
        b.n
    );
    assert!((850..=950).contains(&(ta.n + tc.n)), "{} + {}", ta.n, tc.n);
    let share = ta.n as f64 / (ta.n + tc.n) as f64;
    assert!((share - 2.0 / 3.0).abs() < 0.05, "share of Ta {share}");
    for r in [ta, tc] {
        assert!((r.predicted.unwrap() - 1.0 / 3.0).abs() < 1e-12, "{r:?}");
        assert!((r.observed - 1.0 / 3.0).abs() < 0.05, "{r:?}");
        assert_eq!(r.verdict, Verdict::Consistent, "{r:?}");
    }
    assert_eq!(
        row(rows, RowKind::HoldingShape, "A").verdict,
        Verdict::Consistent
    );

    // The fit: B's stays have no spread, and they are the same whichever way the agent came
    // in (Ta or Tc: one chain), so B gets the most stages (20), each of rate 20/3, into
    // B~done, which Tb (now immediate, above every other) leaves; A stays exponential.
    let (fitted, params) = fit(&net, &obs, &opts);
    let stages = params
        .iter()
        .find(|f| f.parameter == "stages")
        .expect("an Erlang fit");
    assert_eq!((stages.transition.as_str(), stages.new), ("B", 20.0));
    assert_eq!(params.iter().filter(|f| f.parameter == "stages").count(), 1);
    assert_eq!(fitted.place_count(), 2 + 20 + 1);
    assert_eq!(fitted.transition_count(), 3 + 20);
    let rate = |name: &str| match fitted
        .transition(fitted.transition_by_name(name).unwrap())
        .timing
    {
        Timing::Exponential { rate, .. } => rate,
        Timing::Immediate { .. } => panic!("{name} is exponential"),
    };
    assert!((rate("B~1>2") - 20.0 / 3.0).abs() < 1e-9);
    assert!((rate("B~20>done") - 20.0 / 3.0).abs() < 1e-9);
    let tb = fitted.transition_by_name("Tb").unwrap();
    assert_eq!(
        fitted.transition(tb).timing,
        Timing::Immediate {
            weight: 1.0,
            priority: 1
        }
    );
    let done = fitted.place_by_name("B~done").unwrap();
    let b = fitted.place_by_name("B").unwrap();
    assert_eq!(fitted.inputs(tb), [(b, 1), (done, 1)]);
    // The learnt model predicts the run's throughput: one cycle per 3 s + A's fitted stay.
    let x = steady_predictions(&fitted, None, 10_000)
        .unwrap()
        .throughput
        .unwrap()[tb.index()];
    let observed = obs.throughput[tb.index()].mean;
    assert!((x - observed).abs() < 0.01 * observed, "{x} vs {observed}");
}

/// One agent: A -Ta-> B, B -Tb-> C -Tc-> B, B -Td-> A. B's action takes 3 s and fires `Tb`
/// when the agent came from A, 0.5 s and fires `Td` when it came from C (it alternates).
#[tokio::test(start_paused = true)]
async fn stays_that_depend_on_the_way_in_get_one_erlang_chain_per_entry() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicU64, Ordering};
    let mut b = NetBuilder::new("entries");
    let (pa, pb, pc) = (b.place("A", 1), b.place("B", 0), b.place("C", 0));
    let ta = b.exponential("Ta", 1.0, Servers::Single);
    let tb = b.exponential("Tb", 1.0, Servers::Single);
    let tc = b.exponential("Tc", 1.0, Servers::Single);
    let td = b.exponential("Td", 1.0, Servers::Single);
    b.moves(pa, ta, pb);
    b.moves(pb, tb, pc);
    b.moves(pc, tc, pb);
    b.moves(pb, td, pa);
    let net = b.build().unwrap();
    let stays = Arc::new(AtomicU64::new(0));
    let alternate = action_fn(move |ctx| {
        let k = stays.fetch_add(1, Ordering::SeqCst);
        async move {
            let (d, t) = if k.is_multiple_of(2) {
                (3.0, "Tb")
            } else {
                (0.5, "Td")
            };
            ctx.clock.sleep(d).await;
            ctx.fire(t)
        }
    });
    let mut h = Runtime::builder(net.clone())
        .action("alternate", alternate)
        .role(pa, role("wait"))
        .role(pb, role("alternate"))
        .role(pc, role("wait"))
        .until(500.0)
        .seed(3)
        .spawn()
        .unwrap();
    let events = h.events().collect().await;
    h.wait().await;
    let trace = Trace::from_events(&net, &events);
    let opts = Options::default();
    let obs = observe(&net, None, &trace, &opts).unwrap();
    let from_a: Vec<f64> = obs
        .holdings
        .iter()
        .filter(|h| h.place == pb && h.entry == Some(ta))
        .map(|h| h.duration)
        .collect();
    assert!(from_a.len() > 50, "{}", from_a.len());
    assert!(from_a.iter().all(|&d| (d - 3.0).abs() < 1e-9), "{from_a:?}");
    let (fitted, params) = fit(&net, &obs, &opts);
    let param = |item: &str, what: &str| {
        params
            .iter()
            .find(|f| f.transition == item && f.parameter == what)
            .unwrap_or_else(|| panic!("no {what} of {item}: {params:#?}"))
            .new
    };
    assert_eq!(param("B from Ta", "stages"), 20.0);
    assert!((param("B from Ta", "mean") - 3.0).abs() < 1e-9);
    assert_eq!(param("B from Tc", "stages"), 20.0);
    assert!((param("B from Tc", "mean") - 0.5).abs() < 1e-9);
    // No initial token and no other way in: no third chain.
    assert!(params.iter().all(|f| !f.transition.contains("other")));
    let share = param("Tb", "exit");
    assert!((share - 0.5).abs() < 0.02, "{share}");
    // A's entry feeds its chain: Ta puts the agent in B and in B's first stage from Ta.
    let chain = fitted.place_by_name("B~Ta~1").unwrap();
    let ta2 = fitted.transition_by_name("Ta").unwrap();
    assert!(fitted.outputs(ta2).contains(&(chain, 1)));
    let last = fitted.transition_by_name("B~Tc~20>done").unwrap();
    match fitted.transition(last).timing {
        Timing::Exponential { rate, servers } => {
            assert!((rate - 40.0).abs() < 1e-9, "{rate}");
            assert_eq!(servers, Servers::Infinite);
        }
        t => panic!("{t:?}"),
    }
    assert_eq!(fitted.place_count(), 3 + 40 + 1);
}

/// P1 -T1-> P2 -t2-> P3 -T3-> P1 with two tokens; T3 infinite-server at rate 2 (each agent's
/// action takes its own time: the steady state does not depend on its distribution).
fn cyc3_agents() -> Net {
    let mut b = NetBuilder::new("cyc3");
    let (p1, p2, p3) = (b.place("P1", 2), b.place("P2", 0), b.place("P3", 0));
    let t1 = b.exponential("T1", 1.0, Servers::Single);
    let t2 = b.immediate("t2", 1.0, 1);
    let t3 = b.exponential("T3", 2.0, Servers::Infinite);
    b.moves(p1, t1, p2);
    b.moves(p2, t2, p3);
    b.moves(p3, t3, p1);
    b.build().unwrap()
}

/// A run of [`cyc3_agents`] until `until` where P3's action takes 0.5 s, and `after` from
/// time 750 on, watched by a monitor of the net; its events and journal.
async fn monitored_run(until: f64, after: f64) -> (Vec<Event>, Vec<Event>) {
    let net = cyc3_agents();
    let p3 = net.place_by_name("P3").unwrap();
    let steady = steady_predictions(&net, None, 1000).unwrap();
    let monitor = Monitor::new(&net, net.initial_marking().into_vec(), Default::default())
        .with_mean_tokens(steady.mean_tokens.unwrap());
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    let slow = action_fn(move |ctx| async move {
        let d = if ctx.time < 750.0 { 0.5 } else { after };
        ctx.clock.sleep(d).await;
        ctx.fire("T3")
    });
    let mut h = Runtime::builder(net.clone())
        .action("slow", slow)
        .role(p3, role("slow"))
        .until(until)
        .seed(11)
        .watch(monitor)
        .journal(&journal)
        .spawn()
        .unwrap();
    let events = h.events().collect().await;
    h.wait().await;
    let text = std::fs::read_to_string(&journal).unwrap();
    (events, read_events(&text, &net).unwrap())
}

fn drifts(events: &[Event]) -> Vec<(u64, f64, gspn::conform::Drift)> {
    events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::Drift(d) => Some((e.seq, e.time, d.clone())),
            _ => None,
        })
        .collect()
}

#[tokio::test(start_paused = true)]
async fn an_action_that_slows_down_half_way_raises_drift_events_and_an_unchanged_one_none() {
    let net = cyc3_agents();
    let (t3, p3) = (
        net.transition_by_name("T3").unwrap(),
        net.place_by_name("P3").unwrap(),
    );
    let (events, journal) = monitored_run(1500.0, 1.5).await;
    let all = drifts(&events);
    // The journal holds the same drift events as the bus (numbers to 1e-12: JSON).
    let back = drifts(&journal);
    assert_eq!(back.len(), all.len(), "{back:?}");
    for ((s1, t1, d1), (s2, t2, d2)) in back.iter().zip(&all) {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
        assert_eq!((s1, d1.of, d1.n), (s2, d2.of, d2.n));
        assert!(
            close(*t1, *t2) && close(d1.observed, d2.observed),
            "{d1:?} {d2:?}"
        );
        assert!(close(d1.predicted, d2.predicted) && close(d1.p_value, d2.p_value));
    }
    let of_t3: Vec<_> = all
        .iter()
        .filter(|d| d.2.of == Monitored::Transition(t3))
        .collect();
    assert_eq!(of_t3.len(), 1, "{all:?}");
    let (seq, time, d) = of_t3[0];
    assert!(*time > 750.0 && *time < 900.0, "{all:?}");
    // Right after the firing of T3 that showed it.
    let before = events.iter().find(|e| e.seq == seq - 1).unwrap();
    assert!(
        matches!(before.kind, EventKind::Fired { transition, .. } if transition == t3),
        "{before:?}"
    );
    assert_eq!(d.predicted, 2.0);
    assert!(d.observed < 2.0 && d.interval[1] < 2.0, "{d:?}");
    // P3 holds more tokens once its action is slower.
    let of_p3: Vec<_> = all
        .iter()
        .filter(|d| d.2.of == Monitored::Place(p3))
        .collect();
    assert_eq!(of_p3.len(), 1, "{all:?}");
    assert!(
        of_p3[0].1 > 750.0 && of_p3[0].2.observed > of_p3[0].2.predicted,
        "{all:?}"
    );
    assert!(all.iter().all(|d| d.1 > 750.0), "{all:?}");

    // Unchanged: the action keeps its 0.5 s; no drift at all.
    let (events, _) = monitored_run(1500.0, 0.5).await;
    assert_eq!(drifts(&events), vec![]);
}
