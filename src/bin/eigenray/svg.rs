//! A hand-written SVG picture of a scene and its rays, coloured by travel time (viridis).

use std::fmt::Write as _;

use eigenray::{Aabb, Point, Ray, Scene, Status};

/// Viridis (matplotlib's perceptually uniform colormap) at 0, 1/8, …, 1; linear in between.
const VIRIDIS: [[u8; 3]; 9] = [
    [0x44, 0x01, 0x54],
    [0x47, 0x2d, 0x7b],
    [0x3b, 0x52, 0x8b],
    [0x2c, 0x72, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x28, 0xae, 0x80],
    [0x5e, 0xc9, 0x62],
    [0xad, 0xdc, 0x30],
    [0xfd, 0xe7, 0x25],
];

/// Largest plot, in pixels; the scene is scaled uniformly to fit.
const PLOT_MAX_W: f64 = 820.0;
const PLOT_MAX_H: f64 = 620.0;
/// Smallest plot area (the colour bar and the title need room even for a flat scene).
const AREA_MIN_W: f64 = 460.0;
const AREA_MIN_H: f64 = 280.0;
const LEFT: f64 = 20.0;
/// Room for the title and the caption.
const TOP: f64 = 62.0;
const BOTTOM: f64 = 20.0;
/// Room right of the plot for the colour bar and its labels.
const BAR_AREA: f64 = 140.0;

/// Viridis at `t ∈ [0, 1]` (clamped; NaN is 0) as `#rrggbb`.
pub fn viridis(t: f64) -> String {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let c = |k: usize| (f64::from(a[k]) + f * (f64::from(b[k]) - f64::from(a[k]))).round() as u8;
    format!("#{:02x}{:02x}{:02x}", c(0), c(1), c(2))
}

/// World → pixel map: uniform scale about the centres, y up.
struct View {
    /// World centre.
    c: Point,
    /// Pixel centre.
    pc: (f64, f64),
    /// Pixels per world unit.
    scale: f64,
}

impl View {
    fn px(&self, p: Point) -> (f64, f64) {
        // `p − c` cannot overflow: `p` lies within the half extents of `c`.
        (
            self.pc.0 + (p.x - self.c.x) * self.scale,
            self.pc.1 - (p.y - self.c.y) * self.scale,
        )
    }
    /// `x,y x,y …` for a `points` attribute.
    fn points(&self, pts: &[Point]) -> String {
        let mut s = String::with_capacity(pts.len() * 16);
        for (k, p) in pts.iter().enumerate() {
            let (x, y) = self.px(*p);
            if k > 0 {
                s.push(' ');
            }
            let _ = write!(s, "{x:.2},{y:.2}");
        }
        s
    }
}

/// Whether a ray is drawn: it has a finite time and at least two finite points.
fn drawable(r: &Ray) -> bool {
    r.status.has_time()
        && r.time.is_finite()
        && r.points.len() >= 2
        && r.points.iter().all(|p| p.is_finite())
}

/// The world to show: centre and half extents holding the scene and the drawn rays, never
/// degenerate, with a margin. Computed in halves so that huge coordinates do not overflow.
fn world(scene: &Scene, rays: &[Ray]) -> (Point, f64, f64) {
    let mut b = scene.bbox();
    for r in rays.iter().filter(|r| drawable(r)) {
        for p in &r.points {
            b = b.union(Aabb::from_points(*p, *p));
        }
    }
    let finite = b.min.is_finite() && b.max.is_finite() && b.min.x <= b.max.x && b.min.y <= b.max.y;
    if !finite {
        b = Aabb {
            min: Point::new(-1.0, -1.0),
            max: Point::new(1.0, 1.0),
        };
    }
    let c = Point::new(0.5 * b.min.x + 0.5 * b.max.x, 0.5 * b.min.y + 0.5 * b.max.y);
    let limit = f64::MAX / 2.5;
    let (hw, hh) = (
        (0.5 * b.max.x - 0.5 * b.min.x).min(limit),
        (0.5 * b.max.y - 0.5 * b.min.y).min(limit),
    );
    let ext = hw.max(hh);
    let ext = if ext > 0.0 {
        ext
    } else {
        c.x.abs().max(c.y.abs()).min(limit).max(1.0)
    };
    (
        c,
        hw.max(0.05 * ext) + 0.08 * ext,
        hh.max(0.05 * ext) + 0.08 * ext,
    )
}

/// XML-escapes text for element content and attribute values.
fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            // Characters XML 1.0 does not allow.
            c if (c as u32) < 0x20 && !matches!(c, '\t' | '\n' | '\r') => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// A tick label: enough decimals to tell `lo` from `hi` apart.
fn tick_label(v: f64, span: f64) -> String {
    let mag = v.abs().max(span.abs());
    if mag != 0.0 && !(1e-4..1e6).contains(&mag) {
        return format!("{v:.3e}");
    }
    let decimals = if span > 0.0 {
        (3.0 - span.log10().floor()).clamp(0.0, 10.0) as usize
    } else {
        6
    };
    format!("{v:.decimals$}")
}

/// A five-pointed star of outer radius `r` centred on `(x, y)`, as polygon points.
fn star(x: f64, y: f64, r: f64) -> String {
    let mut s = String::new();
    for k in 0..10 {
        let rad = if k % 2 == 0 { r } else { 0.45 * r };
        let a = std::f64::consts::PI * (k as f64 / 5.0 - 0.5);
        let _ = write!(
            s,
            "{}{:.2},{:.2}",
            if k > 0 { " " } else { "" },
            x + rad * a.cos(),
            y + rad * a.sin()
        );
    }
    s
}

/// An SVG picture of `scene` and `rays`: the domain box (dashed), the interfaces (closed ones
/// closed), each ray with points as a polyline coloured by travel time (viridis; obstructed
/// rays dashed, vertex rays dotted), sources as stars, receivers as dots, labelled `at` points
/// of the media, a colour bar with the time range, and `title`. The y axis points up.
pub fn scene_svg(scene: &Scene, rays: &[Ray], title: &str) -> String {
    let (centre, hw, hh) = world(scene, rays);
    let scale = (0.5 * PLOT_MAX_W / hw).min(0.5 * PLOT_MAX_H / hh);
    let (plot_w, plot_h) = (2.0 * hw * scale, 2.0 * hh * scale);
    let (area_w, area_h) = (plot_w.max(AREA_MIN_W), plot_h.max(AREA_MIN_H));
    let (width, height) = (LEFT + area_w + BAR_AREA, TOP + area_h + BOTTOM);
    let view = View {
        c: centre,
        pc: (LEFT + 0.5 * area_w, TOP + 0.5 * area_h),
        scale,
    };
    let (left, top) = (view.pc.0 - 0.5 * plot_w, view.pc.1 - 0.5 * plot_h);

    let drawn: Vec<&Ray> = rays.iter().filter(|r| drawable(r)).collect();
    let range = drawn
        .iter()
        .filter(|r| r.status.has_time())
        .map(|r| r.time)
        .fold(None, |acc: Option<(f64, f64)>, t| match acc {
            None => Some((t, t)),
            Some((lo, hi)) => Some((lo.min(t), hi.max(t))),
        });
    let colour = |t: f64| match range {
        Some((lo, hi)) if hi > lo => viridis((t - lo) / (hi - lo)),
        _ => viridis(0.5),
    };

    let mut s = String::with_capacity(4096 + drawn.len() * 96);
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="DejaVu Sans, Helvetica, Arial, sans-serif">"#
    );
    let _ = writeln!(s, "<title>{}</title>", esc(title));
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r##"<rect x="{:.2}" y="{:.2}" width="{plot_w:.2}" height="{plot_h:.2}" fill="#fafafa" stroke="#e0e0e0"/>"##,
        left, top
    );

    // Title and caption.
    let _ = writeln!(
        s,
        r##"<text x="{LEFT}" y="26" font-size="16" font-weight="bold" fill="#222">{}</text>"##,
        esc(title)
    );
    let mut caption = format!(
        "{} of {} rays drawn, coloured by travel time",
        drawn.len(),
        rays.len()
    );
    if drawn.iter().any(|r| r.status == Status::Obstructed) {
        caption.push_str("; dashed: obstructed");
    }
    if drawn.iter().any(|r| r.status == Status::Vertex) {
        caption.push_str("; dotted: vertex (edge-diffracted)");
    }
    caption.push_str("; ★ sources, ● receivers");
    let _ = writeln!(
        s,
        r##"<text x="{LEFT}" y="46" font-size="12" fill="#555">{}</text>"##,
        esc(&caption)
    );

    // Domain box.
    if let Some(d) = scene.domain() {
        let (x0, y0) = view.px(Point::new(d.min.x, d.max.y));
        let (x1, y1) = view.px(Point::new(d.max.x, d.min.y));
        let _ = writeln!(
            s,
            r##"<rect x="{x0:.2}" y="{y0:.2}" width="{:.2}" height="{:.2}" fill="none" stroke="#999" stroke-width="1" stroke-dasharray="6 4"><title>domain</title></rect>"##,
            x1 - x0,
            y1 - y0
        );
    }

    // Rays.
    let stroke = match drawn.len() {
        0..=50 => 1.6,
        51..=2000 => 0.9,
        _ => 0.5,
    };
    let titles = drawn.len() <= 5000;
    let _ = writeln!(
        s,
        r#"<g fill="none" stroke-width="{stroke}" stroke-opacity="0.85" stroke-linejoin="round" stroke-linecap="round">"#
    );
    for r in &drawn {
        let t = r.time;
        let dash = match r.status {
            Status::Obstructed => r#" stroke-dasharray="5 3""#,
            Status::Vertex => r#" stroke-dasharray="1 3""#,
            _ => "",
        };
        let _ = write!(
            s,
            r#"<polyline points="{}" stroke="{}"{dash}>"#,
            view.points(&r.points),
            colour(t)
        );
        if titles {
            let _ = write!(
                s,
                "<title>source {}, receiver {}, path {}: {}, time {t}</title>",
                r.source, r.receiver, r.path, r.status
            );
        }
        let _ = writeln!(s, "</polyline>");
    }
    let _ = writeln!(s, "</g>");

    // Interfaces, over the rays that end on them.
    let _ = writeln!(
        s,
        r##"<g fill="none" stroke="#333" stroke-width="2" stroke-linejoin="round">"##
    );
    for i in scene.interfaces() {
        let tag = if i.polyline.is_closed() {
            "polygon"
        } else {
            "polyline"
        };
        let _ = writeln!(
            s,
            r#"<{tag} points="{}"><title>{}</title></{tag}>"#,
            view.points(i.polyline.vertices()),
            esc(&i.name)
        );
    }
    let _ = writeln!(s, "</g>");
    let halo = r#"stroke="white" stroke-width="3" paint-order="stroke""#;
    let _ = writeln!(s, r##"<g font-size="12" fill="#333" {halo}>"##);
    for i in scene.interfaces() {
        if let Some(p) = i.polyline.vertices().first() {
            let (x, y) = view.px(*p);
            let _ = writeln!(
                s,
                r#"<text x="{:.2}" y="{:.2}">{}</text>"#,
                x + 4.0,
                y - 5.0,
                esc(&i.name)
            );
        }
    }
    for m in scene.media() {
        if let Some(p) = m.at {
            let (x, y) = view.px(p);
            let _ = writeln!(
                s,
                r##"<path d="M{:.2},{y:.2}h8M{x:.2},{:.2}v8" stroke="#777" stroke-width="1"/><text x="{:.2}" y="{:.2}" font-style="italic" fill="#555">{}</text>"##,
                x - 4.0,
                y - 4.0,
                x + 6.0,
                y - 6.0,
                esc(&m.name)
            );
        }
    }
    let _ = writeln!(s, "</g>");

    // Receivers, then sources on top.
    let nr = scene.receivers().len();
    let radius = match nr {
        0..=100 => 3.0,
        101..=2000 => 1.8,
        _ => 1.0,
    };
    let _ = writeln!(
        s,
        r##"<g fill="#111" stroke="white" stroke-width="{:.2}">"##,
        radius * 0.3
    );
    for (k, p) in scene.receivers().iter().enumerate() {
        let (x, y) = view.px(*p);
        let _ = writeln!(
            s,
            r#"<circle cx="{x:.2}" cy="{y:.2}" r="{radius}"><title>receiver {k}</title></circle>"#
        );
    }
    let _ = writeln!(s, "</g>");
    let _ = writeln!(
        s,
        r##"<g fill="#e4572e" stroke="#222" stroke-width="1" stroke-linejoin="round">"##
    );
    for (k, p) in scene.sources().iter().enumerate() {
        let (x, y) = view.px(*p);
        let _ = writeln!(
            s,
            r#"<polygon points="{}"><title>source {k}</title></polygon>"#,
            star(x, y, 9.0)
        );
    }
    let _ = writeln!(s, "</g>");

    // Colour bar: min at the bottom, max at the top.
    let bar_x = LEFT + area_w + 30.0;
    let (bar_top, bar_bottom) = (TOP + 22.0, TOP + area_h - 6.0);
    let _ = writeln!(
        s,
        r##"<text x="{:.2}" y="{:.2}" font-size="12" fill="#222">travel time</text>"##,
        bar_x - 8.0,
        TOP + 8.0
    );
    match range {
        Some((lo, hi)) => {
            let _ = writeln!(
                s,
                r#"<defs><linearGradient id="eigenray-viridis" x1="0" y1="1" x2="0" y2="0">"#
            );
            for (k, c) in VIRIDIS.iter().enumerate() {
                let _ = writeln!(
                    s,
                    r##"<stop offset="{:.4}" stop-color="#{:02x}{:02x}{:02x}"/>"##,
                    k as f64 / (VIRIDIS.len() - 1) as f64,
                    c[0],
                    c[1],
                    c[2]
                );
            }
            let _ = writeln!(s, "</linearGradient></defs>");
            let fill = if hi > lo {
                "url(#eigenray-viridis)".to_string()
            } else {
                viridis(0.5)
            };
            let _ = writeln!(
                s,
                r##"<rect x="{bar_x:.2}" y="{bar_top:.2}" width="16" height="{:.2}" fill="{fill}" stroke="#444" stroke-width="0.8"/>"##,
                bar_bottom - bar_top
            );
            let span = hi - lo;
            let ticks: &[f64] = if hi > lo { &[0.0, 0.5, 1.0] } else { &[0.5] };
            for &f in ticks {
                let y = bar_bottom - f * (bar_bottom - bar_top);
                let v = if hi > lo { lo + f * span } else { lo };
                let _ = writeln!(
                    s,
                    r##"<path d="M{:.2},{y:.2}h5" stroke="#444" stroke-width="1"/><text x="{:.2}" y="{:.2}" font-size="12" fill="#222">{}</text>"##,
                    bar_x + 16.0,
                    bar_x + 24.0,
                    y + 4.0,
                    tick_label(v, span)
                );
            }
        }
        None => {
            let _ = writeln!(
                s,
                r##"<text x="{:.2}" y="{:.2}" font-size="12" fill="#555">no ray has a time</text>"##,
                bar_x - 8.0,
                bar_top + 14.0
            );
        }
    }
    let _ = writeln!(s, "</svg>");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_ends_and_clamps() {
        assert_eq!(viridis(0.0), "#440154");
        assert_eq!(viridis(1.0), "#fde725");
        assert_eq!(viridis(0.5), "#21918c");
        assert_eq!(viridis(-3.0), "#440154");
        assert_eq!(viridis(7.0), "#fde725");
        assert_eq!(viridis(f64::NAN), "#440154");
    }

    #[test]
    fn escapes_markup() {
        assert_eq!(
            esc(r#"a<b & "c">'"#),
            "a&lt;b &amp; &quot;c&quot;&gt;&apos;"
        );
    }

    #[test]
    fn tick_labels_separate_the_range() {
        assert_eq!(tick_label(1.8912, 0.81), "1.8912");
        assert_eq!(tick_label(1234.5, 100.0), "1234.5");
        assert_eq!(tick_label(2.5e7, 1.0), "2.500e7");
    }
}
