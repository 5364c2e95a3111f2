//! The public answers of a complete search: its arrivals, what it did, why it cannot run.

use std::fmt;

use crate::amplitude::Amplitude;
use crate::geom::Point;
use crate::scene::MAX_STATIONARY_STEPS;

use crate::trace::{Reason, Status, Threshold};

/// How the time behaves at the held vertices of a `vertex` path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kink {
    /// Moving any held point off its vertex along either segment makes the time rise.
    Minimum,
    /// Moving any held point off its vertex along either segment makes the time fall.
    Maximum,
    /// Held points of both kinds (two or more held points).
    Mixed,
}

impl Kink {
    /// Its name in every output format: `minimum`, `maximum` (and `mixed`).
    pub fn as_str(self) -> &'static str {
        match self {
            Kink::Minimum => "minimum",
            Kink::Maximum => "maximum",
            Kink::Mixed => "mixed",
        }
    }
}

/// One stationary path of a sequence (see [`Tracer::stationary_paths`](crate::Tracer::stationary_paths)).
#[derive(Clone, Debug, PartialEq)]
pub struct Arrival {
    /// `converged`, `vertex` or `obstructed`.
    pub status: Status,
    /// Travel time (always a number: every arrival has a time).
    pub time: f64,
    /// Source, interaction points, receiver.
    pub points: Vec<Point>,
    /// Interaction parameters (arclengths along their polylines).
    pub parameters: Vec<f64>,
    /// The segment of each interaction (a held point: the segment its vertex starts).
    pub segments: Vec<usize>,
    /// Leg media, as indices into [`Scene::media`](crate::Scene::media).
    pub media: Vec<usize>,
    /// Newton steps of its assignment's solve.
    pub iterations: usize,
    /// Why it is not `converged`, when it is not.
    pub reason: Option<Reason>,
    /// For a `vertex` path: how the time behaves at its held vertices.
    pub kink: Option<Kink>,
    /// Final relative residual of the free points.
    pub residual: f64,
    /// Its amplitude, when the scene asks for amplitudes (`"amplitudes"`).
    pub amplitude: Option<Amplitude>,
    /// The number of turning points on its legs, where it is known (a ray through a
    /// `profile` medium).
    pub turns: Option<u32>,
    /// The number of caustics its ray tube passes, where it is known (a ray through a
    /// `profile` medium).
    pub caustics: Option<u32>,
    /// The direction at the source (radians from +x, counterclockwise), where the path
    /// alone does not give it (a ray through a `profile` medium).
    pub launch_angle: Option<f64>,
}

impl Arrival {
    /// An arrival with empty vectors, to be filled.
    pub(super) fn empty() -> Arrival {
        Arrival {
            status: Status::NoPath,
            time: f64::NAN,
            points: Vec::new(),
            parameters: Vec::new(),
            segments: Vec::new(),
            media: Vec::new(),
            iterations: 0,
            reason: None,
            kink: None,
            residual: f64::NAN,
            amplitude: None,
            turns: None,
            caustics: None,
            launch_angle: None,
        }
    }
}

/// What the search for every stationary path of one sequence between one source and one
/// receiver did: whether it is complete (the one place a search says so; the lists it fills
/// carry it on: `TripleArrivals::complete` per triple, `SearchArrival::complete` per search
/// arrival), and its work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SearchOutcome {
    /// Whether every stationary path of the triple is listed: `false` when the search reached
    /// its limit of tuples or work, an assignment's solve did not settle, or a rule with a
    /// threshold ruled out a candidate ([`undecided`](Self::undecided)): the list may then be
    /// short. With `true`, an empty list is a proof that the sequence has no stationary path:
    /// the pruning is certain, and every assignment is ruled out by its solve exactly (to
    /// round-off).
    pub complete: bool,
    /// The rule with a threshold that ruled out a candidate, if one did (the first).
    pub undecided: Option<Threshold>,
    /// Tuples of hierarchy nodes visited.
    pub tuples: usize,
    /// Assignments solved.
    pub solves: usize,
    /// Work done: the points its Newton steps moved (a step of `k` points counts `k + 1`),
    /// and `k + 1` for each tuple visited. What a search's work budget counts.
    pub work: usize,
}

impl SearchOutcome {
    /// A search that has done nothing yet (complete until it finds otherwise).
    pub fn new() -> SearchOutcome {
        SearchOutcome {
            complete: true,
            undecided: None,
            tuples: 0,
            solves: 0,
            work: 0,
        }
    }

    /// Adds what another search did (of another sequence of media for the same triple).
    pub fn add(&mut self, other: SearchOutcome) {
        self.complete &= other.complete;
        self.undecided = self.undecided.or(other.undecided);
        self.tuples += other.tuples;
        self.solves += other.solves;
        self.work += other.work;
    }

    /// The reason of a triple without a stationary path: [`Reason::NoStationaryPath`] (a
    /// proof) when the search is complete, [`Reason::Undecided`] when a threshold ruled out
    /// a candidate, [`Reason::SearchLimit`] otherwise.
    pub fn reason_without_arrivals(&self) -> Reason {
        match (self.complete, self.undecided) {
            (true, _) => Reason::NoStationaryPath,
            (false, Some(rule)) => Reason::Undecided { rule },
            (false, None) => Reason::SearchLimit,
        }
    }
}

impl Default for SearchOutcome {
    fn default() -> Self {
        SearchOutcome::new()
    }
}

/// Why a search cannot run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StationaryError {
    /// There is no path of that index.
    ///
    /// How to fix: pass an index below `Scene::paths().len()`.
    NoSuchPath {
        /// The index asked for.
        path: usize,
    },
    /// The path has more steps than the search takes: each assignment of segments is tried
    /// with every choice of held vertices, `2^steps` of them.
    ///
    /// How to fix: search sequences of at most [`MAX_STATIONARY_STEPS`] steps.
    TooManySteps {
        /// The path's index.
        path: usize,
        /// Its steps.
        steps: usize,
    },
}

impl fmt::Display for StationaryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StationaryError::NoSuchPath { path } => write!(f, "there is no path {path}"),
            StationaryError::TooManySteps { path, steps } => write!(
                f,
                "path {path} has {steps} steps: the search for every stationary path takes at \
                 most {MAX_STATIONARY_STEPS}"
            ),
        }
    }
}

impl std::error::Error for StationaryError {}

/// The error as a scene error, naming the key: `paths[i].steps` for a path beyond the
/// search's step limit (the command-line tool's message), `paths` otherwise.
impl From<StationaryError> for crate::scene::SceneError {
    fn from(e: StationaryError) -> Self {
        match e {
            StationaryError::TooManySteps { path, steps } => crate::scene::SceneError::new(
                format!("paths[{path}].steps"),
                format!(
                    "{steps} steps; \"stationary\": \"all\" searches paths of at most \
                     {MAX_STATIONARY_STEPS} steps (each assignment of segments is tried with \
                     every choice of held vertices, 2^steps of them)"
                ),
            ),
            other => crate::scene::SceneError::new("paths", other.to_string()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The kinks' names, and the errors' messages and keys as the scene and the command
    /// line give them.
    #[test]
    fn names_and_messages() {
        let names = [Kink::Minimum, Kink::Maximum, Kink::Mixed].map(Kink::as_str);
        assert_eq!(names, ["minimum", "maximum", "mixed"]);
        let none = StationaryError::NoSuchPath { path: 4 };
        assert_eq!(none.to_string(), "there is no path 4");
        let e = crate::scene::SceneError::from(none);
        assert_eq!(
            (e.key.as_str(), e.message.as_str()),
            ("paths", "there is no path 4")
        );
        let long = StationaryError::TooManySteps { path: 2, steps: 99 };
        assert!(long.to_string().starts_with("path 2 has 99 steps"));
        assert!(
            long.to_string()
                .ends_with(&MAX_STATIONARY_STEPS.to_string())
        );
        let e = crate::scene::SceneError::from(long);
        assert_eq!(e.key, "paths[2].steps");
        assert!(e.message.starts_with("99 steps;"));
    }

    /// An empty arrival has nothing in it yet and no time.
    #[test]
    fn an_empty_arrival_is_empty() {
        let a = Arrival::empty();
        assert!(a.points.is_empty() && a.parameters.is_empty() && a.segments.is_empty());
        assert!(a.media.is_empty() && a.time.is_nan() && a.residual.is_nan());
        assert_eq!((a.status, a.kink, a.reason), (Status::NoPath, None, None));
    }
}
