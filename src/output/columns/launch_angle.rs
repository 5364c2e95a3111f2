//! The direction of an entry's ray at its source (`launch_angle`, radians from +x,
//! counterclockwise), for scenes with a `profile` medium, where the path's points (the
//! source and the receiver) do not give it: a number per entry (NaN, `null` or empty where
//! it is not known: a ray through another medium).

use super::{Cell, Column, ColumnType, Entry, Quantity};
use crate::scene::Scene;

/// The `launch_angle` column.
pub(super) struct LaunchAngleQuantity;

impl Quantity for LaunchAngleQuantity {
    fn asked(&self, scene: &Scene) -> bool {
        scene.media().iter().any(|m| m.profile.is_some())
    }

    fn columns(&self) -> &'static [Column] {
        &[Column {
            name: "launch_angle",
            ty: ColumnType::Float,
        }]
    }

    fn cells(&self, entry: &Entry<'_>, each: &mut dyn FnMut(Cell)) {
        each(Cell::Float(entry.launch_angle.unwrap_or(f64::NAN)))
    }
}
