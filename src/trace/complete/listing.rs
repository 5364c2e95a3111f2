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
/// interior path on the same points), and marks whether the search was complete.
pub(crate) fn finish(out: &mut Vec<Arrival>, complete: bool) {
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
    for a in out.iter_mut() {
        a.complete = complete;
    }
}
