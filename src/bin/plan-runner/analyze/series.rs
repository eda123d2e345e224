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

/// Most times one `A:B:STEP` range may expand to.
const MAX_POINTS: usize = 100_000;

/// `--transient` items: a time `T`, or a range `A:B:STEP` (A, A+STEP, … up to B).
pub(super) fn times(items: &[String]) -> Result<Vec<f64>, BadInput> {
    let mut out = Vec::new();
    for item in items {
        let parts: Vec<&str> = item.split(':').collect();
        let num = |s: &str| -> Result<f64, BadInput> {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|t| t.is_finite() && *t >= 0.0)
                .ok_or_else(|| BadInput(format!("--transient: {s} is not a time ≥ 0")))
        };
        match parts.as_slice() {
            [t] => out.push(num(t)?),
            [a, b, step] => {
                let (a, b) = (num(a)?, num(b)?);
                let step: f64 = step.trim().parse().unwrap_or(f64::NAN);
                if !(step.is_finite() && step > 0.0) || b < a {
                    return Err(BadInput(format!(
                        "--transient {item}: a range is A:B:STEP with A ≤ B and STEP > 0"
                    )));
                }
                let count = ((b - a) / step + 1e-9).floor() as usize + 1;
                if count > MAX_POINTS {
                    return Err(BadInput(format!(
                        "--transient {item}: {count} times, at most {MAX_POINTS}"
                    )));
                }
                out.extend((0..count).map(|k| a + k as f64 * step));
            }
            _ => {
                return Err(BadInput(format!(
                    "--transient {item}: expected a time or A:B:STEP"
                )));
            }
        }
    }
    Ok(out)
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
        .filter(|q| {
            q.extreme.is_none() && matches!(q.kind, Kind::Until { bound: Some(_), .. })
        })
        .map(|q| {
            let times: Vec<f64> = points.iter().map(|p| p.t).collect();
            Ok((q, ev.until_over_time(q, &times).with_context(|| format!("{q}"))?))
        })
        .collect::<anyhow::Result<_>>()?;
    let mut columns: Vec<String> = net.places().iter().map(|p| format!("E[{}]", p.name)).collect();
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
pub(super) fn write(
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
