//! The path problem: travel time, its gradient (the residual) and its tridiagonal Hessian.
//!
//! For interaction points `xᵢ = Pᵢ(sᵢ)` on polylines, legs `ℓⱼ = |xⱼ − xⱼ₋₁|` with unit
//! directions `uⱼ` and slownesses `wⱼ` (leg `j` arrives at point `j`), and unit tangents `tᵢ`:
//!
//! ```text
//! T      = Σⱼ wⱼ ℓⱼ
//! rᵢ     = ∂T/∂sᵢ     = (wᵢ uᵢ − wᵢ₊₁ uᵢ₊₁) · tᵢ          (Snell's law, tangential form)
//! Hᵢᵢ    = wᵢ (uᵢ × tᵢ)² / ℓᵢ + wᵢ₊₁ (uᵢ₊₁ × tᵢ)² / ℓᵢ₊₁  [+ κᵢ (wᵢ uᵢ − wᵢ₊₁ uᵢ₊₁) · nᵢ]
//! Hᵢ,ᵢ₊₁ = −wᵢ₊₁ (uᵢ₊₁ × tᵢ)(uᵢ₊₁ × tᵢ₊₁) / ℓᵢ₊₁
//! ```
//!
//! (0-based in the code: point `i` sits between leg `i` and leg `i + 1`.) Every term is a
//! leg's, through the leg model (`leg.rs`): `T` the sum of `Leg::time`, `rᵢ` the arriving
//! minus the departing slowness vector (`Leg::arrival`, `Leg::departure`) along `tᵢ`, and
//! the Hessian's entries the legs' blocks (`Leg::end_block`, `Leg::start_block`,
//! `Leg::coupling`); the formulas above are the uniform medium's. Each leg adds the
//! rank-one matrix `(w/ℓ) g gᵀ` with `g = (−u × tᵢ, u × tᵢ₊₁)`, so on fixed segments `T` is
//! convex and `H` positive semi-definite. The bracketed curvature term is zero on a straight
//! segment; the solver adds an estimate of it only while points travel across the vertices
//! of a digitised smooth curve, where the true `T` (of the smooth curve) may have maxima and
//! saddles that the segment-wise Hessian cannot see.

use crate::geom::{Point, Segment, Vec2};
use crate::leg::{AnyLeg, Leg, LegMedium, LegModel, StraightLeg, Uniform};
use crate::polyline::Polyline;
use crate::scene::{Scene, Step};

/// A symmetric tridiagonal matrix: `diag[i] = Hᵢᵢ`, `off[i] = Hᵢ,ᵢ₊₁`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tridiagonal {
    /// Diagonal, length `k`.
    pub diag: Vec<f64>,
    /// Super-diagonal (= sub-diagonal), length `k − 1` (0 when `k == 0`).
    pub off: Vec<f64>,
}

impl Tridiagonal {
    /// The dense `k × k` matrix, row-major.
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let k = self.diag.len();
        let mut m = vec![vec![0.0; k]; k];
        for i in 0..k {
            m[i][i] = self.diag[i];
            if i + 1 < k {
                m[i][i + 1] = self.off[i];
                m[i + 1][i] = self.off[i];
            }
        }
        m
    }
}

/// How far one interaction point is from moving freely (solver state that the merit needs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pin {
    /// Inside a segment (or at a vertex, moving through it).
    Free,
    /// Held on the vertex where its segment `seg` starts.
    Vertex,
    /// Held at the first vertex of an open polyline.
    Start,
    /// Held at the last vertex of an open polyline.
    End,
    /// Held inside a segment where a leg next to it has vanished (a source, receiver or
    /// neighbouring interaction lies on the interface there): `T` has a kink at the point.
    Kink,
}

/// Scratch buffers of one evaluation (reused: evaluating allocates nothing once sized).
#[derive(Clone, Debug, Default)]
pub(crate) struct Eval {
    /// Positions relative to the source: `k + 2` (source, interactions, receiver).
    pub rel: Vec<Vec2>,
    /// Unit leg directions, `k + 1`.
    pub u: Vec<Vec2>,
    /// Leg lengths, `k + 1`.
    pub len: Vec<f64>,
    /// Their reciprocals (0 for a zero-length leg), `k + 1`.
    pub inv_len: Vec<f64>,
    /// Unit tangents at the interactions, `k`.
    pub tan: Vec<Vec2>,
    /// Residual `∂T/∂sᵢ`, `k`.
    pub r: Vec<f64>,
    /// Hessian diagonal, `k`.
    pub diag: Vec<f64>,
    /// Hessian off-diagonal, `k − 1`.
    pub off: Vec<f64>,
    /// Travel time.
    pub time: f64,
    /// Merit `Σ (rᵢ / (wᵢ + wᵢ₊₁))²` over the points as held (see [`ProblemRef::evaluate`]).
    pub phi: f64,
    /// Largest relative residual `|rᵢ| / (wᵢ + wᵢ₊₁)` of the free points.
    pub rmax: f64,
    /// Number of held points.
    pub held: usize,
    /// Number of free points next to a vanished leg.
    pub vanished: usize,
    /// Forward sweep of the Thomas algorithm on `H x = r` (see
    /// [`ProblemRef::evaluate_passes`]): modified super-diagonal `cp` and right-hand side `y`, `k`
    /// each, valid when `factored`.
    pub cp: Vec<f64>,
    /// See `cp`.
    pub y: Vec<f64>,
    /// Whether `cp` and `y` hold a forward sweep with no tiny or non-finite pivot.
    pub factored: bool,
    /// Length below which a leg counts as vanished: 1e-12 of the path's length, or the
    /// round-off of the coordinates, whichever is larger.
    pub vanish: f64,
    /// The legs of a path whose legs may be curved, `k + 1`, each evaluated once per
    /// evaluation ([`ProblemRef::derive_curved`]; empty for straight legs).
    pub legs: Vec<AnyLeg>,
}

impl Eval {
    pub fn resize(&mut self, k: usize) {
        self.rel.resize(k + 2, Vec2::default());
        self.u.resize(k + 1, Vec2::default());
        self.len.resize(k + 1, 0.0);
        self.inv_len.resize(k + 1, 0.0);
        self.tan.resize(k, Vec2::default());
        self.r.resize(k, 0.0);
        self.diag.resize(k, 0.0);
        self.off.resize(k.saturating_sub(1), 0.0);
        self.cp.resize(k, 0.0);
        self.y.resize(k, 0.0);
    }
}

/// The path problem of one ray as the solver works on it: a [`PathProblem`] borrowed (which
/// polylines, which slownesses, which end points).
#[derive(Clone, Copy)]
pub(crate) struct ProblemRef<'a> {
    pub scene: &'a Scene,
    pub steps: &'a [Step],
    pub slowness: &'a [f64],
    /// Each leg's model, positions relative to the source, where a leg of the path may be
    /// curved (a medium with a gradient); empty for a path of straight legs only (every leg
    /// [`Uniform`] of its slowness, the common case, on its own code).
    pub curved: &'a [LegMedium<'a>],
    pub source: Point,
    pub receiver: Point,
}

impl<'a> ProblemRef<'a> {
    #[inline]
    pub fn line(&self, i: usize) -> &'a Polyline {
        &self.scene.interfaces()[self.steps[i].interface].polyline
    }
    #[inline]
    pub fn k(&self) -> usize {
        self.steps.len()
    }

    /// Positions, legs, time and residual at parameters `s` on segments `seg`; with
    /// `hessian`, also the tridiagonal Hessian (with the curvature estimate when `curvature`).
    ///
    /// Also the merit over the points as `pin` holds them: a free point counts its residual,
    /// a point held at an end only the part pointing back inside (none if a leg next to it has
    /// vanished: it sits on a corner), a point held on a vertex nothing (the kink test judges
    /// it).
    pub fn evaluate(
        &self,
        s: &[f64],
        seg: &[usize],
        pin: &[Pin],
        e: &mut Eval,
        hessian: bool,
        curvature: bool,
    ) {
        let k = self.k();
        let (s, seg, pin) = (&s[..k], &seg[..k], &pin[..k]);
        let interfaces = self.scene.interfaces();
        {
            let (rel, tan) = (&mut e.rel[..k + 2], &mut e.tan[..k]);
            rel[0] = Vec2::default();
            for i in 0..k {
                let line = &interfaces[self.steps[i].interface].polyline;
                rel[i + 1] = line.offset_on(seg[i], s[i], self.source);
                tan[i] = line.tangent(seg[i]);
            }
            rel[k + 1] = self.receiver - self.source;
        }
        let kappa = |i: usize| {
            interfaces[self.steps[i].interface]
                .polyline
                .curvature(seg[i])
        };
        self.derive(e, |i| pin[i], hessian, curvature.then_some(kappa));
    }

    /// [`evaluate`](Self::evaluate) with every point free, on the segments described by
    /// `frames` (the fast path of the solver: no polyline lookups), Hessian included. Gives the
    /// same numbers as `evaluate` on those segments.
    pub fn evaluate_framed(&self, s: &[f64], frames: &[Frame], e: &mut Eval, curvature: bool) {
        self.place_framed(s, frames, e);
        self.derive(
            e,
            |_| Pin::Free,
            true,
            curvature.then_some(|i: usize| frames[i].kappa),
        );
    }

    /// The points' offsets from the source and the segments' tangents at `s` on `frames`
    /// into `e` (the first part of [`evaluate_framed`](Self::evaluate_framed)).
    #[inline]
    fn place_framed(&self, s: &[f64], frames: &[Frame], e: &mut Eval) {
        let k = self.k();
        let (s, frames) = (&s[..k], &frames[..k]);
        let (rel, tan) = (&mut e.rel[..k + 2], &mut e.tan[..k]);
        rel[0] = Vec2::default();
        for i in 0..k {
            rel[i + 1] = frames[i].offset(s[i]);
            tan[i] = frames[i].t;
        }
        rel[k + 1] = self.receiver - self.source;
    }

    /// [`evaluate_framed`](Self::evaluate_framed) without the Hessian (`e.diag`, `e.off` left
    /// alone): positions, legs, time, residuals and merit, the same numbers. For a caller that
    /// has the Hessian at the points from elsewhere (`solver::confirm_start`).
    pub fn evaluate_framed_first(&self, s: &[f64], frames: &[Frame], e: &mut Eval) {
        self.place_framed(s, frames, e);
        self.derive(e, |_| Pin::Free, false, None::<fn(usize) -> f64>);
    }

    /// [`evaluate_framed`](Self::evaluate_framed) for `k ≥ 1` with the forward sweep of the
    /// Thomas algorithm on `H x = r` folded in: leaves `e.cp` and `e.y` (see [`Eval::factored`])
    /// for the back substitution. The same numbers as `evaluate_framed` followed by `thomas`,
    /// bit for bit, except that it leaves `e.tan` (the frames' tangents: the caller stores them
    /// once) alone. It works in passes (positions; legs, with plain square roots and
    /// reciprocals; sums; per-point terms; merit and sweep), each with few live values: more
    /// instructions than one fused pass, but less time. When a leg has vanished, or a squared
    /// leg length is not a normal number below 1e300, it falls back to `evaluate_framed` (and
    /// `e.factored` is `false`).
    pub fn evaluate_passes(&self, s: &[f64], frames: &[Frame], e: &mut Eval, curvature: bool) {
        if !self.curved.is_empty() {
            self.evaluate_framed(s, frames, e, curvature);
            e.factored = false;
            return;
        }
        let k = self.k();
        let (s, frames, w) = (&s[..k], &frames[..k], &self.slowness[..k + 1]);
        let (rel, u, len, inv_len) = (
            &mut e.rel[..k + 2],
            &mut e.u[..k + 1],
            &mut e.len[..k + 1],
            &mut e.inv_len[..k + 1],
        );
        let (r, diag, off, cp, y) = (
            &mut e.r[..k],
            &mut e.diag[..k],
            &mut e.off[..k - 1],
            &mut e.cp[..k],
            &mut e.y[..k],
        );
        rel[0] = Vec2::default();
        for i in 0..k {
            rel[i + 1] = frames[i].offset(s[i]);
        }
        rel[k + 1] = self.receiver - self.source;
        // Legs: `Uniform::leg_along` without its branches (checked below).
        let mut plain = true;
        for j in 0..=k {
            let (leg, ok) = Uniform::new(w[j]).leg_plain(rel[j + 1] - rel[j]);
            plain &= ok;
            len[j] = leg.len;
            inv_len[j] = leg.inv_len;
            u[j] = leg.u;
        }
        let (u, len, inv_len) = (&*u, &*len, &*inv_len);
        let leg = |j: usize| leg_from(u, len, inv_len, j, w[j]);
        let (mut time, mut total, mut shortest) = (0.0, 0.0, f64::INFINITY);
        for j in 0..=k {
            let leg = leg(j);
            time += leg.time();
            total += leg.len;
            shortest = min_num(shortest, leg.len);
        }
        let vanish = vanish_threshold(total, self.coord());
        if !plain || shortest <= vanish {
            // Points next to a vanished leg count differently in the merit.
            self.evaluate_framed(s, frames, e, curvature);
            e.factored = false;
            return;
        }
        // Per point: residual, Hessian row.
        for i in 0..k {
            let t = frames[i].t;
            let (before, after) = (leg(i), leg(i + 1));
            let turn = before.arrival() - after.departure();
            r[i] = turn.dot(t);
            let mut h = before.end_block(t) + after.start_block(t);
            if curvature && frames[i].kappa != 0.0 {
                h += frames[i].kappa * turn.dot(t.perp());
            }
            diag[i] = h;
            if i + 1 < k {
                off[i] = after.coupling(t, frames[i + 1].t);
            }
        }
        // Merit, and the forward sweep of `thomas`.
        let (mut phi, mut rmax) = (0.0, 0.0f64);
        let (mut prev_c, mut prev_y, mut sub) = (0.0, 0.0, 0.0);
        let mut ok = true;
        for i in 0..k {
            let rel_r = r[i] / (w[i] + w[i + 1]);
            rmax = max_num(rmax, rel_r.abs());
            phi += rel_r * rel_r;
            let o = if i + 1 < k { off[i] } else { 0.0 };
            let (c, yi, pivot_ok) = sweep_row(diag[i], sub, o, r[i], prev_c, prev_y);
            ok &= pivot_ok;
            cp[i] = c;
            y[i] = yi;
            (prev_c, prev_y, sub) = (c, yi, o);
        }
        e.time = time;
        e.phi = phi;
        e.rmax = rmax;
        e.held = 0;
        e.vanished = 0;
        e.vanish = vanish;
        e.factored = ok;
    }

    /// The largest coordinate of the end points (the scale of their round-off).
    #[inline]
    pub fn coord(&self) -> f64 {
        coord(self.source, self.receiver)
    }

    /// [`evaluate_framed`](Self::evaluate_framed) for a path of one interaction, bit for bit,
    /// in registers: `w` the two slownesses, `to_receiver` the receiver minus the source,
    /// `coord` [`ProblemRef::coord`].
    #[inline(always)]
    pub fn evaluate_single(
        s: f64,
        f: &Frame,
        w: [f64; 2],
        to_receiver: Vec2,
        coord: f64,
        curvature: bool,
    ) -> OnePointEval {
        // Through the leg model, in registers, operation for operation as `evaluate_framed`
        // (so bit for bit).
        let p = f.offset(s);
        let leg0 = Uniform::new(w[0]).leg(Vec2::default(), p);
        let leg1 = Uniform::new(w[1]).leg(p, to_receiver);
        let time = 0.0 + leg0.time() + leg1.time();
        let total = 0.0 + leg0.len + leg1.len;
        let vanish = vanish_threshold(total, coord);
        let t = f.t;
        let turn = leg0.arrival() - leg1.departure();
        let r = turn.dot(t);
        let rel = r / (w[0] + w[1]);
        let vanished = leg0.len <= vanish || leg1.len <= vanish;
        let (phi, rmax) = if vanished {
            (0.0, 0.0)
        } else {
            (0.0 + rel * rel, max_num(0.0, rel.abs()))
        };
        let mut h = leg0.end_block(t) + leg1.start_block(t);
        if curvature && f.kappa != 0.0 {
            h += f.kappa * turn.dot(t.perp());
        }
        let (u, len, inv_len) = (
            [leg0.u, leg1.u],
            [leg0.len, leg1.len],
            [leg0.inv_len, leg1.inv_len],
        );
        OnePointEval {
            p,
            u,
            len,
            inv_len,
            time,
            r,
            h,
            phi,
            rmax,
            vanished,
            vanish,
        }
    }

    /// Legs, time, residual, merit and (with `hessian`) the Hessian from the positions and
    /// tangents already in `e`.
    #[inline(always)]
    fn derive(
        &self,
        e: &mut Eval,
        pin: impl Fn(usize) -> Pin,
        hessian: bool,
        kappa: Option<impl Fn(usize) -> f64>,
    ) {
        if !self.curved.is_empty() {
            self.derive_curved(e, pin, hessian, kappa);
            return;
        }
        let k = self.k();
        // Exact-length views: the loops below then index without bounds checks.
        let w = &self.slowness[..k + 1];
        let (rel, u, len, inv_len, tan) = (
            &e.rel[..k + 2],
            &mut e.u[..k + 1],
            &mut e.len[..k + 1],
            &mut e.inv_len[..k + 1],
            &e.tan[..k],
        );
        let mut time = 0.0;
        let mut total = 0.0;
        for j in 0..=k {
            let leg = Uniform::new(w[j]).leg(rel[j], rel[j + 1]);
            len[j] = leg.len;
            inv_len[j] = leg.inv_len;
            u[j] = leg.u;
            time += leg.time();
            total += leg.len;
        }
        let (u, len, inv_len) = (&*u, &*len, &*inv_len);
        let leg = |j: usize| leg_from(u, len, inv_len, j, w[j]);
        e.time = time;
        let vanish = vanish_threshold(total, self.coord());
        let merit = residuals(leg, w, tan, len, vanish, pin, &mut e.r[..k]);
        (e.phi, e.rmax, e.held, e.vanished, e.vanish) =
            (merit.phi, merit.rmax, merit.held, merit.vanished, vanish);
        if !hessian {
            return;
        }
        let (diag, off) = (&mut e.diag[..k], &mut e.off[..k.saturating_sub(1)]);
        hessian_blocks(leg, tan, kappa, diag, off);
    }

    /// [`derive`](Self::derive) for a path whose legs may be curved (each leg its model in
    /// `curved`): the same sums and rules, the legs from their models. The columns `u`,
    /// `len`, `inv_len` hold each leg's chord (the solver's scales and the classifier's
    /// tests of vanished legs and sides).
    #[inline(never)]
    fn derive_curved(
        &self,
        e: &mut Eval,
        pin: impl Fn(usize) -> Pin,
        hessian: bool,
        kappa: Option<impl Fn(usize) -> f64>,
    ) {
        let k = self.k();
        let w = &self.slowness[..k + 1];
        let models = &self.curved[..k + 1];
        let rel = &e.rel[..k + 2];
        // Each leg once (an arc's closed forms cost a square root, a `hypot` and an `asinh`):
        // the residuals and the Hessian blocks read each twice or more.
        let mut legs = std::mem::take(&mut e.legs);
        legs.clear();
        legs.extend((0..=k).map(|j| models[j].leg(rel[j], rel[j + 1])));
        let leg = |j: usize| &legs[j];
        let (mut time, mut total) = (0.0, 0.0);
        for j in 0..=k {
            let l = leg(j);
            let len = l.len();
            e.len[j] = len;
            e.inv_len[j] = if len > 0.0 { 1.0 / len } else { 0.0 };
            e.u[j] = l.chord_direction();
            time += l.time();
            total += len;
        }
        e.time = time;
        let vanish = vanish_threshold(total, self.coord());
        let merit = residuals(
            leg,
            w,
            &e.tan[..k],
            &e.len[..k + 1],
            vanish,
            pin,
            &mut e.r[..k],
        );
        (e.phi, e.rmax, e.held, e.vanished, e.vanish) =
            (merit.phi, merit.rmax, merit.held, merit.vanished, vanish);
        if hessian {
            let (diag, off) = (&mut e.diag[..k], &mut e.off[..k.saturating_sub(1)]);
            hessian_blocks(leg, &e.tan[..k], kappa, diag, off);
        }
        e.legs = legs;
    }
}

/// The merit's sums of one evaluation ([`residuals`]).
#[derive(Clone, Copy, Debug)]
struct Merit {
    /// Sum of the squared (pinned) relative residuals.
    phi: f64,
    /// The largest relative residual of a free point.
    rmax: f64,
    /// Points held by their pin.
    held: usize,
    /// Free points next to a vanished leg.
    vanished: usize,
}

/// The residual of every point into `r` and the merit's sums, from the legs (`leg(j)`, any
/// leg model), the slownesses `w`, the tangents `tan`, the legs' lengths `len` (their chords')
/// and each point's pin: what a path's evaluation shares whatever its legs.
#[inline(always)]
fn residuals<L: Leg>(
    leg: impl Fn(usize) -> L,
    w: &[f64],
    tan: &[Vec2],
    len: &[f64],
    vanish: f64,
    pin: impl Fn(usize) -> Pin,
    r: &mut [f64],
) -> Merit {
    let k = r.len();
    // Exact-length views: the loop then indexes without bounds checks.
    let (w, tan, len) = (&w[..k + 1], &tan[..k], &len[..k + 1]);
    let (mut phi, mut rmax, mut held, mut vanished) = (0.0, 0.0f64, 0, 0);
    for i in 0..k {
        let t = tan[i];
        let ri = (leg(i).arrival() - leg(i + 1).departure()).dot(t);
        r[i] = ri;
        let rel = ri / (w[i] + w[i + 1]);
        let p = pin(i);
        let m = match p {
            Pin::Free if leg_vanished(len, i, vanish) => {
                // The residual is undefined here; the solver judges the kink.
                vanished += 1;
                0.0
            }
            Pin::Free => {
                rmax = max_num(rmax, rel.abs());
                rel
            }
            Pin::Vertex | Pin::Kink => 0.0,
            Pin::Start | Pin::End if leg_vanished(len, i, vanish) => 0.0,
            Pin::Start => rel.min(0.0),
            Pin::End => rel.max(0.0),
        };
        held += (p != Pin::Free) as usize;
        phi += m * m;
    }
    Merit {
        phi,
        rmax,
        held,
        vanished,
    }
}

/// The Hessian's diagonal and off-diagonal from the legs (`leg(j)`, any leg model), the
/// tangents and each point's curvature term (`kappa`).
#[inline(always)]
fn hessian_blocks<L: Leg>(
    leg: impl Fn(usize) -> L,
    tan: &[Vec2],
    kappa: Option<impl Fn(usize) -> f64>,
    diag: &mut [f64],
    off: &mut [f64],
) {
    let k = diag.len();
    let (tan, off) = (&tan[..k], &mut off[..k.saturating_sub(1)]);
    for i in 0..k {
        let t = tan[i];
        let (before, after) = (leg(i), leg(i + 1));
        let mut h = before.end_block(t) + after.start_block(t);
        if let Some(kappa) = &kappa {
            let kappa = kappa(i);
            if kappa != 0.0 {
                h += kappa * (before.arrival() - after.departure()).dot(t.perp());
            }
        }
        diag[i] = h;
        if i + 1 < k {
            off[i] = after.coupling(t, tan[i + 1]);
        }
    }
}

/// [`Eval`] of a one-interaction path, in registers (see [`ProblemRef::evaluate_single`]).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct OnePointEval {
    /// The interaction point minus the source.
    pub p: Vec2,
    /// Unit directions of the two legs.
    pub u: [Vec2; 2],
    /// Leg lengths.
    pub len: [f64; 2],
    /// Their reciprocals (0 for a zero-length leg).
    pub inv_len: [f64; 2],
    /// Travel time.
    pub time: f64,
    /// Residual.
    pub r: f64,
    /// Hessian.
    pub h: f64,
    /// Merit.
    pub phi: f64,
    /// Relative residual (0 when a leg vanished).
    pub rmax: f64,
    /// Whether a leg vanished.
    pub vanished: bool,
    /// See [`Eval::vanish`].
    pub vanish: f64,
}

impl OnePointEval {
    /// Writes this evaluation into `e` (sized for one interaction on the segment `f`), as
    /// [`ProblemRef::evaluate_framed`] would have left it.
    pub fn store(&self, f: &Frame, to_receiver: Vec2, e: &mut Eval) {
        e.rel[..3].copy_from_slice(&[Vec2::default(), self.p, to_receiver]);
        e.u[..2].copy_from_slice(&self.u);
        e.len[..2].copy_from_slice(&self.len);
        e.inv_len[..2].copy_from_slice(&self.inv_len);
        e.tan[0] = f.t;
        e.r[0] = self.r;
        e.diag[0] = self.h;
        e.time = self.time;
        e.phi = self.phi;
        e.rmax = self.rmax;
        e.held = 0;
        e.vanished = self.vanished as usize;
        e.vanish = self.vanish;
    }
}

/// One interaction point's segment, as the solver's fast path needs it: the segment's end
/// points relative to the ray's source, its tangent, the parameters of its ends and its
/// curvature estimate.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Frame {
    /// Start vertex minus the source.
    pub a: Vec2,
    /// End vertex minus the source.
    pub b: Vec2,
    /// Unit tangent.
    pub t: Vec2,
    /// Parameter of the start vertex.
    pub lo: f64,
    /// Parameter of the end vertex.
    pub hi: f64,
    /// [`Polyline::curvature`] of the segment.
    pub kappa: f64,
    /// Largest step along the polyline the solver takes at once (a quarter of a closed
    /// polyline's length; infinite on an open one).
    pub quarter: f64,
}

impl Frame {
    /// The frame of segment `j` of `line`, relative to `origin`.
    #[inline]
    pub fn new(line: &Polyline, j: usize, origin: Point) -> Frame {
        let Segment { start: a, end: b } = line.segment(j);
        Frame {
            a: a - origin,
            b: b - origin,
            t: line.tangent(j),
            lo: line.start(j),
            hi: line.start(j + 1),
            kappa: line.curvature(j),
            quarter: if line.is_closed() {
                0.25 * line.length()
            } else {
                f64::INFINITY
            },
        }
    }

    /// [`Polyline::offset_on`] on this segment (bit for bit).
    #[inline]
    pub fn offset(&self, s: f64) -> Vec2 {
        let from_start = s - self.lo;
        let from_end = self.hi - s;
        if from_start <= from_end {
            self.a + self.t * from_start
        } else {
            self.b - self.t * from_end
        }
    }
}

/// One row of the Thomas forward sweep: row `(sub, diag, sup)` with right-hand side `rhs`,
/// after a row that left `prev_c`, `prev_y`. Returns the row's modified super-diagonal and
/// right-hand side, and whether its pivot is finite and not tiny against the row's scale.
#[inline(always)]
pub(crate) fn sweep_row(
    diag: f64,
    sub: f64,
    sup: f64,
    rhs: f64,
    prev_c: f64,
    prev_y: f64,
) -> (f64, f64, bool) {
    let den = diag - sub * prev_c;
    let scale = diag.abs() + sub.abs() + sup.abs();
    let ok = finite(den) & (den.abs() > 1e-14 * scale);
    let inv = 1.0 / den;
    (sup * inv, (rhs - sub * prev_y) * inv, ok)
}

/// Whether a leg next to point `i` has vanished (is not longer than `vanish`, see
/// [`Eval::vanish`]): there the residual is undefined and the point sits on a corner it
/// shares with its neighbour.
#[inline]
pub(crate) fn leg_vanished(len: &[f64], i: usize, vanish: f64) -> bool {
    len[i] <= vanish || len[i + 1] <= vanish
}

/// Length below which a leg counts as vanished ([`Eval::vanish`]), for a path of length
/// `total` between ends whose largest coordinate is `coord` ([`coord`]): `1e-12` of the
/// path's length plus 8 ulps of the largest coordinate (about whichever is larger). Next to
/// a leg that short the residual is undefined (the leg's direction is round-off) and the
/// point counts as sitting on the kink where the leg vanishes. `8ε·coord` is the round-off of
/// a leg between points of coordinates that large (each carries a few ulps of error), and
/// `1e-12` of the path is the solver's default relative tolerance: a shorter leg is below
/// what the solve resolves. The evaluations (and through them the solver and the
/// classifier), the image-source search and the derivatives all decide with this threshold,
/// so that they agree on which legs vanished.
#[inline(always)]
pub(crate) fn vanish_threshold(total: f64, coord: f64) -> f64 {
    1e-12 * total + 8.0 * f64::EPSILON * coord
}

/// Leg `j` of the columns of an evaluation ([`Eval`]: directions, lengths and their
/// reciprocals), in the medium of slowness `w`.
#[inline(always)]
fn leg_from(u: &[Vec2], len: &[f64], inv_len: &[f64], j: usize, w: f64) -> StraightLeg {
    StraightLeg {
        slowness: w,
        u: u[j],
        len: len[j],
        inv_len: inv_len[j],
    }
}

/// The largest coordinate (in absolute value) of the ends of a ray from `source` to
/// `receiver`: the scale of their round-off ([`ProblemRef::coord`]).
///
/// By compare and select ([`max_num`]): one instruction per maximum where `f64::max`, which
/// ignores NaN, takes several (the one-interaction kernels compute this for every ray). The
/// two agree on every input without NaN, and the ends of a solved ray are finite (the tracer
/// checks them); with a NaN end the path's length is NaN, and so is the threshold built from
/// both ([`vanish_threshold`]), and the flat kernel's test of sides fails, either way.
#[inline(always)]
pub(crate) fn coord(source: Point, receiver: Point) -> f64 {
    let m = max_num(source.x.abs(), source.y.abs());
    max_num(max_num(m, receiver.x.abs()), receiver.y.abs())
}

/// `x.is_finite()` as one compare of `|x|` (the standard bit test takes five instructions, and
/// the one-interaction loops make many such tests).
#[inline(always)]
pub(crate) fn finite(x: f64) -> bool {
    x.abs() < f64::INFINITY
}

/// `f64::max` for a first argument that is never NaN: the larger, or `a` when `b` is NaN
/// (the same result, as one compare and select).
#[inline(always)]
pub(crate) fn max_num(a: f64, b: f64) -> f64 {
    if b > a { b } else { a }
}

/// `f64::min` for a first argument that is never NaN (see [`max_num`]).
#[inline(always)]
pub(crate) fn min_num(a: f64, b: f64) -> f64 {
    if b < a { b } else { a }
}

/// One path's travel-time function of the interaction parameters, for inspection, tests and
/// other solvers (the argmin bridge).
///
/// ```
/// use eigenray::problem::PathProblem;
/// use eigenray::Scene;
/// let scene = Scene::from_json(r#"{
///     "media": { "a": { "speed": 1.0 }, "b": { "speed": 0.5 } },
///     "interfaces": { "flat": { "points": [[-10, 0], [10, 0]] } },
///     "sources": [[0, 1]], "receivers": [[2, -1]],
///     "paths": [{ "steps": [{ "refract": "flat" }], "media": ["a", "b"] }]
/// }"#).unwrap();
/// let p = PathProblem::new(&scene, 0, scene.sources()[0], scene.receivers()[0]).unwrap();
/// // s is arclength from the polyline's first vertex (-10, 0): s = 11 is the point (1, 0).
/// let t = p.time(&[11.0]);
/// assert!((t - (2f64.sqrt() + 2.0 * 2f64.sqrt())).abs() < 1e-12);
/// ```
#[derive(Clone, Debug)]
pub struct PathProblem<'a> {
    scene: &'a Scene,
    path: usize,
    slowness: Vec<f64>,
    /// The legs' models where a leg is curved (see [`ProblemRef::curved`]).
    curved: Vec<LegMedium<'static>>,
    source: Point,
    receiver: Point,
}

impl<'a> PathProblem<'a> {
    /// The problem of path `path` between two points, with the path's own leg media.
    /// `None` when the path has no `media` (its media come from region lookup: use
    /// [`PathProblem::with_slowness`]).
    pub fn new(
        scene: &'a Scene,
        path: usize,
        source: Point,
        receiver: Point,
    ) -> Option<PathProblem<'a>> {
        let media = scene.paths().get(path)?.media.as_ref()?;
        let slowness = media.iter().map(|&m| scene.media()[m].slowness).collect();
        let curved = if scene.curved() {
            let models = media.iter().map(|&m| scene.media()[m].leg_model(source));
            models.collect()
        } else {
            Vec::new()
        };
        Some(PathProblem {
            scene,
            path,
            slowness,
            curved,
            source,
            receiver,
        })
    }

    /// The problem with explicit leg slownesses (`steps + 1` of them).
    ///
    /// # Panics
    /// If `path` is out of range or `slowness` has the wrong length.
    pub fn with_slowness(
        scene: &'a Scene,
        path: usize,
        slowness: Vec<f64>,
        source: Point,
        receiver: Point,
    ) -> Self {
        assert_eq!(
            slowness.len(),
            scene.paths()[path].steps.len() + 1,
            "one slowness per leg"
        );
        PathProblem {
            scene,
            path,
            slowness,
            curved: Vec::new(),
            source,
            receiver,
        }
    }

    /// Number of unknowns (interactions).
    pub fn len(&self) -> usize {
        self.scene.paths()[self.path].steps.len()
    }
    /// Whether the path is the direct ray (no unknowns).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Leg slownesses.
    pub fn slowness(&self) -> &[f64] {
        &self.slowness
    }

    pub(crate) fn as_ref(&self) -> ProblemRef<'_> {
        ProblemRef {
            scene: self.scene,
            steps: &self.scene.paths()[self.path].steps,
            slowness: &self.slowness,
            curved: &self.curved,
            source: self.source,
            receiver: self.receiver,
        }
    }

    fn eval(&self, s: &[f64], hessian: bool) -> Eval {
        let g = self.as_ref();
        let k = g.k();
        assert_eq!(s.len(), k, "one parameter per interaction");
        let mut e = Eval::default();
        e.resize(k);
        let mut ss = vec![0.0; k];
        let mut seg = vec![0; k];
        let pin = vec![Pin::Free; k];
        for i in 0..k {
            let line = g.line(i);
            ss[i] = line.wrap(s[i]);
            seg[i] = line.segment_at(ss[i]);
        }
        g.evaluate(&ss, &seg, &pin, &mut e, hessian, false);
        e
    }

    /// Travel time at parameters `s` (wrapped on closed polylines; on open ones a parameter
    /// outside `[0, length]` extends the end segment).
    pub fn time(&self, s: &[f64]) -> f64 {
        self.eval(s, false).time
    }
    /// The residual `∂T/∂sᵢ`.
    pub fn gradient(&self, s: &[f64]) -> Vec<f64> {
        self.eval(s, false).r
    }
    /// The analytic Hessian of `T` (symmetric tridiagonal; segment-wise, no curvature term).
    pub fn hessian(&self, s: &[f64]) -> Tridiagonal {
        let e = self.eval(s, true);
        Tridiagonal {
            diag: e.diag,
            off: e.off,
        }
    }
    /// Source, interaction points and receiver.
    pub fn points(&self, s: &[f64]) -> Vec<Point> {
        let e = self.eval(s, false);
        e.rel.iter().map(|v| self.source + *v).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`coord`] by compare and select is `f64::max` of the four magnitudes, bit for bit, on
    /// every input without NaN: signed zeros, subnormals, infinities, each coordinate the
    /// largest in turn.
    #[test]
    fn coord_is_the_largest_magnitude() {
        let values = [
            0.0,
            -0.0,
            5e-324,
            -1.5,
            2.0,
            1e300,
            f64::MAX,
            -f64::INFINITY,
        ];
        for a in values {
            for b in values {
                for c in values {
                    for d in values {
                        let expected = a.abs().max(b.abs()).max(c.abs()).max(d.abs());
                        let got = coord(Point::new(a, b), Point::new(c, d));
                        assert_eq!(got.to_bits(), expected.to_bits(), "{a} {b} {c} {d}");
                    }
                }
            }
        }
    }
}
