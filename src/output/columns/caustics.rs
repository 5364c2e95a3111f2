//! The number of caustics an entry's ray tube passed (`caustics`: each adds −π/2 to the
//! amplitude's phase), for scenes with a `profile` or `gradient` medium: a number per entry
//! (NaN, `null` or empty where it is not known: a ray without a time, a diffracted ray).

use super::{Cell, Column, ColumnType, Entry, Quantity};
use crate::scene::Scene;

/// The `caustics` column.
pub(super) struct CausticsQuantity;

impl Quantity for CausticsQuantity {
    fn asked(&self, scene: &Scene) -> bool {
        scene
            .media()
            .iter()
            .any(|m| m.profile.is_some() || m.gradient.is_some())
    }

    fn columns(&self) -> &'static [Column] {
        &[Column {
            name: "caustics",
            ty: ColumnType::Float,
        }]
    }

    fn cells(&self, entry: &Entry<'_>, each: &mut dyn FnMut(Cell)) {
        each(Cell::Float(entry.caustics.map_or(f64::NAN, f64::from)));
    }
}
