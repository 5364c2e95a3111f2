//! The minimum of the time with its kinks smoothed away, where several points collapse on one
//! spot.

use crate::geom::{Point, Vec2};
use crate::problem::Pin;
use crate::scene::MAX_STATIONARY_STEPS;
use crate::solver::thomas;

use super::Search;
use super::outcome::{Kinked, Settled};

impl Search<'_> {
    /// Where several points collapse onto one spot, follows the minimum of the time with its
    /// kinks smoothed away (`|d| → √(|d|² + ε²)` on the legs between interactions, ε from
    /// 10⁻² down to 10⁻¹⁰ of the path's length; `T_ε` is convex and smooth, its minimisers
    /// tend to `T`'s): where legs stay below 10⁻⁶ of the path's length, the collapse is taken
    /// to be the minimum, exactly where the points sit on one vertex and the time rises from
    /// it every way ([`cluster_is_minimum`](Self::cluster_is_minimum): no stationary path),
    /// by that threshold otherwise (not a proof); where none does, the points, now apart, go
    /// on with `T` itself. Pins are cleared either way.
    pub(super) fn smooth_away(&mut self, held: usize) -> Kinked {
        let k = self.g.k();
        let fixed = held;
        for i in 0..k {
            if fixed >> i & 1 == 0 {
                self.sc.nw.pin[i] = Pin::Free;
            }
        }
        self.pinned = 0;
        let total: f64 = self.sc.nw.eval.len[..=k].iter().sum();
        if total == 0.0 {
            // Every point on the source, which is the receiver: exactly a collapse.
            return Kinked::Settled(Settled::Collapsed);
        } else if !(total > 0.0 && total.is_finite()) {
            return Kinked::Settled(Settled::No);
        }
        let mut eps = 1e-2 * total;
        while eps >= 1e-10 * total {
            for _ in 0..60 {
                if !self.smoothed_step(fixed, eps) {
                    break;
                }
            }
            eps *= 0.1;
        }
        let len = self.smoothed_legs(0.0);
        let collapsed = |l: usize| len[l] <= 1e-6 * total;
        if !(1..k).any(collapsed) {
            return Kinked::Restarted;
        }
        // One run of collapsed legs on one vertex, its derivative positive every way: exactly
        // the minimum. Otherwise the rule's threshold decided.
        let first = (1..k).find(|&l| collapsed(l)).unwrap_or(1);
        let last = (first..k)
            .take_while(|&l| collapsed(l))
            .last()
            .unwrap_or(first);
        let one_run = !(last + 1..k).any(collapsed);
        Kinked::Settled(
            if one_run && self.cluster_is_minimum(first - 1, last, fixed) {
                Settled::Collapsed
            } else {
                Settled::Threshold(crate::trace::Threshold::ShortLeg)
            },
        )
    }

    /// The legs' lengths at the present points, those between interactions smoothed by
    /// `eps`.
    fn smoothed_legs(&self, eps: f64) -> [f64; MAX_STATIONARY_STEPS + 1] {
        let k = self.g.k();
        let mut out = [0.0; MAX_STATIONARY_STEPS + 1];
        let mut prev = self.g.source;
        for (l, x) in out.iter_mut().enumerate().take(k + 1) {
            let p = self.smoothed_point(l);
            let d = p - prev;
            let smooth = if l >= 1 && l < k { eps * eps } else { 0.0 };
            *x = (d.dot(d) + smooth).sqrt();
            prev = p;
        }
        out
    }

    /// Point `l` of the path (the receiver for `l = k`) at the parameters in `self.sc.nw`.
    fn smoothed_point(&self, l: usize) -> Point {
        let nw = &self.sc.nw;
        if l == self.g.k() {
            self.g.receiver
        } else {
            self.g.line(l).point_on(nw.seg[l], nw.s[l])
        }
    }

    /// One damped Newton step on the smoothed time `T_ε` over the points not in `fixed`,
    /// each kept on its segment: `false` when it no longer descends.
    fn smoothed_step(&mut self, fixed: usize, eps: f64) -> bool {
        let k = self.g.k();
        let w = self.g.slowness;
        let time = |this: &Self| -> f64 {
            let len = this.smoothed_legs(eps);
            (0..=k).map(|l| w[l] * len[l]).sum()
        };
        // Legs, their smoothed lengths and Hessian blocks M = w (I/f − d dᵀ/f³).
        let mut d = [Vec2::default(); MAX_STATIONARY_STEPS + 1];
        let mut prev = self.g.source;
        for (l, x) in d.iter_mut().enumerate().take(k + 1) {
            let p = self.smoothed_point(l);
            *x = p - prev;
            prev = p;
        }
        let f = self.smoothed_legs(eps);
        let tan = |i: usize| self.g.line(i).tangent(self.sc.nw.seg[i]);
        let m = |l: usize, a: Vec2, b: Vec2| {
            w[l] * (a.dot(b) / f[l] - a.dot(d[l]) * b.dot(d[l]) / (f[l] * f[l] * f[l]))
        };
        for i in 0..k {
            let t = tan(i);
            let free = fixed >> i & 1 == 0;
            let r = w[i] * d[i].dot(t) / f[i] - w[i + 1] * d[i + 1].dot(t) / f[i + 1];
            self.sc.rhs[i] = if free { -r } else { 0.0 };
            self.sc.diag[i] = if free {
                m(i, t, t) + m(i + 1, t, t)
            } else {
                1.0
            };
            if i + 1 < k {
                let both = free && fixed >> (i + 1) & 1 == 0;
                self.sc.off[i] = if both { -m(i + 1, t, tan(i + 1)) } else { 0.0 };
            }
        }
        let n = k.saturating_sub(1);
        let sc = &mut *self.sc;
        if !thomas(&sc.diag, &sc.off[..n], &sc.rhs, &mut sc.delta, &mut sc.cp) {
            return false;
        }
        let t0 = time(self);
        let saved: [f64; MAX_STATIONARY_STEPS] =
            std::array::from_fn(|i| if i < k { self.sc.nw.s[i] } else { 0.0 });
        let mut alpha = 1.0;
        while alpha > 1e-10 {
            for (i, &start) in saved.iter().enumerate().take(k) {
                let [lo, hi] = self.extent(i);
                self.sc.nw.s[i] = (start + alpha * self.sc.delta[i]).clamp(lo, hi);
            }
            if time(self) < t0 {
                return true;
            }
            alpha *= 0.5;
        }
        self.sc.nw.s[..k].copy_from_slice(&saved[..k]);
        false
    }
}

#[cfg(test)]
mod tests {
    use crate::demo::SplitMix64;
    use crate::geom::{Point, Vec2};
    use crate::problem::Pin;
    use crate::trace::complete::Search;
    use crate::trace::complete::fixture::{Fixture, points_json};

    /// The smoothed time at the present points, from the points themselves.
    fn smoothed_time(search: &Search<'_>, eps: f64) -> f64 {
        let g = &search.g;
        let nw = &search.sc.nw;
        let mut points = vec![g.source];
        points.extend((0..g.k()).map(|i| g.line(i).point_on(nw.seg[i], nw.s[i])));
        points.push(g.receiver);
        (0..points.len() - 1)
            .map(|l| {
                let d = points[l + 1] - points[l];
                let e = if l >= 1 && l < g.k() { eps } else { 0.0 };
                g.slowness[l] * (d.dot(d) + e * e).sqrt()
            })
            .sum()
    }

    /// Three reflections off random polylines (three points, two legs between them): the
    /// smoothed legs are the legs, those between interactions with `ε` added in quadrature;
    /// a smoothed Newton step lowers the smoothed time (computed from the points), or leaves
    /// the points where they are.
    #[test]
    fn smoothed_steps_lower_the_smoothed_time() {
        let mut rng = SplitMix64(0x5300);
        let (mut moved, mut stayed) = (0, 0);
        for _ in 0..30 {
            let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
            let v: Vec<Point> = (0..5)
                .map(|i| Point::new(i as f64 + r(0.0, 0.9), r(-1.0, 1.0)))
                .collect();
            let fixture = Fixture::new(&format!(
                r#"{{
                    "media": {{ "air": {{ "speed": 1.0 }}, "slow": {{ "speed": 0.5 }} }},
                    "interfaces": {{ "v": {{ "points": {} }} }},
                    "sources": {}, "receivers": {},
                    "paths": [{{ "steps": [{{ "reflect": "v" }}, {{ "reflect": "v" }},
                                           {{ "reflect": "v" }}],
                                 "media": ["air", "slow", "slow", "air"] }}]
                }}"#,
                points_json(&v),
                points_json(&[Point::new(r(0.0, 5.0), 3.0)]),
                points_json(&[Point::new(r(0.0, 5.0), 3.0)])
            ));
            let segs = [0, 1, 2].map(|_| (r(0.0, 3.99)) as usize);
            let f = [r(0.0, 1.0), r(0.0, 1.0), r(0.0, 1.0)];
            let eps = [0.0, 1e-3, 0.1][(r(0.0, 2.99)) as usize];
            fixture.search(0, |search| {
                let nw = &mut search.sc.nw;
                for i in 0..3 {
                    let line = search.g.line(i);
                    let (a, b) = (line.start(segs[i]), line.start(segs[i] + 1));
                    (nw.seg[i], nw.pin[i], nw.s[i]) = (segs[i], Pin::Free, a + f[i] * (b - a));
                }
                let legs = search.smoothed_legs(eps);
                let mut prev = search.g.source;
                for (l, len) in legs.iter().enumerate().take(4) {
                    let p = if l < 3 {
                        search.smoothed_point(l)
                    } else {
                        search.g.receiver
                    };
                    let d: Vec2 = p - prev;
                    let e = if l == 1 || l == 2 { eps } else { 0.0 };
                    assert!((len - (d.dot(d) + e * e).sqrt()).abs() <= 1e-15 * (1.0 + len));
                    prev = p;
                }
                let eps = eps.max(1e-3);
                for _ in 0..50 {
                    let (before, s) = (smoothed_time(search, eps), search.sc.nw.s.clone());
                    if search.smoothed_step(0, eps) {
                        assert!(smoothed_time(search, eps) < before);
                        moved += 1;
                    } else {
                        assert_eq!(search.sc.nw.s, s);
                        stayed += 1;
                        break;
                    }
                }
            });
        }
        assert!(moved > 30 && stayed > 5, "{moved} {stayed}");
    }
}
