//! Echoes: the timed arrivals of a solve or a search, as a response sees them.

use std::fmt;

use num_complex::Complex64;

use crate::options::Run;
use crate::output::RaySet;
use crate::scene::Scene;
use crate::scene::SceneError;
use crate::scene::StationaryMode;
use crate::search::{SearchArrival, SearchError, StreamedArrival, diffractions};
use crate::trace::{Arrival, StationaryError, Status, Tracer};
use crate::{Amplitude, BatchOptions};

/// One arrival as a response sees it: when and how strongly it reaches a receiver from a
/// source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Echo {
    /// Source index.
    pub source: usize,
    /// Receiver index.
    pub receiver: usize,
    /// Travel time.
    pub time: f64,
    /// The complex amplitude, without the travel-time phase ([`Amplitude::value`]).
    pub amplitude: Complex64,
    /// Interactions along the path (0: the direct path), what an echogram colours by.
    pub order: usize,
    /// Of those, the diffractions at vertices (0: a specular path), what an echogram marks
    /// apart.
    pub diffractions: usize,
    /// Of those, the floor and ceiling reflections of an extruded scene's 3-D path (0 in a
    /// plane scene), what an echogram marks apart.
    pub vertical_reflections: usize,
}

impl Echo {
    /// The echo of a path from `source` to `receiver` with `status`, `time` and `amplitude`:
    /// only a `converged` path with an amplitude value is one (an `obstructed` path is
    /// blocked, a `vertex` path has no ray-theory amplitude, and a path traced without
    /// amplitudes has none to give). `diffractions` of its `points.len() − 2` steps diffract,
    /// `vertical` reflect off the floor or the ceiling.
    fn of(
        (source, receiver): (usize, usize),
        status: Status,
        time: f64,
        amplitude: Option<&Amplitude>,
        (points, diffractions, vertical): (usize, usize, usize),
    ) -> Option<Echo> {
        let a = amplitude.filter(|a| a.has_value())?;
        (status == Status::Converged).then_some(Echo {
            source,
            receiver,
            time,
            amplitude: a.value,
            order: points.saturating_sub(2),
            diffractions,
            vertical_reflections: vertical,
        })
    }

    /// The echo of an arrival a streaming search found ([`Tracer::search_into`]): only a
    /// `converged` one with an amplitude value is one.
    pub fn of_streamed(a: &StreamedArrival) -> Option<Echo> {
        let amplitude = a.amplitude.as_ref();
        let pair = (a.source, a.receiver);
        Echo::of(
            pair,
            a.status,
            a.time,
            amplitude,
            (a.steps + 2, a.diffractions, a.vertical_reflections),
        )
    }

    fn of_arrival(
        (source, receiver): (usize, usize),
        a: &Arrival,
        (diffractions, vertical): (usize, usize),
    ) -> Option<Echo> {
        let pair = (source, receiver);
        let counts = (a.points.len(), diffractions, vertical);
        Echo::of(pair, a.status, a.time, a.amplitude.as_ref(), counts)
    }
}

/// The echoes of a solve's rays (of `scene`'s paths): each `converged` ray (or stationary
/// path) that has an amplitude, in the order of `rays`.
pub fn echoes_of_rays<'a>(
    scene: &'a Scene,
    rays: RaySet<'a>,
) -> Box<dyn Iterator<Item = Echo> + 'a> {
    let paths = scene.paths();
    let of_path = move |path: usize| paths.get(path).map_or(0, |p| diffractions(&p.steps));
    match rays {
        RaySet::Rays(rays) => Box::new(rays.iter().filter_map(move |r| {
            let pair = (r.source, r.receiver);
            let counts = (r.points.len(), of_path(r.path), 0);
            Echo::of(pair, r.status, r.time, r.amplitude.as_ref(), counts)
        })),
        RaySet::Batch(b) => Box::new((0..b.len()).filter_map(move |i| {
            let (t, r) = (b.triple(i), b.record(i));
            let pair = (t.source, t.receiver);
            let counts = (b.points(i).len(), of_path(t.path), 0);
            Echo::of(pair, r.status, r.time, b.amplitude(i), counts)
        })),
        RaySet::Stationary(st) => Box::new(st.triples.iter().flat_map(move |t| {
            let pair = (t.source, t.receiver);
            let d = (of_path(t.path), 0);
            (t.arrivals.iter()).filter_map(move |a| Echo::of_arrival(pair, a, d))
        })),
    }
}

/// The echoes of a search's arrivals: each `converged` arrival that has an amplitude.
pub fn echoes_of_arrivals(arrivals: &[SearchArrival]) -> impl Iterator<Item = Echo> + '_ {
    arrivals.iter().filter_map(|a| {
        let counts = (diffractions(&a.steps), a.vertical_reflections());
        Echo::of_arrival((a.source, a.receiver), &a.arrival, counts)
    })
}

/// Why a scene's echoes could not be found ([`echoes_of_scene`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum EchoError {
    /// The paths' every-stationary-path search was refused.
    Stationary(StationaryError),
    /// The scene's `search` was refused.
    Search(SearchError),
    /// The batch of the paths' rays cannot be allocated.
    Batch(SceneError),
}

impl fmt::Display for EchoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EchoError::Stationary(e) => write!(f, "solver.stationary: {e}"),
            EchoError::Search(e) => write!(f, "search: {e}"),
            EchoError::Batch(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for EchoError {}

/// Every echo of `tracer`'s scene, as `eigenray solve` finds them: the rays of its `paths`
/// (one per triple, or every stationary path with `"stationary": "all"`), then the arrivals
/// of its `search`. The batch, the every-stationary-path search and the `search` run with
/// `run`; once it stops, they stop (their results say so: see each), and the caller that
/// asked to stop discards the (short) result.
///
/// # Errors
/// A refused every-stationary-path search or `search`, or a batch too large to allocate.
pub fn echoes_of_scene(tracer: &Tracer, run: &Run) -> Result<Vec<Echo>, EchoError> {
    let scene = tracer.scene();
    let mut echoes: Vec<Echo> = match scene.solver().stationary {
        StationaryMode::One => {
            let batch = tracer
                .trace_batch(&BatchOptions::default(), run)
                .map_err(EchoError::Batch)?;
            echoes_of_rays(scene, RaySet::Batch(&batch)).collect()
        }
        StationaryMode::All => {
            let all = tracer
                .trace_stationary(run)
                .map_err(EchoError::Stationary)?;
            echoes_of_rays(scene, RaySet::Stationary(&all)).collect()
        }
    };
    if scene.search().is_some() {
        let report = tracer.search(run).map_err(EchoError::Search)?;
        echoes.extend(echoes_of_arrivals(&report.arrivals));
    }
    Ok(echoes)
}
