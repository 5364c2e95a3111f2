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
//!   [`MAX_STATIONARY_STEPS`](crate::limits::MAX_STATIONARY_STEPS) steps), every prefix
//!   pruned where no medium or no time allows a path. It counts sequences and the work of
//!   their complete searches.
//!
//! Limits count the work actually done ([`SearchLimits`], and the scene's `solver.max_work`
//! per pair's walk and, for each of its receivers, per source's tree): a source's tree that
//! reaches its limit of beams or of work, a pair's walk that spends its budget, or a search
//! whose arrivals reach their limit (in number, or in the memory they hold with their points,
//! over the whole search) stops there, and every arrival of the pairs it leaves short says
//! `complete: false`. A search is refused up front only where its table of pairs cannot be
//! allocated ([`SearchError::TooLarge`]).

mod beams;
mod diffraction;
mod sequences;
mod strategy;

use rayon::prelude::*;

use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::control::Stop;
pub use crate::scene::SearchOptions;
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
}

/// Beams one source's tree may visit before it stops (its pairs then say `complete: false`).
/// At the tree's pace (tens of millions of beams a second on one core) a few seconds.
pub const MAX_SEARCH_BEAMS: u64 = 1 << 28;

/// Arrivals a search may list before it stops: a few gigabytes of results.
pub const MAX_SEARCH_ARRIVALS: u64 = 1 << 24;

/// Bytes a search's arrivals may take at most ([`SearchLimits::memory`]), whatever memory the
/// machine has: 16 GiB.
pub const MAX_SEARCH_MEMORY: u64 = 1 << 34;

/// Bytes a search's arrivals may take where the memory available is not known: 2 GiB.
const UNKNOWN_MEMORY_SEARCH: u64 = 1 << 31;

/// The bytes one listed arrival of `steps` steps holds, as [`SearchLimits::memory`] counts
/// them: its record (thrice: the list it is gathered into grows by doubling, and the lists of
/// sources and pairs are joined into one), its points, steps, segments, arclengths and leg
/// media, and each of its five lists' allocation.
pub fn arrival_bytes(steps: usize) -> u64 {
    let steps = steps as u64;
    let record = 3 * std::mem::size_of::<SearchArrival>() as u64 + 5 * 16;
    let per_step = (std::mem::size_of::<Step>() + 2 * std::mem::size_of::<usize>() + 8) as u64;
    let point = std::mem::size_of::<crate::geom::Point>() as u64;
    record + (steps + 2) * point + steps * per_step + 8
}

/// Tuples (and assignments solved) of the complete search of one sequence between one pair,
/// beyond which that search gives up and its pair says `complete: false`.
const SEARCH_TUPLES: usize = 1 << 20;

/// Bytes the search holds per (source, receiver) pair whatever it finds: the pair's record
/// (its arrivals' count and whether it is complete). A search whose table of pairs cannot be
/// allocated is refused before it starts.
pub const PAIR_BYTES: usize = std::mem::size_of::<PairRecord>();

/// The limits of a search's work: what it does before it stops and says `complete: false`
/// on the pairs it leaves short. With the scene's `solver.max_work` (the budget of each
/// pair's walk over sequences with refractions, in the complete search's work units, one
/// more per sequence visited; and of each source's beam tree, that much for each of its
/// receivers), the one place a budget plugs in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SearchLimits {
    /// Beams per source's tree.
    pub beams: u64,
    /// Arrivals over the whole search.
    pub arrivals: u64,
    /// Bytes the arrivals listed over the whole search (every source and pair) may hold,
    /// each counted with its points ([`arrival_bytes`]): a search of long paths stops here
    /// long before [`arrivals`](Self::arrivals).
    pub memory: u64,
}

impl Default for SearchLimits {
    /// [`MAX_SEARCH_BEAMS`], [`MAX_SEARCH_ARRIVALS`], and a quarter of the memory available
    /// ([`available_memory`](crate::limits::available_memory): what the machine has free,
    /// or less under an address-space limit) for the arrivals, at most
    /// [`MAX_SEARCH_MEMORY`]: the rest is left to what the caller makes of them (written
    /// text, arrays, responses).
    fn default() -> SearchLimits {
        let memory = crate::control::available_memory()
            .map_or(UNKNOWN_MEMORY_SEARCH, |have| have / 4)
            .min(MAX_SEARCH_MEMORY);
        SearchLimits {
            beams: MAX_SEARCH_BEAMS,
            arrivals: MAX_SEARCH_ARRIVALS,
            memory,
        }
    }
}

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

/// Work a search has done since its last report, as
/// [`search_with`](Tracer::search_with) tells it (from the worker threads).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SearchProgress {
    /// Beams visited.
    pub beams: u64,
    /// Pairs whose walk over sequences is finished.
    pub pairs: usize,
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

/// What every part of one search shares: its limits, its count of arrivals, its progress
/// and its stop request.
#[derive(Clone, Copy)]
struct Control<'a> {
    limits: &'a SearchLimits,
    listed: &'a ArrivalCount,
    progress: &'a (dyn Fn(SearchProgress) + Sync),
    stop: Option<&'a Stop>,
}

impl Control<'_> {
    /// Whether the search was asked to stop.
    fn stopped(&self) -> bool {
        self.stop.is_some_and(Stop::requested)
    }
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
    fn new(limits: &SearchLimits) -> ArrivalCount {
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
        let bytes = arrival_bytes(steps);
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
    /// ones, when the search asks), ordered by source, receiver and time. See
    /// [`search_with`](Self::search_with) for how, for its limits and for what else it tells.
    ///
    /// ```
    /// use eigenray::{Scene, Tracer};
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
    /// let arrivals = Tracer::new(&scene).unwrap().search().unwrap();
    /// assert_eq!(arrivals.len(), 5);
    /// assert!(arrivals[0].steps.is_empty()); // the direct ray comes first
    /// ```
    ///
    /// # Errors
    /// As [`search_with`](Self::search_with).
    pub fn search(&self) -> Result<Vec<SearchArrival>, SearchError> {
        Ok(self
            .search_with(&SearchLimits::default(), &|_| {}, None)?
            .arrivals)
    }

    /// [`search`](Self::search) within `limits` (and each pair's walk within the scene's
    /// `solver.max_work`), with everything the search did ([`SearchReport`]); `progress` hears
    /// of the work as it is done, from the worker threads. When `stop` is requested (from
    /// another thread), the trees and walks under way stop and those not begun are skipped:
    /// the result is then short (the caller that asked discards it).
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
    /// use eigenray::{Scene, Tracer, search::SearchLimits};
    /// // The same square room as one closed polyline, every arrival up to time 3.
    /// let scene = Scene::from_json(r#"{
    ///     "media": { "air": { "speed": 1.0, "at": [0.5, 0.5] } },
    ///     "interfaces": {
    ///         "room": { "points": [[0, 0], [1, 0], [1, 1], [0, 1]], "closed": true } },
    ///     "sources": [[0.3, 0.4]], "receivers": [[0.7, 0.5]],
    ///     "search": { "max_time": 3 }
    /// }"#).unwrap();
    /// let tracer = Tracer::new(&scene).unwrap();
    /// let report = tracer.search_with(&SearchLimits::default(), &|_| {}, None).unwrap();
    /// assert_eq!(report.incomplete_pairs, 0);
    /// assert!(report.arrivals.iter().all(|a| a.arrival.time <= 3.0 && a.complete));
    /// assert!(report.arrivals.iter().any(|a| a.steps.len() >= 4));
    /// ```
    ///
    /// # Errors
    /// [`SearchError::NoSearch`] without a `search` section; [`SearchError::TooLarge`] when
    /// the table of pairs alone cannot be allocated.
    pub fn search_with(
        &self,
        limits: &SearchLimits,
        progress: &(dyn Fn(SearchProgress) + Sync),
        stop: Option<&Stop>,
    ) -> Result<SearchReport, SearchError> {
        let scene = self.scene();
        let options = scene.search().ok_or(SearchError::NoSearch)?;
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
        let listed = ArrivalCount::new(limits);
        let mut report = SearchReport::default();
        let control = Control {
            limits,
            listed: &listed,
            progress,
            stop,
        };
        let trees = self.beam_trees(options, &control);
        let walks = self.walks(options, &control);
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
            for (pair, walk) in self.diffraction_pairs(options, &control) {
                report.work += walk.work;
                pairs[pair].complete &= walk.complete;
                arrivals.extend(walk.arrivals);
            }
            diffraction::drop_listed_twice(self, &mut arrivals);
        }
        for a in &mut arrivals {
            a.complete = pairs[a.source * nr + a.receiver].complete;
        }
        report.incomplete_pairs = pairs.iter().filter(|p| !p.complete).count();
        sort_arrivals(&mut arrivals);
        if scene.amplitudes().is_some() {
            arrivals.par_iter_mut().for_each(|s| {
                self.arrival_amplitudes(&s.steps, std::slice::from_mut(&mut s.arrival))
            });
        }
        report.arrivals = arrivals;
        Ok(report)
    }

    /// Whether an arrival of this status is listed.
    fn listed(status: Status, options: &SearchOptions) -> bool {
        status == Status::Converged
            || (options.vertex && status == Status::Vertex)
            || (options.obstructed && status == Status::Obstructed)
    }
}

/// Orders arrivals by pair and time; ties (none but equal times) by the number of steps, the
/// sequence and the segments, for a fixed order.
fn sort_arrivals(arrivals: &mut [SearchArrival]) {
    fn key(s: &[Step]) -> impl Iterator<Item = (usize, bool, Option<usize>)> + '_ {
        s.iter()
            .map(|t| (t.interface, t.kind == StepKind::Refract, t.kind.vertex()))
    }
    arrivals.par_sort_unstable_by(|a, b| {
        (a.source, a.receiver)
            .cmp(&(b.source, b.receiver))
            .then(a.arrival.time.total_cmp(&b.arrival.time))
            .then_with(|| a.steps.len().cmp(&b.steps.len()))
            .then_with(|| key(&a.steps).cmp(key(&b.steps)))
            .then_with(|| a.arrival.segments.cmp(&b.arrival.segments))
            .then_with(|| a.arrival.status.as_str().cmp(b.arrival.status.as_str()))
    });
}
