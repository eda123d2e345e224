//! `plan-runner import-thesis INPUT.json [--out DIR] [--net FILE]`.

use std::path::PathBuf;
use std::process::ExitCode;

use gspn::plan::thesis::{ImportOptions, import};

/// Arguments of `import-thesis`.
#[derive(clap::Args, Debug)]
#[command(
    long_about = "Turn an execution input of the 2020 thesis framework (JSON whose values are \
                  Python literals: places_tuple, policy_dictionary with '-' wildcards, \
                  place_to_function_mapping or place_to_client_mapping, resources_list) into \
                  DIR/plan.toml next to a copy of its net. The net is the input's `gspn` path, \
                  relative to the JSON file, or a file of that name beside it, or --net. \
                  place_to_function_mapping entries (`module.function`) go to a Python worker \
                  written beside the plan (thesis_functions.py, which needs the gspn Python package's gspn.worker) that \
                  imports the module from the input's project_path (relative to the JSON \
                  file, else the JSON's directory; --project-path overrides) and calls \
                  function(agent_id); place_to_client_mapping entries become `ros2` places. \
                  A place or transition that is not in the net is bad input (exit 2) with the \
                  JSON file's line and column. See docs/plans.md."
)]
pub(crate) struct Args {
    /// The thesis execution input (JSON).
    input: PathBuf,
    /// Directory for plan.toml and the net's copy (default: the input's file stem).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// The net file, when the input's `gspn` path does not lead to it.
    #[arg(long, value_name = "FILE")]
    net: Option<PathBuf>,
    /// The directory of the `place_to_function_mapping` modules, when the input's
    /// `project_path` (relative to the JSON file) does not lead to it.
    #[arg(long, value_name = "DIR")]
    project_path: Option<PathBuf>,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    let out = args.out.unwrap_or_else(|| {
        PathBuf::from(
            args.input
                .file_stem()
                .map_or_else(|| "imported".into(), |s| s.to_string_lossy().into_owned()),
        )
    });
    let imported = import(
        &args.input,
        &ImportOptions {
            out,
            net: args.net,
            project_path: args.project_path,
        },
    )?;
    for w in &imported.warnings {
        eprintln!("warning: {}: {w}", args.input.display());
    }
    let plan = &imported.plan;
    eprintln!(
        "wrote {} and {} ({} places, {} transitions, {} policy rules, {} place roles)",
        imported.plan_path.display(),
        imported.net_path.display(),
        plan.net.place_count(),
        plan.net.transition_count(),
        plan.policy.rules().len(),
        plan.roles.iter().flatten().count()
    );
    Ok(ExitCode::SUCCESS)
}
