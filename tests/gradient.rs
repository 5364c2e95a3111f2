//! Media with a speed gradient (curved legs): prescribed paths through circular arcs against
//! closed forms (the design note's caustic example, a seismic reflection, Snell's law between
//! two gradient media), brute force (every stationary point of a sequence by scanning starts,
//! and by sampling the time along a reflector), the obstruction of an arc whose chord is
//! clear, region lookup, and the validation of the keys.

use std::process::Command;

use eigenray::problem::PathProblem;
use eigenray::{Arrival, Point, Scene, Status, Tracer, Workspace};

/// The design note's caustic example (§5, check 4) with y up: water (1500 m/s) above
/// y = −200, below it c = 1500 + 0.1 (−200 − y); source and receiver at y = 0, 10 km apart.
/// Path 0 gives its media, path 1 looks them up.
const CAUSTIC: &str = r#"{
  "media": {
    "water": { "speed": 1500, "at": [5000, -100] },
    "rock": { "speed": 1480, "gradient": [0, -0.1], "at": [5000, -1000] }
  },
  "interfaces": { "floor": { "points": [[-1000, -200], [11000, -200]] } },
  "domain": [[-1000, -5000], [11000, 100]],
  "sources": [[0, 0]], "receivers": [[10000, 0]],
  "paths": [
    { "steps": [{ "refract": "floor" }, { "refract": "floor" }], "media": ["water", "rock", "water"] },
    { "steps": [{ "refract": "floor" }, { "refract": "floor" }] }
  ]
}"#;

/// The caustic example's closed forms for the take-off angle θ (from the horizontal): the
/// range `X(θ) = 2h cot θ + 2 (c₀/g) tan θ` and the time `T(θ) = 2h / (c₀ sin θ) + (2/g)
/// atanh(sin θ)`.
fn caustic_range_and_time(theta: f64) -> (f64, f64) {
    let (h, c0, g) = (200.0, 1500.0, 0.1);
    (
        2.0 * h / theta.tan() + 2.0 * (c0 / g) * theta.tan(),
        2.0 * h / (c0 * theta.sin()) + 2.0 / g * theta.sin().atanh(),
    )
}

/// The number of negative pivots of the LDLᵀ factorisation of a symmetric tridiagonal
/// matrix (its Morse index).
fn negative_pivots(diag: &[f64], off: &[f64]) -> usize {
    let mut d = diag[0];
    let mut count = usize::from(d < 0.0);
    for i in 1..diag.len() {
        d = diag[i] - off[i - 1] * off[i - 1] / d;
        count += usize::from(d < 0.0);
    }
    count
}

/// Every stationary path of the caustic example's sequence, by brute force: Newton from a
/// grid of 24 × 24 starts over the interface. Exactly the two eigenrays of the design note
/// (6.672526446116 s and 6.628258089353 s), each on the closed forms' range and time at its
/// take-off angle, with Morse index 1 (past the caustic) and 0.
#[test]
fn the_caustic_example_has_exactly_two_eigenrays() {
    let scene = Scene::from_json(CAUSTIC).unwrap();
    let tracer = Tracer::new(scene.clone()).unwrap();
    let mut ws = Workspace::new();
    let mut found: Vec<(f64, Vec<f64>)> = Vec::new();
    for i in 0..24 {
        for j in 0..24 {
            let guess = [500.0 * i as f64 + 250.0, 500.0 * j as f64 + 250.0];
            let r = tracer.solve_indexed_from(0, 0, 0, Some(&guess), &mut ws);
            if r.status != Status::Converged {
                continue;
            }
            if !found.iter().any(|(t, _)| (t - r.time).abs() < 1e-9) {
                found.push((r.time, ws.parameters().to_vec()));
            }
        }
    }
    found.sort_by(|a, b| b.0.total_cmp(&a.0));
    let times: Vec<f64> = found.iter().map(|f| f.0).collect();
    assert_eq!(times.len(), 2, "{times:?}");
    let expected = [(6.672526446116, 1), (6.628258089353, 0)];
    let problem = PathProblem::new(&scene, 0, Point::new(0.0, 0.0), Point::new(10000.0, 0.0))
        .expect("media given");
    for ((time, params), (t, index)) in found.iter().zip(expected) {
        assert!((time - t).abs() < 1e-11, "{time} {t}");
        // The take-off angle from the first crossing (x = s − 1000 on the floor).
        let theta = (200.0 / (params[0] - 1000.0)).atan();
        let (range, closed) = caustic_range_and_time(theta);
        assert!((range - 10000.0).abs() < 1e-6, "{range}");
        // (The angle from the solved point carries its round-off, times dT/dθ ≈ 100 s.)
        assert!((closed - time).abs() < 1e-9, "{closed} {time}");
        let h = problem.hessian(params);
        assert_eq!(negative_pivots(&h.diag, &h.off), index, "{h:?}");
    }
    // Region lookup finds the same media and the same ray from the default start.
    let given = tracer.solve_indexed_from(0, 0, 0, None, &mut ws);
    let looked_up = tracer.solve_indexed_from(0, 0, 1, None, &mut ws);
    assert_eq!(looked_up.status, Status::Converged);
    // (Media in name order: rock 0, water 1.)
    assert_eq!(ws.media(), &[1, 0, 1]);
    assert!((looked_up.time - given.time).abs() < 1e-12);
}

/// A seismic reflection in `v = v₀ + k z` (z down) off a flat reflector at depth `h`, for
/// offsets up to 6 km: the reflection time against the classical closed form `T = (2/k)
/// acosh(1 + k² (x²/4 + h²) / (2 v₀ v_h))` (the reflection point mid-way), and, by sampling
/// the path's time every metre along the reflector, that it has exactly one stationary point.
#[test]
fn seismic_reflections_match_the_closed_form() {
    let (v0, k, h) = (2000.0, 0.6, 1500.0);
    let offsets: Vec<f64> = (1..=30).map(|i| 200.0 * i as f64).collect();
    let receivers: Vec<String> = offsets.iter().map(|x| format!("[{x}, 0]")).collect();
    let json = format!(
        r#"{{
          "media": {{ "rock": {{ "speed": {v0}, "gradient": [0, {g}] }} }},
          "interfaces": {{ "reflector": {{ "points": [[-1000, {y}], [8000, {y}]] }} }},
          "domain": [[-1000, -3000], [8000, 10]],
          "sources": [[0, 0]], "receivers": [{r}],
          "paths": [{{ "steps": [{{ "reflect": "reflector" }}], "media": ["rock", "rock"] }}]
        }}"#,
        g = -k,
        y = -h,
        r = receivers.join(", ")
    );
    let scene = Scene::from_json(&json).unwrap();
    let tracer = Tracer::new(scene.clone()).unwrap();
    let mut ws = Workspace::new();
    let vh = v0 + k * h;
    for (i, x) in offsets.iter().enumerate() {
        let r = tracer.solve_indexed_from(0, i, 0, None, &mut ws);
        assert_eq!(r.status, Status::Converged, "{x}");
        let closed = 2.0 / k * (1.0 + k * k * (x * x / 4.0 + h * h) / (2.0 * v0 * vh)).acosh();
        assert!(
            (r.time - closed).abs() < 1e-12 * closed,
            "{x}: {} {closed}",
            r.time
        );
        assert!(
            (ws.points()[1].x - x / 2.0).abs() < 1e-6,
            "{:?}",
            ws.points()
        );
        // Brute force: the sampled time along the reflector has one local minimum.
        let p = PathProblem::new(&scene, 0, Point::new(0.0, 0.0), Point::new(*x, 0.0)).unwrap();
        let t: Vec<f64> = (0..=9000).map(|s| p.time(&[s as f64])).collect();
        let minima: Vec<usize> = (1..t.len() - 1)
            .filter(|&s| t[s] <= t[s - 1] && t[s] <= t[s + 1])
            .collect();
        assert_eq!(minima.len(), 1, "{x}: {minima:?}");
        assert!((minima[0] as f64 - 1000.0 - x / 2.0).abs() <= 1.0);
    }
}

/// The unit tangent, at `p`, of the circle through `a` and `b` whose centre lies where the
/// speed `c0 + g · q` is zero, pointing from `a` towards `b` along the arc that keeps off
/// that line: the ray's direction by geometry alone (the design note's §2).
fn circle_tangent(c0: f64, g: [f64; 2], a: Point, b: Point, p: Point) -> [f64; 2] {
    let speed = |q: [f64; 2]| c0 + g[0] * q[0] + g[1] * q[1];
    let m = [(a.x + b.x) / 2.0, (a.y + b.y) / 2.0];
    let n = [-(b.y - a.y), b.x - a.x];
    // m + t n on the line c = 0.
    let t = -speed(m) / (g[0] * n[0] + g[1] * n[1]);
    let centre = [m[0] + t * n[0], m[1] + t * n[1]];
    let radius = [p.x - centre[0], p.y - centre[1]];
    let r = radius[0].hypot(radius[1]);
    let mut tangent = [-radius[1] / r, radius[0] / r];
    // Orient it from a to b: the chord's direction has a positive component along the
    // tangent at its middle, and the tangent turns smoothly along the arc.
    let chord = [b.x - a.x, b.y - a.y];
    let ra = [a.x - centre[0], a.y - centre[1]];
    let turns_left = ra[0] * chord[1] - ra[1] * chord[0] > 0.0;
    if !turns_left {
        tangent = [-tangent[0], -tangent[1]];
    }
    tangent
}

/// Snell's law at a flat interface between two media with different gradients: at the
/// converged crossing the horizontal slowness `cos θ / c` of the two arcs (their directions
/// by the circle construction, not by the solver's formulas) is the same, to 1e-12.
#[test]
fn snell_between_two_gradient_media() {
    let json = r#"{
      "media": {
        "air": { "speed": 1500, "gradient": [0.01, -0.05] },
        "ground": { "speed": 1700, "gradient": [-0.02, -0.12] }
      },
      "interfaces": { "flat": { "points": [[-5000, 0], [9000, 0]] } },
      "domain": [[-5000, -3000], [9000, 3000]],
      "sources": [[0, 800]], "receivers": [[4000, -1200], [2500, -2000], [1000, -2500]],
      "paths": [{ "steps": [{ "refract": "flat" }], "media": ["air", "ground"] }]
    }"#;
    let scene = Scene::from_json(json).unwrap();
    let tracer = Tracer::new(scene).unwrap();
    let mut ws = Workspace::new();
    for r in 0..3 {
        let ray = tracer.solve_indexed_from(0, r, 0, None, &mut ws);
        assert_eq!(ray.status, Status::Converged);
        let [s, x, rcv] = [ws.points()[0], ws.points()[1], ws.points()[2]];
        let above = circle_tangent(1500.0, [0.01, -0.05], s, x, x);
        let below = circle_tangent(1700.0, [-0.02, -0.12], x, rcv, x);
        let (c1, c2) = (1500.0 + 0.01 * x.x, 1700.0 - 0.02 * x.x);
        let (p1, p2) = (above[0] / c1, below[0] / c2);
        assert!((p1 - p2).abs() < 1e-12 * p1.abs(), "{p1} {p2}");
        // Both arcs go down through the interface.
        assert!(above[1] < 0.0 && below[1] < 0.0);
    }
}

/// A direct ray whose arc bulges through a screen its chord passes above is obstructed; the
/// same screen mirrored above the chord does not touch the arc.
#[test]
fn an_arc_is_obstructed_where_its_chord_is_not() {
    // c = 1500 − 0.1 y: rays turn towards the lower speed (up), so the arc from (0, 0) to
    // (10000, 0), centred on the line c = 0 (y = 15000), dips 811 m below its chord.
    let scene = |y: f64| {
        let (lo, hi) = (y.min(3.0 * y), y.max(3.0 * y));
        format!(
            r#"{{
              "media": {{ "air": {{ "speed": 1500, "gradient": [0, -0.1] }} }},
              "interfaces": {{ "screen": {{ "points": [[5000, {lo}], [5000, {hi}]] }} }},
              "domain": [[-100, -2000], [10100, 2000]],
              "sources": [[0, 0]], "receivers": [[10000, 0]],
              "paths": [{{ "steps": [], "media": ["air"] }}]
            }}"#
        )
    };
    let mut ws = Workspace::new();
    let below = Tracer::new(Scene::from_json(&scene(-500.0)).unwrap()).unwrap();
    let r = below.solve_indexed_from(0, 0, 0, None, &mut ws);
    assert_eq!(r.status, Status::Obstructed);
    let above = Tracer::new(Scene::from_json(&scene(500.0)).unwrap()).unwrap();
    let r = above.solve_indexed_from(0, 0, 0, None, &mut ws);
    assert_eq!(r.status, Status::Converged);
    // The direct arc's time, against the design note's leg time for these ends.
    let g: f64 = 0.1;
    let closed = 2.0 / g * (g * 10000.0 / (2.0 * 1500.0)).asinh();
    assert!((r.time - closed).abs() < 1e-12 * closed);
}

/// A gradient of almost zero gives the uniform medium's time to rounding (no `1/g`).
#[test]
fn a_tiny_gradient_is_the_uniform_medium() {
    let json = |gradient: &str| {
        format!(
            r#"{{
              "media": {{ "a": {{ "speed": 1500 {gradient} }}, "b": {{ "speed": 1800 }} }},
              "interfaces": {{ "flat": {{ "points": [[-5000, 0], [9000, 0]] }} }},
              "sources": [[0, 800]], "receivers": [[4000, -1200]],
              "paths": [{{ "steps": [{{ "refract": "flat" }}], "media": ["a", "b"] }}]
            }}"#
        )
    };
    let mut ws = Workspace::new();
    let uniform = Tracer::new(Scene::from_json(&json("")).unwrap()).unwrap();
    let t0 = uniform.solve_indexed_from(0, 0, 0, None, &mut ws).time;
    for g in ["1e-9", "1e-13", "0"] {
        let text = json(&format!(r#", "gradient": [0, {g}]"#));
        let curved = Tracer::new(Scene::from_json(&text).unwrap()).unwrap();
        let t = curved.solve_indexed_from(0, 0, 0, None, &mut ws).time;
        assert!((t - t0).abs() < 1e-9 * t0, "{g}: {t} {t0}");
    }
}

/// Bad gradients are refused naming the key: a speed reaching 0 in the domain, a gradient
/// on an `index` medium, a gradient that is not two finite numbers, and what curved legs do
/// not support yet (`search`, `derivatives`, a `diffract` step). The
/// command-line tool exits with status 2 naming the key.
#[test]
fn bad_gradients_are_refused_naming_the_key() {
    let with = |media: &str, extra: &str| {
        format!(
            r#"{{
              "media": {{ {media} }},
              "interfaces": {{ "flat": {{ "points": [[-5000, 0], [9000, 0]] }} }},
              "domain": [[-5000, -3000], [9000, 3000]],
              "sources": [[0, 800]], "receivers": [[4000, 1200]],
              "paths": [{{ "steps": [{{ "reflect": "flat" }}], "media": ["a", "a"] }}]
              {extra}
            }}"#
        )
    };
    let cases = [
        (
            with(r#""a": { "speed": 1500, "gradient": [0, 1] }"#, ""),
            "media.a.gradient",
        ),
        (
            with(r#""a": { "index": 1.5, "gradient": [0, 0.1] }"#, ""),
            "media.a.gradient",
        ),
        (
            with(r#""a": { "speed": 1500, "gradient": [0] }"#, ""),
            "media",
        ),
        (
            with(
                r#""a": { "speed": 1500, "gradient": [0, 0.1] }"#,
                r#", "search": { "max_steps": 1, "diffraction": true }"#,
            ),
            "search.diffraction",
        ),
    ];
    // A diffracted path through a medium with a gradient: refused at its step.
    let diffracted = with(r#""a": { "speed": 1500, "gradient": [0, 0.1] }"#, "").replace(
        r#"{ "reflect": "flat" }"#,
        r#"{ "diffract": "flat", "vertex": 0 }"#,
    );
    let err = Scene::from_json(&diffracted).expect_err("diffract");
    assert_eq!(err.key, "paths[0].steps[0]", "{err}");
    for (text, key) in &cases {
        let err = Scene::from_json(text).expect_err(key);
        assert!(err.key.starts_with(key), "{key}: {err}");
    }
    // The speed of 1500 + y reaches 0 at y = −1500, inside the domain: the message names it.
    let err = Scene::from_json(&cases[0].0).unwrap_err();
    assert!(err.message.contains("reaches"), "{err}");
    // The command-line tool: exit status 2, the key on standard error.
    let dir = std::env::temp_dir().join(format!("eigenray-gradient-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.json");
    std::fs::write(&file, &cases[0].0).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .arg("solve")
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("media.a.gradient"));
    // And a good gradient scene solves from the command line, its time the arc's.
    let good = dir.join("good.json");
    std::fs::write(&good, CAUSTIC).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .arg("solve")
        .arg(&good)
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("6.6725264461"));
    std::fs::remove_dir_all(&dir).ok();
}

/// Every stationary path of the caustic example's sequence through the tracer
/// (`stationary_paths`, and `"stationary": "all"` from the command line): the two eigenrays
/// of the brute force above, ordered by time, for both paths (media given and looked up);
/// the search through arcs says it is no proof (`complete` false).
#[test]
fn stationary_paths_lists_both_caustic_eigenrays() {
    let scene = Scene::from_json(CAUSTIC).unwrap();
    let tracer = Tracer::new(scene).unwrap();
    let mut out: Vec<Arrival> = Vec::new();
    for path in 0..2 {
        let (s, r) = (Point::new(0.0, 0.0), Point::new(10000.0, 0.0));
        let outcome = tracer
            .stationary_paths(s, r, path, &eigenray::options::Run::new(), &mut out)
            .unwrap();
        assert!(!outcome.complete);
        let times: Vec<f64> = out.iter().map(|a| a.time).collect();
        assert_eq!(times.len(), 2, "{times:?}");
        assert!((times[0] - 6.628258089353).abs() < 1e-11, "{times:?}");
        assert!((times[1] - 6.672526446116).abs() < 1e-11, "{times:?}");
        assert!(out.iter().all(|a| a.status == Status::Converged));
    }
    let all = CAUSTIC.replace(
        r#""sources""#,
        r#""solver": { "stationary": "all" }, "sources""#,
    );
    let dir = std::env::temp_dir().join(format!("eigenray-all-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("all.json");
    std::fs::write(&file, all).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .arg("solve")
        .arg(&file)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(text.matches("6.6282580893").count(), 2, "{text}");
    assert_eq!(text.matches("6.6725264461").count(), 2, "{text}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The angle from the horizontal, down positive, of the arc from `a` to `b` in the medium
/// `c = c0 + (0, gy) · p` at `p` (one of its ends), by circle geometry.
fn dip(c0: f64, gy: f64, a: Point, b: Point, p: Point) -> f64 {
    let t = circle_tangent(c0, [0.0, gy], a, b, p);
    (-t[1]).atan2(t[0])
}

/// The spreading of a direct arc in the ocean gradient of the design note (c = 1500 + 0.017
/// depth, source at 100 m, a receiver near 6 km of arc at 10° down) against the dynamic-ray
/// closed form `J = |sin θ_r − sin θ₀| / (g ξ² c_s)` (`ξ = cos θ₀ / c_s`, the angles by circle
/// geometry): the axisymmetric source's `√(c_r cos θ₀ / (c_s r J)) / (4π)` (BELLHOP's
/// `|p|` over 4π) and the point source's `√(c_r / (c_s J ∫c ds / c_s)) / (4π)` with
/// `∫ c ds = |sin θ_r − sin θ₀| / (g ξ²)`; and J near the note's 6030.8975 m/rad.
#[test]
fn arc_spreading_matches_the_dynamic_ray_closed_form() {
    let json = |source: &str| {
        format!(
            r#"{{
              "media": {{ "sea": {{ "speed": 1500, "gradient": [0, -0.017] }} }},
              "domain": [[-10, -3000], [8000, 10]],
              "sources": [[0, -100]], "receivers": [[5939.27, -943.56]],
              "paths": [{{ "steps": [], "media": ["sea"] }}],
              "amplitudes": {{ "source": "{source}" }}
            }}"#
        )
    };
    let (g, s, r) = (0.017, Point::new(0.0, -100.0), Point::new(5939.27, -943.56));
    let (cs, cr) = (1500.0 + g * 100.0, 1500.0 + g * 943.56);
    let (th0, thr) = (dip(1500.0, -g, s, r, s), dip(1500.0, -g, s, r, r));
    let xi = th0.cos() / cs;
    let q = (thr.sin() - th0.sin()).abs() / (g * xi * xi);
    let j = q / cs;
    assert!((j - 6030.8975).abs() < 1e-3 * j, "{j}");
    assert!(
        (th0.to_degrees() - 10.0).abs() < 1e-3,
        "{}",
        th0.to_degrees()
    );
    let quarter = 0.25 / std::f64::consts::PI;
    let expected = [
        (
            "axisymmetric",
            (cr * th0.cos() / (cs * r.x * j)).sqrt() * quarter,
        ),
        ("point", (cr / (cs * j * q / cs)).sqrt() * quarter),
    ];
    let mut ws = Workspace::new();
    for (source, want) in expected {
        let tracer = Tracer::new(Scene::from_json(&json(source)).unwrap()).unwrap();
        let record = tracer.solve_indexed_from(0, 0, 0, None, &mut ws);
        assert_eq!(record.status, Status::Converged);
        let a = tracer.amplitude(0, &record, &ws).expect("an amplitude");
        assert!(a.reason.is_none(), "{a:?}");
        assert!(
            (a.spreading - want).abs() < 1e-9 * want,
            "{source}: {} {want}",
            a.spreading
        );
    }
}

/// The caustic example's amplitudes: the ray past the caustic (Morse index 1) has the
/// phase −π/2 of one caustic, the other none; both have the same transmission coefficients'
/// sign (real, positive: no critical angle), so their values' phases differ by π/2.
#[test]
fn a_caustic_turns_the_phase_by_a_quarter() {
    let json = CAUSTIC.replace(
        r#""sources""#,
        r#""amplitudes": { "source": "point" }, "sources""#,
    );
    let tracer = Tracer::new(Scene::from_json(&json).unwrap()).unwrap();
    let mut out: Vec<Arrival> = Vec::new();
    let (s, r) = (Point::new(0.0, 0.0), Point::new(10000.0, 0.0));
    tracer
        .stationary_paths(s, r, 0, &eigenray::options::Run::new(), &mut out)
        .unwrap();
    assert_eq!(out.len(), 2);
    let phases: Vec<f64> = out
        .iter()
        .map(|a| a.amplitude.as_ref().expect("an amplitude").value.arg())
        .collect();
    // Ordered by time: index 0 first, then the ray past the caustic.
    assert!(phases[0].abs() < 1e-12, "{phases:?}");
    assert!(
        (phases[1] + std::f64::consts::FRAC_PI_2).abs() < 1e-12,
        "{phases:?}"
    );
    for a in &out {
        let amp = a.amplitude.as_ref().unwrap();
        assert!(amp.spreading > 0.0 && amp.spreading.is_finite());
        assert!(amp.coefficient.norm() > 0.0);
    }
}

/// The `caustics` column through gradient media: the caustic example's two eigenrays have
/// the design note's Morse indices (1 past the caustic, 0 before it), which the path
/// Hessian's pivots give independently, in the stationary paths (Rust) and in the
/// command line's JSON, with `"stationary": "all"` and in the default mode.
#[test]
fn the_caustics_column_counts_the_morse_index_through_arcs() {
    let scene = Scene::from_json(CAUSTIC).unwrap();
    let tracer = Tracer::new(scene.clone()).unwrap();
    let (s, r) = (Point::new(0.0, 0.0), Point::new(10000.0, 0.0));
    let problem = PathProblem::new(&scene, 0, s, r).expect("media given");
    let mut out: Vec<Arrival> = Vec::new();
    tracer
        .stationary_paths(s, r, 0, &eigenray::options::Run::new(), &mut out)
        .unwrap();
    let caustics: Vec<Option<u32>> = out.iter().map(|a| a.caustics).collect();
    // Ordered by time: before the caustic (6.628 s), then past it (6.673 s).
    assert_eq!(caustics, [Some(0), Some(1)]);
    for a in &out {
        let h = problem.hessian(&a.parameters);
        let index = negative_pivots(&h.diag, &h.off);
        assert_eq!(a.caustics, Some(index as u32), "{h:?}");
    }
    let dir = std::env::temp_dir().join(format!("eigenray-caustics-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let all = CAUSTIC.replace(
        r#""sources""#,
        r#""solver": { "stationary": "all" }, "sources""#,
    );
    // (time, caustics) of every ray of the command line's JSON for `json`.
    let solve = |name: &str, json: &str| -> Vec<(f64, f64)> {
        let file = dir.join(name);
        std::fs::write(&file, json).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_eigenray"))
            .arg("solve")
            .arg(&file)
            .output()
            .unwrap();
        assert!(out.status.success());
        let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        doc["rays"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| (r["time"].as_f64().unwrap(), r["caustics"].as_f64().unwrap()))
            .collect()
    };
    let rays = solve("all.json", &all);
    assert_eq!(rays.len(), 4, "{rays:?}");
    for (time, caustics) in rays {
        let want = if (time - 6.672526446116).abs() < 1e-11 {
            1.0
        } else {
            assert!((time - 6.628258089353).abs() < 1e-11, "{time}");
            0.0
        };
        assert_eq!(caustics, want, "{time}");
    }
    // The default mode finds the ray past the caustic for both paths.
    let rays = solve("default.json", CAUSTIC);
    assert_eq!(rays.len(), 2, "{rays:?}");
    for (time, caustics) in rays {
        assert!((time - 6.672526446116).abs() < 1e-11, "{time}");
        assert_eq!(caustics, 1.0);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The command line's `--svg` draws a leg through a gradient medium as its arc: a direct ray
/// in the design note's ocean gradient (`c = 1500 − 0.017 y`), its polyline's points mapped
/// back through the affine map its two ends give (the source and the receiver), all within
/// 1e-6 of the radius of the circle through both ends whose centre lies where `c = 0`,
/// computed here; the points run monotonically from the source to the receiver.
#[test]
fn the_svg_draws_an_arc_on_its_circle() {
    let json = r#"{
      "media": { "sea": { "speed": 1500, "gradient": [0, -0.017] } },
      "domain": [[-10, -3000], [8000, 10]],
      "sources": [[0, -100]], "receivers": [[5939.27, -943.56]],
      "paths": [{ "steps": [], "media": ["sea"] }]
    }"#;
    let (s, r): ([f64; 2], [f64; 2]) = ([0.0, -100.0], [5939.27, -943.56]);
    // The centre (xc, yc): yc where c = 0, xc equidistant from s and r.
    let yc: f64 = 1500.0 / 0.017;
    let xc = ((r[0] * r[0] - s[0] * s[0]) + (r[1] - yc).powi(2) - (s[1] - yc).powi(2))
        / (2.0 * (r[0] - s[0]));
    let radius = ((s[0] - xc).powi(2) + (s[1] - yc).powi(2)).sqrt();
    let dir = std::env::temp_dir().join(format!("eigenray-svg-arc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (file, svg) = (dir.join("arc.json"), dir.join("arc.svg"));
    std::fs::write(&file, json).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .arg("solve")
        .arg(&file)
        .arg("--svg")
        .arg(&svg)
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = std::fs::read_to_string(&svg).unwrap();
    let rays = text.split(r#"<g class="rays""#).nth(1).unwrap();
    let attr = rays.split(r#"<polyline points=""#).nth(1).unwrap();
    let pixels: Vec<[f64; 2]> = attr[..attr.find('"').unwrap()]
        .split(' ')
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            [x.parse().unwrap(), y.parse().unwrap()]
        })
        .collect();
    // (At least 8 pieces a leg.)
    assert!(pixels.len() >= 9, "{pixels:?}");
    let (p0, p1) = (pixels[0], pixels[pixels.len() - 1]);
    let world = |p: [f64; 2]| {
        [
            s[0] + (p[0] - p0[0]) / (p1[0] - p0[0]) * (r[0] - s[0]),
            s[1] + (p[1] - p0[1]) / (p1[1] - p0[1]) * (r[1] - s[1]),
        ]
    };
    let mut last = f64::NEG_INFINITY;
    for p in &pixels {
        let [x, y] = world(*p);
        let off = ((x - xc).powi(2) + (y - yc).powi(2)).sqrt() - radius;
        assert!(off.abs() < 1e-6 * radius, "{x} {y}: {off}");
        assert!(x > last, "{x} after {last}");
        last = x;
    }
    // The arc bulges off its chord (by its sagitta, tens of metres here).
    let mid = world(pixels[pixels.len() / 2]);
    let chord_y = s[1] + (mid[0] - s[0]) / (r[0] - s[0]) * (r[1] - s[1]);
    assert!((mid[1] - chord_y).abs() > 10.0, "{mid:?} {chord_y}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A direct arc that bulges far below its ends (`c = 1500 − 0.1 y`, ends 10 km apart at
/// y = 0, no domain: the circle's lowest point at `15000 − √(5000² + 15000²)` ≈ −811): the
/// picture's plot holds every drawn point of it, and its `caustics` is 0 (a direct ray's
/// Hessian has no rows).
#[test]
fn the_svg_frame_holds_a_bulging_arc() {
    let json = r#"{
      "media": { "sea": { "speed": 1500, "gradient": [0, -0.1] } },
      "sources": [[0, 0]], "receivers": [[10000, 0]],
      "paths": [{ "steps": [], "media": ["sea"] }]
    }"#;
    let dir = std::env::temp_dir().join(format!("eigenray-svg-bulge-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (file, svg) = (dir.join("bulge.json"), dir.join("bulge.svg"));
    std::fs::write(&file, json).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .arg("solve")
        .arg(&file)
        .arg("--svg")
        .arg(&svg)
        .output()
        .unwrap();
    assert!(out.status.success());
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(doc["rays"][0]["caustics"].as_f64(), Some(0.0));
    let text = std::fs::read_to_string(&svg).unwrap();
    // The plot's box: the rectangle filled #fafafa.
    let rect = text
        .lines()
        .find(|l| l.starts_with("<rect") && l.contains("#fafafa"))
        .unwrap();
    let attr = |name: &str| -> f64 {
        let at = rect.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
        rect[at..at + rect[at..].find('"').unwrap()]
            .parse()
            .unwrap()
    };
    let (x0, y0) = (attr("x"), attr("y"));
    let (x1, y1) = (x0 + attr("width"), y0 + attr("height"));
    let rays = text.split(r#"<g class="rays""#).nth(1).unwrap();
    let points = rays.split(r#"<polyline points=""#).nth(1).unwrap();
    let pixels: Vec<(f64, f64)> = points[..points.find('"').unwrap()]
        .split(' ')
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect();
    assert!(pixels.len() >= 9);
    for (x, y) in &pixels {
        assert!(
            *x >= x0 && *x <= x1 && *y >= y0 && *y <= y1,
            "{x} {y}: {rect}"
        );
    }
    // The lowest point is well below the ends (which are at one height).
    let lowest = pixels.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    assert!(
        lowest - pixels[0].1 > 0.5 * (y1 - y0),
        "{lowest} {}",
        pixels[0].1
    );
    std::fs::remove_dir_all(&dir).ok();
}
