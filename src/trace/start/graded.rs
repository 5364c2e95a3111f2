//! The ray-parameter start through flat parallel layers whose media vary across the layers
//! only: uniform media, and media with a speed gradient along the interfaces' normal (BELLHOP's
//! `'C'` layers, the ocean's case, whose legs are arcs).
//!
//! There the ray parameter `p` (the slowness along the interfaces) is conserved, and each
//! layer's range `X(p)` across it is the profile medium's closed form
//! ([`layer_range`]: `h p (c₁ + c₂) / (s₁ + s₂)`, `sᵢ = √(1 − p²cᵢ²)`, no division by the
//! gradient, a uniform layer the same formula). The start solves `Σ X(p) = Δx` by Newton's
//! steps in `p` (safeguarded by bisection: `X` is convex and increasing up to the first
//! turning point, `p = 1 / c_max`) and places each crossing at the summed ranges: the ray
//! through the layers up to round-off, which the general solve then confirms in one
//! evaluation (as the uniform stack's start, `ray_parameter` in `start.rs`).
//!
//! A ray that would have to turn (no root below `1 / c_max`), a gradient with a component
//! along the interfaces, or interfaces that are not parallel: no start here (the uniform
//! layers' ray parameter at each medium's speed at the source, as before).

use crate::geom::{Point, Vec2};
use crate::leg::LegMedium;
use crate::leg::profile::layer_range;
use crate::scene::Scene;

use super::{PARALLEL, StepLines, Workspace};

/// The most Newton (or bisection) steps in `p`.
const MAX_STEPS: usize = 100;

/// The largest component of a medium's gradient along the interfaces, relative to the
/// gradient, for which the medium counts as varying across the layers only (the start is a
/// start: the general solve takes the ray from there).
const ALONG: f64 = 1e-12;

/// One layer of the graded start: its thickness, the speeds at the faces the ray enters and
/// leaves by, and the range across it at the last `p` evaluated.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct GradedLayer {
    h: f64,
    speeds: [f64; 2],
    x: f64,
    /// `∂x/∂p` there.
    x_p: f64,
}

impl GradedLayer {
    /// `∂²T/∂X²` of the layer's leg at the start's ray (`X` its range): `1 / (∂X/∂p)`, as
    /// `∂T/∂X = p`. The graded stack kernel's Hessian (`StraightPath::solve_graded_stack`).
    #[inline]
    pub(in crate::trace) fn stiffness(&self) -> f64 {
        1.0 / self.x_p
    }
}

/// Whether path `path` of `scene` (a stack of refractions at parallel interfaces of one
/// segment each, its media given: `StraightPath::stack`)
/// suits the graded start: its interfaces at distinct offsets, in order across them (so that
/// a ray from one side of the stack to the other crosses each once), and each of its media
/// uniform or with a gradient along the interfaces' normal, none with a speed profile. What
/// the plan (`trace::plan`) asks before it gives the path the graded stack kernel (whose
/// start makes a batch's warm start needless).
pub(in crate::trace) fn graded_stack_path(scene: &Scene, path: usize) -> bool {
    let spec = &scene.paths()[path];
    let Some(media) = spec.media.as_deref() else {
        return false;
    };
    let line = |i: usize| &scene.interfaces()[spec.steps[i].interface].polyline;
    let Some(t) = spec.steps.first().map(|_| line(0).tangent(0)) else {
        return false;
    };
    let offsets: Vec<f64> = (0..spec.steps.len())
        .map(|i| line(i).vertices()[0].to_vec2().dot(t.perp()))
        .collect();
    let ordered =
        offsets.windows(2).all(|w| w[1] > w[0]) || offsets.windows(2).all(|w| w[1] < w[0]);
    ordered
        && media.iter().all(|&m| {
            let medium = &scene.media()[m];
            let across = match medium.leg_model(Point::new(0.0, 0.0)) {
                LegMedium::Uniform(_) => true,
                LegMedium::Linear(l) => {
                    let along = l.gradient.dot(t);
                    along * along <= ALONG * ALONG * l.gradient.dot(l.gradient)
                }
                LegMedium::Profile(_) => false,
            };
            across && medium.profile_model().is_none()
        })
}

/// Places the crossings of `ws` (of the straight line `S → R`, `d = R − S`, at the fractions
/// `ws.start.crossing_t`) where the ray through the layers crosses, for a path of two or more
/// refractions whose legs' models (relative to the source) are `ws.ray.curved`. `false`
/// (nothing moved) outside the module's case.
pub(in crate::trace) fn graded_guess(
    lines: &(impl StepLines + ?Sized),
    d: Vec2,
    ws: &mut Workspace,
) -> bool {
    let k = ws.newton.s.len();
    if ws.ray.curved.len() != k + 1 || k == 0 {
        return false;
    }
    let seg = &ws.newton.seg[..k];
    let m = lines.tangent(0, seg[0]);
    if (1..k).any(|i| lines.tangent(i, seg[i]).dot(m).abs() < 1.0 - PARALLEL) {
        return false;
    }
    let across = d.dot(m.perp());
    let along = d.dot(m).abs();
    // The unit normal toward the receiver, and the depth of the receiver below the source.
    let down = m.perp() * across.signum();
    let depth = across.abs();
    let t = &ws.start.crossing_t[..k];
    if !fill_layers(t, &ws.ray.curved, down, depth, &mut ws.start.graded) {
        return false;
    }
    if !(along > 0.0 && along.is_finite()) {
        // No lateral offset: the straight line across the layers is the ray (`p = 0`).
        for l in ws.start.graded.iter_mut() {
            l.x_p = layer_range(0.0, l.h, l.speeds).x_p;
        }
        return along == 0.0;
    }
    if !solve_ray_parameter(&mut ws.start.graded, along) {
        return false;
    }
    let (t, layers) = (&ws.start.crossing_t[..k], &ws.start.graded);
    let (s_at, seg) = (&mut ws.newton.s[..k], &mut ws.newton.seg[..k]);
    let mut acc = 0.0;
    for i in 0..k {
        acc += layers[i].x;
        let tau = acc / along;
        let lateral = d.dot(lines.tangent(i, seg[i]));
        let at = lines.place(i, s_at[i] + (tau - t[i]) * lateral, seg[i]);
        (s_at[i], seg[i]) = (at.s, at.seg);
    }
    true
}

/// The layers between the crossing fractions `t` (increasing in `(0, 1]`) of a ray `depth`
/// deep along `down`, of the leg models `curved`, into `layers`; `false` where the
/// fractions are not increasing, a medium's gradient has a component along the interfaces
/// or a speed is not positive and finite.
fn fill_layers(
    t: &[f64],
    curved: &[LegMedium],
    down: Vec2,
    depth: f64,
    layers: &mut Vec<GradedLayer>,
) -> bool {
    let k = t.len();
    layers.clear();
    let mut prev = 0.0;
    for (j, medium) in curved[..=k].iter().enumerate() {
        let hi = if j < k { t[j] } else { 1.0 };
        if !(hi > prev && hi <= 1.0) {
            return false;
        }
        let (u0, u1) = (prev * depth, hi * depth);
        let speeds = match *medium {
            LegMedium::Uniform(u) => [1.0 / u.slowness; 2],
            LegMedium::Linear(l) => {
                let g = l.gradient;
                let along = g.dot(down.perp());
                if along * along > ALONG * ALONG * g.dot(g) {
                    return false;
                }
                let rate = g.dot(down);
                [l.speed + rate * u0, l.speed + rate * u1]
            }
            LegMedium::Profile(_) => return false,
        };
        let [c0, c1] = speeds;
        if !(c0 > 0.0 && c1 > 0.0 && c0 < f64::INFINITY && c1 < f64::INFINITY) {
            return false;
        }
        layers.push(GradedLayer {
            h: u1 - u0,
            speeds,
            x: 0.0,
            x_p: 0.0,
        });
        prev = hi;
    }
    true
}

/// Solves `Σ X(p) = along` (`along > 0`) over `layers`, leaving each layer's range at the root
/// in it; `false` where there is no root below the first turning point.
///
/// Newton's steps from the paraxial `p` (every sine taken as 1, `X(p) ≥ p Σ h c̄`: above the
/// root) descend on the convex `X` to the root. Where the error a step leaves, `X″ h² / 2`
/// (`X″` at most the secant of the last two slopes, `X″` growing with `p`), is below the
/// tolerance, the step is the last: the layers' ranges follow it to first order without
/// another evaluation.
fn solve_ray_parameter(layers: &mut [GradedLayer], along: f64) -> bool {
    let fastest = layers.iter().flat_map(|l| l.speeds).fold(0.0, f64::max);
    let (mut lo, mut hi) = (0.0, 1.0 / fastest);
    let paraxial: f64 = layers
        .iter()
        .map(|l| 0.5 * l.h * (l.speeds[0] + l.speeds[1]))
        .sum();
    let mut p = along / paraxial;
    if !(p > lo && p < hi) {
        p = 0.5 * (lo + hi);
    }
    let tolerance = 4.0 * (layers.len() as f64) * f64::EPSILON * along;
    // The last evaluation's `p` and slope.
    let mut last: Option<(f64, f64)> = None;
    for _ in 0..MAX_STEPS {
        let (mut f, mut f_p) = (-along, 0.0);
        for l in layers.iter_mut() {
            let r = layer_range(p, l.h, l.speeds);
            (l.x, l.x_p) = (r.x, r.x_p);
            f += r.x;
            f_p += r.x_p;
        }
        if f.abs() <= tolerance {
            return true;
        }
        // (A range that is not finite: at or beyond a turning point.)
        if f > 0.0 || !f.is_finite() {
            hi = p;
        } else {
            lo = p;
        }
        let newton = p - f / f_p;
        if !(newton > lo && newton < hi) {
            last = None;
            let next = 0.5 * (lo + hi);
            if next == p || lo >= hi {
                // No root below the turning point (or none that round-off resolves).
                return false;
            }
            p = next;
            continue;
        }
        let h = newton - p;
        if let Some((p0, slope0)) = last {
            let bend = ((slope0 - f_p) / (p0 - p)).abs();
            if bend * h * h <= tolerance {
                for l in layers.iter_mut() {
                    l.x += h * l.x_p;
                }
                return true;
            }
        }
        if newton == p {
            return f.abs() <= 1e-9 * along;
        }
        last = Some((p, f_p));
        p = newton;
    }
    false
}
