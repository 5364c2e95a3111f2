//! Derivatives of a ray's time through a `profile` medium: every entry of the gradient
//! (source, receiver, the medium's slowness, each knot's speed, the walls' vertices) of every
//! arrival of a leg against central differences of the re-solved time (the arrival found
//! again by its launch angle), on a Munk-like profile (turning rays, several arrivals of one
//! leg) and a waveguide (reflected rays); an isovelocity profile against the straight legs'
//! derivatives; and the command line's `"derivatives": true` through `"stationary": "all"`
//! and a search.

use eigenray::options::Run;
use eigenray::{Arrival, Gradient, Scene, Tracer};
use serde_json::{Value, json};

/// The Munk profile `c(z) = 1500 (1 + 0.00737 (η − 1 + e^(−η)))`, `η = 2 (z − 1300)/1300`,
/// at `n` knots from 0 to 5000 m depth (y = −z).
fn munk(n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let z = 5000.0 * i as f64 / (n - 1) as f64;
            let eta = 2.0 * (z - 1300.0) / 1300.0;
            [-z, 1500.0 * (1.0 + 0.00737 * (eta - 1.0 + (-eta).exp()))]
        })
        .collect()
}

/// Every stationary path of path 0 from source 0 to receiver 0 of `doc`.
fn arrivals(doc: &Value) -> (Scene, Vec<Arrival>) {
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let tracer = Tracer::new(scene.clone()).unwrap();
    let mut out = Vec::new();
    let (s, r) = (scene.sources()[0], scene.receivers()[0]);
    tracer
        .stationary_paths(s, r, 0, &Run::new(), &mut out)
        .unwrap();
    (scene, out)
}

/// The arrival of `found` that is `target` (the same turns and first direction, the nearest
/// launch angle).
fn same<'a>(found: &'a [Arrival], target: &Arrival) -> &'a Arrival {
    let angle = |a: &Arrival| a.launch_angle.unwrap();
    found
        .iter()
        .filter(|a| a.turns == target.turns && angle(a).signum() == angle(target).signum())
        .min_by(|a, b| {
            let (da, db) = (angle(a) - angle(target), angle(b) - angle(target));
            da.abs().total_cmp(&db.abs())
        })
        .expect("the arrival found again")
}

/// The central difference of `target`'s time when `change(doc, d)` moves something by `d`.
fn difference(doc: &Value, target: &Arrival, h: f64, change: &dyn Fn(&mut Value, f64)) -> f64 {
    let at = |d: f64| {
        let mut doc = doc.clone();
        change(&mut doc, d);
        let (_, found) = arrivals(&doc);
        same(&found, target).time
    };
    (at(h) - at(-h)) / (2.0 * h)
}

/// Adds `d` to the number at `pointer`.
fn nudge(doc: &mut Value, pointer: &str, d: f64) {
    let v = doc
        .pointer_mut(pointer)
        .unwrap_or_else(|| panic!("{pointer}"));
    *v = json!(v.as_f64().unwrap() + d);
}

/// Checks every derivative of every arrival of `doc`'s path 0 (the medium `medium` with
/// `knots` knots; `walls`: interfaces whose height is moved as a whole) against central
/// differences: `tol_c` absolute on `dT/dc`, `tol_x` on the positions' and walls'.
fn check_all(doc: &Value, medium: &str, knots: usize, walls: &[&str], tol: [f64; 2]) -> usize {
    let [tol_c, tol_x] = tol;
    let (scene, found) = arrivals(doc);
    let m = scene.medium_index(medium).unwrap();
    let steps = &scene.paths()[0].steps;
    for a in &found {
        let g = Gradient::of_arrival(&scene, steps, a).unwrap();
        let what = format!("arrival at {} s, turns {:?}", a.time, a.turns);
        assert_eq!(g.profile_speed[m].len(), knots, "{what}");
        for k in 0..knots {
            let pointer = format!("/media/{medium}/profile/{k}/1");
            let fd = difference(doc, a, 1e-3, &|d, h| nudge(d, &pointer, h));
            let got = g.profile_speed[m][k];
            assert!(
                (got - fd).abs() <= tol_c,
                "{what}: knot {k}: {got} against {fd}"
            );
        }
        // The slowness entry: w = 1/c of the first knot, every knot moved alike.
        let c0 = doc["media"][medium]["profile"][0][1].as_f64().unwrap();
        let shift = difference(doc, a, 1e-3, &|d, h| {
            for k in 0..knots {
                nudge(d, &format!("/media/{medium}/profile/{k}/1"), h);
            }
        });
        let got = g.slowness[m];
        assert!(
            (got - -c0 * c0 * shift).abs() <= tol_c * c0 * c0,
            "{what}: slowness {got} against {}",
            -c0 * c0 * shift
        );
        for (end, d) in [("sources", g.source), ("receivers", g.receiver)] {
            for (i, v) in [d.x, d.y].into_iter().enumerate() {
                let pointer = format!("/{end}/0/{i}");
                let fd = difference(doc, a, 1e-2, &|d, h| nudge(d, &pointer, h));
                assert!(
                    (v - fd).abs() <= tol_x,
                    "{what}: {end} {i}: {v} against {fd}"
                );
            }
        }
        for wall in walls {
            let i = scene.interface_index(wall).unwrap();
            let count = doc["interfaces"][wall]["points"].as_array().unwrap().len();
            let fd = difference(doc, a, 1e-2, &|d, h| {
                for v in 0..count {
                    nudge(d, &format!("/interfaces/{wall}/points/{v}/1"), h);
                }
            });
            let got: f64 = (g.vertices.iter())
                .filter(|v| v.interface == i)
                .map(|v| v.d.y)
                .sum();
            assert!(
                (got - fd).abs() <= tol_x,
                "{what}: {wall}: {got} against {fd}"
            );
            assert!(g.vertices.iter().all(|v| v.d.x == 0.0));
        }
    }
    found.len()
}

/// The Munk profile at 11 knots, source at 1000 m, receiver at 60 km and 800 m: three
/// arrivals of the one leg (two and three turning points, up and down first), each
/// derivative against central differences.
#[test]
fn munk_arrivals_match_finite_differences() {
    let doc = json!({
        "media": { "ocean": { "profile": munk(11) } },
        "sources": [[0, -1000]], "receivers": [[60000, -800]],
        "paths": [{ "steps": [], "media": ["ocean"] }]
    });
    let n = check_all(&doc, "ocean", 11, &[], [2e-9, 1e-9]);
    assert_eq!(n, 3, "{n} arrivals");
}

/// A waveguide 200 m deep with a five-knot profile (its end knots beyond the walls), a
/// surface and a bottom: the rays of
/// paths reflecting once, twice and three times (five rays of three bottom reflections,
/// turning between them), each derivative against central differences, the walls' heights
/// included.
#[test]
fn reflected_arrivals_match_finite_differences() {
    // (The walls inside layers: at a knot the speed's kink puts an error of the order of
    // the step into a central difference of the wall's height.)
    let knots = [
        [20.0, 1521.0],
        [-30.0, 1512.0],
        [-70.0, 1496.0],
        [-130.0, 1493.0],
        [-230.0, 1506.0],
    ];
    let mut total = 0;
    let b = json!({ "reflect": "bottom" });
    let t = json!({ "reflect": "surface" });
    for (steps, receiver) in [
        (json!([b]), [2500, -150]),
        (json!([t, b]), [2500, -150]),
        (json!([b, t]), [2500, -150]),
        (json!([b, t, b]), [2500, -150]),
        // Five rays of one sequence, turning three or four times between the reflections.
        (json!([b, b, b]), [10000, -120]),
    ] {
        let legs = steps.as_array().unwrap().len() + 1;
        let doc = json!({
            "media": { "water": { "profile": knots } },
            "background": "water",
            "interfaces": {
                "surface": { "points": [[-1000, 0], [3000, 0], [12000, 0]] },
                "bottom": { "points": [[-1000, -200], [12000, -200]] }
            },
            "sources": [[0, -40]], "receivers": [receiver],
            "paths": [{ "steps": steps, "media": vec!["water"; legs] }]
        });
        total += check_all(&doc, "water", 5, &["surface", "bottom"], [2e-9, 1e-9]);
    }
    assert_eq!(total, 9, "{total} arrivals");
}

/// An isovelocity profile between walls is the uniform medium: each arrival's gradient
/// (source, receiver, slowness, every vertex share) is the straight legs' to 1e-12, and the
/// knots' derivatives add up to `−length / c²`.
#[test]
fn isovelocity_profile_is_the_uniform_medium() {
    let doc = |water: Value| {
        json!({
            "media": { "water": water },
            "background": "water",
            "interfaces": {
                "surface": { "points": [[-1000, 0], [700, 0], [10000, 0]] },
                "bottom": { "points": [[-1000, -100], [10000, -100]] }
            },
            "sources": [[0, -30]], "receivers": [[1500, -70]],
            "paths": [{ "steps": [{ "reflect": "surface" }, { "reflect": "bottom" }],
                        "media": ["water", "water", "water"] }]
        })
    };
    let c = 1500.0;
    let (scene, iso) = arrivals(&doc(json!({ "profile": [[0, c], [-40, c], [-100, c]] })));
    let (uniform_scene, uniform) = arrivals(&doc(json!({ "speed": c })));
    assert_eq!(iso.len(), 1);
    assert_eq!(uniform.len(), 1);
    let steps = &scene.paths()[0].steps;
    let a = Gradient::of_arrival(&scene, steps, &iso[0]).unwrap();
    let b = Gradient::of_arrival(&uniform_scene, steps, &uniform[0]).unwrap();
    let near = |x: f64, y: f64| (x - y).abs() <= 1e-12 * (1.0 + y.abs());
    assert!(
        near(a.source.x, b.source.x) && near(a.source.y, b.source.y),
        "{a:?} {b:?}"
    );
    assert!(near(a.receiver.x, b.receiver.x) && near(a.receiver.y, b.receiver.y));
    assert!(near(a.slowness[0], b.slowness[0]), "{a:?} {b:?}");
    assert_eq!(a.vertices.len(), b.vertices.len());
    for (u, v) in a.vertices.iter().zip(&b.vertices) {
        assert_eq!((u.interface, u.vertex), (v.interface, v.vertex));
        assert!(near(u.d.x, v.d.x) && near(u.d.y, v.d.y), "{u:?} {v:?}");
    }
    let length = b.slowness[0];
    let sum: f64 = a.profile_speed[0].iter().sum();
    assert!(near(sum, -length / (c * c)), "{sum}");
    assert!(b.profile_speed.is_empty() && a.speed_gradient.is_empty());
}

/// Runs `eigenray solve` on `doc` with `args`, returning standard output.
fn solve(doc: &Value, args: &[&str]) -> Vec<u8> {
    let dir = std::env::temp_dir().join(format!(
        "eigenray-profile-d-{}-{}",
        std::process::id(),
        args.join("")
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("scene.json");
    std::fs::write(&file, doc.to_string()).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .arg("solve")
        .arg(&file)
        .args(args)
        .output()
        .unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// The command line: every entry of `"stationary": "all"` (several rays of one leg) and
/// every search arrival carries its own gradient with `profile_speed`, the library's
/// [`Gradient::of_arrival`] of the same ray; CSV has the gradient columns.
#[test]
fn command_line_entries_carry_their_own_gradients() {
    let knots = munk(11);
    let mut doc = json!({
        "media": { "ocean": { "profile": knots } },
        "sources": [[0, -1000]], "receivers": [[60000, -800]],
        "paths": [{ "steps": [], "media": ["ocean"] }],
        "solver": { "derivatives": true, "stationary": "all" }
    });
    let (scene, found) = arrivals(&doc);
    let written: Value = serde_json::from_slice(&solve(&doc, &[])).unwrap();
    let rays = written["rays"].as_array().unwrap();
    assert_eq!(rays.len(), found.len());
    assert_eq!(found.len(), 3);
    let near = |x: f64, y: f64| (x - y).abs() <= 1e-12 * (1.0 + y.abs());
    for (ray, a) in rays.iter().zip(&found) {
        let g = Gradient::of_arrival(&scene, &[], a).unwrap();
        let knots_written = ray["gradient"]["profile_speed"]["ocean"]
            .as_array()
            .unwrap();
        assert_eq!(knots_written.len(), 11, "{ray}");
        for (w, d) in knots_written.iter().zip(&g.profile_speed[0]) {
            assert!(near(w.as_f64().unwrap(), *d), "{ray}");
        }
        let source = &ray["gradient"]["source"];
        assert!(near(source[1].as_f64().unwrap(), g.source.y), "{ray}");
    }
    // The arrivals differ: each has its own derivatives.
    let first = &found[0];
    let other = Gradient::of_arrival(&scene, &[], &found[1]).unwrap();
    assert_ne!(
        Gradient::of_arrival(&scene, &[], first)
            .unwrap()
            .profile_speed,
        other.profile_speed
    );
    let csv = String::from_utf8(solve(&doc, &["--format", "csv"])).unwrap();
    assert!(csv.lines().next().unwrap().contains("gradient_slowness"));
    // A search in a waveguide: every arrival (direct, reflected) has its gradient, that of
    // its path's stationary ray with the same launch angle.
    doc = json!({
        "media": { "water": { "profile": [[0, 1520], [-70, 1496], [-200, 1503]] } },
        "background": "water",
        "interfaces": {
            "surface": { "points": [[-1000, 0], [10000, 0]] },
            "bottom": { "points": [[-1000, -200], [10000, -200]] }
        },
        "sources": [[0, -40]], "receivers": [[2500, -150]],
        "search": { "max_steps": 3 },
        "solver": { "derivatives": true }
    });
    let written: Value = serde_json::from_slice(&solve(&doc, &[])).unwrap();
    let listed = written["arrivals"].as_array().unwrap();
    assert!(listed.len() >= 5, "{written}");
    for entry in listed {
        let steps: Vec<Value> = entry["steps"].as_array().unwrap().clone();
        let legs = steps.len() + 1;
        let mut path = doc.clone();
        path.as_object_mut().unwrap().remove("search");
        path["paths"] = json!([{ "steps": steps, "media": vec!["water"; legs] }]);
        let (scene, found) = arrivals(&path);
        let angle = entry["launch_angle"].as_f64().unwrap();
        let a = (found.iter())
            .find(|a| (a.launch_angle.unwrap() - angle).abs() < 1e-12)
            .unwrap_or_else(|| panic!("{entry}"));
        let g = Gradient::of_arrival(&scene, &scene.paths()[0].steps, a).unwrap();
        let written = entry["gradient"]["profile_speed"]["water"]
            .as_array()
            .unwrap();
        for (w, d) in written.iter().zip(&g.profile_speed[0]) {
            assert!(near(w.as_f64().unwrap(), *d), "{entry}");
        }
        let slowness = entry["gradient"]["slowness"]["water"].as_f64().unwrap();
        assert!(near(slowness, g.slowness[0]), "{entry}");
    }
}

/// The gradients of many rays as flat rows ([`GradientRows`], what Python's
/// `Tracer.gradients(rays)` computes) through a profile: each row the ray of its launch angle,
/// bit for bit the gradient of that arrival ([`Gradient::of_arrival`], checked against
/// central differences above), with each knot's `dT/dc`; without the launch angles every row
/// is the default mode's ray, so rows of different rays between the same points differ only
/// with them.
#[test]
fn rows_with_launch_angles_are_each_arrivals_gradient() {
    use eigenray::derivatives::{GradientArraysMut, GradientRows};
    let doc = json!({
        "media": { "ocean": { "profile": munk(11) } },
        "sources": [[0, -1000]], "receivers": [[60000, -800]],
        "paths": [{ "steps": [], "media": ["ocean"] }]
    });
    let (scene, found) = arrivals(&doc);
    assert_eq!(found.len(), 3);
    let n = found.len();
    let codes = eigenray::output::STATUS_CODES;
    let converged = codes.iter().position(|s| s.has_time()).unwrap() as u8;
    let points: Vec<f64> = found
        .iter()
        .flat_map(|a| a.points.iter().flat_map(|p| [p.x, p.y]))
        .collect();
    let launch: Vec<f64> = found.iter().map(|a| a.launch_angle.unwrap()).collect();
    let knots = GradientArraysMut::profile_speed_width(&scene);
    assert_eq!(knots, 11);
    assert_eq!(GradientArraysMut::speed_gradient_width(&scene), 0);
    let rows_of = |launch_angles: Option<&[f64]>| {
        let rows = GradientRows {
            paths: &vec![0; n],
            statuses: &vec![converged; n],
            status_of_code: &codes,
            width: 2,
            points: &points,
            num_points: &vec![2; n],
            media: &vec![0; n],
            launch_angles,
        };
        let (mut source, mut receiver, mut slowness) =
            (vec![0.0; 2 * n], vec![0.0; 2 * n], vec![0.0; n]);
        let mut profile_speed = vec![0.0; n * knots];
        rows.gradients_into(
            &scene,
            GradientArraysMut {
                source: &mut source,
                receiver: &mut receiver,
                slowness: &mut slowness,
                vertex_interface: &mut [],
                vertex: &mut [],
                vertex_d: &mut [],
                speed_gradient: &mut [],
                profile_speed: &mut profile_speed,
            },
        );
        (source, receiver, slowness, profile_speed)
    };
    let (source, receiver, slowness, profile_speed) = rows_of(Some(&launch));
    let steps = &scene.paths()[0].steps;
    for (i, a) in found.iter().enumerate() {
        let g = Gradient::of_arrival(&scene, steps, a).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            bits(&source[2 * i..2 * i + 2]),
            bits(&[g.source.x, g.source.y])
        );
        assert_eq!(
            bits(&receiver[2 * i..2 * i + 2]),
            bits(&[g.receiver.x, g.receiver.y])
        );
        assert_eq!(slowness[i].to_bits(), g.slowness[0].to_bits());
        assert_eq!(
            bits(&profile_speed[knots * i..knots * (i + 1)]),
            bits(&g.profile_speed[0])
        );
    }
    // The three rays leave the source in three directions: their rows differ.
    assert!(source[0] != source[2] && source[2] != source[4] && source[0] != source[4]);
    // Without launch angles each row is the default mode's ray: all alike.
    let (source, _, _, _) = rows_of(None);
    assert!(source[0] == source[2] && source[2] == source[4]);
}
