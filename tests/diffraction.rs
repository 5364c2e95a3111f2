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
    let all = tracer
        .trace_stationary(&eigenray::options::Run::new())
        .unwrap();
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

// ---------------------------------------------------------------------------------------
// The UTD amplitude.

use eigenray::amplitude::Complex64;
use std::f64::consts::{PI, TAU};

/// `∫_a^∞ e^(iτ²) dτ` (any real `a`) by Simpson's rule along `τ = |a| + t e^(iπ/4)`, where
/// the integrand decays as `e^(−√2 |a| t − t²)`; for `a < 0`, `√π e^(iπ/4)` less the tail at
/// `|a|`. Written here on its own, apart from the library's Fresnel integral.
fn tail(a: f64) -> Complex64 {
    let dir = Complex64::from_polar(1.0, PI / 4.0);
    let b = a.abs();
    let f = |t: f64| {
        let tau = dir * t + b;
        (Complex64::new(0.0, 1.0) * tau * tau).exp() * dir
    };
    let (end, n) = (10.0, 40_000);
    let h = end / f64::from(n);
    let mut sum = f(0.0) + f(end);
    for j in 1..n {
        sum += f(f64::from(j) * h) * if j % 2 == 1 { 4.0 } else { 2.0 };
    }
    let t = sum * (h / 3.0);
    if a >= 0.0 {
        t
    } else {
        Complex64::from_polar(PI.sqrt(), PI / 4.0) - t
    }
}

/// Sommerfeld's exact field of a half-plane (the face along φ = 0) lit by the plane wave
/// `e^(−ikr cos(φ − φ₀))` (time factor `e^(−iωt)`): `U(φ − φ₀) ± U(φ + φ₀)` with
/// `U(β) = e^(−ikr cos β) e^(−iπ/4)/√π ∫_−∞^(√(2kr) cos(β/2)) e^(iτ²) dτ`; `+` for a rigid face,
/// `−` for a pressure-release one.
fn sommerfeld(kr: f64, phi: f64, phi0: f64, rigid: bool) -> Complex64 {
    let u = |beta: f64| {
        let upper = (2.0 * kr).sqrt() * (beta / 2.0).cos();
        let below = Complex64::from_polar(PI.sqrt(), PI / 4.0) - tail(upper);
        Complex64::from_polar(1.0, -kr * beta.cos())
            * Complex64::from_polar(1.0 / PI.sqrt(), -PI / 4.0)
            * below
    };
    if rigid {
        u(phi - phi0) + u(phi + phi0)
    } else {
        u(phi - phi0) - u(phi + phi0)
    }
}

/// A wedge scene: faces from the edge at the origin along angle 0 and along angle `alpha`
/// (an open end when `alpha` is 2π), `law` their reflection, a `line` (or other) source at
/// `source`, and the receivers; paths: direct, a reflection off each face, the diffraction.
fn wedge_scene(
    alpha: f64,
    law: &str,
    model: &str,
    source: [f64; 2],
    receivers: &[[f64; 2]],
    face: f64,
) -> Scene {
    wedge_scene_at([0.0, 0.0], alpha, law, model, source, receivers, face)
}

/// [`wedge_scene`] with the edge at `edge` (`source` and `receivers` given relative to it).
fn wedge_scene_at(
    edge: [f64; 2],
    alpha: f64,
    law: &str,
    model: &str,
    source: [f64; 2],
    receivers: &[[f64; 2]],
    face: f64,
) -> Scene {
    let [ex, ey] = edge;
    let end = if alpha == TAU {
        format!(r#""points": [[{ex:e}, {ey:e}], [{:e}, {ey:e}]]"#, ex + face)
    } else {
        let (x, y) = (ex + face * alpha.cos(), ey + face * alpha.sin());
        format!(
            r#""points": [[{:e}, {ey:e}], [{ex:e}, {ey:e}], [{x:e}, {y:e}]]"#,
            ex + face
        )
    };
    let source = [source[0] + ex, source[1] + ey];
    let vertex = usize::from(alpha != TAU);
    let receivers: Vec<String> = receivers
        .iter()
        .map(|r| format!("[{:e}, {:e}]", r[0] + ex, r[1] + ey))
        .collect();
    let json = format!(
        r#"{{
        "media": {{ "air": {{ "speed": 1 }} }},
        "interfaces": {{ "wedge": {{ {end}, "reflection": "{law}" }} }},
        "sources": [[{:e}, {:e}]], "receivers": [{}],
        "paths": [
            {{ "steps": [], "media": ["air"] }},
            {{ "steps": [{{ "reflect": "wedge" }}], "media": ["air", "air"] }},
            {{ "steps": [{{ "diffract": "wedge", "vertex": {vertex} }}], "media": ["air", "air"] }}
        ],
        "solver": {{ "stationary": "all" }},
        "amplitudes": {{ "source": "{model}", "frequency": {} }}
    }}"#,
        source[0],
        source[1],
        receivers.join(", "),
        1.0 / TAU
    );
    scene(&json)
}

/// The total field at each receiver: every `converged` arrival's amplitude × `e^(iωT)`
/// (k = 1: ω = 1 with speed 1).
fn total_field(scene: &Scene) -> Vec<Complex64> {
    let tracer = Tracer::new(scene).unwrap();
    let all = tracer
        .trace_stationary(&eigenray::options::Run::new())
        .unwrap();
    let mut p = vec![Complex64::new(0.0, 0.0); scene.receivers().len()];
    for t in &all.triples {
        assert!(t.complete);
        for a in t.arrivals.iter().filter(|a| a.status == Status::Converged) {
            let amp = a.amplitude.unwrap();
            assert!(amp.has_value(), "{:?} {a:?}", amp.reason);
            p[t.receiver] += amp.value * Complex64::from_polar(1.0, a.time);
        }
    }
    p
}

/// The half-plane lit from far away (a line source at r₀ = 1e9: a plane wave near the edge):
/// the total field (direct, reflected, diffracted) over arcs of receivers that cross the
/// shadow and the reflection boundaries, against Sommerfeld's exact solution. For a
/// half-plane lit by a plane wave the UTD field is Sommerfeld's (its Fresnel integrals are
/// the exact ones), so what is left is the source's distance: the phase `kr²/(2r₀)` of a
/// cylindrical wave against a plane one, 2e-5 at kr = 200.
#[test]
fn half_plane_total_field_matches_sommerfeld() {
    let phi0 = PI / 3.0;
    let r0 = 1e9;
    let s = [r0 * phi0.cos(), r0 * phi0.sin()];
    // The incident field at the edge: the 2-D Green's function's far field.
    let at_edge = Complex64::from_polar(1.0 / (8.0 * PI * r0).sqrt(), PI / 4.0 + r0);
    for (law, rigid) in [("rigid", true), ("pressure-release", false)] {
        let mut worst = Vec::new();
        for kr in [50.0, 100.0, 200.0] {
            // Angles through both boundaries (π − φ₀ and π + φ₀), off them by ≥ 0.02 rad.
            let angles: Vec<f64> = (0..60)
                .map(|j| 0.3 + f64::from(j) * (2.0 * PI - 0.6) / 59.0)
                .collect();
            let receivers: Vec<[f64; 2]> = angles
                .iter()
                .map(|&a| [kr * a.cos(), kr * a.sin()])
                .collect();
            let scene = wedge_scene(TAU, law, "line", s, &receivers, 1e4);
            let p = total_field(&scene);
            let mut err: f64 = 0.0;
            for (j, &phi) in angles.iter().enumerate() {
                let exact = sommerfeld(kr, phi, phi0, rigid);
                err = err.max((p[j] / at_edge - exact).norm());
            }
            eprintln!("half-plane, {law}, kr = {kr}: largest |p/p_i − exact| = {err:.3e}");
            worst.push(err);
        }
        for (err, kr) in worst.iter().zip([50.0f64, 100.0, 200.0]) {
            let bound = 1e-6 + 0.7 * kr * kr / r0;
            assert!(*err < bound, "{law}, kr = {kr}: {err:e} > {bound:e}");
        }
    }
}

#[path = "support/rng.rs"]
mod rng;

/// Receivers stepping across a wedge's shadow boundary and its reflection boundary by 1e-9
/// rad see no jump in the total field (specular + diffracted): |p| on both sides equal within
/// 1e-6, where geometric optics alone jumps by several dB. Random wedges (exterior angles
/// from π to 2π, rigid or pressure-release faces, a line, point or axisymmetric source).
#[test]
fn total_field_is_continuous_across_shadow_and_reflection_boundaries() {
    let mut rng = rng::SplitMix64(41);
    let (mut worst, mut least_jump): (f64, f64) = (0.0, f64::INFINITY);
    let mut cases = 0;
    for case in 0..24 {
        let alpha: f64 = PI + 0.4 + rng.next_f64() * (PI - 0.4);
        let alpha = if case % 6 == 0 { TAU } else { alpha };
        let phi0: f64 = 0.1 + rng.next_f64() * (alpha - PI - 0.2);
        let r0 = 20.0 + 100.0 * rng.next_f64();
        let r = 20.0 + 100.0 * rng.next_f64();
        let law = if case % 2 == 0 {
            "rigid"
        } else {
            "pressure-release"
        };
        let model = ["line", "point", "axisymmetric"][case % 3];
        let source = [r0 * phi0.cos(), r0 * phi0.sin()];
        let delta = 1e-9;
        let mut receivers = Vec::new();
        for boundary in [PI + phi0, PI - phi0] {
            for phi in [boundary - delta, boundary + delta] {
                receivers.push([r * phi.cos(), r * phi.sin()]);
            }
        }
        // An axisymmetric scene: the source on the axis x = 0, everything else at x > 0.
        let edge = if model == "axisymmetric" {
            [-source[0], 0.0]
        } else {
            [0.0, 0.0]
        };
        if model == "axisymmetric" && receivers.iter().any(|p| p[0] + edge[0] <= 0.0) {
            continue;
        }
        let scene = wedge_scene_at(edge, alpha, law, model, source, &receivers, 1e3);
        let p = total_field(&scene);
        for pair in p.chunks(2) {
            let (a, b) = (pair[0].norm(), pair[1].norm());
            let jump = (a - b).abs() / a.max(b);
            assert!(
                jump < 1e-6,
                "case {case} ({alpha}, {law}, {model}): {a} {b}"
            );
            worst = worst.max(jump);
        }
        // Geometric optics alone: the jump that the diffracted arrival fills.
        let tracer = Tracer::new(&scene).unwrap();
        let rays = tracer.trace_all();
        let go = |receiver: usize| {
            rays.iter()
                .filter(|ray| ray.receiver == receiver && ray.path < 2)
                .filter(|ray| ray.status == Status::Converged)
                .map(|ray| ray.amplitude.unwrap().value * Complex64::from_polar(1.0, ray.time))
                .sum::<Complex64>()
                .norm()
        };
        let (lit, dark) = (go(0), go(1));
        least_jump = least_jump.min((lit - dark).abs() / lit.max(dark));
        cases += 1;
    }
    eprintln!(
        "{cases} wedges: largest relative jump of |p| across a boundary {worst:.2e}; geometric \
         optics alone jumps by ≥ {least_jump:.2} of |p| at the shadow boundary"
    );
    assert!(least_jump > 0.3 && cases >= 16);
}

/// Vertices without a wedge coefficient keep a `null` amplitude with a reason naming the case.
#[test]
fn unsupported_vertices_have_no_amplitude_and_say_why() {
    use eigenray::amplitude::{DiffractionCase, NoAmplitude};
    let case = |law: &str, frequency: &str| {
        let json = format!(
            r#"{{ "media": {{ "air": {{ "speed": 343 }}, "wall": {{ "speed": 3000, "at": [0.5, -5] }} }},
                 "background": "air",
                 "interfaces": {{ "screen": {{ "points": [[0, -10], [0, 0], [1, 0], [1, -10]],
                                              "closed": true, "reflection": {law} }} }},
                 "sources": [[-2, -1]], "receivers": [[3, 1]],
                 "paths": [{{ "steps": [{{ "diffract": "screen", "vertex": 1 }}] }}],
                 "amplitudes": {{ "source": "point" {frequency} }} }}"#
        );
        let rays = Tracer::new(scene(&json)).unwrap().trace_all();
        assert_eq!(rays[0].status, Status::Converged);
        let a = rays[0].amplitude.unwrap();
        assert_eq!(a.has_value(), a.reason.is_none());
        a.reason
    };
    let why = |case| Some(NoAmplitude::Diffraction { step: 0, case });
    assert_eq!(
        case(r#""media""#, r#", "frequency": 500"#),
        why(DiffractionCase::PenetrableFace)
    );
    assert_eq!(
        case(r#"{ "absorption": 0.3 }"#, r#", "frequency": 500"#),
        why(DiffractionCase::AbsorbingFace)
    );
    assert_eq!(case(r#""rigid""#, ""), why(DiffractionCase::NoFrequency));
    assert_eq!(case(r#""rigid""#, r#", "frequency": 500"#), None);
}

/// Whether segment `a–b` crosses segment `p–q` at a point strictly inside both (a brute-force
/// test of its own, in plain arithmetic; touching at an end is no crossing).
fn crosses(a: [f64; 2], b: [f64; 2], p: [f64; 2], q: [f64; 2]) -> bool {
    let cross = |o: [f64; 2], u: [f64; 2], v: [f64; 2]| {
        (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])
    };
    let (d1, d2) = (cross(p, q, a), cross(p, q, b));
    let (d3, d4) = (cross(a, b, p), cross(a, b, q));
    let eps = 1e-12;
    ((d1 > eps && d2 < -eps) || (d1 < -eps && d2 > eps))
        && ((d3 > eps && d4 < -eps) || (d3 < -eps && d4 > eps))
}

/// An L-shaped room: the search with `"diffraction": true` lists, for every pair, exactly the
/// vertices that both ends see (a brute force over the walls), each once, with the time of its
/// two straight legs; the edge-held `vertex` arrivals of the same paths are not listed again;
/// `max_time` bounds them.
#[test]
fn search_lists_every_vertex_both_ends_see() {
    let room = [
        [0.0, 0.0],
        [4.0, 0.0],
        [4.0, 2.0],
        [2.0, 2.0],
        [2.0, 4.0],
        [0.0, 4.0],
    ];
    let mut rng = rng::SplitMix64(7);
    let mut inside = |n: usize| -> Vec<[f64; 2]> {
        let mut pts = Vec::new();
        while pts.len() < n {
            let p = [0.1 + 3.8 * rng.next_f64(), 0.1 + 3.8 * rng.next_f64()];
            if p[0] < 1.9 || p[1] < 1.9 {
                pts.push(p);
            }
        }
        pts
    };
    let (sources, receivers) = (inside(3), inside(12));
    let list = |pts: &[[f64; 2]]| {
        pts.iter()
            .map(|p| format!("[{:e}, {:e}]", p[0], p[1]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let json = |max_time: &str| {
        format!(
            r#"{{ "media": {{ "air": {{ "speed": 1, "at": [1, 1] }} }},
                 "interfaces": {{ "room": {{ "points": [[0, 0], [4, 0], [4, 2], [2, 2], [2, 4], [0, 4]],
                                            "closed": true }} }},
                 "sources": [{}], "receivers": [{}],
                 "search": {{ "max_steps": 1, "diffraction": true, "vertex": true {max_time} }},
                 "amplitudes": {{ "source": "point", "frequency": 1000 }} }}"#,
            list(&sources),
            list(&receivers)
        )
    };
    let arrivals = Tracer::new(scene(&json("")))
        .unwrap()
        .search(&eigenray::options::Run::new())
        .unwrap()
        .arrivals;
    let sees = |a: [f64; 2], v: usize| {
        (0..room.len()).all(|j| !crosses(a, room[v], room[j], room[(j + 1) % room.len()]))
    };
    let mut listed = 0;
    for (si, &s) in sources.iter().enumerate() {
        for (ri, &r) in receivers.iter().enumerate() {
            let pair: Vec<_> = arrivals
                .iter()
                .filter(|a| a.source == si && a.receiver == ri)
                .collect();
            for (v, &corner) in room.iter().enumerate() {
                let want = sees(s, v) && sees(r, v);
                let found: Vec<_> = pair
                    .iter()
                    .filter(|a| a.steps.len() == 1 && a.steps[0].kind.vertex() == Some(v))
                    .collect();
                assert_eq!(found.len(), usize::from(want), "pair {si} {ri} vertex {v}");
                if let Some(a) = found.first() {
                    let t = dist(s, corner) + dist(corner, r);
                    assert!((a.arrival.time - t).abs() <= 1e-14 * t);
                    assert_eq!(a.arrival.status, Status::Converged);
                    assert!(a.complete);
                    assert!(a.arrival.amplitude.unwrap().has_value());
                    listed += 1;
                }
            }
            // No edge-held arrival of a one-reflection sequence on a listed vertex.
            for a in pair.iter().filter(|a| a.arrival.status == Status::Vertex) {
                assert!(a.steps.len() > 1, "{a:?}");
            }
        }
    }
    eprintln!("{listed} first-order diffracted arrivals, each vertex both ends see");
    assert!(listed > 36);
    // A time bound drops exactly the later ones.
    let bound = 4.0;
    let timed = Tracer::new(scene(&json(&format!(r#", "max_time": {bound}"#))))
        .unwrap()
        .search(&eigenray::options::Run::new())
        .unwrap()
        .arrivals;
    let diffracted = |list: &[eigenray::SearchArrival], t: f64| {
        list.iter()
            .filter(|a| a.steps.iter().any(|s| s.kind.vertex().is_some()))
            .filter(|a| a.arrival.time <= t)
            .count()
    };
    assert_eq!(
        diffracted(&timed, f64::INFINITY),
        diffracted(&arrivals, bound)
    );
}

/// The transmission loss (from a scene's `search` with `"diffraction": true`, through the
/// responses' echoes) has no jump across a corner's shadow edge; without diffraction it
/// jumps by several dB.
#[test]
fn transmission_loss_has_no_jump_at_a_shadow_edge() {
    use eigenray::response::{echoes_of_scene, pressure_into, transmission_loss};
    let tl = |diffraction: bool| {
        // A building's corner (270° outside, rigid), the source at 60° from its top face.
        let (phi0, r0, r) = (PI / 3.0, 30.0, 40.0);
        let boundary = PI + phi0;
        let receivers: Vec<String> = [boundary - 1e-9, boundary + 1e-9]
            .iter()
            .map(|a| format!("[{:e}, {:e}]", r * a.cos(), r * a.sin()))
            .collect();
        let json = format!(
            r#"{{ "media": {{ "air": {{ "speed": 343 }} }}, "background": "air",
                 "interfaces": {{ "corner": {{ "points": [[500, 0], [0, 0], [0, -500]] }} }},
                 "sources": [[{:e}, {:e}]], "receivers": [{}],
                 "search": {{ "max_steps": 1, "diffraction": {diffraction} }},
                 "amplitudes": {{ "source": "point", "frequency": 250 }} }}"#,
            r0 * phi0.cos(),
            r0 * phi0.sin(),
            receivers.join(", ")
        );
        let tracer = Tracer::new(scene(&json)).unwrap();
        let echoes = echoes_of_scene(&tracer, &eigenray::options::Run::new()).unwrap();
        let mut p = [Complex64::new(0.0, 0.0); 2];
        pressure_into(echoes, 250.0, 1, &eigenray::options::Run::new(), &mut p);
        [transmission_loss(p[0]), transmission_loss(p[1])]
    };
    let [lit, dark] = tl(true);
    eprintln!("TL across the shadow edge, with diffraction: {lit:.9} dB, {dark:.9} dB");
    assert!((lit - dark).abs() < 1e-5, "{lit} {dark}");
    let [lit, dark] = tl(false);
    eprintln!("without: {lit:.3} dB, {dark:.3} dB");
    assert!(!dark.is_finite() || dark - lit > 3.0, "{lit} {dark}");
}

/// `J_ν(x)` and `Y_ν(x)` for `0 ≤ ν < 2`, `x > 0`, by Schläfli's integrals
/// `J_ν = (1/π)∫₀^π cos(νθ − x sin θ) dθ − (sin νπ/π)∫₀^∞ e^(−x sinh t − νt) dt`,
/// `Y_ν = (1/π)∫₀^π sin(x sin θ − νθ) dθ − (1/π)∫₀^∞ (e^(νt) + e^(−νt) cos νπ) e^(−x sinh t) dt`
/// (Simpson's rule): the starting values of the recurrences below.
fn schlafli(nu: f64, x: f64) -> (f64, f64) {
    let simpson = |f: &dyn Fn(f64) -> f64, a: f64, b: f64, n: u32| {
        let h = (b - a) / f64::from(n);
        let mut s = f(a) + f(b);
        for j in 1..n {
            s += f(a + f64::from(j) * h) * if j % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * h / 3.0
    };
    let n = 400_000;
    let j1 = simpson(&|t: f64| (nu * t - x * t.sin()).cos(), 0.0, PI, n) / PI;
    let j2 = simpson(&|t: f64| (-x * t.sinh() - nu * t).exp(), 0.0, 3.0, n);
    let y1 = simpson(&|t: f64| (x * t.sin() - nu * t).sin(), 0.0, PI, n) / PI;
    let y2 = simpson(
        &|t: f64| ((nu * t).exp() + (-nu * t).exp() * (nu * PI).cos()) * (-x * t.sinh()).exp(),
        0.0,
        3.0,
        n,
    );
    (j1 - (nu * PI).sin() / PI * j2, y1 - y2 / PI)
}

/// `J_(ν₀+n)(x)` for `n = 0 … count − 1` by Miller's backward recurrence, scaled to
/// Schläfli's `J_ν₀` and `J_(ν₀+1)` (least squares).
fn bessel_j(nu0: f64, x: f64, count: usize) -> Vec<f64> {
    let start = count.max(x as usize) + 80;
    let mut v = vec![0.0; start + 2];
    v[start] = 1e-300;
    for n in (1..=start).rev() {
        let nu = nu0 + n as f64;
        v[n - 1] = 2.0 * nu / x * v[n] - v[n + 1];
        if v[n - 1].abs() > 1e250 {
            for w in &mut v[n - 1..] {
                *w *= 1e-250;
            }
        }
    }
    let top = v[0].abs().max(v[1].abs());
    for w in &mut v {
        *w /= top;
    }
    let (a, b) = (schlafli(nu0, x).0, schlafli(nu0 + 1.0, x).0);
    let scale = (a * v[0] + b * v[1]) / (v[0] * v[0] + v[1] * v[1]);
    v.truncate(count);
    v.iter().map(|w| w * scale).collect()
}

/// `Y_(ν₀+n)(x)` for `n = 0 … count − 1` by the forward recurrence from Schläfli's values.
fn bessel_y(nu0: f64, x: f64, count: usize) -> Vec<f64> {
    let mut y = vec![schlafli(nu0, x).1, schlafli(nu0 + 1.0, x).1];
    while y.len() < count {
        let n = y.len();
        let nu = nu0 + (n - 1) as f64;
        y.push(2.0 * nu / x * y[n - 1] - y[n - 2]);
    }
    y.truncate(count);
    y
}

/// The exact field of a unit line source (`(i/4) H₀(kR)` in free space) at `(r, φ)` beside a
/// wedge of exterior angle `α = aπ/b` (faces at φ = 0 and φ = α), the source at `(r₀, φ₀)`:
/// the eigenfunction series `(iπ/2α) Σ ε_m J_ν(kr<) H_ν(kr>) cos νφ cos νφ₀` (rigid) or
/// `(iπ/α) Σ J_ν(kr<) H_ν(kr>) sin νφ sin νφ₀` (pressure-release), `ν = mπ/α` (k = 1).
fn wedge_series(
    a: usize,
    b: usize,
    r0: f64,
    phi0: f64,
    r: f64,
    phis: &[f64],
    rigid: bool,
) -> Vec<Complex64> {
    let alpha = PI * a as f64 / b as f64;
    let (small, large) = (r0.min(r), r0.max(r));
    let count = large as usize + 120;
    // Per family ν₀ = f / a (ν = mb/a … written as ν = m π/α = m b / a).
    let families: Vec<(Vec<f64>, Vec<f64>, Vec<f64>)> = (0..a)
        .map(|f| {
            let nu0 = f as f64 / a as f64;
            (
                bessel_j(nu0, small, count),
                bessel_j(nu0, large, count),
                bessel_y(nu0, large, count),
            )
        })
        .collect();
    let mut out = vec![Complex64::new(0.0, 0.0); phis.len()];
    for m in 0.. {
        let whole = m * b;
        let (f, n) = (whole % a, whole / a);
        if n >= count - 1 {
            break;
        }
        let nu = whole as f64 / a as f64;
        let (js, jl, yl) = &families[f];
        let term = Complex64::new(jl[n], yl[n]) * js[n];
        for (o, &phi) in out.iter_mut().zip(phis) {
            *o += if rigid {
                let eps = if m == 0 { 1.0 } else { 2.0 };
                term * (eps * (nu * phi).cos() * (nu * phi0).cos())
            } else {
                term * (2.0 * (nu * phi).sin() * (nu * phi0).sin())
            };
        }
    }
    let front = Complex64::new(0.0, PI / (2.0 * alpha));
    out.iter().map(|o| o * front).collect()
}

/// The exact wedge (270° and a half-plane, rigid and pressure-release, a line source): the
/// total field (specular + diffracted) against the eigenfunction series over an arc of
/// receivers through the shadow and reflection boundaries, the source at half the receivers'
/// radius. The error, relative to the free field at the receivers, shrinks about as 1/(kr).
#[test]
fn wedge_total_field_matches_the_eigenfunction_series() {
    // Bessel functions by recurrence from Schläfli's integrals: J₀(25) against its table
    // value, and the Wronskian J_(ν+1) Y_ν − J_ν Y_(ν+1) = 2/(πx) far along the recurrences.
    let j = bessel_j(0.0, 25.0, 3);
    assert!((j[0] - 0.096_266_783_275_958_17).abs() < 1e-10, "{j:?}");
    for (nu0, x) in [(0.0, 25.0), (1.0 / 3.0, 200.0), (0.5, 100.0)] {
        let (j, y) = (bessel_j(nu0, x, 300), bessel_y(nu0, x, 300));
        for n in [0, 1, 150, 298] {
            let w = j[n + 1] * y[n] - j[n] * y[n + 1];
            let want = 2.0 / (PI * x);
            assert!((w - want).abs() < 1e-8 * want, "{nu0} {x} {n}: {w} {want}");
        }
    }
    let phi0 = PI / 3.0;
    for (a, b) in [(3, 2), (2, 1)] {
        let alpha = PI * a as f64 / b as f64;
        for (law, rigid) in [("rigid", true), ("pressure-release", false)] {
            let mut worst = Vec::new();
            for kr in [50.0, 100.0, 200.0] {
                let r0 = kr / 2.0;
                let angles: Vec<f64> = (0..40)
                    .map(|i| 0.25 + f64::from(i) * (alpha - 0.5) / 39.0)
                    .filter(|&p| (p - (PI + phi0)).abs() > 0.01 && (p - (PI - phi0)).abs() > 0.01)
                    .collect();
                let receivers: Vec<[f64; 2]> = angles
                    .iter()
                    .map(|&p| [kr * p.cos(), kr * p.sin()])
                    .collect();
                let source = [r0 * phi0.cos(), r0 * phi0.sin()];
                let scene = wedge_scene(alpha, law, "line", source, &receivers, 1e5);
                let p = total_field(&scene);
                let exact = wedge_series(a, b, r0, phi0, kr, &angles, rigid);
                let free = 1.0 / (8.0 * PI * kr).sqrt();
                let err = p
                    .iter()
                    .zip(&exact)
                    .map(|(p, e)| (p - e).norm() / free)
                    .fold(0.0, f64::max);
                eprintln!(
                    "wedge {:.0}°, {law}, kr = {kr}: largest |p − exact| / |G₀| = {err:.3e}",
                    alpha.to_degrees()
                );
                worst.push(err);
            }
            // About 1/(kr): err · kr below 0.5 at every kr, and a third of it at 4× the kr.
            for (err, kr) in worst.iter().zip([50.0, 100.0, 200.0]) {
                assert!(err * kr < 0.5, "{law}, kr = {kr}: {err:e}");
            }
            assert!(worst[2] < worst[0] / 3.0, "{law}: {worst:?}");
        }
    }
}

/// The ideal wedges: inside a wedge of angle π/N (N = 1: a flat wall's interior vertex;
/// N = 2: a right-angle corner; 3, 4, 6) the image sum is the exact field, so the corner's
/// diffracted arrival must carry nothing. For random sources and receivers inside, rigid and
/// pressure-release faces, the search (`max_steps` N, diffraction on) lists the corner's
/// diffracted arrival with an amplitude zero to round-off (against the direct sound), and its
/// specular arrivals plus that diffracted one sum to the 2N-term image sum
/// `Σ ±e^(ikR)/(4πR)` (the images at angles `2mα ± θ₀`, the reflected ones negated for
/// pressure-release faces) to round-off. The faces' far open ends (wedges of 2π at 100 units)
/// diffract for real, and are left out of both sides (with the reflections around them that
/// the search lists with them). Every pair's search is complete (with `vertex` arrivals off
/// here; with them on, `narrow_wedges_search_completely_past_their_ideal_order`).
#[test]
fn ideal_wedges_diffract_nothing_and_their_field_is_the_image_sum() {
    let mut rng = rng::SplitMix64(41);
    let k = 10.0;
    let mut worst_diffracted: f64 = 0.0;
    let mut worst_field: f64 = 0.0;
    for big_n in [1u32, 2, 3, 4, 6] {
        let alpha = PI / f64::from(big_n);
        let face = 100.0;
        let polar = |r: f64, t: f64| [r * t.cos(), r * t.sin()];
        let far = polar(face, alpha);
        let mut inside = || {
            polar(
                0.5 + 4.0 * rng.next_f64(),
                alpha * (0.03 + 0.94 * rng.next_f64()),
            )
        };
        let source = inside();
        let receivers: Vec<[f64; 2]> = (0..6).map(|_| inside()).collect();
        for (law, sign) in [("rigid", 1.0), ("pressure-release", -1.0)] {
            let json = format!(
                r#"{{ "media": {{ "air": {{ "speed": 1 }} }}, "background": "air",
                     "interfaces": {{ "wedge": {{ "points": [[{face:e}, 0], [0, 0], [{:e}, {:e}]],
                                                  "reflection": "{law}" }} }},
                     "sources": [[{:e}, {:e}]], "receivers": [{}],
                     "search": {{ "max_steps": {big_n}, "refract": false, "diffraction": true }},
                     "amplitudes": {{ "source": "point", "frequency": {:e} }} }}"#,
                far[0],
                far[1],
                source[0],
                source[1],
                receivers
                    .iter()
                    .map(|r| format!("[{:e}, {:e}]", r[0], r[1]))
                    .collect::<Vec<_>>()
                    .join(", "),
                k / TAU
            );
            let report = Tracer::new(scene(&json))
                .unwrap()
                .search(&eigenray::options::Run::new())
                .unwrap();
            let (rho, theta) = (source[0].hypot(source[1]), source[1].atan2(source[0]));
            for (ri, &r) in receivers.iter().enumerate() {
                let pair: Vec<_> = (report.arrivals.iter())
                    .filter(|a| a.receiver == ri && a.arrival.status == Status::Converged)
                    .collect();
                assert!(pair.iter().all(|a| a.complete), "N = {big_n}");
                let corner: Vec<_> = (pair.iter())
                    .filter(|a| a.steps.iter().any(|s| s.kind.vertex() == Some(1)))
                    .collect();
                assert_eq!(corner.len(), 1, "N = {big_n} {law} receiver {ri}");
                let corner_value = corner[0].arrival.amplitude.unwrap().value;
                let direct = 1.0 / (4.0 * PI * dist(source, r));
                worst_diffracted = worst_diffracted.max(corner_value.norm() / direct);
                let mut field = Complex64::new(0.0, 0.0);
                for a in pair.iter().filter(|a| {
                    a.steps
                        .iter()
                        .all(|s| s.kind.vertex().is_none_or(|v| v == 1))
                }) {
                    let amp = a.arrival.amplitude.unwrap();
                    assert!(amp.has_value());
                    field += amp.value * Complex64::from_polar(1.0, k * a.arrival.time);
                }
                let mut images = Complex64::new(0.0, 0.0);
                for m in 0..big_n {
                    let turn = 2.0 * f64::from(m) * alpha;
                    for (angle, s) in [(turn + theta, 1.0), (turn - theta, sign)] {
                        let d = dist(polar(rho, angle), r);
                        images += Complex64::from_polar(s / (4.0 * PI * d), k * d);
                    }
                }
                worst_field = worst_field.max((field - images).norm() / images.norm());
            }
        }
    }
    eprintln!(
        "ideal wedges: corner's diffracted amplitude ≤ {worst_diffracted:.1e} × the direct's; \
         total field against the image sum ≤ {worst_field:.1e} relative"
    );
    assert!(worst_diffracted < 1e-12, "{worst_diffracted:e}");
    assert!(worst_field < 1e-12, "{worst_field:e}");
}

/// A path of one diffraction takes its own short way in the default mode (two straight legs,
/// no list of arrivals): the same ray, bit for bit, as the pieces' complete searches give it
/// (`"stationary": "all"`, the general code), for every vertex of an L-shaped room and of a
/// screen over a floor, media looked up and given, receivers everywhere (seen, behind the
/// walls, outside the room, on a wall).
#[test]
fn one_diffraction_takes_the_short_way_to_the_same_ray() {
    let mut rng = rng::SplitMix64(4141);
    let receivers: Vec<String> = (0..120)
        .map(|i| {
            if i == 0 {
                "[4, 1]".to_string()
            } else {
                format!(
                    "[{:e}, {:e}]",
                    -1.0 + 6.0 * rng.next_f64(),
                    -1.0 + 6.0 * rng.next_f64()
                )
            }
        })
        .collect();
    let mut paths = Vec::new();
    for k in 0..6 {
        paths.push(format!(
            r#"{{ "steps": [{{ "diffract": "room", "vertex": {k} }}] }}"#
        ));
        paths.push(format!(
            r#"{{ "steps": [{{ "diffract": "room", "vertex": {k} }}], "media": ["air", "air"] }}"#
        ));
    }
    for k in 0..2 {
        paths.push(format!(
            r#"{{ "steps": [{{ "diffract": "screen", "vertex": {k} }}] }}"#
        ));
    }
    let json = |mode: &str| {
        format!(
            r#"{{ "media": {{ "air": {{ "speed": 343, "at": [1, 1] }} }},
                 "interfaces": {{
                     "room": {{ "points": [[0, 0], [4, 0], [4, 2], [2, 2], [2, 4], [0, 4]],
                                "closed": true }},
                     "screen": {{ "points": [[0.5, 0.5], [1.5, 1.0]] }} }},
                 "sources": [[1, 3], [3.5, 0.5]], "receivers": [{}],
                 "paths": [{}],
                 "solver": {{ "stationary": "{mode}" }} }}"#,
            receivers.join(", "),
            paths.join(", ")
        )
    };
    let run = eigenray::options::Run::new();
    let batch = Tracer::new(scene(&json("one")))
        .unwrap()
        .trace_batch(&eigenray::BatchOptions::default(), &run)
        .unwrap();
    let all = Tracer::new(scene(&json("all")))
        .unwrap()
        .trace_stationary(&run)
        .unwrap();
    assert_eq!(batch.len(), all.triples.len());
    let (mut found, mut none) = (0, 0);
    for (i, t) in all.triples.iter().enumerate() {
        let r = batch.record(i);
        match t.arrivals.first() {
            Some(a) => {
                assert_eq!(t.arrivals.len(), 1);
                assert_eq!(r.status, a.status, "ray {i}");
                assert_eq!(r.time.to_bits(), a.time.to_bits(), "ray {i}");
                assert_eq!(r.reason, a.reason, "ray {i}");
                assert_eq!(batch.points(i), &a.points[..], "ray {i}");
                found += 1;
            }
            None => {
                assert_eq!(r.status, Status::NoPath, "ray {i}");
                assert!(r.time.is_nan());
                none += 1;
            }
        }
    }
    eprintln!("one diffraction: {found} rays with a path, {none} without, as the general code");
    assert!(found > 500 && none > 500, "{found} {none}");
}

/// The search's diffracted paths with reflections around the diffraction, against brute
/// force: on random small scenes (a floor, a ceiling and a bent fin, one medium), every
/// sequence of one `diffract` step and up to two reflections, each prescribed as a path
/// (`"stationary": "all"`), gives the same arrivals (the same sequences, as many per
/// sequence, times to 1e-12) as the search with `max_steps` 3 and `"diffraction": true`;
/// with `max_time` the search lists exactly those by that time.
#[test]
fn search_lists_every_path_reflected_around_a_diffraction() {
    let mut rng = rng::SplitMix64(4143);
    let mut compared = 0;
    let mut reflected = 0;
    for _ in 0..4 {
        let mut u = |a: f64, b: f64| a + (b - a) * rng.next_f64();
        let height = u(3.0, 5.0);
        let fin = [
            [u(-1.5, -0.5), u(0.5, 1.5)],
            [u(-0.3, 0.3), u(1.5, height - 1.0)],
            [u(0.5, 1.5), u(0.5, 1.5)],
        ];
        let mut point = || format!("[{:e}, {:e}]", u(-6.0, 6.0), u(0.2, height - 0.2));
        let sources: Vec<String> = (0..2).map(|_| point()).collect();
        let receivers: Vec<String> = (0..4).map(|_| point()).collect();
        let names = ["ceiling", "fin", "floor"];
        let counts = [2usize, 3, 2];
        // Every sequence: reflections before, the diffraction, reflections after.
        let mut sequences: Vec<Vec<(usize, Option<usize>)>> = Vec::new();
        let reflections: Vec<Vec<usize>> = (0..=2)
            .flat_map(|n| {
                (0..3usize.pow(n))
                    .map(move |code| (0..n).map(|j| code / 3usize.pow(j) % 3).collect::<Vec<_>>())
            })
            .collect();
        for (i, &count) in counts.iter().enumerate() {
            for k in 0..count {
                for before in &reflections {
                    for after in &reflections {
                        if before.len() + after.len() > 2 {
                            continue;
                        }
                        let mut seq: Vec<(usize, Option<usize>)> =
                            before.iter().map(|&j| (j, None)).collect();
                        seq.push((i, Some(k)));
                        seq.extend(after.iter().map(|&j| (j, None)));
                        sequences.push(seq);
                    }
                }
            }
        }
        let paths: Vec<String> = (sequences.iter())
            .map(|seq| {
                let steps: Vec<String> = (seq.iter())
                    .map(|&(i, v)| match v {
                        Some(k) => format!(r#"{{ "diffract": "{}", "vertex": {k} }}"#, names[i]),
                        None => format!(r#"{{ "reflect": "{}" }}"#, names[i]),
                    })
                    .collect();
                format!(r#"{{ "steps": [{}] }}"#, steps.join(", "))
            })
            .collect();
        let json = |tail: &str| {
            format!(
                r#"{{ "media": {{ "air": {{ "speed": 1 }} }}, "background": "air",
                     "interfaces": {{
                         "floor": {{ "points": [[-8, 0], [8, 0]] }},
                         "ceiling": {{ "points": [[8, {height:e}], [-8, {height:e}]] }},
                         "fin": {{ "points": [[{:e}, {:e}], [{:e}, {:e}], [{:e}, {:e}]] }} }},
                     "sources": [{}], "receivers": [{}] {tail} }}"#,
                fin[0][0],
                fin[0][1],
                fin[1][0],
                fin[1][1],
                fin[2][0],
                fin[2][1],
                sources.join(", "),
                receivers.join(", ")
            )
        };
        let run = eigenray::options::Run::new();
        let brute = Tracer::new(scene(&json(&format!(
            r#", "paths": [{}], "solver": {{ "stationary": "all" }}"#,
            paths.join(", ")
        ))))
        .unwrap()
        .trace_stationary(&run)
        .unwrap();
        let searched = Tracer::new(scene(&json(
            r#", "search": { "max_steps": 3, "diffraction": true }"#,
        )))
        .unwrap();
        let interface_names: Vec<&str> = (searched.scene().interfaces().iter())
            .map(|i| i.name.as_str())
            .collect();
        let report = searched.search(&run).unwrap();
        assert_eq!(report.incomplete_pairs, 0);
        // (source, receiver, sequence as names) -> times.
        type Key = (usize, usize, Vec<(String, Option<usize>)>);
        let mut want: std::collections::BTreeMap<Key, Vec<f64>> = Default::default();
        for t in &brute.triples {
            assert!(t.complete, "{t:?}");
            let seq: Vec<(String, Option<usize>)> = (sequences[t.path].iter())
                .map(|&(i, v)| (names[i].to_string(), v))
                .collect();
            for a in t.arrivals.iter().filter(|a| a.status == Status::Converged) {
                want.entry((t.source, t.receiver, seq.clone()))
                    .or_default()
                    .push(a.time);
            }
        }
        let mut got: std::collections::BTreeMap<Key, Vec<f64>> = Default::default();
        for a in report
            .arrivals
            .iter()
            .filter(|a| a.steps.iter().any(|s| s.kind.vertex().is_some()))
        {
            assert_eq!(a.arrival.status, Status::Converged);
            let seq: Vec<(String, Option<usize>)> = (a.steps.iter())
                .map(|s| (interface_names[s.interface].to_string(), s.kind.vertex()))
                .collect();
            got.entry((a.source, a.receiver, seq))
                .or_default()
                .push(a.arrival.time);
        }
        let missing: Vec<_> = want.keys().filter(|k| !got.contains_key(k)).collect();
        let extra: Vec<_> = got.keys().filter(|k| !want.contains_key(k)).collect();
        assert!(
            missing.is_empty() && extra.is_empty(),
            "missing {missing:?}, extra {extra:?}"
        );
        for (key, w) in &want {
            let mut w = w.clone();
            let mut g = got[key].clone();
            w.sort_by(f64::total_cmp);
            g.sort_by(f64::total_cmp);
            assert_eq!(w.len(), g.len(), "{key:?}");
            for (x, y) in w.iter().zip(&g) {
                assert!((x - y).abs() <= 1e-12 * x, "{key:?}: {x} {y}");
            }
            compared += w.len();
            reflected += usize::from(key.2.len() > 1) * w.len();
        }
        // A time bound: exactly the arrivals by then.
        let all_times: Vec<f64> = want.values().flatten().copied().collect();
        let bound = all_times.iter().sum::<f64>() / all_times.len() as f64;
        let timed = Tracer::new(scene(&json(&format!(
            r#", "search": {{ "max_steps": 3, "max_time": {bound:e}, "diffraction": true }}"#
        ))))
        .unwrap()
        .search(&run)
        .unwrap();
        let listed = (timed.arrivals.iter())
            .filter(|a| a.steps.iter().any(|s| s.kind.vertex().is_some()))
            .count();
        assert_eq!(listed, all_times.iter().filter(|&&t| t <= bound).count());
    }
    eprintln!("{compared} diffracted arrivals as brute force, {reflected} with reflections");
    assert!(reflected > 100, "{reflected}");
}

/// A half-plane (a screen's lower edge) above a reflecting floor: receivers stepping across
/// the shadow boundary of the source's floor image (the line from the image through the edge)
/// by 1e-9 rad see no jump in the total field (the pressure from the search's echoes) when
/// the search lists the path that reflects off the floor and then diffracts at the edge
/// (`max_steps` 2): 1e-8 dB; with the diffracted paths of one step only, the field jumps by
/// 8 dB there.
#[test]
fn a_reflected_then_diffracted_path_fills_the_image_shadow_edge() {
    use eigenray::response::{echoes_of_scene, pressure_into, transmission_loss};
    let tl = |max_steps: usize| {
        let (edge, image): ([f64; 2], [f64; 2]) = ([0.0, 2.0], [-3.0, -1.0]);
        let boundary = (edge[1] - image[1]).atan2(edge[0] - image[0]);
        let receivers: Vec<String> = [boundary - 1e-9, boundary + 1e-9]
            .iter()
            .map(|a| {
                format!(
                    "[{:e}, {:e}]",
                    edge[0] + 4.0 * a.cos(),
                    edge[1] + 4.0 * a.sin()
                )
            })
            .collect();
        let json = format!(
            r#"{{ "media": {{ "air": {{ "speed": 343 }} }}, "background": "air",
                 "interfaces": {{ "floor": {{ "points": [[-500, 0], [500, 0]] }},
                                 "screen": {{ "points": [[0, 2], [0, 300]] }} }},
                 "sources": [[-3, 1]], "receivers": [{}],
                 "search": {{ "max_steps": {max_steps}, "refract": false, "diffraction": true }},
                 "amplitudes": {{ "source": "point", "frequency": 250 }} }}"#,
            receivers.join(", ")
        );
        let tracer = Tracer::new(scene(&json)).unwrap();
        let run = eigenray::options::Run::new();
        let report = tracer.search(&run).unwrap();
        let reflected_first = (report.arrivals.iter())
            .filter(|a| a.steps.len() == 2 && a.steps[1].kind.vertex() == Some(0))
            .count();
        let echoes = echoes_of_scene(&tracer, &run).unwrap();
        let mut p = [Complex64::new(0.0, 0.0); 2];
        pressure_into(echoes, 250.0, 1, &run, &mut p);
        (
            [transmission_loss(p[0]), transmission_loss(p[1])],
            reflected_first,
        )
    };
    let ([a, b], n) = tl(2);
    eprintln!(
        "TL across the floor image's shadow edge, reflected-then-diffracted: {a:.9} dB, {b:.9} dB"
    );
    assert!(n >= 2, "{n}");
    assert!((a - b).abs() < 1e-5, "{a} {b}");
    let ([a, b], n) = tl(1);
    eprintln!("first-order diffraction only: {a:.3} dB, {b:.3} dB");
    assert_eq!(n, 0);
    assert!((a - b).abs() > 3.0, "{a} {b}");
}

/// Narrow wedges with edge-held arrivals listed (`"vertex": true`, so the walk searches the
/// reflect-only sequences completely too): a search of `max_steps` k with kα > π used to
/// mark every pair `complete: false` (alternate reflections that would turn about the corner
/// by π or more, and points beside a held corner on its own faces, were ruled out by a
/// threshold). Both are now ruled out by proof: every pair is complete, and the arrivals are
/// those of the beam tree's image method alone (`"vertex"` off), the same times.
#[test]
fn narrow_wedges_search_completely_past_their_ideal_order() {
    for big_n in [3u32, 4, 6] {
        let alpha = PI / f64::from(big_n);
        let polar = |r: f64, t: f64| [r * t.cos(), r * t.sin()];
        let far = polar(100.0, alpha);
        let (s, receivers) = (
            polar(2.0, 0.3 * alpha),
            [
                polar(3.0, 0.6 * alpha),
                polar(1.5, 0.8 * alpha),
                polar(4.0, 0.45 * alpha),
            ],
        );
        let doc = |vertex: bool| {
            format!(
                r#"{{ "media": {{ "air": {{ "speed": 1 }} }}, "background": "air",
                     "interfaces": {{ "wedge": {{ "points": [[100, 0], [0, 0], [{:e}, {:e}]] }} }},
                     "sources": [[{:e}, {:e}]],
                     "receivers": [[{:e}, {:e}], [{:e}, {:e}], [{:e}, {:e}]],
                     "search": {{ "max_steps": {}, "refract": false, "vertex": {vertex} }} }}"#,
                far[0],
                far[1],
                s[0],
                s[1],
                receivers[0][0],
                receivers[0][1],
                receivers[1][0],
                receivers[1][1],
                receivers[2][0],
                receivers[2][1],
                big_n + 2
            )
        };
        let search = |vertex| {
            Tracer::new(scene(&doc(vertex)))
                .unwrap()
                .search(&eigenray::options::Run::new())
                .unwrap()
        };
        let (with, images) = (search(true), search(false));
        assert_eq!(with.incomplete_pairs, 0, "N = {big_n}");
        assert!(with.arrivals.iter().all(|a| a.complete), "N = {big_n}");
        let converged = |r: &eigenray::search::SearchReport| {
            let mut t: Vec<(usize, f64)> = (r.arrivals.iter())
                .filter(|a| a.arrival.status == Status::Converged)
                .map(|a| (a.receiver, a.arrival.time))
                .collect();
            t.sort_by(|a, b| a.partial_cmp(b).unwrap());
            t
        };
        let (a, b) = (converged(&with), converged(&images));
        assert_eq!(a.len(), b.len(), "N = {big_n}");
        for (x, y) in a.iter().zip(&b) {
            assert!(
                x.0 == y.0 && (x.1 - y.1).abs() <= 1e-12 * y.1,
                "N = {big_n}: {x:?} {y:?}"
            );
        }
    }
}
