//! Damped Newton iteration on the stationarity residual, with vertex pinning and polyline ends.
//!
//! One iteration: evaluate `r = ∂T/∂s` and the tridiagonal Hessian `H` (the analytic one of
//! `problem`), solve `H δ = −r` by the Thomas algorithm in `O(k)`, cap the step so that no
//! point moves further than its longer leg, and backtrack on the merit function
//! `φ = Σ (rᵢ / (wᵢ + wᵢ₊₁))²`, not on `T`: every Newton direction is a descent direction of
//! `φ`, whether the path is a minimum, a saddle or a maximum of `T`.
//!
//! Points move along their polylines across vertices. A point that the line search sees
//! jump across exactly one vertex with its residual changing sign is pinned on that vertex;
//! while pinned it stays put if the one-sided residuals `r⁻`, `r⁺` bracket zero (a kink of
//! `T`: an edge-diffracted path, reported as `vertex`) and is released to the side where `T`
//! decreases otherwise. A point already on a vertex that the step sends across it (and, from
//! the other side, back: the others move too) is held there until the others have moved, then
//! judged again. A first or last point whose step off its segment passes over the source or
//! receiver, lying on its polyline, is put there (the kink of `T` where that leg vanishes).
//! The iteration is deterministic, so a state met again would repeat for ever: from the eighth
//! iteration on, the states are hashed, and after a repeat — or, past the twelfth, a return to
//! an earlier set of segments and pins (a cycle that need not repeat exactly) — no step takes a
//! point across a vertex: the point stops on it and is held until the others have moved (an
//! active-set iteration on the corners).
//! A point pushed past the end of an open polyline is held at the end and
//! released when its residual points back inside; held there at convergence, the ray has no
//! path.
//!
//! Stopping rule: every free point has `|rᵢ| ≤ tol · (wᵢ + wᵢ₊₁)` (a relative, dimensionless
//! residual: the difference of the sines in Snell's law), or the full Newton step is below
//! round-off (`|δᵢ| ≤ 4ε (|sᵢ| + ℓᵢ + ℓᵢ₊₁)`: no representable parameter is closer), or the
//! line search has stalled with every residual within what round-off of its position produces
//! (`|rᵢ| ≤ tol (wᵢ + wᵢ₊₁) + 8ε (aᵢ |Hᵢᵢ| + wᵢ + wᵢ₊₁)`, `aᵢ` the largest of `|sᵢ|` and the
//! point's coordinates relative to the source; see `at_round_off_floor`: far from the origin or
//! the source, or along grazing legs, the tolerance itself may be out of reach).

use crate::geom::{Point, Vec2};
pub(crate) use crate::problem::Pin;
use crate::problem::{
    Eval, Frame, Geometry, Single, finite, leg_vanished, max_num, min_num, sweep_row,
};

/// How the iteration ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// Stationary with every point free.
    Converged,
    /// Stationary with at least one point held on a vertex.
    Vertex,
    /// The others are stationary but a point is held at an open polyline's end: no path.
    LeftEnd(usize),
    /// Gave up (iteration limit).
    NotConverged,
}

/// The summary of one solve (the points are in the [`Workspace`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solution {
    /// Travel time at the final points.
    pub time: f64,
    /// Iterations used.
    pub iterations: usize,
    /// Final relative residual: `maxᵢ |∂T/∂sᵢ| / (wᵢ + wᵢ₊₁)` over free points.
    pub residual: f64,
}

/// Reusable scratch space for solving rays: once it has grown to the longest path, solving
/// allocates nothing. Use one per thread.
#[derive(Clone, Debug, Default)]
pub struct Workspace {
    pub(crate) s: Vec<f64>,
    pub(crate) seg: Vec<usize>,
    pub(crate) pin: Vec<Pin>,
    s_try: Vec<f64>,
    seg_try: Vec<usize>,
    pin_try: Vec<Pin>,
    /// Per point: pinned on a vertex that it was being sent across and back over; kept there
    /// until the others have moved (see `solve`).
    sticky: Vec<bool>,
    // Boxed, so that accepting a trial swaps two pointers, not two dozen vectors.
    pub(crate) eval: Box<Eval>,
    eval_try: Box<Eval>,
    delta: Vec<f64>,
    rhs: Vec<f64>,
    diag: Vec<f64>,
    off: Vec<f64>,
    scratch: Vec<f64>,
    pub(crate) slowness: Vec<f64>,
    pub(crate) media: Vec<usize>,
    pub(crate) media_prev: Vec<usize>,
    pub(crate) s_alt: Vec<f64>,
    /// Per step of the initial guess: the fraction of `S → R` where that line crosses the
    /// step's interface (NaN where it does not, or for a reflection).
    pub(crate) crossing_t: Vec<f64>,
    pub(crate) seg_alt: Vec<usize>,
    /// Per layer of the initial guess's ray-parameter refinement: thickness, speed, and the
    /// lateral offset across it at the ray parameter found.
    pub(crate) layers: Vec<crate::trace::Layer>,
    pub(crate) points: Vec<Point>,
    frames: Vec<Frame>,
}

impl Workspace {
    /// An empty workspace.
    pub fn new() -> Workspace {
        Workspace::default()
    }

    /// Source, interaction points and receiver of the last solved ray.
    pub fn points(&self) -> &[Point] {
        &self.points
    }

    /// Interaction parameters (arclengths) of the last solved ray.
    pub fn parameters(&self) -> &[f64] {
        &self.s
    }

    /// Leg media of the last solved ray (empty when they were not looked up or given).
    pub fn media(&self) -> &[usize] {
        &self.media
    }

    /// Sizes the workspace for a path of `k` interactions.
    #[inline]
    pub(crate) fn resize(&mut self, k: usize) {
        if self.s.len() != k || self.eval.rel.len() != k + 2 {
            self.resize_to(k);
        }
    }

    /// [`resize`](Self::resize) when the sizes change (the first ray of a path of another
    /// length).
    #[inline(never)]
    fn resize_to(&mut self, k: usize) {
        self.s.resize(k, 0.0);
        self.seg.resize(k, 0);
        self.pin.resize(k, Pin::Free);
        self.s_try.resize(k, 0.0);
        self.seg_try.resize(k, 0);
        self.pin_try.resize(k, Pin::Free);
        self.sticky.resize(k, false);
        self.eval.resize(k);
        self.eval_try.resize(k);
        self.delta.resize(k, 0.0);
        self.rhs.resize(k, 0.0);
        self.diag.resize(k, 0.0);
        self.off.resize(k.saturating_sub(1), 0.0);
        self.scratch.resize(k, 0.0);
        self.s_alt.resize(k, 0.0);
        self.crossing_t.resize(k, f64::NAN);
        self.seg_alt.resize(k, 0);
        // Room for the classification and the media lookups, so that no ray allocates.
        self.media.reserve(k + 1);
        self.media_prev.reserve(k + 1);
        self.slowness.reserve(k + 1);
        self.points.reserve(k + 2);
        self.layers.reserve(k + 1);
        self.frames.reserve(k);
    }
}

/// Solves `A x = d` for symmetric tridiagonal `A` (`diag`, `off`) by the Thomas algorithm.
/// Returns `false` on a pivot that is zero, not finite, or tiny against the row scale.
pub(crate) fn thomas(diag: &[f64], off: &[f64], d: &[f64], x: &mut [f64], cp: &mut [f64]) -> bool {
    let n = diag.len();
    if n == 0 {
        return true;
    }
    // Exact-length views (no bounds checks below); the last row has no super-diagonal.
    let (diag, off, d) = (&diag[..n], &off[..n - 1], &d[..n]);
    let (x, cp) = (&mut x[..n], &mut cp[..n]);
    let (mut prev_c, mut prev_x, mut sub) = (0.0, 0.0, 0.0);
    let mut ok = true;
    for i in 0..n {
        let sup = if i + 1 < n { off[i] } else { 0.0 };
        let (c, xi, pivot_ok) = sweep_row(diag[i], sub, sup, d[i], prev_c, prev_x);
        // Non-short-circuiting: one branch after the loop instead of one per row.
        ok &= pivot_ok;
        cp[i] = c;
        x[i] = xi;
        (prev_c, prev_x, sub) = (c, xi, sup);
    }
    if !ok {
        return false;
    }
    let mut finite = x[n - 1].is_finite();
    for i in (0..n - 1).rev() {
        x[i] -= cp[i] * x[i + 1];
        finite &= x[i].is_finite();
    }
    finite
}

/// Moves point `i` to parameter `s` (wrapping or holding at an end), updating its segment.
#[inline]
fn place(g: &Geometry, i: usize, s: f64, hint: usize) -> (f64, usize, Pin) {
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
fn segment_before(g: &Geometry, i: usize, j: usize) -> Option<usize> {
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
fn segment_behind_vertex(g: &Geometry, s: &[f64], seg: &[usize], i: usize) -> Option<usize> {
    if s[i] == g.line(i).start(seg[i]) {
        segment_before(g, i, seg[i])
    } else {
        None
    }
}

/// Residual of point `i` as if its tangent were that of segment `j`.
#[inline]
fn residual_on(g: &Geometry, e: &Eval, i: usize, j: usize) -> f64 {
    let t = g.line(i).tangent(j);
    (e.u[i] * g.slowness[i] - e.u[i + 1] * g.slowness[i + 1]).dot(t)
}

/// One-sided residuals `(r⁻, r⁺)` of point `i` next to a vanished leg: moving the point
/// along its tangent `t` makes the vanished leg reappear pointing along `±t`.
#[inline]
fn kink_residuals(g: &Geometry, e: &Eval, i: usize, back: Vec2) -> (f64, f64) {
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
fn end_point_between(g: &Geometry, ws: &Workspace, i: usize, j: usize) -> Option<f64> {
    let k = g.k();
    let line = g.line(i);
    let (a, b) = line.segment(j);
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
fn state_hash(ws: &Workspace, k: usize, flags: &[bool], polishes: usize, params: bool) -> u64 {
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
fn end_near_line(g: &Geometry, i: usize, tiny: f64) -> bool {
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
fn vertex_param(g: &Geometry, i: usize, v: usize, seg: usize) -> f64 {
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
fn held_on_vertex(g: &Geometry, ws: &Workspace, i: usize) -> Option<usize> {
    let e = &ws.eval;
    let v = single_vertex_between(g, i, ws.seg[i], ws.seg_try[i])?;
    let on_vertex = ws.s[i] == vertex_param(g, i, v, ws.seg[i]);
    let kink = e.r[i] * residual_on(g, e, i, ws.seg_try[i]) <= 0.0;
    (on_vertex && kink && !leg_vanished(&e.len, i, e.vanish)).then_some(v)
}

/// If `from → to` crosses exactly one vertex of polyline `i`, the segment that starts there.
#[inline]
fn single_vertex_between(g: &Geometry, i: usize, from: usize, to: usize) -> Option<usize> {
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

/// The merit `Σ (rᵢ / (wᵢ + wᵢ₊₁))²` at the parameters in `ws` (all points free).
pub(crate) fn merit_at(g: &Geometry, ws: &mut Workspace) -> f64 {
    g.evaluate(&ws.s, &ws.seg, &ws.pin, &mut ws.eval, false, false);
    ws.eval.phi
}

/// Runs the iteration from the parameters, segments and pins already in `ws` (set by the
/// initial guess). Leaves the final state in `ws` (`s`, `seg`, `pin`, `eval`).
pub(crate) fn solve(
    g: &Geometry,
    ws: &mut Workspace,
    tol: f64,
    max_iterations: usize,
) -> (Outcome, Solution) {
    let k = g.k();
    let w = g.slowness;
    let mut fast = Fast::START;
    #[cfg(test)]
    let general_only = tests::GENERAL_ONLY.with(|c| c.get());
    #[cfg(not(test))]
    let general_only = false;
    if !general_only && ws.pin[..k].iter().all(|&p| p == Pin::Free) {
        let done = match k {
            0 => None,
            1 => fast_newton_single(g, ws, tol, max_iterations, &mut fast),
            _ => {
                ws.frames.clear();
                ws.frames
                    .extend((0..k).map(|i| Frame::new(g.line(i), ws.seg[i], g.source)));
                fast_newton(g, ws, tol, max_iterations, &mut fast)
            }
        };
        if let Some(done) = done {
            return done;
        }
    }
    let Fast {
        mut iterations,
        mut curvature,
        mut evaluated,
        mut polishes,
    } = fast;
    // Set once a vertex or an end point was met: from then on the exact segment-wise model
    // (no curvature estimate), which is right near a kink of T.
    let mut near_kink = false;
    // Releases and pins do not move the others; bound them so that a ring of releases and
    // re-pins cannot spin for ever between counted iterations.
    let mut free_moves = 0;
    // Set when the last step was the non-monotone fallback (no trial lowered the merit): the
    // iteration has stalled, perhaps at the round-off floor of the residual.
    let mut stalled = false;
    ws.sticky[..k].fill(false);
    // Whether some point is held in `ws.sticky`.
    let mut any_sticky = false;
    // Hashes of the states the iteration has been in (the last `seen.len()`), to catch a cycle:
    // the iteration is deterministic, so a state met again repeats for ever. After one, no step
    // takes a point across a vertex (see below).
    let mut seen = [0u64; 32];
    let mut states = 0;
    let mut cautious = false;
    // Likewise the segments and pins alone, each time they change: past the twelfth iteration,
    // coming back to an earlier set is a cycle too (one that need not repeat exactly).
    let mut seen_sets = [0u64; 32];
    let (mut sets, mut last_set) = (0, 0u64);
    loop {
        if !evaluated {
            g.evaluate(&ws.s, &ws.seg, &ws.pin, &mut ws.eval, true, curvature);
        }
        evaluated = false;
        let e = &ws.eval;

        // Held points: keep, or release towards decreasing T.
        if e.held > 0 {
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
            if released && free_moves < 4 * max_iterations {
                free_moves += 1;
                continue;
            }
        }

        // Free points next to a vanished leg sit on a kink of T: hold them if the one-sided
        // residuals bracket zero, else let them move by the residual of the way down.
        if ws.eval.vanished > 0 {
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
            if pinned && free_moves < 4 * max_iterations {
                free_moves += 1;
                continue;
            }
        }
        let e = &ws.eval;

        let residual = e.rmax;
        if residual <= tol && e.held == k {
            return finished(ws, iterations);
        }
        if !residual.is_finite() || iterations >= max_iterations {
            return (
                Outcome::NotConverged,
                Solution {
                    time: e.time,
                    iterations,
                    residual,
                },
            );
        }

        if iterations >= 8 && !cautious {
            // (`any_sticky` follows from the held flags, which the hash includes.)
            let flags = [curvature, near_kink, stalled];
            let h = state_hash(ws, k, &flags, polishes, true);
            if seen[..states.min(seen.len())].contains(&h) {
                cautious = true;
            } else {
                seen[states % seen.len()] = h;
                states += 1;
            }
            let set = state_hash(ws, k, &[], 0, false);
            if set != last_set {
                if iterations >= 12 && seen_sets[..sets.min(seen_sets.len())].contains(&set) {
                    cautious = true;
                }
                seen_sets[sets % seen_sets.len()] = set;
                sets += 1;
                last_set = set;
            }
        }

        // Newton system H δ = −r on the free points (solved as H x = r, δ = −x).
        let ok = if e.held == 0 {
            thomas(&e.diag, &e.off, &e.r, &mut ws.delta, &mut ws.scratch)
        } else {
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
        };
        if !ok {
            damped_step(g, ws);
        }

        // Negate; round-off floor (the full step cannot move any point to another float);
        // cap (no point moves further than its longer leg, nor a quarter way round a closed
        // polyline).
        let e = &ws.eval;
        let mut tiny = true;
        let mut cap: f64 = 1.0;
        for i in 0..k {
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
        if (tiny || residual <= tol) && any_sticky && free_moves < 4 * max_iterations {
            // The others are stationary: judge the points held on the way again.
            ws.sticky[..k].fill(false);
            any_sticky = false;
            free_moves += 1;
            continue;
        }
        if tiny {
            return finished(ws, iterations);
        }
        if residual <= tol || (stalled && at_round_off_floor(e, &ws.s, &ws.pin, w, tol)) {
            // Stationary to tolerance. Where T is flat along the solution (grazing legs, a
            // nearly singular H) the residual allows a point error of about tol / λmin; stop
            // only if the Newton correction is small against the legs, else take it (once
            // more at most: Newton converges quadratically from here).
            let small = (0..k).all(|i| {
                ws.pin[i] != Pin::Free
                    || ws.delta[i].abs() <= tol.sqrt() * (e.len[i] + e.len[i + 1])
            });
            if small || polishes >= 2 {
                return finished(ws, iterations);
            }
            polishes += 1;
        }
        iterations += 1;

        let phi0 = e.phi;
        let mut alpha = cap;
        let mut accepted = false;
        let mut pinned = false;
        let mut best: Option<(f64, f64)> = None;
        for attempt in 0..40 {
            let mut crossed = false;
            for i in 0..k {
                if ws.pin[i] == Pin::Free {
                    let (s, seg, pin) = place(g, i, ws.s[i] + alpha * ws.delta[i], ws.seg[i]);
                    ws.s_try[i] = s;
                    ws.seg_try[i] = seg;
                    ws.pin_try[i] = pin;
                    crossed |= seg != ws.seg[i];
                } else {
                    ws.s_try[i] = ws.s[i];
                    ws.seg_try[i] = ws.seg[i];
                    ws.pin_try[i] = ws.pin[i];
                }
            }
            if cautious && crossed {
                // After a cycle, points stop on the vertices they reach, one at a time, and are
                // held there until the others have moved (an active-set iteration on the
                // corners); a point that would cross several takes a shorter step.
                let mut several = false;
                let mut first = None;
                for i in 0..k {
                    if ws.pin[i] == Pin::Free
                        && ws.pin_try[i] == Pin::Free
                        && ws.seg_try[i] != ws.seg[i]
                    {
                        match single_vertex_between(g, i, ws.seg[i], ws.seg_try[i]) {
                            Some(v) => {
                                first.get_or_insert((i, v));
                            }
                            None => several = true,
                        }
                    }
                }
                if several && attempt < 39 {
                    alpha *= 0.5;
                    continue;
                }
                if let Some((i, v)) = first {
                    ws.s[i] = vertex_param(g, i, v, v);
                    ws.seg[i] = v;
                    ws.pin[i] = Pin::Vertex;
                    ws.sticky[i] = true;
                    any_sticky = true;
                    pinned = true;
                    break;
                }
            }
            g.evaluate(
                &ws.s_try,
                &ws.seg_try,
                &ws.pin_try,
                &mut ws.eval_try,
                true,
                crossed && !near_kink,
            );
            let phi = ws.eval_try.phi;
            // A residual that changes sign while its point crosses vertices has jumped a
            // kink of T or a root: never accepted on the merit alone. Across several
            // vertices with a corner among them: backtrack (across the small turns of a
            // digitised curve, on the merit). Across one: look at the vertex itself.
            let (mut flip_far, mut flip_one) = (false, None);
            for i in 0..k {
                if ws.pin[i] != Pin::Free
                    || ws.pin_try[i] != Pin::Free
                    || ws.seg_try[i] == ws.seg[i]
                {
                    continue;
                }
                if ws.eval_try.r[i] * ws.eval.r[i] < 0.0 {
                    if single_vertex_between(g, i, ws.seg[i], ws.seg_try[i]).is_some() {
                        flip_one.get_or_insert(i);
                    } else if !g.line(i).smooth_between(ws.seg[i], ws.seg_try[i]) {
                        flip_far = true;
                    }
                }
            }
            // A step off its segment that passes over the source or receiver, lying on the
            // segment left or the one reached (on a vertex, say), passes over a kink of T
            // (where the leg vanishes): put the point there; the kink test decides the rest.
            let ends: &[usize] = match k {
                0 => &[],
                1 => &[0],
                _ => &[0, k - 1],
            };
            // (Within one segment the test comes below, only for a trial the merit rejects: the
            // fast paths accept such steps on the merit alone, and must take the same ones.)
            let passed_end = ends.iter().find_map(|&i| {
                let moved = ws.pin[i] == Pin::Free
                    && ws.pin_try[i] == Pin::Free
                    && ws.seg_try[i] != ws.seg[i];
                if !moved || !end_near_line(g, i, ws.eval.vanish) {
                    return None;
                }
                end_point_between(g, ws, i, ws.seg[i])
                    .or_else(|| end_point_between(g, ws, i, ws.seg_try[i]))
                    .map(|sp| (i, sp))
            });
            if let Some((i, sp)) = passed_end {
                ws.s[i] = sp;
                ws.seg[i] = g.line(i).segment_at_hint(sp, ws.seg[i]);
                pinned = true;
                break;
            }
            let merit_ok = phi.is_finite() && phi <= (1.0 - 1e-4 * alpha) * phi0;
            if merit_ok && !flip_far && flip_one.is_none() {
                accepted = true;
                curvature = crossed && !near_kink;
                break;
            }
            if phi.is_finite() && !flip_far && best.is_none_or(|(_, b)| phi < b) {
                best = Some((alpha, phi));
            }
            // The vertex: if the residual does not change sign before it on the current
            // segment, the point goes onto the vertex, held there if the residual changes sign
            // across it (a kink of T) and moved on into the new segment otherwise. The merit
            // is discontinuous at a vertex, so backtracking alone would only creep towards it.
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
                let v =
                    single_vertex_between(g, i, ws.seg[i], ws.seg_try[i]).unwrap_or(ws.seg_try[i]);
                let (s_new, seg_new) = (ws.s_try[i], ws.seg_try[i]);
                let residual_at = |seg: usize, ws: &mut Workspace| {
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
                        any_sticky |= ws.sticky[i];
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
                    if ws.pin[i] == Pin::Free && ws.seg_try[i] == ws.seg[i] {
                        if let Some(sp) = end_point_between(g, ws, i, ws.seg[i]) {
                            ws.s[i] = sp;
                            pinned = true;
                            break;
                        }
                    }
                }
            }
            if pinned || attempt == 39 {
                break;
            }
            alpha *= 0.5;
        }
        if pinned {
            curvature = false;
            near_kink = true;
            continue;
        }
        stalled = false;
        if accepted {
            // The trial was evaluated with the curvature flag of the next iteration: reuse it.
            std::mem::swap(&mut ws.eval, &mut ws.eval_try);
            evaluated = true;
        } else {
            if curvature {
                // The curvature model misled the step; retry on the exact segment-wise model.
                curvature = false;
                continue;
            }
            // Non-monotone fallback: take the best trial so that the iteration moves on.
            stalled = true;
            let Some((a, _)) = best else {
                let e = &ws.eval;
                return (
                    Outcome::NotConverged,
                    Solution {
                        time: e.time,
                        iterations,
                        residual: e.rmax,
                    },
                );
            };
            let mut crossed = false;
            for i in 0..k {
                if ws.pin[i] == Pin::Free {
                    let (s, seg, pin) = place(g, i, ws.s[i] + a * ws.delta[i], ws.seg[i]);
                    ws.s_try[i] = s;
                    ws.seg_try[i] = seg;
                    ws.pin_try[i] = pin;
                    crossed |= seg != ws.seg[i];
                }
            }
            curvature = crossed && !near_kink;
        }
        std::mem::swap(&mut ws.s, &mut ws.s_try);
        std::mem::swap(&mut ws.seg, &mut ws.seg_try);
        std::mem::swap(&mut ws.pin, &mut ws.pin_try);
        // The others have moved: the held points are judged again.
        if any_sticky {
            ws.sticky[..k].fill(false);
            any_sticky = false;
        }
    }
}

/// The iteration state that the fast path hands on to the general loop.
struct Fast {
    /// Newton steps taken.
    iterations: usize,
    /// Whether the next evaluation adds the curvature estimate.
    curvature: bool,
    /// Whether `ws.eval` holds the evaluation at `ws.s`.
    evaluated: bool,
    /// Newton steps taken after the residual met the tolerance.
    polishes: usize,
}

impl Fast {
    /// Before the first step: nothing evaluated, the curvature estimate on.
    const START: Fast = Fast {
        iterations: 0,
        curvature: true,
        evaluated: false,
        polishes: 0,
    };
}

/// The common case of [`solve`], without its bookkeeping: every point free and every full
/// Newton step staying inside the segments the points are on, with no leg vanishing. Takes
/// exactly the steps the general loop would take there (same arithmetic, same tests), on
/// the points' segment frames prepared once in `ws.frames`, and hands over (`None`, with
/// `fast` updated) at the first iteration that needs more: a step leaving a segment or
/// capped, a rejected full step, a vanished leg, a singular Hessian.
#[inline(always)]
fn fast_newton(
    g: &Geometry,
    ws: &mut Workspace,
    tol: f64,
    max_iterations: usize,
    fast: &mut Fast,
) -> Option<(Outcome, Solution)> {
    let k = g.k();
    // `evaluate_passes` leaves the tangents to us: they are the frames'.
    for (i, f) in ws.frames.iter().enumerate() {
        ws.eval.tan[i] = f.t;
        ws.eval_try.tan[i] = f.t;
    }
    loop {
        if !fast.evaluated {
            g.evaluate_passes(&ws.s, &ws.frames, &mut ws.eval, fast.curvature);
            fast.evaluated = true;
        }
        let e = &ws.eval;
        if e.vanished > 0 {
            return None;
        }
        let residual = e.rmax;
        if !finite(residual) || fast.iterations >= max_iterations {
            return Some((
                Outcome::NotConverged,
                Solution {
                    time: e.time,
                    iterations: fast.iterations,
                    residual,
                },
            ));
        }
        if !e.factored {
            // A tiny pivot: the general loop takes the damped step.
            return None;
        }
        // Back substitution of `thomas` (x = H⁻¹ r, the step is −x), fused with the step's
        // tests: round-off floor, and whether the full step stays inside every segment.
        let (s, delta, frames) = (&ws.s[..k], &mut ws.delta[..k], &ws.frames[..k]);
        let (len, s_try, cp, y) = (&e.len[..k + 1], &mut ws.s_try[..k], &e.cp[..k], &e.y[..k]);
        let mut all_finite = true;
        let mut tiny = true;
        let mut inside = true;
        let mut x = 0.0;
        for i in (0..k).rev() {
            x = if i + 1 == k { y[i] } else { y[i] - cp[i] * x };
            all_finite &= finite(x);
            let d = -x;
            delta[i] = d;
            tiny &= d.abs() <= 4.0 * f64::EPSILON * (s[i].abs() + len[i] + len[i + 1]);
            let to = s[i] + d;
            s_try[i] = to;
            let f = &frames[i];
            // Leg lengths are never NaN here (the points are finite): the plain max and min.
            inside &= to > f.lo
                && to < f.hi
                && d.abs() <= min_num(max_num(len[i], len[i + 1]), f.quarter);
        }
        if !all_finite {
            return None;
        }
        if tiny {
            return Some(finished(ws, fast.iterations));
        }
        if !inside {
            return None;
        }
        let polish = residual <= tol;
        if polish {
            let small = (0..k).all(|i| delta[i].abs() <= tol.sqrt() * (len[i] + len[i + 1]));
            if small || fast.polishes >= 2 {
                return Some(finished(ws, fast.iterations));
            }
        }
        let phi0 = e.phi;
        g.evaluate_passes(&ws.s_try, &ws.frames, &mut ws.eval_try, false);
        let phi = ws.eval_try.phi;
        if !(finite(phi) && phi <= (1.0 - 1e-4) * phi0) {
            // The general loop backtracks from here (it evaluates this trial again).
            return None;
        }
        fast.polishes += polish as usize;
        fast.iterations += 1;
        fast.curvature = false;
        std::mem::swap(&mut ws.eval, &mut ws.eval_try);
        std::mem::swap(&mut ws.s, &mut ws.s_try);
    }
}

/// [`fast_newton`] from the start in `ws` (every point free) on frames prepared elsewhere
/// (`frames`: those [`Frame::new`] gives for the points' segments), with a fresh iteration
/// state: the same steps. For callers that keep a path's segments at hand.
#[inline(always)]
pub(crate) fn fast_newton_from(
    g: &Geometry,
    frames: impl Iterator<Item = Frame>,
    ws: &mut Workspace,
    tol: f64,
    max_iterations: usize,
) -> Option<(Outcome, Solution)> {
    debug_assert!(ws.pin[..g.k()].iter().all(|&p| p == Pin::Free));
    ws.frames.clear();
    ws.frames.extend(frames);
    let mut fast = Fast::START;
    fast_newton(g, ws, tol, max_iterations, &mut fast)
}

/// [`fast_newton`] for a path of one interaction, in registers: the same steps and tests.
fn fast_newton_single(
    g: &Geometry,
    ws: &mut Workspace,
    tol: f64,
    max_iterations: usize,
    fast: &mut Fast,
) -> Option<(Outcome, Solution)> {
    // Called first in a solve: no step taken yet, the curvature on.
    debug_assert!(fast.iterations == 0 && fast.polishes == 0 && fast.curvature);
    let f = &Frame::new(g.line(0), ws.seg[0], g.source);
    let w = [g.slowness[0], g.slowness[1]];
    let (to_receiver, coord) = (g.receiver - g.source, g.coord());
    let mut it = SingleIter::start(ws.s[0], f, w, to_receiver, coord);
    let done = loop {
        match it.next(f, tol, max_iterations) {
            SingleNext::Try { to, polish } => {
                let trial = Geometry::evaluate_single(to, f, w, to_receiver, coord, false);
                if !it.accept(to, polish, trial) {
                    break None;
                }
            }
            SingleNext::End(outcome) => break Some(outcome),
            SingleNext::General => break None,
        }
    };
    ws.s[0] = it.s;
    it.e.store(f, to_receiver, &mut ws.eval);
    fast.iterations = it.iterations;
    fast.polishes = it.polishes;
    fast.curvature = it.iterations == 0;
    fast.evaluated = true;
    done.map(|outcome| (outcome, it.solution()))
}

/// The iteration of [`fast_newton`] for one interaction as a state and its steps: the same
/// tests in the same order, the same arithmetic, in registers. [`fast_newton_single`] drives
/// it for a solve with a workspace, the batches' one-interaction chains without one.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SingleIter {
    /// The parameter.
    pub s: f64,
    /// The evaluation at `s`.
    pub e: Single,
    /// Newton steps taken.
    pub iterations: usize,
    /// Newton steps taken after the residual met the tolerance.
    pub polishes: usize,
}

/// What [`SingleIter::next`] decided.
#[derive(Clone, Copy, Debug)]
pub(crate) enum SingleNext {
    /// The solve ends with this outcome.
    End(Outcome),
    /// The general loop must take over from here.
    General,
    /// Evaluate at `to` and [`accept`](SingleIter::accept) the step (`polish`: the residual
    /// already met the tolerance).
    Try { to: f64, polish: bool },
}

impl SingleIter {
    /// The state at the start parameter `s` on the segment `f`, before any step (its
    /// evaluation adds the curvature estimate, as the first one of a solve does).
    #[inline(always)]
    pub fn start(s: f64, f: &Frame, w: [f64; 2], to_receiver: Vec2, coord: f64) -> Self {
        SingleIter {
            s,
            e: Geometry::evaluate_single(s, f, w, to_receiver, coord, true),
            iterations: 0,
            polishes: 0,
        }
    }

    /// The tests at the present point, in the general loop's order.
    #[inline(always)]
    pub fn next(&self, f: &Frame, tol: f64, max_iterations: usize) -> SingleNext {
        let (s, e) = (self.s, &self.e);
        if e.vanished {
            return SingleNext::General;
        }
        let residual = e.rmax;
        if !finite(residual) || self.iterations >= max_iterations {
            return SingleNext::End(Outcome::NotConverged);
        }
        // `thomas` on one row.
        let x = e.r * (1.0 / e.h);
        // `thomas`'s pivot test on one row (|h| > 1e-14 |h| is h ≠ 0 for a finite h).
        if !(finite(e.h) && e.h != 0.0 && finite(x)) {
            return SingleNext::General;
        }
        let d = -x;
        if d.abs() <= 4.0 * f64::EPSILON * (s.abs() + e.len[0] + e.len[1]) {
            return SingleNext::End(Outcome::Converged);
        }
        let to = s + d;
        let reach = min_num(max_num(e.len[0], e.len[1]), f.quarter);
        if !(to > f.lo && to < f.hi && d.abs() <= reach) {
            return SingleNext::General;
        }
        let polish = residual <= tol;
        if polish && (d.abs() <= tol.sqrt() * (e.len[0] + e.len[1]) || self.polishes >= 2) {
            return SingleNext::End(Outcome::Converged);
        }
        SingleNext::Try { to, polish }
    }

    /// Takes the step to `to` evaluated as `trial` if it lowers the merit enough; `false` (and
    /// no change) hands over to the general loop.
    #[inline(always)]
    pub fn accept(&mut self, to: f64, polish: bool, trial: Single) -> bool {
        if !(finite(trial.phi) && trial.phi <= (1.0 - 1e-4) * self.e.phi) {
            return false;
        }
        self.polishes += polish as usize;
        self.iterations += 1;
        (self.s, self.e) = (to, trial);
        true
    }

    /// The solution at the present point.
    #[inline(always)]
    pub fn solution(&self) -> Solution {
        Solution {
            time: self.e.time,
            iterations: self.iterations,
            residual: self.e.rmax,
        }
    }
}

/// How the solution in `ws` moves with the receiver, to first order: after a solve that ended
/// with every point free, writes `z = H⁻¹ eₖ₋₁` into `z` and returns `g = ∂rₖ₋₁/∂R` (only the
/// last residual depends on the receiver), so that moving the receiver by `ΔR` moves the
/// parameters by `−z (g · ΔR)` (differentiating `r(s, R) = 0`). `None` when a point is held,
/// there are no interactions, or `H` is singular there. `unit` and `cp` are scratch, `k` long.
pub(crate) fn receiver_sensitivity(
    ws: &Workspace,
    z: &mut [f64],
    unit: &mut [f64],
    cp: &mut [f64],
) -> Option<Vec2> {
    let k = ws.s.len();
    let e = &ws.eval;
    if k == 0 || e.held > 0 || e.vanished > 0 || ws.slowness.len() != k + 1 {
        return None;
    }
    let g = last_residual_gradient(e.tan[k - 1], e.u[k], e.len[k], ws.slowness[k])?;
    if k == 1 {
        z[0] = pivot_inverse(e.diag[0])?;
        return Some(g);
    }
    unit[..k].fill(0.0);
    unit[k - 1] = 1.0;
    thomas(
        &e.diag[..k],
        &e.off[..k - 1],
        &unit[..k],
        &mut z[..k],
        &mut cp[..k],
    )
    .then_some(g)
}

/// [`receiver_sensitivity`] of a one-interaction solution held in registers: `(z, g)`, with
/// `t` the tangent at the point and `w` the receiver leg's slowness.
#[inline(always)]
pub(crate) fn single_sensitivity(e: &Single, t: Vec2, w: f64) -> Option<(f64, Vec2)> {
    let g = last_residual_gradient(t, e.u[1], e.len[1], w)?;
    Some((pivot_inverse(e.h)?, g))
}

/// `∂rₖ₋₁/∂R` for the last point's tangent `t`, the receiver leg's direction `u`, length `l`
/// and slowness `w`; `None` for a vanished leg.
#[inline(always)]
fn last_residual_gradient(t: Vec2, u: Vec2, l: f64, w: f64) -> Option<Vec2> {
    if l.is_nan() || l <= 0.0 {
        return None;
    }
    // r = (wₖ₋₁ uₖ₋₁ − wₖ uₖ) · t with uₖ = (R − xₖ₋₁) / ℓₖ: ∂(uₖ · t)/∂R = (t − (uₖ · t) uₖ) / ℓₖ.
    Some((t - u * u.dot(t)) * (-w / l))
}

/// `1/h` for a usable pivot `h` (`thomas`'s test on one row).
#[inline(always)]
fn pivot_inverse(h: f64) -> Option<f64> {
    let z = 1.0 / h;
    (finite(h) && h != 0.0 && finite(z)).then_some(z)
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

/// The outcome once the free points are stationary.
fn finished(ws: &Workspace, iterations: usize) -> (Outcome, Solution) {
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
    (
        outcome,
        Solution {
            time: e.time,
            iterations,
            residual: e.rmax,
        },
    )
}

/// Fallback when the Newton system is singular: Levenberg damping relative to the
/// Hessian's natural scale `w/ℓ`, and failing that a scaled steepest-descent step. Leaves
/// `x` with `H x ≈ r` in `ws.delta` (the caller negates it).
#[cold]
fn damped_step(g: &Geometry, ws: &mut Workspace) {
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::trace::Start;
    use crate::{Scene, Tracer};
    use std::cell::Cell;

    thread_local! {
        /// Set: `solve` skips its fast paths (to compare them with the general loop).
        pub(crate) static GENERAL_ONLY: Cell<bool> = const { Cell::new(false) };
        /// Set: one-refraction paths at a flat interface skip their kernel (its steps are not
        /// the general ones; `trace::flat`'s tests compare it with them to a tolerance).
        pub(crate) static FLAT_OFF: Cell<bool> = const { Cell::new(false) };
    }

    /// Every ray of `scene`, solved with and without the fast paths (the one-interaction
    /// kernel and the fast Newton loops; not the flat-refraction kernel, whose steps differ),
    /// from the default start, from a warm start compared with it and from a given start (the
    /// previous receiver's solution, moved): the same rays, bit for bit (status, time,
    /// iterations, residual, reason, points, media). Returns the number of rays.
    pub(crate) fn fast_paths_agree(scene: &Scene) -> usize {
        type Outcome = (crate::Status, u64, usize, u64, Option<crate::Reason>);
        type Rays = Vec<(Outcome, Vec<Point>, Vec<usize>)>;
        let tracer = Tracer::new(scene).unwrap();
        let mut ws = Workspace::new();
        let mut results: [Rays; 2] = Default::default();
        FLAT_OFF.with(|c| c.set(true));
        for (general, out) in results.iter_mut().enumerate() {
            GENERAL_ONLY.with(|c| c.set(general == 1));
            let mut last: Vec<Vec<f64>> = vec![Vec::new(); scene.paths().len()];
            for s in 0..scene.sources().len() {
                for r in 0..scene.receivers().len() {
                    for (p, last) in last.iter_mut().enumerate() {
                        let guess: Vec<f64> = last.iter().map(|x| x + 1e-3).collect();
                        let mut keep = |sum: crate::RaySummary, ws: &Workspace| {
                            let o = (
                                sum.status,
                                sum.time.to_bits(),
                                sum.iterations,
                                sum.residual.to_bits(),
                                sum.reason,
                            );
                            out.push((o, ws.points().to_vec(), ws.media().to_vec()));
                        };
                        let cold = tracer.solve_indexed_from(s, r, p, None, &mut ws);
                        keep(cold, &ws);
                        *last = ws.parameters().to_vec();
                        if !guess.is_empty() {
                            let warm = tracer.solve_indexed_from(s, r, p, Some(&guess), &mut ws);
                            keep(warm, &ws);
                            let given = Start::Given(&guess);
                            let given = tracer.solve_indexed_start(s, r, p, given, &mut ws);
                            keep(given, &ws);
                        }
                    }
                }
            }
        }
        GENERAL_ONLY.with(|c| c.set(false));
        FLAT_OFF.with(|c| c.set(false));
        let [fast, general] = &results;
        assert_eq!(fast.len(), general.len());
        for (a, b) in fast.iter().zip(general) {
            assert_eq!(a, b);
        }
        scene.num_rays()
    }

    #[test]
    fn fast_paths_take_the_general_steps() {
        let demo = |spec: crate::SceneSpec| Scene::from_spec(&spec).unwrap();
        assert_eq!(fast_paths_agree(&demo(crate::demo::air_water(300, 3))), 300);
        assert_eq!(
            fast_paths_agree(&demo(crate::demo::layer_stack(8, 100))),
            100
        );
        assert_eq!(
            fast_paths_agree(&demo(crate::demo::layer_stack(40, 30))),
            30
        );
        assert_eq!(
            fast_paths_agree(&demo(crate::demo::sea_floor(3000, 100))),
            100
        );
        let root = env!("CARGO_MANIFEST_DIR");
        for name in ["room2d", "seed500", "layers10"] {
            let text =
                std::fs::read_to_string(format!("{root}/fixtures/bench/{name}.json")).unwrap();
            assert!(fast_paths_agree(&Scene::from_json(&text).unwrap()) > 0);
        }
        // The contract's cases and the fuzz finds: vertices, ends, wrong sides, degenerate legs.
        for dir in ["cases", "fuzz"] {
            for entry in std::fs::read_dir(format!("{root}/fixtures/{dir}")).unwrap() {
                let path = entry.unwrap().path();
                let name = path.to_string_lossy();
                if name.ends_with(".json") && !name.ends_with(".expected.json") {
                    let text = std::fs::read_to_string(&path).unwrap();
                    assert!(
                        fast_paths_agree(&Scene::from_json(&text).unwrap()) > 0,
                        "{name}"
                    );
                }
            }
        }
        // One refraction through an undulating surface of 6 and of 40 segments (searched
        // segment by segment and through its BVH), one reflection inside a closed polygon, and
        // receivers that put some rays on the wrong side or behind another interface.
        for segments in [6, 40] {
            let surface: Vec<String> = (0..=segments)
                .map(|i| {
                    let x = -4.0 + 8.0 * i as f64 / segments as f64;
                    format!("[{x}, {}]", 0.3 * (1.7 * x).sin())
                })
                .collect();
            let receivers: Vec<String> = (0..150)
                .map(|i| format!("[{}, {}]", -3.5 + 0.047 * i as f64, -2.0 + 0.013 * i as f64))
                .collect();
            let text = format!(
                r#"{{
                "media": {{ "a": {{ "speed": 1.0 }}, "b": {{ "speed": 0.6 }} }},
                "interfaces": {{
                    "surface": {{ "points": [{}] }},
                    "ring": {{ "points": [[-6, -6], [6, -6], [6, 6], [-6, 6], [-7, 0]],
                               "closed": true }},
                    "screen": {{ "points": [[1, -1.2], [2, -1.5]] }}
                }},
                "sources": [[0.3, 2.0], [-2.5, 1.1]], "receivers": [{}],
                "paths": [
                    {{ "steps": [{{ "refract": "surface" }}], "media": ["a", "b"] }},
                    {{ "steps": [{{ "reflect": "ring" }}], "media": ["a", "a"] }},
                    {{ "steps": [{{ "reflect": "surface" }}], "media": ["a", "a"] }}
                ]
            }}"#,
                surface.join(", "),
                receivers.join(", ")
            );
            assert_eq!(fast_paths_agree(&Scene::from_json(&text).unwrap()), 900);
        }
    }

    #[test]
    fn thomas_solves_tridiagonal() {
        let diag = [4.0, 5.0, 6.0, 7.0];
        let off = [1.0, -2.0, 0.5];
        let x_true = [1.0, -2.0, 3.0, 0.25];
        let mut d = [0.0; 4];
        for i in 0..4 {
            d[i] = diag[i] * x_true[i];
            if i > 0 {
                d[i] += off[i - 1] * x_true[i - 1];
            }
            if i < 3 {
                d[i] += off[i] * x_true[i + 1];
            }
        }
        let mut x = [0.0; 4];
        let mut cp = [0.0; 4];
        assert!(thomas(&diag, &off, &d, &mut x, &mut cp));
        for i in 0..4 {
            assert!((x[i] - x_true[i]).abs() < 1e-14);
        }
        assert!(!thomas(&[0.0], &[], &[1.0], &mut x[..1], &mut cp[..1]));
    }
}
