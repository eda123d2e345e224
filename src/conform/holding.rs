//! Holding times of individual agents: how long each agent stayed in an action place before
//! a transition took it out, read from a journal's agent events (`agent_spawned`,
//! `action_started`, `fired` with its `consumed` and `produced` agents).
//!
//! A GSPN's tokens have no identity, so the model predicts an agent's holding time only when
//! the agent is alone in its place and the place is a *race place*: every output transition
//! is exponential and takes one token from this place and nothing else (no other input, no
//! inhibitor). Then the agent leaves after an exponential time of rate `Λ` = the sum of the
//! outputs' rates, by output `t` with probability `λ_t / Λ` (independent of the time). The
//! `holding` rows test the stays during which the agent was alone against that; the
//! `holding_shape` row tests their shape. A drive whose time physics sets is flagged there by
//! the agent's own stays, not only by a transition's enabled-time gaps.

use std::collections::HashMap;

use serde::Serialize;

use crate::net::{Net, PlaceId, Timing, TransitionId};
use crate::runtime::AgentId;
use crate::runtime::event::{Event, EventKind};

/// One agent's stay in an action place.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Holding {
    /// The agent.
    pub agent: AgentId,
    /// The place.
    pub place: PlaceId,
    /// The transition that took it out.
    pub transition: TransitionId,
    /// The transition that put it in (`None` for an agent spawned there at the start).
    pub entry: Option<TransitionId>,
    /// When it entered (model time).
    pub entered: f64,
    /// How long it stayed.
    pub duration: f64,
    /// True when no other token was in the place at any firing during the stay.
    pub alone: bool,
}

/// An agent in a place, not yet out.
struct Stay {
    place: Option<PlaceId>,
    entry: Option<TransitionId>,
    entered: f64,
    alone: bool,
}

/// The stays of the agents of a journal's events (in event order). An agent produced by a
/// firing learns its place from the `action_started` that follows (an agent in a place
/// without output transitions never leaves and has none); agents spawned at the start
/// from their `agent_spawned`.
pub fn holdings(net: &Net, events: &[Event]) -> Vec<Holding> {
    let mut stays: HashMap<AgentId, Stay> = HashMap::new();
    let mut by_place: Vec<Vec<AgentId>> = vec![Vec::new(); net.place_count()];
    let mut out = Vec::new();
    let enter = |stays: &mut HashMap<AgentId, Stay>,
                 by_place: &mut [Vec<AgentId>],
                 a: AgentId,
                 p: PlaceId| {
        if let Some(s) = stays.get_mut(&a)
            && s.place.is_none()
        {
            s.place = Some(p);
            let others = &mut by_place[p.index()];
            if !others.is_empty() {
                s.alone = false;
                for b in others.iter() {
                    if let Some(s) = stays.get_mut(b) {
                        s.alone = false;
                    }
                }
            }
            by_place[p.index()].push(a);
        }
    };
    for e in events {
        match &e.kind {
            EventKind::AgentSpawned { agent, place, .. } => {
                stays.entry(*agent).or_insert(Stay {
                    place: None,
                    entry: None,
                    entered: e.time,
                    alone: true,
                });
                enter(&mut stays, &mut by_place, *agent, *place);
            }
            EventKind::ActionStarted {
                agent,
                place,
                attempt: 0,
            } => enter(&mut stays, &mut by_place, *agent, *place),
            EventKind::Fired {
                transition,
                consumed,
                produced,
                marking,
                ..
            } => {
                for a in consumed {
                    let Some(s) = stays.remove(a) else { continue };
                    let Some(p) = s.place else { continue };
                    by_place[p.index()].retain(|b| b != a);
                    out.push(Holding {
                        agent: *a,
                        place: p,
                        transition: *transition,
                        entry: s.entry,
                        entered: s.entered,
                        duration: e.time - s.entered,
                        alone: s.alone,
                    });
                }
                for a in produced {
                    stays.insert(
                        *a,
                        Stay {
                            place: None,
                            entry: Some(*transition),
                            entered: e.time,
                            alone: true,
                        },
                    );
                }
                // A stay is crowded once another token shares its place at a firing.
                for (p, agents) in by_place.iter().enumerate() {
                    if !agents.is_empty() && marking.get(p).copied().unwrap_or(0) > 1 {
                        for a in agents {
                            if let Some(s) = stays.get_mut(a) {
                                s.alone = false;
                            }
                        }
                    }
                }
            }
            _ => {}
        }
    }
    out
}

/// `Λ`, the total rate out of `p` when `p` is a race place (see the module), else `None`.
pub fn race_rate(net: &Net, p: PlaceId) -> Option<f64> {
    let outs = net.consumers(p);
    if outs.is_empty() {
        return None;
    }
    outs.iter()
        .map(|&t| match net.transition(t).timing {
            Timing::Exponential { rate, .. }
                if net.inputs(t) == [(p, 1)] && net.inhibitors(t).is_empty() =>
            {
                Some(rate)
            }
            _ => None,
        })
        .sum()
}

/// The stays of one place, by exit transition (in net order).
pub(crate) type PlaceStays<'a> = (PlaceId, Vec<(TransitionId, Vec<&'a Holding>)>);

/// Stays grouped by place, then by exit transition, in net order.
pub(crate) fn by_place<'a>(net: &Net, holdings: &'a [Holding]) -> Vec<PlaceStays<'a>> {
    let mut v: Vec<Vec<Vec<&Holding>>> = net
        .place_ids()
        .map(|p| vec![Vec::new(); net.consumers(p).len()])
        .collect();
    for h in holdings {
        if let Some(k) = net
            .consumers(h.place)
            .iter()
            .position(|&t| t == h.transition)
        {
            v[h.place.index()][k].push(h);
        }
    }
    v.into_iter()
        .enumerate()
        .filter(|(_, outs)| outs.iter().any(|o| !o.is_empty()))
        .map(|(p, outs)| {
            let p = PlaceId(p as u32);
            let outs = net.consumers(p).iter().copied().zip(outs).collect();
            (p, outs)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{Marking, NetBuilder, Servers};

    fn ev(seq: u64, time: f64, kind: EventKind) -> Event {
        Event { seq, time, kind }
    }

    fn fired(t: u32, consumed: &[u64], produced: &[u64], marking: &[u32]) -> EventKind {
        EventKind::Fired {
            transition: TransitionId(t),
            consumed: consumed.iter().map(|&a| AgentId(a)).collect(),
            produced: produced.iter().map(|&a| AgentId(a)).collect(),
            marking: Marking::from(marking.to_vec()),
            robots: Vec::new(),
        }
    }

    fn started(a: u64, p: u32, attempt: u32) -> EventKind {
        EventKind::ActionStarted {
            agent: AgentId(a),
            place: PlaceId(p),
            attempt,
        }
    }

    #[test]
    fn stays_run_from_entering_to_the_firing_that_consumes_and_know_when_shared() {
        // A -go-> B -back-> A, two agents.
        let mut b = NetBuilder::new("two");
        let (pa, pb) = (b.place("A", 2), b.place("B", 0));
        let go = b.exponential("go", 1.0, Servers::Infinite);
        let back = b.exponential("back", 2.0, Servers::Infinite);
        b.input(pa, go, 1);
        b.output(go, pb, 1);
        b.input(pb, back, 1);
        b.output(back, pa, 1);
        let net = b.build().unwrap();
        let spawned = |a: u64| EventKind::AgentSpawned {
            agent: AgentId(a),
            place: pa,
            robot: None,
        };
        let events = vec![
            ev(0, 0.0, spawned(0)),
            ev(1, 0.0, spawned(1)),
            ev(2, 0.0, started(0, 0, 0)),
            ev(3, 0.0, started(1, 0, 0)),
            ev(4, 1.5, fired(0, &[0], &[0], &[1, 1])),
            ev(5, 1.5, started(0, 1, 0)),
            ev(6, 1.5, started(0, 1, 1)), // a retry keeps the stay
            ev(7, 2.0, fired(1, &[0], &[0], &[2, 0])),
            ev(8, 2.0, started(0, 0, 0)),
            ev(9, 2.25, fired(0, &[1], &[1], &[1, 1])),
            ev(10, 2.25, started(1, 1, 0)),
            ev(11, 4.0, fired(0, &[0], &[0], &[0, 2])),
            ev(12, 4.0, started(0, 1, 0)),
            ev(13, 4.0, fired(1, &[1], &[1], &[1, 1])),
            ev(14, 4.0, started(1, 0, 0)),
        ];
        let h = holdings(&net, &events);
        let got: Vec<(u64, u32, u32, f64, f64, bool)> = h
            .iter()
            .map(|h| {
                (
                    h.agent.0,
                    h.place.0,
                    h.transition.0,
                    h.entered,
                    h.duration,
                    h.alone,
                )
            })
            .collect();
        assert_eq!(
            got,
            vec![
                // Both agents start in A: shared.
                (0, 0, 0, 0.0, 1.5, false),
                // Agent 0 alone in B (a retry does not restart the stay).
                (0, 1, 1, 1.5, 0.5, true),
                (1, 0, 0, 0.0, 2.25, false),
                // Agent 0 came back to A while agent 1 was still there.
                (0, 0, 0, 2.0, 2.0, false),
                // Agent 1 in B, joined by agent 0 at 4.0.
                (1, 1, 1, 2.25, 1.75, false),
            ]
        );
        assert_eq!(race_rate(&net, pa), Some(1.0));
        assert_eq!(race_rate(&net, pb), Some(2.0));
    }
}
