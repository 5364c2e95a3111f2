//! Rows of a `Rays`' arrays: one slice per column, written one ray at a time (by a batch's
//! workers, in parallel), split for parallel fills.

use std::sync::atomic::{AtomicBool, Ordering};

use eigenray::output::columns::Entry;
use eigenray::{Point, RayRecord, Reason, Scene};

use crate::columns::QuantityRows;
use crate::convert::status_code;

/// Rows of a `Table`: one slice per column, all of the same rows.
pub(crate) struct Rows<'a> {
    /// Points a row.
    pub(crate) width: usize,
    /// Source index of each ray.
    pub(crate) source: &'a mut [i64],
    /// Receiver index of each ray.
    pub(crate) receiver: &'a mut [i64],
    /// Path index of each ray.
    pub(crate) path: &'a mut [i64],
    /// Status code of each ray.
    pub(crate) status: &'a mut [u8],
    /// Travel time of each ray.
    pub(crate) time: &'a mut [f64],
    /// `width` points a row, `(x, y)` each.
    pub(crate) points: &'a mut [f64],
    /// The points of each ray's path.
    pub(crate) num_points: &'a mut [i64],
    /// `width − 1` leg media a row.
    pub(crate) media: &'a mut [i32],
    /// Solver iterations of each ray.
    pub(crate) iterations: &'a mut [u32],
    /// Final relative residual of each ray.
    pub(crate) residual: &'a mut [f64],
    /// Written only where a ray has a reason: every entry is `None` before.
    pub(crate) reason: &'a mut [Option<Reason>],
    /// Set when a reason is written.
    pub(crate) any_reason: &'a AtomicBool,
    /// The columns of the quantities the scene asks for (`None` when it asks for none).
    pub(crate) quantities: Option<QuantityRows<'a>>,
}

/// Rows written by one task of a parallel fill.
const ROWS_PER_TASK: usize = 4096;

/// Fills `rows` in parallel: `write(state, first, rows)` writes the rows of rays `first..`
/// (tasks of at most `ROWS_PER_TASK` rows), each task with its own `state` from `init` (a
/// workspace, say).
pub(crate) fn fill_parallel<S>(
    rows: Rows<'_>,
    first: usize,
    init: &(impl Fn() -> S + Sync),
    write: &(impl Fn(&mut S, usize, &mut Rows<'_>) + Sync),
) {
    let n = rows.time.len();
    if n <= ROWS_PER_TASK {
        let mut rows = rows;
        write(&mut init(), first, &mut rows);
    } else {
        let (a, b) = rows.split_at(n / 2);
        rayon::join(
            || fill_parallel(a, first, init, write),
            || fill_parallel(b, first + n / 2, init, write),
        );
    }
}

impl Rows<'_> {
    /// The rows before `k` and from `k` on.
    pub(crate) fn split_at(self, k: usize) -> (Self, Self) {
        let w = self.width;
        let (source, source_b) = self.source.split_at_mut(k);
        let (receiver, receiver_b) = self.receiver.split_at_mut(k);
        let (path, path_b) = self.path.split_at_mut(k);
        let (status, status_b) = self.status.split_at_mut(k);
        let (time, time_b) = self.time.split_at_mut(k);
        let (points, points_b) = self.points.split_at_mut(k * w * 2);
        let (num_points, num_points_b) = self.num_points.split_at_mut(k);
        let (media, media_b) = self.media.split_at_mut(k * (w - 1));
        let (iterations, iterations_b) = self.iterations.split_at_mut(k);
        let (residual, residual_b) = self.residual.split_at_mut(k);
        let (reason, reason_b) = self.reason.split_at_mut(k);
        let any_reason = self.any_reason;
        let (quantities, quantities_b) = match self.quantities.map(|a| a.split_at(k)) {
            Some((a, b)) => (Some(a), Some(b)),
            None => (None, None),
        };
        (
            Rows {
                width: w,
                source,
                receiver,
                path,
                status,
                time,
                points,
                num_points,
                media,
                iterations,
                residual,
                reason,
                any_reason,
                quantities,
            },
            Rows {
                width: w,
                source: source_b,
                receiver: receiver_b,
                path: path_b,
                status: status_b,
                time: time_b,
                points: points_b,
                num_points: num_points_b,
                media: media_b,
                iterations: iterations_b,
                residual: residual_b,
                reason: reason_b,
                any_reason,
                quantities: quantities_b,
            },
        )
    }

    /// Row `i`: ray `triple` with its record, points (read only when it has a time) and leg
    /// media (`None`, or fewer than its legs, where unknown: −1).
    #[allow(clippy::too_many_arguments, reason = "the parts of one ray")]
    #[inline]
    pub(crate) fn write(
        &mut self,
        i: usize,
        scene: &Scene,
        triple: [usize; 3],
        record: &RayRecord,
        points: &[Point],
        media: Option<impl Iterator<Item = usize>>,
    ) {
        let own = scene.paths()[triple[2]].steps.len() + 2;
        self.write_scalars(i, triple, record, own);
        let w = self.width;
        let row = &mut self.points[i * w * 2..(i + 1) * w * 2];
        let mut written = 0;
        if record.status.has_time() && points.len() == own {
            for (xy, p) in row.chunks_exact_mut(2).zip(points) {
                xy.copy_from_slice(&[p.x, p.y]);
            }
            written = 2 * own;
        }
        if written < row.len() {
            row[written..].fill(f64::NAN);
        }
        let legs = &mut self.media[i * (w - 1)..(i + 1) * (w - 1)];
        let mut written = 0;
        if let Some(media) = media {
            for (leg, m) in legs.iter_mut().zip(media) {
                *leg = leg_code(m);
                written += 1;
            }
        }
        if written < legs.len() {
            legs[written..].fill(-1);
        }
    }

    /// [`write`](Self::write) for a ray of one interaction (three points) whose two leg media
    /// are known: without loops.
    #[inline(always)]
    pub(crate) fn write_one(
        &mut self,
        i: usize,
        triple: [usize; 3],
        record: &RayRecord,
        points: &[Point; 3],
        media: [usize; 2],
    ) {
        self.write_scalars(i, triple, record, 3);
        let w = self.width;
        let (row, rest) = self.points[i * w * 2..(i + 1) * w * 2].split_at_mut(6);
        if record.status.has_time() {
            let [a, b, c] = points;
            row.copy_from_slice(&[a.x, a.y, b.x, b.y, c.x, c.y]);
        } else {
            row.fill(f64::NAN);
        }
        let (legs, rest_legs) = self.media[i * (w - 1)..(i + 1) * (w - 1)].split_at_mut(2);
        legs.copy_from_slice(&[leg_code(media[0]), leg_code(media[1])]);
        // (Only when other paths have more points: a `fill` of nothing still calls memset.)
        if w > 3 {
            rest.fill(f64::NAN);
            rest_legs.fill(-1);
        }
    }

    /// Whether the rows have the columns of a quantity (the scene asks for one).
    #[inline(always)]
    pub(crate) fn has_quantities(&self) -> bool {
        self.quantities.is_some()
    }

    /// The quantities of row `i`, when the rows have their columns.
    #[inline]
    pub(crate) fn write_quantities(&mut self, i: usize, entry: &Entry<'_>) {
        if let Some(columns) = &mut self.quantities {
            columns.write(i, entry);
        }
    }

    /// The one-number columns of row `i`, for a ray of `own` points.
    #[inline(always)]
    fn write_scalars(&mut self, i: usize, triple: [usize; 3], record: &RayRecord, own: usize) {
        let [source, receiver, path] = triple;
        self.source[i] = source as i64;
        self.receiver[i] = receiver as i64;
        self.path[i] = path as i64;
        self.status[i] = status_code(record.status);
        self.time[i] = record.time;
        self.num_points[i] = own as i64;
        self.iterations[i] = record.iterations;
        self.residual[i] = record.residual;
        if let Some(reason) = record.reason {
            self.reason[i] = Some(reason);
            // (Read first: the flag's cache line stays shared between the workers.)
            if !self.any_reason.load(Ordering::Relaxed) {
                self.any_reason.store(true, Ordering::Relaxed);
            }
        }
    }
}

/// The `media` entry of a leg in medium `m`.
#[inline]
fn leg_code(m: usize) -> i32 {
    i32::try_from(m).unwrap_or(-1)
}
