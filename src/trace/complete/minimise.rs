//! The damped Newton minimisation of the time over one assignment's segments.

use crate::geom::orient;
use crate::scene::MAX_STATIONARY_STEPS;
use crate::solver::thomas;
use crate::trace::Threshold;

use super::Search;
use super::outcome::{Kinked, Settled};

/// Newton steps per assignment (again after each pin or restart).
const MAX_STEPS: usize = 200;

/// How one Newton step of an assignment's solve went.
enum NewtonStep {
    /// The points moved.
    Moved,
    /// The step is below round-off: at the minimum.
    Done,
    /// No step descends.
    Stalled,
    /// The Hessian cannot be solved, even damped.
    Singular,
}

impl Search<'_> {
    /// Minimises the time over the free points on the lines of their segments (the held ones
    /// stay on their vertices) from the state in `self.sc.nw`: damped Newton steps on the
    /// analytic Hessian of `problem` with backtracking on `T` itself, which is convex there.
    ///
    /// Where a leg between two free points collapses, `T` has a kink: the two points are held
    /// together at their lines' crossing (the leg *pinned*) while the others settle, and then
    /// the subgradient decides ([`kink_direction`](Self::kink_direction)): when every pinned
    /// leg's `|g| ≤ 1`, `0 ∈ ∂T` and the minimum is the collapse (no stationary path); a
    /// pinned leg with `|g| > 1` is not at the minimum, and its points restart apart along `g`.
    /// Returns how it ended and the steps taken; leaves the evaluation at the end in
    /// `self.sc.nw.eval`.
    pub(super) fn minimise(&mut self, held: usize) -> (Settled, usize) {
        let k = self.g.k();
        let tol = self.tolerance;
        let (mut steps, mut budget, mut restarts) = (0, MAX_STEPS, 0);
        self.pinned = 0;
        self.smoothed = false;
        self.moved_off = 0;
        loop {
            let nw = &mut self.sc.nw;
            self.g
                .evaluate(&nw.s, &nw.seg, &nw.pin, &mut nw.eval, true, false);
            let e = &nw.eval;
            let pinned = self.pinned;
            let collapsed = (1..k).find(|&j| pinned >> j & 1 == 0 && e.len[j] <= e.vanish);
            // Free points at an end of their segment that T pushes outwards stay there.
            let outward = self.outward(held | self.pinned_points());
            let now = held | self.pinned_points() | outward;
            let verdict = if let Some(j) = collapsed {
                // Two points on one spot: held there while the others settle.
                Some(self.pin(held, j))
            } else if self.sc.nw.eval.vanished > 0 {
                // The source or the receiver on an interaction's spot.
                return (self.end_collapsed(), steps);
            } else if !self.sc.nw.eval.rmax.is_finite() {
                return (Settled::No, steps);
            } else if self.residual(now) <= tol || k == 0 || now == (1 << k) - 1 {
                self.settled(held, outward, &mut restarts)
            } else if steps >= budget {
                Some(self.stalled(held))
            } else {
                match self.newton_step(now) {
                    NewtonStep::Moved => {
                        steps += 1;
                        None
                    }
                    NewtonStep::Done => self.settled(held, outward, &mut restarts),
                    // A singular Hessian: legs along their lines, or next to a kink.
                    NewtonStep::Singular => Some(self.stalled(held)),
                    // Within round-off of the minimum, or next to a kink of `T`.
                    NewtonStep::Stalled if self.residual(now) <= 1e-8 => {
                        self.settled(held, outward, &mut restarts)
                    }
                    NewtonStep::Stalled => Some(self.stalled(held)),
                }
            };
            match verdict {
                None => {}
                Some(Kinked::Settled(settled)) => return (settled, steps),
                Some(Kinked::Restarted) => budget = steps + MAX_STEPS,
            }
        }
    }

    /// The minimum over the segments is reached (the points not in `outward` settled): with
    /// pinned legs, first the subgradient test ([`unpin`](Self::unpin)), which may restart;
    /// then, with a point held at a segment's end by `T` pushing outwards, the minimum of the
    /// convex `T` lies outside the segments and no stationary path is inside them; otherwise
    /// the minimiser (or the collapse's verdict).
    fn settled(&mut self, held: usize, outward: usize, restarts: &mut usize) -> Option<Kinked> {
        let pinned = if self.pinned != 0 {
            match self.unpin(restarts) {
                Kinked::Settled(settled) => Some(settled),
                restarted => return Some(restarted),
            }
        } else {
            None
        };
        Some(Kinked::Settled(match (outward, pinned) {
            (0, None) if self.minimiser_inside(held) => Settled::Yes,
            (0, Some(settled)) => settled,
            _ => Settled::Outside,
        }))
    }

    /// Whether one more Newton step from the settled points leaves every free point inside
    /// its segment, ends included: the minimiser of `T` on the segments' lines itself, not a
    /// point the tolerance accepted next to a segment's end while the minimiser lies beyond
    /// it. A minimiser beyond an end by no more than the round-off of the parameters counts as
    /// at that end (a path that reflects exactly at an open end, or at a vertex between two
    /// segments on one line, is a path); the point is put there.
    fn minimiser_inside(&mut self, held: usize) -> bool {
        if !self.newton_direction(held) {
            return true;
        }
        let inside = (0..self.g.k()).filter(|&i| held >> i & 1 == 0).all(|i| {
            let [lo, hi] = self.extent(i);
            let s = self.sc.nw.s[i] + self.sc.delta[i];
            let slack = 16.0 * f64::EPSILON * (lo.abs() + hi.abs());
            s >= lo - slack && s <= hi + slack
        });
        if inside {
            // Points that the step would take past an end (to round-off) stay at it.
            for i in (0..self.g.k()).filter(|&i| held >> i & 1 == 0) {
                let [lo, hi] = self.extent(i);
                let s = &mut self.sc.nw.s[i];
                *s = s.clamp(lo, hi);
            }
        }
        inside
    }

    /// The round-off of the residual of point `i` at the evaluation in `self.sc.nw`: a few
    /// ulps of the slownesses, grown by the ratio of the path's length to its shorter leg (the
    /// directions of the legs are differences of points). A residual this small is zero to
    /// round-off.
    pub(super) fn residual_round_off(&self, i: usize) -> f64 {
        let (k, e, w) = (self.g.k(), &self.sc.nw.eval, self.g.slowness);
        let total: f64 = e.len[..=k].iter().sum();
        // (A vanished leg, whose direction does not count, is left out.)
        let shorter = [e.len[i], e.len[i + 1]]
            .into_iter()
            .filter(|&l| l > e.vanish)
            .fold(total, f64::min);
        16.0 * f64::EPSILON * (w[i] + w[i + 1]) * (1.0 + total / shorter)
    }

    /// A leg to the source or the receiver vanished (within the vanishing threshold): exactly
    /// a collapse when that end lies exactly on the line of its interaction's segment (the
    /// exact orientation test), by the threshold otherwise (an end that near the line, whose
    /// path may exist with a leg that short).
    fn end_collapsed(&self) -> Settled {
        let (k, e) = (self.g.k(), &self.sc.nw.eval);
        let on_line = |i: usize, end: crate::geom::Point| {
            let (line, j) = (self.g.line(i), self.sc.nw.seg[i]);
            let seg = line.segment(j);
            orient(seg.start, seg.end, end) == 0.0
        };
        let exact = (e.len[0] > e.vanish || on_line(0, self.g.source))
            && (e.len[k] > e.vanish || on_line(k - 1, self.g.receiver));
        if exact {
            Settled::Collapsed
        } else {
            Settled::Threshold(Threshold::VanishedLeg)
        }
    }

    /// The extent `[start, end]` of point `i`'s segment, in its polyline's parameter.
    pub(super) fn extent(&self, i: usize) -> [f64; 2] {
        let (line, j) = (self.g.line(i), self.sc.nw.seg[i]);
        [line.start(j), line.start(j + 1)]
    }

    /// The points not in `fixed` that sit at an end of their segment with the residual
    /// pushing them out of it (beyond its round-off: a residual zero to round-off at an end
    /// is a minimiser there).
    fn outward(&self, fixed: usize) -> usize {
        let nw = &self.sc.nw;
        (0..self.g.k())
            .filter(|&i| fixed >> i & 1 == 0)
            .filter(|&i| {
                let [lo, hi] = self.extent(i);
                let (r, slack) = (nw.eval.r[i], self.residual_round_off(i));
                (nw.s[i] <= lo && r > slack) || (nw.s[i] >= hi && r < -slack)
            })
            .fold(0, |m, i| m | 1 << i)
    }

    /// The largest relative residual of the points not in `fixed`.
    fn residual(&self, fixed: usize) -> f64 {
        let (e, w) = (&self.sc.nw.eval, self.g.slowness);
        (0..self.g.k())
            .filter(|&i| fixed >> i & 1 == 0)
            .map(|i| e.r[i].abs() / (w[i] + w[i + 1]))
            .fold(0.0, f64::max)
    }

    /// The points of the pinned legs (leg `j` joins points `j − 1` and `j`).
    pub(super) fn pinned_points(&self) -> usize {
        self.pinned | (self.pinned >> 1)
    }

    /// The Newton step in `self.sc.delta` for the points not in `fixed` (0 for those), from
    /// the evaluation in `self.sc.nw`; damped where the Hessian is singular (legs along a
    /// segment's line). `false` when even the damped one cannot be solved.
    fn newton_direction(&mut self, fixed: usize) -> bool {
        let k = self.g.k();
        let is_fixed = |i: usize| fixed >> i & 1 == 1;
        let sc = &mut *self.sc;
        let e = &sc.nw.eval;
        for i in 0..k {
            let free = !is_fixed(i);
            sc.diag[i] = if free { e.diag[i] } else { 1.0 };
            sc.rhs[i] = if free { -e.r[i] } else { 0.0 };
            if i + 1 < k {
                sc.off[i] = if free && !is_fixed(i + 1) {
                    e.off[i]
                } else {
                    0.0
                };
            }
        }
        let n = k.saturating_sub(1);
        if thomas(&sc.diag, &sc.off[..n], &sc.rhs, &mut sc.delta, &mut sc.cp) {
            return true;
        }
        let scale = sc.diag.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        for d in &mut sc.diag {
            *d += 1e-9 * scale + f64::MIN_POSITIVE;
        }
        thomas(&sc.diag, &sc.off[..n], &sc.rhs, &mut sc.delta, &mut sc.cp)
    }

    /// One damped Newton step of [`minimise`](Self::minimise) from the evaluation in
    /// `self.sc.nw` for the points not in `held`, with backtracking on `T` along the step
    /// projected onto the segments (held points do not move: their step is 0).
    fn newton_step(&mut self, held: usize) -> NewtonStep {
        let k = self.g.k();
        let mut extent = [[f64::NEG_INFINITY, f64::INFINITY]; MAX_STATIONARY_STEPS];
        for (i, x) in extent.iter_mut().enumerate().take(k) {
            *x = self.extent(i);
        }
        // A point at an end of its segment that the step would push out of it stays there:
        // the step again without it (the Hessian of the rest stays positive definite).
        let mut fixed = held;
        loop {
            if !self.newton_direction(fixed) {
                return NewtonStep::Singular;
            }
            let (s, delta) = (&self.sc.nw.s, &self.sc.delta);
            let out = (0..k)
                .filter(|&i| fixed >> i & 1 == 0)
                .filter(|&i| {
                    let [lo, hi] = extent[i];
                    (s[i] <= lo && delta[i] < 0.0) || (s[i] >= hi && delta[i] > 0.0)
                })
                .fold(0, |m, i| m | 1 << i);
            if out == 0 {
                break;
            }
            fixed |= out;
        }
        let sc = &mut *self.sc;
        let (s, e) = (&sc.nw.s, &sc.nw.eval);
        let tiny = (0..k).all(|i| {
            sc.delta[i].abs() <= 4.0 * f64::EPSILON * (s[i].abs() + e.len[i] + e.len[i + 1])
        });
        if tiny {
            return NewtonStep::Done;
        }
        // No point moves further than twice its longer leg at once.
        let mut cap = 1.0f64;
        for i in 0..k {
            let reach = 2.0 * e.len[i].max(e.len[i + 1]);
            if sc.delta[i].abs() > reach {
                cap = cap.min(reach / sc.delta[i].abs());
            }
        }
        let slope: f64 = (0..k).map(|i| e.r[i] * sc.delta[i]).sum();
        // The residual of the moving points (the others' is held where it is).
        let w = self.g.slowness;
        let moving = |r: &[f64]| {
            (0..k)
                .filter(|&i| fixed >> i & 1 == 0)
                .map(|i| r[i].abs() / (w[i] + w[i + 1]))
                .fold(0.0, f64::max)
        };
        let (t0, rmax0) = (e.time, moving(&e.r));
        let mut alpha = cap;
        loop {
            for (i, &[lo, hi]) in extent.iter().enumerate().take(k) {
                sc.s_try[i] = (sc.nw.s[i] + alpha * sc.delta[i]).clamp(lo, hi);
            }
            let nw = &sc.nw;
            self.g
                .evaluate(&sc.s_try, &nw.seg, &nw.pin, &mut sc.trial, false, false);
            let drop = t0 - sc.trial.time;
            // Descent on T, or (within round-off of T) on the residual.
            let round_off = 4.0 * f64::EPSILON * t0;
            if drop >= -1e-4 * alpha * slope || (drop >= -round_off && moving(&sc.trial.r) < rmax0)
            {
                sc.nw.s[..k].copy_from_slice(&sc.s_try[..k]);
                return NewtonStep::Moved;
            }
            alpha *= 0.5;
            if alpha < 1e-12 {
                return NewtonStep::Stalled;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::SplitMix64;
    use crate::geom::{Point, Vec2};
    use crate::polyline::Polyline;
    use crate::problem::Pin;
    use crate::trace::complete::fixture::{Fixture, points_json};

    /// The minimum of the convex `f` over `[lo, hi]` (ternary search) and where it is.
    fn ternary(lo: f64, hi: f64, f: impl Fn(f64) -> f64) -> (f64, f64) {
        let (mut a, mut b) = (lo, hi);
        for _ in 0..90 {
            let (m1, m2) = (a + (b - a) / 3.0, b - (b - a) / 3.0);
            if f(m1) <= f(m2) {
                b = m2;
            } else {
                a = m1;
            }
        }
        let x = 0.5 * (a + b);
        (f(x), x)
    }

    /// Where the brute force puts the minimum of a convex time over the two segments.
    #[derive(Debug, PartialEq)]
    enum Minimum {
        /// Both points strictly inside their segments, apart.
        Inside,
        /// A point at an end of its segment, or the two on one spot: no stationary path.
        Edge,
        /// Too near the border between the two to tell.
        Unclear,
    }

    /// Two reflections off a random V (two segments meeting at a corner), each assignment
    /// of the two points to its segments: the solve ends at the minimum of the time over
    /// the segments that a brute force (nested ternary searches on the convex time) finds
    /// and says `Yes` where that minimum lies inside both segments (apart); it says `Outside`
    /// or a collapse (exactly or by a threshold) where the minimum lies at an end or on one.
    #[test]
    fn the_solve_finds_the_brute_force_minimum() {
        let mut rng = SplitMix64(0x3a1c);
        let mut seen = [0usize; 3];
        for case in 0..80 {
            let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
            let (a, open) = (r(0.0, 6.3), r(0.3, 2.8));
            let corner = Point::new(r(-1.0, 1.0), r(-1.0, 1.0));
            let arm = |angle: f64, len: f64| corner + Vec2::new(angle.cos(), angle.sin()) * len;
            let v = [arm(a, r(1.0, 3.0)), corner, arm(a + open, r(1.0, 3.0))];
            let (s, rcv) = (
                Point::new(r(-3.0, 3.0), r(-3.0, 3.0)),
                Point::new(r(-3.0, 3.0), r(-3.0, 3.0)),
            );
            let fixture = Fixture::new(&format!(
                r#"{{
                    "media": {{ "air": {{ "speed": 1.0 }} }},
                    "interfaces": {{ "v": {{ "points": {} }} }},
                    "sources": {}, "receivers": {},
                    "paths": [{{ "steps": [{{ "reflect": "v" }}, {{ "reflect": "v" }}],
                                 "media": ["air", "air", "air"] }}]
                }}"#,
                points_json(&v),
                points_json(&[s]),
                points_json(&[rcv])
            ));
            let line: &Polyline = &fixture.scene.interfaces()[0].polyline;
            for segs in [[0, 0], [0, 1], [1, 0], [1, 1]] {
                let ext = segs.map(|j| [line.start(j), line.start(j + 1)]);
                let at = |i: usize, x: f64| line.point_on(segs[i], x);
                let time = |a: f64, b: f64| {
                    let (pa, pb) = (at(0, a), at(1, b));
                    (pa - s).length() + (pb - pa).length() + (rcv - pb).length()
                };
                let (best, sa) = ternary(ext[0][0], ext[0][1], |a| {
                    ternary(ext[1][0], ext[1][1], |b| time(a, b)).0
                });
                let sb = ternary(ext[1][0], ext[1][1], |b| time(sa, b)).1;
                let margin =
                    |i: usize, x: f64| (x - ext[i][0]).min(ext[i][1] - x) / (ext[i][1] - ext[i][0]);
                let gap = (at(1, sb) - at(0, sa)).length();
                let inner = margin(0, sa).min(margin(1, sb));
                // (A solve that stalls next to a leg shorter than `COLLAPSE` of the path
                // takes it to vanish: a rule, so a short leg is not clearly inside.)
                let expected = if inner > 1e-4 && gap > 1e-2 {
                    Minimum::Inside
                } else if inner.min(gap) < 1e-7 {
                    Minimum::Edge
                } else {
                    Minimum::Unclear
                };
                let ((settled, solved), _) = fixture.search(0, |search| {
                    let nw = &mut search.sc.nw;
                    for (i, &j) in segs.iter().enumerate() {
                        nw.seg[i] = j;
                        nw.pin[i] = Pin::Free;
                        nw.s[i] = ext[i][0] + (i + 1) as f64 / 3.0 * (ext[i][1] - ext[i][0]);
                    }
                    let (settled, _) = search.minimise(0);
                    (settled, search.sc.nw.eval.time)
                });
                let what = format!("case {case} {segs:?}: {expected:?}, {solved} vs {best}");
                match settled {
                    Settled::Yes => {
                        assert_ne!(expected, Minimum::Edge, "{what}");
                        assert!((solved - best).abs() <= 1e-9 * best, "{what}");
                        seen[0] += 1;
                    }
                    Settled::Outside | Settled::Collapsed | Settled::Threshold(_) => {
                        assert_ne!(expected, Minimum::Inside, "{what}");
                        seen[1 + !matches!(settled, Settled::Outside) as usize] += 1;
                    }
                    Settled::No => panic!("not settled: {what}"),
                }
            }
        }
        // Each ending is reached.
        assert!(seen.iter().all(|&n| n >= 5), "{seen:?}");
    }
}
