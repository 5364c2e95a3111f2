//! Extruded rooms (`"extrusion"`): the search's 3-D arrivals against references written here.
//!
//! - An independent enumeration: the plan paths of the same floor plan without `extrusion`
//!   (the 2-D search) × the vertical image sources of each (the floor z → −z and the ceiling
//!   z → 2H − z applied in turn), in an L-shaped room: the same arrivals, times to 1e-12, and
//!   3-D points whose legs add up to the path's length.
//! - A shoebox: the 3-D lattice of image sources, each wall, the floor and the ceiling with
//!   its own absorption: the same times and amplitudes.
//! - Streamed responses (pressure) equal the sum over the listed arrivals.
//! - Bad extruded scenes are refused, naming the key (exit 2 from the command line).

use std::f64::consts::PI;

use eigenray::amplitude::Complex64;
use eigenray::options::Run;
use eigenray::response::pressure_of_scene_into;
use eigenray::{Scene, SearchArrival, Tracer};
use serde_json::{Value, json};

const C: f64 = 343.0;

/// The L-shaped plan (one closed polyline), walls absorbing 0.1.
fn l_plan() -> Value {
    json!({ "points": [[0, 0], [6, 0], [6, 3], [3, 3], [3, 5], [0, 5]], "closed": true,
            "reflection": { "absorption": 0.1 } })
}

/// A scene document of the L-shaped room, with or without its extrusion.
fn l_room(extruded: bool, search: Value) -> Value {
    let (sources, receivers) = if extruded {
        (
            json!([[1.0, 1.2, 1.1]]),
            json!([[5.1, 2.2, 1.7], [1.4, 4.1, 2.6]]),
        )
    } else {
        (json!([[1.0, 1.2]]), json!([[5.1, 2.2], [1.4, 4.1]]))
    };
    let mut doc = json!({
        "media": { "air": { "speed": C, "at": [1.0, 1.0] } },
        "interfaces": { "walls": l_plan() },
        "sources": sources, "receivers": receivers,
        "search": search,
        "amplitudes": { "source": "point" }
    });
    if extruded {
        doc["extrusion"] = json!({ "height": 3.0, "floor": { "absorption": 0.3 },
                                    "ceiling": { "absorption": 0.05 } });
    }
    doc
}

const ZS: f64 = 1.1;
const ZR: [f64; 2] = [1.7, 2.6];
const H: f64 = 3.0;

/// The unfolded vertical lengths of every alternating sequence of up to `most` floor and
/// ceiling reflections, from the image sources (mirrors applied in turn): (reflections,
/// length).
fn vertical_images(zs: f64, zr: f64, h: f64, most: usize) -> Vec<(usize, f64)> {
    let mut out = vec![(0, (zr - zs).abs())];
    for floor_first in [true, false] {
        let (mut z, mut floor) = (zs, floor_first);
        for n in 1..=most {
            z = if floor { -z } else { 2.0 * h - z };
            floor = !floor;
            out.push((n, (zr - z).abs()));
        }
    }
    out
}

/// (receiver, time) of each arrival, ordered.
fn times(arrivals: &[SearchArrival]) -> Vec<(usize, f64)> {
    let mut t: Vec<(usize, f64)> = arrivals
        .iter()
        .map(|a| (a.receiver, a.arrival.time))
        .collect();
    t.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    t
}

fn same_times(got: &[(usize, f64)], want: &[(usize, f64)], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: counts");
    for (g, w) in got.iter().zip(want) {
        assert_eq!(g.0, w.0, "{what}");
        assert!(
            (g.1 - w.1).abs() <= 1e-12 * w.1.max(1e-3),
            "{what}: {g:?} {w:?}"
        );
    }
}

/// The plan paths of the 2-D search × their vertical images, within `max_steps` reflections
/// in all and `max_time`.
fn enumerated(max_steps: usize, max_time: f64) -> Vec<(usize, f64)> {
    let plan_doc = l_room(
        false,
        json!({ "max_steps": max_steps, "max_time": max_time }),
    );
    let plan = Scene::from_json(&plan_doc.to_string()).unwrap();
    let arrivals = Tracer::new(&plan)
        .unwrap()
        .search(&Run::new())
        .unwrap()
        .arrivals;
    let mut out = Vec::new();
    for a in &arrivals {
        let l: f64 = a
            .arrival
            .points
            .windows(2)
            .map(|w| w[0].distance(w[1]))
            .sum();
        for (n, z) in vertical_images(ZS, ZR[a.receiver], H, max_steps) {
            let t = l.hypot(z) / C;
            if a.steps.len() + n <= max_steps && t <= max_time {
                out.push((a.receiver, t));
            }
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    out
}

#[test]
fn an_l_shaped_room_gives_its_plan_paths_times_their_vertical_images() {
    for (max_steps, max_time) in [(4, 1.0), (8, 0.045), (30, 0.04)] {
        let doc = l_room(
            true,
            json!({ "max_steps": max_steps, "max_time": max_time }),
        );
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let report = Tracer::new(&scene).unwrap().search(&Run::new()).unwrap();
        assert_eq!(report.incomplete_pairs, 0);
        let what = format!("max_steps {max_steps}, max_time {max_time}");
        let want = enumerated(max_steps, max_time);
        assert!(want.len() > 50, "{what}: {}", want.len());
        same_times(&times(&report.arrivals), &want, &what);
        let floor = scene.interfaces().len();
        for a in &report.arrivals {
            // 3-D points: legs adding up to the path's length, flat reflections on their
            // faces, in order along the path, alternating.
            let p = &a.arrival.points;
            assert_eq!(a.heights.len(), p.len());
            assert_eq!(p.len(), a.steps.len() + 2);
            let length: f64 = (1..p.len())
                .map(|i| {
                    let (dx, dy) = (p[i].x - p[i - 1].x, p[i].y - p[i - 1].y);
                    (dx * dx + dy * dy + (a.heights[i] - a.heights[i - 1]).powi(2)).sqrt()
                })
                .sum();
            assert!((length / C - a.arrival.time).abs() < 1e-12, "{what}");
            let flats: Vec<usize> = a
                .steps
                .iter()
                .filter(|s| s.interface >= floor)
                .map(|s| s.interface)
                .collect();
            assert!(flats.windows(2).all(|w| w[0] != w[1]), "{what}");
            for (i, s) in a.steps.iter().enumerate() {
                let z = a.heights[i + 1];
                if s.interface == floor {
                    assert_eq!(z, 0.0);
                } else if s.interface == floor + 1 {
                    assert_eq!(z, H);
                } else {
                    assert!(z > 0.0 && z < H, "{what}: {z}");
                }
            }
            assert_eq!(a.heights[0], ZS);
            assert_eq!(*a.heights.last().unwrap(), ZR[a.receiver]);
        }
    }
}

/// Image sources of a source at `s` in `[0, l]`, each with its reflections off the wall at 0
/// and off the wall at `l`, for reflections up to `most`.
fn images_1d(s: f64, l: f64, most: i64) -> Vec<(f64, u32, u32)> {
    let mut out = Vec::new();
    for i in -most..=most {
        for q in [0, 1] {
            let x = 2.0 * i as f64 * l + if q == 0 { s } else { -s };
            out.push((x, (i - q).unsigned_abs() as u32, i.unsigned_abs() as u32));
        }
    }
    out
}

#[test]
fn a_shoebox_gives_its_3d_image_sources() {
    let (lx, ly, h) = (5.0, 4.0, 2.8);
    let alpha = [0.1, 0.2, 0.3, 0.4, 0.5, 0.15]; // west, east, south, north, floor, ceiling
    let wall = |a: f64| json!({ "absorption": a });
    let (s, r) = ([1.13, 1.37, 0.91], [3.71, 2.93, 2.2]); // no path through a corner
    let (max_steps, max_time) = (6usize, 0.05);
    let doc = json!({
        "media": { "air": { "speed": C } }, "background": "air",
        "interfaces": {
            "west":  { "points": [[0, 0], [0, ly]], "reflection": wall(alpha[0]) },
            "east":  { "points": [[lx, 0], [lx, ly]], "reflection": wall(alpha[1]) },
            "south": { "points": [[0, 0], [lx, 0]], "reflection": wall(alpha[2]) },
            "north": { "points": [[0, ly], [lx, ly]], "reflection": wall(alpha[3]) }
        },
        "extrusion": { "height": h, "floor": wall(alpha[4]), "ceiling": wall(alpha[5]) },
        "sources": [s], "receivers": [r],
        "search": { "max_steps": max_steps, "max_time": max_time, "refract": false },
        "amplitudes": { "source": "point", "frequency": 250 }
    });
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let arrivals = tracer.search(&Run::new()).unwrap().arrivals;
    let beta: Vec<f64> = alpha.iter().map(|a| (1.0 - a).sqrt()).collect();
    let mut want = Vec::new();
    let m = max_steps as i64;
    for (x, w, e) in images_1d(s[0], lx, m) {
        for (y, so, no) in images_1d(s[1], ly, m) {
            for (z, fl, ce) in images_1d(s[2], h, m) {
                let k = (w + e + so + no + fl + ce) as usize;
                let d = ((x - r[0]).powi(2) + (y - r[1]).powi(2) + (z - r[2]).powi(2)).sqrt();
                if k <= max_steps && d / C <= max_time {
                    let counts = [w, e, so, no, fl, ce];
                    let c: f64 = beta
                        .iter()
                        .zip(counts)
                        .map(|(b, n)| b.powi(n as i32))
                        .product();
                    want.push((d / C, c / (4.0 * PI * d)));
                }
            }
        }
    }
    let key = |v: &(f64, f64)| ((v.0 * 1e9).round() as i64, (v.1 * 1e12).round() as i64);
    want.sort_by_key(key);
    let mut got: Vec<(f64, f64)> = arrivals
        .iter()
        .map(|a| (a.arrival.time, a.arrival.amplitude.unwrap().value.re))
        .collect();
    got.sort_by_key(key);
    assert!(want.len() > 200, "{}", want.len());
    if got.len() != want.len() {
        for w in &want {
            if !got
                .iter()
                .any(|g| (g.0 - w.0).abs() < 1e-12 && (g.1 - w.1).abs() < 1e-12)
            {
                eprintln!("missing {w:?}");
            }
        }
    }
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(&want) {
        assert!((g.0 - w.0).abs() < 1e-12 * w.0, "{g:?} {w:?}");
        assert!((g.1 - w.1).abs() < 1e-12 * w.1, "{g:?} {w:?}");
    }
    // The streamed pressure is the sum over the listed arrivals.
    let f = 250.0;
    let mut streamed = vec![Complex64::new(0.0, 0.0); 1];
    pressure_of_scene_into(&tracer, f, &Run::new(), &mut streamed).unwrap();
    let listed: Complex64 = arrivals
        .iter()
        .map(|a| {
            let t = a.arrival.time;
            a.arrival.amplitude.unwrap().value
                * Complex64::from_polar(1.0, 2.0 * PI * (f * t).fract())
        })
        .sum();
    let scale: f64 = want.iter().map(|w| w.1).sum();
    assert!(
        (streamed[0] - listed).norm() < 1e-12 * scale,
        "{streamed:?} {listed}"
    );
}

/// A `"media"` wall takes its coefficient at the 3-D incidence angle: the plan angle's
/// cosine times L/D.
#[test]
fn a_media_wall_reflects_at_the_3d_angle() {
    let doc = json!({
        "media": { "air": { "speed": 343.0, "density": 1.2, "at": [0, 1] },
                   "wall": { "speed": 1500.0, "density": 1000.0, "at": [0, -1] } },
        "domain": [[-10, -5], [10, 5]],
        "interfaces": { "w": { "points": [[-10, 0], [10, 0]], "reflection": "media" } },
        "extrusion": { "height": 3.0 },
        "sources": [[0.0, 1.0, 1.0]], "receivers": [[2.0, 1.5, 2.0]],
        "search": { "max_steps": 1, "refract": false },
        "amplitudes": { "source": "point" }
    });
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let arrivals = Tracer::new(&scene)
        .unwrap()
        .search(&Run::new())
        .unwrap()
        .arrivals;
    let a = arrivals
        .iter()
        .find(|a| a.steps.len() == 1 && a.steps[0].interface == 0)
        .unwrap();
    // The image of the source in the wall y = 0: (0, −1, 1).
    let (dx, dy, dz) = (2.0, 2.5, 1.0);
    let d: f64 = dx * dx + dy * dy + dz * dz;
    let cos1 = dy / d.sqrt();
    let (z1, z2) = (1.2 * 343.0, 1000.0 * 1500.0);
    let sin2 = 1.0 - cos1 * cos1;
    let q = (1500.0f64 / 343.0).powi(2) * sin2;
    // Beyond the critical angle the coefficient is complex of modulus 1.
    let cos2 = if q <= 1.0 {
        Complex64::new((1.0 - q).sqrt(), 0.0)
    } else {
        Complex64::new(0.0, (q - 1.0).sqrt())
    };
    let want = (z2 * cos1 - z1 * cos2) / (z2 * cos1 + z1 * cos2);
    let got = a.arrival.amplitude.unwrap().coefficient;
    assert!((got - want).norm() < 1e-12, "{got} {want}");
    let spreading = a.arrival.amplitude.unwrap().spreading;
    assert!((spreading - 1.0 / (4.0 * PI * d.sqrt())).abs() < 1e-15);
}

#[test]
fn bad_extruded_scenes_name_their_key() {
    let base = l_room(true, json!({ "max_steps": 2 }));
    type Edit = Box<dyn Fn(&mut Value)>;
    let cases: Vec<(Edit, &str)> = vec![
        (
            Box::new(|d| d["sources"] = json!([[1.0, 1.2, 3.0]])),
            "sources[0]",
        ),
        (
            Box::new(|d| d["receivers"] = json!([[1.0, 1.2, 0.0]])),
            "receivers[0]",
        ),
        (
            Box::new(|d| d["receivers"] = json!([[5.1, 2.2, 1.7], [1.4, 4.1]])),
            "receivers[1]",
        ),
        (
            Box::new(|d| d["extrusion"]["height"] = json!(-1.0)),
            "extrusion.height",
        ),
        (
            Box::new(|d| d["extrusion"]["floor"] = json!("media")),
            "extrusion.floor",
        ),
        (
            Box::new(|d| d["extrusion"]["ceiling"] = json!({ "absorption": 2 })),
            "extrusion.ceiling.absorption",
        ),
        (
            Box::new(|d| d["interfaces"]["floor"] = json!({ "points": [[7, 0], [8, 0]] })),
            "interfaces.floor",
        ),
        (
            Box::new(|d| d["amplitudes"]["source"] = json!("axisymmetric")),
            "amplitudes.source",
        ),
        (Box::new(|d| d["paths"] = json!([{ "steps": [] }])), "paths"),
        (
            Box::new(|d| d["receivers"] = json!({ "grid": { "x": [1, 2, 2], "y": [1, 2, 2] } })),
            "receivers.grid.z",
        ),
        (
            Box::new(|d| {
                d["receivers"] = json!({ "grid": { "x": [1, 2, 2], "y": [1, 2, 2], "z": 3.0 } })
            }),
            "receivers.grid.z",
        ),
        (
            Box::new(|d| d["search"]["diffraction"] = json!(true)),
            "search.diffraction",
        ),
    ];
    for (edit, key) in cases {
        let mut doc = base.clone();
        edit(&mut doc);
        let e = Scene::from_json(&doc.to_string()).unwrap_err();
        assert_eq!(e.key, key, "{e}");
    }
    // The command-line tool: exit 2, the key named.
    let dir = std::env::temp_dir().join(format!("eigenray-extrusion-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.json");
    let mut doc = base.clone();
    doc["sources"] = json!([[1.0, 1.2, 4.0]]);
    std::fs::write(&path, doc.to_string()).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .arg("solve")
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("sources[0]"));
}

#[test]
fn an_extruded_scene_reads_back_from_its_document() {
    let doc = l_room(true, json!({ "max_steps": 2 }));
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let again = Scene::from_json(&scene.to_json()).unwrap();
    assert_eq!(format!("{scene:?}"), format!("{again:?}"));
    assert_eq!(again.extrusion().unwrap().receiver_heights, ZR.to_vec());
}

/// A grid with its height `z` is the list of its points, each at that height: the same
/// pressure at every receiver, to the bit, and its document reads back with the grid.
#[test]
fn an_extruded_grid_is_its_points_at_its_height() {
    let (xs, z) = ([0.5, 2.5, 4.5], 1.6);
    let search = json!({ "max_steps": 5, "refract": false });
    let mut grid = l_room(true, search.clone());
    grid["amplitudes"]["frequency"] = json!(250.0);
    grid["receivers"] = json!({ "grid": { "x": [0.5, 4.5, 3], "y": [0.5, 4.5, 5], "z": z } });
    let mut list = grid.clone();
    let points: Vec<Value> = xs
        .iter()
        .flat_map(|&x| {
            [0.5, 1.5, 2.5, 3.5, 4.5]
                .into_iter()
                .map(move |y| json!([x, y, z]))
        })
        .collect();
    list["receivers"] = Value::Array(points);
    let pressure = |doc: &Value| {
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let mut out = vec![Complex64::new(0.0, 0.0); scene.receivers().len()];
        pressure_of_scene_into(&tracer, 250.0, &Run::new(), &mut out).unwrap();
        (scene, out)
    };
    let (scene, from_grid) = pressure(&grid);
    let (_, from_list) = pressure(&list);
    assert_eq!(from_grid.len(), 15);
    assert_eq!(from_grid, from_list);
    // Receivers in the plan's missing corner (x > 3, y > 3) hear nothing; the others do.
    for (k, p) in from_grid.iter().enumerate() {
        let (x, y) = (xs[k / 5], [0.5, 1.5, 2.5, 3.5, 4.5][k % 5]);
        assert_eq!(
            *p == Complex64::new(0.0, 0.0),
            x > 3.0 && y > 3.0,
            "receiver {k}"
        );
    }
    assert_eq!(scene.extrusion().unwrap().receiver_heights, vec![z; 15]);
    let again = Scene::from_json(&scene.to_json()).unwrap();
    assert_eq!(again.receiver_grid(), scene.receiver_grid());
    assert_eq!(again.extrusion(), scene.extrusion());
    assert!(scene.to_json().contains("\"z\":1.6"), "{}", scene.to_json());
}

/// The shoebox room of the parameters' check: absorbing walls, floor and ceiling, every
/// arrival up to 0.4 s, a 0.4 s response at 8 kHz.
fn reverberant_box() -> Value {
    json!({
        "media": { "air": { "speed": C, "at": [1.0, 1.0] } },
        "interfaces": { "walls": { "points": [[0, 0], [4.3, 0], [4.3, 3.1], [0, 3.1]],
                                   "closed": true, "reflection": { "absorption": 0.3 } } },
        "extrusion": { "height": 2.6, "floor": { "absorption": 0.4 }, "ceiling": "rigid" },
        "sources": [[1.03, 1.11, 1.23]], "receivers": [[3.07, 2.02, 1.61]],
        "search": { "max_time": 0.4 },
        "amplitudes": { "source": "point", "frequency": 500 },
        "impulse_response": { "rate": 8000, "duration": 0.4 }
    })
}

/// Least squares of `y` over `x`, written the two-pass way (means first).
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

#[test]
fn room_parameters_match_an_independent_schroeder_integration() {
    use eigenray::response::{ImpulseResponses, echoes_of_scene, room_parameters_of_scene};
    let scene = Scene::from_json(&reverberant_box().to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let options = scene.impulse_response().unwrap();
    let responses = ImpulseResponses::new(options, 1, 1);
    let found = room_parameters_of_scene(&tracer, &responses, &Run::new()).unwrap();
    let p = &found.parameters[0];
    // The same response, collected then rendered; its first arrival from the echoes.
    let echoes = echoes_of_scene(&tracer, &Run::new()).unwrap();
    let t0 = echoes.iter().map(|e| e.time).fold(f64::INFINITY, f64::min);
    assert_eq!(p.first_arrival, Some(t0));
    let h = responses.render(echoes, &Run::new()).unwrap();
    let rate = responses.rate();
    // Schroeder: E(t) = Σ_{m ≥ n} h², as a running sum from the end, in dB of the total.
    let total: f64 = h.iter().map(|v| v * v).sum();
    let mut tail = total;
    let mut level = Vec::with_capacity(h.len());
    for v in &h {
        level.push(10.0 * (tail / total).log10());
        tail -= v * v;
    }
    let start = (t0 * rate).floor() as usize;
    let decay_time = |hi: f64, lo: f64| {
        let last = (start..h.len()).find(|&n| level[n] < lo).unwrap();
        let (x, y): (Vec<f64>, Vec<f64>) = (start..last)
            .filter(|&n| level[n] <= hi && level[n] >= lo)
            .map(|n| (n as f64 / rate, level[n]))
            .unzip();
        -60.0 / slope(&x, &y)
    };
    let split = |ms: f64| {
        let n = ((t0 + ms / 1000.0) * rate).ceil() as usize;
        let early: f64 = h[..n].iter().map(|v| v * v).sum();
        (early, total - early)
    };
    let checks = [
        ("edt", &p.edt, decay_time(0.0, -10.0)),
        ("t20", &p.t20, decay_time(-5.0, -25.0)),
        ("t30", &p.t30, decay_time(-5.0, -35.0)),
        (
            "c50",
            &p.c50,
            10.0 * (split(50.0).0 / split(50.0).1).log10(),
        ),
        (
            "c80",
            &p.c80,
            10.0 * (split(80.0).0 / split(80.0).1).log10(),
        ),
        ("d50", &p.d50, split(50.0).0 / total),
    ];
    for (what, got, want) in checks {
        let got = got
            .value
            .unwrap_or_else(|| panic!("{what}: {:?}", got.reason));
        assert!(
            (got - want).abs() <= 0.01 * want.abs(),
            "{what}: {got} {want}"
        );
    }
    // A reverberation time of the order of Sabine's and Eyring's (0.2 to 0.5 s here).
    let t30 = p.t30.value.unwrap();
    assert!(t30 > 0.2 && t30 < 0.5, "{t30}");
}

#[test]
fn the_command_line_writes_the_parameters_and_refuses_an_unwritable_file() {
    let dir = std::env::temp_dir().join(format!("eigenray-parameters-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("box.json");
    let mut doc = reverberant_box();
    doc["search"] = json!({ "max_time": 0.1 });
    doc["impulse_response"] = json!({ "rate": 8000, "duration": 0.1 });
    std::fs::write(&scene, doc.to_string()).unwrap();
    let bin = env!("CARGO_BIN_EXE_eigenray");
    let file = dir.join("p.json");
    let out = std::process::Command::new(bin)
        .args([
            "solve".as_ref(),
            scene.as_os_str(),
            "--parameters".as_ref(),
            file.as_os_str(),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stdout.is_empty());
    let written: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    let entry = &written["parameters"][0];
    assert!(entry["c50"]["value"].is_number(), "{entry}");
    // 0.1 s of response: too short for −35 dB.
    assert!(
        entry["t30"]["value"].is_null() && entry["t30"]["reason"].is_string(),
        "{entry}"
    );
    // The library's own pass over the scene: the same parameters, whether the file comes
    // alone, beside `--ir` (one rendering for both: the written response is the one read) or
    // beside the listed arrivals (summed in their listed order).
    let built = Scene::from_json(&doc.to_string()).unwrap();
    let responses = eigenray::response::ImpulseResponses::new(
        built.impulse_response().unwrap(),
        1,
        built.receivers().len(),
    );
    let want = eigenray::response::room_parameters_of_scene(
        &Tracer::new(&built).unwrap(),
        &responses,
        &Run::new(),
    )
    .unwrap();
    let ir = dir.join("ir.npy");
    let arrivals = dir.join("arrivals.json");
    for extra in [
        vec![],
        vec!["--ir".as_ref(), ir.as_os_str()],
        vec!["--arrivals".as_ref(), arrivals.as_os_str()],
    ] {
        let out = std::process::Command::new(bin)
            .args([
                "solve".as_ref(),
                scene.as_os_str(),
                "--parameters".as_ref(),
                file.as_os_str(),
            ])
            .args(&extra)
            .output()
            .unwrap();
        assert!(out.status.success(), "{extra:?}");
        let got: Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
        for (k, p) in want.parameters.iter().enumerate() {
            let w = serde_json::to_value(p).unwrap();
            for key in ["edt", "t20", "c50", "c80", "d50"] {
                let (g, w) = (&got["parameters"][k][key]["value"], &w[key]["value"]);
                match (g.as_f64(), w.as_f64()) {
                    (Some(g), Some(w)) => {
                        assert!((g - w).abs() <= 1e-12 * w.abs(), "{extra:?} {key}: {g} {w}");
                    }
                    _ => assert!(g.is_null() && w.is_null(), "{extra:?} {key}: {g} {w}"),
                }
            }
        }
        // One search: its summary line once.
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(stderr.matches("search:").count(), 1, "{stderr}");
    }
    let bad = dir.join("missing").join("p.json");
    let out = std::process::Command::new(bin)
        .args([
            "solve".as_ref(),
            scene.as_os_str(),
            "--parameters".as_ref(),
            bad.as_os_str(),
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--parameters"));
}

/// The extruded search within its run: a stop requested before it lists nothing complete; a
/// budget stops it short, every pair it leaves saying `complete: false`; streamed and listed
/// arrivals agree.
#[test]
fn an_extruded_search_keeps_to_its_run() {
    let doc = l_room(true, json!({ "max_time": 0.06 }));
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let full = tracer.search(&Run::new()).unwrap();
    assert_eq!(full.incomplete_pairs, 0);
    let stopped = Run::new();
    stopped.request_stop();
    let report = tracer.search(&stopped).unwrap();
    assert_eq!(report.incomplete_pairs, 2);
    assert!(report.arrivals.iter().all(|a| !a.complete));
    let short = tracer.search(&Run::new().budget(50)).unwrap();
    assert!(short.incomplete_pairs > 0);
    assert!(short.arrivals.len() < full.arrivals.len());
    // Streamed: the same arrivals' count and times.
    let times = std::sync::Mutex::new(Vec::new());
    let streamed = tracer
        .search_into(&Run::new(), &|a| times.lock().unwrap().push(a.time))
        .unwrap();
    assert_eq!(streamed.arrivals as usize, full.arrivals.len());
    let mut times = times.into_inner().unwrap();
    times.sort_by(f64::total_cmp);
    let mut listed: Vec<f64> = full.arrivals.iter().map(|a| a.arrival.time).collect();
    listed.sort_by(f64::total_cmp);
    assert_eq!(times, listed);
}

/// A streamed extruded search (each plan path's family in closed form, its walls'
/// coefficients taken once) hands on the listed search's arrivals to the bit: the same
/// steps, floor and ceiling reflections, status, time and amplitude, in the L room (a law
/// of absorption per wall, floor and ceiling) and by a `"media"` wall (a coefficient at each
/// member's own 3-D angle).
///
/// Mutants caught: a family's wall coefficient taken at one angle for a `"media"` wall; the
/// floor and ceiling factors in another order or count; a member's time or vertical count
/// off.
#[test]
fn streamed_extruded_arrivals_are_the_listed_ones_to_the_bit() {
    let media = json!({
        "media": { "air": { "speed": 343.0, "density": 1.2, "at": [0, 1] },
                   "wall": { "speed": 1500.0, "density": 1000.0, "at": [0, -1] } },
        "domain": [[-10, -5], [10, 5]],
        "interfaces": { "w": { "points": [[-10, 0], [10, 0]], "reflection": "media" },
                        "v": { "points": [[4, 0.5], [4, 4]],
                               "reflection": { "absorption": 0.2 } } },
        "extrusion": { "height": 3.0, "floor": { "absorption": 0.3 } },
        "sources": [[0.0, 1.0, 1.0]], "receivers": [[2.0, 1.5, 2.0], [1.0, 3.0, 0.5]],
        "search": { "max_time": 0.05, "refract": false },
        "amplitudes": { "source": "point" }
    });
    for doc in [l_room(true, json!({ "max_time": 0.06 })), media] {
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let key = |a: &eigenray::search::StreamedArrival| {
            let amplitude = a.amplitude.unwrap();
            let v = amplitude.value;
            let c = amplitude.coefficient;
            (
                (a.source, a.receiver, a.steps, a.diffractions),
                (a.vertical_reflections, format!("{:?}", a.status)),
                [a.time, v.re, v.im, c.re, c.im, amplitude.spreading].map(f64::to_bits),
                amplitude.attenuation_db.to_bits(),
            )
        };
        let mut listed: Vec<_> = (tracer.search(&Run::new()).unwrap().arrivals.iter())
            .map(|a| key(&a.streamed()))
            .collect();
        let streamed = std::sync::Mutex::new(Vec::new());
        tracer
            .search_into(&Run::new(), &|a| streamed.lock().unwrap().push(key(&a)))
            .unwrap();
        let mut streamed = streamed.into_inner().unwrap();
        assert!(listed.iter().any(|k| k.1.0 > 0 && k.0.2 > k.1.0));
        listed.sort();
        streamed.sort();
        assert_eq!(streamed, listed);
    }
}

/// The writer gives an extruded arrival's points in 3-D in every format, and its steps name
/// the floor and the ceiling.
#[test]
fn every_format_writes_3d_points() {
    use eigenray::{Format, write};
    let doc = l_room(true, json!({ "max_steps": 2 }));
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let arrivals = Tracer::new(&scene)
        .unwrap()
        .search(&Run::new())
        .unwrap()
        .arrivals;
    let mut json_text = Vec::new();
    write(&scene, &arrivals, Format::Json, &mut json_text).unwrap();
    let written: Value = serde_json::from_slice(&json_text).unwrap();
    let listed = written["arrivals"].as_array().unwrap();
    assert_eq!(listed.len(), arrivals.len());
    for (w, a) in listed.iter().zip(&arrivals) {
        let points = w["points"].as_array().unwrap();
        for (k, p) in points.iter().enumerate() {
            assert_eq!(p[2].as_f64(), Some(a.heights[k]));
        }
    }
    let names: Vec<&str> = listed
        .iter()
        .flat_map(|w| w["steps"].as_array().unwrap())
        .map(|s| s["reflect"].as_str().unwrap())
        .collect();
    assert!(names.contains(&"floor") && names.contains(&"ceiling"));
    let mut csv = Vec::new();
    write(&scene, &arrivals, Format::Csv, &mut csv).unwrap();
    let csv = String::from_utf8(csv).unwrap();
    let first = csv.lines().nth(1).unwrap();
    assert!(first.contains("1.0 1.2 1.1;"), "{first}");
    let mut npy = Vec::new();
    write(&scene, &arrivals, Format::Npy, &mut npy).unwrap();
    let header = String::from_utf8_lossy(&npy[..npy.len().min(1024)]);
    assert!(header.contains("('points', '<f8', (4, 3))"), "{header}");
}

/// Each echo (listed or streamed) counts its arrival's floor and ceiling reflections, the
/// steps on the interfaces past the walls (floor `interfaces().len()`, ceiling the next);
/// the plane room's echoes count none.
#[test]
fn echoes_count_their_floor_and_ceiling_reflections() {
    use eigenray::response::echoes_of_arrivals;
    use eigenray::search::StreamedArrival;
    let doc = l_room(true, json!({ "max_steps": 4, "max_time": 0.05 }));
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let report = tracer.search(&Run::new()).unwrap();
    let walls = scene.interfaces().len();
    let counted = |a: &SearchArrival| a.steps.iter().filter(|s| s.interface >= walls).count();
    let mut want: Vec<(u64, usize)> = (report.arrivals.iter())
        .map(|a| (a.arrival.time.to_bits(), counted(a)))
        .collect();
    want.sort_unstable();
    assert!(want.iter().any(|w| w.1 == 0) && want.iter().any(|w| w.1 >= 3));
    for a in &report.arrivals {
        assert_eq!(a.vertical_reflections(), counted(a));
    }
    let mut echoes: Vec<(u64, usize)> = echoes_of_arrivals(&report.arrivals)
        .map(|e| (e.time.to_bits(), e.vertical_reflections))
        .collect();
    echoes.sort_unstable();
    assert_eq!(echoes, want);
    let streamed = std::sync::Mutex::new(Vec::new());
    let keep = |a: StreamedArrival| {
        let pair = (a.time.to_bits(), a.vertical_reflections);
        streamed.lock().unwrap().push(pair);
    };
    tracer.search_into(&Run::new(), &keep).unwrap();
    let mut streamed = streamed.into_inner().unwrap();
    streamed.sort_unstable();
    assert_eq!(streamed, want);
    // The plane room: none.
    let plane = Scene::from_json(&l_room(false, json!({ "max_steps": 4 })).to_string()).unwrap();
    let plane = Tracer::new(&plane).unwrap().search(&Run::new()).unwrap();
    assert!(!plane.arrivals.is_empty());
    assert!(echoes_of_arrivals(&plane.arrivals).all(|e| e.vertical_reflections == 0));
}
