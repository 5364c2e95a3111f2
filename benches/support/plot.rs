//! Hand-written SVG line plots (log or linear axes, markers, legend) for the generated docs.

#![allow(
    dead_code,
    reason = "shared by the examples and the bench; each uses a part"
)]

use std::fmt::Write as _;

/// How an axis maps values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// Evenly spaced values.
    Linear,
    /// Evenly spaced decades (values ≤ 0 are not drawn).
    Log,
}

/// A marker shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A filled circle.
    Circle,
    /// A filled square.
    Square,
    /// A filled triangle.
    Triangle,
    /// A filled diamond.
    Diamond,
    /// An open circle.
    Ring,
    /// A five-pointed star (for other tools' figures).
    Star,
}

/// One named polyline with markers (markers only when `line` is false).
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// `(x, y)` in data units, drawn in order.
    pub points: Vec<(f64, f64)>,
    /// Optional small label beside each point (same length as `points`, or empty).
    pub labels: Vec<String>,
    /// CSS colour.
    pub color: String,
    /// Marker shape.
    pub marker: Marker,
    /// Whether to join the points.
    pub line: bool,
    /// Whether the line is dashed.
    pub dashed: bool,
}

impl Series {
    /// A joined series with the `i`-th colour and marker of the palette.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>, i: usize) -> Series {
        Series {
            name: name.into(),
            points,
            labels: Vec::new(),
            color: PALETTE[i % PALETTE.len()].to_string(),
            marker: MARKERS[i % MARKERS.len()],
            line: true,
            dashed: false,
        }
    }
}

/// A colour-blind-friendly palette (Okabe–Ito, then greys).
pub const PALETTE: [&str; 8] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#8C8C8C",
];
const MARKERS: [Marker; 5] = [
    Marker::Circle,
    Marker::Square,
    Marker::Triangle,
    Marker::Diamond,
    Marker::Ring,
];

/// A plot: axes, series, horizontal reference lines, legend.
#[derive(Clone, Debug)]
pub struct Plot {
    /// Title above the plot area.
    pub title: String,
    /// A smaller second title line (may be empty).
    pub subtitle: String,
    /// Label under the x axis.
    pub x_label: String,
    /// Label beside the y axis.
    pub y_label: String,
    /// x axis mapping.
    pub x_scale: Scale,
    /// y axis mapping.
    pub y_scale: Scale,
    /// The data.
    pub series: Vec<Series>,
    /// Dashed horizontal lines with a label: `(y, label)`.
    pub hlines: Vec<(f64, String)>,
    /// Forced axis ranges (data range, widened to whole decades or nice steps, when `None`).
    pub x_range: Option<(f64, f64)>,
    /// See `x_range`.
    pub y_range: Option<(f64, f64)>,
}

const H: f64 = 540.0;
const LEFT: f64 = 78.0;
/// Width of the plot area.
const AREA: f64 = 560.0;
const TOP: f64 = 58.0;
const BOTTOM: f64 = 56.0;

struct Axis {
    scale: Scale,
    lo: f64,
    hi: f64,
    /// Pixel positions of `lo` and `hi`.
    p0: f64,
    p1: f64,
}

impl Axis {
    fn f(&self, v: f64) -> f64 {
        match self.scale {
            Scale::Linear => v,
            Scale::Log => v.log10(),
        }
    }
    fn px(&self, v: f64) -> f64 {
        let (a, b) = (self.f(self.lo), self.f(self.hi));
        self.p0 + (self.f(v) - a) / (b - a) * (self.p1 - self.p0)
    }
    fn drawable(&self, v: f64) -> bool {
        v.is_finite() && (self.scale == Scale::Linear || v > 0.0)
    }
    /// Major ticks `(value, label)` and minor tick values.
    fn ticks(&self) -> (Vec<(f64, String)>, Vec<f64>) {
        match self.scale {
            Scale::Log => {
                let (a, b) = (
                    self.lo.log10().round() as i32,
                    self.hi.log10().round() as i32,
                );
                let span = (b - a).max(1);
                let every = (span as f64 / 9.0).ceil().max(1.0) as i32;
                let mut major = Vec::new();
                let mut minor = Vec::new();
                for e in a..=b {
                    let v = 10f64.powi(e);
                    if (e - a) % every == 0 {
                        major.push((v, pow10_label(e)));
                    } else {
                        minor.push(v);
                    }
                    if span <= 6 && e < b {
                        minor.extend((2..10).map(|m| m as f64 * v));
                    }
                }
                (major, minor)
            }
            Scale::Linear => {
                let step = nice_step((self.hi - self.lo) / 6.0);
                let mut major = Vec::new();
                let mut v = (self.lo / step).ceil() * step;
                while v <= self.hi + 1e-9 * step {
                    major.push((v, fmt_linear(v, step)));
                    v += step;
                }
                (major, Vec::new())
            }
        }
    }
}

fn nice_step(raw: f64) -> f64 {
    let e = raw.log10().floor();
    let base = 10f64.powf(e);
    let m = raw / base;
    let nice = if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * base
}

fn fmt_linear(v: f64, step: f64) -> String {
    if v.abs() >= 1e5 || (v != 0.0 && v.abs() < 1e-3) {
        return format!("{v:e}");
    }
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10()).ceil() as usize
    };
    format!("{v:.decimals$}")
}

fn pow10_label(e: i32) -> String {
    match e {
        0 => "1".to_string(),
        1 => "10".to_string(),
        _ => format!("10<tspan dy=\"-7\" font-size=\"10\">{e}</tspan>"),
    }
}

/// The axis range drawn for `values`: whole decades on a log axis; on a linear one, nice
/// steps from `min(0, smallest)`.
pub fn range(scale: Scale, values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        if v.is_finite() && (scale == Scale::Linear || v > 0.0) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if !lo.is_finite() {
        return (1.0, 10.0);
    }
    match scale {
        Scale::Log => {
            let (a, mut b) = (lo.log10().floor(), hi.log10().ceil());
            if b <= a {
                b = a + 1.0;
            }
            (10f64.powf(a), 10f64.powf(b))
        }
        Scale::Linear => {
            let lo = lo.min(0.0);
            let hi = if hi > lo { hi } else { lo + 1.0 };
            let step = nice_step((hi - lo) / 6.0);
            ((lo / step).floor() * step, (hi / step).ceil() * step)
        }
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn marker(out: &mut String, m: Marker, x: f64, y: f64, color: &str) {
    let r = 4.5;
    let _ = match m {
        Marker::Circle => writeln!(
            out,
            r#"<circle cx="{x:.1}" cy="{y:.1}" r="{r}" fill="{color}"/>"#
        ),
        Marker::Ring => writeln!(
            out,
            r#"<circle cx="{x:.1}" cy="{y:.1}" r="{r}" fill="white" stroke="{color}" stroke-width="2"/>"#
        ),
        Marker::Square => writeln!(
            out,
            r#"<rect x="{:.1}" y="{:.1}" width="8" height="8" fill="{color}"/>"#,
            x - 4.0,
            y - 4.0
        ),
        Marker::Triangle => writeln!(
            out,
            r#"<path d="M{x:.1},{:.1} L{:.1},{:.1} L{:.1},{:.1} Z" fill="{color}"/>"#,
            y - 5.5,
            x + 5.0,
            y + 4.0,
            x - 5.0,
            y + 4.0
        ),
        Marker::Diamond => writeln!(
            out,
            r#"<path d="M{x:.1},{:.1} L{:.1},{y:.1} L{x:.1},{:.1} L{:.1},{y:.1} Z" fill="{color}"/>"#,
            y - 5.5,
            x + 5.0,
            y + 5.5,
            x - 5.0
        ),
        Marker::Star => {
            let mut d = String::new();
            for i in 0..10 {
                let a = std::f64::consts::PI * (i as f64) / 5.0 - std::f64::consts::FRAC_PI_2;
                let rr = if i % 2 == 0 { 7.5 } else { 3.2 };
                let _ = write!(
                    d,
                    "{}{:.1},{:.1} ",
                    if i == 0 { "M" } else { "L" },
                    x + rr * a.cos(),
                    y + rr * a.sin()
                );
            }
            writeln!(
                out,
                r#"<path d="{d}Z" fill="{color}" stroke="black" stroke-width="0.6"/>"#
            )
        }
    };
}

impl Plot {
    /// A plot with no series yet.
    pub fn new(title: impl Into<String>, x_label: &str, y_label: &str, x: Scale, y: Scale) -> Plot {
        Plot {
            title: title.into(),
            subtitle: String::new(),
            x_label: x_label.to_string(),
            y_label: y_label.to_string(),
            x_scale: x,
            y_scale: y,
            series: Vec::new(),
            hlines: Vec::new(),
            x_range: None,
            y_range: None,
        }
    }

    /// The SVG document.
    pub fn to_svg(&self) -> String {
        let all = || self.series.iter().flat_map(|s| s.points.iter().copied());
        let (xlo, xhi) = self
            .x_range
            .unwrap_or_else(|| range(self.x_scale, all().map(|p| p.0)));
        let (ylo, yhi) = self.y_range.unwrap_or_else(|| {
            range(
                self.y_scale,
                all().map(|p| p.1).chain(self.hlines.iter().map(|h| h.0)),
            )
        });
        // The legend sits right of the plot area and sets the width.
        let longest = self
            .series
            .iter()
            .map(|s| s.name.chars().count())
            .max()
            .unwrap_or(0);
        let right = (60.0 + 6.4 * longest as f64).max(40.0);
        let w = (LEFT + AREA + right).max(LEFT + 6.2 * self.subtitle.chars().count() as f64 + 20.0);
        let (x0, x1, y0, y1) = (LEFT, LEFT + AREA, H - BOTTOM, TOP);
        let xa = Axis {
            scale: self.x_scale,
            lo: xlo,
            hi: xhi,
            p0: x0,
            p1: x1,
        };
        let ya = Axis {
            scale: self.y_scale,
            lo: ylo,
            hi: yhi,
            p0: y0,
            p1: y1,
        };
        let mut o = String::new();
        let _ = writeln!(
            o,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{H}" viewBox="0 0 {w:.0} {H}" font-family="DejaVu Sans, Helvetica, Arial, sans-serif" font-size="12">"#
        );
        let _ = writeln!(o, r#"<rect width="{w:.0}" height="{H}" fill="white"/>"#);
        let _ = writeln!(
            o,
            r#"<text x="{LEFT}" y="22" font-size="15" font-weight="bold">{}</text>"#,
            esc(&self.title)
        );
        if !self.subtitle.is_empty() {
            let _ = writeln!(
                o,
                r##"<text x="{LEFT}" y="40" font-size="11" fill="#444">{}</text>"##,
                esc(&self.subtitle)
            );
        }
        // Grid and ticks.
        let (xmaj, xmin) = xa.ticks();
        let (ymaj, ymin) = ya.ticks();
        for v in xmin {
            let x = xa.px(v);
            let _ = writeln!(
                o,
                r##"<line x1="{x:.1}" y1="{y0}" x2="{x:.1}" y2="{y1}" stroke="#f0f0f0"/>"##
            );
        }
        for v in ymin {
            let y = ya.px(v);
            let _ = writeln!(
                o,
                r##"<line x1="{x0}" y1="{y:.1}" x2="{x1}" y2="{y:.1}" stroke="#f0f0f0"/>"##
            );
        }
        for (v, label) in &xmaj {
            let x = xa.px(*v);
            let _ = writeln!(
                o,
                r##"<line x1="{x:.1}" y1="{y0}" x2="{x:.1}" y2="{y1}" stroke="#d8d8d8"/><line x1="{x:.1}" y1="{y0}" x2="{x:.1}" y2="{:.1}" stroke="black"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{label}</text>"##,
                y0 + 5.0,
                y0 + 20.0
            );
        }
        for (v, label) in &ymaj {
            let y = ya.px(*v);
            let _ = writeln!(
                o,
                r##"<line x1="{x0}" y1="{y:.1}" x2="{x1}" y2="{y:.1}" stroke="#d8d8d8"/><line x1="{:.1}" y1="{y:.1}" x2="{x0}" y2="{y:.1}" stroke="black"/><text x="{:.1}" y="{:.1}" text-anchor="end">{label}</text>"##,
                x0 - 5.0,
                x0 - 8.0,
                y + 4.0
            );
        }
        let _ = writeln!(
            o,
            r#"<rect x="{x0}" y="{y1}" width="{:.1}" height="{:.1}" fill="none" stroke="black"/>"#,
            x1 - x0,
            y0 - y1
        );
        let _ = writeln!(
            o,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="13">{}</text>"#,
            (x0 + x1) / 2.0,
            H - 14.0,
            esc(&self.x_label)
        );
        let _ = writeln!(
            o,
            r#"<text transform="translate(18,{:.1}) rotate(-90)" text-anchor="middle" font-size="13">{}</text>"#,
            (y0 + y1) / 2.0,
            esc(&self.y_label)
        );
        // Reference lines.
        for (v, label) in &self.hlines {
            if !ya.drawable(*v) || *v < ylo || *v > yhi {
                continue;
            }
            let y = ya.px(*v);
            // The label below the line (markers tend to sit on such lines from above), or
            // above it near the bottom of the plot area.
            let ty = if y + 13.0 < y0 - 2.0 {
                y + 13.0
            } else {
                y - 4.0
            };
            let _ = writeln!(
                o,
                r##"<line x1="{x0}" y1="{y:.1}" x2="{x1}" y2="{y:.1}" stroke="#777" stroke-dasharray="6,4"/><text x="{:.1}" y="{ty:.1}" text-anchor="end" font-size="10" fill="#555">{}</text>"##,
                x1 - 4.0,
                esc(label)
            );
        }
        // Data, clipped to the plot area.
        let _ = writeln!(
            o,
            r#"<clipPath id="area"><rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}"/></clipPath><g clip-path="url(#area)">"#,
            x0 - 8.0,
            y1 - 8.0,
            x1 - x0 + 16.0,
            y0 - y1 + 16.0
        );
        for s in &self.series {
            let pts: Vec<(f64, f64, usize)> = s
                .points
                .iter()
                .enumerate()
                .filter(|(_, p)| xa.drawable(p.0) && ya.drawable(p.1))
                .map(|(i, p)| (xa.px(p.0), ya.px(p.1), i))
                .collect();
            if s.line && pts.len() > 1 {
                let d: Vec<String> = pts
                    .iter()
                    .map(|p| format!("{:.1},{:.1}", p.0, p.1))
                    .collect();
                let dash = if s.dashed {
                    r#" stroke-dasharray="5,3""#
                } else {
                    ""
                };
                let _ = writeln!(
                    o,
                    r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="1.8"{dash}/>"#,
                    d.join(" "),
                    s.color
                );
            }
            for &(x, y, i) in &pts {
                marker(&mut o, s.marker, x, y, &s.color);
                if let Some(label) = s.labels.get(i).filter(|l| !l.is_empty()) {
                    let _ = writeln!(
                        o,
                        r#"<text x="{:.1}" y="{:.1}" font-size="9.5" fill="{}">{}</text>"#,
                        x + 6.0,
                        y - 5.0,
                        s.color,
                        esc(label)
                    );
                }
            }
        }
        let _ = writeln!(o, "</g>");
        // Legend, right of the plot area.
        let lx = x1 + 18.0;
        let mut ly = y1 + 8.0;
        for s in &self.series {
            if s.line {
                let dash = if s.dashed {
                    r#" stroke-dasharray="5,3""#
                } else {
                    ""
                };
                let _ = writeln!(
                    o,
                    r#"<line x1="{lx:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{}" stroke-width="1.8"{dash}/>"#,
                    lx + 26.0,
                    s.color
                );
            }
            marker(&mut o, s.marker, lx + 13.0, ly, &s.color);
            let _ = writeln!(
                o,
                r#"<text x="{:.1}" y="{:.1}" font-size="11.5">{}</text>"#,
                lx + 34.0,
                ly + 4.0,
                esc(&s.name)
            );
            ly += 20.0;
        }
        let _ = writeln!(o, "</svg>");
        o
    }
}
