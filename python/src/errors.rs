//! Failures of the engine, raised in Python as the exceptions of `gspn.errors`.

use std::path::PathBuf;

use gspn::io::LoadError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// What went wrong, built on the worker thread (no GIL) and raised on the caller's.
#[derive(Debug)]
pub(crate) enum Failure {
    /// Bad input (`gspn.errors.InputError`, a `ValueError`): the file, line and column when
    /// the input was a file.
    Input {
        message: String,
        file: Option<PathBuf>,
        line: Option<u32>,
        column: Option<u32>,
    },
    /// The analysis could not answer (`gspn.errors.AnalysisError`).
    Analysis(String),
    /// A run could not start or failed (`gspn.errors.RunError`).
    Run(String),
}

impl Failure {
    /// Bad input that is not in a file (an argument, an expression).
    pub(crate) fn input(message: impl Into<String>) -> Failure {
        Failure::Input {
            message: message.into(),
            file: None,
            line: None,
            column: None,
        }
    }

    /// The Python exception.
    pub(crate) fn into_py(self, py: Python<'_>) -> PyErr {
        match self.raise(py) {
            Ok(e) | Err(e) => e,
        }
    }

    fn raise(self, py: Python<'_>) -> PyResult<PyErr> {
        let errors = py.import("gspn.errors")?;
        let kwargs = PyDict::new(py);
        let (class, message) = match self {
            Failure::Input {
                message,
                file,
                line,
                column,
            } => {
                kwargs.set_item("file", file.map(|f| f.display().to_string()))?;
                kwargs.set_item("line", line)?;
                kwargs.set_item("column", column)?;
                ("InputError", message)
            }
            Failure::Analysis(m) => ("AnalysisError", m),
            Failure::Run(m) => ("RunError", m),
        };
        let e = errors.getattr(class)?.call((message,), Some(&kwargs))?;
        Ok(PyErr::from_value(e))
    }
}

impl From<LoadError> for Failure {
    fn from(e: LoadError) -> Failure {
        Failure::Input {
            message: e.to_string(),
            line: e.span.map(|s| s.line),
            column: e.span.map(|s| s.column),
            file: Some(e.path),
        }
    }
}

/// `Result` of the work done without the GIL.
pub(crate) type Outcome<T> = Result<T, Failure>;

/// Raises `f`'s failure in Python.
pub(crate) fn raise<T>(py: Python<'_>, r: Outcome<T>) -> PyResult<T> {
    r.map_err(|f| f.into_py(py))
}
