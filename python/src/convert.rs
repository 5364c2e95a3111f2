//! Conversions between Python values and the library's types: points and point arrays from
//! array-likes, indices from names, and the names and codes of statuses, media and kinks.

use eigenray::{Point, Scene, Status, output::STATUS_CODES, trace::Kink};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2};
use pyo3::exceptions::{PyIndexError, PyKeyError, PyMemoryError, PyTypeError};
use pyo3::prelude::*;

use crate::error::{argument_error, check_memory};

/// The status names in the order of their codes (the `.npy` output's codes).
pub(crate) fn status_names() -> Vec<&'static str> {
    STATUS_CODES.iter().map(|s| s.as_str()).collect()
}

/// The code of `status` (its place in the `.npy` output's codes).
pub(crate) fn status_code(status: Status) -> u8 {
    STATUS_CODES
        .iter()
        .position(|&s| s == status)
        .expect("every status has a code") as u8
}

/// `TypeError` when `value` holds complex numbers (numpy would keep only their real parts).
fn refuse_complex(py: Python<'_>, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
    let complex: bool = py
        .import("numpy")?
        .call_method1("iscomplexobj", (value,))?
        .extract()?;
    if complex {
        return Err(PyTypeError::new_err(format!(
            "{key}: complex numbers are not coordinates (give real x and y)"
        )));
    }
    Ok(())
}

/// A point from any Python sequence of two numbers (tuple, list, numpy array).
pub(crate) fn point_arg(py: Python<'_>, key: &str, value: &Bound<'_, PyAny>) -> PyResult<Point> {
    refuse_complex(py, key, value)?;
    let xy: [f64; 2] = value
        .extract()
        .map_err(|_| argument_error(py, key, "needs a point: a sequence of two numbers"))?;
    Ok(Point::new(xy[0], xy[1]))
}

/// Points from an array-like of shape `(n, 2)`, for a call that builds `per_row` bytes from
/// each (at least the point's 16): `MemoryError` before anything is copied when that does not
/// fit in the memory available.
pub(crate) fn points_arg(
    py: Python<'_>,
    key: &str,
    value: &Bound<'_, PyAny>,
    per_row: u64,
) -> PyResult<Vec<Point>> {
    refuse_complex(py, key, value)?;
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
    let rows = view.nrows() as u64;
    check_memory(
        &format!("{key}: {rows} points"),
        rows.checked_mul(per_row.max(16)),
    )?;
    let mut out = Vec::new();
    out.try_reserve_exact(view.nrows())
        .map_err(|_| PyMemoryError::new_err(format!("{key}: {rows} points do not fit")))?;
    out.extend(view.rows().into_iter().map(|r| Point::new(r[0], r[1])));
    Ok(out)
}

/// `points` as a numpy array of shape `(n, 2)`.
pub(crate) fn points_array<'py>(py: Python<'py>, points: &[Point]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = points.iter().flat_map(|p| [p.x, p.y]).collect();
    Array2::from_shape_vec((points.len(), 2), flat)
        .expect("two coordinates a point")
        .into_pyarray(py)
}

/// The names of the media `media` (indices into the scene's media).
pub(crate) fn medium_names(scene: &Scene, media: impl Iterator<Item = usize>) -> Vec<String> {
    media.map(|m| scene.media()[m].name.clone()).collect()
}

/// The name of a vertex path's kink (`"minimum"`, `"maximum"`, `"mixed"`).
pub(crate) fn kink_name(kink: Option<Kink>) -> Option<String> {
    kink.map(|k| k.as_str().to_string())
}

/// The names of the interfaces of `scene`, by index.
pub(crate) fn interface_names(scene: &Scene) -> Vec<String> {
    // An extruded scene's steps also name the floor and the ceiling, after the interfaces.
    (0..scene.interfaces().len() + 2)
        .filter_map(|i| scene.step_name(i).map(str::to_owned))
        .collect()
}

/// An index into a list of `len` named things (`what`: interface, medium) from a name (via
/// `lookup`) or an integer.
pub(crate) fn named_index(
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
