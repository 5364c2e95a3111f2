//! Every reflect-only path from one source, by the image-source tree with beam pruning: the
//! automatic search's tree for reflections, shared by every receiver of the source. Each
//! segment of each reflecting interface (open or closed, of any number of segments) is one
//! wall; every leg is in the source's medium (a reflection keeps the medium), so one slowness:
//! a uniform medium's straight legs (`leg.rs`, [`Uniform`]), the image method's.
//!
//! A depth-first walk over wall sequences from the source. Each node of the tree holds the
//! source's image (mirrored in each wall's line in turn) and its beam: the wedge from the
//! image through the part of the last wall that rays can reach (clipped by the parent's
//! beam), beyond that wall's line. A child wall is visited only where part of it lies in the
//! beam; an empty clip prunes the whole subtree. The same wall twice in a row is no path (its
//! two points would lie on one line); two adjacent segments of one polyline are two walls, and
//! the beam's clip keeps the pair only where their corner is concave. At each node, each
//! receiver in the beam gets the image method's path (the line from the image to the receiver
//! meets the last wall's line, the line from the image before to that point the wall
//! before's, …), validated as the classifier validates a ray: each point on its segment,
//! strictly inside it except at a free end (an open end of its polyline where no other
//! segment ends: a path through it reflects there, as the complete search finds it; a point
//! exactly on a vertex between two segments is a `vertex` case, and one on a corner where two
//! interfaces end is no reflection either, so that a room drawn one interface per wall gives
//! the arrivals of its polyline), both legs of each reflection strictly on one side of its
//! wall ([`leg_sides`], [`sides_suit`]), no vanished leg between two reflections, and no leg crossing an interface
//! strictly between its ends ([`Scene::first_crossing`] with the classifier's margin and the
//! legs' own segments left out).
//!
//! The arithmetic of a wall depends only on its segment's end points and its polyline's unit
//! normal there, which are the same whether the segment is an interface of its own or one
//! segment of a polyline: a room drawn as one closed polyline gives the same paths, to the
//! bit, as the room drawn one interface per wall.
//!
//! **The time bound.** Every path at or below a node, to any receiver `r`, is at least
//! `|I − r|` long, `I` the node's image: the path up to the node's last reflection point `p`
//! unfolds to the straight segment from `I` to `p`, and the rest is at least `|p − r|` long,
//! so the whole is at least `|I − p| + |p − r| ≥ |I − r|`; and it is at least `|I − p|`, `p`
//! on the part of the wall the beam reaches. So a node whose image lies farther than
//! `max_time / slowness` from the receivers' box, or from its wall's reachable part, is pruned
//! with its whole subtree, as is a receiver farther than that from the image. Tighter, and
//! what prunes the beams that reach no receiver in time: the rest after `p` is at least
//! `dist(p, box)` long, so a node is pruned where the least `|I − p| + dist(p, box)` over `p`
//! in the reachable part (a convex function along it, bounded from below by tangents,
//! [`Bounds::late_through`]) exceeds `max_time / slowness`. The margin is
//! the beam tests' (far more than the round-off of the distances), so a path whose computed
//! time is within `max_time` is never pruned by rounding. Each path's own computed time then
//! decides.
//!
//! The pruning is certain: every beam test is widened by [`BEAM_MARGIN`] of the coordinates'
//! magnitude (far more than the round-off of the images, which grows by a few ulps a level),
//! so that a path the validation would accept is never pruned by rounding; the per-path
//! validation alone decides. Where the side of a wall's line an image lies on is within that
//! margin, the child's beam is the whole plane (no pruning below it).
//!
//! One pruning relies on exact geometry instead ([`MirrorWalls::tight`]): each beam also
//! carries its tight beam, clipped level after level without any margin; a child whose
//! window, clipped so, is empty or one point holds only rays through a corner, which no
//! valid path follows; certain but for the round-off of those clips (1e-15 of the
//! coordinates a level). It removes the slivers that the margins alone keep where a beam's
//! edge runs exactly through a corner, and the slivers below them.

use crate::geom::{Aabb, Point, Vec2, orient};
use crate::leg::Uniform;
use crate::scene::{Scene, SegmentRef, StepKind};

use super::classify::{END_MARGIN, leg_sides, sides_suit};
use super::occlusion::{OCCLUSION_MARGIN, Occluders, Target, Window, segment_distance};
use super::{Reason, Status};

mod crossers;
mod grid;
mod shoebox;
use crossers::Crossers;
use shoebox::Shoebox;
mod waveguide;
pub(crate) use grid::TreeRun;
pub(crate) use shoebox::RoomPath;
pub(crate) use waveguide::{GuidePath, Waveguide};

/// The beam tests' margin, relative to the largest coordinate an image can have: each
/// mirroring and clip adds a few ulps (about 1e-16) of it, so this covers thousands of levels
/// (and it grows with the deepest level a search allows).
const BEAM_MARGIN: f64 = 1e-11;

/// Beams a tree asks its run for at a time (its `progress`).
pub(crate) const PROGRESS_BEAMS: u64 = 1 << 14;

/// Wall tries (children tested, made or not) between two polls of a tree's run for a stop
/// request: a node of many walls may try thousands before its next beam.
const POLL_TRIES: u32 = 1 << 12;

/// One wall: segment `p → q` of an interface.
#[derive(Clone, Copy, Debug)]
struct Wall {
    /// Its segment, as the obstruction test names it (interface and segment index).
    own: SegmentRef,
    /// The arclength of the polyline where the segment starts.
    start: f64,
    /// Start and end.
    p: Point,
    q: Point,
    /// `q − p`.
    e: Vec2,
    /// The unit normal (the polyline's: the segment's tangent turned left).
    n: Vec2,
    /// Whether `p`, and `q`, is a free end: an open end of its polyline where no other segment
    /// of the scene ends (not a vertex between two of its segments, nor a corner where two
    /// interfaces meet): a reflection may lie there.
    open: [bool; 2],
}

impl Wall {
    /// Signed distance of `x` from the wall's line (positive on the side `n` points to).
    #[inline(always)]
    fn height(&self, x: Point) -> f64 {
        self.n.dot(x - self.p)
    }

    /// `x` mirrored in the wall's line.
    #[inline(always)]
    fn mirror(&self, x: Point) -> Point {
        x - self.n * (2.0 * self.height(x))
    }

    /// The point at fraction `u` of the way from `p` to `q`.
    #[inline(always)]
    fn at(&self, u: f64) -> Point {
        self.p + self.e * u
    }

    /// [`Wall::at`], exactly `q` at 1 (the tight beam's edges run exactly through a corner
    /// where its clip ends there).
    #[inline(always)]
    fn end_at(&self, u: f64) -> Point {
        if u == 1.0 { self.q } else { self.at(u) }
    }
}

/// The walls a search may reflect off: every segment of the reflecting interfaces.
#[derive(Clone, Debug)]
pub(crate) struct MirrorWalls {
    /// Per wall: its segment, ends, direction and unit normal.
    walls: Vec<Wall>,
    /// The largest absolute coordinate of any wall end.
    extent: f64,
    /// Every interface segment of the scene, for the occlusion of beams.
    occluders: Occluders,
    /// The rectangle the walls form, when they are the scene's only segments
    /// (`mirrors/shoebox.rs`: its arrivals from the image lattice).
    shoebox: Option<Shoebox>,
    /// The two parallel walls the walls form, when they are the scene's only segments
    /// (`mirrors/waveguide.rs`: a streamed search's arrivals from their image lattice).
    waveguide: Option<Waveguide>,
    /// Per pair of walls (`last · count + child`), the heights of the child's ends above the
    /// last's line ([`MirrorWalls::behind`]); empty above [`BEHIND_WALLS`] walls.
    heights: Vec<[f64; 2]>,
    /// Per pair of walls, the segments a leg between them can be found to cross
    /// (`mirrors/crossers.rs`); none kept above [`BEHIND_WALLS`] walls.
    crossers: Crossers,
}

/// The most walls whose pairs [`MirrorWalls::behind`] keeps heights for (a table of their
/// square).
const BEHIND_WALLS: usize = 64;

/// Where a wall of [`MirrorWalls`] lies in the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct WallPlace {
    /// The interface's index in the scene.
    pub interface: usize,
    /// The segment's index in its interface.
    pub segment: usize,
    /// The arclength of the polyline where the segment starts.
    pub start: f64,
    /// The segment's first vertex.
    pub p: Point,
}

/// The beam of a node of the image-source tree: the rays from the node's image through the
/// part `a → b` of its wall (a at the lower fraction along the wall) that continue beyond
/// the wall's line.
#[derive(Clone, Copy, Debug)]
struct Beam {
    /// Which side of the wall's line the reflected rays travel on: +1 or −1 (the side of the
    /// image before the mirroring, opposite the node's image).
    side: f64,
    /// `a − image` and `b − image`, the wedge's edges.
    to_a: Vec2,
    to_b: Vec2,
    /// `|to_a|₁` and `|to_b|₁`, for the tests' margins.
    reach_a: f64,
    reach_b: f64,
    /// The window's ends `a` and `b` themselves.
    a: Point,
    b: Point,
    /// The edges of the tight beam: the rays from the image through the window clipped
    /// without any margin, level after level ([`MirrorWalls::tight`]): the true beam to
    /// round-off, narrower than `to_a → to_b` by the margins.
    tight_a: Vec2,
    tight_b: Vec2,
}

/// A node of the image-source tree on the search's stack.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// The index (into [`MirrorWalls`]) of the last wall, `usize::MAX` at the root.
    wall: usize,
    /// The source mirrored in each wall of the sequence in turn.
    image: Point,
    /// Its beam; `None` where it is the whole plane (at the root, and below an image whose
    /// side of its wall's line is within the margin).
    beam: Option<Beam>,
    /// The next child wall to try.
    next: usize,
}

/// The search's reusable state: the stack of the beam tree, its walls, and the points of the
/// path under validation. Once grown to the longest sequence, a search allocates nothing but
/// its results.
#[derive(Clone, Debug, Default)]
pub(crate) struct MirrorScratch {
    /// The nodes from the root to the present one.
    stack: Vec<Node>,
    /// The walls of the nodes below the root (the present sequence).
    walls: Vec<usize>,
    /// Source, reflection points, receiver of the path under validation.
    points: Vec<Point>,
    /// The points relative to the source.
    rel: Vec<Vec2>,
    /// The legs' lengths.
    lens: Vec<f64>,
    /// Per leg, the receiver mirrored back into the leg's frame: the leg lies on the line
    /// from its node's image through it.
    far: Vec<Point>,
    /// The hidden intervals of a child wall (the occlusion's scratch).
    shadows: Vec<[f64; 2]>,
    /// What each node on the stack certainly holds (the streamed walk's, `mirrors/grid.rs`).
    certain: Vec<grid::Certain>,
    /// The bounce groups and mirrored axes of the nodes on the stack (`mirrors/grid.rs`).
    bounces: grid::Bounces,
}

/// One source's search: what the tree walks and its bounds.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MirrorSearch<'a> {
    /// The scene (for the obstruction test).
    pub scene: &'a Scene,
    /// The source.
    pub source: Point,
    /// The receivers.
    pub receivers: &'a [Point],
    /// The most reflections of a path (at most `max_depth` are walked).
    pub max_steps: usize,
    /// The most reflections walked whatever `max_steps` ([`Limits::depth`](crate::options::Limits)).
    pub max_depth: usize,
    /// The latest time listed (infinite: no bound).
    pub max_time: f64,
    /// The slowness of every leg (time = slowness × length).
    pub slowness: f64,
    /// Whether obstructed paths are listed too (with [`Status::Obstructed`] and
    /// [`Reason::Crosses`]).
    pub obstructed: bool,
    /// Beams visited before the search stops.
    pub max_beams: u64,
    /// Work (in the units of `solver.max_work`: one per child wall tried, one per segment an
    /// occlusion test weighs, one per leg of a path validated) before the search stops.
    pub max_work: u64,
}

impl MirrorSearch<'_> {
    /// The medium of every leg: a uniform one, whose legs are straight (the image method's
    /// legs; a medium with a speed gradient has no images, and its reflect-only sequences go
    /// to the walk over sequences).
    #[inline]
    fn medium(&self) -> Uniform {
        Uniform::new(self.slowness)
    }
}

/// One path the tree found, as the tree holds it (valid during the call that reports it).
#[derive(Clone, Copy, Debug)]
pub(crate) struct MirrorPath<'a> {
    /// The receiver's index in the receivers given.
    pub receiver: usize,
    /// The walls of its reflections, in order (indices into [`MirrorWalls`]).
    pub walls: &'a [usize],
    /// Source, reflection points, receiver.
    pub points: &'a [Point],
    /// Travel time: the slowness times the path's length.
    pub time: f64,
    /// [`Status::Converged`], or [`Status::Obstructed`] when a leg crosses an interface.
    pub status: Status,
    /// For an obstructed path, the first leg that crosses an interface and that interface.
    pub reason: Option<Reason>,
}

/// What one source's search did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct MirrorStats {
    /// Beams visited (nodes of the tree below the root).
    pub beams: u64,
    /// Paths validated (receivers in a node's beam and within the time bound).
    pub leaves: u64,
    /// Work done, as [`MirrorSearch::max_work`] counts it.
    pub work: u64,
    /// Whether the search stopped before the end of its tree: at `max_beams`, where its
    /// `found` said so, where its `progress` said so, or at `max_depth` deep with more allowed.
    pub stopped: bool,
}

/// How a beam test of a point came out, with the margin it is widened by.
#[derive(Clone, Copy, Debug)]
struct Gauge {
    /// The three constraints' values: beyond the wall's line, inside edge `a`, inside edge
    /// `b` (each must be at least minus its margin).
    values: [f64; 3],
    /// Their margins.
    margins: [f64; 3],
}

impl Beam {
    /// The constraints of point `x` (`image` the node's image, `wall` its wall, `delta` the
    /// absolute margin on positions).
    #[inline(always)]
    fn gauge(&self, wall: &Wall, image: Point, x: Point, delta: f64) -> Gauge {
        let v = x - image;
        let reach = v.x.abs() + v.y.abs();
        // The wedge turns from `a` to `b` clockwise when the rays run on the positive side
        // (its orientation is −side: the image lies on the negative side, see the module).
        let o = -self.side;
        Gauge {
            values: [
                self.side * wall.height(x),
                o * self.to_a.cross(v),
                o * v.cross(self.to_b),
            ],
            margins: [
                2.0 * delta,
                delta * (self.reach_a + 2.0 * reach),
                delta * (self.reach_b + 2.0 * reach),
            ],
        }
    }

    /// The constraints of point `x` against the tight beam (`tight_a → tight_b`), with no
    /// margin: each is at least 0 where `x` lies in it.
    #[inline(always)]
    fn tight_values(&self, wall: &Wall, image: Point, x: Point) -> [f64; 3] {
        let v = x - image;
        let o = -self.side;
        [
            self.side * wall.height(x),
            o * self.tight_a.cross(v),
            o * v.cross(self.tight_b),
        ]
    }

    /// Whether `x` may lie in the beam (certainly so when it lies in it).
    #[inline(always)]
    fn holds(&self, wall: &Wall, image: Point, x: Point, delta: f64) -> bool {
        let g = self.gauge(wall, image, x, delta);
        (g.values[0] >= -g.margins[0])
            & (g.values[1] >= -g.margins[1])
            & (g.values[2] >= -g.margins[2])
    }
}

/// The fractions `[lo, hi]` of a segment from `x(0)` to `x(1)` where an affine constraint
/// with values `g0` and `g1` at the ends is at least `-margin`, intersected with `range`;
/// `None` when empty.
#[inline(always)]
fn restrict(range: [f64; 2], g0: f64, g1: f64, margin: f64) -> Option<[f64; 2]> {
    let (f0, f1) = (g0 + margin, g1 + margin);
    let [mut lo, mut hi] = range;
    if f0 >= 0.0 && f1 >= 0.0 {
        return Some(range);
    }
    if !(f0 >= 0.0 || f1 >= 0.0) {
        return None;
    }
    // One end in, one out: the root, widened outward by its round-off.
    let u = f0 / (f0 - f1);
    if f0 < 0.0 {
        lo = lo.max(u - 4.0 * f64::EPSILON);
    } else {
        hi = hi.min(u + 4.0 * f64::EPSILON);
    }
    (lo <= hi).then_some([lo, hi])
}

/// The fractions `[lo, hi]` of a segment from `x(0)` to `x(1)` where an affine constraint
/// with values `g0` and `g1` at the ends is at least 0, intersected with `range`, with no
/// margin and the root not widened (the tight beam's clip: the exact one to round-off, and
/// exact where the root is, as at a constraint that vanishes at an end); `None` when empty.
#[inline(always)]
fn restrict_tight(range: [f64; 2], g0: f64, g1: f64) -> Option<[f64; 2]> {
    let [mut lo, mut hi] = range;
    if g0 >= 0.0 && g1 >= 0.0 {
        return Some(range);
    }
    if !(g0 >= 0.0 || g1 >= 0.0) {
        return None;
    }
    let u = g0 / (g0 - g1);
    if g0 < 0.0 {
        lo = lo.max(u);
    } else {
        hi = hi.min(u);
    }
    (lo <= hi).then_some([lo, hi])
}

/// Whether `wall` shares an end with `last` (exactly) and its other end lies strictly on the
/// side of `last`'s line that the beam's rays do not travel on (`side`, exact orientation):
/// every point of `wall` but the shared corner is then behind `last`, so no path reflects off
/// `last` and then strictly inside `wall` (the beam's margins alone would keep a sliver at
/// the corner, and a chain of slivers below it).
#[inline]
fn behind_corner(last: &Wall, wall: &Wall, side: f64) -> bool {
    let other = if wall.p == last.p || wall.p == last.q {
        wall.q
    } else if wall.q == last.p || wall.q == last.q {
        wall.p
    } else {
        return false;
    };
    // `n` is `e` turned left: the positive side is the left of `p → q`.
    let o = crate::geom::orient(last.p, last.q, other);
    o != 0.0 && o.signum() != side
}

/// Whether `wall` meets the beam at a window's end alone: it starts at that end exactly (a
/// corner it shares with the window's wall) and its other end lies certainly outside the
/// beam's edge through that end (beyond the margin), so that every point of it but the
/// corner lies outside the beam. (The margins alone would keep a sliver at the corner.)
#[inline]
fn beyond_edge(beam: &Beam, last: &Wall, image: Point, wall: &Wall, delta: f64) -> bool {
    [(beam.a, 1), (beam.b, 2)].into_iter().any(|(end, c)| {
        let other = if end == wall.p {
            wall.q
        } else if end == wall.q {
            wall.p
        } else {
            return false;
        };
        let g = beam.gauge(last, image, other, delta);
        g.values[c] < -g.margins[c]
    })
}

/// The angle (radians, up to a factor near 1 for thin ones) that segment `a–b` subtends
/// from `x`: `|sin|` of the angle between the rays to its ends.
#[inline(always)]
fn subtends(x: Point, a: Point, b: Point) -> f64 {
    let (u, v) = (a - x, b - x);
    let d = u.length() * v.length();
    if d > 0.0 { u.cross(v).abs() / d } else { 0.0 }
}

/// Whether segment `a–b` subtends less than [`THIN`] from `x` ([`subtends`] below it): decided
/// from the squares of the sine's terms where they are farther from the threshold than
/// their round-off (some 1e-15 relative, against a band of 1e-9), else by [`subtends`] itself,
/// so always as [`subtends`] decides, without its two square roots but near the threshold.
#[inline(always)]
fn thin(x: Point, a: Point, b: Point) -> bool {
    let (u, v) = (a - x, b - x);
    let cross = u.cross(v);
    let (uu, vv) = (u.dot(u), v.dot(v));
    let (lhs, rhs) = (cross * cross, THIN * THIN * uu * vv);
    // Both finite and normal (no overflow or underflow in the squares): the band decides.
    if lhs.is_normal() && rhs.is_normal() {
        if lhs < rhs * (1.0 - 1e-9) {
            return true;
        }
        if lhs > rhs * (1.0 + 1e-9) {
            return false;
        }
    }
    subtends(x, a, b) < THIN
}

/// The bounds of one search, fixed at its start: the margin of the beam tests and the time
/// bound's test.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    /// The absolute margin on positions.
    delta: f64,
    /// The receivers' box.
    receivers: Aabb,
    /// `max_time / slowness` (infinite: no bound).
    reach: f64,
    /// Whether a node is also pruned by the shortest way from its image through its wall's
    /// part to the receivers' box ([`Bounds::late_through`]); off only in tests, to show it
    /// changes no arrival.
    through: bool,
    /// Whether a child is also pruned where its window, clipped without the margins, holds
    /// no ray or only the rays through one point ([`MirrorWalls::tight`]); off only in
    /// tests, to show it changes no arrival.
    degenerate: bool,
}

/// The widest angle (radians) a child's window may subtend from its image and still be
/// clipped by the shadows with no margin in [`MirrorWalls::tight`]: a window the margins
/// alone keep is far narrower (their width over the beam's length, some 1e-6 here), and a
/// wider one is not worth the test.
const THIN: f64 = 1e-4;

/// The most halvings [`Bounds::late_through`] makes of a wall's part.
const THROUGH_STEPS: u32 = 24;

impl Bounds {
    /// Whether every path at or below a node of image `image`, whose beam reaches its wall's
    /// part `a–b` (`None`: the root), certainly takes longer than the time bound.
    #[inline(always)]
    fn late(&self, image: Point, part: Option<(Point, Point)>) -> bool {
        if self.reach.is_infinite() {
            return false;
        }
        let mut d = self.receivers.distance_sq(image).sqrt();
        if let Some((a, b)) = part {
            d = d.max(segment_distance(image, a, b));
        }
        if d - 4.0 * self.delta > self.reach {
            return true;
        }
        match part {
            Some((a, b)) if self.through => self.late_through(image, a, b),
            _ => false,
        }
    }

    /// The length `|image − x| + dist(x, box)` of the shortest way from `image` through the
    /// point `x = a + t (b − a)` to the receivers' box, and a subgradient of it in `t`.
    #[inline(always)]
    fn through_at(&self, image: Point, a: Point, e: Vec2, t: f64) -> (f64, f64) {
        let x = a + e * t;
        let u = x - image;
        let c = Point::new(
            x.x.clamp(self.receivers.min.x, self.receivers.max.x),
            x.y.clamp(self.receivers.min.y, self.receivers.max.y),
        );
        let v = x - c;
        let (du, dv) = (u.length(), v.length());
        let mut g = 0.0;
        if du > 0.0 {
            g += e.dot(u) / du;
        }
        if dv > 0.0 {
            g += e.dot(v) / dv;
        }
        (du + dv, g)
    }

    /// Whether every way from `image` through a point of `a–b` to the receivers' box is
    /// certainly longer than the reach (by more than the margin, four beam margins): every
    /// path below a node leaves its image along a straight (unfolded) leg to a point `x` of
    /// its wall's part and then goes on at least `dist(x, box)` to its receiver.
    ///
    /// `f(t) = |image − x(t)| + dist(x(t), box)` is convex along the segment (a norm and the
    /// distance to a convex set, of an affine point), so each tangent `f(s) + g(s) (t − s)`
    /// (`g` a subgradient: the terms' unit vectors dotted with `b − a`, 0 where a term is
    /// 0) lies below it everywhere. Bisecting on the sign of `g` keeps a bracket `lo < hi`
    /// with `g(lo) < 0 < g(hi)`; the two tangents there meet at or below the minimum, and
    /// the smaller of the two at any `t` is at most where they meet, so it bounds every
    /// `f(t)` from below whatever the round-off of that `t`. Any sample within the reach
    /// (plus the margin) ends the test: no pruning is possible.
    #[inline]
    fn late_through(&self, image: Point, a: Point, b: Point) -> bool {
        let margin = 4.0 * self.delta;
        let late = |f: f64| f - margin > self.reach;
        let e = b - a;
        let (f0, g0) = self.through_at(image, a, e, 0.0);
        if !late(f0) {
            return false;
        }
        if g0 >= 0.0 {
            return true;
        }
        let (f1, g1) = self.through_at(image, a, e, 1.0);
        if !late(f1) {
            return false;
        }
        if g1 <= 0.0 {
            return true;
        }
        let (mut lo, mut hi) = ((0.0, f0, g0), (1.0, f1, g1));
        for _ in 0..THROUGH_STEPS {
            let ((tl, fl, gl), (th, fh, gh)) = (lo, hi);
            let t = (fl - fh - gl * tl + gh * th) / (gh - gl);
            let below = (fl + gl * (t - tl)).min(fh + gh * (t - th));
            if late(below) {
                return true;
            }
            let tm = 0.5 * (tl + th);
            let (fm, gm) = self.through_at(image, a, e, tm);
            if !late(fm) {
                return false;
            }
            if gm == 0.0 {
                return true;
            }
            if gm > 0.0 {
                hi = (tm, fm, gm);
            } else {
                lo = (tm, fm, gm);
            }
        }
        false
    }
}

impl MirrorWalls {
    /// Every segment of each of `interfaces` (scene interface indices), in order.
    pub(crate) fn new(scene: &Scene, interfaces: &[usize]) -> MirrorWalls {
        // The ends of every segment of the scene, to tell a free end from a corner where
        // another interface ends too (a room drawn one interface per wall).
        let mut ends: Vec<(u64, u64)> = (0..scene.interfaces().len())
            .flat_map(|i| {
                let line = &scene.interfaces()[i].polyline;
                (0..line.num_segments()).flat_map(move |j| {
                    let s = line.segment(j);
                    [s.start, s.end]
                })
            })
            .map(|p| (p.x.to_bits(), p.y.to_bits()))
            .collect();
        ends.sort_unstable();
        let shared = |p: Point| {
            let key = (p.x.to_bits(), p.y.to_bits());
            ends.partition_point(|&e| e < key) + 1 < ends.partition_point(|&e| e <= key)
        };
        let mut walls = Vec::new();
        for &interface in interfaces {
            let line = &scene.interfaces()[interface].polyline;
            for segment in 0..line.num_segments() {
                let s = line.segment(segment);
                walls.push(Wall {
                    own: SegmentRef {
                        interface: interface as u32,
                        segment: segment as u32,
                    },
                    start: line.start(segment),
                    p: s.start,
                    q: s.end,
                    e: s.end - s.start,
                    n: line.normal(segment),
                    open: [
                        !line.is_closed() && segment == 0 && !shared(s.start),
                        !line.is_closed() && segment + 1 == line.num_segments() && !shared(s.end),
                    ],
                });
            }
        }
        let extent = walls
            .iter()
            .flat_map(|w| [w.p, w.q])
            .fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
        let shoebox = Shoebox::of(scene, &walls, extent);
        let waveguide = Waveguide::of(scene, &walls);
        let heights = if walls.len() <= BEHIND_WALLS {
            (walls.iter())
                .flat_map(|last| walls.iter().map(|w| [last.height(w.p), last.height(w.q)]))
                .collect()
        } else {
            Vec::new()
        };
        let crossers = if walls.len() <= BEHIND_WALLS {
            Crossers::new(scene, &walls)
        } else {
            Crossers::default()
        };
        MirrorWalls {
            walls,
            extent,
            occluders: Occluders::new(scene),
            shoebox,
            waveguide,
            heights,
            crossers,
        }
    }

    /// Whether wall `w` lies wholly behind wall `last`'s line, beyond the beam tests' margin
    /// (`delta`), on the side that a beam of `last` whose rays travel on `side` does not
    /// reach: then [`child`](Self::child) clips `w` to nothing by its first constraint (this
    /// is that test, on the same numbers), so the child is none. `false` where no heights
    /// are kept (over [`BEHIND_WALLS`] walls).
    #[inline(always)]
    fn behind(&self, last: usize, w: usize, side: f64, delta: f64) -> bool {
        let Some(&[hp, hq]) = self.heights.get(last * self.walls.len() + w) else {
            return false;
        };
        // As `Beam::gauge` and `restrict` take them: the value times the side, plus the
        // margin (the larger of the two ends', which are equal).
        let margin = 2.0 * delta;
        !(side * hp + margin >= 0.0 || side * hq + margin >= 0.0)
    }

    /// The number of walls.
    pub(crate) fn count(&self) -> usize {
        self.walls.len()
    }

    /// Where wall `i` lies in the scene.
    pub(crate) fn place(&self, i: usize) -> WallPlace {
        let w = &self.walls[i];
        WallPlace {
            interface: w.own.interface as usize,
            segment: w.own.segment as usize,
            start: w.start,
            p: w.p,
        }
    }

    /// Every reflect-only sequence of 0..=`max_steps` walls from the source to each receiver
    /// whose path exists and arrives by `max_time`, reported to `found` in the order of the
    /// tree's walk: each reflection point strictly inside its wall or on a free end, both legs
    /// of each reflection strictly on one side of it, no vanished leg between reflections, and
    /// (unless `obstructed`, which lists obstructed paths too, with [`Status::Obstructed`] and
    /// [`Reason::Crosses`]) no leg crossing an interface of the scene strictly between its
    /// ends (the classifier's test). Sequence 0 is the direct ray. `found` returns `false` to
    /// stop the search; `progress` is asked for every [`PROGRESS_BEAMS`] beams before they
    /// are visited (and polled with 0 every [`POLL_TRIES`] walls tried), and returns `false`
    /// to stop it (a stop request, a budget spent).
    pub(crate) fn arrivals(
        &self,
        search: &MirrorSearch<'_>,
        scratch: &mut MirrorScratch,
        found: &mut impl FnMut(MirrorPath<'_>) -> bool,
        progress: &mut impl FnMut(u64) -> bool,
    ) -> MirrorStats {
        self.arrivals_with(search, scratch, found, None, progress)
    }

    /// [`MirrorWalls::arrivals`] for a caller that needs no points: in a rectangular room,
    /// the paths whose sequence the image lattice makes certain go to `unfolded` in closed
    /// form ([`RoomPath`]: length, time, reflections per wall and the two incidence angles),
    /// every other one to `found` as [`arrivals`](Self::arrivals) gives it. The same paths,
    /// to round-off; everywhere else the same as [`arrivals`](Self::arrivals).
    pub(crate) fn arrivals_unfolded(
        &self,
        search: &MirrorSearch<'_>,
        scratch: &mut MirrorScratch,
        found: &mut impl FnMut(MirrorPath<'_>) -> bool,
        unfolded: &mut dyn FnMut(&RoomPath) -> bool,
        progress: &mut impl FnMut(u64) -> bool,
    ) -> MirrorStats {
        self.arrivals_with(search, scratch, found, Some(unfolded), progress)
    }

    /// [`MirrorWalls::arrivals`], with [`arrivals_unfolded`](Self::arrivals_unfolded)'s
    /// closed forms where `unfolded` is given.
    fn arrivals_with(
        &self,
        search: &MirrorSearch<'_>,
        scratch: &mut MirrorScratch,
        found: &mut impl FnMut(MirrorPath<'_>) -> bool,
        unfolded: Option<&mut dyn FnMut(&RoomPath) -> bool>,
        progress: &mut impl FnMut(u64) -> bool,
    ) -> MirrorStats {
        let bounds = self.bounds(search, search.max_steps.min(search.max_depth));
        if let Some(room) = &self.shoebox
            && room.serves(search)
        {
            return self.room_arrivals(room, search, &bounds, scratch, found, unfolded, progress);
        }
        self.walk(search, &bounds, scratch, found, progress)
    }

    /// Whether `search` goes through the image lattice of a rectangular room (where
    /// [`arrivals_unfolded`](Self::arrivals_unfolded) gives closed forms), and its walls
    /// (indices into the walls) on the local lines x = 0, x = L₁, y = 0, y = L₂.
    pub(crate) fn room_walls(&self, search: &MirrorSearch<'_>) -> Option<[usize; 4]> {
        self.shoebox
            .as_ref()
            .filter(|room| room.serves(search))
            .map(Shoebox::walls)
    }

    /// [`MirrorWalls::arrivals`] through the beam tree, also in a rectangular room (the
    /// reference of the lattice's tests).
    #[cfg(test)]
    pub(crate) fn tree_arrivals(
        &self,
        search: &MirrorSearch<'_>,
        scratch: &mut MirrorScratch,
        found: &mut impl FnMut(MirrorPath<'_>) -> bool,
        progress: &mut impl FnMut(u64) -> bool,
    ) -> MirrorStats {
        let bounds = self.bounds(search, search.max_steps.min(search.max_depth));
        self.walk(search, &bounds, scratch, found, progress)
    }

    /// [`MirrorWalls::arrivals`] within `bounds`.
    fn walk(
        &self,
        search: &MirrorSearch<'_>,
        bounds: &Bounds,
        scratch: &mut MirrorScratch,
        found: &mut impl FnMut(MirrorPath<'_>) -> bool,
        progress: &mut impl FnMut(u64) -> bool,
    ) -> MirrorStats {
        let mut stats = MirrorStats::default();
        let max_steps = search.max_steps.min(search.max_depth);
        let (mut granted, mut tries) = (0u64, 0u32);
        let MirrorScratch {
            stack,
            walls,
            points,
            rel,
            lens,
            far,
            shadows,
            ..
        } = scratch;
        stack.clear();
        walls.clear();
        if bounds.late(search.source, None) {
            return stats;
        }
        stack.push(Node {
            wall: usize::MAX,
            image: search.source,
            beam: None,
            next: 0,
        });
        let mut validation = Validation {
            search,
            walls: &self.walls,
            points,
            rel,
            lens,
            far,
            crossings: true,
            crossers: Some(&self.crossers),
        };
        if !validation.node(stack, walls, bounds, found, &mut stats) {
            stats.stopped = true;
            return stats;
        }
        while let Some(top) = stack.last_mut() {
            let depth = walls.len();
            if depth >= max_steps || top.next >= self.walls.len() {
                if depth >= max_steps && search.max_steps > max_steps && depth > 0 {
                    // The tree's own depth limit, below which paths may remain.
                    stats.stopped = true;
                }
                stack.pop();
                walls.pop();
                continue;
            }
            let w = top.next;
            top.next += 1;
            if w == top.wall {
                continue;
            }
            tries = tries.wrapping_add(1);
            if tries % POLL_TRIES == 0 && !progress(0) {
                stats.stopped = true;
                break;
            }
            stats.work += 1;
            if stats.work > search.max_work {
                stats.stopped = true;
                break;
            }
            let occlusion = (!search.obstructed).then_some(&mut *shadows);
            // Most walls tried are none of the node's children, many because they lie behind
            // its wall: that one test first, from the walls' heights.
            if let Some(beam) = &top.beam
                && self.behind(top.wall, w, beam.side, bounds.delta)
            {
                continue;
            }
            // The node in place (a copy of its beam per wall tried costs more than the test),
            // and its beam's clip first, here.
            let Some(range) = self.in_beam(top, w, bounds.delta) else {
                continue;
            };
            let Some(child) = self.child_in(top, w, range, bounds, occlusion, &mut stats.work)
            else {
                continue;
            };
            stats.beams += 1;
            if stats.beams > granted {
                if !progress(PROGRESS_BEAMS) {
                    stats.beams -= 1;
                    stats.stopped = true;
                    break;
                }
                granted += PROGRESS_BEAMS;
            }
            if stats.beams > search.max_beams {
                stats.beams -= 1;
                stats.stopped = true;
                break;
            }
            stack.push(child);
            walls.push(w);
            if !validation.node(stack, walls, bounds, found, &mut stats) {
                stats.stopped = true;
                break;
            }
        }
        stats
    }

    /// The margin and time bound of `search`, walked `max_steps` deep.
    fn bounds(&self, search: &MirrorSearch<'_>, max_steps: usize) -> Bounds {
        let big = |p: &Point| p.x.abs().max(p.y.abs());
        let far = search.receivers.iter().map(big).fold(0.0f64, f64::max);
        let reach = search.medium().reach(search.max_time);
        // |image| ≤ |source| + 2 k |wall point| (a mirroring keeps distances to its line's
        // points), in the max-norm within a factor √2; an image the time bound keeps lies
        // within `reach` of the receivers' box, and its children one mirroring (at most
        // three times its distance from a wall point) farther.
        let by_steps = (3 * max_steps + 1) as f64 * self.extent;
        let by_time = 3.0 * (far + 1.01 * reach) + 3.0 * self.extent;
        let scale = 1.5 * big(&search.source) + far + by_steps.min(by_time);
        // Round-off grows by a few ulps a level: more margin for deeper trees.
        let levels = 1.0 + max_steps as f64 / 1000.0;
        Bounds {
            delta: BEAM_MARGIN * scale * levels,
            receivers: Aabb::around(search.receivers),
            reach,
            through: true,
            degenerate: true,
        }
    }

    /// The child of `node` through wall `w`, if part of the wall lies in the node's beam (and,
    /// with `occlusion`, is not hidden from it) and a path through that part may arrive in
    /// time; the occlusion test's work is added to `work`.
    #[inline]
    fn child(
        &self,
        node: &Node,
        w: usize,
        bounds: &Bounds,
        occlusion: Option<&mut Vec<[f64; 2]>>,
        work: &mut u64,
    ) -> Option<Node> {
        let range = self.in_beam(node, w, bounds.delta)?;
        self.child_in(node, w, range, bounds, occlusion, work)
    }

    /// The part of wall `w` (fractions along it) that lies in `node`'s beam, with the margin
    /// `delta` (all of it where the beam is the whole plane): the first test of
    /// [`child`](Self::child), which leaves out most walls (inlined where the tree walks,
    /// the rest of the child made only for the walls it keeps).
    #[inline(always)]
    fn in_beam(&self, node: &Node, w: usize, delta: f64) -> Option<[f64; 2]> {
        let wall = &self.walls[w];
        let mut range = [0.0, 1.0];
        if let Some(beam) = &node.beam {
            let last = &self.walls[node.wall];
            let gp = beam.gauge(last, node.image, wall.p, delta);
            let gq = beam.gauge(last, node.image, wall.q, delta);
            for c in 0..3 {
                let margin = gp.margins[c].max(gq.margins[c]);
                range = restrict(range, gp.values[c], gq.values[c], margin)?;
            }
            // After the clips, which leave out most walls first (each test only prunes, so
            // the order changes no child).
            if behind_corner(last, wall, beam.side)
                || beyond_edge(beam, last, node.image, wall, delta)
            {
                return None;
            }
        }
        Some(range)
    }

    /// [`child`](Self::child) of the part `range` of wall `w` that lies in `node`'s beam
    /// ([`in_beam`](Self::in_beam)).
    #[inline(never)]
    fn child_in(
        &self,
        node: &Node,
        w: usize,
        mut range: [f64; 2],
        bounds: &Bounds,
        mut occlusion: Option<&mut Vec<[f64; 2]>>,
        work: &mut u64,
    ) -> Option<Node> {
        let wall = &self.walls[w];
        let delta = bounds.delta;
        if let Some(shadows) = occlusion.as_deref_mut()
            && let Some(window) = self.window(node)
        {
            let target = Target {
                own: wall.own,
                p: wall.p,
                q: wall.q,
                n: wall.n,
            };
            let m = OCCLUSION_MARGIN * delta;
            *work += self.occluders.work();
            range = self
                .occluders
                .unhidden(&window, &target, range, m, shadows)?;
        }
        let h = wall.height(node.image);
        let image = node.image - wall.n * (2.0 * h);
        let (a, b) = (wall.at(range[0]), wall.at(range[1]));
        if bounds.late(image, Some((a, b))) {
            return None;
        }
        let tight = if bounds.degenerate {
            self.tight(node, w, image, range, occlusion)?
        } else {
            range
        };
        // Where the image's side of the line is not certain, the beam is the whole plane.
        let beam = (h.abs() > 2.0 * delta).then(|| {
            let (to_a, to_b) = (a - image, b - image);
            Beam {
                side: h.signum(),
                to_a,
                to_b,
                reach_a: to_a.x.abs() + to_a.y.abs(),
                reach_b: to_b.x.abs() + to_b.y.abs(),
                a,
                b,
                tight_a: wall.end_at(tight[0]) - image,
                tight_b: wall.end_at(tight[1]) - image,
            }
        });
        Some(Node {
            wall: w,
            image,
            beam,
            next: 0,
        })
    }
}

impl MirrorWalls {
    /// The tight window of `node`'s child through wall `w` (its image `image`): its window as
    /// the margins keep it (`range`), clipped again by the node's tight beam with no margin
    /// and (with `occlusion`, where the window is thin, below [`THIN`]) by the shadows with
    /// no margin; `None` where that is empty or one point (its two ends the same point, or
    /// on one ray from the child's image), so that the child is pruned.
    ///
    /// Such a child holds no path the validation accepts, but through round-off of the
    /// clips (below 1e-15 of the coordinates a level): the tight beam is the true beam (the
    /// rays from the image through the part of the wall that paths can reach) up to that
    /// round-off, since each level clips the true rays with no margin, so every ray of the
    /// child outside it reaches the wall outside the node's true beam, or is hidden, or
    /// passes through the one point where the window's ends meet. That point is a corner: a
    /// wall's end, where a reflection is no path (but at a free end, which keeps the child:
    /// the window then holds that end), or an occluder's end that the ray touches, and a leg
    /// that touches an interface crosses it for the classifier; below such a child every ray
    /// passes through the same corner. These children are the slivers that the margins alone
    /// keep where a beam's edge runs exactly through a corner (a room of right angles and
    /// round coordinates has many), and below them the slivers of their own margins: each
    /// splits again at the next corner its ray meets exactly, so their number grows
    /// exponentially with the path length while the arrivals grow as its square. The
    /// tight beam is kept level after level for that reason: a beam clipped by the margins
    /// alone keeps a sliver one margin wide along its edge.
    fn tight(
        &self,
        node: &Node,
        w: usize,
        image: Point,
        range: [f64; 2],
        occlusion: Option<&mut Vec<[f64; 2]>>,
    ) -> Option<[f64; 2]> {
        let wall = &self.walls[w];
        let mut tight = range;
        if let Some(beam) = &node.beam {
            let last = &self.walls[node.wall];
            let gp = beam.tight_values(last, node.image, wall.p);
            let gq = beam.tight_values(last, node.image, wall.q);
            for c in 0..3 {
                tight = restrict_tight(tight, gp[c], gq[c])?;
            }
        }
        let thin = |t: [f64; 2]| thin(image, wall.end_at(t[0]), wall.end_at(t[1]));
        if let Some(shadows) = occlusion
            && thin(tight)
            && let Some(window) = self.window(node)
        {
            let target = Target {
                own: wall.own,
                p: wall.p,
                q: wall.q,
                n: wall.n,
            };
            tight = self
                .occluders
                .unhidden(&window, &target, tight, 0.0, shadows)?;
        }
        if (tight[0] == 0.0 && wall.open[0]) || (tight[1] == 1.0 && wall.open[1]) {
            return Some(tight);
        }
        let (a, b) = (wall.end_at(tight[0]), wall.end_at(tight[1]));
        (a != b && (a - image).cross(b - image) != 0.0).then_some(tight)
    }

    /// Where the legs of `node`'s children start, for their occlusion: the source at the
    /// root, the beam's part of its wall below it; `None` where its beam is the whole plane.
    fn window(&self, node: &Node) -> Option<Window> {
        if node.wall == usize::MAX {
            return Some(Window {
                image: node.image,
                start: None,
                own: SegmentRef::NONE,
                bounds: Aabb::from_points(node.image, node.image),
            });
        }
        let beam = node.beam.as_ref()?;
        let last = &self.walls[node.wall];
        Some(Window {
            image: node.image,
            start: Some((last.n * beam.side, last.p)),
            own: last.own,
            bounds: Aabb::from_points(node.image + beam.to_a, node.image + beam.to_b),
        })
    }
}

/// What the validation of a node's paths needs: the search, the walls, and the scratch for
/// one path.
struct Validation<'a, 's> {
    search: &'a MirrorSearch<'s>,
    walls: &'a [Wall],
    points: &'a mut Vec<Point>,
    rel: &'a mut Vec<Vec2>,
    lens: &'a mut Vec<f64>,
    far: &'a mut Vec<Point>,
    /// Whether each leg is tested for crossing an interface (the lattice of a rectangular
    /// room leaves it out where no leg can cross one).
    crossings: bool,
    /// [`MirrorWalls::crossers`]: per pair of walls, the segments a leg between them can be
    /// found to cross (`None`: the whole scene's test for every leg).
    crossers: Option<&'a Crossers>,
}

impl Validation<'_, '_> {
    /// The paths of the node on top of `stack` (its walls `walls`) to each receiver in its
    /// beam and within the time bound, validated, reported to `found`; `false` when `found`
    /// stops the search.
    #[inline]
    fn node(
        &mut self,
        stack: &[Node],
        walls: &[usize],
        bounds: &Bounds,
        found: &mut impl FnMut(MirrorPath<'_>) -> bool,
        stats: &mut MirrorStats,
    ) -> bool {
        let top = stack[stack.len() - 1];
        let search = self.search;
        for (r, &receiver) in search.receivers.iter().enumerate() {
            let inside = match &top.beam {
                Some(beam) => beam.holds(&self.walls[top.wall], top.image, receiver, bounds.delta),
                None => true,
            };
            if !inside || top.image.distance(receiver) - 4.0 * bounds.delta > bounds.reach {
                continue;
            }
            stats.leaves += 1;
            stats.work += stack.len() as u64;
            let Some((length, reason)) = self.path(stack, receiver) else {
                continue;
            };
            let time = search.medium().time_along(length);
            if time > search.max_time {
                continue;
            }
            let path = MirrorPath {
                receiver: r,
                walls,
                points: self.points,
                time,
                status: if reason.is_some() {
                    Status::Obstructed
                } else {
                    Status::Converged
                },
                reason,
            };
            if !found(path) {
                return false;
            }
        }
        true
    }

    /// The image method's path of the sequence on `stack` to `receiver` into the scratch's
    /// points, if it is valid: its length, and for an obstructed one (listed when asked) the
    /// first leg that crosses an interface and that interface.
    #[inline]
    fn path(&mut self, stack: &[Node], receiver: Point) -> Option<(f64, Option<Reason>)> {
        let k = stack.len() - 1;
        let source = self.search.source;
        let points = &mut *self.points;
        points.clear();
        points.resize(k + 2, source);
        points[k + 1] = receiver;
        // Backwards: the point of each wall's line that the point after sees its image at.
        // `far` is the receiver mirrored back into wall `i`'s frame: the line from node `i`'s
        // image through it is the path's line there, so which side of it each end of the
        // wall lies on (exact orientation tests) decides where the path meets the wall:
        // exactly for exact images (a dyadic room of axis-aligned walls), to round-off else.
        let fars = &mut *self.far;
        fars.clear();
        fars.resize(k + 1, receiver);
        // Where obstructed paths are not listed, any leg that crosses an interface makes the
        // path none, whichever is found first: the last leg first, the moment its reflection
        // point is known (before the other points are unfolded), for it crosses where a
        // receiver lies outside the walls that the path reflects off (a receiver outside the
        // room is in the beams as often as one inside).
        let last_first = self.crossings && !self.search.obstructed && k > 0;
        let (mut to, mut far) = (receiver, receiver);
        for i in (1..=k).rev() {
            let node = &stack[i];
            let wall = &self.walls[node.wall];
            let sp = orient(node.image, far, wall.p);
            let sq = orient(node.image, far, wall.q);
            // Strictly inside the segment, or on a free end: a path through a free end reflects
            // there, as the complete search finds it, while one through a vertex between two
            // segments is a `vertex` case and one through a corner of two walls no reflection.
            let u = if sp * sq < 0.0 {
                let d = to - node.image;
                ((wall.p - node.image).cross(d) / d.cross(wall.e)).clamp(0.0, 1.0)
            } else if sp == 0.0 && sq != 0.0 && wall.open[0] {
                0.0
            } else if sq == 0.0 && sp != 0.0 && wall.open[1] {
                1.0
            } else {
                return None;
            };
            // A leg along the wall's line (NaN) is no path.
            if u.is_nan() {
                return None;
            }
            to = wall.at(u);
            points[i] = to;
            if last_first && i == k {
                // The last leg, on the line from the last image through the receiver.
                let own = wall.own;
                let line = [node.image, receiver];
                let crossing = (self.search.scene).first_crossing_on_line(
                    to,
                    receiver,
                    line,
                    END_MARGIN,
                    [own, SegmentRef::NONE],
                );
                if to != receiver && crossing.is_some() {
                    return None;
                }
            }
            far = wall.mirror(far);
            fars[i - 1] = far;
        }
        let lens = &mut *self.lens;
        lens.clear();
        lens.extend(points.windows(2).map(|p| (p[1] - p[0]).length()));
        let total: f64 = lens.iter().sum();
        // A leg between two reflections that vanished (the classifier's threshold).
        let coord = crate::problem::coord(source, receiver);
        let vanish = crate::problem::vanish_threshold(total, coord);
        if lens[1..k.max(1)].iter().any(|&l| l <= vanish) {
            return None;
        }
        let rel = &mut *self.rel;
        rel.clear();
        rel.extend(points.iter().map(|&p| p - source));
        for i in 0..k {
            let n = self.walls[stack[i + 1].wall].n;
            let (a, b) = leg_sides(n, vanish, &rel[i..i + 3], &lens[i..i + 2]);
            if !sides_suit(StepKind::Reflect, a, b) {
                return None;
            }
        }
        let mut own_a = SegmentRef::NONE;
        for leg in 0..=k {
            if last_first && leg == k {
                break;
            }
            let own_b = if leg < k {
                self.walls[stack[leg + 1].wall].own
            } else {
                SegmentRef::NONE
            };
            let (a, b) = (points[leg], points[leg + 1]);
            let line = [stack[leg].image, fars[leg]];
            let scene = self.search.scene;
            // Between two walls, the segments the leg can be found to cross (where an
            // obstructed path is not listed: any crossing ends it, whichever is found).
            let listed = match self.crossers {
                Some(c) if leg > 0 && leg < k && last_first && lens[leg] > c.shortest => {
                    c.of(stack[leg].wall, stack[leg + 1].wall)
                }
                _ => None,
            };
            let hit = || match listed {
                Some(list) => {
                    scene.first_crossing_on_line_among(a, b, line, END_MARGIN, list, [own_a, own_b])
                }
                None => scene.first_crossing_on_line(a, b, line, END_MARGIN, [own_a, own_b]),
            };
            if self.crossings
                && a != b
                && let Some(hit) = hit()
            {
                if !self.search.obstructed {
                    return None;
                }
                let reason = Reason::Crosses {
                    leg,
                    interface: hit.interface as usize,
                };
                return Some((total, Some(reason)));
            }
            own_a = own_b;
        }
        Some((total, None))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::SplitMix64;
    use crate::trace::Tracer;
    use std::collections::BTreeMap;

    /// One path that [`arrivals`] found.
    #[derive(Clone, Debug, PartialEq)]
    struct MirrorArrival {
        /// The receiver's index in the receivers given.
        receiver: usize,
        /// The interface index of each reflection, in order.
        walls: Vec<usize>,
        /// Source, reflection points, receiver.
        points: Vec<Point>,
        /// Travel time.
        time: f64,
        /// Converged or obstructed.
        status: Status,
        /// For an obstructed path, its first crossing.
        reason: Option<Reason>,
    }

    /// [`MirrorWalls::arrivals`] without a time bound or a limit, into `out` (not cleared),
    /// each path's walls as interface indices.
    #[expect(
        clippy::too_many_arguments,
        reason = "the search's inputs, its scratch and its output"
    )]
    fn arrivals(
        mirrors: &MirrorWalls,
        scene: &Scene,
        source: Point,
        receivers: &[Point],
        max_steps: usize,
        slowness: f64,
        obstructed: bool,
        scratch: &mut MirrorScratch,
        out: &mut Vec<MirrorArrival>,
    ) {
        let search = MirrorSearch {
            scene,
            source,
            receivers,
            max_steps,
            max_time: f64::INFINITY,
            slowness,
            obstructed,
            max_beams: u64::MAX,
            max_work: u64::MAX,
            max_depth: crate::scene::MAX_SEARCH_STEPS,
        };
        let stats = mirrors.arrivals(
            &search,
            scratch,
            &mut |p: MirrorPath<'_>| {
                out.push(MirrorArrival {
                    receiver: p.receiver,
                    walls: p
                        .walls
                        .iter()
                        .map(|&w| mirrors.place(w).interface)
                        .collect(),
                    points: p.points.to_vec(),
                    time: p.time,
                    status: p.status,
                    reason: p.reason,
                });
                true
            },
            &mut |_| true,
        );
        assert!(!stats.stopped);
    }

    /// A room: its corners (counter-clockwise, each wall from one corner to the next), its
    /// sources and receivers.
    pub(super) struct Room {
        pub(super) corners: Vec<Point>,
        pub(super) sources: Vec<Point>,
        pub(super) receivers: Vec<Point>,
    }

    /// Whether `x` lies inside the polygon `corners` (even-odd rule).
    fn inside(corners: &[Point], x: Point) -> bool {
        let n = corners.len();
        let mut odd = false;
        for i in 0..n {
            let (a, b) = (corners[i], corners[(i + 1) % n]);
            if (a.y > x.y) != (b.y > x.y) && x.x < a.x + (x.y - a.y) * (b.x - a.x) / (b.y - a.y) {
                odd = !odd;
            }
        }
        odd
    }

    /// Distance from `x` to segment `a–b`.
    fn distance_to_segment(x: Point, a: Point, b: Point) -> f64 {
        let e = b - a;
        let t = ((x - a).dot(e) / e.dot(e)).clamp(0.0, 1.0);
        x.distance(a + e * t)
    }

    /// `count` points inside the room, each at least 0.05 from every wall.
    fn points_inside(corners: &[Point], count: usize, rng: &mut SplitMix64) -> Vec<Point> {
        let b = crate::geom::Aabb::around(corners);
        let n = corners.len();
        let mut found = Vec::new();
        while found.len() < count {
            let x = Point::new(
                b.min.x + (b.max.x - b.min.x) * rng.next_f64(),
                b.min.y + (b.max.y - b.min.y) * rng.next_f64(),
            );
            let clear =
                (0..n).all(|i| distance_to_segment(x, corners[i], corners[(i + 1) % n]) >= 0.05);
            if inside(corners, x) && clear {
                found.push(x);
            }
        }
        found
    }

    /// A random room of kind `kind` (0: a convex polygon of 5 to 8 walls on an ellipse; 1, 2,
    /// 3: an L, a U or a T with jittered corners), turned and moved at random, with
    /// `sources` sources and `receivers` receivers inside.
    pub(super) fn random_room(
        kind: usize,
        sources: usize,
        receivers: usize,
        rng: &mut SplitMix64,
    ) -> Room {
        let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
        let shape: Vec<[f64; 2]> = match kind {
            0 => {
                let n = 5 + (r(0.0, 4.0) as usize).min(3);
                let (rx, ry) = (r(2.0, 6.0), r(2.0, 6.0));
                (0..n)
                    .map(|i| {
                        let theta = std::f64::consts::TAU * (i as f64 + r(0.0, 0.8)) / n as f64;
                        [rx * theta.cos(), ry * theta.sin()]
                    })
                    .collect()
            }
            _ => {
                let (w, h) = (r(4.0, 8.0), r(4.0, 8.0));
                let mut corners = match kind {
                    1 => {
                        let (a, b) = (r(0.3, 0.7) * w, r(0.3, 0.7) * h);
                        vec![[0.0, 0.0], [w, 0.0], [w, b], [a, b], [a, h], [0.0, h]]
                    }
                    2 => {
                        let (t, b) = (r(0.25, 0.4) * w, r(0.3, 0.6) * h);
                        vec![
                            [0.0, 0.0],
                            [w, 0.0],
                            [w, h],
                            [w - t, h],
                            [w - t, b],
                            [t, b],
                            [t, h],
                            [0.0, h],
                        ]
                    }
                    _ => {
                        let (a, b) = (r(0.25, 0.4) * w, r(0.4, 0.7) * h);
                        vec![
                            [a, 0.0],
                            [w - a, 0.0],
                            [w - a, b],
                            [w, b],
                            [w, h],
                            [0.0, h],
                            [0.0, b],
                            [a, b],
                        ]
                    }
                };
                for c in &mut corners {
                    c[0] += r(-0.15, 0.15);
                    c[1] += r(-0.15, 0.15);
                }
                corners
            }
        };
        let (turn, dx, dy) = (
            r(0.0, std::f64::consts::TAU),
            r(-20.0, 20.0),
            r(-20.0, 20.0),
        );
        let (c, s) = (turn.cos(), turn.sin());
        let corners: Vec<Point> = shape
            .iter()
            .map(|&[x, y]| Point::new(c * x - s * y + dx, s * x + c * y + dy))
            .collect();
        let sources = points_inside(&corners, sources, rng);
        let receivers = points_inside(&corners, receivers, rng);
        Room {
            corners,
            sources,
            receivers,
        }
    }

    /// Every sequence of `1..=order` of `walls` walls without a wall twice in a row, the
    /// empty one first.
    fn sequences(walls: usize, order: usize) -> Vec<Vec<usize>> {
        let mut all = vec![Vec::new()];
        let mut level = vec![Vec::new()];
        for _ in 0..order {
            let mut next = Vec::new();
            for seq in &level {
                for w in 0..walls {
                    if seq.last() != Some(&w) {
                        let mut longer: Vec<usize> = seq.clone();
                        longer.push(w);
                        next.push(longer);
                    }
                }
            }
            all.extend(next.iter().cloned());
            level = next;
        }
        all
    }

    /// The room as a scene: wall `i` the interface `w{i}` from corner `i` to the next, medium
    /// `air` (speed 343) inside, and `paths` (wall sequences) with their media given.
    pub(super) fn room_scene(room: &Room, paths: &[Vec<usize>]) -> Scene {
        let n = room.corners.len();
        let xy = |p: &Point| [p.x, p.y];
        let interfaces: serde_json::Map<String, serde_json::Value> = (0..n)
            .map(|i| {
                let (a, b) = (room.corners[i], room.corners[(i + 1) % n]);
                (
                    format!("w{i}"),
                    serde_json::json!({ "points": [xy(&a), xy(&b)] }),
                )
            })
            .collect();
        let paths: Vec<serde_json::Value> = paths
            .iter()
            .map(|seq| {
                let steps: Vec<_> = seq
                    .iter()
                    .map(|w| serde_json::json!({ "reflect": format!("w{w}") }))
                    .collect();
                serde_json::json!({ "steps": steps, "media": vec!["air"; seq.len() + 1] })
            })
            .collect();
        let doc = serde_json::json!({
            "media": { "air": { "speed": 343.0, "at": xy(&room.sources[0]) } },
            "interfaces": interfaces,
            "sources": room.sources.iter().map(xy).collect::<Vec<_>>(),
            "receivers": room.receivers.iter().map(xy).collect::<Vec<_>>(),
            "paths": paths,
        });
        Scene::from_json(&doc.to_string()).unwrap()
    }

    /// One path found, as compared: its time, points, status and reason.
    #[derive(Clone, Debug)]
    struct Found {
        time: f64,
        points: Vec<Point>,
        status: Status,
        reason: Option<Reason>,
    }

    /// Per (source, receiver, interface sequence): the path the mirror search finds.
    type Listing = BTreeMap<(usize, usize, Vec<usize>), Found>;

    /// The mirror search's paths of every source of `scene` (every interface a wall).
    fn mirror_listing(scene: &Scene, order: usize, obstructed: bool) -> Listing {
        let walls: Vec<usize> = (0..scene.interfaces().len()).collect();
        let mirrors = MirrorWalls::new(scene, &walls);
        let slowness = scene.media()[0].slowness;
        let (mut scratch, mut out) = (MirrorScratch::default(), Vec::new());
        let mut listing = Listing::new();
        for (s, &source) in scene.sources().iter().enumerate() {
            out.clear();
            arrivals(
                &mirrors,
                scene,
                source,
                scene.receivers(),
                order,
                slowness,
                obstructed,
                &mut scratch,
                &mut out,
            );
            for a in &out {
                let found = Found {
                    time: a.time,
                    points: a.points.clone(),
                    status: a.status,
                    reason: a.reason,
                };
                let previous = listing.insert((s, a.receiver, a.walls.clone()), found);
                assert!(previous.is_none(), "{:?} listed twice", a.walls);
            }
        }
        listing
    }

    /// The reference's paths of every path of `scene` (each an interface sequence) between
    /// each source and receiver, those `converged` and `obstructed` ones if asked, and how
    /// many of them only the general solve found: the complete search
    /// ([`Tracer::stationary_paths`]), and where it lists nothing, the general solve from the
    /// paraxial start without kernels (no image method); also where the complete search
    /// reports itself incomplete, for the path it may have missed. The time being convex on
    /// the walls' lines, the general solve finds the one stationary path there, from the
    /// paraxial start, or where that start leaves a wall's end on the way, from the documented
    /// start (the image method's points, which the Newton solve confirms and the classifier
    /// judges).
    fn reference_listing(scene: &Scene, obstructed: bool) -> (Listing, usize) {
        let tracer = Tracer::new(scene).unwrap();
        let general = Tracer::new(scene)
            .unwrap()
            .with_initial_guess(crate::InitialGuess::Paraxial)
            .with_kernels(crate::trace::Kernels::GeneralOnly);
        let keep = |status: Status| {
            status == Status::Converged || (obstructed && status == Status::Obstructed)
        };
        let (mut out, mut ws) = (Vec::new(), crate::Workspace::new());
        let (mut listing, mut general_only) = (Listing::new(), 0);
        for (s, &source) in scene.sources().iter().enumerate() {
            for (r, &receiver) in scene.receivers().iter().enumerate() {
                for (p, path) in scene.paths().iter().enumerate() {
                    let search = tracer
                        .stationary_paths(
                            source,
                            receiver,
                            p,
                            &crate::options::Run::new(),
                            &mut out,
                        )
                        .unwrap();
                    let walls: Vec<usize> = path.steps.iter().map(|s| s.interface).collect();
                    let mut found: Vec<Found> = out
                        .iter()
                        .filter(|a| keep(a.status))
                        .map(|a| Found {
                            time: a.time,
                            points: a.points.clone(),
                            status: a.status,
                            reason: a.reason,
                        })
                        .collect();
                    if out.is_empty() || !search.complete {
                        let mut ray = general.solve(source, receiver, p, &mut ws);
                        if !ray.status.has_time() {
                            ray = tracer.solve(source, receiver, p, &mut ws);
                        }
                        if out.is_empty() && keep(ray.status) {
                            general_only += 1;
                            found.push(Found {
                                time: ray.time,
                                points: ws.points().to_vec(),
                                status: ray.status,
                                reason: ray.reason,
                            });
                        }
                    }
                    assert!(found.len() <= 1, "{walls:?}: two stationary paths");
                    if let Some(f) = found.pop() {
                        listing.insert((s, r, walls), f);
                    }
                }
            }
        }
        (listing, general_only)
    }

    /// The two listings hold the same (source, receiver, sequence) with the same status and
    /// obstructed leg (crossing the interface named: of two crossed, either may be named), times within 1e-12 relative and points within 1e-9 of the scene's scale.
    fn assert_same(scene: &Scene, found: &Listing, reference: &Listing, scale: f64, what: &str) {
        let missing: Vec<_> = reference
            .keys()
            .filter(|k| !found.contains_key(k))
            .collect();
        let extra: Vec<_> = found
            .keys()
            .filter(|k| !reference.contains_key(k))
            .collect();
        assert!(
            missing.is_empty() && extra.is_empty(),
            "{what}: missing {missing:?}, extra {extra:?}"
        );
        for (key, a) in found {
            let b = &reference[key];
            // A leg that crosses two interfaces may name either: the classifier takes the
            // first among the path's candidates, the scene's query the first it meets.
            let leg = |r: Option<Reason>| match r {
                Some(Reason::Crosses { leg, interface }) => Some((leg, interface)),
                _ => None,
            };
            assert_eq!(a.status, b.status, "{what}: {key:?}");
            assert_eq!(
                leg(a.reason).map(|l| l.0),
                leg(b.reason).map(|l| l.0),
                "{what}: {key:?}: {:?} vs {:?}",
                a.reason,
                b.reason
            );
            if let Some((l, interface)) = leg(a.reason) {
                let crate::geom::Segment { start: p, end: q } =
                    scene.interfaces()[interface].polyline.segment(0);
                let t = crate::polyline::segment_intersection(a.points[l], a.points[l + 1], p, q);
                assert!(
                    t.is_some_and(|(t, _)| t > END_MARGIN && t < 1.0 - END_MARGIN),
                    "{what}: {key:?}: leg {l} does not cross interface {interface}"
                );
            }
            assert!(
                (a.time - b.time).abs() <= 1e-12 * b.time,
                "{what}: {key:?}: {} vs {}",
                a.time,
                b.time
            );
            assert_eq!(a.points.len(), b.points.len());
            for (p, q) in a.points.iter().zip(&b.points) {
                assert!(
                    p.distance(*q) <= 1e-9 * scale,
                    "{what}: {key:?}: {p:?} vs {q:?}"
                );
            }
        }
    }

    /// The mirror search against the complete search of every wall sequence up to order 4
    /// (no wall twice in a row), in random convex, L-, U- and T-shaped rooms: the same paths,
    /// without and with the obstructed ones.
    #[test]
    fn rooms_agree_with_the_complete_search() {
        use rayon::prelude::*;
        let mut rng = SplitMix64(2024);
        let order = 4;
        let rooms: Vec<(usize, Room)> = (0..ROOMS)
            .map(|i| (i % 4, random_room(i % 4, 2, 2, &mut rng)))
            .collect();
        // Per room: paths, obstructed paths, paths only the general solve found.
        let counts: Vec<[usize; 3]> = rooms
            .par_iter()
            .enumerate()
            .map(|(room_index, (kind, room))| {
                let scene = room_scene(room, &sequences(room.corners.len(), order));
                let scale = room
                    .corners
                    .iter()
                    .fold(1.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
                let (reference, general_only) = reference_listing(&scene, true);
                let mut counts = [0, 0, general_only];
                for asked in [false, true] {
                    let mut reference = reference.clone();
                    reference.retain(|_, f| asked || f.status == Status::Converged);
                    let found = mirror_listing(&scene, order, asked);
                    let what = format!("room {room_index} (kind {kind}), obstructed {asked}");
                    assert_same(&scene, &found, &reference, scale, &what);
                    if asked {
                        counts[0] = found.len();
                        counts[1] = found
                            .values()
                            .filter(|f| f.status == Status::Obstructed)
                            .count();
                    }
                }
                counts
            })
            .collect();
        let [paths, obstructed, missed] = counts
            .iter()
            .fold([0; 3], |t, c| [t[0] + c[0], t[1] + c[1], t[2] + c[2]]);
        eprintln!(
            "{paths} paths, {obstructed} obstructed, {missed} found by the general solve only"
        );
        // The complete search misses nothing that the general solve finds.
        assert_eq!(missed, 0, "paths only the general solve found");
        // Enough of both kinds for the comparison to say something.
        assert!(
            paths > 100 * ROOMS && obstructed > 20 * ROOMS,
            "{paths} paths, {obstructed} obstructed"
        );
    }

    /// Per source, per receiver: pyroomacoustics' visible images, each its distance and the
    /// wall sequences that give it.
    type Visible = Vec<Vec<Vec<(f64, Vec<Vec<usize>>)>>>;

    /// The rooms of `benches/pyroomacoustics_rooms.py` (`fixtures/pyroomacoustics/rooms.json`):
    /// name, room, and per (source, receiver) pyroomacoustics' visible images (distance and
    /// the wall sequences that give each image).
    fn pyroomacoustics_rooms() -> Vec<(String, Room, Visible)> {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/fixtures/pyroomacoustics/rooms.json"
        );
        let doc: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let points = |v: &serde_json::Value| -> Vec<Point> {
            v.as_array()
                .unwrap()
                .iter()
                .map(|p| Point::new(p[0].as_f64().unwrap(), p[1].as_f64().unwrap()))
                .collect()
        };
        doc["rooms"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| {
                let room = Room {
                    corners: points(&r["corners"]),
                    sources: points(&r["sources"]),
                    receivers: points(&r["receivers"]),
                };
                let mut images = vec![vec![Vec::new(); room.receivers.len()]; room.sources.len()];
                for p in r["paths"].as_array().unwrap() {
                    let (s, rec) = (
                        p["source"].as_u64().unwrap(),
                        p["receiver"].as_u64().unwrap(),
                    );
                    images[s as usize][rec as usize] = p["images"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|i| {
                            let seqs = i["sequences"]
                                .as_array()
                                .unwrap()
                                .iter()
                                .map(|q| {
                                    q.as_array()
                                        .unwrap()
                                        .iter()
                                        .map(|w| w.as_u64().unwrap() as usize)
                                        .collect()
                                })
                                .collect();
                            (i["distance"].as_f64().unwrap(), seqs)
                        })
                        .collect();
                }
                (r["name"].as_str().unwrap().to_string(), room, images)
            })
            .collect()
    }

    /// The mirror search on pyroomacoustics' two rooms against its image source model: the
    /// paths both find (same wall sequence, distances within its float32 round-off), and
    /// those only one finds, each checked against the general solve of its sequence.
    #[test]
    fn pyroomacoustics_rooms_agree() {
        for (name, room, images) in pyroomacoustics_rooms() {
            let scene = room_scene(&room, &sequences(room.corners.len(), 4));
            let found = mirror_listing(&scene, 4, false);
            let tracer = Tracer::new(&scene).unwrap();
            let path_of: BTreeMap<Vec<usize>, usize> = scene
                .paths()
                .iter()
                .enumerate()
                .map(|(i, p)| (p.steps.iter().map(|s| s.interface).collect(), i))
                .collect();
            let mut ws = crate::Workspace::new();
            let (mut both, mut disagreements) = (0, Vec::new());
            for (s, per_receiver) in images.iter().enumerate() {
                for (r, visible) in per_receiver.iter().enumerate() {
                    let mut matched = vec![false; visible.len()];
                    for ((fs, fr, walls), f) in found.range((s, r, Vec::new())..) {
                        if (*fs, *fr) != (s, r) {
                            break;
                        }
                        let distance = f.time * 343.0;
                        let hit = visible.iter().position(|(d, seqs)| {
                            seqs.contains(walls) && (d - distance).abs() <= 1e-5 * d
                        });
                        match hit {
                            Some(i) if !matched[i] => {
                                both += 1;
                                matched[i] = true;
                            }
                            _ => {
                                let (src, rec) = (room.sources[s], room.receivers[r]);
                                let ray = tracer.solve(src, rec, path_of[walls], &mut ws);
                                disagreements.push(format!(
                                    "({s}, {r}) {walls:?} eigenray only: {distance}, \
                                     general solve {:?}",
                                    ray.status
                                ));
                            }
                        }
                    }
                    for (i, (d, seqs)) in visible.iter().enumerate() {
                        if matched[i] {
                            continue;
                        }
                        for seq in seqs {
                            let (src, rec) = (room.sources[s], room.receivers[r]);
                            let ray = tracer.solve(src, rec, path_of[seq], &mut ws);
                            disagreements.push(format!(
                                "({s}, {r}) {seq:?} pyroomacoustics only: {d}, general solve \
                                 {:?} {:?}",
                                ray.status, ray.reason
                            ));
                        }
                    }
                }
            }
            eprintln!("{name}: {both} paths found by both");
            assert!(both > 500, "{name}: {both} paths");
            assert!(disagreements.is_empty(), "{name}: {disagreements:#?}");
        }
    }

    /// In a rectangle every image of order `|i| + |j|` is `(i a + x or a − x, j b + y or
    /// b − y)` (by the parity of `i` and `j`) and every one is seen: 41 paths up to order 4,
    /// their times the images' distances.
    #[test]
    fn rectangle_times_are_the_closed_form() {
        let (a, b) = (4.0, 3.0);
        let room = Room {
            corners: vec![
                Point::new(0.0, 0.0),
                Point::new(a, 0.0),
                Point::new(a, b),
                Point::new(0.0, b),
            ],
            sources: vec![Point::new(1.3, 0.7), Point::new(2.9, 2.2)],
            receivers: vec![Point::new(3.1, 2.45), Point::new(0.55, 1.6)],
        };
        let scene = room_scene(&room, &[Vec::new()]);
        let found = mirror_listing(&scene, 4, false);
        let slowness = scene.media()[0].slowness;
        for (s, source) in room.sources.iter().enumerate() {
            for (r, receiver) in room.receivers.iter().enumerate() {
                let image = |i: i32, len: f64, x: f64| {
                    i as f64 * len + if i % 2 == 0 { x } else { len - x }
                };
                let mut expected: Vec<f64> = Vec::new();
                for i in -4i32..=4 {
                    for j in -4i32..=4 {
                        if i.abs() + j.abs() <= 4 {
                            let p = Point::new(image(i, a, source.x), image(j, b, source.y));
                            expected.push(slowness * p.distance(*receiver));
                        }
                    }
                }
                expected.sort_by(f64::total_cmp);
                let mut times: Vec<f64> = found
                    .iter()
                    .filter(|((fs, fr, _), f)| {
                        (*fs, *fr) == (s, r) && f.status == Status::Converged
                    })
                    .map(|(_, f)| f.time)
                    .collect();
                times.sort_by(f64::total_cmp);
                assert_eq!(times.len(), 41);
                for (t, e) in times.iter().zip(&expected) {
                    assert!((t - e).abs() <= 1e-12 * e, "{t} vs {e}");
                }
            }
        }
    }

    /// A receiver exactly on a beam's boundary: the path of two reflections between parallel
    /// mirrors whose second point is a wall's end (exact in floating point) reflects there (a
    /// path, as one exactly at an open end is); a receiver just inside the beam has one (its
    /// time the image's distance), one just outside none. The complete search says the same.
    #[test]
    fn a_path_through_an_open_wall_end_reflects_there() {
        let doc = r#"{
            "media": { "air": { "speed": 1.0 } },
            "interfaces": { "high": { "points": [[0, 2], [4, 2]] },
                            "low": { "points": [[0, 0], [4, 0]] } },
            "sources": [[1, 1]], "receivers": [[5, 1], [4.999, 1], [5.001, 1]],
            "paths": [{ "steps": [{ "reflect": "low" }, { "reflect": "high" }],
                        "media": ["air", "air", "air"] }]
        }"#;
        let scene = Scene::from_json(doc).unwrap();
        let (high, low) = (0, 1);
        let mirrors = MirrorWalls::new(&scene, &[high, low]);
        let (mut scratch, mut out) = (MirrorScratch::default(), Vec::new());
        let source = scene.sources()[0];
        let receivers = scene.receivers();
        arrivals(
            &mirrors,
            &scene,
            source,
            receivers,
            2,
            1.0,
            true,
            &mut scratch,
            &mut out,
        );
        let two: Vec<&MirrorArrival> = out.iter().filter(|a| a.walls == [low, high]).collect();
        assert_eq!(two.len(), 2, "{two:?}");
        for (a, r) in two.iter().zip([0, 1]) {
            assert_eq!(a.receiver, r);
            // The source's image in `low`, then in `high`: (1, 5).
            let expected = Point::new(1.0, 5.0).distance(receivers[r]);
            assert!((a.time - expected).abs() <= 1e-15 * expected);
        }
        assert_eq!(two[0].points[2], Point::new(4.0, 2.0));
        let tracer = Tracer::new(&scene).unwrap();
        let mut arrivals = Vec::new();
        for (r, &receiver) in receivers.iter().enumerate() {
            tracer
                .stationary_paths(
                    source,
                    receiver,
                    0,
                    &crate::options::Run::new(),
                    &mut arrivals,
                )
                .unwrap();
            assert_eq!(
                arrivals.len(),
                usize::from(r < 2),
                "receiver {r}: {arrivals:?}"
            );
        }
    }

    /// Once its scratch has grown, a search allocates only its results: one vector of points
    /// per path and one of walls per reflected path.
    #[test]
    fn a_warm_search_allocates_only_its_results() {
        let mut rng = SplitMix64(77);
        let room = random_room(1, 1, 6, &mut rng);
        let scene = room_scene(&room, &[Vec::new()]);
        let walls: Vec<usize> = (0..scene.interfaces().len()).collect();
        let mirrors = MirrorWalls::new(&scene, &walls);
        let (mut scratch, mut out) = (MirrorScratch::default(), Vec::new());
        let source = room.sources[0];
        arrivals(
            &mirrors,
            &scene,
            source,
            &room.receivers,
            4,
            1.0,
            true,
            &mut scratch,
            &mut out,
        );
        let expected = out.len() + out.iter().filter(|a| !a.walls.is_empty()).count();
        assert!(out.len() > 50, "{} paths", out.len());
        out.clear();
        let info = allocation_counter::measure(|| {
            arrivals(
                &mirrors,
                &scene,
                source,
                &room.receivers,
                4,
                1.0,
                true,
                &mut scratch,
                &mut out,
            );
        });
        assert_eq!(info.count_total as usize, expected);
    }

    /// A measurement, not a test: the mirror search's time per room on pyroomacoustics' two
    /// rooms (every source against every receiver, order 4, unobstructed paths), the median
    /// of many repetitions. Run in release:
    /// `cargo test --release --lib mirrors -- --ignored --nocapture`.
    #[test]
    #[ignore = "a measurement; run in release with --ignored --nocapture"]
    fn measure_pyroomacoustics_rooms() {
        for (name, room, _) in pyroomacoustics_rooms() {
            let scene = room_scene(&room, &[Vec::new()]);
            let walls: Vec<usize> = (0..scene.interfaces().len()).collect();
            let slowness = scene.media()[0].slowness;
            let (mut scratch, mut out) = (MirrorScratch::default(), Vec::new());
            let mut run = |out: &mut Vec<MirrorArrival>| {
                let mirrors = MirrorWalls::new(&scene, &walls);
                out.clear();
                for &source in &room.sources {
                    arrivals(
                        &mirrors,
                        &scene,
                        source,
                        &room.receivers,
                        4,
                        slowness,
                        false,
                        &mut scratch,
                        out,
                    );
                }
            };
            for _ in 0..200 {
                run(&mut out);
            }
            let mut times: Vec<f64> = (0..2000)
                .map(|_| {
                    let t = std::time::Instant::now();
                    run(&mut out);
                    t.elapsed().as_secs_f64() * 1e3
                })
                .collect();
            times.sort_by(f64::total_cmp);
            eprintln!(
                "{name}: {} sources x {} receivers, {} paths: median {:.4} ms, fastest {:.4} ms \
                 (of 2000)",
                room.sources.len(),
                room.receivers.len(),
                out.len(),
                times[times.len() / 2],
                times[0]
            );
        }
    }

    /// Random rooms the comparison runs on.
    const ROOMS: usize = 80;
}

#[cfg(test)]
mod time_bound_tests;
