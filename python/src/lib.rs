//! `gspn._native`: the engine behind the `gspn` Python package (`python/gspn/`).
//!
//! Each function takes plain Python values and runs the library on a thread of its own with
//! the GIL released ([`wait::interruptible`]): Ctrl-C reaches Python within a twentieth of a
//! second and cancels the work. Results cross as JSON text, which the Python side turns into
//! typed results (numpy arrays, dataclasses); the numbers are the ones `plan-runner … --json`
//! prints, because they come from the same library calls. Errors become the exceptions of
//! `gspn.errors`, carrying the file, line and column of bad input.

use pyo3::prelude::*;

mod analyze;
mod errors;
mod model;
mod run;
mod simulate;
mod synthesize;
mod wait;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<model::Model>()?;
    m.add_function(wrap_pyfunction!(model::load, m)?)?;
    m.add_function(wrap_pyfunction!(model::build, m)?)?;
    m.add_function(wrap_pyfunction!(analyze::analyze, m)?)?;
    m.add_function(wrap_pyfunction!(analyze::query, m)?)?;
    m.add_function(wrap_pyfunction!(synthesize::synthesize, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
