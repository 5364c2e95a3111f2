//! The branch-and-bound over tuples of hierarchy nodes.

use super::Search;
use super::bounds::pruned;
use super::result::Arrival;

impl Search<'_> {
    /// [`pruned`] for the places in `self.sc.places`.
    pub(super) fn pruned(&self) -> bool {
        let g = &self.g;
        pruned(&self.sc.places, g.source, g.receiver, g.slowness)
    }

    /// The branch-and-bound from the tuple of roots.
    pub(super) fn run(&mut self, out: &mut Vec<Arrival>) {
        let k = self.g.k();
        if k == 0 {
            self.solve_leaf_choice(&[], 0, out);
            return;
        }
        let mut stack = std::mem::take(&mut self.sc.stack);
        let mut tuple = std::mem::take(&mut self.sc.tuple);
        let mut segs = std::mem::take(&mut self.sc.segs);
        stack.clear();
        stack.resize(k, 0);
        self.branch_and_bound(&mut stack, &mut tuple, &mut segs, out);
        (self.sc.stack, self.sc.tuple, self.sc.segs) = (stack, tuple, segs);
    }

    /// The search's loop, on the tuples in `stack` (scratch `tuple` and `segs`, `k` long).
    fn branch_and_bound(
        &mut self,
        stack: &mut Vec<u32>,
        tuple: &mut [u32],
        segs: &mut [usize],
        out: &mut Vec<Arrival>,
    ) {
        let k = self.g.k();
        while !stack.is_empty() {
            let at = stack.len() - k;
            tuple.copy_from_slice(&stack[at..]);
            stack.truncate(at);
            self.stats.tuples += 1;
            if self.over_budget(k + 1) {
                return;
            }
            self.sc.places.clear();
            for (i, &n) in tuple.iter().enumerate() {
                let mut place = self.hierarchies[i].nodes[n as usize].place;
                place.interface = self.g.steps[i].interface;
                self.sc.places.push(place);
            }
            if self.pruned() {
                continue;
            }
            // Split the widest node that has halves.
            let split = (0..k)
                .filter_map(|i| {
                    let node = &self.hierarchies[i].nodes[tuple[i] as usize];
                    node.kids.map(|kids| (i, kids, node.bbox.diagonal()))
                })
                .max_by(|a, b| a.2.total_cmp(&b.2).then(b.0.cmp(&a.0)));
            match split {
                Some((i, [l, r], _)) => {
                    for child in [r, l] {
                        stack.extend_from_slice(tuple);
                        let at = stack.len() - k + i;
                        stack[at] = child;
                    }
                }
                None => {
                    for (i, &n) in tuple.iter().enumerate() {
                        segs[i] = self.hierarchies[i].nodes[n as usize].first as usize;
                    }
                    for held in 0..(1usize << k) {
                        self.solve_leaf_choice(segs, held, out);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use std::collections::BTreeMap;

    use crate::demo::SplitMix64;
    use crate::geom::Point;
    use crate::trace::Status;
    use crate::trace::complete::Kink;
    use crate::trace::complete::fixture::{Fixture, points_json};

    /// A scene of one reflection off the mirror `floor` through `points`, from `s` to `r`.
    pub(in crate::trace::complete) fn mirror(points: &[Point], s: Point, r: Point) -> Fixture {
        Fixture::new(&format!(
            r#"{{
                "media": {{ "air": {{ "speed": 1.0 }} }},
                "interfaces": {{ "floor": {{ "points": {} }} }},
                "sources": {}, "receivers": {},
                "paths": [{{ "steps": [{{ "reflect": "floor" }}], "media": ["air", "air"] }}]
            }}"#,
            points_json(points),
            points_json(&[s]),
            points_json(&[r])
        ))
    }

    /// The time of the straight legs from `s` to `x` to `r`.
    fn time(s: Point, x: Point, r: Point) -> f64 {
        (x - s).length() + (r - x).length()
    }

    /// Whether segments `a–b` and `p–q` cross at a point inside both.
    fn crosses(a: Point, b: Point, p: Point, q: Point) -> bool {
        let side = |o: Point, d: Point, x: Point| (d - o).cross(x - o);
        side(a, b, p) * side(a, b, q) < 0.0 && side(p, q, a) * side(p, q, b) < 0.0
    }

    /// What the brute force finds on a height field `v` seen from above: on each segment,
    /// the image method's reflection point when it lies inside the segment (with its time);
    /// at each inner vertex, the kind of kink the time has there, from finite differences of
    /// the time along the two segments (none when it falls one way and rises the other).
    /// Each with whether its legs are clear of the other segments.
    #[derive(Debug, Default)]
    struct Expected {
        interior: BTreeMap<usize, (f64, bool)>,
        vertex: BTreeMap<usize, (Kink, bool)>,
    }

    fn brute_force(v: &[Point], s: Point, r: Point) -> Expected {
        let clear = |x: Point, own: &[usize]| {
            (0..v.len() - 1)
                .filter(|i| !own.contains(i))
                .all(|i| !crosses(s, x, v[i], v[i + 1]) && !crosses(x, r, v[i], v[i + 1]))
        };
        let mut e = Expected::default();
        for j in 0..v.len() - 1 {
            let (p, q) = (v[j], v[j + 1]);
            let t = (q - p) * (1.0 / (q - p).length());
            let n = t.perp();
            let image = r - n * (2.0 * (r - p).dot(n));
            let (hs, hi) = ((s - p).dot(n), (image - p).dot(n));
            if hs.signum() == hi.signum() {
                continue; // `s` and `r` on either side of the segment's line.
            }
            let x = s + (image - s) * (hs / (hs - hi));
            let f = (x - p).dot(t) / (q - p).length();
            assert!(
                !(1e-9..=1e-6).contains(&f.min(1.0 - f).abs()),
                "too near an end"
            );
            if f > 0.0 && f < 1.0 {
                e.interior.insert(j, ((image - s).length(), clear(x, &[j])));
            }
        }
        for j in 1..v.len() - 1 {
            let h = 1e-7;
            let at = time(s, v[j], r);
            let step = |to: Point| {
                let d = to - v[j];
                time(s, v[j] + d * (h / d.length()), r) - at
            };
            let (back, ahead) = (step(v[j - 1]), step(v[j + 1]));
            assert!(back.abs().min(ahead.abs()) > 1e-12, "a flat side");
            let kink = match (back > 0.0, ahead > 0.0) {
                (true, true) => Kink::Minimum,
                (false, false) => Kink::Maximum,
                _ => continue,
            };
            e.vertex.insert(j, (kink, clear(v[j], &[j - 1, j])));
        }
        e
    }

    /// Random height fields of 2 to 40 segments seen from above: the branch-and-bound
    /// (`Search::run`) finds exactly the image method's reflection points (at their times)
    /// and the vertices where the time has a kink of one kind, and prunes some tuples.
    #[test]
    fn the_search_finds_what_the_brute_force_finds() {
        let mut rng = SplitMix64(0xb4a9c4);
        let mut found = [0; 3];
        let mut pruned = 0;
        for case in 0..40 {
            let m = 2 + case % 39;
            // Rough (heights at random) or smooth (a wave with a little noise).
            let (rough, wave, phase) = (case % 2 == 0, 0.3 + rng.next_f64(), 6.0 * rng.next_f64());
            let mut x = 0.0;
            let v: Vec<Point> = (0..=m)
                .map(|_| {
                    x += 0.05 + rng.next_f64() * 10.0 / m as f64;
                    let noise = 2.0 * rng.next_f64() - 1.0;
                    let y = if rough {
                        noise
                    } else {
                        0.8 * (wave * x + phase).sin() + 0.1 * noise
                    };
                    Point::new(x, y)
                })
                .collect();
            let up = |rng: &mut SplitMix64| Point::new(x * rng.next_f64(), 1.5 + rng.next_f64());
            let (s, r) = (up(&mut rng), up(&mut rng));
            let expected = brute_force(&v, s, r);
            let fixture = mirror(&v, s, r);
            let line = &fixture.scene.interfaces()[0].polyline;
            let (out, stats) = fixture.search(0, |search| {
                let mut out = Vec::new();
                search.run(&mut out);
                out
            });
            assert!(stats.complete);
            // One step: each node at most once; fewer where the bound prunes.
            assert!(
                stats.tuples < 2 * m,
                "{} tuples, {m} segments",
                stats.tuples
            );
            pruned += 2 * m - 1 - stats.tuples;
            // Every path the brute force finds with clear legs is listed, with its time and
            // kink; one whose legs cross the polyline may be (obstructed); nothing else is.
            let (mut interior, mut vertex) = (BTreeMap::new(), BTreeMap::new());
            for a in &out {
                let j = a.segments[0];
                assert_eq!(a.points[0], s);
                let held = a.parameters[0] == line.start(j);
                let (listed, clear) = if held {
                    let (kink, clear) = expected.vertex[&j];
                    assert_eq!(a.kink, (a.status == Status::Vertex).then_some(kink));
                    (vertex.insert(j, a.status), clear)
                } else {
                    let (t, clear) = expected.interior[&j];
                    assert!(
                        (a.time - t).abs() <= 1e-9 * t,
                        "segment {j}: {} ≠ {t}",
                        a.time
                    );
                    (interior.insert(j, a.status), clear)
                };
                assert!(listed.is_none(), "{j} twice");
                assert_eq!(a.status == Status::Obstructed, !clear, "case {case}, {j}");
            }
            for (j, &(_, clear)) in &expected.interior {
                assert!(
                    !clear || interior.contains_key(j),
                    "case {case}: segment {j}"
                );
            }
            for (j, &(_, clear)) in &expected.vertex {
                assert!(!clear || vertex.contains_key(j), "case {case}: vertex {j}");
            }
            found[1] += vertex.len();
            found[0] += out.len();
            found[2] += out
                .iter()
                .filter(|a| a.status == Status::Obstructed)
                .count();
        }
        // The cases hold interior and vertex paths, and obstructed ones.
        assert!(
            found[0] - found[1] > 20 && found[1] > 20 && found[2] > 0,
            "{found:?}"
        );
        assert!(pruned > 150, "{pruned} tuples pruned");
    }
}
