//! The names on the plot: interfaces' labels at their middle and media's names beside their
//! `at` points or amid their rays, each where it covers the fewest rays and no other label.

use std::fmt::Write as _;

use eigenray::{Point, Scene};

use super::entries::Item;
use super::layout::View;
use super::markup::halo_text;

/// A label's box in pixels: `(x0, y0, x1, y1)`.
pub(super) type LabelBox = (f64, f64, f64, f64);

/// A straight piece of a drawing in pixels: its two ends.
pub(super) type PixelSegment = ((f64, f64), (f64, f64));

/// The box of a `size`-pixel text of `chars` characters whose baseline starts at `(x, y)`.
pub(super) fn text_box(x: f64, y: f64, chars: usize, size: f64) -> LabelBox {
    (
        x - 2.0,
        y - size,
        x + 0.6 * size * chars as f64 + 2.0,
        y + 0.3 * size,
    )
}

/// Whether the pixel segments `a → b` and `c → d` cross (touching counts).
fn segments_cross(a: (f64, f64), b: (f64, f64), c: (f64, f64), d: (f64, f64)) -> bool {
    let orient = |p: (f64, f64), q: (f64, f64), r: (f64, f64)| {
        (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0)
    };
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    o1 * o2 <= 0.0 && o3 * o4 <= 0.0 && (a != b)
}

/// Whether boxes `a` and `b` overlap (touching does not count).
pub(super) fn boxes_overlap(a: LabelBox, b: LabelBox) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

/// Whether the pixel segment `p → q` meets box `b` (Liang–Barsky clipping).
fn segment_meets_box(p: (f64, f64), q: (f64, f64), b: LabelBox) -> bool {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (den, num) in [
        (-dx, p.0 - b.0),
        (dx, b.2 - p.0),
        (-dy, p.1 - b.1),
        (dy, b.3 - p.1),
    ] {
        if den == 0.0 {
            if num < 0.0 {
                return false;
            }
        } else {
            let t = num / den;
            if den < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t0 <= t1
}

/// Draws the labels: interfaces at their middle, where they cover the fewest rays and no other
/// label (the names of media with `at` points, which stay beside them, are placed first); then
/// the other media.
pub(super) fn draw_labels(s: &mut String, scene: &Scene, view: &View, rays: &[Item]) {
    let ray_segments: Vec<PixelSegment> = rays
        .iter()
        .flat_map(|r| r.points.windows(2).map(|w| (view.px(w[0]), view.px(w[1]))))
        .collect();
    let mut taken: Vec<LabelBox> = scene
        .media()
        .iter()
        .filter_map(|m| {
            let (x, y) = view.px(m.at?);
            Some(text_box(x + 6.0, y - 6.0, m.name.chars().count(), 13.0))
        })
        .collect();
    let _ = writeln!(s, r#"<g class="labels" font-size="12">"#);
    for i in scene.interfaces() {
        let (x, y) = interface_label_spot(view, i, &ray_segments, &taken);
        taken.push(text_box(x, y, i.name.chars().count(), 12.0));
        halo_text(s, x, y, "", "#222", &i.name);
    }
    let room = MediumRoom {
        plot: (view.left(), view.top(), view.right(), view.bottom()),
        walls: interface_walls(scene, view),
        rays: &ray_segments,
    };
    for (m, (x, y)) in medium_spots(scene, view, rays) {
        let name = &scene.media()[m].name;
        let chars = name.chars().count();
        let spot = if scene.media()[m].at.is_some() {
            // Beside the user's point.
            (x + 6.0, y - 6.0)
        } else {
            room.free_spot((x, y), chars, &taken)
        };
        taken.push(text_box(spot.0, spot.1, chars, 13.0));
        if scene.media()[m].at.is_some() {
            let _ = writeln!(
                s,
                r##"<path d="M{:.2},{y:.2}h8M{x:.2},{:.2}v8" stroke="#777" stroke-width="1"/>"##,
                x - 4.0,
                y - 4.0
            );
        }
        halo_text(
            s,
            spot.0,
            spot.1,
            r#"font-size="13" font-style="italic""#,
            "#555",
            name,
        );
    }
    let _ = writeln!(s, "</g>");
}

/// Every straight piece of the scene's interfaces in pixels (a closed one's closing piece too).
fn interface_walls(scene: &Scene, view: &View) -> Vec<PixelSegment> {
    scene
        .interfaces()
        .iter()
        .flat_map(|i| {
            let v = i.polyline.vertices();
            let closing = if i.polyline.is_closed() && v.len() > 2 {
                Some((v[v.len() - 1], v[0]))
            } else {
                None
            };
            v.windows(2)
                .map(|w| (w[0], w[1]))
                .chain(closing)
                .map(|(a, b)| (view.px(a), view.px(b)))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// What a medium's name without an `at` point must keep within and clear of.
struct MediumRoom<'a> {
    /// The plot's box.
    plot: LabelBox,
    /// The interfaces' pieces, which the label neither covers nor is moved across.
    walls: Vec<PixelSegment>,
    /// The rays' pieces, of which the label covers as few as it can.
    rays: &'a [PixelSegment],
}

impl MediumRoom<'_> {
    /// Where a name of `chars` characters goes near `(x, y)`, the middle of the medium's legs:
    /// where it covers the fewest rays, crosses no interface on the way and overlaps no label
    /// in `taken` (at `(x, y)` itself when no place is free).
    fn free_spot(&self, (x, y): (f64, f64), chars: usize, taken: &[LabelBox]) -> (f64, f64) {
        let plot = self.plot;
        let mut best = (f64::INFINITY, (x, y));
        for dy in [0.0, -40.0, 40.0, -80.0, 80.0, -120.0, 120.0] {
            for dx in [
                0.0, -60.0, 60.0, -120.0, 120.0, -180.0, 180.0, -240.0, 240.0,
            ] {
                let (bx, by) = (x + dx - 0.3 * 13.0 * chars as f64, y + dy + 4.0);
                let b = text_box(bx, by, chars, 13.0);
                let inside = b.0 >= plot.0 && b.2 <= plot.2 && b.1 >= plot.1 && b.3 <= plot.3;
                let crosses = self.walls.iter().any(|&(p, q)| {
                    segment_meets_box(p, q, b) || segments_cross((x, y), (x + dx, y + dy), p, q)
                });
                if !inside || crosses || taken.iter().any(|t| boxes_overlap(*t, b)) {
                    continue;
                }
                let covered = self
                    .rays
                    .iter()
                    .filter(|(p, q)| segment_meets_box(*p, *q, b))
                    .count() as f64;
                let score = covered + 0.01 * dx.hypot(dy);
                if score < best.0 {
                    best = (score, (bx, by));
                }
            }
        }
        best.1
    }
}

/// Where interface `i`'s label goes: near the middle of its length, on whichever side and at
/// whichever of a few places along it covers the fewest ray segments and no label in `taken`.
fn interface_label_spot(
    view: &View,
    i: &eigenray::scene::Interface,
    rays: &[PixelSegment],
    taken: &[LabelBox],
) -> (f64, f64) {
    let v = i.polyline.vertices();
    let mut pts: Vec<(f64, f64)> = v.iter().map(|p| view.px(*p)).collect();
    if i.polyline.is_closed() && !pts.is_empty() {
        pts.push(pts[0]);
    }
    let lens: Vec<f64> = pts
        .windows(2)
        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
        .collect();
    let total: f64 = lens.iter().sum();
    // The point at fraction `f` of the length, and the unit normal there.
    let at = |f: f64| -> ((f64, f64), (f64, f64)) {
        let mut d = f * total;
        for (k, &l) in lens.iter().enumerate() {
            if d <= l || k + 1 == lens.len() {
                let (a, b) = (pts[k], pts[k + 1]);
                let t = if l > 0.0 {
                    (d / l).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let (dx, dy) = if l > 0.0 {
                    ((b.0 - a.0) / l, (b.1 - a.1) / l)
                } else {
                    (1.0, 0.0)
                };
                return ((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)), (-dy, dx));
            }
            d -= l;
        }
        (pts.first().copied().unwrap_or((0.0, 0.0)), (0.0, -1.0))
    };
    let chars = i.name.chars().count();
    let width = 0.6 * 12.0 * chars as f64;
    let mut best = (f64::INFINITY, (0.0, 0.0));
    for (rank, f) in [0.5, 0.4, 0.6, 0.3, 0.7, 0.2, 0.8].into_iter().enumerate() {
        let ((x, y), n) = at(f);
        for side in [1.0, -1.0] {
            // The label's centre off the line by half its box's extent across it and 5 px.
            let off = 5.0 + 0.5 * (n.0.abs() * width + n.1.abs() * 15.6);
            let (cx, cy) = (x + side * n.0 * off, y + side * n.1 * off);
            let (bx, by) = (cx - 0.5 * width, cy + 4.0);
            let b = text_box(bx, by, chars, 12.0);
            let covered = rays
                .iter()
                .filter(|(p, q)| segment_meets_box(*p, *q, b))
                .count() as f64;
            let inside = b.0 >= view.left()
                && b.2 <= view.right()
                && b.1 >= view.top()
                && b.3 <= view.bottom();
            let clash = if taken.iter().any(|t| boxes_overlap(*t, b)) {
                1e9
            } else if inside {
                0.0
            } else {
                1e6
            };
            // Prefer the middle, then fewer rays under the label.
            let score = clash + covered + 0.5 * rank as f64;
            if score < best.0 {
                best = (score, (bx, by));
            }
        }
    }
    best.1
}

/// Where each medium's name goes: at its `at` point, or else at the middle of the drawn legs in
/// that medium (the centroid of their midpoints); media with neither are not labelled.
fn medium_spots(scene: &Scene, view: &View, rays: &[Item]) -> Vec<(usize, (f64, f64))> {
    let n = scene.media().len();
    let mut sum = vec![(0.0, 0.0, 0usize); n];
    for r in rays {
        for (leg, &m) in r.media.iter().enumerate() {
            if let (Some(a), Some(b), Some(acc)) =
                (r.points.get(leg), r.points.get(leg + 1), sum.get_mut(m))
            {
                let (x, y) = view.px(Point::new(0.5 * a.x + 0.5 * b.x, 0.5 * a.y + 0.5 * b.y));
                acc.0 += x;
                acc.1 += y;
                acc.2 += 1;
            }
        }
    }
    (0..n)
        .filter_map(|m| match scene.media()[m].at {
            Some(p) => Some((m, view.px(p))),
            None => {
                let (x, y, k) = sum[m];
                (k > 0).then(|| (m, (x / k as f64, y / k as f64)))
            }
        })
        .collect()
}
