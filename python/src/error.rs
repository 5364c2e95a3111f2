//! The package's errors: `EigenrayError`, from the library's scene errors and from arguments.

use eigenray::SceneError;
use eigenray::options::available_memory;
use pyo3::exceptions::{PyMemoryError, PyValueError};
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

/// `MemoryError` unless `bytes` (what `what` needs; `None`: more than can be addressed) fits
/// in the memory available, as the command-line tool checks it
/// ([`available_memory`]: the machine's free memory and the address-space limit). Where the
/// memory available is unknown, the allocations themselves are the test.
pub(crate) fn check_memory(what: &str, bytes: Option<u64>) -> PyResult<()> {
    let have = available_memory();
    let fits = match (bytes, have) {
        (None, _) => false,
        (Some(b), Some(h)) => b <= h,
        (Some(_), None) => true,
    };
    if fits {
        return Ok(());
    }
    let gb = |b: u64| format!("{:.1} GB", b as f64 / 1e9);
    let need = bytes.map_or("more bytes than can be addressed".to_string(), gb);
    let have = have.map_or(String::new(), |h| {
        format!(", more than the {} available", gb(h))
    });
    Err(PyMemoryError::new_err(format!(
        "{what} needs {need}{have}: split the work over several calls"
    )))
}
