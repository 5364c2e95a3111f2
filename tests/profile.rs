//! Media with a speed profile (`media.NAME.profile`: the speed piecewise linear in y,
//! BELLHOP's `'C'`): every ray of a path without steps against independent references — the
//! same medium given as a `gradient` (the arc kernel, its Hessian sweep for amplitudes), the
//! closed form of a turning arc, Simpson quadrature of the ray integrals through two layers,
//! the design note's caustic example — the `turns` and `caustics` columns in every format,
//! and the validation of the key.

use std::process::Command;

use eigenray::options::Run;
use eigenray::{Point, Scene, Status, Tracer};

/// A scene of one medium `medium` (a JSON object), a path without steps through it, and
/// `extra` keys.
fn scene(medium: &str, sources: &str, receivers: &str, extra: &str) -> Scene {
    Scene::from_json(&format!(
        r#"{{ "media": {{ "sea": {medium} }},
             "sources": {sources}, "receivers": {receivers},
             "paths": [{{ "steps": [], "media": ["sea"] }}] {extra} }}"#
    ))
    .unwrap()
}

/// Every stationary path of each (source, receiver) ray of `scene`, by time.
fn arrivals(scene: &Scene) -> Vec<Vec<eigenray::Arrival>> {
    let tracer = Tracer::new(scene).unwrap();
    let mut out = Vec::new();
    for &s in scene.sources() {
        for &r in scene.receivers() {
            let mut a = Vec::new();
            tracer
                .stationary_paths(s, r, 0, &Run::new(), &mut a)
                .unwrap();
            out.push(a);
        }
    }
    out
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs())
}

/// A profile of two knots is one linear layer: between points inside it, the one ray of the
/// same medium given as `speed` + `gradient` (the arc kernel), its time to 1e-13 and its
/// amplitude (the ray-parameter form's `∂X/∂p` against the arc's Hessian blocks) to 1e-9.
#[test]
fn one_layer_is_the_gradient_medium() {
    let sources = "[[0, -300], [0, -2500]]";
    let receivers = "[[5000, -300], [-3000, -2000], [12000, -2500], [700, -4900]]";
    let amplitudes = r#", "amplitudes": { "source": "point" }"#;
    let profile = scene(
        r#"{ "profile": [[0, 1500], [-5000, 1585]] }"#,
        sources,
        receivers,
        amplitudes,
    );
    let gradient = scene(
        r#"{ "speed": 1500, "gradient": [0, -0.017] }"#,
        sources,
        receivers,
        amplitudes,
    );
    let (a, b) = (
        Tracer::new(&profile).unwrap().trace_all(),
        Tracer::new(&gradient).unwrap().trace_all(),
    );
    let mut worst = [0.0f64; 2];
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.status, Status::Converged, "{x:?}");
        assert_eq!(y.status, Status::Converged, "{y:?}");
        worst[0] = worst[0].max(rel(x.time, y.time));
        let (ax, ay) = (x.amplitude.unwrap(), y.amplitude.unwrap());
        worst[1] = worst[1].max((ax.value - ay.value).norm() / ay.value.norm());
    }
    println!(
        "one layer against the gradient medium: time {:e}, amplitude {:e}",
        worst[0], worst[1]
    );
    assert!(worst[0] < 1e-13, "{worst:?}");
    assert!(worst[1] < 1e-9, "{worst:?}");
    // Exactly one ray each (above the top knot the speed is constant: no ray comes back).
    for list in arrivals(&profile) {
        assert_eq!(list.len(), 1);
    }
}

/// The design note's turning arc (c = 1500 + 0.017 depth, both ends at 100 m depth, 20 km
/// apart): one ray, one turning point, `T = (2/g) asinh(g L / (2c)) = 13.289955753698131 s`.
#[test]
fn a_turning_ray_has_the_closed_form_time() {
    let s = scene(
        r#"{ "profile": [[0, 1500], [-5000, 1585]] }"#,
        "[[0, -100]]",
        "[[20000, -100]]",
        r#", "solver": { "stationary": "all" }"#,
    );
    let list = &arrivals(&s)[0];
    assert_eq!(list.len(), 1);
    let (g, c, l) = (0.017f64, 1500.0 + 0.017 * 100.0, 20000.0f64);
    let closed = 2.0 / g * (g * l / (2.0 * c)).asinh();
    assert!((closed - 13.289_955_753_698_13).abs() < 1e-12);
    assert!(
        rel(list[0].time, closed) < 1e-13,
        "{} {closed}",
        list[0].time
    );
    assert_eq!(list[0].turns, Some(1));
    assert_eq!(list[0].caustics, Some(0));
}

/// Simpson's rule on the ray integrals `X = ∫ p c / √(1 − p²c²) dy`, `T = ∫ 1 / (c √(1 −
/// p²c²)) dy` between `y1` and `y2` (no turning point between them), layer by layer.
fn simpson(knots: &[[f64; 2]], p: f64, y1: f64, y2: f64) -> (f64, f64) {
    let speed = |y: f64| {
        let i = knots
            .windows(2)
            .position(|w| y <= w[0][0] && y >= w[1][0])
            .unwrap();
        let ([ya, ca], [yb, cb]) = (knots[i], knots[i + 1]);
        ca + (cb - ca) * (y - ya) / (yb - ya)
    };
    let (lo, hi) = (y1.min(y2), y1.max(y2));
    let mut cuts = vec![lo];
    cuts.extend(knots.iter().map(|k| k[0]).filter(|&y| y > lo && y < hi));
    cuts.push(hi);
    cuts.sort_by(f64::total_cmp);
    let (mut x, mut t) = (0.0, 0.0);
    for w in cuts.windows(2) {
        let n = 20000;
        let h = (w[1] - w[0]) / n as f64;
        for i in 0..=n {
            // The layer's own speed at its ends (the profile kinks at knots).
            let y = (w[0] + h * i as f64).clamp(w[0] + 1e-9 * h, w[1] - 1e-9 * h);
            let c = speed(y);
            let s = (1.0 - p * p * c * c).sqrt();
            let k = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            x += k * h / 3.0 * p * c / s;
            t += k * h / 3.0 / (c * s);
        }
    }
    (x, t)
}

/// Two layers (a sound channel, its axis at y = −1000): the direct ray (no turning point)
/// between points in different layers against Simpson quadrature of the ray integrals with
/// `p` found by bisection, to 1e-9.
#[test]
fn two_layers_match_quadrature() {
    let knots = [[0.0, 1520.0], [-1000.0, 1490.0], [-3000.0, 1530.0]];
    let s = scene(
        r#"{ "profile": [[0, 1520], [-1000, 1490], [-3000, 1530]] }"#,
        "[[0, -500]]",
        "[[3000, -2500], [1500, -1200], [-4000, -2900]]",
        "",
    );
    let lists = arrivals(&s);
    let (a, receivers) = (s.sources()[0], s.receivers());
    for (r, list) in receivers.iter().zip(&lists) {
        let dx = (r.x - a.x).abs();
        // Bisection on p over the direct branch, X increasing in p.
        let (mut lo, mut hi) = (0.0, 1.0 / 1530.0 * (1.0 - 1e-12));
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if simpson(&knots, mid, a.y, r.y).0 < dx {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let (_, t) = simpson(&knots, 0.5 * (lo + hi), a.y, r.y);
        let direct: Vec<_> = list.iter().filter(|x| x.turns == Some(0)).collect();
        assert_eq!(direct.len(), 1, "{r:?}");
        let e = rel(direct[0].time, t);
        println!(
            "two layers, receiver {r:?}: {} s against {t} s ({e:e})",
            direct[0].time
        );
        assert!(e < 1e-9, "{r:?}: {e:e}");
        // Every ray listed lands on the receiver's time order.
        assert!(list.windows(2).all(|w| w[0].time <= w[1].time));
    }
}

/// The design note's caustic example through a profile (a uniform layer of 200 m over
/// c = 1500 + 0.1 (depth − 200)): exactly two rays, 6.628258089353 s (no caustic) and
/// 6.672526446116 s (one caustic: the phase −π/2), each with one turning point; their
/// amplitudes equal those of the same medium as two media and two refractions (the arc
/// kernel's Hessian sweep, caustic counted by its negative pivot) to 1e-7.
#[test]
fn the_caustic_example_through_a_profile() {
    let amplitudes = r#", "amplitudes": { "source": "point" }, "solver": { "stationary": "all" }"#;
    let s = scene(
        r#"{ "profile": [[0, 1500], [-200, 1500], [-5200, 2000]] }"#,
        "[[0, 0]]",
        "[[10000, 0]]",
        amplitudes,
    );
    let list = &arrivals(&s)[0];
    let times: Vec<f64> = list.iter().map(|a| a.time).collect();
    assert_eq!(times.len(), 2, "{times:?}");
    assert!((times[0] - 6.628258089353).abs() < 1e-11, "{times:?}");
    assert!((times[1] - 6.672526446116).abs() < 1e-11, "{times:?}");
    let caustics: Vec<_> = list.iter().map(|a| a.caustics).collect();
    assert_eq!(caustics, [Some(0), Some(1)]);
    assert!(list.iter().all(|a| a.turns == Some(1)));
    let phase = list[1].amplitude.unwrap().coefficient.arg();
    assert!((phase + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    // The same medium as water over a gradient half-space, two refractions.
    let two_media = Scene::from_json(
        r#"{
      "media": {
        "water": { "speed": 1500, "at": [5000, -100] },
        "rock": { "speed": 1480, "gradient": [0, -0.1], "at": [5000, -1000] }
      },
      "interfaces": { "floor": { "points": [[-1000, -200], [11000, -200]] } },
      "domain": [[-1000, -5000], [11000, 100]],
      "sources": [[0, 0]], "receivers": [[10000, 0]],
      "paths": [{ "steps": [{ "refract": "floor" }, { "refract": "floor" }],
                  "media": ["water", "rock", "water"] }],
      "amplitudes": { "source": "point" }
    }"#,
    )
    .unwrap();
    let tracer = Tracer::new(&two_media).unwrap();
    let mut other = Vec::new();
    tracer
        .stationary_paths(
            Point::new(0.0, 0.0),
            Point::new(10000.0, 0.0),
            0,
            &Run::new(),
            &mut other,
        )
        .unwrap();
    assert_eq!(other.len(), 2);
    for (x, y) in list.iter().zip(&other) {
        assert!(rel(x.time, y.time) < 1e-12);
        let (ax, ay) = (x.amplitude.unwrap().value, y.amplitude.unwrap().value);
        let e = (ax - ay).norm() / ay.norm();
        println!("caustic example amplitude {ax} against {ay} ({e:e})");
        assert!(e < 1e-7, "{ax} {ay}");
    }
}

/// An interface across the profile's rays makes the ones that cross it `obstructed`; the
/// default mode's ray is the earliest that crosses nothing.
#[test]
fn interfaces_obstruct_rays() {
    let s = Scene::from_json(
        r#"{ "media": { "sea": { "profile": [[0, 1500], [-200, 1500], [-5200, 2000]] } },
             "interfaces": { "wall": { "points": [[5000, -600], [5000, -100000]] } },
             "sources": [[0, 0]], "receivers": [[10000, 0]],
             "paths": [{ "steps": [], "media": ["sea"] }] }"#,
    )
    .unwrap();
    // The steep ray (6.628 s) turns deeper than 600 m at x = 5000; the shallow one does not.
    let list = &arrivals(&s)[0];
    let status: Vec<Status> = list.iter().map(|a| a.status).collect();
    assert_eq!(status, [Status::Obstructed, Status::Converged]);
    let ray = &Tracer::new(&s).unwrap().trace_all()[0];
    assert_eq!(ray.status, Status::Converged);
    assert!((ray.time - 6.672526446116).abs() < 1e-11);
}

/// The `turns` and `caustics` columns in JSON, CSV and `.npy` for a scene with a profile,
/// and none of them for a scene without one.
#[test]
fn turns_and_caustics_are_columns() {
    let dir = std::env::temp_dir().join(format!("eigenray-profile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("caustic.json");
    std::fs::write(
        &file,
        r#"{ "media": { "sea": { "profile": [[0, 1500], [-200, 1500], [-5200, 2000]] } },
             "sources": [[0, 0]], "receivers": [[10000, 0]],
             "paths": [{ "steps": [], "media": ["sea"] }],
             "solver": { "stationary": "all" } }"#,
    )
    .unwrap();
    let run = |format: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_eigenray"))
            .args(["solve", "--format", format])
            .arg(&file)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        out.stdout
    };
    let json = String::from_utf8(run("json")).unwrap();
    assert!(json.contains(r#""turns":1.0,"caustics":0.0"#), "{json}");
    assert!(json.contains(r#""turns":1.0,"caustics":1.0"#), "{json}");
    let csv = String::from_utf8(run("csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(
        header.ends_with(",turns,caustics") || header.contains(",turns,caustics,"),
        "{header}"
    );
    let npy = run("npy");
    let head = String::from_utf8_lossy(&npy[..1024.min(npy.len())]).to_string();
    assert!(
        head.contains("('turns', '<f8'), ('caustics', '<f8')"),
        "{head}"
    );
    // The default mode: the earliest ray, its turns and caustics.
    let text = std::fs::read_to_string(&file)
        .unwrap()
        .replace(r#""stationary": "all""#, r#""stationary": "one""#);
    std::fs::write(&file, text).unwrap();
    let json = String::from_utf8(run("json")).unwrap();
    assert!(
        json.contains(r#""time":6.6282580893"#) && json.contains(r#""turns":1.0,"caustics":0.0"#),
        "{json}"
    );
    // A scene without a profile writes neither column.
    std::fs::write(
        &file,
        r#"{ "media": { "sea": { "speed": 1500 } }, "sources": [[0, 0]], "receivers": [[10, 0]],
             "paths": [{ "steps": [], "media": ["sea"] }] }"#,
    )
    .unwrap();
    let json = String::from_utf8(run("json")).unwrap();
    assert!(
        !json.contains("turns") && !json.contains("caustics"),
        "{json}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Bad profiles are refused naming the key, and what profile scenes do not support yet.
/// The command-line tool exits with status 2 naming the key.
#[test]
fn bad_profiles_are_refused_naming_the_key() {
    let with = |medium: &str, steps: &str, extra: &str| {
        format!(
            r#"{{ "media": {{ "sea": {medium} }},
                 "interfaces": {{ "floor": {{ "points": [[-10, -900], [9000, -900]] }} }},
                 "sources": [[0, -100]], "receivers": [[4000, -200]],
                 "paths": [{{ "steps": [{steps}], "media": ["sea"{more}] }}] {extra} }}"#,
            more = if steps.is_empty() { "" } else { r#", "sea""# }
        )
    };
    let good = r#"{ "profile": [[0, 1500], [-1000, 1490]] }"#;
    let cases = [
        (
            with(r#"{ "profile": [[0, 1500]] }"#, "", ""),
            "media.sea.profile",
        ),
        (with(r#"{ "profile": [] }"#, "", ""), "media.sea.profile"),
        (
            with(r#"{ "profile": [[0, 1500], [0, 1490]] }"#, "", ""),
            "media.sea.profile[1]",
        ),
        (
            with(r#"{ "profile": [[-10, 1500], [0, 1490]] }"#, "", ""),
            "media.sea.profile[1]",
        ),
        (
            with(r#"{ "profile": [[0, 1500], [-10, 0]] }"#, "", ""),
            "media.sea.profile[1]",
        ),
        (
            with(
                r#"{ "speed": 1500, "profile": [[0, 1500], [-10, 1490]] }"#,
                "",
                "",
            ),
            "media.sea.profile",
        ),
        (
            with(
                r#"{ "index": 1.3, "profile": [[0, 1500], [-10, 1490]] }"#,
                "",
                "",
            ),
            "media.sea.profile",
        ),
        (
            with(
                r#"{ "profile": [[0, 1500], [-10, 1490]], "gradient": [0, 1] }"#,
                "",
                "",
            ),
            "media.sea.gradient",
        ),
        (
            with(good, r#"{ "refract": "floor" }"#, ""),
            "paths[0].steps[0]",
        ),
        (
            with(
                good,
                "",
                r#", "search": { "max_steps": 2, "diffraction": true }"#,
            ),
            "search.diffraction",
        ),
    ];
    for (text, key) in &cases {
        let err = Scene::from_json(text).expect_err(key);
        assert_eq!(err.key, *key, "{err}");
    }
    Scene::from_json(&with(good, "", "")).unwrap();
    // Derivatives through a profile are taken (tests/profile_derivatives.rs).
    Scene::from_json(&with(good, "", r#", "solver": { "derivatives": true }"#)).unwrap();
    // A sloping interface: a reflection off it is taken (tests/profile_slope.rs), and so is
    // the search (a closed interface is not).
    let sloping =
        with(good, r#"{ "reflect": "floor" }"#, "").replace("[9000, -900]", "[9000, -950]");
    Scene::from_json(&sloping).unwrap();
    // Derivatives off a sloping wall are taken (tests/profile_slope_derivatives.rs).
    let with_derivatives = with(
        good,
        r#"{ "reflect": "floor" }"#,
        r#", "solver": { "derivatives": true }"#,
    )
    .replace("[9000, -900]", "[9000, -950]");
    assert!(
        Scene::from_json(&with_derivatives)
            .unwrap()
            .solver()
            .derivatives
    );
    let sloping =
        with(good, "", r#", "search": { "max_steps": 2 }"#).replace("[9000, -900]", "[9000, -950]");
    Scene::from_json(&sloping).unwrap();
    let closed = sloping.replace("-950]] }", r#"-950], [4000, -990]], "closed": true }"#);
    let err = Scene::from_json(&closed).unwrap_err();
    assert_eq!(err.key, "search", "{err}");
    assert!(err.to_string().contains("interfaces.floor"), "{err}");
    // A profile medium's speed is its knots: `set_medium_speed` refuses.
    let mut s = Scene::from_json(&with(good, "", "")).unwrap();
    let err = s.set_medium_speed(0, 1500.0).unwrap_err();
    assert_eq!(err.key, "media.sea.profile");
    // The document reads back to the same scene.
    let back = Scene::from_json(&s.to_json()).unwrap();
    assert_eq!(back.media()[0].profile, s.media()[0].profile);
    // The command-line tool: exit status 2, the key on standard error.
    let dir = std::env::temp_dir().join(format!("eigenray-profile-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.json");
    std::fs::write(&file, &cases[2].0).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .arg("solve")
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("media.sea.profile[1]"));
    std::fs::remove_dir_all(&dir).ok();
}
