//! A journal read one line at a time ([`JournalReader`]), so `replay` and `conform` hold
//! what they keep of a run, not the file and every event of it: issue 32 measured
//! 1.7 GB for a 100 MB journal read whole (its text, then every event as a struct).

use std::io::BufRead;

use super::{JournalError, JournalHeader, Record, Recording};
use crate::net::Net;
use crate::runtime::event::{Event, EventKind};

/// One line of a journal after its header.
#[derive(Clone, Debug)]
pub enum Entry {
    /// An event of the run.
    Event(Event),
    /// A side record ([`super::JournalTap::record`]).
    Record(Record),
}

/// Why a journal line is not an entry of a run of the net ([`JournalError::BadLine`] holds
/// its text, beside the line number).
#[derive(Debug, thiserror::Error)]
pub(crate) enum LineError {
    /// Not the JSON of an event or a record.
    #[error("{0}")]
    Json(#[from] serde_json::Error),
    /// A fired transition's id past the net's transitions.
    #[error("`transition` is not a transition id of this net")]
    Transition,
    /// A marking of another length than the net's places.
    #[error("`marking` is not a marking of this net")]
    Marking,
}

/// Reads `line` (not the header) as an [`Entry`] of a run of `net`: a fired transition must
/// be one of its transitions and its marking one of its markings.
pub(crate) fn entry(line: &str, net: &Net) -> Result<Entry, LineError> {
    if line.starts_with("{\"record\"") {
        return Ok(Entry::Record(serde_json::from_str(line)?));
    }
    let e: Event = serde_json::from_str(line)?;
    if let EventKind::Fired {
        transition,
        marking,
        ..
    } = &e.kind
    {
        if transition.index() >= net.transition_count() {
            return Err(LineError::Transition);
        }
        if marking.len() != net.place_count() {
            return Err(LineError::Marking);
        }
    }
    Ok(Entry::Event(e))
}

/// A journal of a run, read a line at a time from any [`BufRead`] (a file, a pipe): the
/// header is read and checked against the net when it is made
/// ([`JournalHeader::net_that_ran`]), then each [`Entry`] comes out of the iterator as it
/// is read. A last line cut short (no newline after it, not JSON: what a `SIGKILL` in a
/// write leaves) ends the iteration and is kept in [`JournalReader::torn`], as
/// [`super::split_torn`] does for a journal read whole.
///
/// ```
/// use gspn::net::{NetBuilder, Servers};
/// use gspn::runtime::journal::{Entry, JournalReader, net_hash};
///
/// let mut b = NetBuilder::new("n");
/// let p = b.place("P", 1);
/// let t = b.exponential("T", 1.0, Servers::Single);
/// b.input(p, t, 1);
/// let net = b.build().unwrap();
/// let header = serde_json::json!({"net": "n", "hash": net_hash(&net), "seed": 1,
///     "time_scale": 0.0, "places": ["P"], "transitions": ["T"]});
/// let text = format!("{header}\n{{\"seq\":0,\"time\":0.0,\"event\":\"stopped\",\"reason\":\"dead\"}}\n");
/// let mut journal = JournalReader::new(text.as_bytes(), &net)?;
/// let stopped = journal.next().unwrap()?;
/// assert!(matches!(stopped, Entry::Event(e) if e.seq == 0));
/// assert!(journal.next().is_none() && journal.torn().is_none());
/// # Ok::<(), gspn::runtime::journal::JournalError>(())
/// ```
#[derive(Debug)]
pub struct JournalReader<R> {
    input: R,
    /// The net as it ran (the net given, or it with the header's initial marking).
    net: Net,
    remarked: bool,
    file: Option<String>,
    robots: Vec<String>,
    /// 1-based number of the last line read.
    line: usize,
    /// Bytes read so far, and where the last line read starts ([`JournalReader::line_start`]).
    offset: u64,
    line_start: u64,
    buf: String,
    torn: Option<JournalError>,
    done: bool,
}

impl<R: BufRead> JournalReader<R> {
    /// Reads the header (the first line that is not blank) and checks it against `net`.
    pub fn new(mut input: R, net: &Net) -> Result<JournalReader<R>, JournalError> {
        let mut buf = String::new();
        let mut line = 0;
        let mut offset = 0;
        loop {
            buf.clear();
            line += 1;
            let n = input
                .read_line(&mut buf)
                .map_err(|e| read_error(line, &e))?;
            offset += n as u64;
            if n == 0 {
                return Err(JournalError::BadLine {
                    line: 1,
                    reason: "empty journal: no header".into(),
                });
            }
            if !buf.trim().is_empty() {
                break;
            }
        }
        let header: JournalHeader<'_> =
            serde_json::from_str(buf.trim_end()).map_err(|e| JournalError::BadLine {
                line,
                reason: e.to_string(),
            })?;
        let ran = header.net_that_ran(net)?;
        Ok(JournalReader {
            remarked: ran.is_some(),
            net: ran.unwrap_or_else(|| net.clone()),
            file: header.file.map(|f| f.into_owned()),
            robots: header.robots.iter().map(|r| r.to_string()).collect(),
            input,
            line,
            offset,
            line_start: offset,
            buf: String::new(),
            torn: None,
            done: false,
        })
    }

    /// The byte offset of the start of the last line read (after the iterator returned an
    /// entry: that entry's line; before: the first line after the header).
    pub(crate) fn line_start(&self) -> u64 {
        self.line_start
    }

    /// The bytes read so far: where the last line read ends.
    pub(crate) fn offset(&self) -> u64 {
        self.offset
    }

    /// The 1-based number of the last line read.
    pub(crate) fn line(&self) -> usize {
        self.line
    }

    /// The net as it ran: the net given, or it with the journal's initial marking.
    pub fn net(&self) -> &Net {
        &self.net
    }

    /// True when [`net`](Self::net) has the journal's initial marking instead of the given
    /// net's (as [`super::Recording::remarked`]).
    pub fn remarked(&self) -> bool {
        self.remarked
    }

    /// The file the run read its net from, when the header says.
    pub fn file(&self) -> Option<&str> {
        self.file.as_deref()
    }

    /// The robots bound to the initial agents (empty without robots).
    pub fn robots(&self) -> &[String] {
        &self.robots
    }

    /// The last line, cut short, once the iteration has reached it (a warning, not an
    /// error: the run was killed while writing it).
    pub fn torn(&self) -> Option<&JournalError> {
        self.torn.as_ref()
    }

    /// Reads the rest into a [`Recording`] (as [`super::read_recording`] gives it, without
    /// ever holding the file's text); with the cut last line, if any.
    pub fn into_recording(mut self) -> Result<(Recording, Option<JournalError>), JournalError> {
        let mut events = Vec::new();
        let mut records = Vec::new();
        for entry in self.by_ref() {
            match entry? {
                Entry::Event(e) => events.push(e),
                Entry::Record(r) => records.push(r),
            }
        }
        let recording = Recording {
            net: self.net,
            remarked: self.remarked,
            file: self.file,
            robots: self.robots,
            events,
            records,
        };
        Ok((recording, self.torn))
    }
}

fn read_error(line: usize, e: &std::io::Error) -> JournalError {
    JournalError::BadLine {
        line,
        reason: format!("cannot read: {e}"),
    }
}

impl<R: BufRead> Iterator for JournalReader<R> {
    type Item = Result<Entry, JournalError>;

    fn next(&mut self) -> Option<Self::Item> {
        while !self.done {
            self.buf.clear();
            self.line += 1;
            let n = match self.input.read_line(&mut self.buf) {
                Ok(n) => n,
                Err(e) => {
                    self.done = true;
                    return Some(Err(read_error(self.line, &e)));
                }
            };
            if n == 0 {
                self.done = true;
                break;
            }
            self.line_start = self.offset;
            self.offset += n as u64;
            let whole = self.buf.ends_with('\n');
            let text = self.buf.trim_end();
            if text.trim().is_empty() {
                continue;
            }
            match entry(text, &self.net) {
                Ok(e) => return Some(Ok(e)),
                Err(reason) => {
                    self.done = true;
                    if !whole && let Err(cut) = serde_json::from_str::<serde_json::Value>(text) {
                        self.torn = Some(JournalError::BadLine {
                            line: self.line,
                            reason: format!("cut short ({cut})"),
                        });
                        return None;
                    }
                    return Some(Err(JournalError::BadLine {
                        line: self.line,
                        reason: reason.to_string(),
                    }));
                }
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{Servers, cyc3};
    use crate::runtime::journal::{net_hash, read_recording, split_torn};

    fn journal(net: &Net, lines: &[&str]) -> String {
        let header = serde_json::json!({
            "net": "cyc3", "hash": net_hash(net), "seed": 1, "time_scale": 0.0,
            "places": ["P1", "P2", "P3"], "transitions": ["T1", "t2", "T3"],
        });
        let mut text = format!("{header}\n");
        for l in lines {
            text.push_str(l);
        }
        text
    }

    const FIRED: &str = "{\"seq\":0,\"time\":0.5,\"event\":\"fired\",\"transition\":0,\
        \"marking\":[1,1,0],\"consumed\":[],\"produced\":[]}\n";
    const STOPPED: &str = "{\"seq\":1,\"time\":0.5,\"event\":\"stopped\",\"reason\":\"dead\"}\n";

    #[test]
    fn reads_what_read_recording_reads_a_line_at_a_time() {
        let net = cyc3(Servers::Single);
        let text = journal(&net, &[FIRED, "\n", STOPPED]);
        let whole = read_recording(&text, &net).unwrap();
        let streamed: Vec<Event> = JournalReader::new(text.as_bytes(), &net)
            .unwrap()
            .map(|e| match e.unwrap() {
                Entry::Event(e) => e,
                Entry::Record(_) => panic!("no records here"),
            })
            .collect();
        assert_eq!(streamed, whole.events);
    }

    #[test]
    fn a_cut_last_line_is_torn_and_a_bad_whole_line_an_error_with_its_number() {
        let net = cyc3(Servers::Single);
        let text = journal(&net, &[FIRED, &STOPPED[..20]]);
        let mut r = JournalReader::new(text.as_bytes(), &net).unwrap();
        assert!(matches!(r.next(), Some(Ok(Entry::Event(_)))));
        assert!(r.next().is_none());
        let (_, torn) = split_torn(&text);
        assert_eq!(r.torn(), torn.as_ref());
        assert!(matches!(
            r.torn(),
            Some(JournalError::BadLine { line: 3, .. })
        ));

        let bad = journal(&net, &[FIRED.replace("[1,1,0]", "[1,1]").as_str()]);
        let mut r = JournalReader::new(bad.as_bytes(), &net).unwrap();
        assert_eq!(
            r.next().unwrap().unwrap_err(),
            JournalError::BadLine {
                line: 2,
                reason: "`marking` is not a marking of this net".into()
            }
        );
        assert!(r.next().is_none());
    }
}
