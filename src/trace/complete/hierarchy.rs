//! The segment hierarchy of one polyline: nodes of consecutive segments, each with its box and
//! tangent cone.

use crate::geom::{Aabb, Vec2};
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
        let (p, q) = line.segment(a);
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
