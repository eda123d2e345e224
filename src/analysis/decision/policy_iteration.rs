//! Policy iteration for the long-run average reward inside one maximal end component.
//!
//! A MEC is communicating, so its optimal average `g` is one number. Each round evaluates the
//! current policy exactly — gain `g` and bias `h` from the linear system
//!
//! - Markovian state `s` (exit rate `E`): `g + E·h(s) − E·Σ p·h(s') = rate(s) + E·impulse`,
//! - instant state `s`: `h(s) − Σ p·h(s') = impulse`,
//! - `h(ref) = 0` for one recurrent Markovian state,
//!
//! solved one strongly connected component of the policy's graph at a time, sinks first
//! (the components are kept from round to round and updated where the policy changed:
//! [`PolicyGraph::update`])
//! ([`evaluate`]: dense LU for small components, sparse LU for large ones; the GSPNR models'
//! policies have components of at most a few states, so a round is a few passes over the
//! branches, where one LU of the whole system filled in to hundreds of MB at 8 robots),
//! then improves it: an instant state switches to a choice whose `impulse + Σ p·h(s')` is
//! strictly better (Markovian states have one choice). A policy whose chain has several
//! bottom components is repaired first: each bottom component's gain is evaluated alone, and
//! every state outside the best one is steered to it ([`steer`]: almost surely, through
//! choices that stay in the MEC), which makes it unichain with that best gain. The gain never
//! gets worse from round to round; the rounds stop when no state switches.
//!
//! The result is not trusted as such: the caller ([`lra`](super::lra)) starts its value
//! iteration from the final bias, whose one Bellman step gives the sound interval
//! `min(Tv − v)·Λ ≤ g ≤ max(Tv − v)·Λ` — tight at once when the policy is optimal.

use super::lra::Mecs;
use super::policy_graph::{Components, Graph, PolicyGraph};
use super::solve::{Algorithm, SolveOptions};
use super::{DecisionError, DecisionModel, Kind, Rewards};
use crate::analysis::linear::solve_block;
use crate::analysis::scc::{Members, Sccs};

/// Most rounds before giving up (each round at least improves the bias).
const MAX_ROUNDS: usize = 1000;

/// Runs policy iteration on the MEC `states`; writes the policy of its instant states into
/// `policy` and returns the bias per state (indexed globally; 0 outside the MEC) and the
/// number of rounds.
pub(super) fn mec_policy_iteration(
    model: &DecisionModel,
    rewards: &Rewards,
    mecs: &Mecs,
    states: &[u32],
    max: bool,
    opts: &SolveOptions,
    policy: &mut [u32],
) -> Result<Option<(Vec<f64>, usize)>, DecisionError> {
    let n = model.state_count();
    let mut h = vec![0.0f64; n];
    // A dead state is a MEC alone: gain 0, nothing to choose.
    if states.iter().any(|&s| model.kind(s as usize) == Kind::Dead) {
        return Ok(Some((h, 0)));
    }
    let mut local = vec![u32::MAX; n];
    for (i, &s) in states.iter().enumerate() {
        local[s as usize] = i as u32;
    }
    let better = |a: f64, b: f64| if max { a > b } else { a < b };
    // Start with the first inside choice that time can leave: an instant state prefers a
    // choice reaching a Markovian state, so the start has no timeless loop when avoidable.
    for &s in states {
        let s = s as usize;
        let mut inside = model.choices(s).filter(|&c| mecs.inside[c]);
        let first = inside
            .clone()
            .next()
            .expect("a MEC state has an inside choice");
        policy[s] = inside
            .find(|&c| {
                model
                    .branches(c)
                    .any(|(t, _)| model.kind(t as usize) != Kind::Instant)
            })
            .unwrap_or(first) as u32;
    }
    let g = Graph {
        model,
        states,
        local: &local,
    };
    // The components of the last round's graph, and the local states switched since.
    let mut kept: Option<PolicyGraph> = None;
    let mut switched: Vec<u32> = Vec::new();
    let mut rounds = 0;
    loop {
        if opts.cancelled() {
            return Err(DecisionError::Cancelled { iterations: rounds });
        }
        if rounds >= MAX_ROUNDS {
            return Err(DecisionError::NoConvergence {
                iterations: rounds,
                lower: f64::NAN,
                upper: f64::NAN,
            });
        }
        rounds += 1;
        let successors = |v: u32, out: &mut Vec<u32>| g.successors(policy, v, out);
        let graph = kept
            .take()
            .and_then(|mut graph| graph.update(successors, &switched).then_some(graph))
            .unwrap_or_else(|| PolicyGraph::compute(states.len(), successors));
        let (reference, graph) = make_unichain(rewards, mecs, g, max, policy, graph)?;
        if opts.algorithm == Algorithm::Auto
            && graph.comps.largest() > Algorithm::AUTO_COMPONENT_LIMIT
        {
            return Ok(None);
        }
        let x = evaluate(
            model,
            rewards,
            states,
            &local,
            policy,
            reference,
            &graph.comps,
        )?;
        for (i, &s) in states.iter().enumerate() {
            h[s as usize] = if i == reference { 0.0 } else { x[i] };
        }
        // Improvement: instant states only (a Markovian state has one choice).
        switched.clear();
        for (i, &s) in states.iter().enumerate() {
            let s = s as usize;
            if model.kind(s) != Kind::Instant || model.choices(s).len() < 2 {
                continue;
            }
            let value = |c: usize| {
                rewards.impulse[c]
                    + model
                        .branches(c)
                        .map(|(t, p)| p * h[t as usize])
                        .sum::<f64>()
            };
            let current = value(policy[s] as usize);
            let tol = 1e-10 * (1.0 + current.abs());
            let mut best = (current, policy[s] as usize);
            for c in model.choices(s) {
                if !mecs.inside[c] || c == policy[s] as usize {
                    continue;
                }
                let v = value(c);
                if better(v, best.0) && (v - current).abs() > tol {
                    best = (v, c);
                }
            }
            if best.1 != policy[s] as usize {
                policy[s] = best.1 as u32;
                switched.push(i as u32);
            }
        }
        if switched.is_empty() {
            return Ok(Some((h, rounds)));
        }
        kept = Some(graph);
    }
}

/// Makes the policy unichain: when its chain on the MEC has several bottom components (or one
/// where time never passes), evaluates each and steers every state to the best. Returns the
/// local index of a Markovian state of the remaining bottom component, and the components of
/// the policy's graph (`graph`, the components of `policy` on entry, or new ones after
/// steering).
fn make_unichain(
    rewards: &Rewards,
    mecs: &Mecs,
    g: Graph<'_>,
    max: bool,
    policy: &mut [u32],
    graph: PolicyGraph,
) -> Result<(usize, PolicyGraph), DecisionError> {
    let (model, states) = (g.model, g.states);
    let markovian = |comp: &[u32]| {
        comp.iter()
            .copied()
            .find(|&v| model.kind(states[v as usize] as usize) == Kind::Markovian)
    };
    let bottoms = |graph: &PolicyGraph| -> Vec<usize> {
        (0..graph.comps.sccs.count)
            .filter(|&c| graph.bottom[c])
            .collect()
    };
    if let [only] = bottoms(&graph)[..]
        && let Some(r) = markovian(&graph.comps.members[only])
    {
        return Ok((r as usize, graph));
    }
    // The bottom components are taken in a fresh search's order, so that a tie between
    // equal gains goes the same way whatever the earlier rounds split.
    let graph = if graph.fresh {
        graph
    } else {
        PolicyGraph::compute(states.len(), |v, out| g.successors(policy, v, out))
    };
    let members = &graph.comps.members;
    let bottoms = bottoms(&graph);
    // Several bottom components: the gain of each (timeless ones are worst).
    let better = |a: f64, b: f64| if max { a > b } else { a < b };
    let mut best: Option<(f64, usize, u32)> = None;
    let mut sub_local = vec![u32::MAX; model.state_count()];
    for &c in &bottoms {
        let Some(r) = markovian(&members[c]) else {
            continue;
        };
        let comp: Vec<u32> = members[c].iter().map(|&v| states[v as usize]).collect();
        for (i, &s) in comp.iter().enumerate() {
            sub_local[s as usize] = i as u32;
        }
        let r_sub = sub_local[states[r as usize] as usize] as usize;
        // A bottom component is one component of its own graph.
        let one = Components::new(Sccs {
            count: 1,
            component: vec![0; comp.len()],
        });
        let x = evaluate(model, rewards, &comp, &sub_local, policy, r_sub, &one)?;
        for &s in &comp {
            sub_local[s as usize] = u32::MAX;
        }
        let gain = x[r_sub];
        if best.is_none_or(|(b, _, _)| better(gain, b)) {
            best = Some((gain, c, r));
        }
    }
    let Some((_, c, r)) = best else {
        return Err(DecisionError::TimelessPolicy {
            marking: format!("{:?}", model.marking(states[0] as usize)),
        });
    };
    let mut target = vec![false; model.state_count()];
    for &v in &members[c] {
        target[states[v as usize] as usize] = true;
    }
    steer(model, &mecs.inside, states, &mut target, policy);
    Ok((
        r as usize,
        PolicyGraph::compute(states.len(), |v, out| g.successors(policy, v, out)),
    ))
}

/// Steers every state of `states` not in `target` towards it, almost surely: a backward
/// search over the choices flagged `inside`, each state taking a choice with a branch into
/// the states already steered (Markovian states have one choice, which then qualifies).
/// `target` grows to every state steered.
pub(super) fn steer(
    model: &DecisionModel,
    inside: &[bool],
    states: &[u32],
    target: &mut [bool],
    policy: &mut [u32],
) {
    // Predecessors (state, choice) of each state, over inside choices.
    let mut local = vec![u32::MAX; model.state_count()];
    for (i, &s) in states.iter().enumerate() {
        local[s as usize] = i as u32;
    }
    let mut start = vec![0u32; states.len() + 1];
    for &s in states {
        for c in model.choices(s as usize).filter(|&c| inside[c]) {
            for (t, _) in model.branches(c) {
                if local[t as usize] != u32::MAX {
                    start[local[t as usize] as usize + 1] += 1;
                }
            }
        }
    }
    for i in 0..states.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut pred = vec![(0u32, 0u32); start[states.len()] as usize];
    for &s in states {
        for c in model.choices(s as usize).filter(|&c| inside[c]) {
            for (t, _) in model.branches(c) {
                let l = local[t as usize];
                if l != u32::MAX {
                    pred[fill[l as usize] as usize] = (s, c as u32);
                    fill[l as usize] += 1;
                }
            }
        }
    }
    let mut queue: Vec<u32> = states
        .iter()
        .copied()
        .filter(|&s| target[s as usize])
        .collect();
    let mut head = 0;
    while head < queue.len() {
        let t = local[queue[head] as usize] as usize;
        head += 1;
        for &(s, c) in &pred[start[t] as usize..start[t + 1] as usize] {
            if !target[s as usize] {
                target[s as usize] = true;
                policy[s as usize] = c;
                queue.push(s);
            }
        }
    }
}

/// The gain and bias of the policy on `states` (closed under it), `h(reference) = 0`: the
/// local solution vector, whose entry `reference` is the gain. `comps`: the components of the
/// policy's graph on `states`.
///
/// The equations follow the policy's graph, so they are solved one strongly connected
/// component at a time. The reference's component — the one bottom component of a unichain
/// policy ([`make_unichain`]) — comes first: with `M` its rows and columns other than the
/// reference's, `M·u = b` (rewards) and `M·w = τ` (time: 1 in each Markovian row) give
/// `h = u − g·w` (expected reward and time to reach the reference), and the reference's own
/// row then gives `g` (solving for `g` as an unknown instead would put a dense column in the
/// system). Every other component follows sinks first, its equations taking the bias of the
/// states it leads to as known. Under the GSPNR models' policies the components have a few
/// states each, so a round costs about one pass over the chosen branches; a large component
/// is solved by sparse LU.
fn evaluate(
    model: &DecisionModel,
    rewards: &Rewards,
    states: &[u32],
    local: &[u32],
    policy: &[u32],
    reference: usize,
    comps: &Components,
) -> Result<Vec<f64>, DecisionError> {
    let k = states.len();
    let ev = Evaluation {
        model,
        rewards,
        states,
        local,
        policy,
        sccs: &comps.sccs,
        members: &comps.members,
        pos: &comps.pos,
    };
    // The bias (h(reference) = 0) and the gain.
    let mut h = vec![0.0f64; k];
    let rc = comps.sccs.component[reference] as usize;
    let g = ev.bottom(reference, &mut h)?;
    // The other components, sinks first: every branch leaving one leads to a component
    // numbered below it, already solved.
    let mut scratch = Scratch::default();
    for ci in (0..ev.members.len()).filter(|&ci| ci != rc) {
        ev.component(ci, g, &mut h, &mut scratch)?;
    }
    h[reference] = g;
    if h.iter().all(|v| v.is_finite()) {
        Ok(h)
    } else {
        Err(lu_failed(
            k,
            crate::analysis::linear::SolveError::Failed("singular matrix".into()),
        ))
    }
}

/// A policy evaluation's data: the MEC's states in local numbering, their components and
/// each one's position in its component.
struct Evaluation<'a> {
    model: &'a DecisionModel,
    rewards: &'a Rewards,
    states: &'a [u32],
    local: &'a [u32],
    policy: &'a [u32],
    sccs: &'a Sccs,
    members: &'a Members,
    /// Each local state's index in its component.
    pos: &'a [u32],
}

impl Evaluation<'_> {
    /// Local state `i`'s row: its scale, its time flag and right-hand side, and its choice.
    fn row(&self, i: usize) -> (f64, f64, f64, usize) {
        let (model, rewards) = (self.model, self.rewards);
        let s = self.states[i] as usize;
        let c = self.policy[s] as usize;
        match model.kind(s) {
            Kind::Instant => (1.0, 0.0, rewards.impulse[c], c),
            Kind::Markovian => {
                let e = model.exit_rate(s);
                (e, 1.0, rewards.rate[s] + e * rewards.impulse[c], c)
            }
            Kind::Dead => (1.0, 1.0, rewards.rate[s] + rewards.impulse[c], c),
        }
    }

    /// The reference's component: the bias of its states into `h` and the gain.
    fn bottom(&self, reference: usize, h: &mut [f64]) -> Result<f64, DecisionError> {
        let (pos, local) = (self.pos, self.local);
        let bottom = &self.members[self.sccs.component[reference] as usize];
        let rp = pos[reference] as usize;
        let at = |i: usize| if i > rp { i - 1 } else { i };
        let m = bottom.len() - 1;
        let mut triplets: Vec<(usize, usize, f64)> = Vec::new();
        let mut rhs = vec![0.0f64; 2 * m];
        // The reference's row: (unknown, coefficient), its right-hand side and time flag.
        let mut ref_row: Vec<(usize, f64)> = Vec::new();
        let (mut b_ref, mut tau_ref) = (0.0, 1.0);
        for (i, &v) in bottom.iter().enumerate() {
            let (scale, tau, b, c) = self.row(v as usize);
            if i == rp {
                (b_ref, tau_ref) = (b, tau);
            } else {
                triplets.push((at(i), at(i), scale));
                rhs[2 * at(i)] = b;
                rhs[2 * at(i) + 1] = tau;
            }
            for (t, p) in self.model.branches(c) {
                let j = local[t as usize] as usize;
                if j == reference {
                    continue;
                }
                let entry = (at(pos[j] as usize), -scale * p);
                if i == rp {
                    ref_row.push(entry);
                } else {
                    triplets.push((at(i), entry.0, entry.1));
                }
            }
        }
        solve_block(m, &triplets, &mut rhs, 2).map_err(|e| lu_failed(m, e))?;
        // The reference's row, h(reference) = 0: g·τ + Σ a_j·(u_j − g·w_j) = b.
        let (au, aw) = ref_row.iter().fold((0.0, 0.0), |(x, y), &(j, a)| {
            (x + a * rhs[2 * j], y + a * rhs[2 * j + 1])
        });
        let g = (b_ref - au) / (tau_ref - aw);
        for (i, &v) in bottom.iter().enumerate() {
            if i != rp {
                h[v as usize] = rhs[2 * at(i)] - g * rhs[2 * at(i) + 1];
            }
        }
        Ok(g)
    }

    /// Component `ci` (not the reference's) under gain `g`, the bias of the components it
    /// leads to already in `h`: its states' bias into `h`.
    fn component(
        &self,
        ci: usize,
        g: f64,
        h: &mut [f64],
        scratch: &mut Scratch,
    ) -> Result<(), DecisionError> {
        let comp = &self.members[ci];
        let Scratch { triplets, rhs } = scratch;
        triplets.clear();
        rhs.clear();
        rhs.resize(comp.len(), 0.0);
        for (i, &v) in comp.iter().enumerate() {
            let (scale, tau, b, c) = self.row(v as usize);
            let mut diag = scale;
            let mut r = b - tau * g;
            for (t, p) in self.model.branches(c) {
                let j = self.local[t as usize] as usize;
                if self.sccs.component[j] as usize == ci {
                    if self.pos[j] as usize == i {
                        diag -= scale * p;
                    } else {
                        triplets.push((i, self.pos[j] as usize, -scale * p));
                    }
                } else {
                    r += scale * p * h[j];
                }
            }
            triplets.push((i, i, diag));
            rhs[i] = r;
        }
        if let [v] = comp[..] {
            h[v as usize] = rhs[0] / triplets[triplets.len() - 1].2;
        } else {
            solve_block(comp.len(), triplets, rhs, 1).map_err(|e| lu_failed(comp.len(), e))?;
            for (i, &v) in comp.iter().enumerate() {
                h[v as usize] = rhs[i];
            }
        }
        Ok(())
    }
}

/// The buffers of one component's equations, kept from one component to the next (most
/// have a state or two).
#[derive(Default)]
struct Scratch {
    triplets: Vec<(usize, usize, f64)>,
    rhs: Vec<f64>,
}

/// A component's LU failed.
fn lu_failed(size: usize, e: crate::analysis::linear::SolveError) -> DecisionError {
    DecisionError::Unsupported(format!(
        "policy evaluation (LU of a component of {size} states): {e}"
    ))
}
