//! `plan-runner run` (being written).

use std::process::ExitCode;

/// Arguments of `run`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// Input file.
    file: std::path::PathBuf,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("{}: `run` is not implemented yet", args.file.display())
}
