//! The amplitude of one ray from its points and leg media: one pass over its interactions
//! that multiplies the coefficients, sums the attenuation and the out-of-plane width, and
//! runs the forward sweep of the tridiagonal solve that gives the in-plane width.

use std::f64::consts::PI;

use num_complex::Complex64;

use super::coefficients::{Weights, cos_across};
use super::{Amplitude, NoAmplitude};
use crate::geom::{Point, Vec2};
use crate::polyline::Polyline;
use crate::regions::Regions;
use crate::scene::{Amplitudes, Reflection, Scene, SourceModel, Step, StepKind};

/// A solved path as the amplitude reads it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PathGeometry<'a> {
    /// Its steps.
    pub steps: &'a [Step],
    /// Source, interaction points, receiver.
    pub points: &'a [Point],
    /// Leg media (indices into [`Scene::media`]).
    pub media: &'a [usize],
    /// The segment of each interaction point, when the solve knows it (tried first).
    pub segments: Option<&'a [usize]>,
}

/// The unit direction, length and inverse length of the leg from `p` to `q` (`None` for a
/// leg of zero length).
#[inline(always)]
fn leg(p: Point, q: Point) -> Option<(Vec2, f64, f64)> {
    let d = q - p;
    let l = d.length();
    if !(l > 0.0 && l.is_finite()) {
        return None;
    }
    let inv = 1.0 / l;
    Some((d * inv, l, inv))
}

/// The segment of `line` that interaction point `p` lies on: the only one, the solve's
/// `hint` when `p` lies on it (to round-off), else the nearest.
#[inline(always)]
fn segment_of(line: &Polyline, p: Point, hint: Option<usize>) -> usize {
    let n = line.num_segments();
    if n == 1 {
        return 0;
    }
    if let Some(j) = hint.filter(|&j| j < n) {
        let (a, _) = line.segment(j);
        let (t, len) = (line.tangent(j), line.segment_length(j));
        let d = p - a;
        let round = 16.0 * f64::EPSILON * (p.x.abs() + p.y.abs() + a.x.abs() + a.y.abs());
        let slack = 1e-9 * len + 4.0 * round;
        let along = d.dot(t);
        if d.cross(t).abs() <= slack && along >= -slack && along <= len + slack {
            return j;
        }
    }
    line.nearest(p).seg
}

/// What the pass over a path gathers.
struct Walk {
    /// The product of the coefficients.
    coefficient: Complex64,
    /// `Π cos θ₂ / cos θ₁` over the refractions.
    cos_ratio: f64,
    /// `Σ ℓⱼ / wⱼ`.
    reduced_length: f64,
    /// `Σ αⱼ ℓⱼ` (dB).
    attenuation_db: f64,
    /// `|∂φ₀/∂x⊥|`: how the take-off angle turns per unit move of the receiver across the
    /// last leg.
    turn: f64,
    /// The first leg's direction.
    first: Vec2,
    /// The first converted reflection (legs in two media), which has no coefficient.
    converted: Option<usize>,
}

/// The state of the forward sweep of `H x = e_{k−1} β` (Thomas' elimination), kept for the
/// first unknown only: `x₀ = β Π_{i<k−1} (−hᵢ,ᵢ₊₁ / rᵢ) / r_{k−1}` with `rᵢ` the pivots.
struct Sweep {
    /// The last pivot.
    pivot: f64,
    /// `Π (−hᵢ,ᵢ₊₁ / rᵢ)` so far.
    product: f64,
    /// The previous interaction's tangent.
    tangent: Vec2,
}

/// The amplitude of the ray through `path` (a `converged` ray: every interaction strictly
/// inside its segment) in `scene` with the amplitude settings `settings`; `regions` for
/// `"media"` reflections.
pub(crate) fn of_path(
    scene: &Scene,
    settings: &Amplitudes,
    regions: Option<&Regions>,
    path: PathGeometry<'_>,
) -> Amplitude {
    let k = path.steps.len();
    let media = scene.media();
    if path.points.len() != k + 2
        || path.media.len() != k + 1
        || path.media.iter().any(|&m| m >= media.len())
    {
        return Amplitude::none(NoAmplitude::UnknownMedia);
    }
    let walk = match walk(scene, settings, regions, path) {
        Ok(w) => w,
        Err(reason) => return Amplitude::none(reason),
    };
    let w0 = media[path.media[0]].slowness;
    let width = 1.0 / walk.turn;
    if !(width.is_finite() && width > 0.0) {
        return Amplitude::none(NoAmplitude::Caustic);
    }
    let root = walk.cos_ratio.sqrt();
    let spreading = match settings.source {
        SourceModel::Point => root / (4.0 * PI * (width * (w0 * walk.reduced_length)).sqrt()),
        SourceModel::Axisymmetric => {
            let out = match out_of_plane_axisymmetric(path.points, walk.first) {
                Ok(Some(y)) => y,
                Ok(None) => w0 * walk.reduced_length,
                Err(reason) => return Amplitude::none(reason),
            };
            root / (4.0 * PI * (width * out).sqrt())
        }
        SourceModel::Line => {
            let k0 = 2.0 * PI * settings.frequency.unwrap_or(f64::NAN) * w0;
            root / (8.0 * PI * k0 * width).sqrt()
        }
    };
    if !(spreading.is_finite() && spreading > 0.0) {
        return Amplitude::none(NoAmplitude::Caustic);
    }
    let loss = if walk.attenuation_db > 0.0 {
        10f64.powf(-walk.attenuation_db / 20.0)
    } else {
        1.0
    };
    if let Some(step) = walk.converted {
        // The geometry's spreading and the attenuation, but no coefficient.
        let nan = Complex64::new(f64::NAN, f64::NAN);
        return Amplitude {
            value: nan,
            spreading,
            coefficient: nan,
            attenuation_db: walk.attenuation_db,
            reason: Some(NoAmplitude::ConvertedReflection { step }),
        };
    }
    let mut value = walk.coefficient * (spreading * loss);
    if settings.source == SourceModel::Line {
        // e^(iπ/4): the phase of the 2-D Green's function's far field.
        value *= Complex64::new(
            std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        );
    }
    Amplitude {
        value,
        spreading,
        coefficient: walk.coefficient,
        attenuation_db: walk.attenuation_db,
        reason: None,
    }
}

/// The out-of-plane width of an axisymmetric scene: `|x_R| / |t₀ₓ|`; `None` for a path along
/// the axis (the point source's width is the limit there).
fn out_of_plane_axisymmetric(points: &[Point], first: Vec2) -> Result<Option<f64>, NoAmplitude> {
    if points[0].x != 0.0 {
        return Err(NoAmplitude::SourceOffAxis);
    }
    let side = first.x;
    let rest = &points[1..];
    if side == 0.0 {
        // Along the axis: every point on it, the tube a cone about the axis.
        return if rest.iter().all(|p| p.x == 0.0) {
            Ok(None)
        } else {
            Err(NoAmplitude::OnAxis)
        };
    }
    if rest.iter().any(|p| p.x * side <= 0.0) {
        return Err(NoAmplitude::OnAxis);
    }
    let range = points[points.len() - 1].x.abs();
    Ok(Some(range / side.abs()))
}

/// One pass over the path's interactions.
fn walk(
    scene: &Scene,
    settings: &Amplitudes,
    regions: Option<&Regions>,
    path: PathGeometry<'_>,
) -> Result<Walk, NoAmplitude> {
    let (points, legs) = (path.points, path.media);
    let media = scene.media();
    let (u0, l0, inv0) = leg(points[0], points[1]).ok_or(NoAmplitude::VanishedLeg { leg: 0 })?;
    let attenuation = &settings.attenuation;
    let mut out = Walk {
        coefficient: Complex64::new(1.0, 0.0),
        cos_ratio: 1.0,
        reduced_length: l0 / media[legs[0]].slowness,
        attenuation_db: attenuation[legs[0]] * l0,
        turn: inv0,
        first: u0,
        converted: None,
    };
    let (mut u_in, mut inv_in, mut w_in) = (u0, inv0, media[legs[0]].slowness);
    let mut sweep = Sweep {
        pivot: 1.0,
        product: 1.0,
        tangent: Vec2::default(),
    };
    let mut first_tangent = Vec2::default();
    for (i, step) in path.steps.iter().enumerate() {
        let (u, l, inv) =
            leg(points[i + 1], points[i + 2]).ok_or(NoAmplitude::VanishedLeg { leg: i + 1 })?;
        let (m_in, m) = (legs[i], legs[i + 1]);
        let w = media[m].slowness;
        let line = &scene.interfaces()[step.interface].polyline;
        let seg = segment_of(
            line,
            points[i + 1],
            path.segments.and_then(|s| s.get(i).copied()),
        );
        let t = line.tangent(seg);
        let n = t.perp();
        let (c1, c2) = (u_in.dot(n), u.dot(n));
        // Row i of the Hessian of the time, and the forward sweep through it.
        let diag = w_in * c1 * c1 * inv_in + w * c2 * c2 * inv;
        let pivot = if i == 0 {
            first_tangent = t;
            diag
        } else {
            let prev = sweep.tangent;
            let off = -t.dot(prev - u_in * u_in.dot(prev)) * (w_in * inv_in);
            sweep.product *= -off / sweep.pivot;
            diag - off * off / sweep.pivot
        };
        if !(pivot.is_finite() && pivot > 0.0) {
            return Err(NoAmplitude::Caustic);
        }
        (sweep.pivot, sweep.tangent) = (pivot, t);
        let (cos1, cos2) = (c1.abs(), c2.abs());
        if cos1 == 0.0 || cos2 == 0.0 {
            return Err(NoAmplitude::Grazing { step: i });
        }
        let c = match step.kind {
            StepKind::Reflect if m_in != m => {
                // A converted wave: its tube narrows as a refraction's, its coefficient is
                // not modelled.
                out.cos_ratio *= cos2 / cos1;
                out.converted.get_or_insert(i);
                Complex64::new(1.0, 0.0)
            }
            StepKind::Reflect => match settings.reflection[step.interface] {
                Reflection::Fixed(r) => Complex64::new(r, 0.0),
                Reflection::Media => {
                    let across = medium_across(regions, line, step, seg, points[i], points[i + 1])
                        .ok_or(NoAmplitude::NoMediumAcross { step: i })?;
                    let sin2 = u_in.dot(t) * u_in.dot(t);
                    let ratio = w_in / media[across].slowness;
                    let weights = Weights::of(scene, settings, m_in, across);
                    weights.reflection(cos1, cos_across(ratio, sin2))
                }
            },
            StepKind::Refract => {
                out.cos_ratio *= cos2 / cos1;
                let weights = Weights::of(scene, settings, m_in, m);
                Complex64::new(weights.transmission(cos1, cos2), 0.0)
            }
        };
        out.coefficient *= c;
        out.reduced_length += l / w;
        out.attenuation_db += attenuation[m] * l;
        (u_in, inv_in, w_in) = (u, inv, w);
    }
    if !path.steps.is_empty() {
        // The receiver moved across the last leg by one unit: the right-hand side's one entry
        // (β, last row), the first point's move along its tangent, the first leg's turn.
        let beta = sweep.tangent.dot(u_in.perp()) * (w_in * inv_in);
        let x0 = beta * sweep.product / sweep.pivot;
        out.turn = (first_tangent.dot(u0.perp()) * x0 * inv0).abs();
    }
    Ok(out)
}

/// The medium across the interface of `step` at `here` (on segment `seg`) from `from`.
#[inline]
fn medium_across(
    regions: Option<&Regions>,
    line: &Polyline,
    step: &Step,
    seg: usize,
    from: Point,
    here: Point,
) -> Option<usize> {
    let (a, _) = line.segment(seg);
    let s = line.start(seg) + (here - a).dot(line.tangent(seg));
    regions?.medium_across(step.interface, seg, s, from)
}
