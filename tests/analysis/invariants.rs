//! P- and T-invariants (Farkas), the bounds they give, and token conservation.

use gspn::analysis::invariants::{
    DEFAULT_CAP, TokenLeak, conserves_tokens, p_invariants, structural_bounds, t_invariants,
};
use gspn::net::{Net, NetBuilder, Servers};

/// Two processes sharing a mutex: idle_i → enter_i → crit_i → leave_i → idle_i.
fn mutex() -> Net {
    let mut b = NetBuilder::new("mutex");
    let m = b.place("mutex", 1);
    for i in 1..=2 {
        let idle = b.place(format!("idle{i}"), 1);
        let crit = b.place(format!("crit{i}"), 0);
        let enter = b.exponential(format!("enter{i}"), 1.0, Servers::Single);
        let leave = b.exponential(format!("leave{i}"), 1.0, Servers::Single);
        b.input(idle, enter, 1);
        b.input(m, enter, 1);
        b.output(enter, crit, 1);
        b.input(crit, leave, 1);
        b.output(leave, idle, 1);
        b.output(leave, m, 1);
    }
    b.build().unwrap()
}

#[test]
fn mutex_has_three_minimal_p_invariants() {
    let net = mutex();
    // Places: mutex, idle1, crit1, idle2, crit2.
    let inv = p_invariants(&net, DEFAULT_CAP);
    assert!(inv.complete);
    assert_eq!(
        inv.vectors,
        vec![
            vec![0, 0, 0, 1, 1],
            vec![0, 1, 1, 0, 0],
            vec![1, 0, 1, 0, 1]
        ]
    );
    assert!(inv.covers_all(net.place_count()));
    assert_eq!(structural_bounds(&net), vec![Some(1); 5]);
}

#[test]
fn mutex_t_invariants_are_the_two_critical_sections() {
    let inv = t_invariants(&mutex(), DEFAULT_CAP);
    // Transitions: enter1, leave1, enter2, leave2.
    assert_eq!(inv.vectors, vec![vec![0, 0, 1, 1], vec![1, 1, 0, 0]]);
}

#[test]
fn weighted_arcs_give_weighted_invariants() {
    // Two tokens of a make one of b: 1·a + 2·b is constant.
    let mut b = NetBuilder::new("merge");
    let pa = b.place("a", 4);
    let pb = b.place("b", 0);
    let join = b.exponential("join", 1.0, Servers::Single);
    let split = b.exponential("split", 1.0, Servers::Single);
    b.input(pa, join, 2);
    b.output(join, pb, 1);
    b.input(pb, split, 1);
    b.output(split, pa, 2);
    let net = b.build().unwrap();
    assert_eq!(p_invariants(&net, DEFAULT_CAP).vectors, vec![vec![1, 2]]);
    assert_eq!(structural_bounds(&net), vec![Some(4), Some(2)]);
    assert_eq!(t_invariants(&net, DEFAULT_CAP).vectors, vec![vec![1, 1]]);
}

#[test]
fn resource_place_leaks_unless_removed() {
    // A robot moves p1 → p2 and drops a part in the resource place r.
    let mut b = NetBuilder::new("robot");
    let p1 = b.place("p1", 1);
    let p2 = b.place("p2", 0);
    let r = b.place("r", 0);
    let go = b.exponential("go", 1.0, Servers::Single);
    let back = b.exponential("back", 1.0, Servers::Single);
    b.input(p1, go, 1);
    b.output(go, p2, 1);
    b.output(go, r, 1);
    b.input(p2, back, 1);
    b.output(back, p1, 1);
    let net = b.build().unwrap();
    assert_eq!(
        conserves_tokens(&net, &[]),
        Err(vec![TokenLeak {
            transition: go,
            delta: 1
        }])
    );
    assert_eq!(conserves_tokens(&net, &[r]), Ok(()));
    assert_eq!(structural_bounds(&net), vec![Some(1), Some(1), None]);
}

#[test]
fn size_cap_reports_an_incomplete_answer() {
    // n independent pairs joined by one shared place: many invariants combine.
    let mut b = NetBuilder::new("wide");
    let hub = b.place("hub", 1);
    for i in 0..12 {
        let x = b.place(format!("x{i}"), 0);
        let y = b.place(format!("y{i}"), 0);
        let t = b.exponential(format!("t{i}"), 1.0, Servers::Single);
        let u = b.exponential(format!("u{i}"), 1.0, Servers::Single);
        b.input(hub, t, 1);
        b.output(t, x, 1);
        b.input(x, u, 1);
        b.output(u, y, 1);
        let v = b.exponential(format!("v{i}"), 1.0, Servers::Single);
        b.input(y, v, 1);
        b.output(v, hub, 1);
    }
    let net = b.build().unwrap();
    let full = p_invariants(&net, DEFAULT_CAP);
    assert!(full.complete);
    assert_eq!(full.vectors.len(), 1);
    let entries = full.vectors[0].entries();
    assert_eq!(entries.len(), net.place_count());
    assert!(entries.iter().all(|&(_, w)| w == 1));
    let capped = p_invariants(&net, 0);
    assert!(!capped.complete && capped.vectors.is_empty());
}
