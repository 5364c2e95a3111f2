//! eigenray: eigenrays through prescribed reflections and refractions on 2-D piecewise-linear
//! interfaces.
//!
//! A path runs source → interaction points → receiver. Each interaction point lives on one
//! interface polyline and is one arclength parameter. Travel time is
//! `T = Σ slowness × leg length`; a ray makes `T` stationary (Fermat), so the unknowns solve
//! `∂T/∂sᵢ = 0`: Snell's law in tangential form at every interaction. eigenray solves these
//! equations by damped Newton iteration on the analytic, symmetric tridiagonal Hessian of `T`
//! (an `O(k)` step for `k` interactions), then classifies each ray.
//!
//! # Start here
//!
//! 1. **A scene**: [`Scene::from_json`] reads the scene document (its format:
//!    `docs/scene-format.md`), [`Scene::builder`] writes the same keys in code
//!    ([`SceneBuilder`], [`MediumSpec::speed`], [`InterfaceSpec::open`], [`PathSpec::new`],
//!    [`StepSpec::reflect`]). Either validates everything and names the key of the first
//!    problem ([`SceneError`]).
//! 2. **A tracer**: [`Tracer::new`] takes the scene (moved in, an `Arc`, or a `&Scene` it
//!    copies) and prepares it once; it owns what it needs (`'static`, `Send`, `Sync`).
//! 3. **Rays**: [`Tracer::trace_all`] solves every (source, receiver, path) of the scene into
//!    [`Ray`]s, in parallel; [`Tracer::trace_batch`] into flat arrays ([`Batch`]);
//!    [`Tracer::solve`] one ray between any two points into a reusable [`Workspace`];
//!    [`Tracer::stationary_paths`] every stationary path of one sequence;
//!    [`Tracer::search`] every sequence up to a number of steps. Each ray has a [`Status`];
//!    one that is not `converged` says why ([`Reason`]); [`Ray::describe`] writes it with the
//!    scene's names.
//! 4. **Change and trace again**: [`Tracer::set_receiver`], [`Tracer::set_source`],
//!    [`Tracer::set_interface_points`], [`Tracer::set_medium_speed`] edit the tracer's scene,
//!    validated as the document is, and prepare again only what depends on the change.
//! 5. **Write**: [`write_rays`], [`write_batch`] and their siblings write JSON, JSON Lines,
//!    CSV or `.npy` ([`Format`]).
//! 6. **Derivatives**: [`Tracer::gradient`] gives the derivatives of a solved ray's time with
//!    respect to its source, receiver, each medium's slowness and the vertices it touches
//!    ([`Gradient`]); [`PointSensitivities`] how its points move; [`BatchGradients`] both for
//!    a whole batch.
//!
//! ```
//! use eigenray::{InterfaceSpec, MediumSpec, PathSpec, Point, Scene, Status, StepSpec, Tracer};
//! let scene = Scene::builder()
//!     .medium("air", MediumSpec::index(1.0))
//!     .medium("water", MediumSpec::index(1.333))
//!     .interface("surface", InterfaceSpec::open([[-1.0, 0.0], [2.0, 0.0]]))
//!     .source([0.0, 1.0])
//!     .receiver([1.0, -1.0])
//!     .path(PathSpec::new([StepSpec::refract("surface")]).media(["air", "water"]))
//!     .build()?;
//! let mut tracer = Tracer::new(scene)?;
//! let rays = tracer.trace_all();
//! assert_eq!(rays[0].status, Status::Converged);
//! assert!((rays[0].time - 2.6017642).abs() < 1e-6);
//!
//! tracer.set_receiver(0, Point::new(1.5, -2.0))?;
//! assert!(tracer.trace_all()[0].time > rays[0].time);
//! # Ok::<(), eigenray::SceneError>(())
//! ```
//!
//! The modules and how they depend on each other: `ARCHITECTURE.md`.

mod arrivals;
mod batch;
mod bvh;
pub mod demo;
mod derivatives;
mod geom;
mod output;
mod polyline;
mod problem;
mod regions;
mod scene;
mod solver;
mod trace;

#[cfg(feature = "argmin")]
pub mod argmin_bridge;

// The vocabulary: scenes, the tracer and its options, ray results, batches, outputs.
pub use arrivals::{
    MAX_SEARCH_WORK, SearchArrival, SearchError, StationaryEntry, StationaryRays, TripleArrivals,
};
pub use batch::{Batch, BatchOptions, BatchRay, BatchRays, BatchScratch, BatchSink, RaySlot};
pub use derivatives::{
    Axis, BatchGradients, DerivativeError, Gradient, GradientArraysMut, GradientRows, Parameter,
    PointSensitivities, VertexGradient,
};
pub use geom::{Point, Vec2};
pub use output::{
    Format, RaySet, write_arrivals, write_batch, write_names, write_rays, write_rays_and_arrivals,
    write_rays_json, write_stationary,
};
pub use problem::{PathProblem, Tridiagonal};
pub use scene::{
    InterfaceSpec, MediumSpec, PathSpec, Scene, SceneBuilder, SceneError, SceneSpec, SearchOptions,
    SearchSpec, SolverOptions, SolverSpec, StationaryMode, StepSpec, escape_text,
};
pub use trace::{
    Arrival, InitialGuess, Kernels, Kink, Ray, RayRecord, Reason, Stationary, StationaryError,
    Status, Tracer, Workspace, ray_index,
};

/// The parts of a validated [`Scene`], as its accessors give them: media, interfaces, paths
/// and their steps, segments, and the sizes of a batch.
pub mod scene_parts {
    pub use crate::scene::{BatchSize, Interface, Medium, Path, SegmentRef, Step, StepKind};
}

/// The limits a scene is validated against, and the solver's defaults.
pub mod limits {
    pub use crate::scene::{
        DEFAULT_MAX_ITERATIONS, DEFAULT_TOLERANCE, MAX_COORDINATE, MAX_ITERATIONS_LIMIT,
        MAX_SPEED_RATIO, MAX_STATIONARY_STEPS, MIN_COORDINATE, REGION_RANGE_BITS,
    };
}

/// The geometry beneath a scene: polylines and their queries, boxes, and the robust
/// orientation and segment-contact tests the validation uses.
pub mod geometry {
    pub use crate::geom::{Aabb, SegmentContact, orient, segment_contact};
    pub use crate::polyline::{Nearest, Polyline, PolylineError};
}

/// Region lookup: the regions the interfaces cut the plane into, and the medium of each
/// ([`Tracer::regions`]).
pub mod lookup {
    pub use crate::regions::{LocateHint, Regions, Sides};
}

/// The fixed codes of the `.npy` format: the status and kink codes, the index marking a leg
/// medium that was not found, and the padding of an arrival's steps.
pub mod npy {
    pub use crate::output::{KINK_CODES, NO_INTERFACE, NO_MEDIUM, NO_STEP_KIND, STATUS_CODES};
}

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
