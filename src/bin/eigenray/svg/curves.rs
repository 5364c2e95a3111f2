//! The curved legs of a drawn ray: through a `gradient` medium circular arcs, through a
//! `profile` medium the ray itself (a circular arc per layer, through its turning points and
//! its reflections), sampled on the ray by the library's [`ray_curve`]: 64 points a leg and
//! two more per degree the ray turns (from a first, coarse sampling), at most 4,000.

use eigenray::trace::ray_curve;
use eigenray::{Point, Scene};

use super::entries::Item;

/// The most points drawn on one ray.
const MOST_POINTS: usize = 4000;

/// The points to draw `r` through, its curved legs sampled: `None` in a scene without a
/// `gradient` or `profile` medium (every leg straight, drawn through its points), or when
/// the ray's curve cannot be found again (drawn through its points).
pub(super) fn sampled(scene: &Scene, r: &Item) -> Option<Vec<Point>> {
    if !scene.curved() || r.media.len() + 1 != r.points.len() {
        return None;
    }
    let media = scene.media();
    let curved = r.media.iter().any(|&m| {
        media
            .get(m)
            .is_some_and(|m| m.gradient.is_some() || m.profile.is_some())
    });
    if !curved {
        return None;
    }
    let legs = r.media.len();
    let coarse = ray_curve(scene, &r.points, &r.media, r.launch_angle, 1 + 16 * legs).ok()?;
    let n = (2 * turn_degrees(&coarse).ceil() as usize + 64 * legs + 1)
        .clamp(coarse.len(), MOST_POINTS);
    if n == coarse.len() {
        return Some(coarse);
    }
    ray_curve(scene, &r.points, &r.media, r.launch_angle, n).ok()
}

/// The total turn of a polyline, degrees: the sum of the angles between its pieces.
fn turn_degrees(points: &[Point]) -> f64 {
    let turns = points.windows(3).map(|w| {
        let (u, v) = (w[1] - w[0], w[2] - w[1]);
        (u.x * v.y - u.y * v.x).atan2(u.dot(v)).abs()
    });
    turns.filter(|t| t.is_finite()).sum::<f64>().to_degrees()
}
