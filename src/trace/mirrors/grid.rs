//! The beam tree streamed: each node's receivers located directly (a scan over a grid of
//! receivers), and the paths of the node's *certain beam* taken without their points: no
//! validation but the last leg's crossings, and the amplitude from the unfolded line.
//!
//! **Which receivers a node visits.** The receivers [`Beam::holds`] keeps, as
//! [`Validation::node`] visits them: when the receivers form a grid (every x of a set with
//! every y of a set, in any order: a `receivers.grid`, or a list that is one), the beam's
//! three half-planes, widened by their largest margin over the receivers' box and by far more
//! than their round-off, cut each row (or column) of the grid to an interval, found by
//! bisection; each receiver there then takes [`Beam::holds`] itself. Otherwise every
//! receiver is tested, as before. The same receivers, in another order.
//!
//! **The certain beam.** Beside its beam (a superset of the rays of its valid paths: every
//! test widened by the margins), each node carries a certain beam, a subset: its window is
//! the part of its wall inside the parent's certain beam by [`INNER`] times the beam tests'
//! margins, less every interval any leg from the parent's window to it could be obstructed
//! on (the shadows widened by the occlusion's margin, [`Occluders::clear`]). A receiver
//! inside the certain beam by [`INNER`] margins has, in exact arithmetic, the image method's
//! path through every wall of the sequence with each reflection point strictly inside its
//! certain window, hence inside its segment, and every leg but the last unobstructed; the
//! margins lie far above the round-off of the images and of [`Validation::path`]'s tests, so
//! that validation certainly accepts the path's points and its legs but the last. Its other
//! tests, each leg on one side of its reflection and no vanished leg, hold where the heights
//! of the points above the walls' lines exceed the vanishing threshold (1e-12 of the path,
//! far below the margin `δ`): the node is *sure* where, for every two consecutive
//! reflections `j−1, j`, the leg between them is at least `ℓ` long and meets both walls at
//! cosines of at least `c`, with `ℓ` the larger of the least heights of window `j` over wall
//! `j−1`'s line and of window `j−1` over wall `j`'s, `c` from the rays through the window's
//! ends, and every height so bounded above `4 δ` ([`MirrorWalls::certain_child`]). Every
//! other receiver of the node, and every receiver of a node that is not sure, is validated
//! as before.
//!
//! **The last leg.** A node's last legs run from its window to its receivers, inside its
//! beam beyond its wall's line and within the box of its window and the receivers. Where no
//! segment of the scene meets that region (widened by the occlusion's margin; a segment that
//! shares a corner with the wall counts only where it runs to the legs' side of the wall's
//! line), no last leg can cross one, and none is tested; elsewhere each is, by the same test
//! ([`Scene::first_crossing_on_line`](crate::scene::Scene) on the same points).
//!
//! **The amplitude.** The path's time is the slowness times the unfolded length `|I − r|`;
//! its amplitude is the unfolded tube's closed form (`amplitude::ray::TreeLaws`) with each
//! bounce's cosine the unfolded line's direction against its wall's normal mirrored into the
//! last leg's frame ([`BounceGroup`]), the bounces grouped by interface and (where the
//! coefficient depends on the angle) by that normal, so that each distinct angle's
//! coefficient is taken once. An axisymmetric source's width takes the first leg's direction,
//! the x axis mirrored likewise. Where the closed form declines (a bounce near a critical
//! angle, a point of the path perhaps across the axis), the path is validated and walked as
//! before.
//!
//! The walk, its limits, its work and its stops are [`MirrorWalls::walk`]'s: the same nodes,
//! the same receivers visited, the same arrivals (each path's time and amplitude to
//! round-off).

use std::cmp::Ordering::{Equal, Greater, Less};

use crate::amplitude::BounceGroup;
use crate::geom::{Aabb, Point, Vec2, orient};
use crate::scene::SegmentRef;

use super::super::classify::END_MARGIN;
use super::super::occlusion::{OCCLUSION_MARGIN, Target};
use super::{
    Beam, Bounds, MirrorPath, MirrorScratch, MirrorSearch, MirrorStats, MirrorWalls, Node,
    POLL_TRIES, PROGRESS_BEAMS, Status, Validation, Wall,
};

/// How many times the beam tests' margins a receiver (and a child's certain window) must lie
/// inside a certain beam.
const INNER: f64 = 16.0;

/// The largest `|m × n|` of two unit normals taken for one angle: the mirrored normals'
/// round-off is a few ulps a level.
const SAME_ANGLE: f64 = 1e-13;

/// Receivers that form a grid: every x of `xs` with every y of `ys`.
#[derive(Clone, Debug)]
pub(crate) struct ReceiverGrid {
    /// The distinct x and y, ascending.
    xs: Vec<f64>,
    ys: Vec<f64>,
    /// The receiver at `(xs[i], ys[j])`: `index[i * ys.len() + j]`.
    index: Vec<u32>,
    /// The receivers' box.
    bounds: Aabb,
}

impl ReceiverGrid {
    /// The grid `receivers` form, when they form one (at least two x and two y, finite).
    pub(crate) fn of(receivers: &[Point]) -> Option<ReceiverGrid> {
        let n = receivers.len();
        if n < 4 || u32::try_from(n).is_err() {
            return None;
        }
        let sorted = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v.dedup_by(|a, b| a.to_bits() == b.to_bits());
            v
        };
        // Receivers listed row by row (a scene's `grid`: receiver `ix · ny + iy`): the axes
        // of the first run of one x and of every `ny`-th receiver. Where every receiver
        // then finds its own slot of the `nx · ny = n`, the receivers' x are all in these
        // xs and every slot is filled, so these are the receivers' distinct x (and y):
        // the axes the sorts of all of them give.
        let ny = receivers
            .iter()
            .take_while(|p| p.x.to_bits() == receivers[0].x.to_bits())
            .count();
        if n.is_multiple_of(ny) {
            let xs = sorted(receivers.iter().step_by(ny).map(|p| p.x).collect());
            let ys = sorted(receivers[..ny].iter().map(|p| p.y).collect());
            if let Some(grid) = Self::indexed(receivers, xs, ys) {
                return Some(grid);
            }
        }
        let axis = |f: fn(&Point) -> f64| sorted(receivers.iter().map(f).collect());
        Self::indexed(receivers, axis(|p| p.x), axis(|p| p.y))
    }

    /// The grid of `receivers` over the axes `xs` and `ys` (sorted, distinct), when each
    /// receiver has a slot of its own and there are as many slots as receivers.
    fn indexed(receivers: &[Point], xs: Vec<f64>, ys: Vec<f64>) -> Option<ReceiverGrid> {
        let n = receivers.len();
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if xs.len() < 2 || ys.len() < 2 || xs.len() * ys.len() != n || !finite(&xs) || !finite(&ys)
        {
            return None;
        }
        let mut index = vec![u32::MAX; n];
        for (k, p) in receivers.iter().enumerate() {
            let i = xs.binary_search_by(|v| v.total_cmp(&p.x)).ok()?;
            let j = ys.binary_search_by(|v| v.total_cmp(&p.y)).ok()?;
            let slot = &mut index[i * ys.len() + j];
            if *slot != u32::MAX {
                return None;
            }
            *slot = k as u32;
        }
        Some(ReceiverGrid {
            xs,
            ys,
            index,
            bounds: Aabb::around(receivers),
        })
    }

    /// Every receiver that may lie in `beam` (of the node of image `image` on `wall`; a
    /// superset of those [`Beam::holds`] keeps with the margin `delta`) into `out` (cleared
    /// first), row by row (or column by column, whichever are fewer). With
    /// `inner` (a sure node's certain beam), `out` also says which receivers certainly
    /// lie inside it by [`INNER`] margins (its part of each row, shrunk far beyond the
    /// round-off of its ends and of [`Beam::gauge`]: each such receiver passes the gauge's
    /// test, which need not be taken; the others may pass it too).
    #[inline(always)]
    fn scan(
        &self,
        (beam, inner): (&Beam, Option<&Beam>),
        wall: &Wall,
        image: Point,
        delta: f64,
        out: &mut Vec<(u32, bool)>,
    ) {
        out.clear();
        let b = self.bounds;
        let corners = [
            b.min,
            b.max,
            Point::new(b.min.x, b.max.y),
            Point::new(b.max.x, b.min.y),
        ];
        // The receivers' largest `|x − image|₁` (a convex function: at a corner), which
        // bounds the gauge's margins over them.
        let reach = corners
            .iter()
            .map(|&c| (c.x - image.x).abs() + (c.y - image.y).abs())
            .fold(0.0f64, f64::max);
        let size = corners
            .iter()
            .map(|c| c.x.abs() + c.y.abs())
            .fold(image.x.abs() + image.y.abs(), f64::max);
        let near = BeamSide {
            wall,
            image,
            delta,
            reach,
            size,
        };
        // The beam's constraints, widened far beyond their round-off; the certain beam's,
        // by `INNER` times their largest margins and far beyond their round-off inward.
        let outer = near.constraints(beam, |margin, slack| -(2.0 * margin + slack));
        let deep = inner.map(|inner| {
            near.constraints(inner, |margin, slack| {
                INNER * margin * (1.0 + 1e-12) + slack
            })
        });
        let by_rows = self.ys.len() <= self.xs.len();
        let (lines, along) = if by_rows {
            (&self.ys, &self.xs)
        } else {
            (&self.xs, &self.ys)
        };
        let ny = self.ys.len();
        let slack = 1e-9 * size;
        for (li, &v) in lines.iter().enumerate() {
            let Some((lo, hi)) = row_interval(&outer, by_rows, v) else {
                continue;
            };
            let first = along.partition_point(|&u| u < lo - slack);
            let last = along.partition_point(|&u| u <= hi + slack);
            let (deep_first, deep_last) =
                match deep.as_ref().and_then(|d| row_interval(d, by_rows, v)) {
                    Some((lo, hi)) => (
                        along.partition_point(|&u| u < lo + slack).max(first),
                        along.partition_point(|&u| u <= hi - slack).min(last),
                    ),
                    None => (last, last),
                };
            for ai in first..last {
                let (i, j) = if by_rows { (ai, li) } else { (li, ai) };
                let certain = (deep_first..deep_last).contains(&ai);
                out.push((self.index[i * ny + j], certain));
            }
        }
    }
}

/// A node's beams against the receivers' grid: its wall and image, the margin on
/// positions, the receivers' largest `|x − image|₁` and the scale of the coordinates.
struct BeamSide<'w> {
    wall: &'w Wall,
    image: Point,
    delta: f64,
    reach: f64,
    size: f64,
}

/// A beam's three constraints on a point `x` of the plane as `(a, c, bound)`: `a · x + c ≥
/// bound`, `a · x + c` the value [`Beam::gauge`] takes.
type Constraints = [(Vec2, f64, f64); 3];

impl BeamSide<'_> {
    /// `beam`'s constraints, each bound `bound(margin, slack)` of its largest margin over
    /// the receivers and a slack far above the round-off of its value.
    fn constraints(&self, beam: &Beam, bound: impl Fn(f64, f64) -> f64) -> Constraints {
        let (wall, image, delta, reach) = (self.wall, self.image, self.delta, self.reach);
        let o = -beam.side;
        let normal = wall.n * beam.side;
        let edge_a = Vec2::new(-beam.to_a.y, beam.to_a.x) * o;
        let edge_b = Vec2::new(beam.to_b.y, -beam.to_b.x) * o;
        [
            (
                normal,
                -normal.dot(wall.p - Point::new(0.0, 0.0)),
                2.0 * delta,
            ),
            (
                edge_a,
                -edge_a.dot(image - Point::new(0.0, 0.0)),
                delta * (beam.reach_a + 2.0 * reach),
            ),
            (
                edge_b,
                -edge_b.dot(image - Point::new(0.0, 0.0)),
                delta * (beam.reach_b + 2.0 * reach),
            ),
        ]
        .map(|(a, c, margin)| {
            let slack = 1e-9 * (a.x.abs() + a.y.abs()) * self.size;
            (a, c, bound(margin, slack))
        })
    }
}

/// The part `[lo, hi]` of the row (or column) at `v` where every constraint holds (`None`:
/// none; the ends as computed, to be widened or shrunk by the caller).
#[inline]
fn row_interval(constraints: &Constraints, by_rows: bool, v: f64) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for &(a, c, bound) in constraints {
        let (a_along, a_line) = if by_rows { (a.x, a.y) } else { (a.y, a.x) };
        // a_along · u ≥ rhs.
        let rhs = bound - c - a_line * v;
        if a_along > 0.0 {
            lo = lo.max(rhs / a_along);
        } else if a_along < 0.0 {
            hi = hi.min(rhs / a_along);
        } else if !matches!(rhs.partial_cmp(&0.0), Some(Less | Equal)) {
            return None;
        }
    }
    matches!(lo.partial_cmp(&hi), Some(Less | Equal)).then_some((lo, hi))
}

/// How many receivers a [`TreeRun`] holds at most.
pub(crate) const RUN: usize = 64;

/// Arrivals of one node of the streamed tree in closed form, one receiver after another
/// (valid during the call that reports them): what the node's paths share, and per path
/// its receiver, unfolded line, length and time.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TreeRun<'a> {
    /// Which node of the walk they come from (the number of beams before it): the paths of
    /// one node, which share its bounce groups and axes, come one after another.
    pub node: u64,
    /// Their reflections.
    pub steps: usize,
    /// Their bounces, grouped by angle.
    pub groups: &'a [BounceGroup],
    /// The x axis mirrored into the last leg's frame: `Lₖ ⋯ Lⱼ₊₁ eₓ` for each leg `j`
    /// (distinct to 1e-13), so that leg `j`'s x component is `axes[j] · direction / length`;
    /// the first leg's (`j = 0`) is `axis`.
    pub axis: Vec2,
    pub axes: &'a [Vec2],
    /// Whether every leg of each path certainly runs one way along x by far more than
    /// [`axisymmetric_run`](Self::axisymmetric_run)'s threshold (found once for the node's
    /// certain beam, which holds the paths: [`one_way`]).
    pub one_way: bool,
    /// Per path: the receiver's index in the receivers given; the unfolded line, from the
    /// image to the receiver; its length `|I − r|`; the travel time.
    pub receivers: &'a [usize],
    pub directions: &'a [Vec2],
    pub lengths: &'a [f64],
    pub times: &'a [f64],
}

impl TreeRun<'_> {
    /// For an axisymmetric source on the axis (`x = 0`), path `k`'s first leg's run along x
    /// over the unfolded line's, `|A₀ · d|` (its out-of-plane width is then `|x_R| ℓ₀ /
    /// |x₁ − x₀| = |x_R| L / |A₀ · d|`), where every leg certainly runs one way along x (each
    /// `|Aⱼ · d|` above 1e-12 of `L`, all of one sign), so that every point of the path but
    /// the source lies strictly on one side of the axis; `None` where that is not certain.
    #[inline]
    pub(crate) fn axisymmetric_run(&self, k: usize) -> Option<f64> {
        let d = self.directions[k];
        let first = self.axis.dot(d);
        if self.one_way {
            return Some(first.abs());
        }
        let tiny = 1e-12 * self.lengths[k];
        let sign = first.signum();
        let one_way = self.axes.iter().all(|a| {
            let v = a.dot(d);
            v.abs() > tiny && v.signum() == sign
        });
        (one_way && first.abs() > tiny).then(|| first.abs())
    }
}

/// The closed-form paths of one node gathered for a [`TreeRun`], up to [`RUN`] of them.
struct RunBuffer {
    len: usize,
    receivers: [usize; RUN],
    directions: [Vec2; RUN],
    lengths: [f64; RUN],
    times: [f64; RUN],
}

impl RunBuffer {
    fn new() -> RunBuffer {
        RunBuffer {
            len: 0,
            receivers: [0; RUN],
            directions: [Vec2::new(0.0, 0.0); RUN],
            lengths: [0.0; RUN],
            times: [0.0; RUN],
        }
    }
}

/// What the closed-form paths of a node share: its bounce groups, its mirrored x axes
/// ([`TreeRun::axes`]), and whether every leg of each certainly runs one way along x
/// ([`TreeRun::one_way`]).
#[derive(Clone, Copy, Debug)]
struct NodeOwn<'a> {
    groups: &'a [BounceGroup],
    axes: &'a [Vec2],
    one_way: bool,
}

/// Whether every direction `d` inside the wedge of the certain beam `inner` (from its
/// image between its edges `to_a` and `to_b`, an angle below π: `d = α to_a + β to_b`,
/// `α, β ≥ 0`) has each `A · d` (`A` the first leg's mirrored x axis `axis` and every one
/// of `axes`) of one sign and above `1e-9 |A| |d|` in size: `A · d ≥ min(A · to_a / |to_a|,
/// A · to_b / |to_b|) (α |to_a| + β |to_b|)`, the latter at least `|d|`. So the closed form's
/// own test ([`TreeRun::axisymmetric_run`]: each above 1e-12 of `|d|`, of the first's
/// sign) holds for every receiver of the certain beam, far beyond its round-off.
fn one_way(inner: &Beam, axis: Vec2, axes: &[Vec2]) -> bool {
    let (la, lb) = (inner.to_a.length(), inner.to_b.length());
    if !(la > 0.0 && lb > 0.0 && la.is_finite() && lb.is_finite()) {
        return false;
    }
    let run = |a: Vec2| {
        let size = a.length();
        let (u, v) = (a.dot(inner.to_a) / la, a.dot(inner.to_b) / lb);
        let least = 1e-9 * size;
        if u > least && v > least {
            1
        } else if u < -least && v < -least {
            -1
        } else {
            0
        }
    };
    let sign = run(axis);
    sign != 0 && axes.iter().all(|&a| run(a) == sign)
}

/// What a node of the tree certainly holds (beside its [`Node`] on the stack).
#[derive(Clone, Copy, Debug)]
pub(super) struct Certain {
    /// Its certain beam (`None`: none, or the root's whole plane).
    inner: Option<Beam>,
    /// Whether every receiver inside `inner` by [`INNER`] margins (every receiver at the
    /// root) certainly has a valid path but for its last leg's crossings.
    sure: bool,
    /// `Lₖ ⋯ L₁ eₓ`.
    axis: Vec2,
    /// Where the node's bounce groups, and its mirrored x axes ([`TreeRun::axes`]), start
    /// in the scratch's.
    groups: usize,
    axes: usize,
}

impl Default for Certain {
    fn default() -> Certain {
        Certain {
            inner: None,
            sure: true,
            axis: Vec2::new(1.0, 0.0),
            groups: 0,
            axes: 0,
        }
    }
}

/// The fractions of `range` where an affine function, `g0` and `g1` at the segment's ends,
/// is at least `margin`, shrunk inward by its round-off; `None` when empty.
#[inline(always)]
fn restrict_inside(range: [f64; 2], g0: f64, g1: f64, margin: f64) -> Option<[f64; 2]> {
    let (f0, f1) = (g0 - margin, g1 - margin);
    let [mut lo, mut hi] = range;
    if f0 >= 0.0 && f1 >= 0.0 {
        return Some(range);
    }
    if !(f0 >= 0.0 || f1 >= 0.0) {
        return None;
    }
    let u = f0 / (f0 - f1);
    if f0 < 0.0 {
        lo = lo.max(u + 4.0 * f64::EPSILON);
    } else {
        hi = hi.min(u - 4.0 * f64::EPSILON);
    }
    (lo <= hi).then_some([lo, hi])
}

/// The bounce groups and mirrored x axes of the nodes on the stack, each node's after its
/// parent's.
#[derive(Clone, Debug, Default)]
pub(super) struct Bounces {
    groups: Vec<BounceGroup>,
    axes: Vec<Vec2>,
}

impl Bounces {
    fn clear(&mut self) {
        self.groups.clear();
        self.axes.clear();
    }

    /// Back to the nodes below `c`.
    fn pop(&mut self, c: &Certain) {
        self.groups.truncate(c.groups);
        self.axes.truncate(c.axes);
    }
}

/// `a` into the axes from `start` on, unless one of them is within 1e-13 of it.
#[inline(always)]
fn push_axis(axes: &mut Vec<Vec2>, start: usize, a: Vec2) {
    let near = |b: &Vec2| (a.x - b.x).abs() + (a.y - b.y).abs() <= 1e-13;
    if !axes[start..].iter().any(near) {
        axes.push(a);
    }
}

/// `v` mirrored in a line of unit normal `n`.
#[inline(always)]
fn mirrored(v: Vec2, n: Vec2) -> Vec2 {
    v - n * (2.0 * n.dot(v))
}

impl MirrorWalls {
    /// The certain beam of `child` (`node`'s child through wall `w`) and what else it
    /// certainly holds (see the module), its bounce groups appended to `groups`.
    #[expect(
        clippy::too_many_arguments,
        reason = "the parent and child, the search's bounds and its scratch"
    )]
    fn certain_child(
        &self,
        node: &Node,
        parent: &Certain,
        child: &Node,
        w: usize,
        bounds: &Bounds,
        angled: &[bool],
        shadows: &mut Vec<[f64; 2]>,
        bounces: &mut Bounces,
    ) -> Certain {
        let wall = &self.walls[w];
        let Bounces { groups, axes } = bounces;
        let start = groups.len();
        let parent_groups = parent.groups..start;
        for k in parent_groups {
            let g = groups[k];
            groups.push(BounceGroup {
                normal: mirrored(g.normal, wall.n),
                ..g
            });
        }
        let interface = wall.own.interface;
        let angle = angled.get(interface as usize).copied().unwrap_or(true);
        let normal = if angle { wall.n } else { Vec2::new(0.0, 0.0) };
        match groups[start..].iter_mut().find(|g| {
            g.interface == interface && (!angle || g.normal.cross(normal).abs() <= SAME_ANGLE)
        }) {
            Some(g) => g.count += 1,
            None => groups.push(BounceGroup {
                interface,
                count: 1,
                normal,
            }),
        }
        let axis = mirrored(parent.axis, wall.n);
        let first_axis = axes.len();
        for k in parent.axes..first_axis {
            let a = mirrored(axes[k], wall.n);
            push_axis(axes, first_axis, a);
        }
        push_axis(axes, first_axis, Vec2::new(1.0, 0.0));
        let inner = if parent.sure {
            self.certain_window(node, parent, child, w, bounds, shadows)
        } else {
            None
        };
        Certain {
            inner,
            sure: inner.is_some(),
            axis,
            groups: start,
            axes: first_axis,
        }
    }

    /// The certain beam of `child` (`node`'s child through wall `w`) when the node is sure
    /// and so is the child (see the module); `None` else.
    fn certain_window(
        &self,
        node: &Node,
        parent: &Certain,
        child: &Node,
        w: usize,
        bounds: &Bounds,
        shadows: &mut Vec<[f64; 2]>,
    ) -> Option<Beam> {
        let wall = &self.walls[w];
        let delta = bounds.delta;
        let side = child.beam?.side;
        let mut range = [0.0, 1.0];
        let root = node.wall == usize::MAX;
        if !root {
            let beam = parent.inner.as_ref()?;
            let last = &self.walls[node.wall];
            let gp = beam.gauge(last, node.image, wall.p, delta);
            let gq = beam.gauge(last, node.image, wall.q, delta);
            for c in 0..3 {
                let margin = INNER * gp.margins[c].max(gq.margins[c]);
                range = restrict_inside(range, gp.values[c], gq.values[c], margin)?;
            }
        }
        let window = self.window(node)?;
        let target = Target {
            own: wall.own,
            p: wall.p,
            q: wall.q,
            n: wall.n,
        };
        let m = OCCLUSION_MARGIN * delta;
        range = self.occluders.clear(&window, &target, range, m, shadows)?;
        let (a, b) = (wall.at(range[0]), wall.at(range[1]));
        // The heights and cosines of the legs between the two reflections.
        let floor = 4.0 * delta;
        let height = |x: Point| side * wall.height(x);
        if root {
            if height(node.image).partial_cmp(&floor) != Some(Greater) {
                return None;
            }
        } else {
            let (pa, pb) = (parent.inner?.a, parent.inner?.b);
            let last = &self.walls[node.wall];
            let last_side = node.beam?.side;
            let incoming = height(pa).min(height(pb));
            let outgoing = (last_side * last.height(a)).min(last_side * last.height(b));
            let leg = incoming.max(outgoing);
            let unit = |x: Point| {
                let d = x - node.image;
                d * (1.0 / d.length())
            };
            let (ua, ub) = (unit(a), unit(b));
            let cos = |n: Vec2| ua.dot(n).abs().min(ub.dot(n).abs());
            let into = incoming.max(leg * cos(wall.n));
            let out_of = outgoing.max(leg * cos(last.n));
            if !(leg > floor && into > floor && out_of > floor) {
                return None;
            }
        }
        let (to_a, to_b) = (a - child.image, b - child.image);
        Some(Beam {
            side,
            to_a,
            to_b,
            reach_a: to_a.x.abs() + to_a.y.abs(),
            reach_b: to_b.x.abs() + to_b.y.abs(),
            a,
            b,
            // The certain beam is inside the true one: its own edges bound it tightly.
            tight_a: to_a,
            tight_b: to_b,
        })
    }

    /// Whether a last leg of `node` (from its window to a receiver in its beam within
    /// `receivers`, the receivers' box) may cross a segment of the scene: whether any
    /// segment but the node's wall meets the region those legs fill (see the module).
    fn last_legs_may_cross(&self, node: &Node, source: Point, receivers: Aabb, delta: f64) -> bool {
        let m = OCCLUSION_MARGIN * delta;
        let grow = |b: Aabb| {
            let g = Vec2::new(m, m);
            Aabb::from_points(b.min - g, b.max + g)
        };
        if node.wall == usize::MAX {
            let region = grow(receivers.union(Aabb::from_points(source, source)));
            return self
                .occluders
                .each()
                .any(|(c, d, _)| Aabb::from_points(c, d).overlaps(region));
        }
        let Some(beam) = &node.beam else {
            return true;
        };
        let wall = &self.walls[node.wall];
        let region = grow(receivers.union(Aabb::from_points(beam.a, beam.b)));
        self.occluders.each().any(|(c, d, own)| {
            if own == wall.own || !Aabb::from_points(c, d).overlaps(region) {
                return false;
            }
            let other = if c == wall.p || c == wall.q {
                Some(d)
            } else if d == wall.p || d == wall.q {
                Some(c)
            } else {
                None
            };
            if let Some(other) = other {
                // A segment from a corner of the wall: only one that runs to the legs' side.
                let o = orient(wall.p, wall.q, other);
                return o != 0.0 && o.signum() == beam.side;
            }
            let gc = beam.gauge(wall, node.image, c, delta);
            let gd = beam.gauge(wall, node.image, d, delta);
            let mut range = [0.0, 1.0];
            for k in 0..3 {
                let margin = m + INNER * gc.margins[k].max(gd.margins[k]);
                match super::restrict(range, gc.values[k], gd.values[k], margin) {
                    Some(r) => range = r,
                    None => return false,
                }
            }
            true
        })
    }
}

/// One node's receivers, as the streamed walk visits them.
struct NodeReceivers<'v, 'a, 's, F> {
    walls: &'a MirrorWalls,
    bounds: &'a Bounds,
    validation: Validation<'v, 's>,
    found: &'v mut F,
    unfolded: &'v mut dyn FnMut(&TreeRun<'_>) -> usize,
    stats: &'v mut MirrorStats,
    /// The node's closed-form paths not yet given to `unfolded`.
    run: RunBuffer,
    /// The processor's vector instructions ([`visit`](Self::visit)).
    arch: pulp::Arch,
    /// The receivers a node's scan found ([`ReceiverGrid::scan`]), kept for the next.
    scanned: Vec<(u32, bool)>,
}

/// [`NodeReceivers::visit`] as [`pulp::Arch::dispatch`] compiles it for each set of vector
/// instructions (the receivers' tests and closed forms inlined, so compiled with them).
struct VisitNode<'n, 'v, 'a, 's, 'x, F> {
    receivers: &'n mut NodeReceivers<'v, 'a, 's, F>,
    stack: &'x [Node],
    walls: &'x [usize],
    certain: &'x [Certain],
    bounces: &'x Bounces,
    grid: Option<&'x ReceiverGrid>,
}

impl<F> pulp::WithSimd for VisitNode<'_, '_, '_, '_, '_, F>
where
    F: FnMut(MirrorPath<'_>) -> bool,
{
    type Output = bool;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> bool {
        let VisitNode {
            receivers,
            stack,
            walls,
            certain,
            bounces,
            grid,
        } = self;
        receivers.visit_compiled(stack, walls, certain, bounces, grid)
    }
}

/// What [`NodeReceivers::closed`] finds for a receiver.
enum ClosedForm {
    /// Its path in closed form: the unfolded line (from the image to the receiver), its
    /// length and the travel time.
    Path {
        direction: Vec2,
        length: f64,
        time: f64,
    },
    /// Certainly no path: too late, or obstructed where obstructed paths are not listed.
    NoPath,
    /// Its path must be validated on its points.
    Validate,
}

impl<F> NodeReceivers<'_, '_, '_, F>
where
    F: FnMut(MirrorPath<'_>) -> bool,
{
    /// Receiver `r` at the node on top of `stack` (its walls `walls`): as
    /// [`Validation::node`] takes it, but in closed form where the node's certain beam holds
    /// it (gathered into [`run`](Self::run), [`flush`](Self::flush)ed to `unfolded` before
    /// any receiver is validated, when full and at the node's end, so that the arrivals
    /// keep their order); `false` where `found` stops the search. `crossings`: whether the
    /// node's last legs may cross a segment, found at the first receiver that asks.
    /// `known_deep`: whether the grid's scan found `r` inside the certain beam by [`INNER`]
    /// margins ([`ReceiverGrid::scan`]), so that neither beam's test is taken for it.
    #[inline(always)]
    fn receiver(
        &mut self,
        stack: &[Node],
        walls: &[usize],
        certain: &Certain,
        own: NodeOwn<'_>,
        crossings: &mut Option<bool>,
        (r, known_deep): (usize, bool),
    ) -> bool {
        let search = self.validation.search;
        let top = &stack[stack.len() - 1];
        let receiver = search.receivers[r];
        let delta = self.bounds.delta;
        // Inside the certain beam by `INNER` margins (a sure node's): inside the beam, whose
        // test is then not needed (the certain beam lies in it, its margins far above the
        // round-off of either test).
        #[cfg(test)]
        if known_deep {
            tests::check_known_deep(self.walls, top, certain, receiver, delta);
        }
        let deep = known_deep
            || (certain.sure
                && match (&top.beam, &certain.inner) {
                    (Some(_), Some(inner)) => {
                        let g =
                            inner.gauge(&self.walls.walls[top.wall], top.image, receiver, delta);
                        (0..3).all(|c| g.values[c] >= INNER * g.margins[c])
                    }
                    _ => false,
                });
        let inside = deep
            || match &top.beam {
                Some(beam) => beam.holds(&self.walls.walls[top.wall], top.image, receiver, delta),
                None => true,
            };
        // (Without a time bound, no receiver is too far: the distance is not needed.)
        let reach = self.bounds.reach;
        if !inside || (reach.is_finite() && top.image.distance(receiver) - 4.0 * delta > reach) {
            return true;
        }
        self.stats.leaves += 1;
        self.stats.work += stack.len() as u64;
        match self.closed(stack, certain, crossings, (r, deep)) {
            ClosedForm::NoPath => true,
            ClosedForm::Validate => {
                self.flush(stack, walls, certain, own) && self.validated(stack, walls, r)
            }
            ClosedForm::Path {
                direction,
                length,
                time,
            } => {
                let run = &mut self.run;
                let k = run.len;
                run.receivers[k] = r;
                run.directions[k] = direction;
                run.lengths[k] = length;
                run.times[k] = time;
                run.len += 1;
                run.len < RUN || self.flush(stack, walls, certain, own)
            }
        }
    }

    /// Receiver `r`'s path validated on its points and given to `found` (nothing where it
    /// has none or comes too late); `false` where `found` stops the search.
    fn validated(&mut self, stack: &[Node], walls: &[usize], r: usize) -> bool {
        let search = self.validation.search;
        let Some((length, reason)) = self.validation.path(stack, search.receivers[r]) else {
            return true;
        };
        let time = search.medium().time_along(length);
        if time > search.max_time {
            return true;
        }
        (self.found)(MirrorPath {
            receiver: r,
            walls,
            points: self.validation.points,
            time,
            status: if reason.is_some() {
                Status::Obstructed
            } else {
                Status::Converged
            },
            reason,
        })
    }

    /// The gathered closed-form paths ([`run`](Self::run)) to `unfolded`, in order; each
    /// one it declines validated and given to `found` in its place. `false` where `found`
    /// stops the search.
    fn flush(
        &mut self,
        stack: &[Node],
        walls: &[usize],
        certain: &Certain,
        own: NodeOwn<'_>,
    ) -> bool {
        let len = std::mem::replace(&mut self.run.len, 0);
        let mut start = 0;
        while start < len {
            let run = &self.run;
            start += (self.unfolded)(&TreeRun {
                node: self.stats.beams,
                steps: stack.len() - 1,
                groups: own.groups,
                axis: certain.axis,
                axes: own.axes,
                one_way: own.one_way,
                receivers: &run.receivers[start..len],
                directions: &run.directions[start..len],
                lengths: &run.lengths[start..len],
                times: &run.times[start..len],
            });
            if start < len {
                let r = self.run.receivers[start];
                start += 1;
                if !self.validated(stack, walls, r) {
                    return false;
                }
            }
        }
        true
    }

    /// Receiver `r`'s path in closed form, or that it certainly has none, or that it must
    /// be validated. `deep`: whether it lies inside the node's certain beam by [`INNER`]
    /// margins.
    #[inline(always)]
    fn closed(
        &mut self,
        stack: &[Node],
        certain: &Certain,
        crossings: &mut Option<bool>,
        (r, deep): (usize, bool),
    ) -> ClosedForm {
        if !certain.sure {
            return ClosedForm::Validate;
        }
        let search = self.validation.search;
        let top = &stack[stack.len() - 1];
        let receiver = search.receivers[r];
        let root = top.wall == usize::MAX;
        if !root && !deep {
            return ClosedForm::Validate;
        }
        let d = receiver - top.image;
        let l2 = d.x * d.x + d.y * d.y;
        if !(f64::MIN_POSITIVE..1e300).contains(&l2) {
            return ClosedForm::Validate;
        }
        let length = l2.sqrt();
        let time = search.medium().time_along(length);
        if search.max_time.is_finite() && (time - search.max_time).abs() <= 1e-9 * time {
            return ClosedForm::Validate;
        }
        if time > search.max_time {
            return ClosedForm::NoPath;
        }
        let may_cross = *crossings.get_or_insert_with(|| {
            self.walls.last_legs_may_cross(
                top,
                search.source,
                self.bounds.receivers,
                self.bounds.delta,
            )
        });
        if may_cross {
            // The last leg as `Validation::path` has it: from the wall's point on the line.
            let (from, own) = if root {
                (search.source, SegmentRef::NONE)
            } else {
                let wall = &self.walls.walls[top.wall];
                let u = ((wall.p - top.image).cross(d) / d.cross(wall.e)).clamp(0.0, 1.0);
                if u.is_nan() {
                    return ClosedForm::Validate;
                }
                (wall.at(u), wall.own)
            };
            let line = [top.image, receiver];
            if from != receiver
                && search
                    .scene
                    .first_crossing_on_line(
                        from,
                        receiver,
                        line,
                        END_MARGIN,
                        [own, SegmentRef::NONE],
                    )
                    .is_some()
            {
                // Obstructed (listed only where asked, and then never in closed form).
                return if search.obstructed {
                    ClosedForm::Validate
                } else {
                    ClosedForm::NoPath
                };
            }
        }
        ClosedForm::Path {
            direction: d,
            length,
            time,
        }
    }
}

impl MirrorWalls {
    /// [`MirrorWalls::arrivals`] for a streamed search: the paths of each node's certain
    /// beam to `unfolded` in closed form ([`TreeRun`]; it returns how many of the run's
    /// paths it takes, from the first: the next is validated and given to `found` instead),
    /// every other one to `found`
    /// as [`arrivals`](Self::arrivals) gives it; each node's receivers located on their grid
    /// where they form one (see `mirrors/grid.rs`). `angled[i]`: whether interface `i`'s
    /// coefficient depends on the angle. The same paths, to round-off, in another order.
    pub(crate) fn arrivals_streamed(
        &self,
        search: &MirrorSearch<'_>,
        scratch: &mut MirrorScratch,
        angled: &[bool],
        found: &mut impl FnMut(MirrorPath<'_>) -> bool,
        unfolded: &mut dyn FnMut(&TreeRun<'_>) -> usize,
        progress: &mut impl FnMut(u64) -> bool,
    ) -> MirrorStats {
        let bounds = self.bounds(search, search.max_steps.min(search.max_depth));
        let grid = ReceiverGrid::of(search.receivers);
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
            certain,
            bounces,
        } = scratch;
        stack.clear();
        walls.clear();
        certain.clear();
        bounces.clear();
        if bounds.late(search.source, None) {
            return stats;
        }
        stack.push(Node {
            wall: usize::MAX,
            image: search.source,
            beam: None,
            next: 0,
        });
        certain.push(Certain::default());
        bounces.axes.push(Vec2::new(1.0, 0.0));
        let mut node = NodeReceivers {
            walls: self,
            bounds: &bounds,
            validation: Validation {
                search,
                walls: &self.walls,
                points,
                rel,
                lens,
                far,
                crossings: true,
                crossers: Some(&self.crossers),
            },
            found,
            unfolded,
            stats: &mut stats,
            run: RunBuffer::new(),
            arch: pulp::Arch::new(),
            scanned: Vec::new(),
        };
        if !node.visit(stack, walls, certain, bounces, grid.as_ref()) {
            node.stats.stopped = true;
            return stats;
        }
        while let Some(top) = stack.last_mut() {
            let depth = walls.len();
            if depth >= max_steps || top.next >= self.walls.len() {
                if depth >= max_steps && search.max_steps > max_steps && depth > 0 {
                    node.stats.stopped = true;
                }
                stack.pop();
                walls.pop();
                if let Some(c) = certain.pop() {
                    bounces.pop(&c);
                }
                continue;
            }
            let w = top.next;
            top.next += 1;
            if w == top.wall {
                continue;
            }
            tries = tries.wrapping_add(1);
            if tries % POLL_TRIES == 0 && !progress(0) {
                node.stats.stopped = true;
                break;
            }
            let parent = *top;
            node.stats.work += 1;
            if node.stats.work > search.max_work {
                node.stats.stopped = true;
                break;
            }
            let occlusion = (!search.obstructed).then_some(&mut *shadows);
            let Some(child) = self.child(&parent, w, &bounds, occlusion, &mut node.stats.work)
            else {
                continue;
            };
            node.stats.beams += 1;
            if node.stats.beams > granted {
                if !progress(PROGRESS_BEAMS) {
                    node.stats.beams -= 1;
                    node.stats.stopped = true;
                    break;
                }
                granted += PROGRESS_BEAMS;
            }
            if node.stats.beams > search.max_beams {
                node.stats.beams -= 1;
                node.stats.stopped = true;
                break;
            }
            let up = certain[certain.len() - 1];
            let next =
                self.certain_child(&parent, &up, &child, w, &bounds, angled, shadows, bounces);
            stack.push(child);
            walls.push(w);
            certain.push(next);
            if !node.visit(stack, walls, certain, bounces, grid.as_ref()) {
                node.stats.stopped = true;
                break;
            }
        }
        stats
    }
}

impl<F> NodeReceivers<'_, '_, '_, F>
where
    F: FnMut(MirrorPath<'_>) -> bool,
{
    /// Every receiver of the node on top of `stack`: those its beam may hold on `grid`,
    /// else all; `false` where the search stops. Compiled for the processor's vector
    /// instructions where it has them (AVX2, AVX-512: fewer instructions for the same
    /// operations, so the same numbers), as [`VisitNode`].
    fn visit(
        &mut self,
        stack: &[Node],
        walls: &[usize],
        certain: &[Certain],
        bounces: &Bounces,
        grid: Option<&ReceiverGrid>,
    ) -> bool {
        self.arch.dispatch(VisitNode {
            receivers: self,
            stack,
            walls,
            certain,
            bounces,
            grid,
        })
    }

    /// [`visit`](Self::visit)'s work.
    #[inline(always)]
    fn visit_compiled(
        &mut self,
        stack: &[Node],
        walls: &[usize],
        certain: &[Certain],
        bounces: &Bounces,
        grid: Option<&ReceiverGrid>,
    ) -> bool {
        let top = stack[stack.len() - 1];
        let c = certain[certain.len() - 1];
        let axes = &bounces.axes[c.axes..];
        let own = NodeOwn {
            groups: &bounces.groups[c.groups..],
            axes,
            one_way: c.sure && c.inner.is_some_and(|inner| one_way(&inner, c.axis, axes)),
        };
        let (mirrors, delta) = (self.walls, self.bounds.delta);
        let count = self.validation.search.receivers.len();
        let mut crossings = None;
        let go = match (grid, &top.beam) {
            (Some(grid), Some(beam)) => {
                let wall = &mirrors.walls[top.wall];
                let inner = c.inner.as_ref().filter(|_| c.sure);
                let mut scanned = std::mem::take(&mut self.scanned);
                grid.scan((beam, inner), wall, top.image, delta, &mut scanned);
                // A loop, not `all`: its body stays inlined (and compiled for the vector
                // instructions).
                let mut go = true;
                for &(r, known_deep) in &scanned {
                    let at = (r as usize, known_deep);
                    if !self.receiver(stack, walls, &c, own, &mut crossings, at) {
                        go = false;
                        break;
                    }
                }
                self.scanned = scanned;
                go
            }
            _ => {
                (0..count).all(|r| self.receiver(stack, walls, &c, own, &mut crossings, (r, false)))
            }
        };
        go && self.flush(stack, walls, &c, own)
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

    use super::*;
    use crate::options::Run;
    use crate::{Scene, Tracer};

    /// Receivers the grid's scan took as inside their node's certain beam by [`INNER`]
    /// margins, and of those, the ones the gauge's own test does not find so.
    static KNOWN_DEEP: AtomicU64 = AtomicU64::new(0);
    static NOT_DEEP: AtomicU64 = AtomicU64::new(0);

    /// The test [`NodeReceivers::receiver`] takes where the scan did not find `receiver`
    /// deep, counted for a receiver the scan found deep.
    pub(super) fn check_known_deep(
        walls: &MirrorWalls,
        top: &Node,
        certain: &Certain,
        receiver: Point,
        delta: f64,
    ) {
        KNOWN_DEEP.fetch_add(1, Relaxed);
        let deep = certain.sure
            && match (&top.beam, &certain.inner) {
                (Some(_), Some(inner)) => {
                    let g = inner.gauge(&walls.walls[top.wall], top.image, receiver, delta);
                    (0..3).all(|c| g.values[c] >= INNER * g.margins[c])
                }
                _ => false,
            };
        if !deep {
            NOT_DEEP.fetch_add(1, Relaxed);
        }
    }

    /// The axes from the first row and column, where they index every receiver, are those
    /// of sorting all the receivers' coordinates: the same grid (axes, index and box, bit
    /// for bit) or none, for grids listed by rows, by columns and shuffled, with a receiver
    /// moved off the grid, repeated, or missing, and for lists whose first run of one x is
    /// no row.
    #[test]
    fn the_first_row_and_column_give_the_sorted_axes() {
        let full = |r: &[Point]| {
            let axis = |f: fn(&Point) -> f64| {
                let mut v: Vec<f64> = r.iter().map(f).collect();
                v.sort_by(f64::total_cmp);
                v.dedup_by(|a, b| a.to_bits() == b.to_bits());
                v
            };
            ReceiverGrid::indexed(r, axis(|p| p.x), axis(|p| p.y))
        };
        let bits = |g: &Option<ReceiverGrid>| {
            g.as_ref().map(|g| {
                let b = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let corners = [
                    g.bounds.min.x,
                    g.bounds.min.y,
                    g.bounds.max.x,
                    g.bounds.max.y,
                ];
                (b(&g.xs), b(&g.ys), g.index.clone(), b(&corners))
            })
        };
        let grid = |nx: usize, ny: usize, by_rows: bool| -> Vec<Point> {
            let point =
                |i: usize, j: usize| Point::new(100.0 + 25.0 * i as f64, -1.0 - 2.0 * j as f64);
            if by_rows {
                (0..nx)
                    .flat_map(|i| (0..ny).map(move |j| point(i, j)))
                    .collect()
            } else {
                (0..ny)
                    .flat_map(|j| (0..nx).map(move |i| point(i, j)))
                    .collect()
            }
        };
        let mut cases: Vec<Vec<Point>> = Vec::new();
        for (nx, ny) in [(197, 50), (2, 2), (3, 7), (7, 3), (1, 5), (5, 1)] {
            for by_rows in [true, false] {
                cases.push(grid(nx, ny, by_rows));
            }
        }
        let mut shuffled = grid(9, 4, true);
        let mut state = 7u64;
        for i in (1..shuffled.len()).rev() {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            shuffled.swap(i, (state >> 33) as usize % (i + 1));
        }
        cases.push(shuffled);
        let mut off = grid(9, 4, true);
        off[13].x += 1.0;
        cases.push(off);
        let mut repeated = grid(9, 4, true);
        repeated[13] = repeated[12];
        cases.push(repeated);
        let mut missing = grid(9, 4, true);
        missing.pop();
        cases.push(missing);
        // A first run of two that is no row: the grid is by columns of four.
        let mut runs = grid(4, 4, false);
        runs.swap(1, 4);
        cases.push(runs);
        let mut found = 0;
        for (k, r) in cases.iter().enumerate() {
            let (got, want) = (ReceiverGrid::of(r), full(r));
            assert_eq!(bits(&got), bits(&want), "case {k}");
            found += usize::from(got.is_some());
        }
        assert_eq!(found, 10, "the grids of two or more x and y are found");
    }

    /// Every receiver the grid's scan finds inside a certain beam by `INNER` margins (and so
    /// takes without a test) passes the certain beam's own test, which the other receivers
    /// take: the same receivers in closed form, the same arrivals. Random sloping waveguides
    /// (one to four bottom segments, a tilted surface, grids of receivers of random size and
    /// spacing, in rows or in columns), the scan's receivers checked one by one.
    #[test]
    fn receivers_the_scan_finds_deep_pass_the_certain_beams_test() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |lo: f64, hi: f64| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
        };
        for case in 0..16 {
            let length = next(500.0, 3000.0);
            let pieces = 1 + case % 4;
            let mut bottom = vec![[-10.0, -next(40.0, 150.0)]];
            for k in 1..=pieces {
                let x = if k == pieces {
                    length + 10.0
                } else {
                    length * k as f64 / pieces as f64 + next(-20.0, 20.0)
                };
                bottom.push([x, -next(40.0, 150.0)]);
            }
            let tilt = next(-3.0, 3.0) * f64::from(case % 2);
            let (nx, ny) = if case % 3 == 0 {
                (5 + case, 40)
            } else {
                (40 + 3 * case, 7 + case)
            };
            let doc = serde_json::json!({
                "media": { "water": { "speed": 1500, "density": 1 },
                           "sediment": { "speed": 1700, "density": 1.8, "at": [10, -300] } },
                "background": "water",
                "domain": [[-10, -400], [length + 10.0, 20]],
                "interfaces": {
                    "surface": { "points": [[-10, 0], [length + 10.0, tilt]],
                                 "reflection": "pressure-release" },
                    "bottom": { "points": bottom, "reflection": "media" }
                },
                "sources": [[0, -next(5.0, 35.0)]],
                "receivers": { "grid": { "x": [next(20.0, 80.0), length - next(5.0, 50.0), nx],
                                         "y": [-next(0.5, 2.0), -next(30.0, 38.0), ny] } },
                "search": { "max_steps": 14, "refract": false },
                "amplitudes": { "source": "axisymmetric", "frequency": 100 }
            });
            let scene = Scene::from_json(&doc.to_string()).unwrap();
            let tracer = Tracer::new(&scene).unwrap();
            tracer.search_into(&Run::new(), &|_| {}).unwrap();
        }
        let (known, not) = (KNOWN_DEEP.load(Relaxed), NOT_DEEP.load(Relaxed));
        assert_eq!(not, 0, "{not} of {known}");
        assert!(known > 100_000, "{known}");
    }
}
