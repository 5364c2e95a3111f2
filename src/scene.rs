//! Scenes: the JSON document (`SceneSpec`), its validation, and the validated `Scene`.

use std::collections::BTreeMap;
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::bvh::Bvh;
use crate::geom::{Aabb, Point, SegmentContact, orient, segment_contact};
use crate::polyline::{Polyline, PolylineError};

/// Default relative tolerance on the stationarity residual.
pub const DEFAULT_TOLERANCE: f64 = 1e-12;
/// Default iteration limit per ray.
pub const DEFAULT_MAX_ITERATIONS: usize = 100;
/// Largest `solver.max_iterations` accepted (so that no scene can make a ray run for ever).
pub const MAX_ITERATIONS_LIMIT: usize = 100_000;

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
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.key, self.message)
    }
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
    pub media: BTreeMap<String, MediumSpec>,
    /// Medium of every region that no `at` claims.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub background: Option<String>,
    /// `[[xmin, ymin], [xmax, ymax]]`: a box whose edges close regions for lookup.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub domain: Option<[[f64; 2]; 2]>,
    /// Interfaces by name.
    #[serde(default)]
    pub interfaces: BTreeMap<String, InterfaceSpec>,
    /// Source points.
    pub sources: Vec<[f64; 2]>,
    /// Receiver points.
    pub receivers: Vec<[f64; 2]>,
    /// Paths: sequences of interactions.
    pub paths: Vec<PathSpec>,
    /// Solver settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<SolverSpec>,
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
    /// A point strictly inside the region this medium fills.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<[f64; 2]>,
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

/// One interaction: `{"reflect": NAME}` or `{"refract": NAME}`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StepSpec {
    /// Reflection off the named interface.
    Reflect(String),
    /// Refraction through the named interface.
    Refract(String),
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
}

/// A medium of a validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// Its name.
    pub name: String,
    /// Slowness: time per unit length (1 / speed, or the refractive index).
    pub slowness: f64,
    /// A point inside its region, if given.
    pub at: Option<Point>,
}

/// A named interface of a validated scene.
#[derive(Clone, Debug)]
pub struct Interface {
    /// Its name.
    pub name: String,
    /// Its shape.
    pub polyline: Polyline,
}

/// Reflection or refraction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StepKind {
    /// Both legs on the same side of the interface.
    Reflect,
    /// The legs on opposite sides.
    Refract,
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

/// Solver settings of a validated scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverOptions {
    /// Relative tolerance on the stationarity residual `|∂T/∂sᵢ| / (wᵢ + wᵢ₊₁)`.
    pub tolerance: f64,
    /// Iteration limit per ray.
    pub max_iterations: usize,
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            tolerance: DEFAULT_TOLERANCE,
            max_iterations: DEFAULT_MAX_ITERATIONS,
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
    background: Option<usize>,
    domain: Option<Aabb>,
    interfaces: Vec<Interface>,
    sources: Vec<Point>,
    receivers: Vec<Point>,
    paths: Vec<Path>,
    solver: SolverOptions,
    segments: Vec<SegmentRef>,
    /// End points of `segments`, in the same order.
    segment_ends: Vec<(Point, Point)>,
    segment_bvh: Bvh,
}

/// Largest coordinate magnitude accepted: beyond it distances and times could overflow.
pub const MAX_COORDINATE: f64 = 1e100;
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

impl Scene {
    /// Parses and validates a scene document.
    ///
    /// # Errors
    /// The first problem found, with the key that holds it.
    pub fn from_json(text: &str) -> Result<Scene, SceneError> {
        Scene::from_spec(&SceneSpec::from_json(text)?)
    }

    /// Validates a scene document: every rule of the scene format, plus finite numbers and
    /// interfaces that neither cross nor overlap (themselves or each other).
    ///
    /// # Errors
    /// The first problem found, with the key that holds it.
    pub fn from_spec(spec: &SceneSpec) -> Result<Scene, SceneError> {
        if spec.media.is_empty() {
            return Err(SceneError::new("media", "needs at least one medium"));
        }
        let mut media = Vec::with_capacity(spec.media.len());
        for (name, m) in &spec.media {
            let key = format!("media.{name}");
            let slowness = match (m.speed, m.index) {
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
            media.push(Medium {
                name: name.clone(),
                slowness,
                at,
            });
        }
        let medium_index = |key: &str, name: &str| -> Result<usize, SceneError> {
            media
                .iter()
                .position(|m| m.name == name)
                .ok_or_else(|| SceneError::new(key, format!("unknown medium `{name}`")))
        };
        let background = match &spec.background {
            Some(name) => Some(medium_index("background", name)?),
            None => None,
        };
        let domain = match spec.domain {
            Some([lo, hi]) => {
                let (lo, hi) = (point("domain", lo)?, point("domain", hi)?);
                if !(lo.x < hi.x && lo.y < hi.y) {
                    return Err(SceneError::new(
                        "domain",
                        "needs [[xmin, ymin], [xmax, ymax]] with xmin < xmax and ymin < ymax",
                    ));
                }
                Some(Aabb { min: lo, max: hi })
            }
            None => None,
        };

        let mut interfaces = Vec::with_capacity(spec.interfaces.len());
        for (name, i) in &spec.interfaces {
            let key = format!("interfaces.{name}.points");
            let mut pts = Vec::with_capacity(i.points.len());
            for (k, p) in i.points.iter().enumerate() {
                pts.push(point(&format!("{key}[{k}]"), *p)?);
            }
            let polyline = Polyline::new(pts, i.closed).map_err(|e| match e {
                PolylineError::NotFinite { index } | PolylineError::ZeroLengthSegment { index } => {
                    SceneError::new(format!("{key}[{index}]"), e.to_string())
                }
                PolylineError::TooFewPoints { .. } | PolylineError::Collinear => {
                    SceneError::new(&key, e.to_string())
                }
            })?;
            interfaces.push(Interface {
                name: name.clone(),
                polyline,
            });
        }
        let (segments, segment_bvh) = index_segments(&interfaces);
        check_crossings(&interfaces, &segments, &segment_bvh)?;

        for m in &media {
            if let Some(at) = m.at {
                if on_interface(&interfaces, &segments, &segment_bvh, at).is_some() {
                    return Err(SceneError::new(
                        format!("media.{}.at", m.name),
                        "lies on an interface; it must be strictly inside a region",
                    ));
                }
            }
        }

        let points = |key: &str, list: &[[f64; 2]]| -> Result<Vec<Point>, SceneError> {
            list.iter()
                .enumerate()
                .map(|(k, p)| point(&format!("{key}[{k}]"), *p))
                .collect()
        };
        let sources = points("sources", &spec.sources)?;
        let receivers = points("receivers", &spec.receivers)?;

        let mut paths = Vec::with_capacity(spec.paths.len());
        for (k, p) in spec.paths.iter().enumerate() {
            let key = format!("paths[{k}]");
            let mut steps = Vec::with_capacity(p.steps.len());
            for (j, s) in p.steps.iter().enumerate() {
                let (kind, name, which) = match s {
                    StepSpec::Reflect(n) => (StepKind::Reflect, n, "reflect"),
                    StepSpec::Refract(n) => (StepKind::Refract, n, "refract"),
                };
                let interface =
                    interfaces
                        .iter()
                        .position(|i| &i.name == name)
                        .ok_or_else(|| {
                            SceneError::new(
                                format!("{key}.steps[{j}].{which}"),
                                format!("unknown interface `{name}`"),
                            )
                        })?;
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
                        idx.push(medium_index(&format!("{key}.media[{j}]"), n)?);
                    }
                    Some(idx)
                }
                None => None,
            };
            paths.push(Path {
                name: p.name.clone(),
                steps,
                media,
            });
        }

        let mut solver = SolverOptions::default();
        if let Some(s) = &spec.solver {
            if let Some(t) = s.tolerance {
                if !(t.is_finite() && t > 0.0 && t < 1.0) {
                    return Err(SceneError::new(
                        "solver.tolerance",
                        "must be a number in (0, 1)",
                    ));
                }
                solver.tolerance = t;
            }
            if let Some(m) = s.max_iterations {
                if m == 0 || m > MAX_ITERATIONS_LIMIT as u64 {
                    return Err(SceneError::new(
                        "solver.max_iterations",
                        format!("must be between 1 and {MAX_ITERATIONS_LIMIT}"),
                    ));
                }
                solver.max_iterations = m as usize;
            }
        }

        let segment_ends = segments
            .iter()
            .map(|r| {
                interfaces[r.interface as usize]
                    .polyline
                    .segment(r.segment as usize)
            })
            .collect();
        Ok(Scene {
            media,
            background,
            domain,
            interfaces,
            sources,
            receivers,
            paths,
            solver,
            segment_ends,
            segments,
            segment_bvh,
        })
    }

    /// The media, in name order.
    pub fn media(&self) -> &[Medium] {
        &self.media
    }
    /// Index of the medium with this name.
    pub fn medium_index(&self, name: &str) -> Option<usize> {
        self.media.iter().position(|m| m.name == name)
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
        self.interfaces.iter().position(|i| i.name == name)
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
    /// Solver settings.
    pub fn solver(&self) -> SolverOptions {
        self.solver
    }
    /// Replaces the solver settings.
    pub fn set_solver(&mut self, options: SolverOptions) {
        self.solver = options;
    }
    /// Number of rays: sources × receivers × paths.
    pub fn num_rays(&self) -> usize {
        self.sources.len() * self.receivers.len() * self.paths.len()
    }
    /// Whether some path needs region lookup (gives no `media`).
    pub fn needs_regions(&self) -> bool {
        self.paths.iter().any(|p| p.media.is_none())
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
        let sbox = middle_box(a, b, margin);
        let mut hit = None;
        self.segment_bvh.any_near_segment_in(sbox, a, b, |i| {
            let r = self.segments[i as usize];
            let crossed = r != own[0] && r != own[1] && self.crosses(i, a, b, margin);
            if crossed {
                hit = Some(r);
            }
            crossed
        });
        hit
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
        // Most legs have no candidate but their own segments: no box to build for them.
        let mut sbox = None;
        for &i in candidates {
            let r = self.segments[i as usize];
            if r == own[0] || r == own[1] {
                continue;
            }
            let sbox = *sbox.get_or_insert_with(|| middle_box(a, b, margin));
            let (p, q) = self.segment_ends[i as usize];
            // Scene vertices are finite.
            if Aabb::from_finite(p, q).overlaps(sbox) && self.crosses(i, a, b, margin) {
                return Some(r);
            }
        }
        None
    }

    /// Whether scene segment `i` meets `a–b` at a fraction `t ∈ (margin, 1 − margin)` of it.
    #[inline]
    fn crosses(&self, i: u32, a: Point, b: Point, margin: f64) -> bool {
        let (p, q) = self.segment_ends[i as usize];
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
    pub fn segment_points(&self, s: SegmentRef) -> (Point, Point) {
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
        // serde would also accept a struct written as an array: a scene is an object.
        if !text.trim_start().starts_with('{') {
            let msg = if text.trim().is_empty() {
                "empty document: expected a JSON object"
            } else {
                "expected a JSON object"
            };
            return Err(SceneError::new("scene", msg));
        }
        let de = &mut serde_json::Deserializer::from_str(text);
        let spec: SceneSpec = serde_path_to_error::deserialize(&mut *de).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            let root = path == "." || path.is_empty() || path == "?";
            let text = inner.to_string();
            if inner.is_syntax() || inner.is_eof() {
                if text.starts_with("trailing characters") && !root {
                    // An array with too many elements, such as a point with 3 coordinates.
                    return SceneError::new(path, format!("too many elements ({text})"));
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
        de.end()
            .map_err(|e| SceneError::new("scene", format!("invalid JSON: {e}")))?;
        Ok(spec)
    }
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
            let (a, b) = iface.polyline.segment(j);
            boxes.push(Aabb::from_points(a, b));
        }
    }
    let bvh = Bvh::build(&boxes);
    (segments, bvh)
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
        let (a, b) = interfaces[s.interface as usize]
            .polyline
            .segment(s.segment as usize);
        orient(a, b, p) == 0.0 && Aabb::from_points(a, b).contains(p) && visit(s, a, b)
    });
}

/// Rejects segments that cross or overlap, and polylines that touch themselves away from a
/// shared vertex of neighbouring segments. Touching at a vertex is allowed between interfaces
/// (also a vertex of one on a segment of another, as where a fault ends on a layer).
fn check_crossings(
    interfaces: &[Interface],
    segments: &[SegmentRef],
    bvh: &Bvh,
) -> Result<(), SceneError> {
    for (k, s) in segments.iter().enumerate() {
        let line = &interfaces[s.interface as usize].polyline;
        let (a0, a1) = line.segment(s.segment as usize);
        let mut problem: Option<SceneError> = None;
        bvh.any_overlapping(Aabb::from_points(a0, a1), |other| {
            let o = segments[other as usize];
            if (other as usize) <= k {
                return false;
            }
            let oline = &interfaces[o.interface as usize].polyline;
            let (b0, b1) = oline.segment(o.segment as usize);
            let contact = segment_contact(a0, a1, b0, b1);
            let same = o.interface == s.interface;
            let nseg = line.num_segments() as u32;
            let adjacent = same
                && (o.segment == s.segment + 1
                    || (line.is_closed() && s.segment == 0 && o.segment == nseg - 1));
            let name = &interfaces[s.interface as usize].name;
            let oname = &interfaces[o.interface as usize].name;
            let msg = match contact {
                SegmentContact::Disjoint => return false,
                SegmentContact::Touch if !same || adjacent => return false,
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
            problem = Some(SceneError::new(format!("interfaces.{name}.points"), msg));
            true
        });
        if let Some(p) = problem {
            return Err(p);
        }
    }
    Ok(())
}
