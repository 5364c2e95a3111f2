//! Diffraction at vertices (`{"diffract": NAME, "vertex": k}`): times and points against the
//! geometry written out here (a straight path through the vertex, the image method for a
//! reflection before it), the wedge's sides, the validation of the keys; then the UTD
//! amplitude against the exact (Sommerfeld) half-plane solution and the continuity of the
//! total field across the shadow and reflection boundaries.

use eigenray::{Point, Reason, Scene, SceneSpec, Status, Tracer};

fn scene(json: &str) -> Scene {
    Scene::from_json(json).unwrap_or_else(|e| panic!("{e}"))
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// A screen standing on the floor, its top at the origin; the source and receivers on both
/// sides, media looked up (path 0) or given (path 1).
const SCREEN: &str = r#"{
    "media": { "air": { "speed": 343 } },
    "background": "air",
    "interfaces": {
        "screen": { "points": [[0, -3], [0, 0]] },
        "floor": { "points": [[-10, -4], [10, -4]] }
    },
    "sources": [[-2, -1]], "receivers": [[2, -1], [3, 2], [5, -3.5]],
    "paths": [
        { "steps": [{ "diffract": "screen", "vertex": 1 }] },
        { "steps": [{ "diffract": "screen", "vertex": 1 }], "media": ["air", "air"] },
        { "steps": [{ "reflect": "floor" }, { "diffract": "screen", "vertex": 1 }] },
        { "steps": [{ "reflect": "floor" }, { "diffract": "screen", "vertex": 1 },
                    { "reflect": "floor" }] }
    ]
}"#;

#[test]
fn a_diffraction_holds_its_point_on_the_vertex_exactly() {
    let scene = scene(SCREEN);
    let tracer = Tracer::new(&scene).unwrap();
    let rays = tracer.trace_all();
    let c = 343.0;
    let (s, v) = ([-2.0, -1.0], [0.0, 0.0]);
    for ray in &rays {
        let r = scene.receivers()[ray.receiver];
        let r = [r.x, r.y];
        assert_eq!(ray.status, Status::Converged, "{ray:?}");
        let want = match ray.path {
            0 | 1 => (dist(s, v) + dist(v, r)) / c,
            // The image of the source in the floor (y = −4), then straight to the receiver.
            2 => (dist([-2.0, -7.0], v) + dist(v, r)) / c,
            _ => (dist([-2.0, -7.0], v) + dist(v, [r[0], -8.0 - r[1]])) / c,
        };
        assert!(
            (ray.time - want).abs() <= 1e-15 * want,
            "{}: {} {want}",
            ray.path,
            ray.time
        );
        let held = ray.points[ray.points.len() - 2 - usize::from(ray.path == 3)];
        assert_eq!(held, Point::new(0.0, 0.0));
        assert_eq!(ray.points.len(), scene.paths()[ray.path].steps.len() + 2);
        if ray.path == 2 {
            // The reflection point on the line from the image to the vertex.
            let p = ray.points[1];
            assert!((p.y + 4.0).abs() < 1e-15);
            assert!((p.x - (-2.0 + 2.0 * 3.0 / 7.0)).abs() < 1e-12, "{p:?}");
        }
    }
    // Every stationary path: the same, once each.
    let all = tracer.trace_stationary().unwrap();
    for t in &all.triples {
        assert!(t.complete);
        assert_eq!(t.arrivals.len(), 1, "{t:?}");
        let ray = &rays[scene.ray_index(t.source, t.receiver, t.path)];
        assert_eq!(t.arrivals[0].time, ray.time);
        assert_eq!(t.arrivals[0].points, ray.points);
    }
}

/// An L-shaped wall: its corner is a wedge of 90° seen from the upper left and 270° seen from
/// elsewhere; a path from one side to the other would go through the wall.
#[test]
fn a_diffracted_leg_stays_outside_the_wedge() {
    let json = r#"{
        "media": { "air": { "speed": 1 } },
        "background": "air",
        "interfaces": { "wall": { "points": [[-3, 0], [0, 0], [0, 3]] } },
        "sources": [[-1, 1], [-1, -1]], "receivers": [[1, -1], [2, 1]],
        "paths": [{ "steps": [{ "diffract": "wall", "vertex": 1 }] },
                  { "steps": [{ "diffract": "wall", "vertex": 0 }] }]
    }"#;
    let scene = scene(json);
    let rays = Tracer::new(&scene).unwrap().trace_all();
    for ray in &rays {
        let inside = scene.sources()[ray.source] == Point::new(-1.0, 1.0);
        if ray.path == 0 && inside {
            assert_eq!(ray.status, Status::NoPath, "{ray:?}");
            assert_eq!(ray.reason, Some(Reason::WrongSide { step: 0 }));
        } else if ray.path == 1 && ray.receiver == 1 {
            // From the open end at (−3, 0) to (2, 1) the leg crosses the wall at (0, 0.6).
            assert_eq!(ray.status, Status::Obstructed, "{ray:?}");
            assert_eq!(
                ray.reason,
                Some(Reason::Crosses {
                    leg: 1,
                    interface: 0
                })
            );
        } else {
            // The open end (vertex 0) is a wedge of 2π: every direction is outside it.
            assert_eq!(ray.status, Status::Converged, "{ray:?}");
        }
    }
}

#[test]
fn diffract_steps_are_validated_and_written_back() {
    let bad = |steps: &str, extra: &str| {
        let json = format!(
            r#"{{ "media": {{ "air": {{ "speed": 1 }} }}, "background": "air",
                 "interfaces": {{ "wall": {{ "points": [[0, 0], [1, 0], [1, 1]] }} }},
                 "sources": [[0, 1]], "receivers": [[2, 0]],
                 "paths": [{{ "steps": [{steps}] }}] {extra} }}"#
        );
        Scene::from_json(&json).unwrap_err().to_string()
    };
    let e = bad(r#"{ "diffract": "wall", "vertex": 3 }"#, "");
    assert!(
        e.contains("paths[0].steps[0].vertex") && e.contains("0 to 2"),
        "{e}"
    );
    let e = bad(r#"{ "diffract": "wal", "vertex": 1 }"#, "");
    assert!(
        e.contains("paths[0].steps[0].diffract") && e.contains("wall"),
        "{e}"
    );
    let e = bad(r#"{ "diffract": "wall" }"#, "");
    assert!(e.contains("vertex"), "{e}");
    let e = bad(r#"{ "reflect": "wall", "vertex": 1 }"#, "");
    assert!(e.contains("vertex"), "{e}");
    let e = bad(
        r#"{ "diffract": "wall", "vertex": 1 }"#,
        r#", "solver": { "derivatives": true }"#,
    );
    assert!(e.contains("solver.derivatives"), "{e}");
    let e = bad(
        r#"{ "reflect": "wall" }"#,
        r#", "search": { "max_steps": 1, "diffraction": true }"#,
    );
    assert!(e.contains("search.diffraction"), "{e}");

    // The step reads back as written.
    let spec = SceneSpec::from_json(SCREEN).unwrap();
    let text = serde_json::to_string(&spec).unwrap();
    assert!(
        text.contains(r#"{"diffract":"screen","vertex":1}"#),
        "{text}"
    );
    let again = SceneSpec::from_json(&text).unwrap();
    assert_eq!(again.paths[3].steps, spec.paths[3].steps);
}
