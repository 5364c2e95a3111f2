//! Every stationary path of a sequence ([`Tracer::stationary_paths`]) and of every ray of a
//! scene (`"solver": {"stationary": "all"}`, [`Tracer::trace_stationary`]): solved in
//! parallel into one list of arrivals per (source, receiver, path) triple, in ray order.

use rayon::prelude::*;

use crate::amplitude::Amplitude;
use crate::geom::Point;
use crate::options::{Progress, Run};
use crate::scene::{MAX_STATIONARY_STEPS, Scene};
use crate::trace::{Arrival, Kink, SearchOutcome, StationaryError, Threshold};
use crate::trace::{RayRecord, Reason, Status, Tracer};

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
    /// Whether the search was complete (see [`SearchOutcome::complete`]):
    /// with `true` the list holds every stationary path of the triple, and an empty list is a
    /// proof that it has none; with `false` it may be short.
    pub complete: bool,
    /// The rule with a threshold that ruled out a candidate, if one did (see
    /// [`SearchOutcome::undecided`]); the search is then not complete.
    pub undecided: Option<Threshold>,
}

impl TripleArrivals {
    /// The status of this triple's entry when it has no arrivals: `no_path` (a proof) when the
    /// search was complete, `not_converged` when it stopped at a limit or a threshold decided.
    pub fn status_without_arrivals(&self) -> Status {
        if self.complete {
            Status::NoPath
        } else {
            Status::NotConverged
        }
    }

    /// The reason of that entry: [`Reason::NoStationaryPath`], [`Reason::Undecided`] or
    /// [`Reason::SearchLimit`] (see [`SearchOutcome::reason_without_arrivals`]).
    pub fn reason_without_arrivals(&self) -> Reason {
        SearchOutcome {
            complete: self.complete,
            undecided: self.undecided,
            ..SearchOutcome::new()
        }
        .reason_without_arrivals()
    }
}

/// Every stationary path of every ray of a scene: one [`TripleArrivals`] per (source,
/// receiver, path) triple, in ray order ([`Scene::ray_index`]), as
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
    /// Its amplitude, when the scene asks for amplitudes (none for a triple without paths).
    pub amplitude: Option<&'a Amplitude>,
    /// The number of turning points on its legs, where known (a `profile` medium).
    pub turns: Option<u32>,
    /// The number of caustics its ray tube passed, where known (a `profile` medium).
    pub caustics: Option<u32>,
    /// Its direction at the source (radians from +x), where known (a `profile` medium).
    pub launch_angle: Option<f64>,
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
            amplitude: a.amplitude.as_ref(),
            turns: a.turns,
            caustics: a.caustics,
            launch_angle: a.launch_angle,
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
            amplitude: None,
            turns: None,
            caustics: None,
            launch_angle: None,
        }
    }
}

impl Tracer {
    /// Every stationary path of every (source, receiver, path) triple of the scene, as
    /// [`Tracer::stationary_paths`] finds them for one triple, solved in parallel (rayon), in
    /// ray order. This is what a scene with `"solver": {"stationary": "all"}` asks for.
    ///
    /// Each triple is one item of `run` (each search's work its units, as
    /// [`Tracer::stationary_paths`] counts them); once `run` stops (a stop request, a spent
    /// budget), the triples not yet searched are left empty and not complete, and the
    /// searches under way end, not complete.
    ///
    /// ```
    /// use eigenray::trace::Kink;
    /// use eigenray::{Scene, Status, Tracer, options::Run};
    /// // A mirror bent into a valley: a specular point on each slope, and the bottom, where
    /// // the time has a maximum-type kink.
    /// let scene = Scene::from_json(r#"{
    ///     "media": { "air": { "speed": 1.0 } },
    ///     "interfaces": { "valley": { "points": [[-3, 0], [0, -2], [3, 0]] } },
    ///     "sources": [[-0.5, 2]], "receivers": [[0.5, 2], [20, 2]],
    ///     "paths": [{ "steps": [{ "reflect": "valley" }], "media": ["air", "air"] }],
    ///     "solver": { "stationary": "all" }
    /// }"#).unwrap();
    /// let rays = Tracer::new(&scene).unwrap().trace_stationary(&Run::new()).unwrap();
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
    /// [`MAX_STATIONARY_STEPS`] steps, before any search
    /// runs.
    pub fn trace_stationary(&self, run: &Run) -> Result<StationaryRays, StationaryError> {
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
                let search = if run.keep_going(Progress { work: 0, items: 1 }) {
                    self.stationary_paths(
                        scene.sources()[source],
                        scene.receivers()[receiver],
                        path,
                        run,
                        &mut arrivals,
                    )?
                } else {
                    SearchOutcome {
                        complete: false,
                        ..SearchOutcome::new()
                    }
                };
                Ok(TripleArrivals {
                    source,
                    receiver,
                    path,
                    arrivals,
                    complete: search.complete,
                    undecided: search.undecided,
                })
            })
            .collect::<Result<Vec<_>, StationaryError>>()?;
        Ok(StationaryRays { triples })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Scene, Status};

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
        let run = Run::new();
        let rays = tracer.trace_stationary(&run).unwrap();
        assert_eq!(rays.triples.len(), 12);
        let mut one = Vec::new();
        for (i, t) in rays.triples.iter().enumerate() {
            assert_eq!(scene.ray_index(t.source, t.receiver, t.path), i);
            let search = tracer
                .stationary_paths(
                    scene.sources()[t.source],
                    scene.receivers()[t.receiver],
                    t.path,
                    &run,
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

    /// The entries are the rows `write` writes, in its order: every stationary path
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
        let rays = Tracer::new(&scene)
            .unwrap()
            .trace_stationary(&Run::new())
            .unwrap();
        let mut out = Vec::new();
        crate::write(&scene, &rays, crate::Format::Jsonl, &mut out).unwrap();
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
        let err = Tracer::new(&scene)
            .unwrap()
            .trace_stationary(&Run::new())
            .unwrap_err();
        assert_eq!(
            err,
            StationaryError::TooManySteps {
                path: 1,
                steps: MAX_STATIONARY_STEPS + 1
            }
        );
    }
}
