//! Property tests: random valid scenes trace cleanly and physically, random invalid ones fail cleanly.
//!
//! The generator builds layered scenes: up to four open polylines, each confined to its own
//! horizontal band (x strictly increasing, so it neither crosses itself nor another band),
//! either spanning the whole `domain` width (it divides the domain) or ending inside it, plus
//! optionally a convex closed polygon placed in one of the gaps between bands ("slots"). Media
//! carry `at` points in distinct regions (the regions are known by construction) and usually a
//! background, so region lookup works for paths without `media`. Sources and receivers lie
//! anywhere (also outside the domain) or inside a chosen slot. Paths are either random step
//! sequences (mostly impossible: they exercise `no_path` and friends) or plausible ones: a walk
//! up and down the layers from the first source's slot to the first receiver's, with
//! reflections, refractions and passes through or off the polygon. Everything is scaled and
//! shifted by a random similarity so that units and far-from-origin coordinates are exercised.
//!
//! Every test uses a fixed seed and no failure persistence, so a run is reproducible; the
//! numbers of cases are sized so that the whole file runs in well under 20 s in release
//! (about 7 s on 2 cores). `PROP_CASES=N` and `PROP_SEED=S` override both for a deeper or a
//! different search. Plausible paths are named `q0`, `q1`, … in a failing scene, random ones
//! `p0`, `p1`, …

use eigenray::geom::{Segment, orient};
use eigenray::scene::DEFAULT_MAX_ITERATIONS;
use eigenray::scene::StepKind;
use eigenray::{
    InterfaceSpec, MediumSpec, PathSpec, Point, Ray, Scene, SceneSpec, Status, StepSpec, Tracer,
    Workspace, scene::SolverSpec,
};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use serde_json::{Value, json};

#[path = "support/interface.rs"]
mod interface;
use interface::{distance_to_polyline, segment_distance};

/// Width and height of the unit layout before the random similarity.
const W: f64 = 10.0;
const H: f64 = 10.0;

fn config(cases: u32, seed: u64) -> Config {
    let cases = std::env::var("PROP_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(cases);
    let seed = std::env::var("PROP_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(seed);
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        max_shrink_iters: 2000,
        ..Config::default()
    }
}

/// One open interface: its interior vertices (`(u, v)` in the unit square of its band) and
/// whether it spans the domain's width.
#[derive(Clone, Debug)]
struct RawLine {
    vertices: Vec<(f64, f64)>,
    full: bool,
}

/// A convex polygon in gap `slot`: angle jitters, radius and centre fractions.
#[derive(Clone, Debug)]
struct RawPolygon {
    slot: usize,
    jitter: Vec<f64>,
    radius: f64,
    cx: f64,
}

/// A source or receiver: anywhere around the domain, inside slot `slot`, or exactly on a
/// vertex of an interface (a receiver on the sea floor).
#[derive(Clone, Copy, Debug)]
enum RawPoint {
    Anywhere(f64, f64),
    InSlot(usize, f64, f64),
    OnVertex(f64),
}

/// The steps of a path.
#[derive(Clone, Debug)]
enum RawSteps {
    /// `(reflect?, interface choice)` per step.
    Random(Vec<(bool, usize)>),
    /// A walk through the layers: start going up?, then per move `(reflect?, lens code)`.
    Plausible(bool, Vec<(bool, u8)>),
}

/// One path: its steps, and leg media choices when explicit.
#[derive(Clone, Debug)]
struct RawPath {
    steps: RawSteps,
    media: Option<Vec<usize>>,
}

/// Everything random about a scene; [`build`] turns it into a valid [`SceneSpec`].
#[derive(Clone, Debug)]
struct RawScene {
    scale_exp: f64,
    offset: (f64, f64),
    /// `(log10 speed, given as index?, region claimed by its at)`.
    media: Vec<(f64, bool, Option<usize>)>,
    background: Option<usize>,
    lines: Vec<RawLine>,
    polygon: Option<RawPolygon>,
    sources: Vec<RawPoint>,
    receivers: Vec<RawPoint>,
    paths: Vec<RawPath>,
    max_iterations: Option<u64>,
    tolerance: Option<f64>,
}

fn raw_scene() -> impl Strategy<Value = RawScene> {
    let unit = 0.0..1.0f64;
    let medium = (
        -1.0..1.0f64,
        any::<bool>(),
        prop::option::weighted(0.8, 0..6usize),
    );
    let line = (
        prop::collection::vec((unit.clone(), unit.clone()), 0..7),
        prop::bool::weighted(0.8),
    )
        .prop_map(|(vertices, full)| RawLine { vertices, full });
    let polygon = (
        0..5usize,
        prop::collection::vec(unit.clone(), 3..9),
        0.3..0.9f64,
        unit.clone(),
    )
        .prop_map(|(slot, jitter, radius, cx)| RawPolygon {
            slot,
            jitter,
            radius,
            cx,
        });
    let point = prop_oneof![
        1 => (-0.1..1.1f64, -0.1..1.1f64).prop_map(|(u, v)| RawPoint::Anywhere(u, v)),
        2 => (0..5usize, unit.clone(), unit.clone()).prop_map(|(s, u, v)| RawPoint::InSlot(s, u, v)),
        1 => unit.clone().prop_map(RawPoint::OnVertex),
    ];
    let steps = prop_oneof![
        prop::collection::vec((any::<bool>(), 0..5usize), 0..7).prop_map(RawSteps::Random),
        (
            any::<bool>(),
            prop::collection::vec((prop::bool::weighted(0.4), any::<u8>()), 0..5)
        )
            .prop_map(|(up, moves)| RawSteps::Plausible(up, moves)),
    ];
    let path = (steps, any::<bool>(), prop::collection::vec(0..4usize, 20)).prop_map(
        |(steps, explicit, media)| RawPath {
            steps,
            media: explicit.then_some(media),
        },
    );
    (
        (
            -3.0..3.0f64,
            (-100.0..100.0f64, -100.0..100.0f64),
            prop::collection::vec(medium, 1..5),
            prop::option::weighted(0.85, 0..4usize),
        ),
        prop::collection::vec(line, 1..5),
        prop::option::weighted(0.4, polygon),
        prop::collection::vec(point.clone(), 1..3),
        prop::collection::vec(point, 1..4),
        prop::collection::vec(path, 1..5),
        prop::option::weighted(0.3, 1..300u64),
        prop::option::weighted(0.2, -13.0..-10.0f64),
    )
        .prop_map(
            |(
                (scale_exp, offset, media, background),
                lines,
                polygon,
                sources,
                receivers,
                paths,
                max_iterations,
                tolerance,
            )| {
                RawScene {
                    scale_exp,
                    offset,
                    media,
                    background,
                    lines,
                    polygon,
                    sources,
                    receivers,
                    paths,
                    max_iterations,
                    tolerance: tolerance.map(|e| 10f64.powf(e)),
                }
            },
        )
}

/// The steps of a plausible path from slot `from` to slot `to` through `n` layer interfaces
/// (interface `c` lies between slots `c` and `c + 1`), with the polygon (if any) in slot
/// `lens`: `(reflect?, interface index)`, where index `n` is the polygon.
fn walk(
    from: usize,
    to: usize,
    n: usize,
    lens: Option<usize>,
    up: bool,
    moves: &[(bool, u8)],
) -> Vec<(bool, usize)> {
    let mut steps = Vec::new();
    let (mut c, mut up) = (from, if from == to { up } else { to > from });
    for &(reflect, code) in moves {
        if lens == Some(c) && code % 4 == 0 {
            // Through the lens, or off its outside.
            if code % 8 == 0 {
                steps.extend([(false, n), (false, n)]);
            } else {
                steps.push((true, n));
            }
            continue;
        }
        let next = if up {
            (c < n).then_some(c)
        } else {
            c.checked_sub(1)
        };
        let Some(i) = next else {
            break;
        };
        steps.push((reflect, i));
        if reflect {
            up = !up;
        } else if up {
            c += 1;
        } else {
            c -= 1;
        }
    }
    if c != to && (to > c) != up {
        let next = if up {
            (c < n).then_some(c)
        } else {
            c.checked_sub(1)
        };
        if let Some(i) = next {
            steps.push((true, i));
        }
    }
    while c < to {
        steps.push((false, c));
        c += 1;
    }
    while c > to {
        c -= 1;
        steps.push((false, c));
    }
    steps
}

/// The scene of a [`RawScene`], valid by construction.
fn build(raw: &RawScene) -> SceneSpec {
    let s = 10f64.powf(raw.scale_exp);
    let (ox, oy) = (raw.offset.0 * s, raw.offset.1 * s);
    let map = |x: f64, y: f64| [ox + s * x, oy + s * y];
    // A polygon needs a free gap, and at most four interfaces in all.
    let nlines = if raw.polygon.is_some() {
        raw.lines.len().min(3)
    } else {
        raw.lines.len()
    };
    let lines = &raw.lines[..nlines];
    let pitch = H / (nlines + 1) as f64;
    let half = 0.25 * pitch;
    let centre = |k: usize| pitch * (k + 1) as f64;

    let mut spec = SceneSpec::default();
    let mut names = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        let (x0, x1) = if line.full {
            (0.0, W)
        } else {
            (0.03 * W, 0.97 * W)
        };
        let mut xs: Vec<(f64, f64)> = line
            .vertices
            .iter()
            .map(|&(u, v)| (x0 + (x1 - x0) * (0.01 + 0.98 * u), v))
            .collect();
        xs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut pts = vec![map(x0, centre(k))];
        let mut last = x0;
        for (x, v) in xs {
            if x - last > 1e-3 * W && x1 - x > 1e-3 * W {
                pts.push(map(x, centre(k) + half * (2.0 * v - 1.0)));
                last = x;
            }
        }
        pts.push(map(x1, centre(k)));
        let name = format!("i{k}");
        spec.interfaces.insert(
            name.clone(),
            InterfaceSpec {
                points: pts,
                closed: false,
                reflection: None,
            },
        );
        names.push(name);
    }

    // Slots bottom to top, and the regions they make: a slot merges with the next one when
    // the interface between them does not span the domain.
    let slot_bounds = |l: usize| {
        let lo = if l == 0 { 0.0 } else { centre(l - 1) + half };
        let hi = if l == nlines { H } else { centre(l) - half };
        (lo, hi)
    };
    let mut region_at: Vec<[f64; 2]> = Vec::new();
    for l in 0..=nlines {
        if l == 0 || lines[l - 1].full {
            let (lo, hi) = slot_bounds(l);
            region_at.push(map(0.25 * W, 0.5 * (lo + hi)));
        }
    }
    let lens = raw.polygon.as_ref().map(|p| p.slot % (nlines + 1));
    if let (Some(poly), Some(slot)) = (&raw.polygon, lens) {
        let (lo, hi) = slot_bounds(slot);
        let r = poly.radius * (0.5 * (hi - lo)).min(0.1 * W);
        let (cx, cy) = (W * (0.55 + 0.3 * poly.cx), 0.5 * (lo + hi));
        let n = poly.jitter.len();
        let mut pts = Vec::new();
        let (mut sx, mut sy) = (0.0, 0.0);
        for (k, j) in poly.jitter.iter().enumerate() {
            let a = std::f64::consts::TAU * (k as f64 + 0.8 * j) / n as f64;
            let (x, y) = (cx + r * a.cos(), cy + r * a.sin());
            sx += x / n as f64;
            sy += y / n as f64;
            pts.push(map(x, y));
        }
        spec.interfaces.insert(
            "poly".into(),
            InterfaceSpec {
                points: pts,
                closed: true,
                reflection: None,
            },
        );
        names.push("poly".into());
        region_at.push(map(sx, sy));
    }

    let mut claimed = vec![false; region_at.len()];
    let medium_names: Vec<String> = (0..raw.media.len()).map(|k| format!("m{k}")).collect();
    // One kind of medium a scene (the first one's): a scene that mixes them is refused.
    let as_index = raw.media.first().is_some_and(|m| m.1);
    for (k, &(log_speed, _, region)) in raw.media.iter().enumerate() {
        let v = 10f64.powf(log_speed);
        let at = region.map(|r| r % region_at.len()).and_then(|r| {
            (!claimed[r]).then(|| {
                claimed[r] = true;
                region_at[r]
            })
        });
        spec.media.insert(
            medium_names[k].clone(),
            MediumSpec {
                speed: (!as_index).then_some(v),
                index: as_index.then_some(1.0 / v),
                at,
                ..MediumSpec::default()
            },
        );
    }
    spec.background = raw
        .background
        .map(|b| medium_names[b % medium_names.len()].clone());
    spec.domain = Some([map(0.0, 0.0), map(W, H)]);

    let vertices: Vec<[f64; 2]> = spec
        .interfaces
        .values()
        .flat_map(|i| i.points.iter().copied())
        .collect();
    let place = |p: &RawPoint| match *p {
        RawPoint::OnVertex(u) => {
            vertices[((u * vertices.len() as f64) as usize).min(vertices.len() - 1)]
        }
        RawPoint::Anywhere(u, v) => map(W * u, H * v),
        RawPoint::InSlot(slot, u, v) => {
            let (lo, hi) = slot_bounds(slot % (nlines + 1));
            map(W * (0.02 + 0.96 * u), lo + (hi - lo) * (0.1 + 0.8 * v))
        }
    };
    let slot_of = |p: &RawPoint, default: usize| match *p {
        RawPoint::InSlot(slot, ..) => slot % (nlines + 1),
        RawPoint::Anywhere(..) | RawPoint::OnVertex(..) => default,
    };
    spec.sources = raw.sources.iter().map(place).collect();
    spec.receivers = raw.receivers.iter().map(place).collect::<Vec<_>>().into();
    let from = slot_of(&raw.sources[0], 0);
    let to = slot_of(&raw.receivers[0], nlines);

    spec.paths = raw
        .paths
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let steps = match &p.steps {
                RawSteps::Random(steps) => steps
                    .iter()
                    .map(|&(reflect, i)| (reflect, i % names.len()))
                    .collect(),
                RawSteps::Plausible(up, moves) => walk(from, to, nlines, lens, *up, moves),
            };
            let media = p.media.as_ref().map(|m| {
                (0..=steps.len())
                    .map(|j| medium_names[m[j % m.len()] % medium_names.len()].clone())
                    .collect()
            });
            PathSpec {
                name: Some(format!(
                    "{}{k}",
                    if matches!(p.steps, RawSteps::Plausible(..)) {
                        "q"
                    } else {
                        "p"
                    }
                )),
                steps: steps
                    .into_iter()
                    .map(|(reflect, i)| {
                        let name = names[i].clone();
                        if reflect {
                            StepSpec::Reflect(name)
                        } else {
                            StepSpec::Refract(name)
                        }
                    })
                    .collect(),
                media,
            }
        })
        .collect();
    // A scene where no medium fills any region is refused: the first medium is the
    // background then. A medium that fills no region (no `at`, not the background) and that
    // no path names is refused too: leave it out.
    if spec.background.is_none() && spec.media.values().all(|m| m.at.is_none()) {
        spec.background = spec.media.keys().next().cloned();
    }
    let named: std::collections::BTreeSet<&String> = spec
        .paths
        .iter()
        .flat_map(|p| p.media.iter().flatten())
        .collect();
    let unused: Vec<String> = spec
        .media
        .iter()
        .filter(|(name, m)| {
            m.at.is_none() && spec.background.as_ref() != Some(*name) && !named.contains(name)
        })
        .map(|(name, _)| name.clone())
        .collect();
    if unused.len() == spec.media.len() {
        // No medium would fill anything: the first one becomes the background.
        spec.background = Some(unused[0].clone());
    }
    for name in unused
        .iter()
        .filter(|n| spec.background.as_ref() != Some(*n))
    {
        spec.media.remove(name);
    }
    if raw.max_iterations.is_some() || raw.tolerance.is_some() {
        spec.solver = Some(SolverSpec {
            tolerance: raw.tolerance,
            max_iterations: raw.max_iterations,
            ..Default::default()
        });
    }
    spec
}

/// Which side of interface `line` the point `p` is on, when that is clear: for an open
/// polyline (the generator's are graphs over x) whether `p` is above it, for a closed one
/// whether `p` is inside. `None` for a point beyond an open polyline's x-range or within
/// `margin` of the curve.
fn side_of(line: &eigenray::polyline::Polyline, p: Point, margin: f64) -> Option<bool> {
    let v = line.vertices();
    let n = line.num_segments();
    let near = (0..n).any(|j| {
        let Segment { start: a, end: b } = line.segment(j);
        segment_distance(p, a, b) <= margin
    });
    if near {
        return None;
    }
    if line.is_closed() {
        let mut inside = false;
        for j in 0..n {
            let Segment { start: a, end: b } = line.segment(j);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                inside = !inside;
            }
        }
        return Some(inside);
    }
    if !(p.x > v[0].x && p.x < v[v.len() - 1].x) {
        return None;
    }
    let j = (0..n).find(|&j| v[j + 1].x >= p.x)?;
    let (a, b) = (v[j], v[j + 1]);
    let y = a.y + (p.x - a.x) / (b.x - a.x) * (b.y - a.y);
    Some(p.y > y)
}

fn unit(a: Point, b: Point) -> (f64, f64) {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let l = dx.hypot(dy);
    (dx / l, dy / l)
}

/// Checks one traced ray against the physics and the documented output; `Err` says what is wrong.
fn check_ray(scene: &Scene, tracer: &Tracer, ray: &Ray) -> Result<(), String> {
    let path = &scene.paths()[ray.path];
    let k = path.steps.len();
    let size = scene.bbox().diagonal();
    if ray.iterations > scene.solver().max_iterations {
        return Err(format!(
            "{} iterations > max_iterations {}",
            ray.iterations,
            scene.solver().max_iterations
        ));
    }
    if (ray.status == Status::Converged) != ray.reason.is_none() {
        return Err(format!(
            "status {} with reason {:?}",
            ray.status, ray.reason
        ));
    }
    // One unknown: the time along one polyline, a function of one parameter. Its iteration
    // must end in a classification (a smooth stationary point, a vertex, an end of the
    // polyline), not cycle until the default iteration limit.
    if k == 1
        && scene.solver().max_iterations >= DEFAULT_MAX_ITERATIONS
        && ray.status == Status::NotConverged
    {
        return Err(format!(
            "a single-step ray did not converge in {} iterations (residual {})",
            ray.iterations, ray.residual
        ));
    }
    if !ray.status.has_time() {
        return if ray.time.is_nan() && ray.points.is_empty() {
            Ok(())
        } else {
            Err(format!("{} ray with a time or points", ray.status))
        };
    }
    let time = ray.time;
    if !(time.is_finite() && time >= 0.0) {
        return Err(format!("time {time}"));
    }
    if ray.points.len() != k + 2 || ray.points.iter().any(|p| !p.is_finite()) {
        return Err(format!("points {:?}", ray.points));
    }
    if ray.points[0] != scene.sources()[ray.source]
        || ray.points[k + 1] != scene.receivers()[ray.receiver]
    {
        return Err("points do not start at the source and end at the receiver".into());
    }
    if ray.media.len() != k + 1 {
        return Err(format!("{} leg media for {k} steps", ray.media.len()));
    }
    if let Some(m) = &path.media
        && &ray.media != m
    {
        return Err(format!("leg media {:?}, path gives {m:?}", ray.media));
    }
    let w: Vec<f64> = ray
        .media
        .iter()
        .map(|&m| scene.media()[m].slowness)
        .collect();
    let sum: f64 = (0..=k)
        .map(|i| w[i] * ray.points[i].distance(ray.points[i + 1]))
        .sum();
    if (sum - time).abs() > 1e-10 * sum.max(f64::MIN_POSITIVE) {
        return Err(format!("time {time}, but Σ w ℓ = {sum}"));
    }
    for (i, step) in path.steps.iter().enumerate() {
        let line = &scene.interfaces()[step.interface].polyline;
        let p = ray.points[i + 1];
        let d = distance_to_polyline(line, p);
        if d > 1e-9 * size {
            return Err(format!(
                "interaction {i} at {p:?} is {d:e} from its interface"
            ));
        }
        if path.media.is_none()
            && step.kind == StepKind::Reflect
            && ray.media[i] != ray.media[i + 1]
        {
            return Err(format!("reflection {i} changes the medium"));
        }
    }
    if ray.status != Status::Converged {
        return Ok(());
    }
    // A leg between two interactions never vanishes on a converged ray. The first or last
    // leg does when the source or receiver lies on the interface there: `T` has a kink, and
    // only the other leg's side is defined.
    let vanished: Vec<bool> = (0..=k)
        .map(|l| ray.points[l].distance(ray.points[l + 1]) <= 1e-9 * size)
        .collect();
    if let Some(l) = (1..k).find(|&l| vanished[l]) {
        return Err(format!("leg {l} between two interactions vanished"));
    }

    for (i, step) in path.steps.iter().enumerate() {
        let line = &scene.interfaces()[step.interface].polyline;
        let (prev, p, next) = (ray.points[i], ray.points[i + 1], ray.points[i + 2]);
        // The segment the point lies on (near a vertex, either neighbour may be it).
        let dists: Vec<f64> = (0..line.num_segments())
            .map(|j| {
                let Segment { start: a, end: b } = line.segment(j);
                segment_distance(p, a, b)
            })
            .collect();
        let best = dists.iter().copied().fold(f64::INFINITY, f64::min);
        let mut why = String::new();
        let ok = (0..line.num_segments())
            .filter(|&j| dists[j] <= best + 1e-12 * size)
            .any(|j| {
                let t = line.tangent(j);
                let Segment { start: a, end: b } = line.segment(j);
                let u0 = unit(prev, p);
                let u1 = unit(p, next);
                let lhs = w[i] * (u0.0 * t.x + u0.1 * t.y);
                let rhs = w[i + 1] * (u1.0 * t.x + u1.1 * t.y);
                let (sa, sb) = (orient(a, b, prev), orient(a, b, next));
                let (snell, side) = if vanished[i] {
                    (true, sb != 0.0)
                } else if vanished[i + 1] {
                    (true, sa != 0.0)
                } else {
                    let snell = (lhs - rhs).abs() <= 1e-9 * (w[i] + w[i + 1]);
                    let side = match step.kind {
                        StepKind::Reflect => sa * sb > 0.0,
                        StepKind::Refract => sa * sb < 0.0,
                        StepKind::Diffract { .. } => true,
                    };
                    (snell, side)
                };
                if !(snell && side) {
                    why = format!(
                        "segment {j}: w u·t {lhs} vs {rhs} (diff {:e}), sides {sa:e} {sb:e}",
                        (lhs - rhs) / (w[i] + w[i + 1])
                    );
                }
                snell && side
            });
        if !ok {
            return Err(format!("interaction {i} ({:?}): {why}", step.kind));
        }
    }

    // Globally, too: a leg crosses no interface, so its side of every interface (above or
    // below an open one, inside or outside the polygon) changes only at a refraction through
    // that interface. This does not rely on the local side test near the interaction points.
    // (Around an open polyline's end a path changes sides without crossing: the two legs and
    // the point between them must lie over its x-range, where it separates the plane.)
    let mid = |leg: usize| ray.points[leg].lerp(ray.points[leg + 1], 0.5);
    for (idx, iface) in scene.interfaces().iter().enumerate() {
        let line = &iface.polyline;
        for leg in 1..=k {
            let p = ray.points[leg];
            let v = line.vertices();
            let over = p.x > v[0].x && p.x < v[v.len() - 1].x;
            if !(line.is_closed() || over) {
                continue;
            }
            let before = side_of(line, mid(leg - 1), 1e-9 * size);
            let now = side_of(line, mid(leg), 1e-9 * size);
            if let (Some(before), Some(now)) = (before, now) {
                let step = path.steps[leg - 1];
                let flips = step.interface == idx && step.kind == StepKind::Refract;
                if (before != now) != flips {
                    return Err(format!(
                        "leg {leg} is on side {now} of interface `{}`, leg {} on side {before}, \
                         across a {:?} on interface {}",
                        iface.name,
                        leg - 1,
                        step.kind,
                        step.interface
                    ));
                }
            }
        }
    }

    // Leg media: a leg of a converged ray crosses no interface, so with region lookup it lies
    // in one region, and that region's medium is the leg's when the whole ray stays inside
    // the domain box (a leg from outside it keeps its medium across a reflection into it).
    if path.media.is_none() {
        let regions = tracer.regions().ok_or("lookup path without regions")?;
        let dom = scene.domain().ok_or("no domain")?;
        let inside =
            |p: Point| p.x > dom.min.x && p.x < dom.max.x && p.y > dom.min.y && p.y < dom.max.y;
        if ray.points.iter().all(|&p| inside(p)) {
            for leg in (0..=k).filter(|&l| !vanished[l]) {
                let mid = ray.points[leg].lerp(ray.points[leg + 1], 0.5);
                let m = regions.medium_at(mid);
                if m != Some(ray.media[leg]) {
                    return Err(format!(
                        "leg {leg} has medium {}, the region at its midpoint {m:?}",
                        ray.media[leg]
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Traces a generated scene and checks every ray; also that a second, sequential trace with
/// one reused workspace in reverse ray order gives identical rays.
fn check_scene(spec: &SceneSpec) -> Result<(), TestCaseError> {
    let text = serde_json::to_string(spec).expect("a spec serialises");
    // Scenes whose media cannot mean what they say are refused up front: a source on an
    // interface or in a region no medium fills (the generator puts sources on vertices and
    // leaves regions unclaimed on purpose).
    let refused = |e: &eigenray::SceneError| e.key.starts_with("sources[");
    let scene = match Scene::from_json(&text) {
        Err(e) if refused(&e) => return Ok(()),
        other => other
            .map_err(|e| TestCaseError::fail(format!("generated scene rejected: {e}\n{text}")))?,
    };
    Scene::from_spec(spec)
        .map_err(|e| TestCaseError::fail(format!("from_spec rejects, from_json accepts: {e}")))?;
    let tracer = match Tracer::new(&scene) {
        Err(e) if refused(&e) => return Ok(()),
        other => other.map_err(|e| TestCaseError::fail(format!("Tracer::new: {e}\n{text}")))?,
    };
    let rays = tracer.trace_all();
    prop_assert_eq!(rays.len(), scene.num_rays());
    for (n, ray) in rays.iter().enumerate() {
        if let Err(e) = check_ray(&scene, &tracer, ray) {
            return Err(TestCaseError::fail(format!(
                "ray {n} (source {}, receiver {}, path {}): {} {:?}: {e}\npoints {:?}\n{text}",
                ray.source, ray.receiver, ray.path, ray.status, ray.reason, ray.points
            )));
        }
    }
    let mut ws = Workspace::new();
    for (n, ray) in rays.iter().enumerate().rev() {
        let again = tracer.trace(ray.source, ray.receiver, ray.path, &mut ws);
        // NaN residuals (rays that failed before iterating) compare unequal: compare bits.
        let same = again.status == ray.status
            && again.time.to_bits() == ray.time.to_bits()
            && again.points == ray.points
            && again.media == ray.media
            && again.iterations == ray.iterations
            && again.residual.to_bits() == ray.residual.to_bits();
        prop_assert!(
            same,
            "ray {} differs when traced with a reused workspace:\n{:?}\n{:?}\n{}",
            n,
            ray,
            again,
            text
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(12_000, 0x5eed_e16e_4a7f_0001))]

    /// Valid scenes: accepted, and every ray ends cleanly and, when converged, physically.
    #[test]
    fn valid_scenes_trace_physically(raw in raw_scene()) {
        check_scene(&build(&raw))?;
    }
}

/// How to break a valid scene, and the key the error must start with.
#[derive(Clone, Debug)]
enum Breakage {
    /// Delete a required top-level key.
    DropTopLevel(usize),
    /// Delete `points` of the first interface.
    DropPoints,
    /// Delete `steps` of the first path.
    DropSteps,
    /// Set the first medium's speed (or index) to this non-positive value.
    NonPositiveSpeed(f64),
    /// Give the first interface one vertex.
    OnePoint,
    /// Repeat one vertex of the first interface.
    RepeatedVertex(usize),
    /// Make the first interface a closed polyline on one line.
    ClosedCollinear(usize),
    /// Rename a step of the first path with steps to an unknown interface.
    UnknownInterface(usize),
    /// Add an unknown top-level key.
    UnknownKey,
    /// Give the first path the wrong number of media.
    WrongMediaCount,
}

fn breakage() -> impl Strategy<Value = Breakage> {
    prop_oneof![
        (0..3usize).prop_map(Breakage::DropTopLevel),
        Just(Breakage::DropPoints),
        Just(Breakage::DropSteps),
        prop_oneof![Just(0.0), Just(-0.0), -10.0..0.0f64].prop_map(Breakage::NonPositiveSpeed),
        Just(Breakage::OnePoint),
        (0..8usize).prop_map(Breakage::RepeatedVertex),
        (3..6usize).prop_map(Breakage::ClosedCollinear),
        (0..8usize).prop_map(Breakage::UnknownInterface),
        Just(Breakage::UnknownKey),
        Just(Breakage::WrongMediaCount),
    ]
}

/// Applies `b` to the scene document; returns the key prefix the error must have, or `None`
/// when the scene offers nothing to break that way.
fn apply(doc: &mut Value, b: &Breakage) -> Option<String> {
    let first_iface = doc["interfaces"]
        .as_object()
        .and_then(|m| m.keys().next().cloned())?;
    let first_medium = doc["media"]
        .as_object()
        .and_then(|m| m.keys().next().cloned())?;
    match *b {
        Breakage::DropTopLevel(k) => {
            let key = ["media", "sources", "receivers"][k];
            doc.as_object_mut()?.remove(key);
            Some(key.into())
        }
        Breakage::DropPoints => {
            doc["interfaces"][&first_iface]
                .as_object_mut()?
                .remove("points");
            Some(format!("interfaces.{first_iface}.points"))
        }
        Breakage::DropSteps => {
            doc["paths"][0].as_object_mut()?.remove("steps");
            Some("paths[0].steps".into())
        }
        Breakage::NonPositiveSpeed(v) => {
            let m = doc["media"][&first_medium].as_object_mut()?;
            let field = if m.contains_key("index") {
                "index"
            } else {
                "speed"
            };
            m.insert(field.into(), json!(v));
            Some(format!("media.{first_medium}.{field}"))
        }
        Breakage::OnePoint => {
            let pts = doc["interfaces"][&first_iface]["points"].as_array_mut()?;
            pts.truncate(1);
            Some(format!("interfaces.{first_iface}.points"))
        }
        Breakage::RepeatedVertex(k) => {
            let pts = doc["interfaces"][&first_iface]["points"].as_array_mut()?;
            let k = k % pts.len();
            let p = pts[k].clone();
            pts.insert(k, p);
            Some(format!("interfaces.{first_iface}.points"))
        }
        Breakage::ClosedCollinear(n) => {
            let iface = doc["interfaces"][&first_iface].as_object_mut()?;
            let pts: Vec<Value> = (0..n).map(|k| json!([k as f64, 2.0 * k as f64])).collect();
            iface.insert("points".into(), Value::Array(pts));
            iface.insert("closed".into(), json!(true));
            // It may now also cross another interface; validation reports one of the two,
            // both under this interface's points.
            Some(format!("interfaces.{first_iface}.points"))
        }
        Breakage::UnknownInterface(j) => {
            let paths = doc["paths"].as_array_mut()?;
            let (k, path) = paths
                .iter_mut()
                .enumerate()
                .find(|(_, p)| p["steps"].as_array().is_some_and(|s| !s.is_empty()))?;
            let steps = path["steps"].as_array_mut()?;
            let j = j % steps.len();
            let step = steps[j].as_object_mut()?;
            let kind = step.keys().next()?.clone();
            step.insert(kind.clone(), json!("no such interface"));
            Some(format!("paths[{k}].steps[{j}].{kind}"))
        }
        Breakage::UnknownKey => {
            doc.as_object_mut()?.insert("recievers".into(), json!([]));
            Some(String::new())
        }
        Breakage::WrongMediaCount => {
            let path = doc["paths"][0].as_object_mut()?;
            let n = path["steps"].as_array()?.len();
            let media: Vec<Value> = (0..n + 2).map(|_| json!(first_medium)).collect();
            path.insert("media".into(), Value::Array(media));
            Some("paths[0].media".into())
        }
    }
}

proptest! {
    #![proptest_config(config(10_000, 0x5eed_e16e_4a7f_0002))]

    /// Broken scenes: a clean error naming the broken key, never a panic.
    #[test]
    fn invalid_scenes_fail_cleanly(raw in raw_scene(), b in breakage()) {
        let mut doc = serde_json::to_value(build(&raw)).expect("a spec serialises");
        // A base scene refused already (a source on an interface, see `check_scene`) would
        // name its own problem first.
        if Scene::from_json(&doc.to_string()).is_err() {
            return Ok(());
        }
        let Some(prefix) = apply(&mut doc, &b) else {
            return Ok(());
        };
        let text = doc.to_string();
        match Scene::from_json(&text) {
            Ok(_) => prop_assert!(false, "{:?} accepted:\n{}", b, text),
            Err(e) => {
                prop_assert!(!e.key.is_empty() && !e.message.is_empty(), "{:?}: {:?}", b, e);
                prop_assert!(
                    e.key.starts_with(&prefix),
                    "{:?}: error {} does not name {}\n{}",
                    b,
                    e,
                    prefix,
                    text
                );
            }
        }
    }
}
