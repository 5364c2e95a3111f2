//! The `extrusion` key: the scene is the floor plan of a 3-D room whose walls are vertical and
//! whose floor (z = 0) and ceiling (z = `height`) are flat. Every source and receiver gains
//! its height z, the third coordinate of its point (`[x, y, z]`), strictly between the floor
//! and the ceiling. The names `floor` and `ceiling` are reserved: the steps of a 3-D path name
//! them (`search/extruded.rs` lists such paths).

use serde::{Deserialize, Serialize};

use super::{MAX_COORDINATE, ReceiversSpec, ReflectionSpec, SceneError, SceneSpec, SourceModel};

/// The floor's name in a step (`{"reflect": "floor"}`), reserved in an extruded scene.
pub const FLOOR: &str = "floor";
/// The ceiling's name in a step (`{"reflect": "ceiling"}`), reserved in an extruded scene.
pub const CEILING: &str = "ceiling";

/// The `extrusion` section as given: the room's height and the laws of its floor and ceiling
/// (`"rigid"` where not given). The points' heights are the third coordinates of `sources`
/// and `receivers` in the document; [`SceneSpec::from_json`] moves them here.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtrusionSpec {
    /// The ceiling's height above the floor (> 0).
    pub height: f64,
    /// The floor's reflection law (as an interface's `reflection`, `"media"` excepted).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor: Option<ReflectionSpec>,
    /// The ceiling's reflection law.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ceiling: Option<ReflectionSpec>,
    /// Each source's height z, in the order of `sources` (NaN where its point gave none).
    #[serde(skip)]
    pub source_heights: Vec<f64>,
    /// Each receiver's height z, in the order of `receivers` (NaN where its point gave none).
    #[serde(skip)]
    pub receiver_heights: Vec<f64>,
    /// The height z of every receiver of a grid (`"receivers": {"grid": {..., "z": 1.6}}`),
    /// `None` where the receivers are a list.
    #[serde(skip)]
    pub grid_height: Option<f64>,
}

/// A validated extrusion ([`Scene::extrusion`](super::Scene::extrusion)).
#[derive(Clone, Debug, PartialEq)]
pub struct Extrusion {
    /// The ceiling's height (the floor is z = 0).
    pub height: f64,
    /// The floor's real pressure reflection coefficient.
    pub floor: f64,
    /// The ceiling's real pressure reflection coefficient.
    pub ceiling: f64,
    /// Each source's height, strictly between 0 and `height`.
    pub source_heights: Vec<f64>,
    /// Each receiver's height, strictly between 0 and `height`.
    pub receiver_heights: Vec<f64>,
}

/// The heights an extruded scene's document gives ([`split_heights`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct DocumentHeights {
    /// Each source's (NaN where its point has two coordinates).
    pub sources: Vec<f64>,
    /// Each listed receiver's (NaN where its point has two coordinates).
    pub receivers: Vec<f64>,
    /// A receiver grid's `z` (NaN where it is not a number), `None` without one.
    pub grid: Option<f64>,
}

/// Moves the third coordinate of each point of `sources` and `receivers` (a list) of an
/// extruded scene's document `value` into heights, leaving plan points `[x, y]`, and a
/// receiver grid's `z` likewise. `None` when the document has no `extrusion` object.
pub(super) fn split_heights(value: &mut serde_json::Value) -> Option<DocumentHeights> {
    let object = value.as_object_mut()?;
    if !object.get("extrusion")?.is_object() {
        return None;
    }
    let mut split = |key: &str| {
        let mut heights = Vec::new();
        if let Some(serde_json::Value::Array(points)) = object.get_mut(key) {
            for p in points {
                let mut z = f64::NAN;
                if let serde_json::Value::Array(xyz) = p
                    && xyz.len() == 3
                    && let Some(h) = xyz[2].as_f64()
                {
                    z = h;
                    xyz.pop();
                }
                heights.push(z);
            }
        }
        heights
    };
    let sources = split("sources");
    let receivers = split("receivers");
    let grid = object
        .get_mut("receivers")
        .and_then(|r| r.get_mut("grid"))
        .and_then(serde_json::Value::as_object_mut)
        .and_then(|g| g.remove("z"))
        .map(|z| z.as_f64().unwrap_or(f64::NAN));
    Some(DocumentHeights {
        sources,
        receivers,
        grid,
    })
}

/// `value` (a serialised scene document) with each height of `spec`'s extrusion written back
/// as its point's third coordinate.
pub(super) fn join_heights(spec: &ExtrusionSpec, value: &mut serde_json::Value) {
    let Some(object) = value.as_object_mut() else {
        return;
    };
    if let Some(z) = spec.grid_height.and_then(serde_json::Number::from_f64)
        && let Some(grid) = object
            .get_mut("receivers")
            .and_then(|r| r.get_mut("grid"))
            .and_then(serde_json::Value::as_object_mut)
    {
        grid.insert("z".into(), serde_json::Value::Number(z));
    }
    for (key, heights) in [
        ("sources", &spec.source_heights),
        ("receivers", &spec.receiver_heights),
    ] {
        if let Some(serde_json::Value::Array(points)) = object.get_mut(key) {
            for (p, &z) in points.iter_mut().zip(heights) {
                if let (serde_json::Value::Array(xy), Some(z)) =
                    (p, serde_json::Number::from_f64(z))
                {
                    xy.push(serde_json::Value::Number(z));
                }
            }
        }
    }
}

/// The real coefficient of a floor's or ceiling's law at `key`.
fn law(key: &str, spec: Option<ReflectionSpec>) -> Result<f64, SceneError> {
    match spec.unwrap_or(ReflectionSpec::Rigid) {
        ReflectionSpec::Rigid => Ok(1.0),
        ReflectionSpec::PressureRelease => Ok(-1.0),
        ReflectionSpec::Absorption(a) if (0.0..=1.0).contains(&a) => Ok((1.0 - a).sqrt()),
        ReflectionSpec::Absorption(_) => Err(SceneError::new(
            format!("{key}.absorption"),
            "must be a number from 0 to 1 (the fraction of the energy absorbed)",
        )),
        ReflectionSpec::Coefficient(r) if (-1.0..=1.0).contains(&r) => Ok(r),
        ReflectionSpec::Coefficient(_) => Err(SceneError::new(
            format!("{key}.coefficient"),
            "must be a number from -1 to 1 (a real pressure coefficient)",
        )),
        ReflectionSpec::Media => Err(SceneError::new(
            key,
            "\"media\" needs a medium across, and no medium lies beyond the floor or the \
             ceiling: give \"rigid\", \"pressure-release\", {\"absorption\": a} or \
             {\"coefficient\": r}",
        )),
    }
}

/// The heights of `count` points at `key` (`sources` or `receivers`), each strictly between
/// 0 and `height`.
fn heights(key: &str, given: &[f64], count: usize, height: f64) -> Result<Vec<f64>, SceneError> {
    (0..count)
        .map(|k| {
            let z = given.get(k).copied().unwrap_or(f64::NAN);
            if z.is_nan() {
                return Err(SceneError::new(
                    format!("{key}[{k}]"),
                    "needs its height: the points of an extruded scene are [x, y, z]",
                ));
            }
            if !(z > 0.0 && z < height) {
                return Err(SceneError::new(
                    format!("{key}[{k}]"),
                    format!(
                        "its height z = {z} must lie strictly between the floor (0) and the \
                         ceiling (extrusion.height = {height})"
                    ),
                ));
            }
            Ok(z)
        })
        .collect()
}

/// The validated extrusion of `spec` (`None` without one), with `sources` and `receivers`
/// points: the height, the laws, the points' heights, and what an extruded scene cannot hold
/// (a receiver grid without its `z`, interfaces named `floor` or `ceiling`, paths, a speed gradient,
/// refractions among several media, a source other than `point`, diffraction, derivatives).
///
/// # Errors
/// The first problem, at its key.
pub(super) fn validate(
    spec: &SceneSpec,
    sources: usize,
    receivers: usize,
) -> Result<Option<Extrusion>, SceneError> {
    let Some(e) = &spec.extrusion else {
        return Ok(None);
    };
    let height = e.height;
    if !(height.is_finite() && height > 0.0 && height <= MAX_COORDINATE) {
        return Err(SceneError::new(
            "extrusion.height",
            format!("must be a finite number > 0 (at most {MAX_COORDINATE:e})"),
        ));
    }
    let floor = law("extrusion.floor", e.floor)?;
    let ceiling = law("extrusion.ceiling", e.ceiling)?;
    let receiver_heights = match (&spec.receivers, e.grid_height) {
        (ReceiversSpec::Grid { .. }, None) => {
            return Err(SceneError::new(
                "receivers.grid.z",
                "an extruded scene's grid needs its height: \"grid\": {\"x\": [...], \"y\": \
                 [...], \"z\": 1.6} places every receiver at that height",
            ));
        }
        (ReceiversSpec::Grid { .. }, Some(z)) if z > 0.0 && z < height => vec![z; receivers],
        (ReceiversSpec::Grid { .. }, Some(z)) => {
            return Err(SceneError::new(
                "receivers.grid.z",
                format!(
                    "the grid's height must be a number strictly between the floor (0) and the \
                     ceiling (extrusion.height = {height}), not {z}"
                ),
            ));
        }
        (ReceiversSpec::Points(_), _) => {
            heights("receivers", &e.receiver_heights, receivers, height)?
        }
    };
    for name in [FLOOR, CEILING] {
        if spec.interfaces.contains_key(name) {
            return Err(SceneError::new(
                format!("interfaces.{name}"),
                format!("`{name}` is reserved in an extruded scene: rename the interface"),
            ));
        }
    }
    if !spec.paths.is_empty() {
        return Err(SceneError::new(
            "paths",
            "an extruded scene lists its paths through a `search` (its floor and ceiling \
             reflections in closed form): give a `search` instead of `paths`",
        ));
    }
    if let Some((name, _)) = spec.media.iter().find(|(_, m)| m.gradient.is_some()) {
        return Err(SceneError::new(
            format!("media.{name}.gradient"),
            "an extruded room's media have one speed each (no gradient)",
        ));
    }
    if spec.media.len() > 1
        && spec
            .search
            .as_ref()
            .is_some_and(|s| s.refract != Some(false))
    {
        return Err(SceneError::new(
            "search.refract",
            "an extruded room unfolds paths in one medium: with several media (walls' \
             materials for \"media\" laws), set `refract` to false",
        ));
    }
    if let Some(a) = &spec.amplitudes
        && a.source != SourceModel::Point
    {
        return Err(SceneError::new(
            "amplitudes.source",
            "an extruded room is 3-D: its source must be \"point\"",
        ));
    }
    if spec
        .search
        .as_ref()
        .is_some_and(|s| s.diffraction == Some(true))
    {
        return Err(SceneError::new(
            "search.diffraction",
            "diffraction is not available in an extruded scene",
        ));
    }
    if spec
        .solver
        .as_ref()
        .is_some_and(|s| s.derivatives == Some(true))
    {
        return Err(SceneError::new(
            "solver.derivatives",
            "derivatives are not available in an extruded scene",
        ));
    }
    Ok(Some(Extrusion {
        height,
        floor,
        ceiling,
        source_heights: heights("sources", &e.source_heights, sources, height)?,
        receiver_heights,
    }))
}

impl super::Scene {
    /// The name a step's `interface` index stands for: an interface's, or in an extruded
    /// scene `floor` (index [`interfaces`](super::Scene::interfaces)`().len()`) and `ceiling`
    /// (the one after).
    pub fn step_name(&self, interface: usize) -> Option<&str> {
        let n = self.interfaces().len();
        match self.interfaces().get(interface) {
            Some(i) => Some(i.name.as_str()),
            None if self.extrusion().is_some() && interface == n => Some(FLOOR),
            None if self.extrusion().is_some() && interface == n + 1 => Some(CEILING),
            None => None,
        }
    }
}
