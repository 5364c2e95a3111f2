//! Every stationary path of every ray of a scene (`"solver": {"stationary": "all"}`), solved
//! in parallel into one list of arrivals per (source, receiver, path) triple, in ray order;
//! and [`SearchArrival`], one arrival of a scene's automatic `search`.

use rayon::prelude::*;

use std::fmt;

use crate::geom::Point;
use crate::scene::{MAX_STATIONARY_STEPS, Scene, SearchOptions, Step, StepKind};
use crate::trace::{
    Arrival, Kink, MirrorArrival, MirrorScratch, MirrorWalls, RayRecord, Reason, Sequence,
    StationaryError, Status, Tracer,
};

/// Every stationary path of one (source, receiver, path) triple.
#[derive(Clone, Debug, PartialEq)]
pub struct TripleArrivals {
    /// Source index.
    pub source: usize,
    /// Receiver index.
    pub receiver: usize,
    /// Path index.
    pub path: usize,
    /// Its stationary paths (`converged`, `vertex`, `obstructed`), each once, ordered by time.
    pub arrivals: Vec<Arrival>,
    /// Whether the search was complete (see [`Stationary::complete`](crate::Stationary)):
    /// with `true` the list holds every stationary path of the triple, and an empty list is a
    /// proof that it has none; with `false` it may be short.
    pub complete: bool,
}

impl TripleArrivals {
    /// The status of this triple's entry when it has no arrivals: `no_path` (a proof) when the
    /// search was complete, `not_converged` when it stopped at a limit.
    pub fn status_without_arrivals(&self) -> Status {
        if self.complete {
            Status::NoPath
        } else {
            Status::NotConverged
        }
    }

    /// The reason of that entry: [`Reason::NoStationaryPath`] or [`Reason::SearchLimit`].
    pub fn reason_without_arrivals(&self) -> Reason {
        if self.complete {
            Reason::NoStationaryPath
        } else {
            Reason::SearchLimit
        }
    }
}

/// Every stationary path of every ray of a scene: one [`TripleArrivals`] per (source,
/// receiver, path) triple, in ray order ([`ray_index`](crate::ray_index)), as
/// [`Tracer::trace_stationary`] finds them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StationaryRays {
    /// One entry per triple, in ray order.
    pub triples: Vec<TripleArrivals>,
}

impl StationaryRays {
    /// Stationary paths found, over all triples.
    pub fn arrivals(&self) -> usize {
        self.triples.iter().map(|t| t.arrivals.len()).sum()
    }

    /// Entries of the written output: one per stationary path, and one (`no_path`, or
    /// `not_converged` when its search was not complete) per triple that has none.
    pub fn entries(&self) -> usize {
        self.triples.iter().map(|t| t.arrivals.len().max(1)).sum()
    }

    /// Whether every triple's search was complete.
    pub fn complete(&self) -> bool {
        self.triples.iter().all(|t| t.complete)
    }

    /// The entries of the written output ([`entries`](Self::entries) of them), in its order:
    /// by triple in ray order, each stationary path of a triple by time, and one entry
    /// (`no_path`, or `not_converged` when its search was not complete) for a triple that has
    /// none, with the leg media of its path in `scene` when the scene gives them.
    pub fn entries_in_order<'a>(
        &'a self,
        scene: &'a Scene,
    ) -> impl Iterator<Item = StationaryEntry<'a>> + 'a {
        self.triples.iter().flat_map(move |t| {
            let found = (t.arrivals.iter().enumerate()).map(move |(i, a)| t.entry(i, a));
            let none = t
                .arrivals
                .is_empty()
                .then(|| t.entry_without_arrivals(scene));
            found.chain(none)
        })
    }
}

/// One entry of the output of every stationary path ([`StationaryRays::entries_in_order`]): a
/// stationary path of a triple, or the entry of a triple that has none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StationaryEntry<'a> {
    /// Source index.
    pub source: usize,
    /// Receiver index.
    pub receiver: usize,
    /// Path index.
    pub path: usize,
    /// Its place by time among its triple's stationary paths (0 for a triple without any).
    pub arrival: usize,
    /// Status, time (NaN without one), iterations, residual and reason.
    pub record: RayRecord,
    /// Source, interaction points and receiver (empty for a triple without stationary paths).
    pub points: &'a [Point],
    /// Leg media (indices into [`Scene::media`]), when known.
    pub media: Option<&'a [usize]>,
    /// On a `vertex` path: the kind of kink.
    pub kink: Option<Kink>,
    /// Whether its triple's search was complete.
    pub complete: bool,
}

impl TripleArrivals {
    /// The entry of stationary path `arrival`, `a`.
    fn entry<'a>(&self, arrival: usize, a: &'a Arrival) -> StationaryEntry<'a> {
        StationaryEntry {
            source: self.source,
            receiver: self.receiver,
            path: self.path,
            arrival,
            record: RayRecord {
                status: a.status,
                time: a.time,
                iterations: a.iterations.try_into().unwrap_or(u32::MAX),
                residual: a.residual,
                reason: a.reason,
            },
            points: &a.points,
            media: Some(&a.media),
            kink: a.kink,
            complete: self.complete,
        }
    }

    /// The entry of this triple when it has no stationary path.
    fn entry_without_arrivals<'a>(&self, scene: &'a Scene) -> StationaryEntry<'a> {
        StationaryEntry {
            source: self.source,
            receiver: self.receiver,
            path: self.path,
            arrival: 0,
            record: RayRecord {
                status: self.status_without_arrivals(),
                time: f64::NAN,
                iterations: 0,
                residual: f64::NAN,
                reason: Some(self.reason_without_arrivals()),
            },
            points: &[],
            media: scene
                .paths()
                .get(self.path)
                .and_then(|p| p.media.as_deref()),
            kink: None,
            complete: self.complete,
        }
    }
}

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
}

impl Tracer {
    /// Every stationary path of every (source, receiver, path) triple of the scene, as
    /// [`Tracer::stationary_paths`] finds them for one triple, solved in parallel (rayon), in
    /// ray order. This is what a scene with `"solver": {"stationary": "all"}` asks for.
    ///
    /// ```
    /// use eigenray::{Kink, Scene, Status, Tracer};
    /// // A mirror bent into a valley: a specular point on each slope, and the bottom, where
    /// // the time has a maximum-type kink.
    /// let scene = Scene::from_json(r#"{
    ///     "media": { "air": { "speed": 1.0 } },
    ///     "interfaces": { "valley": { "points": [[-3, 0], [0, -2], [3, 0]] } },
    ///     "sources": [[-0.5, 2]], "receivers": [[0.5, 2], [20, 2]],
    ///     "paths": [{ "steps": [{ "reflect": "valley" }], "media": ["air", "air"] }],
    ///     "solver": { "stationary": "all" }
    /// }"#).unwrap();
    /// let rays = Tracer::new(&scene).unwrap().trace_stationary().unwrap();
    /// assert_eq!(rays.triples.len(), 2);
    /// let valley = &rays.triples[0];
    /// assert!(valley.complete);
    /// let statuses: Vec<Status> = valley.arrivals.iter().map(|a| a.status).collect();
    /// assert_eq!(statuses, [Status::Converged, Status::Converged, Status::Vertex]);
    /// assert_eq!(valley.arrivals[2].kink, Some(Kink::Maximum));
    /// // The far receiver sees no reflection off the valley at all: a proof.
    /// assert!(rays.triples[1].arrivals.is_empty() && rays.triples[1].complete);
    /// assert_eq!((rays.arrivals(), rays.entries()), (3, 4));
    /// ```
    ///
    /// # Errors
    /// [`StationaryError::TooManySteps`] for the first path of more than
    /// [`MAX_STATIONARY_STEPS`](crate::limits::MAX_STATIONARY_STEPS) steps, before any search
    /// runs.
    pub fn trace_stationary(&self) -> Result<StationaryRays, StationaryError> {
        self.trace_stationary_with_progress(&|_| {})
    }

    /// [`Tracer::trace_stationary`], calling `progress` from the worker threads with the number
    /// of triples each finished piece of work searched.
    ///
    /// # Errors
    /// As [`Tracer::trace_stationary`].
    pub fn trace_stationary_with_progress(
        &self,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<StationaryRays, StationaryError> {
        let scene = self.scene();
        for (path, p) in scene.paths().iter().enumerate() {
            if p.steps.len() > MAX_STATIONARY_STEPS {
                return Err(StationaryError::TooManySteps {
                    path,
                    steps: p.steps.len(),
                });
            }
        }
        let (receivers, paths) = (scene.receivers().len(), scene.paths().len());
        let triples = (0..scene.num_rays())
            .into_par_iter()
            .map(|ray| {
                let path = ray % paths;
                let receiver = (ray / paths) % receivers;
                let source = ray / paths / receivers;
                let mut arrivals = Vec::new();
                let search = self.stationary_paths(
                    scene.sources()[source],
                    scene.receivers()[receiver],
                    path,
                    &mut arrivals,
                )?;
                progress(1);
                Ok(TripleArrivals {
                    source,
                    receiver,
                    path,
                    arrivals,
                    complete: search.complete,
                })
            })
            .collect::<Result<Vec<_>, StationaryError>>()?;
        Ok(StationaryRays { triples })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Scene, Status, ray_index};

    #[test]
    fn triples_come_in_ray_order_and_match_one_by_one_searches() {
        let scene = Scene::from_json(
            r#"{
            "media": { "air": { "speed": 1.0 } },
            "interfaces": { "valley": { "points": [[-3, 0], [0, -2], [3, 0]] } },
            "sources": [[-0.5, 2], [0, 3]], "receivers": [[0.5, 2], [1, 1], [20, 2]],
            "paths": [
                { "steps": [{ "reflect": "valley" }], "media": ["air", "air"] },
                { "steps": [], "media": ["air"] }
            ]
        }"#,
        )
        .unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let rays = tracer.trace_stationary().unwrap();
        assert_eq!(rays.triples.len(), 12);
        let mut one = Vec::new();
        for (i, t) in rays.triples.iter().enumerate() {
            assert_eq!(ray_index(t.source, t.receiver, t.path, 3, 2), i);
            let search = tracer
                .stationary_paths(
                    scene.sources()[t.source],
                    scene.receivers()[t.receiver],
                    t.path,
                    &mut one,
                )
                .unwrap();
            assert_eq!(t.arrivals, one, "triple {i}");
            assert_eq!(t.complete, search.complete);
            assert!(t.arrivals.windows(2).all(|w| w[0].time <= w[1].time));
        }
        // The direct ray is one arrival everywhere; the valley gives three to its own receiver.
        assert_eq!(rays.triples[1].arrivals.len(), 1);
        assert_eq!(rays.triples[1].arrivals[0].status, Status::Converged);
        assert_eq!(rays.triples[0].arrivals.len(), 3);
        assert!(rays.triples[4].arrivals.is_empty());
        assert_eq!(rays.entries(), rays.arrivals() + 2);
        assert!(rays.complete());
    }

    /// The entries are the rows `write_stationary` writes, in its order: every stationary path
    /// of a triple by time, and one `no_path` row for a triple without any (the valley seen
    /// from the far receiver).
    #[test]
    fn entries_in_order_are_the_written_rows() {
        let scene = Scene::from_json(
            r#"{
            "media": { "air": { "speed": 1.0 } },
            "interfaces": { "valley": { "points": [[-3, 0], [0, -2], [3, 0]] } },
            "sources": [[-0.5, 2], [0, 3]], "receivers": [[0.5, 2], [20, 2], [1, 1]],
            "paths": [
                { "steps": [{ "reflect": "valley" }], "media": ["air", "air"] },
                { "name": "direct", "steps": [], "media": ["air"] }
            ]
        }"#,
        )
        .unwrap();
        let rays = Tracer::new(&scene).unwrap().trace_stationary().unwrap();
        let mut out = Vec::new();
        crate::write_stationary(&scene, &rays, crate::Format::Jsonl, &mut out).unwrap();
        let lines: Vec<serde_json::Value> = (out.split(|&b| b == b'\n'))
            .filter(|l| !l.is_empty())
            .map(|l| serde_json::from_slice(l).unwrap())
            .collect();
        let entries: Vec<StationaryEntry<'_>> = rays.entries_in_order(&scene).collect();
        assert_eq!(entries.len(), lines.len());
        assert_eq!(entries.len(), rays.entries());
        for (e, line) in entries.iter().zip(&lines) {
            let fields = [e.source, e.receiver, e.path, e.arrival];
            let written = ["source", "receiver", "path", "arrival"].map(|k| line[k].as_u64());
            assert_eq!(written, fields.map(|f| Some(f as u64)), "{line}");
            assert_eq!(line["status"], e.record.status.as_str());
            assert_eq!(line["complete"], e.complete);
            assert_eq!(line["kink"].as_str(), e.kink.map(|k| k.as_str()));
            let points = line["points"].as_array().map_or(0, |p| p.len());
            assert_eq!(points, e.points.len());
        }
        // Triple by triple in ray order; within one, by time; one `no_path` row for none.
        let mut expected = Vec::new();
        for t in &rays.triples {
            for i in 0..t.arrivals.len().max(1) {
                expected.push((t.source, t.receiver, t.path, i));
            }
        }
        let got: Vec<_> = (entries.iter())
            .map(|e| (e.source, e.receiver, e.path, e.arrival))
            .collect();
        assert_eq!(got, expected);
        let none: Vec<_> = entries.iter().filter(|e| e.points.is_empty()).collect();
        assert!(!none.is_empty());
        for e in none {
            assert_eq!(e.record.status, Status::NoPath);
            assert!(e.record.time.is_nan() && e.complete && e.arrival == 0);
            let legs = scene.paths()[e.path].steps.len() + 1;
            assert_eq!(e.media, Some(&[0, 0][..legs]));
        }
        let times: Vec<f64> = entries.iter().map(|e| e.record.time).collect();
        assert!(entries.windows(2).zip(times.windows(2)).all(|(e, t)| {
            (e[0].source, e[0].receiver, e[0].path) != (e[1].source, e[1].receiver, e[1].path)
                || t[0] <= t[1]
        }));
    }

    #[test]
    fn a_path_beyond_the_step_limit_is_refused_before_any_search() {
        let steps = vec![r#"{ "reflect": "floor" }"#; MAX_STATIONARY_STEPS + 1].join(",");
        let media = vec![r#""air""#; MAX_STATIONARY_STEPS + 2].join(",");
        let scene = Scene::from_json(&format!(
            r#"{{
            "media": {{ "air": {{ "speed": 1.0 }} }},
            "interfaces": {{ "floor": {{ "points": [[-3, 0], [3, 0]] }} }},
            "sources": [[0, 1]], "receivers": [[1, 1]],
            "paths": [{{ "steps": [], "media": ["air"] }}, {{ "steps": [{steps}], "media": [{media}] }}]
        }}"#
        ))
        .unwrap();
        let err = Tracer::new(&scene).unwrap().trace_stationary().unwrap_err();
        assert_eq!(
            err,
            StationaryError::TooManySteps {
                path: 1,
                steps: MAX_STATIONARY_STEPS + 1
            }
        );
    }
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
            self.search_rooms(options)
        } else {
            self.search_sequences(options)
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
        Ok(out)
    }

    /// Whether an arrival of this status is listed.
    fn listed(status: Status, options: &SearchOptions) -> bool {
        matches!(status, Status::Converged | Status::Vertex)
            || (options.obstructed && status == Status::Obstructed)
    }

    /// [`search`](Self::search) sequence by sequence, pair by pair in parallel.
    fn search_sequences(&self, options: &SearchOptions) -> Vec<SearchArrival> {
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
                let mut visit = |steps: &[Step]| {
                    let sequence = Sequence { steps, path: None };
                    let limit = SEARCH_TUPLES;
                    self.stationary_of(sequence, None, s, medium, r, limit, &mut arrivals);
                    for a in arrivals.drain(..) {
                        if Self::listed(a.status, options) {
                            found.push(SearchArrival {
                                source,
                                receiver,
                                steps: steps.to_vec(),
                                arrival: a,
                            });
                        }
                    }
                };
                let mut steps = Vec::with_capacity(options.max_steps);
                for_each_sequence(scene, &choices, options.max_steps, &mut steps, &mut visit);
                found
            })
            .collect()
    }

    /// [`search`](Self::search) for reflections off one-segment walls: the image-source tree
    /// once per source, for all receivers (every leg in the source's medium).
    fn search_rooms(&self, options: &SearchOptions) -> Vec<SearchArrival> {
        let scene = self.scene();
        let walls = MirrorWalls::new(scene, &options.interfaces);
        (0..scene.sources().len())
            .into_par_iter()
            .flat_map_iter(|source| {
                let s = scene.sources()[source];
                let Some(medium) = self.source_medium(false, s) else {
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
            complete: true,
        },
    }
}
