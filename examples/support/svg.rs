//! What the layout examples (`locate_source`, `place_reflector`, `shape_lens`) share for their
//! before-and-after pictures: a white SVG canvas over a box of the scene, y up.

use eigenray::Point;

/// The box `x0..x1 × y0..y1` of the scene drawn at `sx`, `sy` pixels per unit, with `below`
/// pixels of room under it.
pub struct Canvas {
    x0: f64,
    y1: f64,
    sx: f64,
    sy: f64,
    width: f64,
    height: f64,
}

impl Canvas {
    pub fn new([x0, x1]: [f64; 2], [y0, y1]: [f64; 2], [sx, sy]: [f64; 2], below: f64) -> Canvas {
        Canvas {
            x0,
            y1,
            sx,
            sy,
            width: (x1 - x0) * sx,
            height: (y1 - y0) * sy + below,
        }
    }

    /// The opening of the document: the `<svg>` element and a white background.
    pub fn header(&self) -> String {
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" \
             font-family=\"sans-serif\" font-size=\"14\">\n\
             <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
            self.width, self.height
        )
    }

    /// Pixel coordinates of a scene point.
    pub fn px(&self, p: Point) -> (f64, f64) {
        ((p.x - self.x0) * self.sx, (self.y1 - p.y) * self.sy)
    }

    /// A `<polyline>` through scene points, with SVG attributes `style`.
    pub fn polyline(&self, points: &[Point], style: &str) -> String {
        polyline_through(points.iter().map(|&p| self.px(p)), style)
    }
}

/// A `<polyline>` through pixel coordinates, with SVG attributes `style`.
pub fn polyline_through(pixels: impl Iterator<Item = (f64, f64)>, style: &str) -> String {
    let coords: Vec<String> = pixels.map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
    format!(
        "<polyline points=\"{}\" fill=\"none\" {style}/>\n",
        coords.join(" ")
    )
}
