//! The live view of a running plan: the run's events folded into one snapshot (marking,
//! clock, agents, recent events), pushed to every browser over a WebSocket.
//!
//! A browser that connects — first, late, or again after losing the connection — gets the
//! net first, then the current snapshot, then a new snapshot whenever something changed, at
//! most one per [`FRAME`]: events are coalesced to what a browser can draw, and a slow
//! browser only ever skips to the latest state (the fold never waits for it).

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};
use std::time::Duration;

use axum::extract::State;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::response::Response;
use serde_json::{Map, Value, json};
use tokio::sync::watch;

use crate::net::Net;
use crate::runtime::{AgentInfo, EventKind, Events, Outcome, Received, RuntimeHandle};
use crate::web::WebState;
use crate::web::api::net_json;
use crate::web::limits::{WS_BUFFER, WS_MAX_INCOMING, WS_SEND_TIMEOUT};
use crate::web::stays::RobotStays;
use crate::web::throughput::Throughput;

/// Shortest time between two snapshots sent to one browser.
pub const FRAME: Duration = Duration::from_millis(50);

/// Events kept for the log (the oldest are dropped past this).
const LOG_KEEP: usize = 500;

/// Token counts kept for a late page's history (markings × places; the oldest markings are
/// dropped past this): 8 MB, 20,000 markings of a 100-place net.
const HISTORY_CELLS: usize = 2_000_000;

/// A running plan as the viewer shows it. Cheap to clone.
#[derive(Clone, Debug)]
pub struct LiveRun {
    inner: Arc<LiveInner>,
}

#[derive(Debug)]
struct LiveInner {
    handle: Arc<RuntimeHandle>,
    snapshot: Mutex<Snapshot>,
    version: watch::Sender<u64>,
    /// The simulated world (map and robots), when a backend feeds one.
    world: OnceLock<watch::Receiver<Value>>,
    /// The agents as the supervisor listed them after the latest firing: what the page
    /// shows once the run is over and the supervisor lists none.
    last_agents: Mutex<Vec<AgentInfo>>,
    /// The run's monitor (`run --monitor`), whose statistics the page tabulates.
    monitor: OnceLock<crate::conform::SharedMonitor>,
}

#[derive(Debug)]
struct Snapshot {
    tokens: Vec<u32>,
    time: f64,
    firings: u64,
    stopped: Option<String>,
    /// Events missed because the fold fell behind the bus.
    lagged: u64,
    log: VecDeque<Value>,
    /// The marking after each firing so far (`(time, tokens)`, the oldest dropped past
    /// [`HISTORY_CELLS`]), and each robot's stays: what a page that joins late is sent first.
    history: VecDeque<(f64, Vec<u32>)>,
    stays: RobotStays,
    /// Firings per transition per window of model time since the start.
    throughput: Throughput,
}

impl LiveRun {
    /// Follows `handle`'s run through `events` (take them with
    /// [`RuntimeHandle::events`] before wrapping the handle in an `Arc`). Spawns the task
    /// that folds the events: call it inside a tokio runtime.
    pub fn start(handle: Arc<RuntimeHandle>, events: Events) -> LiveRun {
        let tokens = handle.net().initial_marking().into_vec();
        let (version, _) = watch::channel(0);
        let live = LiveRun {
            inner: Arc::new(LiveInner {
                handle,
                snapshot: Mutex::new(Snapshot {
                    tokens,
                    time: 0.0,
                    firings: 0,
                    stopped: None,
                    lagged: 0,
                    log: VecDeque::new(),
                    history: VecDeque::new(),
                    throughput: Throughput::default(),
                    stays: RobotStays::default(),
                }),
                version,
                world: OnceLock::new(),
                last_agents: Mutex::new(Vec::new()),
                monitor: OnceLock::new(),
            }),
        };
        tokio::spawn(live.clone().fold(events));
        live
    }

    /// Adds a feed of the simulated world, drawn as a 2D map beside the net: the latest
    /// value of `rx` is served at `GET /api/live/world` and sent as `"world"` in every state
    /// frame (a new value wakes the frames like an event does). Plain JSON, so the viewer
    /// does not depend on any simulator; metres, y up:
    ///
    /// ```json
    /// {"time": 1.5,
    ///  "map": {"locations": [{"name": "L1", "x": 0.0, "y": 0.0}],
    ///          "edges": [["L1", "L2"]],
    ///          "walls": [[0.0, 0.0, 10.0, 0.0]],
    ///          "obstacles": [{"x": 4.0, "y": 2.0, "w": 1.0, "h": 0.5}]},
    ///  "robots": [{"id": "r1", "agent": 3, "x": 1.0, "y": 2.0, "radius": 0.3}]}
    /// ```
    ///
    /// `x, y` of an obstacle is its lower-left corner. A second feed is ignored (the first
    /// one stays).
    pub fn with_world(self, rx: watch::Receiver<Value>) -> LiveRun {
        let _ = self.inner.world.set(rx);
        self
    }

    /// Adds the run's monitor (the one given to the run as its watcher): every state frame
    /// carries its statistics as `"conform"` (see `src/web/conform.rs`), which the page shows
    /// as a table, drifting items highlighted. A second monitor is ignored.
    pub fn with_monitor(self, monitor: crate::conform::SharedMonitor) -> LiveRun {
        let _ = self.inner.monitor.set(monitor);
        self
    }

    /// The latest world value, if there is a feed.
    fn world(&self) -> Option<Value> {
        self.inner.world.get().map(|rx| rx.borrow().clone())
    }

    /// The run's handle (to stop it, or wait for it).
    pub fn handle(&self) -> &Arc<RuntimeHandle> {
        &self.inner.handle
    }

    fn net(&self) -> &Net {
        self.inner.handle.net()
    }

    fn snapshot(&self) -> MutexGuard<'_, Snapshot> {
        self.inner
            .snapshot
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn last_agents(&self) -> MutexGuard<'_, Vec<AgentInfo>> {
        self.inner
            .last_agents
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    async fn fold(self, mut events: Events) {
        while let Some(r) = events.recv().await {
            // Where every agent (and robot) is after a firing, from the supervisor itself
            // (it answers after the firing it reported): kept for after the run.
            if matches!(&r, Received::Event(e) if matches!(e.kind, EventKind::Fired { .. } | EventKind::AgentSpawned { .. }))
            {
                let agents = self.inner.handle.agents().await;
                if !agents.is_empty() {
                    *self.last_agents() = agents;
                }
            }
            {
                let net = self.net();
                let mut s = self.snapshot();
                match r {
                    Received::Lagged(n) => s.lagged += n,
                    Received::Event(e) => {
                        s.time = s.time.max(e.time);
                        s.stays.push(&e);
                        match &e.kind {
                            EventKind::Fired {
                                marking,
                                transition,
                                ..
                            } => {
                                s.firings += 1;
                                s.throughput
                                    .fired(e.time, &net.transition(*transition).name);
                                s.tokens.copy_from_slice(marking.as_slice());
                                let kept = (HISTORY_CELLS / marking.len().max(1)).max(1);
                                if s.history.len() >= kept {
                                    s.history.pop_front();
                                }
                                s.history.push_back((e.time, marking.to_vec()));
                            }
                            EventKind::Stopped { reason } => s.stopped = Some(reason.to_string()),
                            _ => {}
                        }
                        if s.log.len() == LOG_KEEP {
                            s.log.pop_front();
                        }
                        let mut v = serde_json::to_value(&e).unwrap_or(Value::Null);
                        v["text"] = json!(describe(net, &e.kind));
                        if let Some(m) = v.as_object_mut() {
                            m.remove("marking");
                        }
                        s.log.push_back(v);
                    }
                }
            }
            self.inner.version.send_modify(|v| *v += 1);
        }
        // The bus closed: the run is over.
        let summary = self.inner.handle.wait().await;
        {
            let mut s = self.snapshot();
            s.tokens.copy_from_slice(summary.marking.as_slice());
            s.stopped.get_or_insert_with(|| summary.stopped.to_string());
        }
        self.inner.version.send_modify(|v| *v += 1);
    }

    /// `{"type": "history", "frames": [{time, tokens}], "robots": [{robot, stays}],
    /// "throughput": {width, counts}, "after": seq}`: the initial marking and the marking
    /// after each firing kept, each robot's stays so far, the firings per transition per
    /// window of model time up to event `after`.
    fn history_json(&self) -> Value {
        let net = self.net();
        let s = self.snapshot();
        let initial = (s.history.len() as u64 == s.firings)
            .then(|| json!({ "time": 0.0, "tokens": net.initial_marking().as_slice() }));
        let frames: Vec<Value> = initial
            .into_iter()
            .chain(
                s.history
                    .iter()
                    .map(|(t, m)| json!({ "time": t, "tokens": m })),
            )
            .collect();
        // The last event the counts include: the page counts the log's firings after it.
        let after = s.log.back().and_then(|v| v.get("seq")).cloned();
        json!({
            "type": "history",
            "frames": frames,
            "robots": s.stays.json(net),
            "throughput": s.throughput,
            "after": after,
        })
    }

    /// The snapshot as JSON, with the log entries after `after_seq` (all kept ones if `None`).
    async fn state_json(&self, after_seq: Option<u64>) -> Value {
        let mut agents = self.inner.handle.agents().await;
        if agents.is_empty() {
            agents = self.last_agents().clone();
        }
        let net = self.net();
        let state_name = |a: &AgentInfo| {
            serde_json::to_value(a.state)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default()
        };
        let agent_list: Vec<Value> = agents
            .iter()
            .map(|a| {
                json!({
                    "id": a.id.0, "place": net.place(a.place).name, "state": state_name(a),
                    "robot": a.robot.as_deref(),
                })
            })
            .collect();
        let mut per_place: Vec<Map<String, Value>> = vec![Map::new(); net.place_count()];
        for a in &agents {
            let state = serde_json::to_value(a.state).unwrap_or(Value::Null);
            let key = state.as_str().unwrap_or("?").to_string();
            let count = per_place[a.place.index()].entry(key).or_insert(json!(0u64));
            *count = json!(count.as_u64().unwrap_or(0) + 1);
        }
        let agents_by_place: Map<String, Value> = net
            .places()
            .iter()
            .zip(per_place)
            .filter(|(_, m)| !m.is_empty())
            .map(|(p, m)| (p.name.clone(), Value::Object(m)))
            .collect();
        let s = self.snapshot();
        let log: Vec<&Value> = s
            .log
            .iter()
            .filter(|e| match after_seq {
                Some(after) => e["seq"].as_u64().is_some_and(|q| q > after),
                None => true,
            })
            .collect();
        let firable: Vec<&str> = net
            .firable(&s.tokens)
            .into_iter()
            .map(|t| net.transition(t).name.as_str())
            .collect();
        let mut v = json!({
            "type": "state",
            "firable": firable,
            "tokens": s.tokens,
            "marking": crate::analysis::report::by_place(net, &s.tokens),
            "text": net.format_marking(&s.tokens),
            "time": s.time,
            "firings": s.firings,
            "stopped": s.stopped,
            "lagged": s.lagged,
            "agents": agents_by_place,
            "agent_list": agent_list,
            "log": log,
        });
        drop(s);
        if let Some(world) = self.world() {
            v["world"] = world;
        }
        if let Some(m) = self.inner.monitor.get() {
            v["conform"] = super::conform::rows(net, m);
        }
        v
    }
}

/// One line for the event log, with names instead of indices.
fn describe(net: &Net, kind: &EventKind) -> String {
    let place = |p: crate::net::PlaceId| net.place(p).name.as_str();
    match kind {
        EventKind::Fired {
            transition, robots, ..
        } => {
            let name = &net.transition(*transition).name;
            if robots.is_empty() {
                format!("{name} fired")
            } else {
                format!("{name} fired ({})", robots.join(", "))
            }
        }
        EventKind::AgentSpawned {
            agent,
            place: p,
            robot,
        } => match robot {
            Some(r) => format!("agent {} ({r}) spawned in {}", agent.0, place(*p)),
            None => format!("agent {} spawned in {}", agent.0, place(*p)),
        },
        EventKind::ActionStarted {
            agent, place: p, ..
        } => format!("agent {} started the action of {}", agent.0, place(*p)),
        EventKind::ActionEnded {
            agent,
            place: p,
            outcome,
        } => {
            let outcome = match outcome {
                Outcome::Fire(t) => format!("fire {}", net.transition(*t).name),
                Outcome::Decide => "decide".to_string(),
                Outcome::Failed(why) => format!("failed: {why}"),
                Outcome::Cancelled => "cancelled".to_string(),
            };
            format!(
                "agent {} ended the action of {}: {outcome}",
                agent.0,
                place(*p)
            )
        }
        EventKind::ActionOutput {
            agent,
            place: p,
            stream,
            line,
        } => match stream {
            crate::runtime::OutputStream::Stdout => {
                format!("agent {} in {}: {line}", agent.0, place(*p))
            }
            crate::runtime::OutputStream::Stderr => {
                format!("agent {} in {} (stderr): {line}", agent.0, place(*p))
            }
        },
        EventKind::AgentEnded { agent } => format!("agent {} ended", agent.0),
        EventKind::Error { message } => format!("error: {message}"),
        EventKind::Warning { message } => format!("warning: {message}"),
        EventKind::Stopped { reason } => format!("stopped: {reason}"),
        EventKind::Drift(d) => format!("drift: {}", d.describe(net)),
    }
}

/// `GET /api/live/state`: the current snapshot (404 without a live run).
pub(crate) async fn state(State(state): State<WebState>) -> Response {
    use axum::response::IntoResponse;
    match state.live() {
        Some(live) => axum::Json(live.state_json(None).await).into_response(),
        None => no_live(),
    }
}

/// `GET /api/live/world`: the latest world value (404 without a live run or a world feed).
pub(crate) async fn world(State(state): State<WebState>) -> Response {
    use axum::response::IntoResponse;
    match state.live().map(|l| l.world()) {
        Some(Some(w)) => axum::Json(w).into_response(),
        Some(None) => crate::web::api::error(
            axum::http::StatusCode::NOT_FOUND,
            "this run has no simulated world",
        ),
        None => no_live(),
    }
}

/// `POST /api/live/stop`: asks the run to stop.
pub(crate) async fn stop(State(state): State<WebState>) -> Response {
    use axum::response::IntoResponse;
    match state.live() {
        Some(live) => {
            live.handle().stop();
            axum::Json(json!({ "stopping": true })).into_response()
        }
        None => no_live(),
    }
}

fn no_live() -> Response {
    crate::web::api::error(axum::http::StatusCode::NOT_FOUND, "no live run")
}

/// `GET /api/live/ws`: the net, the snapshot, then coalesced snapshots.
pub(crate) async fn ws(State(state): State<WebState>, upgrade: WebSocketUpgrade) -> Response {
    use axum::response::IntoResponse;
    match state.live().cloned() {
        Some(live) => upgrade
            .read_buffer_size(WS_BUFFER)
            .write_buffer_size(WS_BUFFER)
            .max_message_size(WS_MAX_INCOMING)
            .max_frame_size(WS_MAX_INCOMING)
            .on_upgrade(move |socket| follow(socket, live))
            .into_response(),
        None => no_live(),
    }
}

/// Sends `text`; false when the browser went away or has not taken it within
/// [`WS_SEND_TIMEOUT`] — then it is told so in a close frame (`1008`, "too slow") and
/// dropped, as a slow browser is not buffered for.
async fn send(socket: &mut WebSocket, text: String) -> bool {
    match tokio::time::timeout(WS_SEND_TIMEOUT, socket.send(Message::Text(text.into()))).await {
        Ok(sent) => sent.is_ok(),
        Err(_) => {
            let close = Message::Close(Some(axum::extract::ws::CloseFrame {
                code: axum::extract::ws::close_code::POLICY,
                reason: "too slow: the viewer drops a browser that does not read its updates"
                    .into(),
            }));
            let _ = tokio::time::timeout(WS_SEND_TIMEOUT, socket.send(close)).await;
            false
        }
    }
}

async fn follow(mut socket: WebSocket, live: LiveRun) {
    let mut net = net_json(live.net(), live.handle().seed(), None, false);
    net["type"] = json!("net");
    if !send(&mut socket, net.to_string()).await {
        return;
    }
    // The run so far, for a page that joins late: its plot and robot timeline start at the
    // beginning of the run, not at the page's arrival.
    if !send(&mut socket, live.history_json().to_string()).await {
        return;
    }
    let mut version = live.inner.version.subscribe();
    let mut world = live.inner.world.get().cloned();
    let mut last_seq: Option<u64> = None;
    loop {
        version.borrow_and_update();
        if let Some(w) = &mut world {
            w.borrow_and_update();
        }
        let msg = live.state_json(last_seq).await;
        if let Some(seq) = msg["log"]
            .as_array()
            .and_then(|l| l.last())
            .and_then(|e| e["seq"].as_u64())
        {
            last_seq = Some(seq);
        }
        if !send(&mut socket, msg.to_string()).await {
            return;
        }
        tokio::time::sleep(FRAME).await;
        let world_changed = async {
            match &mut world {
                Some(w) => w.changed().await.is_ok(),
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            changed = version.changed() => if changed.is_err() { return },
            fed = world_changed => if !fed {
                // The feed ended: keep its last value, stop waiting on it.
                world = None;
            },
            incoming = socket.recv() => match incoming {
                Some(Ok(Message::Close(_))) | None | Some(Err(_)) => return,
                Some(Ok(_)) => {}
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::describe;
    use crate::net::{NetBuilder, Servers};
    use crate::runtime::{AgentId, EventKind, Outcome};

    #[test]
    fn log_lines_name_agents_places_transitions_and_robots() {
        let mut b = NetBuilder::new("n");
        let p = b.place("p1:Check_L1", 1);
        let t = b.exponential("t1:Temperature_High_L1", 1.0, Servers::Single);
        b.input(p, t, 1);
        let net = b.build().unwrap();
        let ended = EventKind::ActionEnded {
            agent: AgentId(3),
            place: p,
            outcome: Outcome::Fire(t),
        };
        assert_eq!(
            describe(&net, &ended),
            "agent 3 ended the action of p1:Check_L1: fire t1:Temperature_High_L1"
        );
        let fired = EventKind::Fired {
            transition: t,
            consumed: vec![AgentId(3)],
            produced: vec![],
            marking: net.initial_marking(),
            robots: vec![Arc::from("r2")],
        };
        assert_eq!(describe(&net, &fired), "t1:Temperature_High_L1 fired (r2)");
        let spawned = EventKind::AgentSpawned {
            agent: AgentId(0),
            place: p,
            robot: Some(Arc::from("r1")),
        };
        assert_eq!(
            describe(&net, &spawned),
            "agent 0 (r1) spawned in p1:Check_L1"
        );
    }
}
