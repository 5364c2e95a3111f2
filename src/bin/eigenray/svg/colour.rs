//! The colours of rays: what colours them (time, path or sequence), viridis for travel times,
//! the palette and dashes of paths and sequences.

pub use super::colouring::Colouring;
use super::entries::Item;
use super::legend::Legend;

/// Viridis (matplotlib's perceptually uniform colormap) at 0, 1/8, …, 1; linear in between.
pub(super) const VIRIDIS: [[u8; 3]; 9] = [
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

/// Colours of paths (Tableau's 10, then their lighter companions), repeated beyond 20 paths.
pub(super) const PATH_COLOURS: [&str; 20] = [
    "#4e79a7", "#f28e2b", "#e15759", "#76b7b2", "#59a14f", "#edc948", "#b07aa1", "#ff9da7",
    "#9c755f", "#bab0ac", "#a0cbe8", "#ffbe7d", "#ff9d9a", "#86bcb6", "#8cd17d", "#f1ce63",
    "#d4a6c8", "#fabfd2", "#d7b5a6", "#79706e",
];

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

/// The line style of path `p` when colouring by path: the colours repeat every 20 paths, solid
/// the first time round, long dashes the second, and so on.
pub(super) fn path_dash(p: usize) -> &'static str {
    if (p / PATH_COLOURS.len()) % 2 == 1 {
        r#" stroke-dasharray="8 3""#
    } else {
        ""
    }
}

/// The range of travel times of the drawn items that have one: `(min, max)`, `None` for none.
pub(super) fn time_range(items: &[Item]) -> Option<(f64, f64)> {
    items
        .iter()
        .filter(|r| r.status.has_time())
        .map(|r| r.time)
        .fold(None, |acc: Option<(f64, f64)>, t| match acc {
            None => Some((t, t)),
            Some((lo, hi)) => Some((lo.min(t), hi.max(t))),
        })
}

/// The colour of each drawn item under a colouring: its legend line's, or its time's on
/// viridis over the drawn times' range.
pub(super) struct RayColours<'a> {
    /// What colours the rays.
    pub(super) colouring: Colouring,
    /// The legend (empty by time).
    pub(super) legend: &'a Legend,
    /// The drawn items' range of travel times.
    pub(super) range: Option<(f64, f64)>,
}

impl RayColours<'_> {
    /// The colour of drawn item `k`, `r`, as `#rrggbb`.
    pub(super) fn of(&self, k: usize, r: &Item) -> String {
        match self.colouring {
            Colouring::Path | Colouring::Sequence => {
                let c = self.legend.entries[self.legend.of_item[k]].colour;
                PATH_COLOURS[c % PATH_COLOURS.len()].to_string()
            }
            Colouring::Time => {
                let t = r.time;
                match self.range {
                    Some((lo, hi)) if hi > lo => viridis((t - lo) / (hi - lo)),
                    _ => viridis(0.5),
                }
            }
        }
    }

    /// The dash of drawn item `k`, `r`: obstructed dashed, vertex dotted, and by path or
    /// sequence the dash of its legend line's colour.
    pub(super) fn dash(&self, k: usize, r: &Item) -> &'static str {
        match r.status {
            eigenray::Status::Obstructed => r#" stroke-dasharray="5 3""#,
            eigenray::Status::Vertex => r#" stroke-dasharray="1 3""#,
            _ if self.colouring != Colouring::Time => {
                path_dash(self.legend.entries[self.legend.of_item[k]].colour)
            }
            _ => "",
        }
    }
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
}
