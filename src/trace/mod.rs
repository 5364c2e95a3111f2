//! Rays: the per-path plan, the documented start, the solve, the leg media and the
//! classification of the result.
//!
//! A ray of path `p` goes through `Tracer::solve_planned`, which dispatches on the path's
//! `PathPlan` (built once in [`Tracer::new`]): a kernel for a common case (`one_step`,
//! `flat`, `stack`) or the general solve (`Tracer::solve_general`): the start (`start`,
//! `straight`), the Newton solve (`crate::solver`), the media lookup and the classification
//! (`classify`). Every kernel ends in the same classifier. A batch's chain of rays of one path
//! goes through `Tracer::solve_chain` (`chain`), which reads the plan once per chain: the
//! rays of a one-interaction path in registers, without the workspace, and every other ray
//! (and a one-interaction ray outside the common case) through `solve_planned`.

use std::sync::Arc;

use rayon::prelude::*;

use crate::geom::Point;
use crate::problem::ProblemRef;
use crate::regions::Regions;
use crate::scene::{MAX_COORDINATE, Scene, SceneError, Step};
use crate::solver::{NewtonOptions, NewtonWorkspace, solve};

mod amplitude;
mod chain;
mod classify;
mod complete;
mod curve;
pub(crate) mod diffract;
mod flat;
mod mirrors;
mod occlusion;
mod one_step;
mod plan;
mod profile;
mod profile_slope;
mod sloped_found;
pub(crate) use profile::{ProfileShape, profile_ray_of, profile_shape};
pub(crate) use profile_slope::takes_sloped_route;
pub(crate) use profile_slope::{has_sloped_walls, sloped_shape};
pub(crate) use sloped_found::sloped_derivatives;
mod result;
mod stack;
mod start;
mod stationary;
mod straight;
mod update;

pub(crate) use chain::{ChainLink, ChainRays, WarmStarts};
pub(crate) use classify::{Classifier, Sequence};
pub(crate) use complete::SearchBudget;
pub use complete::{Arrival, Kink, SearchOutcome, StationaryError};
pub use curve::{CurveError, ray_curve};
pub(crate) use flat::SegmentFrame;
pub(crate) use mirrors::{
    GuidePath, MirrorPath, MirrorScratch, MirrorSearch, MirrorStats, MirrorWalls, RoomPath,
    TreeRun, Waveguide,
};
pub use plan::Kernels;
pub use result::{Ray, RayRecord, Reason, Status, Threshold};

use one_step::{OneStepStart, flat_status};
use plan::{OneStepPath, PathPlan, PlanKernel};
use start::given_param;

use start::{StartScratch, given_start, initial_guess, refraction_guess};
use straight::StraightStart;

/// Where a solve starts.
#[derive(Clone, Copy, Debug)]
enum Start<'a> {
    /// The documented initial guess.
    Default,
    /// These parameters (a caller's start).
    Given(&'a [f64]),
    /// These parameters as a trial (a neighbouring receiver's solution in a batch): where
    /// they lead to no stationary path the ray ends there, without the complete search, and
    /// the caller tries the default start next.
    Trial(&'a [f64]),
}

/// The documented start of a ray, and how it refines the start of refraction paths.
///
/// Interaction `i` of `k` starts at the point of its interface nearest to the target
/// `S + (i + 1)/(k + 1) · (R − S)` on the straight line from source to receiver; a refraction
/// whose interface that line crosses starts at the crossing nearest the target instead. On a
/// polyline of more than 1,024 segments (a digitised sea floor) the nearest point is replaced
/// by the crossing, nearest the target, of the line through the target perpendicular to
/// `R − S` (an `O(log M)` query), and a single reflection there starts at the specular point
/// of the tangent line at that crossing.
///
/// When every step is such a refraction, each point then moves along its interface to where a
/// ray through flat layers would cross: layers parallel to the first interface at its
/// crossing, `Δtⱼ Z` thick (`tᵢ` the crossings' fractions of the way from `S` to `R`, `Z` and
/// `X` the extents of `R − S` across and along the layers, `wⱼ` the legs' slownesses). With
/// [`RayParameter`](InitialGuess::RayParameter), where the interfaces' tangents at the
/// crossings are parallel (to within 5e-5 rad), the ray parameter `p` solves
/// `Σⱼ Δtⱼ tan θⱼ = X / Z` with `sin θⱼ = p / wⱼ` (Halley's steps from above the root) and the
/// points move to the lateral fractions `τᵢ = Σ_{j≤i} Δtⱼ tan θⱼ · Z / X`: for parallel flat
/// layers, the solution itself. Elsewhere (a single refraction, non-parallel interfaces, or
/// [`Paraxial`](InitialGuess::Paraxial)) the small-angle limit
/// `τᵢ = Σ_{j≤i} Δtⱼ/wⱼ / Σⱼ Δtⱼ/wⱼ`.
///
/// A path whose every step reflects off an interface of one segment (flat mirrors, the walls
/// of a room), with one slowness on every leg, starts with `RayParameter` at the image
/// method's specular points (the source mirrored in each mirror's line in turn, then the
/// points back from the receiver towards each image) when every one lies strictly inside its
/// segment: the solution itself. When one lies clearly beyond its segment's end (media given),
/// the ray has no path (`T` is convex in the parameters, so that is its one stationary point)
/// and is [`Status::NoPath`] at once.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum InitialGuess {
    /// The ray-parameter refinement through parallel layers and the image method off flat
    /// mirrors (see above).
    #[default]
    RayParameter,
    /// The paraxial (small-angle) refinement only, and no image method: a start that leaves
    /// Newton steps to do even through flat layers and off flat mirrors, for comparing solvers
    /// from one start.
    Paraxial,
}

/// Reusable scratch space for solving rays: once it has grown to the longest path, solving
/// allocates nothing. Use one per thread.
#[derive(Clone, Debug, Default)]
pub struct Workspace {
    /// The Newton iteration's state (the points' parameters, segments, pins) and scratch.
    pub(crate) newton: NewtonWorkspace,
    /// The start's scratch.
    pub(crate) start: StartScratch,
    /// The last ray's points, leg media and slownesses.
    pub(crate) ray: RayData,
}

/// What a solve leaves of its ray, beside its record.
#[derive(Clone, Debug, Default)]
pub(crate) struct RayData {
    /// Leg slownesses.
    pub slowness: Vec<f64>,
    /// Leg models relative to the source, in a scene with curved legs (else empty: see
    /// [`ProblemRef::curved`]).
    pub curved: Vec<crate::leg::LegMedium<'static>>,
    /// Leg media, and those of the last lookup while they settle.
    pub media: Vec<usize>,
    pub media_prev: Vec<usize>,
    /// Source, interaction points, receiver.
    pub points: Vec<Point>,
}

impl Workspace {
    /// An empty workspace.
    pub fn new() -> Workspace {
        Workspace::default()
    }

    /// Source, interaction points and receiver of the last solved ray; empty when it has no
    /// time.
    pub fn points(&self) -> &[Point] {
        &self.ray.points
    }

    /// Interaction parameters (arclengths along their polylines) of the last solved ray.
    pub fn parameters(&self) -> &[f64] {
        &self.newton.s
    }

    /// Leg media of the last solved ray, as indices into [`Scene::media`] (empty when they
    /// were not found).
    pub fn media(&self) -> &[usize] {
        &self.ray.media
    }

    /// The travel time at the Newton solver's last iterate of the last solved ray, for studies
    /// of convergence: a ray that ends `not_converged` has no `time`, but its last iterate has
    /// one. (A ray that the flat-refraction kernel solved leaves this untouched: its record
    /// holds its time.)
    pub fn iterate_time(&self) -> f64 {
        self.newton.eval.time
    }

    /// Sizes the workspace for a path of `k` interactions.
    #[inline]
    pub(crate) fn resize(&mut self, k: usize) {
        if !self.newton.fits(k) {
            self.resize_to(k);
        }
    }

    /// [`resize`](Self::resize) when the sizes change (the first ray of a path of another
    /// length).
    #[inline(never)]
    fn resize_to(&mut self, k: usize) {
        self.newton.resize_to(k);
        self.start.resize(k);
        // Room for the classification and the media lookups, so that no ray allocates.
        self.ray.media.reserve(k + 1);
        self.ray.media_prev.reserve(k + 1);
        self.ray.slowness.reserve(k + 1);
        self.ray.points.reserve(k + 2);
    }
}

/// What the kernels and the general solve need of a tracer: the scene,
/// the classifier, the solver's options and the start's refinement.
#[derive(Clone, Copy)]
pub(crate) struct Context<'a> {
    pub scene: &'a Scene,
    pub classifier: &'a Classifier,
    pub newton: NewtonOptions,
    pub guess: InitialGuess,
}

/// Solves the rays of a scene: holds what `Tracer::new` prepares once (the region lookup when
/// the scene needs one, each path's plan, the classifier's candidate segments).
///
/// Each ray starts from the documented start ([`InitialGuess`]) and is solved by damped
/// Newton iteration on the stationarity of its travel time, then classified ([`Status`]).
/// Common cases take a kernel (see [`Kernels`]): a single refraction at a flat interface, a
/// stack of parallel flat layers, one interaction with its media given. Every kernel ends in
/// the same classification and hands the rays outside its case to the general code.
pub struct Tracer {
    scene: Arc<Scene>,
    regions: Option<Regions>,
    /// Medium at each source (when regions exist).
    source_media: Vec<Option<usize>>,
    classifier: Classifier,
    /// Per path: how its rays are solved.
    plans: Vec<PathPlan>,
    newton: NewtonOptions,
    guess: InitialGuess,
    kernels: Kernels,
    /// Per interface: its segment hierarchy for the complete search, built on first use.
    hierarchies: Vec<std::sync::OnceLock<complete::Hierarchy>>,
    /// Per interface: the pairs of media on its sides (with regions), found on first use.
    sides: Vec<std::sync::OnceLock<Vec<crate::regions::Sides>>>,
}

/// A tracer owns what it needs: a layout tool keeps one in a struct, threads share it, a
/// binding to another language holds it.
const _: fn() = || {
    fn owned<T: Send + Sync + 'static>() {}
    owned::<Tracer>();
};

impl Tracer {
    /// Prepares a scene for tracing: builds the region lookup only if some path needs it.
    ///
    /// The tracer owns its scene (`'static`, `Send` and `Sync`: keep it in a struct, share it
    /// between threads). `scene` is a [`Scene`] (moved in), an `Arc<Scene>` (shared with
    /// other tracers) or a `&Scene` (copied: the caller keeps its own).
    ///
    /// # Errors
    /// A scene whose regions are inconsistent (two `at` points in one region).
    pub fn new(scene: impl Into<Arc<Scene>>) -> Result<Tracer, SceneError> {
        let scene: Arc<Scene> = scene.into();
        let regions = if scene.needs_regions() {
            Some(Regions::build(&scene)?)
        } else {
            None
        };
        let source_media = match &regions {
            Some(r) => scene
                .sources()
                .iter()
                .map(|&p| r.source_medium(&scene, p))
                .collect(),
            None => Vec::new(),
        };
        let opts = scene.solver();
        let classifier = Classifier::new(&scene);
        let hierarchies = scene
            .interfaces()
            .iter()
            .map(|_| Default::default())
            .collect();
        let sides = scene
            .interfaces()
            .iter()
            .map(|_| Default::default())
            .collect();
        let mut tracer = Tracer {
            scene,
            regions,
            source_media,
            classifier,
            plans: Vec::new(),
            newton: NewtonOptions {
                tolerance: opts.tolerance,
                max_iterations: opts.max_iterations,
                fast_path: true,
            },
            guess: InitialGuess::default(),
            kernels: Kernels::default(),
            hierarchies,
            sides,
        };
        tracer.plan();
        Ok(tracer)
    }

    /// Decides each path's plan for the present start and kernels.
    fn plan(&mut self) {
        let scene = &*self.scene;
        self.plans = (0..scene.paths().len())
            .map(|p| PathPlan::of(scene, p, self.guess, self.kernels))
            .collect();
        // Curved legs take the general code alone: the kernels and the fast path are the
        // straight leg's.
        self.newton.fast_path = self.kernels != Kernels::GeneralOnly && !scene.curved();
        // The classifier's proof that arcs are clear is a shortcut, like a kernel.
        self.classifier.arc_shortcut = self.kernels != Kernels::GeneralOnly;
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
        self.plan();
        self
    }

    /// The same tracer with only `kernels` (see [`Kernels`]): the general code alone, for
    /// example, to compare a kernel's rays with it.
    ///
    /// ```
    /// use eigenray::trace::Kernels;
    /// use eigenray::{Scene, Tracer};
    /// let scene = Scene::from_spec(&eigenray::demo::layer_stack(8, 20)).unwrap();
    /// let fast = Tracer::new(&scene).unwrap().trace_all();
    /// let general = Tracer::new(&scene).unwrap().with_kernels(Kernels::GeneralOnly).trace_all();
    /// assert_eq!(fast, general); // the stack kernel takes the general code's steps
    /// ```
    pub fn with_kernels(mut self, kernels: Kernels) -> Self {
        self.kernels = kernels;
        self.plan();
        self
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene, shared (what a result that outlives the tracer keeps of it: the Python
    /// package's rays, for their curves).
    pub fn shared_scene(&self) -> Arc<Scene> {
        Arc::clone(&self.scene)
    }

    /// The region lookup, if the scene needed one.
    pub fn regions(&self) -> Option<&Regions> {
        self.regions.as_ref()
    }

    /// What the kernels and the general solve need of the tracer.
    #[inline(always)]
    pub(crate) fn context(&self) -> Context<'_> {
        Context {
            scene: &self.scene,
            classifier: &self.classifier,
            newton: self.newton,
            guess: self.guess,
        }
    }

    /// Solves one ray of the scene.
    ///
    /// # Panics
    /// If an index is out of range (`source`, `receiver`, `path` index the scene's lists).
    pub fn trace(&self, source: usize, receiver: usize, path: usize, ws: &mut Workspace) -> Ray {
        let record = self.solve_indexed_from(source, receiver, path, None, ws);
        Ray {
            source,
            receiver,
            path,
            status: record.status,
            time: record.time,
            points: ws.ray.points.clone(),
            iterations: record.iterations as usize,
            residual: record.residual,
            media: ws.ray.media.clone(),
            reason: record.reason,
            amplitude: self.amplitude(path, &record, ws),
        }
    }

    /// Solves every ray of the scene, in parallel, in ray order ([`Scene::ray_index`]).
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

    /// Solves path `path` between two arbitrary points. The points of the ray are left in
    /// `ws` ([`Workspace::points`]); nothing is allocated once `ws` has grown.
    ///
    /// # Panics
    /// If a point is not finite or lies beyond ±[`MAX_COORDINATE`],
    /// or `path` is not an index into [`Scene::paths`]: [`Scene::check_solve`] tells beforehand.
    pub fn solve(
        &self,
        source: Point,
        receiver: Point,
        path: usize,
        ws: &mut Workspace,
    ) -> RayRecord {
        self.assert_solvable(source, receiver, path, "Tracer::solve");
        let src_medium = self
            .regions
            .as_ref()
            .and_then(|r| r.source_medium(&self.scene, source));
        let record = self.solve_planned(source, src_medium, receiver, path, Start::Default, ws);
        ws.forget_points_without_time(&record);
        record
    }

    /// [`solve`](Self::solve) from a start of the caller's: `guess` holds interaction
    /// parameters (for example those of a neighbouring receiver's solution,
    /// [`Workspace::parameters`]), and the solver starts there (each parameter clamped to its
    /// open polyline, wrapped on a closed one). Where that start leads to no stationary path,
    /// the answer is that of a complete search, as for [`solve`](Self::solve).
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
    ) -> RayRecord {
        self.assert_solvable(source, receiver, path, "Tracer::solve_from");
        assert_eq!(
            guess.len(),
            self.scene.paths()[path].steps.len(),
            "one parameter per step"
        );
        let src_medium = self
            .regions
            .as_ref()
            .and_then(|r| r.source_medium(&self.scene, source));
        let start = Start::Given(guess);
        let record = self.solve_planned(source, src_medium, receiver, path, start, ws);
        ws.forget_points_without_time(&record);
        record
    }

    /// Solves ray (`source`, `receiver`, `path`) of the scene, optionally from the caller's
    /// start (see [`solve_from`](Self::solve_from)); the points stay in `ws`.
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
    ) -> RayRecord {
        let start = guess.map_or(Start::Default, Start::Given);
        let record = self.solve_indexed_start(source, receiver, path, start, ws);
        ws.forget_points_without_time(&record);
        record
    }

    /// Ray (`source`, `receiver`, `path`) of the scene from `start` (the batches' entry: the
    /// points of a ray without a time stay in `ws`, unread).
    #[inline(always)]
    fn solve_indexed_start(
        &self,
        source: usize,
        receiver: usize,
        path: usize,
        start: Start,
        ws: &mut Workspace,
    ) -> RayRecord {
        let src_medium = self.source_media.get(source).copied().flatten();
        self.solve_planned(
            self.scene.sources()[source],
            src_medium,
            self.scene.receivers()[receiver],
            path,
            start,
            ws,
        )
    }

    /// Panics unless `source`, `receiver` and `path` are valid arguments of a solve
    /// ([`Scene::check_solve`]): a quick test on the hot path, the message out of line.
    #[inline(always)]
    fn assert_solvable(&self, source: Point, receiver: Point, path: usize, call: &str) {
        // Finite and within ±MAX_COORDINATE (NaN fails every comparison), without branches.
        let ok = |v: f64| v.abs() <= MAX_COORDINATE;
        let fine = ok(source.x) & ok(source.y) & ok(receiver.x) & ok(receiver.y);
        if !(fine & (path < self.plans.len())) {
            self.refuse(source, receiver, path, call);
        }
    }

    /// The panic of [`assert_solvable`](Self::assert_solvable).
    #[cold]
    #[inline(never)]
    fn refuse(&self, source: Point, receiver: Point, path: usize, call: &str) {
        if let Err(e) = self.scene.check_solve(source, receiver, path) {
            panic!("{call}: {e}");
        }
    }

    /// The plan of path `path`.
    #[inline(always)]
    fn plan_of(&self, path: usize) -> &PathPlan {
        &self.plans[path]
    }

    /// The start's refinement.
    fn initial_guess(&self) -> InitialGuess {
        self.guess
    }

    /// The solver's options.
    fn newton_options(&self) -> NewtonOptions {
        self.newton
    }

    /// The classifier.
    fn classifier(&self) -> &Classifier {
        &self.classifier
    }

    /// The one segment of the interface of path `path` when the flat kernel's plan solves
    /// its rays (a refraction at an open interface of one segment, the media given).
    #[inline(always)]
    pub(crate) fn flat_segment(&self, path: usize) -> Option<SegmentFrame> {
        self.plans.get(path)?.flat().map(|flat| flat.frame())
    }

    /// Solves one ray from `start` as its path's plan says: the one dispatch of every ray.
    /// The flat kernel in place; the one-step code and the general solve out of line.
    #[inline(always)]
    fn solve_planned(
        &self,
        source: Point,
        src_medium: Option<usize>,
        receiver: Point,
        path: usize,
        start: Start,
        ws: &mut Workspace,
    ) -> RayRecord {
        let record = match self.plans[path].kernel() {
            PlanKernel::Flat(one, flat) => {
                if let Start::Default = start
                    && let Some(sol) = flat.solve(source, receiver)
                {
                    let cx = self.context();
                    one.flat_ray(&cx, flat, path, source, receiver, sol, ws)
                } else {
                    one.solve(&self.context(), path, source, receiver, start, ws)
                }
            }
            PlanKernel::OneStep(one) => {
                one.solve(&self.context(), path, source, receiver, start, ws)
            }
            PlanKernel::General(plan) => {
                self.solve_general(plan, source, src_medium, receiver, path, start, ws)
            }
            PlanKernel::Graded(sp, plan) => {
                let cx = self.context();
                match start {
                    Start::Default => sp.solve_graded_stack(&cx, path, source, receiver, ws),
                    _ => None,
                }
                .unwrap_or_else(|| {
                    self.solve_general(plan, source, src_medium, receiver, path, start, ws)
                })
            }
        };
        if record.status.has_time() || matches!(start, Start::Trial(_)) {
            return record;
        }
        self.search_instead(record, source, src_medium, receiver, path, ws)
    }

    /// The general solve (after the stack kernel, where the plan has it): the start, the
    /// Newton solve with the leg media looked up again until they settle, and the
    /// classification. Out of line, so that the one-interaction code keeps a small stack frame.
    #[expect(
        clippy::too_many_arguments,
        reason = "the parts of a ray held in registers by its callers"
    )]
    #[inline(never)]
    fn solve_general(
        &self,
        plan: &PathPlan,
        source: Point,
        src_medium: Option<usize>,
        receiver: Point,
        path: usize,
        start: Start,
        ws: &mut Workspace,
    ) -> RayRecord {
        if plan.diffracted() {
            return self.solve_diffracted(source, receiver, path, ws);
        }
        if let Some((m, profile)) = self.profile_medium(path, source, src_medium) {
            return self.solve_profile(m, &profile, source, receiver, ws);
        }
        if let Some(m) = self.profile_sloped_medium(path, source, src_medium) {
            return self.solve_sloped(path, m, source, receiver, ws);
        }
        if let Some((m, profile)) = self.profile_walled_medium(path, source, src_medium) {
            return self.solve_walled(path, m, &profile, source, receiver, ws);
        }
        let cx = self.context();
        if let (Start::Default, Some(sp)) = (start, plan.stack())
            && let Some(ray) = sp.solve_stack(&cx, path, source, receiver, ws)
        {
            return ray;
        }
        let scene = &*self.scene;
        let spec = &scene.paths()[path];
        let k = spec.steps.len();
        ws.resize(k);
        ws.ray.clear();
        let mut beyond = None;
        match start {
            Start::Given(params) | Start::Trial(params) => {
                given_start(scene, &spec.steps, params, &mut ws.newton);
            }
            Start::Default => {
                let images = self.guess == InitialGuess::RayParameter;
                match plan
                    .straight()
                    .map(|sp| sp.start(source, receiver, images, ws))
                {
                    Some(StraightStart::At) => {}
                    // With media given (a lookup decides before the geometry).
                    Some(StraightStart::Beyond { step }) if spec.media.is_some() => {
                        beyond = Some(Reason::BeyondEnd { step });
                    }
                    Some(StraightStart::Apart { .. }) if spec.media.is_some() => {
                        beyond = Some(Reason::NoStationaryPath);
                    }
                    _ => initial_guess(scene, &spec.steps, source, receiver, ws),
                }
            }
        }
        if let (Some(reason), Some(media)) = (beyond, &spec.media) {
            // Only with media given: the ray records them.
            ws.ray.media.extend_from_slice(media);
            return RayRecord::failed(Status::NoPath, reason);
        }
        let sequence = Sequence::of(scene, path);
        self.settle(
            sequence,
            spec.media.as_deref(),
            source,
            src_medium,
            receiver,
            start,
            ws,
        )
    }

    /// Leg media into `ws`: `media` when given, else from the regions at the points of `ws`
    /// (all of them or none, as a batch records them: not those found before a gap).
    fn leg_media(
        &self,
        steps: &[Step],
        media: Option<&[usize]>,
        source: Point,
        src_medium: Option<usize>,
        ws: &mut Workspace,
    ) -> Result<(), Reason> {
        if let Some(m) = media {
            ws.ray.media.extend_from_slice(m);
            return Ok(());
        }
        let found = classify::lookup_media(
            self.regions.as_ref(),
            &self.scene,
            source,
            src_medium,
            steps,
            &ws.newton,
            &mut ws.ray.media,
        );
        if found.is_err() {
            ws.ray.media.clear();
        }
        found
    }

    /// The general solve from the start in `ws` (its points placed): the leg media (given, or
    /// looked up again at the solution until they settle), the Newton solve and the
    /// classification of `sequence` (a path of the scene, or any sequence of steps through
    /// curved legs).
    #[expect(
        clippy::too_many_arguments,
        reason = "a ray's ends, its sequence and media, its start and its workspace"
    )]
    fn settle(
        &self,
        sequence: Sequence<'_>,
        media: Option<&[usize]>,
        source: Point,
        src_medium: Option<usize>,
        receiver: Point,
        start: Start,
        ws: &mut Workspace,
    ) -> RayRecord {
        let scene = &*self.scene;
        let steps = sequence.steps;
        let lookup = media.is_none();
        if let Err(reason) = self.leg_media(steps, media, source, src_medium, ws) {
            return RayRecord::failed(Status::NoPath, reason);
        }
        ws.ray
            .slowness
            .extend(ws.ray.media.iter().map(|&m| scene.media()[m].slowness));
        ws.ray.set_curved(scene, source);
        if let Start::Default = start {
            refraction_guess(scene, steps, source, receiver, self.guess, ws);
        }

        let mut total_iterations = 0;
        let mut rounds = 0;
        let sol = loop {
            let g = ProblemRef {
                scene,
                steps,
                slowness: &ws.ray.slowness,
                curved: &ws.ray.curved,
                source,
                receiver,
            };
            let opts = NewtonOptions {
                max_iterations: self.newton.max_iterations.saturating_sub(total_iterations),
                ..self.newton
            };
            let mut sol = solve(&g, &mut ws.newton, opts);
            total_iterations += sol.iterations;
            sol.iterations = total_iterations;
            if !lookup || sol.outcome == crate::solver::Outcome::NotConverged {
                break sol;
            }
            // Media must match the solution's geometry: look them up again at the final points.
            std::mem::swap(&mut ws.ray.media, &mut ws.ray.media_prev);
            if let Err(reason) = self.leg_media(steps, None, source, src_medium, ws) {
                std::mem::swap(&mut ws.ray.media, &mut ws.ray.media_prev);
                return RayRecord::untimed(Status::NoPath, reason, &sol);
            }
            if ws.ray.media == ws.ray.media_prev {
                break sol;
            }
            rounds += 1;
            if rounds >= 3 {
                return RayRecord::untimed(Status::NoPath, Reason::MediaUnsettled, &sol);
            }
            ws.ray.slowness.clear();
            ws.ray
                .slowness
                .extend(ws.ray.media.iter().map(|&m| scene.media()[m].slowness));
            ws.ray.set_curved(scene, source);
        };
        let sequence = Sequence {
            curved: &ws.ray.curved,
            ..sequence
        };
        self.classifier.classify(
            scene,
            sequence,
            source,
            receiver,
            &sol,
            &ws.newton,
            &mut ws.ray.points,
        )
    }

    /// One ray of the step sequence `steps` (not necessarily a path of the scene) in a scene
    /// with curved legs, from the start `guess` (one arclength parameter per step; the
    /// default start without steps), its leg media `media` or looked up from `src_medium` at
    /// the source: the general solve, as a path of these steps solves from that start.
    #[expect(
        clippy::too_many_arguments,
        reason = "a ray's ends, its sequence and media, its start and its workspace"
    )]
    pub(crate) fn solve_steps_curved(
        &self,
        steps: &[Step],
        media: Option<&[usize]>,
        source: Point,
        src_medium: Option<usize>,
        receiver: Point,
        guess: &[f64],
        ws: &mut Workspace,
    ) -> RayRecord {
        let k = steps.len();
        ws.resize(k);
        ws.ray.clear();
        let start = if k == 0 {
            initial_guess(&self.scene, steps, source, receiver, ws);
            Start::Default
        } else {
            given_start(&self.scene, steps, guess, &mut ws.newton);
            Start::Given(guess)
        };
        let sequence = Sequence {
            steps,
            path: None,
            curved: &[],
        };
        self.settle(sequence, media, source, src_medium, receiver, start, ws)
    }
}

impl RayData {
    /// Empties its legs and points (keeps `media_prev`, the last lookup's).
    pub(super) fn clear(&mut self) {
        self.slowness.clear();
        self.curved.clear();
        self.media.clear();
        self.points.clear();
    }

    /// The leg models of the media in `media`, relative to `source`, when the scene has
    /// curved legs (else none: every leg straight, on the uniform medium's own code).
    pub(super) fn set_curved(&mut self, scene: &Scene, source: Point) {
        self.curved.clear();
        if scene.curved() {
            let models = self
                .media
                .iter()
                .map(|&m| scene.media()[m].leg_model(source));
            self.curved.extend(models);
        }
    }
}

impl Workspace {
    /// Empties the points of a ray without a time (the one convention of the public calls:
    /// points only with a time).
    #[inline(always)]
    fn forget_points_without_time(&mut self, record: &RayRecord) {
        if !record.status.has_time() {
            self.ray.points.clear();
        }
    }
}

/// Test helpers shared by the kernels' tests.
#[cfg(test)]
pub(crate) mod test_support {
    use super::*;

    /// Every ray of `scene`, solved with the bit-exact kernels and fast paths
    /// ([`Kernels::BitExact`]) and with the general code alone ([`Kernels::GeneralOnly`]), from
    /// the default start, from a warm start compared with it and from a given start (the
    /// previous receiver's solution, moved): the same rays, bit for bit (status, time,
    /// iterations, residual, reason, points, media). Returns the number of rays.
    pub(crate) fn kernels_agree(scene: &Scene) -> usize {
        type Outcome = (Status, u64, u32, u64, Option<Reason>);
        type Rays = Vec<(Outcome, Vec<Point>, Vec<usize>)>;
        let mut ws = Workspace::new();
        let mut results: [Rays; 2] = Default::default();
        let kernels = [Kernels::BitExact, Kernels::GeneralOnly];
        for (out, kernels) in results.iter_mut().zip(kernels) {
            let tracer = Tracer::new(scene).unwrap().with_kernels(kernels);
            let mut last: Vec<Vec<f64>> = vec![Vec::new(); scene.paths().len()];
            for s in 0..scene.sources().len() {
                for r in 0..scene.receivers().len() {
                    for (p, last) in last.iter_mut().enumerate() {
                        let guess: Vec<f64> = last.iter().map(|x| x + 1e-3).collect();
                        let mut keep = |rec: RayRecord, ws: &Workspace| {
                            let o = (
                                rec.status,
                                rec.time.to_bits(),
                                rec.iterations,
                                rec.residual.to_bits(),
                                rec.reason,
                            );
                            out.push((o, ws.points().to_vec(), ws.media().to_vec()));
                        };
                        let cold = tracer.solve_indexed_from(s, r, p, None, &mut ws);
                        keep(cold, &ws);
                        *last = ws.parameters().to_vec();
                        if !guess.is_empty() {
                            let warm = tracer.solve_indexed_from(s, r, p, Some(&guess), &mut ws);
                            keep(warm, &ws);
                            let given = Start::Given(&guess);
                            let given = tracer.solve_indexed_start(s, r, p, given, &mut ws);
                            keep(given, &ws);
                        }
                    }
                }
            }
        }
        let [fast, general] = &results;
        assert_eq!(fast.len(), general.len());
        for (a, b) in fast.iter().zip(general) {
            assert_eq!(a, b);
        }
        scene.num_rays()
    }

    /// [`kernels_agree`] (cold, warm and given starts) over the demo and benchmark scenes,
    /// the fixtures, and undulating surfaces with a ring and a screen.
    #[test]
    fn kernels_take_the_general_steps_from_every_start() {
        let demo = |spec: crate::SceneSpec| Scene::from_spec(&spec).unwrap();
        assert_eq!(kernels_agree(&demo(crate::demo::air_water(300, 3))), 300);
        assert_eq!(kernels_agree(&demo(crate::demo::layer_stack(8, 100))), 100);
        assert_eq!(kernels_agree(&demo(crate::demo::layer_stack(40, 30))), 30);
        assert_eq!(kernels_agree(&demo(crate::demo::sea_floor(3000, 100))), 100);
        let root = env!("CARGO_MANIFEST_DIR");
        for name in ["room2d", "seed500", "layers10"] {
            let text =
                std::fs::read_to_string(format!("{root}/fixtures/bench/{name}.json")).unwrap();
            assert!(kernels_agree(&Scene::from_json(&text).unwrap()) > 0);
        }
        // The documented cases and the fuzz finds: vertices, ends, wrong sides, degenerate legs.
        for dir in ["cases", "fuzz"] {
            for entry in std::fs::read_dir(format!("{root}/fixtures/{dir}")).unwrap() {
                let path = entry.unwrap().path();
                let name = path.to_string_lossy();
                if name.ends_with(".json") && !name.ends_with(".expected.json") {
                    let text = std::fs::read_to_string(&path).unwrap();
                    assert!(
                        kernels_agree(&Scene::from_json(&text).unwrap()) > 0,
                        "{name}"
                    );
                }
            }
        }
        // One refraction through an undulating surface of 6 and of 40 segments (searched
        // segment by segment and through its BVH), one reflection inside a closed polygon, and
        // receivers that put some rays on the wrong side or behind another interface.
        for segments in [6, 40] {
            let surface: Vec<String> = (0..=segments)
                .map(|i| {
                    let x = -4.0 + 8.0 * i as f64 / segments as f64;
                    format!("[{x}, {}]", 0.3 * (1.7 * x).sin())
                })
                .collect();
            let receivers: Vec<String> = (0..150)
                .map(|i| format!("[{}, {}]", -3.5 + 0.047 * i as f64, -2.0 + 0.013 * i as f64))
                .collect();
            let text = format!(
                r#"{{
                "media": {{ "a": {{ "speed": 1.0 }}, "b": {{ "speed": 0.6 }} }},
                "interfaces": {{
                    "surface": {{ "points": [{}] }},
                    "ring": {{ "points": [[-6, -6], [6, -6], [6, 6], [-6, 6], [-7, 0]],
                               "closed": true }},
                    "screen": {{ "points": [[1, -1.2], [2, -1.5]] }}
                }},
                "sources": [[0.3, 2.0], [-2.5, 1.1]], "receivers": [{}],
                "paths": [
                    {{ "steps": [{{ "refract": "surface" }}], "media": ["a", "b"] }},
                    {{ "steps": [{{ "reflect": "ring" }}], "media": ["a", "a"] }},
                    {{ "steps": [{{ "reflect": "surface" }}], "media": ["a", "a"] }}
                ]
            }}"#,
                surface.join(", "),
                receivers.join(", ")
            );
            assert_eq!(kernels_agree(&Scene::from_json(&text).unwrap()), 900);
        }
    }
}
