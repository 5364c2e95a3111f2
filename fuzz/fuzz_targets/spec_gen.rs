//! Scene specs built from structured fuzz data (grid-snapped coordinates, so touching,
//! collinear and T-junction cases are common), shared by the `structured` and `scaled` targets.

use std::collections::BTreeMap;

use arbitrary::Arbitrary;
use eigenray::scene::{ReceiversSpec, SolverSpec};
use eigenray::{InterfaceSpec, MediumSpec, PathSpec, SceneSpec, StepSpec};

/// One coordinate: on a coarse grid (many exact coincidences), a fine grid, or any f64.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Coord {
    Grid(i8),
    Fine(i16),
    Raw(f64),
}

impl Coord {
    fn value(self) -> f64 {
        match self {
            Coord::Grid(v) => f64::from(v) / 4.0,
            Coord::Fine(v) => f64::from(v) / 1024.0,
            Coord::Raw(v) => v,
        }
    }
}

pub type P = (Coord, Coord);

/// One path: `(reflect?, interface choice)` per step, and leg medium choices when given.
pub type RawPath = (Vec<(bool, u8)>, Option<Vec<u8>>);

#[derive(Arbitrary, Debug)]
pub struct Input {
    /// Power of ten applied to every coordinate (picked from a few).
    pub scale: u8,
    /// `(speed code, as index?, at)`.
    pub media: Vec<(u8, bool, Option<P>)>,
    pub background: Option<u8>,
    pub domain: Option<(P, P)>,
    pub interfaces: Vec<(Vec<P>, bool)>,
    pub sources: Vec<P>,
    pub receivers: Vec<P>,
    pub paths: Vec<RawPath>,
    pub max_iterations: Option<u8>,
    pub tolerance: Option<u8>,
}

/// Scales applied to every coordinate: within the accepted range and beyond it (subnormal
/// ones included), so that refusals are exercised as much as traces.
const SCALES: [f64; 16] = [
    1.0, 1e-3, 1e3, 1e-150, 1e90, 1.0, 1.0, 1.0, 1e-99, 1e99, 1e-101, 1e-300, 1e-310, 5e-324,
    1e-320, 2e-308,
];

pub fn build(input: &Input) -> SceneSpec {
    let scale = SCALES[usize::from(input.scale) % SCALES.len()];
    let pt = |p: &P| [p.0.value() * scale, p.1.value() * scale];
    let media_names: Vec<String> = (0..input.media.len().clamp(1, 4))
        .map(|k| format!("m{k}"))
        .collect();
    let iface_names: Vec<String> = (0..input.interfaces.len().min(5))
        .map(|k| format!("i{k}"))
        .collect();
    let mut media = BTreeMap::new();
    for (k, name) in media_names.iter().enumerate() {
        let (code, as_index, at) = input.media.get(k).copied().unwrap_or((128, false, None));
        let v = match code {
            0 => 0.0,
            255 => -1.0,
            c => 10f64.powf((f64::from(c) - 128.0) / 32.0),
        };
        media.insert(
            name.clone(),
            MediumSpec {
                speed: (!as_index).then_some(v),
                index: as_index.then(|| if v > 0.0 { 1.0 / v } else { v }),
                at: at.as_ref().map(pt),
                density: None,
                attenuation: None,
            },
        );
    }
    let interfaces = input
        .interfaces
        .iter()
        .zip(&iface_names)
        .map(|((points, closed), name)| {
            (
                name.clone(),
                InterfaceSpec {
                    points: points.iter().take(12).map(pt).collect(),
                    closed: *closed,
                    reflection: None,
                },
            )
        })
        .collect();
    let name_of = |names: &[String], k: u8, unknown: &str| {
        names
            .get(usize::from(k) % (names.len() + 1))
            .cloned()
            .unwrap_or_else(|| unknown.to_string())
    };
    let paths = input
        .paths
        .iter()
        .take(4)
        .map(|(steps, leg_media)| {
            let steps: Vec<StepSpec> = steps
                .iter()
                .take(6)
                .map(|&(reflect, i)| {
                    // Mostly known interfaces, sometimes an unknown one.
                    let name = if iface_names.is_empty() {
                        "none".to_string()
                    } else {
                        iface_names[usize::from(i) % iface_names.len()].clone()
                    };
                    if reflect {
                        StepSpec::Reflect(name)
                    } else {
                        StepSpec::Refract(name)
                    }
                })
                .collect();
            let media = leg_media.as_ref().map(|m| {
                m.iter()
                    .take(steps.len() + 1 + usize::from(m.len() > 20))
                    .map(|&j| name_of(&media_names, j, "unknown"))
                    .collect()
            });
            PathSpec {
                name: None,
                steps,
                media,
            }
        })
        .collect();
    SceneSpec {
        description: None,
        media,
        background: input
            .background
            .map(|b| name_of(&media_names, b, "unknown")),
        domain: input.domain.as_ref().map(|(a, b)| [pt(a), pt(b)]),
        interfaces,
        sources: input.sources.iter().take(3).map(pt).collect(),
        receivers: input
            .receivers
            .iter()
            .take(3)
            .map(pt)
            .collect::<Vec<_>>()
            .into(),
        paths,
        solver: (input.max_iterations.is_some() || input.tolerance.is_some()).then(|| SolverSpec {
            max_iterations: input.max_iterations.map(u64::from),
            tolerance: input.tolerance.map(|t| 10f64.powf(-f64::from(t % 20))),
            ..SolverSpec::default()
        }),
        search: None,
        amplitudes: None,
        impulse_response: None,
    }
}

/// Whether every number in the spec is finite (then it round-trips through JSON exactly).
#[allow(dead_code, reason = "used by the structured target only")]
pub fn all_finite(spec: &SceneSpec) -> bool {
    let p = |p: &[f64; 2]| p[0].is_finite() && p[1].is_finite();
    spec.media.values().all(|m| m.at.as_ref().is_none_or(p))
        && spec.domain.as_ref().is_none_or(|[a, b]| p(a) && p(b))
        && spec.interfaces.values().all(|i| i.points.iter().all(p))
        && spec.sources.iter().all(p)
        && match &spec.receivers {
            ReceiversSpec::Points(list) => list.iter().all(p),
            ReceiversSpec::Grid { grid } => grid.x.iter().chain(&grid.y).all(|v| v.is_finite()),
        }
}

