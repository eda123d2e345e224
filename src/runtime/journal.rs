//! The journal: every event of a run as JSON Lines, after a header line with the net's
//! identity and the seed (enough for a later `plan-runner replay`).
//!
//! The supervisor hands every event, serialised, to a writer thread as it happens, so the
//! journal never misses an event and never blocks the run on the disk. The writer thread
//! holds at most [`FLUSH_EVENTS`] events or [`FLUSH_AFTER`] of them before it writes them to
//! the file, and flushes (and syncs) when the run stops, whatever stopped it. After a
//! `SIGKILL` the file holds every event up to the last write, with at most one line cut
//! short at the end, which `replay` skips with a warning (see docs/reliability.md).
//!
//! Besides the events, a backend can add *side records* through a [`JournalTap`]
//! ([`RuntimeHandle::journal_tap`](super::RuntimeHandle::journal_tap)): lines
//! `{"record": KIND, "time": t, "data": …}` that are not events (the simulated world writes
//! its map once and the robots' poses at the viewer's rate, so `replay --web` draws the
//! map). [`read_recording`] gives them back apart from the events; a journal without them
//! (every journal written before them) reads as before.

use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::Path;
use std::sync::{Arc, OnceLock, mpsc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

mod lines;

pub use lines::{Entry, JournalReader};

use super::action::Outcome;
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

/// Most events the writer holds before it writes them to the file.
pub const FLUSH_EVENTS: usize = 100;

/// Longest time an event waits in the writer before it is written to the file.
pub const FLUSH_AFTER: Duration = Duration::from_millis(100);

/// What the supervisor (and the taps) send the writer thread.
enum Msg {
    /// One serialised line, newline included.
    Line(Vec<u8>),
    /// The run's `stopped` event: written even after a write failed, when it fits.
    Last(Vec<u8>),
    /// The run is over: write out, sync and end (taps may still be held).
    End,
}

/// Adds side records to a run's journal (see the module doc); cheap to clone. Records sent
/// after the run's journal was flushed are dropped.
#[derive(Clone, Debug)]
pub struct JournalTap {
    tx: mpsc::Sender<Msg>,
}

impl JournalTap {
    /// Writes the line `{"record": kind, "time": time, "data": data}` (`kind` is a plain
    /// word such as `world`). A value that does not serialise is skipped.
    pub fn record(&self, kind: &str, time: f64, data: &impl Serialize) {
        let line = Record {
            record: kind.into(),
            time,
            data,
        };
        if let Ok(mut bytes) = serde_json::to_vec(&line) {
            bytes.push(b'\n');
            let _ = self.tx.send(Msg::Line(bytes));
        }
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

/// A JSON Lines writer for one run's events: a thread that writes through a buffer it
/// flushes every [`FLUSH_EVENTS`] events or [`FLUSH_AFTER`], whichever comes first.
#[derive(Debug)]
pub(crate) struct Journal {
    tx: Option<mpsc::Sender<Msg>>,
    writer: Option<JoinHandle<Option<String>>>,
    failed: Option<String>,
    /// The writer thread's first write error, as soon as it happens: the supervisor stops
    /// the run on it ([`Journal::broken`]).
    broken: Arc<OnceLock<String>>,
    names: Names,
}

/// Place and transition names as JSON strings, added to each event line beside the ids
/// (`place_name`, `transition_name`), so a journal reads without its header.
#[derive(Debug)]
struct Names {
    places: Vec<Box<str>>,
    transitions: Vec<Box<str>>,
}

impl Names {
    /// Adds the names of the place and the transition `e` carries to its serialised object
    /// in `line` (which ends with `}`).
    fn append(&self, e: &Event, line: &mut Vec<u8>) {
        let (place, transition) = match &e.kind {
            EventKind::Fired { transition, .. } => (None, Some(*transition)),
            EventKind::AgentSpawned { place, .. }
            | EventKind::ActionStarted { place, .. }
            | EventKind::ActionOutput { place, .. } => (Some(*place), None),
            EventKind::Drift(d) => match d.of {
                super::event::Monitored::Transition(t) => (None, Some(t)),
                super::event::Monitored::Place(p) => (Some(p), None),
            },
            EventKind::ActionEnded { place, outcome, .. } => (
                Some(*place),
                match outcome {
                    Outcome::Fire(t) => Some(*t),
                    _ => None,
                },
            ),
            _ => (None, None),
        };
        if place.is_none() && transition.is_none() || line.last() != Some(&b'}') {
            return;
        }
        line.pop();
        for (key, names, id) in [
            ("place_name", &self.places, place.map(|p| p.index())),
            (
                "transition_name",
                &self.transitions,
                transition.map(|t| t.index()),
            ),
        ] {
            if let Some(name) = id.and_then(|i| names.get(i)) {
                line.extend_from_slice(b",\"");
                line.extend_from_slice(key.as_bytes());
                line.extend_from_slice(b"\":");
                line.extend_from_slice(name.as_bytes());
            }
        }
        line.push(b'}');
    }
}

impl Journal {
    /// Creates the file, writes the header (on disk before the run starts) and starts the
    /// writer thread.
    pub(crate) fn create(path: &Path, net: &Net, run: RunFacts<'_>) -> std::io::Result<Journal> {
        let mut out_file = File::create(path)?;
        let RunFacts {
            seed,
            time_scale,
            file,
            robots,
        } = run;
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
            file: file.map(|f| f.to_string_lossy()),
            robots: robots.iter().map(|r| (**r).into()).collect(),
            initial: Some(net.initial_marking().into_vec()),
        };
        let quoted = |names: &[std::borrow::Cow<'_, str>]| -> Vec<Box<str>> {
            names
                .iter()
                .map(|n| serde_json::to_string(n).unwrap_or_default().into())
                .collect()
        };
        let names = Names {
            places: quoted(&header.places),
            transitions: quoted(&header.transitions),
        };
        let mut first = serde_json::to_vec(&header)?;
        first.push(b'\n');
        // On disk before the run starts: a target that cannot be written (a full disk,
        // `/dev/full`, a read-only file system) refuses the run instead of failing in it.
        out_file.write_all(&first)?;
        let broken = Arc::new(OnceLock::new());
        let out = LineWriter::new(out_file, first.len() as u64, Arc::clone(&broken));
        let (tx, rx) = mpsc::channel();
        let writer = std::thread::Builder::new()
            .name("gspn-journal".into())
            .spawn(move || write_through(out, rx))?;
        Ok(Journal {
            tx: Some(tx),
            writer: Some(writer),
            failed: None,
            broken,
            names,
        })
    }

    /// A tap for side records, while the writer runs.
    pub(crate) fn tap(&self) -> Option<JournalTap> {
        self.tx.clone().map(|tx| JournalTap { tx })
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
        self.names.append(e, &mut line);
        line.push(b'\n');
        let msg = if matches!(e.kind, EventKind::Stopped { .. }) {
            Msg::Last(line)
        } else {
            Msg::Line(line)
        };
        if tx.send(msg).is_err() {
            // The writer ended early: it failed, and says why when joined.
            self.tx = None;
        }
    }

    /// The first error writing the file (a full disk), once the writer has met one: the
    /// events after it are not in the journal, so the run must stop.
    pub(crate) fn broken(&self) -> Option<&str> {
        self.broken.get().map(String::as_str)
    }

    /// Writes out and syncs everything handed over so far and ends the writer; the first
    /// error of the run, if any. Later events are dropped.
    pub(crate) fn flush(&mut self) -> Option<String> {
        if let Some(tx) = self.tx.take() {
            let _ = tx.send(Msg::End);
        }
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

/// What the header says of a run besides its net.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RunFacts<'a> {
    /// The seed.
    pub(crate) seed: u64,
    /// The time scale (0 = virtual time).
    pub(crate) time_scale: f64,
    /// The net's file.
    pub(crate) file: Option<&'a Path>,
    /// The robots bound to the initial agents.
    pub(crate) robots: &'a [Arc<str>],
}

/// The journal file as the writer thread keeps it: whole lines only. Lines are buffered and
/// written in one go; when a write fails (the disk is full) the file is cut back to the end
/// of its last whole line, so a journal that met an error still reads to its end, and every
/// later line is dropped but the run's `stopped` event ([`Msg::Last`]), tried once more.
struct LineWriter {
    file: File,
    buf: Vec<u8>,
    /// Bytes on disk, all of them whole lines.
    whole: u64,
    broken: Arc<OnceLock<String>>,
}

impl LineWriter {
    fn new(file: File, whole: u64, broken: Arc<OnceLock<String>>) -> LineWriter {
        LineWriter {
            file,
            buf: Vec::with_capacity(1 << 16),
            whole,
            broken,
        }
    }

    fn failed(&self) -> bool {
        self.broken.get().is_some()
    }

    fn push(&mut self, line: &[u8]) {
        if !self.failed() {
            self.buf.extend_from_slice(line);
        }
    }

    /// Writes the buffered lines; on an error, cuts the file back to whole lines and
    /// records the error (later lines are dropped).
    fn flush(&mut self) {
        if self.buf.is_empty() || self.failed() {
            self.buf.clear();
            return;
        }
        let buf = std::mem::take(&mut self.buf);
        self.write_or_cut(&buf);
        self.buf = buf;
        self.buf.clear();
    }

    fn write_or_cut(&mut self, bytes: &[u8]) -> bool {
        match self.file.write_all(bytes) {
            Ok(()) => {
                self.whole += bytes.len() as u64;
                true
            }
            Err(e) => {
                // Freeing the partial line also makes room for the `stopped` event.
                let _ = self.file.set_len(self.whole);
                let _ = self.file.seek(SeekFrom::Start(self.whole));
                let _ = self.broken.set(io_message(&e));
                false
            }
        }
    }

    /// The run's last event: written after the others, or — when a write failed — on its
    /// own after the last whole line, if it fits.
    fn last(&mut self, line: &[u8]) {
        if self.failed() {
            self.write_or_cut(line);
        } else {
            self.push(line);
            self.flush();
        }
    }

    /// Flushes and syncs; the first error.
    fn end(mut self) -> Option<String> {
        self.flush();
        if let Err(e) = self.file.sync_data() {
            let _ = self.broken.set(io_message(&e));
        }
        self.broken.get().cloned()
    }
}

/// An I/O error as the user reads it: `No space left on device` (without the errno).
fn io_message(e: &std::io::Error) -> String {
    let text = e.to_string();
    match text.find(" (os error") {
        Some(i) => text[..i].to_string(),
        None => text,
    }
}

/// The writer thread: lines in, written to the file at most [`FLUSH_EVENTS`] lines or
/// [`FLUSH_AFTER`] after they arrived; a final flush and sync at [`Msg::End`] or when every
/// sender went away.
fn write_through(mut out: LineWriter, rx: mpsc::Receiver<Msg>) -> Option<String> {
    let mut pending = 0usize;
    let mut deadline: Option<Instant> = None;
    loop {
        let msg = match deadline {
            None => rx.recv().map_err(|_| mpsc::RecvTimeoutError::Disconnected),
            Some(d) => rx.recv_timeout(d.saturating_duration_since(Instant::now())),
        };
        match msg {
            Ok(Msg::Line(line)) => {
                out.push(&line);
                pending += 1;
                deadline.get_or_insert_with(|| Instant::now() + FLUSH_AFTER);
                if pending >= FLUSH_EVENTS {
                    out.flush();
                    pending = 0;
                    deadline = None;
                }
            }
            Ok(Msg::Last(line)) => {
                out.last(&line);
                pending = 0;
                deadline = None;
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {
                out.flush();
                pending = 0;
                deadline = None;
            }
            Ok(Msg::End) | Err(mpsc::RecvTimeoutError::Disconnected) => return out.end(),
        }
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
        match lines::entry(l, net).map_err(|reason| bad(i, reason))? {
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
        for e in &self.events {
            if let EventKind::Fired {
                transition,
                marking,
                ..
            } = &e.kind
            {
                frames.push(Frame {
                    time: e.time,
                    transition: Some(self.net.transition(*transition).name.clone()),
                    tokens: marking.to_vec(),
                });
            }
        }
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
