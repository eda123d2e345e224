//! `plan-runner check FILE [--json]`.

use std::path::PathBuf;
use std::process::ExitCode;

use crate::common::{NetArgs, load_net};

/// Arguments of `check`.
#[derive(clap::Args, Debug)]
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
    let loaded = load_net(&args.file, &args.net)?;
    let _ = args.json;
    println!(
        "{}: {} places",
        args.file.display(),
        loaded.net.place_count()
    );
    Ok(ExitCode::SUCCESS)
}
