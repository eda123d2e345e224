//! `plan-runner convert IN OUT`: read a net in one format, write it in another.

use std::path::PathBuf;
use std::process::ExitCode;

use gspn::io::{Format, write_net};

use crate::common::{BadInput, NetArgs, load_net};

/// Arguments of `convert`.
#[derive(clap::Args, Debug)]
#[command(
    long_about = "Read a net (PIPE .xml, PNML .pnml, GreatSPN .PNPRO) and write it in the \
                  format named by OUT's extension: .PNPRO, .pnml (with the timed extension), \
                  .xml (PIPE) or .dot (Graphviz, write only)."
)]
pub(crate) struct Args {
    /// The net to read.
    input: PathBuf,
    /// Where to write it; the extension picks the format.
    output: PathBuf,
    #[command(flatten)]
    net: NetArgs,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    let format = match Format::from_extension(&args.output) {
        Some(Format::Plan) | None => {
            return Err(BadInput(format!(
                "{}: cannot tell the output format from the extension (use .PNPRO, .pnml, .xml or .dot)",
                args.output.display()
            ))
            .into());
        }
        Some(f) => f,
    };
    let loaded = load_net(&args.input, &args.net)?;
    for w in &loaded.warnings {
        eprintln!("warning: {}: {w}", args.input.display());
    }
    write_net(&loaded.net, &args.output, format)?;
    eprintln!(
        "wrote {} ({}, {} places, {} transitions)",
        args.output.display(),
        format.name(),
        loaded.net.place_count(),
        loaded.net.transition_count()
    );
    Ok(ExitCode::SUCCESS)
}
