//! The JSON API: the net and its layout, the token game, the analysis.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use axum::Json;
use axum::extract::{Query, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use serde_json::{Value, json};

use crate::net::{ArcKind, Net, Servers, Timing};
use crate::web::WebState;
use crate::web::analysis_job::{Answer, Outcome};
use crate::web::greatspn::Source;
use crate::web::layout::{Choice, Layout, LayoutSource, choose, has_positions};
use crate::web::limits::{MAX_STEP, STEP_CHUNK};
use crate::web::session::SessionError;

/// An error as `{"error": "..."}` with a status.
pub(crate) fn error(status: StatusCode, message: impl Into<String>) -> Response {
    (status, Json(json!({ "error": message.into() }))).into_response()
}

/// `GET /api/net`: places, transitions, arcs and the layout.
pub(crate) async fn net(State(state): State<WebState>) -> Json<Value> {
    Json(crate::web::edit::routes::net_value(&state))
}

/// The net as the page draws it (with the look of its nodes in `source`, when it has one):
/// at the default layout ([`choose`]: the file's positions unless they are useless; an
/// `edited` net's positions always, the page wrote them), with `layout_note` saying why the
/// file's were set aside, and — when the file has positions — the other layout in
/// `other_layout`, for the page's `layout` control.
pub(crate) fn net_json(net: &Net, seed: u64, source: Option<&Source>, edited: bool) -> Value {
    let (l, note) = choose(
        net,
        if edited {
            Choice::File
        } else {
            Choice::Default
        },
    );
    let other = has_positions(net).then(|| {
        let other = match l.source {
            LayoutSource::File => Choice::Automatic,
            LayoutSource::Layered => Choice::File,
        };
        positions_json(&choose(net, other).0)
    });
    let places: Vec<Value> = net
        .places()
        .iter()
        .zip(&l.places)
        .enumerate()
        .map(|(i, (p, pos))| {
            let mut v = json!({
                "id": i, "name": p.name, "tokens": p.initial, "capacity": p.capacity,
                "x": pos.x, "y": pos.y,
            });
            if let Some(s) = source {
                v["look"] = s.look_json(true, i);
            }
            v
        })
        .collect();
    let transitions: Vec<Value> = net
        .transitions()
        .iter()
        .zip(&l.transitions)
        .enumerate()
        .map(|(i, (t, pos))| {
            let mut v = json!({ "id": i, "name": t.name, "x": pos.x, "y": pos.y });
            if let Some(s) = source {
                v["look"] = s.look_json(false, i);
            }
            match t.timing {
                Timing::Immediate { weight, priority } => {
                    v["kind"] = json!("immediate");
                    v["weight"] = json!(weight);
                    v["priority"] = json!(priority);
                }
                Timing::Exponential { rate, servers } => {
                    v["kind"] = json!("exponential");
                    v["rate"] = json!(rate);
                    v["servers"] = match servers {
                        Servers::Single => json!("single"),
                        Servers::Infinite => json!("infinite"),
                        Servers::K(k) => json!(k),
                    };
                }
            }
            v
        })
        .collect();
    let arcs: Vec<Value> = net
        .arcs()
        .iter()
        .zip(&l.arcs)
        .map(|(a, bends)| {
            let kind = match a.kind {
                ArcKind::Input => "input",
                ArcKind::Output => "output",
                ArcKind::Inhibitor => "inhibitor",
            };
            let points: Vec<Value> = bends.iter().map(|p| json!([p.x, p.y])).collect();
            json!({
                "kind": kind, "place": a.place.index(), "transition": a.transition.index(),
                "weight": a.weight, "points": points,
            })
        })
        .collect();
    json!({
        "name": net.name(),
        "seed": seed,
        "layout": l.source,
        "layout_note": note,
        "other_layout": other,
        "places": places,
        "transitions": transitions,
        "arcs": arcs,
    })
}

/// A layout alone: `{layout, places: [[x, y]], transitions: [[x, y]], arcs: [[[x, y]]]}`.
fn positions_json(l: &Layout) -> Value {
    let xy = |p: &crate::net::Position| json!([p.x, p.y]);
    json!({
        "layout": l.source,
        "places": l.places.iter().map(xy).collect::<Vec<_>>(),
        "transitions": l.transitions.iter().map(xy).collect::<Vec<_>>(),
        "arcs": l.arcs.iter().map(|a| a.iter().map(xy).collect::<Vec<_>>()).collect::<Vec<_>>(),
    })
}

/// Query of `GET /api/sim/state`.
#[derive(Debug, Deserialize)]
pub(crate) struct StateQuery {
    /// Trace entries to return (the most recent; default 200).
    trace: Option<usize>,
}

/// `GET /api/sim/state`.
pub(crate) async fn sim_state(
    State(state): State<WebState>,
    Query(q): Query<StateQuery>,
) -> Json<Value> {
    Json(state.sim_json(q.trace.unwrap_or(200)))
}

/// Query of `GET /api/sim/wait`.
#[derive(Debug, Deserialize)]
pub(crate) struct WaitQuery {
    /// The version the page shows.
    after: u64,
}

/// Longest a `/api/sim/wait` request is held open.
const WAIT_HELD: std::time::Duration = std::time::Duration::from_secs(20);

/// `GET /api/sim/wait?after=V`: the state once its version is not `V` (or after
/// [`WAIT_HELD`] unchanged).
pub(crate) async fn sim_wait(
    State(state): State<WebState>,
    Query(q): Query<WaitQuery>,
) -> Json<Value> {
    let mut rx = state.inner.sim_version.subscribe();
    let _ = tokio::time::timeout(WAIT_HELD, rx.wait_for(|&v| v != q.after)).await;
    Json(state.sim_json(200))
}

/// Body of `POST /api/sim/reset`.
#[derive(Debug, Default, Deserialize)]
pub(crate) struct ResetBody {
    /// New seed; the current one when absent.
    seed: Option<u64>,
}

/// `POST /api/sim/reset {seed}`.
pub(crate) async fn sim_reset(
    State(state): State<WebState>,
    body: Option<Json<ResetBody>>,
) -> Json<Value> {
    let seed = body.and_then(|Json(b)| b.seed);
    state.session().reset(seed);
    state.sim_changed();
    Json(state.sim_json(200))
}

/// Body of `POST /api/sim/step`.
#[derive(Debug, Default, Deserialize)]
pub(crate) struct StepBody {
    /// Firings to do (default 1).
    n: Option<u64>,
}

/// `POST /api/sim/step {n}`: on a blocking thread, [`STEP_CHUNK`] firings per hold of the
/// token game's lock (so the state stays readable and the server's threads free while a
/// million firings run), one step request at a time (the next waits its turn); a step
/// whose request goes away stops at the end of its chunk.
pub(crate) async fn sim_step(
    State(state): State<WebState>,
    body: Option<Json<StepBody>>,
) -> Response {
    let n = body.and_then(|Json(b)| b.n).unwrap_or(1);
    if n > MAX_STEP {
        return error(
            StatusCode::BAD_REQUEST,
            format!("n = {n}: at most {MAX_STEP} steps per request"),
        );
    }
    let Ok(_turn) = state.inner.stepping.acquire().await else {
        return error(StatusCode::SERVICE_UNAVAILABLE, "the server is stopping");
    };
    let gone = StopOnDrop::default();
    let stop = gone.0.clone();
    let st = state.clone();
    let result = tokio::task::spawn_blocking(move || {
        let mut fired = 0;
        while fired < n && !stop.load(Ordering::Relaxed) {
            let chunk = (n - fired).min(STEP_CHUNK);
            let got = st.session().step(chunk)?;
            fired += got;
            if got < chunk {
                break;
            }
        }
        Ok::<u64, SessionError>(fired)
    })
    .await;
    state.sim_changed();
    match result {
        Ok(Ok(fired)) => {
            let mut v = state.sim_json(200);
            v["fired"] = json!(fired);
            Json(v).into_response()
        }
        Ok(Err(e)) => session_error(e),
        Err(e) => error(
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("the step failed: {e}"),
        ),
    }
}

/// Raised when the request it belongs to is dropped (the client went away).
#[derive(Debug, Default)]
struct StopOnDrop(Arc<AtomicBool>);

impl Drop for StopOnDrop {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
    }
}

/// Body of `POST /api/sim/fire`.
#[derive(Debug, Deserialize)]
pub(crate) struct FireBody {
    /// Name of the transition to fire.
    transition: String,
}

/// `POST /api/sim/fire {transition}`.
pub(crate) async fn sim_fire(State(state): State<WebState>, Json(b): Json<FireBody>) -> Response {
    let result = state.session().fire(&b.transition);
    state.sim_changed();
    match result {
        Ok(()) => Json(state.sim_json(200)).into_response(),
        Err(e) => session_error(e),
    }
}

fn session_error(e: SessionError) -> Response {
    let status = match e {
        SessionError::UnknownTransition(_) => StatusCode::NOT_FOUND,
        SessionError::NotFirable(_) => StatusCode::CONFLICT,
        SessionError::Sim(_) => StatusCode::UNPROCESSABLE_ENTITY,
    };
    error(status, e.to_string())
}

/// `GET /api/analysis`: starts the analysis if needed (on a blocking thread) and waits for
/// it; the result is kept. 409 `{error, kind: "cancelled", progress}` if it is cancelled
/// meanwhile.
pub(crate) async fn analysis(State(state): State<WebState>) -> Response {
    match state.analysis().result().await {
        Outcome::Done(value) => {
            let status = if value.get("error").is_some() {
                StatusCode::UNPROCESSABLE_ENTITY
            } else {
                StatusCode::OK
            };
            (status, Json(Value::clone(&value))).into_response()
        }
        Outcome::Cancelled(progress) => cancelled("the analysis", progress),
    }
}

/// 409 `{error: "WHAT was cancelled", kind: "cancelled", progress}`.
fn cancelled(what: &str, progress: Value) -> Response {
    (
        StatusCode::CONFLICT,
        Json(
            json!({ "error": format!("{what} was cancelled"), "kind": "cancelled",
                     "progress": progress }),
        ),
    )
        .into_response()
}

/// Body of `POST /api/analysis/start`.
#[derive(Debug, Default, Deserialize)]
pub(crate) struct StartBody {
    /// Most reachable markings to explore (the server's limit when absent).
    max_states: Option<usize>,
}

/// `POST /api/analysis/start {max_states}`: starts the analysis (unless running, or done
/// with the same limit); the progress. 400 for a limit of 0.
pub(crate) async fn analysis_start(
    State(state): State<WebState>,
    body: Option<Json<StartBody>>,
) -> Response {
    let max_states = body.and_then(|Json(b)| b.max_states);
    if max_states == Some(0) {
        return error(
            StatusCode::BAD_REQUEST,
            "max_states = 0: the analysis needs at least the initial marking",
        );
    }
    Json(state.analysis().start(max_states)).into_response()
}

/// Body of `POST /api/analysis/query`.
#[derive(Debug, Default, Deserialize)]
pub(crate) struct QueryBody {
    /// Times of the transient points (`analyze --transient`).
    #[serde(default)]
    transient: Vec<f64>,
    /// Predicates (`analyze --prob`).
    #[serde(default)]
    prob: Vec<String>,
    /// Queries in Storm's syntax (`analyze --query`).
    #[serde(default)]
    query: Vec<String>,
}

/// `POST /api/analysis/query {transient: [t], prob: [expr], query: [q]}`: on the finished
/// analysis's state space, `{steady_state: {probability: {expr: p}}, transient: [{t,
/// mean_tokens, throughput, probability}], queries: [{query, value}]}` as `plan-runner
/// analyze --json --transient … --prob … --query …` gives them. 409 before an analysis has
/// finished, 422 when it found no steady state to ask about or the question asks past a
/// [limit](crate::web::limits) (time points, predicates and queries, their length), 413
/// when its answer would be too large,
/// 400 for a bad time or predicate (the message names it), 409 `{error, kind: "cancelled",
/// progress}` when the question was cancelled (`/api/analysis/query/cancel`, a newer
/// question, an edit of the net). Its progress is at `/api/analysis/query/progress`.
pub(crate) async fn analysis_query(
    State(state): State<WebState>,
    Json(b): Json<QueryBody>,
) -> Response {
    let job = state.analysis();
    let (net, kept) = match job.kept() {
        None => {
            return error(
                StatusCode::CONFLICT,
                "analyse first: the questions are asked of the analysed state space",
            );
        }
        Some(None) => {
            return error(
                StatusCode::UNPROCESSABLE_ENTITY,
                "the analysis has no steady state to ask about (see its result)",
            );
        }
        Some(Some(k)) => k,
    };
    // Queries are held to the predicates' limits (count, length).
    let limits = crate::web::limits::check_question(&net, &b.transient, &b.prob)
        .and_then(|()| crate::web::limits::check_question(&net, &[], &b.query));
    if let Err(over) = limits {
        return error(over.status, over.message);
    }
    match job.ask(net, kept, b.transient, b.prob, b.query).await {
        Answer::Done(v) => Json(v).into_response(),
        Answer::Refused(message) => error(StatusCode::BAD_REQUEST, message),
        Answer::Cancelled(progress) => cancelled("the question", progress),
        Answer::Failed(message) => error(StatusCode::INTERNAL_SERVER_ERROR, message),
    }
}

/// `GET /api/analysis/query/progress`: the question's `{state, phase, point, points,
/// iterations, of, seconds}`.
pub(crate) async fn query_progress(State(state): State<WebState>) -> Json<Value> {
    Json(state.analysis().question_progress())
}

/// `POST /api/analysis/query/cancel`: stops a running question (the transient solver within
/// one iteration); its progress.
pub(crate) async fn query_cancel(State(state): State<WebState>) -> Json<Value> {
    Json(state.analysis().cancel_question())
}

/// `GET /api/analysis/progress`: `{state, phase, markings, seconds}`.
pub(crate) async fn analysis_progress(State(state): State<WebState>) -> Json<Value> {
    Json(state.analysis().progress())
}

/// `POST /api/analysis/cancel`: stops a running analysis; the progress.
pub(crate) async fn analysis_cancel(State(state): State<WebState>) -> Json<Value> {
    Json(state.analysis().cancel())
}

/// Body of `POST /api/layout`.
#[derive(Debug, Deserialize)]
pub(crate) struct LayoutBody {
    /// `[x, y]` per place, in the file's units.
    places: Vec<[f64; 2]>,
    /// `[x, y]` per transition.
    transitions: Vec<[f64; 2]>,
}

/// `POST /api/layout {places, transitions}`: the net with these positions, as a GreatSPN
/// PNPRO document (`{"pnpro": "...", "file": name}`) for the page to save: the project the
/// net came from with only its nodes' positions changed when there is one, else the net
/// written anew.
pub(crate) async fn save_layout(
    State(state): State<WebState>,
    Json(b): Json<LayoutBody>,
) -> Response {
    let pos = |v: &[[f64; 2]]| -> Vec<crate::net::Position> {
        v.iter()
            .map(|&[x, y]| crate::net::Position { x, y })
            .collect()
    };
    let net = &state.current_net();
    if let Some(source) = state.source()
        && b.places.len() == net.place_count()
        && b.transitions.len() == net.transition_count()
    {
        let text = source.with_positions(&pos(&b.places), &pos(&b.transitions));
        let file = source
            .path()
            .file_name()
            .map(|f| f.to_string_lossy().into_owned());
        return Json(json!({ "pnpro": text, "file": file })).into_response();
    }
    match crate::web::layout::with_positions(net, &pos(&b.places), &pos(&b.transitions)) {
        None => error(
            StatusCode::BAD_REQUEST,
            format!(
                "expected {} place and {} transition positions",
                net.place_count(),
                net.transition_count()
            ),
        ),
        Some(Err(e)) => error(StatusCode::UNPROCESSABLE_ENTITY, e.to_string()),
        Some(Ok(n)) => Json(json!({ "pnpro": crate::io::pnpro::write(&n) })).into_response(),
    }
}

impl WebState {
    /// The token game's state as JSON, with the last `trace` firings.
    pub(crate) fn sim_json(&self, trace: usize) -> Value {
        let version = *self.inner.sim_version.borrow();
        let net_version = self.editor().version();
        let s = self.session();
        let net = s.net().clone();
        let m = s.marking();
        let enabled: Vec<&str> = net
            .transition_ids()
            .filter(|&t| net.is_enabled(m, t))
            .map(|t| net.transition(t).name.as_str())
            .collect();
        let firable_ids = net.firable(m);
        let firable: Vec<&str> = firable_ids
            .iter()
            .map(|&t| net.transition(t).name.as_str())
            .collect();
        // The plan's policy in a vanishing marking: its rule's choice among the firable
        // immediate transitions (`null` when no rule applies: the net's weights choose).
        let choice = s
            .policy()
            .filter(|_| net.is_vanishing(m))
            .and_then(|p| {
                p.rule_for(m, &firable_ids)
                    .map(|(i, _)| i)
                    .zip(p.distribution(m, &firable_ids))
            })
            .map(|(rule, dist)| {
                let by_name: serde_json::Map<String, Value> = dist
                    .iter()
                    .map(|&(t, p)| (net.transition(t).name.clone(), json!(p)))
                    .collect();
                json!({ "rule": rule, "probabilities": by_name })
            });
        json!({
            "version": version,
            "net_version": net_version,
            "choice": choice,
            "seed": s.seed(),
            "time": s.time(),
            "firings": s.firings(),
            "marking": crate::analysis::report::by_place(&net, m),
            "tokens": m,
            "text": net.format_marking(m),
            "enabled": enabled,
            "firable": firable,
            "vanishing": net.is_vanishing(m),
            "dead": firable.is_empty(),
            "trace": s.trace_tail(trace),
        })
    }
}
