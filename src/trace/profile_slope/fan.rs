//! The search of a scene with a `profile` medium and walls that are not all flat and
//! horizontal (a sloping bottom, a polyline): per (source, receiver) pair, one fan of
//! [`SHOTS`] launch angles all round the source, each ray marched through the profile and
//! reflected specularly off the first wall it meets (any interface the search may reflect
//! off), until it has met `max_steps` walls and meets one more, passes a lower bound of
//! `max_time` (with a margin), leaves the scene's extent or runs [`MAX_PIECES`] pieces. Each
//! ray records the walls it met in order (interface, segment, turns before each) and where
//! it passed the receiver's height (after how many walls, after how many turns on that leg).
//! Two neighbouring rays that passed the receiver's height on the same family (the same
//! walls, segments and turns before it) on either side of the receiver bracket an
//! arrival of that sequence of walls: the bracket is refined by the path route's shooting
//! ([`Shooting::bisect`], its steps the family's walls) and solved by its Newton
//! ([`Shooting::ray_of_start`]). Like the flat waveguide's, the search is sampled: no
//! pair is complete.
//!
//! The time bound of a ray is a lower bound: each piece's chord over the greater of its
//! ends' speeds (the speed is linear along a piece's height, and the arc is no shorter
//! than its chord).

use crate::geom::Point;
use crate::leg::profile::{MAX_EVENTS, PieceEnd, Profile};
use crate::scene::{Scene, Step, StepKind};

use super::{
    MAX_PASSES, MAX_PIECES, SHOTS, Shooting, ShotBudget, SlopedRay, WallHit, extent, keep_new,
    piece_hit, reflected,
};

/// The margin on `max_time` of the fan's rays (their time is a lower bound, and an arrival
/// by `max_time` needs both rays of its bracket).
const TIME_MARGIN: f64 = 0.05;

/// One wall a ray of the fan met: its interface, its segment, the turns on the leg before.
#[derive(Clone, Copy, Debug, PartialEq)]
struct FanHit {
    interface: usize,
    segment: usize,
    turns: u32,
}

/// One pass of a ray of the fan at the receiver's height: where (x), after how many walls
/// and after how many turns on that leg.
#[derive(Clone, Copy, Debug, PartialEq)]
struct FanPass {
    x: f64,
    walls: usize,
    turns: u32,
}

/// One ray of the fan.
#[derive(Clone, Debug, Default)]
struct FanRay {
    hits: Vec<FanHit>,
    passes: Vec<FanPass>,
}

/// What the search of one pair found: each arrival's steps and ray (by sequence, then
/// time), and the work it did.
#[derive(Clone, Debug, Default)]
pub(crate) struct SlopedSearch {
    pub rays: Vec<(Vec<Step>, SlopedRay)>,
    pub work: u64,
}

/// The fan of one pair.
struct Fan<'a> {
    scene: &'a Scene,
    profile: &'a Profile,
    /// The interfaces a ray reflects off.
    walls: &'a [usize],
    /// The most walls of an arrival.
    max_walls: usize,
    /// The latest time a ray is followed to (with its margin).
    max_time: f64,
    source: Point,
    receiver: Point,
    /// Where the rays may go ([`extent`]).
    bounds: crate::geom::Aabb,
    budget: &'a ShotBudget<'a>,
}

impl<'a> Fan<'a> {
    /// The path shooting of `steps` between the fan's pair, within its bounds and budget.
    fn shooting<'s>(&'s self, steps: &'s [Step]) -> Shooting<'s>
    where
        'a: 's,
    {
        Shooting {
            scene: self.scene,
            profile: self.profile,
            steps,
            source: self.source,
            receiver: self.receiver,
            bounds: self.bounds,
            budget: self.budget,
        }
    }

    /// The ray at launch angle `theta` (radians from +x); `None` when the budget refuses it.
    fn shoot(&self, theta: f64) -> Option<FanRay> {
        if !self.budget.shot() {
            return None;
        }
        let bounds = self.bounds;
        let eps = 1e-9 * bounds.diagonal();
        let yr = self.receiver.y;
        let (mut at, mut d) = (
            self.source,
            crate::geom::Vec2::new(theta.cos(), theta.sin()),
        );
        let mut ray = FanRay::default();
        let mut elapsed = 0.0;
        loop {
            let (mut turns, mut first, mut work) = (0, true, 0);
            let mut next: Option<(WallHit, u32)> = None;
            let walls = ray.hits.len();
            let passes = &mut ray.passes;
            let heights = [bounds.min.y, bounds.max.y];
            self.profile
                .march(at.to_vec2(), d, heights, MAX_PIECES, |piece| {
                    if elapsed > self.max_time {
                        return false;
                    }
                    work += 1;
                    let hit = piece_hit(self.scene, piece, self.walls, eps, first, &mut work);
                    first = false;
                    let start = piece.start.to_point();
                    let end = hit.map_or(piece.end.to_point(), |h| h.point);
                    if let Some(q) = piece.at_height(yr)
                        && q != piece.start
                        && (q.to_point() - at).length() > eps
                        && (q.y - start.y).abs() <= (end.y - start.y).abs()
                        && passes.len() < MAX_PASSES
                    {
                        passes.push(FanPass {
                            x: q.x,
                            walls,
                            turns,
                        });
                    }
                    elapsed += start.distance(end) / piece.speeds[0].max(piece.speeds[1]);
                    if let Some(h) = hit {
                        next = Some((h, turns));
                        return false;
                    }
                    turns += u32::from(piece.end_kind == PieceEnd::Turn);
                    piece.end.x >= bounds.min.x && piece.end.x <= bounds.max.x
                });
            self.budget.spend(work);
            let Some((h, turns)) = next else { break };
            if walls >= self.max_walls || elapsed > self.max_time {
                break;
            }
            ray.hits.push(FanHit {
                interface: h.interface,
                segment: h.segment,
                turns,
            });
            d = reflected(self.scene, h.interface, h.segment, h.arriving);
            at = h.point;
        }
        Some(ray)
    }
}

/// The brackets between two neighbouring rays: each pair of passes of one family (the
/// same walls before it, the same turns) on either side of the receiver.
fn brackets<'r>(r0: &'r FanRay, r1: &'r FanRay, xr: f64) -> impl Iterator<Item = FanPass> + 'r {
    r0.passes.iter().copied().filter(move |a| {
        r1.passes.iter().any(|b| {
            b.walls == a.walls
                && b.turns == a.turns
                && ((a.x - xr) > 0.0) != ((b.x - xr) > 0.0)
                && r0.hits.get(..a.walls) == r1.hits.get(..a.walls)
        })
    })
}

impl FanRay {
    /// The steps of its first `walls` reflections.
    fn steps(&self, walls: usize) -> Vec<Step> {
        (self.hits[..walls].iter())
            .map(|h| Step {
                kind: StepKind::Reflect,
                interface: h.interface,
            })
            .collect()
    }
}

/// Adds `ray` (of sequence `steps`) to the arrivals `found` by sequence, unless its
/// sequence's list holds it already ([`keep_new`]).
fn keep_found(
    found: &mut Vec<(Vec<Step>, Vec<SlopedRay>)>,
    steps: Vec<Step>,
    ray: SlopedRay,
    bounds: crate::geom::Aabb,
) {
    match found.iter_mut().find(|(s, _)| *s == steps) {
        Some((_, list)) => keep_new(list, ray, bounds),
        None => found.push((steps, vec![ray])),
    }
}

/// The sequences of walls after which either of two neighbouring rays passes the receiver's
/// height past the first wall where the two parted (a different segment, or other turns
/// before it); none where they met the same walls.
fn parted_sequences(r0: &FanRay, r1: &FanRay) -> Vec<Vec<Step>> {
    let common = r0
        .hits
        .iter()
        .zip(&r1.hits)
        .take_while(|(a, b)| a == b)
        .count();
    if common == r0.hits.len() && common == r1.hits.len() {
        return Vec::new();
    }
    let mut out: Vec<Vec<Step>> = Vec::new();
    for ray in [r0, r1] {
        for pass in ray.passes.iter().filter(|p| p.walls > common) {
            let steps = ray.steps(pass.walls);
            if !out.contains(&steps) {
                out.push(steps);
            }
        }
    }
    out
}

/// The search of one pair (see the module) through the profile medium `medium`: walls
/// `walls`, at most `max_walls` of them, arrivals by `max_time`, within `budget`.
pub(crate) fn sloped_search(
    scene: &Scene,
    medium: usize,
    [source, receiver]: [Point; 2],
    (walls, max_walls, max_time): (&[usize], usize, f64),
    shots: usize,
    budget: &ShotBudget<'_>,
) -> SlopedSearch {
    let Some(profile) = scene.media().get(medium).and_then(|m| m.profile_model()) else {
        return SlopedSearch::default();
    };
    let bounds = extent(scene, source, receiver);
    let fan = Fan {
        scene,
        profile: &profile,
        walls,
        max_walls: max_walls.min(MAX_EVENTS as usize),
        max_time: max_time * (1.0 + TIME_MARGIN),
        source,
        receiver,
        bounds,
        budget,
    };
    let angle = |i: usize| -std::f64::consts::PI + std::f64::consts::TAU * i as f64 / shots as f64;
    let mut rays: Vec<FanRay> = Vec::with_capacity(shots + 1);
    for i in 0..=shots {
        let Some(ray) = fan.shoot(angle(i)) else {
            break;
        };
        rays.push(ray);
    }
    let mut found: Vec<(Vec<Step>, Vec<SlopedRay>)> = Vec::new();
    for (i, pair) in rays.windows(2).enumerate() {
        let (r0, r1) = (&pair[0], &pair[1]);
        for pass in brackets(r0, r1, receiver.x) {
            let steps = r0.steps(pass.walls);
            let shooting = fan.shooting(&steps);
            let Some(ray) = shooting
                .bracket([angle(i), angle(i + 1)], pass.turns)
                .and_then(|start| shooting.ray_of_start(&start))
                .filter(|r| r.time <= max_time)
            else {
                continue;
            };
            keep_found(&mut found, steps, ray, bounds);
        }
        // Where the two parted (a reflection point crossed a vertex, the miss jumping
        // there), every sequence either passes the receiver after: its own shots between
        // them, bracketed on each side of the boundary.
        let lo_hi = [angle(i), angle(i + 1)];
        for steps in parted_sequences(r0, r1) {
            let shooting = fan.shooting(&steps);
            let (Some(s0), Some(s1)) = (shooting.shoot(lo_hi[0]), shooting.shoot(lo_hi[1])) else {
                continue;
            };
            let mut starts = Vec::new();
            shooting.starts_between(lo_hi, [&s0, &s1], &mut starts);
            for start in starts {
                let Some(ray) = shooting.ray_of_start(&start).filter(|r| r.time <= max_time) else {
                    continue;
                };
                keep_found(&mut found, steps.clone(), ray, bounds);
            }
        }
    }
    let mut out = SlopedSearch {
        rays: found
            .into_iter()
            .flat_map(|(steps, list)| list.into_iter().map(move |r| (steps.clone(), r)))
            .collect(),
        work: budget.spent(),
    };
    out.rays.sort_by(|a, b| a.1.time.total_cmp(&b.1.time));
    out
}

impl Shooting<'_> {
    /// The start of the bracket `[lo, hi]` of launch angles whose rays pass the receiver's
    /// height on either side of it after the steps' walls and `turns` turns: both ends
    /// shot again through the steps, then bisection.
    fn bracket(&self, [lo, hi]: [f64; 2], turns: u32) -> Option<(f64, super::Shot, usize)> {
        let s0 = self.shoot(lo)?;
        let s1 = self.shoot(hi)?;
        let j = s0.passes.iter().position(|p| p.1 == turns)?;
        let (v0, v1) = (self.miss(&s0, j)?, self.miss(&s1, j)?);
        if (v0 > 0.0) == (v1 > 0.0) || !s0.same_family(&s1, j) {
            return None;
        }
        self.bisect([lo, hi], v0, &s0, j)
    }
}

/// Whether a scene's interfaces are not all flat horizontal lines (open, every point at one
/// `y`): its profile search is this module's.
pub(crate) fn has_sloped_walls(scene: &Scene) -> bool {
    scene.interfaces().iter().any(|i| {
        let line = &i.polyline;
        let v = line.vertices();
        line.is_closed() || v.iter().any(|p| p.y != v[0].y)
    })
}

impl crate::trace::Tracer {
    /// The arrivals of the search of one pair off sloping walls (see the module) through
    /// the profile medium `medium`, each with its steps, by time: `converged` ones (and
    /// `obstructed` ones when the search lists them), and the work done. The pair's work
    /// stops at `solver.max_work` and at `run`'s stop request or budget.
    pub(crate) fn search_sloped_pair(
        &self,
        medium: usize,
        ends: [Point; 2],
        options: &crate::scene::SearchOptions,
        run: &crate::options::Run,
    ) -> (Vec<(Vec<Step>, crate::trace::Arrival)>, u64) {
        let scene = self.scene();
        let walls: &[usize] = if options.reflect {
            &options.interfaces
        } else {
            &[]
        };
        let budget = ShotBudget::new(scene.solver().max_work, Some(run));
        let bounds = (walls, options.step_limit(), options.time_limit());
        let found = sloped_search(scene, medium, ends, bounds, SHOTS, &budget);
        let arrivals = found
            .rays
            .iter()
            .filter(|(_, r)| {
                r.status == crate::trace::Status::Converged
                    || (options.obstructed && r.status == crate::trace::Status::Obstructed)
            })
            .map(|(steps, r)| (steps.clone(), self.sloped_arrival(steps, medium, r)))
            .collect();
        (arrivals, found.work)
    }
}
