//! The curve of a ray, sampled: `n` points on the ray itself, from its source through its
//! interaction points to its receiver, for pictures and for whatever a caller measures along
//! a ray. A straight leg is its chord; a leg through a `gradient` medium its circular arc
//! ([`ArcLeg::offset_at`]); a ray through a `profile` medium the ray the profile traced (found
//! again by its launch angle, or by the default mode's rule), piece by piece: a circular arc
//! per layer, through its turning points and its reflections at the walls
//! ([`RayPiece::at`]); a ray reflected off walls that are not all flat and horizontal (the
//! sloped route) leg by leg, each leg its own ray of the profile between its two points
//! (the ray found again by its points, its reflections' interfaces read off them). Every
//! point is on the ray to rounding: the arcs' points are their closed forms at an arc
//! length, a profile's its closed-form range at a height.

use std::fmt;

use crate::geom::Point;
use crate::leg::profile::{PieceEnd, RayPiece};
use crate::leg::{ArcLeg, LegModel};
use crate::scene::{Scene, Step};

use super::profile::profile_ray_between;
use super::profile_slope::takes_sloped_route;
use super::sloped_found::{reflections_through, sloped_leg_pieces, sloped_ray_found};

/// Why a ray's curve could not be sampled.
#[derive(Clone, Debug, PartialEq)]
pub enum CurveError {
    /// Fewer than two points, or a point that is not finite (a ray without a time).
    Points,
    /// Fewer samples asked (`n`) than the ray has points (`least`): each point is a sample.
    TooFewSamples {
        /// The samples asked for.
        n: usize,
        /// The ray's points.
        least: usize,
    },
    /// No ray of the profile medium `medium` joins the points (leaving at the launch angle
    /// given): the scene changed since the ray was traced, or the points are not a ray's.
    NoProfileRay {
        /// The medium's name.
        medium: String,
    },
}

impl fmt::Display for CurveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CurveError::Points => write!(
                f,
                "a curve needs at least two finite points (a ray with a time)"
            ),
            CurveError::TooFewSamples { n, least } => write!(
                f,
                "n = {n} samples are fewer than the ray's {least} points (each is a sample)"
            ),
            CurveError::NoProfileRay { medium } => write!(
                f,
                "no ray of the profile medium \"{medium}\" joins these points at this launch angle"
            ),
        }
    }
}

impl std::error::Error for CurveError {}

/// The shape of one leg (between two consecutive points of a ray).
enum LegShape {
    /// A straight leg.
    Straight(Point, Point),
    /// A circular arc from its start, with its arc length.
    Arc(Point, ArcLeg, f64),
    /// A profile's pieces, with their arc lengths summed from the start (one more entry
    /// than pieces).
    Pieces(Vec<RayPiece>, Vec<f64>),
}

impl LegShape {
    /// Its arc length.
    fn length(&self) -> f64 {
        match self {
            LegShape::Straight(a, b) => (*b - *a).length(),
            LegShape::Arc(_, _, len) => *len,
            LegShape::Pieces(_, sums) => sums.last().copied().unwrap_or(0.0),
        }
    }

    /// The point at the fraction `f` (0 < f < 1) of its arc length.
    fn at(&self, f: f64) -> Point {
        match self {
            LegShape::Straight(a, b) => *a + (*b - *a) * f,
            LegShape::Arc(a, arc, len) => *a + arc.offset_at(f * len),
            LegShape::Pieces(pieces, sums) => {
                let s = f * sums[sums.len() - 1];
                let i = sums[1..]
                    .partition_point(|&end| end < s)
                    .min(pieces.len() - 1);
                let len = sums[i + 1] - sums[i];
                let g = if len > 0.0 { (s - sums[i]) / len } else { 1.0 };
                let v = pieces[i].at(g);
                Point::new(v.x, v.y)
            }
        }
    }
}

/// `n` points on the ray through `points` (its source, its interaction points, its
/// receiver) whose legs lie in the media `media` (indices into [`Scene::media`]; a leg
/// whose medium is not known, or a `media` of another length than the legs, is drawn
/// straight), in `scene`: the first the source, the last the receiver, and every
/// interaction point among them; each leg gets a share of the `n − 1` steps in proportion
/// to its arc length (at least one), its points evenly spaced in arc length. A ray through
/// a `profile` medium is the one that leaves at `launch_angle` (radians from +x, the
/// `launch_angle` its entry gives), or without one the one the default mode chose.
pub fn ray_curve(
    scene: &Scene,
    points: &[Point],
    media: &[usize],
    launch_angle: Option<f64>,
    n: usize,
) -> Result<Vec<Point>, CurveError> {
    if points.len() < 2 || !points.iter().all(|p| p.is_finite()) {
        return Err(CurveError::Points);
    }
    if n < points.len() {
        return Err(CurveError::TooFewSamples {
            n,
            least: points.len(),
        });
    }
    let legs = leg_shapes(scene, points, media, launch_angle)?;
    let lengths: Vec<f64> = legs.iter().map(LegShape::length).collect();
    let mut out = Vec::with_capacity(n);
    out.push(points[0]);
    for (i, (leg, steps)) in legs.iter().zip(shares(&lengths, n - 1)).enumerate() {
        out.extend((1..steps).map(|j| leg.at(j as f64 / steps as f64)));
        out.push(points[i + 1]);
    }
    Ok(out)
}

/// `total` steps (at least one per leg) shared among legs of `lengths` in proportion to
/// them, the remainder to the largest fractions (evenly when the lengths say nothing).
fn shares(lengths: &[f64], total: usize) -> Vec<usize> {
    let legs = lengths.len();
    let sum: f64 = lengths.iter().sum();
    let extra = total - legs;
    let weight = |l: f64| {
        if sum.is_finite() && sum > 0.0 {
            l / sum
        } else {
            1.0 / legs as f64
        }
    };
    let quotas: Vec<f64> = lengths.iter().map(|&l| extra as f64 * weight(l)).collect();
    let mut out: Vec<usize> = quotas.iter().map(|q| 1 + q.floor() as usize).collect();
    let given: usize = out.iter().sum();
    let mut order: Vec<usize> = (0..legs).collect();
    order.sort_by(|&i, &j| {
        (quotas[j] - quotas[j].floor()).total_cmp(&(quotas[i] - quotas[i].floor()))
    });
    for &i in order.iter().cycle().take(total.saturating_sub(given)) {
        out[i] += 1;
    }
    out
}

/// Each leg's shape: a profile medium's ray as a whole, split at its reflections; else leg
/// by leg, an arc through a `gradient` medium and a straight line otherwise.
fn leg_shapes(
    scene: &Scene,
    points: &[Point],
    media: &[usize],
    launch_angle: Option<f64>,
) -> Result<Vec<LegShape>, CurveError> {
    let legs = points.len() - 1;
    let known = media.len() == legs;
    let medium = |i: usize| {
        known
            .then(|| media[i])
            .and_then(|m| scene.media().get(m).map(|medium| (m, medium)))
    };
    if let Some((m, medium)) = medium(0)
        && medium.profile.is_some()
    {
        return profile_legs(scene, points, m, launch_angle);
    }
    let origin = points[0];
    Ok((0..legs)
        .map(|i| {
            let (a, b) = (points[i], points[i + 1]);
            match medium(i) {
                Some((_, medium)) if medium.gradient.is_some() => {
                    match medium.leg_model(origin).leg(a - origin, b - origin).arc() {
                        Some(arc) if arc.len > 0.0 => LegShape::Arc(a, *arc, arc.arc_length()),
                        _ => LegShape::Straight(a, b),
                    }
                }
                _ => LegShape::Straight(a, b),
            }
        })
        .collect())
}

/// The legs of a ray through the profile medium `m`: its pieces, split at its reflections,
/// each leg's ends put on the given points (the ray's own to its refinement).
fn profile_legs(
    scene: &Scene,
    points: &[Point],
    m: usize,
    launch_angle: Option<f64>,
) -> Result<Vec<LegShape>, CurveError> {
    let missing = || CurveError::NoProfileRay {
        medium: scene.media()[m].name.clone(),
    };
    if let Some(steps) = reflections_through(scene, points)
        && takes_sloped_route(scene, &steps)
    {
        return sloped_legs(scene, &steps, points, m, launch_angle).ok_or_else(missing);
    }
    let (profile, ray) = profile_ray_between(scene, points, m, launch_angle).ok_or_else(missing)?;
    let (a, b) = (points[0].to_vec2(), points[points.len() - 1].to_vec2());
    let pieces = profile.pieces(&ray, a, b);
    if pieces.last().map(|p| p.end_kind) != Some(PieceEnd::Target) {
        return Err(missing());
    }
    let mut legs = Vec::with_capacity(points.len() - 1);
    let mut current: Vec<RayPiece> = Vec::new();
    for piece in pieces {
        let ends_leg = matches!(piece.end_kind, PieceEnd::Wall | PieceEnd::Target);
        current.push(piece);
        if ends_leg {
            legs.push(std::mem::take(&mut current));
        }
    }
    if legs.len() != points.len() - 1 {
        return Err(missing());
    }
    Ok(legs
        .into_iter()
        .enumerate()
        .map(|(i, mut leg)| {
            leg[0].start = points[i].to_vec2();
            let last = leg.len() - 1;
            leg[last].end = points[i + 1].to_vec2();
            pieces_shape(leg)
        })
        .collect())
}

/// The legs of a ray of the sloped route (reflections of `steps` through the profile medium
/// `m` off walls not all flat and horizontal): each leg's own ray of the profile, piece by
/// piece, its ends on the given points. `None` when no ray of the path passes through them.
fn sloped_legs(
    scene: &Scene,
    steps: &[Step],
    points: &[Point],
    m: usize,
    launch_angle: Option<f64>,
) -> Option<Vec<LegShape>> {
    let profile = scene.media()[m].profile_model()?;
    let ray = sloped_ray_found(scene, steps, points, m, launch_angle)?;
    let legs = sloped_leg_pieces(&profile, &ray)?;
    Some(legs.into_iter().map(pieces_shape).collect())
}

/// The shape of one leg of a profile's pieces (its arc lengths summed).
fn pieces_shape(leg: Vec<RayPiece>) -> LegShape {
    let mut sums = vec![0.0];
    for piece in &leg {
        sums.push(sums[sums.len() - 1] + piece.arc_length());
    }
    LegShape::Pieces(leg, sums)
}
