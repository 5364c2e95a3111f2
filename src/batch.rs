//! Batches: every ray of a scene in parallel, in ray order, in flat storage, with warm starts.

use rayon::prelude::*;

use crate::geom::{Point, Vec2};
use crate::problem::{Frame, coord};
use crate::scene::SceneError;
use crate::solver::{
    OneStepNewton, Outcome, ReceiverSensitivity, one_step_sensitivity, receiver_sensitivity,
};
use crate::trace::{
    OneStepPath, PathPlan, Ray, RayRecord, Start, Status, Tracer, Workspace, flat_status,
    given_param,
};

/// How to run a batch.
#[derive(Clone, Copy)]
pub struct BatchOptions<'a> {
    /// Solve receivers in a spatial order (a Morton curve over their positions) and start each
    /// ray from the previous receiver's converged solution of the same path when that receiver
    /// is near (closer than a quarter of the source–receiver distance) instead of the default
    /// initial guess: that solution moved to first order in the receiver's displacement (one
    /// tridiagonal solve with the converged Hessian, a continuation step), which typically
    /// leaves one Newton step to do. A warm-started ray that does not converge is solved again
    /// from the default start, so warm starts never lose a ray the default start finds.
    /// Rays whose default start is already the solution (off a flat mirror, through flat
    /// layers) and single refractions at a one-segment interface (solved by a dedicated
    /// kernel, whose own start costs less than a warm start's bookkeeping) are not
    /// warm-started: they come out bit for bit as one by one. Where a path's step sequence
    /// holds several stationary paths (an interface of several segments: a zigzag or bent
    /// floor, a bent mirror), a warm start that converges may reach another of them than the
    /// default start; turn warm starts off for the very rays of one-by-one solving.
    pub warm_start: bool,
    /// Receivers per work unit (one workspace and one warm-start chain per unit).
    pub chunk: usize,
    /// Called from the worker threads with the number of rays each finished unit solved.
    pub progress: Option<&'a (dyn Fn(usize) + Sync)>,
}

impl Default for BatchOptions<'_> {
    fn default() -> Self {
        BatchOptions {
            warm_start: true,
            chunk: 256,
            progress: None,
        }
    }
}

/// Every ray of a scene, in ray order (source-major, then receiver, then path), in flat
/// arrays: one record per ray and, per (source, receiver) pair, one block holding the points
/// (and leg media) of all paths.
///
/// ```
/// use eigenray::{BatchOptions, Scene, Status, Tracer};
/// let scene = Scene::from_spec(&eigenray::demo::air_water(100, 7)).unwrap();
/// let batch = Tracer::new(&scene).unwrap().trace_batch(&BatchOptions::default());
/// assert_eq!(batch.len(), 100);
/// assert!((0..batch.len()).all(|i| batch.record(i).status == Status::Converged));
/// assert_eq!(batch.points(0).len(), 3); // source, interaction, receiver
/// ```
#[derive(Clone, Debug, Default)]
pub struct Batch {
    receivers: usize,
    paths: usize,
    records: Vec<RayRecord>,
    points: Vec<Point>,
    media: Vec<u32>,
    /// Offset of each path's points within a block, and the block size (last entry).
    point_offsets: Vec<usize>,
    /// Offset of each path's leg media within a block, and the block size (last entry).
    media_offsets: Vec<usize>,
    /// Results in solving order when that is not ray order (kept for reuse).
    spatial: Option<Box<Arrays>>,
}

/// One ray of a [`Batch`], as [`Batch::rays`] walks them.
#[derive(Clone, Copy, Debug)]
pub struct BatchRay<'a> {
    /// Its index in ray order.
    pub index: usize,
    /// Source index.
    pub source: usize,
    /// Receiver index.
    pub receiver: usize,
    /// Path index.
    pub path: usize,
    /// Its record.
    pub record: &'a RayRecord,
    /// Source, interaction points and receiver (see [`Batch::points`]).
    pub points: &'a [Point],
    legs: &'a [u32],
}

impl BatchRay<'_> {
    /// Leg media (indices into [`crate::Scene::media`]), when known (see [`Batch::media`]).
    pub fn media(&self) -> Option<impl Iterator<Item = usize> + '_> {
        (self.legs.first() != Some(&NO_MEDIUM)).then(|| self.legs.iter().map(|&m| m as usize))
    }
}

/// The walk of [`Batch::rays`].
#[derive(Clone, Debug)]
pub struct BatchRays<'a> {
    batch: &'a Batch,
    next: usize,
    end: usize,
    source: usize,
    receiver: usize,
    path: usize,
    /// Where the current (source, receiver) block starts in the points and media arrays.
    points_base: usize,
    media_base: usize,
}

impl<'a> Iterator for BatchRays<'a> {
    type Item = BatchRay<'a>;

    fn next(&mut self) -> Option<BatchRay<'a>> {
        if self.next >= self.end {
            return None;
        }
        let b = self.batch;
        let (p, po, mo) = (self.path, &b.point_offsets, &b.media_offsets);
        let ray = BatchRay {
            index: self.next,
            source: self.source,
            receiver: self.receiver,
            path: p,
            record: &b.records[self.next],
            points: &b.points[self.points_base + po[p]..self.points_base + po[p + 1]],
            legs: &b.media[self.media_base + mo[p]..self.media_base + mo[p + 1]],
        };
        self.next += 1;
        self.path += 1;
        if self.path == b.paths {
            self.path = 0;
            self.points_base += po[b.paths];
            self.media_base += mo[b.paths];
            self.receiver += 1;
            if self.receiver == b.receivers {
                self.receiver = 0;
                self.source += 1;
            }
        }
        Some(ray)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.end - self.next;
        (left, Some(left))
    }
}

impl ExactSizeIterator for BatchRays<'_> {}

/// A batch's three arrays: records, points, leg media.
type Arrays = (Vec<RayRecord>, Vec<Point>, Vec<u32>);

/// Marks a leg medium that was not determined.
const NO_MEDIUM: u32 = u32::MAX;

impl Batch {
    /// Number of rays.
    pub fn len(&self) -> usize {
        self.records.len()
    }
    /// Whether there are no rays.
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }
    /// The record of ray `ray`.
    pub fn record(&self, ray: usize) -> &RayRecord {
        &self.records[ray]
    }
    /// All records, in ray order.
    pub fn records(&self) -> &[RayRecord] {
        &self.records
    }
    /// `(source, receiver, path)` of ray `ray`.
    pub fn triple(&self, ray: usize) -> (usize, usize, usize) {
        let p = ray % self.paths;
        let r = (ray / self.paths) % self.receivers;
        (ray / (self.paths * self.receivers), r, p)
    }
    fn block(&self, ray: usize) -> (usize, usize) {
        (ray / self.paths, ray % self.paths)
    }
    /// Source, interaction points and receiver of ray `ray` (NaN when it has no time).
    pub fn points(&self, ray: usize) -> &[Point] {
        let (b, p) = self.block(ray);
        let base = b * self.point_offsets[self.paths];
        &self.points[base + self.point_offsets[p]..base + self.point_offsets[p + 1]]
    }
    /// Leg media of ray `ray` (indices into [`crate::Scene::media`]), when known.
    pub fn media(&self, ray: usize) -> Option<impl Iterator<Item = usize> + '_> {
        let (b, p) = self.block(ray);
        let base = b * self.media_offsets[self.paths];
        let legs = &self.media[base + self.media_offsets[p]..base + self.media_offsets[p + 1]];
        (legs.first() != Some(&NO_MEDIUM)).then(|| legs.iter().map(|&m| m as usize))
    }
    /// Rays `range` of the batch in ray order, each with its indices, record, points and leg
    /// media: a walk that steps from one ray to the next without the divisions that
    /// [`triple`](Self::triple), [`points`](Self::points) and [`media`](Self::media) take per
    /// call (for converting a whole batch, in parallel over ranges).
    ///
    /// # Panics
    /// If `range` reaches beyond the batch.
    pub fn rays(&self, range: std::ops::Range<usize>) -> BatchRays<'_> {
        assert!(range.end <= self.len(), "rays beyond the batch");
        let paths = self.paths.max(1);
        let block = range.start / paths;
        BatchRays {
            batch: self,
            next: range.start,
            end: range.end,
            source: block / self.receivers.max(1),
            receiver: block % self.receivers.max(1),
            path: range.start % paths,
            points_base: block * self.point_offsets.last().copied().unwrap_or(0),
            media_base: block * self.media_offsets.last().copied().unwrap_or(0),
        }
    }
    /// Total solver iterations over all rays.
    pub fn total_iterations(&self) -> u64 {
        self.records.iter().map(|r| r.iterations as u64).sum()
    }
    /// Ray `ray` as an owned [`Ray`].
    pub fn ray(&self, ray: usize) -> Ray {
        let rec = self.records[ray];
        let (source, receiver, path) = self.triple(ray);
        let has = rec.status.has_time();
        Ray {
            source,
            receiver,
            path,
            status: rec.status,
            time: rec.time,
            points: if has {
                self.points(ray).to_vec()
            } else {
                Vec::new()
            },
            iterations: rec.iterations as usize,
            residual: rec.residual,
            media: self.media(ray).map(|m| m.collect()).unwrap_or_default(),
            reason: rec.reason,
        }
    }
    /// Every ray as an owned [`Ray`], in ray order.
    pub fn to_rays(&self) -> Vec<Ray> {
        (0..self.len()).map(|i| self.ray(i)).collect()
    }
    /// Bytes held by the batch's arrays.
    pub fn memory_bytes(&self) -> usize {
        let bytes = |r: &Vec<RayRecord>, p: &Vec<Point>, m: &Vec<u32>| {
            r.capacity() * std::mem::size_of::<RayRecord>()
                + p.capacity() * std::mem::size_of::<Point>()
                + m.capacity() * std::mem::size_of::<u32>()
        };
        bytes(&self.records, &self.points, &self.media)
            + self
                .spatial
                .as_deref()
                .map_or(0, |(r, p, m)| bytes(r, p, m))
    }
}

/// Interleaves the bits of two 32-bit integers (Morton / Z-order code).
fn morton(x: u32, y: u32) -> u64 {
    fn spread(v: u32) -> u64 {
        let mut v = v as u64;
        v = (v | (v << 16)) & 0x0000_FFFF_0000_FFFF;
        v = (v | (v << 8)) & 0x00FF_00FF_00FF_00FF;
        v = (v | (v << 4)) & 0x0F0F_0F0F_0F0F_0F0F;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        v = (v | (v << 1)) & 0x5555_5555_5555_5555;
        v
    }
    spread(x) | (spread(y) << 1)
}

/// The warm-start state of one worker: per path, the last converged solution and how it moves
/// with the receiver ([`receiver_sensitivity`]), to predict the next receiver's solution.
struct Warm {
    /// Parameters of the last converged solution, per path (at the paths' parameter offsets).
    params: Vec<f64>,
    /// Their sensitivity `z` to the last residual.
    z: Vec<f64>,
    /// Per path: `∂rₖ₋₁/∂R`, or `None` (no prediction, the parameters as they are).
    g: Vec<Option<Vec2>>,
    /// The predicted start.
    guess: Vec<f64>,
    /// Scratch for the sensitivity solve.
    unit: Vec<f64>,
    cp: Vec<f64>,
}

impl Warm {
    fn new(params: usize, paths: usize) -> Warm {
        Warm {
            params: vec![0.0; params],
            z: vec![0.0; params],
            g: vec![None; paths],
            guess: vec![0.0; params],
            unit: vec![0.0; params],
            cp: vec![0.0; params],
        }
    }

    /// Keeps the converged solution of path `p` in `ws` and its sensitivity.
    fn store(&mut self, p: usize, range: std::ops::Range<usize>, ws: &Workspace) {
        let k = range.len();
        self.params[range.clone()].copy_from_slice(ws.parameters());
        self.g[p] = receiver_sensitivity(
            &ws.newton,
            &ws.ray.slowness,
            &mut self.z[range],
            &mut self.unit[..k],
            &mut self.cp[..k],
        );
    }

    /// [`store`](Self::store) for a one-interaction path whose solution `s` was solved without
    /// a workspace, with its sensitivity (`one_step_sensitivity`).
    fn store_one(&mut self, p: usize, at: usize, s: f64, sensitivity: Option<ReceiverSensitivity>) {
        self.params[at] = s;
        (self.z[at], self.g[p]) = match sensitivity {
            Some(sens) => (sens.z, Some(sens.g)),
            None => (0.0, None),
        };
    }

    /// The predicted start of path `p` for a receiver `moved` from the last one: the last
    /// solution moved by `−z (g · moved)` (a first-order continuation step).
    fn predict(&mut self, p: usize, range: std::ops::Range<usize>, moved: Vec2) -> &[f64] {
        let guess = &mut self.guess[range.clone()];
        let (params, z) = (&self.params[range.clone()], &self.z[range]);
        match self.g[p] {
            Some(g) => {
                let shift = g.dot(moved);
                for ((out, &s), &zi) in guess.iter_mut().zip(params).zip(z) {
                    *out = s - zi * shift;
                }
            }
            None => guess.copy_from_slice(params),
        }
        guess
    }
}

/// Gives `v` length `n`. Elements it already has keep their values (the caller overwrites
/// them all); new ones are `value`, written by the rayon pool (the first touch of a batch's
/// hundreds of megabytes is then not a serial step before the parallel solve).
fn sized<T: Copy + Send + Sync>(v: &mut Vec<T>, n: usize, value: T) {
    if v.len() >= n {
        v.truncate(n);
        return;
    }
    let have = v.len();
    v.par_extend(rayon::iter::repeat_n(value, n - have));
}

/// Whether receiver `here` is near receiver `last`: closer than a quarter of its distance to
/// `source` (compared squared: no square roots).
#[inline]
fn near(here: Point, last: Point, source: Point) -> bool {
    let (a, b) = (here - last, here - source);
    a.dot(a) <= 0.0625 * b.dot(b)
}

/// Whether at least 90 % of consecutive receivers are near each other (closer than a quarter
/// of the distance to `source`), so that warm starts work in the given order.
fn coherent(receivers: &[Point], source: Point) -> bool {
    let near = receivers
        .windows(2)
        .filter(|w| near(w[1], w[0], source))
        .count();
    near * 10 >= receivers.len().saturating_sub(1) * 9
}

/// Receiver indices sorted along a Morton curve over their bounding box.
fn spatial_order(points: &[Point]) -> Vec<usize> {
    let bbox = crate::geom::Aabb::around(points);
    let (w, h) = (
        (bbox.max.x - bbox.min.x).max(f64::MIN_POSITIVE),
        (bbox.max.y - bbox.min.y).max(f64::MIN_POSITIVE),
    );
    let q = |v: f64| (v.clamp(0.0, 1.0) * 65535.0) as u32;
    let mut keyed: Vec<(u64, usize)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            (
                morton(q((p.x - bbox.min.x) / w), q((p.y - bbox.min.y) / h)),
                i,
            )
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

impl Tracer {
    /// [`trace_batch`](Self::trace_batch), with an error instead of an abort when the
    /// batch's arrays cannot be allocated (a scene of more rays than the machine can hold):
    /// the memory is reserved before any ray is solved.
    ///
    /// ```
    /// use eigenray::{BatchOptions, Scene, Tracer};
    /// let scene = Scene::from_spec(&eigenray::demo::air_water(100, 7)).unwrap();
    /// let batch = Tracer::new(&scene).unwrap().try_trace_batch(&BatchOptions::default()).unwrap();
    /// assert_eq!(batch.len(), 100);
    /// ```
    ///
    /// # Errors
    /// `paths` (the batch's size: sources × receivers × paths), saying how many bytes it
    /// needs.
    pub fn try_trace_batch(&self, opts: &BatchOptions) -> Result<Batch, SceneError> {
        let mut batch = Batch::default();
        self.try_trace_batch_into(opts, &mut batch)?;
        Ok(batch)
    }

    /// [`trace_batch_into`](Self::trace_batch_into), with an error instead of an abort when
    /// the batch's arrays cannot be allocated (see [`try_trace_batch`](Self::try_trace_batch)).
    ///
    /// # Errors
    /// As [`try_trace_batch`](Self::try_trace_batch).
    pub fn try_trace_batch_into(
        &self,
        opts: &BatchOptions,
        batch: &mut Batch,
    ) -> Result<(), SceneError> {
        let scene = self.scene();
        let size = scene.batch_size();
        // Results in solving order as well when the receivers are put in a spatial order.
        let spatial = opts.warm_start
            && !scene.sources().is_empty()
            && !coherent(scene.receivers(), scene.sources()[0]);
        let needs =
            |records: &mut Vec<RayRecord>, points: &mut Vec<Point>, media: &mut Vec<u32>| {
                let grow = |have: usize, want: usize| want.saturating_sub(have);
                records
                    .try_reserve_exact(grow(records.len(), size.rays))
                    .and_then(|()| points.try_reserve_exact(grow(points.len(), size.points)))
                    .and_then(|()| media.try_reserve_exact(grow(media.len(), size.legs)))
            };
        let mut reserved = needs(&mut batch.records, &mut batch.points, &mut batch.media);
        if spatial && reserved.is_ok() {
            let arrays = batch.spatial.get_or_insert_with(Box::default);
            let (r, p, m) = &mut **arrays;
            reserved = needs(r, p, m);
        }
        if reserved.is_err() {
            let bytes = size
                .bytes(
                    std::mem::size_of::<RayRecord>(),
                    std::mem::size_of::<Point>(),
                    std::mem::size_of::<u32>(),
                )
                .and_then(|b| b.checked_mul(1 + usize::from(spatial)))
                .map_or("more than the address space holds".to_string(), |b| {
                    format!("{b} bytes")
                });
            return Err(SceneError::new(
                "paths",
                format!(
                    "a batch of {} rays needs {bytes} for its records, points and leg media, \
                     which cannot be allocated",
                    size.rays
                ),
            ));
        }
        self.trace_batch_into(opts, batch);
        Ok(())
    }

    /// Solves every ray of the scene in parallel (rayon, one workspace per work unit), with
    /// the same results as solving them one by one (up to the start each ray is solved from
    /// when `warm_start` is on), in ray order.
    ///
    /// # Panics
    /// Aborts when its arrays cannot be allocated (as every allocation in Rust does);
    /// [`try_trace_batch`](Self::try_trace_batch) returns an error instead.
    pub fn trace_batch(&self, opts: &BatchOptions) -> Batch {
        let mut batch = Batch::default();
        self.trace_batch_into(opts, &mut batch);
        batch
    }

    /// [`trace_batch`](Self::trace_batch) into an existing batch, reusing its memory: a tool
    /// that traces every layout change again keeps one `Batch` and pays for its hundreds of
    /// megabytes (page faults, first writes) only once. The results are the same as those of
    /// `trace_batch`.
    ///
    /// ```
    /// use eigenray::{Batch, BatchOptions, Scene, Tracer};
    /// let mut batch = Batch::default();
    /// for receivers in [100, 200] {
    ///     let scene = Scene::from_spec(&eigenray::demo::air_water(receivers, 7)).unwrap();
    ///     Tracer::new(&scene).unwrap().trace_batch_into(&BatchOptions::default(), &mut batch);
    ///     assert_eq!(batch.len(), receivers);
    /// }
    /// ```
    pub fn trace_batch_into(&self, opts: &BatchOptions, batch: &mut Batch) {
        let scene = self.scene();
        let (ns, nr, np) = (
            scene.sources().len(),
            scene.receivers().len(),
            scene.paths().len(),
        );
        let mut point_offsets = vec![0];
        let mut media_offsets = vec![0];
        let mut param_offsets = vec![0];
        for p in scene.paths() {
            let k = p.steps.len();
            point_offsets.push(point_offsets.last().unwrap() + k + 2);
            media_offsets.push(media_offsets.last().unwrap() + k + 1);
            param_offsets.push(param_offsets.last().unwrap() + k);
        }
        let (pts_block, media_block, params_block) =
            (point_offsets[np], media_offsets[np], param_offsets[np]);
        let blocks = ns * nr;
        batch.receivers = nr;
        batch.paths = np;
        batch.point_offsets = point_offsets;
        batch.media_offsets = media_offsets;
        if blocks == 0 || np == 0 {
            batch.records.clear();
            batch.points.clear();
            batch.media.clear();
            return;
        }
        // Receivers already in a coherent order (a grid, a survey line) keep it: sorting and
        // putting the rays back would cost more than the warm starts save.
        let order = if opts.warm_start && !coherent(scene.receivers(), scene.sources()[0]) {
            spatial_order(scene.receivers())
        } else {
            (0..nr).collect()
        };
        let identity = order.iter().enumerate().all(|(i, &r)| i == r);
        let chunk = opts.chunk.max(1);

        // Solve in (source, spatial position) block order; each unit is `chunk` blocks. Every
        // element is written by the solve: the arrays need only the right lengths.
        let mut spatial = if identity {
            None
        } else {
            Some(batch.spatial.take().unwrap_or_default())
        };
        let (records, points, media) = match spatial.as_deref_mut() {
            Some((r, p, m)) => (r, p, m),
            None => (&mut batch.records, &mut batch.points, &mut batch.media),
        };
        sized(records, blocks * np, RayRecord::default());
        sized(points, blocks * pts_block, Point::new(f64::NAN, f64::NAN));
        sized(media, blocks * media_block, NO_MEDIUM);
        let (po, mo) = (&batch.point_offsets, &batch.media_offsets);
        records
            .par_chunks_mut(chunk * np)
            .zip(points.par_chunks_mut(chunk * pts_block))
            .zip(media.par_chunks_mut(chunk * media_block))
            .enumerate()
            .for_each_init(
                || (Workspace::new(), Warm::new(params_block, np)),
                |(ws, warm), (unit, ((rec, pts), med))| {
                    let n = rec.len() / np;
                    let mut unit = Unit {
                        first: unit * chunk,
                        n,
                        nr,
                        order: &order,
                        warm_start: opts.warm_start,
                        rec,
                        pts,
                        med,
                        np,
                        pts_block,
                        media_block,
                        po,
                        mo,
                    };
                    // Path by path: each path's rays form one chain of warm starts.
                    for p in 0..np {
                        let params = param_offsets[p]..param_offsets[p + 1];
                        match self.plan_of(p) {
                            PathPlan::OneStep(one) | PathPlan::FlatRefraction(one, _) => {
                                self.one_step_chain(one, p, params.start, &mut unit, ws, warm)
                            }
                            _ => self.path_chain(p, params, &mut unit, ws, warm),
                        }
                    }
                    if let Some(progress) = opts.progress {
                        progress(n * np);
                    }
                },
            );

        let Some(spatial) = spatial else {
            return;
        };
        // Back from spatial order to ray order (a parallel gather of whole blocks).
        let (records, points, media) = &*spatial;
        sized(&mut batch.records, blocks * np, RayRecord::default());
        sized(
            &mut batch.points,
            blocks * pts_block,
            Point::new(f64::NAN, f64::NAN),
        );
        sized(&mut batch.media, blocks * media_block, NO_MEDIUM);
        let src_block = |block: usize, inverse: &[usize]| (block / nr) * nr + inverse[block % nr];
        let mut inverse = vec![0; nr];
        for (pos, &r) in order.iter().enumerate() {
            inverse[r] = pos;
        }
        batch
            .records
            .par_chunks_mut(np)
            .enumerate()
            .for_each(|(block, out)| {
                let from = src_block(block, &inverse) * np;
                out.copy_from_slice(&records[from..from + np]);
            });
        batch
            .points
            .par_chunks_mut(pts_block)
            .enumerate()
            .for_each(|(block, out)| {
                let from = src_block(block, &inverse) * pts_block;
                out.copy_from_slice(&points[from..from + pts_block]);
            });
        batch
            .media
            .par_chunks_mut(media_block)
            .enumerate()
            .for_each(|(block, out)| {
                let from = src_block(block, &inverse) * media_block;
                out.copy_from_slice(&media[from..from + media_block]);
            });
        batch.spatial = Some(spatial);
    }
}

/// One work unit of a batch: blocks `first..first + n` in solve order (a block is one
/// (source, receiver) pair, all paths) and their output.
struct Unit<'a> {
    first: usize,
    n: usize,
    /// Receivers per source.
    nr: usize,
    /// Solve order of the receivers.
    order: &'a [usize],
    warm_start: bool,
    rec: &'a mut [RayRecord],
    pts: &'a mut [Point],
    med: &'a mut [u32],
    /// Paths, points and leg media per block, and each path's offsets in a block.
    np: usize,
    pts_block: usize,
    media_block: usize,
    po: &'a [usize],
    mo: &'a [usize],
}

impl Unit<'_> {
    /// Source and receiver of block `b` of the unit.
    #[inline]
    fn ends(&self, b: usize) -> (usize, usize) {
        let block = self.first + b;
        (block / self.nr, self.order[block % self.nr])
    }

    /// Whether block `b` is the first of its source (the warm-start chain breaks there).
    #[inline]
    fn new_source(&self, b: usize) -> bool {
        (self.first + b) % self.nr == 0
    }

    /// Writes ray `s` of path `p` of block `b` with its points and leg media.
    #[inline]
    fn write(&mut self, b: usize, p: usize, s: &RayRecord, points: &[Point], media: &[usize]) {
        self.rec[b * self.np + p] = *s;
        let at = b * self.pts_block;
        let ray_points = &mut self.pts[at + self.po[p]..at + self.po[p + 1]];
        if s.status.has_time() {
            ray_points.copy_from_slice(points);
        } else {
            ray_points.fill(Point::new(f64::NAN, f64::NAN));
        }
        let at = b * self.media_block;
        let ray_media = &mut self.med[at + self.mo[p]..at + self.mo[p + 1]];
        if media.len() == ray_media.len() {
            for (dst, &m) in ray_media.iter_mut().zip(media) {
                *dst = m as u32;
            }
        } else {
            ray_media.fill(NO_MEDIUM);
        }
    }

    /// [`write`](Self::write) for a ray of one interaction with its leg media given: its
    /// three points and two media, copied without a loop.
    #[inline(always)]
    fn write_one(
        &mut self,
        b: usize,
        p: usize,
        s: &RayRecord,
        points: &[Point; 3],
        media: [usize; 2],
    ) {
        self.rec[b * self.np + p] = *s;
        let at = b * self.pts_block + self.po[p];
        let nan = Point::new(f64::NAN, f64::NAN);
        let points = if s.status.has_time() {
            *points
        } else {
            [nan; 3]
        };
        self.pts[at..at + 3].copy_from_slice(&points);
        let at = b * self.media_block + self.mo[p];
        self.med[at..at + 2].copy_from_slice(&[media[0] as u32, media[1] as u32]);
    }
}

/// What [`Tracer::one_step_chain`] needs of its path, looked up once.
#[derive(Clone, Copy)]
struct OneStepChain<'a> {
    one: &'a OneStepPath,
    p: usize,
    kind: crate::scene::StepKind,
    line: &'a crate::polyline::Polyline,
}

/// A ray of [`Tracer::one_step_chain`] solved without the workspace: its record, points,
/// final iterate and segment.
struct OneStepRay {
    record: RayRecord,
    points: [Point; 3],
    newton: OneStepNewton,
    seg: usize,
}

/// One path's chain of warm starts through the blocks of a unit: whether its last ray
/// converged, and the last receiver.
#[derive(Default)]
struct Chain {
    have: bool,
    last: Point,
}

/// A block's place in a [`Chain`].
struct Link {
    source: usize,
    receiver: usize,
    /// The receiver's position and its move from the last one.
    here: Point,
    moved: Vec2,
    /// Whether the ray starts from the last solution: warm starts on, the last ray converged,
    /// the same source, and the last receiver near (closer than a quarter of this receiver's
    /// distance to the source).
    warm: bool,
}

impl Chain {
    /// Block `b` of `unit` in the chain.
    #[inline]
    fn link(&mut self, scene: &crate::scene::Scene, unit: &Unit, b: usize) -> Link {
        let (source, receiver) = unit.ends(b);
        if b > 0 && unit.new_source(b) {
            self.have = false;
        }
        let here = scene.receivers()[receiver];
        let near = b > 0 && near(here, self.last, scene.sources()[source]);
        let moved = here - self.last;
        self.last = here;
        Link {
            source,
            receiver,
            here,
            moved,
            warm: unit.warm_start && self.have && near,
        }
    }
}

impl Tracer {
    /// Path `p` of every block of `unit`, one block after the other, each starting from the
    /// last one's solution when that receiver is near.
    fn path_chain(
        &self,
        p: usize,
        params: std::ops::Range<usize>,
        unit: &mut Unit,
        ws: &mut Workspace,
        warm: &mut Warm,
    ) {
        let mut chain = Chain::default();
        // Through parallel flat layers the default start is already the solution: a warm
        // start would leave a Newton step or two.
        let skip = self.plan_of(p).skips_warm_start(self.initial_guess());
        let warm_start = unit.warm_start && !skip;
        for b in 0..unit.n {
            let link = chain.link(self.scene(), unit, b);
            let guess =
                (link.warm && warm_start).then(|| warm.predict(p, params.clone(), link.moved));
            let s = self.solve_ray(link.source, link.receiver, p, guess, ws);
            unit.write(b, p, &s, ws.points(), ws.media());
            chain.have = s.status == Status::Converged;
            if chain.have && warm_start {
                warm.store(p, params.clone(), ws);
            }
        }
    }

    /// One ray from `guess` if given, else from the default start; a warm-started ray that
    /// does not converge is solved again from the default start.
    fn solve_ray(
        &self,
        source: usize,
        receiver: usize,
        p: usize,
        guess: Option<&[f64]>,
        ws: &mut Workspace,
    ) -> RayRecord {
        let start = guess.map_or(Start::Default, Start::Trial);
        let s = self.solve_indexed_start(source, receiver, p, start, ws);
        if guess.is_none() || s.status == Status::Converged {
            return s;
        }
        // The neighbour's path may lead elsewhere (off an end, onto a vertex): the
        // documented start decides.
        let cold = self.solve_indexed_start(source, receiver, p, Start::Default, ws);
        RayRecord {
            iterations: s.iterations + cold.iterations,
            ..cold
        }
    }

    /// [`path_chain`](Self::path_chain) for a one-interaction path (its parameter at `at` in
    /// `warm`), without the workspace: each ray's start, Newton steps ([`OneStepNewton`], the
    /// steps of one-by-one solving) and classification in registers. A ray that leaves this
    /// common case (no crossing or specular point to start from, a step leaving its segment,
    /// any status but `converged` after a warm start, no time) is solved one by one from the
    /// same start. A refraction at a one-segment interface goes through the flat kernel instead,
    /// never warm-started, as one by one.
    fn one_step_chain(
        &self,
        one: &OneStepPath,
        p: usize,
        at: usize,
        unit: &mut Unit,
        ws: &mut Workspace,
        warm: &mut Warm,
    ) {
        let scene = self.scene();
        let step = &scene.paths()[p].steps[0];
        let path = OneStepChain {
            one,
            p,
            kind: step.kind,
            line: &scene.interfaces()[step.interface].polyline,
        };
        let mut chain = Chain::default();
        // The last ray's segment: the first one tried for the next start.
        let mut seg = 0;
        // Off a flat mirror the default start is already the solution; at a flat interface
        // the kernel's steps from its own start cost less than a warm start saves.
        let flat = match self.plan_of(p) {
            PathPlan::FlatRefraction(_, flat) => Some(flat),
            _ => None,
        };
        let skip = self.plan_of(p).skips_warm_start(self.initial_guess());
        let warm_start = unit.warm_start && !skip;
        let cx = self.context();
        for b in 0..unit.n {
            let link = chain.link(scene, unit, b);
            let guess =
                (link.warm && warm_start).then(|| warm.predict(p, at..at + 1, link.moved)[0]);
            let source = scene.sources()[link.source];
            let fast = match flat {
                // (Never warm-started.)
                Some(flat) => flat.solve(source, link.here).map(|sol| {
                    let points = [source, flat.point(sol.s), link.here];
                    let record = flat_status(&cx, flat, p, &points, sol);
                    (record, points, None)
                }),
                None => self
                    .one_step_fast(&path, source, link.here, guess, seg)
                    .map(|ray| (ray.record, ray.points, Some((ray.newton, ray.seg)))),
            };
            // A ray without a time goes one by one: where the start led to no stationary
            // path, the complete search answers.
            match fast.filter(|(record, _, _)| record.status.has_time()) {
                Some((record, points, newton)) => {
                    unit.write_one(b, p, &record, &points, one.media);
                    chain.have = record.status == Status::Converged;
                    if let Some((it, j)) = newton.filter(|_| chain.have && warm_start) {
                        let t = path.line.tangent(j);
                        let sens = one_step_sensitivity(&it.e, t, one.slowness[1]);
                        warm.store_one(p, at, it.s, sens);
                        seg = j;
                    }
                }
                None => {
                    let guess = guess.map(|g| [g]);
                    let guess = guess.as_ref().map(|g| &g[..]);
                    let s = self.solve_ray(link.source, link.receiver, p, guess, ws);
                    unit.write(b, p, &s, ws.points(), ws.media());
                    chain.have = s.status == Status::Converged;
                    if chain.have && warm_start {
                        warm.store(p, at..at + 1, ws);
                        seg = ws.newton.seg[0];
                    }
                }
            }
        }
    }

    /// One ray of [`one_step_chain`](Self::one_step_chain) from `guess` (else the crossing
    /// start), `hint` a segment to try first; `None` when the ray must be solved one by one.
    #[inline(always)]
    fn one_step_fast(
        &self,
        path: &OneStepChain,
        source: Point,
        receiver: Point,
        guess: Option<f64>,
        hint: usize,
    ) -> Option<OneStepRay> {
        let OneStepChain { one, p, kind, line } = *path;
        let at = match guess {
            Some(wanted) => given_param(line, wanted, hint),
            None => match one.crossing_start(kind, line, source, receiver) {
                crate::trace::OneStepStart::At(at) => at,
                _ => return None,
            },
        };
        let (s, j) = (at.s, at.seg);
        let (to_receiver, coord) = (receiver - source, coord(source, receiver));
        let f = &Frame::new(line, j, source);
        let mut it = OneStepNewton::start(s, f, one.slowness, to_receiver, coord);
        if it.run(f, one.slowness, to_receiver, coord, self.newton_options())
            != Some(Outcome::Converged)
        {
            return None;
        }
        let e = &it.e;
        let points = [source, line.point_on(j, it.s), receiver];
        let rel = [Vec2::default(), e.p, to_receiver];
        let sol = it.solution(Outcome::Converged);
        let sides = std::iter::once((kind, line.normal(j)));
        let record = self.classifier().free_points(
            self.scene(),
            p,
            sides,
            &rel,
            &e.len,
            &points,
            &[j],
            &sol,
        );
        if record.status != Status::Converged && guess.is_some() {
            return None;
        }
        Some(OneStepRay {
            record,
            points,
            newton: it,
            seg: j,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_orders_quadrants() {
        assert!(morton(0, 0) < morton(1, 0));
        assert!(morton(1, 0) < morton(0, 1));
        assert!(morton(65535, 65535) > morton(65535, 0));
    }
}
