//! Brute-force distance from a point to an interface polyline, independent of the library's
//! own nearest-point search (shared by `tests/regressions.rs`, `tests/properties.rs` and the
//! fuzz targets through `#[path]`).

use eigenray::Point;
use eigenray::geom::Segment;
use eigenray::polyline::Polyline;

/// Distance from `p` to segment `a–b` (computed on coordinates scaled to the segment, so that
/// tiny and huge scenes neither underflow nor overflow).
pub fn segment_distance(p: Point, a: Point, b: Point) -> f64 {
    let scale = (b.x - a.x).abs().max((b.y - a.y).abs());
    let (dx, dy) = ((b.x - a.x) / scale, (b.y - a.y) / scale);
    let (px, py) = ((p.x - a.x) / scale, (p.y - a.y) / scale);
    let t = ((px * dx + py * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
    (px - t * dx).hypot(py - t * dy) * scale
}

/// Distance from `p` to the nearest segment of `line`, by checking every segment.
pub fn distance_to_polyline(line: &Polyline, p: Point) -> f64 {
    (0..line.num_segments())
        .map(|j| {
            let Segment { start: a, end: b } = line.segment(j);
            segment_distance(p, a, b)
        })
        .fold(f64::INFINITY, f64::min)
}
