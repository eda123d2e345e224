//! The journal: every event of a run as JSON Lines, after a header line with the net's
//! identity and the seed (enough for a later `plan-runner replay`).
//!
//! The supervisor hands every event, serialised, to a writer thread as it happens, so the
//! journal never misses an event and never blocks the run on the disk. The writer thread
//! holds at most [`FLUSH_EVENTS`] events or [`FLUSH_AFTER`] of them before it writes them to
//! the file, and flushes (and syncs) when the run stops, whatever stopped it. After a
//! `SIGKILL` the file holds every event up to the last write, with at most one line cut
//! short at the end, which `replay` skips with a warning (see docs/reliability.md).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

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

/// Most events the writer holds before it writes them to the file.
pub const FLUSH_EVENTS: usize = 100;

/// Longest time an event waits in the writer before it is written to the file.
pub const FLUSH_AFTER: Duration = Duration::from_millis(100);

/// What the supervisor sends the writer thread.
enum Msg {
    /// One serialised line, newline included.
    Line(Vec<u8>),
}

/// A JSON Lines writer for one run's events: a thread that writes through a buffer it
/// flushes every [`FLUSH_EVENTS`] events or [`FLUSH_AFTER`], whichever comes first.
#[derive(Debug)]
pub(crate) struct Journal {
    tx: Option<mpsc::Sender<Msg>>,
    writer: Option<JoinHandle<Option<String>>>,
    failed: Option<String>,
}

impl Journal {
    /// Creates the file, writes the header (on disk before the run starts) and starts the
    /// writer thread.
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
        out.flush()?;
        let (tx, rx) = mpsc::channel();
        let writer = std::thread::Builder::new()
            .name("gspn-journal".into())
            .spawn(move || write_through(out, rx))?;
        Ok(Journal {
            tx: Some(tx),
            writer: Some(writer),
            failed: None,
        })
    }

    /// Hands one event to the writer (an I/O error is reported once, at the end).
    pub(crate) fn write(&mut self, e: &Event) {
        let Some(tx) = &self.tx else {
            return;
        };
        let mut line = Vec::with_capacity(128);
        if let Err(err) = serde_json::to_writer(&mut line, e) {
            self.failed.get_or_insert(err.to_string());
            return;
        }
        line.push(b'\n');
        if tx.send(Msg::Line(line)).is_err() {
            // The writer ended early: it failed, and says why when joined.
            self.tx = None;
        }
    }

    /// Writes out and syncs everything handed over so far and ends the writer; the first
    /// error of the run, if any. Later events are dropped.
    pub(crate) fn flush(&mut self) -> Option<String> {
        self.tx = None;
        if let Some(w) = self.writer.take() {
            let r = w
                .join()
                .unwrap_or_else(|_| Some("the journal writer panicked".into()));
            if let Some(e) = r {
                self.failed.get_or_insert(e);
            }
        }
        self.failed.clone()
    }
}

impl Drop for Journal {
    /// A run dropped without stopping (its supervisor killed) still gets its events written.
    fn drop(&mut self) {
        self.flush();
    }
}

/// The writer thread: lines in, written to the file at most [`FLUSH_EVENTS`] lines or
/// [`FLUSH_AFTER`] after they arrived; a final flush and sync when the sender goes away.
fn write_through(mut out: BufWriter<File>, rx: mpsc::Receiver<Msg>) -> Option<String> {
    let mut failed: Option<String> = None;
    let mut pending = 0usize;
    let mut deadline: Option<Instant> = None;
    let flush = |out: &mut BufWriter<File>, failed: &mut Option<String>| {
        if let Err(e) = out.flush() {
            failed.get_or_insert(e.to_string());
        }
    };
    loop {
        let msg = match deadline {
            None => rx.recv().map_err(|_| mpsc::RecvTimeoutError::Disconnected),
            Some(d) => rx.recv_timeout(d.saturating_duration_since(Instant::now())),
        };
        match msg {
            Ok(Msg::Line(line)) => {
                if failed.is_none()
                    && let Err(e) = out.write_all(&line)
                {
                    failed = Some(e.to_string());
                }
                pending += 1;
                deadline.get_or_insert_with(|| Instant::now() + FLUSH_AFTER);
                if pending >= FLUSH_EVENTS {
                    flush(&mut out, &mut failed);
                    pending = 0;
                    deadline = None;
                }
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {
                flush(&mut out, &mut failed);
                pending = 0;
                deadline = None;
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                flush(&mut out, &mut failed);
                if let Err(e) = out.get_ref().sync_data() {
                    failed.get_or_insert(e.to_string());
                }
                return failed;
            }
        }
    }
}
