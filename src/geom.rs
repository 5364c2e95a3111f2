//! Points, vectors, boxes and exact orientation predicates in the plane.

use std::ops::{Add, AddAssign, Mul, Neg, Sub};

/// A position in the plane.
///
/// `Point` and [`Vec2`] are different types so that adding two points does not compile.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Point {
    /// Horizontal coordinate.
    pub x: f64,
    /// Vertical coordinate.
    pub y: f64,
}

/// A displacement in the plane.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec2 {
    /// Horizontal component.
    pub x: f64,
    /// Vertical component.
    pub y: f64,
}

impl Point {
    /// The point `(x, y)`.
    #[inline]
    pub const fn new(x: f64, y: f64) -> Self {
        Point { x, y }
    }
    /// The displacement from the origin to this point.
    #[inline]
    pub const fn to_vec2(self) -> Vec2 {
        Vec2 {
            x: self.x,
            y: self.y,
        }
    }
    /// Euclidean distance to `other`.
    #[inline]
    pub fn distance(self, other: Point) -> f64 {
        (self - other).length()
    }
    /// Whether both coordinates are finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }
    /// The point `t` of the way from `self` to `other`.
    #[inline]
    pub fn lerp(self, other: Point, t: f64) -> Point {
        self + (other - self) * t
    }
}

impl Vec2 {
    /// The vector `(x, y)`.
    #[inline]
    pub const fn new(x: f64, y: f64) -> Self {
        Vec2 { x, y }
    }
    /// Dot product.
    #[inline]
    pub fn dot(self, o: Vec2) -> f64 {
        self.x * o.x + self.y * o.y
    }
    /// The z component of the 3-D cross product: `self.x * o.y - self.y * o.x`.
    #[inline]
    pub fn cross(self, o: Vec2) -> f64 {
        self.x * o.y - self.y * o.x
    }
    /// Euclidean length (computed with `hypot`, so it neither overflows nor underflows early).
    #[inline]
    pub fn length(self) -> f64 {
        self.x.hypot(self.y)
    }
    /// This vector turned a quarter turn counter-clockwise: the left normal of a direction.
    #[inline]
    pub fn perp(self) -> Vec2 {
        Vec2::new(-self.y, self.x)
    }
    /// The point at this displacement from the origin.
    #[inline]
    pub const fn to_point(self) -> Point {
        Point {
            x: self.x,
            y: self.y,
        }
    }
}

impl Sub for Point {
    type Output = Vec2;
    #[inline]
    fn sub(self, o: Point) -> Vec2 {
        Vec2::new(self.x - o.x, self.y - o.y)
    }
}
impl Add<Vec2> for Point {
    type Output = Point;
    #[inline]
    fn add(self, v: Vec2) -> Point {
        Point::new(self.x + v.x, self.y + v.y)
    }
}
impl Sub<Vec2> for Point {
    type Output = Point;
    #[inline]
    fn sub(self, v: Vec2) -> Point {
        Point::new(self.x - v.x, self.y - v.y)
    }
}
impl Add for Vec2 {
    type Output = Vec2;
    #[inline]
    fn add(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x + o.x, self.y + o.y)
    }
}
impl AddAssign for Vec2 {
    #[inline]
    fn add_assign(&mut self, o: Vec2) {
        self.x += o.x;
        self.y += o.y;
    }
}
impl Sub for Vec2 {
    type Output = Vec2;
    #[inline]
    fn sub(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x - o.x, self.y - o.y)
    }
}
impl Mul<f64> for Vec2 {
    type Output = Vec2;
    #[inline]
    fn mul(self, k: f64) -> Vec2 {
        Vec2::new(self.x * k, self.y * k)
    }
}
impl Neg for Vec2 {
    type Output = Vec2;
    #[inline]
    fn neg(self) -> Vec2 {
        Vec2::new(-self.x, -self.y)
    }
}
impl From<[f64; 2]> for Point {
    fn from(a: [f64; 2]) -> Point {
        Point::new(a[0], a[1])
    }
}
impl From<Point> for [f64; 2] {
    fn from(p: Point) -> [f64; 2] {
        [p.x, p.y]
    }
}

/// A straight segment from `start` to `end`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// Where it starts.
    pub start: Point,
    /// Where it ends.
    pub end: Point,
}

/// An axis-aligned box `[min, max]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower-left corner.
    pub min: Point,
    /// Upper-right corner.
    pub max: Point,
}

impl Aabb {
    /// The empty box: the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: Point::new(f64::INFINITY, f64::INFINITY),
        max: Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
    };
    /// The smallest box holding both points.
    #[inline]
    pub fn from_points(a: Point, b: Point) -> Aabb {
        Aabb {
            min: Point::new(a.x.min(b.x), a.y.min(b.y)),
            max: Point::new(a.x.max(b.x), a.y.max(b.y)),
        }
    }
    /// [`from_points`](Self::from_points) for points that are not NaN (a compare and select
    /// per bound, which is what `f64::min` and `max` give there).
    #[inline]
    pub fn from_finite(a: Point, b: Point) -> Aabb {
        let (x0, x1) = if b.x < a.x { (b.x, a.x) } else { (a.x, b.x) };
        let (y0, y1) = if b.y < a.y { (b.y, a.y) } else { (a.y, b.y) };
        Aabb {
            min: Point::new(x0, y0),
            max: Point::new(x1, y1),
        }
    }
    /// The smallest box holding all `points` ([`EMPTY`](Self::EMPTY) for none).
    pub fn around(points: &[Point]) -> Aabb {
        points
            .iter()
            .fold(Aabb::EMPTY, |b, &p| b.union(Aabb::from_points(p, p)))
    }
    /// The smallest box holding both boxes.
    #[inline]
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: Point::new(self.min.x.min(o.min.x), self.min.y.min(o.min.y)),
            max: Point::new(self.max.x.max(o.max.x), self.max.y.max(o.max.y)),
        }
    }
    /// `rel` times the box's size plus its coordinates' magnitudes: room for the round-off
    /// of points computed on its contents.
    pub fn round_off_pad(self, rel: f64) -> f64 {
        rel * (self.max.x - self.min.x
            + (self.max.y - self.min.y)
            + self.max.x.abs()
            + self.min.x.abs()
            + self.max.y.abs()
            + self.min.y.abs())
    }
    /// The box grown by `pad` on every side.
    pub fn grown(self, pad: f64) -> Aabb {
        Aabb {
            min: Point::new(self.min.x - pad, self.min.y - pad),
            max: Point::new(self.max.x + pad, self.max.y + pad),
        }
    }
    /// Whether the closed boxes share a point.
    #[inline]
    pub fn overlaps(self, o: Aabb) -> bool {
        self.min.x <= o.max.x
            && o.min.x <= self.max.x
            && self.min.y <= o.max.y
            && o.min.y <= self.max.y
    }
    /// Squared distance from `p` to the box (0 inside).
    #[inline]
    pub fn distance_sq(self, p: Point) -> f64 {
        let dx = (self.min.x - p.x).max(0.0).max(p.x - self.max.x);
        let dy = (self.min.y - p.y).max(0.0).max(p.y - self.max.y);
        dx * dx + dy * dy
    }
    /// Whether `p` lies in the closed box.
    #[inline]
    pub fn contains(self, p: Point) -> bool {
        p.x >= self.min.x && p.x <= self.max.x && p.y >= self.min.y && p.y <= self.max.y
    }
    /// Centre of the box.
    #[inline]
    pub fn center(self) -> Point {
        self.min.lerp(self.max, 0.5)
    }
    /// Length of the box's diagonal.
    #[inline]
    pub fn diagonal(self) -> f64 {
        (self.max - self.min).length()
    }
}

/// The side of a polyline at one of its vertices that a direction lies on, from its sides of
/// the two segments' lines (`before`, `after`: positive on the left, the side the normals
/// point to) and whether the polyline turns left there (`turns_left`). Near the vertex the
/// side on the inside of the turn is a wedge narrower than a half-plane (both lines' side),
/// the other one the rest: `1.0` left, `-1.0` right, `0.0` on a boundary.
#[inline]
pub(crate) fn vertex_side(turns_left: bool, before: f64, after: f64) -> f64 {
    let (left, right) = if turns_left {
        (before > 0.0 && after > 0.0, before < 0.0 || after < 0.0)
    } else {
        (before > 0.0 || after > 0.0, before < 0.0 && after < 0.0)
    };
    if left && !right {
        1.0
    } else if right && !left {
        -1.0
    } else {
        0.0
    }
}

/// Exact orientation of `c` relative to the directed line `a → b`: positive when `c` is to the
/// left, negative to the right, zero when the three are collinear.
///
/// Uses Shewchuk's adaptive-precision predicate (`robust` crate), so the sign is exact.
#[inline]
pub fn orient(a: Point, b: Point, c: Point) -> f64 {
    robust::orient2d(
        robust::Coord { x: a.x, y: a.y },
        robust::Coord { x: b.x, y: b.y },
        robust::Coord { x: c.x, y: c.y },
    )
}

/// How two closed segments meet, decided with exact predicates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentContact {
    /// No common point.
    Disjoint,
    /// They cross at one point interior to both.
    Cross,
    /// They share exactly one point, which is an endpoint of at least one of them.
    Touch,
    /// They are collinear and share more than one point.
    Overlap,
}

/// Classifies how segment `a0–a1` meets segment `b0–b1` (exact).
pub fn segment_contact(a0: Point, a1: Point, b0: Point, b1: Point) -> SegmentContact {
    let d1 = orient(a0, a1, b0);
    let d2 = orient(a0, a1, b1);
    let d3 = orient(b0, b1, a0);
    let d4 = orient(b0, b1, a1);
    if d1 == 0.0 && d2 == 0.0 {
        // Collinear: compare projections on the dominant axis.
        let use_x = (a1.x - a0.x).abs() >= (a1.y - a0.y).abs();
        let key = |p: Point| if use_x { p.x } else { p.y };
        let (alo, ahi) = minmax(key(a0), key(a1));
        let (blo, bhi) = minmax(key(b0), key(b1));
        let lo = alo.max(blo);
        let hi = ahi.min(bhi);
        return if lo < hi {
            SegmentContact::Overlap
        } else if lo == hi {
            SegmentContact::Touch
        } else {
            SegmentContact::Disjoint
        };
    }
    let opposite = |p: f64, q: f64| (p > 0.0 && q < 0.0) || (p < 0.0 && q > 0.0);
    if opposite(d1, d2) && opposite(d3, d4) {
        return SegmentContact::Cross;
    }
    let on =
        |d: f64, p: Point, s0: Point, s1: Point| d == 0.0 && Aabb::from_points(s0, s1).contains(p);
    if on(d1, b0, a0, a1) || on(d2, b1, a0, a1) || on(d3, a0, b0, b1) || on(d4, a1, b0, b1) {
        SegmentContact::Touch
    } else {
        SegmentContact::Disjoint
    }
}

#[inline]
fn minmax(a: f64, b: f64) -> (f64, f64) {
    if a <= b { (a, b) } else { (b, a) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contact_cases() {
        let p = Point::new;
        assert_eq!(
            segment_contact(p(0., 0.), p(2., 0.), p(1., -1.), p(1., 1.)),
            SegmentContact::Cross
        );
        assert_eq!(
            segment_contact(p(0., 0.), p(2., 0.), p(1., 0.), p(1., 1.)),
            SegmentContact::Touch
        );
        assert_eq!(
            segment_contact(p(0., 0.), p(2., 0.), p(2., 0.), p(3., 1.)),
            SegmentContact::Touch
        );
        assert_eq!(
            segment_contact(p(0., 0.), p(2., 0.), p(1., 0.), p(3., 0.)),
            SegmentContact::Overlap
        );
        assert_eq!(
            segment_contact(p(0., 0.), p(2., 0.), p(2., 0.), p(3., 0.)),
            SegmentContact::Touch
        );
        assert_eq!(
            segment_contact(p(0., 0.), p(2., 0.), p(3., 0.), p(4., 0.)),
            SegmentContact::Disjoint
        );
        assert_eq!(
            segment_contact(p(0., 0.), p(2., 0.), p(0., 1.), p(2., 1.)),
            SegmentContact::Disjoint
        );
        // Nearly collinear but exactly decided.
        assert_eq!(
            segment_contact(p(0., 0.), p(1., 1e-300), p(0.5, -1.0), p(0.5, 1.0)),
            SegmentContact::Cross
        );
    }

    #[test]
    fn box_distance() {
        let b = Aabb::from_points(Point::new(0., 0.), Point::new(1., 1.));
        assert_eq!(b.distance_sq(Point::new(0.5, 0.5)), 0.0);
        assert_eq!(b.distance_sq(Point::new(3.0, 1.0)), 4.0);
    }
}
