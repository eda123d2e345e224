//! The journal: every event of a run as JSON Lines, after a header line with the net's
//! identity and the seed (enough for a later `plan-runner replay`).
//!
//! The supervisor hands every event, serialised, to a writer thread as it happens, so the
//! journal never misses an event and never blocks the run on the disk. The writer thread
//! holds at most [`FLUSH_EVENTS`] events or 25 ms of them before it writes them to the file
//! (so each is there within the [`FLUSH_AFTER`] bound, the thread's wake-up on a loaded
//! machine included), and flushes (and syncs) when the run stops, whatever stopped it. After a
//! `SIGKILL` the file holds every event up to the last write, with at most one line cut
//! short at the end, which `replay` skips with a warning (see docs/reliability.md).
//!
//! Besides the events, a backend can add *side records* through a [`JournalTap`]
//! ([`RuntimeHandle::journal_tap`](super::RuntimeHandle::journal_tap)): lines
//! `{"record": KIND, "time": t, "data": …}` that are not events (the simulated world writes
//! its map once and the robots' poses at the viewer's rate, so `replay --web` draws the
//! map). [`read_recording`] gives them back apart from the events; a journal without them
//! (every journal written before them) reads as before.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

mod lines;
mod writer;

pub(crate) use lines::entry;
pub use lines::{Entry, JournalReader};
pub use writer::{FLUSH_AFTER, FLUSH_EVENTS, HANDOVERS_ENV, JournalTap};
pub(crate) use writer::{Journal, RunFacts};

use super::event::Event;
use crate::net::{ArcKind, Net, Servers, Timing};
use crate::sample::fnv::Fnv;

/// The identity of a net: a 64-bit FNV-1a hash of its places (name, initial marking,
/// capacity), transitions (name, timing) and arcs, written as 16 hex digits.
///
/// Every enum goes in as an explicit tag ([`timing_tag`], [`servers_tag`], [`arc_tag`]),
/// never as a derived `Debug` text or a declaration-order discriminant, so renaming or
/// reordering a variant cannot silently orphan every saved journal. The tags are the bytes
/// the hash was fed before it had them (`0`/`1` for the timings, `"Single"`, `"Infinite"`,
/// `"K(k)"` for the servers, `0`/`1`/`2` for the arcs), so journals written then still
/// match; the tests pin one net per variant.
pub fn net_hash(net: &Net) -> String {
    let mut h = Fnv::new();
    for p in net.places() {
        h.str(&p.name);
        h.u64(p.initial as u64);
        h.u64(p.capacity.map_or(u64::MAX, |c| c as u64));
    }
    for t in net.transitions() {
        h.str(&t.name);
        h.u64(timing_tag(&t.timing));
        match t.timing {
            Timing::Immediate { weight, priority } => {
                h.u64(weight.to_bits());
                h.u64(priority as u64);
            }
            Timing::Exponential { rate, servers } => {
                h.u64(rate.to_bits());
                h.str(&servers_tag(servers));
            }
        }
    }
    for a in net.arcs() {
        h.u64(arc_tag(a.kind));
        h.u64(a.place.0 as u64);
        h.u64(a.transition.0 as u64);
        h.u64(a.weight as u64);
    }
    format!("{:016x}", h.finish())
}

/// The hash's tag of a timing.
fn timing_tag(t: &Timing) -> u64 {
    match t {
        Timing::Immediate { .. } => 0,
        Timing::Exponential { .. } => 1,
    }
}

/// The hash's tag of a server policy (the text `{:?}` gave when the hash took that).
fn servers_tag(s: Servers) -> std::borrow::Cow<'static, str> {
    match s {
        Servers::Single => "Single".into(),
        Servers::Infinite => "Infinite".into(),
        Servers::K(k) => format!("K({k})").into(),
    }
}

/// The hash's tag of an arc kind.
fn arc_tag(k: ArcKind) -> u64 {
    match k {
        ArcKind::Input => 0,
        ArcKind::Output => 1,
        ArcKind::Inhibitor => 2,
    }
}

/// The first line of a journal.
#[derive(Debug, Serialize, Deserialize)]
pub struct JournalHeader<'a> {
    /// The net's name.
    #[serde(borrow)]
    pub net: std::borrow::Cow<'a, str>,
    /// [`net_hash`].
    pub hash: String,
    /// The seed of the run.
    pub seed: u64,
    /// The time scale (0 = virtual time).
    pub time_scale: f64,
    /// Place names, by id (events carry ids).
    #[serde(borrow)]
    pub places: Vec<std::borrow::Cow<'a, str>>,
    /// Transition names, by id.
    #[serde(borrow)]
    pub transitions: Vec<std::borrow::Cow<'a, str>>,
    /// The file the run's net (or plan) was read from, when the run was told
    /// ([`RuntimeBuilder::source`](super::RuntimeBuilder::source)).
    #[serde(default, borrow, skip_serializing_if = "Option::is_none")]
    pub file: Option<std::borrow::Cow<'a, str>>,
    /// The robots bound to the initial agents, in agent order (their number is the run's
    /// robot count; empty without robots).
    #[serde(default, borrow, skip_serializing_if = "Vec::is_empty")]
    pub robots: Vec<std::borrow::Cow<'a, str>>,
    /// The marking the run started from. It is part of [`hash`](Self::hash); written so a
    /// run whose initial marking was not its file's (`--robots N` scales the robots' tokens)
    /// is still recognised as a run of that file's net.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial: Option<Vec<u32>>,
}

impl JournalHeader<'_> {
    /// Checks the header against `net`: `None` when the journal is of `net` as it is,
    /// `net` with the header's initial marking when the run started from that one (`run
    /// --robots N`), [`JournalError::OtherNet`] when it is of neither.
    pub fn net_that_ran(&self, net: &Net) -> Result<Option<Net>, JournalError> {
        let expected = net_hash(net);
        if self.hash == expected {
            return Ok(None);
        }
        let mut initial_differs = false;
        if let Some(m) = &self.initial
            && m.len() == net.place_count()
            && m.as_slice() != net.initial_marking().as_slice()
        {
            initial_differs = true;
            if let Some(ran) = net
                .with_initial_marking(m)
                .ok()
                .filter(|n| net_hash(n) == self.hash)
            {
                return Ok(Some(ran));
            }
        }
        Err(JournalError::OtherNet {
            journal: self.net.to_string(),
            journal_file: self.file.as_ref().map(|f| f.to_string()),
            hash: self.hash.clone(),
            net: net.name().to_string(),
            expected,
            initial_differs,
        })
    }
}

/// A side record of a journal: written by a [`JournalTap`], read by [`read_recording`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record<D = serde_json::Value> {
    /// What it records (`world`, `map`, …).
    pub record: Arc<str>,
    /// Model time (seconds).
    pub time: f64,
    /// The record itself.
    #[serde(default)]
    pub data: D,
}

/// The marking at one point of a recorded run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Frame {
    /// Model time.
    pub time: f64,
    /// The transition that fired to get here (`None` for the initial marking).
    pub transition: Option<String>,
    /// Tokens per place.
    pub tokens: Vec<u32>,
}

/// A journal that does not belong to the net, or a line that cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum JournalError {
    /// A line is not the JSON the journal writes.
    #[error("line {line}: {reason}")]
    BadLine {
        /// 1-based line number.
        line: usize,
        /// What was wrong.
        reason: String,
    },
    /// The header names another net.
    #[error(
        "the journal is of net `{journal}`{} (hash {hash}), not of this net `{net}` (hash {expected}){}",
        journal_file.as_deref().map(|f| format!(" from {f}")).unwrap_or_default(),
        if *initial_differs { " even with the journal's initial marking" } else { "" }
    )]
    OtherNet {
        /// The journal's net name.
        journal: String,
        /// The file the journal's run read its net from, when the header says.
        journal_file: Option<String>,
        /// The journal's net hash.
        hash: String,
        /// This net's name.
        net: String,
        /// This net's hash.
        expected: String,
        /// The header has an initial marking of this net's size, other than this net's,
        /// and this net with it still hashes differently.
        initial_differs: bool,
    },
}

/// A journal read back by [`read_recording`].
#[derive(Clone, Debug)]
pub struct Recording {
    /// The net as it ran: the net given, or — for a run that started from another marking
    /// (`plan-runner run --robots N` scales the robots' initial tokens) — that net with the
    /// journal's initial marking.
    pub net: Net,
    /// True when [`net`](Self::net) has the journal's initial marking instead of the given
    /// net's.
    pub remarked: bool,
    /// The file the run read its net from, when the header says.
    pub file: Option<String>,
    /// The robots bound to the initial agents (empty without robots).
    pub robots: Vec<String>,
    /// The events, in order.
    pub events: Vec<Event>,
    /// The side records ([`JournalTap::record`]), in order.
    pub records: Vec<Record>,
}

/// Reads a journal (JSON Lines: a header, then one [`Event`] or side [`Record`] per line) of
/// a run of `net`, checked against the net: the header's hash (of `net`, or of `net` with
/// the header's initial marking), every transition id and marking.
pub fn read_recording(text: &str, net: &Net) -> Result<Recording, JournalError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let bad = |i: usize, reason: String| JournalError::BadLine {
        line: i + 1,
        reason,
    };
    let Some((i, first)) = lines.next() else {
        return Err(bad(0, "empty journal: no header".into()));
    };
    let header: JournalHeader<'_> =
        serde_json::from_str(first).map_err(|e| bad(i, e.to_string()))?;
    let ran = header.net_that_ran(net)?;
    let remarked = ran.is_some();
    let mut events = Vec::new();
    let mut records = Vec::new();
    for (i, l) in lines {
        match lines::entry(l, net).map_err(|reason| bad(i, reason.to_string()))? {
            Entry::Event(e) => events.push(e),
            Entry::Record(r) => records.push(r),
        }
    }
    Ok(Recording {
        net: ran.unwrap_or_else(|| net.clone()),
        remarked,
        file: header.file.map(|f| f.into_owned()),
        robots: header.robots.iter().map(|r| r.to_string()).collect(),
        events,
        records,
    })
}

/// Reads a journal of a run of `net`: its events ([`read_recording`] without the side
/// records).
pub fn read_events(text: &str, net: &Net) -> Result<Vec<Event>, JournalError> {
    read_recording(text, net).map(|r| r.events)
}

/// Reads a journal of a run of `net` into frames: the initial marking, then the marking
/// after each firing ([`read_recording`], [`Recording::frames`]).
pub fn read_journal(text: &str, net: &Net) -> Result<Vec<Frame>, JournalError> {
    read_recording(text, net).map(|r| r.frames())
}

impl Recording {
    /// The initial marking (the run's), then the marking after each firing.
    pub fn frames(&self) -> Vec<Frame> {
        let mut frames = vec![Frame {
            time: 0.0,
            transition: None,
            tokens: self.net.initial_marking().into_vec(),
        }];
        frames.extend(self.events.iter().filter_map(Event::firing).map(|f| Frame {
            time: f.time,
            transition: Some(self.net.transition(f.transition).name.clone()),
            tokens: f.marking.to_vec(),
        }));
        frames
    }

    /// The side records of one kind, in order.
    pub fn records<'a>(&'a self, kind: &'a str) -> impl Iterator<Item = &'a Record> + 'a {
        self.records.iter().filter(move |r| &*r.record == kind)
    }
}

/// The journal of a killed run, read back: a last line cut short — no newline after it and
/// not valid JSON, what a `SIGKILL` in the middle of a write leaves — is split off and
/// reported as a [`JournalError::BadLine`] (a warning for `plan-runner replay`), so the rest
/// reads with [`read_journal`]. Any other bad line is still an error there.
pub fn split_torn(text: &str) -> (&str, Option<JournalError>) {
    if !text.ends_with('\n')
        && let Some(start) = text.rfind('\n').map(|i| i + 1)
        && !text[start..].trim().is_empty()
        && let Err(e) = serde_json::from_str::<serde_json::Value>(&text[start..])
    {
        let torn = JournalError::BadLine {
            line: text.lines().count(),
            reason: format!("cut short ({e})"),
        };
        return (&text[..start], Some(torn));
    }
    (text, None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::NetBuilder;

    /// `P(1) → T → Q(0, capacity 2)` with `T` timed as given, plus an inhibitor `Q —o T`
    /// of weight 2 when asked.
    fn net(timing: Timing, inhibitor: bool) -> Net {
        let mut b = NetBuilder::new("n");
        let p = b.place("P", 1);
        let q = b.place_with_capacity("Q", 0, Some(2));
        let t = b.add_transition(crate::net::Transition {
            name: "T".into(),
            timing,
            position: None,
        });
        b.input(p, t, 1);
        b.output(t, q, 1);
        if inhibitor {
            b.inhibitor(q, t, 2);
        }
        b.build().unwrap()
    }

    // The hashes below were computed outside the crate (an FNV-1a over the bytes the hash
    // was fed when it used `{:?}` and `as u64`); a change here orphans saved journals.

    #[test]
    fn hash_of_an_immediate_transition_with_input_and_output_arcs_is_pinned() {
        let timing = Timing::Immediate {
            weight: 2.5,
            priority: 3,
        };
        assert_eq!(net_hash(&net(timing, false)), "3f5e168200c7f0df");
    }

    #[test]
    fn hash_of_a_single_server_with_an_inhibitor_arc_is_pinned() {
        let timing = Timing::Exponential {
            rate: 1.5,
            servers: Servers::Single,
        };
        assert_eq!(net_hash(&net(timing, true)), "4663924657a906c3");
    }

    #[test]
    fn hash_of_an_infinite_server_is_pinned() {
        let timing = Timing::Exponential {
            rate: 1.5,
            servers: Servers::Infinite,
        };
        assert_eq!(net_hash(&net(timing, false)), "717c7a63b8d8c76c");
    }

    #[test]
    fn hash_of_k_servers_is_pinned() {
        let timing = Timing::Exponential {
            rate: 1.5,
            servers: Servers::K(3),
        };
        assert_eq!(net_hash(&net(timing, false)), "2d08252421828c8b");
    }
}
