//! Automatic sequences (`search`): the image-source tree of rooms against the complete search
//! of every sequence, one by one; the refusal of searches too large to run.

use eigenray::{Scene, Status, Tracer, search::SearchError};

fn fixture(name: &str) -> serde_json::Value {
    let path = format!(
        "{}/fixtures/pyroomacoustics/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// In the hexagon and the L-shaped room (each wall its own interface, order 4), the search
/// for reflections alone takes the image-source tree, and finds as many paths as
/// pyroomacoustics' image-source model. Allowing refractions too (into the outside, where no
/// medium is: none can happen) sends every sequence through the complete search one by one.
/// Both list the same arrivals: sequences, statuses, times to 1e-12.
#[test]
fn rooms_image_tree_matches_the_sequence_search() {
    for (name, expected) in [("hexagon", 794), ("l_shape", 893)] {
        let mut doc = fixture(name);
        doc["search"] = serde_json::json!({ "max_steps": 4, "refract": false });
        let rooms = Scene::from_json(&doc.to_string()).unwrap();
        doc["search"] = serde_json::json!({ "max_steps": 4 });
        let sequences = Scene::from_json(&doc.to_string()).unwrap();
        let a = Tracer::new(&rooms).unwrap().search().unwrap();
        let b = Tracer::new(&sequences).unwrap().search().unwrap();
        assert_eq!(a.len(), expected, "{name}");
        assert_eq!(a.len(), b.len(), "{name}");
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(
                (x.source, x.receiver, &x.steps, x.arrival.status),
                (y.source, y.receiver, &y.steps, y.arrival.status),
                "{name}"
            );
            let (t, u) = (x.arrival.time, y.arrival.time);
            assert!((t - u).abs() <= 1e-12 * t, "{name}: {t} vs {u}");
            assert!(y.complete);
        }
        assert!(a.iter().all(|x| x.arrival.status == Status::Converged));
        // Ordered by source, receiver, time.
        assert!(a.windows(2).all(|w| {
            (w[0].source, w[0].receiver) < (w[1].source, w[1].receiver)
                || w[0].arrival.time <= w[1].arrival.time
        }));
    }
}

/// A search whose sequences times pairs would exceed the limit is refused before it starts.
#[test]
fn huge_searches_are_refused() {
    let mut doc = fixture("hexagon");
    doc["search"] = serde_json::json!({ "max_steps": 12 });
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    match Tracer::new(&scene).unwrap().search() {
        Err(SearchError::TooLarge { sequences, pairs }) => {
            assert!(sequences > 1_000_000_000 && pairs > 0);
        }
        other => panic!("{other:?}"),
    }
}

/// `eigenray solve` on the hexagon room writes the search's arrivals under `arrivals`: as
/// many as the library's search, in its order, each with its steps in the scene's notation
/// and a time equal to the slowness times the length of its points (recomputed here).
#[test]
fn the_cli_writes_the_arrivals() {
    let path = format!(
        "{}/fixtures/pyroomacoustics/hexagon.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .args(["solve", &path])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let written = doc["arrivals"].as_array().unwrap();
    let scene = Scene::from_json(&fixture("hexagon").to_string()).unwrap();
    let found = Tracer::new(&scene).unwrap().search().unwrap();
    assert_eq!(written.len(), found.len());
    let slowness = scene.media()[0].slowness;
    for (w, f) in written.iter().zip(&found) {
        assert_eq!(w["source"], f.source);
        assert_eq!(w["receiver"], f.receiver);
        assert_eq!(w["status"], "converged");
        let steps: Vec<String> = w["steps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["reflect"].as_str().unwrap().to_string())
            .collect();
        let names: Vec<String> = f
            .steps
            .iter()
            .map(|s| scene.interfaces()[s.interface].name.clone())
            .collect();
        assert_eq!(steps, names);
        let points: Vec<[f64; 2]> = w["points"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()])
            .collect();
        let length: f64 = points
            .windows(2)
            .map(|l| (l[1][0] - l[0][0]).hypot(l[1][1] - l[0][1]))
            .sum();
        let time = w["time"].as_f64().unwrap();
        assert_eq!(time, f.arrival.time);
        assert!((time - slowness * length).abs() <= 1e-14 * time, "{w}");
    }
}
