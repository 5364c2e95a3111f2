//! Bounded, interruptible work: every complete search has a work budget (`solver.max_work`),
//! the default mode's fallback a small one a ray; long runs show their progress on a
//! terminal; a stop request (`Run::request_stop`) ends a library call that its budget would not end for hours.
//!
//! No test here reads a clock to pass or fail: each bounds the work (the budgets, counted in
//! units of work) and checks what the bound promises (`complete: false`, the limit named as
//! the reason). The command-line runs are killed after ten minutes ([`run_bounded`]) and
//! the stop's call is given up after [`STOP_WATCHDOG`] only so that a broken bound cannot
//! hang the test run.

use std::sync::{Arc, mpsc};
use std::time::Duration;

use eigenray::options::Run;
use eigenray::{Scene, Tracer};
use serde_json::{Value, json};

use super::{TempFile, run_bounded, solve_file};

/// How long a stopped call may take before the test gives up on it: no clock decides the
/// test's answer (a stop that works returns within a fraction of a second); this only keeps a
/// broken stop from running its hours of budget.
const STOP_WATCHDOG: Duration = Duration::from_secs(120);

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

/// The entries of `eigenray solve` on `scene`.
fn solve(scene: &Value) -> Vec<Value> {
    let run = solve_file(&scene.to_string());
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let out: Value = serde_json::from_slice(&run.stdout).unwrap();
    out["rays"].as_array().unwrap().clone()
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
/// default budget ends it (about a second), `complete: false`; a small budget sooner; the
/// budget counts the bounds of each held-vertex choice (2^10 a leaf), which it did not.
#[test]
fn every_stationary_path_between_wavy_walls_stops_at_its_budget() {
    let mut scene = walls(10, json!([[1.0, 1.0]]), json!([[9.0, 1.1]]));
    scene["solver"] = json!({ "stationary": "all" });
    let rays = solve(&scene);
    assert!(!rays.is_empty());
    assert!(rays.iter().all(|r| r["complete"] == false), "{rays:?}");
    scene["solver"]["max_work"] = json!(1000);
    let rays = solve(&scene);
    assert!(!rays.is_empty());
    assert!(rays.iter().all(|r| r["complete"] == false));
}

/// Default settings, 12 reflections from beneath the floor (no admissible path: every ray
/// falls back to the complete search), 10 × 10 sources and receivers: 60 s before, now each
/// ray's fallback stops at its budget (2^18 units, about 10 ms), `not_converged` with the
/// search's limit as its reason.
#[test]
fn the_default_modes_fallback_is_bounded_per_ray() {
    let sources: Vec<[f64; 2]> = (0..10).map(|i| [1.0 + 0.3 * i as f64, -1.0]).collect();
    let receivers: Vec<[f64; 2]> = (0..10).map(|i| [9.0 - 0.3 * i as f64, 1.1]).collect();
    let rays = solve(&walls(12, json!(sources), json!(receivers)));
    assert_eq!(rays.len(), 100);
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
        let run = solve_file(&scene.to_string());
        assert_eq!(run.code, Some(0), "{}", run.stderr);
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
    let quiet = run_bounded(&format!("solve {}", file.path()), "", None);
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

/// Every stationary path of `tracer`'s scene under `stop`, on a thread of its own: `None`
/// when it has not returned after [`STOP_WATCHDOG`] (the thread is left to the process's
/// exit).
fn stationary_under(
    tracer: &Arc<Tracer>,
    stop: &Run,
    request_after: Option<Duration>,
) -> Option<eigenray::StationaryRays> {
    let (sender, answer) = mpsc::channel();
    let (tracer, worker_stop) = (Arc::clone(tracer), stop.clone());
    std::thread::spawn(move || {
        let rays = tracer.trace_stationary(&worker_stop);
        let _ = sender.send(rays.expect("every stationary path"));
    });
    if let Some(wait) = request_after {
        std::thread::sleep(wait);
        stop.request_stop();
    }
    answer.recv_timeout(STOP_WATCHDOG).ok()
}

/// A stop requested (`Run::request_stop`) from another thread ends every stationary path of the walls, whose
/// budget (2^40 units: hours of work a triple) would not end it: the call returns at all, and
/// every triple says `complete: false`. Requested before a call, it ends the call before any
/// search: no arrival at all.
#[test]
fn a_stop_ends_a_library_call_its_budget_would_not_end() {
    let mut doc = walls(
        10,
        json!([[1.0, 1.0], [1.2, 1.0]]),
        json!([[9.0, 1.1], [8.8, 1.1]]),
    );
    doc["solver"] = json!({ "stationary": "all", "max_work": 1u64 << 40 });
    let tracer = Arc::new(Tracer::new(Scene::from_json(&doc.to_string()).unwrap()).unwrap());
    let stop = Run::new();
    // Into the search (200 ms: when does not matter, the request is checked throughout).
    let rays = stationary_under(&tracer, &stop, Some(Duration::from_millis(200)))
        .expect("the stop ends the call");
    assert_eq!(rays.triples.len(), 4);
    assert!(rays.triples.iter().all(|t| !t.complete));
    // Already requested: nothing is searched.
    let rays = stationary_under(&tracer, &stop, None).expect("the stop ends the call");
    assert_eq!(rays.triples.len(), 4);
    assert!(
        rays.triples
            .iter()
            .all(|t| t.arrivals.is_empty() && !t.complete)
    );
}
