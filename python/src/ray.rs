//! `Ray`: one ray (or one stationary path) as Python values.

use eigenray::{Arrival, Point, RayRecord, Scene};
use numpy::PyArray2;
use pyo3::prelude::*;

use crate::convert::{kink_name, medium_names, points_array};

/// One ray: its status, time, points and leg media.
#[pyclass(module = "eigenray", name = "Ray", frozen, get_all)]
pub(crate) struct PyRay {
    /// `converged`, `vertex`, `no_path`, `obstructed` or `not_converged`.
    status: String,
    /// Travel time; NaN when the status has none.
    time: f64,
    /// Source, interaction points and receiver, shape `(k + 2, 2)`; empty without a time.
    points: Py<PyArray2<f64>>,
    /// Leg media's names, when known.
    media: Vec<String>,
    /// Solver iterations.
    iterations: usize,
    /// Final relative residual (NaN where the solver did not run).
    residual: f64,
    /// Why it is not `converged` (`None` when it is).
    reason: Option<String>,
    /// Among the stationary paths of its triple, its place by time (0: the first); `None`
    /// for a ray of `Tracer.solve`.
    arrival: Option<usize>,
    /// On a `vertex` path of `stationary_paths`: `"minimum"` or `"maximum"`.
    kink: Option<String>,
}

#[pymethods]
impl PyRay {
    fn __repr__(&self) -> String {
        format!(
            "Ray(status={:?}, time={}, iterations={})",
            self.status, self.time, self.iterations
        )
    }
}

impl PyRay {
    /// The ray of `record`, with its points and leg media (a ray of `Tracer.solve`).
    pub(crate) fn from_record(
        py: Python<'_>,
        scene: &Scene,
        record: &RayRecord,
        points: &[Point],
        media: &[usize],
    ) -> PyRay {
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
        }
    }

    /// Stationary path `index` of a triple, `a` (of `Tracer.stationary_paths`).
    pub(crate) fn from_arrival(py: Python<'_>, scene: &Scene, index: usize, a: &Arrival) -> PyRay {
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
        }
    }
}
