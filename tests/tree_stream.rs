//! The beam tree in a streamed search (`trace/mirrors/grid.rs`: each node's receivers
//! located on their grid, the paths of its certain beam taken without validating their
//! points and with their amplitude from the unfolded line) against the listed search (every
//! path validated on its points, each amplitude walked over them): the same arrivals, times
//! and amplitudes to 1e-12, on the sloping shallow-water scene's grid (subsampled), random
//! sloping waveguides and polygon rooms with grids of receivers, and receivers exactly on a
//! beam's edge, on a wall and on a vertex.

use std::sync::Mutex;

use eigenray::options::Run;
use eigenray::search::{ArrivalSink, StreamedArrival};
use eigenray::{Scene, Tracer};
use serde_json::{Value, json};

/// A small deterministic generator (SplitMix64).
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
}

/// (receiver, steps, time, amplitude value (re, im) or NaN, and its spreading) of each
/// arrival.
type Row = (usize, usize, f64, [f64; 3]);

fn value(a: Option<eigenray::Amplitude>) -> [f64; 3] {
    a.filter(|a| a.has_value())
        .map_or([f64::NAN; 3], |a| [a.value.re, a.value.im, a.spreading])
}

/// The rows sorted by receiver, steps, time (to the nanosecond: paths of one time, to
/// round-off, such as mirror images of each other, then by their amplitudes) and amplitude.
fn sorted(mut rows: Vec<Row>) -> Vec<Row> {
    let ns = |t: f64| (t * 1e9).round() as i64;
    rows.sort_by(|a, b| {
        (a.0, a.1, ns(a.2))
            .cmp(&(b.0, b.1, ns(b.2)))
            .then(a.3[0].total_cmp(&b.3[0]))
            .then(a.3[1].total_cmp(&b.3[1]))
    });
    rows
}

/// What a comparison found: the largest relative differences of the times and the
/// amplitudes, the arrivals, and those with an amplitude.
struct Compared {
    time: f64,
    amplitude: f64,
    arrivals: usize,
    with_amplitude: usize,
}

/// The streamed arrivals of `scene` against its listed ones, which must be the same
/// arrivals (the same receivers and numbers of steps, times to 1e-12 apart when paired in
/// order of time).
fn compare(scene: &Scene) -> Compared {
    let tracer = Tracer::new(scene).unwrap();
    let listed = tracer.search(&Run::new()).unwrap();
    let out = Mutex::new(Vec::<StreamedArrival>::new());
    let report = tracer
        .search_into(&Run::new(), &|a| out.lock().unwrap().push(a))
        .unwrap();
    assert_eq!(report.incomplete_pairs, 0);
    let stream = out.into_inner().unwrap();
    let a = sorted(
        (listed.arrivals.iter())
            .map(|a| {
                let v = value(a.arrival.amplitude);
                (a.receiver, a.steps.len(), a.arrival.time, v)
            })
            .collect(),
    );
    let b = sorted(
        (stream.iter())
            .map(|a| (a.receiver, a.steps, a.time, value(a.amplitude)))
            .collect(),
    );
    assert_eq!(a.len(), b.len(), "arrival counts");
    let mut c = Compared {
        time: 0.0,
        amplitude: 0.0,
        arrivals: a.len(),
        with_amplitude: 0,
    };
    for (x, y) in a.iter().zip(&b) {
        assert_eq!((x.0, x.1), (y.0, y.1), "{x:?} {y:?}");
        c.time = c.time.max((x.2 - y.2).abs() / x.2);
        if x.3[0].is_nan() {
            assert!(y.3[0].is_nan(), "{x:?} {y:?}");
        } else {
            // Relative (where the coefficients' product underflows 1e-12, against 1e-12 of
            // the spreading).
            c.with_amplitude += 1;
            let size = x.3[0].hypot(x.3[1]).max(1e-12 * x.3[2]);
            let d = (x.3[0] - y.3[0]).hypot(x.3[1] - y.3[1]);
            c.amplitude = c.amplitude.max(d / size);
        }
    }
    c
}

/// The benchmark's sloping shallow-water scene with `receivers` (a grid) and `max_steps`.
fn slope_scene(receivers: Value, max_steps: usize, source: &str) -> Scene {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/benches/scenes/shallow_water_tl_slope.json"
    ))
    .unwrap();
    let mut doc: Value = serde_json::from_str(&text).unwrap();
    doc["receivers"] = receivers;
    doc["search"]["max_steps"] = json!(max_steps);
    doc["amplitudes"]["source"] = json!(source);
    Scene::from_json(&doc.to_string()).unwrap()
}

/// The sloping shallow-water scene (three bottom segments, a `"media"` bottom, an
/// axisymmetric source, 40 bounces) on its grid subsampled to 25 × 9 receivers over the
/// same box: the streamed arrivals are the listed ones.
#[test]
fn the_sloping_grid_streams_the_listed_arrivals() {
    let grid = json!({ "grid": { "x": [100, 5000, 25], "y": [-1, -99, 9] } });
    let c = compare(&slope_scene(grid, 40, "axisymmetric"));
    assert!(
        c.time <= 1e-12 && c.amplitude <= 1e-12,
        "{:e} {:e}",
        c.time,
        c.amplitude
    );
    assert!(c.arrivals > 25 * 9 * 60, "{}", c.arrivals);
    assert_eq!(c.with_amplitude, c.arrivals);
}

/// A sink that keeps each batch as it came.
struct Batches(Mutex<Vec<Vec<StreamedArrival>>>);

impl ArrivalSink for Batches {
    fn arrival(&self, a: StreamedArrival) {
        self.0.lock().unwrap().push(vec![a]);
    }

    fn arrivals(&self, batch: &[StreamedArrival]) {
        self.0.lock().unwrap().push(batch.to_vec());
    }
}

/// A batching sink (`search_into_sink`) gets the arrivals `search_into` hands on one at a
/// time, every one once, in the same order (one source: one tree, one order), bit for bit;
/// the closed-form ones in batches of several, the search's count the same.
#[test]
fn a_batching_sink_gets_every_arrival_once_in_order() {
    let grid = json!({ "grid": { "x": [100, 5000, 25], "y": [-1, -99, 9] } });
    let scene = slope_scene(grid, 40, "axisymmetric");
    let tracer = Tracer::new(&scene).unwrap();
    let one = Mutex::new(Vec::<StreamedArrival>::new());
    let each = tracer
        .search_into(&Run::new(), &|a| one.lock().unwrap().push(a))
        .unwrap();
    let batches = Batches(Mutex::new(Vec::new()));
    let batched = tracer.search_into_sink(&Run::new(), &batches).unwrap();
    let batches = batches.0.into_inner().unwrap();
    let flat: Vec<StreamedArrival> = batches.iter().flatten().copied().collect();
    let one = one.into_inner().unwrap();
    assert_eq!(each.arrivals, one.len() as u64);
    assert_eq!(batched.arrivals, flat.len() as u64);
    assert_eq!(one.len(), flat.len());
    let bits = |a: &StreamedArrival| {
        let v = a
            .amplitude
            .map(|v| [v.value.re, v.value.im, v.spreading].map(f64::to_bits));
        (a.source, a.receiver, a.steps, a.time.to_bits(), v)
    };
    assert!(one.iter().zip(&flat).all(|(a, b)| bits(a) == bits(b)));
    let longest = batches.iter().map(Vec::len).max().unwrap();
    assert!(longest > 100, "{longest}");
    assert!(batches.len() * 10 < flat.len(), "{} batches", batches.len());
}

/// Receivers exactly on a beam's edge (on the line from the source's image in the bottom
/// through the vertex where the bottom starts to slope: (3000, −25)), on the vertex itself,
/// on the surface and on the bottom, with a point and a line source.
#[test]
fn receivers_on_edges_walls_and_vertices_stream_the_listed_arrivals() {
    for source in ["axisymmetric", "point", "line"] {
        let grid = json!({ "grid": { "x": [1000, 3000, 5], "y": [0, -100, 5] } });
        let c = compare(&slope_scene(grid, 12, source));
        assert!(
            c.time <= 1e-12 && c.amplitude <= 1e-12,
            "{source}: {:e} {:e}",
            c.time,
            c.amplitude
        );
        assert!(c.arrivals > 100, "{}", c.arrivals);
    }
}

/// A random fixed law of reflection.
fn law(rng: &mut SplitMix64) -> Value {
    match (rng.next_f64() * 4.0) as usize {
        0 => json!("rigid"),
        1 => json!("pressure-release"),
        2 => json!({ "absorption": 0.2 }),
        _ => json!({ "coefficient": -0.7 }),
    }
}

/// Random sloping waveguides: a surface (flat or tilted) over a bottom of two to four
/// segments at random depths, `"media"`, fixed and absorbing laws, point, line and
/// axisymmetric sources, attenuation, a grid of receivers: the streamed arrivals are the
/// listed ones.
#[test]
fn random_sloping_waveguides_stream_the_listed_arrivals() {
    let mut rng = SplitMix64(3939);
    let mut total = 0;
    for case in 0..12 {
        let length = rng.range(800.0, 2000.0);
        let pieces = 2 + case % 3;
        let mut bottom = vec![[-10.0, -rng.range(60.0, 120.0)]];
        for k in 1..=pieces {
            // The last point on the domain's edge, so that the bottom closes the sediment.
            let x = length * k as f64 / pieces as f64
                + rng.range(-30.0, 30.0) * f64::from(k < pieces)
                + 10.0 * f64::from(k == pieces);
            bottom.push([x, -rng.range(60.0, 120.0)]);
        }
        let tilt = if case % 2 == 0 {
            0.0
        } else {
            rng.range(-5.0, 5.0)
        };
        let source = if case % 3 == 0 {
            "axisymmetric"
        } else if case % 3 == 1 {
            "point"
        } else {
            "line"
        };
        let sediment = json!({ "speed": rng.range(1550.0, 1900.0), "density": rng.range(1.2, 2.0),
                               "at": [10, -200] });
        let attenuation = if case % 4 == 3 { 0.001 } else { 0.0 };
        let doc = json!({
            "media": { "water": { "speed": 1500, "density": 1, "attenuation": attenuation },
                       "sediment": sediment },
            "background": "water",
            "domain": [[-10, -300], [length + 10.0, 20]],
            "interfaces": {
                "surface": { "points": [[-10, 0], [length + 10.0, tilt]], "reflection": law(&mut rng) },
                "bottom": { "points": bottom, "reflection": "media" }
            },
            "sources": [[0, -rng.range(10.0, 50.0)]],
            "receivers": { "grid": { "x": [50, length - 20.0, 9], "y": [-1, -55, 6] } },
            "search": { "max_steps": 16, "refract": false },
            "amplitudes": { "source": source, "frequency": 100 }
        });
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let c = compare(&scene);
        assert!(
            c.time <= 1e-12 && c.amplitude <= 1e-12,
            "case {case}: {:e} {:e}",
            c.time,
            c.amplitude
        );
        total += c.arrivals;
    }
    assert!(total > 12 * 54 * 20, "{total}");
}

/// Random polygon rooms (convex ones and L shapes, one interface per wall), fixed and absorbing laws, a point or a line source, with a grid of receivers over
/// the room's box (some outside it): the streamed arrivals are the listed ones.
#[test]
fn random_rooms_with_grids_stream_the_listed_arrivals() {
    let mut rng = SplitMix64(393939);
    let mut total = 0;
    for case in 0..10 {
        let corners: Vec<[f64; 2]> = if case % 2 == 0 {
            let n = 5 + case % 4;
            let (rx, ry) = (rng.range(3.0, 6.0), rng.range(3.0, 6.0));
            (0..n)
                .map(|i| {
                    let t = std::f64::consts::TAU * (i as f64 + rng.range(0.0, 0.7)) / n as f64;
                    [rx * t.cos(), ry * t.sin()]
                })
                .collect()
        } else {
            let (w, h) = (rng.range(5.0, 8.0), rng.range(4.0, 7.0));
            let (a, b) = (rng.range(0.3, 0.7) * w, rng.range(0.3, 0.7) * h);
            let mut c = vec![[0.0, 0.0], [w, 0.0], [w, b], [a, b], [a, h], [0.0, h]];
            for p in &mut c {
                p[0] += rng.range(-0.1, 0.1) - w / 2.0;
                p[1] += rng.range(-0.1, 0.1) - h / 2.0;
            }
            c
        };
        let mut interfaces = serde_json::Map::new();
        {
            for i in 0..corners.len() {
                let (p, q) = (corners[i], corners[(i + 1) % corners.len()]);
                let reflection = match (rng.next_f64() * 3.0) as usize {
                    0 => json!("rigid"),
                    1 => json!({ "absorption": 0.3 }),
                    _ => json!({ "coefficient": 0.8 }),
                };
                interfaces.insert(
                    format!("w{i}"),
                    json!({ "points": [p, q], "reflection": reflection }),
                );
            }
        }
        let (lo, hi) = corners
            .iter()
            .fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), p| {
                (
                    [lo[0].min(p[0]), lo[1].min(p[1])],
                    [hi[0].max(p[0]), hi[1].max(p[1])],
                )
            });
        let doc = json!({
            "media": { "air": { "speed": 343 } }, "background": "air",
            "interfaces": interfaces,
            "sources": [[rng.range(-0.5, 0.5), rng.range(-0.5, 0.5)]],
            "receivers": { "grid": { "x": [lo[0] + 0.05, hi[0] - 0.05, 7],
                                     "y": [lo[1] + 0.05, hi[1] - 0.05, 6] } },
            "search": { "max_steps": 6, "refract": false },
            "amplitudes": { "source": if case % 2 == 0 { "point" } else { "line" }, "frequency": 500 }
        });
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let c = compare(&scene);
        assert!(
            c.time <= 1e-12 && c.amplitude <= 1e-12,
            "case {case}: {:e} {:e}",
            c.time,
            c.amplitude
        );
        total += c.arrivals;
    }
    assert!(total > 10 * 42 * 20, "{total}");
}
