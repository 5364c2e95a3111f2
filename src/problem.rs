//! The path problem: travel time, its gradient (the residual) and its tridiagonal Hessian.
//!
//! For interaction points `xᵢ = Pᵢ(sᵢ)` on polylines, legs `ℓⱼ = |xⱼ − xⱼ₋₁|` with unit
//! directions `uⱼ` and slownesses `wⱼ` (leg `j` arrives at point `j`), and unit tangents `tᵢ`:
//!
//! ```text
//! T      = Σⱼ wⱼ ℓⱼ
//! rᵢ     = ∂T/∂sᵢ     = (wᵢ uᵢ − wᵢ₊₁ uᵢ₊₁) · tᵢ          (Snell's law, tangential form)
//! Hᵢᵢ    = wᵢ (uᵢ × tᵢ)² / ℓᵢ + wᵢ₊₁ (uᵢ₊₁ × tᵢ)² / ℓᵢ₊₁  [+ κᵢ (wᵢ uᵢ − wᵢ₊₁ uᵢ₊₁) · nᵢ]
//! Hᵢ,ᵢ₊₁ = −wᵢ₊₁ (uᵢ₊₁ × tᵢ)(uᵢ₊₁ × tᵢ₊₁) / ℓᵢ₊₁
//! ```
//!
//! (0-based in the code: point `i` sits between leg `i` and leg `i + 1`.) Each leg adds the
//! rank-one matrix `(w/ℓ) g gᵀ` with `g = (−u × tᵢ, u × tᵢ₊₁)`, so on fixed segments `T` is
//! convex and `H` positive semi-definite. The bracketed curvature term is zero on a straight
//! segment; the solver adds an estimate of it only while points travel across the vertices
//! of a digitised smooth curve, where the true `T` (of the smooth curve) may have maxima and
//! saddles that the segment-wise Hessian cannot see.

use crate::geom::{Point, Vec2};
use crate::polyline::Polyline;
use crate::scene::{Scene, Step};

/// A symmetric tridiagonal matrix: `diag[i] = Hᵢᵢ`, `off[i] = Hᵢ,ᵢ₊₁`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tridiagonal {
    /// Diagonal, length `k`.
    pub diag: Vec<f64>,
    /// Super-diagonal (= sub-diagonal), length `k − 1` (0 when `k == 0`).
    pub off: Vec<f64>,
}

impl Tridiagonal {
    /// The dense `k × k` matrix, row-major.
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let k = self.diag.len();
        let mut m = vec![vec![0.0; k]; k];
        for i in 0..k {
            m[i][i] = self.diag[i];
            if i + 1 < k {
                m[i][i + 1] = self.off[i];
                m[i + 1][i] = self.off[i];
            }
        }
        m
    }
}

/// How far one interaction point is from moving freely (solver state that the merit needs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pin {
    /// Inside a segment (or at a vertex, moving through it).
    Free,
    /// Held on the vertex where its segment `seg` starts.
    Vertex,
    /// Held at the first vertex of an open polyline.
    Start,
    /// Held at the last vertex of an open polyline.
    End,
    /// Held inside a segment where a leg next to it has vanished (a source, receiver or
    /// neighbouring interaction lies on the interface there): `T` has a kink at the point.
    Kink,
}

/// Scratch buffers of one evaluation (reused: evaluating allocates nothing once sized).
#[derive(Clone, Debug, Default)]
pub(crate) struct Eval {
    /// Positions relative to the source: `k + 2` (source, interactions, receiver).
    pub rel: Vec<Vec2>,
    /// Unit leg directions, `k + 1`.
    pub u: Vec<Vec2>,
    /// Leg lengths, `k + 1`.
    pub len: Vec<f64>,
    /// Unit tangents at the interactions, `k`.
    pub tan: Vec<Vec2>,
    /// Residual `∂T/∂sᵢ`, `k`.
    pub r: Vec<f64>,
    /// Hessian diagonal, `k`.
    pub diag: Vec<f64>,
    /// Hessian off-diagonal, `k − 1`.
    pub off: Vec<f64>,
    /// Travel time.
    pub time: f64,
    /// Merit `Σ (rᵢ / (wᵢ + wᵢ₊₁))²` over the points as held (see [`Geometry::evaluate`]).
    pub phi: f64,
    /// Largest relative residual `|rᵢ| / (wᵢ + wᵢ₊₁)` of the free points.
    pub rmax: f64,
    /// Number of held points.
    pub held: usize,
    /// Number of free points next to a vanished leg.
    pub vanished: usize,
    /// Length below which a leg counts as vanished: 1e-12 of the path's length, or the
    /// round-off of the coordinates, whichever is larger.
    pub vanish: f64,
}

impl Eval {
    pub fn resize(&mut self, k: usize) {
        self.rel.resize(k + 2, Vec2::default());
        self.u.resize(k + 1, Vec2::default());
        self.len.resize(k + 1, 0.0);
        self.tan.resize(k, Vec2::default());
        self.r.resize(k, 0.0);
        self.diag.resize(k, 0.0);
        self.off.resize(k.saturating_sub(1), 0.0);
    }
}

/// The geometry of one ray: which polylines, which slownesses, which end points.
#[derive(Clone, Copy)]
pub(crate) struct Geometry<'a> {
    pub scene: &'a Scene,
    pub steps: &'a [Step],
    pub slowness: &'a [f64],
    pub source: Point,
    pub receiver: Point,
}

impl<'a> Geometry<'a> {
    #[inline]
    pub fn line(&self, i: usize) -> &'a Polyline {
        &self.scene.interfaces()[self.steps[i].interface].polyline
    }
    #[inline]
    pub fn k(&self) -> usize {
        self.steps.len()
    }

    /// Positions, legs, time and residual at parameters `s` on segments `seg`; with
    /// `hessian`, also the tridiagonal Hessian (with the curvature estimate when `curvature`).
    ///
    /// Also the merit over the points as `pin` holds them: a free point counts its residual,
    /// a point held at an end only the part pointing back inside (none if a leg next to it has
    /// vanished: it sits on a corner), a point held on a vertex nothing (the kink test judges
    /// it).
    pub fn evaluate(
        &self,
        s: &[f64],
        seg: &[usize],
        pin: &[Pin],
        e: &mut Eval,
        hessian: bool,
        curvature: bool,
    ) {
        let k = self.k();
        // Exact-length views: the loops below then index without bounds checks.
        let (s, seg, pin, w) = (&s[..k], &seg[..k], &pin[..k], &self.slowness[..k + 1]);
        let (rel, u, len, tan) = (
            &mut e.rel[..k + 2],
            &mut e.u[..k + 1],
            &mut e.len[..k + 1],
            &mut e.tan[..k],
        );
        let interfaces = self.scene.interfaces();
        rel[0] = Vec2::default();
        for i in 0..k {
            let line = &interfaces[self.steps[i].interface].polyline;
            rel[i + 1] = line.offset_on(seg[i], s[i], self.source);
            tan[i] = line.tangent(seg[i]);
        }
        rel[k + 1] = self.receiver - self.source;
        let mut time = 0.0;
        let mut total = 0.0;
        for j in 0..=k {
            let d = rel[j + 1] - rel[j];
            let l = leg_length(d);
            len[j] = l;
            u[j] = if l > 0.0 {
                d * (1.0 / l)
            } else {
                Vec2::default()
            };
            time += w[j] * l;
            total += l;
        }
        e.time = time;
        let coord = self
            .source
            .x
            .abs()
            .max(self.source.y.abs())
            .max(self.receiver.x.abs())
            .max(self.receiver.y.abs());
        let vanish = 1e-12 * total + 8.0 * f64::EPSILON * coord;
        let r = &mut e.r[..k];
        let (mut phi, mut rmax, mut held, mut vanished) = (0.0, 0.0f64, 0, 0);
        for i in 0..k {
            let t = tan[i];
            let ri = (u[i] * w[i] - u[i + 1] * w[i + 1]).dot(t);
            r[i] = ri;
            let rel = ri / (w[i] + w[i + 1]);
            let m = match pin[i] {
                Pin::Free if leg_vanished(len, i, vanish) => {
                    // The residual is undefined here; the solver judges the kink.
                    vanished += 1;
                    0.0
                }
                Pin::Free => {
                    rmax = rmax.max(rel.abs());
                    rel
                }
                Pin::Vertex | Pin::Kink => 0.0,
                Pin::Start | Pin::End if leg_vanished(len, i, vanish) => 0.0,
                Pin::Start => rel.min(0.0),
                Pin::End => rel.max(0.0),
            };
            held += (pin[i] != Pin::Free) as usize;
            phi += m * m;
        }
        e.phi = phi;
        e.rmax = rmax;
        e.held = held;
        e.vanished = vanished;
        e.vanish = vanish;
        if !hessian {
            return;
        }
        let (diag, off) = (&mut e.diag[..k], &mut e.off[..k.saturating_sub(1)]);
        for i in 0..k {
            let t = tan[i];
            let (ua, ub) = (u[i], u[i + 1]);
            let ca = ua.cross(t);
            let cb = ub.cross(t);
            let mut h = w[i] * ca * ca * inv(len[i]) + w[i + 1] * cb * cb * inv(len[i + 1]);
            if curvature {
                let kappa = interfaces[self.steps[i].interface]
                    .polyline
                    .curvature(seg[i]);
                if kappa != 0.0 {
                    h += kappa * (ua * w[i] - ub * w[i + 1]).dot(t.perp());
                }
            }
            diag[i] = h;
            if i + 1 < k {
                off[i] = -w[i + 1] * cb * ub.cross(tan[i + 1]) * inv(len[i + 1]);
            }
        }
    }
}

/// Whether a leg next to point `i` has vanished (is not longer than `vanish`, see
/// [`Eval::vanish`]): there the residual is undefined and the point sits on a corner it
/// shares with its neighbour.
#[inline]
pub(crate) fn leg_vanished(len: &[f64], i: usize, vanish: f64) -> bool {
    len[i] <= vanish || len[i + 1] <= vanish
}

/// `|d|`: a plain square root where the squares neither overflow nor lose precision to
/// underflow, `hypot` otherwise.
#[inline]
fn leg_length(d: Vec2) -> f64 {
    let l2 = d.x * d.x + d.y * d.y;
    if l2.is_normal() && l2 < 1e300 {
        l2.sqrt()
    } else {
        d.length()
    }
}

/// `1/ℓ`, with a zero-length leg contributing nothing (its direction is undefined).
#[inline]
fn inv(l: f64) -> f64 {
    if l > 0.0 { 1.0 / l } else { 0.0 }
}

/// One path's travel-time function of the interaction parameters, for inspection, tests and
/// other solvers (the argmin bridge).
///
/// ```
/// use eigenray::{PathProblem, Scene};
/// let scene = Scene::from_json(r#"{
///     "media": { "a": { "speed": 1.0 }, "b": { "speed": 0.5 } },
///     "interfaces": { "flat": { "points": [[-10, 0], [10, 0]] } },
///     "sources": [[0, 1]], "receivers": [[2, -1]],
///     "paths": [{ "steps": [{ "refract": "flat" }], "media": ["a", "b"] }]
/// }"#).unwrap();
/// let p = PathProblem::new(&scene, 0, scene.sources()[0], scene.receivers()[0]).unwrap();
/// // s is arclength from the polyline's first vertex (-10, 0): s = 11 is the point (1, 0).
/// let t = p.time(&[11.0]);
/// assert!((t - (2f64.sqrt() + 2.0 * 2f64.sqrt())).abs() < 1e-12);
/// ```
#[derive(Clone, Debug)]
pub struct PathProblem<'a> {
    scene: &'a Scene,
    path: usize,
    slowness: Vec<f64>,
    source: Point,
    receiver: Point,
}

impl<'a> PathProblem<'a> {
    /// The problem of path `path` between two points, with the path's own leg media.
    /// `None` when the path has no `media` (its media come from region lookup: use
    /// [`PathProblem::with_slowness`]).
    pub fn new(
        scene: &'a Scene,
        path: usize,
        source: Point,
        receiver: Point,
    ) -> Option<PathProblem<'a>> {
        let media = scene.paths().get(path)?.media.as_ref()?;
        let slowness = media.iter().map(|&m| scene.media()[m].slowness).collect();
        Some(PathProblem {
            scene,
            path,
            slowness,
            source,
            receiver,
        })
    }

    /// The problem with explicit leg slownesses (`steps + 1` of them).
    ///
    /// # Panics
    /// If `path` is out of range or `slowness` has the wrong length.
    pub fn with_slowness(
        scene: &'a Scene,
        path: usize,
        slowness: Vec<f64>,
        source: Point,
        receiver: Point,
    ) -> Self {
        assert_eq!(
            slowness.len(),
            scene.paths()[path].steps.len() + 1,
            "one slowness per leg"
        );
        PathProblem {
            scene,
            path,
            slowness,
            source,
            receiver,
        }
    }

    /// Number of unknowns (interactions).
    pub fn len(&self) -> usize {
        self.scene.paths()[self.path].steps.len()
    }
    /// Whether the path is the direct ray (no unknowns).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Leg slownesses.
    pub fn slowness(&self) -> &[f64] {
        &self.slowness
    }

    pub(crate) fn geometry(&self) -> Geometry<'_> {
        Geometry {
            scene: self.scene,
            steps: &self.scene.paths()[self.path].steps,
            slowness: &self.slowness,
            source: self.source,
            receiver: self.receiver,
        }
    }

    fn eval(&self, s: &[f64], hessian: bool) -> Eval {
        let g = self.geometry();
        let k = g.k();
        assert_eq!(s.len(), k, "one parameter per interaction");
        let mut e = Eval::default();
        e.resize(k);
        let mut ss = vec![0.0; k];
        let mut seg = vec![0; k];
        let pin = vec![Pin::Free; k];
        for i in 0..k {
            let line = g.line(i);
            ss[i] = line.wrap(s[i]);
            seg[i] = line.segment_at(ss[i]);
        }
        g.evaluate(&ss, &seg, &pin, &mut e, hessian, false);
        e
    }

    /// Travel time at parameters `s` (wrapped on closed polylines; on open ones a parameter
    /// outside `[0, length]` extends the end segment).
    pub fn time(&self, s: &[f64]) -> f64 {
        self.eval(s, false).time
    }
    /// The residual `∂T/∂sᵢ`.
    pub fn gradient(&self, s: &[f64]) -> Vec<f64> {
        self.eval(s, false).r
    }
    /// The analytic Hessian of `T` (symmetric tridiagonal; segment-wise, no curvature term).
    pub fn hessian(&self, s: &[f64]) -> Tridiagonal {
        let e = self.eval(s, true);
        Tridiagonal {
            diag: e.diag,
            off: e.off,
        }
    }
    /// Source, interaction points and receiver.
    pub fn points(&self, s: &[f64]) -> Vec<Point> {
        let e = self.eval(s, false);
        e.rel.iter().map(|v| self.source + *v).collect()
    }
}
