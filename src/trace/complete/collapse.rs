//! Collapsing legs and stalled solves: points pinned at a crossing, the subgradient test,
//! restarts apart, and the thresholds of a stall.

use crate::geom::{Vec2, orient};
use crate::problem::Pin;
use crate::trace::Threshold;

use super::Search;
use super::outcome::{Kinked, Settled};

/// Restarts away from collapses per assignment (see `Search::unpin`).
const MAX_RESTARTS: usize = 6;

/// Shortest leg between two interactions, relative to the path's length, below which a solve
/// that stalls is taken to approach a minimum where that leg vanishes (where `T` is not
/// differentiable: no stationary path, the classifier's `coincident`). Where `T` is smooth
/// the damped Newton steps on a convex `T` converge quadratically and do not stall; they
/// stall only next to such a kink, which they approach slowly.
pub(super) const COLLAPSE: f64 = 1e-3;

/// Sine of the angle between a leg and its interaction's segment below which a stalled solve
/// is taken to run along the segment's line.
pub(super) const ALONG: f64 = 1e-7;

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
    /// path's length), or with a leg along its interaction's line (within [`ALONG`]), taken to
    /// hold no stationary path ([`Settled::Threshold`]: by these thresholds, not a proof);
    /// otherwise not settled.
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
        Kinked::Settled(if short {
            Settled::Threshold(Threshold::ShortLeg)
        } else if !(0..k).any(along) {
            Settled::No
        } else if self.along_exactly() {
            Settled::Collapsed
        } else {
            Settled::Threshold(Threshold::Grazing)
        })
    }

    /// Whether every leg that runs along its interaction's line (within [`ALONG`]) does so
    /// exactly: the source or the receiver at its far end lies exactly on that line (by the
    /// orientation test). Such a leg lies on neither side wherever its point is, or vanishes
    /// onto the end (a collapse), so the assignment holds no stationary path.
    fn along_exactly(&self) -> bool {
        let (k, nw) = (self.g.k(), &self.sc.nw);
        let e = &nw.eval;
        let on = |i: usize, x: crate::geom::Point| {
            let g = self.g.line(i).segment(nw.seg[i]);
            orient(g.start, g.end, x) == 0.0
        };
        (0..k).all(|i| {
            let a = e.u[i].cross(e.tan[i]).abs() <= ALONG;
            let b = e.u[i + 1].cross(e.tan[i]).abs() <= ALONG;
            (!a || (i == 0 && on(0, self.g.source)))
                && (!b || (i + 1 == k && on(k - 1, self.g.receiver)))
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
    /// there while the others settle. Where it cannot: a point held on a vertex (or by a pinned
    /// neighbour) that the other reached, or no crossing inside the segments. Decided exactly
    /// where it can be ([`collapse_onto_fixed`](Self::collapse_onto_fixed): the subgradient at
    /// the held point; [`on_one_line`](Self::on_one_line): a leg along one line lies on no
    /// side): no stationary path. Otherwise taken to hold none by the rule of [`COLLAPSE`] (or
    /// of the vanishing threshold, for a leg that short): not a proof.
    pub(super) fn pin(&mut self, held: usize, j: usize) -> Kinked {
        let (a, b) = (j - 1, j);
        if self.pinned_points() & ((1 << a) | (1 << b)) != 0 && !self.smoothed {
            // Three points on one spot: the smoothed time decides.
            self.smoothed = true;
            return self.smooth_away(held);
        }
        let fixed = (held | self.pinned_points()) & ((1 << a) | (1 << b)) != 0;
        let Some([sa, sb]) = self.crossing(j).filter(|_| !fixed) else {
            let exact = if fixed {
                self.collapse_onto_fixed(held | self.pinned_points(), j)
            } else {
                self.on_one_line(j)
            };
            if exact {
                return Kinked::Settled(Settled::Collapsed);
            }
            if fixed
                && self.moved_off < MAX_RESTARTS
                && self.move_off(held | self.pinned_points(), j)
            {
                self.moved_off += 1;
                return Kinked::Restarted;
            }
            if fixed && !self.smoothed {
                // Not the minimum, or not decided: the smoothed time moves the points apart
                // or decides.
                self.smoothed = true;
                return self.smooth_away(held);
            }
            let e = &self.sc.nw.eval;
            return Kinked::Settled(Settled::Threshold(if e.len[j] <= e.vanish {
                Threshold::VanishedLeg
            } else {
                Threshold::ShortLeg
            }));
        };
        let nw = &mut self.sc.nw;
        (nw.s[a], nw.s[b]) = (sa, sb);
        (nw.pin[a], nw.pin[b]) = (Pin::Vertex, Pin::Vertex);
        self.pinned |= 1 << j;
        Kinked::Restarted
    }

    /// Whether the two segments of leg `j`'s points lie on one line (exactly): a leg between
    /// them runs along it wherever the points are, on neither side of either, so the
    /// assignment holds no stationary path.
    fn on_one_line(&self, j: usize) -> bool {
        let nw = &self.sc.nw;
        let sa = self.g.line(j - 1).segment(nw.seg[j - 1]);
        let sb = self.g.line(j).segment(nw.seg[j]);
        orient(sa.start, sa.end, sb.start) == 0.0 && orient(sa.start, sa.end, sb.end) == 0.0
    }

    /// Whether the collapse of leg `j` onto a held point (in `fixed`) is exactly the minimum:
    /// the run of vanished legs through it (at most three points on one spot) on one vertex,
    /// the time rising from it in every direction the free points may move
    /// ([`cluster_is_minimum`](Self::cluster_is_minimum)).
    fn collapse_onto_fixed(&self, fixed: usize, j: usize) -> bool {
        let [a, b] = self.vanished_run(j);
        self.cluster_is_minimum(a, b, fixed)
    }

    /// The points `[a, b]` joined by the run of vanished legs through leg `j`.
    fn vanished_run(&self, j: usize) -> [usize; 2] {
        let (k, e) = (self.g.k(), &self.sc.nw.eval);
        let gone = |l: usize| e.len[l] <= e.vanish;
        let first = (1..=j).rev().take_while(|&l| gone(l)).last().unwrap_or(j);
        let last = (j..k).take_while(|&l| gone(l)).last().unwrap_or(j);
        [first - 1, last]
    }

    /// Where the run of vanished legs through leg `j` holds one free point on a held point's
    /// vertex and the time falls as it moves off into its segment
    /// ([`falls_off`](Self::falls_off)): moves it there, by the one of 10⁻¹ … 10⁻⁶ of the
    /// path's length where the time is least. `false` when it cannot.
    fn move_off(&mut self, fixed: usize, j: usize) -> bool {
        let [a, b] = self.vanished_run(j);
        let Some((i, sign)) = self.falls_off(a, b, fixed) else {
            return false;
        };
        let k = self.g.k();
        let total: f64 = self.sc.nw.eval.len[..=k].iter().sum();
        let [lo, hi] = self.extent(i);
        let from = self.sc.nw.s[i];
        let mut best = (f64::INFINITY, from);
        let mut delta = 0.1 * total;
        for _ in 0..6 {
            let sc = &mut *self.sc;
            sc.s_try[..k].copy_from_slice(&sc.nw.s[..k]);
            sc.s_try[i] = (from + sign * delta).clamp(lo, hi);
            let nw = &sc.nw;
            self.g
                .evaluate(&sc.s_try, &nw.seg, &nw.pin, &mut sc.trial, false, false);
            if sc.trial.time < best.0 {
                best = (sc.trial.time, sc.s_try[i]);
            }
            delta *= 0.1;
        }
        self.sc.nw.s[i] = best.1;
        best.1 != from
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
                // A neighbouring leg vanished too: exactly a collapse where every leg is
                // zero (the source is the receiver, every point on it).
                return Kinked::Settled(if total == 0.0 {
                    Settled::Collapsed
                } else {
                    Settled::No
                });
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
            Kinked::Settled(Settled::Collapsed)
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

#[cfg(test)]
mod tests {
    use crate::demo::SplitMix64;
    use crate::geom::{Point, Vec2};
    use crate::problem::Pin;
    use crate::trace::complete::Search;
    use crate::trace::complete::fixture::{Fixture, points_json};
    use crate::trace::complete::outcome::{Kinked, Settled};

    /// Two reflections off the polyline through `v`, from `s` to `r`.
    fn twice(v: &[Point], s: Point, r: Point) -> Fixture {
        Fixture::new(&format!(
            r#"{{
                "media": {{ "air": {{ "speed": 1.0 }} }},
                "interfaces": {{ "v": {{ "points": {} }} }},
                "sources": {}, "receivers": {},
                "paths": [{{ "steps": [{{ "reflect": "v" }}, {{ "reflect": "v" }}],
                             "media": ["air", "air", "air"] }}]
            }}"#,
            points_json(v),
            points_json(&[s]),
            points_json(&[r])
        ))
    }

    /// Puts the two points on segments `segs` at fractions `f` of them, free, and evaluates.
    fn place(search: &mut Search<'_>, segs: [usize; 2], f: [f64; 2]) {
        let nw = &mut search.sc.nw;
        for i in 0..2 {
            let line = search.g.line(i);
            let (a, b) = (line.start(segs[i]), line.start(segs[i] + 1));
            (nw.seg[i], nw.pin[i], nw.s[i]) = (segs[i], Pin::Free, a + f[i] * (b - a));
        }
        search
            .g
            .evaluate(&nw.s, &nw.seg, &nw.pin, &mut nw.eval, true, false);
    }

    /// On random polylines, `crossing` gives the parameters where the lines of two segments
    /// cross when that is inside both (Cramer's rule on the segments' ends, independently),
    /// and none otherwise; `pin` holds both points there.
    #[test]
    fn the_crossing_is_where_the_lines_meet() {
        let mut rng = SplitMix64(0xc405);
        let (mut inside, mut outside) = (0, 0);
        for _ in 0..40 {
            let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
            let v: Vec<Point> = (0..6)
                .map(|i| Point::new(i as f64 + r(0.0, 0.8), r(-2.0, 2.0)))
                .collect();
            let f = [r(0.0, 1.0), r(0.0, 1.0)];
            let fixture = twice(&v, Point::new(0.0, 5.0), Point::new(6.0, 5.0));
            for ja in 0..5 {
                for jb in 0..5 {
                    let (pa, qa, pb, qb) = (v[ja], v[ja + 1], v[jb], v[jb + 1]);
                    let (da, db) = (qa - pa, qb - pb);
                    let det = da.cross(db);
                    // pa + α da = pb + β db.
                    let (alpha, beta) = ((pb - pa).cross(db) / det, (pb - pa).cross(da) / det);
                    let near = |x: f64| x.abs().min((x - 1.0).abs()) < 1e-6;
                    let adjacent = ja + 1 == jb || jb + 1 == ja;
                    if ja == jb || (!adjacent && (near(alpha) || near(beta))) {
                        continue;
                    }
                    // (On a polyline that does not cross itself: adjacent segments only.)
                    let meets = (-1e-12..=1.0 + 1e-12).contains(&alpha)
                        && (-1e-12..=1.0 + 1e-12).contains(&beta);
                    assert_eq!(meets, adjacent);
                    fixture.search(0, |search| {
                        place(search, [ja, jb], f);
                        let got = search.crossing(1);
                        assert_eq!(got.is_some(), meets, "{ja}, {jb}: {alpha}, {beta}");
                        let Some([sa, sb]) = got else { return };
                        let x = pa + da * alpha;
                        let line = search.g.line(0);
                        let scale = 1e-9 * (1.0 + x.x.abs() + x.y.abs());
                        assert!((line.point_on(ja, sa) - x).length() <= scale);
                        assert!((line.point_on(jb, sb) - x).length() <= scale);
                        // Pinned: both points held there.
                        assert!(matches!(search.pin(0, 1), Kinked::Restarted));
                        let nw = &search.sc.nw;
                        assert_eq!(
                            (nw.s[0], nw.s[1], nw.pin[0], nw.pin[1]),
                            (sa, sb, Pin::Vertex, Pin::Vertex)
                        );
                        assert_eq!((search.pinned, search.pinned_points()), (0b10, 0b11));
                    });
                    if meets {
                        inside += 1;
                    } else {
                        outside += 1;
                    }
                }
            }
        }
        assert!(inside > 100 && outside > 100, "{inside} {outside}");
    }

    /// Two interfaces in a T: `b` ends on `a` (the line y = 0, exactly); the lines of the
    /// two segments cross there, inside `a` and at `b`'s end.
    #[test]
    fn the_crossing_of_a_t_junction() {
        let mut rng = SplitMix64(0x7);
        for _ in 0..50 {
            let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
            let (c, angle, len) = (r(-1.5, 1.5), r(0.2, 2.9), r(0.5, 2.0));
            let x = Point::new(c, 0.0);
            let top = x + Vec2::new(angle.cos(), angle.sin()) * len;
            let fixture = Fixture::new(&format!(
                r#"{{
                    "media": {{ "air": {{ "speed": 1.0 }} }},
                    "interfaces": {{ "a": {{ "points": [[-2, 0], [2, 0]] }},
                                     "b": {{ "points": {} }} }},
                    "sources": [[-1, 3]], "receivers": [[1, 3]],
                    "paths": [{{ "steps": [{{ "reflect": "a" }}, {{ "reflect": "b" }}],
                                 "media": ["air", "air", "air"] }}]
                }}"#,
                points_json(&[top, x])
            ));
            let f = [r(0.0, 1.0), r(0.0, 1.0)];
            fixture.search(0, |search| {
                place(search, [0, 0], f);
                let [sa, sb] = search.crossing(1).expect("the lines cross at the junction");
                assert!((sa - (c + 2.0)).abs() <= 1e-12 && (sb - len).abs() <= 1e-12 * len);
            });
        }
    }

    /// Parallel segments have no crossing; a point already held by a vertex cannot be pinned,
    /// and where the other is not on its vertex the collapse is not a proof (the smoothed time
    /// takes over).
    #[test]
    fn parallel_or_held_points_do_not_pin() {
        let v = [
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(1.0, 1.0),
            Point::new(2.0, 1.0),
        ];
        let fixture = twice(&v, Point::new(0.0, 3.0), Point::new(2.0, 3.0));
        fixture.search(0, |search| {
            place(search, [0, 2], [0.5, 0.5]);
            assert_eq!(search.crossing(1), None);
            place(search, [0, 1], [0.5, 0.5]);
            assert_eq!(search.crossing(1), Some([1.0, 1.0]));
            let proof = |k| matches!(k, Kinked::Settled(Settled::Collapsed));
            assert!(!proof(search.pin(0b01, 1)));
            assert!(search.smoothed);
            assert_eq!(search.pinned, 0);
        });
    }
}
