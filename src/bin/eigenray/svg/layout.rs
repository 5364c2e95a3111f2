//! Where the picture's parts go: the world shown (the scene and its rays, with a margin), the
//! stretch of a flat or tall one, the plot's size, the canvas around it and the world → pixel
//! map.

use std::fmt::Write as _;

use eigenray::geom::Aabb;
use eigenray::{Point, Scene};

use super::colour::Colouring;
use super::entries::Item;
use super::legend::{LEGEND_CHAR_W, LEGEND_LINE, Legend};

/// Largest plot's width, in pixels.
const PLOT_MAX_W: f64 = 820.0;
/// Largest plot's height, in pixels.
const PLOT_MAX_H: f64 = 620.0;
/// A plot is never flatter (or narrower) than this: beyond it one axis is stretched, and the
/// caption gives the factor.
pub(super) const MAX_ASPECT: f64 = 3.0;
/// Smallest plot area's width (the colour bar and the title need room even for a small scene).
const AREA_MIN_W: f64 = 460.0;
/// Smallest plot area's height.
const AREA_MIN_H: f64 = 300.0;
/// Room left of the plot for the y axis's labels.
pub(super) const LEFT: f64 = 78.0;
/// Room for the title and the caption.
pub(super) const TOP: f64 = 66.0;
/// Room below the plot for the x axis's labels.
const BOTTOM: f64 = 48.0;
/// Room right of the plot for the colour bar and its labels.
const BAR_AREA: f64 = 170.0;

/// World → pixel map, y up. Positions are taken relative to the centre and divided by the half
/// extents (never multiplied by a scale), so that tiny or huge scenes stay finite.
pub(super) struct View {
    /// World centre.
    pub(super) c: Point,
    /// World half width shown.
    pub(super) hw: f64,
    /// World half height shown.
    pub(super) hh: f64,
    /// Pixel centre of the plot.
    pub(super) pc: (f64, f64),
    /// Pixel half sizes of the plot.
    half: (f64, f64),
}

impl View {
    /// The pixel of world point `p`.
    pub(super) fn px(&self, p: Point) -> (f64, f64) {
        (
            self.pc.0 + (p.x - self.c.x) / self.hw * self.half.0,
            self.pc.1 - (p.y - self.c.y) / self.hh * self.half.1,
        )
    }
    /// `x,y x,y …` for a `points` attribute.
    pub(super) fn points(&self, pts: &[Point]) -> String {
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
    /// [`points`](Self::points) to 6 decimals (sampled arcs, which are checked against
    /// their circles).
    pub(super) fn points_fine(&self, pts: &[Point]) -> String {
        let mut s = String::with_capacity(pts.len() * 24);
        for (k, p) in pts.iter().enumerate() {
            let (x, y) = self.px(*p);
            if k > 0 {
                s.push(' ');
            }
            let _ = write!(s, "{x:.6},{y:.6}");
        }
        s
    }
    /// The plot's left edge, in pixels.
    pub(super) fn left(&self) -> f64 {
        self.pc.0 - self.half.0
    }
    /// The plot's top edge, in pixels.
    pub(super) fn top(&self) -> f64 {
        self.pc.1 - self.half.1
    }
    /// The plot's right edge, in pixels.
    pub(super) fn right(&self) -> f64 {
        self.pc.0 + self.half.0
    }
    /// The plot's bottom edge, in pixels.
    pub(super) fn bottom(&self) -> f64 {
        self.pc.1 + self.half.1
    }
}

/// The world to show: centre and half extents holding the scene and the drawn rays, never
/// degenerate, with a margin.
struct World {
    /// The centre.
    centre: Point,
    /// Half the width.
    half_w: f64,
    /// Half the height.
    half_h: f64,
    /// The margin around it (the same along both axes before a stretch).
    pad: f64,
}

/// The world holding `scene` and the drawn `rays` (arcs and all); computed in halves so that huge coordinates
/// do not overflow.
fn world(scene: &Scene, rays: &[Item]) -> World {
    let mut b = scene.bbox();
    for r in rays {
        // (Curved legs as drawn: they may bulge past their ends.)
        for p in r.curve.as_deref().unwrap_or(&r.points) {
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
        // A single point: a box of its own magnitude (or 1 at the origin).
        let m = c.x.abs().max(c.y.abs()).min(limit);
        if m > 0.0 { m } else { 1.0 }
    };
    World {
        centre: c,
        half_w: hw.max(0.05 * ext),
        half_h: hh.max(0.05 * ext),
        pad: 0.08 * ext,
    }
}

/// One axis stretched so that a flat (or tall) scene's plot stays readable: its scale is
/// `factor` times the other's.
#[derive(Clone, Copy)]
pub(super) struct Stretch {
    /// `vertical` or `horizontal`.
    pub(super) axis: &'static str,
    /// How many times the other axis's scale.
    pub(super) factor: f64,
}

/// The plot: the world's half extents it shows, its size in pixels and its stretch.
struct Plot {
    /// World half width shown.
    hw: f64,
    /// World half height shown.
    hh: f64,
    /// Width in pixels.
    w: f64,
    /// Height in pixels.
    h: f64,
    /// The stretched axis, if any.
    stretch: Option<Stretch>,
}

impl Plot {
    /// The plot of `world`, within [`PLOT_MAX_W`] × [`PLOT_MAX_H`] and never flatter (or
    /// narrower) than [`MAX_ASPECT`].
    fn of(world: &World) -> Plot {
        let (rw, rh, pad) = (world.half_w, world.half_h, world.pad);
        // Stretch the short axis of a flat (or tall) scene so that the plot stays readable:
        // its scale becomes `factor` times the other's. The margin around the scene is the
        // same on every side on the screen, so it is `pad / factor` in the world along the
        // stretched axis.
        let mut stretch = None;
        let (mut fx, mut fy) = (1.0, 1.0);
        if rw > MAX_ASPECT * rh {
            fy = rw / (MAX_ASPECT * rh);
            stretch = Some(Stretch {
                axis: "vertical",
                factor: fy,
            });
        } else if rh > MAX_ASPECT * rw {
            fx = rh / (MAX_ASPECT * rw);
            stretch = Some(Stretch {
                axis: "horizontal",
                factor: fx,
            });
        }
        // The half extents shown, in the world and on the screen (in the world's units of the
        // unstretched axis).
        let (hw, hh) = (rw + pad / fx, rh + pad / fy);
        let (sw, sh) = (hw * fx, hh * fy);
        let (plot_w, plot_h) = if sw >= sh {
            (PLOT_MAX_W, (PLOT_MAX_W * (sh / sw)).min(PLOT_MAX_H))
        } else {
            ((PLOT_MAX_H * (sw / sh)).min(PLOT_MAX_W), PLOT_MAX_H)
        };
        // Both fit within the maxima.
        let fit = (PLOT_MAX_W / plot_w).min(PLOT_MAX_H / plot_h).min(1.0);
        Plot {
            hw,
            hh,
            w: plot_w * fit,
            h: plot_h * fit,
            stretch,
        }
    }
}

/// The room the key beside the plot needs: the colour bar's, or the legend's lines.
struct KeySize {
    /// Width right of the plot area.
    w: f64,
    /// Height (0 for the colour bar, which takes the plot area's).
    h: f64,
}

impl KeySize {
    /// The room of `legend` under `colouring`.
    fn of(legend: &Legend, colouring: Colouring) -> KeySize {
        let h = match colouring {
            Colouring::Path | Colouring::Sequence => 40.0 + LEGEND_LINE * legend.rows() as f64,
            Colouring::Time => 0.0,
        };
        // The legend's rows start 20 px right of its left edge, which is 26 px right of the
        // plot area; 16 px to spare at the canvas's right edge.
        let w = match colouring {
            Colouring::Time => BAR_AREA,
            Colouring::Path | Colouring::Sequence => {
                (62.0 + LEGEND_CHAR_W * legend.widest_row() as f64).max(BAR_AREA)
            }
        };
        KeySize { w, h }
    }
}

/// The picture's geometry: the canvas, the plot area within it and the plot's world → pixel
/// map.
pub(super) struct Frame {
    /// The world → pixel map of the plot.
    pub(super) view: View,
    /// The plot's width in pixels.
    pub(super) plot_w: f64,
    /// The plot's height in pixels.
    pub(super) plot_h: f64,
    /// The plot area's width (at least [`AREA_MIN_W`]), the plot centred in it.
    pub(super) area_w: f64,
    /// The plot area's height (at least [`AREA_MIN_H`] and the legend's).
    pub(super) area_h: f64,
    /// The canvas's width.
    pub(super) width: f64,
    /// The canvas's height.
    pub(super) height: f64,
    /// The stretched axis, if any.
    pub(super) stretch: Option<Stretch>,
}

impl Frame {
    /// The frame of a picture of `scene` and its drawn `rays`, keyed by `legend` under
    /// `colouring`.
    pub(super) fn new(
        scene: &Scene,
        rays: &[Item],
        legend: &Legend,
        colouring: Colouring,
    ) -> Frame {
        let world = world(scene, rays);
        let plot = Plot::of(&world);
        let key = KeySize::of(legend, colouring);
        let (area_w, area_h) = (plot.w.max(AREA_MIN_W), plot.h.max(AREA_MIN_H).max(key.h));
        let (width, height) = (LEFT + area_w + key.w, TOP + area_h + BOTTOM);
        let view = View {
            c: world.centre,
            hw: plot.hw,
            hh: plot.hh,
            pc: (LEFT + 0.5 * area_w, TOP + 0.5 * area_h),
            half: (0.5 * plot.w, 0.5 * plot.h),
        };
        Frame {
            view,
            plot_w: plot.w,
            plot_h: plot.h,
            area_w,
            area_h,
            width,
            height,
            stretch: plot.stretch,
        }
    }
}
