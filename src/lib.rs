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
//!    [`BatchGradients`](derivatives::BatchGradients) both for a whole batch.
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

// Each public module is the file of its name (`src/NAME.rs` or `src/NAME/mod.rs`): the one
// path of what it defines. `ARCHITECTURE.md` lists them in the order they depend on each other.
pub mod amplitude;
pub mod batch;
mod bvh;
pub mod demo;
pub mod derivatives;
pub mod geom;
mod leg;
pub mod options;
pub mod output;
pub mod polyline;
pub mod problem;
pub mod regions;
pub mod response;
pub mod scene;
pub mod search;
mod solver;
pub mod stationary;
pub mod trace;

#[cfg(feature = "argmin")]
pub mod argmin_bridge;

// The vocabulary: what a user of the README names, also reachable at its module's path.
// `tests/architecture.rs` keeps this list at 30 or fewer.
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

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

/// The tour's examples (`docs/guide.md`), compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../docs/guide.md")]
struct GuideDoctests;
