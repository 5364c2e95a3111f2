//! The second round of careless and hostile input: work that grows with the input stays
//! bounded, memory sized by the input never aborts, and text from the user stays readable.

use std::time::Duration;

use serde_json::json;

use super::{TempFile, run_capped};

/// A 32 KB medium name on every leg of 32,768 rays (16,384 receivers, two paths), written
/// as CSV under a 1.5 GB address-space cap: the names make 1.6 GB of text, and the writer
/// formats as many rays at a time as fit its memory budget, so the run succeeds instead of
/// aborting (it formatted 16,384 rays at a time, two such windows at once).
#[test]
fn long_names_on_many_rays_are_written_within_a_memory_cap() {
    let name = "m".repeat(32 << 10);
    let receivers: Vec<[f64; 2]> = (0..16_384).map(|i| [i as f64 * 1e-3, 1.0]).collect();
    let scene = json!({
        "media": { &name: { "speed": 1.0 } },
        "interfaces": { "mirror": { "points": [[-100.0, 0.0], [100.0, 0.0]] } },
        "sources": [[0.0, 1.0]],
        "receivers": receivers,
        "paths": [
            { "steps": [{ "reflect": "mirror" }], "media": [&name, &name] },
            { "steps": [], "media": [&name] }
        ]
    });
    let file = TempFile::with(scene.to_string());
    let out = TempFile::with("");
    let run = run_capped(
        1_500_000,
        &format!("solve {} --format csv", file.path()),
        &format!("> {}", out.path()),
        None,
        Duration::from_secs(120),
    );
    assert_eq!(run.code, Some(0), "stderr: {}", run.stderr);
    let bytes = std::fs::metadata(out.path()).unwrap().len();
    assert!(bytes > 16_384 * 3 * (32 << 10), "{bytes} bytes");
}

/// `"stationary": "all"` over 10⁷ triples (1,000 sources × 1,000 receivers × 10 paths) under
/// a 1.5 GB address-space cap: refused before the run, naming `solver.stationary` and what
/// it needs, instead of aborting once the arrivals fill the memory. The check counts the
/// cap, not only the machine's free memory.
#[test]
fn every_stationary_path_of_too_many_rays_is_refused_up_front() {
    let points: Vec<[f64; 2]> = (0..1000).map(|i| [i as f64 * 1e-3, 1.0]).collect();
    let paths: Vec<_> = (0..10)
        .map(|_| json!({ "steps": [{ "reflect": "mirror" }], "media": ["air", "air"] }))
        .collect();
    let scene = json!({
        "media": { "air": { "speed": 1.0 } },
        "interfaces": { "mirror": { "points": [[-100.0, 0.0], [100.0, 0.0]] } },
        "sources": points, "receivers": points, "paths": paths,
        "solver": { "stationary": "all" }
    });
    let file = TempFile::with(scene.to_string());
    let run = run_capped(
        1_500_000,
        &format!("solve {}", file.path()),
        "",
        None,
        Duration::from_secs(60),
    );
    run.assert_refused("solver.stationary");
    assert!(run.stderr.contains("GB"), "{}", run.stderr);
}
