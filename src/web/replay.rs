//! A recorded run in the viewer (`plan-runner replay --web`): the journal's frames and, when
//! the run had a simulated world, its map and the robots' poses over time (the journal's
//! `map` and `world` side records, see [`crate::world::WorldBackend`]'s doc).
//!
//! **Memory bounded by the window shown** (issue 32: the page used to get the whole run at
//! once, and the server held 4.9 GB for a 100 MB robot journal to send it). The journal is
//! read once when the viewer starts, keeping an index: for every [`WINDOW`] firings, the
//! time of the window's first frame and where its lines start in the file. The page asks for
//! the window its slider is in (`GET /api/replay/window?k=K`), which is read from the file
//! again then, and keeps a few. What is kept for the whole run is what the panels show for
//! the whole run: the robots' stays (the robot timeline) and at most 400 snapshots of the
//! conformance table.

use std::borrow::Cow;
use std::io::{BufRead, BufReader, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use axum::extract::{Query, State};
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::{Deserialize, Serialize};
use serde_json::value::RawValue;
use serde_json::{Value, json};

use super::conform::ReplayRows;
use super::stays::RobotStays;
use super::throughput::Throughput;
use super::{WebState, api};
use crate::net::Net;
use crate::runtime::journal::{
    Entry, Frame, JournalError, JournalReader, Record, Recording, entry,
};

/// A pose record (`world`) as the page gets it: its time and the robots' JSON as written.
type Pose = (f64, Box<RawValue>);

/// Frames per window the page asks for.
pub(crate) const WINDOW: usize = 256;

/// What `GET /api/replay` and `GET /api/replay/window` serve.
#[derive(Debug)]
pub(crate) struct Replay {
    /// Firings in the run.
    firings: usize,
    /// The time of each window's first frame.
    starts: Vec<f64>,
    source: Source,
    /// The journal recorded a world (`map` and `world` records).
    world: bool,
    /// `GET /api/replay`'s answer, made once: the panels' whole-run parts are kept as the
    /// JSON they are sent as (a tenth of the memory of `Value`s).
    outline: axum::body::Bytes,
}

/// Where the frames and poses come from.
#[derive(Debug)]
enum Source {
    /// Given whole (a library caller's frames or recording): the frames and the poses.
    Memory {
        frames: Vec<Frame>,
        poses: Vec<Pose>,
    },
    /// A journal file, read a window at a time.
    File {
        path: PathBuf,
        /// The net as it ran.
        net: Box<Net>,
        /// Per window, where to start reading.
        marks: Vec<Mark>,
        /// Where the last whole line ends (a line cut short after it is never read).
        end: u64,
    },
}

/// Where window `k`'s lines start: its first firing's line (window 0: the first line after
/// the header), and the `world` record before it if any (the robots' pose at the window's
/// start), each as (byte offset, line number).
#[derive(Clone, Copy, Debug)]
struct Mark {
    firing: (u64, usize),
    pose: Option<(u64, usize)>,
}

/// One window as `GET /api/replay/window` sends it: its frames, and the poses recorded over
/// its time.
#[derive(Serialize)]
struct Window {
    k: usize,
    first: usize,
    frames: Vec<Frame>,
    poses: Vec<PoseJson>,
}

/// `{time, robots}`.
#[derive(Serialize)]
struct PoseJson {
    time: f64,
    robots: Box<RawValue>,
}

/// A side record read for its kind and time, its data left as written.
#[derive(Deserialize)]
struct RawRecord<'a> {
    #[serde(borrow)]
    record: Cow<'a, str>,
    time: f64,
    #[serde(borrow, default)]
    data: Option<&'a RawValue>,
}

impl Replay {
    /// The frames of a journal of `net` without a world.
    pub(crate) fn of_frames(net: &Net, frames: Vec<Frame>) -> Replay {
        let conform = super::conform::replay_rows(net, &frames);
        let robots = RobotStays::default().raw_json(net);
        Replay::of_memory(frames, Vec::new(), None, conform, robots)
    }

    /// The frames and the world of `recording`.
    pub(crate) fn of_recording(recording: &Recording) -> Replay {
        let world = recording
            .records("map")
            .next()
            .map(|m| world_of(m, &recording.robots));
        let poses = recording
            .records("world")
            .filter_map(|r| Some((r.time, serde_json::value::to_raw_value(&r.data).ok()?)))
            .collect();
        let frames = recording.frames();
        let conform = super::conform::replay_rows(&recording.net, &frames);
        let robots = RobotStays::of(&recording.events).raw_json(&recording.net);
        Replay::of_memory(frames, poses, world, conform, robots)
    }

    fn of_memory(
        frames: Vec<Frame>,
        poses: Vec<Pose>,
        world: Option<Value>,
        conform: Option<Box<RawValue>>,
        robots: Box<RawValue>,
    ) -> Replay {
        let last = |t: Option<f64>| t.unwrap_or(0.0);
        let end = last(frames.last().map(|f| f.time)).max(last(poses.last().map(|p| p.0)));
        let starts: Vec<f64> = frames.iter().step_by(WINDOW).map(|f| f.time).collect();
        let firings = frames.len().saturating_sub(1);
        let mut throughput = Throughput::default();
        for f in &frames {
            if let Some(name) = &f.transition {
                throughput.fired(f.time, name);
            }
        }
        let panels = Panels {
            world: world.as_ref(),
            conform,
            robots: &robots,
            throughput: &throughput,
        };
        Replay {
            outline: outline(firings, end, &starts, panels),
            firings,
            starts,
            world: world.is_some(),
            source: Source::Memory { frames, poses },
        }
    }

    /// Reads the rest of `journal` (the file at `path`, its header read) once, keeping the
    /// index of its windows and what the panels show for the whole run; with the cut last
    /// line, if any.
    pub(crate) fn of_journal(
        path: &Path,
        mut journal: JournalReader<BufReader<std::fs::File>>,
    ) -> Result<(Replay, Option<JournalError>), JournalError> {
        let net = journal.net().clone();
        let mut table = ReplayRows::new(&net, net.initial_marking().into_vec());
        let mut stays = RobotStays::default();
        let mut throughput = Throughput::default();
        let mut marks = vec![Mark {
            firing: (journal.line_start(), journal.line() + 1),
            pose: None,
        }];
        let mut starts = vec![0.0];
        let (mut firings, mut end, mut file_end) = (0usize, 0.0f64, journal.line_start());
        let (mut world, mut pose) = (None, None);
        while let Some(entry) = journal.next() {
            let at = (journal.line_start(), journal.line());
            match entry? {
                Entry::Event(e) => {
                    end = end.max(e.time);
                    if let Some(f) = e.firing() {
                        firings += 1;
                        if firings % WINDOW == 0 {
                            marks.push(Mark { firing: at, pose });
                            starts.push(f.time);
                        }
                        table.fired(f.time, f.transition, f.marking);
                        throughput.fired(f.time, &net.transition(f.transition).name);
                    }
                    stays.push(&e);
                }
                Entry::Record(r) => {
                    end = end.max(r.time);
                    match &*r.record {
                        "map" if world.is_none() => world = Some(world_of(&r, journal.robots())),
                        "world" => pose = Some(at),
                        _ => {}
                    }
                }
            }
            file_end = journal.offset();
        }
        let torn = journal.torn().cloned();
        let robots = stays.raw_json(&net);
        let panels = Panels {
            world: world.as_ref(),
            conform: table.finish(),
            robots: &robots,
            throughput: &throughput,
        };
        let replay = Replay {
            outline: outline(firings, end, &starts, panels),
            firings,
            starts,
            world: world.is_some(),
            source: Source::File {
                path: path.to_path_buf(),
                net: Box::new(net),
                marks,
                end: file_end,
            },
        };
        Ok((replay, torn))
    }

    /// The firings of the recorded run.
    pub(crate) fn firings(&self) -> usize {
        self.firings
    }

    /// Window `k`: frames `k × WINDOW` up to the next window's first (excluded), and the
    /// poses recorded from the one before the window's first frame to the next window's.
    fn window(&self, k: usize) -> Result<Window, String> {
        let first = k * WINDOW;
        if k >= self.starts.len() {
            return Err(format!(
                "no window {k}: the run has {} (of {WINDOW} frames each)",
                self.starts.len()
            ));
        }
        match &self.source {
            Source::Memory { frames, poses } => {
                let last = (first + WINDOW).min(frames.len());
                let (t0, t1) = (frames[first].time, self.starts.get(k + 1).copied());
                let from = poses.partition_point(|p| p.0 <= t0).saturating_sub(1);
                let to = t1.map_or(poses.len(), |t| {
                    (poses.partition_point(|p| p.0 < t) + 1).min(poses.len())
                });
                Ok(Window {
                    k,
                    first,
                    frames: frames[first..last].to_vec(),
                    poses: poses[from.min(to)..to]
                        .iter()
                        .map(|(time, robots)| PoseJson {
                            time: *time,
                            robots: robots.clone(),
                        })
                        .collect(),
                })
            }
            Source::File {
                path,
                net,
                marks,
                end,
            } => read_window(path, net, marks, *end, self.world, k).map_err(|e| e.to_string()),
        }
    }
}

/// The `world` panel's fixed part: the map and the robots' radius from a `map` record.
fn world_of(map: &Record, robots: &[String]) -> Value {
    json!({
        "map": map.data.get("map").cloned().unwrap_or(Value::Null),
        "radius": map.data.get("radius").cloned().unwrap_or(Value::Null),
        "robots": robots,
    })
}

/// What the panels show for the whole run, in `GET /api/replay`'s answer.
#[derive(Serialize)]
struct Panels<'a> {
    robots: &'a RawValue,
    throughput: &'a Throughput,
    #[serde(skip_serializing_if = "Option::is_none")]
    world: Option<&'a Value>,
    #[serde(skip_serializing_if = "Option::is_none")]
    conform: Option<Box<RawValue>>,
}

/// `GET /api/replay`'s answer (see [`outline_route`]).
fn outline(firings: usize, end: f64, starts: &[f64], panels: Panels<'_>) -> axum::body::Bytes {
    #[derive(Serialize)]
    struct Outline<'a> {
        firings: usize,
        end: f64,
        window: usize,
        starts: &'a [f64],
        #[serde(flatten)]
        panels: Panels<'a>,
    }
    let v = Outline {
        firings,
        end,
        window: WINDOW,
        starts,
        panels,
    };
    serde_json::to_vec(&v).unwrap_or_default().into()
}

/// Reads window `k` of the journal at `path` (see [`Replay::window`]).
fn read_window(
    path: &Path,
    net: &Net,
    marks: &[Mark],
    end: u64,
    world: bool,
    k: usize,
) -> Result<Window, JournalError> {
    let mark = marks[k];
    let stop = marks.get(k + 1).map_or(end, |m| m.firing.0);
    let (offset, first_line) = match mark.pose {
        Some(p) if p.0 < mark.firing.0 => p,
        _ => mark.firing,
    };
    let mut line = first_line - 1;
    let bad = |line: usize, reason: String| JournalError::BadLine { line, reason };
    let io = |e: std::io::Error| bad(first_line, format!("cannot read {}: {e}", path.display()));
    let mut file = std::fs::File::open(path).map_err(io)?;
    file.seek(SeekFrom::Start(offset)).map_err(io)?;
    let mut input = BufReader::new(file);
    let mut frames = Vec::with_capacity(WINDOW);
    if k == 0 {
        frames.push(Frame {
            time: 0.0,
            transition: None,
            tokens: net.initial_marking().into_vec(),
        });
    }
    let mut poses = Vec::new();
    let (mut at, mut buf) = (offset, String::new());
    while at < end {
        buf.clear();
        let n = input.read_line(&mut buf).map_err(io)?;
        if n == 0 {
            break;
        }
        let start = at;
        at += n as u64;
        line += 1;
        let text = buf.trim_end();
        // Past the window: only the first pose after it (for the robots to move towards).
        let past = start >= stop;
        if text.is_empty() || past && !world {
            if past {
                break;
            }
            continue;
        }
        if text.starts_with("{\"record\"") {
            let r: RawRecord<'_> =
                serde_json::from_str(text).map_err(|e| bad(line, e.to_string()))?;
            if r.record == "world"
                && let Some(robots) = r.data
            {
                poses.push(PoseJson {
                    time: r.time,
                    robots: robots.to_owned(),
                });
                if past {
                    break;
                }
            }
        } else if !past && start >= mark.firing.0 {
            let entry = entry(text, net).map_err(|e| bad(line, e.to_string()))?;
            if let Entry::Event(e) = entry
                && let Some(f) = e.firing()
            {
                frames.push(Frame {
                    time: f.time,
                    transition: Some(net.transition(f.transition).name.clone()),
                    tokens: f.marking.to_vec(),
                });
            }
        }
    }
    Ok(Window {
        k,
        first: k * WINDOW,
        frames,
        poses,
    })
}

/// `GET /api/replay`: the run's outline — `{"firings", "end", "window": frames per window,
/// "starts": [each window's first time], "robots": [{robot, stays: [{t0, t1, place,
/// agent}]}], "throughput": {width, counts: {transition: [firings per window]}}, "world"?:
/// {map, radius, robots}, "conform"?: [{time, rows}]}` (404 without a recording; `conform`:
/// the monitor's table of transitions' rates along the run; `throughput`: see
/// [`Throughput`]).
pub(crate) async fn outline_route(State(state): State<WebState>) -> Response {
    match state.inner.replay.get() {
        Some(r) => (
            [(header::CONTENT_TYPE, "application/json")],
            r.outline.clone(),
        )
            .into_response(),
        None => api::error(StatusCode::NOT_FOUND, "no recorded run"),
    }
}

/// Which window `GET /api/replay/window` asks for.
#[derive(Deserialize)]
pub(crate) struct WindowQuery {
    k: usize,
}

/// `GET /api/replay/window?k=K`: `{"k", "first": index of its first frame, "frames":
/// [{time, transition, tokens}], "poses": [{time, robots: [{id, agent, x, y}]}]}` (404
/// without a recording or past the last window). Read from the journal on a blocking thread.
pub(crate) async fn window(
    State(state): State<WebState>,
    Query(q): Query<WindowQuery>,
) -> Response {
    let Some(replay) = state.inner.replay.get().cloned() else {
        return api::error(StatusCode::NOT_FOUND, "no recorded run");
    };
    match tokio::task::spawn_blocking(move || replay.window(q.k)).await {
        Ok(Ok(w)) => axum::Json(w).into_response(),
        Ok(Err(e)) => api::error(StatusCode::NOT_FOUND, e),
        Err(e) => api::error(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()),
    }
}
