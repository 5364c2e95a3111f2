//! A ray of the sloped route (reflections through a `profile` medium off walls that are not
//! all flat and horizontal, `profile_slope.rs`) found again from what an entry says of it:
//! its points, its medium and its launch angle. Derivatives and curves start from these
//! (an entry keeps no legs): the path's rays are shot and solved again (remembered per
//! thread for the last path and pair) and the one through the entry's points is taken, its
//! legs each the profile's ray of one branch between two of the points.

use crate::geom::{Point, Vec2};
use crate::leg::Leg;
use crate::leg::profile::{Profile, RayPiece};
use crate::scene::{Scene, Step, StepKind};

use super::profile::default_choice;
use super::profile_slope::{SlopedRay, sloped_rays_cached, takes_sloped_route};

/// How far (relative to the box of the points) an entry's points may lie from a ray's to be
/// that ray's: the entry's points are the ray's own (to the digits written), so this only
/// forgives rounding.
const SAME_POINTS: f64 = 1e-9;

/// The ray of the sloped route of `steps` through the profile medium `medium` whose points
/// are `points` (source, reflections, receiver): of the path's rays through these points,
/// the one that leaves nearest `launch` (radians from +x) when given, else the default
/// mode's (the earliest no interface crosses, else the earliest). `None` when the path does
/// not take the sloped route or no ray passes through the points.
pub(crate) fn sloped_ray_found(
    scene: &Scene,
    steps: &[Step],
    points: &[Point],
    medium: usize,
    launch: Option<f64>,
) -> Option<SlopedRay> {
    if points.len() != steps.len() + 2 || !scene.curved() || !takes_sloped_route(scene, steps) {
        return None;
    }
    scene.media().get(medium)?.profile.as_ref()?;
    let (&s, &r) = (points.first()?, points.last()?);
    let scale = points
        .iter()
        .fold(0.0f64, |m, p| m.max((*p - s).length()))
        .max(1.0);
    let rays: Vec<SlopedRay> = sloped_rays_cached(scene, steps, medium, [s, r], None)
        .into_iter()
        .filter(|w| {
            w.points
                .iter()
                .zip(points)
                .all(|(a, b)| a.distance(*b) <= SAME_POINTS * scale)
        })
        .collect();
    match launch {
        Some(angle) => rays.into_iter().min_by(|a, b| {
            let off = |w: &SlopedRay| {
                let d = (w.launch_angle() - angle).rem_euclid(std::f64::consts::TAU);
                d.min(std::f64::consts::TAU - d)
            };
            off(a).total_cmp(&off(b))
        }),
        None => default_choice(&rays, |w| w.status).cloned(),
    }
}

/// The steps of a ray of reflections through `points` (source, reflection points,
/// receiver) as its points say them: each reflection point's interface, the one it lies on
/// (the nearest, within [`SAME_POINTS`] of the points' box). `None` when a point lies on
/// none.
pub(crate) fn reflections_through(scene: &Scene, points: &[Point]) -> Option<Vec<Step>> {
    let (&s, inner) = (
        points.first()?,
        points.get(1..points.len().checked_sub(1)?)?,
    );
    let scale = points
        .iter()
        .fold(0.0f64, |m, p| m.max((*p - s).length()))
        .max(1.0);
    inner
        .iter()
        .map(|&p| {
            let (interface, distance) = scene
                .interfaces()
                .iter()
                .enumerate()
                .map(|(i, itf)| (i, itf.polyline.nearest(p).distance))
                .filter(|(_, d)| d.is_finite())
                .min_by(|a, b| a.1.total_cmp(&b.1))?;
            (distance <= SAME_POINTS * scale).then_some(Step {
                kind: StepKind::Reflect,
                interface,
            })
        })
        .collect()
}

/// Each leg of `ray` (through the profile `profile`, without walls) as the pieces of its
/// own ray of the profile, from its start to its end (its ends put on the ray's points).
/// `None` when a leg's ray is not found again.
pub(crate) fn sloped_leg_pieces(profile: &Profile, ray: &SlopedRay) -> Option<Vec<Vec<RayPiece>>> {
    ray.legs
        .iter()
        .enumerate()
        .map(|(j, leg)| {
            let (a, b) = (ray.points[j].to_vec2(), ray.points[j + 1].to_vec2());
            let found = profile.leg_ray(a, b, leg.branch())?;
            let mut pieces = profile.pieces(&found, a, b);
            let last = pieces.len().checked_sub(1)?;
            (pieces[last].end_kind == crate::leg::profile::PieceEnd::Target).then_some(())?;
            pieces[0].start = a;
            pieces[last].end = b;
            Some(pieces)
        })
        .collect()
}

/// The derivatives of the time of a ray of the sloped route ([`sloped_derivatives`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SlopedDerivatives {
    /// `(dT/dx, dT/dy)` of the source (minus the first leg's slowness vector there) and of
    /// the receiver (the last leg's).
    pub source: Vec2,
    pub receiver: Vec2,
    /// `∂T/∂x` of each reflection point: the jump of the slowness vector there (the
    /// arriving leg's minus the leaving leg's; along the wall's normal where the ray is
    /// stationary).
    pub walls: Vec<Vec2>,
    /// `dT/dc` of each knot of the profile, in the profile's order (increasing `y`): each
    /// leg's, its ends held ([`Profile::knot_derivatives`]), summed.
    pub knots: Vec<f64>,
}

/// The derivatives of the time of the ray of the sloped route that
/// [`sloped_ray_found`] finds: by the envelope theorem (the ray is stationary in its
/// reflection points) each is the partial with the reflection points held, so the source's
/// and receiver's are the end legs' slowness vectors, a reflection point's the jump of the
/// slowness vector, a knot's the sum of each leg's between its held ends.
pub(crate) fn sloped_derivatives(
    scene: &Scene,
    steps: &[Step],
    points: &[Point],
    medium: usize,
    launch: Option<f64>,
) -> Option<SlopedDerivatives> {
    let profile = scene.media().get(medium)?.profile_model()?;
    let ray = sloped_ray_found(scene, steps, points, medium, launch)?;
    let (first, last) = (ray.legs.first()?, ray.legs.last()?);
    let mut knots: Vec<f64> = Vec::new();
    for (j, leg) in ray.legs.iter().enumerate() {
        let (a, b) = (ray.points[j].to_vec2(), ray.points[j + 1].to_vec2());
        let found = profile.leg_ray(a, b, leg.branch())?;
        let each = profile.knot_derivatives(&found, a.y, b.y);
        if knots.is_empty() {
            knots = each;
        } else {
            knots.iter_mut().zip(each).for_each(|(sum, d)| *sum += d);
        }
    }
    Some(SlopedDerivatives {
        source: first.departure() * -1.0,
        receiver: last.arrival(),
        walls: ray
            .legs
            .windows(2)
            .map(|w| w[0].arrival() - w[1].departure())
            .collect(),
        knots,
    })
}
