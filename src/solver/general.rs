//! The general Newton loop: every case the fast path hands over (points held on vertices and
//! at ends, vanished legs, steps across vertices, rejected steps), in named steps.
//!
//! One iteration: release or keep the held points ([`release_held`]), hold the points next to
//! a vanished leg on their kink ([`hold_on_kinks`]), test for convergence, solve the Newton
//! system on the free points ([`newton_system`], [`damped_step`] when it is singular), cap
//! the step ([`negate_and_cap`]), and search along it ([`GeneralLoop::line_search`]), where
//! points that meet a vertex or an end point of the ray are put there instead.

use super::{IterationState, NewtonOptions, NewtonWorkspace, Outcome, Solution, thomas};
use crate::geom::{Point, Segment, Vec2};
use crate::problem::{Eval, Pin, ProblemRef, leg_vanished};

/// The general iteration from `ws` as the fast path left it (`fast`). Leaves the final state in
/// `ws` (`s`, `seg`, `pin`, `eval`).
pub(super) fn run(
    g: &ProblemRef,
    ws: &mut NewtonWorkspace,
    opts: NewtonOptions,
    fast: IterationState,
) -> Solution {
    let k = g.k();
    let (tol, max_iterations) = (opts.tolerance, opts.max_iterations);
    let mut it = GeneralLoop::new(fast, k, ws);
    loop {
        if !it.evaluated {
            g.evaluate(&ws.s, &ws.seg, &ws.pin, &mut ws.eval, true, it.curvature);
        }
        it.evaluated = false;

        // Held points: keep, or release towards decreasing T.
        if ws.eval.held > 0 && release_held(g, ws, tol) && it.free_move(max_iterations) {
            continue;
        }
        // Free points next to a vanished leg sit on a kink of T: hold them if the one-sided
        // residuals bracket zero, else let them move by the residual of the way down.
        if ws.eval.vanished > 0 && hold_on_kinks(g, ws, tol) && it.free_move(max_iterations) {
            continue;
        }

        let residual = ws.eval.rmax;
        if residual <= tol && ws.eval.held == k {
            return finished_at_kinks(g, ws, it.iterations, tol);
        }
        if !residual.is_finite() || it.iterations >= max_iterations {
            return not_converged(&ws.eval, it.iterations);
        }
        if it.iterations >= 8 && !it.cautious {
            it.watch_for_cycles(ws, k);
        }

        // Newton system H δ = −r on the free points (solved as H x = r, δ = −x).
        if !newton_system(ws, k) {
            damped_step(g, ws);
        }
        let step = negate_and_cap(g, ws);
        if (step.tiny || residual <= tol) && it.any_sticky && it.free_move(max_iterations) {
            // The others are stationary: judge the points held on the way again.
            ws.sticky[..k].fill(false);
            it.any_sticky = false;
            continue;
        }
        if step.tiny {
            return finished_at_kinks(g, ws, it.iterations, tol);
        }
        if residual <= tol
            || (it.stalled && at_round_off_floor(&ws.eval, &ws.s, &ws.pin, g.slowness, tol))
        {
            // Stationary to tolerance. Where T is flat along the solution (grazing legs, a
            // nearly singular H) the residual allows a point error of about tol / λmin; stop
            // only if the Newton correction is small against the legs, else take it (once
            // more at most: Newton converges quadratically from here).
            let e = &ws.eval;
            let small = (0..k).all(|i| {
                ws.pin[i] != Pin::Free
                    || ws.delta[i].abs() <= tol.sqrt() * (e.len[i] + e.len[i + 1])
            });
            if small || it.polishes >= 2 {
                return finished_at_kinks(g, ws, it.iterations, tol);
            }
            it.polishes += 1;
        }
        it.iterations += 1;

        match it.line_search(g, ws, step.cap) {
            Search::Pinned => {
                it.curvature = false;
                it.near_kink = true;
                continue;
            }
            Search::Accepted { curvature } => {
                it.stalled = false;
                it.curvature = curvature;
                // The trial was evaluated with the curvature flag of the next iteration: reuse it.
                std::mem::swap(&mut ws.eval, &mut ws.eval_try);
                it.evaluated = true;
            }
            Search::Rejected { best } => {
                it.stalled = false;
                if it.curvature {
                    // The curvature model misled the step; retry on the exact segment-wise model.
                    it.curvature = false;
                    continue;
                }
                // Non-monotone fallback: take the best trial so that the iteration moves on.
                it.stalled = true;
                let Some(alpha) = best else {
                    return not_converged(&ws.eval, it.iterations);
                };
                let crossed = trial_step(g, ws, alpha, false);
                it.curvature = crossed && !it.near_kink;
            }
        }
        std::mem::swap(&mut ws.s, &mut ws.s_try);
        std::mem::swap(&mut ws.seg, &mut ws.seg_try);
        std::mem::swap(&mut ws.pin, &mut ws.pin_try);
        // The others have moved: the held points are judged again.
        if it.any_sticky {
            ws.sticky[..k].fill(false);
            it.any_sticky = false;
        }
    }
}

/// The general loop's state between iterations.
struct GeneralLoop {
    /// Newton steps taken.
    iterations: usize,
    /// Whether the next evaluation adds the curvature estimate.
    curvature: bool,
    /// Whether `ws.eval` holds the evaluation at `ws.s`.
    evaluated: bool,
    /// Newton steps taken after the residual met the tolerance.
    polishes: usize,
    /// Set once a vertex or an end point was met: from then on the exact segment-wise model
    /// (no curvature estimate), which is right near a kink of T.
    near_kink: bool,
    /// Releases and pins do not move the others; bound them so that a ring of releases and
    /// re-pins cannot spin for ever between counted iterations.
    free_moves: usize,
    /// Set when the last step was the non-monotone fallback (no trial lowered the merit): the
    /// iteration has stalled, perhaps at the round-off floor of the residual.
    stalled: bool,
    /// Whether some point is held in `ws.sticky`.
    any_sticky: bool,
    /// Hashes of the states the iteration has been in (the last `seen.len()`), to catch a
    /// cycle: the iteration is deterministic, so a state met again repeats for ever. After
    /// one, no step takes a point across a vertex (`cautious`).
    seen: [u64; 32],
    states: usize,
    cautious: bool,
    /// Likewise the segments and pins alone, each time they change: past the twelfth
    /// iteration, coming back to an earlier set is a cycle too (one that need not repeat
    /// exactly).
    seen_sets: [u64; 32],
    sets: usize,
    last_set: u64,
}

/// How a line search ended.
enum Search {
    /// A trial lowered the merit: it is in `ws.*_try` and `ws.eval_try` (evaluated with the
    /// curvature flag `curvature` of the next iteration).
    Accepted { curvature: bool },
    /// A point was put on a vertex or an end point of the ray: the iteration goes on from
    /// there without a step.
    Pinned,
    /// No trial lowered the merit enough; `best` is the step fraction of the lowest finite
    /// merit seen, if any.
    Rejected { best: Option<f64> },
}

/// The Newton step after [`negate_and_cap`].
struct StepSize {
    /// Whether the full step moves no free point to another float (the round-off floor).
    tiny: bool,
    /// The largest fraction of the step the line search starts from.
    cap: f64,
}

impl GeneralLoop {
    fn new(fast: IterationState, k: usize, ws: &mut NewtonWorkspace) -> GeneralLoop {
        ws.sticky[..k].fill(false);
        GeneralLoop {
            iterations: fast.iterations,
            curvature: fast.curvature,
            evaluated: fast.evaluated,
            polishes: fast.polishes,
            near_kink: false,
            free_moves: 0,
            stalled: false,
            any_sticky: false,
            seen: [0; 32],
            states: 0,
            cautious: false,
            seen_sets: [0; 32],
            sets: 0,
            last_set: 0,
        }
    }

    /// Counts a move that is not a Newton step (a release, a pin), if the budget allows it.
    #[inline]
    fn free_move(&mut self, max_iterations: usize) -> bool {
        let allowed = self.free_moves < 4 * max_iterations;
        self.free_moves += allowed as usize;
        allowed
    }

    /// Remembers the state and turns `cautious` on when it was met before (see the fields).
    fn watch_for_cycles(&mut self, ws: &NewtonWorkspace, k: usize) {
        // (`any_sticky` follows from the held flags, which the hash includes.)
        let flags = [self.curvature, self.near_kink, self.stalled];
        let h = state_hash(ws, k, &flags, self.polishes, true);
        if self.seen[..self.states.min(self.seen.len())].contains(&h) {
            self.cautious = true;
        } else {
            self.seen[self.states % self.seen.len()] = h;
            self.states += 1;
        }
        let set = state_hash(ws, k, &[], 0, false);
        if set != self.last_set {
            if self.iterations >= 12
                && self.seen_sets[..self.sets.min(self.seen_sets.len())].contains(&set)
            {
                self.cautious = true;
            }
            self.seen_sets[self.sets % self.seen_sets.len()] = set;
            self.sets += 1;
            self.last_set = set;
        }
    }

    /// Backtracking along the Newton step in `ws.delta` from the fraction `cap`, on the merit,
    /// with the vertices and end points met on the way (see the module).
    fn line_search(&mut self, g: &ProblemRef, ws: &mut NewtonWorkspace, cap: f64) -> Search {
        let k = g.k();
        let phi0 = ws.eval.phi;
        let mut alpha = cap;
        let mut best: Option<(f64, f64)> = None;
        for attempt in 0..40 {
            let crossed = trial_step(g, ws, alpha, true);
            if self.cautious && crossed {
                // After a cycle, points stop on the vertices they reach, one at a time, and are
                // held there until the others have moved (an active-set iteration on the
                // corners); a point that would cross several takes a shorter step.
                let reached = vertices_reached(g, ws);
                if reached.several && attempt < 39 {
                    alpha *= 0.5;
                    continue;
                }
                if let Some((i, v)) = reached.first {
                    ws.s[i] = vertex_param(g, i, v, v);
                    ws.seg[i] = v;
                    ws.pin[i] = Pin::Vertex;
                    ws.sticky[i] = true;
                    self.any_sticky = true;
                    return Search::Pinned;
                }
            }
            g.evaluate(
                &ws.s_try,
                &ws.seg_try,
                &ws.pin_try,
                &mut ws.eval_try,
                true,
                crossed && !self.near_kink,
            );
            let phi = ws.eval_try.phi;
            let flips = residual_flips(g, ws);
            // A step off its segment that passes over the source or receiver, lying on the
            // segment left or the one reached (on a vertex, say), passes over a kink of T
            // (where the leg vanishes): put the point there; the kink test decides the rest.
            // (Within one segment the test comes below, only for a trial the merit rejects:
            // the fast paths accept such steps on the merit alone, and must take the same
            // ones.)
            if let Some((i, sp)) = end_point_passed(g, ws, k) {
                ws.s[i] = sp;
                ws.seg[i] = g.line(i).segment_at_hint(sp, ws.seg[i]);
                return Search::Pinned;
            }
            let merit_ok = phi.is_finite() && phi <= (1.0 - 1e-4 * alpha) * phi0;
            if merit_ok && !flips.far && flips.one.is_none() {
                return Search::Accepted {
                    curvature: crossed && !self.near_kink,
                };
            }
            if phi.is_finite() && !flips.far && best.is_none_or(|(_, b)| phi < b) {
                best = Some((alpha, phi));
            }
            if vertex_met(g, ws, &flips, &mut self.any_sticky) {
                return Search::Pinned;
            }
            if attempt == 39 {
                break;
            }
            alpha *= 0.5;
        }
        Search::Rejected {
            best: best.map(|(a, _)| a),
        }
    }
}

/// Releases the held points whose residuals say that `T` decreases off their hold, keeps the
/// others: whether one was released.
fn release_held(g: &ProblemRef, ws: &mut NewtonWorkspace, tol: f64) -> bool {
    let (k, w) = (g.k(), g.slowness);
    let e = &ws.eval;
    let mut released = false;
    for i in 0..k {
        let scale = tol * (w[i] + w[i + 1]);
        match ws.pin[i] {
            Pin::Free => {}
            Pin::Vertex if ws.sticky[i] => {}
            Pin::Vertex => {
                let Some(before) = segment_before(g, i, ws.seg[i]) else {
                    ws.pin[i] = Pin::Free;
                    released = true;
                    continue;
                };
                let rp = e.r[i];
                let rm = residual_on(g, e, i, before);
                if rp < -scale && rm < -scale {
                    ws.pin[i] = Pin::Free;
                    released = true;
                } else if rp > scale && rm > scale {
                    ws.pin[i] = Pin::Free;
                    ws.s[i] = vertex_param(g, i, ws.seg[i], before);
                    ws.seg[i] = before;
                    released = true;
                }
            }
            Pin::Start | Pin::End => {
                if !stays_at_end(e, i, ws.pin[i], scale) {
                    ws.pin[i] = Pin::Free;
                    released = true;
                }
            }
            Pin::Kink => {
                let keep = leg_vanished(&e.len, i, e.vanish) && {
                    let before = segment_behind_vertex(g, &ws.s, &ws.seg, i);
                    let back = before.map_or(e.tan[i], |j| g.line(i).tangent(j));
                    let (rm, rp) = kink_residuals(g, e, i, back);
                    rm <= scale && rp >= -scale
                };
                if !keep {
                    ws.pin[i] = Pin::Free;
                    released = true;
                }
            }
        }
    }
    released
}

/// Holds the free points next to a vanished leg on their kink where the one-sided residuals
/// bracket zero, and otherwise gives them the residual of the way down (or moves them onto
/// the previous segment): whether one was held or moved.
fn hold_on_kinks(g: &ProblemRef, ws: &mut NewtonWorkspace, tol: f64) -> bool {
    let (k, w) = (g.k(), g.slowness);
    let mut pinned = false;
    for i in 0..k {
        if ws.pin[i] != Pin::Free || !leg_vanished(&ws.eval.len, i, ws.eval.vanish) {
            continue;
        }
        let scale = tol * (w[i] + w[i + 1]);
        let before = segment_behind_vertex(g, &ws.s, &ws.seg, i);
        let back = before.map_or(ws.eval.tan[i], |j| g.line(i).tangent(j));
        let (rm, rp) = kink_residuals(g, &ws.eval, i, back);
        if rm <= scale && rp >= -scale {
            ws.pin[i] = Pin::Kink;
            pinned = true;
        } else if rp >= 0.0
            && let Some(j) = before
        {
            // The way down leaves the vertex backwards, into the previous segment.
            ws.s[i] = vertex_param(g, i, ws.seg[i], j);
            ws.seg[i] = j;
            pinned = true;
        } else {
            let r = if rp < 0.0 { rp } else { rm };
            let rel = r / (w[i] + w[i + 1]);
            ws.eval.r[i] = r;
            ws.eval.rmax = ws.eval.rmax.max(rel.abs());
            ws.eval.phi += rel * rel;
        }
    }
    pinned
}

/// Solves the Newton system `H x = r` on the free points into `ws.delta` (the step is `−x`):
/// whether the Thomas algorithm succeeded.
fn newton_system(ws: &mut NewtonWorkspace, k: usize) -> bool {
    let e = &ws.eval;
    if e.held == 0 {
        return thomas(&e.diag, &e.off, &e.r, &mut ws.delta, &mut ws.scratch);
    }
    for i in 0..k {
        let free = ws.pin[i] == Pin::Free;
        ws.rhs[i] = if free { e.r[i] } else { 0.0 };
        ws.diag[i] = if free { e.diag[i] } else { 1.0 };
        if i + 1 < k {
            ws.off[i] = if free && ws.pin[i + 1] == Pin::Free {
                e.off[i]
            } else {
                0.0
            };
        }
    }
    thomas(&ws.diag, &ws.off, &ws.rhs, &mut ws.delta, &mut ws.scratch)
}

/// Negates the solution of [`newton_system`] into the step, and measures it: the round-off
/// floor (the full step cannot move any point to another float), and the cap (no point moves
/// further than its longer leg, nor a quarter way round a closed polyline, nor past the next
/// corner).
fn negate_and_cap(g: &ProblemRef, ws: &mut NewtonWorkspace) -> StepSize {
    let e = &ws.eval;
    let mut tiny = true;
    let mut cap: f64 = 1.0;
    for i in 0..g.k() {
        let d = -ws.delta[i];
        ws.delta[i] = d;
        if ws.pin[i] != Pin::Free {
            continue;
        }
        tiny &= d.abs() <= 4.0 * f64::EPSILON * (ws.s[i].abs() + e.len[i] + e.len[i + 1]);
        let line = g.line(i);
        let mut limit = e.len[i].max(e.len[i + 1]);
        if line.is_closed() {
            limit = limit.min(0.25 * line.length());
        }
        // The segment-wise model of T holds up to the next corner, not past it.
        limit = limit.min(line.reach_past(ws.seg[i], ws.s[i], d).abs());
        if d.abs() > limit && limit > 0.0 {
            cap = cap.min(limit / d.abs());
        }
    }
    StepSize { tiny, cap }
}

/// Places the free points at the fraction `alpha` of the step in `ws.*_try` (and, with
/// `copy_held`, the held ones where they are): whether a point changed segments.
fn trial_step(g: &ProblemRef, ws: &mut NewtonWorkspace, alpha: f64, copy_held: bool) -> bool {
    let mut crossed = false;
    for i in 0..g.k() {
        if ws.pin[i] == Pin::Free {
            let (s, seg, pin) = place(g, i, ws.s[i] + alpha * ws.delta[i], ws.seg[i]);
            ws.s_try[i] = s;
            ws.seg_try[i] = seg;
            ws.pin_try[i] = pin;
            crossed |= seg != ws.seg[i];
        } else if copy_held {
            ws.s_try[i] = ws.s[i];
            ws.seg_try[i] = ws.seg[i];
            ws.pin_try[i] = ws.pin[i];
        }
    }
    crossed
}

/// The vertices that the free points' trial steps cross.
struct VerticesReached {
    /// A point crosses more than one vertex.
    several: bool,
    /// The first point that crosses exactly one, and that vertex (the segment starting there).
    first: Option<(usize, usize)>,
}

/// [`VerticesReached`] of the trial in `ws`.
fn vertices_reached(g: &ProblemRef, ws: &NewtonWorkspace) -> VerticesReached {
    let mut several = false;
    let mut first = None;
    for i in 0..g.k() {
        if ws.pin[i] == Pin::Free && ws.pin_try[i] == Pin::Free && ws.seg_try[i] != ws.seg[i] {
            match single_vertex_between(g, i, ws.seg[i], ws.seg_try[i]) {
                Some(v) => {
                    first.get_or_insert((i, v));
                }
                None => several = true,
            }
        }
    }
    VerticesReached { several, first }
}

/// Residuals that change sign while their points cross vertices in the trial: such a step has
/// jumped a kink of T or a root and is never accepted on the merit alone.
struct Flips {
    /// Across several vertices with a corner among them: backtrack (across the small turns
    /// of a digitised curve, on the merit).
    far: bool,
    /// The first point whose residual flips across one vertex: look at the vertex itself.
    one: Option<usize>,
}

/// [`Flips`] of the trial in `ws` (evaluated in `ws.eval_try`).
fn residual_flips(g: &ProblemRef, ws: &NewtonWorkspace) -> Flips {
    let (mut far, mut one) = (false, None);
    for i in 0..g.k() {
        if ws.pin[i] != Pin::Free || ws.pin_try[i] != Pin::Free || ws.seg_try[i] == ws.seg[i] {
            continue;
        }
        if ws.eval_try.r[i] * ws.eval.r[i] < 0.0 {
            if single_vertex_between(g, i, ws.seg[i], ws.seg_try[i]).is_some() {
                one.get_or_insert(i);
            } else if !g.line(i).smooth_between(ws.seg[i], ws.seg_try[i]) {
                far = true;
            }
        }
    }
    Flips { far, one }
}

/// A first or last point whose trial step off its segment passes over the source or
/// receiver lying on the segment left or the one reached: the point and that end point's
/// parameter.
fn end_point_passed(g: &ProblemRef, ws: &NewtonWorkspace, k: usize) -> Option<(usize, f64)> {
    let ends: &[usize] = match k {
        0 => &[],
        1 => &[0],
        _ => &[0, k - 1],
    };
    ends.iter().find_map(|&i| {
        let moved =
            ws.pin[i] == Pin::Free && ws.pin_try[i] == Pin::Free && ws.seg_try[i] != ws.seg[i];
        if !moved || !end_near_line(g, i, ws.eval.vanish) {
            return None;
        }
        end_point_between(g, ws, i, ws.seg[i])
            .or_else(|| end_point_between(g, ws, i, ws.seg_try[i]))
            .map(|sp| (i, sp))
    })
}

/// A trial the merit rejected, with a point crossing a vertex: if the residual does not
/// change sign before the vertex on the current segment, the point goes onto the vertex,
/// held there if the residual changes sign across it (a kink of T) and moved on into the new
/// segment otherwise (the merit is discontinuous at a vertex, so backtracking alone would
/// only creep towards it). Likewise an end point of the ray on a point's segment. Whether a
/// point was put somewhere.
fn vertex_met(
    g: &ProblemRef,
    ws: &mut NewtonWorkspace,
    flips: &Flips,
    any_sticky: &mut bool,
) -> bool {
    let k = g.k();
    let (flip_far, flip_one) = (flips.far, flips.one);
    let mut pinned = false;
    let crosser = if flip_far {
        None
    } else {
        flip_one.or_else(|| {
            (0..k).find(|&i| {
                ws.pin[i] == Pin::Free
                    && ws.pin_try[i] == Pin::Free
                    && single_vertex_between(g, i, ws.seg[i], ws.seg_try[i]).is_some()
            })
        })
    };
    if let Some((i, v)) = crosser.and_then(|i| held_on_vertex(g, ws, i).map(|v| (i, v))) {
        // Already on that vertex, with a kink of T there at the others' present
        // positions: held. (Judged on the trial's positions of the others instead, it
        // could be sent across the vertex and back for ever.)
        ws.s[i] = vertex_param(g, i, v, v);
        ws.seg[i] = v;
        ws.pin[i] = Pin::Vertex;
        pinned = true;
    } else if let Some(i) = crosser {
        let v = single_vertex_between(g, i, ws.seg[i], ws.seg_try[i]).unwrap_or(ws.seg_try[i]);
        let (s_new, seg_new) = (ws.s_try[i], ws.seg_try[i]);
        let residual_at = |seg: usize, ws: &mut NewtonWorkspace| {
            ws.s_try[i] = vertex_param(g, i, v, seg);
            ws.seg_try[i] = seg;
            g.evaluate(
                &ws.s_try,
                &ws.seg_try,
                &ws.pin_try,
                &mut ws.eval_try,
                false,
                false,
            );
            ws.eval_try.r[i]
        };
        let r_before = residual_at(ws.seg[i], ws);
        // The source or receiver sits on this vertex: go there; the kink test of a
        // vanished leg decides the rest.
        let end_point_here = leg_vanished(&ws.eval_try.len, i, ws.eval_try.vanish);
        let r_after = residual_at(seg_new, ws);
        (ws.s_try[i], ws.seg_try[i]) = (s_new, seg_new);
        let at_vertex = vertex_param(g, i, v, ws.seg[i]);
        if end_point_here && ws.s[i] != at_vertex {
            ws.s[i] = at_vertex;
            pinned = true;
        } else if end_point_here {
        } else if r_before * ws.eval.r[i] > 0.0 {
            if r_after * r_before <= 0.0 || ws.s[i] == at_vertex {
                // Already on the vertex and sent across it (from the other side the
                // step sends it back: the others, moving too, change its residuals):
                // held there until the others have moved, then judged again.
                ws.sticky[i] = ws.s[i] == at_vertex;
                *any_sticky |= ws.sticky[i];
                ws.s[i] = vertex_param(g, i, v, v);
                ws.seg[i] = v;
                ws.pin[i] = Pin::Vertex;
            } else {
                ws.s[i] = vertex_param(g, i, v, seg_new);
                ws.seg[i] = seg_new;
            }
            pinned = true;
        }
    } else if !flip_far {
        // Likewise an end point of the ray lying on a point's segment: T has a kink
        // where the point reaches it; put the point there.
        for i in 0..k {
            if ws.pin[i] == Pin::Free
                && ws.seg_try[i] == ws.seg[i]
                && let Some(sp) = end_point_between(g, ws, i, ws.seg[i])
            {
                ws.s[i] = sp;
                pinned = true;
                break;
            }
        }
    }
    pinned
}

/// The solution at the present state when the iteration gives up.
pub(super) fn not_converged(e: &Eval, iterations: usize) -> Solution {
    Solution {
        outcome: Outcome::NotConverged,
        time: e.time,
        iterations,
        residual: e.rmax,
    }
}

/// [`finished`], where every point held on a vertex sits on a kink of `T` (its one-sided
/// residuals bracket zero, to the tolerance: the test that keeps a held point in
/// `release_held`, which a point held only until the others settle skips); otherwise the
/// solve has not found a stationary path (`not_converged`, which the tracer's complete search
/// then settles).
fn finished_at_kinks(
    g: &ProblemRef,
    ws: &NewtonWorkspace,
    iterations: usize,
    tol: f64,
) -> Solution {
    let (k, w, e) = (g.k(), g.slowness, &ws.eval);
    let no_kink = (0..k).any(|i| {
        if ws.pin[i] != Pin::Vertex {
            return false;
        }
        let Some(before) = segment_before(g, i, ws.seg[i]) else {
            return true;
        };
        let scale = tol * (w[i] + w[i + 1]);
        let (rp, rm) = (e.r[i], residual_on(g, e, i, before));
        (rp < -scale && rm < -scale) || (rp > scale && rm > scale)
    });
    if no_kink {
        not_converged(e, iterations)
    } else {
        finished(ws, iterations)
    }
}

/// The outcome once the free points are stationary.
pub(super) fn finished(ws: &NewtonWorkspace, iterations: usize) -> Solution {
    let e = &ws.eval;
    let outcome = if e.held == 0 {
        Outcome::Converged
    } else if let Some(i) = ws
        .pin
        .iter()
        .position(|p| matches!(p, Pin::Start | Pin::End))
    {
        Outcome::LeftEnd(i)
    } else if ws.pin.contains(&Pin::Vertex) {
        Outcome::Vertex
    } else {
        // Held only on kinks of vanished legs: inside segments, stationary.
        Outcome::Converged
    };
    Solution {
        outcome,
        time: e.time,
        iterations,
        residual: e.rmax,
    }
}

/// Moves point `i` to parameter `s` (wrapping or holding at an end), updating its segment.
#[inline]
fn place(g: &ProblemRef, i: usize, s: f64, hint: usize) -> (f64, usize, Pin) {
    let line = g.line(i);
    if line.is_closed() {
        let w = line.wrap(s);
        return (w, line.segment_at_hint(w, hint), Pin::Free);
    }
    let l = line.length();
    if s <= 0.0 {
        (0.0, 0, Pin::Start)
    } else if s >= l {
        (l, line.num_segments() - 1, Pin::End)
    } else {
        (s, line.segment_at_hint(s, hint), Pin::Free)
    }
}

/// The segment before the vertex where segment `j` starts, if any.
#[inline]
fn segment_before(g: &ProblemRef, i: usize, j: usize) -> Option<usize> {
    let line = g.line(i);
    if j > 0 {
        Some(j - 1)
    } else if line.is_closed() {
        Some(line.num_segments() - 1)
    } else {
        None
    }
}

/// The segment before point `i` when the point sits exactly on the vertex where its segment
/// starts (moving back it follows that segment), else `None`.
#[inline]
fn segment_behind_vertex(g: &ProblemRef, s: &[f64], seg: &[usize], i: usize) -> Option<usize> {
    if s[i] == g.line(i).start(seg[i]) {
        segment_before(g, i, seg[i])
    } else {
        None
    }
}

/// Residual of point `i` as if its tangent were that of segment `j`.
#[inline]
fn residual_on(g: &ProblemRef, e: &Eval, i: usize, j: usize) -> f64 {
    let t = g.line(i).tangent(j);
    (e.u[i] * g.slowness[i] - e.u[i + 1] * g.slowness[i + 1]).dot(t)
}

/// One-sided residuals `(r⁻, r⁺)` of point `i` next to a vanished leg: moving the point
/// along its tangent `t` makes the vanished leg reappear pointing along `±t`.
#[inline]
fn kink_residuals(g: &ProblemRef, e: &Eval, i: usize, back: Vec2) -> (f64, f64) {
    let w = g.slowness;
    let tiny = e.vanish;
    // Moving forward the point follows its segment's tangent `t`, moving back `back` (the
    // same, or the previous segment's tangent when the point sits on a vertex).
    let one_sided = |t: Vec2, forward: bool| {
        let sign = if forward { 1.0 } else { -1.0 };
        // Arriving leg i: its direction becomes ±t; leaving leg i + 1: ∓t.
        let a = if e.len[i] <= tiny {
            sign * w[i]
        } else {
            w[i] * e.u[i].dot(t)
        };
        let b = if e.len[i + 1] <= tiny {
            -sign * w[i + 1]
        } else {
            w[i + 1] * e.u[i + 1].dot(t)
        };
        a - b
    };
    (one_sided(back, false), one_sided(e.tan[i], true))
}

/// If point `i` is the first or last interaction, the source or receiver lies on segment `j`
/// of its polyline, and the trial step passes over that end point's parameter: the parameter.
/// (On a closed polyline the step is the shorter way from `s` to `s_try`: steps are capped at a
/// quarter of its length.)
#[inline]
fn end_point_between(g: &ProblemRef, ws: &NewtonWorkspace, i: usize, j: usize) -> Option<f64> {
    let k = g.k();
    let line = g.line(i);
    let Segment { start: a, end: b } = line.segment(j);
    let tiny = ws.eval.vanish;
    let on_segment = |p: crate::geom::Point| -> Option<f64> {
        let t = line.tangent(j);
        // Off the segment's line (nearly always): nothing more to compute.
        if (p - a).cross(t).abs() > tiny {
            return None;
        }
        let along = (p - a).dot(t);
        (along >= 0.0 && along <= (b - a).length()).then(|| line.start(j) + along)
    };
    let passes = |p: crate::geom::Point| -> Option<f64> {
        let sp = on_segment(p)?;
        let (from, to) = (ws.s[i], ws.s_try[i]);
        let passed = if line.is_closed() {
            let l = line.length();
            let mut d = to - from;
            if d > 0.5 * l {
                d -= l;
            } else if d < -0.5 * l {
                d += l;
            }
            let (ahead, behind) = ((sp - from).rem_euclid(l), (from - sp).rem_euclid(l));
            (d > 0.0 && ahead > 0.0 && ahead < d) || (d < 0.0 && behind > 0.0 && behind < -d)
        } else {
            let (lo, hi) = if from <= to { (from, to) } else { (to, from) };
            sp > lo && sp < hi
        };
        passed.then_some(sp)
    };
    let from_source = if i == 0 { passes(g.source) } else { None };
    from_source.or_else(|| if i + 1 == k { passes(g.receiver) } else { None })
}

/// A hash of the iteration's state: parameters (with `params`), segments, pins, held flags, and
/// the loop's flags.
fn state_hash(
    ws: &NewtonWorkspace,
    k: usize,
    flags: &[bool],
    polishes: usize,
    params: bool,
) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut mix = |x: u64| {
        h = (h ^ x).wrapping_mul(0x0000_0100_0000_01b3);
        h ^= h >> 29;
    };
    for i in 0..k {
        if params {
            mix(ws.s[i].to_bits());
        }
        mix(ws.seg[i] as u64);
        mix(ws.pin[i] as u64 | (ws.sticky[i] as u64) << 8);
    }
    for &f in flags {
        mix(f as u64);
    }
    mix(polishes as u64);
    h
}

/// Whether the source (for the first point) or the receiver (for the last) lies within `tiny`
/// of polyline `i`'s bounding box: else neither lies on one of its segments (the quick test
/// before [`end_point_between`]).
#[inline]
fn end_near_line(g: &ProblemRef, i: usize, tiny: f64) -> bool {
    let b = g.line(i).bbox();
    let near = |p: Point| {
        p.x >= b.min.x - tiny
            && p.x <= b.max.x + tiny
            && p.y >= b.min.y - tiny
            && p.y <= b.max.y + tiny
    };
    (i == 0 && near(g.source)) || (i + 1 == g.k() && near(g.receiver))
}

/// The parameter of vertex `v` (where segment `v` starts) seen from segment `seg` (`v` or the
/// segment before it): on a closed polyline vertex 0 is at `length` from the last segment.
#[inline]
fn vertex_param(g: &ProblemRef, i: usize, v: usize, seg: usize) -> f64 {
    let line = g.line(i);
    if seg == v {
        line.start(v)
    } else {
        line.start(seg + 1)
    }
}

/// If free point `i` sits exactly on the vertex that its trial step crosses (from `ws.seg[i]` to
/// `ws.seg_try[i]`), with a kink of `T` there at the present positions of the others (the
/// residuals on the two segments, from `ws.eval`, do not agree in sign: a point held there
/// would stay), that vertex (the segment starting there).
fn held_on_vertex(g: &ProblemRef, ws: &NewtonWorkspace, i: usize) -> Option<usize> {
    let e = &ws.eval;
    let v = single_vertex_between(g, i, ws.seg[i], ws.seg_try[i])?;
    let on_vertex = ws.s[i] == vertex_param(g, i, v, ws.seg[i]);
    let kink = e.r[i] * residual_on(g, e, i, ws.seg_try[i]) <= 0.0;
    (on_vertex && kink && !leg_vanished(&e.len, i, e.vanish)).then_some(v)
}

/// If `from → to` crosses exactly one vertex of polyline `i`, the segment that starts there.
#[inline]
fn single_vertex_between(g: &ProblemRef, i: usize, from: usize, to: usize) -> Option<usize> {
    let line = g.line(i);
    let n = line.num_segments();
    if to == from + 1 || (line.is_closed() && from == n - 1 && to == 0) {
        Some(to)
    } else if from == to + 1 || (line.is_closed() && to == n - 1 && from == 0) {
        Some(from)
    } else {
        None
    }
}

/// Whether point `i`, held at an end, stays held: its residual points outside, or a leg next
/// to it has vanished (two interactions meeting at a corner are no specular path).
#[inline]
fn stays_at_end(e: &Eval, i: usize, pin: Pin, margin: f64) -> bool {
    match pin {
        Pin::Start => e.r[i] > margin || leg_vanished(&e.len, i, e.vanish),
        Pin::End => e.r[i] < -margin || leg_vanished(&e.len, i, e.vanish),
        _ => false,
    }
}

/// Whether every free point's residual is within the tolerance plus what round-off of its
/// position produces: `|rᵢ| ≤ tol (wᵢ + wᵢ₊₁) + 8ε (aᵢ |Hᵢᵢ| + wᵢ + wᵢ₊₁)`, `aᵢ` the largest of
/// `|sᵢ|` and the point's coordinates relative to the source (a move of the point by a few
/// units in the last place of either moves `rᵢ` by `|Hᵢᵢ|` times that). Far from the origin or
/// the source, or where `H` is nearly singular (grazing legs, legs of 1e-9 between points far
/// from the source), no representable parameter may have a residual below the tolerance;
/// there the iteration stops as it would at the tolerance.
fn at_round_off_floor(e: &Eval, s: &[f64], pin: &[Pin], w: &[f64], tol: f64) -> bool {
    (0..s.len()).all(|i| {
        let scale = w[i] + w[i + 1];
        // The point's position carries the round-off of its parameter and of its coordinates
        // relative to the source (`Polyline::offset_on`): far from the source, between two
        // short legs, the second is the larger.
        let p = e.rel[i + 1];
        let at = s[i].abs().max(p.x.abs()).max(p.y.abs());
        pin[i] != Pin::Free
            || e.r[i].abs() <= tol * scale + 8.0 * f64::EPSILON * (at * e.diag[i].abs() + scale)
    })
}

/// Fallback when the Newton system is singular: Levenberg damping relative to the
/// Hessian's natural scale `w/ℓ`, and failing that a scaled steepest-descent step. Leaves
/// `x` with `H x ≈ r` in `ws.delta` (the caller negates it).
#[cold]
fn damped_step(g: &ProblemRef, ws: &mut NewtonWorkspace) {
    let k = g.k();
    let w = g.slowness;
    let e = &ws.eval;
    let mut mu = 1e-10;
    while mu <= 1.0 {
        for i in 0..k {
            let free = ws.pin[i] == Pin::Free;
            ws.rhs[i] = if free { e.r[i] } else { 0.0 };
            let d = if free { e.diag[i] } else { 1.0 };
            let nat = w[i] / e.len[i].max(f64::MIN_POSITIVE)
                + w[i + 1] / e.len[i + 1].max(f64::MIN_POSITIVE);
            ws.diag[i] = if free {
                d + mu * nat.min(1e300) * if d < 0.0 { -1.0 } else { 1.0 }
            } else {
                1.0
            };
            if i + 1 < k {
                ws.off[i] = if free && ws.pin[i + 1] == Pin::Free {
                    e.off[i]
                } else {
                    0.0
                };
            }
        }
        if thomas(&ws.diag, &ws.off, &ws.rhs, &mut ws.delta, &mut ws.scratch) {
            return;
        }
        mu *= 1e3;
    }
    for i in 0..k {
        ws.delta[i] = if ws.pin[i] == Pin::Free {
            e.r[i] / (w[i] + w[i + 1]) * e.len[i].min(e.len[i + 1]).max(f64::MIN_POSITIVE) * 0.5
        } else {
            0.0
        };
    }
}
