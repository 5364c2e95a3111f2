//! The shared benchmark scenes (`fixtures/bench/`) against their 40-digit references.

use eigenray::Status;
use serde_json::Value;

use crate::common::*;

fn load(name: &str) -> (String, Value) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bench");
    let read =
        |f: String| std::fs::read_to_string(dir.join(&f)).unwrap_or_else(|e| panic!("{f}: {e}"));
    let scene = read(format!("{name}.json"));
    let reference =
        serde_json::from_str(&read(format!("{name}.ref.json"))).expect("reference JSON");
    (scene, reference)
}

/// Solves every ray of benchmark `name` and compares it with the reference; returns the
/// largest relative time error and point distance over converged rays.
fn check(name: &str) -> (f64, f64) {
    check_at(name, None, 1e-9)
}

/// [`check`] with the scene's tolerance replaced by `tolerance` (when given), and point
/// distances bounded by `max_point`.
fn check_at(name: &str, tolerance: Option<f64>, max_point: f64) -> (f64, f64) {
    let (text, reference) = load(name);
    let mut sc = eigenray::Scene::from_json(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
    if let Some(tolerance) = tolerance {
        sc.set_solver(eigenray::SolverOptions {
            tolerance,
            ..sc.solver()
        })
        .expect("valid solver options");
    }
    let rays = trace_all(&sc);
    let status = reference["status"].as_array().expect("status");
    let times = reference["time"].as_array().expect("time");
    let points = reference["points"].as_array().expect("points");
    assert_eq!(rays.len(), status.len(), "{name}: number of rays");
    let (mut max_t, mut max_p) = (0.0f64, 0.0f64);
    let mut mismatches = Vec::new();
    for (i, ray) in rays.iter().enumerate() {
        let want = status[i].as_str().expect("status string");
        if ray.status.as_str() != want {
            mismatches.push(format!(
                "ray {i} (source {}, receiver {} at {:?}, path {} {:?}): got {} ({:?}, time {:?}, points {:?}), reference {want} (time {}, points {})",
                ray.source,
                ray.receiver,
                sc.receivers()[ray.receiver],
                ray.path,
                sc.paths()[ray.path].name,
                ray.status,
                ray.reason,
                ray.time,
                ray.points,
                times[i],
                points[i],
            ));
            continue;
        }
        if ray.status != Status::Converged {
            continue;
        }
        let t = times[i].as_f64().expect("time");
        let err = rel_err(ray.time, t);
        max_t = max_t.max(err);
        let pts = points[i].as_array().expect("points");
        assert_eq!(pts.len(), ray.points.len(), "{name}: ray {i} points");
        for (got, want) in ray.points.iter().zip(pts) {
            let w = [want[0].as_f64().unwrap(), want[1].as_f64().unwrap()];
            max_p = max_p.max(dist(pt(*got), w));
        }
    }
    for m in mismatches.iter().take(5) {
        println!("{name}: {m}");
    }
    assert!(
        mismatches.is_empty(),
        "{name}: {} status mismatches, first: {}",
        mismatches.len(),
        mismatches[0]
    );
    println!(
        "bench {name}: {} rays, max relative time error {max_t:.2e}, max point distance {max_p:.2e}",
        rays.len()
    );
    assert!(max_t <= 1e-12, "{name}: max relative time error {max_t:e}");
    assert!(max_p <= max_point, "{name}: max point distance {max_p:e}");
    (max_t, max_p)
}

#[test]
fn seed500() {
    check("seed500");
}

#[test]
fn layers10() {
    check("layers10");
}

#[test]
fn room2d() {
    check("room2d");
}

/// The travel time is stationary: its error is of second order in the points' error, so a
/// residual tolerance of 1e-6 (sines of angles equal to 1e-6) already gives times exact to
/// 1e-12 on the refraction scenes — the setting the speed figures "at ≤ 1e-12 relative error"
/// use. The room, with its grazing reflections, needs 1e-8.
#[test]
fn loose_tolerances_give_times_to_1e_12() {
    for (name, tolerance) in [("seed500", 1e-6), ("layers10", 1e-6), ("room2d", 1e-8)] {
        let (max_t, _) = check_at(name, Some(tolerance), 1e-5);
        assert!(max_t <= 1e-12, "{name}: {max_t:e}");
    }
}
