//! `Tracer.search`: the scene's automatic search, run with the GIL released on a thread of its
//! own, and its arrivals written there into the columns of an `Arrivals` (no Python object per
//! arrival).

use std::sync::Arc;

use eigenray::options::Run;
use eigenray::output::columns::{Entry, Schema};
use eigenray::trace::Kink;
use eigenray::{Reason, Scene, SearchArrival, Tracer, scene::StepKind};
use numpy::IntoPyArray;
use numpy::ndarray::{Array2, Array3};
use pyo3::prelude::*;

use crate::arrivals::{DIFFRACT_KIND_NAMES, NO_STEP, PyArrivals, STEP_KIND_NAMES};
use crate::columns::QuantityColumns;
use crate::convert::{interface_names, status_code, status_names};
use crate::error::{argument_error, check_memory};
use crate::interrupt::interruptible;
use crate::rays::Reasons;

/// The arrivals of the scene's `search` of `tracer` (see `Tracer.search`): searched and
/// written into arrays with the GIL released, on a thread of its own (Ctrl-C stops the
/// search); `MemoryError` when the arrays would not fit.
pub(crate) fn search_arrivals(py: Python<'_>, tracer: &Tracer) -> PyResult<PyArrivals> {
    let run = Run::new();
    let schema = Schema::of(tracer.scene());
    let dims = if tracer.scene().extrusion().is_some() {
        3
    } else {
        2
    };
    let search = || {
        tracer.search(&run).map(|report| {
            if run.stop_requested() {
                // Interrupted: the caller raises, the arrivals are not wanted.
                return Ok(None);
            }
            ArrivalTable::of(report.arrivals, schema, dims).map(Some)
        })
    };
    let table = interruptible(py, &run, search, || {})?
        .map_err(|e| argument_error(py, "search", e.to_string()))??;
    let Some(table) = table else {
        return Err(pyo3::exceptions::PyRuntimeError::new_err(
            "the search was stopped",
        ));
    };
    Ok(table.finish(py, &tracer.shared_scene()))
}

/// The columns of a search's arrivals while they are filled: one entry per arrival, and
/// `steps` (the most steps of any arrival) columns in the tables of steps.
struct ArrivalTable {
    /// The most steps of any arrival (its order).
    steps: usize,
    /// Source index of each arrival.
    source: Vec<i64>,
    /// Receiver index of each arrival.
    receiver: Vec<i64>,
    /// Travel time of each arrival.
    time: Vec<f64>,
    /// Steps of each arrival.
    order: Vec<u32>,
    /// Status code of each arrival.
    status: Vec<u8>,
    /// Whether the search of each arrival's pair was complete.
    complete: Vec<bool>,
    /// Newton steps of each arrival's solve.
    iterations: Vec<u32>,
    /// Final relative residual of each arrival.
    residual: Vec<f64>,
    /// Why each arrival is not `converged`.
    reason: Vec<Option<Reason>>,
    /// The kink of each `vertex` arrival.
    kink: Vec<Option<Kink>>,
    /// `steps + 2` points an arrival, `(x, y)` each (`(x, y, z)` in an extruded scene), NaN
    /// past its own.
    points: Vec<f64>,
    /// Coordinates a point: 2, or 3 in an extruded scene.
    dims: usize,
    /// `steps` interface indices an arrival, −1 past its own steps.
    step_interface: Vec<i64>,
    /// `steps` step kinds an arrival, [`NO_STEP`] past its own steps.
    step_kind: Vec<u8>,
    /// `steps + 1` leg media an arrival, −1 past its own legs.
    media: Vec<i64>,
    /// The columns of the quantities the scene asks for.
    quantities: QuantityColumns,
}

impl ArrivalTable {
    /// The bytes of the columns of `n` arrivals of at most `steps` steps (`None`: more than
    /// can be addressed).
    fn bytes(n: usize, steps: usize, schema: &Schema) -> Option<u64> {
        let steps = steps as u64;
        let codes = std::mem::size_of::<Option<Reason>>() + std::mem::size_of::<Option<Kink>>();
        // Indices, time, order, status, complete, iterations, residual, reason and kink.
        let row = 8 + 8 + 8 + 4 + 1 + 1 + 4 + 8 + codes as u64;
        // The points, the steps' interfaces and kinds, and the leg media.
        let tables = steps
            .checked_add(2)?
            .checked_mul(16)?
            .checked_add(steps.checked_mul(9)?)?
            .checked_add(steps.checked_add(1)?.checked_mul(8)?)?;
        let quantities = QuantityColumns::bytes_per_ray(schema);
        (n as u64).checked_mul(row.checked_add(tables)?.checked_add(quantities)?)
    }

    /// The columns of `arrivals` (with the columns of the quantities of `schema`), each
    /// arrival freed once written; `MemoryError` when they would not fit.
    fn of(arrivals: Vec<SearchArrival>, schema: Schema, dims: usize) -> PyResult<ArrivalTable> {
        let n = arrivals.len();
        let steps = arrivals.iter().map(|a| a.steps.len()).max().unwrap_or(0);
        check_memory(
            &format!("search: {n} arrivals of up to {steps} steps"),
            ArrivalTable::bytes(n, steps, &schema),
        )?;
        let mut table = ArrivalTable {
            steps,
            source: arrivals.iter().map(|a| a.source as i64).collect(),
            receiver: arrivals.iter().map(|a| a.receiver as i64).collect(),
            time: arrivals.iter().map(|a| a.arrival.time).collect(),
            order: arrivals.iter().map(|a| a.steps.len() as u32).collect(),
            status: arrivals
                .iter()
                .map(|a| status_code(a.arrival.status))
                .collect(),
            complete: arrivals.iter().map(|a| a.complete).collect(),
            iterations: arrivals
                .iter()
                .map(|a| u32::try_from(a.arrival.iterations).unwrap_or(u32::MAX))
                .collect(),
            residual: arrivals.iter().map(|a| a.arrival.residual).collect(),
            reason: arrivals.iter().map(|a| a.arrival.reason).collect(),
            kink: arrivals.iter().map(|a| a.arrival.kink).collect(),
            points: vec![f64::NAN; n * (steps + 2) * dims],
            dims,
            step_interface: vec![-1; n * steps],
            step_kind: vec![NO_STEP; n * steps],
            media: vec![-1; n * (steps + 1)],
            quantities: QuantityColumns::new(schema, n),
        };
        for (i, a) in arrivals.into_iter().enumerate() {
            table.write_row(i, &a);
        }
        Ok(table)
    }

    /// The rows of arrival `i` in the tables of points, steps and media, and its amplitude.
    fn write_row(&mut self, i: usize, a: &SearchArrival) {
        let w = self.steps + 2;
        let d = self.dims;
        let points = &mut self.points[i * w * d..(i + 1) * w * d];
        for (k, (xy, p)) in points
            .chunks_exact_mut(d)
            .zip(&a.arrival.points)
            .enumerate()
        {
            xy[0] = p.x;
            xy[1] = p.y;
            if d == 3 {
                xy[2] = a.heights.get(k).copied().unwrap_or(f64::NAN);
            }
        }
        let steps = i * self.steps..(i + 1) * self.steps;
        let interfaces = self.step_interface[steps.clone()].iter_mut();
        for ((interface, kind), step) in interfaces.zip(&mut self.step_kind[steps]).zip(&a.steps) {
            *interface = step.interface as i64;
            *kind = match step.kind {
                StepKind::Reflect => 0,
                StepKind::Refract => 1,
                StepKind::Diffract { .. } => 2,
            };
        }
        let legs = &mut self.media[i * (w - 1)..(i + 1) * (w - 1)];
        for (leg, &m) in legs.iter_mut().zip(&a.arrival.media) {
            *leg = m as i64;
        }
        if let Some(mut rows) = self.quantities.rows() {
            rows.write(i, &Entry::of_search(a));
        }
    }

    /// The columns as the `Arrivals` of `scene`.
    fn finish(self, py: Python<'_>, scene: &Arc<Scene>) -> PyArrivals {
        let (n, steps) = (self.time.len(), self.steps);
        let (quantities, whys) = self.quantities.finish(py);
        let interfaces = interface_names(scene);
        let diffraction = scene.search().is_some_and(|s| s.diffraction);
        let table = |columns: usize, values: Vec<_>| {
            Array2::from_shape_vec((n, columns), values).expect("columns entries a row")
        };
        PyArrivals {
            source: self.source.into_pyarray(py).unbind(),
            receiver: self.receiver.into_pyarray(py).unbind(),
            time: self.time.into_pyarray(py).unbind(),
            order: self.order.into_pyarray(py).unbind(),
            status: self.status.into_pyarray(py).unbind(),
            complete: self.complete.into_pyarray(py).unbind(),
            iterations: self.iterations.into_pyarray(py).unbind(),
            residual: self.residual.into_pyarray(py).unbind(),
            points: Array3::from_shape_vec((n, steps + 2, self.dims), self.points)
                .expect("steps + 2 points a row")
                .into_pyarray(py)
                .unbind(),
            step_interface: table(steps, self.step_interface).into_pyarray(py).unbind(),
            step_kind: Array2::from_shape_vec((n, steps), self.step_kind)
                .expect("steps kinds a row")
                .into_pyarray(py)
                .unbind(),
            media: table(steps + 1, self.media).into_pyarray(py).unbind(),
            status_names: status_names(),
            step_kind_names: if diffraction {
                DIFFRACT_KIND_NAMES.to_vec()
            } else {
                STEP_KIND_NAMES.to_vec()
            },
            vertices: if diffraction {
                let lines = scene.interfaces().iter();
                lines.map(|i| i.polyline.vertices().to_vec()).collect()
            } else {
                Vec::new()
            },
            interface_names: interfaces.clone(),
            media_names: scene.media().iter().map(|m| m.name.clone()).collect(),
            reasons: Reasons {
                any: self.reason.iter().any(Option::is_some),
                codes: self.reason,
                interfaces,
                whys,
            },
            kinks: self.kink,
            quantities,
            scene: Arc::clone(scene),
        }
    }
}
