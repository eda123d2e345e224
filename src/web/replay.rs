//! A run played back from its journal (`plan-runner replay`): the marking after each firing,
//! with its time, for the page's time slider.

use serde::Serialize;
use serde_json::Value;

use crate::net::Net;
use crate::runtime::journal::net_hash;

/// The marking at one point of a run.
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
pub enum ReplayError {
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

/// A journal read back by [`read_journal_tolerant`].
#[derive(Clone, Debug, PartialEq)]
pub struct Replay {
    /// The initial marking, then the marking after each `fired` event.
    pub frames: Vec<Frame>,
    /// The last line, when it was cut short (a run killed mid-write) and skipped: its
    /// 1-based number and why it does not parse.
    pub torn: Option<ReplayError>,
}

/// Reads a journal (JSON Lines: a header, then one event per line) of a run of `net` into
/// frames: the initial marking, then the marking after each `fired` event. Every line must
/// be whole (see [`read_journal_tolerant`] for a journal of a killed run).
pub fn read_journal(text: &str, net: &Net) -> Result<Vec<Frame>, ReplayError> {
    let r = read_journal_tolerant(text, net)?;
    match r.torn {
        Some(e) => Err(e),
        None => Ok(r.frames),
    }
}

/// Like [`read_journal`], but a last line cut short — no newline after it and not valid
/// JSON, what a `SIGKILL` in the middle of a write leaves — is skipped and reported in
/// [`Replay::torn`] instead of refusing the whole journal. Any other bad line is an error.
pub fn read_journal_tolerant(text: &str, net: &Net) -> Result<Replay, ReplayError> {
    let mut torn = None;
    let mut text = text;
    if !text.ends_with('\n')
        && let Some(start) = text.rfind('\n').map(|i| i + 1)
        && !text[start..].trim().is_empty()
        && let Err(e) = serde_json::from_str::<Value>(&text[start..])
    {
        torn = Some(ReplayError::BadLine {
            line: text.lines().count(),
            reason: format!("cut short ({e})"),
        });
        text = &text[..start];
    }
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let parse = |i: usize, l: &str| -> Result<Value, ReplayError> {
        serde_json::from_str(l).map_err(|e| ReplayError::BadLine {
            line: i + 1,
            reason: e.to_string(),
        })
    };
    let Some((i, first)) = lines.next() else {
        return Err(ReplayError::BadLine {
            line: 1,
            reason: "empty journal: no header".into(),
        });
    };
    let header = parse(i, first)?;
    let expected = net_hash(net);
    let hash = header["hash"].as_str().unwrap_or_default();
    if hash != expected {
        return Err(ReplayError::OtherNet {
            journal: header["net"].as_str().unwrap_or_default().to_string(),
            hash: hash.to_string(),
            net: net.name().to_string(),
            expected,
        });
    }
    let mut frames = vec![Frame {
        time: 0.0,
        transition: None,
        tokens: net.initial_marking().into_vec(),
    }];
    for (i, l) in lines {
        let e = parse(i, l)?;
        if e["event"] != "fired" {
            continue;
        }
        let bad = |reason: &str| ReplayError::BadLine {
            line: i + 1,
            reason: reason.to_string(),
        };
        let t = e["transition"]
            .as_u64()
            .filter(|&t| (t as usize) < net.transition_count())
            .ok_or_else(|| bad("`transition` is not a transition id of this net"))?;
        let tokens: Vec<u32> = serde_json::from_value(e["marking"].clone())
            .ok()
            .filter(|m: &Vec<u32>| m.len() == net.place_count())
            .ok_or_else(|| bad("`marking` is not a marking of this net"))?;
        frames.push(Frame {
            time: e["time"].as_f64().ok_or_else(|| bad("no `time`"))?,
            transition: Some(net.transitions()[t as usize].name.clone()),
            tokens,
        });
    }
    Ok(Replay { frames, torn })
}
