//! The arrays of an earlier `Rays`, borrowed for a `trace(out=...)` that rewrites them in
//! place.

use std::sync::MutexGuard;
use std::sync::atomic::{AtomicBool, Ordering};

use eigenray::output::columns::Schema;
use eigenray::{Reason, Scene};
use numpy::{
    PyArrayMethods, PyReadwriteArray1, PyReadwriteArray2, PyReadwriteArray3, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use crate::columns::{OutColumn, out_rows};
use crate::convert::interface_names;
use crate::error::argument_error;
use crate::rays::{PyRays, Reasons, none_of};
use crate::rows::Rows;

/// The arrays of an earlier `Rays` from `trace`, borrowed for writing in place.
pub(crate) struct OutArrays<'py, 'a> {
    /// Points a ray.
    width: usize,
    /// Source index of each ray.
    source: PyReadwriteArray1<'py, i64>,
    /// Receiver index of each ray.
    receiver: PyReadwriteArray1<'py, i64>,
    /// Path index of each ray.
    path: PyReadwriteArray1<'py, i64>,
    /// Status code of each ray.
    status: PyReadwriteArray1<'py, u8>,
    /// Travel time of each ray.
    time: PyReadwriteArray1<'py, f64>,
    /// `width` points a ray.
    points: PyReadwriteArray3<'py, f64>,
    /// The points of each ray's path.
    num_points: PyReadwriteArray1<'py, i64>,
    /// `width − 1` leg media a ray.
    media: PyReadwriteArray2<'py, i32>,
    /// Solver iterations of each ray.
    iterations: PyReadwriteArray1<'py, u32>,
    /// Final relative residual of each ray.
    residual: PyReadwriteArray1<'py, f64>,
    /// The reasons, locked while the batch writes them.
    reasons: MutexGuard<'a, Reasons>,
    /// Set when the batch writes a reason.
    any_reason: AtomicBool,
    /// The reasons of the earlier result while the batch writes new ones (all `None` first),
    /// put back if it does not finish.
    earlier: Option<Vec<Option<Reason>>>,
    /// The schema of the scene's quantities.
    schema: Schema,
    /// The numpy columns of its quantities (a `Why` column's entries are in `reasons`).
    quantities: Vec<OutColumn<'py>>,
}

impl<'py, 'a> OutArrays<'py, 'a> {
    /// The arrays of `out`, which must hold the rays of `scene` (those of an earlier `trace`
    /// of the same scene).
    pub(crate) fn borrow(py: Python<'py>, out: &'a PyRays, scene: &Scene) -> PyResult<Self> {
        let (n, width) = (scene.num_rays(), crate::table::width(scene));
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
        let schema = Schema::of(scene);
        let asked: Vec<&str> = schema.columns().map(|c| c.name).collect();
        if out.quantities.names() != asked {
            let message = if asked.is_empty() {
                format!(
                    "needs the Rays of an earlier trace() without {}",
                    out.quantities.names().join(", ")
                )
            } else {
                format!(
                    "needs the Rays of an earlier trace() with {} (the scene asks for them)",
                    asked.join(", ")
                )
            };
            return Err(argument_error(py, "out", message));
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
        if !out.quantities.all_of_length(py, n) {
            return Err(shape_error());
        }
        let quantities = out.quantities.borrow(py, || {
            argument_error(py, "out", "its arrays are in use or not writeable")
        })?;
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
            schema,
            quantities,
        })
    }

    /// Their rows.
    pub(crate) fn rows(&mut self, py: Python<'_>) -> PyResult<Rows<'_>> {
        let message = "its arrays must be C-contiguous (in row order, as trace() gave them)";
        // (`as_slice_mut` takes Fortran order too: its rows would be written as C order's.)
        let c_order = [
            self.source.is_c_contiguous(),
            self.receiver.is_c_contiguous(),
            self.path.is_c_contiguous(),
            self.status.is_c_contiguous(),
            self.time.is_c_contiguous(),
            self.points.is_c_contiguous(),
            self.num_points.is_c_contiguous(),
            self.media.is_c_contiguous(),
            self.iterations.is_c_contiguous(),
            self.residual.is_c_contiguous(),
        ];
        if c_order.contains(&false) {
            return Err(argument_error(py, "out", message));
        }
        let contiguous = |_| argument_error(py, "out", message);
        let reasons = &mut *self.reasons;
        if reasons.any && self.earlier.is_none() {
            let n = reasons.codes.len();
            self.earlier = Some(std::mem::replace(
                &mut reasons.codes,
                py.detach(|| none_of(n)),
            ));
        }
        let quantities = out_rows(
            &self.schema,
            &mut self.quantities,
            &mut reasons.whys,
            || argument_error(py, "out", message),
        )?;
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
            quantities,
        })
    }

    /// After the batch has written every row: the reasons' flag and names.
    pub(crate) fn finish(mut self, scene: &Scene) {
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
