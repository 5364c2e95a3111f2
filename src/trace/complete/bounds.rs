//! The certain bounds of the residuals over a tuple of places, which prune the search.

use std::f64::consts::PI;

use crate::geom::{Aabb, Point, Vec2};
use crate::leg::{LegModel, Uniform};

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

/// The [`Chord`] of a leg from a point of `a` to a point of `b`.
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
    /// Between boxes apart: the directions of the differences of their points.
    Box(Legs),
    /// Between touching places on one interface: an arc of directions.
    Arc(Chord),
    /// Any direction.
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
    /// The box of the differences.
    d: Aabb,
    /// The round-off of a direction's components.
    pad: f64,
    /// The directions of the box's corners.
    corners: [Vec2; 4],
}

/// The [`Legs`] from a point of `from` to a point of `to`.
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
/// `rᵢ` within `(wᵢ uᵢ − wᵢ₊₁ uᵢ₊₁) · t₀ ± (wᵢ + wᵢ₊₁) |tᵢ − t₀|`. The directions `u` are the
/// legs' chords' (the boxes' differences); the slowness vectors at the legs' ends come from
/// them through the leg model ([`LegModel::along_at_ends`], [`LegModel::greatest_slowness`]:
/// for the uniform medium's straight legs, `w u` and `w`).
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
            // The legs' slowness vectors at the point, through the leg model: their sizes,
            // and their components along `t` from their chords'.
            let (ma, mb) = (Uniform::new(w[i]), Uniform::new(w[i + 1]));
            let (wa, wb) = (ma.greatest_slowness(), mb.greatest_slowness());
            let slack = (wa + wb) * spread + 1e-10 * (wa + wb);
            let excludes =
                |a: [f64; 2], b: [f64; 2]| a[0] - b[1] - slack > 0.0 || a[1] - b[0] + slack < 0.0;
            let (a0, a1) = before.dot_ranges(t);
            let (b0, b1) = after.dot_ranges(t);
            let (a0, a1) = (ma.along_at_ends(a0), a1.map(|a| ma.along_at_ends(a)));
            let (b0, b1) = (mb.along_at_ends(b0), b1.map(|b| mb.along_at_ends(b)));
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

#[cfg(test)]
mod tests {
    use std::f64::consts::TAU;

    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngSeed};

    use super::*;
    use crate::demo::SplitMix64;
    use crate::polyline::Polyline;
    use crate::trace::complete::hierarchy::Hierarchy;

    /// A fixed budget: a few thousand cases, well under a second in the test-opt profile.
    fn config(cases: u32, seed: u64) -> Config {
        Config {
            cases,
            rng_seed: RngSeed::Fixed(seed),
            failure_persistence: None,
            ..Config::default()
        }
    }

    /// The unit vector at angle `a`.
    fn unit(a: f64) -> Vec2 {
        Vec2::new(a.cos(), a.sin())
    }

    /// The point at fractions `(fx, fy)` of box `b`.
    fn in_box(b: Aabb, fx: f64, fy: f64) -> Point {
        Point::new(
            b.min.x + fx * (b.max.x - b.min.x),
            b.min.y + fy * (b.max.y - b.min.y),
        )
    }

    /// A box from its centre and half-sizes.
    fn boxed(c: (f64, f64), h: (f64, f64)) -> Aabb {
        Aabb::from_points(
            Point::new(c.0 - h.0, c.1 - h.1),
            Point::new(c.0 + h.0, c.1 + h.1),
        )
    }

    /// Whether `x` lies in `range`.
    fn within(x: f64, range: [f64; 2]) -> bool {
        range[0] <= x && x <= range[1]
    }

    /// A fraction, the ends of the range drawn more often (a box's corners and edges).
    fn fraction() -> impl Strategy<Value = f64> {
        prop_oneof![Just(0.0), Just(1.0), 0.0..=1.0]
    }

    /// The place of a free point on a segment through `x` along the unit tangent at angle
    /// `alpha`, reaching `back` behind `x` and `ahead` beyond it (as a leaf's assignment
    /// bounds it: spread 0).
    fn segment_place(x: Point, alpha: f64, back: f64, ahead: f64) -> Place {
        let t = unit(alpha);
        let bbox = Aabb::from_points(x - t * back, x + t * ahead);
        Place {
            tangent: t,
            spread: 0.0,
            ..Place::new(bbox, [alpha, alpha], 0, 1)
        }
    }

    /// The place of a hierarchy node around `x`: the box grown by `grow` on each side and the
    /// cone widened by `widen` on each side of `alpha`.
    fn node_place(x: Point, alpha: f64, grow: [f64; 4], widen: [f64; 2]) -> Place {
        let bbox = Aabb::from_points(
            Point::new(x.x - grow[0], x.y - grow[1]),
            Point::new(x.x + grow[2], x.y + grow[3]),
        );
        Place::new(bbox, [alpha - widen[0], alpha + widen[1]], 0, 1)
    }

    /// The outgoing direction at a point on a line of unit tangent `t`, for the incoming
    /// direction `u` (crossing from the normal's side to the other, `u · n < 0`), slowness
    /// `w0` before and `w1` after: Snell's law (`w0 sin θ0 = w1 sin θ1`) for a refraction, the
    /// mirror image for a reflection. `None` beyond the critical angle.
    fn outgoing(u: Vec2, t: Vec2, w0: f64, w1: f64, reflect: bool) -> Option<Vec2> {
        let n = t.perp();
        let (along, across) = (u.dot(t), u.dot(n));
        if reflect {
            return Some(t * along - n * across);
        }
        let sine = w0 * along / w1;
        (sine.abs() < 1.0).then(|| t * sine + n * (across.signum() * (1.0 - sine * sine).sqrt()))
    }

    /// The box of differences of [(−2, −1), (−1, 1)] seen from the origin holds the
    /// direction (−1, 0): with t = (1, 0) the lower bound reaches −1, below every corner's.
    #[test]
    fn a_box_astride_minus_t_reaches_minus_one() {
        let from = Aabb::from_points(Point::new(0.0, 0.0), Point::new(0.0, 0.0));
        let to = Aabb::from_points(Point::new(-2.0, -1.0), Point::new(-1.0, 1.0));
        let l = legs(from, to).expect("the boxes are apart");
        let [lo, hi] = dot_range(l, Vec2::new(1.0, 0.0));
        assert!(lo <= -1.0, "lower bound {lo}");
        // The upper bound: the corners (−1, ±1), at 135° and 225°.
        assert!((hi + 0.5f64.sqrt()).abs() < 1e-9, "upper bound {hi}");
        // And seen along t = (−1, 0): the upper bound reaches 1.
        let [_, hi] = dot_range(l, Vec2::new(-1.0, 0.0));
        assert!(hi >= 1.0, "upper bound {hi}");
    }

    /// Touching boxes give no box of directions; boxes apart do.
    #[test]
    fn touching_boxes_give_no_bound() {
        let a = Aabb::from_points(Point::new(0.0, 0.0), Point::new(1.0, 1.0));
        let b = Aabb::from_points(Point::new(1.0, 0.5), Point::new(2.0, 2.0));
        assert!(legs(a, b).is_none());
        assert!(legs(a, a).is_none());
        let c = Aabb::from_points(Point::new(1.5, 0.5), Point::new(2.0, 2.0));
        assert!(legs(a, c).is_some());
    }

    /// A reflection in the line y = 0 at the origin (source (−1, 1), receiver (1, 1)) is
    /// not pruned where its segment holds the origin, and pruned where the segment lies at
    /// x ∈ [5, 6], where every leg's residual has one sign.
    #[test]
    fn a_mirror_is_pruned_only_away_from_its_reflection() {
        let (s, r) = (Point::new(-1.0, 1.0), Point::new(1.0, 1.0));
        let w = [1.0, 1.0];
        let here = segment_place(Point::new(0.0, 0.0), 0.0, 1.0, 2.0);
        assert!(!pruned(&[here], s, r, &w));
        let there = segment_place(Point::new(5.0, 0.0), 0.0, 0.0, 1.0);
        assert!(pruned(&[there], s, r, &w));
        // A node holding both: not pruned.
        let node = node_place(Point::new(0.0, 0.0), 0.0, [1.0, 0.0, 6.0, 0.0], [0.1, 0.1]);
        assert!(!pruned(&[node], s, r, &w));
    }

    /// A corner reflector: the walls x = 0 and y = 0 as one polyline (0, 2), (0, 0), (2, 0);
    /// the path (1, 2) → (0, 1) → (1, 0) → (2, 1) reflects off both. The two points' boxes
    /// touch at the corner, so the leg between them is bounded by its chord.
    #[test]
    fn a_corner_reflection_is_not_pruned() {
        let (s, r) = (Point::new(1.0, 2.0), Point::new(2.0, 1.0));
        let half = std::f64::consts::FRAC_PI_2;
        let mut a = segment_place(Point::new(0.0, 1.0), -half, 1.0, 1.0);
        let mut b = segment_place(Point::new(1.0, 0.0), 0.0, 1.0, 1.0);
        (a.first, a.end, b.first, b.end) = (0, 1, 1, 2);
        (a.interface, b.interface) = (0, 0);
        assert!(legs(a.bbox, b.bbox).is_none(), "the boxes touch");
        assert!(chord(&a, &b).is_some());
        assert!(!pruned(&[a, b], s, r, &[1.0, 1.0, 1.0]));
        // With the receiver moved behind the first wall, every leg to it from the second
        // wall runs back along that wall, while the leg arriving there runs forward along
        // it: no point of the second wall is stationary, pruned.
        assert!(pruned(&[a, b], s, Point::new(-1.0, 1.0), &[1.0, 1.0, 1.0]));
    }

    /// Random polylines: for two nodes of its hierarchy whose places touch, every direction
    /// from a point of the first to a point of the second lies in the chord's arc (the
    /// opposite one where the second point comes first), and its `u · t` in the chord's
    /// ranges.
    #[test]
    fn a_chord_holds_every_leg_along_the_polyline() {
        let mut rng = SplitMix64(0xc0ed);
        let mut checked = 0;
        for m in 2..=24 {
            for closed in [false, true] {
                if closed && m < 3 {
                    continue;
                }
                let line = random_polyline(&mut rng, m, closed);
                let h = Hierarchy::new(&line);
                for na in &h.nodes {
                    for nb in &h.nodes {
                        let (mut a, mut b) = (na.place, nb.place);
                        (a.interface, b.interface) = (3, 3);
                        let Some(c) = chord(&a, &b) else { continue };
                        for _ in 0..8 {
                            let ja = a.first + (rng.next_u64() as usize) % (a.end - a.first);
                            let jb = b.first + (rng.next_u64() as usize) % (b.end - b.first);
                            let (fa, fb) = (rng.next_f64(), rng.next_f64());
                            let x =
                                line.point_on(ja, line.start(ja) + fa * line.segment_length(ja));
                            let y =
                                line.point_on(jb, line.start(jb) + fb * line.segment_length(jb));
                            let d = y - x;
                            if d.length() < 1e-9 {
                                continue;
                            }
                            let u = d * (1.0 / d.length());
                            let later = jb > ja || (ja == jb && fb > fa);
                            assert!(c.both || later != c.reversed, "{ja} → {jb}: {c:?}");
                            let along = if later { u } else { -u };
                            let [e0, e1] = c.ends;
                            let inside = e0.cross(along) >= -1e-12 && along.cross(e1) >= -1e-12;
                            assert!(inside, "{ja} → {jb}: {along:?} outside {c:?}");
                            let t = unit(TAU * rng.next_f64());
                            let (r0, r1) = LegBound::Arc(c).dot_ranges(t);
                            let dot = u.dot(t);
                            let range = match (c.both, later) {
                                (true, false) => r1.expect("both arcs"),
                                _ => r0,
                            };
                            assert!(within(dot, range), "{dot} outside {range:?}");
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert!(checked > 1000, "{checked} legs checked");
    }

    /// A random polyline of `m` segments: a walk of random lengths and turns up to ±2.5 rad.
    fn random_polyline(rng: &mut SplitMix64, m: usize, closed: bool) -> Polyline {
        loop {
            let vertices = if closed { m } else { m + 1 };
            let mut heading = TAU * rng.next_f64();
            let mut p = Point::new(0.0, 0.0);
            let mut points = vec![p];
            for _ in 1..vertices {
                heading += 2.5 * (2.0 * rng.next_f64() - 1.0);
                p = p + unit(heading) * (0.1 + rng.next_f64());
                points.push(p);
            }
            if let Ok(line) = Polyline::new(points, closed) {
                return line;
            }
        }
    }

    proptest! {
        #![proptest_config(config(4000, 0xb0_0de5))]

        /// `dot_range` never excludes a direction: for boxes apart, every unit direction
        /// from a point of one to a point of the other has its `u · t` inside the range.
        #[test]
        fn dot_range_holds_every_direction(
            c0 in (-4.0..4.0f64, -4.0..4.0f64), h0 in (0.0..2.0f64, 0.0..2.0f64),
            c1 in (-4.0..4.0f64, -4.0..4.0f64), h1 in (0.0..2.0f64, 0.0..2.0f64),
            angle in 0.0..TAU,
            samples in proptest::collection::vec(
                (fraction(), fraction(), fraction(), fraction()),
                12,
            ),
        ) {
            let (from, to) = (boxed(c0, h0), boxed(c1, h1));
            let Some(l) = legs(from, to) else { return Ok(()) };
            // Along a random tangent, the axes, away from the corners and from the middle
            // of the differences (whose direction then gives u · t = −1).
            let mut tangents = vec![unit(angle), Vec2::new(1.0, 0.0), Vec2::new(0.0, -1.0)];
            tangents.extend(l.corners.iter().map(|&c| -c));
            let middle = to.center() - from.center();
            tangents.push(middle * (-1.0 / middle.length()));
            for t in tangents {
                let range = dot_range(l, t);
                for &(a, b, c, d) in samples.iter().chain([&(0.5, 0.5, 0.5, 0.5)]) {
                    let v = in_box(to, c, d) - in_box(from, a, b);
                    let u = v * (1.0 / v.length());
                    prop_assert!(within(u.dot(t), range), "{} outside {:?}", u.dot(t), range);
                }
            }
        }

        /// `dot_range` is tight: each of its ends is reached by a direction of the box (its
        /// boundary sampled densely), so the bound prunes what it can. Along the axes too,
        /// where `ray_meets` takes a zero component.
        #[test]
        fn dot_range_is_tight(
            c0 in (-4.0..4.0f64, -4.0..4.0f64), h0 in (0.0..2.0f64, 0.0..2.0f64),
            c1 in (-4.0..4.0f64, -4.0..4.0f64), h1 in (0.0..2.0f64, 0.0..2.0f64),
            angle in 0.0..TAU, axis in 0..4usize,
        ) {
            let (from, to) = (boxed(c0, h0), boxed(c1, h1));
            let Some(l) = legs(from, to) else { return Ok(()) };
            let axes = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)];
            for t in [unit(angle), Vec2::new(axes[axis].0, axes[axis].1)] {
                let [lo, hi] = dot_range(l, t);
                let (mut least, mut most) = (f64::INFINITY, f64::NEG_INFINITY);
                for i in 0..=400 {
                    let f = i as f64 / 400.0;
                    for (a, b) in [(f, 0.0), (f, 1.0), (0.0, f), (1.0, f)] {
                        let v = in_box(l.d, a, b) - Point::new(0.0, 0.0);
                        let dot = v.dot(t) / v.length();
                        (least, most) = (least.min(dot), most.max(dot));
                    }
                }
                // The boundary's directions hold every direction of the box.
                let tight = hi <= most + 1e-3 && lo >= least - 1e-3;
                prop_assert!(tight, "{lo}, {hi} vs {least}, {most}");
            }
        }

        /// `arc_dot_range` holds every unit vector of its arc.
        #[test]
        fn arc_dot_range_holds_every_direction(
            start in 0.0..TAU, width in 0.0..3.1f64, angle in 0.0..TAU,
            at in proptest::collection::vec(fraction(), 12),
        ) {
            let (e0, e1) = (unit(start), unit(start + width));
            for t in [unit(angle), -e0, e1, unit(start + 0.5 * width + std::f64::consts::PI)] {
                let range = arc_dot_range(e0, e1, t);
                for &f in &at {
                    let u = unit(start + f * width);
                    prop_assert!(within(u.dot(t), range), "{} outside {:?}", u.dot(t), range);
                }
            }
        }

        /// A chord's ranges: the forward arc's where the legs run forward, the opposite
        /// arc's where they run back, both where either may.
        #[test]
        fn chord_ranges_hold_their_arcs(
            start in 0.0..TAU, width in 0.0..3.1f64, angle in 0.0..TAU, f in fraction(),
            both in any::<bool>(), reversed in any::<bool>(),
        ) {
            let c = Chord { ends: [unit(start), unit(start + width)], both, reversed };
            let (r0, r1) = LegBound::Arc(c).dot_ranges(unit(angle));
            let u = unit(start + f * width);
            let t = unit(angle);
            match (both, reversed) {
                (true, _) => {
                    prop_assert!(within(u.dot(t), r0));
                    prop_assert!(within(-u.dot(t), r1.expect("both arcs")));
                }
                (false, false) => prop_assert!(within(u.dot(t), r0)),
                (false, true) => prop_assert!(within(-u.dot(t), r0)),
            }
        }

        /// A stationary path through one point is never pruned: a reflection, or a
        /// refraction by Snell's law, inside the box of its segment or of a node around it.
        #[test]
        fn a_stationary_point_is_never_pruned(
            x in (-3.0..3.0f64, -3.0..3.0f64), alpha in -4.0..4.0f64, incidence in -1.5..1.5f64,
            lengths in (0.05..5.0f64, 0.05..5.0f64), w in (0.3..3.0f64, 0.3..3.0f64),
            reflect in any::<bool>(), reach in (0.0..3.0f64, 0.0..3.0f64),
            grow in proptest::array::uniform4(0.0..2.0f64),
            widen in proptest::array::uniform2(0.0..1.5f64),
        ) {
            let x = Point::new(x.0, x.1);
            let t = unit(alpha);
            let n = t.perp();
            let w1 = if reflect { w.0 } else { w.1 };
            let u0 = t * incidence.sin() - n * incidence.cos();
            let Some(u1) = outgoing(u0, t, w.0, w1, reflect) else { return Ok(()) };
            let (s, r) = (x - u0 * lengths.0, x + u1 * lengths.1);
            // The residual vanishes (the construction is right).
            prop_assert!(((u0 * w.0 - u1 * w1).dot(t)).abs() < 1e-12);
            let seg = segment_place(x, alpha, reach.0, reach.1);
            prop_assert!(!pruned(&[seg], s, r, &[w.0, w1]));
            let node = node_place(x, alpha, grow, widen);
            prop_assert!(!pruned(&[node], s, r, &[w.0, w1]));
        }

        /// The same for a path through two points on different interfaces, each a reflection
        /// or a refraction.
        #[test]
        fn a_stationary_path_of_two_points_is_never_pruned(
            x in (-3.0..3.0f64, -3.0..3.0f64), alpha in (-4.0..4.0f64, -4.0..4.0f64),
            incidence in -1.5..1.5f64, lengths in proptest::array::uniform3(0.05..5.0f64),
            w in proptest::array::uniform3(0.3..3.0f64), reflect in (any::<bool>(), any::<bool>()),
            grow in proptest::array::uniform4(0.0..1.0f64),
            widen in proptest::array::uniform2(0.0..1.0f64),
        ) {
            let x0 = Point::new(x.0, x.1);
            let (t0, t1) = (unit(alpha.0), unit(alpha.1));
            let w1 = if reflect.0 { w[0] } else { w[1] };
            let u0 = t0 * incidence.sin() - t0.perp() * incidence.cos();
            let Some(u1) = outgoing(u0, t0, w[0], w1, reflect.0) else { return Ok(()) };
            let x1 = x0 + u1 * lengths[1];
            // The second line crosses the leg (its normal faces the leg's start).
            let t1 = if u1.dot(t1.perp()) < 0.0 { t1 } else { -t1 };
            prop_assume!(u1.dot(t1.perp()).abs() > 1e-3);
            let w2 = if reflect.1 { w1 } else { w[2] };
            let Some(u2) = outgoing(u1, t1, w1, w2, reflect.1) else { return Ok(()) };
            let (s, r) = (x0 - u0 * lengths[0], x1 + u2 * lengths[2]);
            let a1 = t1.y.atan2(t1.x);
            let segs = [segment_place(x0, alpha.0, 0.5, 0.5), segment_place(x1, a1, 0.5, 0.5)];
            prop_assert!(!pruned(&segs, s, r, &[w[0], w1, w2]));
            let nodes = [node_place(x0, alpha.0, grow, widen), node_place(x1, a1, grow, widen)];
            prop_assert!(!pruned(&nodes, s, r, &[w[0], w1, w2]));
        }

        /// A corner reflector of any opening: two walls of one polyline meeting at the
        /// origin, a path reflecting off both; the places touch at the corner (a chord bounds
        /// the leg between them), and the path is not pruned.
        #[test]
        fn a_reflection_off_two_touching_walls_is_never_pruned(
            f in (0.0..TAU, 0.3..2.8f64), at in (0.05..2.0f64, 0.05..2.0f64),
            lengths in (0.05..5.0f64, 0.05..5.0f64), reach in (0.0..1.0f64, 0.0..1.0f64),
        ) {
            // The polyline runs in along −f1 to the corner, out along f2.
            let (f1, f2) = (unit(f.0), unit(f.0 + f.1));
            let (xa, xb) = (Point::new(0.0, 0.0) + f1 * at.0, Point::new(0.0, 0.0) + f2 * at.1);
            let d = (xb - xa) * (1.0 / (xb - xa).length());
            let (ta, tb) = (-f1, f2);
            let mirror = |v: Vec2, t: Vec2| t * (2.0 * v.dot(t)) - v;
            let (u0, u2) = (mirror(d, ta), mirror(d, tb));
            let (s, r) = (xa - u0 * lengths.0, xb + u2 * lengths.1);
            let (aa, ab) = (ta.y.atan2(ta.x), tb.y.atan2(tb.x));
            let ab = aa + (ab - aa + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
            let mut a = segment_place(xa, aa, reach.0, at.0);
            let mut b = segment_place(xb, ab, at.1, reach.1);
            (a.first, a.end, b.first, b.end, a.interface, b.interface) = (0, 1, 1, 2, 0, 0);
            prop_assert!(!pruned(&[a, b], s, r, &[1.0, 1.0, 1.0]));
        }
    }
}
