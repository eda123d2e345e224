//! `analyze --transient 0:600:10 --csv FILE --plot FILE.svg`: the transient measures as a
//! table over time — E[tokens] of every place, each `--prob` predicate, and each
//! time-bounded `--query` `P=? [F<=t φ]` with its bound set to the row's time.

use std::path::Path;

use anyhow::Context;
use gspn::analysis::measures::TransientPoint;
use gspn::analysis::query::{Evaluator, Kind, Query};
use gspn::io::series::Series;
use gspn::net::Net;

use crate::common::BadInput;

/// `--transient` items: a time `T`, or a range `A:B:STEP` (A, A+STEP, … up to B).
pub(crate) fn times(items: &[String]) -> Result<Vec<f64>, BadInput> {
    gspn::io::series::parse_times(items).map_err(|e| BadInput(format!("--transient: {e}")))
}

/// The columns: `E[place]` for every place, `P(expr)` for every predicate, then every
/// time-bounded `P=?` query.
pub(super) fn table(
    net: &Net,
    points: &[TransientPoint],
    prob: &[String],
    queries: &[Query],
    ev: &Evaluator<'_>,
) -> anyhow::Result<(Series, Vec<usize>)> {
    let curves: Vec<(&Query, Vec<f64>)> = queries
        .iter()
        .filter(|q| q.extreme.is_none() && matches!(q.kind, Kind::Until { bound: Some(_), .. }))
        .map(|q| {
            let times: Vec<f64> = points.iter().map(|p| p.t).collect();
            Ok((
                q,
                ev.until_over_time(q, &times)
                    .with_context(|| format!("{q}"))?,
            ))
        })
        .collect::<anyhow::Result<_>>()?;
    let mut columns: Vec<String> = net
        .places()
        .iter()
        .map(|p| format!("E[{}]", p.name))
        .collect();
    columns.extend(prob.iter().map(|e| format!("P({e})")));
    columns.extend(curves.iter().map(|(q, _)| q.source().to_string()));
    let mut s = Series::new(columns);
    for (i, p) in points.iter().enumerate() {
        let mut row = p.measures.mean_tokens.clone();
        row.extend(&p.probabilities);
        row.extend(curves.iter().map(|(_, v)| v[i]));
        s.push(p.t, row);
    }
    // Plot the probabilities asked for when there are any, else every place's E[tokens].
    let places = net.place_count();
    let plotted = if s.columns.len() > places {
        (places..s.columns.len()).collect()
    } else {
        (0..places).collect()
    };
    Ok((s, plotted))
}

/// Writes the CSV and the SVG asked for.
pub(crate) fn write(
    s: &Series,
    plotted: &[usize],
    title: &str,
    csv: Option<&Path>,
    plot: Option<&Path>,
) -> anyhow::Result<()> {
    if let Some(path) = csv {
        std::fs::write(path, s.to_csv()).with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = plot {
        let svg = s.to_svg(title, plotted)?;
        std::fs::write(path, svg).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
