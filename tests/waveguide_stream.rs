//! Two parallel walls (a waveguide) in a streamed search: the image lattice's arrivals
//! (`trace/mirrors/waveguide.rs`, times and amplitudes in closed form, no points) against the
//! listed search's (the beam tree's paths, validated, each amplitude walked over its
//! points): the same arrivals, times and amplitudes to 1e-12, over random waveguides in any
//! orientation, reflection laws, attenuation and source models; and the limits.

use std::sync::Mutex;

use eigenray::options::Run;
use eigenray::search::StreamedArrival;
use eigenray::{Scene, Tracer};
use serde_json::{Value, json};

/// A small deterministic generator (SplitMix64).
struct SplitMix64(u64);

impl SplitMix64 {
    fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The streamed arrivals of `tracer`'s search, with its report.
fn streamed(tracer: &Tracer, run: &Run) -> (Vec<StreamedArrival>, eigenray::search::StreamReport) {
    let out = Mutex::new(Vec::new());
    let report = tracer
        .search_into(run, &|a| out.lock().unwrap().push(a))
        .unwrap();
    (out.into_inner().unwrap(), report)
}

/// (receiver, steps, time, amplitude value (re, im) or NaN) of each arrival, sorted.
type Row = (usize, usize, f64, [f64; 2]);

fn sorted(mut rows: Vec<Row>) -> Vec<Row> {
    rows.sort_by(|a, b| (a.0, a.1).cmp(&(b.0, b.1)).then(a.2.total_cmp(&b.2)));
    rows
}

fn value(a: Option<eigenray::Amplitude>) -> [f64; 2] {
    a.filter(|a| a.has_value())
        .map_or([f64::NAN; 2], |a| [a.value.re, a.value.im])
}

/// The largest relative differences (time, amplitude) of the streamed arrivals from the
/// listed ones, which must be the same arrivals.
fn differences(scene: &Scene) -> (f64, f64, usize) {
    let tracer = Tracer::new(scene).unwrap();
    let listed = tracer.search(&Run::new()).unwrap();
    let (stream, report) = streamed(&tracer, &Run::new());
    assert_eq!(report.incomplete_pairs, 0);
    let a = sorted(
        listed
            .arrivals
            .iter()
            .map(|a| {
                let v = value(a.arrival.amplitude);
                (a.receiver, a.steps.len(), a.arrival.time, v)
            })
            .collect(),
    );
    let b = sorted(
        stream
            .iter()
            .map(|a| (a.receiver, a.steps, a.time, value(a.amplitude)))
            .collect(),
    );
    assert_eq!(a.len(), b.len(), "arrival counts");
    let (mut dt, mut da) = (0.0f64, 0.0f64);
    for (x, y) in a.iter().zip(&b) {
        assert_eq!((x.0, x.1), (y.0, y.1));
        dt = dt.max((x.2 - y.2).abs() / x.2);
        let size = x.3[0].hypot(x.3[1]);
        let d = (x.3[0] - y.3[0]).hypot(x.3[1] - y.3[1]);
        assert!(size > 0.0 || scene.amplitudes().is_none(), "{x:?}");
        if size > 0.0 {
            da = da.max(d / size);
        } else {
            assert!(y.3[0].is_nan());
        }
    }
    (dt, da, a.len())
}

/// A waveguide: walls `a → b` and `c → d` (`laws` theirs), the source and receivers, with
/// `extra` keys.
fn guide(
    walls: [[[f64; 2]; 2]; 2],
    laws: [Value; 2],
    source: [f64; 2],
    receivers: &[[f64; 2]],
    extra: Value,
) -> Scene {
    let mut doc = json!({
        "media": { "water": { "speed": 1500.0 } }, "background": "water",
        "interfaces": {
            "one": { "points": walls[0], "reflection": laws[0] },
            "two": { "points": walls[1], "reflection": laws[1] }
        },
        "sources": [source],
        "receivers": receivers,
        "search": { "max_steps": 14, "refract": false },
        "amplitudes": { "source": "point", "frequency": 50 }
    });
    for (k, v) in extra.as_object().unwrap() {
        doc[k] = v.clone();
    }
    Scene::from_json(&doc.to_string()).unwrap()
}

/// Random waveguides in any orientation (each wall either way round, of different lengths),
/// fixed laws, point and line sources, with and without attenuation: the closed forms are
/// the walked ones to 1e-12.
#[test]
fn random_waveguides_stream_the_listed_arrivals() {
    let mut rng = SplitMix64::new(39);
    let laws = [
        json!("rigid"),
        json!("pressure-release"),
        json!({ "absorption": 0.3 }),
        json!({ "coefficient": -0.55 }),
    ];
    let mut total = 0;
    for case in 0..24 {
        let angle = rng.next_f64() * std::f64::consts::TAU;
        let (c, s) = (angle.cos(), angle.sin());
        let (ox, oy) = (rng.next_f64() * 40.0 - 20.0, rng.next_f64() * 40.0 - 20.0);
        let h = 2.0 + 30.0 * rng.next_f64();
        let len = 200.0 + 300.0 * rng.next_f64();
        let at = |x: f64, y: f64| [ox + c * x - s * y, oy + s * x + c * y];
        let mut one = [at(-10.0, 0.0), at(len, 0.0)];
        let mut two = [at(-5.0 - 20.0 * rng.next_f64(), h), at(len + 7.0, h)];
        if rng.next_f64() < 0.5 {
            one.reverse();
        }
        if rng.next_f64() < 0.5 {
            two.reverse();
        }
        let pick = |r: f64| laws[(r * 4.0) as usize % 4].clone();
        let law = [pick(rng.next_f64()), pick(rng.next_f64())];
        let source = at(
            len * 0.3 * rng.next_f64(),
            h * (0.05 + 0.9 * rng.next_f64()),
        );
        let receivers: Vec<[f64; 2]> = (0..6)
            .map(|_| {
                at(
                    len * 0.95 * rng.next_f64(),
                    h * (0.02 + 0.96 * rng.next_f64()),
                )
            })
            .collect();
        let model = if case % 2 == 0 { "point" } else { "line" };
        let mut extra = json!({ "amplitudes": { "source": model, "frequency": 50 } });
        if case % 3 == 0 {
            extra["media"] = json!({ "water": { "speed": 1500.0, "attenuation": 0.002 } });
        }
        if case % 4 == 1 {
            extra["search"] = json!({ "max_time": len / 1500.0 * 1.3, "refract": false });
        }
        let scene = guide([one, two], law, source, &receivers, extra);
        let (dt, da, n) = differences(&scene);
        assert!(dt <= 1e-12 && da <= 1e-12, "case {case}: {dt:e} {da:e}");
        total += n;
    }
    assert!(total > 24 * 6 * 10, "{total}");
}

/// The shallow-water scenes' waveguide: a pressure-release surface over a `"media"` bottom
/// (a fluid half-space, where the grazing paths pass the critical angle), an axisymmetric
/// source, receivers on both sides of the axis, and a bottom with attenuation.
#[test]
fn shallow_water_streams_the_listed_arrivals() {
    let mut rng = SplitMix64::new(7);
    for case in 0..6 {
        let depth = 60.0 + 80.0 * rng.next_f64();
        let sediment = json!({ "speed": 1600.0 + 300.0 * rng.next_f64(),
                               "density": 1.2 + rng.next_f64(),
                               "attenuation": 0.01 * (case % 2) as f64, "at": [10, -depth - 50.0] });
        let zs = depth * (0.1 + 0.8 * rng.next_f64());
        let receivers: Vec<[f64; 2]> = (0..8)
            .map(|i| {
                let x = 50.0 + 3000.0 * rng.next_f64();
                [
                    if i % 3 == 0 { -x } else { x },
                    -depth * (0.01 + 0.98 * rng.next_f64()),
                ]
            })
            .collect();
        let doc = json!({
            "media": { "water": { "speed": 1500, "density": 1 }, "sediment": sediment },
            "background": "water",
            "domain": [[-4000, -depth - 200.0], [4000, 0]],
            "interfaces": {
                "surface": { "points": [[-4000, 0], [4000, 0]], "reflection": "pressure-release" },
                "bottom": { "points": [[-4000, -depth], [4000, -depth]], "reflection": "media" }
            },
            "sources": [[0, -zs]],
            "receivers": receivers,
            "search": { "max_steps": 30, "refract": false },
            "amplitudes": { "source": if case < 4 { "axisymmetric" } else { "point" }, "frequency": 100 }
        });
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let (dt, da, n) = differences(&scene);
        assert!(dt <= 1e-12 && da <= 1e-12, "case {case}: {dt:e} {da:e}");
        assert_eq!(n, 8 * 61);
    }
}

/// The flat shallow-water scene's geometry, where a path meets the bottom exactly at its
/// critical angle: speeds 1500 and 1700 m/s, the image of 8 bounces 800 m across and 1500 m
/// along (an 8-15-17 triangle), `sin² θ (c₂/c₁)² = 1` to an ulp. There the coefficient
/// turns each ulp of the angle into 1e-8, so the closed form hands such a bounce to the
/// tree's points: the streamed amplitudes are the listed ones to 1e-15, not 1e-8.
#[test]
fn a_bounce_at_the_critical_angle_is_walked() {
    let doc = json!({
        "media": { "water": { "speed": 1500, "density": 1 },
                   "sediment": { "speed": 1700, "density": 1.8, "at": [10, -250] } },
        "background": "water",
        "domain": [[-10, -300], [5100, 0]],
        "interfaces": {
            "surface": { "points": [[-10, 0], [5100, 0]], "reflection": "pressure-release" },
            "bottom": { "points": [[-10, -100], [5100, -100]], "reflection": "media" }
        },
        "sources": [[0, -25]],
        "receivers": [[1500, -25], [1500, -24.999], [3000, -25]],
        "search": { "max_steps": 40, "refract": false },
        "amplitudes": { "source": "axisymmetric", "frequency": 100 }
    });
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let (dt, da, n) = differences(&scene);
    assert_eq!(n, 3 * 81);
    assert!(dt <= 1e-14 && da <= 1e-13, "{dt:e} {da:e}");
}

/// Two walls 0.01 apart (the third hostile probe's), searched 65,536 reflections deep or
/// by `max_time` 1e6: the lattice lists the images one by one within the work budget,
/// stops at the depth limit or the budget and says so, and never holds more than one.
/// Beams, a stop request and `max_time` as the tree honours them.
#[test]
fn a_thin_waveguide_stays_within_its_limits() {
    let thin = |search: Value| {
        let doc = json!({
            "media": { "air": { "speed": 343 } }, "background": "air",
            "interfaces": {
                "a": { "points": [[0, 0], [10, 0]] },
                "b": { "points": [[0, 0.01], [10, 0.01]] }
            },
            "sources": [[2, 0.004]], "receivers": [[7, 0.006], [3, 0.002]],
            "search": search,
            "amplitudes": { "source": "line", "frequency": 1000 }
        });
        Tracer::new(Scene::from_json(&doc.to_string()).unwrap()).unwrap()
    };
    // 65,536 deep: every image, to both receivers (2 × 2 × 65,536 + 2 of them).
    let deep = thin(json!({ "max_steps": 65536, "refract": false }));
    let (all, report) = streamed(&deep, &Run::new());
    assert_eq!(all.len(), 2 * (2 * 65536 + 1));
    assert_eq!(report.incomplete_pairs, 0);
    assert!(all.iter().all(|a| a.amplitude.unwrap().has_value()));
    // By time: 1e6 s reaches far past the depth limit: stopped there, said short.
    let long = thin(json!({ "max_time": 1e6, "refract": false }));
    let (some, report) = streamed(&long, &Run::new());
    assert_eq!(report.incomplete_pairs, 2);
    assert!(!some.is_empty() && some.len() <= 2 * (2 * 65536 + 1));
    // A beams limit, a budget of work, a stop requested: short, and said so.
    let mut few = Run::new();
    few.limits.beams = 1000;
    let (part, report) = streamed(&deep, &few);
    assert_eq!(report.incomplete_pairs, 2);
    assert!(
        part.len() <= 1000 + 2 && part.len() >= 500,
        "{}",
        part.len()
    );
    let (part, report) = streamed(&deep, &Run::new().budget(50_000));
    assert_eq!(report.incomplete_pairs, 2);
    assert!(part.len() < all.len());
    let stopped = Run::new();
    stopped.request_stop();
    let (none, report) = streamed(&deep, &stopped);
    assert!(none.is_empty() && report.incomplete_pairs == 2);
    // `max_time`: exactly the arrivals by that time.
    let early = thin(json!({ "max_time": 0.5, "max_steps": 65536, "refract": false }));
    let (first, report) = streamed(&early, &Run::new());
    assert_eq!(report.incomplete_pairs, 0);
    let mut want: Vec<f64> = all.iter().map(|a| a.time).filter(|&t| t <= 0.5).collect();
    let mut got: Vec<f64> = first.iter().map(|a| a.time).collect();
    want.sort_by(f64::total_cmp);
    got.sort_by(f64::total_cmp);
    assert_eq!(got.len(), want.len());
    for (a, b) in got.iter().zip(&want) {
        assert!((a - b).abs() <= 1e-12 * b);
    }
}
