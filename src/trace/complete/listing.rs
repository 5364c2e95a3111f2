//! The list of arrivals a search fills: ordered, rid of repeats, its vectors reused.

use super::result::Arrival;
use super::scratch::with_scratch;
use crate::trace::Status;

/// Empties `out`, keeping its arrivals' vectors for the next ones this thread finds: once
/// warm, a search allocates nothing.
pub(crate) fn recycle(out: &mut Vec<Arrival>) {
    with_scratch(|sc| sc.spare.append(out));
}

/// Keeps the arrivals for which `keep` holds, in order; the others' vectors are kept for
/// reuse.
pub(crate) fn retain(out: &mut Vec<Arrival>, mut keep: impl FnMut(&Arrival) -> bool) {
    let mut w = 0;
    for r in 0..out.len() {
        if keep(&out[r]) {
            out.swap(w, r);
            w += 1;
        }
    }
    with_scratch(|sc| sc.spare.extend(out.drain(w..)));
}

/// Orders the arrivals by time, drops repeats of one path (a vertex path kept over an
/// interior path on the same points).
pub(crate) fn finish(out: &mut Vec<Arrival>) {
    let order =
        |a: &Arrival, b: &Arrival| a.time.total_cmp(&b.time).then(a.segments.cmp(&b.segments));
    out.sort_unstable_by(order);
    let same = |a: &Arrival, b: &Arrival| {
        let scale = a
            .points
            .iter()
            .fold(1.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
        (a.time - b.time).abs() <= 1e-9 * a.time.abs().max(1e-300)
            && a.points.len() == b.points.len()
            && a.points
                .iter()
                .zip(&b.points)
                .all(|(p, q)| (*p - *q).length() <= 1e-9 * scale)
    };
    // Kept ones move to the front (`out[..w]`); a repeat stays behind, or swaps places with
    // the one it repeats when it is the vertex path of the two.
    let mut w = 0;
    for r in 0..out.len() {
        match (0..w).rev().find(|&j| same(&out[j], &out[r])) {
            Some(j) => {
                if out[r].status == Status::Vertex && out[j].status != Status::Vertex {
                    out.swap(j, r);
                }
            }
            None => {
                out.swap(w, r);
                w += 1;
            }
        }
    }
    with_scratch(|sc| sc.spare.extend(out.drain(w..)));
    out.sort_unstable_by(order);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::SplitMix64;
    use crate::geom::Point;
    use crate::trace::complete::scratch::take_scratch;

    /// An arrival of `status` at time `time` through `points`, on segments `segments`.
    fn arrival(status: Status, time: f64, points: &[(f64, f64)], segments: &[usize]) -> Arrival {
        Arrival {
            status,
            time,
            points: points.iter().map(|&(x, y)| Point::new(x, y)).collect(),
            segments: segments.to_vec(),
            ..Arrival::empty()
        }
    }

    /// The arrivals of a search that found paths twice (a vertex path also as the interior
    /// path of both its segments, an interior path from two assignments), in no order:
    /// `finish` keeps one of each, the vertex one of a vertex path, ordered by time.
    #[test]
    fn finish_orders_and_keeps_one_of_each() {
        let v = [(0.0, 1.0), (1.0, 0.0), (2.0, 1.0)];
        let c = [(0.0, 1.0), (0.5, 0.2), (2.0, 1.0)];
        let far = [(0.0, 1.0), (3.0, -1.0), (2.0, 1.0)];
        let near = |(x, y): (f64, f64)| (x + 1e-12, y);
        let mut out = vec![
            arrival(Status::Obstructed, 5.0, &far, &[7]),
            arrival(Status::Converged, 2.0, &v, &[1]),
            arrival(Status::Converged, 1.5, &c, &[0]),
            arrival(Status::Vertex, 2.0 + 1e-12, &v.map(near), &[2]),
            arrival(Status::Converged, 2.0, &v, &[2]),
            arrival(Status::Converged, 1.5, &c.map(near), &[0]),
        ];
        finish(&mut out);
        let got: Vec<(Status, f64)> = out.iter().map(|a| (a.status, a.time)).collect();
        assert_eq!(
            got,
            [
                (Status::Converged, 1.5),
                (Status::Vertex, 2.0 + 1e-12),
                (Status::Obstructed, 5.0)
            ]
        );
        assert_eq!(out[1].segments, [2]);
        // The three repeats' vectors wait for the next search.
        assert_eq!(take_scratch().spare.len(), 3);
    }

    /// Against a reference (sort, then keep an arrival unless an earlier kept one is
    /// within 1e-9 of it): random arrivals, many of them repeats, none of them vertex paths.
    #[test]
    fn finish_matches_a_simple_reference() {
        let mut rng = SplitMix64(71);
        for _ in 0..200 {
            let n = (rng.next_u64() % 12) as usize;
            let mut out: Vec<Arrival> = (0..n)
                .map(|i| {
                    let t = 1.0 + (rng.next_u64() % 4) as f64;
                    let x = t + 1e-11 * rng.next_f64();
                    arrival(Status::Converged, t, &[(x, 0.0)], &[i])
                })
                .collect();
            let mut reference: Vec<(f64, f64)> = Vec::new();
            let mut sorted: Vec<&Arrival> = out.iter().collect();
            sorted.sort_by(|a, b| a.time.total_cmp(&b.time).then(a.segments.cmp(&b.segments)));
            for a in sorted {
                let x = a.points[0].x;
                if !reference
                    .iter()
                    .any(|&(t, y)| t == a.time && (x - y).abs() <= 1e-9 * x)
                {
                    reference.push((a.time, x));
                }
            }
            finish(&mut out);
            let times: Vec<f64> = out.iter().map(|a| a.time).collect();
            let expected: Vec<f64> = reference.iter().map(|r| r.0).collect();
            assert_eq!(times, expected);
        }
    }

    /// `retain` keeps the arrivals it is told to, in order; `recycle` empties the list; the
    /// arrivals let go wait in the thread's scratch.
    #[test]
    fn retain_and_recycle_keep_the_vectors() {
        let mut out: Vec<Arrival> = (0..6)
            .map(|i| arrival(Status::Converged, i as f64, &[(0.0, 0.0)], &[i]))
            .collect();
        retain(&mut out, |a| a.segments[0] % 2 == 1);
        let kept: Vec<usize> = out.iter().map(|a| a.segments[0]).collect();
        assert_eq!(kept, [1, 3, 5]);
        recycle(&mut out);
        assert!(out.is_empty());
        assert_eq!(take_scratch().spare.len(), 6);
    }
}
