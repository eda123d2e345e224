//! What `synthesize` reads: the objective, the method, and the net with its rewards and
//! controls (from a plan or a GSPNR-style rewards file).

use super::*;

/// What to optimise, parsed from the command line.
#[derive(Clone, Debug)]
pub(super) enum Goal {
    Lra,
    Reach(Predicate),
    Total(Predicate),
    Time(Predicate),
    Discounted(f64),
    PerStep(f64),
}

pub(super) fn parse_objective(args: &Args, net: &Net) -> anyhow::Result<(Goal, bool)> {
    let o = args.objective.replace('_', "-");
    let (kind, max) = match o.rsplit_once('-') {
        Some((k, "max")) => (k.to_string(), true),
        Some((k, "min")) => (k.to_string(), false),
        _ => {
            return Err(BadInput(format!(
                "--objective `{}`: expected NAME-max or NAME-min (lra, reach, total, time, discounted, discounted-per-step)",
                args.objective
            ))
            .into());
        }
    };
    let goal = || -> anyhow::Result<Predicate> {
        let text = args.goal.as_deref().ok_or_else(|| {
            BadInput(format!(
                "--objective {o} needs --goal EXPR (e.g. 'P_done == 3')"
            ))
        })?;
        Ok(Predicate::parse(net, text).map_err(|e| BadInput(format!("--goal `{text}`: {e}")))?)
    };
    let g = match kind.as_str() {
        "lra" => Goal::Lra,
        "reach" => Goal::Reach(goal()?),
        "total" => Goal::Total(goal()?),
        "time" => Goal::Time(goal()?),
        "discounted" => {
            let r = args
                .discount
                .ok_or_else(|| BadInput("--objective discounted-… needs --discount RATE".into()))?;
            if !(r > 0.0 && r.is_finite()) {
                return Err(BadInput(format!("--discount {r}: must be a rate > 0")).into());
            }
            Goal::Discounted(r)
        }
        "discounted-per-step" => {
            let g = args.gamma.ok_or_else(|| {
                BadInput("--objective discounted-per-step-… needs --gamma G".into())
            })?;
            if !(g > 0.0 && g < 1.0) {
                return Err(BadInput(format!("--gamma {g}: must be in (0, 1)")).into());
            }
            Goal::PerStep(g)
        }
        other => {
            return Err(BadInput(format!(
                "--objective `{}`: unknown objective `{other}` (lra, reach, total, time, discounted, discounted-per-step)",
                args.objective
            ))
            .into());
        }
    };
    Ok((g, max))
}

/// Rewards, controllable transitions and WAIT from a GSPNR-style rewards file.
pub(super) fn read_rewards(
    path: &Path,
    net: &Net,
) -> anyhow::Result<(RewardSpec, Option<Controls>)> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let table: toml::Table = text
        .parse()
        .map_err(|e| BadInput(format!("{}: {e}", path.display())))?;
    let bad = |msg: String| BadInput(format!("{}: {msg}", path.display()));
    let mut spec = RewardSpec {
        name: "reward".into(),
        ..RewardSpec::default()
    };
    let number = |v: &toml::Value| v.as_float().or(v.as_integer().map(|i| i as f64));
    if let Some(places) = table.get("places").and_then(|v| v.as_table()) {
        for (name, v) in places {
            let p = net
                .place_by_name(name)
                .ok_or_else(|| bad(format!("[places]: unknown place `{name}`")))?;
            let r = number(v).ok_or_else(|| bad(format!("[places] `{name}`: not a number")))?;
            spec.places.push((p, r, PlaceMode::Marked));
        }
    }
    if let Some(ts) = table.get("transitions").and_then(|v| v.as_table()) {
        for (name, v) in ts {
            let t = net
                .transition_by_name(name)
                .ok_or_else(|| bad(format!("[transitions]: unknown transition `{name}`")))?;
            let r =
                number(v).ok_or_else(|| bad(format!("[transitions] `{name}`: not a number")))?;
            spec.transitions.push((t, r));
        }
    }
    let mut controls = None;
    if let Some(list) = table.get("controllable").and_then(|v| v.as_array()) {
        let mut ids = Vec::new();
        for v in list {
            let name = v
                .as_str()
                .ok_or_else(|| bad("controllable: expected transition names".into()))?;
            let t = net
                .transition_by_name(name)
                .ok_or_else(|| bad(format!("controllable: unknown transition `{name}`")))?;
            if !net.transition(t).is_immediate() {
                return Err(bad(format!(
                    "controllable: `{name}` is exponential; only immediate transitions are decisions"
                ))
                .into());
            }
            ids.push(t);
        }
        controls = Some(Controls::of(net, &ids));
    }
    if let Some(w) = table.get("wait").and_then(|v| v.as_bool()) {
        let c = controls.get_or_insert_with(|| Controls::zero_weight(net));
        c.wait = w;
    }
    Ok((spec, controls))
}

/// The algorithm `--method` names (policy iteration for the long-run average only).
pub(super) fn algorithm(args: &Args, goal: &Goal) -> anyhow::Result<Algorithm> {
    match args.method.as_str() {
        "value" => Ok(Algorithm::ValueIteration),
        "auto" => Ok(Algorithm::Auto),
        "policy" if matches!(goal, Goal::Lra) => Ok(Algorithm::PolicyIteration),
        "policy" => Err(BadInput(format!(
            "--method policy: policy iteration is implemented for lra-max and lra-min only, not --objective {}",
            args.objective
        ))
        .into()),
        other => Err(BadInput(format!("--method `{other}`: expected auto, value or policy")).into()),
    }
}

/// What the input gave: the net, the rewards and controls, and a plan's path and text.
pub(super) struct Input {
    pub(super) net: Net,
    pub(super) spec: RewardSpec,
    pub(super) controls: Controls,
    pub(super) plan: Option<String>,
    /// Per place: its tokens are a resource (`role = "resource"`), not robots; a sweep keeps
    /// them (all false for a bare net).
    pub(super) resource: Vec<bool>,
}

pub(super) fn read_input(args: &Args) -> anyhow::Result<Input> {
    let is_plan = args
        .file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if !is_plan {
        if args.reward.is_some() {
            return Err(BadInput(
                "--reward NAME picks a plan's [rewards.NAME]; give a plan".into(),
            )
            .into());
        }
        let net = load_net(&args.file, &args.net)?.net;
        let (spec, file_controls) = match &args.rewards {
            Some(p) => read_rewards(p, &net)?,
            None => (RewardSpec::default(), None),
        };
        let controls = file_controls.unwrap_or_else(|| Controls::zero_weight(&net));
        let resource = vec![false; net.place_count()];
        return Ok(Input {
            net,
            spec,
            controls,
            plan: None,
            resource,
        });
    }
    if args.rewards.is_some() {
        return Err(BadInput(
            "--rewards is for a bare net; a plan has its own [rewards.NAME]".into(),
        )
        .into());
    }
    let plan = gspn::plan::read_plan(&args.file, &args.net.read_options())?;
    let spec = match &args.reward {
        Some(name) => plan
            .rewards
            .iter()
            .find(|r| &r.name == name)
            .cloned()
            .ok_or_else(|| {
                let names: Vec<&str> = plan.rewards.iter().map(|r| r.name.as_str()).collect();
                BadInput(format!(
                    "--reward {name}: the plan has no [rewards.{name}] (it has: {})",
                    if names.is_empty() {
                        "none".to_string()
                    } else {
                        names.join(", ")
                    }
                ))
            })?,
        None => match plan.rewards.len() {
            0 => RewardSpec::default(),
            1 => plan.rewards[0].clone(),
            _ => {
                let names: Vec<&str> = plan.rewards.iter().map(|r| r.name.as_str()).collect();
                return Err(BadInput(format!(
                    "the plan has several reward structures ({}): pick one with --reward NAME",
                    names.join(", ")
                ))
                .into());
            }
        },
    };
    if !plan.policy.is_empty() {
        return Err(BadInput(format!(
            "{}: the plan already has [[policy]] rules; synthesize from a plan without them",
            args.file.display()
        ))
        .into());
    }
    let text = std::fs::read_to_string(&args.file)
        .with_context(|| format!("reading {}", args.file.display()))?;
    let resource = plan
        .roles
        .iter()
        .map(|r| matches!(r, Some(gspn::runtime::Role::Resource)))
        .collect();
    Ok(Input {
        net: plan.net,
        spec,
        controls: plan.controls,
        plan: Some(text),
        resource,
    })
}

/// Refuses a synthesis with nothing to optimise (exit 2, with the reason): no decision to
/// make (no controllable transition, no WAIT), or an objective over rewards without any.
/// Without the check the solver answers 0 and the command looks like it succeeded.
pub(super) fn something_to_optimise(
    args: &Args,
    goal: &Goal,
    spec: &RewardSpec,
    controls: &Controls,
) -> anyhow::Result<()> {
    if !controls.controllable.iter().any(|&c| c) && !controls.wait {
        return Err(BadInput(format!(
            "{}: nothing to optimise: the net has no decision (no controllable immediate \
             transition: weight 0, or a plan's/rewards file's `controllable = [...]`)",
            args.file.display()
        ))
        .into());
    }
    let uses_rewards = matches!(
        goal,
        Goal::Lra | Goal::Total(_) | Goal::Discounted(_) | Goal::PerStep(_)
    );
    if uses_rewards && spec.places.is_empty() && spec.transitions.is_empty() {
        return Err(BadInput(format!(
            "{}: nothing to optimise: --objective {} needs rewards and there are none (a \
             plan's [rewards.NAME] or --rewards FILE with [places]/[transitions])",
            args.file.display(),
            args.objective
        ))
        .into());
    }
    Ok(())
}
