//! Answers to `=?` queries on a state space (the bare net, or a plan's net under its
//! policy): time-bounded ones by uniformisation (error ≤ [`TRANSIENT_EPS`] in probability),
//! unbounded ones by a sparse LU on the embedded chain, long-run ones from the limiting
//! distribution.

use std::sync::OnceLock;

use super::absorbing::{Absorbing, Class};
use super::{Kind, Query, QueryError};
use crate::analysis::ctmc::{Ctmc, Limiting, poisson_weights};
use crate::analysis::decision::{BuildOptions, Controls, RewardSpec};
use crate::analysis::measures::{
    MAX_UNIFORMISATION, Solver, SolverOptions, TRANSIENT_EPS, TransientOptions,
};
use crate::analysis::state_space::StateSpace;
use crate::analysis::under_policy::reward_rate;
use crate::net::Net;
use crate::net::predicate::Predicate;

/// Answers queries on one state space; the limiting distribution is solved once, on the
/// first long-run query. `max`/`min` queries go to the synthesis engine when the
/// evaluator knows the plan's controllable transitions ([`Evaluator::with_controls`]).
#[derive(Debug)]
pub struct Evaluator<'a> {
    net: &'a Net,
    space: &'a StateSpace,
    rewards: &'a [RewardSpec],
    limiting: OnceLock<Result<Limiting, QueryError>>,
    controls: Option<(&'a Controls, BuildOptions)>,
}

impl<'a> Evaluator<'a> {
    /// An evaluator over `space`, the state space of `net` (under a policy or not), with the
    /// reward structures `R{"name"}` refers to (the ones given to [`Query::parse`]).
    pub fn new(net: &'a Net, space: &'a StateSpace, rewards: &'a [RewardSpec]) -> Self {
        Evaluator {
            net,
            space,
            rewards,
            limiting: OnceLock::new(),
            controls: None,
        }
    }

    /// An evaluator that answers `Pmax=?`, `Tmin=?`, … too: over the policies of
    /// `controls` (a plan's controllable transitions), through [`super::extreme`], with the
    /// decision model searched under `build`.
    pub fn with_controls(mut self, controls: &'a Controls, build: BuildOptions) -> Self {
        self.controls = Some((controls, build));
        self
    }

    /// An evaluator that reuses a limiting distribution already solved on `space`.
    pub fn with_limiting(mut self, limiting: Limiting) -> Self {
        self.limiting = OnceLock::from(Ok(limiting));
        self
    }

    /// The value of `query` (`f64::INFINITY` for an expected time or reward when the goal is
    /// missed with positive probability). `max`/`min` queries go to [`super::extreme`],
    /// and are refused unless [`Evaluator::with_controls`] gave the controllable transitions.
    pub fn evaluate(&self, query: &Query) -> Result<f64, QueryError> {
        if query.extreme.is_some() {
            return match &self.controls {
                Some((controls, build)) => {
                    super::extreme::evaluate(self.net, controls, self.rewards, query, build)
                }
                None => Err(QueryError::Unsupported(format!(
                    "`{query}` asks for the best or worst choice: it needs the plan's \
                     controllable transitions (query::extreme)"
                ))),
            };
        }
        match &query.kind {
            Kind::Until { safe, goal, bound } => {
                let abs = self.until(safe.as_ref(), goal)?;
                Ok(match bound {
                    Some(t) => self.bounded(&abs, &[*t])?[0],
                    None => unbounded(&abs)?,
                })
            }
            Kind::Globally { phi, bound } => {
                let abs = Absorbing::build(self.space, self.net.place_count(), |m| {
                    if phi.eval(m) { Class::Go } else { Class::Goal }
                })?;
                let miss = match bound {
                    Some(t) => self.bounded(&abs, &[*t])?[0],
                    None => unbounded(&abs)?,
                };
                Ok((1.0 - miss).max(0.0))
            }
            Kind::Time { goal } => {
                let abs = self.until(None, goal)?;
                let exit = abs.chain.exit_rates();
                let rho: Vec<f64> = (0..abs.chain.n)
                    .map(|s| if exit[s] > 0.0 { 1.0 } else { 0.0 })
                    .collect();
                accumulated(&abs, &rho)
            }
            Kind::Steady { phi } => {
                let l = self.limiting()?;
                Ok(Solver::new(self.net, self.space).probability(&l.pi, phi))
            }
            Kind::RewardSteady { reward } => {
                let l = self.limiting()?;
                let solver = Solver::new(self.net, self.space);
                let measures = solver.measures(&l.pi);
                Ok(reward_rate(
                    self.net,
                    self.space,
                    &l.pi,
                    &measures,
                    &self.rewards[*reward],
                )
                .rate)
            }
            Kind::RewardCumulative { reward, bound } => {
                let rho = state_rewards(self.net, self.space, &self.rewards[*reward]);
                let solver = Solver::new(self.net, self.space);
                cumulative(solver.chain(), self.space.initial(), &rho, *bound)
            }
            Kind::RewardReach { reward, goal } => {
                let abs = self.until(None, goal)?;
                let mut rho = state_rewards(self.net, self.space, &self.rewards[*reward]);
                rho.extend([0.0, 0.0]);
                accumulated(&abs, &rho)
            }
        }
    }

    /// `P=? [safe U<=t goal]` at each of `times` (one uniformisation over them all): a
    /// curve over time for `analyze --transient … --query`.
    pub fn until_over_time(&self, query: &Query, times: &[f64]) -> Result<Vec<f64>, QueryError> {
        match &query.kind {
            Kind::Until { safe, goal, .. } => {
                let abs = self.until(safe.as_ref(), goal)?;
                self.bounded(&abs, times)
            }
            _ => Err(QueryError::Unsupported(format!(
                "`{query}` is not a time-bounded `P=? [F<=t φ]` or `U<=t`"
            ))),
        }
    }

    fn until(&self, safe: Option<&Predicate>, goal: &Predicate) -> Result<Absorbing, QueryError> {
        Absorbing::build(self.space, self.net.place_count(), |m| {
            if goal.eval(m) {
                Class::Goal
            } else if safe.is_some_and(|s| !s.eval(m)) {
                Class::Fail
            } else {
                Class::Go
            }
        })
    }

    /// P(in the goal sink at each time).
    fn bounded(&self, abs: &Absorbing, times: &[f64]) -> Result<Vec<f64>, QueryError> {
        let lambda = abs.chain.exit_rates().into_iter().fold(0.0, f64::max);
        if let Some(&t) = times.iter().find(|&&t| lambda * t > MAX_UNIFORMISATION) {
            return Err(QueryError::Unsupported(format!(
                "t = {t:e} needs about {:.3e} iterations of uniformisation (Λ = {lambda}); at \
                 most {MAX_UNIFORMISATION:e}: ask the unbounded `F φ`",
                lambda * t
            )));
        }
        let goal = abs.goal() as usize;
        let at = abs
            .chain
            .transient(&abs.initial, times, &TransientOptions::default())?;
        Ok(at.iter().map(|pi| pi[goal].min(1.0)).collect())
    }

    fn limiting(&self) -> Result<&Limiting, QueryError> {
        self.limiting
            .get_or_init(|| {
                Solver::new(self.net, self.space)
                    .steady_state(&SolverOptions::default())
                    .map_err(QueryError::from)
            })
            .as_ref()
            .map_err(Clone::clone)
    }
}

/// Reward per unit of time in each tangible state of `space`: its places' rates (where time
/// passes), and the impulses of the exponential transitions and of the immediate ones after
/// them, at their rates — the same expectation as impulses per firing, for every `R`
/// query and PRISM's `.srew` ([`Explicit::with_rewards`](crate::io::prism::Explicit::with_rewards)).
pub fn state_rewards(net: &Net, space: &StateSpace, spec: &RewardSpec) -> Vec<f64> {
    let n = space.tangible_count();
    let impulse = spec.impulses(net);
    let mut m = vec![0u32; net.place_count()];
    let mut rho: Vec<f64> = (0..n)
        .map(|s| {
            let arcs = space.arcs(s);
            if arcs.is_empty() {
                return 0.0;
            }
            space.marking_into(s, &mut m);
            spec.place_rate(&m)
                + arcs
                    .iter()
                    .map(|mv| mv.rate * impulse[mv.transition.index()])
                    .sum::<f64>()
        })
        .collect();
    for f in space.immediate_flows() {
        let s = f.state as usize;
        let rate: f64 = space
            .arcs(s)
            .iter()
            .filter(|mv| mv.transition == f.transition)
            .map(|mv| mv.rate)
            .next()
            .unwrap_or(0.0);
        rho[s] += rate * f.expected * impulse[f.immediate.index()];
    }
    rho
}

/// States that can reach `target` (target included), backwards over the chain.
fn reaching(chain: &Ctmc, target: &[bool]) -> Vec<bool> {
    let (ptr, rows, _) = chain.incoming();
    let mut seen = target.to_vec();
    let mut queue: Vec<u32> = (0..chain.n as u32)
        .filter(|&s| target[s as usize])
        .collect();
    while let Some(j) = queue.pop() {
        for &i in &rows[ptr[j as usize]..ptr[j as usize + 1]] {
            if !seen[i as usize] {
                seen[i as usize] = true;
                queue.push(i);
            }
        }
    }
    seen
}

/// Solves `E_s·x_s − Σ_{j ∈ keep} q_sj·x_j = b_s` over the states `keep` (0 elsewhere).
fn solve_on(chain: &Ctmc, keep: &[bool], b: &[f64]) -> Result<Vec<f64>, QueryError> {
    let mut index = vec![usize::MAX; chain.n];
    let mut states = Vec::new();
    for s in 0..chain.n {
        if keep[s] {
            index[s] = states.len();
            states.push(s);
        }
    }
    let mut triplets = Vec::new();
    let mut rhs = Vec::with_capacity(states.len());
    for (k, &s) in states.iter().enumerate() {
        triplets.push((k, k, chain.exit_rate(s)));
        for (j, q) in chain.row(s) {
            if index[j as usize] != usize::MAX {
                triplets.push((k, index[j as usize], -q));
            }
        }
        rhs.push(b[s]);
    }
    let mut x = vec![0.0; chain.n];
    if states.is_empty() {
        return Ok(x);
    }
    let sol = crate::analysis::ctmc::lu::solve(states.len(), &triplets, &rhs)
        .map_err(crate::analysis::ctmc::SolveError::from)?;
    for (k, &s) in states.iter().enumerate() {
        x[s] = sol[k];
    }
    Ok(x)
}

/// P(ever in the goal sink) from the initial distribution.
fn unbounded(abs: &Absorbing) -> Result<f64, QueryError> {
    let goal = abs.goal() as usize;
    let mut target = vec![false; abs.chain.n];
    target[goal] = true;
    let mut maybe = reaching(&abs.chain, &target);
    maybe[goal] = false;
    let b: Vec<f64> = (0..abs.chain.n)
        .map(|s| {
            abs.chain
                .row(s)
                .filter(|&(j, _)| j as usize == goal)
                .map(|(_, q)| q)
                .sum()
        })
        .collect();
    let x = solve_on(&abs.chain, &maybe, &b)?;
    let p: f64 = abs
        .initial
        .iter()
        .map(|&(s, p)| {
            p * if s as usize == goal {
                1.0
            } else {
                x[s as usize]
            }
        })
        .sum();
    Ok(p.clamp(0.0, 1.0))
}

/// The expected reward (rate `rho` per state) accumulated until the goal sink, from the
/// initial distribution; ∞ when the goal is missed with positive probability.
fn accumulated(abs: &Absorbing, rho: &[f64]) -> Result<f64, QueryError> {
    let n = abs.chain.n;
    let goal = abs.goal() as usize;
    let mut target = vec![false; n];
    target[goal] = true;
    let can = reaching(&abs.chain, &target);
    let never: Vec<bool> = can.iter().map(|&c| !c).collect();
    let bad = reaching(&abs.chain, &never);
    if abs.initial.iter().any(|&(s, p)| p > 0.0 && bad[s as usize]) {
        return Ok(f64::INFINITY);
    }
    let keep: Vec<bool> = (0..n).map(|s| s != goal && !bad[s]).collect();
    let y = solve_on(&abs.chain, &keep, rho)?;
    Ok(abs.initial.iter().map(|&(s, p)| p * y[s as usize]).sum())
}

/// `E[∫_0^t rho(X_u) du]` on `chain` from `initial`: `(1/Λ)·Σ_k π_k·rho·P(N(Λt) > k)`,
/// the Poisson tail truncated at [`TRANSIENT_EPS`].
fn cumulative(
    chain: &Ctmc,
    initial: &[(u32, f64)],
    rho: &[f64],
    t: f64,
) -> Result<f64, QueryError> {
    let exit = chain.exit_rates();
    let lambda = exit.iter().copied().fold(0.0, f64::max);
    let mut cur = vec![0.0; chain.n];
    for &(s, p) in initial {
        cur[s as usize] += p;
    }
    let dot = |v: &[f64]| v.iter().zip(rho).map(|(a, b)| a * b).sum::<f64>();
    if lambda == 0.0 || t == 0.0 {
        return Ok(t * dot(&cur));
    }
    if lambda * t > MAX_UNIFORMISATION {
        return Err(QueryError::Unsupported(format!(
            "C<={t}: about {:.3e} iterations of uniformisation, at most {MAX_UNIFORMISATION:e}",
            lambda * t
        )));
    }
    let (first, weights) = poisson_weights(lambda * t, TRANSIENT_EPS);
    let last = first + weights.len() - 1;
    let inv = 1.0 / lambda;
    let mut next = vec![0.0; chain.n];
    let mut cdf = 0.0;
    let mut total = 0.0;
    for k in 0..=last {
        if k >= first {
            cdf += weights[k - first];
        }
        total += dot(&cur) * (1.0 - cdf).max(0.0);
        if k == last {
            break;
        }
        chain.uniform_step(&cur, &mut next, &exit, inv);
        std::mem::swap(&mut cur, &mut next);
    }
    Ok(total * inv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::decision::PlaceMode;
    use crate::analysis::state_space::Options;
    use crate::net::{NetBuilder, Servers};

    /// A machine up (fails at λ = 0.5) and down (repaired at μ = 2); reward 1 per unit of
    /// time up, 5 per failure.
    fn machine() -> (Net, Vec<RewardSpec>) {
        let mut b = NetBuilder::new("machine");
        let (up, down) = (b.place("Up", 1), b.place("Down", 0));
        let fail = b.exponential("fail", 0.5, Servers::Single);
        let repair = b.exponential("repair", 2.0, Servers::Single);
        b.input(up, fail, 1);
        b.output(fail, down, 1);
        b.input(down, repair, 1);
        b.output(repair, up, 1);
        let spec = RewardSpec {
            name: "r".into(),
            places: vec![(up, 1.0, PlaceMode::Marked)],
            transitions: vec![(fail, 5.0)],
        };
        (b.build().unwrap(), vec![spec])
    }

    fn ask(net: &Net, rewards: &[RewardSpec], text: &str) -> f64 {
        let space = StateSpace::build(net, &Options::default()).unwrap();
        let ev = Evaluator::new(net, &space, rewards);
        ev.evaluate(&Query::parse(net, rewards, text).unwrap())
            .unwrap()
    }

    #[test]
    fn rewards_long_run_accumulated_and_until() {
        let (net, rw) = machine();
        let (l, m) = (0.5f64, 2.0f64);
        // Long run: P(up)·1 + throughput(fail)·5 = μ/(λ+μ) + 5·λμ/(λ+μ).
        let s = ask(&net, &rw, "R{\"r\"}=? [S]");
        assert!(
            (s - (m / (l + m) + 5.0 * l * m / (l + m))).abs() < 1e-12,
            "{s}"
        );
        // ∫_0^t P(up) du + 5·∫_0^t λ·P(up) du, P(up)(u) = μ/(λ+μ) + λ/(λ+μ)·e^{−(λ+μ)u}.
        let t = 3.0;
        let up = m * t / (l + m) + l / (l + m).powi(2) * (1.0 - (-(l + m) * t).exp());
        let c = ask(&net, &rw, "R{\"r\"}=? [C<=3]");
        assert!(
            (c - (up + 5.0 * l * up)).abs() < 1e-9,
            "{c} vs {}",
            up + 5.0 * l * up
        );
        // Until the first failure: 1/λ up, then the failure's impulse 5.
        let f = ask(&net, &rw, "R{\"r\"}=? [F Down=1]");
        assert!((f - (1.0 / l + 5.0)).abs() < 1e-12, "{f}");
        // Never reached: infinite.
        assert_eq!(ask(&net, &rw, "R{\"r\"}=? [F Down=2]"), f64::INFINITY);
        // P(still up through [0, t]) = e^{−λt}; G for ever is 0.
        let g = ask(&net, &rw, "P=? [G<=3 Up=1]");
        assert!((g - (-l * t).exp()).abs() < 1e-10, "{g}");
        assert!(ask(&net, &rw, "P=? [G Up=1]").abs() < 1e-12);
    }

    /// Regression against Storm 2.0.0, which keeps one of the two: A → T1 (rate 1) or T2
    /// (rate 2) → B, vanishing (an immediate transition empties it into D). The time to D is
    /// 1/3; Storm answers 1.
    #[test]
    fn two_exponential_transitions_into_one_vanishing_marking_add_up() {
        let mut b = NetBuilder::new("twins");
        let (a, bb, d) = (b.place("A", 1), b.place("B", 0), b.place("D", 0));
        for (name, rate) in [("T1", 1.0), ("T2", 2.0)] {
            let t = b.exponential(name, rate, Servers::Single);
            b.input(a, t, 1);
            b.output(t, bb, 1);
        }
        let i = b.immediate("i", 1.0, 1);
        b.input(bb, i, 1);
        b.output(i, d, 1);
        let net = b.build().unwrap();
        assert!((ask(&net, &[], "T=? [F D=1]") - 1.0 / 3.0).abs() < 1e-12);
        // Within t = 0.5: 1 − e^{−3·0.5}.
        let p = ask(&net, &[], "P=? [F<=0.5 D=1]");
        assert!((p - (1.0 - (-1.5f64).exp())).abs() < 1e-10, "{p}");
    }
}
