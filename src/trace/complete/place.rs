//! What a point of a tuple may be: a box of positions and a cone of tangents.

use std::f64::consts::PI;

use crate::geom::{Aabb, Vec2};

/// Widening of every tangent cone (rad): the round-off of the unwrapped angles.
pub(super) const CONE_PAD: f64 = 1e-9;

/// What a point of a tuple may be: a box, and tangents `t` with `|t − tangent| ≤ spread`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Place {
    pub(super) bbox: Aabb,
    pub(super) tangent: Vec2,
    pub(super) spread: f64,
    /// The interface (set by the search; `usize::MAX` in a hierarchy's nodes).
    pub(super) interface: usize,
    /// The segments `first..end` whose points (and first vertex) the place holds, and the
    /// range of their tangent angles.
    pub(super) first: usize,
    pub(super) end: usize,
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
