//! Batches: the same rays as one-by-one solving, in ray order, and warm starts that save
//! iterations.

use eigenray::scene::RayTriple;
use eigenray::{BatchOptions, Scene, Status, Tracer, Workspace, demo};

#[path = "support/rng.rs"]
mod rng;
use rng::SplitMix64;

fn scene(spec: &eigenray::SceneSpec) -> Scene {
    Scene::from_spec(spec).expect("valid scene")
}

/// `spec` with its receivers in a random order (a Fisher-Yates shuffle seeded by `seed`).
fn shuffled(mut spec: eigenray::SceneSpec, seed: u64) -> eigenray::SceneSpec {
    let mut rng = SplitMix64(seed);
    let receivers = spec.receivers.points_mut();
    for i in (1..receivers.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        receivers.swap(i, j);
    }
    spec
}

/// A ray with its residual as bits: two rays without one (NaN, as a ray the image method
/// finds without a path) compare equal.
fn bits(ray: eigenray::Ray) -> (u64, eigenray::Ray) {
    (
        ray.residual.to_bits(),
        eigenray::Ray {
            residual: 0.0,
            ..ray
        },
    )
}

fn bench(name: &str) -> Scene {
    let path = format!("{}/fixtures/bench/{name}.json", env!("CARGO_MANIFEST_DIR"));
    Scene::from_json(&std::fs::read_to_string(path).expect("fixture")).expect("valid scene")
}

/// Compares a batch with one-by-one `Tracer::trace`: identical without warm starts; with them,
/// the same statuses and times and points equal to the tolerance's worth (a warm start ends at
/// another point of the same tolerance ball). Returns (iterations one by one, in the batch).
fn compare(scene: &Scene, warm_start: bool) -> (u64, u64) {
    compare_in_units(scene, warm_start, BatchOptions::default().chunk)
}

/// [`compare`] with `chunk` receivers per work unit.
fn compare_in_units(scene: &Scene, warm_start: bool, chunk: usize) -> (u64, u64) {
    let tracer = Tracer::new(scene).expect("tracer");
    let batch = tracer
        .trace_batch(
            &BatchOptions { warm_start, chunk },
            &eigenray::options::Run::new(),
        )
        .unwrap();
    assert_eq!(batch.len(), scene.num_rays());
    let mut ws = Workspace::new();
    let (mut single_iterations, mut batch_iterations) = (0, 0);
    for i in 0..scene.num_rays() {
        let RayTriple {
            source: s,
            receiver: r,
            path: p,
        } = batch.triple(i);
        let one = tracer.trace(s, r, p, &mut ws);
        let got = batch.ray(i);
        assert_eq!((got.source, got.receiver, got.path), (s, r, p));
        single_iterations += one.iterations as u64;
        batch_iterations += got.iterations as u64;
        if !warm_start {
            assert_eq!(bits(got), bits(one), "ray {i}");
            continue;
        }
        assert_eq!(got.status, one.status, "ray {i}: {got:?} vs {one:?}");
        if got.status.has_time() {
            let (a, b) = (got.time, one.time);
            assert!((a - b).abs() <= 1e-12 * b.abs(), "ray {i}: {a} vs {b}");
            let scale = got
                .points
                .iter()
                .map(|p| p.x.abs().max(p.y.abs()))
                .sum::<f64>();
            for (p, q) in got.points.iter().zip(&one.points) {
                assert!(
                    (*p - *q).length() <= 1e-6 * scale,
                    "ray {i}: {p:?} vs {q:?}"
                );
            }
        }
    }
    (single_iterations, batch_iterations)
}

#[test]
fn batch_without_warm_starts_is_one_by_one_solving() {
    compare(&scene(&demo::air_water(500, 5)), false);
    compare(&scene(&demo::layer_stack(8, 200)), false);
    compare(&bench("room2d"), false);
}

/// One refraction and one reflection off a zigzag interface, two sources, a barrier in the
/// upper medium and receivers on both sides: batches solve such one-interaction rays without
/// the workspace, and every way a ray can leave that common case (a step across a vertex, an
/// obstructed leg, a receiver on the wrong side, no crossing to start from, a reflection) must
/// still give the one-by-one ray.
fn zigzag_with_barrier() -> Scene {
    let zigzag: Vec<String> = (0..=16)
        .map(|i| {
            format!(
                "[{}, {}]",
                -4.0 + 0.5 * i as f64,
                if i % 2 == 0 { 0.03 } else { -0.03 }
            )
        })
        .collect();
    let receivers: Vec<String> = demo::jittered_grid(300, [-3.0, 3.0], [-2.0, 1.5], 11)
        .iter()
        .map(|[x, y]| format!("[{x}, {y}]"))
        .collect();
    Scene::from_json(&format!(
        r#"{{
            "media": {{ "air": {{ "speed": 1.0 }}, "water": {{ "speed": 0.6 }} }},
            "interfaces": {{
                "zigzag": {{ "points": [{}] }},
                "barrier": {{ "points": [[1.0, 0.4], [1.0, 1.3]] }}
            }},
            "sources": [[0.2, 2.0], [-1.5, 1.8]],
            "receivers": [{}],
            "paths": [
                {{ "steps": [{{ "refract": "zigzag" }}], "media": ["air", "water"] }},
                {{ "steps": [{{ "reflect": "zigzag" }}], "media": ["air", "air"] }}
            ]
        }}"#,
        zigzag.join(", "),
        receivers.join(", ")
    ))
    .expect("valid scene")
}

#[test]
fn one_interaction_rays_of_a_batch_are_one_by_one_rays() {
    let sc = zigzag_with_barrier();
    let rays = Tracer::new(&sc).expect("tracer").trace_all();
    let statuses: std::collections::BTreeSet<_> = rays.iter().map(|r| r.status.as_str()).collect();
    for status in [
        Status::Converged,
        Status::Obstructed,
        Status::NoPath,
        Status::Vertex,
    ] {
        assert!(
            statuses.contains(status.as_str()),
            "no {status} ray among {statuses:?}"
        );
    }
    // Units of one receiver, of a few (sources changing inside a unit) and of the default
    // size.
    // A digitised curve too: its segments carry a curvature estimate, which the first
    // evaluation of a ray adds and the later ones do not.
    let curved = scene(&demo::undulating_stack(1, 200, 500));
    for chunk in [1, 7, 256] {
        compare_in_units(&sc, false, chunk);
        compare_in_units(&curved, false, chunk);
    }
    // A zigzag has several eigenrays for some receivers, and a warm start may find another
    // one than the default start: check every converged ray for itself (its time from its
    // points, Snell's law on its segment), and that most rays are the one-by-one ones.
    let tracer = Tracer::new(&sc).expect("tracer");
    let slowness = |p: usize| if p == 0 { [1.0, 1.0 / 0.6] } else { [1.0, 1.0] };
    for chunk in [7, 256] {
        let batch = tracer
            .trace_batch(
                &BatchOptions {
                    chunk,
                    ..BatchOptions::default()
                },
                &eigenray::options::Run::new(),
            )
            .unwrap();
        let mut same = 0;
        for (i, one) in rays.iter().enumerate() {
            let got = batch.ray(i);
            let close = match (got.status.has_time(), one.status.has_time()) {
                (true, true) => (got.time - one.time).abs() <= 1e-12 * one.time,
                (a, b) => a == b,
            };
            same += (close && got.status == one.status) as usize;
            if got.status != Status::Converged {
                continue;
            }
            let w = slowness(got.path);
            let [a, x, b] = got.points[..] else {
                panic!("ray {i}: {:?}", got.points)
            };
            let (u0, u1) = (x - a, b - x);
            let time = w[0] * u0.length() + w[1] * u1.length();
            let t_ray = got.time;
            assert!(
                (t_ray - time).abs() <= 1e-12 * time,
                "ray {i}: {t_ray} vs {time}"
            );
            let seg = ((x.x + 4.0) / 0.5).floor().clamp(0.0, 15.0);
            let rising = if (seg as usize).is_multiple_of(2) {
                -0.06
            } else {
                0.06
            };
            let t = eigenray::Vec2::new(0.5, rising) * (1.0 / 0.5f64.hypot(rising));
            let snell = w[0] * u0.dot(t) / u0.length() - w[1] * u1.dot(t) / u1.length();
            assert!(snell.abs() <= 1e-9, "ray {i}: Snell residual {snell}");
        }
        assert!(
            same * 10 >= rays.len() * 9,
            "{same} of {} rays as one by one",
            rays.len()
        );
    }
}

#[test]
fn warm_starts_keep_the_rays_and_save_iterations() {
    // Reflections off a digitised floor: each receiver starts from its neighbour's solution
    // moved to first order.
    let (single, warm) = compare(&scene(&demo::sea_floor(5000, 3000)), true);
    assert!(
        warm * 10 < single * 8,
        "sea floor: {warm} iterations warm vs {single} one by one"
    );
    // One refraction on a grid of receivers, at a surface of two segments.
    let mut kinked = demo::air_water(3000, 5);
    let surface = kinked.interfaces.get_mut("surface").expect("surface");
    surface.points = vec![[-1.0, 0.0], [0.5, 0.0], [2.0, 0.0]];
    let (single, warm) = compare(&scene(&kinked), true);
    assert!(
        warm * 10 < single * 9,
        "air over water: {warm} iterations warm vs {single} one by one"
    );
    // At a surface of one segment the flat kernel solves the rays, from the paraxial start
    // whatever the neighbours: the batch with warm starts on gives the very rays of
    // one-by-one solving.
    let sc = scene(&demo::air_water(3000, 5));
    let tracer = Tracer::new(&sc).expect("tracer");
    let batch = tracer
        .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
        .unwrap();
    let mut ws = Workspace::new();
    for i in 0..sc.num_rays() {
        let RayTriple {
            source: s,
            receiver: r,
            path: p,
        } = batch.triple(i);
        let one = tracer.trace(s, r, p, &mut ws);
        assert_eq!(bits(batch.ray(i)), bits(one), "flat surface, ray {i}");
    }
    // Through parallel flat layers the default start (the ray parameter) is already the
    // solution, and a batch does not warm-start them: no Newton step, and the very rays of
    // one-by-one solving. Through dipping layers the warm starts save steps again.
    let sc = scene(&demo::layer_stack(8, 400));
    let (single, warm) = compare(&sc, true);
    assert_eq!((single, warm), (0, 0), "flat layers: iterations");
    let tracer = Tracer::new(&sc).expect("tracer");
    let warm_batch = tracer
        .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
        .unwrap();
    let cold_batch = tracer
        .trace_batch(
            &BatchOptions {
                warm_start: false,
                ..BatchOptions::default()
            },
            &eigenray::options::Run::new(),
        )
        .unwrap();
    for i in 0..sc.num_rays() {
        assert_eq!(
            bits(warm_batch.ray(i)),
            bits(cold_batch.ray(i)),
            "flat layers, ray {i}"
        );
    }
    let (single, warm) = compare(&scene(&demo::dipping_stack(8, 400)), true);
    assert!(
        warm * 10 < single * 8,
        "dipping layers: {warm} iterations warm vs {single} one by one"
    );
    // A room with all its reflection sequences: whatever the warm starts save, the rays stay
    // the same.
    let (single, warm) = compare(&bench("room2d"), true);
    assert!(
        warm <= single,
        "room: {warm} iterations warm vs {single} one by one"
    );
}

#[test]
fn warm_starts_follow_a_shuffled_receiver_order() {
    // Receivers in random order: the batch solves them along a Morton curve and puts the
    // rays back in ray order.
    let spec = shuffled(demo::sea_floor(5000, 3000), 3);
    let (single, warm) = compare(&scene(&spec), true);
    assert!(
        warm * 10 < single * 8,
        "{warm} iterations warm vs {single} one by one"
    );
    let sc = scene(&spec);
    let tracer = Tracer::new(&sc).expect("tracer");
    let batch = tracer
        .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
        .unwrap();
    let ordered = tracer
        .trace_batch(
            &BatchOptions {
                warm_start: false,
                ..BatchOptions::default()
            },
            &eigenray::options::Run::new(),
        )
        .unwrap();
    for i in 0..batch.len() {
        assert_eq!(batch.record(i).status, ordered.record(i).status, "ray {i}");
    }
}

#[test]
fn dense_receivers_need_fewer_newton_steps() {
    // 40,000 receivers over the sea floor: the continuation step from the neighbour leaves
    // about 2.2 Newton steps per ray, against 3.6 from the default start.
    let sc = scene(&demo::sea_floor(5000, 40_000));
    let tracer = Tracer::new(&sc).expect("tracer");
    let per_ray = |warm_start| {
        let b = tracer
            .trace_batch(
                &BatchOptions {
                    warm_start,
                    ..BatchOptions::default()
                },
                &eigenray::options::Run::new(),
            )
            .unwrap();
        b.total_iterations() as f64 / b.len() as f64
    };
    let (cold, warm) = (per_ray(false), per_ray(true));
    assert!(cold > 3.0, "cold starts: {cold} iterations per ray");
    assert!(
        warm < 0.7 * cold,
        "warm starts: {warm} iterations per ray (cold {cold})"
    );
}

#[test]
fn flat_layers_start_at_their_solution() {
    // The initial guess solves the ray-parameter equation of flat parallel layers: no Newton
    // step is left. (The times themselves are checked independently: tests/physics/layers.rs
    // against a bisection on the ray parameter, tests/physics/benchmarks.rs on layers10
    // against 40-digit references.)
    for spec in [
        demo::layer_stack(2, 300),
        demo::layer_stack(8, 300),
        demo::layer_stack(100, 30),
    ] {
        let sc = scene(&spec);
        let tracer = Tracer::new(&sc).expect("tracer");
        let mut ws = Workspace::new();
        for r in 0..sc.receivers().len() {
            let ray = tracer.trace(0, r, 0, &mut ws);
            assert_eq!(ray.status, Status::Converged);
            assert_eq!(ray.iterations, 0, "receiver {r}: {ray:?}");
        }
    }
}

#[test]
fn a_reused_batch_gives_the_same_rays() {
    // Into one batch: a shuffled scene (solved in spatial order and gathered back), then a
    // larger one, then a smaller one with rays that have no time: each equal to a fresh batch.
    // Receivers beyond the end of the surface: their refraction point would be past it.
    let mut beyond = demo::air_water(300, 4);
    beyond
        .receivers
        .points_mut()
        .extend([[3.0, -1.0], [4.0, -0.5], [5.0, -0.3]]);
    let mut reused = eigenray::Batch::default();
    let mut timeless = 0;
    for spec in [
        shuffled(demo::sea_floor(500, 400), 5),
        demo::layer_stack(8, 900),
        beyond,
        demo::sea_floor(40, 200),
    ] {
        let sc = scene(&spec);
        let tracer = Tracer::new(&sc).expect("tracer");
        let opts = BatchOptions::default();
        tracer
            .trace_batch_into(&opts, &eigenray::options::Run::new(), &mut reused)
            .unwrap();
        let fresh = tracer
            .trace_batch(&opts, &eigenray::options::Run::new())
            .unwrap();
        assert_eq!(reused.len(), fresh.len());
        timeless += (0..fresh.len())
            .filter(|&i| !fresh.record(i).status.has_time())
            .count();
        for i in 0..fresh.len() {
            // Debug strings: NaN residuals compare equal there.
            assert_eq!(
                format!("{:?}", reused.ray(i)),
                format!("{:?}", fresh.ray(i)),
                "ray {i}"
            );
            assert_eq!(
                format!("{:?}", reused.points(i)),
                format!("{:?}", fresh.points(i))
            );
        }
    }
    assert!(timeless > 0, "no ray without a time");
}

/// A waveguide of two straight mirrors and four bounces, its legs alternating between two
/// wave speeds (converted reflections: no image method, so the batch warm-starts them), with
/// receivers along it and beyond its ends. Each sequence has one stationary path (`T` is
/// convex in the parameters), so a warm start either finds that path or fails: a neighbour's
/// bounce points lead it off a mirror's end where the default start finds the path. Such a
/// ray is solved again from the default start, so the batch gives one-by-one solving's rays,
/// ray for ray.
#[test]
fn batches_keep_the_rays_where_warm_starts_fail() {
    let guide = serde_json::json!({
        "media": { "p": { "speed": 1.5 }, "s": { "speed": 0.9 } },
        "interfaces": {
            "top": { "points": [[-5.0, 1.0], [5.0, 1.0]] },
            "bottom": { "points": [[5.0, -1.0], [-5.0, -1.0]] }
        },
        "sources": [[-4.0, 0.1], [0.5, -0.3]],
        "receivers": demo::jittered_grid(900, [-4.9, 9.0], [-0.9, 0.9], 7),
        "paths": [
            { "steps": [{ "reflect": "top" }, { "reflect": "bottom" },
                        { "reflect": "top" }, { "reflect": "bottom" }],
              "media": ["p", "s", "p", "s", "p"] },
            { "steps": [{ "reflect": "bottom" }, { "reflect": "top" }, { "reflect": "bottom" }],
              "media": ["s", "p", "s", "p"] }
        ]
    });
    let scene = Scene::from_json(&guide.to_string()).expect("valid scene");
    let tracer = Tracer::new(&scene).expect("tracer");
    let one_by_one = tracer.trace_all();
    let count = |s: Status| one_by_one.iter().filter(|r| r.status == s).count();
    let (converged, no_path) = (count(Status::Converged), count(Status::NoPath));
    assert!(
        converged > 1000 && no_path > 500,
        "{converged} converged, {no_path} without a path"
    );
    for chunk in [16, 256] {
        let batch = tracer
            .trace_batch(
                &BatchOptions {
                    chunk,
                    ..BatchOptions::default()
                },
                &eigenray::options::Run::new(),
            )
            .unwrap();
        // Rays that took more iterations than one by one were solved twice: their warm start
        // failed.
        let mut resolved = 0;
        for (i, one) in one_by_one.iter().enumerate() {
            let got = batch.ray(i);
            assert_eq!(got.status, one.status, "ray {i}: {got:?} vs {one:?}");
            if got.status.has_time() {
                let (a, b) = (got.time, one.time);
                assert!((a - b).abs() <= 1e-12 * b, "ray {i}: {got:?} vs {one:?}");
            }
            resolved += usize::from(got.iterations > one.iterations + 2);
        }
        assert!(
            resolved > 20,
            "chunk {chunk}: {resolved} warm starts failed"
        );
    }
}

/// `Batch::rays` walks the rays with the indices, records, points and media that the
/// per-ray accessors give, from any start, over scenes of several sources, receivers and
/// paths of different lengths.
#[test]
fn the_walk_over_a_batch_gives_each_rays_parts() {
    for name in ["room2d", "layers10", "seed500"] {
        let scene = bench(name);
        let batch = Tracer::new(&scene)
            .unwrap()
            .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
            .unwrap();
        let n = batch.len();
        for start in [0, 1, n / 3, n - 1, n] {
            let mut count = 0;
            for ray in batch.rays(start..n) {
                let i = ray.index;
                assert_eq!(i, start + count);
                let t = batch.triple(i);
                assert_eq!(
                    (ray.source, ray.receiver, ray.path),
                    (t.source, t.receiver, t.path)
                );
                assert_eq!(ray.record, batch.record(i));
                // The same slice of the batch (its points are NaN for a ray without a time).
                assert!(std::ptr::eq(ray.points, batch.points(i)), "{name} ray {i}");
                assert_eq!(
                    ray.media().map(|m| m.collect::<Vec<_>>()),
                    batch.media(i).map(|m| m.collect::<Vec<_>>())
                );
                count += 1;
            }
            assert_eq!(count, n - start, "{name} from {start}");
        }
    }
}

/// Each ray as a [`eigenray::batch::BatchSink`] receives it: indices, record, points (with a time)
/// and leg media.
type Written = (
    [usize; 3],
    eigenray::RayRecord,
    Vec<eigenray::Point>,
    Vec<usize>,
);

/// A sink that keeps what it is given, one slot per ray (counting the writes of each).
struct Keep<'a> {
    paths: usize,
    rays: &'a mut [(usize, Option<Written>)],
}

impl eigenray::batch::BatchSink for Keep<'_> {
    fn blocks(&self) -> usize {
        self.rays.len() / self.paths
    }

    fn split_at(self, blocks: usize) -> (Self, Self) {
        let (a, b) = self.rays.split_at_mut(blocks * self.paths);
        let paths = self.paths;
        (Keep { paths, rays: a }, Keep { paths, rays: b })
    }

    fn write(
        &mut self,
        at: eigenray::batch::RaySlot,
        record: &eigenray::RayRecord,
        points: &[eigenray::Point],
        media: &[usize],
    ) {
        let slot = &mut self.rays[at.block * self.paths + at.path];
        let points = if record.status.has_time() {
            points.to_vec()
        } else {
            Vec::new()
        };
        slot.0 += 1;
        slot.1 = Some((
            [at.source, at.receiver, at.path],
            *record,
            points,
            media.to_vec(),
        ));
    }
}

/// A batch into a sink gives the sink every ray of `Tracer::trace_batch`, bit for bit, once
/// each, in ray order: receivers in their own order (solved straight into the sink) and
/// shuffled (solved in a spatial order, then written in ray order), one-interaction and
/// general paths, several sources and paths, rays without a time, work units that do not
/// divide the receivers, warm starts on and off, one scratch for all.
#[test]
fn a_sink_gets_the_rays_of_the_batch_bit_for_bit() {
    let mut beyond = demo::air_water(300, 4);
    beyond
        .receivers
        .points_mut()
        .extend([[3.0, -1.0], [4.0, -0.5], [5.0, -0.3]]);
    let scenes = [
        scene(&demo::air_water(1000, 2)),
        scene(&shuffled(demo::air_water(1000, 2), 3)),
        scene(&shuffled(demo::sea_floor(500, 400), 5)),
        scene(&demo::layer_stack(8, 900)),
        scene(&shuffled(demo::dipping_stack(4, 700), 9)),
        scene(&beyond),
        bench("room2d"),
    ];
    let mut scratch = eigenray::batch::BatchScratch::default();
    for (k, sc) in scenes.iter().enumerate() {
        let tracer = Tracer::new(sc).expect("tracer");
        for (warm_start, chunk) in [(true, 256), (true, 37), (false, 256)] {
            let opts = BatchOptions { warm_start, chunk };
            let batch = tracer
                .trace_batch(&opts, &eigenray::options::Run::new())
                .unwrap();
            let mut rays = vec![(0, None); sc.num_rays()];
            let sink = Keep {
                paths: sc.paths().len(),
                rays: &mut rays,
            };
            tracer
                .trace_batch_to(&opts, &eigenray::options::Run::new(), sink, &mut scratch)
                .expect("room");
            for (i, (writes, got)) in rays.into_iter().enumerate() {
                let at = format!("scene {k}, warm {warm_start}, chunk {chunk}, ray {i}");
                assert_eq!(writes, 1, "{at}");
                let (triple, record, points, media) = got.expect("written");
                let RayTriple {
                    source: s,
                    receiver: r,
                    path: p,
                } = batch.triple(i);
                assert_eq!(triple, [s, r, p], "{at}");
                let want = batch.record(i);
                // Debug strings: NaN times and residuals compare equal there.
                assert_eq!(format!("{record:?}"), format!("{want:?}"), "{at}");
                assert_eq!(record.time.to_bits(), want.time.to_bits(), "{at}");
                assert_eq!(record.residual.to_bits(), want.residual.to_bits(), "{at}");
                if record.status.has_time() {
                    assert_eq!(
                        format!("{points:?}"),
                        format!("{:?}", batch.points(i)),
                        "{at}"
                    );
                }
                let legs = sc.paths()[p].steps.len() + 1;
                let media = (media.len() == legs).then_some(media);
                assert_eq!(media, batch.media(i).map(|m| m.collect()), "{at}");
            }
        }
    }
    assert!(
        scratch.memory_bytes() > 0,
        "no scene was solved in a spatial order"
    );
}

/// A scene without rays writes nothing into its sink; a sink of the wrong size is refused.
#[test]
fn a_sink_holds_every_ray_of_the_scene() {
    let mut spec = demo::air_water(10, 1);
    spec.paths.clear();
    let sc = scene(&spec);
    let tracer = Tracer::new(&sc).expect("tracer");
    let mut scratch = eigenray::batch::BatchScratch::default();
    let sink = Keep {
        paths: 1,
        rays: &mut [],
    };
    tracer
        .trace_batch_to(
            &BatchOptions::default(),
            &eigenray::options::Run::new(),
            sink,
            &mut scratch,
        )
        .expect("nothing to solve");
    let sc = scene(&demo::air_water(10, 1));
    let tracer = Tracer::new(&sc).expect("tracer");
    let mut rays = vec![(0, None); 9];
    let wrong = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let sink = Keep {
            paths: 1,
            rays: &mut rays,
        };
        tracer.trace_batch_to(
            &BatchOptions::default(),
            &eigenray::options::Run::new(),
            sink,
            &mut scratch,
        )
    }));
    assert!(wrong.is_err(), "a sink of 9 rays for a scene of 10");
}
