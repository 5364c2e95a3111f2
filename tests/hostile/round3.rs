//! The third round of hostile input: searches whose arrivals would outgrow memory stop at
//! their documented limit (the bytes of the arrivals with their points, over the whole
//! search), a beam tree stays inside `solver.max_work`, `--ir` writes a response of most of
//! the memory without a second copy, and the two refusals users hit are lifted (a `"media"`
//! reflection in a scene that declares regions; an axisymmetric source on a domain's left
//! edge). Memory cases run the command-line tool under an address-space cap; none asserts a
//! time.

use eigenray::options::{Limits, Run};
use eigenray::search::arrival_bytes;
use eigenray::{Point, Scene, Status, Tracer, Workspace};
use serde_json::{Value, json};

use super::{TempFile, run_capped};

/// Two parallel walls 0.01 apart, source and receiver midway, 0.5 apart: `search`.
fn close_walls(search: Value) -> Value {
    json!({
        "media": { "air": { "speed": 1 } }, "background": "air",
        "interfaces": {
            "floor": { "points": [[-1, 0], [1, 0]] },
            "roof": { "points": [[-1, 0.01], [1, 0.01]] }
        },
        "sources": [[0, 0.005]], "receivers": [[0.5, 0.005]],
        "search": search
    })
}

/// The 312-byte scene of the probe, by `max_time` 1e6 and by `max_steps` 65,536: between the
/// walls every order has paths, so the arrivals' points grow as the square of the order (4.3
/// billion points by order 65,536). Under a 2 GB cap the search stops at its memory limit (a
/// quarter of the memory available) with `complete: false`, and the run succeeds; it aborted
/// before.
#[test]
fn close_walls_stop_at_the_memory_limit_under_a_cap() {
    for search in [json!({ "max_time": 1e6 }), json!({ "max_steps": 65536 })] {
        let file = TempFile::with(close_walls(search.clone()).to_string());
        let run = run_capped(
            2_000_000,
            &format!("solve {} --format jsonl", file.path()),
            "> /dev/null",
            None,
        );
        assert_eq!(run.code, Some(0), "{search}: {}", run.stderr);
        assert!(
            run.stderr.contains("1 pair stopped at a limit"),
            "{search}: {}",
            run.stderr
        );
    }
}

/// The same search in the library with a 4 MB limit: every arrival listed is an image-method
/// path (time `hypot(0.5, 0.01·k)` for `k` reflections), says `complete: false`, and the
/// arrivals' bytes stay within the limit.
#[test]
fn close_walls_list_exact_arrivals_within_the_memory_limit() {
    let scene = Scene::from_json(&close_walls(json!({ "max_time": 1e6 })).to_string()).unwrap();
    let tracer = Tracer::new(scene).unwrap();
    let memory = 4 << 20;
    let mut run = Run::new();
    run.limits = Limits {
        memory,
        ..Limits::default()
    };
    let report = tracer.search(&run).unwrap();
    assert_eq!(report.incomplete_pairs, 1);
    let arrivals = &report.arrivals;
    assert!(arrivals.len() > 100, "{}", arrivals.len());
    let bytes: u64 = arrivals.iter().map(|a| arrival_bytes(a.steps.len())).sum();
    assert!(bytes <= memory, "{bytes} bytes");
    // The next order would not have fitted: the limit, not something else, stopped it.
    let longest = arrivals.iter().map(|a| a.steps.len()).max().unwrap();
    assert!(bytes + arrival_bytes(longest + 1) > memory);
    for a in arrivals {
        assert!(!a.complete);
        let k = a.steps.len() as f64;
        let exact = 0.5f64.hypot(0.01 * k);
        assert!(
            (a.arrival.time - exact).abs() <= 1e-12,
            "{} steps: {} against {exact}",
            a.steps.len(),
            a.arrival.time
        );
    }
}

/// A zigzag wall of 20 segments under a flat wall.
fn zigzag(search: Value, solver: Value) -> Scene {
    let zig: Vec<[f64; 2]> = (0..=20)
        .map(|i| [0.5 * i as f64, if i % 2 == 1 { 0.5 } else { 0.0 }])
        .collect();
    let scene = json!({
        "media": { "air": { "speed": 1 } }, "background": "air",
        "interfaces": {
            "zigzag": { "points": zig },
            "flat": { "points": [[0, 2], [10, 2]] }
        },
        "sources": [[1, 1]], "receivers": [[9, 1.2]],
        "search": search, "solver": solver
    });
    Scene::from_json(&scene.to_string()).unwrap()
}

/// The probe's zigzag search (`vertex`, `max_time` 30) ran for minutes in the beam tree, which
/// counted beams only (2^28 of them, each weighing every segment for occlusion). The tree now
/// counts its work in `solver.max_work`'s units and stops there: within the budget (one
/// child's work over at most), `complete: false`.
#[test]
fn a_zigzag_beam_tree_stays_inside_max_work() {
    for max_work in [1u64 << 17, 1 << 19] {
        let scene = zigzag(
            json!({ "max_time": 30, "vertex": true }),
            json!({ "max_work": max_work }),
        );
        let tracer = Tracer::new(scene).unwrap();
        let report = tracer.search(&Run::new()).unwrap();
        assert_eq!(report.incomplete_pairs, 1);
        assert!(report.arrivals.iter().all(|a| !a.complete));
        let slack = 1000;
        assert!(
            report.tree_work > max_work && report.tree_work <= max_work + slack,
            "{} units against {max_work}",
            report.tree_work
        );
    }
}

/// Ground truth for the budget: a tree stopped by it lists only arrivals of the complete
/// search (the same sequences, times and points), and a budget large enough changes nothing.
#[test]
fn a_beam_tree_stopped_by_its_budget_lists_only_true_arrivals() {
    let search = json!({ "max_steps": 6, "refract": false });
    let full = Tracer::new(zigzag(search.clone(), json!({})))
        .unwrap()
        .search(&Run::new())
        .unwrap();
    assert_eq!(full.incomplete_pairs, 0);
    assert!(full.arrivals.len() > 5, "{}", full.arrivals.len());
    let cut = Tracer::new(zigzag(
        search.clone(),
        json!({ "max_work": full.tree_work / 3 }),
    ))
    .unwrap()
    .search(&Run::new())
    .unwrap();
    assert_eq!(cut.incomplete_pairs, 1);
    assert!(cut.arrivals.len() < full.arrivals.len());
    for a in &cut.arrivals {
        assert!(
            full.arrivals.iter().any(|b| b.steps == a.steps
                && b.arrival.points == a.arrival.points
                && b.arrival.time == a.arrival.time),
            "{a:?}"
        );
    }
    let roomy = Tracer::new(zigzag(search, json!({ "max_work": full.tree_work })))
        .unwrap()
        .search(&Run::new())
        .unwrap();
    // (`residual` is NaN for the tree's paths: compared field by field.)
    let key = |r: &eigenray::search::SearchReport| -> Vec<_> {
        (r.arrivals.iter())
            .map(|a| {
                (
                    a.steps.clone(),
                    a.arrival.points.clone(),
                    a.arrival.time,
                    a.complete,
                )
            })
            .collect()
    };
    assert_eq!(roomy.incomplete_pairs, 0);
    assert_eq!(key(&roomy), key(&full));
}

/// `--ir` of a response array of 300 MB (0.6 of a 500 MB cap) as `.npy` and as `.wav`: the
/// file is written as it is made, not built in a second buffer first (which aborted).
#[test]
fn an_impulse_response_of_most_of_the_memory_is_written() {
    let receivers: Vec<[f64; 2]> = (0..10).map(|i| [3.0 + 0.2 * i as f64, 2.0]).collect();
    let scene = json!({
        "media": { "air": { "speed": 343, "at": [1, 1] } },
        "interfaces": { "room": { "points": [[0, 0], [6, 0], [6, 4], [0, 4]], "closed": true } },
        "sources": [[1, 1]], "receivers": receivers,
        "search": { "max_steps": 2 },
        "amplitudes": { "source": "point" },
        "impulse_response": { "rate": 48000, "duration": 78.125 }
    });
    let file = TempFile::with(scene.to_string());
    for (ext, bytes) in [("npy", 300_000_000u64), ("wav", 150_000_000)] {
        let out = TempFile::with("");
        let path = format!("{}.{ext}", out.path());
        let run = run_capped(
            500_000,
            &format!("solve {} --ir {path}", file.path()),
            "> /dev/null",
            None,
        );
        let size = std::fs::metadata(&path).map(|m| m.len());
        let _ = std::fs::remove_file(&path);
        assert_eq!(run.code, Some(0), "{ext}: {}", run.stderr);
        let size = size.unwrap();
        assert!(size >= bytes && size < bytes + 4096, "{ext}: {size} bytes");
    }
}

/// Water over sediment (each with an `at`), a `"media"` bottom and a path that gives its
/// media: accepted (it was refused), with the Rayleigh coefficient computed here from the
/// geometry. Without any declared region the scene is still refused, naming the key.
#[test]
fn a_media_reflection_in_a_scene_with_regions_takes_the_medium_across() {
    let mut doc = json!({
        "media": {
            "water": { "speed": 1500, "density": 1000, "at": [0, -50] },
            "sediment": { "speed": 1700, "density": 1800, "at": [0, -150] }
        },
        "domain": [[-1000, -300], [1000, 10]],
        "interfaces": { "bottom": { "points": [[-1000, -100], [1000, -100]], "reflection": "media" } },
        "sources": [[0, -20]], "receivers": [[150, -40]],
        "paths": [{ "steps": [{ "reflect": "bottom" }], "media": ["water", "water"] }],
        "amplitudes": { "source": "point" }
    });
    let tracer = Tracer::new(Scene::from_json(&doc.to_string()).unwrap()).unwrap();
    let mut ws = Workspace::new();
    let mut amplitude = None;
    let record = tracer.solve_with_amplitude(
        Point::new(0.0, -20.0),
        Point::new(150.0, -40.0),
        0,
        &mut ws,
        &mut amplitude,
    );
    assert_eq!(record.status, Status::Converged);
    // The image method: the bounce at x = 150·80/140 on y = −100.
    let (dx, dz): (f64, f64) = (150.0, 80.0 + 60.0);
    let cos1 = dz / dx.hypot(dz);
    let sin1 = dx / dx.hypot(dz);
    let (z1, z2) = (1000.0 * 1500.0, 1800.0 * 1700.0);
    let sin2 = sin1 * 1700.0 / 1500.0;
    assert!(sin2 < 1.0);
    let cos2 = (1.0 - sin2 * sin2).sqrt();
    let rayleigh = (z2 * cos1 - z1 * cos2) / (z2 * cos1 + z1 * cos2);
    let c = amplitude.expect("an amplitude").coefficient;
    assert!(
        (c.re - rayleigh).abs() <= 1e-12 && c.im.abs() <= 1e-12,
        "{c} against {rayleigh}"
    );
    // No `background`, `at` or `domain`: refused, naming the interface's reflection.
    doc["media"]["water"].as_object_mut().unwrap().remove("at");
    doc["media"]["sediment"]
        .as_object_mut()
        .unwrap()
        .remove("at");
    doc.as_object_mut().unwrap().remove("domain");
    let e = Scene::from_json(&doc.to_string()).unwrap_err();
    assert_eq!(e.key, "interfaces.bottom.reflection", "{e}");
}

/// An axisymmetric shallow-water scene whose domain starts at the axis x = 0, the source on
/// it: accepted (it was refused as lying on the domain's edge), the source in the water on
/// its right, and every arrival (times, points, amplitudes) the same, to round-off, as with
/// the domain and the interfaces reaching beyond the axis.
#[test]
fn an_axisymmetric_source_on_the_domains_edge_is_in_the_medium_on_its_right() {
    let doc = |left: f64| {
        json!({
            "media": {
                "water": { "speed": 1500, "density": 1, "at": [100, -50] },
                "bottom": { "speed": 1700, "density": 1.8, "at": [100, -150] }
            },
            "domain": [[left, -200], [5000, 0]],
            "interfaces": {
                "surface": { "points": [[left, 0], [5000, 0]], "reflection": "pressure-release" },
                "seabed": { "points": [[left, -100], [5000, -100]], "reflection": "media" }
            },
            "sources": [[0, -25]], "receivers": [[1000, -30], [3000, -80]],
            "search": { "max_steps": 4, "refract": false },
            "amplitudes": { "source": "axisymmetric", "frequency": 100 }
        })
    };
    let arrivals = |left: f64| {
        let scene = Scene::from_json(&doc(left).to_string()).unwrap_or_else(|e| panic!("{e}"));
        Tracer::new(scene)
            .unwrap()
            .search(&Run::new())
            .unwrap()
            .arrivals
    };
    let on_axis = arrivals(0.0);
    let beyond = arrivals(-10.0);
    assert!(on_axis.len() >= 10, "{}", on_axis.len());
    assert!(
        on_axis
            .iter()
            .all(|a| a.arrival.media.iter().all(|&m| m == 1))
    );
    assert_eq!(on_axis.len(), beyond.len());
    for (a, b) in on_axis.iter().zip(&beyond) {
        // The walls start at another point: the same paths to round-off.
        assert_eq!(a.steps, b.steps);
        assert!((a.arrival.time - b.arrival.time).abs() <= 1e-12 * b.arrival.time);
        for (p, q) in a.arrival.points.iter().zip(&b.arrival.points) {
            assert!(p.distance(*q) <= 1e-9, "{p:?} against {q:?}");
        }
        let (x, y) = (a.arrival.amplitude.unwrap(), b.arrival.amplitude.unwrap());
        assert!(
            (x.value - y.value).norm() <= 1e-9 * y.value.norm(),
            "{x:?} against {y:?}"
        );
    }
    // A source off the axis on that edge is still refused.
    let mut off = doc(0.0);
    off["amplitudes"]["source"] = json!("point");
    let e = Scene::from_json(&off.to_string()).unwrap_err();
    assert_eq!(e.key, "sources[0]", "{e}");
}

/// A receiver grid solves as the list of its points (written out as `numpy.linspace` gives
/// them), ray for ray; a bad grid is refused naming its key, exit 2.
#[test]
fn a_receiver_grid_solves_as_its_list_of_points() {
    let grid = json!({
        "media": { "air": { "speed": 1 } },
        "interfaces": { "mirror": { "points": [[-10, 0], [10, 0]] } },
        "sources": [[0, 1]],
        "receivers": { "grid": { "x": [0.1, 0.7, 4], "y": [2, 1, 3] } },
        "paths": [{ "steps": [{ "reflect": "mirror" }], "media": ["air", "air"] }]
    });
    let mut list = grid.clone();
    // numpy.linspace(0.1, 0.7, 4) and numpy.linspace(2, 1, 3), x-major.
    let (xs, ys) = ([0.1, 0.3, 0.5, 0.7], [2.0, 1.5, 1.0]);
    list["receivers"] = json!(
        xs.iter()
            .flat_map(|&x| ys.iter().map(move |&y| [x, y]))
            .collect::<Vec<_>>()
    );
    let solve = |doc: &Value| {
        let file = TempFile::with(doc.to_string());
        let run = run_capped(4_000_000, &format!("solve {}", file.path()), "", None);
        assert_eq!(run.code, Some(0), "{}", run.stderr);
        run.stdout
    };
    let (a, b) = (solve(&grid), solve(&list));
    assert_eq!(a, b);
    let rays: Value = serde_json::from_slice(&a).unwrap();
    assert_eq!(rays["rays"].as_array().unwrap().len(), 12);
    let mut bad = grid.clone();
    bad["receivers"]["grid"]["y"] = json!([2, 1, 0]);
    let file = TempFile::with(bad.to_string());
    run_capped(4_000_000, &format!("solve {}", file.path()), "", None)
        .assert_refused("receivers.grid.y");
}

/// A 250 MiB scene of one polyline of 10.5 million vertices under a 4 GB cap: read, validated
/// and solved (3.5 GB at its peak). It aborted at 3.7 GB: the command-line tool held the
/// scene twice, its own and the tracer's copy; it now shares one.
#[test]
fn a_polyline_of_250_mib_is_solved_under_a_4_gb_cap() {
    let n = 10_500_000;
    let mut text = String::with_capacity(25 * n + 300);
    text.push_str(r#"{"media":{"air":{"speed":1}},"interfaces":{"long":{"points":["#);
    for i in 0..n {
        use std::fmt::Write;
        let sep = if i == 0 { "" } else { "," };
        let _ = write!(
            text,
            "{sep}[{:.7},{:.7}]",
            i as f64 * 0.001,
            (i % 2) as f64 * 0.0005
        );
    }
    text.push_str(
        r#"]}},"sources":[[1.0,1.0]],"receivers":[[2.0,1.0]],
        "paths":[{"steps":[{"reflect":"long"}],"media":["air","air"]}]}"#,
    );
    assert!(text.len() > 245 << 20, "{} bytes", text.len());
    let file = TempFile::with(&text);
    drop(text);
    let run = run_capped(4_000_000, &format!("solve {}", file.path()), "", None);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let out: Value = serde_json::from_slice(&run.stdout).unwrap();
    let rays = out["rays"].as_array().unwrap();
    assert_eq!(rays.len(), 1);
    // A path off the saw-tooth (between y = 0 and 0.0005) between the two points, 1 apart
    // at height 1: no shorter than the mirror image off the line y = 0.0005 gives.
    let status = rays[0]["status"].as_str().unwrap();
    assert!(status == "converged" || status == "vertex", "{}", rays[0]);
    let time = rays[0]["time"].as_f64().unwrap();
    assert!(time >= 1f64.hypot(2.0 * 0.9995) - 1e-12, "{}", rays[0]);
}
