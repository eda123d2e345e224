//! Elimination of vanishing markings: where each vanishing marking leads, as a probability
//! distribution over tangible states, and how often each immediate transition fires on the way.
//!
//! The vanishing markings are an absorbing chain whose exits are the tangible markings,
//! resolved by the one solver for loops of immediate transitions,
//! [`absorbing`](crate::analysis::absorbing): components sinks first, a loop by LU of `I − P`
//! (sparse above a few dozen markings). Every path is kept, so a loop tangible → vanishing →
//! the same tangible state keeps its probability. A component that no positive arc leaves is
//! a timeless trap.

use crate::analysis::absorbing::{Target, absorb};
use crate::analysis::state_space::explore::Raw;
use crate::analysis::state_space::table::MoveTable;
use crate::analysis::state_space::{AnalysisError, ImmediateFlow, Move};
use crate::net::{Net, TransitionId};

/// The tangible chain after elimination.
#[derive(Debug, Default)]
pub(crate) struct Eliminated {
    /// Moves of tangible states `0..T`, targets renumbered.
    pub(crate) moves: MoveTable,
    /// Expected immediate firings after each (state, exponential transition).
    pub(crate) flows: Vec<ImmediateFlow>,
    /// Initial distribution over tangible states.
    pub(crate) initial: Vec<(u32, f64)>,
}

/// Eliminates the vanishing markings of `raw`. `order[new] = raw id` lists tangible markings
/// first (`0..tangible`), `new_id` is its inverse.
pub(crate) fn eliminate(
    net: &Net,
    raw: &Raw,
    order: &[u32],
    new_id: &[u32],
    tangible: usize,
) -> Result<Eliminated, AnalysisError> {
    let vanishing = order.len() - tangible;
    let t_base = tangible as u32;
    let is_tangible = |raw_id: u32| raw.tangible[raw_id as usize];
    let local = |raw_id: u32| new_id[raw_id as usize] - t_base;
    let target = |raw_id: u32| {
        if is_tangible(raw_id) {
            Target::Out(new_id[raw_id as usize])
        } else {
            Target::In(local(raw_id))
        }
    };
    let group = |v: u32| raw.moves.group(order[tangible + v as usize] as usize);
    let absorbed = absorb(
        vanishing,
        |v, out| out.extend(group(v).iter().map(|m| (target(m.to), m.prob))),
        |v, out| {
            out.extend(
                group(v)
                    .iter()
                    .filter(|m| m.prob > 0.0)
                    .map(|m| (m.transition.0, m.prob)),
            )
        },
    )
    .map_err(|e| {
        e.into_analysis(|v| {
            let mut mk = vec![0u32; net.place_count()];
            raw.store
                .get(order[tangible + v as usize] as usize, &mut mk);
            net.format_marking(&mk)
        })
    })?;
    let (mut dist, flow) = (absorbed.dist, absorbed.counts);
    let mut out = Eliminated::default();
    let mut group: Vec<Move> = Vec::new();
    for (s, &r) in order[..tangible].iter().enumerate() {
        group.clear();
        for m in raw.moves.group(r as usize) {
            if is_tangible(m.to) {
                group.push(Move {
                    to: new_id[m.to as usize],
                    ..*m
                });
                continue;
            }
            let w = local(m.to) as usize;
            for &(to, prob) in &dist[w] {
                group.push(Move {
                    transition: m.transition,
                    rate: m.rate,
                    to,
                    prob,
                });
            }
            for &(i, expected) in &flow[w] {
                out.flows.push(ImmediateFlow {
                    state: s as u32,
                    transition: m.transition,
                    immediate: TransitionId(i),
                    expected,
                });
            }
        }
        out.moves.push_group(&group);
    }
    out.moves.shrink();
    out.initial = if is_tangible(0) {
        vec![(new_id[0], 1.0)]
    } else {
        std::mem::take(&mut dist[local(0) as usize])
    };
    Ok(out)
}
