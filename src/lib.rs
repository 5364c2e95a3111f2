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
//! 5. **Write**: [`write()`] writes rays, batches, every stationary path and search arrivals
//!    as JSON, JSON Lines, CSV or `.npy` ([`Format`]).
//! 6. **Derivatives**: [`Tracer::gradient`] gives the derivatives of a solved ray's time with
//!    respect to its source, receiver, each medium's slowness and the vertices it touches
//!    ([`Gradient`]); [`PointSensitivities`] how its points move;
//!    [`BatchGradients`](gradients::BatchGradients) both for a whole batch.
//! 7. **Amplitudes**: a scene with `"amplitudes"` ([`SceneBuilder::amplitudes`]) gives every
//!    timed ray and arrival its [`Amplitude`] (spreading, reflection and transmission
//!    coefficients, attenuation); [`Tracer::amplitude_of`] computes one for any solved path.
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

mod amplitude;
mod batch;
mod bvh;
mod control;
pub mod demo;
mod derivatives;
mod geom;
mod leg;
mod output;
mod polyline;
mod problem;
mod regions;
pub mod response;
mod scene;
pub mod search;
mod solver;
pub mod stationary;
mod trace;

#[cfg(feature = "argmin")]
pub mod argmin_bridge;

// The vocabulary: what a user of the README names. Everything else that is public lives in a
// module named for its concept, below. `tests/architecture.rs` keeps this list at 30 or fewer.
pub use amplitude::Amplitude;
pub use batch::{Batch, BatchOptions};
pub use derivatives::{Gradient, PointSensitivities};
pub use geom::{Point, Vec2};
pub use output::{Document, Format, RaySet, write};
pub use scene::{
    InterfaceSpec, MediumSpec, PathSpec, Scene, SceneBuilder, SceneError, SceneSpec, SolverOptions,
    StepSpec,
};
pub use search::SearchArrival;
pub use stationary::StationaryRays;
pub use trace::{Arrival, InitialGuess, Ray, RayRecord, Reason, Status, Tracer, Workspace};

/// The scene document's parts as plain data ([`SceneSpec`] and the specs of its keys), for
/// scenes written in code or read with serde.
pub mod spec {
    pub use crate::scene::{
        AmplitudesSpec, AttenuationSpec, ImpulseResponseSpec, InterfaceSpec, MediumSpec, PathSpec,
        Polarization, ReceiverGridSpec, ReceiversSpec, ReflectionSpec, SceneSpec, SearchSpec,
        SolverSpec, SourceModel, StationaryMode, StepSpec,
    };
}

/// The parts of a validated [`Scene`], as its accessors give them: media, interfaces, paths
/// and their steps, segments, the search's options, and the sizes of a batch.
pub mod scene_parts {
    pub use crate::scene::{
        Amplitudes, BatchSize, ImpulseResponseOptions, Interface, Medium, Path, RayTriple,
        Reflection, SearchOptions, SegmentRef, Step, StepKind, Waves,
    };
}

/// Amplitudes ([`Amplitude`]): why a timed ray may have none, and the complex numbers they
/// are written in; the uniform wedge coefficient of diffracted paths and its Fresnel integral.
pub mod amplitudes {
    pub use crate::amplitude::diffraction::{Faces, fresnel_tail, transition, wedge_coefficient};
    pub use crate::amplitude::{Complex64, DiffractionCase, NoAmplitude};
}

/// What a [`Tracer`] can be told besides its scene: the solver's options, the start of each
/// ray, and which kernels it may use (for comparing the kernels with the general solve).
pub mod options {
    pub use crate::control::Stop;
    pub use crate::scene::SolverOptions;
    pub use crate::trace::{InitialGuess, Kernels};
}

/// Writing a batch into arrays of your own ([`Tracer::trace_batch_to`]): the sink each worker
/// writes a ray into right after solving it, where a ray goes, and the scratch a sink reuses.
pub mod sink {
    pub use crate::batch::{BatchRay, BatchRays, BatchScratch, BatchSink, RaySlot};
}

/// Derivatives of a ray's time ([`Gradient`]) and of its points ([`PointSensitivities`]), per
/// ray and for a whole batch ([`BatchGradients`](gradients::BatchGradients)).
pub mod gradients {
    pub use crate::derivatives::{
        Axis, BatchGradientArrays, BatchGradients, DerivativeError, Gradient, GradientArraysMut,
        GradientRows, Parameter, PointSensitivities, VertexGradient,
    };
}

/// The path problem of one ray on its own: travel time, residual and tridiagonal Hessian at
/// any parameters ([`PathProblem`](path_problem::PathProblem)), for cross-checks with other
/// solvers.
pub mod path_problem {
    pub use crate::problem::{PathProblem, Tridiagonal};
}

/// The limits a scene is validated against, and the solver's defaults.
pub mod limits {
    pub use crate::control::{MAX_INPUT_BYTES, available_memory, fits_in_memory, read_limited};
    pub use crate::scene::{
        DEFAULT_MAX_ITERATIONS, DEFAULT_MAX_WORK, DEFAULT_TOLERANCE, FALLBACK_MAX_WORK,
        MAX_ATTENUATION, MAX_COORDINATE, MAX_ITERATIONS_LIMIT, MAX_SEARCH_STEPS, MAX_SPEED_RATIO,
        MAX_STATIONARY_STEPS, MAX_WORK_LIMIT, MIN_COORDINATE, REGION_RANGE_BITS,
    };
    pub use crate::scene::{DEFAULT_TAPS, MAX_RATE, MAX_SAMPLES, MAX_TAPS};
    pub use crate::search::{MAX_SEARCH_ARRIVALS, MAX_SEARCH_BEAMS, MAX_SEARCH_MEMORY};
}

/// The geometry beneath a scene: polylines and their queries, boxes, and the robust
/// orientation and segment-contact tests the validation uses.
pub mod geometry {
    pub use crate::geom::{Aabb, Segment, SegmentContact, orient, segment_contact};
    pub use crate::polyline::{Nearest, Polyline, PolylineError};
}

/// Region lookup: the regions the interfaces cut the plane into, and the medium of each
/// ([`Tracer::regions`]).
pub mod lookup {
    pub use crate::regions::{LocateHint, Regions, Sides};
}

/// The column schema of the quantities that follow a ray's or an arrival's own fields (the
/// gradient, the amplitude): what the writers and the Python package iterate over.
pub mod columns {
    pub use crate::output::columns::{Cell, Column, ColumnType, Entry, Schema, Why};
}

/// The `.npy` format's fixed codes (the status and kink codes, the index marking a leg medium
/// that was not found, the padding of an arrival's steps) and the name tables that give its
/// indices their names ([`write_names`](npy::write_names), the `--names` sidecar).
pub mod npy {
    pub use crate::output::{
        AMPLITUDE_NOT_COMPUTED, KINK_CODES, NO_INTERFACE, NO_MEDIUM, NO_STEP_KIND, STATUS_CODES,
        write_f64_array, write_names,
    };
}

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

/// The tour's examples (`docs/guide.md`), compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../docs/guide.md")]
struct GuideDoctests;
