//! Actions as programs, in any language: [`CommandAction`] starts a program per action,
//! [`Worker`] keeps one long-lived program per spec and sends it JSON Lines requests.
//!
//! Both implement [`Action`](crate::runtime::Action): they sit above the runtime (which knows
//! nothing of processes) like the robot world and ROS 2, and the plan registers them by name.
//! Every program leads its own process group; a timeout or a stop sends SIGTERM to the group
//! and SIGKILL after a grace period, so no child outlives its action ([`terminate_all`] for a
//! program that exits early). The protocol is in `docs/actions.md`.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use rustc_hash::FxHashMap;

use crate::net::PlaceId;
use crate::runtime::ActionContext;

mod backend;
pub(crate) mod command;
mod group;
pub(crate) mod worker;

pub use backend::ProgramActions;
pub use command::{CommandAction, CommandSpec};
pub use group::terminate_all;
pub use worker::{Worker, WorkerAction, WorkerSpec};

/// The default grace period between SIGTERM and SIGKILL (plan key `kill_grace`).
pub const DEFAULT_KILL_GRACE: Duration = Duration::from_secs(2);

/// Lines of one stream recorded per action run; the rest are counted in one last line.
pub const MAX_OUTPUT_LINES: usize = 1000;

/// The names of each place's output transitions, computed once per place.
#[derive(Debug, Default)]
struct OutputNames(Mutex<FxHashMap<PlaceId, Arc<[String]>>>);

impl OutputNames {
    fn get(&self, ctx: &ActionContext) -> Arc<[String]> {
        if let Ok(map) = self.0.lock()
            && let Some(v) = map.get(&ctx.place)
        {
            return Arc::clone(v);
        }
        let names: Arc<[String]> = ctx
            .outputs()
            .into_iter()
            .map(|t| ctx.net.transition(t).name.clone())
            .collect();
        if let Ok(mut map) = self.0.lock() {
            map.insert(ctx.place, Arc::clone(&names));
        }
        names
    }
}

/// The marking as a JSON object, place name → tokens, in net order (serialised in place).
struct MarkingMap<'a>(&'a ActionContext);

impl serde::Serialize for MarkingMap<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let ctx = self.0;
        let mut map = s.serialize_map(Some(ctx.net.place_count()))?;
        for (i, p) in ctx.net.places().iter().enumerate() {
            map.serialize_entry(&p.name, &ctx.marking[PlaceId(i as u32)])?;
        }
        map.end()
    }
}

/// [`MarkingMap`] as a string (for `GSPN_MARKING`).
fn marking_json(ctx: &ActionContext) -> String {
    serde_json::to_string(&MarkingMap(ctx)).unwrap_or_default()
}

/// A stated duration: a JSON number or numeric string of model seconds, finite, ≥ 0 and at
/// most [`MAX_SECONDS`](crate::limits::MAX_SECONDS).
fn stated_seconds(v: &serde_json::Value) -> Option<f64> {
    let s = match v {
        serde_json::Value::Number(n) => n.as_f64()?,
        serde_json::Value::String(s) => s.trim().parse().ok()?,
        _ => return None,
    };
    crate::limits::valid_wait(s).then_some(s)
}

/// A command's last stdout line: `NAME`, `NAME after S` or `after S` (NAME a transition or
/// `decide`; S model seconds the outcome takes effect after). The name, and the seconds or
/// why they are not seconds.
fn split_after(line: &str) -> (&str, Result<f64, BadAfter>) {
    let line = line.trim();
    let (name, secs) = if let Some(s) = line.strip_prefix("after ") {
        ("", s)
    } else if let Some((n, s)) = line.rsplit_once(" after ") {
        (n.trim(), s)
    } else {
        return (line, Ok(0.0));
    };
    let secs = secs.trim();
    match secs.parse::<f64>() {
        Ok(v) if crate::limits::valid_wait(v) => (name, Ok(v)),
        _ => (name, Err(BadAfter(secs.to_string()))),
    }
}

/// An answer's `after S` whose `S` is not a number of model seconds.
#[derive(Debug, thiserror::Error)]
#[error("`after {0}`: not a number of model seconds (finite, ≥ 0, ≤ 315576000)")]
struct BadAfter(String);

/// What a program's answer (a last stdout line, a worker's `fire`) means for the run.
fn outcome_of_name(ctx: &ActionContext, who: &str, name: &str) -> crate::runtime::Outcome {
    use crate::runtime::Outcome;
    let name = name.trim();
    if name.is_empty() || name == "decide" {
        return Outcome::Decide;
    }
    match ctx.transition(name) {
        // The supervisor checks that it is an output of the place (an error event names it).
        Some(t) => Outcome::Fire(t),
        None => Outcome::Failed(format!(
            "{who} answered `{name}`, which is not a transition of the net (outputs of `{}`: {})",
            ctx.place_name(),
            ctx.outputs()
                .into_iter()
                .map(|t| ctx.net.transition(t).name.clone())
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}
