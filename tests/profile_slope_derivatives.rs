//! Derivatives of a ray's time through a `profile` medium off sloping walls (each leg the
//! profile's ray between its ends): every column of the gradient (source, receiver, the
//! medium's slowness, each knot's speed, each coordinate of each wall vertex) of every
//! arrival of several paths against central differences of the re-solved time (the arrival
//! found again by its turns and nearest launch angle); an isovelocity profile against the
//! uniform medium's straight legs; the default mode's gradient and the command line's
//! `"derivatives": true`.

use std::process::Command;

use eigenray::options::Run;
use eigenray::{Arrival, Gradient, Scene, Status, Tracer, Workspace};
use serde_json::{Value, json};

/// Knots whose layers hold the walls (a surface at 0, a bottom between −95 and −125): at a
/// knot the speed's kink would put an error of the order of the step into a central
/// difference of a wall's height.
const KNOTS: [[f64; 2]; 5] = [
    [20.0, 1521.0],
    [-30.0, 1512.0],
    [-70.0, 1496.0],
    [-130.0, 1493.0],
    [-230.0, 1506.0],
];

/// A waveguide with a flat surface at 0 and a bottom sloping from −95 m to −118 m at 2 km
/// and −125 m at 7 km, the medium `water`, the paths `steps`.
fn doc(water: Value, steps: Value, receiver: [f64; 2]) -> Value {
    let legs = steps.as_array().unwrap().len() + 1;
    json!({
        "media": { "water": water },
        "background": "water",
        "interfaces": {
            "surface": { "points": [[-1000, 0], [7000, 0]], "reflection": "pressure-release" },
            "bottom": { "points": [[-1000, -95], [2000, -118], [7000, -125]], "reflection": "rigid" }
        },
        "sources": [[0, -40]], "receivers": [receiver],
        "paths": [{ "steps": steps, "media": vec!["water"; legs] }]
    })
}

/// Every stationary path of path 0 from source 0 to receiver 0 of `doc` with a time
/// (`obstructed` ones too: a ray that grazes the bottom is one or the other as a knot moves
/// by 1e-3 m/s, and its time is the same stationary time).
fn arrivals(doc: &Value) -> (Scene, Vec<Arrival>) {
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let tracer = Tracer::new(scene.clone()).unwrap();
    let mut out = Vec::new();
    let (s, r) = (scene.sources()[0], scene.receivers()[0]);
    tracer
        .stationary_paths(s, r, 0, &Run::new(), &mut out)
        .unwrap();
    out.retain(|a| a.status.has_time());
    (scene, out)
}

/// The arrival of `found` that is `target` (the same turns, the nearest launch angle).
fn same<'a>(found: &'a [Arrival], target: &Arrival, what: &str) -> &'a Arrival {
    let angle = |a: &Arrival| a.launch_angle.unwrap();
    found
        .iter()
        .filter(|a| a.turns == target.turns)
        .min_by(|a, b| {
            let (da, db) = (angle(a) - angle(target), angle(b) - angle(target));
            da.abs().total_cmp(&db.abs())
        })
        .unwrap_or_else(|| panic!("{what}: {target:?} not found again in {found:?}"))
}

/// Adds `d` to the number at `pointer`.
fn nudge(doc: &mut Value, pointer: &str, d: f64) {
    let v = doc
        .pointer_mut(pointer)
        .unwrap_or_else(|| panic!("{pointer}"));
    *v = json!(v.as_f64().unwrap() + d);
}

/// One column of the gradient: what it moves (JSON pointers, each by the step), the step,
/// the scale of the derivative (`−c₀²` for the slowness entry, else 1) and each arrival's
/// value.
struct Column {
    name: String,
    pointers: Vec<String>,
    step: f64,
    scale: f64,
    values: Vec<f64>,
}

/// Checks every column of every arrival's gradient of `doc`'s path 0 against
/// central differences of the re-solved arrivals' times (`tol_c` absolute on `dT/dc` and the
/// slowness entry over `c₀²`, `tol_x` on the positions'); returns the arrivals checked and
/// the worst difference of each kind.
fn check_all(doc: &Value, tol: [f64; 2]) -> (usize, [f64; 2]) {
    let [tol_c, tol_x] = tol;
    let (scene, found) = arrivals(doc);
    let m = scene.medium_index("water").unwrap();
    let steps = &scene.paths()[0].steps;
    let grads: Vec<Gradient> = (found.iter())
        .map(|a| Gradient::of_arrival(&scene, steps, a).unwrap())
        .collect();
    let knots = doc["media"]["water"]["profile"].as_array().unwrap().len();
    let mut columns = Vec::new();
    for k in 0..knots {
        columns.push(Column {
            name: format!("knot {k}"),
            pointers: vec![format!("/media/water/profile/{k}/1")],
            step: 1e-3,
            scale: 1.0,
            values: grads.iter().map(|g| g.profile_speed[m][k]).collect(),
        });
    }
    let c0 = doc["media"]["water"]["profile"][0][1].as_f64().unwrap();
    columns.push(Column {
        name: "slowness".into(),
        pointers: (0..knots)
            .map(|k| format!("/media/water/profile/{k}/1"))
            .collect(),
        step: 1e-3,
        scale: -c0 * c0,
        values: grads.iter().map(|g| g.slowness[m]).collect(),
    });
    for axis in 0..2 {
        let pick = |v: eigenray::Vec2| if axis == 0 { v.x } else { v.y };
        for (end, of) in [("sources", 0), ("receivers", 1)] {
            columns.push(Column {
                name: format!("{end} {axis}"),
                pointers: vec![format!("/{end}/0/{axis}")],
                step: 1e-2,
                scale: 1.0,
                values: (grads.iter())
                    .map(|g| pick(if of == 0 { g.source } else { g.receiver }))
                    .collect(),
            });
        }
        for wall in ["surface", "bottom"] {
            let i = scene.interface_index(wall).unwrap();
            let count = doc["interfaces"][wall]["points"].as_array().unwrap().len();
            for v in 0..count {
                columns.push(Column {
                    name: format!("{wall} vertex {v} axis {axis}"),
                    pointers: vec![format!("/interfaces/{wall}/points/{v}/{axis}")],
                    step: 1e-2,
                    scale: 1.0,
                    values: grads.iter().map(|g| pick(g.vertex(i, v))).collect(),
                });
            }
        }
    }
    let mut worst = [0.0f64; 2];
    for column in &columns {
        let h = column.step;
        let moved = |d: f64| {
            let mut doc = doc.clone();
            for p in &column.pointers {
                nudge(&mut doc, p, d);
            }
            arrivals(&doc).1
        };
        let (up, down) = (moved(h), moved(-h));
        for (a, got) in found.iter().zip(&column.values) {
            let fd = column.scale
                * (same(&up, a, &column.name).time - same(&down, a, &column.name).time)
                / (2.0 * h);
            let knot = column.step == 1e-3;
            let (off, bound) = if knot {
                ((got - fd).abs() / column.scale.abs(), tol_c)
            } else {
                ((got - fd).abs(), tol_x)
            };
            worst[usize::from(!knot)] = worst[usize::from(!knot)].max(off);
            assert!(
                off <= bound,
                "arrival at {} s (turns {:?}): {}: {got} against {fd}",
                a.time,
                a.turns,
                column.name
            );
        }
    }
    (found.len(), worst)
}

/// The rays of bottom, surface–bottom, bottom–surface–bottom and bottom–bottom paths over
/// the sloping bottom (8 arrivals: both of its segments met, legs of up to 3 turning
/// points, two `obstructed` ones): every column of every arrival against central
/// differences.
#[test]
fn sloped_arrivals_match_finite_differences() {
    let b = json!({ "reflect": "bottom" });
    let t = json!({ "reflect": "surface" });
    let mut total = 0;
    let mut worst = [0.0f64; 2];
    for (steps, receiver) in [
        (json!([b]), [2000.0, -60.0]),
        (json!([t, b]), [1500.0, -60.0]),
        (json!([b, t, b]), [3000.0, -60.0]),
        (json!([b, b]), [5000.0, -60.0]),
    ] {
        let what = steps.to_string();
        let (n, w) = check_all(
            &doc(json!({ "profile": KNOTS }), steps, receiver),
            [1e-10, 1e-10],
        );
        println!("{what}: {n} arrivals");
        total += n;
        worst = [worst[0].max(w[0]), worst[1].max(w[1])];
    }
    println!(
        "{total} arrivals: worst |dT/dc − difference| {:.1e} s²/m, |dT/dx − difference| {:.1e} s/m",
        worst[0], worst[1]
    );
    assert_eq!(total, 8, "{total} arrivals");
}

/// An isovelocity profile over the sloping bottom is the uniform medium: each arrival's
/// source, receiver and vertex derivatives are the straight legs' (the uniform medium's
/// gradient at the same points) to 1e-10 relative, and the knots' derivatives add up to
/// `−length / c²`.
#[test]
fn isovelocity_is_the_uniform_medium() {
    let b = json!({ "reflect": "bottom" });
    let t = json!({ "reflect": "surface" });
    let mut compared = 0;
    for steps in [json!([b]), json!([t, b]), json!([b, t, b])] {
        let profile = doc(
            json!({ "profile": [[20, 1500], [-230, 1500]] }),
            steps.clone(),
            [3000.0, -60.0],
        );
        let uniform = doc(json!({ "speed": 1500 }), steps, [3000.0, -60.0]);
        let (scene, found) = arrivals(&profile);
        let flat = Scene::from_json(&uniform.to_string()).unwrap();
        let steps = &scene.paths()[0].steps;
        for a in &found {
            let g = Gradient::of_arrival(&scene, steps, a).unwrap();
            let u = Gradient::of_points(&flat, steps, &a.points, &a.media).unwrap();
            let close = |x: eigenray::Vec2, y: eigenray::Vec2| {
                (x - y).length() <= 1e-10 * y.length().max(1e-6)
            };
            assert!(close(g.source, u.source), "{:?} {:?}", g.source, u.source);
            assert!(close(g.receiver, u.receiver));
            assert_eq!(g.vertices.len(), u.vertices.len());
            for (x, y) in g.vertices.iter().zip(&u.vertices) {
                assert_eq!((x.interface, x.vertex), (y.interface, y.vertex));
                assert!(close(x.d, y.d), "{x:?} {y:?}");
            }
            let length: f64 = a.points.windows(2).map(|w| w[0].distance(w[1])).sum();
            let sum: f64 = g.profile_speed[0].iter().sum();
            assert!((sum + length / 1500.0 / 1500.0).abs() <= 1e-12 * length / 2.25e6);
            compared += 1;
        }
    }
    assert!(compared >= 3, "{compared}");
}

/// The default mode's ray: `Gradient::of_solved` after `Tracer::solve` is the gradient of
/// the stationary path it chose (the earliest converged), and the command line writes a
/// `gradient` for each ray of the example `examples/scenes/profile_slope.json` with
/// `"derivatives": true` (its receiver's the last leg's slowness vector: length `1/c`).
#[test]
fn default_mode_and_command_line_give_the_gradient() {
    let b = json!({ "reflect": "bottom" });
    let d = doc(json!({ "profile": KNOTS }), json!([b]), [3000.0, -60.0]);
    let (scene, found) = arrivals(&d);
    let tracer = Tracer::new(scene.clone()).unwrap();
    let mut ws = Workspace::new();
    let record = tracer.solve(scene.sources()[0], scene.receivers()[0], 0, &mut ws);
    assert_eq!(record.status, Status::Converged);
    let solved = Gradient::of_solved(&scene, 0, &ws).unwrap();
    let chosen = found.first().unwrap();
    assert_eq!(ws.points(), &chosen.points[..]);
    let steps = &scene.paths()[0].steps;
    assert_eq!(
        solved,
        Gradient::of_arrival(&scene, steps, chosen).unwrap(),
        "the default mode's gradient is its arrival's"
    );

    let mut example: Value = serde_json::from_str(
        &std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/examples/scenes/profile_slope.json"
        ))
        .unwrap(),
    )
    .unwrap();
    example["solver"]["derivatives"] = json!(true);
    let dir = std::env::temp_dir().join(format!("eigenray-slope-grad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("scene.json");
    std::fs::write(&file, example.to_string()).unwrap();
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
    let doc: Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut timed = 0;
    for ray in doc["rays"].as_array().unwrap() {
        if ray["time"].is_null() {
            continue;
        }
        let g = &ray["gradient"];
        let r = [
            g["receiver"][0].as_f64().unwrap(),
            g["receiver"][1].as_f64().unwrap(),
        ];
        let knots = g["profile_speed"]["water"].as_array().unwrap();
        assert_eq!(knots.len(), 5, "{g}");
        let y = ray["points"].as_array().unwrap().last().unwrap()[1]
            .as_f64()
            .unwrap();
        // The receiver at 60 m depth: 1488 + (1490 − 1488) · 20/30 m/s.
        let c = 1490.0 - 2.0 * (-50.0 - y) / 30.0;
        assert!((r[0].hypot(r[1]) - 1.0 / c).abs() <= 1e-12 / c, "{r:?}");
        timed += 1;
    }
    assert!(timed >= 3, "{timed}");
    std::fs::remove_dir_all(&dir).ok();
}
