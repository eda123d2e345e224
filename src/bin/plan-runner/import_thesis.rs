//! `plan-runner import_thesis` (being written).

use std::process::ExitCode;

/// Arguments of `import_thesis`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// Input file.
    file: std::path::PathBuf,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!(
        "{}: `import_thesis` is not implemented yet",
        args.file.display()
    )
}
