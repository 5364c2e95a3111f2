//! The `receivers` key: a list of points, or a grid (`{"grid": {"x": [first, last, count],
//! "y": [first, last, count]}}`) that expands to one, receiver `ix · ny + iy` at
//! `(x[ix], y[iy])`, each axis spaced as `numpy.linspace`.

use std::fmt;

use serde::de::value::{MapAccessDeserializer, SeqAccessDeserializer};
use serde::de::{MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

use super::{MAX_COORDINATE, MIN_COORDINATE, SceneError, point};
use crate::geom::Point;

/// The `receivers` key of a scene document: a list of points, or a grid of them.
///
/// ```
/// use eigenray::scene::{ReceiverGridSpec, ReceiversSpec};
/// let list: ReceiversSpec = serde_json::from_str("[[1, -1], [2, -1]]").unwrap();
/// assert_eq!(list, ReceiversSpec::Points(vec![[1.0, -1.0], [2.0, -1.0]]));
/// let grid: ReceiversSpec =
///     serde_json::from_str(r#"{"grid": {"x": [100, 5000, 197], "y": [-1, -99, 50]}}"#).unwrap();
/// assert_eq!(
///     grid,
///     ReceiversSpec::Grid {
///         grid: ReceiverGridSpec { x: [100.0, 5000.0, 197.0], y: [-1.0, -99.0, 50.0] }
///     }
/// );
/// ```
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ReceiversSpec {
    /// The receivers, one point each.
    Points(Vec<[f64; 2]>),
    /// A grid of receivers (`{"grid": {...}}`).
    Grid {
        /// Its two axes.
        grid: ReceiverGridSpec,
    },
}

impl Default for ReceiversSpec {
    /// No receivers.
    fn default() -> ReceiversSpec {
        ReceiversSpec::Points(Vec::new())
    }
}

impl From<Vec<[f64; 2]>> for ReceiversSpec {
    fn from(points: Vec<[f64; 2]>) -> ReceiversSpec {
        ReceiversSpec::Points(points)
    }
}

impl ReceiversSpec {
    /// The points, when given as a list (`None` for a grid).
    pub fn list(&self) -> Option<&[[f64; 2]]> {
        match self {
            ReceiversSpec::Points(points) => Some(points),
            ReceiversSpec::Grid { .. } => None,
        }
    }

    /// The list of points, made a list first where it was a grid (its points then as the
    /// grid places them; a grid that does not validate gives an empty list): what the
    /// [`SceneBuilder`](crate::SceneBuilder) appends to.
    pub fn points_mut(&mut self) -> &mut Vec<[f64; 2]> {
        if let ReceiversSpec::Grid { grid } = self {
            let points = grid
                .points()
                .map(|p| p.iter().map(|q| [q.x, q.y]).collect())
                .unwrap_or_default();
            *self = ReceiversSpec::Points(points);
        }
        match self {
            ReceiversSpec::Points(points) => points,
            ReceiversSpec::Grid { .. } => unreachable!("made a list above"),
        }
    }

    /// The validated receivers: the list's points, or the grid's.
    ///
    /// # Errors
    /// `receivers[k]` for a point of the list out of range; the grid's errors at
    /// `receivers.grid.x` or `receivers.grid.y` (an axis' count not a whole number ≥ 1, an
    /// end out of range) or `receivers.grid` (more receivers than fit in memory).
    pub(super) fn validate(&self) -> Result<Vec<Point>, SceneError> {
        match self {
            ReceiversSpec::Points(list) => list
                .iter()
                .enumerate()
                .map(|(k, p)| point(&format!("receivers[{k}]"), *p))
                .collect(),
            ReceiversSpec::Grid { grid } => grid.points(),
        }
    }
}

/// A grid of receivers: `x` and `y` are `[first, last, count]`, each axis spaced as
/// `numpy.linspace(first, last, count)`; receiver `ix · ny + iy` lies at `(x[ix], y[iy])`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReceiverGridSpec {
    /// `[first, last, count]` of the x axis.
    pub x: [f64; 3],
    /// `[first, last, count]` of the y axis.
    pub y: [f64; 3],
}

/// One axis of a validated grid.
#[derive(Clone, Copy, Debug, PartialEq)]
struct GridAxis {
    first: f64,
    last: f64,
    count: usize,
}

impl GridAxis {
    /// Axis `name` (`x` or `y`) of `[first, last, count]`.
    fn of(name: &str, [first, last, count]: [f64; 3]) -> Result<GridAxis, SceneError> {
        let key = format!("receivers.grid.{name}");
        if !(count >= 1.0 && count.fract() == 0.0 && count <= u32::MAX as f64) {
            return Err(SceneError::new(
                &key,
                format!(
                    "the count (the third number) must be a whole number from 1 to {}, not {count}",
                    u32::MAX
                ),
            ));
        }
        // The ends as the coordinates of points, so that they pass a point's checks.
        let ends = [first, last].map(|v| if name == "x" { [v, 0.0] } else { [0.0, v] });
        for (k, e) in ends.iter().enumerate() {
            point(&format!("{key}[{k}]"), *e)?;
        }
        Ok(GridAxis {
            first,
            last,
            count: count as usize,
        })
    }

    /// Coordinate `i` (of `count`): `numpy.linspace`'s, the last exactly `last`.
    fn at(&self, i: usize) -> f64 {
        if i + 1 == self.count && i > 0 {
            return self.last;
        }
        let step = if self.count > 1 {
            (self.last - self.first) / (self.count - 1) as f64
        } else {
            0.0
        };
        i as f64 * step + self.first
    }
}

impl ReceiverGridSpec {
    /// `(nx, ny)`: the receivers along x and along y, when both counts are whole numbers
    /// that fit a `usize` (not checked further: its expansion into points validates).
    pub fn shape(&self) -> Option<(usize, usize)> {
        let count =
            |c: f64| (c >= 1.0 && c.fract() == 0.0 && c <= u32::MAX as f64).then_some(c as usize);
        Some((count(self.x[2])?, count(self.y[2])?))
    }

    /// The grid's receivers, `ix · ny + iy` at `(x[ix], y[iy])`, each checked as a point
    /// of the scene.
    ///
    /// # Errors
    /// As [`ReceiversSpec::validate`].
    fn points(&self) -> Result<Vec<Point>, SceneError> {
        let x = GridAxis::of("x", self.x)?;
        let y = GridAxis::of("y", self.y)?;
        let too_many = || {
            SceneError::new(
                "receivers.grid",
                format!(
                    "{} × {} receivers do not fit in memory: use a coarser grid, or split it",
                    x.count, y.count
                ),
            )
        };
        let n = x.count.checked_mul(y.count).ok_or_else(too_many)?;
        let mut out = Vec::new();
        out.try_reserve_exact(n).map_err(|_| too_many())?;
        // Each axis' coordinates once, each with whether it passes a point's checks: a
        // point passes them when both its coordinates do (the checks are coordinate by
        // coordinate), and only a point that may not is checked whole, for its error.
        let ys: Vec<(f64, bool)> = (0..y.count)
            .map(|iy| {
                let v = y.at(iy);
                (v, passes_point_checks(v))
            })
            .collect();
        for ix in 0..x.count {
            let px = x.at(ix);
            let x_passes = passes_point_checks(px);
            for &(py, y_passes) in &ys {
                out.push(if x_passes && y_passes {
                    Point::new(px, py)
                } else {
                    point("receivers.grid", [px, py])?
                });
            }
        }
        Ok(out)
    }
}

/// Whether a coordinate passes the checks [`point`] makes of each coordinate of a point:
/// finite, within `MAX_COORDINATE`, and zero or at least `MIN_COORDINATE` in magnitude.
fn passes_point_checks(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_COORDINATE && (v == 0.0 || v.abs() >= MIN_COORDINATE)
}

/// `{"grid": ...}`: the one key a grid's object holds.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GridKey {
    grid: ReceiverGridSpec,
}

impl<'de> Deserialize<'de> for ReceiversSpec {
    /// A list of points, or `{"grid": {...}}`, each with the error of its own shape.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<ReceiversSpec, D::Error> {
        struct Either;
        impl<'de> Visitor<'de> for Either {
            type Value = ReceiversSpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(
                    "a list of points, or {\"grid\": {\"x\": [first, last, count], \"y\": [first, \
                     last, count]}}",
                )
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ReceiversSpec, A::Error> {
                Vec::deserialize(SeqAccessDeserializer::new(seq)).map(ReceiversSpec::Points)
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<ReceiversSpec, A::Error> {
                GridKey::deserialize(MapAccessDeserializer::new(map))
                    .map(|g| ReceiversSpec::Grid { grid: g.grid })
            }
        }
        d.deserialize_any(Either)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(x: [f64; 3], y: [f64; 3]) -> ReceiverGridSpec {
        ReceiverGridSpec { x, y }
    }

    /// The documented order and spacing: receiver `ix · ny + iy` at `(x[ix], y[iy])`, each
    /// axis as `numpy.linspace` (the values numpy 2.4 gives, written out; the same formula
    /// matched numpy on 20,000 random axes).
    #[test]
    fn a_grid_expands_in_the_documented_order() {
        let points = grid([0.0, 1.0, 3.0], [-1.0, -2.0, 2.0]).points().unwrap();
        let xy: Vec<[f64; 2]> = points.iter().map(|p| [p.x, p.y]).collect();
        assert_eq!(
            xy,
            [
                [0.0, -1.0],
                [0.0, -2.0],
                [0.5, -1.0],
                [0.5, -2.0],
                [1.0, -1.0],
                [1.0, -2.0]
            ]
        );
        let xs = |first: f64, last: f64, count: f64| -> Vec<f64> {
            let g = grid([first, last, count], [0.0, 0.0, 1.0]);
            g.points().unwrap().iter().map(|p| p.x).collect()
        };
        // numpy.linspace(0.1, 0.7, 4)
        assert_eq!(xs(0.1, 0.7, 4.0), [0.1, 0.3, 0.5, 0.7]);
        // numpy.linspace(100, 5000, 197)[[1, 57, 195]]
        let tl = xs(100.0, 5000.0, 197.0);
        assert_eq!([tl[1], tl[57], tl[195]], [125.0, 1525.0, 4975.0]);
        let one = grid([3.0, 9.0, 1.0], [2.0, 5.0, 1.0]).points().unwrap();
        assert_eq!(one, [Point::new(3.0, 2.0)]);
    }

    #[test]
    fn bad_counts_and_ends_name_their_axis() {
        for (g, key) in [
            (grid([0.0, 1.0, 0.0], [0.0, 1.0, 2.0]), "receivers.grid.x"),
            (grid([0.0, 1.0, 2.0], [0.0, 1.0, 1.5]), "receivers.grid.y"),
            (grid([0.0, 1.0, 2.0], [0.0, 1.0, -3.0]), "receivers.grid.y"),
            (
                grid([0.0, 1e300, 2.0], [0.0, 1.0, 2.0]),
                "receivers.grid.x[1]",
            ),
            (
                grid([0.0, 1.0, 2.0], [f64::NAN, 1.0, 2.0]),
                "receivers.grid.y[0]",
            ),
            (grid([0.0, 1.0, 4e9], [0.0, 1.0, 4e9]), "receivers.grid"),
        ] {
            let e = ReceiversSpec::Grid { grid: g }.validate().unwrap_err();
            assert_eq!(e.key, key, "{e}");
        }
    }

    /// The grid's points are those of checking every point whole (each coordinate computed
    /// by its axis, then `point`), value for value, and its errors the same error: the
    /// coordinates checked once an axis, the points only where one may fail. The grids span
    /// signs and magnitudes, interior coordinates below `MIN_COORDINATE` (not at the ends)
    /// on either axis, and zeros.
    #[test]
    fn the_points_are_those_checked_one_by_one() {
        let one_by_one = |g: &ReceiverGridSpec| -> Result<Vec<Point>, SceneError> {
            let (x, y) = (GridAxis::of("x", g.x)?, GridAxis::of("y", g.y)?);
            let mut out = Vec::new();
            for ix in 0..x.count {
                for iy in 0..y.count {
                    out.push(point("receivers.grid", [x.at(ix), y.at(iy)])?);
                }
            }
            Ok(out)
        };
        let tiny = -1.5 * MIN_COORDINATE;
        let grids = [
            grid([100.0, 5000.0, 197.0], [-1.0, -99.0, 50.0]),
            grid([-1.0, 1.0, 21.0], [-0.3, 0.3, 7.0]),
            grid([-0.7, 0.7, 8.0], [1e-90, -1e-90, 5.0]),
            grid([tiny, MIN_COORDINATE, 3.0], [0.0, 1.0, 2.0]),
            grid([0.0, 1.0, 2.0], [tiny, MIN_COORDINATE, 3.0]),
            grid([tiny, MIN_COORDINATE, 3.0], [tiny, MIN_COORDINATE, 3.0]),
            grid([-1e100, 1e100, 5.0], [0.0, 0.0, 1.0]),
        ];
        let mut failed = 0;
        for g in &grids {
            let (got, want) = (g.points(), one_by_one(g));
            match (&got, &want) {
                (Ok(a), Ok(b)) => {
                    let bits = |v: &[Point]| -> Vec<[u64; 2]> {
                        v.iter().map(|p| [p.x.to_bits(), p.y.to_bits()]).collect()
                    };
                    assert_eq!(bits(a), bits(b), "{g:?}");
                }
                (Err(a), Err(b)) => {
                    assert_eq!((&a.key, &a.message), (&b.key, &b.message), "{g:?}");
                    failed += 1;
                }
                _ => panic!("{g:?}: {got:?} against {want:?}"),
            }
        }
        assert_eq!(failed, 3, "the grids with a tiny interior coordinate fail");
    }

    /// A list stays a list and a grid a grid when written and read back.
    #[test]
    fn both_forms_read_back_as_written() {
        for text in [
            r#"[[1.0,2.0],[3.0,4.0]]"#,
            r#"{"grid":{"x":[100.0,5000.0,197.0],"y":[-1.0,-99.0,50.0]}}"#,
        ] {
            let spec: ReceiversSpec = serde_json::from_str(text).unwrap();
            assert_eq!(serde_json::to_string(&spec).unwrap(), text);
        }
        for bad in [
            r#"{"grid":{"x":[0,1,2]}}"#,
            r#"{"grid":{"x":[0,1,2],"y":[0,1,2],"z":[0,1,2]}}"#,
            r#"{"points":[]}"#,
            "3",
        ] {
            assert!(serde_json::from_str::<ReceiversSpec>(bad).is_err(), "{bad}");
        }
    }
}
