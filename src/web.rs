//! The viewer (feature `web`): an axum server that draws a net in the browser, plays its
//! token game, and shows its analysis.
//!
//! Every asset (HTML, JavaScript, CSS — plain, hand-written, no framework) is compiled into
//! the binary ([`ASSETS`]). The page draws a net in SVG, or past 1,500 nodes on a canvas (the
//! test hooks then sit on hidden elements), and a live run's simulated world as a 2D map.
//! Every response forbids the page to load anything from another origin
//! (`Content-Security-Policy: default-src 'self'`), so the viewer works with the network off.
//!
//! # API
//!
//! | route | what |
//! |---|---|
//! | `GET /api/net` | places (name, tokens, capacity, x, y), transitions (name, kind, rate or weight and priority, servers, x, y), arcs (kind, place, transition, weight, bend points), `layout`: `file` or `layered` ([`layout::choose`]), `layout_note`: why the file's positions were set aside, `other_layout`: `{layout, places: [[x, y]], transitions, arcs}` the other one when the file has positions |
//! | `GET /api/sim/state?trace=K` | `seed, time, firings, marking {place: k}, tokens [k], enabled, firable, vanishing, dead, trace` (last K firings) |
//! | `POST /api/sim/reset {seed}` | back to the initial marking, with that seed |
//! | `POST /api/sim/step {n}` | fire `n` transitions drawn by the token game: after a reset with seed S, `n` steps are exactly `plan-runner simulate --seed S --steps n` |
//! | `POST /api/sim/fire {transition}` | fire one firable transition by hand (409 if it may not fire) |
//! | `GET /api/sim/wait?after=V` | the state (as `/api/sim/state`, with its `version`) as soon as its version differs from `V` — at once if it already does, else when a request (from any tab) changes the token game, or after 20 s unchanged: every open page follows the same session |
//! | `GET /api/analysis` | properties, steady-state mean tokens and throughputs, dead markings with a firing sequence to each; `{error, kind}` (422) for an unbounded net; starts the analysis if needed and waits for it (409 `kind: "cancelled"` if it is cancelled meanwhile) |
//! | `POST /api/analysis/start` | starts the analysis on a blocking thread (unless it is running or done); the progress |
//! | `GET /api/analysis/progress` | `{state: idle\|running\|cancelling\|cancelled\|done, phase: "state space"\|"properties"\|"steady state", markings, seconds}`: markings found so far by the state-space search |
//! | `POST /api/analysis/cancel` | stops a running analysis (the search within one block of ~1,000 markings, the steady-state solver at its next sweep, the properties before they start); the progress |
//! | `POST /api/analysis/query {transient: [t], prob: [expr]}` | on the finished analysis's state space, as `plan-runner analyze --json --transient t,.. --prob expr ..`: `{steady_state: {probability: {expr: p}}, transient: [{t, mean_tokens, throughput, probability}]}`; 409 before an analysis finished, 400 for a bad time or predicate, 409 `{kind: "cancelled", progress}` when the question is cancelled (by `/api/analysis/query/cancel`, a newer question, an edit, or its request going away) |
//! | `GET /api/analysis/query/progress` | the question's `{state: idle\|running\|cancelling\|cancelled\|done, phase: "transient t=…"\|"probabilities", point, points, iterations, of, seconds}`: the time point the transient solver works towards (of the times asked, earliest first) and its iterations (products with the generator) done of planned |
//! | `POST /api/analysis/query/cancel` | stops a running question (the transient solver within one iteration); its progress |
//! | `GET /api/mode` | `{"live": bool, "replay": bool}`: a running plan ([`LiveRun`]), a journal ([`crate::runtime::journal::read_journal`]), or the token game |
//! | `POST /api/layout {places: [[x, y]], transitions: [[x, y]]}` | `{"pnpro": "..."}`: the net with these positions as a GreatSPN project ("save layout") |
//! | `GET /api/edit` | `{editable, reason, save_to, history {version, edits, undo, redo}}`: whether the net may be edited (not a live run, a replay, or a policy or rewards without their plan file), where "save" writes, the labels of the edits undo and redo would take back or do again |
//! | `POST /api/edit {op, ...}` | one edit of the net ([`edit`](self#editing)): `{net, history, state}` — the new net as `/api/net` gives it (with its `version`, also in every token-game state as `net_version`), the history, the token game restarted on it; 422 `{error}` when refused (the net is unchanged), also when the plan served would no longer load with the edited net |
//! | `POST /api/edit/undo`, `POST /api/edit/redo` | back to the version before the last edit, on to the one after; as `POST /api/edit`; 409 when there is nothing to undo or redo |
//! | `POST /api/edit/export {format: "pnpro"\|"pipe", places, transitions}` | `{text, file}`: the current net (with the page's positions) as a GreatSPN project or a PIPE net, to download |
//! | `POST /api/edit/save {places, transitions}` | writes the current net to the file of `serve --save-to PATH` ([`WebState::saving_to`]) in its format; `{saved, format, bytes}`; 409 without one |
//! | `GET /api/replay` | a journal's outline: `{"firings", "end", "window": frames per window, "starts": [each window's first time], "robots": [{robot, stays: [{t0, t1, place, agent}]}]}`, `world: {map, radius, robots}` when it recorded a simulated world, `conform: [{time, rows}]` |
//! | `GET /api/replay/window?k=K` | window K of the run: `{"k", "first", "frames": [{time, transition, tokens}], "poses": [{time, robots: [{id, agent, x, y}]}]}`, read from the journal when asked |
//! | `GET /api/live/state` | the live run's snapshot: `tokens, marking, time, firings, stopped, agents {place: {state: n}}, log`, and `world` with a world feed |
//! | `GET /api/live/world` | the latest value of the run's simulated world ([`LiveRun::with_world`]: map and robots, metres, y up); 404 without a feed |
//! | `POST /api/live/stop` | asks the live run to stop |
//! | `GET /api/live/ws` | WebSocket: `{"type": "net", ...}` first, then `{"type": "history", "frames": [{time, tokens}], "robots": [{robot, stays}]}` (the run so far), then `{"type": "state", ...}` snapshots (log entries since the previous one, `world` with a world feed), at most one per [`FRAME`]; a new event or world value wakes the next one |
//!
//! # Editing
//!
//! The page edits the net as GreatSPN's editor does (places, transitions, arcs, their
//! names and parameters, undo and redo) by sending one operation at a time to `POST
//! /api/edit`. The server rebuilds the net with it and checks it as the readers check a
//! file (a whole number ≥ 0 for a marking, a finite rate > 0, a weight ≥ 0, unique names,
//! arcs between a place and a transition, ...): a refused edit answers its reason and
//! leaves the net as it was. Every version is kept (undo and redo move between them). The
//! token game and the analysis panel then use the edited net, and every open page redraws
//! it. The net of a plan ([`WebState::with_plan`]) is checked against the plan after every
//! edit, undo and redo by the plan reader's own checks: an edit that would leave the policy
//! or a reward (a role, the stop condition, the map) naming a node that is gone, or no
//! longer of the kind it needs, is refused with the reader's message and the plan's line;
//! an accepted one is played and analysed under the plan's policy resolved against it. Saving writes GreatSPN's PNPRO or PIPE XML through the same writers as
//! `plan-runner convert`, to the file named on the command line only.
//!
//! # Security
//!
//! The viewer has no accounts: whoever can send it requests can drive the token game and
//! stop a live run. So it binds the loopback unless told otherwise (`plan-runner serve
//! --addr` and `run --web` refuse a non-loopback address without `--allow-remote`), and it
//! checks every request before any route runs, so that a page on another site cannot use
//! the visitor's browser to reach it:
//!
//! | check | refused with |
//! |---|---|
//! | `Host` names this server: `localhost`, `127.0.0.1`, `[::1]` or the bound IP, with the bound port (any IP literal when bound to a non-loopback address; never another name, which defeats DNS rebinding) | 421 Misdirected Request |
//! | `Origin`, when sent, is the page's own (`http://` + `Host`); this covers the live websocket | 403 Forbidden |
//! | `POST` requests say `Content-Type: application/json` (what a cross-origin form or `no-cors` fetch cannot send) | 415 Unsupported Media Type |
//!
//! Every response carries `Content-Security-Policy` ([`CONTENT_SECURITY_POLICY`]),
//! `X-Content-Type-Options: nosniff` and `Referrer-Policy: no-referrer`.
//!
//! ```no_run
//! # async fn demo(net: gspn::net::Net) -> std::io::Result<()> {
//! let state = gspn::web::WebState::new(net, None, 42);
//! let listener = tokio::net::TcpListener::bind("127.0.0.1:8080").await?;
//! gspn::web::serve(listener, state).await
//! # }
//! ```

mod analysis_job;
mod api;
mod conform;
mod edit;
mod greatspn;
mod guard;
pub mod layout;
pub(crate) mod limits;
mod live;
mod replay;
mod report;
mod server;
mod session;
mod stays;
mod throughput;

use std::net::SocketAddr;
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};

use axum::Router;
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use serde_json::{Value, json};
use tokio::net::TcpListener;

use crate::analysis::decision::RewardSpec;
use crate::net::Net;
use crate::policy::Policy;
use crate::runtime::journal::{Frame, Recording};
pub use edit::routes::SaveFormatError;
pub use live::{FRAME, LiveRun};
use session::Session;

/// Markings the analysis panel explores before it gives up.
pub const DEFAULT_MAX_STATES: usize = 2_000_000;

/// The policy every response carries: nothing from another origin, ever.
pub const CONTENT_SECURITY_POLICY: &str = "default-src 'self'; img-src 'self' data:; \
     connect-src 'self'; style-src 'self'; script-src 'self'; object-src 'none'; \
     base-uri 'none'; frame-ancestors 'none'";

/// A file the page loads, compiled into the binary.
#[derive(Clone, Copy, Debug)]
pub struct Asset {
    /// The route it is served at.
    pub path: &'static str,
    /// Its `Content-Type`.
    pub mime: &'static str,
    /// Its text.
    pub body: &'static str,
}

/// Every asset of the page.
pub const ASSETS: &[Asset] = &[
    Asset {
        path: "/",
        mime: "text/html; charset=utf-8",
        body: include_str!("web/assets/index.html"),
    },
    Asset {
        path: "/app.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/app.js"),
    },
    Asset {
        path: "/canvas.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/canvas.js"),
    },
    Asset {
        path: "/map.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/map.js"),
    },
    Asset {
        path: "/analysis.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/analysis.js"),
    },
    Asset {
        path: "/conform.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/conform.js"),
    },
    Asset {
        path: "/live.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/live.js"),
    },
    Asset {
        path: "/follow.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/follow.js"),
    },
    Asset {
        path: "/plot.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/plot.js"),
    },
    Asset {
        path: "/share.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/share.js"),
    },
    Asset {
        path: "/pdf.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/pdf.js"),
    },
    Asset {
        path: "/navigate.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/navigate.js"),
    },
    Asset {
        path: "/edit.js",
        mime: "text/javascript; charset=utf-8",
        body: include_str!("web/assets/edit.js"),
    },
    // The tab's icon; browsers ask for `/favicon.ico` whatever the page links, so both
    // paths serve it.
    Asset {
        path: "/favicon.svg",
        mime: "image/svg+xml",
        body: include_str!("web/assets/favicon.svg"),
    },
    Asset {
        path: "/favicon.ico",
        mime: "image/svg+xml",
        body: include_str!("web/assets/favicon.svg"),
    },
    Asset {
        path: "/style.css",
        mime: "text/css; charset=utf-8",
        body: include_str!("web/assets/style.css"),
    },
];

/// What the server shares between requests: the net, the token game, the cached analysis.
#[derive(Clone, Debug)]
pub struct WebState {
    inner: Arc<Inner>,
}

#[derive(Debug)]
struct Inner {
    /// The net the viewer was opened with (the editor's versions are in `editor`).
    net: Arc<Net>,
    seed: u64,
    session: Mutex<Session>,
    /// The analysis of the current net (replaced by every edit).
    analysis: Mutex<Arc<analysis_job::AnalysisJob>>,
    /// The versions of the net the page edited, the current one last.
    editor: Mutex<edit::History>,
    /// Why this net cannot be edited, when it cannot: a policy or rewards given without
    /// their plan ([`WebState::with_plan`]), which could not be checked against an edit.
    not_editable: Option<String>,
    /// The plan served, checked again after every edit ([`WebState::with_plan`]).
    plan: OnceLock<crate::plan::PlanText>,
    /// Where the editor saves (`serve --save-to`).
    save_to: OnceLock<std::path::PathBuf>,
    live: OnceLock<LiveRun>,
    replay: OnceLock<Arc<replay::Replay>>,
    source: OnceLock<greatspn::Source>,
    /// Bumped by every change of the token game: the pages waiting on `/api/sim/wait`
    /// (other tabs) fetch the new state.
    sim_version: tokio::sync::watch::Sender<u64>,
    /// Held by the `step` running (one at a time; [`limits::STEP_CHUNK`]).
    stepping: tokio::sync::Semaphore,
}

impl WebState {
    /// Serves `net`; the token game uses `policy` (if any) for immediate choices and starts
    /// with `seed`.
    pub fn new(net: Net, policy: Option<Policy>, seed: u64) -> WebState {
        WebState::with_max_states(net, policy, seed, DEFAULT_MAX_STATES)
    }

    /// Like [`WebState::new`], exploring at most `max_states` markings for the analysis
    /// unless the page asks for another limit.
    pub fn with_max_states(
        net: Net,
        policy: Option<Policy>,
        seed: u64,
        max_states: usize,
    ) -> WebState {
        WebState::for_plan(net, policy, Vec::new(), seed, max_states)
    }

    /// The viewer of a plan: its token game chooses with `policy` (if any), and its
    /// analysis panel analyses the net under that policy ("net under plan policy"; the
    /// "bare net" without one, as `plan-runner analyze` does) with the long-run rates of
    /// `rewards`, exploring at most `max_states` markings unless the page asks for another
    /// limit.
    pub fn for_plan(
        net: Net,
        policy: Option<Policy>,
        rewards: Vec<RewardSpec>,
        seed: u64,
        max_states: usize,
    ) -> WebState {
        let net = Arc::new(net);
        let policy = policy.filter(|p| !p.is_empty()).map(Arc::new);
        let not_editable = (policy.is_some() || !rewards.is_empty()).then(|| {
            "a policy or rewards given without their plan file cannot be checked against an \
             edited net (gspn::web::WebState::with_plan)"
                .to_string()
        });
        let session = Session::new(net.clone(), policy.clone(), seed);
        let analysis = Arc::new(analysis_job::AnalysisJob::new(
            net.clone(),
            policy.unwrap_or_else(|| Arc::new(Policy::empty())),
            rewards,
            max_states,
        ));
        WebState {
            inner: Arc::new(Inner {
                net: Arc::clone(&net),
                seed,
                session: Mutex::new(session),
                analysis: Mutex::new(analysis),
                editor: Mutex::new(edit::History::new(Arc::clone(&net))),
                not_editable,
                plan: OnceLock::new(),
                save_to: OnceLock::new(),
                live: OnceLock::new(),
                replay: OnceLock::new(),
                source: OnceLock::new(),
                sim_version: tokio::sync::watch::channel(0).0,
                stepping: tokio::sync::Semaphore::new(1),
            }),
        }
    }

    /// A viewer of a running plan: the page follows `live` (and can stop it) instead of
    /// playing its own token game.
    pub fn for_live(live: LiveRun) -> WebState {
        let h = live.handle();
        let state = WebState::new(Net::clone(h.net()), None, h.seed());
        let _ = state.inner.live.set(live);
        state
    }

    /// A viewer of a recorded run ([`crate::runtime::journal::read_journal`]): the page shows a time slider
    /// over `frames` instead of playing its own token game.
    pub fn for_replay(net: Net, frames: Vec<Frame>) -> WebState {
        let replay = replay::Replay::of_frames(&net, frames);
        let state = WebState::new(net, None, 0);
        let _ = state.inner.replay.set(Arc::new(replay));
        state
    }

    /// A viewer of a journal read back ([`crate::runtime::journal::read_recording`]): the
    /// time slider over its firings on the net as it ran, and the map of its simulated world
    /// when the journal recorded one.
    pub fn for_recording(recording: Recording) -> WebState {
        let replay = replay::Replay::of_recording(&recording);
        let state = WebState::new(recording.net, None, 0);
        let _ = state.inner.replay.set(Arc::new(replay));
        state
    }

    /// A viewer of the journal at `path`, its header read by `journal`: the time slider over
    /// its firings on the net as it ran (and its world's map), read from the file a window
    /// at a time as the page asks — the memory held is the index of the windows and what the
    /// panels show for the whole run (the robots' stays, the conformance table's snapshots),
    /// not the file. With the last line if it was cut short (a warning: the run was killed
    /// while writing it).
    pub fn for_journal(
        path: &std::path::Path,
        journal: crate::runtime::journal::JournalReader<std::io::BufReader<std::fs::File>>,
    ) -> Result<
        (WebState, Option<crate::runtime::journal::JournalError>),
        crate::runtime::journal::JournalError,
    > {
        let net = journal.net().clone();
        let (replay, torn) = replay::Replay::of_journal(path, journal)?;
        let state = WebState::new(net, None, 0);
        let _ = state.inner.replay.set(Arc::new(replay));
        Ok((state, torn))
    }

    /// The firings of the recorded run (0 unless this is a replay).
    pub fn replay_firings(&self) -> usize {
        self.inner.replay.get().map_or(0, |r| r.firings())
    }

    /// The net came from `path`: when that is a GreatSPN project whose page is this net, the
    /// page draws its nodes as the file does (transition rotation, label offsets) and `save
    /// layout` writes the file back with only the positions changed.
    pub fn with_source(self, path: &std::path::Path) -> WebState {
        if let Some(source) = greatspn::Source::read(path, &self.inner.net) {
            let _ = self.inner.source.set(source);
        }
        self
    }

    /// The net is the one of the plan `text` (whose policy and rewards this viewer was made
    /// with, [`WebState::for_plan`]): the page may edit it, and every edit, undo and redo is
    /// checked against the plan as the plan reader checks it ([`crate::plan::PlanText::check`]);
    /// one that would leave the policy, a reward, a role, the stop condition or the map
    /// naming a node that no longer exists (or is no longer of the kind it needs) is refused
    /// with the reader's message. The token game and the analysis then play the edited net
    /// under the plan's policy resolved against it.
    pub fn with_plan(self, text: crate::plan::PlanText) -> WebState {
        let _ = self.inner.plan.set(text);
        self
    }

    /// The editor's "save" writes the edited net to `path` (a GreatSPN project `.PNPRO` or
    /// a PIPE net `.xml`, by its extension), replacing it; without it the page downloads
    /// the net. A request never names the file.
    pub fn saving_to(self, path: std::path::PathBuf) -> Result<WebState, SaveFormatError> {
        edit::routes::save_format(&path)?;
        let _ = self.inner.save_to.set(path);
        Ok(self)
    }

    fn live(&self) -> Option<&LiveRun> {
        self.inner.live.get()
    }

    /// The net the viewer was opened with.
    pub fn net(&self) -> &Net {
        &self.inner.net
    }

    /// The net as the page's edits left it (the opened one until an edit): the one the
    /// token game plays and the analysis panel analyses.
    pub fn current_net(&self) -> Arc<Net> {
        self.editor().net().clone()
    }

    fn editor(&self) -> MutexGuard<'_, edit::History> {
        self.inner
            .editor
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn analysis(&self) -> Arc<analysis_job::AnalysisJob> {
        self.inner
            .analysis
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .clone()
    }

    /// The GreatSPN file the net came from, while the net is the file's (not edited).
    fn source(&self) -> Option<&greatspn::Source> {
        self.inner.source.get().filter(|_| !self.editor().edited())
    }

    fn session(&self) -> MutexGuard<'_, Session> {
        // A panic while holding the lock cannot leave the session half-updated in a way
        // that matters more than refusing every later request would.
        self.inner
            .session
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Tells the pages that follow the token game that it changed.
    fn sim_changed(&self) {
        self.inner.sim_version.send_modify(|v| *v += 1);
    }
}

/// The viewer's routes: the assets and the [JSON API](self#api), for a server whose address
/// is not known here: the `Host` of a request must then be `localhost`, `127.0.0.1` or
/// `[::1]` (any port). [`serve`] uses [`router_on`] with the listener's address instead.
/// Either way every request passes the [security checks](self#security).
pub fn router(state: WebState) -> Router {
    routes(state, guard::Bound::Unknown)
}

/// The viewer's routes for a server listening on `addr`: the `Host` of a request must name
/// `addr`'s port and, as host, `localhost`, `127.0.0.1`, `[::1]` or `addr`'s own IP (any IP
/// literal when `addr` is not a loopback address) — see [security](self#security).
pub fn router_on(state: WebState, addr: SocketAddr) -> Router {
    routes(state, guard::Bound::At(addr))
}

fn routes(state: WebState, bound: guard::Bound) -> Router {
    let mut r = Router::new();
    for asset in ASSETS {
        r = r.route(
            asset.path,
            get(move || async move { asset_response(asset) }),
        );
    }
    r.route("/api/net", get(api::net))
        .route("/api/sim/state", get(api::sim_state))
        .route("/api/sim/reset", post(api::sim_reset))
        .route("/api/sim/step", post(api::sim_step))
        .route("/api/sim/fire", post(api::sim_fire))
        .route("/api/sim/wait", get(api::sim_wait))
        .route("/api/analysis", get(api::analysis))
        .route("/api/analysis/start", post(api::analysis_start))
        .route("/api/analysis/progress", get(api::analysis_progress))
        .route("/api/analysis/cancel", post(api::analysis_cancel))
        .route("/api/analysis/query", post(api::analysis_query))
        .route("/api/analysis/query/progress", get(api::query_progress))
        .route("/api/analysis/query/cancel", post(api::query_cancel))
        .route("/api/mode", get(mode))
        .route("/api/layout", post(api::save_layout))
        .route(
            "/api/edit",
            get(edit::routes::status).post(edit::routes::edit),
        )
        .route("/api/edit/undo", post(edit::routes::undo))
        .route("/api/edit/redo", post(edit::routes::redo))
        .route("/api/edit/export", post(edit::routes::export))
        .route("/api/edit/save", post(edit::routes::save))
        .route("/api/replay", get(replay::outline_route))
        .route("/api/replay/window", get(replay::window))
        .route("/api/live/state", get(live::state))
        .route("/api/live/world", get(live::world))
        .route("/api/live/stop", post(live::stop))
        .route("/api/live/ws", get(live::ws))
        .fallback(|| async { api::error(StatusCode::NOT_FOUND, "no such route") })
        .layer(axum::middleware::from_fn_with_state(bound, guard::guard))
        .layer(axum::middleware::map_response(add_security_headers))
        .with_state(state)
}

/// `GET /api/mode`: `{"live": bool, "replay": bool}` — a running plan, a recorded one, or
/// neither (the token game).
async fn mode(axum::extract::State(state): axum::extract::State<WebState>) -> axum::Json<Value> {
    axum::Json(json!({
        "live": state.live().is_some(),
        "replay": state.inner.replay.get().is_some(),
    }))
}

async fn add_security_headers(mut res: Response) -> Response {
    let h = res.headers_mut();
    h.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(CONTENT_SECURITY_POLICY),
    );
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-cache"));
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    h.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
    res
}

fn asset_response(asset: &'static Asset) -> Response {
    (
        [(header::CONTENT_TYPE, HeaderValue::from_static(asset.mime))],
        asset.body,
    )
        .into_response()
}

/// Serves the viewer on `listener` ([`router_on`] its address) until the task is dropped.
/// Idle connections are closed after [`limits::HEADER_TIMEOUT`], and at most
/// [`limits::connection_cap`] are held at once (one more is answered 503); see
/// docs/viewer.md, "Limits".
pub async fn serve(listener: TcpListener, state: WebState) -> std::io::Result<()> {
    let addr = listener.local_addr()?;
    server::run(listener, router_on(state, addr)).await
}
