//! [`PlanFile::resolve`]: a plan file checked against its net, names turned into ids —
//! roles, the policy, stop conditions, robots, the map and the ROS 2 places. Every mistake is
//! a [`LoadError`] at the offending name's line and column.

use std::ops::Range;
use std::path::Path;

use toml::Spanned;

use super::Plan;
use super::file::{PlanFile, RuleFile, locate};
use super::programs::Programs;
use super::rewards::{resolve_controls, resolve_rewards};
use super::ros2::resolve_ros2;
use crate::io::{LoadError, LoadErrorKind};
use crate::net::predicate::{Predicate, PredicateErrorKind};
use crate::net::{Net, Timing, TransitionId};
use crate::policy::{Pattern, Policy, PolicyError, Rule};
use crate::runtime::{Role, StopConditions};

mod role;

use role::{check_builtin, resolve_role};

impl PlanFile {
    /// Checks the plan against `net` (read from [`PlanFile::net_path`]) and resolves names
    /// to ids. `text` is the plan's text, for line and column numbers. In the order of the
    /// file's sections: the time scale, the places' roles, the ROS 2 places, the policy,
    /// the stop conditions, the robots, the map (and the robot actions that name its
    /// locations), the rewards and controls.
    pub fn resolve(self, path: &Path, text: &str, net: Net) -> Result<Plan, LoadError> {
        let at =
            |span: Range<usize>, kind: LoadErrorKind| LoadError::at(path, locate(text, span), kind);
        self.check_time_scale(&net, &at)?;
        let mut programs = Programs::new(&self.workers, path, &at)?;
        // Positions of many places and rules: one line index, not a scan per position.
        let lines = crate::io::LineIndex::new(text.as_bytes());
        let Roles {
            roles,
            action_spans,
            warnings,
        } = self.roles(&net, text, &lines, &mut programs, &at)?;
        let ros2 = resolve_ros2(&net, self.ros2.as_ref(), &self.places, &at)?;
        let (policy, rule_spans) = self.policy(&net, text, &lines, &at)?;
        let stop = self.stop(&net, text, &at)?;
        let robots = self.robots(&net, &roles, text, &at)?;
        let map = match &self.map {
            Some(m) => Some(m.get_ref().resolve(&net, m.span(), &at)?),
            None => None,
        };
        if let Some(m) = &map {
            self.check_robot_actions(&net, m, &at)?;
        }
        let rewards = resolve_rewards(&net, &self.rewards, &at)?;
        let controls = resolve_controls(&net, self.controllable.as_ref(), self.wait, &at)?;

        Ok(Plan {
            path: path.to_path_buf(),
            net_path: self.net_path(path),
            page: self.page,
            net,
            seed: self.seed,
            time_scale: self.time_scale.map(Spanned::into_inner),
            roles,
            policy,
            rule_spans,
            stop,
            robots,
            warnings,
            map,
            ros2,
            rewards,
            controls,
            programs: programs.list,
            action_spans,
            transition_at: Vec::new(),
            text: None,
        })
    }

    /// `time_scale` in range, and short enough for every delay of the net in real time.
    fn check_time_scale(
        &self,
        net: &Net,
        at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
    ) -> Result<(), LoadError> {
        let Some(ts) = &self.time_scale else {
            return Ok(());
        };
        let v = *ts.get_ref();
        if !(v.is_finite() && (0.0..=crate::limits::MAX_SECONDS).contains(&v)) {
            return Err(at(
                ts.span(),
                out_of_range("time_scale", "plan", v, TIME_SCALE_EXPECTED),
            ));
        }
        // In real time a rate is a wait on the clock: refuse one that would never end.
        if let Some((t, rate)) = crate::limits::too_slow_for_real_time(net, v) {
            return Err(at(
                ts.span(),
                LoadErrorKind::Invalid(real_time_wait(
                    &format!("time_scale = {}", show(v)),
                    net,
                    t,
                    rate,
                    v,
                )),
            ));
        }
        Ok(())
    }

    /// Each place's role, where its action is written, and a warning per action place
    /// without an output transition.
    fn roles(
        &self,
        net: &Net,
        text: &str,
        lines: &crate::io::LineIndex,
        programs: &mut Programs,
        at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
    ) -> Result<Roles, LoadError> {
        let mut roles: Vec<Option<Role>> = vec![None; net.place_count()];
        let mut action_spans = vec![None; net.place_count()];
        let mut warnings = Vec::new();
        for (name, role) in &self.places {
            let p = net
                .place_by_name(name.get_ref())
                .ok_or_else(|| at(name.span(), unknown("place", name.get_ref())))?;
            roles[p.index()] = Some(resolve_role(
                net,
                p,
                role,
                at,
                programs,
                self.map.is_some(),
            )?);
            if let Some(a) = &role.get_ref().action {
                action_spans[p.index()] = Some(lines.locate(text.as_bytes(), a.span().start));
            }
            if matches!(roles[p.index()], Some(Role::Action { .. })) && net.consumers(p).is_empty()
            {
                warnings.push(format!(
                    "place `{}` has an action but no output transition: its agents end Inactive",
                    name.get_ref()
                ));
            }
        }
        Ok(Roles {
            roles,
            action_spans,
            warnings,
        })
    }

    /// The policy's rules, and where each starts.
    fn policy(
        &self,
        net: &Net,
        text: &str,
        lines: &crate::io::LineIndex,
        at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
    ) -> Result<(Policy, Vec<crate::io::Span>), LoadError> {
        let mut rules = Vec::with_capacity(self.policy.len());
        let mut rule_spans = Vec::with_capacity(self.policy.len());
        for rule in &self.policy {
            rules.push(resolve_rule(net, rule.get_ref(), at)?);
            rule_spans.push(lines.locate(text.as_bytes(), rule.span().start));
        }
        let policy = Policy::new(net, rules).map_err(|e| {
            let rule = self.policy[e.rule()].get_ref();
            let span = policy_error_span(&e, rule).unwrap_or_else(|| self.policy[e.rule()].span());
            at(span, LoadErrorKind::Invalid(format!("policy {e}")))
        })?;
        Ok((policy, rule_spans))
    }

    /// The `[stop]` section: its predicate (errors at the offending character), time limit
    /// and firing limit.
    fn stop(
        &self,
        net: &Net,
        text: &str,
        at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
    ) -> Result<StopConditions, LoadError> {
        let mut stop = StopConditions::default();
        let Some(s) = &self.stop else {
            return Ok(stop);
        };
        if let Some(w) = &s.when {
            let pred = Predicate::parse(net, w.get_ref()).map_err(|e| {
                let span = w.span();
                let start = span.start + string_content_offset(text, span.start);
                // Columns count characters; the content starts after the opening quote.
                let byte = w
                    .get_ref()
                    .char_indices()
                    .nth(e.column.saturating_sub(1))
                    .map_or(w.get_ref().len(), |(i, _)| i);
                let kind = match (e.kind, e.name) {
                    (PredicateErrorKind::UnknownPlace, Some(n)) => unknown("place", &n),
                    _ => LoadErrorKind::Invalid(format!("stop.when: {}", e.message)),
                };
                at(start + byte..start + byte, kind)
            })?;
            stop.when = Some(pred);
        }
        if let Some(t) = &s.time_limit {
            let v = *t.get_ref();
            if !(v.is_finite() && v > 0.0) {
                return Err(at(
                    t.span(),
                    out_of_range("time_limit", "stop", v, "must be a finite number > 0"),
                ));
            }
            stop.time_limit = Some(v);
        }
        if let Some(n) = &s.max_firings {
            if *n.get_ref() == 0 {
                return Err(at(
                    n.span(),
                    LoadErrorKind::OutOfRange {
                        what: "max_firings",
                        name: "stop".into(),
                        value: "0".into(),
                        expected: "must be at least 1 (a run that may not fire at all would do nothing)",
                    },
                ));
            }
            stop.max_firings = Some(*n.get_ref());
        }
        Ok(stop)
    }

    /// The robots' names: non-empty, without spaces, each once, as many as the initial
    /// agents.
    fn robots(
        &self,
        net: &Net,
        roles: &[Option<Role>],
        text: &str,
        at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
    ) -> Result<Vec<String>, LoadError> {
        let mut robots: Vec<String> = Vec::with_capacity(self.robots.len());
        for r in &self.robots {
            let name = r.get_ref();
            if name.is_empty() || name.contains(char::is_whitespace) {
                return Err(at(
                    r.span(),
                    LoadErrorKind::Invalid(format!(
                        "robot name `{name}` must be non-empty and without spaces"
                    )),
                ));
            }
            if robots.iter().any(|n| n == name) {
                return Err(at(
                    r.span(),
                    LoadErrorKind::Invalid(format!("robot `{name}` is listed twice")),
                ));
            }
            robots.push(name.clone());
        }
        if !robots.is_empty() {
            check_robot_count(net, roles, robots.len()).map_err(|kind| {
                let span = key_span(text, "robots").unwrap_or_else(|| self.robots[0].span());
                at(span, kind)
            })?;
        }
        Ok(robots)
    }

    /// Built-in robot actions (`goto L2; measure`) name locations of the map: checked once
    /// the map is read.
    fn check_robot_actions(
        &self,
        net: &Net,
        map: &crate::world::map::Map,
        at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
    ) -> Result<(), LoadError> {
        for (name, role) in &self.places {
            let Some(a) = &role.get_ref().action else {
                continue;
            };
            let Some(text) = a.get_ref().name() else {
                continue;
            };
            let program = map.program(text).map_err(|e| {
                at(
                    a.span(),
                    LoadErrorKind::Invalid(format!("place `{}`: {e}", name.get_ref())),
                )
            })?;
            if program.is_none()
                && let Some(p) = net.place_by_name(name.get_ref())
            {
                check_builtin(net, p, text, a.span(), at)?;
            }
        }
        Ok(())
    }
}

/// The places' roles as [`PlanFile::resolve`] reads them.
struct Roles {
    roles: Vec<Option<Role>>,
    action_spans: Vec<Option<crate::io::Span>>,
    warnings: Vec<String>,
}

/// Refuses a `robots` list whose length is not the number of initial agents: every initial
/// token outside resource places is an agent (agents keep their identity through places
/// without actions), so the names must number the initial tokens of all the other places.
fn check_robot_count(
    net: &Net,
    roles: &[Option<Role>],
    robots: usize,
) -> Result<(), LoadErrorKind> {
    let holding: Vec<(&str, u32)> = net
        .place_ids()
        .filter(|p| !matches!(roles[p.index()], Some(Role::Resource)))
        .map(|p| (net.place(p).name.as_str(), net.place(p).initial))
        .filter(|&(_, k)| k > 0)
        .collect();
    let agents: u64 = holding.iter().map(|&(_, k)| u64::from(k)).sum();
    if agents == robots as u64 {
        return Ok(());
    }
    /// Places listed by name in the message; the rest are counted.
    const SHOWN: usize = 8;
    let mut places = holding
        .iter()
        .take(SHOWN)
        .map(|(name, k)| format!("{name} {k}"))
        .collect::<Vec<_>>()
        .join(", ");
    if holding.len() > SHOWN {
        places.push_str(&format!(" and {} more place(s)", holding.len() - SHOWN));
    }
    let tokens = if holding.is_empty() {
        "no initial tokens outside resource places".to_string()
    } else {
        format!("initial tokens outside resource places: {places}")
    };
    Err(LoadErrorKind::Invalid(format!(
        "`robots` names {robots} robot(s) but the net starts with {agents} agent(s) ({tokens}); \
         name one robot per initial agent, or make the places that count things `role = \"resource\"`"
    )))
}

/// The span of the top-level key `key` in the TOML `text` (its name, not its value), when
/// the text parses and has it.
fn key_span(text: &str, key: &str) -> Option<Range<usize>> {
    let table = toml::de::DeTable::parse(text).ok()?;
    table
        .get_ref()
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == key)
        .map(|(k, _)| k.span())
}

/// Bytes between the start of a TOML string value and its content (its opening quotes).
fn string_content_offset(text: &str, start: usize) -> usize {
    let rest = &text[start.min(text.len())..];
    if rest.starts_with("\"\"\"") || rest.starts_with("'''") {
        3
    } else if rest.starts_with('"') || rest.starts_with('\'') {
        1
    } else {
        0
    }
}

pub(super) fn unknown(what: &'static str, name: &str) -> LoadErrorKind {
    LoadErrorKind::UnknownNode {
        what,
        name: name.to_string(),
    }
}

pub(super) fn out_of_range(
    what: &'static str,
    name: &str,
    v: f64,
    expected: &'static str,
) -> LoadErrorKind {
    LoadErrorKind::OutOfRange {
        what,
        name: name.to_string(),
        value: show(v),
        expected,
    }
}

/// What a time scale must be (seconds per unit of model time).
pub const TIME_SCALE_EXPECTED: &str =
    "must be a finite number ≥ 0 and ≤ 315576000 (seconds of real time per unit of model time)";

/// A number as a person writes it: `1e300`, not three hundred digits.
fn show(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-6..1e15).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}

fn resolve_rule(
    net: &Net,
    r: &RuleFile,
    at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
) -> Result<Rule, LoadError> {
    let mut listed = Vec::with_capacity(r.marking.len());
    for (name, k) in &r.marking {
        let p = net
            .place_by_name(name.get_ref())
            .ok_or_else(|| at(name.span(), unknown("place", name.get_ref())))?;
        if let Some(cap) = net.place(p).capacity
            && *k.get_ref() > cap
        {
            return Err(at(
                k.span(),
                LoadErrorKind::Invalid(format!(
                    "policy marking of `{}` is {}, above its capacity {cap}: the rule could never apply",
                    name.get_ref(),
                    k.get_ref()
                )),
            ));
        }
        listed.push((p, *k.get_ref()));
    }
    listed.sort_by_key(|&(p, _)| p);
    let pattern = if r.partial {
        Pattern::Partial(listed)
    } else {
        let mut m = vec![0; net.place_count()];
        for (p, k) in listed {
            m[p.index()] = k;
        }
        Pattern::Exact(m)
    };
    let mut choose = Vec::with_capacity(r.choose.len());
    for (name, prob) in &r.choose {
        let t = net
            .transition_by_name(name.get_ref())
            .ok_or_else(|| at(name.span(), unknown("transition", name.get_ref())))?;
        if !matches!(net.transition(t).timing, Timing::Immediate { .. }) {
            return Err(at(
                name.span(),
                LoadErrorKind::Invalid(format!(
                    "policy chooses `{}`, an exponential transition: a policy chooses among immediate transitions",
                    name.get_ref()
                )),
            ));
        }
        choose.push((t, *prob.get_ref()));
    }
    Ok(Rule { pattern, choose })
}

/// The most precise span for a policy error: the offending transition's value or key.
fn policy_error_span(e: &PolicyError, rule: &RuleFile) -> Option<Range<usize>> {
    match e {
        PolicyError::BadProbability { name, .. } => rule
            .choose
            .iter()
            .find(|(k, _)| k.get_ref() == name)
            .map(|(_, v)| v.span()),
        PolicyError::NotImmediate { name, .. } | PolicyError::DuplicateTransition { name, .. } => {
            rule.choose
                .keys()
                .find(|k| k.get_ref() == name)
                .map(Spanned::span)
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests;

/// The message for a transition too slow for real time ([`crate::limits::too_slow_for_real_time`]):
/// `what` names the time scale's source (`time_scale = 1`, `--time-scale 1`).
pub(crate) fn real_time_wait(
    what: &str,
    net: &Net,
    t: TransitionId,
    rate: f64,
    scale: f64,
) -> String {
    format!(
        "{what}: transition `{}` (rate {}) would wait {:.1e} s of real time on average, more than the maximum {} s (10 years)",
        net.transition(t).name,
        show(rate),
        scale / rate,
        crate::limits::MAX_SECONDS
    )
}
