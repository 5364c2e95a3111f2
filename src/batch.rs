//! Batches: every ray of a scene in parallel, in ray order, in flat storage, with warm starts.

use rayon::iter::plumbing::{Consumer, Producer, ProducerCallback, UnindexedConsumer, bridge};
use rayon::prelude::*;

use crate::amplitude::Amplitude;
use crate::geom::Point;
use crate::options::{Progress, Run};
use crate::scene::{RayTriple, SceneError};
use crate::trace::{
    ChainLink, ChainRays, Ray, RayRecord, Reason, Status, Tracer, WarmStarts, Workspace,
};

mod amplitudes;

/// How to run a batch (what stops it and who hears of its progress: its
/// [`Run`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BatchOptions {
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
}

impl Default for BatchOptions {
    fn default() -> Self {
        BatchOptions {
            warm_start: true,
            chunk: 256,
        }
    }
}

/// Every ray of a scene, in ray order (source-major, then receiver, then path), in flat
/// arrays: one record per ray and, per (source, receiver) pair, one block holding the points
/// (and leg media) of all paths.
///
/// ```
/// use eigenray::{BatchOptions, Scene, Status, Tracer, options::Run};
/// let scene = Scene::from_spec(&eigenray::demo::air_water(100, 7)).unwrap();
/// let tracer = Tracer::new(&scene).unwrap();
/// let batch = tracer.trace_batch(&BatchOptions::default(), &Run::new()).unwrap();
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
    /// Each ray's amplitude, in ray order, when the scene asks for amplitudes (else empty).
    amplitudes: Vec<Amplitude>,
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

/// Where a batch writes its rays as it solves them ([`Tracer::trace_batch_to`]): a
/// destination for every ray of a scene in ray order, in blocks (a block is one (source,
/// receiver) pair: the rays of all its paths, in path order).
///
/// The batch cuts its sink into parts of whole blocks ([`split_at`](Self::split_at)), one
/// per work unit, and the worker that solves a unit writes each of its rays into the unit's
/// part right after solving it, while the ray is in cache: a front end's own arrays (numpy's,
/// a GPU staging buffer) are filled in the batch's parallel pass, without a [`Batch`] in
/// between and a second pass to copy it. [`Batch`] itself is filled through one.
///
/// Every ray is written exactly once, with [`write()`](Self::write) or
/// [`write_one`](Self::write_one); which rays go through which is not part of the contract.
///
/// ```
/// use eigenray::batch::{BatchScratch, BatchSink, RaySlot};
/// use eigenray::{BatchOptions, Point, RayRecord, Scene, Tracer, options::Run};
///
/// /// Times only, into a slice of one time per ray (one path here).
/// struct Times<'a>(&'a mut [f64]);
///
/// impl BatchSink for Times<'_> {
///     fn blocks(&self) -> usize {
///         self.0.len()
///     }
///     fn split_at(self, blocks: usize) -> (Self, Self) {
///         let (a, b) = self.0.split_at_mut(blocks);
///         (Times(a), Times(b))
///     }
///     fn write(&mut self, at: RaySlot, record: &RayRecord, _: &[Point], _: &[usize]) {
///         self.0[at.block] = record.time;
///     }
/// }
///
/// let scene = Scene::from_spec(&eigenray::demo::air_water(1000, 7)).unwrap();
/// let tracer = Tracer::new(&scene).unwrap();
/// let mut times = vec![0.0; 1000];
/// let mut scratch = BatchScratch::default();
/// tracer
///     .trace_batch_to(&BatchOptions::default(), &Run::new(), Times(&mut times), &mut scratch)
///     .unwrap();
/// let run = eigenray::options::Run::new();
/// let batch = tracer.trace_batch(&BatchOptions::default(), &run).unwrap();
/// assert!((0..1000).all(|i| times[i].to_bits() == batch.record(i).time.to_bits()));
/// ```
pub trait BatchSink: Send + Sized {
    /// Its number of blocks.
    fn blocks(&self) -> usize;

    /// Its first `blocks` blocks, and the rest.
    fn split_at(self, blocks: usize) -> (Self, Self);

    /// Writes the ray at `at`: its record, its points (source, interaction points, receiver:
    /// meaningful only when [`Status::has_time`], and then as many as its path has) and its
    /// leg media (indices into [`crate::Scene::media`]: one per leg when known, else fewer,
    /// usually none).
    fn write(&mut self, at: RaySlot, record: &RayRecord, points: &[Point], media: &[usize]);

    /// [`write()`](Self::write) for a ray of one interaction whose three points and two leg
    /// media are known (the batch's fastest rays): an implementation may copy them without
    /// loops. By default, `write`.
    #[inline(always)]
    fn write_one(
        &mut self,
        at: RaySlot,
        record: &RayRecord,
        points: &[Point; 3],
        media: [usize; 2],
    ) {
        self.write(at, record, points, &media);
    }
}

/// Where a [`BatchSink`] writes a ray: the ray's block within the part of the sink it is
/// given (counted from the part's first block), and the ray's indices. Its index in ray order
/// is `(source × receivers + receiver) × paths + path`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RaySlot {
    /// The block within the part.
    pub block: usize,
    /// Source index.
    pub source: usize,
    /// Receiver index.
    pub receiver: usize,
    /// Path index (the ray's place within its block).
    pub path: usize,
}

/// Memory that [`Tracer::trace_batch_to`] keeps from one call to the next: the rays in
/// solving order when the receivers are solved in a spatial order (see
/// [`BatchOptions::warm_start`]), before they go to the sink in ray order. Receivers already
/// in a coherent order (a grid, a survey line) are solved straight into the sink and leave it
/// empty.
#[derive(Clone, Debug, Default)]
pub struct BatchScratch {
    arrays: Arrays,
}

impl BatchScratch {
    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        let (r, p, m) = &self.arrays;
        arrays_bytes((r, p, m))
    }
}

/// A batch's three arrays: records, points, leg media.
type Arrays = (Vec<RayRecord>, Vec<Point>, Vec<u32>);

/// Bytes held by a batch's three arrays.
fn arrays_bytes((r, p, m): (&Vec<RayRecord>, &Vec<Point>, &Vec<u32>)) -> usize {
    r.capacity() * std::mem::size_of::<RayRecord>()
        + p.capacity() * std::mem::size_of::<Point>()
        + m.capacity() * std::mem::size_of::<u32>()
}

/// Where each path's rays sit in a batch's blocks.
#[derive(Clone, Copy)]
struct Layout<'a> {
    /// Paths per block.
    np: usize,
    /// Points and leg media per block.
    pts_block: usize,
    media_block: usize,
    /// Offset of each path's points and leg media within a block, and the block size (last
    /// entry).
    po: &'a [usize],
    mo: &'a [usize],
}

/// Each path's offsets of points, leg media and parameters within a block, and the block
/// sizes (last entries).
fn offsets(scene: &crate::scene::Scene) -> [Vec<usize>; 3] {
    let mut point_offsets = vec![0];
    let mut media_offsets = vec![0];
    let mut param_offsets = vec![0];
    for p in scene.paths() {
        let k = p.steps.len();
        point_offsets.push(point_offsets.last().unwrap() + k + 2);
        media_offsets.push(media_offsets.last().unwrap() + k + 1);
        param_offsets.push(param_offsets.last().unwrap() + k);
    }
    [point_offsets, media_offsets, param_offsets]
}

/// The [`BatchSink`] of a batch's own arrays (records, points, leg media, in block order).
struct Out<'a> {
    rec: &'a mut [RayRecord],
    pts: &'a mut [Point],
    med: &'a mut [u32],
    layout: Layout<'a>,
}

impl BatchSink for Out<'_> {
    fn blocks(&self) -> usize {
        self.rec.len() / self.layout.np
    }

    fn split_at(self, blocks: usize) -> (Self, Self) {
        let l = self.layout;
        let (rec, rec_b) = self.rec.split_at_mut(blocks * l.np);
        let (pts, pts_b) = self.pts.split_at_mut(blocks * l.pts_block);
        let (med, med_b) = self.med.split_at_mut(blocks * l.media_block);
        (
            Out {
                rec,
                pts,
                med,
                layout: l,
            },
            Out {
                rec: rec_b,
                pts: pts_b,
                med: med_b,
                layout: l,
            },
        )
    }

    #[inline(always)]
    fn write(&mut self, at: RaySlot, s: &RayRecord, points: &[Point], media: &[usize]) {
        self.write_at(at.block, at.path, s, points, media);
    }

    #[inline(always)]
    fn write_one(&mut self, at: RaySlot, s: &RayRecord, points: &[Point; 3], media: [usize; 2]) {
        let (b, p, l) = (at.block, at.path, self.layout);
        self.rec[b * l.np + p] = *s;
        let base = b * l.pts_block + l.po[p];
        let nan = Point::new(f64::NAN, f64::NAN);
        let points = if s.status.has_time() {
            *points
        } else {
            [nan; 3]
        };
        self.pts[base..base + 3].copy_from_slice(&points);
        let base = b * l.media_block + l.mo[p];
        self.med[base..base + 2].copy_from_slice(&[media[0] as u32, media[1] as u32]);
    }
}

impl Out<'_> {
    /// Writes ray `p` of block `b` (a call of its own: the general paths' rays).
    #[inline]
    fn write_at(&mut self, b: usize, p: usize, s: &RayRecord, points: &[Point], media: &[usize]) {
        // (The layout's fields read where needed: a copy of it loads them all first.)
        self.rec[b * self.layout.np + p] = *s;
        let (base, po) = (b * self.layout.pts_block, self.layout.po);
        let ray_points = &mut self.pts[base + po[p]..base + po[p + 1]];
        if s.status.has_time() {
            ray_points.copy_from_slice(points);
        } else {
            ray_points.fill(Point::new(f64::NAN, f64::NAN));
        }
        let (base, mo) = (b * self.layout.media_block, self.layout.mo);
        let ray_media = &mut self.med[base + mo[p]..base + mo[p + 1]];
        if media.len() == ray_media.len() {
            for (dst, &m) in ray_media.iter_mut().zip(media) {
                *dst = m as u32;
            }
        } else {
            ray_media.fill(NO_MEDIUM);
        }
    }
}

/// A sink cut into parts of `unit` blocks (the last may be shorter), as a rayon indexed
/// parallel iterator: the `par_chunks_mut` of a sink.
struct Parts<S> {
    sink: S,
    unit: usize,
}

impl<S: BatchSink> Parts<S> {
    fn new(sink: S, unit: usize) -> Self {
        Parts {
            sink,
            unit: unit.max(1),
        }
    }
}

impl<S: BatchSink> ParallelIterator for Parts<S> {
    type Item = S;

    fn drive_unindexed<C: UnindexedConsumer<S>>(self, consumer: C) -> C::Result {
        bridge(self, consumer)
    }

    fn opt_len(&self) -> Option<usize> {
        Some(IndexedParallelIterator::len(self))
    }
}

impl<S: BatchSink> IndexedParallelIterator for Parts<S> {
    fn len(&self) -> usize {
        self.sink.blocks().div_ceil(self.unit)
    }

    fn drive<C: Consumer<S>>(self, consumer: C) -> C::Result {
        bridge(self, consumer)
    }

    fn with_producer<CB: ProducerCallback<S>>(self, callback: CB) -> CB::Output {
        callback.callback(self)
    }
}

impl<S: BatchSink> Producer for Parts<S> {
    type Item = S;
    type IntoIter = PartsIter<S>;

    fn into_iter(self) -> PartsIter<S> {
        let parts = IndexedParallelIterator::len(&self);
        PartsIter {
            parts,
            sink: (parts > 0).then_some(self.sink),
            unit: self.unit,
        }
    }

    fn split_at(self, index: usize) -> (Self, Self) {
        let at = (index * self.unit).min(self.sink.blocks());
        let (a, b) = self.sink.split_at(at);
        (Parts::new(a, self.unit), Parts::new(b, self.unit))
    }
}

/// The parts of [`Parts`], one after the other.
struct PartsIter<S> {
    sink: Option<S>,
    unit: usize,
    /// Parts left.
    parts: usize,
}

impl<S: BatchSink> Iterator for PartsIter<S> {
    type Item = S;

    // Out of line: the split of each unit's part stays out of the solve loop that the
    // workers' job inlines (about one instruction a ray fewer in a batch of one refraction).
    #[inline(never)]
    fn next(&mut self) -> Option<S> {
        let sink = self.sink.take()?;
        self.parts -= 1;
        if self.parts == 0 {
            return Some(sink);
        }
        let (part, rest) = sink.split_at(self.unit);
        self.sink = Some(rest);
        Some(part)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.parts, Some(self.parts))
    }
}

impl<S: BatchSink> DoubleEndedIterator for PartsIter<S> {
    fn next_back(&mut self) -> Option<S> {
        let sink = self.sink.take()?;
        self.parts -= 1;
        if self.parts == 0 {
            return Some(sink);
        }
        let (rest, part) = sink.split_at(self.parts * self.unit);
        self.sink = Some(rest);
        Some(part)
    }
}

impl<S: BatchSink> ExactSizeIterator for PartsIter<S> {}

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
    /// The (source, receiver, path) of ray `ray`.
    pub fn triple(&self, ray: usize) -> RayTriple {
        RayTriple::of(ray, self.receivers, self.paths)
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
        let RayTriple {
            source,
            receiver,
            path,
        } = self.triple(ray);
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
            amplitude: self.amplitude(ray).copied(),
        }
    }
    /// Every ray as an owned [`Ray`], in ray order.
    pub fn to_rays(&self) -> Vec<Ray> {
        (0..self.len()).map(|i| self.ray(i)).collect()
    }
    /// Bytes held by the batch's arrays.
    pub fn memory_bytes(&self) -> usize {
        arrays_bytes((&self.records, &self.points, &self.media))
            + self.amplitudes.capacity() * std::mem::size_of::<Amplitude>()
            + self
                .spatial
                .as_deref()
                .map_or(0, |(r, p, m)| arrays_bytes((r, p, m)))
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
    /// Solves every ray of the scene in parallel (rayon, one workspace per work unit), with
    /// the same results as solving them one by one (up to the start each ray is solved from
    /// when `warm_start` is on), in ray order. The memory is reserved before any ray is
    /// solved: a batch of more rays than the machine can hold is an error, not an abort.
    ///
    /// Each work unit's rays are items (and units of work) of `run`, asked for before the
    /// unit is solved; the searches of rays whose start finds no path run with it too. Once
    /// `run` stops (a stop request, a spent budget), the units not yet begun are not solved:
    /// their rays are `not_converged` with [`Reason::SearchLimit`](crate::Reason).
    ///
    /// ```
    /// use eigenray::{BatchOptions, Scene, Tracer, options::Run};
    /// let scene = Scene::from_spec(&eigenray::demo::air_water(100, 7)).unwrap();
    /// let tracer = Tracer::new(&scene).unwrap();
    /// let batch = tracer.trace_batch(&BatchOptions::default(), &Run::new()).unwrap();
    /// assert_eq!(batch.len(), 100);
    /// ```
    ///
    /// # Errors
    /// `paths` (the batch's size: sources × receivers × paths), saying how many bytes it
    /// needs.
    pub fn trace_batch(&self, opts: &BatchOptions, run: &Run) -> Result<Batch, SceneError> {
        let mut batch = Batch::default();
        self.trace_batch_into(opts, run, &mut batch)?;
        Ok(batch)
    }

    /// [`trace_batch`](Self::trace_batch) into an existing batch, reusing its memory: a tool
    /// that traces every layout change again keeps one `Batch` and pays for its hundreds of
    /// megabytes (page faults, first writes) only once. The results are the same as those of
    /// `trace_batch`.
    ///
    /// ```
    /// use eigenray::{Batch, BatchOptions, Scene, Tracer, options::Run};
    /// let mut batch = Batch::default();
    /// for receivers in [100, 200] {
    ///     let scene = Scene::from_spec(&eigenray::demo::air_water(receivers, 7)).unwrap();
    ///     let tracer = Tracer::new(&scene).unwrap();
    ///     tracer.trace_batch_into(&BatchOptions::default(), &Run::new(), &mut batch).unwrap();
    ///     assert_eq!(batch.len(), receivers);
    /// }
    /// ```
    ///
    /// # Errors
    /// As [`trace_batch`](Self::trace_batch).
    pub fn trace_batch_into(
        &self,
        opts: &BatchOptions,
        run: &Run,
        batch: &mut Batch,
    ) -> Result<(), SceneError> {
        // Without rays there is no order to decide (its test and sort scan the receivers).
        let has_rays = self.scene().num_rays() > 0;
        let spatial = has_rays && self.solves_spatially(opts);
        let mut reserved = reserve(
            (&mut batch.records, &mut batch.points, &mut batch.media),
            self.scene(),
        );
        if spatial && reserved.is_ok() {
            let (r, p, m) = &mut **batch.spatial.get_or_insert_with(Box::default);
            reserved = reserve((r, p, m), self.scene());
        }
        if reserved.is_err() {
            return Err(self.too_large(1 + usize::from(spatial)));
        }
        // The order decided once (its test scans the receivers).
        let order = if has_rays {
            self.order_of(spatial)
        } else {
            Vec::new()
        };
        self.solve_batch_into(opts, run, &order, batch);
        self.batch_amplitudes(batch, run);
        Ok(())
    }

    /// Whether a batch with `opts` may solve the receivers in a spatial order (and so needs
    /// a second copy of its arrays).
    fn solves_spatially(&self, opts: &BatchOptions) -> bool {
        let scene = self.scene();
        opts.warm_start
            && !scene.sources().is_empty()
            && !coherent(scene.receivers(), scene.sources()[0])
    }

    /// The error of a batch whose `copies` copies of its arrays cannot be allocated.
    fn too_large(&self, copies: usize) -> SceneError {
        let size = self.scene().batch_size();
        let bytes = size
            .bytes(
                std::mem::size_of::<RayRecord>(),
                std::mem::size_of::<Point>(),
                std::mem::size_of::<u32>(),
            )
            .and_then(|b| b.checked_mul(copies))
            .map_or("more than the address space holds".to_string(), |b| {
                format!("{b} bytes")
            });
        SceneError::new(
            "paths",
            format!(
                "a batch of {} rays needs {bytes} for its records, points and leg media, \
                 which cannot be allocated",
                size.rays
            ),
        )
    }

    /// [`trace_batch_into`](Self::trace_batch_into)'s solve of every ray, the receivers of
    /// each source in `order`.
    fn solve_batch_into(&self, opts: &BatchOptions, run: &Run, order: &[usize], batch: &mut Batch) {
        let scene = self.scene();
        let (nr, np) = (scene.receivers().len(), scene.paths().len());
        let [point_offsets, media_offsets, param_offsets] = offsets(scene);
        let (pts_block, media_block) = (point_offsets[np], media_offsets[np]);
        let blocks = scene.sources().len() * nr;
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
        let identity = order.iter().enumerate().all(|(i, &r)| i == r);

        // Solve in (source, spatial position) block order. Every element is written by the
        // solve: the arrays need only the right lengths.
        let mut spatial = if identity {
            None
        } else {
            Some(batch.spatial.take().unwrap_or_default())
        };
        let (records, points, media) = match spatial.as_deref_mut() {
            Some((r, p, m)) => (r, p, m),
            None => (&mut batch.records, &mut batch.points, &mut batch.media),
        };
        let layout = Layout {
            np,
            pts_block,
            media_block,
            po: &batch.point_offsets,
            mo: &batch.media_offsets,
        };
        self.solve_units(
            opts,
            run,
            order,
            &param_offsets,
            sized_out(records, points, media, blocks, layout),
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
        let from = solved_block(order, nr);
        batch
            .records
            .par_chunks_mut(np)
            .enumerate()
            .for_each(|(block, out)| {
                let at = from(block) * np;
                out.copy_from_slice(&records[at..at + np]);
            });
        batch
            .points
            .par_chunks_mut(pts_block)
            .enumerate()
            .for_each(|(block, out)| {
                let at = from(block) * pts_block;
                out.copy_from_slice(&points[at..at + pts_block]);
            });
        batch
            .media
            .par_chunks_mut(media_block)
            .enumerate()
            .for_each(|(block, out)| {
                let at = from(block) * media_block;
                out.copy_from_slice(&media[at..at + media_block]);
            });
        batch.spatial = Some(spatial);
    }

    /// [`trace_batch`](Self::trace_batch) into a [`BatchSink`] of every ray of the
    /// scene: each ray is written into `sink` by the worker that solves it, right after
    /// solving it, with the same results as [`trace_batch`](Self::trace_batch) (bit for bit).
    /// A front end fills its own arrays this way in the batch's parallel pass, without a
    /// [`Batch`] to copy from. Receivers solved in a spatial order (see
    /// [`BatchOptions::warm_start`]) are solved into `scratch` first and then written into
    /// the sink in parallel; keep one `scratch` for a loop of batches. A scene without rays
    /// (no paths, sources or receivers) writes nothing.
    ///
    /// # Errors
    /// As [`trace_batch`](Self::trace_batch), when `scratch` cannot be allocated;
    /// nothing has been written to the sink then.
    ///
    /// # Panics
    /// If the sink does not have one block per (source, receiver) pair (and the scene has
    /// rays).
    pub fn trace_batch_to<S: BatchSink>(
        &self,
        opts: &BatchOptions,
        run: &Run,
        sink: S,
        scratch: &mut BatchScratch,
    ) -> Result<(), SceneError> {
        let scene = self.scene();
        let (nr, np) = (scene.receivers().len(), scene.paths().len());
        let blocks = scene.sources().len() * nr;
        if blocks == 0 || np == 0 {
            return Ok(());
        }
        assert_eq!(
            sink.blocks(),
            blocks,
            "a batch's sink holds one block per (source, receiver) pair"
        );
        let [point_offsets, media_offsets, param_offsets] = offsets(scene);
        let order = self.solve_order(opts);
        if order.iter().enumerate().all(|(i, &r)| i == r) {
            self.solve_units(opts, run, &order, &param_offsets, sink);
            return Ok(());
        }
        let (records, points, media) = &mut scratch.arrays;
        if reserve((records, points, media), scene).is_err() {
            return Err(self.too_large(1));
        }
        let layout = Layout {
            np,
            pts_block: point_offsets[np],
            media_block: media_offsets[np],
            po: &point_offsets,
            mo: &media_offsets,
        };
        let out = sized_out(records, points, media, blocks, layout);
        self.solve_units(opts, run, &order, &param_offsets, out);
        // Back from spatial order to ray order, the sink's parts in parallel.
        let (records, points, media) = &scratch.arrays;
        let from = solved_block(&order, nr);
        let chunk = opts.chunk.max(1);
        Parts::new(sink, chunk)
            .enumerate()
            .for_each_init(Vec::new, |legs, (unit, mut part)| {
                for b in 0..part.blocks() {
                    let block = unit * chunk + b;
                    let (source, receiver) = (block / nr, block % nr);
                    let solved = from(block);
                    for p in 0..np {
                        let at = solved * layout.pts_block;
                        let ray_points = &points[at + layout.po[p]..at + layout.po[p + 1]];
                        let at = solved * layout.media_block;
                        let stored = &media[at + layout.mo[p]..at + layout.mo[p + 1]];
                        legs.clear();
                        if stored.first() != Some(&NO_MEDIUM) {
                            legs.extend(stored.iter().map(|&m| m as usize));
                        }
                        let slot = RaySlot {
                            block: b,
                            source,
                            receiver,
                            path: p,
                        };
                        part.write(slot, &records[solved * np + p], ray_points, legs);
                    }
                }
            });
        Ok(())
    }

    /// The order in which a batch solves the receivers of each source: a Morton order when
    /// warm starts are on and the receivers' own order is not coherent, else their own
    /// (sorting and putting the rays back would cost more than the warm starts save).
    fn solve_order(&self, opts: &BatchOptions) -> Vec<usize> {
        self.order_of(self.solves_spatially(opts))
    }

    /// A Morton order of the receivers when `spatial`, else their own.
    fn order_of(&self, spatial: bool) -> Vec<usize> {
        let scene = self.scene();
        if spatial {
            spatial_order(scene.receivers())
        } else {
            (0..scene.receivers().len()).collect()
        }
    }

    /// Solves every ray into `sink` in (source, `order`) block order, in parallel: one work
    /// unit per `opts.chunk` blocks (one part of the sink), one workspace and warm-start state
    /// per rayon job. A unit that `run` does not let through writes its rays as
    /// `not_converged` with [`Reason::SearchLimit`].
    fn solve_units<S: BatchSink>(
        &self,
        opts: &BatchOptions,
        run: &Run,
        order: &[usize],
        param_offsets: &[usize],
        sink: S,
    ) {
        let scene = self.scene();
        let (nr, np) = (scene.receivers().len(), scene.paths().len());
        let chunk = opts.chunk.max(1);
        Parts::new(sink, chunk).enumerate().for_each_init(
            || (Workspace::new(), WarmStarts::new(param_offsets[np], np)),
            |(ws, warm), (unit, mut out)| {
                let n = out.blocks();
                if !run.keep_going(Progress::items((n * np) as u64)) {
                    let first = unit * chunk;
                    for b in 0..n {
                        let block = first + b;
                        let (source, receiver) = (block / nr, order[block % nr]);
                        for path in 0..np {
                            let slot = RaySlot {
                                block: b,
                                source,
                                receiver,
                                path,
                            };
                            out.write(slot, &NOT_SOLVED, &[], &[]);
                        }
                    }
                    return;
                }
                let mut unit = Unit {
                    first: unit * chunk,
                    n,
                    nr,
                    order,
                    warm_start: opts.warm_start,
                    out,
                };
                // Path by path: each path's rays form one chain of warm starts (their searches
                // where a start finds no path run with `run`).
                run.within(|| {
                    for p in 0..np {
                        let params = param_offsets[p]..param_offsets[p + 1];
                        let mut rays = UnitChain {
                            scene,
                            unit: &mut unit,
                            path: p,
                            have: false,
                            last: Point::default(),
                        };
                        self.solve_chain(p, params, &mut rays, warm, ws);
                    }
                });
            },
        );
    }
}

/// The record of a ray that a stopped batch did not solve.
const NOT_SOLVED: RayRecord = RayRecord {
    status: Status::NotConverged,
    time: f64::NAN,
    iterations: 0,
    residual: f64::NAN,
    reason: Some(Reason::SearchLimit),
};

/// Reserves room in a batch's arrays for every ray of `scene`.
fn reserve(
    (records, points, media): (&mut Vec<RayRecord>, &mut Vec<Point>, &mut Vec<u32>),
    scene: &crate::scene::Scene,
) -> Result<(), std::collections::TryReserveError> {
    let size = scene.batch_size();
    let grow = |have: usize, want: usize| want.saturating_sub(have);
    records
        .try_reserve_exact(grow(records.len(), size.rays))
        .and_then(|()| points.try_reserve_exact(grow(points.len(), size.points)))
        .and_then(|()| media.try_reserve_exact(grow(media.len(), size.legs)))
}

/// The [`Out`] sink of `blocks` blocks over the arrays, sized for them.
fn sized_out<'a>(
    records: &'a mut Vec<RayRecord>,
    points: &'a mut Vec<Point>,
    media: &'a mut Vec<u32>,
    blocks: usize,
    layout: Layout<'a>,
) -> Out<'a> {
    sized(records, blocks * layout.np, RayRecord::default());
    sized(
        points,
        blocks * layout.pts_block,
        Point::new(f64::NAN, f64::NAN),
    );
    sized(media, blocks * layout.media_block, NO_MEDIUM);
    Out {
        rec: records,
        pts: points,
        med: media,
        layout,
    }
}

/// Where the block of ray order `block` was solved, with the receivers of each source solved
/// in `order` (the inverse permutation, per source).
fn solved_block(order: &[usize], nr: usize) -> impl Fn(usize) -> usize + Sync {
    let mut inverse = vec![0; nr];
    for (pos, &r) in order.iter().enumerate() {
        inverse[r] = pos;
    }
    move |block| (block / nr) * nr + inverse[block % nr]
}

/// One work unit of a batch: blocks `first..first + n` in solve order (a block is one
/// (source, receiver) pair, all paths) and the part of the sink they go to.
struct Unit<'a, S> {
    first: usize,
    n: usize,
    /// Receivers per source.
    nr: usize,
    /// Solve order of the receivers.
    order: &'a [usize],
    warm_start: bool,
    out: S,
}

impl<S: BatchSink> Unit<'_, S> {
    /// Source and receiver of block `b` of the unit.
    #[inline]
    fn ends(&self, b: usize) -> (usize, usize) {
        let block = self.first + b;
        (block / self.nr, self.order[block % self.nr])
    }

    /// Whether block `b` is the first of its source (the warm-start chain breaks there).
    #[inline]
    fn new_source(&self, b: usize) -> bool {
        (self.first + b).is_multiple_of(self.nr)
    }
}

/// One path's rays through the blocks of a unit, as the tracer solves them ([`ChainRays`]):
/// the chain of warm starts (whether its last ray converged, the last receiver) and where
/// each ray goes in the unit's part of the sink.
struct UnitChain<'u, 'a, S> {
    scene: &'u crate::scene::Scene,
    unit: &'u mut Unit<'a, S>,
    /// The path.
    path: usize,
    /// Whether the last ray converged.
    have: bool,
    /// The last receiver.
    last: Point,
}

impl<S: BatchSink> UnitChain<'_, '_, S> {
    /// Where block `b`'s ray at `link` goes in the unit's part.
    #[inline(always)]
    fn slot(&self, b: usize, link: &ChainLink) -> RaySlot {
        RaySlot {
            block: b,
            source: link.source,
            receiver: link.receiver,
            path: self.path,
        }
    }
}

impl<S: BatchSink> ChainRays for UnitChain<'_, '_, S> {
    #[inline(always)]
    fn warm_starts(&self) -> bool {
        self.unit.warm_start
    }

    #[inline(always)]
    fn rays(&self) -> usize {
        self.unit.n
    }

    /// Block `b` of the unit: it starts from the last solution when warm starts are on, the
    /// last ray converged, the source is the same, and the last receiver is near (closer than
    /// a quarter of this receiver's distance to the source).
    #[inline(always)]
    fn link(&mut self, b: usize) -> ChainLink {
        let (scene, unit) = (self.scene, &*self.unit);
        let (source, receiver) = unit.ends(b);
        if b > 0 && unit.new_source(b) {
            self.have = false;
        }
        let here = scene.receivers()[receiver];
        let near = b > 0 && near(here, self.last, scene.sources()[source]);
        let moved = here - self.last;
        self.last = here;
        ChainLink {
            source,
            receiver,
            here,
            moved,
            warm: unit.warm_start && self.have && near,
        }
    }

    #[inline(always)]
    fn write(
        &mut self,
        b: usize,
        link: &ChainLink,
        record: &RayRecord,
        points: &[Point],
        media: &[usize],
    ) {
        let slot = self.slot(b, link);
        self.unit.out.write(slot, record, points, media);
        self.have = record.status == Status::Converged;
    }

    #[inline(always)]
    fn write_one(
        &mut self,
        b: usize,
        link: &ChainLink,
        record: &RayRecord,
        points: &[Point; 3],
        media: [usize; 2],
    ) {
        let slot = self.slot(b, link);
        self.unit.out.write_one(slot, record, points, media);
        self.have = record.status == Status::Converged;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scene without rays (paths dropped: a search alone) gives an empty batch, fresh or
    /// reused after one with rays (receivers out of order, solved in a spatial order, with
    /// amplitudes): no rays and no amplitudes, the receivers and offsets of the scene. Its
    /// receivers' order is then neither tested nor sorted, nor its amplitudes' pass run.
    #[test]
    fn a_scene_without_rays_gives_an_empty_batch() {
        let scene = |paths: &str| {
            let receivers: Vec<String> = (0..40)
                .map(|i| format!("[{}, {}]", (i * 17 % 40) as f64 * 0.5 - 9.0, -1 - i % 3))
                .collect();
            crate::Scene::from_json(&format!(
                r#"{{ "media": {{ "water": {{ "speed": 1500, "density": 1 }} }},
                     "interfaces": {{ "floor": {{ "points": [[-20, -5], [20, -6]] }} }},
                     "sources": [[0, -0.5]], "receivers": [{}],
                     "background": "water", "paths": {paths},
                     "amplitudes": {{ "source": "point" }} }}"#,
                receivers.join(", ")
            ))
            .unwrap()
        };
        let with_rays = scene(r#"[{ "steps": [{ "reflect": "floor" }] }]"#);
        let without = scene("[]");
        let opts = BatchOptions::default();
        let run = Run::new();
        let mut reused = Batch::default();
        let tracer = Tracer::new(&with_rays).unwrap();
        assert!(
            tracer.solves_spatially(&opts),
            "the receivers are out of order"
        );
        tracer.trace_batch_into(&opts, &run, &mut reused).unwrap();
        assert_eq!((reused.len(), reused.amplitudes.len()), (40, 40));
        let tracer = Tracer::new(&without).unwrap();
        tracer.trace_batch_into(&opts, &run, &mut reused).unwrap();
        let fresh = tracer.trace_batch(&opts, &run).unwrap();
        for batch in [&reused, &fresh] {
            assert!(batch.is_empty() && batch.amplitudes.is_empty());
            assert!(batch.points.is_empty() && batch.media.is_empty());
            assert_eq!((batch.receivers, batch.paths), (40, 0));
            assert_eq!(
                (&batch.point_offsets, &batch.media_offsets),
                (&vec![0], &vec![0])
            );
        }
    }

    #[test]
    fn morton_orders_quadrants() {
        assert!(morton(0, 0) < morton(1, 0));
        assert!(morton(1, 0) < morton(0, 1));
        assert!(morton(65535, 65535) > morton(65535, 0));
    }
}
