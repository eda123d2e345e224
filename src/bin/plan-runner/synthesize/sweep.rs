//! `synthesize --sweep robots=A..B`: one synthesis per robot count, as a table.

use super::*;

/// Without the robot world (feature `sim`) there is no robot scaling.
#[cfg(not(feature = "sim"))]
pub(super) fn scaled(_: &Net, _: &[bool], _: usize) -> anyhow::Result<Net> {
    Err(
        BadInput("--sweep scales robots like `run --robots`: build with feature `sim`".into())
            .into(),
    )
}

/// Parses `robots=A..B`.
pub(super) fn parse_sweep(s: &str) -> anyhow::Result<std::ops::RangeInclusive<usize>> {
    let bad = || {
        BadInput(format!(
            "--sweep `{s}`: expected robots=A..B, e.g. robots=1..10"
        ))
    };
    let range = s.strip_prefix("robots=").ok_or_else(bad)?;
    let (a, b) = range.split_once("..").ok_or_else(bad)?;
    let a: usize = a.trim().parse().map_err(|_| bad())?;
    let b: usize = b
        .trim_start_matches('=')
        .trim()
        .parse()
        .map_err(|_| bad())?;
    if a == 0 || b < a {
        return Err(bad().into());
    }
    Ok(a..=b)
}

/// The net with its initial robots scaled to `n`: every marked place's share, largest
/// remainder first (as `run --robots` scales a plan's robot places). Places whose tokens
/// are a `resource` (a charger, a counter) keep theirs: they are not robots.
#[cfg(feature = "sim")]
pub(super) fn scaled(net: &Net, resource: &[bool], n: usize) -> anyhow::Result<Net> {
    let robot: Vec<bool> = net
        .places()
        .iter()
        .zip(resource)
        .map(|(p, &res)| p.initial > 0 && !res)
        .collect();
    let m = gspn::world::fleet::scaled_marking(net, &robot, n);
    net.with_initial_marking(&m)
        .map_err(|e| anyhow::anyhow!("scaling the initial marking: {e}"))
}

/// The DRN file of robot count `n` in a sweep: `-nN` before the extension of `--export-drn`'s
/// path (`model.drn` → `model-n3.drn`; `model` → `model-n3`).
pub(super) fn drn_for(path: &Path, n: usize) -> PathBuf {
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    let name = match path.extension() {
        Some(ext) => format!("{stem}-n{n}.{}", ext.to_string_lossy()),
        None => format!("{stem}-n{n}"),
    };
    path.with_file_name(name)
}

pub(super) fn finite(v: f64) -> serde_json::Value {
    if v.is_finite() {
        json!(v)
    } else {
        json!(format!("{v}"))
    }
}
#[allow(clippy::too_many_arguments)]
pub(super) fn run_sweep(
    args: &Args,
    net: &Net,
    resource: &[bool],
    controls: &Controls,
    spec: &RewardSpec,
    goal: &Goal,
    max: bool,
    range: std::ops::RangeInclusive<usize>,
    monitor: &Arc<Monitor>,
) -> anyhow::Result<ExitCode> {
    let mut rows = Vec::new();
    if !args.json {
        println!(
            "{:>6} {:>10} {:>10} {:>10} {:>10} {:>14}",
            "robots", "states", "choices", "build_s", "solve_s", "value"
        );
    }
    for n in range {
        let t0 = Instant::now();
        let net_n = scaled(net, resource, n)?;
        let s = synthesize(&net_n, controls, spec, goal, max, args, false, monitor)?;
        let total = t0.elapsed().as_secs_f64();
        let (value, lower, upper) = shown(goal, &s.solution);
        let drn_file = match &args.export_drn {
            Some(path) => {
                let file = drn_for(path, n);
                let text =
                    drn::to_string(&net_n, &s.model, &[(spec.name.as_str(), &s.rewards)], &[]);
                std::fs::write(&file, text)
                    .with_context(|| format!("writing {}", file.display()))?;
                Some(file)
            }
            None => None,
        };
        if args.json {
            rows.push(json!({
                "robots": n,
                "states": s.model.state_count(),
                "choices": s.model.choice_count(),
                "toolbox_states": s.model.toolbox_state_count(),
                "build_s": s.build_s,
                "solve_s": s.solve_s,
                "total_s": total,
                "value": finite(value),
                "lower": finite(lower),
                "upper": finite(upper),
                "drn": drn_file.as_ref().map(|f| f.display().to_string()),
            }));
        } else {
            println!(
                "{n:>6} {:>10} {:>10} {:>10.4} {:>10.4} {:>14.9}",
                s.model.state_count(),
                s.model.choice_count(),
                s.build_s,
                s.solve_s,
                value
            );
        }
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    }
    Ok(ExitCode::SUCCESS)
}
