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
//! pushes out at an end, beyond the residual's round-off, stays there: the minimum then lies
//! outside and no path is inside; a minimiser within the parameters' round-off of an end is at
//! that end, a path). It cannot be the solver's own loop, which moves points across vertices.
//! Where two points collapse onto the crossing of their lines (`T` has a kink there), they are
//! held there while the others settle, and the subgradient decides whether the collapse is
//! the minimum (no path) or the points restart apart; where points collapse onto a held vertex
//! or three share one spot, the directional derivative of `T` off that vertex decides
//! (`cluster.rs`), or the minimum of `T` with its kinks smoothed away moves them apart. Legs
//! that run along their line wherever the points are (consecutive points on segments of one
//! line, an end exactly on the line: exact orientation tests) rule their assignment out.
//!
//! What only a threshold decides is not a proof: a solve that stalls next to a collapse that
//! cannot be tested (within [`COLLAPSE`] of the path's length), with a leg whose sine with its
//! segment's line is below [`ALONG`], a leg below the vanishing threshold, or a side within
//! it. Such a candidate is dropped, but the search says so: it is not complete, and its
//! outcome names the rule ([`SearchOutcome::undecided`]), so that a triple without a path
//! answers `not_converged` with that reason rather than `no_path`. Any other solve that does
//! not settle marks the search incomplete too.
//!
//! [`COLLAPSE`]: collapse::COLLAPSE
//! [`ALONG`]: collapse::ALONG

mod bounds;
mod branch;
mod cluster;
mod collapse;
#[cfg(test)]
mod fixture;
mod hierarchy;
mod leaf;
mod listing;
mod minimise;
mod outcome;
mod place;
mod result;
mod scratch;
mod smoothed;

pub(crate) use hierarchy::Hierarchy;
pub(crate) use listing::{finish, recycle, retain};
pub use result::{Arrival, Kink, SearchOutcome, StationaryError};

use crate::geom::Point;
use crate::options::{Progress, Run};
use crate::problem::ProblemRef;
use crate::scene::{MAX_STATIONARY_STEPS, Scene};

use super::Classifier;
use super::classify::Sequence;
use scratch::Scratch;

/// Tuples (and assignments solved) a search of one sequence visits at most when asked for
/// every stationary path, before it gives up and says it is not complete.
pub(crate) const MAX_TUPLES: usize = 1 << 26;

/// How much a search of one sequence may do before it gives up and says it is not complete:
/// tuples of hierarchy nodes visited (and assignments solved), and work, the points moved by
/// its Newton steps (each step of an assignment of `k` points counts `k + 1`, as does each
/// tuple), which bounds its time where a few tuples hold costly solves (long sequences over
/// many segments, where each assignment is solved with every choice of held vertices).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct SearchBudget {
    /// Tuples, and assignments solved.
    pub tuples: usize,
    /// Points moved and tuples weighed, as above.
    pub work: usize,
}

impl SearchBudget {
    /// A budget of `tuples` tuples and no limit on work.
    #[cfg(test)]
    pub(crate) fn tuples(tuples: usize) -> SearchBudget {
        SearchBudget {
            tuples,
            work: usize::MAX,
        }
    }
}

/// What a search of one sequence with given leg media borrows.
#[derive(Clone, Copy)]
pub(crate) struct SequenceSearch<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The classifier of the scene's rays, which every candidate goes through.
    pub classifier: &'a Classifier,
    /// The segment hierarchy of each step's interface.
    pub hierarchies: &'a [&'a Hierarchy],
    /// The solver's tolerance on the relative residual.
    pub tolerance: f64,
    /// The steps.
    pub sequence: Sequence<'a>,
    /// Leg media (steps + 1), as indices into [`Scene::media`].
    pub media: &'a [usize],
    /// The path's first point.
    pub source: Point,
    /// The path's last point.
    pub receiver: Point,
    /// What the search may do before it gives up (incomplete).
    pub budget: SearchBudget,
    /// The run of the call the search is part of: its stop request, budget and progress.
    pub run: &'a Run,
}

/// The search's scratch and settings for one triple.
struct Search<'a> {
    /// The sequence's time and its derivatives.
    g: ProblemRef<'a>,
    /// The steps.
    sequence: Sequence<'a>,
    /// Leg media, as indices into [`Scene::media`].
    media: &'a [usize],
    /// See [`SequenceSearch::budget`].
    budget: SearchBudget,
    /// The classifier every candidate goes through.
    classifier: &'a Classifier,
    /// The segment hierarchy of each step's interface.
    hierarchies: &'a [&'a Hierarchy],
    /// The solver's tolerance on the relative residual.
    tolerance: f64,
    /// This thread's scratch, held for the search.
    sc: Box<Scratch>,
    /// What the search did so far.
    stats: SearchOutcome,
    /// The legs (bits) whose two points [`minimise`](Search::minimise) holds together at a
    /// collapse while the others settle.
    pinned: usize,
    /// Whether the present solve has followed the smoothed time once
    /// ([`smooth_away`](Search::smooth_away)).
    smoothed: bool,
    /// How many times the present solve moved a point off a vertex that a held point shares
    /// ([`move_off`](Search::move_off)).
    moved_off: usize,
    /// The run of the call the search is part of ([`crate::options`]).
    run: &'a Run,
}

impl Search<'_> {
    /// Counts `work` and tells whether the search must end here: its budget of tuples (and
    /// solves) or of work is spent, or its job was asked to stop. The search is then not
    /// complete. The one test of a search's limits, and of its run's
    /// ([`Run::keep_going`]).
    fn over_budget(&mut self, work: usize) -> bool {
        self.stats.work += work;
        let spent = self.stats.tuples > self.budget.tuples
            || self.stats.solves > self.budget.tuples
            || self.stats.work > self.budget.work;
        let over = spent || !self.run.keep_going(Progress::work(work as u64));
        if over {
            self.stats.complete = false;
        }
        over
    }
}

/// Every stationary path of one sequence with given leg media, appended to `out` unsorted
/// (see [`finish`]); adds what it did to `stats`.
pub(crate) fn search_sequence(
    input: SequenceSearch<'_>,
    out: &mut Vec<Arrival>,
    stats: &mut SearchOutcome,
) {
    let done = searching(input, |search| search.run(out));
    stats.add(done);
}

/// Runs `f` on the search of `input` (with this thread's scratch, given back at the end);
/// returns what the search did.
fn searching(input: SequenceSearch<'_>, f: impl FnOnce(&mut Search<'_>)) -> SearchOutcome {
    let k = input.sequence.steps.len();
    debug_assert!(k <= MAX_STATIONARY_STEPS && input.media.len() == k + 1);
    let mut sc = scratch::take_scratch();
    sc.resize(k);
    let mut slowness = std::mem::take(&mut sc.slowness);
    slowness.clear();
    slowness.extend(input.media.iter().map(|&m| input.scene.media()[m].slowness));
    let mut search = Search {
        g: ProblemRef {
            scene: input.scene,
            steps: input.sequence.steps,
            slowness: &slowness,
            curved: &[],
            source: input.source,
            receiver: input.receiver,
        },
        sequence: input.sequence,
        media: input.media,
        budget: input.budget,
        classifier: input.classifier,
        hierarchies: input.hierarchies,
        tolerance: input.tolerance,
        sc,
        stats: SearchOutcome::new(),
        pinned: 0,
        smoothed: false,
        moved_off: 0,
        run: input.run,
    };
    f(&mut search);
    let done = search.stats;
    let mut sc = search.sc;
    sc.slowness = slowness;
    scratch::give_back(sc);
    done
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::Status;
    use crate::trace::complete::branch::tests::mirror;

    /// A work budget stops a search that its tuples alone would let finish: the valley's
    /// search with ample work is complete and counts its work; with less work than it needs,
    /// it says it is not complete.
    #[test]
    fn a_work_budget_makes_a_search_incomplete() {
        let v = [
            Point::new(-3.0, 0.0),
            Point::new(0.0, -2.0),
            Point::new(3.0, 0.0),
        ];
        let fixture = mirror(&v, Point::new(-0.5, 2.0), Point::new(0.5, 2.0));
        let run = |work: usize| {
            let mut stats = SearchOutcome::new();
            let mut out = Vec::new();
            fixture.with_input(0, MAX_TUPLES, |mut input| {
                input.budget.work = work;
                search_sequence(input, &mut out, &mut stats);
            });
            stats
        };
        let full = run(usize::MAX);
        assert!(full.complete && full.work >= 2 * full.tuples);
        let short = run(full.work / 2);
        assert!(!short.complete && short.work <= full.work);
    }

    /// The valley of `Tracer::stationary_paths`'s example: `search_sequence` appends the
    /// three paths (two reflections and the bottom vertex) and adds what it did to the
    /// stats it is given; a second search appends the same again; a limit of one tuple
    /// makes the search incomplete.
    #[test]
    fn search_sequence_appends_and_adds_up() {
        let v = [
            Point::new(-3.0, 0.0),
            Point::new(0.0, -2.0),
            Point::new(3.0, 0.0),
        ];
        let fixture = mirror(&v, Point::new(-0.5, 2.0), Point::new(0.5, 2.0));
        let mut out = Vec::new();
        let start = SearchOutcome {
            tuples: 5,
            solves: 7,
            work: 11,
            ..SearchOutcome::new()
        };
        let mut stats = start;
        fixture.with_input(0, MAX_TUPLES, |input| {
            search_sequence(input, &mut out, &mut stats);
        });
        let once = stats;
        assert!(once.complete && once.tuples > 5 && once.solves > 7 && once.work > 11);
        let mut statuses: Vec<Status> = out.iter().map(|a| a.status).collect();
        statuses.sort_by_key(|s| s.as_str());
        assert_eq!(
            statuses,
            [Status::Converged, Status::Converged, Status::Vertex]
        );
        // The image method's time of the two reflections: from (−0.5, 2) to the image of
        // (0.5, 2) in either slope.
        for a in out.iter().filter(|a| a.status == Status::Converged) {
            assert!((a.time - 45f64.sqrt()).abs() <= 1e-12, "{}", a.time);
        }
        fixture.with_input(0, MAX_TUPLES, |input| {
            search_sequence(input, &mut out, &mut stats);
        });
        assert_eq!(out.len(), 6);
        assert_eq!(out[..3], out[3..]);
        assert_eq!(stats.tuples - once.tuples, once.tuples - start.tuples);
        assert_eq!(stats.solves - once.solves, once.solves - start.solves);
        fixture.with_input(0, 1, |input| {
            search_sequence(input, &mut out, &mut stats);
        });
        assert!(!stats.complete);
    }
}
