//! The argmin layout objectives: their gradients against central differences of their costs,
//! and L-BFGS reaching the layouts they describe.
#![cfg(feature = "argmin")]

use argmin::core::Executor;
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use eigenray::argmin_bridge::{ObservedArrival, Placement, ReflectorPlacement, SourceLocation};
use eigenray::{Point, Scene, SceneSpec, Tracer, Workspace};
use nalgebra::DVector;

const SEA: &str = r#"{
    "media": { "air": { "speed": 343.0 }, "water": { "speed": 1480.0 } },
    "interfaces": { "surface": { "points": [[-60, 0], [-30, 1.5], [-10, -1], [10, 1.2], [30, -0.8], [60, 0]] } },
    "sources": [[0, 10]],
    "receivers": [[-25, -12], [-12, -20], [0, -8], [8, -25], [20, -15], [32, -10]],
    "paths": [{ "steps": [{ "refract": "surface" }], "media": ["air", "water"] }]
}"#;

#[test]
fn source_location_gradient_and_solution() {
    let scene = Scene::from_json(SEA).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let truth = Point::new(7.0, 14.0);
    let mut ws = Workspace::new();
    let observed: Vec<ObservedArrival> = scene
        .receivers()
        .iter()
        .map(|&receiver| ObservedArrival {
            receiver,
            path: 0,
            time: tracer.solve(truth, receiver, 0, &mut ws).time,
        })
        .collect();
    let problem = SourceLocation::new(&tracer, observed);
    let at = Point::new(-3.0, 6.0);
    let m = problem.misfit(at).unwrap();
    let h = 1e-5;
    for (k, e) in [(0, Point::new(h, 0.0)), (1, Point::new(0.0, h))] {
        let plus = problem
            .misfit(Point::new(at.x + e.x, at.y + e.y))
            .unwrap()
            .cost;
        let minus = problem
            .misfit(Point::new(at.x - e.x, at.y - e.y))
            .unwrap()
            .cost;
        let fd = (plus - minus) / (2.0 * h);
        let an = if k == 0 { m.gradient.x } else { m.gradient.y };
        assert!(
            (fd - an).abs() <= 1e-6 * an.abs().max(1e-12),
            "{k}: {fd} vs {an}"
        );
    }
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7)
        .with_tolerance_grad(1e-16)
        .unwrap()
        .with_tolerance_cost(0.0)
        .unwrap();
    let result = Executor::new(problem, solver)
        .configure(|s| s.param(DVector::from_vec(vec![-20.0, 4.0])).max_iters(100))
        .run()
        .unwrap();
    let found = result.state().best_param.clone().unwrap();
    assert!((found[0] - truth.x).abs() < 1e-8 && (found[1] - truth.y).abs() < 1e-8);
    // A wrong parameter count is an error, not a panic.
    let scene = Scene::from_json(SEA).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let problem = SourceLocation::new(&tracer, Vec::new());
    use argmin::core::CostFunction;
    assert!(problem.cost(&DVector::from_vec(vec![1.0])).is_err());
}

const ROOM: &str = r#"{
    "media": { "air": { "speed": 343.0 } },
    "interfaces": { "panel": { "points": [[0, 5], [3, 5]] } },
    "sources": [[0, 1.5]], "receivers": [[6, 1.2]],
    "paths": [
        { "steps": [], "media": ["air"] },
        { "steps": [{ "reflect": "panel" }], "media": ["air", "air"] }
    ]
}"#;

fn placement_problem(weight: f64) -> ReflectorPlacement {
    let spec: SceneSpec = serde_json::from_str(ROOM).unwrap();
    let start = Placement {
        center: Point::new(2.2, 4.2),
        angle: 0.15,
    };
    ReflectorPlacement::new(
        spec,
        "panel",
        1,
        0,
        Point::new(0.0, 1.5),
        Point::new(6.0, 1.2),
        3.0,
        0.015,
        start,
        weight,
    )
    .unwrap()
}

#[test]
fn reflector_placement_gradient_and_solution() {
    let problem = placement_problem(1e-4);
    let at = Placement {
        center: Point::new(2.4, 4.6),
        angle: 0.25,
    };
    let m = problem.misfit(at).unwrap();
    let h = 1e-6;
    for k in 0..3 {
        let moved = |s: f64| {
            let mut p = at;
            match k {
                0 => p.center.x += s,
                1 => p.center.y += s,
                _ => p.angle += s,
            }
            problem.misfit(p).unwrap().cost
        };
        let fd = (moved(h) - moved(-h)) / (2.0 * h);
        let an = m.gradient[k];
        assert!(
            (fd - an).abs() <= 1e-6 * an.abs().max(1e-9),
            "{k}: {fd} vs {an}"
        );
    }
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7)
        .with_tolerance_grad(1e-12)
        .unwrap()
        .with_tolerance_cost(0.0)
        .unwrap();
    let result = Executor::new(problem, solver)
        .configure(|s| {
            s.param(DVector::from_vec(vec![2.2, 4.2, 0.15]))
                .max_iters(100)
        })
        .run()
        .unwrap();
    let best = result.state().best_param.clone().unwrap();
    let placed = Placement {
        center: Point::new(best[0], best[1]),
        angle: best[2],
    };
    let delay = placement_problem(1e-4).misfit(placed).unwrap().delay;
    assert!((delay - 0.015).abs() < 1e-6, "{delay}");
    // Bad inputs are errors naming what is wrong.
    let spec: SceneSpec = serde_json::from_str(ROOM).unwrap();
    let start = Placement {
        center: Point::new(2.2, 4.2),
        angle: 0.15,
    };
    let (s, l) = (Point::new(0.0, 1.5), Point::new(6.0, 1.2));
    let e = ReflectorPlacement::new(spec.clone(), "wall", 1, 0, s, l, 3.0, 0.015, start, 0.0);
    assert!(e.err().unwrap().to_string().contains("interfaces.wall"));
    let e = ReflectorPlacement::new(spec, "panel", 0, 1, s, l, 3.0, 0.015, start, 0.0);
    assert!(e.err().unwrap().to_string().contains("paths[1].steps"));
}

#[test]
fn lens_profile_gradient_and_improvement() {
    use eigenray::argmin_bridge::LensProfile;
    let points: Vec<[f64; 2]> = (0..7).map(|i| [0.6, 1.8 - 0.6 * i as f64]).collect();
    let spec: SceneSpec = serde_json::from_value(serde_json::json!({
        "media": { "glass": { "index": 1.5 }, "air": { "index": 1.0 } },
        "interfaces": { "back": { "points": points } },
        "sources": [[0.0, 0.0]], "receivers": [[20.6, 0.0]],
        "paths": [{ "steps": [{ "refract": "back" }], "media": ["glass", "air"] }]
    }))
    .unwrap();
    let entries: Vec<Point> = (0..9)
        .map(|i| Point::new(0.0, -1.6 + 0.4 * i as f64))
        .collect();
    let free = vec![0, 1, 2, 4, 5, 6];
    let (source, focus) = (Point::new(-20.0, 0.0), Point::new(20.6, 0.0));
    let make = || {
        LensProfile::new(
            spec.clone(),
            "back",
            free.clone(),
            0,
            source,
            1.0,
            entries.clone(),
            focus,
        )
        .unwrap()
    };
    let problem = make();
    // Off the flat start (every vertex at 0.6), where the paths meet the segments inside.
    let x = [0.31, 0.45, 0.57, 0.58, 0.46, 0.33];
    let m = problem.misfit(&x).unwrap();
    let h = 1e-6;
    for j in 0..x.len() {
        let at = |s: f64| {
            let mut y = x;
            y[j] += s;
            problem.misfit(&y).unwrap().cost
        };
        let fd = (at(h) - at(-h)) / (2.0 * h);
        let an = m.gradient[j];
        assert!(
            (fd - an).abs() <= 1e-6 * an.abs().max(1e-9),
            "{j}: {fd} vs {an}"
        );
    }
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7)
        .with_tolerance_grad(1e-14)
        .unwrap()
        .with_tolerance_cost(0.0)
        .unwrap();
    let flat = vec![0.6; free.len()];
    let before = make().misfit(&flat).unwrap().cost;
    let result = Executor::new(problem, solver)
        .configure(|s| s.param(DVector::from_vec(flat.clone())).max_iters(100))
        .run();
    // The objective has kinks where paths change segments: the line search may end the run.
    let best = match result {
        Ok(r) => r.state().best_param.clone().unwrap().as_slice().to_vec(),
        Err(e) => panic!("{e}"),
    };
    let after = make().misfit(&best).unwrap().cost;
    assert!(after < 1e-3 * before, "{before} → {after}");
    // Convex: thinner towards the edges.
    assert!(
        best[0] < best[1] && best[1] < best[2] && best[2] < 0.6,
        "{best:?}"
    );
}
