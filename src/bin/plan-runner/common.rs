//! What every command shares: net options, loading, exit codes.

use std::path::Path;

use gspn::io::{LoadError, Loaded, ReadOptions, read_net};

/// Options of every command that reads a net.
#[derive(clap::Args, Debug, Clone, Default)]
pub(crate) struct NetArgs {
    /// The page to read (PNPRO files may hold several `<gspn>` pages).
    #[arg(long, value_name = "NAME")]
    pub(crate) page: Option<String>,
    /// Set a template parameter (PNPRO), overriding the file's last binding. Repeatable.
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = parse_param)]
    pub(crate) params: Vec<(String, String)>,
}

impl NetArgs {
    pub(crate) fn read_options(&self) -> ReadOptions {
        ReadOptions {
            page: self.page.clone(),
            params: self.params.clone(),
        }
    }
}

fn parse_param(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.trim().to_string())),
        _ => Err(format!("`{s}` is not NAME=VALUE")),
    }
}

/// Bad input the user gave on the command line (exit code 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct BadInput(pub(crate) String);

/// Reads a net file with the command's options.
pub(crate) fn load_net(path: &Path, args: &NetArgs) -> anyhow::Result<Loaded> {
    Ok(read_net(path, &args.read_options())?)
}

/// Interrupted by Ctrl-C before the run could start (exit code 130).
#[derive(Debug, thiserror::Error)]
#[error("interrupted {0}")]
pub(crate) struct Interrupted(pub(crate) &'static str);

/// Exit code for an error: 2 for bad input, 130 when interrupted, 1 for anything else.
pub(crate) fn exit_code_for(e: &anyhow::Error) -> u8 {
    for cause in e.chain() {
        if cause.is::<Interrupted>() {
            return 130;
        }
        if cause.is::<LoadError>() || cause.is::<BadInput>() {
            return 2;
        }
    }
    1
}
