//! Where a long batch reports its progress: a tqdm bar or the caller's callable.

use eigenray::options::Run;
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

/// The reports of one call that runs on a thread of its own: its workers count the items they
/// begin in its `Run`, and the calling thread [`poll`](Self::poll)s it (at most one report a
/// poll, none after one failed), then [`finish`](Self::finish)es.
pub(crate) struct Reports<'a, 'py> {
    progress: Option<&'a Progress<'py>>,
    run: &'a Run,
    total: usize,
    shown: usize,
    reported: PyResult<()>,
}

impl<'a, 'py> Reports<'a, 'py> {
    /// The reports of a call over `total` items to `progress` (none without one).
    pub(crate) fn new(
        progress: Option<&'a Progress<'py>>,
        run: &'a Run,
        total: usize,
    ) -> Reports<'a, 'py> {
        Reports {
            progress,
            run,
            total,
            shown: 0,
            reported: Ok(()),
        }
    }

    /// Reports what was done since the last report, if anything was.
    pub(crate) fn poll(&mut self) {
        let now = usize::try_from(self.run.items())
            .unwrap_or(usize::MAX)
            .min(self.total);
        if let Some(progress) = self.progress
            && self.reported.is_ok()
            && now > self.shown
        {
            self.reported = progress.report(now, self.shown, self.total);
            self.shown = now;
        }
    }

    /// The call is over: reports it whole and closes the progress; the error of a report, if
    /// one failed.
    pub(crate) fn finish(mut self) -> PyResult<()> {
        if let Some(progress) = self.progress {
            if self.reported.is_ok() && self.shown < self.total {
                self.reported = progress.report(self.total, self.shown, self.total);
            }
            self.reported = self.reported.and(progress.close());
        }
        self.reported
    }
}
