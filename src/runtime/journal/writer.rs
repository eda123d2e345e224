//! Writing a journal: the header, then every event the supervisor hands over, through a
//! writer thread that never blocks the run on the disk (see the [module doc](super)), and
//! the side records of the taps.

use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::Path;
use std::sync::{Arc, OnceLock, mpsc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use serde::Serialize;

use super::super::action::Outcome;
use super::super::event::{Event, EventKind};
use super::{JournalHeader, Record, net_hash};
use crate::net::Net;

/// Most events the writer holds before it writes them to the file.
pub const FLUSH_EVENTS: usize = 100;

/// The journal's durability bound: an event handed to the writer is in the file (written:
/// in the kernel's hands, so it survives a `SIGKILL` of the process) at most this long after,
/// on a loaded machine too. The writer's own timer is 25 ms; the rest is the margin
/// for the writer thread to get a CPU to wake on (issue 32: with a 100 ms timer, 3 of 20
/// kills at load 8–9 lost events 100.0–104.0 ms old; docs/reliability.md).
pub const FLUSH_AFTER: Duration = Duration::from_millis(100);

/// Longest time an event waits in the writer before the writer writes it to the file (a
/// quarter of [`FLUSH_AFTER`]: at most 40 writes a second while events trickle in).
const WRITE_AFTER: Duration = Duration::from_millis(25);

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

/// A JSON Lines writer for one run's events: a thread that writes through a buffer it
/// flushes every [`FLUSH_EVENTS`] events or [`WRITE_AFTER`], whichever comes first.
#[derive(Debug)]
pub(crate) struct Journal {
    tx: Option<mpsc::Sender<Msg>>,
    writer: Option<JoinHandle<Option<String>>>,
    failed: Option<String>,
    /// The writer thread's first write error, as soon as it happens: the supervisor stops
    /// the run on it ([`Journal::broken`]).
    broken: Arc<OnceLock<String>>,
    names: Names,
    handovers: Option<Handovers>,
}

/// The environment variable naming a file to which every event's handover to the writer is
/// appended as `SEQ UNIX_NANOS` (unbuffered: a line per event, in the kernel's hands before
/// the event is sent, so a `SIGKILL` loses none of them). A measurement hook, not a
/// feature: `benches/journal_kill.py` compares it with the journal after killing the run,
/// which gives the age of every event the kill lost (docs/reliability.md).
pub const HANDOVERS_ENV: &str = "GSPN_JOURNAL_HANDOVERS";

/// The handover log ([`HANDOVERS_ENV`]).
#[derive(Debug)]
struct Handovers(File);

impl Handovers {
    fn from_env() -> Option<Handovers> {
        let path = std::env::var_os(HANDOVERS_ENV)?;
        File::options()
            .create(true)
            .append(true)
            .open(path)
            .ok()
            .map(Handovers)
    }

    fn log(&mut self, seq: u64) {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        // One write per line (formatting straight into the file would write it in pieces).
        let _ = self.0.write_all(format!("{seq} {nanos}\n").as_bytes());
    }
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
                super::super::event::Monitored::Transition(t) => (None, Some(t)),
                super::super::event::Monitored::Place(p) => (Some(p), None),
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
            handovers: Handovers::from_env(),
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
        if let Some(h) = &mut self.handovers {
            h.log(e.seq);
        }
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
/// [`WRITE_AFTER`] after they arrived; a final flush and sync at [`Msg::End`] or when every
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
                deadline.get_or_insert_with(|| Instant::now() + WRITE_AFTER);
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
