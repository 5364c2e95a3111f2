//! `Rays`: every ray of a scene (or every stationary path) as numpy arrays, and the reasons of
//! those that are not `converged`.

use eigenray::amplitudes::Complex64;
use numpy::{PyArray1, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyType};

use crate::amplitude::reason_words;
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

    /// With `"amplitudes"`: the complex pressure (field) amplitude of each ray for a unit
    /// source, without the travel-time phase (complex128); NaN where it has none (a ray
    /// without a time, a `vertex` path: see `amplitude_reason`). `None` for a scene without
    /// `"amplitudes"`.
    #[getter]
    fn amplitude(&self, py: Python<'_>) -> Option<Py<PyArray1<Complex64>>> {
        self.amplitudes.as_ref().map(|a| a.value.clone_ref(py))
    }

    /// With `"amplitudes"`: the geometric spreading factor of each ray (float64, NaN where
    /// the ray has none).
    #[getter]
    fn spreading(&self, py: Python<'_>) -> Option<Py<PyArray1<f64>>> {
        self.amplitudes.as_ref().map(|a| a.spreading.clone_ref(py))
    }

    /// With `"amplitudes"`: the product of each ray's reflection and transmission
    /// coefficients (complex128, NaN where the ray has none).
    #[getter]
    fn coefficient(&self, py: Python<'_>) -> Option<Py<PyArray1<Complex64>>> {
        self.amplitudes
            .as_ref()
            .map(|a| a.coefficient.clone_ref(py))
    }

    /// With `"amplitudes"`: the attenuation of the media along each ray, dB (float64, NaN
    /// where the ray has none).
    #[getter]
    fn attenuation_db(&self, py: Python<'_>) -> Option<Py<PyArray1<f64>>> {
        self.amplitudes
            .as_ref()
            .map(|a| a.attenuation_db.clone_ref(py))
    }

    /// With `"amplitudes"`: why each timed ray's amplitude has no value (`None` where it has
    /// one, and for a ray without a time), the command-line tool's `amplitude_reason`.
    #[getter]
    fn amplitude_reason(&self, py: Python<'_>) -> Option<Vec<Option<String>>> {
        self.amplitudes.as_ref()?;
        py.detach(|| {
            let reasons = self.reasons.lock().ok()?;
            reasons.amplitude.as_deref().map(reason_words)
        })
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
