//! The journal: every event of a run as JSON Lines, after a header line with the net's
//! identity and the seed (enough for a later `plan-runner replay`).
//!
//! The supervisor writes it itself, through a buffer, so the journal never lags and never
//! misses an event; it is flushed when the run stops. [`read_journal`] reads one back into
//! typed [`Event`]s and the marking after each firing (`plan-runner replay`, with or without
//! the viewer).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::event::{Event, EventKind};
use crate::net::{Net, Timing};

/// The identity of a net: a 64-bit FNV-1a hash of its places (name, initial marking,
/// capacity), transitions (name, timing) and arcs, written as 16 hex digits.
pub fn net_hash(net: &Net) -> String {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    for p in net.places() {
        h.str(&p.name);
        h.u64(p.initial as u64);
        h.u64(p.capacity.map_or(u64::MAX, |c| c as u64));
    }
    for t in net.transitions() {
        h.str(&t.name);
        match t.timing {
            Timing::Immediate { weight, priority } => {
                h.u64(0);
                h.u64(weight.to_bits());
                h.u64(priority as u64);
            }
            Timing::Exponential { rate, servers } => {
                h.u64(1);
                h.u64(rate.to_bits());
                h.str(&format!("{servers:?}"));
            }
        }
    }
    for a in net.arcs() {
        h.u64(a.kind as u64);
        h.u64(a.place.0 as u64);
        h.u64(a.transition.0 as u64);
        h.u64(a.weight as u64);
    }
    format!("{:016x}", h.0)
}

struct Fnv(u64);

impl Fnv {
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.bytes(s.as_bytes());
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
}

/// A JSON Lines writer for one run's events.
#[derive(Debug)]
pub(crate) struct Journal {
    out: BufWriter<File>,
    failed: Option<String>,
}

impl Journal {
    /// Creates the file and writes the header.
    pub(crate) fn create(
        path: &Path,
        net: &Net,
        seed: u64,
        time_scale: f64,
    ) -> std::io::Result<Journal> {
        let mut out = BufWriter::with_capacity(1 << 16, File::create(path)?);
        let header = JournalHeader {
            net: net.name().into(),
            hash: net_hash(net),
            seed,
            time_scale,
            places: net
                .places()
                .iter()
                .map(|p| p.name.as_str().into())
                .collect(),
            transitions: net
                .transitions()
                .iter()
                .map(|t| t.name.as_str().into())
                .collect(),
        };
        serde_json::to_writer(&mut out, &header)?;
        out.write_all(b"\n")?;
        Ok(Journal { out, failed: None })
    }

    /// Appends one event (an I/O error is remembered and reported once, at the end).
    pub(crate) fn write(&mut self, e: &Event) {
        if self.failed.is_some() {
            return;
        }
        let r = serde_json::to_writer(&mut self.out, e)
            .map_err(std::io::Error::from)
            .and_then(|_| self.out.write_all(b"\n"));
        if let Err(err) = r {
            self.failed = Some(err.to_string());
        }
    }

    /// Flushes the buffer to the file; the first error of the run, if any.
    pub(crate) fn flush(&mut self) -> Option<String> {
        if let Err(e) = self
            .out
            .flush()
            .and_then(|_| self.out.get_ref().sync_data())
        {
            self.failed.get_or_insert(e.to_string());
        }
        self.failed.clone()
    }
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
    #[error("the journal is of net `{journal}` ({hash}), not of this net `{net}` ({expected})")]
    OtherNet {
        /// The journal's net name.
        journal: String,
        /// The journal's net hash.
        hash: String,
        /// This net's name.
        net: String,
        /// This net's hash.
        expected: String,
    },
}

/// Reads a journal (JSON Lines: a header, then one [`Event`] per line) of a run of `net`:
/// its events, checked against the net (the header's hash, every transition id and marking).
pub fn read_events(text: &str, net: &Net) -> Result<Vec<Event>, JournalError> {
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
    let expected = net_hash(net);
    if header.hash != expected {
        return Err(JournalError::OtherNet {
            journal: header.net.into_owned(),
            hash: header.hash,
            net: net.name().to_string(),
            expected,
        });
    }
    let mut events = Vec::new();
    for (i, l) in lines {
        let e: Event = serde_json::from_str(l).map_err(|e| bad(i, e.to_string()))?;
        if let EventKind::Fired {
            transition,
            marking,
            ..
        } = &e.kind
        {
            if transition.index() >= net.transition_count() {
                return Err(bad(
                    i,
                    "`transition` is not a transition id of this net".into(),
                ));
            }
            if marking.len() != net.place_count() {
                return Err(bad(i, "`marking` is not a marking of this net".into()));
            }
        }
        events.push(e);
    }
    Ok(events)
}

/// Reads a journal of a run of `net` into frames: the initial marking, then the marking
/// after each firing ([`read_events`]).
pub fn read_journal(text: &str, net: &Net) -> Result<Vec<Frame>, JournalError> {
    let mut frames = vec![Frame {
        time: 0.0,
        transition: None,
        tokens: net.initial_marking().into_vec(),
    }];
    for e in read_events(text, net)? {
        if let EventKind::Fired {
            transition,
            marking,
            ..
        } = e.kind
        {
            frames.push(Frame {
                time: e.time,
                transition: Some(net.transition(transition).name.clone()),
                tokens: marking.into_vec(),
            });
        }
    }
    Ok(frames)
}
