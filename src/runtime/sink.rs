//! Where a run's events go: numbered in order, written to the journal, sent on the bus.

use tokio::sync::broadcast;

use super::event::{Event, EventKind};
use super::journal::Journal;

/// The run's event bus, sequence and journal.
#[derive(Debug)]
pub(crate) struct EventSink {
    bus: broadcast::Sender<Event>,
    seq: u64,
    journal: Option<Journal>,
}

impl EventSink {
    pub(crate) fn new(bus: broadcast::Sender<Event>, journal: Option<Journal>) -> EventSink {
        EventSink {
            bus,
            seq: 0,
            journal,
        }
    }

    /// True when someone reads the events (a journal or a subscriber): otherwise the
    /// supervisor does not build them.
    pub(crate) fn observed(&self) -> bool {
        self.journal.is_some() || self.bus.receiver_count() > 0
    }

    /// Numbers, journals and broadcasts one event at model time `time`.
    pub(crate) fn emit(&mut self, time: f64, kind: EventKind) {
        let e = Event {
            seq: self.seq,
            time,
            kind,
        };
        self.seq += 1;
        if let Some(j) = &mut self.journal {
            j.write(&e);
        }
        let _ = self.bus.send(e);
    }

    /// The journal's first write error, once its writer met one (the run must stop).
    pub(crate) fn journal_broken(&self) -> Option<&str> {
        self.journal.as_ref().and_then(Journal::broken)
    }

    /// Flushes the journal; the first journal error of the run, if any.
    pub(crate) fn flush(&mut self) -> Option<String> {
        self.journal.as_mut().and_then(Journal::flush)
    }
}
