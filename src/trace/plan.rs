//! The per-path plan: which kernel solves a path's rays, decided once in `Tracer::new`.
//!
//! Every ray goes through [`PathPlan`]: [`Tracer::solve`](super::Tracer::solve) and the
//! batches' chains (`trace::chain`) dispatch on it and on nothing else. Its variants are
//! inspected here only: the rest of `trace/` asks it through [`PathPlan::kernel`] (the
//! dispatch), [`PathPlan::one_step`],
//! [`PathPlan::flat`], [`PathPlan::stack`], [`PathPlan::straight`] and
//! [`PathPlan::skips_warm_start`]. A kernel is a shortcut for a common case
//! that ends in the same classifier (`classify`) as the general solve, and hands every ray
//! outside its case to the general code from the same start.

use crate::scene::{Scene, StepKind};

use super::InitialGuess;
use super::flat::FlatRefraction;
use super::start::graded_stack_path;
use super::straight::StraightPath;

/// Which kernels a [`Tracer`](super::Tracer) may use (see
/// [`Tracer::with_kernels`](super::Tracer::with_kernels)). Every kernel gives the status the
/// general code gives; all but the flat-refraction kernel take the general code's own steps
/// and give its rays bit for bit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Kernels {
    /// Every kernel (the default, and the fastest).
    #[default]
    All,
    /// The kernels whose rays are the general code's bit for bit: every one but the
    /// flat-refraction kernel (its own Halley steps on Snell's law give times within 1e-12 of
    /// the general solve's, not the same bits).
    BitExact,
    /// No kernel and no fast path: the documented start and the general Newton loop for every
    /// ray (for comparisons with the kernels).
    GeneralOnly,
}

/// How the rays of one path are solved.
#[derive(Debug)]
pub(crate) enum PathPlan {
    /// The documented start and the general solve.
    General,
    /// Every step refracts at, or every step reflects off, an interface of one segment: the
    /// start from the segments kept here (crossings; the image method off mirrors), then the
    /// general solve.
    Straight(StraightPath),
    /// Two or more refractions at parallel interfaces of one segment, the media given: from
    /// the default start, the stack kernel (`trace::stack`); otherwise as `Straight`.
    Stack(StraightPath),
    /// In a scene with curved legs, two or more refractions at parallel interfaces of one
    /// segment, the media given: from the default start, the graded stack kernel
    /// (`trace::stack`); otherwise as `General`.
    GradedStack(StraightPath),
    /// One interaction with its media given: the one-step code (`trace::one_step`).
    OneStep(OneStepPath),
    /// One refraction at an interface of one segment, the media given: from the default
    /// start, the flat kernel (`trace::flat`); otherwise as `OneStep`.
    FlatRefraction(OneStepPath, FlatRefraction),
    /// A path with `diffract` steps: each piece between its vertices searched on its own
    /// (`trace::diffract`), from the general solve's entry.
    Diffracted,
}

/// Which code solves a path's rays ([`PathPlan::kernel`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum PlanKernel<'p> {
    /// The flat kernel from the default start, the one-step code otherwise.
    Flat(&'p OneStepPath, &'p FlatRefraction),
    /// The one-step code.
    OneStep(&'p OneStepPath),
    /// The general solve (with the stack kernel first where the plan has it).
    General(&'p PathPlan),
    /// The graded stack kernel from the default start, the general solve otherwise.
    Graded(&'p StraightPath, &'p PathPlan),
}

/// A path of one interaction whose leg media are given.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OneStepPath {
    /// The two legs' media and slownesses.
    pub media: [usize; 2],
    pub slowness: [f64; 2],
    /// Whether the default start of a reflection is the image method's specular point (a
    /// mirror of one segment, one slowness on both legs, [`InitialGuess::RayParameter`]).
    pub images: bool,
}

impl PathPlan {
    /// The plan of path `path` of `scene` for rays started as `guess`, with `kernels`.
    pub(crate) fn of(
        scene: &Scene,
        path: usize,
        guess: InitialGuess,
        kernels: Kernels,
    ) -> PathPlan {
        if scene.paths()[path].diffracts() {
            return PathPlan::Diffracted;
        }
        let ray_parameter = guess == InitialGuess::RayParameter;
        if scene.curved() {
            // Curved legs: the general solve (the other kernels, the image method and the
            // start's proofs of no path are the straight leg's), after the graded stack
            // kernel where it applies.
            let stack = (kernels != Kernels::GeneralOnly && ray_parameter)
                .then(|| StraightPath::of(scene, path))
                .flatten()
                .filter(|sp| sp.stack() && graded_stack_path(scene, path));
            return stack.map_or(PathPlan::General, PathPlan::GradedStack);
        }
        let straight = StraightPath::of(scene, path);
        if kernels != Kernels::GeneralOnly
            && let Some(one) = OneStepPath::of(scene, path, straight.as_ref(), ray_parameter)
        {
            let spec = &scene.paths()[path];
            let step = &spec.steps[0];
            let line = &scene.interfaces()[step.interface].polyline;
            let flat = (kernels == Kernels::All && step.kind == StepKind::Refract)
                .then(|| FlatRefraction::of(line, one.slowness, scene.solver()))
                .flatten();
            return match flat {
                Some(flat) => PathPlan::FlatRefraction(one, flat),
                None => PathPlan::OneStep(one),
            };
        }
        match straight {
            Some(sp) if kernels != Kernels::GeneralOnly && sp.stack() && ray_parameter => {
                PathPlan::Stack(sp)
            }
            Some(sp) => PathPlan::Straight(sp),
            None => PathPlan::General,
        }
    }

    /// The segments of a path whose start comes from them.
    #[inline(always)]
    pub(crate) fn straight(&self) -> Option<&StraightPath> {
        match self {
            PathPlan::Straight(sp) | PathPlan::Stack(sp) => Some(sp),
            _ => None,
        }
    }

    /// The code that solves the path's rays: the one dispatch of every ray on its own
    /// (`Tracer::solve_planned`).
    #[inline(always)]
    pub(crate) fn kernel(&self) -> PlanKernel<'_> {
        match self {
            PathPlan::FlatRefraction(one, flat) => PlanKernel::Flat(one, flat),
            PathPlan::OneStep(one) => PlanKernel::OneStep(one),
            PathPlan::GradedStack(sp) => PlanKernel::Graded(sp, self),
            plan => PlanKernel::General(plan),
        }
    }

    /// The segments of a path whose rays from the default start take the stack kernel.
    #[inline(always)]
    pub(crate) fn stack(&self) -> Option<&StraightPath> {
        match self {
            PathPlan::Stack(sp) => Some(sp),
            _ => None,
        }
    }

    /// The one-interaction data of a path solved by the one-step code (the flat kernel's
    /// path too, whose rays outside its case the one-step code solves).
    #[inline(always)]
    pub(crate) fn one_step(&self) -> Option<&OneStepPath> {
        match self {
            PathPlan::OneStep(one) | PathPlan::FlatRefraction(one, _) => Some(one),
            _ => None,
        }
    }

    /// The flat kernel of a path whose rays from the default start take it.
    #[inline(always)]
    pub(crate) fn flat(&self) -> Option<&FlatRefraction> {
        match self {
            PathPlan::FlatRefraction(_, flat) => Some(flat),
            _ => None,
        }
    }

    /// Whether the default start of the path is its solution up to round-off where it applies
    /// (reflections off one-segment interfaces by the image method, refractions through
    /// parallel ones from the ray parameter), or its rays take the flat kernel, whose own start
    /// costs less than a warm start's bookkeeping: a batch does not warm-start such a path.
    pub(crate) fn skips_warm_start(&self, guess: InitialGuess) -> bool {
        let ray_parameter = guess == InitialGuess::RayParameter;
        match self {
            PathPlan::FlatRefraction(..) => true,
            PathPlan::OneStep(one) => one.images,
            PathPlan::Straight(sp) | PathPlan::Stack(sp) => sp.exact(ray_parameter),
            PathPlan::General => false,
            // Its start is the ray up to round-off (`trace::start::graded`).
            PathPlan::GradedStack(_) => ray_parameter,
            // Its pieces are searched, not started.
            PathPlan::Diffracted => true,
        }
    }

    /// Whether the path has `diffract` steps (`trace::diffract` solves its rays).
    #[inline(always)]
    pub(crate) fn diffracted(&self) -> bool {
        matches!(self, PathPlan::Diffracted)
    }
}

impl OneStepPath {
    /// The path's one-interaction data, if it is such a path (`straight` its segments, when it
    /// has a straight start; `ray_parameter` whether the tracer refines starts).
    fn of(
        scene: &Scene,
        path: usize,
        straight: Option<&StraightPath>,
        ray_parameter: bool,
    ) -> Option<OneStepPath> {
        let spec = &scene.paths()[path];
        match (spec.steps.len(), spec.media.as_deref()) {
            (1, Some(&[m0, m1])) => Some(OneStepPath {
                media: [m0, m1],
                slowness: [scene.media()[m0].slowness, scene.media()[m1].slowness],
                images: spec.steps[0].kind == StepKind::Reflect
                    && straight.is_some_and(|sp| sp.exact(ray_parameter)),
            }),
            _ => None,
        }
    }
}
