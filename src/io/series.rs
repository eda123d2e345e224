//! Measures over time as data and as a picture: a table of named columns against time,
//! written as CSV (`analyze --transient 0:600:10 --csv`, `simulate --runs … --csv`) or as an
//! SVG line plot (plotters, its SVG backend: no browser, no font files).
//!
//! ```
//! use gspn::io::series::Series;
//! let mut s = Series::new(vec!["E[P1]".into(), "P(done)".into()]);
//! s.push(0.0, vec![2.0, 0.0]);
//! s.push(1.5, vec![1.25, 0.5]);
//! assert_eq!(s.to_csv(), "t,E[P1],P(done)\n0,2,0\n1.5,1.25,0.5\n");
//! let svg = s.to_svg("cyc3", &[1]).unwrap();
//! assert!(svg.starts_with("<svg") && svg.contains("P(done)"));
//! ```

use plotters::prelude::*;

/// Most times one `A:B:STEP` range may expand to.
pub const MAX_POINTS: usize = 100_000;

/// Why [`parse_times`] refused an item (each names it).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TimesError {
    /// A time that is not a finite number ≥ 0.
    #[error("{0} is not a time ≥ 0")]
    NotATime(String),
    /// A range `A:B:STEP` with `B < A` or `STEP ≤ 0`.
    #[error("{0}: a range is A:B:STEP with A ≤ B and STEP > 0")]
    BadRange(String),
    /// A range of more than [`MAX_POINTS`] times.
    #[error("{item}: {count} times, at most {MAX_POINTS}")]
    TooMany {
        /// The range as written.
        item: String,
        /// How many times it holds.
        count: f64,
    },
    /// Neither a time nor a range.
    #[error("{0}: expected a time or A:B:STEP")]
    Syntax(String),
}

/// Times written as the CLI takes them (`--transient 0.5,0:600:10`): each item a time `T`
/// or a range `A:B:STEP` (A, A+STEP, … up to B), every time ≥ 0. The error names the item.
///
/// ```
/// use gspn::io::series::parse_times;
/// assert_eq!(parse_times(&["0:1:0.25".into(), "5".into()]).unwrap(), vec![0.0, 0.25, 0.5, 0.75, 1.0, 5.0]);
/// assert!(parse_times(&["2:1:1".into()]).unwrap_err().to_string().contains("A ≤ B"));
/// ```
pub fn parse_times(items: &[String]) -> Result<Vec<f64>, TimesError> {
    let mut out = Vec::new();
    for item in items {
        let parts: Vec<&str> = item.split(':').collect();
        let num = |s: &str| -> Result<f64, TimesError> {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|t| t.is_finite() && *t >= 0.0)
                .ok_or_else(|| TimesError::NotATime(s.trim().to_string()))
        };
        match parts.as_slice() {
            [t] => out.push(num(t)?),
            [a, b, step] => {
                let (a, b) = (num(a)?, num(b)?);
                let step: f64 = step.trim().parse().unwrap_or(f64::NAN);
                if !(step.is_finite() && step > 0.0) || b < a {
                    return Err(TimesError::BadRange(item.clone()));
                }
                let count = ((b - a) / step * (1.0 + 1e-12)).floor() + 1.0;
                if count > MAX_POINTS as f64 {
                    return Err(TimesError::TooMany {
                        item: item.clone(),
                        count,
                    });
                }
                out.extend((0..count as usize).map(|k| a + k as f64 * step));
            }
            _ => return Err(TimesError::Syntax(item.clone())),
        }
    }
    Ok(out)
}

/// Columns of numbers against time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    /// The column names (time not included).
    pub columns: Vec<String>,
    /// `(t, one value per column)`, in the order pushed.
    pub rows: Vec<(f64, Vec<f64>)>,
}

/// Why a plot could not be drawn.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("plot: {0}")]
pub struct PlotError(pub String);

/// The colours of the lines, in turn (plotters' palette 99, readable on white).
fn colour(i: usize) -> RGBColor {
    let (r, g, b) = Palette99::COLORS[i % Palette99::COLORS.len()];
    RGBColor(r, g, b)
}

/// A CSV field: quoted when it holds a comma, a quote or a line break.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

impl Series {
    /// An empty table with these columns.
    pub fn new(columns: Vec<String>) -> Self {
        Series {
            columns,
            rows: Vec::new(),
        }
    }

    /// Appends the row at time `t` (one value per column).
    pub fn push(&mut self, t: f64, values: Vec<f64>) {
        debug_assert_eq!(values.len(), self.columns.len());
        self.rows.push((t, values));
    }

    /// The table as CSV: a header `t,NAME,…`, then one line per time; numbers in Rust's
    /// shortest round-trip form (`inf` for an infinite value).
    pub fn to_csv(&self) -> String {
        let mut out = String::from("t");
        for c in &self.columns {
            out.push(',');
            out.push_str(&field(c));
        }
        out.push('\n');
        for (t, values) in &self.rows {
            out.push_str(&t.to_string());
            for v in values {
                out.push(',');
                out.push_str(&v.to_string());
            }
            out.push('\n');
        }
        out
    }

    /// A line plot of the columns `which` (indices into [`Series::columns`]) against time,
    /// titled `title`, as an SVG document (800 × 500). Non-finite values are left out.
    pub fn to_svg(&self, title: &str, which: &[usize]) -> Result<String, PlotError> {
        let err = |e: &dyn std::fmt::Display| PlotError(e.to_string());
        if let Some(&bad) = which.iter().find(|&&i| i >= self.columns.len()) {
            return Err(PlotError(format!("no column {bad}")));
        }
        let finite = |v: &f64| v.is_finite();
        let t_max = self.rows.iter().map(|r| r.0).fold(0.0, f64::max);
        let t_min = self.rows.iter().map(|r| r.0).fold(t_max, f64::min);
        let values = || {
            self.rows
                .iter()
                .flat_map(|(_, v)| which.iter().map(move |&i| v[i]))
                .filter(finite)
        };
        let y_max = values().fold(f64::NEG_INFINITY, f64::max);
        let y_min = values().fold(f64::INFINITY, f64::min).min(0.0);
        let y_max = if y_max.is_finite() && y_max > y_min {
            y_max
        } else {
            y_min + 1.0
        };
        let x_max = if t_max > t_min { t_max } else { t_min + 1.0 };
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (800, 500)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| err(&e))?;
            let mut chart = ChartBuilder::on(&root)
                .caption(title, ("sans-serif", 20))
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d(t_min..x_max, y_min..y_max * 1.05)
                .map_err(|e| err(&e))?;
            chart
                .configure_mesh()
                .x_desc("t")
                .draw()
                .map_err(|e| err(&e))?;
            for (k, &i) in which.iter().enumerate() {
                let c = colour(k);
                let points: Vec<(f64, f64)> = self
                    .rows
                    .iter()
                    .filter(|(_, v)| v[i].is_finite())
                    .map(|(t, v)| (*t, v[i]))
                    .collect();
                chart
                    .draw_series(LineSeries::new(points, c.stroke_width(2)))
                    .map_err(|e| err(&e))?
                    .label(self.columns[i].clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(|e| err(&e))?;
            root.present().map_err(|e| err(&e))?;
        }
        Ok(svg)
    }
}
