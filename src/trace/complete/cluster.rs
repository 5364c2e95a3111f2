//! Whether interactions that collapse onto one polyline vertex are exactly the minimum of the
//! time: the directional derivative of the time at the collapse, minimised over the
//! directions the points may move in.
//!
//! Points `a ..= b` of an assignment all at one vertex `V` (an end of each of their
//! segments), the other points settled: moving point `i` by `δᵢ ≥ 0` along `dᵢ`, the unit
//! direction from `V` into its segment, changes the time at first order by
//!
//! ```text
//! T′(δ) = wₐ u_in · δₐ dₐ + Σ_{a<l≤b} w_l |δ_l d_l − δ_{l−1} d_{l−1}| − w_{b+1} u_out · δ_b d_b
//! ```
//!
//! (`u_in` the unit vector from the point before the cluster to `V`, `u_out` from `V` to the
//! point after; the legs between the collapsed points grow as the norms of their ends'
//! moves, exactly, since every point moves along a line through `V`). The other points' own
//! derivatives are zero there and `T` is differentiable in them, so `T′` is the directional
//! derivative of `T` in every direction that moves the cluster. `T` being convex, the collapse
//! is its minimum over the segments exactly when `T′ ≥ 0` in every direction; `T′` is convex
//! and positively homogeneous, so that is its minimum over the simplex `Σ δᵢ = 1`, found by
//! (nested) ternary search. A minimum above round-off proves the collapse (no stationary
//! path); anything else is left to the thresholds.

use crate::geom::{Point, Vec2};

use super::Search;

/// Golden-section steps per dimension: the interval shrinks by 0.618^76 ≈ 1e-16.
const STEPS: usize = 76;

/// The most points of a cluster this test takes (a simplex of two dimensions).
const MAX_POINTS: usize = 3;

impl Search<'_> {
    /// Whether points `a ..= b` (2 or 3 of them, one run of collapsed legs) sit on one vertex
    /// that ends each of their segments and the time's directional derivative there is
    /// positive beyond round-off in every direction the points not in `fixed` (held on the
    /// vertex) may move: the collapse is then exactly the minimum (see the module).
    pub(super) fn cluster_is_minimum(&self, a: usize, b: usize, fixed: usize) -> bool {
        let Some(c) = self.cluster(a, b, fixed) else {
            return false;
        };
        let along = |x: &[f64]| c.slope_free(x);
        let least = match c.free_count {
            // Every point held there: the legs between them vanish exactly.
            0 => return true,
            1 => along(&[1.0]),
            2 => golden(0.0, 1.0, |x| along(&[x, 1.0 - x])),
            _ => golden(0.0, 1.0, |x| {
                golden(0.0, 1.0 - x, |y| along(&[x, y, 1.0 - x - y]))
            }),
        };
        least > 1e-12 * c.scale
    }

    /// Where points `a ..= b` sit on one vertex with one free point among them (not in
    /// `fixed`) and the time falls (beyond round-off) as that point moves off into its
    /// segment: the point, and the sign of its parameter's move.
    pub(super) fn falls_off(&self, a: usize, b: usize, fixed: usize) -> Option<(usize, f64)> {
        let c = self.cluster(a, b, fixed)?;
        if c.free_count != 1 || c.slope_free(&[1.0]) >= -1e-12 * c.scale {
            return None;
        }
        let i = a + c.free[0];
        let t = self.g.line(i).tangent(self.sc.nw.seg[i]);
        Some((i, c.dirs[c.free[0]].dot(t).signum()))
    }

    /// The cluster of points `a ..= b` (2 or 3) on one vertex ending each of their segments,
    /// the points not in `fixed` free to move off it.
    fn cluster(&self, a: usize, b: usize, fixed: usize) -> Option<Cluster> {
        let m = b + 1 - a;
        if !(2..=MAX_POINTS).contains(&m) {
            return None;
        }
        let nw = &self.sc.nw;
        let vertex_of = |i: usize| {
            let ends = self.g.line(i).segment(nw.seg[i]);
            let p = self.g.line(i).point_on(nw.seg[i], nw.s[i]);
            // The end nearer the point.
            if (p - ends.start).length() <= (p - ends.end).length() {
                (ends.start, self.g.line(i).tangent(nw.seg[i]))
            } else {
                (ends.end, -self.g.line(i).tangent(nw.seg[i]))
            }
        };
        let (v, _) = vertex_of(a);
        let mut dirs = [Vec2::default(); MAX_POINTS];
        for (d, i) in dirs.iter_mut().zip(a..=b) {
            let (vi, into) = vertex_of(i);
            if vi != v {
                return None;
            }
            *d = into;
        }
        // The points before and after the cluster (source, receiver or an interaction).
        let k = self.g.k();
        let at = |i: usize| -> Point {
            match i {
                0 => self.g.source,
                i if i == k + 1 => self.g.receiver,
                i => self.g.line(i - 1).point_on(nw.seg[i - 1], nw.s[i - 1]),
            }
        };
        let vanish = nw.eval.vanish;
        let u_in = unit(v - at(a), vanish)?;
        let u_out = unit(at(b + 2) - v, vanish)?;
        let mut w = [0.0; MAX_POINTS + 1];
        w[..=m].copy_from_slice(&self.g.slowness[a..=b + 1]);
        let mut free = [0; MAX_POINTS];
        let mut free_count = 0;
        for i in (a..=b).filter(|&i| fixed >> i & 1 == 0) {
            free[free_count] = i - a;
            free_count += 1;
        }
        Some(Cluster {
            m,
            dirs,
            u_in,
            u_out,
            w,
            free,
            free_count,
            scale: w[..=m].iter().sum(),
        })
    }
}

/// Points collapsed on one vertex (see the module).
struct Cluster {
    /// How many.
    m: usize,
    /// Each one's unit direction from the vertex into its segment.
    dirs: [Vec2; MAX_POINTS],
    /// The unit vector from the point before the cluster to the vertex.
    u_in: Vec2,
    /// The unit vector from the vertex to the point after.
    u_out: Vec2,
    /// The slownesses of the legs into, between and out of the cluster (`m + 1`).
    w: [f64; MAX_POINTS + 1],
    /// The points that may move (their places in the cluster).
    free: [usize; MAX_POINTS],
    /// How many may.
    free_count: usize,
    /// The sum of the slownesses: the scale of the derivative's round-off.
    scale: f64,
}

impl Cluster {
    /// `T′(δ)` (see the module) for the moves `delta` of the cluster's points.
    fn slope(&self, delta: &[f64]) -> f64 {
        let (m, d, w) = (self.m, &self.dirs, &self.w);
        let mut t =
            w[0] * self.u_in.dot(d[0]) * delta[0] - w[m] * self.u_out.dot(d[m - 1]) * delta[m - 1];
        for l in 1..m {
            let v = d[l] * delta[l] - d[l - 1] * delta[l - 1];
            t += w[l] * v.dot(v).sqrt();
        }
        t
    }

    /// `T′` for the moves `x` of the free points alone.
    fn slope_free(&self, x: &[f64]) -> f64 {
        let mut delta = [0.0; MAX_POINTS];
        for (c, &f) in x.iter().zip(&self.free[..self.free_count]) {
            delta[f] = *c;
        }
        self.slope(&delta[..self.m])
    }
}

/// `d / |d|`, if `d` is longer than `vanish`.
fn unit(d: Vec2, vanish: f64) -> Option<Vec2> {
    let len = d.length();
    (len > vanish).then(|| d * (1.0 / len))
}

/// The minimum of the convex `f` over `[lo, hi]`, by golden-section search (one evaluation
/// a step), and at the ends.
fn golden(lo: f64, hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    const R: f64 = 0.618_033_988_749_894_9;
    let (mut x, mut y) = (lo, hi);
    let (mut p, mut q) = (y - R * (y - x), x + R * (y - x));
    let (mut fp, mut fq) = (f(p), f(q));
    for _ in 0..STEPS {
        if fp <= fq {
            (y, q, fq) = (q, p, fp);
            p = y - R * (y - x);
            fp = f(p);
        } else {
            (x, p, fp) = (p, q, fq);
            q = x + R * (y - x);
            fq = f(q);
        }
    }
    f(lo).min(f(hi)).min(fp).min(fq)
}

#[cfg(test)]
mod tests {
    use super::golden;
    use crate::demo::SplitMix64;
    use crate::geom::{Point, Vec2};
    use crate::trace::complete::Search;
    use crate::trace::complete::fixture::{Fixture, points_json};

    /// Golden-section search finds the minimum of convex functions, at an end or inside.
    #[test]
    fn golden_finds_the_minimum() {
        assert!((golden(0.0, 1.0, |x| (x - 0.3).powi(2) + 2.0) - 2.0).abs() < 1e-15);
        assert!((golden(0.0, 1.0, |x| (x - 0.3).abs()) - 0.0).abs() < 1e-15);
        assert_eq!(golden(0.0, 1.0, |x| 1.0 - x), 0.0);
        let nested = golden(0.0, 1.0, |x| {
            golden(0.0, 1.0 - x, |y| (x - 0.2).abs() + (y - 0.5).abs())
        });
        assert!(nested.abs() < 1e-14, "{nested}");
    }

    /// Two points collapsed on the apex of a random V (two segments), random ends and
    /// slownesses: `cluster_is_minimum` says the collapse is the minimum exactly where every
    /// small move of the points off the apex into their arms (a grid over the simplex of
    /// moves, by finite differences of the time itself) makes the time rise; where it is not,
    /// and one point is held, `falls_off` names the other and the way it falls.
    #[test]
    fn a_collapse_on_a_vertex_is_decided_by_its_slopes() {
        let mut rng = SplitMix64(0xc105);
        let (mut minima, mut not) = (0, 0);
        for _ in 0..300 {
            let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
            let apex = Point::new(r(-1.0, 1.0), r(-1.0, 1.0));
            let (a0, a1) = (r(0.0, std::f64::consts::TAU), r(0.0, std::f64::consts::TAU));
            let arm = |a: f64| apex + Vec2::new(a.cos(), a.sin()) * 2.0;
            let v = [arm(a0), apex, arm(a1)];
            let (s, t) = (
                Point::new(r(-4.0, 4.0), r(-4.0, 4.0)),
                Point::new(r(-4.0, 4.0), r(-4.0, 4.0)),
            );
            let speeds = [r(0.5, 2.0), r(0.5, 2.0), r(0.5, 2.0)];
            let fixture = Fixture::new(&format!(
                r#"{{
                    "media": {{ "a": {{ "speed": {:?} }}, "b": {{ "speed": {:?} }},
                                "c": {{ "speed": {:?} }} }},
                    "interfaces": {{ "v": {{ "points": {} }} }},
                    "sources": {}, "receivers": {},
                    "paths": [{{ "steps": [{{ "reflect": "v" }}, {{ "reflect": "v" }}],
                                 "media": ["a", "b", "c"] }}]
                }}"#,
                speeds[0],
                speeds[1],
                speeds[2],
                points_json(&v),
                points_json(&[s]),
                points_json(&[t])
            ));
            let w = speeds.map(|c| 1.0 / c);
            let time = |x: Point, y: Point| {
                w[0] * (x - s).length() + w[1] * (y - x).length() + w[2] * (t - y).length()
            };
            let into = [(v[0] - apex) * 0.5, (v[2] - apex) * 0.5];
            // Finite-difference slopes over a grid of the simplex of moves (h small).
            let h = 1e-7;
            let slope = |d0: f64, d1: f64| {
                (time(apex + into[0] * (h * d0), apex + into[1] * (h * d1)) - time(apex, apex)) / h
            };
            let least = (0..=100)
                .map(|n| n as f64 / 100.0)
                .map(|x| slope(x, 1.0 - x))
                .fold(f64::INFINITY, f64::min);
            if least.abs() < 1e-4 {
                continue; // Too near the border for finite differences.
            }
            let ((minimum, off), _) = fixture.search(0, |search: &mut Search<'_>| {
                let at = search.g.line(0).start(1);
                let nw = &mut search.sc.nw;
                (nw.seg[0], nw.s[0], nw.seg[1], nw.s[1]) = (0, at, 1, at);
                search
                    .g
                    .evaluate(&nw.s, &nw.seg, &nw.pin, &mut nw.eval, true, false);
                (
                    search.cluster_is_minimum(0, 1, 0),
                    search.falls_off(0, 1, 0b01),
                )
            });
            assert_eq!(
                minimum,
                least > 0.0,
                "{v:?} {s:?} {t:?} {speeds:?}: {least}"
            );
            // Point 0 held: the second falls off exactly where its own slope is negative.
            let alone = slope(0.0, 1.0);
            if alone.abs() > 1e-4 {
                assert_eq!(off.is_some(), alone < 0.0, "{alone}");
                if let Some((i, sign)) = off {
                    assert_eq!((i, sign), (1, 1.0));
                }
            }
            if minimum {
                minima += 1;
            } else {
                not += 1;
            }
        }
        assert!(minima > 30 && not > 30, "{minima} {not}");
    }
}
