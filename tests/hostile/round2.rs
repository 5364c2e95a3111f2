//! The second round of careless and hostile input: work that grows with the input stays
//! bounded, memory sized by the input never aborts, and text from the user stays readable.

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
    let run = run_capped(1_500_000, &format!("solve {}", file.path()), "", None);
    run.assert_refused("solver.stationary");
    assert!(run.stderr.contains("GB"), "{}", run.stderr);
}

/// The air-over-water scene of the format's example with one path, for the messages below.
fn air_over_water(media: serde_json::Value, steps: serde_json::Value) -> serde_json::Value {
    json!({
        "media": media,
        "background": "air",
        "domain": [[-2.0, -3.0], [5.0, 3.0]],
        "interfaces": { "surface": { "points": [[-2.0, 0.0], [5.0, 0.0]] } },
        "sources": [[0.0, 1.0]],
        "receivers": [[1.0, -1.0]],
        "paths": [{ "steps": steps }]
    })
}

/// Air given an index and water a speed: the times would mix two units, so the scene is
/// refused, naming the medium of the other kind (it returned 1.0009 before).
#[test]
fn media_that_mix_speed_and_index_are_refused() {
    let media = json!({ "air": { "index": 1.0 }, "water": { "speed": 1500.0, "at": [0.5, -0.5] } });
    let run =
        super::solve_file(&air_over_water(media, json!([{ "refract": "surface" }])).to_string());
    run.assert_refused("media.water: has a `speed` while `air` has an `index`");
}

/// A misspelt medium or interface name gets the nearest known name as a suggestion; a name
/// far from every known one gets none.
#[test]
fn typos_in_names_get_a_suggestion() {
    let media = json!({ "air": { "speed": 1.0 }, "water": { "speed": 0.75, "at": [0.5, -0.5] } });
    let mut scene = air_over_water(media.clone(), json!([{ "refract": "surfce" }]));
    let run = super::solve_file(&scene.to_string());
    run.assert_refused(
        "paths[0].steps[0].refract: unknown interface `surfce` (did you mean `surface`?)",
    );
    scene["paths"][0] = json!({ "steps": [{ "refract": "surface" }], "media": ["air", "watr"] });
    let run = super::solve_file(&scene.to_string());
    run.assert_refused("paths[0].media[1]: unknown medium `watr` (did you mean `water`?)");
    scene["paths"][0] = json!({ "steps": [{ "refract": "surface" }], "media": ["air", "oil"] });
    let run = super::solve_file(&scene.to_string());
    assert_eq!(
        run.first_line(),
        "error: paths[0].media[1]: unknown medium `oil`"
    );
}

/// A step with both `reflect` and `refract` is named, with what is wrong, not called invalid
/// JSON; so is a step with neither.
#[test]
fn a_step_of_both_kinds_is_named() {
    let media = json!({ "air": { "speed": 1.0 }, "water": { "speed": 0.75, "at": [0.5, -0.5] } });
    let both = json!([{ "reflect": "surface" }, { "reflect": "surface", "refract": "surface" }]);
    let run = super::solve_file(&air_over_water(media.clone(), both).to_string());
    run.assert_refused("paths[0].steps[1]: a step is one interaction");
    assert!(!run.stderr.contains("invalid JSON"), "{}", run.stderr);
    let run = super::solve_file(&air_over_water(media, json!([{}])).to_string());
    run.assert_refused("paths[0].steps[0]: a step needs `reflect`, `refract` or `diffract`");
}

/// An unknown name of a megabyte is quoted cut short, saying how long it was: one short line.
#[test]
fn long_unknown_names_are_cut_in_messages() {
    let media = json!({ "air": { "speed": 1.0 }, "water": { "speed": 0.75, "at": [0.5, -0.5] } });
    let name = "x".repeat(1 << 20);
    let scene = air_over_water(media, json!([{ "reflect": name }]));
    let run = super::solve_file(&scene.to_string());
    run.assert_refused("paths[0].steps[0].reflect: unknown interface `xxx");
    assert!(run.stderr.len() < 300, "{} bytes", run.stderr.len());
    assert!(run.stderr.contains("(1048576 bytes)"), "{}", run.stderr);
}

/// A path without `media` in a scene where no medium fills a region: the message names that
/// path's `media` and says how to give regions, not `background`, a key the user never wrote.
#[test]
fn a_path_without_media_is_named_when_no_region_has_a_medium() {
    let scene = json!({
        "media": { "air": { "speed": 1.0 } },
        "interfaces": { "wall": { "points": [[0, 0], [1, 0]] } },
        "sources": [[0, 1]], "receivers": [[1, 1]],
        "paths": [
            { "steps": [{ "reflect": "wall" }], "media": ["air", "air"] },
            { "steps": [{ "reflect": "wall" }] }
        ]
    });
    let run = super::solve_file(&scene.to_string());
    run.assert_refused("paths[1].media: missing: path 1 takes its leg media from the regions");
    assert!(run.stderr.contains("`background`") && run.stderr.contains("`at`"));
}

/// `--format csv` for a scene with a search but no `--arrivals`: one readable message, without
/// the run of spaces a line continuation once left in it.
#[test]
fn the_arrivals_message_has_no_run_of_spaces() {
    let scene = json!({
        "media": { "air": { "speed": 1.0 } },
        "background": "air",
        "interfaces": { "wall": { "points": [[0, 0], [1, 0]] } },
        "sources": [[0.2, 1]], "receivers": [[0.8, 1]],
        "paths": [{ "steps": [], "media": ["air"] }],
        "search": { "max_steps": 1, "refract": false }
    });
    let file = TempFile::with(scene.to_string());
    let run = super::run_bounded(&format!("solve {} --format csv", file.path()), "", None);
    run.assert_refused("--format csv: the scene's `search` arrivals are a table of their own");
    assert!(!run.stderr.contains("  "), "{:?}", run.stderr);
}
