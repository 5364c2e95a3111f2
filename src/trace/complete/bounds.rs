//! The certain bounds of the residuals over a tuple of places, which prune the search.

use std::f64::consts::PI;

use crate::geom::{Aabb, Point, Vec2};

use super::place::{CONE_PAD, Place};

/// The directions of a leg between two places on one interface whose boxes touch: a point
/// `y` after `x` along the polyline has `y − x` a sum of non-negative multiples of the
/// tangents between them, so for adjacent or overlapping ranges of segments the direction lies
/// in the arc of their tangent angles (`both`: or in the opposite arc, when either point may
/// come first). `None` when the ranges are apart or the arc is not narrower than π.
#[derive(Clone, Copy, Debug)]
struct Chord {
    /// Unit vectors at the arc's ends (counter-clockwise from `ends[0]`).
    ends: [Vec2; 2],
    /// Whether the opposite arc is possible too.
    both: bool,
    /// Whether the arc is reversed (the second point comes first along the polyline).
    reversed: bool,
}

fn chord(a: &Place, b: &Place) -> Option<Chord> {
    if a.interface != b.interface || a.interface == usize::MAX {
        return None;
    }
    let (forward, backward) = (a.end <= b.first, b.end <= a.first);
    let overlap = !forward && !backward;
    let adjacent = a.end == b.first || b.end == a.first || overlap;
    if !adjacent {
        return None;
    }
    let lo = a.cone[0].min(b.cone[0]) - CONE_PAD;
    let hi = a.cone[1].max(b.cone[1]) + CONE_PAD;
    if hi - lo >= PI || (hi - lo).is_nan() {
        return None;
    }
    Some(Chord {
        ends: [Vec2::new(lo.cos(), lo.sin()), Vec2::new(hi.cos(), hi.sin())],
        both: overlap,
        reversed: backward,
    })
}

/// The range of `u · t` over the unit vectors `u` of the arc from `e0` counter-clockwise to
/// `e1` (narrower than π).
fn arc_dot_range(e0: Vec2, e1: Vec2, t: Vec2) -> [f64; 2] {
    let within = |v: Vec2| e0.cross(v) >= 0.0 && v.cross(e1) >= 0.0;
    let (a, b) = (e0.dot(t), e1.dot(t));
    let hi = if within(t) { 1.0 } else { a.max(b) };
    let lo = if within(-t) { -1.0 } else { a.min(b) };
    [lo - 1e-12, hi + 1e-12]
}

/// What bounds the directions of one leg.
#[derive(Clone, Copy, Debug)]
enum LegBound {
    Box(Legs),
    Arc(Chord),
    Unknown,
}

impl LegBound {
    /// The ranges of `u · t` (two for a chord that may run either way).
    fn dot_ranges(self, t: Vec2) -> ([f64; 2], Option<[f64; 2]>) {
        match self {
            LegBound::Box(l) => (dot_range(l, t), None),
            LegBound::Arc(c) => {
                let [e0, e1] = c.ends;
                let fwd = arc_dot_range(e0, e1, t);
                let back = arc_dot_range(-e0, -e1, t);
                match (c.both, c.reversed) {
                    (true, _) => (fwd, Some(back)),
                    (false, false) => (fwd, None),
                    (false, true) => (back, None),
                }
            }
            LegBound::Unknown => ([-1.0, 1.0], None),
        }
    }
}

/// Every difference of a point of `to` and a point of `from`: a box, with the round-off of
/// its corners against its distance from the origin (the error of a direction taken from it);
/// `None` when the boxes touch (a leg between them may vanish: no bound).
#[derive(Clone, Copy, Debug)]
struct Legs {
    d: Aabb,
    pad: f64,
    /// The directions of the box's corners.
    corners: [Vec2; 4],
}

fn legs(from: Aabb, to: Aabb) -> Option<Legs> {
    let d = Aabb {
        min: Point::new(to.min.x - from.max.x, to.min.y - from.max.y),
        max: Point::new(to.max.x - from.min.x, to.max.y - from.min.y),
    };
    let near = d.distance_sq(Point::new(0.0, 0.0)).sqrt();
    if near.is_nan() || near <= 0.0 {
        return None;
    }
    let scale = [from.min, from.max, to.min, to.max]
        .iter()
        .fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
    let pad = 1e-12 + 16.0 * f64::EPSILON * scale / near;
    // (A square that overflows, far beyond the scene's coordinates: no bound.)
    let big = [d.min.x, d.min.y, d.max.x, d.max.y]
        .iter()
        .any(|c| c.abs() >= 1e150 || c.is_nan());
    if big {
        return None;
    }
    let unit = |x: f64, y: f64| {
        let l = (x * x + y * y).sqrt();
        Vec2::new(x / l, y / l)
    };
    let corners = [
        unit(d.min.x, d.min.y),
        unit(d.max.x, d.min.y),
        unit(d.min.x, d.max.y),
        unit(d.max.x, d.max.y),
    ];
    pad.is_finite().then_some(Legs { d, pad, corners })
}

/// Whether the ray from the origin along `t` meets the box `d`.
fn ray_meets(t: Vec2, d: Aabb) -> bool {
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    for (t, a, b) in [(t.x, d.min.x, d.max.x), (t.y, d.min.y, d.max.y)] {
        if t == 0.0 {
            if a > 0.0 || b < 0.0 {
                return false;
            }
        } else {
            let (p, q) = (a / t, b / t);
            lo = lo.max(p.min(q));
            hi = hi.min(p.max(q));
        }
    }
    lo <= hi
}

/// The range of `u · t` over the unit directions `u` of the differences in `legs`: at the
/// corners (the extreme directions of a box that misses the origin), or ±1 where the
/// directions pass through `±t`.
fn dot_range(legs: Legs, t: Vec2) -> [f64; 2] {
    let d = legs.d;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for c in legs.corners {
        let c = c.dot(t);
        lo = lo.min(c);
        hi = hi.max(c);
    }
    if ray_meets(t, d) {
        hi = 1.0;
    }
    if ray_meets(-t, d) {
        lo = -1.0;
    }
    [lo - legs.pad, hi + legs.pad]
}

/// Whether the places of the points (with the source and receiver around them) hold no
/// stationary path: for some point the bound of `rᵢ = (wᵢ uᵢ − wᵢ₊₁ uᵢ₊₁) · tᵢ` excludes zero,
/// `rᵢ` within `(wᵢ uᵢ − wᵢ₊₁ uᵢ₊₁) · t₀ ± (wᵢ + wᵢ₊₁) |tᵢ − t₀|`.
pub(super) fn pruned(places: &[Place], source: Point, receiver: Point, w: &[f64]) -> bool {
    let k = places.len();
    let end = |p: Point| Aabb::from_points(p, p);
    let bbox = |i: usize| match i {
        0 => end(source),
        i if i == k + 1 => end(receiver),
        i => places[i - 1].bbox,
    };
    // Leg `l` joins point l − 1 and point l (0: the source; k + 1: the receiver).
    let leg = |l: usize| match legs(bbox(l), bbox(l + 1)) {
        Some(b) => LegBound::Box(b),
        None if l >= 1 && l < k => {
            chord(&places[l - 1], &places[l]).map_or(LegBound::Unknown, LegBound::Arc)
        }
        None => LegBound::Unknown,
    };
    let mut before = leg(0);
    for i in 0..k {
        let after = leg(i + 1);
        if !matches!(before, LegBound::Unknown) && !matches!(after, LegBound::Unknown) {
            let (t, spread) = (places[i].tangent, places[i].spread);
            let (wa, wb) = (w[i], w[i + 1]);
            let slack = (wa + wb) * spread + 1e-10 * (wa + wb);
            let excludes = |a: [f64; 2], b: [f64; 2]| {
                wa * a[0] - wb * b[1] - slack > 0.0 || wa * a[1] - wb * b[0] + slack < 0.0
            };
            let (a0, a1) = before.dot_ranges(t);
            let (b0, b1) = after.dot_ranges(t);
            let all = [Some(a0), a1]
                .into_iter()
                .flatten()
                .all(|a| [Some(b0), b1].into_iter().flatten().all(|b| excludes(a, b)));
            if all {
                return true;
            }
        }
        before = after;
    }
    false
}
