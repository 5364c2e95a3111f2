//! The exact solve of one assignment of segments (with its held vertices), and its arrival.

use crate::geom::Aabb;
use crate::problem::Pin;
use crate::solver::{Outcome, Solution};

use super::Search;
use super::minimise::Settled;
use super::place::Place;
use super::result::{Arrival, Kink};
use crate::trace::Status;

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
                let (p, q) = line.segment(j);
                let t = h.theta[j];
                self.sc.places.push(Place {
                    tangent: line.tangent(j),
                    spread: 0.0,
                    ..Place::new(Aabb::from_points(p, q), [t, t], j, j + 1)
                });
            }
            self.sc.places[i].interface = self.g.steps[i].interface;
        }
        if self.pruned() {
            return;
        }
        self.stats.solves += 1;
        if self.stats.solves > self.max_tuples {
            self.stats.complete = false;
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
        match settled {
            Settled::Yes => {}
            Settled::Degenerate | Settled::Outside => return,
            Settled::No => {
                self.stats.complete = false;
                return;
            }
        }
        let nw = &self.sc.nw;
        let e = &nw.eval;
        // Free points strictly inside their segments.
        for (i, &j) in segs.iter().enumerate() {
            let line = self.g.line(i);
            let inside = nw.s[i] > line.start(j) && nw.s[i] < line.start(j + 1);
            if !is_held(i) && !inside {
                return;
            }
        }
        // Held points: the one-sided derivatives bracket zero.
        let w = self.g.slowness;
        let mut kink = None;
        for (i, &j) in segs.iter().enumerate() {
            if !is_held(i) {
                continue;
            }
            let line = self.g.line(i);
            let before = if j > 0 {
                j - 1
            } else {
                line.num_segments() - 1
            };
            let v = e.u[i] * w[i] - e.u[i + 1] * w[i + 1];
            let (r_before, r_after) = (v.dot(line.tangent(before)), v.dot(line.tangent(j)));
            let this = if r_before < 0.0 && r_after > 0.0 {
                Kink::Minimum
            } else if r_before > 0.0 && r_after < 0.0 {
                Kink::Maximum
            } else {
                return;
            };
            kink = Some(match kink {
                None => this,
                Some(k) if k == this => this,
                Some(_) => Kink::Mixed,
            });
        }
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
        a.complete = true;
        out.push(a);
    }
}
