//! The automatic search over step sequences (`"search"`, [`Tracer::search`]): every sequence
//! up to `max_steps` through the allowed interfaces and kinds, each searched completely per
//! (source, receiver) pair in parallel; rooms of one-segment walls through the image-source
//! tree. Its results are [`SearchArrival`]s.

use rayon::prelude::*;

use std::fmt;

use crate::control::{Stop, within};
use crate::geom::Point;
pub use crate::scene::SearchOptions;
use crate::scene::{MAX_STATIONARY_STEPS, Step, StepKind};
use crate::trace::{
    Arrival, MirrorArrival, MirrorScratch, MirrorWalls, SearchBudget, Sequence, Status, Tracer,
};

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
    /// Whether the search that found it was complete: `false` where it stopped at a limit
    /// (its list may then be short).
    pub complete: bool,
}

/// Tuples (and assignments solved) of the search of one sequence between one pair, beyond
/// which that search gives up and its arrivals say `complete: false`.
const SEARCH_TUPLES: usize = 1 << 20;

/// Sequence-and-pair searches a `search` may ask for: beyond it the search is refused before
/// it starts (each one is a complete search of one sequence between one source and one
/// receiver).
pub const MAX_SEARCH_WORK: u64 = 5_000_000;

/// Why a scene's `search` cannot run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SearchError {
    /// The scene has no `search` section.
    NoSearch,
    /// More sequences × (source, receiver) pairs than [`MAX_SEARCH_WORK`].
    ///
    /// How to fix: fewer `max_steps`, fewer `interfaces`, or fewer sources and receivers.
    TooLarge {
        /// Step sequences the search would generate.
        sequences: u64,
        /// (source, receiver) pairs.
        pairs: u64,
    },
}

impl fmt::Display for SearchError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SearchError::NoSearch => f.write_str("the scene has no `search` section"),
            SearchError::TooLarge { sequences, pairs } => write!(
                f,
                "{sequences} step sequences for {pairs} source-receiver pairs: more than the \
                 {MAX_SEARCH_WORK} searches allowed (lower `max_steps`, list fewer \
                 `interfaces`, or use fewer sources and receivers)"
            ),
        }
    }
}

impl std::error::Error for SearchError {}

/// The steps a search may take next, in a fixed order.
fn step_choices(options: &SearchOptions) -> Vec<Step> {
    let mut out = Vec::new();
    for &interface in &options.interfaces {
        if options.reflect {
            out.push(Step {
                kind: StepKind::Reflect,
                interface,
            });
        }
        if options.refract {
            out.push(Step {
                kind: StepKind::Refract,
                interface,
            });
        }
    }
    out
}

/// Calls `visit` with every step sequence of 0 to `max_steps` steps from `choices`, depth
/// first, each extending `steps` (a step that reflects off the one-segment interface of the
/// step before it is left out: its two points would lie on one line, where no path exists).
fn for_each_sequence(
    scene: &crate::Scene,
    choices: &[Step],
    max_steps: usize,
    steps: &mut Vec<Step>,
    visit: &mut impl FnMut(&[Step]),
) {
    visit(steps);
    if steps.len() == max_steps {
        return;
    }
    for &c in choices {
        let repeat = steps.last().is_some_and(|l| {
            l.interface == c.interface
                && l.kind == StepKind::Reflect
                && c.kind == StepKind::Reflect
                && scene.interfaces()[c.interface].polyline.num_segments() == 1
        });
        if !repeat {
            steps.push(c);
            for_each_sequence(scene, choices, max_steps, steps, visit);
            steps.pop();
        }
    }
}

/// How many sequences [`for_each_sequence`] visits at most (without leaving out repeated
/// reflections), without visiting them.
fn count_sequences(options: &SearchOptions) -> u64 {
    let c = (step_choices(options).len() as u64).max(1);
    let mut total: u64 = 1;
    let mut level: u64 = 1;
    for _ in 0..options.max_steps {
        level = level.saturating_mul(c);
        total = total.saturating_add(level);
    }
    total
}

impl Tracer {
    /// The arrivals of the scene's `search`: every step sequence of 0 to `max_steps` steps
    /// through the allowed interfaces and kinds, each searched completely (as
    /// [`stationary_paths`](Tracer::stationary_paths) does) with its leg media from the
    /// regions, for every (source, receiver) pair in parallel. Listed: every `converged` and
    /// `vertex` arrival (and `obstructed` ones when the search asks), ordered by source,
    /// receiver and time.
    ///
    /// A room of one-segment walls searched for reflections only goes through the
    /// image-source tree with beam pruning instead (once per source, for all receivers): the
    /// same arrivals, checked against the sequence-by-sequence search in the tests.
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
    /// [`SearchError::NoSearch`] without a `search` section; [`SearchError::TooLarge`] when
    /// the sequences times the pairs exceed [`MAX_SEARCH_WORK`].
    pub fn search(&self) -> Result<Vec<SearchArrival>, SearchError> {
        self.search_with(None)
    }

    /// [`search`](Self::search) that stops when `stop` is requested (from another thread):
    /// the pairs not yet searched are skipped and the searches under way stop (the caller that
    /// asked discards the result).
    ///
    /// # Errors
    /// As [`search`](Self::search).
    pub fn search_with(&self, stop: Option<&Stop>) -> Result<Vec<SearchArrival>, SearchError> {
        let scene = self.scene();
        let options = scene.search().ok_or(SearchError::NoSearch)?;
        let pairs = (scene.sources().len() as u64) * (scene.receivers().len() as u64);
        let count = count_sequences(options);
        if count.saturating_mul(pairs) > MAX_SEARCH_WORK {
            return Err(SearchError::TooLarge {
                sequences: count,
                pairs,
            });
        }
        debug_assert!(options.max_steps <= MAX_STATIONARY_STEPS);
        let rooms = !options.refract
            && options.interfaces.iter().all(|&i| {
                let line = &scene.interfaces()[i].polyline;
                !line.is_closed() && line.num_segments() == 1
            });
        let mut out = if rooms {
            self.search_rooms(options, stop)
        } else {
            self.search_sequences(options, stop)
        };
        // By pair and time; ties (none but equal times) by the sequence, for a fixed order.
        fn key(s: &[Step]) -> impl Iterator<Item = (usize, bool)> + '_ {
            s.iter().map(|t| (t.interface, t.kind == StepKind::Refract))
        }
        out.sort_by(|a, b| {
            (a.source, a.receiver)
                .cmp(&(b.source, b.receiver))
                .then(a.arrival.time.total_cmp(&b.arrival.time))
                .then_with(|| a.steps.len().cmp(&b.steps.len()))
                .then_with(|| key(&a.steps).cmp(key(&b.steps)))
        });
        if scene.amplitudes().is_some() {
            out.par_iter_mut().for_each(|s| {
                self.arrival_amplitudes(&s.steps, std::slice::from_mut(&mut s.arrival))
            });
        }
        Ok(out)
    }

    /// Whether an arrival of this status is listed.
    fn listed(status: Status, options: &SearchOptions) -> bool {
        matches!(status, Status::Converged | Status::Vertex)
            || (options.obstructed && status == Status::Obstructed)
    }

    /// [`search`](Self::search) sequence by sequence, pair by pair in parallel.
    fn search_sequences(&self, options: &SearchOptions, stop: Option<&Stop>) -> Vec<SearchArrival> {
        let scene = self.scene();
        let choices = step_choices(options);
        let nr = scene.receivers().len();
        (0..scene.sources().len() * nr)
            .into_par_iter()
            .flat_map_iter(|pair| {
                let (source, receiver) = (pair / nr, pair % nr);
                let (s, r) = (scene.sources()[source], scene.receivers()[receiver]);
                let medium = self.source_medium(false, s);
                let mut found = Vec::new();
                let mut arrivals = Vec::new();
                // The pair's work budget, spent over its sequences.
                let mut left = self.search_budget().work;
                let mut visit = |steps: &[Step]| {
                    let sequence = Sequence { steps, path: None };
                    let limit = SearchBudget {
                        tuples: SEARCH_TUPLES,
                        work: left,
                    };
                    let outcome =
                        self.stationary_of(sequence, None, s, medium, r, limit, &mut arrivals);
                    left = left.saturating_sub(outcome.work);
                    for a in arrivals.drain(..) {
                        if Self::listed(a.status, options) {
                            found.push(SearchArrival {
                                source,
                                receiver,
                                steps: steps.to_vec(),
                                arrival: a,
                                complete: outcome.complete,
                            });
                        }
                    }
                };
                let mut steps = Vec::with_capacity(options.max_steps);
                if !stop.is_some_and(Stop::requested) {
                    within(stop, || {
                        for_each_sequence(
                            scene,
                            &choices,
                            options.max_steps,
                            &mut steps,
                            &mut visit,
                        )
                    });
                }
                found
            })
            .collect()
    }

    /// [`search`](Self::search) for reflections off one-segment walls: the image-source tree
    /// once per source, for all receivers (every leg in the source's medium).
    fn search_rooms(&self, options: &SearchOptions, stop: Option<&Stop>) -> Vec<SearchArrival> {
        let scene = self.scene();
        let walls = MirrorWalls::new(scene, &options.interfaces);
        (0..scene.sources().len())
            .into_par_iter()
            .flat_map_iter(|source| {
                let s = scene.sources()[source];
                let medium = self.source_medium(false, s);
                let Some(medium) = medium.filter(|_| !stop.is_some_and(Stop::requested)) else {
                    return Vec::new();
                };
                let slowness = scene.media()[medium].slowness;
                let mut found: Vec<MirrorArrival> = Vec::new();
                walls.arrivals(
                    scene,
                    s,
                    scene.receivers(),
                    options.max_steps,
                    slowness,
                    options.obstructed,
                    &mut MirrorScratch::default(),
                    &mut found,
                );
                found
                    .into_iter()
                    .map(|m| mirror_arrival(scene, source, medium, m))
                    .collect::<Vec<_>>()
            })
            .collect()
    }
}

/// A [`MirrorArrival`] as a [`SearchArrival`]: one-segment walls, so segment 0 and the
/// arclength from the wall's first vertex.
fn mirror_arrival(
    scene: &crate::Scene,
    source: usize,
    medium: usize,
    m: MirrorArrival,
) -> SearchArrival {
    let k = m.walls.len();
    let parameters = m
        .walls
        .iter()
        .zip(&m.points[1..=k])
        .map(|(&w, &p): (&usize, &Point)| scene.interfaces()[w].polyline.vertices()[0].distance(p))
        .collect();
    SearchArrival {
        source,
        receiver: m.receiver,
        steps: m
            .walls
            .iter()
            .map(|&interface| Step {
                kind: StepKind::Reflect,
                interface,
            })
            .collect(),
        arrival: Arrival {
            status: m.status,
            time: m.time,
            points: m.points,
            parameters,
            segments: vec![0; k],
            media: vec![medium; k + 1],
            iterations: 0,
            reason: m.reason,
            kink: None,
            // The image method's points: no solve, no residual.
            residual: f64::NAN,
            amplitude: None,
        },
        complete: true,
    }
}
