//! Control-flow features against ground truth that does not come from the code under test:
//! the layout of the impulse-response buffer (its documented index, each response the closed
//! form of a point source), `max_time` (an arrival exactly at it, in exactly representable
//! geometry), the walk's time bound (a path's first leg in the slow medium), the work budget
//! of a pair's walk, the stop request of the beam tree, and a corner where two walls meet
//! (exact rational arithmetic). Each test here fails on a one-line bug that the rest of the
//! suite once let through (a mutation audit): see the comment of each.

use std::f64::consts::PI;

use eigenray::options::Stop;
use eigenray::response::{ImpulseResponses, echoes_of_scene};
use eigenray::search::{SearchLimits, SearchProgress, SearchReport};
use eigenray::{Scene, Status, Tracer};
use serde_json::{Value, json};

fn scene(doc: &Value) -> Scene {
    Scene::from_json(&doc.to_string()).unwrap()
}

/// The scene's search, without limits, progress or stop.
fn search(scene: &Scene) -> SearchReport {
    Tracer::new(scene)
        .unwrap()
        .search_with(&SearchLimits::default(), &|_| {}, None)
        .unwrap()
}

/// The 81-tap Hann-windowed sinc pulse of amplitude `a` centred on sample `x`, added to
/// `out`: the pulse of a response, written out here from its definition.
fn add_pulse(out: &mut [f64], x: f64, a: f64) {
    let whole = x.floor();
    for tap in 0..81 {
        let n = whole - 40.0 + tap as f64;
        if n >= 0.0 && (n as usize) < out.len() {
            let hann = 0.5 - 0.5 * (2.0 * PI * tap as f64 / 80.0).cos();
            let u = PI * (n - x);
            out[n as usize] += a * hann * if u == 0.0 { 1.0 } else { u.sin() / u };
        }
    }
}

/// Two sources and three receivers in free space (speed 343, a point source's amplitudes,
/// 8 kHz for 0.1 s): the buffer of their responses is source-major, `(s · 3 + r) · samples +
/// n`, and each response is the direct ray's pulse, `1 / (4π d)` at `d / 343` (the closed
/// form of a point source), no two alike.
///
/// Mutant caught: the buffer laid out receiver-major (`(r · sources + s) · samples`) in
/// `ImpulseResponses` (`render_into` and `response`), which every test with one source and
/// one receiver lets through.
#[test]
fn impulse_responses_are_laid_out_source_major() {
    let sources = [[0.0, 0.0], [1.5, 4.0]];
    let receivers = [[3.0, 1.0], [-2.0, 2.5], [5.5, -1.0]];
    let doc = json!({
        "media": { "air": { "speed": 343 } },
        "background": "air",
        "sources": sources,
        "receivers": receivers,
        "search": { "max_steps": 0 },
        "amplitudes": { "source": "point", "frequency": 500 },
        "impulse_response": { "rate": 8000, "duration": 0.1 }
    });
    let scene = scene(&doc);
    let tracer = Tracer::new(&scene).unwrap();
    let echoes = echoes_of_scene(&tracer).unwrap();
    assert_eq!(echoes.len(), 6, "one direct ray per pair");
    let options = scene.impulse_response().unwrap();
    let ir = ImpulseResponses::new(options, 2, 3);
    let out = ir.try_render(echoes.iter().copied()).unwrap();
    let n = ir.samples();
    assert_eq!(out.len(), 2 * 3 * n);
    let mut blocks: Vec<Vec<f64>> = Vec::new();
    for (s, p) in sources.iter().enumerate() {
        for (r, q) in receivers.iter().enumerate() {
            let d = (p[0] - q[0]).hypot(p[1] - q[1]);
            let mut want = vec![0.0; n];
            add_pulse(&mut want, d / 343.0 * 8000.0, 1.0 / (4.0 * PI * d));
            let got = &out[(s * 3 + r) * n..(s * 3 + r + 1) * n];
            let norm = want.iter().map(|v| v * v).sum::<f64>().sqrt();
            let err = (got.iter().zip(&want))
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(err < 1e-12 * norm, "source {s}, receiver {r}: error {err:e}");
            assert_eq!(ir.response(&out, s, r), got, "source {s}, receiver {r}");
            blocks.push(want);
        }
    }
    // No two responses alike: a permutation of the blocks cannot pass.
    for i in 0..blocks.len() {
        for j in 0..i {
            let diff = (blocks[i].iter().zip(&blocks[j]))
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(diff > 1e-4, "responses {i} and {j} alike");
        }
    }
}

/// A floor `y = 0`, source (0, 1), receiver (3, 3), speed 1: the floor's image of the source
/// is (0, −1), 5 from the receiver, and the reflection point (3/4, 0) splits the path into
/// legs of 5/4 and 15/4: its time is exactly 5 in binary floating point. With `max_time`
/// exactly 5 it is listed (`max_time` is the latest time listed); with the number just below
/// 5 it is not. The direct ray (√13) is listed in both.
///
/// Mutant caught: `max_time` compared with `>=` instead of `>` in the beam tree
/// (`trace/mirrors.rs`, the validation of a node's paths), and any late bound of the tree
/// tightened below the exact one.
#[test]
fn an_arrival_exactly_at_max_time_is_listed() {
    let doc = |max_time: f64| {
        json!({
            "media": { "air": { "speed": 1 } },
            "background": "air",
            "interfaces": { "floor": { "points": [[-10, 0], [10, 0]] } },
            "sources": [[0, 1]],
            "receivers": [[3, 3]],
            "search": { "max_time": max_time, "refract": false }
        })
    };
    let at = search(&scene(&doc(5.0)));
    assert_eq!(at.incomplete_pairs, 0);
    let times: Vec<(usize, f64)> = (at.arrivals.iter())
        .map(|a| (a.steps.len(), a.arrival.time))
        .collect();
    assert_eq!(times, [(0, 13f64.sqrt()), (1, 5.0)]);
    let reflection = &at.arrivals[1].arrival;
    assert_eq!(reflection.status, Status::Converged);
    assert_eq!(reflection.points[1].x, 0.75);
    assert_eq!(reflection.points[1].y, 0.0);

    let before = search(&scene(&doc(f64::from_bits(5.0f64.to_bits() - 1))));
    assert_eq!(before.arrivals.len(), 1, "{:?}", before.arrivals);
    assert!(before.arrivals[0].steps.is_empty());
}
