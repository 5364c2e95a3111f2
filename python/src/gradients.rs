//! `Gradients`: the derivatives of many rays' times as numpy arrays, computed by the library
//! from the arrays of a `Rays`.

use eigenray::derivatives::{GradientArraysMut, GradientRows};
use eigenray::{Scene, output::STATUS_CODES, scene::Medium};
use numpy::ndarray::{Array2, Array3, ArrayBase, Data, Dimension, s};
use numpy::{IntoPyArray, PyArray2, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::interface_names;
use crate::error::{argument_error, check_memory};
use crate::rays::PyRays;

/// The derivatives of many rays' times as numpy arrays (see `Tracer.gradients`), row `i`
/// those of ray `i` of the `Rays` they were computed from: NaN (and −1 for the vertex indices)
/// for a ray without a time. `K` below is the most steps of a path of the scene.
#[pyclass(module = "eigenray", name = "Gradients", frozen, get_all)]
pub(crate) struct PyGradients {
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
    /// `(dT/dgx, dT/dgy)` of each medium with a speed gradient, by name, shape `(n, 2)` (a
    /// scene with a `gradient` medium; empty otherwise). Their `slowness` column is then
    /// `dT/dw` with `w = 1/speed` and the gradient held.
    speed_gradient: Py<PyDict>,
    /// `dT/dc` of each knot of each medium with a speed profile, by name, shape
    /// `(n, knots)` in the order of the medium's `profile` (a scene with a `profile` medium;
    /// empty otherwise). Their `slowness` column is then `dT/dw` with `w = 1/c` of the first
    /// knot and the profile's shape held.
    profile_speed: Py<PyDict>,
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

impl PyGradients {
    /// The gradients of `rays` (of a tracer of `scene`), computed in parallel with the GIL
    /// released.
    pub(crate) fn of_rays(py: Python<'_>, scene: &Scene, rays: &PyRays) -> PyResult<Self> {
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
            && points.shape()[2] == 2
            && media.shape()[1] + 1 == width;
        if !shapes_agree {
            return Err(argument_error(py, "rays", "arrays of different lengths"));
        }
        let m = scene.media().len();
        let slots = GradientArraysMut::slots(scene);
        // The arrays it fills, and a copy of each input array that is not in standard layout
        // (a broadcast `Rays` state holds many rows in little memory).
        let copy = |standard: bool, bytes: usize| if standard { 0 } else { bytes as u64 };
        let copies = copy(path.is_standard_layout(), 8 * n)
            + copy(status.is_standard_layout(), n)
            + copy(points.is_standard_layout(), 8 * points.len())
            + copy(num_points.is_standard_layout(), 8 * n)
            + copy(media.is_standard_layout(), 4 * media.len());
        let sg_width = GradientArraysMut::speed_gradient_width(scene);
        let ps_width = GradientArraysMut::profile_speed_width(scene);
        let per_ray =
            8 * (4 + m as u64 + (sg_width + ps_width) as u64) + slots as u64 * (4 + 4 + 16);
        check_memory(
            &format!("gradients: {n} rays"),
            (n as u64)
                .checked_mul(per_ray)
                .and_then(|b| b.checked_add(copies)),
        )?;
        // (In the arrays' own memory unless a caller changed their strides.)
        let (path, status, points) = (
            path.as_standard_layout(),
            status.as_standard_layout(),
            points.as_standard_layout(),
        );
        let (num_points, media) = (num_points.as_standard_layout(), media.as_standard_layout());
        // Which ray each row is where several share their points (through a profile).
        let launch = rays.quantities.float_column(py, "launch_angle");
        let launch = launch.as_ref().map(|a| a.readonly());
        let launch = launch.as_ref().map(|a| a.as_array());
        let launch = launch.as_ref().map(|a| a.as_standard_layout());
        if launch.as_ref().is_some_and(|a| a.len() != n) {
            return Err(argument_error(py, "rays", "arrays of different lengths"));
        }
        let rows = GradientRows {
            paths: flat(&path),
            statuses: flat(&status),
            status_of_code: &STATUS_CODES,
            width,
            points: flat(&points),
            num_points: flat(&num_points),
            media: flat(&media),
            launch_angles: launch.as_ref().map(flat),
        };
        // (Zeroed memory, written in the computation's parallel pass: every entry is written.)
        let mut source = vec![0.0; 2 * n];
        let mut receiver = vec![0.0; 2 * n];
        let mut slowness = vec![0.0; m * n];
        let mut vertex_interface = vec![0i32; slots * n];
        let mut vertex = vec![0i32; slots * n];
        let mut vertex_d = vec![0.0; 2 * slots * n];
        let mut speed_gradient = vec![0.0; sg_width * n];
        let mut profile_speed = vec![0.0; ps_width * n];
        py.detach(|| {
            let out = GradientArraysMut {
                source: &mut source,
                receiver: &mut receiver,
                slowness: &mut slowness,
                vertex_interface: &mut vertex_interface,
                vertex: &mut vertex,
                vertex_d: &mut vertex_d,
                speed_gradient: &mut speed_gradient,
                profile_speed: &mut profile_speed,
            };
            rows.gradients_into(scene, out);
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
            // Two a medium in a scene with a gradient medium; each profile's knots.
            speed_gradient: columns_by_medium(py, scene, speed_gradient, n, |m| {
                (2 * usize::from(sg_width > 0), m.gradient.is_some())
            })?,
            profile_speed: columns_by_medium(py, scene, profile_speed, n, |m| {
                let knots = m.profile.as_ref().map_or(0, Vec::len);
                (knots * usize::from(ps_width > 0), knots > 0)
            })?,
            media_names,
            interface_names: interface_names(scene),
        })
    }
}

/// Per-medium columns of `n` rows as a dict of `(n, w)` arrays by medium name: each row
/// holds `columns(m).0` entries of each medium `m` in the scene's order, and the medium is
/// listed when `columns(m).1`.
fn columns_by_medium(
    py: Python<'_>,
    scene: &Scene,
    rows: Vec<f64>,
    n: usize,
    columns: impl Fn(&Medium) -> (usize, bool),
) -> PyResult<Py<PyDict>> {
    let d = PyDict::new(py);
    let width: usize = scene.media().iter().map(|m| columns(m).0).sum();
    if !scene.media().iter().any(|m| columns(m).1) {
        return Ok(d.unbind());
    }
    let all = Array2::from_shape_vec((n, width), rows)
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let mut at = 0;
    for m in scene.media() {
        let (w, listed) = columns(m);
        if listed {
            let column = all.slice(s![.., at..at + w]).to_owned();
            d.set_item(&m.name, column.into_pyarray(py))?;
        }
        at += w;
    }
    Ok(d.unbind())
}

/// The entries of an array in standard (C) order, as one slice.
fn flat<A, S: Data<Elem = A>, D: Dimension>(array: &ArrayBase<S, D>) -> &[A] {
    array.as_slice().expect("an array in standard layout")
}
