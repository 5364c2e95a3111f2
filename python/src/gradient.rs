//! `Gradient`: the derivatives of one ray's travel time, as Python values.

use eigenray::{Gradient, RayRecord, Scene};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// The derivatives of one ray's travel time (see `Tracer.gradient`): with respect to the
/// source and receiver positions, each medium's slowness, and every polyline vertex the path
/// touches. A ray without a time has `time` NaN, NaN derivatives and no vertices.
#[pyclass(module = "eigenray", name = "Gradient", frozen, get_all)]
pub(crate) struct PyGradient {
    /// The ray's status.
    status: String,
    /// The ray's travel time (NaN without one).
    time: f64,
    /// `(dT/dx, dT/dy)` of the source.
    source: Py<PyArray1<f64>>,
    /// `(dT/dx, dT/dy)` of the receiver.
    receiver: Py<PyArray1<f64>>,
    /// `dT/dw` of each medium by name (`w`: the slowness, 1/speed or the index); 0 for a
    /// medium the ray does not pass through.
    slowness: Py<PyDict>,
    /// Every vertex whose movement changes the time, each once: dicts with `interface`
    /// (name), `vertex` (index in its points) and `d` (`(dT/dx, dT/dy)`).
    vertices: Py<PyList>,
    /// `(dT/dgx, dT/dgy)` of each medium with a speed gradient, by name (a scene with a
    /// `gradient` medium; empty otherwise). Their `slowness` entry is `dT/dw` with
    /// `w = 1/speed` and the gradient held.
    speed_gradient: Py<PyDict>,
    /// `dT/dc` of each knot of each medium with a speed profile, by name (an array in the
    /// order of the medium's `profile`; a scene with a `profile` medium, empty otherwise).
    /// Their `slowness` entry is `dT/dw` with `w = 1/c` of the first knot and the profile's
    /// shape held.
    profile_speed: Py<PyDict>,
}

#[pymethods]
impl PyGradient {
    fn __repr__(&self) -> String {
        format!("Gradient(status={:?}, time={})", self.status, self.time)
    }
}

impl PyGradient {
    /// The gradient `g` of the ray of `record` (`None` for a ray without a time).
    pub(crate) fn new(
        py: Python<'_>,
        scene: &Scene,
        record: &RayRecord,
        g: Option<&Gradient>,
    ) -> PyResult<Self> {
        let nan = [f64::NAN, f64::NAN];
        let (source, receiver) = match g {
            Some(g) => ([g.source.x, g.source.y], [g.receiver.x, g.receiver.y]),
            None => (nan, nan),
        };
        let slowness = PyDict::new(py);
        for (i, m) in scene.media().iter().enumerate() {
            slowness.set_item(&m.name, g.map_or(f64::NAN, |g| g.slowness[i]))?;
        }
        let vertices = PyList::empty(py);
        for v in g.map_or(&[][..], |g| &g.vertices) {
            let d = PyDict::new(py);
            d.set_item("interface", &scene.interfaces()[v.interface].name)?;
            d.set_item("vertex", v.vertex)?;
            d.set_item("d", PyArray1::from_slice(py, &[v.d.x, v.d.y]))?;
            vertices.append(d)?;
        }
        let speed_gradient = PyDict::new(py);
        for (i, m) in scene.media().iter().enumerate() {
            if m.gradient.is_none() {
                continue;
            }
            let d = g
                .and_then(|g| g.speed_gradient.get(i))
                .map_or([f64::NAN, f64::NAN], |d| [d.x, d.y]);
            speed_gradient.set_item(&m.name, PyArray1::from_slice(py, &d))?;
        }
        let profile_speed = PyDict::new(py);
        for (i, m) in scene.media().iter().enumerate() {
            let Some(knots) = &m.profile else {
                continue;
            };
            let d = g
                .and_then(|g| g.profile_speed.get(i))
                .filter(|d| d.len() == knots.len())
                .map_or_else(|| vec![f64::NAN; knots.len()], Clone::clone);
            profile_speed.set_item(&m.name, PyArray1::from_vec(py, d))?;
        }
        Ok(PyGradient {
            status: record.status.as_str().to_string(),
            time: record.time,
            source: PyArray1::from_slice(py, &source).unbind(),
            receiver: PyArray1::from_slice(py, &receiver).unbind(),
            slowness: slowness.unbind(),
            vertices: vertices.unbind(),
            speed_gradient: speed_gradient.unbind(),
            profile_speed: profile_speed.unbind(),
        })
    }
}
