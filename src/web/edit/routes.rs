//! The editor's routes. Every edit replaces the session's net: the token game starts again
//! from the new initial marking (same seed), the analysis panel analyses the new net, and
//! the other open pages redraw it (its `version` is in every token-game state).
//!
//! Saving writes only where the command line said (`plan-runner serve FILE --save-to
//! PATH`): a request names no path, so a page can never choose which file is written; and
//! like every state-changing route these pass the [security checks](crate::web#security).
//! Without `--save-to` the page downloads the file instead (`/api/edit/export`).

use std::path::{Path, PathBuf};

use axum::Json;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use serde_json::{Value, json};

use super::{Edit, EditError};
use crate::io::Format;
use crate::net::{Net, Position};
use crate::web::WebState;
use crate::web::api::{error, net_json};

/// `serve --save-to PATH` with a file the editor cannot write.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{}: the editor saves GreatSPN projects (.PNPRO) and PIPE nets (.xml)",
    .0.display()
)]
pub struct SaveFormatError(pub PathBuf);

/// The format the editor writes to `path`, by its extension.
pub(crate) fn save_format(path: &Path) -> Result<Format, SaveFormatError> {
    match Format::from_extension(path) {
        Some(f @ (Format::Pnpro | Format::Pipe)) => Ok(f),
        _ => Err(SaveFormatError(path.to_path_buf())),
    }
}

fn text_of(net: &Net, format: Format) -> String {
    match format {
        Format::Pipe => crate::io::pipe::write(net),
        _ => crate::io::pnpro::write(net),
    }
}

fn refusal(e: &EditError) -> Response {
    let status = if e.is_conflict() {
        StatusCode::CONFLICT
    } else {
        StatusCode::UNPROCESSABLE_ENTITY
    };
    error(status, e.to_string())
}

/// The current net as `/api/net` draws it, with its `version`; after an edit, the nodes
/// the opened GreatSPN file drew keep their look (rotation, label offsets), found by name.
pub(crate) fn net_value(state: &WebState) -> Value {
    let (net, version, edited) = {
        let h = state.editor();
        (h.net().clone(), h.version(), h.edited())
    };
    let source = state.inner.source.get();
    let mut v = net_json(&net, state.inner.seed, source.filter(|_| !edited), edited);
    if edited && let Some(s) = source {
        let original = &state.inner.net;
        for (key, place) in [("places", true), ("transitions", false)] {
            for node in v[key].as_array_mut().into_iter().flatten() {
                let name = node["name"].as_str().unwrap_or_default();
                let i = if place {
                    original.place_by_name(name).map(|p| p.index())
                } else {
                    original.transition_by_name(name).map(|t| t.index())
                };
                if let Some(i) = i {
                    node["look"] = s.look_json(place, i);
                }
            }
        }
    }
    v["version"] = json!(version);
    v
}

/// What every change answers: the net to draw, the history, the token game's state.
fn changed(state: &WebState) -> Response {
    Json(json!({
        "net": net_value(state),
        "history": state.editor().json(),
        "state": state.sim_json(200),
    }))
    .into_response()
}

/// `GET /api/edit`: `{editable, reason, save_to, history}`.
pub(crate) async fn status(State(state): State<WebState>) -> Json<Value> {
    let reason = state.editable().err().map(|e| e.to_string());
    Json(json!({
        "editable": reason.is_none(),
        "reason": reason,
        "save_to": state.inner.save_to.get().map(|p| p.display().to_string()),
        "history": state.editor().json(),
    }))
}

/// `POST /api/edit {op, ...}`: applies one [`Edit`]; 422 `{error}` when it is refused.
pub(crate) async fn edit(State(state): State<WebState>, Json(body): Json<Value>) -> Response {
    let edit: Edit = match serde_json::from_value(body) {
        Ok(e) => e,
        Err(e) => return error(StatusCode::BAD_REQUEST, format!("not an edit: {e}")),
    };
    if let Err(e) = state.change(|h, check| h.apply(&edit, check)) {
        return refusal(&e);
    }
    changed(&state)
}

/// `POST /api/edit/undo`.
pub(crate) async fn undo(State(state): State<WebState>) -> Response {
    match state.change(|h, check| h.undo(check)) {
        Ok(()) => changed(&state),
        Err(e) => refusal(&e),
    }
}

/// `POST /api/edit/redo`.
pub(crate) async fn redo(State(state): State<WebState>) -> Response {
    match state.change(|h, check| h.redo(check)) {
        Ok(()) => changed(&state),
        Err(e) => refusal(&e),
    }
}

/// Body of `/api/edit/export` and `/api/edit/save`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SaveBody {
    /// `pnpro` (default) or `pipe`; export only (a save writes its file's format).
    format: Option<String>,
    /// `[x, y]` per place as the page draws them, in the file's units.
    places: Option<Vec<[f64; 2]>>,
    /// `[x, y]` per transition.
    transitions: Option<Vec<[f64; 2]>>,
}

/// The current net with the page's positions, when it sent them.
fn to_save(state: &WebState, b: &SaveBody) -> Result<Net, (StatusCode, String)> {
    let net = state.current_net();
    let (Some(places), Some(transitions)) = (&b.places, &b.transitions) else {
        return Ok(Net::clone(&net));
    };
    let pos =
        |v: &[[f64; 2]]| -> Vec<Position> { v.iter().map(|&[x, y]| Position { x, y }).collect() };
    match crate::web::layout::with_positions(&net, &pos(places), &pos(transitions)) {
        None => Err((
            StatusCode::BAD_REQUEST,
            format!(
                "expected {} place and {} transition positions (the net changed: reload the page)",
                net.place_count(),
                net.transition_count()
            ),
        )),
        Some(Err(e)) => Err((StatusCode::UNPROCESSABLE_ENTITY, e.to_string())),
        Some(Ok(n)) => Ok(n),
    }
}

/// `POST /api/edit/export {format, places, transitions}`: `{text, file}`, the current net
/// as a GreatSPN project (`pnpro`) or a PIPE net (`pipe`) for the page to download.
pub(crate) async fn export(State(state): State<WebState>, body: Option<Json<Value>>) -> Response {
    let b: SaveBody = match body.map(|Json(v)| serde_json::from_value(v)).transpose() {
        Ok(b) => b.unwrap_or_default(),
        Err(e) => return error(StatusCode::BAD_REQUEST, e.to_string()),
    };
    let format = match b.format.as_deref().unwrap_or("pnpro") {
        "pnpro" => Format::Pnpro,
        "pipe" => Format::Pipe,
        other => {
            return error(
                StatusCode::BAD_REQUEST,
                format!("format `{other}`: the editor writes `pnpro` and `pipe`"),
            );
        }
    };
    let net = match to_save(&state, &b) {
        Ok(n) => n,
        Err((status, message)) => return error(status, message),
    };
    let ext = if format == Format::Pipe {
        "xml"
    } else {
        "PNPRO"
    };
    Json(json!({
        "text": text_of(&net, format),
        "file": format!("{}.{ext}", net.name()),
    }))
    .into_response()
}

/// `POST /api/edit/save {places, transitions}`: writes the current net to the `--save-to`
/// file (in its format, replacing it whole); `{saved, format, bytes}`. 409 without one.
pub(crate) async fn save(State(state): State<WebState>, body: Option<Json<Value>>) -> Response {
    let Some(path) = state.inner.save_to.get().cloned() else {
        return error(
            StatusCode::CONFLICT,
            "this viewer saves no file (start it with `plan-runner serve FILE --save-to \
             PATH`): download the net instead",
        );
    };
    let b: SaveBody = match body.map(|Json(v)| serde_json::from_value(v)).transpose() {
        Ok(b) => b.unwrap_or_default(),
        Err(e) => return error(StatusCode::BAD_REQUEST, e.to_string()),
    };
    if b.format.is_some() {
        return error(
            StatusCode::BAD_REQUEST,
            format!("a save writes {}'s own format", path.display()),
        );
    }
    let format = match save_format(&path) {
        Ok(f) => f,
        Err(e) => return error(StatusCode::CONFLICT, e.to_string()),
    };
    let net = match to_save(&state, &b) {
        Ok(n) => n,
        Err((status, message)) => return error(status, message),
    };
    let text = text_of(&net, format);
    let bytes = text.len();
    match tokio::task::spawn_blocking(move || write_whole(&path, &text).map(|()| path)).await {
        Ok(Ok(path)) => Json(json!({
            "saved": path.display().to_string(),
            "format": format.name(),
            "bytes": bytes,
        }))
        .into_response(),
        Ok(Err((path, e))) => error(
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("cannot write {}: {e}", path.display()),
        ),
        Err(e) => error(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()),
    }
}

/// Writes `text` next to `path` and renames it over `path`: a reader never sees half a file.
fn write_whole(path: &Path, text: &str) -> Result<(), (PathBuf, std::io::Error)> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.gspn-saving"));
    std::fs::write(&tmp, text).map_err(|e| (tmp.clone(), e))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        (path.to_path_buf(), e)
    })
}
