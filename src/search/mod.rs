//! The automatic search (`"search"`, [`Tracer::search`]): every arrival of up to `max_steps`
//! steps, or up to `max_time`, or within both, per (source, receiver) pair. Its results are
//! [`SearchArrival`]s.
//!
//! Two strategies share the work, each with its own counter of the work it does; which
//! lists which arrivals of which sequence is one function, `strategy.rs` (`owner`), whose
//! tests check that every sequence is claimed exactly once:
//!
//! - **The beam tree** (`beams.rs`, over `trace/mirrors.rs`): every reflect-only sequence,
//!   one tree per source shared by all its receivers, each segment of each reflecting
//!   interface (open or closed, any number of segments) a wall. Its `converged` (and
//!   `obstructed`) arrivals are the specular paths of those sequences. It counts beams.
//! - **The walk over sequences** (`sequences.rs`): sequences with refractions, and with
//!   `vertex` the edge-held arrivals of reflect-only ones through polylines with vertices,
//!   each searched completely per pair (as [`Tracer::stationary_paths`] does, at most
//!   [`MAX_STATIONARY_STEPS`](crate::scene::MAX_STATIONARY_STEPS) steps), every prefix
//!   pruned where no medium or no time allows a path. It counts sequences and the work of
//!   their complete searches.
//!
//! In a scene with curved legs (a medium with a gradient) there are no images: the walk
//! takes every sequence, the direct ray included, each searched from a grid of starts
//! (`Tracer::curved_paths_of`), which is no proof (every such pair says `complete: false`).
//!
//! Limits count the work actually done (the [`Run`]'s [`Limits`](crate::options::Limits), and
//! the scene's `solver.max_work` per pair's walk and, for each of its receivers, per source's
//! tree): a source's tree that reaches its limit of beams or of work, a pair's walk that
//! spends its budget, or a search whose arrivals reach their limit (in number, or in the
//! memory they hold with their points, over the whole search) stops there, and every arrival
//! of the pairs it leaves short says
//! `complete: false`. A search is refused up front only where its table of pairs cannot be
//! allocated ([`SearchError::TooLarge`]).

mod beams;
mod diffraction;
mod extruded;
mod profile;
mod sequences;
mod strategy;

use rayon::prelude::*;

use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::Amplitude;
use crate::options::Run;
use crate::scene::SearchOptions;
use crate::scene::{Step, StepKind};
use crate::trace::{Arrival, Status, Tracer};

/// One arrival of a scene's automatic `search`: a stationary path of a step sequence that the
/// search generated, between one source and one receiver.
#[derive(Clone, Debug, PartialEq)]
pub struct SearchArrival {
    /// Source index.
    pub source: usize,
    /// Receiver index.
    pub receiver: usize,
    /// The step sequence (empty: the direct ray).
    pub steps: Vec<Step>,
    /// The stationary path, with its status, time, points and leg media.
    pub arrival: Arrival,
    /// Whether the search of its pair was complete: `false` where it stopped at a limit
    /// (its list may then be short).
    pub complete: bool,
    /// In an extruded scene (`"extrusion"`), the height z of each of `arrival.points` (whose
    /// x and y are the plan's): the 3-D path. Its `steps` then list the floor and ceiling
    /// reflections among the walls', the floor as interface `interfaces().len()` and the
    /// ceiling as the one after it (their `segments` 0, their `parameters` NaN). Empty
    /// otherwise.
    pub heights: Vec<f64>,
}

impl SearchArrival {
    /// The arrival as a streaming search hands it on (its points left out).
    pub fn streamed(&self) -> StreamedArrival {
        StreamedArrival {
            source: self.source,
            receiver: self.receiver,
            steps: self.steps.len(),
            diffractions: diffractions(&self.steps),
            vertical_reflections: self.vertical_reflections(),
            status: self.arrival.status,
            time: self.arrival.time,
            amplitude: self.arrival.amplitude,
        }
    }

    /// Its floor and ceiling reflections (in an extruded scene; 0 otherwise): the steps that
    /// reflect with no wall parameter (NaN), as `heights` documents them.
    pub fn vertical_reflections(&self) -> usize {
        if self.heights.is_empty() {
            return 0;
        }
        (self.steps.iter().zip(&self.arrival.parameters))
            .filter(|(s, t)| s.kind == StepKind::Reflect && t.is_nan())
            .count()
    }
}

/// The `diffract` steps of `steps`.
pub(crate) fn diffractions(steps: &[Step]) -> usize {
    steps.iter().filter(|s| s.kind.vertex().is_some()).count()
}

/// One arrival as a streaming search ([`Tracer::search_into`]) hands it on, the moment it
/// is found: between which pair, when, how strongly. Its points are not kept.
#[derive(Clone, Copy, Debug)]
pub struct StreamedArrival {
    /// Source index.
    pub source: usize,
    /// Receiver index.
    pub receiver: usize,
    /// Steps of its sequence (0: the direct ray).
    pub steps: usize,
    /// Of those, the `diffract` steps (0: a specular path).
    pub diffractions: usize,
    /// Of those, the floor and ceiling reflections (in an extruded scene; 0 otherwise).
    pub vertical_reflections: usize,
    /// `converged`, or (when the search lists them) `obstructed` or `vertex`.
    pub status: Status,
    /// Travel time.
    pub time: f64,
    /// Its amplitude, when the scene asks for amplitudes (as [`Tracer::amplitude_of`] gives
    /// it, bit for bit the one [`Tracer::search`] lists; a rectangular room's image paths
    /// in closed form, to 1e-12 relative: see [`Tracer::search_into`]).
    pub amplitude: Option<Amplitude>,
}

/// Where a streaming search ([`Tracer::search_into_sink`]) hands its arrivals: one at a
/// time, or several at once (each batch's arrivals in the order found). Called from the
/// search's threads.
pub trait ArrivalSink: Sync {
    /// Takes one arrival.
    fn arrival(&self, arrival: StreamedArrival);

    /// Takes `batch`, in order: by default one at a time.
    fn arrivals(&self, batch: &[StreamedArrival]) {
        for &a in batch {
            self.arrival(a);
        }
    }
}

/// A sink of one arrival at a time ([`Tracer::search_into`]'s).
struct EachArrival<'a>(&'a (dyn Fn(StreamedArrival) + Sync));

impl ArrivalSink for EachArrival<'_> {
    #[inline]
    fn arrival(&self, arrival: StreamedArrival) {
        (self.0)(arrival);
    }
}

/// What a streaming search ([`Tracer::search_into`]) did: [`SearchReport`] without the
/// arrivals, which went to the caller's sink.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamReport {
    /// Arrivals handed to the sink.
    pub arrivals: u64,
    /// Beams the trees visited (as [`SearchReport::beams`]).
    pub beams: u64,
    /// Paths the trees validated (as [`SearchReport::leaves`]).
    pub leaves: u64,
    /// Work the trees did (as [`SearchReport::tree_work`]).
    pub tree_work: u64,
    /// Work the walks did (as [`SearchReport::work`]).
    pub work: u64,
    /// Pairs whose search stopped at a limit (some of their arrivals may be missing).
    pub incomplete_pairs: usize,
}

/// The bytes one listed arrival of `steps` steps holds, as a search counts them against
/// [`Limits::memory`](crate::options::Limits::memory): its record (thrice: the list it is
/// gathered into grows by doubling, and the lists of sources and pairs are joined into one),
/// its points, steps, segments, arclengths and leg media, and each of its five lists'
/// allocation.
pub fn arrival_bytes(steps: usize) -> u64 {
    let steps = steps as u64;
    let record = 3 * std::mem::size_of::<SearchArrival>() as u64 + 5 * 16;
    let per_step = (std::mem::size_of::<Step>() + 2 * std::mem::size_of::<usize>() + 8) as u64;
    let point = std::mem::size_of::<crate::geom::Point>() as u64;
    record + (steps + 2) * point + steps * per_step + 8
}

/// Bytes the search holds per (source, receiver) pair whatever it finds: the pair's record
/// (its arrivals' count and whether it is complete). A search whose table of pairs cannot be
/// allocated is refused before it starts.
pub const PAIR_BYTES: usize = std::mem::size_of::<PairRecord>();

/// Everything a search found and did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SearchReport {
    /// The arrivals, ordered by source, receiver and time.
    pub arrivals: Vec<SearchArrival>,
    /// Beams the trees visited (nodes below their roots), over all sources.
    pub beams: u64,
    /// Paths the trees validated (receivers in a beam and within the time bound).
    pub leaves: u64,
    /// Work the trees did, over all sources, in the units of `solver.max_work` (one per
    /// child wall tried, one per segment an occlusion test weighs, one per leg validated):
    /// each source's tree stops at `solver.max_work` for each of its receivers.
    pub tree_work: u64,
    /// Work the walks did over all pairs: sequences visited plus the work units of their
    /// complete searches (as `solver.max_work` counts them).
    pub work: u64,
    /// Pairs whose search stopped at a limit (their arrivals say `complete: false`).
    pub incomplete_pairs: usize,
}

/// Why a scene's `search` cannot run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SearchError {
    /// The scene has no `search` section.
    NoSearch,
    /// The table of (source, receiver) pairs alone ([`PAIR_BYTES`] each) cannot be allocated.
    ///
    /// How to fix: fewer sources or receivers per search.
    TooLarge {
        /// Sources times receivers.
        pairs: u128,
    },
}

impl fmt::Display for SearchError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SearchError::NoSearch => f.write_str("the scene has no `search` section"),
            SearchError::TooLarge { pairs } => write!(
                f,
                "{pairs} source-receiver pairs: their table alone ({PAIR_BYTES} bytes each) \
                 does not fit in memory (search fewer sources and receivers at a time)"
            ),
        }
    }
}

impl std::error::Error for SearchError {}

/// What every part of one search shares: its run (limits, budget, progress, stop request)
/// and its count of arrivals.
#[derive(Clone, Copy)]
struct Control<'a> {
    run: &'a Run,
    listed: &'a ArrivalCount,
    /// Where each arrival goes the moment it is found ([`Tracer::search_into`]); `None`:
    /// the arrivals are listed with their points ([`Tracer::search`]).
    sink: Option<&'a dyn ArrivalSink>,
    /// Where each arrival goes with its points the moment it is found, instead of being
    /// listed or streamed (an extruded room's plan paths, `extruded.rs`); it says whether to
    /// go on.
    paths: Option<&'a (dyn Fn(SearchArrival) -> bool + Sync)>,
}

/// What the search keeps per pair.
#[derive(Clone, Copy, Debug, Default)]
struct PairRecord {
    /// Whether its search was complete.
    complete: bool,
}

/// The arrivals listed so far over the whole search, and the bytes they hold, against their
/// limits.
struct ArrivalCount {
    count: AtomicU64,
    limit: u64,
    bytes: AtomicU64,
    memory: u64,
}

impl ArrivalCount {
    fn new(limits: &crate::options::Limits) -> ArrivalCount {
        ArrivalCount {
            count: AtomicU64::new(0),
            limit: limits.arrivals,
            bytes: AtomicU64::new(0),
            memory: limits.memory,
        }
    }

    /// Takes one more arrival of `steps` steps; `false` (and nothing taken) when that passes
    /// the limit of arrivals or of memory.
    fn take(&self, steps: usize) -> bool {
        self.take_bytes(arrival_bytes(steps))
    }

    /// Counts one more streamed arrival, which holds nothing: no limit.
    fn stream(&self) {
        self.count.fetch_add(1, Ordering::Relaxed);
    }

    /// Counts `n` more streamed arrivals at once.
    fn stream_many(&self, n: usize) {
        self.count.fetch_add(n as u64, Ordering::Relaxed);
    }

    /// Takes one more arrival that holds `bytes`; `false` (and nothing taken) when that
    /// passes the limit of arrivals or of memory.
    fn take_bytes(&self, bytes: u64) -> bool {
        let before = self.count.fetch_add(1, Ordering::Relaxed);
        let held = self.bytes.fetch_add(bytes, Ordering::Relaxed);
        if before >= self.limit || held.saturating_add(bytes) > self.memory {
            self.count.fetch_sub(1, Ordering::Relaxed);
            self.bytes.fetch_sub(bytes, Ordering::Relaxed);
            return false;
        }
        true
    }
}

impl Tracer {
    /// The arrivals of the scene's `search`: every step sequence of up to `max_steps` steps
    /// (or every arrival up to `max_time`, or within both bounds) through the allowed
    /// interfaces and kinds, with its leg media from the regions, for every (source,
    /// receiver) pair. Listed: every `converged` arrival (and `obstructed` ones, and `vertex`
    /// ones, when the search asks), ordered by source, receiver and time, with everything
    /// the search did ([`SearchReport`]).
    ///
    /// The search runs within `run`'s limits (beams per source's tree, arrivals, the budget of
    /// the whole call: [`Limits`](crate::options::Limits)) and each pair's walk within the
    /// scene's `solver.max_work`; `run` hears of the work as it is done, from the worker
    /// threads (beams, and each pair's walk as one item). When a stop is requested (from
    /// another thread), the trees and walks under way stop and those not begun are skipped:
    /// every pair then says `complete: false` (and the arrivals have no amplitudes: the caller
    /// that asked discards them).
    ///
    /// ```
    /// use eigenray::{Scene, Tracer, options::Run};
    /// // A square room, each wall its own interface: the direct ray and one reflection off
    /// // each wall.
    /// let scene = Scene::from_json(r#"{
    ///     "media": { "air": { "speed": 1.0, "at": [0.5, 0.5] } },
    ///     "interfaces": {
    ///         "s": { "points": [[0, 0], [1, 0]] }, "e": { "points": [[1, 0], [1, 1]] },
    ///         "n": { "points": [[1, 1], [0, 1]] }, "w": { "points": [[0, 1], [0, 0]] } },
    ///     "sources": [[0.3, 0.4]], "receivers": [[0.7, 0.5]],
    ///     "search": { "max_steps": 1, "refract": false }
    /// }"#).unwrap();
    /// let arrivals = Tracer::new(&scene).unwrap().search(&Run::new()).unwrap().arrivals;
    /// assert_eq!(arrivals.len(), 5);
    /// assert!(arrivals[0].steps.is_empty()); // the direct ray comes first
    /// ```
    ///
    /// Reflect-only sequences go through the beam tree, one per source in parallel, shared by
    /// its receivers: each segment of each reflecting interface is a wall, each node an image
    /// of the source and the beam of rays that can reach it, pruned where the beam misses
    /// every wall or where the image lies too far from the receivers to arrive by `max_time`.
    /// Sequences with refractions (and with `vertex`, the edge-held arrivals of reflect-only
    /// ones) are searched completely one by one per pair in parallel, each prefix pruned
    /// where no medium or no time allows a path. A pair whose search stopped at a limit says
    /// `complete: false` on every arrival.
    ///
    /// ```
    /// use eigenray::{Scene, Tracer, options::Run};
    /// // The same square room as one closed polyline, every arrival up to time 3.
    /// let scene = Scene::from_json(r#"{
    ///     "media": { "air": { "speed": 1.0, "at": [0.5, 0.5] } },
    ///     "interfaces": {
    ///         "room": { "points": [[0, 0], [1, 0], [1, 1], [0, 1]], "closed": true } },
    ///     "sources": [[0.3, 0.4]], "receivers": [[0.7, 0.5]],
    ///     "search": { "max_time": 3 }
    /// }"#).unwrap();
    /// let tracer = Tracer::new(&scene).unwrap();
    /// let report = tracer.search(&Run::new()).unwrap();
    /// assert_eq!(report.incomplete_pairs, 0);
    /// assert!(report.arrivals.iter().all(|a| a.arrival.time <= 3.0 && a.complete));
    /// assert!(report.arrivals.iter().any(|a| a.steps.len() >= 4));
    /// ```
    ///
    /// # Errors
    /// [`SearchError::NoSearch`] without a `search` section; [`SearchError::TooLarge`] when
    /// the table of pairs alone cannot be allocated.
    pub fn search(&self, run: &Run) -> Result<SearchReport, SearchError> {
        let scene = self.scene();
        let options = scene.search().ok_or(SearchError::NoSearch)?;
        if let Some(x) = scene.extrusion() {
            return self.search_extruded(options, run, x);
        }
        let nr = scene.receivers().len();
        let mut pairs = self.pair_table()?;
        let listed = ArrivalCount::new(&run.limits);
        let control = Control {
            run,
            listed: &listed,
            sink: None,
            paths: None,
        };
        if scene.media().iter().any(|m| m.profile.is_some()) {
            // A waveguide through a profile medium: its own search, sampled (never
            // complete), each arrival with its amplitude.
            let (mut report, mut arrivals) = self.search_profile(options, &control);
            sort_arrivals(&mut arrivals);
            report.arrivals = arrivals;
            return Ok(report);
        }
        let (mut report, mut arrivals) = self.strategies(options, &control, &mut pairs);
        for a in &mut arrivals {
            a.complete = pairs[a.source * nr + a.receiver].complete;
        }
        if run.stop_requested() {
            report.arrivals = arrivals;
            return Ok(report);
        }
        sort_arrivals(&mut arrivals);
        if scene.amplitudes().is_some() {
            arrivals.par_iter_mut().for_each(|s| {
                self.arrival_amplitudes(&s.steps, std::slice::from_mut(&mut s.arrival))
            });
        }
        report.arrivals = arrivals;
        Ok(report)
    }

    /// The scene's `search` as [`search`](Self::search) runs it, each arrival handed to `sink`
    /// the moment it is found instead of listed: nothing of an arrival is kept, so the
    /// memory is the search's working set (the trees' stacks, one walk's sequence per
    /// thread) whatever the number of arrivals. The arrivals are those
    /// [`search`](Self::search) lists, with the same times and (bit for bit) amplitudes,
    /// except in a rectangular room (the image lattice), whose image paths come in closed
    /// form without their points (time and amplitude from the unfolded line, within 1e-12
    /// relative of the listed ones; `trace/mirrors/shoebox.rs`). They come in
    /// the order found, not by time: a tree's arrivals reach `sink` from the thread of its
    /// source, a walk's from the thread of its pair, every tree's before any walk's, so that
    /// the arrivals of one pair come in one fixed order. Streamed arrivals count against
    /// neither the run's limit of arrivals nor its memory (they hold none); the run, its
    /// budget, its limit of beams and `solver.max_work` bound the search as they bound
    /// [`search`](Self::search).
    ///
    /// ```
    /// use std::sync::Mutex;
    /// use eigenray::{Scene, Tracer, options::Run};
    /// let scene = Scene::from_json(r#"{
    ///     "media": { "air": { "speed": 1.0, "at": [0.5, 0.5] } },
    ///     "interfaces": {
    ///         "room": { "points": [[0, 0], [1, 0], [1, 1], [0, 1]], "closed": true } },
    ///     "sources": [[0.3, 0.4]], "receivers": [[0.7, 0.5]],
    ///     "search": { "max_time": 3 }
    /// }"#).unwrap();
    /// let tracer = Tracer::new(&scene).unwrap();
    /// let last = Mutex::new(0.0f64);
    /// let report = tracer
    ///     .search_into(&Run::new(), &|a| {
    ///         let mut last = last.lock().unwrap();
    ///         *last = last.max(a.time);
    ///     })
    ///     .unwrap();
    /// let listed = tracer.search(&Run::new()).unwrap().arrivals;
    /// assert_eq!(report.arrivals, listed.len() as u64);
    /// // (A rectangular room: the times in closed form, to round-off.)
    /// let latest = listed.iter().map(|a| a.arrival.time).fold(0.0, f64::max);
    /// assert!((*last.lock().unwrap() - latest).abs() <= 1e-12 * latest);
    /// ```
    ///
    /// # Errors
    /// As [`search`](Self::search).
    pub fn search_into(
        &self,
        run: &Run,
        sink: &(dyn Fn(StreamedArrival) + Sync),
    ) -> Result<StreamReport, SearchError> {
        self.search_into_sink(run, &EachArrival(sink))
    }

    /// [`search_into`](Self::search_into) with a sink that may take the arrivals several at
    /// a time ([`ArrivalSink::arrivals`]): the same arrivals, some of them handed on in
    /// batches (a beam tree's closed-form ones, `search/beams.rs`), so that a sink that locks
    /// or counts does so once a batch.
    ///
    /// # Errors
    /// As [`search`](Self::search).
    pub fn search_into_sink(
        &self,
        run: &Run,
        sink: &dyn ArrivalSink,
    ) -> Result<StreamReport, SearchError> {
        let scene = self.scene();
        let options = scene.search().ok_or(SearchError::NoSearch)?;
        if let Some(x) = scene.extrusion() {
            return self.search_extruded_into(options, run, x, sink);
        }
        let mut pairs = self.pair_table()?;
        let listed = ArrivalCount::new(&run.limits);
        let control = Control {
            run,
            listed: &listed,
            sink: Some(sink),
            paths: None,
        };
        let (report, _) = if scene.media().iter().any(|m| m.profile.is_some()) {
            self.search_profile(options, &control)
        } else {
            self.strategies(options, &control, &mut pairs)
        };
        Ok(StreamReport {
            arrivals: listed.count.load(Ordering::Relaxed),
            beams: report.beams,
            leaves: report.leaves,
            tree_work: report.tree_work,
            work: report.work,
            incomplete_pairs: report.incomplete_pairs,
        })
    }

    /// The table of (source, receiver) pairs, each complete until a strategy says not.
    fn pair_table(&self) -> Result<Vec<PairRecord>, SearchError> {
        let scene = self.scene();
        let (ns, nr) = (scene.sources().len(), scene.receivers().len());
        let too_large = || SearchError::TooLarge {
            pairs: ns as u128 * nr as u128,
        };
        let count = ns
            .checked_mul(nr)
            .filter(|c| {
                c.checked_mul(PAIR_BYTES)
                    .is_some_and(|b| b <= isize::MAX as usize)
            })
            .ok_or_else(too_large)?;
        let mut pairs: Vec<PairRecord> = Vec::new();
        pairs.try_reserve_exact(count).map_err(|_| too_large())?;
        pairs.resize(count, PairRecord { complete: true });
        Ok(pairs)
    }

    /// Both strategies, the trees then the walks: what they did, each pair's completeness
    /// in `pairs`, and the arrivals they listed (none when `control` streams them).
    fn strategies(
        &self,
        options: &SearchOptions,
        control: &Control<'_>,
        pairs: &mut [PairRecord],
    ) -> (SearchReport, Vec<SearchArrival>) {
        let nr = self.scene().receivers().len();
        let mut report = SearchReport::default();
        // Curved legs have no images: the walk takes every sequence (`strategy.rs`).
        let trees = if self.scene().curved() {
            Vec::new()
        } else {
            self.beam_trees(options, control)
        };
        let walks = self.walks(options, control);
        let mut arrivals = Vec::new();
        for (source, tree) in trees.into_iter().enumerate() {
            report.beams += tree.stats.beams;
            report.leaves += tree.stats.leaves;
            report.tree_work += tree.stats.work;
            if tree.stats.stopped {
                for p in &mut pairs[source * nr..(source + 1) * nr] {
                    p.complete = false;
                }
            }
            arrivals.extend(tree.arrivals);
        }
        for (pair, walk) in walks {
            report.work += walk.work;
            pairs[pair].complete &= walk.complete;
            arrivals.extend(walk.arrivals);
        }
        if options.diffraction {
            let diffracted = self.diffraction_search(options, control);
            report.work += diffracted.work;
            for (p, complete) in pairs.iter_mut().zip(&diffracted.complete) {
                p.complete &= complete;
            }
            // Streamed, each diffracted arrival went to the sink with its amplitude (the
            // edge-held `vertex` entries it repeats have none, so no response counts them
            // twice); listed, the `vertex` entries of the same paths go.
            if control.sink.is_none() {
                arrivals.extend(diffracted.arrivals);
                diffraction::drop_listed_twice(self, &mut arrivals);
            }
        }
        if control.run.stop_requested() {
            // Asked to stop: the result is discarded, every pair is short.
            pairs.iter_mut().for_each(|p| p.complete = false);
        }
        report.incomplete_pairs = pairs.iter().filter(|p| !p.complete).count();
        (report, arrivals)
    }

    /// Whether an arrival of this status is listed.
    fn listed(status: Status, options: &SearchOptions) -> bool {
        status == Status::Converged
            || (options.vertex && status == Status::Vertex)
            || (options.obstructed && status == Status::Obstructed)
    }
}

/// The order of arrivals: by pair and time; ties (none but equal times) by the number of
/// steps, the sequence and the segments, for a fixed order.
fn arrival_order(a: &SearchArrival, b: &SearchArrival) -> std::cmp::Ordering {
    fn key(s: &[Step]) -> impl Iterator<Item = (usize, bool, Option<usize>)> + '_ {
        s.iter()
            .map(|t| (t.interface, t.kind == StepKind::Refract, t.kind.vertex()))
    }
    (a.source, a.receiver)
        .cmp(&(b.source, b.receiver))
        .then(a.arrival.time.total_cmp(&b.arrival.time))
        .then_with(|| a.steps.len().cmp(&b.steps.len()))
        .then_with(|| key(&a.steps).cmp(key(&b.steps)))
        .then_with(|| a.arrival.segments.cmp(&b.arrival.segments))
        .then_with(|| a.arrival.status.as_str().cmp(b.arrival.status.as_str()))
}

/// Orders arrivals by [`arrival_order`]: as `par_sort_unstable_by` would, to the order of
/// ties.
fn sort_arrivals(arrivals: &mut [SearchArrival]) {
    // Each arrival's place in the order's first three terms, as one number: its pair (each
    // index below 2³², as every scene's are) and its time's bits as `total_cmp` orders them.
    let head = |a: &SearchArrival| -> Option<u128> {
        let pair = (
            u32::try_from(a.source).ok()?,
            u32::try_from(a.receiver).ok()?,
        );
        let bits = a.arrival.time.to_bits() as i64;
        let time = (bits ^ (((bits >> 63) as u64) >> 1) as i64) as u64 ^ (1 << 63);
        Some(u128::from(pair.0) << 96 | u128::from(pair.1) << 64 | u128::from(time))
    };
    // The indices sorted, with those numbers: the same sort makes the same comparisons with
    // the same outcomes (the numbers compare as the order's first terms, the rest of it
    // decides their ties), so it leaves them in the order it would leave the arrivals in
    // (ties too), moving a few words for each move of a whole arrival.
    let mut index: Vec<(u128, usize)> = Vec::with_capacity(arrivals.len());
    for (i, a) in arrivals.iter().enumerate() {
        match head(a) {
            Some(h) => index.push((h, i)),
            None => {
                arrivals.par_sort_unstable_by(arrival_order);
                return;
            }
        }
    }
    index.par_sort_unstable_by(|&(h, i), &(g, j)| {
        h.cmp(&g)
            .then_with(|| arrival_order(&arrivals[i], &arrivals[j]))
    });
    let mut index: Vec<usize> = index.into_iter().map(|(_, i)| i).collect();
    // Arrival `index[k]` to place `k`, cycle by cycle (each placed index marks itself).
    for start in 0..index.len() {
        let mut k = start;
        while index[k] != k {
            let from = index[k];
            index[k] = k;
            if from == start {
                break;
            }
            arrivals.swap(k, from);
            k = from;
        }
    }
}

#[cfg(test)]
mod sort_tests {
    use super::*;
    use crate::geom::Point;

    /// An arrival of pair (`source`, `receiver`) at `time` with `steps` reflections off
    /// interface 0, told apart by `mark` (its first point), which the order does not see.
    fn arrival(
        source: usize,
        receiver: usize,
        time: f64,
        steps: usize,
        mark: f64,
    ) -> SearchArrival {
        SearchArrival {
            source,
            receiver,
            steps: vec![
                Step {
                    kind: StepKind::Reflect,
                    interface: 0,
                };
                steps
            ],
            arrival: Arrival {
                status: Status::Converged,
                time,
                points: vec![Point::new(mark, 0.0)],
                parameters: Vec::new(),
                segments: vec![0; steps],
                media: Vec::new(),
                iterations: 0,
                reason: None,
                kink: None,
                residual: f64::NAN,
                amplitude: None,
                turns: None,
                caustics: None,
                launch_angle: None,
            },
            complete: true,
            heights: Vec::new(),
        }
    }

    /// `sort_arrivals` (indices sorted by a number for the pair and time, then the arrivals
    /// moved once) leaves arrivals in the order that sorting them in place leaves them in,
    /// ties (arrivals equal to the order but told apart by their points) included, at
    /// lengths on both sides of the parallel sort's sequential cut-off and of its insertion
    /// sort's.
    ///
    /// Mutants caught: the permutation applied inverted (`arrivals[k]` to `index[k]`), the
    /// time's number not flipped for negative times (or its sign bit not flipped).
    #[test]
    fn sorting_indices_is_sorting_the_arrivals() {
        let mut rng = crate::demo::SplitMix64(17);
        for n in [0, 1, 2, 7, 19, 20, 21, 60, 500, 2_001, 6_000] {
            let arrivals: Vec<SearchArrival> = (0..n)
                .map(|i| {
                    let pick = |k: u64, rng: &mut crate::demo::SplitMix64| {
                        (rng.next_f64() * k as f64) as usize
                    };
                    let (s, r) = (pick(2, &mut rng), pick(3, &mut rng));
                    // Few times and step counts: many ties; times of both signs, and both
                    // zeros, which `total_cmp` tells apart.
                    let time = match i % 7 {
                        0 => -0.0,
                        _ => pick(8, &mut rng) as f64 * 0.125 - 0.5,
                    };
                    let steps = pick(3, &mut rng);
                    arrival(s, r, time, steps, i as f64)
                })
                .collect();
            let mut direct = arrivals.clone();
            direct.par_sort_unstable_by(arrival_order);
            let mut sorted = arrivals;
            sort_arrivals(&mut sorted);
            let marks = |a: &[SearchArrival]| -> Vec<f64> {
                a.iter().map(|a| a.arrival.points[0].x).collect()
            };
            assert_eq!(marks(&sorted), marks(&direct), "{n} arrivals");
        }
    }
}
