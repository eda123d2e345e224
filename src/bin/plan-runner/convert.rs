//! `plan-runner convert` (being written).

use std::process::ExitCode;

/// Arguments of `convert`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// Input file.
    file: std::path::PathBuf,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("{}: `convert` is not implemented yet", args.file.display())
}
