//! Open and closed polylines parametrised by arclength.

use crate::bvh::Bvh;
use crate::geom::{Aabb, Point, Segment, Vec2, orient};

/// Turning angles above this (radians) are corners, not a digitised smooth curve: they add
/// nothing to the curvature estimate that guides the solver across vertices.
const SMOOTH_TURN: f64 = 0.35;

/// Why a list of vertices is not a valid polyline.
#[derive(Clone, Debug, PartialEq)]
pub enum PolylineError {
    /// Fewer than two distinct vertices (or three for a closed polyline).
    TooFewPoints {
        /// Vertices needed.
        needed: usize,
    },
    /// A coordinate is NaN or infinite. How to fix: give finite numbers.
    NotFinite {
        /// Index of the vertex.
        index: usize,
    },
    /// Vertex `index` repeats the vertex before it (a zero-length segment). How to fix: drop it;
    /// a closed polyline does not repeat its first vertex at the end.
    ZeroLengthSegment {
        /// Index of the vertex that ends the zero-length segment.
        index: usize,
    },
    /// All vertices of a closed polyline lie on one line: it encloses nothing.
    Collinear,
}

impl std::fmt::Display for PolylineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PolylineError::TooFewPoints { needed } => {
                write!(f, "needs at least {needed} distinct points")
            }
            PolylineError::NotFinite { index } => write!(f, "point {index} is not finite"),
            PolylineError::ZeroLengthSegment { index } => {
                write!(
                    f,
                    "point {index} repeats the point before it (zero-length segment)"
                )
            }
            PolylineError::Collinear => write!(
                f,
                "a closed polyline needs points that are not all on one line"
            ),
        }
    }
}

/// The point of a polyline nearest to a given point ([`Polyline::nearest`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    /// Its parameter (arclength from the first vertex).
    pub s: f64,
    /// Its segment.
    pub seg: usize,
    /// Its distance from the given point.
    pub distance: f64,
}

/// A polyline: the shape of one interface.
///
/// A point on it is one number, its arclength `s` from the first vertex. Segment `j` runs from
/// vertex `j` to vertex `j + 1` (for a closed polyline the last segment returns to vertex 0) and
/// covers `s ∈ [start(j), start(j + 1)]`; finding the segment of a parameter is a binary search
/// on the cumulative lengths, `O(log M)` for `M` segments.
///
/// ```
/// use eigenray::Point;
/// use eigenray::polyline::Polyline;
/// let p = Polyline::new(vec![Point::new(0.0, 0.0), Point::new(3.0, 0.0), Point::new(3.0, 4.0)], false).unwrap();
/// assert_eq!(p.length(), 7.0);
/// assert_eq!(p.segment_at(4.0), 1);
/// assert_eq!(p.point_at(5.0), Point::new(3.0, 2.0));
/// ```
#[derive(Clone, Debug)]
pub struct Polyline {
    /// The vertices, with the first repeated at the end on a closed polyline: segment `j` runs
    /// from `ends[j]` to `ends[j + 1]`.
    ends: Vec<Point>,
    closed: bool,
    /// Arclength at the start of each segment, plus the total length at the end.
    cum: Vec<f64>,
    /// Unit direction of each segment.
    dirs: Vec<Vec2>,
    /// Curvature estimate of each segment (from small turning angles only).
    curv: Vec<f64>,
    /// Per segment: parameter of the first corner at or after its end vertex (beyond the
    /// length on a closed polyline when it wraps; infinite if there is none).
    corner_ahead: Vec<f64>,
    /// Per segment: parameter of the last corner at or before its start vertex (negative on a
    /// closed polyline when it wraps; minus infinity if there is none).
    corner_behind: Vec<f64>,
    bbox: Aabb,
    bvh: Bvh,
}

impl Polyline {
    /// Builds a polyline from its vertices; `closed` joins the last vertex to the first.
    pub fn new(vertices: Vec<Point>, closed: bool) -> Result<Polyline, PolylineError> {
        if let Some(index) = vertices.iter().position(|p| !p.is_finite()) {
            return Err(PolylineError::NotFinite { index });
        }
        let needed = if closed { 3 } else { 2 };
        let mut distinct = vertices.clone();
        distinct.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        distinct.dedup();
        if distinct.len() < needed {
            return Err(PolylineError::TooFewPoints { needed });
        }
        for i in 1..vertices.len() {
            if vertices[i] == vertices[i - 1] {
                return Err(PolylineError::ZeroLengthSegment { index: i });
            }
        }
        if closed {
            if vertices[0] == vertices[vertices.len() - 1] {
                return Err(PolylineError::ZeroLengthSegment { index: 0 });
            }
            // Exact orientation underflows on tiny coordinates (products below the smallest
            // subnormal): test a copy scaled up by a power of two (exact) when they are small.
            let largest = vertices
                .iter()
                .fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
            let (f0, f1) = if largest < 1.0 {
                // 2^k with 2^k × largest in [1, 2): at most 2^1074, applied in two steps.
                let k = -largest.log2().floor() as i32;
                (2f64.powi(k / 2), 2f64.powi(k - k / 2))
            } else {
                (1.0, 1.0)
            };
            let up = |p: Point| Point::new(p.x * f0 * f1, p.y * f0 * f1);
            let (a, b) = (up(vertices[0]), up(vertices[1]));
            if vertices.iter().all(|&c| orient(a, b, up(c)) == 0.0) {
                return Err(PolylineError::Collinear);
            }
        }
        let n = vertices.len();
        let nseg = if closed { n } else { n - 1 };
        let mut cum = Vec::with_capacity(nseg + 1);
        let mut dirs = Vec::with_capacity(nseg);
        let mut boxes = Vec::with_capacity(nseg);
        let mut total = 0.0;
        for j in 0..nseg {
            let (a, b) = (vertices[j], vertices[(j + 1) % n]);
            let d = b - a;
            let len = d.length();
            cum.push(total);
            total += len;
            dirs.push(d * (1.0 / len));
            boxes.push(Aabb::from_points(a, b));
        }
        cum.push(total);
        let bbox = boxes.iter().fold(Aabb::EMPTY, |acc, b| acc.union(*b));
        let bvh = Bvh::build(&boxes);
        let mut ends = vertices;
        if closed {
            ends.push(ends[0]);
        }
        let mut line = Polyline {
            ends,
            closed,
            cum,
            dirs,
            curv: Vec::new(),
            corner_ahead: Vec::new(),
            corner_behind: Vec::new(),
            bbox,
            bvh,
        };
        line.curv = line.curvature_estimates();
        line.find_corners();
        Ok(line)
    }

    /// Whether vertex `v` is a corner: a turn sharper than a digitised smooth curve's (the
    /// ends of an open polyline are not: the solver holds points there by projection).
    fn is_corner(&self, v: usize) -> bool {
        let nseg = self.num_segments();
        let (prev, next) = if self.closed {
            ((v + nseg - 1) % nseg, v % nseg)
        } else if v == 0 || v == nseg {
            return false;
        } else {
            (v - 1, v)
        };
        let (a, b) = (self.dirs[prev], self.dirs[next]);
        a.cross(b).atan2(a.dot(b)).abs() > SMOOTH_TURN
    }

    fn find_corners(&mut self) {
        let nseg = self.num_segments();
        let l = self.length();
        let corners: Vec<bool> = (0..nseg + usize::from(!self.closed))
            .map(|v| self.is_corner(v))
            .collect();
        let nv = corners.len();
        self.corner_ahead = vec![f64::INFINITY; nseg];
        self.corner_behind = vec![f64::NEG_INFINITY; nseg];
        // Sweep twice round a closed polyline so that wrapped corners are found.
        let rounds = if self.closed { 2 } else { 1 };
        let mut next = f64::INFINITY;
        for u in (1..=rounds * nseg).rev() {
            let v = u % nv.max(1);
            let wraps = if self.closed {
                (u / nseg) as f64 * l
            } else {
                0.0
            };
            if corners[if self.closed { u % nseg } else { v.min(nv - 1) }] {
                next = self.cum[if self.closed { u % nseg } else { u.min(nseg) }] + wraps;
            }
            if u - 1 < nseg {
                self.corner_ahead[u - 1] = next;
            }
        }
        let mut last = f64::NEG_INFINITY;
        let start = if self.closed { -(nseg as isize) } else { 0 };
        for u in start..nseg as isize {
            let v = u.rem_euclid(nseg as isize) as usize;
            let wraps = if u < 0 { -l } else { 0.0 };
            if corners[v] {
                last = self.cum[v] + wraps;
            }
            if u >= 0 {
                self.corner_behind[u as usize] = last;
            }
        }
    }

    /// How far a point at parameter `s` on segment `j` can move by `delta` before it reaches a
    /// corner (a vertex the segment-wise model of the travel time cannot see past): the
    /// largest `|step| ≤ |delta|` in the direction of `delta`.
    #[inline]
    pub fn reach(&self, j: usize, s: f64, delta: f64) -> f64 {
        if delta > 0.0 {
            delta.min(self.corner_ahead[j] - s).max(0.0)
        } else {
            -((-delta).min(s - self.corner_behind[j]).max(0.0))
        }
    }

    /// Whether no corner lies between segments `a` and `b` (the vertices a step from `a` to
    /// `b` crosses, taken without wrapping round a closed polyline; a wrap counts as a corner).
    #[inline]
    pub(crate) fn smooth_between(&self, a: usize, b: usize) -> bool {
        if self.closed && a.abs_diff(b) > self.num_segments() / 2 {
            false
        } else if b > a {
            self.corner_ahead[a] > self.cum[b]
        } else if b < a {
            self.corner_behind[a] < self.cum[b + 1]
        } else {
            true
        }
    }

    /// [`reach`](Self::reach) plus a hair (1e-7 of the segment): a step limited by it ends
    /// just past the corner, in the next segment, so that the corner is seen as crossed.
    #[inline]
    pub(crate) fn reach_past(&self, j: usize, s: f64, delta: f64) -> f64 {
        let hair = 1e-7 * self.segment_length(j);
        let r = self.reach(j, s, delta);
        if r.abs() < delta.abs() {
            (r.abs() + hair).min(delta.abs()).copysign(delta)
        } else {
            r
        }
    }

    fn curvature_estimates(&self) -> Vec<f64> {
        let nseg = self.num_segments();
        // Curvature at each vertex: turning angle over the mean of the adjacent lengths.
        let vertex_k = |v: usize| -> f64 {
            let (prev, next) = if self.closed {
                ((v + nseg - 1) % nseg, v % nseg)
            } else if v == 0 || v == nseg {
                return 0.0;
            } else {
                (v - 1, v)
            };
            let (a, b) = (self.dirs[prev], self.dirs[next]);
            let turn = a.cross(b).atan2(a.dot(b));
            if turn.abs() > SMOOTH_TURN {
                return 0.0;
            }
            turn / (0.5 * (self.segment_length(prev) + self.segment_length(next)))
        };
        (0..nseg)
            .map(|j| 0.5 * (vertex_k(j) + vertex_k(j + 1)))
            .collect()
    }

    /// Whether the last vertex joins the first.
    #[inline]
    pub fn is_closed(&self) -> bool {
        self.closed
    }
    /// The vertices (a closed polyline does not repeat the first at the end).
    #[inline]
    pub fn vertices(&self) -> &[Point] {
        &self.ends[..self.ends.len() - usize::from(self.closed)]
    }
    /// Number of segments.
    #[inline]
    pub fn num_segments(&self) -> usize {
        self.dirs.len()
    }
    /// Total arclength.
    #[inline]
    pub fn length(&self) -> f64 {
        self.cum[self.dirs.len()]
    }
    /// Bounding box.
    #[inline]
    pub fn bbox(&self) -> Aabb {
        self.bbox
    }
    /// Arclength where segment `j` starts (`start(num_segments())` is the total length).
    #[inline]
    pub fn start(&self, j: usize) -> f64 {
        self.cum[j]
    }
    /// Length of segment `j`.
    #[inline]
    pub fn segment_length(&self, j: usize) -> f64 {
        self.cum[j + 1] - self.cum[j]
    }
    /// Segment `j`, from its vertex `j` to the next.
    #[inline]
    pub fn segment(&self, j: usize) -> Segment {
        let e = &self.ends[j..j + 2];
        Segment {
            start: e[0],
            end: e[1],
        }
    }
    /// Unit tangent of segment `j` (the direction of increasing arclength).
    #[inline]
    pub fn tangent(&self, j: usize) -> Vec2 {
        self.dirs[j]
    }
    /// Unit normal of segment `j`: the tangent turned a quarter turn counter-clockwise (left).
    #[inline]
    pub fn normal(&self, j: usize) -> Vec2 {
        self.dirs[j].perp()
    }
    /// Curvature estimate on segment `j` (signed, positive turning left), from the turning
    /// angles at its ends that are small enough to belong to a digitised smooth curve; zero
    /// for a straight segment between corners.
    #[inline]
    pub fn curvature(&self, j: usize) -> f64 {
        self.curv[j]
    }

    /// Maps `s` into `[0, length)` on a closed polyline; returns it unchanged on an open one.
    #[inline]
    pub fn wrap(&self, s: f64) -> f64 {
        if self.closed {
            let l = self.length();
            let w = s.rem_euclid(l);
            if w >= l { 0.0 } else { w }
        } else {
            s
        }
    }

    /// `s` made a valid parameter: wrapped on a closed polyline, clamped to `[0, length]` on an
    /// open one (a non-finite value gives 0).
    #[inline]
    pub fn clamp_param(&self, s: f64) -> f64 {
        let s = if s.is_finite() { s } else { 0.0 };
        if self.closed {
            self.wrap(s)
        } else {
            s.clamp(0.0, self.length())
        }
    }

    /// Segment holding parameter `s` (binary search; a vertex belongs to the segment it starts;
    /// `s` outside `[0, length]` gives the first or last segment).
    #[inline]
    pub fn segment_at(&self, s: f64) -> usize {
        let nseg = self.dirs.len();
        self.cum[1..nseg].partition_point(|&c| c <= s)
    }

    /// [`segment_at`](Self::segment_at), trying segment `hint` and its neighbours first.
    #[inline]
    pub fn segment_at_hint(&self, s: f64, hint: usize) -> usize {
        let nseg = self.dirs.len();
        if hint < nseg {
            let inside =
                |j: usize| (j == 0 || self.cum[j] <= s) && (j + 1 == nseg || s < self.cum[j + 1]);
            if inside(hint) {
                return hint;
            }
            if hint + 1 < nseg && inside(hint + 1) {
                return hint + 1;
            }
            if hint > 0 && inside(hint - 1) {
                return hint - 1;
            }
        }
        self.segment_at(s)
    }

    /// Point at parameter `s` on segment `j`, interpolated from the nearer end of the segment
    /// so that `s` at a vertex gives that vertex exactly.
    #[inline]
    pub fn point_on(&self, j: usize, s: f64) -> Point {
        let Segment { start: a, end: b } = self.segment(j);
        point_between(a, b, self.dirs[j], self.cum[j], self.cum[j + 1], s)
    }

    /// `point_on(j, s) - origin`, computed as (vertex − origin) + offset, which keeps full
    /// relative precision for paths far from the coordinate origin.
    #[inline]
    pub fn offset_on(&self, j: usize, s: f64, origin: Point) -> Vec2 {
        let Segment { start: a, end: b } = self.segment(j);
        let from_start = s - self.cum[j];
        let from_end = self.cum[j + 1] - s;
        if from_start <= from_end {
            (a - origin) + self.dirs[j] * from_start
        } else {
            (b - origin) - self.dirs[j] * from_end
        }
    }

    /// Point at parameter `s` (wrapped on a closed polyline, clamped to the ends of an open one).
    pub fn point_at(&self, s: f64) -> Point {
        let s = if self.closed {
            self.wrap(s)
        } else {
            s.clamp(0.0, self.length())
        };
        self.point_on(self.segment_at(s), s)
    }

    /// The point of the polyline nearest to `p`. `O(log M)` for well-spread segments (a BVH
    /// query). A point with a NaN coordinate gets the first vertex, at distance NaN.
    pub fn nearest(&self, p: Point) -> Nearest {
        let found = self.bvh.nearest(p, |j| {
            let (_, q) = self.project(j as usize, p);
            (q - p).dot(q - p)
        });
        match found {
            Some((seg, d2)) => {
                let (s, _) = self.project(seg as usize, p);
                Nearest {
                    s,
                    seg: seg as usize,
                    distance: d2.sqrt(),
                }
            }
            None => Nearest {
                s: 0.0,
                seg: 0,
                distance: f64::NAN,
            },
        }
    }

    /// The parameters where segment `a–b` crosses or touches this polyline, reported to `f`
    /// as `(parameter, fraction along a–b)`.
    pub fn crossings(&self, a: Point, b: Point, mut f: impl FnMut(f64, f64)) {
        self.crossings_with_segment(a, b, |s, t, _| f(s, t));
    }

    /// [`crossings`](Self::crossings), also reporting the segment of each crossing.
    // Always inlined: the initial guess calls it per interaction, and as a call (with its
    // callback behind a reference) it cost 2.5 % more instructions per ray through 8 layers.
    #[inline(always)]
    pub(crate) fn crossings_with_segment(
        &self,
        a: Point,
        b: Point,
        mut f: impl FnMut(f64, f64, usize),
    ) {
        /// Polylines of at most this many segments are searched segment by segment: cheaper
        /// than the BVH query.
        const SHORT: usize = 8;
        if self.num_segments() <= SHORT {
            for j in 0..self.num_segments() {
                let Segment { start: p, end: q } = self.segment(j);
                if let Some((t, u)) = segment_intersection(a, b, p, q) {
                    f(self.cum[j] + u * self.segment_length(j), t, j);
                }
            }
            return;
        }
        self.bvh.any_near_segment(a, b, |j| {
            let j = j as usize;
            let Segment { start: p, end: q } = self.segment(j);
            if let Some((t, u)) = segment_intersection(a, b, p, q) {
                f(self.cum[j] + u * self.segment_length(j), t, j);
            }
            false
        });
    }

    /// Orthogonal projection of `p` on segment `j`, clamped: `(parameter, point)`.
    fn project(&self, j: usize, p: Point) -> (f64, Point) {
        let a = self.segment(j).start;
        let len = self.segment_length(j);
        let t = (p - a).dot(self.dirs[j]).clamp(0.0, len);
        let s = self.cum[j] + t;
        (s, self.point_on(j, s))
    }
}

/// Where segments `a–b` and `p–q` meet, as fractions `(t along a–b, u along p–q)`, both in
/// `[0, 1]`; `None` when they do not meet or are parallel.
pub(crate) fn segment_intersection(a: Point, b: Point, p: Point, q: Point) -> Option<(f64, f64)> {
    let d = b - a;
    let e = q - p;
    let den = d.cross(e);
    if den == 0.0 {
        return None;
    }
    let w = p - a;
    let t = w.cross(e) / den;
    let u = w.cross(d) / den;
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)).then_some((t, u))
}

/// The point at parameter `s` on the segment `a → b` (unit tangent `t`) whose ends are at
/// parameters `lo` and `hi`: [`Polyline::point_on`], interpolated from the nearer end.
#[inline(always)]
pub(crate) fn point_between(a: Point, b: Point, t: Vec2, lo: f64, hi: f64, s: f64) -> Point {
    let (from_start, from_end) = (s - lo, hi - s);
    if from_start <= from_end {
        a + t * from_start
    } else {
        b - t * from_end
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Polyline {
        let p = Point::new;
        Polyline::new(vec![p(0., 0.), p(1., 0.), p(1., 1.), p(0., 1.)], true).unwrap()
    }

    #[test]
    fn closed_wraps() {
        let sq = square();
        assert_eq!(sq.length(), 4.0);
        assert_eq!(sq.num_segments(), 4);
        assert_eq!(sq.point_at(3.5), Point::new(0.0, 0.5));
        assert_eq!(sq.point_at(-0.5), Point::new(0.0, 0.5));
        assert_eq!(sq.point_at(4.25), Point::new(0.25, 0.0));
        assert_eq!(sq.segment_at(2.0), 2);
        assert_eq!(sq.normal(0), Vec2::new(0.0, 1.0));
        // The closing segment runs from the last vertex back to the first, which the vertex
        // list does not repeat.
        assert_eq!(sq.vertices().len(), 4);
        assert_eq!(
            sq.segment(3),
            Segment {
                start: sq.vertices()[3],
                end: sq.vertices()[0]
            }
        );
    }

    #[test]
    fn errors() {
        let p = Point::new;
        assert_eq!(
            Polyline::new(vec![p(0., 0.)], false).unwrap_err(),
            PolylineError::TooFewPoints { needed: 2 }
        );
        assert_eq!(
            Polyline::new(vec![p(0., 0.), p(0., 0.)], false).unwrap_err(),
            PolylineError::TooFewPoints { needed: 2 }
        );
        assert_eq!(
            Polyline::new(vec![p(0., 0.), p(1., 0.), p(1., 0.)], false).unwrap_err(),
            PolylineError::ZeroLengthSegment { index: 2 }
        );
        assert_eq!(
            Polyline::new(vec![p(0., 0.), p(1., 0.), p(2., 0.)], true).unwrap_err(),
            PolylineError::Collinear
        );
        assert_eq!(
            Polyline::new(vec![p(0., 0.), p(f64::NAN, 0.)], false).unwrap_err(),
            PolylineError::NotFinite { index: 1 }
        );
    }

    #[test]
    fn hint_search_agrees_with_binary_search() {
        let pts: Vec<Point> = (0..200)
            .map(|i| Point::new(i as f64, (i as f64 * 0.1).sin()))
            .collect();
        let line = Polyline::new(pts, false).unwrap();
        for k in 0..1000 {
            let s = k as f64 * line.length() / 999.0;
            let j = line.segment_at(s);
            assert!(line.start(j) <= s || j == 0);
            for hint in [0, j.saturating_sub(1), j, j + 1, 150] {
                assert_eq!(line.segment_at_hint(s, hint), j);
            }
        }
    }

    #[test]
    fn nearest_point() {
        let sq = square();
        let Nearest {
            s,
            seg,
            distance: d,
        } = sq.nearest(Point::new(0.5, -2.0));
        assert_eq!((s, seg, d), (0.5, 0, 2.0));
        let Nearest { s, distance: d, .. } = sq.nearest(Point::new(2.0, 0.5));
        assert_eq!((s, d), (1.5, 1.0));
        let Nearest {
            s,
            seg,
            distance: d,
        } = sq.nearest(Point::new(f64::NAN, 0.5));
        assert_eq!((s, seg), (0.0, 0));
        assert!(d.is_nan());
    }

    #[test]
    fn corners_limit_the_reach() {
        let p = Point::new;
        // A square: every vertex is a corner.
        let sq = square();
        assert_eq!(sq.reach(0, 0.25, 2.0), 0.75);
        assert_eq!(sq.reach(0, 0.25, -2.0), -0.25);
        assert_eq!(sq.reach(3, 3.5, 2.0), 0.5);
        assert_eq!(sq.reach(0, 0.0, -2.0), -0.0);
        // An open polyline with a gentle bend (not a corner) and a sharp one.
        let line =
            Polyline::new(vec![p(0., 0.), p(1., 0.), p(2., 0.1), p(2., 1.1)], false).unwrap();
        let l1 = line.start(1);
        let l2 = line.start(2);
        assert_eq!(line.reach(0, 0.5, 5.0), l2 - 0.5);
        assert_eq!(line.reach(1, l1 + 0.1, -5.0), -5.0);
        assert_eq!(line.reach(2, l2 + 0.5, 5.0), 5.0);
        assert_eq!(line.reach(2, l2 + 0.5, -5.0), -0.5);
        // A fine circle has no corners.
        let circle: Vec<Point> = (0..360)
            .map(|i| {
                let t = i as f64 * std::f64::consts::TAU / 360.0;
                p(t.cos(), t.sin())
            })
            .collect();
        let c = Polyline::new(circle, true).unwrap();
        assert_eq!(c.reach(10, 0.2, 3.0), 3.0);
        assert_eq!(c.reach(10, 0.2, -3.0), -3.0);
        assert!(c.smooth_between(10, 40) && c.smooth_between(40, 10));
        assert!(!c.smooth_between(1, 359), "a wrap counts as a corner");
        assert!(!sq.smooth_between(0, 2) && sq.smooth_between(1, 1));
        assert!(line.smooth_between(0, 1) && !line.smooth_between(0, 2));
    }

    #[test]
    fn vertex_is_exact() {
        let p = Point::new;
        let line = Polyline::new(vec![p(0.1, 0.7), p(0.3, 0.9), p(1.7, -0.2)], false).unwrap();
        let s1 = line.start(1);
        assert_eq!(line.point_on(0, s1), p(0.3, 0.9));
        assert_eq!(line.point_on(1, s1), p(0.3, 0.9));
        assert_eq!(line.point_on(1, line.length()), p(1.7, -0.2));
    }
}
