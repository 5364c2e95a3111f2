//! The rows of a `Rays` as a batch's sink: each worker writes a ray's row right after solving
//! it.

use eigenray::{
    Point, RayRecord, Scene,
    sink::{BatchSink, RaySlot},
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
        let legs = self.scene.paths()[at.path].steps.len() + 1;
        // Leg media are known when there is one per leg (as a `Batch` keeps them).
        let media = (media.len() == legs).then(|| media.iter().copied());
        let row = at.block * self.paths + at.path;
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
        let row = at.block * self.paths + at.path;
        let triple = [at.source, at.receiver, at.path];
        self.rows.write_one(row, triple, record, points, media);
    }
}
