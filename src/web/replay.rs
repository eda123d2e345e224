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

use std::io::{BufReader, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use axum::extract::{Query, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde_json::{Value, json};

use super::conform::ReplayRows;
use super::stays::RobotStays;
use super::{WebState, api};
use crate::net::Net;
use crate::runtime::journal::{Entry, Frame, JournalError, JournalReader, Record, Recording};

/// Frames per window the page asks for.
pub(crate) const WINDOW: usize = 256;

/// What `GET /api/replay` and `GET /api/replay/window` serve.
#[derive(Debug)]
pub(crate) struct Replay {
    /// Firings in the run.
    firings: usize,
    /// The model time of the last event or record.
    end: f64,
    /// The time of each window's first frame.
    starts: Vec<f64>,
    source: Source,
    /// `{"map", "radius", "robots"}` when the journal recorded a world.
    world: Option<Value>,
    /// The conformance table along the run (`[{time, rows}]`, see [`ReplayRows`]).
    conform: Option<Value>,
    /// Each robot's stays in places (`[{robot, stays}]`, see [`RobotStays`]), empty when
    /// no robot was bound.
    robots: Value,
}

/// Where the frames and poses come from.
#[derive(Debug)]
enum Source {
    /// Given whole (a library caller's frames or recording): the frames and the poses.
    Memory {
        frames: Vec<Frame>,
        poses: Vec<(f64, Value)>,
    },
    /// A journal file, read a window at a time.
    File {
        path: PathBuf,
        /// The net as it ran.
        net: Net,
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

/// One window: its frames, and the poses recorded over its time.
struct Window {
    first: usize,
    frames: Vec<Frame>,
    poses: Vec<(f64, Value)>,
}

impl Replay {
    /// The frames of a journal of `net` without a world.
    pub(crate) fn of_frames(net: &Net, frames: Vec<Frame>) -> Replay {
        let conform = super::conform::replay_rows(net, &frames);
        Replay::of_memory(frames, Vec::new(), None, conform, Value::Array(Vec::new()))
    }

    /// The frames and the world of `recording`.
    pub(crate) fn of_recording(recording: &Recording) -> Replay {
        let world = recording
            .records("map")
            .next()
            .map(|m| world_of(m, &recording.robots));
        let poses = recording
            .records("world")
            .map(|r| (r.time, r.data.clone()))
            .collect();
        let frames = recording.frames();
        let conform = super::conform::replay_rows(&recording.net, &frames);
        let robots = RobotStays::of(&recording.events).json(&recording.net);
        Replay::of_memory(frames, poses, world, conform, robots)
    }

    fn of_memory(
        frames: Vec<Frame>,
        poses: Vec<(f64, Value)>,
        world: Option<Value>,
        conform: Option<Value>,
        robots: Value,
    ) -> Replay {
        let last = |t: Option<f64>| t.unwrap_or(0.0);
        let end = last(frames.last().map(|f| f.time)).max(last(poses.last().map(|p| p.0)));
        Replay {
            firings: frames.len().saturating_sub(1),
            end,
            starts: frames.iter().step_by(WINDOW).map(|f| f.time).collect(),
            source: Source::Memory { frames, poses },
            world,
            conform,
            robots,
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
        let replay = Replay {
            firings,
            end,
            starts,
            world,
            conform: table.finish(),
            robots: stays.json(&net),
            source: Source::File {
                path: path.to_path_buf(),
                net,
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
                    first,
                    frames: frames[first..last].to_vec(),
                    poses: poses[from.min(to)..to].to_vec(),
                })
            }
            Source::File {
                path,
                net,
                marks,
                end,
            } => read_window(path, net, marks, *end, self.world.is_some(), k)
                .map_err(|e| e.to_string()),
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
    let (offset, line) = match mark.pose {
        Some(p) if p.0 < mark.firing.0 => p,
        _ => mark.firing,
    };
    let io = |e: std::io::Error| JournalError::BadLine {
        line,
        reason: format!("cannot read {}: {e}", path.display()),
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    file.seek(SeekFrom::Start(offset)).map_err(io)?;
    let mut reader = JournalReader::resume(BufReader::new(file), net.clone(), line, offset);
    let mut frames = Vec::with_capacity(WINDOW);
    if k == 0 {
        frames.push(Frame {
            time: 0.0,
            transition: None,
            tokens: net.initial_marking().into_vec(),
        });
    }
    let mut poses = Vec::new();
    while let Some(entry) = reader.next() {
        let start = reader.line_start();
        // Past the window: only the first pose after it (for the robots to move towards).
        let past = start >= stop;
        if past && !world {
            break;
        }
        match entry? {
            Entry::Event(e) if !past && start >= mark.firing.0 => {
                if let Some(f) = e.firing() {
                    frames.push(Frame {
                        time: f.time,
                        transition: Some(net.transition(f.transition).name.clone()),
                        tokens: f.marking.to_vec(),
                    });
                }
            }
            Entry::Record(r) if &*r.record == "world" => {
                poses.push((r.time, r.data));
                if past {
                    break;
                }
            }
            _ => {}
        }
    }
    Ok(Window {
        first: k * WINDOW,
        frames,
        poses,
    })
}

/// `GET /api/replay`: the run's outline — `{"firings", "end", "window": frames per window,
/// "starts": [each window's first time], "robots": [{robot, stays: [{t0, t1, place,
/// agent}]}], "world"?: {map, radius, robots}, "conform"?: [{time, rows}]}` (404 without a
/// recording; `conform`: the monitor's table of transitions' rates along the run).
pub(crate) async fn outline(State(state): State<WebState>) -> Response {
    match state.inner.replay.get() {
        Some(r) => {
            let mut v = json!({
                "firings": r.firings,
                "end": r.end,
                "window": WINDOW,
                "starts": r.starts,
                "robots": r.robots,
            });
            if let Some(w) = &r.world {
                v["world"] = w.clone();
            }
            if let Some(c) = &r.conform {
                v["conform"] = c.clone();
            }
            axum::Json(v).into_response()
        }
        None => api::error(StatusCode::NOT_FOUND, "no recorded run"),
    }
}

/// Which window `GET /api/replay/window` asks for.
#[derive(serde::Deserialize)]
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
    let read = tokio::task::spawn_blocking(move || replay.window(q.k)).await;
    match read {
        Ok(Ok(w)) => {
            let poses: Vec<Value> = w
                .poses
                .into_iter()
                .map(|(time, robots)| json!({ "time": time, "robots": robots }))
                .collect();
            axum::Json(json!({
                "k": q.k,
                "first": w.first,
                "frames": w.frames,
                "poses": poses,
            }))
            .into_response()
        }
        Ok(Err(e)) => api::error(StatusCode::NOT_FOUND, &e),
        Err(e) => api::error(StatusCode::INTERNAL_SERVER_ERROR, &e.to_string()),
    }
}
