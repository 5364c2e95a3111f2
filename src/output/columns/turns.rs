//! The number of turning points on an entry's legs (`turns`), for scenes with a `profile`
//! medium: a number per entry (NaN, `null` or empty where it is not known: a ray through
//! another medium).

use super::{Cell, Column, ColumnType, Entry, Quantity};
use crate::scene::Scene;

/// The `turns` column.
pub(super) struct TurnsQuantity;

impl Quantity for TurnsQuantity {
    fn asked(&self, scene: &Scene) -> bool {
        scene.media().iter().any(|m| m.profile.is_some())
    }

    fn columns(&self) -> &'static [Column] {
        &[Column {
            name: "turns",
            ty: ColumnType::Float,
        }]
    }

    fn cells(&self, entry: &Entry<'_>, each: &mut dyn FnMut(Cell)) {
        each(Cell::Float(entry.turns.map_or(f64::NAN, f64::from)));
    }
}
