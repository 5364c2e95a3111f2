//! Collapsing legs and stalled solves: points pinned at a crossing, the subgradient test,
//! restarts apart, and the thresholds of a stall.

use crate::geom::Vec2;
use crate::problem::Pin;

use super::Search;
use super::minimise::Settled;

/// Restarts away from collapses per assignment (see `Search::unpin`).
const MAX_RESTARTS: usize = 6;

/// Shortest leg between two interactions, relative to the path's length, below which a solve
/// that stalls is taken to approach a minimum where that leg vanishes (where `T` is not
/// differentiable: no stationary path, the classifier's `coincident`). Where `T` is smooth
/// the damped Newton steps on a convex `T` converge quadratically and do not stall; they
/// stall only next to such a kink, which they approach slowly.
const COLLAPSE: f64 = 1e-3;

/// Sine of the angle between a leg and its interaction's segment below which a stalled solve
/// is taken to run along the segment's line.
const ALONG: f64 = 1e-7;

/// What a collapse or a stall of an assignment's solve leads to.
pub(super) enum Kinked {
    /// The solve ends so.
    Settled(Settled),
    /// Points were pinned at a collapse, or moved away from one that is not the minimum:
    /// the solve goes on.
    Restarted,
}

/// What [`Search::kink_direction`] finds of a pinned leg.
struct KinkDirection {
    /// The direction that makes both points' residuals vanish.
    both: Vec2,
    /// The least `|g|` that makes the collapse a minimum over the segments.
    least: f64,
    /// Whether the collapse sits at an end of either segment.
    at_end: bool,
}

impl Search<'_> {
    /// A solve that stalled or ran out of steps at the evaluation in `self.sc.nw`, where `T`
    /// is smooth only away from collapsed legs: the shortest leg between two free points on
    /// crossing lines is pinned ([`pin`](Self::pin); the subgradient test then decides
    /// exactly). Without such a leg: next to a vanishing leg (within [`COLLAPSE`] of the
    /// path's length), or with a leg along its interaction's line (within [`ALONG`]), no
    /// stationary path ([`Settled::Degenerate`], by these thresholds); otherwise not settled.
    pub(super) fn stalled(&mut self, held: usize) -> Kinked {
        let k = self.g.k();
        let e = &self.sc.nw.eval;
        let total: f64 = e.len[..=k].iter().sum();
        let fixed = held | self.pinned_points();
        let pinnable = |j: usize| {
            e.len[j] <= COLLAPSE * total
                && fixed & ((1 << (j - 1)) | (1 << j)) == 0
                && self.crossing(j).is_some()
        };
        let shortest = (1..k)
            .filter(|&j| pinnable(j))
            .min_by(|&x, &y| e.len[x].total_cmp(&e.len[y]));
        if let Some(j) = shortest {
            return self.pin(held, j);
        }
        let along = |i: usize| {
            e.u[i].cross(e.tan[i]).abs() <= ALONG || e.u[i + 1].cross(e.tan[i]).abs() <= ALONG
        };
        let short = (0..=k).any(|j| e.len[j] <= COLLAPSE * total);
        Kinked::Settled(if short || (0..k).any(along) {
            Settled::Degenerate
        } else {
            Settled::No
        })
    }

    /// Where points `j − 1` and `j` meet if their leg collapses: their parameters at the
    /// crossing of their segments' lines, when the lines cross (not parallel) inside both
    /// segments (to round-off).
    fn crossing(&self, j: usize) -> Option<[f64; 2]> {
        let (a, b) = (j - 1, j);
        let nw = &self.sc.nw;
        let e = &nw.eval;
        let (ta, tb) = (e.tan[a], e.tan[b]);
        let det = ta.cross(tb);
        if det.abs() <= 1e-9 {
            return None;
        }
        let d = e.rel[b + 1] - e.rel[a + 1];
        let at = [nw.s[a] + d.cross(tb) / det, nw.s[b] + d.cross(ta) / det];
        let mut out = at;
        for (x, i) in out.iter_mut().zip([a, b]) {
            let [lo, hi] = self.extent(i);
            let pad = 1e-9 * (hi - lo);
            if !(*x >= lo - pad && *x <= hi + pad) {
                return None;
            }
            *x = x.clamp(lo, hi);
        }
        Some(out)
    }

    /// Pins collapsing leg `j`: its two points to the crossing of their segments' lines, held
    /// there while the others settle. Points held on vertices, a point already held by a
    /// pinned neighbour (three points on one spot), or no crossing inside the segments
    /// (points meeting along one line, where no side holds): no stationary path, by the rule
    /// of [`COLLAPSE`].
    pub(super) fn pin(&mut self, held: usize, j: usize) -> Kinked {
        let (a, b) = (j - 1, j);
        if self.pinned_points() & ((1 << a) | (1 << b)) != 0 && !self.smoothed {
            // Three points on one spot: the smoothed time decides.
            self.smoothed = true;
            return self.smooth_away(held);
        }
        let fixed = (held | self.pinned_points()) & ((1 << a) | (1 << b)) != 0;
        let Some([sa, sb]) = self.crossing(j).filter(|_| !fixed) else {
            return Kinked::Settled(Settled::Degenerate);
        };
        let nw = &mut self.sc.nw;
        (nw.s[a], nw.s[b]) = (sa, sb);
        (nw.pin[a], nw.pin[b]) = (Pin::Vertex, Pin::Vertex);
        self.pinned |= 1 << j;
        Kinked::Restarted
    }

    /// The other points settled with the pinned legs held: every pinned leg whose collapse is
    /// not at the minimum ([`kink_direction`](Self::kink_direction) `|g| > 1`) restarts
    /// ([`restart_apart`](Self::restart_apart); at most [`MAX_RESTARTS`] times in a solve,
    /// then not settled); when none does, `0 ∈ ∂T` at the collapse: no stationary path.
    pub(super) fn unpin(&mut self, restarts: &mut usize) -> Kinked {
        let k = self.g.k();
        let total: f64 = self.sc.nw.eval.len[..=k].iter().sum();
        let (mut moved, mut at_end) = (false, false);
        for j in 1..k {
            if self.pinned >> j & 1 == 0 {
                continue;
            }
            let Some(kink) = self.kink_direction(j) else {
                return Kinked::Settled(Settled::No);
            };
            if kink.least <= 1.0 {
                at_end |= kink.at_end;
                continue;
            }
            if *restarts >= MAX_RESTARTS {
                return Kinked::Settled(Settled::No);
            }
            let n = kink.both.length();
            self.restart_apart(j, kink.both * (1.0 / n), total);
            moved = true;
        }
        if moved {
            *restarts += 1;
            Kinked::Restarted
        } else if at_end {
            // The minimum over the segments has points at their ends.
            Kinked::Settled(Settled::Outside)
        } else {
            Kinked::Settled(Settled::Degenerate)
        }
    }

    /// Frees pinned leg `j`'s two points, apart along the unit direction `dir` (`σ_b t_b −
    /// σₐ tₐ = δ dir`): `δ` the one of 10⁻¹ … 10⁻⁶ of the path's length `total` where `T` is
    /// least (the leg of the minimum is short where `|g|` is near 1).
    fn restart_apart(&mut self, j: usize, dir: Vec2, total: f64) {
        let (a, b) = (j - 1, j);
        let (ea, eb) = (self.extent(a), self.extent(b));
        let sc = &mut *self.sc;
        let (ta, tb) = (sc.nw.eval.tan[a], sc.nw.eval.tan[b]);
        let det = ta.cross(tb);
        (sc.nw.pin[a], sc.nw.pin[b]) = (Pin::Free, Pin::Free);
        let (sa, sb) = (sc.nw.s[a], sc.nw.s[b]);
        let k = self.g.k();
        let mut best = (f64::INFINITY, 0.0);
        let mut delta = 0.1 * total;
        for _ in 0..6 {
            let v = dir * delta;
            sc.s_try[..k].copy_from_slice(&sc.nw.s[..k]);
            sc.s_try[a] = (sa - v.cross(tb) / det).clamp(ea[0], ea[1]);
            sc.s_try[b] = (sb + ta.cross(v) / det).clamp(eb[0], eb[1]);
            let nw = &sc.nw;
            self.g
                .evaluate(&sc.s_try, &nw.seg, &nw.pin, &mut sc.trial, false, false);
            if sc.trial.time < best.0 {
                best = (sc.trial.time, delta);
            }
            delta *= 0.1;
        }
        let v = dir * best.1;
        sc.nw.s[a] = (sa - v.cross(tb) / det).clamp(ea[0], ea[1]);
        sc.nw.s[b] = (sb + ta.cross(v) / det).clamp(eb[0], eb[1]);
        self.pinned &= !(1 << j);
    }

    /// For pinned leg `j` (points `a = j − 1`, `b = j` on one spot `X`): the directions `g`
    /// that in place of the leg's would make `X` a minimum over the segments, given the
    /// others: `w g · tₐ = wᵢₙ uᵢₙ · tₐ` and `w g · t_b = wₒᵤₜ uₒᵤₜ · t_b`, each equation an
    /// inequality where its point sits at an end of its segment (`T` may only rise inwards).
    /// `T` being convex, `X` is the minimum exactly when one of them has `|g| ≤ 1`. `None`
    /// when a neighbouring leg has vanished too.
    fn kink_direction(&self, j: usize) -> Option<KinkDirection> {
        let (a, b) = (j - 1, j);
        let e = &self.sc.nw.eval;
        let (ta, tb) = (e.tan[a], e.tan[b]);
        let det = ta.cross(tb);
        if e.len[a] <= e.vanish || e.len[j + 1] <= e.vanish {
            return None;
        }
        let w = self.g.slowness;
        let alpha = w[a] * e.u[a].dot(ta) / w[j];
        let beta = w[j + 1] * e.u[j + 1].dot(tb) / w[j];
        // Both equations: the direction to restart along.
        let both = Vec2::new(
            (alpha * tb.y - ta.y * beta) / det,
            (ta.x * beta - alpha * tb.x) / det,
        );
        // Where a point sits at an end, its equation holds as `g · t ≤ c` or `≥ c`
        // (∂T/∂s ≥ 0 at the start, ≤ 0 at the end; ∂T/∂sₐ = w (c − g · tₐ) for `a`,
        // ∂T/∂s_b = w (g · t_b − c) for `b`).
        let nw = &self.sc.nw;
        let side = |i: usize| {
            let [lo, hi] = self.extent(i);
            if nw.s[i] <= lo {
                -1
            } else if nw.s[i] >= hi {
                1
            } else {
                0
            }
        };
        let holds = |g: Vec2| {
            let pad = 1e-12;
            let ok = |v: f64, c: f64, sense: i32| match sense {
                0 => (v - c).abs() <= pad,
                s if s < 0 => v <= c + pad,
                _ => v >= c - pad,
            };
            // At its start, g · tₐ ≤ α for `a` and g · t_b ≥ β for `b`.
            ok(g.dot(ta), alpha, side(a)) && ok(g.dot(tb), beta, -side(b))
        };
        let least = [Vec2::default(), ta * alpha, tb * beta]
            .into_iter()
            .filter(|&g| holds(g))
            .map(Vec2::length)
            .fold(both.length(), f64::min);
        let at_end = side(a) != 0 || side(b) != 0;
        (both.length().is_finite()).then_some(KinkDirection {
            both,
            least,
            at_end,
        })
    }
}
