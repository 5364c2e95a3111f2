//! `PointSensitivities`: how one ray's points move with everything its time depends on.

use eigenray::{
    PointSensitivities, RayRecord, Scene,
    derivatives::{Axis, Parameter},
};
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyList;

/// How one ray's points move with everything its time depends on (see
/// `Tracer.point_sensitivities`): row `i` of `d` is `d(points)/d(parameters[i])`, one `(dx, dy)`
/// per point (source, interaction points, receiver). A ray without a time has `time` NaN, no
/// parameters and `d` of shape `(0, 0, 2)`.
#[pyclass(module = "eigenray", name = "PointSensitivities", frozen, get_all)]
pub(crate) struct PyPointSensitivities {
    /// The ray's status.
    status: String,
    /// The ray's travel time (NaN without one).
    time: f64,
    /// The parameters, in the order of `d`'s rows: `("source", "x")`, `("receiver", "y")`,
    /// `("slowness", medium name)` or `("vertex", interface name, vertex index, "x")`.
    parameters: Py<PyList>,
    /// `d(points)/dθ`: shape `(parameters, points, 2)`.
    d: Py<PyArray3<f64>>,
}

#[pymethods]
impl PyPointSensitivities {
    fn __repr__(&self) -> String {
        format!(
            "PointSensitivities(status={:?}, time={})",
            self.status, self.time
        )
    }
}

impl PyPointSensitivities {
    /// The sensitivities `sens` of the ray of `record` (`None` for a ray without a time).
    pub(crate) fn new(
        py: Python<'_>,
        scene: &Scene,
        record: &RayRecord,
        sens: Option<&PointSensitivities>,
    ) -> PyResult<Self> {
        let axis = |a: Axis| match a {
            Axis::X => "x",
            Axis::Y => "y",
        };
        let parameters = PyList::empty(py);
        let (rows, points) = sens.map_or((0, 0), |s| (s.parameters().len(), s.points()));
        let mut d = Array3::<f64>::zeros((rows, points, 2));
        if let Some(s) = sens {
            for (row, parameter) in s.parameters().iter().enumerate() {
                let entry = match *parameter {
                    Parameter::Source(a) => ("source", axis(a)).into_pyobject(py)?.into_any(),
                    Parameter::Receiver(a) => ("receiver", axis(a)).into_pyobject(py)?.into_any(),
                    Parameter::Slowness { medium } => ("slowness", &scene.media()[medium].name)
                        .into_pyobject(py)?
                        .into_any(),
                    Parameter::Vertex {
                        interface,
                        vertex,
                        axis: a,
                    } => (
                        "vertex",
                        &scene.interfaces()[interface].name,
                        vertex,
                        axis(a),
                    )
                        .into_pyobject(py)?
                        .into_any(),
                };
                parameters.append(entry)?;
                for (i, v) in s.row(row).iter().enumerate() {
                    d[[row, i, 0]] = v.x;
                    d[[row, i, 1]] = v.y;
                }
            }
        }
        Ok(PyPointSensitivities {
            status: record.status.as_str().to_string(),
            time: record.time,
            parameters: parameters.unbind(),
            d: d.into_pyarray(py).unbind(),
        })
    }
}
