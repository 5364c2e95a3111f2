//! Python bindings of eigenray (the `eigenray._eigenray` extension module).
//!
//! Everything here converts: Python values to the library's types (with the library's own
//! validation and error messages) and the library's results to numpy arrays. The Python
//! package (`python/eigenray/`) re-exports these classes and adds the plotting helper.

mod arrivals;
mod columns;
mod convert;
mod curve;
mod error;
mod gradient;
mod gradients;
mod interrupt;
mod out_arrays;
mod pickling;
mod progress;
mod ray;
mod rays;
mod rays_data;
mod response;
mod rows;
mod scene;
mod search;
mod sensitivities;
mod sink;
mod table;
mod trace;
mod tracer;

use pyo3::prelude::*;

use crate::arrivals::PyArrivals;
use crate::convert::status_names;
use crate::error::EigenrayError;
use crate::gradient::PyGradient;
use crate::gradients::PyGradients;
use crate::ray::PyRay;
use crate::rays::PyRays;
use crate::scene::PyScene;
use crate::sensitivities::PyPointSensitivities;
use crate::tracer::PyTracer;

/// The compiled core of the `eigenray` package.
#[pymodule]
fn _eigenray(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScene>()?;
    m.add_class::<PyTracer>()?;
    m.add_class::<PyRay>()?;
    m.add_class::<PyRays>()?;
    m.add_class::<PyArrivals>()?;
    m.add_class::<PyGradient>()?;
    m.add_class::<PyPointSensitivities>()?;
    m.add_class::<PyGradients>()?;
    m.add("EigenrayError", m.py().get_type::<EigenrayError>())?;
    m.add("STATUS_NAMES", status_names())?;
    Ok(())
}
