//! The package's errors: `EigenrayError`, from the library's scene errors and from arguments.

use eigenray::SceneError;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

pyo3::create_exception!(
    _eigenray,
    EigenrayError,
    PyValueError,
    "An invalid scene or argument: `key` names where the problem is, `message` what it is."
);

/// The Python exception of a scene error: `EigenrayError(str)` with `key` and `message`.
pub(crate) fn scene_error(py: Python<'_>, e: &SceneError) -> PyErr {
    let err = EigenrayError::new_err(e.to_string());
    let value = err.value(py);
    // Setting attributes on a fresh exception instance cannot fail.
    let _ = value.setattr("key", e.key.as_str());
    let _ = value.setattr("message", e.message.as_str());
    err
}

/// An error at `key` from an argument of a call (not from the scene).
pub(crate) fn argument_error(py: Python<'_>, key: &str, message: impl Into<String>) -> PyErr {
    scene_error(py, &SceneError::new(key, message))
}
