//! The key beside the plot: the travel-time colour bar, or the legend of paths or sequences.

use std::fmt::Write as _;

use super::axes::tick_label;
use super::colour::{Colouring, PATH_COLOURS, VIRIDIS, path_dash, viridis};
use super::legend::{LEGEND_LINE, Legend, rest_line};
use super::markup::esc;

/// Draws the key of `colouring` with its left edge at `x` and its top at `top`: the colour bar
/// of `range` (as tall as the plot area, `area_h`) or the `legend`.
pub(super) fn draw_key(
    s: &mut String,
    x: f64,
    top: f64,
    area_h: f64,
    colouring: Colouring,
    range: Option<(f64, f64)>,
    legend: &Legend,
) {
    match colouring {
        Colouring::Time => colour_bar(s, x, top, area_h, range),
        Colouring::Path | Colouring::Sequence => path_legend(s, x, top, legend),
    }
}

/// The travel-time colour bar: min at the bottom, max at the top, in the scene's time unit.
fn colour_bar(s: &mut String, x: f64, top: f64, area_h: f64, range: Option<(f64, f64)>) {
    let (bar_top, bar_bottom) = (top + 40.0, top + area_h - 6.0);
    let _ = writeln!(
        s,
        r##"<g class="colour-bar"><text x="{:.2}" y="{:.2}" font-size="12" fill="#222">travel time</text><text x="{:.2}" y="{:.2}" font-size="11" fill="#555">(length ÷ speed)</text>"##,
        x - 8.0,
        top + 10.0,
        x - 8.0,
        top + 26.0
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
                r##"<rect x="{x:.2}" y="{bar_top:.2}" width="16" height="{:.2}" fill="{fill}" stroke="#444" stroke-width="0.8"/>"##,
                bar_bottom - bar_top
            );
            let span = hi - lo;
            let ticks: &[f64] = if hi > lo {
                &[0.0, 0.25, 0.5, 0.75, 1.0]
            } else {
                &[0.5]
            };
            for &f in ticks {
                let y = bar_bottom - f * (bar_bottom - bar_top);
                let v = if hi > lo { lo + f * span } else { lo };
                let _ = writeln!(
                    s,
                    r##"<path d="M{:.2},{y:.2}h5" stroke="#444" stroke-width="1"/><text x="{:.2}" y="{:.2}" font-size="12" fill="#222">{}</text>"##,
                    x + 16.0,
                    x + 24.0,
                    y + 4.0,
                    tick_label(v, span)
                );
            }
        }
        None => {
            let _ = writeln!(
                s,
                r##"<text x="{:.2}" y="{:.2}" font-size="12" fill="#555">no ray has a time</text>"##,
                x - 8.0,
                bar_top + 14.0
            );
        }
    }
    let _ = writeln!(s, "</g>");
}

/// The legend of paths or sequences: a line of each drawn one's colour, its name and its drawn
/// rays (past [`MAX_LEGEND_LINES`], a last line counts the rest).
fn path_legend(s: &mut String, x: f64, top: f64, legend: &Legend) {
    let _ = writeln!(
        s,
        r##"<g class="legend" font-size="12" fill="#222"><text x="{:.2}" y="{:.2}">{}</text>"##,
        x - 8.0,
        top + 10.0,
        legend.heading
    );
    if legend.entries.is_empty() {
        let _ = writeln!(
            s,
            r##"<text x="{:.2}" y="{:.2}" fill="#555">no ray has a time</text>"##,
            x - 8.0,
            top + 30.0
        );
    }
    let shown = legend.shown();
    let mut row = 0;
    for e in &legend.entries[..shown] {
        let y = top + 32.0 + LEGEND_LINE * row as f64;
        let _ = writeln!(
            s,
            r#"<path d="M{:.2},{:.2}h22" stroke="{}" stroke-width="3"{}/>"#,
            x - 8.0,
            y - 4.0,
            PATH_COLOURS[e.colour % PATH_COLOURS.len()],
            path_dash(e.colour),
        );
        for text in e.rows() {
            let y = top + 32.0 + LEGEND_LINE * row as f64;
            let _ = writeln!(
                s,
                r#"<text x="{:.2}" y="{y:.2}">{}</text>"#,
                x + 20.0,
                esc(&text)
            );
            row += 1;
        }
    }
    if shown < legend.entries.len() {
        let rest = &legend.entries[shown..];
        let drawn: usize = rest.iter().map(|e| e.count).sum();
        let y = top + 32.0 + LEGEND_LINE * row as f64;
        let _ = writeln!(
            s,
            r##"<text x="{:.2}" y="{y:.2}" fill="#555">{}</text>"##,
            x - 8.0,
            rest_line(rest.len(), drawn)
        );
    }
    let _ = writeln!(s, "</g>");
}
