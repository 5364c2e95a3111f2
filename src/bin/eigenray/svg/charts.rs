//! Charts of what arrives: the echogram of one (source, receiver) and the transmission-loss
//! map of one source over its receivers, each an SVG with axes, units and a key.

use std::f64::consts::PI;
use std::fmt::Write as _;

use eigenray::response::Echo;
use eigenray::{Point, Scene};

use super::axes::{Axes, AxisSpec, axis_ticks};
use super::colour::{PATH_COLOURS, viridis};
use super::marks::star;
use super::markup::esc;

/// The canvas: the plot's box inside margins for the axes, the title and the key.
const WIDTH: f64 = 860.0;
const HEIGHT: f64 = 520.0;
const LEFT: f64 = 78.0;
const TOP: f64 = 54.0;
const PLOT_W: f64 = 600.0;
const PLOT_H: f64 = 390.0;

/// The dynamic range of both charts: levels more than this far below the loudest are drawn at
/// the floor (echogram) or at the colour bar's end (map).
pub const RANGE_DB: f64 = 60.0;

/// Most orders an echogram keys by a legend of distinct colours; with more, each order takes
/// its colour on a colour bar of orders.
pub const MAX_ORDER_LEGEND: usize = 10;

/// The colour of a diffracted arrival's stem and mark (apart from the orders' palettes).
const DIFFRACTED_COLOUR: &str = "#111111";

/// A diamond mark (a diffracted arrival's) of half-width `r` centred on `(x, y)`, as path data.
fn diamond(x: f64, y: f64, r: f64) -> String {
    format!("M{x:.2},{:.2}l{r},{r}l-{r},{r}l-{r},-{r}z", y - r)
}

/// A plot box mapping `[x0, x1] × [y0, y1]` onto the canvas (y up), numbered as its axes say.
struct Plot<'a> {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    x_axis: &'a AxisSpec,
    y_axis: &'a AxisSpec,
}

impl Plot<'_> {
    fn px(&self, x: f64, y: f64) -> (f64, f64) {
        (
            LEFT + (x - self.x0) / (self.x1 - self.x0) * PLOT_W,
            TOP + PLOT_H - (y - self.y0) / (self.y1 - self.y0) * PLOT_H,
        )
    }

    /// Opens the document: white canvas, title, the plot's box, grid, ticks and axis titles.
    fn open(&self, s: &mut String, title: &str) {
        let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="DejaVu Sans, Helvetica, Arial, sans-serif">"#
        );
        let _ = writeln!(s, "<title>{}</title>", esc(title));
        let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
        let _ = writeln!(
            s,
            r##"<text x="{LEFT}" y="30" font-size="15" fill="#222">{}</text>"##,
            esc(title)
        );
        let _ = writeln!(
            s,
            r##"<rect class="plot" x="{LEFT}" y="{TOP}" width="{PLOT_W}" height="{PLOT_H}" fill="#fafafa" stroke="#bbb"/>"##
        );
        let _ = writeln!(
            s,
            r##"<g class="axes" stroke="#e4e4e4" stroke-width="1" font-size="11" fill="#444">"##
        );
        for (v, label) in self.x_axis.ticks(self.x0, self.x1, PLOT_W / 90.0) {
            let (x, _) = self.px(v, self.y0);
            let _ = writeln!(
                s,
                r##"<path d="M{x:.2},{TOP}V{:.2}"/><path d="M{x:.2},{:.2}v5" stroke="#444"/><text class="x-tick" x="{x:.2}" y="{:.2}" text-anchor="middle" stroke="none">{}</text>"##,
                TOP + PLOT_H,
                TOP + PLOT_H,
                TOP + PLOT_H + 17.0,
                esc(&label)
            );
        }
        for (v, label) in self.y_axis.ticks(self.y0, self.y1, PLOT_H / 55.0) {
            let (_, y) = self.px(self.x0, v);
            let _ = writeln!(
                s,
                r##"<path d="M{LEFT},{y:.2}H{:.2}"/><path d="M{LEFT},{y:.2}h-5" stroke="#444"/><text class="y-tick" x="{:.2}" y="{:.2}" text-anchor="end" stroke="none">{}</text>"##,
                LEFT + PLOT_W,
                LEFT - 8.0,
                y + 4.0,
                esc(&label)
            );
        }
        let _ = writeln!(
            s,
            r##"<text class="x-title" x="{:.2}" y="{:.2}" text-anchor="middle" stroke="none" font-size="13" fill="#222">{}</text>"##,
            LEFT + PLOT_W / 2.0,
            TOP + PLOT_H + 40.0,
            esc(&self.x_axis.title())
        );
        let (yx, yy) = (LEFT - 58.0, TOP + PLOT_H / 2.0);
        let _ = writeln!(
            s,
            r##"<text class="y-title" x="{yx:.2}" y="{yy:.2}" text-anchor="middle" stroke="none" font-size="13" fill="#222" transform="rotate(-90 {yx:.2} {yy:.2})">{}</text>"##,
            esc(&self.y_axis.title())
        );
        let _ = writeln!(s, "</g>");
    }
}

/// The level of an amplitude in dB re the free field 1 unit of length from a point source:
/// `20 log10(|a| · 4π)`.
fn level_db(amplitude: f64) -> f64 {
    20.0 * (amplitude * 4.0 * PI).log10()
}

/// The legend label of an order.
fn order_label(order: usize) -> String {
    match order {
        0 => "direct".into(),
        1 => "1 interaction".into(),
        k => format!("{k} interactions"),
    }
}

/// The colour of each order of an echogram: up to [`MAX_ORDER_LEGEND`] orders, a distinct
/// colour of the path palette each (with a legend); beyond, the order's place on viridis
/// between the lowest and highest order (with a colour bar), a distinct colour for each order
/// up to hundreds of them.
struct OrderColours {
    /// The orders present, ascending.
    orders: Vec<usize>,
}

impl OrderColours {
    /// Whether a legend keys the colours (else a colour bar).
    fn legend(&self) -> bool {
        self.orders.len() <= MAX_ORDER_LEGEND
    }

    /// The range of orders of the colour bar.
    fn range(&self) -> (usize, usize) {
        (
            self.orders.first().copied().unwrap_or(0),
            self.orders.last().copied().unwrap_or(0),
        )
    }

    /// The colour of `order`, as `#rrggbb`.
    fn of(&self, order: usize) -> String {
        if self.legend() {
            let i = self.orders.binary_search(&order).unwrap_or(0);
            PATH_COLOURS[i % PATH_COLOURS.len()].to_string()
        } else {
            let (lo, hi) = self.range();
            // Short of viridis's last, palest yellow, which a thin stem on white hides.
            viridis(0.92 * (order - lo) as f64 / (hi - lo).max(1) as f64)
        }
    }
}

/// The time axis of an echogram of arrivals from `first` to `last`: from just before the first
/// arrival (a twentieth of the spread of times before it), or from t = 0 with `from_zero`, to
/// as far after the last.
fn time_axis(first: f64, last: f64, from_zero: bool) -> (f64, f64) {
    if !(first.is_finite() && last.is_finite()) {
        return (0.0, 1.0);
    }
    let spread = last - first;
    let pad = if spread > 0.0 {
        0.05 * spread
    } else if last > 0.0 {
        0.05 * last
    } else {
        0.05
    };
    let start = if from_zero {
        0.0_f64.min(first - pad)
    } else if first >= 0.0 {
        (first - pad).max(0.0)
    } else {
        first - pad
    };
    (start, last + pad)
}

/// The echogram of `echoes` (one pair's): a stem per echo at its time, up to its level in dB
/// re 1 unit of length of free field (from [`RANGE_DB`] below the loudest), coloured by its
/// order, with a legend of the orders (or past [`MAX_ORDER_LEGEND`] of them a colour bar);
/// a diffracted echo (one with a diffraction at a vertex) apart: a dashed dark stem ending in
/// a diamond, keyed "diffracted" (its order not among the colours); `title` above. The time axis starts just before the first arrival, or at t = 0 with
/// `from_zero`.
pub fn echogram_svg(title: &str, echoes: &[Echo], from_zero: bool) -> String {
    let mut s = String::with_capacity(4096 + 160 * echoes.len());
    let levels: Vec<f64> = echoes
        .iter()
        .map(|e| level_db(e.amplitude.norm()))
        .collect();
    let top = levels.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (top, floor) = if top.is_finite() {
        let top = (top / 10.0).ceil() * 10.0 + 5.0;
        (top, top - RANGE_DB - 5.0)
    } else {
        (0.0, -RANGE_DB)
    };
    let first = echoes.iter().map(|e| e.time).fold(f64::INFINITY, f64::min);
    let last = echoes
        .iter()
        .map(|e| e.time)
        .fold(f64::NEG_INFINITY, f64::max);
    let (x0, x1) = time_axis(first, last, from_zero);
    let (time_axis, level_axis) = (
        AxisSpec {
            name: "time".into(),
            unit: Some("s".into()),
            scale: 1.0,
        },
        AxisSpec::plain("level (dB re free field at 1 unit of length)"),
    );
    let plot = Plot {
        x0,
        x1,
        y0: floor,
        y1: top,
        x_axis: &time_axis,
        y_axis: &level_axis,
    };
    plot.open(&mut s, title);
    let mut orders: Vec<usize> = (echoes.iter())
        .filter(|e| e.diffractions == 0)
        .map(|e| e.order)
        .collect();
    orders.sort_unstable();
    orders.dedup();
    let colours = OrderColours { orders };
    // The quietest first, so that the loud ones are on top.
    let mut by_level: Vec<usize> = (0..echoes.len()).collect();
    by_level.sort_by(|&a, &b| levels[a].total_cmp(&levels[b]));
    let _ = writeln!(s, r#"<g class="stems" stroke-width="1.6">"#);
    for i in by_level {
        let e = &echoes[i];
        let level = levels[i].max(floor);
        let (x, y) = plot.px(e.time, level);
        let (_, y0) = plot.px(e.time, floor);
        if e.diffractions > 0 {
            let _ = writeln!(
                s,
                r##"<path d="M{x:.2},{y0:.2}V{y:.2}" stroke="{DIFFRACTED_COLOUR}" stroke-dasharray="3 2"/><path class="diffracted" d="{}" fill="{DIFFRACTED_COLOUR}" stroke="none"><title>{} s, {:.1} dB, {}, diffracted</title></path>"##,
                diamond(x, y, 3.6),
                e.time,
                levels[i],
                order_label(e.order)
            );
            continue;
        }
        let c = colours.of(e.order);
        if e.vertical_reflections > 0 {
            // Off the floor or the ceiling of an extruded room: a square, outlined.
            let _ = writeln!(
                s,
                r##"<path d="M{x:.2},{y0:.2}V{y:.2}" stroke="{c}"/><rect class="vertical" x="{:.2}" y="{:.2}" width="6" height="6" fill="{c}" stroke="{DIFFRACTED_COLOUR}" stroke-width="0.9"><title>{} s, {:.1} dB, {}, {} floor/ceiling</title></rect>"##,
                x - 3.0,
                y - 3.0,
                e.time,
                levels[i],
                order_label(e.order),
                e.vertical_reflections
            );
            continue;
        }
        let _ = writeln!(
            s,
            r##"<path d="M{x:.2},{y0:.2}V{y:.2}" stroke="{c}"/><circle cx="{x:.2}" cy="{y:.2}" r="2.4" fill="{c}" stroke="none"><title>{} s, {:.1} dB, {}</title></circle>"##,
            e.time,
            levels[i],
            order_label(e.order)
        );
    }
    let _ = writeln!(s, "</g>");
    let diffracted = echoes.iter().any(|e| e.diffractions > 0);
    let vertical = echoes
        .iter()
        .any(|e| e.diffractions == 0 && e.vertical_reflections > 0);
    if colours.legend() {
        order_legend(&mut s, &colours, diffracted, vertical);
    } else {
        order_colour_bar(&mut s, &colours);
        // Above the colour bar, in the title's row.
        if diffracted {
            diffracted_key(&mut s, LEFT + PLOT_W + 22.0, TOP - 22.0);
        }
        if vertical {
            let x = LEFT + PLOT_W + if diffracted { -90.0 } else { 22.0 };
            vertical_key(&mut s, x, TOP - 22.0);
        }
    }
    let caption = format!(
        "{} arrivals; stems start {RANGE_DB:.0} dB below the loudest; time {}",
        echoes.len(),
        if from_zero {
            "from 0"
        } else {
            "from just before the first arrival"
        }
    );
    let _ = writeln!(
        s,
        r##"<text x="{LEFT}" y="{:.1}" font-size="11" fill="#555">{}</text>"##,
        HEIGHT - 12.0,
        esc(&caption)
    );
    let _ = writeln!(s, "</svg>");
    s
}

/// The key of a diffracted arrival's mark, its diamond's top left near `(x, y)`.
fn diffracted_key(s: &mut String, x: f64, y: f64) {
    let _ = writeln!(
        s,
        r##"<g class="diffracted-key" font-size="12" fill="#222"><path d="M{:.1},{:.1}v12" stroke="{DIFFRACTED_COLOUR}" stroke-width="1.6" stroke-dasharray="3 2"/><path d="{}" fill="{DIFFRACTED_COLOUR}"/><text x="{:.1}" y="{:.1}">diffracted</text></g>"##,
        x + 6.0,
        y + 2.0,
        diamond(x + 6.0, y - 4.0, 4.0),
        x + 18.0,
        y + 2.0,
    );
}

/// The key of a floor or ceiling reflection's mark (an extruded room's), its square's top
/// left near `(x, y)`.
fn vertical_key(s: &mut String, x: f64, y: f64) {
    let _ = writeln!(
        s,
        r##"<g class="vertical-key" font-size="12" fill="#222"><rect x="{:.1}" y="{:.1}" width="8" height="8" fill="none" stroke="{DIFFRACTED_COLOUR}" stroke-width="1.2"/><text x="{:.1}" y="{:.1}">floor/ceiling</text></g>"##,
        x + 2.0,
        y - 6.0,
        x + 18.0,
        y + 2.0,
    );
}

/// The legend of an echogram's orders, right of the plot: a swatch and a label each, and
/// with `diffracted` the diffracted arrivals' mark below them, with `vertical` the floor
/// and ceiling reflections'.
fn order_legend(s: &mut String, colours: &OrderColours, diffracted: bool, vertical: bool) {
    let x = LEFT + PLOT_W + 22.0;
    let _ = writeln!(
        s,
        r##"<g class="legend" font-size="12" fill="#222"><text x="{x}" y="{}" font-weight="bold">order</text>"##,
        TOP + 10.0
    );
    for (k, &order) in colours.orders.iter().enumerate() {
        let y = TOP + 30.0 + 17.0 * k as f64;
        let _ = writeln!(
            s,
            r##"<rect x="{x}" y="{:.1}" width="12" height="12" fill="{}"/><text x="{:.1}" y="{:.1}">{}</text>"##,
            y - 10.0,
            colours.of(order),
            x + 18.0,
            y,
            order_label(order)
        );
    }
    let mut y = TOP + 30.0 + 17.0 * colours.orders.len() as f64 + 6.0;
    if diffracted {
        diffracted_key(s, x, y);
        y += 20.0;
    }
    if vertical {
        vertical_key(s, x, y);
    }
    let _ = writeln!(s, "</g>");
}

/// The colour bar of an echogram's orders, right of the plot: a block per order from the
/// lowest (top) to the highest, numbered at round orders.
fn order_colour_bar(s: &mut String, colours: &OrderColours) {
    let (lo, hi) = colours.range();
    let x = LEFT + PLOT_W + 30.0;
    let n = hi - lo + 1;
    let block = PLOT_H / n as f64;
    let _ = writeln!(s, r##"<g class="order-bar" font-size="11" fill="#222">"##);
    for order in lo..=hi {
        let y = TOP + block * (order - lo) as f64;
        let _ = writeln!(
            s,
            r#"<rect x="{x}" y="{y:.2}" width="18" height="{:.2}" fill="{}" stroke="none"/>"#,
            block + 0.3,
            colours.of(order)
        );
    }
    let _ = writeln!(
        s,
        r##"<rect x="{x}" y="{TOP}" width="18" height="{PLOT_H}" fill="none" stroke="#888"/>"##
    );
    for (v, label) in axis_ticks(lo as f64, hi as f64, 8.0) {
        if v.fract() != 0.0 {
            continue;
        }
        let y = TOP + block * (v - lo as f64 + 0.5);
        bar_tick(s, x, y, &label);
    }
    let (tx, ty) = (x + 60.0, TOP + PLOT_H / 2.0);
    let _ = writeln!(
        s,
        r##"<text x="{tx:.1}" y="{ty:.1}" text-anchor="middle" font-size="13" transform="rotate(-90 {tx:.1} {ty:.1})">order (interactions; 0: direct)</text></g>"##
    );
}

/// What a transmission-loss map shows: one source's loss at every receiver of a scene.
pub struct TlMap<'a> {
    /// Above the map.
    pub title: &'a str,
    /// The scene: its receivers, interfaces and sources.
    pub scene: &'a Scene,
    /// The source mapped.
    pub source: usize,
    /// The loss in dB at each receiver, in the scene's order (+inf where nothing arrives).
    pub tl: &'a [f64],
    /// The frequency, in Hz.
    pub frequency: f64,
    /// The axes' names, units and scales.
    pub axes: &'a Axes,
}

/// The interface that bounds the water below `source`: of the open interfaces that pass
/// beneath it (a segment spanning its x), the one nearest below it.
fn bottom_below(scene: &Scene, source: Point) -> Option<usize> {
    nearest_interface(scene, source, -1.0)
}

/// Of the open interfaces that pass over or under `source` (a segment spanning its x), the
/// one nearest to it on the side of `side` (+1 above, −1 below).
fn nearest_interface(scene: &Scene, source: Point, side: f64) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (k, interface) in scene.interfaces().iter().enumerate() {
        if interface.polyline.is_closed() {
            continue;
        }
        for w in interface.polyline.vertices().windows(2) {
            let (a, b) = (w[0], w[1]);
            let (lo, hi) = (a.x.min(b.x), a.x.max(b.x));
            if !(lo <= source.x && source.x <= hi) || hi <= lo {
                continue;
            }
            let y = a.y + (b.y - a.y) * (source.x - a.x) / (b.x - a.x);
            let distance = side * (y - source.y);
            if distance > 0.0 && best.is_none_or(|(_, d)| distance < d) {
                best = Some((k, distance));
            }
        }
    }
    best.map(|(k, _)| k)
}

/// The lowest and highest y of `vertices` (a polyline) over `x0 ≤ x ≤ x1`, `None` where it
/// does not reach there.
fn y_range_within(vertices: &[Point], x0: f64, x1: f64) -> Option<(f64, f64)> {
    let mut range: Option<(f64, f64)> = None;
    let mut take = |y: f64| {
        range = Some(range.map_or((y, y), |(lo, hi)| (lo.min(y), hi.max(y))));
    };
    for w in vertices.windows(2) {
        let (a, b) = (w[0], w[1]);
        for p in [a, b] {
            if x0 <= p.x && p.x <= x1 {
                take(p.y);
            }
        }
        if a.x != b.x {
            for x in [x0, x1] {
                let t = (x - a.x) / (b.x - a.x);
                if (0.0..=1.0).contains(&t) {
                    take(a.y + t * (b.y - a.y));
                }
            }
        }
    }
    range
}

/// The transmission-loss map of one source: each receiver's loss in dB as a cell of a grid
/// when the receivers form one (every pair of their distinct x and y), else as a dot; on
/// reversed viridis over [`RANGE_DB`] from the lowest loss (loud is bright), with a colour bar;
/// receivers nothing reaches in grey. Over it the scene's interfaces, the bottom (below the
/// first open interface under the source) shaded, and the source as a star; the axes named,
/// and numbered, as `map.axes` says.
pub fn tl_map_svg(map: &TlMap<'_>) -> String {
    let (scene, tl, frequency) = (map.scene, map.tl, map.frequency);
    let receivers = scene.receivers();
    let source = scene.sources()[map.source];
    let mut s = String::with_capacity(4096 + 200 * receivers.len());
    let xs = distinct(receivers.iter().map(|p| p.x));
    let ys = distinct(receivers.iter().map(|p| p.y));
    let grid = xs.len() * ys.len() == receivers.len() && receivers.len() > 1;
    // Half a cell beyond the outer receivers.
    let half = |v: &[f64]| {
        if v.len() > 1 {
            (v[v.len() - 1] - v[0]) / (v.len() - 1) as f64 / 2.0
        } else {
            0.5
        }
    };
    let (hx, hy) = (half(&xs), half(&ys));
    let (mut x0, mut x1) = (
        xs.first().copied().unwrap_or(0.0) - hx,
        xs.last().copied().unwrap_or(1.0) + hx,
    );
    let (mut y0, mut y1) = (
        ys.first().copied().unwrap_or(0.0) - hy,
        ys.last().copied().unwrap_or(1.0) + hy,
    );
    // The source in view, with a margin when it lies outside the receivers' box.
    let (mx, my) = (0.02 * (x1 - x0), 0.04 * (y1 - y0));
    if source.x < x0 || source.x > x1 {
        (x0, x1) = (x0.min(source.x - mx), x1.max(source.x + mx));
    }
    if source.y < y0 || source.y > y1 {
        (y0, y1) = (y0.min(source.y - my), y1.max(source.y + my));
    }
    // The surface above the source and the bottom below it in view too, where they lie
    // within half the map's height of it.
    let reach = 0.5 * (y1 - y0);
    for side in [1.0, -1.0] {
        let Some(k) = nearest_interface(scene, source, side) else {
            continue;
        };
        let vertices = scene.interfaces()[k].polyline.vertices();
        if let Some((lo, hi)) = y_range_within(vertices, x0, x1) {
            if side < 0.0 && lo < y0 && y0 - lo <= reach {
                y0 = lo - 0.03 * (y1 - lo);
            } else if side > 0.0 && hi > y1 && hi - y1 <= reach {
                y1 = hi + 0.03 * (hi - y0);
            }
        }
    }
    let plot = Plot {
        x0,
        x1,
        y0,
        y1,
        x_axis: &map.axes.x,
        y_axis: &map.axes.y,
    };
    plot.open(&mut s, map.title);
    let lo = tl
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(f64::INFINITY, f64::min);
    let lo = if lo.is_finite() { lo.floor() } else { 0.0 };
    let hi = lo + RANGE_DB;
    let colour = |v: f64| {
        if v.is_finite() {
            viridis(1.0 - (v - lo) / RANGE_DB)
        } else {
            "#c8c8c8".to_string()
        }
    };
    // Crisp edges: no seams of anti-aliasing between neighbouring cells.
    let _ = writeln!(s, r#"<g class="cells" shape-rendering="crispEdges">"#);
    for (p, &v) in receivers.iter().zip(tl) {
        let c = colour(v);
        if grid {
            let (cx0, cy0) = plot.px(p.x - hx, p.y + hy);
            let (cx1, cy1) = plot.px(p.x + hx, p.y - hy);
            let _ = writeln!(
                s,
                r#"<rect x="{cx0:.2}" y="{cy0:.2}" width="{:.2}" height="{:.2}" fill="{c}" stroke="{c}" stroke-width="0.3"/>"#,
                cx1 - cx0,
                cy1 - cy0
            );
        } else {
            let (x, y) = plot.px(p.x, p.y);
            let _ = writeln!(s, r#"<circle cx="{x:.2}" cy="{y:.2}" r="4" fill="{c}"/>"#);
        }
    }
    let _ = writeln!(s, "</g>");
    let bottom = draw_scene_on_map(&mut s, &plot, scene, map.source);
    draw_colour_bar(&mut s, lo, hi);
    let missing = tl.iter().filter(|v| !v.is_finite()).count();
    let mut caption = format!(
        "{} receivers at {frequency} Hz; TL = −20 log10(|p| · 4π)",
        super::markup::thousands(receivers.len())
    );
    if missing > 0 {
        let _ = write!(caption, "; grey: {missing} that nothing reaches");
    }
    if let Some(k) = bottom {
        let _ = write!(caption, "; shaded: below {}", scene.interfaces()[k].name);
    }
    let _ = writeln!(
        s,
        r##"<text x="{LEFT}" y="{:.1}" font-size="11" fill="#555">{}</text>"##,
        HEIGHT - 12.0,
        esc(&caption)
    );
    let _ = writeln!(s, "</svg>");
    s
}

/// Draws, clipped to the plot, the bottom under `source` shaded, every interface as a line
/// (titled with its name) and the source as a star; returns the bottom's interface.
fn draw_scene_on_map(
    s: &mut String,
    plot: &Plot<'_>,
    scene: &Scene,
    source: usize,
) -> Option<usize> {
    let _ = writeln!(
        s,
        r#"<defs><clipPath id="plot-box"><rect x="{LEFT}" y="{TOP}" width="{PLOT_W}" height="{PLOT_H}"/></clipPath></defs>"#
    );
    let _ = writeln!(s, r#"<g clip-path="url(#plot-box)">"#);
    let at = scene.sources()[source];
    let bottom = bottom_below(scene, at);
    if let Some(k) = bottom {
        let vertices = scene.interfaces()[k].polyline.vertices();
        // Down to well below the plot along the polyline's two ends.
        let below = plot.y0 - (plot.y1 - plot.y0);
        let mut points: Vec<String> = vertices
            .iter()
            .map(|p| {
                let (x, y) = plot.px(p.x, p.y);
                format!("{x:.2},{y:.2}")
            })
            .collect();
        for p in [vertices[vertices.len() - 1], vertices[0]] {
            let (x, y) = plot.px(p.x, below);
            points.push(format!("{x:.2},{y:.2}"));
        }
        let _ = writeln!(
            s,
            r##"<polygon class="bottom" points="{}" fill="#b59b6d" fill-opacity="0.8" stroke="none"><title>{} (bottom)</title></polygon>"##,
            points.join(" "),
            esc(&scene.interfaces()[k].name)
        );
    }
    let _ = writeln!(
        s,
        r##"<g class="interfaces" fill="none" stroke="#333" stroke-width="1.6" stroke-linejoin="round">"##
    );
    for interface in scene.interfaces() {
        let mut points: Vec<String> = interface
            .polyline
            .vertices()
            .iter()
            .map(|p| {
                let (x, y) = plot.px(p.x, p.y);
                format!("{x:.2},{y:.2}")
            })
            .collect();
        if interface.polyline.is_closed() {
            points.push(points[0].clone());
        }
        let _ = writeln!(
            s,
            r#"<polyline points="{}"><title>{}</title></polyline>"#,
            points.join(" "),
            esc(&interface.name)
        );
    }
    let _ = writeln!(s, "</g>");
    let (x, y) = plot.px(at.x, at.y);
    let _ = writeln!(
        s,
        r##"<polygon class="source" points="{}" fill="#e4572e" stroke="#222" stroke-width="1" stroke-linejoin="round"><title>source {source}</title></polygon>"##,
        star(x, y, 9.0)
    );
    let _ = writeln!(s, "</g>");
    bottom
}

/// The colour bar of the map: `lo` (bright) at the top to `hi` at the bottom, in dB.
fn draw_colour_bar(s: &mut String, lo: f64, hi: f64) {
    let x = LEFT + PLOT_W + 30.0;
    let _ = writeln!(
        s,
        r##"<defs><linearGradient id="tl" x1="0" y1="0" x2="0" y2="1">"##
    );
    for k in 0..=8 {
        let t = f64::from(k) / 8.0;
        let _ = writeln!(
            s,
            r#"<stop offset="{t:.3}" stop-color="{}"/>"#,
            viridis(1.0 - t)
        );
    }
    let _ = writeln!(s, "</linearGradient></defs>");
    let _ = writeln!(
        s,
        r##"<rect x="{x}" y="{TOP}" width="18" height="{PLOT_H}" fill="url(#tl)" stroke="#888"/>"##
    );
    let _ = writeln!(s, r##"<g font-size="11" fill="#222">"##);
    for (v, label) in axis_ticks(lo, hi, 8.0) {
        let y = TOP + (v - lo) / (hi - lo) * PLOT_H;
        bar_tick(s, x, y, &label);
    }
    let (tx, ty) = (x + 72.0, TOP + PLOT_H / 2.0);
    let _ = writeln!(
        s,
        r##"<text x="{tx:.1}" y="{ty:.1}" text-anchor="middle" font-size="13" transform="rotate(-90 {tx:.1} {ty:.1})">transmission loss (dB)</text></g>"##
    );
}

/// The distinct values of `values`, sorted.
fn distinct(values: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

/// One tick of a colour bar whose left edge is at `x`: a mark at height `y` and its label.
fn bar_tick(s: &mut String, x: f64, y: f64, label: &str) {
    let _ = writeln!(
        s,
        r##"<path d="M{:.1},{y:.2}h5" stroke="#444"/><text x="{:.1}" y="{:.2}">{}</text>"##,
        x + 18.0,
        x + 26.0,
        y + 4.0,
        esc(label)
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use eigenray::amplitude::Complex64;

    fn echo(time: f64, amplitude: f64, order: usize) -> Echo {
        let amplitude = Complex64::new(amplitude, 0.0);
        Echo {
            source: 0,
            receiver: 0,
            time,
            amplitude,
            order,
            diffractions: 0,
            vertical_reflections: 0,
        }
    }

    /// The texts of `class`'s elements (or of every text, for `None`).
    fn texts(svg: &str, class: &str) -> Vec<(f64, f64, String)> {
        let doc = roxmltree::Document::parse(svg).unwrap();
        doc.descendants()
            .filter(|n| n.has_tag_name("text") && n.attribute("class") == Some(class))
            .map(|n| {
                let at = |a: &str| n.attribute(a).unwrap().parse::<f64>().unwrap();
                (at("x"), at("y"), n.text().unwrap_or_default().to_string())
            })
            .collect()
    }

    #[test]
    fn the_echogram_has_a_stem_per_echo_and_a_legend_per_order() {
        let echoes = [
            echo(0.01, 1.0 / (4.0 * PI), 0),
            echo(0.02, -0.5 / (4.0 * PI), 1),
            echo(0.03, 0.25 / (4.0 * PI), 2),
            echo(0.035, 1e-9, 2),
        ];
        let svg = echogram_svg("room <1>", &echoes, false);
        assert_eq!(svg.matches("<circle").count(), 4);
        for label in [
            "direct",
            "1 interaction",
            "2 interactions",
            "time (s)",
            "room &lt;1&gt;",
        ] {
            assert!(svg.contains(label), "{label}");
        }
        // 0 dB for the first, −6.0 for the second; the quiet one drawn at the floor.
        assert!(svg.contains("0.01 s, 0.0 dB") && svg.contains("0.02 s, -6.0 dB"));
    }

    /// Diffracted echoes are marked apart: a diamond each (no circle), a "diffracted" entry in
    /// the legend, their orders not among the legend's; with a colour bar, the key above it.
    #[test]
    fn the_echogram_marks_diffracted_arrivals_apart() {
        let diffracted = |time: f64, order: usize| Echo {
            diffractions: 1,
            vertical_reflections: 0,
            ..echo(time, 0.1 / (4.0 * PI), order)
        };
        let echoes = [
            echo(0.01, 1.0 / (4.0 * PI), 0),
            diffracted(0.012, 1),
            echo(0.02, 0.5 / (4.0 * PI), 2),
            diffracted(0.025, 3),
            diffracted(0.03, 1),
        ];
        let svg = echogram_svg("L room", &echoes, false);
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let marks: Vec<_> = doc
            .descendants()
            .filter(|n| n.attribute("class") == Some("diffracted"))
            .collect();
        assert_eq!(marks.len(), 3);
        assert!(
            marks
                .iter()
                .all(|n| n.attribute("fill") == Some(DIFFRACTED_COLOUR))
        );
        assert_eq!(svg.matches("<circle").count(), 2);
        assert_eq!(svg.matches(r#"class="diffracted-key""#).count(), 1);
        let legend = texts_in(&svg, "legend");
        assert_eq!(legend, ["order", "direct", "2 interactions", "diffracted"]);
        // Without diffracted echoes, no key.
        let plain = echogram_svg("room", &[echoes[0], echoes[2]], false);
        assert!(!plain.contains("diffracted"));
        // A colour bar of 31 orders, and the key above it.
        let mut many: Vec<Echo> = (0..=30)
            .map(|o| echo(0.01 + 0.001 * o as f64, 0.1 / (1.0 + o as f64), o))
            .collect();
        many.push(diffracted(0.05, 1));
        let svg = echogram_svg("room", &many, false);
        assert!(svg.contains("order-bar"));
        assert_eq!(svg.matches(r#"class="diffracted-key""#).count(), 1);
        assert_eq!(svg.matches(r#"class="diffracted""#).count(), 1);
    }

    /// Echoes off the floor or ceiling of an extruded room are marked apart: a square each in
    /// their order's colour (no circle), titled with their count, a "floor/ceiling" entry in
    /// the legend after "diffracted"; with a colour bar, the key above it; none without them.
    #[test]
    fn the_echogram_marks_floor_and_ceiling_reflections_apart() {
        let off = |time: f64, order: usize, vertical: usize| Echo {
            vertical_reflections: vertical,
            ..echo(time, 0.1 / (4.0 * PI), order)
        };
        let diffracted = Echo {
            diffractions: 1,
            ..echo(0.03, 0.1 / (4.0 * PI), 1)
        };
        let echoes = [
            echo(0.01, 1.0 / (4.0 * PI), 0),
            off(0.012, 1, 1),
            echo(0.013, 0.5 / (4.0 * PI), 1),
            off(0.02, 2, 2),
            diffracted,
        ];
        let svg = echogram_svg("extruded", &echoes, false);
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let marks: Vec<_> = doc
            .descendants()
            .filter(|n| n.attribute("class") == Some("vertical"))
            .collect();
        assert_eq!(marks.len(), 2);
        let titles: Vec<&str> = marks
            .iter()
            .map(|n| n.children().find_map(|c| c.text()).unwrap())
            .collect();
        assert!(
            titles[0].ends_with("1 interaction, 1 floor/ceiling"),
            "{titles:?}"
        );
        assert!(
            titles[1].ends_with("2 interactions, 2 floor/ceiling"),
            "{titles:?}"
        );
        let colours = OrderColours {
            orders: vec![0, 1, 2],
        };
        assert_eq!(marks[0].attribute("fill"), Some(colours.of(1).as_str()));
        assert_eq!(svg.matches("<circle").count(), 2);
        let legend = texts_in(&svg, "legend");
        assert_eq!(
            legend,
            [
                "order",
                "direct",
                "1 interaction",
                "2 interactions",
                "diffracted",
                "floor/ceiling"
            ]
        );
        let plain = echogram_svg("room", &[echoes[0], echoes[2]], false);
        assert!(!plain.contains("vertical") && !plain.contains("floor/ceiling"));
        let mut many: Vec<Echo> = (0..=30)
            .map(|o| echo(0.01 + 0.001 * o as f64, 0.1 / (1.0 + o as f64), o))
            .collect();
        many.push(off(0.05, 3, 1));
        let svg = echogram_svg("room", &many, false);
        assert!(svg.contains("order-bar"));
        assert_eq!(svg.matches(r#"class="vertical-key""#).count(), 1);
        assert_eq!(svg.matches(r#"class="vertical""#).count(), 1);
    }

    /// The texts inside the group of `class`, in order.
    fn texts_in(svg: &str, class: &str) -> Vec<String> {
        let doc = roxmltree::Document::parse(svg).unwrap();
        let group = doc
            .descendants()
            .find(|n| n.attribute("class") == Some(class))
            .unwrap();
        group
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .map(|n| n.text().unwrap_or_default().to_string())
            .collect()
    }

    /// The time axis starts just before the first arrival, or at 0 when asked: at 4 km in
    /// water the arrivals (2.667 to 3.231 s) fill the plot's width.
    #[test]
    fn the_echogram_starts_just_before_the_first_arrival() {
        let echoes = [echo(2.667, 1e-4, 0), echo(3.231, 1e-5, 3)];
        let stems = |svg: &str| -> Vec<f64> {
            let doc = roxmltree::Document::parse(svg).unwrap();
            doc.descendants()
                .filter(|n| n.has_tag_name("circle"))
                .map(|n| n.attribute("cx").unwrap().parse().unwrap())
                .collect()
        };
        let zoomed = echogram_svg("t", &echoes, false);
        let x = stems(&zoomed);
        // The first stem within the first tenth of the plot, the last within the last tenth.
        assert!(x.iter().all(|&x| x > LEFT && x < LEFT + PLOT_W), "{x:?}");
        let spread = (x[0] - x[1]).abs();
        assert!(spread > 0.85 * PLOT_W, "{x:?}");
        let first_tick: f64 = texts(&zoomed, "x-tick")[0].2.parse().unwrap();
        assert!((2.6..=2.7).contains(&first_tick), "{first_tick}");
        let from_zero = echogram_svg("t", &echoes, true);
        let x = stems(&from_zero);
        assert!((x[0] - x[1]).abs() < 0.25 * PLOT_W, "{x:?}");
        assert_eq!(texts(&from_zero, "x-tick")[0].2, "0");
        assert!(from_zero.contains("time from 0"));
    }

    /// With more orders than a legend holds, a colour bar keys them, and every order up to 40
    /// has a colour of its own: "20 interactions" is not "direct"'s colour.
    #[test]
    fn every_order_up_to_40_has_its_own_colour() {
        for top in [11usize, 20, 21, 31, 40, 60] {
            let colours = OrderColours {
                orders: (0..=top).collect(),
            };
            let all: Vec<String> = (0..=top).map(|o| colours.of(o)).collect();
            let mut unique = all.clone();
            unique.sort();
            unique.dedup();
            assert_eq!(unique.len(), all.len(), "orders 0 to {top}: {all:?}");
        }
        let echoes: Vec<Echo> = (0..=30)
            .map(|o| echo(0.01 + 0.001 * o as f64, 0.1 / (1.0 + o as f64), o))
            .collect();
        let svg = echogram_svg("room", &echoes, false);
        assert!(svg.contains(r#"class="order-bar""#) && !svg.contains(r#"class="legend""#));
        let colour_of = |label: &str| {
            let doc = roxmltree::Document::parse(&svg).unwrap();
            let stem = doc
                .descendants()
                .find(|n| {
                    n.has_tag_name("circle")
                        && n.children()
                            .any(|c| c.text().is_some_and(|t| t.ends_with(&format!(", {label}"))))
                })
                .unwrap();
            stem.attribute("fill").unwrap().to_string()
        };
        assert_ne!(colour_of("direct"), colour_of("20 interactions"));
        // A few orders: a legend, one line each.
        let svg = echogram_svg("room", &echoes[..4], false);
        assert!(svg.contains(r#"class="legend""#) && !svg.contains("order-bar"));
    }

    /// A small waveguide: a surface, a bottom sloping from 100 to 130 below it, a source at
    /// 25 below the surface, and `receivers`.
    fn waveguide(receivers: &[[f64; 2]]) -> Scene {
        let json = format!(
            r#"{{
            "media": {{ "water": {{ "speed": 1500 }} }},
            "interfaces": {{
                "surface": {{ "points": [[0, 0], [5000, 0]] }},
                "seabed": {{ "points": [[0, -100], [1500, -100], [3500, -130], [5000, -130]] }}
            }},
            "sources": [[0, -25]], "receivers": {},
            "paths": []
        }}"#,
            serde_json::to_string(receivers).unwrap()
        );
        Scene::from_json(&json).unwrap()
    }

    #[test]
    fn a_grid_of_receivers_is_drawn_as_cells_with_a_colour_bar() {
        let receivers: Vec<[f64; 2]> = (0..6)
            .map(|i| {
                [
                    1000.0 * f64::from(i % 3 + 1),
                    -10.0 - 10.0 * f64::from(i / 3),
                ]
            })
            .collect();
        let scene = waveguide(&receivers);
        let tl = [10.0, 20.0, 30.0, 40.0, f64::INFINITY, 55.0];
        let axes = Axes::default();
        let map = TlMap {
            title: "map",
            scene: &scene,
            source: 0,
            tl: &tl,
            frequency: 100.0,
            axes: &axes,
        };
        let svg = tl_map_svg(&map);
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let cells = doc
            .descendants()
            .find(|n| n.attribute("class") == Some("cells"))
            .unwrap();
        assert_eq!(cells.children().filter(|n| n.is_element()).count(), 6);
        assert!(svg.contains("transmission loss (dB)") && svg.contains("#c8c8c8"));
        assert!(svg.contains("grey: 1 that nothing reaches"));
        let scattered = waveguide(&[[0.0, 0.0], [1.0, 2.0], [3.0, 1.0]]);
        let map = TlMap {
            scene: &scattered,
            tl: &[1.0, 2.0, 3.0],
            ..map
        };
        assert_eq!(tl_map_svg(&map).matches("<circle").count(), 3);
    }

    /// The map of a waveguide in km and depth: the axes named and numbered so, the surface
    /// and the seabed drawn, the seabed shaded below, and the source as a star where it is.
    #[test]
    fn the_map_draws_the_scene_in_the_axes_it_is_given() {
        let receivers: Vec<[f64; 2]> = (1..=20)
            .flat_map(|i| (1..=10).map(move |j| [250.0 * f64::from(i), -10.0 * f64::from(j)]))
            .collect();
        let scene = waveguide(&receivers);
        let tl = vec![50.0; receivers.len()];
        let axes = Axes {
            x: "range,km,0.001".parse().unwrap(),
            y: "depth,m,-1".parse().unwrap(),
        };
        let svg = tl_map_svg(&TlMap {
            title: "waveguide",
            scene: &scene,
            source: 0,
            tl: &tl,
            frequency: 100.0,
            axes: &axes,
        });
        assert_eq!(texts(&svg, "x-title")[0].2, "range (km)");
        assert_eq!(texts(&svg, "y-title")[0].2, "depth (m)");
        // Depth numbers grow downwards; range ticks are whole km.
        let depth = texts(&svg, "y-tick");
        assert!(depth.len() >= 3, "{depth:?}");
        for w in depth.windows(2) {
            let (a, b): (f64, f64) = (w[0].2.parse().unwrap(), w[1].2.parse().unwrap());
            assert!((a < b) == (w[0].1 < w[1].1), "{depth:?}");
        }
        assert!(depth.iter().any(|t| t.2 == "100"), "{depth:?}");
        let range: Vec<String> = texts(&svg, "x-tick").into_iter().map(|t| t.2).collect();
        assert!(
            range.contains(&"1".to_string()) && range.contains(&"5".to_string()),
            "{range:?}"
        );
        let doc = roxmltree::Document::parse(&svg).unwrap();
        let titled = |name: &str| {
            doc.descendants()
                .any(|n| n.has_tag_name("polyline") && n.children().any(|c| c.text() == Some(name)))
        };
        assert!(titled("surface") && titled("seabed"));
        let bottom = doc
            .descendants()
            .find(|n| n.attribute("class") == Some("bottom"))
            .expect("the seabed shaded");
        assert!(
            bottom
                .children()
                .any(|c| c.text() == Some("seabed (bottom)"))
        );
        assert!(svg.contains("shaded: below seabed"));
        // The source (0, −25) lies left of the receivers: the map reaches out to it.
        let star = doc
            .descendants()
            .find(|n| n.attribute("class") == Some("source"))
            .unwrap();
        let corners: Vec<f64> = star
            .attribute("points")
            .unwrap()
            .split([' ', ','])
            .map(|v| v.parse().unwrap())
            .collect();
        let cx = corners.iter().step_by(2).sum::<f64>() / 10.0;
        assert!(cx > LEFT && cx < LEFT + 0.1 * PLOT_W, "{cx}");
        // Where a depth tick says 25 m, the star is.
        let cy = corners.iter().skip(1).step_by(2).sum::<f64>() / 10.0;
        let ticks = texts(&svg, "y-tick");
        let (t0, t1) = (&ticks[0], &ticks[1]);
        let (d0, d1): (f64, f64) = (t0.2.parse().unwrap(), t1.2.parse().unwrap());
        let y25 = t0.1 + (25.0 - d0) / (d1 - d0) * (t1.1 - t0.1) - 4.0;
        assert!((cy - y25).abs() < 1.5, "{cy} against {y25}");
    }

    #[test]
    fn the_bottom_is_the_first_open_interface_under_the_source() {
        let scene = waveguide(&[[10.0, -10.0]]);
        assert_eq!(
            bottom_below(&scene, Point::new(100.0, -25.0)),
            scene.interface_index("seabed")
        );
        // Above the surface, the surface is the first one below.
        assert_eq!(
            bottom_below(&scene, Point::new(100.0, 5.0)),
            scene.interface_index("surface")
        );
        // Below the seabed, or beyond its ends: none.
        assert_eq!(bottom_below(&scene, Point::new(100.0, -200.0)), None);
        assert_eq!(bottom_below(&scene, Point::new(6000.0, -25.0)), None);
    }
}
