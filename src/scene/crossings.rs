//! The crossing check of a scene's interfaces: a sweep over the segments' end points (Shamos
//! and Hoey's), `O(n log n)` for `n` segments however their boxes overlap.
//!
//! The sweep visits the end points in lexicographic order (`x`, then `y`) and keeps the
//! segments that span the sweep line ordered from below to above. Two segments that neither
//! cross nor overlap keep their order while both span the line, so the order of two is decided
//! once, at the later start, by exact orientation tests. Every pair that becomes neighbours in
//! that order is classified; the leftmost forbidden contact is between neighbours before the
//! sweep passes it, so the sweep finds one if there is any. Contacts at an end point (where
//! touching is allowed between interfaces, and between neighbouring segments of one) are
//! checked at that point among all the segments through it.

use std::cmp::Ordering;
use std::collections::BTreeSet;

use super::{Interface, SceneError, SegmentRef, contact_problem};
use crate::geom::{Point, Segment, orient};

/// A segment in the sweep's order (`a` before `b` lexicographically), or a probe: a point
/// that sorts just below (`probe < 0`) or just above (`probe > 0`) the segments through it.
#[derive(Clone, Copy, Debug)]
struct Key {
    a: Point,
    b: Point,
    id: u32,
    probe: i8,
}

fn lex(p: Point, q: Point) -> Ordering {
    // Scene coordinates are finite: no NaN.
    p.x.partial_cmp(&q.x)
        .unwrap_or(Ordering::Equal)
        .then(p.y.partial_cmp(&q.y).unwrap_or(Ordering::Equal))
}

fn sign(d: f64) -> Ordering {
    d.partial_cmp(&0.0).unwrap_or(Ordering::Equal)
}

/// Order of segment `s` against segment `t`, both spanning the sweep line: decided at the
/// later start. Collinear segments compare by index (they overlap, which the sweep reports).
fn segments(s: &Key, t: &Key) -> Ordering {
    if lex(s.a, t.a) == Ordering::Less {
        return segments(t, s).reverse();
    }
    let d = sign(orient(t.a, t.b, s.a));
    if d != Ordering::Equal {
        return d;
    }
    let e = sign(orient(t.a, t.b, s.b));
    if e != Ordering::Equal {
        return e;
    }
    s.id.cmp(&t.id)
}

impl Ord for Key {
    fn cmp(&self, o: &Key) -> Ordering {
        match (self.probe, o.probe) {
            (0, 0) => segments(self, o),
            (p, 0) => match sign(orient(o.a, o.b, self.a)) {
                Ordering::Equal => p.cmp(&0),
                d => d,
            },
            (0, _) => o.cmp(self).reverse(),
            (p, q) => p.cmp(&q),
        }
    }
}
impl PartialOrd for Key {
    fn partial_cmp(&self, o: &Key) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl PartialEq for Key {
    fn eq(&self, o: &Key) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Key {}

/// The first forbidden contact the sweep meets: segments that cross or overlap, or a polyline
/// that touches itself away from the shared vertex of neighbouring segments.
pub(super) fn check(interfaces: &[Interface], refs: &[SegmentRef]) -> Result<(), SceneError> {
    let keys: Vec<Key> = refs
        .iter()
        .enumerate()
        .map(|(id, r)| {
            let Segment { start: p, end: q } = interfaces[r.interface as usize]
                .polyline
                .segment(r.segment as usize);
            let (a, b) = if lex(p, q) == Ordering::Greater {
                (q, p)
            } else {
                (p, q)
            };
            Key {
                a,
                b,
                id: id as u32,
                probe: 0,
            }
        })
        .collect();
    let mut starts: Vec<u32> = (0..keys.len() as u32).collect();
    starts.sort_by(|&i, &j| lex(keys[i as usize].a, keys[j as usize].a));
    let mut events: Vec<Point> = keys.iter().flat_map(|k| [k.a, k.b]).collect();
    events.sort_by(|&p, &q| lex(p, q));
    events.dedup_by(|p, q| lex(*p, *q) == Ordering::Equal);

    let problem = |i: u32, j: u32| contact_problem(interfaces, refs, i, j);
    let probe = |p: Point, side: i8| Key {
        a: p,
        b: p,
        id: u32::MAX,
        probe: side,
    };
    let mut active: BTreeSet<Key> = BTreeSet::new();
    let mut next_start = 0;
    let mut here: Vec<(u32, bool)> = Vec::new();
    for p in events {
        let (lo, hi) = (probe(p, -1), probe(p, 1));
        let first = next_start;
        while next_start < starts.len()
            && lex(keys[starts[next_start] as usize].a, p) == Ordering::Equal
        {
            next_start += 1;
        }
        let new = &starts[first..next_start];

        // Every segment through `p`: (index, whether `p` is inside it rather than an end).
        here.clear();
        here.extend(
            active
                .range(lo..hi)
                .map(|k| (k.id, lex(k.b, p) != Ordering::Equal)),
        );
        here.extend(new.iter().map(|&i| (i, false)));
        // Two segments with `p` inside both cross or overlap there.
        let inside: Vec<u32> = here.iter().filter(|h| h.1).map(|h| h.0).take(2).collect();
        if let [i, j] = inside[..]
            && let Some(e) = problem(i, j)
        {
            return Err(e);
        }
        // Segments of one interface through `p`: at most two, neighbours, meeting at a vertex.
        here.sort_unstable_by_key(|&(i, _)| (refs[i as usize].interface, refs[i as usize].segment));
        for group in
            here.chunk_by(|x, y| refs[x.0 as usize].interface == refs[y.0 as usize].interface)
        {
            if group.len() < 2 {
                continue;
            }
            let few = &group[..group.len().min(4)];
            for (n, x) in few.iter().enumerate() {
                for y in &few[n + 1..] {
                    if let Some(e) = problem(x.0, y.0) {
                        return Err(e);
                    }
                }
            }
        }

        // Segments that end at `p` leave; those that start there join; then every pair of
        // neighbours around `p` is classified.
        for &(i, inside) in &here {
            if !inside && lex(keys[i as usize].b, p) == Ordering::Equal {
                active.remove(&keys[i as usize]);
            }
        }
        for &i in new {
            active.insert(keys[i as usize]);
        }
        let below = active.range(..lo).next_back().map(|k| k.id);
        let above = active.range(hi..).next().map(|k| k.id);
        let mut last = below;
        for id in active.range(lo..hi).map(|k| k.id).chain(above) {
            if let Some(prev) = last
                && let Some(e) = problem(prev, id)
            {
                return Err(e);
            }
            last = Some(id);
        }
    }
    Ok(())
}
