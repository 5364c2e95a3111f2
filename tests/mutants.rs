//! Control-flow features against ground truth that does not come from the code under test:
//! the layout of the impulse-response buffer (its documented index, each response the closed
//! form of a point source), `max_time` (an arrival exactly at it, in exactly representable
//! geometry), the walk's time bound (a path's first leg in the slow medium), the work budget
//! of a pair's walk, the stop request of the beam tree, and a corner where two walls meet
//! (exact rational arithmetic). Each test here fails on a one-line bug that the rest of the
//! suite once let through (a mutation audit): see the comment of each.

use std::f64::consts::PI;

use eigenray::options::{Progress, Run};
use eigenray::response::{ImpulseResponses, echoes_of_scene};
use eigenray::search::SearchReport;
use eigenray::{Scene, Status, Tracer};
use serde_json::{Value, json};

fn scene(doc: &Value) -> Scene {
    Scene::from_json(&doc.to_string()).unwrap()
}

/// The scene's search, without limits, progress or stop.
fn search(scene: &Scene) -> SearchReport {
    Tracer::new(scene).unwrap().search(&Run::new()).unwrap()
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
    let sources: [[f64; 2]; 2] = [[0.0, 0.0], [1.5, 4.0]];
    let receivers: [[f64; 2]; 3] = [[3.0, 1.0], [-2.0, 2.5], [5.5, -1.0]];
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
    let echoes = echoes_of_scene(&tracer, &Run::new()).unwrap();
    assert_eq!(echoes.len(), 6, "one direct ray per pair");
    let options = scene.impulse_response().unwrap();
    let ir = ImpulseResponses::new(options, 2, 3);
    let out = ir.render(echoes.iter().copied(), &Run::new()).unwrap();
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
            assert!(
                err < 1e-12 * norm,
                "source {s}, receiver {r}: error {err:e}"
            );
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

/// The lens's iteration limit per solve.
const MAX_ITERATIONS: u64 = 20;

/// A lens: a closed polygon of `n` segments on the unit circle, glass (speed 1/2) inside, air
/// (speed 1) outside, source left and receiver right.
fn lens(n: usize, search: Value, max_work: Option<u64>) -> Value {
    let points: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let a = 2.0 * PI * k as f64 / n as f64;
            [a.cos(), a.sin()]
        })
        .collect();
    let mut doc = json!({
        "media": { "air": { "speed": 1 }, "glass": { "speed": 0.5, "at": [0, 0] } },
        "background": "air",
        "interfaces": { "lens": { "points": points, "closed": true } },
        "sources": [[-3, 0.1]],
        "receivers": [[3, -0.2]],
        "search": search
    });
    doc["solver"] = json!({ "max_iterations": MAX_ITERATIONS });
    if let Some(w) = max_work {
        doc["solver"]["max_work"] = json!(w);
    }
    doc
}

/// The lens (8 segments) searched for every arrival of up to 2 steps, its one pair's walk
/// within `solver.max_work` = `w`: the work a walk does is its budget at most, plus what one
/// step of the complete search that crosses it counts (a bound, steps + 1 units, then at most
/// one solve) and the sequence's own unit, whatever the budget; a budget below what the walk needs leaves the
/// pair incomplete. The walk spends about 3,500 units without a budget: each budget here
/// stops it part way, after several complete searches. (A solve counts its Newton work when
/// it ends: (iterations + 1) × (steps + 1) units, at most (`max_iterations` + 1) × 3 here.)
///
/// Mutant caught: each complete search of the pair given the whole `max_work` instead of what
/// is left of it (`search/sequences.rs`, `PairState::search`): the pair's work then reaches
/// what it spent before that search plus the whole budget.
#[test]
fn a_pairs_walk_spends_at_most_its_budget() {
    let steps = 2u64;
    let unbounded = search(&scene(&lens(8, json!({ "max_steps": steps }), None)));
    assert_eq!(unbounded.incomplete_pairs, 0);
    let needed = unbounded.work;
    assert!(needed > 3000, "{needed}");
    for w in [needed / 4, needed / 2, 3 * needed / 4, needed - needed / 10] {
        let report = search(&scene(&lens(8, json!({ "max_steps": steps }), Some(w))));
        assert_eq!(report.incomplete_pairs, 1, "max_work {w}");
        assert!(
            report.work <= w + (MAX_ITERATIONS + 2) * (steps + 1) + 1,
            "max_work {w}: the walk spent {}",
            report.work
        );
        assert!(report.arrivals.iter().all(|a| !a.complete));
    }
}

/// A vertical interface `x = 10` across the domain, slow medium (speed 1) left of it, fast
/// (speed 10) right of it; source (0, 0), receiver (20, 0). Every path with a step at the
/// interface has its first leg in the slow medium, from the source to `x = 10`: at least 10
/// long, so it takes at least 10. With `max_time` 5 the walk over sequences therefore
/// searches no sequence: it visits the empty one alone (work 1) and lists nothing. With
/// `max_time` 12 it lists the refracted path straight through, 10 + 10 / 10 = 11.
///
/// Mutant caught: the walk's time bound taken from the least slowness of every medium (or of
/// the leg after the step) instead of the prefix's leg media (`search/sequences.rs`,
/// `Walk::child`): that bound, 1 + 1 = 2, prunes nothing, and the walk searches on.
#[test]
fn the_walk_prunes_by_the_slowness_of_the_prefix() {
    let doc = |max_time: f64| {
        json!({
            "media": {
                "slow": { "speed": 1, "at": [0, 0] },
                "fast": { "speed": 10, "at": [20, 0] }
            },
            "domain": [[-100, -100], [100, 100]],
            "interfaces": { "wall": { "points": [[10, -100], [10, 100]] } },
            "sources": [[0, 0]],
            "receivers": [[20, 0]],
            "search": { "max_time": max_time, "max_steps": 3 }
        })
    };
    let early = search(&scene(&doc(5.0)));
    assert!(early.arrivals.is_empty(), "{:?}", early.arrivals);
    assert_eq!(early.incomplete_pairs, 0);
    assert_eq!(early.work, 1, "sequences visited and searched");

    let late = search(&scene(&doc(12.0)));
    assert_eq!(late.incomplete_pairs, 0);
    assert_eq!(late.arrivals.len(), 1, "{:?}", late.arrivals);
    let a = &late.arrivals[0];
    assert_eq!(a.steps.len(), 1);
    assert!((a.arrival.time - 11.0).abs() <= 1e-12, "{}", a.arrival.time);
    assert!(late.work > 1);
}

/// A hexagonal room (pyroomacoustics' hexagon, each wall its own interface), one source, every
/// reflection up to order 60: its beam tree visits tens of thousands of beams. Asked to stop
/// before the search, the tree visits none; asked to stop from the search's first report of
/// progress (which comes after at most 2^14 beams), it visits no more beams than that report
/// told of. Either way its pairs say `complete: false`.
///
/// Mutants caught: the beam tree not checking the stop, at its start or at its reports of
/// progress (`search/beams.rs`, `Tracer::beam_tree`).
#[test]
fn the_beam_tree_stops_when_asked() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fixtures/pyroomacoustics/hexagon.json"
    );
    let mut doc: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    doc["sources"] = json!([doc["sources"][0]]);
    doc["search"] = json!({ "max_steps": 60, "refract": false });
    let scene = scene(&doc);
    let tracer = Tracer::new(&scene).unwrap();
    let receivers = scene.receivers().len();

    let full = tracer.search(&Run::new()).unwrap();
    assert_eq!(full.incomplete_pairs, 0);
    assert!(full.beams > 4 << 14, "{} beams", full.beams);

    let stop = Run::new();
    stop.request_stop();
    let before = tracer.search(&stop).unwrap();
    assert_eq!(before.beams, 0);
    assert_eq!(before.incomplete_pairs, receivers);
    assert!(before.arrivals.is_empty());

    let reported = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
    let stop = Run::new();
    let (heard, handle) = (reported.clone(), stop.clone());
    let stop = stop.on_progress(move |p: Progress| {
        if p.work > 0 {
            heard.fetch_add(p.work, std::sync::atomic::Ordering::Relaxed);
            handle.request_stop();
        }
    });
    let during = tracer.search(&stop).unwrap();
    let told = reported.load(std::sync::atomic::Ordering::Relaxed);
    assert!(told > 0 && told <= 1 << 14, "{told} beams reported");
    assert!(during.beams <= told, "{} beams after {told}", during.beams);
    assert_eq!(during.incomplete_pairs, receivers);
    assert!(during.arrivals.len() < full.arrivals.len());
    assert!(during.arrivals.iter().all(|a| !a.complete));
}

/// Two walls that meet at a corner, each its own interface: `floor` from (4, 0) to (0, 0) and
/// `side` from (0, 0) to (0, 4); source (1, 1) inside the corner, receiver (−2, 2) beyond
/// `side`. The floor's image of the source, (1, −1), sees the receiver through (0, 0)
/// exactly (checked here in integers): the only candidate reflection lies on the corner,
/// which is no reflection point (an end of both walls: no free end of either), and no other
/// path exists (the direct ray crosses `side`, and `side` has the source and the receiver on
/// its two sides). Without `side`, (0, 0) is a free end of the floor, where a path reflects:
/// the image method's path, √18 long, is listed.
///
/// Mutant caught: the corner taken as a reflection point (a shared end taken as free in
/// `trace/mirrors.rs`, `MirrorWalls::new`), once caught only by a Python test.
#[test]
fn a_corner_where_two_walls_meet_is_no_reflection_point() {
    let (source, receiver, image) = ([1i64, 1], [-2i64, 2], [1i64, -1]);
    // The line image + t (receiver − image) meets y = 0 at t = −image_y / (receiver_y −
    // image_y) = 1/3, where x = image_x + t (receiver_x − image_x) = (3·1 + 1·(−3)) / 3 = 0.
    let (dx, dy) = (receiver[0] - image[0], receiver[1] - image[1]);
    assert_eq!(
        image[0] * dy - image[1] * dx,
        0,
        "x = 0 where the line meets y = 0"
    );
    assert!(
        dy > 0 && -image[1] > 0 && -image[1] < dy,
        "between image and receiver"
    );
    let doc = |with_side: bool| {
        let mut interfaces = json!({ "floor": { "points": [[4, 0], [0, 0]] } });
        if with_side {
            interfaces["side"] = json!({ "points": [[0, 0], [0, 4]] });
        }
        json!({
            "media": { "air": { "speed": 1 } },
            "background": "air",
            "interfaces": interfaces,
            "sources": [source],
            "receivers": [receiver],
            "search": { "max_steps": 2, "refract": false }
        })
    };
    let corner = search(&scene(&doc(true)));
    assert_eq!(corner.incomplete_pairs, 0);
    assert!(corner.arrivals.is_empty(), "{:?}", corner.arrivals);

    let free_end = search(&scene(&doc(false)));
    let times: Vec<(usize, f64)> = (free_end.arrivals.iter())
        .map(|a| (a.steps.len(), a.arrival.time))
        .collect();
    assert_eq!(times.len(), 2, "{times:?}");
    // The direct ray, (1, 1) to (−2, 2): √10.
    assert_eq!(times[0].0, 0);
    assert!((times[0].1 - 10f64.sqrt()).abs() <= 1e-15 * 10f64.sqrt());
    assert_eq!(times[1].0, 1);
    assert!((times[1].1 - 18f64.sqrt()).abs() <= 1e-15 * 18f64.sqrt());
    let p = free_end.arrivals[1].arrival.points[1];
    assert_eq!((p.x, p.y), (0.0, 0.0));
}
