//! Runs recorded to MCAP, the storage of rosbag2 and the format Foxglove opens: a journal
//! (JSON Lines, the crash-tolerant record `replay` and `conform` read) exported as ROS 2
//! messages with their `ros2msg` schemas ([`super::msgs::schema`]) and CDR payloads, through
//! the `mcap` crate.
//!
//! | topic | type | from the journal |
//! |---|---|---|
//! | `/gspn/firings` | `gspn_msgs/msg/Firing` | each `fired` event (`seq` 1, 2, …) |
//! | `/gspn/marking` | `gspn_msgs/msg/Marking` | the initial marking, then the one after each firing |
//! | `/gspn/drift` | `gspn_msgs/msg/Drift` | each `drift` event (`run --monitor`) |
//! | `/<robot>/pose` | `geometry_msgs/msg/PoseStamped` (frame `map`) | the simulated world's `world` records |
//!
//! A journal holds model time only: log, publish and header times are the model time (in
//! nanoseconds from 0), and `model_time` says it in model units.

use std::collections::BTreeMap;
use std::io::{Seek, Write};

use byteorder::LittleEndian;
use serde::Serialize;

use super::msgs::{self, Firing, Header, MAP_FRAME, Marking, PoseStamped, Time, schema};
use crate::runtime::journal::{JournalHeader, Record};
use crate::runtime::{Event, EventKind, Monitored};

/// What went wrong exporting a journal.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    /// A line of the journal could not be read.
    #[error("journal line {line}: {reason}")]
    Journal {
        /// The line, from 1.
        line: usize,
        /// Why.
        reason: String,
    },
    /// Writing the MCAP file failed.
    #[error("MCAP: {0}")]
    Mcap(String),
}

/// What an export wrote, by kind of message.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Exported {
    /// `gspn_msgs/msg/Firing` messages.
    pub firings: u64,
    /// `gspn_msgs/msg/Marking` messages.
    pub markings: u64,
    /// `gspn_msgs/msg/Drift` messages.
    pub drifts: u64,
    /// `geometry_msgs/msg/PoseStamped` messages (all robots).
    pub poses: u64,
    /// Robots with a pose topic.
    pub robots: u64,
    /// A last line cut short (a killed run) that was skipped: 0 or 1.
    pub skipped: u64,
}

/// A time in model units as a ROS time and MCAP nanoseconds.
fn stamp(t: f64) -> (Time, u64) {
    let ns = (t.max(0.0) * 1e9).round() as u64;
    let time = Time {
        sec: i32::try_from(ns / 1_000_000_000).unwrap_or(i32::MAX),
        nanosec: (ns % 1_000_000_000) as u32,
    };
    (time, ns)
}

/// The CDR payload of `msg` as ROS 2 writes it: little-endian encapsulation, then the data.
fn cdr<M: Serialize>(msg: &M) -> Result<Vec<u8>, BagError> {
    let mut out = vec![0x00, 0x01, 0x00, 0x00];
    let body = rustdds::cdr_encoding::to_vec::<M, LittleEndian>(msg)
        .map_err(|e| BagError::Mcap(format!("CDR: {e}")))?;
    out.extend(body);
    Ok(out)
}

/// The MCAP writer with one channel per topic, schemas added once.
struct Bag<W: Write + Seek> {
    out: mcap::Writer<W>,
    channels: BTreeMap<String, (u16, u32)>,
}

impl<W: Write + Seek> Bag<W> {
    fn write<M: Serialize>(
        &mut self,
        topic: &str,
        ty: &str,
        t: f64,
        msg: &M,
    ) -> Result<(), BagError> {
        let mcap_err = |e: mcap::McapError| BagError::Mcap(e.to_string());
        if !self.channels.contains_key(topic) {
            let text = schema::ros2msg(ty)
                .ok_or_else(|| BagError::Mcap(format!("no definition of {ty}")))?;
            let schema = self
                .out
                .add_schema(ty, "ros2msg", text.as_bytes())
                .map_err(mcap_err)?;
            let id = self
                .out
                .add_channel(schema, topic, "cdr", &BTreeMap::new())
                .map_err(mcap_err)?;
            self.channels.insert(topic.to_string(), (id, 0));
        }
        let Some((id, seq)) = self.channels.get_mut(topic) else {
            return Ok(());
        };
        *seq += 1;
        let (_, ns) = stamp(t);
        let header = mcap::records::MessageHeader {
            channel_id: *id,
            sequence: *seq,
            log_time: ns,
            publish_time: ns,
        };
        self.out
            .write_to_known_channel(&header, &cdr(msg)?)
            .map_err(mcap_err)
    }
}

/// A robot's pose in a `world` record.
#[derive(serde::Deserialize)]
struct WorldPose {
    id: String,
    x: f64,
    y: f64,
}

/// Writes the journal `text` to `out` as MCAP.
pub fn export<W: Write + Seek>(text: &str, out: W) -> Result<Exported, BagError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .peekable();
    let (i, first) = lines
        .next()
        .ok_or_else(|| bad(0, "empty journal: no header".into()))?;
    let header: JournalHeader<'_> =
        serde_json::from_str(first).map_err(|e| bad(i, e.to_string()))?;
    let out = mcap::WriteOptions::new()
        .compression(None)
        .create(out)
        .map_err(|e| BagError::Mcap(e.to_string()))?;
    let mut x = Exporter {
        bag: Bag {
            out,
            channels: BTreeMap::new(),
        },
        places: header.places.iter().map(|p| p.to_string()).collect(),
        header: &header,
        n: Exported::default(),
        robots: std::collections::BTreeSet::new(),
    };
    if let Some(m) = &header.initial {
        let msg = x.marking(0, 0.0, m.clone());
        x.bag.write(MARKING, "gspn_msgs/msg/Marking", 0.0, &msg)?;
        x.n.markings += 1;
    }
    while let Some((i, line)) = lines.next() {
        let last = lines.peek().is_none();
        let v: serde_json::Value = match serde_json::from_str(line) {
            Ok(v) => v,
            // A run killed mid-write leaves its last line cut short.
            Err(_) if last => {
                x.n.skipped += 1;
                continue;
            }
            Err(e) => return Err(bad(i, e.to_string())),
        };
        if v.get("record").is_some() {
            let r: Record = serde_json::from_value(v).map_err(|e| bad(i, e.to_string()))?;
            x.record(i, r)?;
        } else {
            let e: Event = serde_json::from_value(v).map_err(|e| bad(i, e.to_string()))?;
            x.event(i, e)?;
        }
    }
    let Exporter {
        mut bag,
        mut n,
        robots,
        ..
    } = x;
    n.robots = robots.len() as u64;
    bag.out
        .finish()
        .map_err(|e| BagError::Mcap(e.to_string()))?;
    Ok(n)
}

/// A journal line `i` (0-based) that cannot be read.
fn bad(i: usize, reason: String) -> BagError {
    BagError::Journal {
        line: i + 1,
        reason,
    }
}

/// The export under way: the bag, the journal's header and what was written so far.
struct Exporter<'h, W: Write + Seek> {
    bag: Bag<W>,
    header: &'h JournalHeader<'h>,
    places: Vec<String>,
    n: Exported,
    robots: std::collections::BTreeSet<String>,
}

impl<W: Write + Seek> Exporter<'_, W> {
    /// The marking after firing `seq` (0: the initial one) at model time `t`.
    fn marking(&self, seq: u64, t: f64, tokens: Vec<u32>) -> Marking {
        Marking {
            header: Header {
                stamp: stamp(t).0,
                frame_id: String::new(),
            },
            model_time: t,
            seq,
            places: self.places.clone(),
            tokens,
        }
    }

    /// The name of transition or place `k` (`what`) in the header.
    fn name_of(
        &self,
        names: &[std::borrow::Cow<'_, str>],
        k: usize,
        what: &str,
        i: usize,
    ) -> Result<String, BagError> {
        names
            .get(k)
            .map(|n| n.to_string())
            .ok_or_else(|| bad(i, format!("{what} {k} is not in the header")))
    }

    /// A `record` line: a `world` record's robot poses, each on `/<robot>/pose`; other
    /// records are not exported.
    fn record(&mut self, i: usize, r: Record) -> Result<(), BagError> {
        if &*r.record != "world" {
            return Ok(());
        }
        let poses: Vec<WorldPose> =
            serde_json::from_value(r.data).map_err(|e| bad(i, e.to_string()))?;
        for p in poses {
            let mut msg = PoseStamped::on_map(p.x, p.y, 0.0);
            msg.header = Header {
                stamp: stamp(r.time).0,
                frame_id: MAP_FRAME.into(),
            };
            let topic = format!("/{}/pose", p.id);
            self.bag
                .write(&topic, "geometry_msgs/msg/PoseStamped", r.time, &msg)?;
            self.robots.insert(p.id);
            self.n.poses += 1;
        }
        Ok(())
    }

    /// An event line: a firing (on the firings and marking topics) or a drift alarm.
    fn event(&mut self, i: usize, e: Event) -> Result<(), BagError> {
        let hdr = Header {
            stamp: stamp(e.time).0,
            frame_id: String::new(),
        };
        match e.kind {
            EventKind::Fired {
                transition,
                marking: tokens,
                robots: who,
                ..
            } => {
                self.n.firings += 1;
                let seq = self.n.firings;
                let msg = Firing {
                    header: hdr,
                    model_time: e.time,
                    seq,
                    transition: self.name_of(
                        &self.header.transitions,
                        transition.index(),
                        "transition",
                        i,
                    )?,
                    marking: tokens.to_vec(),
                    robots: who.iter().map(|r| r.to_string()).collect(),
                };
                self.bag
                    .write(FIRINGS, "gspn_msgs/msg/Firing", e.time, &msg)?;
                let marking = self.marking(seq, e.time, tokens.to_vec());
                self.bag
                    .write(MARKING, "gspn_msgs/msg/Marking", e.time, &marking)?;
                self.n.markings += 1;
            }
            EventKind::Drift(d) => {
                let (transition, place) = match d.of {
                    Monitored::Transition(t) => (
                        self.name_of(&self.header.transitions, t.index(), "transition", i)?,
                        String::new(),
                    ),
                    Monitored::Place(p) => (
                        String::new(),
                        self.name_of(&self.header.places, p.index(), "place", i)?,
                    ),
                };
                let msg = msgs::Drift {
                    header: hdr,
                    model_time: e.time,
                    text: format!(
                        "{}{}: observed {:.4}, the net says {:.4} (p {:.1e})",
                        transition, place, d.observed, d.predicted, d.p_value
                    ),
                    transition,
                    place,
                    observed: d.observed,
                    predicted: d.predicted,
                    interval_low: d.interval[0],
                    interval_high: d.interval[1],
                    n: d.n,
                    p_value: d.p_value,
                };
                self.bag.write(DRIFT, "gspn_msgs/msg/Drift", e.time, &msg)?;
                self.n.drifts += 1;
            }
            _ => {}
        }
        Ok(())
    }
}

const FIRINGS: &str = msgs::FIRINGS_TOPIC;
const MARKING: &str = msgs::MARKING_TOPIC;
const DRIFT: &str = msgs::DRIFT_TOPIC;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn model_time_becomes_a_ros_time_and_nanoseconds() {
        let (t, ns) = stamp(12.5);
        assert_eq!((t.sec, t.nanosec, ns), (12, 500_000_000, 12_500_000_000));
        assert_eq!(stamp(-1.0).1, 0);
    }

    #[test]
    fn a_cdr_payload_starts_with_the_little_endian_encapsulation() {
        let b = cdr(&msgs::Heartbeat {
            robot: "r1".into(),
            seq: 7,
        })
        .unwrap();
        // encapsulation, string length 3 ("r1\0"), the bytes, padding to 8, u64 7.
        assert_eq!(
            b,
            [
                0, 1, 0, 0, 3, 0, 0, 0, b'r', b'1', 0, 0, 7, 0, 0, 0, 0, 0, 0, 0
            ]
        );
    }
}
