//! Rays: initial guess, leg media, the solve, and the classification of the result.

use std::fmt;

use rayon::prelude::*;

use crate::geom::{Aabb, Point, Vec2};
use crate::polyline::Polyline;
use crate::problem::Geometry;
use crate::regions::Regions;
use crate::scene::{Scene, SceneError, SegmentRef, StepKind};
use crate::solver::{Outcome, Pin, Workspace, solve};

mod flat;
mod single;
mod stack;
mod straight;
pub(crate) use single::SinglePath;

/// How a ray ended (the contract's `status`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// A stationary-time path: every interaction strictly inside a segment, every leg on the
    /// side its step demands, no leg crossing an interface.
    Converged,
    /// Time is stationary only with an interaction held on a polyline vertex (a kink: an
    /// edge-diffracted path, not a specular one).
    Vertex,
    /// No such path exists from the solver's start: it would leave an open polyline's end, or
    /// the side conditions cannot hold.
    NoPath,
    /// The stationary path exists but a leg crosses another interface.
    Obstructed,
    /// The solver gave up.
    NotConverged,
}

impl Status {
    /// The contract's name: `converged`, `vertex`, `no_path`, `obstructed`, `not_converged`.
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
    /// The iteration limit was reached.
    IterationLimit,
}

impl Reason {
    /// The reason in words, naming interfaces by their names in `scene`.
    pub fn describe(&self, scene: &Scene) -> String {
        match *self {
            Reason::Crosses { leg, interface } => match scene.interfaces().get(interface) {
                Some(i) => format!("leg {leg} crosses interface `{}`", i.name),
                None => self.to_string(),
            },
            _ => self.to_string(),
        }
    }
}

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
            Reason::IterationLimit => f.write_str("iteration limit reached"),
        }
    }
}

/// The result of solving one ray without its points (they stay in the [`Workspace`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RaySummary {
    /// How it ended.
    pub status: Status,
    /// Travel time (meaningful when `status.has_time()`).
    pub time: f64,
    /// Solver iterations.
    pub iterations: usize,
    /// Final relative residual (NaN when the solver did not run: no medium, or no path by
    /// the image method).
    pub residual: f64,
    /// Why it is not `converged`, when it is not.
    pub reason: Option<Reason>,
}

/// One solved ray: a (source, receiver, path) triple and its result.
#[derive(Clone, Debug, PartialEq)]
pub struct Ray {
    /// Source index.
    pub source: usize,
    /// Receiver index.
    pub receiver: usize,
    /// Path index.
    pub path: usize,
    /// How it ended.
    pub status: Status,
    /// Travel time, for `converged`, `vertex` and `obstructed`.
    pub time: Option<f64>,
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
}

/// Where a solve starts.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Start<'a> {
    /// The documented initial guess.
    Default,
    /// Whichever of these parameters and the default guess has the smaller residual.
    Compare(&'a [f64]),
    /// These parameters (a neighbouring receiver's solution in a batch).
    Given(&'a [f64]),
}

/// How a path made only of refractions crossed by the straight line `S → R`, or only of
/// reflections off flat mirrors, refines its start (see [`Tracer`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum InitialGuess {
    /// The flat-layer ray-parameter solution where the interfaces at the crossings are
    /// parallel (the solution itself for parallel flat layers), the paraxial one elsewhere;
    /// off mirrors of one segment each, the image method (the solution itself, or no path).
    #[default]
    RayParameter,
    /// The paraxial (small-angle) solution only, and no image method: a start that leaves
    /// Newton steps to do even through flat layers and off flat mirrors, for comparing solvers
    /// from one start.
    Paraxial,
}

/// The contract's ray numbering: source-major, then receiver, then path.
#[inline]
pub fn ray_index(
    source: usize,
    receiver: usize,
    path: usize,
    receivers: usize,
    paths: usize,
) -> usize {
    (source * receivers + receiver) * paths + path
}

/// Solves the rays of a scene. Holds the region lookup when the scene needs one.
///
/// Initial guess (documented, deterministic): interaction `i` of `k` starts at the point of
/// its interface nearest to the target `S + (i + 1)/(k + 1) · (R − S)` on the straight line
/// from source to receiver; a refraction whose interface that line crosses starts at the
/// crossing nearest the target instead. When every step is such a refraction, each point
/// then moves along its interface to where a ray through flat layers would cross: the layers
/// are taken as parallel to the first interface at its crossing, `Δtⱼ Z` thick (`tᵢ` the
/// crossings' fractions of the way from `S` to `R`, `Z` and `X` the extents of `R − S` across
/// and along the layers, `wⱼ` the legs' slownesses). Where the interfaces' tangents at the
/// crossings are parallel (to within 5e-5 rad), the ray parameter `p` solves
/// `Σⱼ Δtⱼ tan θⱼ = X / Z` with `sin θⱼ = p / wⱼ` (a 1-D iteration of Halley's steps from
/// above, from the smallest of the paraxial `p`, the root of the equation with `tan θ` cut to
/// its series' first four terms, and the `p` at which the layers of the smallest slowness
/// alone take the whole offset) and the lateral fractions become `τᵢ = Σ_{j≤i} Δtⱼ tan θⱼ · Z / X`:
/// the solution itself for parallel flat layers, so the Newton solve that follows only
/// confirms it (for interfaces of one segment with the media given, a kernel of its own
/// takes the general code's steps without its bookkeeping, bit for bit). Elsewhere, for a
/// single refraction (whose 1-D ray-parameter solve would cost what its Newton steps do), or
/// with [`InitialGuess::Paraxial`], the small-angle limit
/// `τᵢ = Σ_{j≤i} Δtⱼ/wⱼ / Σⱼ Δtⱼ/wⱼ`.
/// On a polyline of more than 1,024 segments (a
/// digitised sea floor, a measured profile) the nearest point is replaced by the crossing,
/// nearest the target, of the line through the target perpendicular to `R − S`, when there is
/// one: an `O(log M)` query where the nearest-point search grows about like `√M`; a single
/// reflection there then starts at the specular point of the tangent line at that crossing
/// (the image method: exact on a straight mirror). A path whose every step refracts at an
/// interface of one segment (flat or dipping layers) finds its crossings from the segments
/// `Tracer::new` kept for it, with no search: the same start, bit for bit. A path whose every
/// step reflects off an interface of one segment (flat mirrors, the walls of a room), with
/// one slowness on every leg, starts (unless [`InitialGuess::Paraxial`])
/// at the image method's specular points instead (the source mirrored in each mirror's line
/// in turn, then the points back from the receiver towards each image) when every one lies
/// strictly inside its segment: the solution itself. When one lies clearly beyond its
/// segment's end (media given), the ray has no path (`T` is convex in the parameters, so
/// that is its one stationary point) and is [`Status::NoPath`] at once.
///
/// A single refraction with its media given, at an interface of one segment (air over
/// water, a flat sea floor, a lens face), from the default start, is solved by a dedicated
/// kernel in the segment's frame: from the paraxial start, two Halley steps on Snell's law
/// squared (a quartic: no square root), then Newton steps on the residual with the solver's
/// convergence tests, within a bracket that keeps every iterate between the feet of the
/// source and the receiver. Its `iterations` count those steps (two at least; usually two).
/// A ray outside its clean case (a source or receiver nearer the interface's line than 1e-9
/// of the ray's extent, the root at or beyond the segment's end, no convergence within
/// `max_iterations`) is solved by the general code from the same start; where the kernel
/// converges, the general solve gives the same status (tested on the benchmark and demo
/// scenes), with a time within 1e-12.
///
/// Two or more refractions at parallel interfaces of one segment each, with the media
/// given, from the default start, take a kernel too: the general code's own steps (the
/// ray-parameter start, the solver's fast Newton path, the classification) on data prepared
/// once per path, so that its rays are the general code's bit for bit.
pub struct Tracer<'s> {
    scene: &'s Scene,
    regions: Option<Regions>,
    /// Medium at each source (when regions exist).
    source_media: Vec<Option<usize>>,
    /// Per path, per leg: every scene segment that can cross it, when there are few (see
    /// [`leg_candidates`]).
    leg_candidates: Vec<Vec<Option<Box<[u32]>>>>,
    /// Per path: whether no leg has a candidate (a path through single-segment interfaces
    /// with nothing between them): for a source and a receiver within `ends`, no leg can be
    /// obstructed.
    clear: Vec<bool>,
    /// The boxes of the scene's sources and receivers, for which the candidates of the legs
    /// from the source and to the receiver hold.
    ends: [Aabb; 2],
    /// Per path: its one-interaction data when it is one interaction with given media.
    single: Vec<Option<SinglePath>>,
    /// Per path: its segments when it refracts at one-segment interfaces only, or reflects
    /// off them only.
    straight: Vec<Option<straight::StraightPath>>,
    guess: InitialGuess,
}

impl<'s> Tracer<'s> {
    /// Prepares a scene for tracing: builds the region lookup only if some path needs it.
    ///
    /// # Errors
    /// A scene whose regions are inconsistent (two `at` points in one region).
    pub fn new(scene: &'s Scene) -> Result<Tracer<'s>, SceneError> {
        let regions = if scene.needs_regions() {
            Some(Regions::build(scene)?)
        } else {
            None
        };
        let source_media = match &regions {
            Some(r) => scene.sources().iter().map(|&p| r.medium_at(p)).collect(),
            None => Vec::new(),
        };
        let ends = [
            Aabb::around(scene.sources()),
            Aabb::around(scene.receivers()),
        ];
        let candidates: Vec<_> = scene
            .paths()
            .iter()
            .map(|p| leg_candidates(scene, &p.steps, ends))
            .collect();
        Ok(Tracer {
            scene,
            regions,
            source_media,
            clear: candidates
                .iter()
                .map(|legs| legs.iter().all(|c| c.as_deref() == Some(&[])))
                .collect(),
            leg_candidates: candidates,
            ends,
            single: (0..scene.paths().len())
                .map(|p| SinglePath::of(scene, p))
                .collect(),
            straight: (0..scene.paths().len())
                .map(|p| straight::StraightPath::of(scene, p))
                .collect(),
            guess: InitialGuess::default(),
        })
    }

    /// The same tracer with another refinement of the start of refraction paths.
    ///
    /// ```
    /// use eigenray::{InitialGuess, Scene, Tracer, Workspace};
    /// let scene = Scene::from_spec(&eigenray::demo::layer_stack(8, 10)).unwrap();
    /// let (src, rec) = (scene.sources()[0], scene.receivers()[9]);
    /// let mut ws = Workspace::new();
    /// // Through flat layers the default start is the solution; the paraxial one is not.
    /// let exact = Tracer::new(&scene).unwrap().solve(src, rec, 0, &mut ws);
    /// let paraxial = Tracer::new(&scene)
    ///     .unwrap()
    ///     .with_initial_guess(InitialGuess::Paraxial)
    ///     .solve(src, rec, 0, &mut ws);
    /// assert_eq!(exact.iterations, 0);
    /// assert!(paraxial.iterations > 0);
    /// assert!((exact.time - paraxial.time).abs() <= 1e-12 * exact.time);
    /// ```
    pub fn with_initial_guess(mut self, guess: InitialGuess) -> Self {
        self.guess = guess;
        self
    }

    /// The scene.
    pub fn scene(&self) -> &'s Scene {
        self.scene
    }

    /// The region lookup, if the scene needed one.
    pub fn regions(&self) -> Option<&Regions> {
        self.regions.as_ref()
    }

    /// Solves one ray of the scene.
    ///
    /// # Panics
    /// If an index is out of range (`source`, `receiver`, `path` index the scene's lists).
    pub fn trace(&self, source: usize, receiver: usize, path: usize, ws: &mut Workspace) -> Ray {
        let s = self.solve_indexed(source, receiver, path, ws);
        self.to_ray(source, receiver, path, &s, ws)
    }

    /// Solves every ray of the scene, in parallel, in the contract's ray order.
    pub fn trace_all(&self) -> Vec<Ray> {
        let (r, p) = (self.scene.receivers().len(), self.scene.paths().len());
        (0..self.scene.num_rays())
            .into_par_iter()
            .map_init(Workspace::new, |ws, idx| {
                let path = idx % p;
                let receiver = (idx / p) % r;
                let source = idx / (p * r);
                self.trace(source, receiver, path, ws)
            })
            .collect()
    }

    fn to_ray(
        &self,
        source: usize,
        receiver: usize,
        path: usize,
        s: &RaySummary,
        ws: &Workspace,
    ) -> Ray {
        let has = s.status.has_time();
        Ray {
            source,
            receiver,
            path,
            status: s.status,
            time: has.then_some(s.time),
            points: if has { ws.points.clone() } else { Vec::new() },
            iterations: s.iterations,
            residual: s.residual,
            media: ws.media.clone(),
            reason: s.reason,
        }
    }

    fn solve_indexed(
        &self,
        source: usize,
        receiver: usize,
        path: usize,
        ws: &mut Workspace,
    ) -> RaySummary {
        self.solve_indexed_from(source, receiver, path, None, ws)
    }

    /// Solves path `path` between two arbitrary points. The points of the ray are left in
    /// `ws` ([`Workspace::points`]); nothing is allocated once `ws` has grown.
    ///
    /// # Panics
    /// If a point is not finite or lies outside the scene's coordinate range, or `path` is
    /// not an index into [`Scene::paths`]: [`Scene::check_solve`] tells beforehand.
    pub fn solve(
        &self,
        source: Point,
        receiver: Point,
        path: usize,
        ws: &mut Workspace,
    ) -> RaySummary {
        if let Err(e) = self.scene.check_solve(source, receiver, path) {
            panic!("Tracer::solve: {e}");
        }
        let src_medium = self.regions.as_ref().and_then(|r| r.medium_at(source));
        self.solve_inner(source, src_medium, receiver, path, Start::Default, ws)
    }

    /// [`solve`](Self::solve) with a warm start: `guess` holds interaction parameters (for
    /// example those of a neighbouring receiver's solution, [`Workspace::parameters`]); the
    /// solver starts from whichever of `guess` and the default initial guess has the smaller
    /// residual.
    ///
    /// # Panics
    /// If `guess` does not have one parameter per step of the path, or as
    /// [`solve`](Self::solve) does.
    pub fn solve_from(
        &self,
        source: Point,
        receiver: Point,
        path: usize,
        guess: &[f64],
        ws: &mut Workspace,
    ) -> RaySummary {
        if let Err(e) = self.scene.check_solve(source, receiver, path) {
            panic!("Tracer::solve_from: {e}");
        }
        assert_eq!(
            guess.len(),
            self.scene.paths()[path].steps.len(),
            "one parameter per step"
        );
        let src_medium = self.regions.as_ref().and_then(|r| r.medium_at(source));
        self.solve_inner(
            source,
            src_medium,
            receiver,
            path,
            Start::Compare(guess),
            ws,
        )
    }

    /// Solves ray (`source`, `receiver`, `path`) of the scene, optionally warm-started
    /// (see [`solve_from`](Self::solve_from)); the points stay in `ws`.
    ///
    /// # Panics
    /// If an index is out of range.
    pub fn solve_indexed_from(
        &self,
        source: usize,
        receiver: usize,
        path: usize,
        guess: Option<&[f64]>,
        ws: &mut Workspace,
    ) -> RaySummary {
        self.solve_indexed_start(
            source,
            receiver,
            path,
            guess.map_or(Start::Default, Start::Compare),
            ws,
        )
    }

    pub(crate) fn solve_indexed_start(
        &self,
        source: usize,
        receiver: usize,
        path: usize,
        start: Start,
        ws: &mut Workspace,
    ) -> RaySummary {
        let src_medium = self.source_media.get(source).copied().flatten();
        self.solve_inner(
            self.scene.sources()[source],
            src_medium,
            self.scene.receivers()[receiver],
            path,
            start,
            ws,
        )
    }

    /// The one-interaction data of `path` when its rays take the one-interaction code.
    #[inline]
    pub(crate) fn single_path(&self, path: usize) -> Option<&SinglePath> {
        #[cfg(test)]
        if crate::solver::tests::GENERAL_ONLY.with(|c| c.get()) {
            return None;
        }
        self.single[path].as_ref()
    }

    /// The segments of `path` when its rays from the default start take the kernel of a
    /// stack of parallel layers (`trace::stack`): a [`StraightPath::stack`] started from the
    /// ray parameter.
    #[inline(always)]
    fn stack_path(&self, path: usize) -> Option<&straight::StraightPath> {
        #[cfg(test)]
        if crate::solver::tests::GENERAL_ONLY.with(|c| c.get()) {
            return None;
        }
        self.straight[path]
            .as_ref()
            .filter(|sp| sp.stack() && self.guess == InitialGuess::RayParameter)
    }

    /// Whether the default start of path `path` is its solution up to round-off where it
    /// applies: reflections off one-segment interfaces (the image method), refractions
    /// through parallel ones started from the ray parameter. A batch does not warm-start such
    /// a path.
    pub(crate) fn exact_start(&self, path: usize) -> bool {
        let ray_parameter = self.guess == InitialGuess::RayParameter;
        self.straight[path]
            .as_ref()
            .is_some_and(|f| f.exact(ray_parameter))
    }

    /// Solves one ray from `start`: a refraction at a one-segment interface with the flat
    /// kernel in place, else the one-interaction code or the general solve, both out of line.
    #[inline(always)]
    fn solve_inner(
        &self,
        source: Point,
        src_medium: Option<usize>,
        receiver: Point,
        path: usize,
        start: Start,
        ws: &mut Workspace,
    ) -> RaySummary {
        if let Some(sp) = self.single_path(path) {
            if let (Start::Default, Some(flat)) = (start, sp.flat())
                && let Some(sol) = flat.solve(source, receiver)
            {
                return self.single_flat(sp, flat, path, source, receiver, sol, ws);
            }
            return self.solve_single_path(sp, source, receiver, path, start, ws);
        }
        self.solve_general(source, src_medium, receiver, path, start, ws)
    }

    /// [`solve_inner`](Self::solve_inner) for a path of more than one interaction, or without
    /// its media given: out of line, so that the one-interaction code keeps a small stack
    /// frame.
    #[inline(never)]
    fn solve_general(
        &self,
        source: Point,
        src_medium: Option<usize>,
        receiver: Point,
        path: usize,
        start: Start,
        ws: &mut Workspace,
    ) -> RaySummary {
        if let (Start::Default, Some(sp)) = (start, self.stack_path(path))
            && let Some(ray) = self.solve_stack(sp, path, source, receiver, ws)
        {
            return ray;
        }
        let scene = self.scene;
        let spec = &scene.paths()[path];
        let k = spec.steps.len();
        let opts = scene.solver();
        ws.resize(k);
        ws.slowness.clear();
        ws.media.clear();
        ws.points.clear();
        let mut beyond = None;
        match start {
            Start::Given(params) => given_start(scene, &spec.steps, params, ws),
            Start::Default | Start::Compare(_) => {
                let straight = self.straight[path].as_ref();
                let images = self.guess == InitialGuess::RayParameter;
                match straight.map(|f| f.start(source, receiver, images, ws)) {
                    Some(straight::Start::At) => {}
                    // With media given (a lookup decides before the geometry).
                    Some(straight::Start::Beyond { step }) if spec.media.is_some() => {
                        beyond = Some(step);
                    }
                    _ => initial_guess(scene, &spec.steps, source, receiver, ws),
                }
            }
        }
        let lookup = spec.media.is_none();
        if let Some(m) = &spec.media {
            ws.media.extend_from_slice(m);
        } else if let Err(reason) = self.lookup_media(source, src_medium, &spec.steps, ws) {
            // All leg media or none, as a batch records them (not those found before the gap).
            ws.media.clear();
            return failed(Status::NoPath, reason);
        }
        if let Some(step) = beyond {
            return failed(Status::NoPath, Reason::LeavesEnd { step });
        }
        ws.slowness
            .extend(ws.media.iter().map(|&m| scene.media()[m].slowness));
        if !matches!(start, Start::Given(_)) {
            refraction_guess(scene, &spec.steps, source, receiver, self.guess, ws);
        }
        if let Start::Compare(guess) = start {
            let slowness = std::mem::take(&mut ws.slowness);
            let g = Geometry {
                scene,
                steps: &spec.steps,
                slowness: &slowness,
                source,
                receiver,
            };
            warm_start(&g, guess, ws);
            ws.slowness = slowness;
        }

        let mut total_iterations = 0;
        let mut rounds = 0;
        let (outcome, sol) = loop {
            let slowness = std::mem::take(&mut ws.slowness);
            let g = Geometry {
                scene,
                steps: &spec.steps,
                slowness: &slowness,
                source,
                receiver,
            };
            let (outcome, mut sol) = solve(
                &g,
                ws,
                opts.tolerance,
                opts.max_iterations.saturating_sub(total_iterations),
            );
            ws.slowness = slowness;
            total_iterations += sol.iterations;
            sol.iterations = total_iterations;
            if !lookup || outcome == Outcome::NotConverged {
                break (outcome, sol);
            }
            // Media must match the solution's geometry: look them up again at the final points.
            std::mem::swap(&mut ws.media, &mut ws.media_prev);
            if let Err(reason) = self.lookup_media(source, src_medium, &spec.steps, ws) {
                std::mem::swap(&mut ws.media, &mut ws.media_prev);
                return RaySummary {
                    reason: Some(reason),
                    status: Status::NoPath,
                    ..summary(sol)
                };
            }
            if ws.media == ws.media_prev {
                break (outcome, sol);
            }
            rounds += 1;
            if rounds >= 3 {
                return RaySummary {
                    reason: Some(Reason::MediaUnsettled),
                    status: Status::NoPath,
                    ..summary(sol)
                };
            }
            ws.slowness.clear();
            ws.slowness
                .extend(ws.media.iter().map(|&m| scene.media()[m].slowness));
        };

        self.classify(path, source, receiver, outcome, sol, ws)
    }

    /// The ray's status after the solve ended with `outcome` (`sol`): its points in `ws`, then
    /// the end, vertex, side and obstruction tests.
    fn classify(
        &self,
        path: usize,
        source: Point,
        receiver: Point,
        outcome: Outcome,
        sol: crate::solver::Solution,
        ws: &mut Workspace,
    ) -> RaySummary {
        let scene = self.scene;
        let spec = &scene.paths()[path];
        let k = spec.steps.len();
        ws.points.clear();
        ws.points.push(source);
        let on = spec.steps.iter().zip(&ws.seg[..k]).zip(&ws.s[..k]);
        ws.points.extend(
            on.map(|((step, &j), &s)| scene.interfaces()[step.interface].polyline.point_on(j, s)),
        );
        ws.points.push(receiver);
        let base = summary(sol);
        match outcome {
            Outcome::NotConverged => {
                return RaySummary {
                    status: Status::NotConverged,
                    reason: Some(Reason::IterationLimit),
                    ..base
                };
            }
            Outcome::LeftEnd(step) => {
                return RaySummary {
                    status: Status::NoPath,
                    reason: Some(Reason::LeavesEnd { step }),
                    ..base
                };
            }
            Outcome::Converged | Outcome::Vertex => {}
        }
        // The first interaction next to a vanished leg between two interactions: leg `j`
        // (1 ≤ j < k) joins interactions `j − 1` and `j`.
        let interior = ws.eval.len.get(1..k).unwrap_or(&[]);
        if let Some(step) = interior.iter().position(|&l| l <= ws.eval.vanish) {
            return RaySummary {
                status: Status::NoPath,
                reason: Some(Reason::Coincident { step }),
                ..base
            };
        }
        // A point held where a leg to the source or receiver vanished must still be strictly
        // inside a segment: at an open end there is no path, at a vertex it is a kink there.
        let mut at_vertex = None;
        for (i, step) in spec.steps.iter().enumerate() {
            if ws.pin[i] != Pin::Kink {
                continue;
            }
            let line = &scene.interfaces()[step.interface].polyline;
            let (s, j) = (ws.s[i], ws.seg[i]);
            if s > line.start(j) && s < line.start(j + 1) {
                continue;
            }
            if !line.is_closed() && (s <= 0.0 || s >= line.length()) {
                return RaySummary {
                    status: Status::NoPath,
                    reason: Some(Reason::LeavesEnd { step: i }),
                    ..base
                };
            }
            at_vertex.get_or_insert(i);
        }
        if let Some(step) = self.wrong_side(&spec.steps, ws) {
            return RaySummary {
                status: Status::NoPath,
                reason: Some(Reason::WrongSide { step }),
                ..base
            };
        }
        if let Some((leg, interface)) = self.obstruction(path, &ws.points, &ws.seg[..k]) {
            return RaySummary {
                status: Status::Obstructed,
                reason: Some(Reason::Crosses { leg, interface }),
                ..base
            };
        }
        if let Some(step) = ws.pin.iter().position(|p| *p == Pin::Vertex).or(at_vertex) {
            return RaySummary {
                status: Status::Vertex,
                reason: Some(Reason::AtVertex { step }),
                ..base
            };
        }
        RaySummary {
            status: Status::Converged,
            reason: None,
            ..base
        }
    }

    /// Leg media from the regions at the current points: the source's region for leg 0; a
    /// reflection keeps the medium, a refraction takes the one across the interface.
    fn lookup_media(
        &self,
        source: Point,
        src_medium: Option<usize>,
        steps: &[crate::scene::Step],
        ws: &mut Workspace,
    ) -> Result<(), Reason> {
        let regions = self.regions.as_ref().ok_or(Reason::NoMedium { leg: 0 })?;
        ws.media.clear();
        let mut m = src_medium.ok_or(Reason::NoMedium { leg: 0 })?;
        ws.media.push(m);
        let mut prev = source;
        for (i, step) in steps.iter().enumerate() {
            let line = &self.scene.interfaces()[step.interface].polyline;
            let here = line.point_on(ws.seg[i], ws.s[i]);
            if step.kind == StepKind::Refract {
                m = regions
                    .medium_across(step.interface, ws.seg[i], ws.s[i], prev)
                    .ok_or(Reason::NoMedium { leg: i + 1 })?;
            }
            ws.media.push(m);
            prev = here;
        }
        Ok(())
    }

    /// First step whose legs are not on the sides it demands.
    fn wrong_side(&self, steps: &[crate::scene::Step], ws: &Workspace) -> Option<usize> {
        let (k, e) = (steps.len(), &ws.eval);
        let (seg, pin, rel, len) = (&ws.seg[..k], &ws.pin[..k], &e.rel[..k + 2], &e.len[..k + 1]);
        for (i, step) in steps.iter().enumerate() {
            let line = &self.scene.interfaces()[step.interface].polyline;
            let j = seg[i];
            let mut n = line.normal(j);
            // |n|: 1 for a segment's unit normal; at a vertex, of the sum of the two.
            let mut n_len = 1.0;
            if pin[i] == Pin::Vertex {
                let before = if j > 0 {
                    j - 1
                } else {
                    line.num_segments() - 1
                };
                n += line.normal(before);
                n_len = n.length();
            }
            let (a, b) = leg_sides(n, n_len, &rel[i..i + 3], &len[i..i + 2]);
            let (la, lb) = (len[i], len[i + 1]);
            // A vanished leg (an end point on the interface there) lies on both sides: the
            // other leg must still lie on one.
            let tiny = e.vanish;
            let (gone_a, gone_b) = (la <= tiny, lb <= tiny);
            if gone_a || gone_b {
                let other_on_a_side = if gone_a {
                    !gone_b && b != 0.0
                } else {
                    a != 0.0
                };
                if !other_on_a_side {
                    return Some(i);
                }
                continue;
            }
            if !sides_suit(step.kind, a, b) {
                return Some(i);
            }
        }
        None
    }

    /// First leg that crosses an interface strictly between its ends: `(leg, interface)`.
    /// `pts` are the source, the interaction points and the receiver; `seg` the segments of
    /// the interaction points, which their own legs are not tested against (see
    /// [`Scene::first_crossing`]).
    #[inline(always)]
    fn obstruction(&self, path: usize, pts: &[Point], seg: &[usize]) -> Option<(usize, usize)> {
        // A clear path between points within the scene's ends: nothing to test (the common
        // case of a survey through layers, checked here without a call).
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        if self.clear[path] && self.ends[0].contains(a) && self.ends[1].contains(b) {
            return None;
        }
        self.obstruction_tested(path, pts, seg)
    }

    /// [`obstruction`](Self::obstruction) leg by leg.
    fn obstruction_tested(
        &self,
        path: usize,
        pts: &[Point],
        seg: &[usize],
    ) -> Option<(usize, usize)> {
        let k = seg.len();
        let (pts, steps) = (&pts[..k + 2], &self.scene.paths()[path].steps[..k]);
        let legs = &self.leg_candidates[path][..k + 1];
        // The end legs' candidates hold for a source and a receiver within the scene's.
        let usable = [
            self.ends[0].contains(pts[0]),
            self.ends[1].contains(pts[k + 1]),
        ];
        let mut own_a = SegmentRef::NONE;
        for leg in 0..=k {
            let (a, b) = (pts[leg], pts[leg + 1]);
            let own_b = if leg < k {
                SegmentRef {
                    interface: steps[leg].interface as u32,
                    segment: seg[leg] as u32,
                }
            } else {
                SegmentRef::NONE
            };
            if a != b {
                let own = [own_a, own_b];
                let hit = match legs[leg].as_deref() {
                    Some(c) if (leg > 0 || usable[0]) && (leg < k || usable[1]) => {
                        self.scene.first_crossing_among(a, b, END_MARGIN, c, own)
                    }
                    _ => self.scene.first_crossing(a, b, END_MARGIN, own),
                };
                if let Some(r) = hit {
                    return Some((leg, r.interface as usize));
                }
            }
            own_a = own_b;
        }
        None
    }
}

/// A leg between two interactions has its end points on their interfaces, so it lies in the
/// convex hull of the two interfaces; a leg from the source lies in the hull of the first
/// interface and the box `ends[0]` (when the source is in it), one to the receiver in that of
/// the last interface and `ends[1]`: the scene segments that meet that hull (widened by
/// round-off) are all it can cross. Where they are few (a leg between two layers of a stack,
/// flat or dipping: those two interfaces; the legs of a refraction at a lone surface), the
/// obstruction test checks just them instead of querying the scene's BVH, whose boxes of long
/// slanted segments all overlap. The segment of an end's interface when it has only that one
/// is left out: the leg ends on it, so it is the leg's own (see [`Scene::first_crossing`]).
/// Per leg `0..=k`.
fn leg_candidates(
    scene: &Scene,
    steps: &[crate::scene::Step],
    ends: [Aabb; 2],
) -> Vec<Option<Box<[u32]>>> {
    /// More candidates than this: the BVH query is as quick.
    const MAX: usize = 8;
    /// Segments in the hull's box beyond which the hull test is not worth making.
    const BOX_LIMIT: usize = 4096;
    let k = steps.len();
    let corners = |b: Aabb| {
        [
            b.min,
            Point::new(b.max.x, b.min.y),
            b.max,
            Point::new(b.min.x, b.max.y),
        ]
    };
    (0..=k)
        .map(|leg| {
            // What each end of the leg lies on: an interaction's interface, or the box of the
            // scene's sources (receivers); `None` when there are none.
            enum Side<'a> {
                Line(&'a crate::polyline::Polyline),
                Box(Aabb),
            }
            let side = |i: Option<usize>, b: Aabb| match i {
                Some(i) => Some(Side::Line(&scene.interfaces()[steps[i].interface].polyline)),
                None => (b.min.x <= b.max.x).then_some(Side::Box(b)),
            };
            let sides = [
                side(leg.checked_sub(1), ends[0])?,
                side((leg < k).then_some(leg), ends[1])?,
            ];
            let bbox = sides
                .iter()
                .map(|e| match e {
                    Side::Line(line) => line.bbox(),
                    Side::Box(b) => *b,
                })
                .fold(Aabb::EMPTY, Aabb::union);
            let pad = 1e-9
                * (bbox.max.x - bbox.min.x
                    + (bbox.max.y - bbox.min.y)
                    + bbox.max.x.abs()
                    + bbox.min.x.abs()
                    + bbox.max.y.abs()
                    + bbox.min.y.abs());
            let grown = Aabb {
                min: Point::new(bbox.min.x - pad, bbox.min.y - pad),
                max: Point::new(bbox.max.x + pad, bbox.max.y + pad),
            };
            // (A long interface fills the box with its own segments: no copy of its vertices.)
            let in_box = scene.segments_in(grown, BOX_LIMIT)?;
            let pts = sides
                .iter()
                .flat_map(|e| match e {
                    Side::Line(line) => line.vertices().to_vec(),
                    Side::Box(b) => corners(*b).to_vec(),
                })
                .collect();
            let hull = convex_hull(pts);
            // The interfaces of the leg's ends that are one segment.
            let lone = |i: Option<usize>| {
                i.map(|i| steps[i].interface)
                    .filter(|&f| scene.interfaces()[f].polyline.num_segments() == 1)
            };
            let own = [lone(leg.checked_sub(1)), lone((leg < k).then_some(leg))];
            let found: Vec<u32> = in_box
                .into_iter()
                .filter(|&i| {
                    let r = scene.segments()[i as usize];
                    let (p, q) = scene.segment_points(r);
                    !own.contains(&Some(r.interface as usize)) && meets_convex(p, q, &hull, pad)
                })
                .collect();
            (found.len() <= MAX).then(|| found.into_boxed_slice())
        })
        .collect()
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain; collinear points
/// dropped; fewer than three points as they are, sorted).
fn convex_hull(mut points: Vec<Point>) -> Vec<Point> {
    points.sort_by(|p, q| p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    // Appends `p` to the chain that starts at `floor`, dropping the points it turns right at.
    let push = |hull: &mut Vec<Point>, floor: usize, p: Point| {
        while hull.len() >= floor + 2
            && crate::geom::orient(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
        {
            hull.pop();
        }
        hull.push(p);
    };
    let mut hull = Vec::with_capacity(2 * points.len());
    for &p in &points {
        push(&mut hull, 0, p);
    }
    hull.pop();
    let floor = hull.len();
    for &p in points.iter().rev() {
        push(&mut hull, floor, p);
    }
    hull.pop();
    hull
}

/// Whether segment `p–q` meets the convex polygon `hull` (counter-clockwise, or up to two
/// points: a segment or a point) grown by `pad`: no separating axis among the polygon's edge
/// normals and the segment's normal.
fn meets_convex(p: Point, q: Point, hull: &[Point], pad: f64) -> bool {
    let separated = |n: Vec2| {
        let len = n.length();
        if len.is_nan() || len <= 0.0 {
            return false;
        }
        let proj = |x: Point| x.x * n.x + x.y * n.y;
        let (s0, s1) = (proj(p).min(proj(q)), proj(p).max(proj(q)));
        let (h0, h1) = hull
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &h| {
                (lo.min(proj(h)), hi.max(proj(h)))
            });
        s1 < h0 - pad * len || s0 > h1 + pad * len
    };
    let n = hull.len();
    let edges = (0..n).map(|i| hull[(i + 1) % n] - hull[i]);
    let mut axes: Vec<Vec2> = edges.map(|e| e.perp()).collect();
    axes.push((q - p).perp());
    // Axis-aligned axes too: a degenerate hull (a segment) needs its own extent checked.
    axes.push(Vec2::new(1.0, 0.0));
    axes.push(Vec2::new(0.0, 1.0));
    !axes.into_iter().any(separated)
}

/// A leg whose sine with the interface is below this runs along it, on neither side.
const SIDE_MARGIN: f64 = 1e-10;

/// Where the legs of an interaction lie against the normal `n` (of length `n_len`) of its
/// interface there, from the points before, at and after it (`rel`, relative to the source)
/// and the two legs' lengths (`len`): `(a, b)`, the source-side and receiver-side legs'
/// components along `n`, zero for a leg within [`SIDE_MARGIN`] rad of the interface (it runs
/// along it: on neither side).
#[inline(always)]
fn leg_sides(n: Vec2, n_len: f64, rel: &[Vec2], len: &[f64]) -> (f64, f64) {
    let a = n.dot(rel[0] - rel[1]);
    let b = n.dot(rel[2] - rel[1]);
    let (la, lb) = (len[0], len[1]);
    let a = if a.abs() <= SIDE_MARGIN * la * n_len {
        0.0
    } else {
        a
    };
    let b = if b.abs() <= SIDE_MARGIN * lb * n_len {
        0.0
    } else {
        b
    };
    (a, b)
}

/// Whether legs on sides `a` and `b` ([`leg_sides`]) are what `kind` demands: one side for a
/// reflection, opposite sides for a refraction.
#[inline(always)]
fn sides_suit(kind: StepKind, a: f64, b: f64) -> bool {
    match kind {
        StepKind::Reflect => (a > 0.0 && b > 0.0) || (a < 0.0 && b < 0.0),
        StepKind::Refract => (a > 0.0 && b < 0.0) || (a < 0.0 && b > 0.0),
    }
}

/// Crossings closer than this fraction of a leg to its ends are the leg's own end points.
const END_MARGIN: f64 = 1e-10;

/// A ray that ended before the solver ran: no time, no residual.
fn failed(status: Status, reason: Reason) -> RaySummary {
    RaySummary {
        status,
        time: f64::NAN,
        iterations: 0,
        residual: f64::NAN,
        reason: Some(reason),
    }
}

fn summary(sol: crate::solver::Solution) -> RaySummary {
    RaySummary {
        status: Status::NotConverged,
        time: sol.time,
        iterations: sol.iterations,
        residual: sol.residual,
        reason: None,
    }
}

/// Replaces the default guess already in `ws` by `guess` if the residual is smaller there.
fn warm_start(g: &Geometry, guess: &[f64], ws: &mut Workspace) {
    let default_merit = crate::solver::merit_at(g, ws);
    ws.s_alt.copy_from_slice(&ws.s);
    ws.seg_alt.copy_from_slice(&ws.seg);
    given_start(g.scene, g.steps, guess, ws);
    let warm_merit = crate::solver::merit_at(g, ws);
    // Keep the default guess unless the warm one is better (NaN counts as worse).
    if warm_merit.partial_cmp(&default_merit) != Some(std::cmp::Ordering::Less) {
        ws.s.copy_from_slice(&ws.s_alt);
        ws.seg.copy_from_slice(&ws.seg_alt);
    }
}

/// Starts from given parameters (wrapped on closed polylines, clamped to open ones).
fn given_start(scene: &Scene, steps: &[crate::scene::Step], params: &[f64], ws: &mut Workspace) {
    for (i, (step, &wanted)) in steps.iter().zip(params).enumerate() {
        let line = &scene.interfaces()[step.interface].polyline;
        (ws.s[i], ws.seg[i]) = given_param(line, wanted, ws.seg[i]);
        ws.pin[i] = Pin::Free;
    }
}

/// One parameter of [`given_start`]: `wanted` made valid on `line` and its segment (`hint`
/// tried first; the segment does not depend on it).
#[inline(always)]
pub(crate) fn given_param(
    line: &crate::polyline::Polyline,
    wanted: f64,
    hint: usize,
) -> (f64, usize) {
    let s = line.clamp_param(wanted);
    (s, line.segment_at_hint(s, hint))
}

/// Polylines with more segments than this start a reflection at the crossing of the
/// perpendicular through the target point (see [`Tracer`]) rather than at the nearest point.
const LONG_POLYLINE: usize = 1024;

/// Where the line through `target` perpendicular to `source → receiver` crosses `line`,
/// nearest to `target`: `(parameter, distance, segment)`. An `O(log M)` query of the
/// polyline's BVH (a line crosses a gently curved polyline a few times), where the
/// nearest-point query from a target far from a long digitised curve opens about `√M` leaves.
fn perpendicular_crossing(
    line: &crate::polyline::Polyline,
    source: Point,
    receiver: Point,
    target: Point,
) -> Option<(f64, f64, usize)> {
    let d = receiver - source;
    let len = d.length();
    if !(len > 0.0 && len.is_finite()) {
        return None;
    }
    let n = d.perp() * (1.0 / len);
    let b = line.bbox();
    let reach = (b.max.x - target.x).abs().max((b.min.x - target.x).abs())
        + (b.max.y - target.y).abs().max((b.min.y - target.y).abs());
    let (a, e) = (target - n * reach, target + n * reach);
    let mut best: Option<(f64, f64, usize)> = None;
    line.crossings_with_segment(a, e, |s, t, j| {
        let dist = (t - 0.5).abs() * 2.0 * reach;
        if best.is_none_or(|(_, bd, _)| dist < bd) {
            best = Some((s, dist, j));
        }
    });
    best
}

/// Refines the straight-line guess of a path of refractions only (every step crossed by the
/// line `S → R`, at increasing fractions `tᵢ`, kept in `ws.crossing_t`): each point moves along
/// its interface to the lateral fraction `τᵢ` where a ray through flat layers would cross.
///
/// The layers are taken as flat and parallel, `Δzⱼ = Δtⱼ Z` thick, where `Z` and `X` are the
/// extents of `R − S` across and along them. When the interfaces' normals at the crossings agree
/// to within [`PARALLEL`], the ray parameter `p` solves `Σⱼ Δzⱼ tan θⱼ = X` with
/// `sin θⱼ = p / wⱼ` (Halley's steps from a `p` above the root of this convex, increasing
/// function, see [`ray_parameter`]), and
/// `τᵢ = Σ_{j≤i} Δzⱼ tan θⱼ / X`: the exact solution for parallel flat layers. Otherwise, for
/// a single refraction, or when that equation has no root (a ray beyond the critical angle of
/// a layer), the paraxial fractions
/// `τᵢ = Σ_{j≤i} Δtⱼ/wⱼ / Σ Δtⱼ/wⱼ` (the small-angle limit).
fn refraction_guess(
    scene: &Scene,
    steps: &[crate::scene::Step],
    source: Point,
    receiver: Point,
    guess: InitialGuess,
    ws: &mut Workspace,
) {
    let k = steps.len();
    let w = &ws.slowness;
    if k == 0 || w.len() != k + 1 {
        return;
    }
    if k == 1 {
        // One refraction: the 1-D ray-parameter solve is the Newton solve's own one-unknown
        // problem and costs as much; the paraxial start.
        let line = &scene.interfaces()[steps[0].interface].polyline;
        let (t, w) = (ws.crossing_t[0], [w[0], w[1]]);
        (ws.s[0], ws.seg[0]) = paraxial_one(line, ws.s[0], t, ws.seg[0], w, receiver - source);
        return;
    }
    let lines = PathLines { scene, steps };
    layered_guess(&lines, receiver - source, guess, ws);
}

/// The interfaces of a path as [`layered_guess`] sees them.
pub(super) trait Lines {
    /// The unit tangent of interface `i` on its segment `seg`.
    fn tangent(&self, i: usize, seg: usize) -> Vec2;
    /// Parameter `s` made valid on interface `i` ([`Polyline::clamp_param`]) and its segment
    /// (`seg` tried first).
    fn place(&self, i: usize, s: f64, seg: usize) -> (f64, usize);
}

/// The interfaces of a path's steps, looked up in the scene.
struct PathLines<'a> {
    scene: &'a Scene,
    steps: &'a [crate::scene::Step],
}

impl PathLines<'_> {
    #[inline(always)]
    fn line(&self, i: usize) -> &Polyline {
        &self.scene.interfaces()[self.steps[i].interface].polyline
    }
}

impl Lines for PathLines<'_> {
    #[inline(always)]
    fn tangent(&self, i: usize, seg: usize) -> Vec2 {
        self.line(i).tangent(seg)
    }

    #[inline(always)]
    fn place(&self, i: usize, s: f64, seg: usize) -> (f64, usize) {
        let line = self.line(i);
        let s = line.clamp_param(s);
        (s, line.segment_at_hint(s, seg))
    }
}

/// [`refraction_guess`] for two or more refractions (`lines` the path's interfaces, `d` the
/// receiver minus the source, the slownesses and crossings in `ws`).
#[inline(always)]
pub(super) fn layered_guess(
    lines: &(impl Lines + ?Sized),
    d: Vec2,
    guess: InitialGuess,
    ws: &mut Workspace,
) {
    let k = ws.s.len();
    debug_assert!(k >= 2 && ws.slowness.len() == k + 1);
    let (t, w) = (&ws.crossing_t[..k], &ws.slowness[..k + 1]);
    let mut prev = 0.0;
    let mut sum = 0.0;
    for i in 0..=k {
        let ti = if i < k { t[i] } else { 1.0 };
        if !(ti > prev && ti <= 1.0) {
            return;
        }
        sum += (ti - prev) / w[i];
        prev = ti;
    }
    let seg = &ws.seg[..k];
    let tangent = |i: usize| lines.tangent(i, seg[i]);
    let p = match guess {
        InitialGuess::RayParameter => ray_parameter(t, w, sum, d, tangent, &mut ws.layers),
        InitialGuess::Paraxial => None,
    };
    let mut acc = 0.0;
    prev = 0.0;
    let (s_at, seg) = (&mut ws.s[..k], &mut ws.seg[..k]);
    for i in 0..k {
        let tau = match p {
            Some((_, x)) => {
                // Δtᵢ tan θᵢ, from the evaluation at p.
                acc += ws.layers[i].offset;
                acc / x
            }
            None => {
                acc += (t[i] - prev) / w[i];
                acc / sum
            }
        };
        prev = t[i];
        let lateral = d.dot(lines.tangent(i, seg[i]));
        (s_at[i], seg[i]) = lines.place(i, s_at[i] + (tau - t[i]) * lateral, seg[i]);
    }
}

/// Largest angle between two interfaces' normals (as `1 − cos`) for which
/// [`refraction_guess`] treats the layers as parallel: about 5e-5 rad, round-off of digitised
/// coordinates. (With 8° the refinement also served nearly parallel layers: through the 5°
/// dips of `demo::dipping_stack` it saved 0.1–0.3 of 3 Newton steps per ray but cost more
/// time than it saved.)
const PARALLEL: f64 = 1e-9;

/// One layer of [`ray_parameter`]'s equation: its thickness `Δt` (in units of `Z`) and
/// speed `v`, and at the last ray parameter `p` evaluated, the lateral offset across it
/// `Δt tan θ` (`sin θ = p v`) and that offset's first two derivatives in `p`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Layer {
    dt: f64,
    v: f64,
    pub(crate) offset: f64,
    slope: f64,
    bend: f64,
}

/// The ray parameter of [`refraction_guess`] for crossing fractions `t` (increasing, in
/// `(0, 1]`), slownesses `w`, the paraxial denominator `sum = Σⱼ Δtⱼ/wⱼ` and `d = R − S`, with
/// `tangent(i)` the tangent of interface `i` at its crossing: `(p, X / Z)`, `p` solving `Σⱼ Δtⱼ tan θⱼ = X / Z` with `sin θⱼ = p / wⱼ`
/// (thicknesses in units of `Z`). `None` when the interfaces are not parallel, `X` is zero (the
/// straight line is the ray) or the equation has no root. `layers` is scratch.
fn ray_parameter(
    t: &[f64],
    w: &[f64],
    sum: f64,
    d: Vec2,
    tangent: impl Fn(usize) -> Vec2,
    layers: &mut Vec<Layer>,
) -> Option<(f64, f64)> {
    let k = t.len();
    let m = tangent(0);
    if (1..k).any(|i| tangent(i).dot(m).abs() < 1.0 - PARALLEL) {
        return None;
    }
    // Across (`z`) and along (`x`) the first interface.
    let (z, x) = (d.cross(m).abs(), d.dot(m).abs());
    let x = x / z;
    if !(x > 0.0 && x.is_finite()) {
        return None;
    }
    // Per layer: thickness Δtⱼ (in units of Z) and speed vⱼ = 1/wⱼ; the sums Σ Δtⱼ vⱼⁿ for
    // n = 3, 5, 7 (of the series below); the smallest slowness `limit` (a layer's critical
    // angle) and how thick the layers of that slowness are together (`critical`).
    let (mut limit, mut critical, mut prev) = (f64::INFINITY, 0.0, 0.0);
    let mut series = [0.0; 3];
    layers.clear();
    for (j, &wj) in w[..=k].iter().enumerate() {
        let hi = if j < k { t[j] } else { 1.0 };
        let (dt, v) = (hi - prev, 1.0 / wj);
        layers.push(Layer {
            dt,
            v,
            ..Layer::default()
        });
        let (a, v2) = (dt * v, v * v);
        series[0] += a * v2;
        series[1] += a * v2 * v2;
        series[2] += a * v2 * v2 * v2;
        prev = hi;
        // (Slownesses are positive and finite.)
        if wj < limit {
            (limit, critical) = (wj, dt);
        } else if wj == limit {
            critical += dt;
        }
    }
    // The paraxial p (tan θ ≈ sin θ): f(p) ≥ 0 there, as tan θ ≥ sin θ. Below the smallest
    // slowness f is defined; just below it, it must be positive.
    let cap = limit * (1.0 - 1e-9);
    let small_angle = x / sum;
    let paraxial = small_angle.min(cap);
    // Where the paraxial p is near that critical angle, the p at which the layers of the
    // smallest slowness alone (`Δt` thick together) take the whole offset, `Δt tan θ = x`, is
    // nearer the root and still above it (the other layers add to f). From the paraxial p
    // alone the iterates would first back away from the pole (f is steep there, like
    // 1/√(p_max − p)) by a factor of about 3 a step: 15 or more steps.
    let tan = x / critical;
    let alone = limit * (tan / (1.0 + tan * tan).sqrt());
    // f(p) = Σ Δtⱼ sⱼ / cⱼ − x with sⱼ = p / wⱼ, cⱼ = √(1 − sⱼ²); f' = Σ Δtⱼ vⱼ / cⱼ³ and
    // f'' = Σ 3 Δtⱼ vⱼ² sⱼ / cⱼ⁵. Each evaluation leaves the offsets Δtⱼ tan θⱼ = Δtⱼ sⱼ / cⱼ
    // and their derivatives in the layers, for the caller: every return with a p follows an
    // evaluation at that p, or a last step whose own error is below round-off, with the
    // offsets moved along their Taylor series.
    let mut f = |p: f64| {
        let (mut f, mut df, mut d2f) = (-x, 0.0, 0.0);
        for l in layers.iter_mut() {
            let sin = p * l.v;
            let r = 1.0 / (1.0 - sin * sin).sqrt();
            let a = l.dt * r;
            l.offset = a * sin;
            l.slope = a * l.v * r * r;
            l.bend = 3.0 * l.slope * l.v * sin * r * r;
            f += l.offset;
            df += l.slope;
            d2f += l.bend;
        }
        (f, df, d2f)
    };
    // (`alone` may exceed `cap`: the root can lie nearer the pole than that.)
    let mut p = small_angle.min(alone);
    // tan θ = sin θ (1 + sin²θ / 2 + 3 sin⁴θ / 8 + 5 sin⁶θ / 16 + …), all terms positive: the
    // first four make a polynomial P(p) ≤ f(p) + x, convex and increasing, whose root is
    // therefore above f's; Newton's iterates on it from its linear part's root (the
    // paraxial p) stay above its root. Three of them, without a square root or a division by
    // layer, save 1.5 of the 4.8 evaluations of f per ray through `demo::layer_stack(8, _)`.
    let [b3, b5, b7] = series;
    let mut q = small_angle;
    for _ in 0..3 {
        let q2 = q * q;
        let g = q * (sum + q2 * (0.5 * b3 + q2 * (0.375 * b5 + q2 * 0.3125 * b7))) - x;
        let dg = sum + q2 * (1.5 * b3 + q2 * (1.875 * b5 + q2 * 2.1875 * b7));
        q -= g / dg;
    }
    // (A NaN `q`, from overflowing powers of a huge speed, is not taken.)
    let series_bound = q < p;
    if series_bound {
        p = q;
    }
    if p >= limit {
        p = cap;
    }
    let (mut fp, mut dfp, mut d2fp) = f(p);
    if series_bound && fp < 0.0 && fp >= -64.0 * f64::EPSILON * x {
        // Where the series' neglected terms are below round-off, its root is f's to within
        // round-off, on either side.
        return Some((p, x));
    }
    if (fp.is_nan() || fp < 0.0) && p < paraxial {
        // Round-off put `alone` (or the series' root) below the root.
        p = paraxial;
        (fp, dfp, d2fp) = f(p);
    }
    let sound = |fp: f64, dfp: f64, d2fp: f64| dfp > 0.0 && crate::problem::finite(fp + dfp + d2fp);
    if !(fp >= 0.0 && sound(fp, dfp, d2fp)) {
        return None;
    }
    // Halley's steps from above the root of this convex increasing function (Newton's, where
    // the curvature would more than double the step): the error after a step of `h` is about
    // `(ρ²/4 + (h vₘₐₓ)²/2) |h|` with `ρ = h f''/f'` (the f‴ term bounded through the
    // largest speed, `1/limit`). Where a thousand times that is below round-off, the step is
    // the last: the offsets follow it to second order (their error of order h³, below
    // round-off too), without another evaluation. Through `demo::layer_stack(8, 500)` this
    // takes 1.8 evaluations per ray where Newton's steps to a residual at round-off took 3.3.
    let vmax = 1.0 / limit;
    for _ in 0..60 {
        if fp.abs() <= 4.0 * f64::EPSILON * x {
            break;
        }
        let newton = fp / dfp;
        let rho = newton * d2fp / dfp;
        let h = if rho.abs() < 1.0 {
            newton / (1.0 - 0.5 * rho)
        } else {
            newton
        };
        let next = p - h;
        // (A step that leaves `[0, limit)` or does not move is round-off.)
        if !(next >= 0.0 && next < limit && next != p) {
            break;
        }
        let hv = h * vmax;
        if (rho * rho + hv * hv) * h.abs() <= 1e-3 * f64::EPSILON * next {
            for l in layers.iter_mut() {
                l.offset -= h * (l.slope - 0.5 * h * l.bend);
            }
            return Some((next, x));
        }
        p = next;
        (fp, dfp, d2fp) = f(p);
        if !sound(fp, dfp, d2fp) {
            return None;
        }
    }
    Some((p, x))
}

/// The image method on the tangent line of `line` at parameter `s` (segment `j`): the
/// specular point of a mirror along that line between `source` and `receiver`, as a parameter
/// of `line` (moved by the offset along the tangent, clamped). Exact for a straight mirror; a
/// gently curved one starts close to its specular point. `s` itself when both are not on one
/// side of the line.
fn image_point(
    line: &crate::polyline::Polyline,
    s: f64,
    j: usize,
    source: Point,
    receiver: Point,
) -> f64 {
    let t = line.tangent(j);
    let p0 = line.point_on(j, s);
    let (hs, hr) = ((source - p0).cross(t), (receiver - p0).cross(t));
    let product = hs * hr;
    if product.is_nan() || product <= 0.0 {
        return s;
    }
    let (us, ur) = ((source - p0).dot(t), (receiver - p0).dot(t));
    let u = us + (ur - us) * hs / (hs + hr);
    if !u.is_finite() {
        return s;
    }
    line.clamp_param(s + u)
}

/// The crossing of `source → receiver` with `line` nearest the fraction `frac` of the way:
/// `(parameter, fraction, segment)`; the first one found of equally near ones.
#[inline(always)]
pub(super) fn nearest_crossing(
    line: &crate::polyline::Polyline,
    source: Point,
    receiver: Point,
    frac: f64,
) -> Option<(f64, f64, usize)> {
    let mut best: Option<(f64, f64, f64, usize)> = None;
    line.crossings_with_segment(source, receiver, |s, t, j| {
        let d = (t - frac).abs();
        if best.is_none_or(|(_, bd, _, _)| d < bd) {
            best = Some((s, d, t, j));
        }
    });
    best.map(|(s, _, t, j)| (s, t, j))
}

/// [`refraction_guess`] for one refraction: the paraxial point from the crossing of `S → R`
/// at fraction `t`, parameter `s` on segment `j` of `line` (unchanged unless `0 < t < 1`),
/// `w` the two slownesses and `d = R − S`.
#[inline(always)]
pub(super) fn paraxial_one(
    line: &crate::polyline::Polyline,
    s: f64,
    t: f64,
    j: usize,
    w: [f64; 2],
    d: Vec2,
) -> (f64, usize) {
    if !(t > 0.0 && t < 1.0) {
        return (s, j);
    }
    let first = (t - 0.0) / w[0];
    let sum = 0.0 + first + (1.0 - t) / w[1];
    let tau = (0.0 + first) / sum;
    let s = line.clamp_param(s + (tau - t) * d.dot(line.tangent(j)));
    (s, line.segment_at_hint(s, j))
}

/// The documented initial guess (see [`Tracer`]).
fn initial_guess(
    scene: &Scene,
    steps: &[crate::scene::Step],
    source: Point,
    receiver: Point,
    ws: &mut Workspace,
) {
    let k = steps.len();
    for (i, step) in steps.iter().enumerate() {
        let line = &scene.interfaces()[step.interface].polyline;
        let frac = (i + 1) as f64 / (k + 1) as f64;
        let target = source.lerp(receiver, frac);
        let mut best: Option<(f64, f64, usize)> = None;
        let mut crossing_t = f64::NAN;
        if step.kind == StepKind::Refract
            && let Some((s, t, j)) = nearest_crossing(line, source, receiver, frac)
        {
            best = Some((s, (t - frac).abs(), j));
            crossing_t = t;
        }
        if best.is_none() && line.num_segments() > LONG_POLYLINE {
            best = perpendicular_crossing(line, source, receiver, target);
            if k == 1
                && step.kind == StepKind::Reflect
                && let Some((s, d, j)) = best
            {
                best = Some((image_point(line, s, j, source, receiver), d, j));
            }
        }
        // The crossing's fraction along S → R, for `refraction_guess` (NaN: no crossing).
        ws.crossing_t[i] = crossing_t;
        let (s, hint) = match best {
            Some((s, _, j)) => (s, j),
            None => {
                let (s, j, _) = line.nearest(target);
                (s, j)
            }
        };
        let s = line.wrap(s);
        ws.s[i] = s;
        ws.seg[i] = line.segment_at_hint(s, hint);
        ws.pin[i] = Pin::Free;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::SplitMix64;

    /// Between two wavy interfaces with a third reaching in between them, the candidate
    /// segments of a leg find a crossing exactly when the scene's BVH query does.
    #[test]
    fn leg_candidates_find_every_crossing() {
        let doc = r#"{
            "media": { "m": { "speed": 1.0 } },
            "interfaces": {
                "a": { "points": [[0, 0], [1.3, 0.3], [2.6, -0.2], [4, 0.2]] },
                "b": { "points": [[0, 2], [1.3, 1.6], [2.6, 2.3], [4, 1.9]] },
                "c": { "points": [[1.5, 1.0], [2.5, 1.2]] },
                "far": { "points": [[10, 10], [11, 10]] }
            },
            "sources": [[0, -1]], "receivers": [[0, 3]],
            "paths": [{ "steps": [{ "refract": "a" }, { "refract": "b" }],
                        "media": ["m", "m", "m"] }]
        }"#;
        let scene = Scene::from_json(doc).unwrap();
        let steps = &scene.paths()[0].steps;
        let cands = leg_candidates(&scene, steps, [Aabb::EMPTY; 2]);
        let c = cands[1].as_deref().expect("few candidates");
        // a, b and c, not the far one.
        assert_eq!(c.len(), 3 + 3 + 1);
        let (a, b) = (
            &scene.interfaces()[steps[0].interface].polyline,
            &scene.interfaces()[steps[1].interface].polyline,
        );
        let mut rng = SplitMix64(3);
        let (mut hits, mut misses) = (0, 0);
        let own = |step: usize, line: &crate::polyline::Polyline, s: f64| SegmentRef {
            interface: steps[step].interface as u32,
            segment: line.segment_at(s) as u32,
        };
        for _ in 0..20_000 {
            let (sa, sb) = (rng.next_f64() * a.length(), rng.next_f64() * b.length());
            let (p, q) = (a.point_at(sa), b.point_at(sb));
            // Without and with the leg's own segments left out: the same answer either way.
            for own in [[SegmentRef::NONE; 2], [own(0, a, sa), own(1, b, sb)]] {
                let bvh = scene.first_crossing(p, q, END_MARGIN, own);
                let among = scene.first_crossing_among(p, q, END_MARGIN, c, own);
                assert_eq!(bvh.is_some(), among.is_some(), "leg {p:?} → {q:?}");
                assert!(
                    bvh.is_none_or(|r| !own.contains(&r)),
                    "{bvh:?} is the leg's own"
                );
                if own[0] != SegmentRef::NONE {
                    if bvh.is_some() {
                        hits += 1
                    } else {
                        misses += 1
                    }
                }
            }
        }
        assert!(hits > 1000 && misses > 1000, "{hits} hits, {misses} misses");
    }

    /// Legs between the layers of a stack, flat or dipping (where the boxes of all layers
    /// overlap), can cross nothing but the two layers they join: one segment each, the legs'
    /// own, so no candidates at all (the path is clear); a third layer or a bend in one
    /// brings candidates back.
    #[test]
    fn stack_legs_have_no_candidates() {
        for spec in [
            crate::demo::layer_stack(20, 3),
            crate::demo::dipping_stack(20, 3),
        ] {
            let scene = Scene::from_spec(&spec).unwrap();
            let tracer = Tracer::new(&scene).unwrap();
            let cands = &tracer.leg_candidates[0];
            assert_eq!(cands.len(), 21);
            assert!(cands.iter().all(|c| c.as_deref() == Some(&[])), "{cands:?}");
            assert!(tracer.clear[0]);
            // Bend the interface of step 5: the legs that end on it (5 and 6) can cross its
            // other segment.
            let mut bent = spec.clone();
            let crate::scene::StepSpec::Refract(name) = &spec.paths[0].steps[5] else {
                panic!("a refraction");
            };
            let points = &mut bent.interfaces.get_mut(name).unwrap().points;
            let (a, b) = (points[0], points[1]);
            points.insert(1, [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]) + 1e-3]);
            let scene = Scene::from_spec(&bent).unwrap();
            let tracer = Tracer::new(&scene).unwrap();
            assert!(!tracer.clear[0]);
            for (leg, c) in tracer.leg_candidates[0].iter().enumerate() {
                let c = c.as_deref().expect("few candidates");
                let expected = if leg == 5 || leg == 6 { 2 } else { 0 };
                assert_eq!(c.len(), expected, "leg {leg}: {c:?}");
                for &i in c {
                    let r = scene.segments()[i as usize];
                    assert_eq!(r.interface as usize, scene.paths()[0].steps[5].interface);
                }
            }
        }
    }

    /// The candidate lists of the legs from the source and to the receiver hold for points
    /// within the scene's sources and receivers: a ray between other points is tested against
    /// every interface.
    #[test]
    fn points_beyond_the_scene_ends_are_tested_against_every_interface() {
        let doc = r#"{
            "media": { "air": { "speed": 1.0 }, "water": { "speed": 0.75 } },
            "interfaces": {
                "surface": { "points": [[-10, 0], [2, 0]] },
                "wall": { "points": [[-3, 0.8], [-3, 3]] },
                "deep": { "points": [[-3, -0.8], [-3, -3]] }
            },
            "sources": [[0, 1]], "receivers": [[0.5, -0.5]],
            "paths": [{ "steps": [{ "refract": "surface" }], "media": ["air", "water"] }]
        }"#;
        let scene = Scene::from_json(doc).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        assert!(tracer.clear[0], "{:?}", tracer.leg_candidates);
        let index = |name: &str| scene.interfaces().iter().position(|f| f.name == name);
        let (wall, deep) = (index("wall").unwrap(), index("deep").unwrap());
        let mut ws = Workspace::new();
        let (near, far) = (Point::new(-0.5, 1.0), Point::new(-5.0, 3.0));
        let receiver = scene.receivers()[0];
        assert_eq!(
            tracer.solve(near, receiver, 0, &mut ws).status,
            Status::Converged
        );
        let beyond = tracer.solve(far, receiver, 0, &mut ws);
        assert_eq!(beyond.status, Status::Obstructed, "{beyond:?}");
        assert_eq!(
            beyond.reason,
            Some(Reason::Crosses {
                leg: 0,
                interface: wall
            })
        );
        // And from the receiver's side.
        let beyond = tracer.solve(Point::new(0.5, 1.0), Point::new(-5.0, -3.0), 0, &mut ws);
        assert_eq!(
            beyond.reason,
            Some(Reason::Crosses {
                leg: 1,
                interface: deep
            })
        );
    }

    /// The hull test against brute force: a segment meets the hull exactly when it crosses
    /// one of its edges or has an end inside it.
    #[test]
    fn convex_hull_and_segment_test() {
        let mut rng = SplitMix64(9);
        let mut pt = |s: f64| Point::new(rng.next_f64() * s, rng.next_f64() * s);
        for _ in 0..200 {
            let cloud: Vec<Point> = (0..7).map(|_| pt(10.0)).collect();
            let hull = convex_hull(cloud.clone());
            let n = hull.len();
            let inside = |p: Point| {
                (0..n).all(|i| crate::geom::orient(hull[i], hull[(i + 1) % n], p) >= 0.0)
            };
            assert!(
                cloud.iter().all(|&p| inside(p)),
                "hull {hull:?} of {cloud:?}"
            );
            for _ in 0..50 {
                let (p, q) = (pt(14.0), pt(14.0));
                let crosses = (0..n).any(|i| {
                    crate::polyline::segment_intersection(p, q, hull[i], hull[(i + 1) % n])
                        .is_some()
                });
                let expected = crosses || inside(p) || inside(q);
                assert_eq!(
                    meets_convex(p, q, &hull, 0.0),
                    expected,
                    "{p:?}–{q:?} vs {hull:?}"
                );
            }
        }
    }

    /// The flat-layer ray parameter against a bisection of `Σ Δtⱼ tan θⱼ = x`, from near-normal
    /// offsets to ones where the paraxial start lies beyond a layer's critical angle.
    #[test]
    fn ray_parameter_solves_the_flat_layer_equation() {
        // Fractions of the way down at the crossings, and slownesses (the third is the fastest).
        let t = [0.2, 0.45, 0.5, 0.8];
        let w = [1.0, 0.8, 0.4, 0.9, 0.6];
        let sum: f64 = (0..5)
            .map(|j| {
                let lo = if j == 0 { 0.0 } else { t[j - 1] };
                let hi = if j < 4 { t[j] } else { 1.0 };
                (hi - lo) / w[j]
            })
            .sum();
        let lhs = |p: f64| {
            (0..5)
                .map(|j| {
                    let lo = if j == 0 { 0.0 } else { t[j - 1] };
                    let hi = if j < 4 { t[j] } else { 1.0 };
                    let sin = p / w[j];
                    (hi - lo) * sin / (1.0 - sin * sin).sqrt()
                })
                .sum::<f64>()
        };
        let mut layers = Vec::new();
        for x in [1e-8, 1e-5, 1e-3, 0.05, 0.3, 1.0, 3.0, 30.0, 3e3, 3e5] {
            let (mut lo, mut hi) = (0.0, 0.4);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if lhs(mid) < x { lo = mid } else { hi = mid }
            }
            // The paraxial p is past the critical one (0.4) from x ≈ 1.5 on.
            let d = Vec2::new(x, -1.0);
            let along = |_: usize| Vec2::new(1.0, 0.0);
            let (p, scaled) = ray_parameter(&t, &w, sum, d, along, &mut layers).unwrap();
            assert_eq!(scaled, x);
            assert!((p - lo).abs() <= 1e-14 * lo, "x = {x}: {p} against {lo}");
            // The layers' lateral offsets, which the start uses, are those at that p: they
            // make up x (tested away from the critical angle: from x ≈ 1.5 on they are steep
            // functions of p, and a rounding of it moves their sum by up to 1e-7 x).
            let offsets: f64 = layers.iter().map(|l| l.offset).sum();
            if x <= 1.0 {
                assert!(
                    (offsets - x).abs() <= 1e-13 * x,
                    "x = {x}: offsets {offsets}"
                );
                // Each one (after a last step taken without an evaluation, moved along its
                // Taylor series) against the layer's own offset at the bisected p.
                for (j, l) in layers.iter().enumerate() {
                    let lo_t = if j == 0 { 0.0 } else { t[j - 1] };
                    let hi_t = if j < 4 { t[j] } else { 1.0 };
                    let sin = lo / w[j];
                    let exact = (hi_t - lo_t) * sin / (1.0 - sin * sin).sqrt();
                    assert!(
                        (l.offset - exact).abs() <= 1e-13 * x,
                        "x = {x}, layer {j}: {} against {exact}",
                        l.offset
                    );
                }
            }
        }
    }
}
