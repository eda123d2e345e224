//! The plan written for a thesis input: its TOML text, section by section, with the
//! warnings of the translation.

use std::fmt::Write as _;

use rustc_hash::{FxHashMap, FxHashSet};

use super::{KeyItem, Named, PolicyEntry, ThesisInput};
use crate::io::{LoadError, LoadErrorKind, Span};
use crate::net::{Net, PlaceId, Timing};

/// The plan (TOML text) for `input` over `net`, whose file will be `net_file` beside the
/// plan; and the warnings of the translation. `project` is the directory of the functions'
/// modules as `thesis_functions.py` (beside the plan) is given it: relative to the plan's
/// directory, or absolute. Written in the plan's order: the header, the places' roles
/// ([`write_roles`]), then the policy ([`policy_rules`], [`write_rule`]).
pub fn plan_text(
    input: &ThesisInput,
    net: &Net,
    net_file: &str,
    project: &str,
) -> Result<(String, Vec<String>), LoadError> {
    let mut warnings = Vec::new();
    let order = places_tuple(input, net)?;
    let covers_net = order.len() == net.place_count();

    let file_label = input
        .path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# Imported by `plan-runner import-thesis` from {file_label}\n# (the 2020 thesis framework's execution input; see docs/plans.md).\n"
    );
    let _ = writeln!(out, "net = {}", toml_str(net_file));
    if let Some(sync) = input.full_synchronization {
        let _ = writeln!(
            out,
            "# full_synchronization = {sync} (gspn always synchronises fully)"
        );
    }
    write_roles(input, net, project, &mut out, &mut warnings)?;
    for (e, choose) in policy_rules(input, net, order.len(), &mut warnings)? {
        if !choose.is_empty() {
            write_rule(&mut out, input, e, &choose, covers_net);
        }
    }
    Ok((out, warnings))
}

/// An error at `span` of the input file.
fn input_error(input: &ThesisInput, span: Span, kind: LoadErrorKind) -> LoadError {
    LoadError::at(&input.path, span, kind)
}

/// A name of the input that the net does not have.
fn unknown(input: &ThesisInput, what: &'static str, n: &Named) -> LoadError {
    input_error(
        input,
        n.span,
        LoadErrorKind::UnknownNode {
            what,
            name: n.name.clone(),
        },
    )
}

/// The places of `places_tuple`, each once and each a place of the net, in the order the
/// policy's keys list their counts.
fn places_tuple(input: &ThesisInput, net: &Net) -> Result<Vec<PlaceId>, LoadError> {
    let mut order = Vec::with_capacity(input.places.len());
    let mut listed: FxHashSet<&str> = FxHashSet::default();
    for p in &input.places {
        if !listed.insert(&p.name) {
            return Err(input_error(
                input,
                p.span,
                LoadErrorKind::Duplicate {
                    what: "place in places_tuple",
                    name: p.name.clone(),
                },
            ));
        }
        order.push(
            net.place_by_name(&p.name)
                .ok_or_else(|| unknown(input, "place", p))?,
        );
    }
    Ok(order)
}

/// The `[places.*]` sections: an action per mapped place (a ROS 2 server or a function of
/// the thesis's project, run by the `functions` worker), `resource` for the resources.
fn write_roles(
    input: &ThesisInput,
    net: &Net,
    project: &str,
    out: &mut String,
    warnings: &mut Vec<String>,
) -> Result<(), LoadError> {
    let mut resources: Vec<&Named> = Vec::new();
    let mut resource_names: FxHashSet<&str> = FxHashSet::default();
    for r in &input.resources {
        net.place_by_name(&r.name)
            .ok_or_else(|| unknown(input, "place", r))?;
        if resource_names.insert(&r.name) {
            resources.push(r);
        }
    }
    let mut seen: FxHashSet<&str> = FxHashSet::default();
    for a in &input.actions {
        net.place_by_name(&a.place.name)
            .ok_or_else(|| unknown(input, "place", &a.place))?;
        if !seen.insert(&a.place.name) {
            warnings.push(format!(
                "place `{}` is mapped twice; the first mapping is used",
                a.place.name
            ));
            continue;
        }
        if resource_names.contains(a.place.name.as_str()) {
            warnings.push(format!(
                "place `{}` is in resources_list and also has action `{}`: it is a resource",
                a.place.name, a.action
            ));
            continue;
        }
        let _ = write!(out, "\n[places.{}]\n", toml_key(&a.place.name));
        match &a.action_type {
            Some(t) => {
                let _ = writeln!(
                    out,
                    "action = \"ros2\"   # the thesis's {t} action server `{}` (place_to_client_mapping)\nserver = {}",
                    a.action,
                    toml_str(&a.action)
                );
            }
            None => {
                let _ = writeln!(
                    out,
                    "action = {{ worker = \"functions\", name = {} }}   # place_to_function_mapping",
                    toml_str(&a.action)
                );
            }
        }
    }
    if input.actions.iter().any(|a| a.action_type.is_none()) {
        let _ = writeln!(
            out,
            "\n# The thesis's functions (`module.function`, called as function(agent_id)), imported\n# from the input's project_path by thesis_functions.py, a gspn worker (docs/actions.md).\n[workers.functions]\ncommand = [\"python3\", \"thesis_functions.py\", {}]",
            toml_str(project)
        );
    }
    for r in &resources {
        let _ = writeln!(out, "\n[places.{}]\nrole = \"resource\"", toml_key(&r.name));
    }
    Ok(())
}

/// The policy's entries with their choices, one per key: Python dicts keep the first
/// position of a key and the last value.
#[allow(clippy::type_complexity)]
fn policy_rules<'i>(
    input: &'i ThesisInput,
    net: &Net,
    places: usize,
    warnings: &mut Vec<String>,
) -> Result<Vec<(&'i PolicyEntry, Vec<(String, f64)>)>, LoadError> {
    let mut rules: Vec<(&PolicyEntry, Vec<(String, f64)>)> = Vec::new();
    let mut rule_of: FxHashMap<&[KeyItem], usize> = FxHashMap::default();
    for (n, e) in input.policy.iter().enumerate() {
        if e.key.len() != places {
            return Err(input_error(
                input,
                e.span,
                LoadErrorKind::Invalid(format!(
                    "policy key has {} entries but places_tuple has {} places",
                    e.key.len(),
                    places
                )),
            ));
        }
        let choose = resolve_choice(input, net, e, n + 1, warnings)?;
        if let Some(first) = rule_of.get(e.key.as_slice()).map(|&i| &mut rules[i]) {
            warnings.push(format!(
                "policy key at {} repeats the key at {}: the later value is used (as in Python)",
                e.span, first.0.span
            ));
            first.1 = choose;
        } else {
            rule_of.insert(&e.key, rules.len());
            rules.push((e, choose));
        }
    }
    Ok(rules)
}

/// One `[[policy]]` rule: the key's counts as its marking (`partial` unless the key gives
/// every place of the net a count), the choice's probabilities.
fn write_rule(
    out: &mut String,
    input: &ThesisInput,
    e: &PolicyEntry,
    choose: &[(String, f64)],
    covers_net: bool,
) {
    let exact = covers_net && e.key.iter().all(|k| matches!(k, KeyItem::Count(_)));
    let key_text: Vec<String> = e
        .key
        .iter()
        .map(|k| match k {
            KeyItem::Free => "'-'".to_string(),
            KeyItem::Count(c) => c.to_string(),
        })
        .collect();
    let _ = writeln!(
        out,
        "\n# policy_dictionary at line {}: ({})\n[[policy]]",
        e.span.line,
        key_text.join(",")
    );
    let cells: Vec<String> = e
        .key
        .iter()
        .zip(&input.places)
        .filter_map(|(k, p)| match k {
            KeyItem::Count(c) => Some(format!("{} = {c}", toml_key(&p.name))),
            KeyItem::Free => None,
        })
        .collect();
    if cells.is_empty() {
        let _ = writeln!(out, "marking = {{}}");
    } else {
        let _ = writeln!(out, "marking = {{ {} }}", cells.join(", "));
    }
    if !exact {
        let _ = writeln!(out, "partial = true");
    }
    let probs: Vec<String> = choose
        .iter()
        .map(|(t, p)| format!("{} = {p:?}", toml_key(t)))
        .collect();
    let _ = writeln!(out, "choose = {{ {} }}", probs.join(", "));
}

/// The transitions of one entry, checked against the net: unknown names are errors,
/// exponential ones are dropped (the thesis only consulted the policy for immediate ones).
fn resolve_choice(
    input: &ThesisInput,
    net: &Net,
    e: &PolicyEntry,
    n: usize,
    warnings: &mut Vec<String>,
) -> Result<Vec<(String, f64)>, LoadError> {
    let mut choose = Vec::new();
    let mut dropped = false;
    for (t, p) in &e.choose {
        // The 2020 framework looked a rule up only when its marking came up and never
        // checked its names, so its own standalone example ships rules for `t4`/`t5`,
        // which its net lacks: such a choice is dropped, as there, with a warning.
        let Some(id) = net.transition_by_name(&t.name) else {
            warnings.push(format!(
                "policy entry {n} (line {}, column {}) chooses `{}`, which the net does not \
                 have: the choice is dropped (the 2020 framework ignored it too)",
                t.span.line, t.span.column, t.name
            ));
            dropped = true;
            continue;
        };
        if !matches!(net.transition(id).timing, Timing::Immediate { .. }) {
            warnings.push(format!(
                "policy entry {n} (line {}) chooses `{}`, an exponential transition: a policy \
                 chooses among immediate transitions, so the entry is dropped",
                t.span.line, t.name
            ));
            dropped = true;
            continue;
        }
        if !(p.is_finite() && (0.0..=1.0).contains(p)) {
            return Err(LoadError::at(
                &input.path,
                t.span,
                LoadErrorKind::OutOfRange {
                    what: "probability",
                    name: t.name.clone(),
                    value: p.to_string(),
                    expected: "must be in [0, 1]",
                },
            ));
        }
        choose.push((t.name.clone(), *p));
    }
    let sum: f64 = choose.iter().map(|(_, p)| p).sum();
    if !choose.is_empty() && (sum - 1.0).abs() > crate::policy::SUM_TOLERANCE {
        if dropped && sum > 0.0 {
            for (_, p) in &mut choose {
                *p /= sum;
            }
        } else {
            return Err(LoadError::at(
                &input.path,
                e.span,
                LoadErrorKind::Invalid(format!(
                    "the probabilities of this policy entry sum to {sum}, not 1"
                )),
            ));
        }
    }
    Ok(choose)
}

/// A TOML key: bare when it can be, else a quoted string.
fn toml_key(s: &str) -> String {
    if !s.is_empty()
        && s.bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
    {
        s.to_string()
    } else {
        toml_str(s)
    }
}

/// A TOML basic string (JSON's escapes are valid TOML escapes).
fn toml_str(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| format!("\"{s}\""))
}
