//! Cheap updates of a tracer's scene: a source, a receiver (or all of them), an interface's
//! vertices, a medium's speed, each validated as the scene document is (see
//! `scene/update.rs`), and only what depends on it prepared again.
//!
//! What the tracer prepares, and what each update touches:
//!
//! | prepared | source | receiver | interface | medium |
//! | --- | --- | --- | --- | --- |
//! | region lookup (`Regions`) | its checks | | rebuilt | |
//! | the sources' media | that source's | | all | |
//! | the classifier's candidates | if the sources' box changes | if the receivers' box changes | rebuilt | |
//! | the per-path plans | | | rebuilt | rebuilt |
//! | segment hierarchies (complete search) | | | that interface's | |
//! | media on each interface's sides | | | all | |
//!
//! After any sequence of updates the tracer gives the rays of a tracer built afresh from the
//! edited scene, bit for bit (`tests/updates.rs`).

use std::sync::{Arc, OnceLock};

use crate::geom::{Aabb, Point};
use crate::regions::Regions;
use crate::scene::{Scene, SceneError};

use super::{Classifier, Tracer};

/// Whether two boxes are the same to the bit (the classifier's candidates depend on them).
fn same_box(a: Aabb, b: Aabb) -> bool {
    let bits = |b: Aabb| [b.min.x, b.min.y, b.max.x, b.max.y].map(f64::to_bits);
    bits(a) == bits(b)
}

/// Whether the box around `points` stays `old` when one of them moves from `from` to `to`:
/// surely so when `from` lay strictly inside it and `to` lies within it.
fn box_unchanged(old: Aabb, from: Point, to: Point) -> bool {
    let strictly =
        from.x > old.min.x && from.x < old.max.x && from.y > old.min.y && from.y < old.max.y;
    strictly && old.contains(to)
}

impl Tracer {
    /// The scene, to edit: a copy first if another `Arc` shares it.
    fn scene_mut(&mut self) -> &mut Scene {
        Arc::make_mut(&mut self.scene)
    }

    /// Moves source `source` to `p` ([`Scene::set_source`]'s checks, and with region lookup a
    /// medium in its region): the tracer then solves as one built afresh from the edited
    /// scene, without preparing anything again but the source's medium (and the classifier's
    /// candidates, when the box around the sources grows or shrinks).
    ///
    /// The tracer's scene is edited in place; a scene shared with another tracer (built from
    /// one `Arc`) is copied first.
    ///
    /// # Errors
    /// As [`Scene::set_source`], or `sources[i]` in a region that no medium fills; the
    /// tracer is then left as it was.
    pub fn set_source(&mut self, source: usize, p: Point) -> Result<(), SceneError> {
        let old = self.scene.sources().get(source).copied();
        self.scene_mut().set_source(source, p)?;
        let Some(old) = old else { return Ok(()) };
        let p = self.scene.sources()[source];
        if let Some(regions) = &self.regions {
            if let Err(e) = regions.check_source(&self.scene, source, p) {
                // The old position was accepted before: it is again.
                let _ = Arc::make_mut(&mut self.scene).set_source(source, old);
                return Err(e);
            }
            self.source_media[source] = regions.source_medium(&self.scene, p);
        }
        self.refresh_ends(0, old, p);
        Ok(())
    }

    /// Moves receiver `receiver` to `p` ([`Scene::set_receiver`]'s checks): nothing is
    /// prepared again (but the classifier's candidates, when the box around the receivers
    /// grows or shrinks).
    ///
    /// ```
    /// use eigenray::{Point, Scene, Tracer};
    /// let scene = Scene::from_json(r#"{
    ///     "media": { "air": { "index": 1.0 }, "water": { "index": 1.333 } },
    ///     "interfaces": { "surface": { "points": [[-10, 0], [10, 0]] } },
    ///     "sources": [[0, 1]], "receivers": [[1, -1]],
    ///     "paths": [{ "steps": [{ "refract": "surface" }], "media": ["air", "water"] }]
    /// }"#).unwrap();
    /// let mut tracer = Tracer::new(scene).unwrap();
    /// tracer.set_receiver(0, Point::new(3.0, -2.0)).unwrap();
    /// let moved = tracer.trace_all();
    /// assert_eq!(moved[0].points[2], Point::new(3.0, -2.0));
    /// let e = tracer.set_receiver(0, Point::new(f64::NAN, 0.0)).unwrap_err();
    /// assert_eq!(e.to_string(), "receivers[0]: coordinates must be finite numbers");
    /// ```
    ///
    /// # Errors
    /// As [`Scene::set_receiver`]; the tracer is then left as it was.
    pub fn set_receiver(&mut self, receiver: usize, p: Point) -> Result<(), SceneError> {
        let old = self.scene.receivers().get(receiver).copied();
        self.scene_mut().set_receiver(receiver, p)?;
        if let Some(old) = old {
            let p = self.scene.receivers()[receiver];
            self.refresh_ends(1, old, p);
        }
        Ok(())
    }

    /// Moves every receiver at once ([`Scene::set_receivers`]'s checks, all or nothing):
    /// what a block of a large map does, with one tracer moved from block to block. Nothing
    /// is prepared again but the classifier's candidates, when the box around the receivers
    /// changes; unlike as many [`set_receiver`](Self::set_receiver) calls, each of which may
    /// look at every receiver, it costs time in proportion to the receivers.
    ///
    /// # Errors
    /// As [`Scene::set_receivers`]; the tracer is then left as it was.
    pub fn set_receivers(&mut self, points: &[Point]) -> Result<(), SceneError> {
        let old = self.classifier.ends()[1];
        self.scene_mut().set_receivers(points)?;
        if !same_box(old, Aabb::around(self.scene.receivers())) {
            self.classifier = Classifier::new(&self.scene);
        }
        Ok(())
    }

    /// Gives interface `interface` new vertices ([`Scene::set_interface_points`]'s checks,
    /// then those of [`Tracer::new`]'s region lookup): rebuilds the scene's segment index, the
    /// region lookup (when the scene has one), the classifier's candidates, the per-path plans
    /// and this interface's segment hierarchy; the rest stays.
    ///
    /// # Errors
    /// As [`Scene::set_interface_points`], or a region lookup that the new shape makes
    /// inconsistent (as [`Tracer::new`] would refuse it); the tracer is then left as it was.
    pub fn set_interface_points(
        &mut self,
        interface: usize,
        points: &[Point],
    ) -> Result<(), SceneError> {
        let undo = self
            .scene_mut()
            .replace_interface_points(interface, points)?;
        if self.regions.is_some() {
            match Regions::build(&self.scene) {
                Ok(regions) => {
                    self.source_media = self
                        .scene
                        .sources()
                        .iter()
                        .map(|&p| regions.source_medium(&self.scene, p))
                        .collect();
                    self.regions = Some(regions);
                }
                Err(e) => {
                    self.scene_mut().undo_interface(undo);
                    return Err(e);
                }
            }
            for sides in &mut self.sides {
                *sides = OnceLock::new();
            }
        }
        self.classifier = Classifier::new(&self.scene);
        self.plan();
        self.hierarchies[interface] = OnceLock::new();
        Ok(())
    }

    /// Gives medium `medium` the speed `speed` ([`Scene::set_medium_speed`]'s checks):
    /// rebuilds the per-path plans (which hold the leg slownesses); the rest stays.
    ///
    /// # Errors
    /// As [`Scene::set_medium_speed`]; the tracer is then left as it was.
    pub fn set_medium_speed(&mut self, medium: usize, speed: f64) -> Result<(), SceneError> {
        self.scene_mut().set_medium_speed(medium, speed)?;
        self.plan();
        Ok(())
    }

    /// Gives medium `medium` the refractive index `index`
    /// ([`Scene::set_medium_index`]'s checks), as [`set_medium_speed`](Self::set_medium_speed).
    ///
    /// # Errors
    /// As [`Scene::set_medium_index`]; the tracer is then left as it was.
    pub fn set_medium_index(&mut self, medium: usize, index: f64) -> Result<(), SceneError> {
        self.scene_mut().set_medium_index(medium, index)?;
        self.plan();
        Ok(())
    }

    /// Rebuilds the classifier's candidates when the box around the sources (`end` 0) or the
    /// receivers (`end` 1) is no longer the one they were found for, after one point moved
    /// from `from` to `to`.
    fn refresh_ends(&mut self, end: usize, from: Point, to: Point) {
        let old = self.classifier.ends()[end];
        if box_unchanged(old, from, to) {
            return;
        }
        let points = if end == 0 {
            self.scene.sources()
        } else {
            self.scene.receivers()
        };
        if !same_box(old, Aabb::around(points)) {
            self.classifier = Classifier::new(&self.scene);
        }
    }
}
