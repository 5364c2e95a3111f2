//! `Arrivals`: a search's arrivals (`Tracer.search`) as named numpy arrays, which read as the
//! list of dicts `search` gave before them too: `len`, indexing (slices and negative indices),
//! iteration and `to_dicts`, each dict made from the arrays when asked for.

use std::sync::Arc;

use eigenray::trace::Kink;
use eigenray::{Point, Scene};
use numpy::ndarray::Dimension;
use numpy::{
    Element, NpyIndex, PyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PySlice};

use crate::columns::{QuantityArrays, dir_of, why_words};
use crate::convert::{kink_name, points_array};
use crate::curve::CurveInput;
use crate::rays::Reasons;

/// The names of the step kinds, by their code in `step_kind`.
pub(crate) const STEP_KIND_NAMES: [&str; 2] = ["reflect", "refract"];

/// [`STEP_KIND_NAMES`] of a scene whose search lists diffracted arrivals.
pub(crate) const DIFFRACT_KIND_NAMES: [&str; 3] = ["reflect", "refract", "diffract"];

/// The `step_kind` entry past an arrival's own steps.
pub(crate) const NO_STEP: u8 = 255;

/// A search's arrivals as numpy arrays, ordered as the search lists them (source-major, then
/// receiver, then by time). `len`, `arrivals[i]`, slices, iteration and `to_dicts()` give each
/// arrival as a dict, as `search` did before it gave arrays.
#[pyclass(module = "eigenray", name = "Arrivals", frozen)]
pub(crate) struct PyArrivals {
    /// Source index of each arrival, shape `(n,)`.
    #[pyo3(get)]
    pub(crate) source: Py<PyArray1<i64>>,
    /// Receiver index of each arrival.
    #[pyo3(get)]
    pub(crate) receiver: Py<PyArray1<i64>>,
    /// Travel time of each arrival (every arrival has one).
    #[pyo3(get)]
    pub(crate) time: Py<PyArray1<f64>>,
    /// Steps (reflections and refractions) of each arrival, `uint32`: 0 for the direct ray.
    #[pyo3(get)]
    pub(crate) order: Py<PyArray1<u32>>,
    /// Status code of each arrival (an index into `status_names`), `uint8`.
    #[pyo3(get)]
    pub(crate) status: Py<PyArray1<u8>>,
    /// Whether the search of each arrival's pair was complete.
    #[pyo3(get)]
    pub(crate) complete: Py<PyArray1<bool>>,
    /// Newton steps of each arrival's solve, `uint32`.
    #[pyo3(get)]
    pub(crate) iterations: Py<PyArray1<u32>>,
    /// Final relative residual of each arrival.
    #[pyo3(get)]
    pub(crate) residual: Py<PyArray1<f64>>,
    /// Source, interaction points and receiver, shape `(n, K + 2, 2)` (K: the largest
    /// `order`), NaN past an arrival's own `order + 2` points.
    #[pyo3(get)]
    pub(crate) points: Py<PyArray3<f64>>,
    /// The interface of each step, shape `(n, K)`: indices into `interface_names`, −1 past an
    /// arrival's own steps.
    #[pyo3(get)]
    pub(crate) step_interface: Py<PyArray2<i64>>,
    /// The kind of each step, shape `(n, K)`, `uint8`: 0 reflect, 1 refract, 2 diffract
    /// (indices into `step_kind_names`), 255 past an arrival's own steps.
    #[pyo3(get)]
    pub(crate) step_kind: Py<PyArray2<u8>>,
    /// Leg media, shape `(n, K + 1)`: indices into `media_names`, −1 past an arrival's own
    /// `order + 1` legs.
    #[pyo3(get)]
    pub(crate) media: Py<PyArray2<i64>>,
    /// The status names, by code.
    #[pyo3(get)]
    pub(crate) status_names: Vec<&'static str>,
    /// The step kinds' names, by code: `["reflect", "refract"]`, and `"diffract"` when the
    /// search lists diffracted arrivals.
    #[pyo3(get)]
    pub(crate) step_kind_names: Vec<&'static str>,
    /// Per interface, its vertices, when the search lists diffracted arrivals (a diffraction's
    /// `vertex` in the dicts is the index of its point among them); else empty.
    pub(crate) vertices: Vec<Vec<Point>>,
    /// The scene's interface names, by interface index.
    #[pyo3(get)]
    pub(crate) interface_names: Vec<String>,
    /// The scene's medium names, by medium index.
    #[pyo3(get)]
    pub(crate) media_names: Vec<String>,
    /// Why each arrival is not `converged`, and why its amplitude has no value: read through
    /// the `reason` and `amplitude_reason` getters.
    pub(crate) reasons: Reasons,
    /// The kink of each `vertex` arrival: read through the `kink` getter.
    pub(crate) kinks: Vec<Option<Kink>>,
    /// The columns of the quantities the scene asks for (with `"amplitudes"`: `amplitude`,
    /// `spreading`, `coefficient`, `attenuation_db`, `amplitude_reason`), read as attributes
    /// (`None` for a quantity the scene does not ask for).
    pub(crate) quantities: QuantityArrays,
    /// The scene searched, for the arrivals' curves.
    pub(crate) scene: Arc<Scene>,
}

#[pymethods]
impl PyArrivals {
    /// Why each arrival is not `converged` (`None` where it is), naming interfaces.
    #[getter]
    fn reason(&self) -> Vec<Option<String>> {
        self.reasons.words()
    }

    /// `"minimum"`, `"maximum"` or `"mixed"` for a `vertex` arrival, else `None`.
    #[getter]
    fn kink(&self) -> Vec<Option<String>> {
        self.kinks.iter().map(|&k| kink_name(k)).collect()
    }

    /// A quantity's column (with `"amplitudes"`: `amplitude` and `coefficient`, complex128,
    /// `spreading` and `attenuation_db`, float64, NaN where an arrival has none, and
    /// `amplitude_reason`, why an arrival's amplitude has no value, the command-line tool's
    /// words); `None` for a quantity the scene does not ask for.
    fn __getattr__(&self, py: Python<'_>, name: &str) -> PyResult<Py<PyAny>> {
        self.quantities
            .attribute(py, "Arrivals", name, || why_words(&self.reasons.whys, name))
    }

    fn __dir__(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        dir_of::<PyArrivals>(py)
    }

    /// Arrival `i`'s curve (negative: from the end) sampled at `n` points, an `(n, 2)`
    /// float64 array, as `Ray.curve` gives it: on the ray itself (arcs through `gradient`
    /// and `profile` media, through a profile the ray of its `launch_angle`, turning points
    /// and reflections and all), the first its source, the last its receiver, every
    /// interaction point among them. Raises `IndexError` past the arrivals, `EigenrayError`
    /// (a `ValueError`) for `n` below its number of points or an extruded scene's arrival
    /// (its 3-D points are its straight legs).
    #[pyo3(signature = (i, n = 100))]
    fn curve<'py>(
        &self,
        py: Python<'py>,
        i: isize,
        n: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let len = self.len(py);
        let at = if i < 0 { i + len as isize } else { i };
        if at < 0 || at >= len as isize {
            return Err(PyIndexError::new_err(format!(
                "arrival index {i} is out of range ({len} arrivals)"
            )));
        }
        let at = at as usize;
        if self.points.bind(py).shape()[2] != 2 {
            return Err(PyValueError::new_err(
                "an extruded scene's arrivals have 3-D points: their legs are straight, their points the curve",
            ));
        }
        let k = self::at(py, &self.order, at)? as usize + 2;
        let mut row = Vec::with_capacity(k);
        for j in 0..k {
            row.push(Point::new(
                self::at(py, &self.points, [at, j, 0])?,
                self::at(py, &self.points, [at, j, 1])?,
            ));
        }
        let legs: Vec<i64> = (0..k - 1)
            .map(|j| self::at(py, &self.media, [at, j]))
            .collect::<PyResult<_>>()?;
        let angle = self.quantities.float_at(py, "launch_angle", at);
        CurveInput::of_row(row, legs.into_iter(), angle).array(py, &self.scene, n)
    }

    /// Every arrival as a dict: the list `search` gave before it gave arrays.
    fn to_dicts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for i in 0..self.len(py) {
            list.append(self.arrival(py, i)?)?;
        }
        Ok(list)
    }

    fn __len__(&self, py: Python<'_>) -> usize {
        self.len(py)
    }

    /// Arrival `index` as a dict (negative: from the end), or a list of them for a slice.
    fn __getitem__<'py>(
        &self,
        py: Python<'py>,
        index: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let n = self.len(py);
        if let Ok(slice) = index.cast::<PySlice>() {
            let s = slice.indices(n as isize)?;
            let list = PyList::empty(py);
            for k in 0..s.slicelength as isize {
                list.append(self.arrival(py, (s.start + k * s.step) as usize)?)?;
            }
            return Ok(list.into_any());
        }
        let i: isize = index.extract()?;
        let at = if i < 0 { i + n as isize } else { i };
        if at < 0 || at >= n as isize {
            return Err(PyIndexError::new_err(format!(
                "arrival index {i} is out of range ({n} arrivals)"
            )));
        }
        Ok(self.arrival(py, at as usize)?.into_any())
    }

    fn __iter__(slf: Bound<'_, Self>) -> ArrivalsIterator {
        ArrivalsIterator {
            arrivals: slf.unbind(),
            next: 0,
        }
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!("Arrivals({} arrivals)", self.len(py))
    }
}

impl PyArrivals {
    /// The number of arrivals.
    fn len(&self, py: Python<'_>) -> usize {
        self.time.bind(py).len()
    }

    /// Arrival `i` as a dict, from the arrays: `source`, `receiver`, `steps` (`{"reflect":
    /// name}` each), `media` (names), `status`, `time`, `points` (`(order + 2, 2)`, `(order + 2, 3)` in an extruded scene),
    /// `iterations`, `residual`, `reason`, `kink`, `complete` and, with `"amplitudes"`, the
    /// amplitude's five keys.
    fn arrival<'py>(&self, py: Python<'py>, i: usize) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("source", at(py, &self.source, i)?)?;
        d.set_item("receiver", at(py, &self.receiver, i)?)?;
        let order = at(py, &self.order, i)? as usize;
        let steps = PyList::empty(py);
        for j in 0..order {
            let kind = at(py, &self.step_kind, [i, j])?;
            let interface = at(py, &self.step_interface, [i, j])?;
            let step = PyDict::new(py);
            step.set_item(
                name(&DIFFRACT_KIND_NAMES, kind)?,
                name(&self.interface_names, interface)?,
            )?;
            if usize::from(kind) == 2 {
                let p = Point::new(
                    at(py, &self.points, [i, j + 1, 0])?,
                    at(py, &self.points, [i, j + 1, 1])?,
                );
                let vertex = usize::try_from(interface)
                    .ok()
                    .and_then(|k| self.vertices.get(k))
                    .and_then(|v| v.iter().position(|&q| q == p));
                step.set_item("vertex", vertex)?;
            }
            steps.append(step)?;
        }
        d.set_item("steps", steps)?;
        let media = (0..=order)
            .map(|j| name(&self.media_names, at(py, &self.media, [i, j])?))
            .collect::<PyResult<Vec<_>>>()?;
        d.set_item("media", media)?;
        d.set_item(
            "status",
            name(&self.status_names, at(py, &self.status, i)?)?,
        )?;
        d.set_item("time", at(py, &self.time, i)?)?;
        let dims = self.points.bind(py).shape()[2];
        if dims == 3 {
            // An extruded scene's points: (x, y, z).
            let mut flat = Vec::with_capacity((order + 2) * 3);
            for j in 0..order + 2 {
                for k in 0..3 {
                    flat.push(at(py, &self.points, [i, j, k])?);
                }
            }
            let points = numpy::ndarray::Array2::from_shape_vec((order + 2, 3), flat)
                .expect("three coordinates a point");
            d.set_item("points", numpy::IntoPyArray::into_pyarray(points, py))?;
        } else {
            let points = (0..order + 2)
                .map(|j| {
                    Ok(Point::new(
                        at(py, &self.points, [i, j, 0])?,
                        at(py, &self.points, [i, j, 1])?,
                    ))
                })
                .collect::<PyResult<Vec<_>>>()?;
            d.set_item("points", points_array(py, &points))?;
        }
        d.set_item("iterations", at(py, &self.iterations, i)?)?;
        d.set_item("residual", at(py, &self.residual, i)?)?;
        d.set_item("reason", self.reasons.word(i))?;
        d.set_item("kink", kink_name(self.kinks.get(i).copied().flatten()))?;
        d.set_item("complete", at(py, &self.complete, i)?)?;
        self.quantities.set_entry(py, &d, i, |name, i| {
            let why = self.reasons.whys.iter().find(|w| w.column.name == name)?;
            why.reasons.get(i).copied().flatten().map(|r| r.to_string())
        })?;
        Ok(d)
    }
}

/// The entry of `array` at `index`; `ValueError` where there is none (an array reshaped
/// since `search` gave it).
fn at<T: Element + Copy, D: Dimension>(
    py: Python<'_>,
    array: &Py<PyArray<T, D>>,
    index: impl NpyIndex<Dim = D>,
) -> PyResult<T> {
    array
        .bind(py)
        .get_owned(index)
        .ok_or_else(|| PyValueError::new_err("the arrivals' arrays do not hold the arrival"))
}

/// The name of `code` in `names`; `ValueError` for a code that names nothing (an array
/// changed since `search` gave it).
fn name<T: Copy + TryInto<usize> + std::fmt::Display, S: AsRef<str>>(
    names: &[S],
    code: T,
) -> PyResult<&str> {
    code.try_into()
        .ok()
        .and_then(|c| names.get(c))
        .map(AsRef::as_ref)
        .ok_or_else(|| PyValueError::new_err(format!("{code} is not a code of the arrivals")))
}

/// Iterates over an `Arrivals`, one dict at a time.
#[pyclass(module = "eigenray", name = "ArrivalsIterator")]
pub(crate) struct ArrivalsIterator {
    /// The arrivals.
    arrivals: Py<PyArrivals>,
    /// The next arrival's index.
    next: usize,
}

#[pymethods]
impl ArrivalsIterator {
    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __next__<'py>(&mut self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let arrivals = self.arrivals.get();
        if self.next >= arrivals.len(py) {
            return Ok(None);
        }
        self.next += 1;
        arrivals.arrival(py, self.next - 1).map(Some)
    }
}
