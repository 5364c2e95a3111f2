//! What a point of a tuple may be: a box of positions and a cone of tangents.

use std::f64::consts::PI;

use crate::geom::{Aabb, Vec2};

/// Widening of every tangent cone (rad): the round-off of the unwrapped angles.
pub(super) const CONE_PAD: f64 = 1e-9;

/// What a point of a tuple may be: a box, and tangents `t` with `|t − tangent| ≤ spread`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Place {
    /// The box of the points.
    pub(super) bbox: Aabb,
    /// The middle tangent `t₀` of the cone.
    pub(super) tangent: Vec2,
    /// The bound of `|t − t₀|` over the cone's tangents.
    pub(super) spread: f64,
    /// The interface (set by the search; `usize::MAX` in a hierarchy's nodes).
    pub(super) interface: usize,
    /// The segments `first..end` whose points (and first vertex) the place holds, and the
    /// range of their tangent angles.
    pub(super) first: usize,
    /// See `first`.
    pub(super) end: usize,
    /// See `first`.
    pub(super) cone: [f64; 2],
}

impl Place {
    /// The place of points in `bbox` on segments `first..end` with tangent angles in `cone`.
    pub(super) fn new(bbox: Aabb, cone: [f64; 2], first: usize, end: usize) -> Place {
        let mid = 0.5 * (cone[0] + cone[1]);
        let h = 0.5 * (cone[1] - cone[0]) + CONE_PAD;
        // |t − t₀| = 2 sin(|δ|/2) for t at angle δ from t₀.
        let spread = if h < PI { 2.0 * (0.5 * h).sin() } else { 2.0 };
        Place {
            bbox,
            tangent: Vec2::new(mid.cos(), mid.sin()),
            spread,
            interface: usize::MAX,
            first,
            end,
            cone,
        }
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::TAU;

    use super::*;
    use crate::demo::SplitMix64;
    use crate::geom::Point;

    /// Every tangent at an angle of the cone lies within `spread` of the place's tangent,
    /// and the spread is no wider than it must be (the cone's ends reach it, less the pad),
    /// for cones from a point to more than a whole turn.
    #[test]
    fn the_spread_holds_every_tangent_of_the_cone() {
        let mut rng = SplitMix64(0x91ace);
        let b = Aabb::from_points(Point::new(0.0, 0.0), Point::new(1.0, 1.0));
        for case in 0..2000 {
            let lo = 20.0 * rng.next_f64() - 10.0;
            let width = match case % 4 {
                0 => 0.0,
                1 => 1e-6 * rng.next_f64(),
                2 => 7.0 * rng.next_f64(),
                _ => PI * rng.next_f64(),
            };
            let cone = [lo, lo + width];
            let p = Place::new(b, cone, 3, 5);
            assert_eq!((p.first, p.end, p.interface, p.bbox), (3, 5, usize::MAX, b));
            assert!((p.tangent.length() - 1.0).abs() < 1e-15);
            for f in [0.0, 1.0, rng.next_f64(), rng.next_f64()] {
                let a = lo + f * width;
                let t = Vec2::new(a.cos(), a.sin());
                let off = (t - p.tangent).length();
                assert!(
                    off <= p.spread + 1e-15,
                    "cone {cone:?}, angle {a}: {off} > {}",
                    p.spread
                );
            }
            let end = Vec2::new(lo.cos(), lo.sin());
            let reach = (end - p.tangent).length();
            if width < TAU - 0.1 {
                assert!(p.spread <= reach + 2.0 * CONE_PAD + 1e-15, "{cone:?}");
            }
        }
    }
}
