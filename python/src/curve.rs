//! A ray's curve as a numpy array (`Ray.curve`, `Rays.curve`, `Arrivals.curve`,
//! `Scene.curve`): the library's `eigenray::trace::ray_curve`, its errors raised naming the
//! argument.

use eigenray::trace::{CurveError, ray_curve};
use eigenray::{Point, Scene};
use numpy::PyArray2;
use pyo3::prelude::*;

use crate::convert::points_array;
use crate::error::argument_error;

/// What a ray's curve is sampled from: its points, its leg media (empty where not known)
/// and its launch angle (a ray through a `profile` medium).
#[derive(Clone, Debug, Default)]
pub(crate) struct CurveInput {
    /// Source, interaction points, receiver.
    pub(crate) points: Vec<Point>,
    /// Leg media (indices into the scene's media), or empty.
    pub(crate) media: Vec<usize>,
    /// The direction at the source (radians from +x), where the scene gives it.
    pub(crate) launch_angle: Option<f64>,
}

impl CurveInput {
    /// The input of a row of leg media where −1 marks an unknown medium (then every leg's
    /// medium is taken as unknown: the legs are drawn straight).
    pub(crate) fn of_row(
        points: Vec<Point>,
        media: impl Iterator<Item = i64>,
        launch_angle: Option<f64>,
    ) -> CurveInput {
        let media: Option<Vec<usize>> = media.map(|m| usize::try_from(m).ok()).collect();
        CurveInput {
            points,
            media: media.unwrap_or_default(),
            launch_angle: launch_angle.filter(|a| a.is_finite()),
        }
    }

    /// The curve sampled at `n` points, as an `(n, 2)` float64 array (the GIL released
    /// while it is computed: a profile's rays are searched again).
    pub(crate) fn array<'py>(
        &self,
        py: Python<'py>,
        scene: &Scene,
        n: usize,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let curve = py
            .detach(|| ray_curve(scene, &self.points, &self.media, self.launch_angle, n))
            .map_err(|e| curve_error(py, &e))?;
        Ok(points_array(py, &curve))
    }
}

/// `EigenrayError` (a `ValueError`) naming the argument at fault.
fn curve_error(py: Python<'_>, e: &CurveError) -> PyErr {
    let key = match e {
        CurveError::Points => "points",
        CurveError::TooFewSamples { .. } => "n",
        CurveError::NoProfileRay { .. } => "launch_angle",
    };
    argument_error(py, key, e.to_string())
}
