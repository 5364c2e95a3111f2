//! The amplitude of one ray from its points and leg media: one pass over its interactions
//! that multiplies the coefficients, sums the attenuation and the out-of-plane width, and
//! runs the forward sweep of the tridiagonal solve that gives the in-plane width.

use std::f64::consts::PI;

use num_complex::Complex64;

use super::coefficients::{Weights, cos_across};
use super::{Amplitude, NoAmplitude};
use crate::geom::{Point, Vec2};
use crate::leg::{AnyLeg, Leg, LegModel, StraightLeg, Uniform};
use crate::polyline::Polyline;
use crate::regions::Regions;
use crate::scene::{Amplitudes, Reflection, Scene, SourceModel, Step, StepKind};

mod unfolded;
pub(crate) use unfolded::{
    AxisymmetricRun, BounceGroup, Incidence, LANES, NodeBounces, TreeLaws, UnfoldedLaws,
};

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

/// The segment of `line` that interaction point `i` at `p` lies on: the only one, the solve's
/// (in `segments`) when `p` lies on it (to round-off), else the nearest.
#[inline(always)]
fn segment_of(line: &Polyline, p: Point, segments: Option<&[usize]>, i: usize) -> usize {
    let n = line.num_segments();
    if n == 1 {
        return 0;
    }
    let hint = segments.and_then(|s| s.get(i).copied());
    if let Some(j) = hint.filter(|&j| j < n) {
        let a = line.segment(j).start;
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
    /// The tube's in-plane factor `Π (cos θ₂ / cos θ₁) / W` (the cosines' ratio over the
    /// interactions that change the medium, `W` the in-plane width `|∂x⊥/∂φ₀|`: how far the
    /// receiver moves across the last leg per unit turn of the take-off angle), as
    /// `tube_num / tube_den` (the one-interaction form gives it without a division).
    tube_num: f64,
    tube_den: f64,
    /// `w₀ Σ ℓⱼ / wⱼ`: the out-of-plane width of a point source (the out-of-plane slowness
    /// is conserved).
    out_of_plane: f64,
    /// `Σ αⱼ ℓⱼ` (dB).
    attenuation_db: f64,
    /// The first leg's length and slowness.
    l0: f64,
    w0: f64,
    /// The first converted reflection (legs in two media), which has no coefficient.
    converted: Option<usize>,
}

impl Walk {
    /// Interaction `x`'s plane-wave coefficient into the walk, and, where it changes medium,
    /// its cosine ratio into `cos_ratio` (a reflection that does is a converted wave).
    #[inline(always)]
    fn take(
        &mut self,
        cx: Context<'_>,
        x: &Interaction<'_>,
        cos_ratio: &mut f64,
    ) -> Result<(), NoAmplitude> {
        self.coefficient *= coefficient(cx, x)?;
        if changes_medium(x) {
            *cos_ratio *= x.cos2 / x.cos1;
            if matches!(x.step.kind, StepKind::Reflect) {
                self.converted.get_or_insert(x.i);
            }
        }
        Ok(())
    }
}

/// What the amplitude of one path reads besides the path.
#[derive(Clone, Copy)]
struct Context<'a> {
    scene: &'a Scene,
    settings: &'a Amplitudes,
    regions: Option<&'a Regions>,
}

/// One interaction as its coefficient sees it.
struct Interaction<'a> {
    /// Index of the step.
    i: usize,
    step: &'a Step,
    seg: usize,
    /// Where the incoming leg starts, and the interaction point.
    from: Point,
    here: Point,
    /// The incoming leg as a vector along it (its unit direction, or the leg itself) and that
    /// vector's length; the segment's tangent.
    leg_in: Vec2,
    len_in: f64,
    t: Vec2,
    /// `|cos θ|` of the incoming and the outgoing leg, both times `cos_scale` (> 0; a
    /// transmission coefficient depends on their ratio only).
    cos1: f64,
    cos2: f64,
    cos_scale: f64,
    /// The media of the two legs and their slownesses.
    m_in: usize,
    m: usize,
    w_in: f64,
    w: f64,
}

/// Whether the wave leaves interaction `x` in another medium than it came in (a refraction,
/// or a converted reflection): its tube's in-plane width then changes by `cos θ₂ / cos θ₁`.
#[inline(always)]
fn changes_medium(x: &Interaction<'_>) -> bool {
    matches!(x.step.kind, StepKind::Refract) || x.m_in != x.m
}

/// The coefficient of one interaction (1 on a converted reflection, whose coefficient is not
/// modelled: the caller notes it).
#[inline(always)]
fn coefficient(cx: Context<'_>, x: &Interaction<'_>) -> Result<Complex64, NoAmplitude> {
    let (cos1, cos2) = (x.cos1, x.cos2);
    if cos1 == 0.0 || cos2 == 0.0 {
        return Err(NoAmplitude::Grazing { step: x.i });
    }
    Ok(match x.step.kind {
        StepKind::Refract => {
            let weights = Weights::of(cx.settings, [x.m_in, x.m], [x.w_in, x.w]);
            Complex64::new(weights.transmission(cos1, cos2), 0.0)
        }
        // A converted wave: its coefficient is not modelled.
        StepKind::Reflect if x.m_in != x.m => Complex64::new(1.0, 0.0),
        // Pieces between vertices are walked on their own (`amplitude::diffraction`).
        StepKind::Diffract { .. } => return Err(NoAmplitude::UnknownMedia),
        StepKind::Reflect => match cx.settings.reflection[x.step.interface] {
            Reflection::Fixed(r) => Complex64::new(r, 0.0),
            Reflection::Media => {
                let line = &cx.scene.interfaces()[x.step.interface].polyline;
                let across = medium_across(cx.regions, line, x.step, x.seg, x.from, x.here)
                    .ok_or(NoAmplitude::NoMediumAcross { step: x.i })?;
                let along = x.leg_in.dot(x.t) / x.len_in;
                let w_across = cx.scene.media()[across].slowness;
                let weights = Weights::of(cx.settings, [x.m_in, across], [x.w_in, w_across]);
                let cos_in = cos1 / x.cos_scale;
                weights.reflection(cos_in, cos_across(x.w_in / w_across, along * along))
            }
        },
    })
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
    if scene.curved() {
        return of_curved_path(scene, settings, regions, path);
    }
    let cx = Context {
        scene,
        settings,
        regions,
    };
    match walk_straight(cx, path) {
        Ok(walk) => finish(cx, path.points, &walk),
        Err(reason) => diffracted_or_none(cx, path, reason),
    }
}

/// [`of_path`] in a scene without a gradient medium (every leg straight), for the tracer's
/// amplitude (always `Some`, its return): the uniform passes only ([`walk_straight`]), a
/// diffracted path (a step at a vertex) by [`of_diffracted`](super::of_diffracted).
#[inline(always)]
pub(crate) fn of_straight_path(
    scene: &Scene,
    settings: &Amplitudes,
    regions: Option<&Regions>,
    path: PathGeometry<'_>,
) -> Option<Amplitude> {
    let cx = Context {
        scene,
        settings,
        regions,
    };
    match walk_straight(cx, path) {
        Ok(walk) => Some(finish(cx, path.points, &walk)),
        Err(reason) => not_walked(cx, path, reason),
    }
}

/// The pass over a path whose legs are all straight: one interaction written out
/// ([`walk_one`]), reflections in one medium in closed form ([`walk_reflections`]), any other
/// path swept ([`walk`]). A path with a step at a vertex ends with a reason, at its
/// coefficient if not before.
#[inline(always)]
fn walk_straight(cx: Context<'_>, path: PathGeometry<'_>) -> Result<Walk, NoAmplitude> {
    let k = path.steps.len();
    match (path.steps, path.points, path.media) {
        ([step], &[p0, p1, p2], &[m0, m1]) => {
            let line = &cx.scene.interfaces()[step.interface].polyline;
            let seg = segment_of(line, p1, path.segments, 0);
            let at = OnSegment {
                seg,
                tangent: line.tangent(seg),
            };
            walk_one(cx, step, at, [p0, p1, p2], [m0, m1])
        }
        _ if path.points.len() != k + 2 || path.media.len() != k + 1 => {
            Err(NoAmplitude::UnknownMedia)
        }
        _ => walk_reflections(cx, path).map_or_else(|| walk(cx, path), Ok),
    }
}

/// [`diffracted_or_none`] as the tracer returns it (out of line).
#[cold]
#[inline(never)]
fn not_walked(cx: Context<'_>, path: PathGeometry<'_>, reason: NoAmplitude) -> Option<Amplitude> {
    Some(diffracted_or_none(cx, path, reason))
}

/// The amplitude of a path [`walk_straight`] ended with `reason`: a diffracted path's
/// ([`of_diffracted`](super::of_diffracted)), else none for `reason`.
#[cold]
fn diffracted_or_none(cx: Context<'_>, path: PathGeometry<'_>, reason: NoAmplitude) -> Amplitude {
    if path.steps.iter().any(|s| s.kind.vertex().is_some()) {
        return super::of_diffracted(cx.scene, cx.settings, cx.regions, path);
    }
    Amplitude::none(reason)
}

/// [`of_path`] in a scene with a gradient medium: every leg from its model
/// ([`walk_curved`]). Out of line, so that the straight passes' callers stay lean.
#[inline(never)]
fn of_curved_path(
    scene: &Scene,
    settings: &Amplitudes,
    regions: Option<&Regions>,
    path: PathGeometry<'_>,
) -> Amplitude {
    let cx = Context {
        scene,
        settings,
        regions,
    };
    let k = path.steps.len();
    let walked = if path.points.len() != k + 2 || path.media.len() != k + 1 {
        Err(NoAmplitude::UnknownMedia)
    } else {
        walk_curved(cx, path)
    };
    match walked {
        Ok(walk) => finish(cx, path.points, &walk),
        Err(reason) => Amplitude::none(reason),
    }
}

/// The segment an interaction point lies on, and its unit tangent.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OnSegment {
    /// The segment's index in its polyline.
    pub seg: usize,
    /// Its unit tangent.
    pub tangent: Vec2,
}

/// [`of_path`] for a path of one interaction (`step`, on `at`), its points and leg media
/// given: what a solve that knows the interaction's segment calls.
#[inline(always)]
pub(crate) fn of_one(
    scene: &Scene,
    settings: &Amplitudes,
    regions: Option<&Regions>,
    step: &Step,
    at: OnSegment,
    points: [Point; 3],
    media: [usize; 2],
) -> Amplitude {
    let cx = Context {
        scene,
        settings,
        regions,
    };
    if scene.curved() {
        let path = PathGeometry {
            steps: std::slice::from_ref(step),
            points: &points,
            media: &media,
            segments: Some(std::slice::from_ref(&at.seg)),
        };
        return of_path(scene, settings, regions, path);
    }
    match walk_one(cx, step, at, points, media) {
        Ok(walk) => finish(cx, &points, &walk),
        Err(reason) => Amplitude::none(reason),
    }
}

/// The amplitude from what the pass over `path` gathered.
#[inline(always)]
fn finish(cx: Context<'_>, points: &[Point], walk: &Walk) -> Amplitude {
    finish_with(cx.settings, walk, || {
        out_of_plane_axisymmetric(points, walk.l0)
    })
}

/// [`finish`] with the axisymmetric out-of-plane width from `axisymmetric` (asked for that
/// source model only; `None`: the point source's, `walk.out_of_plane`; an error: no
/// amplitude, for its reason).
#[inline(always)]
fn finish_with(
    settings: &Amplitudes,
    walk: &Walk,
    axisymmetric: impl FnOnce() -> Result<Option<f64>, NoAmplitude>,
) -> Amplitude {
    let w0 = walk.w0;
    // spreading = √(Π cos θ₂/cos θ₁ / (W Y)) / (4π), or √(… / W) / √(8π k₀) for a line, whose
    // amplitude also takes the phase e^(iπ/4) of the 2-D Green's function's far field.
    let quarter = 0.25 / PI;
    let (out, scale) = match settings.source {
        SourceModel::Point => (walk.out_of_plane, quarter),
        SourceModel::Axisymmetric => match axisymmetric() {
            Ok(out) => (out.unwrap_or(walk.out_of_plane), quarter),
            Err(reason) => return Amplitude::none(reason),
        },
        SourceModel::Line => {
            let k0 = 2.0 * PI * settings.frequency.unwrap_or(f64::NAN) * w0;
            (k0, 1.0 / (8.0 * PI).sqrt())
        }
    };
    let mut spreading = (walk.tube_num / (walk.tube_den * out)).sqrt() * scale;
    if !positive_finite(spreading) {
        // A degenerate tube gives 0, ∞ or NaN; so does a product that overflows.
        spreading = spreading_scaled(walk.tube_num, walk.tube_den, out, scale);
        if !positive_finite(spreading) {
            return Amplitude::none(NoAmplitude::Caustic);
        }
    }
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
    let mut size = spreading;
    if walk.attenuation_db > 0.0 {
        // 10^(−dB/20).
        size *= (walk.attenuation_db * (-std::f64::consts::LN_10 / 20.0)).exp();
    }
    let value = match settings.source {
        SourceModel::Line => {
            let h = std::f64::consts::FRAC_1_SQRT_2 * size;
            walk.coefficient * Complex64::new(h, h)
        }
        SourceModel::Point | SourceModel::Axisymmetric => walk.coefficient * size,
    };
    Amplitude {
        value,
        spreading,
        coefficient: walk.coefficient,
        attenuation_db: walk.attenuation_db,
        reason: None,
    }
}

/// The spreading `√(num / (den · out)) · scale` with each factor's square root taken first,
/// for the tube whose product `den · out` overflows or underflows (media whose speeds differ
/// by far more than any material's): out of line, never taken where the direct form has a
/// number.
#[cold]
#[inline(never)]
fn spreading_scaled(num: f64, den: f64, out: f64, scale: f64) -> f64 {
    num.sqrt() / den.sqrt() / out.sqrt() * scale
}

/// Whether `x` is a positive finite number, in one integer comparison of its bits (the
/// positive finite doubles are the bit patterns 1 to `0x7fef_ffff_ffff_ffff`).
#[inline(always)]
pub(crate) fn positive_finite(x: f64) -> bool {
    x.to_bits().wrapping_sub(1) < f64::MAX.to_bits()
}

/// What the amplitude of a diffracted path takes from each of its pieces (the specular paths
/// between its source, its vertices and its receiver): [`walk`]'s gatherings.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PieceWalk {
    /// The product of the piece's coefficients.
    pub coefficient: Complex64,
    /// Its in-plane tube factor `Π (cos θ₂ / cos θ₁) / W` (`1 / ℓ` for one straight leg).
    pub tube: f64,
    /// `w₀ Σ ℓⱼ / wⱼ` over its legs, `w₀` its first leg's slowness.
    pub out_of_plane: f64,
    /// Its attenuation (dB).
    pub attenuation_db: f64,
    /// Its first leg's length and slowness.
    pub l0: f64,
    pub w0: f64,
}

/// The pass over one piece of a diffracted path: a specular path from `path.points[0]` (the
/// source or a vertex) to its last point, as [`of_path`] walks a whole path.
pub(crate) fn walk_piece(
    scene: &Scene,
    settings: &Amplitudes,
    regions: Option<&Regions>,
    path: PathGeometry<'_>,
) -> Result<PieceWalk, NoAmplitude> {
    let k = path.steps.len();
    if path.points.len() != k + 2 || path.media.len() != k + 1 {
        return Err(NoAmplitude::UnknownMedia);
    }
    let cx = Context {
        scene,
        settings,
        regions,
    };
    let w = walk(cx, path)?;
    if let Some(step) = w.converted {
        return Err(NoAmplitude::ConvertedReflection { step });
    }
    Ok(PieceWalk {
        coefficient: w.coefficient,
        tube: w.tube_num / w.tube_den,
        out_of_plane: w.out_of_plane,
        attenuation_db: w.attenuation_db,
        l0: w.l0,
        w0: w.w0,
    })
}

/// The out-of-plane width of an axisymmetric scene, `|x_R| / |t₀ₓ|` with `t₀` the first leg's
/// direction (`ℓ₀` its length); `None` for a path along the axis (the point source's width is
/// the limit there).
#[inline(never)]
pub(crate) fn out_of_plane_axisymmetric(
    points: &[Point],
    l0: f64,
) -> Result<Option<f64>, NoAmplitude> {
    if points[0].x != 0.0 {
        return Err(NoAmplitude::SourceOffAxis);
    }
    let side = points[1].x - points[0].x;
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
    Ok(Some(range * l0 / side.abs()))
}

/// The slowness of medium `m`.
#[inline(always)]
fn slowness(scene: &Scene, m: usize) -> Result<f64, NoAmplitude> {
    scene
        .media()
        .get(m)
        .map(|m| m.slowness)
        .ok_or(NoAmplitude::UnknownMedia)
}

/// [`walk`] for a path of one interaction in uniform media (straight legs, the legs' cosines
/// with the normal from [`Uniform::leg_across`]), written out: its Hessian is one number, so the
/// in-plane width is `W = (w₀ c₀² ℓ₁ + w₁ c₁² ℓ₀) / (w₁ |c₀ c₁|)` (`cⱼ` the cosines of the legs
/// with the normal), and the tube's factor `(cos θ₂ / cos θ₁) / W` is `c₁² / D` across a change
/// of medium and `|c₀ c₁| / D` on a reflection, with `D = q c₀² ℓ₁ + c₁² ℓ₀` and `q = w₀ / w₁`.
/// The squared cosines' divisions run beside the legs' square roots, and `q`'s beside both:
/// after the square roots, one division (the coefficient's) and the spreading's.
#[inline(always)]
fn walk_one(
    cx: Context<'_>,
    step: &Step,
    at: OnSegment,
    points: [Point; 3],
    [m0, m1]: [usize; 2],
) -> Result<Walk, NoAmplitude> {
    let (w0, w1) = (slowness(cx.scene, m0)?, slowness(cx.scene, m1)?);
    let t = at.tangent;
    let n = t.perp();
    let d0 = points[1] - points[0];
    let across =
        |d: Vec2, leg: usize| Uniform::leg_across(d, n).ok_or(NoAmplitude::VanishedLeg { leg });
    let (leg0, leg1) = (across(d0, 0)?, across(points[2] - points[1], 1)?);
    let (l0, l1) = (leg0.length, leg1.length);
    let (cc0, cc1) = (leg0.cos_squared, leg1.cos_squared);
    let attenuation_db = if cx.settings.attenuates {
        let a = &cx.settings.attenuation;
        a[m0] * l0 + a[m1] * l1
    } else {
        0.0
    };
    let q = w0 / w1;
    let x = Interaction {
        i: 0,
        step,
        seg: at.seg,
        from: points[0],
        here: points[1],
        leg_in: d0,
        len_in: l0,
        t,
        // |cos θⱼ| ℓ₀ℓ₁.
        cos1: (leg0.across * l1).abs(),
        cos2: (leg1.across * l0).abs(),
        cos_scale: l0 * l1,
        m_in: m0,
        m: m1,
        w_in: w0,
        w: w1,
    };
    let coefficient = coefficient(cx, &x)?;
    let crosses = changes_medium(&x);
    Ok(Walk {
        coefficient,
        tube_num: if crosses { cc1 } else { (cc0 * cc1).sqrt() },
        tube_den: q * cc0 * l1 + cc1 * l0,
        out_of_plane: l0 + l1 * q,
        attenuation_db,
        l0,
        w0,
        converted: (crosses && matches!(step.kind, StepKind::Reflect)).then_some(0),
    })
}

/// One pass over the path's interactions: the coefficients, the lengths, and the forward
/// sweep of the tridiagonal solve `H x = e_{k−1} β` with the Hessian `H` of the time at the
/// solved points (Thomas' elimination, kept for the first unknown only:
/// `x₀ = β Π_{i<k−1} (−hᵢ,ᵢ₊₁ / rᵢ) / r_{k−1}` with `rᵢ` the pivots).
fn walk(cx: Context<'_>, path: PathGeometry<'_>) -> Result<Walk, NoAmplitude> {
    let (points, legs) = (path.points, path.media);
    let w0 = slowness(cx.scene, legs[0])?;
    let first = Uniform::new(w0)
        .valid_leg(points[0], points[1])
        .ok_or(NoAmplitude::VanishedLeg { leg: 0 })?;
    let (l0, inv0) = (first.len, first.inv_len);
    let attenuation = &cx.settings.attenuation;
    let mut out = Walk {
        coefficient: Complex64::new(1.0, 0.0),
        // The direct path: W = ℓ₀.
        tube_num: 1.0,
        tube_den: l0,
        // (The first leg's `out_of_plane_width(w₀)`.)
        out_of_plane: l0,
        attenuation_db: attenuation[legs[0]] * l0,
        l0,
        w0,
        converted: None,
    };
    // `Π cos θ₂ / cos θ₁` over the interactions that change the medium.
    let mut cos_ratio = 1.0;
    let mut incoming: StraightLeg = first;
    // The sweep: the last pivot, the product so far, the previous tangent; the first cosine.
    let (mut pivot, mut product, mut prev) = (1.0, 1.0, Vec2::default());
    let mut first_cos = 0.0;
    // Each step with its two legs' media and the three points about it.
    let around = legs.windows(2).zip(points.windows(3));
    for (i, (step, (media, near))) in path.steps.iter().zip(around).enumerate() {
        let (m_in, m) = (media[0], media[1]);
        let w = slowness(cx.scene, m)?;
        let leg = Uniform::new(w)
            .valid_leg(near[1], near[2])
            .ok_or(NoAmplitude::VanishedLeg { leg: i + 1 })?;
        let w_in = incoming.slowness;
        let line = &cx.scene.interfaces()[step.interface].polyline;
        let seg = segment_of(line, near[1], path.segments, i);
        let t = line.tangent(seg);
        let n = t.perp();
        let u_in = incoming.direction_at_end();
        let (c1, c2) = (u_in.dot(n), leg.direction_at_start().dot(n));
        // Row i of the Hessian, and the forward sweep through it.
        let diag = incoming.end_block(t) + leg.start_block(t);
        let r = if i == 0 {
            first_cos = c1;
            diag
        } else {
            let off = incoming.coupling_projected(prev, t);
            product *= -off / pivot;
            diag - off * off / pivot
        };
        if !(r > 0.0 && r < f64::INFINITY) {
            return Err(NoAmplitude::Caustic);
        }
        (pivot, prev) = (r, t);
        let x = Interaction {
            i,
            step,
            seg,
            from: near[0],
            here: near[1],
            leg_in: u_in,
            len_in: 1.0,
            t,
            cos1: c1.abs(),
            cos2: c2.abs(),
            cos_scale: 1.0,
            m_in,
            m,
            w_in,
            w,
        };
        out.take(cx, &x, &mut cos_ratio)?;
        out.out_of_plane += leg.out_of_plane_width(w0);
        out.attenuation_db += attenuation[m] * leg.len;
        incoming = leg;
    }
    if !path.steps.is_empty() {
        // The receiver moved across the last leg by one unit: the right-hand side's one entry
        // β = (t_{k−1} · n_k) w_k / ℓ_k, the first point's move x₀ along its tangent, and the
        // first leg's turn (t₀ · n₀) x₀ / ℓ₀ (n the legs' normals; t · n = −(u · t⊥)): the
        // inverse of W.
        let beta =
            prev.dot(incoming.direction_at_end().perp()) * (incoming.slowness * incoming.inv_len);
        let x0 = beta * product / pivot;
        out.tube_num = cos_ratio * (first_cos * x0 * inv0).abs();
        out.tube_den = 1.0;
    }
    Ok(out)
}

/// [`walk`] for the commonest path: reflections only, every leg straight in one uniform
/// medium (a scene without a gradient, whose walls are straight segments), two or more of
/// them. Such a path is the straight line from the source's image, so its tube has a closed
/// form in the unfolded length `L = Σ ℓⱼ`: the in-plane width is `W = L` (no sweep), the
/// point source's out-of-plane width `w₀ Σ ℓⱼ / wⱼ` is `L`, the axisymmetric one
/// ([`out_of_plane_axisymmetric`]) already depends on the first leg and the receiver's range
/// only, and a line source's on neither; the attenuation is `α L`. Each bounce still takes
/// its coefficient from the incoming leg's direction and the wall's normal.
///
/// `None` (the caller takes [`walk`]) for any other path, and for one that `walk` would
/// end with a reason (a vanished or unusual leg, a grazing leg, a coefficient without a
/// value), so that reasons stay [`walk`]'s. Equal to [`walk`] to round-off (its tests).
#[inline]
fn walk_reflections(cx: Context<'_>, path: PathGeometry<'_>) -> Option<Walk> {
    let (points, legs, steps) = (path.points, path.media, path.steps);
    let m0 = *legs.first()?;
    // (`legs` has one more than `steps`.)
    if steps.len() < 2
        || (steps.iter().zip(&legs[1..]))
            .any(|(s, &m)| !matches!(s.kind, StepKind::Reflect) || m != m0)
    {
        return None;
    }
    let w0 = slowness(cx.scene, m0).ok()?;
    // The unit direction and length of the leg from `a` to `b` as `Uniform::valid_leg` gives
    // them (the same bits), `None` for a leg of zero, tiny or huge length.
    let leg = |a: Point, b: Point| {
        let d = b - a;
        let l2 = d.x * d.x + d.y * d.y;
        (f64::MIN_POSITIVE..1e300).contains(&l2).then(|| {
            let l = l2.sqrt();
            (d * (1.0 / l), l)
        })
    };
    let (mut u_in, l0) = leg(points[0], points[1])?;
    let mut length = l0;
    let mut product = Complex64::new(1.0, 0.0);
    for (i, step) in steps.iter().enumerate() {
        let (u, l) = leg(points[i + 1], points[i + 2])?;
        let line = &cx.scene.interfaces()[step.interface].polyline;
        let seg = segment_of(line, points[i + 1], path.segments, i);
        let t = line.tangent(seg);
        let n = t.perp();
        let (c1, c2) = (u_in.dot(n), u.dot(n));
        if c1 == 0.0 || c2 == 0.0 {
            return None;
        }
        let x = Interaction {
            i,
            step,
            seg,
            from: points[i],
            here: points[i + 1],
            leg_in: u_in,
            len_in: 1.0,
            t,
            cos1: c1.abs(),
            cos2: c2.abs(),
            cos_scale: 1.0,
            m_in: m0,
            m: m0,
            w_in: w0,
            w: w0,
        };
        product *= coefficient(cx, &x).ok()?;
        length += l;
        u_in = u;
    }
    Some(Walk {
        coefficient: product,
        tube_num: 1.0,
        tube_den: length,
        out_of_plane: length,
        attenuation_db: cx.settings.attenuation[m0] * length,
        l0,
        w0,
        converted: None,
    })
}

/// [`walk`] for a path whose legs may be curved (a scene with a gradient medium): the same
/// pass, each leg from its model ([`crate::leg::LegMedium`], relative to the source), with
/// what a straight leg has in closed form taken from the leg's Hessian blocks:
///
/// - the receiver moved by one unit across its arriving direction `n_r` moves the last
///   residual by `β = coupling(last leg, t_{k−1}, n_r)`; the sweep gives the first point's
///   move `x₀`, and the source's departure turns by `c_s coupling(first leg, n_s, t₀) x₀`:
///   `1 / W` (the direct ray: `c_s |coupling(n_s, n_r)|`; for a straight leg `1/ℓ`);
/// - along each leg the speed changes, so the tube's energy flux adds `c_end / c_start`;
/// - each negative pivot of the sweep is a caustic the tube has passed (the Morse index of
///   the path's Hessian, `design/curved-rays.md` §5): its phase, `−π/2` each, multiplies
///   the coefficient; a pivot within `1e-6` of its row's scale is too near a caustic for
///   ray theory ([`NoAmplitude::Caustic`]);
/// - the slownesses at an interaction, for its coefficient, are the local ones; the
///   attenuation is per unit of arc length; the axisymmetric width takes the departure's
///   direction (through `l0`, see [`out_of_plane_axisymmetric`]).
fn walk_curved(cx: Context<'_>, path: PathGeometry<'_>) -> Result<Walk, NoAmplitude> {
    let points = path.points;
    let origin = points[0];
    let media = cx.scene.media();
    let model = |m: usize| media[m].leg_model(origin);
    let leg_of = |j: usize, m: usize| {
        model(m)
            .valid_leg(
                (points[j] - origin).to_point(),
                (points[j + 1] - origin).to_point(),
            )
            .ok_or(NoAmplitude::VanishedLeg { leg: j })
    };
    walk_legs(cx, path, leg_of)
}

/// [`walk_curved`]'s pass with each leg `j` (in medium `m`) from `leg_of(j, m)`: any leg
/// model, a profile's rays included (each leg's own caustics, those of its tube from its
/// start, add to the sweep's: the Morse index of a broken ray is its pieces' and its
/// break points' Hessian's).
fn walk_legs(
    cx: Context<'_>,
    path: PathGeometry<'_>,
    leg_of: impl Fn(usize, usize) -> Result<AnyLeg, NoAmplitude>,
) -> Result<Walk, NoAmplitude> {
    let (points, legs) = (path.points, path.media);
    let media = cx.scene.media();
    let local = |m: usize, p: Point| 1.0 / media[m].speed_at(p);
    let arc_length = |leg: &AnyLeg| leg.arc_length();
    let own_caustics = |leg: &AnyLeg| leg.profile().map_or(0, |l| l.caustics);
    let w0 = local(legs[0], points[0]);
    let first = leg_of(0, legs[0])?;
    let mut caustics = own_caustics(&first);
    let attenuation = &cx.settings.attenuation;
    let d0 = first.direction_at_start();
    // The axisymmetric width |x_R| / |d₀ₓ| as `range · l0 / side`.
    let side = (points[1].x - points[0].x).abs();
    let l0 = if d0.x != 0.0 {
        side / d0.x.abs()
    } else {
        first.len()
    };
    let mut out = Walk {
        coefficient: Complex64::new(1.0, 0.0),
        tube_num: 1.0,
        tube_den: 1.0,
        out_of_plane: first.out_of_plane_width(w0),
        attenuation_db: attenuation[legs[0]] * arc_length(&first),
        l0,
        w0,
        converted: None,
    };
    let mut flux = local(legs[0], points[0]) / local(legs[0], points[1]);
    let mut cos_ratio = 1.0;
    let mut incoming = first;
    let mut sweep = Sweep::default();
    let mut t0 = Vec2::default();
    for (i, step) in path.steps.iter().enumerate() {
        let (m_in, m) = (legs[i], legs[i + 1]);
        let leg = leg_of(i + 1, m)?;
        let here = points[i + 1];
        let (w_in, w) = (local(m_in, here), local(m, here));
        let line = &cx.scene.interfaces()[step.interface].polyline;
        let seg = segment_of(line, here, path.segments, i);
        let t = line.tangent(seg);
        let n = t.perp();
        let u_in = incoming.direction_at_end();
        let (c1, c2) = (u_in.dot(n), leg.direction_at_start().dot(n));
        if i == 0 {
            t0 = t;
        }
        sweep.pivot(i, &incoming, &leg, t)?;
        let x = Interaction {
            i,
            step,
            seg,
            from: points[i],
            here,
            leg_in: u_in,
            len_in: 1.0,
            t,
            cos1: c1.abs(),
            cos2: c2.abs(),
            cos_scale: 1.0,
            m_in,
            m,
            w_in,
            w,
        };
        out.take(cx, &x, &mut cos_ratio)?;
        caustics += own_caustics(&leg);
        out.out_of_plane += leg.out_of_plane_width(w0);
        out.attenuation_db += attenuation[m] * arc_length(&leg);
        flux *= local(m, here) / local(m, points[i + 2]);
        incoming = leg;
    }
    let n_s = d0.perp();
    let n_r = incoming.direction_at_end().perp();
    let inverse_width = if path.steps.is_empty() {
        first.coupling(n_s, n_r).abs() / w0
    } else {
        let beta = incoming.coupling(sweep.prev, n_r);
        let x0 = beta * sweep.product / sweep.pivot;
        (first.coupling(n_s, t0) * x0).abs() / w0
    };
    // `flux` is Π c_start / c_end in slownesses: c_end / c_start.
    out.tube_num = cos_ratio * flux * inverse_width;
    out.tube_den = 1.0;
    let caustics = caustics + sweep.caustics;
    if caustics > 0 {
        let phase = -std::f64::consts::FRAC_PI_2 * f64::from(caustics);
        out.coefficient *= Complex64::from_polar(1.0, phase);
    }
    Ok(out)
}

/// The amplitude of a path of reflections through a profile medium (every leg the
/// medium's) whose legs are `legs` (`leg/profile/leg.rs`, each its branch's ray between
/// its points): [`walk_curved`]'s pass with these legs, and the caustics it counted (the
/// legs' own and the sweep's negative pivots) beside it.
pub(crate) fn of_profile_legs(
    scene: &Scene,
    settings: &Amplitudes,
    regions: Option<&Regions>,
    path: PathGeometry<'_>,
    legs: &[crate::leg::profile::ProfileLeg],
) -> Amplitude {
    let cx = Context {
        scene,
        settings,
        regions,
    };
    let points = path.points;
    match walk_legs(cx, path, |j, _| Ok(AnyLeg::Profile(legs[j]))) {
        Ok(walk) => finish(cx, points, &walk),
        Err(reason) => Amplitude::none(reason),
    }
}

/// The caustics of a path of reflections through a profile medium whose legs are `legs`:
/// the legs' own (their tubes from their starts) and the negative pivots of the sweep over
/// its reflections (`None` at a caustic).
pub(crate) fn caustics_of_profile_legs(
    scene: &Scene,
    path: PathGeometry<'_>,
    legs: &[crate::leg::profile::ProfileLeg],
) -> Option<u32> {
    let mut sweep = Sweep::default();
    for (i, step) in path.steps.iter().enumerate() {
        let line = &scene.interfaces().get(step.interface)?.polyline;
        let seg = segment_of(line, path.points[i + 1], path.segments, i);
        let (a, b) = (AnyLeg::Profile(legs[i]), AnyLeg::Profile(legs[i + 1]));
        sweep.pivot(i, &a, &b, line.tangent(seg)).ok()?;
    }
    Some(sweep.caustics + legs.iter().map(|l| l.caustics).sum::<u32>())
}

/// The forward sweep of the LDLᵀ factorisation of a curved path's tridiagonal Hessian (its
/// rows the interaction points' moves along their tangents), one row per interaction.
struct Sweep {
    /// The last pivot.
    pivot: f64,
    /// The product of `−off / pivot` over the rows after the first.
    product: f64,
    /// The last row's tangent.
    prev: Vec2,
    /// The negative pivots so far (the caustics the tube has passed).
    caustics: u32,
}

impl Default for Sweep {
    fn default() -> Self {
        Sweep {
            pivot: 1.0,
            product: 1.0,
            prev: Vec2::default(),
            caustics: 0,
        }
    }
}

impl Sweep {
    /// Row `i`: the interaction between `incoming` and `leg` on the tangent `t`.
    /// [`NoAmplitude::Caustic`] for a pivot within `1e-6` of its row's scale.
    #[inline]
    fn pivot(
        &mut self,
        i: usize,
        incoming: &AnyLeg,
        leg: &AnyLeg,
        t: Vec2,
    ) -> Result<(), NoAmplitude> {
        let diag = incoming.end_block(t) + leg.start_block(t);
        let (r, scale) = if i == 0 {
            (diag, diag.abs())
        } else {
            let off = incoming.coupling(self.prev, t);
            self.product *= -off / self.pivot;
            (
                diag - off * off / self.pivot,
                diag.abs() + (off * off / self.pivot).abs(),
            )
        };
        if !(r.abs() > 1e-6 * scale && r.is_finite()) {
            return Err(NoAmplitude::Caustic);
        }
        self.caustics += u32::from(r < 0.0);
        (self.pivot, self.prev) = (r, t);
        Ok(())
    }
}

/// The number of caustics the ray tube of a solved path through a scene with a `gradient`
/// medium passed: the Morse index of its Hessian (the negative pivots of [`walk_curved`]'s
/// sweep, `design/curved-rays.md` §5). `None` for a scene without a gradient medium, a path
/// whose points or media do not fit its steps, one that diffracts or has a leg through a
/// `profile` medium, a vanished leg, or a path at a caustic.
pub(crate) fn caustics_of_path(scene: &Scene, path: PathGeometry<'_>) -> Option<u32> {
    let (points, legs) = (path.points, path.media);
    let k = path.steps.len();
    let media = scene.media();
    if !media.iter().any(|m| m.gradient.is_some())
        || path.steps.iter().any(|s| s.kind.vertex().is_some())
        || points.len() != k + 2
        || legs.len() != k + 1
        || legs
            .iter()
            .any(|&m| media.get(m).is_none_or(|m| m.profile.is_some()))
    {
        return None;
    }
    let origin = points[0];
    let leg_of = |j: usize, m: usize| {
        media[m].leg_model(origin).valid_leg(
            (points[j] - origin).to_point(),
            (points[j + 1] - origin).to_point(),
        )
    };
    let mut incoming = leg_of(0, legs[0])?;
    let mut sweep = Sweep::default();
    for (i, step) in path.steps.iter().enumerate() {
        let leg = leg_of(i + 1, legs[i + 1])?;
        let line = &scene.interfaces().get(step.interface)?.polyline;
        let seg = segment_of(line, points[i + 1], path.segments, i);
        sweep.pivot(i, &incoming, &leg, line.tangent(seg)).ok()?;
        incoming = leg;
    }
    Some(sweep.caustics)
}

/// The amplitude of one ray through a `profile` medium from `points[0]` to `points[1]`
/// (`leg/profile.rs`), the pass of [`walk_curved`] for one leg with what it reads of the
/// leg's Hessian in the ray-parameter form: `1 / W = c_s ‖∂²T/∂a∂b‖ = c_s / (|∂X/∂p| s_a s_b)`,
/// the flux `c_r / c_s`, the out-of-plane width `w₀ ∫ c ds`, the attenuation per arc length,
/// and `−π/2` for each caustic the tube passed (the zeros of `Q`, counted by the kernel).
pub(crate) fn of_profile(
    scene: &Scene,
    settings: &Amplitudes,
    regions: Option<&Regions>,
    points: [Point; 2],
    medium: usize,
    ray: &crate::leg::profile::ProfileRay,
    reflections: &[ProfileReflection<'_>],
) -> Amplitude {
    let cx = Context {
        scene,
        settings,
        regions,
    };
    let [cs, cr] = ray.speeds;
    let w0 = 1.0 / cs;
    let d0 = ray.direction_at_start();
    let side = (points[1].x - points[0].x).abs();
    let l0 = if d0.x != 0.0 {
        side / d0.x.abs()
    } else {
        ray.sums.arc
    };
    let mut coefficient = Complex64::new(1.0, 0.0);
    if ray.caustics > 0 {
        let phase = -std::f64::consts::FRAC_PI_2 * f64::from(ray.caustics);
        coefficient *= Complex64::from_polar(1.0, phase);
    }
    let line_of = |r: &ProfileReflection<'_>| &scene.interfaces()[r.step.interface].polyline;
    for (i, r) in reflections.iter().enumerate() {
        // A flat horizontal wall: the cosine of incidence is the sine of the ray's angle
        // with the horizontal there, the tangent's component the horizontal slowness's.
        let w = 1.0 / r.speed;
        let x = Interaction {
            i,
            step: r.step,
            seg: r.segment,
            from: r.from,
            here: r.here,
            leg_in: r.direction,
            len_in: 1.0,
            t: line_of(r).tangent(r.segment),
            cos1: r.sine,
            cos2: r.sine,
            cos_scale: 1.0,
            m_in: medium,
            m: medium,
            w_in: w,
            w,
        };
        match self::coefficient(cx, &x) {
            Ok(c) => coefficient *= c,
            Err(reason) => return Amplitude::none(reason),
        }
    }
    let walk = Walk {
        coefficient,
        tube_num: (cr / cs) * ray.inverse_width(),
        tube_den: 1.0,
        out_of_plane: w0 * ray.sums.width,
        attenuation_db: cx.settings.attenuation[medium] * ray.sums.arc,
        l0,
        w0,
        converted: None,
    };
    finish(cx, &points, &walk)
}

/// One reflection of a ray through a `profile` medium at a flat horizontal wall, as its
/// coefficient sees it.
pub(crate) struct ProfileReflection<'a> {
    /// The step, and the segment of its interface.
    pub step: &'a Step,
    pub segment: usize,
    /// The point before it on the path (for the side of a `"media"` reflection), and its
    /// own point.
    pub from: Point,
    pub here: Point,
    /// The ray's unit direction arriving there, the sine of its angle with the
    /// horizontal (> 0) and the speed there.
    pub direction: Vec2,
    pub sine: f64,
    pub speed: f64,
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
    let a = line.segment(seg).start;
    let s = line.start(seg) + (here - a).dot(line.tangent(seg));
    regions?.medium_across(step.interface, seg, s, from)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::SplitMix64;
    use crate::regions::Regions;

    /// A refraction, a reflection and a converted reflection at one tilted segment (fluids).
    fn scene(amplitudes: &str) -> Scene {
        Scene::from_json(&format!(
            r#"{{ "media": {{ "a": {{ "speed": 1, "density": 1.2 }},
                             "b": {{ "speed": 1.7, "density": 2.5 }} }},
                 "interfaces": {{ "tilted": {{ "points": [[-3, -1], [9, 2]],
                                               "reflection": {{ "absorption": 0.3 }} }} }},
                 "sources": [[0, 2]], "receivers": [[1, -2]],
                 "paths": [{{ "steps": [{{ "refract": "tilted" }}], "media": ["a", "b"] }},
                           {{ "steps": [{{ "reflect": "tilted" }}], "media": ["a", "a"] }},
                           {{ "steps": [{{ "reflect": "tilted" }}], "media": ["a", "b"] }}],
                 "amplitudes": {amplitudes} }}"#
        ))
        .unwrap()
    }

    /// The relative difference of two numbers (0 when equal).
    fn rel(a: f64, b: f64) -> f64 {
        if a == b {
            0.0
        } else {
            (a - b).abs() / a.abs().max(b.abs())
        }
    }

    /// The written-out form of one interaction (`walk_one`: no sweep, its divisions moved)
    /// against the general pass (`walk`: the forward sweep through a Hessian of one row) on
    /// random points, for every source model and kind of step.
    #[test]
    fn the_one_interaction_form_is_the_sweep() {
        let mut rng = SplitMix64(31);
        let mut worst = 0.0f64;
        for model in [
            r#"{ "source": "point" }"#,
            r#"{ "source": "axisymmetric" }"#,
            r#"{ "source": "line", "frequency": 3 }"#,
        ] {
            let s = scene(model);
            let settings = s.amplitudes().unwrap();
            let cx = Context {
                scene: &s,
                settings,
                regions: None,
            };
            let line = &s.interfaces()[0].polyline;
            let at = OnSegment {
                seg: 0,
                tangent: line.tangent(0),
            };
            for path in s.paths() {
                let legs = path.media.as_ref().unwrap();
                let media = [legs[0], legs[1]];
                for _ in 0..200 {
                    let mut u = || rng.next_f64();
                    let source = Point::new(0.0, 2.0 + 3.0 * u());
                    let here = line.point_on(0, line.length() * (0.3 + 0.6 * u()));
                    let receiver = Point::new(8.0 * u() + 0.5, 4.0 * u() - 2.0);
                    let points = [source, here, receiver];
                    let one = of_one(&s, settings, None, &path.steps[0], at, points, media);
                    let geometry = PathGeometry {
                        steps: &path.steps,
                        points: &points,
                        media: &media,
                        segments: None,
                    };
                    let swept = match walk(cx, geometry) {
                        Ok(w) => finish(cx, &points, &w),
                        Err(reason) => Amplitude::none(reason),
                    };
                    assert_eq!(one.reason, swept.reason, "{model} {points:?}");
                    assert!(one.spreading > 0.0, "{model} {points:?}");
                    let mut errors = vec![
                        rel(one.spreading, swept.spreading),
                        rel(one.attenuation_db, swept.attenuation_db),
                    ];
                    if one.has_value() {
                        for (a, b) in [
                            (one.value, swept.value),
                            (one.coefficient, swept.coefficient),
                        ] {
                            errors.push((a - b).norm() / a.norm());
                        }
                    }
                    for e in errors {
                        assert!(e < 1e-13, "{model} {points:?}: {e:e}");
                        worst = worst.max(e);
                    }
                }
            }
        }
        println!("one interaction against the sweep: {worst:.3e}");
    }

    /// The general pass (`walk`, the sweep) on `path`, finished.
    fn swept(cx: Context<'_>, path: PathGeometry<'_>) -> Amplitude {
        match walk(cx, path) {
            Ok(w) => finish(cx, path.points, &w),
            Err(reason) => Amplitude::none(reason),
        }
    }

    /// The largest relative difference of two amplitudes' numbers (their reasons equal).
    fn amplitude_error(a: &Amplitude, b: &Amplitude) -> f64 {
        assert_eq!(a.reason, b.reason);
        // Without a tube (a reason before the spreading) both are NaN.
        let same = |x: f64, y: f64| {
            if x.is_nan() && y.is_nan() {
                0.0
            } else {
                rel(x, y)
            }
        };
        let mut e = same(a.spreading, b.spreading).max(same(a.attenuation_db, b.attenuation_db));
        if a.has_value() {
            for (x, y) in [(a.value, b.value), (a.coefficient, b.coefficient)] {
                if x != y {
                    e = e.max((x - y).norm() / x.norm().max(y.norm()));
                }
            }
        }
        e
    }

    /// `p` mirrored in the line through `a` along the unit `t`.
    fn mirror(p: Point, a: Point, t: Vec2) -> Point {
        let d = p - a;
        a + (t * (2.0 * d.dot(t)) - d)
    }

    /// The reflection points of the path from `source` to `receiver` off the walls
    /// `walls` (indices of `corners`' edges, the polygon closed) by the image method: `None`
    /// when a point falls outside its edge's middle or the image is on the wrong side.
    fn image_path(
        corners: &[Point],
        walls: &[usize],
        source: Point,
        receiver: Point,
    ) -> Option<Vec<Point>> {
        let edge = |j: usize| (corners[j], corners[(j + 1) % corners.len()]);
        let mut images = vec![source];
        for &j in walls {
            let (a, b) = edge(j);
            let last = *images.last().unwrap();
            images.push(mirror(last, a, (b - a) * (1.0 / (b - a).length())));
        }
        let mut points = vec![receiver];
        let mut target = receiver;
        for (k, &j) in walls.iter().enumerate().rev() {
            let (a, b) = edge(j);
            let image = images[k + 1];
            // image + s (target − image) on the line a + r (b − a).
            let (d, e) = (target - image, b - a);
            let den = d.cross(e);
            if den == 0.0 {
                return None;
            }
            let s = (a - image).cross(e) / den;
            let r = (a - image).cross(d) / den;
            if !(0.01..0.99).contains(&s) || !(0.02..0.98).contains(&r) {
                return None;
            }
            target = a + e * r;
            points.push(target);
        }
        points.push(source);
        points.reverse();
        Some(points)
    }

    /// The path shot from `source` at `angle` through `bounces` specular reflections inside
    /// the convex polygon `corners`, its receiver halfway along the last leg, and the edge of
    /// each bounce; `None` when one lands within 2 % of a corner.
    fn shot_path(
        corners: &[Point],
        source: Point,
        angle: f64,
        bounces: usize,
    ) -> Option<(Vec<Point>, Vec<usize>)> {
        let n = corners.len();
        let (mut p, mut u) = (source, Vec2::new(angle.cos(), angle.sin()));
        let (mut points, mut walls) = (vec![source], Vec::new());
        let mut last = usize::MAX;
        for _ in 0..=bounces {
            // The nearest edge ahead.
            let mut hit: Option<(f64, usize, f64)> = None;
            for j in (0..n).filter(|&j| j != last) {
                let (a, b) = (corners[j], corners[(j + 1) % n]);
                let e = b - a;
                let den = u.cross(e);
                if den == 0.0 {
                    continue;
                }
                let s = (a - p).cross(e) / den;
                let r = (a - p).cross(u) / den;
                if s > 1e-9 && (0.0..=1.0).contains(&r) && hit.is_none_or(|h| s < h.0) {
                    hit = Some((s, j, r));
                }
            }
            let (s, j, r) = hit?;
            if walls.len() == bounces {
                points.push(p + u * (0.5 * s));
                return Some((points, walls));
            }
            if !(0.02..0.98).contains(&r) {
                return None;
            }
            let (a, b) = (corners[j], corners[(j + 1) % n]);
            let t = (b - a) * (1.0 / (b - a).length());
            p = a + (b - a) * r;
            u = t * (2.0 * u.dot(t)) - u;
            points.push(p);
            walls.push(j);
            last = j;
        }
        None
    }

    /// A scene of one closed convex room (`corners`) of air, rock outside, the walls'
    /// reflection `law`, the amplitudes `model`.
    fn room(corners: &[Point], law: &str, model: &str, source: Point) -> Scene {
        let points: Vec<String> = corners
            .iter()
            .map(|p| format!("[{}, {}]", p.x, p.y))
            .collect();
        Scene::from_json(&format!(
            r#"{{ "media": {{ "air": {{ "speed": 343, "density": 1.2, "attenuation": 0.01 }},
                             "rock": {{ "speed": 900, "density": 2.1, "at": [40, 40] }} }},
                 "background": "air", "domain": [[-50, -50], [50, 50]],
                 "interfaces": {{ "room": {{ "points": [{}], "closed": true,
                                            "reflection": {law} }} }},
                 "sources": [[{}, {}]], "receivers": [[1, 0]],
                 "paths": [{{ "steps": [{{ "reflect": "room" }}], "media": ["air", "air"] }}],
                 "amplitudes": {model} }}"#,
            points.join(", "),
            source.x,
            source.y
        ))
        .unwrap()
    }

    /// The closed form for reflections only in one medium (`walk_reflections`: the unfolded
    /// length, no sweep) against the general pass (`walk`) on image-method paths of up to
    /// 12 bounces and shot paths of up to 80 in random convex rooms, for every source model and several reflection
    /// laws (with the medium's attenuation, and `"media"` against the rock outside).
    #[test]
    fn the_unfolded_form_is_the_sweep() {
        let mut rng = SplitMix64(39);
        let (mut worst, mut compared, mut fast) = (0.0f64, 0usize, 0usize);
        let models = [
            r#"{ "source": "point" }"#,
            r#"{ "source": "axisymmetric" }"#,
            r#"{ "source": "line", "frequency": 300 }"#,
        ];
        let laws = [
            r#""rigid""#,
            r#"{ "absorption": 0.37 }"#,
            r#""pressure-release""#,
            r#""media""#,
        ];
        for round in 0..24 {
            // A convex polygon: corners on an ellipse at sorted random angles, about a centre
            // right of the axis (the axisymmetric source on it, inside the room).
            let n = 3 + (rng.next_f64() * 5.0) as usize;
            let mut angles: Vec<f64> = (0..n)
                .map(|j| (j as f64 + 0.2 + 0.6 * rng.next_f64()) * 2.0 * PI / n as f64)
                .collect();
            angles.sort_by(f64::total_cmp);
            let (ax, ay) = (4.0 + 6.0 * rng.next_f64(), 3.0 + 5.0 * rng.next_f64());
            let centre = Point::new(0.5 * ax, 0.3 * rng.next_f64());
            let corners: Vec<Point> = angles
                .iter()
                .map(|a| Point::new(centre.x + ax * a.cos(), centre.y + ay * a.sin()))
                .collect();
            let model = models[round % models.len()];
            let law = laws[(round / models.len()) % laws.len()];
            let source = Point::new(0.0, centre.y + 0.2 * ay * (rng.next_f64() - 0.5));
            let scene = room(&corners, law, model, source);
            let regions = Regions::build(&scene).unwrap();
            let settings = scene.amplitudes().unwrap();
            let cx = Context {
                scene: &scene,
                settings,
                regions: Some(&regions),
            };
            let mut found = 0;
            for _ in 0..4000 {
                if found == 60 {
                    break;
                }
                let receiver = Point::new(
                    centre.x + 0.5 * ax * (rng.next_f64() - 0.3),
                    centre.y + 0.5 * ay * (rng.next_f64() - 0.5),
                );
                // Image-method paths of up to 12 bounces, shot paths of up to 80.
                let (points, walls) = if found % 2 == 0 {
                    let k = 2 + (rng.next_f64() * 11.0) as usize;
                    let mut walls = vec![(rng.next_f64() * n as f64) as usize % n];
                    while walls.len() < k {
                        let step = 1 + (rng.next_f64() * (n - 1) as f64) as usize;
                        walls.push((walls[walls.len() - 1] + step) % n);
                    }
                    let Some(points) = image_path(&corners, &walls, source, receiver) else {
                        continue;
                    };
                    (points, walls)
                } else {
                    let k = 2 + (rng.next_f64() * 79.0) as usize;
                    let Some(shot) = shot_path(&corners, source, 2.0 * PI * rng.next_f64(), k)
                    else {
                        continue;
                    };
                    shot
                };
                let k = walls.len();
                found += 1;
                let steps = vec![
                    Step {
                        kind: StepKind::Reflect,
                        interface: 0,
                    };
                    k
                ];
                let media = vec![0; k + 1];
                let hinted = found % 2 == 0;
                let path = PathGeometry {
                    steps: &steps,
                    points: &points,
                    media: &media,
                    segments: hinted.then_some(&walls[..]),
                };
                fast += usize::from(walk_reflections(cx, path).is_some());
                let (a, b) = (
                    of_path(&scene, settings, Some(&regions), path),
                    swept(cx, path),
                );
                let e = amplitude_error(&a, &b);
                assert!(e <= 1e-12, "{model} {law} {points:?}: {e:e}");
                worst = worst.max(e);
                compared += usize::from(a.has_value());
            }
        }
        assert!(compared > 500 && fast > 1000, "{compared} {fast}");
        println!("unfolded against the sweep: {worst:.3e} over {compared} values");
    }

    /// The closed form against the image sources of a flat waveguide (two horizontal
    /// walls; every image on the axis, so that the axisymmetric tube is the point
    /// source's): `Π R / (4π L)` with `L` the distance from the image, and for a line
    /// source `Π R e^(iπ/4) / √(8π k₀ L)`.
    #[test]
    fn the_unfolded_form_is_the_image_source() {
        let corners = [
            Point::new(-30.0, -8.0),
            Point::new(30.0, -8.0),
            Point::new(30.0, 0.0),
            Point::new(-30.0, 0.0),
        ];
        let mut rng = SplitMix64(7);
        let mut worst = 0.0f64;
        for (model, law, r) in [
            (
                r#"{ "source": "point" }"#,
                r#"{ "absorption": 0.36 }"#,
                0.8f64,
            ),
            (
                r#"{ "source": "axisymmetric" }"#,
                r#""pressure-release""#,
                -1.0,
            ),
            (
                r#"{ "source": "line", "frequency": 300 }"#,
                r#""rigid""#,
                1.0,
            ),
        ] {
            let source = Point::new(0.0, -3.0);
            let scene = room(&corners, law, model, source);
            let settings = scene.amplitudes().unwrap();
            for _ in 0..200 {
                let receiver = Point::new(0.5 + 20.0 * rng.next_f64(), -7.5 + 7.0 * rng.next_f64());
                let k = 2 + (rng.next_f64() * 10.0) as usize;
                let first = usize::from(rng.next_f64() < 0.5);
                // Floor (edge 0) and ceiling (edge 2) in turn.
                let walls: Vec<usize> = (0..k).map(|j| 2 * ((first + j) % 2)).collect();
                let Some(points) = image_path(&corners, &walls, source, receiver) else {
                    continue;
                };
                let mut image = source;
                for &j in &walls {
                    image = Point::new(image.x, if j == 0 { -16.0 - image.y } else { -image.y });
                }
                let l = (receiver - image).length();
                let attenuation = 10f64.powf(-0.01 * l / 20.0);
                let product = r.powi(k as i32) * attenuation;
                let expected = if model.contains("line") {
                    let k0 = 2.0 * PI * 300.0 / 343.0;
                    Complex64::new(1.0, 1.0) * (product / (16.0 * PI * k0 * l).sqrt())
                } else {
                    Complex64::new(product / (4.0 * PI * l), 0.0)
                };
                let steps = vec![
                    Step {
                        kind: StepKind::Reflect,
                        interface: 0,
                    };
                    k
                ];
                let media = vec![0; k + 1];
                let path = PathGeometry {
                    steps: &steps,
                    points: &points,
                    media: &media,
                    segments: None,
                };
                let a = of_path(&scene, settings, None, path);
                let e = (a.value - expected).norm() / expected.norm();
                assert!(e < 1e-12, "{model} {points:?}: {e:e}");
                worst = worst.max(e);
            }
        }
        println!("unfolded against the image sources: {worst:.3e}");
    }
}
