//! The arrays of a `Rays` while they are filled: allocated for their rays, written row by row
//! (see `rows`), then handed to numpy; the tables of `solve_pairs` and of every stationary
//! path.

use std::sync::Mutex;
use std::sync::atomic::AtomicBool;

use eigenray::options::{Progress, Run};
use eigenray::output::columns::{Entry, Schema};
use eigenray::{Point, Reason, Scene, StationaryRays, Tracer, Workspace};
use numpy::IntoPyArray;
use numpy::ndarray::{Array2, Array3};
use pyo3::prelude::*;

use crate::columns::QuantityColumns;
use crate::convert::{interface_names, kink_name, status_names};
use crate::rays::{PyRays, Reasons, none_of};
use crate::rows::{Rows, fill_parallel};

/// The arrays of `Rays`, allocated for their rays and filled in place (in parallel for
/// batches): `width` points a ray.
pub(crate) struct Table {
    /// Points a ray.
    width: usize,
    /// Source index of each ray.
    source: Vec<i64>,
    /// Receiver index of each ray.
    receiver: Vec<i64>,
    /// Path index of each ray.
    path: Vec<i64>,
    /// Status code of each ray.
    status: Vec<u8>,
    /// Travel time of each ray.
    time: Vec<f64>,
    /// `width` points a ray, `(x, y)` each.
    points: Vec<f64>,
    /// The points of each ray's path.
    num_points: Vec<i64>,
    /// `width − 1` leg media a ray.
    media: Vec<i32>,
    /// Solver iterations of each ray.
    iterations: Vec<u32>,
    /// Final relative residual of each ray.
    residual: Vec<f64>,
    /// Why each ray is not `converged`.
    reason: Vec<Option<Reason>>,
    /// Whether a row has a reason.
    any_reason: AtomicBool,
    /// The columns of every stationary path's entries, for `trace_stationary`.
    stationary: Option<StationaryColumns>,
    /// The columns of the quantities the scene asks for.
    quantities: QuantityColumns,
}

/// The columns of every stationary path's entries (see [`stationary_table`]).
struct StationaryColumns {
    /// Each entry's place by time among its triple's stationary paths.
    arrival: Vec<i64>,
    /// The kink of each `vertex` entry.
    kink: Vec<Option<String>>,
    /// Whether each entry's triple's search was complete.
    complete: Vec<bool>,
}

impl Table {
    /// The bytes of the arrays of `rays` rays of `width` points each, and of the batch's
    /// copy of them when it solves in a spatial order (`sorted`): what `new` and the batch
    /// allocate (`None`: more than can be addressed), with the columns of the quantities of
    /// `schema`.
    pub(crate) fn bytes(rays: usize, width: usize, sorted: bool, schema: &Schema) -> Option<u64> {
        let (rays, width) = (rays as u64, width as u64);
        // Indices, status, time, iterations, residual, the reason; the points and media.
        let row = 8 * 3 + 1 + 8 + 8 + 4 + 8 + std::mem::size_of::<Option<Reason>>() as u64;
        let per_ray =
            row + width.checked_mul(16)? + (width - 1) * 4 + QuantityColumns::bytes_per_ray(schema);
        // The batch's copy: a record, the points and the media of each ray.
        let copy = if sorted {
            48 + width * 16 + width * 4
        } else {
            0
        };
        rays.checked_mul(per_ray + copy)
    }

    /// The arrays of `rays` rays of `width` points each, with the columns of the quantities
    /// of `schema` (those the scene asks for).
    pub(crate) fn new(rays: usize, width: usize, schema: Schema) -> Table {
        Table {
            width,
            source: vec![0; rays],
            receiver: vec![0; rays],
            path: vec![0; rays],
            status: vec![0; rays],
            time: vec![0.0; rays],
            points: vec![0.0; rays * width * 2],
            num_points: vec![0; rays],
            media: vec![0; rays * (width - 1)],
            iterations: vec![0; rays],
            residual: vec![0.0; rays],
            reason: none_of(rays),
            any_reason: AtomicBool::new(false),
            stationary: None,
            quantities: QuantityColumns::new(schema, rays),
        }
    }

    /// All its rows, for writing.
    pub(crate) fn rows(&mut self) -> Rows<'_> {
        Rows {
            width: self.width,
            source: &mut self.source,
            receiver: &mut self.receiver,
            path: &mut self.path,
            status: &mut self.status,
            time: &mut self.time,
            points: &mut self.points,
            num_points: &mut self.num_points,
            media: &mut self.media,
            iterations: &mut self.iterations,
            residual: &mut self.residual,
            reason: &mut self.reason,
            any_reason: &self.any_reason,
            quantities: self.quantities.rows(),
        }
    }

    /// The arrays as the `Rays` of `scene`.
    pub(crate) fn finish(self, py: Python<'_>, scene: &Scene) -> PyRays {
        let (n, width) = (self.time.len(), self.width);
        let (arrival, kink, complete) = match self.stationary {
            Some(c) => (
                Some(c.arrival.into_pyarray(py).unbind()),
                Some(c.kink),
                Some(c.complete.into_pyarray(py).unbind()),
            ),
            None => (None, None, None),
        };
        let (quantities, whys) = self.quantities.finish(py);
        PyRays {
            source: self.source.into_pyarray(py).unbind(),
            receiver: self.receiver.into_pyarray(py).unbind(),
            path: self.path.into_pyarray(py).unbind(),
            status: self.status.into_pyarray(py).unbind(),
            time: self.time.into_pyarray(py).unbind(),
            points: Array3::from_shape_vec((n, width, 2), self.points)
                .expect("width points a ray")
                .into_pyarray(py)
                .unbind(),
            num_points: self.num_points.into_pyarray(py).unbind(),
            media: Array2::from_shape_vec((n, width - 1), self.media)
                .expect("width − 1 legs a ray")
                .into_pyarray(py)
                .unbind(),
            iterations: self.iterations.into_pyarray(py).unbind(),
            residual: self.residual.into_pyarray(py).unbind(),
            scene: Mutex::new(None),
            reasons: Mutex::new(Reasons {
                codes: self.reason,
                any: self.any_reason.into_inner(),
                interfaces: interface_names(scene),
                whys,
            }),
            status_names: status_names(),
            path_names: scene.paths().iter().map(|p| p.name.clone()).collect(),
            media_names: scene.media().iter().map(|m| m.name.clone()).collect(),
            arrival,
            kink,
            complete,
            quantities,
        }
    }
}

/// The entries of every stationary path, in the library's order of the written output (one
/// per stationary path, and one `no_path` or `not_converged` per triple that has none).
pub(crate) fn stationary_table(scene: &Scene, rays: &StationaryRays) -> Table {
    let n = rays.entries();
    let mut table = Table::new(n, width(scene), Schema::of(scene));
    let mut columns = StationaryColumns {
        arrival: Vec::with_capacity(n),
        kink: Vec::with_capacity(n),
        complete: Vec::with_capacity(n),
    };
    let mut rows = table.rows();
    for (row, e) in rays.entries_in_order(scene).enumerate() {
        let triple = [e.source, e.receiver, e.path];
        let media = e.media.map(|m| m.iter().copied());
        rows.write(row, scene, triple, &e.record, e.points, media);
        rows.write_quantities(row, &Entry::of_stationary(&e));
        columns.arrival.push(e.arrival as i64);
        columns.kink.push(kink_name(e.kink));
        columns.complete.push(e.complete);
    }
    table.stationary = Some(columns);
    table
}

/// The rays of path `path` between `sources[i]` and `receivers[i]`, solved in parallel (each
/// task with its own workspace).
pub(crate) fn pairs_table(
    tracer: &Tracer,
    sources: &[Point],
    receivers: &[Point],
    path: usize,
    run: &Run,
) -> Table {
    let scene = tracer.scene();
    let mut table = Table::new(sources.len(), width(scene), Schema::of(scene));
    fill_parallel(table.rows(), 0, &Workspace::new, &|ws, first, rows| {
        // Once stopped, the rest is skipped (the caller raises).
        let n = rows.time.len() as u64;
        if !run.keep_going(Progress::items(n)) {
            return;
        }
        run.within(|| {
            for row in 0..rows.time.len() {
                let i = first + row;
                let record = tracer.solve(sources[i], receivers[i], path, ws);
                let media = Some(ws.media().iter().copied());
                rows.write(row, scene, [i, i, path], &record, ws.points(), media);
                if rows.has_quantities() {
                    rows.write_quantities(row, &Entry::solved(tracer, path, &record, ws));
                }
            }
        });
    });
    table
}

/// The most points of any path of `scene` (at least 2: the source and the receiver).
pub(crate) fn width(scene: &Scene) -> usize {
    scene
        .paths()
        .iter()
        .map(|p| p.steps.len() + 2)
        .max()
        .unwrap_or(2)
}
