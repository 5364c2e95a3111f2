//! `Tracer.trace`: the batch of every ray, written into numpy's arrays by its own workers,
//! with progress reported from the calling thread, which Ctrl-C interrupts.

use std::sync::PoisonError;

use eigenray::options::Run;
use eigenray::output::columns::Schema;
use eigenray::{
    BatchOptions, Tracer,
    batch::{BatchScratch, BatchSink},
};
use pyo3::prelude::*;

use crate::error::{check_memory, scene_error};
use crate::interrupt::interruptible;
use crate::out_arrays::OutArrays;
use crate::progress::{Progress, Reports};
use crate::rays::PyRays;
use crate::sink::{QuantitySink, RowSink};
use crate::table::{Table, width};

/// Every ray of `tracer` as `Rays` (see `Tracer.trace`): into the arrays of `out` (the `Rays`
/// of an earlier `trace` of as many rays) when given, else into new ones.
pub(crate) fn trace_rays(
    py: Python<'_>,
    tracer: &Tracer,
    scratch: &mut BatchScratch,
    warm_start: bool,
    progress: Option<&Bound<'_, PyAny>>,
    out: Option<Bound<'_, PyRays>>,
) -> PyResult<Py<PyRays>> {
    let scene = tracer.scene();
    let (n, w) = (scene.num_rays(), width(scene));
    // Each worker writes its rays into the arrays right after solving them.
    match out {
        Some(out) => {
            let mut arrays = OutArrays::borrow(py, out.get(), scene)?;
            let sink = RowSink::new(scene, arrays.rows(py)?);
            let progress = Progress::new(py, progress, n)?;
            let reported = trace_rows(py, tracer, scratch, warm_start, progress, sink)?;
            arrays.finish(scene);
            if let Ok(mut kept) = out.get().scene.lock() {
                *kept = Some(tracer.shared_scene());
            }
            reported?;
            Ok(out.unbind())
        }
        None => {
            let schema = Schema::of(scene);
            let bytes = Table::bytes(n, w, warm_start, &schema);
            check_memory(&format!("trace: {n} rays"), bytes)?;
            let mut table = py.detach(|| Table::new(n, w, schema));
            let sink = RowSink::new(scene, table.rows());
            let progress = Progress::new(py, progress, n)?;
            trace_rows(py, tracer, scratch, warm_start, progress, sink)??;
            let rays = table.finish(py, scene);
            *rays.scene.lock().unwrap_or_else(PoisonError::into_inner) =
                Some(tracer.shared_scene());
            Py::new(py, rays)
        }
    }
}

/// [`trace_into`] the rows of `sink`, with their quantities when they have their columns
/// (the one choice of the batch: a batch without quantities runs the plain sink).
fn trace_rows(
    py: Python<'_>,
    tracer: &Tracer,
    scratch: &mut BatchScratch,
    warm_start: bool,
    progress: Option<Progress<'_>>,
    sink: RowSink<'_>,
) -> PyResult<PyResult<()>> {
    if sink.has_quantities() {
        let sink = QuantitySink::new(tracer, sink);
        trace_into(py, tracer, scratch, warm_start, progress, sink)
    } else {
        trace_into(py, tracer, scratch, warm_start, progress, sink)
    }
}

/// Runs the batch of every ray of `tracer` into `sink` (the GIL released, on a thread of its
/// own: Ctrl-C stops it), reporting to `progress` from the calling thread while it runs.
/// `Err` when the batch did not run or was interrupted (nothing useful is written); else the
/// error of a progress report, if one failed (the rows are written all the same).
fn trace_into<S: BatchSink>(
    py: Python<'_>,
    tracer: &Tracer,
    scratch: &mut BatchScratch,
    warm_start: bool,
    progress: Option<Progress<'_>>,
    sink: S,
) -> PyResult<PyResult<()>> {
    let total = tracer.scene().num_rays();
    let run = Run::new();
    let opts = BatchOptions {
        warm_start,
        ..BatchOptions::default()
    };
    let mut reports = Reports::new(progress.as_ref(), &run, total);
    let solved = interruptible(
        py,
        &run,
        || tracer.trace_batch_to(&opts, &run, sink, scratch),
        || reports.poll(),
    )?;
    solved.map_err(|e| scene_error(py, &e))?;
    Ok(reports.finish())
}
