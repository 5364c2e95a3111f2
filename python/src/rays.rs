//! `Rays`: every ray of a scene (or every stationary path) as numpy arrays, and the reasons of
//! those that are not `converged`.

use eigenray::Point;
use numpy::{PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyType};

use crate::columns::{dir_of, why_words};
use crate::curve::CurveInput;
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

    /// Ray `i`'s curve (negative: from the end) sampled at `n` points, an `(n, 2)` float64
    /// array, as `Ray.curve` gives it: on the ray itself (arcs through `gradient` and
    /// `profile` media, the ray of its `launch_angle` through a profile), the first its
    /// source, the last its receiver, every interaction point among them. Raises
    /// `IndexError` past the rays, `EigenrayError` (a `ValueError`) for a ray without a time
    /// or `n` below its number of points.
    #[pyo3(signature = (i, n = 100))]
    fn curve<'py>(
        &self,
        py: Python<'py>,
        i: isize,
        n: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let len = self.time.bind(py).len();
        let at = if i < 0 { i + len as isize } else { i };
        if at < 0 || at >= len as isize {
            return Err(PyIndexError::new_err(format!(
                "ray index {i} is out of range ({len} rays)"
            )));
        }
        let at = at as usize;
        let scene = self
            .scene
            .lock()
            .ok()
            .and_then(|s| s.clone())
            .ok_or_else(|| PyValueError::new_err("these rays carry no scene for their curves"))?;
        let k = usize::try_from(self.num_points.bind(py).get_owned([at]).unwrap_or(0)).unwrap_or(0);
        let points = self.points.bind(py).readonly();
        let points = points.as_array();
        let media = self.media.bind(py).readonly();
        let media = media.as_array();
        let k = k.min(points.shape()[1]);
        let row: Vec<Point> = (0..k)
            .map(|j| Point::new(points[[at, j, 0]], points[[at, j, 1]]))
            .collect();
        let legs = (0..k.saturating_sub(1)).map(|j| i64::from(media[[at, j]]));
        let angle = self.quantities.float_at(py, "launch_angle", at);
        CurveInput::of_row(row, legs, angle).array(py, &scene, n)
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
