//! `Scene`: a validated scene, read from JSON, a `dict` or a file, and its parts as Python
//! values.

use std::sync::Arc;

use eigenray::Scene;
use eigenray::options::{MAX_INPUT_BYTES, read_limited};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::exceptions::PyIOError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString, PyType};

use crate::convert::{named_index, points_arg, points_array};
use crate::curve::CurveInput;
use crate::error::{argument_error, scene_error};

/// A scene: media, interfaces, sources, receivers and paths, validated.
///
/// Build one with `Scene(source)` from a JSON string, a `dict` of the same shape, or a path to
/// a scene file (`str` ending in `.json` or `os.PathLike`); or with `Scene.from_json`,
/// `Scene.from_dict`, `Scene.from_file`. An invalid scene raises `EigenrayError` naming the
/// key, with the same message as the command-line tool.
#[pyclass(module = "eigenray", name = "Scene", frozen)]
pub(crate) struct PyScene {
    /// Shared with the tracers made from it (a tracer's updates copy it first).
    pub(crate) scene: Arc<Scene>,
}

impl PyScene {
    /// A scene from JSON text the user wrote, parsed with the GIL released.
    fn parse(py: Python<'_>, text: &str) -> PyResult<PyScene> {
        PyScene::validated(py, py.detach(|| Scene::from_json(text)))
    }

    /// A scene from JSON text serialised from the user's `dict`: its errors name the key path
    /// only (no line and column of a text the user never wrote).
    fn parse_generated(py: Python<'_>, text: &str) -> PyResult<PyScene> {
        PyScene::validated(py, py.detach(|| Scene::from_generated_json(text)))
    }

    /// The Python face of a parsed scene, or its error.
    fn validated(py: Python<'_>, scene: Result<Scene, eigenray::SceneError>) -> PyResult<PyScene> {
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
        PyScene::parse_generated(py, text.extract::<&str>()?)
    }

    /// A scene from a file.
    #[staticmethod]
    fn from_file(py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<PyScene> {
        let os = py.import("os")?;
        let path: String = os.call_method1("fspath", (path,))?.extract()?;
        // At most the command-line tool's limit is read (an endless `/dev/zero` included).
        let read = py.detach(|| std::fs::File::open(&path).and_then(|mut f| read_limited(&mut f)));
        let bytes = read
            .map_err(|e| PyIOError::new_err(format!("{path}: {e}")))?
            .ok_or_else(|| {
                argument_error(
                    py,
                    "scene",
                    format!(
                        "{path}: larger than {} MiB, the largest scene file read",
                        MAX_INPUT_BYTES >> 20
                    ),
                )
            })?;
        let text = String::from_utf8(bytes).map_err(|e| {
            argument_error(
                py,
                "scene",
                format!(
                    "{path}: not UTF-8 text (invalid byte at offset {})",
                    e.utf8_error().valid_up_to()
                ),
            )
        })?;
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
    /// The curve of the ray through `points` (its source, its interaction points, its
    /// receiver: a `Ray`'s `points`, a row of `Rays.points` or `Arrivals.points` without its
    /// padding) whose legs lie in `media` (names or indices, one per leg, as `Ray.media` and
    /// the rows of `media` give them; `None` or a −1: not known, the legs drawn straight),
    /// sampled at `n` points, an `(n, 2)` float64 array, as `Ray.curve` gives it. Through a
    /// `profile` medium, the ray that leaves at `launch_angle` (the entry's `launch_angle`;
    /// `None`: the one the default mode chooses). Raises `EigenrayError` (a `ValueError`)
    /// naming the argument at fault.
    #[pyo3(signature = (points, media = None, *, launch_angle = None, n = 100))]
    fn curve<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
        media: Option<&Bound<'py, PyAny>>,
        launch_angle: Option<f64>,
        n: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let points = points_arg(py, "points", points, 16)?;
        let scene = &self.scene;
        let mut legs = Vec::new();
        if let Some(media) = media {
            for m in media.try_iter()? {
                let m = m?;
                if m.extract::<i64>().is_ok_and(|i| i < 0) {
                    legs.push(-1);
                    continue;
                }
                let index = named_index(py, "media", &m, scene.media().len(), |name| {
                    scene.medium_index(name)
                })?;
                legs.push(index as i64);
            }
        }
        CurveInput::of_row(points, legs.into_iter(), launch_angle).array(py, scene, n)
    }

    /// Whether a medium has a `gradient` or a `profile` (some legs are curved: draw them with
    /// `curve`).
    #[getter]
    fn curved(&self) -> bool {
        self.scene.curved()
    }

    #[getter]
    fn num_rays(&self) -> usize {
        self.scene.num_rays()
    }

    /// The scene as a JSON document, edits included: `Scene(scene.to_json())` is this
    /// scene again, bit for bit (every number written with the digits that read back to
    /// it; a medium's speed as given, not recomputed from its slowness).
    fn to_json(&self, py: Python<'_>) -> String {
        py.detach(|| self.scene.to_json())
    }

    /// Pickling (`multiprocessing`, joblib, Dask, Ray): the scene as its JSON document
    /// (`to_json`), which reads back to the same scene, bit for bit.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyType>, (String,))> {
        let py = slf.py();
        Ok((py.get_type::<PyScene>(), (slf.get().to_json(py),)))
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
