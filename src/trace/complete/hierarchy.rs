//! The segment hierarchy of one polyline: nodes of consecutive segments, each with its box and
//! tangent cone.

use crate::geom::{Aabb, Segment, Vec2};
use crate::polyline::Polyline;

use super::place::Place;

/// A range of consecutive segments of a polyline: its box and tangent cone.
#[derive(Clone, Copy, Debug)]
pub(super) struct Node {
    /// First segment.
    pub(super) first: u32,
    /// The box of the range's vertices.
    pub(super) bbox: Aabb,
    /// The range of tangent angles (unwrapped), the segment before the range included.
    cone: [f64; 2],
    /// Its box and cone as the bound takes them.
    pub(super) place: Place,
    /// The two halves, when the range has more than one segment.
    pub(super) kids: Option<[u32; 2]>,
}

/// A binary hierarchy over one polyline's segments (built once per interface).
#[derive(Clone, Debug)]
pub(crate) struct Hierarchy {
    /// The nodes, the root (every segment) first.
    pub(super) nodes: Vec<Node>,
    /// Unwrapped tangent angle of each segment.
    pub(super) theta: Vec<f64>,
    /// On a closed polyline, the angle of the last segment unwrapped against the first.
    before_first: Option<f64>,
}

impl Hierarchy {
    /// The hierarchy of `line`'s segments.
    pub(crate) fn new(line: &Polyline) -> Hierarchy {
        let m = line.num_segments();
        let turn = |a: Vec2, b: Vec2| a.cross(b).atan2(a.dot(b));
        let mut theta = Vec::with_capacity(m);
        let t0 = line.tangent(0);
        theta.push(t0.y.atan2(t0.x));
        for j in 1..m {
            theta.push(theta[j - 1] + turn(line.tangent(j - 1), line.tangent(j)));
        }
        let before_first = line
            .is_closed()
            .then(|| theta[0] - turn(line.tangent(m - 1), line.tangent(0)));
        let mut h = Hierarchy {
            nodes: Vec::with_capacity(2 * m),
            theta,
            before_first,
        };
        h.build(line, 0, m);
        h
    }

    /// The angle of the segment before `j` (none at an open polyline's start).
    pub(super) fn before(&self, j: usize) -> Option<f64> {
        if j > 0 {
            Some(self.theta[j - 1])
        } else {
            self.before_first
        }
    }

    /// The cone of tangents at the vertex where segment `j` starts.
    pub(super) fn vertex_cone(&self, j: usize) -> [f64; 2] {
        let t = self.theta[j];
        let b = self.before(j).unwrap_or(t);
        [t.min(b), t.max(b)]
    }

    /// Adds the node of segments `a..b` and its descendants; returns its index.
    fn build(&mut self, line: &Polyline, a: usize, b: usize) -> u32 {
        let at = self.nodes.len();
        let Segment { start: p, end: q } = line.segment(a);
        let (bbox, cone) = (Aabb::from_points(p, q), self.vertex_cone(a));
        self.nodes.push(Node {
            first: a as u32,
            bbox,
            cone,
            place: Place::new(bbox, cone, a, a + 1),
            kids: None,
        });
        if b - a > 1 {
            let mid = a + (b - a) / 2;
            let l = self.build(line, a, mid);
            let r = self.build(line, mid, b);
            let (nl, nr) = (self.nodes[l as usize], self.nodes[r as usize]);
            let node = &mut self.nodes[at];
            node.bbox = nl.bbox.union(nr.bbox);
            node.cone = [nl.cone[0].min(nr.cone[0]), nl.cone[1].max(nr.cone[1])];
            node.place = Place::new(node.bbox, node.cone, a, b);
            node.kids = Some([l, r]);
        }
        at as u32
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::{PI, TAU};

    use super::*;
    use crate::demo::SplitMix64;
    use crate::geom::Point;

    /// A random polyline of `m` segments (closed: `m ≥ 3`): a walk of random lengths and
    /// turns of up to ±π (sharp corners and reversals included).
    fn random_polyline(rng: &mut SplitMix64, m: usize, closed: bool) -> Polyline {
        loop {
            let vertices = if closed { m } else { m + 1 };
            let mut heading = TAU * rng.next_f64();
            let mut p = Point::new(10.0 * rng.next_f64() - 5.0, 10.0 * rng.next_f64() - 5.0);
            let mut points = vec![p];
            for _ in 1..vertices {
                heading += PI * (2.0 * rng.next_f64() - 1.0);
                let step = 0.05 + 2.0 * rng.next_f64();
                p = p + Vec2::new(heading.cos(), heading.sin()) * step;
                points.push(p);
            }
            if let Ok(line) = Polyline::new(points, closed) {
                return line;
            }
        }
    }

    /// The direction angle of `t`.
    fn angle(t: Vec2) -> f64 {
        t.y.atan2(t.x)
    }

    /// Whether the angle `a`, moved by a whole number of turns, lies in `cone` (to `pad`).
    fn in_cone(a: f64, cone: [f64; 2], pad: f64) -> bool {
        let turns = ((cone[0] - pad - a) / TAU).ceil();
        a + turns * TAU <= cone[1] + pad
    }

    /// The segment before segment `j` (none at an open polyline's start).
    fn segment_before(line: &Polyline, j: usize) -> Option<usize> {
        match j {
            0 if line.is_closed() => Some(line.num_segments() - 1),
            0 => None,
            j => Some(j - 1),
        }
    }

    /// Checks node `n` (segments `place.first..place.end`) and its descendants against the
    /// polyline; counts each leaf's segment in `leaves`; returns the subtree's depth.
    fn check_node(h: &Hierarchy, line: &Polyline, n: usize, leaves: &mut [usize]) -> usize {
        let node = &h.nodes[n];
        let (a, b) = (node.place.first, node.place.end);
        assert!(
            a < b && b <= line.num_segments(),
            "node {n}: segments {a}..{b}"
        );
        assert_eq!(node.first as usize, a);
        // The box: exactly that of the range's vertices.
        let ends: Vec<Point> = (a..b)
            .flat_map(|j| {
                let Segment { start: p, end: q } = line.segment(j);
                [p, q]
            })
            .collect();
        assert_eq!(node.bbox, Aabb::around(&ends), "node {n}'s box");
        assert_eq!(node.place.bbox, node.bbox);
        // The cone: every tangent of the range and of the segment before it, the bound's
        // tangent within its spread of each.
        let tangents = segment_before(line, a).into_iter().chain(a..b);
        for j in tangents {
            let t = line.tangent(j);
            assert!(in_cone(angle(t), node.cone, 1e-12), "node {n}, segment {j}");
            let off = (t - node.place.tangent).length();
            assert!(
                off <= node.place.spread + 1e-12,
                "node {n}, segment {j}: {off}"
            );
        }
        match node.kids {
            None => {
                assert_eq!(b - a, 1, "a leaf holds one segment");
                leaves[a] += 1;
                assert_eq!(node.cone, h.vertex_cone(a));
                1
            }
            Some([l, r]) => {
                let (nl, nr) = (&h.nodes[l as usize].place, &h.nodes[r as usize].place);
                assert_eq!(
                    (nl.first, nl.end, nr.first, nr.end),
                    (a, nr.first, nl.end, b)
                );
                let dl = check_node(h, line, l as usize, leaves);
                let dr = check_node(h, line, r as usize, leaves);
                1 + dl.max(dr)
            }
        }
    }

    /// For random polylines, open and closed, of 1 to 50 segments: every segment in exactly
    /// one leaf, each node's box that of its vertices, each cone holding the tangents of its
    /// segments and of the one before, each vertex cone as wide as the vertex's turn, and a
    /// balanced tree.
    #[test]
    fn the_hierarchy_covers_every_segment_and_vertex() {
        let mut rng = SplitMix64(0x4e1e_7a2c);
        for m in 1..=50 {
            for closed in [false, true] {
                if closed && m < 3 {
                    continue;
                }
                for _ in 0..3 {
                    let line = random_polyline(&mut rng, m, closed);
                    let h = Hierarchy::new(&line);
                    assert_eq!(h.nodes.len(), 2 * m - 1);
                    let mut leaves = vec![0; m];
                    let depth = check_node(&h, &line, 0, &mut leaves);
                    assert!(leaves.iter().all(|&c| c == 1), "{leaves:?}");
                    assert!(
                        depth <= 1 + (m as f64).log2().ceil() as usize,
                        "depth {depth}"
                    );
                    for j in 0..m {
                        let cone = h.vertex_cone(j);
                        let Some(b) = segment_before(&line, j) else {
                            assert_eq!(h.before(j), None);
                            assert_eq!(cone[0], cone[1]);
                            continue;
                        };
                        let (tb, ta) = (line.tangent(b), line.tangent(j));
                        let turn = tb.cross(ta).abs().atan2(tb.dot(ta));
                        assert!((cone[1] - cone[0] - turn).abs() <= 1e-12, "vertex {j}");
                        assert!(in_cone(angle(tb), cone, 1e-12) && in_cone(angle(ta), cone, 1e-12));
                    }
                }
            }
        }
    }
}
