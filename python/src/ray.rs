//! `Ray`: one ray (or one stationary path) as Python values.

use std::sync::Arc;

use eigenray::output::columns::Entry;
use eigenray::{Arrival, Point, RayRecord, Scene};
use numpy::PyArray2;
use pyo3::prelude::*;

use crate::columns::{RayValues, dir_of};
use crate::convert::{kink_name, medium_names, points_array};
use crate::curve::CurveInput;

/// One ray: its status, time, points and leg media (and its amplitude, when the scene asks
/// for amplitudes).
#[pyclass(module = "eigenray", name = "Ray", frozen)]
pub(crate) struct PyRay {
    /// `converged`, `vertex`, `no_path`, `obstructed` or `not_converged`.
    #[pyo3(get)]
    status: String,
    /// Travel time; NaN when the status has none.
    #[pyo3(get)]
    time: f64,
    /// Source, interaction points and receiver, shape `(k + 2, 2)`; empty without a time.
    #[pyo3(get)]
    points: Py<PyArray2<f64>>,
    /// Leg media's names, when known.
    #[pyo3(get)]
    media: Vec<String>,
    /// Solver iterations.
    #[pyo3(get)]
    iterations: usize,
    /// Final relative residual (NaN where the solver did not run).
    #[pyo3(get)]
    residual: f64,
    /// Why it is not `converged` (`None` when it is).
    #[pyo3(get)]
    reason: Option<String>,
    /// Among the stationary paths of its triple, its place by time (0: the first); `None`
    /// for a ray of `Tracer.solve`.
    #[pyo3(get)]
    arrival: Option<usize>,
    /// On a `vertex` path of `stationary_paths`: `"minimum"` or `"maximum"`.
    #[pyo3(get)]
    kink: Option<String>,
    /// The values of the quantities its scene asks for, read as attributes.
    quantities: RayValues,
    /// Its scene (the tracer's when it was solved), for its curve.
    scene: Arc<Scene>,
    /// What its curve is sampled from.
    curve_input: CurveInput,
}

#[pymethods]
impl PyRay {
    /// A quantity's value (with `"amplitudes"`: `amplitude`, the complex pressure (field)
    /// amplitude for a unit source without the travel-time phase, NaN where it has none;
    /// `spreading`, the geometric spreading factor; `coefficient`, the product of the
    /// reflection and transmission coefficients; `attenuation_db`, the attenuation of the
    /// media along the path, dB; `amplitude_reason`, why the amplitude has no value, `None`
    /// where it has one or the ray has no time); `None` for a quantity the scene does not ask
    /// for.
    fn __getattr__(&self, py: Python<'_>, name: &str) -> PyResult<Py<PyAny>> {
        self.quantities.attribute(py, "Ray", name)
    }

    fn __dir__(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        dir_of::<PyRay>(py)
    }

    /// The ray's curve sampled at `n` points, an `(n, 2)` float64 array: on the ray itself
    /// (a leg through a `gradient` medium is its circular arc, a ray through a `profile`
    /// medium its arcs through its turning points and reflections, a straight leg its
    /// chord), the first the source, the last the receiver and every interaction point
    /// among them, each leg's points evenly spaced along it (each leg a share of the `n − 1`
    /// steps in proportion to its length, at least one). Raises `EigenrayError` (a
    /// `ValueError`) for a ray without a time, or `n` below its number of points.
    #[pyo3(signature = (n = 100))]
    fn curve<'py>(&self, py: Python<'py>, n: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.curve_input.array(py, &self.scene, n)
    }

    fn __repr__(&self) -> String {
        format!(
            "Ray(status={:?}, time={}, iterations={})",
            self.status, self.time, self.iterations
        )
    }
}

impl PyRay {
    /// The ray of `record`, with its points, leg media and amplitude (a ray of
    /// `Tracer.solve`).
    pub(crate) fn from_record(
        py: Python<'_>,
        scene: &Arc<Scene>,
        record: &RayRecord,
        points: &[Point],
        media: &[usize],
        entry: &Entry<'_>,
    ) -> PyRay {
        let curve_input = CurveInput {
            points: if record.status.has_time() {
                points.to_vec()
            } else {
                Vec::new()
            },
            media: media.to_vec(),
            launch_angle: entry.launch_angle,
        };
        PyRay {
            status: record.status.as_str().to_string(),
            time: record.time,
            points: points_array(py, points).unbind(),
            media: medium_names(scene, media.iter().copied()),
            iterations: record.iterations as usize,
            residual: record.residual,
            reason: record.reason.map(|r| r.describe(scene)),
            arrival: None,
            kink: None,
            quantities: RayValues::new(scene, entry),
            scene: Arc::clone(scene),
            curve_input,
        }
    }

    /// Stationary path `index` of a triple, `a` (of `Tracer.stationary_paths`).
    pub(crate) fn from_arrival(
        py: Python<'_>,
        scene: &Arc<Scene>,
        index: usize,
        a: &Arrival,
    ) -> PyRay {
        let entry = Entry::of_arrival(a);
        let curve_input = CurveInput {
            points: if a.status.has_time() {
                a.points.clone()
            } else {
                Vec::new()
            },
            media: a.media.clone(),
            launch_angle: a.launch_angle,
        };
        PyRay {
            status: a.status.as_str().to_string(),
            time: a.time,
            points: points_array(py, &a.points).unbind(),
            media: medium_names(scene, a.media.iter().copied()),
            iterations: a.iterations,
            residual: a.residual,
            reason: a.reason.map(|r| r.describe(scene)),
            arrival: Some(index),
            kink: kink_name(a.kink),
            quantities: RayValues::new(scene, &entry),
            scene: Arc::clone(scene),
            curve_input,
        }
    }
}
