//! The legs of a drawn ray through a `gradient` medium as circular arcs: the speed
//! `c(p) = c₀ + g · p` is linear, so a leg from `a` to `b` is the arc of the circle through
//! both whose centre lies on the line `c = 0`, the minor arc (the half of the circle where
//! `c > 0`), sampled every degree (8 to 90 pieces a leg).

use eigenray::{Point, Scene, Vec2};

use super::entries::Item;

/// The points to draw `r` through, its arcs sampled: `None` when every leg is straight (a
/// scene without a gradient medium, or leg media not known), drawn through its points.
pub(super) fn sampled(scene: &Scene, r: &Item) -> Option<Vec<Point>> {
    let media = scene.media();
    if r.media.len() + 1 != r.points.len() {
        return None;
    }
    let arcs: Vec<Option<(Vec2, f64, f64)>> = r
        .points
        .windows(2)
        .zip(&r.media)
        .map(|(w, &m)| {
            let medium = media.get(m)?;
            arc(1.0 / medium.slowness, medium.gradient?, w[0], w[1])
        })
        .collect();
    if arcs.iter().all(Option::is_none) {
        return None;
    }
    let mut out = vec![r.points[0]];
    for (w, leg) in r.points.windows(2).zip(arcs) {
        if let Some((centre, from, sweep)) = leg {
            let radius = (w[0].to_vec2() - centre).length();
            let n = ((sweep.abs().to_degrees()).ceil() as usize).clamp(8, 90);
            for k in 1..n {
                let angle = from + sweep * k as f64 / n as f64;
                let p = centre + Vec2::new(angle.cos(), angle.sin()) * radius;
                out.push(Point::new(p.x, p.y));
            }
        }
        out.push(w[1]);
    }
    Some(out)
}

/// The arc from `a` to `b` in the speed `c₀ + g · p`: its centre, the angle of `a` from it,
/// and the signed angle it sweeps to `b`; `None` for a straight leg (`g` along the chord, or
/// the centre too far for the picture to tell the arc from its chord).
fn arc(c0: f64, g: Vec2, a: Point, b: Point) -> Option<(Vec2, f64, f64)> {
    let (a, b) = (a.to_vec2(), b.to_vec2());
    let chord = b - a;
    let normal = Vec2::new(-chord.y, chord.x);
    let mid = (a + b) * 0.5;
    let across = g.dot(normal);
    let c_mid = c0 + g.dot(mid);
    // The centre `mid + s normal` where the speed is 0.
    let s = -c_mid / across;
    if !s.is_finite() || s.abs() > 1e9 {
        return None;
    }
    let centre = mid + normal * s;
    let (u, v) = (a - centre, b - centre);
    let from = u.y.atan2(u.x);
    let sweep = (u.x * v.y - u.y * v.x).atan2(u.dot(v));
    Some((centre, from, sweep))
}
