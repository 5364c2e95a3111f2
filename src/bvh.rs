//! A bounding-volume hierarchy over boxes (polyline segments), queried without allocating.
//!
//! Built once by median splits on box centres along the longer axis, so its depth is
//! `⌈log2(n / LEAF)⌉ + 1`; queries walk it with a fixed-size stack on the call stack. It serves
//! nearest-point queries on one polyline (the initial guess), segment-crossing queries over a
//! whole scene (the obstruction test) and box-overlap queries (validation), all in
//! `O(log n + hits)` for well-spread segments.

use crate::geom::{Aabb, Point};

/// Items per leaf.
const LEAF: usize = 4;
/// Enough for any tree this module builds (median splits keep the depth near log2 n).
const STACK: usize = 64;

#[derive(Clone, Debug)]
struct Node {
    bbox: Aabb,
    /// Leaf: first item in `items`; inner: index of the left child (the right one follows it
    /// in the subtree layout, at `right`).
    start: u32,
    /// Leaf: number of items (> 0); inner: 0.
    count: u32,
    /// Inner: index of the right child.
    right: u32,
}

/// A static BVH over `n` boxes identified by their index `0..n`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    items: Vec<u32>,
    boxes: Vec<Aabb>,
}

impl Bvh {
    /// Builds the hierarchy over `boxes` (item `i` is `boxes[i]`).
    pub(crate) fn build(boxes: &[Aabb]) -> Bvh {
        let mut items: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * boxes.len() / LEAF + 1);
        if !boxes.is_empty() {
            build_node(boxes, &mut items, 0, boxes.len(), &mut nodes);
        }
        Bvh {
            nodes,
            items,
            boxes: boxes.to_vec(),
        }
    }

    /// The item minimising `dist_sq(item)`, a squared distance that must be at least the
    /// squared distance from `p` to the item's box. Returns `(item, dist_sq)`.
    pub(crate) fn nearest(
        &self,
        p: Point,
        mut dist_sq: impl FnMut(u32) -> f64,
    ) -> Option<(u32, f64)> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best = (u32::MAX, f64::INFINITY);
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if node.bbox.distance_sq(p) > best.1 {
                continue;
            }
            if node.count > 0 {
                for &it in &self.items[node.start as usize..(node.start + node.count) as usize] {
                    let d = dist_sq(it);
                    if d < best.1 {
                        best = (it, d);
                    }
                }
            } else {
                let (l, r) = (node.start, node.right);
                // Visit the nearer child first (pushed last).
                let dl = self.nodes[l as usize].bbox.distance_sq(p);
                let dr = self.nodes[r as usize].bbox.distance_sq(p);
                let (first, second) = if dl <= dr { (l, r) } else { (r, l) };
                if top + 2 <= STACK {
                    stack[top] = second;
                    stack[top + 1] = first;
                    top += 2;
                }
            }
        }
        (best.0 != u32::MAX).then_some(best)
    }

    /// Calls `visit(item)` for every item whose box overlaps `query`, until `visit` returns
    /// `true` ("stop"). Returns whether it was stopped.
    pub(crate) fn any_overlapping(&self, query: Aabb, mut visit: impl FnMut(u32) -> bool) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let mut stack = [0u32; STACK];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if !node.bbox.overlaps(query) {
                continue;
            }
            if node.count > 0 {
                for &it in &self.items[node.start as usize..(node.start + node.count) as usize] {
                    if self.boxes[it as usize].overlaps(query) && visit(it) {
                        return true;
                    }
                }
            } else if top + 2 <= STACK {
                stack[top] = node.start;
                stack[top + 1] = node.right;
                top += 2;
            }
        }
        false
    }

    /// Calls `visit(item)` for every item whose box the segment `a–b` may touch (boxes that
    /// overlap the segment's box and are not strictly on one side of its line), until `visit`
    /// returns `true`. Returns whether it was stopped.
    pub(crate) fn any_near_segment(
        &self,
        a: Point,
        b: Point,
        visit: impl FnMut(u32) -> bool,
    ) -> bool {
        self.any_near_segment_in(Aabb::from_points(a, b), a, b, visit)
    }

    /// [`any_near_segment`](Self::any_near_segment) with the query box `sbox` given (a part of
    /// the segment's box: items outside it are not visited).
    pub(crate) fn any_near_segment_in(
        &self,
        sbox: Aabb,
        a: Point,
        b: Point,
        mut visit: impl FnMut(u32) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        if self.nodes.len() == 1 {
            // A single leaf: test the few items directly.
            return self
                .items
                .iter()
                .any(|&it| self.boxes[it as usize].overlaps(sbox) && visit(it));
        }
        let d = b - a;
        let (lo, hi) = (
            Point::new(a.x.min(b.x), a.y.min(b.y)),
            Point::new(a.x.max(b.x), a.y.max(b.y)),
        );
        // A box that overlaps the query and spans the segment's whole extent along x (or y)
        // meets the segment (which takes every y, or x, of its extent inside the box's band):
        // the line test could not prune it.
        let wanted = |n: &Node| {
            let bb = n.bbox;
            bb.overlaps(sbox)
                && ((bb.min.x <= lo.x && bb.max.x >= hi.x)
                    || (bb.min.y <= lo.y && bb.max.y >= hi.y)
                    || !box_beside_line(bb, a, d))
        };
        let mut node = &self.nodes[0];
        if !wanted(node) {
            return false;
        }
        // Children are tested before they are entered: a node on the stack is wanted.
        let mut stack = [0u32; STACK];
        let mut top = 0;
        loop {
            if node.count > 0 {
                for &it in &self.items[node.start as usize..(node.start + node.count) as usize] {
                    if self.boxes[it as usize].overlaps(sbox) && visit(it) {
                        return true;
                    }
                }
            } else {
                let (l, r) = (
                    &self.nodes[node.start as usize],
                    &self.nodes[node.right as usize],
                );
                match (wanted(l), wanted(r)) {
                    (true, true) => {
                        if top < STACK {
                            stack[top] = node.right;
                            top += 1;
                        }
                        node = l;
                        continue;
                    }
                    (true, false) => {
                        node = l;
                        continue;
                    }
                    (false, true) => {
                        node = r;
                        continue;
                    }
                    (false, false) => {}
                }
            }
            if top == 0 {
                return false;
            }
            top -= 1;
            node = &self.nodes[stack[top] as usize];
        }
    }
}

/// Whether all four corners of `b` lie strictly on one side of the line through `a` with
/// direction `d` (with a small relative margin so that rounding never prunes a true hit).
#[inline]
fn box_beside_line(b: Aabb, a: Point, d: crate::geom::Vec2) -> bool {
    // `d × (c − a)` over the corners `c` is `d.x (c.y − a.y) − d.y (c.x − a.x)`: its extremes
    // take each term's extreme over the box's two x and two y values.
    let (y0, y1) = (d.x * (b.min.y - a.y), d.x * (b.max.y - a.y));
    let (x0, x1) = (d.y * (a.x - b.min.x), d.y * (a.x - b.max.x));
    let lo = y0.min(y1) + x0.min(x1);
    let hi = y0.max(y1) + x0.max(x1);
    // Bounds |d × (c − a)| for every corner (L1 norms: no square roots).
    let far = (b.max.x - a.x).abs().max((b.min.x - a.x).abs())
        + (b.max.y - a.y).abs().max((b.min.y - a.y).abs());
    let margin = 1e-12 * (d.x.abs() + d.y.abs()) * far;
    lo > margin || hi < -margin
}

fn build_node(
    boxes: &[Aabb],
    items: &mut [u32],
    lo: usize,
    hi: usize,
    nodes: &mut Vec<Node>,
) -> u32 {
    let me = nodes.len() as u32;
    let bbox = items[lo..hi]
        .iter()
        .fold(Aabb::EMPTY, |acc, &i| acc.union(boxes[i as usize]));
    nodes.push(Node {
        bbox,
        start: lo as u32,
        count: (hi - lo) as u32,
        right: 0,
    });
    if hi - lo <= LEAF {
        return me;
    }
    let cb = items[lo..hi].iter().fold(Aabb::EMPTY, |acc, &i| {
        let c = boxes[i as usize].center();
        acc.union(Aabb::from_points(c, c))
    });
    let by_x = cb.max.x - cb.min.x >= cb.max.y - cb.min.y;
    let key = |i: &u32| {
        let c = boxes[*i as usize].center();
        if by_x { c.x } else { c.y }
    };
    let mid = (lo + hi) / 2;
    items[lo..hi].select_nth_unstable_by(mid - lo, |a, b| key(a).total_cmp(&key(b)));
    let left = build_node(boxes, items, lo, mid, nodes);
    let right = build_node(boxes, items, mid, hi, nodes);
    let node = &mut nodes[me as usize];
    node.start = left;
    node.count = 0;
    node.right = right;
    me
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes(n: usize) -> Vec<Aabb> {
        (0..n)
            .map(|i| {
                let x = i as f64;
                let y = (x * 0.37).sin();
                Aabb::from_points(
                    Point::new(x, y),
                    Point::new(x + 1.0, (x * 0.37 + 0.37).sin()),
                )
            })
            .collect()
    }

    #[test]
    fn nearest_matches_brute_force() {
        let b = boxes(1000);
        let bvh = Bvh::build(&b);
        for k in 0..50 {
            let p = Point::new(k as f64 * 21.3 - 30.0, (k as f64).cos() * 3.0);
            let (it, d) = bvh.nearest(p, |i| b[i as usize].distance_sq(p)).unwrap();
            let brute = b
                .iter()
                .map(|bb| bb.distance_sq(p))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(d, brute);
            assert_eq!(b[it as usize].distance_sq(p), brute);
        }
    }

    #[test]
    fn segment_query_visits_every_crossed_item() {
        // Segments as items; every one that a query segment crosses must be visited.
        let mut rng = crate::demo::SplitMix64(7);
        let segs: Vec<(Point, Point)> = (0..2000)
            .map(|_| {
                let a = Point::new(rng.next_f64() * 100.0, rng.next_f64() * 100.0);
                let b = Point::new(
                    a.x + rng.next_f64() * 6.0 - 3.0,
                    a.y + rng.next_f64() * 6.0 - 3.0,
                );
                (a, b)
            })
            .collect();
        let b: Vec<Aabb> = segs.iter().map(|&(p, q)| Aabb::from_points(p, q)).collect();
        let bvh = Bvh::build(&b);
        for _ in 0..200 {
            let a = Point::new(rng.next_f64() * 100.0, rng.next_f64() * 100.0);
            let e = Point::new(rng.next_f64() * 100.0, rng.next_f64() * 100.0);
            let mut seen = vec![false; segs.len()];
            bvh.any_near_segment(a, e, |i| {
                seen[i as usize] = true;
                false
            });
            for (i, &(p, q)) in segs.iter().enumerate() {
                if crate::polyline::segment_intersection(a, e, p, q).is_some() {
                    assert!(seen[i], "segment {i} crossed but not visited");
                }
            }
            // And the pruning does prune: far fewer visits than items.
            assert!(seen.iter().filter(|&&v| v).count() < segs.len() / 4);
        }
    }

    #[test]
    fn overlap_query_finds_all() {
        let b = boxes(500);
        let bvh = Bvh::build(&b);
        let q = Aabb::from_points(Point::new(100.5, -2.0), Point::new(103.2, 2.0));
        let mut found = Vec::new();
        bvh.any_overlapping(q, |i| {
            found.push(i);
            false
        });
        found.sort();
        let brute: Vec<u32> = (0..500u32).filter(|&i| b[i as usize].overlaps(q)).collect();
        assert_eq!(found, brute);
    }
}
