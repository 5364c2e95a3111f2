//! Bounded, interruptible work: every complete search has a work budget (`solver.max_work`),
//! the default mode's fallback about 10 ms a ray; long runs show their progress on a
//! terminal; a `Stop` ends a library call soon after it is requested.

use std::time::{Duration, Instant};

use eigenray::options::Run;
use eigenray::{Scene, Tracer};
use serde_json::{Value, json};

use super::{TempFile, run_bounded, solve_file};

/// Two wavy walls of 50 segments (as `benches/adversarial_scenes.py` draws them) and one
/// path of `k` reflections alternating between them, from `sources` to `receivers`.
fn walls(k: usize, sources: Value, receivers: Value) -> Value {
    let wall = |y0: f64, phase: f64| -> Vec<[f64; 2]> {
        (0..=50)
            .map(|i| {
                let x = 10.0 * i as f64 / 50.0;
                let y = y0 + 0.15 * (3.1 * x + phase).sin() + 0.05 * (7.3 * x).sin();
                [x, y]
            })
            .collect()
    };
    let steps: Vec<Value> = (0..k)
        .map(|i| json!({ "reflect": if i % 2 == 0 { "floor" } else { "roof" } }))
        .collect();
    json!({
        "media": { "air": { "speed": 1.0 } },
        "interfaces": { "floor": { "points": wall(0.0, 0.0) }, "roof": { "points": wall(2.0, 1.3) } },
        "sources": sources, "receivers": receivers,
        "paths": [{ "steps": steps, "media": vec!["air"; k + 1] }]
    })
}

/// The entries of `eigenray solve` on `scene`, and how long it took.
fn solve(scene: &Value) -> (Vec<Value>, Duration) {
    let start = Instant::now();
    let run = solve_file(&scene.to_string());
    let took = start.elapsed();
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let out: Value = serde_json::from_slice(&run.stdout).unwrap();
    (out["rays"].as_array().unwrap().clone(), took)
}

/// `solver.max_work` is checked like every key: exit 2, nothing on standard output, the key
/// named.
#[test]
fn max_work_is_validated() {
    for bad in [
        json!(0),
        json!(-1),
        json!(1.5),
        json!("many"),
        json!(2u64 << 40),
    ] {
        let mut scene = walls(2, json!([[1.0, 1.0]]), json!([[9.0, 1.1]]));
        scene["solver"] = json!({ "max_work": bad });
        solve_file(&scene.to_string()).assert_refused("solver.max_work");
    }
    let mut scene = walls(2, json!([[1.0, 1.0]]), json!([[9.0, 1.1]]));
    scene["solver"] = json!({ "max_work": 1_000_000 });
    assert_eq!(solve_file(&scene.to_string()).code, Some(0));
}

/// Every stationary path of 10 reflections between the walls: 418 CPU s before; now the
/// default budget ends it in about a second, `complete: false`; a small budget sooner; the
/// budget counts the bounds of each held-vertex choice (2^10 a leaf), which it did not.
#[test]
fn every_stationary_path_between_wavy_walls_stops_at_its_budget() {
    let mut scene = walls(10, json!([[1.0, 1.0]]), json!([[9.0, 1.1]]));
    scene["solver"] = json!({ "stationary": "all" });
    let (rays, took) = solve(&scene);
    assert!(took < Duration::from_secs(20), "{took:?}");
    assert!(rays.iter().all(|r| r["complete"] == false), "{rays:?}");
    scene["solver"]["max_work"] = json!(1000);
    let (rays, took) = solve(&scene);
    assert!(took < Duration::from_secs(5), "{took:?}");
    assert!(rays.iter().all(|r| r["complete"] == false));
}

/// Default settings, 12 reflections from beneath the floor (no admissible path: every ray
/// falls back to the complete search), 10 × 10 sources and receivers: 60 s before, now about
/// 10 ms a ray, each `not_converged` with the search's limit as its reason.
#[test]
fn the_default_modes_fallback_is_bounded_per_ray() {
    let sources: Vec<[f64; 2]> = (0..10).map(|i| [1.0 + 0.3 * i as f64, -1.0]).collect();
    let receivers: Vec<[f64; 2]> = (0..10).map(|i| [9.0 - 0.3 * i as f64, 1.1]).collect();
    let (rays, took) = solve(&walls(12, json!(sources), json!(receivers)));
    assert_eq!(rays.len(), 100);
    assert!(took < Duration::from_secs(20), "{took:?}");
    for r in &rays {
        assert_eq!(r["status"], "not_converged", "{r}");
        assert!(r["reason"].as_str().unwrap().contains("limit"), "{r}");
    }
}

/// A search of 6 steps over the walls (109 s before): its specular arrivals come from the
/// beam tree, complete and quick; with `vertex` (every edge-held arrival of every sequence
/// through the walls' vertices, searched completely) it ends at its budget per pair.
#[test]
fn a_search_over_wavy_walls_stops_at_its_budget() {
    let mut scene = walls(0, json!([[1.0, 1.0]]), json!([[9.0, 1.1]]));
    scene["media"]["air"]["at"] = json!([5.0, 1.0]);
    scene["paths"] = json!([]);
    scene["search"] = json!({ "max_steps": 6, "refract": false });
    let arrivals = |scene: &Value| {
        let start = Instant::now();
        let run = solve_file(&scene.to_string());
        assert_eq!(run.code, Some(0), "{}", run.stderr);
        assert!(start.elapsed() < Duration::from_secs(20));
        let out: Value = serde_json::from_slice(&run.stdout).unwrap();
        out["arrivals"].as_array().unwrap().clone()
    };
    let specular = arrivals(&scene);
    assert!(specular.len() > 1);
    assert!(specular.iter().all(|a| a["complete"] == true));
    scene["search"]["vertex"] = json!(true);
    scene["solver"] = json!({ "max_work": 1_000_000 });
    let with_vertices = arrivals(&scene);
    assert!(with_vertices.len() > specular.len());
    assert!(with_vertices.iter().all(|a| a["complete"] == false));
}

/// A long run shows its progress on standard error when that is a terminal (through
/// `script`, where it is installed), and nothing when it is not.
#[test]
fn long_runs_show_progress_on_a_terminal() {
    let mut scene = walls(10, json!([[1.0, 1.0]]), json!([[9.0, 1.1]]));
    // About 2 s of work: longer than the half second before progress shows.
    scene["solver"] = json!({ "stationary": "all", "max_work": 1u64 << 27 });
    let file = TempFile::with(scene.to_string());
    let quiet = run_bounded(
        &format!("solve {}", file.path()),
        "",
        None,
        Duration::from_secs(60),
    );
    assert!(quiet.stderr.is_empty(), "{}", quiet.stderr);
    if std::process::Command::new("script")
        .arg("--version")
        .output()
        .is_err()
    {
        return;
    }
    let bin = env!("CARGO_BIN_EXE_eigenray");
    let out = std::process::Command::new("script")
        .args([
            "-qc",
            &format!("{bin} solve {} > /dev/null", file.path()),
            "/dev/null",
        ])
        .output()
        .unwrap();
    let shown = String::from_utf8_lossy(&out.stdout);
    assert!(
        shown.contains("rays searched") && shown.contains("spent"),
        "{shown}"
    );
}

/// A `Stop` requested from another thread ends every stationary path of the walls (about a
/// second of work) and a batch of their fallback rays soon after.
#[test]
fn a_stop_ends_a_library_call_soon() {
    let mut doc = walls(
        10,
        json!([[1.0, 1.0], [1.2, 1.0]]),
        json!([[9.0, 1.1], [8.8, 1.1]]),
    );
    // Several seconds of work a triple without the stop.
    doc["solver"] = json!({ "stationary": "all", "max_work": 1u64 << 28 });
    let tracer = Tracer::new(Scene::from_json(&doc.to_string()).unwrap()).unwrap();
    let run = Run::new();
    let (asked, done) = std::thread::scope(|s| {
        let asker = s.spawn(|| {
            std::thread::sleep(Duration::from_millis(200));
            run.request_stop();
            Instant::now()
        });
        let rays = tracer.trace_stationary(&run).unwrap();
        let done = Instant::now();
        assert!(rays.triples.iter().all(|t| !t.complete));
        (asker.join().unwrap(), done)
    });
    let late = done.saturating_duration_since(asked);
    assert!(late < Duration::from_millis(500), "{late:?}");
    // Already requested: nothing is searched.
    let start = Instant::now();
    let rays = tracer.trace_stationary(&run).unwrap();
    assert!(start.elapsed() < Duration::from_millis(200));
    assert!(
        rays.triples
            .iter()
            .all(|t| t.arrivals.is_empty() && !t.complete)
    );
}
