//! The journal: every event of a run as JSON Lines, after a header line with the net's
//! identity and the seed (enough for a later `plan-runner replay`).
//!
//! The supervisor writes it itself, through a buffer, so the journal never lags and never
//! misses an event; it is flushed when the run stops.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use serde::Serialize;

use super::event::Event;
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
#[derive(Debug, Serialize)]
pub struct JournalHeader<'a> {
    /// The net's name.
    pub net: &'a str,
    /// [`net_hash`].
    pub hash: String,
    /// The seed of the run.
    pub seed: u64,
    /// The time scale (0 = virtual time).
    pub time_scale: f64,
    /// Place names, by id (events carry ids).
    pub places: Vec<&'a str>,
    /// Transition names, by id.
    pub transitions: Vec<&'a str>,
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
            net: net.name(),
            hash: net_hash(net),
            seed,
            time_scale,
            places: net.places().iter().map(|p| p.name.as_str()).collect(),
            transitions: net.transitions().iter().map(|t| t.name.as_str()).collect(),
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
