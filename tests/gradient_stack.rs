//! Rays through flat parallel layers whose media have speed gradients across the layers (the
//! graded start `trace::start::graded`, the graded stack kernel and the classifier's proof
//! that arcs are clear): against the same solve without any shortcut (bit for bit), against
//! the general solve from the paraxial start (times to 1e-12, points to 1e-9, amplitudes and
//! derivatives to 1e-12), and against an independent closed form of the ray parameter.

use eigenray::trace::Kernels;
use eigenray::{Gradient, InitialGuess, Point, Scene, Status, Tracer, Workspace};
use serde_json::{Value, json};

/// A small deterministic generator (SplitMix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A stack of `n` flat parallel interfaces (horizontal, or turned by a random angle), each
/// medium a speed and a gradient along the interfaces' normal of a size drawn from zero,
/// 1e-9, 1e-6 and up to 0.05 (mixed within a stack), one path refracting through all of them
/// with its media given; a source above the stack and receivers below it, inside it and
/// beyond the interfaces' ends; with `screen`, a short segment across the second layer.
fn graded_stack(rng: &mut Rng, n: usize, turned: bool, screen: bool) -> Value {
    let angle = if turned {
        std::f64::consts::TAU * rng.next()
    } else {
        0.0
    };
    let (t, nrm) = ([angle.cos(), angle.sin()], [-angle.sin(), angle.cos()]);
    let at = |along: f64, across: f64| {
        json!([
            along * t[0] + across * nrm[0],
            along * t[1] + across * nrm[1]
        ])
    };
    let half = 6.0 + 6.0 * rng.next();
    let (mut media, mut interfaces) = (serde_json::Map::new(), serde_json::Map::new());
    let (mut steps, mut names) = (Vec::new(), Vec::new());
    let mut depth = 0.0;
    for j in 0..=n {
        let size = match (rng.next() * 5.0) as u32 {
            0 => 0.0,
            1 => 1e-9,
            2 => 1e-6,
            _ => 0.05 * rng.next(),
        };
        // Faster downward or upward, along the normal (−n points down the stack).
        let sign = if rng.next() < 0.7 { -1.0 } else { 1.0 };
        let g = [sign * size * nrm[0], sign * size * nrm[1]];
        let speed = 0.8 + 1.2 * rng.next();
        let name = format!("m{j}");
        let medium = if size == 0.0 && rng.next() < 0.5 {
            json!({ "speed": speed })
        } else {
            json!({ "speed": speed, "gradient": g })
        };
        media.insert(name.clone(), medium);
        names.push(json!(name));
        if j < n {
            depth += 0.3 + 1.7 * rng.next();
            let key = format!("L{j}");
            let (a, b) = (at(-half, -depth), at(half, -depth));
            let pts = if rng.next() < 0.3 { [b, a] } else { [a, b] };
            interfaces.insert(key.clone(), json!({ "points": pts }));
            steps.push(json!({ "refract": key }));
        }
    }
    if screen && n > 1 {
        let screen = json!({ "points": [at(1.0, -0.02), at(1.3, -0.28)] });
        interfaces.insert("screen".into(), screen);
    }
    let source = at(half * (rng.next() - 0.5), 0.2 + 1.5 * rng.next());
    let receivers: Vec<Value> = (0..30)
        .map(|i| {
            let along = half * (2.4 * rng.next() - 1.2);
            let across = match i % 10 {
                0 => -depth * rng.next(),
                _ => -depth - 0.1 - 2.0 * rng.next(),
            };
            at(along, across)
        })
        .collect();
    json!({
        "media": media, "interfaces": interfaces,
        "sources": [source], "receivers": receivers,
        "paths": [{ "steps": steps, "media": names }],
        "amplitudes": { "source": "point" },
        // Tight, for the solve from the paraxial start to meet the start's ray to 1e-12.
        "solver": { "tolerance": 1e-14 },
    })
}

/// The three tracers: the default (the graded stack kernel and the classifier's proof), the
/// same start without shortcut, and the general solve from the paraxial start.
fn tracers(scene: &Scene) -> [Tracer; 3] {
    let general = || {
        Tracer::new(scene)
            .unwrap()
            .with_kernels(Kernels::GeneralOnly)
    };
    [
        Tracer::new(scene).unwrap(),
        general(),
        general().with_initial_guess(InitialGuess::Paraxial),
    ]
}

/// `|a − b| ≤ tol (|a| + scale)`.
fn close(a: f64, b: f64, tol: f64, scale: f64) -> bool {
    (a - b).abs() <= tol * (a.abs() + scale)
}

/// Compares every ray of `scene` three ways (see [`tracers`]); returns how many rays the
/// default tracer solved with its start the ray (no Newton step) and how many it timed.
fn compare(scene: &Scene) -> (usize, usize) {
    let [fast, exact, old] = tracers(scene);
    let rays = fast.trace_all();
    assert_eq!(rays, exact.trace_all(), "the shortcuts change nothing");
    let old_rays = old.trace_all();
    let (mut ws, mut wo) = (Workspace::new(), Workspace::new());
    let (mut gf, mut go) = (Gradient::default(), Gradient::default());
    let (mut started, mut timed) = (0, 0);
    for (r, o) in rays.iter().zip(&old_rays) {
        assert_eq!(r.status, o.status, "{r:?}\n{o:?}");
        if !r.status.has_time() {
            continue;
        }
        timed += 1;
        started += usize::from(r.iterations == 0);
        assert!(close(r.time, o.time, 1e-12, 0.0), "{} {}", r.time, o.time);
        for (p, q) in r.points.iter().zip(&o.points) {
            assert!((*p - *q).length() <= 1e-9, "{p:?} {q:?}");
        }
        match (&r.amplitude, &o.amplitude) {
            (Some(a), Some(b)) if a.reason.is_some() => assert_eq!(a.reason, b.reason),
            (Some(a), Some(b)) => {
                assert!(close(a.spreading, b.spreading, 1e-12, 0.0), "{a:?} {b:?}");
                let d = (a.value - b.value).norm();
                assert!(d <= 1e-12 * a.value.norm(), "{a:?} {b:?}");
                assert_eq!(a.reason, b.reason);
            }
            (a, b) => assert_eq!(a.is_some(), b.is_some()),
        }
        // The derivatives of the two solutions.
        let (src, rec) = (scene.sources()[r.source], scene.receivers()[r.receiver]);
        let a = fast.solve_with_gradient(src, rec, r.path, &mut ws, &mut gf);
        let b = old.solve_with_gradient(src, rec, r.path, &mut wo, &mut go);
        assert_eq!(a.is_ok(), b.is_ok());
        if a.is_ok() {
            let scale = gf.source.length() + gf.receiver.length();
            let near = |x: f64, y: f64| (x - y).abs() <= 1e-12 * (x.abs() + scale);
            assert!(near(gf.source.x, go.source.x) && near(gf.source.y, go.source.y));
            assert!(near(gf.receiver.x, go.receiver.x) && near(gf.receiver.y, go.receiver.y));
            let media = gf.slowness.iter().zip(&go.slowness);
            let spread = gf.slowness.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            for (x, y) in media {
                assert!((x - y).abs() <= 1e-12 * spread, "{x} {y}");
            }
            for (x, y) in gf.speed_gradient.iter().zip(&go.speed_gradient) {
                let s = x.length().max(y.length()).max(spread);
                assert!((*x - *y).length() <= 1e-12 * s, "{x:?} {y:?}");
            }
        }
    }
    (started, timed)
}

#[test]
fn graded_stacks_match_the_general_solve() {
    let mut rng = Rng(40);
    let (mut started, mut timed, mut obstructed) = (0, 0, 0);
    for i in 0..40 {
        let doc = graded_stack(&mut rng, 2 + i % 7, i % 3 == 1, i % 5 == 2);
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let (s, t) = compare(&scene);
        (started, timed) = (started + s, timed + t);
        obstructed += Tracer::new(&scene)
            .unwrap()
            .trace_all()
            .iter()
            .filter(|r| r.status == Status::Obstructed)
            .count();
    }
    assert!(
        started > timed / 2,
        "{started} of {timed} rays solved by the start"
    );
    eprintln!("{started} of {timed} timed rays from the start, {obstructed} obstructed");
    assert!(obstructed > 0, "some rays meet the screen");
}

/// The benchmark's layers with gradients (`examples/gradient_cost.rs`): every ray from its
/// start, the same three ways.
#[test]
fn layers10_with_gradients_match_the_general_solve() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/bench/layers10.json");
    let mut doc: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    for gradient in [[0.0, -0.02], [0.003, -0.15], [0.0, 1e-9]] {
        for m in doc["media"].as_object_mut().unwrap().values_mut() {
            m["gradient"] = json!(gradient);
        }
        doc["receivers"] = json!(doc["receivers"].as_array().unwrap()[..200]);
        doc["amplitudes"] = json!({ "source": "point" });
        doc["solver"]["tolerance"] = json!(1e-14);
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let (started, timed) = compare(&scene);
        if gradient[0] == 0.0 {
            assert_eq!(started, timed, "{gradient:?}");
            assert_eq!(timed, 200);
        } else {
            // A gradient along the interfaces: not the graded start's case.
            assert_eq!(started, 0, "{gradient:?}");
        }
    }
}

/// A layer with `c = c₀ + k d` below the surface (`d` the depth) over two uniform layers:
/// the ray parameter by bisection of the range written with the textbook forms (`X = (s₁ −
/// s₂) / (p k)` in the gradient layer, `h p c / s` in a uniform one) and the time `(atanh s₁
/// − atanh s₂) / k + Σ h / (c s)`, against the traced ray.
#[test]
fn a_graded_stack_matches_the_textbook_forms() {
    let (c0, k, h1) = (1500.0, 0.05, 300.0);
    let uniform = [(1800.0, 200.0), (1650.0, 100.0)];
    let c1 = c0 + k * h1;
    let depth = h1 + uniform[0].1 + uniform[1].1;
    for x in [50.0, 400.0, 1500.0, 3000.0] {
        let doc = json!({
            "media": {
                "water": { "speed": c0, "gradient": [0.0, -k] },
                "rock": { "speed": uniform[0].0 },
                "deep": { "speed": uniform[1].0 },
            },
            "interfaces": {
                "floor": { "points": [[-1e4, -h1], [1e4, -h1]] },
                "base": { "points": [[-1e4, -h1 - uniform[0].1], [1e4, -h1 - uniform[0].1]] },
            },
            "sources": [[0.0, 0.0]], "receivers": [[x, -depth]],
            "paths": [{ "steps": [{ "refract": "floor" }, { "refract": "base" }],
                        "media": ["water", "rock", "deep"] }],
        });
        let sine = |p: f64, c: f64| (1.0 - p * p * c * c).sqrt();
        let range = |p: f64| {
            let uniform: f64 = uniform.iter().map(|&(c, h)| h * p * c / sine(p, c)).sum();
            (sine(p, c0) - sine(p, c1)) / (p * k) + uniform
        };
        let (mut lo, mut hi) = (0.0, 1.0 / 1800.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if range(mid) > x {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let p = 0.5 * (lo + hi);
        let below: f64 = uniform.iter().map(|&(c, h)| h / (c * sine(p, c))).sum();
        let time = (sine(p, c0).atanh() - sine(p, c1).atanh()) / k + below;
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let mut ws = Workspace::new();
        let ray = tracer.solve(Point::new(0.0, 0.0), Point::new(x, -depth), 0, &mut ws);
        assert_eq!(ray.status, Status::Converged);
        assert_eq!(ray.iterations, 0, "the start is the ray");
        assert!(
            close(ray.time, time, 1e-11, 0.0),
            "{x}: {} {time}",
            ray.time
        );
        // The crossing of the floor: the gradient layer's range.
        let floor = ws.points()[1];
        let x1 = (sine(p, c0) - sine(p, c1)) / (p * k);
        assert!((floor.x - x1).abs() <= 1e-8, "{x}: {} {x1}", floor.x);
    }
}
