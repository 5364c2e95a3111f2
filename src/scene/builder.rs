//! Scenes in code that read like the JSON: constructors of the spec's parts and
//! [`SceneBuilder`].

use std::sync::Arc;

use super::{
    AmplitudesSpec, InterfaceSpec, MediumSpec, PathSpec, Scene, SceneError, SceneSpec, SearchSpec,
    SolverSpec, StepSpec,
};

impl MediumSpec {
    /// A medium of propagation speed `speed` (`{"speed": 343}`); time = length / speed.
    pub fn speed(speed: f64) -> MediumSpec {
        MediumSpec {
            speed: Some(speed),
            ..MediumSpec::default()
        }
    }

    /// A medium of refractive index `index` (`{"index": 1.5}`); time = index × length.
    pub fn index(index: f64) -> MediumSpec {
        MediumSpec {
            index: Some(index),
            ..MediumSpec::default()
        }
    }

    /// The same medium claiming the region around `point` (`"at": [x, y]`).
    pub fn at(self, point: impl Into<[f64; 2]>) -> MediumSpec {
        MediumSpec {
            at: Some(point.into()),
            ..self
        }
    }
}

impl InterfaceSpec {
    /// An open polyline through `points` (`{"points": [...]}`): `[x, y]` arrays, `(x, y)`
    /// pairs or [`Point`](crate::Point)s.
    pub fn open<P: Into<[f64; 2]>>(points: impl IntoIterator<Item = P>) -> InterfaceSpec {
        InterfaceSpec {
            points: points.into_iter().map(Into::into).collect(),
            closed: false,
            reflection: None,
        }
    }

    /// A closed polygon through `points` (`"closed": true`): the last vertex joins the first.
    pub fn closed<P: Into<[f64; 2]>>(points: impl IntoIterator<Item = P>) -> InterfaceSpec {
        InterfaceSpec {
            closed: true,
            ..InterfaceSpec::open(points)
        }
    }
}

impl StepSpec {
    /// A reflection off the interface named `interface` (`{"reflect": "north"}`).
    pub fn reflect(interface: impl Into<String>) -> StepSpec {
        StepSpec::Reflect(interface.into())
    }

    /// A refraction through the interface named `interface` (`{"refract": "surface"}`).
    pub fn refract(interface: impl Into<String>) -> StepSpec {
        StepSpec::Refract(interface.into())
    }
}

impl PathSpec {
    /// A path through `steps`, its media from region lookup (`{"steps": [...]}`).
    pub fn new(steps: impl IntoIterator<Item = StepSpec>) -> PathSpec {
        PathSpec {
            name: None,
            steps: steps.into_iter().collect(),
            media: None,
        }
    }

    /// The direct path: no steps (`{"steps": []}`).
    pub fn direct() -> PathSpec {
        PathSpec::new([])
    }

    /// The same path with a name (`"name": "north wall"`).
    pub fn named(self, name: impl Into<String>) -> PathSpec {
        PathSpec {
            name: Some(name.into()),
            ..self
        }
    }

    /// The same path with the medium of every leg given (`"media": ["air", "water"]`, one
    /// more than the steps).
    pub fn media<S: Into<String>>(self, media: impl IntoIterator<Item = S>) -> PathSpec {
        PathSpec {
            media: Some(media.into_iter().map(Into::into).collect()),
            ..self
        }
    }
}

/// A scene in code, key by key as in the JSON; [`build`](Self::build) validates it as
/// [`Scene::from_spec`] does (and refuses a name given twice, as the JSON reader does).
///
/// ```
/// use eigenray::{InterfaceSpec, MediumSpec, PathSpec, Scene, StepSpec, Tracer};
/// let scene = Scene::builder()
///     .medium("air", MediumSpec::index(1.0))
///     .medium("water", MediumSpec::index(1.333))
///     .interface("surface", InterfaceSpec::open([[-1.0, 0.0], [2.0, 0.0]]))
///     .source([0.0, 1.0])
///     .receiver([1.0, -1.0])
///     .path(PathSpec::new([StepSpec::refract("surface")]).media(["air", "water"]))
///     .build()?;
/// let rays = Tracer::new(scene)?.trace_all();
/// assert!((rays[0].time - 2.6017642).abs() < 1e-6);
/// # Ok::<(), eigenray::SceneError>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct SceneBuilder {
    spec: SceneSpec,
    /// The first name given twice.
    twice: Option<SceneError>,
}

impl SceneBuilder {
    /// An empty scene.
    pub fn new() -> SceneBuilder {
        SceneBuilder::default()
    }

    /// Notes `name` under `key` given twice (the first such name is the error).
    fn once(&mut self, taken: bool, key: &str, name: &str) {
        if taken && self.twice.is_none() {
            self.twice = Some(SceneError::new(
                format!("{key}.{name}"),
                format!("the name `{name}` is given twice (each name may appear once)"),
            ));
        }
    }

    /// `"description"`: free text.
    pub fn description(mut self, text: impl Into<String>) -> SceneBuilder {
        self.spec.description = Some(text.into());
        self
    }

    /// A medium under `"media"` (see [`MediumSpec::speed`], [`MediumSpec::index`]).
    pub fn medium(mut self, name: impl Into<String>, medium: MediumSpec) -> SceneBuilder {
        let name = name.into();
        let taken = self.spec.media.insert(name.clone(), medium).is_some();
        self.once(taken, "media", &name);
        self
    }

    /// `"background"`: the medium of every region that no `at` claims.
    pub fn background(mut self, medium: impl Into<String>) -> SceneBuilder {
        self.spec.background = Some(medium.into());
        self
    }

    /// `"domain"`: the box `[[xmin, ymin], [xmax, ymax]]` whose edges close regions.
    pub fn domain(mut self, min: impl Into<[f64; 2]>, max: impl Into<[f64; 2]>) -> SceneBuilder {
        self.spec.domain = Some([min.into(), max.into()]);
        self
    }

    /// An interface under `"interfaces"` (see [`InterfaceSpec::open`],
    /// [`InterfaceSpec::closed`]).
    pub fn interface(mut self, name: impl Into<String>, interface: InterfaceSpec) -> SceneBuilder {
        let name = name.into();
        let taken = self
            .spec
            .interfaces
            .insert(name.clone(), interface)
            .is_some();
        self.once(taken, "interfaces", &name);
        self
    }

    /// One more source.
    pub fn source(mut self, point: impl Into<[f64; 2]>) -> SceneBuilder {
        self.spec.sources.push(point.into());
        self
    }

    /// More sources.
    pub fn sources<P: Into<[f64; 2]>>(
        mut self,
        points: impl IntoIterator<Item = P>,
    ) -> SceneBuilder {
        self.spec.sources.extend(points.into_iter().map(Into::into));
        self
    }

    /// One more receiver.
    pub fn receiver(mut self, point: impl Into<[f64; 2]>) -> SceneBuilder {
        self.spec.receivers.points_mut().push(point.into());
        self
    }

    /// More receivers.
    pub fn receivers<P: Into<[f64; 2]>>(
        mut self,
        points: impl IntoIterator<Item = P>,
    ) -> SceneBuilder {
        self.spec
            .receivers
            .points_mut()
            .extend(points.into_iter().map(Into::into));
        self
    }

    /// One more path (see [`PathSpec::new`]).
    pub fn path(mut self, path: PathSpec) -> SceneBuilder {
        self.spec.paths.push(path);
        self
    }

    /// `"solver"`: the solver's settings.
    pub fn solver(mut self, solver: SolverSpec) -> SceneBuilder {
        self.spec.solver = Some(solver);
        self
    }

    /// `"search"`: automatic sequences.
    pub fn search(mut self, search: SearchSpec) -> SceneBuilder {
        self.spec.search = Some(search);
        self
    }

    /// `"amplitudes"`: every timed ray also carries its amplitude.
    pub fn amplitudes(mut self, amplitudes: AmplitudesSpec) -> SceneBuilder {
        self.spec.amplitudes = Some(amplitudes);
        self
    }

    /// The document so far (to serialize it, or to edit it as plain data).
    pub fn spec(&self) -> &SceneSpec {
        &self.spec
    }

    /// The validated scene.
    ///
    /// # Errors
    /// A name given twice, or what [`Scene::from_spec`] refuses.
    pub fn build(self) -> Result<Scene, SceneError> {
        match self.twice {
            Some(e) => Err(e),
            None => Scene::from_spec(&self.spec),
        }
    }

    /// The validated scene in an `Arc`, for tracers that share it.
    ///
    /// # Errors
    /// As [`build`](Self::build).
    pub fn build_shared(self) -> Result<Arc<Scene>, SceneError> {
        self.build().map(Arc::new)
    }
}

impl Scene {
    /// A scene in code, key by key as in the JSON (see [`SceneBuilder`]).
    pub fn builder() -> SceneBuilder {
        SceneBuilder::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The builder gives the document the JSON gives, and refuses a name given twice.
    #[test]
    fn the_builder_reads_like_the_json() {
        let json = r#"{
            "media": { "air": { "speed": 343.0, "at": [3, 2] }, "wood": { "speed": 3900.0 } },
            "background": "wood",
            "domain": [[-1, -1], [7, 5]],
            "interfaces": {
                "room": { "points": [[0, 0], [6, 0], [6, 4], [0, 4]], "closed": true },
                "screen": { "points": [[2, 1], [2, 3]] }
            },
            "sources": [[1, 1]], "receivers": [[5, 3], [4, 1]],
            "paths": [
                { "name": "direct", "steps": [] },
                { "steps": [{ "reflect": "room" }], "media": ["air", "air"] },
                { "steps": [{ "refract": "room" }, { "reflect": "screen" }] }
            ]
        }"#;
        let built = Scene::builder()
            .medium("air", MediumSpec::speed(343.0).at([3.0, 2.0]))
            .medium("wood", MediumSpec::speed(3900.0))
            .background("wood")
            .domain([-1.0, -1.0], [7.0, 5.0])
            .interface(
                "room",
                InterfaceSpec::closed([(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)]),
            )
            .interface(
                "screen",
                InterfaceSpec::open([crate::Point::new(2.0, 1.0), crate::Point::new(2.0, 3.0)]),
            )
            .source([1.0, 1.0])
            .receivers([[5.0, 3.0], [4.0, 1.0]])
            .path(PathSpec::direct().named("direct"))
            .path(PathSpec::new([StepSpec::reflect("room")]).media(["air", "air"]))
            .path(PathSpec::new([
                StepSpec::refract("room"),
                StepSpec::reflect("screen"),
            ]));
        let read = SceneSpec::from_json(json).unwrap();
        let text = |s: &SceneSpec| serde_json::to_string(s).unwrap();
        assert_eq!(text(built.spec()), text(&read));
        assert!(built.build().is_ok());

        let twice = Scene::builder()
            .medium("air", MediumSpec::speed(1.0))
            .medium("air", MediumSpec::speed(2.0))
            .build()
            .unwrap_err();
        assert_eq!(
            twice.to_string(),
            "media.air: the name `air` is given twice (each name may appear once)"
        );
    }
}
