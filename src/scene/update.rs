//! Edits of a validated scene that layout tools make most: a source, a receiver, an
//! interface's vertices, a medium's speed. Each is validated as the scene document is (the
//! same checks, the same keys and messages), and a refused edit leaves the scene as it was.

use super::amplitudes::per_unit_length;
use super::{
    Bvh, Interface, Point, Polyline, Scene, SceneError, SegmentRef, at_off_interfaces,
    check_region_range, crossings, index_segments, interface_polyline, one_kind_of_medium, point,
    positive, scene_points, segment_ends, source_in_a_region,
};

/// What an interface edit replaced: enough to put it back (a tracer's own checks may refuse
/// what the scene's accepted).
#[derive(Debug)]
pub(crate) struct InterfaceUndo {
    interface: usize,
    polyline: Polyline,
    segments: Vec<SegmentRef>,
    segment_ends: Vec<crate::geom::Segment>,
    segment_bvh: Bvh,
}

/// The error for an index beyond a list of `len` items called `what`.
fn out_of_range(key: &str, what: &str, index: usize, len: usize) -> SceneError {
    SceneError::new(
        key,
        format!("index {index} is out of range (the scene has {len} {what})"),
    )
}

impl Scene {
    /// Moves source `source` to `p`, checked as `sources[source]` of a scene document: finite
    /// and within the coordinate limits and, when the scene needs region lookup, off every
    /// interface and the domain's edge and within the range that lookup holds.
    ///
    /// ```
    /// use eigenray::{Point, Scene};
    /// let mut scene = Scene::from_json(r#"{
    ///     "media": { "air": { "speed": 343.0 } },
    ///     "interfaces": { "wall": { "points": [[0, 0], [6, 0]] } },
    ///     "sources": [[1, 1]], "receivers": [[5, 1]],
    ///     "paths": [{ "steps": [{ "reflect": "wall" }] }]
    /// }"#).unwrap();
    /// scene.set_source(0, Point::new(2.0, 1.5)).unwrap();
    /// let e = scene.set_source(0, Point::new(3.0, 0.0)).unwrap_err();
    /// assert_eq!(e.key, "sources[0]"); // on the wall: no medium there
    /// assert_eq!(scene.sources()[0], Point::new(2.0, 1.5));
    /// ```
    ///
    /// # Errors
    /// `sources` for an index out of range, or the problem with the point at `sources[i]`;
    /// the scene is then left as it was.
    pub fn set_source(&mut self, source: usize, p: Point) -> Result<(), SceneError> {
        let len = self.sources.len();
        if source >= len {
            return Err(out_of_range("sources", "sources", source, len));
        }
        let p = point(&format!("sources[{source}]"), [p.x, p.y])?;
        self.source_on_axis(source, p)?;
        if self.needs_regions() {
            source_in_a_region(
                &self.interfaces,
                &self.segments,
                &self.segment_bvh,
                self.domain,
                self.axisymmetric(),
                source,
                p,
            )?;
        }
        let old = std::mem::replace(&mut self.sources[source], p);
        if let Err(e) = self.check_range() {
            self.sources[source] = old;
            return Err(e);
        }
        Ok(())
    }

    /// Moves receiver `receiver` to `p`, checked as `receivers[receiver]` of a scene
    /// document.
    ///
    /// # Errors
    /// `receivers` for an index out of range, or the problem with the point at
    /// `receivers[i]`; the scene is then left as it was.
    pub fn set_receiver(&mut self, receiver: usize, p: Point) -> Result<(), SceneError> {
        let len = self.receivers.len();
        if receiver >= len {
            return Err(out_of_range("receivers", "receivers", receiver, len));
        }
        let p = point(&format!("receivers[{receiver}]"), [p.x, p.y])?;
        let old = std::mem::replace(&mut self.receivers[receiver], p);
        if let Err(e) = self.check_range() {
            self.receivers[receiver] = old;
            return Err(e);
        }
        self.document.forget_receiver_grid();
        Ok(())
    }

    /// Moves every receiver at once: `points` holds one point per receiver, each checked as
    /// `receivers[i]` of a scene document. All or nothing: a refused point leaves every
    /// receiver where it was.
    ///
    /// # Errors
    /// `receivers` when `points` does not hold one point per receiver, or the problem with
    /// the first refused point at `receivers[i]`; the scene is then left as it was.
    pub fn set_receivers(&mut self, points: &[Point]) -> Result<(), SceneError> {
        let len = self.receivers.len();
        if points.len() != len {
            return Err(SceneError::new(
                "receivers",
                format!("has {} points; the scene has {len} receivers", points.len()),
            ));
        }
        let checked = points
            .iter()
            .enumerate()
            .map(|(i, p)| point(&format!("receivers[{i}]"), [p.x, p.y]))
            .collect::<Result<Vec<Point>, SceneError>>()?;
        let old = std::mem::replace(&mut self.receivers, checked);
        if let Err(e) = self.check_range() {
            self.receivers = old;
            return Err(e);
        }
        self.document.forget_receiver_grid();
        Ok(())
    }

    /// Gives interface `interface` (an index into [`interfaces`](Self::interfaces); see
    /// [`interface_index`](Self::interface_index)) new vertices, any number of them; it stays
    /// open or closed. Checked as `interfaces.NAME.points` of a scene document: each point,
    /// the polyline (enough distinct points, no zero-length segment), no crossing or overlap
    /// with itself or another interface, no `at` point or (with region lookup) source on it.
    /// Rebuilds the scene's index of segments.
    ///
    /// ```
    /// use eigenray::{Point, Scene};
    /// let mut scene = Scene::from_json(r#"{
    ///     "media": { "air": { "speed": 1.0 } },
    ///     "interfaces": { "a": { "points": [[0, 0], [4, 0]] },
    ///                     "b": { "points": [[0, 2], [4, 2]] } },
    ///     "sources": [[1, 1]], "receivers": [[3, 1]],
    ///     "paths": [{ "steps": [{ "reflect": "a" }], "media": ["air", "air"] }]
    /// }"#).unwrap();
    /// let a = scene.interface_index("a").unwrap();
    /// let bent = [Point::new(0.0, 0.0), Point::new(2.0, -0.5), Point::new(4.0, 0.0)];
    /// scene.set_interface_points(a, &bent).unwrap();
    /// let e = scene.set_interface_points(a, &[Point::new(0.0, 0.0), Point::new(2.0, 3.0)]);
    /// assert_eq!(e.unwrap_err().to_string(),
    ///            "interfaces.a.points: crosses interface `b` (segment 0 crosses segment 0)");
    /// assert_eq!(scene.interfaces()[a].polyline.vertices(), &bent);
    /// ```
    ///
    /// # Errors
    /// `interfaces` for an index out of range, or the problem, at the key the scene document
    /// would give; the scene is then left as it was.
    pub fn set_interface_points(
        &mut self,
        interface: usize,
        points: &[Point],
    ) -> Result<(), SceneError> {
        self.replace_interface_points(interface, points).map(|_| ())
    }

    /// [`set_interface_points`](Self::set_interface_points), returning what it replaced.
    pub(crate) fn replace_interface_points(
        &mut self,
        interface: usize,
        points: &[Point],
    ) -> Result<InterfaceUndo, SceneError> {
        let len = self.interfaces.len();
        if interface >= len {
            return Err(out_of_range("interfaces", "interfaces", interface, len));
        }
        let Interface { name, polyline } = &self.interfaces[interface];
        let raw: Vec<[f64; 2]> = points.iter().map(|p| [p.x, p.y]).collect();
        let polyline = interface_polyline(name, &raw, polyline.is_closed())?;
        let old = std::mem::replace(&mut self.interfaces[interface].polyline, polyline);
        let (segments, segment_bvh) = index_segments(&self.interfaces);
        let ends = segment_ends(&self.interfaces, &segments);
        let undo = InterfaceUndo {
            interface,
            polyline: old,
            segments: std::mem::replace(&mut self.segments, segments),
            segment_ends: std::mem::replace(&mut self.segment_ends, ends),
            segment_bvh: std::mem::replace(&mut self.segment_bvh, segment_bvh),
        };
        // The document's checks that involve interfaces, in its order.
        let checked = crossings::check(&self.interfaces, &self.segments)
            .and_then(|()| {
                self.media.iter().try_for_each(|m| {
                    at_off_interfaces(m, &self.interfaces, &self.segments, &self.segment_bvh)
                })
            })
            .and_then(|()| {
                if !self.needs_regions() {
                    return Ok(());
                }
                self.sources.iter().enumerate().try_for_each(|(k, &p)| {
                    source_in_a_region(
                        &self.interfaces,
                        &self.segments,
                        &self.segment_bvh,
                        self.domain,
                        self.axisymmetric(),
                        k,
                        p,
                    )
                })
            })
            .and_then(|()| self.check_range());
        match checked {
            Ok(()) => Ok(undo),
            Err(e) => {
                self.undo_interface(undo);
                Err(e)
            }
        }
    }

    /// Puts back what an interface edit replaced.
    pub(crate) fn undo_interface(&mut self, undo: InterfaceUndo) {
        self.interfaces[undo.interface].polyline = undo.polyline;
        self.segments = undo.segments;
        self.segment_ends = undo.segment_ends;
        self.segment_bvh = undo.segment_bvh;
    }

    /// Gives medium `medium` (an index into [`media`](Self::media); see
    /// [`medium_index`](Self::medium_index)) the speed `speed`, checked as
    /// `media.NAME.speed` of a scene document. An attenuation the document gives per
    /// wavelength follows the speed (`a·f/c` dB per unit length).
    ///
    /// # Errors
    /// `media` for an index out of range, or the problem with the speed; the scene is then
    /// left as it was.
    pub fn set_medium_speed(&mut self, medium: usize, speed: f64) -> Result<(), SceneError> {
        self.set_slowness(medium, false, speed)
    }

    /// Gives medium `medium` the refractive index `index` (its slowness), checked as
    /// `media.NAME.index` of a scene document.
    ///
    /// # Errors
    /// `media` for an index out of range, or the problem with the index; the scene is then
    /// left as it was.
    pub fn set_medium_index(&mut self, medium: usize, index: f64) -> Result<(), SceneError> {
        self.set_slowness(medium, true, index)
    }

    /// Sets a medium's slowness from `value`, its refractive index when `index`, else its
    /// speed (the key `media.NAME.index` or `media.NAME.speed`); the document that
    /// [`to_spec`](Scene::to_spec) writes keeps `value` as given.
    fn set_slowness(&mut self, medium: usize, index: bool, value: f64) -> Result<(), SceneError> {
        let len = self.media.len();
        let Some(m) = self.media.get_mut(medium) else {
            return Err(out_of_range("media", "media", medium, len));
        };
        let what = if index { "index" } else { "speed" };
        if m.profile.is_some() {
            return Err(SceneError::new(
                format!("media.{}.profile", m.name),
                format!("a `profile` medium has no single {what} to set: its knots give its speed"),
            ));
        }
        let v = positive(format!("media.{}.{what}", m.name), value)?;
        let slowness = if index { v } else { 1.0 / v };
        if !(slowness.is_finite() && slowness > 0.0) {
            return Err(SceneError::new(
                format!("media.{}", m.name),
                "slowness (1 / speed) is not a finite positive number",
            ));
        }
        // An attenuation given per wavelength, in dB per unit length at the new speed.
        let per_length = match &self.amplitudes {
            Some(a) => match (a.attenuation_per_wavelength[medium], a.frequency) {
                (Some(per), Some(f)) => {
                    let key = || format!("media.{}.{what}", m.name);
                    Some(per_unit_length(key, per, f, index, value)?)
                }
                _ => None,
            },
            None => None,
        };
        // The document's check of kinds, on the media as they would be.
        let was = m.index;
        m.index = index;
        if let Err(e) = one_kind_of_medium(&self.media) {
            self.media[medium].index = was;
            return Err(e);
        }
        if index && self.media[medium].gradient.is_some() {
            self.media[medium].index = was;
            return Err(SceneError::new(
                format!("media.{}.gradient", self.media[medium].name),
                "only a `speed` medium takes a gradient, not an `index` medium",
            ));
        }
        let old = self.media[medium].slowness;
        self.media[medium].slowness = slowness;
        let points =
            super::scene_points(&self.interfaces, &self.sources, &self.receivers, &[], None);
        if let Err(e) = super::speeds_stay_positive(&mut self.media, points, self.domain) {
            self.media[medium].slowness = old;
            self.media[medium].index = was;
            return Err(e);
        }
        if let (Some(db), Some(a)) = (per_length, &mut self.amplitudes) {
            a.attenuation[medium] = db;
            a.attenuates = a.attenuation.iter().any(|&db| db > 0.0);
        }
        self.document
            .set_medium_value(&self.media[medium].name, index, value);
        Ok(())
    }

    /// The range check of region lookup, when the scene needs it.
    fn check_range(&self) -> Result<(), SceneError> {
        if !self.needs_regions() {
            return Ok(());
        }
        check_region_range(scene_points(
            &self.interfaces,
            &self.sources,
            &self.receivers,
            &self.media,
            self.domain,
        ))
    }
}
