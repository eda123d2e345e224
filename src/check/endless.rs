//! Whether a run of a net can end on its own: [`ending`]. A run with no stop condition ends
//! only when nothing can fire any more; this says whether that can be counted on, from the
//! coverability and reachability analysis (bounded by a budget of markings, so it is quick
//! or silent):
//!
//! - [`Ending::Unbounded`]: places that grow without limit (Karp–Miller), each with the
//!   transitions that pump it (put more tokens in than they take out);
//! - [`Ending::Endless`]: the reachable markings hold a closed loop (a bottom strongly
//!   connected component that is not a dead marking): a run that enters it never ends;
//!   `dead_reachable` says whether some runs can end anyway;
//! - [`Ending::Ends`]: every run ends in a dead marking (with probability 1);
//! - [`Ending::Unknown`]: more markings than the budget.
//!
//! ```
//! use gspn::check::endless::{Ending, ending};
//! use gspn::net::{NetBuilder, Servers};
//! let mut b = NetBuilder::new("ping");
//! let a = b.place("a", 1);
//! let c = b.place("c", 0);
//! let go = b.exponential("go", 1.0, Servers::Single);
//! let back = b.exponential("back", 1.0, Servers::Single);
//! b.input(a, go, 1);
//! b.output(go, c, 1);
//! b.input(c, back, 1);
//! b.output(back, a, 1);
//! let net = b.build().unwrap();
//! assert_eq!(ending(&net, 1000), Ending::Endless { dead_reachable: false });
//! ```

use crate::analysis::scc::tarjan;
use crate::analysis::state_space::{AnalysisError, Options, StateSpace};
use crate::net::{Net, PlaceId, TransitionId};

/// Whether runs of a net end on their own; see the [module docs](self).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Ending {
    /// Every run reaches a dead marking (with probability 1).
    Ends,
    /// Some runs never end: a closed loop of markings is reachable.
    Endless {
        /// Some runs may still end, in a reachable dead marking.
        dead_reachable: bool,
    },
    /// These places can grow without limit, each with the transitions that pump it.
    Unbounded(Vec<(PlaceId, Vec<TransitionId>)>),
    /// The analysis could not tell within its budget.
    Unknown,
}

impl Ending {
    /// True when some run of the net can go on forever.
    pub fn can_run_forever(&self) -> bool {
        matches!(self, Ending::Endless { .. } | Ending::Unbounded(_))
    }

    /// One sentence for a warning, naming places and transitions; `None` for
    /// [`Ending::Ends`] and [`Ending::Unknown`].
    pub fn describe(&self, net: &Net) -> Option<String> {
        match self {
            Ending::Ends | Ending::Unknown => None,
            Ending::Endless {
                dead_reachable: false,
            } => Some("no dead marking is reachable: the net never stops firing".into()),
            Ending::Endless {
                dead_reachable: true,
            } => Some("a closed loop of markings is reachable: some runs never stop firing".into()),
            Ending::Unbounded(places) => Some(
                per_place(net, places, |p, by| {
                    format!("place `{p}` is unbounded (pumped by {by})")
                })
                .join("; "),
            ),
        }
    }
}

/// One warning per unbounded place, naming the transitions that pump it.
pub fn unbounded_warnings(net: &Net, ending: &Ending) -> Vec<String> {
    let Ending::Unbounded(places) = ending else {
        return Vec::new();
    };
    per_place(net, places, |p, by| {
        format!("place `{p}` can grow without limit (coverability): pumped by {by}")
    })
}

/// `say(place name, its pumps by name)` for each unbounded place.
fn per_place(
    net: &Net,
    places: &[(PlaceId, Vec<TransitionId>)],
    say: impl Fn(&str, String) -> String,
) -> Vec<String> {
    places
        .iter()
        .map(|(p, ts)| say(&net.place(*p).name, named(net, ts)))
        .collect()
}

/// Transitions by name, quoted: "`a`, `b`".
fn named(net: &Net, ts: &[TransitionId]) -> String {
    ts.iter()
        .map(|&t| format!("`{}`", net.transition(t).name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The transitions that put more tokens into `p` than they take out of it.
pub fn pumps(net: &Net, p: PlaceId) -> Vec<TransitionId> {
    net.transition_ids()
        .filter(|&t| {
            let weight = |arcs: &[(PlaceId, u32)]| -> u64 {
                arcs.iter()
                    .filter(|&&(q, _)| q == p)
                    .map(|&(_, w)| u64::from(w))
                    .sum()
            };
            weight(net.outputs(t)) > weight(net.inputs(t))
        })
        .collect()
}

/// Whether runs of `net` end on their own, searching at most `max_states` markings (one
/// thread, at most 256 MiB).
pub fn ending(net: &Net, max_states: usize) -> Ending {
    let opts = Options {
        max_states,
        threads: 1,
        max_memory: 256 << 20,
        monitor: None,
    };
    let ss = match StateSpace::build(net, &opts) {
        Ok(ss) => ss,
        Err(AnalysisError::Unbounded { places }) => {
            return Ending::Unbounded(
                places
                    .iter()
                    .filter_map(|name| net.place_by_name(name))
                    .map(|p| (p, pumps(net, p)))
                    .collect(),
            );
        }
        Err(_) => return Ending::Unknown,
    };
    let n = ss.reachable_count();
    let successors = |v: u32, out: &mut Vec<u32>| {
        out.extend(ss.successors(v as usize).map(|(_, to)| to));
    };
    let sccs = tarjan(n, successors);
    let bottom = sccs.bottom(successors);
    let endless =
        (0..n).any(|g| bottom[sccs.component[g] as usize] && ss.successors(g).next().is_some());
    if endless {
        Ending::Endless {
            dead_reachable: !ss.dead_states().is_empty(),
        }
    } else {
        Ending::Ends
    }
}
