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

mod general;
mod one_step;

pub(crate) use one_step::{OneStepNewton, ReceiverSensitivity, one_step_sensitivity};

use crate::geom::Vec2;
use crate::problem::{Frame, Pin, ProblemRef, finite, max_num, min_num, sweep_row};

/// What a solve is asked to do.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NewtonOptions {
    /// Relative residual to reach (see the module's stopping rule).
    pub tolerance: f64,
    /// Newton steps allowed.
    pub max_iterations: usize,
    /// Whether the fast paths run (`Kernels::GeneralOnly` turns them off, to compare them with
    /// the general loop).
    pub fast_path: bool,
}

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

/// How one solve ended (the points are in the [`NewtonWorkspace`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Solution {
    /// How the iteration ended.
    pub outcome: Outcome,
    /// Travel time at the final points.
    pub time: f64,
    /// Iterations used.
    pub iterations: usize,
    /// Final relative residual: `maxᵢ |∂T/∂sᵢ| / (wᵢ + wᵢ₊₁)` over free points.
    pub residual: f64,
}

/// The Newton iteration's state and scratch: the parameters, segments and pins of the
/// points (and of the trial step), the evaluations, the step, the Thomas algorithm's scratch
/// and the fast path's segment frames. Solving allocates nothing once it has grown to the
/// longest path.
#[derive(Clone, Debug, Default)]
pub(crate) struct NewtonWorkspace {
    pub(crate) s: Vec<f64>,
    pub(crate) seg: Vec<usize>,
    pub(crate) pin: Vec<Pin>,
    s_try: Vec<f64>,
    seg_try: Vec<usize>,
    pin_try: Vec<Pin>,
    /// Per point: pinned on a vertex that it was being sent across and back over; kept there
    /// until the others have moved (see `general`).
    sticky: Vec<bool>,
    // Boxed, so that accepting a trial swaps two pointers, not two dozen vectors.
    pub(crate) eval: Box<crate::problem::Eval>,
    eval_try: Box<crate::problem::Eval>,
    delta: Vec<f64>,
    rhs: Vec<f64>,
    diag: Vec<f64>,
    off: Vec<f64>,
    scratch: Vec<f64>,
    frames: Vec<Frame>,
}

impl NewtonWorkspace {
    /// Whether it is sized for a path of `k` interactions.
    #[inline]
    pub(crate) fn fits(&self, k: usize) -> bool {
        self.s.len() == k && self.eval.rel.len() == k + 2
    }

    /// Sizes it for a path of `k` interactions (the first ray of a path of another length).
    #[inline(never)]
    pub(crate) fn resize_to(&mut self, k: usize) {
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

/// Runs the iteration from the parameters, segments and pins already in `ws` (set by the
/// start): the fast path while it applies (every point free, full steps inside the segments),
/// then the general loop. Leaves the final state in `ws` (`s`, `seg`, `pin`, `eval`).
pub(crate) fn solve(g: &ProblemRef, ws: &mut NewtonWorkspace, opts: NewtonOptions) -> Solution {
    let k = g.k();
    let mut state = IterationState::START;
    if opts.fast_path && ws.pin[..k].iter().all(|&p| p == Pin::Free) {
        let done = match k {
            0 => None,
            1 => one_step::fast_newton(g, ws, opts, &mut state),
            _ => {
                ws.frames.clear();
                ws.frames
                    .extend((0..k).map(|i| Frame::new(g.line(i), ws.seg[i], g.source)));
                fast_newton(g, ws, opts, &mut state)
            }
        };
        if let Some(done) = done {
            return done;
        }
    }
    general::run(g, ws, opts, state)
}

/// The iteration state that the fast path hands on to the general loop.
#[derive(Clone, Copy, Debug)]
pub(crate) struct IterationState {
    /// Newton steps taken.
    iterations: usize,
    /// Whether the next evaluation adds the curvature estimate.
    curvature: bool,
    /// Whether `ws.eval` holds the evaluation at `ws.s`.
    evaluated: bool,
    /// Newton steps taken after the residual met the tolerance.
    polishes: usize,
}

impl IterationState {
    /// Before the first step: nothing evaluated, the curvature estimate on.
    const START: IterationState = IterationState {
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
    g: &ProblemRef,
    ws: &mut NewtonWorkspace,
    opts: NewtonOptions,
    fast: &mut IterationState,
) -> Option<Solution> {
    let (tol, max_iterations) = (opts.tolerance, opts.max_iterations);
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
            return Some(general::not_converged(e, fast.iterations));
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
            return Some(general::finished(ws, fast.iterations));
        }
        if !inside {
            return None;
        }
        let polish = residual <= tol;
        if polish {
            let small = (0..k).all(|i| delta[i].abs() <= tol.sqrt() * (len[i] + len[i + 1]));
            if small || fast.polishes >= 2 {
                return Some(general::finished(ws, fast.iterations));
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
    g: &ProblemRef,
    frames: impl Iterator<Item = Frame>,
    ws: &mut NewtonWorkspace,
    opts: NewtonOptions,
) -> Option<Solution> {
    debug_assert!(ws.pin[..g.k()].iter().all(|&p| p == Pin::Free));
    ws.frames.clear();
    ws.frames.extend(frames);
    let mut fast = IterationState::START;
    fast_newton(g, ws, opts, &mut fast)
}

/// How far inside the general loop's tests [`confirm_start`] stays: its Newton correction
/// at most this fraction of the general loop's bound on a correction it may leave untaken,
/// and its pivots at least `1 / CONFIRM_MARGIN` times the general loop's least pivot, so that
/// the Hessian it is given (accurate to far better than this fraction) leads to the general
/// loop's verdict.
const CONFIRM_MARGIN: f64 = 1e-3;

/// The general solve's verdict on a start that is the ray up to round-off, without the
/// Hessian blocks of the legs: evaluates the positions, legs, time, residuals and merit at the
/// parameters in `ws` (every point free, on the segments described by `frames`, a path of two
/// or more interactions) as [`solve`] does first (the general loop's evaluation, bit for bit,
/// but its Hessian), and where the general loop would stop there
/// without a step (no leg vanished, the relative residual within the tolerance, and the Newton
/// correction `H⁻¹ r` below its bound), returns what [`solve`] returns: converged, no
/// iterations, the time and residual of that evaluation, bit for bit. The Hessian comes from
/// the caller (`hessian(i)`: row `i`'s diagonal and its coupling to row `i + 1`, at these
/// points), and the correction from it must pass the general loop's tests by the margin
/// [`CONFIRM_MARGIN`] (the general loop's own Hessian differs from it by round-off). `None`
/// otherwise: `ws` holds the evaluation without its Hessian, and [`solve`] from the same
/// parameters takes the general code's steps.
pub(crate) fn confirm_start(
    g: &ProblemRef,
    frames: impl Iterator<Item = Frame>,
    hessian: impl Fn(usize) -> (f64, f64),
    ws: &mut NewtonWorkspace,
    opts: NewtonOptions,
) -> Option<Solution> {
    let k = g.k();
    if k < 2 || opts.max_iterations == 0 {
        return None;
    }
    if ws.pin[..k].iter().any(|&p| p != Pin::Free) {
        return None;
    }
    ws.frames.clear();
    ws.frames.extend(frames);
    g.evaluate_framed_first(&ws.s, &ws.frames, &mut ws.eval);
    let e = &mut ws.eval;
    e.factored = false;
    let tol = opts.tolerance;
    // (`rmax` NaN fails this too.)
    let within = e.rmax <= tol;
    if e.vanished > 0 || e.held > 0 || !within {
        return None;
    }
    // The Newton correction `x = H⁻¹ r` by the Thomas algorithm (the step is `−x`).
    let (diag, off, r, len) = (
        &mut e.diag[..k],
        &mut e.off[..k - 1],
        &e.r[..k],
        &e.len[..k + 1],
    );
    let (cp, y) = (&mut e.cp[..k], &mut e.y[..k]);
    let (mut prev_c, mut prev_y, mut sub) = (0.0, 0.0, 0.0);
    for i in 0..k {
        let (d, o) = hessian(i);
        let sup = if i + 1 < k { o } else { 0.0 };
        diag[i] = d;
        if i + 1 < k {
            off[i] = o;
        }
        let den = d - sub * prev_c;
        let scale = d.abs() + sub.abs() + sup.abs();
        if !(finite(den) && den.abs() > 1e-14 / CONFIRM_MARGIN * scale) {
            return None;
        }
        let inv = 1.0 / den;
        (prev_c, prev_y) = (sup * inv, (r[i] - sub * prev_y) * inv);
        (cp[i], y[i], sub) = (prev_c, prev_y, sup);
    }
    let bound = CONFIRM_MARGIN * tol.sqrt();
    let mut x = 0.0;
    for i in (0..k).rev() {
        x = if i + 1 == k { y[i] } else { y[i] - cp[i] * x };
        // (A NaN correction fails this too.)
        let small = x.abs() <= bound * (len[i] + len[i + 1]);
        if !small {
            return None;
        }
    }
    Some(Solution {
        outcome: Outcome::Converged,
        time: e.time,
        iterations: 0,
        residual: e.rmax,
    })
}

/// How the solution in `ws` moves with the receiver, to first order: after a solve that ended
/// with every point free, writes `z = H⁻¹ eₖ₋₁` into `z` and returns `g = ∂rₖ₋₁/∂R` (only the
/// last residual depends on the receiver), so that moving the receiver by `ΔR` moves the
/// parameters by `−z (g · ΔR)` (differentiating `r(s, R) = 0`). `None` when a point is held,
/// there are no interactions, or `H` is singular there. `unit` and `cp` are scratch, `k` long.
pub(crate) fn receiver_sensitivity(
    ws: &NewtonWorkspace,
    slowness: &[f64],
    z: &mut [f64],
    unit: &mut [f64],
    cp: &mut [f64],
) -> Option<Vec2> {
    let k = ws.s.len();
    let e = &ws.eval;
    if k == 0 || e.held > 0 || e.vanished > 0 || slowness.len() != k + 1 {
        return None;
    }
    let g = last_residual_gradient(e.tan[k - 1], e.u[k], e.len[k], slowness[k])?;
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

/// `∂rₖ₋₁/∂R` for the last point's tangent `t`, the receiver leg's direction `u`, length `l`
/// and slowness `w`; `None` for a vanished leg.
#[inline(always)]
pub(crate) fn last_residual_gradient(t: Vec2, u: Vec2, l: f64, w: f64) -> Option<Vec2> {
    if l.is_nan() || l <= 0.0 {
        return None;
    }
    // r = (wₖ₋₁ uₖ₋₁ − wₖ uₖ) · t with uₖ = (R − xₖ₋₁) / ℓₖ: ∂(uₖ · t)/∂R = (t − (uₖ · t) uₖ) / ℓₖ.
    Some((t - u * u.dot(t)) * (-w / l))
}

/// `1/h` for a usable pivot `h` (`thomas`'s test on one row).
#[inline(always)]
pub(crate) fn pivot_inverse(h: f64) -> Option<f64> {
    let z = 1.0 / h;
    (finite(h) && h != 0.0 && finite(z)).then_some(z)
}

#[cfg(test)]
mod tests {
    use super::*;

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
