//! Derivatives of a ray's travel time, and of its points, with respect to everything the scene
//! fixes: the source and receiver positions, each medium's slowness and every polyline vertex
//! that the path touches.
//!
//! A ray with a time is a stationary point of `T(s; θ) = Σⱼ wⱼ ℓⱼ` in its interaction
//! parameters `s` (or holds a point on a vertex, where the time has a kink). With each free
//! interaction point written as `xᵢ = aᵢ + λᵢ (bᵢ − aᵢ)` on its segment `[aᵢ, bᵢ]`, the
//! envelope theorem gives the derivative of the solved time as the partial derivative at the
//! solved points, the points held at their fractions `λᵢ`:
//!
//! ```text
//! gᵢ       = ∂T/∂xᵢ = wᵢ uᵢ − wᵢ₊₁ uᵢ₊₁        (uⱼ the unit direction of leg j, leg j ends at point j)
//! dT/dS    = −w₀ u₀            dT/dR = wₖ uₖ
//! dT/dw_m  = Σ ℓⱼ over the legs j in medium m
//! dT/daᵢ  += (1 − λᵢ) gᵢ       dT/dbᵢ += λᵢ gᵢ   (a point held on a vertex v: dT/dv += gᵢ)
//! ```
//!
//! The points themselves move by the implicit function theorem. With `σᵢ` the distance of a
//! free point along its segment's tangent `tᵢ` (at fixed `λᵢ`, `dσᵢ = |bᵢ − aᵢ| dλᵢ`),
//! stationarity `rᵢ = gᵢ · tᵢ = 0` differentiates to `H dσ = −b`, with `H` the converged
//! tridiagonal Hessian of `problem` (segment-wise) and
//!
//! ```text
//! bᵢ = tᵢ · Σₘ (∂gᵢ/∂xₘ) δxₘ + tᵢ · (uᵢ dwᵢ − uᵢ₊₁ dwᵢ₊₁) + (gᵢ · nᵢ) nᵢ · (δbᵢ − δaᵢ) / |bᵢ − aᵢ|
//! ∂gᵢ/∂xᵢ₋₁ = −wᵢ Pᵢ / ℓᵢ,   ∂gᵢ/∂xᵢ₊₁ = −wᵢ₊₁ Pᵢ₊₁ / ℓᵢ₊₁,   ∂gᵢ/∂xᵢ = −(the sum of both),
//! ```
//!
//! `Pⱼ = I − uⱼ uⱼᵀ`, `δxₘ` the motion of point `m` at fixed fractions (the source, the receiver,
//! a vertex) and the last term the turn of the segment. A point is then `δxᵢ + tᵢ dσᵢ`. A point
//! held on a vertex moves with it and leaves the system (its row is the identity); so does a
//! point next to a vanished leg (a source or receiver on the interface), where the time is not
//! differentiable: there the derivatives are those of the point held at its fraction, and a
//! vanished leg's direction counts as zero.
//!
//! Everything here is computed from a ray's points and leg media (and, after a solve, the
//! segments the solver left in the [`Workspace`]): nothing in the solve itself changes, so rays
//! that do not ask for derivatives cost what they did.

use rayon::prelude::*;

use crate::batch::Batch;
use crate::geom::{Point, Vec2};
use crate::polyline::Polyline;
use crate::scene::{Scene, Step};
use crate::solver::thomas;
use crate::trace::{Ray, RayRecord, SegmentFrame, Status, Tracer, Workspace};

/// The derivative of a travel time with respect to one polyline vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VertexGradient {
    /// Index of the interface in [`Scene::interfaces`].
    pub interface: usize,
    /// Index of the vertex in the interface's `points`.
    pub vertex: usize,
    /// `(dT/dx, dT/dy)` of the vertex.
    pub d: Vec2,
}

/// The derivatives of one ray's travel time (the contract's `"gradient"`).
///
/// ```
/// use eigenray::{Gradient, Scene, Tracer, Vec2, Workspace};
/// let scene = Scene::from_json(r#"{
///     "media": { "air": { "index": 1.0 }, "water": { "index": 1.333 } },
///     "interfaces": { "surface": { "points": [[-1, 0], [2, 0]] } },
///     "sources": [[0, 1]], "receivers": [[1, -1]],
///     "paths": [{ "steps": [{ "refract": "surface" }], "media": ["air", "water"] }]
/// }"#).unwrap();
/// let tracer = Tracer::new(&scene).unwrap();
/// let mut ws = Workspace::new();
/// tracer.solve(scene.sources()[0], scene.receivers()[0], 0, &mut ws);
/// let g = Gradient::of_solved(&scene, 0, &ws).unwrap();
/// // Moving the receiver along the last leg lengthens it at the water's slowness.
/// let p = ws.points();
/// let last = (p[2] - p[1]) * (1.0 / (p[2] - p[1]).length());
/// assert!((g.receiver.dot(last) - 1.333).abs() < 1e-9);
/// // dT/dw of each medium is the length of the path in it.
/// assert!((g.slowness[0] - (p[1] - p[0]).length()).abs() < 1e-12);
/// assert_eq!(g.vertices.len(), 2); // both ends of the surface's one segment
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Gradient {
    /// `(dT/dx, dT/dy)` of the source.
    pub source: Vec2,
    /// `(dT/dx, dT/dy)` of the receiver.
    pub receiver: Vec2,
    /// `dT/dw` of each medium, in the order of [`Scene::media`] (0 for a medium the ray does
    /// not pass through). `w` is the slowness: 1/speed, or the index.
    pub slowness: Vec<f64>,
    /// Every vertex whose movement changes the time (those of the segments the path touches;
    /// for a point held on a vertex, that vertex), each once, ordered by interface and vertex.
    pub vertices: Vec<VertexGradient>,
    /// `(dT/dgx, dT/dgy)` of each medium's speed gradient (`c(p) = speed + gradient · p`),
    /// in the order of [`Scene::media`], in a scene with a gradient medium (zero for a medium
    /// without one, or one the ray does not pass through); empty in other scenes. Its
    /// `slowness` entry is then `dT/dw` with `w = 1/speed` and the gradient held.
    pub speed_gradient: Vec<Vec2>,
    /// `dT/dc` of each knot of each medium's speed profile, in the order of
    /// [`Scene::media`] and of the medium's `profile` (empty for a medium without one, or
    /// one the ray does not pass through: zeros), in a scene with a profile medium; empty in
    /// other scenes. Its `slowness` entry is then `dT/dw` with `w = 1/c` of the first knot
    /// and the profile's shape held (every knot's `c` moved alike): `−c₀² Σₖ dT/dcₖ`.
    pub profile_speed: Vec<Vec<f64>>,
}

/// Why derivatives could not be computed for a ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DerivativeError {
    /// The ray has no time (`no_path`, `not_converged`): no points to differentiate at.
    NoTime,
    /// The path index is not one of the scene's paths.
    UnknownPath {
        /// The index given.
        path: usize,
    },
    /// The ray has `points` points where its path has `expected` (steps + 2).
    PointCount {
        /// Points given.
        points: usize,
        /// Points the path has.
        expected: usize,
    },
    /// The leg media are not known, or not one per leg of the scene's media.
    Media,
    /// Interaction point `step` does not lie on its interface.
    OffInterface {
        /// Index of the step.
        step: usize,
    },
    /// The Hessian at the solution is singular (a caustic): the points do not move smoothly.
    Singular,
    /// For [`PointSensitivities`]: the scene has a medium with a speed gradient or a
    /// profile: point sensitivities through curved legs are not available yet.
    CurvedLegs,
    /// The ray's points are not those of a ray of its profile medium (a path without steps
    /// whose ends are not the points', or reflections off the walls elsewhere).
    NoProfileRay,
}

impl std::fmt::Display for DerivativeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DerivativeError::NoTime => f.write_str("the ray has no time (no path was found)"),
            DerivativeError::UnknownPath { path } => write!(f, "no path {path} in the scene"),
            DerivativeError::PointCount { points, expected } => write!(
                f,
                "the ray has {points} points where its path has {expected} (steps + 2)"
            ),
            DerivativeError::Media => {
                f.write_str("the ray's leg media are not known (one per leg is needed)")
            }
            DerivativeError::OffInterface { step } => {
                write!(f, "interaction point {step} does not lie on its interface")
            }
            DerivativeError::CurvedLegs => f.write_str(
                "point sensitivities through curved legs (a medium with a `gradient` or a \
                 `profile`) are not available yet",
            ),
            DerivativeError::NoProfileRay => f.write_str(
                "the ray's points are not those of a ray of its profile medium (its ends, and \
                 its reflections at the waveguide's walls)",
            ),
            DerivativeError::Singular => f.write_str(
                "the Hessian at the solution is singular (a caustic): the points do not move \
                 smoothly",
            ),
        }
    }
}

impl std::error::Error for DerivativeError {}

/// Where one interaction point lies on its polyline.
#[derive(Clone, Copy, Debug, Default)]
struct Contact {
    /// Its segment.
    seg: usize,
    /// Its fraction along the segment from the start vertex, in `[0, 1]`.
    lambda: f64,
    /// The vertex indices of the segment's start and end.
    a: usize,
    b: usize,
    /// The vertex it sits on, if any.
    at_vertex: Option<usize>,
}

impl Contact {
    /// Puts `g`, the time's gradient with respect to the point, onto the polyline's vertices:
    /// all of it on the vertex the point sits on, else shared between its segment's two ends
    /// as the point's position is (`1 − λ` and `λ`).
    #[inline(always)]
    fn share(&self, interface: usize, g: Vec2, put: &mut impl FnMut(VertexGradient)) {
        match self.at_vertex {
            Some(vertex) => put(VertexGradient {
                interface,
                vertex,
                d: g,
            }),
            None => {
                put(VertexGradient {
                    interface,
                    vertex: self.a,
                    d: g * (1.0 - self.lambda),
                });
                put(VertexGradient {
                    interface,
                    vertex: self.b,
                    d: g * self.lambda,
                });
            }
        }
    }
}

/// Where `p` lies on `line`: on segment `hint` when it lies there (the solver's segment), else
/// on the nearest segment. `None` when it is not on the polyline (beyond round-off).
#[inline(always)]
fn locate(line: &Polyline, p: Point, hint: Option<usize>) -> Option<Contact> {
    if let Some(j) = hint
        && j < line.num_segments()
        && let Some(c) = contact_on(line, j, p)
    {
        return Some(c);
    }
    contact_on(line, line.nearest(p).seg, p)
}

/// Where `p` lies on segment `j` of `line`, if it lies there (to round-off).
#[inline(always)]
fn contact_on(line: &Polyline, j: usize, p: Point) -> Option<Contact> {
    let start = line.segment(j).start;
    let frame = SegmentFrame {
        start,
        tangent: line.tangent(j),
        length: line.segment_length(j),
    };
    let end_vertex = if j + 1 == line.vertices().len() {
        0
    } else {
        j + 1
    };
    let at = SegmentPoint::of(&frame, p);
    at.on_segment().then(|| at.contact(j, end_vertex))
}

/// A point measured against a segment: its distance along the segment from the start, across
/// it, and the round-off of both.
struct SegmentPoint {
    along: f64,
    across: f64,
    length: f64,
    round: f64,
}

impl SegmentPoint {
    #[inline(always)]
    fn of(frame: &SegmentFrame, p: Point) -> SegmentPoint {
        let (a, t) = (frame.start, frame.tangent);
        let d = p - a;
        SegmentPoint {
            along: d.dot(t),
            across: d.cross(t),
            length: frame.length,
            round: 16.0 * f64::EPSILON * ((p.x.abs() + p.y.abs()) + (a.x.abs() + a.y.abs())),
        }
    }

    /// Whether the point is on the segment, to round-off.
    #[inline(always)]
    fn on_segment(&self) -> bool {
        let slack = 1e-9 * self.length + 4.0 * self.round;
        self.across.abs() <= slack && self.along >= -slack && self.along <= self.length + slack
    }

    /// The contact of a point on segment `seg`, which ends at vertex `end_vertex`.
    #[inline(always)]
    fn contact(&self, seg: usize, end_vertex: usize) -> Contact {
        let (along, len) = (self.along, self.length);
        // On a vertex: within round-off of it (where the solver holds a point, it is exact).
        let snap = 1e-12 * len + self.round;
        let (at_vertex, lambda) = if along <= snap {
            (Some(seg), 0.0)
        } else if len - along <= snap {
            (Some(end_vertex), 1.0)
        } else {
            (None, along / len)
        };
        Contact {
            seg,
            lambda,
            a: seg,
            b: end_vertex,
            at_vertex,
        }
    }
}

/// The unit direction and length of the leg from `p` to `q` (a zero direction for a leg of
/// zero length).
#[inline(always)]
fn leg(p: Point, q: Point) -> (Vec2, f64) {
    let d = q - p;
    let l2 = d.x * d.x + d.y * d.y;
    // The common leg in line, without a select: a squared length that neither underflows nor
    // overflows.
    if (f64::MIN_POSITIVE..1e300).contains(&l2) {
        let l = l2.sqrt();
        (d * (1.0 / l), l)
    } else {
        leg_unusual(d)
    }
}

/// [`leg`] of a leg of zero, tiny or huge length (out of line: the common ray never comes here).
#[cold]
#[inline(never)]
fn leg_unusual(d: Vec2) -> (Vec2, f64) {
    let l = d.length();
    (
        if l > 0.0 {
            d * (1.0 / l)
        } else {
            Vec2::default()
        },
        l,
    )
}

/// Whether the scene has a medium with a speed profile.
fn has_profile(scene: &Scene) -> bool {
    scene.curved() && scene.media().iter().any(|m| m.profile.is_some())
}

/// Whether the scene has a medium with a speed gradient.
fn has_gradient(scene: &Scene) -> bool {
    scene.curved() && scene.media().iter().any(|m| m.gradient.is_some())
}

/// The steps of path `path`.
fn path_steps(scene: &Scene, path: usize) -> Result<&[Step], DerivativeError> {
    let spec = scene
        .paths()
        .get(path)
        .ok_or(DerivativeError::UnknownPath { path })?;
    Ok(&spec.steps)
}

/// Checks a ray's points against its steps.
fn check_points(steps: &[Step], points: &[Point]) -> Result<(), DerivativeError> {
    if points.is_empty() {
        return Err(DerivativeError::NoTime);
    }
    if points.len() != steps.len() + 2 {
        return Err(DerivativeError::PointCount {
            points: points.len(),
            expected: steps.len() + 2,
        });
    }
    Ok(())
}

/// The parts of a gradient that have a fixed size: the source's and receiver's.
struct EndGradients {
    source: Vec2,
    receiver: Vec2,
}

/// The gradient of the ray through `points` with leg media `media`: `slowness` (one entry per
/// medium of the scene) filled, every vertex share given to `put` (up to `2 × steps`, in the
/// order of the points, not yet merged: see [`merge`]), the source's and receiver's gradients
/// returned. Allocates nothing.
fn gradient_parts(
    scene: &Scene,
    steps: &[Step],
    points: &[Point],
    mut media: impl Iterator<Item = usize>,
    hint: Option<&[usize]>,
    slowness: &mut [f64],
    mut put: impl FnMut(VertexGradient),
) -> Result<EndGradients, DerivativeError> {
    check_points(steps, points)?;
    let all_media = scene.media();
    slowness.fill(0.0);
    if scene.curved() {
        let mut media = media.peekable();
        if let Some(m) = profile_medium(scene, media.peek().copied()) {
            let ray = ProfileLegs {
                steps,
                points,
                medium: m,
                launch: None,
            };
            return profile_parts(scene, ray, media, slowness, None, put);
        }
        let medium = || {
            media
                .next()
                .filter(|&m| m < all_media.len())
                .ok_or(DerivativeError::Media)
        };
        return curved_parts(scene, steps, points, medium, hint, slowness, None, put);
    }
    let mut medium = || {
        media
            .next()
            .filter(|&m| m < all_media.len())
            .ok_or(DerivativeError::Media)
    };
    // Leg 0.
    let m0 = medium()?;
    let (mut u_prev, l0) = leg(points[0], points[1]);
    let mut w_prev = all_media[m0].slowness;
    slowness[m0] += l0;
    let source = u_prev * -w_prev;
    for (i, step) in steps.iter().enumerate() {
        let m = medium()?;
        let (u, l) = leg(points[i + 1], points[i + 2]);
        let w = all_media[m].slowness;
        slowness[m] += l;
        let g = u_prev * w_prev - u * w;
        let line = &scene.interfaces()[step.interface].polyline;
        let c = locate(line, points[i + 1], hint.map(|h| h[i]))
            .ok_or(DerivativeError::OffInterface { step: i })?;
        c.share(step.interface, g, &mut put);
        (u_prev, w_prev) = (u, w);
    }
    if media.next().is_some() {
        return Err(DerivativeError::Media);
    }
    let receiver = u_prev * w_prev;
    Ok(EndGradients { source, receiver })
}

/// One leg's share of a gradient through curved legs: `−∇ₐT`, `∇_bT`, `dT/dw` of its medium
/// (`w = 1/speed`, the gradient held) and `dT/dG` of its medium's gradient (zero without one).
fn leg_parts(medium: &crate::scene::Medium, a: Point, b: Point) -> (Vec2, Vec2, f64, Vec2) {
    if medium.gradient.is_none() {
        let (u, l) = leg(a, b);
        let w = medium.slowness;
        return (u * w, u * w, l, Vec2::default());
    }
    let crate::leg::LegMedium::Linear(model) = medium.leg_model(Point::new(0.0, 0.0)) else {
        unreachable!("a medium with a gradient has linear legs")
    };
    let arc = crate::leg::LegModel::leg(model, a.to_vec2(), b.to_vec2());
    let (dc, dg) = arc.medium_derivatives(a.to_vec2(), b.to_vec2());
    let c0 = 1.0 / medium.slowness;
    use crate::leg::Leg as _;
    (arc.departure(), arc.arrival(), -dc * c0 * c0, dg)
}

/// [`gradient_parts`] in a scene with curved legs (a medium with a gradient; `medium` gives
/// the leg media, `slowness` already zeroed): each leg's slowness vectors at its ends from the
/// leg model (an arc's, whose directions at its ends are not its chord's), and into
/// `speed_gradient` (when given, one entry per medium) each medium's `dT/dG`.
#[expect(
    clippy::too_many_arguments,
    reason = "gradient_parts' arguments, and the speed gradients"
)]
fn curved_parts(
    scene: &Scene,
    steps: &[Step],
    points: &[Point],
    mut medium: impl FnMut() -> Result<usize, DerivativeError>,
    hint: Option<&[usize]>,
    slowness: &mut [f64],
    mut speed_gradient: Option<&mut [Vec2]>,
    mut put: impl FnMut(VertexGradient),
) -> Result<EndGradients, DerivativeError> {
    let all_media = scene.media();
    if let Some(sg) = speed_gradient.as_deref_mut() {
        sg.fill(Vec2::default());
    }
    let mut arrival_prev = Vec2::default();
    let mut source = Vec2::default();
    for (j, ends) in points.windows(2).enumerate() {
        let m = medium()?;
        let (departure, arrival, dw, dg) = leg_parts(&all_media[m], ends[0], ends[1]);
        slowness[m] += dw;
        if let Some(sg) = speed_gradient.as_deref_mut() {
            sg[m] += dg;
        }
        if j == 0 {
            source = departure * -1.0;
        } else {
            let i = j - 1;
            let g = arrival_prev - departure;
            let step = &steps[i];
            let line = &scene.interfaces()[step.interface].polyline;
            let c = locate(line, points[i + 1], hint.map(|h| h[i]))
                .ok_or(DerivativeError::OffInterface { step: i })?;
            c.share(step.interface, g, &mut put);
        }
        arrival_prev = arrival;
    }
    if medium().is_ok() {
        return Err(DerivativeError::Media);
    }
    Ok(EndGradients {
        source,
        receiver: arrival_prev,
    })
}

/// The profile medium `first` (a ray's first leg medium) when it has a profile: its rays
/// are the profile's ([`profile_parts`]).
fn profile_medium(scene: &Scene, first: Option<usize>) -> Option<usize> {
    let m = first?;
    scene.media().get(m)?.profile.is_some().then_some(m)
}

/// A ray through a profile medium as the derivatives read it.
#[derive(Clone, Copy)]
struct ProfileLegs<'a> {
    /// Its steps (none, or reflections at the waveguide's walls).
    steps: &'a [Step],
    /// Source, reflection points, receiver.
    points: &'a [Point],
    /// The profile medium (every leg's).
    medium: usize,
    /// Its direction at the source (`launch_angle`), where the entry gives it: which of the
    /// rays between the same points it is.
    launch: Option<f64>,
}

/// [`gradient_parts`] of a ray through a profile medium (`media` the leg media, every one
/// `ray.medium`; `slowness` zeroed): the ray found again ([`crate::trace::profile_ray_of`]),
/// the ends' slowness vectors (the ray's directions there over the speeds), each reflection's
/// jump of the slowness vector (vertical: the horizontal slowness is conserved) shared by its
/// segment's vertices, the knots' `dT/dc` into `profile_speed` (when given, one entry per
/// medium) and the medium's `slowness` entry from them.
fn profile_parts(
    scene: &Scene,
    ray: ProfileLegs<'_>,
    media: impl Iterator<Item = usize>,
    slowness: &mut [f64],
    profile_speed: Option<&mut [Vec<f64>]>,
    mut put: impl FnMut(VertexGradient),
) -> Result<EndGradients, DerivativeError> {
    let ProfileLegs {
        steps,
        points,
        medium,
        launch,
    } = ray;
    let mut legs = 0;
    for m in media {
        if m != medium {
            return Err(DerivativeError::Media);
        }
        legs += 1;
    }
    if legs != steps.len() + 1 {
        return Err(DerivativeError::Media);
    }
    if crate::trace::takes_sloped_route(scene, steps) {
        return sloped_parts(scene, ray, slowness, profile_speed, put);
    }
    let found = crate::trace::profile_ray_of(scene, steps, points, medium, launch)
        .ok_or(DerivativeError::NoProfileRay)?;
    let (r, [ya, yb]) = (&found.ray, [points[0].y, points[points.len() - 1].y]);
    let knots = found.profile.knot_derivatives(r, ya, yb);
    // Each reflection's jump: the vertical slowness reversed.
    let jumps = (found.at_walls.iter())
        .map(|&(direction, _, speed)| Vec2::new(0.0, 2.0 * (direction * (1.0 / speed)).y));
    put_knots_and_walls(scene, ray, knots, jumps, slowness, profile_speed, &mut put)?;
    let [ca, cb] = r.speeds;
    Ok(EndGradients {
        source: r.direction_at_start() * (-1.0 / ca),
        receiver: r.direction_at_end() * (1.0 / cb),
    })
}

/// [`profile_parts`] of a ray of reflections off walls not all flat and horizontal (the
/// sloped route; its leg media checked): the ray found again
/// ([`crate::trace::sloped_derivatives`]), the ends' slowness vectors from its end legs,
/// each reflection's jump of the slowness vector shared by its segment's vertices (as the
/// point sits on it), the knots' `dT/dc` summed over the legs into `profile_speed` (when
/// given) and the medium's `slowness` entry from them.
fn sloped_parts(
    scene: &Scene,
    ray: ProfileLegs<'_>,
    slowness: &mut [f64],
    profile_speed: Option<&mut [Vec<f64>]>,
    mut put: impl FnMut(VertexGradient),
) -> Result<EndGradients, DerivativeError> {
    let ProfileLegs {
        steps,
        points,
        medium,
        launch,
    } = ray;
    let found = crate::trace::sloped_derivatives(scene, steps, points, medium, launch)
        .ok_or(DerivativeError::NoProfileRay)?;
    let walls = found.walls.iter().copied();
    put_knots_and_walls(
        scene,
        ray,
        found.knots,
        walls,
        slowness,
        profile_speed,
        &mut put,
    )?;
    Ok(EndGradients {
        source: found.source,
        receiver: found.receiver,
    })
}

/// The knots' `dT/dc` of a profile ray `ray` (`knots`, the profile's order: up) into
/// `profile_speed` (when given; the scene's order: down) and the medium's `slowness` entry
/// from them; each reflection's jump of the slowness vector (`jumps`, in order) shared by its
/// segment's vertices.
fn put_knots_and_walls(
    scene: &Scene,
    ray: ProfileLegs<'_>,
    mut knots: Vec<f64>,
    jumps: impl Iterator<Item = Vec2>,
    slowness: &mut [f64],
    profile_speed: Option<&mut [Vec<f64>]>,
    put: &mut impl FnMut(VertexGradient),
) -> Result<(), DerivativeError> {
    let ProfileLegs {
        steps,
        points,
        medium,
        ..
    } = ray;
    knots.reverse();
    let c0 = 1.0 / scene.media()[medium].slowness;
    slowness[medium] = -c0 * c0 * knots.iter().sum::<f64>();
    if let Some(ps) = profile_speed {
        ps[medium].clear();
        ps[medium].extend_from_slice(&knots);
    }
    for (i, (step, g)) in steps.iter().zip(jumps).enumerate() {
        let line = &scene.interfaces()[step.interface].polyline;
        let c =
            locate(line, points[i + 1], None).ok_or(DerivativeError::OffInterface { step: i })?;
        c.share(step.interface, g, &mut *put);
    }
    Ok(())
}

/// The slownesses of the two legs' media `media`.
#[inline(always)]
fn leg_slownesses(scene: &Scene, [m0, m1]: [usize; 2]) -> Result<[f64; 2], DerivativeError> {
    match (scene.media().get(m0), scene.media().get(m1)) {
        (Some(a), Some(b)) => Ok([a.slowness, b.slowness]),
        _ => Err(DerivativeError::Media),
    }
}

/// Sorts `v` by interface and vertex and adds up the entries of one vertex into one; returns
/// how many are left at the front.
fn merge(v: &mut [VertexGradient]) -> usize {
    let key = |e: &VertexGradient| (e.interface, e.vertex);
    // The shares come in order, each vertex once, but for points on neighbouring segments or
    // one segment, a closed polyline's last segment and interfaces met out of order: sort and
    // add up only then.
    if v.windows(2).all(|w| key(&w[0]) < key(&w[1])) {
        return v.len();
    }
    if !v.is_sorted_by_key(key) {
        v.sort_unstable_by_key(key);
    }
    let Some(first) = (1..v.len()).find(|&i| key(&v[i - 1]) == key(&v[i])) else {
        return v.len();
    };
    let mut n = first;
    for i in first..v.len() {
        if n > 0 && v[n - 1].interface == v[i].interface && v[n - 1].vertex == v[i].vertex {
            v[n - 1].d += v[i].d;
        } else {
            v[n] = v[i];
            n += 1;
        }
    }
    n
}

impl Gradient {
    /// The gradient of the ray of path `path` that was last solved in `ws` (by
    /// [`Tracer::solve`] or [`Tracer::trace`]).
    ///
    /// # Errors
    /// See [`DerivativeError`]: a ray without a time, a path index out of range or not the
    /// one solved.
    pub fn of_solved(
        scene: &Scene,
        path: usize,
        ws: &Workspace,
    ) -> Result<Gradient, DerivativeError> {
        let mut g = Gradient::default();
        g.solved_into(scene, path, ws)?;
        Ok(g)
    }

    /// [`of_solved`](Self::of_solved) into this gradient, reusing its memory: allocates
    /// nothing once it has held a gradient of as many media and vertices.
    ///
    /// # Errors
    /// As [`of_solved`](Self::of_solved).
    pub fn solved_into(
        &mut self,
        scene: &Scene,
        path: usize,
        ws: &Workspace,
    ) -> Result<(), DerivativeError> {
        let points = ws.points();
        let steps = path_steps(scene, path)?;
        if let ([step], &[p0, p1, p2], &[m0, m1], false) =
            (steps, points, ws.media(), scene.curved())
        {
            self.size_slowness(scene);
            let hint = ws.newton.seg.first().copied();
            return self.fill_one(scene, step, [p0, p1, p2], [m0, m1], hint);
        }
        let hint = ws.newton.seg.get(..steps.len());
        self.fill(scene, steps, points, ws.media().iter().copied(), hint)
    }

    /// The gradient of an owned [`Ray`] (from [`Tracer::trace_all`] or a batch).
    ///
    /// # Errors
    /// See [`DerivativeError`].
    pub fn of_ray(scene: &Scene, ray: &Ray) -> Result<Gradient, DerivativeError> {
        let steps = path_steps(scene, ray.path)?;
        let mut g = Gradient::default();
        g.fill(scene, steps, &ray.points, ray.media.iter().copied(), None)?;
        Ok(g)
    }

    /// The gradient of the path through `points` (source, interaction points, receiver) by
    /// `steps` with leg media `media` (indices into [`Scene::media`]): any path, also one of
    /// the automatic search's sequences.
    ///
    /// # Errors
    /// See [`DerivativeError`].
    pub fn of_points(
        scene: &Scene,
        steps: &[Step],
        points: &[Point],
        media: &[usize],
    ) -> Result<Gradient, DerivativeError> {
        let mut g = Gradient::default();
        g.points_into(scene, steps, points, media)?;
        Ok(g)
    }

    /// The gradient of a stationary path or search arrival `arrival` of `steps` (from
    /// [`Tracer::stationary_paths`] or a search): [`of_points`](Self::of_points) of its
    /// points and leg media, its `launch_angle` telling which ray it is where several share
    /// the points (a path without steps through a `profile` medium).
    ///
    /// # Errors
    /// See [`DerivativeError`].
    pub fn of_arrival(
        scene: &Scene,
        steps: &[Step],
        arrival: &crate::trace::Arrival,
    ) -> Result<Gradient, DerivativeError> {
        let mut g = Gradient::default();
        let media = arrival.media.iter().copied();
        g.fill_at(
            scene,
            steps,
            &arrival.points,
            media,
            None,
            arrival.launch_angle,
        )?;
        Ok(g)
    }

    /// [`of_points`](Self::of_points) into this gradient, reusing its memory: allocates
    /// nothing once it has held a gradient of as many media and vertices.
    ///
    /// # Errors
    /// As [`of_points`](Self::of_points).
    pub fn points_into(
        &mut self,
        scene: &Scene,
        steps: &[Step],
        points: &[Point],
        media: &[usize],
    ) -> Result<(), DerivativeError> {
        self.fill(scene, steps, points, media.iter().copied(), None)
    }

    /// [`of_points`](Self::of_points) into this gradient, reusing its memory; `segments`, when
    /// given, the segment of each interaction point (tried before a search for it).
    pub(crate) fn fill(
        &mut self,
        scene: &Scene,
        steps: &[Step],
        points: &[Point],
        media: impl Iterator<Item = usize>,
        segments: Option<&[usize]>,
    ) -> Result<(), DerivativeError> {
        self.fill_at(scene, steps, points, media, segments, None)
    }

    /// [`fill`](Self::fill) of an entry that gives its `launch_angle` (through a profile
    /// medium, which of the rays between the same points it is).
    pub(crate) fn fill_at(
        &mut self,
        scene: &Scene,
        steps: &[Step],
        points: &[Point],
        mut media: impl Iterator<Item = usize>,
        segments: Option<&[usize]>,
        launch: Option<f64>,
    ) -> Result<(), DerivativeError> {
        self.size_slowness(scene);
        if scene.curved() {
            return self.fill_curved(scene, steps, points, media, segments, launch);
        }
        // One interaction (the common ray): written out, without the general bookkeeping.
        if let ([step], &[p0, p1, p2]) = (steps, points) {
            let media = match [media.next(), media.next(), media.next()] {
                [Some(a), Some(b), None] => [a, b],
                _ => return Err(DerivativeError::Media),
            };
            let hint = segments.and_then(|h| h.first().copied());
            return self.fill_one(scene, step, [p0, p1, p2], media, hint);
        }
        self.vertices.clear();
        self.vertices.reserve(2 * steps.len());
        let vertices = &mut self.vertices;
        let result = gradient_parts(
            scene,
            steps,
            points,
            media,
            segments,
            &mut self.slowness,
            |v| vertices.push(v),
        );
        match result {
            Ok(ends) => {
                self.source = ends.source;
                self.receiver = ends.receiver;
                let n = merge(&mut self.vertices);
                self.vertices.truncate(n);
                Ok(())
            }
            Err(e) => {
                self.vertices.clear();
                Err(e)
            }
        }
    }

    /// [`fill`](Self::fill) in a scene with a gradient or a profile medium (curved legs),
    /// the slowness entries sized: the leg model's slowness vectors, and each medium's speed
    /// gradient; or a profile ray's ([`profile_parts`]) and its knots' derivatives.
    fn fill_curved(
        &mut self,
        scene: &Scene,
        steps: &[Step],
        points: &[Point],
        media: impl Iterator<Item = usize>,
        segments: Option<&[usize]>,
        launch: Option<f64>,
    ) -> Result<(), DerivativeError> {
        check_points(steps, points)?;
        let all = scene.media();
        let mut media = media.peekable();
        self.speed_gradient.clear();
        if has_gradient(scene) {
            self.speed_gradient.resize(all.len(), Vec2::default());
        }
        if has_profile(scene) {
            self.profile_speed.resize(all.len(), Vec::new());
            for (knots, m) in self.profile_speed.iter_mut().zip(all) {
                knots.clear();
                knots.resize(m.profile.as_ref().map_or(0, Vec::len), 0.0);
            }
        } else {
            self.profile_speed.clear();
        }
        self.slowness.fill(0.0);
        self.vertices.clear();
        let vertices = &mut self.vertices;
        let result = match profile_medium(scene, media.peek().copied()) {
            Some(medium) => {
                let ray = ProfileLegs {
                    steps,
                    points,
                    medium,
                    launch,
                };
                profile_parts(
                    scene,
                    ray,
                    media,
                    &mut self.slowness,
                    Some(&mut self.profile_speed),
                    |v| vertices.push(v),
                )
            }
            None => {
                let medium = || {
                    media
                        .next()
                        .filter(|&m| m < all.len())
                        .ok_or(DerivativeError::Media)
                };
                let sg = (!self.speed_gradient.is_empty()).then_some(&mut self.speed_gradient[..]);
                curved_parts(
                    scene,
                    steps,
                    points,
                    medium,
                    segments,
                    &mut self.slowness,
                    sg,
                    |v| vertices.push(v),
                )
            }
        };
        match result {
            Ok(ends) => {
                self.source = ends.source;
                self.receiver = ends.receiver;
                let n = merge(&mut self.vertices);
                self.vertices.truncate(n);
                Ok(())
            }
            Err(e) => {
                self.vertices.clear();
                Err(e)
            }
        }
    }

    /// One slowness entry per medium of `scene` (what the `fill_*` calls below expect).
    #[inline(always)]
    fn size_slowness(&mut self, scene: &Scene) {
        let media = scene.media().len();
        if self.slowness.len() != media {
            self.slowness.resize(media, 0.0);
        }
    }

    /// [`fill`](Self::fill) for a path of one interaction, its slowness entries already sized.
    #[inline(always)]
    fn fill_one(
        &mut self,
        scene: &Scene,
        step: &Step,
        points: [Point; 3],
        media: [usize; 2],
        hint: Option<usize>,
    ) -> Result<(), DerivativeError> {
        let w = leg_slownesses(scene, media)?;
        let line = &scene.interfaces()[step.interface].polyline;
        let c = locate(line, points[1], hint).ok_or(DerivativeError::OffInterface { step: 0 })?;
        self.fill_one_at(step.interface, c, points, media, w);
        Ok(())
    }

    /// [`fill_one`](Self::fill_one) for a ray of the flat kernel's plan, whose interaction
    /// point the solve put on `segment`, the interface's one segment (nothing to locate), and
    /// whose slowness entries are already sized.
    #[inline(always)]
    fn fill_flat(
        &mut self,
        scene: &Scene,
        interface: usize,
        segment: &SegmentFrame,
        points: [Point; 3],
        media: [usize; 2],
    ) -> Result<(), DerivativeError> {
        let w = leg_slownesses(scene, media)?;
        let at = SegmentPoint::of(segment, points[1]);
        debug_assert!(at.on_segment());
        self.fill_one_at(interface, at.contact(0, 1), points, media, w);
        Ok(())
    }

    /// The gradient of a ray of one interaction at `c` on interface `interface`, through
    /// `points` with leg media `media` of slownesses `w` (valid indices; the slowness entries
    /// already sized).
    #[inline(always)]
    fn fill_one_at(
        &mut self,
        interface: usize,
        c: Contact,
        [p0, p1, p2]: [Point; 3],
        [m0, m1]: [usize; 2],
        [w0, w1]: [f64; 2],
    ) {
        let ((u0, l0), (u1, l1)) = (leg(p0, p1), leg(p1, p2));
        let slowness = &mut self.slowness[..];
        if let [a, b] = slowness
            && m0 != m1
        {
            // Two media, both crossed: every entry written, none to clear first.
            (*a, *b) = if m0 == 0 { (l0, l1) } else { (l1, l0) };
        } else {
            slowness.fill(0.0);
            slowness[m0] += l0;
            slowness[m1] += l1;
        }
        self.source = u0 * -w0;
        self.receiver = u1 * w1;
        let g = u0 * w0 - u1 * w1;
        let share = |vertex, d| VertexGradient {
            interface,
            vertex,
            d,
        };
        match c.at_vertex {
            Some(v) => {
                self.vertices.clear();
                self.vertices.push(share(v, g));
            }
            None => {
                let (a, b) = (share(c.a, g * (1.0 - c.lambda)), share(c.b, g * c.lambda));
                let pair = if c.a < c.b { [a, b] } else { [b, a] };
                // In place when the last ray had two too (no length or capacity checks).
                if let Ok(two) = <&mut [VertexGradient; 2]>::try_from(&mut self.vertices[..]) {
                    *two = pair;
                } else {
                    self.vertices.clear();
                    self.vertices.extend_from_slice(&pair);
                }
            }
        }
    }

    /// The value of a ray without a time: NaN for the source, the receiver and every medium,
    /// no vertices.
    fn set_none(&mut self, media: usize) {
        let nan = Vec2::new(f64::NAN, f64::NAN);
        (self.source, self.receiver) = (nan, nan);
        self.slowness.clear();
        self.slowness.resize(media, f64::NAN);
        self.vertices.clear();
    }

    /// `(dT/dx, dT/dy)` of vertex `vertex` of interface `interface` (zero when the path does
    /// not touch it).
    pub fn vertex(&self, interface: usize, vertex: usize) -> Vec2 {
        self.vertices
            .iter()
            .find(|v| v.interface == interface && v.vertex == vertex)
            .map_or(Vec2::default(), |v| v.d)
    }

    /// `dT/dw` of the medium named `name` (`None` when the scene has no such medium).
    pub fn slowness_of(&self, scene: &Scene, name: &str) -> Option<f64> {
        let m = scene.media().iter().position(|m| m.name == name)?;
        self.slowness.get(m).copied()
    }
}

/// A coordinate axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axis {
    /// `x`.
    X,
    /// `y`.
    Y,
}

impl Axis {
    /// The unit vector along the axis.
    pub fn unit(self) -> Vec2 {
        match self {
            Axis::X => Vec2::new(1.0, 0.0),
            Axis::Y => Vec2::new(0.0, 1.0),
        }
    }
}

/// One scalar that the scene fixes and a ray depends on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Parameter {
    /// A coordinate of the source.
    Source(Axis),
    /// A coordinate of the receiver.
    Receiver(Axis),
    /// The slowness of a medium (index into [`Scene::media`]).
    Slowness {
        /// The medium.
        medium: usize,
    },
    /// A coordinate of a polyline vertex.
    Vertex {
        /// Index of the interface in [`Scene::interfaces`].
        interface: usize,
        /// Index of the vertex in its `points`.
        vertex: usize,
        /// The coordinate.
        axis: Axis,
    },
}

/// How the points of one ray move with every [`Parameter`] it depends on: `d(point)/dθ` by the
/// implicit function theorem (one tridiagonal solve with the converged Hessian per parameter).
///
/// The parameters are the source's and receiver's coordinates, every medium's slowness and
/// both coordinates of every vertex of the ray's [`Gradient`], in that order; the points are
/// those of [`Workspace::points`] (source, interactions, receiver).
///
/// ```
/// use eigenray::derivatives::{Axis, Parameter};
/// use eigenray::{PointSensitivities, Scene, Tracer, Workspace};
/// let scene = Scene::from_json(r#"{
///     "media": { "air": { "speed": 1.0 } },
///     "interfaces": { "mirror": { "points": [[-5, 0], [5, 0]] } },
///     "sources": [[-1, 1]], "receivers": [[1, 1]],
///     "paths": [{ "steps": [{ "reflect": "mirror" }], "media": ["air", "air"] }]
/// }"#).unwrap();
/// let tracer = Tracer::new(&scene).unwrap();
/// let mut ws = Workspace::new();
/// tracer.solve(scene.sources()[0], scene.receivers()[0], 0, &mut ws);
/// let sens = PointSensitivities::of_solved(&scene, 0, &ws).unwrap();
/// // The specular point of equal heights is midway: it moves half as far as the receiver.
/// let rx = sens.find(Parameter::Receiver(Axis::X)).unwrap();
/// assert!((sens.d_point(rx, 1).x - 0.5).abs() < 1e-12);
/// ```
#[derive(Clone, Debug, Default)]
pub struct PointSensitivities {
    parameters: Vec<Parameter>,
    points: usize,
    /// `d(point)/dθ`, one row of `points` per parameter.
    d: Vec<Vec2>,
    scratch: Scratch,
}

/// The scratch of [`PointSensitivities`] (reused).
#[derive(Clone, Debug, Default)]
struct Scratch {
    gradient: Gradient,
    contacts: Vec<Contact>,
    /// Per leg: unit direction, length, slowness, medium.
    u: Vec<Vec2>,
    len: Vec<f64>,
    w: Vec<f64>,
    medium: Vec<usize>,
    /// Per point: whether it is held (on a vertex, or next to a vanished leg), its tangent, the
    /// couplings of its residual to the previous, own and next point, and the turn term.
    held: Vec<bool>,
    tan: Vec<Vec2>,
    c_prev: Vec<Vec2>,
    c_self: Vec<Vec2>,
    c_next: Vec<Vec2>,
    turn: Vec<f64>,
    diag: Vec<f64>,
    off: Vec<f64>,
    rhs: Vec<f64>,
    x: Vec<f64>,
    cp: Vec<f64>,
    /// Per point: its motion at fixed fractions under one parameter.
    moved: Vec<Vec2>,
}

impl PointSensitivities {
    /// The sensitivities of the ray of path `path` last solved in `ws`.
    ///
    /// # Errors
    /// See [`DerivativeError`]; [`DerivativeError::Singular`] at a caustic.
    pub fn of_solved(
        scene: &Scene,
        path: usize,
        ws: &Workspace,
    ) -> Result<PointSensitivities, DerivativeError> {
        let mut s = PointSensitivities::default();
        s.solved_into(scene, path, ws)?;
        Ok(s)
    }

    /// [`of_solved`](Self::of_solved) into this value, reusing its memory: allocates nothing
    /// once it has held the sensitivities of a ray as long.
    ///
    /// # Errors
    /// As [`of_solved`](Self::of_solved).
    pub fn solved_into(
        &mut self,
        scene: &Scene,
        path: usize,
        ws: &Workspace,
    ) -> Result<(), DerivativeError> {
        let points = ws.points();
        let steps = path_steps(scene, path)?;
        let hint = ws.newton.seg.get(..steps.len());
        self.fill(scene, steps, points, ws.media(), hint)
    }

    /// The sensitivities of the path through `points` by `steps` with leg media `media` (see
    /// [`Gradient::of_points`]).
    ///
    /// # Errors
    /// See [`DerivativeError`].
    pub fn of_points(
        scene: &Scene,
        steps: &[Step],
        points: &[Point],
        media: &[usize],
    ) -> Result<PointSensitivities, DerivativeError> {
        let mut s = PointSensitivities::default();
        s.fill(scene, steps, points, media, None)?;
        Ok(s)
    }

    /// The parameters, in the order of the rows.
    pub fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    /// The row of `parameter`, if the ray depends on it.
    pub fn find(&self, parameter: Parameter) -> Option<usize> {
        self.parameters.iter().position(|&p| p == parameter)
    }

    /// Number of points per row (the ray's points: source, interactions, receiver).
    pub fn points(&self) -> usize {
        self.points
    }

    /// `d(points)/dθ` for the parameter of row `row`: one vector per point.
    ///
    /// # Panics
    /// If `row` is not below `parameters().len()`.
    pub fn row(&self, row: usize) -> &[Vec2] {
        &self.d[row * self.points..(row + 1) * self.points]
    }

    /// `d(point)/dθ` of point `point` for the parameter of row `row`.
    ///
    /// # Panics
    /// If `row` or `point` is out of range.
    pub fn d_point(&self, row: usize, point: usize) -> Vec2 {
        self.row(row)[point]
    }

    /// The sensitivities of the path through `points` by `steps` with leg media `media`
    /// (`segments`: each step's segment, a hint): the parameters, the legs, the tridiagonal
    /// system of the points' fractions along their segments, and one solve per parameter.
    fn fill(
        &mut self,
        scene: &Scene,
        steps: &[Step],
        points: &[Point],
        media: &[usize],
        segments: Option<&[usize]>,
    ) -> Result<(), DerivativeError> {
        // The implicit function theorem here takes straight legs' blocks.
        if scene.curved() {
            return Err(DerivativeError::CurvedLegs);
        }
        let sc = &mut self.scratch;
        sc.gradient
            .fill(scene, steps, points, media.iter().copied(), segments)?;
        let k = steps.len();
        let n = k + 2;
        fill_parameters(&mut self.parameters, scene, &sc.gradient.vertices);
        self.points = n;
        let vanish = sc.legs(scene, points, media, k);
        sc.locate_contacts(scene, steps, points, segments)?;
        sc.reset_system(k, n);
        sc.couplings(scene, steps, vanish);
        // One solve per parameter.
        self.d.clear();
        self.d.resize(self.parameters.len() * n, Vec2::default());
        for (row, &param) in self.parameters.iter().enumerate() {
            sc.solve_row(param, steps, &mut self.d[row * n..(row + 1) * n])?;
        }
        Ok(())
    }
}

/// Sets `parameters` to those a ray depends on, in the order of the rows: the source's and
/// the receiver's coordinates, every medium's slowness, and both coordinates of each of the
/// `vertices` the ray's gradient holds.
#[inline]
fn fill_parameters(parameters: &mut Vec<Parameter>, scene: &Scene, vertices: &[VertexGradient]) {
    parameters.clear();
    parameters.extend([
        Parameter::Source(Axis::X),
        Parameter::Source(Axis::Y),
        Parameter::Receiver(Axis::X),
        Parameter::Receiver(Axis::Y),
    ]);
    parameters.extend((0..scene.media().len()).map(|medium| Parameter::Slowness { medium }));
    for v in vertices {
        for axis in [Axis::X, Axis::Y] {
            parameters.push(Parameter::Vertex {
                interface: v.interface,
                vertex: v.vertex,
                axis,
            });
        }
    }
}

impl Scratch {
    /// Sets the legs of the path through `points` (`k` steps) with leg media `media`: each
    /// one's unit direction, length, slowness and medium. Returns the length below which a leg
    /// has vanished (relative to the path's length, and to round-off of its coordinates).
    #[inline]
    fn legs(&mut self, scene: &Scene, points: &[Point], media: &[usize], k: usize) -> f64 {
        self.u.clear();
        self.len.clear();
        self.w.clear();
        self.medium.clear();
        let mut total = 0.0;
        for j in 0..=k {
            let (u, l) = leg(points[j], points[j + 1]);
            self.u.push(u);
            self.len.push(l);
            self.w.push(scene.media()[media[j]].slowness);
            self.medium.push(media[j]);
            total += l;
        }
        let coord = points
            .iter()
            .fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
        crate::problem::vanish_threshold(total, coord)
    }

    /// Finds each step's point on its interface (`segments`: each step's segment, a hint).
    ///
    /// # Errors
    /// [`DerivativeError::OffInterface`] for the first point off its interface.
    #[inline]
    fn locate_contacts(
        &mut self,
        scene: &Scene,
        steps: &[Step],
        points: &[Point],
        segments: Option<&[usize]>,
    ) -> Result<(), DerivativeError> {
        self.contacts.clear();
        for (i, step) in steps.iter().enumerate() {
            let line = &scene.interfaces()[step.interface].polyline;
            let c = locate(line, points[i + 1], segments.map(|h| h[i]))
                .ok_or(DerivativeError::OffInterface { step: i })?;
            self.contacts.push(c);
        }
        Ok(())
    }

    /// Sizes the system of `k` interaction points (of `n` points in all) and zeroes it.
    #[inline]
    fn reset_system(&mut self, k: usize, n: usize) {
        for v in [
            &mut self.tan,
            &mut self.c_prev,
            &mut self.c_self,
            &mut self.c_next,
        ] {
            v.clear();
            v.resize(k, Vec2::default());
        }
        for v in [
            &mut self.turn,
            &mut self.diag,
            &mut self.rhs,
            &mut self.x,
            &mut self.cp,
        ] {
            v.clear();
            v.resize(k, 0.0);
        }
        self.off.clear();
        self.off.resize(k.saturating_sub(1), 0.0);
        self.held.clear();
        self.held.resize(k, false);
        self.moved.clear();
        self.moved.resize(n, Vec2::default());
    }

    /// The system's coefficients at each interaction point: whether it is held (on a vertex,
    /// or beside a leg shorter than `vanish`), its tangent, its residual's couplings to the
    /// previous, own and next point, its turn term, and the tridiagonal matrix.
    #[inline]
    fn couplings(&mut self, scene: &Scene, steps: &[Step], vanish: f64) {
        let project = |u: Vec2, v: Vec2| v - u * u.dot(v);
        for (i, step) in steps.iter().enumerate() {
            let line = &scene.interfaces()[step.interface].polyline;
            let c = self.contacts[i];
            let t = line.tangent(c.seg);
            self.tan[i] = t;
            let (ua, ub) = (self.u[i], self.u[i + 1]);
            let (la, lb) = (self.len[i], self.len[i + 1]);
            self.held[i] = c.at_vertex.is_some() || la <= vanish || lb <= vanish;
            if self.held[i] {
                self.diag[i] = 1.0;
                continue;
            }
            let (wa, wb) = (self.w[i], self.w[i + 1]);
            let pa = project(ua, t) * (wa / la);
            let pb = project(ub, t) * (wb / lb);
            self.c_prev[i] = -pa;
            self.c_self[i] = pa + pb;
            self.c_next[i] = -pb;
            self.diag[i] = t.dot(pa + pb);
            let g = ua * wa - ub * wb;
            self.turn[i] = g.dot(t.perp()) / line.segment_length(c.seg);
        }
        for i in 0..steps.len().saturating_sub(1) {
            if !self.held[i] && !self.held[i + 1] {
                self.off[i] = self.tan[i + 1].dot(self.c_next[i]);
            }
        }
    }

    /// Solves for the row of `param`: how it moves the ray's points (`out`, one per point),
    /// at fixed fractions along their segments and then along the tangents by the system's
    /// solution.
    ///
    /// # Errors
    /// [`DerivativeError::Singular`] when the system has no solution (a caustic).
    #[inline]
    fn solve_row(
        &mut self,
        param: Parameter,
        steps: &[Step],
        out: &mut [Vec2],
    ) -> Result<(), DerivativeError> {
        let sc = self;
        let k = steps.len();
        let n = k + 2;
        let moved = &mut sc.moved;
        moved.fill(Vec2::default());
        let (mut dw_medium, mut vertex) = (None, None);
        match param {
            Parameter::Source(axis) => moved[0] = axis.unit(),
            Parameter::Receiver(axis) => moved[n - 1] = axis.unit(),
            Parameter::Slowness { medium } => dw_medium = Some(medium),
            Parameter::Vertex {
                interface,
                vertex: v,
                axis,
            } => {
                vertex = Some((interface, v, axis.unit()));
                for (i, step) in steps.iter().enumerate() {
                    if step.interface != interface {
                        continue;
                    }
                    let c = sc.contacts[i];
                    moved[i + 1] = match c.at_vertex {
                        Some(at) if at == v => axis.unit(),
                        Some(_) => Vec2::default(),
                        None if c.a == v => axis.unit() * (1.0 - c.lambda),
                        None if c.b == v => axis.unit() * c.lambda,
                        None => Vec2::default(),
                    };
                }
            }
        }
        let dw = |j: usize| -> f64 {
            if dw_medium == Some(sc.medium[j]) {
                1.0
            } else {
                0.0
            }
        };
        for i in 0..k {
            if sc.held[i] {
                sc.rhs[i] = 0.0;
                continue;
            }
            let t = sc.tan[i];
            let mut b = sc.c_prev[i].dot(moved[i])
                + sc.c_self[i].dot(moved[i + 1])
                + sc.c_next[i].dot(moved[i + 2])
                + dw(i) * t.dot(sc.u[i])
                - dw(i + 1) * t.dot(sc.u[i + 1]);
            if let Some((interface, v, e)) = vertex
                && steps[i].interface == interface
            {
                let c = sc.contacts[i];
                let turn_by = if c.b == v { e } else { Vec2::default() }
                    - if c.a == v { e } else { Vec2::default() };
                b += sc.turn[i] * t.perp().dot(turn_by);
            }
            sc.rhs[i] = b;
        }
        if !thomas(&sc.diag, &sc.off, &sc.rhs, &mut sc.x, &mut sc.cp) {
            return Err(DerivativeError::Singular);
        }
        out.copy_from_slice(moved);
        for i in 0..k {
            if !sc.held[i] {
                out[i + 1] += sc.tan[i] * -sc.x[i];
            }
        }
        Ok(())
    }
}

impl Tracer {
    /// The [`Gradient`] of the ray of path `path` last solved in `ws` (see
    /// [`Gradient::of_solved`]).
    ///
    /// # Errors
    /// See [`DerivativeError`].
    pub fn gradient(&self, path: usize, ws: &Workspace) -> Result<Gradient, DerivativeError> {
        Gradient::of_solved(self.scene(), path, ws)
    }

    /// Solves path `path` between two points as [`solve`](Self::solve) does, and puts the
    /// ray's [`Gradient`] in `gradient`, reusing its memory: the call of a layout loop. A ray
    /// without a time leaves NaN in `gradient`'s source, receiver and slownesses, and no
    /// vertices. The gradient is [`Gradient::of_solved`]'s, bit for bit; a refraction at an
    /// interface of one segment (the flat kernel's plan) skips finding its point on the
    /// interface, which the solve already knows.
    ///
    /// # Errors
    /// See [`DerivativeError`] (none for the rays of the solve, whose points lie on their
    /// interfaces).
    ///
    /// # Panics
    /// As [`solve`](Self::solve).
    pub fn solve_with_gradient(
        &self,
        source: Point,
        receiver: Point,
        path: usize,
        ws: &mut Workspace,
        gradient: &mut Gradient,
    ) -> Result<RayRecord, DerivativeError> {
        let record = self.solve(source, receiver, path, ws);
        let scene = self.scene();
        let media = scene.media().len();
        if !record.status.has_time() {
            gradient.set_none(media);
            return Ok(record);
        }
        if let Some(segment) = self.flat_segment(path)
            && let (&[p0, p1, p2], &[m0, m1]) = (ws.points(), ws.media())
        {
            gradient.size_slowness(scene);
            let interface = scene.paths()[path].steps[0].interface;
            gradient.fill_flat(scene, interface, &segment, [p0, p1, p2], [m0, m1])?;
        } else {
            gradient.solved_into(scene, path, ws)?;
        }
        Ok(record)
    }

    /// The [`PointSensitivities`] of the ray of path `path` last solved in `ws`.
    ///
    /// # Errors
    /// See [`DerivativeError`].
    pub fn point_sensitivities(
        &self,
        path: usize,
        ws: &Workspace,
    ) -> Result<PointSensitivities, DerivativeError> {
        PointSensitivities::of_solved(self.scene(), path, ws)
    }
}

/// The gradients of a [`Batch`]'s rays in flat arrays: per ray the source's and receiver's
/// gradients, one `dT/dw` per medium of the scene, and room for `2 × K` vertex gradients (`K`
/// the most steps of a path), of which [`vertices`](Self::vertices) gives the ray's own.
/// A ray without a time, or not asked for, has NaN gradients and no vertices.
///
/// ```
/// use eigenray::derivatives::BatchGradients;
/// use eigenray::{BatchOptions, Scene, Tracer};
/// let scene = Scene::from_spec(&eigenray::demo::air_water(100, 7)).unwrap();
/// let tracer = Tracer::new(&scene).unwrap();
/// let run = eigenray::options::Run::new();
/// let batch = tracer.trace_batch(&BatchOptions::default(), &run).unwrap();
/// let mut gradients = BatchGradients::default();
/// gradients.compute(&scene, &batch, &|_ray| true);
/// assert_eq!(gradients.len(), 100);
/// assert!(gradients.source(0).x.is_finite());
/// assert_eq!(gradients.slowness(0).len(), scene.media().len());
/// ```
#[derive(Clone, Debug, Default)]
pub struct BatchGradients {
    media: usize,
    slots: usize,
    source: Vec<Vec2>,
    receiver: Vec<Vec2>,
    slowness: Vec<f64>,
    vertices: Vec<VertexGradient>,
    counts: Vec<u32>,
}

/// Rays per parallel piece of [`BatchGradients::compute`] and [`GradientRows::gradients_into`].
const GRADIENT_PIECE: usize = 1024;

/// The flat arrays of a [`BatchGradients`] ([`BatchGradients::arrays`]), one row per ray.
#[derive(Clone, Copy, Debug)]
pub struct BatchGradientArrays<'a> {
    /// `(dT/dx, dT/dy)` of each ray's source (NaN without a gradient).
    pub source: &'a [Vec2],
    /// `(dT/dx, dT/dy)` of each ray's receiver.
    pub receiver: &'a [Vec2],
    /// `dT/dw` of each medium, [`BatchGradients::media`] per ray.
    pub slowness: &'a [f64],
    /// Vertex gradients, [`BatchGradients::slots`] per ray, the ray's own first.
    pub vertices: &'a [VertexGradient],
}

impl BatchGradients {
    /// Number of rays.
    pub fn len(&self) -> usize {
        self.counts.len()
    }
    /// Whether there are no rays.
    pub fn is_empty(&self) -> bool {
        self.counts.is_empty()
    }
    /// Whether ray `ray` has a gradient (it has a time and was asked for).
    pub fn has(&self, ray: usize) -> bool {
        self.counts[ray] != u32::MAX
    }
    /// `(dT/dx, dT/dy)` of ray `ray`'s source (NaN when it has no gradient).
    pub fn source(&self, ray: usize) -> Vec2 {
        self.source[ray]
    }
    /// `(dT/dx, dT/dy)` of ray `ray`'s receiver (NaN when it has no gradient).
    pub fn receiver(&self, ray: usize) -> Vec2 {
        self.receiver[ray]
    }
    /// `dT/dw` of each medium for ray `ray`, in the order of [`Scene::media`].
    pub fn slowness(&self, ray: usize) -> &[f64] {
        &self.slowness[ray * self.media..(ray + 1) * self.media]
    }
    /// The vertex gradients of ray `ray` (ordered by interface and vertex, each vertex once).
    pub fn vertices(&self, ray: usize) -> &[VertexGradient] {
        let n = if self.has(ray) {
            self.counts[ray] as usize
        } else {
            0
        };
        &self.vertices[ray * self.slots..ray * self.slots + n]
    }
    /// Ray `ray`'s gradient as an owned [`Gradient`], when it has one.
    pub fn gradient(&self, ray: usize) -> Option<Gradient> {
        self.has(ray).then(|| Gradient {
            source: self.source(ray),
            receiver: self.receiver(ray),
            slowness: self.slowness(ray).to_vec(),
            vertices: self.vertices(ray).to_vec(),
            // The batch's arrays hold no speed gradients.
            speed_gradient: Vec::new(),
            profile_speed: Vec::new(),
        })
    }
    /// The flat arrays: sources' and receivers' gradients (one per ray), slowness gradients
    /// (`media` per ray, see [`media`](Self::media)), vertex gradients (`slots` per ray, see
    /// [`slots`](Self::slots); the ray's own first, [`count`](Self::count) of them).
    pub fn arrays(&self) -> BatchGradientArrays<'_> {
        BatchGradientArrays {
            source: &self.source,
            receiver: &self.receiver,
            slowness: &self.slowness,
            vertices: &self.vertices,
        }
    }
    /// Slowness gradients per ray (the scene's media).
    pub fn media(&self) -> usize {
        self.media
    }
    /// Vertex slots per ray (twice the most steps of a path).
    pub fn slots(&self) -> usize {
        self.slots
    }
    /// Vertex gradients of ray `ray` (0 without a gradient).
    pub fn count(&self, ray: usize) -> usize {
        self.vertices(ray).len()
    }

    /// Computes the gradients of `batch`'s rays (of `scene`) for which `wanted(ray)` holds, in
    /// parallel (rayon), reusing this value's arrays (they grow only for a larger batch, or a
    /// scene of more media or longer paths). A ray that is not wanted costs nothing but its NaN
    /// entries.
    pub fn compute(
        &mut self,
        scene: &Scene,
        batch: &Batch,
        wanted: &(dyn Fn(usize) -> bool + Sync),
    ) {
        let n = batch.len();
        let media = scene.media().len();
        let slots = GradientArraysMut::slots(scene);
        self.media = media;
        self.slots = slots;
        let nan = Vec2::new(f64::NAN, f64::NAN);
        for v in [&mut self.source, &mut self.receiver] {
            v.clear();
            v.resize(n, nan);
        }
        self.slowness.clear();
        self.slowness.resize(n * media, f64::NAN);
        self.vertices.clear();
        self.vertices.resize(n * slots, VertexGradient::default());
        self.counts.clear();
        self.counts.resize(n, u32::MAX);
        let count = n.div_ceil(GRADIENT_PIECE);
        let pieces = row_pieces(&mut self.source, 1, count)
            .zip(row_pieces(&mut self.receiver, 1, count))
            .zip(row_pieces(&mut self.slowness, media, count))
            .zip(row_pieces(&mut self.vertices, slots, count))
            .zip(row_pieces(&mut self.counts, 1, count))
            .map(
                |((((source, receiver), slowness), vertices), counts)| BatchPiece {
                    media,
                    slots,
                    source,
                    receiver,
                    slowness,
                    vertices,
                    counts,
                },
            )
            .collect();
        gradients_in_pieces(pieces, |rays, piece| {
            let first = rays.start;
            for ray in rays {
                let row = ray - first;
                if !(batch.record(ray).status.has_time() && wanted(ray)) {
                    piece.store_none(row);
                    continue;
                }
                let path = batch.triple(ray).path;
                let steps = &scene.paths()[path].steps;
                let Some(media) = batch.media(ray) else {
                    piece.store_none(row);
                    continue;
                };
                store_gradient(scene, piece, row, steps, batch.points(ray), media);
            }
        });
    }
}

/// Rays given as flat rows (the arrays of the Python package's `Rays`), whose gradients
/// [`gradients_into`](Self::gradients_into) computes: `n` rays, row `i` of every array ray
/// `i`'s.
#[derive(Clone, Copy, Debug)]
pub struct GradientRows<'a> {
    /// Path index of each ray (`n` entries).
    pub paths: &'a [i64],
    /// Status code of each ray (`n` entries): an index into `status_of_code`.
    pub statuses: &'a [u8],
    /// The status of each code (the `.npy` output's codes:
    /// `output::STATUS_CODES`).
    pub status_of_code: &'a [Status],
    /// Points a row holds (`width − 1` legs).
    pub width: usize,
    /// Source, interaction points and receiver of each ray, `(x, y)` each, `width` points a
    /// row (`n × width × 2` entries), the ray's own first.
    pub points: &'a [f64],
    /// How many of a row's points are the ray's own (`n` entries).
    pub num_points: &'a [i64],
    /// Leg media, `width − 1` a row (indices into [`Scene::media`]; negative where unknown).
    pub media: &'a [i32],
    /// Each ray's direction at its source (its `launch_angle`; `n` entries, NaN where
    /// unknown), where the rows carry one: which of the rays between the same points through
    /// a `profile` medium a row is. Without it such a row is the default mode's ray.
    pub launch_angles: Option<&'a [f64]>,
}

/// Where [`GradientRows::gradients_into`] writes: flat arrays of `n` rows, every entry
/// written. `slots` below is [`GradientArraysMut::slots`] of the scene.
#[derive(Debug)]
pub struct GradientArraysMut<'a> {
    /// `(dT/dx, dT/dy)` of each ray's source (`n × 2` entries).
    pub source: &'a mut [f64],
    /// `(dT/dx, dT/dy)` of each ray's receiver (`n × 2` entries).
    pub receiver: &'a mut [f64],
    /// `dT/dw` of each medium, in the order of [`Scene::media`] (`n × media` entries).
    pub slowness: &'a mut [f64],
    /// The interface of each vertex gradient, the ray's own first (ordered by interface and
    /// vertex, each vertex once), −1 past them (`n × slots` entries).
    pub vertex_interface: &'a mut [i32],
    /// The vertex's index in its interface's points, −1 past the ray's own (`n × slots`).
    pub vertex: &'a mut [i32],
    /// `(dT/dx, dT/dy)` of that vertex, NaN past the ray's own (`n × slots × 2` entries).
    pub vertex_d: &'a mut [f64],
    /// `(dT/dgx, dT/dgy)` of each medium's speed gradient, in the order of [`Scene::media`]
    /// (`n × media × 2` entries in a scene with a `gradient` medium, zero for a medium
    /// without one; empty in other scenes: see [`GradientArraysMut::speed_gradient_width`]).
    pub speed_gradient: &'a mut [f64],
    /// `dT/dc` of each knot of each `profile` medium, the media in the order of
    /// [`Scene::media`] and each one's knots in its profile's order (`n × knots` entries,
    /// see [`GradientArraysMut::profile_speed_width`]; empty in a scene without a profile).
    pub profile_speed: &'a mut [f64],
}

impl GradientArraysMut<'_> {
    /// Vertex gradients a row has room for, for rays of `scene`: twice the most steps of a
    /// path (a point between two vertices moves both).
    pub fn slots(scene: &Scene) -> usize {
        2 * scene
            .paths()
            .iter()
            .map(|p| p.steps.len())
            .max()
            .unwrap_or(0)
    }

    /// Entries a row of [`speed_gradient`](Self::speed_gradient) has for rays of `scene`:
    /// two per medium in a scene with a `gradient` medium, else none.
    pub fn speed_gradient_width(scene: &Scene) -> usize {
        if has_gradient(scene) {
            2 * scene.media().len()
        } else {
            0
        }
    }

    /// Entries a row of [`profile_speed`](Self::profile_speed) has for rays of `scene`: the
    /// knots of all its `profile` media (none without one).
    pub fn profile_speed_width(scene: &Scene) -> usize {
        if !has_profile(scene) {
            return 0;
        }
        scene
            .media()
            .iter()
            .map(|m| m.profile.as_ref().map_or(0, Vec::len))
            .sum()
    }
}

impl GradientRows<'_> {
    /// Computes the gradient of every ray into `out`, in parallel (rayon), the same numbers
    /// as [`Gradient::points_into`] and [`BatchGradients::compute`]. A ray gets NaN gradients
    /// and no vertices (−1) when its status has no time, its path index is not one of
    /// `scene`'s, its point count is not its path's (or more than `width`), or a leg medium is
    /// unknown.
    ///
    /// # Panics
    /// When the arrays' lengths do not agree with `paths`' (see the fields' documentation).
    pub fn gradients_into(&self, scene: &Scene, out: GradientArraysMut<'_>) {
        let n = self.paths.len();
        let (media, slots) = (scene.media().len(), GradientArraysMut::slots(scene));
        let sg_width = GradientArraysMut::speed_gradient_width(scene);
        let ps_width = GradientArraysMut::profile_speed_width(scene);
        assert!(
            self.statuses.len() == n
                && self.num_points.len() == n
                && self.points.len() == n * self.width * 2
                && self.media.len() == n * self.width.saturating_sub(1)
                && self.launch_angles.is_none_or(|a| a.len() == n),
            "gradient rows of different lengths"
        );
        assert!(
            out.source.len() == 2 * n
                && out.receiver.len() == 2 * n
                && out.slowness.len() == n * media
                && out.vertex_interface.len() == n * slots
                && out.vertex.len() == n * slots
                && out.vertex_d.len() == 2 * n * slots
                && out.speed_gradient.len() == n * sg_width
                && out.profile_speed.len() == n * ps_width,
            "gradient arrays of other lengths than the rows"
        );
        let count = n.div_ceil(GRADIENT_PIECE);
        let pieces = row_pieces(out.source, 2, count)
            .zip(row_pieces(out.receiver, 2, count))
            .zip(row_pieces(out.slowness, media, count))
            .zip(row_pieces(out.vertex_interface, slots, count))
            .zip(row_pieces(out.vertex, slots, count))
            .zip(row_pieces(out.vertex_d, 2 * slots, count))
            .zip(row_pieces(out.speed_gradient, sg_width, count))
            .zip(row_pieces(out.profile_speed, ps_width, count))
            .map(
                |(
                    ((((((source, receiver), slowness), vertex_interface), vertex), vertex_d), sg),
                    ps,
                )| RowsPiece {
                    media,
                    slots,
                    source,
                    receiver,
                    slowness,
                    vertex_interface,
                    vertex,
                    vertex_d,
                    speed_gradient: sg,
                    profile_speed: ps,
                    widths: [sg_width, ps_width],
                    room: vec![VertexGradient::default(); slots],
                },
            )
            .collect();
        if scene.curved() {
            return self.curved_gradients_into(scene, pieces);
        }
        gradients_in_pieces(pieces, |rays, piece| {
            let first = rays.start;
            let mut points = Vec::new();
            for ray in rays {
                match self.ray(scene, ray, &mut points) {
                    Some(path) => {
                        let (steps, media) = (path.steps, path.media);
                        store_gradient(scene, piece, ray - first, steps, path.points, media);
                    }
                    None => piece.store_none(ray - first),
                }
            }
        });
    }

    /// [`gradients_into`](Self::gradients_into) in a scene with curved legs: each row as
    /// [`Gradient::of_arrival`] computes it (the ray of the row's launch angle through a
    /// profile), with its speed gradients and knots' derivatives.
    fn curved_gradients_into(&self, scene: &Scene, pieces: Vec<RowsPiece<'_>>) {
        gradients_in_pieces(pieces, |rays, piece| {
            let first = rays.start;
            let (mut points, mut gradient) = (Vec::new(), Gradient::default());
            for ray in rays {
                let row = ray - first;
                let launch = self.launch_angles.map(|a| a[ray]).filter(|a| a.is_finite());
                let filled = self.ray(scene, ray, &mut points).map(|path| {
                    let (steps, media) = (path.steps, path.media);
                    gradient.fill_at(scene, steps, path.points, media, None, launch)
                });
                match filled {
                    Some(Ok(())) => piece.store_curved(row, &gradient),
                    _ => piece.store_none(row),
                }
            }
        });
    }

    /// Ray `ray`, when it has a time and its points and leg media fit its path (`points` holds
    /// its points).
    fn ray<'s>(
        &'s self,
        scene: &'s Scene,
        ray: usize,
        points: &'s mut Vec<Point>,
    ) -> Option<RayPath<'s, impl Iterator<Item = usize> + 's>> {
        let timed = (self.status_of_code)
            .get(usize::from(self.statuses[ray]))
            .is_some_and(|s| s.has_time());
        let path = usize::try_from(self.paths[ray]).ok();
        let steps = &path
            .and_then(|p| scene.paths().get(p))
            .filter(|_| timed)?
            .steps;
        let count = steps.len() + 2;
        if usize::try_from(self.num_points[ray]) != Ok(count) || count > self.width {
            return None;
        }
        let xy = &self.points[2 * ray * self.width..][..2 * count];
        points.clear();
        points.extend(xy.chunks_exact(2).map(|p| Point::new(p[0], p[1])));
        let legs = &self.media[ray * (self.width - 1)..][..count - 1];
        // An unknown medium (negative) is out of range: no gradient.
        let media = legs
            .iter()
            .map(|&m| usize::try_from(m).unwrap_or(usize::MAX));
        Some(RayPath {
            steps,
            points,
            media,
        })
    }
}

/// `v`, rows of `width` entries, cut into `pieces` pieces of [`GRADIENT_PIECE`] rows (the
/// last shorter; all empty when `width` is 0, so that they still pair up with the pieces of
/// other arrays).
fn row_pieces<T>(v: &mut [T], width: usize, pieces: usize) -> impl Iterator<Item = &mut [T]> {
    let len = GRADIENT_PIECE * width;
    let mut rest = v;
    (0..pieces).map(move |_| {
        let all = std::mem::take(&mut rest);
        let (piece, after) = all.split_at_mut(len.min(all.len()));
        rest = after;
        piece
    })
}

/// One ray as a gradient reads it: its path's steps, its points and its leg media.
struct RayPath<'s, M> {
    /// The steps of its path.
    steps: &'s [Step],
    /// Source, interaction points and receiver.
    points: &'s [Point],
    /// Leg media.
    media: M,
}

/// One piece of the arrays of many gradients, written row by row.
trait GradientPiece: Send {
    /// Rows of the piece.
    fn rows(&self) -> usize;
    /// Row `row`'s slowness entries and room for its vertex shares.
    fn row(&mut self, row: usize) -> RowRoom<'_>;
    /// Row `row` has a gradient: `ends`, its slowness entries, and `count` vertex gradients at
    /// the front of its room.
    fn store(&mut self, row: usize, ends: EndGradients, count: usize);
    /// Row `row` has no gradient (its slowness entries may hold a partial one).
    fn store_none(&mut self, row: usize);
}

/// A row's slowness entries and room for its vertex shares (at least `2 × steps`).
struct RowRoom<'r> {
    /// One per medium.
    slowness: &'r mut [f64],
    /// The row's vertex shares, merged in place.
    vertices: &'r mut [VertexGradient],
}

/// Fills `pieces` in parallel, `fill(rays, piece)` the rows of rays `rays` (piece `p` holds
/// rays `p × GRADIENT_PIECE` on): the core of [`BatchGradients::compute`] and
/// [`GradientRows::gradients_into`], with [`store_gradient`] for each ray.
fn gradients_in_pieces<P: GradientPiece>(
    pieces: Vec<P>,
    fill: impl Fn(std::ops::Range<usize>, &mut P) + Sync,
) {
    pieces
        .into_par_iter()
        .enumerate()
        .for_each(|(p, mut piece)| {
            let first = p * GRADIENT_PIECE;
            fill(first..first + piece.rows(), &mut piece);
        });
}

/// Row `row` of `piece`: the gradient of the ray through `points` by `steps` with leg media
/// `media`, or none when they do not make one.
#[inline(always)]
fn store_gradient<P: GradientPiece>(
    scene: &Scene,
    piece: &mut P,
    row: usize,
    steps: &[Step],
    points: &[Point],
    media: impl Iterator<Item = usize>,
) {
    let room = piece.row(row);
    let vertices = &mut room.vertices[..2 * steps.len()];
    let mut used = 0;
    let parts = gradient_parts(scene, steps, points, media, None, room.slowness, |v| {
        vertices[used] = v;
        used += 1;
    });
    match parts {
        Ok(ends) => {
            let count = merge(&mut vertices[..used]);
            piece.store(row, ends, count);
        }
        Err(_) => piece.store_none(row),
    }
}

/// The pieces of a [`BatchGradients`]' arrays.
struct BatchPiece<'a> {
    /// Slowness entries a row.
    media: usize,
    /// Vertex slots a row.
    slots: usize,
    /// The sources' gradients.
    source: &'a mut [Vec2],
    /// The receivers' gradients.
    receiver: &'a mut [Vec2],
    /// `media` a row.
    slowness: &'a mut [f64],
    /// `slots` a row.
    vertices: &'a mut [VertexGradient],
    /// Each row's vertex gradients (`u32::MAX` without a gradient: set before).
    counts: &'a mut [u32],
}

impl GradientPiece for BatchPiece<'_> {
    fn rows(&self) -> usize {
        self.counts.len()
    }

    fn row(&mut self, row: usize) -> RowRoom<'_> {
        let (media, slots) = (self.media, self.slots);
        RowRoom {
            slowness: &mut self.slowness[row * media..(row + 1) * media],
            vertices: &mut self.vertices[row * slots..(row + 1) * slots],
        }
    }

    fn store(&mut self, row: usize, ends: EndGradients, count: usize) {
        self.source[row] = ends.source;
        self.receiver[row] = ends.receiver;
        self.counts[row] = count as u32;
    }

    fn store_none(&mut self, row: usize) {
        // Everything else holds its value without a gradient already.
        self.slowness[row * self.media..(row + 1) * self.media].fill(f64::NAN);
    }
}

/// The pieces of the arrays of [`GradientArraysMut`].
struct RowsPiece<'a> {
    /// Slowness entries a row.
    media: usize,
    /// Vertex slots a row.
    slots: usize,
    /// `2` a row.
    source: &'a mut [f64],
    /// `2` a row.
    receiver: &'a mut [f64],
    /// `media` a row.
    slowness: &'a mut [f64],
    /// `slots` a row.
    vertex_interface: &'a mut [i32],
    /// `slots` a row.
    vertex: &'a mut [i32],
    /// `2 × slots` a row.
    vertex_d: &'a mut [f64],
    /// `widths[0]` a row.
    speed_gradient: &'a mut [f64],
    /// `widths[1]` a row.
    profile_speed: &'a mut [f64],
    /// Entries a row of `speed_gradient` and of `profile_speed`.
    widths: [usize; 2],
    /// Room for one row's vertex shares (`slots`).
    room: Vec<VertexGradient>,
}

impl RowsPiece<'_> {
    /// Row `row` holds `g`, a gradient of a ray with curved legs: [`store`](GradientPiece::store)
    /// of its parts, its speed gradients and its knots' derivatives.
    fn store_curved(&mut self, row: usize, g: &Gradient) {
        let media = self.media;
        self.slowness[row * media..(row + 1) * media].copy_from_slice(&g.slowness);
        let count = g.vertices.len().min(self.slots);
        self.room[..count].copy_from_slice(&g.vertices[..count]);
        let ends = EndGradients {
            source: g.source,
            receiver: g.receiver,
        };
        self.store(row, ends, count);
        let [sg_width, ps_width] = self.widths;
        let sg = &mut self.speed_gradient[row * sg_width..(row + 1) * sg_width];
        sg.fill(0.0);
        for (d, v) in sg.chunks_exact_mut(2).zip(&g.speed_gradient) {
            d.copy_from_slice(&[v.x, v.y]);
        }
        let ps = &mut self.profile_speed[row * ps_width..(row + 1) * ps_width];
        ps.fill(0.0);
        // (One entry per medium, each as long as its profile: their concatenation.)
        let mut at = 0;
        for knots in &g.profile_speed {
            if let Some(d) = ps.get_mut(at..at + knots.len()) {
                d.copy_from_slice(knots);
            }
            at += knots.len();
        }
    }
}

impl GradientPiece for RowsPiece<'_> {
    fn rows(&self) -> usize {
        self.source.len() / 2
    }

    fn row(&mut self, row: usize) -> RowRoom<'_> {
        let media = self.media;
        RowRoom {
            slowness: &mut self.slowness[row * media..(row + 1) * media],
            vertices: &mut self.room,
        }
    }

    fn store(&mut self, row: usize, ends: EndGradients, count: usize) {
        let (s, r) = (ends.source, ends.receiver);
        self.source[2 * row..2 * row + 2].copy_from_slice(&[s.x, s.y]);
        self.receiver[2 * row..2 * row + 2].copy_from_slice(&[r.x, r.y]);
        let slots = self.slots;
        let interfaces = &mut self.vertex_interface[row * slots..(row + 1) * slots];
        let vertices = &mut self.vertex[row * slots..(row + 1) * slots];
        let ds = &mut self.vertex_d[2 * row * slots..2 * (row + 1) * slots];
        for (slot, v) in self.room[..count].iter().enumerate() {
            interfaces[slot] = i32::try_from(v.interface).unwrap_or(-1);
            vertices[slot] = i32::try_from(v.vertex).unwrap_or(-1);
            ds[2 * slot..2 * slot + 2].copy_from_slice(&[v.d.x, v.d.y]);
        }
        interfaces[count..].fill(-1);
        vertices[count..].fill(-1);
        ds[2 * count..].fill(f64::NAN);
    }

    fn store_none(&mut self, row: usize) {
        let (media, slots) = (self.media, self.slots);
        self.source[2 * row..2 * row + 2].fill(f64::NAN);
        self.receiver[2 * row..2 * row + 2].fill(f64::NAN);
        self.slowness[row * media..(row + 1) * media].fill(f64::NAN);
        self.vertex_interface[row * slots..(row + 1) * slots].fill(-1);
        self.vertex[row * slots..(row + 1) * slots].fill(-1);
        self.vertex_d[2 * row * slots..2 * (row + 1) * slots].fill(f64::NAN);
        let [sg, ps] = self.widths;
        self.speed_gradient[row * sg..(row + 1) * sg].fill(f64::NAN);
        self.profile_speed[row * ps..(row + 1) * ps].fill(f64::NAN);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BatchOptions, demo};

    /// Status codes as the `.npy` output numbers them (the test may use any module).
    const CODES: [Status; 5] = crate::output::STATUS_CODES;

    /// A batch's rays as flat rows (as the Python package's `Rays` holds them).
    struct FlatRays {
        paths: Vec<i64>,
        statuses: Vec<u8>,
        width: usize,
        points: Vec<f64>,
        num_points: Vec<i64>,
        media: Vec<i32>,
    }

    impl FlatRays {
        fn of(scene: &Scene, batch: &Batch) -> FlatRays {
            let width = 2 + scene.paths().iter().map(|p| p.steps.len()).max().unwrap();
            let mut rays = FlatRays {
                paths: Vec::new(),
                statuses: Vec::new(),
                width,
                points: Vec::new(),
                num_points: Vec::new(),
                media: Vec::new(),
            };
            for ray in 0..batch.len() {
                let path = batch.triple(ray).path;
                let status = batch.record(ray).status;
                rays.paths.push(path as i64);
                rays.statuses
                    .push(CODES.iter().position(|&s| s == status).unwrap() as u8);
                let points = batch.points(ray);
                rays.num_points.push(points.len() as i64);
                let xy = points.iter().flat_map(|p| [p.x, p.y]);
                rays.points.extend(xy.chain([f64::NAN; 64]).take(2 * width));
                let legs = batch.media(ray).into_iter().flatten().map(|m| m as i32);
                rays.media.extend(legs.chain([-1; 32]).take(width - 1));
            }
            rays
        }

        fn rows(&self) -> GradientRows<'_> {
            GradientRows {
                paths: &self.paths,
                statuses: &self.statuses,
                status_of_code: &CODES,
                width: self.width,
                points: &self.points,
                num_points: &self.num_points,
                media: &self.media,
                launch_angles: None,
            }
        }
    }

    /// The arrays of [`GradientArraysMut`], filled with a value no gradient has (so that an
    /// entry left unwritten shows).
    struct Arrays {
        source: Vec<f64>,
        receiver: Vec<f64>,
        slowness: Vec<f64>,
        vertex_interface: Vec<i32>,
        vertex: Vec<i32>,
        vertex_d: Vec<f64>,
        speed_gradient: Vec<f64>,
        profile_speed: Vec<f64>,
    }

    impl Arrays {
        fn of(scene: &Scene, rows: &GradientRows<'_>) -> Arrays {
            let n = rows.paths.len();
            let slots = GradientArraysMut::slots(scene);
            let mut a = Arrays {
                source: vec![7.5; 2 * n],
                receiver: vec![7.5; 2 * n],
                slowness: vec![7.5; n * scene.media().len()],
                vertex_interface: vec![99; n * slots],
                vertex: vec![99; n * slots],
                vertex_d: vec![7.5; 2 * n * slots],
                speed_gradient: vec![7.5; n * GradientArraysMut::speed_gradient_width(scene)],
                profile_speed: vec![7.5; n * GradientArraysMut::profile_speed_width(scene)],
            };
            rows.gradients_into(
                scene,
                GradientArraysMut {
                    source: &mut a.source,
                    receiver: &mut a.receiver,
                    slowness: &mut a.slowness,
                    vertex_interface: &mut a.vertex_interface,
                    vertex: &mut a.vertex,
                    vertex_d: &mut a.vertex_d,
                    speed_gradient: &mut a.speed_gradient,
                    profile_speed: &mut a.profile_speed,
                },
            );
            a
        }
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    /// Row `ray` of `a` holds `g`'s gradient of that ray bit for bit, or NaN and −1 without one.
    fn assert_row_is(a: &Arrays, g: &BatchGradients, ray: usize) {
        let (m, slots) = (g.media(), g.slots());
        let (s, r) = (g.source(ray), g.receiver(ray));
        assert_eq!(
            bits(&a.source[2 * ray..2 * ray + 2]),
            bits(&[s.x, s.y]),
            "{ray}"
        );
        assert_eq!(bits(&a.receiver[2 * ray..2 * ray + 2]), bits(&[r.x, r.y]));
        assert_eq!(
            bits(&a.slowness[m * ray..m * (ray + 1)]),
            bits(g.slowness(ray))
        );
        let own = g.vertices(ray);
        for slot in 0..slots {
            let at = slots * ray + slot;
            let d = &a.vertex_d[2 * at..2 * at + 2];
            match own.get(slot) {
                Some(v) => {
                    assert_eq!(a.vertex_interface[at], v.interface as i32);
                    assert_eq!(a.vertex[at], v.vertex as i32);
                    assert_eq!(bits(d), bits(&[v.d.x, v.d.y]));
                }
                None => {
                    assert_eq!((a.vertex_interface[at], a.vertex[at]), (-1, -1));
                    assert!(d.iter().all(|x| x.is_nan()));
                }
            }
        }
    }

    /// Scenes of one refraction (more rays than a parallel piece), flat and dipping layers,
    /// the fixtures' cases (vertex paths, two bounces, rays without a time) and a direct path
    /// alone (no vertex slots).
    fn scenes() -> Vec<Scene> {
        let mut scenes = vec![
            Scene::from_spec(&demo::air_water(2500, 3)).unwrap(),
            Scene::from_spec(&demo::layer_stack(4, 50)).unwrap(),
            Scene::from_spec(&demo::dipping_stack(3, 40)).unwrap(),
            Scene::from_json(
                r#"{ "media": { "air": { "speed": 2.0 } },
                "interfaces": { "floor": { "points": [[-3, 0], [3, 0]] } },
                "sources": [[0, 1]], "receivers": [[1, 1], [2, 3]],
                "paths": [{ "steps": [], "media": ["air"] }] }"#,
            )
            .unwrap(),
        ];
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/cases");
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            let name = path.to_string_lossy().into_owned();
            if name.ends_with(".json") && !name.ends_with(".expected.json") {
                scenes.push(Scene::from_json(&std::fs::read_to_string(&path).unwrap()).unwrap());
            }
        }
        scenes
    }

    #[test]
    fn gradients_of_rows_are_the_batch_gradients_bit_for_bit() {
        let (mut rays, mut with_gradient) = (0, 0);
        let mut gradients = BatchGradients::default();
        for scene in scenes() {
            let batch = Tracer::new(&scene)
                .unwrap()
                .trace_batch(&BatchOptions::default(), &crate::options::Run::new())
                .unwrap();
            gradients.compute(&scene, &batch, &|_| true);
            let flat = FlatRays::of(&scene, &batch);
            let arrays = Arrays::of(&scene, &flat.rows());
            for ray in 0..batch.len() {
                assert_row_is(&arrays, &gradients, ray);
                rays += 1;
                with_gradient += usize::from(gradients.has(ray));
            }
        }
        assert!(
            rays > 2600 && with_gradient > 2550,
            "{rays} rays, {with_gradient}"
        );
    }

    #[test]
    fn rows_that_do_not_fit_their_path_have_no_gradient() {
        let scene = Scene::from_spec(&demo::layer_stack(3, 6)).unwrap();
        let batch = Tracer::new(&scene)
            .unwrap()
            .trace_batch(&BatchOptions::default(), &crate::options::Run::new())
            .unwrap();
        let mut flat = FlatRays::of(&scene, &batch);
        let legs = flat.width - 1;
        flat.media[legs + 1] = -1; // ray 1: a leg medium unknown
        flat.num_points[2] -= 1; // ray 2: a point short
        flat.paths[3] = 7; // ray 3: no such path
        flat.statuses[4] = 2; // ray 4: `no_path`
        let arrays = Arrays::of(&scene, &flat.rows());
        let mut gradients = BatchGradients::default();
        gradients.compute(&scene, &batch, &|ray| !(1..5).contains(&ray));
        assert!(gradients.has(0) && gradients.has(5) && !gradients.has(1));
        for ray in 0..batch.len() {
            assert_row_is(&arrays, &gradients, ray);
        }
    }
}
