//! What a `Rays` holds: every ray's numpy arrays (`PyRays`, whose methods are in `rays.rs`)
//! and the reasons of those that are not `converged` (`Reasons`), apart from the methods so
//! that pickling (`pickling.rs`), which `Rays` calls, can build one without a circle.

use std::sync::{Arc, Mutex};

use eigenray::{Reason, Scene};
use numpy::{PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use rayon::iter::ParallelExtend;

use crate::columns::{QuantityArrays, WhyColumn};

/// Every ray of a scene as numpy arrays, in ray order (source-major, then receiver, then
/// path). Rays without a time have `time` NaN and NaN points.
#[pyclass(module = "eigenray", name = "Rays", frozen)]
pub(crate) struct PyRays {
    /// Source index of each ray, shape `(n,)`.
    #[pyo3(get)]
    pub(crate) source: Py<PyArray1<i64>>,
    /// Receiver index of each ray.
    #[pyo3(get)]
    pub(crate) receiver: Py<PyArray1<i64>>,
    /// Path index of each ray.
    #[pyo3(get)]
    pub(crate) path: Py<PyArray1<i64>>,
    /// Status code of each ray (an index into `status_names`), `uint8`.
    #[pyo3(get)]
    pub(crate) status: Py<PyArray1<u8>>,
    /// Travel time; NaN for a ray without one.
    #[pyo3(get)]
    pub(crate) time: Py<PyArray1<f64>>,
    /// Source, interaction points and receiver, shape `(n, P, 2)`, NaN-padded past a path's
    /// own points (P: the most points of any path) and NaN for a ray without a time.
    #[pyo3(get)]
    pub(crate) points: Py<PyArray3<f64>>,
    /// Points of each ray's path (`k + 2` for `k` steps), shape `(n,)`.
    #[pyo3(get)]
    pub(crate) num_points: Py<PyArray1<i64>>,
    /// Leg media, shape `(n, P − 1)`: indices into `media_names`, −1 where unknown or past the
    /// path's legs.
    #[pyo3(get)]
    pub(crate) media: Py<PyArray2<i32>>,
    /// Solver iterations.
    #[pyo3(get)]
    pub(crate) iterations: Py<PyArray1<u32>>,
    /// Final relative residual (NaN where the solver did not run).
    #[pyo3(get)]
    pub(crate) residual: Py<PyArray1<f64>>,
    /// Why each ray is not `converged` (`None` where it is): read through the `reason`
    /// getter (a list), rewritten by `trace(out=...)`.
    pub(crate) reasons: Mutex<Reasons>,
    /// The status names, by code.
    #[pyo3(get)]
    pub(crate) status_names: Vec<&'static str>,
    /// The scene's path names (`None` for an unnamed path), by path index.
    #[pyo3(get)]
    pub(crate) path_names: Vec<Option<String>>,
    /// The scene's medium names, by medium index.
    #[pyo3(get)]
    pub(crate) media_names: Vec<String>,
    /// From `trace_stationary`: each entry's place by time among its triple's stationary
    /// paths (0 for a triple without any); `None` from `trace`.
    #[pyo3(get)]
    pub(crate) arrival: Option<Py<PyArray1<i64>>>,
    /// From `trace_stationary`: `"minimum"`, `"maximum"` or `"mixed"` on `vertex` entries.
    #[pyo3(get)]
    pub(crate) kink: Option<Vec<Option<String>>>,
    /// From `trace_stationary`: whether the triple's search was complete.
    #[pyo3(get)]
    pub(crate) complete: Option<Py<PyArray1<bool>>>,
    /// The columns of the quantities the scene asks for (with `"amplitudes"`: `amplitude`,
    /// `spreading`, `coefficient`, `attenuation_db`, `amplitude_reason`), read as attributes
    /// (`None` for a quantity the scene does not ask for).
    pub(crate) quantities: QuantityArrays,
    /// The scene the rays were traced in (the tracer's, last written by `trace(out=...)`),
    /// for their curves.
    pub(crate) scene: Mutex<Option<Arc<Scene>>>,
}

/// Why each ray of a `Rays` is not `converged`, as the library's reasons (written by the
/// batch's workers without a string each), worded when read with the interfaces' names.
pub(crate) struct Reasons {
    /// One per ray.
    pub(crate) codes: Vec<Option<Reason>>,
    /// Whether an entry is not `None` (most rays have no reason, and rows write `None` only
    /// over an earlier result that has some).
    pub(crate) any: bool,
    /// The scene's interface names, by index.
    pub(crate) interfaces: Vec<String>,
    /// The quantities' reasons (with `"amplitudes"`, why each ray's amplitude has no value:
    /// one per ray, `None` where it has one or the ray has no time).
    pub(crate) whys: Vec<WhyColumn>,
}

impl Reasons {
    /// Each ray's reason in words (`None` where it has none).
    pub(crate) fn words(&self) -> Vec<Option<String>> {
        (0..self.codes.len()).map(|i| self.word(i)).collect()
    }

    /// Ray `i`'s reason in words (`None` where it has none or there is no ray `i`).
    pub(crate) fn word(&self, i: usize) -> Option<String> {
        let name = |i: usize| self.interfaces.get(i).map(String::as_str);
        self.codes
            .get(i)
            .copied()
            .flatten()
            .map(|r| r.describe_with(name))
    }
}

/// `n` reasons, all `None`, written by the rayon pool (the first touch of fresh memory is
/// then not a serial step before a parallel batch).
pub(crate) fn none_of(n: usize) -> Vec<Option<Reason>> {
    let mut codes = Vec::new();
    codes.par_extend(rayon::iter::repeat_n(None, n));
    codes
}
