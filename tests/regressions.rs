//! Frozen inputs that made the library panic, hang or answer wrongly: one named test each.
//!
//! Each input is `fixtures/fuzz/NAME.json` (its `description` says where it came from and what
//! went wrong) or inline; each test asserts the correct behaviour.

use std::path::Path;

use eigenray::{Point, Ray, Scene, Status, Tracer};

#[path = "support/interface.rs"]
mod interface;
use interface::distance_to_polyline;

/// The text of `fixtures/fuzz/NAME.json`.
fn fixture(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/fuzz")
        .join(format!("{name}.json"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Parses, validates and traces a scene document.
fn trace(text: &str) -> Vec<Ray> {
    let scene = Scene::from_json(text).unwrap_or_else(|e| panic!("scene rejected: {e}"));
    let tracer = Tracer::new(&scene).unwrap_or_else(|e| panic!("Tracer::new: {e}"));
    tracer.trace_all()
}

/// Every interaction point of every ray with points lies on its interface.
fn assert_points_on_interfaces(name: &str, scene: &Scene, rays: &[Ray]) {
    let size = scene.bbox().diagonal();
    for ray in rays.iter().filter(|r| !r.points.is_empty()) {
        for (i, step) in scene.paths()[ray.path].steps.iter().enumerate() {
            let line = &scene.interfaces()[step.interface].polyline;
            let p = ray.points[i + 1];
            let d = distance_to_polyline(line, p);
            assert!(
                d <= 1e-9 * size,
                "{name}: ray {} ({}): interaction {i} at {p:?} is {d:e} from interface `{}`",
                ray.path,
                ray.status,
                scene.interfaces()[step.interface].name
            );
        }
    }
}

/// The only ray of a one-ray fixture (after checking that its points lie on the interfaces).
fn only_ray(name: &str) -> Ray {
    let text = fixture(name);
    let scene = Scene::from_json(&text).unwrap_or_else(|e| panic!("scene rejected: {e}"));
    let rays = trace(&text);
    assert_eq!(rays.len(), 1, "{name}: one ray");
    assert_points_on_interfaces(name, &scene, &rays);
    rays.into_iter().next().expect("one ray")
}

/// An impossible path (the source and receiver are on the wrong sides for its steps) must
/// not be reported as a specular or edge-diffracted path. `no_path` is the documented answer;
/// `obstructed` would also be honest (a stationary path whose leg crosses an interface).
fn assert_impossible(name: &str) {
    let ray = only_ray(name);
    assert!(
        matches!(ray.status, Status::NoPath | Status::Obstructed),
        "{name}: an impossible path reported as {} ({:?}), points {:?}, residual {}",
        ray.status,
        ray.reason,
        ray.points,
        ray.residual
    );
}

/// Two refractions through one interface with the source above and the receiver below: the
/// solver collapsed both interaction points onto one spot (a zero-length middle leg, where
/// Snell's law is undefined) and reported `converged`.
#[test]
fn refract_twice_vanished_middle_leg_is_no_path() {
    assert_impossible("refract_twice_vanished_middle_leg");
}

/// The same with region lookup for the leg media (`converged` with the residual at 0.4).
#[test]
fn refract_twice_vanished_middle_leg_lookup_is_no_path() {
    assert_impossible("refract_twice_vanished_middle_leg_lookup");
}

/// Two reflections with the source above and the receiver below: the middle leg of the
/// stationary path runs inside the interface (on neither side) and was reported `converged`.
#[test]
fn reflect_twice_middle_leg_along_segment_is_no_path() {
    assert_impossible("reflect_twice_middle_leg_along_segment");
}

/// Two refractions with the source above and the receiver below: the middle leg runs inside
/// the interface (a head wave at the critical angle) and was reported `converged`.
#[test]
fn refract_twice_middle_leg_along_segment_is_no_path() {
    assert_impossible("refract_twice_middle_leg_along_segment");
}

/// One refraction with the source and the receiver on the same side: the specular point at
/// s = 0.798 inside segment 0 is stationary with the legs on one side, so `no_path`; the
/// Newton iteration cycled between the open end and vertex 1 until the iteration limit.
#[test]
fn single_refraction_same_side_is_no_path_not_a_cycle() {
    let ray = only_ray("single_refraction_same_side_cycles");
    assert_eq!(
        ray.status,
        Status::NoPath,
        "{:?} after {} iterations, residual {}",
        ray.reason,
        ray.iterations,
        ray.residual
    );
}

/// Two refractions through a closed polygon that the straight source–receiver line misses, one
/// medium everywhere: no path. The solver ended at s = 0 on the polygon's closing segment, so
/// the reported interaction points were extrapolated 1.2 away from the polygon, and called the
/// ray `converged`.
#[test]
fn lens_pass_points_stay_on_polygon() {
    assert_impossible("lens_pass_points_off_polygon");
}

/// A reflection whose receiver is the valley vertex of the mirror: the iteration crept towards
/// the kink at the receiver and stalled just short of it until the iteration limit.
#[test]
fn reflect_receiver_on_vertex_terminates() {
    let ray = only_ray("reflect_receiver_on_vertex_stalls");
    assert_ne!(ray.status, Status::NotConverged, "{ray:?}");
}

/// The same with a refraction and region lookup.
#[test]
fn refract_receiver_on_vertex_terminates() {
    let ray = only_ray("refract_receiver_on_vertex_stalls");
    assert_ne!(ray.status, Status::NotConverged, "{ray:?}");
}

/// A reflection whose source is a vertex of a digitised mirror, with a much larger slowness on
/// the source's leg: steps jumped across the source's vertex (a kink of T) and back, cycling
/// over four segments until the iteration limit. The point is put on the source when a step
/// passes over it; the kink test holds it there. With slowness 6.4 on the source's leg and
/// 0.11 on the other, T grows whichever way the point leaves the source: the reflection
/// collapses onto the source, which is the direct path, not a path of this sequence
/// (`no_path`, saying so).
#[test]
fn reflect_source_on_vertex_terminates() {
    let ray = only_ray("reflect_source_on_vertex_cycles");
    assert_eq!(ray.status, Status::NoPath, "{ray:?}");
    assert_eq!(
        ray.reason,
        Some(eigenray::Reason::AtEnd { step: 0 }),
        "{ray:?}"
    );
    assert!(ray.iterations <= 5, "{ray:?}");
}

/// One refraction through a closed triangle whose vertex is the receiver: a step across the
/// polygon's closing vertex (its parameter wrapping round) must not count as passing over the
/// receiver's parameter.
#[test]
fn wrapped_step_does_not_pass_over_the_receiver() {
    let ray = only_ray("refract_receiver_on_polygon_vertex_wrap");
    assert!(ray.iterations <= 5, "{ray:?}");
    // The solve ends on vertex 0, whose second leg runs along the closing segment to the
    // receiver: on neither side there, so no path; the complete search's one candidate
    // refracts at the receiver itself (vertex 2), which is the path without the refraction:
    // no path of this sequence either, a proof.
    assert_eq!(ray.status, Status::NoPath, "{ray:?}");
    assert_eq!(
        ray.reason,
        Some(eigenray::Reason::NoStationaryPath),
        "{ray:?}"
    );
}

/// Source and receiver both on a straight interface: every leg lies in its line, so whatever
/// the leg media, neither a reflection nor a refraction (some cycled to the iteration limit,
/// some were reported `converged` with time 1).
#[test]
fn ends_on_a_straight_interface_is_no_path() {
    let text = fixture("ends_on_a_straight_interface");
    let scene = Scene::from_json(&text).unwrap_or_else(|e| panic!("scene rejected: {e}"));
    let rays = trace(&text);
    assert_points_on_interfaces("ends_on_a_straight_interface", &scene, &rays);
    for ray in &rays {
        assert_eq!(ray.status, Status::NoPath, "path {}: {ray:?}", ray.path);
    }
}

/// Source and receiver at one point on an interface (its end vertex, or inside a segment):
/// both legs vanish, no leg is on any side, so neither a reflection nor a refraction exists.
/// At the end vertex both were reported `converged` with time 0; inside the segment both ran
/// to the iteration limit.
#[test]
fn source_equals_receiver_on_interface_is_no_path() {
    let text = r#"{
        "media": { "m": { "speed": 1.0 } },
        "interfaces": { "line": { "points": [[0.3, 5.0], [9.7, 5.0]] } },
        "sources": [[0.3, 5.0], [5.0, 5.0]],
        "receivers": [[0.3, 5.0], [5.0, 5.0]],
        "paths": [
            { "steps": [{ "reflect": "line" }], "media": ["m", "m"] },
            { "steps": [{ "refract": "line" }], "media": ["m", "m"] }
        ]
    }"#;
    for ray in trace(text) {
        assert_eq!(
            ray.status,
            Status::NoPath,
            "source {} receiver {} path {}: {ray:?}",
            ray.source,
            ray.receiver,
            ray.path
        );
    }
}

/// Found by the `scene` fuzz target: a vertex of the lens lies exactly on the surface between
/// its vertices, and both cross the domain's edge. Spade's constraint splitting asserted on it
/// (`Regions::build` caught that and rejected the valid scene); the surface's constraint now
/// goes in pieces through the lens's vertex.
#[test]
fn vertex_on_another_interface_across_the_domain_edge() {
    let text = r#"{
      "media": {"air": {"speed": 2.0}, "water": {"speed": 0.75, "at": [0.5, -0.5]}},
      "background": "air",
      "domain": [[-2.1, -4.0], [5.0, 3.4]],
      "interfaces": {"surface": {"points": [[-3.0, 5.0], [7.0, 0.0]]},
                     "lens": {"points": [[2, 4.5], [8, 0.5], [4, 1.5]], "closed": true}},
      "sources": [[0.0, 1.0]],
      "receivers": [[1.0, -1.0], [5.5, -0.0]],
      "paths": [{"steps": [{"refract": "surface"}]}, {"steps": [{"reflect": "surface"}]}]
    }"#;
    let scene = Scene::from_json(text).expect("a valid scene");
    let tracer = Tracer::new(&scene).expect("regions build");
    let regions = tracer.regions().expect("lookup paths need regions");
    let medium = |x: f64, y: f64| {
        regions
            .medium_at(Point::new(x, y))
            .map(|m| scene.media()[m].name.clone())
    };
    // Below the surface: the `at` point's water; above it, outside and inside the lens: the
    // background.
    assert_eq!(medium(0.0, -3.0).as_deref(), Some("water"));
    assert_eq!(medium(-2.0, 3.0).as_deref(), Some("water"));
    assert_eq!(medium(4.9, 3.0).as_deref(), Some("air"));
    assert_eq!(medium(4.9, 2.0).as_deref(), Some("air"));
    let rays = tracer.trace_all();
    assert_eq!(rays.len(), 4);
    assert_points_on_interfaces("vertex on interface", &scene, &rays);
}

/// A ray whose second leg has no medium (region lookup, no `at` below the surface, no
/// background): one-by-one solving kept the leg media found before the gap, a batch none.
#[test]
fn no_medium_ray_has_the_same_media_one_by_one_and_in_a_batch() {
    use eigenray::{BatchOptions, Reason, Workspace};
    let scene = Scene::from_json(&fixture("no_medium_partial_leg_media")).expect("valid scene");
    let tracer = Tracer::new(&scene).expect("tracer");
    let one = tracer.trace(0, 0, 0, &mut Workspace::new());
    assert_eq!(one.status, Status::NoPath, "{one:?}");
    // The start's second leg finds no medium; the complete search then proves it.
    assert_eq!(one.reason, Some(Reason::NoStationaryPath), "{one:?}");
    assert!(one.media.is_empty(), "{one:?}");
    for warm_start in [false, true] {
        let batch = tracer
            .trace_batch(
                &BatchOptions {
                    warm_start,
                    ..BatchOptions::default()
                },
                &eigenray::options::Run::new(),
            )
            .unwrap();
        let got = batch.ray(0);
        assert_eq!(
            (got.status, got.reason, &got.media),
            (one.status, one.reason, &one.media)
        );
    }
}

/// Trailing text after the scene object (a second document, stray words) is bad JSON: it was
/// ignored and the scene traced.
#[test]
fn trailing_characters_after_the_scene_are_rejected() {
    let scene = r#"{"media": {"a": {"speed": 1}}, "sources": [[0, 0]], "receivers": [[1, 1]],
        "paths": [{"steps": []}]}"#;
    assert!(Scene::from_json(scene).is_ok());
    assert!(Scene::from_json(&format!("{scene} \n\t")).is_ok());
    for tail in [" garbage", "\n{}", ",", "}"] {
        let e = Scene::from_json(&format!("{scene}{tail}")).expect_err(tail);
        assert_eq!(e.key, "scene", "{tail:?}: {e}");
        assert!(e.message.contains("trailing characters"), "{tail:?}: {e}");
    }
}

/// Refractions through interfaces 1e-9 apart, far from the source: the middle point's residual
/// sits at the round-off floor of its source-relative coordinates; the line search stalled
/// there until the iteration limit instead of stopping (`no_path`: the ray leaves an end).
#[test]
fn thin_stack_stops_at_the_round_off_floor() {
    let ray = only_ray("thin_stack_round_off_stall");
    assert_eq!(ray.status, Status::NoPath, "{ray:?}");
    assert!(ray.iterations <= 10, "{ray:?}");
}
