//! The axes: their names and units, round ticks with labels that tell them apart, and their
//! drawing along the plot.

use std::fmt::Write as _;
use std::str::FromStr;

use eigenray::Point;

use super::layout::Frame;
use super::markup::esc;

/// How one axis of a picture is named and numbered: its name, its unit, and the scale from the
/// scene's coordinates to the numbers on its ticks. A negative scale numbers the axis the other
/// way round: `depth,m,-1` numbers y = −80 as 80 (depth positive down), the picture unchanged.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisSpec {
    /// What the axis shows (`range`, `depth`).
    pub name: String,
    /// Its unit (`km`), if named.
    pub unit: Option<String>,
    /// Tick number = scale × coordinate; finite and not zero.
    pub scale: f64,
}

impl AxisSpec {
    /// An axis named `name`, without a unit, numbered in the scene's coordinates.
    pub fn plain(name: &str) -> AxisSpec {
        AxisSpec {
            name: name.to_string(),
            unit: None,
            scale: 1.0,
        }
    }

    /// The axis's title: `range (km)`, or the name alone.
    pub fn title(&self) -> String {
        match &self.unit {
            Some(unit) => format!("{} ({unit})", self.name),
            None => self.name.clone(),
        }
    }

    /// Ticks at round numbers of this axis over the coordinates `[lo, hi]`: each as its
    /// coordinate and its label (the number scale × coordinate), about `target` of them.
    pub fn ticks(&self, lo: f64, hi: f64, target: f64) -> Vec<(f64, String)> {
        let (a, b) = (self.scale * lo, self.scale * hi);
        axis_ticks(a.min(b), a.max(b), target)
            .into_iter()
            .map(|(number, label)| (number / self.scale, label))
            .collect()
    }
}

impl FromStr for AxisSpec {
    type Err = String;

    /// `NAME`, `NAME,UNIT` or `NAME,UNIT,SCALE` (an empty unit is none): `range,km,0.001`,
    /// `depth,m,-1`.
    fn from_str(text: &str) -> Result<AxisSpec, String> {
        let mut parts = text.split(',');
        let name = parts.next().unwrap_or_default().trim();
        if name.is_empty() {
            return Err("give NAME[,UNIT[,SCALE]], for example range,km,0.001".into());
        }
        let unit = parts
            .next()
            .map(str::trim)
            .filter(|u| !u.is_empty())
            .map(str::to_string);
        let scale = match parts.next() {
            None => 1.0,
            Some(s) => {
                let scale: f64 = s.trim().parse().map_err(|_| {
                    format!("SCALE `{}` is not a number (NAME[,UNIT[,SCALE]])", s.trim())
                })?;
                if !scale.is_finite() || scale == 0.0 {
                    return Err(format!(
                        "SCALE must be a finite number other than 0, not {scale}"
                    ));
                }
                scale
            }
        };
        if parts.next().is_some() {
            return Err("at most three parts: NAME[,UNIT[,SCALE]]".into());
        }
        Ok(AxisSpec {
            name: name.to_string(),
            unit,
            scale,
        })
    }
}

/// The names, units and scales of a picture's two axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Axes {
    /// The horizontal axis.
    pub x: AxisSpec,
    /// The vertical axis.
    pub y: AxisSpec,
}

impl Default for Axes {
    /// `x` and `y`, in the scene's coordinates.
    fn default() -> Axes {
        Axes {
            x: AxisSpec::plain("x"),
            y: AxisSpec::plain("y"),
        }
    }
}

/// A tick label: enough decimals to tell `lo` from `hi` apart.
pub(super) fn tick_label(v: f64, span: f64) -> String {
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

/// Ticks at a round step (1, 2 or 5 × 10ⁿ) within `[lo, hi]`, about `target` of them, with
/// labels that differ by that step; empty when the range is not finite.
pub(super) fn axis_ticks(lo: f64, hi: f64, target: f64) -> Vec<(f64, String)> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0 && lo.is_finite() && hi.is_finite()) {
        return Vec::new();
    }
    let raw = span / target;
    let mag = 10f64.powf(raw.log10().floor());
    if !(mag.is_finite() && mag > 0.0) {
        return Vec::new();
    }
    let f = raw / mag;
    let step = mag
        * if f <= 1.0 {
            1.0
        } else if f <= 2.0 {
            2.0
        } else if f <= 5.0 {
            5.0
        } else {
            10.0
        };
    let first = (lo / step).ceil();
    let last = (hi / step).floor();
    if !(first.is_finite() && last.is_finite()) || last - first > 40.0 {
        return Vec::new();
    }
    let exponent = step.log10().floor();
    let largest = lo.abs().max(hi.abs());
    let label = |v: f64| -> String {
        if v == 0.0 {
            "0".into()
        } else if (1e-4..1e6).contains(&largest) && (-6.0..=6.0).contains(&exponent) {
            let decimals = (-exponent).max(0.0) as usize;
            let s = format!("{v:.decimals$}");
            if s.trim_start_matches('-')
                .chars()
                .all(|c| c == '0' || c == '.')
            {
                "0".into()
            } else {
                s
            }
        } else {
            // Scientific, with the digits the step needs.
            let digits = (largest.log10().floor() - exponent).clamp(0.0, 12.0) as usize;
            format!("{v:.digits$e}")
        }
    };
    let mut ticks = Vec::new();
    let mut k = first;
    while k <= last {
        let v = k * step;
        ticks.push((v, label(v)));
        k += 1.0;
    }
    ticks
}

/// Draws the axes of `frame`: ticks, grid lines and coordinates along the plot's left and
/// bottom edges, and the axes' names.
pub(super) fn draw_axes(s: &mut String, frame: &Frame, axes: &Axes) {
    let view = &frame.view;
    let (centre, hw, hh) = (view.c, view.hw, view.hh);
    let xt = axes
        .x
        .ticks(centre.x - hw, centre.x + hw, frame.plot_w / 90.0);
    let yt = axes
        .y
        .ticks(centre.y - hh, centre.y + hh, frame.plot_h / 60.0);
    let _ = writeln!(
        s,
        r##"<g class="axes" stroke="#e4e4e4" stroke-width="1" font-size="11" fill="#444">"##
    );
    for (v, label) in &xt {
        let (x, _) = view.px(Point::new(*v, centre.y));
        let _ = writeln!(
            s,
            r##"<path d="M{x:.2},{:.2}V{:.2}"/><path d="M{x:.2},{:.2}v5" stroke="#444"/><text x="{x:.2}" y="{:.2}" text-anchor="middle" stroke="none">{}</text>"##,
            view.top(),
            view.bottom(),
            view.bottom(),
            view.bottom() + 17.0,
            esc(label)
        );
    }
    for (v, label) in &yt {
        let (_, y) = view.px(Point::new(centre.x, *v));
        let _ = writeln!(
            s,
            r##"<path d="M{:.2},{y:.2}H{:.2}"/><path d="M{:.2},{y:.2}h-5" stroke="#444"/><text x="{:.2}" y="{:.2}" text-anchor="end" stroke="none">{}</text>"##,
            view.left(),
            view.right(),
            view.left(),
            view.left() - 8.0,
            y + 4.0,
            esc(label)
        );
    }
    let (yx, yy) = (view.left() - 62.0, view.pc.1);
    let _ = writeln!(
        s,
        r##"<text class="x-title" x="{:.2}" y="{:.2}" text-anchor="middle" stroke="none" font-size="12">{}</text><text class="y-title" x="{yx:.2}" y="{yy:.2}" text-anchor="middle" stroke="none" font-size="12" transform="rotate(-90 {yx:.2} {yy:.2})">{}</text>"##,
        view.pc.0,
        view.bottom() + 36.0,
        esc(&axes.x.title()),
        esc(&axes.y.title())
    );
    let _ = writeln!(s, "</g>");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_separate_the_range() {
        assert_eq!(tick_label(1.8912, 0.81), "1.8912");
        assert_eq!(tick_label(1234.5, 100.0), "1234.5");
        assert_eq!(tick_label(2.5e7, 1.0), "2.500e7");
    }

    #[test]
    fn axis_specs_parse_and_number_their_ticks() {
        let km: AxisSpec = "range,km,0.001".parse().unwrap();
        assert_eq!(km.title(), "range (km)");
        let ticks = km.ticks(0.0, 5000.0, 5.0);
        let labels: Vec<&str> = ticks.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(labels, ["0", "1", "2", "3", "4", "5"]);
        assert!((ticks[3].0 - 3000.0).abs() < 1e-9);
        let depth: AxisSpec = "depth,m,-1".parse().unwrap();
        let ticks = depth.ticks(-120.0, 0.0, 6.0);
        assert!(ticks.contains(&(-100.0, "100".to_string())), "{ticks:?}");
        assert!(ticks.iter().all(|(v, l)| l.parse::<f64>().unwrap() == -v));
        assert_eq!("y".parse::<AxisSpec>().unwrap(), AxisSpec::plain("y"));
        assert_eq!("h,,2".parse::<AxisSpec>().unwrap().unit, None);
        for bad in ["", ",m", "r,km,0", "r,km,x", "r,km,inf", "r,km,1,2"] {
            assert!(bad.parse::<AxisSpec>().is_err(), "{bad}");
        }
    }

    #[test]
    fn axis_ticks_are_round() {
        let t: Vec<String> = axis_ticks(-1.3, 2.2, 6.0)
            .into_iter()
            .map(|t| t.1)
            .collect();
        assert_eq!(t, ["-1", "0", "1", "2"]);
        let t: Vec<String> = axis_ticks(-0.3, 0.45, 6.0)
            .into_iter()
            .map(|t| t.1)
            .collect();
        assert_eq!(t, ["-0.2", "0", "0.2", "0.4"]);
        let t: Vec<String> = axis_ticks(0.0, 1000.0, 5.0)
            .into_iter()
            .map(|t| t.1)
            .collect();
        assert_eq!(t, ["0", "200", "400", "600", "800", "1000"]);
        assert!(axis_ticks(0.0, f64::INFINITY, 5.0).is_empty());
        let tiny = axis_ticks(-2e-310, 2e-310, 4.0);
        let labels: Vec<&str> = tiny.iter().map(|t| t.1.as_str()).collect();
        assert_eq!(labels, ["-2e-310", "-1e-310", "0", "1e-310", "2e-310"]);
    }
}
