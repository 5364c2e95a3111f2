//! Where a long batch reports its progress: a tqdm bar or the caller's callable.

use pyo3::exceptions::{PyRuntimeError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::PyBool;
use pyo3::types::PyDict;

/// Where a long batch reports its progress.
pub(crate) enum Progress<'py> {
    /// A tqdm bar (tqdm.auto: a widget in a notebook, text in a terminal).
    Bar(Bound<'py, PyAny>),
    /// The caller's `progress(done, total)`.
    Callback(Bound<'py, PyAny>),
}

impl<'py> Progress<'py> {
    /// The progress that `arg` asks for (`None`, `False`, `True` or a callable) of a batch of
    /// `total` rays.
    pub(crate) fn new(
        py: Python<'py>,
        arg: Option<&Bound<'py, PyAny>>,
        total: usize,
    ) -> PyResult<Option<Self>> {
        let Some(arg) = arg else { return Ok(None) };
        if arg.is_none() {
            return Ok(None);
        }
        if arg.is_callable() {
            return Ok(Some(Progress::Callback(arg.clone())));
        }
        if !arg.is_instance_of::<PyBool>() {
            return Err(PyTypeError::new_err(format!(
                "progress: needs True (a tqdm bar), False, None or a callable \
                 progress(done, total), not {}",
                arg.get_type().name()?
            )));
        }
        if !arg.is_truthy()? {
            return Ok(None);
        }
        let kwargs = PyDict::new(py);
        kwargs.set_item("total", total)?;
        kwargs.set_item("unit", "ray")?;
        let bar = py
            .import("tqdm.auto")
            .and_then(|m| m.getattr("tqdm"))
            .map_err(|_| {
                PyRuntimeError::new_err("progress=True needs the tqdm package (pip install tqdm)")
            })?
            .call((), Some(&kwargs))?;
        Ok(Some(Progress::Bar(bar)))
    }

    /// Reports `done` rays of `total`, `shown` of them reported before.
    pub(crate) fn report(&self, done: usize, shown: usize, total: usize) -> PyResult<()> {
        match self {
            Progress::Bar(bar) => {
                bar.call_method1("update", (done - shown,))?;
            }
            Progress::Callback(f) => {
                f.call1((done, total))?;
            }
        }
        Ok(())
    }

    /// Closes a bar.
    pub(crate) fn close(&self) -> PyResult<()> {
        if let Progress::Bar(bar) = self {
            bar.call_method0("close")?;
        }
        Ok(())
    }
}
