//! Python bindings of eigenray (the `eigenray._eigenray` extension module).
//!
//! Everything here converts: Python values to the library's types (with the library's own
//! validation and error messages) and the library's results to numpy arrays. The Python
//! package (`python/eigenray/`) re-exports these classes and adds the plotting helper.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use eigenray::{
    Arrival, BatchOptions, Gradient, Point, PointSensitivities, RayRecord, Reason, Scene,
    SceneError, SearchArrival, StationaryRays, Status, Tracer, Workspace,
    gradients::{Axis, Parameter},
    npy::STATUS_CODES,
    scene_parts::StepKind,
    sink::{BatchScratch, BatchSink, RaySlot},
    stationary::Kink,
};
use numpy::ndarray::{Array2, Array3};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray2, PyReadwriteArray1,
    PyReadwriteArray2, PyReadwriteArray3, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyIOError, PyIndexError, PyKeyError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use rayon::iter::ParallelExtend;

pyo3::create_exception!(
    _eigenray,
    EigenrayError,
    PyValueError,
    "An invalid scene or argument: `key` names where the problem is, `message` what it is."
);

/// The status names in the order of their codes (the `.npy` output's codes).
fn status_names() -> Vec<&'static str> {
    STATUS_CODES.iter().map(|s| s.as_str()).collect()
}

fn status_code(status: Status) -> u8 {
    STATUS_CODES
        .iter()
        .position(|&s| s == status)
        .expect("every status has a code") as u8
}

/// The Python exception of a scene error: `EigenrayError(str)` with `key` and `message`.
fn scene_error(py: Python<'_>, e: &SceneError) -> PyErr {
    let err = EigenrayError::new_err(e.to_string());
    let value = err.value(py);
    // Setting attributes on a fresh exception instance cannot fail.
    let _ = value.setattr("key", e.key.as_str());
    let _ = value.setattr("message", e.message.as_str());
    err
}

/// An error at `key` from an argument of a call (not from the scene).
fn argument_error(py: Python<'_>, key: &str, message: impl Into<String>) -> PyErr {
    scene_error(py, &SceneError::new(key, message))
}

/// A point from any Python sequence of two numbers (tuple, list, numpy array).
fn point_arg(py: Python<'_>, key: &str, value: &Bound<'_, PyAny>) -> PyResult<Point> {
    let xy: [f64; 2] = value
        .extract()
        .map_err(|_| argument_error(py, key, "needs a point: a sequence of two numbers"))?;
    Ok(Point::new(xy[0], xy[1]))
}

/// Points from an array-like of shape `(n, 2)`.
fn points_arg(py: Python<'_>, key: &str, value: &Bound<'_, PyAny>) -> PyResult<Vec<Point>> {
    let numpy = py.import("numpy")?;
    let array = numpy
        .call_method1("asarray", (value, "float64"))
        .map_err(|_| argument_error(py, key, "needs an array of numbers of shape (n, 2)"))?;
    let array: PyReadonlyArray2<'_, f64> = array
        .extract()
        .map_err(|_| argument_error(py, key, "needs an array of shape (n, 2)"))?;
    let view = array.as_array();
    if view.ncols() != 2 {
        return Err(argument_error(
            py,
            key,
            format!("needs an array of shape (n, 2), not {:?}", view.shape()),
        ));
    }
    Ok(view
        .rows()
        .into_iter()
        .map(|r| Point::new(r[0], r[1]))
        .collect())
}

/// A scene: media, interfaces, sources, receivers and paths, validated.
///
/// Build one with `Scene(source)` from a JSON string, a `dict` of the same shape, or a path to
/// a scene file (`str` ending in `.json` or `os.PathLike`); or with `Scene.from_json`,
/// `Scene.from_dict`, `Scene.from_file`. An invalid scene raises `EigenrayError` naming the
/// key, with the same message as the command-line tool.
#[pyclass(module = "eigenray", name = "Scene", frozen)]
struct PyScene {
    /// Shared with the tracers made from it (a tracer's updates copy it first).
    scene: Arc<Scene>,
}

impl PyScene {
    fn parse(py: Python<'_>, text: &str) -> PyResult<PyScene> {
        let scene = py.detach(|| Scene::from_json(text));
        scene
            .map(|scene| PyScene {
                scene: Arc::new(scene),
            })
            .map_err(|e| scene_error(py, &e))
    }
}

#[pymethods]
impl PyScene {
    #[new]
    fn new(py: Python<'_>, source: &Bound<'_, PyAny>) -> PyResult<PyScene> {
        if source.is_instance_of::<PyDict>() {
            return PyScene::from_dict(py, source);
        }
        if let Ok(text) = source.cast::<PyString>() {
            let text = text.to_str()?;
            if text.trim_start().starts_with('{') {
                return PyScene::parse(py, text);
            }
            return PyScene::from_file(py, source);
        }
        if source.hasattr("__fspath__")? {
            return PyScene::from_file(py, source);
        }
        Err(argument_error(
            py,
            "scene",
            "needs a JSON string, a dict or a path to a scene file",
        ))
    }

    /// A scene from its JSON text.
    #[staticmethod]
    fn from_json(py: Python<'_>, text: &str) -> PyResult<PyScene> {
        PyScene::parse(py, text)
    }

    /// A scene from a `dict` (or any value `json.dumps` accepts) of the JSON's shape.
    #[staticmethod]
    fn from_dict(py: Python<'_>, scene: &Bound<'_, PyAny>) -> PyResult<PyScene> {
        let json = py.import("json")?;
        let kwargs = PyDict::new(py);
        kwargs.set_item("allow_nan", false)?;
        let text = json
            .call_method("dumps", (scene,), Some(&kwargs))
            .map_err(|e| argument_error(py, "scene", format!("is not JSON: {e}")))?;
        PyScene::parse(py, text.extract::<&str>()?)
    }

    /// A scene from a file.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<PyScene> {
        let os = py.import("os")?;
        let path: String = os.call_method1("fspath", (path,))?.extract()?;
        let text = std::fs::read_to_string(&path)
            .map_err(|e| PyIOError::new_err(format!("{path}: {e}")))?;
        PyScene::parse(py, &text)
    }

    /// Medium names, in the scene's order (the indices of `Rays.media`).
    #[getter]
    fn media_names(&self) -> Vec<String> {
        self.scene.media().iter().map(|m| m.name.clone()).collect()
    }

    /// Slowness of each medium (1 / speed, or the refractive index), in the scene's order.
    #[getter]
    fn slowness<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let w: Vec<f64> = self.scene.media().iter().map(|m| m.slowness).collect();
        w.into_pyarray(py)
    }

    /// Interface names, in the scene's order.
    #[getter]
    fn interface_names(&self) -> Vec<String> {
        self.scene
            .interfaces()
            .iter()
            .map(|i| i.name.clone())
            .collect()
    }

    /// Each interface's vertices as an array of shape `(n, 2)`, by name (a closed
    /// interface's first vertex is not repeated at its end).
    #[getter]
    fn interfaces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for i in self.scene.interfaces() {
            out.set_item(&i.name, points_array(py, i.polyline.vertices()))?;
        }
        Ok(out)
    }

    /// Whether each interface is closed, by name.
    #[getter]
    fn closed<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        for i in self.scene.interfaces() {
            out.set_item(&i.name, i.polyline.is_closed())?;
        }
        Ok(out)
    }

    /// Path names (`None` for an unnamed path), in the scene's order.
    #[getter]
    fn path_names(&self) -> Vec<Option<String>> {
        self.scene.paths().iter().map(|p| p.name.clone()).collect()
    }

    /// Sources, shape `(n, 2)`.
    #[getter]
    fn sources<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        points_array(py, self.scene.sources())
    }

    /// Receivers, shape `(n, 2)`.
    #[getter]
    fn receivers<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        points_array(py, self.scene.receivers())
    }

    /// Rays of the scene: sources × receivers × paths.
    #[getter]
    fn num_rays(&self) -> usize {
        self.scene.num_rays()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({} media, {} interfaces, {} sources, {} receivers, {} paths)",
            self.scene.media().len(),
            self.scene.interfaces().len(),
            self.scene.sources().len(),
            self.scene.receivers().len(),
            self.scene.paths().len()
        )
    }
}

fn points_array<'py>(py: Python<'py>, points: &[Point]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = points.iter().flat_map(|p| [p.x, p.y]).collect();
    Array2::from_shape_vec((points.len(), 2), flat)
        .expect("two coordinates a point")
        .into_pyarray(py)
}

/// Traces the rays of a scene. `Tracer(scene)` prepares it once (region lookup, segment
/// hierarchies); every call after that reuses it.
#[pyclass(module = "eigenray", name = "Tracer")]
struct PyTracer {
    tracer: Tracer,
    /// What the next `trace` reuses (the rays in solving order, for receivers solved in a
    /// spatial order).
    scratch: BatchScratch,
    workspace: Workspace,
    arrivals: Vec<Arrival>,
    /// The last `gradient`'s derivatives (reused).
    gradient: Gradient,
}

/// One ray: its status, time, points and leg media.
#[pyclass(module = "eigenray", name = "Ray", frozen, get_all)]
struct PyRay {
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

fn medium_names(scene: &Scene, media: impl Iterator<Item = usize>) -> Vec<String> {
    media.map(|m| scene.media()[m].name.clone()).collect()
}

fn kink_name(kink: Option<Kink>) -> Option<String> {
    kink.map(|k| k.as_str().to_string())
}

impl PyRay {
    fn from_record(
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

    fn from_arrival(py: Python<'_>, scene: &Scene, index: usize, a: &Arrival) -> PyRay {
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

/// The derivatives of one ray's travel time (see `Tracer.gradient`): with respect to the
/// source and receiver positions, each medium's slowness, and every polyline vertex the path
/// touches. A ray without a time has `time` NaN, NaN derivatives and no vertices.
#[pyclass(module = "eigenray", name = "Gradient", frozen, get_all)]
struct PyGradient {
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
}

#[pymethods]
impl PyGradient {
    fn __repr__(&self) -> String {
        format!("Gradient(status={:?}, time={})", self.status, self.time)
    }
}

impl PyGradient {
    fn new(
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
        Ok(PyGradient {
            status: record.status.as_str().to_string(),
            time: record.time,
            source: PyArray1::from_slice(py, &source).unbind(),
            receiver: PyArray1::from_slice(py, &receiver).unbind(),
            slowness: slowness.unbind(),
            vertices: vertices.unbind(),
        })
    }
}

/// How one ray's points move with everything its time depends on (see
/// `Tracer.point_sensitivities`): row `i` of `d` is `d(points)/d(parameters[i])`, one `(dx, dy)`
/// per point (source, interaction points, receiver). A ray without a time has `time` NaN, no
/// parameters and `d` of shape `(0, 0, 2)`.
#[pyclass(module = "eigenray", name = "PointSensitivities", frozen, get_all)]
struct PyPointSensitivities {
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
    fn new(
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

/// The derivatives of many rays' times as numpy arrays (see `Tracer.gradients`), row `i`
/// those of ray `i` of the `Rays` they were computed from: NaN (and −1 for the vertex indices)
/// for a ray without a time. `K` below is the most steps of a path of the scene.
#[pyclass(module = "eigenray", name = "Gradients", frozen, get_all)]
struct PyGradients {
    /// `(dT/dx, dT/dy)` of the source, shape `(n, 2)`.
    source: Py<PyArray2<f64>>,
    /// `(dT/dx, dT/dy)` of the receiver, shape `(n, 2)`.
    receiver: Py<PyArray2<f64>>,
    /// `dT/dw` of each medium (in the order of `media_names`), shape `(n, M)`.
    slowness: Py<PyArray2<f64>>,
    /// The interface (index into `interface_names`) of each vertex whose movement changes the
    /// time, shape `(n, 2K)`, −1 past the ray's own vertices.
    vertex_interface: Py<PyArray2<i32>>,
    /// Its index in the interface's points, shape `(n, 2K)`, −1 past the ray's own.
    vertex: Py<PyArray2<i32>>,
    /// `(dT/dx, dT/dy)` of that vertex, shape `(n, 2K, 2)`, NaN past the ray's own.
    vertex_d: Py<PyArray3<f64>>,
    /// The scene's medium names.
    media_names: Vec<String>,
    /// The scene's interface names.
    interface_names: Vec<String>,
}

#[pymethods]
impl PyGradients {
    fn __len__(&self, py: Python<'_>) -> usize {
        self.source.bind(py).shape()[0]
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!("Gradients({} rays)", self.source.bind(py).shape()[0])
    }
}

/// `v`, rows of `width` entries, cut into `pieces` pieces of `rows` rows (the last shorter),
/// for a parallel loop: empty pieces when `width` is 0, so that they still pair up with the
/// pieces of the other arrays.
fn row_pieces<T: Send>(
    v: &mut [T],
    width: usize,
    rows: usize,
    pieces: usize,
) -> rayon::vec::IntoIter<&mut [T]> {
    use rayon::prelude::*;
    let cut: Vec<&mut [T]> = if width == 0 {
        (0..pieces).map(|_| &mut [][..]).collect()
    } else {
        v.chunks_mut(width * rows).collect()
    };
    cut.into_par_iter()
}

/// Every ray of a scene as numpy arrays, in ray order (source-major, then receiver, then
/// path). Rays without a time have `time` NaN and NaN points.
#[pyclass(module = "eigenray", name = "Rays", frozen)]
struct PyRays {
    /// Source index of each ray, shape `(n,)`.
    #[pyo3(get)]
    source: Py<PyArray1<i64>>,
    /// Receiver index of each ray.
    #[pyo3(get)]
    receiver: Py<PyArray1<i64>>,
    /// Path index of each ray.
    #[pyo3(get)]
    path: Py<PyArray1<i64>>,
    /// Status code of each ray (an index into `status_names`), `uint8`.
    #[pyo3(get)]
    status: Py<PyArray1<u8>>,
    /// Travel time; NaN for a ray without one.
    #[pyo3(get)]
    time: Py<PyArray1<f64>>,
    /// Source, interaction points and receiver, shape `(n, P, 2)`, NaN-padded past a path's
    /// own points (P: the most points of any path) and NaN for a ray without a time.
    #[pyo3(get)]
    points: Py<PyArray3<f64>>,
    /// Points of each ray's path (`k + 2` for `k` steps), shape `(n,)`.
    #[pyo3(get)]
    num_points: Py<PyArray1<i64>>,
    /// Leg media, shape `(n, P − 1)`: indices into `media_names`, −1 where unknown or past the
    /// path's legs.
    #[pyo3(get)]
    media: Py<PyArray2<i32>>,
    /// Solver iterations.
    #[pyo3(get)]
    iterations: Py<PyArray1<u32>>,
    /// Final relative residual (NaN where the solver did not run).
    #[pyo3(get)]
    residual: Py<PyArray1<f64>>,
    /// Why each ray is not `converged` (`None` where it is): read through the `reason`
    /// getter (a list), rewritten by `trace(out=...)`.
    reasons: Mutex<Reasons>,
    /// The status names, by code.
    #[pyo3(get)]
    status_names: Vec<&'static str>,
    /// The scene's path names (`None` for an unnamed path), by path index.
    #[pyo3(get)]
    path_names: Vec<Option<String>>,
    /// The scene's medium names, by medium index.
    #[pyo3(get)]
    media_names: Vec<String>,
    /// From `trace_stationary`: each entry's place by time among its triple's stationary
    /// paths (0 for a triple without any); `None` from `trace`.
    #[pyo3(get)]
    arrival: Option<Py<PyArray1<i64>>>,
    /// From `trace_stationary`: `"minimum"`, `"maximum"` or `"mixed"` on `vertex` entries.
    #[pyo3(get)]
    kink: Option<Vec<Option<String>>>,
    /// From `trace_stationary`: whether the triple's search was complete.
    #[pyo3(get)]
    complete: Option<Py<PyArray1<bool>>>,
}

#[pymethods]
impl PyRays {
    /// Why each ray is not `converged` (`None` where it is), naming interfaces.
    #[getter]
    fn reason(&self, py: Python<'_>) -> Vec<Option<String>> {
        // The GIL released while waiting: a `trace(out=...)` of these rays in another thread
        // holds the lock through its batch, and takes the GIL to report progress.
        py.detach(|| self.reasons.lock().map(|r| r.words()).unwrap_or_default())
    }

    fn __len__(&self, py: Python<'_>) -> usize {
        self.time.bind(py).len()
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!("Rays({} rays)", self.time.bind(py).len())
    }
}

/// Why each ray of a `Rays` is not `converged`, as the library's reasons (written by the
/// batch's workers without a string each), worded when read with the interfaces' names.
struct Reasons {
    /// One per ray.
    codes: Vec<Option<Reason>>,
    /// Whether an entry is not `None` (most rays have no reason, and rows write `None` only
    /// over an earlier result that has some).
    any: bool,
    /// The scene's interface names, by index.
    interfaces: Vec<String>,
}

impl Reasons {
    fn words(&self) -> Vec<Option<String>> {
        let name = |i: usize| self.interfaces.get(i).map(String::as_str);
        self.codes
            .iter()
            .map(|r| r.map(|r| r.describe_with(name)))
            .collect()
    }
}

/// `n` reasons, all `None`, written by the rayon pool (the first touch of fresh memory is
/// then not a serial step before a parallel batch).
fn none_of(n: usize) -> Vec<Option<Reason>> {
    let mut codes = Vec::new();
    codes.par_extend(rayon::iter::repeat_n(None, n));
    codes
}

/// The names of the interfaces of `scene`, by index.
fn interface_names(scene: &Scene) -> Vec<String> {
    scene.interfaces().iter().map(|i| i.name.clone()).collect()
}

/// The arrays of `Rays`, allocated for their rays and filled in place (in parallel for
/// batches): `width` points a ray.
struct Table {
    width: usize,
    source: Vec<i64>,
    receiver: Vec<i64>,
    path: Vec<i64>,
    status: Vec<u8>,
    time: Vec<f64>,
    points: Vec<f64>,
    num_points: Vec<i64>,
    media: Vec<i32>,
    iterations: Vec<u32>,
    residual: Vec<f64>,
    reason: Vec<Option<Reason>>,
    /// Whether a row has a reason.
    any_reason: AtomicBool,
    /// The columns of every stationary path's entries, for `trace_stationary`.
    stationary: Option<StationaryColumns>,
}

/// The columns of every stationary path's entries (see `stationary_columns`).
struct StationaryColumns {
    arrival: Vec<i64>,
    kink: Vec<Option<String>>,
    complete: Vec<bool>,
}

/// Rows of a [`Table`]: one slice per column, all of the same rows.
struct Rows<'a> {
    width: usize,
    source: &'a mut [i64],
    receiver: &'a mut [i64],
    path: &'a mut [i64],
    status: &'a mut [u8],
    time: &'a mut [f64],
    points: &'a mut [f64],
    num_points: &'a mut [i64],
    media: &'a mut [i32],
    iterations: &'a mut [u32],
    residual: &'a mut [f64],
    /// Written only where a ray has a reason: every entry is `None` before.
    reason: &'a mut [Option<Reason>],
    /// Set when a reason is written.
    any_reason: &'a AtomicBool,
}

/// Rows written by one task of a parallel fill.
const ROWS_PER_TASK: usize = 4096;

impl Table {
    fn new(rays: usize, width: usize) -> Table {
        Table {
            width,
            source: vec![0; rays],
            receiver: vec![0; rays],
            path: vec![0; rays],
            status: vec![0; rays],
            time: vec![0.0; rays],
            points: vec![0.0; rays * width * 2],
            num_points: vec![0; rays],
            media: vec![0; rays * (width - 1)],
            iterations: vec![0; rays],
            residual: vec![0.0; rays],
            reason: none_of(rays),
            any_reason: AtomicBool::new(false),
            stationary: None,
        }
    }

    fn rows(&mut self) -> Rows<'_> {
        Rows {
            width: self.width,
            source: &mut self.source,
            receiver: &mut self.receiver,
            path: &mut self.path,
            status: &mut self.status,
            time: &mut self.time,
            points: &mut self.points,
            num_points: &mut self.num_points,
            media: &mut self.media,
            iterations: &mut self.iterations,
            residual: &mut self.residual,
            reason: &mut self.reason,
            any_reason: &self.any_reason,
        }
    }

    fn finish(self, py: Python<'_>, scene: &Scene) -> PyRays {
        let (n, width) = (self.time.len(), self.width);
        let (arrival, kink, complete) = match self.stationary {
            Some(c) => (
                Some(c.arrival.into_pyarray(py).unbind()),
                Some(c.kink),
                Some(c.complete.into_pyarray(py).unbind()),
            ),
            None => (None, None, None),
        };
        PyRays {
            source: self.source.into_pyarray(py).unbind(),
            receiver: self.receiver.into_pyarray(py).unbind(),
            path: self.path.into_pyarray(py).unbind(),
            status: self.status.into_pyarray(py).unbind(),
            time: self.time.into_pyarray(py).unbind(),
            points: Array3::from_shape_vec((n, width, 2), self.points)
                .expect("width points a ray")
                .into_pyarray(py)
                .unbind(),
            num_points: self.num_points.into_pyarray(py).unbind(),
            media: Array2::from_shape_vec((n, width - 1), self.media)
                .expect("width − 1 legs a ray")
                .into_pyarray(py)
                .unbind(),
            iterations: self.iterations.into_pyarray(py).unbind(),
            residual: self.residual.into_pyarray(py).unbind(),
            reasons: Mutex::new(Reasons {
                codes: self.reason,
                any: self.any_reason.into_inner(),
                interfaces: interface_names(scene),
            }),
            status_names: status_names(),
            path_names: scene.paths().iter().map(|p| p.name.clone()).collect(),
            media_names: scene.media().iter().map(|m| m.name.clone()).collect(),
            arrival,
            kink,
            complete,
        }
    }
}

/// Fills `rows` in parallel: `write(state, first, rows)` writes the rows of rays `first..`
/// (tasks of at most `ROWS_PER_TASK` rows), each task with its own `state` from `init` (a
/// workspace, say).
fn fill_parallel<S>(
    rows: Rows<'_>,
    first: usize,
    init: &(impl Fn() -> S + Sync),
    write: &(impl Fn(&mut S, usize, &mut Rows<'_>) + Sync),
) {
    let n = rows.time.len();
    if n <= ROWS_PER_TASK {
        let mut rows = rows;
        write(&mut init(), first, &mut rows);
    } else {
        let (a, b) = rows.split_at(n / 2);
        rayon::join(
            || fill_parallel(a, first, init, write),
            || fill_parallel(b, first + n / 2, init, write),
        );
    }
}

impl Rows<'_> {
    /// The rows before `k` and from `k` on.
    fn split_at(self, k: usize) -> (Self, Self) {
        let w = self.width;
        let (source, source_b) = self.source.split_at_mut(k);
        let (receiver, receiver_b) = self.receiver.split_at_mut(k);
        let (path, path_b) = self.path.split_at_mut(k);
        let (status, status_b) = self.status.split_at_mut(k);
        let (time, time_b) = self.time.split_at_mut(k);
        let (points, points_b) = self.points.split_at_mut(k * w * 2);
        let (num_points, num_points_b) = self.num_points.split_at_mut(k);
        let (media, media_b) = self.media.split_at_mut(k * (w - 1));
        let (iterations, iterations_b) = self.iterations.split_at_mut(k);
        let (residual, residual_b) = self.residual.split_at_mut(k);
        let (reason, reason_b) = self.reason.split_at_mut(k);
        let any_reason = self.any_reason;
        (
            Rows {
                width: w,
                source,
                receiver,
                path,
                status,
                time,
                points,
                num_points,
                media,
                iterations,
                residual,
                reason,
                any_reason,
            },
            Rows {
                width: w,
                source: source_b,
                receiver: receiver_b,
                path: path_b,
                status: status_b,
                time: time_b,
                points: points_b,
                num_points: num_points_b,
                media: media_b,
                iterations: iterations_b,
                residual: residual_b,
                reason: reason_b,
                any_reason,
            },
        )
    }

    /// Row `i`: ray `triple` with its record, points (read only when it has a time) and leg
    /// media (`None`, or fewer than its legs, where unknown: −1).
    #[allow(clippy::too_many_arguments, reason = "the parts of one ray")]
    #[inline]
    fn write(
        &mut self,
        i: usize,
        scene: &Scene,
        triple: [usize; 3],
        record: &RayRecord,
        points: &[Point],
        media: Option<impl Iterator<Item = usize>>,
    ) {
        let own = scene.paths()[triple[2]].steps.len() + 2;
        self.write_scalars(i, triple, record, own);
        let w = self.width;
        let row = &mut self.points[i * w * 2..(i + 1) * w * 2];
        let mut written = 0;
        if record.status.has_time() && points.len() == own {
            for (xy, p) in row.chunks_exact_mut(2).zip(points) {
                xy.copy_from_slice(&[p.x, p.y]);
            }
            written = 2 * own;
        }
        if written < row.len() {
            row[written..].fill(f64::NAN);
        }
        let legs = &mut self.media[i * (w - 1)..(i + 1) * (w - 1)];
        let mut written = 0;
        if let Some(media) = media {
            for (leg, m) in legs.iter_mut().zip(media) {
                *leg = leg_code(m);
                written += 1;
            }
        }
        if written < legs.len() {
            legs[written..].fill(-1);
        }
    }

    /// [`write`](Self::write) for a ray of one interaction (three points) whose two leg media
    /// are known: without loops.
    #[inline(always)]
    fn write_one(
        &mut self,
        i: usize,
        triple: [usize; 3],
        record: &RayRecord,
        points: &[Point; 3],
        media: [usize; 2],
    ) {
        self.write_scalars(i, triple, record, 3);
        let w = self.width;
        let (row, rest) = self.points[i * w * 2..(i + 1) * w * 2].split_at_mut(6);
        if record.status.has_time() {
            let [a, b, c] = points;
            row.copy_from_slice(&[a.x, a.y, b.x, b.y, c.x, c.y]);
        } else {
            row.fill(f64::NAN);
        }
        let (legs, rest_legs) = self.media[i * (w - 1)..(i + 1) * (w - 1)].split_at_mut(2);
        legs.copy_from_slice(&[leg_code(media[0]), leg_code(media[1])]);
        // (Only when other paths have more points: a `fill` of nothing still calls memset.)
        if w > 3 {
            rest.fill(f64::NAN);
            rest_legs.fill(-1);
        }
    }

    /// The one-number columns of row `i`, for a ray of `own` points.
    #[inline(always)]
    fn write_scalars(&mut self, i: usize, triple: [usize; 3], record: &RayRecord, own: usize) {
        let [source, receiver, path] = triple;
        self.source[i] = source as i64;
        self.receiver[i] = receiver as i64;
        self.path[i] = path as i64;
        self.status[i] = status_code(record.status);
        self.time[i] = record.time;
        self.num_points[i] = own as i64;
        self.iterations[i] = record.iterations;
        self.residual[i] = record.residual;
        if let Some(reason) = record.reason {
            self.reason[i] = Some(reason);
            // (Read first: the flag's cache line stays shared between the workers.)
            if !self.any_reason.load(Ordering::Relaxed) {
                self.any_reason.store(true, Ordering::Relaxed);
            }
        }
    }
}

/// The `media` entry of a leg in medium `m`.
#[inline]
fn leg_code(m: usize) -> i32 {
    i32::try_from(m).unwrap_or(-1)
}

/// The entries of every stationary path, as the command-line tool writes them: one per
/// stationary path, and one (`no_path` or `not_converged`) per triple that has none.
fn stationary_table(scene: &Scene, rays: &StationaryRays) -> Table {
    let n = rays.entries();
    let mut table = Table::new(n, width(scene));
    let mut columns = StationaryColumns {
        arrival: Vec::with_capacity(n),
        kink: Vec::with_capacity(n),
        complete: Vec::with_capacity(n),
    };
    let mut rows = table.rows();
    let mut row = 0;
    for t in &rays.triples {
        let triple = [t.source, t.receiver, t.path];
        for (i, a) in t.arrivals.iter().enumerate() {
            let record = RayRecord {
                status: a.status,
                time: a.time,
                iterations: a.iterations.try_into().unwrap_or(u32::MAX),
                residual: a.residual,
                reason: a.reason,
            };
            let media = Some(a.media.iter().copied());
            rows.write(row, scene, triple, &record, &a.points, media);
            row += 1;
            columns.arrival.push(i as i64);
            columns.kink.push(kink_name(a.kink));
            columns.complete.push(t.complete);
        }
        if t.arrivals.is_empty() {
            let record = RayRecord {
                status: t.status_without_arrivals(),
                time: f64::NAN,
                iterations: 0,
                residual: f64::NAN,
                reason: Some(t.reason_without_arrivals()),
            };
            let media = scene.paths()[t.path]
                .media
                .as_deref()
                .map(|m| m.iter().copied());
            rows.write(row, scene, triple, &record, &[], media);
            row += 1;
            columns.arrival.push(0);
            columns.kink.push(None);
            columns.complete.push(t.complete);
        }
    }
    table.stationary = Some(columns);
    table
}

/// The most points of any path of `scene` (at least 2: the source and the receiver).
fn width(scene: &Scene) -> usize {
    scene
        .paths()
        .iter()
        .map(|p| p.steps.len() + 2)
        .max()
        .unwrap_or(2)
}

/// The rows of `Rays` as a batch's sink: the worker that solves a ray writes its row right
/// after solving it (the library's `Tracer::trace_batch_to`), so that numpy's arrays are
/// filled in the batch's own parallel pass.
struct RowSink<'a> {
    scene: &'a Scene,
    /// Paths (rays per block).
    paths: usize,
    rows: Rows<'a>,
}

impl<'a> RowSink<'a> {
    fn new(scene: &'a Scene, rows: Rows<'a>) -> Self {
        RowSink {
            scene,
            paths: scene.paths().len(),
            rows,
        }
    }
}

impl BatchSink for RowSink<'_> {
    fn blocks(&self) -> usize {
        self.rows.time.len().checked_div(self.paths).unwrap_or(0)
    }

    fn split_at(self, blocks: usize) -> (Self, Self) {
        let (a, b) = self.rows.split_at(blocks * self.paths);
        let (scene, paths) = (self.scene, self.paths);
        (
            RowSink {
                scene,
                paths,
                rows: a,
            },
            RowSink {
                scene,
                paths,
                rows: b,
            },
        )
    }

    #[inline]
    fn write(&mut self, at: RaySlot, record: &RayRecord, points: &[Point], media: &[usize]) {
        let legs = self.scene.paths()[at.path].steps.len() + 1;
        // Leg media are known when there is one per leg (as a `Batch` keeps them).
        let media = (media.len() == legs).then(|| media.iter().copied());
        let row = at.block * self.paths + at.path;
        let triple = [at.source, at.receiver, at.path];
        self.rows
            .write(row, self.scene, triple, record, points, media);
    }

    #[inline(always)]
    fn write_one(
        &mut self,
        at: RaySlot,
        record: &RayRecord,
        points: &[Point; 3],
        media: [usize; 2],
    ) {
        let row = at.block * self.paths + at.path;
        let triple = [at.source, at.receiver, at.path];
        self.rows.write_one(row, triple, record, points, media);
    }
}

/// The arrays of an earlier `Rays` from `trace`, borrowed for writing in place.
struct OutArrays<'py, 'a> {
    width: usize,
    source: PyReadwriteArray1<'py, i64>,
    receiver: PyReadwriteArray1<'py, i64>,
    path: PyReadwriteArray1<'py, i64>,
    status: PyReadwriteArray1<'py, u8>,
    time: PyReadwriteArray1<'py, f64>,
    points: PyReadwriteArray3<'py, f64>,
    num_points: PyReadwriteArray1<'py, i64>,
    media: PyReadwriteArray2<'py, i32>,
    iterations: PyReadwriteArray1<'py, u32>,
    residual: PyReadwriteArray1<'py, f64>,
    reasons: MutexGuard<'a, Reasons>,
    /// Set when the batch writes a reason.
    any_reason: AtomicBool,
    /// The reasons of the earlier result while the batch writes new ones (all `None` first),
    /// put back if it does not finish.
    earlier: Option<Vec<Option<Reason>>>,
}

impl<'py, 'a> OutArrays<'py, 'a> {
    /// The arrays of `out`, which must hold the rays of `scene` (those of an earlier `trace`
    /// of the same scene).
    fn borrow(py: Python<'py>, out: &'a PyRays, scene: &Scene) -> PyResult<Self> {
        let (n, width) = (scene.num_rays(), self::width(scene));
        let shape_error = || {
            argument_error(
                py,
                "out",
                format!("needs the Rays of an earlier trace() of {n} rays of {width} points"),
            )
        };
        if out.arrival.is_some() || out.time.bind(py).len() != n {
            return Err(shape_error());
        }
        if out.points.bind(py).shape() != [n, width, 2]
            || out.media.bind(py).shape() != [n, width - 1]
        {
            return Err(shape_error());
        }
        let busy = |_| argument_error(py, "out", "its arrays are in use or not writeable");
        let reasons = || {
            out.reasons.lock().map_err(|_| {
                PyRuntimeError::new_err("an earlier call failed while writing these rays")
            })
        };
        Ok(OutArrays {
            width,
            source: out.source.bind(py).try_readwrite().map_err(busy)?,
            receiver: out.receiver.bind(py).try_readwrite().map_err(busy)?,
            path: out.path.bind(py).try_readwrite().map_err(busy)?,
            status: out.status.bind(py).try_readwrite().map_err(busy)?,
            time: out.time.bind(py).try_readwrite().map_err(busy)?,
            points: out.points.bind(py).try_readwrite().map_err(busy)?,
            num_points: out.num_points.bind(py).try_readwrite().map_err(busy)?,
            media: out.media.bind(py).try_readwrite().map_err(busy)?,
            iterations: out.iterations.bind(py).try_readwrite().map_err(busy)?,
            residual: out.residual.bind(py).try_readwrite().map_err(busy)?,
            reasons: reasons()?,
            any_reason: AtomicBool::new(false),
            earlier: None,
        })
    }

    /// Their rows.
    fn rows(&mut self, py: Python<'_>) -> PyResult<Rows<'_>> {
        let contiguous = |_| argument_error(py, "out", "its arrays must stay contiguous");
        let reasons = &mut *self.reasons;
        if reasons.any && self.earlier.is_none() {
            let n = reasons.codes.len();
            self.earlier = Some(std::mem::replace(
                &mut reasons.codes,
                py.detach(|| none_of(n)),
            ));
        }
        Ok(Rows {
            width: self.width,
            source: self.source.as_slice_mut().map_err(contiguous)?,
            receiver: self.receiver.as_slice_mut().map_err(contiguous)?,
            path: self.path.as_slice_mut().map_err(contiguous)?,
            status: self.status.as_slice_mut().map_err(contiguous)?,
            time: self.time.as_slice_mut().map_err(contiguous)?,
            points: self.points.as_slice_mut().map_err(contiguous)?,
            num_points: self.num_points.as_slice_mut().map_err(contiguous)?,
            media: self.media.as_slice_mut().map_err(contiguous)?,
            iterations: self.iterations.as_slice_mut().map_err(contiguous)?,
            residual: self.residual.as_slice_mut().map_err(contiguous)?,
            reason: &mut reasons.codes,
            any_reason: &self.any_reason,
        })
    }

    /// After the batch has written every row: the reasons' flag and names.
    fn finish(mut self, scene: &Scene) {
        self.earlier = None;
        self.reasons.any = self.any_reason.load(Ordering::Relaxed);
        self.reasons.interfaces = interface_names(scene);
    }
}

impl Drop for OutArrays<'_, '_> {
    /// A batch that did not finish leaves the earlier result's reasons.
    fn drop(&mut self) {
        if let Some(earlier) = self.earlier.take() {
            self.reasons.codes = earlier;
        }
    }
}

/// An index into a list of `len` named things (`what`: interface, medium) from a name (via
/// `lookup`) or an integer.
fn named_index(
    py: Python<'_>,
    what: &str,
    value: &Bound<'_, PyAny>,
    len: usize,
    lookup: impl Fn(&str) -> Option<usize>,
) -> PyResult<usize> {
    if let Ok(name) = value.extract::<&str>() {
        return lookup(name)
            .ok_or_else(|| PyKeyError::new_err(format!("no {what} is named `{name}`")));
    }
    let index: i64 = value
        .extract()
        .map_err(|_| argument_error(py, what, format!("needs a {what} name or index")))?;
    usize::try_from(index)
        .ok()
        .filter(|&i| i < len)
        .ok_or_else(|| {
            PyIndexError::new_err(format!("{what} index {index} is out of range ({len})"))
        })
}

/// Where a long batch reports its progress.
enum Progress<'py> {
    /// A tqdm bar (tqdm.auto: a widget in a notebook, text in a terminal).
    Bar(Bound<'py, PyAny>),
    /// The caller's `progress(done, total)`.
    Callback(Bound<'py, PyAny>),
}

impl<'py> Progress<'py> {
    fn new(
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

    fn report(&self, done: usize, shown: usize, total: usize) -> PyResult<()> {
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

    fn close(&self) -> PyResult<()> {
        if let Progress::Bar(bar) = self {
            bar.call_method0("close")?;
        }
        Ok(())
    }
}

/// Runs the batch of every ray of `tracer` into `sink` (the GIL released), reporting to
/// `progress` from the calling thread while it runs. `Err` when the batch did not run
/// (nothing is written); else the error of a progress report, if one failed (the rows are
/// written all the same).
fn trace_into(
    py: Python<'_>,
    tracer: &Tracer,
    scratch: &mut BatchScratch,
    warm_start: bool,
    progress: Option<Progress<'_>>,
    sink: RowSink<'_>,
) -> PyResult<PyResult<()>> {
    let total = tracer.scene().num_rays();
    let done = AtomicUsize::new(0);
    let count = |n: usize| {
        done.fetch_add(n, Ordering::Relaxed);
    };
    let opts = BatchOptions {
        warm_start,
        progress: progress.as_ref().map(|_| &count as &(dyn Fn(usize) + Sync)),
        ..BatchOptions::default()
    };
    let (solved, reported) = match &progress {
        None => (
            py.detach(|| tracer.trace_batch_to(&opts, sink, scratch)),
            Ok(()),
        ),
        Some(progress) => {
            let (finished, mut shown) = (AtomicUsize::new(0), 0);
            let result = std::thread::scope(|scope| {
                let worker = scope.spawn(|| {
                    let solved = tracer.trace_batch_to(&opts, sink, scratch);
                    finished.store(1, Ordering::Release);
                    solved
                });
                let mut reported = Ok(());
                while finished.load(Ordering::Acquire) == 0 {
                    py.detach(|| std::thread::sleep(Duration::from_millis(50)));
                    let now = done.load(Ordering::Relaxed);
                    if reported.is_ok() && now > shown {
                        reported = progress.report(now, shown, total);
                        shown = now;
                    }
                }
                let solved = py.detach(|| worker.join());
                (solved, reported)
            });
            let (solved, mut reported) = result;
            let solved = solved.map_err(|_| PyRuntimeError::new_err("the batch panicked"))?;
            if reported.is_ok() && solved.is_ok() && shown < total {
                reported = progress.report(total, shown, total);
            }
            (solved, reported.and(progress.close()))
        }
    };
    solved.map_err(|e| scene_error(py, &e))?;
    Ok(reported)
}

impl PyTracer {
    fn inner_scene(&self) -> &Scene {
        self.tracer.scene()
    }

    fn path_index(&self, py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<usize> {
        let scene = self.inner_scene();
        if let Ok(name) = path.extract::<&str>() {
            return scene
                .paths()
                .iter()
                .position(|p| p.name.as_deref() == Some(name))
                .ok_or_else(|| PyKeyError::new_err(format!("no path is named `{name}`")));
        }
        let index: i64 = path
            .extract()
            .map_err(|_| argument_error(py, "path", "needs a path index or a path name"))?;
        usize::try_from(index)
            .ok()
            .filter(|&i| i < scene.paths().len())
            .ok_or_else(|| {
                PyIndexError::new_err(format!(
                    "path index {index} is out of range (the scene has {} paths)",
                    scene.paths().len()
                ))
            })
    }

    fn interface_index(&self, py: Python<'_>, interface: &Bound<'_, PyAny>) -> PyResult<usize> {
        let scene = self.inner_scene();
        named_index(
            py,
            "interface",
            interface,
            scene.interfaces().len(),
            |name| scene.interface_index(name),
        )
    }

    fn medium_index(&self, py: Python<'_>, medium: &Bound<'_, PyAny>) -> PyResult<usize> {
        let scene = self.inner_scene();
        named_index(py, "medium", medium, scene.media().len(), |name| {
            scene.medium_index(name)
        })
    }

    fn checked_points(
        &self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: usize,
    ) -> PyResult<(Point, Point)> {
        let source = point_arg(py, "source", source)?;
        let receiver = point_arg(py, "receiver", receiver)?;
        self.inner_scene()
            .check_solve(source, receiver, path)
            .map_err(|e| scene_error(py, &e))?;
        Ok((source, receiver))
    }
}

#[pymethods]
impl PyTracer {
    #[new]
    fn new(py: Python<'_>, scene: &Bound<'_, PyScene>) -> PyResult<PyTracer> {
        let shared = Arc::clone(&scene.get().scene);
        let tracer = py.detach(|| Tracer::new(shared));
        let tracer = tracer.map_err(|e| scene_error(py, &e))?;
        Ok(PyTracer {
            tracer,
            scratch: BatchScratch::default(),
            workspace: Workspace::new(),
            arrivals: Vec::new(),
            gradient: Gradient::default(),
        })
    }

    /// The tracer's scene.
    #[getter]
    fn scene(&self) -> PyScene {
        PyScene {
            scene: Arc::new(self.inner_scene().clone()),
        }
    }

    /// Every ray of the scene, in parallel (the GIL released), as numpy arrays (`Rays`).
    ///
    /// `warm_start`: start each receiver from its neighbour's solution (see the library's
    /// `BatchOptions::warm_start`). `progress`: `True` for a tqdm bar, or a callable
    /// `progress(done, total)` called from the calling thread. `out`: the `Rays` of an
    /// earlier `trace()` of this many rays, rewritten in place and returned (a loop then
    /// allocates its arrays once).
    #[pyo3(signature = (*, warm_start = true, progress = None, out = None))]
    fn trace(
        &mut self,
        py: Python<'_>,
        warm_start: bool,
        progress: Option<&Bound<'_, PyAny>>,
        out: Option<Bound<'_, PyRays>>,
    ) -> PyResult<Py<PyRays>> {
        let PyTracer {
            tracer, scratch, ..
        } = self;
        let scene = tracer.scene();
        let (n, w) = (scene.num_rays(), width(scene));
        // Each worker writes its rays into the arrays right after solving them.
        match out {
            Some(out) => {
                let mut arrays = OutArrays::borrow(py, out.get(), scene)?;
                let sink = RowSink::new(scene, arrays.rows(py)?);
                let progress = Progress::new(py, progress, n)?;
                let reported = trace_into(py, tracer, scratch, warm_start, progress, sink)?;
                arrays.finish(scene);
                reported?;
                Ok(out.unbind())
            }
            None => {
                let mut table = py.detach(|| Table::new(n, w));
                let sink = RowSink::new(scene, table.rows());
                let progress = Progress::new(py, progress, n)?;
                trace_into(py, tracer, scratch, warm_start, progress, sink)??;
                Py::new(py, table.finish(py, scene))
            }
        }
    }

    /// Every stationary path of every ray of the scene (not only the one the default start
    /// reaches), in parallel with the GIL released, as `Rays` with `arrival`, `kink` and
    /// `complete`: one entry per stationary path, ordered by time within its triple, and one
    /// `no_path` (a proof) or `not_converged` entry per triple that has none.
    fn trace_stationary(&self, py: Python<'_>) -> PyResult<PyRays> {
        let tracer = &self.tracer;
        let scene = self.inner_scene();
        let rays = py
            .detach(|| tracer.trace_stationary())
            .map_err(|e| scene_error(py, &e.into()))?;
        let table = py.detach(|| stationary_table(scene, &rays));
        Ok(table.finish(py, scene))
    }

    /// One ray of path `path` (index or name) between any two points.
    #[pyo3(signature = (source, receiver, path = None))]
    fn solve(
        &mut self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyRay> {
        let path = match path {
            Some(p) => self.path_index(py, p)?,
            None => 0,
        };
        let (source, receiver) = self.checked_points(py, source, receiver, path)?;
        let record = self
            .tracer
            .solve(source, receiver, path, &mut self.workspace);
        let scene = self.tracer.scene();
        let ws = &self.workspace;
        Ok(PyRay::from_record(
            py,
            scene,
            &record,
            ws.points(),
            ws.media(),
        ))
    }

    /// The travel time of one ray (NaN without one): `solve` without building a `Ray`.
    #[pyo3(signature = (source, receiver, path = None))]
    fn time(
        &mut self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<f64> {
        let path = match path {
            Some(p) => self.path_index(py, p)?,
            None => 0,
        };
        let (source, receiver) = self.checked_points(py, source, receiver, path)?;
        let record = self
            .tracer
            .solve(source, receiver, path, &mut self.workspace);
        Ok(record.time)
    }

    /// Solves one ray of path `path` between any two points and returns the derivatives of
    /// its time (`Gradient`): exact for the path as found (the envelope theorem at the solved
    /// points), so they agree with differences of re-solved times. For a layout loop: move
    /// things with the `set_*` calls, ask again.
    #[pyo3(signature = (source, receiver, path = None))]
    fn gradient(
        &mut self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyGradient> {
        let path = match path {
            Some(p) => self.path_index(py, p)?,
            None => 0,
        };
        let (source, receiver) = self.checked_points(py, source, receiver, path)?;
        let record = self
            .tracer
            .solve_with_gradient(
                source,
                receiver,
                path,
                &mut self.workspace,
                &mut self.gradient,
            )
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        let scene = self.tracer.scene();
        let gradient = record.status.has_time().then_some(&self.gradient);
        PyGradient::new(py, scene, &record, gradient)
    }

    /// Solves one ray of path `path` between any two points and returns how its points move
    /// with every parameter its time depends on (`PointSensitivities`): by the implicit
    /// function theorem, one tridiagonal solve with the converged Hessian per parameter; for
    /// users who need where a ray lands (on a detector, on a wall) rather than when. Raises
    /// `RuntimeError` at a caustic, where the points do not move smoothly.
    #[pyo3(signature = (source, receiver, path = None))]
    fn point_sensitivities(
        &mut self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyPointSensitivities> {
        let path = match path {
            Some(p) => self.path_index(py, p)?,
            None => 0,
        };
        let (source, receiver) = self.checked_points(py, source, receiver, path)?;
        let record = self
            .tracer
            .solve(source, receiver, path, &mut self.workspace);
        let scene = self.tracer.scene();
        if !record.status.has_time() {
            return PyPointSensitivities::new(py, scene, &record, None);
        }
        let sens = PointSensitivities::of_solved(scene, path, &self.workspace)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        PyPointSensitivities::new(py, scene, &record, Some(&sens))
    }

    /// The derivatives of the times of `rays` (from `trace`, `trace_stationary` or
    /// `solve_pairs` of this tracer), as `Gradients`: one row per ray, computed from each ray's
    /// points and leg media in parallel with the GIL released, the same numbers as
    /// `gradient` and the command-line tool's `"derivatives": true`.
    fn gradients(&self, py: Python<'_>, rays: &Bound<'_, PyRays>) -> PyResult<PyGradients> {
        let scene = self.tracer.scene();
        let rays = rays.get();
        let media_names: Vec<String> = scene.media().iter().map(|m| m.name.clone()).collect();
        let path_names: Vec<Option<String>> =
            scene.paths().iter().map(|p| p.name.clone()).collect();
        if rays.media_names != media_names || rays.path_names != path_names {
            return Err(argument_error(
                py,
                "rays",
                "are not rays of this tracer's scene (other media or paths)",
            ));
        }
        let (path, status) = (
            rays.path.bind(py).readonly(),
            rays.status.bind(py).readonly(),
        );
        let points = rays.points.bind(py).readonly();
        let num_points = rays.num_points.bind(py).readonly();
        let media = rays.media.bind(py).readonly();
        let (path, status, points, num_points, media) = (
            path.as_array(),
            status.as_array(),
            points.as_array(),
            num_points.as_array(),
            media.as_array(),
        );
        let n = path.len();
        let width = points.shape()[1];
        let shapes_agree = [
            status.len(),
            points.shape()[0],
            num_points.len(),
            media.shape()[0],
        ]
        .iter()
        .all(|&m| m == n)
            && media.shape()[1] + 1 == width;
        if !shapes_agree {
            return Err(argument_error(py, "rays", "arrays of different lengths"));
        }
        let m = scene.media().len();
        let k = scene
            .paths()
            .iter()
            .map(|p| p.steps.len())
            .max()
            .unwrap_or(0);
        let slots = 2 * k;
        let mut source = vec![f64::NAN; 2 * n];
        let mut receiver = vec![f64::NAN; 2 * n];
        let mut slowness = vec![f64::NAN; m * n];
        let mut vertex_interface = vec![-1i32; slots * n];
        let mut vertex = vec![-1i32; slots * n];
        let mut vertex_d = vec![f64::NAN; 2 * slots * n];
        py.detach(|| {
            use rayon::prelude::*;
            const PIECE: usize = 1024;
            let gradient_of = |g: &mut Gradient, scratch: &mut (Vec<Point>, Vec<usize>), i| {
                let code = usize::from(status[i]);
                let timed = STATUS_CODES.get(code).is_some_and(|s| s.has_time());
                let spec = usize::try_from(path[i])
                    .ok()
                    .and_then(|p| scene.paths().get(p));
                let (Some(spec), true) = (spec, timed) else {
                    return false;
                };
                let count = spec.steps.len() + 2;
                if usize::try_from(num_points[i]) != Ok(count) || count > width {
                    return false;
                }
                let (ray_points, ray_media) = scratch;
                ray_points.clear();
                ray_points
                    .extend((0..count).map(|j| Point::new(points[[i, j, 0]], points[[i, j, 1]])));
                ray_media.clear();
                for j in 0..count - 1 {
                    match usize::try_from(media[[i, j]]) {
                        Ok(medium) => ray_media.push(medium),
                        Err(_) => return false,
                    }
                }
                g.points_into(scene, &spec.steps, ray_points, ray_media)
                    .is_ok()
            };
            let pieces = n.div_ceil(PIECE);
            source
                .par_chunks_mut(2 * PIECE)
                .zip(receiver.par_chunks_mut(2 * PIECE))
                .zip(row_pieces(&mut slowness, m, PIECE, pieces))
                .zip(row_pieces(&mut vertex_interface, slots, PIECE, pieces))
                .zip(row_pieces(&mut vertex, slots, PIECE, pieces))
                .zip(row_pieces(&mut vertex_d, 2 * slots, PIECE, pieces))
                .enumerate()
                .for_each(|(piece, (((((src, rec), slow), ifaces), verts), ds))| {
                    let mut g = Gradient::default();
                    let mut scratch = (Vec::new(), Vec::new());
                    for row in 0..src.len() / 2 {
                        let i = piece * PIECE + row;
                        if !gradient_of(&mut g, &mut scratch, i) {
                            continue;
                        }
                        src[2 * row..2 * row + 2].copy_from_slice(&[g.source.x, g.source.y]);
                        rec[2 * row..2 * row + 2].copy_from_slice(&[g.receiver.x, g.receiver.y]);
                        slow[m * row..m * (row + 1)].copy_from_slice(&g.slowness);
                        for (slot, v) in g.vertices.iter().take(slots).enumerate() {
                            let at = slots * row + slot;
                            ifaces[at] = i32::try_from(v.interface).unwrap_or(-1);
                            verts[at] = i32::try_from(v.vertex).unwrap_or(-1);
                            ds[2 * at..2 * at + 2].copy_from_slice(&[v.d.x, v.d.y]);
                        }
                    }
                });
        });
        let array2 = |v: Vec<f64>, w: usize| Array2::from_shape_vec((n, w), v);
        let shape_error = |e: numpy::ndarray::ShapeError| PyRuntimeError::new_err(e.to_string());
        Ok(PyGradients {
            source: array2(source, 2)
                .map_err(shape_error)?
                .into_pyarray(py)
                .unbind(),
            receiver: array2(receiver, 2)
                .map_err(shape_error)?
                .into_pyarray(py)
                .unbind(),
            slowness: array2(slowness, m)
                .map_err(shape_error)?
                .into_pyarray(py)
                .unbind(),
            vertex_interface: Array2::from_shape_vec((n, slots), vertex_interface)
                .map_err(shape_error)?
                .into_pyarray(py)
                .unbind(),
            vertex: Array2::from_shape_vec((n, slots), vertex)
                .map_err(shape_error)?
                .into_pyarray(py)
                .unbind(),
            vertex_d: Array3::from_shape_vec((n, slots, 2), vertex_d)
                .map_err(shape_error)?
                .into_pyarray(py)
                .unbind(),
            media_names,
            interface_names: scene.interfaces().iter().map(|i| i.name.clone()).collect(),
        })
    }

    /// Rays of path `path` between `sources[i]` and `receivers[i]` (arrays of shape `(n, 2)`),
    /// in parallel with the GIL released, as `Rays` (their `source` and `receiver` hold `i`).
    #[pyo3(signature = (sources, receivers, path = None))]
    fn solve_pairs(
        &mut self,
        py: Python<'_>,
        sources: &Bound<'_, PyAny>,
        receivers: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyRays> {
        let path = match path {
            Some(p) => self.path_index(py, p)?,
            None => 0,
        };
        let sources = points_arg(py, "sources", sources)?;
        let receivers = points_arg(py, "receivers", receivers)?;
        if sources.len() != receivers.len() {
            return Err(argument_error(
                py,
                "receivers",
                format!(
                    "has {} points where sources has {}",
                    receivers.len(),
                    sources.len()
                ),
            ));
        }
        let scene = self.tracer.scene();
        for (i, (&s, &r)) in sources.iter().zip(&receivers).enumerate() {
            scene.check_solve(s, r, path).map_err(|e| {
                let key = format!("{}s[{i}]", e.key);
                scene_error(py, &SceneError::new(key, e.message))
            })?;
        }
        let tracer = &self.tracer;
        let table = py.detach(|| {
            let mut table = Table::new(sources.len(), width(scene));
            fill_parallel(table.rows(), 0, &Workspace::new, &|ws, first, rows| {
                for row in 0..rows.time.len() {
                    let i = first + row;
                    let record = tracer.solve(sources[i], receivers[i], path, ws);
                    let media = Some(ws.media().iter().copied());
                    rows.write(row, scene, [i, i, path], &record, ws.points(), media);
                }
            });
            table
        });
        Ok(table.finish(py, scene))
    }

    /// Every stationary path of path `path` between two points, ordered by time (a `Ray`
    /// each, with its `arrival` index and, on `vertex` paths, its `kink`). Returns the list
    /// and whether the search was complete (with `True`, an empty list proves there is none).
    #[pyo3(signature = (source, receiver, path = None))]
    fn stationary_paths(
        &mut self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<(Vec<PyRay>, bool)> {
        let path = match path {
            Some(p) => self.path_index(py, p)?,
            None => 0,
        };
        let (source, receiver) = self.checked_points(py, source, receiver, path)?;
        let tracer = &self.tracer;
        let out = &mut self.arrivals;
        let search = py
            .detach(|| tracer.stationary_paths(source, receiver, path, out))
            .map_err(|e| scene_error(py, &e.into()))?;
        let scene = self.tracer.scene();
        let rays = self
            .arrivals
            .iter()
            .enumerate()
            .map(|(i, a)| PyRay::from_arrival(py, scene, i, a))
            .collect();
        Ok((rays, search.complete))
    }

    /// Moves source `index` to `point`, checked as `sources[index]` of a scene file (a
    /// refused move leaves the tracer as it was). Cheap: nothing is rebuilt.
    fn set_source(
        &mut self,
        py: Python<'_>,
        index: usize,
        point: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let p = point_arg(py, &format!("sources[{index}]"), point)?;
        self.tracer
            .set_source(index, p)
            .map_err(|e| scene_error(py, &e))
    }

    /// Moves receiver `index` to `point`, checked as `receivers[index]`. Cheap.
    fn set_receiver(
        &mut self,
        py: Python<'_>,
        index: usize,
        point: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let p = point_arg(py, &format!("receivers[{index}]"), point)?;
        self.tracer
            .set_receiver(index, p)
            .map_err(|e| scene_error(py, &e))
    }

    /// Moves every receiver: `points` of shape `(n, 2)`, `n` the scene's receivers. Moves
    /// are checked one by one; a refused one raises, and the receivers before it stay moved.
    fn set_receivers(&mut self, py: Python<'_>, points: &Bound<'_, PyAny>) -> PyResult<()> {
        let points = points_arg(py, "receivers", points)?;
        let n = self.inner_scene().receivers().len();
        if points.len() != n {
            return Err(argument_error(
                py,
                "receivers",
                format!("has {} points; the scene has {n} receivers", points.len()),
            ));
        }
        for (i, p) in points.into_iter().enumerate() {
            self.tracer
                .set_receiver(i, p)
                .map_err(|e| scene_error(py, &e))?;
        }
        Ok(())
    }

    /// Gives interface `interface` (a name or an index) new vertices, `points` of shape
    /// `(n, 2)`, checked as `interfaces.NAME.points` of a scene file (a refused change leaves
    /// the tracer as it was). Rebuilds what depends on the interfaces.
    fn set_interface_points(
        &mut self,
        py: Python<'_>,
        interface: &Bound<'_, PyAny>,
        points: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let index = self.interface_index(py, interface)?;
        let name = &self.inner_scene().interfaces()[index].name;
        let points = points_arg(py, &format!("interfaces.{name}.points"), points)?;
        self.tracer
            .set_interface_points(index, &points)
            .map_err(|e| scene_error(py, &e))
    }

    /// Gives medium `medium` (a name or an index) the speed `speed`.
    fn set_medium_speed(
        &mut self,
        py: Python<'_>,
        medium: &Bound<'_, PyAny>,
        speed: f64,
    ) -> PyResult<()> {
        let index = self.medium_index(py, medium)?;
        self.tracer
            .set_medium_speed(index, speed)
            .map_err(|e| scene_error(py, &e))
    }

    /// Gives medium `medium` (a name or an index) the refractive index `index`.
    fn set_medium_index(
        &mut self,
        py: Python<'_>,
        medium: &Bound<'_, PyAny>,
        index: f64,
    ) -> PyResult<()> {
        let medium = self.medium_index(py, medium)?;
        self.tracer
            .set_medium_index(medium, index)
            .map_err(|e| scene_error(py, &e))
    }

    /// The scene's `search` (its `"search"` section): every arrival per (source, receiver),
    /// ordered by time, as a list of dicts with `source`, `receiver`, `steps` (as in the
    /// scene: `{"reflect": name}`), `media`, `status`, `time`, `points`, `iterations`,
    /// `complete`.
    fn search<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let tracer = &self.tracer;
        let arrivals = py
            .detach(|| tracer.search())
            .map_err(|e| argument_error(py, "search", e.to_string()))?;
        let scene = self.inner_scene();
        let list = PyList::empty(py);
        for a in &arrivals {
            list.append(search_arrival(py, scene, a)?)?;
        }
        Ok(list)
    }
}

fn search_arrival<'py>(
    py: Python<'py>,
    scene: &Scene,
    a: &SearchArrival,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("source", a.source)?;
    d.set_item("receiver", a.receiver)?;
    let steps = PyList::empty(py);
    for step in &a.steps {
        let s = PyDict::new(py);
        let kind = match step.kind {
            StepKind::Reflect => "reflect",
            StepKind::Refract => "refract",
        };
        s.set_item(kind, &scene.interfaces()[step.interface].name)?;
        steps.append(s)?;
    }
    d.set_item("steps", steps)?;
    let arrival = &a.arrival;
    d.set_item("media", medium_names(scene, arrival.media.iter().copied()))?;
    d.set_item("status", arrival.status.as_str())?;
    d.set_item("time", arrival.time)?;
    d.set_item("points", points_array(py, &arrival.points))?;
    d.set_item("iterations", arrival.iterations)?;
    d.set_item("residual", arrival.residual)?;
    d.set_item("reason", arrival.reason.map(|r| r.describe(scene)))?;
    d.set_item("kink", kink_name(arrival.kink))?;
    d.set_item("complete", a.complete)?;
    Ok(d)
}

/// The compiled core of the `eigenray` package.
#[pymodule]
fn _eigenray(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScene>()?;
    m.add_class::<PyTracer>()?;
    m.add_class::<PyRay>()?;
    m.add_class::<PyRays>()?;
    m.add_class::<PyGradient>()?;
    m.add_class::<PyPointSensitivities>()?;
    m.add_class::<PyGradients>()?;
    m.add("EigenrayError", m.py().get_type::<EigenrayError>())?;
    m.add("STATUS_NAMES", status_names())?;
    Ok(())
}
