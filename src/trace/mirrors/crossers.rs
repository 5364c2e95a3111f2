//! Which scene segments a leg between two walls can be found to cross: per pair of walls,
//! a short list in place of the whole scene's hierarchy.
//!
//! A leg from wall `i` to wall `j` lies in the convex hull `H` of the two walls (its ends
//! within round-off of them). The validation's crossing test
//! ([`Scene::first_crossing_on_line`]) reports segment `k` only where `k` straddles the
//! path's line and the leg's line meets `k`'s line at a fraction of the leg in
//! `(END_MARGIN, 1 − END_MARGIN)`, so at a point `X` within round-off `ε` of `H`. If `k`
//! lies farther than `ρ` from `H`, the point `Y` where the path's line meets `k` lies at
//! least `ρ − ε` from `X` along `k`'s line, while the two lines through the leg (the path's
//! and its rounded ends') are within `ε` of each other there: `k` then runs within `ε/ρ`
//! (plus `ε` over the leg's length) of parallel to the leg, and its line passes through `H`.
//! So the list of a pair keeps every segment within `ρ` of `H`, and every segment whose
//! line passes within `ρ` of `H` and whose direction lies within [`PARALLEL`] of a leg's
//! (any direction from a point of `i` to a point of `j`); the others cannot be reported.
//! Legs shorter than [`SHORT`] of the scene's size, whose two lines may differ in direction
//! by more, take the whole test.

use crate::geom::{Point, Vec2};
use crate::scene::Scene;

use super::Wall;

/// `ρ`, relative to the scene's largest coordinate: far above the round-off of a leg's
/// lines (`BEAM_MARGIN`, 1e-11 of it, covers thousands of levels).
const NEAR: f64 = 1e-6;

/// The angle (radians) within which a segment counts as parallel to a leg: far above
/// `ε/ρ` (1e-5).
const PARALLEL: f64 = 1e-3;

/// Legs shorter than this fraction of the scene's largest coordinate take the whole test.
pub(super) const SHORT: f64 = 1e-4;

/// Per ordered pair of walls, the scene segments (indices into [`Scene::segments`]) that a
/// leg between them can be found to cross.
#[derive(Clone, Debug, Default)]
pub(super) struct Crossers {
    /// The number of walls (0: no lists kept).
    walls: usize,
    /// Where pair `a · walls + b`'s list starts in `segments` (one more entry at the end).
    starts: Vec<u32>,
    /// The lists, one after another.
    segments: Vec<u32>,
    /// The shortest leg that the lists serve.
    pub(super) shortest: f64,
}

impl Crossers {
    /// The lists of every pair of `walls` in `scene`.
    pub(super) fn new(scene: &Scene, walls: &[Wall]) -> Crossers {
        let ends: Vec<[Point; 2]> = (scene.segments().iter())
            .map(|&r| {
                let s = scene.segment_points(r);
                [s.start, s.end]
            })
            .collect();
        let extent = (ends.iter().flatten())
            .fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()))
            .max(f64::MIN_POSITIVE);
        let rho = NEAR * extent;
        let n = walls.len();
        let mut starts = Vec::with_capacity(n * n + 1);
        let mut segments = Vec::new();
        for a in walls {
            for b in walls {
                starts.push(segments.len() as u32);
                let hull = Hull::of(&[a.p, a.q, b.p, b.q]);
                let cone = LegCone::of(a, b, rho);
                for (k, &[p, q]) in ends.iter().enumerate() {
                    let own = scene.segments()[k];
                    if own == a.own || own == b.own {
                        continue;
                    }
                    let near = hull.distance_to_segment(p, q) <= rho;
                    let risky = hull.line_within(p, q, rho) && cone.holds(q - p);
                    if near || risky {
                        segments.push(k as u32);
                    }
                }
            }
        }
        starts.push(segments.len() as u32);
        Crossers {
            walls: n,
            starts,
            segments,
            shortest: SHORT * extent,
        }
    }

    /// The list of the pair of walls `a` then `b`; `None` where no lists are kept.
    #[inline]
    pub(super) fn of(&self, a: usize, b: usize) -> Option<&[u32]> {
        if self.walls == 0 {
            return None;
        }
        let k = a * self.walls + b;
        let (s, e) = (self.starts[k] as usize, self.starts[k + 1] as usize);
        Some(&self.segments[s..e])
    }
}

/// A convex polygon, its vertices counterclockwise (or fewer than 3 where the points are
/// collinear).
struct Hull(Vec<Point>);

impl Hull {
    /// The convex hull of `points` (monotone chain; collinear points dropped).
    fn of(points: &[Point]) -> Hull {
        let mut p = points.to_vec();
        p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        p.dedup();
        if p.len() < 3 {
            return Hull(p);
        }
        let turn = |o: Point, a: Point, b: Point| (a - o).cross(b - o);
        let mut hull: Vec<Point> = Vec::with_capacity(2 * p.len());
        // The lower chain left to right, then the upper right to left.
        for pass in 0..2 {
            let start = hull.len();
            for k in 0..p.len() {
                let x = if pass == 0 { p[k] } else { p[p.len() - 1 - k] };
                while hull.len() >= start + 2
                    && turn(hull[hull.len() - 2], hull[hull.len() - 1], x) <= 0.0
                {
                    hull.pop();
                }
                hull.push(x);
            }
            hull.pop();
        }
        Hull(hull)
    }

    /// The edges, each from a vertex to the next.
    fn edges(&self) -> impl Iterator<Item = (Point, Point)> + '_ {
        let n = self.0.len();
        (0..n).map(move |i| (self.0[i], self.0[(i + 1) % n]))
    }

    /// Whether `x` lies inside or on the polygon (a degenerate one holds nothing).
    fn contains(&self, x: Point) -> bool {
        self.0.len() >= 3 && self.edges().all(|(a, b)| (b - a).cross(x - a) >= 0.0)
    }

    /// The distance from the polygon (its inside included) to segment `p–q`.
    fn distance_to_segment(&self, p: Point, q: Point) -> f64 {
        if self.contains(p) || self.contains(q) {
            return 0.0;
        }
        let mut d = f64::INFINITY;
        if self.0.len() == 1 {
            return point_segment(self.0[0], p, q);
        }
        for (a, b) in self.edges() {
            if segments_meet(a, b, p, q) {
                return 0.0;
            }
            d = d
                .min(point_segment(p, a, b))
                .min(point_segment(q, a, b))
                .min(point_segment(a, p, q));
        }
        d
    }

    /// Whether the line through `p` and `q` passes within `rho` of the polygon.
    fn line_within(&self, p: Point, q: Point, rho: f64) -> bool {
        let e = q - p;
        let len = e.length();
        if len == 0.0 {
            return true;
        }
        let side = |x: Point| e.cross(x - p) / len;
        let (lo, hi) = (self.0.iter()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            let s = side(x);
            (lo.min(s), hi.max(s))
        });
        !(lo > rho || hi < -rho)
    }
}

/// The distance from `x` to segment `a–b`.
fn point_segment(x: Point, a: Point, b: Point) -> f64 {
    let e = b - a;
    let ee = e.dot(e);
    let t = if ee > 0.0 {
        ((x - a).dot(e) / ee).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (x - (a + e * t)).length()
}

/// Whether segments `a–b` and `p–q` meet (touching counts).
fn segments_meet(a: Point, b: Point, p: Point, q: Point) -> bool {
    let o = |u: Point, v: Point, w: Point| (v - u).cross(w - u);
    let (d1, d2) = (o(a, b, p), o(a, b, q));
    let (d3, d4) = (o(p, q, a), o(p, q, b));
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0
}

/// The directions of the legs from a point of one wall to a point of another, widened by
/// [`PARALLEL`]: an angle interval, or every direction where the walls come within `ρ` of
/// each other.
struct LegCone {
    /// The cone's two edges, counterclockwise from the first; `None`: every direction.
    edges: Option<(Vec2, Vec2)>,
}

impl LegCone {
    fn of(from: &Wall, to: &Wall, rho: f64) -> LegCone {
        // The legs' directions are the points of the parallelogram `to − from`.
        let corners = [to.p - from.p, to.p - from.q, to.q - from.p, to.q - from.q];
        let as_points = corners.map(|v| Point::new(v.x, v.y));
        let hull = Hull::of(&as_points);
        let origin = Point::new(0.0, 0.0);
        let close = match hull.0.len() {
            0 => true,
            1 => (hull.0[0] - origin).length() <= rho,
            2 => point_segment(origin, hull.0[0], hull.0[1]) <= rho,
            _ => {
                hull.contains(origin)
                    || hull
                        .edges()
                        .any(|(a, b)| point_segment(origin, a, b) <= rho)
            }
        };
        if close {
            return LegCone { edges: None };
        }
        // The extreme directions: the corner with every other to its left, and the one with
        // every other to its right.
        let first = corners
            .iter()
            .copied()
            .find(|&u| corners.iter().all(|&v| u.cross(v) >= 0.0));
        let last = corners
            .iter()
            .copied()
            .find(|&u| corners.iter().all(|&v| v.cross(u) >= 0.0));
        let (Some(first), Some(last)) = (first, last) else {
            return LegCone { edges: None };
        };
        let rotate = |v: Vec2, angle: f64| {
            let (s, c) = angle.sin_cos();
            Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
        };
        let (first, last) = (rotate(first, -PARALLEL), rotate(last, PARALLEL));
        // A cone of half a turn or more after widening: every direction.
        if first.cross(last) <= 0.0 {
            return LegCone { edges: None };
        }
        LegCone {
            edges: Some((first, last)),
        }
    }

    /// Whether direction `d` or its opposite lies in the cone.
    fn holds(&self, d: Vec2) -> bool {
        let Some((first, last)) = self.edges else {
            return true;
        };
        let inside = |d: Vec2| first.cross(d) >= 0.0 && d.cross(last) >= 0.0;
        inside(d) || inside(-d)
    }
}
