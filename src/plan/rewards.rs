//! The plan's decision keys: `[rewards.NAME]` (rates of marked places or per token, impulses
//! of transitions), `controllable = [...]` and `wait = true|false`, resolved against the net
//! for policy synthesis and policy evaluation (`plan-runner synthesize`, `analyze PLAN`).

use std::collections::BTreeMap;
use std::ops::Range;

use schemars::JsonSchema;
use serde::Deserialize;
use toml::Spanned;

use super::resolve::{out_of_range, unknown};
use crate::analysis::decision::{Controls, PlaceMode, RewardSpec};
use crate::io::{LoadError, LoadErrorKind};
use crate::net::Net;

/// One reward structure of a plan (`[rewards.NAME]`).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RewardFile {
    /// Reward per unit of time while the place holds at least one token, by place name
    /// (the GSPNR toolbox's place rewards).
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, f64>")]
    pub marked: BTreeMap<Spanned<String>, Spanned<f64>>,
    /// Reward per unit of time and per token in the place, by place name.
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, f64>")]
    pub per_token: BTreeMap<Spanned<String>, Spanned<f64>>,
    /// Reward earned each time the transition fires, by transition name.
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, f64>")]
    pub transitions: BTreeMap<Spanned<String>, Spanned<f64>>,
}

/// Resolves the reward structures (in name order).
pub(super) fn resolve_rewards(
    net: &Net,
    rewards: &BTreeMap<Spanned<String>, Spanned<RewardFile>>,
    at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
) -> Result<Vec<RewardSpec>, LoadError> {
    let mut out = Vec::with_capacity(rewards.len());
    for (name, file) in rewards {
        let file = file.get_ref();
        let mut spec = RewardSpec {
            name: name.get_ref().clone(),
            ..RewardSpec::default()
        };
        let value = |v: &Spanned<f64>, what: &'static str, who: &str| {
            let x = *v.get_ref();
            if x.is_finite() {
                Ok(x)
            } else {
                Err(at(
                    v.span(),
                    out_of_range(what, who, x, "must be a finite number"),
                ))
            }
        };
        for (mode, table) in [
            (PlaceMode::Marked, &file.marked),
            (PlaceMode::PerToken, &file.per_token),
        ] {
            for (p, v) in table {
                let id = net
                    .place_by_name(p.get_ref())
                    .ok_or_else(|| at(p.span(), unknown("place", p.get_ref())))?;
                spec.places
                    .push((id, value(v, "reward", p.get_ref())?, mode));
            }
        }
        for (t, v) in &file.transitions {
            let id = net
                .transition_by_name(t.get_ref())
                .ok_or_else(|| at(t.span(), unknown("transition", t.get_ref())))?;
            spec.transitions
                .push((id, value(v, "reward", t.get_ref())?));
        }
        out.push(spec);
    }
    Ok(out)
}

/// Resolves `controllable` (default: the net's zero-weight immediate transitions) and `wait`.
pub(super) fn resolve_controls(
    net: &Net,
    controllable: Option<&Vec<Spanned<String>>>,
    wait: Option<bool>,
    at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
) -> Result<Controls, LoadError> {
    let mut controls = match controllable {
        None => Controls::zero_weight(net),
        Some(list) => {
            let mut ids = Vec::with_capacity(list.len());
            for name in list {
                let t = net
                    .transition_by_name(name.get_ref())
                    .ok_or_else(|| at(name.span(), unknown("transition", name.get_ref())))?;
                if !net.transition(t).is_immediate() {
                    return Err(at(
                        name.span(),
                        LoadErrorKind::Invalid(format!(
                            "controllable: `{}` is exponential; only immediate transitions are decisions",
                            name.get_ref()
                        )),
                    ));
                }
                if ids.contains(&t) {
                    return Err(at(
                        name.span(),
                        LoadErrorKind::Invalid(format!(
                            "controllable: `{}` is listed twice",
                            name.get_ref()
                        )),
                    ));
                }
                ids.push(t);
            }
            Controls::of(net, &ids)
        }
    };
    controls.wait = wait.unwrap_or(false);
    Ok(controls)
}
