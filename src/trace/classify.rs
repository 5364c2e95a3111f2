//! The one classifier of a solved ray: its ends, vanished legs, vertices, sides and
//! obstruction, and the leg media found by region lookup. Every kernel and the general solve
//! call it; it takes only what it needs (the scene, the solve's state, the region lookup).
//!
//! A ray is `converged` when every interaction is strictly inside a segment, every leg lies
//! on the side its step demands (a reflection's two legs on one side of the interface, a
//! refraction's on opposite sides, a leg within [`SIDE_MARGIN`] rad of the interface on
//! neither) and no leg crosses an interface between its ends; `vertex` when it is stationary
//! only with a point held on a vertex; `no_path` when a point is held at an open end, two
//! interactions fall on one spot or a side is wrong; `obstructed` when only the crossing test
//! fails.

use crate::geom::{Aabb, Point, Segment, Vec2, orient, vertex_side};
use crate::leg::{AnyLeg, ArcFrame, Leg, LegMedium, LegModel};
use crate::problem::Pin;
use crate::regions::Regions;
use crate::scene::{Scene, SegmentRef, Step, StepKind};
use crate::solver::{NewtonWorkspace, Outcome, Solution};

use super::{RayRecord, Reason, Status};

/// A leg that crosses an interface strictly between its ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Crossing {
    /// The leg (0: the one leaving the source).
    pub leg: usize,
    /// The interface it crosses.
    pub interface: usize,
}

impl Crossing {
    /// The ray's record for this crossing.
    #[inline(always)]
    fn record(self, sol: &Solution) -> RayRecord {
        let reason = Reason::Crosses {
            leg: self.leg,
            interface: self.interface,
        };
        RayRecord::timed(Status::Obstructed, Some(reason), sol)
    }
}

/// What the classification of a scene's rays prepares once: per path and leg, the few scene
/// segments that can cross the leg (see [`leg_candidates`]).
#[derive(Debug)]
pub(crate) struct Classifier {
    /// Per path, per leg: every scene segment that can cross it, when there are few.
    leg_candidates: Vec<Vec<Option<Box<[u32]>>>>,
    /// Per path: whether no leg has a candidate (a path through single-segment interfaces
    /// with nothing between them): for a source and a receiver within `ends`, no leg can be
    /// obstructed.
    clear: Vec<bool>,
    /// The boxes of the scene's sources and receivers, for which the candidates of the legs
    /// from the source and to the receiver hold.
    ends: [Aabb; 2],
    /// In a scene with curved legs, per path: whether no segment but the legs' own meets the
    /// box of any leg's ends' interfaces (see [`arc_boxes_clear`]); empty otherwise.
    arc_boxes_clear: Vec<bool>,
    /// Whether [`Classifier::arcs_clear`] may decide obstruction (not with the general code
    /// alone, [`Kernels::GeneralOnly`](super::Kernels::GeneralOnly)).
    pub(super) arc_shortcut: bool,
}

impl Classifier {
    /// The classifier of `scene`'s paths.
    pub(crate) fn new(scene: &Scene) -> Classifier {
        let ends = [
            Aabb::around(scene.sources()),
            Aabb::around(scene.receivers()),
        ];
        let candidates: Vec<_> = scene
            .paths()
            .iter()
            .map(|p| leg_candidates(scene, &p.steps, ends))
            .collect();
        let arc_boxes_clear = if scene.curved() {
            let clear = |p: &crate::scene::Path| arc_boxes_clear(scene, &p.steps, ends);
            scene.paths().iter().map(clear).collect()
        } else {
            Vec::new()
        };
        Classifier {
            arc_boxes_clear,
            arc_shortcut: true,
            clear: candidates
                .iter()
                .map(|legs| legs.iter().all(|c| c.as_deref() == Some(&[])))
                .collect(),
            leg_candidates: candidates,
            ends,
        }
    }

    /// The boxes of the scene's sources and receivers that the candidates were found for.
    pub(crate) fn ends(&self) -> [Aabb; 2] {
        self.ends
    }

    /// The record of a ray of the step sequence `of` (a scene path's, or one that a search
    /// generated) from `source` to `receiver` after the solve `sol` left its state in `nw`:
    /// its points into `points`, then the end, vanished-leg, vertex, side and obstruction
    /// tests.
    #[expect(
        clippy::too_many_arguments,
        reason = "the parts of a ray, none of which the classifier owns"
    )]
    pub(crate) fn classify(
        &self,
        scene: &Scene,
        of: Sequence<'_>,
        source: Point,
        receiver: Point,
        sol: &Solution,
        nw: &NewtonWorkspace,
        points: &mut Vec<Point>,
    ) -> RayRecord {
        let steps = of.steps;
        let k = steps.len();
        points.clear();
        points.push(source);
        let on = steps.iter().zip(&nw.seg[..k]).zip(&nw.s[..k]);
        points.extend(
            on.map(|((step, &j), &s)| scene.interfaces()[step.interface].polyline.point_on(j, s)),
        );
        points.push(receiver);
        let no_path = |reason| RayRecord::untimed(Status::NoPath, reason, sol);
        match sol.outcome {
            Outcome::NotConverged => {
                return RayRecord::untimed(Status::NotConverged, Reason::IterationLimit, sol);
            }
            Outcome::LeftEnd(step) => return no_path(Reason::LeavesEnd { step }),
            Outcome::Converged | Outcome::Vertex => {}
        }
        // The first interaction next to a vanished leg between two interactions: leg `j`
        // (1 ≤ j < k) joins interactions `j − 1` and `j`.
        let interior = nw.eval.len.get(1..k).unwrap_or(&[]);
        if let Some(step) = interior.iter().position(|&l| l <= nw.eval.vanish) {
            return no_path(Reason::Coincident { step });
        }
        // An interaction on the source or the receiver (the leg between them vanished): the
        // path without it, which is no path of this sequence (it is listed once, as that one).
        let ends = &nw.eval.len[..=k];
        if k > 0 && ends[0] <= nw.eval.vanish {
            return no_path(Reason::AtEnd { step: 0 });
        }
        if k > 0 && ends[k] <= nw.eval.vanish {
            return no_path(Reason::AtEnd { step: k - 1 });
        }
        let curved = !of.curved.is_empty();
        let wrong = if curved {
            curved_wrong_side(scene, steps, nw, of.curved)
        } else {
            wrong_side(scene, steps, nw)
        };
        if let Some(step) = wrong {
            return no_path(Reason::WrongSide { step });
        }
        let crossing = match of.path {
            Some(path) if curved && self.arcs_clear(scene, path, steps, points, nw, of.curved) => {
                None
            }
            _ if curved => arc_obstruction(scene, steps, points, nw, of.curved),
            Some(path) => self.obstruction(scene, path, points, &nw.seg[..k]),
            None => self.obstruction_tested(scene, steps, None, points, &nw.seg[..k]),
        };
        if let Some(crossing) = crossing {
            return crossing.record(sol);
        }
        if let Some(step) = nw.pin.iter().position(|p| *p == Pin::Vertex) {
            return RayRecord::timed(Status::Vertex, Some(Reason::AtVertex { step }), sol);
        }
        RayRecord::timed(Status::Converged, None, sol)
    }

    /// [`classify`](Self::classify) for a converged solve whose points are all free and
    /// strictly inside their segments with no leg vanished (what the kernels give): the side
    /// test at each point, then the obstruction test. `sides` gives each step's kind and its
    /// segment's unit normal, `rel` the points relative to the source (source, interactions,
    /// receiver), `len` the legs' lengths, `vanish` the ray's vanishing threshold (see
    /// [`leg_sides`]), `pts` the points and `seg` their segments.
    #[expect(
        clippy::too_many_arguments,
        reason = "the parts of a ray held in registers by the kernels"
    )]
    #[inline(always)]
    pub(crate) fn free_points(
        &self,
        scene: &Scene,
        path: usize,
        sides: impl Iterator<Item = (StepKind, Vec2)>,
        rel: &[Vec2],
        len: &[f64],
        vanish: f64,
        pts: &[Point],
        seg: &[usize],
        sol: &Solution,
    ) -> RayRecord {
        for (i, (kind, n)) in sides.enumerate() {
            let (a, b) = leg_sides(n, vanish, &rel[i..i + 3], &len[i..i + 2]);
            if !sides_suit(kind, a, b) {
                return RayRecord::untimed(Status::NoPath, Reason::WrongSide { step: i }, sol);
            }
        }
        self.unobstructed(scene, path, pts, seg, sol)
    }

    /// [`free_points`](Self::free_points) for a ray whose sides are known to suit its steps:
    /// the obstruction test.
    #[inline(always)]
    pub(crate) fn unobstructed(
        &self,
        scene: &Scene,
        path: usize,
        pts: &[Point],
        seg: &[usize],
        sol: &Solution,
    ) -> RayRecord {
        match self.obstruction(scene, path, pts, seg) {
            Some(crossing) => crossing.record(sol),
            None => RayRecord::timed(Status::Converged, None, sol),
        }
    }

    /// The first leg that crosses an interface strictly between its ends. `pts` are the
    /// source, the interaction points and the receiver; `seg` the segments of the interaction
    /// points, which their own legs are not tested against (see [`Scene::first_crossing`]).
    #[inline(always)]
    pub(crate) fn obstruction(
        &self,
        scene: &Scene,
        path: usize,
        pts: &[Point],
        seg: &[usize],
    ) -> Option<Crossing> {
        // A clear path between points within the scene's ends: nothing to test (the common
        // case of a survey through layers, checked here without a call).
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        if self.clear[path] && self.ends[0].contains(a) && self.ends[1].contains(b) {
            return None;
        }
        let steps = &scene.paths()[path].steps;
        self.obstruction_tested(scene, steps, Some(&self.leg_candidates[path]), pts, seg)
    }

    /// [`obstruction`](Self::obstruction) leg by leg, for the legs of `steps` with their
    /// prepared candidate segments (`candidates`: per leg, of a scene path) or against every
    /// segment of the scene (`None`: a sequence without prepared candidates).
    fn obstruction_tested(
        &self,
        scene: &Scene,
        steps: &[Step],
        candidates: Option<&[Option<Box<[u32]>>]>,
        pts: &[Point],
        seg: &[usize],
    ) -> Option<Crossing> {
        let k = seg.len();
        let (pts, steps) = (&pts[..k + 2], &steps[..k]);
        // The end legs' candidates hold for a source and a receiver within the scene's.
        let usable = [
            self.ends[0].contains(pts[0]),
            self.ends[1].contains(pts[k + 1]),
        ];
        let mut own_a = SegmentRef::NONE;
        for leg in 0..=k {
            let (a, b) = (pts[leg], pts[leg + 1]);
            let own_b = own_segment(steps, seg, leg);
            if a != b {
                let own = [own_a, own_b];
                let listed = candidates.and_then(|c| c[leg].as_deref());
                let hit = match listed {
                    Some(c) if (leg > 0 || usable[0]) && (leg < k || usable[1]) => {
                        scene.first_crossing_among(a, b, END_MARGIN, c, own)
                    }
                    _ => scene.first_crossing(a, b, END_MARGIN, own),
                };
                if let Some(r) = hit {
                    return Some(Crossing {
                        leg,
                        interface: r.interface as usize,
                    });
                }
            }
            own_a = own_b;
        }
        None
    }
}

impl Classifier {
    /// Whether no leg of the ray of path `path` through `points` (of the legs' models `curved`,
    /// the solve's state in `nw`) can cross a segment, proved without a query: the path's
    /// legs' boxes are clear ([`arc_boxes_clear`]), the ends lie in the scene's sources' and
    /// receivers' boxes, and every leg runs monotonically in `x`, in `y` and across the
    /// interfaces it ends on (its directions at its two ends on one side, by at least
    /// [`MONOTONE`], of each of those axes: an arc turns by less than half a turn, its circle's
    /// centre lying where the speed would be zero, so a direction component of one sign at
    /// both ends keeps that sign all along). Such a leg lies in the box of its ends, inside
    /// the clear box of its interfaces, and meets the lines of its own interfaces at its ends
    /// only. `false` decides nothing (the exact test, [`arc_obstruction`], follows).
    fn arcs_clear(
        &self,
        scene: &Scene,
        path: usize,
        steps: &[Step],
        points: &[Point],
        nw: &NewtonWorkspace,
        curved: &[LegMedium],
    ) -> bool {
        let k = steps.len();
        if !(self.arc_shortcut
            && self.arc_boxes_clear.get(path) == Some(&true)
            && self.ends[0].contains(points[0])
            && self.ends[1].contains(points[k + 1]))
        {
            return false;
        }
        // The solve's last legs (of these points: see `solved_legs`), by reference.
        let legs = &nw.eval.legs;
        if legs.len() != k + 1 || curved.len() != k + 1 {
            return false;
        }
        let normal = |i: usize| {
            scene.interfaces()[steps[i].interface]
                .polyline
                .normal(nw.seg[i])
        };
        let one_way = |a: Vec2, b: Vec2, n: Vec2| {
            let (x, y) = (a.dot(n), b.dot(n));
            (x >= MONOTONE && y >= MONOTONE) || (x <= -MONOTONE && y <= -MONOTONE)
        };
        legs.iter().enumerate().all(|(j, leg)| {
            let (a, b) = (leg.direction_at_start(), leg.direction_at_end());
            one_way(a, b, Vec2::new(1.0, 0.0))
                && one_way(a, b, Vec2::new(0.0, 1.0))
                && (j == 0 || one_way(a, b, normal(j - 1)))
                && (j == k || one_way(a, b, normal(j)))
        })
    }
}

impl Classifier {
    /// [`classify`](Self::classify) for a converged ray of scene path `path` (`steps`) whose
    /// points are all free with no leg vanished and whose solve kept its legs (`Eval::legs`,
    /// of the models `curved`: the graded stack kernel's confirmed start), the points already
    /// in `points` (source, interactions, receiver) and the interfaces' unit normals at them
    /// `normal(i)` (the polylines' [`normal`](crate::polyline::Polyline::normal) there, bit
    /// for bit): the same tests on the same numbers, each leg's directions read once for the
    /// side test ([`curved_wrong_side`]) and the proof that the arcs are clear
    /// ([`Classifier::arcs_clear`]); the exact obstruction test ([`arc_obstruction`]) where
    /// that proof does not hold. Anything else (a leg not kept) takes [`classify`](Self::classify).
    #[expect(
        clippy::too_many_arguments,
        reason = "the parts of a ray, none of which the classifier owns"
    )]
    pub(crate) fn graded_free_points(
        &self,
        scene: &Scene,
        path: usize,
        normal: impl Fn(usize) -> Vec2,
        source: Point,
        receiver: Point,
        sol: &Solution,
        nw: &NewtonWorkspace,
        curved: &[LegMedium],
        points: &mut Vec<Point>,
    ) -> RayRecord {
        let steps = &scene.paths()[path].steps[..];
        let (k, e) = (steps.len(), &nw.eval);
        let legs = &e.legs[..];
        if legs.len() != k + 1
            || curved.len() != k + 1
            || points.len() != k + 2
            || sol.outcome != Outcome::Converged
            || nw.pin[..k].iter().any(|&p| p != Pin::Free)
        {
            let of = Sequence {
                steps,
                path: Some(path),
                curved,
            };
            return self.classify(scene, of, source, receiver, sol, nw, points);
        }
        let no_path = |reason| RayRecord::untimed(Status::NoPath, reason, sol);
        // The vanished-leg tests of `classify` (none holds after a confirmed start).
        if let Some(step) = e.len[1..k].iter().position(|&l| l <= e.vanish) {
            return no_path(Reason::Coincident { step });
        }
        if e.len[0] <= e.vanish {
            return no_path(Reason::AtEnd { step: 0 });
        }
        if e.len[k] <= e.vanish {
            return no_path(Reason::AtEnd { step: k - 1 });
        }
        let mut clear = self.arc_shortcut
            && self.arc_boxes_clear.get(path) == Some(&true)
            && self.ends[0].contains(points[0])
            && self.ends[1].contains(points[k + 1]);
        let one_way = |a: Vec2, b: Vec2, n: Vec2| {
            let (x, y) = (a.dot(n), b.dot(n));
            (x >= MONOTONE && y >= MONOTONE) || (x <= -MONOTONE && y <= -MONOTONE)
        };
        let side = |x: f64| if x.abs() <= SIDE_MARGIN { 0.0 } else { x };
        // The previous leg's length and direction at its end.
        let (mut before_len, mut before_end) = (0.0, Vec2::default());
        for (j, leg) in legs.iter().enumerate() {
            let (start, end, len) = (leg.direction_at_start(), leg.direction_at_end(), leg.len());
            if j > 0 && before_len > e.vanish && len > e.vanish {
                let i = j - 1;
                let n = normal(i);
                let (a, b) = (side(-n.dot(before_end)), side(n.dot(start)));
                if !sides_suit(steps[i].kind, a, b) {
                    return no_path(Reason::WrongSide { step: i });
                }
            }
            clear = clear
                && one_way(start, end, Vec2::new(1.0, 0.0))
                && one_way(start, end, Vec2::new(0.0, 1.0))
                && (j == 0 || one_way(start, end, normal(j - 1)))
                && (j == k || one_way(start, end, normal(j)));
            (before_len, before_end) = (len, end);
        }
        let crossing = if clear {
            None
        } else {
            arc_obstruction(scene, steps, points, nw, curved)
        };
        match crossing {
            Some(crossing) => crossing.record(sol),
            None => RayRecord::timed(Status::Converged, None, sol),
        }
    }
}

/// The least component of a leg's unit directions at its ends along an axis, in either sense,
/// for [`Classifier::arcs_clear`] to take the leg as running one way along it.
const MONOTONE: f64 = 1e-6;

/// Whether, for every leg of a path of `steps` through interfaces of one segment each, no
/// scene segment but the leg's own (its ends' interfaces') has a box meeting the box of the
/// leg's ends' sides (its interfaces' segments; the box `ends[0]` of the sources for the first
/// leg, `ends[1]` of the receivers for the last), grown by round-off: what
/// [`Classifier::arcs_clear`] needs of the scene.
fn arc_boxes_clear(scene: &Scene, steps: &[Step], ends: [Aabb; 2]) -> bool {
    let k = steps.len();
    let line = |i: usize| &scene.interfaces()[steps[i].interface].polyline;
    if k == 0 || (0..k).any(|i| line(i).num_segments() != 1) {
        return false;
    }
    (0..=k).all(|leg| {
        let side = |i: Option<usize>, b: Aabb| match i {
            Some(i) => line(i).bbox(),
            None => b,
        };
        let (before, after) = (leg.checked_sub(1), (leg < k).then_some(leg));
        let (a, b) = (side(before, ends[0]), side(after, ends[1]));
        if a.min.x > a.max.x || b.min.x > b.max.x {
            return false;
        }
        let bbox = a.union(b);
        let grown = bbox.grown(bbox.round_off_pad(1e-9));
        let own = [before, after].map(|i| i.map(|i| steps[i].interface as u32));
        scene.segments_in(grown, 64).is_some_and(|found| {
            found
                .iter()
                .all(|&i| own.contains(&Some(scene.segments()[i as usize].interface)))
        })
    })
}

/// A step sequence to classify: a scene path's (whose legs' candidate segments the classifier
/// prepared) or any other.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sequence<'a> {
    /// The steps.
    pub steps: &'a [Step],
    /// The scene path they are, if they are one.
    pub path: Option<usize>,
    /// The legs' models relative to the source where legs may be curved (empty: every leg
    /// straight; see `ProblemRef::curved`).
    pub curved: &'a [LegMedium<'a>],
}

impl<'a> Sequence<'a> {
    /// Path `path` of `scene`.
    pub(crate) fn of(scene: &'a Scene, path: usize) -> Sequence<'a> {
        Sequence {
            steps: &scene.paths()[path].steps,
            path: Some(path),
            curved: &[],
        }
    }
}

/// Leg media from the regions at the points in `nw` into `media`: the source's region
/// (`source_medium`) for leg 0; a reflection keeps the medium, a refraction takes the one
/// across the interface.
pub(crate) fn lookup_media(
    regions: Option<&Regions>,
    scene: &Scene,
    source: Point,
    source_medium: Option<usize>,
    steps: &[Step],
    nw: &NewtonWorkspace,
    media: &mut Vec<usize>,
) -> Result<(), Reason> {
    let regions = regions.ok_or(Reason::NoMedium { leg: 0 })?;
    media.clear();
    let mut m = source_medium.ok_or(Reason::NoMedium { leg: 0 })?;
    media.push(m);
    let mut prev = source;
    for (i, step) in steps.iter().enumerate() {
        let line = &scene.interfaces()[step.interface].polyline;
        let here = line.point_on(nw.seg[i], nw.s[i]);
        if step.kind == StepKind::Refract {
            // The side the leg arrives from: its start's, or, for an arc (whose start may lie
            // on the interface where it turns beneath it), a point just back along its
            // arriving direction.
            let from = if scene.curved() {
                let leg = scene.media()[m]
                    .leg_model(source)
                    .leg(prev - source, here - source);
                here - leg.direction_at_end() * (1e-3 * leg.len())
            } else {
                prev
            };
            m = regions
                .medium_across(step.interface, nw.seg[i], nw.s[i], from)
                .ok_or(Reason::NoMedium { leg: i + 1 })?;
        }
        media.push(m);
        prev = here;
    }
    Ok(())
}

/// [`wrong_side`] for curved legs: each leg's side from its direction at the interaction
/// (an arc's chord may run along the interface where the arc turns below it), within
/// [`SIDE_MARGIN`] rad on neither side. A step next to a vanished leg is left to the tests of
/// ends and coincident points.
fn curved_wrong_side(
    scene: &Scene,
    steps: &[Step],
    nw: &NewtonWorkspace,
    curved: &[LegMedium],
) -> Option<usize> {
    let (k, e) = (steps.len(), &nw.eval);
    let leg = solved_ends(nw, curved, k);
    (0..k).find(|&i| {
        let (before, after) = (leg(i), leg(i + 1));
        if before.len <= e.vanish || after.len <= e.vanish {
            return false;
        }
        let n = scene.interfaces()[steps[i].interface]
            .polyline
            .normal(nw.seg[i]);
        let side = |x: f64| if x.abs() <= SIDE_MARGIN { 0.0 } else { x };
        let a = side(-n.dot(before.end));
        let b = side(n.dot(after.start));
        !sides_suit(steps[i].kind, a, b)
    })
}

/// Leg `j` of the `k + 1` legs through the points in `nw`, of the models `curved`: the
/// solve's last evaluation's (`Eval::legs`, of these points and models: the solve evaluated
/// them last), evaluated again only where it has not as many.
fn solved_legs<'a>(
    nw: &'a NewtonWorkspace,
    curved: &'a [LegMedium],
    k: usize,
) -> impl Fn(usize) -> AnyLeg + 'a {
    let e = &nw.eval;
    let stored = (e.legs.len() == k + 1).then_some(&e.legs[..]);
    move |j| match stored {
        Some(legs) => legs[j],
        None => curved[j].leg(e.rel[j], e.rel[j + 1]),
    }
}

/// What the side tests read of a leg: its chord's length and its unit directions at its
/// start and at its end.
#[derive(Clone, Copy, Debug)]
struct LegEnds {
    len: f64,
    start: Vec2,
    end: Vec2,
}

/// [`solved_legs`]'s [`LegEnds`], read in place where the solve kept its legs.
fn solved_ends<'a>(
    nw: &'a NewtonWorkspace,
    curved: &'a [LegMedium],
    k: usize,
) -> impl Fn(usize) -> LegEnds + 'a {
    let e = &nw.eval;
    let stored = (e.legs.len() == k + 1).then_some(&e.legs[..]);
    let ends = |l: &AnyLeg| LegEnds {
        len: l.len(),
        start: l.direction_at_start(),
        end: l.direction_at_end(),
    };
    move |j| match stored {
        Some(legs) => ends(&legs[j]),
        None => ends(&curved[j].leg(e.rel[j], e.rel[j + 1])),
    }
}

/// The segment leg `leg` ends on (its step's), or none for the last leg.
#[inline]
fn own_segment(steps: &[Step], seg: &[usize], leg: usize) -> SegmentRef {
    if leg < seg.len() {
        SegmentRef {
            interface: steps[leg].interface as u32,
            segment: seg[leg] as u32,
        }
    } else {
        SegmentRef::NONE
    }
}

/// The first leg whose arc crosses an interface strictly between its ends, for legs that may
/// be curved (`curved`, positions relative to the source `pts[0]`). A straight leg is tested
/// as the classifier tests it; an arc exactly, as a circle against each segment near it
/// ([`Scene::first_arc_crossing`]: the crossing nearest its start, at a fraction of its chord
/// beyond [`END_MARGIN`] from either end). The segments the leg's ends lie on count where the
/// arc meets them again (an arc can dip below its own interface).
fn arc_obstruction(
    scene: &Scene,
    steps: &[Step],
    pts: &[Point],
    nw: &NewtonWorkspace,
    curved: &[LegMedium],
) -> Option<Crossing> {
    let seg = &nw.seg[..steps.len()];
    let k = seg.len();
    let solved = solved_legs(nw, curved, k);
    let mut own_a = SegmentRef::NONE;
    for leg in 0..=k {
        let (a, b) = (pts[leg], pts[leg + 1]);
        let own_b = own_segment(steps, seg, leg);
        if a != b {
            let own = [own_a, own_b];
            let frame = solved(leg)
                .arc()
                .and_then(|arc| ArcFrame::new(a, b, arc.curvature()));
            let hit = match frame {
                Some(frame) => scene.first_arc_crossing(&frame, END_MARGIN, own),
                None => scene.first_crossing(a, b, END_MARGIN, own),
            };
            if let Some(r) = hit {
                return Some(Crossing {
                    leg,
                    interface: r.interface as usize,
                });
            }
        }
        own_a = own_b;
    }
    None
}

/// The first step whose legs are not on the sides it demands, for points in any state (held
/// on a vertex: the sum of the two segments' normals; next to a vanished leg: the other leg
/// must lie on a side).
fn wrong_side(scene: &Scene, steps: &[Step], nw: &NewtonWorkspace) -> Option<usize> {
    (0..steps.len()).find(|&i| {
        let sides = step_sides(scene, steps, nw, i);
        match sides.gone {
            // A vanished leg (an end point on the interface there) lies on both sides: the
            // other leg must still lie on one.
            [true, gone_b] => gone_b || sides.side[1] == 0.0,
            [false, true] => sides.side[0] == 0.0,
            [false, false] => !sides_suit(steps[i].kind, sides.side[0], sides.side[1]),
        }
    })
}

/// Whether the side test of step `step` ([`wrong_side`]) rests on a leg that [`leg_sides`]
/// puts on neither side by its threshold (not a proof), the points in `nw`, `points` the
/// path's points as classified (source, interactions, receiver). A leg whose far end lies
/// exactly on the line of the step's segment (the source, the receiver or a held vertex
/// there, by the exact orientation test; a free point on a segment of that line) runs along
/// it exactly: that verdict is exact.
pub(crate) fn side_undecided(
    scene: &Scene,
    steps: &[Step],
    nw: &NewtonWorkspace,
    points: &[Point],
    step: usize,
) -> bool {
    let sides = step_sides(scene, steps, nw, step);
    let line_of = |i: usize| &scene.interfaces()[steps[i].interface].polyline;
    let (line, j) = (line_of(step), nw.seg[step]);
    // The step's segment, and at a held vertex the one before it too.
    let before = if j > 0 {
        j - 1
    } else {
        line.num_segments() - 1
    };
    let held = nw.pin[step] == Pin::Vertex;
    let lines = [line.segment(j), line.segment(if held { before } else { j })];
    let on_line = |x: Point| lines.iter().any(|g| orient(g.start, g.end, x) == 0.0);
    // The far end of leg `l` (0: from the point before, 1: to the point after) exactly on the
    // step's line.
    let exact = |l: usize| {
        let far = if l == 0 {
            step.checked_sub(1)
        } else {
            Some(step + 1).filter(|&i| i < steps.len())
        };
        match far {
            None => on_line(if l == 0 {
                points[0]
            } else {
                points[steps.len() + 1]
            }),
            Some(i) if nw.pin[i] == Pin::Vertex => on_line(line_of(i).vertices()[nw.seg[i]]),
            Some(i) => {
                let g = line_of(i).segment(nw.seg[i]);
                lines.iter().any(|l| {
                    orient(l.start, l.end, g.start) == 0.0 && orient(l.start, l.end, g.end) == 0.0
                })
            }
        }
    };
    (0..2).any(|l| !sides.gone[l] && sides.side[l] == 0.0 && !exact(l))
}

/// The legs of one interaction against its interface: see [`step_sides`].
struct StepSides {
    /// The source-side and receiver-side legs' sides ([`leg_sides`]; at a held vertex, see
    /// [`vertex_side`]).
    side: [f64; 2],
    /// Whether each has vanished.
    gone: [bool; 2],
}

/// The sides of the two legs of step `i` at the points in `nw`.
fn step_sides(scene: &Scene, steps: &[Step], nw: &NewtonWorkspace, i: usize) -> StepSides {
    let (k, e) = (steps.len(), &nw.eval);
    let (rel, len) = (&e.rel[..k + 2], &e.len[..k + 1]);
    let line = &scene.interfaces()[steps[i].interface].polyline;
    let j = nw.seg[i];
    let (near, legs) = (&rel[i..i + 3], &len[i..i + 2]);
    let (a, b) = leg_sides(line.normal(j), e.vanish, near, legs);
    // At a vertex, each leg's side of the polyline there (see `vertex_side`).
    let (a, b) = if nw.pin[i] == Pin::Vertex {
        let before = if j > 0 {
            j - 1
        } else {
            line.num_segments() - 1
        };
        let (a0, b0) = leg_sides(line.normal(before), e.vanish, near, legs);
        let left = line.tangent(before).cross(line.tangent(j)) > 0.0;
        (vertex_side(left, a0, a), vertex_side(left, b0, b))
    } else {
        (a, b)
    };
    let tiny = e.vanish;
    StepSides {
        side: [a, b],
        gone: [len[i] <= tiny, len[i + 1] <= tiny],
    }
}

/// A leg between two interactions has its end points on their interfaces, so it lies in the
/// convex hull of the two interfaces; a leg from the source lies in the hull of the first
/// interface and the box `ends[0]` (when the source is in it), one to the receiver in that of
/// the last interface and `ends[1]`: the scene segments that meet that hull (widened by
/// round-off) are all it can cross. Where they are few (a leg between two layers of a stack,
/// flat or dipping: those two interfaces; the legs of a refraction at a lone surface), the
/// obstruction test checks just them instead of querying the scene's BVH, whose boxes of long
/// slanted segments all overlap. The segment of an end's interface when it has only that one
/// is left out: the leg ends on it, so it is the leg's own (see [`Scene::first_crossing`]).
/// Per leg `0..=k`.
fn leg_candidates(
    scene: &Scene,
    steps: &[crate::scene::Step],
    ends: [Aabb; 2],
) -> Vec<Option<Box<[u32]>>> {
    /// More candidates than this: the BVH query is as quick.
    const MAX: usize = 8;
    /// Segments in the hull's box beyond which the hull test is not worth making.
    const BOX_LIMIT: usize = 4096;
    let k = steps.len();
    let corners = |b: Aabb| {
        [
            b.min,
            Point::new(b.max.x, b.min.y),
            b.max,
            Point::new(b.min.x, b.max.y),
        ]
    };
    (0..=k)
        .map(|leg| {
            // What each end of the leg lies on: an interaction's interface, or the box of the
            // scene's sources (receivers); `None` when there are none.
            enum Side<'a> {
                Line(&'a crate::polyline::Polyline),
                Box(Aabb),
            }
            let side = |i: Option<usize>, b: Aabb| match i {
                Some(i) => Some(Side::Line(&scene.interfaces()[steps[i].interface].polyline)),
                None => (b.min.x <= b.max.x).then_some(Side::Box(b)),
            };
            let sides = [
                side(leg.checked_sub(1), ends[0])?,
                side((leg < k).then_some(leg), ends[1])?,
            ];
            let bbox = sides
                .iter()
                .map(|e| match e {
                    Side::Line(line) => line.bbox(),
                    Side::Box(b) => *b,
                })
                .fold(Aabb::EMPTY, Aabb::union);
            let pad = bbox.round_off_pad(1e-9);
            let grown = bbox.grown(pad);
            // (A long interface fills the box with its own segments: no copy of its vertices.)
            let in_box = scene.segments_in(grown, BOX_LIMIT)?;
            let pts = sides
                .iter()
                .flat_map(|e| match e {
                    Side::Line(line) => line.vertices().to_vec(),
                    Side::Box(b) => corners(*b).to_vec(),
                })
                .collect();
            let hull = convex_hull(pts);
            // The interfaces of the leg's ends that are one segment.
            let lone = |i: Option<usize>| {
                i.map(|i| steps[i].interface)
                    .filter(|&f| scene.interfaces()[f].polyline.num_segments() == 1)
            };
            let own = [lone(leg.checked_sub(1)), lone((leg < k).then_some(leg))];
            let found: Vec<u32> = in_box
                .into_iter()
                .filter(|&i| {
                    let r = scene.segments()[i as usize];
                    let Segment { start: p, end: q } = scene.segment_points(r);
                    !own.contains(&Some(r.interface as usize)) && meets_convex(p, q, &hull, pad)
                })
                .collect();
            (found.len() <= MAX).then(|| found.into_boxed_slice())
        })
        .collect()
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain; collinear points
/// dropped; fewer than three points as they are, sorted).
fn convex_hull(mut points: Vec<Point>) -> Vec<Point> {
    points.sort_by(|p, q| p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    // Appends `p` to the chain that starts at `floor`, dropping the points it turns right at.
    let push = |hull: &mut Vec<Point>, floor: usize, p: Point| {
        while hull.len() >= floor + 2
            && crate::geom::orient(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
        {
            hull.pop();
        }
        hull.push(p);
    };
    let mut hull = Vec::with_capacity(2 * points.len());
    for &p in &points {
        push(&mut hull, 0, p);
    }
    hull.pop();
    let floor = hull.len();
    for &p in points.iter().rev() {
        push(&mut hull, floor, p);
    }
    hull.pop();
    hull
}

/// Whether segment `p–q` meets the convex polygon `hull` (counter-clockwise, or up to two
/// points: a segment or a point) grown by `pad`: no separating axis among the polygon's edge
/// normals and the segment's normal.
fn meets_convex(p: Point, q: Point, hull: &[Point], pad: f64) -> bool {
    let separated = |n: Vec2| {
        let len = n.length();
        if len.is_nan() || len <= 0.0 {
            return false;
        }
        let proj = |x: Point| x.x * n.x + x.y * n.y;
        let (s0, s1) = (proj(p).min(proj(q)), proj(p).max(proj(q)));
        let (h0, h1) = hull
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &h| {
                (lo.min(proj(h)), hi.max(proj(h)))
            });
        s1 < h0 - pad * len || s0 > h1 + pad * len
    };
    let n = hull.len();
    let edges = (0..n).map(|i| hull[(i + 1) % n] - hull[i]);
    let mut axes: Vec<Vec2> = edges.map(|e| e.perp()).collect();
    axes.push((q - p).perp());
    // Axis-aligned axes too: a degenerate hull (a segment) needs its own extent checked.
    axes.push(Vec2::new(1.0, 0.0));
    axes.push(Vec2::new(0.0, 1.0));
    !axes.into_iter().any(separated)
}

/// A leg whose sine with the interface is below this runs along it, on neither side (or
/// nearer it than the vanishing threshold, whichever is less: see [`leg_sides`]).
pub(crate) const SIDE_MARGIN: f64 = 1e-10;

/// Where the legs of an interaction lie against the unit normal `n` of its interface there,
/// from the points before, at and after it (`rel`, relative to the source) and the two legs'
/// lengths (`len`): `(a, b)`, the source-side and receiver-side legs' components along `n`,
/// zero for a leg that runs along the interface, on neither side: one within [`SIDE_MARGIN`]
/// rad of it and nearer its line than `vanish` (the ray's vanishing threshold,
/// [`Eval::vanish`](crate::problem::Eval): 1e-12 of the path's length plus the round-off of
/// its coordinates, what the solve resolves). A leg that grazes its interface at a height
/// above that, however small its angle, lies on its side (the grazing reflection of a source
/// 1e-10 above a mirror). A zero component is a threshold's verdict, not a proof
/// ([`side_undecided`]).
#[inline(always)]
pub(crate) fn leg_sides(n: Vec2, vanish: f64, rel: &[Vec2], len: &[f64]) -> (f64, f64) {
    let a = n.dot(rel[0] - rel[1]);
    let b = n.dot(rel[2] - rel[1]);
    let (la, lb) = (len[0], len[1]);
    let a = if a.abs() <= (SIDE_MARGIN * la).min(vanish) {
        0.0
    } else {
        a
    };
    let b = if b.abs() <= (SIDE_MARGIN * lb).min(vanish) {
        0.0
    } else {
        b
    };
    (a, b)
}

/// Whether legs on sides `a` and `b` ([`leg_sides`]) are what `kind` demands: one side for a
/// reflection, opposite sides for a refraction.
#[inline(always)]
pub(crate) fn sides_suit(kind: StepKind, a: f64, b: f64) -> bool {
    match kind {
        StepKind::Reflect => (a > 0.0 && b > 0.0) || (a < 0.0 && b < 0.0),
        StepKind::Refract => (a > 0.0 && b < 0.0) || (a < 0.0 && b > 0.0),
        // A diffraction's legs leave its vertex into any direction of the wedge's outside.
        StepKind::Diffract { .. } => true,
    }
}

/// Crossings closer than this fraction of a leg to its ends are the leg's own end points.
pub(crate) const END_MARGIN: f64 = 1e-10;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::SplitMix64;
    use crate::trace::{Tracer, Workspace};

    /// Between two wavy interfaces with a third reaching in between them, the candidate
    /// segments of a leg find a crossing exactly when the scene's BVH query does.
    #[test]
    fn leg_candidates_find_every_crossing() {
        let doc = r#"{
            "media": { "m": { "speed": 1.0 } },
            "interfaces": {
                "a": { "points": [[0, 0], [1.3, 0.3], [2.6, -0.2], [4, 0.2]] },
                "b": { "points": [[0, 2], [1.3, 1.6], [2.6, 2.3], [4, 1.9]] },
                "c": { "points": [[1.5, 1.0], [2.5, 1.2]] },
                "far": { "points": [[10, 10], [11, 10]] }
            },
            "sources": [[0, -1]], "receivers": [[0, 3]],
            "paths": [{ "steps": [{ "refract": "a" }, { "refract": "b" }],
                        "media": ["m", "m", "m"] }]
        }"#;
        let scene = Scene::from_json(doc).unwrap();
        let steps = &scene.paths()[0].steps;
        let cands = leg_candidates(&scene, steps, [Aabb::EMPTY; 2]);
        let c = cands[1].as_deref().expect("few candidates");
        // a, b and c, not the far one.
        assert_eq!(c.len(), 3 + 3 + 1);
        let (a, b) = (
            &scene.interfaces()[steps[0].interface].polyline,
            &scene.interfaces()[steps[1].interface].polyline,
        );
        let mut rng = SplitMix64(3);
        let (mut hits, mut misses) = (0, 0);
        let own = |step: usize, line: &crate::polyline::Polyline, s: f64| SegmentRef {
            interface: steps[step].interface as u32,
            segment: line.segment_at(s) as u32,
        };
        for _ in 0..20_000 {
            let (sa, sb) = (rng.next_f64() * a.length(), rng.next_f64() * b.length());
            let (p, q) = (a.point_at(sa), b.point_at(sb));
            // Without and with the leg's own segments left out: the same answer either way.
            for own in [[SegmentRef::NONE; 2], [own(0, a, sa), own(1, b, sb)]] {
                let bvh = scene.first_crossing(p, q, END_MARGIN, own);
                let among = scene.first_crossing_among(p, q, END_MARGIN, c, own);
                assert_eq!(bvh.is_some(), among.is_some(), "leg {p:?} → {q:?}");
                assert!(
                    bvh.is_none_or(|r| !own.contains(&r)),
                    "{bvh:?} is the leg's own"
                );
                if own[0] != SegmentRef::NONE {
                    if bvh.is_some() {
                        hits += 1
                    } else {
                        misses += 1
                    }
                }
            }
        }
        assert!(hits > 1000 && misses > 1000, "{hits} hits, {misses} misses");
    }

    /// Legs between the layers of a stack, flat or dipping (where the boxes of all layers
    /// overlap), can cross nothing but the two layers they join: one segment each, the legs'
    /// own, so no candidates at all (the path is clear); a third layer or a bend in one
    /// brings candidates back.
    #[test]
    fn stack_legs_have_no_candidates() {
        for spec in [
            crate::demo::layer_stack(20, 3),
            crate::demo::dipping_stack(20, 3),
        ] {
            let scene = Scene::from_spec(&spec).unwrap();
            let classifier = Classifier::new(&scene);
            let cands = &classifier.leg_candidates[0];
            assert_eq!(cands.len(), 21);
            assert!(cands.iter().all(|c| c.as_deref() == Some(&[])), "{cands:?}");
            assert!(classifier.clear[0]);
            // Bend the interface of step 5: the legs that end on it (5 and 6) can cross its
            // other segment.
            let mut bent = spec.clone();
            let crate::scene::StepSpec::Refract(name) = &spec.paths[0].steps[5] else {
                panic!("a refraction");
            };
            let points = &mut bent.interfaces.get_mut(name).unwrap().points;
            let (a, b) = (points[0], points[1]);
            points.insert(1, [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]) + 1e-3]);
            let scene = Scene::from_spec(&bent).unwrap();
            let classifier = Classifier::new(&scene);
            assert!(!classifier.clear[0]);
            for (leg, c) in classifier.leg_candidates[0].iter().enumerate() {
                let c = c.as_deref().expect("few candidates");
                let expected = if leg == 5 || leg == 6 { 2 } else { 0 };
                assert_eq!(c.len(), expected, "leg {leg}: {c:?}");
                for &i in c {
                    let r = scene.segments()[i as usize];
                    assert_eq!(r.interface as usize, scene.paths()[0].steps[5].interface);
                }
            }
        }
    }

    /// The candidate lists of the legs from the source and to the receiver hold for points
    /// within the scene's sources and receivers: a ray between other points is tested against
    /// every interface.
    #[test]
    fn points_beyond_the_scene_ends_are_tested_against_every_interface() {
        let doc = r#"{
            "media": { "air": { "speed": 1.0 }, "water": { "speed": 0.75 } },
            "interfaces": {
                "surface": { "points": [[-10, 0], [2, 0]] },
                "wall": { "points": [[-3, 0.8], [-3, 3]] },
                "deep": { "points": [[-3, -0.8], [-3, -3]] }
            },
            "sources": [[0, 1]], "receivers": [[0.5, -0.5]],
            "paths": [{ "steps": [{ "refract": "surface" }], "media": ["air", "water"] }]
        }"#;
        let scene = Scene::from_json(doc).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let classifier = tracer.classifier();
        assert!(classifier.clear[0], "{:?}", classifier.leg_candidates);
        let index = |name: &str| scene.interfaces().iter().position(|f| f.name == name);
        let (wall, deep) = (index("wall").unwrap(), index("deep").unwrap());
        let mut ws = Workspace::new();
        let (near, far) = (Point::new(-0.5, 1.0), Point::new(-5.0, 3.0));
        let receiver = scene.receivers()[0];
        assert_eq!(
            tracer.solve(near, receiver, 0, &mut ws).status,
            Status::Converged
        );
        let beyond = tracer.solve(far, receiver, 0, &mut ws);
        assert_eq!(beyond.status, Status::Obstructed, "{beyond:?}");
        assert_eq!(
            beyond.reason,
            Some(Reason::Crosses {
                leg: 0,
                interface: wall
            })
        );
        // And from the receiver's side.
        let beyond = tracer.solve(Point::new(0.5, 1.0), Point::new(-5.0, -3.0), 0, &mut ws);
        assert_eq!(
            beyond.reason,
            Some(Reason::Crosses {
                leg: 1,
                interface: deep
            })
        );
    }

    /// The hull test against brute force: a segment meets the hull exactly when it crosses
    /// one of its edges or has an end inside it.
    #[test]
    fn convex_hull_and_segment_test() {
        let mut rng = SplitMix64(9);
        let mut pt = |s: f64| Point::new(rng.next_f64() * s, rng.next_f64() * s);
        for _ in 0..200 {
            let cloud: Vec<Point> = (0..7).map(|_| pt(10.0)).collect();
            let hull = convex_hull(cloud.clone());
            let n = hull.len();
            let inside = |p: Point| {
                (0..n).all(|i| crate::geom::orient(hull[i], hull[(i + 1) % n], p) >= 0.0)
            };
            assert!(
                cloud.iter().all(|&p| inside(p)),
                "hull {hull:?} of {cloud:?}"
            );
            for _ in 0..50 {
                let (p, q) = (pt(14.0), pt(14.0));
                let crosses = (0..n).any(|i| {
                    crate::polyline::segment_intersection(p, q, hull[i], hull[(i + 1) % n])
                        .is_some()
                });
                let expected = crosses || inside(p) || inside(q);
                assert_eq!(
                    meets_convex(p, q, &hull, 0.0),
                    expected,
                    "{p:?}–{q:?} vs {hull:?}"
                );
            }
        }
    }
}
