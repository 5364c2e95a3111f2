//! Paths of reflections through a `profile` medium off walls that are not all flat and
//! horizontal (a sloping bottom, a polyline): each leg is the ray of one branch of the
//! profile between its ends (`leg/profile/leg.rs`: its first vertical direction, its
//! turning points and its ray parameter), and the path is stationary in its reflection
//! points' arclengths, solved by the Newton solver on the legs' model ([`LegMedium::Profile`]).
//!
//! Its starts come from shooting: [`SHOTS`] launch angles all round the source, each ray
//! marched through the profile (`Profile::march`) to the path's walls in order, reflected
//! there (specularly, on the segment it meets), and after the last one to the receiver's
//! height; each sign change of the miss at the receiver between two neighbouring angles
//! whose rays met the same segments with the same turns is refined by bisection, and the
//! ray's reflection points and legs' branches start Newton. Like the flat waveguide's
//! sampling this is no proof (two rays closer than a sample apart may be missed).

use std::cell::Cell;

use crate::geom::{Aabb, Point, Vec2};
use crate::leg::profile::{Branch, PieceEnd, Profile, ProfileLeg, ProfileLegModel, RayPiece};
use crate::leg::{Leg, LegMedium, LegModel};
use crate::options::{Progress, Run};
use crate::problem::ProblemRef;
use crate::scene::{Scene, Step, StepKind};
use crate::solver::{NewtonOptions, NewtonWorkspace, Outcome, solve};

use super::classify::END_MARGIN;
use super::complete::Arrival;
use super::profile::ProfileShape;
use super::{RayRecord, Reason, SearchOutcome, Status, Tracer, Workspace};
use crate::amplitude::{Amplitude, PathGeometry};

mod fan;
pub(crate) use fan::has_sloped_walls;
#[cfg(test)]
use fan::{SlopedSearch, sloped_search};

/// The launch angles shot all round the source.
pub(crate) const SHOTS: usize = 8192;
/// Chords per piece of a ray where it is tested against a wall.
const CHORDS: usize = 8;
/// The most pieces marched on one leg.
const MAX_PIECES: usize = 20_000;
/// The most times the last leg is followed through the receiver's height.
const MAX_PASSES: usize = 256;
/// Points per piece of a leg for its obstruction test.
const PIECE_POINTS: usize = 16;
/// The work of one chord of a piece (its point on the arc, its end angles shared by the
/// piece; a unit is about 220 instructions, as elsewhere: see docs/performance.md).
const CHORD_WORK: u64 = 1;
/// Segment boxes weighed against a chord per unit of work.
const SEGMENTS_PER_UNIT: usize = 8;
/// The work of one crossing of a chord and a segment refined on the piece (64 points, the
/// piece's end angles shared).
const REFINE_WORK: u64 = 48;
/// The work of one Newton solve per leg (its legs' roots at each iteration).
const NEWTON_WORK: u64 = 2000;

/// One ray of a path of reflections through a profile medium.
#[derive(Clone, Debug)]
pub(crate) struct SlopedRay {
    /// Source, reflection points, receiver.
    pub points: Vec<Point>,
    /// Each reflection's segment and arclength on its interface.
    pub segments: Vec<usize>,
    pub parameters: Vec<f64>,
    /// Each leg, its branch's ray.
    pub legs: Vec<ProfileLeg>,
    /// The travel time.
    pub time: f64,
    /// Newton's iterations and its final residual.
    pub iterations: usize,
    pub residual: f64,
    /// `converged`, or `obstructed` (with the interface crossed).
    pub status: Status,
    pub reason: Option<Reason>,
}

impl SlopedRay {
    /// Its turning points (reflections not counted).
    pub fn turns(&self) -> u32 {
        self.legs.iter().map(|l| l.turns).sum()
    }
    /// Its direction at the source, radians from +x.
    pub fn launch_angle(&self) -> f64 {
        let d = self.legs[0].direction_at_start();
        d.y.atan2(d.x)
    }
}

/// Whether a path of `steps` through a profile medium takes this route: reflections only,
/// one at least on an interface that is not a flat horizontal line.
pub(crate) fn takes_sloped_route(scene: &Scene, steps: &[Step]) -> bool {
    !steps.is_empty()
        && steps.iter().all(|s| s.kind == StepKind::Reflect)
        && steps.iter().any(|s| {
            let line = &scene.interfaces()[s.interface].polyline;
            let v = line.vertices();
            line.is_closed() || v.iter().any(|p| p.y != v[0].y)
        })
}

/// Where the shots may go: the box of the interfaces, the source and the receiver, grown by
/// its own size.
fn extent(scene: &Scene, source: Point, receiver: Point) -> Aabb {
    let mut b = Aabb::from_points(source, receiver);
    for i in scene.interfaces() {
        b = b.union(Aabb::around(i.polyline.vertices()));
    }
    let grow = b.diagonal().max(1.0);
    Aabb {
        min: Point::new(b.min.x - grow, b.min.y - grow),
        max: Point::new(b.max.x + grow, b.max.y + grow),
    }
}

/// One shot: where it reflected, how it left each reflection, the turns of each leg before
/// the last, and where the last leg passed the receiver's height (with its turns so far).
#[derive(Clone, Debug, Default, PartialEq)]
struct Shot {
    hits: Vec<(Point, usize)>,
    departures: Vec<Vec2>,
    turns: Vec<u32>,
    passes: Vec<(f64, u32)>,
}

impl Shot {
    /// Whether two shots met the same segments with the same turns, and both passed the
    /// receiver's height a `j`-th time after the same turns.
    fn same_family(&self, o: &Shot, j: usize) -> bool {
        self.same_walls(o) && self.passes.get(j).map(|p| p.1) == o.passes.get(j).map(|p| p.1)
    }

    /// Whether two shots met the same segments with the same turns before each.
    fn same_walls(&self, o: &Shot) -> bool {
        self.hits.len() == o.hits.len()
            && self.hits.iter().zip(&o.hits).all(|(a, b)| a.1 == b.1)
            && self.turns == o.turns
    }
}

/// The most walls' boundaries [`Shooting::across`] follows between two neighbouring shots.
const MAX_BOUNDARIES: u32 = 4;

/// The signed distance of `q` from the line of `a–b` (left positive).
fn side(a: Point, b: Point, q: Point) -> f64 {
    let d = b - a;
    d.cross(q - a) / d.length()
}

/// The shooting of one path: the scene, the profile, the steps, the ends and the extent.
struct Shooting<'a> {
    scene: &'a Scene,
    profile: &'a Profile,
    steps: &'a [Step],
    source: Point,
    receiver: Point,
    bounds: Aabb,
    budget: &'a ShotBudget<'a>,
}

/// Where a ray piece first meets a wall: the point, its interface and segment, the ray's
/// direction there and the fraction of the piece's arc length (an upper bracket).
#[derive(Clone, Copy, Debug)]
struct WallHit {
    point: Point,
    interface: usize,
    segment: usize,
    arriving: Vec2,
    fraction: f64,
}

/// Whether some segment of `interfaces` may meet `piece`: a piece is monotone in height
/// and in `x`, so it (and each of its chords) lies in the box of its ends grown by `eps`;
/// a segment whose box misses that box, or whose line leaves all four of its corners more
/// than `eps` on one side, cannot cross a chord. `work` grows by one per
/// [`SEGMENTS_PER_UNIT`] segments weighed.
fn piece_near_walls(
    scene: &Scene,
    piece: &RayPiece,
    interfaces: &[usize],
    eps: f64,
    work: &mut u64,
) -> bool {
    let reach = Aabb::from_points(piece.start.to_point(), piece.end.to_point()).grown(eps);
    let corners = [
        reach.min,
        reach.max,
        Point::new(reach.min.x, reach.max.y),
        Point::new(reach.max.x, reach.min.y),
    ];
    interfaces.iter().any(|&interface| {
        let line = &scene.interfaces()[interface].polyline;
        *work += line.num_segments().div_ceil(SEGMENTS_PER_UNIT) as u64;
        (0..line.num_segments()).any(|seg| {
            let g = line.segment(seg);
            if !reach.overlaps(Aabb::from_points(g.start, g.end)) {
                return false;
            }
            let sides = corners.map(|c| side(g.start, g.end, c));
            !(sides.iter().all(|&v| v > eps) || sides.iter().all(|&v| v < -eps))
        })
    })
}

/// Where `piece` first meets a segment of one of `interfaces` ([`CHORDS`] chords, each
/// crossing refined by bisection on the piece). `leaving`: the piece starts a leg on a wall,
/// whose start (within `eps` of a segment) is not a meeting. `work` grows by the
/// [`piece_near_walls`] test's, then, only for a piece near a wall, by [`CHORD_WORK`] per
/// chord, one per [`SEGMENTS_PER_UNIT`] segment boxes weighed and one per box the chord's
/// meets, and [`REFINE_WORK`] per crossing refined.
fn piece_hit(
    scene: &Scene,
    piece: &RayPiece,
    interfaces: &[usize],
    eps: f64,
    leaving: bool,
    work: &mut u64,
) -> Option<WallHit> {
    if !piece_near_walls(scene, piece, interfaces, eps, work) {
        return None;
    }
    chord_hit(scene, piece, interfaces, eps, leaving, work)
}

/// [`piece_hit`] without its [`piece_near_walls`] test: every chord against every segment.
fn chord_hit(
    scene: &Scene,
    piece: &RayPiece,
    interfaces: &[usize],
    eps: f64,
    leaving: bool,
    work: &mut u64,
) -> Option<WallHit> {
    let angles = piece.angles();
    let at = |f: f64| piece.at_angles(f, angles).to_point();
    let mut found: Option<WallHit> = None;
    let mut prev = at(0.0);
    for j in 1..=CHORDS {
        let (f0, f1) = ((j - 1) as f64 / CHORDS as f64, j as f64 / CHORDS as f64);
        let q = at(f1);
        let chord = Aabb::from_points(prev, q);
        *work += CHORD_WORK;
        for &interface in interfaces {
            let line = &scene.interfaces()[interface].polyline;
            *work += line.num_segments().div_ceil(SEGMENTS_PER_UNIT) as u64;
            for seg in 0..line.num_segments() {
                let g = line.segment(seg);
                if !chord.overlaps(Aabb::from_points(g.start, g.end)) {
                    continue;
                }
                *work += 1;
                let (mut g0, g1) = (side(g.start, g.end, prev), side(g.start, g.end, q));
                if leaving && j == 1 && g0.abs() < eps {
                    g0 = g1;
                }
                if g0 * g1 > 0.0 || g0 == g1 {
                    continue;
                }
                // Refine on the piece itself.
                *work += REFINE_WORK;
                let (mut lo, mut hi, sign0) = (f0, f1, g0 > 0.0);
                for _ in 0..64 {
                    let mid = 0.5 * (lo + hi);
                    if (side(g.start, g.end, at(mid)) > 0.0) == sign0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let hit = at(0.5 * (lo + hi));
                let along =
                    (hit - g.start).dot(g.end - g.start) / (g.end - g.start).dot(g.end - g.start);
                if (0.0..=1.0).contains(&along) && found.is_none_or(|f| hi < f.fraction) {
                    found = Some(WallHit {
                        point: hit,
                        interface,
                        segment: seg,
                        arriving: piece.direction_at(hit.y),
                        fraction: hi,
                    });
                }
            }
        }
        if found.is_some() {
            return found;
        }
        prev = q;
    }
    None
}

/// The direction `arriving` reflected specularly off segment `seg` of `interface`.
fn reflected(scene: &Scene, interface: usize, seg: usize, arriving: Vec2) -> Vec2 {
    let n = scene.interfaces()[interface].polyline.tangent(seg).perp();
    arriving - n * (2.0 * arriving.dot(n))
}

/// What the shooting of one pair may spend: the scene's `solver.max_work` (units counted by
/// [`piece_hit`] and per piece marched) and the run's stop request and budget (one unit
/// per shot), when there is a run.
pub(crate) struct ShotBudget<'r> {
    run: Option<&'r Run>,
    max_work: u64,
    spent: Cell<u64>,
    stopped: Cell<bool>,
}

impl<'r> ShotBudget<'r> {
    pub(crate) fn new(max_work: u64, run: Option<&'r Run>) -> ShotBudget<'r> {
        ShotBudget {
            run,
            max_work,
            spent: Cell::new(0),
            stopped: Cell::new(false),
        }
    }

    /// Whether one more shot may be taken (`false` from the first refusal on).
    fn shot(&self) -> bool {
        if self.stopped.get()
            || self.spent.get() >= self.max_work
            || self.run.is_some_and(|r| !r.keep_going(Progress::work(1)))
        {
            self.stopped.set(true);
            return false;
        }
        true
    }

    /// Counts `work` units spent.
    fn spend(&self, work: u64) {
        self.spent.set(self.spent.get().saturating_add(work));
    }

    /// The units spent so far.
    pub(crate) fn spent(&self) -> u64 {
        self.spent.get()
    }

    /// Whether the shooting stopped at a limit (or a stop request).
    pub(crate) fn stopped(&self) -> bool {
        self.stopped.get()
    }
}

impl Shooting<'_> {
    /// The ray leaving `from` in direction `d` until it meets `interface` (not within `eps`
    /// of `from`): the point, its segment, the arriving direction and the turns before it.
    fn to_wall(
        &self,
        from: Point,
        d: Vec2,
        interface: usize,
        eps: f64,
    ) -> Option<(Point, usize, Vec2, u32)> {
        let b = self.bounds;
        let mut found = None;
        let mut turns = 0;
        let mut first = true;
        let mut work = 0;
        self.profile
            .march(from.to_vec2(), d, [b.min.y, b.max.y], MAX_PIECES, |piece| {
                let hit = piece_hit(self.scene, piece, &[interface], eps, first, &mut work);
                first = false;
                if let Some(h) = hit {
                    found = Some((h.point, h.segment, h.arriving, turns));
                    return false;
                }
                turns += u32::from(piece.end_kind == PieceEnd::Turn);
                piece.end.x >= b.min.x && piece.end.x <= b.max.x
            });
        self.budget.spend(work);
        found
    }

    /// The shot at launch angle `theta` (radians from +x).
    fn shoot(&self, theta: f64) -> Option<Shot> {
        if !self.budget.shot() {
            return None;
        }
        let eps = 1e-9 * self.bounds.diagonal();
        let mut shot = Shot::default();
        let (mut at, mut d) = (self.source, Vec2::new(theta.cos(), theta.sin()));
        shot.departures.push(d);
        for step in self.steps {
            let (hit, seg, arriving, turns) = self.to_wall(at, d, step.interface, eps)?;
            d = reflected(self.scene, step.interface, seg, arriving);
            at = hit;
            shot.hits.push((hit, seg));
            shot.departures.push(d);
            shot.turns.push(turns);
        }
        let (b, yr) = (self.bounds, self.receiver.y);
        let mut turns = 0;
        let mut passes = Vec::new();
        let mut pieces = 0;
        self.profile
            .march(at.to_vec2(), d, [b.min.y, b.max.y], MAX_PIECES, |piece| {
                pieces += 1;
                let here = piece.at_height(yr).filter(|q| *q != piece.start);
                if let Some(q) = here
                    && (q.to_point() - at).length() > eps
                {
                    passes.push((q.x, turns));
                }
                turns += u32::from(piece.end_kind == PieceEnd::Turn);
                passes.len() < MAX_PASSES && piece.end.x >= b.min.x && piece.end.x <= b.max.x
            });
        self.budget.spend(pieces);
        shot.passes = passes;
        Some(shot)
    }

    /// The miss of the `j`-th pass at the receiver.
    fn miss(&self, shot: &Shot, j: usize) -> Option<f64> {
        shot.passes.get(j).map(|p| p.0 - self.receiver.x)
    }

    /// Every start: the shots between whose neighbours a pass's miss changes sign, refined
    /// by bisection on the launch angle.
    fn starts(&self) -> Vec<(f64, Shot, usize)> {
        let angle =
            |i: usize| -std::f64::consts::PI + std::f64::consts::TAU * i as f64 / SHOTS as f64;
        let shots: Vec<Option<Shot>> = (0..=SHOTS).map(|i| self.shoot(angle(i))).collect();
        let mut out = Vec::new();
        for i in 0..SHOTS {
            let (Some(s0), Some(s1)) = (&shots[i], &shots[i + 1]) else {
                continue;
            };
            self.starts_between([angle(i), angle(i + 1)], [s0, s1], &mut out);
        }
        out
    }

    /// The starts between two neighbouring shots `s0` (at `lo`) and `s1` (at `hi`): each
    /// sign change of a pass's miss within one family, refined by bisection, and where the
    /// two met different segments, [`across`](Self::across) their boundaries.
    pub(super) fn starts_between(
        &self,
        [lo, hi]: [f64; 2],
        [s0, s1]: [&Shot; 2],
        out: &mut Vec<(f64, Shot, usize)>,
    ) {
        self.sign_changes([lo, hi], [s0, s1], out);
        if !s0.same_walls(s1) {
            self.across([lo, hi], [s0, s1], MAX_BOUNDARIES, out);
        }
    }

    /// Each pass whose miss changes sign between shots `s0` (at `lo`) and `s1` (at `hi`) of
    /// one family, refined by bisection.
    fn sign_changes(
        &self,
        [lo, hi]: [f64; 2],
        [s0, s1]: [&Shot; 2],
        out: &mut Vec<(f64, Shot, usize)>,
    ) {
        for j in 0..s0.passes.len().min(s1.passes.len()) {
            let (Some(v0), Some(v1)) = (self.miss(s0, j), self.miss(s1, j)) else {
                continue;
            };
            if (v0 > 0.0) == (v1 > 0.0) || !s0.same_family(s1, j) {
                continue;
            }
            if let Some(found) = self.bisect([lo, hi], v0, s0, j) {
                out.push(found);
            }
        }
    }

    /// The starts between two neighbouring shots that met different segments (or turned
    /// differently): where a reflection point crosses a vertex, the miss at the receiver
    /// jumps, so a root of one side's family may lie between its last shot and the
    /// boundary, out of reach of the neighbours' sign test. The boundary is found by
    /// bisection on the launch angle; each side's family is then bracketed between its
    /// neighbour and its shot nearest the boundary, and what lies beyond a second boundary
    /// likewise (up to `depth` boundaries).
    fn across(
        &self,
        [lo, hi]: [f64; 2],
        [s_lo, s_hi]: [&Shot; 2],
        depth: u32,
        out: &mut Vec<(f64, Shot, usize)>,
    ) {
        if depth == 0 {
            return;
        }
        // The boundary: `a` the last angle of `s_lo`'s walls, `b` the first past them.
        let (mut a, mut b) = (lo, hi);
        let (mut shot_a, mut shot_b): (Option<Shot>, Option<Shot>) = (None, None);
        for _ in 0..64 {
            let mid = 0.5 * (a + b);
            if mid <= a || mid >= b {
                break;
            }
            let Some(shot) = self.shoot(mid) else {
                // No shot (a wall missed, or the budget spent): the boundary is that.
                b = mid;
                shot_b = None;
                continue;
            };
            if shot.same_walls(s_lo) {
                (a, shot_a) = (mid, Some(shot));
            } else {
                (b, shot_b) = (mid, Some(shot));
            }
        }
        if let Some(near) = &shot_a {
            self.sign_changes([lo, a], [s_lo, near], out);
        }
        // Past the boundary: `s_hi`'s family, or another boundary before it.
        let start = shot_b.as_ref().unwrap_or(s_hi);
        if start.same_walls(s_hi) {
            if let Some(near) = &shot_b {
                self.sign_changes([b, hi], [near, s_hi], out);
            }
        } else if let Some(near) = &shot_b {
            self.across([b, hi], [near, s_hi], depth - 1, out);
        }
    }

    /// Bisection on the launch angle between `lo` (miss `v_lo`) and `hi` for the `j`-th pass
    /// of `family`'s shots.
    fn bisect(
        &self,
        [mut lo, mut hi]: [f64; 2],
        v_lo: f64,
        family: &Shot,
        j: usize,
    ) -> Option<(f64, Shot, usize)> {
        let mut last = None;
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            let shot = self.shoot(mid)?;
            if !shot.same_family(family, j) {
                return None;
            }
            let v = self.miss(&shot, j)?;
            if (v > 0.0) == (v_lo > 0.0) {
                lo = mid;
            } else {
                hi = mid;
            }
            last = Some((mid, shot));
        }
        last.map(|(theta, shot)| (theta, shot, j))
    }
}

/// The legs' branches of a start: each leg's first vertical direction, turns and `|p|`.
fn branches(profile: &Profile, start: &(f64, Shot, usize)) -> Vec<Branch> {
    let (_, shot, j) = start;
    let k = shot.hits.len();
    (0..=k)
        .map(|i| {
            let d = shot.departures[i];
            let y = if i == 0 {
                f64::NAN
            } else {
                shot.hits[i - 1].0.y
            };
            let turns = if i < k {
                shot.turns[i]
            } else {
                shot.passes[*j].1
            };
            Branch {
                first: if d.y < 0.0 { -1.0 } else { 1.0 },
                turns,
                near: if y.is_nan() {
                    f64::NAN
                } else {
                    d.x.abs() / profile.speed_at(y)
                },
            }
        })
        .collect()
}

/// Every ray of the path of `steps` (reflections, one at least off a wall that is not flat
/// and horizontal) through the profile medium `medium` from `source` to `receiver`, by
/// time: shot, solved by Newton on the legs' model, each checked (converged, its legs'
/// rays existing, each reflection's legs on one side of its wall) and tested for
/// obstruction (its legs' inscribed polygons against every interface, their ends' margins
/// left out); the same ray is listed once.
pub(crate) fn sloped_rays(
    scene: &Scene,
    steps: &[Step],
    medium: usize,
    [source, receiver]: [Point; 2],
    budget: &ShotBudget<'_>,
) -> Vec<SlopedRay> {
    let Some(profile) = scene.media().get(medium).and_then(|m| m.profile_model()) else {
        return Vec::new();
    };
    let shooting = Shooting {
        scene,
        profile: &profile,
        steps,
        source,
        receiver,
        bounds: extent(scene, source, receiver),
        budget,
    };
    let mut out: Vec<SlopedRay> = Vec::new();
    for start in shooting.starts() {
        if let Some(ray) = shooting.ray_of_start(&start) {
            keep_new(&mut out, ray, shooting.bounds);
        }
    }
    out.sort_by(|a, b| a.time.total_cmp(&b.time));
    out
}

/// Pushes `ray` onto `out` unless `out` holds it already (the same segments, points within
/// 1e-7 of the extent's diagonal, the same branches).
fn keep_new(out: &mut Vec<SlopedRay>, ray: SlopedRay, bounds: Aabb) {
    let tol = 1e-7 * bounds.diagonal();
    let same = |r: &SlopedRay| {
        r.segments == ray.segments
            && r.points.len() == ray.points.len()
            && r.points
                .iter()
                .zip(&ray.points)
                .all(|(a, b)| a.distance(*b) <= tol)
            && r.legs
                .iter()
                .zip(&ray.legs)
                .all(|(a, b)| a.branch().first == b.branch().first && a.turns == b.turns)
    };
    if !out.iter().any(same) {
        out.push(ray);
    }
}

impl Shooting<'_> {
    /// The ray Newton finds from a start (its legs' branches held), when it converges to
    /// one whose legs all exist and reflect.
    fn ray_of_start(&self, start: &(f64, Shot, usize)) -> Option<SlopedRay> {
        let profile = self.profile;
        let mut branch = branches(profile, start);
        // The first leg's ray parameter from the launch angle.
        let d0 = start.1.departures[0];
        branch[0].near = d0.x.abs() / profile.speed_at(self.source.y);
        self.budget
            .spend(NEWTON_WORK * (self.steps.len() as u64 + 1));
        polish(
            self.scene,
            profile,
            self.steps,
            [self.source, self.receiver],
            &start.1,
            &branch,
        )
    }
}

/// Newton on the reflection points from a shot, the legs' branches held; the ray when it
/// converges to one whose legs all exist and reflect.
fn polish(
    scene: &Scene,
    profile: &Profile,
    steps: &[Step],
    [source, receiver]: [Point; 2],
    shot: &Shot,
    branch: &[Branch],
) -> Option<SlopedRay> {
    let k = steps.len();
    let origin = source.to_vec2();
    let models: Vec<LegMedium<'_>> = branch
        .iter()
        .map(|&b| {
            LegMedium::Profile(ProfileLegModel {
                profile,
                origin,
                branch: b,
            })
        })
        .collect();
    let slowness = vec![1.0 / profile.speed_at(source.y); k + 1];
    let mut nw = NewtonWorkspace::default();
    nw.resize_to(k);
    for (i, step) in steps.iter().enumerate() {
        let line = &scene.interfaces()[step.interface].polyline;
        let (hit, seg) = shot.hits[i];
        let g = line.segment(seg);
        nw.s[i] = line.start(seg) + (hit - g.start).dot(line.tangent(seg));
        nw.seg[i] = seg;
    }
    let g = ProblemRef {
        scene,
        steps,
        slowness: &slowness,
        curved: &models,
        source,
        receiver,
    };
    let options = scene.solver();
    // No reflection (the direct ray): nothing to move, the leg is the branch's ray.
    let (iterations, residual) = if k == 0 {
        (0, 0.0)
    } else {
        let sol = solve(
            &g,
            &mut nw,
            NewtonOptions {
                tolerance: options.tolerance,
                max_iterations: options.max_iterations,
                fast_path: false,
            },
        );
        if sol.outcome != Outcome::Converged {
            return None;
        }
        (sol.iterations, sol.residual)
    };
    let mut points = vec![source];
    for (i, step) in steps.iter().enumerate() {
        points.push(
            scene.interfaces()[step.interface]
                .polyline
                .point_at(nw.s[i]),
        );
    }
    points.push(receiver);
    let mut legs = Vec::with_capacity(k + 1);
    for (j, m) in models.iter().enumerate() {
        let leg = m.valid_leg(
            (points[j] - source).to_point(),
            (points[j + 1] - source).to_point(),
        )?;
        legs.push(*leg.profile()?);
    }
    for (i, step) in steps.iter().enumerate() {
        let n = scene.interfaces()[step.interface]
            .polyline
            .tangent(nw.seg[i])
            .perp();
        let (into, away) = (
            legs[i].direction_at_end().dot(n),
            legs[i + 1].direction_at_start().dot(n),
        );
        if into * away >= 0.0 {
            return None;
        }
    }
    let mut ray = SlopedRay {
        time: legs.iter().map(|l| l.time).sum(),
        points,
        segments: nw.seg[..k].to_vec(),
        parameters: nw.s[..k].to_vec(),
        legs,
        iterations,
        residual,
        status: Status::Converged,
        reason: None,
    };
    if let Some((leg, interface)) = obstruction(scene, profile, &ray) {
        ray.status = Status::Obstructed;
        ray.reason = Some(Reason::Crosses { leg, interface });
    }
    Some(ray)
}

/// The first leg (and interface) that crosses an interface: each leg's inscribed polygon,
/// its ends' margins left out.
fn obstruction(scene: &Scene, profile: &Profile, ray: &SlopedRay) -> Option<(usize, usize)> {
    for (j, leg) in ray.legs.iter().enumerate() {
        let (a, b) = (ray.points[j].to_vec2(), ray.points[j + 1].to_vec2());
        let found = profile.leg_ray(a, b, leg.branch())?;
        let curve = profile.curve(&found, a, b, PIECE_POINTS);
        let n = curve.len().saturating_sub(1);
        let at = |i: usize| curve[i].to_point();
        let hit = (0..n).find_map(|i| {
            let margin = if i == 0 || i + 1 == n {
                (END_MARGIN * n as f64).min(0.25)
            } else {
                0.0
            };
            scene
                .first_crossing(
                    at(i),
                    at(i + 1),
                    margin,
                    [crate::scene::SegmentRef::NONE; 2],
                )
                .map(|r| r.interface as usize)
        });
        if let Some(interface) = hit {
            return Some((j, interface));
        }
    }
    None
}

/// What the rays of a path depend on beyond its steps, medium and ends: every interface's
/// vertices and every profile's knots (the key of [`sloped_rays_cached`]).
fn fingerprint(scene: &Scene) -> Vec<f64> {
    let mut out = Vec::new();
    for i in scene.interfaces() {
        out.extend(i.polyline.vertices().iter().flat_map(|p| [p.x, p.y]));
        out.push(f64::NAN);
    }
    for m in scene.media() {
        out.extend(m.profile.iter().flatten().flatten());
        out.push(f64::NAN);
    }
    out
}

/// [`sloped_rays`] within the scene's `solver.max_work` (and `run`'s stop request and
/// budget, when given), remembered per thread for the last path and pair asked (the default
/// mode's solve, its amplitude and its written turns ask for the same in turn) unless the
/// shooting stopped at a limit.
pub(crate) fn sloped_rays_cached(
    scene: &Scene,
    steps: &[Step],
    medium: usize,
    [source, receiver]: [Point; 2],
    run: Option<&Run>,
) -> Vec<SlopedRay> {
    type Key = (Vec<Step>, usize, Point, Point, Vec<u64>, u64);
    thread_local! {
        static LAST: std::cell::RefCell<Option<(Key, Vec<SlopedRay>)>> =
            const { std::cell::RefCell::new(None) };
    }
    let print = fingerprint(scene).iter().map(|v| v.to_bits()).collect();
    let work = scene.solver().max_work;
    let key: Key = (steps.to_vec(), medium, source, receiver, print, work);
    LAST.with(|last| {
        if let Some((k, found)) = &*last.borrow()
            && *k == key
        {
            return found.clone();
        }
        let budget = ShotBudget::new(scene.solver().max_work, run);
        let found = sloped_rays(scene, steps, medium, [source, receiver], &budget);
        if !budget.stopped() {
            *last.borrow_mut() = Some((key, found.clone()));
        }
        found
    })
}

impl Tracer {
    /// The profile medium of path `path` from `source` when the path takes the sloped
    /// route ([`takes_sloped_route`]) and its first leg's medium (given, or found at the
    /// source) has a profile.
    pub(crate) fn profile_sloped_medium(
        &self,
        path: usize,
        source: Point,
        src_medium: Option<usize>,
    ) -> Option<usize> {
        let spec = self.scene.paths().get(path)?;
        if !self.scene.curved() || !takes_sloped_route(&self.scene, &spec.steps) {
            return None;
        }
        let m = match &spec.media {
            Some(m) => *m.first()?,
            None => src_medium.or_else(|| self.source_medium(false, source))?,
        };
        self.scene.media()[m].profile.is_some().then_some(m)
    }

    /// The default mode's ray of a path on the sloped route: the earliest that no interface
    /// crosses (else the earliest, `obstructed`), into `ws`.
    pub(crate) fn solve_sloped(
        &self,
        path: usize,
        medium: usize,
        source: Point,
        receiver: Point,
        ws: &mut Workspace,
    ) -> RayRecord {
        let steps = &self.scene.paths()[path].steps;
        let k = steps.len();
        ws.resize(k);
        ws.ray.clear();
        ws.ray.media.extend(std::iter::repeat_n(medium, k + 1));
        let rays = sloped_rays_cached(&self.scene, steps, medium, [source, receiver], None);
        let Some(r) = super::profile::default_choice(&rays, |r| r.status) else {
            return RayRecord::failed(Status::NoPath, Reason::NoStationaryPath);
        };
        let slowness = r.legs.iter().map(|l| 1.0 / l.speeds[0]);
        ws.keep_profile_ray(&r.points, slowness, &r.parameters, &r.segments);
        RayRecord {
            status: r.status,
            time: r.time,
            iterations: u32::try_from(r.iterations).unwrap_or(u32::MAX),
            residual: r.residual,
            reason: r.reason,
        }
    }

    /// The amplitude of one ray of the sloped route, when the scene asks for amplitudes.
    pub(crate) fn sloped_amplitude(
        &self,
        steps: &[Step],
        medium: usize,
        r: &SlopedRay,
    ) -> Option<Amplitude> {
        let settings = self.scene.amplitudes()?;
        if r.status != Status::Converged {
            return Some(Amplitude::none(crate::amplitude::NoAmplitude::Obstructed));
        }
        let media = vec![medium; r.legs.len()];
        let path = PathGeometry {
            steps,
            points: &r.points,
            media: &media,
            segments: Some(&r.segments),
        };
        Some(crate::amplitude::of_profile_legs(
            &self.scene,
            settings,
            self.regions.as_ref(),
            path,
            &r.legs,
        ))
    }

    /// Every ray of a path on the sloped route as stationary paths, by time (the shooting
    /// within `solver.max_work` and `run`).
    pub(crate) fn sloped_stationary_paths(
        &self,
        path: usize,
        medium: usize,
        [source, receiver]: [Point; 2],
        run: &Run,
        out: &mut Vec<Arrival>,
    ) -> SearchOutcome {
        let steps = &self.scene.paths()[path].steps;
        let rays = sloped_rays_cached(&self.scene, steps, medium, [source, receiver], Some(run));
        out.extend(rays.iter().map(|r| self.sloped_arrival(steps, medium, r)));
        SearchOutcome {
            complete: false,
            solves: SHOTS,
            work: rays.len(),
            ..SearchOutcome::new()
        }
    }

    /// The arrival of one ray of the sloped route (of `steps`, through `medium`), with its
    /// amplitude, turns, caustics and launch angle.
    pub(crate) fn sloped_arrival(&self, steps: &[Step], medium: usize, r: &SlopedRay) -> Arrival {
        let shape = sloped_shape_of(&self.scene, steps, r);
        Arrival {
            status: r.status,
            time: r.time,
            points: r.points.clone(),
            parameters: r.parameters.clone(),
            segments: r.segments.clone(),
            media: vec![medium; steps.len() + 1],
            iterations: r.iterations,
            reason: r.reason,
            kink: None,
            residual: r.residual,
            amplitude: self.sloped_amplitude(steps, medium, r),
            turns: Some(shape.turns),
            caustics: Some(shape.caustics),
            launch_angle: Some(shape.launch_angle),
        }
    }

    /// The ray of the sloped route a default-mode solve chose, found again from its points
    /// (`None` for any other path).
    pub(crate) fn sloped_ray_of(
        &self,
        steps: &[Step],
        points: &[Point],
        media: &[usize],
    ) -> Option<(usize, SlopedRay)> {
        sloped_ray_of(&self.scene, steps, points, media)
    }
}

/// [`Tracer::sloped_ray_of`] of `scene`.
fn sloped_ray_of(
    scene: &Scene,
    steps: &[Step],
    points: &[Point],
    media: &[usize],
) -> Option<(usize, SlopedRay)> {
    if points.len() != steps.len() + 2 || !scene.curved() || !takes_sloped_route(scene, steps) {
        return None;
    }
    let m = *media.first()?;
    scene.media().get(m)?.profile.as_ref()?;
    let (s, r) = (points[0], points[points.len() - 1]);
    sloped_rays_cached(scene, steps, m, [s, r], None)
        .into_iter()
        .find(|w| w.points == points)
        .map(|w| (m, w))
}

/// The turns, caustics and launch angle of a ray of the sloped route.
fn sloped_shape_of(scene: &Scene, steps: &[Step], r: &SlopedRay) -> ProfileShape {
    let media = vec![0; r.legs.len()];
    let path = PathGeometry {
        steps,
        points: &r.points,
        media: &media,
        segments: Some(&r.segments),
    };
    ProfileShape {
        turns: r.turns(),
        caustics: crate::amplitude::caustics_of_profile_legs(scene, path, &r.legs)
            .unwrap_or(r.legs.iter().map(|l| l.caustics).sum()),
        launch_angle: r.launch_angle(),
    }
}

/// The shape of the default mode's ray of a path on the sloped route whose points and leg
/// media these are (`None` for any other).
pub(crate) fn sloped_shape(
    scene: &Scene,
    steps: &[Step],
    points: &[Point],
    media: &[usize],
) -> Option<ProfileShape> {
    let (_, r) = sloped_ray_of(scene, steps, points, media)?;
    Some(sloped_shape_of(scene, steps, &r))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leg::profile::Bounds;

    /// The box test before the chords loses no meeting: pieces of rays all round a source
    /// over a valley of sloping segments and under a tilted surface, marched through a
    /// layered profile and reflected, meet the same wall at the same point (or none) with
    /// and without it; most pieces (here about 60 %) are spared the chords.
    #[test]
    fn the_box_test_keeps_every_meeting_of_a_piece() {
        let scene = Scene::from_json(
            r#"{ "media": { "water": { "profile": [[0, 1500], [-20, 1495], [-50, 1490],
                                                   [-80, 1492], [-150, 1496]], "at": [0, -50] } },
                 "interfaces": {
                   "surface": { "points": [[-500, 0], [800, 3], [3000, -2]],
                                "reflection": "pressure-release" },
                   "bottom": { "points": [[-500, -100], [600, -130], [1200, -85], [3000, -120]],
                               "reflection": "rigid" } },
                 "sources": [[0, -30]], "receivers": [[2500, -60]] }"#,
        )
        .unwrap();
        let profile = scene.media()[0].profile_model().unwrap();
        let (s, r) = (Point::new(0.0, -30.0), Point::new(2500.0, -60.0));
        let bounds = extent(&scene, s, r);
        let eps = 1e-9 * bounds.diagonal();
        let (mut pieces, mut near, mut hits) = (0, 0, 0);
        for i in 0..400 {
            let theta = -std::f64::consts::PI + std::f64::consts::TAU * (i as f64 + 0.5) / 400.0;
            let (mut at, mut d) = (s, Vec2::new(theta.cos(), theta.sin()));
            for _ in 0..6 {
                let mut first = true;
                let mut next = None;
                profile.march(
                    at.to_vec2(),
                    d,
                    [bounds.min.y, bounds.max.y],
                    2000,
                    |piece| {
                        let (mut w0, mut w1) = (0, 0);
                        let fast = piece_hit(&scene, piece, &[0, 1], eps, first, &mut w0);
                        let full = chord_hit(&scene, piece, &[0, 1], eps, first, &mut w1);
                        let key = |h: &WallHit| (h.point, h.interface, h.segment, h.fraction);
                        assert_eq!(fast.as_ref().map(key), full.as_ref().map(key), "{piece:?}");
                        pieces += 1;
                        near += usize::from(piece_near_walls(&scene, piece, &[0, 1], eps, &mut w0));
                        first = false;
                        next = full;
                        next.is_none() && bounds.contains(piece.end.to_point())
                    },
                );
                let Some(h) = next else { break };
                hits += 1;
                d = reflected(&scene, h.interface, h.segment, h.arriving);
                at = h.point;
            }
        }
        assert!(hits > 1000 && pieces > 2 * near, "{pieces} {near} {hits}");
    }

    /// A five-knot summer profile between a flat pressure-release surface at 0 and a flat
    /// rigid bottom at −100 m, a source at (0, −30) and a receiver at (3000, −60), with the
    /// further keys `more` (`""`, or `"paths": …`).
    fn flat_waveguide(more: &str) -> Scene {
        let comma = if more.is_empty() { "" } else { "," };
        Scene::from_json(&format!(
            r#"{{ "media": {{ "water": {{ "profile": [[0, 1500], [-20, 1495], [-50, 1490],
                                                   [-80, 1492], [-150, 1496]], "at": [0, -50] }} }},
                 "interfaces": {{
                   "surface": {{ "points": [[-500, 0], [6000, 0]], "reflection": "pressure-release" }},
                   "bottom": {{ "points": [[-500, -100], [6000, -100]], "reflection": "rigid" }} }},
                 "sources": [[0, -30]], "receivers": [[3000, -60]]{comma} {more} }}"#
        ))
        .unwrap()
    }

    /// Flat walls: the general route (shooting, Newton on the legs) finds what the flat
    /// waveguide's route finds (its reflections as turning points at the walls), the same
    /// arrivals of each path, times to 1e-12, points to 1e-6, turns and caustics the same.
    #[test]
    fn flat_walls_agree_with_the_waveguide_route() {
        let scene = flat_waveguide(
            r#""paths": [{ "steps": [{ "reflect": "bottom" }] },
                         { "steps": [{ "reflect": "surface" }, { "reflect": "bottom" }] },
                         { "steps": [{ "reflect": "bottom" }, { "reflect": "surface" },
                                     { "reflect": "bottom" }] }]"#,
        );
        let profile = scene.media()[0].profile_model().unwrap();
        let s = Point::new(0.0, -30.0);
        let mut compared = 0;
        let receivers = [
            Point::new(3000.0, -60.0),
            Point::new(900.0, -60.0),
            Point::new(-500.0, -80.0),
        ];
        for (r, path) in receivers
            .into_iter()
            .flat_map(|r| scene.paths().iter().map(move |p| (r, p)))
        {
            let steps = &path.steps;
            let budget = ShotBudget::new(u64::MAX, None);
            let general = sloped_rays(&scene, steps, 0, [s, r], &budget);
            let bounds = Bounds {
                reflections: steps.len() as u32,
                time: f64::INFINITY,
            };
            let (flat, _) = super::super::profile::walled_rays(&scene, &profile, s, r, bounds);
            let flat: Vec<_> = flat.into_iter().filter(|w| w.steps == *steps).collect();
            assert_eq!(general.len(), flat.len(), "{steps:?}: {general:?} {flat:?}");
            for (g, f) in general.iter().zip(&flat) {
                let t = f.ray.sums.t;
                assert!((g.time - t).abs() <= 1e-12 * t, "{steps:?}: {} {t}", g.time);
                for (p, q) in g.points.iter().zip(&f.points) {
                    assert!(p.distance(*q) <= 1e-6, "{p:?} {q:?}");
                }
                let shape = sloped_shape_of(&scene, steps, g);
                assert_eq!((shape.turns, shape.caustics), (f.ray.turns, f.ray.caustics));
                assert_eq!(g.status, f.status);
                compared += 1;
            }
        }
        assert!(compared >= 8, "{compared}");
    }

    /// Flat walls: the search off sloping walls (one fan, brackets, the path route's Newton)
    /// lists what the flat waveguide's search lists: the same arrivals within `max_steps`
    /// (steps, times to 1e-12, points to 1e-6, status), obstructed ones included.
    #[test]
    fn flat_walls_search_agrees_with_the_waveguide_search() {
        let scene = flat_waveguide("");
        let profile = scene.media()[0].profile_model().unwrap();
        let s = Point::new(0.0, -30.0);
        let mut compared = 0;
        for r in [
            Point::new(3000.0, -60.0),
            Point::new(900.0, -60.0),
            Point::new(-500.0, -80.0),
            Point::new(5000.0, -5.0),
        ] {
            let budget = ShotBudget::new(u64::MAX, None);
            let general = sloped_search(
                &scene,
                0,
                [s, r],
                (&[0, 1], 3, f64::INFINITY),
                SHOTS,
                &budget,
            );
            let bounds = Bounds {
                reflections: 3,
                time: f64::INFINITY,
            };
            let (flat, _) = super::super::profile::walled_rays(&scene, &profile, s, r, bounds);
            assert_eq!(
                general.rays.len(),
                flat.len(),
                "{r:?}: {general:?} {flat:?}"
            );
            for ((steps, g), f) in general.rays.iter().zip(&flat) {
                let t = f.ray.sums.t;
                assert_eq!(*steps, f.steps, "{r:?}");
                assert!((g.time - t).abs() <= 1e-12 * t, "{r:?}: {} {t}", g.time);
                for (p, q) in g.points.iter().zip(&f.points) {
                    assert!(p.distance(*q) <= 1e-6, "{p:?} {q:?}");
                }
                assert_eq!(g.status, f.status);
                compared += 1;
            }
        }
        eprintln!("{compared} arrivals the same");
        assert!(compared >= 15, "{compared}");
    }

    /// A Munk profile over a bottom sloping 4000 → 4300 → 3800 m, 10 km, up to two walls:
    /// the fan of 8192 rays lists the same arrivals as fans of 16384 and 32768 (the same
    /// walls, turns, times to 1e-9 relative), every one off walls is an arrival of its
    /// steps as the path route (its own shooting through those walls) finds it, and the
    /// direct ones are the profile's free rays that no interface crosses (times to 1e-12).
    #[test]
    fn munk_over_a_slope_is_stable_as_the_fan_densifies() {
        let knots: Vec<String> = (0..=5000)
            .step_by(100)
            .map(|z| {
                let e = 2.0 * (z as f64 - 1300.0) / 1300.0;
                let c = 1500.0 * (1.0 + 0.00737 * (e - 1.0 + (-e).exp()));
                format!("[{}, {c}]", -(z as f64))
            })
            .collect();
        let scene = Scene::from_json(&format!(
            r#"{{ "media": {{ "water": {{ "profile": [{}], "at": [0, -1000] }} }},
                 "interfaces": {{
                   "surface": {{ "points": [[-500, 0], [12000, 0]], "reflection": "pressure-release" }},
                   "bottom": {{ "points": [[-500, -4000], [5000, -4300], [12000, -3800]],
                                "reflection": "rigid" }} }},
                 "sources": [[0, -1000]], "receivers": [[10000, -1500]] }}"#,
            knots.join(", ")
        ))
        .unwrap();
        let (s, r) = (Point::new(0.0, -1000.0), Point::new(10000.0, -1500.0));
        let fans: Vec<SlopedSearch> = [SHOTS, 2 * SHOTS, 4 * SHOTS]
            .iter()
            .map(|&shots| {
                let budget = ShotBudget::new(u64::MAX, None);
                sloped_search(
                    &scene,
                    0,
                    [s, r],
                    (&[0, 1], 2, f64::INFINITY),
                    shots,
                    &budget,
                )
            })
            .collect();
        let key =
            |x: &(Vec<Step>, SlopedRay)| (x.0.clone(), x.1.turns(), x.1.legs[0].branch().first);
        assert!(fans[0].rays.len() >= 6, "{:?}", fans[0].rays);
        for fan in &fans[1..] {
            assert_eq!(fan.rays.len(), fans[0].rays.len());
            for (a, b) in fans[0].rays.iter().zip(&fan.rays) {
                assert_eq!(key(a), key(b));
                assert!(
                    (a.1.time - b.1.time).abs() <= 1e-9 * a.1.time,
                    "{} {}",
                    a.1.time,
                    b.1.time
                );
            }
        }
        let mut walls = 0;
        for (steps, ray) in fans[0].rays.iter().filter(|x| !x.0.is_empty()) {
            let budget = ShotBudget::new(u64::MAX, None);
            let path = sloped_rays(&scene, steps, 0, [s, r], &budget);
            assert!(
                path.iter()
                    .any(|p| (p.time - ray.time).abs() <= 1e-12 * ray.time),
                "{steps:?} {}: {path:?}",
                ray.time
            );
            walls += 1;
        }
        // The direct rays: the free rays of the profile (`Profile::arrivals`) that no
        // interface crosses.
        let tracer = Tracer::new(&scene).unwrap();
        let profile = scene.media()[0].profile_model().unwrap();
        let (free, _) = tracer.profile_rays(&profile, s, r);
        let free: Vec<f64> = (free.iter())
            .filter(|f| f.status == Status::Converged)
            .map(|f| f.ray.sums.t)
            .collect();
        let direct: Vec<f64> = (fans[0].rays.iter())
            .filter(|x| x.0.is_empty() && x.1.status == Status::Converged)
            .map(|x| x.1.time)
            .collect();
        assert!(!free.is_empty());
        assert_eq!(direct.len(), free.len(), "{direct:?} {free:?}");
        for (a, b) in direct.iter().zip(&free) {
            assert!((a - b).abs() <= 1e-12 * b, "{a} {b}");
        }
        let times: Vec<f64> = fans[0].rays.iter().map(|x| x.1.time).collect();
        eprintln!("{} arrivals ({walls} off walls): {times:?}", times.len());
    }
}
