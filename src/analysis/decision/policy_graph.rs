//! The strongly connected components of a policy's graph inside one MEC, kept from one round
//! of policy iteration to the next.
//!
//! A round switches the choice of some instant states; every other state keeps its edges.
//! Recomputing the components from scratch each round (Tarjan over every state, then the
//! bottom flags and the member lists) was about a third of the synthesis time of the home
//! model at 12 robots (issue 33's profile: `tarjan` 25 %, its successor function 8 %), all
//! of it dependent random reads. [`PolicyGraph::update`] looks only at the switched states:
//!
//! - a new edge into a component numbered higher than its source's could close a cycle
//!   through other components (a merge): then the caller recomputes from scratch;
//! - otherwise the numbering stays a reverse topological order, and only the components
//!   holding a switched state can change: each one with several states is searched again on
//!   its own edges (Tarjan over its members) and, when it splits, its pieces take its place
//!   in the numbering, sinks first; the bottom flags of those components are recomputed.
//!
//! The components found are the same sets as a fresh search's, and within each one the
//! states are in increasing order (as [`Sccs::members`] lists them), so the evaluation that
//! follows solves the same equations in the same order: the answers are unchanged.

use super::DecisionModel;
use crate::analysis::scc::{Members, Sccs, tarjan};

/// Components of the policy's graph, numbered sinks first, with their member lists and each
/// state's position in its component.
pub(super) struct Components {
    pub(super) sccs: Sccs,
    pub(super) members: Members,
    /// Local state → its index in its component's member list.
    pub(super) pos: Vec<u32>,
}

impl Components {
    pub(super) fn new(sccs: Sccs) -> Components {
        let members = sccs.members();
        let mut pos = vec![0u32; sccs.component.len()];
        for comp in &members {
            for (i, &v) in comp.iter().enumerate() {
                pos[v as usize] = i as u32;
            }
        }
        Components { sccs, members, pos }
    }

    /// States in the largest component.
    pub(super) fn largest(&self) -> usize {
        self.members.iter().map(<[u32]>::len).max().unwrap_or(0)
    }
}

/// A policy's graph on the states of one MEC (local numbering): `states[v]` is local state
/// `v`'s global id, `local` the inverse (`u32::MAX` outside).
#[derive(Clone, Copy)]
pub(super) struct Graph<'a> {
    pub(super) model: &'a DecisionModel,
    pub(super) states: &'a [u32],
    pub(super) local: &'a [u32],
}

impl Graph<'_> {
    /// The local successors of local state `v` under `policy`.
    pub(super) fn successors(&self, policy: &[u32], v: u32, out: &mut Vec<u32>) {
        let s = self.states[v as usize] as usize;
        out.extend(
            self.model
                .branches(policy[s] as usize)
                .filter(|&(_, p)| p > 0.0)
                .map(|(t, _)| self.local[t as usize]),
        );
    }
}

/// The components of a policy's graph and which of them are bottom components.
pub(super) struct PolicyGraph {
    pub(super) comps: Components,
    /// Per component: no edge leaves it.
    pub(super) bottom: Vec<bool>,
    /// Computed from scratch ([`PolicyGraph::compute`]), not updated since: numbered as
    /// Tarjan numbers a fresh search.
    pub(super) fresh: bool,
}

impl PolicyGraph {
    /// The components from scratch (Tarjan over every state) of the graph on `0..n` whose
    /// `successors(v, out)` appends `v`'s successors to `out`.
    pub(super) fn compute(n: usize, mut successors: impl FnMut(u32, &mut Vec<u32>)) -> Self {
        let sccs = tarjan(n, &mut successors);
        let bottom = sccs.bottom(successors);
        PolicyGraph {
            comps: Components::new(sccs),
            bottom,
            fresh: true,
        }
    }

    /// Brings the components up to date after the states `switched` changed their edges;
    /// `successors` gives the new graph (see the module's documentation). Returns `false`,
    /// leaving `self` untouched, when a component may have merged with others: the caller
    /// then computes the graph again.
    pub(super) fn update(
        &mut self,
        mut successors: impl FnMut(u32, &mut Vec<u32>),
        switched: &[u32],
    ) -> bool {
        let component = &self.comps.sccs.component;
        let mut out = Vec::new();
        for &v in switched {
            out.clear();
            successors(v, &mut out);
            let c = component[v as usize];
            if out.iter().any(|&w| component[w as usize] > c) {
                return false;
            }
        }
        self.fresh = false;
        let mut affected: Vec<u32> = switched.iter().map(|&v| component[v as usize]).collect();
        affected.sort_unstable();
        affected.dedup();
        // Components with several states may have lost an edge that held them together.
        let mut splits: Vec<(u32, Sccs)> = Vec::new();
        for &c in &affected {
            let members = &self.comps.members[c as usize];
            if members.len() < 2 {
                continue;
            }
            let (pos, component) = (&self.comps.pos, &self.comps.sccs.component);
            let inner = tarjan(members.len(), |i, out| {
                let start = out.len();
                successors(members[i as usize], out);
                let mut keep = start;
                for j in start..out.len() {
                    let w = out[j] as usize;
                    if component[w] == c {
                        out[keep] = pos[w];
                        keep += 1;
                    }
                }
                out.truncate(keep);
            });
            if inner.count > 1 {
                splits.push((c, inner));
            }
        }
        if !splits.is_empty() {
            // The affected components' new numbers, every piece of a split one.
            let first = self.renumber(&splits);
            affected = affected
                .iter()
                .flat_map(|&c| first[c as usize]..first[c as usize + 1])
                .collect();
        }
        for &c in &affected {
            self.bottom[c as usize] = self.is_bottom(&mut successors, c);
        }
        true
    }

    /// Whether no edge leaves component `c`.
    fn is_bottom(&self, successors: &mut impl FnMut(u32, &mut Vec<u32>), c: u32) -> bool {
        let component = &self.comps.sccs.component;
        let mut out = Vec::new();
        self.comps.members[c as usize].iter().all(|&v| {
            out.clear();
            successors(v, &mut out);
            out.iter().all(|&w| component[w as usize] == c)
        })
    }

    /// The first new number of each old component: old `c` becomes `first[c]` (and its
    /// pieces `first[c]..first[c + 1]` when it split).
    fn first_numbers(count: usize, splits: &[(u32, Sccs)]) -> Vec<u32> {
        let mut extra = vec![0u32; count];
        for (c, inner) in splits {
            extra[*c as usize] = inner.count as u32 - 1;
        }
        let mut first = Vec::with_capacity(count + 1);
        let mut next = 0u32;
        for e in extra {
            first.push(next);
            next += 1 + e;
        }
        first.push(next);
        first
    }

    /// Splits components in place: each `(c, inner)` replaces component `c` by the
    /// components of its own graph (`inner`, over its members' positions), numbered sinks
    /// first where `c` was. Every edge still runs from a higher number to a lower one.
    /// Returns where each old component went ([`Self::first_numbers`]).
    fn renumber(&mut self, splits: &[(u32, Sccs)]) -> Vec<u32> {
        let count = self.comps.sccs.count;
        let first = Self::first_numbers(count, splits);
        let mut inner_of: Vec<Option<&Sccs>> = vec![None; count];
        for (c, inner) in splits {
            inner_of[*c as usize] = Some(inner);
        }
        let Components { sccs, pos, .. } = &self.comps;
        let component: Vec<u32> = sccs
            .component
            .iter()
            .zip(pos)
            .map(|(&c, &p)| {
                let base = first[c as usize];
                match inner_of[c as usize] {
                    Some(inner) => base + inner.component[p as usize],
                    None => base,
                }
            })
            .collect();
        let mut bottom = vec![false; first[count] as usize];
        for (c, &b) in self.bottom.iter().enumerate() {
            bottom[first[c] as usize] = b;
        }
        self.bottom = bottom;
        self.comps = Components::new(Sccs {
            count: first[count] as usize,
            component,
        });
        first
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small xorshift: deterministic graphs without a crate.
    struct Rng(u64);

    impl Rng {
        fn below(&mut self, n: u64) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0 % n
        }
    }

    /// The components as sets (each vertex's fellow members), the bottom flag of each
    /// vertex's component, and whether every edge runs to a lower or equal number.
    fn shape(pg: &PolicyGraph, edges: &[Vec<u32>]) -> (Vec<Vec<u32>>, Vec<bool>, bool) {
        let c = &pg.comps.sccs.component;
        let sets = (0..edges.len())
            .map(|v| pg.comps.members[c[v] as usize].to_vec())
            .collect();
        let bottom = (0..edges.len()).map(|v| pg.bottom[c[v] as usize]).collect();
        let ordered = edges
            .iter()
            .enumerate()
            .all(|(v, out)| out.iter().all(|&w| c[w as usize] <= c[v]));
        (sets, bottom, ordered)
    }

    /// Random sparse graphs whose vertices switch their edges a few at a time, as a policy's
    /// do: the updated components are a fresh search's, sets and bottom flags, and stay in
    /// reverse topological order; merges are refused (then the caller recomputes).
    #[test]
    fn updates_find_the_components_a_fresh_search_finds() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let (mut updated, mut refused, mut split) = (0, 0, 0);
        for _ in 0..200 {
            let n = 2 + rng.below(40) as usize;
            let mut edges: Vec<Vec<u32>> = (0..n)
                .map(|_| {
                    (0..1 + rng.below(2))
                        .map(|_| rng.below(n as u64) as u32)
                        .collect()
                })
                .collect();
            let mut pg = PolicyGraph::compute(n, |v, out| out.extend(&edges[v as usize]));
            for _ in 0..10 {
                let switched: Vec<u32> = (0..1 + rng.below(3))
                    .map(|_| rng.below(n as u64) as u32)
                    .collect();
                for &v in &switched {
                    edges[v as usize] = (0..1 + rng.below(2))
                        .map(|_| rng.below(n as u64) as u32)
                        .collect();
                }
                let before = pg.comps.sccs.count;
                let fresh = PolicyGraph::compute(n, |v, out| out.extend(&edges[v as usize]));
                if pg.update(|v, out| out.extend(&edges[v as usize]), &switched) {
                    updated += 1;
                    split += usize::from(pg.comps.sccs.count > before);
                    let (sets, bottom, ordered) = shape(&pg, &edges);
                    let (fresh_sets, fresh_bottom, _) = shape(&fresh, &edges);
                    assert_eq!(sets, fresh_sets);
                    assert_eq!(bottom, fresh_bottom);
                    assert!(ordered);
                    assert_eq!(pg.comps.sccs.count, fresh.comps.sccs.count);
                } else {
                    refused += 1;
                    pg = fresh;
                }
            }
        }
        // Every case was met: updates in place, splits, and refused merges.
        assert!(
            updated > 500 && split > 20 && refused > 100,
            "{updated} {split} {refused}"
        );
    }
}
