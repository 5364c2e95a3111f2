//! Every stationary path of a step sequence: a branch-and-bound over tuples of nodes of each
//! polyline's segment hierarchy, pruned by certain bounds on the residuals, and an exact solve
//! of every surviving assignment of segments (and of vertices).
//!
//! On one assignment of segments, with each point on the whole line of its segment, the time
//! `T(s) = Σ wⱼ |xⱼ₊₁ − xⱼ|` is a sum of norms of affine maps, so convex: it has one minimum
//! (one set of minima when degenerate). A path is an interior stationary path of the sequence
//! (`converged` or `obstructed`) exactly when its assignment's minimiser lies strictly inside
//! every segment, and a `vertex` path when some points held on vertices make the others'
//! minimiser lie inside their segments while the one-sided derivatives at each held vertex
//! bracket zero. Each candidate goes through the one classifier.
//!
//! The search visits tuples of hierarchy nodes (a node: a range of consecutive segments, the
//! box of their vertices and the cone of their tangents, the tangent of the segment before
//! the range included so that its first vertex is covered). For point `i` between boxes, the
//! residual `rᵢ = (wᵢ uᵢ − wᵢ₊₁ uᵢ₊₁) · tᵢ` is bounded over every direction `uᵢ` from a point
//! of the previous box to one of this box, every `uᵢ₊₁` from this box to the next, and every
//! tangent `tᵢ` of the cone: `rᵢ` lies within `(wᵢ uᵢ − wᵢ₊₁ uᵢ₊₁) · t₀ ± (wᵢ + wᵢ₊₁) |tᵢ − t₀|`
//! (`t₀` the cone's middle tangent), and `u · t₀` over the directions of a box of differences
//! that misses the origin lies between its values at the box's corners (or reaches ±1 where
//! the directions pass through `±t₀`). Where two consecutive points lie on adjacent or
//! overlapping ranges of one interface (boxes that touch), the leg between them runs along
//! a sum of the tangents between them: its direction lies in the arc of their tangent angles
//! (or, when either point may come first, in that arc or the opposite one). Every bound is
//! widened by its round-off. A tuple whose bound for some point excludes zero holds no
//! stationary path and is dropped; where a bound cannot be computed (boxes that touch
//! otherwise, so a leg may vanish, or a tangent arc of π or more) that point does not prune.
//! Leaves (one segment each) are solved: every choice of interior or held first vertex per
//! point, each choice bounded again first with its own segment's tangent or its vertex's cone.
//!
//! An assignment's solve is damped Newton on the analytic Hessian of `problem` with
//! backtracking on `T` itself (convex there), each point kept on its segment (a point that `T`
//! pushes out at an end stays there: the minimum then lies outside and no path is inside).
//! It cannot be the solver's own loop, which moves points across vertices. Where two points
//! collapse onto the crossing of their lines (`T` has a kink there), they are held there while
//! the others settle, and the subgradient decides whether the collapse is the minimum (no
//! path) or the points restart apart; where three points share one spot, the minimum of `T`
//! with its kinks smoothed away decides. A solve that stalls next to a collapse that cannot be
//! tested (points held on vertices, parallel lines; within [`COLLAPSE`] of the path's length),
//! or with a leg whose sine with its segment's line is below [`ALONG`], is taken to approach a
//! minimum that holds no stationary path: a rule with these thresholds, not a proof. Any other
//! solve that does not settle marks the search incomplete.

use std::f64::consts::PI;
use std::fmt;

use crate::amplitude::Amplitude;
use crate::geom::{Aabb, Point, Vec2};
use crate::polyline::Polyline;
use crate::problem::{Eval, Pin, ProblemRef};
use crate::scene::Scene;
use crate::solver::{NewtonWorkspace, Outcome, Solution, thomas};

use super::classify::Sequence;
use super::{Classifier, Reason, Status};

/// How the time behaves at the held vertices of a `vertex` path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kink {
    /// Moving any held point off its vertex along either segment makes the time rise.
    Minimum,
    /// Moving any held point off its vertex along either segment makes the time fall.
    Maximum,
    /// Held points of both kinds (two or more held points).
    Mixed,
}

impl Kink {
    /// Its name in every output format: `minimum`, `maximum` (and `mixed`).
    pub fn as_str(self) -> &'static str {
        match self {
            Kink::Minimum => "minimum",
            Kink::Maximum => "maximum",
            Kink::Mixed => "mixed",
        }
    }
}

/// One stationary path of a sequence (see [`Tracer::stationary_paths`](super::Tracer::stationary_paths)).
#[derive(Clone, Debug, PartialEq)]
pub struct Arrival {
    /// `converged`, `vertex` or `obstructed`.
    pub status: Status,
    /// Travel time (always a number: every arrival has a time).
    pub time: f64,
    /// Source, interaction points, receiver.
    pub points: Vec<Point>,
    /// Interaction parameters (arclengths along their polylines).
    pub parameters: Vec<f64>,
    /// The segment of each interaction (a held point: the segment its vertex starts).
    pub segments: Vec<usize>,
    /// Leg media, as indices into [`Scene::media`].
    pub media: Vec<usize>,
    /// Newton steps of its assignment's solve.
    pub iterations: usize,
    /// Why it is not `converged`, when it is not.
    pub reason: Option<Reason>,
    /// For a `vertex` path: how the time behaves at its held vertices.
    pub kink: Option<Kink>,
    /// Final relative residual of the free points.
    pub residual: f64,
    /// Whether the search of its triple was complete (see [`Stationary::complete`]).
    pub complete: bool,
    /// Its amplitude, when the scene asks for amplitudes (`"amplitudes"`).
    pub amplitude: Option<Amplitude>,
}

impl Arrival {
    /// An arrival with empty vectors, to be filled.
    fn empty() -> Arrival {
        Arrival {
            status: Status::NoPath,
            time: f64::NAN,
            points: Vec::new(),
            parameters: Vec::new(),
            segments: Vec::new(),
            media: Vec::new(),
            iterations: 0,
            reason: None,
            kink: None,
            residual: f64::NAN,
            complete: true,
            amplitude: None,
        }
    }
}

/// What a search of one triple did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stationary {
    /// Whether every stationary path of the triple is listed: `false` when the search reached
    /// its limit of tuples, or an assignment's solve did not settle (the list may then be
    /// short). With `true`, an empty list says that the sequence has no stationary path: the
    /// pruning is certain, and an assignment is ruled out by its solve, with the thresholds
    /// of the module's documentation for solves that stall at a vanishing or grazing leg.
    pub complete: bool,
    /// Tuples of hierarchy nodes visited.
    pub tuples: usize,
    /// Assignments solved.
    pub solves: usize,
}

/// Why a search cannot run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StationaryError {
    /// There is no path of that index.
    ///
    /// How to fix: pass an index below `Scene::paths().len()`.
    NoSuchPath {
        /// The index asked for.
        path: usize,
    },
    /// The path has more steps than the search takes: each assignment of segments is tried
    /// with every choice of held vertices, `2^steps` of them.
    ///
    /// How to fix: search sequences of at most [`MAX_STATIONARY_STEPS`] steps.
    TooManySteps {
        /// The path's index.
        path: usize,
        /// Its steps.
        steps: usize,
    },
}

pub use crate::scene::MAX_STATIONARY_STEPS;

impl fmt::Display for StationaryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StationaryError::NoSuchPath { path } => write!(f, "there is no path {path}"),
            StationaryError::TooManySteps { path, steps } => write!(
                f,
                "path {path} has {steps} steps: the search for every stationary path takes at \
                 most {MAX_STATIONARY_STEPS}"
            ),
        }
    }
}

impl std::error::Error for StationaryError {}

/// The error as a scene error, naming the key: `paths[i].steps` for a path beyond the
/// search's step limit (the command-line tool's message), `paths` otherwise.
impl From<StationaryError> for crate::scene::SceneError {
    fn from(e: StationaryError) -> Self {
        match e {
            StationaryError::TooManySteps { path, steps } => crate::scene::SceneError::new(
                format!("paths[{path}].steps"),
                format!(
                    "{steps} steps; \"stationary\": \"all\" searches paths of at most \
                     {MAX_STATIONARY_STEPS} steps (each assignment of segments is tried with \
                     every choice of held vertices, 2^steps of them)"
                ),
            ),
            other => crate::scene::SceneError::new("paths", other.to_string()),
        }
    }
}

/// Tuples (and assignments solved) a search of one sequence visits at most when asked for
/// every stationary path, before it gives up and says it is not complete.
pub(crate) const MAX_TUPLES: usize = 1 << 26;
/// Newton steps per assignment (again after each pin or restart).
const MAX_STEPS: usize = 200;
/// Restarts away from collapses per assignment (see `Search::unpin`).
const MAX_RESTARTS: usize = 6;

/// A range of consecutive segments of a polyline: its box and tangent cone.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// First segment.
    first: u32,
    /// The box of the range's vertices.
    bbox: Aabb,
    /// The range of tangent angles (unwrapped), the segment before the range included.
    cone: [f64; 2],
    /// Its box and cone as the bound takes them.
    place: Place,
    /// The two halves, when the range has more than one segment.
    kids: Option<[u32; 2]>,
}

/// A binary hierarchy over one polyline's segments (built once per interface).
#[derive(Clone, Debug)]
pub(crate) struct Hierarchy {
    nodes: Vec<Node>,
    /// Unwrapped tangent angle of each segment.
    theta: Vec<f64>,
    /// On a closed polyline, the angle of the last segment unwrapped against the first.
    before_first: Option<f64>,
}

impl Hierarchy {
    /// The hierarchy of `line`'s segments.
    pub(crate) fn new(line: &Polyline) -> Hierarchy {
        let m = line.num_segments();
        let turn = |a: Vec2, b: Vec2| a.cross(b).atan2(a.dot(b));
        let mut theta = Vec::with_capacity(m);
        let t0 = line.tangent(0);
        theta.push(t0.y.atan2(t0.x));
        for j in 1..m {
            theta.push(theta[j - 1] + turn(line.tangent(j - 1), line.tangent(j)));
        }
        let before_first = line
            .is_closed()
            .then(|| theta[0] - turn(line.tangent(m - 1), line.tangent(0)));
        let mut h = Hierarchy {
            nodes: Vec::with_capacity(2 * m),
            theta,
            before_first,
        };
        h.build(line, 0, m);
        h
    }

    /// The angle of the segment before `j` (none at an open polyline's start).
    fn before(&self, j: usize) -> Option<f64> {
        if j > 0 {
            Some(self.theta[j - 1])
        } else {
            self.before_first
        }
    }

    /// The cone of tangents at the vertex where segment `j` starts.
    fn vertex_cone(&self, j: usize) -> [f64; 2] {
        let t = self.theta[j];
        let b = self.before(j).unwrap_or(t);
        [t.min(b), t.max(b)]
    }

    /// Adds the node of segments `a..b` and its descendants; returns its index.
    fn build(&mut self, line: &Polyline, a: usize, b: usize) -> u32 {
        let at = self.nodes.len();
        let (p, q) = line.segment(a);
        let (bbox, cone) = (Aabb::from_points(p, q), self.vertex_cone(a));
        self.nodes.push(Node {
            first: a as u32,
            bbox,
            cone,
            place: Place::new(bbox, cone, a, a + 1),
            kids: None,
        });
        if b - a > 1 {
            let mid = a + (b - a) / 2;
            let l = self.build(line, a, mid);
            let r = self.build(line, mid, b);
            let (nl, nr) = (self.nodes[l as usize], self.nodes[r as usize]);
            let node = &mut self.nodes[at];
            node.bbox = nl.bbox.union(nr.bbox);
            node.cone = [nl.cone[0].min(nr.cone[0]), nl.cone[1].max(nr.cone[1])];
            node.place = Place::new(node.bbox, node.cone, a, b);
            node.kids = Some([l, r]);
        }
        at as u32
    }
}

/// Widening of every tangent cone (rad): the round-off of the unwrapped angles.
const CONE_PAD: f64 = 1e-9;

/// What a point of a tuple may be: a box, and tangents `t` with `|t − tangent| ≤ spread`.
#[derive(Clone, Copy, Debug)]
struct Place {
    bbox: Aabb,
    tangent: Vec2,
    spread: f64,
    /// The interface (set by the search; `usize::MAX` in a hierarchy's nodes).
    interface: usize,
    /// The segments `first..end` whose points (and first vertex) the place holds, and the
    /// range of their tangent angles.
    first: usize,
    end: usize,
    cone: [f64; 2],
}

impl Place {
    /// The place of points in `bbox` on segments `first..end` with tangent angles in `cone`.
    fn new(bbox: Aabb, cone: [f64; 2], first: usize, end: usize) -> Place {
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
fn pruned(places: &[Place], source: Point, receiver: Point, w: &[f64]) -> bool {
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

/// The search's scratch and settings for one triple.
struct Search<'a> {
    g: ProblemRef<'a>,
    sequence: Sequence<'a>,
    media: &'a [usize],
    /// See [`SequenceSearch::max_tuples`].
    max_tuples: usize,
    classifier: &'a Classifier,
    hierarchies: &'a [&'a Hierarchy],
    tolerance: f64,
    sc: Box<Scratch>,
    stats: Stationary,
    /// The legs (bits) whose two points [`minimise`](Search::minimise) holds together at a
    /// collapse while the others settle.
    pinned: usize,
    /// Whether the present solve has followed the smoothed time once
    /// ([`smooth_away`](Search::smooth_away)).
    smoothed: bool,
}

/// What a search reuses from one triple to the next (per thread): the solve's state and
/// scratch, the tuples' stack.
#[derive(Default)]
struct Scratch {
    nw: NewtonWorkspace,
    trial: Eval,
    s_try: Vec<f64>,
    delta: Vec<f64>,
    diag: Vec<f64>,
    off: Vec<f64>,
    rhs: Vec<f64>,
    cp: Vec<f64>,
    places: Vec<Place>,
    points: Vec<Point>,
    slowness: Vec<f64>,
    stack: Vec<u32>,
    tuple: Vec<u32>,
    segs: Vec<usize>,
    /// Arrivals no longer listed, whose vectors the next ones reuse.
    spare: Vec<Arrival>,
}

impl Scratch {
    /// Sized for paths of `k` interactions.
    fn resize(&mut self, k: usize) {
        if !self.nw.fits(k) {
            self.nw.resize_to(k);
        }
        self.trial.resize(k);
        for v in [
            &mut self.s_try,
            &mut self.delta,
            &mut self.diag,
            &mut self.off,
            &mut self.rhs,
            &mut self.cp,
        ] {
            v.resize(k, 0.0);
        }
        self.tuple.resize(k, 0);
        self.segs.resize(k, 0);
    }
}

thread_local! {
    /// Each thread's scratch, taken by a search and given back at its end.
    static SCRATCH: std::cell::Cell<Option<Box<Scratch>>> = const { std::cell::Cell::new(None) };
}

/// How an assignment's solve ended.
enum Settled {
    /// At the minimiser (to the tolerance or round-off).
    Yes,
    /// At a minimiser where a leg vanished (no stationary path: the classifier's
    /// `coincident`).
    Degenerate,
    /// At the minimum over the segments, with a point at an end of its segment that `T`
    /// pushes outwards: `T` being convex, no stationary point lies inside the segments.
    Outside,
    /// Not settled (the search is then not complete).
    No,
}

/// What a collapse or a stall of an assignment's solve leads to.
enum Kinked {
    /// The solve ends so.
    Settled(Settled),
    /// Points were pinned at a collapse, or moved away from one that is not the minimum:
    /// the solve goes on.
    Restarted,
}

/// What [`Search::kink_direction`] finds of a pinned leg.
struct KinkDirection {
    /// The direction that makes both points' residuals vanish.
    both: Vec2,
    /// The least `|g|` that makes the collapse a minimum over the segments.
    least: f64,
    /// Whether the collapse sits at an end of either segment.
    at_end: bool,
}

/// How one Newton step of an assignment's solve went.
enum NewtonStep {
    /// The points moved.
    Moved,
    /// The step is below round-off: at the minimum.
    Done,
    /// No step descends.
    Stalled,
    /// The Hessian cannot be solved, even damped.
    Singular,
}

/// Shortest leg between two interactions, relative to the path's length, below which a solve
/// that stalls is taken to approach a minimum where that leg vanishes (where `T` is not
/// differentiable: no stationary path, the classifier's `coincident`). Where `T` is smooth
/// the damped Newton steps on a convex `T` converge quadratically and do not stall; they
/// stall only next to such a kink, which they approach slowly.
const COLLAPSE: f64 = 1e-3;
/// Sine of the angle between a leg and its interaction's segment below which a stalled solve
/// is taken to run along the segment's line.
const ALONG: f64 = 1e-7;

/// What a search of one sequence with given leg media borrows.
#[derive(Clone, Copy)]
pub(crate) struct SequenceSearch<'a> {
    pub scene: &'a Scene,
    pub classifier: &'a Classifier,
    /// The segment hierarchy of each step's interface.
    pub hierarchies: &'a [&'a Hierarchy],
    pub tolerance: f64,
    pub sequence: Sequence<'a>,
    /// Leg media (steps + 1), as indices into [`Scene::media`].
    pub media: &'a [usize],
    pub source: Point,
    pub receiver: Point,
    /// Tuples, and assignments solved, after which the search gives up (incomplete).
    pub max_tuples: usize,
}

/// Every stationary path of one sequence with given leg media, appended to `out` unsorted
/// (see [`finish`]); adds what it did to `stats`.
pub(crate) fn search_sequence(
    input: SequenceSearch<'_>,
    out: &mut Vec<Arrival>,
    stats: &mut Stationary,
) {
    let k = input.sequence.steps.len();
    debug_assert!(k <= MAX_STATIONARY_STEPS && input.media.len() == k + 1);
    let mut sc = SCRATCH.with(|c| c.take()).unwrap_or_default();
    sc.resize(k);
    let mut slowness = std::mem::take(&mut sc.slowness);
    slowness.clear();
    slowness.extend(input.media.iter().map(|&m| input.scene.media()[m].slowness));
    let mut search = Search {
        g: ProblemRef {
            scene: input.scene,
            steps: input.sequence.steps,
            slowness: &slowness,
            source: input.source,
            receiver: input.receiver,
        },
        sequence: input.sequence,
        media: input.media,
        max_tuples: input.max_tuples,
        classifier: input.classifier,
        hierarchies: input.hierarchies,
        tolerance: input.tolerance,
        sc,
        stats: Stationary {
            complete: true,
            tuples: 0,
            solves: 0,
        },
        pinned: 0,
        smoothed: false,
    };
    search.run(out);
    stats.complete &= search.stats.complete;
    stats.tuples += search.stats.tuples;
    stats.solves += search.stats.solves;
    let mut sc = search.sc;
    sc.slowness = slowness;
    SCRATCH.with(|c| c.set(Some(sc)));
}

/// Runs `f` on this thread's scratch (made on first use).
fn with_scratch<R>(f: impl FnOnce(&mut Scratch) -> R) -> R {
    let mut sc = SCRATCH.with(|c| c.take()).unwrap_or_default();
    let r = f(&mut sc);
    SCRATCH.with(|c| c.set(Some(sc)));
    r
}

/// Empties `out`, keeping its arrivals' vectors for the next ones this thread finds: once
/// warm, a search allocates nothing.
pub(crate) fn recycle(out: &mut Vec<Arrival>) {
    with_scratch(|sc| sc.spare.append(out));
}

/// Keeps the arrivals for which `keep` holds, in order; the others' vectors are kept for
/// reuse.
pub(crate) fn retain(out: &mut Vec<Arrival>, mut keep: impl FnMut(&Arrival) -> bool) {
    let mut w = 0;
    for r in 0..out.len() {
        if keep(&out[r]) {
            out.swap(w, r);
            w += 1;
        }
    }
    with_scratch(|sc| sc.spare.extend(out.drain(w..)));
}

/// Orders the arrivals by time, drops repeats of one path (a vertex path kept over an
/// interior path on the same points), and marks whether the search was complete.
pub(crate) fn finish(out: &mut Vec<Arrival>, complete: bool) {
    let order =
        |a: &Arrival, b: &Arrival| a.time.total_cmp(&b.time).then(a.segments.cmp(&b.segments));
    out.sort_unstable_by(order);
    let same = |a: &Arrival, b: &Arrival| {
        let scale = a
            .points
            .iter()
            .fold(1.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
        (a.time - b.time).abs() <= 1e-9 * a.time.abs().max(1e-300)
            && a.points.len() == b.points.len()
            && a.points
                .iter()
                .zip(&b.points)
                .all(|(p, q)| (*p - *q).length() <= 1e-9 * scale)
    };
    // Kept ones move to the front (`out[..w]`); a repeat stays behind, or swaps places with
    // the one it repeats when it is the vertex path of the two.
    let mut w = 0;
    for r in 0..out.len() {
        match (0..w).rev().find(|&j| same(&out[j], &out[r])) {
            Some(j) => {
                if out[r].status == Status::Vertex && out[j].status != Status::Vertex {
                    out.swap(j, r);
                }
            }
            None => {
                out.swap(w, r);
                w += 1;
            }
        }
    }
    with_scratch(|sc| sc.spare.extend(out.drain(w..)));
    out.sort_unstable_by(order);
    for a in out.iter_mut() {
        a.complete = complete;
    }
}

impl Search<'_> {
    /// [`pruned`] for the places in `self.sc.places`.
    fn pruned(&self) -> bool {
        let g = &self.g;
        pruned(&self.sc.places, g.source, g.receiver, g.slowness)
    }

    /// The branch-and-bound from the tuple of roots.
    fn run(&mut self, out: &mut Vec<Arrival>) {
        let k = self.g.k();
        if k == 0 {
            self.solve_leaf_choice(&[], 0, out);
            return;
        }
        let mut stack = std::mem::take(&mut self.sc.stack);
        let mut tuple = std::mem::take(&mut self.sc.tuple);
        let mut segs = std::mem::take(&mut self.sc.segs);
        stack.clear();
        stack.resize(k, 0);
        self.branch_and_bound(&mut stack, &mut tuple, &mut segs, out);
        (self.sc.stack, self.sc.tuple, self.sc.segs) = (stack, tuple, segs);
    }

    /// The search's loop, on the tuples in `stack` (scratch `tuple` and `segs`, `k` long).
    fn branch_and_bound(
        &mut self,
        stack: &mut Vec<u32>,
        tuple: &mut [u32],
        segs: &mut [usize],
        out: &mut Vec<Arrival>,
    ) {
        let k = self.g.k();
        while !stack.is_empty() {
            let at = stack.len() - k;
            tuple.copy_from_slice(&stack[at..]);
            stack.truncate(at);
            self.stats.tuples += 1;
            if self.stats.tuples > self.max_tuples {
                self.stats.complete = false;
                return;
            }
            self.sc.places.clear();
            for (i, &n) in tuple.iter().enumerate() {
                let mut place = self.hierarchies[i].nodes[n as usize].place;
                place.interface = self.g.steps[i].interface;
                self.sc.places.push(place);
            }
            if self.pruned() {
                continue;
            }
            // Split the widest node that has halves.
            let split = (0..k)
                .filter_map(|i| {
                    let node = &self.hierarchies[i].nodes[tuple[i] as usize];
                    node.kids.map(|kids| (i, kids, node.bbox.diagonal()))
                })
                .max_by(|a, b| a.2.total_cmp(&b.2).then(b.0.cmp(&a.0)));
            match split {
                Some((i, [l, r], _)) => {
                    for child in [r, l] {
                        stack.extend_from_slice(tuple);
                        let at = stack.len() - k + i;
                        stack[at] = child;
                    }
                }
                None => {
                    for (i, &n) in tuple.iter().enumerate() {
                        segs[i] = self.hierarchies[i].nodes[n as usize].first as usize;
                    }
                    for held in 0..(1usize << k) {
                        self.solve_leaf_choice(segs, held, out);
                    }
                }
            }
        }
    }

    /// The assignment of segments `segs` with the points in the bit set `held` on the first
    /// vertices of their segments: its bound, then its solve and classification.
    fn solve_leaf_choice(&mut self, segs: &[usize], held: usize, out: &mut Vec<Arrival>) {
        let k = segs.len();
        let is_held = |i: usize| held >> i & 1 == 1;
        self.sc.places.clear();
        for (i, &j) in segs.iter().enumerate() {
            let h = self.hierarchies[i];
            let line = self.g.line(i);
            if is_held(i) {
                if h.before(j).is_none() {
                    // The start of an open polyline: an end, not a vertex.
                    return;
                }
                let v = line.vertices()[j];
                let cone = h.vertex_cone(j);
                let place = Place::new(Aabb::from_points(v, v), cone, j, j + 1);
                self.sc.places.push(place);
            } else {
                let (p, q) = line.segment(j);
                let t = h.theta[j];
                self.sc.places.push(Place {
                    tangent: line.tangent(j),
                    spread: 0.0,
                    ..Place::new(Aabb::from_points(p, q), [t, t], j, j + 1)
                });
            }
            self.sc.places[i].interface = self.g.steps[i].interface;
        }
        if self.pruned() {
            return;
        }
        self.stats.solves += 1;
        if self.stats.solves > self.max_tuples {
            self.stats.complete = false;
            return;
        }
        let nw = &mut self.sc.nw;
        for (i, &j) in segs.iter().enumerate() {
            let line = self.g.line(i);
            nw.seg[i] = j;
            if is_held(i) {
                nw.pin[i] = Pin::Vertex;
                nw.s[i] = line.start(j);
            } else {
                nw.pin[i] = Pin::Free;
                // Consecutive points on one segment start apart.
                let f = (i + 1) as f64 / (k + 1) as f64;
                nw.s[i] = line.start(j) + f * (line.start(j + 1) - line.start(j));
            }
        }
        let (settled, iterations) = self.minimise(held);
        match settled {
            Settled::Yes => {}
            Settled::Degenerate | Settled::Outside => return,
            Settled::No => {
                self.stats.complete = false;
                return;
            }
        }
        let nw = &self.sc.nw;
        let e = &nw.eval;
        // Free points strictly inside their segments.
        for (i, &j) in segs.iter().enumerate() {
            let line = self.g.line(i);
            let inside = nw.s[i] > line.start(j) && nw.s[i] < line.start(j + 1);
            if !is_held(i) && !inside {
                return;
            }
        }
        // Held points: the one-sided derivatives bracket zero.
        let w = self.g.slowness;
        let mut kink = None;
        for (i, &j) in segs.iter().enumerate() {
            if !is_held(i) {
                continue;
            }
            let line = self.g.line(i);
            let before = if j > 0 {
                j - 1
            } else {
                line.num_segments() - 1
            };
            let v = e.u[i] * w[i] - e.u[i + 1] * w[i + 1];
            let (r_before, r_after) = (v.dot(line.tangent(before)), v.dot(line.tangent(j)));
            let this = if r_before < 0.0 && r_after > 0.0 {
                Kink::Minimum
            } else if r_before > 0.0 && r_after < 0.0 {
                Kink::Maximum
            } else {
                return;
            };
            kink = Some(match kink {
                None => this,
                Some(k) if k == this => this,
                Some(_) => Kink::Mixed,
            });
        }
        let sol = Solution {
            outcome: if held == 0 {
                Outcome::Converged
            } else {
                Outcome::Vertex
            },
            time: e.time,
            iterations,
            residual: e.rmax,
        };
        let record = self.classifier.classify(
            self.g.scene,
            self.sequence,
            self.g.source,
            self.g.receiver,
            &sol,
            nw,
            &mut self.sc.points,
        );
        if !record.status.has_time() {
            return;
        }
        let mut a = self.sc.spare.pop().unwrap_or_else(Arrival::empty);
        a.status = record.status;
        a.time = record.time;
        a.points.clear();
        a.points.extend_from_slice(&self.sc.points);
        a.parameters.clear();
        a.parameters.extend_from_slice(&nw.s[..k]);
        a.segments.clear();
        a.segments.extend_from_slice(segs);
        a.media.clear();
        a.media.extend_from_slice(self.media);
        a.iterations = iterations;
        a.reason = record.reason;
        a.kink = (record.status == Status::Vertex).then_some(kink).flatten();
        a.residual = record.residual;
        a.complete = true;
        a.amplitude = None;
        out.push(a);
    }

    /// Minimises the time over the free points on the lines of their segments (the held ones
    /// stay on their vertices) from the state in `self.sc.nw`: damped Newton steps on the
    /// analytic Hessian of `problem` with backtracking on `T` itself, which is convex there.
    ///
    /// Where a leg between two free points collapses, `T` has a kink: the two points are held
    /// together at their lines' crossing (the leg *pinned*) while the others settle, and then
    /// the subgradient decides ([`kink_direction`](Self::kink_direction)): when every pinned
    /// leg's `|g| ≤ 1`, `0 ∈ ∂T` and the minimum is the collapse (no stationary path); a
    /// pinned leg with `|g| > 1` is not at the minimum, and its points restart apart along `g`.
    /// Returns how it ended and the steps taken; leaves the evaluation at the end in
    /// `self.sc.nw.eval`.
    fn minimise(&mut self, held: usize) -> (Settled, usize) {
        let k = self.g.k();
        let tol = self.tolerance;
        let (mut steps, mut budget, mut restarts) = (0, MAX_STEPS, 0);
        self.pinned = 0;
        self.smoothed = false;
        loop {
            let nw = &mut self.sc.nw;
            self.g
                .evaluate(&nw.s, &nw.seg, &nw.pin, &mut nw.eval, true, false);
            let e = &nw.eval;
            let pinned = self.pinned;
            let collapsed = (1..k).find(|&j| pinned >> j & 1 == 0 && e.len[j] <= e.vanish);
            // Free points at an end of their segment that T pushes outwards stay there.
            let outward = self.outward(held | self.pinned_points());
            let now = held | self.pinned_points() | outward;
            let verdict = if let Some(j) = collapsed {
                // Two points on one spot: held there while the others settle.
                Some(self.pin(held, j))
            } else if self.sc.nw.eval.vanished > 0 {
                // The source or the receiver on an interaction's spot.
                return (Settled::Degenerate, steps);
            } else if !self.sc.nw.eval.rmax.is_finite() {
                return (Settled::No, steps);
            } else if self.residual(now) <= tol || k == 0 || now == (1 << k) - 1 {
                self.settled(held, outward, &mut restarts)
            } else if steps >= budget {
                Some(self.stalled(held))
            } else {
                match self.newton_step(now) {
                    NewtonStep::Moved => {
                        steps += 1;
                        None
                    }
                    NewtonStep::Done => self.settled(held, outward, &mut restarts),
                    // A singular Hessian: legs along their lines, or next to a kink.
                    NewtonStep::Singular => Some(self.stalled(held)),
                    // Within round-off of the minimum, or next to a kink of `T`.
                    NewtonStep::Stalled if self.residual(now) <= 1e-8 => {
                        self.settled(held, outward, &mut restarts)
                    }
                    NewtonStep::Stalled => Some(self.stalled(held)),
                }
            };
            match verdict {
                None => {}
                Some(Kinked::Settled(settled)) => return (settled, steps),
                Some(Kinked::Restarted) => budget = steps + MAX_STEPS,
            }
        }
    }

    /// The minimum over the segments is reached (the points not in `outward` settled): with
    /// pinned legs, first the subgradient test ([`unpin`](Self::unpin)), which may restart;
    /// then, with a point held at a segment's end by `T` pushing outwards, the minimum of the
    /// convex `T` lies outside the segments and no stationary path is inside them; otherwise
    /// the minimiser (or the collapse's verdict).
    fn settled(&mut self, held: usize, outward: usize, restarts: &mut usize) -> Option<Kinked> {
        let pinned = if self.pinned != 0 {
            match self.unpin(restarts) {
                Kinked::Settled(settled) => Some(settled),
                restarted => return Some(restarted),
            }
        } else {
            None
        };
        Some(Kinked::Settled(match (outward, pinned) {
            (0, None) if self.minimiser_inside(held) => Settled::Yes,
            (0, Some(settled)) => settled,
            _ => Settled::Outside,
        }))
    }

    /// Whether one more Newton step from the settled points leaves every free point strictly
    /// inside its segment: the minimiser of `T` on the segments' lines itself, not a point the
    /// tolerance accepted next to a segment's end while the minimiser lies on or beyond it.
    fn minimiser_inside(&mut self, held: usize) -> bool {
        if !self.newton_direction(held) {
            return true;
        }
        (0..self.g.k()).filter(|&i| held >> i & 1 == 0).all(|i| {
            let [lo, hi] = self.extent(i);
            let s = self.sc.nw.s[i] + self.sc.delta[i];
            s > lo && s < hi
        })
    }

    /// The extent `[start, end]` of point `i`'s segment, in its polyline's parameter.
    fn extent(&self, i: usize) -> [f64; 2] {
        let (line, j) = (self.g.line(i), self.sc.nw.seg[i]);
        [line.start(j), line.start(j + 1)]
    }

    /// The points not in `fixed` that sit at an end of their segment with the residual
    /// pushing them out of it.
    fn outward(&self, fixed: usize) -> usize {
        let nw = &self.sc.nw;
        (0..self.g.k())
            .filter(|&i| fixed >> i & 1 == 0)
            .filter(|&i| {
                let [lo, hi] = self.extent(i);
                let r = nw.eval.r[i];
                (nw.s[i] <= lo && r > 0.0) || (nw.s[i] >= hi && r < 0.0)
            })
            .fold(0, |m, i| m | 1 << i)
    }

    /// The largest relative residual of the points not in `fixed`.
    fn residual(&self, fixed: usize) -> f64 {
        let (e, w) = (&self.sc.nw.eval, self.g.slowness);
        (0..self.g.k())
            .filter(|&i| fixed >> i & 1 == 0)
            .map(|i| e.r[i].abs() / (w[i] + w[i + 1]))
            .fold(0.0, f64::max)
    }

    /// The points of the pinned legs (leg `j` joins points `j − 1` and `j`).
    fn pinned_points(&self) -> usize {
        self.pinned | (self.pinned >> 1)
    }

    /// The Newton step in `self.sc.delta` for the points not in `fixed` (0 for those), from
    /// the evaluation in `self.sc.nw`; damped where the Hessian is singular (legs along a
    /// segment's line). `false` when even the damped one cannot be solved.
    fn newton_direction(&mut self, fixed: usize) -> bool {
        let k = self.g.k();
        let is_fixed = |i: usize| fixed >> i & 1 == 1;
        let sc = &mut *self.sc;
        let e = &sc.nw.eval;
        for i in 0..k {
            let free = !is_fixed(i);
            sc.diag[i] = if free { e.diag[i] } else { 1.0 };
            sc.rhs[i] = if free { -e.r[i] } else { 0.0 };
            if i + 1 < k {
                sc.off[i] = if free && !is_fixed(i + 1) {
                    e.off[i]
                } else {
                    0.0
                };
            }
        }
        let n = k.saturating_sub(1);
        if thomas(&sc.diag, &sc.off[..n], &sc.rhs, &mut sc.delta, &mut sc.cp) {
            return true;
        }
        let scale = sc.diag.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        for d in &mut sc.diag {
            *d += 1e-9 * scale + f64::MIN_POSITIVE;
        }
        thomas(&sc.diag, &sc.off[..n], &sc.rhs, &mut sc.delta, &mut sc.cp)
    }

    /// One damped Newton step of [`minimise`](Self::minimise) from the evaluation in
    /// `self.sc.nw` for the points not in `held`, with backtracking on `T` along the step
    /// projected onto the segments (held points do not move: their step is 0).
    fn newton_step(&mut self, held: usize) -> NewtonStep {
        let k = self.g.k();
        let mut extent = [[f64::NEG_INFINITY, f64::INFINITY]; MAX_STATIONARY_STEPS];
        for (i, x) in extent.iter_mut().enumerate().take(k) {
            *x = self.extent(i);
        }
        // A point at an end of its segment that the step would push out of it stays there:
        // the step again without it (the Hessian of the rest stays positive definite).
        let mut fixed = held;
        loop {
            if !self.newton_direction(fixed) {
                return NewtonStep::Singular;
            }
            let (s, delta) = (&self.sc.nw.s, &self.sc.delta);
            let out = (0..k)
                .filter(|&i| fixed >> i & 1 == 0)
                .filter(|&i| {
                    let [lo, hi] = extent[i];
                    (s[i] <= lo && delta[i] < 0.0) || (s[i] >= hi && delta[i] > 0.0)
                })
                .fold(0, |m, i| m | 1 << i);
            if out == 0 {
                break;
            }
            fixed |= out;
        }
        let sc = &mut *self.sc;
        let (s, e) = (&sc.nw.s, &sc.nw.eval);
        let tiny = (0..k).all(|i| {
            sc.delta[i].abs() <= 4.0 * f64::EPSILON * (s[i].abs() + e.len[i] + e.len[i + 1])
        });
        if tiny {
            return NewtonStep::Done;
        }
        // No point moves further than twice its longer leg at once.
        let mut cap = 1.0f64;
        for i in 0..k {
            let reach = 2.0 * e.len[i].max(e.len[i + 1]);
            if sc.delta[i].abs() > reach {
                cap = cap.min(reach / sc.delta[i].abs());
            }
        }
        let slope: f64 = (0..k).map(|i| e.r[i] * sc.delta[i]).sum();
        // The residual of the moving points (the others' is held where it is).
        let w = self.g.slowness;
        let moving = |r: &[f64]| {
            (0..k)
                .filter(|&i| fixed >> i & 1 == 0)
                .map(|i| r[i].abs() / (w[i] + w[i + 1]))
                .fold(0.0, f64::max)
        };
        let (t0, rmax0) = (e.time, moving(&e.r));
        let mut alpha = cap;
        loop {
            for (i, &[lo, hi]) in extent.iter().enumerate().take(k) {
                sc.s_try[i] = (sc.nw.s[i] + alpha * sc.delta[i]).clamp(lo, hi);
            }
            let nw = &sc.nw;
            self.g
                .evaluate(&sc.s_try, &nw.seg, &nw.pin, &mut sc.trial, false, false);
            let drop = t0 - sc.trial.time;
            // Descent on T, or (within round-off of T) on the residual.
            let round_off = 4.0 * f64::EPSILON * t0;
            if drop >= -1e-4 * alpha * slope || (drop >= -round_off && moving(&sc.trial.r) < rmax0)
            {
                sc.nw.s[..k].copy_from_slice(&sc.s_try[..k]);
                return NewtonStep::Moved;
            }
            alpha *= 0.5;
            if alpha < 1e-12 {
                return NewtonStep::Stalled;
            }
        }
    }

    /// A solve that stalled or ran out of steps at the evaluation in `self.sc.nw`, where `T`
    /// is smooth only away from collapsed legs: the shortest leg between two free points on
    /// crossing lines is pinned ([`pin`](Self::pin); the subgradient test then decides
    /// exactly). Without such a leg: next to a vanishing leg (within [`COLLAPSE`] of the
    /// path's length), or with a leg along its interaction's line (within [`ALONG`]), no
    /// stationary path ([`Settled::Degenerate`], by these thresholds); otherwise not settled.
    fn stalled(&mut self, held: usize) -> Kinked {
        let k = self.g.k();
        let e = &self.sc.nw.eval;
        let total: f64 = e.len[..=k].iter().sum();
        let fixed = held | self.pinned_points();
        let pinnable = |j: usize| {
            e.len[j] <= COLLAPSE * total
                && fixed & ((1 << (j - 1)) | (1 << j)) == 0
                && self.crossing(j).is_some()
        };
        let shortest = (1..k)
            .filter(|&j| pinnable(j))
            .min_by(|&x, &y| e.len[x].total_cmp(&e.len[y]));
        if let Some(j) = shortest {
            return self.pin(held, j);
        }
        let along = |i: usize| {
            e.u[i].cross(e.tan[i]).abs() <= ALONG || e.u[i + 1].cross(e.tan[i]).abs() <= ALONG
        };
        let short = (0..=k).any(|j| e.len[j] <= COLLAPSE * total);
        Kinked::Settled(if short || (0..k).any(along) {
            Settled::Degenerate
        } else {
            Settled::No
        })
    }

    /// Where points `j − 1` and `j` meet if their leg collapses: their parameters at the
    /// crossing of their segments' lines, when the lines cross (not parallel) inside both
    /// segments (to round-off).
    fn crossing(&self, j: usize) -> Option<[f64; 2]> {
        let (a, b) = (j - 1, j);
        let nw = &self.sc.nw;
        let e = &nw.eval;
        let (ta, tb) = (e.tan[a], e.tan[b]);
        let det = ta.cross(tb);
        if det.abs() <= 1e-9 {
            return None;
        }
        let d = e.rel[b + 1] - e.rel[a + 1];
        let at = [nw.s[a] + d.cross(tb) / det, nw.s[b] + d.cross(ta) / det];
        let mut out = at;
        for (x, i) in out.iter_mut().zip([a, b]) {
            let [lo, hi] = self.extent(i);
            let pad = 1e-9 * (hi - lo);
            if !(*x >= lo - pad && *x <= hi + pad) {
                return None;
            }
            *x = x.clamp(lo, hi);
        }
        Some(out)
    }

    /// Pins collapsing leg `j`: its two points to the crossing of their segments' lines, held
    /// there while the others settle. Points held on vertices, a point already held by a
    /// pinned neighbour (three points on one spot), or no crossing inside the segments
    /// (points meeting along one line, where no side holds): no stationary path, by the rule
    /// of [`COLLAPSE`].
    fn pin(&mut self, held: usize, j: usize) -> Kinked {
        let (a, b) = (j - 1, j);
        if self.pinned_points() & ((1 << a) | (1 << b)) != 0 && !self.smoothed {
            // Three points on one spot: the smoothed time decides.
            self.smoothed = true;
            return self.smooth_away(held);
        }
        let fixed = (held | self.pinned_points()) & ((1 << a) | (1 << b)) != 0;
        let Some([sa, sb]) = self.crossing(j).filter(|_| !fixed) else {
            return Kinked::Settled(Settled::Degenerate);
        };
        let nw = &mut self.sc.nw;
        (nw.s[a], nw.s[b]) = (sa, sb);
        (nw.pin[a], nw.pin[b]) = (Pin::Vertex, Pin::Vertex);
        self.pinned |= 1 << j;
        Kinked::Restarted
    }

    /// Where several points collapse onto one spot, follows the minimum of the time with its
    /// kinks smoothed away (`|d| → √(|d|² + ε²)` on the legs between interactions, ε from
    /// 10⁻² down to 10⁻¹⁰ of the path's length; `T_ε` is convex and smooth, its minimisers
    /// tend to `T`'s): where the collapsed legs stay below 10⁻⁶ of the path's length, the
    /// collapse is the minimum (no stationary path); otherwise the points, now apart, go on
    /// with `T` itself. Pins are cleared either way.
    fn smooth_away(&mut self, held: usize) -> Kinked {
        let k = self.g.k();
        let fixed = held;
        for i in 0..k {
            if fixed >> i & 1 == 0 {
                self.sc.nw.pin[i] = Pin::Free;
            }
        }
        self.pinned = 0;
        let total: f64 = self.sc.nw.eval.len[..=k].iter().sum();
        let mut eps = 1e-2 * total;
        while eps >= 1e-10 * total {
            for _ in 0..60 {
                if !self.smoothed_step(fixed, eps) {
                    break;
                }
            }
            eps *= 0.1;
        }
        let len = self.smoothed_legs(0.0);
        let apart = (1..k).all(|l| len[l] > 1e-6 * total);
        if apart {
            Kinked::Restarted
        } else {
            Kinked::Settled(Settled::Degenerate)
        }
    }

    /// The legs' lengths at the present points, those between interactions smoothed by
    /// `eps`.
    fn smoothed_legs(&self, eps: f64) -> [f64; MAX_STATIONARY_STEPS + 1] {
        let k = self.g.k();
        let mut out = [0.0; MAX_STATIONARY_STEPS + 1];
        let mut prev = self.g.source;
        for (l, x) in out.iter_mut().enumerate().take(k + 1) {
            let p = self.smoothed_point(l);
            let d = p - prev;
            let smooth = if l >= 1 && l < k { eps * eps } else { 0.0 };
            *x = (d.dot(d) + smooth).sqrt();
            prev = p;
        }
        out
    }

    /// Point `l` of the path (the receiver for `l = k`) at the parameters in `self.sc.nw`.
    fn smoothed_point(&self, l: usize) -> Point {
        let nw = &self.sc.nw;
        if l == self.g.k() {
            self.g.receiver
        } else {
            self.g.line(l).point_on(nw.seg[l], nw.s[l])
        }
    }

    /// One damped Newton step on the smoothed time `T_ε` over the points not in `fixed`,
    /// each kept on its segment: `false` when it no longer descends.
    fn smoothed_step(&mut self, fixed: usize, eps: f64) -> bool {
        let k = self.g.k();
        let w = self.g.slowness;
        let time = |this: &Self| -> f64 {
            let len = this.smoothed_legs(eps);
            (0..=k).map(|l| w[l] * len[l]).sum()
        };
        // Legs, their smoothed lengths and Hessian blocks M = w (I/f − d dᵀ/f³).
        let mut d = [Vec2::default(); MAX_STATIONARY_STEPS + 1];
        let mut prev = self.g.source;
        for (l, x) in d.iter_mut().enumerate().take(k + 1) {
            let p = self.smoothed_point(l);
            *x = p - prev;
            prev = p;
        }
        let f = self.smoothed_legs(eps);
        let tan = |i: usize| self.g.line(i).tangent(self.sc.nw.seg[i]);
        let m = |l: usize, a: Vec2, b: Vec2| {
            w[l] * (a.dot(b) / f[l] - a.dot(d[l]) * b.dot(d[l]) / (f[l] * f[l] * f[l]))
        };
        for i in 0..k {
            let t = tan(i);
            let free = fixed >> i & 1 == 0;
            let r = w[i] * d[i].dot(t) / f[i] - w[i + 1] * d[i + 1].dot(t) / f[i + 1];
            self.sc.rhs[i] = if free { -r } else { 0.0 };
            self.sc.diag[i] = if free {
                m(i, t, t) + m(i + 1, t, t)
            } else {
                1.0
            };
            if i + 1 < k {
                let both = free && fixed >> (i + 1) & 1 == 0;
                self.sc.off[i] = if both { -m(i + 1, t, tan(i + 1)) } else { 0.0 };
            }
        }
        let n = k.saturating_sub(1);
        let sc = &mut *self.sc;
        if !thomas(&sc.diag, &sc.off[..n], &sc.rhs, &mut sc.delta, &mut sc.cp) {
            return false;
        }
        let t0 = time(self);
        let saved: [f64; MAX_STATIONARY_STEPS] =
            std::array::from_fn(|i| if i < k { self.sc.nw.s[i] } else { 0.0 });
        let mut alpha = 1.0;
        while alpha > 1e-10 {
            for (i, &start) in saved.iter().enumerate().take(k) {
                let [lo, hi] = self.extent(i);
                self.sc.nw.s[i] = (start + alpha * self.sc.delta[i]).clamp(lo, hi);
            }
            if time(self) < t0 {
                return true;
            }
            alpha *= 0.5;
        }
        self.sc.nw.s[..k].copy_from_slice(&saved[..k]);
        false
    }

    /// The other points settled with the pinned legs held: every pinned leg whose collapse is
    /// not at the minimum ([`kink_direction`](Self::kink_direction) `|g| > 1`) restarts
    /// ([`restart_apart`](Self::restart_apart); at most [`MAX_RESTARTS`] times in a solve,
    /// then not settled); when none does, `0 ∈ ∂T` at the collapse: no stationary path.
    fn unpin(&mut self, restarts: &mut usize) -> Kinked {
        let k = self.g.k();
        let total: f64 = self.sc.nw.eval.len[..=k].iter().sum();
        let (mut moved, mut at_end) = (false, false);
        for j in 1..k {
            if self.pinned >> j & 1 == 0 {
                continue;
            }
            let Some(kink) = self.kink_direction(j) else {
                return Kinked::Settled(Settled::No);
            };
            if kink.least <= 1.0 {
                at_end |= kink.at_end;
                continue;
            }
            if *restarts >= MAX_RESTARTS {
                return Kinked::Settled(Settled::No);
            }
            let n = kink.both.length();
            self.restart_apart(j, kink.both * (1.0 / n), total);
            moved = true;
        }
        if moved {
            *restarts += 1;
            Kinked::Restarted
        } else if at_end {
            // The minimum over the segments has points at their ends.
            Kinked::Settled(Settled::Outside)
        } else {
            Kinked::Settled(Settled::Degenerate)
        }
    }

    /// Frees pinned leg `j`'s two points, apart along the unit direction `dir` (`σ_b t_b −
    /// σₐ tₐ = δ dir`): `δ` the one of 10⁻¹ … 10⁻⁶ of the path's length `total` where `T` is
    /// least (the leg of the minimum is short where `|g|` is near 1).
    fn restart_apart(&mut self, j: usize, dir: Vec2, total: f64) {
        let (a, b) = (j - 1, j);
        let (ea, eb) = (self.extent(a), self.extent(b));
        let sc = &mut *self.sc;
        let (ta, tb) = (sc.nw.eval.tan[a], sc.nw.eval.tan[b]);
        let det = ta.cross(tb);
        (sc.nw.pin[a], sc.nw.pin[b]) = (Pin::Free, Pin::Free);
        let (sa, sb) = (sc.nw.s[a], sc.nw.s[b]);
        let k = self.g.k();
        let mut best = (f64::INFINITY, 0.0);
        let mut delta = 0.1 * total;
        for _ in 0..6 {
            let v = dir * delta;
            sc.s_try[..k].copy_from_slice(&sc.nw.s[..k]);
            sc.s_try[a] = (sa - v.cross(tb) / det).clamp(ea[0], ea[1]);
            sc.s_try[b] = (sb + ta.cross(v) / det).clamp(eb[0], eb[1]);
            let nw = &sc.nw;
            self.g
                .evaluate(&sc.s_try, &nw.seg, &nw.pin, &mut sc.trial, false, false);
            if sc.trial.time < best.0 {
                best = (sc.trial.time, delta);
            }
            delta *= 0.1;
        }
        let v = dir * best.1;
        sc.nw.s[a] = (sa - v.cross(tb) / det).clamp(ea[0], ea[1]);
        sc.nw.s[b] = (sb + ta.cross(v) / det).clamp(eb[0], eb[1]);
        self.pinned &= !(1 << j);
    }

    /// For pinned leg `j` (points `a = j − 1`, `b = j` on one spot `X`): the directions `g`
    /// that in place of the leg's would make `X` a minimum over the segments, given the
    /// others: `w g · tₐ = wᵢₙ uᵢₙ · tₐ` and `w g · t_b = wₒᵤₜ uₒᵤₜ · t_b`, each equation an
    /// inequality where its point sits at an end of its segment (`T` may only rise inwards).
    /// `T` being convex, `X` is the minimum exactly when one of them has `|g| ≤ 1`. `None`
    /// when a neighbouring leg has vanished too.
    fn kink_direction(&self, j: usize) -> Option<KinkDirection> {
        let (a, b) = (j - 1, j);
        let e = &self.sc.nw.eval;
        let (ta, tb) = (e.tan[a], e.tan[b]);
        let det = ta.cross(tb);
        if e.len[a] <= e.vanish || e.len[j + 1] <= e.vanish {
            return None;
        }
        let w = self.g.slowness;
        let alpha = w[a] * e.u[a].dot(ta) / w[j];
        let beta = w[j + 1] * e.u[j + 1].dot(tb) / w[j];
        // Both equations: the direction to restart along.
        let both = Vec2::new(
            (alpha * tb.y - ta.y * beta) / det,
            (ta.x * beta - alpha * tb.x) / det,
        );
        // Where a point sits at an end, its equation holds as `g · t ≤ c` or `≥ c`
        // (∂T/∂s ≥ 0 at the start, ≤ 0 at the end; ∂T/∂sₐ = w (c − g · tₐ) for `a`,
        // ∂T/∂s_b = w (g · t_b − c) for `b`).
        let nw = &self.sc.nw;
        let side = |i: usize| {
            let [lo, hi] = self.extent(i);
            if nw.s[i] <= lo {
                -1
            } else if nw.s[i] >= hi {
                1
            } else {
                0
            }
        };
        let holds = |g: Vec2| {
            let pad = 1e-12;
            let ok = |v: f64, c: f64, sense: i32| match sense {
                0 => (v - c).abs() <= pad,
                s if s < 0 => v <= c + pad,
                _ => v >= c - pad,
            };
            // At its start, g · tₐ ≤ α for `a` and g · t_b ≥ β for `b`.
            ok(g.dot(ta), alpha, side(a)) && ok(g.dot(tb), beta, -side(b))
        };
        let least = [Vec2::default(), ta * alpha, tb * beta]
            .into_iter()
            .filter(|&g| holds(g))
            .map(Vec2::length)
            .fold(both.length(), f64::min);
        let at_end = side(a) != 0 || side(b) != 0;
        (both.length().is_finite()).then_some(KinkDirection {
            both,
            least,
            at_end,
        })
    }
}
