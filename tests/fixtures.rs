//! Runs every `fixtures/cases/NAME.json` scene and compares it with `NAME.expected.json`.
//!
//! An expected file holds `{"rays": [{"status", "time"?, "points"?}, ...]}` in ray order;
//! times must agree to 1e-12 relative, points to 1e-9 absolute. `fixtures/make_expected.py`
//! writes both files of each case from closed forms.

use std::path::{Path, PathBuf};

use eigenray::{Ray, Scene, Tracer};
use serde_json::Value;

const TIME_TOL: f64 = 1e-12;
const POINT_TOL: f64 = 1e-9;

/// The scenes of `fixtures/cases`, sorted by name.
fn cases() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/cases");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            name.ends_with(".json") && !name.ends_with(".expected.json")
        })
        .collect();
    v.sort();
    v
}

/// Compares one ray with its expected entry; `Err` says what differs.
fn compare(ray: &Ray, want: &Value) -> Result<f64, String> {
    let status = want["status"]
        .as_str()
        .ok_or("expected entry without a status")?;
    if ray.status.as_str() != status {
        return Err(format!(
            "status {} ({:?}), expected {status}",
            ray.status, ray.reason
        ));
    }
    let Some(t) = want.get("time").and_then(Value::as_f64) else {
        return if ray.time.is_nan() {
            Ok(0.0)
        } else {
            Err(format!("time {:?}, expected none", ray.time))
        };
    };
    let time = ray.time;
    let err = ((time - t) / t).abs();
    if err.is_nan() || err > TIME_TOL {
        return Err(format!(
            "time {time}, expected {t} (relative error {err:e})"
        ));
    }
    if let Some(pts) = want.get("points").and_then(Value::as_array) {
        if pts.len() != ray.points.len() {
            return Err(format!(
                "{} points, expected {}",
                ray.points.len(),
                pts.len()
            ));
        }
        for (i, (got, w)) in ray.points.iter().zip(pts).enumerate() {
            let (x, y) = (
                w[0].as_f64().ok_or("bad point")?,
                w[1].as_f64().ok_or("bad point")?,
            );
            let d = (got.x - x).hypot(got.y - y);
            if d.is_nan() || d > POINT_TOL {
                return Err(format!(
                    "point {i} ({}, {}), expected ({x}, {y})",
                    got.x, got.y
                ));
            }
        }
    }
    Ok(err)
}

/// Runs one case; the failures as messages, and the largest time error.
fn run(scene_path: &Path) -> (Vec<String>, f64) {
    let name = scene_path
        .file_stem()
        .unwrap()
        .to_string_lossy()
        .into_owned();
    let read =
        |p: &Path| std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let expected_path = scene_path.with_extension("expected.json");
    let scene = Scene::from_json(&read(scene_path))
        .unwrap_or_else(|e| panic!("fixture {name}: invalid scene: {e}"));
    let expected: Value = serde_json::from_str(&read(&expected_path))
        .unwrap_or_else(|e| panic!("fixture {name}: {}: {e}", expected_path.display()));
    let want = expected["rays"]
        .as_array()
        .unwrap_or_else(|| panic!("fixture {name}: no `rays` list"));
    let rays = Tracer::new(&scene)
        .unwrap_or_else(|e| panic!("fixture {name}: {e}"))
        .trace_all();
    if rays.len() != want.len() {
        return (
            vec![format!(
                "fixture {name}: {} rays, expected {}",
                rays.len(),
                want.len()
            )],
            0.0,
        );
    }
    let mut failures = Vec::new();
    let mut max = 0.0f64;
    for (i, (ray, w)) in rays.iter().zip(want).enumerate() {
        match compare(ray, w) {
            Ok(e) => max = max.max(e),
            Err(msg) => failures.push(format!(
                "fixture {name}: ray {i} (source {}, receiver {}, path {}): {msg}",
                ray.source, ray.receiver, ray.path
            )),
        }
    }
    (failures, max)
}

#[test]
fn every_case_matches_its_expected_result() {
    let cases = cases();
    assert!(cases.len() >= 6, "only {} fixture cases", cases.len());
    let mut failures = Vec::new();
    for case in &cases {
        let (f, max) = run(case);
        let name = case.file_stem().unwrap().to_string_lossy();
        println!(
            "fixture {name}: {}, max relative time error {max:.2e}",
            if f.is_empty() { "ok" } else { "FAILED" }
        );
        failures.extend(f);
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
