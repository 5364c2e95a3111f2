//! The rows of a `Rays` as a batch's sink: each worker writes a ray's row (and its amplitude,
//! when the scene asks for amplitudes) right after solving it.

use eigenray::{
    Point, RayRecord, Scene, Tracer,
    sink::{BatchSink, RaySlot},
};

use crate::rows::Rows;

/// The rows of `Rays` as a batch's sink: the worker that solves a ray writes its row right
/// after solving it (the library's `Tracer::trace_batch_to`), so that numpy's arrays are
/// filled in the batch's own parallel pass. With amplitude columns, the worker computes the
/// ray's amplitude from the points and leg media it writes (`Tracer::amplitude_of`, the
/// function a `Batch` calls after its solve: the same numbers, without a second pass).
pub(crate) struct RowSink<'a> {
    /// The rays' tracer.
    tracer: &'a Tracer,
    /// Its scene.
    scene: &'a Scene,
    /// Paths (rays per block).
    paths: usize,
    /// The rows, one per ray of the batch (or of its part).
    rows: Rows<'a>,
}

impl<'a> RowSink<'a> {
    /// The sink of `rows`, the rays of `tracer`.
    pub(crate) fn new(tracer: &'a Tracer, rows: Rows<'a>) -> Self {
        let scene = tracer.scene();
        RowSink {
            tracer,
            scene,
            paths: scene.paths().len(),
            rows,
        }
    }

    /// The amplitude of the ray of path `path` in row `row` (its record, points and leg
    /// media), when the rows have amplitude columns.
    #[inline(always)]
    fn amplitude(
        &mut self,
        row: usize,
        path: usize,
        record: &RayRecord,
        points: &[Point],
        media: &[usize],
    ) {
        if self.rows.has_amplitudes() {
            let steps = &self.scene.paths()[path].steps;
            let a = self
                .tracer
                .amplitude_of(steps, record.status, points, media);
            self.rows.write_amplitude(row, a.as_ref());
        }
    }
}

impl BatchSink for RowSink<'_> {
    fn blocks(&self) -> usize {
        self.rows.time.len().checked_div(self.paths).unwrap_or(0)
    }

    fn split_at(self, blocks: usize) -> (Self, Self) {
        let (a, b) = self.rows.split_at(blocks * self.paths);
        let (tracer, scene, paths) = (self.tracer, self.scene, self.paths);
        (
            RowSink {
                tracer,
                scene,
                paths,
                rows: a,
            },
            RowSink {
                tracer,
                scene,
                paths,
                rows: b,
            },
        )
    }

    #[inline]
    fn write(&mut self, at: RaySlot, record: &RayRecord, points: &[Point], media: &[usize]) {
        let legs = self.scene.paths()[at.path].steps.len() + 1;
        // Leg media are known when there is one per leg (as a `Batch` keeps them).
        let known = (media.len() == legs).then_some(media);
        let row = at.block * self.paths + at.path;
        let triple = [at.source, at.receiver, at.path];
        let known_media = known.map(|m| m.iter().copied());
        self.rows
            .write(row, self.scene, triple, record, points, known_media);
        self.amplitude(row, at.path, record, points, known.unwrap_or(&[]));
    }

    #[inline(always)]
    fn write_one(
        &mut self,
        at: RaySlot,
        record: &RayRecord,
        points: &[Point; 3],
        media: [usize; 2],
    ) {
        let row = at.block * self.paths + at.path;
        let triple = [at.source, at.receiver, at.path];
        self.rows.write_one(row, triple, record, points, media);
        self.amplitude(row, at.path, record, points, &media);
    }
}
