//! The exact solve of one assignment of segments (with its held vertices), and its arrival.

use crate::geom::{Aabb, Segment, orient};
use crate::problem::Pin;
use crate::scene::StepKind;
use crate::solver::{Outcome, Solution};

use super::Search;
use super::outcome::Settled;
use super::place::Place;
use super::result::{Arrival, Kink};
use crate::trace::classify::side_undecided;
use crate::trace::{Reason, Status, Threshold};

impl Search<'_> {
    /// The assignment of segments `segs` with the points in the bit set `held` on the first
    /// vertices of their segments: its bound, then its solve and classification.
    pub(super) fn solve_leaf_choice(
        &mut self,
        segs: &[usize],
        held: usize,
        out: &mut Vec<Arrival>,
    ) {
        let k = segs.len();
        // Each choice's bound is work too (2^k of them a leaf).
        if self.over_budget(k + 1) {
            return;
        }
        let is_held = |i: usize| held >> i & 1 == 1;
        self.sc.places.clear();
        for (i, &j) in segs.iter().enumerate() {
            let h = self.hierarchies[i];
            let line = self.g.line(i);
            if is_held(i) {
                if h.before(j).is_none() {
                    // The start of an open polyline: an end, not a vertex.
                    return;
                }
                let v = line.vertices()[j];
                let cone = h.vertex_cone(j);
                let place = Place::new(Aabb::from_points(v, v), cone, j, j + 1);
                self.sc.places.push(place);
            } else {
                let Segment { start: p, end: q } = line.segment(j);
                let t = h.theta[j];
                self.sc.places.push(Place {
                    tangent: line.tangent(j),
                    spread: 0.0,
                    ..Place::new(Aabb::from_points(p, q), [t, t], j, j + 1)
                });
            }
            self.sc.places[i].interface = self.g.steps[i].interface;
        }
        if self.pruned()
            || self.consecutive_on_one_line(segs)
            || self.end_on_line(segs, held)
            || self.round_a_corner_past_pi(segs, held)
        {
            return;
        }
        self.stats.solves += 1;
        if self.over_budget(0) {
            return;
        }
        let nw = &mut self.sc.nw;
        for (i, &j) in segs.iter().enumerate() {
            let line = self.g.line(i);
            nw.seg[i] = j;
            if is_held(i) {
                nw.pin[i] = Pin::Vertex;
                nw.s[i] = line.start(j);
            } else {
                nw.pin[i] = Pin::Free;
                // Consecutive points on one segment start apart.
                let f = (i + 1) as f64 / (k + 1) as f64;
                nw.s[i] = line.start(j) + f * (line.start(j + 1) - line.start(j));
            }
        }
        let (settled, iterations) = self.minimise(held);
        self.stats.work += (iterations + 1) * (k + 1);
        match settled {
            Settled::Yes => {}
            Settled::Collapsed | Settled::Outside => return,
            Settled::Threshold(rule) => return self.undecided(rule),
            Settled::No => {
                self.stats.complete = false;
                return;
            }
        }
        // Free points on their segments, ends included (the solve keeps them there, and
        // takes a minimiser within round-off of an end to be at it).
        for (i, &j) in segs.iter().enumerate() {
            let line = self.g.line(i);
            let s = self.sc.nw.s[i];
            let on_segment = (line.start(j)..=line.start(j + 1)).contains(&s);
            if !is_held(i) && !on_segment {
                return;
            }
        }
        let Some(kink) = self.held_kink(segs, held) else {
            return;
        };
        let nw = &self.sc.nw;
        let e = &nw.eval;
        let sol = Solution {
            outcome: if held == 0 {
                Outcome::Converged
            } else {
                Outcome::Vertex
            },
            time: e.time,
            iterations,
            residual: e.rmax,
        };
        let record = self.classifier.classify(
            self.g.scene,
            self.sequence,
            self.g.source,
            self.g.receiver,
            &sol,
            nw,
            &mut self.sc.points,
        );
        if !record.status.has_time() {
            // A side or a vanished leg decided by a threshold is not a proof.
            let rule = match record.reason {
                Some(Reason::Coincident { .. }) => Some(Threshold::VanishedLeg),
                // Exact where the end lies on the step's segment (the path through it is the
                // one without the step); a threshold where it lies only near.
                Some(Reason::AtEnd { step }) if !self.end_on_segment(nw, step) => {
                    Some(Threshold::VanishedLeg)
                }
                Some(Reason::WrongSide { step })
                    if side_undecided(self.g.scene, self.g.steps, nw, &self.sc.points, step) =>
                {
                    Some(Threshold::Side)
                }
                _ => None,
            };
            if let Some(rule) = rule {
                self.undecided(rule);
            }
            return;
        }
        let mut a = self.sc.spare.pop().unwrap_or_else(Arrival::empty);
        a.status = record.status;
        a.time = record.time;
        a.points.clear();
        a.points.extend_from_slice(&self.sc.points);
        a.parameters.clear();
        a.parameters.extend_from_slice(&nw.s[..k]);
        a.segments.clear();
        a.segments.extend_from_slice(segs);
        a.media.clear();
        a.media.extend_from_slice(self.media);
        a.iterations = iterations;
        a.reason = record.reason;
        a.kink = (record.status == Status::Vertex).then_some(kink).flatten();
        a.residual = record.residual;
        a.amplitude = None;
        out.push(a);
    }

    /// Whether two consecutive points of the assignment `segs` lie on segments of one line
    /// (exactly, by the orientation test of both ends): the leg between them runs along it,
    /// on neither side of either (or vanishes), so the assignment holds no stationary path.
    fn consecutive_on_one_line(&self, segs: &[usize]) -> bool {
        (1..segs.len()).any(|i| {
            let a = self.g.line(i - 1).segment(segs[i - 1]);
            let b = self.g.line(i).segment(segs[i]);
            orient(a.start, a.end, b.start) == 0.0 && orient(a.start, a.end, b.end) == 0.0
        })
    }

    /// Whether the source lies exactly on the line of the first point's segment, or the
    /// receiver on the last's (the orientation test), that point free (not in `held`): the
    /// leg between them runs along that line wherever the point is, on neither side of it
    /// (or vanishes); or that point held on a vertex that is the end (the leg vanishes). The
    /// assignment then holds no stationary path. A piece of a diffracted
    /// path that starts or ends at a vertex of the interface it reflects off meets this on
    /// the vertex's own segments.
    fn end_on_line(&self, segs: &[usize], held: usize) -> bool {
        let k = segs.len();
        // A free point next to a point held on a vertex on its segment's line: the leg
        // between them runs along that line too.
        let is_held = |i: usize| held >> i & 1 == 1;
        let beside_held = (0..k).filter(|&i| !is_held(i)).any(|i| {
            let g = self.g.line(i).segment(segs[i]);
            [i.checked_sub(1), Some(i + 1)]
                .into_iter()
                .flatten()
                .filter(|&j| j < k && is_held(j))
                .any(|j| {
                    let held_at = self.g.line(j).vertices().get(segs[j]).copied();
                    held_at.is_some_and(|w| orient(g.start, g.end, w) == 0.0)
                })
        });
        if beside_held {
            return true;
        }
        let on = |i: usize, end: crate::geom::Point| {
            let line = self.g.line(i);
            if held >> i & 1 == 1 {
                // Held on the vertex the end is: the leg vanishes.
                return line.vertices().get(segs[i]) == Some(&end);
            }
            let g = line.segment(segs[i]);
            orient(g.start, g.end, end) == 0.0
        };
        k > 0 && (on(0, self.g.source) || on(k - 1, self.g.receiver))
    }

    /// Whether every free point of `segs` (none held) reflects off a segment of one common
    /// vertex `V`, every leg straight and of one slowness, and the path would have to turn about `V` by
    /// π or more: the angles at `V` between the source, the segments' rays from `V` in turn
    /// and the receiver (each the angle, below π, that a straight leg between them sweeps
    /// about `V`) add up to π or more. The path unfolded about the segments' lines is then a
    /// straight line, which turns about `V` by the same sum and by less than π: no interior
    /// stationary path (a proof; the minimum of the time lies on the corner, where the solve
    /// would stall against vanishing legs). The narrow wedges' alternate reflections, `max_steps`
    /// k with kα > π, are such assignments.
    fn round_a_corner_past_pi(&self, segs: &[usize], held: usize) -> bool {
        const MARGIN: f64 = 1e-9;
        let k = segs.len();
        // Straight legs of one slowness: a reflection's law is then the mirror's.
        let w = self.g.slowness;
        let curved = !self.g.curved.is_empty() || self.g.scene.curved();
        if held != 0 || k < 2 || curved || w.iter().any(|&x| x != w[0]) {
            return false;
        }
        if self.g.steps.iter().any(|s| s.kind != StepKind::Reflect) {
            return false;
        }
        let first = self.g.line(0).segment(segs[0]);
        let corner = (1..k).fold([Some(first.start), Some(first.end)], |found, i| {
            let g = self.g.line(i).segment(segs[i]);
            found.map(|v| v.filter(|&v| v == g.start || v == g.end))
        });
        let Some(v) = corner.into_iter().flatten().next() else {
            return false;
        };
        let ray = |i: usize| {
            let g = self.g.line(i).segment(segs[i]);
            if g.start == v { g.end - v } else { g.start - v }
        };
        let angle = |a: crate::geom::Vec2, b: crate::geom::Vec2| a.cross(b).atan2(a.dot(b)).abs();
        let (from, to) = (self.g.source - v, self.g.receiver - v);
        if from.length() == 0.0 || to.length() == 0.0 {
            return false;
        }
        let mut turn = angle(from, ray(0)) + angle(ray(k - 1), to);
        for i in 1..k {
            turn += angle(ray(i - 1), ray(i));
        }
        turn >= std::f64::consts::PI + MARGIN
    }

    /// Whether the end (source or receiver) that interaction `step` fell on
    /// ([`Reason::AtEnd`]) lies exactly on the step's segment (the exact orientation test, and
    /// within the segment's box): the path through it is then exactly the one without the
    /// step, the points in `nw` and `self.sc.points` (source, interactions, receiver).
    fn end_on_segment(&self, nw: &crate::solver::NewtonWorkspace, step: usize) -> bool {
        let k = self.g.steps.len();
        let points = &self.sc.points;
        let end = if step == 0 && nw.eval.len[0] <= nw.eval.vanish {
            points[0]
        } else {
            points[k + 1]
        };
        let g = self.g.line(step).segment(nw.seg[step]);
        let inside = |x: f64, a: f64, b: f64| a.min(b) <= x && x <= a.max(b);
        orient(g.start, g.end, end) == 0.0
            && inside(end.x, g.start.x, g.end.x)
            && inside(end.y, g.start.y, g.end.y)
    }

    /// A candidate ruled out by `rule`, a threshold: the search is not complete, and says why.
    fn undecided(&mut self, rule: Threshold) {
        self.stats.complete = false;
        self.stats.undecided.get_or_insert(rule);
    }

    /// The kind of kink at the points of `held` (on the first vertices of their segments in
    /// `segs`), the evaluation at the solved points in `self.sc.nw`: `None` when at some held
    /// point the one-sided derivatives along its two segments do not bracket zero (no
    /// stationary path holds it there), or are both zero to round-off (the time is smooth
    /// there: the path is the interior one of either segment, which lists it at the segment's
    /// end). A derivative zero to round-off on one side only brackets zero either way (the
    /// kink is of the kind of the other side).
    fn held_kink(&self, segs: &[usize], held: usize) -> Option<Option<Kink>> {
        let (w, e) = (self.g.slowness, &self.sc.nw.eval);
        let mut kink = None;
        for (i, &j) in segs.iter().enumerate() {
            if held >> i & 1 == 0 {
                continue;
            }
            let line = self.g.line(i);
            let before = if j > 0 {
                j - 1
            } else {
                line.num_segments() - 1
            };
            let v = e.u[i] * w[i] - e.u[i + 1] * w[i + 1];
            let slack = self.residual_round_off(i);
            let sign = |r: f64| {
                if r.abs() <= slack {
                    0
                } else {
                    r.signum() as i32
                }
            };
            let (r_before, r_after) = (v.dot(line.tangent(before)), v.dot(line.tangent(j)));
            let this = match (sign(r_before), sign(r_after)) {
                (-1, 1) | (0, 1) | (-1, 0) => Kink::Minimum,
                (1, -1) | (0, -1) | (1, 0) => Kink::Maximum,
                _ => return None,
            };
            kink = Some(match kink {
                None => this,
                Some(k) if k == this => this,
                Some(_) => Kink::Mixed,
            });
        }
        Some(kink)
    }
}

#[cfg(test)]
mod tests {
    use crate::demo::SplitMix64;
    use crate::geom::{Point, Vec2};
    use crate::trace::Status;
    use crate::trace::complete::branch::tests::mirror;
    use crate::trace::complete::fixture::{Fixture, points_json};
    use crate::trace::complete::{Arrival, Kink};

    /// The unit vector at angle `a`.
    fn unit(a: f64) -> Vec2 {
        Vec2::new(a.cos(), a.sin())
    }

    /// Snell's law at a line of unit tangent `t` for the incoming unit direction `u`, from
    /// slowness `w0` into `w1`: `None` beyond the critical angle.
    fn snell(u: Vec2, t: Vec2, w0: f64, w1: f64) -> Option<Vec2> {
        let n = t.perp();
        let sine = w0 * u.dot(t) / w1;
        let across = u.dot(n).signum() * (1.0 - sine * sine).sqrt();
        (sine.abs() < 1.0).then(|| t * sine + n * across)
    }

    /// Whether segments `a` and `b` share a point.
    fn meet(a: [Point; 2], b: [Point; 2]) -> bool {
        let side = |o: [Point; 2], x: Point| (o[1] - o[0]).cross(x - o[0]);
        side(a, b[0]) * side(a, b[1]) <= 0.0 && side(b, a[0]) * side(b, a[1]) <= 0.0
    }

    /// The arrivals of the assignment `segs` of path 0 with the points in `held` on vertices.
    fn leaf(fixture: &Fixture, segs: &[usize], held: usize) -> Vec<Arrival> {
        let (out, _) = fixture.search(0, |search| {
            let mut out = Vec::new();
            search.solve_leaf_choice(segs, held, &mut out);
            out
        });
        out
    }

    /// Two refractions, built forwards by Snell's law from random lines, slownesses and
    /// angles: the assignment of the two segments holds exactly that path, at its points
    /// and time; the segment moved along its line away from the point, nothing.
    #[test]
    fn two_refractions_are_where_snell_puts_them() {
        let mut rng = SplitMix64(0x5e11);
        let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
        let mut solved = 0;
        for _ in 0..60 {
            let speed = [r(0.4, 2.5), r(0.4, 2.5), r(0.4, 2.5)];
            let w = speed.map(|v| 1.0 / v);
            let x1 = Point::new(r(-2.0, 2.0), r(-2.0, 2.0));
            let t1 = unit(r(-3.0, 3.0));
            let u0 = t1 * r(-0.9, 0.9) - t1.perp() * 1.0;
            let u0 = u0 * (1.0 / u0.length());
            let Some(u1) = snell(u0, t1, w[0], w[1]) else {
                continue;
            };
            let len = [r(0.3, 4.0), r(0.3, 4.0), r(0.3, 4.0)];
            let x2 = x1 + u1 * len[1];
            let t2 = unit(r(-3.0, 3.0));
            let t2 = if u1.dot(t2.perp()) < 0.0 { t2 } else { -t2 };
            if u1.dot(t2.perp()).abs() < 0.2 {
                continue;
            }
            let Some(u2) = snell(u1, t2, w[1], w[2]) else {
                continue;
            };
            let (s, rcv) = (x1 - u0 * len[0], x2 + u2 * len[2]);
            let ends = |x: Point, t: Vec2, back: f64, ahead: f64| [x - t * back, x + t * ahead];
            let scene = |a: [Point; 2], b: [Point; 2]| {
                Fixture::new(&format!(
                    r#"{{
                        "media": {{ "m0": {{ "speed": {:?} }}, "m1": {{ "speed": {:?} }},
                                    "m2": {{ "speed": {:?} }} }},
                        "interfaces": {{ "a": {{ "points": {} }}, "b": {{ "points": {} }} }},
                        "sources": {}, "receivers": {},
                        "paths": [{{ "steps": [{{ "refract": "a" }}, {{ "refract": "b" }}],
                                     "media": ["m0", "m1", "m2"] }}]
                    }}"#,
                    speed[0],
                    speed[1],
                    speed[2],
                    points_json(&a),
                    points_json(&b),
                    points_json(&[s]),
                    points_json(&[rcv])
                ))
            };
            let (ra, rb) = ([r(0.1, 1.0), r(0.1, 1.0)], [r(0.1, 1.0), r(0.1, 1.0)]);
            let b = ends(x2, t2, rb[0], rb[1]);
            let moved = ends(x1 + t1 * (ra[1] + 0.05), t1, 0.0, 1.0);
            if meet(ends(x1, t1, ra[0], ra[1]), b) || meet(moved, b) {
                continue; // Interfaces may not cross.
            }
            let out = leaf(&scene(ends(x1, t1, ra[0], ra[1]), b), &[0, 0], 0);
            assert_eq!(out.len(), 1, "{out:?}");
            let a = &out[0];
            assert!(matches!(a.status, Status::Converged | Status::Obstructed));
            for (p, q) in a.points.iter().zip([s, x1, x2, rcv]) {
                assert!((*p - q).length() <= 1e-9, "{p:?} ≠ {q:?}");
            }
            let time: f64 = (0..3).map(|i| w[i] * len[i]).sum();
            assert!((a.time - time).abs() <= 1e-12 * time, "{} ≠ {time}", a.time);
            assert_eq!((a.segments.as_slice(), a.kink), ([0, 0].as_slice(), None));
            // Segment `a` moved along its line past the point: no path on it.
            assert!(leaf(&scene(moved, b), &[0, 0], 0).is_empty());
            solved += 1;
        }
        assert!(solved > 30, "{solved} cases");
    }

    /// A valley seen from above holds, at its bottom, a path whose time falls off the vertex
    /// both ways (a maximum-type kink); a ridge, at its top, one whose time rises both ways.
    /// The kink and the time checked against the straight legs and finite differences.
    #[test]
    fn a_held_vertex_has_the_kink_of_its_time() {
        let (s, r) = (Point::new(-0.5, 3.0), Point::new(0.5, 3.0));
        let time = |x: Point| (x - s).length() + (r - x).length();
        for (tip, kink) in [(-2.0, Kink::Maximum), (2.0, Kink::Minimum)] {
            let v = [
                Point::new(-3.0, 0.0),
                Point::new(0.0, tip),
                Point::new(3.0, 0.0),
            ];
            // Finite differences off the vertex, along each segment.
            let at = time(v[1]);
            let off = |to: Point| time(v[1] + (to - v[1]) * 1e-7) - at;
            let rises = (off(v[0]) > 0.0, off(v[2]) > 0.0);
            assert_eq!(
                rises,
                if kink == Kink::Minimum {
                    (true, true)
                } else {
                    (false, false)
                }
            );
            let fixture = mirror(&v, s, r);
            let out = leaf(&fixture, &[1], 1);
            assert_eq!(out.len(), 1);
            let a = &out[0];
            assert_eq!((a.status, a.kink), (Status::Vertex, Some(kink)));
            assert_eq!(a.points, [s, v[1], r]);
            assert!((a.time - at).abs() <= 1e-14 * at);
            // The same vertex from the segment before it is not held: its first vertex is
            // the polyline's open end.
            assert!(leaf(&fixture, &[0], 1).is_empty());
        }
    }
}
