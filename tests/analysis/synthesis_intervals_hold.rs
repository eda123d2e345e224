//! Every synthesis objective answers, and every interval it prints holds the answer
//! (issue 27, part 4): the cases that used to fail or answer wrongly, against Storm's values
//! or exact fractions, and random small models against an exact referee that evaluates every
//! deterministic policy in rational arithmetic.

use gspn::analysis::decision::{
    Controls, DecisionModel, Objective, PlaceMode, RewardSpec, Rewards, Solution, SolveOptions,
    solve,
};
use gspn::net::predicate::Predicate;
use gspn::net::{Net, NetBuilder, Servers};
use proptest::prelude::*;

use super::decision_model::{fixture_rewards, gspnr};

fn holds(sol: &Solution, exact: f64, tol: f64, what: &str) {
    assert!(
        sol.lower <= exact + tol && exact <= sol.upper + tol,
        "{what}: [{}, {}] misses {exact}",
        sol.lower,
        sol.upper
    );
    assert!(
        (sol.value - exact).abs() <= tol * exact.abs().max(1.0),
        "{what}: {} vs {exact}",
        sol.value
    );
}

fn goal(net: &Net, model: &DecisionModel, expr: &str) -> Vec<bool> {
    let p = Predicate::parse(net, expr).unwrap();
    model.states_where(|m| p.eval(m))
}

/// A GSPNR fixture's model and rewards; `keep_races` for the per-step objective.
fn fixture(name: &str, wait: Option<bool>, keep_races: bool) -> (Net, DecisionModel, Rewards) {
    let (net, mut controls, table) = gspnr(name);
    if let Some(w) = wait {
        controls.wait = w;
    }
    controls.keep_races = keep_races;
    let model = DecisionModel::build(&net, &controls, &Default::default()).unwrap();
    let rewards = model.rewards(&fixture_rewards(&net, &table));
    (net, model, rewards)
}

#[test]
fn discounted_with_a_negative_reward_gets_an_upper_bound_tiny_cycle() {
    // Was [8, inf] and exit 1: the upper bound never left ∞.
    let (net, controls, table) = gspnr("tiny_cycle");
    let model = DecisionModel::build(&net, &controls, &Default::default()).unwrap();
    let mut spec = fixture_rewards(&net, &table);
    let p3 = net.place_by_name("p3").unwrap();
    spec.places = vec![(p3, -1.0, PlaceMode::Marked)];
    let rewards = model.rewards(&spec);
    let sol = solve(
        &model,
        &rewards,
        &Objective::Discounted {
            max: true,
            rate: 0.5,
        },
        &SolveOptions::default(),
    )
    .unwrap();
    holds(&sol, 8.0, 1e-8, "tiny_cycle");
}

#[test]
fn the_toolbox_objective_with_negative_rewards_equals_storm() {
    // Storm's values (issue 27); the toolbox's γ = 0.99 per uniformised step, races kept.
    for (name, storm) in [
        ("robocup_initial", 0.1894461726025),
        ("solarfarm_battery_1uav", 1.05477908),
    ] {
        let (_, model, rewards) = fixture(name, None, true);
        let sol = solve(
            &model,
            &rewards,
            &Objective::DiscountedPerStep {
                max: true,
                gamma: 0.99,
            },
            &SolveOptions::default(),
        )
        .unwrap();
        holds(&sol, storm, 1e-6, name);
    }
}

#[test]
fn total_min_leaves_a_zero_reward_end_component_solarfarm() {
    // Was 0 in [0, 0]: the robots could roam for ever at no cost. Storm: 5, the impulse of
    // the only way into the goal.
    let (net, model, rewards) = fixture("solarfarm_2timeouts_experiment", Some(false), false);
    let g = goal(&net, &model, "Inspecting_panel5 >= 1");
    let sol = solve(
        &model,
        &rewards,
        &Objective::Total {
            max: false,
            goal: g,
        },
        &SolveOptions::default(),
    )
    .unwrap();
    holds(&sol, 5.0, 1e-6, "total-min");
}

/// Two robots; each chooses route A (succeeds with 2/3) or route B (succeeds with 2/3 per
/// try and retries with 3/5 after a failure: 5/6 in all). A failed robot stops for good.
fn two_routes() -> Net {
    let mut b = NetBuilder::new("two_routes");
    let goal = b.place("Goal", 0);
    for i in 0..2 {
        let start = b.place(format!("Start{i}"), 1);
        let (ra, rb) = (b.place(format!("A{i}"), 0), b.place(format!("B{i}"), 0));
        let (retry, failed) = (
            b.place(format!("Retry{i}"), 0),
            b.place(format!("Failed{i}"), 0),
        );
        let (a, bb) = (
            b.immediate(format!("take_a{i}"), 0.0, 1),
            b.immediate(format!("take_b{i}"), 0.0, 1),
        );
        b.moves(start, a, ra);
        b.moves(start, bb, rb);
        for (from, to, rate, name) in [
            (ra, goal, 2.0, "a_ok"),
            (ra, failed, 1.0, "a_fail"),
            (rb, goal, 2.0, "b_ok"),
            (rb, retry, 1.0, "b_fail"),
            (retry, rb, 3.0, "retry"),
            (retry, failed, 2.0, "give_up"),
        ] {
            let t = b.exponential(format!("{name}{i}"), rate, Servers::Single);
            b.moves(from, t, to);
        }
    }
    b.build().unwrap()
}

#[test]
fn reach_both_robots_upper_bound_converges() {
    // Was "no convergence after 626 iterations (interval [0.694…, inf])".
    let net = two_routes();
    let model =
        DecisionModel::build(&net, &Controls::zero_weight(&net), &Default::default()).unwrap();
    let rewards = model.rewards(&RewardSpec::default());
    let g = goal(&net, &model, "Goal >= 2");
    for (max, exact) in [(true, 25.0 / 36.0), (false, 4.0 / 9.0)] {
        let sol = solve(
            &model,
            &rewards,
            &Objective::Reach {
                max,
                goal: g.clone(),
            },
            &SolveOptions::default(),
        )
        .unwrap();
        holds(
            &sol,
            exact,
            1e-9,
            if max { "reach-max" } else { "reach-min" },
        );
    }
}

// ---- Random small models against an exact referee -------------------------------------

/// An exact fraction (small numerators: the models use rates and weights below 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Q(i128, i128);

impl Q {
    fn new(n: i128, d: i128) -> Q {
        fn gcd(a: i128, b: i128) -> i128 {
            if b == 0 {
                a.abs().max(1)
            } else {
                gcd(b, a % b)
            }
        }
        let g = gcd(n, d) * d.signum();
        Q(n / g, d / g)
    }
    fn f64(self) -> f64 {
        self.0 as f64 / self.1 as f64
    }
}

impl From<i128> for Q {
    fn from(n: i128) -> Q {
        Q(n, 1)
    }
}

impl std::ops::Add for Q {
    type Output = Q;
    fn add(self, o: Q) -> Q {
        Q::new(self.0 * o.1 + o.0 * self.1, self.1 * o.1)
    }
}

impl std::ops::Sub for Q {
    type Output = Q;
    fn sub(self, o: Q) -> Q {
        Q::new(self.0 * o.1 - o.0 * self.1, self.1 * o.1)
    }
}

impl std::ops::Mul for Q {
    type Output = Q;
    fn mul(self, o: Q) -> Q {
        Q::new(self.0 * o.0, self.1 * o.1)
    }
}

impl std::ops::Div for Q {
    type Output = Q;
    fn div(self, o: Q) -> Q {
        Q::new(self.0 * o.1, self.1 * o.0)
    }
}

impl std::ops::AddAssign for Q {
    fn add_assign(&mut self, o: Q) {
        *self = *self + o;
    }
}

impl std::ops::SubAssign for Q {
    fn sub_assign(&mut self, o: Q) {
        *self = *self - o;
    }
}

impl PartialOrd for Q {
    fn partial_cmp(&self, o: &Q) -> Option<std::cmp::Ordering> {
        (self.0 * o.1).partial_cmp(&(o.0 * self.1))
    }
}

/// A random model as a one-token state machine: place `i` is state `i`. Decision places
/// offer controllable transitions, each into a race place whose weighted immediate
/// transitions spread the token (the choice's branches); timed places race exponential
/// transitions. Small integers keep the referee's fractions exact.
#[derive(Clone, Debug)]
struct Spec {
    /// Per state: `None` for timed, `Some(choices)` for a decision; each choice a list of
    /// `(target, weight)`.
    decisions: Vec<Option<Vec<Vec<(usize, u8)>>>>,
    /// Per timed state: `(target, rate)`.
    timed: Vec<Vec<(usize, u8)>>,
    /// Per state: reward rate while marked (timed) ; per choice: impulse.
    rate: Vec<i8>,
    impulse: Vec<Vec<i8>>,
}

fn spec(n: usize) -> impl Strategy<Value = Spec> {
    let arc = (0..n, 1u8..4);
    let state = prop_oneof![
        prop::collection::vec(prop::collection::vec(arc.clone(), 1..3), 1..3).prop_map(Some),
        Just(None),
    ];
    (
        prop::collection::vec(state, n),
        prop::collection::vec(prop::collection::vec(arc, 1..3), n),
        prop::collection::vec(-2i8..3, n),
        prop::collection::vec(prop::collection::vec(0i8..3, 2), n),
    )
        .prop_map(|(decisions, timed, rate, impulse)| Spec {
            decisions,
            timed,
            rate,
            impulse,
        })
}

impl Spec {
    fn net(&self) -> (Net, Vec<Vec<gspn::net::TransitionId>>) {
        let n = self.decisions.len();
        let mut b = NetBuilder::new("random");
        let places: Vec<_> = (0..n)
            .map(|i| b.place(format!("S{i}"), (i == 0) as u32))
            .collect();
        let mut choices = vec![Vec::new(); n];
        for i in 0..n {
            match &self.decisions[i] {
                Some(cs) => {
                    for (k, arcs) in cs.iter().enumerate() {
                        let t = b.immediate(format!("c{i}_{k}"), 0.0, 1);
                        choices[i].push(t);
                        let race = b.place(format!("R{i}_{k}"), 0);
                        b.moves(places[i], t, race);
                        for (j, &(to, w)) in arcs.iter().enumerate() {
                            let u = b.immediate(format!("r{i}_{k}_{j}"), w as f64, 1);
                            b.moves(race, u, places[to]);
                        }
                    }
                }
                None => {
                    for (j, &(to, rate)) in self.timed[i].iter().enumerate() {
                        let t = b.exponential(format!("e{i}_{j}"), rate as f64, Servers::Single);
                        b.moves(places[i], t, places[to]);
                    }
                }
            }
        }
        (b.build().unwrap(), choices)
    }

    /// Per state, per choice: `(impulse, [(target, probability)])`, the exponential race
    /// as one choice of a timed state with its exit rate.
    fn chain(&self) -> Vec<(Option<Q>, Vec<(Q, Vec<(usize, Q)>)>)> {
        let merge = |arcs: &[(usize, u8)]| {
            let total: i128 = arcs.iter().map(|&(_, w)| w as i128).sum();
            arcs.iter()
                .map(|&(to, w)| (to, Q::new(w as i128, total)))
                .collect::<Vec<_>>()
        };
        (0..self.decisions.len())
            .map(|i| match &self.decisions[i] {
                Some(cs) => (
                    None,
                    cs.iter()
                        .enumerate()
                        .map(|(k, arcs)| (Q::from(self.impulse[i][k.min(1)] as i128), merge(arcs)))
                        .collect(),
                ),
                None => {
                    let exit: i128 = self.timed[i].iter().map(|&(_, r)| r as i128).sum();
                    (
                        Some(Q::from(exit)),
                        vec![(Q::from(0), merge(&self.timed[i]))],
                    )
                }
            })
            .collect()
    }
}

/// Solves `x = b + A x` over the states flagged `free` (others give their `x` in `known`),
/// by Gaussian elimination in rationals; `None` when singular.
fn solve_exact(a: &[Vec<(usize, Q)>], b: &[Q], free: &[bool], known: &[Q]) -> Option<Vec<Q>> {
    let n = b.len();
    let idx: Vec<usize> = (0..n).filter(|&i| free[i]).collect();
    let pos = |s: usize| idx.iter().position(|&i| i == s);
    let k = idx.len();
    let mut m = vec![vec![Q::from(0); k + 1]; k];
    for (r, &s) in idx.iter().enumerate() {
        m[r][r] += Q::from(1);
        m[r][k] += b[s];
        for &(t, p) in &a[s] {
            match pos(t) {
                Some(c) => m[r][c] -= p,
                None => m[r][k] += p * known[t],
            }
        }
    }
    for c in 0..k {
        let piv = (c..k).find(|&r| m[r][c] != Q::from(0))?;
        m.swap(c, piv);
        for r in 0..k {
            if r != c && m[r][c] != Q::from(0) {
                let f = m[r][c] / m[c][c];
                for j in c..=k {
                    let x = m[c][j];
                    m[r][j] -= f * x;
                }
            }
        }
    }
    let mut x = known.to_vec();
    for (r, &s) in idx.iter().enumerate() {
        x[s] = m[r][k] / m[r][r];
    }
    Some(x)
}

/// Which objective the referee and the solver compare.
#[derive(Clone, Copy, Debug)]
enum Kind {
    Reach,
    TotalMin,
    Discounted,
}

/// The exact optimum at state 0 over every deterministic policy (None: infinite).
fn referee(spec: &Spec, kind: Kind, max: bool, goal: usize) -> Option<f64> {
    let chain = spec.chain();
    let n = chain.len();
    let counts: Vec<usize> = chain.iter().map(|(_, cs)| cs.len()).collect();
    let mut pick = vec![0usize; n];
    let mut best: Option<Option<Q>> = None;
    loop {
        let mut a: Vec<Vec<(usize, Q)>> = vec![Vec::new(); n];
        let mut b = vec![Q::from(0); n];
        let mut free = vec![true; n];
        let mut known = vec![Q::from(0); n];
        for s in 0..n {
            let (exit, cs) = &chain[s];
            let (imp, arcs) = &cs[pick[s]];
            match kind {
                Kind::Reach | Kind::TotalMin if s == goal => {
                    free[s] = false;
                    known[s] = Q::from(matches!(kind, Kind::Reach) as i128);
                }
                Kind::Reach => a[s] = arcs.clone(),
                Kind::TotalMin => {
                    a[s] = arcs.clone();
                    b[s] = match exit {
                        Some(e) => Q::from(spec.rate[s] as i128) / e,
                        None => *imp,
                    };
                }
                Kind::Discounted => {
                    // x = (ρ + Σ rate·x') / (e + δ), δ = 1/2; instant: x = imp + Σ p x'.
                    match exit {
                        Some(e) => {
                            let d = *e + Q::new(1, 2);
                            b[s] = Q::from(spec.rate[s] as i128) / d;
                            a[s] = arcs.iter().map(|&(t, p)| (t, p * *e / d)).collect();
                        }
                        None => {
                            b[s] = *imp;
                            a[s] = arcs.clone();
                        }
                    }
                }
            }
        }
        // Only what the policy reaches from state 0 matters (and a loop elsewhere must not
        // make the system singular).
        let seen = reachable(&a, 0);
        for s in 0..n {
            if !seen[s] {
                free[s] = false;
            }
        }
        let value = match kind {
            Kind::Reach => {
                // States that cannot reach the goal under the policy are 0.
                let reach = reaches(&a, goal);
                for s in 0..n {
                    if !reach[s] {
                        free[s] = false;
                    }
                }
                solve_exact(&a, &b, &free, &known).map(|x| Some(x[0]))
            }
            Kind::TotalMin => {
                // Infinite unless the goal is reached with probability 1.
                let reach = reaches(&a, goal);
                let sure = (0..n).all(|s| !reachable(&a, 0)[s] || reach[s]);
                if sure {
                    solve_exact(&a, &b, &free, &known).map(|x| Some(x[0]))
                } else {
                    Some(None)
                }
            }
            Kind::Discounted => solve_exact(&a, &b, &free, &known).map(|x| Some(x[0])),
        };
        // A policy whose equations are singular loops through instant states for ever: the
        // solver never picks it for a finite answer; skip it.
        if let Some(v) = value {
            let better = |x: &Option<Q>, y: &Option<Q>| match (x, y) {
                (Some(x), Some(y)) => {
                    if max {
                        x > y
                    } else {
                        x < y
                    }
                }
                (Some(_), None) => !max,
                (None, Some(_)) => max,
                (None, None) => false,
            };
            if best.as_ref().is_none_or(|bv| better(&v, bv)) {
                best = Some(v);
            }
        }
        // Next policy.
        let mut i = 0;
        while i < n {
            pick[i] += 1;
            if pick[i] < counts[i] {
                break;
            }
            pick[i] = 0;
            i += 1;
        }
        if i == n {
            break;
        }
    }
    best.flatten().map(Q::f64)
}

/// States that reach `goal` along positive arcs.
fn reaches(a: &[Vec<(usize, Q)>], goal: usize) -> Vec<bool> {
    let n = a.len();
    let mut r = vec![false; n];
    r[goal] = true;
    loop {
        let mut changed = false;
        for s in 0..n {
            if !r[s] && a[s].iter().any(|&(t, _)| r[t]) {
                r[s] = true;
                changed = true;
            }
        }
        if !changed {
            return r;
        }
    }
}

/// States reachable from `from`.
fn reachable(a: &[Vec<(usize, Q)>], from: usize) -> Vec<bool> {
    let mut r = vec![false; a.len()];
    let mut stack = vec![from];
    r[from] = true;
    while let Some(s) = stack.pop() {
        for &(t, _) in &a[s] {
            if !r[t] {
                r[t] = true;
                stack.push(t);
            }
        }
    }
    r
}

fn check_random(spec: &Spec, kind: Kind, max: bool) -> Result<(), TestCaseError> {
    let n = spec.decisions.len();
    let goal_state = n - 1;
    let (net, choices) = spec.net();
    let model = match DecisionModel::build(&net, &Controls::zero_weight(&net), &Default::default())
    {
        Ok(m) => m,
        // Timeless traps and the like are refused at build: nothing to compare.
        Err(_) => return Ok(()),
    };
    let mut rs = RewardSpec::default();
    for i in 0..n {
        if spec.decisions[i].is_none() {
            let p = net.place_by_name(&format!("S{i}")).unwrap();
            rs.places.push((p, spec.rate[i] as f64, PlaceMode::Tokens));
        }
        for (k, &t) in choices[i].iter().enumerate() {
            rs.transitions.push((t, spec.impulse[i][k.min(1)] as f64));
        }
    }
    if matches!(kind, Kind::TotalMin) {
        // Total reward needs rewards ≥ 0.
        rs.places.iter_mut().for_each(|p| p.1 = p.1.abs());
    }
    let rewards = model.rewards(&rs);
    let target = format!("S{goal_state} >= 1");
    let g = goal(&net, &model, &target);
    let objective = match kind {
        Kind::Reach => Objective::Reach { max, goal: g },
        Kind::TotalMin => Objective::Total {
            max: false,
            goal: g,
        },
        Kind::Discounted => Objective::Discounted { max, rate: 0.5 },
    };
    let mut exact_spec = spec.clone();
    if matches!(kind, Kind::TotalMin) {
        exact_spec.rate.iter_mut().for_each(|r| *r = r.abs());
    }
    let want = referee(&exact_spec, kind, max, goal_state);
    // A model whose policy can loop through decisions for ever without time has no unique
    // fixed point; the iteration then stops at its limit (an error, allowed below).
    let opts = SolveOptions {
        max_iterations: 20_000,
        ..SolveOptions::default()
    };
    // Refusing is allowed; printing a wrong interval is not.
    if let Ok(sol) = solve(&model, &rewards, &objective, &opts) {
        let tol = 1e-9 * want.unwrap_or(1.0).abs().max(1.0);
        match want {
            Some(w) => prop_assert!(
                sol.lower <= w + tol && w <= sol.upper + tol,
                "{kind:?} max={max}: [{}, {}] misses {w}",
                sol.lower,
                sol.upper
            ),
            None => prop_assert!(sol.value.is_infinite(), "{kind:?}: {} for ∞", sol.value),
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn every_printed_interval_holds_the_exact_optimum(s in spec(5), max in any::<bool>()) {
        for kind in [Kind::Reach, Kind::TotalMin, Kind::Discounted] {
            check_random(&s, kind, max)?;
        }
    }
}
