//! Batches: the same rays as one-by-one solving, in ray order, and warm starts that save
//! iterations.

use eigenray::{BatchOptions, Scene, Status, Tracer, Workspace, demo};

fn scene(spec: &eigenray::SceneSpec) -> Scene {
    Scene::from_spec(spec).expect("valid scene")
}

fn bench(name: &str) -> Scene {
    let path = format!("{}/fixtures/bench/{name}.json", env!("CARGO_MANIFEST_DIR"));
    Scene::from_json(&std::fs::read_to_string(path).expect("fixture")).expect("valid scene")
}

/// Compares a batch with one-by-one `Tracer::trace`: identical without warm starts; with them,
/// the same statuses and times and points equal to the tolerance's worth (a warm start ends at
/// another point of the same tolerance ball). Returns (iterations one by one, in the batch).
fn compare(scene: &Scene, warm_start: bool) -> (u64, u64) {
    let tracer = Tracer::new(scene).expect("tracer");
    let batch = tracer.trace_batch(&BatchOptions {
        warm_start,
        ..BatchOptions::default()
    });
    assert_eq!(batch.len(), scene.num_rays());
    let mut ws = Workspace::new();
    let (mut single_iterations, mut batch_iterations) = (0, 0);
    for i in 0..scene.num_rays() {
        let (s, r, p) = batch.triple(i);
        let one = tracer.trace(s, r, p, &mut ws);
        let got = batch.ray(i);
        assert_eq!((got.source, got.receiver, got.path), (s, r, p));
        single_iterations += one.iterations as u64;
        batch_iterations += got.iterations as u64;
        if !warm_start {
            assert_eq!(got, one, "ray {i}");
            continue;
        }
        assert_eq!(got.status, one.status, "ray {i}: {got:?} vs {one:?}");
        if let (Some(a), Some(b)) = (got.time, one.time) {
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

#[test]
fn warm_starts_keep_the_rays_and_save_iterations() {
    // Receivers on a grid: each starts from its neighbour's solution moved to first order.
    let (single, warm) = compare(&scene(&demo::air_water(3000, 5)), true);
    assert!(
        warm * 10 < single * 9,
        "air over water: {warm} iterations warm vs {single} one by one"
    );
    let (single, warm) = compare(&scene(&demo::layer_stack(8, 400)), true);
    assert!(
        warm * 10 < single * 9,
        "8 layers: {warm} iterations warm vs {single} one by one"
    );
    // A digitised floor with vertex rays, and a room with all its reflection sequences:
    // whatever the warm starts save, the rays stay the same.
    compare(&scene(&demo::sea_floor(5000, 300)), true);
    compare(&bench("room2d"), true);
}

#[test]
fn warm_starts_follow_a_shuffled_receiver_order() {
    // Receivers in random order: the batch solves them along a Morton curve and puts the
    // rays back in ray order.
    let mut spec = demo::air_water(2000, 9);
    let mut rng = demo::SplitMix64(3);
    for i in (1..spec.receivers.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        spec.receivers.swap(i, j);
    }
    let (single, warm) = compare(&scene(&spec), true);
    assert!(
        warm * 10 < single * 9,
        "{warm} iterations warm vs {single} one by one"
    );
    let tracer_scene = scene(&spec);
    let tracer = Tracer::new(&tracer_scene).expect("tracer");
    let batch = tracer.trace_batch(&BatchOptions::default());
    assert!(
        batch
            .records()
            .iter()
            .all(|r| r.status == Status::Converged)
    );
}

#[test]
fn dense_receivers_need_fewer_newton_steps() {
    // 40,000 receivers on a 0.005-spaced grid: the continuation step from the neighbour
    // leaves 1.45 Newton steps per ray, against 2.43 from the default start (and 1.01 for the
    // million receivers of the scaling report).
    let sc = scene(&demo::air_water(40_000, 2));
    let tracer = Tracer::new(&sc).expect("tracer");
    let per_ray = |warm_start| {
        let b = tracer.trace_batch(&BatchOptions {
            warm_start,
            ..BatchOptions::default()
        });
        assert!(b.records().iter().all(|r| r.status == Status::Converged));
        b.total_iterations() as f64 / b.len() as f64
    };
    let (cold, warm) = (per_ray(false), per_ray(true));
    assert!(cold > 2.0, "cold starts: {cold} iterations per ray");
    assert!(
        warm < 0.7 * cold,
        "warm starts: {warm} iterations per ray (cold {cold})"
    );
}
