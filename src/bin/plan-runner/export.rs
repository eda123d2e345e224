//! `plan-runner export JOURNAL OUT.mcap`: a run's journal as MCAP (feature `ros2`), and the
//! same export at the end of `run --journal OUT.mcap`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use crate::common::BadInput;

/// Arguments of `export`.
#[derive(clap::Args, Debug)]
#[command(
    long_about = "Write a run's journal (JSON Lines) as MCAP, the storage of rosbag2 that \
                  Foxglove and `ros2 bag play` open: firings, markings and drifts as \
                  gspn_msgs messages and the simulated robots' poses as \
                  geometry_msgs/PoseStamped on /<robot>/pose, with ros2msg schemas and CDR \
                  payloads (feature `ros2`; docs/ros2.md, \"Runs recorded to MCAP\")."
)]
pub(crate) struct Args {
    /// The journal (`run --journal FILE.jsonl`).
    journal: PathBuf,
    /// The MCAP file to write (.mcap).
    output: PathBuf,
}

/// Whether `path` names an MCAP file (by its extension).
pub(crate) fn is_mcap(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
}

/// Where `run --journal OUT.mcap` writes its JSON Lines journal: `OUT.mcap.jsonl`.
pub(crate) fn journal_beside(mcap: &Path) -> PathBuf {
    let mut s = mcap.as_os_str().to_owned();
    s.push(".jsonl");
    PathBuf::from(s)
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    if !is_mcap(&args.output) {
        return Err(BadInput(format!(
            "{}: the output must be an .mcap file",
            args.output.display()
        ))
        .into());
    }
    let n = write(&args.journal, &args.output)?;
    eprintln!(
        "{}: {} firings, {} markings, {} drifts, {} poses of {} robot(s)",
        args.output.display(),
        n.0,
        n.1,
        n.2,
        n.3,
        n.4
    );
    Ok(ExitCode::SUCCESS)
}

/// Exports `journal` to `output`; the counts of firings, markings, drifts, poses, robots.
#[cfg(feature = "ros2")]
pub(crate) fn write(journal: &Path, output: &Path) -> anyhow::Result<(u64, u64, u64, u64, u64)> {
    let text = std::fs::read_to_string(journal)
        .map_err(|e| BadInput(format!("{}: {e}", journal.display())))?;
    let file =
        std::fs::File::create(output).map_err(|e| anyhow::anyhow!("{}: {e}", output.display()))?;
    let n = gspn::ros2::bag::export(&text, std::io::BufWriter::new(file)).map_err(|e| match e {
        gspn::ros2::bag::BagError::Journal { .. } => {
            anyhow::Error::from(BadInput(format!("{}: {e}", journal.display())))
        }
        e => anyhow::anyhow!("{}: {e}", output.display()),
    })?;
    if n.skipped > 0 {
        eprintln!(
            "warning: {}: its last line was cut short (a killed run) and is left out",
            journal.display()
        );
    }
    Ok((n.firings, n.markings, n.drifts, n.poses, n.robots))
}

/// Without the feature: refused (exit 2).
#[cfg(not(feature = "ros2"))]
pub(crate) fn write(_journal: &Path, output: &Path) -> anyhow::Result<(u64, u64, u64, u64, u64)> {
    Err(BadInput(format!(
        "{}: MCAP export needs the feature `ros2` (cargo build --features ros2)",
        output.display()
    ))
    .into())
}
