//! Charts of what arrives: the echogram of one (source, receiver) and the transmission-loss
//! map of one source over its receivers, each an SVG with axes, units and a key.

use std::f64::consts::PI;
use std::fmt::Write as _;

use eigenray::Point;
use eigenray::response::Echo;

use super::axes::axis_ticks;
use super::colour::{PATH_COLOURS, viridis};
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

/// A plot box mapping `[x0, x1] × [y0, y1]` onto the canvas (y up).
struct Plot {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Plot {
    fn px(&self, x: f64, y: f64) -> (f64, f64) {
        (
            LEFT + (x - self.x0) / (self.x1 - self.x0) * PLOT_W,
            TOP + PLOT_H - (y - self.y0) / (self.y1 - self.y0) * PLOT_H,
        )
    }

    /// Opens the document: white canvas, title, the plot's box, grid, ticks and axis names.
    fn open(&self, s: &mut String, title: &str, x_name: &str, y_name: &str) {
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
            r##"<rect x="{LEFT}" y="{TOP}" width="{PLOT_W}" height="{PLOT_H}" fill="#fafafa" stroke="#bbb"/>"##
        );
        let _ = writeln!(
            s,
            r##"<g stroke="#e4e4e4" stroke-width="1" font-size="11" fill="#444">"##
        );
        for (v, label) in axis_ticks(self.x0, self.x1, PLOT_W / 90.0) {
            let (x, _) = self.px(v, self.y0);
            let _ = writeln!(
                s,
                r##"<path d="M{x:.2},{TOP}V{:.2}"/><path d="M{x:.2},{:.2}v5" stroke="#444"/><text x="{x:.2}" y="{:.2}" text-anchor="middle" stroke="none">{}</text>"##,
                TOP + PLOT_H,
                TOP + PLOT_H,
                TOP + PLOT_H + 17.0,
                esc(&label)
            );
        }
        for (v, label) in axis_ticks(self.y0, self.y1, PLOT_H / 55.0) {
            let (_, y) = self.px(self.x0, v);
            let _ = writeln!(
                s,
                r##"<path d="M{LEFT},{y:.2}H{:.2}"/><path d="M{LEFT},{y:.2}h-5" stroke="#444"/><text x="{:.2}" y="{:.2}" text-anchor="end" stroke="none">{}</text>"##,
                LEFT + PLOT_W,
                LEFT - 8.0,
                y + 4.0,
                esc(&label)
            );
        }
        let _ = writeln!(
            s,
            r##"<text x="{:.2}" y="{:.2}" text-anchor="middle" stroke="none" font-size="13" fill="#222">{}</text>"##,
            LEFT + PLOT_W / 2.0,
            TOP + PLOT_H + 40.0,
            esc(x_name)
        );
        let (yx, yy) = (LEFT - 58.0, TOP + PLOT_H / 2.0);
        let _ = writeln!(
            s,
            r##"<text x="{yx:.2}" y="{yy:.2}" text-anchor="middle" stroke="none" font-size="13" fill="#222" transform="rotate(-90 {yx:.2} {yy:.2})">{}</text>"##,
            esc(y_name)
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

/// The echogram of `echoes` (one pair's): a stem per echo at its time, up to its level in dB
/// re 1 unit of length of free field (from [`RANGE_DB`] below the loudest), coloured by its
/// order, with a legend of the orders; `title` above.
pub fn echogram_svg(title: &str, echoes: &[Echo]) -> String {
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
    let t_max = echoes.iter().map(|e| e.time).fold(0.0, f64::max);
    let plot = Plot {
        x0: 0.0,
        x1: if t_max > 0.0 { t_max * 1.05 } else { 1.0 },
        y0: floor,
        y1: top,
    };
    plot.open(
        &mut s,
        title,
        "time (s)",
        "level (dB re free field at 1 unit of length)",
    );
    let mut orders: Vec<usize> = echoes.iter().map(|e| e.order).collect();
    orders.sort_unstable();
    orders.dedup();
    let colour = |order: usize| {
        let i = orders.binary_search(&order).unwrap_or(0);
        PATH_COLOURS[i % PATH_COLOURS.len()]
    };
    // The quietest first, so that the loud ones are on top.
    let mut by_level: Vec<usize> = (0..echoes.len()).collect();
    by_level.sort_by(|&a, &b| levels[a].total_cmp(&levels[b]));
    let _ = writeln!(s, r#"<g stroke-width="1.6">"#);
    for i in by_level {
        let e = &echoes[i];
        let level = levels[i].max(floor);
        let (x, y) = plot.px(e.time, level);
        let (_, y0) = plot.px(e.time, floor);
        let c = colour(e.order);
        let _ = writeln!(
            s,
            r##"<path d="M{x:.2},{y0:.2}V{y:.2}" stroke="{c}"/><circle cx="{x:.2}" cy="{y:.2}" r="2.4" fill="{c}" stroke="none"><title>{} s, {:.1} dB, {}</title></circle>"##,
            e.time,
            levels[i],
            order_label(e.order)
        );
    }
    let _ = writeln!(s, "</g>");
    // The legend, right of the plot.
    let x = LEFT + PLOT_W + 22.0;
    let _ = writeln!(
        s,
        r##"<g font-size="12" fill="#222"><text x="{x}" y="{}" font-weight="bold">order</text>"##,
        TOP + 10.0
    );
    for (k, &order) in orders.iter().take(24).enumerate() {
        let y = TOP + 30.0 + 17.0 * k as f64;
        let _ = writeln!(
            s,
            r##"<rect x="{x}" y="{:.1}" width="12" height="12" fill="{}"/><text x="{:.1}" y="{:.1}">{}</text>"##,
            y - 10.0,
            colour(order),
            x + 18.0,
            y,
            order_label(order)
        );
    }
    if orders.len() > 24 {
        let _ = writeln!(
            s,
            r#"<text x="{x}" y="{:.1}">… {} orders in all</text>"#,
            TOP + 30.0 + 17.0 * 24.0,
            orders.len()
        );
    }
    let caption = format!(
        "{} arrivals; stems start {RANGE_DB:.0} dB below the loudest",
        echoes.len()
    );
    let _ = writeln!(
        s,
        r##"<text x="{LEFT}" y="{:.1}" font-size="11" fill="#555">{}</text></g>"##,
        HEIGHT - 12.0,
        esc(&caption)
    );
    let _ = writeln!(s, "</svg>");
    s
}

/// The transmission-loss map of one source: each receiver's loss in dB (`tl`, in the order
/// of `receivers`) as a cell of a grid when the receivers form one (every pair of their
/// distinct x and y), else as a dot; on reversed viridis over [`RANGE_DB`] from the lowest
/// loss (loud is bright), with a colour bar; receivers nothing reaches in grey.
pub fn tl_map_svg(title: &str, receivers: &[Point], tl: &[f64], frequency: f64) -> String {
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
    let plot = Plot {
        x0: xs.first().copied().unwrap_or(0.0) - hx,
        x1: xs.last().copied().unwrap_or(1.0) + hx,
        y0: ys.first().copied().unwrap_or(0.0) - hy,
        y1: ys.last().copied().unwrap_or(1.0) + hy,
    };
    plot.open(&mut s, title, "x (range)", "y (height)");
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
    let _ = writeln!(s, r#"<g shape-rendering="crispEdges">"#);
    for (p, &v) in receivers.iter().zip(tl) {
        let c = colour(v);
        if grid {
            let (x0, y0) = plot.px(p.x - hx, p.y + hy);
            let (x1, y1) = plot.px(p.x + hx, p.y - hy);
            let _ = writeln!(
                s,
                r#"<rect x="{x0:.2}" y="{y0:.2}" width="{:.2}" height="{:.2}" fill="{c}" stroke="{c}" stroke-width="0.3"/>"#,
                x1 - x0,
                y1 - y0
            );
        } else {
            let (x, y) = plot.px(p.x, p.y);
            let _ = writeln!(s, r#"<circle cx="{x:.2}" cy="{y:.2}" r="4" fill="{c}"/>"#);
        }
    }
    let _ = writeln!(s, "</g>");
    draw_colour_bar(&mut s, lo, hi);
    let missing = tl.iter().filter(|v| !v.is_finite()).count();
    let caption = format!(
        "{} receivers at {frequency} Hz; TL = −20 log10(|p| · 4π){}",
        receivers.len(),
        if missing > 0 {
            format!("; grey: {missing} that nothing reaches")
        } else {
            String::new()
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
        let _ = writeln!(
            s,
            r##"<path d="M{:.1},{y:.2}h5" stroke="#444"/><text x="{:.1}" y="{:.2}">{}</text>"##,
            x + 18.0,
            x + 26.0,
            y + 4.0,
            esc(&label)
        );
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

#[cfg(test)]
mod tests {
    use super::*;
    use eigenray::amplitudes::Complex64;

    fn echo(time: f64, amplitude: f64, order: usize) -> Echo {
        let amplitude = Complex64::new(amplitude, 0.0);
        Echo {
            source: 0,
            receiver: 0,
            time,
            amplitude,
            order,
        }
    }

    #[test]
    fn the_echogram_has_a_stem_per_echo_and_a_legend_per_order() {
        let echoes = [
            echo(0.01, 1.0 / (4.0 * PI), 0),
            echo(0.02, -0.5 / (4.0 * PI), 1),
            echo(0.03, 0.25 / (4.0 * PI), 2),
            echo(0.035, 1e-9, 2),
        ];
        let svg = echogram_svg("room <1>", &echoes);
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

    #[test]
    fn a_grid_of_receivers_is_drawn_as_cells_with_a_colour_bar() {
        let receivers: Vec<Point> = (0..6)
            .map(|i| Point::new(f64::from(i % 3), -f64::from(i / 3)))
            .collect();
        let tl = [10.0, 20.0, 30.0, 40.0, f64::INFINITY, 55.0];
        let svg = tl_map_svg("map", &receivers, &tl, 100.0);
        assert_eq!(svg.matches("<rect x=").count(), 6 + 2); // cells, plot box, colour bar
        assert!(svg.contains("transmission loss (dB)") && svg.contains("#c8c8c8"));
        assert!(svg.contains("grey: 1 that nothing reaches"));
        let scattered = [
            Point::new(0.0, 0.0),
            Point::new(1.0, 2.0),
            Point::new(3.0, 1.0),
        ];
        let svg = tl_map_svg("dots", &scattered, &[1.0, 2.0, 3.0], 100.0);
        assert_eq!(svg.matches("<circle").count(), 3);
    }
}
