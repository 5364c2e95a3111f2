//! No false proofs: `no_path` only where no path exists. Near-degenerate paths that a
//! threshold once ruled out (a grazing reflection, a slab thinner than the vanishing
//! threshold, a reflection exactly at an open end) are found, or reported `not_converged`
//! with the rule that decided, in both modes, through the library and the command line.

use eigenray::trace::Threshold;
use eigenray::{Point, Reason, Scene, Status, Tracer, Workspace};
use serde_json::{Value, json};

use super::solve_file;

/// One path of `steps` (media given) from `source` to `receiver` between the `interfaces`.
fn scene(interfaces: Value, steps: Value, media: Value, ends: [[f64; 2]; 2]) -> Value {
    json!({
        "media": { "air": { "speed": 1.0 }, "glass": { "speed": 0.5 } },
        "interfaces": interfaces,
        "sources": [ends[0]], "receivers": [ends[1]],
        "paths": [{ "steps": steps, "media": media }]
    })
}

/// A mirror `[[-4, 0], [4, 0]]` grazed by a ray from 1e-10 above it to 1e-10 above it: the
/// path through (0, 0), time 6.
fn grazing() -> Value {
    scene(
        json!({ "mirror": { "points": [[-4.0, 0.0], [4.0, 0.0]] } }),
        json!([{ "reflect": "mirror" }]),
        json!(["air", "air"]),
        [[-3.0, 1e-10], [3.0, 1e-10]],
    )
}

/// A slab of glass 1e-12 thick, refracted through.
fn thin_slab() -> Value {
    scene(
        json!({ "top": { "points": [[-4.0, 0.0], [4.0, 0.0]] },
                "bottom": { "points": [[-4.0, -1e-12], [4.0, -1e-12]] } }),
        json!([{ "refract": "top" }, { "refract": "bottom" }]),
        json!(["air", "glass", "air"]),
        [[-1.0, 1.0], [1.0, -1.0]],
    )
}

/// A mirror ending at (0, 0), where the specular point of the ray is.
fn open_end() -> Value {
    scene(
        json!({ "mirror": { "points": [[-4.0, 0.0], [0.0, 0.0]] } }),
        json!([{ "reflect": "mirror" }]),
        json!(["air", "air"]),
        [[-1.0, 1.0], [1.0, 1.0]],
    )
}

/// `scene` with `"solver": {"stationary": "all"}`.
fn all(mut scene: Value) -> Value {
    scene["solver"] = json!({ "stationary": "all" });
    scene
}

/// The default mode's ray and every stationary path of the scene's one triple, by the
/// library.
fn library(scene: &Value) -> (eigenray::RayRecord, Vec<eigenray::Arrival>, bool) {
    let scene = Scene::from_json(&scene.to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let (s, r) = (scene.sources()[0], scene.receivers()[0]);
    let ray = tracer.solve(s, r, 0, &mut Workspace::new());
    let mut arrivals = Vec::new();
    let search = tracer
        .stationary_paths(s, r, 0, &eigenray::options::Run::new(), &mut arrivals)
        .unwrap();
    (ray, arrivals, search.complete)
}

/// The rays of `eigenray solve` on `scene`.
fn cli(scene: &Value) -> Vec<Value> {
    let run = solve_file(&scene.to_string());
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let out: Value = serde_json::from_slice(&run.stdout).unwrap();
    out["rays"].as_array().unwrap().clone()
}

/// The grazing reflection is found in both modes: time 6 through (0, 0). (It was
/// `no_path`: the legs, 3.3e-11 rad off the mirror, counted as on neither side of it.)
#[test]
fn a_grazing_reflection_is_found() {
    let (ray, arrivals, complete) = library(&grazing());
    assert_eq!(ray.status, Status::Converged, "{ray:?}");
    assert!((ray.time - 6.0).abs() <= 1e-15 * 6.0, "{ray:?}");
    assert!(complete);
    assert_eq!(arrivals.len(), 1, "{arrivals:?}");
    assert_eq!(arrivals[0].status, Status::Converged);
    assert!((arrivals[0].points[1] - Point::new(0.0, 0.0)).length() <= 1e-12);
    for scene in [grazing(), all(grazing())] {
        let rays = cli(&scene);
        assert_eq!(rays.len(), 1);
        assert_eq!(rays[0]["status"], "converged", "{rays:?}");
        assert!((rays[0]["time"].as_f64().unwrap() - 6.0).abs() <= 1e-14);
    }
}

/// A 1e-12 slab: the path exists, but its middle leg is below the vanishing threshold, so
/// no mode may call it a proof of no path: `not_converged`, the reason naming the rule, and
/// `complete: false`. (It was `no_path`, "a complete search … found no stationary path".)
#[test]
fn a_slab_thinner_than_the_threshold_is_not_a_proof() {
    let (ray, arrivals, complete) = library(&thin_slab());
    let undecided = Some(Reason::Undecided {
        rule: Threshold::VanishedLeg,
    });
    assert_eq!((ray.status, ray.reason), (Status::NotConverged, undecided));
    assert!(arrivals.is_empty() && !complete);
    for scene in [thin_slab(), all(thin_slab())] {
        let rays = cli(&scene);
        assert_eq!(rays.len(), 1);
        assert_eq!(rays[0]["status"], "not_converged", "{rays:?}");
        let reason = rays[0]["reason"].as_str().unwrap();
        assert!(
            reason.contains("not a proof") && reason.contains("1e-12"),
            "{reason}"
        );
    }
    assert_eq!(cli(&all(thin_slab()))[0]["complete"], false);
}

/// A reflection exactly at an open end is one path in both modes, `converged` at (0, 0).
/// (It was `converged` by default and `no_path` under `"all"`.) Just beyond the end, none.
#[test]
fn a_reflection_at_an_open_end_is_a_path_in_both_modes() {
    let (ray, arrivals, complete) = library(&open_end());
    assert_eq!(ray.status, Status::Converged, "{ray:?}");
    assert!(complete);
    assert_eq!(arrivals.len(), 1, "{arrivals:?}");
    assert_eq!(arrivals[0].status, Status::Converged);
    assert!((arrivals[0].time - ray.time).abs() <= 1e-15);
    assert_eq!(arrivals[0].points[1], Point::new(0.0, 0.0));
    for scene in [open_end(), all(open_end())] {
        let rays = cli(&scene);
        assert_eq!(rays.len(), 1);
        assert_eq!(rays[0]["status"], "converged", "{rays:?}");
    }
    // The receiver moved so that the specular point lies 1e-6 beyond the end: no path, a
    // proof in both modes.
    let mut beyond = open_end();
    beyond["receivers"] = json!([[1.000002, 1.0]]);
    let (ray, arrivals, complete) = library(&beyond);
    assert_eq!(ray.status, Status::NoPath, "{ray:?}");
    assert!(arrivals.is_empty() && complete);
}

/// Every `no_path` of these scenes and their neighbours (the ends moved by 1e-14 … 1e-6)
/// is a proof in the sense the search gives it: `complete`, with no rule of a threshold.
#[test]
fn near_degenerate_neighbours_never_give_a_false_no_path() {
    for base in [grazing(), thin_slab(), open_end()] {
        for dy in [0.0, 1e-14, -1e-14, 1e-10, 1e-8, 1e-6] {
            let mut scene = base.clone();
            let r = scene["receivers"][0][1].as_f64().unwrap();
            scene["receivers"] = json!([[scene["receivers"][0][0], r + dy]]);
            let (ray, arrivals, complete) = library(&scene);
            if ray.status == Status::NoPath {
                assert!(arrivals.is_empty() && complete, "{scene}: {arrivals:?}");
            }
            if arrivals.is_empty() && complete {
                assert_ne!(ray.status, Status::Converged, "{scene}");
            }
        }
    }
}

/// The same exactly at an interior vertex: between two segments on one line it is the one
/// `converged` path (it was `no_path` under `"all"`: neither segment held it strictly inside,
/// and the vertex is no kink); where the second segment bends away, the one `vertex` path
/// both modes give.
#[test]
fn a_reflection_exactly_at_a_vertex_is_one_path_in_both_modes() {
    for (far, status) in [(0.0, Status::Converged), (-1.0, Status::Vertex)] {
        let scene = scene(
            json!({ "mirror": { "points": [[-4.0, 0.0], [0.0, 0.0], [4.0, far]] } }),
            json!([{ "reflect": "mirror" }]),
            json!(["air", "air"]),
            [[-1.0, 1.0], [1.0, 1.0]],
        );
        let (ray, arrivals, complete) = library(&scene);
        assert_eq!(ray.status, status, "{ray:?}");
        assert!(complete);
        assert_eq!(arrivals.len(), 1, "{arrivals:?}");
        assert_eq!(arrivals[0].status, status);
        assert_eq!(arrivals[0].points[1], Point::new(0.0, 0.0));
    }
}

/// A receiver exactly on an interface: the direct path is the one arrival. The reflection
/// and the refraction there collapse onto it (their last leg vanishes), so they are no path
/// of their own sequences, saying why, in both modes (they were `converged` with the direct
/// path's time: an echogram counted one arrival three times); the reflection's `no_path` is
/// a proof, the refraction's solve stalls next to its collapse and says that a threshold
/// decided. 1e-13 above the mirror the reflection is below the vanishing threshold: not a
/// proof.
#[test]
fn a_receiver_on_an_interface_is_reached_once() {
    let paths = json!([
        { "steps": [], "media": ["air"] },
        { "steps": [{ "reflect": "sea" }], "media": ["air", "air"] },
        { "steps": [{ "refract": "sea" }], "media": ["air", "glass"] }
    ]);
    let mut doc = scene(
        json!({ "sea": { "points": [[-10.0, 0.0], [10.0, 0.0]] } }),
        json!([]),
        json!(["air"]),
        [[0.0, 1.0], [3.0, 0.0]],
    );
    doc["paths"] = paths;
    for doc in [doc.clone(), all(doc.clone())] {
        let rays = cli(&doc);
        let converged: Vec<&Value> = rays.iter().filter(|r| r["status"] == "converged").collect();
        assert_eq!(converged.len(), 1, "{rays:?}");
        assert_eq!(converged[0]["path"], 0);
        let reflected = rays.iter().find(|r| r["path"] == 1).unwrap();
        assert_eq!(reflected["status"], "no_path", "{reflected}");
        if reflected.get("complete").is_some() {
            assert_eq!(reflected["complete"], true);
        }
        // The refraction into the glass stalls next to its collapse: by a threshold, so not
        // a proof, and not an arrival.
        let refracted = rays.iter().find(|r| r["path"] == 2).unwrap();
        assert!(
            ["no_path", "not_converged"].contains(&refracted["status"].as_str().unwrap()),
            "{refracted}"
        );
    }
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let (s, r) = (scene.sources()[0], scene.receivers()[0]);
    let ray = tracer.solve(s, r, 1, &mut Workspace::new());
    assert_eq!(ray.reason, Some(Reason::AtEnd { step: 0 }), "{ray:?}");
    let mut arrivals = Vec::new();
    let search = tracer
        .stationary_paths(s, r, 1, &eigenray::options::Run::new(), &mut arrivals)
        .unwrap();
    assert!(arrivals.is_empty() && search.complete);
    // Just above the mirror the two legs' collapse is a threshold's decision.
    let above = Point::new(3.0, 1e-13);
    let search = tracer
        .stationary_paths(s, above, 1, &eigenray::options::Run::new(), &mut arrivals)
        .unwrap();
    assert!(search.complete || search.undecided == Some(Threshold::VanishedLeg));
    if search.complete {
        assert_eq!(arrivals.len(), 1, "{arrivals:?}");
    }
}
