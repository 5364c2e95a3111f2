//! The documented start of a ray (see [`Tracer`](super::Tracer)): the straight-line guess,
//! the layered (ray-parameter or paraxial) refinement of refraction paths, and starts from
//! given parameters.

use crate::geom::{Point, Vec2};
use crate::polyline::Polyline;
use crate::problem::Pin;
use crate::scene::{Scene, Step, StepKind};
use crate::solver::NewtonWorkspace;

use super::{InitialGuess, Workspace};

mod graded;
pub(super) use graded::{GradedLayer, graded_guess, graded_stack_path};

/// Scratch of the start: crossings, the layers of the ray-parameter refinement, and the
/// default guess kept while a warm start is compared with it.
#[derive(Clone, Debug, Default)]
pub(crate) struct StartScratch {
    /// Per step: the fraction of `S → R` where that line crosses the step's interface (NaN
    /// where it does not, or for a reflection).
    pub crossing_t: Vec<f64>,
    /// Per layer of the ray-parameter refinement: thickness, speed, and the lateral offset
    /// across it at the ray parameter found.
    pub layers: Vec<Layer>,
    /// Per layer of the graded refinement (media with speed gradients across the layers).
    pub graded: Vec<graded::GradedLayer>,
    /// The default guess's parameters and segments while a warm start is tried.
    pub s_alt: Vec<f64>,
    pub seg_alt: Vec<usize>,
}

impl StartScratch {
    /// Sizes it for a path of `k` interactions.
    pub(crate) fn resize(&mut self, k: usize) {
        self.s_alt.resize(k, 0.0);
        self.crossing_t.resize(k, f64::NAN);
        self.seg_alt.resize(k, 0);
        self.layers.reserve(k + 1);
    }
}

/// A parameter on a polyline and its segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Placed {
    pub s: f64,
    pub seg: usize,
}

/// Starts from given parameters (wrapped on closed polylines, clamped to open ones).
pub(super) fn given_start(scene: &Scene, steps: &[Step], params: &[f64], nw: &mut NewtonWorkspace) {
    for (i, (step, &wanted)) in steps.iter().zip(params).enumerate() {
        let line = &scene.interfaces()[step.interface].polyline;
        let at = given_param(line, wanted, nw.seg[i]);
        (nw.s[i], nw.seg[i]) = (at.s, at.seg);
        nw.pin[i] = Pin::Free;
    }
}

/// One parameter of [`given_start`]: `wanted` made valid on `line` and its segment (`hint`
/// tried first; the segment does not depend on it).
#[inline(always)]
pub(crate) fn given_param(line: &Polyline, wanted: f64, hint: usize) -> Placed {
    let s = line.clamp_param(wanted);
    Placed {
        s,
        seg: line.segment_at_hint(s, hint),
    }
}

/// A start point on a polyline, and how far it is from its target.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    s: f64,
    distance: f64,
    seg: usize,
}

/// Polylines with more segments than this start a reflection at the crossing of the
/// perpendicular through the target point (see [`Tracer`]) rather than at the nearest point.
const LONG_POLYLINE: usize = 1024;

/// Where the line through `target` perpendicular to `source → receiver` crosses `line`,
/// nearest to `target`. An `O(log M)` query of the
/// polyline's BVH (a line crosses a gently curved polyline a few times), where the
/// nearest-point query from a target far from a long digitised curve opens about `√M` leaves.
fn perpendicular_crossing(
    line: &Polyline,
    source: Point,
    receiver: Point,
    target: Point,
) -> Option<Candidate> {
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
    let mut best: Option<Candidate> = None;
    line.crossings_with_segment(a, e, |s, t, j| {
        let distance = (t - 0.5).abs() * 2.0 * reach;
        if best.is_none_or(|b| distance < b.distance) {
            best = Some(Candidate {
                s,
                distance,
                seg: j,
            });
        }
    });
    best
}

/// Refines the straight-line guess of a path of refractions only (every step crossed by the
/// line `S → R`, at increasing fractions kept in `ws.start.crossing_t`): each point moves along
/// its interface to where a ray through flat layers would cross, as [`InitialGuess`] describes
/// (the ray parameter through parallel interfaces, [`ray_parameter`]; the small-angle limit
/// elsewhere, for a single refraction, or where that equation has no root).
pub(super) fn refraction_guess(
    scene: &Scene,
    steps: &[Step],
    source: Point,
    receiver: Point,
    guess: InitialGuess,
    ws: &mut Workspace,
) {
    let k = steps.len();
    let w = &ws.ray.slowness;
    if k == 0 || w.len() != k + 1 {
        return;
    }
    if k == 1 {
        // One refraction: the 1-D ray-parameter solve is the Newton solve's own one-unknown
        // problem and costs as much; the paraxial start.
        let line = &scene.interfaces()[steps[0].interface].polyline;
        let (t, w) = (ws.start.crossing_t[0], [w[0], w[1]]);
        let at = paraxial_one(
            line,
            ws.newton.s[0],
            t,
            ws.newton.seg[0],
            w,
            receiver - source,
        );
        (ws.newton.s[0], ws.newton.seg[0]) = (at.s, at.seg);
        return;
    }
    let lines = SceneStepLines { scene, steps };
    // Curved legs through flat layers whose speeds vary across them only: the ray itself.
    if guess == InitialGuess::RayParameter
        && !ws.ray.curved.is_empty()
        && graded_guess(&lines, receiver - source, ws)
    {
        return;
    }
    layered_guess(&lines, receiver - source, guess, ws);
}

/// The interfaces of a path's steps as [`layered_guess`] sees them.
pub(super) trait StepLines {
    /// The unit tangent of interface `i` on its segment `seg`.
    fn tangent(&self, i: usize, seg: usize) -> Vec2;
    /// Parameter `s` made valid on interface `i` ([`Polyline::clamp_param`]) and its segment
    /// (`seg` tried first).
    fn place(&self, i: usize, s: f64, seg: usize) -> Placed;
}

/// The interfaces of a path's steps, looked up in the scene.
struct SceneStepLines<'a> {
    scene: &'a Scene,
    steps: &'a [Step],
}

impl SceneStepLines<'_> {
    #[inline(always)]
    fn line(&self, i: usize) -> &Polyline {
        &self.scene.interfaces()[self.steps[i].interface].polyline
    }
}

impl StepLines for SceneStepLines<'_> {
    #[inline(always)]
    fn tangent(&self, i: usize, seg: usize) -> Vec2 {
        self.line(i).tangent(seg)
    }

    #[inline(always)]
    fn place(&self, i: usize, s: f64, seg: usize) -> Placed {
        let line = self.line(i);
        let s = line.clamp_param(s);
        Placed {
            s,
            seg: line.segment_at_hint(s, seg),
        }
    }
}

/// [`refraction_guess`] for two or more refractions (`lines` the path's interfaces, `d` the
/// receiver minus the source, the slownesses and crossings in `ws`).
#[inline(always)]
pub(super) fn layered_guess(
    lines: &(impl StepLines + ?Sized),
    d: Vec2,
    guess: InitialGuess,
    ws: &mut Workspace,
) {
    let k = ws.newton.s.len();
    debug_assert!(k >= 2 && ws.ray.slowness.len() == k + 1);
    let (t, w) = (&ws.start.crossing_t[..k], &ws.ray.slowness[..k + 1]);
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
    let seg = &ws.newton.seg[..k];
    let tangent = |i: usize| lines.tangent(i, seg[i]);
    let p = match guess {
        InitialGuess::RayParameter => ray_parameter(t, w, sum, d, tangent, &mut ws.start.layers),
        InitialGuess::Paraxial => None,
    };
    let mut acc = 0.0;
    prev = 0.0;
    let (s_at, seg) = (&mut ws.newton.s[..k], &mut ws.newton.seg[..k]);
    for i in 0..k {
        let tau = match p {
            Some(RayParameter { x, .. }) => {
                // Δtᵢ tan θᵢ, from the evaluation at p.
                acc += ws.start.layers[i].offset;
                acc / x
            }
            None => {
                acc += (t[i] - prev) / w[i];
                acc / sum
            }
        };
        prev = t[i];
        let lateral = d.dot(lines.tangent(i, seg[i]));
        let at = lines.place(i, s_at[i] + (tau - t[i]) * lateral, seg[i]);
        (s_at[i], seg[i]) = (at.s, at.seg);
    }
}

/// Largest angle between two interfaces' normals (as `1 − cos`) for which
/// [`refraction_guess`] treats the layers as parallel: about 5e-5 rad, round-off of digitised
/// coordinates.
pub(super) const PARALLEL: f64 = 1e-9;

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
) -> Option<RayParameter> {
    let x = parallel_offset(t.len(), d, tangent)?;
    let sums = LayerSums::fill(t, w, layers);
    let limit = sums.limit;
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
    let tan = x / sums.critical;
    let alone = limit * (tan / (1.0 + tan * tan).sqrt());
    // (`alone` may exceed `cap`: the root can lie nearer the pole than that.)
    let mut p = small_angle.min(alone);
    let q = series_root(sums.series, sum, x, small_angle);
    // (A NaN `q`, from overflowing powers of a huge speed, is not taken.)
    let series_bound = q < p;
    if series_bound {
        p = q;
    }
    if p >= limit {
        p = cap;
    }
    let mut at = evaluate(layers, x, p);
    if series_bound && at.f < 0.0 && at.f >= -64.0 * f64::EPSILON * x {
        // Where the series' neglected terms are below round-off, its root is f's to within
        // round-off, on either side.
        return Some(RayParameter { p, x });
    }
    if (at.f.is_nan() || at.f < 0.0) && p < paraxial {
        // Round-off put `alone` (or the series' root) below the root.
        p = paraxial;
        at = evaluate(layers, x, p);
    }
    if !(at.f >= 0.0 && at.sound()) {
        return None;
    }
    halley(layers, x, limit, p, at)
}

/// The offset `x = X / Z` of [`ray_parameter`]'s equation for `d = R − S`: along (`X`) over
/// across (`Z`) the first of `k` interfaces, `tangent(i)` the tangent of interface `i` at its
/// crossing. `None` when the interfaces are not parallel or `x` is not finite and positive
/// (the straight line is the ray).
#[inline]
fn parallel_offset(k: usize, d: Vec2, tangent: impl Fn(usize) -> Vec2) -> Option<f64> {
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
    Some(x)
}

/// What [`ray_parameter`] needs of its layers besides each one's thickness and speed.
struct LayerSums {
    /// The sums `Σ Δtⱼ vⱼⁿ` for `n` = 3, 5, 7 (of the series of [`series_root`]).
    series: [f64; 3],
    /// The smallest slowness (a layer's critical angle).
    limit: f64,
    /// How thick the layers of that slowness are together.
    critical: f64,
}

impl LayerSums {
    /// Sets `layers` to the thickness `Δtⱼ` (in units of `Z`) and speed `vⱼ = 1/wⱼ` of each
    /// layer between the crossing fractions `t`, with slownesses `w`, and sums them up.
    #[inline]
    fn fill(t: &[f64], w: &[f64], layers: &mut Vec<Layer>) -> LayerSums {
        let k = t.len();
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
        LayerSums {
            series,
            limit,
            critical,
        }
    }
}

/// An upper bound of the root of [`ray_parameter`]'s equation from the series of its layers
/// (`series`, see [`LayerSums`]), the paraxial denominator `sum` and the offset `x`, starting
/// at the paraxial `small_angle`.
///
/// tan θ = sin θ (1 + sin²θ / 2 + 3 sin⁴θ / 8 + 5 sin⁶θ / 16 + …), all terms positive: the
/// first four make a polynomial P(p) ≤ f(p) + x, convex and increasing, whose root is
/// therefore above f's; Newton's iterates on it from its linear part's root (the paraxial p)
/// stay above its root. Three of them, without a square root or a division by layer, save
/// evaluations of f.
#[inline]
fn series_root(series: [f64; 3], sum: f64, x: f64, small_angle: f64) -> f64 {
    let [b3, b5, b7] = series;
    let mut q = small_angle;
    for _ in 0..3 {
        let q2 = q * q;
        let g = q * (sum + q2 * (0.5 * b3 + q2 * (0.375 * b5 + q2 * 0.3125 * b7))) - x;
        let dg = sum + q2 * (1.5 * b3 + q2 * (1.875 * b5 + q2 * 2.1875 * b7));
        q -= g / dg;
    }
    q
}

/// [`ray_parameter`]'s function at one `p` and its first two derivatives.
#[derive(Clone, Copy)]
struct Evaluation {
    /// `f(p)`.
    f: f64,
    /// `f'(p)`.
    df: f64,
    /// `f''(p)`.
    d2f: f64,
}

impl Evaluation {
    /// Whether the evaluation can be stepped from: `f'` positive and everything finite.
    #[inline]
    fn sound(self) -> bool {
        self.df > 0.0 && crate::problem::finite(self.f + self.df + self.d2f)
    }
}

/// Evaluates `f(p) = Σ Δtⱼ sⱼ / cⱼ − x` with `sⱼ = p / wⱼ`, `cⱼ = √(1 − sⱼ²)`; `f' = Σ Δtⱼ vⱼ /
/// cⱼ³` and `f'' = Σ 3 Δtⱼ vⱼ² sⱼ / cⱼ⁵`. Each evaluation leaves the offsets `Δtⱼ tan θⱼ = Δtⱼ
/// sⱼ / cⱼ` and their derivatives in the layers, for the caller: every return of
/// [`ray_parameter`] with a p follows an evaluation at that p, or a last step whose own error
/// is below round-off, with the offsets moved along their Taylor series.
#[inline]
fn evaluate(layers: &mut [Layer], x: f64, p: f64) -> Evaluation {
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
    Evaluation { f, df, d2f }
}

/// Halley's steps on [`ray_parameter`]'s equation (offset `x`, smallest slowness `limit`)
/// from `p`, above the root, where it evaluates to `at`; the root, or `None` where an
/// evaluation is not sound.
///
/// From above the root of this convex increasing function (Newton's steps, where the
/// curvature would more than double the step): the error after a step of `h` is about
/// `(ρ²/4 + (h vₘₐₓ)²/2) |h|` with `ρ = h f''/f'` (the f‴ term bounded through the largest
/// speed, `1/limit`). Where a thousand times that is below round-off, the step is the last:
/// the offsets follow it to second order (their error of order h³, below round-off too),
/// without another evaluation.
#[inline(always)]
fn halley(
    layers: &mut [Layer],
    x: f64,
    limit: f64,
    mut p: f64,
    mut at: Evaluation,
) -> Option<RayParameter> {
    let vmax = 1.0 / limit;
    for _ in 0..60 {
        if at.f.abs() <= 4.0 * f64::EPSILON * x {
            break;
        }
        let newton = at.f / at.df;
        let rho = newton * at.d2f / at.df;
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
            return Some(RayParameter { p: next, x });
        }
        p = next;
        at = evaluate(layers, x, p);
        if !at.sound() {
            return None;
        }
    }
    Some(RayParameter { p, x })
}

/// A solution of [`ray_parameter`]'s equation: the ray parameter `p` and the offset `x = X / Z`
/// it takes across the layers.
#[derive(Clone, Copy, Debug)]
struct RayParameter {
    #[cfg_attr(
        not(test),
        expect(dead_code, reason = "the layers' offsets carry what the start needs")
    )]
    p: f64,
    x: f64,
}

/// The image method on the tangent line of `line` at parameter `s` (segment `j`): the
/// specular point of a mirror along that line between `source` and `receiver`, as a parameter
/// of `line` (moved by the offset along the tangent, clamped). Exact for a straight mirror; a
/// gently curved one starts close to its specular point. `s` itself when both are not on one
/// side of the line.
fn image_point(line: &Polyline, s: f64, j: usize, source: Point, receiver: Point) -> f64 {
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
    line: &Polyline,
    source: Point,
    receiver: Point,
    frac: f64,
) -> Option<LineCrossing> {
    let mut best: Option<(f64, LineCrossing)> = None;
    line.crossings_with_segment(source, receiver, |s, t, j| {
        let d = (t - frac).abs();
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, LineCrossing { s, t, seg: j }));
        }
    });
    best.map(|(_, c)| c)
}

/// Where a straight line crosses a polyline: the polyline's parameter `s` and segment, and
/// the fraction `t` along the line.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LineCrossing {
    pub s: f64,
    pub t: f64,
    pub seg: usize,
}

/// [`refraction_guess`] for one refraction: the paraxial point from the crossing of `S → R`
/// at fraction `t`, parameter `s` on segment `j` of `line` (unchanged unless `0 < t < 1`),
/// `w` the two slownesses and `d = R − S`.
#[inline(always)]
pub(super) fn paraxial_one(
    line: &Polyline,
    s: f64,
    t: f64,
    j: usize,
    w: [f64; 2],
    d: Vec2,
) -> Placed {
    if !(t > 0.0 && t < 1.0) {
        return Placed { s, seg: j };
    }
    let first = (t - 0.0) / w[0];
    let sum = 0.0 + first + (1.0 - t) / w[1];
    let tau = (0.0 + first) / sum;
    let s = line.clamp_param(s + (tau - t) * d.dot(line.tangent(j)));
    Placed {
        s,
        seg: line.segment_at_hint(s, j),
    }
}

/// The documented initial guess (see [`Tracer`]).
pub(super) fn initial_guess(
    scene: &Scene,
    steps: &[Step],
    source: Point,
    receiver: Point,
    ws: &mut Workspace,
) {
    let k = steps.len();
    for (i, step) in steps.iter().enumerate() {
        let line = &scene.interfaces()[step.interface].polyline;
        let frac = (i + 1) as f64 / (k + 1) as f64;
        let target = source.lerp(receiver, frac);
        let mut best: Option<Candidate> = None;
        let mut crossing_t = f64::NAN;
        if step.kind == StepKind::Refract
            && let Some(c) = nearest_crossing(line, source, receiver, frac)
        {
            best = Some(Candidate {
                s: c.s,
                distance: (c.t - frac).abs(),
                seg: c.seg,
            });
            crossing_t = c.t;
        }
        if best.is_none() && line.num_segments() > LONG_POLYLINE {
            best = perpendicular_crossing(line, source, receiver, target);
            if k == 1
                && step.kind == StepKind::Reflect
                && let Some(c) = best
            {
                best = Some(Candidate {
                    s: image_point(line, c.s, c.seg, source, receiver),
                    ..c
                });
            }
        }
        // The crossing's fraction along S → R, for `refraction_guess` (NaN: no crossing).
        ws.start.crossing_t[i] = crossing_t;
        let (s, hint) = match best {
            Some(c) => (c.s, c.seg),
            None => {
                let nearest = line.nearest(target);
                (nearest.s, nearest.seg)
            }
        };
        let s = line.wrap(s);
        ws.newton.s[i] = s;
        ws.newton.seg[i] = line.segment_at_hint(s, hint);
        ws.newton.pin[i] = Pin::Free;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            let RayParameter { p, x: scaled } =
                ray_parameter(&t, &w, sum, d, along, &mut layers).unwrap();
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
