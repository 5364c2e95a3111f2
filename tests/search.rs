//! Automatic sequences (`search`): the beam tree of rooms against the complete search of every
//! sequence, one by one; rooms drawn as one polyline against one interface per wall; `max_time`
//! against `max_steps`; every search option; limits on the work and the refusal of what
//! cannot fit in memory.

use eigenray::options::Run;
use eigenray::scene::StepKind;
use eigenray::search::SearchArrival;
use eigenray::{Scene, Status, Tracer};
use serde_json::{Value, json};

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
        let a = Tracer::new(&rooms)
            .unwrap()
            .search(&eigenray::options::Run::new())
            .unwrap()
            .arrivals;
        let b = Tracer::new(&sequences)
            .unwrap()
            .search(&eigenray::options::Run::new())
            .unwrap()
            .arrivals;
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

/// The comb-shaped room of pyroomacoustics issue #383: 12 walls, counter-clockwise.
const COMB: [[f64; 2]; 12] = [
    [0.0, 0.0],
    [0.0, 5.0],
    [1.0, 5.0],
    [1.0, 2.0],
    [2.0, 2.0],
    [2.0, 5.0],
    [3.0, 5.0],
    [3.0, 0.0],
    [2.0, 0.0],
    [2.0, 1.0],
    [1.0, 1.0],
    [1.0, 0.0],
];

/// A room with corners `corners` in air (343 m/s), as one interface per wall (`w00`, `w01`,
/// …: names in wall order) or as one closed polyline `room`, with `search`.
fn room(
    corners: &[[f64; 2]],
    polyline: bool,
    sources: Value,
    receivers: Value,
    search: Value,
) -> Scene {
    let n = corners.len();
    let interfaces: serde_json::Map<String, Value> = if polyline {
        [(
            "room".to_string(),
            json!({ "points": corners, "closed": true }),
        )]
        .into_iter()
        .collect()
    } else {
        (0..n)
            .map(|i| {
                (
                    format!("w{i:02}"),
                    json!({ "points": [corners[i], corners[(i + 1) % n]] }),
                )
            })
            .collect()
    };
    let at = sources[0].clone();
    let doc = json!({
        "media": { "air": { "speed": 343.0, "at": at } },
        "interfaces": interfaces,
        "sources": sources,
        "receivers": receivers,
        "search": search,
    });
    Scene::from_json(&doc.to_string()).unwrap()
}

/// The corners of a fixture room whose walls are its interfaces in order.
fn corners_of(name: &str) -> Vec<[f64; 2]> {
    let doc = fixture(name);
    let mut walls: Vec<(&String, &Value)> = doc["interfaces"].as_object().unwrap().iter().collect();
    walls.sort_by_key(|(k, _)| k[1..].parse::<usize>().unwrap());
    walls
        .iter()
        .map(|(_, w)| {
            [
                w["points"][0][0].as_f64().unwrap(),
                w["points"][0][1].as_f64().unwrap(),
            ]
        })
        .collect()
}

/// Whether two arrivals are the same, to the bit (the image method's residual is NaN).
fn same(x: &SearchArrival, y: &SearchArrival) -> bool {
    let (a, b) = (&x.arrival, &y.arrival);
    (x.source, x.receiver, &x.steps, x.complete) == (y.source, y.receiver, &y.steps, y.complete)
        && (
            a.status,
            a.time.to_bits(),
            &a.points,
            &a.segments,
            &a.media,
            a.reason,
        ) == (
            b.status,
            b.time.to_bits(),
            &b.points,
            &b.segments,
            &b.media,
            b.reason,
        )
        && a.parameters
            .iter()
            .map(|p| p.to_bits())
            .eq(b.parameters.iter().map(|p| p.to_bits()))
}

/// Asserts that two lists of arrivals are the same, naming the first that differs.
fn assert_same(a: &[SearchArrival], b: &[SearchArrival], what: &str) {
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            same(x, y),
            "{what}: arrival {i} of {} and {}: {x:?} vs {y:?}",
            a.len(),
            b.len()
        );
    }
    assert_eq!(
        a.len(),
        b.len(),
        "{what}: {:?}",
        a.get(b.len()).or(b.get(a.len()))
    );
}

fn search(scene: &Scene) -> Vec<SearchArrival> {
    Tracer::new(scene)
        .unwrap()
        .search(&eigenray::options::Run::new())
        .unwrap()
        .arrivals
}

/// Nine listeners spread over the comb room.
fn comb_listeners() -> Value {
    json!([
        [2.5, 4.5],
        [0.5, 4.5],
        [0.5, 2.5],
        [2.5, 2.5],
        [2.5, 0.5],
        [1.5, 1.5],
        [0.25, 1.25],
        [2.75, 3.75],
        [1.25, 1.75]
    ])
}

/// A room drawn as one closed polyline and the same room drawn as one interface per wall give
/// the same arrivals, bit for bit (times and points), the polyline's segment `i` standing for
/// wall `i`: the comb room (order 8, nine listeners), pyroomacoustics' hexagon and L-shaped
/// room (order 6), and with `max_time` instead of `max_steps`. The comb room's dyadic
/// listeners meet corners exactly: a corner where two walls drawn apart end is no free end of
/// either (no reflection lies there), as the polyline's vertex is none.
#[test]
fn one_polyline_gives_the_arrivals_of_one_interface_per_wall() {
    let hexagon = fixture("hexagon");
    let l_shape = fixture("l_shape");
    let cases = [
        (
            COMB.to_vec(),
            json!([[0.5, 0.5]]),
            comb_listeners(),
            json!({ "max_steps": 8 }),
        ),
        (
            COMB.to_vec(),
            json!([[0.5, 0.5], [2.5, 4.5]]),
            comb_listeners(),
            json!({ "max_time": 0.05 }),
        ),
        (
            corners_of("hexagon"),
            hexagon["sources"].clone(),
            hexagon["receivers"].clone(),
            json!({ "max_steps": 6 }),
        ),
        (
            corners_of("l_shape"),
            l_shape["sources"].clone(),
            l_shape["receivers"].clone(),
            json!({ "max_steps": 6, "obstructed": true }),
        ),
    ];
    for (corners, sources, receivers, options) in cases {
        let walls = search(&room(
            &corners,
            false,
            sources.clone(),
            receivers.clone(),
            options.clone(),
        ));
        let polyline = search(&room(&corners, true, sources, receivers, options.clone()));
        assert!(walls.len() > 20, "{options}: {} arrivals", walls.len());
        assert!(walls.iter().any(|a| a.steps.len() >= 5), "{options}");
        assert_eq!(walls.len(), polyline.len(), "{options}");
        for (a, b) in walls.iter().zip(&polyline) {
            assert_eq!((a.source, a.receiver), (b.source, b.receiver));
            assert_eq!(
                a.arrival.time.to_bits(),
                b.arrival.time.to_bits(),
                "{options}"
            );
            assert_eq!(a.arrival.points, b.arrival.points, "{options}");
            assert_eq!(a.arrival.status, b.arrival.status);
            let wall: Vec<usize> = a.steps.iter().map(|s| s.interface).collect();
            assert_eq!(wall, b.arrival.segments, "{options}");
            assert!(
                b.steps
                    .iter()
                    .all(|s| s.interface == 0 && s.kind == StepKind::Reflect)
            );
            assert!(a.complete && b.complete);
        }
    }
}

/// `max_time` T lists exactly the arrivals of a deep `max_steps` search whose time is at most
/// T: the comb room (T = 0.06 s: the deepest arrival has far fewer than 40 steps) and the
/// L-shaped room; with both keys, both bounds hold.
#[test]
fn max_time_gives_the_arrivals_of_max_steps_up_to_that_time() {
    let l_shape = fixture("l_shape");
    let cases = [
        (COMB.to_vec(), json!([[0.5, 0.5]]), comb_listeners(), 0.06),
        (
            corners_of("l_shape"),
            l_shape["sources"].clone(),
            l_shape["receivers"].clone(),
            0.05,
        ),
    ];
    for (corners, sources, receivers, t) in cases {
        for polyline in [false, true] {
            let make = |o: Value| room(&corners, polyline, sources.clone(), receivers.clone(), o);
            let by_time = search(&make(json!({ "max_time": t })));
            let deepest = by_time.iter().map(|a| a.steps.len()).max().unwrap();
            assert!((8..30).contains(&deepest), "{deepest} steps");
            // Deep enough: the deepest arrival by T has far fewer steps.
            let k = 30;
            let mut by_steps = search(&make(json!({ "max_steps": k })));
            assert!(by_steps.iter().all(|a| a.complete));
            assert!(deepest + 8 <= k, "{deepest} steps");
            by_steps.retain(|a| a.arrival.time <= t);
            assert_same(&by_time, &by_steps, &format!("T = {t}"));
            let both = search(&make(json!({ "max_time": t, "max_steps": 6 })));
            let expected: Vec<_> = by_time
                .iter()
                .filter(|a| a.steps.len() <= 6)
                .cloned()
                .collect();
            assert!(expected.len() < by_time.len());
            assert_same(&both, &expected, "both");
        }
    }
}

/// `vertex`: off by default (every arrival `converged`), on it adds the corner-held arrivals
/// of the polyline (found by the complete search of each sequence) and keeps the converged
/// ones the same. `obstructed` adds obstructed arrivals; `interfaces` keeps the steps to those
/// listed.
#[test]
fn vertex_obstructed_and_interfaces_each_change_what_is_listed() {
    let make = |o: Value| {
        room(
            &COMB,
            true,
            json!([[0.5, 0.5]]),
            json!([[2.5, 4.5], [0.5, 2.5]]),
            o,
        )
    };
    let plain = search(&make(json!({ "max_steps": 3 })));
    assert!(
        plain
            .iter()
            .all(|a| a.arrival.status == Status::Converged && a.complete)
    );
    // The comb's corner-held candidates include a retro-reflection along y = 2 between the
    // vertices (1, 2) and (2, 2) off the wall x = 0: its leg along the line of a segment is on
    // neither side by a threshold, not by an exact test, so these pairs say `complete: false`
    // (no false proof); what they list is the same.
    let vertex = search(&make(json!({ "max_steps": 3, "vertex": true })));
    assert!(vertex.iter().all(|a| !a.complete));
    let vertices = vertex
        .iter()
        .filter(|a| a.arrival.status == Status::Vertex)
        .count();
    assert!(vertices > 0, "{vertex:?}");
    let converged: Vec<_> = vertex
        .iter()
        .filter(|a| a.arrival.status == Status::Converged)
        .map(|a| SearchArrival {
            complete: true,
            ..a.clone()
        })
        .collect();
    assert_same(&converged, &plain, "vertex");
    assert!(
        vertex
            .iter()
            .all(|a| matches!(a.arrival.status, Status::Converged | Status::Vertex))
    );
    let obstructed = search(&make(json!({ "max_steps": 3, "obstructed": true })));
    assert!(
        obstructed
            .iter()
            .any(|a| a.arrival.status == Status::Obstructed)
    );
    let clear: Vec<_> = obstructed
        .iter()
        .filter(|a| a.arrival.status != Status::Obstructed)
        .cloned()
        .collect();
    assert_same(&clear, &plain, "obstructed");
    // Walls 0 and 1 (w00, w01) alone.
    let walls = |o: Value| room(&COMB, false, json!([[0.5, 0.5]]), json!([[0.5, 2.5]]), o);
    let all = search(&walls(json!({ "max_steps": 3 })));
    let some = search(&walls(
        json!({ "max_steps": 3, "interfaces": ["w00", "w11"] }),
    ));
    assert!(some.len() > 1 && some.len() < all.len());
    assert!(some.iter().all(|a| {
        a.steps
            .iter()
            .all(|s| s.interface == 0 || s.interface == 11)
    }));
    assert!(some.iter().all(|a| all.iter().any(|b| same(a, b))));
}

/// Reflect-only and refract-only searches over a bent interface between two media list only
/// steps of their kind, and each finds some; a room with one bent wall among one-segment walls
/// gives the same arrivals with refractions allowed (the outside has no medium: none can
/// happen) and without.
#[test]
fn reflect_and_refract_choose_the_steps() {
    let doc = |search: Value| {
        json!({
            "domain": [[-20, -10], [20, 10]],
            "media": { "air": { "speed": 343.0, "at": [0.0, 5.0] },
                       "water": { "speed": 1500.0, "at": [0.0, -5.0] } },
            "interfaces": {
                "surface": { "points": [[-20, 0], [-5, 0.5], [5, -0.5], [20, 0]] },
                "bottom": { "points": [[-20, -10], [20, -10]] }
            },
            "sources": [[0.0, 5.0]],
            "receivers": [[8.0, 3.0], [6.0, -4.0]],
            "search": search
        })
    };
    let run = |search: Value| {
        let scene = Scene::from_json(&doc(search).to_string()).unwrap();
        Tracer::new(&scene)
            .unwrap()
            .search(&eigenray::options::Run::new())
            .unwrap()
            .arrivals
    };
    let reflect = run(json!({ "max_steps": 2, "refract": false }));
    let refract = run(json!({ "max_steps": 2, "reflect": false }));
    let both = run(json!({ "max_steps": 3 }));
    let kinds = |a: &[SearchArrival], k: StepKind| {
        a.iter()
            .flat_map(|x| &x.steps)
            .filter(|s| s.kind == k)
            .count()
    };
    assert!(kinds(&reflect, StepKind::Reflect) > 0 && kinds(&reflect, StepKind::Refract) == 0);
    assert!(kinds(&refract, StepKind::Refract) > 0 && kinds(&refract, StepKind::Reflect) == 0);
    // Refracted into the water and reflected off the bottom: a sequence of both kinds.
    assert!(both.iter().any(|a| {
        a.steps.iter().any(|s| s.kind == StepKind::Reflect)
            && a.steps.iter().any(|s| s.kind == StepKind::Refract)
    }));
    for a in refract.iter().chain(&reflect) {
        assert!(both.iter().any(|b| same(a, b)), "{a:?}");
    }
    // A room: a square with its top wall bent (three segments).
    let corners = json!({
        "s": { "points": [[0, 0], [4, 0]] }, "e": { "points": [[4, 0], [4, 3]] },
        "n": { "points": [[4, 3], [3, 3.5], [1, 3.25], [0, 3]] }, "w": { "points": [[0, 3], [0, 0]] }
    });
    let room = |search: Value| {
        let d = json!({
            "media": { "air": { "speed": 343.0, "at": [1.0, 1.0] } },
            "interfaces": corners, "sources": [[1.0, 1.0]], "receivers": [[3.0, 2.0], [0.5, 2.5]],
            "search": search
        });
        Tracer::new(Scene::from_json(&d.to_string()).unwrap())
            .unwrap()
            .search(&eigenray::options::Run::new())
            .unwrap()
            .arrivals
    };
    let with = room(json!({ "max_steps": 4 }));
    let without = room(json!({ "max_steps": 4, "refract": false }));
    assert!(with.len() > 30);
    assert!(
        with.iter()
            .any(|a| a.arrival.segments.contains(&1) && a.steps.iter().any(|s| s.interface == 1))
    );
    assert_same(&with, &without, "refract");
}

/// A search stopped at its limit of beams says `complete: false` on every arrival of the pairs
/// it left short, and lists no more than a complete search; within the limits, `complete`.
#[test]
fn a_work_limit_gives_incomplete_pairs() {
    let scene = room(
        &COMB,
        true,
        json!([[0.5, 0.5]]),
        comb_listeners(),
        json!({ "max_steps": 12 }),
    );
    let tracer = Tracer::new(&scene).unwrap();
    let full = tracer.search(&Run::new()).unwrap();
    assert_eq!(full.incomplete_pairs, 0);
    assert!(full.beams > 1000);
    let mut run = Run::new();
    run.limits.beams = full.beams / 10;
    let short = tracer.search(&run).unwrap();
    assert_eq!(short.incomplete_pairs, 9);
    assert!(short.beams <= run.limits.beams);
    assert!(short.arrivals.iter().all(|a| !a.complete));
    assert!(short.arrivals.len() < full.arrivals.len());
    for a in &short.arrivals {
        let mut b = a.clone();
        b.complete = true;
        assert!(full.arrivals.iter().any(|c| same(&b, c)));
    }
    let mut run = Run::new();
    run.limits.arrivals = 5;
    let few = tracer.search(&run).unwrap();
    assert!(few.arrivals.len() <= 5 && few.incomplete_pairs > 0);
}

/// A search whose table of pairs alone cannot fit in the memory the process may use is refused
/// before it starts, naming the pairs (here 2^32 pairs under an address-space limit of 2 GB).
#[test]
fn a_search_that_cannot_fit_in_memory_is_refused() {
    let points: Vec<[f64; 2]> = (0..65536)
        .map(|i| [0.1 + (i % 256) as f64 * 0.01, 0.1 + (i / 256) as f64 * 0.01])
        .collect();
    let doc = json!({
        "media": { "air": { "speed": 343.0, "at": [0.05, 0.05] } },
        "interfaces": { "floor": { "points": [[-1, 0], [10, 0]] } },
        "sources": points, "receivers": points,
        "search": { "max_steps": 1 }
    });
    let dir = std::env::temp_dir().join(format!("eigenray-search-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("huge.json");
    std::fs::write(&path, doc.to_string()).unwrap();
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 2000000 && exec \"$0\" solve \"$1\"")
        .arg(env!("CARGO_BIN_EXE_eigenray"))
        .arg(&path)
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("4294967296 source-receiver pairs"),
        "{stderr}"
    );
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
    let found = Tracer::new(&scene)
        .unwrap()
        .search(&eigenray::options::Run::new())
        .unwrap()
        .arrivals;
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
