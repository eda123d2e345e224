//! Holding times of individual agents: how long each agent stayed in an action place before
//! a transition took it out, read from a journal's agent events (`agent_spawned`,
//! `action_started`, `fired` with its `consumed` and `produced` agents).
//!
//! **What the model predicts for a stay** ([`stay_model`]). A GSPN's tokens have no
//! identity; what it says about one token's stay comes from its server semantics, read as the
//! GSPN literature does: a transition with `k` servers serves `k` of its tokens at once, each
//! on its own exponential clock (infinite servers: every token). So an agent's stay in place
//! `p` is predicted when
//!
//! - `p` is a *race place*: every output transition is exponential and takes one token from
//!   `p` and nothing else (no other input, no inhibitor) — else whether it can leave depends
//!   on other places;
//! - every token in `p` is always being served: each output has infinite servers, or at least
//!   as many as the most tokens `p` holds in a tangible marking (its bound under the model) —
//!   else a token may wait for a server, and how long depends on the queue and on which token
//!   the net serves next, which a GSPN does not say.
//!
//! Then every stay, whatever the other tokens do, is exponential with rate `Λ` = the sum of
//! the outputs' rates, and leaves by output `t` with probability `λ_t / Λ`, independently of
//! its length. The `holding` rows test every stay against that (the mean by exit, the
//! distribution over all exits; see [`super::stats::stays_mean_test`]); other places' rows say
//! `no prediction` and why. No stay is selected by what happened during it (such as "the agent
//! was alone": short stays are more often alone, and that selection made runs of the model
//! diverge). A drive whose time physics sets is flagged there by the agent's own stays, not
//! only by a transition's enabled-time gaps.

use std::collections::HashMap;

use serde::Serialize;

use crate::net::{Net, PlaceId, Servers, Timing, TransitionId};
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
}

/// An agent in a place, not yet out.
#[derive(Debug)]
struct Stay {
    place: Option<PlaceId>,
    entry: Option<TransitionId>,
    entered: f64,
}

/// The stays of the agents of a journal's events (in event order). An agent produced by a
/// firing learns its place from the `action_started` that follows (an agent in a place
/// without output transitions never leaves and has none); agents spawned at the start
/// from their `agent_spawned`.
pub fn holdings(events: &[Event]) -> Vec<Holding> {
    let mut stays = Stays::default();
    for e in events {
        stays.see(e);
    }
    stays.into_holdings()
}

/// [`holdings`] one event at a time: the agents in a place and the stays that ended.
#[derive(Debug, Default)]
pub(crate) struct Stays {
    open: HashMap<AgentId, Stay>,
    ended: Vec<Holding>,
}

impl Stays {
    fn enter(&mut self, a: AgentId, p: PlaceId) {
        if let Some(s) = self.open.get_mut(&a)
            && s.place.is_none()
        {
            s.place = Some(p);
        }
    }

    /// Follows the agents through one event.
    pub(crate) fn see(&mut self, e: &Event) {
        match &e.kind {
            EventKind::AgentSpawned { agent, place, .. } => {
                self.open.entry(*agent).or_insert(Stay {
                    place: None,
                    entry: None,
                    entered: e.time,
                });
                self.enter(*agent, *place);
            }
            EventKind::ActionStarted {
                agent,
                place,
                attempt: 0,
            } => self.enter(*agent, *place),
            EventKind::Fired {
                transition,
                consumed,
                produced,
                ..
            } => {
                for a in consumed {
                    let Some(s) = self.open.remove(a) else {
                        continue;
                    };
                    let Some(p) = s.place else { continue };
                    self.ended.push(Holding {
                        agent: *a,
                        place: p,
                        transition: *transition,
                        entry: s.entry,
                        entered: s.entered,
                        duration: e.time - s.entered,
                    });
                }
                for a in produced {
                    self.open.insert(
                        *a,
                        Stay {
                            place: None,
                            entry: Some(*transition),
                            entered: e.time,
                        },
                    );
                }
            }
            _ => {}
        }
    }

    /// The stays that ended, in the order they ended.
    pub(crate) fn into_holdings(self) -> Vec<Holding> {
        self.ended
    }
}

/// What the model predicts for an agent's stay in a place (see the module).
#[derive(Clone, Debug, PartialEq)]
pub enum StayModel {
    /// Every stay is exponential with rate `rate` (`Λ`, the sum of the outputs' rates) and
    /// leaves by output `t` with probability `λ_t / Λ`, independently of its length.
    Exponential {
        /// `Λ`.
        rate: f64,
    },
    /// The model does not say how long a stay lasts.
    Unpredicted(Unpredicted),
}

/// Why the model predicts no stay in a place.
#[derive(Clone, Debug, PartialEq)]
pub enum Unpredicted {
    /// The place has no output transition: its agents never leave.
    NoOutput,
    /// An output is immediate: it fires when the rest of the net lets it.
    Immediate(TransitionId),
    /// An output takes more than one token from the place, takes from another place too, or
    /// has an inhibitor arc: whether it can fire depends on more than this token.
    NotARace(TransitionId),
    /// An output has `servers` servers and the place may hold more tokens (`bound`, `None`
    /// when no bound is known): a token may wait for a server.
    Queue {
        /// The output with the fewest servers.
        transition: TransitionId,
        /// Its servers.
        servers: u32,
        /// The most tokens in the place in a tangible marking, when known.
        bound: Option<u32>,
    },
}

impl Unpredicted {
    /// Why, in words, with the net's names.
    pub fn describe(&self, net: &Net) -> String {
        let name = |t: &TransitionId| net.transition(*t).name.as_str();
        match self {
            Unpredicted::NoOutput => "no output transition".into(),
            Unpredicted::Immediate(t) => format!("{} is immediate", name(t)),
            Unpredicted::NotARace(t) => format!(
                "{} needs more than this token (other inputs, a weight, an inhibitor)",
                name(t)
            ),
            Unpredicted::Queue {
                transition,
                servers,
                bound,
            } => {
                let servers = match servers {
                    1 => "a single server".to_string(),
                    k => format!("{k} servers"),
                };
                let tokens = match bound {
                    Some(b) => format!("up to {b} tokens"),
                    None => "no known bound on its tokens".into(),
                };
                format!(
                    "{} has {servers} and the place {tokens}: a stay depends on the queue",
                    name(transition)
                )
            }
        }
    }
}

/// What the model predicts for an agent's stay in `p` (see the module), given the most tokens
/// `p` holds in a tangible marking (`None` when unknown; only needed when an output has a
/// finite number of servers).
pub fn stay_model(net: &Net, p: PlaceId, bound: Option<u32>) -> StayModel {
    let outs = net.consumers(p);
    if outs.is_empty() {
        return StayModel::Unpredicted(Unpredicted::NoOutput);
    }
    let mut rate = 0.0;
    let mut fewest: Option<(TransitionId, u32)> = None;
    for &t in outs {
        let Timing::Exponential { rate: r, servers } = net.transition(t).timing else {
            return StayModel::Unpredicted(Unpredicted::Immediate(t));
        };
        if net.inputs(t) != [(p, 1)] || !net.inhibitors(t).is_empty() {
            return StayModel::Unpredicted(Unpredicted::NotARace(t));
        }
        rate += r;
        let k = match servers {
            Servers::Infinite => continue,
            Servers::Single => 1,
            Servers::K(k) => k,
        };
        if fewest.is_none_or(|(_, f)| k < f) {
            fewest = Some((t, k));
        }
    }
    match fewest {
        Some((transition, servers)) if bound.is_none_or(|b| b > servers) => {
            StayModel::Unpredicted(Unpredicted::Queue {
                transition,
                servers,
                bound,
            })
        }
        _ => StayModel::Exponential { rate },
    }
}

/// `Λ`, the total rate out of `p` when `p` is a race place (see the module; whatever its
/// servers), else `None`.
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
    fn stays_run_from_entering_to_the_firing_that_consumes_whoever_shares_the_place() {
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
        let got: Vec<(u64, u32, u32, Option<u32>, f64, f64)> = holdings(&events)
            .iter()
            .map(|h| {
                (
                    h.agent.0,
                    h.place.0,
                    h.transition.0,
                    h.entry.map(|t| t.0),
                    h.entered,
                    h.duration,
                )
            })
            .collect();
        assert_eq!(
            got,
            vec![
                (0, 0, 0, None, 0.0, 1.5),
                // A retry does not restart the stay.
                (0, 1, 1, Some(0), 1.5, 0.5),
                (1, 0, 0, None, 0.0, 2.25),
                (0, 0, 0, Some(1), 2.0, 2.0),
                (1, 1, 1, Some(0), 2.25, 1.75),
            ]
        );
        assert_eq!(race_rate(&net, pa), Some(1.0));
        assert_eq!(race_rate(&net, pb), Some(2.0));
    }

    /// A place `P` with `outs` (rate, servers) transitions to `Q`; `extra` adds an input
    /// from `Q` to the first one.
    fn place_with(outs: &[(f64, Servers)], extra: bool) -> (Net, PlaceId) {
        let mut b = NetBuilder::new("p");
        let (p, q) = (b.place("P", 3), b.place("Q", 0));
        for (i, &(rate, servers)) in outs.iter().enumerate() {
            let t = b.exponential(format!("t{i}"), rate, servers);
            b.moves(p, t, q);
            if extra && i == 0 {
                b.input(q, t, 1);
            }
        }
        let back = b.immediate("back", 1.0, 1);
        b.moves(q, back, p);
        (b.build().unwrap(), p)
    }

    #[test]
    fn a_stay_is_predicted_when_every_token_has_its_own_server() {
        let exp = |rate| StayModel::Exponential { rate };
        // Infinite servers: whatever the bound, even unknown.
        let (net, p) = place_with(&[(1.0, Servers::Infinite), (0.5, Servers::Infinite)], false);
        assert_eq!(stay_model(&net, p, None), exp(1.5));
        assert_eq!(stay_model(&net, p, Some(7)), exp(1.5));
        // Finite servers: only when the place never holds more tokens than the fewest.
        let (net, p) = place_with(&[(1.0, Servers::K(3)), (0.5, Servers::Infinite)], false);
        assert_eq!(stay_model(&net, p, Some(3)), exp(1.5));
        let (t0, t1) = (TransitionId(0), TransitionId(1));
        let queue = |transition, servers, bound| {
            StayModel::Unpredicted(Unpredicted::Queue {
                transition,
                servers,
                bound,
            })
        };
        assert_eq!(stay_model(&net, p, Some(4)), queue(t0, 3, Some(4)));
        assert_eq!(stay_model(&net, p, None), queue(t0, 3, None));
        let (net, p) = place_with(&[(1.0, Servers::K(2)), (0.5, Servers::Single)], false);
        assert_eq!(stay_model(&net, p, Some(1)), exp(1.5));
        assert_eq!(stay_model(&net, p, Some(2)), queue(t1, 1, Some(2)));
        let StayModel::Unpredicted(why) = stay_model(&net, p, Some(2)) else {
            unreachable!()
        };
        assert_eq!(
            why.describe(&net),
            "t1 has a single server and the place up to 2 tokens: a stay depends on the queue"
        );
        // An output that needs another place.
        let (net, p) = place_with(&[(1.0, Servers::Infinite)], true);
        assert_eq!(
            stay_model(&net, p, None),
            StayModel::Unpredicted(Unpredicted::NotARace(t0))
        );
        // Immediate outputs, no outputs.
        let (net, _) = place_with(&[(1.0, Servers::Infinite)], false);
        let q = net.place_by_name("Q").unwrap();
        let back = net.transition_by_name("back").unwrap();
        assert_eq!(
            stay_model(&net, q, Some(1)),
            StayModel::Unpredicted(Unpredicted::Immediate(back))
        );
        let mut b = NetBuilder::new("sink");
        let s = b.place("S", 1);
        let net = b.build().unwrap();
        assert_eq!(
            stay_model(&net, s, Some(1)),
            StayModel::Unpredicted(Unpredicted::NoOutput)
        );
    }
}
