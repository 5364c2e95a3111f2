//! Fuzz target `cli`: raw bytes as a scene document through what `eigenray solve` does: the
//! ray-count arithmetic, the memory estimate, a batch (with and without warm starts) and every
//! output writer.
#![no_main]

use eigenray::{BatchOptions, Format, Point, RayRecord, Scene, SolverOptions, Tracer, write};
use libfuzzer_sys::fuzz_target;

/// Largest batch traced (beyond it only the arithmetic runs).
const MAX_RAYS: usize = 64;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(mut scene) = Scene::from_json(text) else {
        return;
    };
    // The counts a batch allocates for are the exact products.
    let size = scene.batch_size();
    let pairs = scene.sources().len() as u128 * scene.receivers().len() as u128;
    assert_eq!(size.rays as u128, pairs * scene.paths().len() as u128);
    let points: u128 = scene.paths().iter().map(|p| p.steps.len() as u128 + 2).sum();
    let legs: u128 = scene.paths().iter().map(|p| p.steps.len() as u128 + 1).sum();
    assert_eq!(size.points as u128, pairs * points);
    assert_eq!(size.legs as u128, pairs * legs);
    let bytes = size.bytes(
        std::mem::size_of::<RayRecord>(),
        std::mem::size_of::<Point>(),
        4,
    );
    let exact = size.rays as u128 * std::mem::size_of::<RayRecord>() as u128
        + size.points as u128 * 16
        + size.legs as u128 * 4;
    assert_eq!(bytes.map(|b| b as u128), (exact <= usize::MAX as u128).then_some(exact));
    if size.rays > MAX_RAYS || size.points > 16 * MAX_RAYS {
        return;
    }
    let capped = SolverOptions {
        max_iterations: scene.solver().max_iterations.min(200),
        ..scene.solver()
    };
    scene.set_solver(capped).expect("valid options");
    let Ok(tracer) = Tracer::new(&scene) else {
        return;
    };
    for warm_start in [true, false] {
        let options = BatchOptions {
            warm_start,
            chunk: 3,
        };
        let Ok(batch) = tracer.trace_batch(&options, &eigenray::options::Run::new()) else {
            return;
        };
        assert_eq!(batch.len(), size.rays);
        for format in [Format::Json, Format::Jsonl, Format::Csv, Format::Npy] {
            let mut out = Vec::new();
            write(&scene, &batch, format, &mut out).expect("writing to a Vec");
            match format {
                Format::Json => {
                    let doc: serde_json::Value =
                        serde_json::from_slice(&out).expect("valid JSON");
                    assert_eq!(doc["rays"].as_array().map(Vec::len), Some(size.rays));
                }
                Format::Jsonl => {
                    let text = std::str::from_utf8(&out).expect("UTF-8");
                    assert_eq!(text.lines().count(), size.rays);
                    for line in text.lines() {
                        let _: serde_json::Value = serde_json::from_str(line).expect("JSON line");
                    }
                }
                Format::Csv => {
                    let text = std::str::from_utf8(&out).expect("UTF-8");
                    assert!(text.lines().count() > size.rays);
                }
                Format::Npy => assert!(out.starts_with(b"\x93NUMPY")),
            }
        }
    }
});
