//! What both fuzz targets check on a valid scene: tracing and writing it neither panics nor
//! produces non-finite times or points, and the output is valid JSON.

use std::time::{Duration, Instant};

use eigenray::{Scene, SolverOptions, Tracer, write};

#[path = "../../tests/support/interface.rs"]
mod interface;
use interface::distance_to_polyline;

/// Largest scene traced (beyond these only validation runs, to keep executions fast).
const MAX_RAYS: usize = 64;
const MAX_STEPS: usize = 16;
const MAX_SEGMENTS: usize = 2000;
/// Iteration cap per ray, so that a timeout means a hang rather than a large legitimate limit.
const MAX_ITERATIONS: usize = 200;

/// Runs `f`, the work of one input of `bytes` bytes, and fails when it took longer than the
/// input's CPU budget: issue 29's contract of at most 1 s of CPU per KB of input with default
/// settings, with a floor of 1 s for the smallest inputs, doubled for the instrumented build
/// (wall time, which bounds the CPU time of the one thread a fuzzer runs on). An input that
/// exceeds it is a finding, like a panic.
#[allow(dead_code, reason = "not every target uses it")]
pub fn within_budget<R>(bytes: usize, f: impl FnOnce() -> R) -> R {
    let budget = Duration::from_secs_f64(2.0 * (1.0 + bytes as f64 / 1024.0));
    let start = Instant::now();
    let out = f();
    let took = start.elapsed();
    assert!(
        took <= budget,
        "an input of {bytes} bytes took {took:?}, beyond its budget of {budget:?}"
    );
    out
}

/// Traces every ray of `scene` (if it is small enough) and checks the results.
pub fn trace_and_check(mut scene: Scene) {
    let steps: usize = scene.paths().iter().map(|p| p.steps.len()).sum();
    if scene.num_rays() > MAX_RAYS || steps > MAX_STEPS || scene.segments().len() > MAX_SEGMENTS {
        return;
    }
    let opts = scene.solver();
    scene.set_solver(SolverOptions {
        max_iterations: opts.max_iterations.min(MAX_ITERATIONS),
        ..opts
    })
        .expect("valid solver options");
    let tracer = match Tracer::new(&scene) {
        Ok(t) => t,
        Err(e) => {
            assert!(!e.key.is_empty(), "Tracer::new error without a key: {e:?}");
            return;
        }
    };
    let rays = tracer.trace_all();
    assert_eq!(rays.len(), scene.num_rays());
    for r in &rays {
        let k = scene.paths()[r.path].steps.len();
        assert!(r.iterations <= scene.solver().max_iterations, "{r:?}");
        if r.status.has_time() {
            let t = r.time;
            assert!(t.is_finite() && t >= 0.0, "time {t}: {r:?}");
            assert_eq!(r.points.len(), k + 2, "{r:?}");
            assert!(r.points.iter().all(|p| p.is_finite()), "{r:?}");
            assert_eq!(r.media.len(), k + 1, "{r:?}");
            // Every interaction point lies on its interface.
            let size = scene.bbox().diagonal();
            for (i, step) in scene.paths()[r.path].steps.iter().enumerate() {
                let line = &scene.interfaces()[step.interface].polyline;
                let p = r.points[i + 1];
                let d = distance_to_polyline(line, p);
                assert!(
                    d <= 1e-9 * size,
                    "interaction {i} at {p:?} is {d:e} from its interface (scene size {size:e}): {r:?}"
                );
            }
        } else {
            assert!(r.time.is_nan() && r.points.is_empty(), "{r:?}");
        }
    }
    // Every stationary path and the search, where the scene asks: bounded by their work
    // budgets (`solver.max_work`), so within the input's CPU budget too.
    if scene.solver().stationary == eigenray::scene::StationaryMode::All
        && let Ok(all) = tracer.trace_stationary(&eigenray::options::Run::new())
    {
        for t in &all.triples {
            for a in &t.arrivals {
                assert!(a.time.is_nan() || (a.time.is_finite() && a.time >= 0.0), "{a:?}");
            }
        }
    }
    if scene.search().is_some()
        && let Ok(report) = tracer.search(&eigenray::options::Run::new())
    {
        for a in &report.arrivals {
            assert!(a.arrival.time.is_finite() && a.arrival.time >= 0.0, "{a:?}");
        }
    }
    let mut out = Vec::new();
    write(&scene, &rays, eigenray::Format::Json, &mut out).expect("writing to a Vec");
    let doc: serde_json::Value = serde_json::from_slice(&out).expect("the output is valid JSON");
    assert_eq!(
        doc["rays"].as_array().map(Vec::len),
        Some(rays.len()),
        "one output entry per ray"
    );
}

