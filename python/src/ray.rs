//! `Ray`: one ray (or one stationary path) as Python values.

use eigenray::amplitudes::Complex64;
use eigenray::{Amplitude, Arrival, Point, RayRecord, Scene};
use numpy::PyArray2;
use pyo3::prelude::*;

use crate::amplitude::RayAmplitude;
use crate::convert::{kink_name, medium_names, points_array};

/// One ray: its status, time, points and leg media (and its amplitude, when the scene asks
/// for amplitudes).
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
    /// With `"amplitudes"`: the complex pressure (field) amplitude for a unit source, without
    /// the travel-time phase; NaN where it has none (see `amplitude_reason`). `None` for a
    /// scene without `"amplitudes"`, as the four below.
    amplitude: Option<Complex64>,
    /// With `"amplitudes"`: the geometric spreading factor.
    spreading: Option<f64>,
    /// With `"amplitudes"`: the product of the reflection and transmission coefficients.
    coefficient: Option<Complex64>,
    /// With `"amplitudes"`: the attenuation of the media along the path, dB.
    attenuation_db: Option<f64>,
    /// Why the amplitude has no value (`None` where it has one, or the ray has no time).
    amplitude_reason: Option<String>,
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
    /// The ray of `record`, with its points, leg media and amplitude (a ray of
    /// `Tracer.solve`).
    pub(crate) fn from_record(
        py: Python<'_>,
        scene: &Scene,
        record: &RayRecord,
        points: &[Point],
        media: &[usize],
        amplitude: Option<&Amplitude>,
    ) -> PyRay {
        let a = RayAmplitude::new(scene.amplitudes().is_some(), amplitude);
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
            amplitude: a.amplitude,
            spreading: a.spreading,
            coefficient: a.coefficient,
            attenuation_db: a.attenuation_db,
            amplitude_reason: a.reason,
        }
    }

    /// Stationary path `index` of a triple, `a` (of `Tracer.stationary_paths`).
    pub(crate) fn from_arrival(py: Python<'_>, scene: &Scene, index: usize, a: &Arrival) -> PyRay {
        let amp = RayAmplitude::new(scene.amplitudes().is_some(), a.amplitude.as_ref());
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
            amplitude: amp.amplitude,
            spreading: amp.spreading,
            coefficient: amp.coefficient,
            attenuation_db: amp.attenuation_db,
            amplitude_reason: amp.reason,
        }
    }
}
