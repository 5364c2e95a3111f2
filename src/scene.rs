//! Scenes: the JSON document (`SceneSpec`), its validation, and the validated `Scene`.

use std::collections::{BTreeMap, HashMap};
use std::fmt;

use serde::{Deserialize, Deserializer, Serialize};

use crate::bvh::Bvh;
use crate::geom::{Aabb, Point, Segment, SegmentContact, Vec2, orient, segment_contact};
use crate::leg::profile::Profile;
use crate::leg::{ArcFrame, EndsOn, LegMedium, Linear, Uniform};
use crate::polyline::{Polyline, PolylineError};

mod amplitudes;
mod builder;
mod crossings;
mod document;
mod extrusion;
mod grid;
mod impulse;
mod names;
mod transmission;
mod update;

pub use amplitudes::{
    Amplitudes, AmplitudesSpec, AttenuationSpec, MAX_ATTENUATION, Polarization, Reflection,
    ReflectionSpec, SourceModel, Waves,
};
pub use builder::SceneBuilder;
pub use extrusion::{CEILING, Extrusion, ExtrusionSpec, FLOOR};
pub use grid::{ReceiverGridSpec, ReceiversSpec};
pub use impulse::{
    DEFAULT_TAPS, ImpulseResponseOptions, ImpulseResponseSpec, MAX_RATE, MAX_SAMPLES, MAX_TAPS,
};
pub use transmission::{TransmissionLossMode, TransmissionLossSpec};

/// Default relative tolerance on the stationarity residual.
pub const DEFAULT_TOLERANCE: f64 = 1e-12;
/// Default iteration limit per ray.
pub const DEFAULT_MAX_ITERATIONS: usize = 100;
/// Largest `solver.max_iterations` accepted (so that no scene can make a ray run for ever).
pub const MAX_ITERATIONS_LIMIT: usize = 100_000;
/// Default `solver.max_work`: the work budget of each complete search (per triple of
/// `"stationary": "all"`, per source–receiver pair of a `search`). A unit of work is a point
/// moved by a Newton step or weighed in a bound (about 35 ns of one core): 2^25 units are
/// about a second, whatever the scene.
pub const DEFAULT_MAX_WORK: u64 = 1 << 25;
/// Largest `solver.max_work` accepted: 2^40 units, about ten hours of one core per search.
pub const MAX_WORK_LIMIT: u64 = 1 << 40;
pub(crate) use crate::options::MAX_SEARCH_STEPS;

/// An invalid scene: the key that holds the first problem, and what is wrong with it.
///
/// Displays as `key: message`, for example
/// `interfaces.surface.points: needs at least 2 distinct points`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneError {
    /// Where the problem is, as a path of keys (`media.water.speed`, `paths[1].steps[0]`).
    pub key: String,
    /// What is wrong.
    pub message: String,
}

impl SceneError {
    /// A new error at `key`.
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError {
            key: key.into(),
            message: message.into(),
        }
    }

    /// `text` with every character that must not reach a terminal or a log as it is (control
    /// characters, line separators, bidirectional overrides, non-characters) as `\u{hex}`:
    /// what this error's `Display` does to the names it quotes. For messages of your own that
    /// quote user input.
    pub fn escape_text(text: &str) -> String {
        escape_text(text)
    }
}

impl fmt::Display for SceneError {
    /// `key: message`, with control characters, line and paragraph separators, bidirectional
    /// overrides and non-characters escaped as `\u{..}`: names come from the user, and a
    /// terminal must not act on them.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_escaped(f, &self.key)?;
        f.write_str(": ")?;
        write_escaped(f, &self.message)
    }
}

/// Whether `c` must not reach a terminal or a log as it is: control characters (C0, DEL, C1),
/// line and paragraph separators, bidirectional overrides and isolates, and non-characters.
fn needs_escape(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{2028}' | '\u{2029}' | '\u{200e}' | '\u{200f}' | '\u{061c}'
        )
        || ('\u{202a}'..='\u{202e}').contains(&c)
        || ('\u{2066}'..='\u{2069}').contains(&c)
        || ('\u{fdd0}'..='\u{fdef}').contains(&c)
        || (c as u32) & 0xfffe == 0xfffe
}

/// `text` with every character that must not reach a terminal or a log as it is (control
/// characters, line separators, bidirectional overrides, non-characters) as `\u{hex}`: what
/// [`SceneError`]'s `Display` does to the names it quotes.
fn escape_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if needs_escape(c) {
            let _ = fmt::Write::write_fmt(&mut out, format_args!("\\u{{{:x}}}", c as u32));
        } else {
            out.push(c);
        }
    }
    out
}

/// Writes `text` as [`escape_text`] gives it.
fn write_escaped(f: &mut fmt::Formatter<'_>, text: &str) -> fmt::Result {
    f.write_str(&escape_text(text))
}

impl std::error::Error for SceneError {}

/// The scene document exactly as in the JSON format: plain data with names, not yet checked.
///
/// Build one in code or deserialize it, then turn it into a [`Scene`] with
/// [`Scene::from_spec`], which validates everything.
///
/// ```
/// use eigenray::{Scene, SceneSpec};
/// let spec: SceneSpec = serde_json::from_str(r#"{
///     "media": { "air": { "speed": 1.0 }, "water": { "speed": 0.75 } },
///     "interfaces": { "surface": { "points": [[-2, 0], [5, 0]] } },
///     "sources": [[0, 1]], "receivers": [[1, -1]],
///     "paths": [{ "steps": [{ "refract": "surface" }], "media": ["air", "water"] }]
/// }"#).unwrap();
/// let scene = Scene::from_spec(&spec).unwrap();
/// assert_eq!(scene.interfaces().len(), 1);
/// ```
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// Free text, ignored.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Media by name.
    #[serde(deserialize_with = "unique_names")]
    pub media: BTreeMap<String, MediumSpec>,
    /// Medium of every region that no `at` claims.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub background: Option<String>,
    /// `[[xmin, ymin], [xmax, ymax]]`: a box whose edges close regions for lookup.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub domain: Option<[[f64; 2]; 2]>,
    /// Interfaces by name.
    #[serde(default, deserialize_with = "unique_names")]
    pub interfaces: BTreeMap<String, InterfaceSpec>,
    /// Source points.
    pub sources: Vec<[f64; 2]>,
    /// Receivers: a list of points, or a grid of them (`{"grid": {"x": [first, last,
    /// count], "y": [first, last, count]}}`). Required, as before grids.
    pub receivers: ReceiversSpec,
    /// Paths: sequences of interactions (none when the scene only asks for a `search`).
    #[serde(default)]
    pub paths: Vec<PathSpec>,
    /// Solver settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<SolverSpec>,
    /// Automatic sequences: let the tracer generate the step sequences itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search: Option<SearchSpec>,
    /// Amplitudes: every timed ray also carries how much of the wave arrives along it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitudes: Option<AmplitudesSpec>,
    /// Impulse responses: one per (source, receiver), from every timed arrival's amplitude.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub impulse_response: Option<ImpulseResponseSpec>,
    /// Transmission loss: how `--tl` sums the arrivals at each receiver.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transmission_loss: Option<TransmissionLossSpec>,
    /// An extruded room: the plan's height, and its floor's and ceiling's laws (the points'
    /// heights are their third coordinates, which [`SceneSpec::from_json`] moves here).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extrusion: Option<ExtrusionSpec>,
}

/// A JSON object of names: like a `BTreeMap`, but a name given twice is an error (serde's
/// maps keep the last one silently).
fn unique_names<'de, D, V>(d: D) -> Result<BTreeMap<String, V>, D::Error>
where
    D: Deserializer<'de>,
    V: Deserialize<'de>,
{
    struct Names<V>(std::marker::PhantomData<V>);
    impl<'de, V: Deserialize<'de>> serde::de::Visitor<'de> for Names<V> {
        type Value = BTreeMap<String, V>;
        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("an object of names")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(
            self,
            mut map: A,
        ) -> Result<Self::Value, A::Error> {
            let mut out = BTreeMap::new();
            while let Some(name) = map.next_key::<String>()? {
                if out.contains_key(&name) {
                    return Err(serde::de::Error::custom(format!(
                        "the name `{name}` is given twice (each name may appear once)"
                    )));
                }
                let value = map.next_value()?;
                out.insert(name, value);
            }
            Ok(out)
        }
    }
    d.deserialize_map(Names(std::marker::PhantomData))
}

/// A medium: exactly one of `speed` or `index`, and optionally a point inside its region.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MediumSpec {
    /// Propagation speed (> 0); time = length / speed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed: Option<f64>,
    /// Refractive index (> 0); time = index × length.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub index: Option<f64>,
    /// With `speed`: the speed's gradient `[gx, gy]` (speed per length), so that the speed at
    /// `p` is `speed + gradient · p`; rays in the medium are circular arcs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gradient: Option<[f64; 2]>,
    /// Instead of `speed`: the speed profile `[[y, c], ...]` (`y` strictly decreasing, at
    /// least two knots, `c > 0`): the speed is linear in `y` between knots, the nearest
    /// knot's beyond the end knots, and constant in `x` (BELLHOP's `'C'` profile).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile: Option<Vec<[f64; 2]>>,
    /// A point strictly inside the region this medium fills (inside the domain, when there is
    /// one). One point claims one region: two separate pieces of one material are two media.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<[f64; 2]>,
    /// Density (> 0, default 1): with the speed, the impedance ρc (amplitudes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<f64>,
    /// Attenuation (default none; amplitudes): dB per unit length, or dB per wavelength at the
    /// scene's `amplitudes.frequency`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attenuation: Option<AttenuationSpec>,
}

/// An interface polyline.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InterfaceSpec {
    /// Vertices.
    pub points: Vec<[f64; 2]>,
    /// Whether the last vertex joins the first.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub closed: bool,
    /// How it reflects (default rigid; amplitudes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflection: Option<ReflectionSpec>,
}

/// One path: a sequence of interactions and optionally the medium of every leg.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathSpec {
    /// A label.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Interactions in order; empty for the direct ray.
    pub steps: Vec<StepSpec>,
    /// One medium name per leg (`steps.len() + 1`); without it, media come from region lookup.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub media: Option<Vec<String>>,
}

/// One interaction: `{"reflect": NAME}`, `{"refract": NAME}` or
/// `{"diffract": NAME, "vertex": k}`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "StepDocument", into = "StepDocument")]
pub enum StepSpec {
    /// Reflection off the named interface.
    Reflect(String),
    /// Refraction through the named interface.
    Refract(String),
    /// Diffraction at vertex `vertex` (an index into its polyline's points) of the named
    /// interface: the path's point there is the vertex itself.
    Diffract {
        /// The interface.
        interface: String,
        /// The vertex's index in the interface's `points`.
        vertex: u64,
    },
}

/// A step as the document writes it, before the check that it names exactly one kind: the
/// form serde reads, so that a step with both keys or neither gets a message of its own.
#[derive(Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a step, {\"reflect\": NAME}, {\"refract\": NAME} or {\"diffract\": NAME, \"vertex\": k}"
)]
struct StepDocument {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    reflect: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    refract: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    diffract: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    vertex: Option<u64>,
}

impl TryFrom<StepDocument> for StepSpec {
    type Error = String;

    fn try_from(step: StepDocument) -> Result<StepSpec, String> {
        match (step.reflect, step.refract, step.diffract, step.vertex) {
            (Some(name), None, None, None) => Ok(StepSpec::Reflect(name)),
            (None, Some(name), None, None) => Ok(StepSpec::Refract(name)),
            (None, None, Some(interface), Some(vertex)) => {
                Ok(StepSpec::Diffract { interface, vertex })
            }
            (None, None, Some(_), None) => Err("a `diffract` step needs its `vertex` \
                 (`{\"diffract\": NAME, \"vertex\": k}`, k the index in the interface's points)"
                .into()),
            (_, _, None, Some(_)) => Err(
                "`vertex` belongs to a `diffract` step (`{\"diffract\": NAME, \"vertex\": k}`)"
                    .into(),
            ),
            (None, None, None, None) => Err("a step needs `reflect`, `refract` or `diffract` \
                 (`{\"reflect\": NAME}`)"
                .into()),
            _ => Err(
                "a step is one interaction: give one of `reflect`, `refract` or `diffract` \
                 (`{\"reflect\": NAME}`), not several; write two steps for two interactions"
                    .into(),
            ),
        }
    }
}

impl From<StepSpec> for StepDocument {
    fn from(step: StepSpec) -> StepDocument {
        let mut doc = StepDocument {
            reflect: None,
            refract: None,
            diffract: None,
            vertex: None,
        };
        match step {
            StepSpec::Reflect(name) => doc.reflect = Some(name),
            StepSpec::Refract(name) => doc.refract = Some(name),
            StepSpec::Diffract { interface, vertex } => {
                doc.diffract = Some(interface);
                doc.vertex = Some(vertex);
            }
        }
        doc
    }
}

/// Solver settings.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Relative tolerance on the stationarity residual.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// Iteration limit per ray.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_iterations: Option<u64>,
    /// `"one"` (the default): each ray reports the stationary path its start reaches; `"all"`:
    /// each ray reports every stationary path of its sequence.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stationary: Option<StationaryMode>,
    /// Whether each ray with a time also carries the derivatives of its time (`"gradient"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub derivatives: Option<bool>,
    /// The work budget of each complete search (see [`SolverOptions::max_work`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_work: Option<u64>,
}

/// Which stationary paths a ray reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StationaryMode {
    /// The one stationary path that the documented start reaches (or, where that is not
    /// admissible, the earliest admissible one a complete search finds).
    #[default]
    One,
    /// Every stationary path of the sequence, ordered by time.
    All,
}

/// The `search` section: which step sequences the tracer generates.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SearchSpec {
    /// Every sequence of 0 to `max_steps` steps is considered (0: the direct ray). At least
    /// one of `max_steps` and `max_time` is required.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_steps: Option<u64>,
    /// Every arrival with a time of at most `max_time` is listed, of any number of steps
    /// (within `max_steps` when both are given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_time: Option<f64>,
    /// The interfaces the steps may use (default: all).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interfaces: Option<Vec<String>>,
    /// Whether steps may reflect (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflect: Option<bool>,
    /// Whether steps may refract (default true).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refract: Option<bool>,
    /// Whether obstructed paths are listed too (default false).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub obstructed: Option<bool>,
    /// Whether `vertex` (edge-held) arrivals are listed too (default false).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertex: Option<bool>,
    /// Also list edge-diffracted arrivals (`diffract` steps): first order, every vertex that
    /// both ends see (a diffraction counts as a step for `max_steps`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diffraction: Option<bool>,
}

/// The search settings of a validated scene (see [`SearchSpec`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SearchOptions {
    /// The longest sequence considered (`None`: bounded by `max_time` alone).
    pub max_steps: Option<usize>,
    /// The latest arrival listed (`None`: bounded by `max_steps` alone).
    pub max_time: Option<f64>,
    /// Indices of the interfaces the steps may use, increasing.
    pub interfaces: Vec<usize>,
    /// Whether steps may reflect.
    pub reflect: bool,
    /// Whether steps may refract.
    pub refract: bool,
    /// Whether obstructed paths are listed too.
    pub obstructed: bool,
    /// Whether `vertex` (edge-held) arrivals are listed too.
    pub vertex: bool,
    /// Whether diffracted arrivals (`diffract` steps) are listed too: every vertex of the
    /// allowed interfaces that both ends see, once per pair (first order).
    pub diffraction: bool,
}

impl SearchOptions {
    /// The most steps of a sequence: `max_steps`, or without it no bound (`usize::MAX`;
    /// `max_time` bounds the search).
    pub fn step_limit(&self) -> usize {
        self.max_steps.unwrap_or(usize::MAX)
    }

    /// The latest time listed: `max_time`, or without it no bound (infinite).
    pub fn time_limit(&self) -> f64 {
        self.max_time.unwrap_or(f64::INFINITY)
    }
}

/// A medium of a validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// Its name.
    pub name: String,
    /// Slowness: time per unit length (1 / speed, or the refractive index).
    pub slowness: f64,
    /// Whether it was given as a refractive index (optics), not a speed. A scene's media are
    /// all of one kind.
    pub index: bool,
    /// The speed's gradient when the speed is linear in position (`c(p) = 1 / slowness +
    /// gradient · p`: legs are circular arcs); `None` for a uniform medium (a gradient of
    /// zero is one).
    pub gradient: Option<Vec2>,
    /// The speed profile's knots `[y, c]` (`y` strictly decreasing) when the speed is
    /// piecewise linear in `y` (`slowness` is then `1 / c` of the first knot); `None` otherwise.
    pub profile: Option<Vec<[f64; 2]>>,
    /// The least speed of the medium over the scene's extent (its `domain`, else the box of
    /// its points): `1 / slowness` for a uniform medium.
    pub least_speed: f64,
    /// A point inside its region, if given.
    pub at: Option<Point>,
}

impl Medium {
    /// The model of legs through this medium, positions relative to `origin`.
    pub(crate) fn leg_model(&self, origin: Point) -> LegMedium<'static> {
        match self.gradient {
            None => LegMedium::Uniform(Uniform::new(self.slowness)),
            Some(gradient) => LegMedium::Linear(
                Linear {
                    speed: 1.0 / self.slowness,
                    gradient,
                    least_speed: self.least_speed,
                }
                .shifted(origin.to_vec2()),
            ),
        }
    }

    /// The speed profile, when the medium has one.
    pub(crate) fn profile_model(&self) -> Option<Profile> {
        self.profile.as_deref().map(Profile::new)
    }

    /// The speed at `p`.
    pub fn speed_at(&self, p: Point) -> f64 {
        if let Some(model) = self.profile_model() {
            return model.speed_at(p.y);
        }
        match self.gradient {
            None => 1.0 / self.slowness,
            Some(g) => 1.0 / self.slowness + g.dot(p.to_vec2()),
        }
    }
}

/// A named interface of a validated scene.
#[derive(Clone, Debug)]
pub struct Interface {
    /// Its name.
    pub name: String,
    /// Its shape.
    pub polyline: Polyline,
}

/// Reflection, refraction or diffraction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StepKind {
    /// Both legs on the same side of the interface.
    Reflect,
    /// The legs on opposite sides.
    Refract,
    /// The point held at a vertex of the interface (an edge-diffracted path): no unknown.
    Diffract {
        /// The vertex's index in the interface's polyline points.
        vertex: u32,
    },
}

impl StepKind {
    /// Its key in the scene's notation: `reflect`, `refract` or `diffract`.
    pub fn as_str(self) -> &'static str {
        match self {
            StepKind::Reflect => "reflect",
            StepKind::Refract => "refract",
            StepKind::Diffract { .. } => "diffract",
        }
    }

    /// The vertex of a diffraction.
    pub fn vertex(self) -> Option<usize> {
        match self {
            StepKind::Diffract { vertex } => Some(vertex as usize),
            _ => None,
        }
    }
}

/// One interaction of a validated path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Step {
    /// Reflection or refraction.
    pub kind: StepKind,
    /// Index of the interface in [`Scene::interfaces`].
    pub interface: usize,
}

/// A validated path.
#[derive(Clone, Debug, PartialEq)]
pub struct Path {
    /// Its label.
    pub name: Option<String>,
    /// Interactions in order.
    pub steps: Vec<Step>,
    /// Medium index of every leg, when the path gives them.
    pub media: Option<Vec<usize>>,
}

impl Path {
    /// Whether a step of the path is a diffraction.
    pub fn diffracts(&self) -> bool {
        self.steps.iter().any(|s| s.kind.vertex().is_some())
    }
}

/// Solver settings of a validated scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverOptions {
    /// Relative tolerance on the stationarity residual `|∂T/∂sᵢ| / (wᵢ + wᵢ₊₁)`.
    pub tolerance: f64,
    /// Iteration limit per ray.
    pub max_iterations: usize,
    /// Which stationary paths a ray reports.
    pub stationary: StationaryMode,
    /// Whether the output carries each timed ray's [`Gradient`](crate::Gradient).
    pub derivatives: bool,
    /// The work budget of each complete search: of each triple's with `"stationary": "all"`
    /// ([`Tracer::stationary_paths`](crate::Tracer::stationary_paths)), of each source–receiver
    /// pair's over all its sequences in a `search`, and of the default mode's search of a ray
    /// whose start leads to no path (there at most
    /// [`FALLBACK_MAX_WORK`](crate::options::FALLBACK_MAX_WORK)). A search that spends it
    /// stops and says so (`complete: false`, or `not_converged` with the reason
    /// `search_limit`). Units: points moved by Newton steps or weighed in bounds (about 35 ns
    /// each); default [`DEFAULT_MAX_WORK`], at most [`MAX_WORK_LIMIT`].
    pub max_work: u64,
}

impl SolverOptions {
    /// Checks the settings as a scene document's `solver` is checked, except that
    /// `max_iterations` may be 0 (a solve then returns its start: useful to inspect it).
    ///
    /// # Errors
    /// `solver.tolerance` outside `(0, 1)`, `solver.max_iterations` above
    /// [`MAX_ITERATIONS_LIMIT`], or `solver.max_work` outside `1 ..=` [`MAX_WORK_LIMIT`].
    pub fn validate(&self) -> Result<(), SceneError> {
        let t = self.tolerance;
        if !(t.is_finite() && t > 0.0 && t < 1.0) {
            return Err(SceneError::new(
                "solver.tolerance",
                "must be a number in (0, 1)",
            ));
        }
        if self.max_iterations > MAX_ITERATIONS_LIMIT {
            return Err(SceneError::new(
                "solver.max_iterations",
                format!("must be between 1 and {MAX_ITERATIONS_LIMIT}"),
            ));
        }
        if !(1..=MAX_WORK_LIMIT).contains(&self.max_work) {
            return Err(SceneError::new(
                "solver.max_work",
                format!(
                    "must be a whole number between 1 and {MAX_WORK_LIMIT} (2^40; the default \
                     is {DEFAULT_MAX_WORK}, about a second of one core per search)"
                ),
            ));
        }
        Ok(())
    }
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            tolerance: DEFAULT_TOLERANCE,
            max_iterations: DEFAULT_MAX_ITERATIONS,
            stationary: StationaryMode::One,
            derivatives: false,
            max_work: DEFAULT_MAX_WORK,
        }
    }
}

/// One segment of one interface, as indexed scene-wide.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SegmentRef {
    /// Interface index.
    pub interface: u32,
    /// Segment index within the interface.
    pub segment: u32,
}

impl SegmentRef {
    /// No segment (an index no scene has).
    pub const NONE: SegmentRef = SegmentRef {
        interface: u32::MAX,
        segment: u32::MAX,
    };
}

/// A validated scene: media, interfaces, sources, receivers, paths and solver settings, with
/// a scene-wide spatial index of all interface segments.
#[derive(Clone, Debug)]
pub struct Scene {
    media: Vec<Medium>,
    /// Whether a medium's speed has a gradient ([`Scene::curved`]).
    curved: bool,
    background: Option<usize>,
    domain: Option<Aabb>,
    interfaces: Vec<Interface>,
    sources: Vec<Point>,
    receivers: Vec<Point>,
    paths: Vec<Path>,
    solver: SolverOptions,
    search: Option<SearchOptions>,
    segments: Vec<SegmentRef>,
    /// End points of `segments`, in the same order.
    segment_ends: Vec<Segment>,
    segment_bvh: Bvh,
    batch_size: BatchSize,
    amplitudes: Option<Amplitudes>,
    impulse_response: Option<ImpulseResponseOptions>,
    transmission_loss: Option<TransmissionLossMode>,
    /// The extruded room, when the scene is one ([`Scene::extrusion`]).
    extrusion: Option<Extrusion>,
    /// The document's keys as given, for [`Scene::to_spec`].
    document: document::Document,
}

/// A copy of the scene in an `Arc`: what lets [`Tracer::new`](crate::Tracer::new) take a
/// `&Scene` (the tracer owns its copy; the caller keeps its own).
impl From<&Scene> for std::sync::Arc<Scene> {
    fn from(scene: &Scene) -> Self {
        std::sync::Arc::new(scene.clone())
    }
}

/// The sizes of a whole batch of a scene, computed once at validation with checked
/// arithmetic (a scene whose counts would overflow is refused), so that code that allocates
/// for every ray can rely on them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BatchSize {
    /// Rays: sources × receivers × paths.
    pub rays: usize,
    /// Points of all rays: sources × receivers × Σ over paths of (steps + 2).
    pub points: usize,
    /// Leg media of all rays: sources × receivers × Σ over paths of (steps + 1).
    pub legs: usize,
}

impl BatchSize {
    /// Bytes that storing a whole batch takes, given the bytes of one ray's record, of one
    /// point and of one leg's medium (`None` when it does not fit in a `usize`).
    pub fn bytes(&self, per_ray: usize, per_point: usize, per_leg: usize) -> Option<usize> {
        self.rays
            .checked_mul(per_ray)?
            .checked_add(self.points.checked_mul(per_point)?)?
            .checked_add(self.legs.checked_mul(per_leg)?)
    }
}

/// One ray's (source, receiver, path) indices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct RayTriple {
    /// Source index.
    pub source: usize,
    /// Receiver index.
    pub receiver: usize,
    /// Path index.
    pub path: usize,
}

impl RayTriple {
    /// The triple of ray `ray` among `receivers` receivers and `paths` paths a source, in ray
    /// order (source-major, then receiver, then path).
    #[inline]
    pub fn of(ray: usize, receivers: usize, paths: usize) -> RayTriple {
        RayTriple {
            source: ray / (paths * receivers),
            receiver: (ray / paths) % receivers,
            path: ray % paths,
        }
    }
}

/// Largest coordinate magnitude accepted: beyond it distances and times could overflow.
pub const MAX_COORDINATE: f64 = 1e100;
/// Smallest magnitude of a nonzero coordinate accepted: below it products of coordinate
/// differences (orientation tests, squared lengths) could underflow. Within
/// `[MIN_COORDINATE, MAX_COORDINATE]` a scene scaled by any factor gives the same statuses.
pub const MIN_COORDINATE: f64 = 1e-100;
/// Region lookup holds coordinates whose magnitudes lie within `2^REGION_RANGE_BITS` of the
/// largest (its triangulation's exact predicates need exponents within a fixed range): a
/// scene that needs region lookup and has a nonzero coordinate smaller than that is refused.
pub const REGION_RANGE_BITS: i32 = 340;
/// Speeds and indices must lie in `[1 / MAX_SPEED_RATIO, MAX_SPEED_RATIO]`.
pub const MAX_SPEED_RATIO: f64 = 1e100;

fn point(key: &str, p: [f64; 2]) -> Result<Point, SceneError> {
    if !(p[0].is_finite() && p[1].is_finite()) {
        Err(SceneError::new(key, "coordinates must be finite numbers"))
    } else if p[0].abs() > MAX_COORDINATE || p[1].abs() > MAX_COORDINATE {
        Err(SceneError::new(
            key,
            format!("coordinates must lie within ±{MAX_COORDINATE:e} (distances would overflow)"),
        ))
    } else if p.iter().any(|v| *v != 0.0 && v.abs() < MIN_COORDINATE) {
        Err(SceneError::new(
            key,
            format!(
                "a nonzero coordinate must be at least {MIN_COORDINATE:e} in magnitude (smaller \
                 ones underflow in products; measure the scene in smaller units)"
            ),
        ))
    } else {
        Ok(Point::new(p[0], p[1]))
    }
}

fn positive(key: String, v: f64) -> Result<f64, SceneError> {
    if !(v.is_finite() && v > 0.0) {
        Err(SceneError::new(key, "must be a finite number > 0"))
    } else if !(1.0 / MAX_SPEED_RATIO..=MAX_SPEED_RATIO).contains(&v) {
        Err(SceneError::new(
            key,
            format!(
                "must lie between {:e} and {MAX_SPEED_RATIO:e}",
                1.0 / MAX_SPEED_RATIO
            ),
        ))
    } else {
        Ok(v)
    }
}

/// Steps a sequence may have for the complete search of its stationary paths (each assignment
/// of segments is tried with every choice of held vertices, `2^steps` of them): the longest
/// sequence with a refraction (or, with `vertex`, the longest reflect-only sequence whose
/// edge-held arrivals) a `search` lists. Reflections alone go through the beam tree, up to
/// [`MAX_SEARCH_STEPS`].
pub const MAX_STATIONARY_STEPS: usize = 12;

/// The validated `search` section.
fn search_options(
    spec: &SearchSpec,
    interfaces: &[Interface],
) -> Result<SearchOptions, SceneError> {
    if spec.max_steps.is_none() && spec.max_time.is_none() {
        return Err(SceneError::new(
            "search",
            "give `max_steps` (the most steps of a sequence), `max_time` (the latest arrival \
             listed), or both",
        ));
    }
    if let Some(k) = spec.max_steps
        && k > MAX_SEARCH_STEPS as u64
    {
        return Err(SceneError::new(
            "search.max_steps",
            format!("must be at most {MAX_SEARCH_STEPS} (give `max_time` to bound by time)"),
        ));
    }
    if let Some(t) = spec.max_time
        && !(t.is_finite() && t > 0.0)
    {
        return Err(SceneError::new(
            "search.max_time",
            format!("must be finite and positive (got {t})"),
        ));
    }
    let interfaces = match &spec.interfaces {
        None => (0..interfaces.len()).collect(),
        Some(names) => {
            let mut idx: Vec<usize> = Vec::with_capacity(names.len());
            for (j, name) in names.iter().enumerate() {
                let key = format!("search.interfaces[{j}]");
                let i = by_name(interfaces, |i| &i.name, name).ok_or_else(|| {
                    let known = interfaces.iter().map(|i| i.name.as_str());
                    SceneError::new(&key, names::unknown("interface", name, known))
                })?;
                if idx.contains(&i) {
                    return Err(SceneError::new(key, format!("`{name}` is listed twice")));
                }
                idx.push(i);
            }
            idx.sort_unstable();
            idx
        }
    };
    let (reflect, refract) = (spec.reflect.unwrap_or(true), spec.refract.unwrap_or(true));
    if !reflect && !refract && spec.max_steps != Some(0) {
        return Err(SceneError::new(
            "search",
            "`reflect` and `refract` are both false: no step is allowed (set `max_steps` to 0 \
             for the direct ray alone)",
        ));
    }
    Ok(SearchOptions {
        max_steps: spec.max_steps.map(|k| k as usize),
        max_time: spec.max_time,
        interfaces,
        reflect,
        refract,
        obstructed: spec.obstructed.unwrap_or(false),
        vertex: spec.vertex.unwrap_or(false),
        diffraction: spec.diffraction.unwrap_or(false),
    })
}

/// The media of a scene document, in name order: each with its slowness (from its `speed` or
/// its `index`) and its `at` point.
///
/// # Errors
/// `media` when there is none; `media.NAME` (or its `speed`, `index`, `at`) when a medium has
/// neither or both of `speed` and `index`, a slowness that is not finite and positive, or an
/// `at` point that is not finite.
fn media_of(spec: &SceneSpec) -> Result<Vec<Medium>, SceneError> {
    if spec.media.is_empty() {
        return Err(SceneError::new("media", "needs at least one medium"));
    }
    let mut media = Vec::with_capacity(spec.media.len());
    for (name, m) in &spec.media {
        let key = format!("media.{name}");
        let profile = profile_of(&key, m)?;
        let slowness = match (m.speed, m.index) {
            (None, None) if let Some(knots) = &profile => 1.0 / knots[0][1],
            (Some(v), None) => 1.0 / positive(format!("{key}.speed"), v)?,
            (None, Some(n)) => positive(format!("{key}.index"), n)?,
            (Some(_), Some(_)) => {
                return Err(SceneError::new(
                    key,
                    "give exactly one of `speed` or `index`, not both",
                ));
            }
            (None, None) => return Err(SceneError::new(key, "needs `speed` or `index`")),
        };
        if !(slowness.is_finite() && slowness > 0.0) {
            return Err(SceneError::new(
                key,
                "slowness (1 / speed) is not a finite positive number",
            ));
        }
        let at = match m.at {
            Some(p) => Some(point(&format!("{key}.at"), p)?),
            None => None,
        };
        let gradient = match m.gradient {
            Some(_) if m.index.is_some() => {
                return Err(SceneError::new(
                    format!("{key}.gradient"),
                    "only a `speed` medium takes a gradient, not an `index` medium",
                ));
            }
            Some([gx, gy]) => {
                if !(gx.is_finite() && gy.is_finite()) {
                    return Err(SceneError::new(
                        format!("{key}.gradient"),
                        "needs two finite numbers [gx, gy]",
                    ));
                }
                (gx != 0.0 || gy != 0.0).then_some(Vec2::new(gx, gy))
            }
            None => None,
        };
        media.push(Medium {
            name: name.clone(),
            slowness,
            index: m.index.is_some(),
            gradient,
            least_speed: profile.as_ref().map_or(1.0 / slowness, |k| {
                k.iter().map(|k| k[1]).fold(f64::INFINITY, f64::min)
            }),
            profile,
            at,
        });
    }
    one_kind_of_medium(&media)?;
    Ok(media)
}

/// The knots of a medium's `profile`, validated: only instead of `speed` (not with
/// `speed`, `index` or `gradient`), at least two, `y` strictly decreasing, every number
/// finite and `c > 0`.
///
/// # Errors
/// `media.NAME.profile` (or `media.NAME.profile[i]` for one knot; `media.NAME.gradient` for a
/// gradient beside a profile), saying what is wrong.
fn profile_of(key: &str, m: &MediumSpec) -> Result<Option<Vec<[f64; 2]>>, SceneError> {
    let Some(knots) = &m.profile else {
        return Ok(None);
    };
    let at = format!("{key}.profile");
    if m.index.is_some() {
        return Err(SceneError::new(
            at,
            "only a `speed` medium takes a profile, not an `index` medium",
        ));
    }
    if m.speed.is_some() {
        return Err(SceneError::new(
            at,
            "give `speed` or `profile`, not both: the profile gives the speed at every height",
        ));
    }
    if m.gradient.is_some() {
        return Err(SceneError::new(
            format!("{key}.gradient"),
            "a `profile` medium takes no `gradient`: its speed is linear between its knots",
        ));
    }
    if knots.len() < 2 {
        return Err(SceneError::new(
            at,
            format!(
                "needs at least two knots [[y, c], ...], got {}",
                knots.len()
            ),
        ));
    }
    for (i, &[y, c]) in knots.iter().enumerate() {
        if !(y.is_finite() && y.abs() <= MAX_COORDINATE) {
            return Err(SceneError::new(
                format!("{at}[{i}]"),
                format!("y must be a finite number within ±{MAX_COORDINATE:e}, got {y}"),
            ));
        }
        if !(c.is_finite() && c > 0.0) {
            return Err(SceneError::new(
                format!("{at}[{i}]"),
                format!("the speed c must be a finite positive number, got {c}"),
            ));
        }
        if i > 0 && y >= knots[i - 1][0] {
            return Err(SceneError::new(
                format!("{at}[{i}]"),
                format!(
                    "y must strictly decrease from knot to knot (y up, the first knot on \
                     top): {y} follows {}",
                    knots[i - 1][0]
                ),
            ));
        }
    }
    Ok(Some(knots.clone()))
}

/// Sets each medium's least speed over the scene's extent (the `domain`, else the box of
/// `points`, the interfaces' vertices, sources and receivers) and refuses a medium with a
/// gradient whose speed reaches 0 there: the speed is linear, so its least value is at a
/// corner of the box.
///
/// # Errors
/// `media.NAME.gradient` for the first medium whose speed reaches 0, naming the corner.
pub(crate) fn speeds_stay_positive(
    media: &mut [Medium],
    points: impl Iterator<Item = Point>,
    domain: Option<Aabb>,
) -> Result<(), SceneError> {
    let uniform_least = |m: &Medium| {
        m.profile.as_ref().map_or(1.0 / m.slowness, |k| {
            k.iter().map(|k| k[1]).fold(f64::INFINITY, f64::min)
        })
    };
    if media.iter().all(|m| m.gradient.is_none()) {
        for m in media.iter_mut() {
            m.least_speed = uniform_least(m);
        }
        return Ok(());
    }
    let extent = match domain {
        Some(d) => Some(d),
        None => points.fold(None, |b: Option<Aabb>, p| {
            let one = Aabb::from_points(p, p);
            Some(b.map_or(one, |b| b.union(one)))
        }),
    };
    let Some(extent) = extent else {
        return Ok(());
    };
    for m in media.iter_mut() {
        let Some(g) = m.gradient else {
            m.least_speed = uniform_least(m);
            continue;
        };
        let corners = [
            extent.min,
            Point::new(extent.max.x, extent.min.y),
            Point::new(extent.min.x, extent.max.y),
            extent.max,
        ];
        let speed = |p: Point| 1.0 / m.slowness + g.dot(p.to_vec2());
        let least = corners
            .into_iter()
            .min_by(|a, b| speed(*a).total_cmp(&speed(*b)))
            .unwrap_or(extent.min);
        let c = speed(least);
        if !(c > 0.0 && c.is_finite()) {
            let within = if domain.is_some() {
                "the domain"
            } else {
                "the box of the scene's points"
            };
            return Err(SceneError::new(
                format!("media.{}.gradient", m.name),
                format!(
                    "the speed reaches {c} at ({}, {}), a corner of {within}: a medium's speed \
                     must stay positive wherever it is used (a smaller gradient, a larger \
                     speed, or a `domain` that keeps clear of it)",
                    least.x, least.y
                ),
            ));
        }
        m.least_speed = c;
    }
    Ok(())
}

/// Refuses, in a scene with a medium whose speed has a gradient or a profile (curved legs),
/// what curved legs do not reach yet: diffraction, and with a profile refraction and the
/// automatic search off interfaces that are not flat and horizontal. Each of those assumes
/// straight legs (the wedge's straight pieces) or a waveguide of flat walls, so it is
/// refused rather than wrong.
///
/// # Errors
/// `search` (with a profile), `search.diffraction`, the first step a profile scene does not
/// take, or the first `diffract` step.
fn curved_legs_supported(spec: &SceneSpec) -> Result<(), SceneError> {
    let why = "is not available yet with curved legs (a medium with a `gradient` or a \
               `profile`); prescribed paths solve, with `\"stationary\"` `\"one\"` or `\"all\"`";
    let profiled = spec.media.values().any(|m| m.profile.is_some());
    if let Some(search) = &spec.search {
        if search.diffraction == Some(true) {
            let why = if profiled {
                "diffraction is not available yet in a scene with a `profile` medium".to_string()
            } else {
                format!("`true` {why}")
            };
            return Err(SceneError::new("search.diffraction", why));
        }
        if profiled && let Some((name, _)) = spec.interfaces.iter().find(|(_, i)| i.closed) {
            return Err(SceneError::new(
                "search",
                format!(
                    "the automatic search in a scene with a `profile` medium takes open \
                     interfaces only (a surface, a bottom: flat, sloping or polylines); \
                     `interfaces.{name}` is closed"
                ),
            ));
        }
    }
    if profiled {
        for (k, path) in spec.paths.iter().enumerate() {
            for (j, step) in path.steps.iter().enumerate() {
                match step {
                    StepSpec::Reflect(_) => {}
                    StepSpec::Refract(_) => {
                        return Err(SceneError::new(
                            format!("paths[{k}].steps[{j}]"),
                            "a scene with a `profile` medium takes reflections only; refraction \
                             there is not available yet",
                        ));
                    }
                    StepSpec::Diffract { .. } => {}
                }
            }
        }
    }
    for (k, path) in spec.paths.iter().enumerate() {
        if let Some(j) = path
            .steps
            .iter()
            .position(|s| matches!(s, StepSpec::Diffract { .. }))
        {
            return Err(SceneError::new(
                format!("paths[{k}].steps[{j}]"),
                format!("a `diffract` step {why}"),
            ));
        }
    }
    Ok(())
}

/// Refuses a scene that mixes `speed` media with `index` media: a speed gives time in length
/// over the scene's speed unit, an index time in length over the speed of light (c = 1), so a
/// path through both has no time in any one unit.
///
/// # Errors
/// `media.NAME` for the first medium (in name order) of the other kind than the first.
fn one_kind_of_medium(media: &[Medium]) -> Result<(), SceneError> {
    let Some(first) = media.first() else {
        return Ok(());
    };
    let word = |index: bool| if index { "an `index`" } else { "a `speed`" };
    let (first, kind) = (&first.name, first.index);
    match media.iter().find(|m| m.index != kind) {
        Some(Medium { name, .. }) => Err(SceneError::new(
            format!("media.{name}"),
            format!(
                "has {} while `{first}` has {}: a scene's media are all `speed` media (times \
                 in length / speed) or all `index` media (optics: time = index × length), not \
                 both; give every medium the same kind",
                word(!kind),
                word(kind)
            ),
        )),
        None => Ok(()),
    }
}

/// The index of medium `name` among `media` (in name order: found by binary search, so that
/// validation stays O(n log n)).
///
/// # Errors
/// `key` when no medium has that name.
fn medium_index(media: &[Medium], key: &str, name: &str) -> Result<usize, SceneError> {
    by_name(media, |m| &m.name, name).ok_or_else(|| {
        let known = media.iter().map(|m| m.name.as_str());
        SceneError::new(key, names::unknown("medium", name, known))
    })
}

/// The domain box of `[[xmin, ymin], [xmax, ymax]]`, if given.
///
/// # Errors
/// `domain` when a corner is not finite or the box is empty.
fn domain_of(domain: Option<[[f64; 2]; 2]>) -> Result<Option<Aabb>, SceneError> {
    match domain {
        Some([lo, hi]) => {
            let (lo, hi) = (point("domain", lo)?, point("domain", hi)?);
            if !(lo.x < hi.x && lo.y < hi.y) {
                return Err(SceneError::new(
                    "domain",
                    "needs [[xmin, ymin], [xmax, ymax]] with xmin < xmax and ymin < ymax",
                ));
            }
            Ok(Some(Aabb { min: lo, max: hi }))
        }
        None => Ok(None),
    }
}

/// Refuses medium `m`'s `at` point (if it has one) on an interface, outside the `domain` or on
/// its edge.
///
/// # Errors
/// `media.NAME.at`.
fn at_point_in_place(
    m: &Medium,
    interfaces: &[Interface],
    segments: &[SegmentRef],
    segment_bvh: &Bvh,
    domain: Option<Aabb>,
) -> Result<(), SceneError> {
    let Some(at) = m.at else {
        return Ok(());
    };
    let key = format!("media.{}.at", m.name);
    at_off_interfaces(m, interfaces, segments, segment_bvh)?;
    if let Some(d) = domain {
        if !d.contains(at) {
            return Err(SceneError::new(
                key,
                "lies outside the domain; it must be strictly inside a region of the domain \
                 (outside the domain is the background's)",
            ));
        }
        if at.x == d.min.x || at.x == d.max.x || at.y == d.min.y || at.y == d.max.y {
            return Err(SceneError::new(
                key,
                "lies on the edge of the domain; it must be strictly inside a region",
            ));
        }
    }
    Ok(())
}

/// The points of the list under `key` (`sources`, `receivers`).
///
/// # Errors
/// `KEY[k]` for the first point that is not finite.
fn points_of(key: &str, list: &[[f64; 2]]) -> Result<Vec<Point>, SceneError> {
    list.iter()
        .enumerate()
        .map(|(k, p)| point(&format!("{key}[{k}]"), *p))
        .collect()
}

/// The paths of a scene document, their steps and media by index into `interfaces` and
/// `media`.
///
/// # Errors
/// `paths[k].name` when two paths share a name; the errors of [`path_of`].
fn paths_of(
    specs: &[PathSpec],
    interfaces: &[Interface],
    media: &[Medium],
) -> Result<Vec<Path>, SceneError> {
    let mut paths = Vec::with_capacity(specs.len());
    let mut path_names: HashMap<&str, usize> = HashMap::new();
    for (k, p) in specs.iter().enumerate() {
        if let Some(name) = &p.name
            && let Some(first) = path_names.insert(name, k)
        {
            return Err(SceneError::new(
                format!("paths[{k}].name"),
                format!("`{name}` is also the name of paths[{first}] (names must differ)"),
            ));
        }
        paths.push(path_of(k, p, interfaces, media)?);
    }
    Ok(paths)
}

/// Path `k` of a scene document: its steps and its leg media by index.
///
/// # Errors
/// `paths[k].steps[j].reflect` (or `refract`) for an unknown interface; `paths[k].media` when
/// it does not hold one medium per leg; `paths[k].media[j]` for an unknown medium.
fn path_of(
    k: usize,
    p: &PathSpec,
    interfaces: &[Interface],
    media: &[Medium],
) -> Result<Path, SceneError> {
    let key = format!("paths[{k}]");
    let mut steps = Vec::with_capacity(p.steps.len());
    for (j, s) in p.steps.iter().enumerate() {
        let (kind, name, which) = match s {
            StepSpec::Reflect(n) => (StepKind::Reflect, n, "reflect"),
            StepSpec::Refract(n) => (StepKind::Refract, n, "refract"),
            // The vertex is checked once the interface is known.
            StepSpec::Diffract { interface, .. } => {
                (StepKind::Diffract { vertex: 0 }, interface, "diffract")
            }
        };
        let interface = by_name(interfaces, |i| &i.name, name).ok_or_else(|| {
            SceneError::new(
                format!("{key}.steps[{j}].{which}"),
                names::unknown(
                    "interface",
                    name,
                    interfaces.iter().map(|i| i.name.as_str()),
                ),
            )
        })?;
        let kind = match s {
            StepSpec::Diffract { vertex, .. } => {
                let line = &interfaces[interface].polyline;
                let n = line.vertices().len();
                match u32::try_from(*vertex) {
                    Ok(v) if (v as usize) < n => StepKind::Diffract { vertex: v },
                    _ => {
                        return Err(SceneError::new(
                            format!("{key}.steps[{j}].vertex"),
                            format!(
                                "interface `{name}` has vertices 0 to {}, not {vertex}",
                                n - 1
                            ),
                        ));
                    }
                }
            }
            _ => kind,
        };
        steps.push(Step { kind, interface });
    }
    let media = match &p.media {
        Some(names) => {
            if names.len() != steps.len() + 1 {
                return Err(SceneError::new(
                    format!("{key}.media"),
                    format!(
                        "needs one medium per leg: {} (steps + 1), got {}",
                        steps.len() + 1,
                        names.len()
                    ),
                ));
            }
            let mut idx = Vec::with_capacity(names.len());
            for (j, n) in names.iter().enumerate() {
                idx.push(medium_index(media, &format!("{key}.media[{j}]"), n)?);
            }
            Some(idx)
        }
        None => None,
    };
    Ok(Path {
        name: p.name.clone(),
        steps,
        media,
    })
}

/// The solver options of a scene document: the defaults, with what its `solver` section sets.
///
/// # Errors
/// `solver.max_iterations` when it is 0; the errors of [`SolverOptions::validate`].
fn solver_of(spec: Option<&SolverSpec>) -> Result<SolverOptions, SceneError> {
    let mut solver = SolverOptions::default();
    if let Some(s) = spec {
        if let Some(t) = s.tolerance {
            solver.tolerance = t;
        }
        if let Some(m) = s.max_iterations {
            solver.max_iterations = usize::try_from(m).unwrap_or(usize::MAX);
            if m == 0 {
                return Err(SceneError::new(
                    "solver.max_iterations",
                    format!("must be between 1 and {MAX_ITERATIONS_LIMIT}"),
                ));
            }
        }
        if let Some(m) = s.stationary {
            solver.stationary = m;
        }
        if let Some(d) = s.derivatives {
            solver.derivatives = d;
        }
        if let Some(w) = s.max_work {
            solver.max_work = w;
        }
        solver.validate()?;
    }
    Ok(solver)
}

impl Scene {
    /// Parses and validates a scene document.
    ///
    /// # Errors
    /// The first problem found, with the key that holds it.
    pub fn from_json(text: &str) -> Result<Scene, SceneError> {
        Scene::from_spec(&SceneSpec::from_json(text)?)
    }

    /// Parses and validates a scene document that the caller generated from its own data
    /// (the Python package's `dict`, serialised): errors name the key path only, without the
    /// line and column of a text the user never wrote ([`SceneSpec::from_generated_json`]).
    ///
    /// # Errors
    /// The first problem found, with the key that holds it.
    pub fn from_generated_json(text: &str) -> Result<Scene, SceneError> {
        Scene::from_spec(&SceneSpec::from_generated_json(text)?)
    }

    /// Validates a scene document: every rule of the scene format, plus finite numbers and
    /// interfaces that neither cross nor overlap (themselves or each other).
    ///
    /// # Errors
    /// The first problem found, with the key that holds it.
    pub fn from_spec(spec: &SceneSpec) -> Result<Scene, SceneError> {
        let media = media_of(spec)?;
        let background = match &spec.background {
            Some(name) => Some(medium_index(&media, "background", name)?),
            None => None,
        };
        let domain = domain_of(spec.domain)?;
        let mut interfaces = Vec::with_capacity(spec.interfaces.len());
        for (name, i) in &spec.interfaces {
            interfaces.push(Interface {
                name: name.clone(),
                polyline: interface_polyline(name, &i.points, i.closed)?,
            });
        }
        let (segments, segment_bvh) = index_segments(&interfaces);
        crossings::check(&interfaces, &segments)?;
        for m in &media {
            at_point_in_place(m, &interfaces, &segments, &segment_bvh, domain)?;
        }
        let sources = points_of("sources", &spec.sources)?;
        let receivers = spec.receivers.validate()?;

        let needs_regions = spec.paths.iter().any(|p| p.media.is_none())
            || spec.search.is_some()
            || media_reflections_look_up(spec);
        if needs_regions {
            let axis = spec
                .amplitudes
                .is_some_and(|a| a.source == SourceModel::Axisymmetric);
            for (k, &p) in sources.iter().enumerate() {
                source_in_a_region(&interfaces, &segments, &segment_bvh, domain, axis, k, p)?;
            }
        }
        let paths = paths_of(&spec.paths, &interfaces, &media)?;
        let solver = solver_of(spec.solver.as_ref())?;
        if solver.derivatives
            && let Some(k) = paths.iter().position(Path::diffracts)
        {
            return Err(SceneError::new(
                "solver.derivatives",
                format!(
                    "derivatives of diffracted paths are not available (paths[{k}] has a \
                     `diffract` step)"
                ),
            ));
        }
        let search = match &spec.search {
            Some(s) => Some(search_options(s, &interfaces)?),
            None => None,
        };
        let extrusion = extrusion::validate(spec, sources.len(), receivers.len())?;
        let amplitudes = amplitudes::validate(spec, &sources, needs_regions)?;
        let impulse_response = impulse::validate(spec)?;
        let transmission_loss = transmission::validate(spec)?;
        let batch_size = batch_size(sources.len(), receivers.len(), &paths)?;
        if needs_regions {
            check_region_range(scene_points(
                &interfaces,
                &sources,
                &receivers,
                &media,
                domain,
            ))?;
        }

        let mut media = media;
        speeds_stay_positive(
            &mut media,
            scene_points(&interfaces, &sources, &receivers, &[], domain),
            domain,
        )?;
        let curved = media
            .iter()
            .any(|m| m.gradient.is_some() || m.profile.is_some());
        if curved {
            curved_legs_supported(spec)?;
        }

        let segment_ends = segment_ends(&interfaces, &segments);
        Ok(Scene {
            media,
            curved,
            background,
            domain,
            interfaces,
            sources,
            receivers,
            paths,
            solver,
            search,
            segment_ends,
            segments,
            segment_bvh,
            batch_size,
            amplitudes,
            impulse_response,
            transmission_loss,
            extrusion,
            document: document::Document::of(spec),
        })
    }

    /// The impulse-response settings, when the scene asks for responses
    /// (`"impulse_response"`).
    pub fn impulse_response(&self) -> Option<&ImpulseResponseOptions> {
        self.impulse_response.as_ref()
    }

    /// How the scene's transmission loss sums its arrivals, when it gives a
    /// `"transmission_loss"` section (without one, `--tl` sums them coherently).
    pub fn transmission_loss(&self) -> Option<TransmissionLossMode> {
        self.transmission_loss
    }

    /// The extruded room (`"extrusion"`), when the scene is one: its height, the laws of its
    /// floor and ceiling, and the heights of its sources and receivers.
    pub fn extrusion(&self) -> Option<&Extrusion> {
        self.extrusion.as_ref()
    }

    /// The media, in name order.
    pub fn media(&self) -> &[Medium] {
        &self.media
    }
    /// Whether a medium's speed has a gradient or a profile (some legs are circular arcs).
    #[inline]
    pub fn curved(&self) -> bool {
        self.curved
    }
    /// Index of the medium with this name.
    pub fn medium_index(&self, name: &str) -> Option<usize> {
        by_name(&self.media, |m| &m.name, name)
    }
    /// Index of the background medium.
    pub fn background(&self) -> Option<usize> {
        self.background
    }
    /// The lookup domain box.
    pub fn domain(&self) -> Option<Aabb> {
        self.domain
    }
    /// The interfaces, in name order.
    pub fn interfaces(&self) -> &[Interface] {
        &self.interfaces
    }
    /// Index of the interface with this name.
    pub fn interface_index(&self, name: &str) -> Option<usize> {
        by_name(&self.interfaces, |i| &i.name, name)
    }
    /// Source points.
    pub fn sources(&self) -> &[Point] {
        &self.sources
    }
    /// Receiver points.
    pub fn receivers(&self) -> &[Point] {
        &self.receivers
    }
    /// Paths.
    pub fn paths(&self) -> &[Path] {
        &self.paths
    }
    /// The number of the ray of (`source`, `receiver`, `path`) in `eigenray solve`'s ray order:
    /// source-major, then receiver, then path.
    #[inline]
    pub fn ray_index(&self, source: usize, receiver: usize, path: usize) -> usize {
        (source * self.receivers.len() + receiver) * self.paths.len() + path
    }
    /// The (source, receiver, path) triple of ray `ray` in `eigenray solve`'s ray order: the
    /// inverse of [`Scene::ray_index`].
    #[inline]
    pub fn ray_triple(&self, ray: usize) -> RayTriple {
        RayTriple::of(ray, self.receivers.len(), self.paths.len())
    }
    /// Solver settings.
    pub fn solver(&self) -> SolverOptions {
        self.solver
    }
    /// The `search` section's settings, when the scene asks for automatic sequences.
    pub fn search(&self) -> Option<&SearchOptions> {
        self.search.as_ref()
    }
    /// Replaces the solver settings, after the checks that a scene document's `solver` gets.
    ///
    /// # Errors
    /// As [`SolverOptions::validate`]; the settings are then left as they were.
    pub fn set_solver(&mut self, options: SolverOptions) -> Result<(), SceneError> {
        options.validate()?;
        self.solver = options;
        Ok(())
    }
    /// Number of rays: sources × receivers × paths (checked at validation: it fits).
    pub fn num_rays(&self) -> usize {
        self.batch_size.rays
    }
    /// The sizes of a whole batch of this scene (rays, their points and leg media), checked at
    /// validation: every product fits in a `usize`. Multiply by the bytes of each
    /// ([`BatchSize::bytes`]) to know what a batch needs before allocating it.
    pub fn batch_size(&self) -> BatchSize {
        self.batch_size
    }

    /// Checks the arguments of a solve between two arbitrary points (what
    /// [`Tracer::solve`](crate::Tracer::solve) needs): both points finite and within
    /// ±[`MAX_COORDINATE`], and `path` an index into [`paths`](Self::paths). (A coordinate
    /// below [`MIN_COORDINATE`] is allowed here: the scene's own coordinates fix its scale, and
    /// to it such a coordinate is zero.)
    ///
    /// # Errors
    /// `source`, `receiver` or `path`, with what is wrong.
    pub fn check_solve(
        &self,
        source: Point,
        receiver: Point,
        path: usize,
    ) -> Result<(), SceneError> {
        for (key, p) in [("source", source), ("receiver", receiver)] {
            if !(p.x.abs() <= MAX_COORDINATE && p.y.abs() <= MAX_COORDINATE) {
                // The scene's own message for a point that is not finite or too large.
                point(key, [p.x, p.y])?;
            }
        }
        if path >= self.paths.len() {
            return Err(SceneError::new(
                "path",
                format!(
                    "index {path} is out of range (the scene has {} paths)",
                    self.paths.len()
                ),
            ));
        }
        Ok(())
    }
    /// Whether some path needs region lookup (gives no `media`), the scene asks for a
    /// `search` (whose media come from the regions), or its amplitudes' `"media"`
    /// reflections take the medium across an interface from the regions it declares
    /// (`background`, an `at` or a `domain`).
    pub fn needs_regions(&self) -> bool {
        let media_reflections = self.amplitudes.as_ref().is_some_and(|a| {
            a.reflection.contains(&Reflection::Media)
                && (self.background.is_some()
                    || self.domain.is_some()
                    || self.media.iter().any(|m| m.at.is_some()))
        });
        self.paths.iter().any(|p| p.media.is_none()) || self.search.is_some() || media_reflections
    }
    /// Whether a source at `p` lies on the axis of an axisymmetric scene where the axis is
    /// the `domain`'s left edge: it is then in the medium on the axis' right.
    pub(crate) fn source_on_axis_edge(&self, p: Point) -> bool {
        on_axis_edge(self.domain, self.axisymmetric(), p)
    }
    /// Whether the scene's amplitudes are those of an `axisymmetric` source.
    fn axisymmetric(&self) -> bool {
        self.amplitudes
            .as_ref()
            .is_some_and(|a| a.source == SourceModel::Axisymmetric)
    }
    /// Bounding box of everything in the scene (interfaces, sources, receivers, `at` points,
    /// domain).
    pub fn bbox(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for i in &self.interfaces {
            b = b.union(i.polyline.bbox());
        }
        for p in self
            .sources
            .iter()
            .chain(&self.receivers)
            .chain(self.media.iter().filter_map(|m| m.at.as_ref()))
        {
            b = b.union(Aabb::from_points(*p, *p));
        }
        if let Some(d) = self.domain {
            b = b.union(d);
        }
        b
    }

    /// Whether the boxes of the interface segments overlap in more than `budget` pairs (each
    /// pair counted from both sides, a segment with itself once); stops counting beyond it.
    pub(crate) fn box_overlaps_exceed(&self, budget: usize) -> bool {
        let mut count = 0usize;
        self.segment_ends
            .iter()
            .any(|&Segment { start: a, end: b }| {
                self.segment_bvh
                    .any_overlapping(Aabb::from_points(a, b), |_| {
                        count += 1;
                        count > budget
                    })
            })
    }

    /// Every interface segment, scene-wide.
    pub fn segments(&self) -> &[SegmentRef] {
        &self.segments
    }

    /// The first interface segment that the segment `a–b` crosses or touches strictly inside,
    /// at a fraction `t ∈ (margin, 1 − margin)` of the way from `a` to `b` (its end points
    /// may lie on interfaces: touching there does not count), other than the segments in
    /// `own`.
    ///
    /// `own` names the segments that `a` and `b` lie on ([`SegmentRef::NONE`] for an end on
    /// no interface). A straight segment meets a leg that ends on it only at that end (or
    /// along all of it, which is no crossing), so testing it could only find round-off: a leg
    /// that grazes its own interface at a small angle would otherwise seem to cross it.
    ///
    /// Only boxes that meet the middle part of `a–b` (`t` from about `margin / 2` to `1 −
    /// margin / 2`, less round-off) are visited: a leg between two interfaces then does not
    /// even look at the segments its end points lie on when they are axis-parallel.
    pub(crate) fn first_crossing(
        &self,
        a: Point,
        b: Point,
        margin: f64,
        own: [SegmentRef; 2],
    ) -> Option<SegmentRef> {
        self.first_crossing_by(a, b, margin, own, |i| self.crosses(i, a, b, margin))
    }

    /// The first segment near `a–b` (not one of `own`) that `crosses` says the leg crosses.
    fn first_crossing_by(
        &self,
        a: Point,
        b: Point,
        margin: f64,
        own: [SegmentRef; 2],
        crosses: impl Fn(u32) -> bool,
    ) -> Option<SegmentRef> {
        let sbox = middle_box(a, b, margin);
        let mut hit = None;
        self.segment_bvh.any_near_segment_in(sbox, a, b, |i| {
            let r = self.segments[i as usize];
            let crossed = r != own[0] && r != own[1] && crosses(i);
            if crossed {
                hit = Some(r);
            }
            crossed
        });
        hit
    }

    /// [`first_crossing`](Self::first_crossing) for a circular arc (a leg in a medium with a
    /// speed gradient), exactly ([`ArcFrame::meets`]): the interface segment that `arc`
    /// crosses or touches at a fraction of its chord in `(margin, 1 − margin)`, the one
    /// nearest its start. `own` names the segments that the arc's start and end lie on: it
    /// meets those there, which does not count, and crosses them wherever else it meets them.
    pub(crate) fn first_arc_crossing(
        &self,
        arc: &ArcFrame,
        margin: f64,
        own: [SegmentRef; 2],
    ) -> Option<SegmentRef> {
        let mut first: Option<(f64, SegmentRef)> = None;
        self.segment_bvh.any_overlapping(arc.bounding_box(), |i| {
            let r = self.segments[i as usize];
            let ends_on = match (r == own[0], r == own[1]) {
                (false, false) => EndsOn::Neither,
                (true, false) => EndsOn::Start,
                (false, true) => EndsOn::End,
                (true, true) => EndsOn::Both,
            };
            let Segment { start, end } = self.segment_ends[i as usize];
            if let Some(at) = arc.meets(start, end, margin, ends_on)
                && first.is_none_or(|(nearest, _)| at < nearest)
            {
                first = Some((at, r));
            }
            false
        });
        first.map(|(_, r)| r)
    }

    /// [`first_crossing`](Self::first_crossing) ignoring the interfaces `skip` names (a
    /// waveguide's walls, which its rays touch but never cross).
    pub(crate) fn first_crossing_except(
        &self,
        a: Point,
        b: Point,
        margin: f64,
        skip: impl Fn(usize) -> bool,
    ) -> Option<SegmentRef> {
        self.first_crossing_by(a, b, margin, [SegmentRef::NONE; 2], |i| {
            !skip(self.segments[i as usize].interface as usize) && self.crosses(i, a, b, margin)
        })
    }

    /// [`first_crossing`](Self::first_crossing) for a leg `a–b` known to lie on the line
    /// through `line` (points that hold it more exactly than its rounded ends, such as a beam's
    /// image and the receiver mirrored back): which side of that line each segment's ends lie
    /// on is decided by the exact orientation test, so that a leg through a vertex exactly is
    /// found to touch it (the leg's own rounded ends may pass it by a hair).
    pub(crate) fn first_crossing_on_line(
        &self,
        a: Point,
        b: Point,
        line: [Point; 2],
        margin: f64,
        own: [SegmentRef; 2],
    ) -> Option<SegmentRef> {
        self.first_crossing_by(a, b, margin, own, |i| {
            self.crosses_on_line(i, a, b, line, margin)
        })
    }

    /// [`first_crossing_on_line`](Self::first_crossing_on_line) among `candidates` only
    /// (scene segment indices, which must include every segment that the leg can be found
    /// to cross), each tested as the hierarchy's leaves test it (its box against the leg's
    /// middle box, then the crossing): the first one listed that `a–b` crosses.
    pub(crate) fn first_crossing_on_line_among(
        &self,
        a: Point,
        b: Point,
        line: [Point; 2],
        margin: f64,
        candidates: &[u32],
        own: [SegmentRef; 2],
    ) -> Option<SegmentRef> {
        self.first_crossing_among_by(a, b, margin, candidates, own, |i| {
            self.crosses_on_line(i, a, b, line, margin)
        })
    }

    /// Whether scene segment `i` meets leg `a–b` at a fraction `t ∈ (margin, 1 − margin)` of
    /// it, with its ends on either side of (or on) the line through `line` (exactly).
    #[inline]
    fn crosses_on_line(&self, i: u32, a: Point, b: Point, line: [Point; 2], margin: f64) -> bool {
        let Segment { start: p, end: q } = self.segment_ends[i as usize];
        let (d, e) = (b - a, q - p);
        let den = d.cross(e);
        let t = (p - a).cross(e) / den;
        den != 0.0
            && t > margin
            && t < 1.0 - margin
            && orient(line[0], line[1], p) * orient(line[0], line[1], q) <= 0.0
    }

    /// [`first_crossing`](Self::first_crossing) among `candidates` only (scene segment
    /// indices, which must include every segment that can meet `a–b`, as
    /// [`segments_in`](Self::segments_in) of a box holding it gives): the first one listed
    /// that `a–b` crosses.
    pub(crate) fn first_crossing_among(
        &self,
        a: Point,
        b: Point,
        margin: f64,
        candidates: &[u32],
        own: [SegmentRef; 2],
    ) -> Option<SegmentRef> {
        self.first_crossing_among_by(a, b, margin, candidates, own, |i| {
            self.crosses(i, a, b, margin)
        })
    }

    /// The first of `candidates` (not one of `own`) whose box meets the middle of `a–b` and
    /// that `crosses` says the leg crosses: the hierarchy's leaf test over a list.
    fn first_crossing_among_by(
        &self,
        a: Point,
        b: Point,
        margin: f64,
        candidates: &[u32],
        own: [SegmentRef; 2],
        crosses: impl Fn(u32) -> bool,
    ) -> Option<SegmentRef> {
        // Most legs have no candidate but their own segments: no box to build for them.
        let mut sbox = None;
        for &i in candidates {
            let r = self.segments[i as usize];
            if r == own[0] || r == own[1] {
                continue;
            }
            let sbox = *sbox.get_or_insert_with(|| middle_box(a, b, margin));
            let Segment { start: p, end: q } = self.segment_ends[i as usize];
            // Scene vertices are finite.
            if Aabb::from_finite(p, q).overlaps(sbox) && crosses(i) {
                return Some(r);
            }
        }
        None
    }

    /// Whether scene segment `i` meets `a–b` at a fraction `t ∈ (margin, 1 − margin)` of it.
    #[inline]
    fn crosses(&self, i: u32, a: Point, b: Point, margin: f64) -> bool {
        let Segment { start: p, end: q } = self.segment_ends[i as usize];
        matches!(
            crate::polyline::segment_intersection(a, b, p, q),
            Some((t, _)) if t > margin && t < 1.0 - margin
        )
    }

    /// The scene segments whose boxes overlap `bbox`, in index order, when there are at most
    /// `max` of them.
    pub(crate) fn segments_in(&self, bbox: Aabb, max: usize) -> Option<Vec<u32>> {
        let mut found = Vec::new();
        let too_many = self.segment_bvh.any_overlapping(bbox, |i| {
            found.push(i);
            found.len() > max
        });
        if too_many {
            return None;
        }
        found.sort_unstable();
        Some(found)
    }

    /// End points of a scene segment.
    #[inline]
    pub fn segment_points(&self, s: SegmentRef) -> Segment {
        self.interfaces[s.interface as usize]
            .polyline
            .segment(s.segment as usize)
    }

    /// Calls `visit` with every interface segment that passes exactly through `p` strictly
    /// between its ends (a vertex of one interface on a segment of another).
    pub(crate) fn segments_through(&self, p: Point, mut visit: impl FnMut(SegmentRef)) {
        segments_on(
            &self.interfaces,
            &self.segments,
            &self.segment_bvh,
            p,
            |s, a, b| {
                if a != p && b != p {
                    visit(s);
                }
                false
            },
        );
    }

    /// The interface segment that `p` lies on exactly, if any.
    pub fn on_interface(&self, p: Point) -> Option<SegmentRef> {
        on_interface(&self.interfaces, &self.segments, &self.segment_bvh, p)
    }
}

/// The box of the middle part of `a–b` that [`Scene::first_crossing`] looks at: `t` from about
/// `margin / 2` to `1 − margin / 2`, less round-off.
#[inline]
fn middle_box(a: Point, b: Point, margin: f64) -> Aabb {
    let d = b - a;
    let cut = |lo: f64, hi: f64, along: f64| {
        let slack = 4.0 * f64::EPSILON * (lo.abs() + hi.abs());
        let c = (0.5 * margin * along.abs() - slack).max(0.0);
        (lo + c, hi - c)
    };
    // The legs' end points are finite.
    let Aabb { min, max } = Aabb::from_finite(a, b);
    let (x0, x1) = cut(min.x, max.x, d.x);
    let (y0, y1) = cut(min.y, max.y, d.y);
    Aabb {
        min: Point::new(x0, y0),
        max: Point::new(x1, y1),
    }
}

impl SceneSpec {
    /// Parses a scene document (no validation beyond the JSON shape; see [`Scene::from_spec`]).
    ///
    /// # Errors
    /// Bad JSON, or a value of the wrong type, with the key that holds it.
    pub fn from_json(text: &str) -> Result<SceneSpec, SceneError> {
        SceneSpec::parse(text, JsonOrigin::Written)
    }

    /// Parses a scene document that the caller generated from its own data (the Python
    /// package's `dict`, serialised): as [`from_json`](SceneSpec::from_json), but an error
    /// names the key path only, without the line and column of a text the user never wrote.
    ///
    /// # Errors
    /// Bad JSON, or a value of the wrong type, with the key that holds it.
    pub fn from_generated_json(text: &str) -> Result<SceneSpec, SceneError> {
        SceneSpec::parse(text, JsonOrigin::Generated)
    }

    /// Parses a scene document; `origin` says whether its errors may point into the text.
    fn parse(text: &str, origin: JsonOrigin) -> Result<SceneSpec, SceneError> {
        // serde would also accept a struct written as an array: a scene is an object.
        if !text.trim_start().starts_with('{') {
            let msg = if text.trim().is_empty() {
                "empty document: expected a JSON object"
            } else {
                "expected a JSON object"
            };
            return Err(SceneError::new("scene", msg));
        }
        if text.contains("\"extrusion\"")
            && let Ok(mut value) = serde_json::from_str::<serde_json::Value>(text)
            && let Some(heights) = extrusion::split_heights(&mut value)
        {
            // An extruded scene's points are [x, y, z]: their plans parsed as any scene's,
            // their heights kept beside them.
            let plan = value.to_string();
            let mut spec = SceneSpec::parse_plan(&plan, JsonOrigin::Generated)?;
            if let Some(e) = &mut spec.extrusion {
                e.source_heights = heights.sources;
                e.receiver_heights = heights.receivers;
                e.grid_height = heights.grid;
            }
            return Ok(spec);
        }
        SceneSpec::parse_plan(text, origin)
    }

    /// Parses a scene document whose points are plan points `[x, y]`.
    fn parse_plan(text: &str, origin: JsonOrigin) -> Result<SceneSpec, SceneError> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let spec: SceneSpec = serde_path_to_error::deserialize(&mut *de).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            let root = path == "." || path.is_empty() || path == "?";
            let text = origin.message(&inner);
            if inner.is_syntax() || inner.is_eof() {
                if text.starts_with("trailing characters") && !root {
                    // An array with too many elements, such as a point with 3 coordinates.
                    return SceneError::new(
                        path,
                        match origin {
                            JsonOrigin::Written => format!("too many elements ({text})"),
                            JsonOrigin::Generated => "too many elements".to_string(),
                        },
                    );
                }
                return SceneError::new(
                    if root { "scene".to_string() } else { path },
                    format!("invalid JSON: {text}"),
                );
            }
            if let Some(field) = text
                .strip_prefix("missing field `")
                .and_then(|r| r.split('`').next())
            {
                let key = if root {
                    field.to_string()
                } else {
                    format!("{path}.{field}")
                };
                return SceneError::new(key, "missing (this key is required)");
            }
            SceneError::new(if root { "scene".to_string() } else { path }, text)
        })?;
        // Anything but whitespace after the document (a second document, stray text) is bad
        // JSON too.
        de.end().map_err(|e| {
            SceneError::new("scene", format!("invalid JSON: {}", origin.message(&e)))
        })?;
        Ok(spec)
    }
}

/// Who wrote a scene document's text: the user (a file, a string), whose errors may say
/// where in it they are, or the caller from its own data, whose errors name the key only.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum JsonOrigin {
    /// Text the user wrote: errors keep serde_json's line and column.
    Written,
    /// Text serialised from the caller's data: errors without a line and column.
    Generated,
}

impl JsonOrigin {
    /// serde_json's message for `e`, without its ` at line L column C` where the text was
    /// generated.
    fn message(self, e: &serde_json::Error) -> String {
        let text = e.to_string();
        if self == JsonOrigin::Written || e.line() == 0 {
            return text;
        }
        let position = format!(" at line {} column {}", e.line(), e.column());
        match text.strip_suffix(&position) {
            Some(message) => message.to_string(),
            None => text,
        }
    }
}

/// Index of the item named `name` in `items`, which are sorted by name.
fn by_name<T>(items: &[T], name_of: impl Fn(&T) -> &String, name: &str) -> Option<usize> {
    items
        .binary_search_by(|item| name_of(item).as_str().cmp(name))
        .ok()
}

/// The sizes of a batch, with checked arithmetic: a scene whose counts overflow is refused.
fn batch_size(sources: usize, receivers: usize, paths: &[Path]) -> Result<BatchSize, SceneError> {
    let too_many = |what: &str| {
        SceneError::new(
            "paths",
            format!(
                "too many rays: {sources} sources × {receivers} receivers × {} paths ({what}) \
                 is more than this machine can count",
                paths.len()
            ),
        )
    };
    let pairs = sources
        .checked_mul(receivers)
        .ok_or_else(|| too_many("sources × receivers"))?;
    let rays = pairs
        .checked_mul(paths.len())
        .ok_or_else(|| too_many("rays"))?;
    let (mut points, mut legs) = (0usize, 0usize);
    for p in paths {
        let k = p.steps.len();
        points = k
            .checked_add(2)
            .and_then(|n| points.checked_add(n))
            .ok_or_else(|| too_many("points"))?;
        legs = k
            .checked_add(1)
            .and_then(|n| legs.checked_add(n))
            .ok_or_else(|| too_many("legs"))?;
    }
    Ok(BatchSize {
        rays,
        points: pairs
            .checked_mul(points)
            .ok_or_else(|| too_many("points of all rays"))?,
        legs: pairs
            .checked_mul(legs)
            .ok_or_else(|| too_many("legs of all rays"))?,
    })
}

/// Refuses a scene whose coordinates span more than region lookup can hold: a nonzero
/// magnitude below `2^-REGION_RANGE_BITS` of the largest.
fn check_region_range(points: impl Iterator<Item = Point>) -> Result<(), SceneError> {
    // The largest magnitude and the smallest nonzero one, in one pass over their bits: the
    // magnitudes of finite numbers (a scene's coordinates) order as their bits do, and zero,
    // the one magnitude whose bits less one wrap around, drops out of the smallest.
    let magnitude = |v: f64| v.to_bits() & !(1 << 63);
    let (largest, smallest) = points.fold((0u64, u64::MAX), |(large, small), p| {
        let (x, y) = (magnitude(p.x), magnitude(p.y));
        (
            large.max(x).max(y),
            small.min(x.wrapping_sub(1)).min(y.wrapping_sub(1)),
        )
    });
    let largest = f64::from_bits(largest);
    let smallest = smallest
        .checked_add(1)
        .map_or(f64::INFINITY, f64::from_bits);
    // 2^-REGION_RANGE_BITS, in two exact steps (each factor is a normal number).
    let floor = largest
        * 2f64.powi(-REGION_RANGE_BITS / 2)
        * 2f64.powi(-(REGION_RANGE_BITS - REGION_RANGE_BITS / 2));
    if smallest < floor {
        return Err(SceneError::new(
            "scene",
            format!(
                "coordinates span too many orders of magnitude for region lookup (from \
                 {smallest:e} to {largest:e}; at most 2^{REGION_RANGE_BITS}, about 1e102): \
                 move the origin near the geometry, drop far geometry, or give every path its \
                 `media`"
            ),
        ));
    }
    Ok(())
}

/// Whether the scene document's `"media"` reflections take the medium across an interface
/// from region lookup: it asks for amplitudes, some interface reflects by `"media"`, and it
/// declares regions (`background`, an `at` or a `domain`). Without regions such a scene is
/// refused at `interfaces.NAME.reflection`.
fn media_reflections_look_up(spec: &SceneSpec) -> bool {
    let declares_regions = spec.background.is_some()
        || spec.domain.is_some()
        || spec.media.values().any(|m| m.at.is_some());
    spec.amplitudes.is_some()
        && declares_regions
        && spec
            .interfaces
            .values()
            .any(|i| i.reflection == Some(ReflectionSpec::Media))
}

/// Whether `p` lies on the axis x = 0 of an `axisymmetric` scene (`axisymmetric`) where that
/// axis is the left edge of the `domain`, strictly between its corners.
fn on_axis_edge(domain: Option<Aabb>, axisymmetric: bool, p: Point) -> bool {
    domain.is_some_and(|d| {
        axisymmetric && p.x == 0.0 && d.min.x == 0.0 && p.y > d.min.y && p.y < d.max.y
    })
}

/// A source of a scene that needs region lookup must lie strictly inside a region: not on an
/// interface, nor on the domain's edge, except on the axis of an `axisymmetric` scene
/// (`axisymmetric`), which may be the domain's left edge: the source is then in the medium on
/// its right.
fn source_in_a_region(
    interfaces: &[Interface],
    segments: &[SegmentRef],
    bvh: &Bvh,
    domain: Option<Aabb>,
    axisymmetric: bool,
    k: usize,
    p: Point,
) -> Result<(), SceneError> {
    let key = format!("sources[{k}]");
    if let Some(s) = on_interface(interfaces, segments, bvh, p) {
        return Err(SceneError::new(
            key,
            format!(
                "lies exactly on interface `{}`, so it has no medium: move it off the \
                 interface, or give every path its `media`",
                interfaces[s.interface as usize].name
            ),
        ));
    }
    if let Some(d) = domain {
        let inside = p.x > d.min.x && p.x < d.max.x && p.y > d.min.y && p.y < d.max.y;
        if d.contains(p) && !inside && !on_axis_edge(domain, axisymmetric, p) {
            return Err(SceneError::new(
                key,
                "lies exactly on the edge of the domain, so it has no medium: move it off the \
                 edge, or give every path its `media`",
            ));
        }
    }
    Ok(())
}

fn index_segments(interfaces: &[Interface]) -> (Vec<SegmentRef>, Bvh) {
    let mut segments = Vec::new();
    let mut boxes = Vec::new();
    for (i, iface) in interfaces.iter().enumerate() {
        for j in 0..iface.polyline.num_segments() {
            segments.push(SegmentRef {
                interface: i as u32,
                segment: j as u32,
            });
            let Segment { start: a, end: b } = iface.polyline.segment(j);
            boxes.push(Aabb::from_points(a, b));
        }
    }
    let bvh = Bvh::build(&boxes);
    (segments, bvh)
}

/// The polyline of interface `name` from its `points`, validated as the scene format says
/// (errors at `interfaces.NAME.points` or one of its points).
fn interface_polyline(
    name: &str,
    points: &[[f64; 2]],
    closed: bool,
) -> Result<Polyline, SceneError> {
    let key = format!("interfaces.{name}.points");
    let mut pts = Vec::with_capacity(points.len());
    for (k, p) in points.iter().enumerate() {
        pts.push(point(&format!("{key}[{k}]"), *p)?);
    }
    Polyline::new(pts, closed).map_err(|e| match e {
        PolylineError::NotFinite { index } | PolylineError::ZeroLengthSegment { index } => {
            SceneError::new(format!("{key}[{index}]"), e.to_string())
        }
        PolylineError::TooFewPoints { .. } | PolylineError::Collinear => {
            SceneError::new(&key, e.to_string())
        }
    })
}

/// End points of `segments`, in the same order.
fn segment_ends(interfaces: &[Interface], segments: &[SegmentRef]) -> Vec<Segment> {
    segments
        .iter()
        .map(|r| {
            interfaces[r.interface as usize]
                .polyline
                .segment(r.segment as usize)
        })
        .collect()
}

/// A medium's `at` point must not lie on an interface.
fn at_off_interfaces(
    medium: &Medium,
    interfaces: &[Interface],
    segments: &[SegmentRef],
    bvh: &Bvh,
) -> Result<(), SceneError> {
    match medium.at {
        Some(at) if on_interface(interfaces, segments, bvh, at).is_some() => Err(SceneError::new(
            format!("media.{}.at", medium.name),
            "lies on an interface; it must be strictly inside a region",
        )),
        _ => Ok(()),
    }
}

/// Every point of a scene whose magnitude region lookup must hold: the interfaces' vertices,
/// the sources, the receivers, the `at` points and the domain's corners.
fn scene_points<'a>(
    interfaces: &'a [Interface],
    sources: &'a [Point],
    receivers: &'a [Point],
    media: &'a [Medium],
    domain: Option<Aabb>,
) -> impl Iterator<Item = Point> + Clone + 'a {
    interfaces
        .iter()
        .flat_map(|i| i.polyline.vertices().iter().copied())
        .chain(sources.iter().copied())
        .chain(receivers.iter().copied())
        .chain(media.iter().filter_map(|m| m.at))
        .chain(domain.into_iter().flat_map(|d| [d.min, d.max]))
}

fn on_interface(
    interfaces: &[Interface],
    segments: &[SegmentRef],
    bvh: &Bvh,
    p: Point,
) -> Option<SegmentRef> {
    let mut found = None;
    segments_on(interfaces, segments, bvh, p, |s, _, _| {
        found = Some(s);
        true
    });
    found
}

/// Calls `visit(segment, start, end)` for the interface segments that `p` lies on exactly
/// (robust orientation), until it returns `true` ("stop").
fn segments_on(
    interfaces: &[Interface],
    segments: &[SegmentRef],
    bvh: &Bvh,
    p: Point,
    mut visit: impl FnMut(SegmentRef, Point, Point) -> bool,
) {
    bvh.any_overlapping(Aabb::from_points(p, p), |i| {
        let s = segments[i as usize];
        let Segment { start: a, end: b } = interfaces[s.interface as usize]
            .polyline
            .segment(s.segment as usize);
        orient(a, b, p) == 0.0 && Aabb::from_points(a, b).contains(p) && visit(s, a, b)
    });
}

/// The problem with segments `i` and `j` (scene-wide indices), if they meet where they must
/// not: a crossing or an overlap, or a polyline touching itself away from the shared vertex of
/// neighbouring segments. Touching is allowed between interfaces (also a vertex of one on a
/// segment of another, as where a fault ends on a layer). Reported at the segment of lower
/// index.
fn contact_problem(
    interfaces: &[Interface],
    segments: &[SegmentRef],
    i: u32,
    j: u32,
) -> Option<SceneError> {
    let (s, o) = (segments[i.min(j) as usize], segments[i.max(j) as usize]);
    let line = &interfaces[s.interface as usize].polyline;
    let Segment { start: a0, end: a1 } = line.segment(s.segment as usize);
    let oline = &interfaces[o.interface as usize].polyline;
    let Segment { start: b0, end: b1 } = oline.segment(o.segment as usize);
    let contact = segment_contact(a0, a1, b0, b1);
    let same = o.interface == s.interface;
    let nseg = line.num_segments() as u32;
    let (lo, hi) = (s.segment.min(o.segment), s.segment.max(o.segment));
    let adjacent = same && (hi == lo + 1 || (line.is_closed() && lo == 0 && hi == nseg - 1));
    let name = &interfaces[s.interface as usize].name;
    let oname = &interfaces[o.interface as usize].name;
    let msg = match contact {
        SegmentContact::Disjoint => return None,
        SegmentContact::Touch if !same || adjacent => return None,
        SegmentContact::Touch => format!(
            "the polyline touches itself (segments {} and {})",
            s.segment, o.segment
        ),
        SegmentContact::Overlap if same => format!(
            "the polyline overlaps itself (segments {} and {})",
            s.segment, o.segment
        ),
        SegmentContact::Cross if same => format!(
            "the polyline crosses itself (segments {} and {})",
            s.segment, o.segment
        ),
        SegmentContact::Overlap => format!(
            "overlaps interface `{oname}` (segment {} on segment {})",
            s.segment, o.segment
        ),
        SegmentContact::Cross => format!(
            "crosses interface `{oname}` (segment {} crosses segment {})",
            s.segment, o.segment
        ),
    };
    Some(SceneError::new(format!("interfaces.{name}.points"), msg))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The one pass over the coordinates' bits finds the largest magnitude and the smallest
    /// nonzero one as the two passes over their values do (the check written as it was):
    /// the same verdict and the same message, over point sets of both signs, zeros, both
    /// zeros' signs, and magnitudes from `MIN_COORDINATE` to `MAX_COORDINATE`.
    #[test]
    fn the_region_range_is_that_of_two_passes_over_the_values() {
        let two_passes = |points: &[Point]| -> Result<(), SceneError> {
            let largest = points
                .iter()
                .fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs()));
            let floor = largest
                * 2f64.powi(-REGION_RANGE_BITS / 2)
                * 2f64.powi(-(REGION_RANGE_BITS - REGION_RANGE_BITS / 2));
            let smallest = points
                .iter()
                .flat_map(|p| [p.x.abs(), p.y.abs()])
                .filter(|&v| v != 0.0)
                .fold(f64::INFINITY, f64::min);
            if smallest < floor {
                return Err(SceneError::new(
                    "scene",
                    format!("{smallest:e} {largest:e}"),
                ));
            }
            Ok(())
        };
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            state >> 11
        };
        let mut refused = 0;
        for set in 0..400 {
            let n = 1 + next() as usize % 12;
            let mut coordinate = || match next() % 8 {
                0 => 0.0,
                1 => -0.0,
                _ => {
                    // A magnitude 10^e, e in [-100, 100] (the scene's range), either sign.
                    let e = (next() % 201) as i32 - 100;
                    let v = (1.0 + (next() % 1000) as f64 / 1000.0) * 10f64.powi(e);
                    let v = v.clamp(MIN_COORDINATE, MAX_COORDINATE);
                    if next() % 2 == 0 { v } else { -v }
                }
            };
            let points: Vec<Point> = (0..n)
                .map(|_| Point::new(coordinate(), coordinate()))
                .collect();
            let (got, want) = (
                check_region_range(points.iter().copied()),
                two_passes(&points),
            );
            assert_eq!(got.is_ok(), want.is_ok(), "set {set}: {points:?}");
            if let (Err(got), Err(want)) = (got, want) {
                let ends = want.message.replace(' ', " to ");
                assert!(
                    got.message.contains(&format!("(from {ends};")),
                    "{got} {want}"
                );
                refused += 1;
            }
        }
        assert!((50..350).contains(&refused), "{refused} of 400 refused");
        assert!(check_region_range([Point::new(0.0, -0.0)].into_iter()).is_ok());
        assert!(check_region_range(std::iter::empty()).is_ok());
    }

    #[test]
    fn ray_counts_that_overflow_are_refused() {
        let path = |steps: usize| Path {
            name: None,
            steps: vec![
                Step {
                    kind: StepKind::Reflect,
                    interface: 0
                };
                steps
            ],
            media: None,
        };
        let one = [path(0)];
        // 2^63 sources × 2 receivers × 1 path: 2^64 rays, which would wrap to 0.
        let e = batch_size(usize::MAX / 2 + 1, 2, &one).expect_err("2^64");
        assert_eq!(e.key, "paths");
        assert!(e.message.contains("too many rays"), "{e}");
        let e = batch_size(1 << 22, 1 << 22, &[path(0), path(0)]).map(|s| s.rays);
        assert_eq!(e, Ok(1 << 45));
        let e = batch_size(1 << 31, 1 << 31, &[path(2)]).expect_err("points overflow");
        assert!(e.message.contains("points"), "{e}");
        let ok = batch_size(3, 5, &[path(0), path(2)]).expect("fits");
        assert_eq!((ok.rays, ok.points, ok.legs), (30, 15 * 6, 15 * 4));
    }

    /// A scene document generated from the caller's data gives the same error, key and words
    /// as the same text written by the user, without serde_json's line and column; a valid one
    /// gives the same scene.
    #[test]
    fn generated_json_errors_name_the_key_path_only() {
        let base = serde_json::json!({
            "media": {"air": {"speed": 1.0}},
            "sources": [[0, 1]], "receivers": [[1, 1]], "paths": []
        });
        for (key_set, value, key, words) in [
            (
                "sources",
                serde_json::json!([[0, "x"]]),
                "sources[0][1]",
                "invalid type: string",
            ),
            (
                "sources",
                serde_json::json!([[0, 1, 2]]),
                "sources[0]",
                "too many elements",
            ),
            (
                "solver",
                serde_json::json!({"max_iterations": -3}),
                "solver.max_iterations",
                "invalid value",
            ),
            (
                "paths",
                serde_json::json!([{"media": ["air"]}]),
                "paths[0].steps",
                "missing",
            ),
        ] {
            let mut doc = base.clone();
            doc[key_set] = value;
            let text = serde_json::to_string_pretty(&doc).expect("JSON");
            let written = Scene::from_json(&text).map(|_| ()).expect_err(&text);
            let generated = Scene::from_generated_json(&text)
                .map(|_| ())
                .expect_err(&text);
            assert_eq!(
                (written.key.as_str(), generated.key.as_str()),
                (key, key),
                "{text}"
            );
            assert!(generated.message.contains(words), "{generated}");
            assert!(
                !generated.message.contains("line") && !generated.message.contains("column"),
                "{generated}"
            );
            // serde_json places its type errors in the text; a missing key has no place.
            if words == "missing" {
                assert_eq!(written.message, generated.message);
            } else {
                assert!(written.message.contains(" at line "), "{written}");
            }
        }
        let text = base.to_string();
        assert_eq!(
            Scene::from_generated_json(&text).unwrap().to_json(),
            Scene::from_json(&text).unwrap().to_json()
        );
    }
}
