//! What a ray's solve gives: its status, the reason for a failure, its record and the owned
//! ray with its points.

use std::fmt;

use crate::amplitude::Amplitude;
use crate::geom::Point;
use crate::scene::Scene;
use crate::solver::Solution;

/// How a ray ended (`status` in every output format).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// A stationary-time path: every interaction strictly inside a segment, every leg on the
    /// side its step demands, no leg crossing an interface.
    Converged,
    /// Time is stationary only with an interaction held on a polyline vertex (a kink: an
    /// edge-diffracted path, not a specular one).
    Vertex,
    /// No such path exists: the sequence has no stationary path whose interactions lie on
    /// their interfaces with every leg on the side its step demands (a proof, to round-off:
    /// where the documented start leads to none, a complete search rules every one out
    /// without a threshold; where only a threshold could, the ray is
    /// [`NotConverged`](Status::NotConverged) with [`Reason::Undecided`]).
    NoPath,
    /// The stationary path exists but a leg crosses another interface.
    Obstructed,
    /// The search for the sequence's stationary paths reached a limit before it could rule
    /// one out, or ruled one out only by a threshold ([`Reason::Undecided`]).
    NotConverged,
}

impl Status {
    /// Its name in every output format: `converged`, `vertex`, `no_path`, `obstructed`,
    /// `not_converged`.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Converged => "converged",
            Status::Vertex => "vertex",
            Status::NoPath => "no_path",
            Status::Obstructed => "obstructed",
            Status::NotConverged => "not_converged",
        }
    }
    /// Whether the ray has a travel time and points (`converged`, `vertex`, `obstructed`).
    pub fn has_time(self) -> bool {
        matches!(
            self,
            Status::Converged | Status::Vertex | Status::Obstructed
        )
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Why a ray is not `converged`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    /// Interaction `step` was pushed to the end of its open polyline.
    LeavesEnd {
        /// Index of the step.
        step: usize,
    },
    /// At interaction `step` the legs are not on the sides the step demands.
    WrongSide {
        /// Index of the step.
        step: usize,
    },
    /// Interaction `step` is held on a vertex of its polyline.
    AtVertex {
        /// Index of the step.
        step: usize,
    },
    /// Leg `leg` crosses interface `interface`.
    Crosses {
        /// Index of the leg (0: the one leaving the source).
        leg: usize,
        /// Index of the interface it crosses.
        interface: usize,
    },
    /// No medium fills the region of leg `leg` (no `at` claims it and there is no background).
    NoMedium {
        /// Index of the leg.
        leg: usize,
    },
    /// The leg media found at the solution differ from those it was solved with, again and
    /// again.
    MediaUnsettled,
    /// Interaction `step` and the next one fell on one spot (the leg between them vanished):
    /// the path degenerates to fewer interactions.
    Coincident {
        /// Index of the step.
        step: usize,
    },
    /// Interaction `step` fell on the source or the receiver (the leg between them vanished):
    /// the path is the one without this step (the direct path, for one step), which the
    /// sequence without it lists; so this one is not listed twice.
    AtEnd {
        /// Index of the step.
        step: usize,
    },
    /// The iteration limit was reached.
    IterationLimit,
    /// Interaction `step` lies beyond the end of its open interface at the one stationary
    /// point of the sequence (the image method through one-segment mirrors, where the time
    /// is convex): no path.
    BeyondEnd {
        /// Index of the step.
        step: usize,
    },
    /// A complete search of the sequence found no stationary path (where the documented
    /// start led to none); or, for reflections off one-segment mirrors, the image method
    /// showed that a leg would reach its mirror from behind, so that no path exists.
    NoStationaryPath,
    /// The search for the sequence's stationary paths reached a limit (more steps than
    /// [`MAX_STATIONARY_STEPS`](crate::scene::MAX_STATIONARY_STEPS), its limit of tuples or
    /// of work) before it could rule out a path.
    SearchLimit,
    /// A search of the sequence found no stationary path, but a rule with a threshold, not
    /// exact arithmetic, ruled out a candidate: a path may exist (a leg shorter or a grazing
    /// angle smaller than the rule's threshold), so the answer is not a proof.
    Undecided {
        /// The rule that decided.
        rule: Threshold,
    },
}

/// A rule with a threshold that the complete search of a sequence
/// ([`Tracer::stationary_paths`](crate::Tracer::stationary_paths)) may use to rule out a
/// candidate where exact arithmetic cannot decide. A search that used one says so
/// ([`SearchOutcome::undecided`](super::SearchOutcome::undecided)) and is not
/// complete; a triple without a path then answers `not_converged` with
/// [`Reason::Undecided`], never `no_path`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Threshold {
    /// A leg not longer than the vanishing threshold (1e-12 of the path's length plus the
    /// round-off of its coordinates) counted as vanished, the path collapsed (a slab thinner
    /// than that, an end point that near an interface).
    VanishedLeg,
    /// A solve that stalled next to a leg shorter than 1e-3 of the path's length (1e-6 where
    /// three interactions met) was taken to approach its collapse.
    ShortLeg,
    /// A solve that stalled with a leg whose sine with its interface's line is below 1e-7 was
    /// taken to run along it.
    Grazing,
    /// A leg nearer its interface's line than the vanishing threshold counted as on neither
    /// side of it.
    Side,
}

impl Threshold {
    /// Its name in every output format: `vanished_leg`, `short_leg`, `grazing`, `side`.
    pub fn as_str(self) -> &'static str {
        match self {
            Threshold::VanishedLeg => "vanished_leg",
            Threshold::ShortLeg => "short_leg",
            Threshold::Grazing => "grazing",
            Threshold::Side => "side",
        }
    }
}

/// The rule in words, with its threshold.
impl fmt::Display for Threshold {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Threshold::VanishedLeg => {
                "a leg shorter than 1e-12 of the path's length counted as vanished"
            }
            Threshold::ShortLeg => {
                "a stalled solve next to a leg shorter than 1e-3 of the path's length was taken \
                 to collapse"
            }
            Threshold::Grazing => {
                "a stalled solve with a leg within 1e-7 rad of its interface was taken to run \
                 along it"
            }
            Threshold::Side => {
                "a leg within 1e-12 of the path's length of its interface's line counted as on \
                 neither side"
            }
        })
    }
}

impl Reason {
    /// The reason in words, naming interfaces by their names in `scene`.
    pub fn describe(&self, scene: &Scene) -> String {
        self.describe_with(|i| scene.interfaces().get(i).map(|i| i.name.as_str()))
    }

    /// [`describe`](Self::describe) with the interfaces' names from `interface_name` (by
    /// index; `None` names it by its index): for a front end that keeps a batch's reasons
    /// and words them later, with the names alone.
    pub fn describe_with<'a>(
        &self,
        interface_name: impl FnOnce(usize) -> Option<&'a str>,
    ) -> String {
        match *self {
            Reason::Crosses { leg, interface } => match interface_name(interface) {
                Some(name) => format!("leg {leg} crosses interface `{name}`"),
                None => self.to_string(),
            },
            _ => self.to_string(),
        }
    }
}

/// The reason with indices only (`leg 1 crosses interface 2`); [`Reason::describe`] and
/// [`Ray::describe`] name the interfaces, paths and media from the scene.
impl fmt::Display for Reason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Reason::LeavesEnd { step } => {
                write!(f, "step {step} would leave the end of its open interface")
            }
            Reason::WrongSide { step } => write!(
                f,
                "at step {step} the legs are not on the sides the step demands"
            ),
            Reason::AtVertex { step } => write!(f, "step {step} is held on a polyline vertex"),
            Reason::Crosses { leg, interface } => {
                write!(f, "leg {leg} crosses interface {interface}")
            }
            Reason::NoMedium { leg } => write!(f, "no medium fills the region of leg {leg}"),
            Reason::MediaUnsettled => f.write_str("the leg media change with the solution"),
            Reason::Coincident { step } => {
                write!(
                    f,
                    "steps {step} and {} fall on one spot (the leg between them vanished)",
                    step + 1
                )
            }
            Reason::AtEnd { step } => write!(
                f,
                "step {step} falls on the source or the receiver (the leg between them \
                 vanished): it is the path without this step"
            ),
            Reason::IterationLimit => f.write_str("iteration limit reached"),
            Reason::BeyondEnd { step } => write!(
                f,
                "step {step} lies beyond the end of its open interface at the sequence's one \
                 stationary point"
            ),
            Reason::NoStationaryPath => {
                f.write_str("a complete search of the sequence found no stationary path")
            }
            Reason::SearchLimit => f.write_str(
                "the search for the sequence's stationary paths reached its limit (steps, \
                 tuples or work)",
            ),
            Reason::Undecided { rule } => write!(
                f,
                "no stationary path found, but a threshold decided (not a proof): {rule}"
            ),
        }
    }
}

/// The result of one ray without its points: what [`Tracer::solve`](crate::Tracer::solve)
/// returns (the points stay in the [`Workspace`](crate::Workspace)) and what a
/// [`Batch`](crate::Batch) holds per ray.
///
/// A ray without a time (`no_path`, `not_converged`) has `time` NaN: in every result type,
/// `time` is a number exactly when [`Status::has_time`] holds.
#[derive(Clone, Copy, Debug)]
pub struct RayRecord {
    /// How it ended.
    pub status: Status,
    /// Travel time; NaN when `status` has none.
    pub time: f64,
    /// Solver iterations.
    pub iterations: u32,
    /// Final relative residual `maxᵢ |∂T/∂sᵢ| / (wᵢ + wᵢ₊₁)` (NaN when the solver did not
    /// run: no medium, or no path by the image method).
    pub residual: f64,
    /// Why it is not `converged`, when it is not.
    pub reason: Option<Reason>,
}

/// `a` and `b` are the same number, or both NaN (no value).
fn same(a: f64, b: f64) -> bool {
    a == b || (a.is_nan() && b.is_nan())
}

/// Equal when every field is, a NaN `time` or `residual` (none) equal to another.
impl PartialEq for RayRecord {
    fn eq(&self, o: &Self) -> bool {
        self.status == o.status
            && same(self.time, o.time)
            && self.iterations == o.iterations
            && same(self.residual, o.residual)
            && self.reason == o.reason
    }
}

/// Equal when every field is, a NaN `time` or `residual` (none) equal to another.
impl PartialEq for Ray {
    fn eq(&self, o: &Self) -> bool {
        (self.source, self.receiver, self.path, self.status)
            == (o.source, o.receiver, o.path, o.status)
            && same(self.time, o.time)
            && self.points == o.points
            && self.iterations == o.iterations
            && same(self.residual, o.residual)
            && self.media == o.media
            && self.reason == o.reason
            && self.amplitude == o.amplitude
    }
}

impl Default for RayRecord {
    fn default() -> Self {
        RayRecord {
            status: Status::NotConverged,
            time: f64::NAN,
            iterations: 0,
            residual: f64::NAN,
            reason: None,
        }
    }
}

impl RayRecord {
    /// The record of a solve that ended as `status`, a status with a time (`converged`,
    /// `vertex`, `obstructed`), for `reason`.
    #[inline(always)]
    pub(crate) fn timed(status: Status, reason: Option<Reason>, sol: &Solution) -> RayRecord {
        debug_assert!(status.has_time());
        RayRecord {
            status,
            time: sol.time,
            iterations: sol.iterations as u32,
            residual: sol.residual,
            reason,
        }
    }

    /// The record of a solve that ended as `status`, a status without a time (`no_path`,
    /// `not_converged`), for `reason`.
    #[inline(always)]
    pub(crate) fn untimed(status: Status, reason: Reason, sol: &Solution) -> RayRecord {
        debug_assert!(!status.has_time());
        RayRecord {
            status,
            time: f64::NAN,
            iterations: sol.iterations as u32,
            residual: sol.residual,
            reason: Some(reason),
        }
    }

    /// A ray that ended before the solver ran: no time, no residual.
    pub(crate) fn failed(status: Status, reason: Reason) -> RayRecord {
        RayRecord {
            status,
            time: f64::NAN,
            iterations: 0,
            residual: f64::NAN,
            reason: Some(reason),
        }
    }
}

/// One solved ray: a (source, receiver, path) triple and its result.
#[derive(Clone, Debug)]
pub struct Ray {
    /// Source index.
    pub source: usize,
    /// Receiver index.
    pub receiver: usize,
    /// Path index.
    pub path: usize,
    /// How it ended.
    pub status: Status,
    /// Travel time; NaN when `status` has none (`no_path`, `not_converged`).
    pub time: f64,
    /// Source, interaction points and receiver, whenever `time` is present (else empty).
    pub points: Vec<Point>,
    /// Solver iterations.
    pub iterations: usize,
    /// Final relative residual `maxᵢ |∂T/∂sᵢ| / (wᵢ + wᵢ₊₁)` (NaN when the solver did not
    /// run: no medium, or no path by the image method).
    pub residual: f64,
    /// Leg media (indices into [`Scene::media`]), when known.
    pub media: Vec<usize>,
    /// Why it is not `converged`, when it is not.
    pub reason: Option<Reason>,
    /// Its amplitude, when the scene asks for amplitudes (`"amplitudes"`) and it has a time.
    pub amplitude: Option<Amplitude>,
}

impl Ray {
    /// The ray in one line, with the names `scene` gives its path, its steps' interfaces,
    /// its leg media and the interface a reason names, for example
    /// ``source 0, receiver 1, path `north wall` (reflect `north`): converged, time
    /// 0.014577259475218658, media air, air`` or ``…: obstructed (leg 1 crosses interface
    /// `screen`), time …``: the status and its reason, then the time and the leg media when
    /// the ray has them. Names are escaped as [`SceneError`](crate::SceneError)'s are.
    ///
    /// ```
    /// use eigenray::{Scene, Tracer};
    /// let scene = Scene::from_json(r#"{
    ///     "media": { "air": { "speed": 1.0 } },
    ///     "interfaces": { "north": { "points": [[0, 4], [6, 4]] } },
    ///     "sources": [[1, 1]], "receivers": [[5, 1], [15, 1]],
    ///     "paths": [{ "name": "north wall", "steps": [{ "reflect": "north" }],
    ///                 "media": ["air", "air"] }]
    /// }"#).unwrap();
    /// let tracer = Tracer::new(&scene).unwrap();
    /// let rays = tracer.trace_all();
    /// assert_eq!(rays[0].describe(&scene),
    ///            "source 0, receiver 0, path `north wall` (reflect `north`): converged, \
    ///             time 7.211102550927978, media air, air");
    /// assert_eq!(rays[1].describe(&scene),
    ///            "source 0, receiver 1, path `north wall` (reflect `north`): no_path (step 0 \
    ///             lies beyond the end of its open interface at the sequence's one stationary \
    ///             point), media air, air");
    /// ```
    pub fn describe(&self, scene: &Scene) -> String {
        use fmt::Write as _;
        let esc = crate::scene::SceneError::escape_text;
        let mut out = format!("source {}, receiver {}, ", self.source, self.receiver);
        let path = scene.paths().get(self.path);
        match path.and_then(|p| p.name.as_deref()) {
            Some(name) => {
                let _ = write!(out, "path `{}`", esc(name));
            }
            None => {
                let _ = write!(out, "path {}", self.path);
            }
        }
        let steps: Vec<String> = path
            .map(|p| p.steps.as_slice())
            .unwrap_or(&[])
            .iter()
            .map(|s| {
                let kind = s.kind.as_str();
                let name = scene.interfaces().get(s.interface).map_or("?", |i| &i.name);
                format!("{kind} `{}`", esc(name))
            })
            .collect();
        if steps.is_empty() {
            out.push_str(" (direct)");
        } else {
            let _ = write!(out, " ({})", steps.join(", "));
        }
        let _ = write!(out, ": {}", self.status);
        if let Some(reason) = &self.reason {
            let _ = write!(out, " ({})", esc(&reason.describe(scene)));
        }
        if self.status.has_time() {
            let _ = write!(out, ", time {}", self.time);
        }
        if !self.media.is_empty() {
            let names: Vec<String> = self
                .media
                .iter()
                .map(|&m| scene.media().get(m).map_or("?".into(), |m| esc(&m.name)))
                .collect();
            let _ = write!(out, ", media {}", names.join(", "));
        }
        out
    }
}
