//! `plan-runner synthesize FILE --objective OBJ [--goal EXPR] [--discount RATE] [--gamma G]
//! [--rewards FILE] [--wait true|false] [--precision P] [--max-states N] [--out FILE]
//! [--rules-json FILE] [--compact] [--json] [--export-drn FILE] [--sweep robots=A..B]`: the
//! optimal policy of a GSPN with rewards (see docs/synthesis.md).

use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Instant;

use anyhow::Context;
use gspn::analysis::decision::{
    Algorithm, BuildOptions, Controls, DecisionError, DecisionModel, Objective, PlaceMode,
    PolicyTable, RewardSpec, Rewards, Solution, SolveOptions, compress, solve,
};
use gspn::analysis::state_space::{AnalysisError, Monitor};
use gspn::io::drn;
use gspn::net::Net;
use gspn::net::predicate::Predicate;
use gspn::policy::{Pattern, Rule};
use serde_json::json;

use crate::common::{BadInput, Interrupted, NetArgs, load_net};
use crate::progress::Spinner;

mod input;
mod policy_file;
mod sweep;

use input::{Goal, algorithm, parse_objective, read_input, something_to_optimise};
use policy_file::{rebase_plan, relative_to, rules_toml};
use sweep::{finite, parse_sweep, run_sweep};

/// Arguments of `synthesize`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// A plan (.toml: its `[rewards.NAME]`, `controllable` and `wait` apply) or a net
    /// (.xml, .pnml, .PNPRO; rewards from --rewards).
    file: PathBuf,
    /// The plan's reward structure to use (default: its only one).
    #[arg(long, value_name = "NAME")]
    reward: Option<String>,
    /// lra-max, lra-min, reach-max, reach-min, total-max, total-min, time-max, time-min,
    /// discounted-max, discounted-min (with --discount RATE), discounted-per-step-max,
    /// discounted-per-step-min (with --gamma G).
    #[arg(long, default_value = "lra-max")]
    objective: String,
    /// The goal of reach-, total- and time- objectives, a marking predicate (`P_done == 3`).
    #[arg(long, value_name = "EXPR")]
    goal: Option<String>,
    /// Discount rate per unit of time of the discounted objectives.
    #[arg(long, value_name = "RATE")]
    discount: Option<f64>,
    /// γ of the per-step discounted objectives (the GSPNR toolbox's).
    #[arg(long, value_name = "G")]
    gamma: Option<f64>,
    /// Rewards, controllable transitions and WAIT, in the GSPNR fixtures' format
    /// (`[places]` rates while marked, `[transitions]` impulses, `controllable = [...]`,
    /// `wait = true|false`).
    #[arg(long, value_name = "FILE")]
    rewards: Option<PathBuf>,
    /// Offer WAIT in hybrid markings (overrides the rewards file).
    #[arg(long, value_name = "BOOL")]
    wait: Option<bool>,
    /// Relative width of the value's interval.
    #[arg(long, default_value_t = 1e-9)]
    precision: f64,
    /// `value` (value iteration with sound bounds), `policy` (policy iteration with exact
    /// evaluation, component by component; long-run average only), then the same bounding
    /// step; `auto`: policy for lra while a policy's components stay small (up to 2,000
    /// states; value iteration for a MEC above), value for the others.
    #[arg(long, value_name = "METHOD", default_value = "auto")]
    method: String,
    /// Most reachable markings before giving up.
    #[arg(long, value_name = "N", default_value_t = 10_000_000)]
    max_states: usize,
    /// Write the policy as `[[policy]]` rules of a plan that `run` executes.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Write the compressed rules (a decision tree over token counts) instead of one rule
    /// per marking.
    #[arg(long)]
    compact: bool,
    /// Write the exact policy rules as JSON: `{"net_hash": H, "rules": [{"marking":
    /// {PLACE: TOKENS, ...}, "choose": TRANSITION}, ...]}`, one rule per decision marking
    /// that fires a transition (places with no token left out).
    #[arg(long, value_name = "FILE")]
    rules_json: Option<PathBuf>,
    /// Print the summary as JSON instead of text (value, sizes, timings, rule counts; the
    /// rules themselves go to --out or --rules-json).
    #[arg(long)]
    json: bool,
    /// Write the model in Storm's DRN format. With --sweep, one file per robot count:
    /// `-nN` before the extension (`model.drn` gives `model-n3.drn` for 3 robots).
    #[arg(long, value_name = "FILE")]
    export_drn: Option<PathBuf>,
    /// Solve for each robot count: `robots=1..10` scales the initial tokens of the places
    /// that are not `role = "resource"` (as `run --robots` does).
    #[arg(long, value_name = "robots=A..B")]
    sweep: Option<String>,
    #[command(flatten)]
    net: NetArgs,
}

/// One solved model with its timings.
struct Solved {
    model: DecisionModel,
    rewards: Rewards,
    solution: Solution,
    build_s: f64,
    solve_s: f64,
}

/// Ctrl-C (SIGINT) cancels `monitor`, which the search checks at each batch of markings and
/// the solver at each sweep or round: the command then stops within about a second with
/// exit code 130 ([`interrupted`]). A thread of its own waits for the signal, registered
/// before any work starts.
fn cancel_on_interrupt(monitor: &Monitor) -> anyhow::Result<()> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_io()
        .build()?;
    #[cfg(unix)]
    let mut int = {
        let _guard = rt.enter();
        tokio::signal::unix::signal(tokio::signal::unix::SignalKind::interrupt())?
    };
    let flag = monitor.cancel_flag();
    std::thread::Builder::new()
        .name("sigint".into())
        .spawn(move || {
            #[cfg(unix)]
            let got = rt.block_on(int.recv()).is_some();
            #[cfg(not(unix))]
            let got = rt.block_on(tokio::signal::ctrl_c()).is_ok();
            if got {
                flag.store(true, Ordering::Relaxed);
            }
        })?;
    Ok(())
}

/// The error of a command that Ctrl-C stopped while `doing`: exit code 130.
fn interrupted(doing: String) -> anyhow::Error {
    anyhow::Error::new(Interrupted {
        what: "synthesize",
        signal: "SIGINT",
        code: 130,
    })
    .context(doing)
}

/// Turns a cancelled search or solver into [`interrupted`] when the monitor was cancelled;
/// any other error gets `context`.
fn or_interrupted(
    e: DecisionError,
    monitor: &Monitor,
    file: &Path,
    context: impl std::fmt::Display + Send + Sync + 'static,
) -> anyhow::Error {
    match e {
        DecisionError::Analysis(AnalysisError::Cancelled { markings })
            if monitor.is_cancelled() =>
        {
            interrupted(format!(
                "{}: stopped building the model after {markings} markings",
                file.display()
            ))
        }
        DecisionError::Cancelled { iterations } if monitor.is_cancelled() => interrupted(format!(
            "{}: stopped solving after {iterations} iterations",
            file.display()
        )),
        e => anyhow::Error::new(e).context(context),
    }
}

#[allow(clippy::too_many_arguments)]
fn synthesize(
    net: &Net,
    controls: &Controls,
    spec: &RewardSpec,
    goal: &Goal,
    max: bool,
    args: &Args,
    progress: bool,
    monitor: &Arc<Monitor>,
) -> anyhow::Result<Solved> {
    let t0 = Instant::now();
    let spinner = Spinner::start(progress, monitor);
    let model = DecisionModel::build(
        net,
        controls,
        &BuildOptions {
            max_states: args.max_states,
            threads: 0,
            monitor: Some(Arc::clone(monitor)),
        },
    )
    .map_err(|e| or_interrupted(e, monitor, &args.file, args.file.display().to_string()))?;
    drop(spinner);
    let build_s = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let flags = |p: &Predicate| model.states_where(|m| p.eval(m));
    let (rewards, objective) = match goal {
        Goal::Lra => (model.rewards(spec), Objective::Lra { max }),
        Goal::Reach(p) => (
            model.rewards(spec),
            Objective::Reach {
                max,
                goal: flags(p),
            },
        ),
        Goal::Total(p) => (
            model.rewards(spec),
            Objective::Total {
                max,
                goal: flags(p),
            },
        ),
        Goal::Time(p) => (
            model.time_rewards(),
            Objective::Total {
                max,
                goal: flags(p),
            },
        ),
        Goal::Discounted(rate) => (
            model.rewards(spec),
            Objective::Discounted { max, rate: *rate },
        ),
        Goal::PerStep(gamma) => (
            model.rewards(spec),
            Objective::DiscountedPerStep { max, gamma: *gamma },
        ),
    };
    let solution = solve(
        &model,
        &rewards,
        &objective,
        &SolveOptions {
            precision: args.precision,
            algorithm: algorithm(args, goal)?,
            cancel: Some(monitor.cancel_flag()),
            ..SolveOptions::default()
        },
    )
    .map_err(|e| or_interrupted(e, monitor, &args.file, "solving"))?;
    let solve_s = t1.elapsed().as_secs_f64();
    Ok(Solved {
        model,
        rewards,
        solution,
        build_s,
        solve_s,
    })
}

/// The value and its bounds as printed: a probability (reach-) clamped to [0, 1], since the
/// solver's sound bounds may overshoot by its precision (`1.000000000124984`).
fn shown(goal: &Goal, sol: &Solution) -> (f64, f64, f64) {
    match goal {
        Goal::Reach(_) => (
            sol.value.clamp(0.0, 1.0),
            sol.lower.clamp(0.0, 1.0),
            sol.upper.clamp(0.0, 1.0),
        ),
        _ => (sol.value, sol.lower, sol.upper),
    }
}

/// The policy table: each decision marking and the transition the solution fires there.
pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    let input = read_input(&args)?;
    let net = &input.net;
    let (goal, max) = parse_objective(&args, net)?;
    let spec = input.spec.clone();
    let mut controls = input.controls.clone();
    if let Some(w) = args.wait {
        controls.wait = w;
    }
    something_to_optimise(&args, &goal, &spec, &controls)?;
    if matches!(goal, Goal::PerStep(_)) {
        // The toolbox counts every vanishing step, races included.
        controls.keep_races = true;
    }
    let progress = !args.json && std::io::stderr().is_terminal();
    let monitor = Arc::new(Monitor::new());
    cancel_on_interrupt(&monitor)?;
    if let Some(sweep) = &args.sweep {
        refuse_policy_outputs_in_sweep(&args)?;
        return run_sweep(
            &args,
            net,
            &input.resource,
            &controls,
            &spec,
            &goal,
            max,
            parse_sweep(sweep)?,
            &monitor,
        );
    }
    let s = synthesize(net, &controls, &spec, &goal, max, &args, progress, &monitor)?;
    let check = |doing: &str| {
        if monitor.is_cancelled() {
            Err(interrupted(format!(
                "{}: stopped {doing}",
                args.file.display()
            )))
        } else {
            Ok(())
        }
    };
    if let Some(path) = &args.export_drn {
        let text = drn::to_string(net, &s.model, &[(spec.name.as_str(), &s.rewards)], &[]);
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    check("after solving")?;
    let PolicyTable {
        fires: table,
        waits,
    } = s.model.policy_table(&s.solution.policy);
    let compressed = compress(&table);
    check("compressing the policy")?;
    let policy = Synthesised {
        s: &s,
        shown: shown(&goal, &s.solution),
        table: &table,
        waits,
        compressed: &compressed,
    };
    if let Some(out) = &args.out {
        let text = policy.file(&args, &input, out)?;
        std::fs::write(out, text).with_context(|| format!("writing {}", out.display()))?;
    }
    if let Some(path) = &args.rules_json {
        policy
            .write_rules_json(net, path)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&policy.json(&args, net))?
        );
    } else {
        policy.print(&args);
    }
    Ok(ExitCode::SUCCESS)
}

/// `--sweep` solves several models and writes no policy: the options that write one are
/// refused (exit code 2) rather than silently ignored.
fn refuse_policy_outputs_in_sweep(args: &Args) -> anyhow::Result<()> {
    let given = crate::common::given_flags(&[
        (args.out.is_some(), "--out"),
        (args.rules_json.is_some(), "--rules-json"),
        (args.compact, "--compact"),
    ]);
    if given.is_empty() {
        return Ok(());
    }
    Err(BadInput(format!(
        "--sweep writes no policy, so {} would write nothing: synthesize one robot count \
         without --sweep to get its rules (--export-drn writes one model per robot count)",
        given.join(" and ")
    ))
    .into())
}

/// A solved model with its policy as rules, ready to be written and reported.
struct Synthesised<'a> {
    s: &'a Solved,
    /// The value and its interval as printed ([`shown`]).
    shown: (f64, f64, f64),
    /// Each decision marking that fires a transition, and that transition.
    table: &'a [(Vec<u32>, gspn::net::TransitionId)],
    /// Decision markings that choose WAIT.
    waits: usize,
    compressed: &'a [Rule],
}

impl Synthesised<'_> {
    /// `--out FILE`: the plan (or a plan naming the net) with the policy's rules, its paths
    /// rebased to the file's directory, and a header saying what was solved.
    fn file(&self, args: &Args, input: &input::Input, out: &Path) -> anyhow::Result<String> {
        let (net, sol) = (&input.net, &self.s.solution);
        let (value, lower, upper) = self.shown;
        let dir = out
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let mut text = String::new();
        let _ = writeln!(text, "# policy synthesised by plan-runner synthesize");
        let _ = writeln!(
            text,
            "# net: {} (hash {})",
            net.name(),
            gspn::runtime::journal::net_hash(net)
        );
        let _ = writeln!(
            text,
            "# objective: {}, optimal value {value} in [{lower}, {upper}] ({:?})",
            args.objective, sol.method
        );
        let _ = writeln!(
            text,
            "# {} decision markings; {} exact rules, {} compressed rules{}",
            self.table.len() + self.waits,
            self.table.len(),
            self.compressed.len(),
            if args.compact { " (written here)" } else { "" }
        );
        if self.waits > 0 {
            let _ = writeln!(
                text,
                "# {} markings choose WAIT: no rule (run fires an immediate transition at once)",
                self.waits
            );
        }
        match &input.plan {
            None => {
                let net_rel = relative_to(&args.file, dir);
                let _ = writeln!(text, "net = {:?}", net_rel.to_string_lossy());
            }
            Some(plan_text) => text.push_str(&rebase_plan(&args.file, plan_text, dir)?),
        }
        if args.compact {
            text.push_str(&rules_toml(net, self.compressed));
        } else {
            // One exact rule per decision marking, built only here: the table holds the same.
            let exact: Vec<Rule> = self
                .table
                .iter()
                .map(|(m, t)| Rule {
                    pattern: Pattern::Exact(m.clone()),
                    choose: vec![(*t, 1.0)],
                })
                .collect();
            text.push_str(&rules_toml(net, &exact));
        }
        Ok(text)
    }

    /// `--rules-json FILE`: the exact rules, streamed one at a time (a model of a million
    /// decision markings would otherwise hold its whole JSON tree in memory).
    fn write_rules_json(&self, net: &Net, path: &Path) -> anyhow::Result<()> {
        use std::io::Write as _;
        let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
        write!(
            w,
            "{{\"net_hash\": {},\n\"rules\": [",
            serde_json::to_string(&gspn::runtime::journal::net_hash(net))?
        )?;
        for (i, (m, t)) in self.table.iter().enumerate() {
            let marking: serde_json::Map<String, serde_json::Value> = m
                .iter()
                .enumerate()
                .filter(|&(_, &k)| k > 0)
                .map(|(p, &k)| (net.places()[p].name.clone(), json!(k)))
                .collect();
            let rule = json!({ "marking": marking, "choose": net.transition(*t).name });
            let sep = if i == 0 { "\n" } else { ",\n" };
            write!(w, "{sep}{}", serde_json::to_string(&rule)?)?;
        }
        writeln!(w, "\n]}}")?;
        w.flush()?;
        Ok(())
    }

    /// `--json`: the value, the model's size, the timings and the rule counts (the rules
    /// themselves go to `--out` or `--rules-json`).
    fn json(&self, args: &Args, net: &Net) -> serde_json::Value {
        let (s, sol) = (self.s, &self.s.solution);
        let (value, lower, upper) = self.shown;
        json!({
            "objective": args.objective,
            "value": finite(value),
            "lower": finite(lower),
            "upper": finite(upper),
            "method": format!("{:?}", sol.method),
            "iterations": sol.iterations,
            "states": s.model.state_count(),
            "choices": s.model.choice_count(),
            "markings": s.model.marking_count(),
            "wait_copies": s.model.wait_copies(),
            "eliminated": s.model.eliminated_count(),
            "toolbox_states": s.model.toolbox_state_count(),
            "build_s": s.build_s,
            "solve_s": s.solve_s,
            "decision_markings": self.table.len() + self.waits,
            "wait_markings": self.waits,
            "exact_rules": self.table.len(),
            "compressed_rules": self.compressed.len(),
            "net_hash": gspn::runtime::journal::net_hash(net),
        })
    }

    /// The text report.
    fn print(&self, args: &Args) {
        let (s, sol) = (self.s, &self.s.solution);
        let (value, lower, upper) = self.shown;
        println!(
            "{} states ({} markings, {} WAIT copies, {} eliminated), {} choices",
            s.model.state_count(),
            s.model.marking_count(),
            s.model.wait_copies(),
            s.model.eliminated_count(),
            s.model.choice_count()
        );
        println!(
            "{}: {value} in [{lower}, {upper}] ({:?}, {} iterations)",
            args.objective, sol.method, sol.iterations
        );
        println!(
            "policy: {} decision markings, {} exact rules, {} compressed rules",
            self.table.len() + self.waits,
            self.table.len(),
            self.compressed.len()
        );
        println!("build {:.3} s, solve {:.3} s", s.build_s, s.solve_s);
    }
}
