//! `plan-runner check FILE [--json]`: summary and structural warnings of a net or a plan.

use std::path::PathBuf;
use std::process::ExitCode;

use gspn::check::Report;
use gspn::plan::Opened;

use crate::common::NetArgs;

/// Arguments of `check`.
#[derive(clap::Args, Debug)]
#[command(
    long_about = "Load a net (PIPE .xml, PNML .pnml, GreatSPN .PNPRO) or a plan (.toml) and print \
                  a summary (places, transitions, arcs, tokens) and warnings: transitions that \
                  can never fire structurally, isolated places, policy rules that can never \
                  apply. With --json the keys are format, places, transitions, immediate, \
                  exponential, arcs (every kind), inhibitor_arcs, tokens, warnings. \
                  Exit code 0 when the file loads (warnings or not), 2 on bad input."
)]
pub(crate) struct Args {
    /// A net (.xml, .pnml, .PNPRO) or a plan (.toml).
    file: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    net: NetArgs,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    let (report, extra) = match crate::common::open_checked(&args.file, &args.net)? {
        Opened::Plan(plan) => {
            let roles = plan.roles.iter().flatten().count();
            let extra = format!(
                "net {}; {} policy rule(s), {roles} place role(s)",
                plan.net_path.display(),
                plan.policy.rules().len()
            );
            (Report::for_plan(&plan), Some(extra))
        }
        Opened::Net { loaded, .. } => (
            Report::for_net(&loaded.net, loaded.format, &loaded.warnings),
            None,
        ),
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!("{}: {}", args.file.display(), report.format);
    if let Some(extra) = extra {
        println!("  {extra}");
    }
    println!(
        "  {} places, {} transitions ({} immediate, {} exponential), {} arcs ({} inhibitor), {} tokens",
        report.places,
        report.transitions,
        report.immediate,
        report.exponential,
        report.arcs,
        report.inhibitor_arcs,
        report.tokens
    );
    if report.warnings.is_empty() {
        println!("  no warnings");
    } else {
        println!("warnings:");
        for w in &report.warnings {
            println!("  - {w}");
        }
    }
    Ok(ExitCode::SUCCESS)
}
