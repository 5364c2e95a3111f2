//! The rows of a `Rays` as a batch's sink: each worker writes a ray's row right after solving
//! it, and with the columns of quantities (the amplitude) the ray's quantities too.

use eigenray::output::columns::Entry;
use eigenray::{
    Point, RayRecord, Scene, Tracer,
    batch::{BatchSink, RaySlot},
};

use crate::rows::Rows;

/// The rows of `Rays` as a batch's sink: the worker that solves a ray writes its row right
/// after solving it (the library's `Tracer::trace_batch_to`), so that numpy's arrays are
/// filled in the batch's own parallel pass.
pub(crate) struct RowSink<'a> {
    /// The rays' scene.
    scene: &'a Scene,
    /// Paths (rays per block).
    paths: usize,
    /// The rows, one per ray of the batch (or of its part).
    rows: Rows<'a>,
}

impl<'a> RowSink<'a> {
    /// The sink of `rows`, the rays of `scene`.
    pub(crate) fn new(scene: &'a Scene, rows: Rows<'a>) -> Self {
        RowSink {
            scene,
            paths: scene.paths().len(),
            rows,
        }
    }

    /// Whether its rows have the columns of a quantity.
    pub(crate) fn has_quantities(&self) -> bool {
        self.rows.has_quantities()
    }

    /// The row of the ray at `at`.
    #[inline(always)]
    fn row(&self, at: RaySlot) -> usize {
        at.block * self.paths + at.path
    }

    /// The leg media of a ray of path `path` when known (one per leg, as a `Batch` keeps them).
    #[inline(always)]
    fn known<'m>(&self, path: usize, media: &'m [usize]) -> Option<&'m [usize]> {
        let legs = self.scene.paths()[path].steps.len() + 1;
        (media.len() == legs).then_some(media)
    }
}

impl BatchSink for RowSink<'_> {
    fn blocks(&self) -> usize {
        self.rows.time.len().checked_div(self.paths).unwrap_or(0)
    }

    fn split_at(self, blocks: usize) -> (Self, Self) {
        let (a, b) = self.rows.split_at(blocks * self.paths);
        let (scene, paths) = (self.scene, self.paths);
        (
            RowSink {
                scene,
                paths,
                rows: a,
            },
            RowSink {
                scene,
                paths,
                rows: b,
            },
        )
    }

    #[inline]
    fn write(&mut self, at: RaySlot, record: &RayRecord, points: &[Point], media: &[usize]) {
        let media = self.known(at.path, media).map(|m| m.iter().copied());
        let row = self.row(at);
        let triple = [at.source, at.receiver, at.path];
        self.rows
            .write(row, self.scene, triple, record, points, media);
    }

    #[inline(always)]
    fn write_one(
        &mut self,
        at: RaySlot,
        record: &RayRecord,
        points: &[Point; 3],
        media: [usize; 2],
    ) {
        let row = self.row(at);
        let triple = [at.source, at.receiver, at.path];
        self.rows.write_one(row, triple, record, points, media);
    }
}

/// [`RowSink`] for rows with the columns of quantities: the worker that writes a ray's row
/// computes its quantities from the points and leg media it writes (the amplitude:
/// `Tracer::amplitude_of`, the function a `Batch` calls after its solve: the same numbers,
/// without a second pass). A sink of its own, so that a batch without quantities runs the
/// plain sink's code, unchanged.
pub(crate) struct QuantitySink<'a> {
    /// The rays' tracer.
    tracer: &'a Tracer,
    /// The rows, with the columns of quantities.
    rows: RowSink<'a>,
}

impl<'a> QuantitySink<'a> {
    /// The sink of `rows` (with the columns of quantities), the rays of `tracer`.
    pub(crate) fn new(tracer: &'a Tracer, rows: RowSink<'a>) -> Self {
        QuantitySink { tracer, rows }
    }

    /// The quantities of the ray of path `path` in row `row`, from its record, points and leg
    /// media (`&[]` where unknown).
    #[inline(always)]
    fn quantities(
        &mut self,
        row: usize,
        path: usize,
        record: &RayRecord,
        points: &[Point],
        media: &[usize],
    ) {
        let steps = &self.rows.scene.paths()[path].steps;
        let entry = Entry::computed(self.tracer, steps, record.status, points, media);
        self.rows.rows.write_quantities(row, &entry);
    }
}

impl BatchSink for QuantitySink<'_> {
    fn blocks(&self) -> usize {
        self.rows.blocks()
    }

    fn split_at(self, blocks: usize) -> (Self, Self) {
        let (a, b) = self.rows.split_at(blocks);
        let tracer = self.tracer;
        (
            QuantitySink { tracer, rows: a },
            QuantitySink { tracer, rows: b },
        )
    }

    #[inline]
    fn write(&mut self, at: RaySlot, record: &RayRecord, points: &[Point], media: &[usize]) {
        self.rows.write(at, record, points, media);
        let known = self.rows.known(at.path, media).unwrap_or(&[]);
        self.quantities(self.rows.row(at), at.path, record, points, known);
    }

    #[inline(always)]
    fn write_one(
        &mut self,
        at: RaySlot,
        record: &RayRecord,
        points: &[Point; 3],
        media: [usize; 2],
    ) {
        self.rows.write_one(at, record, points, media);
        self.quantities(self.rows.row(at), at.path, record, points, &media);
    }
}
