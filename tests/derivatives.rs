//! Derivatives of travel times and points: against central differences of re-solved rays on
//! random scenes (refractions through layers, reflections, converted legs, a closed lens with
//! media given and from region lookup, diffraction at a roof's apex), against forward-mode
//! dual numbers carried through a Newton solve of each ray, and the seed's case in closed form.
//!
//! `DERIV_SEED=S` and `DERIV_SCENES=N` change the random scenes; each test prints the largest
//! errors it saw (`--nocapture`).

use eigenray::{
    BatchOptions, Gradient, Point, PointSensitivities, Scene, Status, Tracer, Vec2, Workspace,
    derivatives::{Axis, BatchGradients, Parameter},
};
use serde_json::{Value, json};

/// SplitMix64: a small reproducible generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

fn env_or(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// An open polyline across `x ∈ [−10, 10]` around height `y` with `n` vertices.
fn band(rng: &mut Rng, y: f64, n: usize, wiggle: f64) -> Value {
    let pts: Vec<Value> = (0..n)
        .map(|i| {
            let x = -10.0 + 20.0 * i as f64 / (n - 1) as f64;
            let x = if i == 0 || i == n - 1 {
                x
            } else {
                x + rng.uniform(-1.0, 1.0)
            };
            json!([x, y + rng.uniform(-wiggle, wiggle)])
        })
        .collect();
    json!({ "points": pts })
}

/// A layered scene: `layers` open polylines `l0` (top) … with media `m0` (above `l0`) …,
/// converted media `s1` …, paths: down through every layer, the reflection off each layer
/// back up, and that reflection converted (its reflected leg in `sJ`).
fn layered(rng: &mut Rng) -> Value {
    let layers = 1 + rng.below(3);
    let mut interfaces = serde_json::Map::new();
    let mut media = serde_json::Map::new();
    for j in 0..layers {
        let n = 2 + rng.below(5);
        interfaces.insert(format!("l{j}"), band(rng, -3.0 * j as f64, n, 0.6));
    }
    // Both forms, one per scene (a scene's media are of one kind): indices, or speeds.
    let mut as_index = None;
    for j in 0..=layers {
        let index = *as_index.get_or_insert(rng.below(2) == 0);
        let m = if index {
            json!({ "index": rng.uniform(1.0, 2.0) })
        } else {
            json!({ "speed": rng.uniform(0.5, 1.0) })
        };
        media.insert(format!("m{j}"), m);
        let slow = rng.uniform(1.5, 3.0);
        let s = if index {
            json!({ "index": slow })
        } else {
            json!({ "speed": 1.0 / slow })
        };
        media.insert(format!("s{j}"), s);
    }
    let source = json!([rng.uniform(-4.0, 4.0), rng.uniform(2.0, 4.0)]);
    let below = -3.0 * (layers - 1) as f64 - rng.uniform(2.0, 4.0);
    let receivers = json!([
        [rng.uniform(-5.0, 5.0), below],
        [rng.uniform(-6.0, 6.0), rng.uniform(1.5, 4.0)]
    ]);
    let mut paths = Vec::new();
    let down: Vec<Value> = (0..layers)
        .map(|j| json!({ "refract": format!("l{j}") }))
        .collect();
    let down_media: Vec<String> = (0..=layers).map(|j| format!("m{j}")).collect();
    paths.push(json!({ "name": "down", "steps": down, "media": down_media }));
    for j in 0..layers {
        let mut steps: Vec<Value> = (0..j)
            .map(|i| json!({ "refract": format!("l{i}") }))
            .collect();
        steps.push(json!({ "reflect": format!("l{j}") }));
        steps.extend((0..j).rev().map(|i| json!({ "refract": format!("l{i}") })));
        let mut m: Vec<String> = (0..=j).map(|i| format!("m{i}")).collect();
        m.extend((0..=j).rev().map(|i| format!("m{i}")));
        paths.push(json!({ "name": format!("reflect{j}"), "steps": steps, "media": m }));
        let mut converted = m.clone();
        converted[j + 1] = format!("s{j}");
        paths.push(json!({ "name": format!("converted{j}"), "steps": steps, "media": converted }));
    }
    json!({
        "media": media, "interfaces": interfaces,
        "sources": [source], "receivers": receivers, "paths": paths,
        "solver": { "tolerance": 1e-15 }
    })
}

/// A closed convex lens of 4 to 8 vertices between a source on the left and receivers on the
/// right: through it (media given, and from region lookup) and off its outside.
fn lens(rng: &mut Rng) -> Value {
    let n = 4 + rng.below(5);
    let (r, turn) = (rng.uniform(1.0, 2.0), rng.uniform(0.0, 1.0));
    let pts: Vec<Value> = (0..n)
        .map(|i| {
            let a = turn + std::f64::consts::TAU * i as f64 / n as f64;
            let rr = r * rng.uniform(0.92, 1.0);
            json!([rr * a.cos(), 0.6 * rr * a.sin()])
        })
        .collect();
    json!({
        "media": {
            "air": { "index": 1.0 },
            "glass": { "index": rng.uniform(1.3, 1.8), "at": [0.0, 0.0] }
        },
        "background": "air",
        "interfaces": { "lens": { "points": pts, "closed": true } },
        "sources": [[-6.0, rng.uniform(-0.5, 0.5)]],
        "receivers": [[6.0, rng.uniform(-0.5, 0.5)], [rng.uniform(-3.0, 3.0), 4.0]],
        "paths": [
            { "name": "through", "steps": [{ "refract": "lens" }, { "refract": "lens" }],
              "media": ["air", "glass", "air"] },
            { "name": "looked-up", "steps": [{ "refract": "lens" }, { "refract": "lens" }] },
            { "name": "off", "steps": [{ "reflect": "lens" }], "media": ["air", "air"] }
        ],
        "solver": { "tolerance": 1e-15 }
    })
}

/// A convex roof with short slopes seen from far apart: no specular point on either slope,
/// so the ray diffracts at the apex (`vertex`); and a flat floor beyond, reflected off.
fn roof(rng: &mut Rng) -> Value {
    let (a, h) = (rng.uniform(0.5, 1.5), rng.uniform(0.3, 1.0));
    let apex = rng.uniform(-0.3, 0.3);
    json!({
        "media": { "air": { "index": 1.0 }, "slow": { "index": rng.uniform(1.1, 2.0) } },
        "interfaces": {
            "roof": { "points": [[apex - a, 0.0], [apex, h], [apex + a, 0.0]] }
        },
        "sources": [[rng.uniform(-6.0, -4.0), rng.uniform(0.5, 2.0)]],
        "receivers": [[rng.uniform(4.0, 6.0), rng.uniform(0.5, 2.0)]],
        "paths": [
            { "steps": [{ "reflect": "roof" }], "media": ["air", "air"] },
            { "steps": [{ "reflect": "roof" }], "media": ["air", "slow"] }
        ],
        "solver": { "tolerance": 1e-15 }
    })
}

/// `doc` with `param` (of `scene`, the scene `doc` describes) moved by `h`.
fn perturbed(doc: &Value, scene: &Scene, param: Parameter, h: f64) -> Value {
    let mut d = doc.clone();
    let axis = |a: Axis| if a == Axis::X { 0 } else { 1 };
    let add = |v: &mut Value, h: f64| *v = json!(v.as_f64().unwrap() + h);
    match param {
        Parameter::Source(a) => add(&mut d["sources"][0][axis(a)], h),
        Parameter::Receiver(a) => add(&mut d["receivers"][0][axis(a)], h),
        Parameter::Slowness { medium } => {
            let m = &mut d["media"][&scene.media()[medium].name];
            if let Some(index) = m.get("index").and_then(Value::as_f64) {
                m["index"] = json!(index + h);
            } else {
                let w = 1.0 / m["speed"].as_f64().unwrap();
                m["speed"] = json!(1.0 / (w + h));
            }
        }
        Parameter::Vertex {
            interface,
            vertex,
            axis: a,
        } => {
            let name = &scene.interfaces()[interface].name;
            add(&mut d["interfaces"][name]["points"][vertex][axis(a)], h);
        }
    }
    d
}

/// One solved ray: status, time, points.
#[derive(Clone, Debug)]
struct Solved {
    status: Status,
    time: f64,
    points: Vec<Point>,
}

/// Ray (source 0, receiver `receiver`, path `path`) of the scene `doc` describes, with the
/// receiver moved to receiver 0's place (the perturbations move receiver 0).
fn solve_doc(doc: &Value, receiver: usize, path: usize) -> Option<Solved> {
    let mut d = doc.clone();
    d["receivers"][0] = d["receivers"][receiver].clone();
    let scene = Scene::from_json(&d.to_string()).ok()?;
    let tracer = Tracer::new(&scene).ok()?;
    let mut ws = Workspace::new();
    let rec = tracer.solve(scene.sources()[0], scene.receivers()[0], path, &mut ws);
    rec.status.has_time().then(|| Solved {
        status: rec.status,
        time: rec.time,
        points: ws.points().to_vec(),
    })
}

/// The largest errors seen, and how many derivatives were compared.
#[derive(Debug, Default)]
struct Errors {
    /// Time derivatives: the largest absolute error, and relative error where |dT/dθ| ≥ 0.01.
    time_abs: f64,
    time_rel: f64,
    /// Point derivatives: the largest absolute error.
    point_abs: f64,
    compared: usize,
    skipped: usize,
    /// Rays compared, by status.
    rays: [usize; 3],
    /// Untouched vertices whose difference was checked to be zero.
    untouched: usize,
}

/// The analytic derivative of `T` with respect to `param`.
fn analytic(g: &Gradient, param: Parameter) -> f64 {
    let pick = |v: Vec2, a: Axis| if a == Axis::X { v.x } else { v.y };
    match param {
        Parameter::Source(a) => pick(g.source, a),
        Parameter::Receiver(a) => pick(g.receiver, a),
        Parameter::Slowness { medium } => g.slowness[medium],
        Parameter::Vertex {
            interface,
            vertex,
            axis,
        } => pick(g.vertex(interface, vertex), axis),
    }
}

const STEP: f64 = 1e-5;

/// Compares every derivative of one ray with central differences of re-solved rays.
fn check_ray(doc: &Value, receiver: usize, path: usize, e: &mut Errors) {
    let mut d = doc.clone();
    d["receivers"][0] = d["receivers"][receiver].clone();
    let scene = Scene::from_json(&d.to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let mut ws = Workspace::new();
    let base = tracer.solve(scene.sources()[0], scene.receivers()[0], path, &mut ws);
    if !base.status.has_time() {
        return;
    }
    let g = tracer.gradient(path, &ws).unwrap();
    let sens = tracer.point_sensitivities(path, &ws).ok();
    let slot = match base.status {
        Status::Converged => 0,
        Status::Vertex => 1,
        _ => 2,
    };
    e.rays[slot] += 1;
    let mut params = vec![
        Parameter::Source(Axis::X),
        Parameter::Source(Axis::Y),
        Parameter::Receiver(Axis::X),
        Parameter::Receiver(Axis::Y),
    ];
    params.extend((0..scene.media().len()).map(|medium| Parameter::Slowness { medium }));
    // Every vertex of every interface the path uses: those not in the gradient must not move
    // the time.
    let steps = &scene.paths()[path].steps;
    let mut used: Vec<usize> = steps.iter().map(|s| s.interface).collect();
    used.sort_unstable();
    used.dedup();
    for &interface in &used {
        for vertex in 0..scene.interfaces()[interface].polyline.vertices().len() {
            for axis in [Axis::X, Axis::Y] {
                params.push(Parameter::Vertex {
                    interface,
                    vertex,
                    axis,
                });
            }
        }
    }
    for param in params {
        let plus = solve_doc(&perturbed(&d, &scene, param, STEP), 0, path);
        let minus = solve_doc(&perturbed(&d, &scene, param, -STEP), 0, path);
        let (Some(plus), Some(minus)) = (plus, minus) else {
            e.skipped += 1;
            continue;
        };
        // The same path on both sides (status, and no jump to another stationary path).
        let jump = |s: &Solved| {
            s.points
                .iter()
                .zip(ws.points())
                .any(|(a, b)| (*a - *b).length() > 1e-3)
        };
        if plus.status != base.status || minus.status != base.status || jump(&plus) || jump(&minus)
        {
            e.skipped += 1;
            continue;
        }
        let fd = (plus.time - minus.time) / (2.0 * STEP);
        let an = analytic(&g, param);
        let err = (fd - an).abs();
        assert!(
            err <= 2e-7 * (1.0 + an.abs()),
            "dT/d{param:?}: analytic {an}, central difference {fd} ({err:e}), ray {:?} path {path} \
             receiver {receiver} in {d}",
            base.status
        );
        e.time_abs = e.time_abs.max(err);
        if an.abs() >= 0.01 {
            e.time_rel = e.time_rel.max(err / an.abs());
        }
        if let Parameter::Vertex {
            interface, vertex, ..
        } = param
            && !g
                .vertices
                .iter()
                .any(|v| v.interface == interface && v.vertex == vertex)
        {
            e.untouched += 1;
        }
        e.compared += 1;
        if let Some(sens) = &sens {
            // Untouched vertices are not parameters of the points: they do not move them.
            let row = sens.find(param);
            for (i, (a, b)) in plus.points.iter().zip(&minus.points).enumerate() {
                let fd = (*a - *b) * (0.5 / STEP);
                let an = row.map_or(Vec2::default(), |r| sens.d_point(r, i));
                let err = (fd - an).length();
                assert!(
                    err <= 1e-5 * (1.0 + an.length()),
                    "d(point {i})/d{param:?}: analytic {an:?}, central difference {fd:?}, ray \
                     {:?} path {path} receiver {receiver} in {d}",
                    base.status
                );
                e.point_abs = e.point_abs.max(err);
            }
        }
    }
}

fn random_docs() -> Vec<Value> {
    let mut rng = Rng(env_or("DERIV_SEED", 21));
    let n = env_or("DERIV_SCENES", 8);
    let mut docs = Vec::new();
    for _ in 0..n {
        docs.push(layered(&mut rng));
        docs.push(lens(&mut rng));
        docs.push(roof(&mut rng));
    }
    docs
}

#[test]
fn derivatives_match_central_differences_of_re_solved_rays() {
    let mut e = Errors::default();
    for doc in random_docs() {
        let receivers = doc["receivers"].as_array().unwrap().len();
        let paths = doc["paths"].as_array().unwrap().len();
        for r in 0..receivers {
            for p in 0..paths {
                check_ray(&doc, r, p, &mut e);
            }
        }
    }
    println!("central differences (step {STEP:e}): {e:?}");
    // Enough of each kind compared for the test to mean something.
    assert!(e.rays[0] >= 40, "{e:?}");
    assert!(e.rays[1] >= 8, "{e:?}");
    assert!(e.compared >= 1000, "{e:?}");
    assert!(e.untouched >= 50, "{e:?}");
}

/// The seed's case: source (0, 1), air (index 1) over water (index 1.333), receiver (1, −1).
#[test]
fn seed_case_receiver_gradient_is_slowness_times_last_leg_direction() {
    let scene = Scene::from_json(
        r#"{
        "media": { "air": { "index": 1.0 }, "water": { "index": 1.333 } },
        "interfaces": { "surface": { "points": [[-1, 0], [2, 0]] } },
        "sources": [[0, 1]], "receivers": [[1, -1]],
        "paths": [{ "steps": [{ "refract": "surface" }], "media": ["air", "water"] }]
    }"#,
    )
    .unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let mut ws = Workspace::new();
    let rec = tracer.solve(scene.sources()[0], scene.receivers()[0], 0, &mut ws);
    assert_eq!(rec.status, Status::Converged);
    let g = tracer.gradient(0, &ws).unwrap();
    let p = ws.points().to_vec();
    let unit = |a: Point, b: Point| (b - a) * (1.0 / (b - a).length());
    let (first, last) = (unit(p[0], p[1]), unit(p[1], p[2]));
    let want_receiver = last * 1.333;
    let want_source = first * -1.0;
    assert!((g.receiver - want_receiver).length() < 1e-12, "{g:?}");
    assert!((g.source - want_source).length() < 1e-12, "{g:?}");
    // Snell's law: the horizontal components agree (the ray parameter).
    assert!((g.receiver.x + g.source.x).abs() < 1e-12);
    // dT/dw per medium: the length in each.
    assert!((g.slowness_of(&scene, "air").unwrap() - (p[1] - p[0]).length()).abs() < 1e-15);
    assert!((g.slowness_of(&scene, "water").unwrap() - (p[2] - p[1]).length()).abs() < 1e-15);
    // The surface's two vertices share the normal force w₁u₁ − w₂u₂ by the lever rule, and
    // lifting the whole surface changes the time by the sum.
    let normal = first.y - 1.333 * last.y;
    let lambda = (p[1].x + 1.0) / 3.0;
    assert!((g.vertex(0, 0).y - (1.0 - lambda) * normal).abs() < 1e-12);
    assert!((g.vertex(0, 1).y - lambda * normal).abs() < 1e-12);
    assert!(g.vertex(0, 0).x.abs() < 1e-12 && g.vertex(0, 1).x.abs() < 1e-12);
    // The point moves along the surface only, unless the surface moves.
    let sens = tracer.point_sensitivities(0, &ws).unwrap();
    for (row, param) in sens.parameters().iter().enumerate() {
        if !matches!(param, Parameter::Vertex { .. }) {
            assert_eq!(sens.d_point(row, 1).y, 0.0, "{param:?}");
        }
    }
}

/// The gradient's vertices: both ends of a segment a point lies on, one vertex for a point
/// held on it, each once; a reflection and a refraction on one interface add up.
#[test]
fn vertices_are_listed_once_in_order() {
    let scene = Scene::from_json(
        r#"{
        "media": { "a": { "speed": 1.0 }, "b": { "speed": 0.5 } },
        "interfaces": { "z": { "points": [[-4, 0], [4, 0]] },
                        "roof": { "points": [[-1, -3], [0, -2.5], [1, -3]] } },
        "sources": [[-0.5, 1]], "receivers": [[0.7, 1], [-6, -2]],
        "paths": [
            { "steps": [{ "refract": "z" }, { "reflect": "roof" }, { "refract": "z" }],
              "media": ["a", "b", "b", "a"] }
        ]
    }"#,
    )
    .unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let mut ws = Workspace::new();
    let rec = tracer.solve(scene.sources()[0], scene.receivers()[0], 0, &mut ws);
    assert!(rec.status.has_time(), "{rec:?}");
    let g = tracer.gradient(0, &ws).unwrap();
    let keys: Vec<(usize, usize)> = g.vertices.iter().map(|v| (v.interface, v.vertex)).collect();
    let mut sorted = keys.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(keys, sorted, "ordered, each once");
    let z = scene
        .interfaces()
        .iter()
        .position(|i| i.name == "z")
        .unwrap();
    assert!(keys.contains(&(z, 0)) && keys.contains(&(z, 1)));
}

/// Invalid `derivatives` values are refused naming the key; `true` is kept.
#[test]
fn the_scene_key_is_validated() {
    let doc = |v: &str| {
        format!(
            r#"{{ "media": {{ "a": {{ "speed": 1 }} }}, "sources": [[0, 0]], "receivers": [[1, 0]],
                "paths": [{{ "steps": [], "media": ["a"] }}], "solver": {{ "derivatives": {v} }} }}"#
        )
    };
    let e = Scene::from_json(&doc(r#""yes""#)).unwrap_err().to_string();
    assert!(e.contains("solver.derivatives"), "{e}");
    assert!(Scene::from_json(&doc("true")).unwrap().solver().derivatives);
    assert!(
        !Scene::from_json(&doc("false"))
            .unwrap()
            .solver()
            .derivatives
    );
}

/// Errors, not panics, for rays without a time and for wrong inputs.
#[test]
fn bad_inputs_are_errors() {
    let scene = Scene::from_json(
        r#"{ "media": { "a": { "speed": 1 } }, "interfaces": { "m": { "points": [[-1, 0], [1, 0]] } },
             "sources": [[0, 1]], "receivers": [[5, 1]],
             "paths": [{ "steps": [{ "reflect": "m" }], "media": ["a", "a"] }] }"#,
    )
    .unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let mut ws = Workspace::new();
    let rec = tracer.solve(scene.sources()[0], scene.receivers()[0], 0, &mut ws);
    assert_eq!(rec.status, Status::NoPath);
    assert_eq!(
        tracer.gradient(0, &ws).unwrap_err(),
        eigenray::derivatives::DerivativeError::NoTime
    );
    assert!(matches!(
        tracer.gradient(3, &ws).unwrap_err(),
        eigenray::derivatives::DerivativeError::UnknownPath { path: 3 }
    ));
    let off = [
        Point::new(0.0, 1.0),
        Point::new(0.0, 0.5),
        Point::new(1.0, 1.0),
    ];
    let steps = &scene.paths()[0].steps;
    assert_eq!(
        Gradient::of_points(&scene, steps, &off, &[0, 0]).unwrap_err(),
        eigenray::derivatives::DerivativeError::OffInterface { step: 0 }
    );
    let on = [
        Point::new(0.0, 1.0),
        Point::new(0.5, 0.0),
        Point::new(1.0, 1.0),
    ];
    assert_eq!(
        Gradient::of_points(&scene, steps, &on, &[0]).unwrap_err(),
        eigenray::derivatives::DerivativeError::Media
    );
    assert_eq!(
        Gradient::of_points(&scene, steps, &on[..2], &[0, 0]).unwrap_err(),
        eigenray::derivatives::DerivativeError::PointCount {
            points: 2,
            expected: 3
        }
    );
}

/// A batch's gradients are those of its rays one by one; rays not asked for have none.
#[test]
fn batch_gradients_are_the_rays_gradients() {
    let scene = Scene::from_spec(&eigenray::demo::layer_stack(4, 50)).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let batch = tracer
        .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
        .unwrap();
    let mut gradients = BatchGradients::default();
    gradients.compute(&scene, &batch, &|ray| ray % 3 != 1);
    let mut reused = Gradient::default();
    let mut timed = 0;
    for ray in 0..batch.len() {
        let has = batch.record(ray).status.has_time() && ray % 3 != 1;
        assert_eq!(gradients.has(ray), has);
        if !has {
            assert!(gradients.source(ray).x.is_nan());
            continue;
        }
        timed += 1;
        let one = Gradient::of_ray(&scene, &batch.ray(ray)).unwrap();
        assert_eq!(gradients.gradient(ray).unwrap(), one);
        // The flat arrays hold the same rows.
        let arrays = gradients.arrays();
        assert_eq!(arrays.source[ray], one.source);
        assert_eq!(arrays.receiver[ray], one.receiver);
        let m = gradients.media();
        assert_eq!(
            &arrays.slowness[ray * m..(ray + 1) * m],
            gradients.slowness(ray)
        );
        let first = ray * gradients.slots();
        let own = &arrays.vertices[first..first + one.vertices.len()];
        assert_eq!(own, gradients.vertices(ray));
        // Into a reused gradient, from the points and media alone.
        let path = batch.triple(ray).path;
        let steps = &scene.paths()[path].steps;
        let media: Vec<usize> = batch.media(ray).unwrap().collect();
        reused
            .points_into(&scene, steps, batch.points(ray), &media)
            .unwrap();
        assert_eq!(reused, one);
    }
    assert!(timed > 20);
}

/// `Tracer::solve_with_gradient` gives `Tracer::solve` and then `Gradient::of_solved`, bit for
/// bit: on the flat kernel's plan (which skips locating its point) with rays the kernel hands
/// over (grazing ones, near the interface's ends), rays without a time, and the random scenes.
#[test]
fn one_call_gives_the_solve_and_its_gradient() {
    let mut rng = Rng(7);
    let mut docs = random_docs();
    docs.push(serde_json::to_value(eigenray::demo::air_water(4, 1)).unwrap());
    let (mut compared, mut none) = (0, 0);
    for doc in &docs {
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let (mut one, mut two) = (Workspace::new(), Workspace::new());
        let mut g = Gradient::default();
        for _ in 0..300 {
            let point = |rng: &mut Rng| Point::new(rng.uniform(-3.0, 4.0), rng.uniform(-3.0, 3.0));
            let (s, r) = (point(&mut rng), point(&mut rng));
            for path in 0..scene.paths().len() {
                let record = tracer
                    .solve_with_gradient(s, r, path, &mut one, &mut g)
                    .unwrap();
                let want = tracer.solve(s, r, path, &mut two);
                assert_eq!(format!("{record:?}"), format!("{want:?}"));
                assert_eq!(one.points(), two.points());
                if want.status.has_time() {
                    assert_eq!(g, Gradient::of_solved(&scene, path, &two).unwrap());
                    compared += 1;
                } else {
                    assert!(g.source.x.is_nan() && g.receiver.y.is_nan());
                    assert!(g.slowness.iter().all(|w| w.is_nan()) && g.vertices.is_empty());
                    none += 1;
                }
            }
        }
    }
    println!("{compared} gradients compared, {none} rays without a time");
    assert!(compared > 2000 && none > 1000, "{compared} {none}");
}

/// Once warm, the per-ray calls allocate nothing.
#[test]
fn warm_calls_allocate_nothing() {
    let scene = Scene::from_spec(&eigenray::demo::layer_stack(8, 20)).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let mut ws = Workspace::new();
    let mut g = Gradient::default();
    let mut sens = PointSensitivities::default();
    let (s, rs) = (scene.sources()[0], scene.receivers().to_vec());
    let sweep = |ws: &mut Workspace, g: &mut Gradient, sens: &mut PointSensitivities| {
        let mut done = 0;
        for &r in &rs {
            if tracer.solve(s, r, 0, ws).status.has_time() {
                g.solved_into(&scene, 0, ws).unwrap();
                sens.solved_into(&scene, 0, ws).unwrap();
                done += 1;
            }
        }
        done
    };
    assert!(sweep(&mut ws, &mut g, &mut sens) > 10);
    let info = allocation_counter::measure(|| {
        sweep(&mut ws, &mut g, &mut sens);
    });
    assert_eq!(info.count_total, 0);
}

/// `"derivatives": true` puts the contract's `"gradient"` on every ray with a time, in JSON
/// (one ray per triple and every stationary path), JSON Lines, CSV and `.npy`.
#[test]
fn outputs_carry_the_gradient() {
    use eigenray::{Format, write};
    let text = r#"{
        "media": { "air": { "index": 1.0 }, "water": { "index": 1.333 } },
        "interfaces": { "surface": { "points": [[-1, 0], [2, 0]] } },
        "sources": [[0, 1]], "receivers": [[1, -1], [1, 2]],
        "paths": [{ "steps": [{ "refract": "surface" }], "media": ["air", "water"] }],
        "solver": { "derivatives": true }
    }"#;
    let scene = Scene::from_json(text).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let batch = tracer
        .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
        .unwrap();
    let write = |format| {
        let mut out = Vec::new();
        write(&scene, &batch, format, &mut out).unwrap();
        out
    };
    let doc: Value = serde_json::from_slice(&write(eigenray::Format::Json)).unwrap();
    let ray = &doc["rays"][0];
    let want = Gradient::of_ray(&scene, &batch.ray(0)).unwrap();
    let g = &ray["gradient"];
    assert_eq!(g["receiver"], json!([want.receiver.x, want.receiver.y]));
    assert_eq!(g["source"], json!([want.source.x, want.source.y]));
    assert_eq!(g["slowness"]["air"], json!(want.slowness[0]));
    assert_eq!(g["slowness"]["water"], json!(want.slowness[1]));
    assert_eq!(g["vertices"][1]["interface"], "surface");
    assert_eq!(g["vertices"][1]["vertex"], 1);
    assert_eq!(
        g["vertices"][1]["d"],
        json!([want.vertices[1].d.x, want.vertices[1].d.y])
    );
    // No time, no gradient.
    assert_eq!(doc["rays"][1]["status"], "no_path");
    assert!(doc["rays"][1].get("gradient").is_none());
    let lines = String::from_utf8(write(Format::Jsonl)).unwrap();
    let first: Value = serde_json::from_str(lines.lines().next().unwrap()).unwrap();
    assert_eq!(first["gradient"], *g);
    let csv = String::from_utf8(write(Format::Csv)).unwrap();
    let mut rows = csv.lines();
    assert!(rows.next().unwrap().ends_with(
        ",reason,gradient_source,gradient_receiver,gradient_slowness,gradient_vertices"
    ));
    let row: Vec<&str> = rows.next().unwrap().split(',').collect();
    assert_eq!(row.len(), 15);
    assert_eq!(row[14].split(';').count(), 2);
    assert!(rows.next().unwrap().ends_with(",,,,"));
    let npy = write(Format::Npy);
    let header = String::from_utf8_lossy(&npy[..npy.len().min(1024)]);
    assert!(
        header.contains("('gradient_vertices', '<f8', (2, 2))"),
        "{header}"
    );
    // Every stationary path carries its own.
    let all = Scene::from_json(&text.replace(
        r#""derivatives": true"#,
        r#""derivatives": true, "stationary": "all""#,
    ))
    .unwrap();
    let rays = Tracer::new(&all)
        .unwrap()
        .trace_stationary(&eigenray::options::Run::new())
        .unwrap();
    let mut out = Vec::new();
    eigenray::write(&all, &rays, Format::Json, &mut out).unwrap();
    let doc: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(doc["rays"][0]["gradient"], *g);
}

/// The arrivals of a search carry the same gradient in JSON, JSON Lines, CSV and `.npy`, and
/// it is the gradient of the arrival's points (`Gradient::of_points`).
#[test]
fn search_arrivals_carry_the_gradient_in_every_format() {
    use eigenray::{Format, write};
    let path = format!(
        "{}/fixtures/pyroomacoustics/hexagon.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut doc: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    doc["search"] = json!({ "max_steps": 2, "refract": false });
    doc["solver"] = json!({ "derivatives": true });
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let arrivals = Tracer::new(&scene)
        .unwrap()
        .search(&eigenray::options::Run::new())
        .unwrap()
        .arrivals;
    assert!(arrivals.len() > 20, "{}", arrivals.len());
    let write = |format| {
        let mut out = Vec::new();
        write(&scene, &arrivals, format, &mut out).unwrap();
        out
    };
    let json_doc: Value = serde_json::from_slice(&write(Format::Json)).unwrap();
    let listed = json_doc["arrivals"].as_array().unwrap();
    let lines = String::from_utf8(write(Format::Jsonl)).unwrap();
    let csv = String::from_utf8(write(Format::Csv)).unwrap();
    let mut rows = csv.lines();
    assert!(rows.next().unwrap().ends_with(
        ",complete,gradient_source,gradient_receiver,gradient_slowness,gradient_vertices"
    ));
    let npy = write(Format::Npy);
    let len = u16::from_le_bytes([npy[8], npy[9]]) as usize;
    let header = String::from_utf8_lossy(&npy[10..10 + len]).to_string();
    let (k, media) = (2, scene.media().len());
    assert!(
        header.contains(&format!(
            "('gradient_slowness', '<f8', ({media},)), ('gradient_vertex_interface', '<u4', (4,))"
        )),
        "{header}"
    );
    // The record: the arrival's own fields, then 2 + 2 + M floats, 2 × 2K indices, 2K pairs.
    let own = 12 + k + 4 * k + 3 + 4 + 16 + 16 * (k + 2) + 4 * (k + 1);
    let size = own + 8 * (4 + media) + 8 * 2 * k + 16 * 2 * k;
    let data = &npy[10 + len..];
    assert_eq!(data.len(), arrivals.len() * size);
    let f = |r: &[u8], at: usize| f64::from_le_bytes(r[at..at + 8].try_into().unwrap());
    let u = |r: &[u8], at: usize| u32::from_le_bytes(r[at..at + 4].try_into().unwrap());
    for (i, ((a, entry), line)) in arrivals.iter().zip(listed).zip(lines.lines()).enumerate() {
        let want =
            Gradient::of_points(&scene, &a.steps, &a.arrival.points, &a.arrival.media).unwrap();
        let g = &entry["gradient"];
        assert_eq!(g["source"], json!([want.source.x, want.source.y]));
        assert_eq!(g["receiver"], json!([want.receiver.x, want.receiver.y]));
        let marked: Value = serde_json::from_str(line).unwrap();
        assert_eq!(marked["gradient"], *g);
        // CSV: the last four columns.
        let row: Vec<&str> = rows.next().unwrap().rsplitn(5, ',').collect();
        let pair =
            |text: &str| -> Vec<f64> { text.split(' ').map(|x| x.parse().unwrap()).collect() };
        assert_eq!(pair(row[3]), [want.source.x, want.source.y]);
        assert_eq!(pair(row[2]), [want.receiver.x, want.receiver.y]);
        let slowness: Vec<f64> = row[1].split(';').map(|x| x.parse().unwrap()).collect();
        assert_eq!(slowness, want.slowness);
        let listed_vertices = row[0].split(';').filter(|v| !v.is_empty()).count();
        assert_eq!(listed_vertices, want.vertices.len());
        // `.npy`.
        let r = &data[i * size..(i + 1) * size];
        assert_eq!([f(r, own), f(r, own + 8)], [want.source.x, want.source.y]);
        assert_eq!(f(r, own + 16 + 8), want.receiver.y);
        for (m, w) in want.slowness.iter().enumerate() {
            assert_eq!(f(r, own + 32 + 8 * m), *w);
        }
        let at = own + 8 * (4 + media);
        for slot in 0..2 * k {
            let (interface, vertex) = (u(r, at + 4 * slot), u(r, at + 8 * k + 4 * slot));
            let d = (
                f(r, at + 16 * k + 16 * slot),
                f(r, at + 16 * k + 16 * slot + 8),
            );
            match want.vertices.get(slot) {
                Some(v) => {
                    assert_eq!(
                        (interface as usize, vertex as usize),
                        (v.interface, v.vertex)
                    );
                    assert_eq!(d, (v.d.x, v.d.y));
                }
                None => assert!(interface == u32::MAX && vertex == u32::MAX && d.0.is_nan()),
            }
        }
    }
}

/// A forward-mode dual number `re + eps ε`, `ε² = 0`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Dual {
    re: f64,
    eps: f64,
}

impl Dual {
    fn constant(re: f64) -> Dual {
        Dual { re, eps: 0.0 }
    }
    fn seeded(re: f64, seed: bool) -> Dual {
        Dual {
            re,
            eps: if seed { 1.0 } else { 0.0 },
        }
    }
    fn sqrt(self) -> Dual {
        let r = self.re.sqrt();
        Dual {
            re: r,
            eps: self.eps / (2.0 * r),
        }
    }
}

impl std::ops::Add for Dual {
    type Output = Dual;
    fn add(self, o: Dual) -> Dual {
        Dual {
            re: self.re + o.re,
            eps: self.eps + o.eps,
        }
    }
}
impl std::ops::Sub for Dual {
    type Output = Dual;
    fn sub(self, o: Dual) -> Dual {
        Dual {
            re: self.re - o.re,
            eps: self.eps - o.eps,
        }
    }
}
impl std::ops::Mul for Dual {
    type Output = Dual;
    fn mul(self, o: Dual) -> Dual {
        Dual {
            re: self.re * o.re,
            eps: self.re * o.eps + self.eps * o.re,
        }
    }
}
impl std::ops::Div for Dual {
    type Output = Dual;
    fn div(self, o: Dual) -> Dual {
        Dual {
            re: self.re / o.re,
            eps: (self.eps * o.re - self.re * o.eps) / (o.re * o.re),
        }
    }
}

/// A point or vector of dual numbers.
#[derive(Clone, Copy, Debug, Default)]
struct D2 {
    x: Dual,
    y: Dual,
}

impl D2 {
    fn of(p: Point, seed: Option<Axis>) -> D2 {
        D2 {
            x: Dual::seeded(p.x, seed == Some(Axis::X)),
            y: Dual::seeded(p.y, seed == Some(Axis::Y)),
        }
    }
    fn sub(self, o: D2) -> D2 {
        D2 {
            x: self.x - o.x,
            y: self.y - o.y,
        }
    }
    fn lerp(self, o: D2, t: Dual) -> D2 {
        D2 {
            x: self.x + (o.x - self.x) * t,
            y: self.y + (o.y - self.y) * t,
        }
    }
    fn dot(self, o: D2) -> Dual {
        self.x * o.x + self.y * o.y
    }
}

/// Where an interaction point lies, found by the test itself: its segment's vertex indices
/// and its fraction, or the vertex it is held on.
#[derive(Clone, Copy, Debug)]
enum Place {
    On { a: usize, b: usize, lambda: f64 },
    Held { vertex: usize },
}

fn place_of(line: &eigenray::polyline::Polyline, p: Point) -> Place {
    let v = line.vertices();
    let mut best = (f64::INFINITY, Place::Held { vertex: 0 });
    for j in 0..line.num_segments() {
        let eigenray::geom::Segment { start: a, end: b } = line.segment(j);
        let e = b - a;
        let t = ((p - a).dot(e) / e.dot(e)).clamp(0.0, 1.0);
        let q = a + e * t;
        let dist = (p - q).length();
        if dist < best.0 {
            let bj = (j + 1) % v.len();
            let place = if (p - a).length() <= 1e-9 * e.length() {
                Place::Held { vertex: j }
            } else if (p - b).length() <= 1e-9 * e.length() {
                Place::Held { vertex: bj }
            } else {
                Place::On {
                    a: j,
                    b: bj,
                    lambda: t,
                }
            };
            best = (dist, place);
        }
    }
    best.1
}

/// The time and points of one ray differentiated with respect to `param` by carrying dual
/// numbers through Newton's iteration on the fractions of its free points (on the segments the
/// ray was solved on, from its solution), to a fixed point: `(dT/dθ, d(points)/dθ)`.
fn dual_solve(
    scene: &Scene,
    path: usize,
    points: &[Point],
    media: &[usize],
    param: Parameter,
) -> (f64, Vec<Vec2>) {
    let steps = &scene.paths()[path].steps;
    let k = steps.len();
    let seed_point =
        |which: fn(Axis) -> Parameter| [Axis::X, Axis::Y].into_iter().find(|&a| param == which(a));
    let source = D2::of(points[0], seed_point(Parameter::Source));
    let receiver = D2::of(points[k + 1], seed_point(Parameter::Receiver));
    let w: Vec<Dual> = media
        .iter()
        .map(|&m| {
            Dual::seeded(
                scene.media()[m].slowness,
                param == Parameter::Slowness { medium: m },
            )
        })
        .collect();
    let vertex = |interface: usize, v: usize| {
        let p = scene.interfaces()[interface].polyline.vertices()[v];
        let seed = [Axis::X, Axis::Y].into_iter().find(|&axis| {
            param
                == Parameter::Vertex {
                    interface,
                    vertex: v,
                    axis,
                }
        });
        D2::of(p, seed)
    };
    let places: Vec<Place> = (0..k)
        .map(|i| {
            place_of(
                &scene.interfaces()[steps[i].interface].polyline,
                points[i + 1],
            )
        })
        .collect();
    let mut lambda: Vec<Dual> = places
        .iter()
        .map(|p| match *p {
            Place::On { lambda, .. } => Dual::constant(lambda),
            Place::Held { .. } => Dual::constant(0.0),
        })
        .collect();
    // The path's points, time and λ-residuals at fractions `lambda`.
    let evaluate = |lambda: &[Dual]| {
        let mut xs = vec![source];
        let mut ends = Vec::new();
        for i in 0..k {
            let interface = steps[i].interface;
            match places[i] {
                Place::On { a, b, .. } => {
                    let (a, b) = (vertex(interface, a), vertex(interface, b));
                    xs.push(a.lerp(b, lambda[i]));
                    ends.push(Some(b.sub(a)));
                }
                Place::Held { vertex: v } => {
                    xs.push(vertex(interface, v));
                    ends.push(None);
                }
            }
        }
        xs.push(receiver);
        let mut time = Dual::constant(0.0);
        let mut u = Vec::new();
        for j in 0..=k {
            let d = xs[j + 1].sub(xs[j]);
            let l = d.dot(d).sqrt();
            time = time + w[j] * l;
            u.push(D2 {
                x: d.x / l,
                y: d.y / l,
            });
        }
        let r: Vec<Dual> = (0..k)
            .map(|i| match ends[i] {
                Some(e) => {
                    let g = D2 {
                        x: w[i] * u[i].x - w[i + 1] * u[i + 1].x,
                        y: w[i] * u[i].y - w[i + 1] * u[i + 1].y,
                    };
                    g.dot(e)
                }
                None => Dual::constant(0.0),
            })
            .collect();
        (xs, time, r)
    };
    let free: Vec<usize> = (0..k)
        .filter(|&i| matches!(places[i], Place::On { .. }))
        .collect();
    for _ in 0..6 {
        let (_, _, r) = evaluate(&lambda);
        // The Newton matrix from central differences of the real residual (only the fixed
        // point matters: its dual part is exact for any matrix near the Jacobian).
        let n = free.len();
        let mut m = vec![vec![0.0; n]; n];
        for (c, &j) in free.iter().enumerate() {
            let h = 1e-7;
            let mut plus = lambda.clone();
            let mut minus = lambda.clone();
            plus[j].re += h;
            minus[j].re -= h;
            let (_, _, rp) = evaluate(&plus);
            let (_, _, rm) = evaluate(&minus);
            for (row, &i) in free.iter().enumerate() {
                m[row][c] = (rp[i].re - rm[i].re) / (2.0 * h);
            }
        }
        // Gaussian elimination with partial pivoting, right-hand sides re and eps.
        let mut rhs: Vec<[f64; 2]> = free.iter().map(|&i| [r[i].re, r[i].eps]).collect();
        for col in 0..n {
            let p = (col..n)
                .max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))
                .unwrap();
            m.swap(col, p);
            rhs.swap(col, p);
            for row in col + 1..n {
                let f = m[row][col] / m[col][col];
                let pivot_row = m[col].clone();
                for (x, p) in m[row].iter_mut().zip(&pivot_row).skip(col) {
                    *x -= f * p;
                }
                rhs[row] = [rhs[row][0] - f * rhs[col][0], rhs[row][1] - f * rhs[col][1]];
            }
        }
        let mut step = vec![[0.0; 2]; n];
        for row in (0..n).rev() {
            let mut acc = rhs[row];
            for c in row + 1..n {
                acc = [
                    acc[0] - m[row][c] * step[c][0],
                    acc[1] - m[row][c] * step[c][1],
                ];
            }
            step[row] = [acc[0] / m[row][row], acc[1] / m[row][row]];
        }
        for (row, &i) in free.iter().enumerate() {
            lambda[i] = lambda[i]
                - Dual {
                    re: step[row][0],
                    eps: step[row][1],
                };
        }
    }
    let (xs, time, _) = evaluate(&lambda);
    (
        time.eps,
        xs.iter().map(|p| Vec2::new(p.x.eps, p.y.eps)).collect(),
    )
}

/// Every derivative of every timed ray of the random scenes against dual numbers carried
/// through the whole Newton solve (from the solution, on its segments, with the vertices held).
#[test]
fn derivatives_match_dual_numbers_through_the_solve() {
    let (mut time_abs, mut time_rel, mut point_abs, mut compared) = (0.0f64, 0.0f64, 0.0f64, 0);
    for doc in random_docs() {
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let mut ws = Workspace::new();
        for r in 0..scene.receivers().len() {
            for p in 0..scene.paths().len() {
                let rec = tracer.solve(scene.sources()[0], scene.receivers()[r], p, &mut ws);
                if !rec.status.has_time() {
                    continue;
                }
                let g = tracer.gradient(p, &ws).unwrap();
                let sens = tracer.point_sensitivities(p, &ws).unwrap();
                for (row, &param) in sens.parameters().iter().enumerate() {
                    let (dt, dx) = dual_solve(&scene, p, ws.points(), ws.media(), param);
                    let an = analytic(&g, param);
                    let err = (dt - an).abs();
                    assert!(
                        err <= 1e-9 * (1.0 + an.abs()),
                        "dT/d{param:?}: analytic {an}, dual {dt}, path {p} receiver {r} in {doc}"
                    );
                    time_abs = time_abs.max(err);
                    if an.abs() >= 0.01 {
                        time_rel = time_rel.max(err / an.abs());
                    }
                    for (i, d) in dx.iter().enumerate() {
                        let err = (*d - sens.d_point(row, i)).length();
                        assert!(
                            err <= 1e-8 * (1.0 + d.length()),
                            "d(point {i})/d{param:?}: analytic {:?}, dual {d:?}, path {p} \
                             receiver {r} in {doc}",
                            sens.d_point(row, i)
                        );
                        point_abs = point_abs.max(err);
                    }
                    compared += 1;
                }
            }
        }
    }
    println!(
        "dual numbers: {compared} parameters, time abs {time_abs:e} rel {time_rel:e}, points abs \
         {point_abs:e}"
    );
    assert!(compared >= 1000);
}

/// Every stationary path of a valley reflector (`"stationary": "all"`): two specular points on
/// the slopes and the bottom, a maximum-type kink held on its vertex. Each arrival's gradient
/// (from its points and media) against central differences of the same arrival re-solved.
#[test]
fn every_stationary_path_has_its_derivatives() {
    let doc = json!({
        "media": { "air": { "speed": 1.0 }, "slow": { "speed": 0.5 } },
        "interfaces": { "valley": { "points": [[-3.0, 0.0], [0.0, -2.0], [3.0, 0.0]] } },
        "sources": [[-0.5, 2.0]], "receivers": [[0.7, 1.8]],
        "paths": [
            { "steps": [{ "reflect": "valley" }], "media": ["air", "air"] },
            { "steps": [{ "reflect": "valley" }], "media": ["air", "slow"] }
        ],
        "solver": { "stationary": "all", "tolerance": 1e-15 }
    });
    let arrivals_of = |d: &Value, path: usize| {
        let scene = Scene::from_json(&d.to_string()).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let mut out = Vec::new();
        tracer
            .stationary_paths(
                scene.sources()[0],
                scene.receivers()[0],
                path,
                &eigenray::options::Run::new(),
                &mut out,
            )
            .unwrap();
        out
    };
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let mut vertex_arrivals = 0;
    for path in 0..2 {
        let arrivals = arrivals_of(&doc, path);
        assert_eq!(arrivals.len(), 3, "{arrivals:?}");
        let steps = &scene.paths()[path].steps;
        for (a, arrival) in arrivals.iter().enumerate() {
            let g = Gradient::of_points(&scene, steps, &arrival.points, &arrival.media).unwrap();
            if arrival.status == Status::Vertex {
                vertex_arrivals += 1;
                // Held on the bottom vertex: that vertex alone.
                assert_eq!(g.vertices.len(), 1);
                assert_eq!(g.vertices[0].vertex, 1);
            }
            let mut params = vec![
                Parameter::Source(Axis::X),
                Parameter::Source(Axis::Y),
                Parameter::Receiver(Axis::X),
                Parameter::Receiver(Axis::Y),
                Parameter::Slowness { medium: 0 },
                Parameter::Slowness { medium: 1 },
            ];
            for vertex in 0..3 {
                for axis in [Axis::X, Axis::Y] {
                    params.push(Parameter::Vertex {
                        interface: 0,
                        vertex,
                        axis,
                    });
                }
            }
            for param in params {
                let time = |h: f64| {
                    let moved = arrivals_of(&perturbed(&doc, &scene, param, h), path);
                    // The same arrival: the same status, nearest in time.
                    moved
                        .iter()
                        .filter(|m| m.status == arrival.status)
                        .map(|m| m.time)
                        .min_by(|x, y| {
                            (x - arrival.time)
                                .abs()
                                .total_cmp(&(y - arrival.time).abs())
                        })
                        .unwrap()
                };
                let fd = (time(STEP) - time(-STEP)) / (2.0 * STEP);
                let an = analytic(&g, param);
                assert!(
                    (fd - an).abs() <= 1e-7 * (1.0 + an.abs()),
                    "arrival {a} ({:?}) of path {path}: dT/d{param:?} {an} vs {fd}",
                    arrival.status
                );
            }
        }
    }
    assert_eq!(vertex_arrivals, 2);
}
