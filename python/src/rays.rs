//! `Rays`: every ray of a scene (or every stationary path) as numpy arrays, and the reasons of
//! those that are not `converged`.

use numpy::PyUntypedArrayMethods;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyType};

use crate::columns::{dir_of, why_words};
use crate::pickling;

pub(crate) use crate::rays_data::{PyRays, Reasons, none_of};

#[pymethods]
impl PyRays {
    /// Why each ray is not `converged` (`None` where it is), naming interfaces.
    #[getter]
    fn reason(&self, py: Python<'_>) -> Vec<Option<String>> {
        // The GIL released while waiting: a `trace(out=...)` of these rays in another thread
        // holds the lock through its batch, and takes the GIL to report progress.
        py.detach(|| self.reasons.lock().map(|r| r.words()).unwrap_or_default())
    }

    /// A quantity's column (with `"amplitudes"`: `amplitude` and `coefficient`, complex128,
    /// `spreading` and `attenuation_db`, float64, NaN where a ray has none, and
    /// `amplitude_reason`, why a timed ray's amplitude has no value, the command-line tool's
    /// words); `None` for a quantity the scene does not ask for.
    fn __getattr__(&self, py: Python<'_>, name: &str) -> PyResult<Py<PyAny>> {
        self.quantities.attribute(py, "Rays", name, || {
            // The GIL released while waiting, as the `reason` getter does.
            py.detach(|| {
                let reasons = self.reasons.lock().ok()?;
                why_words(&reasons.whys, name)
            })
        })
    }

    fn __dir__(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        dir_of::<PyRays>(py)
    }

    /// Pickling (`multiprocessing`, joblib, Dask): the arrays, the names and the reasons;
    /// the unpickled `Rays` has every attribute of this one, equal array by array.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyDict>,))> {
        let py = slf.py();
        let state = pickling::rays_state(py, slf.get())?;
        let from_state = py.get_type::<PyRays>().getattr("_from_state")?;
        Ok((from_state, (state,)))
    }

    /// The `Rays` of a pickled state (see `__reduce__`).
    #[classmethod]
    fn _from_state(_cls: &Bound<'_, PyType>, state: &Bound<'_, PyDict>) -> PyResult<PyRays> {
        pickling::rays_of_state(state)
    }

    fn __len__(&self, py: Python<'_>) -> usize {
        self.time.bind(py).len()
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!("Rays({} rays)", self.time.bind(py).len())
    }
}
