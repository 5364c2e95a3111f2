//! The marks of sources and receivers: which receivers are shown (past [`MAX_RECEIVERS`],
//! those of the drawn rays), dots for them and stars for the sources.

use std::fmt::Write as _;

use eigenray::Scene;

use super::entries::Item;
use super::layout::View;

/// At most this many receivers are drawn (beyond it, those of the drawn rays).
const MAX_RECEIVERS: usize = 2_000;

/// The receivers a picture shows.
pub(super) struct ShownReceivers {
    /// Their indices, ascending.
    pub(super) indices: Vec<usize>,
    /// The scene's receivers.
    pub(super) total: usize,
    /// Whether some are left out (past [`MAX_RECEIVERS`], only those of the drawn rays).
    pub(super) thinned: bool,
}

impl ShownReceivers {
    /// The receivers of `scene` shown with the drawn `rays`: every one, or past
    /// [`MAX_RECEIVERS`] those of the rays (at most [`MAX_RECEIVERS`] of them).
    pub(super) fn of(scene: &Scene, rays: &[Item]) -> ShownReceivers {
        let nr = scene.receivers().len();
        if nr <= MAX_RECEIVERS {
            return ShownReceivers {
                indices: (0..nr).collect(),
                total: nr,
                thinned: false,
            };
        }
        let mut seen: Vec<usize> = rays.iter().map(|r| r.receiver).collect();
        seen.sort_unstable();
        seen.dedup();
        seen.truncate(MAX_RECEIVERS);
        ShownReceivers {
            indices: seen,
            total: nr,
            thinned: true,
        }
    }
}

/// Draws the shown receivers as dots, smaller the more there are.
pub(super) fn draw_receivers(s: &mut String, scene: &Scene, view: &View, shown: &ShownReceivers) {
    let radius = match shown.indices.len() {
        0..=100 => 3.0,
        101..=600 => 1.8,
        _ => 1.2,
    };
    let _ = writeln!(
        s,
        r##"<g class="receivers" fill="#111" stroke="white" stroke-width="{:.2}">"##,
        radius * 0.3
    );
    for &k in &shown.indices {
        let (x, y) = view.px(scene.receivers()[k]);
        let _ = writeln!(
            s,
            r#"<circle cx="{x:.2}" cy="{y:.2}" r="{radius}"><title>receiver {k}</title></circle>"#
        );
    }
    let _ = writeln!(s, "</g>");
}

/// Draws the sources as stars.
pub(super) fn draw_sources(s: &mut String, scene: &Scene, view: &View) {
    let _ = writeln!(
        s,
        r##"<g class="sources" fill="#e4572e" stroke="#222" stroke-width="1" stroke-linejoin="round">"##
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
}

/// A five-pointed star of outer radius `r` centred on `(x, y)`, as polygon points.
pub(super) fn star(x: f64, y: f64, r: f64) -> String {
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
