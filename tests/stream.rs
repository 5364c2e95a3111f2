//! Streaming responses and transmission loss: each response of a scene summed as the search
//! finds its arrivals (`echoes_of_scene_into` and the responses over it) equals the
//! collect-then-sum path (`echoes_of_scene`, then `pressure_into` / `render_into`) to
//! round-off, and both equal independent image-source sums written here: a rectangular room
//! with absorbing walls, a flat waveguide under a pressure-release surface, Lloyd's mirror
//! and the free field.

use std::f64::consts::PI;

use eigenray::amplitude::Complex64;
use eigenray::options::Run;
use eigenray::response::{
    FractionalDelay, ImpulseResponses, echoes_of_scene, echoes_of_scene_into, incoherent_loss,
    pressure_into, pressure_of_scene_into, transmission_loss, transmission_loss_of_scene_into,
};
use eigenray::scene::TransmissionLossMode;
use eigenray::{Scene, Tracer};
use serde_json::{Value, json};

const C: f64 = 343.0;

/// A `lx × ly` room in air, each wall its own interface absorbing `alpha`, one source,
/// `receivers`, every arrival up to `max_time`, amplitudes at `frequency` and responses at
/// `rate` for `duration`.
fn room(alpha: f64, receivers: Value, max_time: f64, frequency: f64) -> Scene {
    let (lx, ly) = (6.0, 4.0);
    let r = json!({ "absorption": alpha });
    let doc = json!({
        "media": { "air": { "speed": C } }, "background": "air",
        "interfaces": {
            "north": { "points": [[0, ly], [lx, ly]], "reflection": r },
            "east":  { "points": [[lx, 0], [lx, ly]], "reflection": r },
            "south": { "points": [[0, 0], [lx, 0]], "reflection": r },
            "west":  { "points": [[0, 0], [0, ly]], "reflection": r }
        },
        "sources": [[1.5, 1.2]],
        "receivers": receivers,
        "search": { "max_time": max_time, "refract": false },
        "amplitudes": { "source": "point", "frequency": frequency },
        "impulse_response": { "rate": 8000, "duration": max_time + 0.01 }
    });
    Scene::from_json(&doc.to_string()).unwrap()
}

/// Image sources of a source at `s` in `[0, l]`: (position, reflections) for every image
/// within `reach` of the interval.
fn images_1d(s: f64, l: f64, reach: f64) -> Vec<(f64, u32)> {
    let m = (reach / (2.0 * l)).ceil() as i64 + 1;
    let mut out = Vec::new();
    for k in -m..=m {
        let base = 2.0 * l * k as f64;
        out.push((base + s, (2 * k).unsigned_abs() as u32));
        out.push((base - s, (2 * k - 1).unsigned_abs() as u32));
    }
    out
}

/// The image-source echoes of the room at `r`: (time, amplitude) of each image within
/// `max_time`, the amplitude `(√(1 − α))^k / (4πR)`.
fn room_images(alpha: f64, s: [f64; 2], r: [f64; 2], max_time: f64) -> Vec<(f64, f64)> {
    let reach = max_time * C + 10.0;
    let mut out = Vec::new();
    for (x, kx) in images_1d(s[0], 6.0, reach) {
        for (y, ky) in images_1d(s[1], 4.0, reach) {
            let d = ((x - r[0]).powi(2) + (y - r[1]).powi(2)).sqrt();
            if d / C <= max_time {
                let a = (1.0 - alpha).sqrt().powi((kx + ky) as i32) / (4.0 * PI * d);
                out.push((d / C, a));
            }
        }
    }
    out
}

fn phase(f: f64, t: f64) -> Complex64 {
    Complex64::from_polar(1.0, 2.0 * PI * (f * t).fract())
}

/// The pressures of `scene` both ways: streamed, and collected then summed.
fn both_ways(tracer: &Tracer, f: f64) -> (Vec<Complex64>, Vec<Complex64>) {
    let scene = tracer.scene();
    let n = scene.sources().len() * scene.receivers().len();
    let mut streamed = vec![Complex64::new(0.0, 0.0); n];
    pressure_of_scene_into(tracer, f, &Run::new(), &mut streamed).unwrap();
    let echoes = echoes_of_scene(tracer, &Run::new()).unwrap();
    let mut collected = vec![Complex64::new(0.0, 0.0); n];
    pressure_into(
        echoes,
        f,
        scene.sources().len(),
        &Run::new(),
        &mut collected,
    );
    (streamed, collected)
}

/// Σ|a| per pair: the scale of a coherent sum's round-off.
fn scales(tracer: &Tracer) -> Vec<f64> {
    let scene = tracer.scene();
    let nr = scene.receivers().len();
    let mut s = vec![0.0; scene.sources().len() * nr];
    for e in echoes_of_scene(tracer, &Run::new()).unwrap() {
        s[e.source * nr + e.receiver] += e.amplitude.norm();
    }
    s
}

#[test]
fn a_streamed_room_equals_its_collected_sum_and_its_image_sources() {
    let (alpha, max_time, f) = (0.1, 0.08, 500.0);
    let receivers = [[4.5, 2.7], [3.8, 1.0], [2.2, 3.1], [0.4, 0.3]];
    let scene = room(alpha, json!(receivers), max_time, f);
    let tracer = Tracer::new(&scene).unwrap();
    let (streamed, collected) = both_ways(&tracer, f);
    let scale = scales(&tracer);
    for (k, r) in receivers.iter().enumerate() {
        let images = room_images(alpha, [1.5, 1.2], *r, max_time);
        assert!(images.len() > 40, "{}", images.len());
        let want: Complex64 = images.iter().map(|&(t, a)| a * phase(f, t)).sum();
        let sum: f64 = images.iter().map(|&(_, a)| a).sum();
        assert!(
            (scale[k] - sum).abs() < 1e-12 * sum,
            "{k}: {} {sum}",
            scale[k]
        );
        assert!((streamed[k] - collected[k]).norm() <= 1e-12 * sum, "{k}");
        assert!(
            (streamed[k] - want).norm() <= 1e-12 * sum,
            "{k}: {} {want}",
            streamed[k]
        );
    }
    // The echoes streamed are the echoes listed.
    let count = std::sync::atomic::AtomicU64::new(0);
    let summed = echoes_of_scene_into(&tracer, &Run::new(), &|_| {
        count.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    })
    .unwrap();
    let listed = echoes_of_scene(&tracer, &Run::new()).unwrap().len() as u64;
    assert_eq!((summed.echoes, count.into_inner()), (listed, listed));
    assert_eq!((summed.without_amplitude, summed.incomplete_pairs), (0, 0));
}

#[test]
fn a_streamed_impulse_response_equals_its_collected_one_and_its_image_sources() {
    let (alpha, max_time) = (0.1, 0.1);
    let receivers = [[4.5, 2.7], [3.8, 1.0]];
    let scene = room(alpha, json!(receivers), max_time, 500.0);
    let tracer = Tracer::new(&scene).unwrap();
    let ir = ImpulseResponses::new(scene.impulse_response().unwrap(), 1, 2);
    let mut streamed = vec![f64::NAN; ir.len()];
    ir.render_scene_into(&tracer, &Run::new(), &mut streamed)
        .unwrap();
    let echoes = echoes_of_scene(&tracer, &Run::new()).unwrap();
    let collected = ir.render(echoes, &Run::new()).unwrap();
    let pulse = FractionalDelay::hann_sinc(81);
    for (k, r) in receivers.iter().enumerate() {
        let mut want = vec![0.0; ir.samples()];
        for (t, a) in room_images(alpha, [1.5, 1.2], *r, max_time) {
            pulse.add(&mut want, t * ir.rate(), Complex64::new(a, 0.0));
        }
        let peak = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(peak > 0.0);
        let (s, c) = (ir.response(&streamed, 0, k), ir.response(&collected, 0, k));
        for n in 0..ir.samples() {
            assert!((s[n] - c[n]).abs() <= 1e-12 * peak, "{k} {n}");
            assert!(
                (s[n] - want[n]).abs() <= 1e-12 * peak,
                "{k} {n}: {} {}",
                s[n],
                want[n]
            );
        }
    }
}

#[test]
fn a_streamed_search_with_refractions_equals_its_collected_sum() {
    // Air over water under a bent surface: the walk over sequences (refractions) streams
    // its arrivals from the threads of its pairs, after every tree's.
    let doc = json!({
        "domain": [[-20, -10], [20, 10]],
        "media": { "air": { "speed": 343.0, "at": [0.0, 5.0], "density": 1.2 },
                   "water": { "speed": 1500.0, "at": [0.0, -5.0], "density": 1000.0 } },
        "interfaces": {
            "surface": { "points": [[-20, 0], [-5, 0.5], [5, -0.5], [20, 0]],
                         "reflection": "media" },
            "bottom": { "points": [[-20, -10], [20, -10]] }
        },
        "sources": [[0.0, 5.0], [-3.0, 2.0]],
        "receivers": [[8.0, 3.0], [6.0, -4.0], [-7.0, -8.0], [2.0, 1.0]],
        "search": { "max_steps": 3 },
        "amplitudes": { "source": "point", "frequency": 200 }
    });
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let (streamed, collected) = both_ways(&tracer, 200.0);
    let scale = scales(&tracer);
    assert!(scale.iter().all(|&s| s > 0.0));
    for k in 0..streamed.len() {
        assert!(
            (streamed[k] - collected[k]).norm() <= 1e-12 * scale[k],
            "{k}"
        );
    }
}

/// A waveguide of depth `depth` (surface y = 0 pressure-release, a rigid bottom), the source
/// at `(0, −zs)`, `receivers`, every arrival by `max_time`, with `extra` keys.
fn waveguide(depth: f64, zs: f64, receivers: Value, max_time: f64, extra: Value) -> Scene {
    let mut doc = json!({
        "media": { "water": { "speed": 1500.0 } }, "background": "water",
        "interfaces": {
            "surface": { "points": [[-20000, 0], [20000, 0]], "reflection": "pressure-release" },
            "bottom": { "points": [[-20000, -depth], [20000, -depth]], "reflection": "rigid" }
        },
        "sources": [[0.0, -zs]],
        "receivers": receivers,
        "search": { "max_time": max_time, "refract": false },
        "amplitudes": { "source": "point", "frequency": 100 }
    });
    for (k, v) in extra.as_object().unwrap() {
        doc[k] = v.clone();
    }
    Scene::from_json(&doc.to_string()).unwrap()
}

/// The image sum of the waveguide at `(x, −z)`: (time, amplitude) of each image within
/// `max_time`, the sign `(−1)^(surface reflections)`.
fn waveguide_images(depth: f64, zs: f64, x: f64, z: f64, max_time: f64) -> Vec<(f64, f64)> {
    let m = (max_time * 1500.0 / depth).ceil() as i64 + 2;
    let mut out = Vec::new();
    for k in -m..=m {
        // The image in the k-th mirrored copy of the guide: depth kD + zs (k even) or
        // (k + 1)D − zs (k odd); the planes jD crossed on the way, surfaces where j is even.
        let d = if k % 2 == 0 {
            k as f64 * depth + zs
        } else {
            (k + 1) as f64 * depth - zs
        };
        let planes: Vec<i64> = if k > 0 {
            (1..=k).collect()
        } else {
            (k + 1..=0).collect()
        };
        let surfaces = planes.iter().filter(|j| *j % 2 == 0).count() as i32;
        let r = (x * x + (d - z) * (d - z)).sqrt();
        if r / 1500.0 <= max_time {
            out.push((r / 1500.0, (-1.0f64).powi(surfaces) / (4.0 * PI * r)));
        }
    }
    out
}

#[test]
fn waveguide_transmission_loss_against_its_image_sum_both_modes() {
    let (depth, zs, max_time) = (100.0, 25.0, 1.2);
    let receivers: Vec<[f64; 2]> = (1..=12)
        .flat_map(|i| [[100.0 * i as f64, -10.0], [100.0 * i as f64 + 7.0, -63.0]])
        .collect();
    let extra = json!({ "transmission_loss": { "mode": "incoherent" } });
    let scene = waveguide(depth, zs, json!(receivers), max_time, extra);
    assert_eq!(
        scene.transmission_loss(),
        Some(TransmissionLossMode::Incoherent)
    );
    let tracer = Tracer::new(&scene).unwrap();
    let f = 100.0;
    let mut coherent = vec![0.0; receivers.len()];
    let mut incoherent = vec![0.0; receivers.len()];
    let run = Run::new();
    let c = TransmissionLossMode::Coherent;
    transmission_loss_of_scene_into(&tracer, f, c, &run, &mut coherent).unwrap();
    let i = TransmissionLossMode::Incoherent;
    transmission_loss_of_scene_into(&tracer, f, i, &run, &mut incoherent).unwrap();
    for (k, r) in receivers.iter().enumerate() {
        let images = waveguide_images(depth, zs, r[0], -r[1], max_time);
        assert!(images.len() > 10);
        let p: Complex64 = images.iter().map(|&(t, a)| a * phase(f, t)).sum();
        let sum: f64 = images.iter().map(|&(_, a)| a.abs()).sum();
        let energy: f64 = images.iter().map(|&(_, a)| a * a).sum();
        // dB of the coherent sum, to its round-off relative to |p|.
        let tl = -20.0 * (4.0 * PI * p.norm()).log10();
        let db = 20.0 / 10f64.ln() * 1e-12 * sum / p.norm();
        assert!(
            (coherent[k] - tl).abs() <= db.max(1e-12),
            "{k}: {} {tl}",
            coherent[k]
        );
        let tli = -10.0 * (16.0 * PI * PI * energy).log10();
        assert!(
            (incoherent[k] - tli).abs() < 1e-9,
            "{k}: {} {tli}",
            incoherent[k]
        );
        assert!((incoherent_loss(energy) - tli).abs() < 1e-12);
        // The incoherent sum is the mean of the coherent one over phases: never below the
        // strongest single echo's loss.
        let strongest = images.iter().fold(0.0f64, |m, &(_, a)| m.max(a.abs()));
        assert!(incoherent[k] <= -20.0 * (4.0 * PI * strongest).log10() + 1e-9);
    }
}

#[test]
fn lloyds_mirror_and_the_free_field() {
    // Pressure-release surface alone: the direct and surface-reflected arrivals,
    // |e^(ikR₁)/R₁ − e^(ikR₂)/R₂| / (4π).
    let (zs, f) = (25.0, 100.0);
    let k = 2.0 * PI * f / 1500.0;
    let receivers: Vec<[f64; 2]> = (1..40).map(|i| [37.0 * i as f64, -40.0]).collect();
    let doc = json!({
        "media": { "water": { "speed": 1500.0 } }, "background": "water",
        "interfaces": {
            "surface": { "points": [[-5000, 0], [5000, 0]], "reflection": "pressure-release" }
        },
        "sources": [[0.0, -zs]],
        "receivers": receivers,
        "search": { "max_steps": 1 },
        "amplitudes": { "source": "point", "frequency": f }
    });
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let mut tl = vec![0.0; receivers.len()];
    let c = TransmissionLossMode::Coherent;
    transmission_loss_of_scene_into(&tracer, f, c, &Run::new(), &mut tl).unwrap();
    for (i, r) in receivers.iter().enumerate() {
        let r1 = (r[0] * r[0] + (r[1] + zs).powi(2)).sqrt();
        let r2 = (r[0] * r[0] + (r[1] - zs).powi(2)).sqrt();
        let p = Complex64::from_polar(1.0 / r1, k * r1) - Complex64::from_polar(1.0 / r2, k * r2);
        let want = -20.0 * (p.norm()).log10();
        let db = 20.0 / 10f64.ln() * 1e-12 * (1.0 / r1 + 1.0 / r2) / p.norm();
        assert!(
            (tl[i] - want).abs() <= db.max(1e-11),
            "{i}: {} {want}",
            tl[i]
        );
        assert!((tl[i] - transmission_loss(p / (4.0 * PI))).abs() <= db.max(1e-11));
    }
    // Free field: 20 log10(r), and +inf where nothing arrives (a receiver above the
    // surface, which no arrival of the water reaches).
    let doc = json!({
        "media": { "water": { "speed": 1500.0 } }, "background": "water",
        "sources": [[0.0, 0.0]],
        "receivers": [[1.0, 0.0], [30.0, 40.0], [-1000.0, 0.0]],
        "search": { "max_time": 0.1 },
        "amplitudes": { "source": "point", "frequency": f }
    });
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    for mode in [
        TransmissionLossMode::Coherent,
        TransmissionLossMode::Incoherent,
    ] {
        let mut tl = vec![0.0; 3];
        transmission_loss_of_scene_into(&tracer, f, mode, &Run::new(), &mut tl).unwrap();
        assert!(tl[0].abs() < 1e-12, "{tl:?}");
        assert!((tl[1] - 20.0 * 50f64.log10()).abs() < 1e-12, "{tl:?}");
        // 1000 m is 0.667 s away: past max_time, nothing arrives.
        assert_eq!(tl[2], f64::INFINITY);
    }
}

#[test]
fn a_streamed_response_holds_no_arrival() {
    // A memory limit of a few arrivals stops the listing search short; the streamed sum
    // holds none of them, so it completes, and equals the image sum.
    let (alpha, max_time, f) = (0.1, 0.08, 500.0);
    let scene = room(alpha, json!([[4.5, 2.7]]), max_time, f);
    let tracer = Tracer::new(&scene).unwrap();
    let mut run = Run::new();
    run.limits.memory = 4 * eigenray::search::arrival_bytes(3);
    let listed = tracer.search(&run).unwrap();
    assert_eq!(listed.incomplete_pairs, 1);
    assert!(listed.arrivals.len() < 10);
    let mut p = [Complex64::new(0.0, 0.0)];
    let summed = pressure_of_scene_into(&tracer, f, &run, &mut p).unwrap();
    let images = room_images(alpha, [1.5, 1.2], [4.5, 2.7], max_time);
    assert_eq!(summed.incomplete_pairs, 0);
    assert_eq!(summed.echoes, images.len() as u64);
    let want: Complex64 = images.iter().map(|&(t, a)| a * phase(f, t)).sum();
    let sum: f64 = images.iter().map(|&(_, a)| a).sum();
    assert!((p[0] - want).norm() <= 1e-12 * sum);
}

/// The times of the arrivals `search_into` streams with `run`, sorted, and its report.
fn streamed_times(tracer: &Tracer, run: &Run) -> (Vec<f64>, eigenray::search::StreamReport) {
    let times = std::sync::Mutex::new(Vec::new());
    let report = tracer
        .search_into(run, &|a| times.lock().unwrap().push(a.time))
        .unwrap();
    let mut times = times.into_inner().unwrap();
    times.sort_by(f64::total_cmp);
    (times, report)
}

#[test]
fn a_streamed_search_honours_its_run() {
    let scene = room(0.1, json!([[4.5, 2.7], [3.8, 1.0]]), 0.08, 500.0);
    let tracer = Tracer::new(&scene).unwrap();
    let (all, report) = streamed_times(&tracer, &Run::new());
    let mut listed: Vec<f64> = (tracer.search(&Run::new()).unwrap().arrivals.iter())
        .map(|a| a.arrival.time)
        .collect();
    listed.sort_by(f64::total_cmp);
    // The room's image paths stream in closed form (their times to round-off).
    assert_eq!(all.len(), listed.len());
    for (a, b) in all.iter().zip(&listed) {
        assert!((a - b).abs() <= 1e-12 * b, "{a} {b}");
    }
    assert_eq!(
        (report.arrivals, report.incomplete_pairs),
        (listed.len() as u64, 0)
    );
    // A stop requested before: nothing streamed, every pair short.
    let stopped = Run::new();
    stopped.request_stop();
    let (none, report) = streamed_times(&tracer, &stopped);
    assert!(none.is_empty());
    assert_eq!(report.incomplete_pairs, 2);
    // A budget: a part of the arrivals, each one of the unbounded call's, pairs short.
    let (some, report) = streamed_times(&tracer, &Run::new().budget(40));
    assert!(some.len() < all.len() && report.incomplete_pairs > 0);
    assert!(some.iter().all(|t| all.contains(t)));
    // `max_time`: exactly the unbounded arrivals up to that time.
    let early = room(0.1, json!([[4.5, 2.7], [3.8, 1.0]]), 0.05, 500.0);
    let (first, _) = streamed_times(&Tracer::new(&early).unwrap(), &Run::new());
    let want: Vec<f64> = all.iter().copied().filter(|&t| t <= 0.05).collect();
    assert_eq!(first, want);
    // A response stopped before does not sum.
    let mut p = [Complex64::new(0.0, 0.0); 2];
    let summed = pressure_of_scene_into(&tracer, 500.0, &stopped, &mut p).unwrap();
    assert_eq!(summed.echoes, 0);
    assert_eq!(p, [Complex64::new(0.0, 0.0); 2]);
}

/// A small deterministic generator (SplitMix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A rectangular room's streamed arrivals (its image paths in closed form: the time and the
/// amplitude from the unfolded line, each wall's coefficient to the power of its
/// reflections) against the listed ones (each path's points validated and walked by the
/// general amplitude pass), arrival by arrival, in random rooms (axis-aligned and turned),
/// with a random law per wall (rigid, pressure-release, absorption, a coefficient, `"media"`
/// against a slower fluid or a faster one, beyond its critical angle for some paths), point
/// and line sources, with and without attenuation: the same arrivals and times (1e-12), the
/// same amplitudes within 1e-12 relative where every wall's law is a fixed coefficient. A
/// `"media"` coefficient can be ill-conditioned in its angle (near the critical angle, or
/// near its zero), where the general pass's angles from the path's points (found by
/// mirroring, to round-off that grows with the depth) and the closed form's (the unfolded
/// line's, to an ulp) give values that differ by more; there every amplitude is within
/// 1e-12 of its receiver's largest (what a response sees) and nine in ten within 1e-12
/// relative. Some amplitudes differ in their last bits (the closed forms were taken).
///
/// Mutants caught: the two cosines swapped, a `"media"` wall's coefficient at the other
/// pair's angle, the counts of two walls swapped, the attenuation of one leg.
#[test]
fn a_rectangular_rooms_closed_forms_are_its_listed_arrivals() {
    let mut rng = Rng(11);
    let (mut compared, mut differ) = (0usize, 0usize);
    let (mut media_arrivals, mut media_close) = (0usize, 0usize);
    let mut worst_fixed = 0.0f64;
    for round in 0..16 {
        let (lx, ly) = (2.0 + 8.0 * rng.next(), 1.0 + 5.0 * rng.next());
        let angle = if round % 2 == 1 {
            6.0 * rng.next()
        } else {
            0.0
        };
        let (c, s) = (angle.cos(), angle.sin());
        let at = |x: f64, y: f64| json!([3.0 + c * x - s * y, -1.0 + s * x + c * y]);
        let inside = |rng: &mut Rng| {
            at(
                lx * (0.05 + 0.9 * rng.next()),
                ly * (0.05 + 0.9 * rng.next()),
            )
        };
        // Every other round fixed coefficients only.
        let laws = if round % 2 == 0 { 4.0 } else { 6.0 };
        let law = |rng: &mut Rng| match (rng.next() * laws) as u32 {
            0 => json!("rigid"),
            1 => json!("pressure-release"),
            2 => json!({ "absorption": 0.05 + 0.5 * rng.next() }),
            3 => json!({ "coefficient": 1.6 * rng.next() - 0.8 }),
            _ => json!("media"),
        };
        let corners = [at(0.0, 0.0), at(lx, 0.0), at(lx, ly), at(0.0, ly)];
        let mut interfaces = serde_json::Map::new();
        let mut media = false;
        for w in 0..4 {
            let reflection = law(&mut rng);
            media |= reflection == json!("media");
            interfaces.insert(
                format!("w{w}"),
                json!({ "points": [corners[w], corners[(w + 1) % 4]], "reflection": reflection }),
            );
        }
        let outside = if round % 4 < 2 { 1200.0 } else { 300.0 };
        let attenuation = if round % 3 == 0 {
            0.01 + 0.05 * rng.next()
        } else {
            0.0
        };
        let amplitudes = if round % 4 == 3 {
            json!({ "source": "line", "frequency": 700.0 })
        } else {
            json!({ "source": "point" })
        };
        let receivers: Vec<Value> = (0..3).map(|_| inside(&mut rng)).collect();
        let doc = json!({
            "media": {
                "air": { "speed": C, "at": at(lx / 2.0, ly / 2.0), "attenuation": attenuation },
                "rock": { "speed": outside, "density": 2.5, "at": at(-1.0, -1.0) }
            },
            "interfaces": interfaces,
            "sources": [inside(&mut rng)],
            "receivers": receivers,
            "search": { "max_time": 9.0 * (lx + ly) / C, "refract": false },
            "amplitudes": amplitudes
        });
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let tracer = Tracer::new(&scene).unwrap();
        let listed = tracer.search(&Run::new()).unwrap().arrivals;
        let streamed = std::sync::Mutex::new(Vec::new());
        tracer
            .search_into(&Run::new(), &|a| streamed.lock().unwrap().push(a))
            .unwrap();
        let mut streamed = streamed.into_inner().unwrap();
        assert_eq!(streamed.len(), listed.len(), "round {round}");
        assert!(listed.len() > 100, "round {round}: {}", listed.len());
        let mut peak = [0.0f64; 3];
        for a in &listed {
            let v = a.arrival.amplitude.unwrap().value.norm();
            peak[a.receiver] = peak[a.receiver].max(v);
        }
        for a in &listed {
            let want = a.arrival.amplitude.unwrap();
            let (t, v) = (a.arrival.time, want.value);
            // The streamed arrival of the same receiver, steps, time and amplitude (to
            // 1e-12 of the receiver's largest: equal times are common).
            let close = |b: &eigenray::search::StreamedArrival| {
                let got = b.amplitude.unwrap();
                b.receiver == a.receiver
                    && b.steps == a.steps.len()
                    && (b.time - t).abs() <= 1e-12 * t
                    && (got.value - v).norm() <= 1e-12 * peak[a.receiver]
                    && (got.spreading - want.spreading).abs() <= 1e-12 * want.spreading
                    && (got.attenuation_db - want.attenuation_db).abs()
                        <= 1e-12 * want.attenuation_db
            };
            let Some(k) = streamed.iter().position(close) else {
                panic!(
                    "round {round}: no streamed arrival for {:?} {t} {want:?}",
                    a.steps.len()
                );
            };
            let b = streamed.swap_remove(k);
            let got = b.amplitude.unwrap().value;
            let rel = (got - v).norm() / v.norm();
            if media {
                media_arrivals += 1;
                media_close += usize::from(rel <= 1e-12);
            } else {
                worst_fixed = worst_fixed.max(rel);
                assert!(rel <= 1e-12, "round {round}: {got} {v}");
            }
            differ += usize::from(got != v || b.time != t);
            compared += 1;
        }
    }
    assert!(differ > compared / 10, "{differ} of {compared}");
    assert!(media_arrivals > 1000 && media_close * 10 > media_arrivals * 9);
    eprintln!(
        "{compared} arrivals, {differ} not bit for bit; fixed laws: worst {worst_fixed:e}; \
         media: {media_close} of {media_arrivals} within 1e-12 relative"
    );
}
