//! A validated scene written back as its document ([`Scene::to_spec`], [`Scene::to_json`]):
//! what validation turns into other numbers (a speed into a slowness, an absorption into a
//! coefficient, a duration into samples) is kept as the document gave it, so that the
//! document reads back to the same scene, bit for bit.

use super::{
    ExtrusionSpec, InterfaceSpec, ReceiverGridSpec, ReceiversSpec, Scene, SceneSpec, SolverOptions,
    SolverSpec,
};

/// The scene document without what the validated scene holds exactly and its edits change
/// (the sources, the receivers, the interfaces' points, the solver settings): every other key
/// as given, a medium's `speed` or `index` as last set.
#[derive(Clone, Debug, Default)]
pub(super) struct Document(SceneSpec);

impl Document {
    /// The parts of `spec` that the validated scene does not hold as given.
    pub(super) fn of(spec: &SceneSpec) -> Document {
        // Field by field (not a clone of the whole): the points would be copied for nothing.
        let SceneSpec {
            description,
            media,
            background,
            domain,
            interfaces,
            sources: _,
            receivers,
            paths,
            solver: _,
            search,
            amplitudes,
            impulse_response,
            transmission_loss,
            extrusion,
        } = spec;
        let interfaces = interfaces
            .iter()
            .map(|(name, i)| {
                let shape = InterfaceSpec {
                    points: Vec::new(),
                    closed: i.closed,
                    reflection: i.reflection,
                };
                (name.clone(), shape)
            })
            .collect();
        Document(SceneSpec {
            description: description.clone(),
            media: media.clone(),
            background: background.clone(),
            domain: *domain,
            interfaces,
            sources: Vec::new(),
            // A grid as given (a list is the scene's own points).
            receivers: match receivers {
                ReceiversSpec::Grid { grid } => ReceiversSpec::Grid { grid: *grid },
                ReceiversSpec::Points(_) => ReceiversSpec::default(),
            },
            paths: paths.clone(),
            solver: None,
            search: search.clone(),
            amplitudes: *amplitudes,
            impulse_response: *impulse_response,
            transmission_loss: *transmission_loss,
            // The heights are the scene's own, as its points.
            extrusion: extrusion.as_ref().map(|e| ExtrusionSpec {
                source_heights: Vec::new(),
                receiver_heights: Vec::new(),
                ..e.clone()
            }),
        })
    }

    /// The receivers' grid as given, if the document gave one and no edit has moved a
    /// receiver since.
    pub(super) fn receiver_grid(&self) -> Option<ReceiverGridSpec> {
        match self.0.receivers {
            ReceiversSpec::Grid { grid } => Some(grid),
            ReceiversSpec::Points(_) => None,
        }
    }

    /// A receiver moved: the document lists the receivers' points from now on.
    pub(super) fn forget_receiver_grid(&mut self) {
        self.0.receivers = ReceiversSpec::default();
    }

    /// Medium `name` now has the refractive index `value` (when `index`) or the speed `value`.
    pub(super) fn set_medium_value(&mut self, name: &str, index: bool, value: f64) {
        if let Some(m) = self.0.media.get_mut(name) {
            (m.speed, m.index) = if index {
                (None, Some(value))
            } else {
                (Some(value), None)
            };
        }
    }
}

/// The `solver` section of `options`: the settings that differ from the defaults (`None`
/// when none does).
fn solver_spec(options: SolverOptions) -> Option<SolverSpec> {
    let d = SolverOptions::default();
    let spec = SolverSpec {
        tolerance: (options.tolerance.to_bits() != d.tolerance.to_bits())
            .then_some(options.tolerance),
        max_iterations: (options.max_iterations != d.max_iterations)
            .then_some(options.max_iterations as u64),
        stationary: (options.stationary != d.stationary).then_some(options.stationary),
        derivatives: (options.derivatives != d.derivatives).then_some(options.derivatives),
        max_work: (options.max_work != d.max_work).then_some(options.max_work),
    };
    let empty = spec.tolerance.is_none()
        && spec.max_iterations.is_none()
        && spec.stationary.is_none()
        && spec.derivatives.is_none()
        && spec.max_work.is_none();
    (!empty).then_some(spec)
}

impl Scene {
    /// The scene as a document: one that [`Scene::from_spec`] turns into this scene again,
    /// bit for bit, edits included ([`set_source`](Self::set_source),
    /// [`set_receiver`](Self::set_receiver), [`set_interface_points`](Self::set_interface_points),
    /// [`set_medium_speed`](Self::set_medium_speed), [`set_medium_index`](Self::set_medium_index),
    /// [`set_solver`](Self::set_solver)). Every key keeps the value it was given (a medium's
    /// `speed`, not the slowness computed from it; an absorption, not its coefficient), the
    /// points are the scene's own, and the `solver` section lists the settings that differ
    /// from the defaults. (One setting has no document: a `max_iterations` of 0, which
    /// [`set_solver`](Self::set_solver) allows and a document refuses.)
    ///
    /// ```
    /// use eigenray::{Point, Scene};
    /// let mut scene = Scene::from_json(r#"{
    ///     "media": { "water": { "speed": 1500.0 } },
    ///     "interfaces": { "surface": { "points": [[-10, 0], [10, 0]] } },
    ///     "sources": [[0, -5]], "receivers": [[8, -3]],
    ///     "paths": [{ "steps": [{ "reflect": "surface" }], "media": ["water", "water"] }]
    /// }"#).unwrap();
    /// scene.set_receiver(0, Point::new(0.1, -0.3)).unwrap();
    /// scene.set_medium_speed(0, 1480.0).unwrap();
    /// let spec = scene.to_spec();
    /// assert_eq!(spec.receivers, vec![[0.1, -0.3]].into());
    /// assert_eq!(spec.media["water"].speed, Some(1480.0));
    /// let again = Scene::from_spec(&spec).unwrap();
    /// assert_eq!(again.media(), scene.media());
    /// ```
    pub fn to_spec(&self) -> SceneSpec {
        let xy = |p: &crate::geom::Point| [p.x, p.y];
        let mut spec = self.document.0.clone();
        spec.sources = self.sources.iter().map(xy).collect();
        if self.document.receiver_grid().is_none() {
            spec.receivers = ReceiversSpec::Points(self.receivers.iter().map(xy).collect());
        }
        for i in &self.interfaces {
            if let Some(shape) = spec.interfaces.get_mut(&i.name) {
                shape.points = i.polyline.vertices().iter().map(xy).collect();
            }
        }
        spec.solver = solver_spec(self.solver);
        if let (Some(e), Some(x)) = (&mut spec.extrusion, &self.extrusion) {
            e.source_heights = x.source_heights.clone();
            e.receiver_heights = x.receiver_heights.clone();
            if self.document.receiver_grid().is_none() {
                // Moved receivers are a list, each with its own height.
                e.grid_height = None;
            }
        }
        spec
    }

    /// The receivers' grid as the document gave it (`"receivers": {"grid": ...}`), while no
    /// edit has moved a receiver; [`receivers`](Self::receivers) holds its points, receiver
    /// `ix · ny + iy` at `(x[ix], y[iy])`.
    pub fn receiver_grid(&self) -> Option<ReceiverGridSpec> {
        self.document.receiver_grid()
    }

    /// The scene as a JSON document ([`to_spec`](Self::to_spec), written compactly): one that
    /// [`Scene::from_json`] reads back to this scene, bit for bit (every number is written
    /// with the shortest digits that read back to it). What a scene is shipped as to another
    /// process (the Python package pickles a `Scene` and a `Tracer` as it).
    ///
    /// ```
    /// use eigenray::Scene;
    /// let scene = Scene::from_json(r#"{
    ///     "media": { "air": { "index": 1.0 }, "glass": { "index": 1.5 } },
    ///     "interfaces": { "face": { "points": [[-1, 0], [2, 0]] } },
    ///     "sources": [[0, 1]], "receivers": [[1, -1]],
    ///     "paths": [{ "steps": [{ "refract": "face" }], "media": ["air", "glass"] }]
    /// }"#).unwrap();
    /// let again = Scene::from_json(&scene.to_json()).unwrap();
    /// assert_eq!(again.to_json(), scene.to_json());
    /// assert_eq!(again.media()[1].slowness, 1.5);
    /// ```
    pub fn to_json(&self) -> String {
        let spec = self.to_spec();
        match &spec.extrusion {
            Some(e) => {
                // The points' heights back as their third coordinates.
                let mut value =
                    serde_json::to_value(&spec).expect("a scene document is plain JSON data");
                super::extrusion::join_heights(e, &mut value);
                value.to_string()
            }
            None => serde_json::to_string(&spec).expect("a scene document is plain JSON data"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo;
    use crate::geom::Point;
    use crate::scene::StationaryMode;

    /// Whether two scenes are the same to the bit: `Debug` prints every `f64` so that it
    /// reads back to the same bits, and every field (the segment index included).
    fn same(a: &Scene, b: &Scene) -> bool {
        format!("{a:?}") == format!("{b:?}")
    }

    /// `scene` written and read back, as JSON and as a spec.
    fn round_trip(scene: &Scene, what: &str) {
        let json = scene.to_json();
        let again = Scene::from_json(&json).unwrap_or_else(|e| panic!("{what}: {e}\n{json}"));
        assert!(same(&again, scene), "{what}: the scene read back differs");
        assert_eq!(again.to_json(), json, "{what}");
        let spec = Scene::from_spec(&scene.to_spec()).unwrap();
        assert!(same(&spec, scene), "{what}: the spec read back differs");
    }

    /// Every scene file under `fixtures/` (but the invalid ones).
    fn fixture_scenes() -> Vec<(String, Scene)> {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
        let mut dirs = vec![root];
        let mut out = Vec::new();
        while let Some(dir) = dirs.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                let name = path.display().to_string();
                if path.is_dir() {
                    if !name.ends_with("invalid") {
                        dirs.push(path);
                    }
                } else if name.ends_with(".json") && !name.contains(".expected.") {
                    let text = std::fs::read_to_string(&path).unwrap();
                    // Reference outputs (`*.ref.json`) are not scenes.
                    if let Ok(scene) = Scene::from_json(&text) {
                        out.push((name, scene));
                    }
                }
            }
        }
        out
    }

    #[test]
    fn every_fixture_reads_back_bit_for_bit() {
        let scenes = fixture_scenes();
        assert!(scenes.len() >= 30, "{} fixture scenes", scenes.len());
        for (name, scene) in &scenes {
            round_trip(scene, name);
        }
    }

    #[test]
    fn the_benchmark_scenes_read_back_bit_for_bit() {
        let specs = [
            ("air_water", demo::air_water(500, 7)),
            ("layer_stack", demo::layer_stack(10, 200)),
            ("dipping_stack", demo::dipping_stack(8, 200)),
            ("undulating_stack", demo::undulating_stack(5, 40, 100)),
            ("sea_floor", demo::sea_floor(1000, 300)),
        ];
        for (name, spec) in &specs {
            round_trip(&Scene::from_spec(spec).unwrap(), name);
        }
    }

    /// A speed whose slowness does not give it back (1 / (1 / v) ≠ v), an absorption whose
    /// coefficient does not, a duration that is not samples / rate, a negative zero, a
    /// description: each kept as given.
    #[test]
    fn values_that_validation_rounds_are_kept_as_given() {
        let speed = (1..2000)
            .map(|k| 1.0 + k as f64 * 0.0137)
            .find(|&v: &f64| 1.0 / (1.0 / v) != v)
            .expect("a speed that 1 / (1 / v) does not give back");
        let json = format!(
            r#"{{
            "description": "kept",
            "media": {{ "water": {{ "speed": {speed}, "density": 1000, "attenuation": 0.25 }},
                        "mud": {{ "speed": 1700 }} }},
            "background": "water",
            "interfaces": {{ "surface": {{ "points": [[-10, -0.0], [10, 0]],
                                           "reflection": {{ "absorption": 0.3 }} }},
                             "floor": {{ "points": [[-10, -10], [10, -10]],
                                         "reflection": "media" }} }},
            "sources": [[0, -5]], "receivers": [[8, -3], [-0.0, -1]],
            "search": {{ "max_steps": 2, "interfaces": ["surface", "floor"] }},
            "solver": {{ "tolerance": 1e-10, "max_work": 12345 }},
            "amplitudes": {{ "source": "point", "frequency": 250 }},
            "impulse_response": {{ "rate": 8000, "duration": 0.12345, "taps": 41 }}
        }}"#
        );
        let scene = Scene::from_json(&json).unwrap();
        round_trip(&scene, "rounded values");
        let spec = scene.to_spec();
        assert_eq!(spec.media["water"].speed, Some(speed));
        assert_eq!(spec.description.as_deref(), Some("kept"));
        let ReceiversSpec::Points(receivers) = &spec.receivers else {
            panic!("a list of receivers written as a grid")
        };
        assert_eq!(receivers[1][0].to_bits(), (-0.0f64).to_bits());
        let ir = spec.impulse_response.unwrap();
        assert_eq!((ir.duration, ir.taps), (0.12345, Some(41)));
        let solver = spec.solver.unwrap();
        assert_eq!(solver.tolerance, Some(1e-10));
        assert_eq!(
            (solver.max_iterations, solver.max_work),
            (None, Some(12345))
        );
    }

    /// A receiver grid is written as given, and read back to the same receivers; once a
    /// receiver moves, the document lists the receivers instead.
    #[test]
    fn a_receiver_grid_is_kept_until_a_receiver_moves() {
        let json = r#"{
            "media": { "water": { "speed": 1500 } },
            "interfaces": { "surface": { "points": [[-10, 0], [6000, 0]] } },
            "sources": [[0, -5]],
            "receivers": { "grid": { "x": [100, 5000, 197], "y": [-1, -99, 50] } },
            "paths": [{ "steps": [{ "reflect": "surface" }], "media": ["water", "water"] }]
        }"#;
        let mut scene = Scene::from_json(json).unwrap();
        assert_eq!(scene.receivers().len(), 197 * 50);
        assert_eq!(scene.receivers()[50], Point::new(125.0, -1.0));
        assert_eq!(scene.receivers()[197 * 50 - 1], Point::new(5000.0, -99.0));
        let grid = ReceiverGridSpec {
            x: [100.0, 5000.0, 197.0],
            y: [-1.0, -99.0, 50.0],
        };
        assert_eq!(scene.receiver_grid(), Some(grid));
        round_trip(&scene, "grid");
        assert!(
            scene.to_json().contains(
                r#""receivers":{"grid":{"x":[100.0,5000.0,197.0],"y":[-1.0,-99.0,50.0]}}"#
            )
        );
        scene.set_receiver(7, Point::new(1.0, -2.0)).unwrap();
        assert_eq!(scene.receiver_grid(), None);
        round_trip(&scene, "grid after set_receiver");
        assert!(
            matches!(scene.to_spec().receivers, ReceiversSpec::Points(ref p) if p.len() == 197 * 50)
        );
    }

    /// After each edit the scene writes the document of the edited scene.
    #[test]
    fn edits_are_written() {
        let mut scene = Scene::from_spec(&demo::layer_stack(3, 20)).unwrap();
        round_trip(&scene, "before");
        let speed = 1.0 / 3.0;
        scene.set_medium_speed(1, speed).unwrap();
        round_trip(&scene, "set_medium_speed");
        assert_eq!(
            scene.to_spec().media[&scene.media()[1].name].speed,
            Some(speed)
        );
        scene.set_receiver(3, Point::new(0.3, -3.7)).unwrap();
        round_trip(&scene, "set_receiver");
        scene.set_source(0, Point::new(-0.25, 1.1)).unwrap();
        round_trip(&scene, "set_source");
        let bent = [
            Point::new(-100.0, -1.0),
            Point::new(0.5, -1.2),
            Point::new(100.0, -1.0),
        ];
        scene.set_interface_points(0, &bent).unwrap();
        round_trip(&scene, "set_interface_points");
        let options = SolverOptions {
            stationary: StationaryMode::All,
            derivatives: true,
            ..scene.solver()
        };
        scene.set_solver(options).unwrap();
        round_trip(&scene, "set_solver");
        // A refused edit changes nothing.
        let before = scene.to_json();
        assert!(scene.set_medium_index(1, 1.5).is_err()); // a mix of speeds and indices
        assert!(scene.set_medium_speed(1, -1.0).is_err());
        assert_eq!(scene.to_json(), before);

        let mut optics = Scene::from_spec(&demo::air_water(20, 3)).unwrap();
        optics.set_medium_index(1, 1.3330000000000002).unwrap();
        round_trip(&optics, "set_medium_index");
        assert_eq!(
            optics.to_spec().media["water"].index,
            Some(1.3330000000000002)
        );
    }
}
